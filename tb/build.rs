//! Builds a Verilated model of every Neo top (and of the harness's own test fixture), with a
//! generated `extern "C"` shim and a safe Rust wrapper per top (`neo_tb::models::*`).
//!
//! - The Verilog comes from `neo_gen::files_for` (the generator is a build-dependency). Each
//!   wrapper records its files' names and content hash (`build/hdl_hash.rs`): with
//!   `NEO_HDL_DIR=DIR` set when a test RUNS, a wrapper whose files in `DIR` differ runs a model
//!   of them built at run time instead (`neo_tb::hdl_dir`; mutation testing), so `NEO_HDL_DIR`
//!   does not touch the build.
//! - Verilator output and the compiled static libraries are cached in
//!   `$NEO_CACHE_DIR` or `<target>/neo-verilator-cache/<top>-<hash>/`, keyed by the Verilog text,
//!   the flags, `verilator --version`, the C++ compiler and the shim generator version.
//! - The models trace VCD (`--trace`), or FST (`--trace-fst`, `VerilatedFstC`, linked with zlib)
//!   when `WAVES=fst` is set for the build; the FST builds are cache entries of their own
//!   (`<top>-fst-<hash>/`, `runtime-fst-<hash>/`), and `NEO_TB_MODEL_WAVES` (`vcd` or `fst`) tells
//!   `neo_tb::waves` which the models write. A `WAVES` value that is not a waveform choice fails
//!   the build, naming the accepted values.
//! - With `NEO_COVERAGE=1` the models are built for Verilator coverage instead (`--coverage`,
//!   untraced; cache entries `<top>-cov-<hash>/`, `runtime-cov-<hash>/`): dropping a model
//!   writes its counts (`neo_tb::coverage`). `NEO_TB_COVERAGE` (`0` or `1`) tells the crate.
//! - Without Verilator the crate builds without models (no `neo_has_verilator` cfg) and the
//!   cosimulation tests skip; with `CI` set that is an error instead.

#[path = "build/cache.rs"]
mod cache;
#[path = "build/coverage_env.rs"]
mod coverage_env;
#[path = "build/hdl_hash.rs"]
mod hdl_hash;
#[path = "build/shim.rs"]
mod shim;
#[path = "build/verilate.rs"]
mod verilate;
#[path = "build/verilator.rs"]
mod verilator;
#[path = "build/waves_env.rs"]
mod waves_env;

use neo_gen::interface::ModuleInterface;
use std::fmt::Write as _;
use std::fs;
use std::path::{Path, PathBuf};

/// One model to build: its interface and its Verilog files (file name, text), plus an optional
/// Verilator configuration file (lint waivers) passed before them.
struct Unit {
    iface: ModuleInterface,
    files: Vec<(String, String)>,
    vlt: Option<String>,
    /// For generated tops: the file names and their hash, which the wrapper compares with
    /// `$NEO_HDL_DIR`'s at run time (none for the fixtures).
    hdl: Option<shim::HdlFiles>,
}

/// A cache entry (its directory, and whether it was already there) or the build error.
type Built = Result<(PathBuf, bool), String>;

/// Tops whose coverage model counts lines and cover points but not toggles: with toggle
/// coverage the raster core's C++ is over ten times larger (316 files instead of 28; most of an
/// hour to compile on two shared cores). Its SCU and ITU get toggle coverage in their own benches.
const NO_TOGGLE_COVERAGE: &[&str] = &["neo_raster_core"];

const FIXTURE_DIR: &str = "tests/fixtures";
const FIXTURES: &[&str] = &["neo_tb_adder"];

fn main() {
    println!("cargo::rustc-check-cfg=cfg(neo_has_verilator)");
    println!("cargo::rerun-if-changed=build.rs");
    println!("cargo::rerun-if-changed=build");
    println!("cargo::rerun-if-changed={FIXTURE_DIR}");
    for var in ["NEO_CACHE_DIR", "NEO_CONFIG", "CI", "VERILATOR", "WAVES", "NEO_COVERAGE"] {
        println!("cargo::rerun-if-env-changed={var}");
    }
    let out_dir = PathBuf::from(std::env::var_os("OUT_DIR").expect("OUT_DIR"));
    let target = cache::target_dir(&out_dir);
    println!("cargo::rustc-env=NEO_TB_TARGET_DIR={}", target.display());
    let trace = match trace_flavour() {
        Ok(t) => t,
        Err(e) => panic!("neo-tb build failed:\n{e}"),
    };
    println!("cargo::rustc-env=NEO_TB_MODEL_WAVES={}", if trace.is_fst() { "fst" } else { "vcd" });
    println!("cargo::rustc-env=NEO_TB_COVERAGE={}", u8::from(trace.coverage));
    if let Err(e) = run(&out_dir, &trace) {
        panic!("neo-tb build failed:\n{e}");
    }
}

/// The flavour of the static models: coverage (untraced) when `NEO_COVERAGE=1` at build time,
/// else the trace writer: FST when `WAVES=fst`, else VCD.
fn trace_flavour() -> Result<verilate::Trace, String> {
    let waves = std::env::var("WAVES").unwrap_or_default();
    let wave = waves_env::parse_waves(&waves)?;
    if coverage_env::parse_coverage(&std::env::var("NEO_COVERAGE").unwrap_or_default())? {
        if wave.is_some() {
            return Err(format!("NEO_COVERAGE=1 builds untraced models: unset WAVES (WAVES={waves})"));
        }
        return Ok(verilate::Trace::COVERAGE);
    }
    Ok(match wave {
        Some("fst") => verilate::Trace::FST,
        _ => verilate::Trace::VCD,
    })
}

fn run(out_dir: &Path, trace: &verilate::Trace) -> Result<(), String> {
    let mut units = fixture_units()?;
    let cfg = engine_config(out_dir)?;
    units.extend(gen_units(&cfg)?);

    let models_rs = out_dir.join("models.rs");
    let Some(v) = verilator::Verilator::find() else {
        // The rule of `neo_golden::shared::ci` (a build script cannot call it): `CI` set.
        let ci = std::env::var_os("CI").is_some();
        if ci {
            return Err("verilator not found (CI is set, so the cosimulation models are required): \
                        install it (scripts/setup does, with apt-get) or set VERILATOR=/path"
                .into());
        }
        println!(
            "cargo::warning=neo-tb: verilator not found; building without models (cosim tests will skip)"
        );
        // Re-check on every build until it is installed.
        println!("cargo::rerun-if-changed=/usr/bin/verilator");
        fs::write(&models_rs, "// verilator not found at build time: no models\n")
            .map_err(|e| e.to_string())?;
        return Ok(());
    };

    let root = cache::root(out_dir);
    let compiler = verilate::compiler_id();

    // The runtime library (shared by all models) and every model, built in parallel threads on a
    // cache miss (the compilers are the bottleneck; cc also limits itself through the jobserver).
    let (runtime, built): (Built, Vec<Built>) = std::thread::scope(|s| {
        let rt = s.spawn(|| build_runtime(&v, trace, &root, &compiler));
        let models: Vec<_> =
            units.iter().map(|u| s.spawn(|| build_unit(&v, trace, &root, &compiler, u))).collect();
        let join = |h: std::thread::ScopedJoinHandle<'_, Built>| {
            h.join().unwrap_or_else(|_| Err("a build thread panicked".into()))
        };
        (join(rt), models.into_iter().map(join).collect())
    });
    let (rt_dir, hit) = runtime?;
    if !hit {
        println!("cargo::warning=neo-tb: built the Verilator runtime into {}", rt_dir.display());
    }

    let mut rust = String::from("// Generated by neo-tb/build.rs: one wrapper per Verilated top.\n\n");
    let mut names = Vec::new();
    let mut link = Vec::new();
    for (u, result) in units.iter().zip(built) {
        let (dir, hit) = result?;
        let top = &u.iface.name;
        if !hit {
            let log = fs::read_to_string(dir.join("build.log")).unwrap_or_default();
            println!("cargo::warning=neo-tb: built {}", log.trim());
        }
        let wrapper = shim::rust(&u.iface, trace.coverage, u.hdl.as_ref());
        fs::write(dir.join("wrapper.rs"), &wrapper).map_err(|e| e.to_string())?;
        rust.push_str(&wrapper);
        names.push(top.clone());
        link.push((dir, top.clone()));
    }
    let _ = writeln!(
        rust,
        "/// Every Verilated top in this build, by module name.\npub const TOPS: &[&str] = &{names:?};"
    );
    fs::write(&models_rs, rust).map_err(|e| e.to_string())?;

    for (dir, top) in &link {
        println!("cargo::rustc-link-search=native={}", dir.display());
        println!("cargo::rustc-link-lib=static=neo_{top}_fast");
        println!("cargo::rustc-link-lib=static=neo_{top}_slow");
    }
    println!("cargo::rustc-link-search=native={}", rt_dir.display());
    println!("cargo::rustc-link-lib=static=neo_verilated");
    for lib in trace.libs {
        println!("cargo::rustc-link-lib=dylib={lib}");
    }
    println!("cargo::rustc-link-lib=dylib=stdc++");
    println!("cargo::rustc-cfg=neo_has_verilator");
    Ok(())
}

/// The Verilator runtime library (with `trace`'s writer) from the cache, built on a miss.
fn build_runtime(v: &verilator::Verilator, trace: &verilate::Trace, root: &Path, compiler: &str) -> Built {
    let mut key = cache::Key::new();
    key.add("runtime", verilate::RUNTIME_VERSION.to_string().as_bytes());
    key.add("verilator", v.version.as_bytes());
    key.add("root", v.root.to_string_lossy().as_bytes());
    key.add("compiler", compiler.as_bytes());
    key.add("opt", verilate::OPT_FAST.to_string().as_bytes());
    if let Some(k) = trace.key() {
        key.add("trace", k.as_bytes());
    }
    let name = format!("runtime{}", trace.suffix);
    cache::get_or_build(root, &name, &key, "libneo_verilated.a", |d| verilate::build_runtime(v, trace, d))
}

/// One model's libraries (traced with `trace`'s writer) from the cache, built (Verilator, then
/// the C++ and the shim) on a miss.
fn build_unit(
    v: &verilator::Verilator,
    trace: &verilate::Trace,
    root: &Path,
    compiler: &str,
    u: &Unit,
) -> Result<(PathBuf, bool), String> {
    shim::validate(&u.iface)?;
    let top = &u.iface.name;
    let trace = if trace.coverage && NO_TOGGLE_COVERAGE.contains(&top.as_str()) {
        &verilate::Trace::COVERAGE_NO_TOGGLE
    } else {
        trace
    };
    let mut cpp = shim::cpp_traced(&u.iface, trace.shim);
    if trace.coverage {
        shim::cpp_coverage(&mut cpp, &u.iface);
    }
    let mut key = cache::Key::new();
    key.add("top", top.as_bytes());
    for (name, text) in &u.files {
        key.add(&format!("file {name}"), hdl_hash::without_header(text).as_bytes());
    }
    if let Some(vlt) = &u.vlt {
        key.add("lint.vlt", vlt.as_bytes());
    }
    key.add("flags", trace.flags.join(" ").as_bytes());
    if let Some(k) = trace.key() {
        // Only for FST and coverage, so that the VCD models' keys (and cache entries) stay as they were.
        key.add("trace", k.as_bytes());
    }
    key.add("verilator", v.version.as_bytes());
    key.add("compiler", compiler.as_bytes());
    key.add("opt", format!("{} {}", verilate::OPT_FAST, verilate::OPT_SLOW).as_bytes());
    key.add("shim", shim::SHIM_VERSION.to_string().as_bytes());
    key.add("shim.cpp", cpp.as_bytes());
    let ready = format!("libneo_{top}_slow.a");
    let name = format!("{top}{}", trace.suffix);
    cache::get_or_build(root, &name, &key, &ready, |d| {
        let hdl = d.join("hdl");
        fs::create_dir_all(&hdl).map_err(|e| e.to_string())?;
        let mut paths = Vec::new();
        if let Some(vlt) = &u.vlt {
            let p = hdl.join("lint.vlt");
            fs::write(&p, vlt).map_err(|e| format!("{}: {e}", p.display()))?;
            paths.push(p);
        }
        for (name, text) in &u.files {
            let p = hdl.join(name);
            fs::write(&p, text).map_err(|e| format!("{}: {e}", p.display()))?;
            paths.push(p);
        }
        let t = std::time::Instant::now();
        let log = verilate::build_model(v, trace, top, &paths, &cpp, d)?;
        let log = format!("{top}: {log}, total {:.1} s\n", t.elapsed().as_secs_f64());
        fs::write(d.join("build.log"), &log).map_err(|e| e.to_string())
    })
}

/// The harness's own test modules: `tests/fixtures/NAME.v` described by `NAME.json`.
fn fixture_units() -> Result<Vec<Unit>, String> {
    FIXTURES
        .iter()
        .map(|name| {
            let dir = Path::new(FIXTURE_DIR);
            let json = fs::read_to_string(dir.join(format!("{name}.json"))).map_err(|e| e.to_string())?;
            let iface: ModuleInterface =
                serde_json::from_str(&json).map_err(|e| format!("{FIXTURE_DIR}/{name}.json: {e}"))?;
            let file = format!("{name}.v");
            let text = fs::read_to_string(dir.join(&file)).map_err(|e| e.to_string())?;
            Ok(Unit { iface, files: vec![(file, text)], vlt: None, hdl: None })
        })
        .collect()
}

/// The engine configuration to build the models of: the JSON file named by `NEO_CONFIG` (the
/// format `neo gen --config` reads), else the default. Written to `OUT_DIR/engine_config.json`,
/// which `neo_tb::config` reads back, so the benches check the configuration that was built.
fn engine_config(out_dir: &Path) -> Result<neo_gen::EngineConfig, String> {
    let cfg = match std::env::var_os("NEO_CONFIG").filter(|p| !p.is_empty()) {
        Some(p) => {
            println!("cargo::rerun-if-changed={}", Path::new(&p).display());
            neo_gen::EngineConfig::from_json_file(Path::new(&p)).map_err(|e| format!("NEO_CONFIG: {e}"))?
        }
        None => neo_gen::EngineConfig::default(),
    };
    let json = serde_json::to_string_pretty(&cfg).map_err(|e| e.to_string())?;
    fs::write(out_dir.join("engine_config.json"), json).map_err(|e| format!("engine_config.json: {e}"))?;
    Ok(cfg)
}

/// The Neo tops from the generator, with their Verilog and the lint waivers (`hdl/lint.vlt`).
fn gen_units(cfg: &neo_gen::EngineConfig) -> Result<Vec<Unit>, String> {
    let vlt_path = PathBuf::from("../hdl/lint.vlt");
    println!("cargo::rerun-if-changed={}", vlt_path.display());
    let vlt = fs::read_to_string(&vlt_path).ok();
    let mut units = Vec::new();
    for iface in neo_gen::tops(cfg) {
        let files: Vec<(String, String)> = neo_gen::files_for(cfg, &iface.name)
            .into_iter()
            .map(|f| {
                let name = if f.name.ends_with(".v") || f.name.ends_with(".sv") {
                    f.name
                } else {
                    format!("{}.v", f.name)
                };
                (name, f.text)
            })
            .collect();
        let hdl = shim::HdlFiles {
            names: files.iter().map(|(n, _)| n.clone()).collect(),
            hash: hdl_hash::verilog_hash(files.iter().map(|(n, t)| (n.as_str(), t.as_str()))),
        };
        units.push(Unit { iface, files, vlt: vlt.clone(), hdl: Some(hdl) });
    }
    Ok(units)
}
