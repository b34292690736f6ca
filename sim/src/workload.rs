//! The model's input: the golden pipeline's per-frame, per-tile work (no pixels).
//!
//! One [`Workload`] is one run of a golden strategy along a trajectory at one resolution. Per
//! frame and tile it records what each engine has to do: the conventional sort, the DPS and the
//! MSU+ merge of the reuse-and-update step (or the background sorter's sort), the raster's table
//! and feature reads with its per-subtile routed pairs, the write-back; plus the hierarchical
//! sort of the same tile's list from scratch (what a GSCore-style sorter does) so that the
//! baselines run on the same trace. [`crate::driver`] fills it from `neo_golden::pipeline`.

use serde::{Deserialize, Serialize};

/// The work of a hierarchical (GSCore-style) sort of one tile's list from scratch
/// (`neo_golden::pipeline::hierarchical`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct HierTile {
    /// Entries sorted.
    pub entries: u32,
    /// Entries streamed through approximate (binning) passes.
    pub approx_entries: u32,
    /// Approximate passes.
    pub approx_passes: u32,
    /// On-chip sorts of bins (and fallback chunks).
    pub bin_sorts: u32,
    /// Entries in those sorts.
    pub bin_entries: u32,
    /// Entries through fallback global merge passes.
    pub fallback_global: u32,
}

/// One tile of one frame.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct TileWork {
    /// The tile was sorted from scratch (shot start, `full`, periodic refresh, `hierarchical`).
    pub from_scratch: bool,
    /// `|S|`: Gaussians touching the tile.
    pub current: u32,
    /// `|S \ V|`: newly visible entries.
    pub incoming: u32,
    /// Entries of the conventional sort this frame (the incoming list, or all of `S` from
    /// scratch); 0 for `hierarchical`.
    pub sort_n: u32,
    /// Reused-table entries through DPS (0: no DPS).
    pub dps_len: u32,
    /// DPS passes.
    pub dps_passes: u32,
    /// Chunk of those DPS passes when it is not the engine's (`adaptive` with a wide chunk);
    /// 0 for the engine's chunk.
    #[serde(default)]
    pub dps_chunk: u32,
    /// MSU+ insert/delete merge: table entries in.
    pub merge_a: u32,
    /// MSU+ merge: incoming entries in.
    pub merge_b: u32,
    /// MSU+ merge: entries out (before the capacity cut).
    pub merge_out: u32,
    /// Entries removed by the capacity cut.
    pub dropped_capacity: u32,
    /// Entries of the table the raster reads.
    pub table_len: u32,
    /// Table entries with a feature entry (the raster's feature gathers).
    pub raster_entries: u32,
    /// Table entries written back after the raster (depth keys and valid bits).
    pub writeback: u32,
    /// Entries the background sorter sorts (`background:K`).
    pub background_n: u32,
    /// Hierarchical sort of `S` from scratch (the `hierarchical` strategy's and GSCore's sort).
    pub hier: HierTile,
    /// Per subtile (row-major), entry-subtile pairs routed to its SCU; 0 for subtiles outside
    /// the image.
    pub routed: Vec<u32>,
}

/// Image quality of one frame from the golden statistics (when the golden raster ran).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Quality {
    /// PSNR against the exact-order frame (`None`: identical or not computed).
    pub psnr_vs_exact: Option<f64>,
    /// PSNR against the float reference.
    pub psnr_vs_float: Option<f64>,
    /// PSNR of the exact-order frame against the float reference.
    pub exact_psnr_vs_float: Option<f64>,
    /// The frame equals the exact-order frame.
    pub identical_to_exact: Option<bool>,
}

/// The golden model's frame sums the workload must agree with (entries, not bytes).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct GoldenSums {
    /// Sorting-stage DRAM entries read (`StageWork::dram_read`).
    pub sort_read: u64,
    /// Sorting-stage DRAM entries written.
    pub sort_written: u64,
    /// Entries the binning wrote for sorting.
    pub binned_written: u64,
    /// Table entries the raster read.
    pub raster_read: u64,
    /// Table entries written back.
    pub writeback: u64,
    /// Background sorter entries read.
    pub background_read: u64,
    /// Background sorter entries written.
    pub background_written: u64,
}

/// One frame.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct FrameWork {
    /// Frame index.
    pub frame: usize,
    /// A scene cut starts here.
    pub cut: bool,
    /// Every tile was sorted from scratch.
    pub from_scratch: bool,
    /// Gaussians in the scene.
    pub gaussians: u64,
    /// Gaussians with a feature entry.
    pub visible: u64,
    /// Which Gaussians have a feature entry: bit `i % 64` of word `i / 64` for Gaussian `i`.
    /// Empty in a workload made by hand, which stands for ids `0 .. visible`
    /// ([`FrameWork::visible_ids`]).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub visible_set: Vec<u64>,
    /// Candidate tile tests of the duplication (binning) stage.
    pub binning_tests: u64,
    /// Entry-subtile pairs the SCUs processed over pairs routed (early termination), from the
    /// golden raster (all tiles, or a sample, see `raster_sampled`).
    pub processed_ratio: f64,
    /// True when `processed_ratio` comes from a sample of tiles rather than the whole frame.
    pub raster_sampled: bool,
    /// Tile-Gaussian pairs of the CUDA rasterizer's duplication (screen-space bounding rectangle
    /// of radius `3 sigma` over 16-pixel tiles), for the GPU baseline.
    pub gpu_pairs: u64,
    /// Gaussians the CUDA rasterizer keeps (radius > 0 and some tile touched).
    pub gpu_visible: u64,
    /// Golden sums for cross-checks.
    pub golden: GoldenSums,
    /// Image quality (when the golden raster and references ran).
    pub quality: Option<Quality>,
    /// Tiles, row-major.
    pub tiles: Vec<TileWork>,
    /// The golden pipeline's per-tile columns (disorder signals, error against the exact order),
    /// when it ran beside the work-only generation (`None` otherwise).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub golden_tiles: Option<neo_golden::pipeline::stats::TileColumns>,
}

impl FrameWork {
    /// The ids of the Gaussians with a feature entry, ascending ([`FrameWork::visible_set`], or
    /// `0 .. visible` when it is empty).
    pub fn visible_ids(&self) -> impl Iterator<Item = u64> + Clone + '_ {
        let by_hand = if self.visible_set.is_empty() { self.visible } else { 0 };
        (0..by_hand).chain(self.visible_set.iter().enumerate().flat_map(|(w, &bits)| {
            let mut rest = bits;
            std::iter::from_fn(move || {
                (rest != 0).then(|| {
                    let b = rest.trailing_zeros() as u64;
                    rest &= rest - 1;
                    64 * w as u64 + b
                })
            })
        }))
    }
}

/// What the workload is.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct WorkloadInfo {
    /// Scene spec or path.
    pub scene: String,
    /// Trajectory spec.
    pub trajectory: String,
    /// Strategy (`neo`, `periodic:4`, ...).
    pub strategy: String,
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Tile grid.
    pub grid: [u32; 2],
    /// Tile side.
    pub tile: u32,
    /// Subtile side.
    pub subtile: u32,
    /// Chunk size.
    pub chunk: usize,
    /// DPS passes per frame.
    pub dps_passes: usize,
    /// Capacity (`None`: unbounded).
    pub capacity: Option<usize>,
    /// The raster cores' reorder window the tables were blended and written back through (1:
    /// none; left out of the file then, and 1 when absent).
    #[serde(
        default = "neo_golden::raster::window::no_window",
        skip_serializing_if = "neo_golden::raster::window::is_no_window"
    )]
    pub raster_window: usize,
    /// Bytes per sort entry.
    pub sort_entry_bytes: u32,
    /// Bytes per feature entry.
    pub feature_entry_bytes: u32,
    /// The scene's SH degree.
    pub sh_degree: u8,
    /// Bytes of a Gaussian's geometry record in the baked parameter format.
    pub gaussian_geometry_bytes: u32,
    /// Bytes of a Gaussian's SH record in the baked parameter format (by the SH degree).
    pub gaussian_sh_bytes: u32,
    /// Gaussians in the scene.
    pub gaussians: u64,
    /// True when the golden raster ran on every frame (quality and exact termination ratios).
    pub golden_raster: bool,
}

/// A whole workload.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Workload {
    /// Description.
    pub info: WorkloadInfo,
    /// Frames in order.
    pub frames: Vec<FrameWork>,
    /// Wall-clock seconds spent generating it.
    pub generation_s: f64,
}

impl Workload {
    /// Subtiles per tile.
    pub fn subtiles(&self) -> usize {
        let n = (self.info.tile / self.info.subtile.max(1)) as usize;
        n * n
    }

    /// Largest table over all tiles and frames.
    pub fn max_table_len(&self) -> u32 {
        self.frames.iter().flat_map(|f| f.tiles.iter().map(|t| t.table_len.max(t.merge_a))).max().unwrap_or(0)
    }

    /// Largest conventional-sort or hierarchical input over all tiles and frames.
    pub fn max_sort_len(&self) -> u32 {
        self.frames
            .iter()
            .flat_map(|f| f.tiles.iter().map(|t| t.sort_n.max(t.current).max(t.background_n).max(t.merge_b)))
            .max()
            .unwrap_or(0)
    }

    /// Approximate heap bytes held (for reports).
    pub fn heap_bytes(&self) -> usize {
        self.frames
            .iter()
            .map(|f| {
                std::mem::size_of::<FrameWork>()
                    + f.tiles
                        .iter()
                        .map(|t| std::mem::size_of::<TileWork>() + 4 * t.routed.capacity())
                        .sum::<usize>()
            })
            .sum()
    }
}
