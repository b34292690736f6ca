//! [`AxiMemory`]: K AXI4 subordinate ports served from one golden [`Memory`], cycle by cycle.
//!
//! - AR and AW are accepted on random cycles (`ready_percent`); W only for an accepted AW (the
//!   beats of the AWs in order); the address channels' readies depend on the memory's state and
//!   its random draws only, never on the manager's signals of the same cycle.
//! - A read burst becomes eligible `latency` cycles after its AR (plus, for `extra_percent` of
//!   them, up to `extra_max` more); a write's B likewise after its last W beat.
//! - R beats of one burst go back to back (no interleaving); the next burst is the oldest eligible
//!   one, or with `reorder` a random one among the oldest eligible burst of each ID (never two of
//!   one ID out of order). B responses likewise.
//! - Read data is sampled from the memory when the beat is first driven (and held until
//!   RREADY); a write is applied to the memory when its B is first driven.
//! - `bandwidth = (n, d)`: at most `n / d` R beats and `n / d` W beats per cycle per port.
//!
//! Beats are 8 bytes; beat `k` of a burst at byte `a` covers `(a & !7) + 8 k ..+ 8` (an unaligned
//! start reads/writes the whole first beat; write strobes select the bytes).

use super::{Addr, BResp, ManagerSignals, RBeat, SubordinateSignals};
use crate::rng::Rng;
use neo_golden::engine::memory::Memory;
use std::collections::VecDeque;

/// Timing of an [`AxiMemory`] port.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct AxiTiming {
    /// Cycles from an accepted AR (or a write's last W beat) to its response at the earliest.
    pub latency: u32,
    /// Data beats per cycle per port and channel (R, W), `(numerator, denominator)`.
    pub bandwidth: (u32, u32),
    /// Percent of responses delayed further, by a uniform `1..=extra_max` cycles.
    pub extra_percent: u32,
    /// Longest extra delay.
    pub extra_max: u32,
    /// Responses of different IDs may overtake each other.
    pub reorder: bool,
    /// Percent of cycles AR, AW and W are ready.
    pub ready_percent: u32,
}

impl AxiTiming {
    /// The timing's means, for a cycle model: (cycles to the first response beat, with the
    /// mean random extra delay; data beats per cycle; fraction of cycles AR, AW and W are
    /// ready).
    pub fn means(&self) -> (f64, f64, f64) {
        let extra = self.extra_percent as f64 / 100.0 * (self.extra_max as f64 + 1.0) / 2.0;
        let bandwidth = self.bandwidth.0 as f64 / self.bandwidth.1.max(1) as f64;
        (self.latency as f64 + extra, bandwidth, (self.ready_percent as f64 / 100.0).min(1.0))
    }

    /// The late responses, for a cycle model: (the share of responses delayed further, the
    /// longest extra delay in cycles).
    pub fn late(&self) -> (f64, f64) {
        (self.extra_percent as f64 / 100.0, self.extra_max as f64)
    }

    /// One-cycle latency, full bandwidth, always ready, in order.
    pub const IDEAL: AxiTiming = AxiTiming {
        latency: 1,
        bandwidth: (1, 1),
        extra_percent: 0,
        extra_max: 0,
        reorder: false,
        ready_percent: 100,
    };
    /// A hostile memory: latency 6, 3/4 bandwidth, random extra delays up to 24 cycles, responses
    /// reordered across IDs, ready 60 % of the time.
    pub const RANDOM: AxiTiming = AxiTiming {
        latency: 6,
        bandwidth: (3, 4),
        extra_percent: 30,
        extra_max: 24,
        reorder: true,
        ready_percent: 60,
    };
}

/// Bytes of a beat.
const BEAT: u64 = 8;

/// A read burst accepted and not yet fully answered.
#[derive(Clone, Debug)]
struct ReadBurst {
    a: Addr,
    ready_at: u64,
    sent: u32,
}

/// A write whose data is complete, waiting for its B.
#[derive(Clone, Debug)]
struct Write {
    a: Addr,
    data: Vec<(u64, u8)>,
    ready_at: u64,
}

/// One port's state.
#[derive(Clone, Debug, Default)]
struct Port {
    out: SubordinateSignals,
    reads: Vec<ReadBurst>,
    /// Index into `reads` of the burst whose beats are being sent.
    r_cur: Option<usize>,
    aw: VecDeque<Addr>,
    w_data: Vec<(u64, u8)>,
    writes: Vec<Write>,
    credit_r: u32,
    credit_w: u32,
    now: u64,
    r_beats: u64,
    w_beats: u64,
}

/// One address handshake a port took (an AR or an AW): a line of a transfer log.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct AddrRecord {
    /// The port.
    pub port: usize,
    /// The port's cycle (counted from the memory's creation).
    pub cycle: u64,
    /// An AW (else an AR).
    pub write: bool,
    /// Byte address.
    pub addr: u64,
    /// The ID on the port (the port mux's client slot).
    pub id: u32,
    /// Data beats of the burst.
    pub beats: u32,
}

/// K AXI4 subordinate ports over one [`Memory`] (see the module docs).
#[derive(Clone, Debug)]
pub struct AxiMemory {
    mem: Memory,
    timing: AxiTiming,
    ports: Vec<Port>,
    rngs: Vec<Rng>,
    /// Every AR and AW taken, while recording ([`AxiMemory::record_addresses`]).
    log: Option<Vec<AddrRecord>>,
}

impl AxiMemory {
    /// `ports` ports over `mem`, random draws seeded from `seed`.
    pub fn new(ports: usize, mem: Memory, timing: AxiTiming, seed: u64) -> AxiMemory {
        let mut root = Rng::new(seed ^ 0xa11_0a11);
        let rngs = (0..ports).map(|k| root.fork(k as u64)).collect();
        AxiMemory { mem, timing, ports: vec![Port::default(); ports], rngs, log: None }
    }

    /// Starts (`true`) or stops recording every AR and AW taken ([`AddrRecord`]).
    pub fn record_addresses(&mut self, on: bool) {
        self.log = on.then(|| self.log.take().unwrap_or_default());
    }

    /// The records since the last call (empty when not recording).
    pub fn take_addresses(&mut self) -> Vec<AddrRecord> {
        self.log.as_mut().map(std::mem::take).unwrap_or_default()
    }

    fn record(&mut self, k: usize, write: bool, a: &Addr) {
        if let Some(log) = &mut self.log {
            let cycle = self.ports[k].now;
            log.push(AddrRecord { port: k, cycle, write, addr: a.addr, id: a.id, beats: a.beats() });
        }
    }

    /// The backing memory.
    pub fn memory(&self) -> &Memory {
        &self.mem
    }

    /// The backing memory, to preload or inspect.
    pub fn memory_mut(&mut self) -> &mut Memory {
        &mut self.mem
    }

    /// Changes the timing (takes effect for new requests and cycles).
    pub fn set_timing(&mut self, t: AxiTiming) {
        self.timing = t;
    }

    /// What port `k` drives in the current cycle.
    pub fn outputs(&self, k: usize) -> SubordinateSignals {
        self.ports[k].out
    }

    /// True when port `k` has nothing in flight (no read, no write, no W data pending).
    pub fn idle(&self, k: usize) -> bool {
        let p = &self.ports[k];
        p.reads.is_empty() && p.aw.is_empty() && p.writes.is_empty() && p.out.b.is_none()
    }

    /// R and W data beats port `k` has transferred.
    pub fn beats(&self, k: usize) -> (u64, u64) {
        (self.ports[k].r_beats, self.ports[k].w_beats)
    }

    fn delay(&mut self, k: usize) -> u64 {
        let t = self.timing;
        let rng = &mut self.rngs[k];
        let extra = if t.extra_max > 0 && rng.percent(t.extra_percent) {
            rng.range(1, t.extra_max.into())
        } else {
            0
        };
        u64::from(t.latency) + extra
    }

    /// The clock edge of port `k`: applies the handshakes between what it drove this cycle and
    /// the manager's signals `m`, and returns what it drives in the next cycle.
    pub fn tick(&mut self, k: usize, m: &ManagerSignals) -> SubordinateSignals {
        let out = self.ports[k].out;
        // AR.
        if let (true, Some(a)) = (out.arready, m.ar) {
            self.record(k, false, &a);
            let ready_at = self.ports[k].now + self.delay(k);
            self.ports[k].reads.push(ReadBurst { a, ready_at, sent: 0 });
        }
        // R.
        if let (Some(r), true) = (out.r, m.rready) {
            let p = &mut self.ports[k];
            let i = p.r_cur.expect("an R beat is driven only for a current burst");
            p.reads[i].sent += 1;
            p.r_beats += 1;
            p.credit_r = p.credit_r.saturating_sub(self.timing.bandwidth.1);
            if r.last {
                p.reads.remove(i);
                p.r_cur = None;
            }
        }
        // AW.
        if let (true, Some(a)) = (out.awready, m.aw) {
            self.record(k, true, &a);
            self.ports[k].aw.push_back(a);
        }
        // W.
        if let (true, Some(w)) = (out.wready, m.w) {
            let d = self.delay(k);
            let p = &mut self.ports[k];
            p.w_data.push((w.data, w.strb));
            p.w_beats += 1;
            p.credit_w = p.credit_w.saturating_sub(self.timing.bandwidth.1);
            let a = *p.aw.front().expect("W is ready only for an accepted AW");
            if p.w_data.len() as u32 == a.beats() {
                p.aw.pop_front();
                let data = std::mem::take(&mut p.w_data);
                p.writes.push(Write { a, data, ready_at: p.now + d });
            }
        }
        // B.
        let b_taken = out.b.is_some() && m.bready;
        self.ports[k].now += 1;
        let next = self.next_outputs(k, out, m.rready, b_taken);
        self.ports[k].out = next;
        next
    }

    /// The next cycle's outputs of port `k` (`out`: this cycle's).
    fn next_outputs(
        &mut self,
        k: usize,
        out: SubordinateSignals,
        rready: bool,
        b_taken: bool,
    ) -> SubordinateSignals {
        let t = self.timing;
        let (num, den) = t.bandwidth;
        let p = &mut self.ports[k];
        p.credit_r = (p.credit_r + num).min(2 * den);
        p.credit_w = (p.credit_w + num).min(2 * den);
        let rng = &mut self.rngs[k];
        let mut next = SubordinateSignals {
            arready: rng.percent(t.ready_percent),
            awready: rng.percent(t.ready_percent),
            wready: !p.aw.is_empty() && p.credit_w >= den && rng.percent(t.ready_percent),
            r: None,
            b: None,
        };
        // R: hold a beat not taken; else the current burst's next beat; else a new burst.
        let held = out.r.filter(|_| !rready);
        if held.is_some() {
            next.r = held;
        } else if p.credit_r >= den {
            if p.r_cur.is_none() {
                p.r_cur = pick(&p.reads, p.now, t.reorder, rng, |b| (b.a.id, b.ready_at));
            }
            if let Some(i) = p.r_cur {
                let b = &p.reads[i];
                let addr = (b.a.addr & !(BEAT - 1)) + BEAT * u64::from(b.sent);
                next.r = Some(RBeat {
                    id: b.a.id,
                    data: self.mem.read_u64(addr),
                    resp: 0,
                    last: b.sent + 1 == b.a.beats(),
                });
            }
        }
        // B: hold one not taken; else a new one (its write applied now).
        if out.b.is_some() && !b_taken {
            next.b = out.b;
        } else if let Some(i) = pick(&p.writes, p.now, t.reorder, rng, |w| (w.a.id, w.ready_at)) {
            let w = p.writes.remove(i);
            let base = w.a.addr & !(BEAT - 1);
            for (j, (data, strb)) in w.data.iter().enumerate() {
                self.mem.write_strobed(base + BEAT * j as u64, &data.to_le_bytes(), u128::from(*strb));
            }
            next.b = Some(BResp { id: w.a.id, resp: 0 });
        }
        next
    }
}

/// The index of the next response among `items` (in arrival order, `key` = (ID, ready cycle)):
/// the oldest of all when it is ready (in order), or with `reorder` a random one among the
/// oldest item of each ID, when ready.
fn pick<T>(
    items: &[T],
    now: u64,
    reorder: bool,
    rng: &mut Rng,
    key: impl Fn(&T) -> (u32, u64),
) -> Option<usize> {
    if !reorder {
        return items.first().filter(|x| key(x).1 <= now).map(|_| 0);
    }
    let mut seen: Vec<u32> = Vec::new();
    let mut cands = Vec::new();
    for (i, x) in items.iter().enumerate() {
        let (id, at) = key(x);
        if seen.contains(&id) {
            continue;
        }
        seen.push(id);
        if at <= now {
            cands.push(i);
        }
    }
    (!cands.is_empty()).then(|| cands[rng.below(cands.len() as u64) as usize])
}
