//! `neo_fp_bench`: every binary32 primitive side by side on shared operands, for the
//! cosimulation bench (one Verilator build for all of them; tb builds it at run time). Not
//! part of `neo_engine`.

use super::{cmp, conv, label, FpPrim};
use crate::emit::{conns, Module};

/// Module name.
pub const NAME: &str = "neo_fp_bench";

/// The output of the combinational half widening (`neo_fp_widen_half_comb`).
pub const WIDEN_COMB_PORT: &str = "widen_comb_y_o";

/// The output port of primitive `p`: `<short>_y_o`.
pub fn port(p: FpPrim) -> String {
    format!("{}_y_o", p.short())
}

/// The bench top: `a_i`/`b_i` feed every primitive (the unary ones read `a_i`), one output per
/// primitive, and the combinational modules' outputs (the comparator, the half widening).
pub fn module() -> Module {
    let mut m = Module::new(NAME);
    m.doc("Cosimulation top: every neo_fp primitive on the same operands (bench only).");
    m.input_c("clk_i", 1, "clock");
    m.input_c("en_i", 1, "advance every pipeline");
    m.input_c("a_i", 32, "operand a (an integer for from_int, half bits for widen_half)");
    m.input_c("b_i", 32, "operand b of the binary primitives");
    for p in FpPrim::ALL {
        m.output_c(port(p), 32, &label(p));
    }
    m.output_c("lt_o", 1, "neo_fp_cmp: a < b");
    m.output_c("le_o", 1, "neo_fp_cmp: a <= b");
    m.output_c("eq_o", 1, "neo_fp_cmp: a == b");
    m.output_c("max_o", 32, "neo_fp_cmp: max(a, b)");
    m.output_c("min_o", 32, "neo_fp_cmp: min(a, b)");
    m.output_c(WIDEN_COMB_PORT, 32, "neo_fp_widen_half_comb: a's low half widened (combinational)");
    for p in FpPrim::ALL {
        let b = p.binary().then_some("b_i");
        super::instantiate(&mut m, p, &format!("u_{}", p.short()), "en_i", "a_i", b, &port(p));
    }
    m.instance(
        cmp::NAME,
        "u_cmp",
        conns(&[
            ("a_i", "a_i".into()),
            ("b_i", "b_i".into()),
            ("lt_o", "lt_o".into()),
            ("le_o", "le_o".into()),
            ("eq_o", "eq_o".into()),
            ("max_o", "max_o".into()),
            ("min_o", "min_o".into()),
        ]),
    );
    m.instance(
        conv::WIDEN_HALF_COMB_NAME,
        "u_widen_comb",
        conns(&[("a_i", "a_i".into()), ("y_o", WIDEN_COMB_PORT.into())]),
    );
    m
}
