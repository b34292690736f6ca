//! Verilator builds and cosimulation test benches for the Neo units.
//!
//! `build.rs` Verilates every top emitted by `neo-gen` (and the harness's own fixture) and
//! generates a safe wrapper per top in [`models`]. The test benches drive them cocotb-style:
//! drivers with random input stalls, monitors under random output backpressure, and checkers that
//! compare against the bit-exact golden model (`neo_golden::sort`) and stop at the first
//! mismatch.

pub mod axi;
pub mod axil;
pub mod bench;
pub mod bits;
#[cfg(neo_has_verilator)]
pub mod bsu;
pub mod check;
pub mod configs;
#[cfg(neo_has_verilator)]
pub mod core;
pub mod coverage;
pub mod datapath;
pub mod dup;
pub mod dut;
pub mod dynmodel;
pub mod engine;
pub mod engine_budget;
pub mod engine_regs;
pub mod fetch;
pub mod fp;
#[cfg(neo_has_verilator)]
pub mod frame;
pub mod hdl_dir;
#[cfg(neo_has_verilator)]
pub mod itu;
pub mod lane;
pub mod lanes;
#[cfg(neo_has_verilator)]
pub mod latency;
pub mod lists;
#[cfg(neo_has_verilator)]
pub mod msu;
pub mod pre;
pub mod pre_engine;
#[cfg(neo_has_verilator)]
pub mod raster;
pub mod rng;
#[cfg(neo_has_verilator)]
pub mod scu;
#[cfg(neo_has_verilator)]
pub mod seq;
pub mod stimulus;
pub mod stream;
pub mod waves;
pub mod window;
pub mod xinit;

/// The Verilated models, one struct per top (generated; absent without Verilator).
#[cfg(neo_has_verilator)]
pub mod models {
    include!(concat!(env!("OUT_DIR"), "/models.rs"));
}

/// Whether this build has the Verilated models in `models` (Verilator was found at build time).
pub const HAS_MODELS: bool = cfg!(neo_has_verilator);

/// Expands to its items when this build of neo-tb has the Verilated models, and to nothing
/// otherwise: for cosimulation tests in other packages (the root package's RTL validation),
/// which cannot see neo-tb's `neo_has_verilator` cfg. Pair it with [`require_models`].
#[cfg(neo_has_verilator)]
#[macro_export]
macro_rules! with_models {
    ($($item:item)*) => { $($item)* };
}

/// Expands to its items when this build of neo-tb has the Verilated models, and to nothing
/// otherwise (this build has none).
#[cfg(not(neo_has_verilator))]
#[macro_export]
macro_rules! with_models {
    ($($item:item)*) => {};
}

/// For every cosimulation test (in neo-tb and in other packages, such as the root package's RTL
/// validations): returns whether the Verilated models are present. Without them it prints
/// `SKIP <test>: <reason>` and returns false, or panics when `CI` is set (as `build.rs` refuses
/// to build without Verilator there: CI runs every cosimulation). `test` names the test and what
/// it checks.
pub fn require_models(test: &str) -> bool {
    if !HAS_MODELS {
        skip(test, "neo-tb was built without Verilator (install it: scripts/setup); not checked");
    }
    HAS_MODELS
}

/// A test that cannot run here: [`neo_golden::shared::skip_or_fail`] (SKIP, or a failure when
/// `CI` is set).
pub use neo_golden::shared::skip_or_fail as skip;

/// The engine configuration the models in [`models`] were built from: the default, or the file
/// named by `NEO_CONFIG` when this crate was built (`NEO_CONFIG=cfg.json cargo test -p neo-tb`
/// cosimulates and measures that configuration).
pub fn config() -> neo_gen::EngineConfig {
    serde_json::from_str(include_str!(concat!(env!("OUT_DIR"), "/engine_config.json")))
        .expect("build.rs writes the configuration it built")
}
