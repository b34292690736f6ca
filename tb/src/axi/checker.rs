//! [`AxiChecker`]: AXI4 protocol assertions on one port, observed cycle by cycle from both sides'
//! signals. The first violation is kept and returned, naming the cycle, port, channel, field,
//! expected and actual values (hex).
//!
//! Checked: a valid (AR, AW, W, R, B) stays asserted with a stable payload until its ready;
//! AR/AW are INCR bursts of `size` 3 (8-byte beats) inside one 4 KiB page; WLAST on the AWLEN-th
//! beat (the W beats of the AWs in order, W may run ahead of its AW); R only for an ID with a read
//! outstanding, RLAST on its ARLEN-th beat; B only for an ID with a write whose data is complete;
//! at most `max_reads` read bursts and `max_writes` writes (AW accepted, B not yet) in flight.

use super::{Addr, ManagerSignals, SubordinateSignals};
use std::collections::{HashMap, VecDeque};
use std::fmt;

/// One protocol violation.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Violation {
    /// Cycle of the violation (the checker's count of observed cycles).
    pub cycle: u64,
    /// Port index and name.
    pub port: usize,
    /// Port name (e.g. `m_axi`, `s1_axi`).
    pub name: String,
    /// Channel (AR, R, AW, W, B).
    pub channel: &'static str,
    /// Field (e.g. `araddr`, `wlast`, `reads in flight`).
    pub field: String,
    /// Expected value (hex or a description).
    pub expected: String,
    /// Actual value (hex).
    pub actual: String,
}

impl fmt::Display for Violation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "AXI PROTOCOL VIOLATION at cycle {}: port {} ({}), channel {}, field {}: expected {}, actual {}",
            self.cycle, self.port, self.name, self.channel, self.field, self.expected, self.actual
        )
    }
}

fn hex(v: u64) -> String {
    format!("0x{v:x}")
}

/// Protocol checker of one port (see the module docs).
#[derive(Clone, Debug)]
pub struct AxiChecker {
    port: usize,
    name: String,
    max_reads: usize,
    max_writes: usize,
    cycle: u64,
    prev_m: ManagerSignals,
    prev_s: SubordinateSignals,
    /// Beats left of each outstanding read burst, per ID, in order.
    reads: HashMap<u32, VecDeque<u32>>,
    reads_in_flight: usize,
    /// AWs accepted whose W beats are not complete, in order.
    aw_wait: VecDeque<Addr>,
    /// W bursts completed before their AW (beat counts), and the beats of the current burst.
    w_early: VecDeque<u32>,
    w_cur: u32,
    /// Writes with complete data awaiting B, per ID.
    b_due: HashMap<u32, usize>,
    writes_in_flight: usize,
    first: Option<Box<Violation>>,
}

impl AxiChecker {
    /// A checker for port `port` named `name`, allowing `max_reads` read bursts and `max_writes`
    /// writes in flight.
    pub fn new(port: usize, name: &str, max_reads: usize, max_writes: usize) -> AxiChecker {
        AxiChecker {
            port,
            name: name.to_string(),
            max_reads,
            max_writes,
            cycle: 0,
            prev_m: ManagerSignals::default(),
            prev_s: SubordinateSignals::default(),
            reads: HashMap::new(),
            reads_in_flight: 0,
            aw_wait: VecDeque::new(),
            w_early: VecDeque::new(),
            w_cur: 0,
            b_due: HashMap::new(),
            writes_in_flight: 0,
            first: None,
        }
    }

    /// The first violation seen, if any.
    pub fn first_violation(&self) -> Option<&Violation> {
        self.first.as_deref()
    }

    /// Read bursts and writes in flight.
    pub fn in_flight(&self) -> (usize, usize) {
        (self.reads_in_flight, self.writes_in_flight)
    }

    fn v(&self, channel: &'static str, field: &str, expected: String, actual: String) -> Box<Violation> {
        Box::new(Violation {
            cycle: self.cycle,
            port: self.port,
            name: self.name.clone(),
            channel,
            field: field.to_string(),
            expected,
            actual,
        })
    }

    /// Observes one cycle (both sides' signals, the handshakes happen at its end). Returns the
    /// first violation (this cycle's or an earlier one).
    pub fn observe(&mut self, m: &ManagerSignals, s: &SubordinateSignals) -> Result<(), Box<Violation>> {
        if let Some(v) = &self.first {
            return Err(v.clone());
        }
        let r = self.check(m, s);
        self.prev_m = *m;
        self.prev_s = *s;
        self.cycle += 1;
        if let Err(v) = r {
            self.first = Some(v.clone());
            return Err(v);
        }
        Ok(())
    }

    fn held_addr(
        &self,
        ch: &'static str,
        p: &str,
        prev: Option<Addr>,
        taken: bool,
        now: Option<Addr>,
    ) -> Result<(), Box<Violation>> {
        let Some(a) = prev.filter(|_| !taken) else { return Ok(()) };
        let Some(b) = now else {
            return Err(self.v(ch, &format!("{p}valid (held until {p}ready)"), hex(1), hex(0)));
        };
        for (f, x, y) in [
            ("id", u64::from(a.id), u64::from(b.id)),
            ("addr", a.addr, b.addr),
            ("len", a.len.into(), b.len.into()),
            ("size", a.size.into(), b.size.into()),
            ("burst", a.burst.into(), b.burst.into()),
        ] {
            if x != y {
                return Err(self.v(ch, &format!("{p}{f} (stable while valid)"), hex(x), hex(y)));
            }
        }
        Ok(())
    }

    fn burst_ok(&self, ch: &'static str, p: &str, a: &Addr) -> Result<(), Box<Violation>> {
        if a.burst != 1 {
            return Err(self.v(ch, &format!("{p}burst"), hex(1), hex(a.burst.into())));
        }
        if a.size != 3 {
            return Err(self.v(ch, &format!("{p}size"), hex(3), hex(a.size.into())));
        }
        let end = (a.addr & 4095) + (u64::from(a.beats()) << a.size);
        if end > 4096 {
            return Err(self.v(
                ch,
                &format!("{p}addr + {p}len (INCR burst within 4 KiB)"),
                format!("end <= 0x1000 in the page of 0x{:x}", a.addr),
                format!("{} beats from 0x{:x} end at page offset 0x{end:x}", a.beats(), a.addr),
            ));
        }
        Ok(())
    }

    fn check(&mut self, m: &ManagerSignals, s: &SubordinateSignals) -> Result<(), Box<Violation>> {
        let (pm, ps) = (self.prev_m, self.prev_s);
        // Valids held with stable payloads.
        self.held_addr("AR", "ar", pm.ar, ps.arready, m.ar)?;
        self.held_addr("AW", "aw", pm.aw, ps.awready, m.aw)?;
        if let (Some(a), false) = (pm.w, ps.wready) {
            let Some(b) = m.w else { return Err(self.v("W", "wvalid (held until wready)", hex(1), hex(0))) };
            for (f, x, y) in [
                ("wdata", a.data, b.data),
                ("wstrb", a.strb.into(), b.strb.into()),
                ("wlast", a.last.into(), b.last.into()),
            ] {
                if x != y {
                    return Err(self.v("W", &format!("{f} (stable while valid)"), hex(x), hex(y)));
                }
            }
        }
        if let (Some(a), false) = (ps.r, pm.rready) {
            let Some(b) = s.r else { return Err(self.v("R", "rvalid (held until rready)", hex(1), hex(0))) };
            for (f, x, y) in [
                ("rid", a.id.into(), b.id.into()),
                ("rdata", a.data, b.data),
                ("rresp", a.resp.into(), b.resp.into()),
                ("rlast", a.last.into(), b.last.into()),
            ] {
                if x != y {
                    return Err(self.v("R", &format!("{f} (stable while valid)"), hex(x), hex(y)));
                }
            }
        }
        if let (Some(a), false) = (ps.b, pm.bready) {
            let Some(b) = s.b else { return Err(self.v("B", "bvalid (held until bready)", hex(1), hex(0))) };
            if (a.id, a.resp) != (b.id, b.resp) {
                return Err(self.v(
                    "B",
                    "bid/bresp (stable while valid)",
                    hex(a.id.into()),
                    hex(b.id.into()),
                ));
            }
        }
        // Responses only to outstanding IDs (checked whenever valid).
        if let Some(r) = s.r {
            if self.reads.get(&r.id).is_none_or(|q| q.is_empty()) {
                return Err(self.v(
                    "R",
                    "rid (an ID with a read outstanding)",
                    "none outstanding".into(),
                    hex(r.id.into()),
                ));
            }
        }
        if let Some(b) = s.b {
            if self.b_due.get(&b.id).copied().unwrap_or(0) == 0 {
                return Err(self.v(
                    "B",
                    "bid (an ID with a complete write awaiting B)",
                    "none awaiting B".into(),
                    hex(b.id.into()),
                ));
            }
        }
        // Handshakes at the end of the cycle: R and B first (a response frees its slot), then
        // the new requests.
        if let (Some(r), true) = (s.r, m.rready) {
            let last = {
                let q = self.reads.get_mut(&r.id).expect("checked above");
                let left = q.front_mut().expect("checked above");
                *left -= 1;
                let last = *left == 0;
                if last {
                    q.pop_front();
                }
                last
            };
            if last {
                self.reads_in_flight -= 1;
            }
            if r.last != last {
                return Err(self.v(
                    "R",
                    &format!("rlast (ID 0x{:x})", r.id),
                    hex(last.into()),
                    hex(r.last.into()),
                ));
            }
        }
        if let (Some(b), true) = (s.b, m.bready) {
            *self.b_due.get_mut(&b.id).expect("checked above") -= 1;
            self.writes_in_flight -= 1;
        }
        if let (Some(a), true) = (m.ar, s.arready) {
            self.burst_ok("AR", "ar", &a)?;
            self.reads.entry(a.id).or_default().push_back(a.beats());
            self.reads_in_flight += 1;
            if self.reads_in_flight > self.max_reads {
                return Err(self.v(
                    "AR",
                    "reads in flight",
                    format!("<= {}", self.max_reads),
                    hex(self.reads_in_flight as u64),
                ));
            }
        }
        if let (Some(a), true) = (m.aw, s.awready) {
            self.burst_ok("AW", "aw", &a)?;
            self.writes_in_flight += 1;
            if self.writes_in_flight > self.max_writes {
                return Err(self.v(
                    "AW",
                    "writes in flight",
                    format!("<= {}", self.max_writes),
                    hex(self.writes_in_flight as u64),
                ));
            }
            if let Some(n) = self.w_early.pop_front() {
                if n != a.beats() {
                    return Err(self.v(
                        "W",
                        "beats of a burst sent before its AW (AWLEN + 1)",
                        hex(a.beats().into()),
                        hex(n.into()),
                    ));
                }
                *self.b_due.entry(a.id).or_default() += 1;
            } else {
                if self.aw_wait.is_empty() && self.w_cur > a.beats() {
                    return Err(self.v(
                        "W",
                        "beats before WLAST (AWLEN + 1)",
                        hex(a.beats().into()),
                        hex(self.w_cur.into()),
                    ));
                }
                self.aw_wait.push_back(a);
            }
        }
        if let (Some(w), true) = (m.w, s.wready) {
            self.w_cur += 1;
            if self.w_early.is_empty() && !self.aw_wait.is_empty() {
                let a = self.aw_wait[0];
                let last = self.w_cur == a.beats();
                if w.last != last {
                    return Err(self.v(
                        "W",
                        &format!(
                            "wlast (beat {} of {} of AW ID 0x{:x} at 0x{:x})",
                            self.w_cur,
                            a.beats(),
                            a.id,
                            a.addr
                        ),
                        hex(last.into()),
                        hex(w.last.into()),
                    ));
                }
                if last {
                    self.aw_wait.pop_front();
                    *self.b_due.entry(a.id).or_default() += 1;
                    self.w_cur = 0;
                }
            } else if w.last {
                self.w_early.push_back(self.w_cur);
                self.w_cur = 0;
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::super::{RBeat, WBeat};
    use super::*;

    fn ar(addr: u64, len: u8) -> Addr {
        Addr { id: 0, addr, len, size: 3, burst: 1 }
    }

    #[test]
    fn a_clean_read_and_write_pass() {
        let mut c = AxiChecker::new(0, "m_axi", 2, 2);
        let idle = SubordinateSignals::default();
        let m = ManagerSignals { ar: Some(ar(0x100, 1)), ..Default::default() };
        c.observe(&m, &idle).unwrap();
        c.observe(&m, &SubordinateSignals { arready: true, ..idle }).unwrap();
        let r = |last| SubordinateSignals { r: Some(RBeat { id: 0, data: 5, resp: 0, last }), ..idle };
        let rr = ManagerSignals { rready: true, ..Default::default() };
        c.observe(&rr, &r(false)).unwrap();
        c.observe(&rr, &r(true)).unwrap();
        let w = ManagerSignals {
            aw: Some(ar(0x200, 0)),
            w: Some(WBeat { data: 1, strb: 0xff, last: true }),
            ..Default::default()
        };
        c.observe(&w, &SubordinateSignals { awready: true, wready: true, ..idle }).unwrap();
        assert_eq!(c.in_flight(), (0, 1));
        c.observe(
            &ManagerSignals { bready: true, ..Default::default() },
            &SubordinateSignals { b: Some(Default::default()), ..idle },
        )
        .unwrap();
        assert_eq!(c.in_flight(), (0, 0));
    }

    #[test]
    fn violations_name_channel_field_and_values() {
        let idle = SubordinateSignals::default();
        // Payload changed while valid.
        let mut c = AxiChecker::new(1, "s1_axi", 4, 4);
        c.observe(&ManagerSignals { ar: Some(ar(0x100, 1)), ..Default::default() }, &idle).unwrap();
        let e =
            c.observe(&ManagerSignals { ar: Some(ar(0x108, 1)), ..Default::default() }, &idle).unwrap_err();
        assert_eq!((e.cycle, e.channel, e.expected.as_str(), e.actual.as_str()), (1, "AR", "0x100", "0x108"));
        assert!(
            e.to_string()
                .starts_with("AXI PROTOCOL VIOLATION at cycle 1: port 1 (s1_axi), channel AR, field araddr"),
            "{e}"
        );
        // 4 KiB crossing.
        let mut c = AxiChecker::new(0, "m", 4, 4);
        let e = c
            .observe(
                &ManagerSignals { ar: Some(ar(0xff8, 1)), ..Default::default() },
                &SubordinateSignals { arready: true, ..idle },
            )
            .unwrap_err();
        assert!(e.field.contains("4 KiB"), "{e}");
        // R for an ID with nothing outstanding.
        let mut c = AxiChecker::new(0, "m", 4, 4);
        let e = c
            .observe(&ManagerSignals::default(), &SubordinateSignals { r: Some(RBeat::default()), ..idle })
            .unwrap_err();
        assert_eq!(e.channel, "R");
        // WLAST early, and the violation sticks.
        let mut c = AxiChecker::new(0, "m", 4, 4);
        let m = ManagerSignals {
            aw: Some(ar(0, 1)),
            w: Some(WBeat { data: 0, strb: 0xff, last: true }),
            ..Default::default()
        };
        let e = c.observe(&m, &SubordinateSignals { awready: true, wready: true, ..idle }).unwrap_err();
        assert!(e.field.starts_with("wlast"), "{e}");
        assert_eq!(c.observe(&ManagerSignals::default(), &idle).unwrap_err(), e);
        // Too many writes in flight.
        let mut c = AxiChecker::new(0, "m", 4, 1);
        let m = ManagerSignals { aw: Some(ar(0, 0)), ..Default::default() };
        let s = SubordinateSignals { awready: true, ..idle };
        c.observe(&m, &s).unwrap();
        assert_eq!(c.observe(&m, &s).unwrap_err().field, "writes in flight");
    }
}
