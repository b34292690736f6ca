//! `neo_raster_window_loader`: LOAD of a raster core with a reorder window (`raster_window` `W`
//! above 1; else [`super::loader`]). Two halves around a `neo_raster_window`
//! ([`super::window`]):
//! - the **reader** goes through the table in segments of `F` entries: the segment's table
//!   entries in bursts into a staging buffer, then one feature read per entry; each feature
//!   response pushes `{current key, id, feature word}` into the window (the current key: the
//!   feature word's depth key, or the table key of a culled Gaussian, as golden's);
//! - the **filler** takes the next free bank for the next segment of table positions and writes
//!   the window's emissions into it in order (one register stage), and reports the segment
//!   loaded once it holds the segment's entries. It takes the following segment's bank as soon
//!   as that one is free, so the reads run on across the boundary. At the table's end it drains
//!   the window.
//!
//! Responses are always taken: feature read `n` (of the table) is issued only when the window's
//! emission it causes (`n - (W - 1)`, once the window is full) has a place in the bank being
//! filled (`n < W - 1 + fill limit`, the fill limit being the end of the last segment the filler
//! holds a bank for, or the next segment's start while it waits for one).

use super::loader::{burst_len, command_segments, next_segment, segment_ports};
use super::{feature_word, table_word, window, Dims, L_FEAT, L_IDLE, L_TABLE};
use crate::emit::expr::{lit, resize, zext};
use crate::emit::{if_, if_else, set, Module, Stmt};
use neo_golden::engine::EngineConfig;

/// Module name.
pub const NAME: &str = "neo_raster_window_loader";

const F_IDLE: u64 = 0;
const F_FILL: u64 = 1;

/// The loader with a window for `cfg`.
pub fn module(cfg: &EngineConfig) -> Module {
    let d = Dims::new(cfg);
    let mut m = Module::new(NAME);
    m.doc(format!(
        "Raster core LOAD through a reorder window of {} entries: table bursts and feature reads per segment",
        cfg.raster_window
    ));
    m.doc("into the window; its emissions fill the next free bank in order.");
    ports(&mut m, &d);
    m.blank();
    for (n, v) in [("L_IDLE", L_IDLE), ("L_TABLE", L_TABLE), ("L_FEAT", L_FEAT)] {
        m.localparam(n, 2, lit(2, v));
    }
    m.localparam("F_IDLE", 1, lit(1, F_IDLE)).localparam("F_FILL", 1, lit(1, F_FILL));
    let tw = table_word(&d);
    tw.declare_bits(&mut m);
    tw.declare(&mut m);
    feature_word(cfg, &d).subset(&["depth_key", "present"]).declare(&mut m);
    m.comment("Segments of the table (the reader's and the filler's are the same).");
    command_segments(&mut m, &d);
    m.comment("Between the halves: the filler's limit on feature reads, the window's emissions.");
    m.wire("fill_limit", d.lw);
    m.wire("win_emit", 1).wire("win_key", d.kb).wire("win_id", d.ib).wire("win_feat", d.fw);
    reader(&mut m, cfg, &d);
    filler(&mut m, &d);
    instance(&mut m, &d);
    m
}

fn ports(m: &mut Module, d: &Dims) {
    segment_ports(m, d);
    m.input_c("next_free_i", 1, "bank bank_o + 1 is free (taken ahead for the next segment)");
    m.input_c("rsp_valid_i", 1, "a read response beat");
    m.input_c("rsp_data_i", d.fw, "its table entry (low bits) or feature word");
    m.output_c("wr_valid_o", 1, "write an emitted entry into the bank");
    m.output_c("wr_idx_o", d.fx, "at buffer index {bank, entry}");
    m.output_c("wr_table_o", d.tw, "its table word {key, id} (the key it was ordered by)");
    m.output_c("wr_feat_o", d.fw, "its feature word");
}

/// The reader: a segment's table bursts into the staging buffer, then its feature reads, each
/// response pushed into the window. The next segment's table bursts go out as soon as this
/// one's feature reads are all issued: responses come in request order, so while a feature read
/// is outstanding every response is a feature word, and the next segment's table entries
/// overwrite the staging buffer only after the last of them (one buffer is enough).
fn reader(m: &mut Module, cfg: &EngineConfig, d: &Dims) {
    let (sl, lw, bl, aw, fa) = (d.sl, d.lw, d.bl, d.aw, d.fa);
    let tw = table_word(d);
    m.blank();
    m.comment("Reader: a segment's table entries into the staging buffer, then one feature read per");
    m.comment("entry; the next segment's table bursts follow its last feature read (before the responses).");
    m.reg("rstate_q", 2).reg("rstart_q", lw).reg("rlen_q", sl).reg("rsegs_left_q", lw);
    m.reg("issued_q", sl).reg("table_rcv_q", sl);
    m.comment("The segment whose feature reads are in flight: its length and responses.");
    m.reg("flen_q", sl).reg("frcv_q", sl).reg("pushed_q", lw);
    m.mem("sbuf", d.tw, d.f);
    next_segment(m, d, "r_", "rstart_q");
    burst_len(m, cfg, d, "rlen_q");
    m.wire_assign("rd_table", 1, "rstate_q == L_TABLE");
    m.comment("Feature read n (of the table) only when its emission has a place in the bank being filled.");
    let w1 = lit(lw + 1, cfg.raster_window as u64 - 1);
    m.wire_assign("feat_n", lw, format!("rstart_q + {}", resize("issued_q", sl, lw)));
    m.wire_assign(
        "feat_room",
        1,
        format!("{} < {} + {w1}", zext("feat_n", lw, lw + 1), zext("fill_limit", lw, lw + 1)),
    );
    m.assign("rd_table_o", "rd_table");
    m.assign("rd_valid_o", "(rstate_q != L_IDLE) & (issued_q != rlen_q) & (rd_table | feat_room)");
    m.wire_assign("iss_id", d.ib, tw.get(&format!("sbuf[{}]", resize("issued_q", sl, fa)), "id"));
    m.assign(
        "rd_addr_o",
        format!(
            "rd_table ? (table_i + {} + {}) : (feat_i + {})",
            resize("rstart_q", lw, aw),
            resize("issued_q", sl, aw),
            resize("iss_id", d.ib, aw)
        ),
    );
    m.wire_assign("rd_len", bl, format!("rd_table ? table_len : {}", lit(bl, 1)));
    m.assign("rd_len_o", "rd_len");
    m.wire_assign("all_issued", 1, "issued_q == rlen_q");
    m.wire_assign("table_in", 1, "all_issued & (table_rcv_q == rlen_q)");
    m.comment("A response is a feature word while a feature read is outstanding, else a table entry.");
    m.wire_assign("feat_out", 1, "frcv_q != flen_q");
    m.wire_assign("push", 1, "rsp_valid_i & feat_out");
    m.wire_assign("table_rsp", 1, "rsp_valid_i & ~feat_out");
    m.comment(
        "A feature response: the entry's current key (culled: its table key) and id go into the window.",
    );
    m.wire_assign("rcv_word", d.tw, format!("sbuf[{}]", resize("frcv_q", sl, fa)));
    let fw = feature_word(cfg, d);
    let dkw = fw.width_of("depth_key");
    m.wire_assign(
        "push_key",
        d.kb,
        format!(
            "{} ? {} : {}",
            fw.get("rsp_data_i", "present"),
            resize(&fw.get("rsp_data_i", "depth_key"), dkw, d.kb),
            tw.get("rcv_word", "key")
        ),
    );
    m.seq_noreset(vec![if_(
        "table_rsp",
        vec![set(format!("sbuf[{}]", resize("table_rcv_q", sl, fa)), tw.low_of("rsp_data_i"))],
    )]);
    reader_control(m, d);
}

/// The reader's phases: IDLE -> TABLE -> FEAT -> TABLE (next segment) ... -> IDLE.
fn reader_control(m: &mut Module, d: &Dims) {
    let (sl, lw, bl) = (d.sl, d.lw, d.bl);
    let zero = lit(sl, 0);
    let table = |start: &str, len: &str| {
        vec![
            set("rstate_q", "L_TABLE"),
            set("rstart_q", start),
            set("rlen_q", len),
            set("issued_q", zero.clone()),
            set("table_rcv_q", zero.clone()),
        ]
    };
    let clear = vec![
        set("rstate_q", "L_IDLE"),
        set("rstart_q", lit(lw, 0)),
        set("rlen_q", "cmd_seg_len"),
        set("rsegs_left_q", "cmd_segs"),
        set("issued_q", zero.clone()),
        set("table_rcv_q", zero.clone()),
        set("flen_q", zero.clone()),
        set("frcv_q", zero.clone()),
        set("pushed_q", lit(lw, 0)),
    ];
    let mut next = vec![set("rsegs_left_q", format!("rsegs_left_q - {}", lit(lw, 1)))];
    next.push(crate::emit::if_else(
        format!("rsegs_left_q == {}", lit(lw, 1)),
        vec![set("rstate_q", "L_IDLE")],
        table("r_next_start", "r_next_seg_len"),
    ));
    let states = Stmt::Case(
        "rstate_q".into(),
        vec![
            (
                "L_IDLE".into(),
                vec![if_(
                    format!("run_i & (rsegs_left_q != {})", lit(lw, 0)),
                    vec![
                        set("rstate_q", "L_TABLE"),
                        set("issued_q", zero.clone()),
                        set("table_rcv_q", zero.clone()),
                    ],
                )],
            ),
            (
                "L_TABLE".into(),
                vec![if_(
                    "table_in",
                    vec![
                        set("rstate_q", "L_FEAT"),
                        set("issued_q", zero.clone()),
                        set("flen_q", "rlen_q"),
                        set("frcv_q", zero.clone()),
                    ],
                )],
            ),
            ("L_FEAT".into(), vec![if_("all_issued", next)]),
        ],
        vec![set("rstate_q", "L_IDLE")],
    );
    m.seq_d(
        Some(m.q_resets(&[])),
        vec![
            if_("rd_grant_i", vec![set("issued_q", format!("issued_q + {}", resize("rd_len", bl, sl)))]),
            if_("table_rsp", vec![set("table_rcv_q", format!("table_rcv_q + {}", lit(sl, 1)))]),
            if_("push", vec![set("frcv_q", format!("frcv_q + {}", lit(sl, 1)))]),
            if_("push", vec![set("pushed_q", format!("pushed_q + {}", lit(lw, 1)))]),
            if_else("clear_i", clear, vec![states]),
        ],
    );
}

/// The filler: a bank per segment of table positions, filled with the window's emissions.
fn filler(m: &mut Module, d: &Dims) {
    let (sl, lw, bkb, fa) = (d.sl, d.lw, d.bkb, d.fa);
    m.blank();
    m.comment(
        "Filler: the next free bank for the next segment, written with the window's emissions in order.",
    );
    m.reg("fstate_q", 1).reg("fbank_q", bkb).reg("fstart_q", lw).reg("fseg_len_q", sl);
    m.reg("fsegs_left_q", lw).reg("fpos_q", sl).reg("fnext_q", 1).reg("wr_valid_q", 1);
    m.reg("wr_idx_q", d.fx).reg("wr_table_q", d.tw).reg("wr_feat_q", d.fw);
    next_segment(m, d, "f_", "fstart_q");
    m.wire_assign("filling", 1, "fstate_q == F_FILL");
    m.wire_assign("fill_end", lw, format!("fstart_q + {}", resize("fseg_len_q", sl, lw)));
    m.comment("The next segment's bank is taken as soon as it is free, so the reads run on across the");
    m.comment("segment boundary; the emission after the segment's last goes to its first entry.");
    m.wire_assign(
        "next_ok",
        1,
        format!("filling & ~fnext_q & (fsegs_left_q > {}) & next_free_i", lit(lw, 1)),
    );
    m.assign(
        "fill_limit",
        format!(
            "filling ? (fnext_q ? (fill_end + {}) : fill_end) : fstart_q",
            resize("f_next_seg_len", sl, lw)
        ),
    );
    m.wire_assign("at_end", 1, "fpos_q == fseg_len_q");
    m.wire_assign("seg_done", 1, "filling & at_end");
    m.comment("Every entry pushed: drain the window into the bank.");
    m.wire_assign("drain", 1, "filling & (pushed_q == len_i) & (~at_end | fnext_q)");
    m.assign("done_o", "seg_done");
    m.assign("bank_o", "fbank_q");
    m.assign("start_o", "fstart_q");
    m.assign("seg_len_o", "fseg_len_q");
    m.assign("wr_valid_o", "wr_valid_q");
    m.assign("wr_idx_o", "wr_idx_q");
    m.assign("wr_table_o", "wr_table_q");
    m.assign("wr_feat_o", "wr_feat_q");
    let clear = vec![
        set("fstate_q", "F_IDLE"),
        set("fbank_q", lit(bkb, 0)),
        set("fstart_q", lit(lw, 0)),
        set("fseg_len_q", "cmd_seg_len"),
        set("fsegs_left_q", "cmd_segs"),
        set("fpos_q", lit(sl, 0)),
        set("fnext_q", lit(1, 0)),
    ];
    let states = Stmt::Case(
        "fstate_q".into(),
        vec![
            (
                "F_IDLE".into(),
                vec![if_(
                    format!("run_i & (fsegs_left_q != {}) & bank_free_i", lit(lw, 0)),
                    vec![set("fstate_q", "F_FILL"), set("fpos_q", lit(sl, 0))],
                )],
            ),
            (
                "F_FILL".into(),
                vec![
                    if_("next_ok", vec![set("fnext_q", lit(1, 1))]),
                    if_(
                        "seg_done",
                        vec![
                            set("fstate_q", "fnext_q ? F_FILL : F_IDLE"),
                            set("fbank_q", format!("fbank_q + {}", lit(bkb, 1))),
                            set("fstart_q", "f_next_start"),
                            set("fseg_len_q", "f_next_seg_len"),
                            set("fsegs_left_q", format!("fsegs_left_q - {}", lit(lw, 1))),
                            set("fnext_q", lit(1, 0)),
                            set("fpos_q", format!("{{{}, win_emit}}", lit(sl - 1, 0))),
                        ],
                    ),
                ],
            ),
        ],
        Vec::new(),
    );
    m.seq_d(
        Some(vec![
            set("fstate_q", "F_IDLE"),
            set("fbank_q", lit(bkb, 0)),
            set("fstart_q", lit(lw, 0)),
            set("fseg_len_q", lit(sl, 0)),
            set("fsegs_left_q", lit(lw, 0)),
            set("fpos_q", lit(sl, 0)),
            set("fnext_q", lit(1, 0)),
            set("wr_valid_q", lit(1, 0)),
        ]),
        vec![
            set("wr_valid_q", "win_emit"),
            if_("win_emit", vec![set("fpos_q", format!("fpos_q + {}", lit(sl, 1)))]),
            if_else("clear_i", clear, vec![states]),
        ],
    );
    m.seq_noreset(vec![if_(
        "win_emit",
        vec![
            set(
                "wr_idx_q",
                format!(
                    "at_end ? {{fbank_q + {}, {}}} : {{fbank_q, {}}}",
                    lit(bkb, 1),
                    lit(fa, 0),
                    resize("fpos_q", sl, fa)
                ),
            ),
            set(table_word(d).get("wr_table_q", "key"), "win_key"),
            set(table_word(d).get("wr_table_q", "id"), "win_id"),
            set("wr_feat_q", "win_feat"),
        ],
    )]);
}

/// The window instance.
fn instance(m: &mut Module, d: &Dims) {
    m.blank();
    m.comment("The window: pushes from the reader, emissions to the filler.");
    m.wire("win_full", 1).wire("win_empty", 1);
    m.wire_assign("unused_win", 1, "win_full ^ win_empty");
    let tw = table_word(d);
    let c = |p: &str, e: String| (p.to_string(), e);
    m.instance(
        window::NAME,
        "u_window",
        vec![
            c("clk_i", "clk_i".into()),
            c("rst_ni", "rst_ni".into()),
            c("clear_i", "clear_i".into()),
            c("push_i", "push".into()),
            c("push_key_i", "push_key".into()),
            c("push_id_i", tw.get("rcv_word", "id")),
            c("push_feat_i", "rsp_data_i".into()),
            c("pop_i", "drain".into()),
            c("emit_valid_o", "win_emit".into()),
            c("emit_key_o", "win_key".into()),
            c("emit_id_o", "win_id".into()),
            c("emit_feat_o", "win_feat".into()),
            c("full_o", "win_full".into()),
            c("empty_o", "win_empty".into()),
        ],
    );
}
