//! `neo_fp_mul` (`a * b`): IEEE binary32, round to nearest even, subnormals, canonical NaN
//! (golden `Native::mul`).
//!
//! Stages: 1 the 24 x 24 significand product and the exponent sum; 2 normalisation (left shift
//! by the leading zeros, limited so the exponent stays >= 1); 3 the subnormal right shift with
//! sticky; 4 rounding, packing and the special cases.

use super::common::{denorm, lzc, q, r, round_pack, unpack, Fields, Pipe, CANONICAL_NAN};
use super::{latency, FpPrim};
use crate::emit::Module;

/// The multiplier.
pub fn module() -> Module {
    let mut p = Pipe::new(super::module_name(FpPrim::Mul), true);
    p.m.doc("binary32 a * b, round to nearest even, subnormals, canonical NaN 0x7fc00000.");
    p.m.doc(format!(
        "Latency {} enabled cycles, one operation per cycle (stages in gen/src/units/fp/mul.rs).",
        latency(FpPrim::Mul)
    ));
    let f = Fields { nan: true, inf: true, zero: true, m: true, ee: true };
    unpack(&mut p, "a", "a_i", f);
    unpack(&mut p, "b", "b_i", f);
    p.w("prod", 48, "{24'd0, a_m} * {24'd0, b_m}");
    // Biased exponent of product bit 47: ea + eb - 127 + 1.
    p.w("e0", 10, "{2'd0, a_ee} + {2'd0, b_ee} - 10'd126");
    p.w("nan", 1, "a_nan | b_nan | (a_inf & b_zero) | (a_zero & b_inf)");
    p.stage(
        "significand product",
        &[
            r(q("prod", 1), 48, "prod"),
            r(q("e0", 1), 10, "e0"),
            r(q("sg", 1), 1, "a_s ^ b_s"),
            r(q("nan", 1), 1, "nan"),
            r(q("inf", 1), 1, "a_inf | b_inf"),
            r(q("zero", 1), 1, "a_zero | b_zero"),
        ],
    );
    p.w("lzin", 64, "{prod_q, 16'hffff}");
    let cw = lzc(&mut p, "lz", "lzin", 64, false);
    assert_eq!(cw, 6);
    p.w("e0pos", 1, "~e0_q[9] & (e0_q != 10'd0)");
    p.w("lim", 10, "e0_q - 10'd1");
    p.w("sl", 6, "e0pos ? (({4'd0, lz_c} > lim) ? lim[5:0] : lz_c) : 6'd0");
    p.stage(
        "normalised product",
        &[
            r(q("pn", 2), 48, "prod_q << sl"),
            r(q("e1", 2), 10, "e0_q - {4'd0, sl}"),
            r(q("sg", 2), 1, "sg_q"),
            r(q("nan", 2), 1, "nan_q"),
            r(q("inf", 2), 1, "inf_q"),
            r(q("zero", 2), 1, "zero_q"),
        ],
    );
    denorm(&mut p, "dn", "pn_q2", 48, "e1_q2", None);
    p.stage(
        "subnormal shift",
        &[
            r(q("top", 3), 24, "dn_top"),
            r(q("stk", 3), 1, "dn_stk"),
            r(q("fld", 3), 8, "dn_fld"),
            r(q("ovf", 3), 1, "dn_ovf"),
            r(q("sg", 3), 1, "sg_q2"),
            r(q("nan", 3), 1, "nan_q2"),
            r(q("inf", 3), 1, "inf_q2"),
            r(q("zero", 3), 1, "zero_q2"),
        ],
    );
    round_pack(&mut p, "rp", "fld_q3", "top_q3", "stk_q3");
    p.w(
        "y",
        32,
        format!(
            "nan_q3 ? {CANONICAL_NAN} : (inf_q3 | ovf_q3) ? {{sg_q3, 8'hff, 23'd0}} : \
             zero_q3 ? {{sg_q3, 31'd0}} : {{sg_q3, rp_mag}}"
        ),
    );
    p.stage("rounded result", &[r("y_q4", 32, "y")]);
    p.m.assign("y_o", "y_q4");
    assert_eq!(p.stages, latency(FpPrim::Mul));
    p.finish()
}
