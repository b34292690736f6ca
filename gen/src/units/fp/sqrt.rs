//! `neo_fp_sqrt` and its recurrence stage `neo_fp_sqrt_stage`: IEEE binary32 square root,
//! round to nearest even, subnormal inputs, `sqrt(-0) = -0`, negative gives the canonical NaN
//! (golden `Native::sqrt`).
//!
//! Stages: 1 unpack, normalise (subnormals shifted up), make the exponent even (the radicand
//! doubles when it is odd); then [`SQRT_BITS`] / [`STEPS`] stages of [`STEPS`] radix-2
//! digit-by-digit steps (`neo_fp_sqrt_stage`, a generate loop); then rounding, packing and the
//! special cases (a square root is never subnormal, never overflows).

use super::common::{lzc, r, round_pack, unpack, Fields, Pipe, CANONICAL_NAN};
use super::div::STEPS;
use super::{latency, FpPrim};
use crate::emit::{conns, if_, set, Instance, Item, Module};

/// Root bits computed: hidden bit, 23 fraction bits, guard and one more (the remainder gives
/// the sticky bit).
pub const SQRT_BITS: u32 = 26;
/// Recurrence stages.
pub const SQRT_STAGES: u32 = SQRT_BITS / STEPS;
/// Side information: result exponent (8), sign, NaN, inf, zero.
const TAG: u32 = 12;
/// Remainder width.
const RW: u32 = 28;

/// Name of the recurrence stage module.
pub const STAGE_NAME: &str = "neo_fp_sqrt_stage";

/// One recurrence stage: [`STEPS`] steps `r = 4r + next two radicand bits; r >= 4q + 1 ?
/// (r -= 4q + 1, q = 2q + 1) : (q = 2q)`, registered.
pub fn stage_module() -> Module {
    let mut m = Module::new(STAGE_NAME);
    m.doc(format!("neo_fp_sqrt recurrence stage: {STEPS} radix-2 square-root digit steps, registered."));
    m.input_c("clk_i", 1, "clock");
    m.input_c("en_i", 1, "advance (registers hold while low)");
    m.input_c("r_i", RW, "partial remainder, <= 2 q");
    m.input_c("n_i", SQRT_BITS, "radicand bits still to bring down, two per step, from the top");
    m.input_c("q_i", SQRT_BITS, "root bits so far");
    m.input_c("tag_i", TAG, "side information, passed through");
    m.output_c("r_o", RW, "partial remainder after the steps");
    m.output_c("n_o", SQRT_BITS, "radicand bits left (shifted up)");
    m.output_c("q_o", SQRT_BITS, "root with the new bits appended");
    m.output_c("tag_o", TAG, "side information");
    let (mut rin, mut nin, mut qin) = ("r_i".to_string(), "n_i".to_string(), "q_i".to_string());
    for s in 0..STEPS {
        m.wire_assign(
            format!("rr{s}"),
            RW + 2,
            format!("{{{rin}, {nin}[{}:{}]}}", SQRT_BITS - 1, SQRT_BITS - 2),
        );
        m.wire_assign(format!("sb{s}"), RW + 2, format!("{{2'd0, {qin}, 2'b01}}"));
        m.wire_assign(format!("ge{s}"), 1, format!("rr{s} >= sb{s}"));
        m.wire_assign(format!("df{s}"), RW + 2, format!("rr{s} - sb{s}"));
        m.wire_assign(format!("r{s}"), RW, format!("ge{s} ? df{s}[{}:0] : rr{s}[{}:0]", RW - 1, RW - 1));
        m.wire_assign(format!("n{s}"), SQRT_BITS, format!("{{{nin}[{}:0], 2'b00}}", SQRT_BITS - 3));
        m.wire_assign(format!("q{s}"), SQRT_BITS, format!("{{{qin}[{}:0], ge{s}}}", SQRT_BITS - 2));
        rin = format!("r{s}");
        nin = format!("n{s}");
        qin = format!("q{s}");
    }
    // The difference's top bits are 0 whenever it is kept.
    let spent: Vec<String> = (0..STEPS).map(|s| format!("df{s}[{}:{RW}]", RW + 1)).collect();
    m.wire_assign("unused_bits", 1, format!("^{{{}}}", spent.join(", ")));
    m.reg("r_q", RW).reg("n_q", SQRT_BITS).reg("q_q", SQRT_BITS).reg("tag_q", TAG);
    m.seq_noreset(vec![if_(
        "en_i",
        vec![set("r_q", rin), set("n_q", nin), set("q_q", qin), set("tag_q", "tag_i")],
    )]);
    m.assign("r_o", "r_q");
    m.assign("n_o", "n_q");
    m.assign("q_o", "q_q");
    m.assign("tag_o", "tag_q");
    m
}

/// The square root.
pub fn module() -> Module {
    let mut p = Pipe::new(super::module_name(FpPrim::Sqrt), false);
    p.m.doc("binary32 sqrt(a), round to nearest even, subnormal inputs, sqrt(-0) = -0, canonical NaN.");
    p.m.doc(format!(
        "Latency {} enabled cycles, one operation per cycle: {SQRT_STAGES} stages of {STEPS} radix-2 steps.",
        latency(FpPrim::Sqrt)
    ));
    let f = Fields { nan: true, inf: true, zero: true, m: true, ee: true };
    unpack(&mut p, "a", "a_i", f);
    p.w("lzin", 32, "{a_m, 8'hff}");
    lzc(&mut p, "lz", "lzin", 32, false);
    p.w("mn", 24, "a_m << lz_c");
    p.w("en", 10, "{2'd0, a_ee} - {5'd0, lz_c}");
    // The unbiased exponent en - 127 is odd when en is even: the radicand doubles.
    p.w("odd", 1, "~en[0]");
    p.w("mp", 25, "odd ? {mn, 1'b0} : {1'b0, mn}");
    p.w("xe", 10, "en - 10'd127 - {9'd0, odd}");
    p.w("e", 10, "{xe[9], xe[9:1]} + 10'd127");
    p.w("nan", 1, "a_nan | (a_s & ~a_zero)");
    p.w("tag", TAG, "{e[7:0], a_s, nan, a_inf, a_zero}");
    p.stage("normalised radicand", &[r("n_q", SQRT_BITS, "{mp, 1'b0}"), r("tag_q", TAG, "tag")]);
    let n = SQRT_STAGES;
    p.m.wire("r_c", RW * (n + 1));
    p.m.wire("n_c", SQRT_BITS * (n + 1));
    p.m.wire("q_c", SQRT_BITS * (n + 1));
    p.m.wire("t_c", TAG * (n + 1));
    p.m.assign(format!("r_c[{}:0]", RW - 1), format!("{RW}'d0"));
    p.m.assign(format!("n_c[{}:0]", SQRT_BITS - 1), "n_q");
    p.m.assign(format!("q_c[{}:0]", SQRT_BITS - 1), format!("{SQRT_BITS}'d0"));
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
                ("r_i", sl("r_c", RW, "g")),
                ("n_i", sl("n_c", SQRT_BITS, "g")),
                ("q_i", sl("q_c", SQRT_BITS, "g")),
                ("tag_i", sl("t_c", TAG, "g")),
                ("r_o", sl("r_c", RW, "g+1")),
                ("n_o", sl("n_c", SQRT_BITS, "g+1")),
                ("q_o", sl("q_c", SQRT_BITS, "g+1")),
                ("tag_o", sl("t_c", TAG, "g+1")),
            ]),
        })],
    );
    p.stages += n;
    let (rl, ql, tl) = (RW * n, SQRT_BITS * n, TAG * n);
    p.w("rf", RW, format!("r_c[{}:{rl}]", rl + RW - 1));
    p.w("qf", SQRT_BITS, format!("q_c[{}:{ql}]", ql + SQRT_BITS - 1));
    p.w("tf", TAG, format!("t_c[{}:{tl}]", tl + TAG - 1));
    p.w("stk", 1, "qf[0] | (|rf)");
    p.w("fld", 8, "tf[11:4]");
    p.w("top", 24, "qf[24:1]");
    p.unused("qf[25]");
    p.unused("e[9:8]");
    p.unused("xe[0]");
    p.unused(format!("n_c[{}:{ql}]", ql + SQRT_BITS - 1));
    round_pack(&mut p, "rp", "fld", "top", "stk");
    p.w(
        "y",
        32,
        format!(
            "tf[2] ? {CANONICAL_NAN} : tf[0] ? {{tf[3], 31'd0}} : tf[1] ? 32'h7f800000 : {{1'b0, rp_mag}}"
        ),
    );
    p.stage("rounded result", &[r("y_q2", 32, "y")]);
    p.m.assign("y_o", "y_q2");
    assert_eq!(p.stages, latency(FpPrim::Sqrt));
    p.finish()
}
