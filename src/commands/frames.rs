//! `neo frames`: the bit-exact golden pipeline along a trajectory, with a sorting strategy;
//! writes `stats.json` (and optionally PNGs, per-tile statistics and `poc.trace` files).

use crate::args::{FramesArg, SceneArg, StrictArg, TrajectoryArg};
use crate::progress::spin;
use anyhow::{bail, Context, Result};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use neo_golden::pipeline::{
    formats_for, run_trajectory, ConfigRecord, FrameOutput, Pipeline, PipelineConfig, Preprocessing, RunInfo,
    StatsFile, Strategy,
};
use neo_golden::trajectory::parse_resolution;
use neo_golden::{source, trajectory};
use std::fs;
use std::io::{BufWriter, Write};
use std::path::PathBuf;
use std::time::Duration;

/// Arguments of `neo frames`.
#[derive(Args)]
pub struct FramesArgs {
    #[command(flatten)]
    pub scene: SceneArg,
    #[command(flatten)]
    pub trajectory: TrajectoryArg,
    #[command(flatten)]
    pub frames: FramesArg,
    /// Resolution: `hd` (1280x720), `fhd` (1920x1080), `qhd` (2560x1440) or `WxH`; default:
    /// the trajectory's own.
    #[arg(long, value_parser = parse_resolution)]
    pub res: Option<(u32, u32)>,
    /// Sorting strategy: `neo`, `full`, `periodic:K`, `background:K`, `hierarchical`,
    /// `adaptive[:budget=B,max=P,resort=0|1,wide=W]` or `motion:DEG` (docs/adaptive.md).
    #[arg(long, default_value = "neo")]
    pub sort: String,
    /// Output directory (created).
    #[arg(long)]
    pub out: PathBuf,
    /// Write every frame as `frame_NNNNN.png`.
    #[arg(long)]
    pub png: bool,
    /// Write `trace/frame_NNNNN.poc.trace` for every frame (or the `--trace-frames` ones).
    #[arg(long)]
    pub trace: bool,
    /// Frames to trace, comma-separated (implies `--trace`).
    #[arg(long, value_delimiter = ',')]
    pub trace_frames: Vec<usize>,
    /// Write per-tile statistics to `tiles.jsonl` (one line per frame).
    #[arg(long)]
    pub tile_stats: bool,
    /// Chunk size of DPS and the conventional sort.
    #[arg(long, default_value_t = 256)]
    pub chunk: usize,
    /// DPS passes per frame.
    #[arg(long, default_value_t = 1)]
    pub passes: usize,
    /// Entries in the raster core's reorder window, which blends and writes back each tile in
    /// the order of the current depth keys within that reach (1: none, the paper's engine;
    /// docs/adaptive.md section 7).
    #[arg(long, default_value_t = 1)]
    pub raster_window: usize,
    /// Largest table per tile (default: unbounded).
    #[arg(long)]
    pub capacity: Option<usize>,
    /// Fit the feature ranges, the depth key range and the id width to the run.
    #[arg(long)]
    pub fitted: bool,
    /// Tile side in pixels.
    #[arg(long, default_value_t = 64)]
    pub tile: u32,
    /// Subtile side in pixels.
    #[arg(long, default_value_t = 8)]
    pub subtile: u32,
    /// Skip the exact-order reference frame (no psnr_vs_exact).
    #[arg(long)]
    pub no_exact: bool,
    /// Skip the float reference render (no psnr_vs_float).
    #[arg(long)]
    pub no_float: bool,
    /// Skip SSIM.
    #[arg(long)]
    pub no_ssim: bool,
    /// Preprocessing: `hw` (the RTL's arithmetic on the baked scene, SH f32; `hw:f16` with
    /// half SH) or `float` (the float preprocess quantised in f64, for comparison).
    #[arg(long, default_value = "hw", value_parser = Preprocessing::parse)]
    pub preprocess: Preprocessing,
    #[command(flatten)]
    pub strict: StrictArg,
}

fn opt(v: Option<f64>) -> String {
    v.map_or("-".to_string(), |x| format!("{x:.2}"))
}

/// Runs `neo frames`.
pub fn run(a: FramesArgs) -> Result<()> {
    let strategy: Strategy = a.sort.parse().map_err(anyhow::Error::msg)?;
    let scene_spec = &a.scene.scene;
    let (loaded, _) =
        spin(&format!("loading {scene_spec}"), || source::load_scene(scene_spec, a.strict.strict));
    let (scene, report) = loaded?;
    if report.dropped_non_finite > 0 {
        eprintln!("warning: dropped {} Gaussians with NaN values", report.dropped_non_finite);
    }
    let traj_spec = &a.trajectory.trajectory;
    let mut traj = trajectory::parse_trajectory(traj_spec, source::robust_bounds(&scene), a.frames.frames)?;
    if let Some((w, h)) = a.res {
        traj = traj.with_resolution(w, h);
    }
    let n = traj.len();
    if n == 0 {
        bail!("trajectory '{traj_spec}' has no frames");
    }
    let mut cfg = PipelineConfig {
        strategy,
        chunk: a.chunk,
        dps_passes: a.passes,
        raster_window: a.raster_window,
        capacity: a.capacity,
        compare_exact: !a.no_exact,
        compare_float: !a.no_float,
        ssim: !a.no_ssim,
        preprocess: a.preprocess,
        ..PipelineConfig::default()
    };
    cfg.raster.tile = a.tile;
    cfg.raster.subtile = a.subtile;
    cfg.check_window().context("--raster-window")?;
    let (formats, _) = spin("choosing number formats", || formats_for(&scene, &traj.frames, &cfg, a.fitted));
    let formats = formats?;
    fs::create_dir_all(&a.out)
        .with_context(|| format!("{}: cannot create the directory", a.out.display()))?;
    let trace_all = a.trace && a.trace_frames.is_empty();
    if a.trace || !a.trace_frames.is_empty() {
        fs::create_dir_all(a.out.join("trace"))
            .with_context(|| format!("{}: cannot create the trace directory", a.out.display()))?;
    }
    let mut tiles_out = if a.tile_stats {
        let p = a.out.join("tiles.jsonl");
        Some(BufWriter::new(fs::File::create(&p).with_context(|| format!("{}: cannot create", p.display()))?))
    } else {
        None
    };
    let (w, h) = (traj.frames[0].width, traj.frames[0].height);
    let run = RunInfo {
        scene: scene_spec,
        trajectory: traj_spec,
        gaussians: scene.len(),
        frames: n,
        cuts: &traj.cuts,
        size: (w, h),
        fitted: a.fitted,
    };
    let record = ConfigRecord::new(&run, &cfg, &formats);
    let window =
        if a.raster_window > 1 { format!(", raster window {}", a.raster_window) } else { String::new() };
    println!(
        "neo frames: {} Gaussians, {n} frames at {w}x{h}, sort {strategy}{window}, {} threads -> {}",
        scene.len(),
        rayon::current_num_threads(),
        a.out.display()
    );

    let bar = ProgressBar::new(n as u64);
    bar.set_style(
        ProgressStyle::with_template("{bar:30} {pos}/{len} frames [{elapsed} < {eta}] {msg}")
            .expect("valid template"),
    );
    bar.enable_steady_tick(Duration::from_millis(200));
    let on_frame = |p: &Pipeline, out: &FrameOutput| -> Result<()> {
        let f = out.stats.frame;
        if a.png {
            out.image.write_png(a.out.join(format!("frame_{f:05}.png")))?;
        }
        if trace_all || a.trace_frames.contains(&f) {
            let path = a.out.join("trace").join(format!("frame_{f:05}.poc.trace"));
            let mut file =
                fs::File::create(&path).with_context(|| format!("{}: cannot create", path.display()))?;
            p.write_trace(&mut file).with_context(|| format!("{}: write failed", path.display()))?;
        }
        if let Some(t) = tiles_out.as_mut() {
            serde_json::to_writer(&mut *t, &out.tiles)?;
            t.write_all(b"\n")?;
        }
        bar.set_message(format!(
            "psnr vs exact {} vs float {} dB, {:.2} s",
            opt(out.stats.psnr_vs_exact),
            opt(out.stats.psnr_vs_float),
            out.stats.timing.total_s
        ));
        bar.inc(1);
        Ok(())
    };
    let frames = run_trajectory(&scene, &traj, None, cfg, formats, on_frame)?;
    bar.finish_and_clear();
    if let Some(mut t) = tiles_out {
        t.flush()?;
    }
    let stats = StatsFile::new(record, frames);
    let path = a.out.join("stats.json");
    let file = fs::File::create(&path).with_context(|| format!("{}: cannot create", path.display()))?;
    serde_json::to_writer_pretty(BufWriter::new(file), &stats)?;
    let s = &stats.summary;
    println!(
        "{} frames: psnr vs exact mean {} min {} dB ({} identical; exact with a raster window of {}), vs float {} \
         (exact {}), retention {}, sort DRAM {:.1} MB, dropped (capacity) {}",
        s.frames,
        opt(s.psnr_vs_exact_mean),
        opt(s.psnr_vs_exact_min),
        s.frames_identical_to_exact,
        if s.window_needed_max == 0 { "-".to_string() } else { s.window_needed_max.to_string() },
        opt(s.psnr_vs_float_mean),
        opt(s.exact_psnr_vs_float_mean),
        s.retention_pooled.map_or("-".into(), |r| format!("{:.3}", r)),
        s.sort_dram_bytes as f64 / 1e6,
        s.dropped_capacity
    );
    let t = &s.timing;
    let nf = s.frames.max(1) as f64;
    println!(
        "time per frame: preprocess {:.3} s, quantise {:.3} s, binning {:.3} s, sort {:.3} s, raster {:.3} s \
         (pipeline {:.3} s); references {:.3} s, metrics {:.3} s",
        t.preprocess_s / nf,
        t.quantize_s / nf,
        t.binning_s / nf,
        t.sort_s / nf,
        t.raster_s / nf,
        t.pipeline_s / nf,
        (t.reference_s + t.float_s) / nf,
        t.metrics_s / nf
    );
    println!("wrote {}", path.display());
    Ok(())
}
