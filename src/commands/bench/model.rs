//! `neo bench model`: the CPU the cycle model spends per frame, workload generation included,
//! against issue 13's target (a benchmark, never a CI test).
//!
//! Issue 13 states that the official artifact spends about 33 s of CPU per QHD frame of a
//! 500k-Gaussian real scene, and sets neo's target at a hundredth of that: at most 0.33 s of CPU
//! per frame for the model of Neo including the workload generation of that frame. The bench
//! runs what `neo report`'s throughput runs do on one point (the work-only golden workload of
//! Neo's strategy with the hierarchical record for GSCore, early termination sampled on every
//! 16th tile), on a synthetic scene of that size, and reads the process's CPU time (user +
//! system, every thread) around each phase.

use super::sampler::{split, Counts, Sampler};
use super::verdict;
use crate::args::ModelArgs;
use crate::points::{check_buffers, load_config, load_latency};
use crate::progress::self_cpu;
use anyhow::{anyhow, Result};
use clap::Args;
use neo_sim::driver::GoldenRaster;
use neo_sim::run::{simulate, Arch, RunOptions};
use neo_sim::suite::{self, parse_res, Point};
use std::time::Instant;

/// CPU seconds per frame the target allows (issue 13: a hundredth of the artifact's).
pub const TARGET_CPU_S_PER_FRAME: f64 = 0.33;

/// The artifact's CPU seconds per QHD frame of a 500k-Gaussian real scene, as issue 13 states it
/// (not measured by neo).
pub const ARTIFACT_CPU_S_PER_FRAME: f64 = 33.0;

/// Arguments of `neo bench model`.
#[derive(Args)]
pub struct ModelBenchArgs {
    /// Gaussians of the synthetic outdoor scene.
    #[arg(long, default_value_t = 500_000)]
    pub gaussians: usize,
    /// Frames of `orbit` (frame 0 sorts from scratch, the others reuse the tables).
    #[arg(long, default_value_t = 12)]
    pub frames: usize,
    /// Resolution.
    #[arg(long, default_value = "qhd", value_parser = crate::args::resolution)]
    pub res: String,
    /// Architectures timed besides Neo (`all`: GSCore-4, GSCore-16 and the GPU too).
    #[arg(long, default_value = "all")]
    pub arch: String,
    #[command(flatten)]
    pub model: ModelArgs,
}

/// Runs `f` and returns its result with its (CPU, wall) seconds.
fn timed<T>(f: impl FnOnce() -> T) -> (T, f64, f64) {
    let (c, t) = (self_cpu(), Instant::now());
    let v = f();
    (v, self_cpu() - c, t.elapsed().as_secs_f64())
}

/// Where the CPU of Neo's frames went (CPU seconds per frame), from the sampler: the workload's
/// phases, then the model's.
fn print_split(workload: &Counts, workload_cpu: f64, model: &Counts, model_cpu: f64) {
    use neo_golden::profile::Phase::*;
    println!(
        "where it goes    CPU s/frame by phase ({} SIGPROF samples of the process's CPU time):",
        workload.total() + model.total()
    );
    println!(
        "  workload       {}",
        split(workload, &[Preprocess, Binning, Sort, TileWork, Other], workload_cpu)
    );
    println!("  model neo      {}", split(model, &[Engine, Dram, Other], model_cpu));
    println!(
        "                 (tile work: write-back, sampled raster and hierarchical record; engine: event loop, jobs and address walks)"
    );
}

/// Runs `neo bench model`.
pub fn run(a: ModelBenchArgs) -> Result<()> {
    if a.frames == 0 {
        anyhow::bail!("--frames 0: the bench needs at least one frame");
    }
    let cfg = load_config(a.model.config.as_deref(), a.model.engine.as_deref(), a.model.sizes.as_deref())?;
    let lat = load_latency(&a.model.latency, &cfg)?;
    let mut archs = Arch::parse_list(&a.arch, &cfg).map_err(|e| anyhow!(e))?;
    archs.retain(|&x| x != Arch::Neo);
    archs.insert(0, Arch::Neo);
    let spec = super::synthetic_spec(a.gaussians)?;
    let (label, width, height) = parse_res(&a.res).map_err(|e| anyhow!(e))?;
    let point = Point {
        scene: spec.clone(),
        trajectory: "orbit".into(),
        speed: 1.0,
        frames: a.frames,
        res: label,
        width,
        height,
        strategy: "neo".into(),
        chunk: cfg.engine.chunk,
        passes: cfg.pipeline.dps_passes,
        raster_window: cfg.engine.raster_window,
    };
    check_buffers(&a.model, &cfg, [(&point, &archs[..])])?;
    let threads = rayon::current_num_threads();
    let (scene, cpu, wall) = timed(|| suite::load_scene(&spec));
    let scene = scene.map_err(|e| anyhow!(e))?;
    let sampled = match a.model.raster_sample {
        0 => "early termination not sampled (--raster-sample 0: ratio 1)".to_string(),
        k => format!("early termination sampled on one tile in {k}"),
    };
    println!(
        "neo bench model: {spec} ({} Gaussians, made in {wall:.1} s, {cpu:.1} CPU s; not counted), {} frames of orbit at {}x{}, {sampled}, {threads} threads",
        scene.len(),
        a.frames,
        width,
        height
    );
    let sampler = Sampler::start().map_err(|e| eprintln!("neo bench model: no CPU split ({e})")).ok();
    let samples = || sampler.as_ref().map(Sampler::counts).unwrap_or_default();
    let at_start = samples();
    let bar = crate::engine_run::frame_bar(a.frames as u64, false);
    let (wl, gen_cpu, gen_wall) = timed(|| {
        suite::workload(&scene, &point, &cfg, GoldenRaster::Off, a.model.raster_sample, |_| bar.inc(1))
    });
    bar.finish_and_clear();
    let wl = wl.map_err(|e| anyhow!(e))?;
    let n = a.frames as f64;
    println!(
        "workload        {:>7.3} CPU s/frame ({:.3} s wall/frame): golden work-only pipeline (preprocess, binning, Neo's sort, hierarchical record, sampled raster)",
        gen_cpu / n,
        gen_wall / n
    );
    let workload_samples = samples().since(&at_start);
    let (mut neo_cpu, mut neo_samples) = (0.0, None);
    for &arch in &archs {
        let before = samples();
        let (r, cpu, wall) = timed(|| simulate(arch, &cfg, &lat, &wl, RunOptions::default()));
        let r = r.map_err(|e| anyhow!(e))?;
        if arch == Arch::Neo {
            neo_cpu = cpu;
            neo_samples = Some(samples().since(&before));
        }
        println!(
            "model {:<9} {:>7.3} CPU s/frame ({:.3} s wall/frame; {:.1} FPS simulated, {:.2} M DRAM requests/frame)",
            r.arch,
            cpu / n,
            wall / n,
            r.fps,
            r.traffic.total_requests() as f64 / n / 1e6
        );
    }
    let per_frame = (gen_cpu + neo_cpu) / n;
    println!(
        "neo per frame   {per_frame:>7.3} CPU s (workload {:.3} + model {:.3}); target <= {TARGET_CPU_S_PER_FRAME} CPU s: {:.2}x the target, {}",
        gen_cpu / n,
        neo_cpu / n,
        per_frame / TARGET_CPU_S_PER_FRAME,
        verdict(per_frame <= TARGET_CPU_S_PER_FRAME)
    );
    println!(
        "                (issue 13 states {ARTIFACT_CPU_S_PER_FRAME} CPU s per QHD frame of a 500k-Gaussian real scene for the official artifact: {:.0}x that)",
        ARTIFACT_CPU_S_PER_FRAME / per_frame
    );
    if let (Some(_), Some(model)) = (&sampler, neo_samples) {
        print_split(&workload_samples, gen_cpu / n, &model, neo_cpu / n);
    }
    Ok(())
}
