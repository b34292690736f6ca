//! One module per `neo` subcommand; none imports another (shared arguments are in
//! [`crate::args`], shared point runners in [`crate::points`], the verilated engine's frame loop
//! of `neo cosim` and `neo bench engine` in [`crate::engine_run`]).

pub mod artifact;
pub mod bench;
pub mod compare;
pub mod cosim;
pub mod dram;
pub mod frames;
pub mod gen;
pub mod render;
pub mod report;
pub mod scene;
pub mod signals;
pub mod simulate;
pub mod trajectory;
