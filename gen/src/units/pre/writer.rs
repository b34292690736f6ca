//! The AXI4 write side the Preprocessing Engine's writers share (`neo_pre_lane`'s feature words,
//! `neo_pre_lists`' lines and lengths): one registered write at a time, its AW and its W beats
//! shifted out of `w_q` (W may run ahead of AW, as AXI4 allows), and a count of writes whose B
//! has not arrived.
//!
//! Declares `aw_v_q`, `aw_addr_q`, `w_left_q`, `w_q`, `wr_cnt_q`, the wires `wr_free` (a new
//! write may be taken this cycle: none registered, room for another B), `wr_idle` (nothing
//! registered, every B back) and `aw_fire`, `w_fire`, `b_fire`, and drives the port's AW, W and
//! B signals.

use crate::emit::expr::{bits_for, hex, lit};
use crate::emit::{if_, if_else, set, Module};
use neo_golden::engine::EngineConfig;

/// One writer's parameters.
pub struct Writes<'a> {
    /// The AXI4 port's prefix (`ma_axi_`).
    pub port: &'a str,
    /// One-bit expression: a write is taken this cycle (the caller includes `wr_free`).
    pub take: &'a str,
    /// Its byte address, `axi_addr_bits` wide.
    pub addr: String,
    /// Its data, beat 0 in the low bits, `width` bits.
    pub data: String,
    /// Width of `data`.
    pub width: u32,
    /// Its beats (an expression of [`beat_bits`]`(max_beats)` bits) and the most there can be.
    pub beats: String,
    /// The most beats of a write.
    pub max_beats: u32,
    /// AWLEN and WSTRB of the registered write (expressions over the caller's registers).
    pub awlen: String,
    /// WSTRB.
    pub strb: String,
    /// Writes without their B at most.
    pub outstanding: usize,
}

/// Width of `w_left_q` for writes of at most `max_beats` beats.
pub fn beat_bits(max_beats: u32) -> u32 {
    bits_for(u64::from(max_beats))
}

/// WSTRB with every byte of a beat of `cfg` enabled.
pub fn all_bytes(cfg: &EngineConfig) -> String {
    let sb = cfg.axi_data_bits / 8;
    hex(sb, (1u64 << sb) - 1)
}

/// Emits the write side of `w` (see the module docs).
pub fn writes(m: &mut Module, cfg: &EngineConfig, w: &Writes) {
    let (ab, db, p) = (cfg.axi_addr_bits, cfg.axi_data_bits, w.port);
    let bb = beat_bits(w.max_beats);
    let ob = bits_for(w.outstanding as u64);
    m.reg("aw_v_q", 1).reg("aw_addr_q", ab).reg("w_left_q", bb).reg("w_q", w.width).reg("wr_cnt_q", ob);
    m.wire_assign(
        "wr_free",
        1,
        format!("~aw_v_q & (w_left_q == {}) & (wr_cnt_q != {})", lit(bb, 0), lit(ob, w.outstanding as u64)),
    );
    m.wire_assign(
        "wr_idle",
        1,
        format!("~aw_v_q & (w_left_q == {}) & (wr_cnt_q == {})", lit(bb, 0), lit(ob, 0)),
    );
    m.wire_assign("aw_fire", 1, format!("{p}awvalid_o & {p}awready_i"));
    m.wire_assign("w_fire", 1, format!("{p}wvalid_o & {p}wready_i"));
    m.wire_assign("b_fire", 1, format!("{p}bvalid_i"));
    let take = w.take;
    m.seq(
        vec![
            set("aw_v_q", lit(1, 0)),
            set("aw_addr_q", lit(ab, 0)),
            set("w_left_q", lit(bb, 0)),
            set("wr_cnt_q", lit(ob, 0)),
        ],
        vec![
            if_else(
                take,
                vec![
                    set("aw_v_q", lit(1, 1)),
                    set("aw_addr_q", w.addr.clone()),
                    set("w_left_q", w.beats.clone()),
                ],
                vec![
                    if_("aw_fire", vec![set("aw_v_q", lit(1, 0))]),
                    if_("w_fire", vec![set("w_left_q", format!("w_left_q - {}", lit(bb, 1)))]),
                ],
            ),
            if_else(
                format!("{take} & ~b_fire"),
                vec![set("wr_cnt_q", format!("wr_cnt_q + {}", lit(ob, 1)))],
                vec![if_(
                    format!("b_fire & ~({take})"),
                    vec![set("wr_cnt_q", format!("wr_cnt_q - {}", lit(ob, 1)))],
                )],
            ),
        ],
    );
    m.seq_noreset(vec![if_else(
        take,
        vec![set("w_q", w.data.clone())],
        vec![if_("w_fire", vec![set("w_q", format!("w_q >> {db}"))])],
    )]);
    m.assign(format!("{p}awvalid_o"), "aw_v_q");
    m.assign(format!("{p}awaddr_o"), "aw_addr_q");
    m.assign(format!("{p}awlen_o"), w.awlen.clone());
    m.assign(format!("{p}awid_o"), lit(cfg.axi_id_bits, 0));
    m.assign(format!("{p}awsize_o"), lit(3, u64::from((db / 8).trailing_zeros())));
    m.assign(format!("{p}awburst_o"), lit(2, 1));
    m.comment("W may run ahead of its AW (AXI4 allows it).");
    m.assign(format!("{p}wvalid_o"), format!("w_left_q != {}", lit(bb, 0)));
    m.assign(format!("{p}wdata_o"), format!("w_q[{}:0]", db - 1));
    m.assign(format!("{p}wlast_o"), format!("w_left_q == {}", lit(bb, 1)));
    m.assign(format!("{p}wstrb_o"), w.strb.clone());
    m.assign(format!("{p}bready_o"), lit(1, 1));
    m.wire_assign(format!("unused_{p}b"), 1, format!("^{{{p}bid_i, {p}bresp_i}}"));
}
