//! The memory side of the engine: AXI4 bridges from the cores' memory ports and the port mux.
//!
//! - [`sort_bridge`]: `neo_axi_sort_bridge`, a `neo_sort_core` memory port as an AXI4 manager;
//! - [`raster_bridge`]: `neo_axi_raster_bridge`, a `neo_raster_core` memory port as an AXI4
//!   manager;
//! - [`mux`]: `neo_axi_mux #(PORTS)`, PORTS AXI4 managers onto one AXI4 port;
//! - [`rr_arb`]: `neo_axi_rr_arb #(PORTS)`, the mux's round-robin AR and AW request arbiter.
//!
//! Every manager drives the AXI4 subset of the engine contract (docs/rtl.md "AXI4 memory side"):
//! AR/AW `{valid, ready, id, addr, len, size, burst}`, R `{valid, ready, id, data, resp, last}`,
//! W `{valid, ready, data, strb, last}`, B `{valid, ready, id, resp}`; INCR bursts of 8-byte beats.

pub mod mux;
pub mod raster_bridge;
pub mod rr_arb;
pub mod sort_bridge;

use crate::emit::expr::{bits_for, lit, resize, slice};
use crate::emit::{if_, if_else, set, Module};
use neo_golden::engine::EngineConfig;

/// One AXI4 signal of the subset: name (`arvalid`), driven by the manager, width.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct AxiSignal {
    /// Channel letter(s) and field, e.g. `araddr`.
    pub name: &'static str,
    /// True when the manager drives it (an output of a manager, an input of a subordinate).
    pub from_manager: bool,
    /// Width in bits.
    pub width: u32,
}

/// The AXI4 subset's signals for `cfg` (ID `axi_id_bits`, address `axi_addr_bits`, data
/// `axi_data_bits`), channel by channel: AR, R, AW, W, B.
pub fn signals(cfg: &EngineConfig) -> Vec<AxiSignal> {
    let (i, a, d) = (cfg.axi_id_bits, cfg.axi_addr_bits, cfg.axi_data_bits);
    let s = |name, from_manager, width| AxiSignal { name, from_manager, width };
    vec![
        s("arvalid", true, 1),
        s("arready", false, 1),
        s("arid", true, i),
        s("araddr", true, a),
        s("arlen", true, 8),
        s("arsize", true, 3),
        s("arburst", true, 2),
        s("rvalid", false, 1),
        s("rready", true, 1),
        s("rid", false, i),
        s("rdata", false, d),
        s("rresp", false, 2),
        s("rlast", false, 1),
        s("awvalid", true, 1),
        s("awready", false, 1),
        s("awid", true, i),
        s("awaddr", true, a),
        s("awlen", true, 8),
        s("awsize", true, 3),
        s("awburst", true, 2),
        s("wvalid", true, 1),
        s("wready", false, 1),
        s("wdata", true, d),
        s("wstrb", true, d / 8),
        s("wlast", true, 1),
        s("bvalid", false, 1),
        s("bready", true, 1),
        s("bid", false, i),
        s("bresp", false, 2),
    ]
}

/// The port name of AXI signal `sig` with `prefix` (`m_axi_`, `s0_axi_`) on the manager side
/// (`manager`) or the subordinate side: `m_axi_araddr_o`, `s0_axi_araddr_i`.
pub fn port_name(prefix: &str, sig: &AxiSignal, manager: bool) -> String {
    let out = sig.from_manager == manager;
    format!("{prefix}{}_{}", sig.name, if out { "o" } else { "i" })
}

/// Declares one AXI4 interface's ports: the manager side (`manager`) or the subordinate side.
pub fn ports(m: &mut Module, cfg: &EngineConfig, prefix: &str, manager: bool) {
    for sig in signals(cfg) {
        let name = port_name(prefix, &sig, manager);
        if sig.from_manager == manager {
            m.output(name, sig.width);
        } else {
            m.input(name, sig.width);
        }
    }
}

/// Bits of an index into `n` items (0 for a single item).
pub fn index_bits(n: usize) -> u32 {
    if n <= 1 {
        0
    } else {
        bits_for(n as u64 - 1)
    }
}

/// AXI `size` of a beat of `axi_data_bits` (log2 of its bytes).
fn size_code(cfg: &EngineConfig) -> u64 {
    u64::from((cfg.axi_data_bits / 8).trailing_zeros())
}

/// `log2` of the bytes of a beat.
const BEAT_SHIFT: u32 = 3;

/// Width of a per-client transaction counter (`0..=axi_outstanding`).
fn count_bits(cfg: &EngineConfig) -> u32 {
    bits_for(cfg.axi_outstanding as u64)
}

/// The AR channel of a bridge: one pending request (`ar_v_q`, entry address `ar_addr_q`,
/// entries left `ar_len_q`, and with `feat` a feature flag `ar_feat_q`), issued as INCR bursts
/// of one entry per beat, cut at 4 KiB boundaries and at 256 beats (a feature word: one 4-beat
/// burst at `32 w`). Declares `ar_take` (input: the bridge takes a new request this cycle, with
/// `ar_new_addr`, `ar_new_len`, `ar_new_feat` wires the caller drives), `ar_fire`, `ar_done`
/// (the pending request's last burst issues), `rd_cnt_q` (bursts in flight) and drives the
/// `m_axi_ar*` ports. `lb` is the width of the request length.
fn read_issuer(m: &mut Module, cfg: &EngineConfig, lb: u32, feat: bool) {
    let (aw, ab, cb, o) = (cfg.addr_bits, cfg.axi_addr_bits, count_bits(cfg), cfg.axi_outstanding as u64);
    let cw = lb.max(10);
    m.blank();
    m.comment("AR: the pending request, issued as INCR bursts cut at 4 KiB boundaries and at 256 beats;");
    m.comment(format!("at most {o} bursts in flight (rd_cnt_q counts AR accepted, RLAST not yet received)."));
    m.reg("ar_v_q", 1).reg("ar_addr_q", aw).reg("ar_len_q", lb).reg("rd_cnt_q", cb);
    if feat {
        m.reg("ar_feat_q", 1);
    }
    m.wire_assign(
        "ar_off",
        9,
        if aw >= 9 { slice("ar_addr_q", 8, 0) } else { format!("{{{}, ar_addr_q}}", lit(9 - aw, 0)) },
    );
    m.comment("Entries up to the next 4 KiB boundary (512 entries a page), at most 256 beats.");
    m.wire_assign("ar_room", 10, format!("{} - {{{}, ar_off}}", lit(10, 512), lit(1, 0)));
    m.wire_assign("ar_cap", 10, format!("(ar_room > {v}) ? {v} : ar_room", v = lit(10, 256)));
    m.wire_assign("ar_len_x", cw, resize("ar_len_q", lb, cw));
    m.wire_assign("ar_cap_x", cw, resize("ar_cap", 10, cw));
    m.wire_assign("ar_chunk", cw, "(ar_len_x < ar_cap_x) ? ar_len_x : ar_cap_x");
    let last = "ar_chunk == ar_len_x";
    m.wire_assign("ar_last", 1, if feat { format!("ar_feat_q | ({last})") } else { last.to_string() });
    byte_addr(m, "ar_byte", "ar_addr_q", aw, BEAT_SHIFT, ab);
    if feat {
        byte_addr(m, "ar_fbyte", "ar_addr_q", aw, 5, ab);
    }
    m.assign("m_axi_arvalid_o", format!("ar_v_q & (rd_cnt_q != {})", lit(cb, o)));
    m.wire_assign("ar_fire", 1, "m_axi_arvalid_o & m_axi_arready_i");
    m.wire_assign("ar_done", 1, "ar_fire & ar_last");
    let tlen = format!("{} - {}", slice("ar_chunk", 7, 0), lit(8, 1));
    if feat {
        m.assign("m_axi_araddr_o", "ar_feat_q ? ar_fbyte : ar_byte");
        m.assign("m_axi_arlen_o", format!("ar_feat_q ? {} : ({tlen})", lit(8, 3)));
    } else {
        m.assign("m_axi_araddr_o", "ar_byte");
        m.assign("m_axi_arlen_o", tlen);
    }
    m.assign("m_axi_arid_o", lit(cfg.axi_id_bits, 0));
    m.assign("m_axi_arsize_o", lit(3, size_code(cfg)));
    m.assign("m_axi_arburst_o", lit(2, 1));
    m.wire_assign("r_fire", 1, "m_axi_rvalid_i & m_axi_rready_o");
    m.wire_assign("r_end", 1, "r_fire & m_axi_rlast_i");
    let mut take =
        vec![set("ar_v_q", lit(1, 1)), set("ar_addr_q", "ar_new_addr"), set("ar_len_q", "ar_new_len")];
    if feat {
        take.push(set("ar_feat_q", "ar_new_feat"));
    }
    m.seq(
        {
            let mut r = vec![
                set("ar_v_q", lit(1, 0)),
                set("ar_addr_q", lit(aw, 0)),
                set("ar_len_q", lit(lb, 0)),
                set("rd_cnt_q", lit(cb, 0)),
            ];
            if feat {
                r.push(set("ar_feat_q", lit(1, 0)));
            }
            r
        },
        vec![
            if_else(
                "ar_take",
                take,
                vec![if_else(
                    "ar_done",
                    vec![set("ar_v_q", lit(1, 0))],
                    vec![if_(
                        "ar_fire",
                        vec![
                            set("ar_addr_q", format!("ar_addr_q + {}", resize("ar_chunk", cw, aw))),
                            set("ar_len_q", format!("ar_len_q - {}", resize("ar_chunk", cw, lb))),
                        ],
                    )],
                )],
            ),
            if_else(
                "ar_fire & ~r_end",
                vec![set("rd_cnt_q", format!("rd_cnt_q + {}", lit(cb, 1)))],
                vec![if_("r_end & ~ar_fire", vec![set("rd_cnt_q", format!("rd_cnt_q - {}", lit(cb, 1)))])],
            ),
        ],
    );
}

/// Declares `wire [ab-1:0] name = src << shift` (`src` of `aw` bits, an element address, as a
/// byte address of `ab` bits): zero-extended, or its high bits dropped (tied to an `unused_`
/// wire) when the byte address is wider than `ab`.
fn byte_addr(m: &mut Module, name: &str, src: &str, aw: u32, shift: u32, ab: u32) {
    if aw + shift <= ab {
        let pad = ab - aw - shift;
        let v = if pad == 0 {
            format!("{{{src}, {}}}", lit(shift, 0))
        } else {
            format!("{{{}, {src}, {}}}", lit(pad, 0), lit(shift, 0))
        };
        m.wire_assign(name, ab, v);
    } else {
        let keep = ab - shift;
        m.wire_assign(name, ab, format!("{{{}, {}}}", slice(src, keep - 1, 0), lit(shift, 0)));
        m.wire_assign(format!("unused_{name}"), 1, format!("^{}", slice(src, aw - 1, keep)));
    }
}

/// The write-side counter `wr_cnt_q` (writes taken from the core, B not yet received; at most
/// `axi_outstanding`), incremented on `wr_take` (the caller's wire), decremented on B; `bready`
/// is always 1.
fn write_counter(m: &mut Module, cfg: &EngineConfig) {
    let cb = count_bits(cfg);
    m.blank();
    m.comment("B: always taken; wr_cnt_q counts writes taken from the core whose B has not arrived.");
    m.reg("wr_cnt_q", cb);
    m.assign("m_axi_bready_o", lit(1, 1));
    m.wire_assign("b_fire", 1, "m_axi_bvalid_i");
    m.wire_assign("wr_room", 1, format!("wr_cnt_q != {}", lit(cb, cfg.axi_outstanding as u64)));
    m.seq(
        vec![set("wr_cnt_q", lit(cb, 0))],
        vec![if_else(
            "wr_take & ~b_fire",
            vec![set("wr_cnt_q", format!("wr_cnt_q + {}", lit(cb, 1)))],
            vec![if_("b_fire & ~wr_take", vec![set("wr_cnt_q", format!("wr_cnt_q - {}", lit(cb, 1)))])],
        )],
    );
}

/// The moves of a bridge's two W slots (head `w_*_q`, second `w2_*_q`), for a head whose last
/// beat leaves on `leave`: `w_shift` (w2 moves to the head), `w_to_head` and `w_to_w2` (where a
/// write taken on `wr_take` goes).
fn w_slot_moves(m: &mut Module, leave: &str) {
    m.comment("After the head's last W beat leaves, w2 moves to the head; a taken write joins behind it.");
    m.wire_assign("w_shift", 1, format!("{leave} & w2_v_q"));
    m.wire_assign("w_to_head", 1, format!("wr_take & (~w_v_q | ({leave} & ~w2_v_q))"));
    m.wire_assign("w_to_w2", 1, "wr_take & ~w_to_head");
}

/// The constant AW fields (ID 0, full beats, INCR) and WSTRB all ones.
fn write_constants(m: &mut Module, cfg: &EngineConfig) {
    m.assign("m_axi_awid_o", lit(cfg.axi_id_bits, 0));
    m.assign("m_axi_awsize_o", lit(3, size_code(cfg)));
    m.assign("m_axi_awburst_o", lit(2, 1));
    let sb = cfg.axi_data_bits / 8;
    m.assign(
        "m_axi_wstrb_o",
        if sb >= 64 { format!("{{{sb}{{1'b1}}}}") } else { crate::emit::expr::hex(sb, (1u64 << sb) - 1) },
    );
}

/// Response fields a bridge does not use (IDs: every response is its own; RRESP/BRESP: errors
/// are not reported) tied into one `unused_*` wire.
fn unused_responses(m: &mut Module, extra: &[&str]) {
    let mut v = vec!["m_axi_rid_i", "m_axi_rresp_i", "m_axi_bid_i", "m_axi_bresp_i"];
    v.extend_from_slice(extra);
    m.comment("Response IDs and RESP fields are not used (one ID; errors are not reported).");
    m.wire_assign("unused_rsp", 1, format!("^{{{}}}", v.join(", ")));
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_mux_whose_client_index_does_not_fit_the_id_is_refused() {
        let cfg = EngineConfig { axi_id_bits: 1, ..EngineConfig::default() };
        let e = mux::check(&cfg, 3).unwrap_err().to_string();
        assert!(e.contains("neo_axi_mux #(.PORTS(3))") && e.contains("axi_id_bits is 1"), "{e}");
        assert!(mux::check(&cfg, 2).is_ok() && mux::check(&cfg, 1).is_ok());
        assert!(mux::check(&EngineConfig::default(), 0).is_err());
        // The engine's 8 slots per port need 3 ID bits.
        assert!(mux::module(&cfg).is_err());
        assert!(crate::units::try_generate(&cfg).is_err());
    }

    #[test]
    fn bridges_and_muxes_have_the_contract_ports() {
        let cfg = EngineConfig::default();
        let has = |m: &Module, p: &str, w: u32| m.ports.iter().any(|x| x.name == p && x.width == w);
        for m in [sort_bridge::module(&cfg), raster_bridge::module(&cfg)] {
            for (p, w) in
                [("m_axi_arvalid_o", 1), ("m_axi_araddr_o", 32), ("m_axi_arlen_o", 8), ("m_axi_rdata_i", 64)]
            {
                assert!(has(&m, p, w), "{}: {p}", m.name);
            }
            for (p, w) in [("m_axi_wstrb_o", 8), ("m_axi_bid_i", 4), ("idle_o", 1)] {
                assert!(has(&m, p, w), "{}: {p}", m.name);
            }
        }
        let mux = mux::module(&cfg).unwrap();
        assert_eq!(mux.name, "neo_axi_mux");
        // The client buses at the default PORTS (the engine's 8 slots per port), the manager port.
        assert!(
            has(&mux, "s_axi_rdata_o", 8 * 64)
                && has(&mux, "s_axi_awaddr_i", 8 * 32)
                && has(&mux, "s_axi_arvalid_i", 8)
                && has(&mux, "m_axi_bready_o", 1)
                && has(&mux, "m_axi_araddr_o", 32)
        );
        let v = mux.to_verilog();
        for l in [
            "  parameter integer PORTS = 8,\n",
            "  input  wire [PORTS*ADDR_BITS-1:0]     s_axi_araddr_i,\n",
            "  input  wire [PORTS*(DATA_BITS/8)-1:0] s_axi_wstrb_i,\n",
            "    for (c = 0; c < PORTS; c = c + 1) begin\n",
            "  assign s_axi_rdata_o = {PORTS{m_axi_rdata_i}};\n",
            // One arbiter module, twice; the AW one offers only with room in the W-order FIFO.
            "  neo_axi_rr_arb #(\n    .PORTS(PORTS),\n    .ID_BITS(ID_BITS),\n    .ADDR_BITS(ADDR_BITS)\n  ) u_ar_arb (\n",
            "  ) u_aw_arb (\n",
            "    .en_i(1'b1),\n",
            "    .en_i(wq_room),\n",
            "    .grant_o(aw_oh),\n",
            "    .addr_i(s_axi_awaddr_i),\n",
            "    .id_o(m_axi_arid_o),\n",
        ] {
            assert!(v.contains(l), "{l:?} missing in\n{v}");
        }
        assert_eq!(mux.instantiated(), vec![rr_arb::NAME.to_string()]);
        let arb = rr_arb::module(&cfg).to_verilog();
        for l in [
            "  parameter integer PORTS = 8,\n",
            "  localparam [PORTS-1:0] CLIENT0 = 1;\n",
            "  assign oh = lock_q ? lock_oh_q : pick;\n",
            "  assign valid_o = en_i & (|(oh & req_i));\n",
            // The downstream ID is the client index.
            "      sel_id = sel_id | ({ID_BITS{oh[c]}} & c[ID_BITS-1:0]);\n",
            "      sel_addr = sel_addr | ({ADDR_BITS{oh[c]}} & addr_i[c*ADDR_BITS +: ADDR_BITS]);\n",
        ] {
            assert!(arb.contains(l), "{l:?} missing in\n{arb}");
        }
    }
}
