//! Verilator builds and cosimulation test benches for the Neo units.
//!
//! `build.rs` Verilates every top emitted by `neo-gen` (and the harness's own fixture) and
//! generates a safe wrapper per top in [`models`]. The test benches drive them cocotb-style:
//! drivers with random input stalls, monitors under random output backpressure, and checkers that
//! compare against the bit-exact golden model (`neo_golden::sort`) and stop at the first
//! mismatch.

pub mod bench;
pub mod bits;
#[cfg(neo_has_verilator)]
pub mod bsu;
pub mod check;
#[cfg(neo_has_verilator)]
pub mod core;
pub mod dut;
#[cfg(neo_has_verilator)]
pub mod itu;
pub mod lanes;
#[cfg(neo_has_verilator)]
pub mod latency;
#[cfg(neo_has_verilator)]
pub mod msu;
#[cfg(neo_has_verilator)]
pub mod raster;
pub mod rng;
#[cfg(neo_has_verilator)]
pub mod scu;
pub mod stimulus;
pub mod stream;
pub mod waves;

/// The Verilated models, one struct per top (generated; absent without Verilator).
#[cfg(neo_has_verilator)]
pub mod models {
    include!(concat!(env!("OUT_DIR"), "/models.rs"));
}

/// The generator configuration the models in [`models`] were built from (the default one).
pub fn config() -> neo_gen::GenConfig {
    neo_gen::GenConfig::default()
}
