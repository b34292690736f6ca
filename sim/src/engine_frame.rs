//! The cycle model of one `neo_engine` frame, as the RTL top is built: the frame controller's
//! descriptor reads and tile scheduler, each Sorting Core's per-tile command plan with its stage
//! barriers, and the raster cores, over AXI4 ports of a given memory timing.
//!
//! Inputs: the golden reference's per-tile work ([`FrameTrace`]: every tile's command plan and
//! raster work, from `neo_golden::engine::execute_frame_traced`), the unit timing measured on
//! the RTL ([`Latency`], `reports/latency.json`) and the memory's timing ([`PortTiming`]).
//! The model adds time only; the algorithm is golden's.
//!
//! # Timing
//! - **Memory.** A request's first beat comes `latency` cycles after the request leaves the
//!   client, plus the AXI path's register stages ([`AXI_PATH_CYCLES`]); a port moves
//!   `bandwidth` beats (8 bytes) per cycle per direction (client `c` on port `c mod K`). The
//!   unit timing of `latency.json` was measured with the first beat one cycle after the
//!   request (`memory.read_latency`); the model adds the difference once per dependent round
//!   trip.
//! - **Sorting.** A stage's commands run back to back ([`crate::sortcmd::batch_cycles`]: the
//!   first command's latency, then the measured intervals), or at the port's pace; the stage
//!   ends with the barrier: the last write's response ([`EngineFrameModel::sort_cycles`]).
//! - **Raster.** [`raster_tile_cycles`](crate::arch::raster_tile_cycles) with the engine's load rate: a table entry is one beat
//!   and its feature word `FEATURE_BYTES / 8` beats on the port; the pixels `tile^2 * 4 / 8`
//!   write beats, the write-back one beat per entry.
//! - **Sharing a port.** The jobs of one port (a sort's stages, a raster) are played together
//!   as fluids from their start times ([`crate::port_share`]): the channels divided by their
//!   beats in flight, a raster's reads slowed by the others' (they wait behind them).
//! - **Preprocessing** (scene mode, [`EngineFrameModel::predict_frame`]): the Preprocessing
//!   Engine's phase comes before the tile walk ([`EngineFrameModel::pre_cycles`]: its busiest
//!   port's traffic, charged client by client).
//! - **Planned frames** (`ADAPT_CTRL`, golden `engine::adapt`): the frame controller first reads
//!   every tile's previous result (one 2-beat read at a time, [`EngineFrameModel::scan_cycles`]),
//!   then reads each again after its descriptor.
//! - **Scheduling.** Tiles in index order; a descriptor read (4 beats) per tile into a
//!   one-descriptor buffer; `first_free` (the lowest-numbered free core) or `round_robin`; a
//!   tile's raster after its sort, the completion queue taking the lowest sequencer's first;
//!   the frame ends with the last raster and its writes' responses.

use neo_golden::engine::memory::{DPS_PASSES_BITS, ENTRY_BYTES, FEATURE_BYTES, PIXEL_BYTES};
use neo_golden::engine::pre::{beats_spanned, pre_transfers, PrePart, PreRecords, PreWork};
use neo_golden::engine::{
    execute_frame_traced, EngineConfig, FrameError, FrameRegs, FrameTrace, Memory, MemoryClient,
    SchedulerPolicy, TileTrace, BRIDGE_W_SLOTS, COMPLETION_QUEUE_DEPTH, MUX_W_FIFO_DEPTH,
};
use neo_golden::sort::SortMode;

use crate::arch::raster_tile_cycles_in_segments;
use crate::latency::Latency;
use crate::port_share::{self, FluidJob, FluidPhase};
use crate::pre_writers::{pre_writer_cycles, WriterLoad};
use crate::sortcmd::{batch_cycles, Cmd};

/// Bytes of one AXI beat (the engine's data width, 64 bits).
const BEAT_BYTES: u64 = 8;

/// Read beats of one raster entry: its table entry and its feature word.
const RASTER_ENTRY_BEATS: u64 = (ENTRY_BYTES + FEATURE_BYTES).div_ceil(BEAT_BYTES);

/// Register stages of the AXI path between a core and the memory, both ways (bridge and port
/// mux), beyond the unit benches' direct memory port.
pub const AXI_PATH_CYCLES: f64 = 4.0;

/// Cycles from the memory's B to a free write slot of the writer: the port mux passes B
/// unregistered (`neo_axi_mux`) and the bridge's count (`wr_cnt_q`) falls at the next edge.
/// (Until 2026-12-06 the B path was charged [`AXI_PATH_CYCLES`]: the single-write rate on the
/// random memory came out 0.29, against the 0.315 the RTL's merges wrote.)
pub const B_PATH_CYCLES: f64 = 1.0;

/// The memory's timing on every AXI port.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PortTiming {
    /// Cycles from a request to its first response beat (the harness's `latency`).
    pub latency: f64,
    /// Beats per cycle per port and direction: each channel (R, W) earns `bandwidth` beats of
    /// credit a cycle, up to two beats, and moves a beat only when it holds a whole one.
    pub bandwidth: f64,
    /// Fraction of cycles the port accepts a request (AR, AW) or a write beat (drawn each
    /// cycle; a W beat needs the credit too).
    pub ready: f64,
    /// Fraction of the responses that come later than the others, by a uniform `1..=late_max`
    /// cycles (`latency` is the mean over all of them). Responses of one ID stay in order, so a
    /// late write response holds back the ones behind it.
    pub late_share: f64,
    /// The longest extra delay of a late response (cycles).
    pub late_max: f64,
}

impl PortTiming {
    /// One-cycle latency, one beat per cycle.
    pub const IDEAL: PortTiming =
        PortTiming { latency: 1.0, bandwidth: 1.0, ready: 1.0, late_share: 0.0, late_max: 0.0 };

    /// W beats per cycle a port takes while a write is always offered: the chance that a cycle
    /// finds a whole beat of credit, times `ready`. The credit is a Markov chain over its
    /// level in units of `1 / d` (`bandwidth = n / d`, the smallest `d` up to 256, else the
    /// nearest 256th), solved for its stationary distribution (by iterating the lazy chain,
    /// which has the same one and no period). Neither `min(bandwidth, ready)` nor their
    /// product: at 3/4 and 60% it is 0.577 (the product, 0.45, charged the writes of the
    /// harness's random memory 28% too many cycles).
    pub fn write_rate(&self) -> f64 {
        let (n, d) = rational(self.bandwidth.min(1.0));
        let cap = 2 * d;
        let p = self.ready.clamp(0.0, 1.0);
        let earned = |c: usize| (c + n).min(cap);
        let mut dist = vec![0.0f64; cap + 1];
        dist[0] = 1.0;
        for _ in 0..1_000_000 {
            let mut next: Vec<f64> = dist.iter().map(|w| w / 2.0).collect();
            for (c, &w) in dist.iter().enumerate() {
                let e = earned(c);
                if e >= d {
                    next[e - d] += w * p / 2.0;
                    next[e] += w * (1.0 - p) / 2.0;
                } else {
                    next[e] += w / 2.0;
                }
            }
            let moved: f64 = dist.iter().zip(&next).map(|(a, b)| (a - b).abs()).sum();
            dist = next;
            if moved < 1e-14 {
                break;
            }
        }
        dist.iter().enumerate().filter(|&(c, _)| earned(c) >= d).map(|(_, w)| w * p).sum()
    }

    /// Single-beat writes per cycle through a bridge, its port mux and the port, while a core
    /// offers one every cycle (a sort's output entries, a raster core's write-back), played
    /// cycle by cycle for [`WRITE_PLAY_CYCLES`] (after a warm-up) with fixed random draws. Structure read off
    /// the RTL: the bridge takes a write when its AW register is free (or its AW leaves) and
    /// one of its [`BRIDGE_W_SLOTS`] W registers is, with fewer than `outstanding` writes
    /// awaiting their B; the mux passes an AW while its W-order FIFO
    /// ([`MUX_W_FIFO_DEPTH`]) has room and forwards the head's W; the memory takes an AW on
    /// `ready` of its cycles and a W only for an AW it took, with the credit of
    /// [`Self::write_rate`]; a B frees the bridge's count [`B_PATH_CYCLES`] after the
    /// memory's `latency` (later by `1..=late_max` for `late_share` of them), and never before
    /// the B of the write ahead of it (one ID). On the ideal memory it is 1; on the harness's
    /// random one 0.47 with every B on time and 0.32 with its late ones in order (the bridge's
    /// writes in flight wait behind a late B; the RTL's merges wrote 0.315 a cycle there).
    pub fn single_write_rate(&self, outstanding: usize) -> f64 {
        let (n, d) = self.credit();
        let mut draws = XorShift(0x2545_F491_4F6C_DD1D);
        let b_delay = self.b_delay();
        let mut last_due = 0u64;
        let (mut aw_v, mut w_slots, mut in_flight) = (false, 0u32, 0usize);
        let (mut mem_aw, mut w_fifo, mut credit) = (0u64, 0u32, 0u64);
        let (mut aw_ready, mut w_ready) = (draws.ready(self.ready), false);
        let mut b_due = std::collections::VecDeque::new();
        let mut writes = 0u64;
        for t in 0..WRITE_PLAY_CYCLES {
            while b_due.front().is_some_and(|&due| due <= t) {
                b_due.pop_front();
                in_flight -= 1;
            }
            let aw_fire = aw_v && w_fifo < MUX_W_FIFO_DEPTH && aw_ready;
            let w_fire = w_slots > 0 && w_fifo > 0 && w_ready;
            let take = (!aw_v || aw_fire) && (w_slots < BRIDGE_W_SLOTS || w_fire) && in_flight < outstanding;
            if w_fire {
                w_slots -= 1;
                w_fifo -= 1;
                mem_aw -= 1;
                credit -= d;
                writes += u64::from(t >= WRITE_PLAY_WARM_UP);
                let late = self.late_delay(&mut draws);
                // One ID: a B never overtakes the one before it.
                last_due = last_due.max(t + b_delay + late);
                b_due.push_back(last_due);
            }
            if aw_fire {
                aw_v = false;
                mem_aw += 1;
                w_fifo += 1;
            }
            if take {
                aw_v = true;
                w_slots += 1;
                in_flight += 1;
            }
            credit = (credit + n).min(2 * d);
            aw_ready = draws.ready(self.ready);
            w_ready = mem_aw > 0 && credit >= d && draws.ready(self.ready);
        }
        writes as f64 / (WRITE_PLAY_CYCLES - WRITE_PLAY_WARM_UP) as f64
    }

    /// The channels' credit as `(n, d)`: `n / d` beats earned a cycle (`bandwidth`, at most 1;
    /// [`rational`]), a beat costing `d`, at most `2 d` held.
    pub(crate) fn credit(&self) -> (u64, u64) {
        let (n, d) = rational(self.bandwidth.min(1.0));
        (n as u64, d as u64)
    }

    /// Cycles from a write's last beat until its B frees the writer's count, when it is on
    /// time: `latency` less the late responses' share of the mean, plus [`B_PATH_CYCLES`].
    pub(crate) fn b_delay(&self) -> u64 {
        let late_mean = self.late_share * (self.late_max + 1.0) / 2.0;
        ((self.latency - late_mean).round().max(1.0) + B_PATH_CYCLES) as u64
    }

    /// A response's extra delay, drawn: `1..=late_max` cycles for `late_share` of them, else 0.
    pub(crate) fn late_delay(&self, draws: &mut XorShift) -> u64 {
        if self.late_share > 0.0 && draws.unit() < self.late_share {
            1 + (draws.unit() * self.late_max.max(1.0)) as u64
        } else {
            0
        }
    }
}

/// Cycles [`PortTiming::single_write_rate`] plays, and the first of them it does not count.
const WRITE_PLAY_CYCLES: u64 = 200_000;
const WRITE_PLAY_WARM_UP: u64 = 1_000;

/// A xorshift64 generator: the fixed draws of [`PortTiming::single_write_rate`], of
/// [`crate::pre_writers`] and of their tests.
pub(crate) struct XorShift(pub(crate) u64);

impl XorShift {
    /// A draw that is true on a share `p` of them (always when `p >= 1`, drawing nothing).
    pub(crate) fn ready(&mut self, p: f64) -> bool {
        p >= 1.0 || self.unit() < p
    }

    /// A draw in `[0, 1)`.
    pub(crate) fn unit(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// `x` (in `(0, 1]`) as `n / d`: the smallest `d <= 256` that gives it within `1e-9`, else the
/// nearest `n / 256`.
pub(crate) fn rational(x: f64) -> (usize, usize) {
    (1..=256usize)
        .find_map(|d| {
            let n = (x * d as f64).round();
            ((x * d as f64 - n).abs() < 1e-9 && n >= 1.0).then_some((n as usize, d))
        })
        .unwrap_or_else(|| (((x * 256.0).round() as usize).max(1), 256))
}

/// The model's prediction of one frame.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FramePrediction {
    /// Cycles from start to done.
    pub cycles: f64,
    /// Cycles with any sorting core busy.
    pub sort_busy: f64,
    /// Cycles with any raster core busy.
    pub raster_busy: f64,
    /// Cycles of the Preprocessing Engine's phase before the tile walk (0 when it does not run;
    /// [`EngineFrameModel::pre_cycles`]); part of `cycles`.
    pub pre_busy: f64,
    /// Cycles of the frame controller's scan of the previous results (0 unless it plans the
    /// passes, [`EngineFrameModel::scan_cycles`]); part of `cycles`.
    pub scan: f64,
    /// Every tile's DPS passes in golden's reference (the descriptors', or the engine's own
    /// plan: [`FrameTrace::planned`]).
    pub dps_passes: Vec<usize>,
    /// Whether each tile's DPS passes use the wide chunk.
    pub dps_wide: Vec<bool>,
}

/// The engine-level model for one configuration, unit timing and memory timing.
pub struct EngineFrameModel<'a> {
    cfg: &'a EngineConfig,
    lat: &'a Latency,
    mem: PortTiming,
    /// [`PortTiming::write_rate`] of `mem`: W beats of bursts.
    write_rate: f64,
    /// [`PortTiming::single_write_rate`] of `mem`: single-beat writes.
    single_write_rate: f64,
}

impl<'a> EngineFrameModel<'a> {
    /// The model of `cfg` with the unit timing `lat`, over ports of timing `mem`. Refuses unit
    /// timing measured on cores of another configuration (the engine's counts may differ: they
    /// do not change a core's timing; the Preprocessing Engine's lane count is one of them, the
    /// frame model covers the tile walk). The wide DPS chunk may differ too
    /// ([`Latency::check_engine`]): a wide chunk of `n > C` entries is timed as any chunk between
    /// measured points ([`Latency::chunk_cycles`]: the MSU+ passes of `n` entries at the measured
    /// rate plus the measured remainder, extrapolated from the largest points).
    pub fn new(cfg: &'a EngineConfig, lat: &'a Latency, mem: PortTiming) -> Result<Self, String> {
        cfg.validate().map_err(|e| e.to_string())?;
        let same_cores = EngineConfig {
            sort_cores: lat.config.sort_cores,
            raster_cores: lat.config.raster_cores,
            mem_channels: lat.config.mem_channels,
            scheduler: lat.config.scheduler,
            table_capacity: lat.config.table_capacity,
            axi_id_bits: lat.config.axi_id_bits,
            pre_units: lat.config.pre_units,
            ..cfg.clone()
        };
        lat.check_engine(&same_cores).map_err(|e| e.to_string())?;
        if !(mem.bandwidth > 0.0 && mem.ready > 0.0 && mem.latency >= 0.0) {
            return Err(format!(
                "memory timing {mem:?}: bandwidth and ready must be positive, latency not negative"
            ));
        }
        let (write_rate, single_write_rate) = (mem.write_rate(), mem.single_write_rate(cfg.axi_outstanding));
        Ok(EngineFrameModel { cfg, lat, mem, write_rate, single_write_rate })
    }

    /// Extra cycles of one dependent round trip over the unit benches' memory.
    fn round_trip(&self) -> f64 {
        self.mem.latency + AXI_PATH_CYCLES - 1.0
    }

    /// Cycles of `beats` write beats in bursts through a port ([`PortTiming::write_rate`]).
    fn write_beats(&self, beats: u64) -> f64 {
        beats as f64 / self.write_rate
    }

    /// Cycles of `n` single-beat writes through a bridge and its port
    /// ([`PortTiming::single_write_rate`]).
    fn single_writes(&self, n: u64) -> f64 {
        n as f64 / self.single_write_rate
    }

    /// Cycles of `beats` read beats through a port (bandwidth-limited).
    fn beats(&self, beats: u64) -> f64 {
        beats as f64 / self.mem.bandwidth
    }

    /// Cycles of one tile's sort alone on its port, stage by stage ([`Self::sort_job`]).
    pub fn sort_cycles(&self, t: &TileTrace) -> f64 {
        self.sort_job(t).phases.iter().map(|p| p.alone).sum()
    }

    /// A tile's sort as a job on its core's port, one phase per stage. A stage alone costs
    /// the longer of its commands back to back ([`batch_cycles`]: the measured latency of the
    /// first command, then the measured intervals, with the unit bench's one write and one
    /// read a cycle) and its port traffic (its outputs at [`Self::single_writes`], or its inputs
    /// at the port's bandwidth: a merge streams, its writes overlap the core's pace), then the
    /// barrier (the last write's response). A chunk command (SORT, DPS) writes its chunk during
    /// its last merge pass, a write a cycle on the unit bench, so a slower write path lengthens
    /// each chunk by its writes' extra cycles (on the random memory a 256-entry chunk took
    /// 1 600 cycles in the RTL, where the longer of batch and writes gave 1 053). Its demands:
    /// the stage's read beats and write beats (at [`PortTiming::write_rate`]) over its cycles.
    /// Reads in bursts of `burst` entries, `max_outstanding` of them in flight; writes single.
    fn sort_job(&self, t: &TileTrace) -> FluidJob {
        let phases = (0..t.plan.stages.len())
            .map(|s| {
                let cmds: Vec<Cmd> = t.plan.stages[s].iter().map(Cmd::from).collect();
                let (read, written) = stage_entries(t, s);
                let batch = batch_cycles(&cmds, self.lat) as f64;
                let (reads, writes) = (self.beats(read), self.single_writes(written));
                let core = if cmds.iter().all(Cmd::is_chunk) {
                    batch + (writes - written as f64).max(0.0)
                } else {
                    batch
                };
                let alone = core.max(writes).max(reads) + self.round_trip();
                FluidPhase { alone, read: reads / alone, write: self.write_beats(written) / alone }
            })
            .collect();
        let burst = self.cfg.burst as f64;
        FluidJob {
            phases,
            read_weight: burst * self.cfg.max_outstanding as f64,
            write_weight: 1.0,
            latency_bound: false,
        }
    }

    /// Write beats of a tile's pixels.
    fn pixel_beats(&self) -> u64 {
        (self.cfg.tile * self.cfg.tile) as u64 * PIXEL_BYTES / BEAT_BYTES
    }

    /// Cycles of one tile's raster.
    pub fn raster_cycles(&self, t: &TileTrace) -> f64 {
        let r = &t.raster;
        let routed: Vec<u32> = r.subtiles.iter().map(|s| s.routed).collect();
        let all: u64 = r.subtiles.iter().map(|s| s.routed as u64).sum();
        let done: u64 = r.subtiles.iter().map(|s| s.processed as u64).sum();
        let ratio = if all == 0 { 1.0 } else { done as f64 / all as f64 };
        let mut rt = self.lat.raster.clone();
        // Per entry: its table beat and its feature word's beats on the R channel (or the unit's
        // load cycles, if longer); its write-back takes the core's one request port, stopping the
        // loads while it lasts. The pixels leave in bursts.
        rt.load_cycles_per_entry = rt.load_cycles_per_entry.max(self.beats(RASTER_ENTRY_BEATS));
        rt.write_back_cycles_per_entry = rt.write_back_cycles_per_entry.max(self.single_writes(1));
        // A segment's write-back stops the read requests (the core's one request port), but it
        // begins as the next segment's loads begin, with their table bursts: the bridge's
        // `axi_outstanding` bursts of `burst` entries in flight still arrive while it lasts. A
        // core with a reorder window issues the next segment's table bursts right after this
        // segment's last feature read instead (`neo_raster_window_loader`): none are in flight
        // by the write-back, which then stops the loads outright.
        let bursts = (rt.feature_buffer.max(1) as f64 / self.cfg.burst as f64).ceil();
        let in_flight = bursts.min(self.cfg.axi_outstanding as f64) * self.cfg.burst as f64;
        rt.write_back_overlap = if self.cfg.raster_window > 1 { 0.0 } else { self.beats(1) * in_flight };
        rt.pixel_write_cycles = rt.pixel_write_cycles.max(self.write_beats(self.pixel_beats()).ceil() as u64);
        rt.window = self.cfg.raster_window as u64;
        let writes = self.raster_writes(t);
        let (cycles, _) = raster_tile_cycles_in_segments(
            &routed,
            ratio,
            r.present as u32,
            r.len as u32,
            &rt,
            self.cfg.raster_itus as u32,
            self.cfg.raster_scus as u32,
            true,
            Some(&r.segments),
        );
        cycles.max(writes) + 2.0 * self.round_trip()
    }

    /// Cycles of a tile's raster writes on its port: the write-back one entry each
    /// ([`Self::single_writes`]), the pixels in bursts.
    fn raster_writes(&self, t: &TileTrace) -> f64 {
        self.single_writes(t.raster.len) + self.write_beats(self.pixel_beats())
    }

    /// A tile's raster as a job on its core's port, one phase: the table in bursts and a
    /// 4-beat burst per feature word, `axi_outstanding` bursts in flight, its reads bound by
    /// them ([`FluidJob::latency_bound`]); the write-back one beat an entry and the pixels in
    /// rows of `S / 2` beats.
    fn raster_job(&self, t: &TileTrace) -> FluidJob {
        let len = t.raster.len as f64;
        let row_beats = (self.cfg.subtile as u64 * PIXEL_BYTES / BEAT_BYTES) as f64;
        let pixels = self.pixel_beats() as f64;
        let read = RASTER_ENTRY_BEATS as f64 * len;
        let read_bursts = len + len / self.cfg.burst as f64;
        let read_burst = if len > 0.0 { read / read_bursts } else { 1.0 };
        let alone = self.raster_cycles(t);
        let demand = |cycles: f64| if alone > 0.0 { cycles / alone } else { 0.0 };
        FluidJob {
            phases: vec![FluidPhase {
                alone,
                read: demand(self.beats(RASTER_ENTRY_BEATS * t.raster.len)),
                write: demand(self.write_beats(t.raster.len + self.pixel_beats())),
            }],
            read_weight: read_burst * self.cfg.axi_outstanding as f64,
            write_weight: (len + pixels) / (len + pixels / row_beats),
            latency_bound: true,
        }
    }

    /// [`Self::predict`] for the frame of `regs` whose inputs are in `mem` (before the engine
    /// runs it): golden's reference runs the frame on a copy of the memory for its trace. A
    /// frame that runs the Preprocessing Engine gets its phase ([`Self::pre_cycles`]) added.
    pub fn predict_frame(&self, regs: &FrameRegs, mem: &Memory) -> Result<FramePrediction, FrameError> {
        let mut copy = mem.clone();
        let (_, trace) = execute_frame_traced(self.cfg, regs, &mut copy)?;
        let mut p = self.predict(&trace);
        if let Some(pre) = &trace.pre {
            p.pre_busy = self.pre_cycles(regs, pre);
            p.cycles += p.pre_busy;
        }
        if trace.planned {
            p.scan = self.scan_cycles(trace.tiles.len());
            p.cycles += p.scan;
        }
        p.dps_passes = trace.tiles.iter().map(|t| t.plan.dps_passes()).collect();
        p.dps_wide = trace.tiles.iter().map(|t| t.plan.wide && t.plan.dps_passes() > 0).collect();
        Ok(p)
    }

    /// Cycles of the Preprocessing Engine's phase (the tile walk starts at its `done`): the
    /// busiest port's traffic, the lanes' own pace, the slowest client's read window or fetch
    /// assembly, or the busiest port's burst writers, then the pipeline fill and the lists'
    /// flush.
    ///
    /// - **Ports.** Every transfer of golden `pre_transfers` (geometry streams, one SH record
    ///   and previous word per visible Gaussian, feature words, list lines, lengths) is charged
    ///   to the client that makes it (lane `p`'s geometry port or SH port, by the Gaussian's
    ///   lane; the list writer), its beats ([`beats_spanned`]) to that client's port: a port's
    ///   phase lasts its read beats at `bandwidth` or its write beats at
    ///   [`PortTiming::write_rate`], whichever is longer (the lanes keep both channels busy).
    /// - **Lanes.** A lane takes one Gaussian a cycle at most (the units' measured II).
    /// - **Window.** A client's reads move at most its fetch unit's window
    ///   ([`EngineConfig::pre_window_beats`]) per round trip.
    /// - **Assembly.** A fetch unit assembles at most a beat a cycle and loads each command in a
    ///   cycle of its own (`neo_pre_fetch`: a command is taken only when the previous one is
    ///   done): a client's reads take their beats plus one cycle per read transfer (one command
    ///   each: a lane's geometry stream, every visible Gaussian's SH record and previous word).
    ///   On a reuse frame of small records behind a fast memory this bounds the phase: biker's
    ///   SH port, `(1 + 4) + (1 + 2)` = 8 cycles per Gaussian.
    /// - **Writers.** The feature writers and the list writer hold one transfer in flight each
    ///   (AW, then its W beats, before the next), so a port's writes take the cycles
    ///   [`pre_writer_cycles`] plays for them: behind the ideal memory a feature word takes 6
    ///   cycles, not 4 beats, and every list line on the same port adds 6 more. This bounds a
    ///   frame from scratch of small records (biker's: 7.1 cycles per Gaussian).
    /// - **Fill and flush.** The projection and colour units' measured latencies, a round trip
    ///   for the first read and one for the last write's response; then each tile's length (a
    ///   single write) after the lanes are done.
    pub fn pre_cycles(&self, regs: &FrameRegs, pre: &PreWork) -> f64 {
        let cfg = self.cfg;
        let p = &regs.pre;
        let lane_of = |id: u64| cfg.pre_lane_of(p.gaussians, id);
        let records = PreRecords::engine(p.sh_degree as u8, p.sh_precision());
        let id = |addr: u64, base: u64, bytes: u64| (addr - base) / bytes.max(1);
        let mut client_reads = vec![0u64; cfg.memory_clients()];
        let mut client_commands = vec![0u64; cfg.memory_clients()];
        let mut port_beats = vec![[0u64; 2]; cfg.mem_channels];
        let mut writes = vec![(0u64, 0u64); cfg.memory_clients()];
        let lens = pre.lists.iter().map(Vec::len);
        pre_transfers(cfg, regs, pre.visible.iter().copied(), lens, |t| {
            let client = match t.part {
                PrePart::Geometry => {
                    MemoryClient::PreGeometry(lane_of(id(t.addr, p.geo_base, records.geometry)))
                }
                PrePart::Feature => {
                    MemoryClient::PreGeometry(lane_of(id(t.addr, regs.feat_base, records.feature)))
                }
                PrePart::Sh => MemoryClient::PreSh(lane_of(id(t.addr, p.sh_base, records.sh))),
                PrePart::PrevFeature => {
                    MemoryClient::PreSh(lane_of(id(t.addr, p.prev_feat_base, records.feature)))
                }
                PrePart::ListLine | PrePart::ListLen => MemoryClient::PreListWriter,
            };
            let beats = beats_spanned(t.addr, t.bytes, BEAT_BYTES);
            port_beats[cfg.client_port(client)][t.part.is_write() as usize] += beats;
            if !t.part.is_write() {
                client_reads[cfg.client_index(client)] += beats;
                client_commands[cfg.client_index(client)] += 1;
            } else if t.part != PrePart::ListLen {
                let w = &mut writes[cfg.client_index(client)];
                *w = (w.0 + 1, w.1 + beats);
            }
        });
        let writers = self.pre_writers(&writes);
        let port =
            port_beats.iter().map(|&[r, w]| self.beats(r).max(self.write_beats(w))).fold(0.0, f64::max);
        let ii = |u: Option<(f64, u64)>| u.map_or(1.0, |(ii, _)| ii);
        let pre_lat = &self.lat.preprocess;
        let pace = ii(pre_lat.projection).max(ii(pre_lat.color));
        let lanes = (0..cfg.pre_units).map(|l| cfg.pre_lane_range(p.gaussians, l).1).max().unwrap_or(0);
        let window = cfg.pre_window_beats().max(1) as f64;
        let windowed =
            client_reads.iter().map(|&r| r as f64 * self.round_trip() / window).fold(0.0, f64::max);
        let fill = [pre_lat.projection, pre_lat.color].iter().map(|u| u.map_or(0, |(_, l)| l)).sum::<u64>()
            as f64
            + 2.0 * self.round_trip();
        let flush = self.single_writes(pre.lists.len() as u64);
        let assembly =
            client_reads.iter().zip(&client_commands).map(|(r, c)| r + c).max().unwrap_or(0) as f64;
        port.max(f64::from(lanes) * pace).max(windowed).max(assembly).max(writers) + fill + flush
    }

    /// The busiest port's burst writers ([`pre_writer_cycles`]): each memory client's
    /// `(transfers, beats)` in `writes`; the list writer may have `pre_outstanding` writes
    /// awaiting their B, a lane's feature writer `axi_outstanding`.
    fn pre_writers(&self, writes: &[(u64, u64)]) -> f64 {
        let cfg = self.cfg;
        let list = cfg.client_index(MemoryClient::PreListWriter);
        (0..cfg.mem_channels)
            .map(|port| {
                let loads: Vec<WriterLoad> = (0..writes.len())
                    .filter(|&c| cfg.client_port_slot(c).0 == port && writes[c].0 > 0)
                    .map(|c| WriterLoad {
                        transfers: writes[c].0,
                        beats: writes[c].1,
                        outstanding: if c == list { cfg.pre_outstanding } else { cfg.axi_outstanding },
                    })
                    .collect();
                pre_writer_cycles(&self.mem, &loads)
            })
            .fold(0.0, f64::max)
    }

    /// The prediction for one frame: the schedule with every job alone on its port, then (a
    /// few rounds) each job's time with the jobs of its port sharing it, played from the
    /// schedule's start times ([`port_share::play`]: a sort's stages and a raster as phases
    /// with their demands on R and W), and the schedule again.
    pub fn predict(&self, trace: &FrameTrace) -> FramePrediction {
        let tiles = &trace.tiles;
        let jobs: Vec<[FluidJob; 2]> = tiles.iter().map(|t| [self.sort_job(t), self.raster_job(t)]).collect();
        let mut dur: Vec<[f64; 2]> =
            jobs.iter().map(|j| j.each_ref().map(|j| j.phases.iter().map(|p| p.alone).sum())).collect();
        let mut sched = self.schedule(tiles, &dur, trace.planned);
        for _ in 0..CONTENTION_ROUNDS {
            for (j, phases) in sched.jobs.iter().zip(self.share_ports(&sched, &jobs)) {
                let d = &mut dur[j.tile][j.engine];
                *d = 0.5 * (*d + phases.iter().sum::<f64>());
            }
            sched = self.schedule(tiles, &dur, trace.planned);
        }
        sched.prediction()
    }

    /// Every scheduled job's phase durations with the jobs of each port sharing it
    /// ([`port_share::play`]), `jobs[t]` being tile `t`'s sort and raster.
    fn share_ports(&self, sched: &Schedule, jobs: &[[FluidJob; 2]]) -> Vec<Vec<f64>> {
        let mut out = vec![Vec::new(); sched.jobs.len()];
        for port in 0..self.cfg.mem_channels {
            let on: Vec<usize> = (0..sched.jobs.len()).filter(|&i| sched.jobs[i].port == port).collect();
            let fluid: Vec<(f64, &FluidJob)> = on
                .iter()
                .map(|&i| {
                    let j = &sched.jobs[i];
                    (j.start, &jobs[j.tile][j.engine])
                })
                .collect();
            for (&i, d) in on.iter().zip(port_share::play(&fluid)) {
                out[i] = d;
            }
        }
        out
    }

    /// One read of `beats` beats by the frame controller (one burst in flight): the memory's
    /// latency, the beats and two cycles, without the cores' bridge stages (the RTL's
    /// descriptor reads follow each other every 7 cycles behind the ideal memory; until
    /// 2026-12-06 the model charged a core's round trip, 10).
    fn ctrl_read(&self, beats: u64) -> f64 {
        self.mem.latency + self.beats(beats) + 2.0
    }

    /// The frame controller's scan of the previous results before a planned frame's walk
    /// (golden `engine::adapt`): one 2-beat read per tile, then the cap (a cycle per level).
    pub fn scan_cycles(&self, tiles: usize) -> f64 {
        tiles as f64 * self.ctrl_read(2) + (1 << DPS_PASSES_BITS) as f64
    }

    /// Tiles in order on the cores by the scheduler policy, with `dur[t] = [sort, raster]`;
    /// `planned`: each descriptor read is followed by the tile's previous result.
    fn schedule(&self, tiles: &[TileTrace], dur: &[[f64; 2]], planned: bool) -> Schedule {
        let desc = self.ctrl_read(4) + if planned { self.ctrl_read(2) } else { 0.0 };
        let mut s = Scheduling::new(self.cfg, dur);
        let mut t_ctrl = 0.0f64;
        for (i, t) in tiles.iter().enumerate() {
            let ready = t_ctrl + desc;
            if t.plan.overflow {
                s.pending.push(Pending { end: ready, tile: i, seq: None });
                t_ctrl = ready;
                continue;
            }
            let c = s.sequencer_for(ready, i);
            let start = ready.max(s.seq_free[c]);
            s.seq_free[c] = f64::INFINITY;
            s.sorts.push(Job { tile: i, engine: 0, port: s.sort_port[c], start, end: 0.0 });
            s.pending.push(Pending { end: start + dur[i][0], tile: i, seq: Some((c, s.sorts.len() - 1)) });
            t_ctrl = start;
        }
        while s.accept_next() {}
        let end = s.raster_free.iter().copied().fold(t_ctrl, f64::max);
        let mut jobs = s.sorts;
        jobs.extend(s.rasters);
        Schedule { jobs, end }
    }
}

/// A finished sort (or an overflowing tile) not yet in the completion queue.
struct Pending {
    end: f64,
    tile: usize,
    /// The sequencer and its job's index, for a sorted tile.
    seq: Option<(usize, usize)>,
}

/// The frame controller's state while [`EngineFrameModel::schedule`] places a frame's jobs:
/// sequencers, the completion queue ([`COMPLETION_QUEUE_DEPTH`] entries, each leaving when its
/// raster command is taken) and the raster cores.
struct Scheduling<'d> {
    dur: &'d [[f64; 2]],
    policy: SchedulerPolicy,
    /// The AXI4 port of each sorting core's and each raster core's bridge
    /// ([`EngineConfig::client_port`]).
    sort_port: Vec<usize>,
    raster_port: Vec<usize>,
    /// When each sequencer takes a new tile (infinite while its completion is pending).
    seq_free: Vec<f64>,
    raster_free: Vec<f64>,
    pending: Vec<Pending>,
    /// When each queued completion left the queue (its raster command taken), in queue order.
    left: Vec<f64>,
    sorts: Vec<Job>,
    rasters: Vec<Job>,
}

impl<'d> Scheduling<'d> {
    fn new(cfg: &EngineConfig, dur: &'d [[f64; 2]]) -> Self {
        Scheduling {
            dur,
            policy: cfg.scheduler,
            sort_port: (0..cfg.sort_cores).map(|i| cfg.client_port(MemoryClient::SortCore(i))).collect(),
            raster_port: (0..cfg.raster_cores)
                .map(|j| cfg.client_port(MemoryClient::RasterCore(j)))
                .collect(),
            seq_free: vec![0.0; cfg.sort_cores],
            raster_free: vec![0.0; cfg.raster_cores],
            pending: Vec::new(),
            left: Vec::new(),
            sorts: Vec::new(),
            rasters: Vec::new(),
        }
    }

    /// The sequencer that takes tile `j`, its descriptor ready at `ready`: the completions the
    /// queue takes by then are queued ([`Self::accept_next`]), then more, one at a time, until
    /// the policy's choice is free (a tile dispatched later cannot compete for those slots).
    fn sequencer_for(&mut self, ready: f64, j: usize) -> usize {
        while self.next_acceptance().is_some_and(|(_, at)| at <= ready) {
            self.accept_next();
        }
        loop {
            let c = pick(&self.seq_free, ready, j, self.policy);
            if self.seq_free[c].is_finite() || !self.accept_next() {
                return c;
            }
        }
    }

    /// The pending completion the queue takes next and when ([`Self::accept_next`]).
    fn next_acceptance(&self) -> Option<(usize, f64)> {
        let slot = self.left.len().checked_sub(COMPLETION_QUEUE_DEPTH).map_or(0.0, |q| self.left[q]);
        let first = self.pending.iter().map(|p| p.end).min_by(f64::total_cmp)?;
        let when = first.max(slot);
        let key = |p: &Pending| (p.seq.map_or(0, |(c, _)| c + 1), p.end);
        let k = (0..self.pending.len()).filter(|&k| self.pending[k].end <= when).min_by(|&a, &b| {
            let (ka, kb) = (key(&self.pending[a]), key(&self.pending[b]));
            ka.0.cmp(&kb.0).then(ka.1.total_cmp(&kb.1))
        })?;
        Some((k, when))
    }

    /// Moves the next pending completion into the completion queue, once a slot is free, and
    /// hands its raster to a core. Returns false when nothing was pending. The next one is the
    /// frame controller's choice when the queue takes one (`neo_frame_ctrl`): of the completions
    /// waiting by then (the slot's time, or the earliest completion's), an overflowing tile
    /// first, then the lowest sequencer, whatever their order of finishing. A sequencer that
    /// keeps finishing short tiles keeps the slots; a higher one holds its tile. (Until
    /// 2026-12-06 the earliest finisher went first: on biker with four ports three of 80 tiles
    /// were rastered out of the RTL's order.)
    fn accept_next(&mut self) -> bool {
        let Some((k, queued)) = self.next_acceptance() else {
            return false;
        };
        let p = self.pending.swap_remove(k);
        if let Some((c, job)) = p.seq {
            self.seq_free[c] = queued;
            self.sorts[job].end = queued;
        }
        let ready = queued.max(self.left.last().copied().unwrap_or(0.0)) + 1.0;
        let r = pick(&self.raster_free, ready, self.left.len(), self.policy);
        let start = ready.max(self.raster_free[r]);
        let end = start + self.dur[p.tile][1];
        self.raster_free[r] = end;
        self.left.push(start);
        self.rasters.push(Job { tile: p.tile, engine: 1, port: self.raster_port[r], start, end });
        true
    }
}

/// Rounds of the port-sharing correction in [`EngineFrameModel::predict`].
const CONTENTION_ROUNDS: usize = 12;

/// One sort (engine 0) or raster (engine 1) of a tile, on its core's AXI port.
struct Job {
    tile: usize,
    engine: usize,
    port: usize,
    start: f64,
    /// When its core is free again: a sort waits for a completion-queue slot.
    end: f64,
}

/// A frame's jobs and its end.
struct Schedule {
    jobs: Vec<Job>,
    end: f64,
}

impl Schedule {
    fn prediction(&self) -> FramePrediction {
        let spans = |e: usize| -> f64 {
            let mut v: Vec<(f64, f64)> =
                self.jobs.iter().filter(|j| j.engine == e).map(|j| (j.start, j.end)).collect();
            union(&mut v)
        };
        FramePrediction {
            cycles: self.end,
            sort_busy: spans(0),
            raster_busy: spans(1),
            pre_busy: 0.0,
            scan: 0.0,
            dps_passes: Vec::new(),
            dps_wide: Vec::new(),
        }
    }
}

/// Entries stage `s` of a tile's sort reads and writes: every command writes what it reads,
/// except the reuse tile's closing MERGE_DELETE, which writes the next table.
fn stage_entries(t: &TileTrace, s: usize) -> (u64, u64) {
    let last = t.plan.stages.len().saturating_sub(1);
    t.plan.stages[s].iter().fold((0, 0), |(r, w), c| {
        let read = c.len_a + c.len_b;
        let written = match c.mode {
            SortMode::MergeDelete if s == last => t.next_len,
            _ => read,
        };
        (r + read, w + written)
    })
}

/// The model's error against the RTL, in percent: `(model - rtl) / rtl`.
pub fn error_pct(model: f64, rtl: u64) -> f64 {
    (model - rtl as f64) / (rtl as f64).max(1.0) * 100.0
}

/// The core a job ready at `ready` goes to: the lowest-numbered one free by then (else the one
/// free first) for `first_free`; job `j mod N` for `round_robin`.
fn pick(free: &[f64], ready: f64, j: usize, policy: SchedulerPolicy) -> usize {
    match policy {
        SchedulerPolicy::RoundRobin => j % free.len(),
        SchedulerPolicy::FirstFree => match free.iter().position(|&f| f <= ready) {
            Some(k) => k,
            None => (0..free.len()).min_by(|&a, &b| free[a].total_cmp(&free[b])).unwrap_or(0),
        },
    }
}

/// Length of the union of the intervals.
fn union(spans: &mut [(f64, f64)]) -> f64 {
    spans.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut total = 0.0;
    let mut cur: Option<(f64, f64)> = None;
    for &(s, e) in spans.iter() {
        cur = match cur {
            Some((cs, ce)) if s <= ce => Some((cs, ce.max(e))),
            Some((cs, ce)) => {
                total += ce - cs;
                Some((s, e))
            }
            None => Some((s, e)),
        };
    }
    if let Some((cs, ce)) = cur {
        total += ce - cs;
    }
    total
}

#[cfg(test)]
mod tests {
    use super::*;
    use neo_golden::engine::{RasterTrace, SegmentWork, TileCmd, TilePlan};
    use neo_golden::raster::SubtileWork;
    use std::path::PathBuf;

    fn latency() -> Latency {
        let p = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../reports/latency.json");
        Latency::from_file(&p).expect("reports/latency.json")
    }

    fn sort_tile(n: u64) -> TileTrace {
        let cmds = (0..n.div_ceil(256))
            .map(|k| TileCmd {
                mode: SortMode::Sort,
                src_a: 256 * k,
                len_a: (n - 256 * k).min(256),
                src_b: 0,
                len_b: 0,
                dst: 256 * k,
            })
            .collect();
        TileTrace {
            plan: TilePlan { overflow: false, stages: vec![cmds], wide: false },
            next_len: n,
            raster: RasterTrace { len: 0, present: 0, subtiles: Vec::new(), segments: Vec::new() },
        }
    }

    /// A tile from scratch of `n` entries whose sort is the conventional one (chunks, then merge
    /// passes) and whose raster routes every entry to an eighth of the subtiles.
    fn merge_tile(n: u64) -> TileTrace {
        let mut stages: Vec<Vec<TileCmd>> = Vec::new();
        for c in neo_golden::sort::conventional_sort_plan(n, 256) {
            if stages.len() as u64 == c.stage {
                stages.push(Vec::new());
            }
            let (src_a, src_b) = (c.start, c.start_b());
            stages[c.stage as usize].push(TileCmd {
                mode: c.mode,
                src_a,
                len_a: c.len_a,
                src_b,
                len_b: c.len_b,
                dst: c.start,
            });
        }
        TileTrace { plan: TilePlan { overflow: false, stages, wide: false }, ..raster_tile(n) }
    }

    /// A tile of `n` entries, no sort, each entry routed to 8 of the 64 subtiles.
    fn raster_tile(n: u64) -> TileTrace {
        let share = |e: u64| (e / 8) as u32;
        let segments = (0..n.div_ceil(256))
            .map(|k| {
                let e = (n - 256 * k).min(256);
                SegmentWork { entries: e as u32, routed: vec![share(e); 64], processed: vec![share(e); 64] }
            })
            .collect();
        let sub = SubtileWork { routed: share(n), processed: share(n), ..SubtileWork::default() };
        TileTrace {
            plan: TilePlan { overflow: false, stages: Vec::new(), wide: false },
            next_len: n,
            raster: RasterTrace { len: n, present: n, subtiles: vec![sub; 64], segments },
        }
    }

    #[test]
    fn union_merges_overlapping_spans() {
        assert_eq!(union(&mut [(0.0, 10.0), (5.0, 12.0), (20.0, 25.0)]), 17.0);
        assert_eq!(union(&mut []), 0.0);
    }

    #[test]
    fn first_free_takes_the_lowest_free_core_and_round_robin_the_next() {
        assert_eq!(pick(&[5.0, 0.0, 0.0], 1.0, 7, SchedulerPolicy::FirstFree), 1);
        assert_eq!(pick(&[5.0, 3.0], 1.0, 7, SchedulerPolicy::FirstFree), 1);
        assert_eq!(pick(&[0.0, 0.0, 0.0], 1.0, 7, SchedulerPolicy::RoundRobin), 1);
    }

    #[test]
    fn a_sort_stage_costs_its_batch_and_round_trip_and_a_chunks_slow_writes() {
        let lat = latency();
        let cfg = lat.config.clone();
        let m = EngineFrameModel::new(&cfg, &lat, PortTiming::IDEAL).unwrap();
        let t = sort_tile(600);
        let cmds: Vec<Cmd> =
            t.plan.commands().map(|c| Cmd { mode: c.mode, len_a: c.len_a, len_b: 0 }).collect();
        let want = batch_cycles(&cmds, &lat) as f64 + m.round_trip();
        assert_eq!(m.sort_cycles(&t), want);
        // Half the bandwidth: the chunks' loads (600 entries, 1200 cycles) still hide under
        // their merge passes, but each chunk's last pass writes at half the pace: 600 more
        // cycles. A tenth: 5400 more.
        let port = |bandwidth: f64| {
            let mem = PortTiming { bandwidth, ..PortTiming::IDEAL };
            EngineFrameModel::new(&cfg, &lat, mem).unwrap().sort_cycles(&t)
        };
        assert!((port(0.5) - (want + 600.0)).abs() < 1e-6, "{}", port(0.5));
        assert!((port(0.1) - (want + 5400.0)).abs() < 1e-6, "{}", port(0.1));
        // Merges stream: their writes overlap the core's pace, so a slow port costs the longer.
        let merge = TileTrace {
            plan: TilePlan {
                stages: vec![vec![TileCmd {
                    mode: SortMode::Merge,
                    len_a: 300,
                    len_b: 300,
                    ..t.plan.stages[0][0]
                }]],
                ..t.plan.clone()
            },
            ..t.clone()
        };
        let alone = m.sort_cycles(&merge);
        let slow = PortTiming { bandwidth: 0.1, ..PortTiming::IDEAL };
        let slow = EngineFrameModel::new(&cfg, &lat, slow).unwrap().sort_cycles(&merge);
        assert!(alone < 6000.0 && (slow - (6000.0 + m.round_trip())).abs() < 1e-6, "{alone} {slow}");
    }

    #[test]
    fn a_held_completion_waits_while_a_lower_sequencer_keeps_taking_the_queue() {
        // neo_frame_ctrl: when the completion queue takes one, the lowest sequencer's wins,
        // whatever finished first. Tile 0's long raster keeps the queue full (its short sort
        // frees sequencer 0 before tile 1's descriptor arrives). Sequencer 0 sorts tile 1
        // (long), so sequencer 1 takes tiles 2 to 6; tile 6 finishes first but waits:
        // tile 1 takes the next slot, then sequencer 0's tiles 7 and 8 (finishing before each
        // slot frees) take theirs. Earliest-first would raster 6 before 1, 7 and 8.
        let lat = latency();
        let cfg = EngineConfig { sort_cores: 2, raster_cores: 1, ..lat.config.clone() };
        let m = EngineFrameModel::new(&cfg, &lat, PortTiming::IDEAL).unwrap();
        let tiles: Vec<TileTrace> = (0..9).map(|_| sort_tile(0)).collect();
        let mut dur = vec![[10.0, 100.0]; 9];
        dur[0] = [2.0, 100_000.0];
        dur[1] = [2_000.0, 100.0];
        let sched = m.schedule(&tiles, &dur, false);
        let mut rasters: Vec<&Job> = sched.jobs.iter().filter(|j| j.engine == 1).collect();
        rasters.sort_by(|a, b| a.start.total_cmp(&b.start));
        let order: Vec<usize> = rasters.iter().map(|j| j.tile).collect();
        assert_eq!(order, [0, 2, 3, 4, 5, 1, 7, 8, 6]);
    }

    #[test]
    fn a_descriptor_read_costs_the_latency_its_beats_and_two_cycles() {
        // The RTL's descriptor reads follow each other every 7 cycles behind the ideal memory.
        let lat = latency();
        let m = EngineFrameModel::new(&lat.config, &lat, PortTiming::IDEAL).unwrap();
        assert_eq!(m.ctrl_read(4), 7.0);
        let slow = PortTiming { latency: 9.75, bandwidth: 0.75, ..PortTiming::IDEAL };
        let m = EngineFrameModel::new(&lat.config, &lat, slow).unwrap();
        assert!((m.ctrl_read(4) - (9.75 + 4.0 / 0.75 + 2.0)).abs() < 1e-12);
    }

    #[test]
    fn a_sort_beside_a_raster_on_its_port_slows_only_in_its_merges() {
        // One sort core and one raster core on one port: tile 1's sort (its chunk stage light on
        // the port, its merges heavy) runs beside tile 0's raster. The raster is slowed
        // throughout; the sort's chunk stage is not.
        let lat = latency();
        let one_port = EngineConfig { sort_cores: 1, raster_cores: 1, mem_channels: 1, ..lat.config.clone() };
        let two_ports = EngineConfig { mem_channels: 2, ..one_port.clone() };
        let m1 = EngineFrameModel::new(&one_port, &lat, PortTiming::IDEAL).unwrap();
        let m2 = EngineFrameModel::new(&two_ports, &lat, PortTiming::IDEAL).unwrap();
        assert_ne!(
            two_ports.client_port(MemoryClient::SortCore(0)),
            two_ports.client_port(MemoryClient::RasterCore(0)),
            "two ports: each core alone"
        );
        let raster = m1.raster_job(&raster_tile(20_000));
        let sort = m1.sort_job(&merge_tile(20_000));
        assert!(sort.phases.len() > 2 && sort.phases[0].read < 0.5 && sort.phases[1].read > 0.6, "{sort:?}");
        let played = port_share::play(&[(0.0, &raster), (0.0, &sort)]);
        let alone = |j: &FluidJob| j.phases.iter().map(|p| p.alone).collect::<Vec<f64>>();
        assert!(played[0][0] > 1.2 * alone(&raster)[0], "the raster waits behind the merges: {played:?}");
        assert!(
            (played[1][0] - alone(&sort)[0]).abs() < 0.02 * alone(&sort)[0],
            "the chunk stage: {played:?}"
        );
        assert!(played[1][1] > 1.1 * alone(&sort)[1], "the first merge pass: {played:?}");
        // And in the frame: the same two tiles cost more on one port than on two.
        let trace =
            FrameTrace { tiles: vec![raster_tile(20_000), merge_tile(20_000)], ..FrameTrace::default() };
        let (p1, p2) = (m1.predict(&trace), m2.predict(&trace));
        assert!(p1.raster_busy > 1.1 * p2.raster_busy && p1.cycles > p2.cycles, "{p1:?} vs {p2:?}");
    }

    #[test]
    fn a_window_core_holds_entries_back_and_its_write_back_stops_the_loads() {
        // A tile of 8 segments behind a memory with latency: without the window, the bridge's
        // table bursts in flight keep arriving during each write-back; with one, the table
        // bursts went out after the last feature read, so each write-back stops the loads.
        let lat = latency();
        let mem = PortTiming { latency: 20.0, bandwidth: 0.75, ..PortTiming::IDEAL };
        let plain = EngineFrameModel::new(&lat.config, &lat, mem).unwrap();
        let w = 64;
        let cfg = EngineConfig { raster_window: w, ..lat.config.clone() };
        let windowed = EngineFrameModel::new(&cfg, &lat, mem).unwrap();
        let tile = raster_tile(2048);
        let (a, b) = (plain.raster_cycles(&tile), windowed.raster_cycles(&tile));
        // The write-backs of 7 segments overlap the next loads without the window: with it, each
        // costs the bridge's bursts in flight more.
        let overlap = plain.beats(1) * (lat.config.axi_outstanding * lat.config.burst) as f64;
        assert!(b - a > 7.0 * overlap, "{a} -> {b}: each write-back stops the loads ({overlap} a segment)");
        // A one-segment tile has no write-back between loads: its held entries drain one a cycle.
        let short = raster_tile(200);
        let d = windowed.raster_cycles(&short) - plain.raster_cycles(&short);
        assert_eq!(d, (w - 1) as f64);
    }

    #[test]
    fn tiles_spread_over_the_cores_and_the_frame_ends_with_the_last_raster() {
        let lat = latency();
        let one = EngineConfig { sort_cores: 1, raster_cores: 1, ..lat.config.clone() };
        let two = EngineConfig { sort_cores: 2, ..one.clone() };
        let trace = FrameTrace { tiles: vec![sort_tile(2048), sort_tile(2048)], ..FrameTrace::default() };
        let p1 = EngineFrameModel::new(&one, &lat, PortTiming::IDEAL).unwrap().predict(&trace);
        let p2 = EngineFrameModel::new(&two, &lat, PortTiming::IDEAL).unwrap().predict(&trace);
        // Both sorts at once on two cores; the rasters share one core either way.
        assert!(p2.sort_busy < 0.55 * p1.sort_busy, "two cores: {p2:?}, one: {p1:?}");
        assert!(p2.cycles < p1.cycles && p2.raster_busy == p1.raster_busy, "{p2:?} vs {p1:?}");
        // One core of each: the second sort overlaps the first raster; the last raster follows
        // the last sort.
        assert!(p1.sort_busy + p1.raster_busy / 2.0 <= p1.cycles + 1.0, "{p1:?}");
        assert!(p1.sort_busy + p1.raster_busy > p1.cycles, "{p1:?}");
    }

    /// The credit rule played cycle by cycle (a whole beat of credit and a ready draw move a
    /// beat; `bandwidth` earned a cycle up to two beats), with fixed draws.
    fn played_write_rate(bandwidth: f64, ready: f64, cycles: u64) -> f64 {
        let (mut credit, mut beats, mut draws) = (0.0f64, 0u64, XorShift(0x9E37_79B9_7F4A_7C15));
        for _ in 0..cycles {
            credit = (credit + bandwidth).min(2.0);
            if credit >= 1.0 - 1e-12 && draws.unit() < ready {
                credit -= 1.0;
                beats += 1;
            }
        }
        beats as f64 / cycles as f64
    }

    #[test]
    fn the_write_rate_is_the_credit_rules_played_rate() {
        assert_eq!(PortTiming::IDEAL.write_rate(), 1.0);
        for (bandwidth, ready) in [(0.75, 0.6), (0.75, 1.0), (1.0, 0.6), (0.5, 0.6), (0.75, 0.3), (0.3, 0.9)]
        {
            let t = PortTiming { bandwidth, ready, ..PortTiming::IDEAL };
            let (got, played) = (t.write_rate(), played_write_rate(bandwidth, ready, 2_000_000));
            assert!(
                (got - played).abs() < 0.003,
                "bandwidth {bandwidth}, ready {ready}: {got} vs played {played}"
            );
            assert!(
                got <= bandwidth.min(ready) + 1e-12 && got >= bandwidth * ready - 1e-12,
                "{bandwidth} {ready}: {got}"
            );
        }
        // The harness's random memory (3/4 bandwidth, ready 60% of cycles).
        let random = PortTiming { latency: 6.0, bandwidth: 0.75, ready: 0.6, ..PortTiming::IDEAL };
        assert!((random.write_rate() - 0.5766).abs() < 0.001, "{}", random.write_rate());
    }

    #[test]
    fn single_beat_writes_wait_for_an_aw_and_a_w_ready_each() {
        assert_eq!(PortTiming::IDEAL.single_write_rate(8), 1.0);
        let random = PortTiming { latency: 6.0, bandwidth: 0.75, ready: 0.6, ..PortTiming::IDEAL };
        let single = random.single_write_rate(8);
        assert!(single < random.write_rate() && single > 0.3, "{single}");
        // One write in flight: a round trip per write.
        let one = random.single_write_rate(1);
        assert!(one < 1.0 / (6.0 + B_PATH_CYCLES) + 0.01, "{one}");
        // Late responses of one ID stay in order: a late B holds the ones behind it, and the
        // writes in flight with them (the harness's random memory: 0.32; its merges wrote 0.315
        // a cycle in the RTL).
        let late = PortTiming { late_share: 0.3, late_max: 24.0, latency: 9.75, ..random };
        let harness = late.single_write_rate(8);
        assert!(harness < single - 0.03, "{harness} vs {single}");
        assert!((harness - 0.315).abs() < 0.01, "{harness}");
        // Always ready at full bandwidth: only the outstanding limit and the B's delay matter:
        // a write's take, AW and W, then its B.
        let slow_b = PortTiming { latency: 30.0, ..PortTiming::IDEAL };
        let limited = slow_b.single_write_rate(8);
        assert!((limited - 8.0 / (30.0 + B_PATH_CYCLES + 2.0)).abs() < 0.005, "{limited}");
    }

    #[test]
    fn unit_timing_of_other_cores_and_bad_memory_timing_are_refused() {
        let lat = latency();
        let wide = EngineConfig { bsu_width: lat.config.bsu_width * 2, ..lat.config.clone() };
        let e = EngineFrameModel::new(&wide, &lat, PortTiming::IDEAL).err().expect("refused");
        assert!(e.contains("bsu_width"), "{e}");
        let counts = EngineConfig { sort_cores: 3, raster_cores: 2, mem_channels: 1, ..lat.config.clone() };
        assert!(EngineFrameModel::new(&counts, &lat, PortTiming::IDEAL).is_ok());
        let buffers = EngineConfig { dps_wide: 4, ..lat.config.clone() };
        assert!(EngineFrameModel::new(&buffers, &lat, PortTiming::IDEAL).is_ok(), "the wide chunk");
        let bad = PortTiming { bandwidth: 0.0, ..PortTiming::IDEAL };
        assert!(EngineFrameModel::new(&lat.config, &lat, bad).is_err());
    }
}
