//! `neo_raster_feeder`: the routing FIFO and the feeder of one SCU.
//!
//! Each ITU result (a quad of `raster_itus` lanes) is routed to the SCU when a valid lane's
//! bitmap has the SCU's subtile of the result's group set; the element
//! `{final, last, resume, lane mask, base}` is pushed into a FIFO of [`FIFO_DEPTH`] entries
//! (a piece's last quad is pushed even with an empty mask). The feeder pops the FIFO and sends
//! one beat per set mask bit (lowest first), or one empty beat for an element with an empty
//! mask that ends its piece, to the SCU; it drives the SCU's list inputs (subtile origin, inside
//! columns and rows, final / resume) and counts the segments whose last piece it has taken.

use super::{Dims, FIFO_DEPTH};
use crate::emit::bundle::Bundle;
use crate::emit::expr::{bits_for, lit, resize};
use crate::emit::{if_, if_else, set, Item, Module};
use crate::units::scu;
use neo_golden::engine::EngineConfig;

/// Module name.
pub const NAME: &str = "neo_raster_feeder";

/// The feeder for `cfg`.
pub fn module(cfg: &EngineConfig) -> Module {
    let d = Dims::new(cfg);
    let mut m = Module::new(NAME);
    m.doc(format!(
        "Raster core: routing FIFO ({FIFO_DEPTH} deep) and feeder of one SCU (parameter SCU: its index)."
    ));
    m.doc(
        "Routes each ITU result to the SCU when a lane's bitmap has the SCU's subtile of the result's group,",
    );
    m.doc("then feeds the routed entries' features to the SCU in table order, one beat per set mask bit.");
    ports(&mut m, cfg, &d);
    // One bit with one SCU (which `pix_scu_i`, one bit too, is compared with).
    let ib = d.cb.max(1);
    m.localparam("SCU_IDX", ib, format!("SCU[{}:0]", ib - 1));
    route(&mut m, &d);
    element(&mut m, &d);
    beats(&mut m, cfg, &d);
    m.covers(&[
        ("cov_fifo_full", "fifo_full".into(), "the routing FIFO is full: the ITU results are held"),
        (
            "cov_resumed_piece",
            "beat & piece_first_q & elem_resume_q & ~skip".into(),
            "a piece's first beat resumes its subtile from the saved state",
        ),
        (
            "cov_skipped_piece",
            "skip".into(),
            "an empty resumed piece that does not end the subtile is skipped",
        ),
        ("cov_empty_beat", "beat & empty_beat & ~skip".into(), "an empty beat goes to the SCU"),
    ]);
    m
}

fn ports(m: &mut Module, cfg: &EngineConfig, d: &Dims) {
    let w = scu::ScuWidths::new(cfg);
    m.param("SCU", 0).clock_reset();
    m.input_c("clear_i", 1, "command accepted: a new tile starts");
    m.input_c("res_fire_i", 1, "an ITU result (a quad) is taken");
    m.input_c("res_lanes_i", d.ni, "its valid lanes").vector("res_lanes_i");
    m.input_c("res_bitmaps_i", d.ni * d.nsub, "lane u's subtile bitmap at [u * subtiles +: subtiles]");
    m.input_c("res_group_i", d.gw, "its subtile group");
    m.input_c("res_base_i", d.fx, "feature-buffer index {bank, entry} of lane 0");
    m.input_c("res_seg_last_i", 1, "last quad of the group's walk of the segment: ends a piece");
    m.input_c("res_list_last_i", 1, "... of the last segment: the piece is final");
    m.input_c("res_resume_i", 1, "the segment is not the first: the piece resumes its subtile");
    m.output_c("full_o", 1, "FIFO full: hold the ITU results");
    m.output_c("busy_o", 1, "an element is held or queued");
    m.input_c("tile_x_i", d.tb, "command tile column");
    m.input_c("tile_y_i", d.tb, "command tile row");
    m.input_c("width_i", d.wd, "image width in pixels");
    m.input_c("height_i", d.wd, "image height in pixels");
    m.input_c("pix_taken_i", 1, "the pixel writer takes a subtile's last row ...");
    m.input_c("pix_scu_i", d.cb.max(1), "... from this SCU");
    m.output_c("segs_done_o", d.rsw, "segments whose last piece (group G-1) the SCU has taken");
    m.output_c("feat_idx_o", d.fx, "feature-buffer index of the beat's Gaussian");
    m.output_c("scu_valid_o", 1, "neo_scu in_valid_i");
    m.input_c("scu_ready_i", 1, "neo_scu in_ready_o");
    m.output_c("scu_empty_o", 1, "neo_scu in_empty_i");
    m.output_c("scu_last_o", 1, "neo_scu in_last_i");
    m.output_c("scu_final_o", 1, "neo_scu in_final_i");
    m.output_c("scu_resume_o", 1, "neo_scu in_resume_i");
    m.output_c("scu_sub_o", w.row_bits, "neo_scu in_sub_i (the list's group)");
    m.output_c("scu_origin_x_o", w.origin, "neo_scu in_origin_x_i");
    m.output_c("scu_origin_y_o", w.origin, "neo_scu in_origin_y_i");
    m.output_c("scu_cols_o", d.sb + 1, "neo_scu in_cols_i");
    m.output_c("scu_rows_o", d.sb + 1, "neo_scu in_rows_i");
    m.output_c("scu_out_ready_o", 1, "neo_scu out_ready_i: the pixel writer took the subtile");
}

/// `{group, SCU_IDX}`: the subtile of SCU `SCU` in subtile group `group` (`sub_w` bits).
fn scu_subtile(d: &Dims, group: &str) -> String {
    let sub = if d.cb == 0 { group.to_string() } else { format!("{{{group}, SCU_IDX}}") };
    resize(&sub, d.gw + d.cb, d.sub_w)
}

/// Routing into the FIFO.
fn route(m: &mut Module, d: &Dims) {
    let (ew, db) = (d.ew, d.db);
    m.blank();
    m.comment("Routing: lane u goes to this SCU when bit {group, SCU} of its bitmap is set.");
    m.wire_assign("route_sub", d.sub_w, scu_subtile(d, "res_group_i"));
    m.wire("route_mask", d.ni).vector("route_mask");
    m.localparam_int("SUBTILES", d.nsub);
    m.gen_for(
        "u",
        d.ni,
        "g_route",
        vec![
            Item::Wire { name: "bitmap".into(), width: d.nsub },
            Item::Assign { lhs: "bitmap".into(), rhs: "res_bitmaps_i[u*SUBTILES +: SUBTILES]".into() },
            Item::Assign { lhs: "route_mask[u]".into(), rhs: "res_lanes_i[u] & bitmap[route_sub]".into() },
        ],
    );
    m.wire_assign("push", 1, "res_fire_i & ((|route_mask) | res_seg_last_i)");
    m.blank();
    m.comment(format!(
        "FIFO of {FIFO_DEPTH} elements {{final, last, resume, lane mask, base}} (fields EL_*): a RAM (no reset)."
    ));
    let el = element_fields(d);
    el.declare(m);
    m.mem("fifo", ew, FIFO_DEPTH);
    m.reg("wr_ptr_q", db + 1).reg("rd_ptr_q", db + 1);
    m.wire("pop", 1);
    m.wire_assign("count", db + 1, "wr_ptr_q - rd_ptr_q");
    m.wire_assign("fifo_full", 1, format!("count == {}", lit(db + 1, FIFO_DEPTH as u64)));
    m.wire_assign("fifo_empty", 1, format!("count == {}", lit(db + 1, 0)));
    m.assign("full_o", "fifo_full");
    m.seq_noreset(vec![if_(
        "push",
        vec![set(
            format!("fifo[wr_ptr_q[{}:0]]", db - 1),
            "{res_list_last_i, res_seg_last_i, res_resume_i, route_mask, res_base_i}",
        )],
    )]);
    let one = lit(db + 1, 1);
    m.seq_d(
        Some(vec![set("wr_ptr_q", lit(db + 1, 0)), set("rd_ptr_q", lit(db + 1, 0))]),
        vec![
            if_("push", vec![set("wr_ptr_q", format!("wr_ptr_q + {one}"))]),
            if_("pop", vec![set("rd_ptr_q", format!("rd_ptr_q + {one}"))]),
        ],
    );
    m.comment("The FIFO head's fields.");
    m.wire_assign("head", ew, format!("fifo[rd_ptr_q[{}:0]]", db - 1));
    for f in el.fields() {
        m.wire_assign(format!("head_{}", f.name), f.width, el.get("head", &f.name));
    }
}

/// The FIFO element `{final, last, resume, lane mask, base}`.
fn element_fields(d: &Dims) -> Bundle {
    let b = Bundle::packed("EL", &[("base", d.fx), ("mask", d.ni), ("resume", 1), ("last", 1), ("final", 1)]);
    debug_assert_eq!(b.width(), d.ew);
    b
}

/// The current element and the list state.
fn element(m: &mut Module, d: &Dims) {
    let gw = d.gw;
    m.blank();
    m.comment("The current element (popped from the FIFO) and its list state.");
    m.reg("elem_valid_q", 1).reg("elem_base_q", d.fx).reg("elem_mask_q", d.ni);
    m.reg("elem_last_q", 1).reg("group_q", gw).reg("elem_final_q", 1).reg("elem_resume_q", 1);
    m.reg("out_ready_q", 1);
    m.comment("First beat of a piece: an empty piece that neither starts nor ends its subtile is skipped.");
    m.reg("piece_first_q", 1);
    m.comment("Segments whose last piece (group G-1) the SCU has taken, to release their bank.");
    m.reg("segs_done_q", d.rsw);
    m.wire("beat", 1).wire("elem_done", 1).wire("beat_last", 1).wire("rest", d.ni);
    m.seq_d(
        Some(vec![
            set("elem_valid_q", lit(1, 0)),
            set("group_q", lit(gw, 0)),
            set("out_ready_q", lit(1, 0)),
            set("piece_first_q", lit(1, 1)),
        ]),
        vec![
            if_("beat", vec![set("piece_first_q", "beat_last")]),
            if_("clear_i", vec![set("group_q", lit(gw, 0)), set("piece_first_q", lit(1, 1))]),
            if_("beat & beat_last", vec![set("group_q", format!("group_q + {}", lit(gw, 1)))]),
            if_else(
                "pop",
                vec![set("elem_valid_q", lit(1, 1))],
                vec![if_("elem_done", vec![set("elem_valid_q", lit(1, 0))])],
            ),
            set("out_ready_q", "pix_taken_i & (pix_scu_i == SCU_IDX)"),
        ],
    );
    m.seq_d(
        None,
        vec![if_else(
            "pop",
            vec![
                set("elem_base_q", "head_base"),
                set("elem_mask_q", "head_mask"),
                set("elem_resume_q", "head_resume"),
                set("elem_last_q", "head_last"),
                set("elem_final_q", "head_final"),
            ],
            vec![if_("beat", vec![set("elem_mask_q", "rest")])],
        )],
    );
    m.seq_d(
        Some(vec![set("segs_done_q", lit(d.rsw, 0))]),
        vec![if_else(
            "clear_i",
            vec![set("segs_done_q", lit(d.rsw, 0))],
            vec![if_(
                format!("beat & beat_last & (group_q == {})", lit(gw, d.groups as u64 - 1)),
                vec![set("segs_done_q", format!("segs_done_q + {}", lit(d.rsw, 1)))],
            )],
        )],
    );
    m.assign("segs_done_o", "segs_done_q");
    m.assign("busy_o", "elem_valid_q | ~fifo_empty");
    m.assign("scu_out_ready_o", "out_ready_q");
}

/// Beats to the SCU and the list inputs.
fn beats(m: &mut Module, cfg: &EngineConfig, d: &Dims) {
    let w = scu::ScuWidths::new(cfg);
    let ni = d.ni;
    let lb = bits_for(ni as u64 - 1);
    m.blank();
    m.comment("Beats: one per set mask bit, lowest first; one empty beat for an element with an empty mask.");
    let mut sel = lit(lb, 0);
    if ni > 1 {
        for u in (0..ni).rev() {
            sel = format!("elem_mask_q[{u}] ? {} : ({sel})", lit(lb, u as u64));
        }
    }
    m.wire_assign("lane", lb, sel);
    m.assign("feat_idx_o", format!("elem_base_q + {}", resize("lane", lb, d.fx)));
    m.assign("rest", format!("elem_mask_q & (elem_mask_q - {})", lit(ni, 1)));
    m.wire_assign("empty_beat", 1, "~(|elem_mask_q)");
    m.assign("beat_last", "elem_last_q & ~(|rest)");
    m.wire_assign("skip", 1, "piece_first_q & empty_beat & elem_last_q & elem_resume_q & ~elem_final_q");
    m.assign("beat", "elem_valid_q & (scu_ready_i | skip)");
    m.assign("elem_done", "beat & ~(|rest)");
    m.assign("pop", "~fifo_empty & (~elem_valid_q | elem_done)");
    m.assign("scu_valid_o", "elem_valid_q & ~skip");
    m.assign("scu_empty_o", "empty_beat");
    m.assign("scu_last_o", "beat_last");
    m.assign("scu_final_o", "elem_final_q");
    m.assign("scu_resume_o", "elem_resume_q");
    m.assign("scu_sub_o", resize("group_q", d.gw, w.row_bits));
    m.blank();
    m.comment("The list's subtile {group, SCU}: origin and the columns / rows inside the image.");
    m.wire_assign("sub", d.sub_w, scu_subtile(d, "group_q"));
    subtile_origin(m, d);
    m.assign("scu_origin_x_o", resize("origin_x", d.ow, w.origin));
    m.assign("scu_origin_y_o", resize("origin_y", d.ow, w.origin));
    m.assign("scu_cols_o", "cols");
    m.assign("scu_rows_o", "rows");
}

/// `origin_{x,y}` (`ow` bits) and the inside `cols` / `rows` of subtile `sub`.
fn subtile_origin(m: &mut Module, d: &Dims) {
    let (side_w, sb, tl, ow) = (d.side_w, d.sb, d.tl, d.ow);
    let sub = Bundle::packed("SUB", &[("x", side_w), ("y", side_w)]);
    m.comment("The subtile index's fields SUB_*: {row, column} (row-major).");
    sub.declare(m);
    for (a, tile, dim, n) in [("x", "tile_x_i", "width_i", "cols"), ("y", "tile_y_i", "height_i", "rows")] {
        let idx = sub.get("sub", a);
        m.wire_assign(
            format!("origin_{a}"),
            ow,
            format!(
                "{} + {}",
                resize(&format!("{{{tile}, {}}}", lit(tl, 0)), d.tb + tl, ow),
                resize(&format!("{{{idx}, {}}}", lit(sb, 0)), side_w + sb, ow)
            ),
        );
        m.wire_assign(format!("left_{a}"), ow, format!("{} - origin_{a}", resize(dim, ow - 1, ow)));
        m.wire_assign(
            n,
            sb + 1,
            format!(
                "({} <= origin_{a}) ? {} : ((left_{a} > {}) ? {} : left_{a}[{sb}:0])",
                resize(dim, ow - 1, ow),
                lit(sb + 1, 0),
                lit(ow, d.s as u64),
                lit(sb + 1, d.s as u64)
            ),
        );
    }
}
