//! `neo simulate`: the cycle model on golden workloads. Every combination of the list-valued
//! options (`--res`, `--sort`, `--chunk`, `--passes`, `--speed`) is one point: one workload,
//! evaluated on every `--arch`. `--shard i/n` runs only the points whose index is `i mod n`, so
//! a sweep runs as independent jobs (Slurm arrays, GNU parallel), each writing its own JSON.
//! The points run as `neo report`'s jobs do ([`run_jobs`]): those that share their cameras (one
//! resolution and speed; any strategies, chunks and passes) generate their workloads in one pass
//! over the frames, and the architectures run while the next workloads are generated; every
//! result is the one the point has alone. The tables are printed in the points' order at the end.

use crate::args::{resolution, FramesArg, ModelArgs, SceneArg, TrajectoryArg};
use crate::points::{check_buffers, load_config, load_latency, log_point, run_jobs, Scenes};
use anyhow::{anyhow, bail, Context, Result};
use clap::Args;
use neo_sim::config::SimConfig;
use neo_sim::driver::GoldenRaster;
use neo_sim::latency::Latency;
use neo_sim::report::point_table;
use neo_sim::report_plan::PointJob;
use neo_sim::run::Arch;
use neo_sim::suite::{self, Grid, Point, PointResult};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Arguments of `neo simulate`.
#[derive(Args)]
pub struct SimulateArgs {
    #[command(flatten)]
    pub scene: SceneArg,
    #[command(flatten)]
    pub trajectory: TrajectoryArg,
    #[command(flatten)]
    pub frames: FramesArg,
    /// Resolutions, comma-separated: `hd`, `fhd`, `qhd` or `WxH`.
    #[arg(long, default_value = "qhd", value_delimiter = ',', value_parser = resolution)]
    pub res: Vec<String>,
    /// Architectures, comma-separated: `neo`, `gscore` (4 and 16 cores), `gscoreN`, `gpu`, `all`.
    #[arg(long, default_value = "all")]
    pub arch: String,
    /// Strategies Neo's hardware runs, comma-separated: `neo`, `full`, `periodic:K`,
    /// `background:K`, `hierarchical`, `adaptive[:budget=B,max=P,resort=0|1,wide=W]`,
    /// `motion:DEG` (adaptive's own comma-separated parameters stay with it).
    #[arg(long, default_value = "neo")]
    pub sort: String,
    /// Chunk sizes (default: the configuration's, 256).
    #[arg(long, value_delimiter = ',')]
    pub chunk: Vec<usize>,
    /// DPS passes per frame, 0 to 16 (default: the configuration's, 1).
    #[arg(long, value_delimiter = ',')]
    pub passes: Vec<usize>,
    /// Camera speed multipliers.
    #[arg(long, default_value = "1", value_delimiter = ',')]
    pub speed: Vec<f64>,
    /// Image quality from the golden raster: `auto` (on for small runs), `off`, `exact` (PSNR
    /// vs the exact order) or `full` (also vs the float reference).
    #[arg(long, default_value = "auto")]
    pub quality: String,
    #[command(flatten)]
    pub model: ModelArgs,
    /// Print JSON instead of tables.
    #[arg(long)]
    pub json: bool,
    /// Also print, per architecture, a table of every frame: interval, engine busy time and
    /// the bytes each stage read and wrote (the `frames` records of `--json`).
    #[arg(long)]
    pub per_frame: bool,
    /// Write one `<point id>.json` per point into this directory.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Run shard `i` of `n` (0-based): the points whose index is `i mod n`.
    #[arg(long)]
    pub shard: Option<String>,
    /// Write `poc.trace` files of the golden pipeline into this directory (turns the golden
    /// raster on).
    #[arg(long)]
    pub trace: Option<PathBuf>,
    /// Frames to trace (default: all).
    #[arg(long, value_delimiter = ',')]
    pub trace_frames: Vec<usize>,
}

/// Parses `--quality`; `auto` turns the golden raster on when `pixels x frames` is small.
fn golden_mode(q: &str, points: &[Point]) -> Result<GoldenRaster> {
    Ok(match q {
        "off" => GoldenRaster::Off,
        "exact" => GoldenRaster::Exact,
        "full" => GoldenRaster::Full,
        "auto" => {
            let work: u64 =
                points.iter().map(|p| p.width as u64 * p.height as u64 * p.frames as u64).max().unwrap_or(0);
            if work <= 640 * 360 * 30 {
                GoldenRaster::Full
            } else {
                GoldenRaster::Off
            }
        }
        other => bail!("--quality '{other}': expected auto, off, exact or full"),
    })
}

/// Runs `neo simulate`.
pub fn run(a: SimulateArgs) -> Result<()> {
    let cfg = load_config(a.model.config.as_deref(), a.model.engine.as_deref(), a.model.sizes.as_deref())?;
    let lat = load_latency(&a.model.latency, &cfg)?;
    let archs = Arch::parse_list(&a.arch, &cfg).map_err(|e| anyhow!(e))?;
    let grid = Grid {
        scenes: vec![a.scene.scene.clone()],
        trajectory: a.trajectory.trajectory.clone(),
        frames: a.frames.frames,
        res: a.res.clone(),
        strategies: neo_golden::pipeline::split_strategies(&a.sort),
        chunks: if a.chunk.is_empty() { vec![cfg.engine.chunk] } else { a.chunk.clone() },
        passes: if a.passes.is_empty() { vec![cfg.pipeline.dps_passes] } else { a.passes.clone() },
        speeds: a.speed.clone(),
        raster_window: cfg.engine.raster_window,
    };
    if a.frames.frames == 0 {
        bail!("--frames must be at least 1");
    }
    for &p in &a.passes {
        neo_golden::pipeline::check_passes(p).map_err(|e| anyhow!("--passes: {e}"))?;
    }
    if grid.strategies.is_empty() {
        bail!("--sort {:?}: no strategy given", a.sort);
    }
    if let Some(f) = a.trace_frames.iter().find(|&&f| f >= a.frames.frames) {
        bail!(
            "--trace-frames {f}: the run has {} frame(s), numbered 0 to {}",
            a.frames.frames,
            a.frames.frames - 1
        );
    }
    let all = grid.points().map_err(|e| anyhow!(e))?;
    let points = match &a.shard {
        Some(s) => {
            let (i, n) = suite::parse_shard(s).map_err(|e| anyhow!(e))?;
            suite::shard(&all, i, n)
        }
        None => all.clone(),
    };
    check_buffers(&a.model, &cfg, points.iter().map(|p| (p, &archs[..])))?;
    let mut golden = golden_mode(&a.quality, &points)?;
    if a.trace.is_some() && golden == GoldenRaster::Off {
        golden = GoldenRaster::Exact;
    }
    if let Some(dir) = &a.out {
        std::fs::create_dir_all(dir)
            .with_context(|| format!("{}: cannot create the directory", dir.display()))?;
    }
    // The scenes first: a bad scene is reported before anything else is printed.
    let mut scenes = Scenes::default();
    for p in &points {
        scenes.get(&p.scene)?;
    }
    if !a.json {
        eprintln!(
            "neo simulate: {} of {} points, archs {}, golden raster {:?}, {}",
            points.len(),
            all.len(),
            archs.iter().map(Arch::name).collect::<Vec<_>>().join(","),
            golden,
            lat.raster_source.label()
        );
        if cfg.sizes != neo_sim::config::DataSizes::default() {
            eprintln!("byte sizes (not neo's defaults): {:?}", cfg.sizes);
        }
        if cfg.engine.raster_window > 1 {
            eprintln!(
                "raster window {} entries: Neo's tiles are blended and written back in its order; its cost is timed as the loads it holds back (docs/cycle-model.md: 3-5% short of the RTL)",
                cfg.engine.raster_window
            );
        }
    }
    let results = match &a.trace {
        Some(dir) => traced_points(&mut scenes, &points, (&cfg, &lat), &archs, golden, dir, &a)?,
        None => shared_points(&mut scenes, &points, (&cfg, &lat), &archs, golden, &a)?,
    };
    for (p, r) in points.iter().zip(&results) {
        if let Some(dir) = &a.out {
            let path = dir.join(format!("{}.json", p.id()));
            let f =
                std::fs::File::create(&path).with_context(|| format!("{}: cannot create", path.display()))?;
            serde_json::to_writer_pretty(std::io::BufWriter::new(f), r)?;
        }
        if !a.json {
            println!("{}", point_table(r));
            if a.per_frame {
                for arch in &r.archs {
                    println!("{}", neo_sim::report::frame_table(arch));
                }
            }
        }
    }
    if a.json && a.out.is_none() {
        println!("{}", serde_json::to_string_pretty(&results)?);
    }
    Ok(())
}

/// The points' results, as `neo report` runs its jobs ([`run_jobs`]): points that share their
/// cameras generate their workloads in one pass over the frames, and the architectures run
/// while the next workloads are generated. Each finished point is logged unless `--json`.
fn shared_points(
    scenes: &mut Scenes,
    points: &[Point],
    (cfg, lat): (&SimConfig, &Latency),
    archs: &[Arch],
    golden: GoldenRaster,
    a: &SimulateArgs,
) -> Result<Vec<PointResult>> {
    let jobs: Vec<PointJob> = points
        .iter()
        .map(|p| PointJob { point: p.clone(), archs: archs.to_vec(), golden, headline: false })
        .collect();
    let started = Instant::now();
    let quiet = a.json;
    let log = move |_: &PointJob, r: &PointResult, label: &str| {
        if !quiet {
            log_point(started, r, label);
        }
    };
    let timed = run_jobs(scenes, &jobs, cfg, lat, a.model.raster_sample, "simulate", &log)?;
    Ok(timed.into_iter().map(|(r, _)| r).collect())
}

/// The points' results through the golden pipeline with its trace export, one after the other.
fn traced_points(
    scenes: &mut Scenes,
    points: &[Point],
    (cfg, lat): (&SimConfig, &Latency),
    archs: &[Arch],
    golden: GoldenRaster,
    dir: &Path,
    a: &SimulateArgs,
) -> Result<Vec<PointResult>> {
    let mut results = Vec::with_capacity(points.len());
    for p in points {
        let scene = scenes.get(&p.scene)?;
        let (mut ws, traj) =
            suite::workload_spec(scene, p, cfg, golden, a.model.raster_sample).map_err(|e| anyhow!(e))?;
        ws.golden_raster = golden;
        ws.trace = Some((dir.join(p.id()), a.trace_frames.clone()));
        let (wl, _) = crate::progress::spin("golden pipeline with trace export", || {
            neo_sim::driver::generate(scene, &traj.frames, &traj.cuts, &ws, |_| {})
        });
        let wl = wl?;
        results.push(suite::evaluate(p, &wl, cfg, lat, archs).map_err(|e| anyhow!(e))?);
        eprintln!("wrote poc.trace files into {}", dir.join(p.id()).display());
    }
    Ok(results)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pt(w: u32, h: u32, frames: usize) -> Point {
        Point {
            scene: "s".into(),
            trajectory: "orbit".into(),
            speed: 1.0,
            frames,
            res: "x".into(),
            width: w,
            height: h,
            strategy: "neo".into(),
            chunk: 256,
            passes: 1,
            raster_window: 1,
        }
    }

    #[test]
    fn quality_auto_runs_the_golden_raster_only_for_small_runs() {
        assert_eq!(golden_mode("auto", &[pt(640, 360, 30)]).unwrap(), GoldenRaster::Full);
        assert_eq!(golden_mode("auto", &[pt(2560, 1440, 30)]).unwrap(), GoldenRaster::Off);
        assert_eq!(golden_mode("exact", &[pt(2560, 1440, 30)]).unwrap(), GoldenRaster::Exact);
        assert!(golden_mode("maybe", &[]).is_err());
    }
}
