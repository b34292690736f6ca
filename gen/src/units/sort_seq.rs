//! `neo_sort_seq`: the command sequencer of one Sorting Core. It takes a tile job (the
//! descriptor's fields, the frame parity and the core's scratch base), plans the tile's
//! commands in hardware exactly as golden [`tile_plan`](neo_golden::engine::tile_plan) does and
//! drives them into `neo_sort_core`'s command port, with a barrier between stages, then reports
//! the tile's `next_len` on its completion port.
//!
//! # Stages (golden `tile_plan`)
//! With `n = list_len` and chunk `C`:
//! - SORT (when `n > 0`): one `SORT` per chunk of at most `C` list entries;
//! - MERGE passes: pass `s` merges pairs of runs of `h = C << (s - 1)` entries (a lone last run
//!   is copied with an empty B) until one run is left; a stage is the last when its output
//!   run covers the list (`n <= C` for SORT, `n - h <= h` for a pass);
//! - stage outputs ping-pong between the scratch regions `S0 = job_scratch_i` and `S1 = S0 +
//!   table_capacity` (`buf_q` = the region written), reading the list first; the last stage of a
//!   from-scratch tile writes `next`;
//! - reuse tiles then: `dps_passes` DPS stages (when `prev_len > 0`), chunks of `D` over `prev`
//!   in place, the first one `D/2` when `frame + pass` is odd (`odd_q ^ pass_q[0]`), with `D`
//!   the wide chunk `W = dps_wide * C` when the job's `dps_wide` is set (`wide_q`), else `C`;
//!   and one
//!   `MERGE_DELETE` of `prev` (A) and the sorted list (B, in `S[buf_q]`) into `next`.
//!
//! # Barrier
//! After a stage's last command is taken, the sequencer waits until every command it issued
//! has its `done_i` pulse (a count of commands in flight) and then for `idle_i` (the core's
//! memory bridge has every write acknowledged) before it issues the next stage or completes.
//! Completion: `cpl_len_o` = `list_len` (from scratch) or the `done_len_i` of the
//! `MERGE_DELETE`; `cpl_inv_o` = that `MERGE_DELETE`'s `done_inv_i` (the MSU+'s boundary
//! inversions of the reused table), 0 from scratch.

use crate::emit::expr::{bits_for, lit, resize};
use crate::emit::{if_, if_else, set, Module, Stmt};
use neo_golden::engine::memory::DPS_PASSES_BITS;
use neo_golden::engine::EngineConfig;
use neo_golden::sort::SortMode;

/// Module name.
pub const NAME: &str = "neo_sort_seq";

/// Sequencer states.
const S_IDLE: u64 = 0;
const S_ISSUE: u64 = 1;
const S_WAIT: u64 = 2;
const S_CPL: u64 = 3;

/// Widths of the sequencer for `cfg`.
struct Dims {
    /// Entry addresses.
    aw: u32,
    /// Lengths.
    lw: u32,
    /// Commands in flight (one stage at most).
    ow: u32,
}

impl Dims {
    fn new(cfg: &EngineConfig) -> Dims {
        let per_stage = (cfg.table_capacity / cfg.chunk) as u64 + 2;
        Dims { aw: cfg.addr_bits, lw: cfg.len_bits, ow: bits_for(per_stage) }
    }
}

/// The sequencer for `cfg`.
pub fn module(cfg: &EngineConfig) -> Module {
    let d = Dims::new(cfg);
    let mut m = Module::new(NAME);
    m.doc("Sorting Core command sequencer: a tile job -> the golden tile plan on the core's cmd port,");
    m.doc("a barrier (every done_i, then idle_i) between stages, completion with next_len.");
    ports(&mut m, &d);
    m.blank();
    for (n, v) in [("S_IDLE", S_IDLE), ("S_ISSUE", S_ISSUE), ("S_WAIT", S_WAIT), ("S_CPL", S_CPL)] {
        m.localparam(n, 2, lit(2, v));
    }
    for (n, v) in [
        ("M_SORT", SortMode::Sort),
        ("M_DPS", SortMode::Dps),
        ("M_MD", SortMode::MergeDelete),
        ("M_MERGE", SortMode::Merge),
    ] {
        m.localparam(n, SortMode::BITS, lit(SortMode::BITS, v.code()));
    }
    m.comment("The job (descriptor fields, parity, scratch base).");
    m.reg("fs_q", 1).reg("odd_q", 1).reg("prev_q", d.aw).reg("plen_q", d.lw).reg("list_q", d.aw);
    m.reg("n_q", d.lw).reg("next_q", d.aw).reg("scr0_q", d.aw).reg("passes_q", DPS_PASSES_BITS);
    m.reg("wide_q", 1);
    m.comment("Plan state: stage mode, offset in the stage, input run of a merge pass, scratch written,");
    m.comment("DPS pass.");
    m.reg("state_q", 2).reg("mode_q", SortMode::BITS).reg("pos_q", d.lw).reg("half_q", d.lw).reg("buf_q", 1);
    m.reg("pass_q", DPS_PASSES_BITS);
    m.reg("out_q", d.ow).reg("dlen_q", d.lw).reg("cpl_len_q", d.lw);
    m.reg("dinv_q", d.lw).reg("cpl_inv_q", d.lw);
    command(&mut m, cfg, &d);
    control(&mut m, cfg, &d);
    m
}

fn ports(m: &mut Module, d: &Dims) {
    let (aw, lw) = (d.aw, d.lw);
    m.clock_reset();
    m.input_c("job_valid_i", 1, "a tile job is offered");
    m.output_c("job_ready_o", 1, "... and taken (the sequencer is idle)");
    m.input_c("job_from_scratch_i", 1, "descriptor: no previous table");
    m.input_c("job_prev_i", aw, "descriptor: previous table (entry address)");
    m.input_c("job_prev_len_i", lw, "descriptor: its entries");
    m.input_c("job_list_i", aw, "descriptor: incoming list (entry address)");
    m.input_c("job_list_len_i", lw, "descriptor: its entries");
    m.input_c("job_next_i", aw, "descriptor: next table (entry address)");
    m.input_c("job_dps_passes_i", DPS_PASSES_BITS, "descriptor: DPS passes of a reuse tile (0: none)");
    m.input_c("job_dps_wide_i", 1, "descriptor: those passes in wide chunks (dps_wide x C)");
    m.input_c("job_odd_i", 1, "frame parity (FRAME[0]): DPS chunks shifted by C/2 on odd frame + pass");
    m.input_c("job_scratch_i", aw, "this core's first scratch region (entry address)");
    m.output_c("cmd_valid_o", 1, "to neo_sort_core: command");
    m.input_c("cmd_ready_i", 1, "");
    m.output_c("cmd_mode_o", SortMode::BITS, "");
    m.output_c("cmd_src_a_o", aw, "");
    m.output_c("cmd_len_a_o", lw, "");
    m.output_c("cmd_src_b_o", aw, "");
    m.output_c("cmd_len_b_o", lw, "");
    m.output_c("cmd_dst_o", aw, "");
    m.input_c("done_i", 1, "from neo_sort_core: a command finished");
    m.input_c("done_len_i", lw, "... entries it wrote");
    m.input_c("done_inv_i", lw, "... boundary inversions of A (merges)");
    m.input_c("idle_i", 1, "the core's memory bridge is idle (writes acknowledged)");
    m.output_c("cpl_valid_o", 1, "the tile is sorted");
    m.input_c("cpl_ready_i", 1, "");
    m.output_c("cpl_len_o", lw, "next_len");
    m.output_c(
        "cpl_inv_o",
        lw,
        "the MERGE_DELETE's boundary inversions of the reused table (0 from scratch)",
    );
}

/// The current command, computed from the plan state.
fn command(m: &mut Module, cfg: &EngineConfig, d: &Dims) {
    let (aw, lw) = (d.aw, d.lw);
    let c = cfg.chunk as u64;
    let min = |a: &str, b: &str| format!("(({a}) < ({b})) ? ({a}) : ({b})");
    m.blank();
    m.comment("The current command.");
    m.wire_assign("scr1", aw, format!("scr0_q + {}", lit(aw, cfg.table_capacity as u64)));
    m.wire_assign("is_dps", 1, "mode_q == M_DPS");
    m.wire_assign("is_merge", 1, "mode_q == M_MERGE");
    m.wire_assign("is_md", 1, "mode_q == M_MD");
    m.wire_assign("total", lw, "is_dps ? plen_q : n_q");
    m.wire_assign("rem", lw, "total - pos_q");
    m.comment("Longest A: a chunk; D/2 for the first DPS chunk of an odd frame + pass; a run for a pass");
    m.comment("(D: the DPS chunk, wide or not).");
    m.wire_assign("dps_odd", 1, "odd_q ^ pass_q[0]");
    let wc = cfg.sort_buffer() as u64;
    if cfg.dps_wide == 1 {
        m.comment("This engine has no wide chunk (dps_wide 1): D is C either way.");
    }
    m.wire_assign("dps_c", lw, format!("wide_q ? {} : {}", lit(lw, wc), lit(lw, c)));
    m.wire_assign("dps_h", lw, format!("wide_q ? {} : {}", lit(lw, wc / 2), lit(lw, c / 2)));
    m.wire_assign(
        "lim",
        lw,
        format!(
            "is_merge ? half_q : (is_dps ? ((dps_odd & (pos_q == {z})) ? dps_h : dps_c) : {c})",
            z = lit(lw, 0),
            c = lit(lw, c)
        ),
    );
    m.wire_assign("len_a", lw, format!("is_md ? plen_q : ({})", min("lim", "rem")));
    m.wire_assign("rem_b", lw, "rem - len_a");
    m.wire_assign(
        "len_b",
        lw,
        format!("is_md ? n_q : (is_merge ? ({}) : {})", min("half_q", "rem_b"), lit(lw, 0)),
    );
    m.wire_assign("last_cmd", 1, "is_md | ((len_a + len_b) == rem)");
    m.comment("The last SORT / MERGE stage: its output run covers the list.");
    m.wire_assign("fin", 1, format!("is_merge ? ((n_q - half_q) <= half_q) : (n_q <= {})", lit(lw, c)));
    m.wire_assign("scr_w", aw, "buf_q ? scr1 : scr0_q");
    m.wire_assign("scr_r", aw, "buf_q ? scr0_q : scr1");
    m.wire_assign("src_base", aw, "(mode_q == M_SORT) ? list_q : (is_merge ? scr_r : prev_q)");
    m.wire_assign("dst_base", aw, "(is_md | (fin & fs_q & ~is_dps)) ? next_q : (is_dps ? prev_q : scr_w)");
    let pos = resize("pos_q", lw, aw);
    m.wire_assign("src_a", aw, format!("src_base + {pos}"));
    let la = resize("len_a", lw, aw);
    m.wire_assign("src_b", aw, format!("is_md ? scr_w : (is_merge ? (src_a + {la}) : {})", lit(aw, 0)));
    m.assign("cmd_valid_o", "state_q == S_ISSUE");
    m.assign("cmd_mode_o", "mode_q");
    m.assign("cmd_src_a_o", "src_a");
    m.assign("cmd_len_a_o", "len_a");
    m.assign("cmd_src_b_o", "src_b");
    m.assign("cmd_len_b_o", "len_b");
    m.assign("cmd_dst_o", format!("dst_base + {pos}"));
    m.assign("job_ready_o", "state_q == S_IDLE");
    m.assign("cpl_valid_o", "state_q == S_CPL");
    m.assign("cpl_len_o", "cpl_len_q");
    m.assign("cpl_inv_o", "cpl_inv_q");
}

fn control(m: &mut Module, cfg: &EngineConfig, d: &Dims) {
    let (lw, ow) = (d.lw, d.ow);
    let c = cfg.chunk as u64;
    let z = lit(lw, 0);
    m.blank();
    m.comment("Commands in flight: +1 per command taken, -1 per done_i.");
    m.wire_assign("take", 1, "(state_q == S_ISSUE) & cmd_ready_i");
    m.wire_assign("barrier_ok", 1, format!("(out_q == {}) & idle_i", lit(ow, 0)));
    m.seq(
        vec![set("out_q", lit(ow, 0)), set("dlen_q", lit(lw, 0)), set("dinv_q", lit(lw, 0))],
        vec![
            if_else(
                "take & ~done_i",
                vec![set("out_q", format!("out_q + {}", lit(ow, 1)))],
                vec![if_("~take & done_i", vec![set("out_q", format!("out_q - {}", lit(ow, 1)))])],
            ),
            if_("done_i", vec![set("dlen_q", "done_len_i"), set("dinv_q", "done_inv_i")]),
        ],
    );
    m.blank();
    m.comment("Plan: IDLE -> (ISSUE -> WAIT)* per stage -> CPL -> IDLE.");
    let pz = lit(DPS_PASSES_BITS, 0);
    let issue = |mode: &str| vec![set("mode_q", mode), set("pos_q", z.clone()), set("state_q", "S_ISSUE")];
    // After the conventional sort of a reuse tile: DPS over prev when there is one and a pass is
    // asked for, else the merge.
    let reuse_next =
        || vec![if_else(format!("(plen_q != {z}) & (passes_q != {pz})"), issue("M_DPS"), issue("M_MD"))];
    m.wire_assign("pass_next", DPS_PASSES_BITS, format!("pass_q + {}", lit(DPS_PASSES_BITS, 1)));
    let complete =
        |len: &str, inv: &str| vec![set("cpl_len_q", len), set("cpl_inv_q", inv), set("state_q", "S_CPL")];
    let start = vec![
        set("fs_q", "job_from_scratch_i"),
        set("odd_q", "job_odd_i"),
        set("prev_q", "job_prev_i"),
        set("plen_q", "job_prev_len_i"),
        set("list_q", "job_list_i"),
        set("n_q", "job_list_len_i"),
        set("next_q", "job_next_i"),
        set("scr0_q", "job_scratch_i"),
        set("passes_q", "job_dps_passes_i"),
        set("wide_q", "job_dps_wide_i"),
        set("pass_q", pz.clone()),
        set("half_q", lit(lw, c)),
        set("buf_q", "1'b0"),
        if_else(
            format!("job_list_len_i != {z}"),
            issue("M_SORT"),
            vec![if_else(
                "job_from_scratch_i",
                complete(&z, &z),
                vec![if_else(
                    format!("(job_prev_len_i != {z}) & (job_dps_passes_i != {pz})"),
                    issue("M_DPS"),
                    issue("M_MD"),
                )],
            )],
        ),
    ];
    // After a DPS pass: the next pass (the other parity) or the merge.
    let after_dps = vec![if_else(
        "pass_next != passes_q",
        {
            let mut v = issue("M_DPS");
            v.push(set("pass_q", "pass_next"));
            v
        },
        issue("M_MD"),
    )];
    let after_stage = Stmt::Case(
        "mode_q".into(),
        vec![("M_DPS".into(), after_dps), ("M_MD".into(), complete("dlen_q", "dinv_q"))],
        // SORT or a MERGE pass.
        vec![if_else("fin", vec![if_else("fs_q", complete("n_q", &z), reuse_next())], {
            let mut v = issue("M_MERGE");
            v.push(set("buf_q", "~buf_q"));
            v.push(if_("is_merge", vec![set("half_q", format!("half_q << {}", lit(lw, 1)))]));
            v
        })],
    );
    let mut reset = m.q_resets(&[("state_q", "S_IDLE"), ("mode_q", "M_SORT"), ("half_q", &lit(lw, c))]);
    reset.retain(|s| !matches!(s, Stmt::Set(n, _) if ["out_q", "dlen_q", "dinv_q"].contains(&n.as_str())));
    m.seq(
        reset,
        vec![Stmt::Case(
            "state_q".into(),
            vec![
                ("S_IDLE".into(), vec![if_("job_valid_i", start)]),
                (
                    "S_ISSUE".into(),
                    vec![if_(
                        "cmd_ready_i",
                        vec![
                            set("pos_q", "pos_q + len_a + len_b"),
                            if_("last_cmd", vec![set("state_q", "S_WAIT")]),
                        ],
                    )],
                ),
                ("S_WAIT".into(), vec![if_("barrier_ok", vec![after_stage])]),
            ],
            // S_CPL
            vec![if_("cpl_ready_i", vec![set("state_q", "S_IDLE")])],
        )],
    );
}
