//! AXI4 on the test-bench side: one port's signals as plain structs ([`ManagerSignals`],
//! [`SubordinateSignals`]), their binding to a Verilated model's ports ([`AxiBinding`]), a memory
//! that serves AXI4 ports from a golden [`neo_golden::engine::memory::Memory`] ([`AxiMemory`]) and
//! a protocol checker ([`AxiChecker`]).
//!
//! The subset is the engine contract's (docs/rtl.md "AXI4 memory side"): AR/AW `{id, addr, len,
//! size, burst}`, R `{id, data, resp, last}`, W `{data, strb, last}`, B `{id, resp}`, 64-bit data.
//!
//! Cycle protocol, for each port and clock cycle: drive the subordinate's current outputs
//! ([`AxiMemory::outputs`]) into the model, `eval`, read the manager's outputs, then call
//! [`AxiMemory::tick`] with them (it applies the handshakes of this clock edge and returns the
//! outputs for the next cycle) and [`AxiChecker::observe`] with both sides, then clock the model.

pub mod checker;
pub mod manager;
pub mod memory;

pub use checker::{AxiChecker, Violation};
pub use memory::{AxiMemory, AxiTiming};

use crate::dut::{Dut, PortIo};

/// An address request (AR or AW).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Addr {
    /// ID.
    pub id: u32,
    /// Byte address.
    pub addr: u64,
    /// Beats minus one.
    pub len: u8,
    /// log2 of the bytes per beat.
    pub size: u8,
    /// Burst type (1 = INCR).
    pub burst: u8,
}

impl Addr {
    /// Beats of the burst.
    pub fn beats(&self) -> u32 {
        u32::from(self.len) + 1
    }

    /// Byte address of beat `k` (INCR).
    pub fn beat_addr(&self, k: u32) -> u64 {
        self.addr + (u64::from(k) << self.size)
    }
}

/// A write data beat.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct WBeat {
    /// Data.
    pub data: u64,
    /// Byte strobes.
    pub strb: u8,
    /// Last beat of the burst.
    pub last: bool,
}

/// A read data beat.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RBeat {
    /// ID.
    pub id: u32,
    /// Data.
    pub data: u64,
    /// Response (0 OKAY).
    pub resp: u8,
    /// Last beat of the burst.
    pub last: bool,
}

/// A write response.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct BResp {
    /// ID.
    pub id: u32,
    /// Response (0 OKAY).
    pub resp: u8,
}

/// What a manager drives on one port in one cycle (`Some` = valid with that payload).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ManagerSignals {
    /// AR.
    pub ar: Option<Addr>,
    /// RREADY.
    pub rready: bool,
    /// AW.
    pub aw: Option<Addr>,
    /// W.
    pub w: Option<WBeat>,
    /// BREADY.
    pub bready: bool,
}

/// What a subordinate drives on one port in one cycle (`Some` = valid with that payload).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SubordinateSignals {
    /// ARREADY.
    pub arready: bool,
    /// AWREADY.
    pub awready: bool,
    /// WREADY.
    pub wready: bool,
    /// R.
    pub r: Option<RBeat>,
    /// B.
    pub b: Option<BResp>,
}

/// The port indices of one AXI4 interface of a Verilated model, by prefix (`m_axi_`,
/// `s0_axi_`), on the manager side (the model drives AR/AW/W) or the subordinate side.
#[derive(Clone, Debug)]
pub struct AxiBinding {
    idx: Vec<usize>,
}

/// The fields in binding order (each with its direction: true = driven by the manager).
const FIELDS: [(&str, bool); 29] = [
    ("arvalid", true),
    ("arready", false),
    ("arid", true),
    ("araddr", true),
    ("arlen", true),
    ("arsize", true),
    ("arburst", true),
    ("rvalid", false),
    ("rready", true),
    ("rid", false),
    ("rdata", false),
    ("rresp", false),
    ("rlast", false),
    ("awvalid", true),
    ("awready", false),
    ("awid", true),
    ("awaddr", true),
    ("awlen", true),
    ("awsize", true),
    ("awburst", true),
    ("wvalid", true),
    ("wready", false),
    ("wdata", true),
    ("wstrb", true),
    ("wlast", true),
    ("bvalid", false),
    ("bready", true),
    ("bid", false),
    ("bresp", false),
];

const AR: [&str; 6] = ["arvalid", "arid", "araddr", "arlen", "arsize", "arburst"];
const AW: [&str; 6] = ["awvalid", "awid", "awaddr", "awlen", "awsize", "awburst"];

/// Index of a field in [`FIELDS`].
fn f(name: &str) -> usize {
    FIELDS.iter().position(|(n, _)| *n == name).expect("AXI field")
}

impl AxiBinding {
    /// Binds the interface `prefix` of model `D`; `manager`: the model is the manager on it.
    ///
    /// # Panics
    /// When a port is missing.
    pub fn new<D: Dut>(prefix: &str, manager: bool) -> AxiBinding {
        Self::lookup(prefix, manager, |n| Ok(D::port(n))).expect("D::port panics on a missing port")
    }

    /// The same for a model bound at run time; an error names a missing port.
    pub fn bind(d: &impl PortIo, prefix: &str, manager: bool) -> Result<AxiBinding, String> {
        Self::lookup(prefix, manager, |n| d.io_port(n))
    }

    fn lookup(
        prefix: &str,
        manager: bool,
        find: impl Fn(&str) -> Result<usize, String>,
    ) -> Result<AxiBinding, String> {
        let idx = FIELDS
            .iter()
            .map(|(n, from_m)| {
                let suffix = if *from_m == manager { "o" } else { "i" };
                find(&format!("{prefix}{n}_{suffix}"))
            })
            .collect::<Result<_, _>>()?;
        Ok(AxiBinding { idx })
    }

    fn get<D: PortIo + ?Sized>(&self, d: &D, name: &str) -> u64 {
        d.io_get(self.idx[f(name)])
    }

    fn set<D: PortIo + ?Sized>(&self, d: &mut D, name: &str, v: u64) {
        d.io_set(self.idx[f(name)], v);
    }

    fn get_addr<D: PortIo + ?Sized>(&self, d: &D, ch: &[&str; 6]) -> Option<Addr> {
        (self.get(d, ch[0]) != 0).then(|| Addr {
            id: self.get(d, ch[1]) as u32,
            addr: self.get(d, ch[2]),
            len: self.get(d, ch[3]) as u8,
            size: self.get(d, ch[4]) as u8,
            burst: self.get(d, ch[5]) as u8,
        })
    }

    fn set_addr<D: PortIo + ?Sized>(&self, d: &mut D, ch: &[&str; 6], a: Option<Addr>) {
        let a2 = a.unwrap_or_default();
        self.set(d, ch[0], a.is_some() as u64);
        self.set(d, ch[1], u64::from(a2.id));
        self.set(d, ch[2], a2.addr);
        self.set(d, ch[3], u64::from(a2.len));
        self.set(d, ch[4], u64::from(a2.size));
        self.set(d, ch[5], u64::from(a2.burst));
    }

    /// Reads what the model drives as the manager.
    pub fn get_manager<D: PortIo + ?Sized>(&self, d: &D) -> ManagerSignals {
        ManagerSignals {
            ar: self.get_addr(d, &AR),
            rready: self.get(d, "rready") != 0,
            aw: self.get_addr(d, &AW),
            w: (self.get(d, "wvalid") != 0).then(|| WBeat {
                data: self.get(d, "wdata"),
                strb: self.get(d, "wstrb") as u8,
                last: self.get(d, "wlast") != 0,
            }),
            bready: self.get(d, "bready") != 0,
        }
    }

    /// Drives the model's manager-side inputs (it is the subordinate).
    pub fn set_manager<D: PortIo + ?Sized>(&self, d: &mut D, m: &ManagerSignals) {
        self.set_addr(d, &AR, m.ar);
        self.set_addr(d, &AW, m.aw);
        self.set(d, "rready", m.rready as u64);
        self.set(d, "bready", m.bready as u64);
        let w = m.w.unwrap_or_default();
        self.set(d, "wvalid", m.w.is_some() as u64);
        self.set(d, "wdata", w.data);
        self.set(d, "wstrb", u64::from(w.strb));
        self.set(d, "wlast", w.last as u64);
    }

    /// Reads what the model drives as the subordinate.
    pub fn get_subordinate<D: PortIo + ?Sized>(&self, d: &D) -> SubordinateSignals {
        SubordinateSignals {
            arready: self.get(d, "arready") != 0,
            awready: self.get(d, "awready") != 0,
            wready: self.get(d, "wready") != 0,
            r: (self.get(d, "rvalid") != 0).then(|| RBeat {
                id: self.get(d, "rid") as u32,
                data: self.get(d, "rdata"),
                resp: self.get(d, "rresp") as u8,
                last: self.get(d, "rlast") != 0,
            }),
            b: (self.get(d, "bvalid") != 0)
                .then(|| BResp { id: self.get(d, "bid") as u32, resp: self.get(d, "bresp") as u8 }),
        }
    }

    /// Drives the model's subordinate-side inputs (it is the manager).
    pub fn set_subordinate<D: PortIo + ?Sized>(&self, d: &mut D, s: &SubordinateSignals) {
        self.set(d, "arready", s.arready as u64);
        self.set(d, "awready", s.awready as u64);
        self.set(d, "wready", s.wready as u64);
        let r = s.r.unwrap_or_default();
        self.set(d, "rvalid", s.r.is_some() as u64);
        self.set(d, "rid", u64::from(r.id));
        self.set(d, "rdata", r.data);
        self.set(d, "rresp", u64::from(r.resp));
        self.set(d, "rlast", r.last as u64);
        let b = s.b.unwrap_or_default();
        self.set(d, "bvalid", s.b.is_some() as u64);
        self.set(d, "bid", u64::from(b.id));
        self.set(d, "bresp", u64::from(b.resp));
    }
}
