//! The conversions: `neo_fp_to_int` (golden `Native::to_int`: exact rounding, the mode a
//! parameter, saturated, NaN gives 0), `neo_fp_from_int` (`int_to_float`, RNE), `neo_fp_f16` (`f16_bits`: |a| as
//! binary16 bits, RNE, saturating at 0x7bff) and `neo_fp_widen_half` (`widen_half`: exact).

use super::common::{lzc, q, r, round_pack, unpack, Fields, Pipe, CANONICAL_NAN};
use super::{latency, FpPrim};
use crate::emit::{conns, set, Module, Stmt};
use neo_golden::hwarith::Round;

/// Module name of the float-to-integer conversion (every rounding mode, [`ROUNDINGS`]).
pub const TO_INT_NAME: &str = "neo_fp_to_int";

/// The rounding modes of `neo_fp_to_int`: (mode, its local parameter, the value of the module's
/// `ROUNDING` parameter that selects it). The default (0) is truncation.
pub const ROUNDINGS: [(Round, &str, u32); 4] = [
    (Round::Trunc, "ROUND_TRUNC", 0),
    (Round::Floor, "ROUND_FLOOR", 1),
    (Round::Ceil, "ROUND_CEIL", 2),
    (Round::HalfUp, "ROUND_HALF_UP", 3),
];

/// The `ROUNDING` parameter value of `mode` ([`ROUNDINGS`]).
pub fn rounding_code(mode: Round) -> u32 {
    ROUNDINGS.iter().find(|(r, _, _)| *r == mode).map(|&(_, _, c)| c).expect("every mode is coded")
}

/// `a` rounded to an integer as parameter `ROUNDING` says ([`ROUNDINGS`]). Stage 1: the
/// magnitude as a fixed-point number (31 integer bits, the half bit and a sticky bit); stage 2:
/// the mode's increment (a `case` on the parameter: synthesis keeps only the selected mode's
/// logic, and truncation's half and sticky registers have no load), the sign and the saturation.
pub fn to_int() -> Module {
    let prim = FpPrim::ToInt(Round::Trunc);
    let mut p = Pipe::new(TO_INT_NAME, false);
    p.m.doc(
        "binary32 -> int32 rounded as ROUNDING says (exact), saturated to [-2^31, 2^31 - 1]; NaN gives 0.",
    );
    let modes: Vec<String> = ROUNDINGS.iter().map(|(r, n, c)| format!("{c} {n} ({r:?})")).collect();
    p.m.doc(format!("ROUNDING: {}; any other value truncates.", modes.join(", ")));
    p.m.doc(format!("Latency {} enabled cycles, one operation per cycle.", latency(prim)));
    p.m.param("ROUNDING", 0);
    for (_, name, code) in ROUNDINGS {
        p.m.localparam_int(name, code);
    }
    unpack(&mut p, "a", "a_i", Fields { nan: true, m: true, ..Default::default() });
    // |a| >= 2^31 (infinities included) saturates; |a| < 1/2 has integer part 0.
    p.w("sat", 1, "a_i[30:23] >= 8'd158");
    p.w("tiny", 1, "a_i[30:23] <= 8'd125");
    p.w("rsh", 8, "8'd157 - a_i[30:23]");
    // 31 integer bits, 26 fraction bits: a_m * 2^(e - 150) = {a_m, 33'b0} >> (157 - e).
    p.w("v", 57, "{a_m, 33'd0} >> rsh[4:0]");
    p.w("ip", 31, "tiny ? 31'd0 : v[56:26]");
    p.unused("rsh[7:5]");
    p.w("hb", 1, "~tiny & v[25]");
    p.w("rest", 1, "tiny ? (|a_i[30:0]) : (|v[24:0])");
    let regs = [
        r(q("ip", 1), 31, "ip"),
        r(q("sg", 1), 1, "a_s"),
        r(q("sat", 1), 1, "sat"),
        r(q("nan", 1), 1, "a_nan"),
        r(q("hb", 1), 1, "hb"),
        r(q("rest", 1), 1, "rest"),
    ];
    p.stage("fixed-point magnitude", &regs);
    let inc = |mode: Round| match mode {
        Round::Trunc => "1'b0",
        Round::Floor => "sg_q & (hb_q | rest_q)",
        Round::Ceil => "~sg_q & (hb_q | rest_q)",
        Round::HalfUp => "sg_q ? (hb_q & rest_q) : hb_q",
    };
    let arms =
        ROUNDINGS.iter().map(|&(mode, name, _)| (name.to_string(), vec![set("inc", inc(mode))])).collect();
    p.m.reg("inc", 1);
    p.m.comb(vec![Stmt::Case("ROUNDING".into(), arms, vec![set("inc", inc(Round::Trunc))])]);
    p.w("mag", 32, "{1'b0, ip_q} + {31'd0, inc}");
    p.w("val", 32, "sg_q ? 32'd0 - mag : mag");
    p.w("y", 32, "nan_q ? 32'd0 : sat_q ? (sg_q ? 32'h80000000 : 32'h7fffffff) : val");
    p.stage("rounded integer", &[r("y_q2", 32, "y")]);
    p.m.assign("y_o", "y_q2");
    assert_eq!(p.stages, latency(prim));
    p.finish()
}

/// `i as f32`, RNE. Stage 1: the magnitude; stage 2: normalisation (leading zeros); stage 3:
/// rounding and packing.
pub fn from_int() -> Module {
    let prim = FpPrim::FromInt;
    let mut p = Pipe::new(super::module_name(prim), false);
    p.m.doc("int32 -> binary32, round to nearest even (Rust's i as f32).");
    p.m.doc(format!("Latency {} enabled cycles, one operation per cycle.", latency(prim)));
    p.w("neg", 1, "a_i[31]");
    p.stage("magnitude", &[r(q("mag", 1), 32, "neg ? 32'd0 - a_i : a_i"), r(q("sg", 1), 1, "neg")]);
    lzc(&mut p, "lz", "mag_q", 32, true);
    p.stage(
        "normalised magnitude",
        &[
            r(q("n", 2), 32, "mag_q << lz_c"),
            r(q("e", 2), 8, "8'd158 - {3'd0, lz_c}"),
            r(q("zero", 2), 1, "lz_z"),
            r(q("sg", 2), 1, "sg_q"),
        ],
    );
    p.w("top", 24, "n_q2[30:7]");
    p.unused("n_q2[31]");
    p.w("stk", 1, "|n_q2[6:0]");
    round_pack(&mut p, "rp", "e_q2", "top", "stk");
    p.w("y", 32, "zero_q2 ? 32'd0 : {sg_q2, rp_mag}");
    p.stage("rounded result", &[r("y_q3", 32, "y")]);
    p.m.assign("y_o", "y_q3");
    assert_eq!(p.stages, latency(prim));
    p.finish()
}

/// `f16_bits(|a|)`: stage 1 the shift to the half's grid (normal: 13 bits, subnormal: more)
/// with guard and sticky; stage 2 rounding and saturation.
pub fn f16() -> Module {
    let prim = FpPrim::F16;
    let mut p = Pipe::new(super::module_name(prim), false);
    p.m.doc("|a| as IEEE binary16 bits (zero-extended), round to nearest even, saturating at 0x7bff;");
    p.m.doc("NaN and infinities give 0x7bff, binary32 zeros and subnormals give 0 (golden f16_bits).");
    p.m.doc(format!("Latency {} enabled cycles, one operation per cycle.", latency(prim)));
    p.w("e", 8, "a_i[30:23]");
    p.w("m", 24, "{1'b1, a_i[22:0]}");
    // Normal half (e >= 113): shift 13, exponent base e - 113; subnormal: shift 126 - e.
    p.w("norm", 1, "e >= 8'd113");
    p.w("sub", 8, "8'd126 - e");
    p.w("sh", 5, "norm ? 5'd13 : ((sub > 8'd31) ? 5'd31 : sub[4:0])");
    // t: m shifted by sh - 1 (its bit 0 is the guard bit).
    p.w("sh1", 5, "sh - 5'd1");
    p.w("t", 24, "m >> sh1");
    p.w("stk", 1, "|(m & ~(24'hffffff << sh1))");
    p.unused("t[23:12]");
    p.unused("a_i[31]");
    p.stage(
        "shifted significand",
        &[
            r(q("t", 1), 12, "t[11:0]"),
            r(q("stk", 1), 1, "stk"),
            r(q("base", 1), 5, "norm ? e[4:0] - 5'd17 : 5'd0"),
            r(q("big", 1), 1, "e > 8'd142"),
            r(q("zero", 1), 1, "e == 8'd0"),
        ],
    );
    p.w("inc", 1, "t_q[0] & (stk_q | t_q[1])");
    p.w("h", 16, "{1'b0, base_q, 10'd0} + {5'd0, t_q[11:1]} + {15'd0, inc}");
    p.w("hs", 16, "(big_q | (h > 16'h7bff)) ? 16'h7bff : h");
    p.w("y", 32, "zero_q ? 32'd0 : {16'd0, hs}");
    p.stage("rounded half", &[r("y_q2", 32, "y")]);
    p.m.assign("y_o", "y_q2");
    assert_eq!(p.stages, latency(prim));
    p.finish()
}

/// Module name of the combinational `widen_half` ([`widen_half_comb`]).
pub const WIDEN_HALF_COMB_NAME: &str = "neo_fp_widen_half_comb";

/// `widen_half(a)`: the binary16 value in a's low 16 bits as binary32 (exact; subnormal halves
/// normalised by their leading zeros; a half NaN gives the canonical NaN). One stage: the
/// combinational [`widen_half_comb`] and the result register.
pub fn widen_half() -> Module {
    let prim = FpPrim::WidenHalf;
    let mut p = Pipe::new(super::module_name(prim), false);
    p.m.doc("binary16 (a_i[15:0]) -> binary32, exact; a half NaN gives the canonical NaN 0x7fc00000.");
    p.m.doc(format!(
        "Latency {} enabled cycle, one operation per cycle: {WIDEN_HALF_COMB_NAME} and a register.",
        latency(prim)
    ));
    p.m.wire("y", 32);
    p.m.instance(WIDEN_HALF_COMB_NAME, "u_widen", conns(&[("a_i", "a_i".into()), ("y_o", "y".into())]));
    p.stage("widened value", &[r("y_q", 32, "y")]);
    p.m.assign("y_o", "y_q");
    assert_eq!(p.stages, latency(prim));
    p.finish()
}

/// The widening of [`widen_half`] without its register (latency 0): `neo_fp_widen_half`'s
/// logic, and what the Preprocessing lane uses on the way into its colour unit (binary16 SH
/// records).
pub fn widen_half_comb() -> Module {
    let mut p = Pipe::combinational(WIDEN_HALF_COMB_NAME);
    p.m.doc("binary16 (a_i[15:0]) -> binary32, exact; a half NaN gives the canonical NaN 0x7fc00000.");
    p.m.doc("Combinational: latency 0 (neo_fp_widen_half is this and a register).");
    p.w("s", 1, "a_i[15]");
    p.unused("a_i[31:16]");
    p.w("e", 5, "a_i[14:10]");
    p.w("f", 10, "a_i[9:0]");
    p.w("lzin", 16, "{f, 6'b111111}");
    lzc(&mut p, "lz", "lzin", 16, false);
    // Subnormal half: the leading one becomes the hidden bit.
    p.w("fs", 10, "f << (lz_c + 4'd1)");
    p.w("es", 8, "8'd112 - {4'd0, lz_c}");
    p.w("fnz", 1, "|f");
    p.w(
        "y",
        32,
        format!(
            "(e == 5'd31) ? (fnz ? {CANONICAL_NAN} : {{s, 8'hff, 23'd0}}) : \
             (e != 5'd0) ? {{s, {{3'd0, e}} + 8'd112, f, 13'd0}} : \
             fnz ? {{s, es, fs, 13'd0}} : {{s, 31'd0}}"
        ),
    );
    p.m.assign("y_o", "y");
    p.finish()
}
