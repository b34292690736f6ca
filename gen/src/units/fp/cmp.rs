//! `neo_fp_cmp`: the binary32 comparisons, max and min (golden `Native::lt`, `le`, `eq`, `max`,
//! `min`), combinational (latency 0).

use crate::emit::Module;

/// Module name.
pub const NAME: &str = "neo_fp_cmp";

/// The comparator: IEEE `a < b`, `a <= b`, `a == b` (false with a NaN; `-0 == +0`), and
/// `max`/`min` as golden defines them (`b` when `b > a` / `b < a` or `a` is NaN, else `a`).
pub fn module() -> Module {
    let mut m = Module::new(NAME);
    m.doc("binary32 compare (IEEE: unordered with a NaN, -0 == +0), max and min (golden Native::max/min:");
    m.doc("b when b > a (b < a) or a is NaN, else a). Combinational: latency 0.");
    m.input_c("a_i", 32, "operand a");
    m.input_c("b_i", 32, "operand b");
    m.output_c("lt_o", 1, "a < b");
    m.output_c("le_o", 1, "a <= b");
    m.output_c("eq_o", 1, "a == b");
    m.output_c("max_o", 32, "max(a, b)");
    m.output_c("min_o", 32, "min(a, b)");
    m.wire_assign("a_nan", 1, "(&a_i[30:23]) & (|a_i[22:0])");
    m.wire_assign("b_nan", 1, "(&b_i[30:23]) & (|b_i[22:0])");
    m.wire_assign("unord", 1, "a_nan | b_nan");
    m.wire_assign("zeros", 1, "~|{a_i[30:0], b_i[30:0]}");
    // Keys in unsigned order of the value: negatives inverted, positives with the top bit set.
    m.wire_assign("ka", 32, "a_i[31] ? ~a_i : {1'b1, a_i[30:0]}");
    m.wire_assign("kb", 32, "b_i[31] ? ~b_i : {1'b1, b_i[30:0]}");
    m.wire_assign("ord", 1, "~unord & ~zeros");
    m.wire_assign("alt", 1, "ord & (ka < kb)");
    m.wire_assign("agt", 1, "ord & (kb < ka)");
    m.wire_assign("aeq", 1, "~unord & ((a_i == b_i) | zeros)");
    m.assign("lt_o", "alt");
    m.assign("le_o", "alt | aeq");
    m.assign("eq_o", "aeq");
    m.assign("max_o", "(alt | a_nan) ? b_i : a_i");
    m.assign("min_o", "(agt | a_nan) ? b_i : a_i");
    m
}
