//! Quality gates on the generated RTL: the checked-in `hdl/` is the generator's output, every
//! top is Verilator-lint clean (`-Wall`, waivers only in `hdl/lint.vlt`) and latch-free in
//! Yosys, for the default configuration and for the other topologies and register spacings.
//! Verilator / Yosys / Icarus missing: these tests fail when `CI` is set and skip otherwise.

use neo_gen::output::check_dir;
use neo_gen::tools::{
    coarse_glue_synth_stats, coarse_synth_stats, icarus_compile, require_for_test, verilator_lint,
};
use neo_gen::units::run_time_tops;
use neo_gen::units::VerilogFile;
use neo_gen::{files_for, generate, top_modules, EngineConfig, Topology};
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
            "bitonic n=8 k=10 chunk=64 narrow scu_lanes=4, raster 2 ITUs 8 SCUs 4 banks of 16".into(),
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
    for_every_top(cfg, what, |files, top| verilator_lint(files, top, Some(&vlt)).map_err(|e| e.to_string()));
}

fn no_latches(cfg: &EngineConfig, what: &str) {
    for_every_top(cfg, what, |files, top| {
        // Cores too large to flatten: their own logic, the units as black boxes (each unit is
        // checked as its own top).
        let boxes = neo_gen::report::hierarchical_boxes(cfg, top);
        let s = match &boxes {
            Some(boxes) => {
                coarse_glue_synth_stats(files, top, &boxes.iter().map(String::as_str).collect::<Vec<_>>())
            }
            None => coarse_synth_stats(files, top),
        }
        .map_err(|e| e.to_string())?;
        if s.latches != 0 {
            return Err(format!("{} latch cells: {:?}", s.latches, s.cells_by_type));
        }
        if s.flip_flops == 0 && top != "neo_cmp_swap" {
            return Err(format!("no flip-flops at all? {:?}", s.cells_by_type));
        }
        Ok(())
    });
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
    for (what, cfg) in other_configs() {
        lint(&cfg, &what);
    }
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
    for (what, cfg) in other_configs() {
        no_latches(&cfg, &what);
    }
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

/// The binary32 primitives (`neo_fp_*`, not cosimulation tops of their own: tb builds them
/// together in `neo_fp_bench`): each lint-clean and latch-free, every pipelined one with flip-flops.
#[test]
fn fp_primitives_are_lint_clean_and_latch_free() {
    use neo_gen::units::fp::{bench, cmp, module_name, FpPrim};
    if !require_for_test("verilator", "fp_primitives_are_lint_clean_and_latch_free")
        || !require_for_test("yosys", "fp_primitives_are_lint_clean_and_latch_free")
    {
        return;
    }
    let cfg = EngineConfig::default();
    let vlt = hdl_dir().join("lint.vlt");
    let mut tops: Vec<&str> = FpPrim::ALL.iter().map(|&p| module_name(p)).collect();
    tops.extend([cmp::NAME, bench::NAME]);
    let mut failures = Vec::new();
    for top in tops {
        let files = files_for(&cfg, top);
        assert!(!files.is_empty(), "{top} is not generated");
        if let Err(e) = verilator_lint(&files, top, Some(&vlt)) {
            failures.push(format!("lint: {top}: {e}"));
        }
        if top == bench::NAME {
            continue; // side by side copies of the primitives checked above: lint only
        }
        match coarse_synth_stats(&files, top) {
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

/// Yosys cells (generic gates, `synth -flatten`) and latency of each binary32 primitive, the
/// table of docs/rtl.md "Preprocessing arithmetic" (slow: run with `--ignored --nocapture`).
#[test]
#[ignore]
fn fp_primitive_cells() {
    use neo_gen::tools::synth_stats;
    use neo_gen::units::fp::{cmp, latency, module_name, FpPrim};
    if !require_for_test("yosys", "fp_primitive_cells") {
        return;
    }
    let cfg = EngineConfig::default();
    println!("| module | latency | cells | flip-flops |");
    println!("|---|---:|---:|---:|");
    let mut rows: Vec<(&str, String)> =
        FpPrim::ALL.iter().map(|&p| (module_name(p), latency(p).to_string())).collect();
    rows.push((cmp::NAME, "0 (combinational)".into()));
    for (top, lat) in rows {
        let s = synth_stats(&files_for(&cfg, top), top).unwrap_or_else(|e| panic!("{top}: {e}"));
        println!("| `{top}` | {lat} | {} | {} |", s.cells, s.flip_flops);
    }
}
