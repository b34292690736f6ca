//! The event-driven core: agents (engine units) run jobs made of segments; every segment reads
//! and writes DRAM lines through [`Dram`]; a [`Scheduler`] decides which job an idle agent runs
//! next and learns when jobs finish.
//!
//! # Segment timing
//! A segment has an ideal duration `T` (what it takes with the cosimulation's ideal memory), an
//! ideal load phase `L <= T`, read accesses and write accesses. Its reads are issued one 64-byte
//! line at a time from its read start `rs`, at most one per `interval`, with at most `window`
//! reads outstanding; the DRAM returns each line's arrival time. Then, with `last` the latest
//! arrival and `prev` the end of the agent's previous segment:
//! - a **serial** segment (a sorting-core chunk command: load, then passes) ends at
//!   `max(prev, max(rs + L, last)) + (T - L)`;
//! - a **streaming** segment (a merge, a raster tile, preprocessing) computes while it reads:
//!   it ends at `max(max(prev, rs) + T, last + (T - L))`.
//!
//! With an ideal memory both reduce to `rs + T` when `rs = prev`: the measured cycles. The next
//! segment's reads start at `prev` of this one (no overlap) or, with double buffering, as soon
//! as this segment's reads are issued and the segment before it has ended (two buffers).
//! Writes are posted: a segment's writes enter the DRAM at its end (`writes_at_end`) or in
//! proportion to its reads as they are issued.

use std::cmp::Reverse;
use std::collections::{BinaryHeap, VecDeque};

use neo_golden::profile::{self, Phase};

use crate::dram::{Dram, Ps, Ticket};
use crate::traffic::{Dir, Stage, Traffic};

/// How an access walks memory.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AccessKind {
    /// `bytes` consecutive bytes from the base.
    Seq {
        /// Bytes.
        bytes: u64,
    },
    /// `count` records of `record_bytes` at pseudo-random record indices in
    /// `0..records_in_region` from the base (a gather: feature-table reads by Gaussian id).
    Gather {
        /// Records read.
        count: u64,
        /// Bytes per record.
        record_bytes: u32,
        /// Records in the region.
        records_in_region: u64,
        /// Seed of the index sequence.
        seed: u64,
    },
    /// `count` transfers of `record_bytes` at `base + stride k`, each moving every line it
    /// touches (two transfers that share a line each move it: no combining).
    Records {
        /// Transfers.
        count: u64,
        /// Bytes per transfer.
        record_bytes: u64,
        /// Bytes from one transfer's start to the next's.
        stride: u64,
    },
}

/// One access of a segment.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Access {
    /// Stage the traffic is charged to.
    pub stage: Stage,
    /// First byte.
    pub base: u64,
    /// Pattern.
    pub kind: AccessKind,
}

impl Access {
    /// A sequential access.
    pub fn seq(stage: Stage, base: u64, bytes: u64) -> Self {
        Access { stage, base, kind: AccessKind::Seq { bytes } }
    }

    /// Lines this access touches (exact for `Seq`, expected for `Gather`).
    pub fn lines_estimate(&self, line: u64) -> f64 {
        match self.kind {
            AccessKind::Seq { bytes } => seq_lines(self.base, bytes, line) as f64,
            AccessKind::Gather { count, record_bytes, .. } => {
                let rb = record_bytes as u64;
                // A record covers ceil(rb / line) lines, plus one when it straddles a boundary.
                let whole = rb.div_ceil(line);
                let extra = ((rb - 1) % line) as f64 / line as f64;
                count as f64 * (whole as f64 + extra.min(1.0))
            }
            AccessKind::Records { count, record_bytes, stride } => {
                records_lines(self.base, count, record_bytes, stride, line) as f64
            }
        }
    }

    /// A run of transfers ([`AccessKind::Records`]).
    pub fn records(stage: Stage, base: u64, count: u64, record_bytes: u64, stride: u64) -> Self {
        Access { stage, base, kind: AccessKind::Records { count, record_bytes, stride } }
    }
}

/// Lines `count` transfers of `bytes` at `base + stride k` touch, each counted by itself: the
/// pattern of line offsets repeats every `line / gcd(stride, line)` transfers.
fn records_lines(base: u64, count: u64, bytes: u64, stride: u64, line: u64) -> u64 {
    let step = stride % line;
    let period = if step == 0 { 1 } else { line / gcd(step, line) };
    let lines = |k: u64| seq_lines(base + stride * k, bytes, line);
    let per_period: u64 = (0..period.min(count)).map(lines).sum();
    let rest: u64 = (0..count % period).map(lines).sum();
    count / period * per_period + rest
}

fn gcd(a: u64, b: u64) -> u64 {
    if b == 0 {
        a
    } else {
        gcd(b, a % b)
    }
}

fn seq_lines(base: u64, bytes: u64, line: u64) -> u64 {
    if bytes == 0 {
        0
    } else {
        line_of(base + bytes - 1, line) - line_of(base, line) + 1
    }
}

/// `addr / line`, a shift for the power-of-two line sizes the DRAM configuration requires.
#[inline]
fn line_of(addr: u64, line: u64) -> u64 {
    if line.is_power_of_two() {
        addr >> line.trailing_zeros()
    } else {
        addr / line
    }
}

/// A 64-bit mix (splitmix64 finaliser).
pub fn mix(mut x: u64) -> u64 {
    x = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
    x = (x ^ (x >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    x = (x ^ (x >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    x ^ (x >> 31)
}

/// Walks the lines of a list of accesses.
#[derive(Clone, Debug, Default)]
struct Cursor {
    idx: usize,
    pos: u64,
    pending: Option<u64>,
    rec_end_line: u64,
}

impl Cursor {
    fn next(&mut self, acc: &[Access], line: u64) -> Option<(u64, Stage)> {
        loop {
            let a = acc.get(self.idx)?;
            if let Some(l) = self.pending {
                if l <= self.rec_end_line {
                    self.pending = Some(l + 1);
                    return Some((l * line, a.stage));
                }
                self.pending = None;
                self.pos += 1;
            }
            match a.kind {
                AccessKind::Seq { bytes } => {
                    let n = seq_lines(a.base, bytes, line);
                    if self.pos < n {
                        let l = line_of(a.base, line) + self.pos;
                        self.pos += 1;
                        return Some((l * line, a.stage));
                    }
                }
                AccessKind::Gather { count, record_bytes, records_in_region, seed } => {
                    if self.pos < count {
                        let r = mix(seed ^ self.pos) % records_in_region.max(1);
                        let start = a.base + r * record_bytes as u64;
                        let first = line_of(start, line);
                        self.rec_end_line = line_of(start + record_bytes.max(1) as u64 - 1, line);
                        self.pending = Some(first + 1);
                        return Some((first * line, a.stage));
                    }
                }
                AccessKind::Records { count, record_bytes, stride } => {
                    if self.pos < count && record_bytes > 0 {
                        let start = a.base + stride * self.pos;
                        let first = line_of(start, line);
                        self.rec_end_line = line_of(start + record_bytes - 1, line);
                        self.pending = Some(first + 1);
                        return Some((first * line, a.stage));
                    }
                }
            }
            self.idx += 1;
            self.pos = 0;
        }
    }
}

/// One unit of work on an agent.
#[derive(Clone, Debug, PartialEq)]
pub struct Segment {
    /// Ideal duration (ps).
    pub compute: Ps,
    /// Ideal load phase (ps), at most `compute`.
    pub load: Ps,
    /// Serial (load then compute) or streaming.
    pub serial: bool,
    /// Reads.
    pub reads: Vec<Access>,
    /// Writes.
    pub writes: Vec<Access>,
    /// Writes enter the DRAM at the segment's end (else in proportion to the reads).
    pub writes_at_end: bool,
    /// Minimum spacing of read issues (ps), the agent's port rate.
    pub min_interval: Ps,
    /// Spread the reads evenly over the segment (streaming units that consume as they compute).
    pub spread_reads: bool,
}

/// What a job is, for the scheduler.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct JobTag {
    /// Frame.
    pub frame: u32,
    /// Tile (or 0).
    pub tile: u32,
    /// Kind (scheduler-defined).
    pub kind: u8,
}

/// A job: segments run in order on one agent.
#[derive(Clone, Debug, PartialEq)]
pub struct Job {
    /// Identity.
    pub tag: JobTag,
    /// Segments.
    pub segments: Vec<Segment>,
}

/// An agent's fixed parameters.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct AgentSpec {
    /// Agent class (scheduler-defined).
    pub class: u8,
    /// Outstanding read lines.
    pub window: u32,
    /// Double-buffered: the next segment's reads may overlap this one's compute.
    pub overlap: bool,
}

/// Decides what runs.
pub trait Scheduler {
    /// A job for idle agent `agent` of class `class` at `t`, if one is ready.
    fn next_job(&mut self, agent: usize, class: u8, t: Ps) -> Option<Job>;
    /// `tag` finished at `t`.
    fn job_done(&mut self, tag: JobTag, t: Ps);
    /// True when every job has run.
    fn finished(&self) -> bool;
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
enum Ev {
    Issue(usize),
    Writes(usize),
    Done(usize),
}

/// An event in the heap, ordered by time, then by the order it was posted in: the time in the
/// high 64 bits, then the post's sequence number (40 bits), the event's kind (2 bits) and its
/// agent or write batch (22 bits). One `u128` compares in two instructions and moves in 16
/// bytes, where `(time, sequence, Ev)` took 32.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
struct EvKey(u128);

impl EvKey {
    const INDEX_BITS: u32 = 22;
    const SEQ_BITS: u32 = 40;

    fn new(t: Ps, seq: u64, ev: Ev) -> Self {
        let (kind, index) = match ev {
            Ev::Issue(a) => (0, a),
            Ev::Writes(w) => (1, w),
            Ev::Done(a) => (2, a),
        };
        assert!(
            index < 1 << Self::INDEX_BITS && seq < 1 << Self::SEQ_BITS,
            "event key out of range: index {index}, sequence {seq}"
        );
        let low = seq << (Self::INDEX_BITS + 2) | (kind as u64) << Self::INDEX_BITS | index as u64;
        EvKey((t as u128) << 64 | low as u128)
    }

    fn time(self) -> Ps {
        (self.0 >> 64) as Ps
    }

    fn parts(self) -> (Ps, Ev) {
        let index = (self.0 as u64 & ((1 << Self::INDEX_BITS) - 1)) as usize;
        let ev = match (self.0 as u64 >> Self::INDEX_BITS) & 3 {
            0 => Ev::Issue(index),
            1 => Ev::Writes(index),
            _ => Ev::Done(index),
        };
        (self.time(), ev)
    }
}

#[derive(Debug, Default)]
struct AgentState {
    job: Option<Job>,
    seg: usize,
    cursor: Cursor,
    rs: Ps,
    interval: Ps,
    inflight: VecDeque<Ticket>,
    last_arrival: Ps,
    reads_done: u64,
    reads_est: f64,
    wcursor: Cursor,
    writes_done: u64,
    writes_est: f64,
    prev_end: Ps,
    prev2_end: Ps,
    next_rs: Ps,
    busy_ps: Ps,
    job_start: Ps,
}

struct PendingWrites {
    frame: u32,
    accesses: Vec<Access>,
    cursor: Cursor,
}

/// Counters of one agent.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct AgentStats {
    /// Class.
    pub class: u8,
    /// Time spent running jobs (ps).
    pub busy_ps: Ps,
    /// Jobs run.
    pub jobs: u64,
}

/// The simulation.
pub struct Engine {
    dram: Dram,
    line: u64,
    specs: Vec<AgentSpec>,
    agents: Vec<AgentState>,
    heap: BinaryHeap<Reverse<EvKey>>,
    seq: u64,
    writes: Vec<Option<PendingWrites>>,
    free_writes: Vec<usize>,
    /// Traffic of the whole run.
    pub traffic: Traffic,
    /// Traffic per frame (by the frame of the job that caused it).
    pub frame_traffic: Vec<Traffic>,
    /// Busy time per frame (by the frame of the job) and agent class, summed over the agents
    /// of the class.
    pub frame_busy: Vec<Vec<Ps>>,
    jobs: Vec<u64>,
    now: Ps,
    /// The write lines posted with one read ([`Engine::issue`]), kept to reuse its allocation.
    wlines: Vec<(u64, Stage)>,
}

impl Engine {
    /// An engine over `dram` with `line_bytes` requests and the given agents.
    pub fn new(dram: Dram, line_bytes: u64, agents: Vec<AgentSpec>, frames: usize) -> Self {
        let n = agents.len();
        Engine {
            dram,
            line: line_bytes,
            agents: (0..n).map(|_| AgentState::default()).collect(),
            specs: agents,
            heap: BinaryHeap::new(),
            seq: 0,
            writes: Vec::new(),
            free_writes: Vec::new(),
            traffic: Traffic::new(line_bytes),
            frame_traffic: vec![Traffic::new(line_bytes); frames],
            frame_busy: vec![Vec::new(); frames],
            jobs: vec![0; n],
            now: 0,
            wlines: Vec::new(),
        }
    }

    /// The DRAM (for its statistics).
    pub fn dram(&self) -> &Dram {
        &self.dram
    }

    /// Per-agent counters.
    pub fn agent_stats(&self) -> Vec<AgentStats> {
        self.specs
            .iter()
            .zip(&self.agents)
            .zip(&self.jobs)
            .map(|((s, a), &j)| AgentStats { class: s.class, busy_ps: a.busy_ps, jobs: j })
            .collect()
    }

    fn push(&mut self, t: Ps, ev: Ev) {
        self.seq += 1;
        self.heap.push(Reverse(EvKey::new(t, self.seq, ev)));
    }

    fn count(&mut self, frame: u32, stage: Stage, dir: Dir) {
        self.traffic.add(stage, dir, 1);
        if let Some(f) = self.frame_traffic.get_mut(frame as usize) {
            f.add(stage, dir, 1);
        }
    }

    /// Runs until the scheduler has nothing left; returns the time the last job ended and the
    /// DRAM drained its writes.
    pub fn run(&mut self, sched: &mut dyn Scheduler) -> Ps {
        let _phase = profile::enter(Phase::Engine);
        self.dispatch(sched, 0);
        while let Some(Reverse(key)) = self.heap.pop() {
            let (t, ev) = key.parts();
            self.now = t;
            match ev {
                Ev::Issue(a) => self.issue(a, t),
                Ev::Writes(w) => self.do_writes(w, t),
                Ev::Done(a) => {
                    let job = self.agents[a].job.take().expect("a job");
                    let st = &mut self.agents[a];
                    st.busy_ps += t - st.job_start;
                    let busy = t - st.job_start;
                    self.jobs[a] += 1;
                    let class = self.specs[a].class as usize;
                    if let Some(f) = self.frame_busy.get_mut(job.tag.frame as usize) {
                        if f.len() <= class {
                            f.resize(class + 1, 0);
                        }
                        f[class] += busy;
                    }
                    sched.job_done(job.tag, t);
                    self.dispatch(sched, t);
                }
            }
        }
        debug_assert!(sched.finished(), "scheduler still has jobs but no agent can take them");
        self.dram.flush(self.now).max(self.now)
    }

    fn dispatch(&mut self, sched: &mut dyn Scheduler, t: Ps) {
        for a in 0..self.agents.len() {
            if self.agents[a].job.is_none() {
                if let Some(job) = sched.next_job(a, self.specs[a].class, t) {
                    self.start_job(a, job, t);
                }
            }
        }
    }

    fn start_job(&mut self, a: usize, job: Job, t: Ps) {
        let st = &mut self.agents[a];
        st.job = Some(job);
        st.seg = 0;
        st.prev_end = t;
        st.prev2_end = t;
        st.job_start = t;
        self.start_segment(a, t);
    }

    /// Starts the reads of the agent's current segment at `rs` (completing read-less segments
    /// at once).
    fn start_segment(&mut self, a: usize, mut rs: Ps) {
        let line = self.line;
        loop {
            let st = &mut self.agents[a];
            let seg = &st.job.as_ref().expect("a job").segments[st.seg];
            let est: f64 = seg.reads.iter().map(|r| r.lines_estimate(line)).sum();
            st.rs = rs;
            st.cursor = Cursor::default();
            st.wcursor = Cursor::default();
            debug_assert!(st.inflight.is_empty(), "the previous segment resolved its reads");
            st.last_arrival = rs;
            st.reads_done = 0;
            st.reads_est = est;
            st.writes_done = 0;
            st.writes_est = seg.writes.iter().map(|w| w.lines_estimate(line)).sum();
            st.interval = if seg.spread_reads && est >= 1.0 {
                ((seg.compute as f64 / est) as Ps).max(seg.min_interval)
            } else {
                seg.min_interval
            };
            if est > 0.0 {
                self.push(rs, Ev::Issue(a));
                return;
            }
            if !self.finish_segment(a, rs) {
                return;
            }
            rs = self.agents[a].next_rs;
        }
    }

    /// Issues the agent's reads from `t` on, as long as its window and pacing allow and no
    /// other event comes first. A read's data time is asked of the DRAM only as of the current
    /// time ([`Dram::poll`]): while it is not known, the agent waits for the earliest time it can
    /// be, so no channel is simulated ahead of requests other agents have yet to issue.
    fn issue(&mut self, a: usize, mut t: Ps) {
        let line = self.line;
        let window = self.specs[a].window.max(1) as usize;
        loop {
            // A full window waits for its oldest read's data.
            if self.agents[a].inflight.len() >= window {
                let old = *self.agents[a].inflight.front().expect("window > 0");
                match self.dram.poll(old, t) {
                    Ok(arrival) if arrival <= t => {
                        let st = &mut self.agents[a];
                        st.inflight.pop_front();
                        st.last_arrival = st.last_arrival.max(arrival);
                        self.dram.release(old);
                        continue;
                    }
                    Ok(later) | Err(later) => {
                        self.push(later, Ev::Issue(a));
                        return;
                    }
                }
            }
            let st = &mut self.agents[a];
            let job = st.job.as_ref().expect("a job");
            let frame = job.tag.frame;
            let seg = &job.segments[st.seg];
            let Some((addr, stage)) = st.cursor.next(&seg.reads, line) else {
                // The segment ends when every read's data time is known.
                let mut wait = None;
                for i in 0..self.agents[a].inflight.len() {
                    if let Err(later) = self.dram.poll(self.agents[a].inflight[i], t) {
                        wait = Some(wait.map_or(later, |w: Ps| w.min(later)));
                    }
                }
                if let Some(w) = wait {
                    self.push(w, Ev::Issue(a));
                    return;
                }
                if self.finish_segment(a, t) {
                    let rs = self.agents[a].next_rs;
                    self.start_segment(a, rs);
                }
                return;
            };
            // Writes in proportion to the reads.
            self.wlines.clear();
            st.reads_done += 1;
            if !seg.writes_at_end && st.writes_est > 0.0 {
                // Non-negative, so the truncating cast is the floor (without a libm call).
                let due = (st.reads_done as f64 * st.writes_est / st.reads_est.max(1.0)) as u64;
                while st.writes_done < due {
                    match st.wcursor.next(&seg.writes, line) {
                        Some(w) => {
                            self.wlines.push(w);
                            st.writes_done += 1;
                        }
                        None => break,
                    }
                }
            }
            let ticket = self.dram.submit_read(t, addr);
            self.count(frame, stage, Dir::Read);
            for &(w, ws) in &self.wlines {
                self.dram.write(t, w);
                self.traffic.add(ws, Dir::Write, 1);
                if let Some(f) = self.frame_traffic.get_mut(frame as usize) {
                    f.add(ws, Dir::Write, 1);
                }
            }
            let st = &mut self.agents[a];
            st.inflight.push_back(ticket);
            let next = t + st.interval;
            let top = self.heap.peek().map_or(Ps::MAX, |r| r.0.time());
            if next < top {
                t = next;
                self.now = t;
                continue;
            }
            self.push(next, Ev::Issue(a));
            return;
        }
    }

    /// The agent's current segment has issued all its reads at `t`: computes its end, posts
    /// its remaining writes, and moves to the next segment (returning true, with its read start
    /// in `next_rs`) or schedules the job's end (false).
    fn finish_segment(&mut self, a: usize, t: Ps) -> bool {
        let line = self.line;
        while let Some(k) = self.agents[a].inflight.pop_front() {
            let arrival = self.dram.arrival(k);
            self.dram.release(k);
            let st = &mut self.agents[a];
            st.last_arrival = st.last_arrival.max(arrival);
        }
        let overlap = self.specs[a].overlap;
        let st = &mut self.agents[a];
        let job = st.job.as_ref().expect("a job");
        let frame = job.tag.frame;
        let nseg = job.segments.len();
        let seg = &job.segments[st.seg];
        let tail = seg.compute - seg.load.min(seg.compute);
        let end = if seg.serial {
            st.prev_end.max((st.rs + seg.load).max(st.last_arrival)) + tail
        } else {
            (st.prev_end.max(st.rs) + seg.compute).max(st.last_arrival + tail)
        };
        // Writes not yet posted.
        let pending = if seg.writes_at_end {
            (!seg.writes.is_empty()).then(|| (seg.writes.clone(), Cursor::default()))
        } else {
            let mut probe = st.wcursor.clone();
            probe.next(&seg.writes, line).is_some().then(|| (seg.writes.clone(), st.wcursor.clone()))
        };
        st.prev2_end = st.prev_end;
        st.prev_end = end;
        st.seg += 1;
        let more = st.seg < nseg;
        st.next_rs = if overlap { t.max(st.prev2_end) } else { end };
        if let Some((accesses, cursor)) = pending {
            let id = self.free_writes.pop().unwrap_or_else(|| {
                self.writes.push(None);
                self.writes.len() - 1
            });
            self.writes[id] = Some(PendingWrites { frame, accesses, cursor });
            self.push(end.max(t), Ev::Writes(id));
        }
        if !more {
            self.push(end.max(t), Ev::Done(a));
        }
        more
    }

    fn do_writes(&mut self, id: usize, t: Ps) {
        let mut p = self.writes[id].take().expect("pending writes");
        while let Some((addr, stage)) = p.cursor.next(&p.accesses, self.line) {
            self.dram.write(t, addr);
            self.count(p.frame, stage, Dir::Write);
        }
        self.free_writes.push(id);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn event(kind: u8, index: usize) -> Ev {
        match kind % 3 {
            0 => Ev::Issue(index),
            1 => Ev::Writes(index),
            _ => Ev::Done(index),
        }
    }

    proptest! {
        /// An event key gives back its time and event, and keys order as `(time, sequence)`.
        #[test]
        fn event_keys_keep_their_event_and_order_by_time_then_sequence(
            a in (any::<u64>(), 0u64..1 << 40, any::<u8>(), 0usize..1 << 22),
            b in (any::<u64>(), 0u64..1 << 40, any::<u8>(), 0usize..1 << 22),
            near in any::<bool>(),
        ) {
            // Half the cases share their time, so the sequence decides.
            let b = if near { (a.0, b.1, b.2, b.3) } else { b };
            let (ka, kb) = (EvKey::new(a.0, a.1, event(a.2, a.3)), EvKey::new(b.0, b.1, event(b.2, b.3)));
            prop_assert_eq!(ka.parts(), (a.0, event(a.2, a.3)));
            prop_assert_eq!(kb.parts(), (b.0, event(b.2, b.3)));
            if (a.0, a.1) != (b.0, b.1) {
                prop_assert_eq!(ka.cmp(&kb), (a.0, a.1).cmp(&(b.0, b.1)));
            }
        }
    }

    /// A run of transfers moves, transfer by transfer, the lines each touches: the count
    /// (period shortcut) and the cursor's walk agree with a transfer-by-transfer count.
    #[test]
    fn records_move_each_transfers_lines() {
        for (base, count, bytes, stride) in [
            (0, 10, 32, 32),
            (64, 7, 44, 44),
            (4096, 33, 192, 192),
            (8, 5, 12, 100),
            (0, 3, 4, 32),
            (128, 1, 300, 0),
        ] {
            let by_hand: u64 = (0..count).map(|k| seq_lines(base + stride * k, bytes, 64)).sum();
            let a = Access::records(Stage::Preprocess, base, count, bytes, stride);
            assert_eq!(a.lines_estimate(64), by_hand as f64, "{base} {count} {bytes} {stride}");
            let mut c = Cursor::default();
            let mut walked = Vec::new();
            while let Some((addr, _)) = c.next(&[a], 64) {
                walked.push(addr);
            }
            assert_eq!(walked.len() as u64, by_hand);
            assert_eq!(walked[0], base / 64 * 64);
        }
        // 32-byte words back to back: two per line, each moving the whole line.
        assert_eq!(Access::records(Stage::FeatureTable, 0, 4, 32, 32).lines_estimate(64), 4.0);
        assert_eq!(Access::seq(Stage::FeatureTable, 0, 128).lines_estimate(64), 2.0);
    }
}
