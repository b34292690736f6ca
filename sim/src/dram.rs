//! A command-level LPDDR4 model: per channel, a controller with read, write and activate
//! queues that issues at most one command (ACT, PRE, RD, WR, PREA, REF) per DRAM clock under
//! the standard's timing constraints, as Ramulator 1's controller does (docs/cycle-model.md,
//! "DRAM model" and "Against Ramulator").
//!
//! Each 64-byte request is mapped to (channel, bank, row) by
//! [`crate::config::DramConfig::mapping`]. Per channel and clock:
//! - **refresh**: every `tREFI` a refresh is queued; it takes precedence over reads and writes
//!   (all-bank precharge `PREA` if a row is open, then `REF`, which blocks activates `tRFCab`);
//! - **write mode** starts when more than 80% of `write_queue` writes wait or no read waits, and
//!   ends when fewer than 20% wait and a read waits; reads are served outside it, writes in it;
//! - **activate queue**: a request whose row the controller has just opened goes first if its
//!   column command can issue; the whole queue is scanned, as Ramulator does (the window below
//!   bounds only the read and write queues: with a window of one, a scan of the activate queue's
//!   head alone let two requests to one bank close each other's row forever);
//! - **FR-FCFS with a cap** (Ramulator's `FRFCFS_Cap`): among the first `read_queue` requests
//!   of the queue served, the oldest whose *next command* can issue now, counting a hit of a row
//!   that has already served more than `bypass_cap` accesses as not ready; if none can, the
//!   oldest, if its command can issue; else nothing this clock. So a younger request's
//!   precharge may close a row while older hits to it wait for the data bus;
//! - constraints: `tRCD`, `tRAS`, `tRC`, `tRP` per bank; `tRRD`, `tFAW`, `tPPD`, `tCCD` (= `BL`),
//!   read-to-write (`CL + BL + tDQSCK + 1 - CWL`), write-to-read (`CWL + BL + tWTR + 1`),
//!   `tRTP` and write recovery (`CWL + BL + tWR`) to precharge, per channel;
//! - a read's data returns `CL + tDQSCK + BL` after its RD; a write is done at its WR.
//!
//! Time is simulated lazily: a channel advances to a request's issue time when the request is
//! submitted, and further when a read's data time is asked for ([`Dram::arrival`]); clocks on
//! which no command can issue are skipped (the next issue time is computed, not searched). The
//! FR-FCFS pick of the read or write queue looks, per bank, only at the oldest request of the
//! window that hits the open row and the oldest that does not (their ready clocks are the
//! bank's), kept up to date as requests come and go and rows open and close; the pick and the
//! next command are chosen without branches on the data, which are too irregular to predict.
//! Requests arrive in non-decreasing issue time; a request submitted after its channel has
//! already advanced past its issue time (because an earlier read's time was needed) is queued
//! at the channel's clock, its latency still counted from its issue.
//!
//! Not modelled: power-down, per-bank refresh, ranks (one), command-bus slots beyond one command
//! per clock, data bus inversion, on-die ECC.

use std::collections::VecDeque;
use std::hint::select_unpredictable;

use neo_golden::profile::{self, Phase};
use serde::{Deserialize, Serialize};

use crate::config::DramConfig;

/// Time in picoseconds.
pub type Ps = u64;

/// DRAM clocks.
type Clk = u64;

const CLOSED: u32 = u32::MAX;
const NEVER: Clk = Clk::MAX;

/// Refreshes an LPDDR4 controller may postpone (JESD209-4): the unit tests assert the model
/// never queues more.
#[cfg(test)]
const MAX_POSTPONED_REFRESHES: u32 = 8;

/// One bank: its open row and the earliest clock of each command.
#[derive(Clone, Copy, Debug)]
struct Bank {
    open: u32,
    /// Column accesses to the open row since it was opened.
    hits: u32,
    act: Clk,
    pre: Clk,
    rd: Clk,
    wr: Clk,
}

impl Bank {
    /// Its open row has served more than `cap` accesses: a hit of it can issue only as the
    /// oldest request (FRFCFS_Cap).
    #[inline]
    fn past_cap(&self, cap: u32) -> bool {
        (self.open != CLOSED) & (self.hits > cap)
    }
}

impl Default for Bank {
    fn default() -> Self {
        Bank { open: CLOSED, hits: 0, act: 0, pre: 0, rd: 0, wr: 0 }
    }
}

/// A request in a controller queue.
#[derive(Clone, Copy, Debug, Default)]
struct Req {
    /// Clock of entry (age order).
    arrive: Clk,
    /// Issue time (latency is counted from it).
    issue: Ps,
    bank: u32,
    row: u32,
    line: u64,
    ticket: u32,
    write: bool,
    /// No command issued for it yet (its row outcome is counted at the first).
    first: bool,
    /// Position in its queue's order of entry (read and write queues; [`Index`]).
    seq: u64,
}

/// No request.
const NONE: u64 = u64::MAX;

/// One bank's part of an [`Index`]: its queued requests and, within the scheduler's window,
/// the oldest that hits the bank's open row and the oldest that does not (`NONE` if none), each
/// valid unless its `dirty` flag is set.
#[derive(Clone, Debug)]
struct Slot {
    /// `(seq, row)` of the bank's queued requests in entry order.
    list: VecDeque<(u64, u32)>,
    hit: u64,
    other: u64,
    dirty_hit: bool,
    dirty_other: bool,
}

impl Default for Slot {
    fn default() -> Self {
        Slot { list: VecDeque::new(), hit: NONE, other: NONE, dirty_hit: false, dirty_other: false }
    }
}

impl Slot {
    /// The open row changed: both requests are to be found again.
    fn reopen(&mut self) {
        self.dirty_hit = true;
        self.dirty_other = true;
    }

    /// Recomputes the requests that need it: the window ends at request `bound`.
    #[inline]
    fn clean(&mut self, bound: u64, open: u32) {
        let (dh, dother) = (self.dirty_hit, self.dirty_other);
        if !dh && !dother {
            return;
        }
        // A clean class counts as found.
        let (mut h, mut o) = (NONE, NONE);
        let (mut need_h, mut need_o) = (dh, dother);
        for &(s, row) in &self.list {
            if s > bound {
                break;
            }
            if open == row {
                if need_h {
                    h = s;
                    need_h = false;
                }
            } else if need_o {
                o = s;
                need_o = false;
            }
            if !need_h && !need_o {
                break;
            }
        }
        if dh {
            self.hit = h;
            self.dirty_hit = false;
        }
        if dother {
            self.other = o;
            self.dirty_other = false;
        }
    }
}

/// Per bank, the requests of a read or write queue and, within the scheduler's window (its
/// first `window` requests), the oldest that hits the bank's open row and the oldest that does
/// not. A request's ready clock depends only on its bank and on whether it hits (the queue's
/// requests are all reads or all writes), so the FR-FCFS pick needs only these two per bank.
#[derive(Clone, Debug, Default)]
struct Index {
    /// Per bank.
    slots: Vec<Slot>,
    /// Bit set of the banks with a class to be found again (a `dirty` flag set; 64 banks a
    /// word). A bank without requests has neither class once found again.
    dirty: Vec<u64>,
    /// The next request's `seq`.
    next_seq: u64,
}

impl Index {
    fn new(banks: usize) -> Self {
        let words = banks.div_ceil(64);
        Index { slots: vec![Slot::default(); banks], dirty: vec![0; words], next_seq: 0 }
    }

    /// Request `(seq, bank, row)`, the youngest in the window, entered it.
    fn enter(&mut self, seq: u64, bank: u32, row: u32, open: u32) {
        let sl = &mut self.slots[bank as usize];
        let (class, dirty) =
            if open == row { (&mut sl.hit, sl.dirty_hit) } else { (&mut sl.other, sl.dirty_other) };
        if !dirty && *class == NONE {
            *class = seq;
        }
    }

    /// Request `(seq, bank)` left the queue.
    fn leave(&mut self, seq: u64, bank: u32) {
        let b = bank as usize;
        let sl = &mut self.slots[b];
        // Mostly the bank's oldest.
        if sl.list.front().is_some_and(|e| e.0 == seq) {
            sl.list.pop_front();
        } else {
            let p = sl.list.iter().position(|e| e.0 == seq).expect("an indexed request");
            sl.list.remove(p);
        }
        if sl.hit == seq {
            sl.dirty_hit = true;
        } else if sl.other == seq {
            sl.dirty_other = true;
        } else {
            return;
        }
        self.mark(b);
    }

    /// Bank `b` has a class to be found again.
    fn mark(&mut self, b: usize) {
        self.dirty[b / 64] |= 1 << (b % 64);
    }

    /// Bank `b`'s open row changed: both its requests are to be found again.
    fn reopen(&mut self, b: usize) {
        self.slots[b].reopen();
        self.mark(b);
    }

    /// Every bank's open row changed (all-bank precharge).
    fn reopen_all(&mut self) {
        (0..self.slots.len()).for_each(|b| self.reopen(b));
    }

    /// Finds again the classes to be found (the window ends at request `bound`; `banks` gives
    /// each bank's open row).
    fn clean(&mut self, bound: u64, banks: &[Bank]) {
        for w in 0..self.dirty.len() {
            let mut bits = std::mem::take(&mut self.dirty[w]);
            while bits != 0 {
                let i = w * 64 + bits.trailing_zeros() as usize;
                bits &= bits - 1;
                self.slots[i].clean(bound, banks[i].open);
            }
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Cmd {
    Act,
    Pre,
    Rd,
    Wr,
    Prea,
    Ref,
}

/// Which queue a request is picked from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Q {
    Act,
    Read,
    Write,
}

impl Q {
    /// The [`Channel::idx`] of the read or write queue.
    fn index(self) -> usize {
        match self {
            Q::Read => 0,
            Q::Write => 1,
            Q::Act => unreachable!("the activate queue has no index"),
        }
    }
}

#[derive(Clone, Debug, Default)]
struct Channel {
    /// Clocks ticked.
    clk: Clk,
    banks: Vec<Bank>,
    /// Earliest clock of each command as far as the channel (rank) constraints go.
    act: Clk,
    pre: Clk,
    rd: Clk,
    wr: Clk,
    prea: Clk,
    refresh: Clk,
    /// The last four activates (`tFAW`).
    acts: VecDeque<Clk>,
    readq: VecDeque<Req>,
    writeq: VecDeque<Req>,
    actq: VecDeque<Req>,
    /// Indexes of the read and write queues.
    idx: [Index; 2],
    /// Refreshes queued.
    ref_pending: u32,
    /// Clock of the last refresh request.
    refreshed: Clk,
    write_mode: bool,
    /// Drain every write (the high watermark is 0: end of a run).
    flushing: bool,
    /// Clock of the last WR command.
    last_wr: Clk,
    /// The next command as [`Dram::plan`] found it (cleared when a request arrives, a command
    /// issues or the mode changes).
    plan: Option<Plan>,
}

impl Channel {
    /// The next command of `r` and the clock from which it can issue.
    #[inline]
    fn next_cmd(&self, r: &Req) -> (Cmd, Clk) {
        // Without branches on the data: which command a request needs next is irregular.
        let b = &self.banks[r.bank as usize];
        let closed = b.open == CLOSED;
        let col = (select_unpredictable(r.write, Cmd::Wr, Cmd::Rd), self.column_at(b, r.write));
        let other = (select_unpredictable(closed, Cmd::Act, Cmd::Pre), self.opening_at(b));
        select_unpredictable(!closed & (b.open == r.row), col, other)
    }

    /// The clock from which bank `b` can take a column command (a write if `write`).
    #[inline]
    fn column_at(&self, b: &Bank, write: bool) -> Clk {
        select_unpredictable(write, b.wr, b.rd).max(select_unpredictable(write, self.wr, self.rd))
    }

    /// The clock from which bank `b` can take the command it needs before it serves another
    /// row: ACT if it is closed, else PRE.
    #[inline]
    fn opening_at(&self, b: &Bank) -> Clk {
        select_unpredictable(b.open == CLOSED, b.act.max(self.act), b.pre.max(self.pre))
    }

    /// The clock from which request `r` can issue its next command as a candidate of FR-FCFS
    /// (`NEVER` for a hit of a row that has served more than `cap` accesses, which can issue
    /// only as the oldest).
    #[inline]
    fn ready(&self, r: &Req, cap: u32) -> Clk {
        let b = &self.banks[r.bank as usize];
        if b.open == r.row {
            if b.past_cap(cap) {
                NEVER
            } else {
                self.column_at(b, r.write)
            }
        } else {
            self.opening_at(b)
        }
    }

    /// FRFCFS_Cap's candidates of read or write queue `q` (scheduler window `window`, row cap
    /// `cap`): per bank, the oldest hit and the oldest other request of the window, each added
    /// to `cands` with its ready clock; returns the clock from which the queue's oldest request
    /// can issue its next command (capped or not; `NEVER` for an empty queue).
    fn scan_classes(&mut self, q: Q, window: usize, cap: u32, cands: &mut Oldest) -> Clk {
        let queue = if q == Q::Read { &self.readq } else { &self.writeq };
        let Some(front) = queue.front() else { return NEVER };
        let front_at = self.next_cmd(front);
        let bound = queue[queue.len().min(window) - 1].seq;
        self.idx[q.index()].clean(bound, &self.banks);
        let write = q == Q::Write;
        // Every bank, without branches on the data (a bank with no request has no candidate:
        // both classes `NONE`, ready `NEVER`): the banks' outcomes are too irregular to predict.
        for (b, sl) in self.banks.iter().zip(&self.idx[q.index()].slots) {
            // A hit of a row past the cap can issue only as the oldest: not a candidate.
            let hit_ok = (sl.hit != NONE) & !b.past_cap(cap);
            cands.add(select_unpredictable(hit_ok, self.column_at(b, write), NEVER), sl.hit, 0);
            cands.add(select_unpredictable(sl.other != NONE, self.opening_at(b), NEVER), sl.other, 0);
        }
        front_at.1
    }

    /// The index of the request with entry number `seq` in the first `window` requests of read
    /// or write queue `q`.
    fn position(&self, q: Q, window: usize, seq: u64) -> usize {
        let queue = if q == Q::Read { &self.readq } else { &self.writeq };
        // The queue is in `seq` order: the position is the count of older requests, found in
        // the deque's two slices (mostly the oldest).
        let (a, b) = queue.as_slices();
        let a = &a[..a.len().min(window)];
        let b = &b[..b.len().min(window - a.len())];
        if a[0].seq == seq {
            return 0;
        }
        let i = match a.last() {
            Some(last) if last.seq >= seq => a.partition_point(|r| r.seq < seq),
            _ => a.len() + b.partition_point(|r| r.seq < seq),
        };
        debug_assert!(i < window && queue[i].seq == seq, "an indexed request");
        i
    }

    /// The refresh's next command and its clock.
    fn refresh_cmd(&self) -> (Cmd, Clk) {
        if self.banks.iter().any(|b| b.open != CLOSED) {
            (Cmd::Prea, self.prea)
        } else {
            (Cmd::Ref, self.refresh)
        }
    }

    /// What the channel does next if no request arrives first (scheduler window `window`, row
    /// cap `cap`, refresh interval `refi`): the clock (after its current one) and the command,
    /// as [`Dram::tick`] would choose it then. One pass over each queue's candidates
    /// ([`Oldest`]): the whole activate queue (as Ramulator scans it), then (unless a refresh is
    /// queued) the served queue's per-bank candidates.
    fn plan(&mut self, window: usize, cap: u32, refi: Clk) -> Plan {
        let floor = self.clk + 1;
        let t_ref = self.refreshed.saturating_add(refi);
        // The activate queue, in order (so of equal arrivals the first counts as older).
        let mut act = Oldest::new(floor);
        // Its oldest request: (arrival, index).
        let mut oldest_a: Option<(Clk, usize)> = None;
        for (i, r) in self.actq.iter().enumerate() {
            act.add(self.ready(r, cap), r.arrive, i);
            if oldest_a.is_none_or(|(a, _)| r.arrive < a) {
                oldest_a = Some((r.arrive, i));
            }
        }
        let oldest_at = oldest_a.map_or(NEVER, |(_, o)| self.next_cmd(&self.actq[o]).1);
        let mut next = act.earliest().min(oldest_at);
        let mode = if self.write_mode { Q::Write } else { Q::Read };
        let refresh = (self.ref_pending > 0).then(|| self.refresh_cmd());
        let mut cands = Oldest::new(floor);
        let mut front_at = NEVER;
        match refresh {
            Some((_, at)) => next = next.min(at),
            None => {
                front_at = self.scan_classes(mode, window, cap, &mut cands);
                next = next.min(cands.earliest()).min(front_at);
            }
        }
        let at = next.min(t_ref).max(floor);
        let act_pick = act.pick(at).map(|(_, i)| i).or(oldest_a.filter(|_| oldest_at <= at).map(|(_, o)| o));
        let pick = if at >= t_ref {
            Pick::Slow
        } else if let Some(i) = act_pick {
            Pick::Issue(Q::Act, i, self.next_cmd(&self.actq[i]).0)
        } else if let Some((cmd, _)) = refresh {
            Pick::Refresh(cmd)
        } else {
            let i = match cands.pick(at) {
                Some((s, _)) => Some(self.position(mode, window, s)),
                None => (front_at <= at).then_some(0),
            };
            match i {
                Some(i) => {
                    let queue = if mode == Q::Read { &self.readq } else { &self.writeq };
                    Pick::Issue(mode, i, self.next_cmd(&queue[i]).0)
                }
                None => Pick::Slow,
            }
        };
        Plan { at, pick }
    }
}

/// What a channel does next if no request arrives first.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Plan {
    /// The clock.
    at: Clk,
    pick: Pick,
}

/// The command of a [`Plan`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Pick {
    /// A command of request `.1` of a queue.
    Issue(Q, usize, Cmd),
    /// The queued refresh's next command.
    Refresh(Cmd),
    /// A refresh is queued on that clock: the controller's rules are applied directly.
    Slow,
}

/// The oldest of a plan's candidates (by key, smallest first) among those ready by the planned
/// clock, found in one pass before that clock is known. The plan chooses a clock no earlier
/// than `floor` (the channel's next clock): every candidate ready at or before `floor` is ready
/// then, and a later plan clock is the earliest ready clock of all, so only the candidates ready
/// at that clock are. So the pick is the least `(max(ready, floor), key)`, kept as one `u128`
/// (updated without branches: which candidate wins is irregular).
#[derive(Clone, Copy, Debug)]
struct Oldest {
    floor: Clk,
    /// `max(ready, floor) << 64 | key` of the least candidate (`u128::MAX`: none).
    best: u128,
    /// Its index.
    index: usize,
}

impl Oldest {
    fn new(floor: Clk) -> Self {
        Oldest { floor, best: u128::MAX, index: 0 }
    }

    /// Candidate `i` with key `key` (below `NONE`; of equal keys the first added counts as
    /// older), ready from clock `at` (`NEVER`: not a candidate).
    #[inline]
    fn add(&mut self, at: Clk, key: u64, i: usize) {
        let v = ((at.max(self.floor) as u128) << 64) | key as u128;
        let v = select_unpredictable(at == NEVER, u128::MAX, v);
        let better = v < self.best;
        self.best = select_unpredictable(better, v, self.best);
        self.index = select_unpredictable(better, i, self.index);
    }

    /// The earliest ready clock, or `floor` if a candidate is ready by then (the same plan
    /// clock either way; `NEVER` if there is no candidate).
    fn earliest(&self) -> Clk {
        (self.best >> 64) as Clk
    }

    /// The oldest candidate ready at plan clock `at` (at least `floor`, and at most
    /// [`Oldest::earliest`] unless it is `floor`): its key and index.
    fn pick(&self, at: Clk) -> Option<(u64, usize)> {
        (self.best != u128::MAX && self.earliest() <= at).then_some((self.best as u64, self.index))
    }
}

/// A read submitted with [`Dram::submit_read`]; [`Dram::arrival`] gives its data time and
/// [`Dram::release`] returns the handle.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Ticket(u32);

const PENDING: Ps = Ps::MAX;

/// Counters of the DRAM model.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct DramStats {
    /// Read requests served.
    pub reads: u64,
    /// Write requests accepted.
    pub writes: u64,
    /// Requests that found their row open.
    pub row_hits: u64,
    /// Requests that found their bank closed.
    pub row_misses: u64,
    /// Requests that found another row open.
    pub row_conflicts: u64,
    /// Reads whose first command issued while an older read waited in the read queue.
    pub reordered: u64,
    /// Refreshes performed.
    pub refreshes: u64,
    /// Times a channel entered write mode.
    pub drains: u64,
    /// Reads answered from a queued write to the same line (no DRAM access; Ramulator's
    /// enqueue shortcut, used by [`crate::dram_stream::QueueFeeder`]).
    #[serde(default)]
    pub forwarded: u64,
    /// Sum over reads of (data end - issue), picoseconds.
    pub read_latency_ps: u64,
    /// Latest data-bus activity.
    pub last_data_ps: Ps,
}

impl DramStats {
    /// Mean read latency in nanoseconds.
    pub fn mean_read_latency_ns(&self) -> f64 {
        if self.reads == 0 {
            0.0
        } else {
            self.read_latency_ps as f64 / self.reads as f64 / 1000.0
        }
    }

    /// Fraction of requests that hit an open row.
    pub fn row_hit_rate(&self) -> f64 {
        row_hit_rate(self.row_hits, self.row_misses, self.row_conflicts)
    }
}

/// Row hits over all requests, from the counts of the three row outcomes (0 without requests).
pub fn row_hit_rate(hits: u64, misses: u64, conflicts: u64) -> f64 {
    let n = hits + misses + conflicts;
    if n == 0 {
        0.0
    } else {
        hits as f64 / n as f64
    }
}

/// Timing in DRAM clocks, from the configuration.
#[derive(Clone, Copy, Debug)]
struct T {
    rcd: Clk,
    rp: Clk,
    rpab: Clk,
    ras: Clk,
    rc: Clk,
    rrd: Clk,
    faw: Clk,
    ppd: Clk,
    ccd: Clk,
    bl: Clk,
    cwl: Clk,
    /// RD to data end (`CL + tDQSCK + BL`).
    read_latency: Clk,
    rd_to_wr: Clk,
    wr_to_rd: Clk,
    rd_to_pre: Clk,
    wr_to_pre: Clk,
    refi: Clk,
    rfc: Clk,
}

/// The DRAM: either the LPDDR4 model or an ideal memory (validation against the cosimulation,
/// whose memory answers the cycle after the request and has no bandwidth limit).
#[derive(Clone, Debug)]
pub struct Dram {
    line_shift: u32,
    ch_bits: u32,
    bank_bits: u32,
    col_bits: u32,
    bank_first: bool,
    bank_xor: bool,
    ck: Ps,
    /// `floor((2^64 - 1) / ck)`, for [`ceil_div`].
    ck_inv: u64,
    t: T,
    channels: Vec<Channel>,
    /// Write-mode watermarks: enter above `hi` writes, leave below `lo`.
    hi: usize,
    lo: usize,
    /// Requests of a queue the scheduler looks at (1: in order).
    window: usize,
    cap: u32,
    /// Data time per ticket (`PENDING` while queued), and the free tickets.
    arrivals: Vec<Ps>,
    free_tickets: Vec<u32>,
    ticket_channel: Vec<u32>,
    /// Bank and row of each ticket's read.
    ticket_place: Vec<(u32, u32)>,
    ideal: Option<Ps>,
    stats: DramStats,
}

/// `ceil(t / d)` by a multiply, with `inv = floor((2^64 - 1) / d)` (`d > 0`): `t inv / 2^64`
/// is below `t / d` and above `t / d - 1`, so one correction step gives the floor.
#[inline]
fn ceil_div(t: u64, d: u64, inv: u64) -> u64 {
    let mut q = ((t as u128 * inv as u128) >> 64) as u64;
    let mut r = t - q * d;
    if r >= d {
        q += 1;
        r -= d;
    }
    q + (r != 0) as u64
}

/// The write-mode watermarks `(high, low)` of a `write_queue`-entry write queue (Ramulator's
/// `int(0.8 * size)` and `int(0.2 * size)`): write mode starts above `high` waiting writes and
/// ends below `low`, so a low watermark of 0 never ends it ([`DramConfig::check`] refuses such
/// queues).
pub fn write_watermarks(write_queue: u32) -> (usize, usize) {
    let wq = write_queue as f64;
    ((0.8 * wq) as usize, (0.2 * wq) as usize)
}

impl Dram {
    /// The model of `cfg` (which must pass [`DramConfig::check`]).
    pub fn new(cfg: &DramConfig) -> Self {
        let bl = cfg.n_bl;
        let t = T {
            rcd: cfg.n_rcd,
            rp: cfg.n_rp,
            rpab: cfg.n_rpab,
            ras: cfg.n_ras,
            rc: cfg.n_rc,
            rrd: cfg.n_rrd,
            faw: cfg.n_faw,
            ppd: cfg.n_ppd,
            ccd: cfg.n_ccd.max(bl),
            bl,
            cwl: cfg.n_cwl,
            read_latency: cfg.n_cl + cfg.n_dqsck + bl,
            rd_to_wr: (cfg.n_cl + bl + cfg.n_dqsck + 1).saturating_sub(cfg.n_cwl),
            wr_to_rd: cfg.n_cwl + bl + cfg.n_wtr + 1,
            rd_to_pre: cfg.n_rtp,
            wr_to_pre: cfg.n_cwl + bl + cfg.n_wr,
            refi: if cfg.n_refi == 0 { NEVER } else { cfg.n_refi },
            rfc: cfg.n_rfc,
        };
        let channels = (0..cfg.channels)
            .map(|_| Channel {
                banks: vec![Bank::default(); cfg.banks as usize],
                idx: [Index::new(cfg.banks as usize), Index::new(cfg.banks as usize)],
                ..Channel::default()
            })
            .collect();
        let (hi, lo) = write_watermarks(cfg.write_queue);
        Dram {
            line_shift: cfg.line_bytes.trailing_zeros(),
            ch_bits: cfg.channels.trailing_zeros(),
            bank_bits: cfg.banks.trailing_zeros(),
            col_bits: (cfg.row_bytes / cfg.line_bytes).trailing_zeros(),
            bank_first: cfg.mapping == "RoCoBaCh",
            bank_xor: cfg.bank_xor,
            ck: cfg.t_ck_ps.max(1),
            ck_inv: u64::MAX / cfg.t_ck_ps.max(1),
            t,
            channels,
            hi,
            lo,
            window: (cfg.read_queue as usize).max(1),
            cap: cfg.bypass_cap,
            arrivals: Vec::new(),
            free_tickets: Vec::new(),
            ticket_channel: Vec::new(),
            ticket_place: Vec::new(),
            ideal: None,
            stats: DramStats::default(),
        }
    }

    /// An ideal memory: every read completes `latency_ps` after its issue, writes are free,
    /// nothing else limits.
    pub fn ideal(line_bytes: u32, latency_ps: Ps) -> Self {
        let mut d = Dram::new(&DramConfig { line_bytes, ..DramConfig::default() });
        d.ideal = Some(latency_ps);
        d
    }

    /// True for the ideal memory.
    pub fn is_ideal(&self) -> bool {
        self.ideal.is_some()
    }

    /// Counters so far.
    pub fn stats(&self) -> DramStats {
        self.stats
    }

    /// The bytes of the address space the model maps to distinct rows: every address below it
    /// has a row below the closed-bank marker (at most `2^64`).
    pub fn address_space(&self) -> u128 {
        let shift = self.line_shift + self.ch_bits + self.bank_bits + self.col_bits;
        ((CLOSED as u128) << shift.min(64)).min(1 << 64)
    }

    /// `(channel, bank, row)` of the line holding byte `addr`. With `bank_xor` the bank index is
    /// XORed with the low row bits (permutation-based interleaving, as many memory controllers
    /// do), so streams whose bases are aligned alike do not all fall into the same bank.
    pub fn map(&self, addr: u64) -> (usize, usize, u32) {
        let line = addr >> self.line_shift;
        let ch = (line & ((1 << self.ch_bits) - 1)) as usize;
        let rest = line >> self.ch_bits;
        let mask = (1u64 << self.bank_bits) - 1;
        let (bank, row) = if self.bank_first {
            let bank = rest & mask;
            (bank, rest >> (self.bank_bits + self.col_bits))
        } else {
            let r = rest >> self.col_bits;
            (r & mask, r >> self.bank_bits)
        };
        let bank = if self.bank_xor { bank ^ (row & mask) } else { bank };
        (ch, bank as usize, row as u32)
    }

    /// The first clock at or after `t`.
    fn clock_of(&self, t: Ps) -> Clk {
        ceil_div(t, self.ck, self.ck_inv)
    }

    /// Reads the line holding `addr`, issued at `t`; returns when its data has arrived.
    pub fn read(&mut self, t: Ps, addr: u64) -> Ps {
        let ticket = self.submit_read(t, addr);
        let done = self.arrival(ticket);
        self.release(ticket);
        done
    }

    /// Queues a read of the line holding `addr`, issued at `t` (not before any earlier
    /// submission).
    pub fn submit_read(&mut self, t: Ps, addr: u64) -> Ticket {
        let _phase = profile::enter(Phase::Dram);
        self.stats.reads += 1;
        let ticket = self.new_ticket();
        if let Some(l) = self.ideal {
            self.stats.read_latency_ps += l;
            self.arrivals[ticket as usize] = t + l;
            return Ticket(ticket);
        }
        let req = self.request(t, addr, false, ticket);
        let c = self.ticket_channel[ticket as usize] as usize;
        self.arrivals[ticket as usize] = PENDING;
        self.push(c, Q::Read, req);
        self.replan_after_push(c, Q::Read);
        Ticket(ticket)
    }

    /// Posts a write of the line holding `addr` at `t` (returns at once; served in write mode).
    pub fn write(&mut self, t: Ps, addr: u64) {
        let _phase = profile::enter(Phase::Dram);
        self.stats.writes += 1;
        if self.ideal.is_some() {
            return;
        }
        let req = self.request(t, addr, true, u32::MAX);
        let c = self.map(addr).0;
        self.push(c, Q::Write, req);
        self.replan_after_push(c, Q::Write);
    }

    /// A request of `addr` issued at `t`, its channel advanced to `t`.
    fn request(&mut self, t: Ps, addr: u64, write: bool, ticket: u32) -> Req {
        // A row equal to the closed-bank marker would never be found open: its request would
        // wait forever. Inputs are checked against the address space before they come here.
        assert!((addr as u128) < self.address_space(), "address {addr:#x} beyond the DRAM's address space");
        let (c, b, r) = self.map(addr);
        if !write {
            self.ticket_channel[ticket as usize] = c as u32;
            self.ticket_place[ticket as usize] = (b as u32, r);
        }
        let k = self.clock_of(t);
        self.advance(c, k);
        Req {
            arrive: k.max(self.channels[c].clk),
            issue: t,
            bank: b as u32,
            row: r,
            line: addr >> self.line_shift,
            ticket,
            write,
            first: true,
            seq: 0,
        }
    }

    /// Appends `r` to read or write queue `q` of channel `c`.
    fn push(&mut self, c: usize, q: Q, mut r: Req) {
        let window = self.window;
        let ch = &mut self.channels[c];
        let ix = &mut ch.idx[q.index()];
        r.seq = ix.next_seq;
        ix.next_seq += 1;
        ix.slots[r.bank as usize].list.push_back((r.seq, r.row));
        let queue = if q == Q::Read { &mut ch.readq } else { &mut ch.writeq };
        queue.push_back(r);
        if queue.len() <= window {
            ix.enter(r.seq, r.bank, r.row, ch.banks[r.bank as usize].open);
        }
    }

    /// A free ticket (a returned one, or a new slot).
    fn new_ticket(&mut self) -> u32 {
        self.free_tickets.pop().unwrap_or_else(|| {
            self.arrivals.push(PENDING);
            self.ticket_channel.push(0);
            self.ticket_place.push((0, 0));
            (self.arrivals.len() - 1) as u32
        })
    }

    /// A read answered at `done` without a DRAM access (the line is in a queued write).
    pub fn forwarded_read(&mut self, done: Ps) -> Ticket {
        self.stats.reads += 1;
        self.stats.forwarded += 1;
        let ticket = self.new_ticket();
        self.arrivals[ticket as usize] = done;
        Ticket(ticket)
    }

    /// When the data of `ticket` arrives (advancing its channel as far as needed).
    pub fn arrival(&mut self, ticket: Ticket) -> Ps {
        let _phase = profile::enter(Phase::Dram);
        let k = ticket.0 as usize;
        let c = self.ticket_channel[k] as usize;
        while self.arrivals[k] == PENDING {
            self.step(c, NEVER);
        }
        self.arrivals[k]
    }

    /// Returns a ticket whose arrival is no longer needed (it is still served if queued).
    pub fn release(&mut self, ticket: Ticket) {
        let _phase = profile::enter(Phase::Dram);
        let k = ticket.0 as usize;
        if self.arrivals[k] == PENDING {
            self.arrival(ticket);
        }
        self.free_tickets.push(ticket.0);
    }

    /// The data time of `ticket` if its read command has issued by `now` (its channel advanced
    /// to `now`, never further: an event-driven caller can poll without running a channel ahead
    /// of requests still to come); else a time, after `now`, before which its data cannot
    /// arrive.
    pub fn poll(&mut self, ticket: Ticket, now: Ps) -> Result<Ps, Ps> {
        let _phase = profile::enter(Phase::Dram);
        let k = ticket.0 as usize;
        if self.arrivals[k] == PENDING {
            let c = self.ticket_channel[k] as usize;
            self.advance_to(c, now);
            if self.arrivals[k] == PENDING {
                let ch = &self.channels[c];
                let (bank, row) = self.ticket_place[k];
                let r = &Req { bank, row, ..Req::default() };
                let rd = self.read_bound(c, r).max(ch.clk + 1);
                return Err(((rd + self.t.read_latency) * self.ck).max(now + 1));
            }
        }
        Ok(self.arrivals[k])
    }

    /// A clock before which the read command of queued read `r` cannot issue.
    fn read_bound(&self, c: usize, r: &Req) -> Clk {
        let (cmd, at) = self.next_cmd(c, r);
        match cmd {
            Cmd::Act => at + self.t.rcd,
            Cmd::Pre => at + self.t.rp + self.t.rcd,
            _ => at,
        }
    }

    /// The data time of `ticket` if its read command has issued (without advancing anything).
    pub fn scheduled(&self, ticket: Ticket) -> Option<Ps> {
        let a = self.arrivals[ticket.0 as usize];
        (a != PENDING).then_some(a)
    }

    /// Reads of channel `c` in its read queue (not yet activated or read) at its clock.
    pub fn read_queue_len(&self, c: usize) -> usize {
        self.channels[c].readq.len()
    }

    /// Writes of channel `c` in its write queue at its clock.
    pub fn write_queue_len(&self, c: usize) -> usize {
        self.channels[c].writeq.len()
    }

    /// True when a write of the line holding `addr` waits in its channel's write queue.
    pub fn write_queued(&self, addr: u64) -> bool {
        let line = addr >> self.line_shift;
        self.channels[self.map(addr).0].writeq.iter().any(|w| w.line == line)
    }

    /// The time of channel `c`'s clock.
    pub fn channel_time(&self, c: usize) -> Ps {
        self.channels[c].clk * self.ck
    }

    /// Advances channel `c` to time `t` (no effect if it is already there).
    pub fn advance_to(&mut self, c: usize, t: Ps) {
        let k = self.clock_of(t);
        self.advance(c, k);
    }

    /// The time of the next clock on which channel `c` can change (issue a command or queue a
    /// refresh) if no request arrives before it.
    pub fn next_change(&mut self, c: usize) -> Ps {
        self.update_mode(c);
        let plan = self.plan(c);
        self.channels[c].plan = Some(plan);
        plan.at.saturating_mul(self.ck)
    }

    /// Advances channel `c` until `done` holds of it; returns its time then.
    pub fn advance_until(&mut self, c: usize, done: impl Fn(&Dram) -> bool) -> Ps {
        while !done(self) {
            self.step(c, NEVER);
        }
        self.channel_time(c)
    }

    /// The latest write command's time over all channels.
    pub fn last_write_command(&self) -> Ps {
        self.channels.iter().map(|c| c.last_wr * self.ck).max().unwrap_or(0)
    }

    /// Serves every queued read and write (writes drain as at the end of Ramulator's run);
    /// returns when the last data has left (at least `t`).
    pub fn flush(&mut self, t: Ps) -> Ps {
        let _phase = profile::enter(Phase::Dram);
        if self.ideal.is_some() {
            return t;
        }
        let k = self.clock_of(t);
        for c in 0..self.channels.len() {
            self.advance(c, k);
            self.channels[c].flushing = true;
            self.channels[c].plan = None;
            while !self.idle(c) {
                self.step(c, NEVER);
            }
            self.channels[c].flushing = false;
            self.channels[c].plan = None;
        }
        self.stats.last_data_ps.max(t)
    }

    /// No request waits in channel `c`.
    fn idle(&self, c: usize) -> bool {
        let ch = &self.channels[c];
        ch.readq.is_empty() && ch.writeq.is_empty() && ch.actq.is_empty()
    }

    /// Ticks channel `c` until its clock is `k`.
    fn advance(&mut self, c: usize, k: Clk) {
        while self.channels[c].clk < k {
            self.step(c, k);
        }
    }

    /// Skips to the next clock (at most `limit`) on which channel `c` can issue a command or
    /// queue a refresh, and ticks it.
    fn step(&mut self, c: usize, limit: Clk) {
        self.update_mode(c);
        let plan = match self.channels[c].plan {
            Some(p) => p,
            None => {
                let p = self.plan(c);
                self.channels[c].plan = Some(p);
                p
            }
        };
        let ch = &mut self.channels[c];
        assert!(plan.at != NEVER || limit != NEVER, "DRAM channel {c} waits for nothing");
        if plan.at > limit {
            ch.clk = ch.clk.max(limit);
            return;
        }
        ch.clk = plan.at;
        ch.plan = None;
        match plan.pick {
            Pick::Issue(q, i, cmd) => self.issue(c, q, i, cmd, plan.at),
            Pick::Refresh(cmd) => self.refresh_command(c, cmd, plan.at),
            Pick::Slow => self.tick(c),
        }
    }

    /// Write mode by Ramulator's rule (a fixed point after one application).
    fn update_mode(&mut self, c: usize) {
        let (hi, lo) = (self.hi, self.lo);
        let ch = &mut self.channels[c];
        let hi = if ch.flushing { 0 } else { hi };
        if !ch.write_mode {
            if ch.writeq.len() > hi || ch.readq.is_empty() {
                ch.write_mode = true;
                ch.plan = None;
                if !ch.writeq.is_empty() {
                    self.stats.drains += 1;
                }
            }
        } else if ch.writeq.len() < lo && !ch.readq.is_empty() {
            ch.write_mode = false;
            ch.plan = None;
        }
    }

    /// The next command of `r` and the clock from which it can issue.
    fn next_cmd(&self, c: usize, r: &Req) -> (Cmd, Clk) {
        self.channels[c].next_cmd(r)
    }

    /// A request whose next command is a hit of a row that has served more than the cap.
    fn capped(&self, c: usize, r: &Req) -> bool {
        let b = &self.channels[c].banks[r.bank as usize];
        b.open == r.row && b.hits > self.cap
    }

    /// The refresh's next command and its clock.
    fn refresh_cmd(&self, c: usize) -> (Cmd, Clk) {
        self.channels[c].refresh_cmd()
    }

    /// The queue served outside the activate queue (refresh aside).
    fn mode_queue(&self, c: usize) -> Q {
        if self.channels[c].write_mode {
            Q::Write
        } else {
            Q::Read
        }
    }

    fn queue(&self, c: usize, q: Q) -> &VecDeque<Req> {
        let ch = &self.channels[c];
        match q {
            Q::Act => &ch.actq,
            Q::Read => &ch.readq,
            Q::Write => &ch.writeq,
        }
    }

    /// FRFCFS_Cap over the first `window` requests of queue `q` at clock `now`: the oldest
    /// whose next command can issue (a capped hit counts as not ready), else the oldest. Returns
    /// its index, its command and whether that command can issue now.
    fn head(&self, c: usize, q: Q, now: Clk) -> Option<(usize, Cmd, bool)> {
        let queue = self.queue(c, q);
        // Ramulator scans its whole activate queue; the window bounds the read and write queues.
        let n = if q == Q::Act { queue.len() } else { queue.len().min(self.window) };
        let mut oldest: Option<usize> = None;
        let mut best: Option<(usize, Cmd)> = None;
        for i in 0..n {
            let r = &queue[i];
            if oldest.is_none_or(|o| r.arrive < queue[o].arrive) {
                oldest = Some(i);
            }
            let (cmd, at) = self.next_cmd(c, r);
            if at <= now && !self.capped(c, r) && best.is_none_or(|(b, _)| r.arrive < queue[b].arrive) {
                best = Some((i, cmd));
            }
        }
        if let Some((i, cmd)) = best {
            return Some((i, cmd, true));
        }
        let o = oldest?;
        let (cmd, at) = self.next_cmd(c, &queue[o]);
        Some((o, cmd, at <= now))
    }

    /// What channel `c` does next if no request arrives first: the clock (after its current
    /// one) and the command, as [`Dram::tick`] would choose it then ([`Channel::plan`]).
    fn plan(&mut self, c: usize) -> Plan {
        let (window, cap, refi) = (self.window, self.cap, self.t.refi);
        let plan = self.channels[c].plan(window, cap, refi);
        #[cfg(test)]
        assert_eq!(plan, self.plan_reference(c), "the one-pass plan against the reference");
        plan
    }

    /// Updates channel `c`'s plan for the request just appended to queue `q` (the youngest):
    /// it changes the plan only if it can issue before the planned clock (then it is the only
    /// request that can), or at it (then the plan is made again).
    fn replan_after_push(&mut self, c: usize, q: Q) {
        let ch = &self.channels[c];
        let Some(plan) = ch.plan else { return };
        let n = self.queue(c, q).len() - 1;
        if ch.ref_pending > 0 || q != self.mode_queue(c) || n >= self.window {
            // A refresh goes first, the queue is not served now (a mode change clears the
            // plan), or the scheduler does not look that far.
            return;
        }
        let r = self.queue(c, q)[n];
        if n == 0 || self.capped(c, &r) {
            // The only request, or a capped hit that can issue only as the oldest.
            if n == 0 {
                self.channels[c].plan = None;
            }
            return;
        }
        let (cmd, at) = self.next_cmd(c, &r);
        let at = at.max(ch.clk + 1);
        let ch = &mut self.channels[c];
        if at < plan.at {
            ch.plan = Some(Plan { at, pick: Pick::Issue(q, n, cmd) });
        } else if at == plan.at {
            ch.plan = None;
        }
    }

    /// Issues the refresh's `cmd` at clock `now`.
    fn refresh_command(&mut self, c: usize, cmd: Cmd, now: Clk) {
        self.command(c, cmd, 0, 0, now);
        if cmd == Cmd::Ref {
            self.channels[c].ref_pending -= 1;
            self.stats.refreshes += 1;
        }
    }

    /// One clock of channel `c`'s controller (its clock already advanced to it), by the rules
    /// directly: used on the clocks where a refresh is queued.
    fn tick(&mut self, c: usize) {
        let now = self.channels[c].clk;
        if now - self.channels[c].refreshed >= self.t.refi {
            let ch = &mut self.channels[c];
            ch.ref_pending += 1;
            ch.refreshed = now;
            // LPDDR4 lets a controller postpone at most 8 refreshes; more means the controller
            // starves its refresh (the livelock of 2026-11-25 grew this without bound).
            #[cfg(test)]
            assert!(
                ch.ref_pending <= MAX_POSTPONED_REFRESHES,
                "channel {c}: {} refreshes pending at clock {now}",
                ch.ref_pending
            );
        }
        self.update_mode(c);
        self.channels[c].plan = None;
        if let Some((i, cmd, true)) = self.head(c, Q::Act, now) {
            self.issue(c, Q::Act, i, cmd, now);
            return;
        }
        if self.channels[c].ref_pending > 0 {
            let (cmd, at) = self.refresh_cmd(c);
            if at <= now {
                self.refresh_command(c, cmd, now);
            }
            return;
        }
        let q = self.mode_queue(c);
        if let Some((i, cmd, true)) = self.head(c, q, now) {
            self.issue(c, q, i, cmd, now);
        }
    }

    /// Issues `cmd` for request `i` of queue `q` at clock `now`.
    fn issue(&mut self, c: usize, q: Q, i: usize, cmd: Cmd, now: Clk) {
        let ch = &mut self.channels[c];
        let queue = match q {
            Q::Act => &mut ch.actq,
            Q::Read => &mut ch.readq,
            Q::Write => &mut ch.writeq,
        };
        let r = &mut queue[i];
        if r.first {
            r.first = false;
            let open = ch.banks[r.bank as usize].open;
            if open == r.row {
                self.stats.row_hits += 1;
            } else if open == CLOSED {
                self.stats.row_misses += 1;
            } else {
                self.stats.row_conflicts += 1;
            }
            if q == Q::Read && i > 0 {
                self.stats.reordered += 1;
            }
        }
        let r = *r;
        if matches!(cmd, Cmd::Act | Cmd::Rd | Cmd::Wr) {
            // Mostly the oldest.
            if i == 0 {
                queue.pop_front();
            } else {
                queue.remove(i);
            }
            if q != Q::Act {
                let ix = &mut ch.idx[q.index()];
                ix.leave(r.seq, r.bank);
                if let Some(e) = queue.get(self.window - 1) {
                    ix.enter(e.seq, e.bank, e.row, ch.banks[e.bank as usize].open);
                }
            }
        }
        if cmd == Cmd::Act {
            // Ramulator promotes the request to the activate queue.
            ch.actq.push_back(r);
        }
        self.command(c, cmd, r.bank as usize, r.row, now);
        match cmd {
            Cmd::Rd => {
                let done = (now + self.t.read_latency) * self.ck;
                self.stats.read_latency_ps += done.saturating_sub(r.issue);
                self.stats.last_data_ps = self.stats.last_data_ps.max(done);
                self.arrivals[r.ticket as usize] = done;
            }
            Cmd::Wr => {
                let end = (now + self.t.cwl + self.t.bl) * self.ck;
                self.stats.last_data_ps = self.stats.last_data_ps.max(end);
                self.channels[c].last_wr = now;
            }
            _ => {}
        }
    }

    /// The state and timing effects of `cmd` to bank `b` (row `row`) at clock `now`.
    fn command(&mut self, c: usize, cmd: Cmd, b: usize, row: u32, now: Clk) {
        let t = self.t;
        let ch = &mut self.channels[c];
        let up = |x: &mut Clk, v: Clk| *x = (*x).max(v);
        match cmd {
            Cmd::Act => {
                up(&mut ch.act, now + t.rrd);
                ch.acts.push_back(now);
                if ch.acts.len() > 4 {
                    ch.acts.pop_front();
                }
                if ch.acts.len() == 4 {
                    up(&mut ch.act, ch.acts[0] + t.faw);
                }
                up(&mut ch.prea, now + t.ras);
                let bank = &mut ch.banks[b];
                bank.open = row;
                bank.hits = 0;
                ch.idx[0].reopen(b);
                ch.idx[1].reopen(b);
                up(&mut bank.rd, now + t.rcd);
                up(&mut bank.wr, now + t.rcd);
                up(&mut bank.act, now + t.rc);
                up(&mut bank.pre, now + t.ras);
            }
            Cmd::Pre => {
                up(&mut ch.pre, now + t.ppd);
                up(&mut ch.refresh, now + t.rp);
                let bank = &mut ch.banks[b];
                bank.open = CLOSED;
                up(&mut bank.act, now + t.rp);
                ch.idx[0].reopen(b);
                ch.idx[1].reopen(b);
            }
            Cmd::Rd => {
                up(&mut ch.rd, now + t.ccd);
                up(&mut ch.wr, now + t.rd_to_wr);
                up(&mut ch.prea, now + t.rd_to_pre);
                let bank = &mut ch.banks[b];
                bank.hits += 1;
                up(&mut bank.pre, now + t.rd_to_pre);
            }
            Cmd::Wr => {
                up(&mut ch.wr, now + t.ccd);
                up(&mut ch.rd, now + t.wr_to_rd);
                up(&mut ch.prea, now + t.wr_to_pre);
                let bank = &mut ch.banks[b];
                bank.hits += 1;
                up(&mut bank.pre, now + t.wr_to_pre);
            }
            Cmd::Prea => {
                up(&mut ch.act, now + t.rpab);
                up(&mut ch.refresh, now + t.rpab);
                for bank in ch.banks.iter_mut() {
                    bank.open = CLOSED;
                }
                for ix in ch.idx.iter_mut() {
                    ix.reopen_all();
                }
            }
            Cmd::Ref => {
                up(&mut ch.act, now + t.rfc);
                up(&mut ch.refresh, now + t.rfc);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The plan as first written (a scan of each queue into candidate lists, then a pick over
    /// them): every [`Dram::plan`] of the unit tests is checked against it.
    impl Dram {
        /// The earliest clock at which a head of the activate queue can issue (its state otherwise
        /// unchanged), with each of its requests' ready clock in `ready`, and the
        /// index of the oldest.
        fn scan_act(&self, c: usize, ready: &mut Vec<Clk>) -> (Clk, Option<usize>) {
            let queue = &self.channels[c].actq;
            ready.clear();
            let mut next = NEVER;
            for r in queue {
                let at = self.channels[c].ready(r, self.cap);
                ready.push(at);
                next = next.min(at);
            }
            let oldest = (0..ready.len()).min_by_key(|&i| (queue[i].arrive, i));
            if let Some(o) = oldest {
                next = next.min(self.next_cmd(c, &queue[o]).1);
            }
            (next, oldest)
        }

        /// FRFCFS_Cap's pick of the activate queue at clock `now` from a [`Dram::scan_act`] of it:
        /// the oldest ready request, else the oldest if its command can issue.
        fn pick_act(&self, c: usize, ready: &[Clk], oldest: Option<usize>, now: Clk) -> Option<usize> {
            let queue = &self.channels[c].actq;
            let mut best: Option<usize> = None;
            for (i, &at) in ready.iter().enumerate() {
                if at <= now && best.is_none_or(|b| queue[i].arrive < queue[b].arrive) {
                    best = Some(i);
                }
            }
            best.or_else(|| oldest.filter(|&o| self.next_cmd(c, &queue[o]).1 <= now))
        }

        /// The candidates of read or write queue `q` (in age order): every request of the window
        /// with its ready clock ([`Channel::ready`]; a capped hit is never ready), into `cands`,
        /// straight from the queue (not from its [`Index`]); returns the earliest clock at which
        /// a head of the queue can issue (the oldest request included, capped or not).
        fn scan_classes_reference(&mut self, c: usize, q: Q, cands: &mut Vec<(Clk, u64)>) -> Clk {
            cands.clear();
            let ch = &self.channels[c];
            let queue = if q == Q::Read { &ch.readq } else { &ch.writeq };
            let Some(front) = queue.front() else { return NEVER };
            let mut next = NEVER;
            for r in queue.iter().take(self.window) {
                let at = ch.ready(r, self.cap);
                cands.push((at, r.seq));
                next = next.min(at);
            }
            next.min(self.next_cmd(c, front).1)
        }

        /// FRFCFS_Cap's pick of read or write queue `q` at clock `now` from its
        /// [`Dram::scan_classes`]: the oldest ready request, else the oldest if its command can
        /// issue; as an index into the queue.
        fn pick_classes(&self, c: usize, q: Q, cands: &[(Clk, u64)], now: Clk) -> Option<usize> {
            let queue = self.queue(c, q);
            let best = cands.iter().filter(|&&(at, _)| at <= now).map(|&(_, s)| s).min();
            match best {
                // Mostly the oldest.
                Some(s) if queue[0].seq == s => Some(0),
                Some(s) => Some(queue.binary_search_by_key(&s, |r| r.seq).expect("an indexed request")),
                None => queue.front().filter(|r| self.next_cmd(c, r).1 <= now).map(|_| 0),
            }
        }

        /// What channel `c` does next if no request arrives first: the clock (after its current
        /// one) and the command, as [`Dram::tick`] would choose it then.
        pub(super) fn plan_reference(&mut self, c: usize) -> Plan {
            let mut ready_a = Vec::new();
            let mut cands = Vec::new();
            let t_ref = self.channels[c].refreshed.saturating_add(self.t.refi);
            let (next_a, oldest_a) = self.scan_act(c, &mut ready_a);
            let mode = self.mode_queue(c);
            let mut next = next_a;
            let refresh = (self.channels[c].ref_pending > 0).then(|| self.refresh_cmd(c));
            match refresh {
                Some((_, at)) => next = next.min(at),
                None => next = next.min(self.scan_classes_reference(c, mode, &mut cands)),
            }
            let at = next.min(t_ref).max(self.channels[c].clk + 1);
            let pick = if at >= t_ref {
                Pick::Slow
            } else if let Some(i) = self.pick_act(c, &ready_a, oldest_a, at) {
                Pick::Issue(Q::Act, i, self.next_cmd(c, &self.channels[c].actq[i]).0)
            } else if let Some((cmd, _)) = refresh {
                Pick::Refresh(cmd)
            } else {
                match self.pick_classes(c, mode, &cands, at) {
                    Some(i) => Pick::Issue(mode, i, self.next_cmd(c, &self.queue(c, mode)[i]).0),
                    None => Pick::Slow,
                }
            };
            Plan { at, pick }
        }
    }

    fn gbs(bytes: u64, ps: Ps) -> f64 {
        bytes as f64 / (ps as f64 * 1e-12) / 1e9
    }

    /// Streams `n` reads with at most `window` outstanding (the next is issued when the oldest
    /// returns); returns the achieved GB/s.
    fn run(d: &mut Dram, addrs: impl Iterator<Item = u64>, window: usize) -> f64 {
        let mut inflight = std::collections::VecDeque::new();
        let mut t = 0;
        let mut n = 0u64;
        let mut last = 0;
        for a in addrs {
            if inflight.len() == window {
                let old = inflight.pop_front().unwrap();
                t = t.max(d.arrival(old));
                d.release(old);
            }
            inflight.push_back(d.submit_read(t, a));
            n += 1;
        }
        for k in inflight {
            last = last.max(d.arrival(k));
            d.release(k);
        }
        gbs(n * 64, last.max(t))
    }

    /// Drives `cfg` with 3000 random mixed reads and writes from `seed` (few rows, so hits,
    /// misses and conflicts all occur), every read answered and released; true when every
    /// queue is empty at the end. Every plan is checked against [`Dram::plan_reference`] on the
    /// way (the model does so under `cfg(test)`).
    fn random_traffic_drains(cfg: &DramConfig, seed: u64) -> bool {
        let mut d = Dram::new(cfg);
        let mut x = seed;
        let mut next = move || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            x
        };
        let (mut t, mut inflight) = (0, VecDeque::new());
        for _ in 0..3000 {
            let r = next();
            // A few rows of every bank and channel.
            let addr = ((r >> 8) % (4 << 17).max(cfg.banks as u64 * 4 * 16 * 1024)) & !63;
            t += r % 4 * 700;
            if r % 5 == 0 {
                d.write(t, addr);
            } else {
                inflight.push_back(d.submit_read(t, addr));
            }
            if inflight.len() > (r % 48) as usize {
                let k = inflight.pop_front().unwrap();
                if r % 3 == 0 {
                    // Poll as the engine does, without running the channel ahead.
                    let _ = d.poll(k, t);
                }
                t = t.max(d.arrival(k).saturating_sub(r % 2 * 20_000));
                d.release(k);
            }
        }
        for k in inflight {
            d.arrival(k);
            d.release(k);
        }
        d.flush(t);
        (0..4).all(|c| d.read_queue_len(c) == 0 && d.write_queue_len(c) == 0)
    }

    /// The livelock found on 2026-11-25: with a window of one, the activate queue's head alone
    /// was scanned, and two requests to one bank in it (rows 2 and 3 of bank 74 of channel 2)
    /// closed each other's row forever, each ACT sending its request to the back; the pending
    /// refresh grew without bound and no read was served. Ramulator scans the whole queue.
    #[test]
    fn random_traffic_on_128_banks_finishes() {
        let cfg = DramConfig {
            read_queue: 0,
            bypass_cap: 16,
            write_queue: 32,
            banks: 128,
            n_refi: 700,
            ..DramConfig::default()
        };
        assert!(random_traffic_drains(&cfg, 8026784204512207910));
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(24))]

        /// Random mixed reads and writes on configurations that reach the window's end, the row
        /// cap, write mode and refresh: every plan matches the plain reference
        /// ([`Dram::plan_reference`]), no more than 8 refreshes are ever pending, and every
        /// request is served.
        #[test]
        fn random_traffic_drains_on_every_configuration(
            seed in 1u64..u64::MAX,
            read_queue in proptest::sample::select(vec![0u32, 1, 3, 8, 32]),
            bypass_cap in proptest::sample::select(vec![0u32, 1, 4, 16]),
            write_queue in proptest::sample::select(vec![10u32, 32]),
            banks in proptest::sample::select(vec![2u32, 8, 128]),
        ) {
            let cfg = DramConfig { read_queue, bypass_cap, write_queue, banks, n_refi: 700, ..DramConfig::default() };
            proptest::prop_assert!(random_traffic_drains(&cfg, seed));
        }
    }

    #[test]
    fn ceil_div_by_multiply_is_div_ceil() {
        let mut x = 0x9E37_79B9_7F4A_7C15u64;
        for d in [1u64, 2, 3, 625, 750, 1000, 1 << 20, u64::MAX / 3, u64::MAX] {
            let inv = u64::MAX / d;
            let edges = [0, 1, d - 1, d, d.saturating_add(1), 2 * (d / 2), u64::MAX - 1, u64::MAX];
            for t in edges.into_iter().chain((0..10_000).map(|_| {
                x ^= x << 13;
                x ^= x >> 7;
                x ^= x << 17;
                x >> (x % 64)
            })) {
                assert_eq!(ceil_div(t, d, inv), t.div_ceil(d), "{t} / {d}");
            }
        }
    }

    #[test]
    fn mapping_interleaves_channels_then_columns() {
        let d = Dram::new(&DramConfig::default());
        assert_eq!(d.map(0), (0, 0, 0));
        assert_eq!(d.map(64), (1, 0, 0));
        assert_eq!(d.map(4 * 64), (0, 0, 0));
        // 4 channels x 4 KB rows: the next bank after 16 KB, the next row after 128 KB.
        assert_eq!(d.map(16 * 1024), (0, 1, 0));
        // Ramulator's RoBaRaCoCh: row 1 of bank 0 after 128 KB.
        assert_eq!(d.map(128 * 1024), (0, 0, 1));
        assert_eq!(d.map(128 * 1024 + 16 * 1024), (0, 1, 1));
        // With the bank XOR, row 1 of bank 0 is XORed onto bank 1.
        let x = Dram::new(&DramConfig { bank_xor: true, ..DramConfig::default() });
        assert_eq!(x.map(128 * 1024), (0, 1, 1));
        assert_eq!(x.map(128 * 1024 + 16 * 1024), (0, 0, 1));
    }

    #[test]
    fn streaming_reaches_most_of_peak_and_random_about_half() {
        let cfg = DramConfig::default();
        let mut d = Dram::new(&cfg);
        let stream = run(&mut d, (0..200_000u64).map(|i| i * 64), 64);
        assert!(d.stats().row_hit_rate() > 0.95);
        let mut d = Dram::new(&cfg);
        let mut x = 0x9E37_79B9_7F4A_7C15u64;
        let random = run(
            &mut d,
            (0..200_000).map(|_| {
                x ^= x << 13;
                x ^= x >> 7;
                x ^= x << 17;
                (x % (1 << 30)) & !63
            }),
            64,
        );
        assert!(d.stats().row_hit_rate() < 0.05);
        // Peak 51.2; refresh costs 288/6247 = 4.6%.
        assert!(stream > 0.88 * 51.2 && stream < 51.2, "stream {stream}");
        // tFAW: 4 activates per 40 ns per channel = 25.6 GB/s at most.
        eprintln!("stream {stream:.2} GB/s, random {random:.2} GB/s");
        assert!(random > 0.3 * 51.2 && random < 0.5 * 51.2, "random {random}");
    }

    /// `streams` sequential streams in their own 1 MB regions (the same bank, other rows), four
    /// lines (one per channel) of each in turn, at most `window` reads outstanding (submitted,
    /// resolved oldest first); returns (GB/s, row-hit rate, reads served out of order).
    fn interleaved(cfg: &DramConfig, streams: u64, lines: u64, window: usize) -> (f64, f64, u64) {
        let mut d = Dram::new(cfg);
        let mut inflight = std::collections::VecDeque::new();
        let (mut t, mut last) = (0, 0);
        for i in 0..lines {
            let (s, k) = ((i / 4) % streams, (i / 4 / streams) * 4 + i % 4);
            if inflight.len() == window {
                let old = inflight.pop_front().unwrap();
                let a = d.arrival(old);
                d.release(old);
                t = t.max(a);
                last = last.max(a);
            }
            inflight.push_back(d.submit_read(t, s * (1 << 20) + k * 64));
        }
        for k in inflight {
            last = last.max(d.arrival(k));
            d.release(k);
        }
        (gbs(lines * 64, last), d.stats().row_hit_rate(), d.stats().reordered)
    }

    #[test]
    fn fr_fcfs_serves_row_hits_of_interleaved_streams_first() {
        let fr = DramConfig::default();
        let in_order = DramConfig { read_queue: 0, ..DramConfig::default() };
        let (bw_fr, hits_fr, moved) = interleaved(&fr, 8, 100_000, 128);
        let (bw_io, hits_io, none) = interleaved(&in_order, 8, 100_000, 128);
        eprintln!("8 streams: FR-FCFS {bw_fr:.2} GB/s ({hits_fr:.3} hits), in order {bw_io:.2} GB/s ({hits_io:.3} hits)");
        assert_eq!(none, 0, "read_queue 0 never reorders");
        assert!(moved > 0);
        assert!(hits_fr > hits_io + 0.1, "hits {hits_fr} vs {hits_io}");
        assert!(bw_fr > 1.2 * bw_io, "bandwidth {bw_fr} vs {bw_io}");
        // One stream is already in row order: the row hits are the same, and first-ready only
        // adds the next bank's activate during the current row's bursts.
        let (a, ha, _) = interleaved(&fr, 1, 20_000, 64);
        let (b, hb, _) = interleaved(&in_order, 1, 20_000, 64);
        eprintln!("1 stream: FR-FCFS {a:.2} GB/s ({ha:.3} hits), in order {b:.2} GB/s ({hb:.3} hits)");
        assert!(a >= b && (ha - hb).abs() < 0.01, "{a} {b}, hits {ha} {hb}");
    }

    #[test]
    fn an_open_row_serves_at_most_cap_hits_past_an_older_conflict() {
        let cfg = DramConfig::default();
        let mut d = Dram::new(&cfg);
        // Opens row 0 of channel 0, bank 0 (its first access).
        let first = d.submit_read(0, 0);
        let (c, b, r) = d.map(0);
        let conflict = (1..64u64)
            .map(|k| k * 128 * 1024)
            .find(|&a| {
                let (c2, b2, r2) = d.map(a);
                c2 == c && b2 == b && r2 != r
            })
            .expect("another row of bank 0");
        let old = d.submit_read(0, conflict);
        // 60 more lines of the open row (channel 0 holds every 4th line; a row has 64 of them).
        let hits: Vec<Ticket> = (1..61u64).map(|k| d.submit_read(0, k * 4 * 64)).collect();
        d.arrival(first);
        let t_old = d.arrival(old);
        let before = hits.iter().filter(|&&h| d.arrival(h) < t_old).count();
        // Column commands are tCCD apart and each pushes the conflict's precharge tRTP (> tCCD)
        // later, so the row serves hits until it has served more than the cap (its first access
        // and `cap` hits); then the hits are not ready and the older conflict's precharge goes.
        assert_eq!(before as u32, cfg.bypass_cap, "hits served before the older conflict");
        assert!(d.stats().reordered >= cfg.bypass_cap as u64);
    }

    /// `Oldest` against its definition: among the candidates ready by the plan clock, the
    /// oldest; the plan clock is the floor if one is ready by it, else the earliest ready clock;
    /// of equal keys the first added; a candidate ready `NEVER` is none, even at clock `NEVER`.
    #[test]
    fn oldest_picks_the_oldest_ready_by_the_plan_clock_and_never_a_never() {
        let floor = 100;
        let mut o = Oldest::new(floor);
        assert_eq!((o.earliest(), o.pick(NEVER)), (NEVER, None));
        o.add(NEVER, 1, 0);
        assert_eq!((o.earliest(), o.pick(NEVER)), (NEVER, None), "a NEVER candidate is none");
        o.add(150, 9, 1);
        o.add(120, 7, 2);
        o.add(120, 5, 3);
        o.add(120, 5, 4);
        assert_eq!(o.earliest(), 120, "the earliest ready clock after the floor");
        assert_eq!(o.pick(119), None);
        assert_eq!(o.pick(120), Some((5, 3)), "the oldest ready then, the first of equal keys");
        o.add(90, 8, 5);
        o.add(100, 6, 6);
        assert_eq!(o.earliest(), floor, "a candidate ready by the floor");
        assert_eq!(o.pick(floor), Some((6, 6)), "the oldest ready by the floor, not the earliest");
    }

    #[test]
    fn ideal_memory_answers_after_a_fixed_latency() {
        let mut d = Dram::ideal(64, 1000);
        assert_eq!(d.read(5, 0), 1005);
        d.write(7, 64);
        assert_eq!(d.stats().reads + d.stats().writes, 2);
    }

    #[test]
    fn write_mode_follows_the_watermarks() {
        let cfg = DramConfig::default();
        let ck = cfg.t_ck_ps;
        let miss = (1 + cfg.n_rcd + cfg.n_cl + cfg.n_dqsck + cfg.n_bl) * ck;
        // A read waits in channel 0 (bank 1) with 25 writes (bank 0): not above 80% of 32, so
        // the read goes first, as a plain miss.
        let mut d = Dram::new(&cfg);
        let read = d.submit_read(0, 16 * 1024);
        for i in 0..25u64 {
            d.write(0, i * 256);
        }
        assert_eq!(d.arrival(read), miss);
        // With 26 writes the channel enters write mode first and stays in it until fewer than
        // 20% of 32 (6) writes remain: 21 writes go before the read.
        let mut d = Dram::new(&cfg);
        let read = d.submit_read(0, 16 * 1024);
        for i in 0..26u64 {
            d.write(0, i * 256);
        }
        d.advance_until(0, |d| d.read_queue_len(0) == 0);
        assert_eq!(d.write_queue_len(0), 5, "writes left when the read leaves the read queue");
        let t = d.arrival(read);
        // The read's activate moves it to the activate queue, the read queue is empty, and the
        // channel enters write mode again for the other 5 while the read waits for tRCD.
        assert_eq!(d.stats().drains, 2);
        assert!(t > miss + 21 * cfg.n_bl * ck, "read at {t}");
        // With no read waiting every write is served; a flush drains the rest, and a read after
        // it waits for the write-to-read turnaround.
        let mut d = Dram::new(&cfg);
        for i in 0..400u64 {
            d.write(i, i * 64);
        }
        let end = d.flush(1000);
        assert!((0..4).all(|c| d.write_queue_len(c) == 0));
        assert!(end > 100 * cfg.n_bl * ck, "100 bursts per channel: {end}");
        assert_eq!(d.stats().writes, 400);
        // The last write went to channel 3 (line 399); read it back there.
        let last_wr = d.last_write_command();
        let r = d.read(end, 399 * 64);
        let turnaround = cfg.n_cwl + cfg.n_bl + cfg.n_wtr + 1;
        assert!(r >= last_wr + (turnaround + cfg.n_cl + cfg.n_dqsck + cfg.n_bl) * ck, "read {r}");
    }
}
