//! `neo report`: the README's main job. Runs the default suite on the default synthetic scene
//! (plus any `--scene`) and writes `reports/index.md` with its SVG figures: throughput per
//! resolution and architecture (paper Fig. 15), DRAM traffic by stage (Fig. 16), frame times of
//! the sorting strategies on Neo's hardware (Fig. 19), and speed against error over strategies,
//! chunk sizes, DPS passes and camera speeds with its Pareto front (and `neo` with the raster
//! cores' reorder windows of `--sweep-window`).
//!
//! The plan (which points, in which order, the report data) is `neo_sim::report_plan`; this
//! command parses its options, runs the plan with progress bars and writes the files.

use crate::args::{resolution, ModelArgs, TrajectoryArg};
use crate::points::{check_buffers, load_config, load_latency, ProgressRunner, Scenes};
use anyhow::{anyhow, bail, Context, Result};
use clap::Args;
use neo_sim::report::render;
use neo_sim::report_plan::{parse_sweep_windows, read_point_results, ReportPlan, ReportSpec, SweepSpec};
use std::path::{Path, PathBuf};
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
    /// Frames of the throughput, traffic and timeline runs (default: 8, or 60 with `--full`).
    #[arg(long)]
    pub frames: Option<usize>,
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
    /// Frames per sweep point (default: 4, or 12 with `--full`).
    #[arg(long)]
    pub sweep_frames: Option<usize>,
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
    /// DPS passes of the sweep, each 0 to 16.
    #[arg(long, default_value = "1,2", value_delimiter = ',')]
    pub sweep_passes: Vec<usize>,
    /// Camera speeds of the sweep.
    #[arg(long, default_value = "1,2,4,8,16", value_delimiter = ',')]
    pub sweep_speed: Vec<f64>,
    /// Raster-core reorder windows of the sweep (entries, powers of two in 4..=4096): for each,
    /// `neo` at chunk 256 and one DPS pass at every speed with that window (docs/adaptive.md
    /// section 7); empty or 1: none.
    #[arg(long, default_value = "256")]
    pub sweep_window: String,
    /// Use the point results (`*.json` from `neo simulate --out DIR`) in this directory for the
    /// sweep instead of running it.
    #[arg(long)]
    pub sweep_results: Option<PathBuf>,
    /// Skip the sweep.
    #[arg(long)]
    pub no_sweep: bool,
    /// The paper-scale run: 60 frames per throughput, traffic and timeline run (the paper's
    /// 60-frame sequences), 12 per sweep point (each default is overridden by its own option).
    #[arg(long)]
    pub full: bool,
    #[command(flatten)]
    pub model: ModelArgs,
    /// Leave the default scene out (only the `--scene`s; for quick checks).
    #[arg(long, hide = true)]
    pub no_default_scene: bool,
}

/// Frames per throughput, traffic and timeline run: by default, and with `--full`.
pub const FRAMES: (usize, usize) = (8, 60);

/// Frames per sweep point: by default, and with `--full`.
pub const SWEEP_FRAMES: (usize, usize) = (4, 12);

impl ReportArgs {
    /// `default`'s first value, or its second with `--full`, unless `given`.
    fn scaled(&self, given: Option<usize>, default: (usize, usize)) -> usize {
        given.unwrap_or(if self.full { default.1 } else { default.0 })
    }

    /// The report's plan specification; a bad `--sweep-window` or `--sweep-passes` is refused.
    fn spec(&self) -> Result<ReportSpec> {
        let windows = parse_sweep_windows(&self.sweep_window).map_err(|e| anyhow!(e))?;
        for &p in &self.sweep_passes {
            neo_golden::pipeline::check_passes(p).map_err(|e| anyhow!("--sweep-passes: {e}"))?;
        }
        let sweep = (!self.no_sweep && self.sweep_results.is_none()).then(|| SweepSpec {
            scene: self.sweep_scene.clone(),
            res: self.sweep_res.clone(),
            frames: self.scaled(self.sweep_frames, SWEEP_FRAMES),
            strategies: self.sweep_sort.clone(),
            chunks: self.sweep_chunk.clone(),
            passes: self.sweep_passes.clone(),
            speeds: self.sweep_speed.clone(),
            windows,
        });
        Ok(ReportSpec {
            scenes: self.scene.clone(),
            default_scene: !self.no_default_scene,
            trajectory: self.trajectory.trajectory.clone(),
            frames: self.scaled(self.frames, FRAMES),
            res: self.res.clone(),
            timeline_res: self.timeline_res.clone(),
            timeline_sort: self.timeline_sort.clone(),
            sweep,
            raster_sample: self.model.raster_sample,
        })
    }
}

fn peak_rss_mb() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = s.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb / 1024.0)
}

/// Writes the report's files (`(name, text)`) into `out` as a whole: every file is written under
/// a temporary name first and each target checked, then all are renamed; so a file that cannot
/// be written leaves the previous report as it was, not half old and half new.
fn write_report(out: &Path, files: &[(String, String)]) -> Result<()> {
    let tmp = |name: &str| out.join(format!(".{name}.tmp"));
    let staged = (|| -> Result<()> {
        for (name, text) in files {
            let target = out.join(name);
            if target.is_dir() {
                bail!("{}: is a directory, cannot write the report's file there", target.display());
            }
            std::fs::write(tmp(name), text).with_context(|| format!("{}: cannot write", target.display()))?;
        }
        Ok(())
    })();
    if let Err(e) = staged {
        for (name, _) in files {
            let _ = std::fs::remove_file(tmp(name));
        }
        return Err(e);
    }
    for (name, _) in files {
        let target = out.join(name);
        std::fs::rename(tmp(name), &target).with_context(|| format!("{}: cannot write", target.display()))?;
    }
    Ok(())
}

/// Runs `neo report`.
pub fn run(a: ReportArgs) -> Result<()> {
    let t0 = Instant::now();
    let spec = a.spec()?;
    let cfg = load_config(a.model.config.as_deref(), a.model.engine.as_deref(), a.model.sizes.as_deref())?;
    let lat = load_latency(&a.model.latency, &cfg)?;
    let plan = ReportPlan::new(spec, &cfg).map_err(|e| anyhow!(e))?;
    let jobs = plan.point_jobs();
    check_buffers(&a.model, &cfg, jobs.iter().map(|j| (&j.point, &j.archs[..])))?;
    // Before any work: an --out that cannot be a directory fails now, not after the runs.
    std::fs::create_dir_all(&a.out).with_context(|| format!("{}: cannot create", a.out.display()))?;
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
    let mut files = vec![("index.md".to_string(), md)];
    files.extend(svgs.iter().cloned());
    write_report(&a.out, &files)?;
    println!("wrote {} and {} figures", a.out.join("index.md").display(), svgs.len());
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

    #[derive(clap::Parser)]
    struct Cli {
        #[command(subcommand)]
        command: Top,
    }

    #[derive(clap::Subcommand)]
    enum Top {
        Report(ReportArgs),
    }

    fn spec_of(args: &[&str]) -> ReportSpec {
        use clap::Parser;
        let argv = ["neo", "report"].into_iter().chain(args.iter().copied());
        let Top::Report(a) = Cli::try_parse_from(argv).expect("parses").command;
        a.spec().expect("a valid spec")
    }

    #[test]
    fn full_scales_the_frames_unless_they_are_given() {
        let frames = |s: ReportSpec| (s.frames, s.sweep.expect("a sweep").frames);
        assert_eq!(frames(spec_of(&[])), (FRAMES.0, SWEEP_FRAMES.0));
        assert_eq!(frames(spec_of(&["--full"])), (FRAMES.1, SWEEP_FRAMES.1));
        assert_eq!(frames(spec_of(&["--full", "--frames", "7"])), (7, SWEEP_FRAMES.1));
        assert_eq!(frames(spec_of(&["--sweep-frames", "3"])), (FRAMES.0, 3));
        assert!(FRAMES.0 < FRAMES.1 && SWEEP_FRAMES.0 < SWEEP_FRAMES.1);
    }

    #[test]
    fn sweep_window_defaults_to_256_and_empty_or_1_is_none() {
        let windows = |args: &[&str]| spec_of(args).sweep.expect("a sweep").windows;
        assert_eq!(windows(&[]), [256]);
        assert_eq!(windows(&["--sweep-window", "1024,4096"]), [1024, 4096]);
        assert!(windows(&["--sweep-window", ""]).is_empty());
        assert!(windows(&["--sweep-window", "1"]).is_empty());
    }

    /// `--sweep-passes` has the limit of every `--passes` (16).
    #[test]
    fn sweep_passes_are_bounded_like_every_passes_flag() {
        assert_eq!(spec_of(&["--sweep-passes", "0,16"]).sweep.expect("a sweep").passes, [0, 16]);
        use clap::Parser;
        let argv = ["neo", "report", "--sweep-passes", "1,17"];
        let Top::Report(a) = Cli::try_parse_from(argv).expect("parses").command;
        let e = format!("{:#}", a.spec().unwrap_err());
        assert!(e.contains("--sweep-passes") && e.contains("limit of 16"), "{e}");
    }

    /// A report file that cannot be written (a directory stands at its name) fails before any
    /// file of the previous report changes, and leaves no temporary file.
    #[test]
    fn a_report_is_written_whole_or_not_at_all() {
        let dir = tempfile::tempdir().unwrap();
        let files =
            |v: &str| vec![("index.md".to_string(), v.to_string()), ("fig.svg".to_string(), v.to_string())];
        write_report(dir.path(), &files("old")).unwrap();
        std::fs::remove_file(dir.path().join("fig.svg")).unwrap();
        std::fs::create_dir(dir.path().join("fig.svg")).unwrap();
        let e = format!("{:#}", write_report(dir.path(), &files("new")).unwrap_err());
        assert!(e.contains("fig.svg") && e.contains("directory"), "{e}");
        assert_eq!(std::fs::read_to_string(dir.path().join("index.md")).unwrap(), "old");
        let names: Vec<String> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into())
            .collect();
        assert!(names.iter().all(|n| !n.ends_with(".tmp")), "{names:?}");
        std::fs::remove_dir(dir.path().join("fig.svg")).unwrap();
        write_report(dir.path(), &files("new")).unwrap();
        assert_eq!(std::fs::read_to_string(dir.path().join("fig.svg")).unwrap(), "new");
    }

    #[test]
    fn a_tiny_report_writes_index_and_figures() {
        let dir = tempfile::tempdir().unwrap();
        let args = ReportArgs {
            scene: vec!["synthetic:outdoor?gaussians=10k&seed=2".into()],
            out: dir.path().to_path_buf(),
            trajectory: TrajectoryArg { trajectory: "orbit".into() },
            frames: Some(3),
            res: vec!["128x64".into()],
            timeline_res: "128x64".into(),
            timeline_sort: vec!["periodic:2".into()],
            sweep_scene: "synthetic:outdoor?gaussians=10k&seed=1".into(),
            sweep_res: "128x64".into(),
            sweep_frames: Some(2),
            sweep_sort: vec!["neo".into(), "hierarchical".into()],
            sweep_chunk: vec![64],
            sweep_passes: vec![1],
            sweep_speed: vec![1.0],
            sweep_window: "64".into(),
            sweep_results: None,
            no_sweep: false,
            full: false,
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
            "(paper Fig. 18)",
            "neos16",
            "## 3. Sorting strategies",
            "periodic:2",
            "## 4. Speed against error",
            "hierarchical",
            "| neo + window 64 | ",
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
