//! `neo report`: the README's main job. Runs the default suite on the default synthetic scene
//! (plus any `--scene`) and writes `reports/index.md` with its SVG figures: throughput per
//! resolution and architecture (paper Fig. 15), DRAM traffic by stage (Fig. 16), frame times of
//! the sorting strategies on Neo's hardware (Fig. 19), and speed against error over strategies,
//! chunk sizes, DPS passes and camera speeds with its Pareto front.
//!
//! The plan (which points, in which order, the report data) is `neo_sim::report_plan`; this
//! command parses its options, runs the plan with progress bars and writes the files.

use crate::args::{resolution, ModelArgs, TrajectoryArg};
use crate::points::{load_config, load_latency, ProgressRunner, Scenes};
use anyhow::{anyhow, Context, Result};
use clap::Args;
use neo_sim::report::render;
use neo_sim::report_plan::{read_point_results, ReportPlan, ReportSpec, SweepSpec};
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `neo report`.
#[derive(Args)]
pub struct ReportArgs {
    /// Scenes to add to the default synthetic scene (files or synthetic specs; repeatable).
    #[arg(long)]
    pub scene: Vec<String>,
    /// Output directory of `index.md` and the figures.
    #[arg(long, default_value = "reports")]
    pub out: PathBuf,
    #[command(flatten)]
    pub trajectory: TrajectoryArg,
    /// Frames of the throughput, traffic and timeline runs.
    #[arg(long, default_value_t = 24)]
    pub frames: usize,
    /// Resolutions of the throughput and traffic runs.
    #[arg(long, default_value = "hd,fhd,qhd", value_delimiter = ',', value_parser = resolution)]
    pub res: Vec<String>,
    /// Resolution of the strategy timelines (Fig. 19).
    #[arg(long, default_value = "fhd", value_parser = resolution)]
    pub timeline_res: String,
    /// Strategies compared with `neo` in the timelines.
    #[arg(long, default_value = "periodic:4,background:2,hierarchical", value_delimiter = ',')]
    pub timeline_sort: Vec<String>,
    /// Scene of the speed/error sweep (smaller: every point runs the golden raster twice per
    /// frame for its PSNR).
    #[arg(long, default_value = "synthetic:outdoor?gaussians=100k&seed=1")]
    pub sweep_scene: String,
    /// Resolution of the sweep.
    #[arg(long, default_value = "448x256", value_parser = resolution)]
    pub sweep_res: String,
    /// Frames per sweep point.
    #[arg(long, default_value_t = 5)]
    pub sweep_frames: usize,
    /// Strategies of the sweep.
    #[arg(
        long,
        default_value = "neo,periodic:4,background:2,hierarchical,adaptive,motion:5",
        value_delimiter = ','
    )]
    pub sweep_sort: Vec<String>,
    /// Chunk sizes of the sweep.
    #[arg(long, default_value = "64,128,256,512", value_delimiter = ',')]
    pub sweep_chunk: Vec<usize>,
    /// DPS passes of the sweep.
    #[arg(long, default_value = "1,2", value_delimiter = ',')]
    pub sweep_passes: Vec<usize>,
    /// Camera speeds of the sweep.
    #[arg(long, default_value = "1,2,4,8,16", value_delimiter = ',')]
    pub sweep_speed: Vec<f64>,
    /// Use the point results (`*.json` from `neo simulate --out DIR`) in this directory for the
    /// sweep instead of running it.
    #[arg(long)]
    pub sweep_results: Option<PathBuf>,
    /// Skip the sweep.
    #[arg(long)]
    pub no_sweep: bool,
    #[command(flatten)]
    pub model: ModelArgs,
    /// Leave the default scene out (only the `--scene`s; for quick checks).
    #[arg(long, hide = true)]
    pub no_default_scene: bool,
}

impl ReportArgs {
    /// The report's plan specification.
    fn spec(&self) -> ReportSpec {
        let sweep = (!self.no_sweep && self.sweep_results.is_none()).then(|| SweepSpec {
            scene: self.sweep_scene.clone(),
            res: self.sweep_res.clone(),
            frames: self.sweep_frames,
            strategies: self.sweep_sort.clone(),
            chunks: self.sweep_chunk.clone(),
            passes: self.sweep_passes.clone(),
            speeds: self.sweep_speed.clone(),
        });
        ReportSpec {
            scenes: self.scene.clone(),
            default_scene: !self.no_default_scene,
            trajectory: self.trajectory.trajectory.clone(),
            frames: self.frames,
            res: self.res.clone(),
            timeline_res: self.timeline_res.clone(),
            timeline_sort: self.timeline_sort.clone(),
            sweep,
            raster_sample: self.model.raster_sample,
        }
    }
}

fn peak_rss_mb() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = s.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb / 1024.0)
}

/// Runs `neo report`.
pub fn run(a: ReportArgs) -> Result<()> {
    let t0 = Instant::now();
    let cfg = load_config(a.model.config.as_deref(), a.model.engine.as_deref(), a.model.sizes.as_deref())?;
    let lat = load_latency(&a.model.latency, &cfg)?;
    let plan = ReportPlan::new(a.spec(), &cfg).map_err(|e| anyhow!(e))?;
    let sweep_results = match &a.sweep_results {
        Some(dir) => read_point_results(dir).map_err(|e| anyhow!(e))?,
        None => Vec::new(),
    };
    eprintln!(
        "neo report: {} throughput runs, {} strategy timelines, {} sweep points; {}",
        plan.headline.len(),
        plan.timelines.len() + 1,
        plan.sweep.len(),
        lat.raster_source.label()
    );
    let mut runner =
        ProgressRunner { scenes: Scenes::default(), cfg: &cfg, lat: &lat, started: Instant::now() };
    let (data, times) = plan.run(&mut runner, &lat, sweep_results).map_err(|e| anyhow!(e))?;
    let (md, svgs) = render(&data).map_err(|e| anyhow!(e))?;
    std::fs::create_dir_all(&a.out).with_context(|| format!("{}: cannot create", a.out.display()))?;
    let index = a.out.join("index.md");
    std::fs::write(&index, md).with_context(|| format!("{}: cannot write", index.display()))?;
    for (name, svg) in &svgs {
        let p = a.out.join(name);
        std::fs::write(&p, svg).with_context(|| format!("{}: cannot write", p.display()))?;
    }
    println!("wrote {} and {} figures", index.display(), svgs.len());
    println!(
        "time: throughput {:.0} s, timelines {:.0} s more, sweep {:.0} s more, total {:.0} s wall, {:.0} s CPU; peak memory {}",
        times.headline_s,
        times.timelines_s,
        times.sweep_s,
        t0.elapsed().as_secs_f64(),
        crate::progress::self_cpu(),
        peak_rss_mb().map_or("unknown".into(), |m| format!("{m:.0} MB"))
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use neo_sim::latency;

    #[test]
    fn a_tiny_report_writes_index_and_figures() {
        let dir = tempfile::tempdir().unwrap();
        let args = ReportArgs {
            scene: vec!["synthetic:outdoor?gaussians=10k&seed=2".into()],
            out: dir.path().to_path_buf(),
            trajectory: TrajectoryArg { trajectory: "orbit".into() },
            frames: 3,
            res: vec!["128x64".into()],
            timeline_res: "128x64".into(),
            timeline_sort: vec!["periodic:2".into()],
            sweep_scene: "synthetic:outdoor?gaussians=10k&seed=1".into(),
            sweep_res: "128x64".into(),
            sweep_frames: 2,
            sweep_sort: vec!["neo".into(), "hierarchical".into()],
            sweep_chunk: vec![64],
            sweep_passes: vec![1],
            sweep_speed: vec![1.0],
            sweep_results: None,
            no_sweep: false,
            model: ModelArgs {
                config: None,
                engine: None,
                latency: PathBuf::from(latency::DEFAULT_PATH),
                raster_sample: 4,
                sizes: None,
            },
            no_default_scene: true,
        };
        run(args).unwrap();
        let md = std::fs::read_to_string(dir.path().join("index.md")).unwrap();
        for needle in [
            "## 1. Throughput",
            "gscore16",
            "## 2. DRAM traffic",
            "## 3. Sorting strategies",
            "periodic:2",
            "## 4. Speed against error",
            "hierarchical",
        ] {
            assert!(md.contains(needle), "index.md lacks {needle}");
        }
        for f in ["fig15_fps_0.svg", "fig16_dram_0.svg", "fig19_timeline.svg", "sweep_pareto.svg"] {
            let svg = std::fs::read_to_string(dir.path().join(f)).unwrap();
            assert!(svg.starts_with("<svg"), "{f}");
            assert!(md.contains(f), "index.md links {f}");
        }
    }
}
