//! Running the EDA tools on generated files: Yosys synthesis statistics, Verilator lint and an
//! Icarus compile. Each writes the files to a fresh temporary directory first, so it works on
//! in-memory output as well as on a checked-in directory.

use crate::units::VerilogFile;
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

/// A tool that failed to run or reported a problem.
#[derive(Debug, thiserror::Error)]
pub enum ToolError {
    /// The tool is not on `PATH` (or could not be started).
    #[error("{tool} could not be run: {problem}")]
    Missing {
        /// Program name.
        tool: String,
        /// Why.
        problem: String,
    },
    /// The tool ran and failed; `output` is its stdout and stderr.
    #[error("{tool} failed on {top}:\n{output}")]
    Failed {
        /// Program name.
        tool: String,
        /// The top module it was run on.
        top: String,
        /// Its output.
        output: String,
    },
}

/// True when `tool --version` (`-V` for Yosys and Icarus) runs.
pub fn available(tool: &str) -> bool {
    let flag = if tool == "verilator" { "--version" } else { "-V" };
    Command::new(tool).arg(flag).output().map(|o| o.status.success()).unwrap_or(false)
}

/// For tests: true when `tool` can be run; otherwise panics when the `CI` environment variable
/// is set, and prints a SKIP message naming `test` and returns false when it is not.
pub fn require_for_test(tool: &str, test: &str) -> bool {
    if available(tool) {
        return true;
    }
    neo_golden::shared::skip_or_fail(
        test,
        &format!("{tool} is not on PATH (run scripts/setup to install it)"),
    );
    false
}

/// A temporary directory holding some generated files; removed on drop.
pub struct TempFiles {
    dir: PathBuf,
    paths: Vec<PathBuf>,
}

static COUNTER: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);

impl TempFiles {
    /// Writes `files` (as `NAME.v`) into a new directory under the system temp dir.
    pub fn write(files: &[VerilogFile]) -> std::io::Result<TempFiles> {
        let n = COUNTER.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let dir = std::env::temp_dir().join(format!("neo-gen-{}-{n}", std::process::id()));
        std::fs::create_dir_all(&dir)?;
        let mut paths = Vec::new();
        for f in files {
            let p = dir.join(f.file_name());
            std::fs::write(&p, &f.text)?;
            paths.push(p);
        }
        Ok(TempFiles { dir, paths })
    }

    /// The directory.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// The file paths, in the order given.
    pub fn paths(&self) -> &[PathBuf] {
        &self.paths
    }
}

impl Drop for TempFiles {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

fn run(tool: &str, top: &str, cmd: &mut Command) -> Result<String, ToolError> {
    let out = cmd.output().map_err(|e| ToolError::Missing { tool: tool.into(), problem: e.to_string() })?;
    let text = format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    if out.status.success() {
        Ok(text)
    } else {
        Err(ToolError::Failed { tool: tool.into(), top: top.into(), output: text })
    }
}

fn io_err(tool: &str, e: std::io::Error) -> ToolError {
    ToolError::Missing { tool: tool.into(), problem: format!("temporary files: {e}") }
}

/// Yosys statistics of one synthesized top (generic gates, flattened).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, serde::Deserialize)]
pub struct SynthStats {
    /// The top module.
    pub top: String,
    /// Total cells after `synth -flatten`.
    pub cells: u64,
    /// Flip-flop cells (every `$_*DFF*` type).
    pub flip_flops: u64,
    /// Latch cells (every `*DLATCH*`/`$dlatch*`/`$_SR_*` type); must be 0.
    pub latches: u64,
    /// Cell counts by type.
    pub cells_by_type: BTreeMap<String, u64>,
}

/// True for a Yosys flip-flop cell type.
pub fn is_flip_flop(cell_type: &str) -> bool {
    let t = cell_type.to_ascii_uppercase();
    t.contains("DFF")
}

/// True for a Yosys latch cell type.
pub fn is_latch(cell_type: &str) -> bool {
    let t = cell_type.to_ascii_uppercase();
    t.contains("DLATCH") || t.starts_with("$_SR_") || t == "$SR"
}

/// Synthesizes `top` from `files` with `yosys synth -flatten` (generic gates) and returns its
/// statistics.
pub fn synth_stats(files: &[VerilogFile], top: &str) -> Result<SynthStats, ToolError> {
    yosys_script_stat(files, top, &format!("synth -flatten -top {top};"))
}

/// [`synth_stats`] of `top` with its parameters set to `params` (`(name, value)`, Yosys
/// `chparam -set NAME VALUE TOP` before the synthesis): a parametric module measured at one
/// parameterisation as its own top (`neo_fp_to_int` at each rounding).
pub fn synth_stats_with(
    files: &[VerilogFile],
    top: &str,
    params: &[(String, String)],
) -> Result<SynthStats, ToolError> {
    yosys_script_stat(files, top, &format!("{} synth -flatten -top {top};", chparam(top, params)))
}

/// [`coarse_synth_stats`] of `top` with its parameters set to `params` (see [`synth_stats_with`]).
pub fn coarse_synth_stats_with(
    files: &[VerilogFile],
    top: &str,
    params: &[(String, String)],
) -> Result<SynthStats, ToolError> {
    let script = format!("{} hierarchy -check -top {top}; proc; flatten; opt_clean;", chparam(top, params));
    yosys_script_stat(files, top, &script)
}

/// `chparam -set NAME VALUE ... TOP;`, or nothing without parameters.
fn chparam(top: &str, params: &[(String, String)]) -> String {
    if params.is_empty() {
        return String::new();
    }
    let sets: Vec<String> = params.iter().map(|(n, v)| format!("-set {n} {v}")).collect();
    format!("chparam {} {top};", sets.join(" "))
}

/// The latch check: the front of `synth -flatten` up to `proc`, where a latch is inferred (as
/// `$dlatch`, or `$sr` / `$dlatchsr`) and flip-flops become `$dff` / `$adff` cells
/// (`hierarchy -check; proc; flatten; opt_clean`), and its statistics. `proc` alone decides
/// latches: the optimisations after it (`synth -run :fine`) took 15x longer on the preprocessing
/// datapaths (385 s against 26 s on `neo_pre_project`) and can only remove cells.
pub fn coarse_synth_stats(files: &[VerilogFile], top: &str) -> Result<SynthStats, ToolError> {
    yosys_script_stat(files, top, &format!("hierarchy -check -top {top}; proc; flatten; opt_clean;"))
}

/// Synthesis of `top`'s own logic: the modules in `blackboxes` become black boxes and the design
/// is not flattened (`blackbox ...; hierarchy -top TOP; synth -top TOP`), so the statistics are
/// the top's glue cells plus one cell per black-box instance (counted by type in
/// `cells_by_type`). For cores too large to synthesize flat. The boxes are made before
/// `hierarchy`: an instance of a parametric box with parameters (`neo_axi_mux #(.PORTS(8))`)
/// then stays a cell of the box's name, where `hierarchy` first would derive and keep a
/// `$paramod` copy of the module (synthesized into the glue, not counted as the box).
pub fn glue_synth_stats(
    files: &[VerilogFile],
    top: &str,
    blackboxes: &[&str],
) -> Result<SynthStats, ToolError> {
    let script = format!("blackbox {}; hierarchy -top {top}; synth -top {top};", blackboxes.join(" "));
    yosys_script_stat(&boxed_files("yosys", files, top, &owned(blackboxes))?, top, &script)
}

/// The latch check of [`coarse_synth_stats`] on `top`'s own logic, `blackboxes` as black boxes
/// (one cell per instance, by type, made before `hierarchy` as in [`glue_synth_stats`]), not
/// flattened.
pub fn coarse_glue_synth_stats(
    files: &[VerilogFile],
    top: &str,
    blackboxes: &[&str],
) -> Result<SynthStats, ToolError> {
    let script = format!("blackbox {}; hierarchy -top {top}; proc; opt_clean;", blackboxes.join(" "));
    yosys_script_stat(&boxed_files("yosys", files, top, &owned(blackboxes))?, top, &script)
}

fn owned(names: &[&str]) -> Vec<String> {
    names.iter().map(|s| s.to_string()).collect()
}

/// Runs `script` (Yosys commands after reading `files`) and returns `stat -json`'s statistics.
fn yosys_script_stat(files: &[VerilogFile], top: &str, script: &str) -> Result<SynthStats, ToolError> {
    let tmp = TempFiles::write(files).map_err(|e| io_err("yosys", e))?;
    let json = tmp.dir().join("stat.json");
    let reads: Vec<String> = tmp.paths().iter().map(|p| format!("read_verilog {};", p.display())).collect();
    let script = format!("{} {script} tee -q -o {} stat -json", reads.join(" "), json.display());
    run("yosys", top, Command::new("yosys").args(["-q", "-p", &script]))?;
    let text = std::fs::read_to_string(&json).map_err(|e| io_err("yosys", e))?;
    parse_stat_json(top, &text)
}

/// Parses the output of Yosys `stat -json` (the `design` totals).
pub fn parse_stat_json(top: &str, text: &str) -> Result<SynthStats, ToolError> {
    let bad = |why: &str| ToolError::Failed { tool: "yosys".into(), top: top.into(), output: why.into() };
    let text = without_hierarchy_lines(text);
    let v: serde_json::Value = serde_json::from_str(&text).map_err(|e| bad(&format!("stat JSON: {e}")))?;
    let design = v.get("design").ok_or_else(|| bad("stat JSON has no design"))?;
    let cells = design.get("num_cells").and_then(|c| c.as_u64()).ok_or_else(|| bad("no num_cells"))?;
    let mut by_type = BTreeMap::new();
    if let Some(map) = design.get("num_cells_by_type").and_then(|m| m.as_object()) {
        for (k, n) in map {
            by_type.insert(k.clone(), n.as_u64().unwrap_or(0));
        }
    }
    let flip_flops = by_type.iter().filter(|(k, _)| is_flip_flop(k)).map(|(_, n)| n).sum();
    let latches = by_type.iter().filter(|(k, _)| is_latch(k)).map(|(_, n)| n).sum();
    Ok(SynthStats { top: top.into(), cells, flip_flops, latches, cells_by_type: by_type })
}

/// `text` without the lines of the text hierarchy tree (`name count`, no quotes) that Yosys 0.23
/// writes into `stat -json` when the design has more than two levels of modules (the raster core,
/// its window loader, the window, its cells): they are not JSON.
fn without_hierarchy_lines(text: &str) -> String {
    let tree_line = |l: &str| {
        let mut words = l.split_whitespace();
        matches!((words.next(), words.next(), words.next()), (Some(name), Some(n), None)
            if !name.starts_with('"') && n.parse::<u64>().is_ok())
    };
    text.lines().filter(|l| !tree_line(l)).collect::<Vec<_>>().join("\n")
}

/// Verilator's default `--unroll-count`: it unrolls a generate loop of at most 16 times as many
/// iterations (1024; "Loop unrolling took too long ... set --unroll-count above 1024").
const VERILATOR_DEFAULT_UNROLL: u64 = 64;

/// The iteration count of the longest generate loop with a literal bound in `texts`, as the
/// emitter prints them (`for (i = 0; i < N; i = i + 1) begin : g_name`); 0 when there is none.
pub fn largest_generate_loop<'a>(texts: impl IntoIterator<Item = &'a str>) -> u64 {
    let bound = |line: &str| -> Option<u64> {
        let rest = line.trim_start().strip_prefix("for (")?;
        if !line.contains(") begin : ") {
            return None;
        }
        let (_, after) = rest.split_once(" < ")?;
        after.split_once(';')?.0.trim().parse().ok()
    };
    texts.into_iter().flat_map(str::lines).filter_map(bound).max().unwrap_or(0)
}

/// The Verilator arguments that let it unroll every generate loop of `texts`: none when the
/// longest fits the default unroll count, else `--unroll-count` with 16 times that count above
/// it (a raster core's reorder window of 4096 entries has a loop of 4095 cells).
pub fn verilator_unroll_args<'a>(texts: impl IntoIterator<Item = &'a str>) -> Vec<String> {
    let longest = largest_generate_loop(texts);
    let count = longest / 16 + 1;
    if count <= VERILATOR_DEFAULT_UNROLL {
        Vec::new()
    } else {
        vec!["--unroll-count".into(), count.to_string()]
    }
}

/// `verilator --lint-only -Wall [vlt] FILES --top-module TOP`; `Ok` when it prints nothing and
/// succeeds, else the output.
pub fn verilator_lint(files: &[VerilogFile], top: &str, vlt: Option<&Path>) -> Result<(), ToolError> {
    verilator_lint_with(files, top, vlt, &[])
}

/// [`verilator_lint`] with the top's parameters set to `params` (`-GNAME=VALUE`).
pub fn verilator_lint_with(
    files: &[VerilogFile],
    top: &str,
    vlt: Option<&Path>,
    params: &[(String, String)],
) -> Result<(), ToolError> {
    let tmp = TempFiles::write(files).map_err(|e| io_err("verilator", e))?;
    let mut cmd = Command::new("verilator");
    cmd.args(["--lint-only", "-Wall"]);
    cmd.args(verilator_unroll_args(files.iter().map(|f| f.text.as_str())));
    cmd.args(params.iter().map(|(n, v)| format!("-G{n}={v}")));
    if let Some(v) = vlt {
        cmd.arg(v);
    }
    cmd.args(tmp.paths()).args(["--top-module", top]);
    let out = run("verilator", top, &mut cmd)?;
    if out.trim().is_empty() {
        Ok(())
    } else {
        Err(ToolError::Failed { tool: "verilator".into(), top: top.into(), output: out })
    }
}

/// [`verilator_lint`] of `top` with the modules named in `boxes` replaced by their interfaces
/// ([`interface_stub`]): the lint covers `top`'s own text and every connection to the boxed
/// modules (their ports and parameters are declared as generated), but not the boxed bodies,
/// which must be linted on their own (see [`crate::units::lint_boxes`]).
pub fn verilator_lint_boxed(
    files: &[VerilogFile],
    top: &str,
    vlt: Option<&Path>,
    boxes: &[String],
) -> Result<(), ToolError> {
    verilator_lint(&boxed_files("verilator", files, top, boxes)?, top, vlt)
}

/// `files` for a run on `top` with the modules in `boxes` as interface stubs
/// ([`interface_stub`]), without the files that only boxed modules instantiate (a module is kept
/// when a kept, unboxed file names it).
fn boxed_files(
    tool: &str,
    files: &[VerilogFile],
    top: &str,
    boxes: &[String],
) -> Result<Vec<VerilogFile>, ToolError> {
    let mut kept: Vec<VerilogFile> = Vec::with_capacity(files.len());
    let mut open: Vec<&VerilogFile> = files.iter().filter(|f| f.name == top).collect();
    while let Some(f) = open.pop() {
        if kept.iter().any(|k| k.name == f.name) {
            continue;
        }
        if f.name != top && boxes.contains(&f.name) {
            let text = interface_stub(&f.text).ok_or_else(|| ToolError::Failed {
                tool: tool.into(),
                top: top.into(),
                output: format!("{}: no `module ... );` header to box", f.file_name()),
            })?;
            kept.push(VerilogFile { name: f.name.clone(), text });
            continue;
        }
        open.extend(files.iter().filter(|g| g.name != f.name && instantiates(&f.text, &g.name)));
        kept.push(f.clone());
    }
    // Dependencies first, as given.
    kept.sort_by_key(|k| files.iter().position(|f| f.name == k.name));
    Ok(kept)
}

/// True when `text` names module `name` as a word followed by a space (an instance, or a
/// comment: keeping a file too many is harmless).
fn instantiates(text: &str, name: &str) -> bool {
    text.match_indices(name).any(|(k, _)| {
        let before = text[..k].chars().next_back().is_none_or(|c| !(c.is_alphanumeric() || c == '_'));
        before && text[k + name.len()..].starts_with(' ')
    })
}

/// A generated module's text reduced to its declaration: everything up to the line `);` that
/// closes its port list, then `endmodule`, inside lint waivers for the ports the empty body
/// leaves unused or undriven. `None` when the text has no such header.
pub fn interface_stub(text: &str) -> Option<String> {
    let start = text.find("\nmodule ").map(|k| k + 1).or_else(|| text.starts_with("module ").then_some(0))?;
    let close = text[start..].find("\n);\n")? + start + "\n);\n".len();
    Some(format!(
        "// interface stub for a boxed lint: the body is linted on its own\n\
         /* verilator lint_off UNUSEDSIGNAL */\n/* verilator lint_off UNUSEDPARAM */\n\
         /* verilator lint_off UNDRIVEN */\n{}endmodule\n/* verilator lint_on UNDRIVEN */\n\
         /* verilator lint_on UNUSEDPARAM */\n/* verilator lint_on UNUSEDSIGNAL */\n",
        &text[start..close]
    ))
}

/// `iverilog -g2005 -s TOP FILES` (compile only); `Ok` when it succeeds silently.
pub fn icarus_compile(files: &[VerilogFile], top: &str) -> Result<(), ToolError> {
    let tmp = TempFiles::write(files).map_err(|e| io_err("iverilog", e))?;
    let out_file = tmp.dir().join("a.out");
    let mut cmd = Command::new("iverilog");
    cmd.args(["-g2005", "-Wall", "-s", top, "-o"]).arg(&out_file).args(tmp.paths());
    let out = run("iverilog", top, &mut cmd)?;
    if out.trim().is_empty() {
        Ok(())
    } else {
        Err(ToolError::Failed { tool: "iverilog".into(), top: top.into(), output: out })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn file(name: &str, body: &str) -> VerilogFile {
        VerilogFile {
            name: name.into(),
            text: format!("// header\nmodule {name} (\n  input wire a_i\n);\n{body}endmodule\n"),
        }
    }

    #[test]
    fn the_unroll_count_follows_the_longest_generate_loop_as_emitted() {
        let with_window = |w: usize| {
            let cfg = neo_golden::engine::EngineConfig { raster_window: w, ..Default::default() };
            crate::units::generate(&cfg)
        };
        let texts = |files: &[VerilogFile]| files.iter().map(|f| f.text.clone()).collect::<Vec<_>>();
        let small = texts(&with_window(1));
        assert!(largest_generate_loop(small.iter().map(String::as_str)) < 1024);
        assert!(
            verilator_unroll_args(small.iter().map(String::as_str)).is_empty(),
            "default flags for the paper's engine"
        );
        let big = texts(&with_window(4096));
        assert_eq!(largest_generate_loop(big.iter().map(String::as_str)), 4095, "the window's g_cell loop");
        assert_eq!(verilator_unroll_args(big.iter().map(String::as_str)), ["--unroll-count", "256"]);
        let named = "    for (i = 0; i < PORTS; i = i + 1) begin : g_port\n    for (c = 0; c < 9000; c = c + 1) begin\n";
        assert_eq!(largest_generate_loop([named]), 0, "a named bound and a procedural loop are not counted");
    }

    #[test]
    fn boxing_stubs_the_boxes_and_drops_what_only_they_use() {
        let files = [
            file("leaf", ""),
            file("leaf_wide", ""),
            file("mid", "  leaf u_leaf (.a_i(a_i));\n"),
            file("top", "  mid u_mid (.a_i(a_i));\n  leaf_wide u_w (.a_i(a_i));\n"),
        ];
        let kept = boxed_files("t", &files, "top", &["mid".to_string()]).unwrap();
        let names: Vec<&str> = kept.iter().map(|f| f.name.as_str()).collect();
        assert_eq!(names, ["leaf_wide", "mid", "top"], "leaf is only under the boxed mid");
        let stub = &kept[1].text;
        assert!(
            stub.contains("module mid (") && stub.contains("endmodule") && !stub.contains("u_leaf"),
            "{stub}"
        );
        assert!(!instantiates("  leaf_wide u_w", "leaf"), "a longer name is not the module");
        assert!(interface_stub("no module here").is_none());
    }

    #[test]
    fn cell_classes() {
        for ff in ["$_DFF_P_", "$_DFFE_PN0P_", "$_SDFFCE_PN0P_", "$dff", "$adff"] {
            assert!(is_flip_flop(ff) && !is_latch(ff), "{ff}");
        }
        for l in ["$_DLATCH_P_", "$dlatch", "$adlatch", "$_SR_PP_", "$_DLATCHSR_PPP_"] {
            assert!(is_latch(l) && !is_flip_flop(l), "{l}");
        }
        assert!(!is_flip_flop("$_MUX_") && !is_latch("$_MUX_"));
    }

    #[test]
    fn chparam_sets_every_parameter_of_the_top() {
        assert_eq!(chparam("t", &[]), "");
        let p = [("WIDTH".to_string(), "40".to_string()), ("DEPTH".to_string(), "64".to_string())];
        assert_eq!(chparam("t", &p), "chparam -set WIDTH 40 -set DEPTH 64 t;");
    }

    #[test]
    fn stat_json_is_parsed() {
        let text = r#"{"design": {"num_cells": 10, "num_cells_by_type": {"$_DFFE_PP_": 4, "$_DLATCH_P_": 1, "$_AND_": 5}}}"#;
        let s = parse_stat_json("t", text).unwrap();
        assert_eq!((s.cells, s.flip_flops, s.latches), (10, 4, 1));
        assert!(parse_stat_json("t", "{}").is_err());
        assert!(parse_stat_json("t", "garbage").is_err());
    }

    /// Yosys 0.23 writes the text hierarchy tree into `stat -json` for designs three modules
    /// deep; the totals are still read.
    #[test]
    fn stat_json_with_hierarchy_lines_is_parsed() {
        let text = "{\n \"modules\": {\"\\\\a\": {\"num_cells\": 2}},\n       neo_raster_window             1\n         neo_raster_window_cell     31\n \"design\": {\"num_cells\": 7, \"num_cells_by_type\": {\"$_DFF_P_\": 3}}\n}";
        let s = parse_stat_json("t", text).unwrap();
        assert_eq!((s.cells, s.flip_flops), (7, 3));
    }
}
