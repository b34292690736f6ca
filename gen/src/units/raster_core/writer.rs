//! The raster core's memory port: the fixed-priority arbitration, the pixel writer (finished
//! subtiles, one row of `S` pixels per write) and the table write-back.

use super::{feature_word, space, table_word, Dims, ROW_RGB, SUB_RGB};
use crate::emit::bundle::{Bundle, Field};
use crate::emit::expr::{lit, resize};
use crate::emit::{if_, if_else, set, Module};
use neo_golden::engine::EngineConfig;
use neo_golden::raster::RGB_BITS;

/// The request arbitration: pixel writes first, then the write-back, then the loader's reads.
pub(super) fn arbitration(m: &mut Module, d: &Dims) {
    let cb_bits = d.cb.max(1);
    m.blank();
    m.comment("Memory port: pixel writes first, then the write-back, then reads (fixed priority).");
    m.wire("pix_valid", 1).wire("wb_valid", 1).wire("rd_valid", 1);
    m.comment("The pixel writer's SCU (subtile % SCUs) and its last row (see the pixel writer).");
    m.wire("pix_scu", cb_bits).wire("pix_last_row", 1);
    m.wire_assign("pix_grant", 1, "pix_valid & mem_req_ready_i");
    m.wire_assign("wb_grant", 1, "wb_valid & ~pix_valid & mem_req_ready_i");
    m.wire_assign("rd_grant", 1, "rd_valid & ~pix_valid & ~wb_valid & mem_req_ready_i");
    m.assign("mem_req_valid_o", "pix_valid | wb_valid | rd_valid");
    m.assign("mem_rsp_ready_o", lit(1, 1));
}

/// The pixel writer: subtiles in order, SCU = subtile % SCUs.
pub(super) fn pixels(m: &mut Module, d: &Dims) {
    let (sub_w, sb, side_w, s, tl, cb, nc) = (d.sub_w, d.sb, d.side_w, d.s, d.tl, d.cb, d.nc);
    m.blank();
    m.comment(format!(
        "Pixel writer: subtiles in order, SCU = subtile % {nc}, one row of {s} pixels per write."
    ));
    m.comment("The subtile being written (the top bit: every subtile written) and its row.");
    m.comment("pix_sub_q fields PS_*: {done, sy, sx}; its SCU is the subtile's low bits.");
    let mut fields = vec![
        Field { name: "sx".into(), lsb: 0, width: side_w },
        Field { name: "sy".into(), lsb: side_w, width: side_w },
        Field { name: "done".into(), lsb: sub_w, width: 1 },
    ];
    if cb > 0 {
        fields.push(Field { name: "scu".into(), lsb: 0, width: cb });
    }
    let ps = Bundle::placed("PS", fields);
    ps.declare(m);
    m.reg("pix_sub_q", sub_w + 1).reg("pix_row_q", sb);
    m.assign("pix_scu", if cb == 0 { lit(1, 0) } else { ps.get("pix_sub_q", "scu") });
    m.wire_assign("pix_sx", side_w, ps.get("pix_sub_q", "sx"));
    m.wire_assign("pix_sy", side_w, ps.get("pix_sub_q", "sy"));
    m.wire_assign("pix_all_done", 1, ps.get("pix_sub_q", "done"));
    m.assign("pix_last_row", format!("pix_row_q == {}", lit(sb, s as u64 - 1)));
    // Lane k of a packed vector of `width`-bit lanes; the selects stay a chain of constant
    // part-selects (a variable `[sel*W +: W]` would synthesise as a barrel shifter).
    let part = |v: &str, k: u32, width: &str| format!("{v}[{k}*{width} +: {width}]");
    let mut rgb = part("scu_rgb", nc - 1, SUB_RGB);
    for j in (0..nc - 1).rev() {
        rgb =
            format!("((pix_scu == {}) ? {} : {rgb})", lit(cb.max(1), j as u64), part("scu_rgb", j, SUB_RGB));
    }
    m.wire_assign("pix_rgb", RGB_BITS * s * s, rgb);
    m.assign("pix_valid", "~pix_all_done & scu_out_valid[pix_scu] & ~scu_taken[pix_scu]");
    let pa = 2 * tl;
    m.wire_assign(
        "pix_off",
        pa,
        format!(
            "{{pix_sy, pix_row_q, {}}} + {}",
            lit(tl, 0),
            resize(&format!("{{pix_sx, {}}}", lit(sb, 0)), side_w + sb, pa)
        ),
    );
    m.wire_assign("pix_addr", d.aw, format!("pix_base_q + {}", resize("pix_off", pa, d.aw)));
    let mut row = part("pix_rgb", s - 1, ROW_RGB);
    for r in (0..s - 1).rev() {
        row = format!("(pix_row_q == {}) ? {} : ({row})", lit(sb, r as u64), part("pix_rgb", r, ROW_RGB));
    }
    m.wire_assign("pix_data", d.rw, row);
    m.seq_d(
        Some(vec![set("pix_sub_q", lit(sub_w + 1, 1 << sub_w)), set("pix_row_q", lit(sb, 0))]),
        vec![
            if_("cmd_fire", vec![set("pix_sub_q", lit(sub_w + 1, 0)), set("pix_row_q", lit(sb, 0))]),
            if_(
                "pix_grant",
                vec![
                    set("pix_row_q", format!("pix_row_q + {}", lit(sb, 1))),
                    if_("pix_last_row", vec![set("pix_sub_q", format!("pix_sub_q + {}", lit(sub_w + 1, 1)))]),
                ],
            ),
        ],
    );
}

/// The write-back of a segment once its group-0 results are in.
pub(super) fn write_back(m: &mut Module, cfg: &EngineConfig, d: &Dims) {
    let (fa, sl, kb, ib, bkb, gw) = (d.fa, d.sl, d.kb, d.ib, d.bkb, d.gw);
    let (feat, tw) = (feature_word(cfg, d), table_word(d));
    m.blank();
    m.comment("Write-back of the segment once its group-0 results are in: {present & OR, present ? depth key : key, id}.");
    m.reg("wb_busy_q", 1).reg("wb_ptr_q", fa).reg("wb_bank_q", bkb);
    m.assign("wb_valid", "wb_busy_q");
    m.wire_assign("wb_idx", d.fx, "{wb_bank_q, wb_ptr_q}");
    m.wire_assign("wb_start", d.lw, "bank_start_q[wb_bank_q]");
    m.comment("The entry's feature-word fields and its table word {key, id}.");
    m.wire_assign("wb_present", 1, feat.get("fbuf[wb_idx]", "present"));
    // The key field takes the depth key (its low key_bits bits when it is wider).
    let dkw = feat.width_of("depth_key");
    m.wire_assign("wb_depth_key", dkw, feat.get("fbuf[wb_idx]", "depth_key"));
    m.wire_assign("wb_old_key", kb, tw.get("tbuf[wb_idx]", "key"));
    m.wire_assign("wb_id", ib, tw.get("tbuf[wb_idx]", "id"));
    m.wire_assign("wb_key", kb, format!("wb_present ? {} : wb_old_key", resize("wb_depth_key", dkw, kb)));
    m.wire_assign(
        "wb_entry",
        d.eb,
        resize("{(wb_present & hbuf[wb_idx]), wb_key, wb_id}", 1 + kb + ib, d.eb),
    );
    m.wire_assign(
        "wb_addr",
        d.aw,
        format!("table_q + {} + {}", resize("wb_start", d.lw, d.aw), resize("wb_ptr_q", fa, d.aw)),
    );
    m.wire_assign("wb_next", sl, format!("{} + {}", resize("wb_ptr_q", fa, sl), lit(sl, 1)));
    m.wire_assign("wb_end", 1, "wb_next == bank_len_q[wb_bank_q]");
    m.wire_assign("res_seg_len", sl, "bank_len_q[res_bank]");
    m.seq_d(
        Some(vec![set("wb_busy_q", lit(1, 0)), set("wb_ptr_q", lit(fa, 0)), set("wb_bank_q", lit(bkb, 0))]),
        vec![
            if_(
                format!(
                    "res_fire & (res_group == {}) & res_seg_last & (res_seg_len != {})",
                    lit(gw, 0),
                    lit(sl, 0)
                ),
                vec![set("wb_busy_q", lit(1, 1)), set("wb_ptr_q", lit(fa, 0)), set("wb_bank_q", "res_bank")],
            ),
            if_(
                "wb_grant",
                vec![if_else(
                    "wb_end",
                    vec![set("wb_busy_q", lit(1, 0))],
                    vec![set("wb_ptr_q", format!("wb_ptr_q + {}", lit(fa, 1)))],
                )],
            ),
        ],
    );
}

/// The write-back's disorder signals (golden `adaptive::writeback_signals`, issue 14): over the
/// entries written back in table order, the valid ones are counted (`wbs_len_q`), a running
/// maximum of `{key, id}` and its position are kept, and a valid entry below the maximum
/// raises the reach to its distance from the maximum's position. Cleared by a command; the
/// counts are final with `done_o` and hold until the next command.
pub(super) fn wb_signals(m: &mut Module, d: &Dims) {
    let (lw, kb, ib) = (d.lw, d.kb, d.ib);
    let rank = kb + ib;
    m.blank();
    m.comment("Write-back signals: valid entries, running maximum {key, id} and its position, reach.");
    m.reg("wbs_len_q", lw)
        .reg("wbs_max_q", rank)
        .reg("wbs_at_q", lw)
        .reg("wbs_any_q", 1)
        .reg("wbs_reach_q", lw);
    m.wire_assign("wbs_live", 1, "wb_grant & wb_present & hbuf[wb_idx]");
    m.wire_assign("wbs_rank", rank, "{wb_key, wb_id}");
    m.wire_assign("wbs_behind", 1, "wbs_any_q & (wbs_rank < wbs_max_q)");
    m.wire_assign("wbs_dist", lw, "wbs_len_q - wbs_at_q");
    m.seq_d(
        Some(vec![
            set("wbs_len_q", lit(lw, 0)),
            set("wbs_max_q", lit(rank, 0)),
            set("wbs_at_q", lit(lw, 0)),
            set("wbs_any_q", lit(1, 0)),
            set("wbs_reach_q", lit(lw, 0)),
        ]),
        vec![if_else(
            "cmd_fire",
            vec![set("wbs_len_q", lit(lw, 0)), set("wbs_any_q", lit(1, 0)), set("wbs_reach_q", lit(lw, 0))],
            vec![if_(
                "wbs_live",
                vec![
                    set("wbs_len_q", format!("wbs_len_q + {}", lit(lw, 1))),
                    if_else(
                        "wbs_behind",
                        vec![if_("wbs_dist > wbs_reach_q", vec![set("wbs_reach_q", "wbs_dist")])],
                        vec![
                            set("wbs_max_q", "wbs_rank"),
                            set("wbs_at_q", "wbs_len_q"),
                            set("wbs_any_q", lit(1, 1)),
                        ],
                    ),
                ],
            )],
        )],
    );
    m.assign("done_wb_len_o", "wbs_len_q");
    m.assign("done_wb_reach_o", "wbs_reach_q");
}

/// The request multiplexer.
pub(super) fn requests(m: &mut Module, d: &Dims) {
    let bl = d.bl;
    m.blank();
    m.comment("The granted request.");
    m.assign("mem_req_write_o", "pix_valid | wb_valid");
    m.assign(
        "mem_req_space_o",
        format!(
            "pix_valid ? {} : (wb_valid ? {} : (rd_table ? {} : {}))",
            lit(2, space::PIXEL),
            lit(2, space::TABLE),
            lit(2, space::TABLE),
            lit(2, space::FEATURE)
        ),
    );
    m.assign("mem_req_addr_o", "pix_valid ? pix_addr : (wb_valid ? wb_addr : rd_addr)");
    m.assign(
        "mem_req_len_o",
        format!("pix_valid ? {} : (wb_valid ? {} : rd_len)", lit(bl, d.s as u64), lit(bl, 1)),
    );
    m.assign(
        "mem_wdata_o",
        format!("pix_valid ? {} : {}", resize("pix_data", d.rw, d.wdb), resize("wb_entry", d.eb, d.wdb)),
    );
}
