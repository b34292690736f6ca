//! The per-frame driver: preprocessing into the feature table (the hardware's arithmetic on
//! the baked scene, or the float preprocess quantised in f64, [`super::Preprocessing`]), binning with
//! the ITU, per-tile sorting (the strategy's), fixed-point raster with the write-back of depth
//! keys and valid bits, and the references and statistics.
//!
//! Tiles are independent and processed in parallel (rayon), each phase over all tiles in turn
//! so that the timing of every stage is a wall-clock figure. Per-tile buffers live in the
//! pipeline and are reused from frame to frame; per-thread buffers come from a pool. The
//! work-only mode ([`Pipeline::work_frame`], in `frame/work_only.rs`) shares the stages up to the sort.
//! The strategy-independent stages (preprocessing, binning) make a [`FrameInputs`]
//! (`frame/inputs.rs`), which pipelines along the same cameras can share
//! ([`Pipeline::render_frame_with`], [`Pipeline::work_frame_with`]).

use std::io::{self, Write};
use std::sync::{Arc, Mutex};
use std::time::Instant;

use rayon::prelude::*;

use super::adaptive::{self, angle_deg, writeback_signals, CameraMotion, TilePlan, WritebackSignals};
use super::config::{Formats, PipelineConfig, PipelineError};
use super::order::{compare_orders, TileOrder};
use super::stats::{
    finite, FrameStats, GaussianCounts, OrderStats, RasterWork, Retention, TileAggregates, TileColumns,
    Timing,
};
use super::strategy::Strategy;
use super::tile::{exact_table, sort_tile, FramePos, TileCtx, TileSortOutput, TileState};
use super::trace::write_trace;
use crate::camera::Camera;
use crate::formats::{FeatureEntry, FeatureFormat};
use crate::hwpre::Baked;
use crate::image::Rgb8Image;
use crate::metrics::{psnr, ssim, SSIM_WINDOW};
use crate::profile::{self, Phase};
use crate::raster::window::{current_order_key, window_for_sorted, window_order};
use crate::raster::{raster_tile_into, RasterConfig, TileAt, TileRaster};
use crate::render;
use crate::scene::Scene;
use crate::sort::SortEntry;
pub use inputs::{FrameInputs, FramePrep};
pub use work_only::{
    gpu_count, gpu_duplication, FrameWork, GpuGrid, SampledRaster, TileWork, WorkOptions, GPU_TILE,
};

mod inputs;
mod work_only;

/// Marks a Gaussian without a feature entry this frame.
const CULLED: u32 = u32::MAX;

/// Per-tile buffers of one frame.
#[derive(Clone, Debug, Default)]
struct TileSlot {
    sort: TileSortOutput,
    /// Subtile bitmap of every entry of the rastered table (0 for culled Gaussians).
    bitmaps: Vec<u64>,
    /// Ids of the tile's incoming list (every current id when sorted from scratch).
    incoming: Vec<u32>,
    /// Exact table.
    exact: Vec<SortEntry>,
    /// The strategy's pixels (`tile * tile`).
    pixels: Vec<[u8; 3]>,
    /// The exact order's pixels, when they differ.
    exact_pixels: Vec<[u8; 3]>,
    /// The exact pixels equal `pixels`.
    exact_same: bool,
    /// Sum of `|pixels - exact_pixels|` over the tile.
    abs_error: u64,
    raster: TileRaster,
    /// The feature entries rastered last (indices into the feature table, in blend order).
    entries: Vec<u32>,
    feats: Vec<FeatureEntry>,
    raster_work: RasterWork,
    order: TileOrder,
    displacements: Vec<u32>,
    window: WindowScratch,
    /// The smallest reorder window that would have blended the tile in the exact order (0: not
    /// measured).
    window_needed: u32,
}

/// Where a tile's raster is made: the formats, the tile and the image size.
#[derive(Clone, Copy)]
struct RasterGeometry<'a> {
    fmt: &'a FeatureFormat,
    cfg: &'a RasterConfig,
    at: TileAt,
}

/// Rasterises tile `ti` of `inp` from the feature entries `entries` (indices into its feature
/// table, in blend order) into `out`. A raster depends only on its entries, the tile and the
/// geometry, which the pipelines sharing `inp` have in common: the one another of them made of
/// the same entries is taken when there is one; else it is made here (in `feats`' buffer) and,
/// with `keep`, kept for them.
fn raster_entries(
    inp: &FrameInputs,
    ti: usize,
    entries: &[u32],
    at: RasterGeometry,
    keep: bool,
    feats: &mut Vec<FeatureEntry>,
    out: &mut TileRaster,
) {
    let kept = &inp.rasters[ti];
    if let Some(k) = kept.find(entries) {
        out.clone_from(&k.raster);
        return;
    }
    feats.clear();
    feats.extend(entries.iter().map(|&f| inp.features[f as usize]));
    let TileAt { tile_x, tile_y, width, height } = at.at;
    raster_tile_into(feats, at.fmt, tile_x, tile_y, width, height, at.cfg, out);
    if keep {
        kept.keep(entries, out);
    }
}

/// Buffers of [`reorder_in_window`].
#[derive(Clone, Debug, Default)]
struct WindowScratch {
    keys: Vec<u64>,
    sorted: Vec<(u64, u32)>,
    order: Vec<u32>,
    table: Vec<SortEntry>,
}

/// Puts `table` in the order the raster core's reorder window of `window` entries emits it
/// ([`crate::raster::window`]): by each entry's current `{depth_key, id}` where the Gaussian has
/// a feature entry this frame, by its table key where it has none (culled: the raster reads no
/// feature for it). The raster blends and writes the table back in this order. With `measure`,
/// returns the smallest window that would have emitted the table in that order exactly
/// ([`window_for_sorted`]); else 0.
fn reorder_in_window(
    table: &mut Vec<SortEntry>,
    window: usize,
    inp: &FrameInputs,
    scratch: &mut WindowScratch,
    measure: bool,
) -> u32 {
    if window <= 1 && !measure {
        return 0;
    }
    scratch.keys.clear();
    scratch.keys.extend(table.iter().map(|e| {
        let current = match inp.feature_of[e.id as usize] {
            CULLED => None,
            f => Some(inp.features[f as usize].depth_key),
        };
        current_order_key(e, current)
    }));
    let needed = if measure { window_for_sorted(&scratch.keys, &mut scratch.sorted) as u32 } else { 0 };
    if window > 1 {
        window_order(&scratch.keys, window, &mut scratch.order);
        scratch.table.clear();
        scratch.table.extend(scratch.order.iter().map(|&i| table[i as usize]));
        std::mem::swap(table, &mut scratch.table);
    }
    needed
}

/// A pool of per-thread buffers.
struct CtxPool {
    free: Mutex<Vec<TileCtx>>,
    proto: TileCtx,
}

/// A buffer taken from the pool, returned on drop.
struct PooledCtx<'p> {
    ctx: Option<TileCtx>,
    pool: &'p CtxPool,
}

impl CtxPool {
    fn take(&self) -> PooledCtx<'_> {
        let ctx = self.free.lock().expect("pool lock").pop().unwrap_or_else(|| self.proto.clone());
        PooledCtx { ctx: Some(ctx), pool: self }
    }
}

impl Drop for PooledCtx<'_> {
    fn drop(&mut self) {
        if let Some(c) = self.ctx.take() {
            if let Ok(mut v) = self.pool.free.lock() {
                v.push(c);
            }
        }
    }
}

impl std::ops::Deref for PooledCtx<'_> {
    type Target = TileCtx;
    fn deref(&self) -> &TileCtx {
        self.ctx.as_ref().expect("present until drop")
    }
}

impl std::ops::DerefMut for PooledCtx<'_> {
    fn deref_mut(&mut self) -> &mut TileCtx {
        self.ctx.as_mut().expect("present until drop")
    }
}

/// The images and statistics of one frame.
#[derive(Clone, Debug)]
pub struct FrameOutput {
    /// The strategy's 8-bit frame.
    pub image: Rgb8Image,
    /// The exact-order frame (when compared).
    pub exact_image: Option<Rgb8Image>,
    /// The float reference (when compared).
    pub float_image: Option<Rgb8Image>,
    /// Statistics.
    pub stats: FrameStats,
    /// Per-tile columns.
    pub tiles: TileColumns,
}

/// The golden pipeline over a sequence of frames of one scene at one resolution.
pub struct Pipeline<'s> {
    scene: &'s Scene,
    /// Makes the frame's inputs (`None`: the pipeline takes shared inputs only).
    prep: Option<FramePrep<'s>>,
    /// The current frame's feature table and binning.
    inputs: Arc<FrameInputs>,
    cfg: PipelineConfig,
    formats: Formats,
    width: u32,
    height: u32,
    grid: [u32; 2],
    states: Vec<TileState>,
    slots: Vec<TileSlot>,
    pool: CtxPool,
    shot_start: usize,
    last_frame: Option<usize>,
    /// The previous frame's camera.
    prev_cam: Option<Camera>,
    /// The view direction at the last full sort (`motion`).
    sorted_forward: Option<glam::DVec3>,
    /// Camera motion since the previous frame.
    motion: CameraMotion,
}

/// Records the write-back's disorder signals of a tile's table (after its keys and valid bits
/// were written back) in its state, for the next frame's plan, and in this frame's counts.
fn record_writeback(state: &mut TileState, sort: &mut TileSortOutput) {
    let wb = writeback_signals(&state.table);
    state.writeback = wb;
    let c = &mut sort.counts;
    (c.wb_descents, c.wb_behind, c.wb_reach) = (wb.descents, wb.behind, wb.reach);
}

impl<'s> Pipeline<'s> {
    /// A pipeline for `scene` rendered at `width x height`.
    pub fn new(
        scene: &'s Scene,
        cfg: PipelineConfig,
        formats: Formats,
        width: u32,
        height: u32,
    ) -> Result<Self, PipelineError> {
        let mut p = Self::for_shared_inputs(scene, cfg, formats, width, height)?;
        p.prep = Some(p.frame_prep());
        Ok(p)
    }

    /// A pipeline that makes no inputs of its own: every frame is given its
    /// [`FrameInputs`] ([`Pipeline::render_frame_with`], [`Pipeline::work_frame_with`]), made
    /// by a [`FramePrep`] of the same scene, size and formats ([`Pipeline::frame_prep`]).
    pub fn for_shared_inputs(
        scene: &'s Scene,
        cfg: PipelineConfig,
        formats: Formats,
        width: u32,
        height: u32,
    ) -> Result<Self, PipelineError> {
        formats.check(&cfg.raster, scene.len())?;
        cfg.check_window()?;
        cfg.check_passes()?;
        if width == 0 || height == 0 {
            return Err(PipelineError::Other(format!("image size {width}x{height} is empty")));
        }
        if formats.sort.chunk() != cfg.chunk {
            return Err(PipelineError::Other(format!(
                "chunk {} differs from the sort configuration's {}",
                cfg.chunk,
                formats.sort.chunk()
            )));
        }
        let grid = [width.div_ceil(cfg.raster.tile), height.div_ceil(cfg.raster.tile)];
        let tiles = grid[0] as usize * grid[1] as usize;
        let proto = TileCtx::new(cfg.strategy, &formats.sort, cfg.dps_passes, cfg.capacity_or_max());
        Ok(Pipeline {
            scene,
            prep: None,
            inputs: Arc::default(),
            formats,
            width,
            height,
            grid,
            states: vec![TileState::default(); tiles],
            slots: vec![TileSlot::default(); tiles],
            pool: CtxPool { free: Mutex::new(Vec::new()), proto },
            shot_start: 0,
            last_frame: None,
            prev_cam: None,
            sorted_forward: None,
            motion: CameraMotion::default(),
            cfg,
        })
    }

    /// The image size `(width, height)` in pixels.
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// The configuration.
    pub fn config(&self) -> &PipelineConfig {
        &self.cfg
    }

    /// The number formats.
    pub fn formats(&self) -> &Formats {
        &self.formats
    }

    /// Tile grid `[x, y]`.
    pub fn grid(&self) -> [u32; 2] {
        self.grid
    }

    /// The baked scene the hardware preprocessing runs on (`None` with
    /// [`super::Preprocessing::Float`], or for a pipeline made [`Pipeline::for_shared_inputs`]).
    pub fn baked(&self) -> Option<&Baked> {
        self.prep.as_ref().and_then(FramePrep::baked)
    }

    /// A preparer of this pipeline's frame inputs (the scene baked again: make one and share
    /// it).
    pub fn frame_prep(&self) -> FramePrep<'s> {
        FramePrep::new(
            self.scene,
            &self.formats,
            self.cfg.raster,
            self.cfg.preprocess,
            self.width,
            self.height,
        )
    }

    /// The pipeline's own inputs of the frame seen from `cam` (its buffers reused when no other
    /// pipeline holds them).
    ///
    /// # Panics
    /// For a pipeline made [`Pipeline::for_shared_inputs`].
    fn own_inputs(&mut self, cam: &Camera) -> Arc<FrameInputs> {
        let prep = self.prep.as_ref().expect("a pipeline for shared inputs is given every frame's inputs");
        let mut inputs = std::mem::take(&mut self.inputs);
        match Arc::get_mut(&mut inputs) {
            Some(own) => prep.prepare_into(cam, own),
            None => inputs = Arc::new(prep.prepare(cam)),
        }
        inputs
    }

    /// Lets go of the last frame's inputs (shared ones can then be reused for the next frame);
    /// [`Pipeline::current_lists`], [`Pipeline::visible_ids`] and [`Pipeline::feature`] see an
    /// empty frame until the next one.
    pub fn release_inputs(&mut self) {
        self.inputs = Arc::default();
    }

    /// Takes `inputs` as the current frame's.
    ///
    /// # Panics
    /// When they were made for another image size or raster geometry.
    fn set_inputs(&mut self, inputs: Arc<FrameInputs>) {
        assert_eq!(inputs.size, (self.width, self.height), "frame inputs of another image size");
        assert_eq!(inputs.raster, Some(self.cfg.raster), "frame inputs of another raster geometry");
        assert_eq!(inputs.feature, Some(self.formats.feature), "frame inputs of another feature format");
        self.inputs = inputs;
    }

    /// The tables after the last frame's write-back (row-major tiles): the next frame's reused
    /// tables.
    pub fn tables(&self) -> impl Iterator<Item = &[SortEntry]> {
        self.states.iter().map(|s| s.table.as_slice())
    }

    /// Every tile's disorder counters of the last frame (row-major tiles): the MSU+ boundary
    /// inversions of its reuse merge (0 without one) and the write-back signals of its table.
    pub fn disorder(&self) -> impl Iterator<Item = (u32, WritebackSignals)> + '_ {
        self.states.iter().map(|s| (s.merge_inversions, s.writeback))
    }

    /// The current list of every tile in the last frame (ascending ids, current keys).
    pub fn current_lists(&self) -> impl Iterator<Item = &[SortEntry]> {
        let b = &self.inputs.binning;
        (0..b.tiles()).map(|t| b.tile(t))
    }

    /// The ids of the Gaussians with a feature entry (not culled) in the last frame, in feature
    /// order (ascending ids).
    pub fn visible_ids(&self) -> &[u32] {
        &self.inputs.feature_ids
    }

    /// The exact tables of the last frame (when the exact order was computed).
    pub fn exact_tables(&self) -> impl Iterator<Item = &[SortEntry]> {
        self.slots.iter().map(|s| s.exact.as_slice())
    }

    /// The last frame's feature entry of Gaussian `id`, or `None` when it has none (culled this
    /// frame, or `id` out of range): what the raster reads by a table entry's id.
    pub fn feature(&self, id: u32) -> Option<&FeatureEntry> {
        match self.inputs.feature_of.get(id as usize) {
            Some(&f) if f != CULLED => self.inputs.features.get(f as usize),
            _ => None,
        }
    }

    /// The subtile bitmaps of the last frame's rastered tables, per tile, per entry.
    pub fn bitmaps(&self) -> impl Iterator<Item = &[u64]> {
        self.slots.iter().map(|s| s.bitmaps.as_slice())
    }

    /// Renders frame `frame` from `cam` (of the pipeline's size). `cut` marks a scene cut; the
    /// first frame rendered is always a shot start.
    ///
    /// # Panics
    /// When the camera's size differs from the pipeline's.
    pub fn render_frame(&mut self, cam: &Camera, frame: usize, cut: bool) -> FrameOutput {
        let t_start = Instant::now();
        let inputs = self.own_inputs(cam);
        self.render_frame_from(cam, frame, cut, inputs, t_start)
    }

    /// [`Pipeline::render_frame`] on `inputs` (of this frame's camera, from a [`FramePrep`] of
    /// the pipeline's scene, size and formats), which other pipelines may share: the same
    /// output as making them here. The timing's preprocessing and binning are the inputs'.
    ///
    /// # Panics
    /// When the camera's size differs from the pipeline's, or the inputs were made for another
    /// size or raster geometry.
    pub fn render_frame_with(
        &mut self,
        cam: &Camera,
        frame: usize,
        cut: bool,
        inputs: Arc<FrameInputs>,
    ) -> FrameOutput {
        self.render_frame_from(cam, frame, cut, inputs, Instant::now())
    }

    fn render_frame_from(
        &mut self,
        cam: &Camera,
        frame: usize,
        cut: bool,
        inputs: Arc<FrameInputs>,
        t_start: Instant,
    ) -> FrameOutput {
        let pos = self.begin_frame(cam, frame, cut);
        self.set_inputs(inputs);
        let mut timing = Timing::default();
        (timing.preprocess_s, timing.quantize_s) = self.inputs.feature_s;
        timing.binning_s = self.inputs.binning_s;
        let t = Instant::now();
        self.sort_phase(pos);
        timing.sort_s = t.elapsed().as_secs_f64();
        let strategy = self.cfg.strategy;

        // Raster and write-back.
        let t = Instant::now();
        self.raster_phase(strategy.writes_back_keys());
        let image = self.assemble(false);
        timing.raster_s = t.elapsed().as_secs_f64();
        timing.pipeline_s =
            timing.preprocess_s + timing.quantize_s + timing.binning_s + timing.sort_s + timing.raster_s;

        // Exact reference.
        let t = Instant::now();
        self.reference_phase();
        let exact_image = if self.cfg.compare_exact { Some(self.assemble(true)) } else { None };
        timing.reference_s = t.elapsed().as_secs_f64();

        // Float reference.
        let t = Instant::now();
        let float_image = self
            .cfg
            .compare_float
            .then(|| render::render(self.scene, cam, &render::RenderOptions::default()).image.to_rgb8());
        timing.float_s = t.elapsed().as_secs_f64();

        // Metrics.
        let t = Instant::now();
        let mut stats = self.frame_stats(pos, cut, &image, exact_image.as_ref(), float_image.as_ref());
        timing.metrics_s = t.elapsed().as_secs_f64();
        timing.total_s = t_start.elapsed().as_secs_f64();
        stats.timing = timing;
        let inversions: Vec<u64> = self.slots.iter().map(|s| s.order.inversions).collect();
        let counts: Vec<_> = self.slots.iter().map(|s| s.sort.counts).collect();
        let scratch: Vec<bool> = self.slots.iter().map(|s| s.sort.from_scratch).collect();
        let abs_error: Vec<u64> = self.slots.iter().map(|s| s.abs_error).collect();
        let tiles = TileColumns::new(frame, self.grid, &counts, &inversions, &scratch, &abs_error);
        FrameOutput { image, exact_image, float_image, stats, tiles }
    }

    /// Starts frame `frame`: checks the camera's size and moves the shot start on a cut (the
    /// first frame is always a shot start).
    fn begin_frame(&mut self, cam: &Camera, frame: usize, cut: bool) -> FramePos {
        assert_eq!(
            (cam.width, cam.height),
            (self.width, self.height),
            "camera size differs from the pipeline's"
        );
        if cut || self.last_frame.is_none() {
            self.shot_start = frame;
        }
        self.last_frame = Some(frame);
        self.motion = self.prev_cam.as_ref().map(|p| CameraMotion::between(p, cam)).unwrap_or_default();
        self.prev_cam = Some(cam.clone());
        let pos = FramePos { frame, shot_start: self.shot_start };
        self.plan_phase(pos, cam);
        pos
    }

    /// Sets every tile's plan for this frame (`adaptive`: the budget allocation from the
    /// previous write-back; `motion`: a full sort when the view turned past the threshold).
    fn plan_phase(&mut self, pos: FramePos, cam: &Camera) {
        let shot_start = pos.frame == pos.shot_start;
        match self.cfg.strategy {
            // A still camera (the pose of the last frame) adds no disorder: Neo's single pass.
            Strategy::Adaptive(_) if !shot_start && self.motion == CameraMotion::default() => {
                for s in &mut self.states {
                    s.plan = TilePlan::Passes(1);
                }
            }
            Strategy::Adaptive(p) if !shot_start => {
                let chunk = self.cfg.chunk as u32;
                let requests: Vec<adaptive::Request> = self
                    .states
                    .iter()
                    .zip(&self.slots)
                    .map(|(s, slot)| {
                        adaptive::request(
                            &p,
                            &s.writeback,
                            s.merge_inversions,
                            slot.sort.counts.current,
                            chunk,
                        )
                    })
                    .collect();
                for (s, plan) in self.states.iter_mut().zip(adaptive::allocate(&p, &requests)) {
                    s.plan = plan;
                }
            }
            Strategy::Motion(mdeg) => {
                let fwd = cam.forward();
                let turned = self.sorted_forward.is_none_or(|f| angle_deg(f, fwd) * 1000.0 > mdeg as f64);
                if shot_start || turned {
                    self.sorted_forward = Some(fwd);
                    for s in &mut self.states {
                        s.plan = TilePlan::Resort;
                    }
                }
            }
            _ => {}
        }
    }

    /// The strategy's sorting step of every tile; records each tile's incoming ids.
    fn sort_phase(&mut self, pos: FramePos) {
        let _phase = profile::enter(Phase::Sort);
        let strategy = self.cfg.strategy;
        let binning = &self.inputs.binning;
        let pool = &self.pool;
        self.states.par_iter_mut().zip(self.slots.par_iter_mut()).enumerate().for_each_init(
            || pool.take(),
            |ctx, (ti, (state, slot))| {
                let current = binning.tile(ti);
                slot.sort = sort_tile(strategy, pos, state, current, ctx);
                slot.incoming.clear();
                if slot.sort.from_scratch {
                    slot.incoming.extend(current.iter().map(|e| e.id));
                } else {
                    slot.incoming.extend(ctx.incoming.iter().map(|e| e.id));
                }
            },
        );
    }

    /// True when other pipelines hold this frame's inputs too: only then are the rasters made
    /// kept in them for the others ([`raster_entries`]).
    fn inputs_shared(&self) -> bool {
        Arc::strong_count(&self.inputs) > 1
    }

    /// Rasterises every tile's table, fills the slots' bitmaps and pixels, and writes keys (when
    /// `write_keys`) and valid bits back into the tables.
    fn raster_phase(&mut self, write_keys: bool) {
        let _phase = profile::enter(Phase::TileWork);
        let inp = &*self.inputs;
        let (features, feature_of, binning) = (&inp.features, &inp.feature_of, &inp.binning);
        let (fmt, cfg, w, h, gx) =
            (&self.formats.feature, &self.cfg.raster, self.width, self.height, self.grid[0]);
        let subtiles = cfg.subtiles_per_tile() as u64;
        let (window, measure) = (self.cfg.raster_window, self.cfg.compare_exact && self.cfg.window_needed);
        let keep = self.inputs_shared();
        self.states.par_iter_mut().zip(self.slots.par_iter_mut()).enumerate().for_each(
            |(ti, (state, slot))| {
                let (tx, ty) = (ti as u32 % gx, ti as u32 / gx);
                slot.window_needed =
                    reorder_in_window(&mut state.table, window, inp, &mut slot.window, measure);
                slot.entries.clear();
                slot.entries
                    .extend(state.table.iter().map(|e| feature_of[e.id as usize]).filter(|&f| f != CULLED));
                let at = TileAt { tile_x: tx, tile_y: ty, width: w, height: h };
                let geometry = RasterGeometry { fmt, cfg, at };
                raster_entries(inp, ti, &slot.entries, geometry, keep, &mut slot.feats, &mut slot.raster);
                std::mem::swap(&mut slot.pixels, &mut slot.raster.pixels);
                let current = binning.tile(ti);
                let mut rw = RasterWork { entries: slot.entries.len() as u64, ..RasterWork::default() };
                rw.subtile_tests = rw.entries * subtiles;
                slot.bitmaps.clear();
                let mut j = 0;
                let mut popcount = 0u64;
                for e in state.table.iter_mut() {
                    let f = feature_of[e.id as usize];
                    let in_current = current.binary_search_by_key(&e.id, |c| c.id).is_ok();
                    if f == CULLED {
                        slot.bitmaps.push(0);
                        e.valid = false;
                        rw.itu_mismatch += in_current as u64;
                        continue;
                    }
                    let b = slot.raster.bitmaps[j];
                    let valid = slot.raster.valid[j];
                    slot.bitmaps.push(b);
                    popcount += b.count_ones() as u64;
                    rw.itu_mismatch += (valid != in_current) as u64;
                    e.valid = valid;
                    if write_keys {
                        e.key = features[f as usize].depth_key;
                    }
                    j += 1;
                }
                rw.subtile_blends = popcount;
                for sw in &slot.raster.work {
                    rw.subtile_processed += sw.processed as u64;
                    rw.pixel_evals += sw.pixel_evals as u64;
                    rw.finished_pixels += sw.finished_pixels as u64;
                    rw.terminated_subtiles += sw.terminated as u64;
                }
                slot.sort.counts.bitmap_popcount = popcount as u32;
                slot.raster_work = rw;
                record_writeback(state, &mut slot.sort);
            },
        );
    }

    /// Exact tables of every tile and, when compared, their raster (and each tile's absolute
    /// error against it).
    fn reference_phase(&mut self) {
        let inp = &*self.inputs;
        let (feature_of, binning) = (&inp.feature_of, &inp.binning);
        let (fmt, cfg, w, h, gx) =
            (&self.formats.feature, &self.cfg.raster, self.width, self.height, self.grid[0]);
        let capacity = self.cfg.capacity_or_max();
        let exact_strategy = self.cfg.strategy.is_exact();
        let (compare, shortcut) = (self.cfg.compare_exact, self.cfg.exact_shortcut);
        let keep = self.inputs_shared();
        let pool = &self.pool;
        self.states.par_iter().zip(self.slots.par_iter_mut()).enumerate().for_each_init(
            || pool.take(),
            |ctx, (ti, (state, slot))| {
                let current = binning.tile(ti);
                slot.abs_error = 0;
                exact_table(current, capacity, &mut slot.exact);
                if exact_strategy {
                    debug_assert!(state.table.iter().map(|e| e.id).eq(slot.exact.iter().map(|e| e.id)));
                    slot.exact_same = true;
                    return;
                }
                if !compare {
                    slot.exact_same = false;
                    return;
                }
                if shortcut {
                    ctx.marks.clear();
                    for e in current {
                        ctx.marks.insert(e.id);
                    }
                    let touching = state.table.iter().filter(|e| ctx.marks.contains(e.id)).map(|e| e.id);
                    if touching.eq(slot.exact.iter().map(|e| e.id)) {
                        slot.exact_same = true;
                        return;
                    }
                }
                slot.exact_same = false;
                // The exact table depends only on the current list and the capacity: its raster
                // is made once per tile for the pipelines sharing these inputs.
                slot.entries.clear();
                slot.entries.extend(slot.exact.iter().map(|e| feature_of[e.id as usize]));
                let at = TileAt { tile_x: ti as u32 % gx, tile_y: ti as u32 / gx, width: w, height: h };
                let geometry = RasterGeometry { fmt, cfg, at };
                raster_entries(inp, ti, &slot.entries, geometry, keep, &mut slot.feats, &mut slot.raster);
                std::mem::swap(&mut slot.exact_pixels, &mut slot.raster.pixels);
                slot.abs_error = slot
                    .pixels
                    .iter()
                    .zip(&slot.exact_pixels)
                    .flat_map(|(a, b)| a.iter().zip(b).map(|(x, y)| x.abs_diff(*y) as u64))
                    .sum();
            },
        );
    }

    /// The 8-bit frame from the slots' pixels (`exact`: the exact-order pixels).
    fn assemble(&self, exact: bool) -> Rgb8Image {
        let mut img = Rgb8Image::new(self.width, self.height);
        let t = self.cfg.raster.tile as usize;
        let (w, h, gx) = (self.width as usize, self.height as usize, self.grid[0] as usize);
        let row_bytes = 3 * w;
        img.data.par_chunks_mut(row_bytes * t).enumerate().for_each(|(ty, band)| {
            for tx in 0..gx {
                let slot = &self.slots[ty * gx + tx];
                let px = if exact && !slot.exact_same { &slot.exact_pixels } else { &slot.pixels };
                let x0 = tx * t;
                let cols = t.min(w - x0);
                let rows = t.min(h - ty * t);
                for ly in 0..rows {
                    let dst = &mut band[ly * row_bytes + 3 * x0..ly * row_bytes + 3 * (x0 + cols)];
                    for (d, s) in dst.chunks_exact_mut(3).zip(&px[ly * t..ly * t + cols]) {
                        d.copy_from_slice(s);
                    }
                }
            }
        });
        img
    }

    /// Statistics of the frame just rendered.
    fn frame_stats(
        &mut self,
        pos: FramePos,
        cut: bool,
        image: &Rgb8Image,
        exact: Option<&Rgb8Image>,
        float: Option<&Rgb8Image>,
    ) -> FrameStats {
        let exact_strategy = self.cfg.strategy.is_exact();
        let pool = &self.pool;
        if exact_strategy {
            for (state, slot) in self.states.iter().zip(self.slots.iter_mut()) {
                let n = state.table.len();
                slot.order = TileOrder { compared: n, ..TileOrder::default() };
                slot.displacements.clear();
                slot.displacements.resize(n, 0);
            }
        } else {
            self.states.par_iter().zip(self.slots.par_iter_mut()).for_each_init(
                || pool.take(),
                |ctx, (state, slot)| {
                    slot.displacements.clear();
                    slot.order =
                        compare_orders(&state.table, &slot.exact, &mut ctx.order, &mut slot.displacements);
                },
            );
        }
        let mut disp: Vec<u32> = self.slots.iter().flat_map(|s| s.displacements.iter().copied()).collect();
        let inversions = self.slots.iter().map(|s| s.order.inversions).sum();
        let with_inv = self.slots.iter().filter(|s| s.order.inversions > 0).count() as u64;
        let window_needed = self.slots.iter().map(|s| s.window_needed).max().unwrap_or(0);
        let order = OrderStats::from_displacements(&mut disp, inversions, with_inv, window_needed);

        let counts: Vec<_> = self.slots.iter().map(|s| s.sort.counts).collect();
        let from_scratch = self.slots.iter().filter(|s| s.sort.from_scratch).count() as u64;
        let mut work = super::work::StageWork::default();
        let mut raster = RasterWork::default();
        for s in &self.slots {
            work.add(&s.sort.work);
            raster.add(&s.raster_work);
        }
        let writes_back = self.cfg.strategy.reuses_tables();
        work.raster_read = raster.entries;
        if writes_back {
            work.writeback = counts.iter().map(|c| c.table_len as u64).sum();
        }
        let ssim_on = self.cfg.ssim;
        let metric = |a: &Rgb8Image, b: &Rgb8Image| -> (Option<f64>, Option<f64>) {
            let p = psnr(a, b).ok().and_then(finite);
            let s = if ssim_on { ssim(a, b).ok() } else { None };
            (p, s)
        };
        let identical = exact.map(|e| e.data == image.data);
        let ((pe, se), ((pf, sf), (epf, esf))) = if identical == Some(true) {
            // Same image: PSNR null, SSIM 1, and one comparison against the float reference.
            let vs_float = float.map(|f| metric(image, f)).unwrap_or_default();
            let big = image.width as usize >= SSIM_WINDOW && image.height as usize >= SSIM_WINDOW;
            ((None, (ssim_on && big).then_some(1.0)), (vs_float, vs_float))
        } else {
            rayon::join(
                || exact.map(|e| metric(image, e)).unwrap_or_default(),
                || {
                    rayon::join(
                        || float.map(|f| metric(image, f)).unwrap_or_default(),
                        || match (exact, float) {
                            (Some(e), Some(f)) => metric(e, f),
                            _ => (None, None),
                        },
                    )
                },
            )
        };
        let visible = self.inputs.features.len() as u64;
        FrameStats {
            frame: pos.frame,
            cut: cut && pos.frame == pos.shot_start,
            shot_start: pos.shot_start,
            from_scratch: from_scratch as usize == self.slots.len(),
            psnr_vs_exact: pe,
            psnr_vs_float: pf,
            ssim_vs_exact: se,
            ssim_vs_float: sf,
            exact_psnr_vs_float: epf,
            exact_ssim_vs_float: esf,
            identical_to_exact: identical,
            gaussians: GaussianCounts {
                total: self.scene.len() as u64,
                visible,
                culled: self.scene.len() as u64 - visible,
            },
            tiles: TileAggregates::from_counts(&counts, from_scratch, self.inputs.binning.tiles_tested),
            order,
            retention: Retention::from_counts(&counts),
            dropped_capacity: work.dropped_capacity,
            dropped_invalid: work.dropped_invalid,
            camera: self.motion,
            tiles_multi_pass: counts.iter().filter(|c| c.dps_passes > 1).count() as u64,
            work,
            raster,
            timing: Timing::default(),
        }
    }

    /// Writes the last frame as a `poc.trace` (see [`super::trace`]).
    pub fn write_trace(&self, out: &mut dyn Write) -> io::Result<()> {
        let tables: Vec<&[SortEntry]> = self.states.iter().map(|s| s.table.as_slice()).collect();
        let bitmaps: Vec<&[u64]> = self.slots.iter().map(|s| s.bitmaps.as_slice()).collect();
        let incoming: Vec<&[u32]> = self.slots.iter().map(|s| s.incoming.as_slice()).collect();
        let reused: Vec<u32> = self.slots.iter().map(|s| s.sort.counts.reused).collect();
        let culled: Vec<bool> = self.inputs.feature_of.iter().map(|&f| f == CULLED).collect();
        let header = super::trace::TraceHeader {
            width: self.width,
            height: self.height,
            tile: self.cfg.raster.tile,
            subtile: self.cfg.raster.subtile,
            chunk: self.cfg.chunk,
        };
        write_trace(out, &header, &culled, &tables, &bitmaps, &incoming, &reused)
    }
}
