//! Quality gates on the generated RTL: the checked-in `hdl/` is the generator's output, every
//! top is Verilator-lint clean (`-Wall`, waivers only in `hdl/lint.vlt`) and latch-free in
//! Yosys, for the default configuration and for the other topologies and register spacings.
//! Verilator / Yosys / Icarus missing: these tests fail when `CI` is set and skip otherwise.

use neo_gen::output::check_dir;
use neo_gen::tools::{
    coarse_glue_synth_stats, coarse_synth_stats, coarse_synth_stats_with, icarus_compile, require_for_test,
    verilator_lint, verilator_lint_boxed, verilator_lint_with,
};
use neo_gen::units::VerilogFile;
use neo_gen::units::{lint_boxes, run_time_tops};
use neo_gen::{files_for, generate, top_modules, EngineConfig, Topology};
use std::collections::HashSet;
use std::path::PathBuf;

fn hdl_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..").join("hdl")
}

/// Non-default configurations every gate also covers.
fn other_configs() -> Vec<(String, EngineConfig)> {
    let base = EngineConfig::default();
    vec![
        ("odd_even_merge".into(), EngineConfig { topology: Topology::OddEvenMerge, ..base.clone() }),
        ("best_16".into(), EngineConfig { topology: Topology::Best16, ..base.clone() }),
        (
            "bitonic k=3 scu_lanes=64".into(),
            EngineConfig { register_every: 3, scu_lanes: 64, ..base.clone() },
        ),
        (
            "best_16 k=1".into(),
            EngineConfig { topology: Topology::Best16, register_every: 1, ..base.clone() },
        ),
        (
            "bitonic n=8 k=10 chunk=64 narrow scu_lanes=4, raster 2 ITUs 8 SCUs 4 banks of 16, window 32"
                .into(),
            EngineConfig {
                bsu_width: 8,
                register_every: 10,
                chunk: 64,
                key_bits: 8,
                id_bits: 10,
                addr_bits: 20,
                len_bits: 16,
                table_capacity: 4096,
                burst: 8,
                max_outstanding: 2,
                tile_bits: 4,
                itu_tag_bits: 1,
                scu_lanes: 4,
                raster_itus: 2,
                raster_scus: 8,
                raster_feature_buffer: 16,
                raster_feature_banks: 4,
                raster_window: 32,
                ..base
            },
        ),
    ]
}

/// Runs `check` on every cosimulated top of `cfg`, and on the run-time tops (the
/// preprocessing units) for the default configuration only: their Verilog depends on the
/// feature format and the tile alone, which the other configurations share or barely change,
/// and their synthesis is the slowest of the gates.
fn for_every_top(cfg: &EngineConfig, what: &str, check: impl Fn(&[VerilogFile], &str) -> Result<(), String>) {
    let mut failures = Vec::new();
    let run_time: &[&str] = if *cfg == EngineConfig::default() { run_time_tops() } else { &[] };
    for top in top_modules().iter().chain(run_time) {
        if let Err(e) = check(&files_for(cfg, top), top) {
            failures.push(format!("{what}: {top}: {e}"));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// A top's Verilog without each file's generator header (its first line names the
/// configuration's hash): two configurations whose files are otherwise the same text pass or
/// fail every gate alike.
fn body(files: &[VerilogFile]) -> Vec<(String, String)> {
    files.iter().map(|f| (f.name.clone(), f.body().to_string())).collect()
}

/// Runs `check` on every cosimulated top of every configuration of [`other_configs`] whose
/// Verilog differs from the default configuration's (checked by the `every_top_*` gates) and
/// from every earlier configuration's: a topology changes the sorting tops, not the raster ones.
fn for_other_configs(check: impl Fn(&EngineConfig, &[VerilogFile], &str) -> Result<(), String>) {
    let default = EngineConfig::default();
    let mut seen: HashSet<Vec<(String, String)>> =
        top_modules().iter().map(|top| body(&files_for(&default, top))).collect();
    let (mut failures, mut checked) = (Vec::new(), 0);
    for (what, cfg) in other_configs() {
        for top in top_modules() {
            let files = files_for(&cfg, top);
            if !seen.insert(body(&files)) {
                continue;
            }
            checked += 1;
            if let Err(e) = check(&cfg, &files, top) {
                failures.push(format!("{what}: {top}: {e}"));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    assert!(
        checked >= other_configs().len(),
        "every other configuration changes some top ({checked} checked)"
    );
}

#[test]
fn other_configurations_change_tops_and_share_the_rest() {
    let cfg = EngineConfig { topology: Topology::OddEvenMerge, ..EngineConfig::default() };
    let default = EngineConfig::default();
    let same = |top: &str| body(&files_for(&cfg, top)) == body(&files_for(&default, top));
    assert!(!same("neo_bsu"), "the topology changes the BSU");
    assert!(same("neo_itu"), "the topology leaves the ITU's text alone (only its header)");
}

#[test]
fn checked_in_hdl_is_the_generators_output() {
    let files = generate(&EngineConfig::default());
    let diffs = check_dir(&hdl_dir(), &files).expect("read hdl/");
    let list: Vec<String> = diffs.iter().map(|d| format!("  hdl/{d}")).collect();
    assert!(
        diffs.is_empty(),
        "hdl/ is out of date; run `neo gen` (cargo run -- gen) and commit:\n{}",
        list.join("\n")
    );
    assert!(hdl_dir().join("lint.vlt").exists(), "hdl/lint.vlt is missing");
}

fn lint(cfg: &EngineConfig, what: &str) {
    let vlt = hdl_dir().join("lint.vlt");
    for_every_top(cfg, what, |files, top| {
        verilator_lint_boxed(files, top, Some(&vlt), &lint_boxes(cfg, top)).map_err(|e| e.to_string())
    });
}

fn no_latches(cfg: &EngineConfig, what: &str) {
    for_every_top(cfg, what, |files, top| latch_free(cfg, files, top));
}

/// Modules the latch gate checks on their own and boxes in their parent: the SCU's lanes, blend
/// stages and pixel states are `scu_lanes` (16 to 64) copies of three unparameterised modules,
/// and synthesizing the SCU flat made it the slowest gate (with its 64-lane configuration).
const GATE_BOXES: &[(&str, &[&str])] = &[(
    neo_gen::units::scu::NAME,
    &[neo_gen::units::scu::lane::NAME, neo_gen::units::scu::blend::NAME, neo_gen::units::scu::pixel::NAME],
)];

/// Yosys finds no latch in `top` of `cfg`, and flip-flops (but in the comparator); a top of
/// [`GATE_BOXES`] as its own logic (the boxes instantiated), then each boxed module flat.
fn latch_free(cfg: &EngineConfig, files: &[VerilogFile], top: &str) -> Result<(), String> {
    if let Some((_, subs)) = GATE_BOXES.iter().find(|(t, _)| *t == top) {
        let s = coarse_glue_synth_stats(files, top, subs).map_err(|e| e.to_string())?;
        for sub in subs.iter() {
            let n = s.cells_by_type.get(*sub).copied().unwrap_or(0);
            if n == 0 {
                return Err(format!("no {sub} instance in the glue: {:?}", s.cells_by_type));
            }
            // Flat (the lane holds the exp unit); the blend stage has no flip-flops of its own.
            let own = coarse_synth_stats(&files_for(cfg, sub), sub).map_err(|e| format!("{sub}: {e}"))?;
            no_latch_cells(&own).map_err(|e| format!("{sub}: {e}"))?;
        }
        no_latch_cells(&s)?;
        return if s.flip_flops == 0 {
            Err(format!("no flip-flops in the glue? {:?}", s.cells_by_type))
        } else {
            Ok(())
        };
    }
    // Cores too large to flatten: their own logic, the units as black boxes (each unit is
    // checked as its own top).
    let boxes = neo_gen::report::hierarchical_boxes(top);
    let s = match &boxes {
        Some(boxes) => {
            coarse_glue_synth_stats(files, top, &boxes.iter().map(String::as_str).collect::<Vec<_>>())
        }
        None => coarse_synth_stats(files, top),
    }
    .map_err(|e| e.to_string())?;
    no_latch_cells(&s)?;
    if s.flip_flops == 0 && top != "neo_cmp_swap" {
        return Err(format!("no flip-flops at all? {:?}", s.cells_by_type));
    }
    Ok(())
}

fn no_latch_cells(s: &neo_gen::tools::SynthStats) -> Result<(), String> {
    if s.latches != 0 {
        return Err(format!("{} latch cells: {:?}", s.latches, s.cells_by_type));
    }
    Ok(())
}

#[test]
fn every_top_is_lint_clean() {
    if !require_for_test("verilator", "every_top_is_lint_clean") {
        return;
    }
    lint(&EngineConfig::default(), "default");
}

#[test]
fn other_configurations_are_lint_clean() {
    if !require_for_test("verilator", "other_configurations_are_lint_clean") {
        return;
    }
    let vlt = hdl_dir().join("lint.vlt");
    for_other_configs(|cfg, files, top| {
        verilator_lint_boxed(files, top, Some(&vlt), &lint_boxes(cfg, top)).map_err(|e| e.to_string())
    });
}

#[test]
fn every_top_is_latch_free() {
    if !require_for_test("yosys", "every_top_is_latch_free") {
        return;
    }
    no_latches(&EngineConfig::default(), "default");
}

#[test]
fn other_configurations_are_latch_free() {
    if !require_for_test("yosys", "other_configurations_are_latch_free") {
        return;
    }
    for_other_configs(latch_free);
}

#[test]
fn latch_check_catches_a_latch() {
    if !require_for_test("yosys", "latch_check_catches_a_latch") {
        return;
    }
    let text = "module l (input wire en_i, input wire d_i, output reg q_o);\n\
                always @* begin if (en_i) q_o = d_i; end\nendmodule\n";
    let s = coarse_synth_stats(&[VerilogFile { name: "l".into(), text: text.into() }], "l").unwrap();
    assert!(s.latches >= 1, "{:?}", s.cells_by_type);
}

/// The boxed lint still sees the parent's side of a boxed module: a connection of the wrong
/// width to the stub's port is reported (the stub keeps the generated port declarations).
#[test]
fn boxed_lint_catches_a_wrong_connection() {
    if !require_for_test("verilator", "boxed_lint_catches_a_wrong_connection") {
        return;
    }
    let child = "module c (\n  input  wire [3:0] a_i,\n  output wire [3:0] y_o\n);\n  assign y_o = ~a_i;\nendmodule\n";
    let parent = |w: u32| {
        format!(
            "module p (\n  input  wire [{w}:0] a_i,\n  output wire [{w}:0] y_o\n);\n  c u_c (.a_i(a_i), .y_o(y_o));\nendmodule\n"
        )
    };
    let files = |w| {
        vec![
            VerilogFile { name: "c".into(), text: child.into() },
            VerilogFile { name: "p".into(), text: parent(w) },
        ]
    };
    let boxes = ["c".to_string()];
    verilator_lint_boxed(&files(3), "p", None, &boxes).expect("matching widths lint clean against the stub");
    assert!(
        verilator_lint_boxed(&files(5), "p", None, &boxes).is_err(),
        "a 6-bit connection to a 4-bit port"
    );
}

/// Every module a lint boxes is a top of the gates with the default configuration's text, and
/// the cores under the engine are boxed (their bodies are linted as tops of their own).
#[test]
fn lint_boxes_are_tops_linted_on_their_own() {
    let cfg = EngineConfig::default();
    let tops: Vec<&str> = neo_gen::top_modules().iter().chain(run_time_tops()).copied().collect();
    let engine = lint_boxes(&cfg, neo_gen::units::engine::NAME);
    for core in [neo_gen::units::sort_core::NAME, neo_gen::units::raster_core::NAME] {
        assert!(engine.iter().any(|b| b == core), "{core} boxed under the engine: {engine:?}");
    }
    for top in &tops {
        for b in lint_boxes(&cfg, top) {
            assert!(tops.contains(&b.as_str()), "{top} boxes {b}, which is not a top of the gates");
        }
    }
    let odd = EngineConfig { topology: Topology::OddEvenMerge, ..cfg };
    let sort = lint_boxes(&odd, neo_gen::units::sort_core::NAME);
    assert!(!sort.iter().any(|b| b == "neo_bsu"), "a BSU of another topology is linted in full: {sort:?}");
}

/// The largest reorder window (4096 entries: a `g_cell` loop of 4095 cells, above Verilator's
/// default unroll limit of 1024) lints clean: the lint, like the model builds, passes
/// `--unroll-count` from the longest generate loop (`neo_gen::tools::verilator_unroll_args`).
#[test]
fn the_largest_reorder_window_verilates() {
    if !require_for_test("verilator", "the_largest_reorder_window_verilates") {
        return;
    }
    let cfg =
        EngineConfig { raster_window: neo_golden::engine::MAX_RASTER_WINDOW, ..EngineConfig::default() };
    let files = files_for(&cfg, "neo_raster_window");
    let vlt = hdl_dir().join("lint.vlt");
    verilator_lint(&files, "neo_raster_window", Some(&vlt)).unwrap_or_else(|e| panic!("{e}"));
}

#[test]
fn lint_catches_a_problem() {
    if !require_for_test("verilator", "lint_catches_a_problem") {
        return;
    }
    let text = "module u (input wire [3:0] a_i, output wire [1:0] y_o);\nassign y_o = a_i;\nendmodule\n";
    assert!(verilator_lint(&[VerilogFile { name: "u".into(), text: text.into() }], "u", None).is_err());
}

#[test]
fn icarus_compiles_every_top() {
    if !require_for_test("iverilog", "icarus_compiles_every_top") {
        return;
    }
    for_every_top(&EngineConfig::default(), "default", |files, top| {
        icarus_compile(files, top).map_err(|e| e.to_string())
    });
}

/// A top the primitive gates check: module, files, parameters.
type PrimTop = (String, Vec<VerilogFile>, Vec<(String, String)>);

/// What the primitive gates check for primitive `p`: its module (the top), the files, and the
/// parameters it is checked and measured at (`to_int`: its rounding; Yosys `chparam`, Verilator
/// `-G`), so every parameterisation is checked on its own.
fn prim_top(
    cfg: &EngineConfig,
    p: neo_gen::units::fp::FpPrim,
) -> (String, Vec<VerilogFile>, Vec<(String, String)>) {
    use neo_gen::units::fp::{module_name, params};
    (module_name(p).to_string(), files_for(cfg, module_name(p)), params(p))
}

/// The binary32 primitives (`neo_fp_*`, not cosimulation tops of their own: tb builds them
/// together in `neo_fp_bench`): each lint-clean and latch-free, every pipelined one with flip-flops.
#[test]
fn fp_primitives_are_lint_clean_and_latch_free() {
    use neo_gen::units::fp::{bench, cmp, FpPrim};
    if !require_for_test("verilator", "fp_primitives_are_lint_clean_and_latch_free")
        || !require_for_test("yosys", "fp_primitives_are_lint_clean_and_latch_free")
    {
        return;
    }
    let cfg = EngineConfig::default();
    let vlt = hdl_dir().join("lint.vlt");
    let mut tops: Vec<PrimTop> = FpPrim::ALL.iter().map(|&p| prim_top(&cfg, p)).collect();
    tops.extend([cmp::NAME, bench::NAME].map(|t| (t.to_string(), files_for(&cfg, t), Vec::new())));
    let mut failures = Vec::new();
    for (top, files, params) in &tops {
        let top = top.as_str();
        assert!(files.iter().any(|f| f.name == top), "{top} is not generated");
        let files = files.as_slice();
        if let Err(e) = verilator_lint_with(files, top, Some(&vlt), params) {
            failures.push(format!("lint: {top} {params:?}: {e}"));
        }
        if top == bench::NAME {
            continue; // side by side copies of the primitives checked above: lint only
        }
        match coarse_synth_stats_with(files, top, params) {
            Ok(s) if s.latches != 0 => failures.push(format!("{top}: {} latch cells", s.latches)),
            Ok(s) if s.flip_flops == 0 && top != cmp::NAME => failures.push(format!("{top}: no flip-flops")),
            Ok(_) => {}
            Err(e) => failures.push(format!("yosys: {top}: {e}")),
        }
    }
    if require_for_test("iverilog", "fp_primitives_are_lint_clean_and_latch_free (icarus)") {
        if let Err(e) = icarus_compile(&files_for(&cfg, bench::NAME), bench::NAME) {
            failures.push(format!("iverilog: {}: {e}", bench::NAME));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The port mux at the client counts the benches and engines use and at the bounds (1 client, and
/// `2^axi_id_bits`): lint-clean (Verilator `-GPORTS=P`) and latch-free (Yosys `chparam`), with
/// flip-flops; fewer clients than the engine's default `PORTS` make fewer cells.
#[test]
fn the_port_mux_is_lint_clean_and_latch_free_at_every_size() {
    use neo_gen::units::axi::mux;
    if !require_for_test("verilator", "the_port_mux_is_lint_clean_and_latch_free_at_every_size")
        || !require_for_test("yosys", "the_port_mux_is_lint_clean_and_latch_free_at_every_size")
    {
        return;
    }
    let cfg = EngineConfig::default();
    let (files, vlt) = (files_for(&cfg, mux::NAME), hdl_dir().join("lint.vlt"));
    let mut failures = Vec::new();
    let mut cells = Vec::new();
    for p in [1usize, 2, 3, 8, 1 << cfg.axi_id_bits] {
        let params = vec![("PORTS".to_string(), p.to_string())];
        if let Err(e) = verilator_lint_with(&files, mux::NAME, Some(&vlt), &params) {
            failures.push(format!("lint: PORTS={p}: {e}"));
        }
        match coarse_synth_stats_with(&files, mux::NAME, &params) {
            Ok(s) if s.latches != 0 || s.flip_flops == 0 => {
                failures.push(format!("PORTS={p}: {} latches, {} flip-flops", s.latches, s.flip_flops))
            }
            Ok(s) => cells.push(s.cells),
            Err(e) => failures.push(format!("yosys: PORTS={p}: {e}")),
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    assert!(cells.windows(2).all(|w| w[0] < w[1]), "cells grow with the clients: {cells:?}");
}

/// Yosys cells (generic gates, `synth -flatten`) and latency of each binary32 primitive, the
/// table of docs/rtl.md "Preprocessing arithmetic" (slow: run with `--ignored --nocapture`).
#[test]
#[ignore]
fn fp_primitive_cells() {
    use neo_gen::tools::synth_stats_with;
    use neo_gen::units::fp::{cmp, conv, label, latency, FpPrim};
    if !require_for_test("yosys", "fp_primitive_cells") {
        return;
    }
    let cfg = EngineConfig::default();
    println!("| module | latency | cells | flip-flops |");
    println!("|---|---:|---:|---:|");
    let mut rows: Vec<(String, String, PrimTop)> =
        FpPrim::ALL.iter().map(|&p| (label(p), latency(p).to_string(), prim_top(&cfg, p))).collect();
    for name in [cmp::NAME, conv::WIDEN_HALF_COMB_NAME] {
        let top = (name.to_string(), files_for(&cfg, name), Vec::new());
        rows.push((name.into(), "0 (combinational)".into(), top));
    }
    for (what, lat, (top, files, params)) in rows {
        let s = synth_stats_with(&files, &top, &params).unwrap_or_else(|e| panic!("{top}: {e}"));
        println!("| `{what}` | {lat} | {} | {} |", s.cells, s.flip_flops);
    }
}
