//! Functional smoke simulations of the generated RTL with Icarus Verilog against the golden
//! model: the BSU, the MSU+ and the Sorting Core, under random valid/ready backpressure on every
//! port, plus full-rate runs that check the documented latency and throughput.
//! (The cycle-level cosimulation lives in `tb/`; these are the generator's own sanity checks.)
//! Icarus missing: fails when `CI` is set, skips otherwise.

use neo_gen::tools::{require_for_test, TempFiles};
use neo_gen::units::VerilogFile;
use neo_gen::{files_for, EngineConfig, Topology};
use neo_golden::engine::{run_command, Memory, TileCmd as Cmd};
use neo_golden::sort::{merge2, merge_pass_count, SortEntry, SortFormat, SortMode, Sorter};
use std::process::Command;

/// xorshift64*: deterministic test data without extra crates.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    fn below(&mut self, n: u64) -> u64 {
        self.next() % n
    }
}

/// A random entry with keys in a small range (so (key, id) ties on the key are common).
fn entry(rng: &mut Rng, f: SortFormat, key_range: u64, valid_ratio: u64) -> SortEntry {
    let key = rng.below(key_range.min(f.key_max() as u64 + 1)) as u32;
    let id = rng.below(f.id_max() as u64) as u32; // never the reserved id
    SortEntry { key, id, valid: rng.below(100) < valid_ratio }
}

fn sorted(mut v: Vec<SortEntry>) -> Vec<SortEntry> {
    v.sort_by_key(|e| e.order_key());
    v
}

fn hex_digits(bits: u32) -> usize {
    bits.div_ceil(4) as usize
}

/// Compiles `files` + `tb` (module `tb`) with Icarus, runs it in a directory holding `data`
/// files, and returns its stdout.
fn simulate(files: &[VerilogFile], tb: &str, data: &[(&str, String)]) -> String {
    let mut all = files.to_vec();
    all.push(VerilogFile { name: "tb".into(), text: tb.to_string() });
    let tmp = TempFiles::write(&all).unwrap();
    for (name, text) in data {
        std::fs::write(tmp.dir().join(name), text).unwrap();
    }
    let exe = tmp.dir().join("sim.vvp");
    let out = Command::new("iverilog")
        .args(["-g2005", "-s", "tb", "-o"])
        .arg(&exe)
        .args(tmp.paths())
        .output()
        .unwrap();
    assert!(out.status.success(), "iverilog failed:\n{}", String::from_utf8_lossy(&out.stderr));
    let out = Command::new("vvp").arg("-n").arg(&exe).current_dir(tmp.dir()).output().unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(out.status.success(), "vvp failed:\n{stdout}\n{}", String::from_utf8_lossy(&out.stderr));
    assert!(!stdout.contains("TIMEOUT"), "simulation timed out:\n{stdout}");
    stdout
}

/// Clock, reset and a random-bit helper shared by the test benches. `P_VALID`/`P_READY` are the
/// percentages of cycles in which a source offers / a sink takes data.
fn tb_prelude(seed: u64, p_valid: u32, p_ready: u32) -> String {
    format!(
        "`timescale 1ns/1ps\nmodule tb;\n  reg clk = 1'b0;\n  reg rst_n = 1'b0;\n  always #5 clk = ~clk;\n\
         initial begin #17 rst_n = 1'b1; end\n  integer seed = {seed};\n  integer cycle = 0;\n\
         always @(posedge clk) cycle <= cycle + 1;\n\
         function chance; input integer p; begin chance = ({{$random(seed)}} % 100) < p; end endfunction\n\
         localparam integer P_VALID = {p_valid};\n  localparam integer P_READY = {p_ready};\n"
    )
}

// ------------------------------------------------------------------------------------ BSU

fn bsu_run(
    cfg: &EngineConfig,
    vectors: &[Vec<SortEntry>],
    seed: u64,
    p_valid: u32,
    p_ready: u32,
) -> (Vec<Vec<SortEntry>>, u64) {
    let f = cfg.format();
    let w = cfg.entry_bits();
    let n = cfg.bsu_width;
    let vw = w * n as u32;
    let m = vectors.len();
    let mut hex = String::new();
    for v in vectors {
        for e in v.iter().rev() {
            hex += &format!("{:0width$x}", f.pack(e), width = hex_digits(w));
        }
        hex.push('\n');
    }
    // Pack lanes: the concatenation above is MSB-first lane n-1 .. lane 0, which is only a
    // valid hex image when w is a multiple of 4; the default 48 bits is.
    assert_eq!(w % 4, 0, "test bench packs lanes as hex digits");
    let tb = format!(
        "{pre}  reg [{vw1}:0] vecs [0:{m1}];\n  initial $readmemh(\"in.hex\", vecs);\n\
         integer i_in = 0;\n  integer n_out = 0;\n  reg in_valid = 1'b0;\n  reg out_ready = 1'b0;\n\
         wire in_ready;\n  wire out_valid;\n  wire [{vw1}:0] out_data;\n\
         wire [{vw1}:0] in_data = (i_in < {m}) ? vecs[i_in] : {{{vw}{{1'b0}}}};\n\
         neo_bsu dut (.clk_i(clk), .rst_ni(rst_n), .in_valid_i(in_valid), .in_ready_o(in_ready), .in_data_i(in_data),\n\
           .out_valid_o(out_valid), .out_ready_i(out_ready), .out_data_o(out_data));\n\
         always @(posedge clk) if (rst_n) begin\n\
           if (in_valid & in_ready) i_in <= i_in + 1;\n\
           if (in_valid & ~in_ready) in_valid <= 1'b1;\n\
           else in_valid <= ((in_valid & in_ready) ? i_in + 1 : i_in) < {m} && chance(P_VALID);\n\
           out_ready <= chance(P_READY);\n\
           if (out_valid & out_ready) begin $display(\"OUT %0d %h\", cycle, out_data); n_out <= n_out + 1; end\n\
           if (n_out == {m}) $finish;\n\
           if (cycle > {limit}) begin $display(\"TIMEOUT\"); $finish; end\n\
         end\nendmodule\n",
        pre = tb_prelude(seed, p_valid, p_ready),
        vw1 = vw - 1,
        m1 = m - 1,
        limit = 100 * m + 1000,
    );
    let out = simulate(&files_for(cfg, "neo_bsu"), &tb, &[("in.hex", hex)]);
    let mut got = Vec::new();
    let mut cycles = Vec::new();
    for line in out.lines().filter(|l| l.starts_with("OUT ")) {
        let mut parts = line.split_whitespace().skip(1);
        cycles.push(parts.next().unwrap().parse::<u64>().unwrap());
        let h = parts.next().unwrap();
        let d = hex_digits(w);
        let lanes: Vec<SortEntry> = (0..n)
            .map(|i| f.unpack(u64::from_str_radix(&h[h.len() - (i + 1) * d..h.len() - i * d], 16).unwrap()))
            .collect();
        got.push(lanes);
    }
    let span = cycles.last().copied().unwrap_or(0) - cycles.first().copied().unwrap_or(0);
    (got, span)
}

fn bsu_vectors(cfg: &EngineConfig, m: usize, seed: u64) -> Vec<Vec<SortEntry>> {
    let mut rng = Rng(seed);
    let f = cfg.format();
    (0..m)
        .map(|k| {
            let mut v: Vec<SortEntry> = (0..cfg.bsu_width).map(|_| entry(&mut rng, f, 12, 70)).collect();
            if k % 5 == 0 {
                // Duplicated (key, id) with different valid bits: the network must not swap them.
                v[3] = v[1].with_valid(!v[1].valid);
            }
            if k % 7 == 0 {
                let pad = f.padding();
                for e in v.iter_mut().skip(cfg.bsu_width / 2) {
                    *e = pad;
                }
            }
            v
        })
        .collect()
}

fn check_bsu(cfg: &EngineConfig, seed: u64) {
    let vectors = bsu_vectors(cfg, 60, seed);
    let net = cfg.network();
    let expect: Vec<Vec<SortEntry>> = vectors
        .iter()
        .map(|v| {
            let mut v = v.clone();
            net.apply(&mut v);
            v
        })
        .collect();
    let (got, _) = bsu_run(cfg, &vectors, seed, 60, 50);
    assert_eq!(got.len(), expect.len(), "{:?}: vectors out", cfg.topology);
    for (k, (g, e)) in got.iter().zip(&expect).enumerate() {
        assert_eq!(g, e, "{:?} k={}: vector {k}", cfg.topology, cfg.register_every);
    }
    // Full rate: one vector per cycle, so the outputs span exactly m - 1 cycles.
    let (got, span) = bsu_run(cfg, &vectors, seed, 100, 100);
    assert_eq!(got, expect);
    assert_eq!(span, vectors.len() as u64 - 1, "II = 1 at full rate");
}

#[test]
fn bsu_sorts_like_the_golden_network_under_backpressure() {
    if !require_for_test("iverilog", "bsu_sorts_like_the_golden_network_under_backpressure") {
        return;
    }
    check_bsu(&EngineConfig::default(), 11);
    check_bsu(&EngineConfig { topology: Topology::Best16, register_every: 3, ..EngineConfig::default() }, 12);
    check_bsu(
        &EngineConfig { topology: Topology::OddEvenMerge, register_every: 1, ..EngineConfig::default() },
        13,
    );
}

// ------------------------------------------------------------------------------------ MSU

/// One input stream as beats `(empty, last, entry)`.
fn beats(s: &[SortEntry]) -> Vec<(bool, bool, SortEntry)> {
    if s.is_empty() {
        return vec![(true, true, SortEntry::default())];
    }
    s.iter().enumerate().map(|(i, e)| (false, i + 1 == s.len(), *e)).collect()
}

fn beats_hex(f: SortFormat, b: &[(bool, bool, SortEntry)]) -> String {
    let w = f.entry_bits();
    let mut s = String::new();
    for (empty, last, e) in b {
        let word = ((*empty as u128) << (w + 1)) | ((*last as u128) << w) | f.pack(e) as u128;
        s += &format!("{:0width$x}\n", word, width = hex_digits(w + 2));
    }
    s
}

type Merge = (Vec<SortEntry>, Vec<SortEntry>);

/// Output streams of a run: (entries, ended with an empty beat).
type Streams = Vec<(Vec<SortEntry>, bool)>;

/// Runs the merges back to back; returns the output streams (entries, empty flag) and the
/// cycles of the first and the last output beat.
fn msu_run(
    cfg: &EngineConfig,
    merges: &[Merge],
    drop: bool,
    seed: u64,
    p_valid: u32,
    p_ready: u32,
) -> (Streams, (u64, u64)) {
    let f = cfg.format();
    let w = cfg.entry_bits();
    let a: Vec<_> = merges.iter().flat_map(|(a, _)| beats(a)).collect();
    let b: Vec<_> = merges.iter().flat_map(|(_, b)| beats(b)).collect();
    let src = |s: &str, n: usize| {
        format!(
            "  reg [{bw1}:0] {s}_mem [0:{n1}];\n  initial $readmemh(\"{s}.hex\", {s}_mem);\n\
             integer {s}_i = 0;\n  reg {s}_valid = 1'b0;\n  wire {s}_ready;\n\
             wire [{bw1}:0] {s}_beat = ({s}_i < {n}) ? {s}_mem[{s}_i] : {{{bw}{{1'b0}}}};\n\
             always @(posedge clk) if (rst_n) begin\n\
               if ({s}_valid & {s}_ready) {s}_i <= {s}_i + 1;\n\
               if ({s}_valid & ~{s}_ready) {s}_valid <= 1'b1;\n\
               else {s}_valid <= ((({s}_valid & {s}_ready) ? {s}_i + 1 : {s}_i) < {n}) && chance(P_VALID);\n\
             end\n",
            bw1 = w + 1,
            bw = w + 2,
            n1 = n - 1,
        )
    };
    let outs = merges.len();
    let tb = format!(
        "{pre}{sa}{sb}  reg out_ready = 1'b0;\n  wire out_valid;\n  wire [{w1}:0] out_data;\n  wire out_last;\n  wire out_empty;\n\
         integer n_last = 0;\n\
         neo_msu dut (.clk_i(clk), .rst_ni(rst_n), .drop_invalid_i(1'b{drop}),\n\
           .a_valid_i(a_valid), .a_ready_o(a_ready), .a_data_i(a_beat[{w1}:0]), .a_last_i(a_beat[{w}]), .a_empty_i(a_beat[{w2}]),\n\
           .b_valid_i(b_valid), .b_ready_o(b_ready), .b_data_i(b_beat[{w1}:0]), .b_last_i(b_beat[{w}]), .b_empty_i(b_beat[{w2}]),\n\
           .out_valid_o(out_valid), .out_ready_i(out_ready), .out_data_o(out_data), .out_last_o(out_last), .out_empty_o(out_empty));\n\
         always @(posedge clk) if (rst_n) begin\n\
           out_ready <= chance(P_READY);\n\
           if (out_valid & out_ready) begin\n\
             $display(\"OUT %0d %0d %0d %h\", cycle, out_empty, out_last, out_data);\n\
             if (out_last) n_last <= n_last + 1;\n\
           end\n\
           if (n_last == {outs}) $finish;\n\
           if (cycle > {limit}) begin $display(\"TIMEOUT\"); $finish; end\n\
         end\nendmodule\n",
        pre = tb_prelude(seed, p_valid, p_ready),
        sa = src("a", a.len()),
        sb = src("b", b.len()),
        w1 = w - 1,
        w2 = w + 1,
        drop = drop as u8,
        limit = 50 * (a.len() + b.len()) + 1000,
    );
    let out = simulate(
        &files_for(cfg, "neo_msu"),
        &tb,
        &[("a.hex", beats_hex(f, &a)), ("b.hex", beats_hex(f, &b))],
    );
    let mut streams = Vec::new();
    let mut cur = Vec::new();
    let mut first = None;
    let mut last_cycle = 0;
    for line in out.lines().filter(|l| l.starts_with("OUT ")) {
        let p: Vec<&str> = line.split_whitespace().collect();
        let cycle: u64 = p[1].parse().unwrap();
        first.get_or_insert(cycle);
        last_cycle = cycle;
        let (empty, last) = (p[2] == "1", p[3] == "1");
        if empty {
            assert!(last && cur.is_empty(), "an empty beat must be the single beat of its merge: {line}");
        } else {
            cur.push(f.unpack(u64::from_str_radix(p[4], 16).unwrap()));
        }
        if last {
            streams.push((std::mem::take(&mut cur), empty));
        }
    }
    assert!(cur.is_empty(), "output ended without last");
    (streams, (first.unwrap_or(0), last_cycle))
}

fn msu_cases(f: SortFormat, seed: u64) -> Vec<Merge> {
    let mut rng = Rng(seed);
    let mut list = |n: usize, valid: u64| sorted((0..n).map(|_| entry(&mut rng, f, 40, valid)).collect());
    let mut cases: Vec<Merge> = vec![
        (vec![], vec![]),
        (list(5, 100), vec![]),
        (vec![], list(4, 100)),
        (list(3, 0), list(2, 0)), // everything dropped in drop mode
        (list(1, 100), list(1, 100)),
    ];
    for k in 0..12 {
        cases.push((list(k * 7 % 40, 70), list(k * 5 % 23, 85)));
    }
    // Ties: identical (key, id) in both inputs, different valid bits.
    let a = list(10, 100);
    let b: Vec<SortEntry> = a.iter().map(|e| e.with_valid(false)).collect();
    cases.push((a.clone(), b));
    cases.push((a, list(0, 100)));
    cases
}

fn check_msu(cfg: &EngineConfig, drop: bool, seed: u64, p_valid: u32, p_ready: u32) {
    let cases = msu_cases(cfg.format(), seed);
    let (got, _) = msu_run(cfg, &cases, drop, seed, p_valid, p_ready);
    assert_eq!(got.len(), cases.len(), "one output stream per merge");
    for (k, ((a, b), (out, empty))) in cases.iter().zip(&got).enumerate() {
        let expect = merge2(a, b, drop);
        assert_eq!(out, &expect, "merge {k} (drop {drop}): a={a:?} b={b:?}");
        assert_eq!(*empty, expect.is_empty(), "merge {k}: empty flag");
    }
}

#[test]
fn msu_merges_like_golden_merge2_under_backpressure() {
    if !require_for_test("iverilog", "msu_merges_like_golden_merge2_under_backpressure") {
        return;
    }
    let cfg = EngineConfig::default();
    for (seed, drop) in [(21, false), (22, true), (23, true)] {
        check_msu(&cfg, drop, seed, 55, 60);
    }
}

#[test]
fn msu_sustains_one_entry_per_cycle() {
    if !require_for_test("iverilog", "msu_sustains_one_entry_per_cycle") {
        return;
    }
    // One long merge without invalid entries at full rate: the 500 output beats come in 500
    // consecutive cycles.
    let cfg = EngineConfig::default();
    let f = cfg.format();
    let mut rng = Rng(31);
    let a = sorted((0..300).map(|_| entry(&mut rng, f, 1000, 100)).collect());
    let b = sorted((0..200).map(|_| entry(&mut rng, f, 1000, 100)).collect());
    let (got, (first, last)) = msu_run(&cfg, &[(a.clone(), b.clone())], true, 31, 100, 100);
    assert_eq!(got[0].0, merge2(&a, &b, true));
    assert_eq!(last - first, 499, "one output entry per cycle");
    // With invalid entries, dropping costs input cycles but never output bubbles beyond them:
    // 500 inputs of which the invalid ones are dropped take at most 500 cycles plus overhead.
    let a = sorted((0..300).map(|_| entry(&mut rng, f, 1000, 60)).collect());
    let b = sorted((0..200).map(|_| entry(&mut rng, f, 1000, 60)).collect());
    let (got, (first, last)) = msu_run(&cfg, &[(a.clone(), b.clone())], true, 32, 100, 100);
    assert_eq!(got[0].0, merge2(&a, &b, true));
    let steps = neo_golden::sort::MergeStream::new(&a, &b, true).count() as u64;
    assert!(last - first < steps, "{} cycles for {steps} merge steps", last - first);
}

// ------------------------------------------------------------------------------------ core

/// The golden effect of `cmds` on `mem` (golden's [`run_command`] on a memory holding `mem` at
/// entry address 0); returns the expected `done_len` of each command.
fn golden_core(cfg: &EngineConfig, mem: &mut [SortEntry], cmds: &[Cmd]) -> Vec<u64> {
    let f = cfg.format();
    let mut memory = Memory::default();
    memory.write_entries(&f, 0, mem);
    let mut sorter = Sorter::new(cfg.sort_config());
    let lens = cmds
        .iter()
        .map(|c| run_command(&mut sorter, &mut memory, c).expect("no reserved id in the stimulus").written)
        .collect();
    mem.copy_from_slice(&memory.read_entries(&f, 0, mem.len()));
    lens
}

/// Runs `cmds` on the core with a random-latency, random-ready memory model. With
/// `back_to_back` the next command is offered as soon as the previous one was taken (several in
/// flight), else only once every earlier command is done. Returns the memory, `done_len` per
/// command and the cycle of each `done_o` pulse.
fn core_run(
    cfg: &EngineConfig,
    mem: &[SortEntry],
    cmds: &[Cmd],
    seed: u64,
    p_valid: u32,
    p_ready: u32,
    back_to_back: bool,
) -> (Vec<SortEntry>, Vec<u64>, Vec<u64>) {
    let f = cfg.format();
    let w = cfg.entry_bits();
    let (aw, lw) = (cfg.addr_bits, cfg.len_bits);
    let bl = neo_gen::units::sort_core::mem_len_bits(cfg);
    let mem_hex: String = mem.iter().map(|e| format!("{:x}\n", f.pack(e))).collect();
    let field = |get: fn(&Cmd) -> u64| cmds.iter().map(|c| format!("{:x}\n", get(c))).collect::<String>();
    let nc = cmds.len();
    let mn = mem.len();
    let tb = format!(
        "{pre}  reg [{w1}:0] mem [0:{mn1}];\n  initial $readmemh(\"mem.hex\", mem);\n\
         reg [1:0] c_mode [0:{nc1}];\n  reg [{aw1}:0] c_src_a [0:{nc1}];\n  reg [{lw1}:0] c_len_a [0:{nc1}];\n\
         reg [{aw1}:0] c_src_b [0:{nc1}];\n  reg [{lw1}:0] c_len_b [0:{nc1}];\n  reg [{aw1}:0] c_dst [0:{nc1}];\n\
         initial begin $readmemh(\"mode.hex\", c_mode); $readmemh(\"src_a.hex\", c_src_a); $readmemh(\"len_a.hex\", c_len_a);\n\
           $readmemh(\"src_b.hex\", c_src_b); $readmemh(\"len_b.hex\", c_len_b); $readmemh(\"dst.hex\", c_dst); end\n\
         integer ic = 0;\n  integer nd = 0;\n  reg cmd_valid = 1'b0;\n  wire cmd_ready;\n  wire done;\n  wire [{lw1}:0] done_len;\n\
         wire req_valid;\n  reg req_ready = 1'b0;\n  wire [{aw1}:0] req_addr;\n  wire [{bl1}:0] req_len;\n\
         wire wr_valid;\n  reg wr_ready = 1'b0;\n  wire [{aw1}:0] wr_addr;\n  wire [{w1}:0] wdata;\n\
         reg rsp_valid = 1'b0;\n  wire rsp_ready;\n  reg [{w1}:0] rsp_data = {w}'d0;\n\
         reg [{aw1}:0] q_addr [0:255];\n  reg [{bl1}:0] q_len [0:255];\n  integer q_wp = 0;\n  integer q_rp = 0;\n\
         reg [{aw1}:0] r_addr;\n  integer r_left = 0;\n  integer k;\n\
         neo_sort_core dut (.clk_i(clk), .rst_ni(rst_n),\n\
           .cmd_valid_i(cmd_valid), .cmd_ready_o(cmd_ready), .cmd_mode_i(c_mode[ic]), .cmd_src_a_i(c_src_a[ic]),\n\
           .cmd_len_a_i(c_len_a[ic]), .cmd_src_b_i(c_src_b[ic]), .cmd_len_b_i(c_len_b[ic]), .cmd_dst_i(c_dst[ic]),\n\
           .done_o(done), .done_len_o(done_len),\n\
           .mem_req_valid_o(req_valid), .mem_req_ready_i(req_ready), .mem_req_addr_o(req_addr), .mem_req_len_o(req_len),\n\
           .mem_rsp_valid_i(rsp_valid), .mem_rsp_ready_o(rsp_ready), .mem_rsp_data_i(rsp_data),\n\
           .mem_wr_valid_o(wr_valid), .mem_wr_ready_i(wr_ready), .mem_wr_addr_o(wr_addr), .mem_wr_data_o(wdata));\n\
         always @(posedge clk) if (rst_n) begin\n\
           // commands: ic offered next, nd done\n\
           if (cmd_valid & cmd_ready) begin cmd_valid <= {b2b} && (ic + 1 < {nc}) && chance(P_VALID); ic <= ic + 1; end\n\
           else if (~cmd_valid & (ic < {nc}) & ({b2b} || (nd == ic)) & chance(P_VALID)) cmd_valid <= 1'b1;\n\
           if (done) begin\n\
             if (nd >= ic) $display(\"SPURIOUS done at %0d\", cycle);\n\
             $display(\"DONE %0d %0d %0d\", nd, done_len, cycle); nd <= nd + 1;\n\
           end\n\
           // writes apply at once; read requests queue up\n\
           wr_ready <= chance(P_READY);\n\
           if (wr_valid & wr_ready) mem[wr_addr] <= wdata;\n\
           req_ready <= chance(P_READY);\n\
           if (req_valid & req_ready) begin\n\
             if (req_len == {bl}'d0 || req_len > {burst}) begin $display(\"BADLEN\"); end\n\
             q_addr[q_wp % 256] <= req_addr; q_len[q_wp % 256] <= req_len; q_wp <= q_wp + 1;\n\
           end\n\
           // responses, in order, with random gaps\n\
           if (~rsp_valid | rsp_ready) begin\n\
             if (r_left > 0 && chance(P_VALID)) begin\n\
               rsp_valid <= 1'b1; rsp_data <= mem[r_addr]; r_addr <= r_addr + 1; r_left <= r_left - 1;\n\
             end else begin\n\
               rsp_valid <= 1'b0;\n\
               if (r_left == 0 && q_rp != q_wp) begin r_addr <= q_addr[q_rp % 256]; r_left <= q_len[q_rp % 256]; q_rp <= q_rp + 1; end\n\
             end\n\
           end\n\
           if (nd == {nc}) begin\n\
             for (k = 0; k < {mn}; k = k + 1) $display(\"MEM %h\", mem[k]);\n\
             $finish;\n\
           end\n\
           if (cycle > {limit}) begin $display(\"TIMEOUT\"); $finish; end\n\
         end\nendmodule\n",
        pre = tb_prelude(seed, p_valid, p_ready),
        w1 = w - 1,
        aw1 = aw - 1,
        lw1 = lw - 1,
        bl1 = bl - 1,
        mn1 = mn - 1,
        nc1 = nc - 1,
        limit = 400_000,
        b2b = back_to_back as u32,
        burst = cfg.burst,
    );
    let data = [
        ("mem.hex", mem_hex),
        ("mode.hex", field(|c| c.mode.code())),
        ("src_a.hex", field(|c| c.src_a)),
        ("len_a.hex", field(|c| c.len_a)),
        ("src_b.hex", field(|c| c.src_b)),
        ("len_b.hex", field(|c| c.len_b)),
        ("dst.hex", field(|c| c.dst)),
    ];
    let out = simulate(&files_for(cfg, "neo_sort_core"), &tb, &data);
    assert!(!out.contains("BADLEN"), "a read request of 0 or more than a burst of entries");
    assert!(!out.contains("SPURIOUS"), "done_o with no command in flight:\n{out}");
    assert!(!out.contains("TIMEOUT"), "timeout");
    let mut lens = Vec::new();
    let mut done_at = Vec::new();
    for line in out.lines().filter(|l| l.starts_with("DONE ")) {
        let p: Vec<&str> = line.split_whitespace().collect();
        lens.push(p[2].parse().unwrap());
        done_at.push(p[3].parse().unwrap());
    }
    let got: Vec<SortEntry> = out
        .lines()
        .filter_map(|l| l.strip_prefix("MEM "))
        .map(|h| f.unpack(u64::from_str_radix(h, 16).unwrap()))
        .collect();
    assert_eq!(got.len(), mem.len(), "memory dump");
    (got, lens, done_at)
}

fn check_core(cfg: &EngineConfig, seed: u64, p_valid: u32, p_ready: u32, back_to_back: bool) {
    let f = cfg.format();
    let c = cfg.chunk as u64;
    let mut rng = Rng(seed);
    // Memory: [0, 4c) random input region; [4c, 8c) two sorted streams; [8c, 24c) outputs.
    let mn = 24 * c as usize;
    let mut mem: Vec<SortEntry> = (0..mn).map(|_| entry(&mut rng, f, 50, 75)).collect();
    // Duplicated (key, id) with different valid bits inside the sort region.
    for k in (0..64).step_by(9) {
        mem[k + 3] = mem[k].with_valid(!mem[k].valid);
    }
    let (sa, la) = (4 * c, 2 * c + 37); // longer than a chunk: FIFO wrap-around
    let (sb, lb) = (sa + la, c / 2 + 3);
    let a = sorted(mem[sa as usize..][..la as usize].to_vec());
    let b = sorted(mem[sb as usize..][..lb as usize].to_vec());
    mem[sa as usize..][..la as usize].copy_from_slice(&a);
    mem[sb as usize..][..lb as usize].copy_from_slice(&b);
    let out = 8 * c;
    let s = |mode, src_a, len_a, dst| Cmd { mode, src_a, len_a, src_b: 0, len_b: 0, dst };
    let mg = |mode, src_a, len_a, src_b, len_b, dst| Cmd { mode, src_a, len_a, src_b, len_b, dst };
    let cmds = vec![
        s(SortMode::Sort, 0, c, out),
        s(SortMode::Dps, c, c - 1, out + c),
        s(SortMode::Sort, 2 * c, 17, out + 2 * c),
        s(SortMode::Sort, 2 * c + 20, 1, out + 2 * c + 20),
        s(SortMode::Sort, 2 * c + 30, 0, out + 2 * c + 30),
        s(SortMode::Dps, 2 * c + 40, c / 2 + 5, out + 2 * c + 40),
        s(SortMode::Sort, 3 * c, c + 9, out + 3 * c), // clamped to one chunk
        mg(SortMode::MergeDelete, sa, la, sb, lb, out + 4 * c),
        mg(SortMode::Merge, sa, la, sb, lb, out + 4 * c + la + lb),
        mg(SortMode::MergeDelete, sa, 0, sb, 5, out + 7 * c),
        mg(SortMode::MergeDelete, sa, 0, sb, 0, out + 7 * c + 10),
        mg(SortMode::Merge, sa, 7, sb, 0, out + 7 * c + 20),
    ];
    let mut expect = mem.clone();
    let lens = golden_core(cfg, &mut expect, &cmds);
    let (got, got_lens, _) = core_run(cfg, &mem, &cmds, seed, p_valid, p_ready, back_to_back);
    assert_eq!(got_lens, lens, "done_len per command");
    for (k, (g, e)) in got.iter().zip(&expect).enumerate() {
        assert_eq!(g, e, "memory entry {k} (first difference)");
    }
}

#[test]
fn sort_core_matches_golden_under_backpressure() {
    if !require_for_test("iverilog", "sort_core_matches_golden_under_backpressure") {
        return;
    }
    check_core(&EngineConfig::default(), 41, 60, 55, false);
}

#[test]
fn sort_core_back_to_back_commands_match_golden() {
    if !require_for_test("iverilog", "sort_core_back_to_back_commands_match_golden") {
        return;
    }
    // Every command offered as soon as the previous one was taken (loads overlap passes).
    check_core(&EngineConfig::default(), 43, 90, 70, true);
    check_core(&EngineConfig::default(), 44, 100, 100, true);
}

#[test]
fn sort_core_small_configuration_matches_golden() {
    if !require_for_test("iverilog", "sort_core_small_configuration_matches_golden") {
        return;
    }
    let cfg = EngineConfig {
        bsu_width: 8,
        topology: Topology::OddEvenMerge,
        register_every: 10,
        chunk: 64,
        key_bits: 8,
        id_bits: 11,
        addr_bits: 20,
        len_bits: 16,
        table_capacity: 4096,
        burst: 8,
        max_outstanding: 2,
        ..EngineConfig::default()
    };
    check_core(&cfg, 42, 80, 90, false);
    check_core(&cfg, 45, 85, 60, true);
}

#[test]
fn sort_core_full_rate_chunk_sort_time() {
    if !require_for_test("iverilog", "sort_core_full_rate_chunk_sort_time") {
        return;
    }
    // A 256-entry chunk at full memory rate: load (256 + BSU latency), 4 buffer passes and the
    // final pass to memory (256 + a few cycles per merge each). The bound documents the schedule.
    let cfg = EngineConfig::default();
    let f = cfg.format();
    let mut rng = Rng(51);
    let c = cfg.chunk as u64;
    let mem: Vec<SortEntry> = (0..2 * c as usize).map(|_| entry(&mut rng, f, 1 << 16, 100)).collect();
    let cmds = vec![Cmd { mode: SortMode::Sort, src_a: 0, len_a: c, src_b: 0, len_b: 0, dst: c }];
    let mut expect = mem.clone();
    golden_core(&cfg, &mut expect, &cmds);
    let (got, _, done_at) = core_run(&cfg, &mem, &cmds, 51, 100, 100, false);
    assert_eq!(got, expect);
    let cycles = done_at[0];
    let passes = merge_pass_count(c, cfg.bsu_width as u64) + 1;
    assert!(cycles <= c * (passes + 1) + 200, "chunk sort took {cycles} cycles");
    eprintln!("full-rate 256-entry chunk sort: {cycles} cycles ({passes} merge passes)");
}

#[test]
fn sort_core_back_to_back_chunks_overlap_loads_with_passes() {
    if !require_for_test("iverilog", "sort_core_back_to_back_chunks_overlap_loads_with_passes") {
        return;
    }
    // Four 256-entry SORTs offered back to back at full memory rate: after the first, each
    // chunk's load is hidden under the previous chunk's merge passes, so the interval between
    // `done_o` pulses is bounded by the MSU+ work (passes x entries, plus a few cycles per
    // merge), well under one command's latency (which adds the load of `c` entries).
    let cfg = EngineConfig::default();
    let f = cfg.format();
    let mut rng = Rng(52);
    let c = cfg.chunk as u64;
    let k = 4u64;
    let mem: Vec<SortEntry> =
        (0..2 * k as usize * c as usize).map(|_| entry(&mut rng, f, 1 << 16, 100)).collect();
    let cmds: Vec<Cmd> = (0..k)
        .map(|i| Cmd { mode: SortMode::Sort, src_a: i * c, len_a: c, src_b: 0, len_b: 0, dst: (k + i) * c })
        .collect();
    let mut expect = mem.clone();
    golden_core(&cfg, &mut expect, &cmds);
    let (got, _, done_at) = core_run(&cfg, &mem, &cmds, 52, 100, 100, true);
    assert_eq!(got, expect);
    let (single, _, one) = core_run(&cfg, &mem, &cmds[..1], 52, 100, 100, false);
    assert_eq!(
        &single[k as usize * c as usize..][..c as usize],
        &expect[k as usize * c as usize..][..c as usize]
    );
    let passes = merge_pass_count(c, cfg.bsu_width as u64);
    let merges = c / cfg.bsu_width as u64 - 1;
    let interval = (done_at[k as usize - 1] - done_at[0]) / (k - 1);
    eprintln!("back-to-back 256-entry SORTs: interval {interval} cycles, single {} cycles", one[0]);
    assert!(interval <= passes * c + 4 * merges + 16, "interval {interval} above the MSU+ bound");
    assert!(interval + c <= one[0], "load not hidden: interval {interval}, single {}", one[0]);
}

/// The leading-zero counter's inputs at `width` bits: every value up to 16 bits; else zero,
/// every single bit, every bit with every lower bit set, and random values shifted right by a
/// random amount (so every count occurs).
fn lzc_inputs(width: u32, rng: &mut Rng) -> Vec<u64> {
    if width <= 16 {
        return (0..1u64 << width).collect();
    }
    let mask = if width == 64 { u64::MAX } else { (1u64 << width) - 1 };
    let mut v = vec![0, mask];
    for b in 0..width {
        v.push(1u64 << b);
        v.push((1u64 << b) | ((1u64 << b) - 1));
    }
    for _ in 0..4000 {
        v.push((rng.next() & mask) >> rng.below(u64::from(width)));
    }
    v
}

#[test]
fn lzc_counts_leading_zeros_at_every_width() {
    if !require_for_test("iverilog", "lzc_counts_leading_zeros_at_every_width") {
        return;
    }
    let module = neo_gen::units::fp::lzc::module();
    let file = VerilogFile { name: module.name.clone(), text: module.to_verilog() };
    let mut rng = Rng(0x1ead_2e50);
    for width in [2u32, 4, 8, 16, 32, 64] {
        let inputs = lzc_inputs(width, &mut rng);
        let digits = hex_digits(width);
        let data: String = inputs.iter().map(|x| format!("{x:0digits$x}\n")).collect();
        let cb = neo_gen::units::fp::lzc::count_bits(width);
        let tb = format!(
            "module tb;\n  reg [{w1}:0] x;\n  wire [{c1}:0] cnt;\n  wire zero;\n  reg [{w1}:0] mem [0:{last}];\n\
             \x20 integer i;\n  neo_fp_lzc #(.WIDTH({width})) u_lzc (.x_i(x), .cnt_o(cnt), .zero_o(zero));\n\
             \x20 initial begin\n    $readmemh(\"in.hex\", mem);\n    for (i = 0; i <= {last}; i = i + 1) begin\n\
             \x20     x = mem[i];\n      #1 $display(\"%0d %0d\", cnt, zero);\n    end\n  end\nendmodule\n",
            w1 = width - 1,
            c1 = cb - 1,
            last = inputs.len() - 1,
        );
        let out = simulate(std::slice::from_ref(&file), &tb, &[("in.hex", data)]);
        let lines: Vec<&str> = out.lines().collect();
        assert_eq!(lines.len(), inputs.len(), "width {width}: one line per input");
        for (x, line) in inputs.iter().zip(lines) {
            let lz = (x.leading_zeros() - (64 - width)).min(width - 1);
            assert_eq!(line, format!("{lz} {}", u8::from(*x == 0)), "width {width}, x = {x:#x}");
        }
    }
}
