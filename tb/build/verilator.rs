//! The Verilator installation and what every build of a model shares (flags, the class lists of
//! its makefile). Used by `build.rs` (static models) and by `neo_tb::dynmodel` (models built at
//! run time), so it depends on nothing but std.

use std::fs;
use std::path::{Path, PathBuf};
use std::process::Command;

/// Verilator flags used for every top (part of the cache key). Lint warnings stay fatal.
/// `--x-initial unique`: every variable's initial value is drawn when the model is constructed,
/// as the context's `randReset`/`randSeed` say (random by default: `neo_tb::xinit`), so an
/// output that depends on an unreset register or an unwritten memory word differs from the
/// golden model. `--x-assign unique`: an X Verilator itself inserts (a variable part-select
/// whose index can run past the vector) reads a value drawn the same way, not 0. The generator
/// writes no X; for every unit top and the CI engine the C++ is the same as with
/// `--x-assign fast`; the default engine's differs in three such selects (`docs/rtl.md`,
/// "Initial values").
pub const VERILATOR_FLAGS: &[&str] =
    &["--cc", "--trace", "-O3", "--x-assign", "unique", "--x-initial", "unique"];

/// Preprocessor definitions of every C++ file of a model and of the runtime (VCD tracing on).
pub const CPP_DEFINES: &[(&str, &str)] =
    &[("VM_COVERAGE", "0"), ("VM_SC", "0"), ("VM_TRACE", "1"), ("VM_TRACE_VCD", "1"), ("VM_TRACE_FST", "0")];

/// The Verilator runtime sources (under `include/`) every model links.
pub const RUNTIME_SOURCES: &[&str] = &["verilated.cpp", "verilated_vcd_c.cpp", "verilated_threads.cpp"];

/// [`VERILATOR_FLAGS`] for a model without tracing (`--trace` left out: a run-time model that
/// writes no waves; its C++ is about half as large).
#[allow(dead_code)] // build.rs builds traced models only
pub const VERILATOR_FLAGS_UNTRACED: &[&str] =
    &["--cc", "-O3", "--x-assign", "unique", "--x-initial", "unique"];

/// [`CPP_DEFINES`] for a model without tracing.
#[allow(dead_code)] // build.rs builds traced models only
pub const CPP_DEFINES_UNTRACED: &[(&str, &str)] =
    &[("VM_COVERAGE", "0"), ("VM_SC", "0"), ("VM_TRACE", "0"), ("VM_TRACE_VCD", "0"), ("VM_TRACE_FST", "0")];

/// [`RUNTIME_SOURCES`] for a model without tracing.
#[allow(dead_code)] // build.rs builds traced models only
pub const RUNTIME_SOURCES_UNTRACED: &[&str] = &["verilated.cpp", "verilated_threads.cpp"];

/// [`VERILATOR_FLAGS`] for a model traced as FST (`--trace-fst`; `WAVES=fst` builds).
pub const VERILATOR_FLAGS_FST: &[&str] =
    &["--cc", "--trace-fst", "-O3", "--x-assign", "unique", "--x-initial", "unique"];

/// [`CPP_DEFINES`] for a model traced as FST.
pub const CPP_DEFINES_FST: &[(&str, &str)] =
    &[("VM_COVERAGE", "0"), ("VM_SC", "0"), ("VM_TRACE", "1"), ("VM_TRACE_VCD", "0"), ("VM_TRACE_FST", "1")];

/// [`RUNTIME_SOURCES`] for a model traced as FST (the FST writer includes GTKWave's `fstapi.c`,
/// LZ4 and FastLZ; the library links `-lz`).
pub const RUNTIME_SOURCES_FST: &[&str] = &["verilated.cpp", "verilated_fst_c.cpp", "verilated_threads.cpp"];

/// [`VERILATOR_FLAGS`] for a coverage model (`NEO_COVERAGE=1`): `--coverage` (line, toggle and
/// the generator's named cover points) instead of `--trace` (coverage models write no waves: the
/// C++ stays smaller).
pub const VERILATOR_FLAGS_COVERAGE: &[&str] =
    &["--cc", "--coverage", "-O3", "--x-assign", "unique", "--x-initial", "unique"];

/// [`VERILATOR_FLAGS_COVERAGE`] without toggle coverage (`--coverage-line --coverage-user`):
/// for tops whose toggle instrumentation is too large to build routinely (the raster core's
/// C++ grows from 28 to over 300 files).
pub const VERILATOR_FLAGS_COVERAGE_NO_TOGGLE: &[&str] =
    &["--cc", "--coverage-line", "--coverage-user", "-O3", "--x-assign", "unique", "--x-initial", "unique"];

/// [`CPP_DEFINES`] for a coverage model.
pub const CPP_DEFINES_COVERAGE: &[(&str, &str)] =
    &[("VM_COVERAGE", "1"), ("VM_SC", "0"), ("VM_TRACE", "0"), ("VM_TRACE_VCD", "0"), ("VM_TRACE_FST", "0")];

/// [`RUNTIME_SOURCES`] for a coverage model (`verilated_cov.cpp` writes the data).
pub const RUNTIME_SOURCES_COVERAGE: &[&str] =
    &["verilated.cpp", "verilated_cov.cpp", "verilated_threads.cpp"];

/// The Verilator installation.
pub struct Verilator {
    /// The executable.
    pub exe: PathBuf,
    /// `verilator --version`.
    pub version: String,
    /// `VERILATOR_ROOT` (holds `include/`).
    pub root: PathBuf,
}

impl Verilator {
    /// Finds `verilator` on `PATH` (or `$VERILATOR`), or `None` when it does not run.
    pub fn find() -> Option<Verilator> {
        let exe = std::env::var_os("VERILATOR").map(PathBuf::from).unwrap_or_else(|| "verilator".into());
        let out = Command::new(&exe).arg("--version").output().ok().filter(|o| o.status.success())?;
        let version = String::from_utf8_lossy(&out.stdout).trim().to_string();
        let root = Command::new(&exe).args(["--getenv", "VERILATOR_ROOT"]).output().ok()?;
        let root = PathBuf::from(String::from_utf8_lossy(&root.stdout).trim());
        root.join("include/verilated.cpp").is_file().then_some(Verilator { exe, version, root })
    }

    /// `<root>/include`.
    pub fn include(&self) -> PathBuf {
        self.root.join("include")
    }
}

/// The names listed under the `+=` variables `vars` of a Verilator `_classes.mk`.
fn mk_list(mk: &str, vars: &[&str]) -> Vec<String> {
    let mut names = Vec::new();
    let mut active = false;
    for line in mk.lines() {
        let trimmed = line.trim();
        if let Some(var) = trimmed.strip_suffix("+= \\").or_else(|| trimmed.strip_suffix("+=")) {
            active = vars.contains(&var.trim());
            continue;
        }
        if !active {
            continue;
        }
        let name = trimmed.trim_end_matches('\\').trim();
        if !name.is_empty() {
            names.push(name.to_string());
        }
        if !trimmed.ends_with('\\') {
            active = false;
        }
    }
    names
}

/// Runs Verilator with `flags` ([`VERILATOR_FLAGS`], [`VERILATOR_FLAGS_FST`], ...) on `top` from
/// `verilog_files` into `obj`; returns the C++ classes to compile with the fast and with the slow
/// optimisation level (file stems under `obj`).
pub fn verilate_with(
    v: &Verilator,
    flags: &[&str],
    top: &str,
    verilog_files: &[PathBuf],
    obj: &Path,
) -> Result<(Vec<String>, Vec<String>), String> {
    let mut cmd = Command::new(&v.exe);
    cmd.args(flags)
        .arg("--top-module")
        .arg(top)
        .arg("--prefix")
        .arg(format!("V{top}"))
        .arg("--Mdir")
        .arg(obj)
        .args(verilog_files);
    let out = cmd.output().map_err(|e| format!("cannot run {}: {e}", v.exe.display()))?;
    if !out.status.success() {
        return Err(format!(
            "verilator failed on {top} ({:?}):\n{}{}",
            cmd,
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        ));
    }
    let classes = fs::read_to_string(obj.join(format!("V{top}_classes.mk")))
        .map_err(|e| format!("verilator wrote no V{top}_classes.mk: {e}"))?;
    let fast = mk_list(&classes, &["VM_CLASSES_FAST", "VM_SUPPORT_FAST"]);
    let slow = mk_list(&classes, &["VM_CLASSES_SLOW", "VM_SUPPORT_SLOW"]);
    if fast.is_empty() {
        return Err(format!("V{top}_classes.mk lists no classes"));
    }
    Ok((fast, slow))
}
