//! `neo_axi_mux #(PORTS, ID_BITS, ADDR_BITS, DATA_BITS)`: `PORTS` AXI4 managers (the packed
//! `s_axi_*` buses, client `i`'s signals at `[i*W +: W]` of each; the engine's clients of one
//! memory port) onto one AXI4 port (`m_axi_*`).
//!
//! - AR: round-robin arbiter, an instance `u_ar_arb` of [`rr_arb`] (the client after the last
//!   granted one first); a request offered downstream and not yet accepted keeps its grant (AXI:
//!   valid held with a stable payload).
//! - AW: the same arbiter (`u_aw_arb`), its offer gated by the FIFO's room; each accepted AW
//!   pushes its client onto a W-order FIFO of [`W_FIFO`] entries, and the W channel forwards
//!   the head client's beats until WLAST, so the W beats downstream follow the AW order (AXI4
//!   has no WID). AW waits while the FIFO is full.
//! - IDs: the client's own ID is ignored (each client uses one ID); the downstream ID is the
//!   client index (`clog2(PORTS)` bits, zero-extended to `ID_BITS`). R and B are routed back by
//!   that index; responses to a client carry ID 0.
//! - No buffering on R, B: `rready`/`bready` downstream are the addressed client's.
//!
//! The granted client's fields (the W channel's here, the AR and AW ones in [`rr_arb`]) are an
//! AND-OR over the one-hot grant, written as a `for` loop over the clients in one `always @*`
//! block per channel ([`or_select`]). The defaults of `ID_BITS`, `ADDR_BITS` and
//! `DATA_BITS` are the configuration's; the default of `PORTS` is the engine's slots per port
//! ([`super::super::engine::Clients::slots`]), so the module synthesized on its own at its
//! defaults is the engine's (`neo gen --stats` multiplies it by the engine's ports).

use super::{index_bits, rr_arb, signals, AxiSignal};
use crate::emit::expr::{bits_for, lit};
use crate::emit::{for_, if_, if_else, set, Module};
use neo_golden::engine::{ConfigError, EngineConfig};

/// Module name.
pub const NAME: &str = "neo_axi_mux";

/// Entries of the W-order FIFO (AWs accepted whose W beats have not all passed): golden's
/// [`neo_golden::engine::MUX_W_FIFO_DEPTH`], which the engine-level cycle model reads too.
pub const W_FIFO: u32 = neo_golden::engine::MUX_W_FIFO_DEPTH;

/// The loop variable of the selections over the clients.
pub(super) const C: &str = "c";

/// The parameter expression of `sig`'s width on the manager side (`ID_BITS`, ...), or `None`
/// for the widths AXI4 fixes (LEN 8, SIZE 3, BURST 2, RESP 2, the one-bit signals).
pub(super) fn width_expr(sig: &AxiSignal) -> Option<&'static str> {
    match sig.name {
        "arid" | "rid" | "awid" | "bid" => Some("ID_BITS"),
        "araddr" | "awaddr" => Some("ADDR_BITS"),
        "rdata" | "wdata" => Some("DATA_BITS"),
        "wstrb" => Some("(DATA_BITS/8)"),
        _ => None,
    }
}

/// `sig`'s width as a Verilog expression: its parameter or its fixed width.
pub(super) fn width_of(sig: &AxiSignal) -> String {
    width_expr(sig).map_or_else(|| sig.width.to_string(), str::to_string)
}

/// The bus port of `sig` on the client side, `s_axi_araddr_i` (`PORTS` x the signal).
pub fn client_port(sig: &AxiSignal) -> String {
    super::port_name("s_axi_", sig, false)
}

/// Client `c`'s slice of the bus of `sig` (`s_axi_araddr_i[c*ADDR_BITS +: ADDR_BITS]`).
fn client_field(sig: &AxiSignal) -> String {
    client_slice(&client_port(sig), sig)
}

/// Client `C`'s part of `bus`, which holds every client's `sig` (`bus[C]` for a one-bit
/// signal, else `bus[C*W +: W]`).
pub(super) fn client_slice(bus: &str, sig: &AxiSignal) -> String {
    let w = width_of(sig);
    if sig.width == 1 && width_expr(sig).is_none() {
        format!("{bus}[{C}]")
    } else {
        format!("{bus}[{C}*{w} +: {w}]")
    }
}

/// Checks that `ports` clients fit `cfg`'s AXI IDs (the downstream ID is the client index).
///
/// # Errors
/// When the client index needs more than `axi_id_bits` bits.
pub fn check(cfg: &EngineConfig, ports: usize) -> Result<(), ConfigError> {
    let (xb, ib) = (index_bits(ports), cfg.axi_id_bits);
    if ports == 0 || xb > ib {
        return Err(ConfigError(format!(
            "{NAME} #(.PORTS({ports})): {ports} clients need {xb} ID bits, axi_id_bits is {ib}"
        )));
    }
    Ok(())
}

/// Declares the module's ports: the client buses (`PORTS` x each signal) and the manager port.
fn declare_ports(m: &mut Module, cfg: &EngineConfig, ports: usize) {
    let n = ports as u32;
    m.clock_reset();
    for sig in signals(cfg) {
        let name = client_port(&sig);
        if sig.from_manager {
            m.input(name.clone(), n * sig.width);
        } else {
            m.output(name.clone(), n * sig.width);
        }
        let w = if sig.width == 1 { "PORTS".to_string() } else { format!("PORTS*{}", width_of(&sig)) };
        m.width_param(&name, w);
    }
    for sig in signals(cfg) {
        let name = super::port_name("m_axi_", &sig, true);
        if sig.from_manager {
            m.output(name.clone(), sig.width);
        } else {
            m.input(name.clone(), sig.width);
        }
        if let Some(w) = width_expr(&sig) {
            m.width_param(&name, w);
        }
    }
}

/// `{W{oh[c]}} & x` (`oh[c] & x` for one bit).
fn gated(oh: &str, width: &str, x: &str) -> String {
    if width == "1" {
        format!("{oh}[{C}] & {x}")
    } else {
        format!("{{{width}{{{oh}[{C}]}}}} & {x}")
    }
}

/// One `always @*` block: the fields `(reg, width expression, width at the defaults, value of
/// client C)` of the client granted by one-hot `oh`, each an OR over the clients of
/// `{W{oh[c]}} & value`, declared as `reg`s.
pub(super) fn or_select(m: &mut Module, oh: &str, fields: &[(String, String, u32, String)]) {
    let mut init = Vec::new();
    let mut body = Vec::new();
    for (reg, w, width, value) in fields {
        m.reg(reg.clone(), *width);
        if w.parse::<u32>().is_err() {
            m.width_param(reg, w.clone());
        }
        let zero = if w.parse::<u32>().is_ok() { lit(*width, 0) } else { format!("{{{w}{{1'b0}}}}") };
        init.push(set(reg.clone(), zero));
        body.push(set(reg.clone(), format!("{reg} | ({})", gated(oh, w, value))));
    }
    init.push(for_(C, "PORTS", body));
    m.comb(init);
}

/// The request arbiter of channel `ch` (`ar` or `aw`): a [`rr_arb`] instance `u_{ch}_arb` between
/// the clients' `s_axi_{ch}*` and `m_axi_{ch}*`, its offer gated by `en` (`1'b1`: always), its
/// one-hot grant on wire `{ch}_oh`.
fn arbiter(m: &mut Module, ports: usize, ch: &str, en: &str) {
    m.blank();
    m.comment(format!(
        "{}: the clients' requests one at a time, round robin; the granted client's index is the ID.",
        ch.to_uppercase()
    ));
    let oh = format!("{ch}_oh");
    m.wire(oh.clone(), ports as u32).width_param(&oh, "PORTS");
    let pair = |p: &str, e: String| (p.to_string(), e);
    let mut conns = vec![
        pair("clk_i", "clk_i".into()),
        pair("rst_ni", "rst_ni".into()),
        pair("req_i", format!("s_axi_{ch}valid_i")),
        pair("ready_o", format!("s_axi_{ch}ready_o")),
    ];
    for f in rr_arb::FIELDS {
        conns.push(pair(&format!("{f}_i"), format!("s_axi_{ch}{f}_i")));
    }
    conns.push(pair("en_i", en.to_string()));
    conns.push(pair("valid_o", format!("m_axi_{ch}valid_o")));
    conns.push(pair("ready_i", format!("m_axi_{ch}ready_i")));
    conns.push(pair("grant_o", oh));
    conns.push(pair("id_o", format!("m_axi_{ch}id_o")));
    for f in rr_arb::FIELDS {
        conns.push(pair(&format!("{f}_o"), format!("m_axi_{ch}{f}_o")));
    }
    let params = ["PORTS", "ID_BITS", "ADDR_BITS"].iter().map(|p| (p.to_string(), p.to_string())).collect();
    m.instance_with(rr_arb::NAME, format!("u_{ch}_arb"), params, conns);
}

/// The W-order FIFO (`wq_*`: the one-hot grants of the accepted AWs, [`W_FIFO`] at most) and
/// `w_oh`, the client whose beats pass (the head's, until WLAST). Declares `wq_room`.
fn w_order(m: &mut Module, ports: usize) {
    let (n, fb) = (ports as u32, bits_for(u64::from(W_FIFO - 1)));
    m.blank();
    m.comment(format!(
        "W order: clients of the accepted AWs ({W_FIFO} at most), the head's beats pass until WLAST."
    ));
    m.mem("wq_mem", n, W_FIFO).width_param("wq_mem", "PORTS");
    m.reg("wq_wp_q", fb).reg("wq_rp_q", fb).reg("wq_cnt_q", fb + 1);
    m.wire_assign("wq_room", 1, format!("wq_cnt_q != {}", lit(fb + 1, u64::from(W_FIFO))));
    m.wire_assign("wq_any", 1, format!("wq_cnt_q != {}", lit(fb + 1, 0)));
    m.wire_assign("w_oh", n, "wq_any ? wq_mem[wq_rp_q] : {PORTS{1'b0}}").width_param("w_oh", "PORTS");
}

/// The W channel: the head client's beats, and the FIFO's updates (needs `aw_fire`, `aw_oh`).
fn w_channel(m: &mut Module, cfg: &EngineConfig) {
    let fb = bits_for(u64::from(W_FIFO - 1));
    m.blank();
    m.comment("W: the head client's beats.");
    m.assign("m_axi_wvalid_o", "|(w_oh & s_axi_wvalid_i)");
    let fields: Vec<_> = signals(cfg)
        .into_iter()
        .filter(|s| ["wdata", "wstrb", "wlast"].contains(&s.name))
        .map(|s| (format!("w_{}", &s.name[1..]), width_of(&s), s.width, client_field(&s)))
        .collect();
    or_select(m, "w_oh", &fields);
    for (reg, ..) in &fields {
        m.assign(format!("m_axi_w{}_o", &reg[2..]), reg.clone());
    }
    m.assign("s_axi_wready_o", "w_oh & {PORTS{m_axi_wready_i}}");
    m.wire_assign("w_done", 1, "m_axi_wvalid_o & m_axi_wready_i & m_axi_wlast_o");
    let one = lit(fb + 1, 1);
    m.seq(
        vec![set("wq_wp_q", lit(fb, 0)), set("wq_rp_q", lit(fb, 0)), set("wq_cnt_q", lit(fb + 1, 0))],
        vec![
            if_("aw_fire", vec![set("wq_wp_q", format!("wq_wp_q + {}", lit(fb, 1)))]),
            if_("w_done", vec![set("wq_rp_q", format!("wq_rp_q + {}", lit(fb, 1)))]),
            if_else(
                "aw_fire & ~w_done",
                vec![set("wq_cnt_q", format!("wq_cnt_q + {one}"))],
                vec![if_("w_done & ~aw_fire", vec![set("wq_cnt_q", format!("wq_cnt_q - {one}"))])],
            ),
        ],
    );
    m.seq_noreset(vec![if_("aw_fire", vec![set("wq_mem[wq_wp_q]", "aw_oh")])]);
}

/// R and B: each response goes to the client its ID's low `IDX_BITS` bits name, with ID 0.
fn responses(m: &mut Module, ports: usize) {
    let n = ports as u32;
    m.blank();
    m.comment("R and B: back to the client named by the ID's low IDX_BITS bits, with ID 0.");
    let mut body = Vec::new();
    for ch in ["r", "b"] {
        let sel = format!("{ch}_sel");
        m.reg(sel.clone(), n).width_param(&sel, "PORTS");
        body.push(set(format!("{sel}[{C}]"), format!("m_axi_{ch}id_i[IDX_BITS-1:0] == {C}[IDX_BITS-1:0]")));
    }
    m.comb(vec![for_(C, "PORTS", body)]);
    for (ch, fields) in [("r", &["data", "resp", "last"][..]), ("b", &["resp"][..])] {
        m.assign(format!("m_axi_{ch}ready_o"), format!("|({ch}_sel & s_axi_{ch}ready_i)"));
        m.assign(format!("s_axi_{ch}valid_o"), format!("{ch}_sel & {{PORTS{{m_axi_{ch}valid_i}}}}"));
        m.assign(format!("s_axi_{ch}id_o"), "{(PORTS*ID_BITS){1'b0}}");
        for f in fields {
            m.assign(format!("s_axi_{ch}{f}_o"), format!("{{PORTS{{m_axi_{ch}{f}_i}}}}"));
        }
    }
}

/// The mux for `cfg`, `PORTS` defaulting to the engine's slots per port.
///
/// # Errors
/// When the engine's client index does not fit `axi_id_bits`.
pub fn module(cfg: &EngineConfig) -> Result<Module, ConfigError> {
    let ports = super::super::engine::Clients::of(cfg).slots();
    check(cfg, ports)?;
    let mut m = Module::new(NAME);
    m.doc("AXI4 port mux: PORTS managers (the s_axi_* buses, client i's signals at [i*W +: W] of each) onto");
    m.doc("one port (m_axi_*). Round-robin AR and AW arbiters (neo_axi_rr_arb u_ar_arb, u_aw_arb); W beats follow");
    m.doc(format!(
        "the AW order (a {W_FIFO}-entry FIFO of granted clients, each until WLAST). Downstream ID = client index"
    ));
    m.doc("(IDX_BITS bits, zero-extended); client IDs are ignored, R/B go back by the index with ID 0.");
    m.doc("See docs/rtl.md \"AXI4 memory side\".");
    m.doc("PORTS: clients, 1 to 2^ID_BITS. ID_BITS, ADDR_BITS, DATA_BITS: AXI4 ID, address and data widths.");
    m.param("PORTS", ports as i64)
        .param("ID_BITS", i64::from(cfg.axi_id_bits))
        .param("ADDR_BITS", i64::from(cfg.axi_addr_bits))
        .param("DATA_BITS", i64::from(cfg.axi_data_bits));
    declare_ports(&mut m, cfg, ports);
    m.comment("Bits of a client index (the low bits of the downstream ID).");
    m.localparam("IDX_BITS", 0, "(PORTS > 1) ? $clog2(PORTS) : 1");
    m.comment("The loop variable of the selections over the clients.");
    m.integer(C);
    arbiter(&mut m, ports, "ar", "1'b1");
    w_order(&mut m, ports);
    arbiter(&mut m, ports, "aw", "wq_room");
    m.wire_assign("aw_fire", 1, "m_axi_awvalid_o & m_axi_awready_i");
    w_channel(&mut m, cfg);
    responses(&mut m, ports);
    m.blank();
    m.comment("The clients' IDs (each client uses one) and the response IDs above IDX_BITS are not used.");
    m.wire_assign("unused_ids", 1, "^{s_axi_arid_i, s_axi_awid_i, m_axi_rid_i, m_axi_bid_i}");
    m.comment("Nor is the AR grant (the R beats go back by their ID).");
    m.wire_assign("unused_ar_grant", 1, "^ar_oh");
    Ok(m)
}
