//! AXI4 on the test-bench side: one port's signals as plain structs ([`ManagerSignals`],
//! [`SubordinateSignals`]), their binding to a Verilated model's ports ([`AxiBinding`]), a memory
//! that serves AXI4 ports from a golden [`neo_golden::engine::memory::Memory`] ([`AxiMemory`]), a
//! protocol checker per port ([`AxiChecker`]) and a memory-ordering checker over all ports of one
//! manager ([`HazardChecker`]: RAW, WAR and WAW between transactions in flight at once); the port
//! mux at a chosen client count as a model ([`mux`]).
//!
//! The subset is the engine contract's (docs/rtl.md "AXI4 memory side"): AR/AW `{id, addr, len,
//! size, burst}`, R `{id, data, resp, last}`, W `{data, strb, last}`, B `{id, resp}`, 64-bit data.
//!
//! Cycle protocol, for each port and clock cycle: drive the subordinate's current outputs
//! ([`AxiMemory::outputs`]) into the model, `eval`, read the manager's outputs, then call
//! [`AxiMemory::tick`] with them (it applies the handshakes of this clock edge and returns the
//! outputs for the next cycle) and [`AxiChecker::observe`] with both sides, then clock the model.

pub mod checker;
pub mod hazard;
pub mod manager;
pub mod memory;
pub mod mux;

pub use checker::{AxiChecker, Violation};
pub use hazard::{Hazard, HazardChecker, HazardKind};
pub use memory::{AddrRecord, AxiMemory, AxiTiming};

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
///
/// The indices are resolved once, when the interface is bound, and kept in [`FIELDS`] order, so
/// the per-cycle accessors index an array by a field constant and do no string work.
#[derive(Clone, Debug)]
pub struct AxiBinding {
    idx: [usize; FIELD_COUNT],
}

/// Number of signals of one interface.
const FIELD_COUNT: usize = 29;

/// The fields in binding order (each with its direction: true = driven by the manager); the
/// constants below are positions in this table.
const FIELDS: [(&str, bool); FIELD_COUNT] = [
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

/// Position of field `name` in [`FIELDS`] (evaluated at compile time; an unknown name does not
/// compile).
const fn field(name: &str) -> usize {
    let mut i = 0;
    while i < FIELD_COUNT {
        if bytes_eq(FIELDS[i].0.as_bytes(), name.as_bytes()) {
            return i;
        }
        i += 1;
    }
    panic!("not an AXI field")
}

const fn bytes_eq(a: &[u8], b: &[u8]) -> bool {
    if a.len() != b.len() {
        return false;
    }
    let mut i = 0;
    while i < a.len() {
        if a[i] != b[i] {
            return false;
        }
        i += 1;
    }
    true
}

const ARVALID: usize = field("arvalid");
const ARREADY: usize = field("arready");
const RVALID: usize = field("rvalid");
const RREADY: usize = field("rready");
const RID: usize = field("rid");
const RDATA: usize = field("rdata");
const RRESP: usize = field("rresp");
const RLAST: usize = field("rlast");
const AWVALID: usize = field("awvalid");
const AWREADY: usize = field("awready");
const WVALID: usize = field("wvalid");
const WREADY: usize = field("wready");
const WDATA: usize = field("wdata");
const WSTRB: usize = field("wstrb");
const WLAST: usize = field("wlast");
const BVALID: usize = field("bvalid");
const BREADY: usize = field("bready");
const BID: usize = field("bid");
const BRESP: usize = field("bresp");

/// An address channel's VALID, ID, ADDR, LEN, SIZE and BURST fields.
const AR: [usize; 6] =
    [ARVALID, field("arid"), field("araddr"), field("arlen"), field("arsize"), field("arburst")];
const AW: [usize; 6] =
    [AWVALID, field("awid"), field("awaddr"), field("awlen"), field("awsize"), field("awburst")];

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
        let mut idx = [0; FIELD_COUNT];
        for (i, (n, from_m)) in idx.iter_mut().zip(FIELDS) {
            let suffix = if from_m == manager { "o" } else { "i" };
            *i = find(&format!("{prefix}{n}_{suffix}"))?;
        }
        Ok(AxiBinding { idx })
    }

    #[inline]
    fn get<D: PortIo + ?Sized>(&self, d: &D, field: usize) -> u64 {
        d.io_get(self.idx[field])
    }

    #[inline]
    fn set<D: PortIo + ?Sized>(&self, d: &mut D, field: usize, v: u64) {
        d.io_set(self.idx[field], v);
    }

    /// The address channel `ch` ([`AR`] or [`AW`]).
    fn get_addr<D: PortIo + ?Sized>(&self, d: &D, ch: &[usize; 6]) -> Option<Addr> {
        (self.get(d, ch[0]) != 0).then(|| Addr {
            id: self.get(d, ch[1]) as u32,
            addr: self.get(d, ch[2]),
            len: self.get(d, ch[3]) as u8,
            size: self.get(d, ch[4]) as u8,
            burst: self.get(d, ch[5]) as u8,
        })
    }

    fn set_addr<D: PortIo + ?Sized>(&self, d: &mut D, ch: &[usize; 6], a: Option<Addr>) {
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
            rready: self.get(d, RREADY) != 0,
            aw: self.get_addr(d, &AW),
            w: (self.get(d, WVALID) != 0).then(|| WBeat {
                data: self.get(d, WDATA),
                strb: self.get(d, WSTRB) as u8,
                last: self.get(d, WLAST) != 0,
            }),
            bready: self.get(d, BREADY) != 0,
        }
    }

    /// Drives the model's manager-side inputs (it is the subordinate).
    pub fn set_manager<D: PortIo + ?Sized>(&self, d: &mut D, m: &ManagerSignals) {
        self.set_addr(d, &AR, m.ar);
        self.set_addr(d, &AW, m.aw);
        self.set(d, RREADY, m.rready as u64);
        self.set(d, BREADY, m.bready as u64);
        let w = m.w.unwrap_or_default();
        self.set(d, WVALID, m.w.is_some() as u64);
        self.set(d, WDATA, w.data);
        self.set(d, WSTRB, u64::from(w.strb));
        self.set(d, WLAST, w.last as u64);
    }

    /// Reads what the model drives as the subordinate.
    pub fn get_subordinate<D: PortIo + ?Sized>(&self, d: &D) -> SubordinateSignals {
        SubordinateSignals {
            arready: self.get(d, ARREADY) != 0,
            awready: self.get(d, AWREADY) != 0,
            wready: self.get(d, WREADY) != 0,
            r: (self.get(d, RVALID) != 0).then(|| RBeat {
                id: self.get(d, RID) as u32,
                data: self.get(d, RDATA),
                resp: self.get(d, RRESP) as u8,
                last: self.get(d, RLAST) != 0,
            }),
            b: (self.get(d, BVALID) != 0)
                .then(|| BResp { id: self.get(d, BID) as u32, resp: self.get(d, BRESP) as u8 }),
        }
    }

    /// Drives the model's subordinate-side inputs (it is the manager).
    pub fn set_subordinate<D: PortIo + ?Sized>(&self, d: &mut D, s: &SubordinateSignals) {
        self.set(d, ARREADY, s.arready as u64);
        self.set(d, AWREADY, s.awready as u64);
        self.set(d, WREADY, s.wready as u64);
        let r = s.r.unwrap_or_default();
        self.set(d, RVALID, s.r.is_some() as u64);
        self.set(d, RID, u64::from(r.id));
        self.set(d, RDATA, r.data);
        self.set(d, RRESP, u64::from(r.resp));
        self.set(d, RLAST, r.last as u64);
        let b = s.b.unwrap_or_default();
        self.set(d, BVALID, s.b.is_some() as u64);
        self.set(d, BID, u64::from(b.id));
        self.set(d, BRESP, u64::from(b.resp));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn field_constants_name_their_fields() {
        let named = [
            (ARVALID, "arvalid"),
            (ARREADY, "arready"),
            (RVALID, "rvalid"),
            (RREADY, "rready"),
            (RID, "rid"),
            (RDATA, "rdata"),
            (RRESP, "rresp"),
            (RLAST, "rlast"),
            (AWVALID, "awvalid"),
            (AWREADY, "awready"),
            (WVALID, "wvalid"),
            (WREADY, "wready"),
            (WDATA, "wdata"),
            (WSTRB, "wstrb"),
            (WLAST, "wlast"),
            (BVALID, "bvalid"),
            (BREADY, "bready"),
            (BID, "bid"),
            (BRESP, "bresp"),
        ];
        for (i, n) in named {
            assert_eq!(FIELDS[i].0, n);
        }
        for (ch, pre) in [(AR, "ar"), (AW, "aw")] {
            for (k, f) in ["valid", "id", "addr", "len", "size", "burst"].iter().enumerate() {
                assert_eq!(FIELDS[ch[k]].0, format!("{pre}{f}"));
            }
        }
    }

    #[test]
    fn binding_resolves_every_port_with_its_direction() {
        let names: Vec<String> =
            FIELDS.iter().flat_map(|(n, _)| [format!("m_axi_{n}_o"), format!("m_axi_{n}_i")]).collect();
        let b = AxiBinding::lookup("m_axi_", true, |n| {
            names.iter().position(|x| x == n).ok_or_else(|| format!("no {n}"))
        })
        .expect("every port exists");
        assert_eq!(names[b.idx[ARVALID]], "m_axi_arvalid_o");
        assert_eq!(names[b.idx[RDATA]], "m_axi_rdata_i");
        assert_eq!(names[b.idx[AW[2]]], "m_axi_awaddr_o");
        let missing = AxiBinding::lookup("m_axi_", true, |n| {
            if n.contains("bresp") {
                Err(format!("no {n}"))
            } else {
                Ok(0)
            }
        });
        assert_eq!(missing.unwrap_err(), "no m_axi_bresp_i");
    }
}
