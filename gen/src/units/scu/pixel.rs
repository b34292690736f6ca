//! `neo_scu_pixel`: one pixel of the SCU's subtile: its state `{done, colour, T}` (written by
//! its lane's blend when its pass is in S5), its saved states (one row per subtile slot, for
//! lists that arrive in pieces) and its 8-bit output colour.

use super::blend::{rev, CHANNELS};
use super::ScuWidths;
use crate::emit::expr::{lit, zext};
use crate::emit::{if_, set, Module};
use neo_golden::engine::EngineConfig;
use neo_golden::raster::RGB_BITS;

/// Module name.
pub const NAME: &str = "neo_scu_pixel";

/// Bits of one output channel.
const OUT_BITS: u32 = RGB_BITS / 3;

/// The pixel for `cfg`.
pub fn module(cfg: &EngineConfig) -> Module {
    let w = ScuWidths::new(cfg);
    let (t, c) = (w.t, w.c);
    let slots = 1u32 << w.row_bits;
    let mut m = Module::new(NAME);
    m.doc("One SCU pixel: transmittance T, colour accumulators {blue, green, red} and done; the saved");
    m.doc(format!(
        "states of {} subtiles (bank_q[slot] = {{done, colour, T}}); the output colour of the next state.",
        w.rows
    ));
    m.clock_reset();
    m.input_c("en_i", 1, "the SCU pipeline advances");
    m.input_c("wr_i", 1, "the pixel's pass is blended (S5): take the lane's new state");
    m.input_c("t_i", t, "the lane's new state: transmittance");
    m.input_c("c_i", 3 * c, "colour accumulators");
    m.input_c("done_i", 1, "done");
    m.input_c("save_i", 1, "a piece that does not end its subtile ends: save the next state");
    m.input_c("slot_i", w.row_bits, "the subtile's state slot (save and resume)");
    m.output_c("t_o", t, "the state");
    m.output_c("c_o", 3 * c, "");
    m.output_c("done_o", 1, "");
    m.output_c("saved_t_o", t, "the state saved in slot_i");
    m.output_c("saved_c_o", 3 * c, "");
    m.output_c("saved_done_o", 1, "");
    m.output_c("done_d_o", 1, "the next state's done bit");
    m.output_c("rgb_o", RGB_BITS, "the next state's colour {blue, green, red}, 8 bits each");
    m.reg("t_q", t).reg("c_q", 3 * c).reg("done_q", 1);
    m.wire_assign("t_d", t, "wr_i ? t_i : t_q");
    m.wire_assign("c_d", 3 * c, "wr_i ? c_i : c_q");
    m.wire_assign("done_d", 1, "wr_i ? done_i : done_q");
    m.seq(vec![set("done_q", lit(1, 1))], vec![if_("en_i & wr_i", vec![set("done_q", "done_i")])]);
    m.seq_noreset(vec![if_("en_i", vec![if_("wr_i", vec![set("t_q", "t_i"), set("c_q", "c_i")])])]);
    m.assign("t_o", "t_q").assign("c_o", "c_q").assign("done_o", "done_q");
    m.blank();
    m.comment("Saved states, one row per subtile slot.");
    m.mem("bank_q", w.state_bits(), slots);
    m.seq_noreset(vec![if_("en_i & save_i", vec![set("bank_q[slot_i]", "{done_d, c_d, t_d}")])]);
    m.assign("{saved_done_o, saved_c_o, saved_t_o}", "bank_q[slot_i]");
    m.assign("done_d_o", "done_d");
    m.blank();
    m.comment(format!(
        "Output colour: min(255, (255 C + 2^{}) >> {}) per channel (golden to_u8).",
        w.out_shift - 1,
        w.out_shift
    ));
    let acc: Vec<String> = CHANNELS.iter().map(|ch| format!("{ch}_d")).collect();
    for a in &acc {
        m.wire(a, c);
    }
    m.assign(format!("{{{}}}", rev(&acc)), "c_d");
    let outs: Vec<String> = CHANNELS.iter().zip(&acc).map(|(ch, a)| convert(&mut m, &w, a, ch)).collect();
    m.assign("rgb_o", format!("{{{}}}", rev(&outs)));
    m
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
