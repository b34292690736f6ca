//! `neo_axi_sort_bridge`: a `neo_sort_core` memory port as an AXI4 manager (engine client
//! `1..=N`).
//!
//! - Reads: a core burst of `L` entries at entry address `a` becomes INCR bursts of one entry per
//!   8-byte beat at byte `8 a` (ARLEN `L - 1`), cut in two when it crosses a 4 KiB boundary; the
//!   R beats go to the core unbuffered (`rready = mem_rsp_ready_i`), entry in the low bits of
//!   RDATA. At most `axi_outstanding` bursts in flight.
//! - Writes: one entry is one single-beat AW + W at byte `8 a` (WSTRB all ones, data
//!   zero-extended); at most `axi_outstanding` writes without their B. W has two slots, so a
//!   port mux that forwards W a cycle after granting AW still takes one write per cycle.
//! - `idle_o`: nothing pending, no read or write in flight; pulses `rd_beat_o` (an entry
//!   delivered) and `wr_beat_o` (a write taken from the core).

use super::{
    byte_addr, ports, read_issuer, unused_responses, w_slot_moves, write_constants, write_counter, BEAT_SHIFT,
};
use crate::emit::expr::{lit, zext};
use crate::emit::{if_, if_else, set, Module};
use crate::units::sort_core::mem_len_bits;
use neo_golden::engine::EngineConfig;

/// Module name.
pub const NAME: &str = "neo_axi_sort_bridge";

/// The sort bridge for `cfg`.
///
/// # Panics
/// When the entry does not fit one AXI beat.
pub fn module(cfg: &EngineConfig) -> Module {
    let (eb, aw, ab, db) = (cfg.entry_bits(), cfg.addr_bits, cfg.axi_addr_bits, cfg.axi_data_bits);
    assert!(eb <= db, "an entry of {eb} bits does not fit an AXI beat of {db}");
    let lb = mem_len_bits(cfg);
    let mut m = Module::new(NAME);
    m.doc("Sort bridge: a neo_sort_core memory port (mem_*, the core's ports with _i/_o swapped) as an AXI4");
    m.doc("manager (m_axi_*, ID 0). Entry a at byte 8a, one entry per 8-byte beat; a read burst of L entries is");
    m.doc(
        "ARLEN L-1 (cut at 4 KiB), a write one single-beat AW + W. At most axi_outstanding reads and writes",
    );
    m.doc(format!("({}) each in flight. See docs/rtl.md \"AXI4 memory side\".", cfg.axi_outstanding));
    m.clock_reset();
    m.input_c("mem_req_valid_i", 1, "core: a read request (burst) is offered");
    m.output_c("mem_req_ready_o", 1, "the bridge takes the read request");
    m.input_c("mem_req_addr_i", aw, "entry address of the burst");
    m.input_c("mem_req_len_i", lb, "entries of the burst (1..burst)");
    m.output_c("mem_rsp_valid_o", 1, "a read response beat (one entry), in request order");
    m.input_c("mem_rsp_ready_i", 1, "the core takes the beat");
    m.output_c("mem_rsp_data_o", eb, "the entry read");
    m.input_c("mem_wr_valid_i", 1, "a write of one entry is offered");
    m.output_c("mem_wr_ready_o", 1, "the bridge takes the write");
    m.input_c("mem_wr_addr_i", aw, "entry address of the write");
    m.input_c("mem_wr_data_i", eb, "the entry to write");
    m.output_c("idle_o", 1, "no request pending, no read or write in flight");
    m.output_c("rd_beat_o", 1, "pulse: an entry delivered to the core");
    m.output_c("wr_beat_o", 1, "pulse: a write taken from the core");
    ports(&mut m, cfg, "m_axi_", true);

    m.wire("ar_take", 1).wire("ar_new_addr", aw).wire("ar_new_len", lb);
    read_issuer(&mut m, cfg, lb, false);
    m.assign("mem_req_ready_o", "~ar_v_q | ar_done");
    m.assign("ar_take", "mem_req_valid_i & mem_req_ready_o");
    m.assign("ar_new_addr", "mem_req_addr_i");
    m.assign("ar_new_len", "mem_req_len_i");

    m.blank();
    m.comment("R: straight to the core, the entry in the low bits.");
    m.assign("m_axi_rready_o", "mem_rsp_ready_i");
    m.assign("mem_rsp_valid_o", "m_axi_rvalid_i");
    m.assign("mem_rsp_data_o", format!("m_axi_rdata_i[{}:0]", eb - 1));
    m.assign("rd_beat_o", "r_fire");

    m.blank();
    m.comment("AW + W: one registered single-beat write per entry. W has a second slot (w2): a port mux");
    m.comment("forwards W in the cycle after it grants the AW, so with one W slot a write would be taken");
    m.comment("only every other cycle; with two the bridge takes one write per cycle.");
    m.wire("wr_take", 1);
    write_counter(&mut m, cfg);
    m.reg("aw_v_q", 1).reg("aw_addr_q", aw);
    m.reg("w_v_q", 1).reg("w_data_q", eb).reg("w2_v_q", 1).reg("w2_data_q", eb);
    m.wire_assign("aw_fire", 1, "m_axi_awvalid_o & m_axi_awready_i");
    m.wire_assign("w_fire", 1, "m_axi_wvalid_o & m_axi_wready_i");
    m.assign("mem_wr_ready_o", "(~aw_v_q | aw_fire) & (~w2_v_q | w_fire) & wr_room");
    m.assign("wr_take", "mem_wr_valid_i & mem_wr_ready_o");
    m.assign("wr_beat_o", "wr_take");
    w_slot_moves(&mut m, "w_fire");
    m.seq(
        vec![set("aw_v_q", lit(1, 0)), set("w_v_q", lit(1, 0)), set("w2_v_q", lit(1, 0))],
        vec![
            if_("aw_fire", vec![set("aw_v_q", lit(1, 0))]),
            if_("wr_take", vec![set("aw_v_q", lit(1, 1))]),
            if_("w_fire", vec![set("w_v_q", "w2_v_q"), set("w2_v_q", lit(1, 0))]),
            if_("w_to_head", vec![set("w_v_q", lit(1, 1))]),
            if_("w_to_w2", vec![set("w2_v_q", lit(1, 1))]),
        ],
    );
    m.seq_noreset(vec![
        if_("wr_take", vec![set("aw_addr_q", "mem_wr_addr_i")]),
        if_else(
            "w_shift",
            vec![set("w_data_q", "w2_data_q")],
            vec![if_("w_to_head", vec![set("w_data_q", "mem_wr_data_i")])],
        ),
        if_("w_to_w2", vec![set("w2_data_q", "mem_wr_data_i")]),
    ]);
    byte_addr(&mut m, "aw_byte", "aw_addr_q", aw, BEAT_SHIFT, ab);
    m.assign("m_axi_awvalid_o", "aw_v_q");
    m.assign("m_axi_awaddr_o", "aw_byte");
    m.assign("m_axi_awlen_o", lit(8, 0));
    m.assign("m_axi_wvalid_o", "w_v_q");
    m.assign("m_axi_wdata_o", zext("w_data_q", eb, db));
    m.assign("m_axi_wlast_o", lit(1, 1));
    write_constants(&mut m, cfg);

    m.blank();
    m.assign(
        "idle_o",
        format!("~ar_v_q & (rd_cnt_q == {c}) & (wr_cnt_q == {c})", c = lit(super::count_bits(cfg), 0)),
    );
    let mut extra = vec![];
    let hi = if eb < db { format!("m_axi_rdata_i[{}:{eb}]", db - 1) } else { String::new() };
    if eb < db {
        extra.push(hi.as_str());
    }
    unused_responses(&mut m, &extra);
    m
}
