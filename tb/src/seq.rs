//! The `neo_sort_seq` test bench. Rust plays the sequencer's surroundings:
//! - the job driver offers one tile job (after a random gap; random payload while idle);
//! - the Sorting Core model takes commands when it chooses (random `cmd_ready_i`), executes
//!   each one on a golden [`Memory`] with golden [`run_command`] (`sort_chunk` / `merge2`) and
//!   answers with `done_i` pulses in order, at least two cycles apart, after a random latency,
//!   `done_len_i` = the entries written, held between pulses (as `neo_sort_core` does), and
//!   `done_inv_i` a random count per pulse (the completion must forward the MERGE_DELETE's);
//! - the bridge model raises `idle_i` now and then while commands are in flight (between their
//!   bursts), and holds it low for a random time after each `done_i` (its writes draining);
//! - the completion sink takes `cpl_valid_o` under random backpressure.
//!
//! The golden model is [`tile_plan`] (the commands, stage by stage) and the plan executed on a
//! copy of the memory (the tile's `next_len`). The checker compares every command taken with
//! the plan's next one field by field, checks the barrier before every stage after the first
//! and before the completion (every earlier command done, then `idle_i` high in a later cycle),
//! the completion's `cpl_len_o` and `cpl_inv_o` (the MERGE_DELETE's `done_inv_i`, 0 from
//! scratch), and the handshakes (an offered command held until taken).

use crate::bits::mask;
use crate::check::Checker;
use crate::dut::Clocked;
use crate::dynmodel::DynModel;
use crate::models::NeoSortSeq;
use crate::rng::Rng;
use crate::stimulus::entry_space;
use neo_gen::EngineConfig;
use neo_golden::engine::{run_command, tile_plan, FrameRegs, Memory, TileCmd, TileDescriptor};
use neo_golden::sort::{SortMode, Sorter};
use std::collections::VecDeque;

/// Timing of the sequencer's surroundings.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SeqTiming {
    /// Probability (percent) that `cmd_ready_i` is high in a cycle.
    pub cmd_ready_pct: u32,
    /// Cycles from a command's acceptance to its `done_i`, at least.
    pub min_done: u64,
    /// ... at most.
    pub max_done: u64,
    /// Longest time `idle_i` stays low after a `done_i` (cycles).
    pub max_drain: u64,
    /// Probability (percent) that `cpl_ready_i` is high in a cycle.
    pub cpl_ready_pct: u32,
    /// Longest gap before a job is offered (cycles).
    pub max_job_gap: u64,
    /// Probability (percent) that `idle_i` is high in a cycle while a command is in flight.
    pub idle_busy_pct: u32,
}

impl SeqTiming {
    /// Always ready, quick done pulses, the bridge idle at once.
    pub const FAST: SeqTiming = SeqTiming {
        cmd_ready_pct: 100,
        min_done: 1,
        max_done: 2,
        max_drain: 0,
        cpl_ready_pct: 100,
        max_job_gap: 0,
        idle_busy_pct: 0,
    };
    /// Random stalls, slow and late done pulses, long drains.
    pub const RANDOM: SeqTiming = SeqTiming {
        cmd_ready_pct: 50,
        min_done: 1,
        max_done: 30,
        max_drain: 25,
        cpl_ready_pct: 60,
        max_job_gap: 5,
        idle_busy_pct: 30,
    };
    /// Always ready, every done pulse 600 to 700 cycles late: a whole stage of a tile at the
    /// table capacity (`capacity / C + 1` commands) is in flight before its first done.
    pub const LATE_DONE: SeqTiming = SeqTiming { min_done: 600, max_done: 700, ..SeqTiming::FAST };
}

/// One tile job: the descriptor, the frame (registers `frame` and `scratch_base`) and the core.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SeqJob {
    /// The descriptor.
    pub desc: TileDescriptor,
    /// The frame's registers (only `frame` and `scratch_base` matter).
    pub regs: FrameRegs,
    /// The sorting core the sequencer drives.
    pub core: u64,
}

/// What a tile took.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SeqRun {
    /// Commands issued.
    pub commands: usize,
    /// Stages.
    pub stages: usize,
    /// Cycles from the job's acceptance to the completion's.
    pub cycles: u64,
    /// The completion's `next_len`.
    pub next_len: u64,
    /// The commands the sequencer issued, in order (each already checked against the plan).
    pub cmds: Vec<TileCmd>,
    /// The most commands taken and not yet done at once.
    pub max_in_flight: usize,
}

/// The golden side of one job: the plan and the tile's `next_len`.
struct Expected {
    cmds: Vec<(usize, TileCmd)>,
    stages: usize,
    next_len: u64,
}

impl Expected {
    fn new(cfg: &EngineConfig, job: &SeqJob, mem: &Memory) -> Expected {
        let plan = tile_plan(cfg, &job.regs, &job.desc, job.core);
        assert!(!plan.overflow, "the bench only sends tiles that fit: {:?}", job.desc);
        let mut copy = mem.clone();
        let mut sorter = Sorter::new(cfg.buffer_sort_config());
        let mut next_len = job.desc.list_len as u64;
        for c in plan.commands() {
            let e = run_command(&mut sorter, &mut copy, c).expect("bench data has no reserved id");
            if c.mode == SortMode::MergeDelete {
                next_len = e.written;
            }
        }
        let cmds = plan.stages.iter().enumerate().flat_map(|(s, v)| v.iter().map(move |c| (s, *c))).collect();
        Expected { cmds, stages: plan.stages.len(), next_len }
    }
}

/// The sequencer's ports (indices into the model's).
struct Ports {
    job_valid: usize,
    job_ready: usize,
    /// `job_from_scratch_i`, `job_prev_i`, `job_prev_len_i`, `job_list_i`, `job_list_len_i`,
    /// `job_next_i`, `job_dps_passes_i`, `job_dps_wide_i`, `job_odd_i`, `job_scratch_i`.
    job: [usize; 10],
    cmd_valid: usize,
    cmd_ready: usize,
    /// `cmd_mode_o`, `cmd_src_a_o`, `cmd_len_a_o`, `cmd_src_b_o`, `cmd_len_b_o`, `cmd_dst_o`.
    cmd: [usize; 6],
    done: usize,
    done_len: usize,
    done_inv: usize,
    idle: usize,
    cpl_valid: usize,
    cpl_ready: usize,
    cpl_len: usize,
    cpl_inv: usize,
}

impl Ports {
    fn of<M: Clocked>(dut: &M) -> Self {
        let p = |n: &str| dut.pin(n);
        Ports {
            job_valid: p("job_valid_i"),
            job_ready: p("job_ready_o"),
            job: [
                "job_from_scratch_i",
                "job_prev_i",
                "job_prev_len_i",
                "job_list_i",
                "job_list_len_i",
                "job_next_i",
                "job_dps_passes_i",
                "job_dps_wide_i",
                "job_odd_i",
                "job_scratch_i",
            ]
            .map(p),
            cmd_valid: p("cmd_valid_o"),
            cmd_ready: p("cmd_ready_i"),
            cmd: ["cmd_mode_o", "cmd_src_a_o", "cmd_len_a_o", "cmd_src_b_o", "cmd_len_b_o", "cmd_dst_o"]
                .map(p),
            done: p("done_i"),
            done_len: p("done_len_i"),
            done_inv: p("done_inv_i"),
            idle: p("idle_i"),
            cpl_valid: p("cpl_valid_o"),
            cpl_ready: p("cpl_ready_i"),
            cpl_len: p("cpl_len_o"),
            cpl_inv: p("cpl_inv_o"),
        }
    }
}

/// The sequencer with its surroundings, on the statically linked model of the crate's
/// configuration ([`SeqBench::new`]) or on one built for any configuration ([`SeqBench::build`]).
pub struct SeqBench<M: Clocked = NeoSortSeq> {
    /// The model.
    pub dut: M,
    /// Mismatch reporting.
    pub checker: Checker,
    /// The memory the core model works on.
    pub mem: Memory,
    ports: Ports,
    cfg: EngineConfig,
    sorter: Sorter,
    timing: SeqTiming,
    rng: Rng,
    done_len: u64,
    done_inv: u64,
}

/// A command taken by the core model and not yet done: (due cycle, done_len, done_inv).
type Pending = VecDeque<(u64, u64, u64)>;

impl SeqBench<NeoSortSeq> {
    /// A reset sequencer (the static model of [`crate::config`]) whose surroundings follow
    /// `timing`.
    pub fn new(cfg: &EngineConfig, seed: u64, timing: SeqTiming) -> Self {
        SeqBench::with_model(NeoSortSeq::new(), cfg, seed, timing)
    }
}

impl SeqBench<DynModel> {
    /// A reset sequencer of any configuration `cfg` (`neo_sort_seq` built at run time, or
    /// loaded from the cache: [`crate::configs::build`]).
    pub fn build(cfg: &EngineConfig, seed: u64, timing: SeqTiming) -> Result<Self, String> {
        let dut = crate::configs::build(cfg, "neo_sort_seq")?;
        Ok(SeqBench::with_model(dut, cfg, seed, timing))
    }
}

impl<M: Clocked> SeqBench<M> {
    /// A reset sequencer on model `dut` (`neo_sort_seq` generated from `cfg`).
    pub fn with_model(mut dut: M, cfg: &EngineConfig, seed: u64, timing: SeqTiming) -> Self {
        let ports = Ports::of(&dut);
        for p in [ports.job_valid, ports.cmd_ready, ports.done, ports.cpl_ready] {
            dut.io_set(p, 0);
        }
        dut.io_set(ports.idle, 1);
        dut.io_reset();
        let checker = Checker::new(dut.top(), seed);
        SeqBench {
            dut,
            checker,
            mem: Memory::new(),
            ports,
            cfg: cfg.clone(),
            sorter: Sorter::new(cfg.buffer_sort_config()),
            timing,
            rng: Rng::new(seed).fork(7),
            done_len: 0,
            done_inv: 0,
        }
    }

    /// Restarts the bench's random stream and its checker's seed from `seed`, as a bench made
    /// with `seed` has them.
    pub fn reseed(&mut self, seed: u64) {
        self.rng = Rng::new(seed).fork(7);
        self.checker = Checker::new(self.dut.top(), seed);
    }

    /// Changes the timing.
    pub fn set_timing(&mut self, timing: SeqTiming) {
        self.timing = timing;
    }

    fn drive_job(&mut self, job: Option<&SeqJob>) {
        let r = &mut self.rng;
        let (valid, d, odd, scratch) = match job {
            Some(j) => {
                let s = neo_golden::engine::plan::scratch_entry_base(&self.cfg, &j.regs, j.core);
                (true, j.desc, j.regs.frame & 1 == 1, s)
            }
            None => {
                let w = [r.next_u64(), r.next_u64(), r.next_u64(), r.next_u64()];
                (false, TileDescriptor::from_words(&w), r.percent(50), r.next_u64())
            }
        };
        let fields = [
            d.from_scratch as u64,
            d.prev as u64,
            d.prev_len as u64,
            d.list as u64,
            d.list_len as u64,
            d.next as u64,
            d.passes(),
            d.dps_wide as u64,
            odd as u64,
            scratch & mask(self.cfg.addr_bits),
        ];
        self.dut.io_set(self.ports.job_valid, valid as u64);
        for (&p, v) in self.ports.job.iter().zip(fields) {
            self.dut.io_set(p, v);
        }
    }

    fn offered(&self) -> TileCmd {
        let [mode, src_a, len_a, src_b, len_b, dst] = self.ports.cmd.map(|p| self.dut.io_get(p));
        let mode = SortMode::ALL.into_iter().find(|m| m.code() == mode).expect("2-bit mode");
        TileCmd { mode, src_a, len_a, src_b, len_b, dst }
    }

    /// Runs one tile job to its completion and checks it (see the module docs).
    ///
    /// # Panics
    /// At the first mismatch, protocol violation or timeout.
    pub fn run(&mut self, job: &SeqJob) -> SeqRun {
        let want = Expected::new(&self.cfg, job, &self.mem);
        let work: u64 = want.cmds.iter().map(|(_, c)| c.len_a + c.len_b).sum();
        let limit = self.dut.io_cycle() + 2000 + 200 * want.cmds.len() as u64 + work / 4;
        let t = self.timing;
        let mut gap = self.rng.below(t.max_job_gap + 1);
        let (mut accepted_at, mut taken) = (None, 0usize);
        let mut pending: Pending = VecDeque::new();
        let mut last_done: Option<u64> = None;
        let mut idle_since_done = true;
        let mut busy_until = 0u64;
        let mut held: Option<TileCmd> = None;
        let mut issued = Vec::new();
        let mut max_in_flight = 0;
        let mut md_inv = 0;
        loop {
            let c = self.dut.io_cycle();
            self.checker.protocol(c, c < limit, &format!("timeout: tile {:?} not completed", job.desc));
            // Job driver.
            let offer_job = accepted_at.is_none() && gap == 0;
            gap = gap.saturating_sub(1);
            self.drive_job(offer_job.then_some(job));
            // Core model: done pulses in order, two cycles apart at least.
            let pulse = match (pending.front(), last_done) {
                (Some(&(due, ..)), l) if due <= c && l.is_none_or(|l| c >= l + 2) => pending.pop_front(),
                _ => None,
            };
            if let Some((_, len, inv)) = pulse {
                self.done_len = len;
                self.done_inv = inv;
                last_done = Some(c);
                busy_until = c + 1 + self.rng.below(t.max_drain + 1);
                idle_since_done = false;
            }
            self.dut.io_set(self.ports.done, pulse.is_some() as u64);
            self.dut.io_set(self.ports.done_len, self.done_len);
            self.dut.io_set(self.ports.done_inv, self.done_inv);
            // Bridge model: idle now and then while commands run (between their bursts), and
            // for sure only once they are done and their writes drained.
            let idle = if pending.is_empty() { c >= busy_until } else { self.rng.percent(t.idle_busy_pct) };
            self.dut.io_set(self.ports.idle, idle as u64);
            if idle && pulse.is_none() {
                idle_since_done = true;
            }
            let ready = self.rng.percent(t.cmd_ready_pct);
            self.dut.io_set(self.ports.cmd_ready, ready as u64);
            let cpl_ready = self.rng.percent(t.cpl_ready_pct);
            self.dut.io_set(self.ports.cpl_ready, cpl_ready as u64);
            self.dut.io_eval();

            // Checker.
            if offer_job && self.dut.flag(self.ports.job_ready) {
                accepted_at = Some(c);
            }
            let valid = self.dut.flag(self.ports.cmd_valid);
            if let Some(h) = held {
                self.checker.protocol(c, valid, "cmd_valid_o dropped before the command was taken");
                self.checker.protocol(
                    c,
                    self.offered() == h,
                    "the offered command changed before it was taken",
                );
            }
            held = None;
            if valid {
                self.checker.protocol(c, accepted_at.is_some(), "a command before any job was taken");
                let got = self.offered();
                if let Some(&(stage, _)) = want.cmds.get(taken) {
                    if stage > 0 && want.cmds[taken - 1].0 != stage {
                        barrier(
                            &self.checker,
                            c,
                            &format!("before stage {stage}"),
                            &pending,
                            idle_since_done,
                        );
                    }
                }
                if !ready {
                    held = Some(got);
                } else {
                    let Some(&(_, exp)) = want.cmds.get(taken) else {
                        self.checker.fail(
                            c,
                            &format!("command {taken}"),
                            "no more commands",
                            &format!("{got:x?}"),
                        );
                    };
                    compare(&self.checker, c, taken, &exp, &got);
                    issued.push(got);
                    let e = run_command(&mut self.sorter, &mut self.mem, &got).unwrap_or_else(|a| {
                        self.checker.fail(c, "command data", "no reserved id", &format!("0x{a:x}"))
                    });
                    let due = c + self.rng.range(t.min_done, t.max_done);
                    // Every command reports some count (the core's are 0 for chunks): the
                    // completion must carry the MERGE_DELETE's.
                    let inv = self.rng.next_u32() as u64;
                    if got.mode == SortMode::MergeDelete {
                        md_inv = inv;
                    }
                    pending.push_back((due.max(pending.back().map_or(0, |p| p.0)), e.written, inv));
                    max_in_flight = max_in_flight.max(pending.len());
                    taken += 1;
                }
            }
            if self.dut.flag(self.ports.cpl_valid) {
                self.checker.value(
                    c,
                    "commands issued before the completion",
                    want.cmds.len() as u64,
                    taken as u64,
                );
                barrier(&self.checker, c, "before the completion", &pending, idle_since_done);
                self.checker.value(c, "cpl_len_o", want.next_len, self.dut.io_get(self.ports.cpl_len));
                self.checker.value(
                    c,
                    "cpl_inv_o (the MERGE_DELETE's done_inv_i)",
                    md_inv,
                    self.dut.io_get(self.ports.cpl_inv),
                );
                if cpl_ready {
                    self.dut.io_tick();
                    let start = accepted_at.expect("a completion follows a job");
                    return SeqRun {
                        commands: taken,
                        stages: want.stages,
                        cycles: c - start,
                        next_len: want.next_len,
                        cmds: issued,
                        max_in_flight,
                    };
                }
            }
            self.dut.io_tick();
        }
    }
}

/// The first differing field of command `i`.
fn compare(ck: &Checker, cycle: u64, i: usize, want: &TileCmd, got: &TileCmd) {
    let fields = [
        ("mode", want.mode.code(), got.mode.code()),
        ("src_a", want.src_a, got.src_a),
        ("len_a", want.len_a, got.len_a),
        ("src_b", want.src_b, got.src_b),
        ("len_b", want.len_b, got.len_b),
        ("dst", want.dst, got.dst),
    ];
    for (f, w, g) in fields {
        ck.value(cycle, &format!("command {i} ({:?}).{f}", want.mode), w, g);
    }
}

/// The barrier: every command done and the bridge seen idle after the last `done_i`.
fn barrier(ck: &Checker, cycle: u64, what: &str, pending: &Pending, idle_since_done: bool) {
    ck.protocol(cycle, pending.is_empty(), &format!("barrier {what}: {} command(s) not done", pending.len()));
    ck.protocol(cycle, idle_since_done, &format!("barrier {what}: idle_i not seen since the last done_i"));
}

/// Random entries of a tile's list (`n`) and previous table (`prev_len`, sorted, some invalid)
/// written where `job` says.
pub fn fill(cfg: &EngineConfig, rng: &mut Rng, mem: &mut Memory, d: &TileDescriptor) {
    let fmt = cfg.format();
    let ties = rng.percent(30);
    let list = crate::stimulus::tile_entries(&fmt, rng, d.list_len as usize, ties, 100);
    mem.write_entries(&fmt, d.list as u64, &list);
    if !d.from_scratch {
        let ties = rng.percent(30);
        let mut prev = crate::stimulus::tile_entries(&fmt, rng, d.prev_len as usize, ties, 70);
        prev.sort_by_key(|e| e.order_key());
        let prev = crate::stimulus::nearly_sorted(prev, rng, cfg.chunk / 2, d.prev_len as usize / 8);
        mem.write_entries(&fmt, d.prev as u64, &prev);
    }
}

/// A random descriptor: list and previous lengths drawn from the edge cases (0, 1, `C - 1`, `C`,
/// `C + 1`, and `W / 2`, `W`, `W + 1` of the wide chunk) or up to `max_chunks` chunks, and now and then a table or a list as long as what is
/// left of the table capacity; its previous table, list and next table in three consecutive
/// regions of 2^17 entries at a random place in one half of the entry space below 2^29 (the
/// entry addresses' upper bits toggle; [`random_scratch_base`] puts the scratch regions in the
/// other half); mostly Neo's single DPS pass, else 0, 2, 3, 8 or 15 passes; 30% in the wide
/// chunk.
pub fn random_desc(cfg: &EngineConfig, rng: &mut Rng, max_chunks: u64) -> TileDescriptor {
    let c = cfg.chunk as u64;
    let len = |rng: &mut Rng| -> u32 {
        let w = cfg.sort_buffer() as u64;
        let edge = [0, 1, c / 2 - 1, c / 2, c / 2 + 1, c - 1, c, c + 1, 2 * c, 2 * c + 1, 4 * c + 1];
        let wide_edge = [w / 2 - 1, w / 2 + 1, w, w + 1, 2 * w + 1];
        if rng.percent(40) {
            *rng.pick(&edge) as u32
        } else if rng.percent(15) {
            *rng.pick(&wide_edge) as u32
        } else {
            rng.range(0, max_chunks * c) as u32
        }
    };
    let cap = cfg.table_capacity as u64;
    let long =
        |rng: &mut Rng, room: u64| if rng.percent(4) { Some(rng.range(0, room + 1) as u32) } else { None };
    let prev_len = long(rng, cap).unwrap_or_else(|| len(rng));
    // Within what is left: a long table leaves little room for a list of the usual lengths.
    let list_len =
        long(rng, cap - prev_len as u64).unwrap_or_else(|| len(rng)).min((cap - prev_len as u64) as u32);
    let (region, half) = (1u64 << 17, entry_space(cfg) / 2);
    let base = half * rng.below(2) + rng.below(half - 3 * region);
    let at = |k: u64, rng: &mut Rng| (base + k * region + rng.below(1 << 16)) as u32;
    TileDescriptor {
        tile_x: rng.next_u32() as u16,
        tile_y: rng.next_u32() as u16,
        from_scratch: rng.percent(40),
        prev: at(0, rng),
        prev_len,
        list: at(1, rng),
        list_len,
        next: at(2, rng),
        dps_passes: if rng.percent(60) { 1 } else { *rng.pick(&[0u8, 2, 3, 8, 15]) },
        dps_wide: rng.percent(30),
    }
}

/// A random `SCRATCH_BASE` (bytes, 8-aligned) whose scratch regions, `2 table_capacity` entries
/// for each of the sorting cores, lie in the half of the entry space below 2^29 that `d`'s
/// regions ([`random_desc`]) do not use.
pub fn random_scratch_base(cfg: &EngineConfig, rng: &mut Rng, d: &TileDescriptor) -> u64 {
    let span = 2 * (cfg.table_capacity * cfg.sort_cores) as u64;
    let half = entry_space(cfg) / 2;
    let other = if d.prev as u64 >= half { 0 } else { half };
    8 * (other + rng.below(half - span))
}
