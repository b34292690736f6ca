//! The Sorting Core test bench: a command driver, a memory model with random request stalls and
//! random response latency, and golden-checked flows for every mode:
//!
//! - (a) conventional sort: `SORT` per chunk of at most `C` entries; a longer input (e.g. 257) is
//!   sorted as golden `full_sort` does it: `SORT` per chunk, then `MERGE` passes pairing runs of
//!   `C, 2C, ...` (a lone last run is copied by a `MERGE` with an empty B);
//! - (b) DPS: one `DPS` command per chunk of a pass's parity (golden `dps_pass`);
//! - (c) merges: `MERGE_DELETE` (golden `merge2(a, b, true)`) and `MERGE` (`merge2(a, b, false)`);
//!   and the whole per-tile update (golden `update_tile`) composed from the three.
//!
//! Commands are issued back to back ([`Core::run_queue`]): the next one is offered as soon as
//! the previous one was taken, so several are in flight (the core overlaps a chunk's load with
//! the previous chunk's merge passes); [`queue_checked`] checks a mixed queue against golden.
//!
//! Memory: word-addressed by entry (`mem_req_addr_o` is an entry index). A read request of
//! `len` entries (read port) is answered by `len` response beats in request order, the first
//! after a random latency (the data is read when the request is taken); a write (write port)
//! carries one entry. A read outside the sources of the commands in flight, a write outside
//! the destination of the oldest one (commands complete in order), a second write of one command
//! to the same address ([`WriteOnce`]), and a request or write whose valid or payload depends on
//! ready or changes before it is taken ([`Handshake`]) are protocol errors.

use crate::check::{Checker, WriteOnce};
use crate::dut::Clocked;
use crate::dynmodel::DynModel;
use crate::models::NeoSortCore;
use crate::rng::Rng;
use crate::stream::Handshake;
use neo_gen::EngineConfig;
use neo_golden::engine::{tile_steps, TileRegion, TileShape};
use neo_golden::sort::{merge2, merge_pass_count, Parity, SortEntry, SortFormat};
use std::collections::{HashMap, VecDeque};
use std::ops::Range;

/// Command modes (`cmd_mode_i`): golden's, with the RTL's codes.
pub use neo_golden::sort::SortMode as Mode;

/// One command at entry addresses (golden's, the fields of `cmd_*_i`).
pub use neo_golden::engine::TileCmd as Command;

/// Timing of the memory model.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MemTiming {
    /// Probability (percent) that `mem_req_ready_i` (read requests) is high in a cycle.
    pub req_ready_pct: u32,
    /// Probability (percent) that `mem_wr_ready_i` (writes) is high in a cycle.
    pub wr_ready_pct: u32,
    /// Read latency range (cycles from the request's acceptance to its first response beat).
    pub min_latency: u32,
    /// Upper end of the latency range.
    pub max_latency: u32,
    /// Probability (percent) of a gap (no response offered) in a cycle when one is due.
    pub rsp_gap_pct: u32,
}

impl MemTiming {
    /// An ideal memory: always ready, first beat the cycle after the request, no gaps.
    pub const IDEAL: MemTiming =
        MemTiming { req_ready_pct: 100, wr_ready_pct: 100, min_latency: 1, max_latency: 1, rsp_gap_pct: 0 };
    /// A hostile memory: frequent stalls and gaps, latency 1..40 cycles.
    pub const RANDOM: MemTiming =
        MemTiming { req_ready_pct: 60, wr_ready_pct: 60, min_latency: 1, max_latency: 40, rsp_gap_pct: 25 };
    /// Fast reads, slow writes (a quarter of the cycles): the write-back lags far behind the
    /// next commands' loads, so a buffer reused too early shows up.
    pub const SLOW_WRITES: MemTiming =
        MemTiming { req_ready_pct: 100, wr_ready_pct: 25, min_latency: 1, max_latency: 1, rsp_gap_pct: 0 };
    /// Worst case: long stalls everywhere (requests and writes taken in one cycle of ten, read
    /// latency 30..120 cycles, a gap in half the cycles a response is due).
    pub const LONG_STALLS: MemTiming =
        MemTiming { req_ready_pct: 10, wr_ready_pct: 10, min_latency: 30, max_latency: 120, rsp_gap_pct: 50 };
}

/// What a command did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CmdResult {
    /// Rising edges from the one that accepts the command (`cmd_valid_i & cmd_ready_o`) to the
    /// cycle with its `done_o` pulse (at least 1); with commands in flight before it, this
    /// includes the time it waited for them.
    pub cycles: u64,
    /// Cycle of the accepting edge.
    pub accepted_at: u64,
    /// Cycle of the `done_o` pulse.
    pub done_at: u64,
    /// `done_len_o`.
    pub done_len: u64,
    /// `done_inv_o`.
    pub done_inv: u64,
    /// Read requests issued for the command.
    pub read_bursts: u64,
    /// Entries read for the command.
    pub entries_read: u64,
    /// Entries written by the command.
    pub entries_written: u64,
}

/// A command queue run back to back: every command offered as soon as the previous one was
/// taken (after the random gap of [`Core::set_cmd_gap`], and after any earlier command whose
/// output it reads is done).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct QueueRun {
    /// Per command, in order.
    pub results: Vec<CmdResult>,
    /// Cycles from the edge that accepts the first command to the last `done_o` pulse.
    pub span: u64,
}

/// A command accepted and not yet done.
struct InFlight {
    index: usize,
    reads: [Range<u64>; 2],
    write: Range<u64>,
    accepted_at: u64,
    read_bursts: u64,
    entries_read: u64,
    entries_written: u64,
    /// Addresses this command wrote (a second write to one is a protocol violation).
    written: WriteOnce,
}

/// Entry ranges `cmd` reads (A, B).
fn reads(cmd: &Command) -> [Range<u64>; 2] {
    match cmd.mode {
        Mode::Sort | Mode::Dps => [cmd.src_a..cmd.src_a + cmd.len_a, 0..0],
        Mode::MergeDelete | Mode::Merge => {
            [cmd.src_a..cmd.src_a + cmd.len_a, cmd.src_b..cmd.src_b + cmd.len_b]
        }
    }
}

/// The entry range `cmd` may write (before deletions / the chunk clamp).
fn write_range(cmd: &Command) -> Range<u64> {
    let out = match cmd.mode {
        Mode::Sort | Mode::Dps => cmd.len_a,
        Mode::MergeDelete | Mode::Merge => cmd.len_a + cmd.len_b,
    };
    cmd.dst..cmd.dst + out
}

fn overlaps(a: &Range<u64>, b: &Range<u64>) -> bool {
    a.start < b.end && b.start < a.end
}

/// The memory model.
struct Memory {
    /// The protocol checkers of the read-request and write ports.
    req_hs: Handshake,
    wr_hs: Handshake,
    words: HashMap<u64, u64>,
    timing: MemTiming,
    rng: Rng,
    /// Response beats due: (cycle from which it may be offered, data).
    rsp: VecDeque<(u64, u64)>,
    offering: bool,
    /// Commands accepted and not done, oldest first.
    inflight: VecDeque<InFlight>,
}

/// The Sorting Core's ports (indices into the model's).
struct Ports {
    cmd_valid: usize,
    cmd_ready: usize,
    /// `cmd_mode_i`, `cmd_src_a_i`, `cmd_len_a_i`, `cmd_src_b_i`, `cmd_len_b_i`, `cmd_dst_i`.
    cmd: [usize; 6],
    done: usize,
    done_len: usize,
    done_inv: usize,
    req_valid: usize,
    req_ready: usize,
    req_addr: usize,
    req_len: usize,
    rsp_valid: usize,
    rsp_ready: usize,
    rsp_data: usize,
    wr_valid: usize,
    wr_ready: usize,
    wr_addr: usize,
    wr_data: usize,
}

impl Ports {
    fn of<M: Clocked>(dut: &M) -> Self {
        let p = |n: &str| dut.pin(n);
        Ports {
            cmd_valid: p("cmd_valid_i"),
            cmd_ready: p("cmd_ready_o"),
            cmd: ["cmd_mode_i", "cmd_src_a_i", "cmd_len_a_i", "cmd_src_b_i", "cmd_len_b_i", "cmd_dst_i"]
                .map(p),
            done: p("done_o"),
            done_len: p("done_len_o"),
            done_inv: p("done_inv_o"),
            req_valid: p("mem_req_valid_o"),
            req_ready: p("mem_req_ready_i"),
            req_addr: p("mem_req_addr_o"),
            req_len: p("mem_req_len_o"),
            rsp_valid: p("mem_rsp_valid_i"),
            rsp_ready: p("mem_rsp_ready_o"),
            rsp_data: p("mem_rsp_data_i"),
            wr_valid: p("mem_wr_valid_o"),
            wr_ready: p("mem_wr_ready_i"),
            wr_addr: p("mem_wr_addr_o"),
            wr_data: p("mem_wr_data_o"),
        }
    }
}

/// The Sorting Core with its memory, command driver and checker, on the statically linked model
/// of the crate's configuration ([`Core::new`]) or on one built for any configuration
/// ([`Core::build`]).
pub struct Core<M: Clocked = NeoSortCore> {
    /// The model.
    pub dut: M,
    ports: Ports,
    mem: Memory,
    /// Mismatch reporting.
    pub checker: Checker,
    fmt: SortFormat,
    burst: u64,
    rng: Rng,
    cmd_gap: u64,
    last_done_len: Option<u64>,
}

impl Core<NeoSortCore> {
    /// A reset core (the static model of [`crate::config`]) whose memory follows `timing`.
    pub fn new(cfg: &EngineConfig, seed: u64, timing: MemTiming) -> Self {
        Core::with_model(NeoSortCore::new(), cfg, seed, timing)
    }
}

impl Core<DynModel> {
    /// A reset core of any configuration `cfg` (`neo_sort_core` built at run time, or loaded
    /// from the cache: [`crate::configs::build`]) whose memory follows `timing`.
    pub fn build(cfg: &EngineConfig, seed: u64, timing: MemTiming) -> Result<Self, String> {
        let dut = crate::configs::build(cfg, "neo_sort_core")?;
        Ok(Core::with_model(dut, cfg, seed, timing))
    }
}

impl<M: Clocked> Core<M> {
    /// A reset core on model `dut` (`neo_sort_core` generated from `cfg`) whose memory follows
    /// `timing`.
    pub fn with_model(mut dut: M, cfg: &EngineConfig, seed: u64, timing: MemTiming) -> Self {
        let mut rng = Rng::new(seed);
        let ports = Ports::of(&dut);
        for p in [ports.cmd_valid, ports.req_ready, ports.rsp_valid] {
            dut.io_set(p, 0);
        }
        dut.io_reset();
        // docs/rtl.md "Memory protocol": an offered read request that is not taken may change
        // or be withdrawn, so only "valid does not depend on ready" applies to it; a write holds
        // with its data until taken.
        let bind = |what: &str, valid: &str, ready: &str, data: &[&str]| {
            Handshake::bind(&dut, what, valid, ready, data).unwrap_or_else(|e| panic!("{e}"))
        };
        let mut req_hs = bind(
            "read-request port",
            "mem_req_valid_o",
            "mem_req_ready_i",
            &["mem_req_addr_o", "mem_req_len_o"],
        );
        req_hs.check_stable = false;
        let wr_hs =
            bind("write port", "mem_wr_valid_o", "mem_wr_ready_i", &["mem_wr_addr_o", "mem_wr_data_o"]);
        let mem = Memory {
            req_hs,
            wr_hs,
            words: HashMap::new(),
            timing,
            rng: rng.fork(1),
            rsp: VecDeque::new(),
            offering: false,
            inflight: VecDeque::new(),
        };
        let checker = Checker::new(dut.top(), seed);
        Core {
            dut,
            ports,
            mem,
            checker,
            fmt: cfg.format(),
            burst: cfg.burst as u64,
            rng: rng.fork(2),
            cmd_gap: 2,
            last_done_len: None,
        }
    }

    /// Restarts the bench's random streams (memory timing, command gaps) and its checker's seed
    /// from `seed`, as a core made with `seed` has them (the memory keeps its words).
    pub fn reseed(&mut self, seed: u64) {
        let mut rng = Rng::new(seed);
        self.mem.rng = rng.fork(1);
        self.rng = rng.fork(2);
        self.checker = Checker::new(self.dut.top(), seed);
    }

    /// Changes the memory timing.
    pub fn set_timing(&mut self, timing: MemTiming) {
        self.mem.timing = timing;
    }

    /// Sets the longest random idle gap (cycles) before each command is offered (default 2; 0
    /// offers every command at once, as the cycle measurements need).
    pub fn set_cmd_gap(&mut self, max: u64) {
        self.cmd_gap = max;
    }

    /// Stores `entries` at entry address `addr`.
    pub fn write_entries(&mut self, addr: u64, entries: &[SortEntry]) {
        for (i, e) in entries.iter().enumerate() {
            self.mem.words.insert(addr + i as u64, self.fmt.pack(e));
        }
    }

    /// Reads `len` entries at `addr` (never-written words read as the all-ones word, which is no
    /// valid entry of any test, so a missing write shows up as a mismatch).
    pub fn read_entries(&self, addr: u64, len: usize) -> Vec<SortEntry> {
        (0..len as u64)
            .map(|i| self.fmt.unpack(*self.mem.words.get(&(addr + i)).unwrap_or(&u64::MAX)))
            .collect()
    }

    /// Forgets every word in `range` (so stale results cannot pass for new ones).
    pub fn clear(&mut self, range: Range<u64>) {
        self.mem.words.retain(|a, _| !range.contains(a));
    }

    /// One cycle of the memory model and the clock. Writes must fall in the destination of the
    /// oldest command in flight (commands complete in order), reads in the sources of one in
    /// flight.
    fn step(&mut self) {
        let c = self.dut.io_cycle();
        let ready = self.mem.rng.percent(self.mem.timing.req_ready_pct);
        self.dut.io_set(self.ports.req_ready, ready as u64);
        let wr_ready = self.mem.rng.percent(self.mem.timing.wr_ready_pct);
        self.dut.io_set(self.ports.wr_ready, wr_ready as u64);
        if !self.mem.offering {
            if let Some(&(due, data)) = self.mem.rsp.front() {
                if due <= c && !self.mem.rng.percent(self.mem.timing.rsp_gap_pct) {
                    self.mem.offering = true;
                    self.dut.io_set(self.ports.rsp_data, data);
                }
            }
        }
        if !self.mem.offering {
            self.dut.io_set(self.ports.rsp_data, self.mem.rng.next_u64());
        }
        self.dut.io_set(self.ports.rsp_valid, self.mem.offering as u64);
        self.dut.io_eval();
        self.mem.wr_hs.check(&mut self.dut, wr_ready, &self.checker);
        self.mem.req_hs.check(&mut self.dut, ready, &self.checker);

        if self.mem.offering && self.dut.flag(self.ports.rsp_ready) {
            self.mem.rsp.pop_front();
            self.mem.offering = false;
        }
        if wr_ready && self.dut.flag(self.ports.wr_valid) {
            let addr = self.dut.io_get(self.ports.wr_addr);
            let ok = self.mem.inflight.front().map(|f| f.write.contains(&addr));
            self.checker.protocol(
                c,
                ok == Some(true),
                &format!(
                    "write to 0x{addr:x} outside the destination of the oldest command in flight {:x?}",
                    self.mem.inflight.front().map(|f| f.write.clone())
                ),
            );
            self.mem.words.insert(addr, self.dut.io_get(self.ports.wr_data));
            let f = &mut self.mem.inflight[0];
            f.entries_written += 1;
            f.written.record(&self.checker, c, "entry", addr);
        }
        if ready && self.dut.flag(self.ports.req_valid) {
            let addr = self.dut.io_get(self.ports.req_addr);
            let len = self.dut.io_get(self.ports.req_len);
            self.checker.protocol(
                c,
                (1..=self.burst).contains(&len),
                &format!("read burst of {len} entries"),
            );
            let owner = self
                .mem
                .inflight
                .iter()
                .position(|f| f.reads.iter().any(|r| r.start <= addr && addr + len <= r.end));
            let sources: Vec<_> = self.mem.inflight.iter().map(|f| f.reads.clone()).collect();
            self.checker.protocol(
                c,
                owner.is_some(),
                &format!("read of {len} at 0x{addr:x} outside the sources in flight {sources:x?}"),
            );
            let t = self.mem.timing;
            let mut due =
                c + self.mem.rng.range(t.min_latency as u64, t.max_latency.max(t.min_latency) as u64);
            if let Some(&(last_due, _)) = self.mem.rsp.back() {
                due = due.max(last_due);
            }
            for i in 0..len {
                let data = *self.mem.words.get(&(addr + i)).unwrap_or(&0);
                self.mem.rsp.push_back((due, data));
            }
            let f = &mut self.mem.inflight[owner.unwrap_or(0)];
            f.read_bursts += 1;
            f.entries_read += len;
        }
        self.dut.io_tick();
    }

    /// Runs `cmds` back to back (each offered as soon as the previous one was taken, after a
    /// random gap of up to [`Core::set_cmd_gap`] cycles; a command that reads the output of one
    /// still in flight waits for its `done_o`) and returns each command's cost.
    ///
    /// # Panics
    /// On a timeout, a protocol violation, `done_o` with no command in flight, or `done_len_o`
    /// not held between pulses.
    pub fn run_queue(&mut self, cmds: &[Command]) -> QueueRun {
        let mut results: Vec<Option<CmdResult>> = vec![None; cmds.len()];
        let budget: u64 = cmds.iter().map(|c| 2000 + 400 * (c.len_a + c.len_b)).sum();
        let limit = self.dut.io_cycle() + budget;
        let mut next = 0;
        let mut gap = self.rng.below(self.cmd_gap + 1);
        let mut offered = false;
        let mut first_accept = None;
        loop {
            let c = self.dut.io_cycle();
            if !offered && next < cmds.len() {
                let waits = reads(&cmds[next])
                    .iter()
                    .any(|r| self.mem.inflight.iter().any(|f| overlaps(r, &f.write)));
                if gap > 0 {
                    gap -= 1;
                } else if !waits {
                    let cmd = cmds[next];
                    let fields = [cmd.mode as u64, cmd.src_a, cmd.len_a, cmd.src_b, cmd.len_b, cmd.dst];
                    for (&p, v) in self.ports.cmd.iter().zip(fields) {
                        self.dut.io_set(p, v);
                    }
                    self.dut.io_set(self.ports.cmd_valid, 1);
                    offered = true;
                }
            }
            self.dut.io_eval();
            if self.dut.flag(self.ports.done) {
                let f = self.mem.inflight.pop_front();
                self.checker.protocol(c, f.is_some(), "done_o while no command is running");
                let f = f.expect("checked");
                let done_len = self.dut.io_get(self.ports.done_len);
                results[f.index] = Some(CmdResult {
                    cycles: c - f.accepted_at,
                    accepted_at: f.accepted_at,
                    done_at: c,
                    done_len,
                    done_inv: self.dut.io_get(self.ports.done_inv),
                    read_bursts: f.read_bursts,
                    entries_read: f.entries_read,
                    entries_written: f.entries_written,
                });
                self.last_done_len = Some(done_len);
                if self.mem.inflight.is_empty() {
                    self.checker.protocol(
                        c,
                        self.mem.rsp.is_empty() && !self.mem.offering,
                        "done_o of the last command in flight with read responses pending",
                    );
                }
            } else if let Some(l) = self.last_done_len {
                self.checker.value(
                    c,
                    "done_len_o (held between done_o pulses)",
                    l,
                    self.dut.io_get(self.ports.done_len),
                );
            }
            let accepted = offered && self.dut.flag(self.ports.cmd_ready);
            if accepted {
                let cmd = cmds[next];
                self.mem.inflight.push_back(InFlight {
                    index: next,
                    reads: reads(&cmd),
                    write: write_range(&cmd),
                    accepted_at: c,
                    read_bursts: 0,
                    entries_read: 0,
                    entries_written: 0,
                    written: WriteOnce::default(),
                });
                first_accept.get_or_insert(c);
            }
            self.step();
            if accepted {
                self.dut.io_set(self.ports.cmd_valid, 0);
                // Random garbage on the idle command fields.
                self.dut.io_set(self.ports.cmd[1], self.rng.next_u64());
                self.dut.io_set(self.ports.cmd[2], self.rng.next_u64());
                offered = false;
                next += 1;
                gap = self.rng.below(self.cmd_gap + 1);
            }
            if next == cmds.len() && self.mem.inflight.is_empty() {
                break;
            }
            if self.dut.io_cycle() > limit {
                let what = if offered { "cmd_ready_o" } else { "done_o" };
                self.checker.fail(
                    self.dut.io_cycle(),
                    what,
                    "progress",
                    &format!(
                        "none: timeout with {} of {} commands taken, {} in flight",
                        next,
                        cmds.len(),
                        self.mem.inflight.len()
                    ),
                );
            }
        }
        let results: Vec<CmdResult> = results.into_iter().map(|r| r.expect("every command done")).collect();
        let span = results.last().map_or(0, |r| r.done_at) - first_accept.unwrap_or(0);
        QueueRun { results, span }
    }

    /// Runs one command to completion (random delay before it is offered) and returns its cost.
    ///
    /// # Panics
    /// On a timeout, a protocol violation, or `done_o` at the wrong time.
    pub fn run(&mut self, cmd: Command) -> CmdResult {
        self.checker.protocol(
            self.dut.io_cycle(),
            self.mem.inflight.is_empty(),
            "run with commands in flight",
        );
        let r = self.run_queue(&[cmd]).results[0];
        self.dut.io_eval();
        self.checker.protocol(
            self.dut.io_cycle(),
            !self.dut.flag(self.ports.done),
            "done_o longer than one cycle",
        );
        self.checker.protocol(
            self.dut.io_cycle(),
            self.dut.flag(self.ports.cmd_ready),
            "cmd_ready_o low the cycle after the only command's done_o",
        );
        r
    }

    /// Checks `len` entries at `addr` against `want`, naming the first mismatch.
    #[track_caller]
    pub fn expect(&self, what: &str, addr: u64, want: &[SortEntry]) {
        let got = self.read_entries(addr, want.len());
        for (i, (w, g)) in want.iter().zip(&got).enumerate() {
            self.checker.entry(
                self.dut.io_cycle(),
                &format!("{what}[{i}] (memory 0x{:x})", addr + i as u64),
                w,
                g,
            );
        }
    }
}

/// Memory layout of the flows: regions far apart so ranges never overlap.
pub mod layout {
    /// Input table / chunk.
    pub const SRC: u64 = 0x0001_0000;
    /// Second input (stream B, incoming entries).
    pub const SRC_B: u64 = 0x0010_0000;
    /// Scratch runs, ping.
    pub const PING: u64 = 0x0020_0000;
    /// Scratch runs, pong.
    pub const PONG: u64 = 0x0030_0000;
    /// Output.
    pub const DST: u64 = 0x0040_0000;
    /// Size reserved per region.
    pub const REGION: u64 = 0x000F_0000;
}

/// (a) Sorts one chunk (`entries.len() <= B`, the core's buffer: the chunk `C`, or the wide
/// chunk) with `mode` and checks it against golden `full_sort` (one chunk: BSU vectors plus
/// in-chunk merges). Returns the command's cost.
pub fn sort_chunk_checked<M: Clocked>(
    core: &mut Core<M>,
    cfg: &EngineConfig,
    entries: &[SortEntry],
    mode: Mode,
) -> CmdResult {
    assert!(entries.len() <= cfg.sort_buffer(), "one buffer at most");
    core.write_entries(layout::SRC, entries);
    core.clear(layout::DST..layout::DST + layout::REGION);
    let r = core.run(Command {
        mode,
        src_a: layout::SRC,
        len_a: entries.len() as u64,
        src_b: 0,
        len_b: 0,
        dst: layout::DST,
    });
    let (want, _) = neo_golden::sort::full_sort(entries, &cfg.buffer_sort_config());
    core.checker.value(core.dut.io_cycle(), "done_len_o", want.len() as u64, r.done_len);
    core.checker.value(core.dut.io_cycle(), "done_inv_o (chunk command)", 0, r.done_inv);
    core.expect("sorted chunk", layout::DST, &want);
    r
}

/// (a) Sorts several chunks (each `<= C` entries; chunk `k` read from `SRC + k C`, written to
/// `DST + k C`) with `mode` commands issued back to back, and checks every one against golden.
pub fn sort_chunks_checked<M: Clocked>(
    core: &mut Core<M>,
    cfg: &EngineConfig,
    chunks: &[Vec<SortEntry>],
    mode: Mode,
) -> QueueRun {
    let c = cfg.chunk as u64;
    core.clear(layout::DST..layout::DST + layout::REGION);
    let mut cmds = Vec::new();
    for (k, v) in chunks.iter().enumerate() {
        assert!(v.len() <= cfg.chunk, "one chunk at most");
        let off = k as u64 * c;
        core.write_entries(layout::SRC + off, v);
        cmds.push(Command {
            mode,
            src_a: layout::SRC + off,
            len_a: v.len() as u64,
            src_b: 0,
            len_b: 0,
            dst: layout::DST + off,
        });
    }
    let q = core.run_queue(&cmds);
    for (k, v) in chunks.iter().enumerate() {
        let (want, _) = neo_golden::sort::full_sort(v, &cfg.sort_config());
        core.checker.value(
            core.dut.io_cycle(),
            &format!("done_len_o (chunk {k})"),
            want.len() as u64,
            q.results[k].done_len,
        );
        core.expect(&format!("sorted chunk {k}"), layout::DST + k as u64 * c, &want);
    }
    q
}

/// (a) Conventional sort of any number of entries, golden's commands of a tile sorted from
/// scratch (`tile_steps`, of `conventional_sort_plan`, which golden `full_sort` executes): `SORT` per chunk into runs, then `MERGE` passes over runs of `C, 2C, ...` (a lone last run is copied by merging it
/// with an empty B), all issued as one back-to-back queue (the chunk SORTs overlap; each MERGE
/// waits for the commands whose output it reads). Checks the result and returns the cycles from
/// the first command's acceptance to the last `done_o`.
pub fn full_sort_checked<M: Clocked>(core: &mut Core<M>, cfg: &EngineConfig, entries: &[SortEntry]) -> u64 {
    let c = cfg.chunk;
    let len = entries.len() as u64;
    core.write_entries(layout::SRC, entries);
    core.clear(layout::PING..layout::DST + layout::REGION);
    // golden's commands of a tile sorted from scratch: the chunk sorts into PING, then each
    // merge pass from one buffer into the other, the last into the buffer of its parity.
    let buffer = |stage: u64| if stage.is_multiple_of(2) { layout::PING } else { layout::PONG };
    let passes = merge_pass_count(len, c as u64);
    let shape = TileShape { from_scratch: true, list_len: len, chunk: c as u64, ..TileShape::default() };
    let base = |region| match region {
        TileRegion::List => layout::SRC,
        TileRegion::Scratch(k) => buffer(k as u64),
        TileRegion::Prev | TileRegion::Next => buffer(passes),
    };
    let steps = tile_steps(&shape).concat();
    let cmds: Vec<Command> = steps.iter().map(|s| s.place(base)).collect();
    let want_len: Vec<u64> = steps.iter().map(|s| s.a.2 + s.b.2).collect();
    let from = buffer(passes);
    let q = core.run_queue(&cmds);
    for (k, (r, w)) in q.results.iter().zip(&want_len).enumerate() {
        core.checker.value(
            core.dut.io_cycle(),
            &format!("done_len_o (command {k}: {:?})", cmds[k].mode),
            *w,
            r.done_len,
        );
    }
    let (want, _) = neo_golden::sort::full_sort(entries, &cfg.sort_config());
    core.expect("full sort", from, &want);
    q.span
}

/// (b) One DPS pass over `table` with `parity`: a `DPS` command per chunk of the parity's
/// boundaries, issued back to back, checked against golden `dps_pass`. Returns the sorted table
/// and the cycles from the first command's acceptance to the last `done_o`.
pub fn dps_pass_checked<M: Clocked>(
    core: &mut Core<M>,
    cfg: &EngineConfig,
    table: &[SortEntry],
    parity: Parity,
) -> (Vec<SortEntry>, u64) {
    core.write_entries(layout::SRC, table);
    core.clear(layout::DST..layout::DST + layout::REGION);
    let ranges: Vec<_> = parity.chunks(table.len(), cfg.chunk).collect();
    let cmds: Vec<Command> = ranges
        .iter()
        .map(|r| Command {
            mode: Mode::Dps,
            src_a: layout::SRC + r.start as u64,
            len_a: r.len() as u64,
            src_b: 0,
            len_b: 0,
            dst: layout::DST + r.start as u64,
        })
        .collect();
    let q = core.run_queue(&cmds);
    for (r, res) in ranges.iter().zip(&q.results) {
        core.checker.value(
            core.dut.io_cycle(),
            &format!("done_len_o (DPS chunk {r:?})"),
            r.len() as u64,
            res.done_len,
        );
    }
    let mut want = table.to_vec();
    neo_golden::sort::dps_pass(&mut want, parity, &cfg.sort_config());
    core.expect(&format!("DPS pass {parity:?}"), layout::DST, &want);
    (want, q.span)
}

/// Golden's boundary inversions of `a` in `merge2(a, b, drop_invalid)` (the MSU+'s count).
pub fn a_inversions(a: &[SortEntry], b: &[SortEntry], drop_invalid: bool) -> u64 {
    neo_golden::sort::merge2_into(a, b, drop_invalid, &mut Vec::new()).a_inversions as u64
}

/// (c) Merges sorted `a` and `b` (`MERGE_DELETE` when `drop_invalid`, else `MERGE`) and checks
/// against golden `merge2`. Returns the command's cost.
pub fn merge_checked<M: Clocked>(
    core: &mut Core<M>,
    a: &[SortEntry],
    b: &[SortEntry],
    drop_invalid: bool,
) -> CmdResult {
    core.write_entries(layout::SRC, a);
    core.write_entries(layout::SRC_B, b);
    core.clear(layout::DST..layout::DST + layout::REGION);
    let r = core.run(Command {
        mode: if drop_invalid { Mode::MergeDelete } else { Mode::Merge },
        src_a: layout::SRC,
        len_a: a.len() as u64,
        src_b: layout::SRC_B,
        len_b: b.len() as u64,
        dst: layout::DST,
    });
    let want = merge2(a, b, drop_invalid);
    core.checker.value(core.dut.io_cycle(), "done_len_o", want.len() as u64, r.done_len);
    core.checker.value(core.dut.io_cycle(), "done_inv_o", a_inversions(a, b, drop_invalid), r.done_inv);
    core.expect(if drop_invalid { "merge-delete" } else { "merge" }, layout::DST, &want);
    r
}

/// The per-tile update composed from the three modes (DPS pass of the frame's parity on `prev`,
/// conventional sort of `incoming`, `MERGE_DELETE`), checked against golden `update_tile` with
/// an unlimited capacity. Returns the new table.
pub fn update_checked<M: Clocked>(
    core: &mut Core<M>,
    cfg: &EngineConfig,
    prev: &[SortEntry],
    incoming: &[SortEntry],
    frame: u64,
) -> Vec<SortEntry> {
    let (table, _) = dps_pass_checked(core, cfg, prev, Parity::of(frame, 0));
    full_sort_checked(core, cfg, incoming);
    let (sorted_in, _) = neo_golden::sort::full_sort(incoming, &cfg.sort_config());
    merge_checked(core, &table, &sorted_in, true);
    let ucfg = neo_golden::sort::UpdateConfig::new(cfg.sort_config(), usize::MAX);
    let golden = neo_golden::sort::update_tile(prev, incoming, frame, &ucfg);
    core.expect("update table", layout::DST, &golden.table);
    golden.table
}

/// A command of a mixed queue, its inputs already placed in memory, and its golden output.
#[derive(Clone, Debug)]
pub struct CheckedCmd {
    /// The command.
    pub cmd: Command,
    /// The golden output at `cmd.dst` (its length is the expected `done_len_o`).
    pub want: Vec<SortEntry>,
    /// The expected `done_inv_o`: golden's boundary inversions of A (merges; 0 for chunks).
    pub inversions: u64,
}

/// Entry addresses reserved per queue slot in each region (inputs of a slot never overlap).
pub const SLOT: u64 = 0x1000;

/// Places `entries` in slot `slot` and returns a chunk command (`mode` SORT or DPS) with its
/// golden output (golden `sort_chunk` of the first `min(len, B)` entries, `B` the core's
/// buffer: the core clamps).
pub fn chunk_cmd<M: Clocked>(
    core: &mut Core<M>,
    cfg: &EngineConfig,
    slot: u64,
    entries: &[SortEntry],
    mode: Mode,
) -> CheckedCmd {
    let (src, dst) = (layout::SRC + slot * SLOT, layout::DST + slot * SLOT);
    chunk_cmd_at(core, cfg, src, dst, entries, mode)
}

/// [`chunk_cmd`] with `entries` at entry address `src` and the output at `dst` (the caller keeps
/// the commands' regions apart).
pub fn chunk_cmd_at<M: Clocked>(
    core: &mut Core<M>,
    cfg: &EngineConfig,
    src: u64,
    dst: u64,
    entries: &[SortEntry],
    mode: Mode,
) -> CheckedCmd {
    core.write_entries(src, entries);
    core.clear(dst..dst + SLOT);
    let n = entries.len().min(cfg.sort_buffer());
    let (want, _) = neo_golden::sort::full_sort(&entries[..n], &cfg.buffer_sort_config());
    CheckedCmd {
        cmd: Command { mode, src_a: src, len_a: entries.len() as u64, src_b: 0, len_b: 0, dst },
        want,
        inversions: 0,
    }
}

/// Places sorted `a` and `b` in slot `slot` and returns a MERGE (`drop_invalid` false) or
/// MERGE_DELETE command with its golden output (`merge2`).
pub fn merge_cmd<M: Clocked>(
    core: &mut Core<M>,
    slot: u64,
    a: &[SortEntry],
    b: &[SortEntry],
    drop_invalid: bool,
) -> CheckedCmd {
    let at = MergeAt {
        src_a: layout::SRC + slot * SLOT,
        src_b: layout::SRC_B + slot * SLOT,
        dst: layout::DST + slot * SLOT,
    };
    merge_cmd_at(core, at, a, b, drop_invalid)
}

/// Where a merge's inputs and output lie (entry addresses).
#[derive(Clone, Copy, Debug)]
pub struct MergeAt {
    /// Stream A.
    pub src_a: u64,
    /// Stream B.
    pub src_b: u64,
    /// The output.
    pub dst: u64,
}

/// [`merge_cmd`] at the addresses `at` (the caller keeps the commands' regions apart; the
/// output's region, `max(SLOT, len_a + len_b)` entries, is cleared first).
pub fn merge_cmd_at<M: Clocked>(
    core: &mut Core<M>,
    at: MergeAt,
    a: &[SortEntry],
    b: &[SortEntry],
    drop_invalid: bool,
) -> CheckedCmd {
    core.write_entries(at.src_a, a);
    core.write_entries(at.src_b, b);
    core.clear(at.dst..at.dst + SLOT.max((a.len() + b.len()) as u64));
    CheckedCmd {
        cmd: Command {
            mode: if drop_invalid { Mode::MergeDelete } else { Mode::Merge },
            src_a: at.src_a,
            len_a: a.len() as u64,
            src_b: at.src_b,
            len_b: b.len() as u64,
            dst: at.dst,
        },
        want: merge2(a, b, drop_invalid),
        inversions: a_inversions(a, b, drop_invalid),
    }
}

/// Runs `cmds` back to back ([`Core::run_queue`]) and checks every command's `done_len_o` and
/// output against its golden result.
pub fn queue_checked<M: Clocked>(core: &mut Core<M>, cmds: &[CheckedCmd]) -> QueueRun {
    let plain: Vec<Command> = cmds.iter().map(|c| c.cmd).collect();
    let q = core.run_queue(&plain);
    for (k, (c, r)) in cmds.iter().zip(&q.results).enumerate() {
        let what = format!("command {k} ({:?}, len_a {}, len_b {})", c.cmd.mode, c.cmd.len_a, c.cmd.len_b);
        core.checker.value(r.done_at, &format!("done_len_o of {what}"), c.want.len() as u64, r.done_len);
        core.checker.value(r.done_at, &format!("done_inv_o of {what}"), c.inversions, r.done_inv);
        core.expect(&format!("output of {what}"), c.cmd.dst, &c.want);
    }
    q
}
