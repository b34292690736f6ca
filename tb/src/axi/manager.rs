//! [`RandomManager`]: a Rust-driven AXI4 manager issuing random reads and writes (one ID, at most
//! `outstanding` of each in flight) over its own 4 KiB pages (anywhere in the address space),
//! checking every R beat against its shadow of them.
//!
//! A read never overlaps a write in flight (AW issued, B not received) and a write never overlaps
//! a read or write in flight, so the shadow (updated when a B arrives) is exactly what the memory
//! must return. Bursts are INCR, 8-byte beats, 1..=256 beats, inside one 4 KiB page.

use super::{Addr, ManagerSignals, SubordinateSignals, WBeat};
use crate::check::Checker;
use crate::rng::Rng;
use neo_golden::engine::memory::Memory;
use std::collections::VecDeque;

/// How a [`RandomManager`] behaves.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Traffic {
    /// Read bursts to issue.
    pub reads: usize,
    /// Write bursts to issue.
    pub writes: usize,
    /// Percent of cycles a new request is offered when one may be.
    pub issue_percent: u32,
    /// Percent of cycles RREADY and BREADY are high.
    pub ready_percent: u32,
    /// Longest burst (beats, 1..=256).
    pub max_beats: u32,
    /// Percent of write beats with random (not all-ones) strobes.
    pub partial_strobe_percent: u32,
}

/// A random AXI4 manager (see the module docs).
#[derive(Debug)]
pub struct RandomManager {
    name: String,
    /// Byte address of each of its pages.
    pages: Vec<u64>,
    id: u32,
    outstanding: usize,
    t: Traffic,
    rng: Rng,
    shadow: Memory,
    ar: Option<Addr>,
    aw: Option<Addr>,
    /// Reads accepted: the burst and the beats received.
    reads: VecDeque<(Addr, u32)>,
    /// Writes whose AW is offered or accepted: the burst, its beats, beats sent, AW accepted.
    wq: VecDeque<(Addr, Vec<WBeat>, usize, bool)>,
    /// Writes whose data is all sent, awaiting B, in order.
    bq: VecDeque<(Addr, Vec<WBeat>)>,
    issued: (usize, usize),
    done: (usize, usize),
}

impl RandomManager {
    /// A manager named `name` over the 4 KiB pages at byte addresses `pages` (4 KiB aligned,
    /// at least one), using ID `id`, at most `outstanding` reads and writes each in flight;
    /// `shadow` holds the pages' initial contents (as the memory does).
    pub fn new(
        name: &str,
        pages: &[u64],
        id: u32,
        outstanding: usize,
        t: Traffic,
        seed: u64,
        shadow: Memory,
    ) -> RandomManager {
        RandomManager {
            name: name.to_string(),
            pages: {
                assert!(
                    !pages.is_empty() && pages.iter().all(|p| p.is_multiple_of(4096)),
                    "{name}: 4 KiB pages"
                );
                pages.to_vec()
            },
            id,
            outstanding,
            t,
            rng: Rng::new(seed),
            shadow,
            ar: None,
            aw: None,
            reads: VecDeque::new(),
            wq: VecDeque::new(),
            bq: VecDeque::new(),
            issued: (0, 0),
            done: (0, 0),
        }
    }

    /// Byte addresses of its pages.
    pub fn pages(&self) -> &[u64] {
        &self.pages
    }

    /// Every request issued and answered.
    pub fn finished(&self) -> bool {
        self.done == (self.t.reads, self.t.writes)
    }

    /// Reads and writes completed.
    pub fn done(&self) -> (usize, usize) {
        self.done
    }

    /// The shadow of the region (the memory's expected contents once every write is answered).
    pub fn shadow(&self) -> &Memory {
        &self.shadow
    }

    fn overlaps(a: &Addr, lo: u64, hi: u64) -> bool {
        let (s, e) = (a.addr, a.addr + 8 * u64::from(a.beats()));
        s < hi && lo < e
    }

    fn busy(&self, lo: u64, hi: u64, with_reads: bool) -> bool {
        let w = self
            .wq
            .iter()
            .map(|x| &x.0)
            .chain(self.bq.iter().map(|x| &x.0))
            .any(|a| Self::overlaps(a, lo, hi));
        let r = with_reads
            && self.reads.iter().map(|x| &x.0).chain(self.ar.iter()).any(|a| Self::overlaps(a, lo, hi));
        w || r
    }

    fn random_burst(&mut self) -> Addr {
        let beats = self.rng.range(1, self.t.max_beats.into());
        let page = self.pages[self.rng.below(self.pages.len() as u64) as usize];
        let word = self.rng.range(0, 512 - beats);
        Addr { id: self.id, addr: page + 8 * word, len: (beats - 1) as u8, size: 3, burst: 1 }
    }

    /// What the manager drives this cycle (new requests are decided here and then held).
    pub fn drive(&mut self) -> ManagerSignals {
        let reads_in_flight = self.reads.len() + usize::from(self.ar.is_some());
        if self.ar.is_none()
            && self.issued.0 < self.t.reads
            && reads_in_flight < self.outstanding
            && self.rng.percent(self.t.issue_percent)
        {
            let a = self.random_burst();
            let (lo, hi) = (a.addr, a.addr + 8 * u64::from(a.beats()));
            if !self.busy(lo, hi, false) {
                self.ar = Some(a);
                self.issued.0 += 1;
            }
        }
        let writes_in_flight = self.wq.len() + self.bq.len();
        if self.aw.is_none()
            && self.issued.1 < self.t.writes
            && writes_in_flight < self.outstanding
            && self.rng.percent(self.t.issue_percent)
        {
            let a = self.random_burst();
            let (lo, hi) = (a.addr, a.addr + 8 * u64::from(a.beats()));
            if !self.busy(lo, hi, true) {
                let beats = (0..a.beats())
                    .map(|k| WBeat {
                        data: self.rng.next_u64(),
                        strb: if self.rng.percent(self.t.partial_strobe_percent) {
                            self.rng.next_u32() as u8
                        } else {
                            0xff
                        },
                        last: k + 1 == a.beats(),
                    })
                    .collect();
                self.aw = Some(a);
                self.wq.push_back((a, beats, 0, false));
                self.issued.1 += 1;
            }
        }
        let w = self.wq.front().map(|(_, beats, sent, _)| beats[*sent]);
        ManagerSignals {
            ar: self.ar,
            rready: self.rng.percent(self.t.ready_percent),
            aw: self.aw,
            w,
            bready: self.rng.percent(self.t.ready_percent),
        }
    }

    /// The clock edge: the handshakes of `m` (what [`Self::drive`] returned) against the
    /// subordinate's `s`; R beats and B responses are checked (first mismatch panics through
    /// `chk` at `cycle`).
    pub fn clock(&mut self, m: &ManagerSignals, s: &SubordinateSignals, chk: &Checker, cycle: u64) {
        if let (Some(a), true) = (m.ar, s.arready) {
            self.reads.push_back((a, 0));
            self.ar = None;
        }
        if let (Some(r), true) = (s.r, m.rready) {
            let Some((a, k)) = self.reads.front_mut() else {
                chk.fail(cycle, &format!("{}: rvalid", self.name), "no read outstanding", "1")
            };
            let addr = a.beat_addr(*k);
            let want = self.shadow.read_u64(addr);
            chk.value(cycle, &format!("{}: rdata of beat {k} at 0x{addr:x}", self.name), want, r.data);
            chk.value(cycle, &format!("{}: rid", self.name), 0, r.id.into());
            chk.value(cycle, &format!("{}: rresp", self.name), 0, r.resp.into());
            *k += 1;
            let last = *k == a.beats();
            chk.value(
                cycle,
                &format!("{}: rlast of beat {} of {}", self.name, *k - 1, a.beats()),
                last.into(),
                r.last.into(),
            );
            if last {
                self.reads.pop_front();
                self.done.0 += 1;
            }
        }
        if let (Some(_), true) = (m.aw, s.awready) {
            self.aw = None;
            if let Some(x) = self.wq.iter_mut().find(|x| !x.3) {
                x.3 = true;
            }
        }
        if let (Some(_), true) = (m.w, s.wready) {
            let front = self.wq.front_mut().expect("a W beat is driven only for a queued write");
            front.2 += 1;
            if front.2 == front.1.len() {
                let (a, beats, _, accepted) = self.wq.pop_front().expect("front");
                if !accepted {
                    chk.fail(
                        cycle,
                        &format!("{}: wready", self.name),
                        "W taken only after its AW",
                        "the last beat before the AW",
                    );
                }
                self.bq.push_back((a, beats));
            }
        }
        if let (Some(b), true) = (s.b, m.bready) {
            let Some((a, beats)) = self.bq.pop_front() else {
                chk.fail(cycle, &format!("{}: bvalid", self.name), "no write awaiting B", "1")
            };
            chk.value(cycle, &format!("{}: bid", self.name), 0, b.id.into());
            chk.value(cycle, &format!("{}: bresp", self.name), 0, b.resp.into());
            for (k, w) in beats.iter().enumerate() {
                self.shadow.write_strobed(a.addr + 8 * k as u64, &w.data.to_le_bytes(), u128::from(w.strb));
            }
            self.done.1 += 1;
        }
    }
}
