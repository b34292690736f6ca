//! WALK of the raster core: the segment of bank `walk_bank_q` through the ITUs, a quad of
//! `raster_itus` entries per cycle, once per subtile group. Group 0 tests every quad and records,
//! per quad, the groups it touches (`quad_hit`); a later group walks only those quads (a group
//! touched by no quad walks quad 0 alone, to end its pieces). Each quad's sideband goes through
//! a copy of the ITU pipeline, and group 0's results give every entry's valid bit (`hbuf`).

use super::{feature_word, mask_lit, Dims};
use crate::emit::bundle::Bundle;
use crate::emit::expr::{lit, resize, slice};
use crate::emit::{if_, if_else, set, Instance, Item, Module};
use crate::units::itu;
use neo_golden::engine::EngineConfig;

/// The walk position and the quad skipping.
pub(super) fn walk(m: &mut Module, d: &Dims) {
    let (fa, sl, gw, nq, qb) = (d.fa, d.sl, d.gw, d.nq, d.qb);
    let lane_bits = d.ni.trailing_zeros();
    m.blank();
    m.comment(format!(
        "WALK: {} table entries (a quad) per cycle through the ITUs, once per subtile group.",
        d.ni
    ));
    m.reg("walk_on_q", 1).reg("walk_bank_q", d.bkb).reg("group_q", gw).reg("quad_base_q", fa);
    m.comment(
        "Later groups: wait for group 0's results (seek), then go to the first quad touching the group.",
    );
    m.reg("seek_q", 1).reg("g0_done_q", 1);
    m.wire("walk_start", 1);
    m.wire_assign("walk_seg_len", sl, "bank_len_q[walk_bank_q]");
    m.wire_assign("walk_seg_start", d.lw, "bank_start_q[walk_bank_q]");
    m.wire_assign("last_seg", 1, format!("(len_q - walk_seg_start) <= {}", lit(d.lw, d.f as u64)));
    m.wire_assign("last_group", 1, format!("group_q == {}", lit(gw, d.groups as u64 - 1)));
    m.wire_assign("walk", 1, "running & walk_on_q & ~seek_q");
    m.wire_assign(
        "quad_end",
        sl + 1,
        format!("{} + {}", resize("quad_base_q", fa, sl + 1), lit(sl + 1, d.ni as u64)),
    );
    m.blank();
    m.comment(
        "Quad skipping: quad_hit[{bank, q}][g] = quad q of the segment touches group g (group 0's walk).",
    );
    m.mem("quad_hit", d.groups, d.nbk * nq);
    m.wire_assign("quad_cur", qb, if nq == 1 { lit(1, 0) } else { slice("quad_base_q", fa - 1, lane_bits) });
    m.comment("quad_touch[q]: quad q is in the segment and touches the walked group.");
    m.wire("quad_touch", nq);
    let touch =
        |q: &str, first: &str| format!("quad_hit[{{walk_bank_q, {q}}}][group_q] & ({first} < walk_seg_len)");
    if nq == 1 {
        m.assign("quad_touch", touch(&lit(qb, 0), &lit(sl, 0)));
    } else {
        let items = vec![
            Item::LocalParam { name: "QUAD".into(), width: qb, value: "q".into() },
            Item::LocalParam { name: "QUAD_FIRST".into(), width: sl, value: format!("q * {}", d.ni) },
            Item::Assign { lhs: "quad_touch[q]".into(), rhs: touch("QUAD", "QUAD_FIRST") },
        ];
        m.gen_for("q", nq, "g_quad", items);
    }
    m.wire_assign("quad_above", nq, format!("quad_touch & (({{{nq}{{1'b1}}}} << quad_cur) << 1)"));
    for (src, dst) in [("quad_touch", "quad_first"), ("quad_above", "quad_next")] {
        m.wire_assign(format!("{dst}_oh"), nq, format!("{src} & (~{src} + {})", lit(nq, 1)));
        // Bit b of the index: the one-hot word has its bit at a quad whose index has bit b.
        let bits: Vec<String> = (0..qb)
            .rev()
            .map(|b| format!("(|({dst}_oh & {}))", mask_lit(nq, |q| (q >> b) & 1 == 1)))
            .collect();
        m.wire_assign(format!("{dst}_idx"), qb, format!("{{{}}}", bits.join(", ")));
        m.wire_assign(format!("unused_{dst}_oh0"), 1, format!("{dst}_oh[0]"));
    }
    let to_base = |idx: &str| -> String {
        if lane_bits == 0 {
            resize(idx, qb, fa)
        } else if nq == 1 {
            lit(fa, 0)
        } else {
            format!("{{{idx}, {}}}", lit(lane_bits, 0))
        }
    };
    m.wire_assign("quad_next_base", fa, to_base("quad_next_idx"));
    m.wire_assign("quad_first_base", fa, to_base("quad_first_idx"));
    m.wire_assign(
        "last_quad",
        1,
        format!(
            "(group_q == {}) ? (quad_end >= {}) : ~(|quad_above)",
            lit(gw, 0),
            resize("walk_seg_len", sl, sl + 1)
        ),
    );
}

/// The ITUs, one per lane of the quad, in lockstep.
pub(super) fn itus(m: &mut Module, cfg: &EngineConfig, d: &Dims) {
    let (ni, nsub, groups, nc, fa) = (d.ni, d.nsub, d.groups, d.nc, d.fa);
    let tg = cfg.itu_tag_bits;
    m.blank();
    m.comment("ITUs: lane u tests entry quad_base_q + u; they share every control input (lockstep).");
    m.wire("lane_valid", ni).wire("itu_in_readys", ni).wire("itu_out_valids", ni);
    m.wire("itu_bitmaps", ni * nsub).wire("itu_hits", ni).wire("itu_tags", ni * tg);
    // One bit per ITU, indexed even with one ITU.
    for v in ["lane_valid", "itu_in_readys", "itu_out_valids", "itu_hits"] {
        m.vector(v);
    }
    m.comment("The results are taken when no routing FIFO is full.");
    m.wire("itu_out_ready", 1);
    m.comment("Per lane, the subtile groups its bitmap touches (group 0's walk records them per quad).");
    m.wire("itu_groups", ni * groups);
    m.comment("A bitmap's subtiles (group-major: group g's at [g * SCUS +: SCUS]), the SCUs and the groups.");
    m.localparam_int("SUBTILES", nsub).localparam_int("SCUS", nc).localparam_int("GROUPS", groups);
    let mut items = vec![
        Item::LocalParam { name: "LANE".into(), width: fa, value: "u".into() },
        Item::Wire { name: "entry".into(), width: fa },
        Item::Assign { lhs: "entry".into(), rhs: "quad_base_q + LANE".into() },
        Item::Wire { name: "idx".into(), width: d.fx },
        Item::Assign { lhs: "idx".into(), rhs: "{walk_bank_q, entry}".into() },
    ];
    let feat = feature_word(cfg, d);
    for (name, field) in [("present", "present"), ("mean", "itu_mean"), ("geom", "itu_geom")] {
        items.push(Item::Wire { name: name.into(), width: feat.width_of(field) });
        items.push(Item::Assign { lhs: name.into(), rhs: feat.get("fbuf[idx]", field) });
    }
    items.push(Item::Assign {
        lhs: "lane_valid[u]".into(),
        rhs: format!("({} < walk_seg_len) & present", resize("entry", fa, d.sl)),
    });
    items.push(Item::Wire { name: "bitmap".into(), width: nsub });
    let c = |p: &str, e: String| (p.to_string(), e);
    items.push(Item::Instance(Instance {
        module: itu::NAME.into(),
        name: "u_itu".into(),
        params: Vec::new(),
        conns: vec![
            c("clk_i", "clk_i".into()),
            c("rst_ni", "rst_ni".into()),
            c("in_valid_i", "walk".into()),
            c("in_ready_o", "itu_in_readys[u]".into()),
            c("mean_i", "mean".into()),
            c("geom_i", "geom".into()),
            c("tile_x_i", "tile_x_q".into()),
            c("tile_y_i", "tile_y_q".into()),
            c("tag_i", lit(tg, 0)),
            c("out_valid_o", "itu_out_valids[u]".into()),
            c("out_ready_i", "itu_out_ready".into()),
            c("bitmap_o", "bitmap".into()),
            c("hit_o", "itu_hits[u]".into()),
            c("tag_o", format!("itu_tags[u*{tg} +: {tg}]")),
        ],
    }));
    items.push(Item::Assign { lhs: "itu_bitmaps[u*SUBTILES +: SUBTILES]".into(), rhs: "bitmap".into() });
    m.gen_for("u", ni, "g_itu", items);
    // Lane u's bitmap holds group g's subtiles at [g * SCUs +: SCUs], so group g of lane u is
    // run u * groups + g of the packed bitmaps.
    m.comment("Group k % G of lane k / G: the OR of its SCUs' subtile bits.");
    m.gen_for(
        "k",
        ni * groups,
        "g_touch",
        vec![Item::Assign { lhs: "itu_groups[k]".into(), rhs: "|itu_bitmaps[k*SCUS +: SCUS]".into() }],
    );
    m.wire_assign("itu_in_ready", 1, "&itu_in_readys");
    m.wire_assign("itu_out_valid", 1, "&itu_out_valids");
    m.wire_assign("itu_fire", 1, "walk & itu_in_ready");
    m.wire_assign("res_fire", 1, "itu_out_valid & itu_out_ready");
    m.wire_assign("unused_tags", 1, "^itu_tags");
}

/// The quad sideband and group 0's results.
pub(super) fn results(m: &mut Module, d: &Dims) {
    let (ni, gw, fa, bkb) = (d.ni, d.gw, d.fa, d.bkb);
    let fields = [
        ("lanes", ni),
        ("entry", fa),
        ("bank", bkb),
        ("group", gw),
        ("seg_last", 1),
        ("list_last", 1),
        ("resume", 1),
    ];
    let info = Bundle::packed("QI", &fields);
    let sbw = info.width();
    m.blank();
    m.comment(format!(
        "Quad sideband through {} stages that advance with the ITUs (in_ready_o = their stage enable):",
        itu::LATENCY
    ));
    m.comment("{resume, list last, segment last (last quad), group, bank, entry, lane valids}: fields QI_*.");
    info.declare(m);
    m.wire_assign(
        "quad_info",
        sbw,
        format!(
            "{{(walk_seg_start != {}), (last_quad & last_seg), last_quad, group_q, walk_bank_q, quad_base_q, lane_valid}}",
            lit(d.lw, 0)
        ),
    );
    let mut sh = Vec::new();
    for k in 1..=itu::LATENCY {
        m.reg(format!("quad_info{k}_q"), sbw);
        let src = if k == 1 { "quad_info".to_string() } else { format!("quad_info{}_q", k - 1) };
        sh.push(set(format!("quad_info{k}_q"), src));
    }
    m.seq_d(None, vec![if_("itu_in_ready", sh)]);
    m.comment("The result's sideband fields.");
    let last = format!("quad_info{}_q", itu::LATENCY);
    for (name, width) in fields {
        m.wire_assign(format!("res_{name}"), width, info.get(&last, name));
    }
    // One bit per ITU, indexed even with one ITU.
    m.vector("res_lanes");
    m.wire_assign("res_base", d.fx, "{res_bank, res_entry}");
    let ifl = d.inflight_bits();
    m.reg("inflight_q", ifl);
    m.seq_d(
        Some(vec![set("inflight_q", lit(ifl, 0))]),
        vec![if_else(
            "itu_fire & ~res_fire",
            vec![set("inflight_q", format!("inflight_q + {}", lit(ifl, 1)))],
            vec![if_(
                "~itu_fire & res_fire",
                vec![set("inflight_q", format!("inflight_q - {}", lit(ifl, 1)))],
            )],
        )],
    );
    let g0 = format!("res_fire & (res_group == {})", lit(gw, 0));
    m.comment("Group 0's results: every entry's valid bit (the OR over all subtiles).");
    let hb = (0..ni)
        .map(|u| set(format!("hbuf[res_base + {}]", lit(d.fx, u as u64)), format!("itu_hits[{u}]")))
        .collect();
    m.seq_noreset(vec![if_(g0.clone(), hb)]);
    m.comment("Group 0's results also give each quad's groups (quad_hit) and, with its last quad, g0_done.");
    let lanes: Vec<String> = (0..ni)
        .map(|u| format!("({{GROUPS{{res_lanes[{u}]}}}} & itu_groups[{u}*GROUPS +: GROUPS])"))
        .collect();
    m.wire_assign("res_quad_hit", d.groups, lanes.join(" | "));
    let quad = if d.nq == 1 {
        "res_bank".to_string()
    } else {
        format!("{{res_bank, {}}}", slice("res_entry", fa - 1, ni.trailing_zeros()))
    };
    m.wire_assign("res_quad", bkb + if d.nq == 1 { 0 } else { d.qb }, quad);
    m.seq_noreset(vec![if_(g0.clone(), vec![set("quad_hit[res_quad]", "res_quad_hit")])]);
    m.seq_d(
        Some(vec![set("g0_done_q", lit(1, 0))]),
        vec![if_else(
            "walk_start",
            vec![set("g0_done_q", lit(1, 0))],
            vec![if_(format!("{g0} & res_seg_last"), vec![set("g0_done_q", lit(1, 1))])],
        )],
    );
}

/// The main state and the walk position: RUN walks every group of each loaded segment, then
/// DRAIN waits for the SCUs, the write-back and the pixel writer.
pub(super) fn walk_state(m: &mut Module, d: &Dims) {
    let (fa, gw, bkb) = (d.fa, d.gw, d.bkb);
    m.blank();
    m.comment("Main state and walk: every group of the segment in bank walk_bank_q; a later group starts at");
    m.comment("its first quad once group 0's results are in.");
    let on_cmd = vec![
        set("state_q", "S_RUN"),
        set("tile_x_q", "cmd_tile_x_i"),
        set("tile_y_q", "cmd_tile_y_i"),
        set("width_q", "cmd_width_i"),
        set("height_q", "cmd_height_i"),
        set("table_q", "cmd_table_i"),
        set("feat_base_q", "cmd_feat_i"),
        set("pix_base_q", "cmd_pix_i"),
        set("len_q", "cmd_len_i"),
        set("walk_on_q", lit(1, 0)),
        set("walk_bank_q", lit(bkb, 0)),
    ];
    let next_quad = if_else(
        "~last_quad",
        vec![set(
            "quad_base_q",
            format!(
                "(group_q == {}) ? (quad_base_q + {}) : quad_next_base",
                lit(gw, 0),
                lit(fa, d.ni as u64)
            ),
        )],
        vec![
            set("quad_base_q", lit(fa, 0)),
            if_else(
                "~last_group",
                vec![set("group_q", format!("group_q + {}", lit(gw, 1))), set("seek_q", lit(1, 1))],
                vec![
                    set("walk_on_q", lit(1, 0)),
                    set("walk_bank_q", format!("walk_bank_q + {}", lit(bkb, 1))),
                    if_("last_seg", vec![set("state_q", "S_DRAIN")]),
                ],
            ),
        ],
    );
    let run = vec![
        if_(
            "walk_start",
            vec![
                set("walk_on_q", lit(1, 1)),
                set("group_q", lit(gw, 0)),
                set("quad_base_q", lit(fa, 0)),
                set("seek_q", lit(1, 0)),
            ],
        ),
        if_(
            "seek_q & g0_done_q",
            vec![
                set("seek_q", lit(1, 0)),
                set("quad_base_q", format!("(|quad_touch) ? quad_first_base : {}", lit(fa, 0))),
            ],
        ),
        if_("itu_fire", vec![next_quad]),
    ];
    m.seq_d(
        Some(vec![
            set("state_q", "S_IDLE"),
            set("done_q", lit(1, 0)),
            set("quad_base_q", lit(fa, 0)),
            set("seek_q", lit(1, 0)),
            set("walk_on_q", lit(1, 0)),
            set("walk_bank_q", lit(bkb, 0)),
            set("group_q", lit(gw, 0)),
        ]),
        vec![
            set("done_q", lit(1, 0)),
            crate::emit::Stmt::Case(
                "state_q".into(),
                vec![
                    ("S_IDLE".into(), vec![if_("cmd_valid_i", on_cmd)]),
                    ("S_RUN".into(), run),
                    (
                        "S_DRAIN".into(),
                        vec![if_(
                            "drained & pix_all_done",
                            vec![set("state_q", "S_IDLE"), set("done_q", lit(1, 1))],
                        )],
                    ),
                ],
                vec![set("state_q", "S_IDLE")],
            ),
        ],
    );
    m.assign("done_o", "done_q");
}
