//! `neo_axi_rr_arb #(PORTS, ID_BITS, ADDR_BITS)`: the request arbiter of one AXI4 address
//! channel (AR or AW) of the port mux ([`super::mux`], instances `u_ar_arb` and `u_aw_arb`).
//!
//! - Round robin: among the requesting clients (`req_i`), the first one after the client of the
//!   last accepted request; with none of them after it, the lowest requesting client.
//! - A request offered downstream (`valid_o`) and not yet accepted (`ready_i` low) keeps its
//!   grant: AXI wants the valid held with a stable payload.
//! - `en_i` gates the offer: the AW channel's is the mux's W-order FIFO having room (the AR
//!   channel's is `1'b1`). A request not offered is not locked.
//! - The granted client's `{addr, len, size, burst}` go downstream with its index as the ID
//!   (zero-extended to `ID_BITS`); `grant_o` is the one-hot grant.
//!
//! The defaults of the parameters are the port mux's.

use super::mux;
use crate::emit::expr::lit;
use crate::emit::{if_, if_else, set, Module};
use neo_golden::engine::EngineConfig;

/// Module name.
pub const NAME: &str = "neo_axi_rr_arb";

/// The address-channel fields the arbiter forwards from the granted client (after the ID):
/// each an input `FIELD_i` (`PORTS` x the field) and an output `FIELD_o`.
pub const FIELDS: [&str; 4] = ["addr", "len", "size", "burst"];

/// The AR signal of `field` (the AW one has the same width).
fn signal(cfg: &EngineConfig, field: &str) -> super::AxiSignal {
    let name = format!("ar{field}");
    *super::signals(cfg).iter().find(|s| s.name == name).expect("an AXI4 address-channel field")
}

/// Declares the ports.
fn declare_ports(m: &mut Module, cfg: &EngineConfig, ports: u32) {
    m.clock_reset();
    m.input_c("req_i", ports, "the clients' AxVALID").width_param("req_i", "PORTS");
    m.output_c("ready_o", ports, "the clients' AxREADY: the granted client's, when taken")
        .width_param("ready_o", "PORTS");
    for f in FIELDS {
        let (s, name) = (signal(cfg, f), format!("{f}_i"));
        m.input_c(name.clone(), ports * s.width, "client c's at [c*W +: W]");
        m.width_param(&name, format!("PORTS*{}", mux::width_of(&s)));
    }
    m.input_c("en_i", 1, "the request may be offered (AW: the W-order FIFO has room)");
    m.output_c("valid_o", 1, "AxVALID downstream");
    m.input_c("ready_i", 1, "AxREADY downstream");
    m.output_c("grant_o", ports, "one-hot grant (held while the offered request waits)")
        .width_param("grant_o", "PORTS");
    m.output_c("id_o", cfg.axi_id_bits, "the granted client's index, zero-extended")
        .width_param("id_o", "ID_BITS");
    for f in FIELDS {
        let (s, name) = (signal(cfg, f), format!("{f}_o"));
        m.output_c(name.clone(), s.width, "the granted client's");
        if let Some(w) = mux::width_expr(&s) {
            m.width_param(&name, w);
        }
    }
}

/// The round robin and the held grant: declares `oh` (the one-hot grant) and drives `valid_o`,
/// `ready_o`, `grant_o`.
fn round_robin(m: &mut Module, ports: u32) {
    m.blank();
    m.comment("Round robin: the first requesting client above the last accepted one (mask_q), else the");
    m.comment(
        "lowest requesting client; an offered request not yet taken keeps its grant (lock_q, lock_oh_q).",
    );
    for r in ["lock_oh_q", "mask_q"] {
        m.reg(r, ports).width_param(r, "PORTS");
    }
    m.reg("lock_q", 1);
    for (w, rhs) in [
        ("hi", "req_i & mask_q"),
        ("src", "(|hi) ? hi : req_i"),
        ("pick", "src & (~src + CLIENT0)"),
        ("oh", "lock_q ? lock_oh_q : pick"),
    ] {
        m.wire_assign(w, ports, rhs).width_param(w, "PORTS");
    }
    m.assign("grant_o", "oh");
    m.assign("valid_o", "en_i & (|(oh & req_i))");
    m.wire_assign("fire", 1, "valid_o & ready_i");
    m.assign("ready_o", "oh & {PORTS{en_i & ready_i}}");
    m.seq(
        vec![set("lock_q", lit(1, 0)), set("lock_oh_q", "{PORTS{1'b0}}"), set("mask_q", "{PORTS{1'b0}}")],
        vec![if_else(
            "fire",
            vec![set("lock_q", lit(1, 0)), set("mask_q", "~(oh | (oh - CLIENT0))")],
            vec![if_("valid_o", vec![set("lock_q", lit(1, 1)), set("lock_oh_q", "oh")])],
        )],
    );
}

/// The granted client's request (an AND-OR over the one-hot grant): `id_o` is its index.
fn request(m: &mut Module, cfg: &EngineConfig) {
    m.blank();
    m.comment("The granted client's request; its index is the downstream ID.");
    let mut fields = vec![(
        "sel_id".to_string(),
        "ID_BITS".to_string(),
        cfg.axi_id_bits,
        format!("{}[ID_BITS-1:0]", mux::C),
    )];
    for f in FIELDS {
        let s = signal(cfg, f);
        let value = mux::client_slice(&format!("{f}_i"), &s);
        fields.push((format!("sel_{f}"), mux::width_of(&s), s.width, value));
    }
    mux::or_select(m, "oh", &fields);
    m.assign("id_o", "sel_id");
    for f in FIELDS {
        m.assign(format!("{f}_o"), format!("sel_{f}"));
    }
}

/// The arbiter for `cfg`, `PORTS` defaulting to the engine's slots per port (the mux's).
pub fn module(cfg: &EngineConfig) -> Module {
    let ports = super::super::engine::Clients::of(cfg).slots();
    let mut m = Module::new(NAME);
    m.doc("AXI4 address-channel arbiter of neo_axi_mux (AR and AW): round robin over the PORTS clients' requests,");
    m.doc("from the client after the last accepted one; an offered request keeps its grant until taken.");
    m.doc("en_i gates the offer (AW: W-order FIFO room). The granted client's fields go out, its index as the ID.");
    m.doc("PORTS: clients, 1 to 2^ID_BITS. ID_BITS, ADDR_BITS: AXI4 ID and address widths.");
    m.param("PORTS", ports as i64)
        .param("ID_BITS", i64::from(cfg.axi_id_bits))
        .param("ADDR_BITS", i64::from(cfg.axi_addr_bits));
    declare_ports(&mut m, cfg, ports as u32);
    m.comment("The grant of client 0 (the round robin's +1 and -1).");
    m.localparam("CLIENT0", ports as u32, "1").width_param("CLIENT0", "PORTS");
    m.comment("The loop variable of the selection over the clients.");
    m.integer(mux::C);
    round_robin(&mut m, ports as u32);
    request(&mut m, cfg);
    m
}
