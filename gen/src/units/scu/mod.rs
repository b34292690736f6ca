//! `neo_scu`: the Subtile Compute Unit, front-to-back alpha blending of the Gaussians routed to
//! one subtile, bit-exact with golden [`neo_golden::raster::scu`] (`shade_pixel` /
//! `raster_tile`), and its submodules, one generator file each:
//!
//! | module          | file        | what                                                      |
//! |-----------------|-------------|-----------------------------------------------------------|
//! | `neo_scu`       | `top.rs`    | list tracking, the issue stage, the beat pipeline, lanes, pixel state, output |
//! | `neo_scu_lane`  | `lane.rs`   | one pixel lane, S0..S5: quadratic form, exp, alpha        |
//! | `neo_scu_exp`   | `exp.rs`    | the exp unit (golden `ExpTable`, ROM from `ExpTable::table`) |
//! | `neo_scu_blend` | `blend.rs`  | one lane's blend: a pixel's new T, colour and done bit    |
//! | `neo_scu_pixels` | `pixel.rs` | one lane's pixels: states, saved states, output colours   |
//!
//! The beat bundle carried down the pipeline is laid out in `beat.rs`; its fields are named by
//! `localparam` offsets in the emitted Verilog.
//!
//! Every width and constant comes from the golden formats ([`EngineConfig::feature_format`],
//! [`EngineConfig::raster_config`]); nothing is retyped here.
//!
//! # Stream protocol
//! One input beat per Gaussian (`in_valid_i`/`in_ready_o`) with its feature-entry fields; a
//! subtile's list is the beats up to and including the one with `in_last_i`. The first beat of a
//! list (the first after reset or after a `last` beat) starts the subtile: its origin (pixel
//! coordinates of the top-left pixel) and `in_cols_i`/`in_rows_i` (how many columns / rows of
//! the subtile are inside the image; pixels outside start done and come out black) are taken,
//! and the state is cleared; those fields are ignored on the other beats. A beat with
//! `in_empty_i` carries no Gaussian; an empty list is one beat with `in_empty_i = in_last_i = 1`.
//! Per list one output beat (`out_valid_o`/`out_ready_i`) carries the subtile's pixels, pixel
//! `k = ly * S + lx` at `out_rgb_o[24k +: 24]` as `{blue, green, red}`.
//!
//! # Schedule
//! `L = scu_lanes` pixel lanes, `P = S*S / L` passes: a Gaussian occupies the issue stage for
//! `P` cycles (pass `p` evaluates pixels `p*L .. p*L+L-1`), so II = `P` cycles per Gaussian.
//! Stages: issue (S0), squares of `|dx|, |dy|` (S1), the exact quadratic form `q` (S2), `np` by
//! the rounding shift and saturation (S3), exp (S4), alpha with the 1/255 test (S5), then the
//! blend from S5's registers into the pixel state (transmittance and colour update, a
//! read-modify-write of the pass's pixels in one cycle, so there is no hazard). Latency from
//! accepting a list's last beat to `out_valid_o`: `P + 6` cycles. When every pixel of the list is done (`term_o` high while the list is still being
//! accepted) the rest of the list is drained at one beat per cycle without evaluation. A global
//! stall holds everything only while a finished list waits for the output register.

mod beat;
pub mod blend;
pub mod exp;
pub mod lane;
pub mod pixel;
mod top;

use crate::emit::expr::bits_for;
use neo_golden::engine::EngineConfig;
use neo_golden::raster::scu::min_power_shift;

pub use exp::NAME as EXP_NAME;
pub use top::module;

/// Module name of the SCU.
pub const NAME: &str = "neo_scu";
/// Pipeline stages after issue (S1..=S5).
pub const STAGES: u32 = 5;

/// The Gaussian's feature fields an SCU takes per beat, in port order: field `f` arrives on
/// port `in_{f}_i` ([`gaussian_port`]). The raster core feeds them from its feature buffer.
pub const GAUSSIAN_FIELDS: [&str; 10] =
    ["mean_x", "mean_y", "conic_a", "conic_b", "conic_c", "conic_exp", "opacity", "red", "green", "blue"];

/// The SCU input port of Gaussian field `field` (one of [`GAUSSIAN_FIELDS`]).
pub fn gaussian_port(field: &str) -> String {
    format!("in_{field}_i")
}
/// Width of the list counter that tags beats (more lists than fit in the pipeline).
const LID_BITS: u32 = 3;

/// Widths and constants of the SCU datapath, all derived from the golden formats.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ScuWidths {
    /// Mean field width.
    pub mean: u32,
    /// Mean fraction bits.
    pub mean_frac: u32,
    /// Conic mantissa bits `M` (`b` has `M + 1`).
    pub mant: u32,
    /// Conic exponent field width.
    pub cexp: u32,
    /// Opacity width (all fraction).
    pub opacity: u32,
    /// Colour channel width.
    pub color: u32,
    /// Origin coordinate width (pixels).
    pub origin: u32,
    /// Subtile side `S` and `log2 S`.
    pub side: u32,
    /// `log2 S`.
    pub side_bits: u32,
    /// Pixel lanes.
    pub lanes: u32,
    /// Passes per Gaussian, `S*S / lanes`.
    pub passes: u32,
    /// Signed `dx`/`dy` width.
    pub d: u32,
    /// `|dx|` width.
    pub u: u32,
    /// Signed width of the quadratic form `q`.
    pub q: u32,
    /// Conic-to-power shift at exponent 0.
    pub sh0: u32,
    /// `-power` width (`power_int + power_frac`) and its saturation value.
    pub np: u32,
    /// Largest `np`.
    pub max_np: u64,
    /// Exp result width (`out_frac + 1`).
    pub e: u32,
    /// Alpha fraction bits, cap and threshold.
    pub alpha_frac: u32,
    /// Alpha cap (raw).
    pub max_alpha: u64,
    /// Smallest blended alpha (raw).
    pub min_alpha: u64,
    /// `opacity.frac + out_frac - alpha_frac` (negative: a left shift).
    pub alpha_shift: i32,
    /// Transmittance width (`frac + 1`), 1.0 and the floor.
    pub t: u32,
    /// Transmittance fraction bits.
    pub t_frac: u32,
    /// Transmittance floor (raw).
    pub min_t: u64,
    /// Colour accumulator width `color.bits + t_frac + 1`.
    pub c: u32,
    /// Output shift `color.frac + t_frac`.
    pub out_shift: u32,
    /// Subtiles whose state the SCU keeps between pieces of their lists (the tile's subtiles
    /// over `raster_scus`: one per subtile group), and the width of their index.
    pub rows: u32,
    /// Width of `in_sub_i`.
    pub row_bits: u32,
}

impl ScuWidths {
    /// The widths for `cfg`.
    pub fn new(cfg: &EngineConfig) -> Self {
        let fmt = cfg.feature_format();
        let rc = cfg.raster_config();
        let b = rc.blend;
        let side = rc.subtile;
        assert!(side.is_power_of_two(), "subtile side {side} is not a power of two");
        let mean = fmt.mean.bits as u32;
        let mean_frac = fmt.mean.frac as u32;
        let mant = fmt.conic.mantissa_bits as u32;
        // px < 2^(origin + 1) so (px << Fm) < 2^(mean + 1): dx fits mean + 3 signed bits.
        let origin = mean - mean_frac;
        let d = mean + 3;
        let u = d - 1;
        let lanes = cfg.scu_lanes as u32;
        EngineConfig::validate(cfg).expect("valid configuration");
        let sh0 = min_power_shift(&fmt, &b);
        assert!(sh0 >= 1, "conic-to-power shift {sh0} < 1");
        ScuWidths {
            mean,
            mean_frac,
            mant,
            cexp: fmt.conic.exp_bits as u32,
            opacity: fmt.opacity.bits as u32,
            color: fmt.color.bits as u32,
            origin,
            side,
            side_bits: side.trailing_zeros(),
            lanes,
            passes: side * side / lanes,
            d,
            u,
            q: mant + 2 * u + 3,
            sh0: sh0 as u32,
            np: b.power_int as u32 + b.power_frac as u32,
            max_np: b.max_neg_power() as u64,
            e: b.exp.out_frac as u32 + 1,
            alpha_frac: b.alpha_frac as u32,
            max_alpha: b.max_alpha_raw() as u64,
            min_alpha: b.min_alpha_raw() as u64,
            alpha_shift: fmt.opacity.frac as i32 + b.exp.out_frac as i32 - b.alpha_frac as i32,
            t: b.transmittance_frac as u32 + 1,
            t_frac: b.transmittance_frac as u32,
            min_t: b.min_transmittance_raw() as u64,
            c: fmt.color.bits as u32 + b.transmittance_frac as u32 + 1,
            out_shift: fmt.color.frac as u32 + b.transmittance_frac as u32,
            rows: rc.subtiles_per_tile() / cfg.raster_scus as u32,
            row_bits: bits_for((rc.subtiles_per_tile() / cfg.raster_scus as u32).max(2) as u64 - 1),
        }
    }

    /// Pixels per subtile.
    pub fn pixels(&self) -> u32 {
        self.side * self.side
    }

    /// Bits of one pixel's saved state `{done, colour, T}`.
    pub fn state_bits(&self) -> u32 {
        self.t + 3 * self.c + 1
    }

    /// Width of the pass counter (at least 1).
    pub fn pass_bits(&self) -> u32 {
        bits_for(self.passes as u64 - 1)
    }
}

/// Width of a pixel's index in the subtile, `2 log2 S`.
fn pixel_bits(w: &ScuWidths) -> u32 {
    2 * w.side_bits
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn widths_follow_the_golden_formats() {
        let w = ScuWidths::new(&EngineConfig::default());
        assert_eq!(w.passes * w.lanes, 64);
        assert_eq!(w.max_alpha, 4055);
        assert_eq!(w.sh0, 23);
        // q: a 70-bit exact form at default widths needs no more than w.q bits.
        assert!(w.q >= 70, "{}", w.q);
    }
}
