//! `neo_fp_add` (`a + b`) and `neo_fp_sub` (`a - b`, the adder with b's sign flipped): IEEE
//! binary32, round to nearest even, subnormals, canonical NaN (golden `Native::add`/`sub`).
//!
//! Stages: 1 unpack, order by magnitude, exponent difference; 2 alignment shift (guard, round
//! and sticky bits) and the add or subtract; 3 normalisation (a right shift on carry, else a
//! left shift by the leading zeros, limited so the exponent stays >= 1: subnormal results);
//! 4 rounding, packing and the special cases.

use super::common::{lzc, q, r, round_pack, unpack, Fields, Pipe, CANONICAL_NAN};
use super::{latency, FpPrim};
use crate::emit::{conns, Module};

/// The adder.
pub fn add() -> Module {
    let mut p = Pipe::new(super::module_name(FpPrim::Add), true);
    p.m.doc("binary32 a + b, round to nearest even, subnormals, canonical NaN 0x7fc00000.");
    p.m.doc(format!(
        "Latency {} enabled cycles, one operation per cycle (stages in gen/src/units/fp/add.rs).",
        latency(FpPrim::Add)
    ));
    let f = Fields { nan: true, inf: true, m: true, ee: true, ..Default::default() };
    unpack(&mut p, "a", "a_i", f);
    unpack(&mut p, "b", "b_i", f);
    // Order by magnitude (x: the larger, y: the smaller); NaNs are handled apart.
    p.w("a_big", 1, "a_i[30:0] >= b_i[30:0]");
    p.w("mx", 24, "a_big ? a_m : b_m");
    p.w("my", 24, "a_big ? b_m : a_m");
    p.w("ex", 8, "a_big ? a_ee : b_ee");
    p.w("ey", 8, "a_big ? b_ee : a_ee");
    p.w("sx", 1, "a_big ? a_s : b_s");
    p.w("esub", 1, "a_s ^ b_s");
    p.w("d", 8, "ex - ey");
    p.w("dc", 5, "(d > 8'd27) ? 5'd27 : d[4:0]");
    p.w("nan", 1, "a_nan | b_nan | (a_inf & b_inf & esub)");
    p.w("inf", 1, "a_inf | b_inf");
    p.stage(
        "operands ordered by magnitude",
        &[
            r(q("mx", 1), 24, "mx"),
            r(q("my", 1), 24, "my"),
            r(q("ex", 1), 8, "ex"),
            r(q("dc", 1), 5, "dc"),
            r(q("sx", 1), 1, "sx"),
            r(q("esub", 1), 1, "esub"),
            r(q("nan", 1), 1, "nan"),
            r(q("inf", 1), 1, "inf"),
        ],
    );
    // Alignment: the smaller significand with 3 extra bits, shifted right, sticky into bit 0.
    p.w("yx", 27, "{my_q, 3'd0}");
    p.w("ysh", 27, "yx >> dc_q");
    p.w("ystk", 1, "|(yx & ~(27'h7ffffff << dc_q))");
    p.w("yal", 28, "{1'b0, ysh[26:1], ysh[0] | ystk}");
    p.w("xx", 28, "{1'b0, mx_q, 3'd0}");
    p.w("sum", 28, "esub_q ? xx - yal : xx + yal");
    p.stage(
        "aligned sum",
        &[
            r(q("sum", 2), 28, "sum"),
            r(q("ex", 2), 8, "ex_q"),
            r(q("sx", 2), 1, "sx_q"),
            r(q("esub", 2), 1, "esub_q"),
            r(q("nan", 2), 1, "nan_q"),
            r(q("inf", 2), 1, "inf_q"),
        ],
    );
    // Normalisation: the leading one to bit 26.
    p.w("szero", 1, "~|sum_q2");
    p.w("carry", 1, "sum_q2[27]");
    p.w("lzin", 32, "{sum_q2[26:0], 5'b11111}");
    let cw = lzc(&mut p, "lz", "lzin", 32, false);
    assert_eq!(cw, 5);
    p.w("lim", 8, "ex_q2 - 8'd1");
    p.w("sl", 5, "carry ? 5'd0 : (({3'd0, lz_c} > lim) ? lim[4:0] : lz_c)");
    p.w("nl", 27, "sum_q2[26:0] << sl");
    p.w("nr", 27, "{sum_q2[27:2], sum_q2[1] | sum_q2[0]}");
    p.w("en", 9, "carry ? {1'b0, ex_q2} + 9'd1 : {1'b0, ex_q2} - {4'd0, sl}");
    p.stage(
        "normalised sum",
        &[
            r(q("nrm", 3), 27, "carry ? nr : nl"),
            r(q("en", 3), 9, "en"),
            r(q("zero", 3), 1, "szero"),
            r(q("sx", 3), 1, "sx_q2"),
            r(q("esub", 3), 1, "esub_q2"),
            r(q("nan", 3), 1, "nan_q2"),
            r(q("inf", 3), 1, "inf_q2"),
        ],
    );
    // Rounding and packing.
    p.w("hid", 1, "nrm_q3[26]");
    p.w("fld", 8, "hid ? en_q3[7:0] : 8'd0");
    p.w("ovf", 1, "hid & (en_q3 >= 9'd255)");
    p.w("top", 24, "nrm_q3[25:2]");
    p.w("stk", 1, "nrm_q3[1] | nrm_q3[0]");
    round_pack(&mut p, "rp", "fld", "top", "stk");
    p.w(
        "y",
        32,
        format!(
            "nan_q3 ? {CANONICAL_NAN} : (inf_q3 | ovf) ? {{sx_q3, 8'hff, 23'd0}} : \
             zero_q3 ? {{sx_q3 & ~esub_q3, 31'd0}} : {{sx_q3, rp_mag}}"
        ),
    );
    p.stage("rounded result", &[r("y_q4", 32, "y")]);
    p.m.assign("y_o", "y_q4");
    assert_eq!(p.stages, latency(FpPrim::Add));
    p.finish()
}

/// The subtractor: `neo_fp_add` with b's sign flipped (exact in IEEE: `a - b = a + (-b)`,
/// signed zeros included; a NaN stays a NaN).
pub fn sub() -> Module {
    let mut m = Module::new(super::module_name(FpPrim::Sub));
    m.doc("binary32 a - b = a + (-b): neo_fp_add with b's sign flipped. Latency as neo_fp_add.");
    m.input_c("clk_i", 1, "clock");
    m.input_c("en_i", 1, "advance the pipeline (registers hold while low)");
    m.input_c("a_i", 32, "operand a");
    m.input_c("b_i", 32, "operand b");
    m.output_c("y_o", 32, "a - b, LATENCY enabled cycles after the operands");
    m.wire_assign("nb", 32, "{~b_i[31], b_i[30:0]}");
    m.instance(
        super::module_name(FpPrim::Add),
        "u_add",
        conns(&[
            ("clk_i", "clk_i".into()),
            ("en_i", "en_i".into()),
            ("a_i", "a_i".into()),
            ("b_i", "nb".into()),
            ("y_o", "y_o".into()),
        ]),
    );
    m
}
