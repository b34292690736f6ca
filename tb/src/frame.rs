//! The `neo_frame_ctrl` test bench. Rust plays everything around the frame controller:
//! - AXI client 0's memory (a golden [`Memory`] holding the descriptors and, in frames the
//!   controller plans (`ADAPT_CTRL`, random fields), the previous results; random `arready`,
//!   `rvalid` gaps, `awready`, `wready`, B latency);
//! - the N sequencers: a job is taken when the sequencer is idle and a coin says so; it
//!   completes after a random time with a `next_len` and merge inversions of its own choosing
//!   (functions of the tile; some inversions beyond the result's 24-bit field), held on
//!   `cpl_len_i[k]` and `cpl_inv_i[k]` until taken;
//! - the M raster cores: a command is taken when the core is idle (random), `ras_done_i` pulses
//!   after a random time with the tile's write-back signals on `ras_wb_len_i[j]` and
//!   `ras_wb_reach_i[j]` (random junk in other cycles);
//! - the bridges' `idle_i`: random bits.
//!
//! The checker: every non-overflowing tile is handed to a sequencer exactly once, in tile
//! order, with the descriptor's fields, the frame parity and that sequencer's scratch base, to
//! the sequencer the scheduler policy names, with the descriptor's DPS passes or, in a planned
//! frame, golden `engine_passes` of the previous results (reads: every result in tile order,
//! then each tile's descriptor and result); overflowing tiles never; every tile is rastered
//! exactly once, after its sort completed, with `len` = the sequencer's `next_len` (0 when it
//! overflowed), `table = next`, its tile_x/y, `feat = FEAT_BASE/32`, `pix = FB_BASE/4 + t
//! tile^2`, to the core the policy names among those whose last result is written; descriptor
//! reads are 4-beat INCR bursts at `DESC_BASE + 32 t` in tile order; each result is written once
//! (a 2-beat burst at `RESULT_BASE + 16 t`, all strobes) after the tile's raster, with the
//! tile's `next_len`, overflow, saturated inversions and write-back signals; `done_o` rises only after
//! all of that, with every B back and every `idle_i` high the cycle before; `FIRST_OVERFLOW` and
//! `OVERFLOWS` equal golden's.

use crate::bits::mask;
use crate::check::Checker;
use crate::dut::Clocked;
use crate::dynmodel::DynModel;
use crate::models::NeoFrameCtrl;
use crate::rng::Rng;
use neo_gen::{EngineConfig, SchedulerPolicy};
use neo_golden::engine::adapt::{ADAPT_BUDGET_LSB, ADAPT_MAX_LSB};
use neo_golden::engine::memory::{MAX_DPS_PASSES, RESULT_BYTES};
use neo_golden::engine::{engine_passes, AdaptRegs, FrameRegs, Memory, TileDescriptor, TileResult};
use neo_golden::pipeline::adaptive::WritebackSignals;
use std::collections::VecDeque;

/// One frame: the registers, the descriptors and the previous frame's results.
#[derive(Clone, Debug)]
pub struct FrameCase {
    /// Registers (`tiles` = `descs.len()`).
    pub regs: FrameRegs,
    /// Tile descriptors; `next` must be unique per tile (the bench identifies tiles by it).
    pub descs: Vec<TileDescriptor>,
    /// The results in memory before the start (what a planned frame reads).
    pub prev_results: Vec<TileResult>,
}

impl FrameCase {
    /// Each tile's DPS passes and wide bit as the controller must hand them to its sequencer:
    /// the descriptor's, or golden [`engine_passes`] of the previous results in a planned frame.
    pub fn plans(&self, cfg: &EngineConfig) -> Vec<(u64, bool)> {
        if self.regs.adapt.enabled() {
            engine_passes(&self.regs.adapt, cfg, &self.prev_results)
                .into_iter()
                .map(|p| (u64::from(p.passes), p.wide))
                .collect()
        } else {
            self.descs.iter().map(|d| (d.passes(), d.dps_wide)).collect()
        }
    }

    /// The reads the controller issues, in order: `(byte address, beats)`.
    pub fn reads(&self) -> Vec<(u64, u64)> {
        let (desc, res) = (self.regs.desc_base, self.regs.result_base);
        let tiles = self.descs.len() as u64;
        let planned = self.regs.adapt.enabled();
        let mut v: Vec<(u64, u64)> =
            if planned { (0..tiles).map(|t| (res + RESULT_BYTES * t, 2)).collect() } else { vec![] };
        for t in 0..tiles {
            v.push((desc + 32 * t, 4));
            if planned {
                v.push((res + RESULT_BYTES * t, 2));
            }
        }
        v
    }
}

/// What the frame took.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FrameRun {
    /// Cycles from start to done.
    pub cycles: u64,
    /// Tiles that overflowed.
    pub overflows: u32,
    /// Tiles handed out with more than one DPS pass planned by the controller.
    pub planned_extra: u64,
    /// Tiles handed out with the wide chunk planned by the controller.
    pub planned_wide: u64,
}

/// The merge inversions the sequencer model reports for tile `t`: small counts, and for one tile
/// in 7 a count beyond the result's 24-bit field (saturated there), within `len_bits`.
pub fn model_inversions(t: u64, lw: u32) -> u64 {
    if t % 7 == 3 {
        ((1u64 << 24) + t * 0x9e37_79b9) & mask(lw)
    } else {
        (t * 131) % 5000
    }
}

/// The write-back signals (len, reach) the raster-core model reports for tile `t`: 32-bit
/// hashes of it (every bit of the record's fields), within `len_bits`.
pub fn model_wb_signals(t: u64, lw: u32) -> (u64, u64) {
    let h = neo_golden::synthetic::rng::mix64(t);
    (h & mask(lw.min(32)), (h >> 32) & mask(lw.min(32)))
}

/// The `next_len` the sequencer model reports for tile `t` with descriptor `d`: at most the
/// table capacity `cap` (the contract of a sort), and `cap` itself for one tile in 16.
pub fn model_next_len(t: u64, d: &TileDescriptor, cap: u64) -> u64 {
    if t % 16 == 5 {
        cap
    } else {
        (d.list_len as u64 + (d.prev_len as u64 / 2) + t * 977) % (cap + 1)
    }
}

/// A random frame of `tiles` tiles, some over `table_capacity` (`huge_percent` of them with
/// any 32-bit lengths), a few exactly at it, with the registers drawn over their whole range: width and height any 16-bit
/// value, FEAT_BASE, FB_BASE and SCRATCH_BASE any 32-bit value (the controller uses their
/// upper bits only), DESC_BASE (32-byte aligned: one 4-beat burst a descriptor) and RESULT_BASE
/// (16-byte aligned: one 2-beat burst a result) anywhere in the 32-bit address space with their regions
/// apart. Every tile's `next` is a distinct random 32-bit address.
pub fn random_case(cfg: &EngineConfig, rng: &mut Rng, tiles: usize, huge_percent: u32) -> FrameCase {
    let cap = cfg.table_capacity as u64;
    let mut nexts = std::collections::HashSet::new();
    let descs = (0..tiles)
        .map(|_| {
            let (big, huge, full) = (rng.percent(15), rng.percent(huge_percent), rng.percent(3));
            let list_len = if big { rng.range(cap / 2, cap + 10) } else { rng.below(3000) } as u32;
            let prev_len = if big { rng.range(cap / 2, cap) } else { rng.below(3000) } as u32;
            let from_scratch = rng.percent(30);
            let (list_len, prev_len) = if huge {
                (rng.next_u32(), rng.next_u32())
            } else if full {
                // entries_in = table_capacity exactly: sorted, not an overflow.
                let p = if from_scratch { prev_len } else { prev_len.min(cap as u32) };
                (cap as u32 - if from_scratch { 0 } else { p }, p)
            } else {
                (list_len, prev_len)
            };
            let next = loop {
                let a = rng.next_u32();
                if nexts.insert(a) {
                    break a;
                }
            };
            TileDescriptor {
                tile_x: rng.next_u32() as u16,
                tile_y: rng.next_u32() as u16,
                from_scratch,
                prev: rng.next_u32(),
                prev_len,
                list: rng.next_u32(),
                list_len,
                next,
                dps_passes: rng.below(MAX_DPS_PASSES as u64 + 1) as u8,
                dps_wide: rng.percent(50),
            }
        })
        .collect();
    let (desc_bytes, result_bytes) = (32 * tiles as u64, RESULT_BYTES * tiles as u64);
    let desc_base = 32 * rng.below(((1u64 << 32) - desc_bytes) / 32 + 1);
    let result_base = loop {
        let b = 16 * rng.below(((1u64 << 32) - result_bytes) / 16 + 1);
        if b + result_bytes <= desc_base || desc_base + desc_bytes <= b {
            break b;
        }
    };
    // Half of the frames planned by the controller, its fields over their whole range (and the
    // reserved bits random), previous results with reaches of up to 6 chunks and some inversions.
    let adapt = if tiles > 1000 || rng.percent(50) {
        let reserved = rng.next_u32() & !(0xF << ADAPT_MAX_LSB | 0x3FF << ADAPT_BUDGET_LSB | 1);
        // The large frames at the field's largest budget (1023: products up to 2^54).
        let budget = if tiles > 1000 { 1023 } else { rng.below(1024) as u32 };
        AdaptRegs {
            ctrl: reserved | 1 | budget << ADAPT_BUDGET_LSB | (rng.below(16) as u32) << ADAPT_MAX_LSB,
        }
    } else {
        AdaptRegs { ctrl: rng.next_u32() & !1 }
    };
    let chunk = cfg.chunk as u64;
    // Tables of any 32-bit length and reach in the large frames (all of them: the frame
    // controller's sums reach 2^44 over 4095 tiles) and in half the tiles of one small frame in
    // 4, the largest reach among them; else up to 4000 entries (a tenth empty: a cost of 1) and
    // 6 chunks (half of the tiles 6 wide chunks, in an engine with one).
    let huge_tables = tiles > 1000 || rng.percent(25);
    let prev_results = (0..tiles)
        .map(|_| {
            let huge = huge_tables && (tiles > 1000 || rng.percent(50));
            let wb_len = match (huge, rng.percent(10)) {
                (_, true) => 0,
                // The large frames' tables from 2^31 up: their sums pass 2^44.
                (true, false) if tiles > 1000 => rng.next_u32() | 1 << 31,
                (true, false) => rng.next_u32(),
                (false, false) => rng.below(4000) as u32,
            };
            TileResult {
                next_len: rng.next_u32(),
                overflow: rng.percent(5),
                merge_inversions: if rng.percent(30) { rng.below(1 << 24) as u32 } else { 0 },
                wb_len,
                wb_reach: match (huge, rng.percent(40)) {
                    (true, true) => u32::MAX,
                    (true, false) => rng.next_u32(),
                    (false, true) => 0,
                    (false, false) => {
                        let unit = if cfg.dps_wide > 1 && rng.percent(50) {
                            cfg.sort_buffer() as u64
                        } else {
                            chunk
                        };
                        rng.below(6 * unit) as u32
                    }
                },
            }
        })
        .collect();
    let regs = FrameRegs {
        frame: rng.next_u32(),
        tiles: tiles as u32,
        width: rng.range(1, 0xffff) as u32,
        height: rng.range(1, 0xffff) as u32,
        desc_base,
        result_base,
        feat_base: rng.next_u32() as u64,
        fb_base: rng.next_u32() as u64,
        scratch_base: rng.next_u32() as u64,
        pre: Default::default(),
        adapt,
    };
    FrameCase { regs, descs, prev_results }
}

/// A sequencer model: the tile it sorts, when it completes, and the `next_len`.
#[derive(Clone, Copy, Debug)]
struct SeqModel {
    tile: u64,
    due: u64,
    len: u64,
    inv: u64,
}

/// The frame controller with its surroundings, on the statically linked model of the crate's
/// configuration ([`FrameBench::new`]) or on one built for any configuration
/// ([`FrameBench::build`]).
pub struct FrameBench<M: Clocked = NeoFrameCtrl> {
    /// The model.
    pub dut: M,
    /// Mismatch reporting.
    pub checker: Checker,
    cfg: EngineConfig,
    rng: Rng,
}

impl FrameBench<NeoFrameCtrl> {
    /// A reset frame controller (the static model of [`crate::config`]).
    pub fn new(cfg: &EngineConfig, seed: u64) -> Self {
        FrameBench::with_model(NeoFrameCtrl::new(), cfg, seed)
    }
}

impl FrameBench<DynModel> {
    /// A reset frame controller of any configuration `cfg` (`neo_frame_ctrl` built at run
    /// time, or loaded from the cache: [`crate::configs::build`]).
    pub fn build(cfg: &EngineConfig, seed: u64) -> Result<Self, String> {
        Ok(FrameBench::with_model(crate::configs::build(cfg, "neo_frame_ctrl")?, cfg, seed))
    }
}

impl<M: Clocked> FrameBench<M> {
    /// A reset frame controller on model `dut` (`neo_frame_ctrl` generated from `cfg`).
    pub fn with_model(mut dut: M, cfg: &EngineConfig, seed: u64) -> Self {
        dut.io_reset();
        let checker = Checker::new(dut.top(), seed);
        FrameBench { dut, checker, cfg: cfg.clone(), rng: Rng::new(seed).fork(9) }
    }

    /// Restarts the bench's random stream and its checker's seed from `seed`, as a bench made
    /// with `seed` has them.
    pub fn reseed(&mut self, seed: u64) {
        self.rng = Rng::new(seed).fork(9);
        self.checker = Checker::new(self.dut.top(), seed);
    }

    fn set(&mut self, name: &str, v: u64) {
        let p = self.dut.pin(name);
        self.dut.io_set_words(p, &[v as u32, (v >> 32) as u32]);
    }

    fn get(&self, name: &str) -> u64 {
        self.dut.io_get(self.dut.pin(name))
    }

    fn words(&self, p: usize) -> Vec<u32> {
        vec![0u32; self.dut.io_width(p).div_ceil(32) as usize]
    }

    fn get_lane(&self, name: &str, k: usize, width: u32) -> u64 {
        let p = self.dut.pin(name);
        let mut w = self.words(p);
        self.dut.io_get_words(p, &mut w);
        let lo = k as u32 * width;
        (0..width)
            .fold(0, |acc, b| acc | (((w[((lo + b) / 32) as usize] >> ((lo + b) % 32)) & 1) as u64) << b)
    }

    fn set_lanes(&mut self, name: &str, vals: &[u64], width: u32) {
        let p = self.dut.pin(name);
        let mut w = self.words(p);
        for (k, v) in vals.iter().enumerate() {
            for b in 0..width {
                if (v >> b) & 1 == 1 {
                    let bit = k as u32 * width + b;
                    w[(bit / 32) as usize] |= 1 << (bit % 32);
                }
            }
        }
        self.dut.io_set_words(p, &w);
    }

    /// Runs one frame from `start_i` to `done_o` and checks it (see the module docs).
    ///
    /// # Panics
    /// At the first mismatch, protocol violation or timeout.
    pub fn run(&mut self, case: &FrameCase) -> FrameRun {
        let cfg = self.cfg.clone();
        let (n, m) = (cfg.sort_cores, cfg.raster_cores);
        let (aw, lw, tb) = (cfg.addr_bits, cfg.len_bits, cfg.tile_bits);
        let cap = cfg.table_capacity as u64;
        let regs = case.regs;
        let tiles = case.descs.len();
        let mut mem = Memory::new();
        for (t, d) in case.descs.iter().enumerate() {
            mem.write_descriptor(regs.desc_base, t as u64, d);
            mem.write_result(regs.result_base, t as u64, &case.prev_results[t]);
        }
        let want_plans = case.plans(&cfg);
        let (mut planned_extra, mut planned_wide) = (0, 0);
        let mut want_reads: VecDeque<(u64, u64)> = case.reads().into();
        let tile_of = |next: u64| case.descs.iter().position(|d| d.next as u64 == next);
        let ovf: Vec<bool> = case.descs.iter().map(|d| d.entries_in() > cap).collect();
        let want_first = ovf.iter().position(|&o| o).map_or(u32::MAX, |t| t as u32);
        let want_ovfs = ovf.iter().filter(|&&o| o).count() as u32;
        // Stimulus: registers and the start pulse.
        self.set("frame_i", regs.frame as u64);
        self.set("tiles_i", tiles as u64);
        self.set("width_i", regs.width as u64);
        self.set("height_i", regs.height as u64);
        for (p, v) in [
            ("desc_base_i", regs.desc_base),
            ("result_base_i", regs.result_base),
            ("feat_base_i", regs.feat_base),
            ("fb_base_i", regs.fb_base),
            ("scratch_base_i", regs.scratch_base),
            ("adapt_ctrl_i", regs.adapt.ctrl as u64),
        ] {
            self.set(p, v);
        }
        let start = self.dut.io_cycle();
        let limit = start + 3000 + 400 * tiles as u64;
        // Models' state.
        let mut seqs: Vec<Option<SeqModel>> = vec![None; n];
        // Per raster core: (due, tile) of its command; the tile whose result is not written yet.
        let mut rasters: Vec<Option<(u64, u64)>> = vec![None; m];
        let mut unwritten: Vec<Option<u64>> = vec![None; m];
        let mut inversions = vec![0u64; tiles];
        let mut sorted = vec![false; tiles]; // job taken
        let mut sort_done: Vec<Option<u64>> = vec![None; tiles]; // completion taken: next_len
        let mut rastered = vec![false; tiles];
        let mut ras_done_count = 0usize;
        let (mut jobs, mut ras_cmds) = (0usize, 0usize);
        let mut next_fetch = 0u64;
        let mut r_beats: VecDeque<(u64, u64, bool)> = VecDeque::new(); // (due, data, last)
                                                                       // The result write in progress: its address, its data beats.
        let mut aw_cur: Option<u64> = None;
        let mut w_cur: Vec<u64> = Vec::new();
        let mut b_due: VecDeque<u64> = VecDeque::new();
        let mut writes = vec![0u32; tiles];
        // Half of the frames stall the raster cores for 128 cycles in every 384 (the completion
        // queue fills) and end raster commands on multiples of 32 cycles (several cores
        // report done in the same cycle).
        let (stall, align) = (self.rng.percent(50), self.rng.percent(50));
        let mut prev_idle_all = true;
        let mut was_busy = false;
        let mut started = false;
        loop {
            let c = self.dut.io_cycle();
            self.checker.protocol(c, c < limit, "timeout: the frame did not finish");
            let r = &mut self.rng;
            // Inputs.
            let start_pulse = !started;
            let job_ready: Vec<u64> = seqs.iter().map(|s| (s.is_none() && r.percent(60)) as u64).collect();
            let cpl_valid: Vec<u64> = seqs.iter().map(|s| s.is_some_and(|s| s.due <= c) as u64).collect();
            // A lane without cpl_valid carries any 32-bit value (the controller must not take it).
            let cpl_len: Vec<u64> =
                seqs.iter().map(|s| s.map_or(r.next_u64() & mask(lw), |s| s.len)).collect();
            let cpl_inv: Vec<u64> =
                seqs.iter().map(|s| s.map_or(r.next_u64() & mask(lw), |s| s.inv)).collect();
            let stalled = stall && (c / 128).is_multiple_of(3);
            let ras_ready: Vec<u64> =
                rasters.iter().map(|s| (s.is_none() && !stalled && r.percent(60)) as u64).collect();
            let mut ras_done = vec![0u64; m];
            let mut wb_len: Vec<u64> = (0..m).map(|_| r.next_u64() & mask(lw)).collect();
            let mut wb_reach: Vec<u64> = (0..m).map(|_| r.next_u64() & mask(lw)).collect();
            for (j, s) in rasters.iter_mut().enumerate() {
                if let Some((due, t)) = s.filter(|s| s.0 <= c) {
                    let _ = due;
                    ras_done[j] = 1;
                    (wb_len[j], wb_reach[j]) = model_wb_signals(t, lw);
                    unwritten[j] = Some(t);
                    *s = None;
                    ras_done_count += 1;
                }
            }
            let idle: Vec<u64> = (0..n + m).map(|_| r.percent(85) as u64).collect();
            let idle_all = idle.iter().all(|&b| b == 1);
            let arready = r.percent(60);
            let rbeat = r_beats.front().filter(|b| b.0 <= c && !r.percent(20)).copied();
            let (awready, wready) = (r.percent(60), r.percent(60));
            let bvalid = b_due.front().is_some_and(|&d| d <= c);
            self.set("start_i", start_pulse as u64);
            self.set_lanes("job_ready_i", &job_ready, 1);
            self.set_lanes("cpl_valid_i", &cpl_valid, 1);
            self.set_lanes("cpl_len_i", &cpl_len, lw);
            self.set_lanes("cpl_inv_i", &cpl_inv, lw);
            self.set_lanes("ras_ready_i", &ras_ready, 1);
            self.set_lanes("ras_done_i", &ras_done, 1);
            self.set_lanes("ras_wb_len_i", &wb_len, lw);
            self.set_lanes("ras_wb_reach_i", &wb_reach, lw);
            self.set_lanes("idle_i", &idle, 1);
            self.set("m_axi_arready_i", arready as u64);
            self.set("m_axi_rvalid_i", rbeat.is_some() as u64);
            let junk = self.rng.next_u64();
            self.set("m_axi_rdata_i", rbeat.map_or(junk, |b| b.1));
            self.set("m_axi_rlast_i", rbeat.is_some_and(|b| b.2) as u64);
            self.set("m_axi_rid_i", 0);
            self.set("m_axi_rresp_i", 0);
            self.set("m_axi_awready_i", awready as u64);
            self.set("m_axi_wready_i", wready as u64);
            self.set("m_axi_bvalid_i", bvalid as u64);
            self.set("m_axi_bid_i", 0);
            self.set("m_axi_bresp_i", 0);
            self.dut.io_eval();
            started = true;

            // Checker: status.
            let busy = self.get("busy_o") == 1;
            let done = self.get("done_o") == 1;
            if start_pulse {
                self.checker.protocol(c, !busy, "busy before the start");
            } else if was_busy && !busy {
                self.checker.protocol(c, done, "busy fell without done");
                self.checker.protocol(c, prev_idle_all, "done with a bridge not idle in the deciding cycle");
                self.checker.value(c, "tiles rastered at done", tiles as u64, ras_done_count as u64);
                self.checker.value(c, "reads left at done", 0, want_reads.len() as u64);
                self.checker.protocol(
                    c,
                    b_due.is_empty() && aw_cur.is_none() && w_cur.is_empty(),
                    "done with a result write in flight",
                );
                for t in 0..tiles {
                    self.checker.value(c, &format!("result {t} writes"), 1, writes[t] as u64);
                    let (l, r) = model_wb_signals(t as u64, lw);
                    let wb =
                        WritebackSignals { len: l as u32, reach: r as u32, ..WritebackSignals::default() };
                    let want = match sort_done[t] {
                        _ if ovf[t] => TileResult::new(0, true, 0, &wb),
                        Some(l) => TileResult::new(l as u32, false, inversions[t], &wb),
                        None => self.checker.fail(c, &format!("tile {t}"), "sorted", "never completed"),
                    };
                    let got = mem.read_result(regs.result_base, t as u64);
                    for (k, (w, g)) in want.to_words().into_iter().zip(got.to_words()).enumerate() {
                        self.checker.value(c, &format!("result {t} word {k}"), w, g);
                    }
                }
                self.checker.value(c, "first_overflow_o", want_first as u64, self.get("first_overflow_o"));
                self.checker.value(c, "overflows_o", want_ovfs as u64, self.get("overflows_o"));
                self.checker.value(c, "overflow_o", (want_ovfs > 0) as u64, self.get("overflow_o"));
                self.dut.io_tick();
                return FrameRun { cycles: c - start, overflows: want_ovfs, planned_extra, planned_wide };
            } else if !start_pulse && c > start + 1 {
                self.checker.protocol(c, busy, "busy fell");
            }
            was_busy = busy || start_pulse;
            prev_idle_all = idle_all;

            // AXI reads: descriptors and previous results, in the planned order; the data from
            // the memory when the request is taken.
            if arready && self.get("m_axi_arvalid_o") == 1 {
                let addr = self.get("m_axi_araddr_o");
                let Some((want_addr, beats)) = want_reads.pop_front() else {
                    self.checker.fail(c, "m_axi_arvalid_o", "no more reads", &format!("a read at 0x{addr:x}"))
                };
                self.checker.value(c, &format!("read {next_fetch} araddr"), want_addr, addr);
                self.checker.value(c, "arlen", beats - 1, self.get("m_axi_arlen_o"));
                self.checker.value(c, "arsize", 3, self.get("m_axi_arsize_o"));
                self.checker.value(c, "arburst", 1, self.get("m_axi_arburst_o"));
                let due = c + 1 + self.rng.below(6);
                for i in 0..beats {
                    r_beats.push_back((due, mem.read_u64(addr + 8 * i), i + 1 == beats));
                }
                next_fetch += 1;
            }
            if rbeat.is_some() && self.get("m_axi_rready_o") == 1 {
                r_beats.pop_front();
            }
            // AXI writes: one result (AW and two W beats) at a time.
            if awready && self.get("m_axi_awvalid_o") == 1 {
                self.checker.value(c, "awlen", 1, self.get("m_axi_awlen_o"));
                self.checker.value(c, "awsize", 3, self.get("m_axi_awsize_o"));
                self.checker.value(c, "awburst", 1, self.get("m_axi_awburst_o"));
                self.checker.protocol(c, aw_cur.is_none(), "a second AW before the result's last beat");
                aw_cur = Some(self.get("m_axi_awaddr_o"));
            }
            if wready && self.get("m_axi_wvalid_o") == 1 {
                self.checker.value(c, "wstrb", 0xff, self.get("m_axi_wstrb_o"));
                let last = w_cur.len() == 1;
                self.checker.value(c, "wlast", last as u64, self.get("m_axi_wlast_o"));
                w_cur.push(self.get("m_axi_wdata_o"));
            }
            let mut written_now = None;
            if let (Some(a), 2) = (aw_cur, w_cur.len()) {
                let off = a.wrapping_sub(regs.result_base);
                let t = (off / RESULT_BYTES) as usize;
                self.checker.protocol(
                    c,
                    off % RESULT_BYTES == 0 && t < tiles,
                    &format!("result write at 0x{a:x}"),
                );
                self.checker.protocol(c, rastered[t], &format!("result {t} written before its raster"));
                mem.write_u64(a, w_cur[0]);
                mem.write_u64(a + 8, w_cur[1]);
                writes[t] += 1;
                b_due.push_back(c + 1 + self.rng.below(60));
                (aw_cur, written_now) = (None, Some(t as u64));
                w_cur.clear();
            }
            if bvalid {
                self.checker.protocol(c, self.get("m_axi_bready_o") == 1, "bready low");
                b_due.pop_front();
            }
            // Sort jobs.
            let jv: Vec<u64> = (0..n).map(|k| self.get_lane("job_valid_o", k, 1)).collect();
            self.checker.protocol(c, jv.iter().sum::<u64>() <= 1, "job_valid_o is not one-hot");
            if let Some(k) = (0..n).find(|&k| jv[k] == 1 && job_ready[k] == 1) {
                let next = self.get("job_next_o");
                let Some(t) = tile_of(next) else {
                    self.checker.fail(c, "job_next_o", "a tile's next", &format!("0x{next:x}"))
                };
                let d = &case.descs[t];
                self.checker.protocol(c, !ovf[t], &format!("overflowing tile {t} handed to a sequencer"));
                self.checker.protocol(c, !sorted[t], &format!("tile {t} handed to a sequencer twice"));
                self.checker.protocol(
                    c,
                    sorted.iter().take(t).enumerate().all(|(u, &s)| s || ovf[u]),
                    &format!("tile {t} handed out before an earlier tile"),
                );
                let want_k = match cfg.scheduler {
                    SchedulerPolicy::RoundRobin => jobs % n,
                    SchedulerPolicy::FirstFree => (0..n).find(|&i| job_ready[i] == 1).unwrap_or(n),
                };
                self.checker.value(c, "job sequencer", want_k as u64, k as u64);
                let fields = [
                    ("job_from_scratch_o", d.from_scratch as u64),
                    ("job_prev_o", d.prev as u64),
                    ("job_prev_len_o", d.prev_len as u64),
                    ("job_list_o", d.list as u64),
                    ("job_list_len_o", d.list_len as u64),
                    ("job_dps_passes_o", want_plans[t].0),
                    ("job_dps_wide_o", want_plans[t].1 as u64),
                    ("job_odd_o", (regs.frame & 1) as u64),
                ];
                for (f, w) in fields {
                    self.checker.value(c, &format!("tile {t} {f}"), w, self.get(f));
                }
                let scr = regs.scratch_base / 8 + 2 * cap * k as u64;
                self.checker.value(
                    c,
                    &format!("job_scratch_o[{k}]"),
                    scr & mask(aw),
                    self.get_lane("job_scratch_o", k, aw),
                );
                sorted[t] = true;
                jobs += 1;
                planned_extra += (regs.adapt.enabled() && want_plans[t].0 > 1) as u64;
                planned_wide += (regs.adapt.enabled() && want_plans[t].1) as u64;
                // Quick sorts and, half of the time, slow ones: then every sequencer gets busy (the
                // high-index completions of the first-free scheduler are exercised too).
                let slow = self.rng.percent(50);
                let due = c + 1 + if slow { self.rng.below(1000) } else { self.rng.below(40) };
                let (len, inv) = (model_next_len(t as u64, d, cap), model_inversions(t as u64, lw));
                seqs[k] = Some(SeqModel { tile: t as u64, due, len, inv });
            }
            // Completions.
            for k in 0..n {
                if self.get_lane("cpl_ready_o", k, 1) == 1 {
                    self.checker.protocol(
                        c,
                        cpl_valid[k] == 1,
                        &format!("cpl_ready_o[{k}] without cpl_valid_i"),
                    );
                    let s = seqs[k].take().expect("valid implies a job");
                    sort_done[s.tile as usize] = Some(s.len);
                    inversions[s.tile as usize] = s.inv;
                }
            }
            // Raster commands.
            let rv: Vec<u64> = (0..m).map(|j| self.get_lane("ras_valid_o", j, 1)).collect();
            self.checker.protocol(c, rv.iter().sum::<u64>() <= 1, "ras_valid_o is not one-hot");
            if let Some(j) = (0..m).find(|&j| rv[j] == 1 && ras_ready[j] == 1) {
                let table = self.get("ras_table_o");
                let Some(t) = tile_of(table) else {
                    self.checker.fail(c, "ras_table_o", "a tile's next", &format!("0x{table:x}"))
                };
                let d = &case.descs[t];
                self.checker.protocol(c, !rastered[t], &format!("tile {t} rastered twice"));
                let want_len = if ovf[t] {
                    0
                } else {
                    sort_done[t].unwrap_or_else(|| {
                        self.checker.fail(c, &format!("tile {t} raster"), "after its sort", "before")
                    })
                };
                let free = |i: usize| ras_ready[i] == 1 && unwritten[i].is_none();
                let want_j = match cfg.scheduler {
                    SchedulerPolicy::RoundRobin => ras_cmds % m,
                    SchedulerPolicy::FirstFree => (0..m).find(|&i| free(i)).unwrap_or(m),
                };
                self.checker.protocol(
                    c,
                    free(j),
                    &format!("raster core {j} given a tile before its result was written"),
                );
                self.checker.value(c, "raster core", want_j as u64, j as u64);
                let t2 = (cfg.tile * cfg.tile) as u64;
                let fields = [
                    ("ras_len_o", want_len),
                    ("ras_tile_x_o", d.tile_x as u64 & mask(tb)),
                    ("ras_tile_y_o", d.tile_y as u64 & mask(tb)),
                    ("ras_width_o", regs.width as u64),
                    ("ras_height_o", regs.height as u64),
                    ("ras_feat_o", (regs.feat_base / 32) & mask(aw)),
                    ("ras_pix_o", (regs.fb_base / 4 + t as u64 * t2) & mask(aw)),
                ];
                for (f, w) in fields {
                    self.checker.value(c, &format!("tile {t} {f}"), w, self.get(f));
                }
                rastered[t] = true;
                ras_cmds += 1;
                let due = c + 2 + self.rng.below(30);
                rasters[j] = Some((if align { (due | 31) + 1 } else { due }, t as u64));
            }
            // A written result frees its core from the next cycle.
            if let Some(t) = written_now {
                for u in unwritten.iter_mut().filter(|u| **u == Some(t)) {
                    *u = None;
                }
            }
            self.dut.io_tick();
        }
    }
}
