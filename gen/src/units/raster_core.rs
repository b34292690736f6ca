//! `neo_raster_core`: one Rasterization Core (paper Section 5.4, Fig. 14): `raster_itus`
//! [`super::itu`] units and `raster_scus` [`super::scu`] units, a banked feature buffer, a command port
//! and a memory-request port. Renders one 64x64 tile from its sorted table, bit-exact with golden
//! [`neo_golden::raster::raster_tile`], and writes each table entry back with the current depth
//! key and the ITU's cumulative-OR valid bit (golden `pipeline::frame`'s deferred write-back).
//! The protocols, the schedule and the timing are documented in `docs/rtl.md` ("Raster core").
//!
//! # Schedule
//! The table is processed in *segments* of at most `F = raster_feature_buffer` entries (one
//! segment when the table fits). LOAD reads the segment's table entries (bursts) and then, per
//! entry, its feature word (`feature base + id`) into the buffers. The subtiles are blended in
//! `G = subtiles / raster_scus` *groups* of `raster_scus` consecutive subtiles (row-major, SCU
//! `j` takes subtile `g * raster_scus + j`). WALK issues the segment to the ITUs,
//! `raster_itus` entries (a *quad*) per cycle, once per group (group 0 every quad, a later group
//! only the quads group 0's results showed to touch it); each ITU result is routed, per
//! SCU, into a FIFO of `{final, last, resume, lane mask, base}` elements, and a feeder per SCU
//! sends the masked entries' features to its SCU in table order. The FIFOs decouple the two: the
//! ITUs test the next group while the SCUs blend the current one (Fig. 14). Each segment is
//! loaded once and walked for every group (paper Section 5.4: "writes the intermediate pixel
//! values to the pixel buffer and proceeds to the next group"): one group's walk of a segment
//! is a *piece* of each of its subtiles' lists. A piece that is not the subtile's last saves the
//! subtile's pixel state in its SCU's state bank (`neo_scu` `in_final_i` low), and the next
//! segment's piece resumes from it (`in_resume_i`). The segments go round
//! `raster_feature_banks` banks: the loader fills the next bank while the current one is walked
//! and blended, and a bank is refilled once its segment is walked, every SCU has taken its last
//! piece and its write-back is done.
//!
//! Group 0's ITU results give every entry's valid bit (the bitmap covers all subtiles); the
//! write-back of entry `i` (`{valid = present & |bitmap, key = present ? depth_key : old key,
//! id}`) follows once the segment's group-0 results are in. A feature word with its `present`
//! bit clear is a Gaussian culled this frame (no feature entry): it is not rasterised, its
//! valid bit is cleared and its key kept (golden `raster_phase`). Finished subtiles are written
//! one pixel row (`S` pixels, 24 bits each) per request.

use crate::config::GenConfig;
use crate::emit::expr::{bits_for, lit};
use crate::emit::{conns, if_, if_else, set, Module, Stmt};
use crate::units::{itu, scu};

/// Module name.
pub const NAME: &str = "neo_raster_core";

/// Entries per routing FIFO (one per SCU): how far the ITUs may run ahead of an SCU.
pub const FIFO_DEPTH: u32 = 64;

/// Memory spaces (`mem_req_space_o`).
pub mod space {
    /// Table entries `{valid, key, id}` (read in bursts, written back one per request).
    pub const TABLE: u64 = 0;
    /// Feature words `{present, entry}` indexed by Gaussian id (read one per request).
    pub const FEATURE: u64 = 1;
    /// Pixels (write: one subtile row of `S` pixels at a pixel address).
    pub const PIXEL: u64 = 2;
}

const S_IDLE: u64 = 0;
const S_RUN: u64 = 1;
const S_DRAIN: u64 = 2;
const L_IDLE: u64 = 0;
const L_TABLE: u64 = 1;
const L_FEAT: u64 = 2;

/// Width of a feature word: the packed entry plus the `present` bit on top.
pub fn feature_word_bits(cfg: &GenConfig) -> u32 {
    cfg.feature_format().bits_per_entry() + 1
}

/// Width of the command's image width / height: pixels of `2^tile_bits` tiles.
pub fn image_bits(cfg: &GenConfig) -> u32 {
    cfg.tile_bits + cfg.raster_config().tile.trailing_zeros()
}

/// Width of `mem_wdata_o`: a pixel row (`S` x 24 bits) or a table entry, whichever is wider.
pub fn wdata_bits(cfg: &GenConfig) -> u32 {
    (cfg.raster_config().subtile * 24).max(cfg.entry_bits())
}

/// `x` (`from` bits) resized to `to` bits (zero-extended or truncated).
fn resize(x: &str, from: u32, to: u32) -> String {
    match from.cmp(&to) {
        std::cmp::Ordering::Equal => x.to_string(),
        std::cmp::Ordering::Greater => format!("{x}[{}:0]", to - 1),
        std::cmp::Ordering::Less => format!("{{{}, {x}}}", lit(to - from, 0)),
    }
}

/// The raster core for `cfg`.
pub fn module(cfg: &GenConfig) -> Module {
    let fmt = cfg.feature_format();
    let rc = cfg.raster_config();
    let w = scu::ScuWidths::new(cfg);
    let layout = fmt.layout();
    let field = |n: &str| {
        let f = layout.iter().find(|f| f.name == n).unwrap_or_else(|| panic!("feature field {n}"));
        (f.lsb, f.width)
    };
    let ni = cfg.raster_itus as u32;
    let nc = cfg.raster_scus as u32;
    let nsub = rc.subtiles_per_tile();
    let nside = rc.subtiles_per_side();
    let groups = nsub / nc;
    let gw = bits_for(groups as u64 - 1);
    let cb = nc.trailing_zeros();
    let sub_w = nsub.trailing_zeros(); // subtile index bits
    let side_w = nside.trailing_zeros();
    let s = rc.subtile;
    let sb = s.trailing_zeros();
    let t = rc.tile;
    let tl = t.trailing_zeros();
    let f = cfg.raster_feature_buffer as u32;
    let nbk = cfg.raster_feature_banks as u32;
    let bkb = nbk.trailing_zeros(); // bank index bits
    let rsw = bkb + 2; // segment counters: up to nbk segments in flight
    let fa = bits_for(f as u64 - 1);
    let fx = fa + bkb; // buffer index {bank, entry}
    let sl = bits_for(f as u64);
    let fw = feature_word_bits(cfg);
    let present = fw - 1;
    let kb = cfg.key_bits as u32;
    let ib = cfg.id_bits as u32;
    let tw = kb + ib; // table buffer word {key, id}
    let eb = cfg.entry_bits();
    let aw = cfg.addr_bits;
    let lw = cfg.len_bits;
    let tb = cfg.tile_bits;
    let wd = image_bits(cfg);
    let ow = wd + 1;
    let bl = bits_for((cfg.burst as u64).max(rc.subtile as u64)); // a burst or a pixel row
    let wdb = wdata_bits(cfg);
    let rw = s * 24;
    let tg = cfg.itu_tag_bits;
    let ew = 3 + ni + fx; // FIFO element {final, last, resume, mask, {bank, base}}
    let db = bits_for(FIFO_DEPTH as u64 - 1);
    let ifl = bits_for(itu::LATENCY as u64 + 1);
    let (mean_lsb, _) = field("mean_x");
    let (geom_w, geom_lsb) = itu::geom_bits_lsb(cfg);
    let (dk_lsb, dk_w) = field("depth_key");

    let mut m = Module::new(NAME);
    m.doc(format!(
        "Rasterization core: {ni} ITUs + {nc} SCUs (Fig. 14), {nbk} feature-buffer banks of {f} entries, bit-exact with golden"
    ));
    m.doc("raster_tile plus the deferred write-back {valid = ITU OR, key = depth key, id} of every table entry.");
    m.doc(
        "Command: one tile; memory: table / feature reads, write-back and pixel-row writes. See docs/rtl.md.",
    );
    m.clock_reset();
    m.input_c("cmd_valid_i", 1, "command handshake");
    m.output_c("cmd_ready_o", 1, "idle");
    m.input_c("cmd_tile_x_i", tb, "tile column (origin x = tile_x * tile)");
    m.input_c("cmd_tile_y_i", tb, "tile row");
    m.input_c("cmd_width_i", wd, "image width in pixels (edge tiles: pixels beyond stay black)");
    m.input_c("cmd_height_i", wd, "image height in pixels");
    m.input_c("cmd_table_i", aw, "table address (entries); written back in place");
    m.input_c("cmd_len_i", lw, "table entries");
    m.input_c("cmd_feat_i", aw, "feature base address (feature words; word = base + id)");
    m.input_c("cmd_pix_i", aw, "pixel address of the tile's first pixel; pixel (x, y) at + y * tile + x");
    m.output_c("done_o", 1, "one-cycle pulse: tile finished, every write taken");
    m.output_c("mem_req_valid_o", 1, "request offered");
    m.input_c("mem_req_ready_i", 1, "request taken");
    m.output_c("mem_req_write_o", 1, "1: write; 0: read");
    m.output_c("mem_req_space_o", 2, "0 table, 1 feature, 2 pixel");
    m.output_c("mem_req_addr_o", aw, "address in units of the space's element");
    m.output_c(
        "mem_req_len_o",
        bl,
        "reads: elements (table bursts, features 1); writes: 1 entry or S pixels",
    );
    m.output_c("mem_wdata_o", wdb, "table entry (low bits) or S pixels, pixel k at [24k +: 24] = {b, g, r}");
    m.input_c("mem_rsp_valid_i", 1, "read response beat, in request order");
    m.output_c("mem_rsp_ready_o", 1, "always 1: buffer space is reserved before a read is issued");
    m.input_c("mem_rsp_data_i", fw, "table entry (low bits) or feature word {present, entry}");

    // ------------------------------------------------------------ command and state
    m.blank();
    m.comment("Command registers and the main state.");
    for (n, wi) in [
        ("st_q", 2),
        ("tx_q", tb),
        ("ty_q", tb),
        ("wd_q", wd),
        ("ht_q", wd),
        ("tab_q", aw),
        ("feat_q", aw),
        ("pix_q", aw),
        ("len_q", lw),
        ("ld_st_q", 2),
        ("ld_bank_q", bkb),
        ("ld_start_q", lw),
        ("ld_len_q", sl),
        ("ld_left_q", lw),
        ("rel_seg_q", rsw),
        ("wk_on_q", 1),
        ("wk_bank_q", bkb),
        ("grp_q", gw),
        ("iss_q", sl),
        ("rcv_q", sl),
        ("base_q", fa),
        ("inflight_q", ifl),
        ("done_q", 1),
        ("seek_q", 1),
        ("g0_done_q", 1),
    ] {
        m.reg(n, wi);
    }
    for (n, v) in [("S_IDLE", S_IDLE), ("S_RUN", S_RUN), ("S_DRAIN", S_DRAIN)] {
        m.localparam(n, 2, lit(2, v));
    }
    for (n, v) in [("L_IDLE", L_IDLE), ("L_TABLE", L_TABLE), ("L_FEAT", L_FEAT)] {
        m.localparam(n, 2, lit(2, v));
    }
    m.comment(format!(
        "{nbk} banks of {f} entries: the loader fills the next ones while the walk and the SCUs use the oldest."
    ));
    m.mem("tbuf", tw, nbk * f).mem("fbuf", fw, nbk * f).mem("hbuf", 1, nbk * f);
    for b in 0..nbk {
        m.reg(format!("full{b}_q"), 1).reg(format!("walked{b}_q"), 1);
        m.reg(format!("blen{b}_q"), sl).reg(format!("bstart{b}_q"), lw);
    }
    m.wire_assign("cmd_fire", 1, "cmd_valid_i & cmd_ready_o");
    m.assign("cmd_ready_o", "st_q == S_IDLE");
    let flit = |wi: u32| lit(wi, f as u64);
    m.wire_assign(
        "cmd_seg_len",
        sl,
        format!("(cmd_len_i > {}) ? {} : {}", flit(lw), flit(sl), resize("cmd_len_i", lw, sl)),
    );
    let fl = f.trailing_zeros();
    m.wire_assign(
        "cmd_segs",
        lw,
        format!(
            "(cmd_len_i == {z}) ? {one} : (((cmd_len_i - {one}) >> {fl}) + {one})",
            z = lit(lw, 0),
            one = lit(lw, 1)
        ),
    );
    m.wire_assign("next_start", lw, format!("ld_start_q + {}", flit(lw)));
    m.wire_assign("rem_next", lw, "len_q - next_start");
    m.wire_assign(
        "next_seg_len",
        sl,
        format!("(rem_next > {}) ? {} : {}", flit(lw), flit(sl), resize("rem_next", lw, sl)),
    );
    m.comment("The walked segment (bank wk_bank_q).");
    m.wire_assign("seg_len_w", sl, bank_mux("blen", "wk_bank_q", nbk, bkb));
    m.wire_assign("seg_start_w", lw, bank_mux("bstart", "wk_bank_q", nbk, bkb));
    m.wire_assign("last_seg", 1, format!("(len_q - seg_start_w) <= {}", flit(lw)));
    m.wire_assign("last_grp", 1, format!("grp_q == {}", lit(gw, groups as u64 - 1)));

    // ------------------------------------------------------------ memory arbitration
    m.blank();
    m.comment("Memory port: pixel writes first, then the write-back, then reads (fixed priority).");
    m.wire("pw_v", 1).wire("wb_v", 1).wire("rd_v", 1).wire("pw_last_row", 1).wire("pw_scu", cb.max(1));
    m.wire_assign("pw_g", 1, "pw_v & mem_req_ready_i");
    m.wire_assign("wb_g", 1, "wb_v & ~pw_v & mem_req_ready_i");
    m.wire_assign("rd_g", 1, "rd_v & ~pw_v & ~wb_v & mem_req_ready_i");
    m.assign("mem_req_valid_o", "pw_v | wb_v | rd_v");
    m.assign("mem_rsp_ready_o", lit(1, 1));

    // ------------------------------------------------------------ load
    m.blank();
    m.comment("LOAD: table bursts into tbuf, then one feature read per entry into fbuf.");
    let bur = cfg.burst as u64;
    m.wire_assign("left", sl, "ld_len_q - iss_q");
    // A burst never crosses the segment's end; with bursts as long as a bank, `left` fits.
    let tlen = if bur >= f as u64 {
        resize("left", sl, bl)
    } else {
        format!("(left > {}) ? {} : {}", lit(sl, bur), lit(bl, bur), resize("left", sl, bl))
    };
    m.wire_assign("tlen", bl, tlen);
    m.wire_assign("rd_t", 1, "ld_st_q == L_TABLE");
    m.assign("rd_v", "(ld_st_q != L_IDLE) & (iss_q != ld_len_q)");
    m.wire_assign("iss_idx", fx, format!("{{ld_bank_q, {}}}", resize("iss_q", sl, fa)));
    m.wire_assign("iss_id", ib, format!("tbuf[iss_idx][{}:0]", ib - 1));
    m.wire_assign(
        "rd_addr",
        aw,
        format!(
            "rd_t ? (tab_q + {} + {}) : (feat_q + {})",
            resize("ld_start_q", lw, aw),
            resize("iss_q", sl, aw),
            resize("iss_id", ib, aw)
        ),
    );
    m.wire_assign("rd_len", bl, format!("rd_t ? tlen : {}", lit(bl, 1)));
    m.wire_assign("rcv_idx", fx, format!("{{ld_bank_q, {}}}", resize("rcv_q", sl, fa)));
    m.wire_assign("loaded", 1, "(iss_q == ld_len_q) & (rcv_q == ld_len_q)");
    m.wire_assign("ld_done", 1, "(ld_st_q == L_FEAT) & loaded");
    m.seq_noreset(vec![if_(
        "mem_rsp_valid_i",
        vec![if_else(
            "rd_t",
            vec![set("tbuf[rcv_idx]", format!("mem_rsp_data_i[{}:0]", tw - 1))],
            vec![set("fbuf[rcv_idx]", "mem_rsp_data_i")],
        )],
    )]);

    // ------------------------------------------------------------ ITUs
    m.blank();
    m.comment(format!("WALK: {ni} table entries per cycle through the ITUs, once per subtile group."));
    m.wire_assign("walk", 1, "(st_q == S_RUN) & wk_on_q & ~seek_q");
    m.wire_assign(
        "quad_end",
        sl + 1,
        format!("{} + {}", resize("base_q", fa, sl + 1), lit(sl + 1, ni as u64)),
    );
    // Quad skipping: group 0's walk tests every quad of the segment and records, per quad, the
    // groups it touches (qhit); the later groups walk only the quads that touch them. A group
    // touched by no quad walks quad 0 alone, to end its pieces.
    let nq = f / ni;
    let qb = bits_for(nq as u64 - 1);
    let ib2 = ni.trailing_zeros();
    m.comment("Quad skipping: qhit[q][g] = quad q of the segment touches group g (from group 0's walk).");
    m.mem("qhit", groups, nbk * nq);
    m.wire_assign("cur_q", qb, if nq == 1 { lit(1, 0) } else { format!("base_q[{}:{ib2}]", fa - 1) });
    let col: Vec<String> = (0..nq)
        .rev()
        .map(|q| {
            format!(
                "(qhit[{{wk_bank_q, {}}}][grp_q] & ({} < seg_len_w))",
                lit(qb, q as u64),
                lit(sl, q as u64 * ni as u64)
            )
        })
        .collect();
    // One assign per quad: a single concatenation is too long a line for large buffers.
    m.wire("qcol", nq);
    for (q, c) in col.iter().rev().enumerate() {
        m.assign(if nq == 1 { "qcol".to_string() } else { format!("qcol[{q}]") }, c.clone());
    }
    m.wire_assign("qabove", nq, format!("qcol & (({{{nq}{{1'b1}}}} << cur_q) << 1)"));
    for (src, dst) in [("qcol", "qf"), ("qabove", "qn")] {
        m.wire_assign(format!("{dst}_oh"), nq, format!("{src} & (~{src} + {})", lit(nq, 1)));
        // Bit b of the index: the one-hot word has its bit at a quad whose index has bit b.
        let bits: Vec<String> = (0..qb)
            .rev()
            .map(|b| format!("(|({dst}_oh & {}))", mask_lit(nq, |q| (q >> b) & 1 == 1)))
            .collect();
        m.wire_assign(format!("{dst}_idx"), qb, format!("{{{}}}", bits.join(", ")));
        m.wire_assign(format!("unused_{dst}0"), 1, format!("{dst}_oh[0]"));
    }
    let to_base = |idx: &str| -> String {
        if ib2 == 0 {
            resize(idx, qb, fa)
        } else if nq == 1 {
            lit(fa, 0)
        } else {
            format!("{{{idx}, {}}}", lit(ib2, 0))
        }
    };
    m.wire_assign("qnext_base", fa, to_base("qn_idx"));
    m.wire_assign("qfirst_base", fa, to_base("qf_idx"));
    m.wire_assign(
        "last_quad",
        1,
        format!("(grp_q == {}) ? (quad_end >= {}) : ~(|qabove)", lit(gw, 0), resize("seg_len_w", sl, sl + 1)),
    );
    m.wire("itu_in_ready", 1).wire("itu_out_valid", 1).wire("itu_out_ready", 1);
    m.wire_assign("itu_fire", 1, "walk & itu_in_ready");
    m.wire_assign("itu_out_fire", 1, "itu_out_valid & itu_out_ready");
    let mut in_readies = Vec::new();
    let mut out_valids = Vec::new();
    let mut unused = Vec::new();
    for u in 0..ni {
        m.wire_assign(format!("li{u}"), fa, format!("base_q + {}", lit(fa, u as u64)));
        m.wire_assign(format!("lb{u}"), fx, format!("{{wk_bank_q, li{u}}}"));
        m.wire_assign(
            format!("lv{u}"),
            1,
            format!("({} < seg_len_w) & fbuf[lb{u}][{present}]", resize(&format!("li{u}"), fa, sl)),
        );
        m.wire(format!("itu_rdy{u}"), 1).wire(format!("itu_ov{u}"), 1);
        m.wire(format!("bm{u}"), nsub).wire(format!("hit{u}"), 1).wire(format!("tag_out{u}"), tg);
        m.instance(
            itu::NAME,
            format!("u_itu{u}"),
            conns(&[
                ("clk_i", "clk_i".into()),
                ("rst_ni", "rst_ni".into()),
                ("in_valid_i", "walk".into()),
                ("in_ready_o", format!("itu_rdy{u}")),
                ("mean_i", format!("fbuf[lb{u}][{}:{mean_lsb}]", mean_lsb + itu::mean_bits(cfg) - 1)),
                ("geom_i", format!("fbuf[lb{u}][{}:{geom_lsb}]", geom_lsb + geom_w - 1)),
                ("tile_x_i", "tx_q".into()),
                ("tile_y_i", "ty_q".into()),
                ("tag_i", lit(tg, 0)),
                ("out_valid_o", format!("itu_ov{u}")),
                ("out_ready_i", "itu_out_ready".into()),
                ("bitmap_o", format!("bm{u}")),
                ("hit_o", format!("hit{u}")),
                ("tag_o", format!("tag_out{u}")),
            ]),
        );
        in_readies.push(format!("itu_rdy{u}"));
        out_valids.push(format!("itu_ov{u}"));
        unused.push(format!("tag_out{u}"));
    }
    m.comment("The ITUs share every control input, so they run in lockstep.");
    m.assign("itu_in_ready", in_readies.join(" & "));
    m.assign("itu_out_valid", out_valids.join(" & "));
    m.wire_assign("unused_tags", 1, format!("^{{{}}}", unused.join(", ")));
    // Sideband of each quad, {list_last, seg_last, group, base, lane valids}, through a copy of
    // the ITU pipeline: its stages all advance when in_ready_o is high.
    let sbw = 3 + gw + fx + ni;
    let lvs: Vec<String> = (0..ni).rev().map(|u| format!("lv{u}")).collect();
    m.comment(format!(
        "Quad sideband through {} stages that advance with the ITUs' (in_ready_o = their stage enable).",
        itu::LATENCY
    ));
    m.wire_assign(
        "sb_in",
        sbw,
        format!(
            "{{(seg_start_w != {}), (last_quad & last_seg), last_quad, grp_q, wk_bank_q, base_q, {}}}",
            lit(lw, 0),
            lvs.join(", ")
        ),
    );
    let mut sh = Vec::new();
    for k in 1..=itu::LATENCY {
        m.reg(format!("sb{k}_q"), sbw);
        let src = if k == 1 { "sb_in".to_string() } else { format!("sb{}_q", k - 1) };
        sh.push(set(format!("sb{k}_q"), src));
    }
    m.seq_noreset(vec![if_("itu_in_ready", sh)]);
    let sbo = format!("sb{}_q", itu::LATENCY);
    let mut off = 0;
    let mut tf = |n: &str, wi: u32, m: &mut Module| {
        m.wire_assign(
            n,
            wi,
            if wi == 1 { format!("{sbo}[{off}]") } else { format!("{sbo}[{}:{off}]", off + wi - 1) },
        );
        off += wi;
    };
    for u in 0..ni {
        tf(&format!("o_lv{u}"), 1, &mut m);
    }
    tf("o_base", fx, &mut m);
    tf("o_grp", gw, &mut m);
    tf("o_seg_last", 1, &mut m);
    tf("o_list_last", 1, &mut m);
    tf("o_resume", 1, &mut m);
    m.seq(
        vec![set("inflight_q", lit(ifl, 0))],
        vec![if_else(
            "itu_fire & ~itu_out_fire",
            vec![set("inflight_q", format!("inflight_q + {}", lit(ifl, 1)))],
            vec![if_(
                "~itu_fire & itu_out_fire",
                vec![set("inflight_q", format!("inflight_q - {}", lit(ifl, 1)))],
            )],
        )],
    );
    m.comment("Group 0's results: every entry's valid bit (the OR over all subtiles).");
    let mut hb = Vec::new();
    for u in 0..ni {
        hb.push(set(format!("hbuf[o_base + {}]", lit(fx, u as u64)), format!("hit{u}")));
    }
    m.seq_noreset(vec![if_(format!("itu_out_fire & (o_grp == {})", lit(gw, 0)), hb)]);
    m.comment("Group 0's results also give each quad's groups (qhit) and, with its last quad, g0_done.");
    let qh: Vec<String> = (0..groups)
        .rev()
        .map(|g| {
            let lanes: Vec<String> =
                (0..ni).map(|u| format!("(o_lv{u} & (|bm{u}[{}:{}]))", (g + 1) * nc - 1, g * nc)).collect();
            format!("({})", lanes.join(" | "))
        })
        .collect();
    m.wire_assign("o_qhit", groups, format!("{{{}}}", qh.join(", ")));
    let o_q = format!("o_base[{}:{}]", fx - 1, if f / ni == 1 { fa } else { ni.trailing_zeros() });
    m.seq_noreset(vec![if_(
        format!("itu_out_fire & (o_grp == {})", lit(gw, 0)),
        vec![set(format!("qhit[{o_q}]"), "o_qhit")],
    )]);
    m.seq(
        vec![set("g0_done_q", lit(1, 0))],
        vec![if_else(
            "wk_start",
            vec![set("g0_done_q", lit(1, 0))],
            vec![if_(
                format!("itu_out_fire & (o_grp == {}) & o_seg_last", lit(gw, 0)),
                vec![set("g0_done_q", lit(1, 1))],
            )],
        )],
    );

    // ------------------------------------------------------------ routing FIFOs
    m.blank();
    m.comment(format!(
        "Routing: per SCU j a FIFO of {{final, last, resume, lane mask, base}} ({FIFO_DEPTH} deep); lane u of the"
    ));
    m.comment(
        "quad goes to SCU j when bit (group * SCUs + j) of its bitmap is set. A piece (one group's walk of a",
    );
    m.comment("segment) ends with its last quad, pushed even with an empty mask; the last segment's piece is final.");
    let mut fulls = Vec::new();
    for j in 0..nc {
        let subx = if cb == 0 { "o_grp".to_string() } else { format!("{{o_grp, {}}}", lit(cb, j as u64)) };
        m.wire_assign(format!("rsub{j}"), sub_w, resize(&subx, gw + cb, sub_w));
        let mask: Vec<String> = (0..ni).rev().map(|u| format!("(o_lv{u} & bm{u}[rsub{j}])")).collect();
        m.wire_assign(format!("rmask{j}"), ni, format!("{{{}}}", mask.join(", ")));
        m.wire_assign(format!("push{j}"), 1, format!("itu_out_fire & ((|rmask{j}) | o_seg_last)"));
        m.mem(format!("fifo{j}"), ew, FIFO_DEPTH);
        m.reg(format!("fwp{j}_q"), db + 1).reg(format!("frp{j}_q"), db + 1);
        m.wire_assign(format!("fcnt{j}"), db + 1, format!("fwp{j}_q - frp{j}_q"));
        m.wire_assign(format!("ffull{j}"), 1, format!("fcnt{j} == {}", lit(db + 1, FIFO_DEPTH as u64)));
        m.wire_assign(format!("fempty{j}"), 1, format!("fcnt{j} == {}", lit(db + 1, 0)));
        m.wire(format!("pop{j}"), 1);
        m.seq_noreset(vec![if_(
            format!("push{j}"),
            vec![set(
                format!("fifo{j}[fwp{j}_q[{}:0]]", db - 1),
                format!("{{o_list_last, o_seg_last, o_resume, rmask{j}, o_base}}"),
            )],
        )]);
        m.seq(
            vec![set(format!("fwp{j}_q"), lit(db + 1, 0)), set(format!("frp{j}_q"), lit(db + 1, 0))],
            vec![
                if_(
                    format!("push{j}"),
                    vec![set(format!("fwp{j}_q"), format!("fwp{j}_q + {}", lit(db + 1, 1)))],
                ),
                if_(
                    format!("pop{j}"),
                    vec![set(format!("frp{j}_q"), format!("frp{j}_q + {}", lit(db + 1, 1)))],
                ),
            ],
        );
        fulls.push(format!("ffull{j}"));
    }
    m.assign("itu_out_ready", format!("~({})", fulls.join(" | ")));

    // ------------------------------------------------------------ feeders and SCUs
    m.blank();
    m.comment("Feeders: per SCU the current element; one beat per set mask bit (lowest first), or one empty");
    m.comment(
        "beat for a list's final element with an empty mask. Subtile of SCU j's list: {list group, j}.",
    );
    let beat_fields = [
        ("in_mean_x_i", "mean_x"),
        ("in_mean_y_i", "mean_y"),
        ("in_conic_a_i", "conic_a"),
        ("in_conic_b_i", "conic_b"),
        ("in_conic_c_i", "conic_c"),
        ("in_conic_exp_i", "conic_exp"),
        ("in_opacity_i", "opacity"),
        ("in_red_i", "red"),
        ("in_green_i", "green"),
        ("in_blue_i", "blue"),
    ];
    let mut busy = Vec::new();
    for j in 0..nc {
        let q = |n: &str| format!("{n}{j}_q");
        m.reg(q("cv"), 1).reg(q("cbase"), fx).reg(q("cmask"), ni).reg(q("clast"), 1).reg(q("lgrp"), gw);
        m.reg(q("cfin"), 1).reg(q("cres"), 1);
        m.reg(q("rel"), 1);
        // Lowest set bit of the mask.
        let mut sel = lit(bits_for(ni as u64 - 1), 0);
        if ni > 1 {
            for u in (0..ni).rev() {
                sel = format!("cmask{j}_q[{u}] ? {} : ({sel})", lit(bits_for(ni as u64 - 1), u as u64));
            }
        }
        let lb = bits_for(ni as u64 - 1);
        m.wire_assign(format!("flane{j}"), lb, sel);
        m.wire_assign(
            format!("fidx{j}"),
            fx,
            format!("cbase{j}_q + {}", resize(&format!("flane{j}"), lb, fx)),
        );
        m.wire_assign(format!("frest{j}"), ni, format!("cmask{j}_q & (cmask{j}_q - {})", lit(ni, 1)));
        m.wire_assign(format!("fempty_beat{j}"), 1, format!("~(|cmask{j}_q)"));
        m.wire_assign(format!("flast{j}"), 1, format!("clast{j}_q & ~(|frest{j})"));
        m.wire(format!("scu_rdy{j}"), 1).wire(format!("term{j}"), 1);
        // An empty piece that neither starts nor ends its subtile (resumed, not final) would only
        // reload and re-save the subtile's state: it is dropped instead of sent.
        m.reg(q("pfirst"), 1);
        m.wire_assign(
            format!("fskip{j}"),
            1,
            format!("pfirst{j}_q & fempty_beat{j} & clast{j}_q & cres{j}_q & ~cfin{j}_q"),
        );
        m.wire_assign(format!("beat{j}"), 1, format!("cv{j}_q & (scu_rdy{j} | fskip{j})"));
        m.wire_assign(format!("edone{j}"), 1, format!("beat{j} & ~(|frest{j})"));
        m.assign(format!("pop{j}"), format!("~fempty{j} & (~cv{j}_q | edone{j})"));
        m.wire_assign(format!("fhead{j}"), ew, format!("fifo{j}[frp{j}_q[{}:0]]", db - 1));
        m.seq(
            vec![
                set(q("cv"), lit(1, 0)),
                set(q("lgrp"), lit(gw, 0)),
                set(q("rel"), lit(1, 0)),
                set(q("pfirst"), lit(1, 1)),
            ],
            vec![
                if_("beat{j}".replace("{j}", &j.to_string()), vec![set(q("pfirst"), format!("flast{j}"))]),
                if_("cmd_fire", vec![set(q("lgrp"), lit(gw, 0)), set(q("pfirst"), lit(1, 1))]),
                if_(
                    format!("beat{j} & flast{j}"),
                    vec![set(q("lgrp"), format!("lgrp{j}_q + {}", lit(gw, 1)))],
                ),
                if_else(
                    format!("pop{j}"),
                    vec![set(q("cv"), lit(1, 1))],
                    vec![if_(format!("edone{j}"), vec![set(q("cv"), lit(1, 0))])],
                ),
                set(q("rel"), format!("pw_g & pw_last_row & (pw_scu == {})", lit(cb.max(1), j as u64))),
            ],
        );
        m.seq_noreset(vec![if_else(
            format!("pop{j}"),
            vec![
                set(q("cbase"), format!("fhead{j}[{}:0]", fx - 1)),
                set(q("cmask"), format!("fhead{j}[{}:{fx}]", fx + ni - 1)),
                set(q("cres"), format!("fhead{j}[{}]", fx + ni)),
                set(q("clast"), format!("fhead{j}[{}]", fx + ni + 1)),
                set(q("cfin"), format!("fhead{j}[{}]", fx + ni + 2)),
            ],
            vec![if_(format!("beat{j}"), vec![set(q("cmask"), format!("frest{j}"))])],
        )]);
        // Subtile origin and the inside columns / rows.
        let lsub =
            if cb == 0 { format!("lgrp{j}_q") } else { format!("{{lgrp{j}_q, {}}}", lit(cb, j as u64)) };
        m.wire_assign(format!("lsub{j}"), sub_w, resize(&lsub, gw + cb, sub_w));
        subtile_origin(&mut m, &format!("s{j}"), &format!("lsub{j}"), side_w, sb, tl, tb, ow, s);
        let mut c = vec![
            ("clk_i", "clk_i".to_string()),
            ("rst_ni", "rst_ni".to_string()),
            ("in_valid_i", format!("cv{j}_q & ~fskip{j}")),
            ("in_ready_o", format!("scu_rdy{j}")),
        ];
        for (port, fname) in beat_fields {
            let (lsb, wi) = field(fname);
            c.push((port, format!("fbuf[fidx{j}][{}:{lsb}]", lsb + wi - 1)));
        }
        c.extend([
            ("in_empty_i", format!("fempty_beat{j}")),
            ("in_last_i", format!("flast{j}")),
            ("in_final_i", format!("cfin{j}_q")),
            ("in_resume_i", format!("cres{j}_q")),
            ("in_sub_i", resize(&format!("lgrp{j}_q"), gw, w.row_bits)),
            ("in_origin_x_i", resize(&format!("s{j}_ox"), ow, w.origin)),
            ("in_origin_y_i", resize(&format!("s{j}_oy"), ow, w.origin)),
            ("in_cols_i", format!("s{j}_cols")),
            ("in_rows_i", format!("s{j}_rows")),
            ("term_o", format!("term{j}")),
            ("out_valid_o", format!("scu_ov{j}")),
            ("out_ready_i", format!("rel{j}_q")),
            ("out_rgb_o", format!("scu_rgb{j}")),
        ]);
        m.wire(format!("scu_ov{j}"), 1).wire(format!("scu_rgb{j}"), 24 * s * s);
        let cs: Vec<(&str, String)> = c.iter().map(|(a, b)| (*a, b.clone())).collect();
        m.instance(scu::NAME, format!("u_scu{j}"), conns(&cs));
        busy.push(format!("cv{j}_q | ~fempty{j}"));
    }
    let terms: Vec<String> = (0..nc).map(|j| format!("term{j}")).collect();
    m.wire_assign("unused_term", 1, format!("^{{{}}}", terms.join(", ")));
    m.wire_assign("route_busy", 1, format!("(inflight_q != {}) | {}", lit(ifl, 0), busy.join(" | ")));
    let _ = w.pass_bits();

    // ------------------------------------------------------------ pixel writer
    m.blank();
    m.comment(format!(
        "Pixel writer: subtiles in order, SCU = subtile % {nc}, one row of {s} pixels per write."
    ));
    m.reg("pw_sub_q", sub_w + 1).reg("pw_row_q", sb);
    let pw_scu = if cb == 0 { lit(1, 0) } else { format!("pw_sub_q[{}:0]", cb - 1) };
    m.assign("pw_scu", pw_scu);
    m.assign("pw_last_row", format!("pw_row_q == {}", lit(sb, s as u64 - 1)));
    m.wire_assign("pw_all", 1, format!("pw_sub_q[{sub_w}]"));
    let mut ov = lit(1, 0);
    let mut rgb = format!("scu_rgb{}", nc - 1);
    for j in (0..nc).rev() {
        ov = format!("((pw_scu == {l}) ? (scu_ov{j} & ~rel{j}_q) : {ov})", l = lit(cb.max(1), j as u64));
        if j + 1 < nc {
            rgb = format!("((pw_scu == {l}) ? scu_rgb{j} : {rgb})", l = lit(cb.max(1), j as u64));
        }
    }
    m.wire_assign("pw_rgb", 24 * s * s, rgb);
    m.assign("pw_v", format!("~pw_all & {ov}"));
    m.wire_assign("pw_sx", side_w, format!("pw_sub_q[{}:0]", side_w - 1));
    m.wire_assign("pw_sy", side_w, format!("pw_sub_q[{}:{side_w}]", sub_w - 1));
    let pa = 2 * tl;
    m.wire_assign(
        "pw_off",
        pa,
        format!(
            "{{{}, pw_row_q, {}}} + {}",
            "pw_sy",
            lit(tl, 0),
            resize(&format!("{{pw_sx, {}}}", lit(sb, 0)), side_w + sb, pa)
        ),
    );
    m.wire_assign("pw_addr", aw, format!("pix_q + {}", resize("pw_off", pa, aw)));
    let mut row = format!("pw_rgb[{}:{}]", s * rw - 1, (s - 1) * rw);
    for r in (0..s - 1).rev() {
        row = format!(
            "(pw_row_q == {}) ? pw_rgb[{}:{}] : ({row})",
            lit(sb, r as u64),
            (r + 1) * rw - 1,
            r * rw
        );
    }
    m.wire_assign("pw_data", rw, row);
    m.seq(
        vec![set("pw_sub_q", lit(sub_w + 1, 1 << sub_w)), set("pw_row_q", lit(sb, 0))],
        vec![
            if_("cmd_fire", vec![set("pw_sub_q", lit(sub_w + 1, 0)), set("pw_row_q", lit(sb, 0))]),
            if_(
                "pw_g",
                vec![
                    set("pw_row_q", format!("pw_row_q + {}", lit(sb, 1))),
                    if_("pw_last_row", vec![set("pw_sub_q", format!("pw_sub_q + {}", lit(sub_w + 1, 1)))]),
                ],
            ),
        ],
    );

    // ------------------------------------------------------------ write-back
    m.blank();
    m.comment("Write-back of the segment once its group-0 results are in: {present & OR, present ? depth key : key, id}.");
    m.reg("wb_busy_q", 1).reg("wb_ptr_q", fa).reg("wb_bank_q", bkb);
    m.assign("wb_v", "wb_busy_q");
    m.wire_assign("wb_idx", fx, "{wb_bank_q, wb_ptr_q}");
    m.wire_assign("wb_start", lw, bank_mux("bstart", "wb_bank_q", nbk, bkb));
    m.wire_assign("wb_present", 1, format!("fbuf[wb_idx][{present}]"));
    m.wire_assign(
        "wb_key",
        kb,
        // The key field takes the depth key (its low key_bits bits when it is wider).
        format!(
            "wb_present ? {} : tbuf[wb_idx][{}:{ib}]",
            resize(&format!("fbuf[wb_idx][{}:{dk_lsb}]", dk_lsb + dk_w.min(kb) - 1), dk_w.min(kb), kb),
            tw - 1
        ),
    );
    m.wire_assign(
        "wb_entry",
        eb,
        resize(
            &format!("{{(wb_present & hbuf[wb_idx]), wb_key, tbuf[wb_idx][{}:0]}}", ib - 1),
            1 + kb + ib,
            eb,
        ),
    );
    m.wire_assign(
        "wb_addr",
        aw,
        format!("tab_q + {} + {}", resize("wb_start", lw, aw), resize("wb_ptr_q", fa, aw)),
    );
    m.wire_assign("wb_next", sl, format!("{} + {}", resize("wb_ptr_q", fa, sl), lit(sl, 1)));
    m.wire_assign("wb_end", 1, format!("wb_next == {}", bank_mux("blen", "wb_bank_q", nbk, bkb)));
    m.wire_assign(
        "o_bank",
        bkb,
        if bkb == 1 { format!("o_base[{fa}]") } else { format!("o_base[{}:{fa}]", fx - 1) },
    );
    m.wire_assign("o_blen", sl, bank_mux("blen", "o_bank", nbk, bkb));
    m.seq(
        vec![set("wb_busy_q", lit(1, 0)), set("wb_ptr_q", lit(fa, 0)), set("wb_bank_q", lit(bkb, 0))],
        vec![
            if_(
                format!("itu_out_fire & (o_grp == {}) & o_seg_last & (o_blen != {})", lit(gw, 0), lit(sl, 0)),
                vec![set("wb_busy_q", lit(1, 1)), set("wb_ptr_q", lit(fa, 0)), set("wb_bank_q", "o_bank")],
            ),
            if_(
                "wb_g",
                vec![if_else(
                    "wb_end",
                    vec![set("wb_busy_q", lit(1, 0))],
                    vec![set("wb_ptr_q", format!("wb_ptr_q + {}", lit(fa, 1)))],
                )],
            ),
        ],
    );

    // ------------------------------------------------------------ request mux
    m.assign("mem_req_write_o", "pw_v | wb_v");
    m.assign(
        "mem_req_space_o",
        format!(
            "pw_v ? {} : (wb_v ? {} : (rd_t ? {} : {}))",
            lit(2, space::PIXEL),
            lit(2, space::TABLE),
            lit(2, space::TABLE),
            lit(2, space::FEATURE)
        ),
    );
    m.assign("mem_req_addr_o", "pw_v ? pw_addr : (wb_v ? wb_addr : rd_addr)");
    m.assign("mem_req_len_o", format!("pw_v ? {} : (wb_v ? {} : rd_len)", lit(bl, s as u64), lit(bl, 1)));
    m.assign(
        "mem_wdata_o",
        format!("pw_v ? {} : {}", resize("pw_data", rw, wdb), resize("wb_entry", eb, wdb)),
    );

    // ------------------------------------------------------------ control
    m.blank();
    m.comment("Control: RUN while the loader and the walk work through the segments, then DRAIN.");
    m.wire_assign("drained", 1, "~route_busy & ~wb_busy_q");
    // Per SCU: segments whose last piece (group G-1) it has taken, to release their bank.
    let mut consumed = Vec::new();
    for j in 0..nc {
        m.reg(format!("sc{j}_q"), rsw);
        m.seq(
            vec![set(format!("sc{j}_q"), lit(rsw, 0))],
            vec![if_else(
                "cmd_fire",
                vec![set(format!("sc{j}_q"), lit(rsw, 0))],
                vec![if_(
                    format!("beat{j} & flast{j} & (lgrp{j}_q == {})", lit(gw, groups as u64 - 1)),
                    vec![set(format!("sc{j}_q"), format!("sc{j}_q + {}", lit(rsw, 1)))],
                )],
            )],
        );
        consumed.push(format!("(sc{j}_q != rel_seg_q)"));
    }
    m.comment("A bank is released once its segment is walked, every SCU has taken its last piece and");
    m.comment("its write-back is done (segment k uses bank k mod banks; released in order).");
    m.wire_assign("rel_bank", bkb, format!("rel_seg_q[{}:0]", bkb - 1));
    m.wire_assign(
        "rel_ok",
        1,
        format!(
            "{} & {} & {} & ~(wb_busy_q & (wb_bank_q == rel_bank))",
            bank_mux("full", "rel_bank", nbk, bkb),
            bank_mux("walked", "rel_bank", nbk, bkb),
            consumed.join(" & ")
        ),
    );
    m.wire_assign("ld_free", 1, format!("~{}", bank_mux("full", "ld_bank_q", nbk, bkb)));
    m.wire_assign(
        "wk_start",
        1,
        format!(
            "(st_q == S_RUN) & ~wk_on_q & {} & ~{} & ~wb_busy_q",
            bank_mux("full", "wk_bank_q", nbk, bkb),
            bank_mux("walked", "wk_bank_q", nbk, bkb)
        ),
    );
    m.wire_assign("wk_end", 1, "itu_fire & last_quad & last_grp");
    let mut banks = vec![if_("rel_ok", vec![set("rel_seg_q", format!("rel_seg_q + {}", lit(rsw, 1)))])];
    let mut clear = vec![set("rel_seg_q", lit(rsw, 0))];
    let mut lens = Vec::new();
    for b in 0..nbk {
        let bl_ = lit(bkb, b as u64);
        banks.extend([
            if_(format!("ld_done & (ld_bank_q == {bl_})"), vec![set(format!("full{b}_q"), lit(1, 1))]),
            if_(format!("wk_end & (wk_bank_q == {bl_})"), vec![set(format!("walked{b}_q"), lit(1, 1))]),
            if_(
                format!("rel_ok & (rel_bank == {bl_})"),
                vec![set(format!("full{b}_q"), lit(1, 0)), set(format!("walked{b}_q"), lit(1, 0))],
            ),
        ]);
        clear.extend([set(format!("full{b}_q"), lit(1, 0)), set(format!("walked{b}_q"), lit(1, 0))]);
        lens.push(if_(
            format!("ld_done & (ld_bank_q == {bl_})"),
            vec![set(format!("blen{b}_q"), "ld_len_q"), set(format!("bstart{b}_q"), "ld_start_q")],
        ));
    }
    m.seq(clear.clone(), vec![if_else("cmd_fire", clear, banks)]);
    m.seq_noreset(lens);
    m.comment("Loader: table bursts then one feature read per entry, a segment per free bank.");
    // A load phase starts with no read issued or received.
    let phase = |st: &str| vec![set("ld_st_q", st), set("iss_q", lit(sl, 0)), set("rcv_q", lit(sl, 0))];
    m.seq(
        vec![
            set("ld_st_q", "L_IDLE"),
            set("ld_left_q", lit(lw, 0)),
            set("iss_q", lit(sl, 0)),
            set("rcv_q", lit(sl, 0)),
        ],
        vec![
            if_("rd_g", vec![set("iss_q", format!("iss_q + {}", resize("rd_len", bl, sl)))]),
            if_("mem_rsp_valid_i", vec![set("rcv_q", format!("rcv_q + {}", lit(sl, 1)))]),
            if_else(
                "cmd_fire",
                vec![
                    set("ld_st_q", "L_IDLE"),
                    set("ld_bank_q", lit(bkb, 0)),
                    set("ld_start_q", lit(lw, 0)),
                    set("ld_len_q", "cmd_seg_len"),
                    set("ld_left_q", "cmd_segs"),
                ],
                vec![Stmt::Case(
                    "ld_st_q".into(),
                    vec![
                        (
                            "L_IDLE".into(),
                            vec![if_(
                                format!("(st_q == S_RUN) & (ld_left_q != {}) & ld_free", lit(lw, 0)),
                                phase("L_TABLE"),
                            )],
                        ),
                        ("L_TABLE".into(), vec![if_("loaded", phase("L_FEAT"))]),
                        (
                            "L_FEAT".into(),
                            vec![if_(
                                "loaded",
                                vec![
                                    set("ld_st_q", "L_IDLE"),
                                    set("ld_bank_q", format!("ld_bank_q + {}", lit(bkb, 1))),
                                    set("ld_start_q", "next_start"),
                                    set("ld_len_q", "next_seg_len"),
                                    set("ld_left_q", format!("ld_left_q - {}", lit(lw, 1))),
                                ],
                            )],
                        ),
                    ],
                    vec![set("ld_st_q", "L_IDLE")],
                )],
            ),
        ],
    );
    m.comment("Walk: every group of the segment in bank wk_bank_q; a later group starts at its first");
    m.comment("quad once group 0's results are in.");
    let on_cmd = vec![
        set("st_q", "S_RUN"),
        set("tx_q", "cmd_tile_x_i"),
        set("ty_q", "cmd_tile_y_i"),
        set("wd_q", "cmd_width_i"),
        set("ht_q", "cmd_height_i"),
        set("tab_q", "cmd_table_i"),
        set("feat_q", "cmd_feat_i"),
        set("pix_q", "cmd_pix_i"),
        set("len_q", "cmd_len_i"),
        set("wk_on_q", lit(1, 0)),
        set("wk_bank_q", lit(bkb, 0)),
    ];
    m.seq(
        vec![
            set("st_q", "S_IDLE"),
            set("done_q", lit(1, 0)),
            set("base_q", lit(fa, 0)),
            set("seek_q", lit(1, 0)),
            set("wk_on_q", lit(1, 0)),
            set("wk_bank_q", lit(bkb, 0)),
            set("grp_q", lit(gw, 0)),
        ],
        vec![
            set("done_q", lit(1, 0)),
            Stmt::Case(
                "st_q".into(),
                vec![
                    ("S_IDLE".into(), vec![if_("cmd_valid_i", on_cmd)]),
                    (
                        "S_RUN".into(),
                        vec![
                            if_(
                                "wk_start",
                                vec![
                                    set("wk_on_q", lit(1, 1)),
                                    set("grp_q", lit(gw, 0)),
                                    set("base_q", lit(fa, 0)),
                                    set("seek_q", lit(1, 0)),
                                ],
                            ),
                            if_(
                                "seek_q & g0_done_q",
                                vec![
                                    set("seek_q", lit(1, 0)),
                                    set("base_q", format!("(|qcol) ? qfirst_base : {}", lit(fa, 0))),
                                ],
                            ),
                            if_(
                                "itu_fire",
                                vec![if_else(
                                    "~last_quad",
                                    vec![set(
                                        "base_q",
                                        format!(
                                            "(grp_q == {}) ? (base_q + {}) : qnext_base",
                                            lit(gw, 0),
                                            lit(fa, ni as u64)
                                        ),
                                    )],
                                    vec![
                                        set("base_q", lit(fa, 0)),
                                        if_else(
                                            "~last_grp",
                                            vec![
                                                set("grp_q", format!("grp_q + {}", lit(gw, 1))),
                                                set("seek_q", lit(1, 1)),
                                            ],
                                            vec![
                                                set("wk_on_q", lit(1, 0)),
                                                set("wk_bank_q", format!("wk_bank_q + {}", lit(bkb, 1))),
                                                if_("last_seg", vec![set("st_q", "S_DRAIN")]),
                                            ],
                                        ),
                                    ],
                                )],
                            ),
                        ],
                    ),
                    (
                        "S_DRAIN".into(),
                        vec![if_("drained & pw_all", vec![set("st_q", "S_IDLE"), set("done_q", lit(1, 1))])],
                    ),
                ],
                vec![set("st_q", "S_IDLE")],
            ),
        ],
    );
    m.assign("done_o", "done_q");
    m
}

/// A `width`-bit hex literal whose bit `q` is `bit(q)` (any width).
fn mask_lit(width: u32, bit: impl Fn(u32) -> bool) -> String {
    let digits: String = (0..width.div_ceil(4))
        .rev()
        .map(|d| {
            let v = (0..4).filter(|&k| d * 4 + k < width && bit(d * 4 + k)).fold(0u32, |a, k| a | 1 << k);
            char::from_digit(v, 16).expect("hex digit")
        })
        .collect();
    format!("{width}'h{digits}")
}

/// `name{sel}_q` of banks `0..n` (`sel`: `bits` wide).
fn bank_mux(name: &str, sel: &str, n: u32, bits: u32) -> String {
    let mut e = format!("{name}{}_q", n - 1);
    for b in (0..n - 1).rev() {
        e = format!("(({sel} == {}) ? {name}{b}_q : {e})", lit(bits, b as u64));
    }
    e
}

/// Origin (`P_ox`, `P_oy`, `ow` bits) and inside columns / rows (`P_cols`, `P_rows`) of subtile
/// `sub` (row-major index) of the command's tile.
#[allow(clippy::too_many_arguments)]
fn subtile_origin(
    m: &mut Module,
    p: &str,
    sub: &str,
    side_w: u32,
    sb: u32,
    tl: u32,
    tb: u32,
    ow: u32,
    s: u32,
) {
    let sub_w = 2 * side_w;
    for (a, t, lo, dim) in [("x", "tx_q", 0, "wd_q"), ("y", "ty_q", side_w, "ht_q")] {
        let idx = format!("{sub}[{}:{lo}]", lo + side_w - 1);
        let _ = sub_w;
        m.wire_assign(
            format!("{p}_o{a}"),
            ow,
            format!(
                "{} + {}",
                resize(&format!("{{{t}, {}}}", lit(tl, 0)), tb + tl, ow),
                resize(&format!("{{{idx}, {}}}", lit(sb, 0)), side_w + sb, ow)
            ),
        );
        m.wire_assign(format!("{p}_r{a}"), ow, format!("{} - {p}_o{a}", resize(dim, ow - 1, ow)));
        let n = if a == "x" { "cols" } else { "rows" };
        m.wire_assign(
            format!("{p}_{n}"),
            sb + 1,
            format!(
                "({} <= {p}_o{a}) ? {} : (({p}_r{a} > {}) ? {} : {p}_r{a}[{sb}:0])",
                resize(dim, ow - 1, ow),
                lit(sb + 1, 0),
                lit(ow, s as u64),
                lit(sb + 1, s as u64)
            ),
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn widths_and_ports() {
        let cfg = GenConfig::default();
        assert_eq!(feature_word_bits(&cfg), cfg.feature_format().bits_per_entry() + 1);
        assert_eq!(image_bits(&cfg), cfg.tile_bits + 6);
        assert_eq!(wdata_bits(&cfg), 192);
        let v = module(&cfg).to_verilog();
        for i in
            ["neo_itu u_itu3", "neo_scu u_scu3", "reg  [246:0] fbuf [0:511];", "reg  [15:0] qhit [0:127];"]
        {
            assert!(v.contains(i), "{i} missing");
        }
        assert!(!v.contains("u_itu4") && !v.contains("u_scu4"));
    }

    #[test]
    fn unit_counts_follow_the_config() {
        let cfg =
            GenConfig { raster_itus: 2, raster_scus: 8, raster_feature_buffer: 64, ..GenConfig::default() };
        cfg.validate().unwrap();
        let v = module(&cfg).to_verilog();
        assert!(v.contains("u_itu1") && !v.contains("u_itu2"));
        assert!(v.contains("u_scu7") && !v.contains("u_scu8"));
        assert!(GenConfig { raster_scus: 3, ..GenConfig::default() }.validate().is_err());
        assert!(GenConfig { raster_feature_buffer: 100, ..GenConfig::default() }.validate().is_err());
        assert!(GenConfig { raster_feature_banks: 3, ..GenConfig::default() }.validate().is_err());
        assert!(GenConfig { raster_feature_banks: 1, ..GenConfig::default() }.validate().is_err());
        let four = GenConfig { raster_feature_banks: 4, raster_feature_buffer: 64, ..GenConfig::default() };
        four.validate().unwrap();
        let v = module(&four).to_verilog();
        assert!(v.contains("full3_q") && !v.contains("full4_q") && v.contains("fbuf [0:255]"));
        assert!(GenConfig { raster_itus: 0, ..GenConfig::default() }.validate().is_err());
    }
}
