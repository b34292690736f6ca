//! The ITU test bench: streams of (Gaussian, tile) jobs through `neo_itu` under random input
//! stalls and output backpressure, every result checked against golden
//! [`neo_golden::raster::subtile_bitmap`] (bitmap, OR bit and the sideband tag, in order).
//!
//! Stimulus: random raw field values (any bit pattern), random octagons near the tile, quantised
//! random Gaussians ([`neo_golden::formats::quantize`]), and the directed hard cases of
//! [`directed_jobs`].

use crate::bits::get_bits;
use crate::check::Checker;
use crate::dut::Clocked;
use crate::rng::Rng;
use crate::stream::{Beat, Sink, Source};
use neo_gen::units::itu::{geom_bits_lsb, mean_bits};
use neo_gen::EngineConfig;
use neo_golden::formats::{quantize, FeatureEntry, FeatureFormat};
use neo_golden::raster::subtile_bitmap;
use neo_golden::raster::synth::{cov_from_axes, projected_from_cov};
use neo_golden::sort::DepthKeyCodec;
use std::collections::VecDeque;

/// One ITU job: a feature entry and a tile.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ItuJob {
    /// The Gaussian (only its ITU fields reach the unit).
    pub entry: FeatureEntry,
    /// Tile indices `[x, y]` (below `2^tile_bits`).
    pub tile: [u32; 2],
}

impl ItuJob {
    /// The golden bitmap of this job.
    pub fn expected(&self, cfg: &EngineConfig) -> u64 {
        subtile_bitmap(&self.entry, &cfg.feature_format(), self.tile[0], self.tile[1], &cfg.raster_config())
    }
}

/// `width` bits at `lo` of `words` as little-endian 32-bit words.
fn field_words(words: &[u32], lo: usize, width: usize) -> Vec<u32> {
    let mut out = vec![0u32; width.div_ceil(32)];
    let mut done = 0;
    while done < width {
        let n = (width - done).min(32);
        out[done / 32] = get_bits(words, lo + done, n) as u32;
        done += n;
    }
    out
}

/// The packed entry as little-endian 32-bit words.
pub fn entry_words(e: &FeatureEntry, fmt: &FeatureFormat) -> Vec<u32> {
    e.pack(fmt).iter().flat_map(|w| [*w as u32, (w >> 32) as u32]).collect()
}

/// The input beat of a job: `mean_i`, `geom_i`, `tile_x_i`, `tile_y_i`, `tag_i`.
pub fn job_beat(cfg: &EngineConfig, job: &ItuJob, tag: u64) -> Beat {
    let words = entry_words(&job.entry, &cfg.feature_format());
    let (gb, glsb) = geom_bits_lsb(cfg);
    let tag_mask = if cfg.itu_tag_bits >= 64 { u64::MAX } else { (1u64 << cfg.itu_tag_bits) - 1 };
    let t = tag & tag_mask;
    vec![
        field_words(&words, 0, mean_bits(cfg) as usize),
        field_words(&words, glsb as usize, gb as usize),
        vec![job.tile[0]],
        vec![job.tile[1]],
        vec![t as u32, (t >> 32) as u32],
    ]
}

/// Statistics of a run.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ItuRun {
    /// Jobs checked.
    pub jobs: usize,
    /// Jobs whose golden bitmap is not empty.
    pub hits: usize,
    /// Total set bits over all golden bitmaps.
    pub set_bits: u64,
    /// Cycle of the first input transfer.
    pub first_in: Option<u64>,
    /// Cycle of the first output transfer.
    pub first_out: Option<u64>,
    /// Cycle of the last output transfer.
    pub last_out: Option<u64>,
}

/// Runs `jobs` through the ITU in order and checks every result (bitmap, hit, tag); stops at
/// the first mismatch naming the job, the field and the values in hex. `stall_pct` applies to
/// the input, `ready_pct` to the output. Resets the DUT first. `dut` is `neo_itu` built from
/// `cfg` (the static model for [`crate::config`], a run-time one for another configuration).
pub fn run_checked<M: Clocked>(
    dut: &mut M,
    cfg: &EngineConfig,
    seed: u64,
    jobs: &[ItuJob],
    stall_pct: u32,
    ready_pct: u32,
) -> ItuRun {
    let mut rng = Rng::new(seed);
    let checker = Checker::new(dut.top(), seed);
    let ins = ["mean_i", "geom_i", "tile_x_i", "tile_y_i", "tag_i"];
    let mut src = Source::bind(dut, "in_valid_i", "in_ready_o", &ins, rng.fork(1), stall_pct)
        .unwrap_or_else(|e| panic!("{e}"));
    let outs = ["bitmap_o", "hit_o", "tag_o"];
    let mut sink = Sink::bind(dut, "out_valid_o", "out_ready_i", &outs, rng.fork(2), ready_pct)
        .unwrap_or_else(|e| panic!("{e}"));
    let tag_mask = if cfg.itu_tag_bits >= 64 { u64::MAX } else { (1u64 << cfg.itu_tag_bits) - 1 };
    let (in_valid, out_ready, out_valid) =
        (dut.pin("in_valid_i"), dut.pin("out_ready_i"), dut.pin("out_valid_o"));
    dut.io_set(in_valid, 0);
    dut.io_set(out_ready, 0);
    dut.io_reset();
    let mut run = ItuRun { jobs: jobs.len(), ..ItuRun::default() };
    let mut expected: VecDeque<(usize, u64)> = VecDeque::new();
    for (i, j) in jobs.iter().enumerate() {
        src.push(job_beat(cfg, j, i as u64));
        let b = j.expected(cfg);
        run.hits += (b != 0) as usize;
        run.set_bits += b.count_ones() as u64;
        expected.push_back((i, b));
    }
    let budget = dut.io_cycle() + 100 + 50 * jobs.len() as u64;
    while !expected.is_empty() {
        if dut.io_cycle() > budget {
            checker.fail(
                dut.io_cycle(),
                "out_valid_o",
                &format!("job {}", expected[0].0),
                "no output (timeout)",
            );
        }
        src.drive(dut);
        sink.drive(dut);
        dut.io_eval();
        if src.sample(dut) && run.first_in.is_none() {
            run.first_in = Some(dut.io_cycle());
        }
        if let Some(beat) = sink.sample(dut, &checker) {
            let (i, want) = expected.pop_front().expect("checked non-empty");
            let c = dut.io_cycle();
            run.first_out.get_or_insert(c);
            run.last_out = Some(c);
            let got = beat[0][0] as u64 | (beat[0].get(1).copied().unwrap_or(0) as u64) << 32;
            if got != want {
                let j = &jobs[i];
                checker.fail(
                    c,
                    &format!("job {i} bitmap_o (tile {:?}, entry {:?})", j.tile, j.entry),
                    &format!("0x{want:016x}"),
                    &format!("0x{got:016x} (differs in bits 0x{:016x})", got ^ want),
                );
            }
            checker.value(c, &format!("job {i} hit_o"), (want != 0) as u64, beat[1][0] as u64);
            let tag = beat[2][0] as u64 | (beat[2].get(1).copied().unwrap_or(0) as u64) << 32;
            checker.value(c, &format!("job {i} tag_o"), i as u64 & tag_mask, tag);
        }
        dut.io_tick();
    }
    for _ in 0..3 {
        dut.io_set(in_valid, 0);
        dut.io_set(out_ready, 1);
        dut.io_eval();
        checker.protocol(dut.io_cycle(), !dut.flag(out_valid), "an output after the last job");
        dut.io_tick();
    }
    run
}

/// A signed raw value of `bits` bits from random bits.
fn sraw(rng: &mut Rng, bits: u8) -> i32 {
    let shift = 64 - bits as u32;
    ((rng.next_u64() << shift) as i64 >> shift) as i32
}

/// An extent raw value: mostly small (up to 640 raw, scaled by `scale`, the tile side over 64),
/// sometimes anything, sometimes unbounded.
fn ext(rng: &mut Rng, fmt: &FeatureFormat, scale: f64) -> i32 {
    let unb = fmt.unbounded_extent();
    match rng.below(20) {
        0 => unb,
        1 => unb - 1,
        2 => rng.below(unb as u64 + 1) as i32,
        3 => 0,
        _ => rng.below(((640.0 * scale) as u64).max(2)) as i32,
    }
}

/// A random tile: mostly small indices, sometimes anywhere in the `tile_bits` range.
fn tile(rng: &mut Rng, cfg: &EngineConfig) -> [u32; 2] {
    let max = 1u64 << cfg.tile_bits;
    let mut t = || if rng.percent(70) { rng.below(max.min(32)) as u32 } else { rng.below(max) as u32 };
    [t(), t()]
}

/// A mean raw value `pixels + jitter` around `origin` (pixels), saturated to the format.
fn mean_near(rng: &mut Rng, fmt: &FeatureFormat, origin: i64, reach: i64) -> i32 {
    let f = fmt.mean.frac as u32;
    let px = origin + rng.below(2 * reach as u64 + 1) as i64 - reach;
    let frac = match rng.below(4) {
        0 => 0,
        1 => 1i64 << (f - 1),
        _ => rng.below(1 << f) as i64,
    };
    fmt.mean.saturate((px << f) + frac) as i32
}

/// `count` random jobs: a mix of arbitrary raw fields, random octagons around the tile, and
/// quantised random Gaussians (needles to screen-fillers, all orientations). Sizes and distances
/// are those of the default 64-pixel tile, scaled with the configuration's tile side.
pub fn random_jobs(cfg: &EngineConfig, rng: &mut Rng, count: usize) -> Vec<ItuJob> {
    let fmt = cfg.feature_format();
    let t = cfg.raster_config().tile as i64;
    let scale = t as f64 / 64.0;
    let reach = ((140.0 * scale).round() as i64).max(1);
    (0..count)
        .map(|_| {
            let tile = tile(rng, cfg);
            let origin = [tile[0] as i64 * t, tile[1] as i64 * t];
            let mut e = FeatureEntry::default();
            match rng.below(10) {
                0 => {
                    // Arbitrary bits in every ITU field.
                    e.mean = [sraw(rng, fmt.mean.bits), sraw(rng, fmt.mean.bits)];
                    e.axis = [sraw(rng, fmt.axis.bits), sraw(rng, fmt.axis.bits)];
                    let mut any = || rng.below(fmt.unbounded_extent() as u64 + 1) as i32;
                    e.extent_xy = [any(), any()];
                    e.extent_uv = [any(), any()];
                }
                1..=5 => {
                    // A random octagon near the tile.
                    e.mean = [
                        mean_near(rng, &fmt, origin[0] + t / 2, reach),
                        mean_near(rng, &fmt, origin[1] + t / 2, reach),
                    ];
                    if rng.percent(10) {
                        e.axis = [sraw(rng, fmt.axis.bits), sraw(rng, fmt.axis.bits)];
                    } else {
                        let th = rng.below(1 << 16) as f64 / 65536.0 * std::f64::consts::TAU;
                        e.axis = [fmt.axis.quantize(th.cos()) as i32, fmt.axis.quantize(th.sin()) as i32];
                    }
                    e.extent_xy = [ext(rng, &fmt, scale), ext(rng, &fmt, scale)];
                    e.extent_uv = [ext(rng, &fmt, scale), ext(rng, &fmt, scale)];
                }
                _ => {
                    // A quantised Gaussian.
                    let su = scale
                        * (rng.below(4000) as f64 / 100.0 + 0.3).powf(if rng.percent(20) {
                            1.5
                        } else {
                            1.0
                        });
                    let sv = su * (rng.below(1000) as f64 / 1000.0 + 0.001);
                    let th = rng.below(1 << 16) as f64 / 65536.0 * std::f64::consts::TAU;
                    let cov = cov_from_axes(su, sv, th);
                    let m = [0, 1].map(|a| {
                        let off = rng.below(20_000) as f32 / 100.0 - 100.0;
                        origin[a] as f32 + (t / 2) as f32 + scale as f32 * off
                    });
                    let op = (rng.below(1000) as f32 + 1.0) / 1000.0;
                    let p = projected_from_cov(0, m, cov, op, [0.5; 3], 1.0);
                    e = quantize(&p, &fmt, &DepthKeyCodec::Fp16);
                }
            }
            ItuJob { entry: e, tile }
        })
        .collect()
}

/// The directed hard cases, named: Gaussians on tile and subtile borders (exactly touching and
/// one LSB short), needles along and across the axes and diagonals, screen-filling ones,
/// Gaussians centred outside the tile, unbounded extents on each axis, and extreme raw values.
pub fn directed_jobs(cfg: &EngineConfig) -> Vec<(String, ItuJob)> {
    let fmt = cfg.feature_format();
    let f = fmt.mean.frac as u32;
    let ef = fmt.extent.frac as u32;
    let unb = fmt.unbounded_extent();
    let px = |v: f64| (v * (1u64 << f) as f64).round() as i32;
    let epx = |v: f64| (v * (1u64 << ef) as f64).round() as i32;
    let one = 1i32 << fmt.axis.frac;
    // The geometry (64 and 8 px by default): every position below is in tiles and subtiles.
    let (tt, st) = (cfg.raster_config().tile as f64, cfg.raster_config().subtile as f64);
    let mut out = Vec::new();
    let mut add =
        |name: String, mean: [i32; 2], exy: [i32; 2], axis: [i32; 2], euv: [i32; 2], tile: [u32; 2]| {
            let e = FeatureEntry { mean, extent_xy: exy, axis, extent_uv: euv, ..FeatureEntry::default() };
            out.push((name, ItuJob { entry: e, tile }));
        };
    // Border cases (default geometry): the mean at 12 px reaches x = 16 exactly (touching, not
    // separated) or falls one extent LSB short; the same across a tile border (x = 64) and on
    // y. In general: a radius of half a subtile from 1.5 subtiles (from half a subtile with 2 x 2
    // subtiles, where 2 subtiles are the tile), and from a tile border.
    let half = st / 2.0;
    let inner = (1.5 * st).min(tt - 1.5 * st);
    for (t, base) in [(0u32, inner), (1, tt + inner), (0, tt - half)] {
        for (k, r) in [(0, half), (1, half - 1.0 / (1 << ef) as f64), (2, half - 0.5), (3, 0.0)] {
            let r = epx(r);
            let big = epx(1000.0);
            add(
                format!("x border t{t} base {base} r{k}"),
                [px(base), px(base)],
                [r, big],
                [one, 0],
                [big, big],
                [t, t],
            );
            add(
                format!("y border t{t} base {base} r{k}"),
                [px(base), px(base)],
                [big, r],
                [0, one],
                [big, big],
                [t, t],
            );
            add(
                format!("uv border t{t} base {base} r{k}"),
                [px(base), px(base)],
                [big, big],
                [one, 0],
                [r, r],
                [t, t],
            );
        }
    }
    // Means on subtile and tile corners, at and one mean LSB off.
    for (name, x) in [
        ("corner tile", tt),
        ("corner tile-", tt - 1.0 / (1 << f) as f64),
        ("corner subtile", st),
        ("half", st - 0.5),
    ] {
        for t in [[0u32, 0], [1, 1], [0, 1], [1, 0]] {
            let r = epx(0.5);
            add(format!("{name} tile {t:?}"), [px(x), px(x)], [r, r], [one, 0], [r, r], t);
        }
    }
    // Needles (sigma 20 px along, 0.3 across), through the tile centre and through a corner.
    for (k, th) in [0.0, 0.25, 0.5, 1.0, 1.5, 2.0, 2.8].iter().enumerate() {
        for centre in [tt as f32 / 2.0, tt as f32, 0.0] {
            let p = projected_from_cov(
                0,
                [centre, centre + 3.0],
                cov_from_axes(20.0, 0.3, *th),
                0.9,
                [1.0; 3],
                1.0,
            );
            let e = quantize(&p, &fmt, &DepthKeyCodec::Fp16);
            out.push((format!("needle {k} at {centre}"), ItuJob { entry: e, tile: [0, 0] }));
        }
    }
    // Screen-filling: huge sigma, and every extent unbounded.
    let p = projected_from_cov(0, [500.0, -300.0], cov_from_axes(3000.0, 2000.0, 0.4), 0.9, [1.0; 3], 1.0);
    out.push((
        "screen-filling".into(),
        ItuJob { entry: quantize(&p, &fmt, &DepthKeyCodec::Fp16), tile: [2, 3] },
    ));
    let mut add2 =
        |name: &str, mean: [i32; 2], exy: [i32; 2], axis: [i32; 2], euv: [i32; 2], tile: [u32; 2]| {
            let e = FeatureEntry { mean, extent_xy: exy, axis, extent_uv: euv, ..FeatureEntry::default() };
            out.push((name.to_string(), ItuJob { entry: e, tile }));
        };
    add2("all unbounded", [px(-5000.0), px(9000.0)], [unb; 2], [one, 0], [unb; 2], [7, 1]);
    // Centred outside the tile, reaching in (and not).
    add2(
        "outside left reaching",
        [px(-100.0), px(tt / 2.0 - 2.0)],
        [epx(100.0), epx(5.0)],
        [one, 0],
        [epx(100.0), epx(5.0)],
        [0, 0],
    );
    add2(
        "outside left short",
        [px(-100.0), px(tt / 2.0 - 2.0)],
        [epx(99.75), epx(5.0)],
        [one, 0],
        [epx(99.75), epx(5.0)],
        [0, 0],
    );
    add2(
        "outside below",
        [px(30.0), px(200.0)],
        [epx(5.0), epx(137.0)],
        [0, one],
        [epx(137.0), epx(5.0)],
        [0, 1],
    );
    // Unbounded on one axis only.
    for k in 0..4 {
        let mut exy = [epx(2.0); 2];
        let mut euv = [epx(2.0); 2];
        match k {
            0 => exy[0] = unb,
            1 => exy[1] = unb,
            2 => euv[0] = unb,
            _ => euv[1] = unb,
        }
        add2(&format!("unbounded on axis {k}"), [px(-40.0), px(100.0)], exy, [181, 181], euv, [0, 1]);
    }
    // Extreme raw values.
    let (mmin, mmax) = (fmt.mean.min_raw() as i32, fmt.mean.max_raw() as i32);
    let (amin, amax) = (fmt.axis.min_raw() as i32, fmt.axis.max_raw() as i32);
    let tmax = (1u32 << cfg.tile_bits) - 1;
    for (k, mean) in [[mmin, mmin], [mmax, mmax], [mmin, mmax], [0, 0]].into_iter().enumerate() {
        for tile in [[0, 0], [tmax, tmax], [tmax, 0]] {
            add2(&format!("extreme {k} tile {tile:?}"), mean, [unb - 1; 2], [amin, amax], [unb - 1; 2], tile);
            add2(
                &format!("extreme axis {k} tile {tile:?}"),
                mean,
                [unb - 1; 2],
                [amin, amin],
                [unb - 1; 2],
                tile,
            );
        }
    }
    out.extend(unbounded_far_jobs(cfg));
    // Tile indices the configuration's `tile_bits` cannot hold wrap (the RTL takes the low bits).
    for (_, j) in out.iter_mut() {
        j.tile = j.tile.map(|t| t & tmax);
    }
    out
}

/// Pairs of jobs that tell an unbounded extent from the largest finite one, one pair per axis
/// `k` (x, y, U, V): the mean sits farther from tile `(1, 1)` along axis `k` than the largest
/// finite extent reaches, and the other axes reach the tile. `"unbounded far on axis k"` hits
/// the tile; `"bounded far on axis k"` (extent one LSB smaller) misses it. The axes are at 45
/// degrees, so the other axes' largest finite extents cover the offset. A configuration whose
/// largest extent is under 5 tiles, or whose mean cannot hold the offset, gets no pairs.
pub fn unbounded_far_jobs(cfg: &EngineConfig) -> Vec<(String, ItuJob)> {
    let fmt = cfg.feature_format();
    let unb = fmt.unbounded_extent();
    let tt = cfg.raster_config().tile as f64;
    let reach = fmt.extent.dequantize(unb as i64 - 1);
    let offset = reach + 2.0 * tt;
    let centre = 1.5 * tt;
    if reach < 5.0 * tt || centre + offset >= fmt.mean.max_value() - 1.0 {
        return Vec::new();
    }
    let (c, s) = (fmt.axis.quantize(0.5f64.sqrt()) as i32, fmt.axis.quantize(0.5f64.sqrt()) as i32);
    let norm = (((c * c + s * s) as f64).sqrt()).max(1.0);
    let dirs =
        [[-1.0, 0.0], [0.0, 1.0], [c as f64 / norm, s as f64 / norm], [-s as f64 / norm, c as f64 / norm]];
    let small = fmt.extent.quantize_ceil(2.0) as i32;
    let mut out = Vec::new();
    for (k, dir) in dirs.iter().enumerate() {
        let mean = [0, 1].map(|a| fmt.mean.quantize(centre + offset * dir[a]) as i32);
        for (name, far) in [("unbounded", unb), ("bounded", unb - 1)] {
            // The far axis gets `far`; the other axis of its pair a small extent (the offset is
            // along the far axis only); the other pair the largest finite extent.
            let mut ext = [[unb - 1; 2], [unb - 1; 2]];
            let pair = k / 2;
            ext[pair] = [small; 2];
            ext[pair][k % 2] = far;
            let e = FeatureEntry {
                mean,
                extent_xy: ext[0],
                axis: [c, s],
                extent_uv: ext[1],
                ..FeatureEntry::default()
            };
            out.push((format!("{name} far on axis {k}"), ItuJob { entry: e, tile: [1, 1] }));
        }
    }
    out
}

/// The bitmap with every subtile of a tile set (all 64 bits in the default geometry).
pub fn full_bitmap(cfg: &EngineConfig) -> u64 {
    let n = cfg.raster_config().subtiles_per_tile();
    if n >= 64 {
        u64::MAX
    } else {
        (1u64 << n) - 1
    }
}

/// Measured ITU timing: latency (input transfer to output valid) and initiation interval.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ItuTiming {
    /// Cycles from the input transfer edge to the first cycle the result is on the output.
    pub latency: u64,
    /// Cycles per Gaussian in a back-to-back stream with the output always ready.
    pub ii: f64,
}

/// Measures [`ItuTiming`] with `jobs` random jobs, no stalls, output always ready.
pub fn measure_timing<M: Clocked>(dut: &mut M, cfg: &EngineConfig, seed: u64, jobs: usize) -> ItuTiming {
    let mut rng = Rng::new(seed);
    let one = random_jobs(cfg, &mut rng, 1);
    let r = run_checked(dut, cfg, seed, &one, 0, 100);
    let latency = r.first_out.expect("one output") - r.first_in.expect("one input");
    let many = random_jobs(cfg, &mut rng, jobs);
    let r = run_checked(dut, cfg, seed, &many, 0, 100);
    let span = r.last_out.expect("outputs") - r.first_out.expect("outputs");
    ItuTiming { latency, ii: span as f64 / (jobs as f64 - 1.0) }
}
