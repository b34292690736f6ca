//! `neo bench engine`: the full engine verilated and run on whole frames (issue 11's
//! performance figures; a benchmark, never a CI test).
//!
//! The model is built (or found in the cache) as `neo cosim` builds it, untraced, with
//! Verilator's `--threads N`; the build's wall and CPU time and peak memory are read from the
//! children's resource usage. The frames run through the `neo cosim` harness
//! ([`crate::engine_run`]) with the same bit-exact checks.

use crate::args::{StrictArg, TrajectoryArg};
use crate::engine_run;
use crate::progress::self_cpu;
use anyhow::{anyhow, bail, Result};
use clap::Args;
use neo_golden::engine::cases::CaseScene;
use neo_golden::engine::{HostMode, SessionOptions};
use neo_golden::pipeline::Strategy;
use neo_golden::{shared, source};
use neo_tb::axi::AxiTiming;
use neo_tb::engine::{EngineRig, RunOptions};
use std::path::PathBuf;
use std::time::Instant;

/// The speed target: simulated cycles per second of the whole engine on one core.
const TARGET_CYCLES_PER_S: f64 = 50e3;

/// `--scene biker`: the shared biker scene (compressed .ply).
const BIKER: &str = "scenes/biker.compressed.ply";

/// Arguments of `neo bench engine`.
#[derive(Args)]
pub struct EngineBenchArgs {
    /// Scene: a .ply, a synthetic spec, or `biker` (the shared biker scene, at 640x480 unless
    /// `--res` says otherwise). The default is a box of random Gaussians that gives every tile
    /// of a 256x256 frame (16 tiles: one per sorting core) work.
    #[arg(long, default_value = CaseScene::SYNTHETIC)]
    pub scene: String,
    #[command(flatten)]
    pub trajectory: TrajectoryArg,
    /// Frames to run (frame 0 sorts from scratch, the others reuse the tables).
    #[arg(long, default_value_t = 2)]
    pub frames: usize,
    /// Resolution `WxH` (default 256x256; 640x480 for `--scene biker`).
    #[arg(long, value_parser = neo_golden::trajectory::parse_resolution)]
    pub res: Option<(u32, u32)>,
    /// Engine configuration (the JSON `neo gen --config` takes); default: the 16 + 4 engine.
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// Verilator threads of the model (`--threads N`; each count is its own cached build), at
    /// most the machine's cores.
    #[arg(long, default_value_t = 1)]
    pub threads: usize,
    /// Seed of the harness's random memory timing (default: from the clock; printed).
    #[arg(long)]
    pub seed: Option<String>,
    #[command(flatten)]
    pub strict: StrictArg,
}

/// Refuses a thread count the model cannot run with: 0, or more than `cores` (Verilator's
/// context takes the machine's hardware threads and refuses a model verilated for more).
pub fn check_threads(threads: usize, cores: usize) -> Result<()> {
    if threads == 0 {
        bail!("--threads 0: a model needs at least one thread");
    }
    if threads > cores {
        bail!("--threads {threads}: this machine has {cores} hardware threads (Verilator refuses more)");
    }
    Ok(())
}

/// The scene to load and the resolution: `biker` is the shared scene at 640x480.
fn scene_and_res(a: &EngineBenchArgs) -> Result<(String, (u32, u32))> {
    if a.scene == "biker" {
        let p = shared::shared_dir_path().join(BIKER);
        if !p.is_file() {
            bail!("--scene biker: {} not found (set NEO_SHARED to the shared directory)", p.display());
        }
        return Ok((p.display().to_string(), a.res.unwrap_or((640, 480))));
    }
    Ok((a.scene.clone(), a.res.unwrap_or((256, 256))))
}

/// Resource usage of the children waited for so far: (user + system CPU seconds, peak RSS in
/// bytes of the largest one).
fn children_usage() -> (f64, u64) {
    // SAFETY: getrusage only writes the struct it is given.
    let mut u: libc::rusage = unsafe { std::mem::zeroed() };
    // SAFETY: `u` is a valid rusage to fill.
    if unsafe { libc::getrusage(libc::RUSAGE_CHILDREN, &mut u) } != 0 {
        return (0.0, 0);
    }
    let secs = |t: libc::timeval| t.tv_sec as f64 + t.tv_usec as f64 * 1e-6;
    // Linux reports ru_maxrss in KiB.
    (secs(u.ru_utime) + secs(u.ru_stime), u.ru_maxrss.max(0) as u64 * 1024)
}

/// The target against `cycles` simulated in `wall` seconds using `cpu` CPU seconds: the wall
/// rate (what a user waits) and the rate per CPU second (what one core does when the machine is
/// shared), each with its ratio and verdict.
fn against_target(cycles: u64, wall: f64, cpu: f64) -> String {
    let rate = |s: f64| cycles as f64 / s.max(1e-9);
    let (w, c) = (rate(wall), rate(cpu));
    format!(
        "{:.1} kcycles/s, {:.1} kcycles per CPU s; target >= {:.0} kcycles/s on one core: wall {:.2}x, {}; per CPU s {:.2}x, {}",
        w / 1e3,
        c / 1e3,
        TARGET_CYCLES_PER_S / 1e3,
        w / TARGET_CYCLES_PER_S,
        super::verdict(w >= TARGET_CYCLES_PER_S),
        c / TARGET_CYCLES_PER_S,
        super::verdict(c >= TARGET_CYCLES_PER_S)
    )
}

/// Runs `neo bench engine`.
pub fn run(a: EngineBenchArgs) -> Result<()> {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    check_threads(a.threads, cores)?;
    let cfg = engine_run::engine_config(a.config.as_deref())?;
    let seed = match &a.seed {
        Some(s) => neo_tb::rng::parse_seed(s).ok_or_else(|| anyhow!("--seed {s:?} is not a number"))?,
        None => neo_tb::rng::test_seed("neo bench engine"),
    };
    let (spec, res) = scene_and_res(&a)?;
    let (scene, _) = source::load_scene(&spec, a.strict.strict)?;
    let traj = engine_run::trajectory_at(&a.trajectory.trajectory, &scene, a.frames, res)?;
    let opts = SessionOptions { mode: HostMode::Lists, strategy: Strategy::Neo, ..SessionOptions::default() };
    let mut session = engine_run::session(&scene, traj, &cfg, opts)?;
    println!(
        "neo bench engine: {} + {} cores, {} ports (config 0x{:016x}), {} Verilator thread(s) on a {cores}-core machine; \
         {spec} ({} Gaussians) at {}x{}, {} tiles, {} frames, seed 0x{seed:016x}",
        cfg.sort_cores,
        cfg.raster_cores,
        cfg.mem_channels,
        cfg.hash(),
        a.threads,
        scene.len(),
        res.0,
        res.1,
        session.tiles(),
        session.frames(),
    );

    let (cpu0, _) = children_usage();
    let t0 = Instant::now();
    let engine = engine_run::build_engine(&cfg, None, a.threads)?;
    let wall = t0.elapsed().as_secs_f64();
    let (cpu1, peak) = children_usage();
    let b = &engine.build;
    let dir = b.library.parent().map_or(String::new(), |d| d.display().to_string());
    if b.cached {
        println!("engine build    cached ({dir}), loaded in {wall:.1} s; run from an empty cache entry to measure the build");
    } else {
        println!(
            "engine build    {wall:>9.1} s wall, {:.1} s CPU (Verilator + C++ compiler), peak RSS {:.2} GB (largest child); {} ({dir})",
            cpu1 - cpu0,
            peak as f64 / 1e9,
            b.log
        );
    }

    let opts = RunOptions { timing: AxiTiming::RANDOM, ..RunOptions::default() };
    let mut rig = EngineRig::new(engine, opts, seed, None).map_err(|e| anyhow!(e))?;
    let bar = engine_run::frame_bar(session.frames() as u64, false);
    let (mut cycles, mut seconds, mut cpu) = (0u64, 0f64, 0f64);
    let failed = engine_run::run_frames(
        &mut session,
        &mut rig,
        |_, _| Ok(self_cpu()),
        |f| {
            let c = self_cpu() - f.before;
            bar.inc(1);
            let r = &f.report;
            let s = f.took.as_secs_f64();
            cycles += r.harness_cycles;
            seconds += s;
            cpu += c;
            let status = crate::engine_run::frame_status(r);
            let line = format!(
                "engine frame {:<3}{:>9.1} s/frame ({status}{}, {} RTL cycles, {} with the harness, {:.1} CPU s; {})",
                r.frame,
                s,
                if r.from_scratch { ", from scratch" } else { "" },
                r.rtl_cycles,
                r.harness_cycles,
                c,
                against_target(r.harness_cycles, s, c)
            );
            bar.suspend(|| println!("{line}"));
        },
    );
    bar.finish_and_clear();
    if let Some(f) = failed? {
        bail!("frame {f} is not bit-exact (seed 0x{seed:016x}; replay with --seed 0x{seed:016x})");
    }
    println!(
        "engine overall  {:>9.1} s/frame ({} frames, {} Verilator thread(s); {})",
        seconds / a.frames.max(1) as f64,
        a.frames,
        a.threads,
        against_target(cycles, seconds, cpu)
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    #[derive(Parser)]
    struct Cli {
        #[command(subcommand)]
        command: Top,
    }

    #[derive(clap::Subcommand)]
    enum Top {
        Bench(super::super::BenchArgs),
    }

    fn parse(args: &[&str]) -> Result<super::super::BenchArgs, clap::Error> {
        let argv = std::iter::once("neo").chain(std::iter::once("bench")).chain(args.iter().copied());
        Cli::try_parse_from(argv).map(|c| match c.command {
            Top::Bench(b) => b,
        })
    }

    #[test]
    fn bench_without_a_subcommand_keeps_its_arguments() {
        let b = parse(&["--gaussians", "1000", "--repeat", "1"]).expect("parses");
        assert!(b.command.is_none());
        assert_eq!((b.gaussians, b.repeat), (1000, 1));
    }

    #[test]
    fn bench_engine_parses_its_options() {
        let b = parse(&["engine", "--threads", "2", "--frames", "3", "--res", "320x240"]).expect("parses");
        let Some(super::super::BenchCommand::Engine(e)) = b.command else { panic!("no engine subcommand") };
        assert_eq!((e.threads, e.frames, e.res), (2, 3, Some((320, 240))));
        let (spec, res) = scene_and_res(&e).expect("synthetic scene");
        assert_eq!((spec.as_str(), res), (CaseScene::SYNTHETIC, (320, 240)));
        let d = parse(&["engine"]).expect("parses");
        let Some(super::super::BenchCommand::Engine(d)) = d.command else { panic!("no engine subcommand") };
        assert_eq!((d.threads, d.frames, d.res, d.config.as_deref()), (1, 2, None, None));
        assert_eq!(scene_and_res(&d).expect("default").1, (256, 256));
    }

    #[test]
    fn bench_options_do_not_mix_with_the_engine_subcommand() {
        assert!(parse(&["--gaussians", "10", "engine"]).is_err());
        assert!(parse(&["engine", "--gaussians", "10"]).is_err());
        assert!(parse(&["engine", "--threads", "two"]).is_err());
    }

    #[test]
    fn the_target_is_judged_on_wall_and_cpu_time() {
        let t = against_target(100_000, 4.0, 1.0);
        assert!(t.contains("25.0 kcycles/s") && t.contains("100.0 kcycles per CPU s"), "{t}");
        assert!(t.contains("wall 0.50x, MISSES target; per CPU s 2.00x, meets target"), "{t}");
    }

    #[test]
    fn thread_counts_are_checked_against_the_cores() {
        assert!(check_threads(1, 1).is_ok());
        assert!(check_threads(2, 2).is_ok());
        let e = check_threads(0, 2).unwrap_err().to_string();
        assert!(e.contains("--threads 0"), "{e}");
        let e = check_threads(3, 2).unwrap_err().to_string();
        assert!(e.contains("--threads 3") && e.contains("2 hardware threads"), "{e}");
    }
}
