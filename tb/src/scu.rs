//! The SCU test bench: subtile lists through `neo_scu` under random input stalls and output
//! backpressure, every pixel of every list checked against golden
//! [`neo_golden::raster::shade_pixel`] (the per-pixel definition of the SCU arithmetic), plus the
//! latency / II measurement for `reports/latency.json`.
//!
//! Driver ([`Source`] on the Gaussian beat ports), golden ([`golden_pixels`]) and checker
//! ([`Checker`], per pixel and channel) are separate. A list of `n >= 1` Gaussians is `n` beats
//! with `last` on the final one; an empty list is one `empty`, `last` beat; the origin and the
//! inside columns / rows ride on every beat but only the first beat's count.

use crate::bits::get_bits;
use crate::check::Checker;
use crate::dut::Clocked;
use crate::rng::Rng;
use crate::stream::{Beat, Sink, Source};
use neo_gen::EngineConfig;
use neo_golden::formats::conic::QuantConic;
use neo_golden::formats::feature::{quantize, FeatureEntry, FeatureFormat};
use neo_golden::raster::synth::{cov_from_axes, projected_from_cov};
use neo_golden::raster::{pixel_alpha, shade_pixel, ExpTable, RasterConfig, RGB_BITS};
use neo_golden::sort::DepthKeyCodec;
use std::collections::VecDeque;

/// One subtile's work: its top-left pixel, the columns / rows inside the image, and the routed
/// Gaussians in table order.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ScuList {
    /// Top-left pixel `[x, y]`.
    pub origin: [u32; 2],
    /// Columns inside the image (0..=side).
    pub cols: u32,
    /// Rows inside the image (0..=side).
    pub rows: u32,
    /// The Gaussians.
    pub entries: Vec<FeatureEntry>,
}

/// What a run did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ScuRun {
    /// Lists checked.
    pub lists: usize,
    /// Gaussians sent.
    pub gaussians: usize,
    /// Cycles from the end of reset to the last output.
    pub cycles: u64,
    /// Cycles in which `term_o` was high.
    pub term_cycles: u64,
}

/// The input data ports, in beat order.
const IN_PORTS: [&str; 19] = [
    "in_mean_x_i",
    "in_mean_y_i",
    "in_conic_a_i",
    "in_conic_b_i",
    "in_conic_c_i",
    "in_conic_exp_i",
    "in_opacity_i",
    "in_red_i",
    "in_green_i",
    "in_blue_i",
    "in_empty_i",
    "in_last_i",
    "in_origin_x_i",
    "in_origin_y_i",
    "in_cols_i",
    "in_rows_i",
    "in_final_i",
    "in_resume_i",
    "in_sub_i",
];

/// How a beat ends and starts pieces: `last` ends the piece, `fin` (with `last`) ends the
/// subtile, `resume` (first beat of a piece) continues the subtile saved in slot `sub`.
#[derive(Clone, Copy, Debug)]
struct PieceFlags {
    last: bool,
    fin: bool,
    resume: bool,
    sub: u64,
}

/// The widths of [`IN_PORTS`] on `dut` (the values of a beat are cut to them).
pub fn in_widths<M: Clocked>(dut: &M) -> Vec<u32> {
    IN_PORTS.iter().map(|n| dut.io_width(dut.pin(n))).collect()
}

/// The beat of Gaussian `e` (None: an empty beat) of a list, each value cut to its port's
/// width (`widths`, [`in_widths`]).
fn beat(e: Option<&FeatureEntry>, list: &ScuList, fl: PieceFlags, widths: &[u32]) -> Beat {
    let f = e.copied().unwrap_or_default();
    let vals: [u64; 19] = [
        f.mean[0] as u32 as u64,
        f.mean[1] as u32 as u64,
        f.conic.a as u32 as u64,
        f.conic.b as u32 as u64,
        f.conic.c as u32 as u64,
        f.conic.exp as u64,
        f.opacity as u32 as u64,
        f.rgb[0] as u32 as u64,
        f.rgb[1] as u32 as u64,
        f.rgb[2] as u32 as u64,
        e.is_none() as u64,
        fl.last as u64,
        list.origin[0] as u64,
        list.origin[1] as u64,
        list.cols as u64,
        list.rows as u64,
        fl.fin as u64,
        fl.resume as u64,
        fl.sub,
    ];
    vals.iter().enumerate().map(|(k, &v)| vec![(v & ((1u64 << widths[k]) - 1)) as u32]).collect()
}

/// The beats of `list` (one piece, slot 0) for input ports of `widths`.
pub fn beats(list: &ScuList, widths: &[u32]) -> Vec<Beat> {
    piece_beats(list, 0..list.entries.len(), false, true, 0, widths)
}

/// The beats of the piece `range` of `list`'s entries (an empty range: one empty beat),
/// resuming the subtile saved in slot `sub` when `resume`, and ending it when `fin`.
fn piece_beats(
    list: &ScuList,
    range: std::ops::Range<usize>,
    resume: bool,
    fin: bool,
    sub: u64,
    widths: &[u32],
) -> Vec<Beat> {
    let flags = |last: bool| PieceFlags { last, fin: fin && last, resume, sub };
    if range.is_empty() {
        return vec![beat(None, list, flags(true), widths)];
    }
    let end = range.end;
    range.map(|i| beat(Some(&list.entries[i]), list, flags(i + 1 == end), widths)).collect()
}

/// The beats of `lists` cut into `pieces` pieces each (random cut points, empty pieces
/// included) and interleaved as the raster core sends them: piece 0 of every list (list `k` in
/// slot `k`), then piece 1 of every list, ...; only the last pieces end their subtiles, so the
/// outputs come in list order. `widths`: the input ports' ([`in_widths`]).
pub fn interleaved_piece_beats(rng: &mut Rng, lists: &[ScuList], pieces: usize, widths: &[u32]) -> Vec<Beat> {
    let cuts: Vec<Vec<usize>> = lists
        .iter()
        .map(|l| {
            let mut c: Vec<usize> =
                (1..pieces).map(|_| rng.below(l.entries.len() as u64 + 1) as usize).collect();
            c.push(0);
            c.push(l.entries.len());
            c.sort_unstable();
            c
        })
        .collect();
    let mut out = Vec::new();
    for p in 0..pieces {
        for (k, l) in lists.iter().enumerate() {
            out.extend(piece_beats(l, cuts[k][p]..cuts[k][p + 1], p > 0, p + 1 == pieces, k as u64, widths));
        }
    }
    out
}

/// Golden: the subtile's pixels (row-major), `shade_pixel` over the whole list for pixels
/// inside the image, black outside.
pub fn golden_pixels(list: &ScuList, fmt: &FeatureFormat, rc: &RasterConfig) -> Vec<[u8; 3]> {
    let s = rc.subtile;
    let mut out = Vec::with_capacity((s * s) as usize);
    for ly in 0..s {
        for lx in 0..s {
            if lx < list.cols && ly < list.rows {
                let (px, py) = ((list.origin[0] + lx) as i64, (list.origin[1] + ly) as i64);
                out.push(shade_pixel(&list.entries, fmt, rc, px, py).color);
            } else {
                out.push([0; 3]);
            }
        }
    }
    out
}

/// Sends `lists` through a fresh SCU (input stalls with probability `stall_pct`, output ready
/// with probability `ready_pct`), checking every pixel against [`golden_pixels`] and the
/// valid/ready rules; panics at the first mismatch. `dut` is `neo_scu` built from `cfg` (the
/// static model for [`crate::config`], a run-time one for another configuration).
pub fn run_checked<M: Clocked>(
    dut: &mut M,
    cfg: &EngineConfig,
    seed: u64,
    lists: &[ScuList],
    stall_pct: u32,
    ready_pct: u32,
) -> ScuRun {
    let widths = in_widths(dut);
    let all: Vec<Beat> = lists.iter().flat_map(|l| beats(l, &widths)).collect();
    run_beats_checked(dut, cfg, seed, lists, all, stall_pct, ready_pct)
}

/// [`run_checked`] with each list cut into `pieces` interleaved pieces
/// ([`interleaved_piece_beats`]; at most the SCU's state slots of lists).
pub fn run_pieces_checked<M: Clocked>(
    dut: &mut M,
    cfg: &EngineConfig,
    seed: u64,
    lists: &[ScuList],
    pieces: usize,
    stall_pct: u32,
    ready_pct: u32,
) -> ScuRun {
    let slots = neo_gen::units::scu::ScuWidths::new(cfg).rows as usize;
    assert!(lists.len() <= slots, "{} lists for {slots} state slots", lists.len());
    let mut rng = Rng::new(seed ^ 0x9e37);
    let all = interleaved_piece_beats(&mut rng, lists, pieces, &in_widths(dut));
    run_beats_checked(dut, cfg, seed, lists, all, stall_pct, ready_pct)
}

/// Sends `beats` (ending `lists`' subtiles in order) and checks the outputs.
fn run_beats_checked<M: Clocked>(
    dut: &mut M,
    cfg: &EngineConfig,
    seed: u64,
    lists: &[ScuList],
    beats: Vec<Beat>,
    stall_pct: u32,
    ready_pct: u32,
) -> ScuRun {
    let fmt = cfg.feature_format();
    let rc = cfg.raster_config();
    let mut rng = Rng::new(seed);
    let checker = Checker::new(dut.top(), seed);
    let mut src = Source::bind(dut, "in_valid_i", "in_ready_o", &IN_PORTS, rng.fork(1), stall_pct)
        .unwrap_or_else(|e| panic!("{e}"));
    let mut sink = Sink::bind(dut, "out_valid_o", "out_ready_i", &["out_rgb_o"], rng.fork(2), ready_pct)
        .unwrap_or_else(|e| panic!("{e}"));
    let p = ScuPorts::of(dut);
    let mut expected: VecDeque<Vec<[u8; 3]>> = VecDeque::with_capacity(lists.len());
    let beat_count = beats.len() as u64;
    for b in beats {
        src.push(b);
    }
    let mut gaussians = 0;
    for l in lists {
        gaussians += l.entries.len();
        expected.push_back(golden_pixels(l, &fmt, &rc));
    }
    dut.io_set(p.in_valid, 0);
    dut.io_set(p.out_ready, 0);
    dut.io_reset();
    let passes = (rc.subtile * rc.subtile) as u64 / cfg.scu_lanes as u64;
    let limit = 1000 + beat_count * (passes + 2) * 8 + 40 * lists.len() as u64;
    let mut index = 0usize;
    let mut term_cycles = 0;
    while let Some(want) = expected.front() {
        if dut.io_cycle() > limit {
            checker.fail(dut.io_cycle(), "out_valid_o", "a subtile", &format!("none for {limit} cycles"));
        }
        src.drive(dut);
        sink.drive(dut);
        dut.io_eval();
        term_cycles += dut.flag(p.term) as u64;
        src.sample(dut);
        if let Some(b) = sink.sample(dut, &checker) {
            for (k, px) in want.iter().enumerate() {
                for (c, name) in ["red", "green", "blue"].iter().enumerate() {
                    let got = get_bits(&b[0], RGB_BITS as usize * k + 8 * c, 8);
                    if got != px[c] as u64 {
                        let s = rc.subtile as usize;
                        checker.value(
                            dut.io_cycle(),
                            &format!("list {index} pixel {k} (lx {}, ly {}).{name}", k % s, k / s),
                            px[c] as u64,
                            got,
                        );
                    }
                }
            }
            expected.pop_front();
            index += 1;
        }
        dut.io_tick();
    }
    checker.protocol(dut.io_cycle(), src.is_idle(), "an output for every list but input beats left over");
    for _ in 0..passes + 12 {
        dut.io_set(p.in_valid, 0);
        dut.io_set(p.out_ready, 1);
        dut.io_eval();
        checker.protocol(dut.io_cycle(), !dut.flag(p.out_valid), "an output subtile with no list left");
        dut.io_tick();
    }
    ScuRun { lists: lists.len(), gaussians, cycles: dut.io_cycle(), term_cycles }
}

/// The control ports the SCU bench drives and reads itself (the streams' are bound by the agents).
#[derive(Clone, Copy)]
struct ScuPorts {
    in_valid: usize,
    out_ready: usize,
    out_valid: usize,
    out_rgb: usize,
    term: usize,
}

impl ScuPorts {
    fn of<M: Clocked>(dut: &M) -> Self {
        ScuPorts {
            in_valid: dut.pin("in_valid_i"),
            out_ready: dut.pin("out_ready_i"),
            out_valid: dut.pin("out_valid_o"),
            out_rgb: dut.pin("out_rgb_o"),
            term: dut.pin("term_o"),
        }
    }
}

/// A log-uniform draw in `[lo, hi]`.
fn log_uniform(rng: &mut Rng, lo: f64, hi: f64) -> f64 {
    let u = rng.below(1 << 30) as f64 / (1u64 << 30) as f64;
    (lo.ln() + u * (hi.ln() - lo.ln())).exp()
}

/// A uniform draw in `[lo, hi)`.
fn uniform(rng: &mut Rng, lo: f64, hi: f64) -> f64 {
    lo + (hi - lo) * (rng.below(1 << 30) as f64 / (1u64 << 30) as f64)
}

/// A quantised Gaussian with centre `mean` (pixels), axes `su, sv`, angle `th`.
pub fn gaussian(mean: [f64; 2], su: f64, sv: f64, th: f64, opacity: f64, rgb: [f64; 3]) -> FeatureEntry {
    let cov = cov_from_axes(su, sv, th);
    let p = projected_from_cov(
        0,
        [mean[0] as f32, mean[1] as f32],
        cov,
        opacity as f32,
        rgb.map(|c| c as f32),
        1.0,
    );
    quantize(&p, &FeatureFormat::default(), &DepthKeyCodec::Fp16)
}

/// The first Gaussian whose alpha at pixel `(px, py)` is exactly `alpha` (golden
/// `pixel_alpha`, raw), searching opacities upwards and, for each, means 0..400 pixels to the
/// right of the pixel; `None` when none has it. The directed cases at the 1/255 threshold.
pub fn gaussian_with_alpha(
    fmt: &FeatureFormat,
    rc: &RasterConfig,
    px: i64,
    py: i64,
    alpha: i64,
) -> Option<FeatureEntry> {
    let exp = ExpTable::new(&rc.blend.exp, rc.blend.power_frac);
    for op in 1..(1i32 << fmt.opacity.bits) {
        for off in 0..400 {
            let mut e = gaussian([px as f64 + 1.0, py as f64], 1.5, 1.5, 0.0, 0.5, [1.0, 0.25, 0.5]);
            e.opacity = op;
            e.mean[0] += off;
            if pixel_alpha(&e, fmt, rc, &exp, px, py) == Some(alpha) {
                return Some(e);
            }
        }
    }
    None
}

/// The top of the SCU's origin range: the last subtile whose pixels the origin field holds
/// (`2^(mean.bits - mean.frac) - S` on both axes; the datapath is sized for it, ScuWidths::origin).
pub fn top_origin(fmt: &FeatureFormat, side: u32) -> [u32; 2] {
    let o = (1u32 << (fmt.mean.bits - fmt.mean.frac)) - side;
    [o, o]
}

/// Gaussians at the far end of the lane datapath for the subtile at [`top_origin`]: means at
/// the most negative raw value, 3/4, 1/2 and 0 of it on each axis (`|dx|`, `|dy|` from below
/// `2^(mean.bits)` up to their bound `2^(mean.bits - 1) + (2^origin - 1) 2^Fm`, so the squares
/// reach `2^(2 mean.bits + 1)`), positive definite conics with the largest mantissa at
/// `2^M - 1`, `2^(M-1)`, `2^(M-2)`, `2^(M-3)` (`b` of both signs) and exponents from the
/// largest down by 4 (`np` from 0 to the saturation), opacities from the largest down to one
/// LSB and colours up to the largest. All are quantised values the formats hold (a screen-filling Gaussian far off).
pub fn far_gaussians(fmt: &FeatureFormat) -> Vec<FeatureEntry> {
    let lo = -(1i64 << (fmt.mean.bits - 1));
    let means = [lo, lo / 4 * 3, lo / 2, 0];
    let m = fmt.conic.max_mantissa();
    // (a, b, c) with b^2 < a c; the largest of each at 2^M - 1 .. 2^(M-3).
    let conics = [
        (m, -(m - 1), m),
        (m / 2 + 1, m / 4, m),
        (m / 4 + 3, -(m / 8), m / 2),
        (m / 8 + 5, m / 16 + 1, m / 8 + 1),
    ];
    let max_exp = fmt.conic.max_exp();
    let max_col = (1i64 << fmt.color.bits) - 1;
    let max_op = (1i64 << fmt.opacity.bits) - 1;
    let mut out = Vec::new();
    for (i, &mean_y) in means.iter().enumerate() {
        for (j, &mean_x) in means.iter().enumerate() {
            for (k, &(a, b, c)) in conics.iter().enumerate() {
                let n = (16 * i + 4 * j + k) as u32;
                out.push(FeatureEntry {
                    mean: [mean_x as i32, mean_y as i32],
                    conic: QuantConic {
                        a: a as i32,
                        b: b as i32,
                        c: c as i32,
                        exp: max_exp.saturating_sub(4 * (n % 8)),
                    },
                    opacity: [max_op, max_op / 3, max_op / 8, 1][(n / 8 % 4) as usize] as i32,
                    rgb: [max_col, max_col / 2 + n as i64, (n as i64 * 97) % (max_col + 1)].map(|v| v as i32),
                    ..FeatureEntry::default()
                });
            }
        }
    }
    out
}

/// A random Gaussian for a subtile at `origin`: mostly real (quantised) Gaussians near the
/// subtile of every size and anisotropy, some with raw random fields (any conic, including
/// non positive definite ones), some far away or huge.
pub fn random_gaussian(rng: &mut Rng, fmt: &FeatureFormat, origin: [u32; 2]) -> FeatureEntry {
    let o = [origin[0] as f64, origin[1] as f64];
    match rng.below(100) {
        0..=69 => {
            let mean = [o[0] + uniform(rng, -10.0, 18.0), o[1] + uniform(rng, -10.0, 18.0)];
            let su = log_uniform(rng, 0.2, 20.0);
            let sv = log_uniform(rng, 0.2, 20.0);
            let th = uniform(rng, 0.0, std::f64::consts::PI);
            let op = if rng.percent(20) { uniform(rng, 0.9, 1.0) } else { uniform(rng, 0.0, 1.0) };
            let rgb = [uniform(rng, 0.0, 1.6), uniform(rng, 0.0, 1.6), uniform(rng, 0.0, 1.6)];
            gaussian(mean, su, sv, th, op, rgb)
        }
        70..=84 => {
            let m = fmt.conic.max_mantissa() as u64;
            let mut e = gaussian([o[0] + 4.0, o[1] + 4.0], 2.0, 2.0, 0.0, 0.5, [0.5; 3]);
            let (lo, hi) = (-(1i64 << (fmt.mean.bits - 1)), (1i64 << (fmt.mean.bits - 1)) - 1);
            for m in e.mean.iter_mut() {
                *m = (*m as i64 + rng.range(0, 8 << 8) as i64 - (4 << 8)).clamp(lo, hi) as i32;
            }
            e.conic.a = rng.below(m + 1) as i32;
            e.conic.c = rng.below(m + 1) as i32;
            e.conic.b = rng.below(2 * m + 1) as i32 - m as i32;
            e.conic.exp = rng.below(fmt.conic.max_exp() as u64 + 1) as u32;
            e.opacity = rng.below(1 << fmt.opacity.bits) as i32;
            for c in e.rgb.iter_mut() {
                *c = rng.below(1 << fmt.color.bits) as i32;
            }
            e
        }
        85..=92 => {
            // Far away (outside the subtile, up to a few hundred pixels).
            let mean = [o[0] + uniform(rng, -300.0, 300.0), o[1] + uniform(rng, -300.0, 300.0)];
            gaussian(
                mean,
                log_uniform(rng, 0.5, 80.0),
                log_uniform(rng, 0.5, 80.0),
                1.0,
                0.8,
                [0.7, 0.2, 0.9],
            )
        }
        _ => {
            // Screen-filling.
            let mean = [o[0] + uniform(rng, -500.0, 500.0), o[1] + uniform(rng, -500.0, 500.0)];
            gaussian(
                mean,
                log_uniform(rng, 300.0, 3000.0),
                log_uniform(rng, 300.0, 3000.0),
                0.4,
                0.3,
                [1.0, 0.9, 0.1],
            )
        }
    }
}

/// A random list: origin, inside counts (mostly the whole subtile) and up to `max_len`
/// Gaussians.
pub fn random_list(rng: &mut Rng, fmt: &FeatureFormat, side: u32, max_len: usize) -> ScuList {
    let far = rng.percent(5);
    let span = if far { 8000 } else { 512 };
    let origin = [rng.below(span) as u32 * side, rng.below(span) as u32 * side];
    let (cols, rows) = if rng.percent(15) {
        (rng.below(side as u64 + 1) as u32, rng.below(side as u64 + 1) as u32)
    } else {
        (side, side)
    };
    let n = rng.below(max_len as u64 + 1) as usize;
    let entries = (0..n).map(|_| random_gaussian(rng, fmt, origin)).collect();
    ScuList { origin, cols, rows, entries }
}

/// Latency and II of `neo_scu`, measured at full rate with the output always ready.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ScuTiming {
    /// Rising edges from the edge that accepts a list's last beat to the first cycle its
    /// subtile is offered (`out_valid_o`), pipeline otherwise empty.
    pub latency: u64,
    /// Cycles per Gaussian in a long list that does not terminate.
    pub ii: u64,
    /// Gaussians of the II measurement.
    pub gaussians: u64,
    /// Cycles per Gaussian drained after the subtile terminated (second half of an opaque
    /// stack of `gaussians`).
    pub drain_ii: u64,
}

/// Runs one list at full rate; returns the cycle out_valid_o first rises and the cycle of every
/// input transfer. Checks the pixels against golden.
fn timed<M: Clocked>(dut: &mut M, cfg: &EngineConfig, seed: u64, list: &ScuList) -> (u64, Vec<u64>) {
    let fmt = cfg.feature_format();
    let rc = cfg.raster_config();
    let checker = Checker::new(dut.top(), seed);
    let mut rng = Rng::new(seed);
    let mut src = Source::bind(dut, "in_valid_i", "in_ready_o", &IN_PORTS, rng.fork(1), 0)
        .unwrap_or_else(|e| panic!("{e}"));
    for b in beats(list, &in_widths(dut)) {
        src.push(b);
    }
    let want = golden_pixels(list, &fmt, &rc);
    let p = ScuPorts::of(dut);
    let mut got = vec![0u32; dut.io_width(p.out_rgb).div_ceil(32) as usize];
    dut.io_set(p.out_ready, 1);
    dut.io_set(p.in_valid, 0);
    dut.io_reset();
    let mut sent = Vec::new();
    loop {
        if dut.io_cycle() > 100_000 {
            checker.fail(dut.io_cycle(), "out_valid_o", "a subtile", "none");
        }
        src.drive(dut);
        dut.io_eval();
        if src.sample(dut) {
            sent.push(dut.io_cycle());
        }
        if dut.flag(p.out_valid) {
            dut.io_get_words(p.out_rgb, &mut got);
            for (k, px) in want.iter().enumerate() {
                for (c, &v) in px.iter().enumerate() {
                    checker.value(
                        dut.io_cycle(),
                        &format!("pixel {k}.{c}"),
                        v as u64,
                        get_bits(&got, RGB_BITS as usize * k + 8 * c, 8),
                    );
                }
            }
            let out = dut.io_cycle();
            dut.io_tick();
            return (out, sent);
        }
        dut.io_tick();
    }
}

/// Measures [`ScuTiming`] (every output checked against golden).
pub fn measure_timing<M: Clocked>(dut: &mut M, cfg: &EngineConfig, seed: u64) -> ScuTiming {
    let fmt = cfg.feature_format();
    let side = cfg.raster_config().subtile;
    let origin = [64, 128];
    let one = ScuList {
        origin,
        cols: side,
        rows: side,
        entries: vec![gaussian([67.0, 131.0], 2.0, 2.0, 0.0, 0.5, [0.5; 3])],
    };
    let (out, sent) = timed(dut, cfg, seed, &one);
    let last = sent[sent.len() - 1];
    // A long list of faint Gaussians: never terminates.
    let mut rng = Rng::new(seed ^ 1);
    let n = 256u64;
    let faint: Vec<FeatureEntry> = (0..n)
        .map(|_| {
            let mut e = random_gaussian(&mut rng, &fmt, origin);
            e.opacity = e.opacity.min(8);
            e
        })
        .collect();
    let list = ScuList { origin, cols: side, rows: side, entries: faint };
    let (_, sent) = timed(dut, cfg, seed, &list);
    let ii = (sent[n as usize - 1] - sent[0]) / (n - 1);
    // An opaque stack: terminates after a few Gaussians, the rest drain.
    let mut opaque = vec![gaussian([68.0, 132.0], 400.0, 400.0, 0.0, 0.999, [0.2, 0.4, 0.6]); n as usize];
    opaque[0].rgb = [100, 200, 300];
    let list = ScuList { origin, cols: side, rows: side, entries: opaque };
    let (_, sent) = timed(dut, cfg, seed, &list);
    let h = n as usize / 2;
    let drain_ii = (sent[n as usize - 1] - sent[h]) / (n - 1 - h as u64);
    ScuTiming { latency: out - last, ii, gaussians: n, drain_ii }
}

/// Runs `cfg`'s lists and returns them with the run (for tests that build lists themselves).
pub fn lists_of(rng: &mut Rng, cfg: &EngineConfig, count: usize, max_len: usize) -> Vec<ScuList> {
    let fmt = cfg.feature_format();
    let side = cfg.raster_config().subtile;
    (0..count).map(|_| random_list(rng, &fmt, side, max_len)).collect()
}
