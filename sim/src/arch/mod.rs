//! Neo and the GSCore-style baseline on the engine: the address map ([`layout`]), the jobs each
//! engine runs per frame and tile ([`jobs`]), the raster core's timing ([`timing`]) and the
//! scheduler with the real dependencies between them ([`scheduler`]).
//!
//! # Engines and jobs
//! - **Preprocessing** (one agent): per frame, Neo moves what the RTL Preprocessing Engine
//!   moves (golden `engine::pre::pre_transfers`, each transfer the DRAM lines it touches): every
//!   lane's geometry stream, each visible Gaussian's SH record and, on a frame that reuses
//!   tables, its previous feature word (incoming detection); every Gaussian's 32-byte feature
//!   word (zero when culled), the incoming lists in their per-tile slots and the lengths. GSCore
//!   reads every geometry record and the visible Gaussians' SH and writes a compacted feature
//!   table and every pair (with its subtile bitmap). Compute: the slowest of projection, colour
//!   and duplication units (measured timing).
//! - **Sorting** (`sort_cores` agents): per tile, the sorting-core commands of the strategy
//!   ([`crate::sortcmd`]), each a segment timed by `latency.json`: Neo's are golden's tile
//!   commands (`neo_golden::engine::tile_steps`, as the RTL's sequencer issues them): the
//!   conventional sort of the incoming list (from scratch, of the whole list), the DPS passes
//!   and the MSU+ insert/delete merge, the last DPS pass fused with that merge when
//!   `fused_dps_merge`; GSCore's hierarchical sort (an approximate binning pass, then one
//!   on-chip sort per bin).
//! - **Raster** (`raster_cores` agents): per tile, reads the sorted table and gathers the
//!   features, runs the ITU/SCU pipeline over subtile groups, writes the depth keys and valid
//!   bits back (Neo) and the tile's pixels.
//! - **Update** (Neo-S only, on the sorting cores): per tile after its raster, reads the table,
//!   gathers each entry's feature word (its new depth and visibility) and writes the table back
//!   with depths, valid bits and bitmaps: the separate post-processing the paper's Fig. 18 names
//!   for a GSCore with Neo's Sorting Engine but not its Rasterization Engine.
//!
//! # Dependencies
//! - preprocessing of frame `f` after that of `f - 1` and after every raster of frame
//!   `f - frame_buffers` (its feature table and lists are double-buffered);
//! - sorting of tile `(f, t)` after preprocessing of `f`, after the raster of `(f - 2, t)` (tables
//!   are double-buffered) and, when the strategy reuses tables (Neo hardware), after the raster
//!   of `(f - 1, t)`, whose write-back it reads; `background:K` also after the background sort of
//!   the frame whose order it uses;
//! - the raster of `(f, t)` after its sort;
//! - Neo-S: the update pass of `(f, t)` (on a sorting core) after the raster of `(f, t)`, and the
//!   sort of `(f + 1, t)` after that pass instead of after the raster.
//!
//! Ready jobs run in (frame, tile) order on the first idle agent of their engine; background
//! sorts run on idle sorting cores after every ready foreground sort.

mod jobs;
mod layout;
mod scheduler;
mod timing;

use neo_golden::pipeline::Strategy;

use crate::config::{RasterTiming, SimConfig};
use crate::dram::Ps;
use crate::engine::AgentSpec;
use crate::latency::Latency;
use crate::workload::Workload;
use layout::Layout;
use timing::round_ps;

pub use scheduler::{FrameTimes, Sched};
pub use timing::{fit_raster_core, grid_point_cycles, raster_tile_cycles, raster_tile_cycles_in_segments};

/// Agent classes.
pub const CLASS_PRE: u8 = 0;
/// Sorting cores.
pub const CLASS_SORT: u8 = 1;
/// Raster cores.
pub const CLASS_RASTER: u8 = 2;

const K_PRE: u8 = 0;
const K_SORT: u8 = 1;
const K_RASTER: u8 = 2;
const K_BG: u8 = 3;
const K_UPDATE: u8 = 4;

/// Which accelerator.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Accel {
    /// Neo (the workload's strategy on Neo's hardware).
    Neo,
    /// GSCore-style with `cores` sorting cores and `cores` subtile units.
    Gscore {
        /// Core count.
        cores: u32,
    },
    /// Neo-S, the paper's Fig. 18 ablation: GSCore-style with `cores` cores whose sorting engine
    /// is Neo's (the workload's strategy on reused tables), without Neo's Rasterization Engine
    /// (no ITU, no depth write-back), so a separate pass after each tile's raster refreshes
    /// its table's depths, valid bits and bitmaps for the next frame's sort.
    NeoS {
        /// Core count.
        cores: u32,
    },
}

impl Accel {
    /// The bytes of a sort entry as this accelerator stores it: the workload's
    /// `sort_entry_bytes`, with GSCore's subtile bitmap for the GSCore-style architectures.
    pub fn stored_sort_entry_bytes(self, cfg: &SimConfig, sort_entry_bytes: u32) -> u64 {
        match self {
            Accel::Neo => sort_entry_bytes as u64,
            Accel::Gscore { .. } | Accel::NeoS { .. } => (sort_entry_bytes + cfg.gscore.bitmap_bytes) as u64,
        }
    }
}

/// The model of one accelerator on one workload.
pub struct Model<'a> {
    accel: Accel,
    cfg: &'a SimConfig,
    lat: &'a Latency,
    wl: &'a Workload,
    raster: RasterTiming,
    strategy: Strategy,
    /// Sort entry bytes as stored (GSCore: with the bitmap).
    eb: u64,
    fb: u64,
    line: u64,
    cyc: f64,
    layout: Layout,
    sort_cores: u32,
    raster_cores: u32,
    scus_per_core: u32,
    itus_per_core: u32,
    hier: bool,
    shot_start: Vec<usize>,
}

impl<'a> Model<'a> {
    /// The model of `accel` running `wl`.
    pub fn new(accel: Accel, cfg: &'a SimConfig, lat: &'a Latency, wl: &'a Workload) -> Result<Self, String> {
        let strategy: Strategy = wl.info.strategy.parse().map_err(|e: String| e)?;
        let eb = accel.stored_sort_entry_bytes(cfg, wl.info.sort_entry_bytes);
        let (sort_cores, raster_cores, scus_per_core, itus_per_core, hier) = match accel {
            Accel::Neo => (
                cfg.engine.sort_cores as u32,
                cfg.engine.raster_cores as u32,
                cfg.engine.raster_scus as u32,
                cfg.engine.raster_itus as u32,
                strategy == Strategy::Hierarchical,
            ),
            Accel::Gscore { cores } | Accel::NeoS { cores } => (
                cores,
                cores.div_ceil(4).max(1),
                cores.min(4),
                0,
                matches!(accel, Accel::Gscore { .. }) || strategy == Strategy::Hierarchical,
            ),
        };
        if hier && wl.frames.iter().any(|f| f.tiles.iter().any(|t| t.hier.entries != t.current)) {
            return Err(
                "the workload has no hierarchical-sort record (generate it with hierarchical on)".into()
            );
        }
        cfg.check_buffers(eb)?;
        if wl.info.chunk != cfg.engine.chunk {
            return Err(format!(
                "workload chunk {} differs from the configuration's engine.chunk {}",
                wl.info.chunk, cfg.engine.chunk
            ));
        }
        // 0 (a workload built in memory without the field) is no window, as 1.
        if wl.info.raster_window.max(1) != cfg.engine.raster_window {
            return Err(format!(
                "workload raster_window {} differs from the configuration's engine.raster_window {}",
                wl.info.raster_window, cfg.engine.raster_window
            ));
        }
        let line = cfg.dram.line_bytes as u64;
        let fb = cfg.sizes.feature_entry_bytes.unwrap_or(wl.info.feature_entry_bytes) as u64;
        let layout = Layout::new(cfg, wl, eb, fb, sort_cores);
        let mut shot_start = Vec::with_capacity(wl.frames.len());
        let mut s = 0;
        for (i, f) in wl.frames.iter().enumerate() {
            if i == 0 || f.cut {
                s = i;
            }
            shot_start.push(s);
        }
        // The simulated core's feature buffer is half the architecture's raster buffer (the other
        // half double-buffers the prefetch) when that is larger than the measured RTL's
        // (`raster.core.feature_buffer`); the RTL structure of the rest of the raster timing is
        // kept.
        let mut raster = lat.raster_over(&cfg.raster_assumed)?;
        raster.window = cfg.engine.raster_window as u64;
        if raster.feature_buffer > 0 {
            raster.feature_buffer = raster.feature_buffer.max(cfg.neo.raster_buffer_bytes / 2 / fb.max(1));
        }
        Ok(Model {
            accel,
            cfg,
            lat,
            wl,
            raster,
            strategy,
            eb,
            fb,
            line,
            cyc: cfg.cycle_ps(),
            layout,
            sort_cores,
            raster_cores,
            scus_per_core,
            itus_per_core,
            hier,
            shot_start,
        })
    }

    /// The agents: preprocessing, sorting cores, raster cores.
    pub fn agents(&self) -> Vec<AgentSpec> {
        let n = &self.cfg.neo;
        let pre_window = self.lat.preprocess.window(n.preprocess_read_window);
        let mut v = vec![AgentSpec { class: CLASS_PRE, window: pre_window, overlap: false }];
        for _ in 0..self.sort_cores {
            v.push(AgentSpec {
                class: CLASS_SORT,
                window: n.sort_read_window,
                overlap: n.double_buffered_io,
            });
        }
        let rwin = ((n.raster_buffer_bytes / 2 / self.line).max(1) as u32).min(n.raster_read_window);
        for _ in 0..self.raster_cores {
            v.push(AgentSpec { class: CLASS_RASTER, window: rwin, overlap: false });
        }
        v
    }

    /// The scheduler for this model.
    pub fn scheduler(&self) -> Sched<'_, 'a> {
        Sched::new(self)
    }

    /// True when the duplication unit detects incoming Gaussians (reads the previous feature
    /// words unless the frame is from scratch): Neo's hardware running a strategy that reuses
    /// tables (`background:K` included, charged one frame back like the others although its
    /// reused table is frame `f - K`'s); not GSCore (no incoming step), not `full` or
    /// `hierarchical` (every frame from scratch).
    fn detects_incoming(&self) -> bool {
        self.neo_sorting()
            && (self.strategy.reuses_tables() || matches!(self.strategy, Strategy::Background(_)))
    }

    /// True when the sorting engine is Neo's (Neo and Neo-S): the Preprocessing Engine writes
    /// incoming lists in per-tile slots and the sorts follow the workload's strategy.
    fn neo_sorting(&self) -> bool {
        matches!(self.accel, Accel::Neo | Accel::NeoS { .. })
    }

    /// True when the tables are reused and a frame's sort of a tile reads what the frame
    /// before left in it (Neo's raster write-back, or Neo-S's update pass).
    fn reuses(&self) -> bool {
        self.neo_sorting() && !self.hier && self.strategy != Strategy::Full
    }

    fn ps(&self, cycles: f64) -> Ps {
        round_ps(cycles, self.cyc)
    }
}
