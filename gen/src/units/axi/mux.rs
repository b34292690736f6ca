//! `neo_axi_mux_p{P}`: P AXI4 managers (`s{i}_axi_*`, the engine's clients of one memory port)
//! onto one AXI4 port (`m_axi_*`).
//!
//! - AR: round-robin arbiter (the client after the last granted one first); a request offered
//!   downstream and not yet accepted keeps its grant (AXI: valid held with a stable payload).
//! - AW: the same arbiter; each accepted AW pushes its client onto a W-order FIFO of
//!   [`W_FIFO`] entries, and the W channel forwards the head client's beats until WLAST, so the
//!   W beats downstream follow the AW order (AXI4 has no WID). AW waits while the FIFO is full.
//! - IDs: the client's own ID is ignored (each client uses one ID); the downstream ID is the
//!   client index (`clog2(P)` bits, zero-extended to `axi_id_bits`). R and B are routed back by
//!   that index; responses to a client carry ID 0.
//! - No buffering on R, B: `rready`/`bready` downstream are the addressed client's.

use super::{index_bits, ports, signals};
use crate::emit::expr::{bits_for, lit, slice, zext};
use crate::emit::{if_, if_else, set, Module};
use neo_golden::engine::{ConfigError, EngineConfig};

/// The client count of the cosimulated mux (`tb/tests/axi.rs`), generated in every
/// configuration beside the ones the engine needs.
pub const COSIM_P: usize = 3;

/// Entries of the W-order FIFO (AWs accepted whose W beats have not all passed).
pub const W_FIFO: u32 = 4;

/// Module name of the mux of `p` clients.
pub fn name(p: usize) -> String {
    format!("neo_axi_mux_p{p}")
}

/// `(oh[0] ? a0 : 0) | (oh[1] ? a1 : 0) | ...` for a one-hot `oh` over `n` signals of `width`.
fn or_mux(oh: &str, n: usize, width: u32, sig: impl Fn(usize) -> String) -> String {
    (0..n)
        .map(|i| {
            if width == 1 {
                format!("({oh}[{i}] & {})", sig(i))
            } else {
                format!("({{{width}{{{oh}[{i}]}}}} & {})", sig(i))
            }
        })
        .collect::<Vec<_>>()
        .join(" | ")
}

/// `{x{n-1}, ..., x0}`.
fn concat(n: usize, sig: impl Fn(usize) -> String) -> String {
    format!("{{{}}}", (0..n).rev().map(sig).collect::<Vec<_>>().join(", "))
}

/// The index of the set bit of one-hot `oh` (`n` bits) as `xb` bits (bit `b` = OR of the lanes
/// whose index has bit `b`).
fn oh_index(oh: &str, n: usize, xb: u32) -> String {
    let bits: Vec<String> = (0..xb)
        .rev()
        .map(|b| {
            let lanes: Vec<String> =
                (0..n).filter(|i| (i >> b) & 1 == 1).map(|i| format!("{oh}[{i}]")).collect();
            if lanes.is_empty() {
                lit(1, 0)
            } else {
                lanes.join(" | ")
            }
        })
        .map(|e| format!("({e})"))
        .collect();
    format!("{{{}}}", bits.join(", "))
}

/// A round-robin arbiter for channel `ch` (`ar` or `aw`) over the clients' `{ch}valid`, gated by
/// `en` (none: always enabled): declares `{ch}_oh` (the one-hot grant), `{ch}_fire`, drives `m_axi_{ch}*` from the
/// granted client and the clients' `{ch}ready`.
fn arbiter(m: &mut Module, cfg: &EngineConfig, p: usize, ch: &str, en: Option<&str>) {
    let gate = en.map_or(String::new(), |e| format!("{e} & "));
    let n = p as u32;
    let xb = index_bits(p);
    m.blank();
    m.comment(format!(
        "{} arbiter: round robin from the client after the last grant; a grant offered downstream and not taken is held.",
        ch.to_uppercase()
    ));
    m.reg(format!("{ch}_lock_q"), 1).reg(format!("{ch}_lock_oh_q"), n).reg(format!("{ch}_mask_q"), n);
    // One bit per client: declared with a range even for one client, so `oh[0]` stays legal.
    for v in ["lock_oh_q", "mask_q", "req", "hi", "src", "pick", "oh"] {
        m.vector(format!("{ch}_{v}"));
    }
    m.wire_assign(format!("{ch}_req"), n, concat(p, |i| format!("s{i}_axi_{ch}valid_i")));
    m.wire_assign(format!("{ch}_hi"), n, format!("{ch}_req & {ch}_mask_q"));
    m.wire_assign(format!("{ch}_src"), n, format!("(|{ch}_hi) ? {ch}_hi : {ch}_req"));
    m.wire_assign(format!("{ch}_pick"), n, format!("{ch}_src & (~{ch}_src + {})", lit(n, 1)));
    m.wire_assign(format!("{ch}_oh"), n, format!("{ch}_lock_q ? {ch}_lock_oh_q : {ch}_pick"));
    m.assign(format!("m_axi_{ch}valid_o"), format!("{gate}(|({ch}_oh & {ch}_req))"));
    m.wire_assign(format!("{ch}_fire"), 1, format!("m_axi_{ch}valid_o & m_axi_{ch}ready_i"));
    for f in ["addr", "len", "size", "burst"] {
        let w = signals(cfg).iter().find(|s| s.name == format!("{ch}{f}")).expect("AXI field").width;
        m.assign(
            format!("m_axi_{ch}{f}_o"),
            or_mux(&format!("{ch}_oh"), p, w, |i| format!("s{i}_axi_{ch}{f}_i")),
        );
    }
    let id = if xb == 0 {
        lit(cfg.axi_id_bits, 0)
    } else {
        zext(&oh_index(&format!("{ch}_oh"), p, xb), xb, cfg.axi_id_bits)
    };
    m.assign(format!("m_axi_{ch}id_o"), id);
    for i in 0..p {
        m.assign(format!("s{i}_axi_{ch}ready_o"), format!("{gate}{ch}_oh[{i}] & m_axi_{ch}ready_i"));
    }
    m.seq(
        vec![
            set(format!("{ch}_lock_q"), lit(1, 0)),
            set(format!("{ch}_lock_oh_q"), lit(n, 0)),
            set(format!("{ch}_mask_q"), lit(n, 0)),
        ],
        vec![if_else(
            format!("{ch}_fire"),
            vec![
                set(format!("{ch}_lock_q"), lit(1, 0)),
                set(format!("{ch}_mask_q"), format!("~({ch}_oh | ({ch}_oh - {}))", lit(n, 1))),
            ],
            vec![if_(
                format!("m_axi_{ch}valid_o"),
                vec![
                    set(format!("{ch}_lock_q"), lit(1, 1)),
                    set(format!("{ch}_lock_oh_q"), format!("{ch}_oh")),
                ],
            )],
        )],
    );
}

/// The mux of `p` clients for `cfg`.
///
/// # Errors
/// When the client index does not fit `axi_id_bits`.
pub fn module(cfg: &EngineConfig, p: usize) -> Result<Module, ConfigError> {
    let n = p as u32;
    let xb = index_bits(p);
    let ib = cfg.axi_id_bits;
    if xb > ib {
        return Err(ConfigError(format!("{}: {p} clients need {xb} ID bits, axi_id_bits is {ib}", name(p))));
    }
    let (db, fb) = (cfg.axi_data_bits, bits_for(u64::from(W_FIFO - 1)));
    let mut m = Module::new(name(p));
    m.doc(format!(
        "AXI4 port mux: {p} managers (s0_axi_* .. s{}_axi_*) onto one port (m_axi_*). Round-robin AR and AW",
        p - 1
    ));
    m.doc(format!(
        "arbiters; W beats follow the AW order (a {W_FIFO}-entry FIFO of granted clients, each until WLAST)."
    ));
    m.doc(format!(
        "Downstream ID = client index ({xb} bits, zero-extended); client IDs are ignored, R/B go back by the"
    ));
    m.doc("index with ID 0. See docs/rtl.md \"AXI4 memory side\".");
    m.clock_reset();
    for i in 0..p {
        ports(&mut m, cfg, &format!("s{i}_axi_"), false);
    }
    ports(&mut m, cfg, "m_axi_", true);

    arbiter(&mut m, cfg, p, "ar", None);

    m.blank();
    m.comment(format!(
        "W order: clients of the accepted AWs ({W_FIFO} at most), the head's beats pass until WLAST."
    ));
    m.mem("wq_mem", n, W_FIFO).reg("wq_wp_q", fb).reg("wq_rp_q", fb).reg("wq_cnt_q", fb + 1);
    m.wire_assign("wq_room", 1, format!("wq_cnt_q != {}", lit(fb + 1, u64::from(W_FIFO))));
    m.wire_assign("wq_any", 1, format!("wq_cnt_q != {}", lit(fb + 1, 0)));
    m.vector("w_oh").vector("w_req");
    m.wire_assign("w_oh", n, format!("wq_any ? wq_mem[wq_rp_q] : {}", lit(n, 0)));
    arbiter(&mut m, cfg, p, "aw", Some("wq_room"));
    m.wire_assign("w_req", n, concat(p, |i| format!("s{i}_axi_wvalid_i")));
    m.assign("m_axi_wvalid_o", "|(w_oh & w_req)");
    m.assign("m_axi_wdata_o", or_mux("w_oh", p, db, |i| format!("s{i}_axi_wdata_i")));
    m.assign("m_axi_wstrb_o", or_mux("w_oh", p, db / 8, |i| format!("s{i}_axi_wstrb_i")));
    m.assign("m_axi_wlast_o", or_mux("w_oh", p, 1, |i| format!("s{i}_axi_wlast_i")));
    for i in 0..p {
        m.assign(format!("s{i}_axi_wready_o"), format!("w_oh[{i}] & m_axi_wready_i"));
    }
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

    m.blank();
    m.comment("R and B: back to the client named by the ID's low bits, with ID 0.");
    for (ch, fields) in [("r", &["data", "resp", "last"][..]), ("b", &["resp"][..])] {
        let sel = format!("{ch}_sel");
        m.vector(sel.clone());
        if xb == 0 {
            m.wire_assign(sel.clone(), n, lit(1, 1));
        } else {
            let idx = format!("{ch}_idx");
            m.wire_assign(idx.clone(), xb, slice(&format!("m_axi_{ch}id_i"), xb - 1, 0));
            m.wire_assign(sel.clone(), n, concat(p, |i| format!("({idx} == {})", lit(xb, i as u64))));
        }
        m.assign(
            format!("m_axi_{ch}ready_o"),
            format!("|({sel} & {})", concat(p, |i| format!("s{i}_axi_{ch}ready_i"))),
        );
        for i in 0..p {
            m.assign(format!("s{i}_axi_{ch}valid_o"), format!("m_axi_{ch}valid_i & {sel}[{i}]"));
            m.assign(format!("s{i}_axi_{ch}id_o"), lit(ib, 0));
            for f in fields {
                m.assign(format!("s{i}_axi_{ch}{f}_o"), format!("m_axi_{ch}{f}_i"));
            }
        }
    }
    m.blank();
    m.comment("The clients' IDs (each client uses one) and the ID bits above the client index are not used.");
    let mut unused: Vec<String> =
        (0..p).flat_map(|i| [format!("s{i}_axi_arid_i"), format!("s{i}_axi_awid_i")]).collect();
    if xb < ib {
        unused.push(slice("m_axi_rid_i", ib - 1, xb));
        unused.push(slice("m_axi_bid_i", ib - 1, xb));
    }
    m.wire_assign("unused_ids", 1, format!("^{{{}}}", unused.join(", ")));
    Ok(m)
}
