//! `neo_scu_blend`: one lane's blend (combinational), from `neo_scu`'s S5 registers and the
//! pixel's state: a list's first beat starts the pixel from `T = 1, C = 0` (or from its saved
//! state when the piece resumes); a blended Gaussian takes `w = round(alpha T)`, and either
//! drives `T` below the floor (the pixel is done, the Gaussian is not added) or adds `rgb w` to
//! the colour and sets `T -= w`.

use super::{pixel_bits, ScuWidths};
use crate::emit::expr::{lit, zext};
use crate::emit::Module;
use neo_golden::engine::EngineConfig;

/// Module name.
pub const NAME: &str = "neo_scu_blend";

/// The colour channels, lowest first, as packed in a pixel's colour accumulator `{b, g, r}`.
pub(super) const CHANNELS: [&str; 3] = ["red", "green", "blue"];

/// The blend for `cfg`.
pub fn module(cfg: &EngineConfig) -> Module {
    let w = ScuWidths::new(cfg);
    let (t, c, a, sb) = (w.t, w.c, w.alpha_frac, w.side_bits);
    let mut m = Module::new(NAME);
    m.doc(
        "One SCU lane's blend (golden shade_pixel's update, combinational): the pixel's new transmittance,",
    );
    m.doc("colour accumulators {blue, green, red} and done bit after one Gaussian.");
    m.input_c("pixel_i", pixel_bits(&w), "pixel {y, x} of the subtile");
    m.input_c("cols_i", sb + 1, "columns inside the image");
    m.input_c("rows_i", sb + 1, "rows inside the image");
    m.input_c("first_i", 1, "the list's first beat: start the pixel afresh ...");
    m.input_c("resume_i", 1, "... or from its saved state");
    for ch in CHANNELS {
        m.input_c(format!("{ch}_i"), w.color, "the Gaussian's colour");
    }
    m.input_c("alpha_i", a, "alpha, alpha_frac fraction bits");
    m.input_c("blend_i", 1, "the Gaussian is blended (alpha >= 1/255)");
    m.input_c("t_i", t, "the pixel's state: transmittance");
    m.input_c("c_i", 3 * c, "colour accumulators {blue, green, red}");
    m.input_c("done_i", 1, "done");
    m.input_c("saved_t_i", t, "the pixel's saved state (resume)");
    m.input_c("saved_c_i", 3 * c, "");
    m.input_c("saved_done_i", 1, "");
    m.output_c("t_o", t, "the new state");
    m.output_c("c_o", 3 * c, "");
    m.output_c("done_o", 1, "");
    m.wire("pixel_x", sb).wire("pixel_y", sb);
    m.assign("{pixel_y, pixel_x}", "pixel_i");
    m.wire_assign(
        "in_image",
        1,
        format!("({} < cols_i) & ({} < rows_i)", zext("pixel_x", sb, sb + 1), zext("pixel_y", sb, sb + 1)),
    );
    m.comment("The state before this Gaussian.");
    m.wire_assign("t_old", t, format!("first_i ? (resume_i ? saved_t_i : {}) : t_i", lit(t, 1 << w.t_frac)));
    m.wire_assign("c_old", 3 * c, format!("first_i ? (resume_i ? saved_c_i : {}) : c_i", lit(3 * c, 0)));
    m.wire_assign("done_old", 1, "first_i ? (resume_i ? saved_done_i : ~in_image) : done_i");
    m.wire_assign("bl", 1, "blend_i & ~done_old");
    let ww = a + t + 1;
    m.comment("w = round(alpha T); T' = T - w; T' below the floor: the pixel is done.");
    m.wire_assign(
        "wp",
        ww,
        format!("{} * {} + {}", zext("alpha_i", a, ww), zext("t_old", t, ww), lit(ww, 1 << (a - 1))),
    );
    m.wire_assign("wt", t, format!("wp[{}:{a}]", a + t - 1));
    m.wire_assign("tt", t, "t_old - wt");
    m.wire_assign("fin", 1, format!("tt < {}", lit(t, w.min_t)));
    m.wire_assign("add", 1, "bl & ~fin");
    m.assign("t_o", "add ? tt : t_old");
    m.assign("done_o", "done_old | (bl & fin)");
    let old: Vec<String> = CHANNELS.iter().map(|ch| format!("{ch}_old")).collect();
    for o in &old {
        m.wire(o, c);
    }
    m.assign(format!("{{{}}}", rev(&old)), "c_old");
    let mut sums = Vec::new();
    for (ch, o) in CHANNELS.iter().zip(&old) {
        let sum = format!("{ch}_sum");
        m.wire_assign(
            &sum,
            c,
            format!("{o} + {} * {}", zext(&format!("{ch}_i"), w.color, c), zext("wt", t, c)),
        );
        sums.push(sum);
    }
    m.assign("c_o", format!("add ? {{{}}} : c_old", rev(&sums)));
    m
}

/// `names` highest first, comma separated (a concatenation of channels packed lowest first).
pub(super) fn rev(names: &[String]) -> String {
    names.iter().rev().cloned().collect::<Vec<_>>().join(", ")
}
