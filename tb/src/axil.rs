//! An AXI4-Lite manager driver ([`AxilManager`]) and protocol checker ([`AxilChecker`]) for a
//! subordinate's port `PREFIX{awvalid,awready,awaddr,wvalid,wready,wdata,wstrb,bvalid,bready,bresp,
//! arvalid,arready,araddr,rvalid,rready,rdata,rresp}_{i,o}` (e.g. `s_axil_` on `neo_engine_regs`).
//!
//! Cycle-driven like [`crate::stream`]: per cycle the bench calls [`AxilManager::drive`] (before
//! `eval`), then [`AxilManager::sample`] (after `eval`, before `tick`). Operations are queued with
//! [`AxilManager::write`] / [`AxilManager::read`] and complete in order ([`AxilManager::pop`]).
//!
//! Ordering: consecutive operations of one kind are pipelined (the next AW/W or AR is offered
//! while earlier responses are outstanding, at most [`AxilManager::max_outstanding`]); a read
//! waits for every earlier write's B and a write for every earlier read's R, so the outcome of
//! a sequence is the one of executing it in order (AXI does not order reads against writes).
//!
//! Timing from the seed: each AW, W and AR is offered after a random delay (AW and W drawn
//! independently, so W may come first, AW first or both together), valid and payload are then
//! held until ready; while a channel is idle its payload is random. BREADY and RREADY are
//! random ([`AxilManager::ready_pct`]).

use crate::check::Checker;
use crate::dut::{Dut, PortIo};
use crate::rng::Rng;
use std::collections::VecDeque;

/// AXI response OKAY.
pub const RESP_OKAY: u8 = 0;

/// One operation on the control port.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AxilOp {
    /// Write `data` to byte address `addr`, bytes enabled by `strb`.
    Write {
        /// Byte address.
        addr: u32,
        /// Data word.
        data: u32,
        /// Byte enables (bit b: byte b).
        strb: u8,
    },
    /// Read the word at byte address `addr`.
    Read {
        /// Byte address.
        addr: u32,
    },
}

impl AxilOp {
    fn is_write(&self) -> bool {
        matches!(self, AxilOp::Write { .. })
    }
}

/// A finished operation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct AxilDone {
    /// The operation.
    pub op: AxilOp,
    /// BRESP or RRESP.
    pub resp: u8,
    /// RDATA (0 for a write).
    pub data: u32,
    /// Cycle its last request half (AW or W, or AR) was accepted.
    pub accepted: u64,
    /// Cycle of its response handshake (B or R).
    pub done: u64,
}

/// Port indices of one AXI4-Lite subordinate port.
#[derive(Clone, Copy, Debug)]
pub struct AxilPorts {
    awvalid: usize,
    awready: usize,
    awaddr: usize,
    wvalid: usize,
    wready: usize,
    wdata: usize,
    wstrb: usize,
    bvalid: usize,
    bready: usize,
    bresp: usize,
    arvalid: usize,
    arready: usize,
    araddr: usize,
    rvalid: usize,
    rready: usize,
    rdata: usize,
    rresp: usize,
}

impl AxilPorts {
    /// The ports `PREFIX<name>_i` / `PREFIX<name>_o` of `D` (the subordinate's view).
    pub fn bind<D: Dut>(prefix: &str) -> Self {
        Self::lookup(prefix, |n| Ok(D::port(n))).expect("D::port panics on a missing port")
    }

    /// The same ports of a model bound at run time; an error names a missing port.
    pub fn bind_io(d: &impl PortIo, prefix: &str) -> Result<Self, String> {
        Self::lookup(prefix, |n| d.io_port(n))
    }

    fn lookup(prefix: &str, find: impl Fn(&str) -> Result<usize, String>) -> Result<Self, String> {
        let p = |n: &str| find(&format!("{prefix}{n}"));
        Ok(AxilPorts {
            awvalid: p("awvalid_i")?,
            awready: p("awready_o")?,
            awaddr: p("awaddr_i")?,
            wvalid: p("wvalid_i")?,
            wready: p("wready_o")?,
            wdata: p("wdata_i")?,
            wstrb: p("wstrb_i")?,
            bvalid: p("bvalid_o")?,
            bready: p("bready_i")?,
            bresp: p("bresp_o")?,
            arvalid: p("arvalid_i")?,
            arready: p("arready_o")?,
            araddr: p("araddr_i")?,
            rvalid: p("rvalid_o")?,
            rready: p("rready_i")?,
            rdata: p("rdata_o")?,
            rresp: p("rresp_o")?,
        })
    }
}

/// Every signal of the port in one cycle (after `eval`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct AxilSignals {
    /// AWVALID, AWREADY.
    pub aw: (bool, bool),
    /// WVALID, WREADY.
    pub w: (bool, bool),
    /// BVALID, BREADY.
    pub b: (bool, bool),
    /// BRESP.
    pub bresp: u8,
    /// ARVALID, ARREADY.
    pub ar: (bool, bool),
    /// RVALID, RREADY.
    pub r: (bool, bool),
    /// RDATA.
    pub rdata: u32,
    /// RRESP.
    pub rresp: u8,
}

impl AxilSignals {
    /// Reads the port from `dut`.
    pub fn read<D: PortIo + ?Sized>(dut: &D, p: &AxilPorts) -> Self {
        let b = |i: usize| dut.io_get(i) != 0;
        AxilSignals {
            aw: (b(p.awvalid), b(p.awready)),
            w: (b(p.wvalid), b(p.wready)),
            b: (b(p.bvalid), b(p.bready)),
            bresp: dut.io_get(p.bresp) as u8,
            ar: (b(p.arvalid), b(p.arready)),
            r: (b(p.rvalid), b(p.rready)),
            rdata: dut.io_get(p.rdata) as u32,
            rresp: dut.io_get(p.rresp) as u8,
        }
    }
}

/// Checks the subordinate's side of the protocol, one cycle at a time: B and R stay valid with
/// a stable payload until taken, no B before both halves of a write were accepted, no R before
/// its AR.
#[derive(Clone, Debug, Default)]
pub struct AxilChecker {
    aw: u64,
    w: u64,
    ar: u64,
    b: u64,
    r: u64,
    prev: Option<AxilSignals>,
}

impl AxilChecker {
    /// A checker that has seen nothing.
    pub fn new() -> Self {
        Self::default()
    }

    /// Observes one cycle (`s` after `eval`; transfers happen at the coming edge).
    pub fn observe(&mut self, checker: &Checker, cycle: u64, s: &AxilSignals) {
        if let Some(p) = self.prev {
            if p.b.0 && !p.b.1 {
                checker.protocol(cycle, s.b.0, "BVALID dropped before BREADY");
                checker.protocol(cycle, s.bresp == p.bresp, "BRESP changed while BVALID and not BREADY");
            }
            if p.r.0 && !p.r.1 {
                checker.protocol(cycle, s.r.0, "RVALID dropped before RREADY");
                checker.protocol(
                    cycle,
                    s.rdata == p.rdata && s.rresp == p.rresp,
                    &format!(
                        "RDATA/RRESP changed while RVALID and not RREADY: {:#x} -> {:#x}",
                        p.rdata, s.rdata
                    ),
                );
            }
        }
        // A response may come at the earliest in the cycle after its request's edge.
        if s.b.0 {
            checker.protocol(cycle, self.b < self.aw.min(self.w), "BVALID without an accepted AW and W");
        }
        if s.r.0 {
            checker.protocol(cycle, self.r < self.ar, "RVALID without an accepted AR");
        }
        self.aw += (s.aw.0 && s.aw.1) as u64;
        self.w += (s.w.0 && s.w.1) as u64;
        self.ar += (s.ar.0 && s.ar.1) as u64;
        self.b += (s.b.0 && s.b.1) as u64;
        self.r += (s.r.0 && s.r.1) as u64;
        self.prev = Some(*s);
    }

    /// Writes and reads whose response has not come yet (by the handshakes seen).
    pub fn outstanding(&self) -> (u64, u64) {
        (self.aw.min(self.w) - self.b, self.ar - self.r)
    }
}

/// One channel's request being offered: the delay left before valid, and whether valid is up.
#[derive(Clone, Copy, Debug)]
struct Offer {
    delay: u32,
    valid: bool,
}

/// An operation in flight.
#[derive(Clone, Copy, Debug)]
struct InFlight {
    op: AxilOp,
    /// AW (or AR) still to be accepted.
    a: Option<Offer>,
    /// W still to be accepted (writes).
    w: Option<Offer>,
    accepted: u64,
}

/// The AXI4-Lite manager driver.
pub struct AxilManager {
    ports: AxilPorts,
    rng: Rng,
    queue: VecDeque<AxilOp>,
    flight: VecDeque<InFlight>,
    done: VecDeque<AxilDone>,
    bready: bool,
    rready: bool,
    checker: AxilChecker,
    /// Largest random delay (cycles) before offering a request.
    pub max_delay: u32,
    /// Probability (percent) that a request is offered at once (delay 0).
    pub eager_pct: u32,
    /// Probability (percent) of BREADY / RREADY being high in a cycle.
    pub ready_pct: u32,
    /// Operations in flight at most (requests offered and responses outstanding).
    pub max_outstanding: usize,
}

impl AxilManager {
    /// A manager on `D`'s AXI4-Lite subordinate port `prefix` (e.g. `s_axil_`), timed by `rng`.
    pub fn new<D: Dut>(prefix: &str, rng: Rng) -> Self {
        Self::with_ports(AxilPorts::bind::<D>(prefix), rng)
    }

    /// A manager on the port `prefix` of a model bound at run time.
    pub fn bind(d: &impl PortIo, prefix: &str, rng: Rng) -> Result<Self, String> {
        Ok(Self::with_ports(AxilPorts::bind_io(d, prefix)?, rng))
    }

    fn with_ports(ports: AxilPorts, rng: Rng) -> Self {
        AxilManager {
            ports,
            rng,
            queue: VecDeque::new(),
            flight: VecDeque::new(),
            done: VecDeque::new(),
            bready: false,
            rready: false,
            checker: AxilChecker::new(),
            max_delay: 3,
            eager_pct: 50,
            ready_pct: 70,
            max_outstanding: 4,
        }
    }

    /// Queues a write of `data` to `addr` with byte enables `strb`.
    pub fn write(&mut self, addr: u32, data: u32, strb: u8) {
        self.queue.push_back(AxilOp::Write { addr, data, strb });
    }

    /// Queues a read of `addr`.
    pub fn read(&mut self, addr: u32) {
        self.queue.push_back(AxilOp::Read { addr });
    }

    /// Queues `op`.
    pub fn push(&mut self, op: AxilOp) {
        self.queue.push_back(op);
    }

    /// The oldest finished operation not yet taken.
    pub fn pop(&mut self) -> Option<AxilDone> {
        self.done.pop_front()
    }

    /// True when nothing is queued or in flight (finished operations may wait in [`Self::pop`]).
    pub fn is_idle(&self) -> bool {
        self.queue.is_empty() && self.flight.is_empty()
    }

    fn delay(&mut self) -> u32 {
        if self.rng.percent(self.eager_pct) {
            0
        } else {
            self.rng.range(1, self.max_delay.max(1) as u64) as u32
        }
    }

    /// Starts queued operations that may go now, and sets every input of the port for this cycle
    /// (call before `eval`).
    pub fn drive<D: PortIo + ?Sized>(&mut self, dut: &mut D) {
        // Start the next operation: same kind as those in flight, one request phase per channel.
        while let Some(&op) = self.queue.front() {
            let same_kind = self.flight.iter().all(|f| f.op.is_write() == op.is_write());
            let phase_free = self.flight.iter().all(|f| f.a.is_none() && f.w.is_none());
            if !same_kind || !phase_free || self.flight.len() >= self.max_outstanding {
                break;
            }
            self.queue.pop_front();
            let a = Some(Offer { delay: self.delay(), valid: false });
            let w = if op.is_write() { Some(Offer { delay: self.delay(), valid: false }) } else { None };
            self.flight.push_back(InFlight { op, a, w, accepted: 0 });
        }
        // Raise valids whose delay ran out (a raised valid stays up until its handshake).
        for f in self.flight.iter_mut() {
            for o in [&mut f.a, &mut f.w].into_iter().flatten() {
                if !o.valid {
                    if o.delay == 0 {
                        o.valid = true;
                    } else {
                        o.delay -= 1;
                    }
                }
            }
        }
        let p = self.ports;
        let (mut aw, mut w, mut ar) = (None, None, None);
        if let Some(f) = self.flight.back() {
            match f.op {
                AxilOp::Write { addr, data, strb } => {
                    aw = f.a.filter(|o| o.valid).map(|_| addr);
                    w = f.w.filter(|o| o.valid).map(|_| (data, strb));
                }
                AxilOp::Read { addr } => ar = f.a.filter(|o| o.valid).map(|_| addr),
            }
        }
        let junk = self.rng.next_u64();
        dut.io_set(p.awvalid, aw.is_some() as u64);
        dut.io_set(p.awaddr, aw.unwrap_or(junk as u32) as u64);
        dut.io_set(p.wvalid, w.is_some() as u64);
        let (d, s) = w.unwrap_or(((junk >> 32) as u32, (junk >> 12) as u8));
        dut.io_set(p.wdata, d as u64);
        dut.io_set(p.wstrb, s as u64);
        dut.io_set(p.arvalid, ar.is_some() as u64);
        dut.io_set(p.araddr, ar.unwrap_or((junk >> 20) as u32) as u64);
        self.bready = self.rng.percent(self.ready_pct);
        self.rready = self.rng.percent(self.ready_pct);
        dut.io_set(p.bready, self.bready as u64);
        dut.io_set(p.rready, self.rready as u64);
    }

    /// Records this cycle's handshakes (call after `eval`, before `tick`); protocol violations
    /// panic through `checker`.
    pub fn sample<D: PortIo + ?Sized>(&mut self, dut: &D, checker: &Checker) {
        let cycle = dut.io_cycle();
        let s = AxilSignals::read(dut, &self.ports);
        self.checker.observe(checker, cycle, &s);
        if let Some(f) = self.flight.back_mut() {
            let a_fire = if f.op.is_write() { s.aw.0 && s.aw.1 } else { s.ar.0 && s.ar.1 };
            if a_fire {
                f.a = None;
                f.accepted = cycle;
            }
            if s.w.0 && s.w.1 {
                f.w = None;
                f.accepted = cycle;
            }
        }
        let resp = if s.b.0 && s.b.1 {
            Some((true, s.bresp, 0))
        } else if s.r.0 && s.r.1 {
            Some((false, s.rresp, s.rdata))
        } else {
            None
        };
        if let Some((write, resp, data)) = resp {
            let f = self.flight.pop_front();
            let ok = f.is_some_and(|f| f.op.is_write() == write && f.a.is_none() && f.w.is_none());
            checker.protocol(cycle, ok, "a response with no matching accepted request in flight");
            let f = f.expect("checked");
            self.done.push_back(AxilDone { op: f.op, resp, data, accepted: f.accepted, done: cycle });
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn idle() -> AxilSignals {
        AxilSignals::default()
    }

    #[test]
    fn a_write_and_a_read_pass() {
        let c = Checker::new("sub", 1);
        let mut k = AxilChecker::new();
        k.observe(&c, 0, &AxilSignals { aw: (true, true), w: (true, true), ..idle() });
        k.observe(&c, 1, &AxilSignals { b: (true, false), ..idle() });
        k.observe(&c, 2, &AxilSignals { b: (true, true), ar: (true, true), ..idle() });
        assert_eq!(k.outstanding(), (0, 1));
        k.observe(&c, 3, &AxilSignals { r: (true, true), rdata: 5, ..idle() });
        assert_eq!(k.outstanding(), (0, 0));
    }

    #[test]
    #[should_panic(expected = "BVALID dropped before BREADY")]
    fn a_dropped_bvalid_is_caught() {
        let c = Checker::new("sub", 1);
        let mut k = AxilChecker::new();
        k.observe(&c, 0, &AxilSignals { aw: (true, true), w: (true, true), ..idle() });
        k.observe(&c, 1, &AxilSignals { b: (true, false), ..idle() });
        k.observe(&c, 2, &idle());
    }

    #[test]
    #[should_panic(expected = "RDATA/RRESP changed")]
    fn rdata_changing_under_backpressure_is_caught() {
        let c = Checker::new("sub", 1);
        let mut k = AxilChecker::new();
        k.observe(&c, 0, &AxilSignals { ar: (true, true), ..idle() });
        k.observe(&c, 1, &AxilSignals { r: (true, false), rdata: 1, ..idle() });
        k.observe(&c, 2, &AxilSignals { r: (true, true), rdata: 2, ..idle() });
    }

    #[test]
    #[should_panic(expected = "BVALID without an accepted AW and W")]
    fn a_response_before_both_halves_is_caught() {
        let c = Checker::new("sub", 1);
        let mut k = AxilChecker::new();
        k.observe(&c, 0, &AxilSignals { aw: (true, true), w: (true, false), ..idle() });
        k.observe(&c, 1, &AxilSignals { b: (true, true), ..idle() });
    }
}
