//! Running Verilator and compiling its C++ output (plus the shim) into static libraries.

use crate::shim::ShimTrace;
use crate::verilator::{
    verilate_with, Verilator, CPP_DEFINES, CPP_DEFINES_COVERAGE, CPP_DEFINES_FST, RUNTIME_SOURCES,
    RUNTIME_SOURCES_COVERAGE, RUNTIME_SOURCES_FST, VERILATOR_FLAGS, VERILATOR_FLAGS_COVERAGE,
    VERILATOR_FLAGS_COVERAGE_NO_TOGGLE, VERILATOR_FLAGS_FST,
};
use std::fs;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

/// C++ optimisation of the per-cycle code (the `Slow` files, run once at construction, use -O1).
pub const OPT_FAST: u32 = 3;
/// C++ optimisation of the construction-time (`Slow`) code.
pub const OPT_SLOW: u32 = 1;
/// Version of the way the runtime library is built (part of its cache key).
pub const RUNTIME_VERSION: u32 = 1;

/// The trace writer the static models are built with (`WAVES` at build time): Verilator flags,
/// C++ defines, runtime sources, extra link libraries, cache name suffix, shim writer.
pub struct Trace {
    /// Verilator flags (`--trace` or `--trace-fst`).
    pub flags: &'static [&'static str],
    /// Preprocessor definitions of every C++ file of the models and of the runtime.
    pub defines: &'static [(&'static str, &'static str)],
    /// The runtime sources under Verilator's `include/`.
    pub runtime: &'static [&'static str],
    /// Extra system libraries to link (`z` for the FST writer).
    pub libs: &'static [&'static str],
    /// Cache entry name suffix (`-fst`; none for VCD, whose entries keep their names and keys).
    pub suffix: &'static str,
    /// The shim's trace writer.
    pub shim: ShimTrace,
    /// Verilator coverage (`NEO_COVERAGE=1`): the shim writes the model's data when it is freed.
    pub coverage: bool,
}

impl Trace {
    /// `--trace`: `VerilatedVcdC` (the default).
    pub const VCD: Trace = Trace {
        flags: VERILATOR_FLAGS,
        defines: CPP_DEFINES,
        runtime: RUNTIME_SOURCES,
        libs: &[],
        suffix: "",
        shim: ShimTrace::Vcd,
        coverage: false,
    };
    /// `--trace-fst`: `VerilatedFstC` (GTKWave's FST writer; links zlib).
    pub const FST: Trace = Trace {
        flags: VERILATOR_FLAGS_FST,
        defines: CPP_DEFINES_FST,
        runtime: RUNTIME_SOURCES_FST,
        libs: &["z"],
        suffix: "-fst",
        shim: ShimTrace::Fst,
        coverage: false,
    };
    /// `--coverage` without tracing (`NEO_COVERAGE=1`; cache entries `<top>-cov-<hash>/`).
    pub const COVERAGE: Trace = Trace {
        flags: VERILATOR_FLAGS_COVERAGE,
        defines: CPP_DEFINES_COVERAGE,
        runtime: RUNTIME_SOURCES_COVERAGE,
        libs: &[],
        suffix: "-cov",
        shim: ShimTrace::Off,
        coverage: true,
    };
    /// [`Trace::COVERAGE`] without toggle coverage (line and user points only), for the tops of
    /// `build.rs`'s `NO_TOGGLE_COVERAGE`; the same runtime.
    pub const COVERAGE_NO_TOGGLE: Trace =
        Trace { flags: VERILATOR_FLAGS_COVERAGE_NO_TOGGLE, ..Trace::COVERAGE };

    /// True for the FST flavour.
    pub fn is_fst(&self) -> bool {
        self.suffix == Trace::FST.suffix
    }

    /// The cache key entry of a non-default flavour (`None` for VCD, so that its keys stay as
    /// they were).
    pub fn key(&self) -> Option<String> {
        let parts = format!("{:?} {:?} {:?} {:?}", self.flags, self.defines, self.runtime, self.libs);
        if self.coverage {
            Some(format!("{parts} coverage"))
        } else {
            self.is_fst().then_some(parts)
        }
    }
}

/// A C++ build with the flags Verilator's own makefile uses.
fn cpp_build(v: &Verilator, trace: &Trace, opt: u32, out_dir: &Path) -> cc::Build {
    let mut b = cc::Build::new();
    b.cpp(true)
        .opt_level(opt)
        .debug(false)
        .warnings(false)
        .cargo_metadata(false)
        .out_dir(out_dir)
        .std("gnu++17")
        .include(v.include())
        .include(v.include().join("vltstd"))
        .flag_if_supported("-faligned-new")
        .flag_if_supported("-fcf-protection=none");
    for (name, value) in trace.defines {
        b.define(name, *value);
    }
    b
}

/// A description of the C++ compiler (path and `--version`) for cache keys.
pub fn compiler_id() -> String {
    let tool = cc::Build::new().cpp(true).cargo_metadata(false).get_compiler();
    let version = Command::new(tool.path())
        .arg("--version")
        .output()
        .map(|o| String::from_utf8_lossy(&o.stdout).lines().next().unwrap_or("").to_string())
        .unwrap_or_default();
    // Path and version only: cc's default flags depend on the cargo profile, and the flags that
    // matter are fixed in `cpp_build` (and part of the key through the opt levels).
    format!("{} {}", tool.path().display(), version)
}

/// Compiles the Verilator runtime (`verilated.cpp`, `verilated_vcd_c.cpp` or
/// `verilated_fst_c.cpp`, `verilated_threads.cpp`) into `<dir>/libneo_verilated.a`.
pub fn build_runtime(v: &Verilator, trace: &Trace, dir: &Path) -> Result<(), String> {
    let mut b = cpp_build(v, trace, OPT_FAST, dir);
    for f in trace.runtime {
        b.file(v.include().join(f));
    }
    b.try_compile("neo_verilated").map_err(|e| format!("compiling the Verilator runtime: {e}"))?;
    remove_objects(dir);
    Ok(())
}

/// Verilates `top` from the files in `hdl_dir` into `<dir>/obj`, then compiles the model and the
/// shim (`shim_cpp`) into `<dir>/libneo_<top>_fast.a` and `<dir>/libneo_<top>_slow.a`.
pub fn build_model(
    v: &Verilator,
    trace: &Trace,
    top: &str,
    verilog_files: &[PathBuf],
    shim_cpp: &str,
    dir: &Path,
) -> Result<String, String> {
    let obj = dir.join("obj");
    let t0 = Instant::now();
    let (fast, slow) = verilate_with(v, trace.flags, top, verilog_files, &obj)?;
    let verilate_s = t0.elapsed().as_secs_f64();
    fs::write(dir.join("shim.cpp"), shim_cpp).map_err(|e| e.to_string())?;

    let t1 = Instant::now();
    let mut b = cpp_build(v, trace, OPT_FAST, dir);
    b.include(&obj);
    for c in &fast {
        b.file(obj.join(format!("{c}.cpp")));
    }
    b.file(dir.join("shim.cpp"));
    b.try_compile(&format!("neo_{top}_fast")).map_err(|e| format!("compiling {top}: {e}"))?;
    let mut b = cpp_build(v, trace, OPT_SLOW, dir);
    b.include(&obj);
    for c in &slow {
        b.file(obj.join(format!("{c}.cpp")));
    }
    if slow.is_empty() {
        // Keep the library set uniform: an empty translation unit.
        fs::write(dir.join("empty.cpp"), "// no slow classes\n").map_err(|e| e.to_string())?;
        b.file(dir.join("empty.cpp"));
    }
    b.try_compile(&format!("neo_{top}_slow")).map_err(|e| format!("compiling {top} (slow): {e}"))?;
    remove_objects(dir);
    Ok(format!(
        "verilate {verilate_s:.1} s, compile {:.1} s ({} fast + {} slow files)",
        t1.elapsed().as_secs_f64(),
        fast.len() + 1,
        slow.len()
    ))
}

/// Deletes the object files (`*.o`) cc left under `dir`; only the archives are kept.
fn remove_objects(dir: &Path) {
    let Ok(entries) = fs::read_dir(dir) else { return };
    for e in entries.flatten() {
        let p = e.path();
        if p.is_dir() && p.file_name().is_some_and(|n| n != "obj") {
            remove_objects(&p);
        } else if p.extension().is_some_and(|x| x == "o") {
            let _ = fs::remove_file(&p);
        }
    }
}
