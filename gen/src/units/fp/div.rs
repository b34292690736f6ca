//! `neo_fp_div` (`a / b`) and its recurrence stage `neo_fp_div_stage`: IEEE binary32, round to
//! nearest even, subnormals, canonical NaN (golden `Native::div`).
//!
//! Stages: 1 unpack and normalise both significands (subnormals shifted up, their exponents
//! below 1); then [`DIV_BITS`] / [`STEPS`] recurrence stages, each [`STEPS`] radix-2 restoring
//! steps (`neo_fp_div_stage`, a generate loop); then the one-bit normalisation of the quotient
//! and the subnormal right shift with sticky; then rounding, packing and the special cases.

use super::common::{denorm, lzc, q, r, round_pack, unpack, Fields, Pipe, CANONICAL_NAN};
use super::{latency, FpPrim};
use crate::emit::{conns, if_, set, Instance, Item, Module};

/// Quotient bits computed: hidden bit, 23 fraction bits, guard, and one more for a quotient
/// below 1 (the remainder gives the sticky bit).
pub const DIV_BITS: u32 = 26;
/// Radix-2 steps per recurrence stage.
pub const STEPS: u32 = 2;
/// Recurrence stages.
pub const DIV_STAGES: u32 = DIV_BITS / STEPS;
/// Side information carried through the recurrence: exponent (10), sign, NaN, inf, zero.
const TAG: u32 = 14;

/// Name of the recurrence stage module.
pub const STAGE_NAME: &str = "neo_fp_div_stage";

/// One recurrence stage: [`STEPS`] restoring steps `r >= d ? (q = 2q + 1, r = 2(r - d)) :
/// (q = 2q, r = 2r)`, registered.
pub fn stage_module() -> Module {
    let mut m = Module::new(STAGE_NAME);
    m.doc(format!("neo_fp_div recurrence stage: {STEPS} radix-2 restoring division steps, registered."));
    m.input_c("clk_i", 1, "clock");
    m.input_c("en_i", 1, "advance (registers hold while low)");
    m.input_c("r_i", 25, "partial remainder, < 2 d");
    m.input_c("d_i", 24, "divisor significand, normalised (bit 23 set)");
    m.input_c("q_i", DIV_BITS, "quotient bits so far");
    m.input_c("tag_i", TAG, "side information, passed through");
    m.output_c("r_o", 25, "partial remainder after the steps");
    m.output_c("d_o", 24, "divisor, passed through");
    m.output_c("q_o", DIV_BITS, "quotient with the new bits appended");
    m.output_c("tag_o", TAG, "side information");
    let mut rin = "r_i".to_string();
    for s in 0..STEPS {
        m.wire_assign(format!("t{s}"), 26, format!("{{1'b0, {rin}}} - {{2'd0, d_i}}"));
        m.wire_assign(format!("ge{s}"), 1, format!("~t{s}[25]"));
        m.wire_assign(format!("rn{s}"), 24, format!("ge{s} ? t{s}[23:0] : {rin}[23:0]"));
        m.wire_assign(format!("r{s}"), 25, format!("{{rn{s}, 1'b0}}"));
        rin = format!("r{s}");
    }
    // The quotient's top bits shift out; t's bit 24 is 0 whenever r >= d.
    let spent: Vec<String> = (0..STEPS).map(|s| format!("t{s}[24]")).collect();
    m.wire_assign(
        "unused_bits",
        1,
        format!("^{{q_i[{}:{}], {}}}", DIV_BITS - 1, DIV_BITS - STEPS, spent.join(", ")),
    );
    let ges: Vec<String> = (0..STEPS).map(|s| format!("ge{s}")).collect();
    let qn = format!("{{q_i[{}:0], {}}}", DIV_BITS - 1 - STEPS, ges.join(", "));
    m.reg("r_q", 25).reg("d_q", 24).reg("q_q", DIV_BITS).reg("tag_q", TAG);
    m.seq_noreset(vec![if_(
        "en_i",
        vec![set("r_q", format!("r{}", STEPS - 1)), set("d_q", "d_i"), set("q_q", qn), set("tag_q", "tag_i")],
    )]);
    m.assign("r_o", "r_q");
    m.assign("d_o", "d_q");
    m.assign("q_o", "q_q");
    m.assign("tag_o", "tag_q");
    m
}

/// The divider.
pub fn module() -> Module {
    let mut p = Pipe::new(super::module_name(FpPrim::Div), true);
    p.m.doc("binary32 a / b, round to nearest even, subnormals, canonical NaN 0x7fc00000.");
    p.m.doc(format!(
        "Latency {} enabled cycles, one operation per cycle: {DIV_STAGES} stages of {STEPS} radix-2 steps.",
        latency(FpPrim::Div)
    ));
    let f = Fields { nan: true, inf: true, zero: true, m: true, ee: true };
    unpack(&mut p, "a", "a_i", f);
    unpack(&mut p, "b", "b_i", f);
    for x in ["a", "b"] {
        p.w(&format!("{x}_lzin"), 32, format!("{{{x}_m, 8'hff}}"));
        lzc(&mut p, &format!("{x}_lz"), &format!("{x}_lzin"), 32, false);
        p.w(&format!("{x}_mn"), 24, format!("{x}_m << {x}_lz_c"));
        p.w(&format!("{x}_en"), 10, format!("{{2'd0, {x}_ee}} - {{5'd0, {x}_lz_c}}"));
    }
    p.w("e0", 10, "a_en - b_en + 10'd127");
    p.w("nan", 1, "a_nan | b_nan | (a_zero & b_zero) | (a_inf & b_inf)");
    p.w("tag", TAG, "{e0, a_s ^ b_s, nan, a_inf | b_zero, a_zero | b_inf}");
    p.stage(
        "normalised operands",
        &[r("r_q", 25, "{1'd0, a_mn}"), r("d_q", 24, "b_mn"), r("tag_q", TAG, "tag")],
    );
    // The recurrence: stage k's outputs at chain index k + 1.
    let n = DIV_STAGES;
    p.m.wire("r_c", 25 * (n + 1));
    p.m.wire("d_c", 24 * (n + 1));
    p.m.wire("q_c", DIV_BITS * (n + 1));
    p.m.wire("t_c", TAG * (n + 1));
    p.m.assign("r_c[24:0]", "r_q");
    p.m.assign("d_c[23:0]", "d_q");
    p.m.assign(format!("q_c[{}:0]", DIV_BITS - 1), format!("{DIV_BITS}'d0"));
    p.m.assign(format!("t_c[{}:0]", TAG - 1), "tag_q");
    let sl = |name: &str, w: u32, k: &str| format!("{name}[({k})*{w} +: {w}]");
    p.m.gen_for(
        "g",
        n,
        "g_stage",
        vec![Item::Instance(Instance {
            module: STAGE_NAME.into(),
            name: "u_stage".into(),
            params: Vec::new(),
            conns: conns(&[
                ("clk_i", "clk_i".into()),
                ("en_i", "en_i".into()),
                ("r_i", sl("r_c", 25, "g")),
                ("d_i", sl("d_c", 24, "g")),
                ("q_i", sl("q_c", DIV_BITS, "g")),
                ("tag_i", sl("t_c", TAG, "g")),
                ("r_o", sl("r_c", 25, "g+1")),
                ("d_o", sl("d_c", 24, "g+1")),
                ("q_o", sl("q_c", DIV_BITS, "g+1")),
                ("tag_o", sl("t_c", TAG, "g+1")),
            ]),
        })],
    );
    p.stages += n;
    let (rl, ql, tl) = (25 * n, DIV_BITS * n, TAG * n);
    p.w("rf", 25, format!("r_c[{}:{rl}]", rl + 24));
    p.w("qf", DIV_BITS, format!("q_c[{}:{ql}]", ql + DIV_BITS - 1));
    p.w("tf", TAG, format!("t_c[{}:{tl}]", tl + TAG - 1));
    p.w("lead", 1, format!("qf[{}]", DIV_BITS - 1));
    p.w("qn", DIV_BITS, format!("lead ? qf : {{qf[{}:0], 1'b0}}", DIV_BITS - 2));
    p.w("e1", 10, "lead ? tf[13:4] : tf[13:4] - 10'd1");
    p.w("rnz", 1, "|rf");
    p.unused(format!("d_c[{}:{}]", 24 * n + 23, 24 * n));
    denorm(&mut p, "dn", "qn", DIV_BITS, "e1", Some("rnz"));
    p.stage(
        "normalised quotient, subnormal shift",
        &[
            r(q("top", 2), 24, "dn_top"),
            r(q("stk", 2), 1, "dn_stk"),
            r(q("fld", 2), 8, "dn_fld"),
            r(q("ovf", 2), 1, "dn_ovf"),
            r(q("spec", 2), 4, "tf[3:0]"),
        ],
    );
    round_pack(&mut p, "rp", "fld_q2", "top_q2", "stk_q2");
    p.w("sg", 1, "spec_q2[3]");
    p.w(
        "y",
        32,
        format!(
            "spec_q2[2] ? {CANONICAL_NAN} : (spec_q2[1] | ovf_q2) ? {{sg, 8'hff, 23'd0}} : \
             spec_q2[0] ? {{sg, 31'd0}} : {{sg, rp_mag}}"
        ),
    );
    p.stage("rounded result", &[r("y_q3", 32, "y")]);
    p.m.assign("y_o", "y_q3");
    assert_eq!(p.stages, latency(FpPrim::Div));
    p.finish()
}
