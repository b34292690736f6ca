//! A transaction-level LPDDR4 model: channels, banks with an open row each, a shared data bus per
//! channel, the activation limits and refresh, and posted writes drained in batches.
//!
//! Requests arrive in non-decreasing issue time (the engine serves them in time order). Each
//! 64-byte request is mapped to (channel, bank, row) by [`crate::config::DramConfig::mapping`]
//! and timed at once:
//! - **row hit** (the bank has the row open): column command as soon as the bank allows;
//! - **row miss** (bank closed) or **conflict** (another row open): precharge when allowed
//!   (`tRAS` after the activate, `tRTP` after a read, `tWR` after write data), `tRP`, then
//!   activate, subject to `tRC` (same bank), `tRRD` and the four-activate window `tFAW` (same
//!   channel), then `tRCD` to the column command;
//! - data follows the column command after `CL` (reads) or `CWL` (writes) and occupies the
//!   channel's data bus for `BL` clocks (so column commands are at least `tCCD = BL` apart); a
//!   read takes the earliest free bus slot at or after its data is ready, so a row hit issued
//!   after a slow miss to another bank may return first (bank-level parallelism);
//! - **FR-FCFS read scheduling**: reads wait in a per-channel queue ([`Dram::submit_read`]) and
//!   are timed when their arrival is needed ([`Dram::arrival`]). The scheduler looks at the
//!   first `read_queue` queued reads that had been issued by its decision time (the later of the
//!   oldest read's issue and the column command of the read it scheduled last) and serves the
//!   oldest one that hits an open row, else the one whose bank can activate first (first
//!   ready, the oldest among equals); the oldest is bypassed at most `bypass_cap` times.
//!   `read_queue = 0` serves reads in issue order, timed at once;
//! - **writes** are posted: they return at once and wait in a per-channel queue; when more than
//!   80% of `write_queue` wait, or no read is queued, the channel enters write mode: the queued
//!   reads whose commands come before it are served, then all posted writes drain (first ready,
//!   banks in parallel, write data `tRTRS` after the last read burst), and the reads after the
//!   drain wait for the write-to-read turnaround (`tWTR`), as Ramulator's controller does;
//! - **refresh**: every `tREFI` each channel is blocked for `tRFCab` (after the data already
//!   scheduled, as a controller may postpone refreshes) and all its rows close.
//!
//! Not modelled: command-bus conflicts between banks, reads that arrive after the scheduler
//! needed an earlier read's time (the queue holds what was issued by then), per-bank refresh,
//! power-down, on-die ECC, data bus inversion, rank switching (one rank).

use serde::{Deserialize, Serialize};

use crate::config::DramConfig;

/// Time in picoseconds.
pub type Ps = u64;

const CLOSED: u32 = u32::MAX;

#[derive(Clone, Copy, Debug)]
struct Bank {
    open: u32,
    act: Ps,
    rd_col: Ps,
    wr_end: Ps,
    activated: bool,
}

impl Default for Bank {
    fn default() -> Self {
        Bank { open: CLOSED, act: 0, rd_col: 0, wr_end: 0, activated: false }
    }
}

#[derive(Clone, Debug)]
struct Channel {
    banks: Vec<Bank>,
    /// Reserved data-bus bursts `(start, end)`, sorted, non-overlapping; bursts ending before
    /// the latest issue time are pruned.
    busy: std::collections::VecDeque<(Ps, Ps)>,
    /// Latest end of any burst.
    bus_free: Ps,
    /// No read data before this (write-to-read turnaround after a drain, refresh).
    floor: Ps,
    /// Activate times that can still constrain new ones (`tRRD`, `tFAW`), sorted.
    acts: std::collections::VecDeque<Ps>,
    next_ref: Ps,
    blocked_until: Ps,
    wq: Vec<(u32, u32)>,
    /// Reads waiting for the scheduler, in issue order.
    rq: std::collections::VecDeque<QueuedRead>,
    /// Column command of the read scheduled last (the scheduler's clock).
    last_col: Ps,
    /// Latest end of a read burst.
    read_end: Ps,
    /// No write data before this (read-to-write turnaround).
    write_floor: Ps,
}

/// A read waiting in a channel's queue.
#[derive(Clone, Copy, Debug)]
struct QueuedRead {
    issue: Ps,
    bank: u32,
    row: u32,
    ticket: u32,
    bypassed: u32,
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
    /// Reads served before an older queued read (FR-FCFS row-hit bypasses).
    pub reordered: u64,
    /// Refreshes performed.
    pub refreshes: u64,
    /// Write drains.
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
        let n = self.row_hits + self.row_misses + self.row_conflicts;
        if n == 0 {
            0.0
        } else {
            self.row_hits as f64 / n as f64
        }
    }
}

/// The earliest activate time at or after `x` that keeps `rrd` to every other activate of the
/// channel and at most four activates in any `faw` window; records it. Activates may be placed
/// between earlier-scheduled ones (banks activate out of issue order). `t` is the issue time
/// (activates ending their influence before it are pruned).
fn act_slot(acts: &mut std::collections::VecDeque<Ps>, mut x: Ps, t: Ps, rrd: Ps, faw: Ps) -> Ps {
    while acts.front().is_some_and(|&a| a + faw.max(rrd) <= t) {
        acts.pop_front();
    }
    // `pos` is the partition point of `x` (the first activate after it); `x` only grows, so
    // it moves forward.
    let mut pos = partition_from_back(acts, |&a| a <= x);
    'search: loop {
        while pos < acts.len() && acts[pos] <= x {
            pos += 1;
        }
        // tRRD to the neighbours.
        if pos > 0 && acts[pos - 1] + rrd > x {
            x = acts[pos - 1] + rrd;
            continue;
        }
        if pos < acts.len() && x + rrd > acts[pos] {
            x = acts[pos] + rrd;
            continue;
        }
        // Every five consecutive activates (x among them) must span at least faw.
        for k in 0..5usize {
            // The window holds acts[pos - 4 + k .. pos], x, acts[pos .. pos + k].
            if pos + k < 4 || pos + k > acts.len() {
                continue;
            }
            let first = if k < 4 { acts[pos + k - 4] } else { x };
            let last = if k > 0 { acts[pos + k - 1] } else { x };
            if last - first < faw {
                x = if k == 0 { first + faw } else { acts[pos] + rrd };
                continue 'search;
            }
        }
        acts.insert(pos, x);
        return x;
    }
}

/// `v.partition_point(pred)`, looking at the last few elements first (new requests mostly
/// land near the end of a calendar).
#[inline]
fn partition_from_back<T>(v: &std::collections::VecDeque<T>, pred: impl Fn(&T) -> bool) -> usize {
    let n = v.len();
    for i in (n.saturating_sub(4)..n).rev() {
        if pred(&v[i]) {
            return i + 1;
        }
    }
    if n <= 4 {
        0
    } else {
        v.partition_point(pred)
    }
}

/// The earliest start at or after `ready` of a `bl`-long burst that overlaps no block of
/// `busy` (sorted, non-overlapping), and the index of the first block after it.
fn bus_slot(busy: &std::collections::VecDeque<(Ps, Ps)>, ready: Ps, bl: Ps) -> (usize, Ps) {
    let mut i = partition_from_back(busy, |&(_, e)| e <= ready);
    let mut start = ready;
    while i < busy.len() {
        let (s, e) = busy[i];
        if s >= start + bl {
            break;
        }
        start = start.max(e);
        i += 1;
    }
    (i, start)
}

/// Timing in picoseconds, from the configuration's clock counts.
#[derive(Clone, Copy, Debug)]
struct T {
    cl: Ps,
    dqsck: Ps,
    cwl: Ps,
    rcd: Ps,
    rp: Ps,
    ras: Ps,
    rc: Ps,
    rtp: Ps,
    wtr: Ps,
    wr: Ps,
    rrd: Ps,
    faw: Ps,
    bl: Ps,
    rtrs: Ps,
    refi: Ps,
    rfc: Ps,
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
    t: T,
    channels: Vec<Channel>,
    write_queue: usize,
    read_queue: usize,
    bypass_cap: u32,
    /// Data time per ticket (`PENDING` while queued), and the free tickets.
    arrivals: Vec<Ps>,
    free_tickets: Vec<u32>,
    ticket_channel: Vec<u32>,
    ideal: Option<Ps>,
    stats: DramStats,
    /// `(channel, command time)` of every write drained, when logging ([`Dram::log_writes`]).
    write_log: Option<Vec<(u32, Ps)>>,
}

impl Dram {
    /// The model of `cfg` (which must pass [`DramConfig::check`]).
    pub fn new(cfg: &DramConfig) -> Self {
        let ck = cfg.t_ck_ps;
        let t = T {
            cl: cfg.n_cl * ck,
            dqsck: cfg.n_dqsck * ck,
            cwl: cfg.n_cwl * ck,
            rcd: cfg.n_rcd * ck,
            rp: cfg.n_rp * ck,
            ras: cfg.n_ras * ck,
            rc: cfg.n_rc * ck,
            rtp: cfg.n_rtp * ck,
            wtr: cfg.n_wtr * ck,
            wr: cfg.n_wr * ck,
            rrd: cfg.n_rrd * ck,
            faw: cfg.n_faw * ck,
            bl: cfg.n_bl * ck,
            rtrs: cfg.n_rtrs * ck,
            refi: cfg.n_refi * ck,
            rfc: cfg.n_rfc * ck,
        };
        let channels = (0..cfg.channels)
            .map(|_| Channel {
                banks: vec![Bank::default(); cfg.banks as usize],
                busy: std::collections::VecDeque::new(),
                bus_free: 0,
                floor: 0,
                acts: std::collections::VecDeque::new(),
                // All channels refresh together (staggering would let one refreshing channel
                // stall in-order requesters that stream over all of them).
                next_ref: if t.refi == 0 { Ps::MAX } else { t.refi },
                blocked_until: 0,
                wq: Vec::with_capacity(cfg.write_queue as usize),
                rq: std::collections::VecDeque::new(),
                last_col: 0,
                read_end: 0,
                write_floor: 0,
            })
            .collect();
        Dram {
            line_shift: cfg.line_bytes.trailing_zeros(),
            ch_bits: cfg.channels.trailing_zeros(),
            bank_bits: cfg.banks.trailing_zeros(),
            col_bits: (cfg.row_bytes / cfg.line_bytes).trailing_zeros(),
            bank_first: cfg.mapping == "RoCoBaCh",
            bank_xor: cfg.bank_xor,
            t,
            channels,
            write_queue: cfg.write_queue as usize,
            read_queue: cfg.read_queue as usize,
            bypass_cap: cfg.bypass_cap,
            arrivals: Vec::new(),
            free_tickets: Vec::new(),
            ticket_channel: Vec::new(),
            ideal: None,
            stats: DramStats::default(),
            write_log: None,
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

    /// Reads the line holding `addr`, issued at `t`; returns when its data has arrived (the
    /// read is scheduled with whatever is queued before it, then timed at once).
    pub fn read(&mut self, t: Ps, addr: u64) -> Ps {
        let ticket = self.submit_read(t, addr);
        let done = self.arrival(ticket);
        self.release(ticket);
        done
    }

    /// Queues a read of the line holding `addr`, issued at `t` (not before any earlier
    /// submission). With `read_queue = 0` or the ideal memory it is timed at once.
    pub fn submit_read(&mut self, t: Ps, addr: u64) -> Ticket {
        self.stats.reads += 1;
        let ticket = self.new_ticket();
        if let Some(l) = self.ideal {
            self.stats.read_latency_ps += l;
            self.arrivals[ticket as usize] = t + l;
            return Ticket(ticket);
        }
        let (c, b, r) = self.map(addr);
        self.ticket_channel[ticket as usize] = c as u32;
        if self.read_queue == 0 {
            let done = self.access(t, t, c, b, r, false) + self.t.dqsck;
            self.stats.read_latency_ps += done - t;
            self.arrivals[ticket as usize] = done;
        } else {
            self.arrivals[ticket as usize] = PENDING;
            self.channels[c].rq.push_back(QueuedRead {
                issue: t,
                bank: b as u32,
                row: r,
                ticket,
                bypassed: 0,
            });
        }
        Ticket(ticket)
    }

    /// A free ticket (a returned one, or a new slot).
    fn new_ticket(&mut self) -> u32 {
        self.free_tickets.pop().unwrap_or_else(|| {
            self.arrivals.push(PENDING);
            self.ticket_channel.push(0);
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

    /// When the data of `ticket` arrives (scheduling queued reads as far as needed).
    pub fn arrival(&mut self, ticket: Ticket) -> Ps {
        let k = ticket.0 as usize;
        if self.arrivals[k] == PENDING {
            let c = self.ticket_channel[k] as usize;
            while self.arrivals[k] == PENDING {
                self.schedule_one(c);
            }
        }
        self.arrivals[k]
    }

    /// Returns a ticket whose arrival is no longer needed (it is still served if queued).
    pub fn release(&mut self, ticket: Ticket) {
        let k = ticket.0 as usize;
        if self.arrivals[k] == PENDING {
            self.arrival(ticket);
        }
        self.free_tickets.push(ticket.0);
    }

    /// Serves one queued read of channel `c` (the one the scheduler picks next); false when
    /// none is queued.
    pub fn schedule_next(&mut self, c: usize) -> bool {
        if self.channels[c].rq.is_empty() {
            return false;
        }
        self.schedule_one(c);
        true
    }

    /// The data time of `ticket` if it is already scheduled (without scheduling anything).
    pub fn scheduled(&self, ticket: Ticket) -> Option<Ps> {
        let a = self.arrivals[ticket.0 as usize];
        (a != PENDING).then_some(a)
    }

    /// When the read command of a read whose data arrives at `arrival` was issued.
    pub fn read_command_time(&self, arrival: Ps) -> Ps {
        arrival - self.t.dqsck - self.t.bl - self.t.cl
    }

    /// Writes posted to channel `c` and not yet drained.
    pub fn posted_writes(&self, c: usize) -> usize {
        self.channels[c].wq.len()
    }

    /// Drains the posted writes of channel `c` at `t` (after its queued reads).
    pub fn drain_channel(&mut self, t: Ps, c: usize) {
        self.drain(t, c);
    }

    /// Starts recording the command time of every drained write ([`Dram::take_write_log`]).
    pub fn log_writes(&mut self) {
        self.write_log.get_or_insert_with(Vec::new);
    }

    /// The `(channel, command time)` of the writes drained since the last call.
    pub fn take_write_log(&mut self) -> Vec<(u32, Ps)> {
        self.write_log.as_mut().map(std::mem::take).unwrap_or_default()
    }

    /// Serves every queued read of channel `c`.
    fn schedule_all(&mut self, c: usize) {
        while !self.channels[c].rq.is_empty() {
            self.schedule_one(c);
        }
    }

    /// The earliest activate of queued read `q` on channel `c` as far as its bank allows
    /// (precharge of another open row, `tRP`, `tRC`).
    fn act_ready(&self, c: usize, q: &QueuedRead) -> Ps {
        let tm = self.t;
        let bank = &self.channels[c].banks[q.bank as usize];
        let mut act = q.issue;
        if bank.open != CLOSED {
            let pre = act.max(bank.act + tm.ras).max(bank.rd_col + tm.rtp).max(bank.wr_end + tm.wr);
            act = pre + tm.rp;
        }
        if bank.activated {
            act = act.max(bank.act + tm.rc);
        }
        act
    }

    /// FR-FCFS: times one queued read of channel `c` (which must have one).
    fn schedule_one(&mut self, c: usize) {
        let ch = &self.channels[c];
        let oldest = ch.rq[0];
        let decision = oldest.issue.max(ch.last_col);
        let mut pick = 0;
        if oldest.bypassed < self.bypass_cap && ch.banks[oldest.bank as usize].open != oldest.row {
            let (front, back) = ch.rq.as_slices();
            let limit = self.read_queue.min(ch.rq.len());
            for i in 1..limit {
                let q = if i < front.len() { &front[i] } else { &back[i - front.len()] };
                if q.issue > decision {
                    break;
                }
                if ch.banks[q.bank as usize].open == q.row {
                    pick = i;
                    break;
                }
            }
            if pick == 0 {
                // No row hit: the read whose bank can activate first (first ready, as a
                // cycle-level FR-FCFS issues whichever request's command is ready), the oldest
                // among equals.
                let mut best = self.act_ready(c, &oldest);
                for i in 1..limit {
                    let q = if i < front.len() { &front[i] } else { &back[i - front.len()] };
                    if q.issue > decision {
                        break;
                    }
                    let r = self.act_ready(c, q);
                    if r < best {
                        best = r;
                        pick = i;
                    }
                }
            }
        }
        let ch = &mut self.channels[c];
        let q = ch.rq.remove(pick).expect("a queued read");
        if pick > 0 {
            ch.rq[0].bypassed += 1;
            self.stats.reordered += 1;
        }
        let horizon = ch.rq.front().map_or(q.issue, |o| o.issue.min(q.issue));
        let end = self.access(q.issue, horizon, c, q.bank as usize, q.row, false);
        let ch = &mut self.channels[c];
        ch.last_col = ch.last_col.max(end - self.t.bl - self.t.cl);
        let done = end + self.t.dqsck;
        self.stats.read_latency_ps += done - q.issue;
        self.arrivals[q.ticket as usize] = done;
    }

    /// Posts a write of the line holding `addr` at `t` (returns at once; drained later).
    pub fn write(&mut self, t: Ps, addr: u64) {
        self.stats.writes += 1;
        if self.ideal.is_some() {
            return;
        }
        let (c, b, r) = self.map(addr);
        let ch = &mut self.channels[c];
        ch.wq.push((b as u32, r));
        // Write mode: the queue is full, or no read is waiting (Ramulator's controller).
        if ch.wq.len() * 5 > self.write_queue * 4 || ch.rq.is_empty() {
            self.drain(t, c);
        }
    }

    /// Serves every queued read and drains every write queue at `t`; returns when the last data
    /// has left (at least `t`).
    pub fn flush(&mut self, t: Ps) -> Ps {
        for c in 0..self.channels.len() {
            self.schedule_all(c);
            self.drain(t, c);
        }
        self.channels.iter().map(|c| c.bus_free).max().unwrap_or(0).max(t)
    }

    fn drain(&mut self, t: Ps, c: usize) {
        // Write mode starts at `t`: the queued reads whose commands come before it are served,
        // the others wait for the drain (a controller in write mode serves no reads).
        while !self.channels[c].rq.is_empty() && self.channels[c].last_col < t {
            self.schedule_one(c);
        }
        let mut q = std::mem::take(&mut self.channels[c].wq);
        if q.is_empty() {
            self.channels[c].wq = q;
            return;
        }
        self.stats.drains += 1;
        // First ready: repeatedly the write whose bank can take it first (row hits at once),
        // so the activates of different banks interleave as a cycle-level scheduler issues them.
        let mut order = Vec::with_capacity(q.len());
        {
            let tm = self.t;
            let banks = &self.channels[c].banks;
            let mut state: Vec<(u32, Ps, bool)> =
                banks.iter().map(|b| (b.open, b.act, b.activated)).collect();
            let mut left = q.clone();
            while !left.is_empty() {
                let ready = |&(b, r): &(u32, u32), st: &[(u32, Ps, bool)]| -> Ps {
                    let (open, act, activated) = st[b as usize];
                    if open == r {
                        return 0;
                    }
                    let mut a = t;
                    if open != CLOSED {
                        a = a.max(act + tm.ras) + tm.rp;
                    }
                    if activated {
                        a = a.max(act + tm.rc);
                    }
                    a
                };
                let (i, at) = left
                    .iter()
                    .enumerate()
                    .map(|(i, w)| (i, ready(w, &state)))
                    .min_by_key(|&(i, a)| (a, i))
                    .expect("a write left");
                let (b, r) = left.remove(i);
                if state[b as usize].0 != r {
                    state[b as usize] = (r, at.max(t), true);
                }
                order.push((b, r));
            }
        }
        q.clear();
        q.extend(order);
        // Writes go after the reads already scheduled, with the read-to-write turnaround after
        // the last read burst; banks work in parallel (the data bus orders the bursts).
        let tm = self.t;
        {
            let ch = &mut self.channels[c];
            ch.write_floor = ch.write_floor.max(t.max(ch.read_end + tm.rtrs));
        }
        let mut end = 0;
        for &(b, r) in &q {
            let e = self.access(t, t, c, b as usize, r, true);
            end = end.max(e);
            if let Some(log) = self.write_log.as_mut() {
                log.push((c as u32, e - tm.bl - tm.cwl));
            }
        }
        // Reads wait for the write-to-read turnaround.
        let ch = &mut self.channels[c];
        ch.floor = ch.floor.max(end + tm.wtr + tm.cl);
        q.clear();
        self.channels[c].wq = q;
    }

    /// Performs the refreshes due by the channel's frontier (the later of `t` and its data
    /// bus): a refresh waits for the data already scheduled (LPDDR4 lets a controller postpone
    /// refreshes), then blocks the channel for `tRFCab` and closes every row.
    fn refresh_until(&mut self, c: usize, t: Ps) {
        let tm = self.t;
        let ch = &mut self.channels[c];
        while ch.next_ref <= t.max(ch.bus_free) {
            let start = ch.next_ref.max(ch.bus_free).max(ch.blocked_until);
            ch.blocked_until = start + tm.rfc;
            ch.floor = ch.floor.max(ch.blocked_until);
            for b in ch.banks.iter_mut() {
                b.open = CLOSED;
            }
            ch.next_ref += tm.refi;
            self.stats.refreshes += 1;
        }
    }

    /// One request on channel `c` issued at `t`; returns the end of its data on the bus.
    /// `horizon` (at most `t`) is the earliest issue time any later request of the channel can
    /// have: bus bursts and activates that end before it are pruned.
    fn access(&mut self, t: Ps, horizon: Ps, c: usize, b: usize, row: u32, write: bool) -> Ps {
        self.refresh_until(c, t);
        let tm = self.t;
        let ch = &mut self.channels[c];
        let t = t.max(ch.blocked_until);
        let bank = &mut ch.banks[b];
        let col_ready = if bank.open == row {
            self.stats.row_hits += 1;
            t.max(bank.act + tm.rcd)
        } else {
            let mut act = t;
            if bank.open != CLOSED {
                self.stats.row_conflicts += 1;
                let pre = t.max(bank.act + tm.ras).max(bank.rd_col + tm.rtp).max(bank.wr_end + tm.wr);
                act = act.max(pre + tm.rp);
            } else {
                self.stats.row_misses += 1;
            }
            if bank.activated {
                act = act.max(bank.act + tm.rc);
            }
            act = act_slot(&mut ch.acts, act, horizon, tm.rrd, tm.faw);
            bank.activated = true;
            bank.open = row;
            bank.act = act;
            act + tm.rcd
        };
        let lat = if write { tm.cwl } else { tm.cl };
        let ready = (col_ready + lat).max(if write { ch.write_floor } else { ch.floor });
        // Earliest free burst slot at or after `ready`. Busy blocks are merged when the gap
        // between them is shorter than a burst, so a saturated bus is one block.
        while ch.busy.front().is_some_and(|&(_, e)| e <= horizon) {
            ch.busy.pop_front();
        }
        let (i, start) = bus_slot(&ch.busy, ready, tm.bl);
        let end = start + tm.bl;
        // Insert [start, end) before block i, merging with neighbours closer than a burst (such
        // a gap can never hold a burst, so the merge loses nothing and keeps the calendar short).
        let touches_prev = i > 0 && start - ch.busy[i - 1].1 < tm.bl;
        let touches_next = i < ch.busy.len() && ch.busy[i].0 - end < tm.bl;
        match (touches_prev, touches_next) {
            (true, true) => {
                let next_end = ch.busy[i].1;
                ch.busy[i - 1].1 = next_end;
                ch.busy.remove(i);
            }
            (true, false) => ch.busy[i - 1].1 = end,
            (false, true) => ch.busy[i].0 = start,
            (false, false) => ch.busy.insert(i, (start, end)),
        }
        ch.bus_free = ch.bus_free.max(end);
        let col = start - lat;
        if write {
            bank.wr_end = bank.wr_end.max(end);
        } else {
            bank.rd_col = bank.rd_col.max(col);
            ch.read_end = ch.read_end.max(end);
        }
        self.stats.last_data_ps = self.stats.last_data_ps.max(end);
        end
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn gbs(bytes: u64, ps: Ps) -> f64 {
        bytes as f64 / (ps as f64 * 1e-12) / 1e9
    }

    /// Streams `n` reads with at most `window` outstanding; returns the achieved GB/s.
    fn run(d: &mut Dram, addrs: impl Iterator<Item = u64>, window: usize) -> f64 {
        let mut inflight = std::collections::VecDeque::new();
        let mut t = 0;
        let mut n = 0u64;
        let mut last = 0;
        for a in addrs {
            if inflight.len() == window {
                t = t.max(inflight.pop_front().unwrap());
            }
            let done = d.read(t, a);
            last = last.max(done);
            inflight.push_back(done);
            n += 1;
        }
        gbs(n * 64, last)
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
        // One stream is already in row order: reordering changes nothing.
        let (a, ha, _) = interleaved(&fr, 1, 20_000, 64);
        let (b, hb, _) = interleaved(&in_order, 1, 20_000, 64);
        assert!((a - b).abs() < 1e-9 && (ha - hb).abs() < 1e-12, "{a} {b}");
    }

    #[test]
    fn the_oldest_read_is_bypassed_at_most_bypass_cap_times() {
        let cfg = DramConfig::default();
        let mut d = Dram::new(&cfg);
        // Open row 0 of channel 0, bank 0.
        let t0 = d.read(0, 0);
        let (c, b, r) = d.map(0);
        // Row 1 of the same bank (the bank index is XORed with the row's low bits).
        let conflict = (0..64u64)
            .map(|k| k * 128 * 1024 + (1 << 14) * (k % 8))
            .find(|&a| {
                let (c2, b2, r2) = d.map(a);
                c2 == c && b2 == b && r2 != r
            })
            .expect("another row of bank 0");
        let old = d.submit_read(t0, conflict);
        // 60 more lines of the open row (channel 0 holds every 4th line; a row has 64 of them).
        let hits: Vec<Ticket> = (1..61u64).map(|k| d.submit_read(t0, k * 4 * 64)).collect();
        let t_old = d.arrival(old);
        let before = hits.iter().filter(|&&h| d.arrival(h) < t_old).count();
        assert_eq!(before as u32, cfg.bypass_cap, "hits served before the old conflict");
        assert_eq!(d.stats().reordered, cfg.bypass_cap as u64);
    }

    /// The straightforward `act_slot`: a fresh binary search after every move of `x`.
    fn act_slot_reference(
        acts: &mut std::collections::VecDeque<Ps>,
        mut x: Ps,
        t: Ps,
        rrd: Ps,
        faw: Ps,
    ) -> Ps {
        while acts.front().is_some_and(|&a| a + faw.max(rrd) <= t) {
            acts.pop_front();
        }
        'search: loop {
            let pos = acts.partition_point(|&a| a <= x);
            if pos > 0 && acts[pos - 1] + rrd > x {
                x = acts[pos - 1] + rrd;
                continue;
            }
            if pos < acts.len() && x + rrd > acts[pos] {
                x = acts[pos] + rrd;
                continue;
            }
            for k in 0..5usize {
                if pos + k < 4 || pos + k > acts.len() {
                    continue;
                }
                let first = if k < 4 { acts[pos + k - 4] } else { x };
                let last = if k > 0 { acts[pos + k - 1] } else { x };
                if last - first < faw {
                    x = if k == 0 { first + faw } else { acts[pos] + rrd };
                    continue 'search;
                }
            }
            acts.insert(pos, x);
            return x;
        }
    }

    #[test]
    fn act_slot_places_activates_as_the_reference_search_does() {
        let mut x = 0x2545_F491_4F6C_DD1Du64;
        let mut rnd = move |m: u64| {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            x % m
        };
        let (rrd, faw) = (7_500, 40_000);
        for _ in 0..50 {
            let (mut fast, mut slow) = (std::collections::VecDeque::new(), std::collections::VecDeque::new());
            let mut t = 0;
            for _ in 0..2_000 {
                t += rnd(20_000);
                // Requests wanting an activate at, or well after, their issue (some on a coarse
                // grid, so that many want the same time and the search jumps over several).
                let want = t + match rnd(3) {
                    0 => 0,
                    1 => rnd(400_000),
                    _ => rnd(8) * 50_000,
                };
                let a = act_slot(&mut fast, want, t, rrd, faw);
                let b = act_slot_reference(&mut slow, want, t, rrd, faw);
                assert_eq!(a, b, "activate slot");
                assert_eq!(fast, slow, "activate calendar");
            }
        }
    }

    #[test]
    fn bus_slot_is_the_first_gap_that_holds_a_burst() {
        let mut x = 0x9E37_79B9_7F4A_7C15u64;
        let mut rnd = move |m: u64| {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            x % m
        };
        let bl = 5_000;
        for _ in 0..2_000 {
            // A calendar of random blocks with random gaps.
            let mut busy = std::collections::VecDeque::new();
            let mut t = rnd(20_000);
            for _ in 0..rnd(12) {
                let s = t + rnd(12_000);
                let e = s + 1 + rnd(30_000);
                busy.push_back((s, e));
                t = e;
            }
            let ready = rnd(t + 20_000);
            let (i, start) = bus_slot(&busy, ready, bl);
            // Straightforward: the first start at or after `ready` clear of every block.
            let clear = |x: Ps| busy.iter().all(|&(s, e)| x + bl <= s || x >= e);
            let want = std::iter::once(ready)
                .chain(busy.iter().map(|&(_, e)| e).filter(|&e| e >= ready))
                .filter(|&x| clear(x))
                .min()
                .unwrap();
            assert_eq!(start, want, "calendar {busy:?}, ready {ready}");
            assert_eq!(i, busy.iter().filter(|&&(_, e)| e <= start).count(), "index after {busy:?}");
        }
    }

    #[test]
    fn ideal_memory_answers_after_a_fixed_latency() {
        let mut d = Dram::ideal(64, 1000);
        assert_eq!(d.read(5, 0), 1005);
        d.write(7, 64);
        assert_eq!(d.stats().reads + d.stats().writes, 2);
    }

    #[test]
    fn writes_are_posted_and_drained() {
        let mut d = Dram::new(&DramConfig::default());
        // No read waits: every write drains at once (write mode).
        for i in 0..8u64 {
            d.write(i, i * 64);
        }
        assert_eq!(d.stats().drains, 8);
        let mut d = Dram::new(&DramConfig::default());
        // A read waits in every channel: writes are posted until more than 80% of 32 wait.
        let waiting: Vec<Ticket> = (0..4u64).map(|c| d.submit_read(0, (1 << 20) + c * 64)).collect();
        for i in 0..100u64 {
            d.write(i, i * 64);
        }
        assert_eq!(d.stats().drains, 0, "25 writes per channel are posted");
        for i in 100..104u64 {
            d.write(i, i * 64);
        }
        assert_eq!(d.stats().drains, 4, "the 26th (above 80% of 32) drains, after the waiting read");
        for k in waiting {
            assert!(d.scheduled(k).is_some());
            d.release(k);
        }
        for i in 104..400u64 {
            d.write(i, i * 64);
        }
        let end = d.flush(1000);
        assert!(end > 100 * 5000, "100 bursts of 5 ns per channel: {end}");
        assert_eq!(d.stats().writes, 400);
        // A read after the drain waits for the write-to-read turnaround.
        let r = d.read(1000, 0);
        assert!(r >= end, "read {r} before the drain ended {end}");
    }
}
