//! The `neo_frame_ctrl` test bench. Rust plays everything around the frame controller:
//! - AXI client 0's memory (a golden [`Memory`] holding the descriptors; random `arready`,
//!   `rvalid` gaps, `awready`, `wready`, B latency);
//! - the N sequencers: a job is taken when the sequencer is idle and a coin says so; it
//!   completes after a random time with a `next_len` of its own choosing (a function of the
//!   tile), held on `cpl_len_i[k]` until taken;
//! - the M raster cores: a command is taken when the core is idle (random), `ras_done_i` pulses
//!   after a random time;
//! - the bridges' `idle_i`: random bits.
//!
//! The checker: every non-overflowing tile is handed to a sequencer exactly once, in tile
//! order, with the descriptor's fields, the frame parity and that sequencer's scratch base, to
//! the sequencer the scheduler policy names; overflowing tiles never; every tile is rastered
//! exactly once, after its sort completed, with `len` = the sequencer's `next_len` (0 when it
//! overflowed), `table = next`, its tile_x/y, `feat = FEAT_BASE/32`, `pix = FB_BASE/4 + t
//! tile^2`; descriptor reads are 4-beat INCR bursts at `DESC_BASE + 32 t` in tile order; each
//! result is written once (1 beat, all strobes) with the right value; `done_o` rises only after
//! all of that, with every B back and every `idle_i` high the cycle before; `FIRST_OVERFLOW` and
//! `OVERFLOWS` equal golden's.

use crate::bits::mask;
use crate::check::Checker;
use crate::dut::Dut;
use crate::models::NeoFrameCtrl;
use crate::rng::Rng;
use neo_gen::{EngineConfig, SchedulerPolicy};
use neo_golden::engine::memory::MAX_DPS_PASSES;
use neo_golden::engine::{FrameRegs, Memory, TileDescriptor, TileResult};
use std::collections::VecDeque;

/// One frame: the registers and the descriptors.
#[derive(Clone, Debug)]
pub struct FrameCase {
    /// Registers (`tiles` = `descs.len()`).
    pub regs: FrameRegs,
    /// Tile descriptors; `next` must be unique per tile (the bench identifies tiles by it).
    pub descs: Vec<TileDescriptor>,
}

/// What the frame took.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FrameRun {
    /// Cycles from start to done.
    pub cycles: u64,
    /// Tiles that overflowed.
    pub overflows: u32,
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
/// (8-byte aligned: one beat a result) anywhere in the 32-bit address space with their regions
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
            }
        })
        .collect();
    let (desc_bytes, result_bytes) = (32 * tiles as u64, 8 * tiles as u64);
    let desc_base = 32 * rng.below(((1u64 << 32) - desc_bytes) / 32 + 1);
    let result_base = loop {
        let b = 8 * rng.below(((1u64 << 32) - result_bytes) / 8 + 1);
        if b + result_bytes <= desc_base || desc_base + desc_bytes <= b {
            break b;
        }
    };
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
    };
    FrameCase { regs, descs }
}

/// A sequencer model: the tile it sorts, when it completes, and the `next_len`.
#[derive(Clone, Copy, Debug)]
struct SeqModel {
    tile: u64,
    due: u64,
    len: u64,
}

/// The frame controller with its surroundings.
pub struct FrameBench {
    /// The model.
    pub dut: NeoFrameCtrl,
    /// Mismatch reporting.
    pub checker: Checker,
    cfg: EngineConfig,
    rng: Rng,
}

impl FrameBench {
    /// A reset frame controller.
    pub fn new(cfg: &EngineConfig, seed: u64) -> FrameBench {
        let mut dut = NeoFrameCtrl::new();
        dut.reset();
        FrameBench {
            dut,
            checker: Checker::new(NeoFrameCtrl::NAME, seed),
            cfg: cfg.clone(),
            rng: Rng::new(seed).fork(9),
        }
    }

    fn set(&mut self, name: &str, v: u64) {
        let p = NeoFrameCtrl::port(name);
        self.dut.set_words(p, &[v as u32, (v >> 32) as u32]);
    }

    fn get(&self, name: &str) -> u64 {
        self.dut.get_u64(NeoFrameCtrl::port(name))
    }

    fn get_lane(&self, name: &str, k: usize, width: u32) -> u64 {
        let p = NeoFrameCtrl::port(name);
        let mut w = vec![0u32; NeoFrameCtrl::PORTS[p].words()];
        self.dut.get_words(p, &mut w);
        let lo = k as u32 * width;
        (0..width)
            .fold(0, |acc, b| acc | (((w[((lo + b) / 32) as usize] >> ((lo + b) % 32)) & 1) as u64) << b)
    }

    fn set_lanes(&mut self, name: &str, vals: &[u64], width: u32) {
        let p = NeoFrameCtrl::port(name);
        let mut w = vec![0u32; NeoFrameCtrl::PORTS[p].words()];
        for (k, v) in vals.iter().enumerate() {
            for b in 0..width {
                if (v >> b) & 1 == 1 {
                    let bit = k as u32 * width + b;
                    w[(bit / 32) as usize] |= 1 << (bit % 32);
                }
            }
        }
        self.dut.set_words(p, &w);
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
        }
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
        ] {
            self.set(p, v);
        }
        let start = self.dut.cycle();
        let limit = start + 3000 + 300 * tiles as u64;
        // Models' state.
        let mut seqs: Vec<Option<SeqModel>> = vec![None; n];
        let mut rasters: Vec<Option<u64>> = vec![None; m];
        let mut sorted = vec![false; tiles]; // job taken
        let mut sort_done: Vec<Option<u64>> = vec![None; tiles]; // completion taken: next_len
        let mut rastered = vec![false; tiles];
        let mut ras_done_count = 0usize;
        let (mut jobs, mut ras_cmds) = (0usize, 0usize);
        let mut next_fetch = 0u64;
        let mut r_beats: VecDeque<(u64, u64, bool)> = VecDeque::new(); // (due, data, last)
        let mut aw_q: VecDeque<u64> = VecDeque::new();
        let mut w_q: VecDeque<(u64, u64)> = VecDeque::new();
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
            let c = self.dut.cycle();
            self.checker.protocol(c, c < limit, "timeout: the frame did not finish");
            let r = &mut self.rng;
            // Inputs.
            let start_pulse = !started;
            let job_ready: Vec<u64> = seqs.iter().map(|s| (s.is_none() && r.percent(60)) as u64).collect();
            let cpl_valid: Vec<u64> = seqs.iter().map(|s| s.is_some_and(|s| s.due <= c) as u64).collect();
            // A lane without cpl_valid carries any 32-bit value (the controller must not take it).
            let cpl_len: Vec<u64> =
                seqs.iter().map(|s| s.map_or(r.next_u64() & mask(lw), |s| s.len)).collect();
            let stalled = stall && (c / 128).is_multiple_of(3);
            let ras_ready: Vec<u64> =
                rasters.iter().map(|s| (s.is_none() && !stalled && r.percent(60)) as u64).collect();
            let mut ras_done = vec![0u64; m];
            for (j, s) in rasters.iter_mut().enumerate() {
                if s.is_some_and(|due| due <= c) {
                    ras_done[j] = 1;
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
            self.set_lanes("ras_ready_i", &ras_ready, 1);
            self.set_lanes("ras_done_i", &ras_done, 1);
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
            self.dut.eval();
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
                self.checker.protocol(
                    c,
                    b_due.is_empty() && aw_q.is_empty(),
                    "done with a result write in flight",
                );
                for t in 0..tiles {
                    self.checker.value(c, &format!("result {t} writes"), 1, writes[t] as u64);
                    let want = match sort_done[t] {
                        _ if ovf[t] => TileResult { next_len: 0, overflow: true },
                        Some(l) => TileResult { next_len: l as u32, overflow: false },
                        None => self.checker.fail(c, &format!("tile {t}"), "sorted", "never completed"),
                    };
                    let got = mem.read_result(regs.result_base, t as u64);
                    self.checker.value(c, &format!("result {t}"), want.to_word(), got.to_word());
                }
                self.checker.value(c, "first_overflow_o", want_first as u64, self.get("first_overflow_o"));
                self.checker.value(c, "overflows_o", want_ovfs as u64, self.get("overflows_o"));
                self.checker.value(c, "overflow_o", (want_ovfs > 0) as u64, self.get("overflow_o"));
                self.dut.tick();
                return FrameRun { cycles: c - start, overflows: want_ovfs };
            } else if !start_pulse && c > start + 1 {
                self.checker.protocol(c, busy, "busy fell");
            }
            was_busy = busy || start_pulse;
            prev_idle_all = idle_all;

            // AXI reads.
            if arready && self.get("m_axi_arvalid_o") == 1 {
                let addr = self.get("m_axi_araddr_o");
                self.checker.value(c, "araddr", regs.desc_base + 32 * next_fetch, addr);
                self.checker.value(c, "arlen", 3, self.get("m_axi_arlen_o"));
                self.checker.value(c, "arsize", 3, self.get("m_axi_arsize_o"));
                self.checker.value(c, "arburst", 1, self.get("m_axi_arburst_o"));
                self.checker.protocol(c, (next_fetch as usize) < tiles, "descriptor read past TILES");
                let words = case.descs[next_fetch as usize].to_words();
                let due = c + 1 + self.rng.below(6);
                for (i, w) in words.iter().enumerate() {
                    r_beats.push_back((due, *w, i == 3));
                }
                next_fetch += 1;
            }
            if rbeat.is_some() && self.get("m_axi_rready_o") == 1 {
                r_beats.pop_front();
            }
            // AXI writes.
            if awready && self.get("m_axi_awvalid_o") == 1 {
                self.checker.value(c, "awlen", 0, self.get("m_axi_awlen_o"));
                self.checker.value(c, "awsize", 3, self.get("m_axi_awsize_o"));
                aw_q.push_back(self.get("m_axi_awaddr_o"));
            }
            if wready && self.get("m_axi_wvalid_o") == 1 {
                self.checker.value(c, "wstrb", 0xff, self.get("m_axi_wstrb_o"));
                self.checker.value(c, "wlast", 1, self.get("m_axi_wlast_o"));
                w_q.push_back((self.get("m_axi_wdata_o"), c));
            }
            while !aw_q.is_empty() && !w_q.is_empty() {
                let (a, (data, _)) = (aw_q.pop_front().unwrap(), w_q.pop_front().unwrap());
                let off = a.wrapping_sub(regs.result_base);
                let t = (off / 8) as usize;
                self.checker.protocol(c, off % 8 == 0 && t < tiles, &format!("result write at 0x{a:x}"));
                mem.write_u64(a, data);
                writes[t] += 1;
                b_due.push_back(c + 1 + self.rng.below(60));
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
                    ("job_dps_passes_o", d.passes()),
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
                // Quick sorts and, half of the time, slow ones: then every sequencer gets busy (the
                // high-index completions of the first-free scheduler are exercised too).
                let slow = self.rng.percent(50);
                let due = c + 1 + if slow { self.rng.below(1000) } else { self.rng.below(40) };
                seqs[k] = Some(SeqModel { tile: t as u64, due, len: model_next_len(t as u64, d, cap) });
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
                let want_j = match cfg.scheduler {
                    SchedulerPolicy::RoundRobin => ras_cmds % m,
                    SchedulerPolicy::FirstFree => (0..m).find(|&i| ras_ready[i] == 1).unwrap_or(m),
                };
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
                rasters[j] = Some(if align { (due | 31) + 1 } else { due });
            }
            self.dut.tick();
        }
    }
}
