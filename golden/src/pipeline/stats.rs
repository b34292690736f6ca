//! Per-frame statistics and the `stats.json` schema (serde). See docs/formats.md, section
//! "Reuse-and-update pipeline and statistics", for every field.
//!
//! JSON has no infinity: a PSNR between identical images is written as `null` (and
//! `identical_to_exact` says so); a comparison that was not computed is `null` too (the
//! `config` block says which comparisons were enabled).

use serde::{Deserialize, Serialize};

use super::order::percentile_u32;
use super::tile::TileCounts;
use super::work::StageWork;

/// Gaussian counts of one frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct GaussianCounts {
    /// Gaussians in the scene.
    pub total: u64,
    /// Gaussians with a feature entry (survived preprocessing).
    pub visible: u64,
    /// Gaussians culled by preprocessing.
    pub culled: u64,
}

/// Tile aggregates of one frame (sums over tiles unless named otherwise).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct TileAggregates {
    /// Tiles in the grid.
    pub count: u64,
    /// Tiles with a non-empty current list.
    pub nonempty: u64,
    /// Tiles sorted from scratch this frame.
    pub from_scratch: u64,
    /// Sum of the current-list lengths (tile-Gaussian pairs).
    pub pairs: u64,
    /// Sum of the rastered table lengths.
    pub table_entries: u64,
    /// Longest rastered table.
    pub table_len_max: u64,
    /// Mean rastered table length over non-empty tiles.
    pub table_len_mean: f64,
    /// Newly visible entries (`|S \ V|`).
    pub incoming: u64,
    /// Entries still touching (`|S ∩ V|`).
    pub retained: u64,
    /// Entries that left (`|V \ S|`).
    pub outgoing: u64,
    /// Rastered entries taken over from a reused table.
    pub reused: u64,
    /// Rastered entries not touching the tile now.
    pub stale: u64,
    /// Set bits of all subtile bitmaps of the rastered tables.
    pub bitmap_popcount: u64,
    /// Chunks DPS touched.
    pub dps_chunks: u64,
    /// Candidate tiles the binning tested with the ITU.
    pub binning_tests: u64,
}

impl TileAggregates {
    /// Sums the per-tile counts.
    pub fn from_counts(counts: &[TileCounts], from_scratch: u64, binning_tests: u64) -> Self {
        let mut a =
            TileAggregates { count: counts.len() as u64, from_scratch, binning_tests, ..Default::default() };
        for c in counts {
            a.nonempty += (c.current > 0) as u64;
            a.pairs += c.current as u64;
            a.table_entries += c.table_len as u64;
            a.table_len_max = a.table_len_max.max(c.table_len as u64);
            a.incoming += c.incoming as u64;
            a.retained += c.retained as u64;
            a.outgoing += c.outgoing as u64;
            a.reused += c.reused as u64;
            a.stale += c.stale as u64;
            a.bitmap_popcount += c.bitmap_popcount as u64;
            a.dps_chunks += c.dps_chunks as u64;
        }
        let tiles_with_table = counts.iter().filter(|c| c.table_len > 0).count();
        if tiles_with_table > 0 {
            a.table_len_mean = a.table_entries as f64 / tiles_with_table as f64;
        }
        a
    }
}

/// Order quality of the rastered tables against the exact order (see [`super::order`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct OrderStats {
    /// Entries compared (in both the table and the exact table), over all tiles.
    pub compared: u64,
    /// Mean displacement.
    pub displacement_mean: f64,
    /// 90th percentile of the displacement (nearest rank).
    pub displacement_p90: u32,
    /// 95th percentile.
    pub displacement_p95: u32,
    /// 99th percentile.
    pub displacement_p99: u32,
    /// Largest displacement.
    pub displacement_max: u32,
    /// Pairs out of order, summed over tiles.
    pub inversions: u64,
    /// Tiles with at least one inversion.
    pub tiles_with_inversions: u64,
    /// The smallest raster reorder window (`--raster-window`, [`crate::raster::window`]) that
    /// would have blended every tile of the frame in the exact order, from the tables as the
    /// sort left them: the most places an entry is later than its place in the current order,
    /// plus one (1: already exact; 0: not measured, without `compare_exact` or
    /// `PipelineConfig::window_needed`).
    pub window_needed: u32,
}

impl OrderStats {
    /// From all displacements of the frame (reordered), the inversion total, the number of
    /// tiles with inversions and the largest window a tile needed (0: not measured).
    pub fn from_displacements(
        d: &mut [u32],
        inversions: u64,
        tiles_with_inversions: u64,
        window_needed: u32,
    ) -> Self {
        let sum: u64 = d.iter().map(|&x| x as u64).sum();
        OrderStats {
            compared: d.len() as u64,
            displacement_mean: if d.is_empty() { 0.0 } else { sum as f64 / d.len() as f64 },
            displacement_p90: percentile_u32(d, 0.90),
            displacement_p95: percentile_u32(d, 0.95),
            displacement_p99: percentile_u32(d, 0.99),
            displacement_max: d.iter().copied().max().unwrap_or(0),
            inversions,
            tiles_with_inversions,
            window_needed,
        }
    }
}

/// Retention (paper Fig. 6): the fraction of a tile's current Gaussians that were valid in its
/// previous table, `retained / current`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Retention {
    /// Over all pairs: `sum retained / sum current` (`null` when no tile has Gaussians).
    pub pooled: Option<f64>,
    /// Mean over non-empty tiles.
    pub tile_mean: Option<f64>,
    /// 10th percentile over non-empty tiles.
    pub tile_p10: Option<f64>,
    /// Median over non-empty tiles.
    pub tile_median: Option<f64>,
}

impl Retention {
    /// From the per-tile counts.
    pub fn from_counts(counts: &[TileCounts]) -> Self {
        let mut r: Vec<f64> =
            counts.iter().filter(|c| c.current > 0).map(|c| c.retained as f64 / c.current as f64).collect();
        if r.is_empty() {
            return Retention::default();
        }
        let (cur, ret) =
            counts.iter().fold((0u64, 0u64), |(a, b), c| (a + c.current as u64, b + c.retained as u64));
        let mean = r.iter().sum::<f64>() / r.len() as f64;
        r.sort_unstable_by(f64::total_cmp);
        let q = |q: f64| r[((r.len() - 1) as f64 * q).round() as usize];
        Retention {
            pooled: Some(ret as f64 / cur as f64),
            tile_mean: Some(mean),
            tile_p10: Some(q(0.1)),
            tile_median: Some(q(0.5)),
        }
    }
}

/// Wall-clock seconds per stage of one frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Timing {
    /// Float preprocessing ([`crate::render::preprocess`]).
    pub preprocess_s: f64,
    /// Quantisation into the feature table.
    pub quantize_s: f64,
    /// Binning with the ITU.
    pub binning_s: f64,
    /// Per-tile sorting (the strategy's).
    pub sort_s: f64,
    /// Fixed-point raster of the strategy's tables, write-back, frame assembly.
    pub raster_s: f64,
    /// `preprocess_s + quantize_s + binning_s + sort_s + raster_s`: the golden pipeline.
    pub pipeline_s: f64,
    /// Exact tables and the exact-order raster (the error reference).
    pub reference_s: f64,
    /// The float reference renderer.
    pub float_s: f64,
    /// PSNR, SSIM and order statistics.
    pub metrics_s: f64,
    /// Whole frame.
    pub total_s: f64,
}

/// Raster work of one frame, summed over tiles.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct RasterWork {
    /// Table entries given to the raster (entries of culled Gaussians are not).
    pub entries: u64,
    /// Subtile bitmap tests (entries x subtiles per tile).
    pub subtile_tests: u64,
    /// Entry-subtile pairs routed to an SCU (set bitmap bits).
    pub subtile_blends: u64,
    /// Entry-subtile pairs the SCUs processed before their subtile terminated.
    pub subtile_processed: u64,
    /// Pixel-entry evaluations (for each processed entry, the pixels still active).
    pub pixel_evals: u64,
    /// Pixels whose transmittance reached the floor.
    pub finished_pixels: u64,
    /// Subtiles that stopped before their last routed entry.
    pub terminated_subtiles: u64,
    /// Rastered entries whose raster valid bit disagrees with the binning (must be 0: the
    /// binning and the raster use the same ITU).
    pub itu_mismatch: u64,
}

impl RasterWork {
    /// Adds `o` into `self`.
    pub fn add(&mut self, o: &RasterWork) {
        self.entries += o.entries;
        self.subtile_tests += o.subtile_tests;
        self.subtile_blends += o.subtile_blends;
        self.subtile_processed += o.subtile_processed;
        self.pixel_evals += o.pixel_evals;
        self.finished_pixels += o.finished_pixels;
        self.terminated_subtiles += o.terminated_subtiles;
        self.itu_mismatch += o.itu_mismatch;
    }
}

/// Everything measured for one frame (one element of `frames` in `stats.json`).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct FrameStats {
    /// Frame index.
    pub frame: usize,
    /// True when the frame starts a shot after a scene cut.
    pub cut: bool,
    /// First frame of the frame's shot.
    pub shot_start: usize,
    /// True when every tile was sorted from scratch (shot starts, `full`, `hierarchical`,
    /// periodic refreshes).
    pub from_scratch: bool,
    /// PSNR (dB) against the exact-order frame of the same fixed-point pipeline; `null` when
    /// identical or not computed.
    pub psnr_vs_exact: Option<f64>,
    /// PSNR (dB) against the float reference renderer at the same camera.
    pub psnr_vs_float: Option<f64>,
    /// SSIM against the exact-order frame.
    pub ssim_vs_exact: Option<f64>,
    /// SSIM against the float reference.
    pub ssim_vs_float: Option<f64>,
    /// PSNR of the exact-order frame against the float reference (the floor the strategy is
    /// judged against: `psnr_vs_float - exact_psnr_vs_float` is the strategy's loss).
    pub exact_psnr_vs_float: Option<f64>,
    /// SSIM of the exact-order frame against the float reference.
    pub exact_ssim_vs_float: Option<f64>,
    /// Whether the frame equals the exact-order frame bit for bit (`null` when not compared).
    pub identical_to_exact: Option<bool>,
    /// Gaussian counts.
    pub gaussians: GaussianCounts,
    /// Tile aggregates.
    pub tiles: TileAggregates,
    /// Order quality.
    pub order: OrderStats,
    /// Retention.
    pub retention: Retention,
    /// Sorting-stage work.
    pub work: StageWork,
    /// Raster work.
    pub raster: RasterWork,
    /// Entries removed by the capacity cut (= `work.dropped_capacity`).
    pub dropped_capacity: u64,
    /// Entries removed by the MSU+ for a valid bit of 0 (= `work.dropped_invalid`).
    pub dropped_invalid: u64,
    /// Camera motion since the previous frame rendered (zero for the first).
    pub camera: super::adaptive::CameraMotion,
    /// Tiles sorted with more than one DPS pass (`adaptive`).
    pub tiles_multi_pass: u64,
    /// Timing.
    pub timing: Timing,
}

/// Per-tile columns of one frame (one line of `tiles.jsonl`); index = row-major tile index.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct TileColumns {
    /// Frame index.
    pub frame: usize,
    /// Tile grid `[x, y]`.
    pub grid: [u32; 2],
    /// `|S|`.
    pub current: Vec<u32>,
    /// Rastered table length.
    pub table_len: Vec<u32>,
    /// `|S \ V|`.
    pub incoming: Vec<u32>,
    /// `|V \ S|`.
    pub outgoing: Vec<u32>,
    /// `|S ∩ V|`.
    pub retained: Vec<u32>,
    /// Entries taken over from a reused table.
    pub reused: Vec<u32>,
    /// Subtile-bitmap popcount.
    pub bitmap_popcount: Vec<u32>,
    /// Chunks DPS touched.
    pub dps_chunks: Vec<u32>,
    /// Inversions against the exact order.
    pub inversions: Vec<u64>,
    /// DPS passes run on the tile.
    pub dps_passes: Vec<u32>,
    /// Those passes used the wide chunk (1) or the chunk (0).
    pub dps_wide: Vec<u8>,
    /// Sorted from scratch (1) or reused (0).
    pub from_scratch: Vec<u8>,
    /// MSU+ boundary inversions of the reused stream.
    pub merge_inversions: Vec<u32>,
    /// Write-back descents (the rastered table against the current keys).
    pub wb_descents: Vec<u32>,
    /// Write-back entries behind the running maximum.
    pub wb_behind: Vec<u32>,
    /// Write-back reach.
    pub wb_reach: Vec<u32>,
    /// Sum over the tile's pixels and channels of `|strategy - exact|` (0 when not compared).
    pub abs_error: Vec<u64>,
}

impl TileColumns {
    /// Columns from per-tile counts and inversions.
    pub fn new(
        frame: usize,
        grid: [u32; 2],
        counts: &[TileCounts],
        inversions: &[u64],
        from_scratch: &[bool],
        abs_error: &[u64],
    ) -> Self {
        let col = |f: fn(&TileCounts) -> u32| counts.iter().map(f).collect::<Vec<u32>>();
        TileColumns {
            frame,
            grid,
            current: col(|c| c.current),
            table_len: col(|c| c.table_len),
            incoming: col(|c| c.incoming),
            outgoing: col(|c| c.outgoing),
            retained: col(|c| c.retained),
            reused: col(|c| c.reused),
            bitmap_popcount: col(|c| c.bitmap_popcount),
            dps_chunks: col(|c| c.dps_chunks),
            inversions: inversions.to_vec(),
            dps_passes: col(|c| c.dps_passes),
            dps_wide: counts.iter().map(|c| c.dps_wide as u8).collect(),
            from_scratch: from_scratch.iter().map(|&b| b as u8).collect(),
            merge_inversions: col(|c| c.merge_inversions),
            wb_descents: col(|c| c.wb_descents),
            wb_behind: col(|c| c.wb_behind),
            wb_reach: col(|c| c.wb_reach),
            abs_error: abs_error.to_vec(),
        }
    }
}

/// A PSNR for JSON: `None` for identical images (infinite PSNR).
pub fn finite(v: f64) -> Option<f64> {
    v.is_finite().then_some(v)
}

/// How many frames after `start` the order took to become exact again: the first frame `g >=
/// start` of the same shot with `inversions == 0` gives `g - start`; `None` when it never did
/// within the shot (or the run).
pub fn frames_to_exact(frames: &[FrameStats], start: usize) -> Option<usize> {
    for f in frames.iter().filter(|f| f.frame >= start) {
        if f.frame > start && f.cut {
            return None;
        }
        if f.order.inversions == 0 {
            return Some(f.frame - start);
        }
    }
    None
}

/// Summary over a run (the `summary` block of `stats.json`).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Summary {
    /// Frames rendered.
    pub frames: usize,
    /// Frames identical to the exact-order frame.
    pub frames_identical_to_exact: usize,
    /// Mean PSNR against the exact frame over the non-identical frames.
    pub psnr_vs_exact_mean: Option<f64>,
    /// Lowest PSNR against the exact frame.
    pub psnr_vs_exact_min: Option<f64>,
    /// Lowest SSIM against the exact frame.
    pub ssim_vs_exact_min: Option<f64>,
    /// Mean PSNR against the float reference.
    pub psnr_vs_float_mean: Option<f64>,
    /// Mean PSNR of the exact frames against the float reference.
    pub exact_psnr_vs_float_mean: Option<f64>,
    /// `psnr_vs_float_mean - exact_psnr_vs_float_mean` (the strategy's quality loss, dB).
    pub psnr_loss_vs_exact_db: Option<f64>,
    /// Pooled retention over the frames after the first.
    pub retention_pooled: Option<f64>,
    /// Largest per-frame inversion count.
    pub inversions_max: u64,
    /// Largest displacement seen.
    pub displacement_max: u32,
    /// Largest `order.window_needed` over the frames: the raster reorder window that would have
    /// made every frame exact (0: not measured).
    pub window_needed_max: u32,
    /// For every shot start after frame 0 (a cut): frames until the order was exact again.
    pub recovery: Vec<Recovery>,
    /// Work summed over the frames.
    pub work: StageWork,
    /// Sorting-stage DRAM bytes (entries read + written times the entry size), summed over
    /// frames, the background sorter's included.
    pub sort_dram_bytes: u64,
    /// The background sorter's share of `sort_dram_bytes` (`background:K` only).
    pub background_dram_bytes: u64,
    /// Entries dropped by the capacity cut, summed.
    pub dropped_capacity: u64,
    /// Timing summed over the frames.
    pub timing: Timing,
}

/// Order recovery after a cut.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct Recovery {
    /// The cut frame.
    pub frame: usize,
    /// Frames until `inversions == 0` (0: exact at the cut itself); `null` if never in the run.
    pub frames_to_exact: Option<usize>,
}

fn mean(v: impl Iterator<Item = f64>) -> Option<f64> {
    let (s, n) = v.fold((0.0, 0usize), |(s, n), x| (s + x, n + 1));
    (n > 0).then(|| s / n as f64)
}

fn min(v: impl Iterator<Item = f64>) -> Option<f64> {
    v.fold(None, |m: Option<f64>, x| Some(m.map_or(x, |m| m.min(x))))
}

impl Summary {
    /// Summarises `frames`; `bytes_per_entry` converts sorting-stage entries to bytes.
    pub fn new(frames: &[FrameStats], bytes_per_entry: usize) -> Self {
        let mut work = StageWork::default();
        let mut timing = Timing::default();
        for f in frames {
            work.add(&f.work);
            let t = &f.timing;
            timing.preprocess_s += t.preprocess_s;
            timing.quantize_s += t.quantize_s;
            timing.binning_s += t.binning_s;
            timing.sort_s += t.sort_s;
            timing.raster_s += t.raster_s;
            timing.pipeline_s += t.pipeline_s;
            timing.reference_s += t.reference_s;
            timing.float_s += t.float_s;
            timing.metrics_s += t.metrics_s;
            timing.total_s += t.total_s;
        }
        let pf = mean(frames.iter().filter_map(|f| f.psnr_vs_float));
        let pe = mean(frames.iter().filter_map(|f| f.exact_psnr_vs_float));
        let (cur, ret) =
            frames.iter().skip(1).fold((0u64, 0u64), |(c, r), f| (c + f.tiles.pairs, r + f.tiles.retained));
        let recovery = frames
            .iter()
            .filter(|f| f.cut)
            .map(|f| Recovery { frame: f.frame, frames_to_exact: frames_to_exact(frames, f.frame) })
            .collect();
        Summary {
            frames: frames.len(),
            frames_identical_to_exact: frames.iter().filter(|f| f.identical_to_exact == Some(true)).count(),
            psnr_vs_exact_mean: mean(frames.iter().filter_map(|f| f.psnr_vs_exact)),
            psnr_vs_exact_min: min(frames.iter().filter_map(|f| f.psnr_vs_exact)),
            ssim_vs_exact_min: min(frames.iter().filter_map(|f| f.ssim_vs_exact)),
            psnr_vs_float_mean: pf,
            exact_psnr_vs_float_mean: pe,
            psnr_loss_vs_exact_db: pf.zip(pe).map(|(a, b)| a - b),
            retention_pooled: (cur > 0).then(|| ret as f64 / cur as f64),
            inversions_max: frames.iter().map(|f| f.order.inversions).max().unwrap_or(0),
            displacement_max: frames.iter().map(|f| f.order.displacement_max).max().unwrap_or(0),
            window_needed_max: frames.iter().map(|f| f.order.window_needed).max().unwrap_or(0),
            recovery,
            sort_dram_bytes: (work.dram_read
                + work.dram_written
                + work.background_dram_read
                + work.background_dram_written)
                * bytes_per_entry as u64,
            background_dram_bytes: (work.background_dram_read + work.background_dram_written)
                * bytes_per_entry as u64,
            dropped_capacity: work.dropped_capacity,
            work,
            timing,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(i: usize, cut: bool, shot_start: usize, inv: u64) -> FrameStats {
        FrameStats {
            frame: i,
            cut,
            shot_start,
            order: OrderStats { inversions: inv, ..Default::default() },
            ..Default::default()
        }
    }

    #[test]
    fn recovery_counts_frames_within_the_shot() {
        let fs = vec![
            frame(0, false, 0, 0),
            frame(1, false, 0, 5),
            frame(2, true, 2, 0),
            frame(3, false, 2, 7),
            frame(4, false, 2, 3),
            frame(5, false, 2, 0),
            frame(6, true, 6, 4),
        ];
        assert_eq!(frames_to_exact(&fs, 1), None);
        assert_eq!(frames_to_exact(&fs, 0), Some(0));
        assert_eq!(frames_to_exact(&fs, 3), Some(2));
        assert_eq!(frames_to_exact(&fs, 6), None);
        let s = Summary::new(&fs, 6);
        assert_eq!(
            s.recovery,
            vec![
                Recovery { frame: 2, frames_to_exact: Some(0) },
                Recovery { frame: 6, frames_to_exact: None }
            ]
        );
        assert_eq!(s.inversions_max, 7);
    }

    #[test]
    fn infinite_psnr_becomes_null_in_json() {
        let f = FrameStats {
            psnr_vs_exact: finite(f64::INFINITY),
            psnr_vs_float: finite(31.5),
            ..Default::default()
        };
        let j = serde_json::to_value(&f).unwrap();
        assert!(j["psnr_vs_exact"].is_null());
        assert_eq!(j["psnr_vs_float"], 31.5);
        assert_eq!(j["frame"], 0);
        assert!(j["order"]["displacement_p99"].is_u64());
    }

    #[test]
    fn retention_pools_and_takes_tile_quantiles() {
        let c = |current, retained| TileCounts { current, retained, ..Default::default() };
        let r = Retention::from_counts(&[c(10, 5), c(0, 0), c(30, 30)]);
        assert_eq!(r.pooled, Some(35.0 / 40.0));
        assert_eq!(r.tile_mean, Some(0.75));
        assert_eq!(r.tile_p10, Some(0.5));
        assert_eq!(Retention::from_counts(&[]).pooled, None);
    }
}
