//! `neo_sort_core`: one Sorting Core (paper Section 5.3): BSU + MSU+ + double-buffered I/O
//! buffers, a command port and a memory-request port. The protocols are documented in
//! `docs/rtl.md`.
//!
//! # Commands (`cmd_mode_i`)
//! - `0` SORT: sort the chunk `src_a[0 .. min(len_a, B))` into `dst`, with `B` the buffer
//!   (`chunk * dps_wide`, the wide DPS chunk; the chunk without one) (conventional sort of one
//!   chunk: BSU vectors of `n` with padding, then MSU+ merge passes, no dropping; the sequencer
//!   gives a SORT at most a chunk, a DPS at most a chunk or, for a wide tile, the wide chunk);
//! - `1` DPS: the same datapath (a DPS pass is a chunk sort of the reused table);
//! - `2` MERGE_DELETE: merge the sorted streams `A = src_a[0..len_a)` and `B = src_b[0..len_b)`
//!   into `dst`, dropping entries whose valid bit is 0 (golden `merge2(a, b, true)`);
//! - `3` MERGE: the same without dropping (golden `merge2(a, b, false)`, the global passes).
//!
//! Commands complete in the order they were accepted; `done_o` pulses for one cycle per
//! command once its last write has been accepted by the memory, with `done_len_o` = the
//! entries it wrote and `done_inv_o` = the MSU+'s boundary inversions of stream A in a merge
//! command (0 for a chunk command), both held until the next `done_o`.
//!
//! # Buffers and overlap
//! Four chunk buffers: two input buffers `u_in0`, `u_in1` (ping-pong between consecutive chunk
//! commands) and two work buffers `u_work0`, `u_work1` (ping-pong between merge passes).
//! Two engines run concurrently:
//! - the LOAD engine (front end) takes a chunk command as soon as the next input buffer is free
//!   and no load is running: it reads the chunk in bursts into an `n`-lane deserializer (lanes
//!   start as golden padding), each full (or final partial) vector goes through the BSU, whose
//!   output lanes are written one per cycle into the input buffer (padding is not written);
//! - the PASS engine (back end) takes the loaded input buffers in order: runs of `n, 2n, ...`
//!   are merged pairwise by the MSU+ (a lone last run is merged with an empty stream, i.e.
//!   copied); the first pass reads the input buffer (which is then free for the load after the
//!   next one), the others ping-pong between the work buffers, and the final pass (the one that
//!   leaves a single run, also when the chunk is a single vector) streams to memory.
//!
//! So command `k + 1`'s load overlaps command `k`'s merge passes, and command `k`'s final pass
//! (the write-back) overlaps command `k + 1`'s (and `k + 2`'s) loads. The MSU+ is the
//! bottleneck: back to back, a chunk of `L` entries costs about `passes(L) * L` cycles. Reads
//! (a read-request port and a response port) and writes (a write port) are separate, so the
//! write-back of one command never holds up the reads of the next.
//!
//! MERGE modes serialise with everything else: such a command is taken only when the core is
//! idle, and no command is taken while it runs. Both streams are prefetched in bursts into the
//! two input buffers used as circular FIFOs (space reserved before a read is issued, so
//! responses are always accepted); the MSU+ output is written to memory.

use crate::emit::expr::{bits_for, hex, lane, lit, resize, slice};
use crate::emit::{conns, if_, if_else, set, Item, Module, Stmt};
use neo_golden::engine::EngineConfig;
use neo_golden::sort::SortMode;

/// Module name.
pub const NAME: &str = "neo_sort_core";

/// Back-end (PASS engine) states.
const S_IDLE: u64 = 0;
const S_PASS: u64 = 1;
const S_MERGE: u64 = 2;
const S_FINISH: u64 = 3;

/// Width of `mem_req_len_o` for `cfg` (holds `0..=burst`).
pub fn mem_len_bits(cfg: &EngineConfig) -> u32 {
    bits_for(cfg.burst as u64)
}

/// The chunk buffers: (instance suffix, write-enable expression, write address, write data).
fn buffers(da: u32, dc: u32) -> Vec<(&'static str, String, String, String)> {
    let ser_addr = resize("ser_cnt_q", dc, da);
    vec![
        (
            "in0",
            "(ser_fire & ~ld_sel_q) | beat_a".into(),
            format!("ld_act_q ? {ser_addr} : fa_wp_q"),
            "ld_act_q ? ser_entry : mem_rsp_data_i".into(),
        ),
        (
            "in1",
            "(ser_fire & ld_sel_q) | beat_b".into(),
            format!("ld_act_q ? {ser_addr} : fb_wp_q"),
            "ld_act_q ? ser_entry : mem_rsp_data_i".into(),
        ),
        ("work0", "o_buf & (first_q | wsrc_q)".into(), "ocnt_buf".into(), "o_data".into()),
        ("work1", "o_buf & ~first_q & ~wsrc_q".into(), "ocnt_buf".into(), "o_data".into()),
    ]
}

/// Counts and widths of the Sorting Core, from the configuration.
#[derive(Clone, Copy)]
struct Dims {
    /// BSU width (lanes).
    n: u32,
    /// Entry bits.
    w: u32,
    /// Buffer entries (the wide DPS chunk, or the chunk).
    d: u64,
    /// Buffer address bits.
    da: u32,
    /// Bits of 0..=chunk.
    dc: u32,
    /// Pass arithmetic bits (run, pair start: < 3 * chunk).
    pw: u32,
    /// Address bits.
    aw: u32,
    /// Length bits.
    lw: u32,
    /// Burst length bits.
    bl: u32,
    /// Burst entries.
    burst: u64,
    /// Outstanding read bursts.
    mo: u64,
    /// Tag pointer bits.
    tw: u32,
    /// Tag count bits.
    tc: u32,
    /// Lane index bits.
    nl: u32,
    /// The padding entry (packed).
    pad: u64,
    /// Vector bits (n entries).
    vw: u32,
}

impl Dims {
    fn new(cfg: &EngineConfig) -> Self {
        let n = cfg.bsu_width as u32;
        let w = cfg.entry_bits();
        let d = cfg.sort_buffer() as u64;
        let dc = bits_for(d);
        let mo = cfg.max_outstanding as u64;
        Dims {
            n,
            w,
            d,
            da: bits_for(d - 1),
            dc,
            pw: dc + 2,
            aw: cfg.addr_bits,
            lw: cfg.len_bits,
            bl: mem_len_bits(cfg),
            burst: cfg.burst as u64,
            mo,
            tw: bits_for(mo - 1),
            tc: bits_for(mo),
            nl: bits_for(n as u64 - 1),
            pad: cfg.format().pack(&cfg.format().padding()),
            vw: n * w,
        }
    }
}

/// `bits'd0`.
fn z(bits: u32) -> String {
    lit(bits, 0)
}

/// `bits'd1`.
fn one(bits: u32) -> String {
    lit(bits, 1)
}

/// The Sorting Core for `cfg`.
pub fn module(cfg: &EngineConfig) -> Module {
    let k = Dims::new(cfg);
    let mut m = Module::new(NAME);
    ports(&mut m, cfg, &k);
    registers(&mut m, &k);
    commands(&mut m, &k);
    instances(&mut m, &k);
    read_issuer(&mut m, &k);
    responses(&mut m, &k);
    deserializer(&mut m, &k);
    serializer(&mut m, &k);
    sources(&mut m, &k);
    output_side(&mut m, &k);
    pass_control(&mut m, &k);
    sequential(&mut m, &k);
    covers(&mut m, &k);
    m
}

/// Named cover points (Verilator coverage builds only): every command mode taken, an empty
/// chunk, a load overlapping merge passes, each merge FIFO full (and full while the other stream
/// drains), each merge stream starved while the other has an entry waiting, and the read issuer
/// at its outstanding-burst limit.
fn covers(m: &mut Module, k: &Dims) {
    let Dims { dc, d, .. } = *k;
    let mode = |mo: SortMode| format!("cmd_mode_i == {}", lit(SortMode::BITS, mo.code()));
    let full = |f: &str| format!("st_merge & ({f}_cnt_q == {})", lit(dc, d));
    let starved = |s: &str, o: &str| format!("st_merge & s{s}_act_q & ~{s}_valid & {o}_valid & ~s{o}_none");
    m.covers(&[
        ("cov_mode_sort", format!("take_chunk & ({})", mode(SortMode::Sort)), "a SORT command taken"),
        ("cov_mode_dps", format!("take_chunk & ({})", mode(SortMode::Dps)), "a DPS command taken"),
        (
            "cov_mode_merge_delete",
            format!("take_merge & ({})", mode(SortMode::MergeDelete)),
            "a MERGE_DELETE command taken",
        ),
        ("cov_mode_merge", format!("take_merge & ({})", mode(SortMode::Merge)), "a MERGE command taken"),
        ("cov_empty_chunk", "take_empty".into(), "a chunk command of no entries"),
        (
            "cov_load_during_passes",
            "ld_act_q & st_pass".into(),
            "a load overlaps the previous chunk's passes",
        ),
        (
            "cov_merge_drop",
            "st_merge & drop_q & a_pop_ent & ~a_live".into(),
            "MERGE_DELETE drops an entry of stream A (its valid field clear)",
        ),
        ("cov_fifo_a_full", full("fa"), "merge FIFO A holds a whole chunk buffer"),
        ("cov_fifo_b_full", full("fb"), "merge FIFO B holds a whole chunk buffer"),
        (
            "cov_fifo_a_full_b_drains",
            format!("{} & b_pop_ent", full("fa")),
            "FIFO A full and held back while stream B goes out",
        ),
        (
            "cov_fifo_b_full_a_drains",
            format!("{} & a_pop_ent", full("fb")),
            "FIFO B full and held back while stream A goes out",
        ),
        ("cov_starved_a", starved("a", "b"), "the merge waits for stream A while B has an entry"),
        ("cov_starved_b", starved("b", "a"), "the merge waits for stream B while A has an entry"),
        ("cov_tags_full", "(req_a_ok | req_b_ok) & ~tag_free".into(), "a read waits for a free burst tag"),
    ]);
}

/// Ports.
fn ports(m: &mut Module, cfg: &EngineConfig, k: &Dims) {
    let Dims { n, w, aw, lw, bl, d, pad, .. } = *k;
    m.doc(format!(
        "Sorting Core: {}-input {} BSU, MSU+, 2 input + 2 work {}-entry chunk buffers; entries of {w} bits.",
        n,
        cfg.topology.name(),
        d
    ));
    m.doc("Modes: 0 SORT chunk, 1 DPS chunk, 2 MERGE with delete, 3 MERGE keeping invalid. See docs/rtl.md.");
    m.doc("A chunk command's load overlaps the previous command's merge passes and write-back.");
    m.clock_reset();
    m.input_c("cmd_valid_i", 1, "a command is offered");
    m.output_c("cmd_ready_o", 1, "the core takes the offered command (depends on cmd_mode_i)");
    m.input_c("cmd_mode_i", SortMode::BITS, "0 sort, 1 dps, 2 merge-delete, 3 merge");
    m.input_c("cmd_src_a_i", aw, "entry address of the chunk / stream A");
    m.input_c("cmd_len_a_i", lw, "entries of the chunk (<= buffer size) / stream A");
    m.input_c("cmd_src_b_i", aw, "entry address of stream B (merge modes)");
    m.input_c("cmd_len_b_i", lw, "entries of stream B (merge modes)");
    m.input_c("cmd_dst_i", aw, "entry address of the output");
    m.output_c("done_o", 1, "one-cycle pulse: the oldest command finished");
    m.output_c("done_len_o", lw, "entries written by the last finished command");
    m.output_c("done_inv_o", lw, "boundary inversions of A in the last finished command (merges; else 0)");
    m.output_c("mem_req_valid_o", 1, "a read request (burst) is offered");
    m.input_c("mem_req_ready_i", 1, "the memory takes the read request");
    m.output_c("mem_req_addr_o", aw, "entry address of the burst");
    m.output_c("mem_req_len_o", bl, "entries of the burst (1..burst)");
    m.input_c("mem_rsp_valid_i", 1, "a read response beat (one entry), in request order");
    m.output_c("mem_rsp_ready_o", 1, "the core takes the response beat");
    m.input_c("mem_rsp_data_i", w, "the entry read");
    m.output_c("mem_wr_valid_o", 1, "a write of one entry is offered");
    m.input_c("mem_wr_ready_i", 1, "the memory takes the write");
    m.output_c("mem_wr_addr_o", aw, "entry address of the write");
    m.output_c("mem_wr_data_o", w, "the entry to write");

    m.localparam("S_IDLE", 2, lit(2, S_IDLE));
    m.localparam("S_PASS", 2, lit(2, S_PASS));
    m.localparam("S_MERGE", 2, lit(2, S_MERGE));
    m.localparam("S_FINISH", 2, lit(2, S_FINISH));
    m.localparam("PAD", w, hex(w, pad));
}

/// Registers.
fn registers(m: &mut Module, k: &Dims) {
    let Dims { da, dc, pw, aw, lw, bl, tw, tc, nl, mo, .. } = *k;
    m.blank();
    m.comment("LOAD engine: active, input buffer being loaded next, entries of the load.");
    m.reg("ld_act_q", 1).reg("ld_sel_q", 1).reg("ld_len_q", dc);
    m.comment("Input buffers: loaded (waiting for or in their first pass), and each one's command.");
    m.reg("ib_full_q", 2).reg("ib0_len_q", dc).reg("ib0_dst_q", aw).reg("ib1_len_q", dc).reg("ib1_dst_q", aw);
    m.comment("PASS engine: state, input buffer of the next command, command, outputs, last done length.");
    m.reg("state_q", 2).reg("bk_sel_q", 1).reg("drop_q", 1).reg("bk_dst_q", aw).reg("bk_len_q", dc);
    m.reg("ocnt_q", lw).reg("done_len_q", lw).reg("mrg_q", 1).reg("done_inv_q", lw);
    m.comment("Read issuer: next address and entries left to request per stream, reservations.");
    m.reg("rd_a_addr_q", aw).reg("rd_a_left_q", lw).reg("rd_b_addr_q", aw).reg("rd_b_left_q", lw);
    m.reg("a_resv_q", dc + 1).reg("b_resv_q", dc + 1).reg("rr_q", 1);
    m.comment("Outstanding read bursts {stream, len}, in request order.");
    m.mem("tag_mem", bl + 1, mo as u32);
    m.reg("tag_wp_q", tw).reg("tag_rp_q", tw).reg("tag_cnt_q", tc).reg("rsp_cnt_q", bl);
    m.comment("Stream sources feeding the MSU+ (read pointer, entries left, active).");
    m.reg("sa_act_q", 1).reg("sa_rem_q", lw).reg("sa_ptr_q", da);
    m.reg("sb_act_q", 1).reg("sb_rem_q", lw).reg("sb_ptr_q", da);
    m.comment("Merge-mode FIFOs in the input buffers (write pointer, entries present).");
    m.reg("fa_wp_q", da).reg("fa_cnt_q", dc).reg("fb_wp_q", da).reg("fb_cnt_q", dc);
    m.comment(
        "Merge passes: run length, first pass (reads the input buffer), source work buffer, next pair.",
    );
    m.reg("run_q", pw).reg("first_q", 1).reg("wsrc_q", 1).reg("pair_q", pw);
    m.comment("LOAD: deserializer (lanes, fill index, full), entries received, BSU output serializer.");
    m.reg("des_lane_q", nl).reg("des_full_q", 1).reg("rcv_q", dc).reg("ser_lane_q", nl).reg("ser_cnt_q", dc);
}

/// Commands.
fn commands(m: &mut Module, k: &Dims) {
    let Dims { dc, pw, lw, d, .. } = *k;
    m.blank();
    m.wire_assign("st_idle", 1, "state_q == S_IDLE");
    m.wire_assign("st_pass", 1, "state_q == S_PASS");
    m.wire_assign("st_merge", 1, "state_q == S_MERGE");
    m.wire_assign("st_finish", 1, "state_q == S_FINISH");
    m.wire_assign("cmd_chunk", 1, "~cmd_mode_i[1]");
    let dlit = lit(lw, d);
    m.wire_assign(
        "cmd_len_clamped",
        dc,
        format!("(cmd_len_a_i > {dlit}) ? {} : {}", lit(dc, d), resize("cmd_len_a_i", lw, dc)),
    );
    m.comment("A chunk command needs the next input buffer free and no load or merge running;");
    m.comment("a merge command needs the whole core idle.");
    m.wire_assign("ld_buf_full", 1, "ld_sel_q ? ib_full_q[1] : ib_full_q[0]");
    m.wire_assign("chunk_ok", 1, "~ld_act_q & ~ld_buf_full & ~st_merge");
    m.wire_assign("merge_ok", 1, format!("st_idle & ~ld_act_q & (ib_full_q == {})", z(2)));
    m.assign("cmd_ready_o", "cmd_chunk ? chunk_ok : merge_ok");
    m.wire_assign("take_chunk", 1, "cmd_valid_i & cmd_chunk & chunk_ok");
    m.wire_assign("take_merge", 1, "cmd_valid_i & ~cmd_chunk & merge_ok");
    m.wire_assign("take_empty", 1, format!("take_chunk & (cmd_len_clamped == {})", z(dc)));
    m.comment("PASS engine: the next command's input buffer, and the start of its passes.");
    m.wire_assign("bk_buf_full", 1, "bk_sel_q ? ib_full_q[1] : ib_full_q[0]");
    m.wire_assign("bk_len_in", dc, "bk_sel_q ? ib1_len_q : ib0_len_q");
    m.wire_assign("bk_start", 1, "st_idle & bk_buf_full");
    m.wire_assign("bk_start_empty", 1, format!("bk_start & (bk_len_in == {})", z(dc)));
    m.wire_assign(
        "final_pass",
        1,
        format!("{{run_q[{}:0], 1'b0}} >= {}", pw - 2, resize("bk_len_q", dc, pw)),
    );
}

/// Instances.
fn instances(m: &mut Module, k: &Dims) {
    let Dims { w, da, dc, vw, .. } = *k;
    m.blank();
    m.comment("BSU: fed by the deserializer during a load, drained lane by lane into the input buffer.");
    m.wire("bsu_in_ready", 1).wire("bsu_out_valid", 1).wire("bsu_out_ready", 1).wire("bsu_out_data", vw);
    m.wire("des_data", vw);
    m.instance(
        "neo_bsu",
        "u_bsu",
        conns(&[
            ("clk_i", "clk_i".into()),
            ("rst_ni", "rst_ni".into()),
            ("in_valid_i", "des_full_q".into()),
            ("in_ready_o", "bsu_in_ready".into()),
            ("in_data_i", "des_data".into()),
            ("out_valid_o", "bsu_out_valid".into()),
            ("out_ready_i", "bsu_out_ready".into()),
            ("out_data_o", "bsu_out_data".into()),
        ]),
    );
    m.blank();
    m.comment("MSU+: A and B from the buffers (pass runs or merge FIFOs).");
    for s in ["a", "b"] {
        m.wire(format!("{s}_valid"), 1).wire(format!("{s}_ready"), 1).wire(format!("{s}_data"), w);
        m.wire(format!("{s}_last"), 1).wire(format!("{s}_empty"), 1);
    }
    m.wire("o_valid", 1).wire("o_ready", 1).wire("o_data", w).wire("o_last", 1).wire("o_empty", 1);
    m.wire("o_a_inv", k.lw);
    m.instance(
        "neo_msu",
        "u_msu",
        conns(&[
            ("clk_i", "clk_i".into()),
            ("rst_ni", "rst_ni".into()),
            ("drop_invalid_i", "drop_q".into()),
            ("a_valid_i", "a_valid".into()),
            ("a_ready_o", "a_ready".into()),
            ("a_data_i", "a_data".into()),
            ("a_last_i", "a_last".into()),
            ("a_empty_i", "a_empty".into()),
            ("b_valid_i", "b_valid".into()),
            ("b_ready_o", "b_ready".into()),
            ("b_data_i", "b_data".into()),
            ("b_last_i", "b_last".into()),
            ("b_empty_i", "b_empty".into()),
            ("out_valid_o", "o_valid".into()),
            ("out_ready_i", "o_ready".into()),
            ("out_data_o", "o_data".into()),
            ("out_last_o", "o_last".into()),
            ("out_empty_o", "o_empty".into()),
            ("a_inv_o", "o_a_inv".into()),
        ]),
    );
    m.blank();
    m.comment("Chunk buffers: input buffers (loads, merge FIFOs A and B), work buffers (passes).");
    m.comment("Read port 0 reads source A, port 1 source B.");
    for (b, ..) in buffers(da, dc) {
        m.wire(format!("{b}_we"), 1).wire(format!("{b}_waddr"), da).wire(format!("{b}_wdata"), w);
        m.wire(format!("{b}_rdata0"), w).wire(format!("{b}_rdata1"), w);
        m.instance(
            "neo_chunk_ram",
            format!("u_{b}"),
            conns(&[
                ("clk_i", "clk_i".into()),
                ("we_i", format!("{b}_we")),
                ("waddr_i", format!("{b}_waddr")),
                ("wdata_i", format!("{b}_wdata")),
                ("raddr0_i", "sa_ptr_q".into()),
                ("rdata0_o", format!("{b}_rdata0")),
                ("raddr1_i", "sb_ptr_q".into()),
                ("rdata1_o", format!("{b}_rdata1")),
            ]),
        );
    }
}

/// Read issuer.
fn read_issuer(m: &mut Module, k: &Dims) {
    let Dims { dc, aw, lw, bl, tc, d, burst, mo, .. } = *k;
    m.blank();
    m.comment(
        "Read issuer (read port): bursts of up to the burst size; merge modes reserve FIFO space first.",
    );
    let blit = lit(lw, burst);
    m.wire_assign(
        "len_a_next",
        bl,
        format!("(rd_a_left_q < {blit}) ? {} : {}", resize("rd_a_left_q", lw, bl), lit(bl, burst)),
    );
    m.wire_assign(
        "len_b_next",
        bl,
        format!("(rd_b_left_q < {blit}) ? {} : {}", resize("rd_b_left_q", lw, bl), lit(bl, burst)),
    );
    let fits = |s: &str| {
        format!("({s}_resv_q + {}) <= {}", resize(&format!("len_{s}_next"), bl, dc + 1), lit(dc + 1, d))
    };
    m.wire_assign(
        "req_a_ok",
        1,
        format!("(rd_a_left_q != {}) & (ld_act_q | (st_merge & ({})))", z(lw), fits("a")),
    );
    m.wire_assign("req_b_ok", 1, format!("(rd_b_left_q != {}) & st_merge & ({})", z(lw), fits("b")));
    m.wire_assign("tag_free", 1, format!("tag_cnt_q != {}", lit(tc, mo)));
    m.comment(
        "Both streams ready: the one with fewer entries reserved (the one the merge drains), ties alternate.",
    );
    m.wire_assign("b_drained", 1, "(b_resv_q < a_resv_q) | ((b_resv_q == a_resv_q) & rr_q)");
    m.wire_assign("rd_pick_b", 1, "req_b_ok & (~req_a_ok | b_drained)");
    m.wire_assign("rd_want", 1, "(req_a_ok | req_b_ok) & tag_free");
    m.wire_assign("to_mem", 1, "st_merge | (st_pass & final_pass)");
    m.wire_assign("wr_want", 1, "to_mem & o_valid & ~o_empty");
    m.wire_assign("rd_fire", 1, "rd_want & mem_req_ready_i");
    m.wire_assign("wr_fire", 1, "wr_want & mem_wr_ready_i");
    m.assign("mem_req_valid_o", "rd_want");
    m.assign("mem_req_addr_o", "rd_pick_b ? rd_b_addr_q : rd_a_addr_q");
    m.assign("mem_req_len_o", "rd_pick_b ? len_b_next : len_a_next");
    m.comment("Write port: the MSU+ output of the final pass / a merge, one entry per write.");
    m.assign("mem_wr_valid_o", "wr_want");
    m.assign("mem_wr_addr_o", format!("bk_dst_q + {}", resize("ocnt_q", lw, aw)));
    m.assign("mem_wr_data_o", "o_data");
}

/// Responses.
fn responses(m: &mut Module, k: &Dims) {
    let Dims { bl, tc, .. } = *k;
    m.blank();
    m.comment("Responses: routed by the oldest outstanding burst's tag.");
    m.wire_assign("tag_head", bl + 1, "tag_mem[tag_rp_q]");
    m.wire_assign("tag_head_b", 1, format!("tag_head[{bl}]"));
    m.wire_assign("tag_head_len", bl, format!("tag_head[{}:0]", bl - 1));
    m.wire_assign("des_accept", 1, "~des_full_q | bsu_in_ready");
    m.assign(
        "mem_rsp_ready_o",
        format!("(tag_cnt_q != {}) & (st_merge | (ld_act_q & des_accept))", lit(tc, 0)),
    );
    m.wire_assign("rsp_fire", 1, "mem_rsp_valid_i & mem_rsp_ready_o");
    m.wire_assign("rsp_burst_end", 1, format!("rsp_fire & (rsp_cnt_q + {} == tag_head_len)", lit(bl, 1)));
    m.wire_assign("beat_load", 1, "rsp_fire & ld_act_q");
    m.wire_assign("beat_a", 1, "rsp_fire & st_merge & ~tag_head_b");
    m.wire_assign("beat_b", 1, "rsp_fire & st_merge & tag_head_b");
}

/// Deserializer.
fn deserializer(m: &mut Module, k: &Dims) {
    let Dims { n, w, dc, nl, .. } = *k;
    m.blank();
    m.comment(
        "Deserializer: lanes start as padding; a vector is complete at lane n-1 or the chunk's last entry.",
    );
    m.wire_assign("des_push", 1, "des_full_q & bsu_in_ready");
    m.wire_assign(
        "des_vec_end",
        1,
        format!("(des_lane_q == {}) | (rcv_q + {} == ld_len_q)", lit(nl, n as u64 - 1), lit(dc, 1)),
    );
    let lane_items = vec![
        Item::LocalParam { name: "LANE".into(), width: nl, value: "g".into() },
        Item::Reg { name: "lane_q".into(), width: w },
        Item::Seq {
            reset: Some(vec![set("lane_q", "PAD")]),
            body: vec![if_else(
                "des_push",
                vec![set("lane_q", format!("(beat_load & (LANE == {})) ? mem_rsp_data_i : PAD", lit(nl, 0)))],
                vec![if_("beat_load & (des_lane_q == LANE)", vec![set("lane_q", "mem_rsp_data_i")])],
            )],
        },
        Item::Assign { lhs: format!("des_data[g*{w} +: {w}]"), rhs: "lane_q".into() },
    ];
    m.gen_for("g", n, "g_des_lane", lane_items);
}

/// Serializer.
fn serializer(m: &mut Module, k: &Dims) {
    let Dims { n, w, dc, nl, .. } = *k;
    m.blank();
    m.comment(
        "Serializer: BSU output lanes to the input buffer, one per cycle; padding lanes are not written.",
    );
    m.reg("ser_entry", w);
    let arms =
        (0..n).map(|i| (lit(nl, i as u64), vec![set("ser_entry", lane("bsu_out_data", i, w))])).collect();
    m.comb(vec![set("ser_entry", lit(w, 0)), Stmt::Case("ser_lane_q".into(), arms, vec![])]);
    m.wire_assign("ser_fire", 1, "ld_act_q & bsu_out_valid");
    m.wire_assign(
        "ser_vec_end",
        1,
        format!("(ser_lane_q == {}) | (ser_cnt_q + {} == ld_len_q)", lit(nl, n as u64 - 1), lit(dc, 1)),
    );
    m.assign("bsu_out_ready", "ser_fire & ser_vec_end");
    m.wire_assign("ld_done", 1, format!("ser_fire & ser_vec_end & (ser_cnt_q + {} == ld_len_q)", one(dc)));
}

/// Sources.
fn sources(m: &mut Module, k: &Dims) {
    let Dims { dc, lw, .. } = *k;
    m.blank();
    m.comment("Stream sources: an empty stream is one beat with empty = last = 1. The first pass reads");
    m.comment("the command's input buffer, later passes the source work buffer, merges the input FIFOs.");
    for (s, f, port) in [("a", "fa", "0"), ("b", "fb", "1")] {
        let zero = z(lw);
        m.wire_assign(format!("s{s}_none"), 1, format!("s{s}_rem_q == {zero}"));
        m.assign(
            format!("{s}_valid"),
            format!("s{s}_act_q & (s{s}_none | ~st_merge | ({f}_cnt_q != {}))", z(dc)),
        );
        let fifo = if s == "a" { "in0" } else { "in1" };
        m.assign(
            format!("{s}_data"),
            format!(
                "st_merge ? {fifo}_rdata{port} : (first_q ? (bk_sel_q ? in1_rdata{port} : in0_rdata{port}) \
                 : (wsrc_q ? work1_rdata{port} : work0_rdata{port}))"
            ),
        );
        m.assign(format!("{s}_empty"), format!("s{s}_none"));
        m.assign(format!("{s}_last"), format!("s{s}_rem_q <= {}", one(lw)));
        m.wire_assign(format!("{s}_pop"), 1, format!("{s}_valid & {s}_ready"));
        m.wire_assign(format!("{s}_pop_ent"), 1, format!("{s}_pop & ~s{s}_none"));
    }
    m.comment(
        "Stream A's head entry field live: its valid bit (0: deleted), for the merge-drop cover point.",
    );
    m.wire_assign("a_live", 1, slice("a_data", k.w - 1, k.w - 1));
}

/// Output side.
fn output_side(m: &mut Module, k: &Dims) {
    let Dims { da, dc, lw, .. } = *k;
    m.blank();
    m.comment("MSU+ output: to the other work buffer during non-final passes, else memory writes.");
    m.assign("o_ready", "~to_mem | o_empty | mem_wr_ready_i");
    m.wire_assign("o_ent", 1, "o_valid & o_ready & ~o_empty");
    m.wire_assign("o_buf", 1, "o_ent & st_pass & ~final_pass");
    m.wire_assign("o_count", 1, "o_buf | wr_fire");
    m.wire_assign("merge_end", 1, "st_merge & o_valid & o_ready & o_last");
    m.wire_assign("ocnt_buf", da, resize("ocnt_q", lw, da));
    for (b, we, waddr, wdata) in buffers(da, dc) {
        m.assign(format!("{b}_we"), we);
        m.assign(format!("{b}_waddr"), waddr);
        m.assign(format!("{b}_wdata"), wdata);
    }
}

/// Pass control.
fn pass_control(m: &mut Module, k: &Dims) {
    let Dims { da, dc, pw, lw, .. } = *k;
    m.blank();
    m.comment("Pass control: next pair A = [pair, pair + alen), B = [pair + alen, pair + alen + blen).");
    let len_pw = resize("bk_len_q", dc, pw);
    m.wire_assign("pair_left", pw, format!("{len_pw} - pair_q"));
    m.wire_assign("pair_alen", pw, "(pair_left < run_q) ? pair_left : run_q");
    m.wire_assign("pair_rest", pw, "pair_left - pair_alen");
    m.wire_assign("pair_blen", pw, "(pair_rest < run_q) ? pair_rest : run_q");
    m.wire_assign(
        "pair_bstart",
        da,
        format!("{} + {}", resize("pair_q", pw, da), resize("pair_alen", pw, da)),
    );
    m.wire_assign("pair_start", 1, format!("st_pass & ~sa_act_q & ~sb_act_q & (pair_q < {len_pw})"));
    m.wire_assign("pass_end", 1, format!("st_pass & (ocnt_q == {})", resize("bk_len_q", dc, lw)));
    m.comment("Input buffers: loaded at the end of a load (or at once for an empty chunk), free after");
    m.comment("their command's first pass (or its start when empty).");
    m.wire_assign("ib_set", 1, "ld_done | take_empty");
    m.wire_assign("ib_clr", 1, "(pass_end & first_q) | bk_start_empty");
    m.assign("done_o", "st_finish");
    m.assign("done_len_o", "st_finish ? ocnt_q : done_len_q");
    m.comment("A merge command's inversions: the MSU+ holds its last merge's count from that merge's end.");
    m.wire_assign("fin_inv", lw, format!("mrg_q ? o_a_inv : {}", z(lw)));
    m.assign("done_inv_o", "st_finish ? fin_inv : done_inv_q");
}

/// The control registers: one clocked block (every `_q` register resets to zero, the state
/// machine to S_IDLE).
fn sequential(m: &mut Module, k: &Dims) {
    m.blank();
    m.seq_noreset(vec![if_("rd_fire", vec![set("tag_mem[tag_wp_q]", "{rd_pick_b, mem_req_len_o}")])]);
    // Every control register resets to zero (the state machine to S_IDLE, which is 0).
    let resets = m.q_resets(&[("state_q", "S_IDLE")]);
    let mut body = Vec::new();
    seq_load(&mut body, k);
    seq_pass(&mut body, k);
    seq_reads(&mut body, k);
    seq_streams(&mut body, k);
    m.seq(resets, body);
}

/// LOAD engine: command capture and completion, input-buffer flags.
fn seq_load(body: &mut Vec<Stmt>, k: &Dims) {
    let Dims { dc, lw, nl, .. } = *k;
    // LOAD engine: command capture and completion.
    body.push(Stmt::Comment("LOAD engine: takes chunk commands".into()));
    let ib_capture = |b: u32| {
        vec![set(format!("ib{b}_len_q"), "cmd_len_clamped"), set(format!("ib{b}_dst_q"), "cmd_dst_i")]
    };
    body.push(if_(
        "take_chunk",
        vec![
            if_else("ld_sel_q", ib_capture(1), ib_capture(0)),
            set("ld_len_q", "cmd_len_clamped"),
            set("ld_act_q", "~take_empty"),
            set("rd_a_addr_q", "cmd_src_a_i"),
            set("rd_a_left_q", resize("cmd_len_clamped", dc, lw)),
            set("rd_b_left_q", z(lw)),
            set("des_lane_q", z(nl)),
            set("rcv_q", z(dc)),
            set("ser_lane_q", z(nl)),
            set("ser_cnt_q", z(dc)),
        ],
    ));
    body.push(if_("ld_done", vec![set("ld_act_q", z(1))]));
    body.push(if_("ib_set", vec![set("ld_sel_q", "~ld_sel_q")]));
    body.push(set(
        "ib_full_q",
        "(ib_full_q | {ib_set & ld_sel_q, ib_set & ~ld_sel_q}) & ~{ib_clr & bk_sel_q, ib_clr & ~bk_sel_q}",
    ));
}

/// PASS engine: the state machine and the output counter.
fn seq_pass(body: &mut Vec<Stmt>, k: &Dims) {
    let Dims { n, da, dc, pw, lw, .. } = *k;
    // PASS engine.
    body.push(Stmt::Comment("PASS engine".into()));
    body.push(Stmt::Case(
        "state_q".into(),
        vec![
            (
                "S_IDLE".into(),
                vec![if_else(
                    "take_merge",
                    vec![
                        set(
                            "drop_q",
                            format!("cmd_mode_i == {}", lit(SortMode::BITS, SortMode::MergeDelete.code())),
                        ),
                        set("bk_dst_q", "cmd_dst_i"),
                        set("mrg_q", one(1)),
                        set("ocnt_q", z(lw)),
                        set("rd_a_addr_q", "cmd_src_a_i"),
                        set("rd_b_addr_q", "cmd_src_b_i"),
                        set("rd_a_left_q", "cmd_len_a_i"),
                        set("rd_b_left_q", "cmd_len_b_i"),
                        set("a_resv_q", z(dc + 1)),
                        set("b_resv_q", z(dc + 1)),
                        set("rr_q", z(1)),
                        set("sa_act_q", one(1)),
                        set("sa_rem_q", "cmd_len_a_i"),
                        set("sa_ptr_q", z(da)),
                        set("sb_act_q", one(1)),
                        set("sb_rem_q", "cmd_len_b_i"),
                        set("sb_ptr_q", z(da)),
                        set("fa_wp_q", z(da)),
                        set("fb_wp_q", z(da)),
                        set("state_q", "S_MERGE"),
                    ],
                    vec![if_(
                        "bk_start",
                        vec![
                            set("drop_q", z(1)),
                            set("mrg_q", z(1)),
                            set("bk_len_q", "bk_len_in"),
                            set("bk_dst_q", "bk_sel_q ? ib1_dst_q : ib0_dst_q"),
                            set("ocnt_q", z(lw)),
                            set("run_q", lit(pw, n as u64)),
                            set("first_q", one(1)),
                            set("wsrc_q", z(1)),
                            set("pair_q", z(pw)),
                            if_else(
                                "bk_start_empty",
                                vec![set("bk_sel_q", "~bk_sel_q"), set("state_q", "S_FINISH")],
                                vec![set("state_q", "S_PASS")],
                            ),
                        ],
                    )],
                )],
            ),
            (
                "S_PASS".into(),
                vec![if_(
                    "pass_end",
                    vec![if_else(
                        "final_pass",
                        vec![set("bk_sel_q", "~bk_sel_q"), set("state_q", "S_FINISH")],
                        vec![
                            set("run_q", format!("{{run_q[{}:0], 1'b0}}", pw - 2)),
                            set("first_q", z(1)),
                            set("wsrc_q", "~first_q & ~wsrc_q"),
                            set("pair_q", z(pw)),
                            set("ocnt_q", z(lw)),
                        ],
                    )],
                )],
            ),
            ("S_MERGE".into(), vec![if_("merge_end", vec![set("state_q", "S_FINISH")])]),
            (
                "S_FINISH".into(),
                vec![set("done_len_q", "ocnt_q"), set("done_inv_q", "fin_inv"), set("state_q", "S_IDLE")],
            ),
        ],
        vec![set("state_q", "S_IDLE")],
    ));
    // Output counter (pass_end resets it in the case above; counting never coincides with it:
    // at pass_end every entry of the pass has been counted).
    body.push(if_("o_count", vec![set("ocnt_q", format!("ocnt_q + {}", one(lw)))]));
}

/// Read issuer, outstanding tags, responses and the merge FIFOs.
fn seq_reads(body: &mut Vec<Stmt>, k: &Dims) {
    let Dims { da, dc, aw, lw, bl, tw, tc, .. } = *k;
    // Read issuer.
    body.push(Stmt::Comment("read issuer".into()));
    body.push(if_(
        "rd_fire",
        vec![
            set("rr_q", "~rd_pick_b"),
            set("tag_wp_q", format!("tag_wp_q + {}", one(tw))),
            if_else(
                "rd_pick_b",
                vec![
                    set("rd_b_addr_q", format!("rd_b_addr_q + {}", resize("len_b_next", bl, aw))),
                    set("rd_b_left_q", format!("rd_b_left_q - {}", resize("len_b_next", bl, lw))),
                ],
                vec![
                    set("rd_a_addr_q", format!("rd_a_addr_q + {}", resize("len_a_next", bl, aw))),
                    set("rd_a_left_q", format!("rd_a_left_q - {}", resize("len_a_next", bl, lw))),
                ],
            ),
        ],
    ));
    let resv = |s: &str| {
        let add = format!(
            "((rd_fire & {}rd_pick_b) ? {} : {})",
            if s == "a" { "~" } else { "" },
            resize(&format!("len_{s}_next"), bl, dc + 1),
            z(dc + 1)
        );
        let sub = format!("({s}_pop_ent ? {} : {})", one(dc + 1), z(dc + 1));
        set(format!("{s}_resv_q"), format!("{s}_resv_q + {add} - {sub}"))
    };
    body.push(if_("st_merge", vec![resv("a"), resv("b")]));
    body.push(Stmt::Case(
        "{rd_fire, rsp_burst_end}".into(),
        vec![
            ("2'b10".into(), vec![set("tag_cnt_q", format!("tag_cnt_q + {}", one(tc)))]),
            ("2'b01".into(), vec![set("tag_cnt_q", format!("tag_cnt_q - {}", one(tc)))]),
        ],
        vec![],
    ));
    body.push(Stmt::Comment("responses".into()));
    body.push(if_(
        "rsp_fire",
        vec![if_else(
            "rsp_burst_end",
            vec![set("rsp_cnt_q", z(bl)), set("tag_rp_q", format!("tag_rp_q + {}", one(tw)))],
            vec![set("rsp_cnt_q", format!("rsp_cnt_q + {}", one(bl)))],
        )],
    ));
    body.push(if_("beat_a", vec![set("fa_wp_q", format!("fa_wp_q + {}", one(da)))]));
    body.push(if_("beat_b", vec![set("fb_wp_q", format!("fb_wp_q + {}", one(da)))]));
    for s in ["a", "b"] {
        let f = if s == "a" { "fa" } else { "fb" };
        let beat = format!("beat_{s}");
        let pop = format!("{s}_pop_ent & st_merge");
        body.push(set(
            format!("{f}_cnt_q"),
            format!("{f}_cnt_q + ({beat} ? {} : {}) - ({pop} ? {} : {})", one(dc), z(dc), one(dc), z(dc)),
        ));
    }
}

/// LOAD deserializer and serializer, and the stream sources.
fn seq_streams(body: &mut Vec<Stmt>, k: &Dims) {
    let Dims { da, dc, pw, lw, nl, .. } = *k;
    body.push(Stmt::Comment("LOAD: deserializer and serializer".into()));
    body.push(if_(
        "beat_load",
        vec![
            set("rcv_q", format!("rcv_q + {}", one(dc))),
            set("des_lane_q", format!("des_vec_end ? {} : des_lane_q + {}", z(nl), one(nl))),
        ],
    ));
    body.push(if_else(
        "beat_load & des_vec_end",
        vec![set("des_full_q", one(1))],
        vec![if_("des_push", vec![set("des_full_q", z(1))])],
    ));
    body.push(if_(
        "ser_fire",
        vec![
            set("ser_cnt_q", format!("ser_cnt_q + {}", one(dc))),
            set("ser_lane_q", format!("ser_vec_end ? {} : ser_lane_q + {}", z(nl), one(nl))),
        ],
    ));
    body.push(Stmt::Comment("sources: a pass sets up the next pair when both are idle".into()));
    body.push(if_else(
        "pair_start",
        vec![
            set("sa_act_q", one(1)),
            set("sa_ptr_q", resize("pair_q", pw, da)),
            set("sa_rem_q", resize("pair_alen", pw, lw)),
            set("sb_act_q", one(1)),
            set("sb_ptr_q", "pair_bstart"),
            set("sb_rem_q", resize("pair_blen", pw, lw)),
            set("pair_q", format!("pair_q + {{run_q[{}:0], 1'b0}}", pw - 2)),
        ],
        vec![
            if_(
                "a_pop",
                vec![
                    set("sa_ptr_q", format!("sa_ptr_q + {}", one(da))),
                    if_else(
                        "a_last",
                        vec![set("sa_act_q", z(1)), set("sa_rem_q", z(lw))],
                        vec![set("sa_rem_q", format!("sa_rem_q - {}", one(lw)))],
                    ),
                ],
            ),
            if_(
                "b_pop",
                vec![
                    set("sb_ptr_q", format!("sb_ptr_q + {}", one(da))),
                    if_else(
                        "b_last",
                        vec![set("sb_act_q", z(1)), set("sb_rem_q", z(lw))],
                        vec![set("sb_rem_q", format!("sb_rem_q - {}", one(lw)))],
                    ),
                ],
            ),
        ],
    ));
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::interface::Dir;

    /// Every command mode has its cover point, and so do both merge FIFOs and both streams.
    #[test]
    fn cover_points_name_every_mode_and_both_streams() {
        let labels = module(&EngineConfig::default()).cover_labels();
        let has = |l: &str| labels.iter().any(|x| x == l);
        for mode in SortMode::ALL {
            let name = match mode {
                SortMode::Sort => "cov_mode_sort",
                SortMode::Dps => "cov_mode_dps",
                SortMode::MergeDelete => "cov_mode_merge_delete",
                SortMode::Merge => "cov_mode_merge",
            };
            assert!(has(name), "{mode:?}: {labels:?}");
        }
        for l in ["cov_fifo_a_full", "cov_fifo_b_full", "cov_starved_a", "cov_starved_b"] {
            assert!(has(l), "{l}: {labels:?}");
        }
    }

    #[test]
    fn interface_has_the_documented_ports_and_widths() {
        let cfg = EngineConfig::default();
        let i = module(&cfg).interface();
        let expect: &[(&str, Dir, u32)] = &[
            ("clk_i", Dir::In, 1),
            ("rst_ni", Dir::In, 1),
            ("cmd_valid_i", Dir::In, 1),
            ("cmd_ready_o", Dir::Out, 1),
            ("cmd_mode_i", Dir::In, 2),
            ("cmd_src_a_i", Dir::In, 32),
            ("cmd_len_a_i", Dir::In, 32),
            ("cmd_src_b_i", Dir::In, 32),
            ("cmd_len_b_i", Dir::In, 32),
            ("cmd_dst_i", Dir::In, 32),
            ("done_o", Dir::Out, 1),
            ("done_len_o", Dir::Out, 32),
            ("done_inv_o", Dir::Out, 32),
            ("mem_req_valid_o", Dir::Out, 1),
            ("mem_req_ready_i", Dir::In, 1),
            ("mem_req_addr_o", Dir::Out, 32),
            ("mem_req_len_o", Dir::Out, 5),
            ("mem_rsp_valid_i", Dir::In, 1),
            ("mem_rsp_ready_o", Dir::Out, 1),
            ("mem_rsp_data_i", Dir::In, 48),
            ("mem_wr_valid_o", Dir::Out, 1),
            ("mem_wr_ready_i", Dir::In, 1),
            ("mem_wr_addr_o", Dir::Out, 32),
            ("mem_wr_data_o", Dir::Out, 48),
        ];
        let got: Vec<(&str, Dir, u32)> = i.ports.iter().map(|p| (p.name.as_str(), p.dir, p.width)).collect();
        assert_eq!(got, expect);
    }

    #[test]
    fn padding_and_widths_come_from_the_golden_format() {
        let cfg = EngineConfig { key_bits: 8, id_bits: 10, ..EngineConfig::default() };
        let v = module(&cfg).to_verilog();
        // {valid = 0, key = 0xff, id = 0x3ff} in 19 bits.
        assert!(v.contains("localparam [18:0] PAD = 19'h3ffff;"), "{v}");
        assert_eq!(mem_len_bits(&cfg), 5);
        assert_eq!(resize("x", 8, 8), "x");
        assert_eq!(resize("x", 8, 4), "x[3:0]");
        assert_eq!(resize("x", 4, 8), "{4'd0, x}");
    }
}
