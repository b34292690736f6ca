//! Workload generation from the golden pipeline (`neo_golden::pipeline`).
//!
//! Two ways, same counters:
//! - **work-only** (default): the golden pipeline's work-only mode
//!   ([`Pipeline::work_frame`]) runs the frame stages that decide the work (preprocess,
//!   quantisation, binning, the strategy's sort, the write-back) and returns the per-tile work
//!   counters; this module only turns them into the model's [`Workload`] records. The raster is
//!   skipped; the SCUs' early termination is measured on a sample of tiles
//!   ([`WorkloadSpec::raster_sample`]) with the golden raster.
//! - **with the golden raster** ([`GoldenRaster::Exact`] / [`GoldenRaster::Full`]): the golden
//!   [`Pipeline`] renders every frame in lockstep (PSNR against the exact order and the float
//!   reference, exact termination ratios, `poc.trace` export); the work-only state runs beside it
//!   and every frame's work counters are checked against the golden statistics, which must
//!   agree exactly.

use std::path::PathBuf;
use std::sync::Arc;

use rayon::prelude::*;

use neo_golden::camera::Camera;
use neo_golden::hwpre::bake;
use neo_golden::pipeline::frame::{FrameInputs, FramePrep};
use neo_golden::pipeline::hierarchical::HierWork;
use neo_golden::pipeline::Preprocessing;
use neo_golden::pipeline::{
    self as golden, Formats, Pipeline, PipelineConfig, PipelineError, StageWork, Strategy, WorkOptions,
};
use neo_golden::scene::Scene;
use neo_golden::sort::SortEntry;

use crate::config::PipelineParams;
use crate::workload::{FrameWork, GoldenSums, HierTile, Quality, TileWork, Workload, WorkloadInfo};

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
    #[error(transparent)]
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
        raster_window: p.raster_window,
        compare_exact: raster != GoldenRaster::Off,
        compare_float: raster == GoldenRaster::Full,
        ssim: false,
        // The report does not show it.
        window_needed: false,
        ..PipelineConfig::default()
    };
    cfg.raster.tile = p.tile;
    cfg.raster.subtile = p.subtile;
    cfg
}

/// The number formats of every workload of sort chunk `chunk`: the artifact's.
pub fn workload_formats(chunk: usize) -> Result<Formats, DriverError> {
    Ok(Formats::artifact(chunk)?)
}

/// The bytes of a sort entry in the workloads of sort chunk `chunk` (the workload's
/// `sort_entry_bytes`), known before any workload is generated.
pub fn sort_entry_bytes(chunk: usize) -> Result<u32, DriverError> {
    Ok(workload_formats(chunk)?.sort.format().bytes_per_entry() as u32)
}

/// The work-only pipeline's configuration (no golden raster) and its number formats, for both
/// of [`WorkDriver`]'s constructors.
fn work_config(
    strategy: Strategy,
    params: &PipelineParams,
) -> Result<(PipelineConfig, Formats), DriverError> {
    let cfg = pipeline_config(strategy, params, GoldenRaster::Off);
    let formats = workload_formats(cfg.chunk)?;
    Ok((cfg, formats))
}

/// The work-only state of a strategy along a trajectory: golden's pipeline in its work-only
/// mode.
pub struct WorkDriver<'s> {
    pipeline: Pipeline<'s>,
    options: WorkOptions,
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
        let (cfg, formats) = work_config(strategy, params)?;
        let pipeline = Pipeline::new(scene, cfg, formats, width, height)?;
        Ok(WorkDriver { pipeline, options: WorkOptions { hierarchical, raster_sample } })
    }

    /// A driver that makes no frame inputs of its own: every frame is given them
    /// ([`WorkDriver::step_with`]).
    pub fn for_shared_inputs(
        scene: &'s Scene,
        strategy: Strategy,
        params: &PipelineParams,
        width: u32,
        height: u32,
        hierarchical: bool,
        raster_sample: u32,
    ) -> Result<Self, DriverError> {
        let (cfg, formats) = work_config(strategy, params)?;
        let pipeline = Pipeline::for_shared_inputs(scene, cfg, formats, width, height)?;
        Ok(WorkDriver { pipeline, options: WorkOptions { hierarchical, raster_sample } })
    }

    /// The number formats.
    pub fn formats(&self) -> &Formats {
        self.pipeline.formats()
    }

    /// Tile grid.
    pub fn grid(&self) -> [u32; 2] {
        self.pipeline.grid()
    }

    /// The tables after the last frame's write-back.
    pub fn tables(&self) -> impl Iterator<Item = &[SortEntry]> {
        self.pipeline.tables()
    }

    /// The current list of every tile in the last frame (ascending ids, current keys).
    pub fn current_lists(&self) -> impl Iterator<Item = &[SortEntry]> {
        self.pipeline.current_lists()
    }

    /// Runs frame `frame` from `cam`.
    pub fn step(&mut self, cam: &Camera, frame: usize, cut: bool) -> FrameWork {
        let gw = self.pipeline.work_frame(cam, frame, cut, &self.options);
        self.record(gw, frame, cut)
    }

    /// Lets go of the last frame's inputs ([`Pipeline::release_inputs`]).
    pub fn release_inputs(&mut self) {
        self.pipeline.release_inputs();
    }

    /// Runs frame `frame` from `cam` on its (shared) `inputs` ([`Pipeline::work_frame_with`]).
    pub fn step_with(
        &mut self,
        cam: &Camera,
        frame: usize,
        cut: bool,
        inputs: Arc<FrameInputs>,
    ) -> FrameWork {
        let gw = self.pipeline.work_frame_with(cam, frame, cut, &self.options, inputs);
        self.record(gw, frame, cut)
    }

    /// The model's record of golden's frame work.
    fn record(&self, gw: golden::FrameWork, frame: usize, cut: bool) -> FrameWork {
        let visible_set = id_set(gw.gaussians, self.pipeline.visible_ids());
        let strategy = self.pipeline.config().strategy;
        let chunk = self.pipeline.config().chunk as u32;
        let mut sum = StageWork::default();
        let (mut processed, mut sampled_routed) = (0u64, 0u64);
        let mut tiles = Vec::with_capacity(gw.tiles.len());
        for t in gw.tiles {
            sum.add(&t.sort.work);
            if let Some(r) = t.sampled {
                processed += r.processed;
                sampled_routed += r.routed;
            }
            tiles.push(tile_work(strategy, chunk, t));
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
            cut: cut && frame == gw.pos.shot_start,
            from_scratch: tiles.iter().all(|t| t.from_scratch),
            gaussians: gw.gaussians,
            visible: gw.visible,
            visible_set,
            binning_tests: gw.binning_tests,
            processed_ratio: if sampled_routed > 0 { processed as f64 / sampled_routed as f64 } else { 1.0 },
            raster_sampled: true,
            gpu_pairs: gw.gpu_pairs,
            gpu_visible: gw.gpu_visible,
            golden,
            quality: None,
            tiles,
            golden_tiles: None,
        }
    }
}

/// The set of `ids` among `n` Gaussians as [`FrameWork::visible_set`] holds it.
fn id_set(n: u64, ids: &[u32]) -> Vec<u64> {
    let mut set = vec![0u64; n.div_ceil(64) as usize];
    for &i in ids {
        set[i as usize / 64] |= 1 << (i % 64);
    }
    set
}

/// The model's record of one tile from golden's work counters.
fn tile_work(strategy: Strategy, chunk: u32, t: golden::TileWork) -> TileWork {
    let sw = &t.sort.work;
    TileWork {
        from_scratch: t.sort.from_scratch,
        current: t.sort.counts.current,
        incoming: t.sort.counts.incoming,
        sort_n: sw.entries_sorted as u32 * (strategy != Strategy::Hierarchical) as u32,
        dps_len: sw.dps_entries.checked_div(sw.dps_passes).unwrap_or(0) as u32,
        dps_passes: sw.dps_passes as u32,
        dps_chunk: match strategy {
            Strategy::Adaptive(p) if t.sort.counts.dps_wide => chunk * p.wide,
            _ => 0,
        },
        merge_a: sw.merge_in_table as u32,
        merge_b: sw.merge_in_incoming as u32,
        merge_out: sw.merge_out as u32,
        dropped_capacity: sw.dropped_capacity as u32,
        table_len: t.table_len,
        raster_entries: t.raster_entries,
        writeback: if strategy.reuses_tables() { t.table_len } else { 0 },
        background_n: sw.background_entries_sorted as u32,
        hier: t.hierarchical.as_ref().map(hier_tile).unwrap_or_default(),
        routed: t.routed,
    }
}

/// The model's record of a hierarchical sort.
fn hier_tile(hw: &HierWork) -> HierTile {
    HierTile {
        entries: hw.entries as u32,
        approx_entries: hw.approx_entries as u32,
        approx_passes: hw.approx_passes as u32,
        bin_sorts: hw.chunk.chunks as u32,
        bin_entries: hw.chunk.entries as u32,
        fallback_global: hw.fallback_global_entries as u32,
    }
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
    for (i, t) in fw.tiles.iter().enumerate() {
        tile_shape_holds(t).map_err(|e| format!("tile {i}: {e}"))?;
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

/// A reuse tile's counters are one tile of golden's command sequence (`tile_steps`, which the
/// model's sort jobs run): its conventional sort is the merge's stream B and each DPS pass
/// covers the merge's stream A (the previous table).
fn tile_shape_holds(t: &TileWork) -> Result<(), String> {
    if t.from_scratch {
        return Ok(());
    }
    if t.sort_n != t.merge_b {
        return Err(format!(
            "the incoming sort has {} entries, the merge's stream B {}",
            t.sort_n, t.merge_b
        ));
    }
    if t.dps_passes > 0 && t.dps_len != t.merge_a {
        return Err(format!("DPS covers {} entries, the merge's stream A {}", t.dps_len, t.merge_a));
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
    on_frame: impl FnMut(usize),
) -> Result<Workload, DriverError> {
    let mut v = generate_many(scene, cams, cuts, std::slice::from_ref(spec), on_frame)?;
    Ok(v.remove(0))
}

/// One workload in the making: the work-only state, the golden pipeline beside it when the
/// golden raster runs, and the frames so far.
struct InMaking<'s> {
    spec: &'s WorkloadSpec,
    drv: WorkDriver<'s>,
    golden: Option<Pipeline<'s>>,
    info: WorkloadInfo,
    frames: Vec<FrameWork>,
}

impl<'s> InMaking<'s> {
    fn new(scene: &'s Scene, spec: &'s WorkloadSpec, w: u32, h: u32) -> Result<Self, DriverError> {
        let drv = WorkDriver::for_shared_inputs(
            scene,
            spec.strategy,
            &spec.params,
            w,
            h,
            spec.hierarchical,
            spec.raster_sample,
        )?;
        let golden = if spec.golden_raster != GoldenRaster::Off {
            let cfg = pipeline_config(spec.strategy, &spec.params, spec.golden_raster);
            let formats = workload_formats(cfg.chunk)?;
            Some(Pipeline::for_shared_inputs(scene, cfg, formats, w, h)?)
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
            raster_window: spec.params.raster_window,
            sort_entry_bytes: f.sort.format().bytes_per_entry() as u32,
            feature_entry_bytes: f.feature.bytes_per_entry(),
            sh_degree: scene.sh_degree,
            gaussian_geometry_bytes: bake::geometry_bytes(),
            gaussian_sh_bytes: bake::sh_bytes(scene.sh_degree, Preprocessing::DEFAULT_SH),
            gaussians: scene.len() as u64,
            golden_raster: golden.is_some(),
        };
        Ok(InMaking { spec, drv, golden, info, frames: Vec::with_capacity(0) })
    }

    /// Frame `i` from `cam` on the shared `inputs`.
    fn step(
        &mut self,
        cam: &Camera,
        i: usize,
        cut: bool,
        inputs: &Arc<FrameInputs>,
    ) -> Result<(), DriverError> {
        let mut fw = self.drv.step_with(cam, i, cut, inputs.clone());
        if let Some(p) = self.golden.as_mut() {
            let out = p.render_frame_with(cam, i, cut, inputs.clone());
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
            fw.golden_tiles = Some(out.tiles);
            if let Some((dir, which)) = &self.spec.trace {
                if which.is_empty() || which.contains(&i) {
                    let path = dir.join(neo_golden::pipeline::trace::file_name(i));
                    let mut file = std::fs::File::create(&path)
                        .map_err(|err| DriverError::Io { path: path.clone(), err })?;
                    p.write_trace(&mut file).map_err(|err| DriverError::Io { path: path.clone(), err })?;
                }
            }
        }
        self.frames.push(fw);
        Ok(())
    }

    /// Lets go of the shared inputs of the last frame.
    fn release_inputs(&mut self) {
        self.drv.release_inputs();
        if let Some(p) = self.golden.as_mut() {
            p.release_inputs();
        }
    }
}

/// Generates the workloads of `specs` over the same cameras `cams` (all of one size) with scene
/// cuts `cuts`, in one pass over the frames: each frame's strategy-independent stages
/// (preprocessing and binning, golden's [`FrameInputs`]) run once and every spec's work-only
/// state and golden pipeline take them, the specs in parallel; so do the exact-order rasters of
/// the golden pipelines of one capacity. Each workload is the one [`generate`] makes of its spec
/// alone. The specs must share the tile and subtile sizes. `on_frame(i)` is called after each
/// frame; each workload's `generation_s` is the wall time of the whole pass.
pub fn generate_many(
    scene: &Scene,
    cams: &[Camera],
    cuts: &[usize],
    specs: &[WorkloadSpec],
    mut on_frame: impl FnMut(usize),
) -> Result<Vec<Workload>, DriverError> {
    let t0 = std::time::Instant::now();
    let Some(first) = cams.first() else {
        return Err(DriverError::Other("no frames".into()));
    };
    let Some(spec0) = specs.first() else {
        return Ok(Vec::new());
    };
    let (w, h) = (first.width, first.height);
    let geometry = |s: &WorkloadSpec| (s.params.tile, s.params.subtile);
    if let Some(s) = specs.iter().find(|s| geometry(s) != geometry(spec0)) {
        return Err(DriverError::Other(format!(
            "workloads generated together need one tile geometry: tile {} subtile {} and tile {} subtile {}",
            spec0.params.tile, spec0.params.subtile, s.params.tile, s.params.subtile
        )));
    }
    let mut making =
        specs.iter().map(|s| InMaking::new(scene, s, w, h)).collect::<Result<Vec<_>, DriverError>>()?;
    for m in &mut making {
        m.frames.reserve(cams.len());
    }
    let cfg0 = pipeline_config(spec0.strategy, &spec0.params, GoldenRaster::Off);
    let prep = FramePrep::new(scene, &workload_formats(cfg0.chunk)?, cfg0.raster, cfg0.preprocess, w, h);
    let mut inputs = Arc::new(FrameInputs::default());
    for (i, cam) in cams.iter().enumerate() {
        if (cam.width, cam.height) != (w, h) {
            return Err(DriverError::Other(format!(
                "camera {i} is {}x{}, not {w}x{h}",
                cam.width, cam.height
            )));
        }
        let cut = cuts.contains(&i);
        // The last frame's inputs, released by every pipeline, are made again in place.
        match Arc::get_mut(&mut inputs) {
            Some(buffers) => prep.prepare_into(cam, buffers),
            None => inputs = Arc::new(prep.prepare(cam)),
        }
        making.par_iter_mut().with_max_len(1).try_for_each(|m| m.step(cam, i, cut, &inputs))?;
        making.iter_mut().for_each(InMaking::release_inputs);
        on_frame(i);
    }
    let generation_s = t0.elapsed().as_secs_f64();
    Ok(making.into_iter().map(|m| Workload { info: m.info, frames: m.frames, generation_s }).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A pipeline parameter's error says its cause once, also where the whole chain of sources
    /// is printed (`anyhow`'s `{:#}`): it is the pipeline error itself.
    #[test]
    fn a_pipeline_error_says_its_cause_once() {
        use neo_golden::sort::SortParamError;
        let e = DriverError::from(PipelineError::from(SortParamError::Chunk { chunk: 0, bsu: 16 }));
        assert_eq!(
            e.to_string(),
            "sorting parameters: chunk size 0 is not the BSU width 16 times a power of two"
        );
        assert!(std::error::Error::source(&e).is_none());
    }

    #[test]
    fn a_reuse_tile_whose_counters_are_not_one_command_sequence_is_refused() {
        let t = TileWork {
            sort_n: 40,
            merge_a: 300,
            merge_b: 40,
            dps_len: 300,
            dps_passes: 1,
            ..TileWork::default()
        };
        assert_eq!(tile_shape_holds(&t), Ok(()));
        let e = tile_shape_holds(&TileWork { merge_b: 41, ..t.clone() }).unwrap_err();
        assert!(e.contains("40") && e.contains("41"), "{e}");
        let e = tile_shape_holds(&TileWork { dps_len: 299, ..t.clone() }).unwrap_err();
        assert!(e.contains("DPS covers 299"), "{e}");
        // No DPS pass: the table goes into the merge unsorted; from scratch: no merge at all.
        assert_eq!(tile_shape_holds(&TileWork { dps_len: 0, dps_passes: 0, ..t.clone() }), Ok(()));
        assert_eq!(tile_shape_holds(&TileWork { from_scratch: true, merge_b: 0, ..t }), Ok(()));
    }
}
