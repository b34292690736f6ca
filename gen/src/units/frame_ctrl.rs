//! `neo_frame_ctrl`: the engine's frame controller. On `start_i` it walks the frame's tiles:
//!
//! - **descriptors**: AXI client 0 reads tile `t`'s descriptor (one 4-beat INCR burst at
//!   `DESC_BASE + 32 t`) into a one-descriptor buffer, tiles in index order;
//! - **overflow check**: a tile with `entries_in = list_len (+ prev_len unless from scratch)`
//!   above `table_capacity` is not sorted: it goes straight to the completion queue with
//!   `{next_len 0, overflow 1}` (`FIRST_OVERFLOW` / `OVERFLOWS` updated);
//! - **sort scheduler** (`EngineConfig::scheduler`): `first_free` hands the tile to the
//!   lowest-numbered sequencer whose `job_ready_i` is high; `round_robin` to sequencer
//!   `k = (jobs so far) mod N`, waiting for it. The job payload is shared; each sequencer has its
//!   own scratch base (`job_scratch_o[k]` = `SCRATCH_BASE / 8 + 2 k table_capacity`);
//! - **completion queue**: sequencer completions (lowest index first, with the MERGE_DELETE's
//!   boundary inversions `cpl_inv_i`) and overflowing tiles enter a FIFO of `{tile, tile_x,
//!   tile_y, next, next_len, overflow, inversions}`; its head is handed to a raster core (same
//!   scheduler policy over the `M` cores, a core whose last result is not written yet waiting:
//!   `table = next`, `len = next_len`, `feat = FEAT_BASE / 32`, `pix = FB_BASE / 4 + t * tile *
//!   tile`), which keeps the head's fields in its result record;
//! - **results**: a raster core's `ras_done_i` pulse completes its record with the write-back
//!   signals (`ras_wb_len_i`, `ras_wb_reach_i`); the result writer takes the lowest-numbered
//!   complete record and writes the tile's result (golden `TileResult`: one 2-beat AXI burst at
//!   `RESULT_BASE + 16 t`, at most `axi_outstanding` without their B);
//! - **done**: when every tile was rastered (`raster_done_i` pulses counted), every result is
//!   written and its B back, and every bridge's `idle_i` is high; then `busy_o` falls and
//!   `done_o` rises (held until the next start).
//!
//! Event outputs (for `neo_perf_counters`, counted by the engine top): `ev_desc_read_o` (a
//! descriptor's last beat), `ev_tile_sorted_o` + `ev_entries_sorted_o` (a job handed to a
//! sequencer, with its `entries_in`; 0 in other cycles), `ev_tile_rastered_o` (raster done pulses this cycle),
//! `ev_entries_rastered_o` (a raster command's `len`, when taken), `ev_result_written_o` (a
//! result's B).

use crate::emit::expr::{bits_for, lit, resize, zext};
use crate::emit::{for_, if_, if_else, set, Module, Stmt};
use neo_golden::engine::adapt::{
    ADAPT_BUDGET_BITS, ADAPT_BUDGET_LSB, ADAPT_ENABLE, ADAPT_MAX_BITS, ADAPT_MAX_LSB, ADAPT_WIDE,
};
use neo_golden::engine::memory::{
    DPS_PASSES_BITS, DPS_PASSES_LSB, DPS_WIDE_BIT, INVERSIONS_BITS, INVERSIONS_LSB, INVERSIONS_MAX,
};
use neo_golden::engine::{EngineConfig, SchedulerPolicy};

/// Module name.
pub const NAME: &str = "neo_frame_ctrl";

/// Widths and counts of the controller for `cfg`.
struct Dims {
    n: u32,
    m: u32,
    aw: u32,
    lw: u32,
    xa: u32,
    xd: u32,
    xi: u32,
    tb: u32,
    /// Sequencer index bits (at least 1).
    nb: u32,
    /// Raster-core index bits (at least 1).
    mb: u32,
    /// Completion-queue depth and pointer bits.
    qd: u32,
    qb: u32,
    /// Outstanding-write counter bits.
    ob: u32,
    rr: bool,
}

impl Dims {
    fn new(cfg: &EngineConfig) -> Dims {
        let (n, m) = (cfg.sort_cores as u32, cfg.raster_cores as u32);
        let qd = neo_golden::engine::COMPLETION_QUEUE_DEPTH as u32;
        Dims {
            n,
            m,
            aw: cfg.addr_bits,
            lw: cfg.len_bits,
            xa: cfg.axi_addr_bits,
            xd: cfg.axi_data_bits,
            xi: cfg.axi_id_bits,
            tb: cfg.tile_bits,
            nb: bits_for(n as u64 - 1),
            mb: bits_for(m as u64 - 1),
            qd,
            qb: bits_for(qd as u64 - 1),
            ob: bits_for(cfg.axi_outstanding as u64),
            rr: cfg.scheduler == SchedulerPolicy::RoundRobin,
        }
    }
}

/// Fields of a completion-queue entry: (name, width), packed from bit 0.
fn cq_fields(d: &Dims) -> Vec<(&'static str, u32)> {
    vec![("t", 32), ("x", d.tb), ("y", d.tb), ("next", d.aw), ("len", d.lw), ("ovf", 1), ("inv", d.lw)]
}

/// The frame controller for `cfg`.
pub fn module(cfg: &EngineConfig) -> Module {
    let d = Dims::new(cfg);
    let mut m = Module::new(NAME);
    m.doc("Engine frame controller: descriptor reads and result writes (AXI client 0), the overflow check,");
    m.doc(format!(
        "the {} tile scheduler over {} sequencers and {} raster cores, the completion queue, status and events.",
        cfg.scheduler.name(),
        d.n,
        d.m
    ));
    ports(&mut m, cfg, &d);
    status(&mut m, &d);
    fetch(&mut m, &d);
    adapt(&mut m, cfg);
    dispatch(&mut m, cfg, &d);
    completions(&mut m, &d);
    head(&mut m, cfg, &d);
    results(&mut m, cfg, &d);
    m
}

fn ports(m: &mut Module, cfg: &EngineConfig, d: &Dims) {
    let (aw, lw, xa) = (d.aw, d.lw, d.xa);
    m.clock_reset();
    m.input_c("start_i", 1, "CTRL.start (one cycle; ignored while busy)");
    m.input_c("frame_i", 32, "FRAME");
    m.input_c("tiles_i", 32, "TILES");
    m.input_c("width_i", 16, "image width");
    m.input_c("height_i", 16, "image height");
    for b in ["desc", "result", "feat", "fb", "scratch"] {
        m.input_c(format!("{b}_base_i"), xa, "byte address");
    }
    m.input_c("adapt_ctrl_i", 32, "ADAPT_CTRL: the controller plans the DPS passes (golden engine::adapt)");
    m.output_c("busy_o", 1, "STATUS.busy");
    m.output_c("done_o", 1, "STATUS.done");
    m.output_c("overflow_o", 1, "STATUS.overflow");
    m.output_c("first_overflow_o", 32, "FIRST_OVERFLOW");
    m.output_c("overflows_o", 32, "OVERFLOWS");
    // AXI client 0.
    super::axi::ports(m, cfg, "m_axi_", true);
    for v in [
        "job_valid_o",
        "job_ready_i",
        "cpl_valid_i",
        "cpl_ready_o",
        "ras_valid_o",
        "ras_ready_i",
        "ras_done_i",
    ] {
        m.vector(v);
    }
    // Sequencers.
    m.output_c("job_valid_o", d.n, "per sequencer: a tile job");
    m.input_c("job_ready_i", d.n, "per sequencer: idle");
    m.output_c("job_from_scratch_o", 1, "shared job payload: descriptor fields");
    m.output("job_prev_o", aw);
    m.output("job_prev_len_o", lw);
    m.output("job_list_o", aw);
    m.output("job_list_len_o", lw);
    m.output("job_next_o", aw);
    m.output_c("job_dps_passes_o", DPS_PASSES_BITS, "descriptor: DPS passes");
    m.output_c("job_dps_wide_o", 1, "descriptor: DPS in wide chunks");
    m.output_c("job_odd_o", 1, "FRAME[0]");
    m.output_c("job_scratch_o", d.n * aw, "sequencer k's scratch entry base at [k*AW +: AW]");
    m.input_c("cpl_valid_i", d.n, "per sequencer: tile sorted");
    m.output_c("cpl_ready_o", d.n, "");
    m.input_c("cpl_len_i", d.n * lw, "sequencer k's next_len at [k*LW +: LW]");
    m.input_c("cpl_inv_i", d.n * lw, "sequencer k's merge inversions at [k*LW +: LW]");
    // Raster cores.
    m.output_c("ras_valid_o", d.m, "per raster core: command");
    m.input_c("ras_ready_i", d.m, "");
    m.output_c("ras_tile_x_o", d.tb, "shared raster command payload");
    m.output("ras_tile_y_o", d.tb);
    m.output("ras_width_o", 16);
    m.output("ras_height_o", 16);
    m.output("ras_table_o", aw);
    m.output("ras_len_o", lw);
    m.output("ras_feat_o", aw);
    m.output("ras_pix_o", aw);
    m.input_c("ras_done_i", d.m, "per raster core: tile finished");
    m.input_c("ras_wb_len_i", d.m * lw, "raster core j's write-back len at [j*LW +: LW] (with its done)");
    m.input_c("ras_wb_reach_i", d.m * lw, "raster core j's write-back reach at [j*LW +: LW]");
    m.input_c("idle_i", d.n + d.m, "per bridge (sort bridges, then raster bridges): idle");
    // Events.
    m.output_c("ev_desc_read_o", 1, "a descriptor read");
    m.output_c("ev_tile_sorted_o", 1, "a tile handed to a sequencer ...");
    m.output_c("ev_entries_sorted_o", lw + 1, "... with its entries_in");
    m.output_c("ev_tile_rastered_o", bits_for(d.m as u64), "raster done pulses this cycle");
    m.output_c("ev_entries_rastered_o", lw, "a raster command's len (when taken)");
    m.output_c("ev_result_written_o", 1, "a result's write response");
    m.output_c("ev_result_read_o", 1, "a previous result read (its last beat)");
    let _ = cfg;
}

fn status(m: &mut Module, d: &Dims) {
    let (qb, qd) = (d.qb, d.qd);
    m.blank();
    m.comment("Completion-queue pointers.");
    m.reg("cq_wp_q", qb + 1).reg("cq_rp_q", qb + 1);
    m.wire_assign("cq_count", qb + 1, "cq_wp_q - cq_rp_q");
    m.wire_assign("cq_space", 1, format!("cq_count != {}", lit(qb + 1, qd as u64)));
    m.wire_assign("cq_empty", 1, "cq_wp_q == cq_rp_q");
    m.blank();
    m.comment("Status.");
    m.reg("busy_q", 1).reg("done_q", 1).reg("first_ovf_q", 32).reg("ovfs_q", 32).reg("rastered_q", 32);
    m.wire_assign("start", 1, "start_i & ~busy_q");
    m.assign("busy_o", "busy_q");
    m.assign("done_o", "done_q");
    m.assign("overflow_o", format!("ovfs_q != {}", lit(32, 0)));
    m.assign("first_overflow_o", "first_ovf_q");
    m.assign("overflows_o", "ovfs_q");
}

/// Reads on AXI client 0, one burst at a time: descriptors (4 beats at `DESC_BASE + 32 t`, into
/// the descriptor buffer) and, when the frame controller plans the passes (`ADAPT_CTRL`),
/// previous results (2 beats at `RESULT_BASE + 16 t`): every tile's in the scan, then each
/// tile's again after its descriptor.
fn fetch(m: &mut Module, d: &Dims) {
    let (xa, xd, xi) = (d.xa, d.xd, d.xi);
    m.blank();
    m.comment(
        "Reads: descriptor t (fetch_q) into w0_q..w3_q (dv_q: buffer full), previous results (kind_q).",
    );
    m.reg("fetch_q", 32).reg("ar_q", 1).reg("rd_q", 1).reg("beat_q", 2).reg("dv_q", 1).reg("dt_q", 32);
    m.reg("kind_q", 1).reg("res_pend_q", 1).reg("scan_q", 1).reg("scan_t_q", 32);
    m.reg("w0_q", 1 + 2 * d.tb)
        .reg("passes_q", DPS_PASSES_BITS)
        .reg("wide_q", 1)
        .reg("w1_q", 64)
        .reg("w2_q", 64)
        .reg("w3_q", 32);
    m.wire_assign("more", 1, "fetch_q != tiles_i");
    m.wire_assign("ad_en", 1, format!("adapt_ctrl_i[{}]", ADAPT_ENABLE.trailing_zeros()));
    m.wire_assign("rd_idle", 1, "busy_q & ~ar_q & ~rd_q");
    m.wire_assign("scan_start", 1, "rd_idle & scan_q & (scan_t_q != tiles_i)");
    m.wire_assign("res_start", 1, "rd_idle & res_pend_q");
    m.wire_assign("ar_start", 1, "rd_idle & ~scan_q & ~cap_q & ~res_pend_q & more & ~dv_q");
    m.wire_assign("res_t", 32, "scan_q ? scan_t_q : dt_q");
    m.assign("m_axi_arvalid_o", "ar_q");
    m.assign("m_axi_arid_o", lit(xi, 0));
    m.assign(
        "m_axi_araddr_o",
        format!(
            "kind_q ? (result_base_i + {{{}, 4'd0}}) : (desc_base_i + {{{}, 5'd0}})",
            resize("res_t", 32, xa - 4),
            resize("fetch_q", 32, xa - 5)
        ),
    );
    m.assign("m_axi_arlen_o", "kind_q ? 8'd1 : 8'd3");
    if xa - 4 < 32 {
        // Tile indices above the byte address width's reach are not used.
        m.wire_assign("unused_res_t", 1, format!("^res_t[31:{}]", xa - 4));
    }
    m.assign("m_axi_arsize_o", lit(3, 3));
    m.assign("m_axi_arburst_o", lit(2, 1));
    m.assign("m_axi_rready_o", "rd_q");
    // Register bits below the alignment of their base (and FRAME above the parity), and the
    // reserved ADAPT_CTRL bits, are not used.
    m.wire_assign(
        "unused_regs",
        1,
        format!(
            "^{{frame_i[31:1], feat_base_i[4:0], fb_base_i[1:0], scratch_base_i[2:0], adapt_ctrl_i[31:{}], adapt_ctrl_i[{}:{}], adapt_ctrl_i[{}:1]}}",
            ADAPT_MAX_LSB + ADAPT_MAX_BITS,
            ADAPT_MAX_LSB - 1,
            ADAPT_BUDGET_LSB + ADAPT_BUDGET_BITS,
            ADAPT_BUDGET_LSB - 1
        ),
    );
    m.wire_assign("r_fire", 1, "m_axi_rvalid_i & rd_q");
    m.wire_assign("r_word", 64, "m_axi_rdata_i[63:0]");
    m.wire_assign("desc_in", 1, "r_fire & ~kind_q & (beat_q == 2'd3)");
    m.wire_assign("res_in", 1, "r_fire & kind_q & (beat_q == 2'd1)");
    m.comment(
        "The descriptor buffer is full after the descriptor, or in a planned frame after the tile's result.",
    );
    m.wire_assign("dv_in", 1, "(desc_in & ~ad_en) | (res_in & ~scan_q)");
    m.assign("ev_desc_read_o", "desc_in");
    m.assign("ev_result_read_o", "res_in");
    // The unused response fields (single ID, responses in order; errors are not reported).
    m.wire_assign(
        "unused_r",
        1,
        unused_xor(&[("m_axi_rid_i", xi), ("m_axi_rresp_i", 2), ("m_axi_rlast_i", 1)], xd, "m_axi_rdata_i"),
    );
    m.seq(
        vec![
            set("fetch_q", lit(32, 0)),
            set("ar_q", "1'b0"),
            set("rd_q", "1'b0"),
            set("beat_q", "2'd0"),
            set("dt_q", lit(32, 0)),
            set("kind_q", "1'b0"),
            set("res_pend_q", "1'b0"),
            set("scan_q", "1'b0"),
            set("scan_t_q", lit(32, 0)),
        ],
        vec![
            if_(
                "start",
                vec![
                    set("fetch_q", lit(32, 0)),
                    set("scan_q", "ad_en"),
                    set("scan_t_q", lit(32, 0)),
                    set("res_pend_q", "1'b0"),
                ],
            ),
            if_("scan_start | res_start", vec![set("ar_q", "1'b1"), set("kind_q", "1'b1")]),
            if_("ar_start", vec![set("ar_q", "1'b1"), set("kind_q", "1'b0")]),
            if_(
                "ar_q & m_axi_arready_i",
                vec![set("ar_q", "1'b0"), set("rd_q", "1'b1"), set("beat_q", "2'd0")],
            ),
            if_("r_fire", vec![set("beat_q", "beat_q + 2'd1")]),
            if_(
                "desc_in",
                vec![
                    set("rd_q", "1'b0"),
                    set("dt_q", "fetch_q"),
                    set("fetch_q", format!("fetch_q + {}", lit(32, 1))),
                    set("res_pend_q", "ad_en"),
                ],
            ),
            if_(
                "res_in",
                vec![
                    set("rd_q", "1'b0"),
                    if_else(
                        "scan_q",
                        vec![set("scan_t_q", format!("scan_t_q + {}", lit(32, 1)))],
                        vec![set("res_pend_q", "1'b0")],
                    ),
                ],
            ),
            if_("scan_done", vec![set("scan_q", "1'b0")]),
        ],
    );
    let tb = d.tb;
    let w0 = format!("{{r_word[32], r_word[{}:16], r_word[{}:0]}}", 15 + tb, tb - 1);
    let passes = format!("r_word[{}:{DPS_PASSES_LSB}]", DPS_PASSES_LSB + DPS_PASSES_BITS - 1);
    m.seq_noreset(vec![
        if_(
            "r_fire & ~kind_q",
            vec![Stmt::Case(
                "beat_q".into(),
                vec![
                    (
                        "2'd0".into(),
                        vec![
                            set("w0_q", w0),
                            set("passes_q", passes),
                            set("wide_q", format!("r_word[{DPS_WIDE_BIT}]")),
                        ],
                    ),
                    ("2'd1".into(), vec![set("w1_q", "r_word")]),
                    ("2'd2".into(), vec![set("w2_q", "r_word")]),
                ],
                vec![set("w3_q", "r_word[31:0]")],
            )],
        ),
        if_("res_in & ~scan_q", vec![set("passes_q", "ad_plan"), set("wide_q", "rq_wide")]),
    ]);
    m.comment("Decoded descriptor and its overflow check.");
    m.wire_assign("d_fs", 1, format!("w0_q[{}]", 2 * tb));
    m.wire_assign("d_x", tb, resize_part("w0_q", tb - 1, 0, tb));
    m.wire_assign("d_y", tb, resize_part("w0_q", 2 * tb - 1, tb, tb));
    m.wire_assign("d_ein", 33, "{1'b0, w2_q[63:32]} + (d_fs ? 33'd0 : {1'b0, w1_q[63:32]})");
}

/// Bits of the adaptive accumulators (pass costs summed over the tiles).
const ACC_BITS: u32 = 64;
/// Bits of the budget comparisons (`100 x` a sum, a sum times the budget).
const CMP_BITS: u32 = ACC_BITS + ADAPT_BUDGET_BITS;

/// The frame controller's own `adaptive` plan (golden `engine::adapt`): the request of the
/// previous result being read, the scan's sums, the cap and the walk's grant.
fn adapt(m: &mut Module, cfg: &EngineConfig) {
    let cb = (cfg.chunk as u64).trailing_zeros();
    let pb = DPS_PASSES_BITS;
    let top = (1u32 << pb) - 1;
    let levels = top - 1;
    m.blank();
    m.comment(
        "Adaptive plan (ADAPT_CTRL): the request of the result read (beat 1, with beat 0's inversions).",
    );
    m.reg("rinv_q", 1);
    m.seq_noreset(vec![if_(
        "r_fire & kind_q & (beat_q == 2'd0)",
        vec![set("rinv_q", format!("|r_word[63:{INVERSIONS_LSB}]"))],
    )]);
    let hi = |lsb: u32, bits: u32| lsb + bits - 1;
    m.wire_assign(
        "ad_budget",
        ADAPT_BUDGET_BITS,
        format!("adapt_ctrl_i[{}:{ADAPT_BUDGET_LSB}]", hi(ADAPT_BUDGET_LSB, ADAPT_BUDGET_BITS)),
    );
    m.wire_assign(
        "ad_max_f",
        pb,
        format!("adapt_ctrl_i[{}:{ADAPT_MAX_LSB}]", hi(ADAPT_MAX_LSB, ADAPT_MAX_BITS)),
    );
    m.comment("A max of 0 grants one pass (golden: every plan has at least one).");
    m.wire_assign("ad_max", pb, format!("(ad_max_f == {}) ? {} : ad_max_f", lit(pb, 0), lit(pb, 1)));
    m.wire_assign("rq_len", 32, "r_word[31:0]");
    let wb = (cfg.dps_wide as u64).trailing_zeros();
    if wb == 0 {
        m.comment("This engine has no wide chunk (dps_wide 1): ADAPT_CTRL's wide bit is ignored.");
        m.wire_assign("rq_wide", 1, "1'b0");
        m.wire_assign("rq_steps", 32, format!("r_word[63:32] >> {cb}"));
    } else {
        m.comment("Wide (ADAPT_CTRL's wide bit and a reach of a chunk at least): U = W, else U = C.");
        m.wire_assign(
            "rq_wide",
            1,
            format!(
                "adapt_ctrl_i[{}] & (r_word[63:{}] != {})",
                ADAPT_WIDE.trailing_zeros(),
                32 + cb,
                lit(32 - cb, 0)
            ),
        );
        m.wire_assign(
            "rq_steps",
            32,
            format!("rq_wide ? (r_word[63:32] >> {}) : (r_word[63:32] >> {cb})", cb + wb),
        );
    }
    m.comment("p = 1 + reach / U, plus one when p > 1 and the merge saw inversions, at most max.");
    m.wire_assign(
        "rq_p",
        34,
        format!("{{2'd0, rq_steps}} + {} + {{33'd0, (rq_steps != {}) & rinv_q}}", lit(34, 1), lit(32, 0)),
    );
    m.wire_assign(
        "rq_pass",
        pb,
        format!("(rq_p > {}) ? ad_max : rq_p[{}:0]", zext("ad_max", pb, 34), pb - 1),
    );
    m.comment("The pass cost: 2 len entries, at least 1.");
    m.wire_assign(
        "rq_cost",
        ACC_BITS,
        format!(
            "(rq_len == {}) ? {} : {{{}, rq_len, 1'b0}}",
            lit(32, 0),
            lit(ACC_BITS, 1),
            lit(ACC_BITS - 33, 0)
        ),
    );
    m.comment(format!(
        "Scan: S (every cost) and hist[l - 2] (costs of requests of at least l passes), l = 2..{top}."
    ));
    m.reg("sum_q", ACC_BITS).mem("hist", ACC_BITS, levels).integer("l");
    let at_least = format!("rq_pass >= (l[{}:0] + {})", pb - 1, lit(pb, 2));
    m.seq_noreset(vec![for_(
        "l",
        levels.to_string(),
        vec![if_else(
            "start",
            vec![set("hist[l]", lit(ACC_BITS, 0))],
            vec![if_(format!("res_in & scan_q & ({at_least})"), vec![set("hist[l]", "hist[l] + rq_cost")])],
        )],
    )]);
    m.wire_assign("scan_done", 1, "scan_q & (scan_t_q == tiles_i)");
    m.comment(format!(
        "Cap: the largest c with 100 (hist[0] + ... + hist[c - 2]) <= S x budget (c = 1..{top})."
    ));
    // spent_q: during the cap, the extra cost of the cap so far; in the walk, plus the raises.
    m.reg("cap_q", 1).reg("lvl_q", pb).reg("c_q", pb).reg("spent_q", ACC_BITS);
    m.wire_assign(
        "sb",
        CMP_BITS,
        format!("{} * {}", zext("sum_q", ACC_BITS, CMP_BITS), zext("ad_budget", ADAPT_BUDGET_BITS, CMP_BITS)),
    );
    let ib = bits_for(levels as u64 - 1);
    m.wire_assign("lvl_idx", pb, format!("lvl_q - {}", lit(pb, 2)));
    m.wire_assign("cap_next", ACC_BITS, format!("spent_q + hist[{}]", resize("lvl_idx", pb, ib)));
    let hundred = |v: &str| format!("({} * {})", zext(v, ACC_BITS, CMP_BITS), lit(CMP_BITS, 100));
    m.wire_assign("cap_fits", 1, format!("{} <= sb", hundred("cap_next")));
    m.comment(
        "Walk: min(p, c), or c + 1 when p > c and 100 (spent + cost) <= S x budget (then spent += cost).",
    );
    m.wire_assign("walk_spend", ACC_BITS, "spent_q + rq_cost");
    m.wire_assign("walk_raise", 1, format!("(rq_pass > c_q) & ({} <= sb)", hundred("walk_spend")));
    m.wire_assign(
        "ad_plan",
        pb,
        format!("(rq_pass <= c_q) ? rq_pass : (walk_raise ? c_q + {} : c_q)", lit(pb, 1)),
    );
    let init = vec![
        set("cap_q", "1'b0"),
        set("lvl_q", lit(pb, 2)),
        set("c_q", lit(pb, 1)),
        set("spent_q", lit(ACC_BITS, 0)),
        set("sum_q", lit(ACC_BITS, 0)),
    ];
    m.seq(
        init.clone(),
        vec![if_else(
            "start",
            init,
            vec![
                if_("res_in & scan_q", vec![set("sum_q", "sum_q + rq_cost")]),
                if_("scan_done", vec![set("cap_q", "1'b1")]),
                if_(
                    "cap_q",
                    vec![if_else(
                        "cap_fits",
                        vec![
                            set("c_q", "lvl_q"),
                            set("spent_q", "cap_next"),
                            if_else(
                                format!("lvl_q == {}", lit(pb, top as u64)),
                                vec![set("cap_q", "1'b0")],
                                vec![set("lvl_q", format!("lvl_q + {}", lit(pb, 1)))],
                            ),
                        ],
                        vec![set("cap_q", "1'b0")],
                    )],
                ),
                if_("res_in & ~scan_q & walk_raise", vec![set("spent_q", "walk_spend")]),
            ],
        )],
    );
}

/// `^{a, b, ...}` over whole inputs that are deliberately unused (lint: read once).
fn unused_xor(sigs: &[(&str, u32)], data_bits: u32, data: &str) -> String {
    let mut parts: Vec<String> = sigs.iter().map(|(s, _)| s.to_string()).collect();
    if data_bits > 64 {
        parts.push(format!("{data}[{}:64]", data_bits - 1));
    }
    format!("^{{{}}}", parts.join(", "))
}

/// The sort dispatch: overflow tiles to the completion queue, the others to a sequencer.
fn dispatch(m: &mut Module, cfg: &EngineConfig, d: &Dims) {
    let (n, aw, lw, nb) = (d.n, d.aw, d.lw, d.nb);
    let cap = cfg.table_capacity as u64;
    m.blank();
    m.comment(format!("Sort dispatch ({} over {n} sequencers).", cfg.scheduler.name()));
    m.wire_assign("d_ovf", 1, format!("d_ein > {}", lit(33, cap)));
    m.reg("rr_q", nb);
    m.wire("job_sel", nb).wire("job_any", 1);
    if d.rr {
        m.assign("job_sel", "rr_q");
        m.assign("job_any", pick("job_ready_i", "rr_q", n));
    } else {
        lowest_set(m, "job_sel_c", nb, "job_ready_i", n);
        m.assign("job_sel", "job_sel_c");
        m.assign("job_any", "|job_ready_i");
    }
    m.wire_assign("ovf_push", 1, "dv_q & d_ovf & cq_space");
    m.wire_assign("job_offer", 1, "dv_q & ~d_ovf");
    m.wire_assign("job_fire", 1, "job_offer & job_any");
    m.assign("job_valid_o", format!("job_offer ? ({} << job_sel) : {}", lit(n, 1), lit(n, 0)));
    m.assign("job_from_scratch_o", "d_fs");
    m.assign("job_prev_o", resize_part("w1_q", 31, 0, aw));
    m.assign("job_prev_len_o", resize_part("w1_q", 63, 32, lw));
    m.assign("job_list_o", resize_part("w2_q", 31, 0, aw));
    m.assign("job_list_len_o", resize_part("w2_q", 63, 32, lw));
    m.assign("job_next_o", resize_part("w3_q", 31, 0, aw));
    m.assign("job_dps_passes_o", "passes_q");
    m.assign("job_dps_wide_o", "wide_q");
    m.assign("job_odd_o", "frame_i[0]");
    m.wire_assign("scratch_entry", aw, resize_part("scratch_base_i", d.xa - 1, 3, aw));
    let scr: Vec<String> =
        (0..n).rev().map(|k| format!("scratch_entry + {}", lit(aw, 2 * cap * k as u64))).collect();
    m.assign("job_scratch_o", format!("{{{}}}", scr.join(", ")));
    m.assign("ev_tile_sorted_o", "job_fire");
    m.assign(
        "ev_entries_sorted_o",
        format!("job_fire ? {} : {}", resize("d_ein", 33, lw + 1), lit(lw + 1, 0)),
    );
    m.comment("Per sequencer: the tile it sorts (index, tile_x, tile_y, next).");
    m.mem("seq_t", 32, n).mem("seq_x", d.tb, n).mem("seq_y", d.tb, n).mem("seq_next", aw, n);
    m.seq_noreset(vec![if_(
        "job_fire",
        vec![
            set("seq_t[job_sel]", "dt_q"),
            set("seq_x[job_sel]", "d_x"),
            set("seq_y[job_sel]", "d_y"),
            set("seq_next[job_sel]", resize_part("w3_q", 31, 0, aw)),
        ],
    )]);
}

/// `reg` (`bits` wide, combinational): the index of the lowest set bit of the `count`-bit
/// `vector`, 0 when none is set (a priority encoder: the first-free scheduler, the completion
/// and result pickers).
fn lowest_set(m: &mut Module, reg: &str, bits: u32, vector: &str, count: u32) {
    let mut body = vec![set(reg, lit(bits, 0))];
    for k in (0..count).rev() {
        body.push(if_(pick(vector, &k.to_string(), count), vec![set(reg, lit(bits, k as u64))]));
    }
    m.reg(reg, bits);
    m.comb(body);
}

/// Bit `index` of the `count`-bit signal `name` (the signal itself when it has one bit).
fn pick(name: &str, index: &str, count: u32) -> String {
    if count == 1 {
        name.to_string()
    } else {
        format!("{name}[{index}]")
    }
}

/// `name[hi:lo]` resized to `to` bits: its low `to` bits, or zero-extended ([`zext`]).
fn resize_part(name: &str, hi: u32, lo: u32, to: u32) -> String {
    let w = hi - lo + 1;
    if w > to {
        format!("{name}[{}:{lo}]", lo + to - 1)
    } else {
        zext(&format!("{name}[{hi}:{lo}]"), w, to)
    }
}

/// Sequencer completions into the completion queue (overflow tiles first).
fn completions(m: &mut Module, d: &Dims) {
    let (n, nb, qb, qd, lw) = (d.n, d.nb, d.qb, d.qd, d.lw);
    let _ = qd;
    m.blank();
    m.comment(format!("Completion queue ({qd} entries): overflow tiles first, then the lowest sequencer."));
    let fields = cq_fields(d);
    let ew: u32 = fields.iter().map(|f| f.1).sum();
    m.mem("cq", ew, qd);
    lowest_set(m, "cpl_sel", nb, "cpl_valid_i", n);
    m.wire_assign("cpl_take", 1, "(|cpl_valid_i) & cq_space & ~ovf_push");
    m.assign("cpl_ready_o", format!("cpl_take ? ({} << cpl_sel) : {}", lit(n, 1), lit(n, 0)));
    m.wire_assign("cpl_len", lw, format!("cpl_len_i[cpl_sel * {lw} +: {lw}]"));
    m.wire_assign("cpl_inv", lw, format!("cpl_inv_i[cpl_sel * {lw} +: {lw}]"));
    let ovf_entry = format!(
        "{{{}, 1'b1, {}, {}, {}, {}, dt_q}}",
        lit(lw, 0),
        lit(lw, 0),
        resize_part("w3_q", 31, 0, d.aw),
        "d_y",
        "d_x"
    );
    let cpl_entry =
        "{cpl_inv, 1'b0, cpl_len, seq_next[cpl_sel], seq_y[cpl_sel], seq_x[cpl_sel], seq_t[cpl_sel]}";
    m.wire_assign("cq_push", 1, "ovf_push | cpl_take");
    m.wire_assign("cq_in", ew, format!("ovf_push ? {ovf_entry} : {cpl_entry}"));
    m.seq_noreset(vec![if_("cq_push", vec![set(format!("cq[cq_wp_q[{}:0]]", qb - 1), "cq_in")])]);
    m.comment("The head entry.");
    m.wire_assign("cq_head", ew, format!("cq[cq_rp_q[{}:0]]", qb - 1));
    m.unpack_fields("cq_head", &fields.iter().map(|(f, w)| (format!("h_{f}"), *w)).collect::<Vec<_>>());
}

/// The head's raster dispatch.
fn head(m: &mut Module, cfg: &EngineConfig, d: &Dims) {
    let (mm, mb, xa, aw, lw) = (d.m, d.mb, d.xa, d.aw, d.lw);
    m.blank();
    m.comment(format!(
        "Raster dispatch of the queue's head ({} over {mm} cores; a core whose result is not written waits).",
        cfg.scheduler.name()
    ));
    m.reg("rrr_q", mb);
    m.wire_assign("ras_free", mm, "ras_ready_i & ~rp_q & ~ras_done_i");
    m.wire("ras_sel", mb).wire("ras_any", 1);
    if d.rr {
        m.assign("ras_sel", "rrr_q");
        m.assign("ras_any", pick("ras_free", "rrr_q", mm));
    } else {
        lowest_set(m, "ras_sel_c", mb, "ras_free", mm);
        m.assign("ras_sel", "ras_sel_c");
        m.assign("ras_any", "|ras_free");
    }
    // The command is offered only to a core whose result is written (a core's ready says
    // nothing about that).
    let held = format!("({} | {})", pick("rp_q", "ras_sel", mm), pick("ras_done_i", "ras_sel", mm));
    m.wire_assign("ras_offer", 1, format!("~cq_empty & ~{held}"));
    m.wire_assign("ras_fire", 1, "~cq_empty & ras_any");
    m.assign("ras_valid_o", format!("ras_offer ? ({} << ras_sel) : {}", lit(mm, 1), lit(mm, 0)));
    m.assign("ras_tile_x_o", "h_x");
    m.assign("ras_tile_y_o", "h_y");
    m.assign("ras_width_o", "width_i");
    m.assign("ras_height_o", "height_i");
    m.assign("ras_table_o", "h_next");
    m.assign("ras_len_o", "h_len");
    m.assign("ras_feat_o", resize_part("feat_base_i", xa - 1, 5, aw));
    let sh = (cfg.tile * cfg.tile).trailing_zeros();
    m.wire_assign("pix_off", aw, format!("{} << {sh}", resize("h_t", 32, aw)));
    m.assign("ras_pix_o", format!("{} + pix_off", resize_part("fb_base_i", xa - 1, 2, aw)));
    m.assign("ev_entries_rastered_o", format!("ras_fire ? h_len : {}", lit(lw, 0)));
    // Address bits above the entry-address width (narrow configurations) are not used.
    let mut dropped = Vec::new();
    if aw < 32 {
        for w in ["w1_q", "w2_q", "w3_q", "h_t"] {
            dropped.push(format!("{w}[31:{aw}]"));
        }
    }
    for (b, lo) in [("scratch_base_i", 3), ("feat_base_i", 5), ("fb_base_i", 2)] {
        if xa - lo > aw {
            dropped.push(format!("{b}[{}:{}]", xa - 1, lo + aw));
        }
    }
    if !dropped.is_empty() {
        m.wire_assign("unused_trunc", 1, format!("^{{{}}}", dropped.join(", ")));
    }
    m.wire_assign("cq_pop", 1, "ras_fire");
    control(m, d);
}

/// `reg + 1` wrapping at `count`.
fn wrap(reg: &str, bits: u32, count: u32) -> String {
    if count.is_power_of_two() {
        format!("{reg} + {}", lit(bits, 1))
    } else {
        format!("({reg} == {}) ? {} : ({reg} + {})", lit(bits, count as u64 - 1), lit(bits, 0), lit(bits, 1))
    }
}

/// The controller's status, dispatch and queue registers.
fn control(m: &mut Module, d: &Dims) {
    let (mm, mb, n, nb, qb) = (d.m, d.mb, d.n, d.nb, d.qb);
    // Every control register but the fetch engine's (reset in its own block), the descriptor
    // words (datapath, no reset) and the result writer's (its own block).
    let own = [
        "fetch_q",
        "ar_q",
        "rd_q",
        "beat_q",
        "dt_q",
        "w0_q",
        "passes_q",
        "wide_q",
        "w1_q",
        "w2_q",
        "w3_q",
        "kind_q",
        "res_pend_q",
        "scan_q",
        "scan_t_q",
        "rinv_q",
        "sum_q",
        "cap_q",
        "lvl_q",
        "c_q",
        "spent_q",
    ];
    finish(m, d);
    let mut reset = m.q_resets(&[("first_ovf_q", "32'hffffffff")]);
    reset.retain(|s| !matches!(s, Stmt::Set(n, _) if own.contains(&n.as_str()) || n.starts_with("rw_") || n == "rp_q" || n == "wr_out_q"));
    m.seq(
        reset,
        vec![
            if_(
                "start",
                vec![
                    set("busy_q", "1'b1"),
                    set("done_q", "1'b0"),
                    set("first_ovf_q", "32'hffffffff"),
                    set("ovfs_q", lit(32, 0)),
                    set("rr_q", lit(nb, 0)),
                    set("rrr_q", lit(mb, 0)),
                ],
            ),
            if_("finish", vec![set("busy_q", "1'b0"), set("done_q", "1'b1")]),
            if_("dv_in", vec![set("dv_q", "1'b1")]),
            if_("ovf_push | job_fire", vec![set("dv_q", "1'b0")]),
            if_(
                "ovf_push",
                vec![
                    if_(format!("ovfs_q == {}", lit(32, 0)), vec![set("first_ovf_q", "dt_q")]),
                    set("ovfs_q", format!("ovfs_q + {}", lit(32, 1))),
                ],
            ),
            if_("job_fire", vec![set("rr_q", wrap("rr_q", nb, n))]),
            if_("ras_fire", vec![set("rrr_q", wrap("rrr_q", mb, mm))]),
            if_("cq_push", vec![set("cq_wp_q", format!("cq_wp_q + {}", lit(qb + 1, 1)))]),
            if_("cq_pop", vec![set("cq_rp_q", format!("cq_rp_q + {}", lit(qb + 1, 1)))]),
            if_("ras_done_cnt != 32'd0", vec![set("rastered_q", "rastered_q + ras_done_cnt")]),
            if_("start", vec![set("rastered_q", lit(32, 0))]),
        ],
    );
}

/// Result records per raster core and the result writer.
fn results(m: &mut Module, cfg: &EngineConfig, d: &Dims) {
    let (mm, mb, xa, xd, xi, lw, ob) = (d.m, d.mb, d.xa, d.xd, d.xi, d.lw, d.ob);
    let o = cfg.axi_outstanding as u64;
    m.blank();
    m.comment("Result records: the dispatched head's fields per raster core, completed by its done pulse.");
    m.mem("rc_t", 32, mm).mem("rc_len", lw, mm).mem("rc_ovf", 1, mm).mem("rc_inv", lw, mm);
    m.mem("rc_wbl", lw, mm).mem("rc_reach", lw, mm);
    m.reg("rp_q", mm);
    let mut rec = vec![if_(
        "ras_fire",
        vec![
            set("rc_t[ras_sel]", "h_t"),
            set("rc_len[ras_sel]", "h_len"),
            set("rc_ovf[ras_sel]", "h_ovf"),
            set("rc_inv[ras_sel]", "h_inv"),
        ],
    )];
    m.integer("j");
    let part = |v: &str| format!("{v}[j*{lw} +: {lw}]");
    rec.push(for_(
        "j",
        mm.to_string(),
        vec![if_(
            "ras_done_i[j]",
            vec![set("rc_wbl[j]", part("ras_wb_len_i")), set("rc_reach[j]", part("ras_wb_reach_i"))],
        )],
    ));
    m.seq_noreset(rec);
    m.blank();
    m.comment("Result writer: the lowest complete record, one 2-beat burst at RESULT_BASE + 16 t (golden TileResult).");
    m.reg("rw_act_q", 1).reg("rw_idx_q", mb).reg("rw_aw_q", 1).reg("rw_beat_q", 2).reg("wr_out_q", ob);
    lowest_set(m, "rw_pick", mb, "rp_q", mm);
    m.wire_assign("wr_room", 1, format!("wr_out_q != {}", lit(ob, o)));
    m.assign("m_axi_awvalid_o", "rw_act_q & ~rw_aw_q & wr_room");
    m.assign("m_axi_awid_o", lit(xi, 0));
    m.assign("m_axi_awaddr_o", format!("result_base_i + {{{}, 4'd0}}", resize("rc_t[rw_idx_q]", 32, xa - 4)));
    m.assign("m_axi_awlen_o", lit(8, 1));
    m.assign("m_axi_awsize_o", lit(3, 3));
    m.assign("m_axi_awburst_o", lit(2, 1));
    m.assign("m_axi_wvalid_o", "rw_act_q & ~rw_beat_q[1] & (rw_aw_q | wr_room)");
    // The inversions saturate at the field's all-ones value (golden TileResult::new).
    let sat = INVERSIONS_MAX as u64;
    let inv = if lw > INVERSIONS_BITS {
        format!(
            "(rc_inv[rw_idx_q] > {}) ? {} : rc_inv[rw_idx_q][{}:0]",
            lit(lw, sat),
            lit(INVERSIONS_BITS, sat),
            INVERSIONS_BITS - 1
        )
    } else {
        resize("rc_inv[rw_idx_q]", lw, INVERSIONS_BITS)
    };
    m.wire_assign("rw_inv", INVERSIONS_BITS, inv);
    let len32 = |v: &str| resize(v, lw, 32);
    let gap = INVERSIONS_LSB - 33;
    m.wire_assign(
        "rw_word0",
        64,
        format!("{{rw_inv, {}, rc_ovf[rw_idx_q], {}}}", lit(gap, 0), len32("rc_len[rw_idx_q]")),
    );
    m.wire_assign(
        "rw_word1",
        64,
        format!("{{{}, {}}}", len32("rc_reach[rw_idx_q]"), len32("rc_wbl[rw_idx_q]")),
    );
    let word = "(rw_beat_q[0] ? rw_word1 : rw_word0)";
    m.assign("m_axi_wdata_o", if xd > 64 { format!("{{{}'d0, {word}}}", xd - 64) } else { word.to_string() });
    m.assign("m_axi_wstrb_o", format!("{{{}{{1'b1}}}}", xd / 8));
    m.assign("m_axi_wlast_o", "rw_beat_q[0]");
    m.assign("m_axi_bready_o", "1'b1");
    m.wire_assign("aw_fire", 1, "m_axi_awvalid_o & m_axi_awready_i");
    m.wire_assign("w_fire", 1, "m_axi_wvalid_o & m_axi_wready_i");
    m.wire_assign("b_fire", 1, "m_axi_bvalid_i");
    m.wire_assign("unused_b", 1, "^{m_axi_bid_i, m_axi_bresp_i}");
    m.assign("ev_result_written_o", "b_fire");
    m.wire_assign("rw_end", 1, "rw_act_q & (rw_aw_q | aw_fire) & (rw_beat_q[1] | (w_fire & rw_beat_q[0]))");
    m.seq(
        vec![
            set("rp_q", lit(mm, 0)),
            set("rw_act_q", lit(1, 0)),
            set("rw_idx_q", lit(mb, 0)),
            set("rw_aw_q", lit(1, 0)),
            set("rw_beat_q", lit(2, 0)),
            set("wr_out_q", lit(ob, 0)),
        ],
        vec![
            set(
                "rp_q",
                format!("(rp_q | ras_done_i) & ~((rw_end ? {} : {}) << rw_idx_q)", lit(mm, 1), lit(mm, 0)),
            ),
            if_else(
                "rw_end",
                vec![set("rw_act_q", lit(1, 0)), set("rw_aw_q", lit(1, 0)), set("rw_beat_q", lit(2, 0))],
                vec![
                    if_("~rw_act_q & (|rp_q)", vec![set("rw_act_q", lit(1, 1)), set("rw_idx_q", "rw_pick")]),
                    if_("aw_fire", vec![set("rw_aw_q", lit(1, 1))]),
                    if_("w_fire", vec![set("rw_beat_q", format!("rw_beat_q + {}", lit(2, 1)))]),
                ],
            ),
            if_else(
                "aw_fire & ~b_fire",
                vec![set("wr_out_q", format!("wr_out_q + {}", lit(ob, 1)))],
                vec![if_("~aw_fire & b_fire", vec![set("wr_out_q", format!("wr_out_q - {}", lit(ob, 1)))])],
            ),
        ],
    );
}

/// Raster completions and the end of the frame.
fn finish(m: &mut Module, d: &Dims) {
    let mm = d.m;
    m.blank();
    m.comment("End of the frame: every tile rastered, every B back, every bridge idle.");
    let sum: Vec<String> =
        (0..mm).map(|k| format!("{{31'd0, {}}}", pick("ras_done_i", &k.to_string(), mm))).collect();
    m.wire_assign("ras_done_cnt", 32, sum.join(" + "));
    m.assign("ev_tile_rastered_o", resize("ras_done_cnt", 32, bits_for(mm as u64)));
    m.wire_assign(
        "finish",
        1,
        format!(
            "busy_q & ~start & ~more & ~dv_q & ~ar_q & ~rd_q & ~scan_q & ~cap_q & ~res_pend_q & cq_empty & (rastered_q == tiles_i) & ~(|rp_q) & ~rw_act_q & (wr_out_q == {}) & (&idle_i)",
            lit(d.ob, 0)
        ),
    );
}
