//! `neo_raster_loader`: LOAD of the raster core. For each segment of at most `F` table entries,
//! into the next free bank: the table entries in bursts, then one feature read per entry
//! (`feature base + id`). Reads are issued only for reserved buffer space, so responses are
//! always taken; they arrive in request order and are written at `rcv_idx_o`.

use super::{Dims, L_FEAT, L_IDLE, L_TABLE};
use crate::emit::expr::{lit, resize};
use crate::emit::{if_, set, Module, Stmt};
use neo_golden::engine::EngineConfig;

/// Module name.
pub const NAME: &str = "neo_raster_loader";

/// The loader for `cfg`.
pub fn module(cfg: &EngineConfig) -> Module {
    let d = Dims::new(cfg);
    let mut m = Module::new(NAME);
    m.doc("Raster core LOAD: per segment, table bursts then one feature read per entry, into the next free bank.");
    ports(&mut m, &d);
    m.blank();
    m.comment("Load state: phase, the segment being loaded (bank, first entry, length) and the reads.");
    m.reg("state_q", 2).reg("bank_q", d.bkb).reg("start_q", d.lw).reg("seg_len_q", d.sl);
    m.reg("segs_left_q", d.lw).reg("issued_q", d.sl).reg("received_q", d.sl);
    for (n, v) in [("L_IDLE", L_IDLE), ("L_TABLE", L_TABLE), ("L_FEAT", L_FEAT)] {
        m.localparam(n, 2, lit(2, v));
    }
    segments(&mut m, &d);
    reads(&mut m, cfg, &d);
    control(&mut m, &d);
    m
}

fn ports(m: &mut Module, d: &Dims) {
    segment_ports(m, d);
    m.output_c("iss_idx_o", d.fx, "buffer index of the next feature read's entry ...");
    m.input_c("iss_id_i", d.ib, "... and its Gaussian id (table buffer)");
    m.input_c("rsp_valid_i", 1, "a read response beat");
    m.output_c("rcv_idx_o", d.fx, "its buffer index {bank, entry}");
}

/// The ports both loaders have ([`NAME`] and [`super::window_loader::NAME`]): the command, the
/// segment being loaded and the read requests.
pub(super) fn segment_ports(m: &mut Module, d: &Dims) {
    m.clock_reset();
    m.input_c("clear_i", 1, "command accepted: load the new table from its first segment");
    m.input_c("cmd_len_i", d.lw, "the command's table entries (with clear_i)");
    m.input_c("len_i", d.lw, "the current command's table entries");
    m.input_c("run_i", 1, "the core is running");
    m.input_c("bank_free_i", 1, "bank bank_o is free");
    m.input_c("table_i", d.aw, "table address");
    m.input_c("feat_i", d.aw, "feature base address");
    m.output_c("bank_o", d.bkb, "bank being loaded");
    m.output_c("start_o", d.lw, "its segment's first entry");
    m.output_c("seg_len_o", d.sl, "its segment's entries");
    m.output_c("done_o", 1, "the segment is loaded (one cycle)");
    m.output_c("rd_valid_o", 1, "a read is offered");
    m.input_c("rd_grant_i", 1, "... and taken");
    m.output_c("rd_table_o", 1, "1: table burst; 0: feature read");
    m.output_c("rd_addr_o", d.aw, "read address");
    m.output_c("rd_len_o", d.bl, "read length (elements)");
}

fn segments(m: &mut Module, d: &Dims) {
    m.blank();
    m.comment(format!("Segments of at most {} entries.", d.f));
    command_segments(m, d);
    next_segment(m, d, "", "start_q");
    m.assign("bank_o", "bank_q");
    m.assign("start_o", "start_q");
    m.assign("seg_len_o", "seg_len_q");
}

/// `left` (entries of the segment of `len` entries not yet requested) and `table_len`, the next
/// table burst's length: `burst` entries, never past the segment's end.
pub(super) fn burst_len(m: &mut Module, cfg: &EngineConfig, d: &Dims, len: &str) {
    let (sl, bl) = (d.sl, d.bl);
    let bur = cfg.burst as u64;
    m.wire_assign("left", sl, format!("{len} - issued_q"));
    // With bursts as long as a bank, `left` fits.
    let tlen = if bur >= d.f as u64 {
        resize("left", sl, bl)
    } else {
        format!("(left > {}) ? {} : {}", lit(sl, bur), lit(bl, bur), resize("left", sl, bl))
    };
    m.wire_assign("table_len", bl, tlen);
}

/// `cmd_seg_len` and `cmd_segs`: the first segment's length and the segments of the command's
/// table (`cmd_len_i`; one empty segment for an empty table).
pub(super) fn command_segments(m: &mut Module, d: &Dims) {
    let (lw, sl) = (d.lw, d.sl);
    let flit = |wi: u32| lit(wi, d.f as u64);
    let fl = d.f.trailing_zeros();
    m.wire_assign(
        "cmd_seg_len",
        sl,
        format!("(cmd_len_i > {}) ? {} : {}", flit(lw), flit(sl), resize("cmd_len_i", lw, sl)),
    );
    m.wire_assign(
        "cmd_segs",
        lw,
        format!(
            "(cmd_len_i == {z}) ? {one} : (((cmd_len_i - {one}) >> {fl}) + {one})",
            z = lit(lw, 0),
            one = lit(lw, 1)
        ),
    );
}

/// `{prefix}next_start` and `{prefix}next_seg_len`: the first entry and the length of the
/// segment after the one starting at register `start` (of the table of `len_i` entries).
pub(super) fn next_segment(m: &mut Module, d: &Dims, prefix: &str, start: &str) {
    let (lw, sl) = (d.lw, d.sl);
    let flit = |wi: u32| lit(wi, d.f as u64);
    m.wire_assign(format!("{prefix}next_start"), lw, format!("{start} + {}", flit(lw)));
    m.wire_assign(format!("{prefix}rem_next"), lw, format!("len_i - {prefix}next_start"));
    let rem = format!("{prefix}rem_next");
    m.wire_assign(
        format!("{prefix}next_seg_len"),
        sl,
        format!("({rem} > {}) ? {} : {}", flit(lw), flit(sl), resize(&rem, lw, sl)),
    );
}

fn reads(m: &mut Module, cfg: &EngineConfig, d: &Dims) {
    let (sl, bl, aw, fa) = (d.sl, d.bl, d.aw, d.fa);
    m.blank();
    m.comment("Reads: table bursts (never past the segment's end), then one feature word per entry.");
    burst_len(m, cfg, d, "seg_len_q");
    m.wire_assign("rd_table", 1, "state_q == L_TABLE");
    m.assign("rd_table_o", "rd_table");
    m.assign("rd_valid_o", "(state_q != L_IDLE) & (issued_q != seg_len_q)");
    m.assign("iss_idx_o", format!("{{bank_q, {}}}", resize("issued_q", sl, fa)));
    m.assign(
        "rd_addr_o",
        format!(
            "rd_table ? (table_i + {} + {}) : (feat_i + {})",
            resize("start_q", d.lw, aw),
            resize("issued_q", sl, aw),
            resize("iss_id_i", d.ib, aw)
        ),
    );
    m.wire_assign("rd_len", bl, format!("rd_table ? table_len : {}", lit(bl, 1)));
    m.assign("rd_len_o", "rd_len");
    m.assign("rcv_idx_o", format!("{{bank_q, {}}}", resize("received_q", sl, fa)));
    m.wire_assign("loaded", 1, "(issued_q == seg_len_q) & (received_q == seg_len_q)");
    m.assign("done_o", "(state_q == L_FEAT) & loaded");
}

fn control(m: &mut Module, d: &Dims) {
    let (sl, lw, bkb) = (d.sl, d.lw, d.bkb);
    m.blank();
    m.comment("Phases: IDLE -> TABLE -> FEAT -> IDLE, a segment per free bank.");
    // A load phase starts with no read issued or received.
    let phase =
        |st: &str| vec![set("state_q", st), set("issued_q", lit(sl, 0)), set("received_q", lit(sl, 0))];
    m.seq_d(
        Some(vec![
            set("state_q", "L_IDLE"),
            set("segs_left_q", lit(lw, 0)),
            set("issued_q", lit(sl, 0)),
            set("received_q", lit(sl, 0)),
        ]),
        vec![
            if_("rd_grant_i", vec![set("issued_q", format!("issued_q + {}", resize("rd_len", d.bl, sl)))]),
            if_("rsp_valid_i", vec![set("received_q", format!("received_q + {}", lit(sl, 1)))]),
            crate::emit::if_else(
                "clear_i",
                vec![
                    set("state_q", "L_IDLE"),
                    set("bank_q", lit(bkb, 0)),
                    set("start_q", lit(lw, 0)),
                    set("seg_len_q", "cmd_seg_len"),
                    set("segs_left_q", "cmd_segs"),
                ],
                vec![Stmt::Case(
                    "state_q".into(),
                    vec![
                        (
                            "L_IDLE".into(),
                            vec![if_(
                                format!("run_i & (segs_left_q != {}) & bank_free_i", lit(lw, 0)),
                                phase("L_TABLE"),
                            )],
                        ),
                        ("L_TABLE".into(), vec![if_("loaded", phase("L_FEAT"))]),
                        (
                            "L_FEAT".into(),
                            vec![if_(
                                "loaded",
                                vec![
                                    set("state_q", "L_IDLE"),
                                    set("bank_q", format!("bank_q + {}", lit(bkb, 1))),
                                    set("start_q", "next_start"),
                                    set("seg_len_q", "next_seg_len"),
                                    set("segs_left_q", format!("segs_left_q - {}", lit(lw, 1))),
                                ],
                            )],
                        ),
                    ],
                    vec![set("state_q", "L_IDLE")],
                )],
            ),
        ],
    );
}
