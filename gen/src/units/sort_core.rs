//! `neo_sort_core`: one Sorting Core (paper Section 5.3): BSU + MSU+ + two chunk buffers, a
//! command port and a memory-request port. The protocols are documented in `docs/rtl.md`.
//!
//! # Commands (`cmd_mode_i`)
//! - `0` SORT: sort the chunk `src_a[0 .. min(len_a, chunk))` into `dst` (conventional sort of
//!   one chunk: BSU vectors of `n` with padding, then MSU+ merge passes, no dropping);
//! - `1` DPS: the same datapath (a DPS pass is a chunk sort of the reused table);
//! - `2` MERGE_DELETE: merge the sorted streams `A = src_a[0..len_a)` and `B = src_b[0..len_b)`
//!   into `dst`, dropping entries whose valid bit is 0 (golden `merge2(a, b, true)`);
//! - `3` MERGE: the same without dropping (golden `merge2(a, b, false)`, the global passes).
//!
//! `done_o` pulses for one cycle when the command has finished (every write accepted by the
//! memory); `done_len_o` then holds the number of entries written, and keeps it until the
//! next command is accepted. `cmd_ready_o` is high while the core is idle.
//!
//! # Datapath
//! SORT/DPS: LOAD reads the chunk in bursts; the responses fill an `n`-lane deserializer
//! (lanes start as golden padding), each full (or final partial) vector goes through the BSU,
//! whose output lanes are written one per cycle into buffer 0 (the padding, which sorts last, is
//! not written). Then merge passes: runs of `n, 2n, ...` are merged pairwise by the MSU+ from one
//! buffer into the other (a lone last run is merged with an empty stream, i.e. copied); the
//! final pass (the one that leaves a single run, also when the chunk is a single vector) writes
//! to memory instead.
//! MERGE modes: both streams are prefetched in bursts into the two buffers used as circular
//! FIFOs (space reserved before a read is issued, so responses are always accepted); the MSU+
//! output is written to memory.
//!
//! This is the reduced form of the paper's core: two chunk buffers (not two input and two
//! output buffers), and no overlap of one command's load with the previous one's passes.

use crate::config::GenConfig;
use crate::emit::expr::{bits_for, hex, lane, lit};
use crate::emit::{conns, if_, if_else, set, Item, Module, Stmt};

/// Module name.
pub const NAME: &str = "neo_sort_core";

/// Command modes (`cmd_mode_i`).
pub mod mode {
    /// Chunk sort.
    pub const SORT: u64 = 0;
    /// DPS pass over one chunk (same datapath as SORT).
    pub const DPS: u64 = 1;
    /// Merge of A and B dropping invalid entries.
    pub const MERGE_DELETE: u64 = 2;
    /// Merge of A and B keeping every entry.
    pub const MERGE: u64 = 3;
}

const S_IDLE: u64 = 0;
const S_LOAD: u64 = 1;
const S_PASS: u64 = 2;
const S_MERGE: u64 = 3;
const S_FINISH: u64 = 4;

/// Width of `mem_req_len_o` for `cfg` (holds `0..=burst`).
pub fn mem_len_bits(cfg: &GenConfig) -> u32 {
    bits_for(cfg.burst as u64)
}

/// `x` (`from` bits) resized to `to` bits (zero-extended or truncated).
fn resize(x: &str, from: u32, to: u32) -> String {
    match from.cmp(&to) {
        std::cmp::Ordering::Equal => x.to_string(),
        std::cmp::Ordering::Greater => format!("{x}[{}:0]", to - 1),
        std::cmp::Ordering::Less => format!("{{{}, {x}}}", lit(to - from, 0)),
    }
}

/// The Sorting Core for `cfg`.
pub fn module(cfg: &GenConfig) -> Module {
    let n = cfg.bsu_width as u32;
    let w = cfg.entry_bits();
    let d = cfg.chunk as u64;
    let da = bits_for(d - 1); // buffer address
    let dc = bits_for(d); // 0..=chunk
    let pw = dc + 2; // pass arithmetic (run, pair start: < 3 * chunk)
    let aw = cfg.addr_bits;
    let lw = cfg.len_bits;
    let bl = mem_len_bits(cfg);
    let burst = cfg.burst as u64;
    let mo = cfg.max_outstanding as u64;
    let tw = bits_for(mo - 1); // tag pointer
    let tc = bits_for(mo); // tag count
    let nl = bits_for(n as u64 - 1); // lane index
    let pad = cfg.format().pack(&cfg.format().padding());
    let vw = n * w;

    let mut m = Module::new(NAME);
    m.doc(format!(
        "Sorting Core: {}-input {} BSU, MSU+, two {}-entry chunk buffers; entries of {w} bits.",
        n,
        cfg.topology.name(),
        d
    ));
    m.doc("Modes: 0 SORT chunk, 1 DPS chunk, 2 MERGE with delete, 3 MERGE keeping invalid. See docs/rtl.md.");
    m.clock_reset();
    m.input_c("cmd_valid_i", 1, "a command is offered");
    m.output_c("cmd_ready_o", 1, "the core is idle and takes the command");
    m.input_c("cmd_mode_i", 2, "0 sort, 1 dps, 2 merge-delete, 3 merge");
    m.input_c("cmd_src_a_i", aw, "entry address of the chunk / stream A");
    m.input_c("cmd_len_a_i", lw, "entries of the chunk (<= chunk size) / stream A");
    m.input_c("cmd_src_b_i", aw, "entry address of stream B (merge modes)");
    m.input_c("cmd_len_b_i", lw, "entries of stream B (merge modes)");
    m.input_c("cmd_dst_i", aw, "entry address of the output");
    m.output_c("done_o", 1, "one-cycle pulse: the command finished");
    m.output_c("done_len_o", lw, "entries written by the last command");
    m.output_c("mem_req_valid_o", 1, "a memory request is offered");
    m.input_c("mem_req_ready_i", 1, "the memory takes the request");
    m.output_c("mem_req_write_o", 1, "1: write one entry; 0: read a burst");
    m.output_c("mem_req_addr_o", aw, "entry address");
    m.output_c("mem_req_len_o", bl, "entries (reads: 1..burst; writes: 1)");
    m.output_c("mem_wdata_o", w, "entry to write (writes)");
    m.input_c("mem_rsp_valid_i", 1, "a read response beat (one entry), in request order");
    m.output_c("mem_rsp_ready_o", 1, "the core takes the response beat");
    m.input_c("mem_rsp_data_i", w, "the entry read");

    m.localparam("S_IDLE", 3, lit(3, S_IDLE));
    m.localparam("S_LOAD", 3, lit(3, S_LOAD));
    m.localparam("S_PASS", 3, lit(3, S_PASS));
    m.localparam("S_MERGE", 3, lit(3, S_MERGE));
    m.localparam("S_FINISH", 3, lit(3, S_FINISH));
    m.localparam("PAD", w, hex(w, pad));

    // ---------------------------------------------------------------- registers
    m.blank();
    m.comment("Command and state.");
    m.reg("state_q", 3).reg("mode_q", 2).reg("dst_q", aw).reg("len_q", dc).reg("ocnt_q", lw);
    m.comment("Read issuer: next address and entries left to request per stream, reservations.");
    m.reg("rd_a_addr_q", aw).reg("rd_a_left_q", lw).reg("rd_b_addr_q", aw).reg("rd_b_left_q", lw);
    m.reg("a_resv_q", dc + 1).reg("b_resv_q", dc + 1).reg("rr_q", 1);
    m.comment("Outstanding read bursts {stream, len}, in request order.");
    m.mem("tag_mem", bl + 1, mo as u32);
    m.reg("tag_wp_q", tw).reg("tag_rp_q", tw).reg("tag_cnt_q", tc).reg("rsp_cnt_q", bl);
    m.comment("Stream sources feeding the MSU+ (read pointer, entries left, active).");
    m.reg("sa_act_q", 1).reg("sa_rem_q", lw).reg("sa_ptr_q", da);
    m.reg("sb_act_q", 1).reg("sb_rem_q", lw).reg("sb_ptr_q", da);
    m.comment("Merge-mode FIFOs in the chunk buffers (write pointer, entries present).");
    m.reg("fa_wp_q", da).reg("fa_cnt_q", dc).reg("fb_wp_q", da).reg("fb_cnt_q", dc);
    m.comment("Merge passes: run length, source buffer, next pair start.");
    m.reg("run_q", pw).reg("src_q", 1).reg("pair_q", pw);
    m.comment("LOAD: deserializer (lanes, fill index, full), entries received, BSU output serializer.");
    m.reg("des_lane_q", nl).reg("des_full_q", 1).reg("rcv_q", dc).reg("ser_lane_q", nl).reg("ser_cnt_q", dc);

    // ---------------------------------------------------------------- decode
    m.blank();
    m.wire_assign("st_idle", 1, "state_q == S_IDLE");
    m.wire_assign("st_load", 1, "state_q == S_LOAD");
    m.wire_assign("st_pass", 1, "state_q == S_PASS");
    m.wire_assign("st_merge", 1, "state_q == S_MERGE");
    m.wire_assign("st_finish", 1, "state_q == S_FINISH");
    m.wire_assign("cmd_sort", 1, "~cmd_mode_i[1]");
    let dlit = lit(lw, d);
    m.wire_assign(
        "cmd_len_clamped",
        dc,
        format!("(cmd_len_a_i > {dlit}) ? {} : {}", lit(dc, d), resize("cmd_len_a_i", lw, dc)),
    );
    m.wire_assign("final_pass", 1, format!("{{run_q[{}:0], 1'b0}} >= {}", pw - 2, resize("len_q", dc, pw)));

    // ---------------------------------------------------------------- instances
    m.blank();
    m.comment("BSU: fed by the deserializer during LOAD, drained lane by lane into buffer 0.");
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
    m.comment("MSU+: A and B from the chunk buffers (pass runs or merge FIFOs).");
    for s in ["a", "b"] {
        m.wire(format!("{s}_valid"), 1).wire(format!("{s}_ready"), 1).wire(format!("{s}_data"), w);
        m.wire(format!("{s}_last"), 1).wire(format!("{s}_empty"), 1);
    }
    m.wire("o_valid", 1).wire("o_ready", 1).wire("o_data", w).wire("o_last", 1).wire("o_empty", 1);
    m.instance(
        "neo_msu",
        "u_msu",
        conns(&[
            ("clk_i", "clk_i".into()),
            ("rst_ni", "rst_ni".into()),
            ("drop_invalid_i", format!("mode_q == {}", lit(2, mode::MERGE_DELETE))),
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
        ]),
    );
    m.blank();
    m.comment("Chunk buffers: port 0 reads source A, port 1 source B.");
    for b in 0..2 {
        m.wire(format!("buf{b}_we"), 1).wire(format!("buf{b}_waddr"), da).wire(format!("buf{b}_wdata"), w);
        m.wire(format!("buf{b}_rdata0"), w).wire(format!("buf{b}_rdata1"), w);
        m.instance(
            "neo_chunk_ram",
            format!("u_buf{b}"),
            conns(&[
                ("clk_i", "clk_i".into()),
                ("we_i", format!("buf{b}_we")),
                ("waddr_i", format!("buf{b}_waddr")),
                ("wdata_i", format!("buf{b}_wdata")),
                ("raddr0_i", "sa_ptr_q".into()),
                ("rdata0_o", format!("buf{b}_rdata0")),
                ("raddr1_i", "sb_ptr_q".into()),
                ("rdata1_o", format!("buf{b}_rdata1")),
            ]),
        );
    }

    // ---------------------------------------------------------------- read issuer
    m.blank();
    m.comment("Read issuer: bursts of up to the burst size; merge modes reserve FIFO space first.");
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
        format!("(rd_a_left_q != {}) & (st_load | (st_merge & ({})))", lit(lw, 0), fits("a")),
    );
    m.wire_assign("req_b_ok", 1, format!("(rd_b_left_q != {}) & st_merge & ({})", lit(lw, 0), fits("b")));
    m.wire_assign("tag_free", 1, format!("tag_cnt_q != {}", lit(tc, mo)));
    m.wire_assign("rd_pick_b", 1, "req_b_ok & (~req_a_ok | rr_q)");
    m.wire_assign("rd_want", 1, "(req_a_ok | req_b_ok) & tag_free");
    m.wire_assign("to_mem", 1, "st_merge | (st_pass & final_pass)");
    m.wire_assign("wr_want", 1, "to_mem & o_valid & ~o_empty");
    m.wire_assign("rd_fire", 1, "rd_want & ~wr_want & mem_req_ready_i");
    m.wire_assign("wr_fire", 1, "wr_want & mem_req_ready_i");
    m.wire_assign("wr_addr", aw, format!("dst_q + {}", resize("ocnt_q", lw, aw)));
    m.assign("mem_req_valid_o", "wr_want | rd_want");
    m.assign("mem_req_write_o", "wr_want");
    m.assign("mem_req_addr_o", "wr_want ? wr_addr : (rd_pick_b ? rd_b_addr_q : rd_a_addr_q)");
    m.assign("mem_req_len_o", format!("wr_want ? {} : (rd_pick_b ? len_b_next : len_a_next)", lit(bl, 1)));
    m.assign("mem_wdata_o", "o_data");

    // ---------------------------------------------------------------- responses
    m.blank();
    m.comment("Responses: routed by the oldest outstanding burst's tag.");
    m.wire_assign("tag_head", bl + 1, "tag_mem[tag_rp_q]");
    m.wire_assign("tag_head_b", 1, format!("tag_head[{bl}]"));
    m.wire_assign("tag_head_len", bl, format!("tag_head[{}:0]", bl - 1));
    m.wire_assign("des_accept", 1, "~des_full_q | bsu_in_ready");
    m.assign(
        "mem_rsp_ready_o",
        format!("(tag_cnt_q != {}) & (st_merge | (st_load & des_accept))", lit(tc, 0)),
    );
    m.wire_assign("rsp_fire", 1, "mem_rsp_valid_i & mem_rsp_ready_o");
    m.wire_assign("rsp_burst_end", 1, format!("rsp_fire & (rsp_cnt_q + {} == tag_head_len)", lit(bl, 1)));
    m.wire_assign("beat_load", 1, "rsp_fire & st_load");
    m.wire_assign("beat_a", 1, "rsp_fire & st_merge & ~tag_head_b");
    m.wire_assign("beat_b", 1, "rsp_fire & st_merge & tag_head_b");

    // ---------------------------------------------------------------- deserializer
    m.blank();
    m.comment(
        "Deserializer: lanes start as padding; a vector is complete at lane n-1 or the chunk's last entry.",
    );
    m.wire_assign("des_push", 1, "des_full_q & bsu_in_ready");
    m.wire_assign(
        "des_vec_end",
        1,
        format!("(des_lane_q == {}) | (rcv_q + {} == len_q)", lit(nl, n as u64 - 1), lit(dc, 1)),
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

    // ---------------------------------------------------------------- serializer
    m.blank();
    m.comment("Serializer: BSU output lanes to buffer 0, one per cycle; padding lanes are not written.");
    m.reg("ser_entry", w);
    let arms =
        (0..n).map(|i| (lit(nl, i as u64), vec![set("ser_entry", lane("bsu_out_data", i, w))])).collect();
    m.comb(vec![set("ser_entry", lit(w, 0)), Stmt::Case("ser_lane_q".into(), arms, vec![])]);
    m.wire_assign("ser_fire", 1, "st_load & bsu_out_valid");
    m.wire_assign(
        "ser_vec_end",
        1,
        format!("(ser_lane_q == {}) | (ser_cnt_q + {} == len_q)", lit(nl, n as u64 - 1), lit(dc, 1)),
    );
    m.assign("bsu_out_ready", "ser_fire & ser_vec_end");

    // ---------------------------------------------------------------- sources
    m.blank();
    m.comment("Stream sources: an empty stream is one beat with empty = last = 1.");
    for (s, f, buf_sel) in [
        ("a", "fa", "(~st_merge & src_q) ? buf1_rdata0 : buf0_rdata0"),
        ("b", "fb", "(st_merge | src_q) ? buf1_rdata1 : buf0_rdata1"),
    ] {
        let zero = lit(lw, 0);
        m.wire_assign(format!("s{s}_none"), 1, format!("s{s}_rem_q == {zero}"));
        m.assign(
            format!("{s}_valid"),
            format!("s{s}_act_q & (s{s}_none | ~st_merge | ({f}_cnt_q != {}))", lit(dc, 0)),
        );
        m.assign(format!("{s}_data"), buf_sel);
        m.assign(format!("{s}_empty"), format!("s{s}_none"));
        m.assign(format!("{s}_last"), format!("s{s}_rem_q <= {}", lit(lw, 1)));
        m.wire_assign(format!("{s}_pop"), 1, format!("{s}_valid & {s}_ready"));
        m.wire_assign(format!("{s}_pop_ent"), 1, format!("{s}_pop & ~s{s}_none"));
    }

    // ---------------------------------------------------------------- output side
    m.blank();
    m.comment("MSU+ output: to the other buffer during non-final passes, else memory writes.");
    m.assign("o_ready", "~to_mem | o_empty | mem_req_ready_i");
    m.wire_assign("o_ent", 1, "o_valid & o_ready & ~o_empty");
    m.wire_assign("o_buf", 1, "o_ent & st_pass & ~final_pass");
    m.wire_assign("o_count", 1, "o_buf | wr_fire");
    m.wire_assign("merge_end", 1, "st_merge & o_valid & o_ready & o_last");
    m.wire_assign("ocnt_buf", da, resize("ocnt_q", lw, da));
    m.assign("buf0_we", "(ser_fire & ~st_pass) | beat_a | (o_buf & src_q)");
    m.assign(
        "buf0_waddr",
        format!("st_load ? {} : (st_merge ? fa_wp_q : ocnt_buf)", resize("ser_cnt_q", dc, da)),
    );
    m.assign("buf0_wdata", "st_load ? ser_entry : (st_merge ? mem_rsp_data_i : o_data)");
    m.assign("buf1_we", "beat_b | (o_buf & ~src_q)");
    m.assign("buf1_waddr", "st_merge ? fb_wp_q : ocnt_buf");
    m.assign("buf1_wdata", "st_merge ? mem_rsp_data_i : o_data");

    // ---------------------------------------------------------------- pass control
    m.blank();
    m.comment("Pass control: next pair A = [pair, pair + alen), B = [pair + alen, pair + alen + blen).");
    let len_pw = resize("len_q", dc, pw);
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
    m.wire_assign("pass_end", 1, format!("st_pass & (ocnt_q == {})", resize("len_q", dc, lw)));
    m.assign("cmd_ready_o", "st_idle");
    m.assign("done_o", "st_finish");
    m.assign("done_len_o", "ocnt_q");

    // ---------------------------------------------------------------- sequential
    m.blank();
    m.seq_noreset(vec![if_("rd_fire", vec![set("tag_mem[tag_wp_q]", "{rd_pick_b, mem_req_len_o}")])]);
    let z = |bits: u32| lit(bits, 0);
    let one = |bits: u32| lit(bits, 1);
    let resets = vec![
        set("state_q", "S_IDLE"),
        set("mode_q", z(2)),
        set("dst_q", z(aw)),
        set("len_q", z(dc)),
        set("ocnt_q", z(lw)),
        set("rd_a_addr_q", z(aw)),
        set("rd_a_left_q", z(lw)),
        set("rd_b_addr_q", z(aw)),
        set("rd_b_left_q", z(lw)),
        set("a_resv_q", z(dc + 1)),
        set("b_resv_q", z(dc + 1)),
        set("rr_q", z(1)),
        set("tag_wp_q", z(tw)),
        set("tag_rp_q", z(tw)),
        set("tag_cnt_q", z(tc)),
        set("rsp_cnt_q", z(bl)),
        set("sa_act_q", z(1)),
        set("sa_rem_q", z(lw)),
        set("sa_ptr_q", z(da)),
        set("sb_act_q", z(1)),
        set("sb_rem_q", z(lw)),
        set("sb_ptr_q", z(da)),
        set("fa_wp_q", z(da)),
        set("fa_cnt_q", z(dc)),
        set("fb_wp_q", z(da)),
        set("fb_cnt_q", z(dc)),
        set("run_q", z(pw)),
        set("src_q", z(1)),
        set("pair_q", z(pw)),
        set("des_lane_q", z(nl)),
        set("des_full_q", z(1)),
        set("rcv_q", z(dc)),
        set("ser_lane_q", z(nl)),
        set("ser_cnt_q", z(dc)),
    ];
    let mut body = Vec::new();
    // State machine and command capture.
    body.push(Stmt::Comment("state machine".into()));
    body.push(Stmt::Case(
        "state_q".into(),
        vec![
            (
                "S_IDLE".into(),
                vec![if_(
                    "cmd_valid_i",
                    vec![
                        set("mode_q", "cmd_mode_i"),
                        set("dst_q", "cmd_dst_i"),
                        set("len_q", "cmd_len_clamped"),
                        set("ocnt_q", z(lw)),
                        set("rd_a_addr_q", "cmd_src_a_i"),
                        set("rd_b_addr_q", "cmd_src_b_i"),
                        set("a_resv_q", z(dc + 1)),
                        set("b_resv_q", z(dc + 1)),
                        set("rr_q", z(1)),
                        set("sa_ptr_q", z(da)),
                        set("sb_ptr_q", z(da)),
                        set("fa_wp_q", z(da)),
                        set("fb_wp_q", z(da)),
                        set("run_q", lit(pw, n as u64)),
                        set("src_q", z(1)),
                        set("pair_q", z(pw)),
                        set("des_lane_q", z(nl)),
                        set("rcv_q", z(dc)),
                        set("ser_lane_q", z(nl)),
                        set("ser_cnt_q", z(dc)),
                        if_else(
                            "cmd_sort",
                            vec![
                                set("rd_a_left_q", resize("cmd_len_clamped", dc, lw)),
                                set("rd_b_left_q", z(lw)),
                                set("state_q", format!("(cmd_len_clamped == {}) ? S_FINISH : S_LOAD", z(dc))),
                            ],
                            vec![
                                set("rd_a_left_q", "cmd_len_a_i"),
                                set("rd_b_left_q", "cmd_len_b_i"),
                                set("sa_act_q", one(1)),
                                set("sa_rem_q", "cmd_len_a_i"),
                                set("sb_act_q", one(1)),
                                set("sb_rem_q", "cmd_len_b_i"),
                                set("state_q", "S_MERGE"),
                            ],
                        ),
                    ],
                )],
            ),
            (
                "S_LOAD".into(),
                vec![if_(
                    format!("ser_fire & ser_vec_end & (ser_cnt_q + {} == len_q)", one(dc)),
                    vec![set("state_q", "S_PASS")],
                )],
            ),
            (
                "S_PASS".into(),
                vec![if_(
                    "pass_end",
                    vec![if_else(
                        "final_pass",
                        vec![set("state_q", "S_FINISH")],
                        vec![
                            set("run_q", format!("{{run_q[{}:0], 1'b0}}", pw - 2)),
                            set("src_q", "~src_q"),
                            set("pair_q", z(pw)),
                            set("ocnt_q", z(lw)),
                        ],
                    )],
                )],
            ),
            ("S_MERGE".into(), vec![if_("merge_end", vec![set("state_q", "S_FINISH")])]),
            ("S_FINISH".into(), vec![set("state_q", "S_IDLE")]),
        ],
        vec![set("state_q", "S_IDLE")],
    ));
    // Output counter (pass_end resets it in the case above; counting never coincides with it:
    // at pass_end every entry of the pass has been counted).
    body.push(if_("o_count", vec![set("ocnt_q", format!("ocnt_q + {}", one(lw)))]));
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
    m.seq(resets, body);
    m
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::interface::Dir;

    #[test]
    fn interface_has_the_documented_ports_and_widths() {
        let cfg = GenConfig::default();
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
            ("mem_req_valid_o", Dir::Out, 1),
            ("mem_req_ready_i", Dir::In, 1),
            ("mem_req_write_o", Dir::Out, 1),
            ("mem_req_addr_o", Dir::Out, 32),
            ("mem_req_len_o", Dir::Out, 5),
            ("mem_wdata_o", Dir::Out, 48),
            ("mem_rsp_valid_i", Dir::In, 1),
            ("mem_rsp_ready_o", Dir::Out, 1),
            ("mem_rsp_data_i", Dir::In, 48),
        ];
        let got: Vec<(&str, Dir, u32)> = i.ports.iter().map(|p| (p.name.as_str(), p.dir, p.width)).collect();
        assert_eq!(got, expect);
    }

    #[test]
    fn padding_and_widths_come_from_the_golden_format() {
        let cfg = GenConfig { key_bits: 8, id_bits: 10, ..GenConfig::default() };
        let v = module(&cfg).to_verilog();
        // {valid = 0, key = 0xff, id = 0x3ff} in 19 bits.
        assert!(v.contains("localparam [18:0] PAD = 19'h3ffff;"), "{v}");
        assert_eq!(mem_len_bits(&cfg), 5);
        assert_eq!(resize("x", 8, 8), "x");
        assert_eq!(resize("x", 8, 4), "x[3:0]");
        assert_eq!(resize("x", 4, 8), "{4'd0, x}");
    }
}
