//! The Verilog emitter and one generator per Neo unit.
//!
//! Every generator describes its module with the typed builder in [`emit`], which prints
//! readable Verilog in the lowRISC style and also exports the module's port list
//! ([`interface::ModuleInterface`]), so the Verilator C++ shim and the Rust bindings in `tb/` are
//! generated from the same description rather than written twice.
//!
//! Entry points: [`EngineConfig`] (the parameters, [`EngineConfig::default`] = the paper's Sorting
//! Core), [`generate`] (every module as a [`VerilogFile`]), [`tops`] (the units with their own
//! cosimulation model) and [`files_for`] (the files one top needs).

pub mod emit;
pub mod interface;
pub mod output;
pub mod report;
pub mod tools;
pub mod units;

pub use neo_golden::engine::{ConfigError, EngineConfig, SchedulerPolicy, Topology};
pub use units::{files_for, generate, top_modules, tops, try_generate, VerilogFile};
