//! [`HazardChecker`]: memory ordering across every AXI4 port of one manager (the engine's K
//! ports over one memory), observed cycle by cycle.
//!
//! AXI4 orders nothing between IDs or between ports, and nothing between a read and a write
//! even of one ID, so a manager that needs an order (a read of data it wrote, a write over data
//! it is still reading) must wait for the response itself. The checker stops at the first pair
//! of transactions in flight at once whose bytes overlap:
//!
//! - **RAW**: a read issued (AR accepted) while an overlapping write awaits its B: the read may
//!   see the old data;
//! - **WAR**: a write issued (AW accepted) while an overlapping read has beats not yet taken:
//!   the read may see the new data;
//! - **WAW**: a write issued while an overlapping write awaits its B. Of another port or another
//!   ID, either may land last. Of the same ID on the same port, AXI4 orders the two (a
//!   subordinate applies same-ID writes in order, and [`super::AxiMemory`] does), so the data is
//!   right; the checker flags it all the same: the engine does not rely on that order (every
//!   memory client has its own port and ID, and the whole engine suite passes with it flagged;
//!   docs/rtl.md), so such a pair is a duplicated write or a missing barrier. A unit that comes
//!   to rely on AXI4's same-ID order must document it and be exempted here.
//!
//! In flight: a read from its AR handshake until the handshake of its last R beat, with the
//! bytes of the beats not yet taken (a beat taken is data the manager has; the memory samples a
//! beat no later than its handshake); a write from its AW handshake until its B handshake, with
//! every byte of its burst (beat-aligned, as [`super::AxiMemory`] applies it, whatever the
//! strobes). Within a cycle the responses taken (R, B) retire first, then the ARs, then the AWs,
//! as the memory sees them: a read and a write accepted in the same cycle count as in flight at
//! once.
//!
//! [`HazardChecker::check_quiescent`] says whether anything is in flight or offered (a read, a
//! write awaiting its B, a W beat without its B, an AR/AW/W valid): the engine's `done` must
//! not be raised before.

use super::{Addr, ManagerSignals, SubordinateSignals};
use std::collections::{BTreeMap, VecDeque};
use std::fmt;

/// Bytes of a beat (the engine contract's 64-bit data).
const BEAT: u64 = 8;

/// The kind of a hazard.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HazardKind {
    /// A read issued over a write awaiting its B.
    Raw,
    /// A write issued over a read with beats not yet taken.
    War,
    /// A write issued over another port's or ID's write awaiting its B.
    Waw,
}

impl HazardKind {
    /// `RAW`, `WAR` or `WAW`.
    pub fn name(self) -> &'static str {
        match self {
            HazardKind::Raw => "RAW",
            HazardKind::War => "WAR",
            HazardKind::Waw => "WAW",
        }
    }
}

/// One transaction in flight: where, which bytes, since when.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Access {
    /// Port index.
    pub port: usize,
    /// AXI ID on that port.
    pub id: u32,
    /// Write (AW) or read (AR).
    pub write: bool,
    /// First byte of the bytes in flight (a read's first beat not yet taken).
    pub start: u64,
    /// One past the last byte.
    pub end: u64,
    /// The request as issued.
    pub req: Addr,
    /// Cycle of its address handshake.
    pub since: u64,
    /// Who issued it (the harness's name for the port's ID; empty when unnamed).
    pub who: String,
}

impl fmt::Display for Access {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let (what, how) =
            if self.write { ("write", "awaiting its B") } else { ("read", "beats not yet taken") };
        write!(f, "{what} on port {} ID 0x{:x}", self.port, self.id)?;
        if !self.who.is_empty() {
            write!(f, " ({})", self.who)?;
        }
        write!(
            f,
            " [0x{:x}..0x{:x}) (burst 0x{:x} + {} beats, issued cycle {}; {how})",
            self.start,
            self.end,
            self.req.addr,
            self.req.beats(),
            self.since
        )
    }
}

/// The first ordering hazard: the transaction just issued and the one in flight it overlaps.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Hazard {
    /// Cycle of the new transaction's address handshake.
    pub cycle: u64,
    /// RAW, WAR or WAW.
    pub kind: HazardKind,
    /// The transaction issued this cycle.
    pub new: Access,
    /// The transaction in flight it overlaps.
    pub old: Access,
}

impl fmt::Display for Hazard {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "MEMORY HAZARD ({}) at cycle {}: {} overlaps {} in bytes [0x{:x}..0x{:x})",
            self.kind.name(),
            self.cycle,
            self.new,
            self.old,
            self.new.start.max(self.old.start),
            self.new.end.min(self.old.end)
        )
    }
}

/// A read burst in flight: its request and the beats taken.
#[derive(Clone, Debug)]
struct Read {
    a: Addr,
    taken: u32,
    since: u64,
}

/// A write in flight (AW accepted, B not yet taken).
#[derive(Clone, Debug)]
struct Write {
    a: Addr,
    since: u64,
}

impl Read {
    /// The bytes of the beats not yet taken, `[start, end)`.
    fn span(&self) -> (u64, u64) {
        let base = beat_base(&self.a);
        (base + BEAT * u64::from(self.taken), base + BEAT * u64::from(self.a.beats()))
    }
}

impl Write {
    /// Every byte of the burst, `[start, end)`.
    fn span(&self) -> (u64, u64) {
        let base = beat_base(&self.a);
        (base, base + BEAT * u64::from(self.a.beats()))
    }
}

fn overlap((s0, e0): (u64, u64), (s1, e1): (u64, u64)) -> bool {
    s0 < e1 && s1 < e0
}

/// One port's transactions in flight.
#[derive(Clone, Debug, Default)]
struct PortState {
    /// Read bursts per ID, in issue order (R beats of one ID come back in order).
    reads: BTreeMap<u32, VecDeque<Read>>,
    /// Writes per ID, in issue order (B of one ID comes back in order).
    writes: BTreeMap<u32, VecDeque<Write>>,
    /// W beats taken and not yet answered by a B (each B retires its write's beats).
    w_beats: u64,
    /// What the manager drove in the last observed cycle (its valids offered).
    last: ManagerSignals,
}

/// Names the issuer of `(port, id)` in messages.
pub type Namer = Box<dyn Fn(usize, u32) -> String + Send>;

/// Ordering checker over all ports of one manager (see the module docs).
pub struct HazardChecker {
    ports: Vec<PortState>,
    cycle: u64,
    namer: Option<Namer>,
    first: Option<Box<Hazard>>,
}

impl fmt::Debug for HazardChecker {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("HazardChecker").field("cycle", &self.cycle).field("first", &self.first).finish()
    }
}

fn beat_base(a: &Addr) -> u64 {
    a.addr & !(BEAT - 1)
}

impl HazardChecker {
    /// A checker of `ports` ports.
    pub fn new(ports: usize) -> HazardChecker {
        HazardChecker { ports: vec![PortState::default(); ports], cycle: 0, namer: None, first: None }
    }

    /// Names the issuer of each `(port, id)` in the messages (e.g. the engine's memory client).
    pub fn with_namer(mut self, namer: Namer) -> HazardChecker {
        self.namer = Some(namer);
        self
    }

    /// The first hazard seen, if any.
    pub fn first_hazard(&self) -> Option<&Hazard> {
        self.first.as_deref()
    }

    fn who(&self, port: usize, id: u32) -> String {
        self.namer.as_ref().map(|n| n(port, id)).unwrap_or_default()
    }

    /// Transaction `a` on `port`, in flight since `since`, covering `[start, end)`.
    fn access(&self, port: usize, write: bool, a: Addr, since: u64, (start, end): (u64, u64)) -> Access {
        Access { port, id: a.id, write, start, end, req: a, since, who: self.who(port, a.id) }
    }

    /// Every read and write in flight, port by port.
    pub fn in_flight(&self) -> Vec<Access> {
        let mut v = Vec::new();
        for (p, s) in self.ports.iter().enumerate() {
            let mut ids: Vec<_> = s.reads.keys().chain(s.writes.keys()).copied().collect();
            ids.sort_unstable();
            ids.dedup();
            for id in ids {
                for r in s.reads.get(&id).into_iter().flatten() {
                    v.push(self.access(p, false, r.a, r.since, r.span()));
                }
                for w in s.writes.get(&id).into_iter().flatten() {
                    v.push(self.access(p, true, w.a, w.since, w.span()));
                }
            }
        }
        v
    }

    /// What each port has in flight or offers, one line per port (for a hang's message).
    pub fn describe(&self) -> String {
        let all = self.in_flight();
        let mut out = String::new();
        for (p, s) in self.ports.iter().enumerate() {
            let mine: Vec<&Access> = all.iter().filter(|a| a.port == p).collect();
            let offered: Vec<&str> = [
                (s.last.ar.is_some(), "ARVALID"),
                (s.last.aw.is_some(), "AWVALID"),
                (s.last.w.is_some(), "WVALID"),
            ]
            .iter()
            .filter(|(on, _)| *on)
            .map(|(_, n)| *n)
            .collect();
            out.push_str(&format!(
                "\n  port {p}: {} read(s), {} write(s) in flight, {} W beat(s) without B{}",
                mine.iter().filter(|a| !a.write).count(),
                mine.iter().filter(|a| a.write).count(),
                s.w_beats,
                if offered.is_empty() { String::new() } else { format!(", offering {}", offered.join(" ")) }
            ));
            for a in mine.iter().take(8) {
                out.push_str(&format!("\n    {a}"));
            }
            if mine.len() > 8 {
                out.push_str(&format!("\n    ... and {} more", mine.len() - 8));
            }
        }
        out
    }

    /// `Ok` when nothing is in flight or offered on any port (no read with beats to come, no
    /// write or W beat awaiting its B, no AR/AW/W valid in the last observed cycle); else what
    /// is, port by port.
    pub fn check_quiescent(&self) -> Result<(), String> {
        let busy = self.ports.iter().any(|s| {
            s.reads.values().any(|q| !q.is_empty())
                || s.writes.values().any(|q| !q.is_empty())
                || s.w_beats > 0
                || s.last.ar.is_some()
                || s.last.aw.is_some()
                || s.last.w.is_some()
        });
        if busy {
            Err(self.describe())
        } else {
            Ok(())
        }
    }

    /// The first in-flight access (in port, ID and issue order) that a read (or a write) over
    /// `span` conflicts with, if any.
    fn conflict(&self, write: bool, span: (u64, u64)) -> Option<(HazardKind, Access)> {
        for (p, s) in self.ports.iter().enumerate() {
            if write {
                let r = s.reads.values().flatten().find(|r| overlap(r.span(), span));
                if let Some(r) = r {
                    return Some((HazardKind::War, self.access(p, false, r.a, r.since, r.span())));
                }
            }
            // A write over a write of the same port and ID too (see the module docs).
            let w = s.writes.values().flatten().find(|w| overlap(w.span(), span));
            if let Some(w) = w {
                let kind = if write { HazardKind::Waw } else { HazardKind::Raw };
                return Some((kind, self.access(p, true, w.a, w.since, w.span())));
            }
        }
        None
    }

    /// Observes one cycle of every port (`ports[k]`: what the manager and the subordinate
    /// drive on port `k`; the handshakes happen at the end of the cycle). Returns the first
    /// hazard (this cycle's or an earlier one).
    ///
    /// # Panics
    /// When `ports` does not have one entry per port, or a response has no request (the
    /// per-port [`super::AxiChecker`] reports those first).
    pub fn observe(&mut self, ports: &[(ManagerSignals, SubordinateSignals)]) -> Result<(), Box<Hazard>> {
        assert_eq!(ports.len(), self.ports.len(), "one (manager, subordinate) pair per port");
        if let Some(h) = &self.first {
            return Err(h.clone());
        }
        let r = self.step(ports);
        self.cycle += 1;
        if let Err(h) = r {
            self.first = Some(h.clone());
            return Err(h);
        }
        Ok(())
    }

    fn step(&mut self, ports: &[(ManagerSignals, SubordinateSignals)]) -> Result<(), Box<Hazard>> {
        // Responses taken retire first.
        for (s, (m, sub)) in self.ports.iter_mut().zip(ports) {
            s.last = *m;
            if let (Some(r), true) = (sub.r, m.rready) {
                if let Some(q) = s.reads.get_mut(&r.id) {
                    if let Some(front) = q.front_mut() {
                        front.taken += 1;
                        if front.taken >= front.a.beats() {
                            q.pop_front();
                        }
                    }
                }
            }
            if let (Some(b), true) = (sub.b, m.bready) {
                if let Some(w) = s.writes.get_mut(&b.id).and_then(VecDeque::pop_front) {
                    s.w_beats = s.w_beats.saturating_sub(w.a.beats().into());
                }
            }
            if let (Some(_), true) = (m.w, sub.wready) {
                s.w_beats += 1;
            }
        }
        // Then the reads issued this cycle, then the writes.
        for write in [false, true] {
            for (p, (m, sub)) in ports.iter().enumerate() {
                let (req, ready) = if write { (m.aw, sub.awready) } else { (m.ar, sub.arready) };
                let Some(a) = req.filter(|_| ready) else { continue };
                let (read, wr) = (Read { a, taken: 0, since: self.cycle }, Write { a, since: self.cycle });
                let span = if write { wr.span() } else { read.span() };
                if let Some((kind, old)) = self.conflict(write, span) {
                    let new = self.access(p, write, a, self.cycle, span);
                    return Err(Box::new(Hazard { cycle: self.cycle, kind, new, old }));
                }
                let s = &mut self.ports[p];
                if write {
                    s.writes.entry(a.id).or_default().push_back(wr);
                } else {
                    s.reads.entry(a.id).or_default().push_back(read);
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::super::{BResp, RBeat, WBeat};
    use super::*;

    fn req(id: u32, addr: u64, len: u8) -> Addr {
        Addr { id, addr, len, size: 3, burst: 1 }
    }

    fn idle() -> (ManagerSignals, SubordinateSignals) {
        (ManagerSignals::default(), SubordinateSignals::default())
    }

    /// An AR accepted on a port.
    fn ar(a: Addr) -> (ManagerSignals, SubordinateSignals) {
        (
            ManagerSignals { ar: Some(a), ..Default::default() },
            SubordinateSignals { arready: true, ..Default::default() },
        )
    }

    /// An AW and its single W beat accepted on a port.
    fn aw(a: Addr) -> (ManagerSignals, SubordinateSignals) {
        (
            ManagerSignals {
                aw: Some(a),
                w: Some(WBeat { data: 0, strb: 0xff, last: true }),
                ..Default::default()
            },
            SubordinateSignals { awready: true, wready: true, ..Default::default() },
        )
    }

    /// An R beat of `id` taken.
    fn r(id: u32, last: bool) -> (ManagerSignals, SubordinateSignals) {
        (
            ManagerSignals { rready: true, ..Default::default() },
            SubordinateSignals { r: Some(RBeat { id, data: 0, resp: 0, last }), ..Default::default() },
        )
    }

    /// A B of `id` taken.
    fn b(id: u32) -> (ManagerSignals, SubordinateSignals) {
        (
            ManagerSignals { bready: true, ..Default::default() },
            SubordinateSignals { b: Some(BResp { id, resp: 0 }), ..Default::default() },
        )
    }

    #[test]
    fn ordered_accesses_pass_and_leave_nothing_in_flight() {
        let mut c = HazardChecker::new(2);
        // Port 0 writes 0x100..0x110; port 1 reads it after the B; port 0 rewrites 0x108 after
        // port 1 took the beat that covers it, while port 1 still reads beat 0x110.
        c.observe(&[aw(req(1, 0x100, 1)), idle()]).unwrap();
        assert!(c.check_quiescent().is_err(), "a write awaits its B");
        c.observe(&[b(1), idle()]).unwrap();
        c.observe(&[idle(), ar(req(0, 0x100, 2))]).unwrap();
        c.observe(&[idle(), r(0, false)]).unwrap();
        c.observe(&[idle(), r(0, false)]).unwrap();
        c.observe(&[aw(req(1, 0x108, 0)), r(0, true)]).unwrap();
        // Disjoint bytes in flight on both ports, and two writes of one ID on one port.
        c.observe(&[aw(req(1, 0x110, 0)), ar(req(2, 0x200, 3))]).unwrap();
        c.observe(&[b(1), idle()]).unwrap();
        c.observe(&[b(1), idle()]).unwrap();
        for k in 0..4 {
            c.observe(&[idle(), r(2, k == 3)]).unwrap();
        }
        c.observe(&[idle(), idle()]).unwrap();
        assert_eq!(c.check_quiescent(), Ok(()));
        assert!(c.first_hazard().is_none());
    }

    #[test]
    fn a_read_over_a_write_awaiting_b_is_raw() {
        let mut c =
            HazardChecker::new(2).with_namer(Box::new(|p, id| format!("client {}", id as usize * 2 + p)));
        c.observe(&[aw(req(1, 0x1000, 3)), idle()]).unwrap();
        c.observe(&[idle(), idle()]).unwrap();
        let h = c.observe(&[idle(), ar(req(0, 0x1018, 1))]).unwrap_err();
        assert_eq!((h.kind, h.cycle, h.new.port, h.old.port, h.old.id), (HazardKind::Raw, 2, 1, 0, 1));
        let s = h.to_string();
        assert!(
            s.starts_with(
                "MEMORY HAZARD (RAW) at cycle 2: read on port 1 ID 0x0 (client 1) [0x1018..0x1028)"
            ),
            "{s}"
        );
        assert!(s.contains("write on port 0 ID 0x1 (client 2) [0x1000..0x1020)"), "{s}");
        assert!(s.ends_with("in bytes [0x1018..0x1020)"), "{s}");
        // The hazard sticks.
        assert_eq!(*c.observe(&[idle(), idle()]).unwrap_err(), *h);
    }

    #[test]
    fn a_write_over_beats_not_yet_taken_is_war() {
        let mut c = HazardChecker::new(1);
        c.observe(&[ar(req(0, 0x40, 3))]).unwrap();
        c.observe(&[r(0, false)]).unwrap();
        // Beat 0 (0x40) was taken: writing it is fine; beat 3 (0x58) is not.
        c.observe(&[aw(req(1, 0x40, 0))]).unwrap();
        let h = c.observe(&[aw(req(1, 0x58, 0))]).unwrap_err();
        assert_eq!(h.kind, HazardKind::War);
        assert_eq!((h.old.start, h.old.end, h.new.start, h.new.end), (0x48, 0x60, 0x58, 0x60));
        // A read and a write issued in the same cycle are in flight at once.
        let mut c = HazardChecker::new(2);
        let h = c.observe(&[ar(req(0, 0x40, 0)), aw(req(0, 0x44, 0))]).unwrap_err();
        assert_eq!((h.kind, h.cycle), (HazardKind::War, 0));
    }

    #[test]
    fn overlapping_writes_in_flight_are_waw_whatever_their_ports_and_ids() {
        let mut c = HazardChecker::new(2);
        c.observe(&[aw(req(3, 0x800, 7)), idle()]).unwrap();
        let h = c.observe(&[idle(), aw(req(3, 0x838, 0))]).unwrap_err();
        assert_eq!((h.kind, h.new.port, h.old.port), (HazardKind::Waw, 1, 0));
        let mut c = HazardChecker::new(1);
        c.observe(&[aw(req(3, 0x800, 0))]).unwrap();
        let h = c.observe(&[aw(req(2, 0x800, 0))]).unwrap_err();
        assert_eq!((h.kind, h.new.id, h.old.id), (HazardKind::Waw, 2, 3));
        // One ID on one port: ordered by AXI4, flagged as a duplicated write all the same; the
        // same write after its B passes.
        let mut c = HazardChecker::new(1);
        c.observe(&[aw(req(3, 0x800, 1))]).unwrap();
        let h = c.observe(&[aw(req(3, 0x808, 0))]).unwrap_err();
        assert_eq!((h.kind, h.new.id, h.old.id, h.new.port, h.old.port), (HazardKind::Waw, 3, 3, 0, 0));
        let mut c = HazardChecker::new(1);
        c.observe(&[aw(req(3, 0x800, 0))]).unwrap();
        c.observe(&[b(3)]).unwrap();
        c.observe(&[aw(req(3, 0x800, 0))]).unwrap();
    }

    #[test]
    fn quiescence_names_what_is_in_flight_or_offered() {
        let mut c = HazardChecker::new(2);
        c.observe(&[idle(), ar(req(5, 0x2000, 1))]).unwrap();
        let e = c.check_quiescent().unwrap_err();
        assert!(e.contains("port 1: 1 read(s), 0 write(s) in flight"), "{e}");
        assert!(e.contains("read on port 1 ID 0x5 [0x2000..0x2010)"), "{e}");
        c.observe(&[idle(), r(5, false)]).unwrap();
        c.observe(&[idle(), r(5, true)]).unwrap();
        assert_eq!(c.check_quiescent(), Ok(()));
        // An AR offered and not taken.
        let offered =
            (ManagerSignals { ar: Some(req(0, 0, 0)), ..Default::default() }, SubordinateSignals::default());
        c.observe(&[offered, idle()]).unwrap();
        assert!(c.check_quiescent().unwrap_err().contains("offering ARVALID"));
    }
}
