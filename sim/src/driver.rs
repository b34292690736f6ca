//! Workload generation from the golden pipeline (`neo_golden::pipeline`).
//!
//! Two ways, same counters:
//! - **work-only** (default): the golden stages that decide the work, called directly: float
//!   preprocess, quantisation, binning with the ITU ([`Binning`]), the strategy's per-tile sort
//!   ([`sort_tile`], which returns the per-tile work counters) and the write-back of depth keys
//!   and valid bits. The raster itself is skipped: its valid bit is the ITU's cumulative OR,
//!   which is exactly membership in the tile's current list (the binning uses the same ITU; the
//!   golden pipeline's `itu_mismatch` counter asserts it), and its routed pairs are the subtile
//!   bitmaps ([`subtile_bitmap`]). Only the SCUs' early termination needs blending: it is
//!   measured on a sample of tiles ([`WorkloadSpec::raster_sample`]) with the golden raster.
//! - **with the golden raster** ([`GoldenRaster::Exact`] / [`GoldenRaster::Full`]): the golden
//!   [`Pipeline`] renders every frame in lockstep (PSNR against the exact order and the float
//!   reference, exact termination ratios, `poc.trace` export); the work-only state runs beside it
//!   and every frame's work counters are checked against the golden statistics, which must
//!   agree exactly.

use rayon::prelude::*;
use std::path::PathBuf;

use neo_golden::camera::Camera;
use neo_golden::formats::{quantize, FeatureEntry};
use neo_golden::pipeline::binning::Binning;
use neo_golden::pipeline::hierarchical::hierarchical_sort;
use neo_golden::pipeline::tile::{sort_tile, FramePos, TileCtx, TileState};
use neo_golden::pipeline::{Formats, Pipeline, PipelineConfig, PipelineError, StageWork, Strategy};
use neo_golden::raster::{raster_tile_into, subtile_bitmap, RasterConfig, TileRaster};
use neo_golden::render::preprocess;
use neo_golden::scene::Scene;
use neo_golden::sort::{SortEntry, Sorter};

use crate::config::PipelineParams;
use crate::prefetch::prefetch;
use crate::workload::{FrameWork, GoldenSums, HierTile, Quality, TileWork, Workload, WorkloadInfo};

const CULLED: u32 = u32::MAX;

/// How many table entries ahead the feature gathers are prefetched.
const PREFETCH_AHEAD: usize = 16;

/// Whether the golden raster runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GoldenRaster {
    /// Work-only generation (termination ratio from sampled tiles).
    Off,
    /// The golden pipeline with the exact-order reference (PSNR vs exact).
    Exact,
    /// The golden pipeline with the exact-order and float references.
    Full,
}

/// What to generate.
#[derive(Clone, Debug)]
pub struct WorkloadSpec {
    /// Scene name for the record.
    pub scene: String,
    /// Trajectory spec for the record.
    pub trajectory: String,
    /// Sorting strategy.
    pub strategy: Strategy,
    /// Tile, subtile, chunk, passes, capacity.
    pub params: PipelineParams,
    /// Golden raster mode.
    pub golden_raster: GoldenRaster,
    /// Work-only mode: raster every `raster_sample`-th tile with the golden raster to measure
    /// early termination (0: none, ratio 1).
    pub raster_sample: u32,
    /// Also record each tile's hierarchical sort from scratch (for the GSCore baseline).
    pub hierarchical: bool,
    /// With the golden raster: write `frame_NNNNN.poc.trace` for these frames into the folder.
    pub trace: Option<(PathBuf, Vec<usize>)>,
}

impl WorkloadSpec {
    /// Work-only generation of `strategy` with default parameters.
    pub fn new(scene: &str, trajectory: &str, strategy: Strategy) -> Self {
        WorkloadSpec {
            scene: scene.into(),
            trajectory: trajectory.into(),
            strategy,
            params: PipelineParams::default(),
            golden_raster: GoldenRaster::Off,
            raster_sample: 16,
            hierarchical: true,
            trace: None,
        }
    }
}

/// Why a workload could not be generated.
#[derive(Debug, thiserror::Error)]
pub enum DriverError {
    /// A pipeline parameter.
    #[error("{0}")]
    Pipeline(#[from] PipelineError),
    /// The work-only counters disagree with the golden pipeline's (a bug).
    #[error("frame {frame}: work-only counters disagree with the golden pipeline: {what}")]
    Mismatch {
        /// Frame.
        frame: usize,
        /// What differs.
        what: String,
    },
    /// Writing a trace.
    #[error("{path}: {err}")]
    Io {
        /// File.
        path: PathBuf,
        /// Error.
        err: std::io::Error,
    },
    /// Anything else.
    #[error("{0}")]
    Other(String),
}

/// The golden pipeline configuration of `params` and `strategy`.
pub fn pipeline_config(strategy: Strategy, p: &PipelineParams, raster: GoldenRaster) -> PipelineConfig {
    let mut cfg = PipelineConfig {
        strategy,
        chunk: p.chunk,
        dps_passes: p.dps_passes,
        capacity: p.capacity,
        compare_exact: raster != GoldenRaster::Off,
        compare_float: raster == GoldenRaster::Full,
        ssim: false,
        ..PipelineConfig::default()
    };
    cfg.raster.tile = p.tile;
    cfg.raster.subtile = p.subtile;
    cfg
}

/// Per-thread buffers.
#[derive(Clone)]
struct Ctx {
    tile: TileCtx,
    sorter: Sorter,
    bins: Vec<Vec<SortEntry>>,
    hier_out: Vec<SortEntry>,
    feats: Vec<FeatureEntry>,
    raster: TileRaster,
}

/// The work-only state of a strategy along a trajectory.
pub struct WorkDriver<'s> {
    scene: &'s Scene,
    strategy: Strategy,
    formats: Formats,
    rcfg: RasterConfig,
    width: u32,
    height: u32,
    grid: [u32; 2],
    states: Vec<TileState>,
    proto: Ctx,
    features: Vec<FeatureEntry>,
    feature_ids: Vec<u32>,
    feature_of: Vec<u32>,
    binning: Binning,
    shot_start: usize,
    started: bool,
    hierarchical: bool,
    raster_sample: u32,
}

/// What one tile produced.
struct TileOut {
    work: TileWork,
    stage: StageWork,
    processed: u64,
    sampled_routed: u64,
}

impl<'s> WorkDriver<'s> {
    /// A driver for `scene` at `width x height`.
    pub fn new(
        scene: &'s Scene,
        strategy: Strategy,
        params: &PipelineParams,
        width: u32,
        height: u32,
        hierarchical: bool,
        raster_sample: u32,
    ) -> Result<Self, DriverError> {
        let cfg = pipeline_config(strategy, params, GoldenRaster::Off);
        let formats = Formats::artifact(cfg.chunk)?;
        formats.check(&cfg.raster, scene.len())?;
        if width == 0 || height == 0 {
            return Err(DriverError::Other(format!("image size {width}x{height} is empty")));
        }
        let grid = [width.div_ceil(cfg.raster.tile), height.div_ceil(cfg.raster.tile)];
        let tiles = grid[0] as usize * grid[1] as usize;
        let proto = Ctx {
            tile: TileCtx::new(strategy, &formats.sort, cfg.dps_passes, cfg.capacity_or_max()),
            sorter: Sorter::new(formats.sort.clone()),
            bins: Vec::new(),
            hier_out: Vec::new(),
            feats: Vec::new(),
            raster: TileRaster::default(),
        };
        Ok(WorkDriver {
            scene,
            strategy,
            formats,
            rcfg: cfg.raster,
            width,
            height,
            grid,
            states: vec![TileState::default(); tiles],
            proto,
            features: Vec::new(),
            feature_ids: Vec::new(),
            feature_of: vec![CULLED; scene.len()],
            binning: Binning::default(),
            shot_start: 0,
            started: false,
            hierarchical,
            raster_sample,
        })
    }

    /// The number formats.
    pub fn formats(&self) -> &Formats {
        &self.formats
    }

    /// Tile grid.
    pub fn grid(&self) -> [u32; 2] {
        self.grid
    }

    /// The tables after the last frame's write-back.
    pub fn tables(&self) -> impl Iterator<Item = &[SortEntry]> {
        self.states.iter().map(|s| s.table.as_slice())
    }

    /// The current list of every tile in the last frame (ascending ids, current keys).
    pub fn current_lists(&self) -> impl Iterator<Item = &[SortEntry]> {
        (0..self.binning.tiles()).map(|t| self.binning.tile(t))
    }

    /// Runs frame `frame` from `cam`.
    pub fn step(&mut self, cam: &Camera, frame: usize, cut: bool) -> FrameWork {
        assert_eq!(
            (cam.width, cam.height),
            (self.width, self.height),
            "camera size differs from the driver's"
        );
        if cut || !self.started {
            self.shot_start = frame;
        }
        self.started = true;
        let pos = FramePos { frame, shot_start: self.shot_start };
        let projected = preprocess(self.scene, cam, self.rcfg.tile);
        let (gpu_pairs, gpu_visible) = gpu_duplication(&projected, self.width, self.height, 16);
        let (fmt, key) = (&self.formats.feature, &self.formats.key);
        projected.par_iter().map(|p| quantize(p, fmt, key)).collect_into_vec(&mut self.features);
        self.feature_ids.clear();
        self.feature_ids.extend(projected.iter().map(|p| p.index));
        self.feature_of.par_iter_mut().for_each(|v| *v = CULLED);
        for (i, &id) in self.feature_ids.iter().enumerate() {
            self.feature_of[id as usize] = i as u32;
        }
        drop(projected);
        self.binning.run(&self.features, &self.feature_ids, fmt, &self.rcfg, self.width, self.height);

        let strategy = self.strategy;
        let write_keys = strategy.writes_back_keys();
        let reuses = strategy.reuses_tables();
        let (features, feature_of, binning, rcfg) =
            (&self.features, &self.feature_of, &self.binning, &self.rcfg);
        let (w, h, gx) = (self.width, self.height, self.grid[0]);
        let (want_hier, sample) = (self.hierarchical, self.raster_sample);
        let n = rcfg.subtiles_per_side();
        let s = rcfg.subtile;
        let proto = &self.proto;
        let outs: Vec<TileOut> = self
            .states
            .par_iter_mut()
            .enumerate()
            .map_init(
                || proto.clone(),
                |ctx, (ti, state)| {
                    let current = binning.tile(ti);
                    let out = sort_tile(strategy, pos, state, current, &mut ctx.tile);
                    let hier = if want_hier {
                        let hw =
                            hierarchical_sort(current, &mut ctx.hier_out, &mut ctx.sorter, &mut ctx.bins);
                        HierTile {
                            entries: hw.entries as u32,
                            approx_entries: hw.approx_entries as u32,
                            approx_passes: hw.approx_passes as u32,
                            bin_sorts: hw.chunk.chunks as u32,
                            bin_entries: hw.chunk.entries as u32,
                            fallback_global: hw.fallback_global_entries as u32,
                        }
                    } else {
                        HierTile::default()
                    };
                    let (tx, ty) = (ti as u32 % gx, ti as u32 / gx);
                    // Subtiles with a pixel inside the image.
                    let mut inside = 0u64;
                    for sy in 0..n {
                        for sx in 0..n {
                            if tx * rcfg.tile + sx * s < w && ty * rcfg.tile + sy * s < h {
                                inside |= 1 << (sy * n + sx);
                            }
                        }
                    }
                    let sampled = sample > 0 && (ti as u32).is_multiple_of(sample);
                    let mut routed = vec![0u32; (n * n) as usize];
                    let mut raster_entries = 0u32;
                    ctx.feats.clear();
                    // Table order is depth order: the feature look-ups are random gathers,
                    // prefetched ahead (the id map two steps before the entry it names).
                    let table = &mut state.table;
                    for i in 0..table.len() {
                        if let Some(a) = table.get(i + 2 * PREFETCH_AHEAD) {
                            prefetch(&feature_of[a.id as usize]);
                        }
                        if let Some(a) = table.get(i + PREFETCH_AHEAD) {
                            if let Some(f) = features.get(feature_of[a.id as usize] as usize) {
                                prefetch(f);
                            }
                        }
                        let e = &mut table[i];
                        let f = feature_of[e.id as usize];
                        if f == CULLED {
                            e.valid = false;
                            continue;
                        }
                        let fe = &features[f as usize];
                        raster_entries += 1;
                        if sampled {
                            ctx.feats.push(*fe);
                        }
                        let in_current = current.binary_search_by_key(&e.id, |c| c.id).is_ok();
                        e.valid = in_current;
                        if write_keys {
                            e.key = fe.depth_key;
                        }
                        if in_current {
                            let mut b = subtile_bitmap(fe, fmt, tx, ty, rcfg) & inside;
                            while b != 0 {
                                routed[b.trailing_zeros() as usize] += 1;
                                b &= b - 1;
                            }
                        }
                    }
                    let (mut processed, mut sampled_routed) = (0u64, 0u64);
                    if sampled {
                        raster_tile_into(&ctx.feats, fmt, tx, ty, w, h, rcfg, &mut ctx.raster);
                        for (j, sw) in ctx.raster.work.iter().enumerate() {
                            if inside >> j & 1 == 1 {
                                processed += sw.processed as u64;
                                sampled_routed += sw.routed as u64;
                            }
                        }
                    }
                    let sw = &out.work;
                    let table_len = state.table.len() as u32;
                    let work = TileWork {
                        from_scratch: out.from_scratch,
                        current: out.counts.current,
                        incoming: out.counts.incoming,
                        sort_n: sw.entries_sorted as u32 * (strategy != Strategy::Hierarchical) as u32,
                        dps_len: sw.dps_entries.checked_div(sw.dps_passes).unwrap_or(0) as u32,
                        dps_passes: sw.dps_passes as u32,
                        merge_a: sw.merge_in_table as u32,
                        merge_b: sw.merge_in_incoming as u32,
                        merge_out: sw.merge_out as u32,
                        dropped_capacity: sw.dropped_capacity as u32,
                        table_len,
                        raster_entries,
                        writeback: if reuses { table_len } else { 0 },
                        background_n: sw.background_entries_sorted as u32,
                        hier,
                        routed,
                    };
                    TileOut { work, stage: out.work, processed, sampled_routed }
                },
            )
            .collect();

        let mut sum = StageWork::default();
        let (mut processed, mut sampled_routed) = (0u64, 0u64);
        let mut tiles = Vec::with_capacity(outs.len());
        for o in outs {
            sum.add(&o.stage);
            processed += o.processed;
            sampled_routed += o.sampled_routed;
            tiles.push(o.work);
        }
        let raster_read: u64 = tiles.iter().map(|t| t.raster_entries as u64).sum();
        let writeback: u64 = tiles.iter().map(|t| t.writeback as u64).sum();
        let golden = GoldenSums {
            sort_read: sum.dram_read,
            sort_written: sum.dram_written,
            binned_written: sum.binned_written,
            raster_read,
            writeback,
            background_read: sum.background_dram_read,
            background_written: sum.background_dram_written,
        };
        FrameWork {
            frame,
            cut: cut && frame == self.shot_start,
            from_scratch: tiles.iter().all(|t| t.from_scratch),
            gaussians: self.scene.len() as u64,
            visible: self.features.len() as u64,
            binning_tests: self.binning.tiles_tested,
            processed_ratio: if sampled_routed > 0 { processed as f64 / sampled_routed as f64 } else { 1.0 },
            raster_sampled: true,
            gpu_pairs,
            gpu_visible,
            golden,
            quality: None,
            tiles,
        }
    }
}

/// The CUDA rasterizer's duplication over `tile`-pixel tiles: per Gaussian, the rectangle
/// `getRect(mean, radius)` clamped to the grid; returns (pairs, Gaussians with a non-empty
/// rectangle and a positive radius).
pub fn gpu_duplication(
    projected: &[neo_golden::render::Projected],
    width: u32,
    height: u32,
    tile: u32,
) -> (u64, u64) {
    let (gx, gy) = (width.div_ceil(tile) as i64, height.div_ceil(tile) as i64);
    let t = tile as f32;
    projected
        .par_iter()
        .map(|p| {
            if p.radius == 0 {
                return (0u64, 0u64);
            }
            let r = p.radius as f32;
            let lo = |m: f32, g: i64| (((m - r) / t) as i64).clamp(0, g);
            let hi = |m: f32, g: i64| (((m + r + t - 1.0) / t) as i64).clamp(0, g);
            let nx = hi(p.mean2d[0], gx) - lo(p.mean2d[0], gx);
            let ny = hi(p.mean2d[1], gy) - lo(p.mean2d[1], gy);
            let pairs = (nx.max(0) * ny.max(0)) as u64;
            (pairs, (pairs > 0) as u64)
        })
        .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1))
}

fn check_frame(
    fw: &FrameWork,
    stats: &neo_golden::pipeline::FrameStats,
    table_lens: &[u32],
) -> Result<(), String> {
    let w = &stats.work;
    let g = &fw.golden;
    let pairs = [
        ("sort dram_read", g.sort_read, w.dram_read),
        ("sort dram_written", g.sort_written, w.dram_written),
        ("binned_written", g.binned_written, w.binned_written),
        ("raster_read", g.raster_read, w.raster_read),
        ("writeback", g.writeback, w.writeback),
        ("background_dram_read", g.background_read, w.background_dram_read),
        ("background_dram_written", g.background_written, w.background_dram_written),
        ("visible", fw.visible, stats.gaussians.visible),
        ("binning tests", fw.binning_tests, stats.tiles.binning_tests),
    ];
    for (what, ours, theirs) in pairs {
        if ours != theirs {
            return Err(format!("{what}: {ours} here, {theirs} in the golden pipeline"));
        }
    }
    if table_lens.len() != fw.tiles.len() {
        return Err("tile counts differ".into());
    }
    for (i, (t, &l)) in fw.tiles.iter().zip(table_lens).enumerate() {
        if t.table_len != l {
            return Err(format!("tile {i}: table length {} here, {l} in the golden pipeline", t.table_len));
        }
    }
    let routed: u64 = fw.tiles.iter().flat_map(|t| t.routed.iter()).map(|&r| r as u64).sum();
    if routed > stats.raster.subtile_blends {
        return Err(format!(
            "routed pairs {routed} exceed the golden raster's {}",
            stats.raster.subtile_blends
        ));
    }
    Ok(())
}

/// Generates the workload of `spec` over `cams` (all of one size) with scene cuts `cuts`;
/// `on_frame(i)` is called after each frame.
pub fn generate(
    scene: &Scene,
    cams: &[Camera],
    cuts: &[usize],
    spec: &WorkloadSpec,
    mut on_frame: impl FnMut(usize),
) -> Result<Workload, DriverError> {
    let t0 = std::time::Instant::now();
    let Some(first) = cams.first() else {
        return Err(DriverError::Other("no frames".into()));
    };
    let (w, h) = (first.width, first.height);
    let mut drv =
        WorkDriver::new(scene, spec.strategy, &spec.params, w, h, spec.hierarchical, spec.raster_sample)?;
    let mut golden = if spec.golden_raster != GoldenRaster::Off {
        let cfg = pipeline_config(spec.strategy, &spec.params, spec.golden_raster);
        let formats = Formats::artifact(cfg.chunk)?;
        Some(Pipeline::new(scene, cfg, formats, w, h)?)
    } else {
        None
    };
    if let Some((dir, _)) = &spec.trace {
        std::fs::create_dir_all(dir).map_err(|err| DriverError::Io { path: dir.clone(), err })?;
    }
    let f = drv.formats();
    let info = WorkloadInfo {
        scene: spec.scene.clone(),
        trajectory: spec.trajectory.clone(),
        strategy: spec.strategy.to_string(),
        width: w,
        height: h,
        grid: drv.grid(),
        tile: spec.params.tile,
        subtile: spec.params.subtile,
        chunk: spec.params.chunk,
        dps_passes: spec.params.dps_passes,
        capacity: spec.params.capacity,
        sort_entry_bytes: f.sort.format().bytes_per_entry() as u32,
        feature_entry_bytes: f.feature.bytes_per_entry(),
        gaussians: scene.len() as u64,
        golden_raster: golden.is_some(),
    };
    let mut frames = Vec::with_capacity(cams.len());
    for (i, cam) in cams.iter().enumerate() {
        if (cam.width, cam.height) != (w, h) {
            return Err(DriverError::Other(format!(
                "camera {i} is {}x{}, not {w}x{h}",
                cam.width, cam.height
            )));
        }
        let cut = cuts.contains(&i);
        let mut fw = drv.step(cam, i, cut);
        if let Some(p) = golden.as_mut() {
            let out = p.render_frame(cam, i, cut);
            check_frame(&fw, &out.stats, &out.tiles.table_len)
                .map_err(|what| DriverError::Mismatch { frame: i, what })?;
            let routed: u64 = fw.tiles.iter().flat_map(|t| t.routed.iter()).map(|&r| r as u64).sum();
            fw.processed_ratio =
                if routed > 0 { out.stats.raster.subtile_processed as f64 / routed as f64 } else { 1.0 };
            fw.raster_sampled = false;
            let s = &out.stats;
            fw.quality = Some(Quality {
                psnr_vs_exact: s.psnr_vs_exact,
                psnr_vs_float: s.psnr_vs_float,
                exact_psnr_vs_float: s.exact_psnr_vs_float,
                identical_to_exact: s.identical_to_exact,
            });
            if let Some((dir, which)) = &spec.trace {
                if which.is_empty() || which.contains(&i) {
                    let path = dir.join(format!("frame_{i:05}.poc.trace"));
                    let mut file = std::fs::File::create(&path)
                        .map_err(|err| DriverError::Io { path: path.clone(), err })?;
                    p.write_trace(&mut file).map_err(|err| DriverError::Io { path: path.clone(), err })?;
                }
            }
        }
        frames.push(fw);
        on_frame(i);
    }
    Ok(Workload { info, frames, generation_s: t0.elapsed().as_secs_f64() })
}
