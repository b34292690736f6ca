//! When the engine bench declares a frame hung ([`crate::engine::EngineRig::run_frame`]): a
//! watchdog on the AXI4 ports ([`quiet_limit`]) and a per-frame cycle bound from the frame's
//! work ([`frame_cycle_bound`]). Neither may ever fail a correct run; each is measured against
//! the CI cases in docs/rtl.md ("Hang limits of the engine bench").

use crate::axi::AxiTiming;
use neo_gen::EngineConfig;
use neo_golden::engine::host::FramePlan;
use neo_golden::engine::regs::Counter;
use neo_golden::sort::merge_pass_count;

/// How many times the longest legitimate quiet stretch the watchdog allows.
pub const QUIET_MARGIN: u64 = 4;

/// The longest stretch a correct engine of `cfg` may go without a handshake on any AXI4 port,
/// times [`QUIET_MARGIN`]. The longest stretches come from the units that compute on data
/// they hold:
///
/// - a Rasterization Core blending one feature-buffer segment: every SCU takes `subtile^2 /
///   scu_lanes` cycles per (Gaussian, subtile) and has `(tile / subtile)^2 / raster_scus`
///   subtiles, so a segment of `raster_feature_buffer` Gaussians that all cover the tile keeps
///   it busy `raster_feature_buffer * subtiles_per_scu * cycles_per_pair` cycles (16 384 on the
///   default core), and the loader has loaded the next segment long before;
/// - a Sorting Core's chunk: `chunk` entries through `log2(chunk / bsu_width) + 2` passes of
///   its BSU and in-core merges, one entry a cycle;
/// - the list writer's counter clearing at the start and end of preprocessing: one of its
///   `pre_max_tiles` counters a cycle.
pub fn quiet_limit(cfg: &EngineConfig) -> u64 {
    let per_tile = u64::from((cfg.tile / cfg.subtile).pow(2));
    let subtiles_per_scu = per_tile / cfg.raster_scus.max(1) as u64;
    let pair_cycles = (u64::from(cfg.subtile.pow(2)) / cfg.scu_lanes.max(1) as u64).max(1);
    let raster = cfg.raster_feature_buffer as u64 * subtiles_per_scu * pair_cycles;
    let chunk = cfg.chunk as u64;
    let sort = chunk * (merge_pass_count(chunk, cfg.bsu_width.max(1) as u64) + 2);
    let lists = if cfg.has_preprocessing() { cfg.pre_max_tiles as u64 } else { 0 };
    QUIET_MARGIN * raster.max(sort).max(lists)
}

/// A frame's work as golden counts it (its expected counters and registers): what
/// [`frame_cycle_bound`] charges.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FrameWork {
    /// Tiles of the frame.
    pub tiles: u64,
    /// Entries the Sorting Cores sort (`ENTRIES_SORTED`).
    pub sorted: u64,
    /// Entries the Rasterization Cores raster (`ENTRIES_RASTERED`).
    pub rastered: u64,
    /// Merge passes of the longest sorted tile (its conventional sort, the frame's most DPS
    /// passes and MERGE_DELETE).
    pub passes: u64,
    /// 8-byte beats over all AXI4 ports (every byte counter, reads and writes).
    pub beats: u64,
    /// Gaussians the Preprocessing Engine processes (0 in lists mode).
    pub gaussians: u64,
}

impl FrameWork {
    /// The work of `plan` on an engine of `cfg`.
    pub fn of(cfg: &EngineConfig, plan: &FramePlan) -> FrameWork {
        let c = &plan.expected.outcome.counters;
        let bytes: u64 = Counter::ALL.iter().filter(|k| k.counts_bytes()).map(|&k| c.get(k)).sum();
        let chunk = cfg.chunk.max(1) as u64;
        let longest =
            plan.expected.descriptors.iter().map(|d| u64::from(d.list_len) + u64::from(d.prev_len)).max();
        // The conventional sort's stages, the most DPS passes of a tile (at least one) and the
        // MERGE_DELETE.
        let dps = plan.expected.descriptors.iter().map(|d| d.passes()).max().unwrap_or(0).max(1);
        let passes = 1 + merge_pass_count(longest.unwrap_or(0), chunk) + dps + 1;
        FrameWork {
            tiles: u64::from(plan.regs.tiles),
            sorted: c.get(Counter::EntriesSorted),
            rastered: c.get(Counter::EntriesRastered),
            passes,
            beats: bytes.div_ceil(8),
            gaussians: if plan.regs.pre.enabled() { u64::from(plan.regs.pre.gaussians) } else { 0 },
        }
    }
}

/// How many times the work estimate a frame may take.
pub const FRAME_MARGIN: u64 = 4;

/// Cycles per tile the estimate charges besides its entries: a Rasterization Core's empty
/// table (533 cycles: 512 pixel-row writes and the setup, docs/raster-timing.md), the
/// descriptor read, the result write and the sort sequencer's setup, rounded up.
pub const TILE_CYCLES: u64 = 2048;

/// Cycles per rastered entry the estimate charges: the loads (2 a table entry) and the
/// blending of a Gaussian that covers a quarter of its tile's subtiles on the busiest SCU
/// (4 cycles per subtile, 16 subtiles per SCU).
pub const RASTER_ENTRY_CYCLES: u64 = 18;

/// Cycles per Gaussian the estimate charges the Preprocessing Engine besides its memory
/// beats (one lane's pipeline issue and the list writer's hits).
pub const PRE_GAUSSIAN_CYCLES: u64 = 4;

/// Round trips per tile the estimate charges beyond its merge passes (the descriptor read,
/// the result write, the raster core's loads and its last writes).
pub const TILE_ROUND_TRIPS: u64 = 4;

/// The work estimate of `w` on an engine of `cfg` behind a memory of `timing`, in cycles,
/// charged as if nothing ran in parallel (no credit for the cores, the ports or the overlap of
/// the stages, so more cores or ports only make it looser): every tile's fixed cost and a
/// memory round trip (latency plus the longest extra delay) per merge pass and per
/// [`TILE_ROUND_TRIPS`], every sorted entry once per merge pass of the longest tile, every
/// rastered entry, every Gaussian, and every memory beat on one port at its mean rate
/// (`bandwidth`, `ready_percent`) plus a round trip per 4 beats shared by the
/// `axi_outstanding` transactions a client keeps in flight.
pub fn work_estimate(cfg: &EngineConfig, w: &FrameWork, timing: &AxiTiming) -> u64 {
    let (num, den) = timing.bandwidth;
    let ready = u64::from(timing.ready_percent.clamp(1, 100));
    // Cycles per 100 beats, rounded up: 100 den / num / (ready / 100).
    let beat_x100 = (100 * 100 * u64::from(den.max(1))).div_ceil(u64::from(num.max(1)) * ready);
    let round_trip = u64::from(timing.latency) + u64::from(timing.extra_max);
    let memory = (w.beats * beat_x100).div_ceil(100)
        + (w.beats.div_ceil(4) * round_trip).div_ceil(cfg.axi_outstanding.max(1) as u64);
    w.tiles * (TILE_CYCLES + (w.passes + TILE_ROUND_TRIPS) * round_trip)
        + w.sorted * w.passes
        + w.rastered * RASTER_ENTRY_CYCLES
        + w.gaussians * PRE_GAUSSIAN_CYCLES
        + memory
}

/// The cycles frame `plan` may take on an engine of `cfg` behind a memory of `timing`:
/// [`FRAME_MARGIN`] times its [`work_estimate`], plus the watchdog's [`quiet_limit`] (a frame
/// of no work still gets the longest quiet stretch).
pub fn frame_cycle_bound(cfg: &EngineConfig, plan: &FramePlan, timing: &AxiTiming) -> u64 {
    FRAME_MARGIN * work_estimate(cfg, &FrameWork::of(cfg, plan), timing) + quiet_limit(cfg)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_default_engines_quiet_limit_is_four_raster_segments() {
        // 256 Gaussians x 16 subtiles per SCU x 4 cycles per pair, times 4.
        assert_eq!(quiet_limit(&EngineConfig::default()), 4 * 16_384);
        let big_buffer = EngineConfig { raster_feature_buffer: 1024, ..EngineConfig::default() };
        assert_eq!(quiet_limit(&big_buffer), 4 * 65_536);
    }

    #[test]
    fn the_estimate_grows_with_every_kind_of_work_and_a_slower_memory() {
        let cfg = EngineConfig::default();
        let w = FrameWork { tiles: 4, sorted: 1000, rastered: 900, passes: 3, beats: 8000, gaussians: 0 };
        let ideal = work_estimate(&cfg, &w, &AxiTiming::IDEAL);
        // IDEAL: one cycle a beat, a round trip of 1 cycle per 4 beats over 8 in flight.
        let tiles = 4 * (TILE_CYCLES + 3 + TILE_ROUND_TRIPS);
        assert_eq!(ideal, tiles + 3000 + 900 * RASTER_ENTRY_CYCLES + 8000 + 250);
        assert!(work_estimate(&cfg, &w, &AxiTiming::RANDOM) > ideal);
        let slow = AxiTiming { latency: 100, ..AxiTiming::IDEAL };
        assert!(work_estimate(&cfg, &w, &slow) > ideal);
        for more in [
            FrameWork { tiles: 5, ..w },
            FrameWork { sorted: 1001, ..w },
            FrameWork { rastered: 901, ..w },
            FrameWork { passes: 4, ..w },
            FrameWork { beats: 8004, ..w },
            FrameWork { gaussians: 1, ..w },
        ] {
            assert!(work_estimate(&cfg, &more, &AxiTiming::IDEAL) > ideal, "{more:?}");
        }
    }
}
