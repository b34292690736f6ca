//! `neo_pre_lists`: the Preprocessing Engine's incoming-list writer. The lanes' incoming tiles
//! (`hit_*`, one per cycle) become entries `{valid = 1, key, id}` of the tiles' incoming lists,
//! written a 64-byte line (8 entries) at a time, and at the end each tile's list length goes into
//! its descriptor.
//!
//! - **Layout** (golden `engine::memory`): tile `t`'s list holds up to `table_capacity` entries
//!   from byte `list_base_i + 8 t S`, `S` = [`EngineConfig::list_stride`] (the capacity rounded
//!   up to whole lines); a longer list keeps counting (its length goes
//!   to the descriptor, so the frame controller reports the overflow) but writes nothing more.
//!   The length is the high half of descriptor word 2 (byte `desc_base_i + 32 t + 20`), written
//!   with WSTRB on its 8-byte beat; the host writes the rest of the descriptor.
//! - **Phases** (`phase_q`): `start_i` clears the counters of tiles `0 .. tiles_i` (one a cycle);
//!   then hits are taken; `flush_i` (no more hits) walks the tiles again, writing each partial
//!   line (entries past the length read 0) and each length; `busy_o` falls when every write's B
//!   is back. `run_o` says hits are taken (and a `flush_i` would be).
//! - **Storage**: per tile a 32-bit counter (`u_cnt`) and the line being filled, one memory per
//!   entry slot (`g_slot[s].u_line`: entry `s` of each tile's line, slots 0 to 6);
//!   `pre_max_tiles` tiles. A hit for slot 7 sends the line (with the new entry) to the write
//!   queue `u_wq` at once.
//! - **Writes**: the queue's head is one AW and its beats (a line: 8 beats; a length: 1 beat);
//!   at most `pre_outstanding` writes without their B. Reads are idle.

use super::writer::{self, Writes};
use super::{fifo, ram};
use crate::emit::bundle::Bundle;
use crate::emit::expr::{lit, zext};
use crate::emit::{if_, set, Module};
use crate::units::axi;
use neo_golden::engine::memory::{DESCRIPTOR_BYTES, ENTRY_BYTES};
use neo_golden::engine::EngineConfig;

/// Module name.
pub const NAME: &str = "neo_pre_lists";

/// Entries of a line.
const LINE: u32 = 8;
/// Depth of the write queue.
const WQ_DEPTH: u32 = 4;
/// Width of a counter (a list's length).
const CNT_BITS: u32 = 32;

/// Phases of the writer (`phase_q`).
const IDLE: u64 = 0;
const CLEAR: u64 = 1;
const RUN: u64 = 2;
const FLUSH: u64 = 3;

/// A write-queue word: `{data (a line), addr, len_write}`.
fn wq_bundle(cfg: &EngineConfig) -> Bundle {
    let line = LINE * ENTRY_BYTES as u32 * 8;
    Bundle::packed("WQ", &[("len_write", 1), ("addr", cfg.axi_addr_bits), ("data", line)])
}

fn entry_bits(cfg: &EngineConfig) -> u32 {
    cfg.entry_bits()
}

/// The list writer for `cfg`.
pub fn module(cfg: &EngineConfig) -> Module {
    let (tb, ib, kb, ab) =
        (cfg.tile_bits, u32::from(cfg.id_bits), u32::from(cfg.key_bits), cfg.axi_addr_bits);
    let mut m = Module::new(NAME);
    m.doc("Incoming-list writer: hits -> list entries {valid, key, id} written a 64-byte line at a time at");
    m.doc(format!(
        "list_base_i + 8 (t {} + k); on flush, partial lines and each tile's length (descriptor word 2, high half).",
        cfg.list_stride()
    ));
    m.clock_reset();
    m.input_c("start_i", 1, "pulse: clear the counters of tiles 0 .. tiles_i, then take hits");
    m.input_c("flush_i", 1, "pulse: no more hits; write the partial lines and the lengths");
    m.output_c("busy_o", 1, "from start_i to the last write's B after flush_i");
    m.output_c("run_o", 1, "taking hits: a flush_i now is taken (not while clearing)");
    m.input_c("tiles_i", 32, "tiles of the frame (at most pre_max_tiles)");
    m.input_c("grid_x_i", tb, "tile columns");
    m.input_c("list_base_i", ab, "byte address of tile 0's list (64-byte aligned)");
    m.input_c("desc_base_i", ab, "byte address of tile 0's descriptor");
    m.input_c("hit_valid_i", 1, "an incoming (Gaussian, tile) is offered");
    m.output_c("hit_ready_o", 1, "it is taken");
    m.input_c("hit_tile_x_i", tb, "tile column");
    m.input_c("hit_tile_y_i", tb, "tile row");
    m.input_c("hit_id_i", ib, "Gaussian id");
    m.input_c("hit_key_i", kb, "depth key");
    axi::ports(&mut m, cfg, "m_axi_", true);
    phases(&mut m, cfg);
    storage(&mut m, cfg);
    pushes(&mut m, cfg);
    writer(&mut m, cfg);
    m
}

/// Bits of a tile index.
fn ta(cfg: &EngineConfig) -> u32 {
    ram::addr_bits(cfg.pre_max_tiles as u32)
}

/// The phase register and the tile walker `t_q`.
fn phases(m: &mut Module, cfg: &EngineConfig) {
    let t = ta(cfg);
    m.blank();
    m.comment("Phases: idle, clear (t_q over the tiles), run (hits), flush (t_q over the tiles again).");
    m.reg("phase_q", 2).reg("t_q", t).reg("fl_len_q", 1);
    for (n, v) in [("in_idle", IDLE), ("in_clear", CLEAR), ("in_run", RUN), ("in_flush", FLUSH)] {
        m.wire_assign(n, 1, format!("phase_q == {}", lit(2, v)));
    }
    m.wire_assign("no_tiles", 1, format!("tiles_i == {}", lit(32, 0)));
    m.wire_assign("t_last", 1, format!("{} == tiles_i - {}", zext("t_q", t, 32), lit(32, 1)));
    m.wire_assign("t_step", 1, "in_clear | (in_flush & fl_len_q & wq_push)");
    m.seq(
        vec![set("phase_q", lit(2, IDLE)), set("t_q", lit(t, 0)), set("fl_len_q", lit(1, 0))],
        vec![
            if_(
                "start_i & in_idle",
                vec![
                    set("phase_q", format!("no_tiles ? {} : {}", lit(2, RUN), lit(2, CLEAR))),
                    set("t_q", lit(t, 0)),
                ],
            ),
            if_("in_clear & t_last", vec![set("phase_q", lit(2, RUN))]),
            if_(
                "flush_i & in_run",
                vec![
                    set("phase_q", format!("no_tiles ? {} : {}", lit(2, IDLE), lit(2, FLUSH))),
                    set("t_q", lit(t, 0)),
                    set("fl_len_q", lit(1, 0)),
                ],
            ),
            if_("in_flush & ~fl_len_q & (~partial | wq_push)", vec![set("fl_len_q", lit(1, 1))]),
            if_("in_flush & fl_len_q & wq_push", vec![set("fl_len_q", lit(1, 0))]),
            if_("in_flush & fl_len_q & wq_push & t_last", vec![set("phase_q", lit(2, IDLE))]),
            if_("t_step & ~t_last", vec![set("t_q", format!("t_q + {}", lit(t, 1)))]),
        ],
    );
}

/// The counters and the line memories, read at the hit's tile (run) or at `t_q`.
fn storage(m: &mut Module, cfg: &EngineConfig) {
    let (t, tb, eb) = (ta(cfg), cfg.tile_bits, entry_bits(cfg));
    let mt = cfg.pre_max_tiles as u32;
    let cap = cfg.table_capacity as u64;
    m.blank();
    m.comment("Counters and line slots, at the hit's tile while running, at t_q otherwise.");
    m.wire_assign(
        "hit_t_wide",
        2 * tb,
        format!(
            "{} * {} + {}",
            zext("hit_tile_y_i", tb, 2 * tb),
            zext("grid_x_i", tb, 2 * tb),
            zext("hit_tile_x_i", tb, 2 * tb)
        ),
    );
    let hit_t = if 2 * tb >= t { format!("hit_t_wide[{}:0]", t - 1) } else { zext("hit_t_wide", 2 * tb, t) };
    m.wire_assign("hit_t", t, hit_t);
    if 2 * tb > t {
        m.wire_assign("unused_hit_t", 1, format!("^hit_t_wide[{}:{t}]", 2 * tb - 1));
    }
    m.wire_assign("hit_take", 1, "hit_valid_i & hit_ready_o");
    m.wire_assign("at_t", t, "in_run ? hit_t : t_q");
    m.wire("cnt", CNT_BITS);
    m.wire_assign("in_cap", 1, format!("cnt < {}", lit(CNT_BITS, cap)));
    m.wire_assign("slot", 3, "cnt[2:0]");
    m.wire_assign("entry", eb, "{1'b1, hit_key_i, hit_id_i}");
    m.item(ram::instance(
        CNT_BITS,
        mt,
        "u_cnt",
        vec![
            ("clk_i".into(), "clk_i".into()),
            ("we_i".into(), "in_clear | hit_take".into()),
            ("waddr_i".into(), "at_t".into()),
            ("wdata_i".into(), format!("in_clear ? {} : cnt + {}", lit(CNT_BITS, 0), lit(CNT_BITS, 1))),
            ("raddr_i".into(), "at_t".into()),
            ("rdata_o".into(), "cnt".into()),
        ],
    ));
    m.comment("Slots 0 to 6 of each tile's line; an entry for slot 7 completes the line and leaves at once.");
    m.wire("slots", (LINE - 1) * eb);
    let inst = ram::instance(
        eb,
        mt,
        "u_line",
        vec![
            ("clk_i".into(), "clk_i".into()),
            ("we_i".into(), "hit_take & in_cap & (slot == s[2:0])".into()),
            ("waddr_i".into(), "at_t".into()),
            ("wdata_i".into(), "entry".into()),
            ("raddr_i".into(), "at_t".into()),
            ("rdata_o".into(), format!("slots[{eb}*s +: {eb}]")),
        ],
    );
    m.gen_for("s", LINE - 1, "g_slot", vec![inst]);
}

/// What enters the write queue: a full line (run), a partial line and a length (flush).
fn pushes(m: &mut Module, cfg: &EngineConfig) {
    let (t, eb, ab) = (ta(cfg), entry_bits(cfg), cfg.axi_addr_bits);
    let (cap, stride) = (cfg.table_capacity as u64, cfg.list_stride() as u64);
    let wq = wq_bundle(cfg);
    let lw = wq.width_of("data");
    m.blank();
    m.comment("Write queue: {data, addr, len_write}.");
    wq.declare(m);
    m.wire_assign("n_kept", CNT_BITS, format!("in_cap ? cnt : {}", lit(CNT_BITS, cap)));
    m.wire_assign("partial", 1, "n_kept[2:0] != 3'd0");
    m.wire_assign("line_full", 1, "hit_take & in_cap & (slot == 3'd7)");
    // A line: each slot 64 bits (an entry zero-extended unless it fills the slot); the full one
    // with the new entry in slot 7, the partial one with the slots past the length zeroed.
    let slot = |e: String| if eb == 64 { e } else { format!("{}, {e}", lit(64 - eb, 0)) };
    let full: Vec<String> = (0..LINE)
        .rev()
        .map(|s| slot(if s == LINE - 1 { "entry".to_string() } else { format!("slots[{} +: {eb}]", s * eb) }))
        .collect();
    m.wire_assign("line_with_new", lw, format!("{{{}}}", full.join(", ")));
    let part: Vec<String> = (0..LINE)
        .rev()
        .map(|s| {
            if s == LINE - 1 {
                // A partial line has at most 7 entries.
                slot(lit(eb, 0))
            } else {
                slot(format!("(n_kept[2:0] > 3'd{s}) ? slots[{} +: {eb}] : {}", s * eb, lit(eb, 0)))
            }
        })
        .collect();
    m.wire_assign("line_partial", lw, format!("{{{}}}", part.join(", ")));
    let wide = 64;
    m.wire_assign(
        "line_first",
        CNT_BITS,
        format!("line_full ? (cnt - {}) : {{n_kept[{}:3], 3'd0}}", lit(CNT_BITS, 7), CNT_BITS - 1),
    );
    m.wire_assign(
        "line_off",
        wide,
        format!(
            "({} * {} + {}) << 3",
            zext("at_t", t, wide),
            lit(wide, stride),
            zext("line_first", CNT_BITS, wide)
        ),
    );
    m.wire_assign(
        "len_off",
        wide,
        format!("{} * {} + {}", zext("t_q", t, wide), lit(wide, DESCRIPTOR_BYTES), lit(wide, 16)),
    );
    m.wire_assign("line_addr", ab, format!("list_base_i + line_off[{}:0]", ab - 1));
    m.wire_assign("len_addr", ab, format!("desc_base_i + len_off[{}:0]", ab - 1));
    m.wire_assign("unused_off", 1, format!("^{{line_off[{}:{ab}], len_off[{}:{ab}]}}", wide - 1, wide - 1));
    m.wire_assign("len_data", lw, format!("{{{}, cnt, {}}}", lit(lw - 64, 0), lit(32, 0)));
    m.wire("wq_ready", 1).wire("wq_valid", 1).wire("wq_data", wq.width()).wire("wq_pop", 1);
    m.wire_assign("flush_line", 1, "in_flush & ~fl_len_q & partial");
    m.wire_assign("flush_len", 1, "in_flush & fl_len_q");
    m.wire_assign("wq_push_valid", 1, "line_full | flush_line | flush_len");
    m.wire_assign("wq_push", 1, "wq_push_valid & wq_ready");
    m.assign("hit_ready_o", "in_run & wq_ready");
    m.wire_assign(
        "wq_in",
        wq.width(),
        "flush_len ? {len_data, len_addr, 1'b1} : {line_full ? line_with_new : line_partial, line_addr, 1'b0}",
    );
    m.item(fifo::instance(
        wq.width(),
        WQ_DEPTH,
        "u_wq",
        vec![
            ("clk_i".into(), "clk_i".into()),
            ("rst_ni".into(), "rst_ni".into()),
            ("push_valid_i".into(), "wq_push_valid".into()),
            ("push_ready_o".into(), "wq_ready".into()),
            ("push_data_i".into(), "wq_in".into()),
            ("pop_valid_o".into(), "wq_valid".into()),
            ("pop_ready_i".into(), "wq_pop".into()),
            ("pop_data_o".into(), "wq_data".into()),
        ],
    ));
}

/// The AXI4 writes of the queue's head; reads idle; `busy_o`.
fn writer(m: &mut Module, cfg: &EngineConfig) {
    let db = cfg.axi_data_bits;
    let wq = wq_bundle(cfg);
    let lw = wq.width_of("data");
    let beats = lw / db;
    let sb = db / 8;
    m.blank();
    m.comment(format!("Writes: the head as AW + {beats} beats (a line) or 1 beat (a length, high 4 bytes); at most {} without B.", cfg.pre_outstanding));
    m.reg("aw_len_q", 1);
    m.assign("wq_pop", "wq_valid & wr_free");
    m.wire_assign("head_len", 1, wq.get("wq_data", "len_write"));
    m.seq(vec![set("aw_len_q", lit(1, 0))], vec![if_("wq_pop", vec![set("aw_len_q", "head_len")])]);
    let all = writer::all_bytes(cfg);
    let high = crate::emit::expr::hex(sb, ((1u64 << sb) - 1) & !0xf);
    let bb = writer::beat_bits(beats);
    let w = Writes {
        port: "m_axi_",
        take: "wq_pop",
        addr: wq.get("wq_data", "addr"),
        data: wq.get("wq_data", "data"),
        width: lw,
        beats: format!("head_len ? {} : {}", lit(bb, 1), lit(bb, u64::from(beats))),
        max_beats: beats,
        awlen: format!("aw_len_q ? {} : {}", lit(8, 0), lit(8, u64::from(beats - 1))),
        strb: format!("aw_len_q ? {high} : {all}"),
        outstanding: cfg.pre_outstanding,
    };
    writer::writes(m, cfg, &w);
    for s in axi::signals(cfg).iter().filter(|s| s.from_manager && s.name.starts_with("ar")) {
        m.assign(axi::port_name("m_axi_", s, true), lit(s.width, 0));
    }
    m.assign("m_axi_rready_o", lit(1, 1));
    m.wire_assign(
        "unused_rsp",
        1,
        "^{m_axi_arready_i, m_axi_rvalid_i, m_axi_rid_i, m_axi_rdata_i, m_axi_rresp_i, m_axi_rlast_i}",
    );
    m.assign("busy_o", "~in_idle | wq_valid | ~wr_idle");
    m.assign("run_o", "in_run");
}
