//! The `neo` command line: scene tools, the float reference renderer, image metrics and benchmarks.

mod args;
mod commands;
mod engine_run;
mod points;
mod progress;

use clap::{Parser, Subcommand};
use std::process::ExitCode;

/// RTL generator, cosimulation harness and cycle model for the Neo 3DGS accelerator.
#[derive(Parser)]
#[command(name = "neo", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Inspect or convert a scene (standard or compressed .ply, or a synthetic spec).
    #[command(subcommand)]
    Scene(commands::scene::SceneCommand),
    /// Render one view with the float reference renderer and write an 8-bit PNG.
    Render(commands::render::RenderArgs),
    /// Print PSNR and SSIM between two PNG images.
    Compare(commands::compare::CompareArgs),
    /// Generate a camera trajectory and write it as a cameras.json.
    Trajectory(commands::trajectory::TrajectoryArgs),
    /// Measure throughput figures (scene loading, rendering, unit cosimulation) in one run and
    /// print them; `neo bench engine`: the verilated engine's build and simulation speed.
    Bench(commands::bench::BenchArgs),
    /// Run the bit-exact golden pipeline along a trajectory with a sorting strategy; write stats.json.
    Frames(commands::frames::FramesArgs),
    /// Rank correlation of each per-tile disorder signal with the tile's error, from `neo
    /// frames --tile-stats` runs.
    Signals(commands::signals::SignalsArgs),
    /// The main job: the cycle-model report (throughput, DRAM traffic, strategy timelines, speed
    /// against error) written to reports/index.md.
    Report(commands::report::ReportArgs),
    /// Run the cycle model (Neo, GSCore-style, GPU-style) on golden workloads; print or write
    /// per-point results.
    Simulate(commands::simulate::SimulateArgs),
    /// Run the DRAM model alone on a request stream (`0xADDR R|W` lines); print bandwidth, mean
    /// read latency and row hits, misses and conflicts.
    Dram(commands::dram::DramArgs),
    /// The official artifact simulator's DRAM lines for `poc.trace` frames, the waterfall from
    /// its bytes to neo's charging, and (`--time`) its timing on neo's DRAM model.
    Artifact(commands::artifact::ArtifactArgs),
    /// Run the verilated engine (neo_engine) on a scene, frame by frame, bit-exact against the
    /// golden model.
    Cosim(commands::cosim::CosimArgs),
    /// Generate the Verilog of every unit (BSU, MSU+, sorting core, ITU, SCU), check it, report synthesis.
    Gen(commands::gen::GenArgs),
}

/// Lets a closed standard output (`neo simulate --json | head`) end the process quietly, as it
/// does other Unix tools: Rust ignores `SIGPIPE`, so `println!` would panic on the broken pipe.
fn default_sigpipe() {
    // SAFETY: setting a signal's disposition to its default, before any thread is started.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

fn main() -> ExitCode {
    default_sigpipe();
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Scene(c) => commands::scene::run(c),
        Command::Render(a) => commands::render::run(a),
        Command::Compare(a) => commands::compare::run(a),
        Command::Trajectory(a) => commands::trajectory::run(a),
        Command::Bench(a) => commands::bench::run(a),
        Command::Frames(a) => commands::frames::run(a),
        Command::Signals(a) => commands::signals::run(a),
        Command::Report(a) => commands::report::run(a),
        Command::Simulate(a) => commands::simulate::run(a),
        Command::Dram(a) => commands::dram::run(a),
        Command::Artifact(a) => commands::artifact::run(a),
        Command::Gen(a) => commands::gen::run(a),
        Command::Cosim(a) => commands::cosim::run(a),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
