//! Verilated models built at run time: for tops whose configuration is only known when the
//! program runs (`neo cosim --config`, the engine benches), and for tops too large to build with
//! every `cargo build` (the full engine).
//!
//! [`DynModel::build`] verilates a top with the same flags and shim as `build.rs`, compiles it
//! with the Verilator runtime into one shared library, caches it by content hash beside the
//! static models (`$NEO_CACHE_DIR` or `<target>/neo-verilator-cache/dyn-<top>-<hash>/`) and
//! loads it. Ports are bound by index through the shim's `neo_T_set_port` / `neo_T_get_port`.
//!
//! A model is traced as VCD (`--trace`, as the static models; [`DynModel::build`]) or, built with
//! [`DynModel::build_traced`], as FST (`--trace-fst`, the FST writer and `-lz`) or not at all
//! (no `--trace`: about half the C++ to compile, for runs that write no waves); each is its own
//! cache entry (`dyn-<top>-<hash>`, `dyn-<top>-fst-<hash>`, `dyn-<top>-untraced-<hash>`).
//! With `NEO_COVERAGE=1` in the process every model is built for Verilator coverage instead
//! (`--coverage`, untraced: `dyn-<top>-cov-<hash>`) and writes its counts when it is dropped
//! ([`crate::coverage`]).

#[allow(dead_code)]
#[path = "../build/cache.rs"]
mod cache;
#[allow(dead_code)]
#[path = "../build/shim.rs"]
mod shim;
#[allow(dead_code)]
#[path = "../build/verilator.rs"]
mod verilator;

use crate::waves::WaveFormat;
use neo_gen::interface::{Dir, ModuleInterface};
use std::ffi::{c_char, c_int, c_void, CString};
use std::fs;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

/// Part of the error of a model that does not build (Verilator or the C++ compiler failed):
/// `scripts/mutate-check` reports a mutant whose log holds it as one that does not build.
pub const MODEL_DOES_NOT_BUILD: &str = "the Verilated model does not build";

/// Version of the way shared libraries are compiled (part of the cache key).
const DYN_VERSION: u32 = 1;
/// C++ optimisation of the per-cycle code.
const OPT_FAST: &str = "-O3";
/// C++ optimisation of the construction-time code.
const OPT_SLOW: &str = "-O1";
/// C++ optimisation of the construction-time code (Verilator's `__Slow` files: constructor,
/// reset values, initial and settle evaluation, run once per model) of a model built for short
/// runs: 44% of the CI engine's C++, 47 CPU s at `-O1`, 13 s at `-O0`.
const OPT_QUICK_SLOW: &str = "-O0";
/// C++ optimisation of the per-cycle code of a model built for short runs
/// ([`DynModel::build_for_short_runs`]): large datapaths whose benches simulate seconds compile
/// in about half the time. `NEO_TB_QUICK_OPT` overrides it ([`quick_opt`]).
const OPT_QUICK: &str = "-O1";

/// The optimisation of the construction-time code of a model whose per-cycle code is at
/// `opt_fast`: [`OPT_SLOW`] beside [`OPT_FAST`], else (a model built for short runs)
/// [`OPT_QUICK_SLOW`]. Part of the cache key.
fn slow_opt(opt_fast: &str) -> &'static str {
    if opt_fast == OPT_FAST {
        OPT_SLOW
    } else {
        OPT_QUICK_SLOW
    }
}

/// The optimisation of the models built for short runs: `$NEO_TB_QUICK_OPT` (`-O0` to `-O3`,
/// `-Og`, `-Os`; `scripts/mutate-check` sets `-O0`: its mutants' models run until their first
/// mismatch, so their compile time is what counts), else [`OPT_QUICK`]. Part of the cache key.
fn quick_opt() -> Result<&'static str, String> {
    match std::env::var("NEO_TB_QUICK_OPT") {
        Err(_) => Ok(OPT_QUICK),
        Ok(v) if v.is_empty() => Ok(OPT_QUICK),
        Ok(v) => ["-O0", "-O1", "-O2", "-O3", "-Og", "-Os"]
            .into_iter()
            .find(|o| *o == v)
            .ok_or_else(|| format!("NEO_TB_QUICK_OPT: '{v}' is not one of -O0, -O1, -O2, -O3, -Og, -Os")),
    }
}

/// What a build did: where the library is, whether it came from the cache, how long it took.
#[derive(Clone, Debug)]
pub struct BuildInfo {
    /// The shared library.
    pub library: PathBuf,
    /// True when it was already in the cache.
    pub cached: bool,
    /// Wall time of the build (or of the cache look-up), in seconds.
    pub seconds: f64,
    /// The build log line (Verilator and compile times), empty on a cache hit.
    pub log: String,
}

type NewFn = unsafe extern "C" fn(u32, u32) -> *mut c_void;
type PtrFn = unsafe extern "C" fn(*mut c_void);
type SetFn = unsafe extern "C" fn(*mut c_void, usize, *const u32, usize);
type GetFn = unsafe extern "C" fn(*mut c_void, usize, *mut u32, usize);
type OpenFn = unsafe extern "C" fn(*mut c_void, *const c_char) -> c_int;
type DumpFn = unsafe extern "C" fn(*mut c_void, u64);
type CoverageFn = unsafe extern "C" fn(*mut c_void, *const c_char);

/// The entry points of a loaded library.
struct Api {
    new: NewFn,
    free: PtrFn,
    eval: PtrFn,
    set: SetFn,
    get: GetFn,
    trace_open: OpenFn,
    trace_dump: DumpFn,
    trace_close: PtrFn,
    /// Present in coverage models only.
    coverage_write: Option<CoverageFn>,
}

/// A Verilated model loaded from a shared library; the same operations as [`crate::dut::Dut`],
/// with the port table known at run time.
pub struct DynModel {
    api: Api,
    raw: *mut c_void,
    iface: ModuleInterface,
    clk: Option<usize>,
    rst: Option<usize>,
    cycle: u64,
    time: u64,
    tracing: bool,
    /// Coverage models: the toggle baseline's file (`crate::coverage::write_baseline`).
    cov_base: Option<PathBuf>,
    format: Option<WaveFormat>,
    // Kept last: dropped after `raw` is freed.
    _lib: libloading::Library,
}

// SAFETY: the model and its VerilatedContext are owned by this value alone, and `&mut self`
// serialises every call (as for the static models).
unsafe impl Send for DynModel {}

/// The lint waivers every generated model is verilated with.
pub const LINT_VLT: &str = include_str!("../../hdl/lint.vlt");

/// The interface of generated top `top` for `cfg` (an error when the generator emits none).
pub fn generated_interface(cfg: &neo_gen::EngineConfig, top: &str) -> Result<ModuleInterface, String> {
    neo_gen::units::modules(cfg)
        .map_err(|e| e.to_string())?
        .into_iter()
        .find(|m| m.name == top)
        .map(|m| m.interface())
        .ok_or(format!("the generator emits no {top}"))
}

/// The files of generated top `top` for `cfg` (itself and every module it instantiates) and
/// the lint waivers, for [`DynModel::build`]. With `$NEO_HDL_DIR` set, each of its files there
/// generated from `cfg` (its header names the configuration's hash) replaces the generated one
/// and is listed as read ([`crate::hdl_dir::note_read`]), and `DIR/lint.vlt` replaces the
/// waivers (`scripts/mutate-check` runs the benches on mutated copies of `hdl/`). A file
/// generated from another configuration is left alone: a directory holds one configuration's
/// `hdl/` (plus, for `scripts/mutate-check`'s engine mutants, another's top), and the benches
/// build tops of other configurations too.
pub fn generated_files(
    cfg: &neo_gen::EngineConfig,
    top: &str,
) -> Result<(Vec<(String, String)>, String), String> {
    cfg.validate().map_err(|e| e.to_string())?;
    let mut files: Vec<(String, String)> =
        neo_gen::files_for(cfg, top).into_iter().map(|f| (f.file_name(), f.text)).collect();
    let mut vlt = LINT_VLT.to_string();
    if let Some(dir) = crate::hdl_dir::dir() {
        let header = format!("config 0x{:016x}", cfg.hash());
        let mut read = Vec::new();
        for (name, text) in &mut files {
            let theirs = std::fs::read_to_string(dir.join(&*name)).ok();
            if let Some(t) = theirs.filter(|t| t.lines().next().is_some_and(|h| h.contains(&header))) {
                *text = t;
                read.push(name.clone());
            }
        }
        if !read.is_empty() {
            crate::hdl_dir::note_read(&dir, read.iter().map(String::as_str));
            vlt = std::fs::read_to_string(dir.join("lint.vlt")).unwrap_or(vlt);
        }
    }
    Ok((files, vlt))
}

impl DynModel {
    /// Builds (or finds in the cache) and loads the model of `iface.name` from `files` (file
    /// name, Verilog text) and the optional lint waivers `vlt`.
    /// The model is VCD-traced.
    pub fn build(
        iface: &ModuleInterface,
        files: &[(String, String)],
        vlt: Option<&str>,
    ) -> Result<(DynModel, BuildInfo), String> {
        Self::build_traced(iface, files, vlt, Some(WaveFormat::Vcd))
    }

    /// [`DynModel::build`] with the trace writer of `format`, or without tracing (`None`); each
    /// is a separate build and cache entry.
    pub fn build_traced(
        iface: &ModuleInterface,
        files: &[(String, String)],
        vlt: Option<&str>,
        format: Option<WaveFormat>,
    ) -> Result<(DynModel, BuildInfo), String> {
        Self::build_threaded(iface, files, vlt, format, 1)
    }

    /// [`DynModel::build_traced`] verilated with `--threads threads` (Verilator's multithreaded
    /// model: the evaluation is split into tasks run on `threads` threads); `threads` is part of
    /// the cache key and name (`dyn-<top>[-fst|-untraced]-t<threads>-<hash>`), except 1 (the
    /// default single-threaded model, whose key and name are unchanged). The model's
    /// `VerilatedContext` takes `std::thread::hardware_concurrency()` threads, so `threads`
    /// must not exceed the machine's cores (Verilator refuses the model when it is created).
    pub fn build_threaded(
        iface: &ModuleInterface,
        files: &[(String, String)],
        vlt: Option<&str>,
        format: Option<WaveFormat>,
        threads: usize,
    ) -> Result<(DynModel, BuildInfo), String> {
        if threads == 0 {
            return Err(format!("{}: threads must be at least 1", iface.name));
        }
        let flavour = Flavour::for_run(format);
        let info = build_library(iface, files, vlt, &flavour, threads, OPT_FAST)?;
        let model = DynModel::load(iface, &info.library, flavour.trace)?;
        Ok((model, info))
    }

    /// [`DynModel::build_traced`] with the per-cycle code compiled for build time rather than
    /// speed (`-O1`, the construction-time code at `-O0`, the generated files compiled as one
    /// unity translation unit per core and level: `unity_units`; its own cache entry): for the
    /// preprocessing datapaths, whose C++ takes
    /// minutes at `-O3` and whose benches run seconds, the other configurations' unit models and
    /// the models of `$NEO_HDL_DIR`'s Verilog ([`crate::hdl_dir`]).
    pub fn build_for_short_runs(
        iface: &ModuleInterface,
        files: &[(String, String)],
        vlt: Option<&str>,
        format: Option<WaveFormat>,
    ) -> Result<(DynModel, BuildInfo), String> {
        let flavour = Flavour::for_run(format);
        let info = build_library(iface, files, vlt, &flavour, 1, quick_opt()?)?;
        let model = DynModel::load(iface, &info.library, flavour.trace)?;
        Ok((model, info))
    }

    /// Loads a library built by [`DynModel::build_traced`] for `iface` with `format`.
    pub fn load(
        iface: &ModuleInterface,
        library: &Path,
        format: Option<WaveFormat>,
    ) -> Result<DynModel, String> {
        let t = &iface.name;
        // SAFETY: the library is one of ours (built from the shim); loading runs Verilator's
        // static constructors only.
        let lib = unsafe { libloading::Library::new(library) }
            .map_err(|e| format!("cannot load {}: {e}", library.display()))?;
        macro_rules! sym {
            ($name:expr, $ty:ty) => {{
                let name = format!("neo_{t}_{}\0", $name);
                // SAFETY: the symbol has this signature in the generated shim.
                let s: libloading::Symbol<$ty> = unsafe { lib.get(name.as_bytes()) }.map_err(|e| {
                    format!("{}: no symbol {}: {e}", library.display(), name.trim_end_matches('\0'))
                })?;
                *s
            }};
        }
        let api = Api {
            new: sym!("new", NewFn),
            free: sym!("free", PtrFn),
            eval: sym!("eval", PtrFn),
            set: sym!("set_port", SetFn),
            get: sym!("get_port", GetFn),
            trace_open: sym!("trace_open", OpenFn),
            trace_dump: sym!("trace_dump", DumpFn),
            trace_close: sym!("trace_close", PtrFn),
            coverage_write: {
                let name = format!("neo_{t}_coverage_write\0");
                // SAFETY: when present, the symbol has this signature in the generated shim.
                unsafe { lib.get::<CoverageFn>(name.as_bytes()) }.ok().map(|s| *s)
            },
        };
        // SAFETY: plain constructor; a null return is checked. The initial values come from the
        // bench seed (`crate::xinit`).
        let raw = crate::xinit::construct(t, |mode, seed| unsafe { (api.new)(mode, seed) });
        if raw.is_null() {
            return Err(format!("{t}: model allocation failed"));
        }
        let find = |n: &str| iface.ports.iter().position(|p| p.name == n && p.dir == Dir::In);
        let (clk, rst) = (find("clk_i"), find("rst_ni"));
        let iface = iface.clone();
        let mut m = DynModel {
            api,
            raw,
            iface,
            clk,
            rst,
            cycle: 0,
            time: 0,
            tracing: false,
            cov_base: None,
            format,
            _lib: lib,
        };
        m.set_bit(clk, false);
        m.set_bit(rst, true);
        m.eval();
        if m.rst.is_none() {
            // No reset: the baseline is the first evaluation's.
            m.coverage_baseline();
        }
        Ok(m)
    }

    /// Coverage models: writes the toggle baseline once (`crate::coverage::write_baseline`).
    fn coverage_baseline(&mut self) {
        if let (Some(write), None) = (self.api.coverage_write, &self.cov_base) {
            // SAFETY: `raw` is live; `path` outlives the call.
            self.cov_base = Some(crate::coverage::write_baseline(&self.iface.name, |path| unsafe {
                write(self.raw, path.as_ptr())
            }));
        }
    }

    /// Index of the port called `name`, or an error naming the module and the port.
    pub fn port(&self, name: &str) -> Result<usize, String> {
        let i = &self.iface;
        i.ports.iter().position(|p| p.name == name).ok_or_else(|| format!("{} has no port {name}", i.name))
    }

    /// The model's interface (its ports in index order).
    pub fn interface(&self) -> &ModuleInterface {
        &self.iface
    }

    /// Drives input `port` with little-endian words.
    #[inline]
    pub fn set_words(&mut self, port: usize, words: &[u32]) {
        // SAFETY: `raw` is live; the shim reads at most `words.len()` words.
        unsafe { (self.api.set)(self.raw, port, words.as_ptr(), words.len()) }
    }

    /// Reads `port` into `out` (at most `out.len()` words).
    #[inline]
    pub fn get_words(&self, port: usize, out: &mut [u32]) {
        // SAFETY: `raw` is live; the shim writes at most `out.len()` words.
        unsafe { (self.api.get)(self.raw, port, out.as_mut_ptr(), out.len()) }
    }

    /// Drives a port of at most 64 bits.
    #[inline]
    pub fn set_u64(&mut self, port: usize, v: u64) {
        self.set_words(port, &[v as u32, (v >> 32) as u32]);
    }

    /// Reads a port of at most 64 bits.
    #[inline]
    pub fn get_u64(&self, port: usize) -> u64 {
        let mut w = [0u32; 2];
        self.get_words(port, &mut w);
        w[0] as u64 | (w[1] as u64) << 32
    }

    fn set_bit(&mut self, port: Option<usize>, v: bool) {
        if let Some(p) = port {
            self.set_u64(p, v as u64);
        }
    }

    /// Settles combinational logic.
    #[inline]
    pub fn eval(&mut self) {
        // SAFETY: `raw` is live.
        unsafe { (self.api.eval)(self.raw) }
    }

    fn dump(&mut self) {
        if self.tracing {
            // SAFETY: `raw` is live.
            unsafe { (self.api.trace_dump)(self.raw, self.time) }
        }
    }

    /// One clock cycle, as the static wrappers' `tick`: clock low, eval, dump; clock high, eval,
    /// dump (10 time units a cycle).
    pub fn tick(&mut self) {
        self.set_bit(self.clk, false);
        self.eval();
        self.dump();
        self.time += 5;
        self.set_bit(self.clk, true);
        self.eval();
        self.dump();
        self.time += 5;
        self.cycle += 1;
    }

    /// Asserts the reset for four cycles, releases it and restarts [`DynModel::cycle`] at zero.
    pub fn reset(&mut self) {
        self.set_bit(self.rst, true);
        self.eval();
        self.set_bit(self.rst, false);
        self.eval();
        for _ in 0..4 {
            self.tick();
        }
        self.set_bit(self.rst, true);
        self.set_bit(self.clk, false);
        self.eval();
        self.cycle = 0;
        self.coverage_baseline();
    }

    /// Rising edges since the last reset.
    pub fn cycle(&self) -> u64 {
        self.cycle
    }

    /// The format the model traces in (`None`: built without tracing).
    pub fn wave_format(&self) -> Option<WaveFormat> {
        self.format
    }

    /// Starts a trace at `path` (every later half cycle is dumped). Its extension must name the
    /// model's format ([`WaveFormat::of_path`]: `.fst` for an FST-traced model, anything else
    /// for a VCD-traced one).
    pub fn trace_open(&mut self, path: &Path) -> std::io::Result<()> {
        let wanted = WaveFormat::of_path(path);
        if Some(wanted) != self.format {
            let built = self.format.map_or("nothing".to_string(), |f| f.extension().to_uppercase());
            return Err(std::io::Error::new(
                std::io::ErrorKind::InvalidInput,
                format!(
                    "{}: a {} file, but the {} model was built to trace {built} (build it with that format)",
                    path.display(),
                    wanted.extension().to_uppercase(),
                    self.iface.name,
                ),
            ));
        }
        let c = CString::new(path.as_os_str().to_string_lossy().as_bytes())
            .map_err(|e| std::io::Error::new(std::io::ErrorKind::InvalidInput, e))?;
        // SAFETY: `raw` is live; `c` outlives the call.
        if unsafe { (self.api.trace_open)(self.raw, c.as_ptr()) } == 0 {
            return Err(std::io::Error::other(format!(
                "cannot open {} {}",
                wanted.extension().to_uppercase(),
                path.display()
            )));
        }
        self.tracing = true;
        Ok(())
    }

    /// Flushes and closes the trace, if one is open.
    pub fn trace_close(&mut self) {
        if self.tracing {
            // SAFETY: `raw` is live.
            unsafe { (self.api.trace_close)(self.raw) };
            self.tracing = false;
        }
    }
}

impl Drop for DynModel {
    fn drop(&mut self) {
        if let Some(write) = self.api.coverage_write {
            // SAFETY: `raw` is live; `path` outlives the call.
            crate::coverage::write_model(&self.iface.name, self.cov_base.as_deref(), |path| unsafe {
                write(self.raw, path.as_ptr())
            });
        }
        // SAFETY: `raw` came from `new` and is freed once, before the library is unloaded.
        unsafe { (self.api.free)(self.raw) }
    }
}

/// The cache root: `$NEO_CACHE_DIR`, else `<target>/neo-verilator-cache` (as `build.rs`).
fn cache_root() -> PathBuf {
    match std::env::var_os("NEO_CACHE_DIR").filter(|d| !d.is_empty()) {
        Some(d) => PathBuf::from(d),
        None => PathBuf::from(env!("NEO_TB_TARGET_DIR")).join("neo-verilator-cache"),
    }
}

/// The C++ compiler: `$CXX`, else `c++`.
fn cxx() -> String {
    std::env::var("CXX").ok().filter(|c| !c.is_empty()).unwrap_or_else(|| "c++".into())
}

/// `cxx --version`'s first line (part of the cache key).
fn cxx_version(cxx: &str) -> String {
    Command::new(cxx)
        .arg("--version")
        .output()
        .map(|o| String::from_utf8_lossy(&o.stdout).lines().next().unwrap_or("").to_string())
        .unwrap_or_default()
}

/// The trace-dependent parts of a build: the shim's trace writer, Verilator flags, C++ defines,
/// runtime sources, extra link libraries, cache name suffix, coverage.
struct Flavour {
    /// The trace format the model is built with (`None`: untraced; coverage models are untraced).
    trace: Option<WaveFormat>,
    coverage: bool,
    shim: shim::ShimTrace,
    flags: &'static [&'static str],
    defines: &'static [(&'static str, &'static str)],
    runtime: &'static [&'static str],
    libs: &'static [&'static str],
    suffix: &'static str,
}

impl Flavour {
    /// The coverage model (`--coverage`, untraced).
    fn coverage() -> Flavour {
        Flavour {
            trace: None,
            coverage: true,
            shim: shim::ShimTrace::Off,
            flags: verilator::VERILATOR_FLAGS_COVERAGE,
            defines: verilator::CPP_DEFINES_COVERAGE,
            runtime: verilator::RUNTIME_SOURCES_COVERAGE,
            libs: &[],
            suffix: "-cov",
        }
    }

    /// The coverage model in coverage mode ([`crate::coverage::at_run_time`]), else the model
    /// traced as `format`: the one place that decides what a run builds.
    fn for_run(format: Option<WaveFormat>) -> Flavour {
        if crate::coverage::at_run_time() {
            Flavour::coverage()
        } else {
            Flavour::of(format)
        }
    }

    fn of(format: Option<WaveFormat>) -> Flavour {
        match format {
            None => Flavour {
                trace: format,
                coverage: false,
                shim: shim::ShimTrace::Off,
                flags: verilator::VERILATOR_FLAGS_UNTRACED,
                defines: verilator::CPP_DEFINES_UNTRACED,
                runtime: verilator::RUNTIME_SOURCES_UNTRACED,
                libs: &[],
                suffix: "-untraced",
            },
            Some(WaveFormat::Vcd) => Flavour {
                trace: format,
                coverage: false,
                shim: shim::ShimTrace::Vcd,
                flags: verilator::VERILATOR_FLAGS,
                defines: verilator::CPP_DEFINES,
                runtime: verilator::RUNTIME_SOURCES,
                libs: &[],
                suffix: "",
            },
            Some(WaveFormat::Fst) => Flavour {
                trace: format,
                coverage: false,
                shim: shim::ShimTrace::Fst,
                flags: verilator::VERILATOR_FLAGS_FST,
                defines: verilator::CPP_DEFINES_FST,
                runtime: verilator::RUNTIME_SOURCES_FST,
                libs: &["-lz"],
                suffix: "-fst",
            },
        }
    }
}

/// Builds the shared library of `iface.name` into the cache (or finds it there).
fn build_library(
    iface: &ModuleInterface,
    files: &[(String, String)],
    vlt: Option<&str>,
    flavour: &Flavour,
    threads: usize,
    opt_fast: &'static str,
) -> Result<BuildInfo, String> {
    let t0 = Instant::now();
    shim::validate(iface)?;
    let v = verilator::Verilator::find()
        .ok_or("verilator not found: install it (scripts/setup does) or set VERILATOR")?;
    let top = &iface.name;
    let mut cpp = shim::cpp_traced(iface, flavour.shim);
    shim::cpp_by_index(&mut cpp, iface);
    if flavour.coverage {
        shim::cpp_coverage(&mut cpp, iface);
    }
    let cxx = cxx();
    let tools = format!("{cxx} {}", cxx_version(&cxx));
    let key = library_key(
        LibraryKey { iface, files, vlt, flavour, threads, opt_fast, cpp: &cpp },
        &v.version,
        &tools,
    );
    let thread_flags = thread_flags(threads);
    // Derived from the Verilog, which the key holds: a reorder window of 4096 entries has a
    // generate loop above Verilator's default unroll count.
    let unroll_flags = neo_gen::tools::verilator_unroll_args(files.iter().map(|(_, text)| text.as_str()));
    let lib_name = format!("libneo_{top}.so");
    let mut log = String::new();
    // One build at a time in a process: test threads building the same model would race on its
    // cache entry (the second finds the first's half-written directory).
    static BUILDING: std::sync::Mutex<()> = std::sync::Mutex::new(());
    let _building = BUILDING.lock().unwrap_or_else(|e| e.into_inner());
    let quick = if opt_fast == OPT_FAST { "" } else { "-quick" };
    let name = format!("dyn-{top}{}{}{quick}", flavour.suffix, thread_suffix(threads));
    let (dir, cached) = cache::get_or_build(&cache_root(), &name, &key, &lib_name, |d| {
        let mut flags: Vec<&str> = flavour.flags.to_vec();
        flags.extend(thread_flags.iter().map(String::as_str));
        flags.extend(unroll_flags.iter().map(String::as_str));
        log = compile(&v, &cxx, (flavour, opt_fast), &flags, top, files, vlt, &cpp, d)
            .map_err(|e| format!("{top}: {MODEL_DOES_NOT_BUILD}: {e}"))?;
        fs::write(d.join("build.log"), &log).map_err(|e| e.to_string())
    })?;
    Ok(BuildInfo { library: dir.join(lib_name), cached, seconds: t0.elapsed().as_secs_f64(), log })
}

/// What a shared library's cache key covers besides the tool versions.
struct LibraryKey<'a> {
    iface: &'a ModuleInterface,
    files: &'a [(String, String)],
    vlt: Option<&'a str>,
    flavour: &'a Flavour,
    threads: usize,
    opt_fast: &'static str,
    cpp: &'a str,
}

/// The cache key of a shared library: the Verilog, waivers, flags, flavour, tool versions
/// (`verilator`, the C++ compiler `cxx`), build options and the shim.
fn library_key(k: LibraryKey<'_>, verilator: &str, cxx: &str) -> cache::Key {
    let mut key = cache::Key::new();
    key.add("top", k.iface.name.as_bytes());
    for (name, text) in k.files {
        key.add(&format!("file {name}"), text.as_bytes());
    }
    if let Some(vlt) = k.vlt {
        key.add("lint.vlt", vlt.as_bytes());
    }
    let f = k.flavour;
    key.add("flags", f.flags.join(" ").as_bytes());
    if k.threads > 1 {
        // Only for threaded models, so that single-threaded keys (and cache entries) stay as they were.
        key.add("threads", thread_flags(k.threads).join(" ").as_bytes());
    }
    if !f.suffix.is_empty() {
        // Only for FST, untraced and coverage, so that the VCD models' keys (and cache entries)
        // stay as they were.
        key.add("trace", format!("{:?} {:?} {:?}", f.defines, f.runtime, f.libs).as_bytes());
    }
    if f.coverage {
        key.add("coverage", b"1");
    }
    key.add("verilator", verilator.as_bytes());
    key.add("compiler", cxx.as_bytes());
    let opt_slow = slow_opt(k.opt_fast);
    key.add("dyn", format!("{DYN_VERSION} {} {opt_slow} {}", k.opt_fast, shim::SHIM_VERSION).as_bytes());
    key.add("shim.cpp", k.cpp.as_bytes());
    key
}

/// The Verilator flags of a model evaluated on `threads` threads (none for 1, Verilator's default).
fn thread_flags(threads: usize) -> Vec<String> {
    if threads > 1 {
        vec!["--threads".into(), threads.to_string()]
    } else {
        Vec::new()
    }
}

/// The cache-name suffix of a model evaluated on `threads` threads (none for 1).
fn thread_suffix(threads: usize) -> String {
    if threads > 1 {
        format!("-t{threads}")
    } else {
        String::new()
    }
}

/// Verilates with `flags` (the flavour's and the thread flags) and compiles into
/// `dir/libneo_<top>.so`; returns the log line.
#[allow(clippy::too_many_arguments)]
fn compile(
    v: &verilator::Verilator,
    cxx: &str,
    (flavour, opt_fast): (&Flavour, &'static str),
    flags: &[&str],
    top: &str,
    files: &[(String, String)],
    vlt: Option<&str>,
    cpp: &str,
    dir: &Path,
) -> Result<String, String> {
    let hdl = dir.join("hdl");
    fs::create_dir_all(&hdl).map_err(|e| e.to_string())?;
    let mut paths = Vec::new();
    if let Some(vlt) = vlt {
        paths.push(write(&hdl.join("lint.vlt"), vlt)?);
    }
    for (name, text) in files {
        paths.push(write(&hdl.join(name), text)?);
    }
    let t0 = Instant::now();
    let obj = dir.join("obj");
    let (fast, slow) = verilator::verilate_with(v, flags, top, &paths, &obj)?;
    let verilate_s = t0.elapsed().as_secs_f64();
    let shim = write(&dir.join("shim.cpp"), cpp)?;
    let fast: Vec<PathBuf> = fast.iter().map(|c| obj.join(format!("{c}.cpp"))).chain([shim]).collect();
    let slow: Vec<PathBuf> = slow.iter().map(|c| obj.join(format!("{c}.cpp"))).collect();
    let units: Vec<(PathBuf, &str)> = if opt_fast == OPT_FAST {
        let fast = fast.into_iter().map(|p| (p, OPT_FAST));
        fast.chain(slow.into_iter().map(|p| (p, slow_opt(opt_fast)))).collect()
    } else {
        let mut units = unity_units(&obj, "unity", &fast, opt_fast)?;
        units.extend(unity_units(&obj, "unity-slow", &slow, slow_opt(opt_fast))?);
        units
    };
    let t1 = Instant::now();
    let runtime = runtime_objects(v, cxx, flavour)?;
    let objects = compile_all(v, cxx, flavour.defines, &obj, &units)?;
    let lib = dir.join(format!("libneo_{top}.so"));
    let mut link = Command::new(cxx);
    link.args(["-shared", "-Wl,-Bsymbolic", "-o"])
        .arg(&lib)
        .args(&objects)
        .args(&runtime)
        .args(flavour.libs)
        .arg("-lpthread");
    if flags.contains(&"--threads") {
        // The threaded runtime's atomics (Verilator's makefile links it too).
        link.arg("-latomic");
    }
    run(&mut link, "linking")?;
    for o in &objects {
        let _ = fs::remove_file(o);
    }
    Ok(format!(
        "{top}: verilate {verilate_s:.1} s, compile {:.1} s ({} files)",
        t1.elapsed().as_secs_f64(),
        units.len()
    ))
}

/// The translation units of a model built for short runs ([`quick_opt`]): the `files` included
/// into one `<stem><k>.cpp` per core (at most 4; largest files first into the smallest group),
/// all at `opt`, as Verilator's own makefile does without parallel builds (`V<top>__ALL.cpp`).
/// Each generated file includes Verilator's headers, whose parsing dominates a small model's
/// compile: the BSU's 8 files take 58 s of CPU one by one and 10 s as one unit.
fn unity_units(
    obj: &Path,
    stem: &str,
    files: &[PathBuf],
    opt: &'static str,
) -> Result<Vec<(PathBuf, &'static str)>, String> {
    if files.is_empty() {
        return Ok(Vec::new());
    }
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get()).min(4);
    let mut sized: Vec<(u64, &PathBuf)> =
        files.iter().map(|p| (fs::metadata(p).map_or(0, |m| m.len()), p)).collect();
    sized.sort_by_key(|s| std::cmp::Reverse(s.0));
    let mut groups: Vec<(u64, String)> = vec![(0, String::new()); cores.min(sized.len()).max(1)];
    for (size, path) in sized {
        let g = groups.iter_mut().min_by_key(|g| g.0).expect("at least one group");
        g.0 += size;
        g.1.push_str(&format!("#include \"{}\"\n", path.display()));
    }
    groups
        .iter()
        .enumerate()
        .map(|(k, (_, text))| Ok((write(&obj.join(format!("{stem}{k}.cpp")), text)?, opt)))
        .collect()
}

/// The flavour's Verilator runtime (`verilated.cpp` and its trace writer, position-independent,
/// at [`OPT_FAST`]) as objects from the cache, compiled on a miss: the same objects serve every
/// model of the flavour, instead of each model compiling its own copy (about 10 s of CPU).
fn runtime_objects(v: &verilator::Verilator, cxx: &str, flavour: &Flavour) -> Result<Vec<PathBuf>, String> {
    let mut key = cache::Key::new();
    key.add("runtime", format!("{:?} {:?} {OPT_FAST}", flavour.defines, flavour.runtime).as_bytes());
    key.add("verilator", v.version.as_bytes());
    key.add("compiler", format!("{cxx} {}", cxx_version(cxx)).as_bytes());
    key.add("include", v.include().to_string_lossy().as_bytes());
    let name = format!("dynrt{}", flavour.suffix);
    let units: Vec<(PathBuf, &str)> =
        flavour.runtime.iter().map(|f| (v.include().join(f), OPT_FAST)).collect();
    let (dir, _) = cache::get_or_build(&cache_root(), &name, &key, "done", |d| {
        compile_all(v, cxx, flavour.defines, d, &units)?;
        fs::write(d.join("done"), "").map_err(|e| e.to_string())
    })?;
    Ok((0..units.len()).map(|i| dir.join(format!("u{i}.o"))).collect())
}

/// Compiles every `(source, opt)` to an object under `obj`, on all cores; returns the objects.
fn compile_all(
    v: &verilator::Verilator,
    cxx: &str,
    defines: &[(&str, &str)],
    obj: &Path,
    units: &[(PathBuf, &str)],
) -> Result<Vec<PathBuf>, String> {
    use rayon::prelude::*;
    units
        .par_iter()
        .enumerate()
        .map(|(i, (src, opt))| {
            let out = obj.join(format!("u{i}.o"));
            let mut c = Command::new(cxx);
            c.args(["-c", "-fPIC", "-std=gnu++17", "-faligned-new", "-fcf-protection=none", "-w", opt])
                .arg("-I")
                .arg(v.include())
                .arg("-I")
                .arg(v.include().join("vltstd"))
                .arg("-I")
                .arg(obj);
            for (name, value) in defines {
                c.arg(format!("-D{name}={value}"));
            }
            c.arg("-o").arg(&out).arg(src);
            run(&mut c, &format!("compiling {}", src.display()))?;
            Ok(out)
        })
        .collect()
}

fn run(cmd: &mut Command, what: &str) -> Result<(), String> {
    let out = cmd.output().map_err(|e| format!("{what}: cannot run {cmd:?}: {e}"))?;
    if out.status.success() {
        return Ok(());
    }
    Err(format!(
        "{what} failed:\n{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    ))
}

fn write(path: &Path, text: &str) -> Result<PathBuf, String> {
    fs::write(path, text).map_err(|e| format!("{}: {e}", path.display()))?;
    Ok(path.to_path_buf())
}

#[cfg(test)]
mod tests {
    use super::*;
    use neo_gen::interface::Port;

    fn key_of(flavour: &Flavour) -> String {
        let iface = ModuleInterface {
            name: "neo_x".into(),
            ports: vec![Port { name: "clk_i".into(), dir: Dir::In, width: 1 }],
        };
        let files = [("neo_x.v".to_string(), "module neo_x (input clk_i); endmodule\n".to_string())];
        let mut cpp = shim::cpp_traced(&iface, flavour.shim);
        if flavour.coverage {
            shim::cpp_coverage(&mut cpp, &iface);
        }
        let k = LibraryKey {
            iface: &iface,
            files: &files,
            vlt: None,
            flavour,
            threads: 1,
            opt_fast: OPT_FAST,
            cpp: &cpp,
        };
        library_key(k, "Verilator 5.006", "c++ 12").hex()
    }

    /// The coverage flavour is a cache entry of its own: its key differs from every traced and
    /// untraced model's, and so does its name.
    #[test]
    fn coverage_models_have_their_own_cache_key() {
        let cov = key_of(&Flavour::coverage());
        for format in [None, Some(WaveFormat::Vcd), Some(WaveFormat::Fst)] {
            let other = Flavour::of(format);
            assert_ne!(key_of(&other), cov, "{format:?}");
            assert_ne!(other.suffix, Flavour::coverage().suffix, "{format:?}");
        }
        assert!(Flavour::coverage().flags.contains(&"--coverage"));
        assert!(Flavour::coverage().defines.contains(&("VM_COVERAGE", "1")));
        assert!(Flavour::coverage().runtime.contains(&"verilated_cov.cpp"));
        // The same inputs give the same key.
        assert_eq!(key_of(&Flavour::coverage()), cov);
    }

    /// Only the coverage shim has the entry point that writes the data.
    #[test]
    fn only_the_coverage_shim_writes_data() {
        let iface = ModuleInterface { name: "neo_x".into(), ports: vec![] };
        let mut cpp = shim::cpp_traced(&iface, shim::ShimTrace::Off);
        assert!(!cpp.contains("neo_neo_x_coverage_write") && !cpp.contains("coverage_write"));
        shim::cpp_coverage(&mut cpp, &iface);
        assert!(cpp.contains("void neo_neo_x_coverage_write(void* p, const char* path)"));
        assert!(cpp.contains("coveragep()->write(path)"));
    }
}
