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
//! Memory: word-addressed by entry (`mem_req_addr_o` is an entry index). A read request of
//! `len` entries is answered by `len` response beats in request order, the first after a random
//! latency; a write request carries one entry. Accesses outside the command's source and
//! destination ranges are protocol errors.

use crate::check::Checker;
use crate::models::NeoSortCore;
use crate::rng::Rng;
use neo_gen::GenConfig;
use neo_golden::sort::{merge2, Parity, SortEntry, SortFormat};
use std::collections::{HashMap, VecDeque};
use std::ops::Range;

/// Command modes (`cmd_mode_i`), as documented in `gen/src/units/sort_core.rs`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    /// 0: sort one chunk (conventional sort, mode (a)).
    Sort = 0,
    /// 1: a DPS pass over one chunk (mode (b)).
    Dps = 1,
    /// 2: merge A and B dropping invalid entries (mode (c), the update's delete).
    MergeDelete = 2,
    /// 3: merge A and B keeping every entry (the conventional sort's global passes).
    Merge = 3,
}

/// One command.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Command {
    /// Mode.
    pub mode: Mode,
    /// Entry address of the chunk / stream A.
    pub src_a: u64,
    /// Entries of the chunk / stream A.
    pub len_a: u64,
    /// Entry address of stream B (merge modes).
    pub src_b: u64,
    /// Entries of stream B.
    pub len_b: u64,
    /// Entry address of the output.
    pub dst: u64,
}

/// Timing of the memory model.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MemTiming {
    /// Probability (percent) that `mem_req_ready_i` is high in a cycle.
    pub req_ready_pct: u32,
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
        MemTiming { req_ready_pct: 100, min_latency: 1, max_latency: 1, rsp_gap_pct: 0 };
    /// A hostile memory: frequent stalls and gaps, latency 1..40 cycles.
    pub const RANDOM: MemTiming =
        MemTiming { req_ready_pct: 60, min_latency: 1, max_latency: 40, rsp_gap_pct: 25 };
}

/// What a command did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CmdResult {
    /// Rising edges from the one that accepts the command (`cmd_valid_i & cmd_ready_o`) to the
    /// cycle with the `done_o` pulse (at least 1).
    pub cycles: u64,
    /// `done_len_o`.
    pub done_len: u64,
    /// Read requests and entries read, writes.
    pub read_bursts: u64,
    /// Entries read.
    pub entries_read: u64,
    /// Entries written.
    pub entries_written: u64,
}

/// The memory model.
struct Memory {
    words: HashMap<u64, u64>,
    timing: MemTiming,
    rng: Rng,
    /// Response beats due: (cycle from which it may be offered, data).
    rsp: VecDeque<(u64, u64)>,
    offering: bool,
    read_ok: Vec<Range<u64>>,
    write_ok: Range<u64>,
    read_bursts: u64,
    entries_read: u64,
    entries_written: u64,
}

/// The Sorting Core with its memory, command driver and checker.
pub struct Core {
    /// The model.
    pub dut: NeoSortCore,
    mem: Memory,
    /// Mismatch reporting.
    pub checker: Checker,
    fmt: SortFormat,
    burst: u64,
    rng: Rng,
}

impl Core {
    /// A reset core whose memory follows `timing`.
    pub fn new(cfg: &GenConfig, seed: u64, timing: MemTiming) -> Core {
        let mut rng = Rng::new(seed);
        let mut dut = NeoSortCore::new();
        dut.set_cmd_valid_i(false);
        dut.set_mem_req_ready_i(false);
        dut.set_mem_rsp_valid_i(false);
        dut.reset();
        let mem = Memory {
            words: HashMap::new(),
            timing,
            rng: rng.fork(1),
            rsp: VecDeque::new(),
            offering: false,
            read_ok: Vec::new(),
            write_ok: 0..0,
            read_bursts: 0,
            entries_read: 0,
            entries_written: 0,
        };
        Core {
            dut,
            mem,
            checker: Checker::new(NeoSortCore::NAME, seed),
            fmt: cfg.format(),
            burst: cfg.burst as u64,
            rng: rng.fork(2),
        }
    }

    /// Changes the memory timing.
    pub fn set_timing(&mut self, timing: MemTiming) {
        self.mem.timing = timing;
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

    /// One cycle of the memory model and the clock.
    fn step(&mut self) {
        let c = self.dut.cycle();
        let ready = self.mem.rng.percent(self.mem.timing.req_ready_pct);
        self.dut.set_mem_req_ready_i(ready);
        if !self.mem.offering {
            if let Some(&(due, data)) = self.mem.rsp.front() {
                if due <= c && !self.mem.rng.percent(self.mem.timing.rsp_gap_pct) {
                    self.mem.offering = true;
                    self.dut.set_mem_rsp_data_i(data);
                }
            }
        }
        if !self.mem.offering {
            self.dut.set_mem_rsp_data_i(self.mem.rng.next_u64());
        }
        self.dut.set_mem_rsp_valid_i(self.mem.offering);
        self.dut.eval();

        if self.mem.offering && self.dut.mem_rsp_ready_o() {
            self.mem.rsp.pop_front();
            self.mem.offering = false;
        }
        if ready && self.dut.mem_req_valid_o() {
            let addr = self.dut.mem_req_addr_o();
            let len = self.dut.mem_req_len_o();
            if self.dut.mem_req_write_o() {
                self.checker.value(c, "mem_req_len_o (write)", 1, len);
                self.checker.protocol(
                    c,
                    self.mem.write_ok.contains(&addr),
                    &format!("write to 0x{addr:x} outside the destination {:x?}", self.mem.write_ok),
                );
                self.mem.words.insert(addr, self.dut.mem_wdata_o());
                self.mem.entries_written += 1;
            } else {
                self.checker.protocol(
                    c,
                    (1..=self.burst).contains(&len),
                    &format!("read burst of {len} entries"),
                );
                let inside = self.mem.read_ok.iter().any(|r| r.start <= addr && addr + len <= r.end);
                self.checker.protocol(
                    c,
                    inside,
                    &format!("read of {len} at 0x{addr:x} outside the sources {:x?}", self.mem.read_ok),
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
                self.mem.read_bursts += 1;
                self.mem.entries_read += len;
            }
        }
        self.dut.tick();
    }

    /// Runs one command to completion (random delay before it is offered) and returns its cost.
    ///
    /// # Panics
    /// On a timeout, a protocol violation, or `done_o` at the wrong time.
    pub fn run(&mut self, cmd: Command) -> CmdResult {
        let in_range = |a: u64, l: u64| a..a + l;
        self.mem.read_ok = vec![in_range(cmd.src_a, cmd.len_a), in_range(cmd.src_b, cmd.len_b)];
        let out_len = match cmd.mode {
            Mode::Sort | Mode::Dps => cmd.len_a,
            Mode::MergeDelete | Mode::Merge => cmd.len_a + cmd.len_b,
        };
        self.mem.write_ok = in_range(cmd.dst, out_len);
        let before = (self.mem.read_bursts, self.mem.entries_read, self.mem.entries_written);
        // A random idle gap before the command.
        for _ in 0..self.rng.below(3) {
            self.step();
        }
        self.dut.set_cmd_mode_i(cmd.mode as u64);
        self.dut.set_cmd_src_a_i(cmd.src_a);
        self.dut.set_cmd_len_a_i(cmd.len_a);
        self.dut.set_cmd_src_b_i(cmd.src_b);
        self.dut.set_cmd_len_b_i(cmd.len_b);
        self.dut.set_cmd_dst_i(cmd.dst);
        self.dut.set_cmd_valid_i(true);
        let limit = self.dut.cycle() + 2000 + 400 * (cmd.len_a + cmd.len_b);
        let mut start;
        loop {
            self.dut.eval();
            let accepted = self.dut.cmd_ready_o();
            let c = self.dut.cycle();
            start = c;
            self.checker.protocol(c, !self.dut.done_o(), "done_o while no command is running");
            self.step();
            if accepted {
                break;
            }
            if self.dut.cycle() > limit {
                self.checker.fail(c, "cmd_ready_o", "1", "0 (timeout)");
            }
        }
        self.dut.set_cmd_valid_i(false);
        // Random garbage on the idle command fields.
        self.dut.set_cmd_src_a_i(self.rng.next_u64());
        self.dut.set_cmd_len_a_i(self.rng.next_u64());
        loop {
            self.dut.eval();
            if self.dut.done_o() {
                break;
            }
            let c = self.dut.cycle();
            if c > limit {
                self.checker.fail(
                    c,
                    "done_o",
                    "a pulse",
                    &format!("none after {} cycles ({cmd:?})", c - start),
                );
            }
            self.step();
        }
        let c = self.dut.cycle();
        let cycles = c - start;
        let done_len = self.dut.done_len_o();
        self.checker.protocol(
            c,
            self.mem.rsp.is_empty() && !self.mem.offering,
            "done_o with read responses pending",
        );
        self.step();
        self.dut.eval();
        self.checker.protocol(self.dut.cycle(), !self.dut.done_o(), "done_o longer than one cycle");
        self.checker.protocol(
            self.dut.cycle(),
            self.dut.cmd_ready_o(),
            "cmd_ready_o low the cycle after done_o",
        );
        self.checker.value(self.dut.cycle(), "done_len_o (held)", done_len, self.dut.done_len_o());
        CmdResult {
            cycles,
            done_len,
            read_bursts: self.mem.read_bursts - before.0,
            entries_read: self.mem.entries_read - before.1,
            entries_written: self.mem.entries_written - before.2,
        }
    }

    /// Checks `len` entries at `addr` against `want`, naming the first mismatch.
    #[track_caller]
    pub fn expect(&self, what: &str, addr: u64, want: &[SortEntry]) {
        let got = self.read_entries(addr, want.len());
        for (i, (w, g)) in want.iter().zip(&got).enumerate() {
            self.checker.entry(
                self.dut.cycle(),
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

/// (a) Sorts one chunk (`entries.len() <= C`) with `SORT` and checks it against golden
/// `full_sort` (one chunk: BSU vectors plus in-chunk merges). Returns the command's cost.
pub fn sort_chunk_checked(core: &mut Core, cfg: &GenConfig, entries: &[SortEntry], mode: Mode) -> CmdResult {
    assert!(entries.len() <= cfg.chunk, "one chunk at most");
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
    let (want, _) = neo_golden::sort::full_sort(entries, &cfg.sort_config());
    core.checker.value(core.dut.cycle(), "done_len_o", want.len() as u64, r.done_len);
    core.expect("sorted chunk", layout::DST, &want);
    r
}

/// (a) Conventional sort of any number of entries, as golden `full_sort`: `SORT` per chunk into
/// runs, then `MERGE` passes over runs of `C, 2C, ...` (a lone last run is copied by merging it
/// with an empty B). Checks the result and returns the total cycles.
pub fn full_sort_checked(core: &mut Core, cfg: &GenConfig, entries: &[SortEntry]) -> u64 {
    let c = cfg.chunk;
    let len = entries.len() as u64;
    core.write_entries(layout::SRC, entries);
    core.clear(layout::PING..layout::DST + layout::REGION);
    let mut cycles = 0;
    // Chunks into PING.
    for (k, chunk) in entries.chunks(c).enumerate() {
        let off = (k * c) as u64;
        let r = core.run(Command {
            mode: Mode::Sort,
            src_a: layout::SRC + off,
            len_a: chunk.len() as u64,
            src_b: 0,
            len_b: 0,
            dst: layout::PING + off,
        });
        core.checker.value(
            core.dut.cycle(),
            &format!("done_len_o (chunk {k})"),
            chunk.len() as u64,
            r.done_len,
        );
        cycles += r.cycles;
    }
    let (mut from, mut to) = (layout::PING, layout::PONG);
    let mut run = c as u64;
    while run < len {
        let mut start = 0;
        while start < len {
            let la = run.min(len - start);
            let lb = run.min(len - start - la);
            let r = core.run(Command {
                mode: Mode::Merge,
                src_a: from + start,
                len_a: la,
                src_b: from + start + la,
                len_b: lb,
                dst: to + start,
            });
            core.checker.value(core.dut.cycle(), "done_len_o (merge pass)", la + lb, r.done_len);
            cycles += r.cycles;
            start += la + lb;
        }
        std::mem::swap(&mut from, &mut to);
        run *= 2;
    }
    let (want, _) = neo_golden::sort::full_sort(entries, &cfg.sort_config());
    core.expect("full sort", from, &want);
    cycles
}

/// (b) One DPS pass over `table` with `parity`: a `DPS` command per chunk of the parity's
/// boundaries, checked against golden `dps_pass`. Returns the sorted table and the cycles.
pub fn dps_pass_checked(
    core: &mut Core,
    cfg: &GenConfig,
    table: &[SortEntry],
    parity: Parity,
) -> (Vec<SortEntry>, u64) {
    core.write_entries(layout::SRC, table);
    core.clear(layout::DST..layout::DST + layout::REGION);
    let mut cycles = 0;
    for r in parity.chunks(table.len(), cfg.chunk) {
        let res = core.run(Command {
            mode: Mode::Dps,
            src_a: layout::SRC + r.start as u64,
            len_a: r.len() as u64,
            src_b: 0,
            len_b: 0,
            dst: layout::DST + r.start as u64,
        });
        core.checker.value(
            core.dut.cycle(),
            &format!("done_len_o (DPS chunk {r:?})"),
            r.len() as u64,
            res.done_len,
        );
        cycles += res.cycles;
    }
    let mut want = table.to_vec();
    neo_golden::sort::dps_pass(&mut want, parity, &cfg.sort_config());
    core.expect(&format!("DPS pass {parity:?}"), layout::DST, &want);
    (want, cycles)
}

/// (c) Merges sorted `a` and `b` (`MERGE_DELETE` when `drop_invalid`, else `MERGE`) and checks
/// against golden `merge2`. Returns the command's cost.
pub fn merge_checked(core: &mut Core, a: &[SortEntry], b: &[SortEntry], drop_invalid: bool) -> CmdResult {
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
    core.checker.value(core.dut.cycle(), "done_len_o", want.len() as u64, r.done_len);
    core.expect(if drop_invalid { "merge-delete" } else { "merge" }, layout::DST, &want);
    r
}

/// The per-tile update composed from the three modes (DPS pass of the frame's parity on `prev`,
/// conventional sort of `incoming`, `MERGE_DELETE`), checked against golden `update_tile` with
/// an unlimited capacity. Returns the new table.
pub fn update_checked(
    core: &mut Core,
    cfg: &GenConfig,
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
