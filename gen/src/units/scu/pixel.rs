//! `neo_scu_pixels`: the pixels of one SCU lane. Lane `l` blends pixel `p*L + l` in pass `p`,
//! so it owns `P` pixels: their states `{done, colour, T}` (memories indexed by the pass,
//! written by the lane's blend when the pass is in S5), their saved states (one row per subtile
//! slot and pass, for lists that arrive in pieces), their 8-bit colours and the output register.
//!
//! Only the pixel of S5's pass is read or written in a cycle, so the state sits in memories
//! indexed by the pass rather than in one register per pixel behind a pass multiplexer: the
//! hardware is the same, and a cycle-based simulator (Verilator) touches one entry per lane and
//! cycle instead of every pixel's bits. The 8-bit colour of a state is converted when the state
//! is written (once per lane and cycle) and kept beside it; the output register copies the
//! colours of the next state only when a finished subtile enters it.

use super::blend::{rev, CHANNELS};
use super::ScuWidths;
use crate::emit::expr::{lit, zext};
use crate::emit::{for_, if_, set, Module};
use neo_golden::engine::EngineConfig;
use neo_golden::raster::RGB_BITS;

/// Module name.
pub const NAME: &str = "neo_scu_pixels";

/// Bits of one output channel.
const OUT_BITS: u32 = RGB_BITS / 3;

/// The pixels of one lane for `cfg`.
pub fn module(cfg: &EngineConfig) -> Module {
    let w = ScuWidths::new(cfg);
    let (t, c3, p_n, pb) = (w.t, 3 * w.c, w.passes, w.pass_bits());
    let slots = 1u32 << w.row_bits;
    let mut m = Module::new(NAME);
    m.doc(format!(
        "The {p_n} pixels of one SCU lane (pixel p of the lane is the subtile's pixel p*{} + lane): their",
        w.lanes
    ));
    m.doc("states {done, colour, T} and 8-bit colours (memories indexed by the pass), their saved states");
    m.doc(format!(
        "(bank_q[{{slot, pass}}], {} slots) and the output register. Only S5's pass is read or written.",
        w.rows
    ));
    m.clock_reset();
    m.input_c("en_i", 1, "the SCU pipeline advances");
    m.input_c("wr_i", 1, "S5's pass is blended: its pixel takes the lane's new state");
    if p_n > 1 {
        m.input_c("pass_i", pb, "the pass in S5: the lane's pixel read and written");
    }
    m.input_c("t_i", t, "the lane's new state: transmittance");
    m.input_c("c_i", c3, "colour accumulators {blue, green, red}");
    m.input_c("done_i", 1, "done");
    m.input_c("save_i", 1, "a piece that does not end its subtile ends: save every pixel's next state");
    m.input_c("slot_i", w.row_bits, "the subtile's state slot (save and resume)");
    m.input_c("out_i", 1, "a finished subtile enters the output register: take the next colours");
    m.output_c("t_o", t, "the state of the pass's pixel");
    m.output_c("c_o", c3, "");
    m.output_c("done_o", 1, "");
    m.output_c("saved_t_o", t, "the pass's pixel's state saved in slot_i");
    m.output_c("saved_c_o", c3, "");
    m.output_c("saved_done_o", 1, "");
    m.output_c("done_d_o", p_n, "the next state's done bits (pixel p at bit p)");
    m.output_c("rgb_o", RGB_BITS * p_n, "the output register: pixel p's {blue, green, red} at [24p +: 24]");
    state(&mut m, &w, slots);
    colours(&mut m, &w);
    m
}

/// The pass index expression (`0` with one pass).
fn pass(w: &ScuWidths) -> String {
    if w.passes > 1 {
        "pass_i".into()
    } else {
        lit(1, 0)
    }
}

/// Bit `i` of the `P`-bit vector `v` (`v` itself with one pass).
fn bit(w: &ScuWidths, v: &str, i: &str) -> String {
    if w.passes > 1 {
        format!("{v}[{i}]")
    } else {
        v.into()
    }
}

/// The row of `bank_q` for slot `slot_i` and pass expression `p`.
fn bank_row(w: &ScuWidths, p: &str) -> String {
    if w.passes > 1 {
        format!("bank_q[{{slot_i, {p}}}]")
    } else {
        "bank_q[slot_i]".into()
    }
}

/// The states, the done bits and the saved states.
fn state(m: &mut Module, w: &ScuWidths, slots: u32) {
    let (t, c3, p_n, pb) = (w.t, 3 * w.c, w.passes, w.pass_bits());
    let ps = pass(w);
    m.mem("t_q", t, p_n).mem("c_q", c3, p_n).reg("done_q", p_n);
    m.comment("hit: the pixel written this cycle (S5's pass, when it is blended).");
    m.wire_assign("hit", p_n, format!("{} << {ps}", zext("wr_i", 1, p_n)));
    m.wire_assign("done_d", p_n, format!("(done_q & ~hit) | ({{{p_n}{{done_i}}}} & hit)"));
    m.seq(
        vec![set("done_q", format!("{{{p_n}{{1'b1}}}}"))],
        vec![if_("en_i", vec![set("done_q", "done_d")])],
    );
    m.seq_noreset(vec![if_(
        "en_i & wr_i",
        vec![set(format!("t_q[{ps}]"), "t_i"), set(format!("c_q[{ps}]"), "c_i")],
    )]);
    m.assign("t_o", format!("t_q[{ps}]"))
        .assign("c_o", format!("c_q[{ps}]"))
        .assign("done_o", bit(w, "done_q", &ps));
    m.assign("done_d_o", "done_d");
    m.blank();
    m.comment("Saved states, one row per subtile slot and pass; a save writes every pixel's next state.");
    m.mem("bank_q", w.state_bits(), slots * p_n).integer("p");
    let idx = if p_n > 1 { format!("p[{}:0]", pb - 1) } else { lit(1, 0) };
    m.seq_noreset(vec![if_(
        "en_i & save_i",
        vec![for_(
            "p",
            p_n.to_string(),
            vec![set(
                bank_row(w, &idx),
                format!(
                    "{} ? {{done_i, c_i, t_i}} : {{{}, c_q[p], t_q[p]}}",
                    bit(w, "hit", "p"),
                    bit(w, "done_q", "p")
                ),
            )],
        )],
    )]);
    m.assign("{saved_done_o, saved_c_o, saved_t_o}", bank_row(w, &ps));
}

/// The 8-bit colours: converted from the new state when it is written, copied to the output
/// register when a finished subtile enters it.
fn colours(m: &mut Module, w: &ScuWidths) {
    let p_n = w.passes;
    let ps = pass(w);
    m.blank();
    m.comment(format!(
        "The new state's colour: min(255, (255 C + 2^{}) >> {}) per channel (golden to_u8).",
        w.out_shift - 1,
        w.out_shift
    ));
    let acc: Vec<String> = CHANNELS.iter().map(|ch| format!("{ch}_new")).collect();
    for a in &acc {
        m.wire(a, w.c);
    }
    m.assign(format!("{{{}}}", rev(&acc)), "c_i");
    let outs: Vec<String> = CHANNELS.iter().zip(&acc).map(|(ch, a)| convert(m, w, a, ch)).collect();
    m.wire_assign("rgb_d", RGB_BITS, format!("{{{}}}", rev(&outs)));
    m.mem("rgb_q", RGB_BITS, p_n).reg("out_q", RGB_BITS * p_n);
    m.seq_noreset(vec![if_("en_i & wr_i", vec![set(format!("rgb_q[{ps}]"), "rgb_d")])]);
    m.seq_noreset(vec![if_(
        "out_i",
        vec![for_(
            "p",
            p_n.to_string(),
            vec![set(
                format!("out_q[p*{RGB_BITS} +: {RGB_BITS}]"),
                format!("{} ? rgb_d : rgb_q[p]", bit(w, "hit", "p")),
            )],
        )],
    )]);
    m.assign("rgb_o", "out_q");
}

/// `min(255, (c * 255 + 2^(K-1)) >> K)` of accumulator `c`; returns the 8-bit wire `{name}_u8`.
fn convert(m: &mut Module, w: &ScuWidths, c: &str, name: &str) -> String {
    let k = w.out_shift;
    let xw = w.c + OUT_BITS + 1;
    assert!(xw > k + OUT_BITS, "output conversion needs more than {OUT_BITS} bits");
    let x = format!("{name}_x");
    m.wire_assign(
        &x,
        xw,
        format!("{{1'b0, {c}, {}}} - {} + {}", lit(OUT_BITS, 0), zext(c, w.c, xw), lit(xw, 1 << (k - 1))),
    );
    let out = format!("{name}_u8");
    m.wire_assign(
        &out,
        OUT_BITS,
        format!(
            "(|{x}[{}:{}]) ? {} : {x}[{}:{k}]",
            xw - 1,
            k + OUT_BITS,
            lit(OUT_BITS, (1 << OUT_BITS) - 1),
            k + OUT_BITS - 1
        ),
    );
    out
}
