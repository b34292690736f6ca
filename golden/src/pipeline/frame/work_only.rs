//! The pipeline's work-only mode: the same frame stages as [`Pipeline::render_frame`] up to the
//! sort (float preprocess, quantisation, binning with the ITU, the strategy's sorting step),
//! then, instead of the raster, the write-back of depth keys and valid bits and the per-tile
//! work counters. No pixels.
//!
//! The raster is skipped: its valid bit is the ITU's cumulative OR, which is exactly membership
//! in the tile's current list (the binning uses the same ITU; the full pipeline's
//! `itu_mismatch` counter asserts it), and its routed pairs are the subtile bitmaps
//! ([`subtile_bitmap`]). Only the SCUs' early termination needs blending: it is measured with
//! the golden raster's SCUs on every [`WorkOptions::raster_sample`]-th tile
//! ([`tile_work_into`]: the binning's bitmaps, transmittance only, no pixels).

use std::sync::Arc;

use rayon::prelude::*;

use super::{record_writeback, reorder_in_window, FrameInputs, Pipeline, CULLED};
use crate::camera::Camera;
use crate::pipeline::hierarchical::{hierarchical_sort, HierWork};
use crate::pipeline::prefetch::prefetch;
use crate::pipeline::tile::{FramePos, TileCtx, TileSortOutput};
use crate::profile::{self, Phase};
use crate::raster::{tile_work_into, TileAt};
use crate::render::Projected;

/// How many table entries ahead the feature gathers are prefetched.
const PREFETCH_AHEAD: usize = 16;

/// Tile side of the CUDA rasterizer's duplication ([`gpu_duplication`]).
pub const GPU_TILE: u32 = 16;

/// What the work-only mode measures besides the sort.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct WorkOptions {
    /// Also sort each tile's current list hierarchically from scratch (the GSCore baseline).
    pub hierarchical: bool,
    /// Raster every `raster_sample`-th tile with the golden raster to measure early termination
    /// (0: none).
    pub raster_sample: u32,
}

/// The golden raster's work on a sampled tile, over its subtiles inside the image.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SampledRaster {
    /// Entries the SCUs processed before their subtiles terminated.
    pub processed: u64,
    /// Entries routed to those subtiles.
    pub routed: u64,
}

/// The work counters of one tile in one frame.
#[derive(Clone, Debug, Default)]
pub struct TileWork {
    /// The sorting step's counters and stage work.
    pub sort: TileSortOutput,
    /// Entries of the table the raster reads.
    pub table_len: u32,
    /// Table entries with a feature entry (the raster's feature gathers).
    pub raster_entries: u32,
    /// Per subtile (row-major), the table entries in the current list routed to it by their
    /// subtile bitmap; 0 for subtiles outside the image.
    pub routed: Vec<u32>,
    /// The hierarchical sort of the current list from scratch ([`WorkOptions::hierarchical`]).
    pub hierarchical: Option<HierWork>,
    /// The golden raster's work, on sampled tiles ([`WorkOptions::raster_sample`]).
    pub sampled: Option<SampledRaster>,
}

/// The work counters of one frame.
#[derive(Clone, Debug)]
pub struct FrameWork {
    /// Frame and shot start.
    pub pos: FramePos,
    /// Gaussians in the scene.
    pub gaussians: u64,
    /// Gaussians with a feature entry.
    pub visible: u64,
    /// Tile-Gaussian tests of the binning.
    pub binning_tests: u64,
    /// The CUDA rasterizer's tile-Gaussian pairs over [`GPU_TILE`] tiles ([`gpu_duplication`]).
    pub gpu_pairs: u64,
    /// Gaussians with at least one such pair.
    pub gpu_visible: u64,
    /// Row-major tiles.
    pub tiles: Vec<TileWork>,
}

impl Pipeline<'_> {
    /// Runs frame `frame` from `cam` in the work-only mode (see the module docs): the tables are
    /// sorted and written back as by [`Pipeline::render_frame`], and the per-tile work counters
    /// are returned instead of pixels.
    ///
    /// # Panics
    /// When the camera's size differs from the pipeline's.
    pub fn work_frame(&mut self, cam: &Camera, frame: usize, cut: bool, opts: &WorkOptions) -> FrameWork {
        let inputs = self.own_inputs(cam);
        self.work_frame_with(cam, frame, cut, opts, inputs)
    }

    /// [`Pipeline::work_frame`] on `inputs` (of this frame's camera, from a [`super::FramePrep`]
    /// of the pipeline's scene, size and formats), which other pipelines may share: the same
    /// counters as making them here.
    ///
    /// # Panics
    /// When the camera's size differs from the pipeline's, or the inputs were made for another
    /// size or raster geometry.
    pub fn work_frame_with(
        &mut self,
        cam: &Camera,
        frame: usize,
        cut: bool,
        opts: &WorkOptions,
        inputs: Arc<FrameInputs>,
    ) -> FrameWork {
        let pos = self.begin_frame(cam, frame, cut);
        self.set_inputs(inputs);
        self.sort_phase(pos);
        let tiles = self.work_phase(opts);
        let inp = &*self.inputs;
        FrameWork {
            pos,
            gaussians: self.scene.len() as u64,
            visible: inp.features.len() as u64,
            binning_tests: inp.binning.tiles_tested,
            gpu_pairs: inp.gpu.0,
            gpu_visible: inp.gpu.1,
            tiles,
        }
    }

    /// Writes keys (when the strategy does) and valid bits back into every tile's table and
    /// counts the tile's work.
    fn work_phase(&mut self, opts: &WorkOptions) -> Vec<TileWork> {
        let _phase = profile::enter(Phase::TileWork);
        let inp = &*self.inputs;
        let (features, feature_of, binning) = (&inp.features, &inp.feature_of, &inp.binning);
        let (fmt, rcfg, w, h, gx) =
            (&self.formats.feature, &self.cfg.raster, self.width, self.height, self.grid[0]);
        let write_keys = self.cfg.strategy.writes_back_keys();
        let window = self.cfg.raster_window;
        let (n, s) = (rcfg.subtiles_per_side(), rcfg.subtile);
        let pool = &self.pool;
        self.states
            .par_iter_mut()
            .zip(self.slots.par_iter_mut())
            .enumerate()
            .map_init(
                || pool.take(),
                |pooled, (ti, (state, slot))| {
                    let ctx: &mut TileCtx = pooled;
                    let current = binning.tile(ti);
                    let bitmaps = binning.tile_bitmaps(ti);
                    let hierarchical = opts
                        .hierarchical
                        .then(|| hierarchical_sort(current, &mut ctx.table, &mut ctx.sorter, &mut ctx.bins));
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
                    let sampled = opts.raster_sample > 0 && (ti as u32).is_multiple_of(opts.raster_sample);
                    let mut routed = vec![0u32; (n * n) as usize];
                    let mut raster_entries = 0u32;
                    reorder_in_window(&mut state.table, window, inp, &mut slot.window, false);
                    slot.feats.clear();
                    slot.bitmaps.clear();
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
                        let at = current.binary_search_by_key(&e.id, |c| c.id);
                        e.valid = at.is_ok();
                        if write_keys {
                            e.key = fe.depth_key;
                        }
                        // The binning's bitmap of this Gaussian in this tile (the same feature
                        // entry's `subtile_bitmap`).
                        if let Ok(k) = at {
                            if sampled {
                                // The raster's routing: an entry outside the current list has
                                // an empty bitmap (the ITU's OR is the list's membership).
                                slot.feats.push(*fe);
                                slot.bitmaps.push(bitmaps[k]);
                            }
                            let mut b = bitmaps[k] & inside;
                            while b != 0 {
                                routed[b.trailing_zeros() as usize] += 1;
                                b &= b - 1;
                            }
                        }
                    }
                    record_writeback(state, &mut slot.sort);
                    let sampled = sampled.then(|| {
                        let at = TileAt { tile_x: tx, tile_y: ty, width: w, height: h };
                        tile_work_into(&slot.feats, &slot.bitmaps, fmt, at, rcfg, &mut slot.raster.work);
                        let mut r = SampledRaster::default();
                        for (j, sw) in slot.raster.work.iter().enumerate() {
                            if inside >> j & 1 == 1 {
                                r.processed += sw.processed as u64;
                                r.routed += sw.routed as u64;
                            }
                        }
                        r
                    });
                    TileWork {
                        sort: slot.sort.clone(),
                        table_len: state.table.len() as u32,
                        raster_entries,
                        routed,
                        hierarchical,
                        sampled,
                    }
                },
            )
            .collect()
    }
}

/// The CUDA rasterizer's duplication over `tile`-pixel tiles: per Gaussian, the rectangle
/// `getRect(mean, radius)` clamped to the grid; returns (pairs, Gaussians with a non-empty
/// rectangle and a positive radius).
pub fn gpu_duplication(projected: &[Projected], width: u32, height: u32, tile: u32) -> (u64, u64) {
    let grid = GpuGrid::new(width, height, tile);
    projected
        .par_iter()
        .map(|p| grid.pairs(p))
        .fold(|| (0, 0), gpu_count)
        .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1))
}

/// `acc` (pairs, Gaussians with pairs) counting one more Gaussian with `pairs` pairs.
pub fn gpu_count(acc: (u64, u64), pairs: u64) -> (u64, u64) {
    (acc.0 + pairs, acc.1 + (pairs > 0) as u64)
}

/// The tile grid of [`gpu_duplication`], made once per frame: its size in tiles and the tile
/// side.
#[derive(Clone, Copy, Debug)]
pub struct GpuGrid {
    gx: i64,
    gy: i64,
    tile: f32,
}

impl GpuGrid {
    /// The grid of `tile`-pixel tiles over a `width` x `height` image.
    pub fn new(width: u32, height: u32, tile: u32) -> Self {
        GpuGrid { gx: width.div_ceil(tile) as i64, gy: height.div_ceil(tile) as i64, tile: tile as f32 }
    }

    /// The tile-Gaussian pairs of one Gaussian: its rectangle `getRect(mean, radius)` clamped
    /// to the grid (0 for a zero radius).
    pub fn pairs(&self, p: &Projected) -> u64 {
        if p.radius == 0 {
            return 0;
        }
        let (t, r) = (self.tile, p.radius as f32);
        let lo = |m: f32, g: i64| (((m - r) / t) as i64).clamp(0, g);
        let hi = |m: f32, g: i64| (((m + r + t - 1.0) / t) as i64).clamp(0, g);
        let nx = hi(p.mean2d[0], self.gx) - lo(p.mean2d[0], self.gx);
        let ny = hi(p.mean2d[1], self.gy) - lo(p.mean2d[1], self.gy);
        (nx.max(0) * ny.max(0)) as u64
    }
}
