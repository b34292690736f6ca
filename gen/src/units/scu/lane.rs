//! `neo_scu_lane`: one pixel lane of the SCU, stages S0 -> S5 for the pixel of the current pass
//! (`pixel_i`): the offsets from the mean and their squares (S1), the exact quadratic form `q`
//! (S2), `np` by the rounding shift and saturation (S3), exp (S4, `neo_scu_exp`), and alpha with
//! the 1/255 test (S5). Each stage's Gaussian fields come from `neo_scu`'s beat register of that
//! stage; the lane keeps only its own datapath registers (no reset: they are qualified by the
//! beat's valid bit in `neo_scu`).

use super::{exp, pixel_bits, ScuWidths};
use crate::emit::expr::{bits_for, lit, sext, zext};
use crate::emit::{conns, if_, set, Module, Stmt};
use neo_golden::engine::EngineConfig;

/// Module name.
pub const NAME: &str = "neo_scu_lane";

/// The lane for `cfg`.
pub fn module(cfg: &EngineConfig) -> Module {
    let w = ScuWidths::new(cfg);
    let mut m = Module::new(NAME);
    m.doc(
        "One SCU pixel lane, S0 -> S5 (golden shade_pixel up to alpha): |dx|, |dy| and their products (S1),",
    );
    m.doc("q = a dx^2 + 2 b dx dy + c dy^2 exactly (S2), np = -power rounded and saturated (S3), exp (S4),");
    m.doc("alpha = min(round(o e), cap) and the alpha >= 1/255 test (S5). All registers advance on en_i.");
    m.input_c("clk_i", 1, "clock");
    m.input_c("en_i", 1, "the SCU pipeline advances");
    m.input_c("pixel_i", pixel_bits(&w), "S0: pixel {y, x} of the subtile this lane evaluates");
    m.input_c("mean_x_i", w.mean, "S0: mean, signed, mean.frac fraction bits");
    m.input_c("mean_y_i", w.mean, "");
    m.input_c("origin_x_i", w.origin, "S0: subtile origin (pixels)");
    m.input_c("origin_y_i", w.origin, "");
    m.input_c("conic_a_i", w.mant, "S1: conic a mantissa, unsigned");
    m.input_c("conic_b_i", w.mant + 1, "S1: conic b mantissa, signed");
    m.input_c("conic_c_i", w.mant, "S1: conic c mantissa, unsigned");
    m.input_c("conic_exp_i", w.cexp, "S2: shared conic exponent field");
    m.input_c("empty_i", 1, "S2: the beat carries no Gaussian");
    m.input_c("opacity_i", w.opacity, "S4: opacity");
    m.output_c("alpha_o", w.alpha_frac, "S5: alpha, alpha_frac fraction bits");
    m.output_c("blend_o", 1, "S5: alpha >= 1/255 and power <= 0: the Gaussian is blended");
    squares(&mut m, &w);
    quadratic_form(&mut m, &w);
    neg_power(&mut m, &w);
    m.blank();
    m.comment("S3 -> S4: exp.");
    m.wire("e_d", w.e);
    m.instance(exp::NAME, "u_exp", conns(&[("np_i", "np_q".into()), ("e_o", "e_d".into())]));
    m.reg("e_q", w.e).reg("pos4_q", 1);
    m.item(on_en(vec![set("e_q", "e_d"), set("pos4_q", "pos_q")]));
    alpha(&mut m, &w);
    m.assign("alpha_o", "alpha_q");
    m.assign("blend_o", "blend_q");
    m
}

/// `always @(posedge clk_i) if (en_i) stmts`.
fn on_en(stmts: Vec<Stmt>) -> crate::emit::Item {
    crate::emit::Item::Seq { reset: None, body: vec![if_("en_i", stmts)] }
}

/// S0 -> S1: `d = mean - (p << Fm)` per axis, `|d|`, and the registered products.
fn squares(m: &mut Module, w: &ScuWidths) {
    let (d, u, sb) = (w.d, w.u, w.side_bits);
    let pxw = w.origin + 1;
    m.blank();
    m.comment("S0 -> S1: the pixel's offset from the mean, |dx|, |dy| and their products.");
    m.wire("pixel_x", sb).wire("pixel_y", sb);
    m.assign("{pixel_y, pixel_x}", "pixel_i");
    for axis in ["x", "y"] {
        let mean = format!("mean_{axis}_i");
        m.wire_assign(
            format!("pos_{axis}"),
            pxw,
            format!(
                "{} + {}",
                zext(&format!("origin_{axis}_i"), w.origin, pxw),
                zext(&format!("pixel_{axis}"), sb, pxw)
            ),
        );
        let mext = sext(&mean, w.mean, d);
        let pfull = format!("{{{}, pos_{axis}, {}}}", lit(d - pxw - w.mean_frac, 0), lit(w.mean_frac, 0));
        m.wire_assign(format!("d{axis}"), d, format!("{mext} - {pfull}"));
        m.wire_assign(
            format!("a{axis}"),
            u,
            format!("d{axis}[{}] ? (~d{axis}[{}:0] + {}) : d{axis}[{}:0]", d - 1, u - 1, lit(u, 1), u - 1),
        );
    }
    let (ax, ay) = (zext("ax", u, 2 * u), zext("ay", u, 2 * u));
    m.reg("sq_x_q", 2 * u).reg("sq_y_q", 2 * u).reg("sq_xy_q", 2 * u).reg("neg_xy_q", 1);
    m.item(on_en(vec![
        set("sq_x_q", format!("{ax} * {ax}")),
        set("sq_y_q", format!("{ay} * {ay}")),
        set("sq_xy_q", format!("{ax} * {ay}")),
        set("neg_xy_q", format!("dx[{}] ^ dy[{}]", d - 1, d - 1)),
    ]));
}

/// S1 -> S2: `q = a dx^2 + 2 b dx dy + c dy^2`, exact.
fn quadratic_form(m: &mut Module, w: &ScuWidths) {
    let (u, mt, qw) = (w.u, w.mant, w.q);
    let tw = mt + 2 * u + 1;
    m.blank();
    m.comment("S1 -> S2: q = a dx^2 + 2 b dx dy + c dy^2, exact.");
    m.wire_assign("b_neg", 1, format!("conic_b_i[{mt}]"));
    m.wire_assign("b_abs", mt + 1, format!("b_neg ? (~conic_b_i + {}) : conic_b_i", lit(mt + 1, 1)));
    m.wire_assign("ta", tw, format!("{} * {}", zext("conic_a_i", mt, tw), zext("sq_x_q", 2 * u, tw)));
    m.wire_assign("tc", tw, format!("{} * {}", zext("conic_c_i", mt, tw), zext("sq_y_q", 2 * u, tw)));
    m.wire_assign(
        "tb",
        tw + 1,
        format!("{} * {}", zext("b_abs", mt + 1, tw + 1), zext("sq_xy_q", 2 * u, tw + 1)),
    );
    m.comment("2 |b| |dx dy| (the quadratic form's cross term is 2 b dx dy).");
    m.wire_assign("tbx", qw, zext("{tb, 1'b0}", tw + 2, qw));
    m.wire_assign(
        "q_d",
        qw,
        format!(
            "{} + {} + ((neg_xy_q ^ b_neg) ? (~tbx + {}) : tbx)",
            zext("ta", tw, qw),
            zext("tc", tw, qw),
            lit(qw, 1)
        ),
    );
    m.reg("q_q", qw);
    m.item(on_en(vec![set("q_q", "q_d")]));
}

/// S2 -> S3: `np = shr_round(q, sh) = ((q >>> (sh - 1)) + 1) >>> 1`, saturated; skip if < 0.
fn neg_power(m: &mut Module, w: &ScuWidths) {
    let (qw, np) = (w.q, w.np);
    let shw = bits_for(w.sh0 as u64 - 1 + (1u64 << w.cexp) - 1);
    m.blank();
    m.comment("S2 -> S3: np = shr_round(q, sh0 + exp), saturated; q < 0 (power > 0) or empty: skip.");
    m.wire_assign(
        "shm1",
        shw,
        format!("{} + {}", lit(shw, w.sh0 as u64 - 1), zext("conic_exp_i", w.cexp, shw)),
    );
    m.wire_assign("qt", qw, "$signed(q_q) >>> shm1");
    m.wire_assign("qt1", qw, format!("qt + {}", lit(qw, 1)));
    m.wire_assign("npf", qw, "$signed(qt1) >>> 1");
    m.wire_assign("np_d", np, format!("(|npf[{}:{np}]) ? {} : npf[{}:0]", qw - 2, lit(np, w.max_np), np - 1));
    m.wire_assign("pos_d", 1, format!("~npf[{}] & ~empty_i", qw - 1));
    m.reg("np_q", np).reg("pos_q", 1);
    m.item(on_en(vec![set("np_q", "np_d"), set("pos_q", "pos_d")]));
}

/// S4 -> S5: `alpha = min(shr_round(o * e, AS), cap)`; blended iff `alpha >= min_alpha`.
fn alpha(m: &mut Module, w: &ScuWidths) {
    let ow = w.opacity;
    let pw = ow + w.e + 1;
    let a = w.alpha_frac;
    m.blank();
    m.comment("S4 -> S5: alpha = min(shr_round(o e), cap); blended iff alpha >= 1/255.");
    m.wire_assign("oe", pw, format!("{} * {}", zext("opacity_i", ow, pw), zext("e_q", w.e, pw)));
    let aw;
    if w.alpha_shift > 0 {
        let sh = w.alpha_shift as u32;
        m.wire_assign("oer", pw, format!("oe + {}", lit(pw, 1 << (sh - 1))));
        aw = pw - sh;
        m.wire_assign("ar", aw, format!("oer[{}:{sh}]", pw - 1));
    } else {
        let sh = (-w.alpha_shift) as u32;
        aw = pw + sh;
        m.wire_assign("ar", aw, if sh == 0 { "oe".to_string() } else { format!("{{oe, {}}}", lit(sh, 0)) });
    }
    let aw2 = aw.max(a);
    m.wire_assign("arx", aw2, zext("ar", aw, aw2));
    m.wire_assign(
        "alpha_d",
        a,
        format!("(arx > {}) ? {} : arx[{}:0]", lit(aw2, w.max_alpha), lit(a, w.max_alpha), a - 1),
    );
    m.wire_assign("blend_d", 1, format!("pos4_q & (alpha_d >= {})", lit(a, w.min_alpha)));
    m.reg("alpha_q", a).reg("blend_q", 1);
    m.item(on_en(vec![set("alpha_q", "alpha_d"), set("blend_q", "blend_d")]));
}
