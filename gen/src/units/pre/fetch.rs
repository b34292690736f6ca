//! `neo_pre_fetch`: a Preprocessing Engine fetch unit. Each command asks for `cmd_count_i`
//! records of `cmd_words_i` 32-bit words from the byte address `cmd_base_i` (4-byte aligned;
//! records back to back, as the baked geometry and SH arrays are); the unit reads them over one
//! AXI4 manager port and hands them out one record per handshake, in command order, with the
//! record's index in its command. A lane streams its geometry with one command and gathers the
//! SH record of each visible Gaussian with one command each.
//!
//! # Commands
//! The issue side takes a command once the previous one's bursts are all issued, and queues its
//! `{skip, words, count}` for the assembly (`u_cmdq`, [`CMD_QUEUE`] commands), so the reads of
//! several commands are in flight at once. A command of 0 records is taken and dropped.
//!
//! # Read window
//! The unit keeps up to [`EngineConfig::pre_read_lines`] 64-byte lines in flight: its beat
//! buffer (`u_buf`, a `neo_pre_ram`) holds `pre_window_beats` beats, and a burst is issued
//! only when the buffer has room for it net of the beats already requested (`space_q`), so
//! `rready` is always 1. At most [`EngineConfig::pre_outstanding`] bursts are in flight; full
//! bursts are `pre_burst_beats` beats (the window over `pre_outstanding`, so a stream's bursts
//! fill the window), aligned to their own size (so none crosses 4 KiB); a command's first and
//! last may be shorter.
//!
//! # Record assembly
//! The head beat's `W = axi_data_bits / 32` words enter the record register `rec_q` at its fill
//! level `fill_q` (slot `j` of generate block `g_slot[j]` takes the beat word whose position is
//! `j`); the words past the record's end start the next record. A beat that completes a record
//! moves it to the output register in the same cycle, so the unit takes one beat per cycle as
//! long as its output is taken (and one cycle per command to load it). Words of a command's first
//! beat before its base, and of its last beat after its last record, are dropped. `cmd_words_i`
//! must be at least `W` (a beat completes at most one record) and at most [`max_record_words`];
//! slots at and above it read 0.

use crate::emit::expr::{bits_for, lit, resize, zext};
use crate::emit::{if_, if_else, set, Item, Module};
use crate::units::axi;
use neo_golden::engine::EngineConfig;
use neo_golden::hwpre::bake::{geometry_bytes, sh_bytes, ShPrecision};

/// Module name.
pub const NAME: &str = "neo_pre_fetch";

/// Width of `cmd_count_i` and `rec_index_o`.
pub const COUNT_BITS: u32 = 32;

/// Commands queued between the issue side and the assembly.
pub const CMD_QUEUE: u32 = 64;

/// Words of the longest record a fetch unit assembles: the larger of the geometry record and the
/// degree-3 f32 SH record.
pub fn max_record_words() -> u32 {
    geometry_bytes().max(sh_bytes(3, ShPrecision::F32)).div_ceil(4)
}

/// Widths of the unit.
struct Dims {
    /// Byte-address bits, data bits, words per beat and `log2` of a beat's bytes.
    ab: u32,
    db: u32,
    w: u32,
    beat_shift: u32,
    /// Record slots and the width of a word count up to them.
    maxw: u32,
    wb: u32,
    /// Beat-buffer depth and pointer bits; full-burst beats and their `log2`.
    depth: u32,
    pb: u32,
    burst: u32,
    burst_shift: u32,
    /// Width of a beat count of a whole stream, and of a beat index.
    lb: u32,
    bi: u32,
    /// Bursts-in-flight counter bits.
    cb: u32,
}

impl Dims {
    fn new(cfg: &EngineConfig) -> Dims {
        let maxw = max_record_words();
        let w = cfg.axi_data_bits / 32;
        let depth = cfg.pre_window_beats() as u32;
        let burst = cfg.pre_burst_beats() as u32;
        let beat_shift = (cfg.axi_data_bits / 8).trailing_zeros();
        Dims {
            ab: cfg.axi_addr_bits,
            db: cfg.axi_data_bits,
            w,
            beat_shift,
            maxw,
            wb: bits_for(u64::from(maxw)),
            depth,
            pb: bits_for(u64::from(depth) - 1),
            burst,
            burst_shift: burst.trailing_zeros(),
            lb: COUNT_BITS + bits_for(u64::from(maxw)) + 1,
            bi: cfg.axi_addr_bits - beat_shift,
            cb: bits_for(cfg.pre_outstanding as u64),
        }
    }

    /// Width of the buffer-space counter (`0..=depth`).
    fn sb(&self) -> u32 {
        bits_for(u64::from(self.depth))
    }
}

/// The fetch unit for `cfg`.
pub fn module(cfg: &EngineConfig) -> Module {
    let d = Dims::new(cfg);
    let mut m = Module::new(NAME);
    m.doc("Preprocessing fetch unit: per command, cmd_count_i records of cmd_words_i 32-bit words from cmd_base_i over");
    m.doc(format!(
        "m_axi_* (reads only; ID 0), at most {} lines of 64 bytes in flight ({} beats, bursts of {}).",
        cfg.pre_read_lines, d.depth, d.burst
    ));
    m.doc(format!(
        "Records leave on rec_* one per handshake, slots from cmd_words_i up read 0; cmd_words_i in {}..={}.",
        d.w, d.maxw
    ));
    m.clock_reset();
    m.input_c("cmd_valid_i", 1, "a command is offered");
    m.output_c("cmd_ready_o", 1, "the unit takes it");
    m.input_c("cmd_base_i", d.ab, "byte address of the command's record 0 (4-byte aligned)");
    m.input_c("cmd_words_i", d.wb, "words per record");
    m.input_c("cmd_count_i", COUNT_BITS, "records of the command");
    m.output_c("busy_o", 1, "a command is not finished (its last record not taken)");
    m.output_c("rec_valid_o", 1, "a record is offered");
    m.input_c("rec_ready_i", 1, "the record is taken");
    m.output_c("rec_data_o", d.maxw * 32, "the record, word k at [32k +: 32]");
    m.output_c("rec_index_o", COUNT_BITS, "the record's index in its command");
    axi::ports(&mut m, cfg, "m_axi_", true);
    start(&mut m, &d);
    issue(&mut m, cfg, &d);
    buffer(&mut m, &d);
    assemble(&mut m, &d);
    output(&mut m, &d);
    tie_offs(&mut m, cfg);
    m
}

/// A command's beats, and its entry in the command queue `{skip, words, count}`.
fn start(m: &mut Module, d: &Dims) {
    let (ws, kb) = (d.w.trailing_zeros(), bits_for(u64::from(d.w)));
    m.blank();
    m.comment("Command: it covers the beats from its base's to its last word's; the assembly gets");
    m.comment("{skip (words of the first beat before the base), words, count} through u_cmdq.");
    m.wire_assign("cmd_take", 1, "cmd_valid_i & cmd_ready_o");
    m.wire_assign(
        "words_total",
        d.lb,
        format!("{} * {}", zext("cmd_words_i", d.wb, d.lb), zext("cmd_count_i", COUNT_BITS, d.lb)),
    );
    m.wire_assign("cmd_skip", kb, zext(&format!("cmd_base_i[{}:2]", d.beat_shift - 1), ws, kb));
    m.wire_assign("words_end", d.lb, format!("words_total + {}", zext("cmd_skip", kb, d.lb)));
    let round = lit(d.lb, u64::from(d.w - 1));
    m.wire_assign("cmd_empty", 1, format!("cmd_count_i == {}", lit(COUNT_BITS, 0)));
    m.wire_assign("cmd_beats", d.lb, format!("(words_end + {round}) >> {ws}"));
    let qw = kb + d.wb + COUNT_BITS;
    m.wire("q_ready", 1).wire("q_valid", 1).wire("q_pop", 1).wire("q_data", qw);
    m.assign("cmd_ready_o", format!("(ar_left_q == {}) & q_ready", lit(d.lb, 0)));
    m.item(super::fifo::instance(
        qw,
        CMD_QUEUE,
        "u_cmdq",
        vec![
            ("clk_i".into(), "clk_i".into()),
            ("rst_ni".into(), "rst_ni".into()),
            ("push_valid_i".into(), "cmd_take & ~cmd_empty".into()),
            ("push_ready_o".into(), "q_ready".into()),
            ("push_data_i".into(), "{cmd_skip, cmd_words_i, cmd_count_i}".into()),
            ("pop_valid_o".into(), "q_valid".into()),
            ("pop_ready_i".into(), "q_pop".into()),
            ("pop_data_o".into(), "q_data".into()),
        ],
    ));
    m.wire_assign("q_skip", kb, format!("q_data[{}:{}]", qw - 1, d.wb + COUNT_BITS));
    m.wire_assign("q_words", d.wb, format!("q_data[{}:{COUNT_BITS}]", d.wb + COUNT_BITS - 1));
    m.wire_assign("q_count", COUNT_BITS, format!("q_data[{}:0]", COUNT_BITS - 1));
}

/// AR: bursts over the command's beats, each issued when the buffer has room for it.
fn issue(m: &mut Module, cfg: &EngineConfig, d: &Dims) {
    let (sb, bs) = (d.sb(), d.burst_shift);
    m.blank();
    m.comment(format!(
        "AR: bursts of up to {} beats aligned to their size; one is issued when space_q (buffer slots not",
        d.burst
    ));
    m.comment(format!(
        "holding or awaiting a beat) covers it, with at most {} bursts in flight.",
        cfg.pre_outstanding
    ));
    m.reg("ar_beat_q", d.bi).reg("ar_left_q", d.lb).reg("space_q", sb).reg("rd_cnt_q", d.cb);
    let room = if bs == 0 {
        lit(sb, 1)
    } else {
        format!("{} - {}", lit(sb, u64::from(d.burst)), zext(&format!("ar_beat_q[{}:0]", bs - 1), bs, sb))
    };
    m.wire_assign("ar_room", sb, room);
    m.wire_assign(
        "ar_chunk",
        sb,
        format!("(ar_left_q < {}) ? ar_left_q[{}:0] : ar_room", zext("ar_room", sb, d.lb), sb - 1),
    );
    let o = cfg.pre_outstanding as u64;
    m.assign(
        "m_axi_arvalid_o",
        format!("(ar_left_q != {}) & (rd_cnt_q != {}) & (space_q >= ar_chunk)", lit(d.lb, 0), lit(d.cb, o)),
    );
    m.wire_assign("ar_fire", 1, "m_axi_arvalid_o & m_axi_arready_i");
    m.assign("m_axi_araddr_o", format!("{{ar_beat_q, {}}}", lit(d.beat_shift, 0)));
    m.assign("m_axi_arlen_o", format!("{} - {}", resize("ar_chunk", sb, 8), lit(8, 1)));
    m.assign("m_axi_arid_o", lit(cfg.axi_id_bits, 0));
    m.assign("m_axi_arsize_o", lit(3, u64::from(d.beat_shift)));
    m.assign("m_axi_arburst_o", lit(2, 1));
    m.assign("m_axi_rready_o", lit(1, 1));
    m.wire_assign("r_fire", 1, "m_axi_rvalid_i");
    m.wire_assign("r_end", 1, "r_fire & m_axi_rlast_i");
    m.wire_assign("space_in", sb, format!("{} ? ar_chunk : {}", "ar_fire", lit(sb, 0)));
    m.wire_assign("space_out", sb, zext("beat_take", 1, sb));
    m.seq(
        vec![
            set("ar_beat_q", lit(d.bi, 0)),
            set("ar_left_q", lit(d.lb, 0)),
            set("space_q", lit(sb, u64::from(d.depth))),
            set("rd_cnt_q", lit(d.cb, 0)),
        ],
        vec![
            if_else(
                "cmd_take",
                vec![
                    set("ar_beat_q", format!("cmd_base_i[{}:{}]", d.ab - 1, d.beat_shift)),
                    set("ar_left_q", format!("cmd_empty ? {} : cmd_beats", lit(d.lb, 0))),
                ],
                vec![if_(
                    "ar_fire",
                    vec![
                        set("ar_beat_q", format!("ar_beat_q + {}", resize("ar_chunk", sb, d.bi))),
                        set("ar_left_q", format!("ar_left_q - {}", zext("ar_chunk", sb, d.lb))),
                    ],
                )],
            ),
            set("space_q", "space_q - space_in + space_out"),
            if_else(
                "ar_fire & ~r_end",
                vec![set("rd_cnt_q", format!("rd_cnt_q + {}", lit(d.cb, 1)))],
                vec![if_("r_end & ~ar_fire", vec![set("rd_cnt_q", format!("rd_cnt_q - {}", lit(d.cb, 1)))])],
            ),
        ],
    );
}

/// The beat buffer: R beats in at `wr_ptr_q`, the head at `rd_ptr_q`; `buf_cnt_q` beats held.
fn buffer(m: &mut Module, d: &Dims) {
    let (pb, sb) = (d.pb, d.sb());
    m.blank();
    m.comment(
        "Beat buffer: every R beat is written (space_q reserved its slot); the head feeds the assembly.",
    );
    m.reg("wr_ptr_q", pb).reg("rd_ptr_q", pb).reg("buf_cnt_q", sb);
    m.wire("head", d.db);
    m.wire_assign("head_valid", 1, format!("buf_cnt_q != {}", lit(sb, 0)));
    m.item(super::ram::instance(
        d.db,
        d.depth,
        "u_buf",
        vec![
            ("clk_i".into(), "clk_i".into()),
            ("we_i".into(), "r_fire".into()),
            ("waddr_i".into(), "wr_ptr_q".into()),
            ("wdata_i".into(), "m_axi_rdata_i".into()),
            ("raddr_i".into(), "rd_ptr_q".into()),
            ("rdata_o".into(), "head".into()),
        ],
    ));
    let step = |p: &str| format!("{p} + {}", lit(pb, 1));
    m.seq(
        vec![set("wr_ptr_q", lit(pb, 0)), set("rd_ptr_q", lit(pb, 0)), set("buf_cnt_q", lit(sb, 0))],
        vec![
            if_("r_fire", vec![set("wr_ptr_q", step("wr_ptr_q"))]),
            if_("beat_take", vec![set("rd_ptr_q", step("rd_ptr_q"))]),
            set("buf_cnt_q", format!("buf_cnt_q + {} - {}", zext("r_fire", 1, sb), zext("beat_take", 1, sb))),
        ],
    );
}

/// The record register and the per-slot placement of the head beat's words.
fn assemble(m: &mut Module, d: &Dims) {
    let (w, wb) = (d.w, d.wb);
    let kb = bits_for(u64::from(w));
    let pw = wb + 1;
    m.blank();
    m.comment("Assembly: beat word k (k >= skip_q) lands at record position pos_k = fill_q + k - skip_q;");
    m.comment("positions at or past words_q belong to the next record (slot pos_k - words_q).");
    m.reg("rec_q", d.maxw * 32).reg("fill_q", wb).reg("skip_q", kb).reg("rec_left_q", COUNT_BITS);
    m.reg("words_q", wb);
    m.wire_assign("idle_asm", 1, format!("rec_left_q == {}", lit(COUNT_BITS, 0)));
    m.assign("q_pop", "idle_asm");
    m.wire_assign("q_load", 1, "idle_asm & q_valid");
    m.wire_assign("n_new", pw, format!("{} - {}", lit(pw, u64::from(w)), zext("skip_q", kb, pw)));
    m.wire_assign("rec_end", pw, format!("{} + n_new", zext("fill_q", wb, pw)));
    m.wire_assign("words_x", pw, zext("words_q", wb, pw));
    m.wire_assign("completes", 1, "rec_end >= words_x");
    m.wire_assign("rec_rest", wb, format!("{} - words_q", resize("rec_end", pw, wb)));
    m.wire_assign(
        "beat_take",
        1,
        format!(
            "head_valid & (rec_left_q != {}) & (~completes | ~rec_valid_o | rec_ready_i)",
            lit(COUNT_BITS, 0)
        ),
    );
    m.wire_assign("rec_done", 1, "beat_take & completes");
    for k in 0..w {
        m.wire_assign(format!("word{k}"), 32, format!("head[{}:{}]", 32 * k + 31, 32 * k));
        m.wire_assign(format!("used{k}"), 1, format!("{} >= skip_q", lit(kb, u64::from(k))));
        m.wire_assign(
            format!("pos{k}"),
            pw,
            format!("{} + {} - {}", zext("fill_q", wb, pw), lit(pw, u64::from(k)), zext("skip_q", kb, pw)),
        );
        m.wire_assign(format!("next{k}"), pw, format!("pos{k} - words_x"));
    }
    m.wire("merged", d.maxw * 32).wire("carried", d.maxw * 32).wire("out_next", d.maxw * 32);
    m.gen_for("j", d.maxw, "g_slot", slot_items(d, pw));
    m.seq(
        vec![
            set("fill_q", lit(wb, 0)),
            set("skip_q", lit(kb, 0)),
            set("rec_left_q", lit(COUNT_BITS, 0)),
            set("words_q", lit(wb, 0)),
        ],
        vec![if_else(
            "q_load",
            vec![
                set("fill_q", lit(wb, 0)),
                set("skip_q", "q_skip"),
                set("rec_left_q", "q_count"),
                set("words_q", "q_words"),
            ],
            vec![if_(
                "beat_take",
                vec![
                    set("skip_q", lit(kb, 0)),
                    set("fill_q", format!("completes ? {} : {}", "rec_rest", resize("rec_end", pw, wb))),
                    if_("completes", vec![set("rec_left_q", format!("rec_left_q - {}", lit(COUNT_BITS, 1)))]),
                ],
            )],
        )],
    );
    m.seq_noreset(vec![if_("beat_take", vec![set("rec_q", "completes ? carried : merged")])]);
}

/// Generate-block items of record slot `j`: `merged` (the record with this beat's words),
/// `carried` (the next record's first words) and `out_next` (the output record, 0 past `words_q`).
fn slot_items(d: &Dims, pw: u32) -> Vec<Item> {
    let jx = format!("j[{}:0]", pw - 1);
    let mut merged = "rec_q[32*j +: 32]".to_string();
    let mut carried = lit(32, 0);
    for k in (0..d.w).rev() {
        merged = format!("(used{k} & (pos{k} == {jx})) ? word{k} : ({merged})");
        carried = format!("(used{k} & (pos{k} >= words_x) & (next{k} == {jx})) ? word{k} : ({carried})");
    }
    let assign = |lhs: &str, rhs: String| Item::Assign { lhs: lhs.into(), rhs };
    vec![
        assign("merged[32*j +: 32]", merged),
        assign("carried[32*j +: 32]", carried),
        assign("out_next[32*j +: 32]", format!("({jx} < words_x) ? merged[32*j +: 32] : {}", lit(32, 0))),
    ]
}

/// The output register: a completed record, its index; `busy_o`.
fn output(m: &mut Module, d: &Dims) {
    let sb = d.sb();
    m.blank();
    m.comment("Output: a completed record waits in out_q until taken.");
    m.reg("out_v_q", 1).reg("out_q", d.maxw * 32).reg("out_idx_q", COUNT_BITS).reg("next_idx_q", COUNT_BITS);
    m.seq(
        vec![set("out_v_q", lit(1, 0)), set("next_idx_q", lit(COUNT_BITS, 0))],
        vec![
            if_else(
                "rec_done",
                vec![set("out_v_q", lit(1, 1))],
                vec![if_("rec_ready_i", vec![set("out_v_q", lit(1, 0))])],
            ),
            if_else(
                "q_load",
                vec![set("next_idx_q", lit(COUNT_BITS, 0))],
                vec![if_(
                    "rec_done",
                    vec![set("next_idx_q", format!("next_idx_q + {}", lit(COUNT_BITS, 1)))],
                )],
            ),
        ],
    );
    m.seq_noreset(vec![if_("rec_done", vec![set("out_q", "out_next"), set("out_idx_q", "next_idx_q")])]);
    m.assign("rec_valid_o", "out_v_q");
    m.assign("rec_data_o", "out_q");
    m.assign("rec_index_o", "out_idx_q");
    m.assign(
        "busy_o",
        format!(
            "~idle_asm | q_valid | out_v_q | (ar_left_q != {}) | (rd_cnt_q != {}) | (space_q != {})",
            lit(d.lb, 0),
            lit(d.cb, 0),
            lit(sb, u64::from(d.depth))
        ),
    );
}

/// The write channels are idle; the responses the unit does not use.
fn tie_offs(m: &mut Module, cfg: &EngineConfig) {
    m.blank();
    m.comment("Writes: none (the channels are idle). Unused response fields: one ID, errors not reported.");
    for s in axi::signals(cfg)
        .iter()
        .filter(|s| s.from_manager && (s.name.starts_with("aw") || s.name.starts_with('w')))
    {
        m.assign(axi::port_name("m_axi_", s, true), lit(s.width, 0));
    }
    m.assign("m_axi_bready_o", lit(1, 1));
    let unused = [
        "m_axi_rid_i",
        "m_axi_rresp_i",
        "m_axi_awready_i",
        "m_axi_wready_i",
        "m_axi_bvalid_i",
        "m_axi_bid_i",
        "m_axi_bresp_i",
        "cmd_base_i[1:0]",
    ];
    m.wire_assign("unused_in", 1, format!("^{{{}}}", unused.join(", ")));
}
