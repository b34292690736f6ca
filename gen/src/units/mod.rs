//! One generator per Neo unit, and the file sets of the cosimulated tops.
//!
//! | module          | what                                                    | cosim top |
//! |-----------------|---------------------------------------------------------|-----------|
//! | `neo_cmp_swap`  | compare-exchange on packed entries                      | no        |
//! | `neo_bsu`       | Bitonic Sorting Unit: pipelined comparator network      | yes       |
//! | `neo_msu`       | Merge Sort Unit+: streaming two-way merge with delete   | yes       |
//! | `neo_chunk_ram` | one chunk buffer: 1 write port, 2 asynchronous reads    | no        |
//! | `neo_sort_core` | Sorting Core: BSU + MSU+ + buffers + memory/command ports | yes     |
//! | `neo_itu_centre` | ITU: the centre test of one subtile column or row, parameter `K` | no |
//! | `neo_itu_window` | ITU: the steps and U / V windows of step `K`, parameter `K` | no     |
//! | `neo_itu`       | Intersection Test Unit: subtile bitmap of one Gaussian  | yes       |
//! | `neo_scu_exp`   | SCU exp unit: ROM over one octave + interpolation       | no        |
//! | `neo_scu_lane`  | SCU pixel lane: S0..S5, quadratic form, exp, alpha      | no        |
//! | `neo_scu_blend` | SCU lane blend: a pixel's new T, colour, done bit       | no        |
//! | `neo_scu_pixels` | SCU lane pixels: states, saved states, output colours  | no        |
//! | `neo_scu`       | Subtile Compute Unit: alpha blending of one subtile     | yes       |
//! | `neo_raster_loader` | raster core LOAD: table bursts, then feature reads  | no        |
//! | `neo_raster_feeder` | raster core: one SCU's routing FIFO and feeder      | no        |
//! | `neo_raster_core` | Rasterization Core: ITUs + SCUs + buffers + ports     | yes       |
//! | `neo_pre_color` | Preprocessing: colour unit (SH degree 0-3, from golden's graph) | run time |
//! | `neo_pre_project` | Preprocessing: projection unit (from golden's graph) | run time |
//! | `neo_pre_dup_range` | Preprocessing: duplication unit's candidate tiles along one axis | no |
//! | `neo_pre_dup`   | Preprocessing: duplication unit (tiles entered, incoming flag) | run time |
//! | `neo_pre_fetch` | Preprocessing: record fetch unit (streams, gathers; the read window) | run time |
//! | `neo_pre_lane`  | Preprocessing: one lane (fetch, projection, colour, duplication, feature words) | run time |
//! | `neo_pre_lists` | Preprocessing: the incoming-list writer                  | run time |
//! | `neo_pre_fifo`  | Preprocessing: a queue, parameters `WIDTH` and `DEPTH`      | no        |
//! | `neo_pre_ram`   | Preprocessing: a memory, parameters `WIDTH` and `DEPTH`     | no        |
//! | `neo_pre_engine` | the Preprocessing Engine: lanes, hit arbiter, list writer | in `neo_engine` |
//! | `neo_perf_counter` | one 64-bit performance counter                       | no        |
//! | `neo_perf_counters` | the engine's performance counters                   | yes       |
//! | `neo_engine_regs` | engine control port: AXI4-Lite register map           | yes       |
//! | `neo_sort_seq`  | engine: one Sorting Core's per-tile command sequencer   | yes       |
//! | `neo_frame_ctrl` | engine: descriptors, scheduler, results, raster dispatch | yes      |
//! | `neo_axi_sort_bridge` | sorting core memory port -> AXI4 manager          | yes       |
//! | `neo_axi_raster_bridge` | raster core memory port -> AXI4 manager         | yes       |
//! | `neo_axi_rr_arb` | the port mux's round-robin AR / AW request arbiter, parameter `PORTS` | no |
//! | `neo_axi_mux`   | PORTS AXI4 managers -> one port, parameter `PORTS` (the engine's, and 3 and 8 in its bench) | run time |
//! | `neo_clock_gate` | a falling-edge-enabled clock gate (the idle Preprocessing Engine) | no |
//! | `neo_engine`    | the engine: control port, frame controller, cores, bridges, port muxes | run time |
//! | `neo_fp_*`      | binary32 primitives of the Preprocessing Engine (`fp`; `neo_fp_to_int`'s rounding a parameter) | no |
//! | `neo_fp_bench`  | every `neo_fp_*` primitive side by side                 | run time  |

pub mod axi;
pub mod bsu;
pub mod chunk_ram;
pub mod clock_gate;
pub mod cmp_swap;
pub mod engine;
pub mod engine_regs;
pub mod fp;
pub mod frame_ctrl;
pub mod itu;
pub mod msu;
pub mod perf_counters;
pub mod pre;
pub mod raster_core;
pub mod scu;
pub mod sort_core;
pub mod sort_seq;

use crate::emit::Module;
use crate::interface::ModuleInterface;
use neo_golden::engine::{ConfigError, EngineConfig};

/// One generated file: module `name` in `name.v`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct VerilogFile {
    /// The module name (the file is `NAME.v`).
    pub name: String,
    /// The file text.
    pub text: String,
}

impl VerilogFile {
    /// The file name, `NAME.v`.
    pub fn file_name(&self) -> String {
        format!("{}.v", self.name)
    }

    /// The text without the generator's header line ([`crate::emit::HEADER`], which names the
    /// configuration's hash): two configurations whose modules are otherwise the same text
    /// give the same body. A text without that header is its own body.
    pub fn body(&self) -> &str {
        match self.text.split_once('\n') {
            Some((first, rest)) if first.starts_with(crate::emit::HEADER) => rest,
            _ => &self.text,
        }
    }
}

/// Names of the tops that get their own cosimulation model, in order.
pub fn top_modules() -> &'static [&'static str] {
    &[
        "neo_bsu",
        "neo_msu",
        "neo_sort_core",
        "neo_itu",
        "neo_scu",
        "neo_raster_core",
        "neo_perf_counters",
        "neo_engine_regs",
        "neo_sort_seq",
        "neo_frame_ctrl",
        "neo_axi_sort_bridge",
        "neo_axi_raster_bridge",
    ]
}

/// Tops the benches verilate at run time (`neo_tb::dynmodel`) rather than with every build:
/// the lint and latch gates check them like [`top_modules`] (the lane with the units it
/// instantiates as black boxes, each checked as its own top; the port mux at its defaults, and
/// at other client counts by `gen/tests/hdl_gates.rs`). (The engine, which has its own gates,
/// is not listed.)
pub fn run_time_tops() -> &'static [&'static str] {
    &[
        axi::mux::NAME,
        pre::dup::NAME,
        pre::COLOR_NAME,
        pre::PROJECT_NAME,
        pre::fetch::NAME,
        pre::lane::NAME,
        pre::lists::NAME,
        pre::engine::NAME,
    ]
}

/// The modules under `top` (in `cfg`) that a lint of `top` may box
/// ([`crate::tools::verilator_lint_boxed`]): those that are tops of the lint gates themselves
/// ([`top_modules`], [`run_time_tops`]) and whose text is the default configuration's (the
/// header line aside), since the gates lint every top of the default configuration.
pub fn lint_boxes(cfg: &EngineConfig, top: &str) -> Vec<String> {
    let default = EngineConfig::default();
    let default_files = generate(&default);
    let checked: Vec<&str> = top_modules().iter().chain(run_time_tops()).copied().collect();
    files_for(cfg, top)
        .into_iter()
        .filter(|f| f.name != top && checked.contains(&f.name.as_str()))
        .filter(|f| default_files.iter().any(|d| d.name == f.name && d.body() == f.body()))
        .map(|f| f.name)
        .collect()
}

/// Every module of the configuration, leaves first.
pub fn modules(cfg: &EngineConfig) -> Result<Vec<Module>, ConfigError> {
    cfg.validate()?;
    let hash = cfg.hash();
    let mut all = vec![
        cmp_swap::module(cfg),
        bsu::module(cfg),
        msu::module(cfg),
        chunk_ram::module(cfg),
        sort_core::module(cfg),
        itu::centre_module(cfg),
        itu::window_module(cfg),
        itu::module(cfg),
        scu::exp::module(cfg),
        scu::lane::module(cfg),
        scu::blend::module(cfg),
        scu::pixel::module(cfg),
        scu::module(cfg),
        raster_core::loader::module(cfg),
        raster_core::feeder::module(cfg),
        raster_core::module(cfg),
        perf_counters::counter_module(cfg),
        perf_counters::module(cfg),
        engine_regs::module(cfg),
        sort_seq::module(cfg),
        frame_ctrl::module(cfg),
        axi::sort_bridge::module(cfg),
        axi::raster_bridge::module(cfg),
    ];
    if cfg.raster_window > 1 {
        all.push(raster_core::window::cell_module(cfg));
        all.push(raster_core::window::module(cfg));
        all.push(raster_core::window_loader::module(cfg));
    }
    all.push(axi::rr_arb::module(cfg));
    all.push(axi::mux::module(cfg)?);
    all.push(engine::module(cfg));
    all.extend(fp::modules(cfg));
    all.push(pre::dup::range_module(cfg));
    all.push(pre::dup::module(cfg));
    all.push(pre::fifo::module());
    all.push(pre::ram::module());
    all.push(pre::fetch::module(cfg));
    all.push(pre::color_module(cfg));
    all.push(pre::project_module(cfg));
    all.push(pre::lane::module(cfg));
    all.push(pre::lists::module(cfg));
    if cfg.has_preprocessing() {
        all.push(pre::engine::module(cfg));
    }
    all.push(clock_gate::module(cfg));
    for m in &mut all {
        m.config_hash = Some(hash);
    }
    Ok(all)
}

/// Every module as a file, or the configuration error.
pub fn try_generate(cfg: &EngineConfig) -> Result<Vec<VerilogFile>, ConfigError> {
    Ok(modules(cfg)?.iter().map(|m| VerilogFile { name: m.name.clone(), text: m.to_verilog() }).collect())
}

/// Every module as a file (one module per file `NAME.v`), in a fixed order.
///
/// # Panics
/// When `cfg` is invalid ([`EngineConfig::validate`]); use [`try_generate`] to get the error.
pub fn generate(cfg: &EngineConfig) -> Vec<VerilogFile> {
    try_generate(cfg).unwrap_or_else(|e| panic!("{e}"))
}

/// The interfaces of the cosimulated tops ([`top_modules`]).
///
/// # Panics
/// When `cfg` is invalid.
pub fn tops(cfg: &EngineConfig) -> Vec<ModuleInterface> {
    let all = modules(cfg).unwrap_or_else(|e| panic!("{e}"));
    top_modules()
        .iter()
        .map(|t| all.iter().find(|m| m.name == *t).expect("every top is generated").interface())
        .collect()
}

/// The files module `top` needs: itself and every module it instantiates, transitively
/// (dependencies first, `top` last). Empty when `top` is not a generated module.
///
/// # Panics
/// When `cfg` is invalid.
pub fn files_for(cfg: &EngineConfig, top: &str) -> Vec<VerilogFile> {
    let all = modules(cfg).unwrap_or_else(|e| panic!("{e}"));
    match all.iter().find(|m| m.name == top) {
        Some(m) => files_with(&all, m),
        None => Vec::new(),
    }
}

/// The files of `top`, a module built outside the configuration's set (a bench's own top), and
/// of every generated module it instantiates, transitively (dependencies first, `top` last).
///
/// # Panics
/// When `cfg` is invalid.
pub fn files_for_module(cfg: &EngineConfig, top: &Module) -> Vec<VerilogFile> {
    let all = modules(cfg).unwrap_or_else(|e| panic!("{e}"));
    files_with(&all, top)
}

/// `top` and the modules of `all` it instantiates, transitively, dependencies first.
fn files_with(all: &[Module], top: &Module) -> Vec<VerilogFile> {
    fn visit<'a>(all: &'a [Module], m: &'a Module, order: &mut Vec<&'a Module>) {
        if order.iter().any(|o| o.name == m.name) {
            return;
        }
        for dep in m.instantiated() {
            if let Some(d) = all.iter().find(|x| x.name == dep) {
                visit(all, d, order);
            }
        }
        order.push(m);
    }
    let mut order = Vec::new();
    visit(all, top, &mut order);
    order.iter().map(|m| VerilogFile { name: m.name.clone(), text: m.to_verilog() }).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_file_per_module_named_after_it() {
        let files = generate(&EngineConfig::default());
        for f in &files {
            assert!(f.text.contains(&format!("\nmodule {} ", f.name)), "{}", f.name);
            assert_eq!(f.text.matches("\nmodule ").count(), 1, "{}", f.name);
            let header = f.text.lines().next().unwrap();
            let hash = format!("config {:#018x})", EngineConfig::default().hash());
            assert!(
                header.starts_with(crate::emit::HEADER) && header.contains(&hash),
                "{}: {header}",
                f.name
            );
            assert!(header.contains("gen/src/units/"), "{}: {header}", f.name);
        }
        let mut names: Vec<&str> = files.iter().map(|f| f.name.as_str()).collect();
        names.sort_unstable();
        names.dedup();
        assert_eq!(names.len(), files.len());
    }

    #[test]
    fn files_for_is_the_transitive_closure() {
        let cfg = EngineConfig::default();
        let names = |t: &str| files_for(&cfg, t).into_iter().map(|f| f.name).collect::<Vec<_>>();
        assert_eq!(names("neo_bsu"), ["neo_cmp_swap", "neo_bsu"]);
        assert_eq!(names("neo_msu"), ["neo_msu"]);
        let core = names("neo_sort_core");
        assert_eq!(core.last().map(String::as_str), Some("neo_sort_core"));
        for dep in ["neo_cmp_swap", "neo_bsu", "neo_msu", "neo_chunk_ram"] {
            assert!(core.iter().any(|n| n == dep), "{dep} missing from {core:?}");
        }
        assert!(names("no_such_module").is_empty());
    }

    #[test]
    fn tops_have_clock_and_reset() {
        let t = tops(&EngineConfig::default());
        assert_eq!(t.iter().map(|i| i.name.as_str()).collect::<Vec<_>>(), top_modules());
        for i in &t {
            assert_eq!(i.ports[0].name, "clk_i");
            assert_eq!(i.ports[1].name, "rst_ni");
        }
    }
}
