//! `neo frames`: the bit-exact golden pipeline along a trajectory, with a sorting strategy;
//! writes `stats.json` (and optionally PNGs, per-tile statistics and `poc.trace` files).

use crate::args::{warn_dropped, FramesArg, SceneArg, StrictArg, TrajectoryArg};
use crate::progress::spin;
use anyhow::{anyhow, bail, Context, Result};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use neo_golden::formats::FeatureFormat;
use neo_golden::pipeline::trace;
use neo_golden::pipeline::{
    formats_for, run_trajectory, ConfigRecord, FrameOutput, Pipeline, PipelineConfig, PipelineError,
    Preprocessing, RunInfo, StatsFile, Strategy,
};
use neo_golden::trajectory::parse_resolution;
use neo_golden::{source, trajectory};
use std::fs;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
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
    /// Output directory (created). The files an earlier run wrote there and this one does not
    /// (`frame_NNNNN.png`, `trace/frame_NNNNN.poc.trace`, `tiles.jsonl`) are removed.
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
    /// DPS passes per frame: 0 (the reused table is merged as it is) to 16 (the limit of
    /// adaptive's `max` and of `neo simulate --passes` too).
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

/// What a run writes into its output directory, to tell an earlier run's files from its own.
struct Outputs<'a> {
    /// Frames in the run.
    frames: usize,
    /// `frame_NNNNN.png` for every frame.
    png: bool,
    /// `trace/frame_NNNNN.poc.trace` for every frame (`--trace` without `--trace-frames`).
    trace_all: bool,
    /// The frames traced otherwise.
    trace_frames: &'a [usize],
    /// `tiles.jsonl`.
    tile_stats: bool,
}

impl Outputs<'_> {
    /// Whether the run writes frame `f`'s `poc.trace`.
    fn traces(&self, f: usize) -> bool {
        f < self.frames && (self.trace_all || self.trace_frames.contains(&f))
    }
}

/// The frame number of a file named `frame_NNNNN{suffix}` (5 digits or more), as `neo frames`
/// names its PNGs and traces.
fn frame_index(name: &str, suffix: &str) -> Option<usize> {
    let digits = name.strip_prefix("frame_")?.strip_suffix(suffix)?;
    if digits.len() < 5 || !digits.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    digits.parse().ok()
}

/// Regular files of `dir` (none when it does not exist), by name.
fn files_in(dir: &Path) -> Result<Vec<String>> {
    if !dir.is_dir() {
        return Ok(Vec::new());
    }
    let mut names = Vec::new();
    for e in fs::read_dir(dir).with_context(|| format!("{}: cannot read the directory", dir.display()))? {
        let e = e.with_context(|| format!("{}: cannot read the directory", dir.display()))?;
        if e.file_type().is_ok_and(|t| t.is_file()) {
            names.push(e.file_name().to_string_lossy().into_owned());
        }
    }
    names.sort();
    Ok(names)
}

/// The files an earlier `neo frames` run left in `out` that this run (`o`) does not write, so
/// they would disagree with its `stats.json`: `tiles.jsonl`, `frame_NNNNN.png` and
/// `trace/frame_NNNNN.poc.trace`. Nothing else is touched.
fn stale_outputs(out: &Path, o: &Outputs) -> Result<Vec<PathBuf>> {
    let mut stale = Vec::new();
    for name in files_in(out)? {
        let old = match name.as_str() {
            "tiles.jsonl" => !o.tile_stats,
            _ => frame_index(&name, ".png").is_some_and(|f| !o.png || f >= o.frames),
        };
        if old {
            stale.push(out.join(name));
        }
    }
    let trace = out.join("trace");
    for name in files_in(&trace)? {
        if frame_index(&name, trace::FILE_SUFFIX).is_some_and(|f| !o.traces(f)) {
            stale.push(trace.join(name));
        }
    }
    Ok(stale)
}

/// Removes the [`stale_outputs`] of `out` (and `trace/` when that leaves it empty); returns how
/// many files were removed. An earlier `stats.json` is removed too (not counted): this run
/// writes its own last, so a run that fails leaves none.
fn remove_stale_outputs(out: &Path, o: &Outputs) -> Result<usize> {
    let stale = stale_outputs(out, o)?;
    let stats = out.join("stats.json");
    if stats.is_file() {
        fs::remove_file(&stats)
            .with_context(|| format!("{}: cannot remove the earlier run's", stats.display()))?;
    }
    for p in &stale {
        fs::remove_file(p).with_context(|| format!("{}: cannot remove this earlier output", p.display()))?;
    }
    let trace = out.join("trace");
    if trace.is_dir() && fs::read_dir(&trace).is_ok_and(|mut d| d.next().is_none()) {
        let _ = fs::remove_dir(&trace);
    }
    Ok(stale.len())
}

/// Runs `neo frames`. Every argument is checked before anything is written; the files an
/// earlier run left in `--out` that this run does not write are removed ([`stale_outputs`]).
pub fn run(a: FramesArgs) -> Result<()> {
    let strategy: Strategy = a.sort.parse().map_err(anyhow::Error::msg)?;
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
    cfg.check_passes().context("--passes")?;
    cfg.check_window().context("--raster-window")?;
    cfg.raster.check(&FeatureFormat::default()).map_err(PipelineError::from).context("--tile/--subtile")?;
    let scene_spec = &a.scene.scene;
    let (loaded, _) =
        spin(&format!("loading {scene_spec}"), || source::load_scene(scene_spec, a.strict.strict));
    let (scene, report) = loaded?;
    warn_dropped(&report);
    let traj_spec = &a.trajectory.trajectory;
    let mut traj = trajectory::parse_trajectory(traj_spec, source::robust_bounds(&scene), a.frames.frames)?;
    if let Some((w, h)) = a.res {
        traj = traj.with_resolution(w, h);
    }
    traj.take_first(a.frames.frames).map_err(|e| anyhow!("trajectory '{traj_spec}' {e} (--frames)"))?;
    let n = traj.len();
    if let Some(f) = a.trace_frames.iter().find(|&&f| f >= n) {
        bail!("--trace-frames {f}: the run has {n} frame(s), numbered 0 to {}", n - 1);
    }
    let (formats, _) = spin("choosing number formats", || formats_for(&scene, &traj.frames, &cfg, a.fitted));
    let formats = formats?;
    formats.check(&cfg.raster, scene.len())?;
    let trace_all = a.trace && a.trace_frames.is_empty();
    let outputs =
        Outputs { frames: n, png: a.png, trace_all, trace_frames: &a.trace_frames, tile_stats: a.tile_stats };
    let removed = remove_stale_outputs(&a.out, &outputs)?;
    if removed > 0 {
        eprintln!(
            "removed {removed} file(s) an earlier run wrote into {} and this one does not",
            a.out.display()
        );
    }
    fs::create_dir_all(&a.out)
        .with_context(|| format!("{}: cannot create the directory", a.out.display()))?;
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
            let path = a.out.join("trace").join(trace::file_name(f));
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_index_reads_only_neos_own_names() {
        assert_eq!(frame_index("frame_00003.png", ".png"), Some(3));
        assert_eq!(frame_index("frame_123456.png", ".png"), Some(123_456));
        assert_eq!(frame_index("frame_00003.poc.trace", ".poc.trace"), Some(3));
        for other in
            ["frame_3.png", "frame_0000x.png", "frame_00003.png.bak", "my_frame_00003.png", "frame_.png"]
        {
            assert_eq!(frame_index(other, ".png"), None, "{other}");
        }
    }

    /// A run removes what an earlier run wrote and it does not (PNGs beyond its frames or without
    /// `--png`, traces of frames it does not trace, `tiles.jsonl` without `--tile-stats`), and
    /// nothing else.
    #[test]
    fn stale_outputs_are_an_earlier_runs_files_this_run_does_not_write() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path();
        fs::create_dir(out.join("trace")).unwrap();
        let files = [
            "frame_00000.png",
            "frame_00001.png",
            "frame_00002.png",
            "frame_7.png",
            "notes.txt",
            "tiles.jsonl",
            "stats.json",
            "trace/frame_00000.poc.trace",
            "trace/frame_00002.poc.trace",
            "trace/mine.txt",
        ];
        for f in files {
            fs::write(out.join(f), "x").unwrap();
        }
        let names = |o: &Outputs| -> Vec<String> {
            let mut v: Vec<String> = stale_outputs(out, o)
                .unwrap()
                .iter()
                .map(|p| p.strip_prefix(out).unwrap().to_string_lossy().into_owned())
                .collect();
            v.sort();
            v
        };
        let all = Outputs { frames: 3, png: true, trace_all: true, trace_frames: &[], tile_stats: true };
        assert!(names(&all).is_empty(), "{:?}", names(&all));
        let two = Outputs { frames: 2, png: true, trace_all: false, trace_frames: &[0], tile_stats: true };
        assert_eq!(names(&two), ["frame_00002.png", "trace/frame_00002.poc.trace"]);
        let bare = Outputs { frames: 2, png: false, trace_all: false, trace_frames: &[], tile_stats: false };
        assert_eq!(
            names(&bare),
            [
                "frame_00000.png",
                "frame_00001.png",
                "frame_00002.png",
                "tiles.jsonl",
                "trace/frame_00000.poc.trace",
                "trace/frame_00002.poc.trace"
            ]
        );
        assert_eq!(remove_stale_outputs(out, &bare).unwrap(), 6);
        let mut left: Vec<String> =
            files.iter().filter(|f| out.join(f).exists()).map(|f| f.to_string()).collect();
        left.sort();
        assert_eq!(left, ["frame_7.png", "notes.txt", "trace/mine.txt"]);
        // `trace/` goes when it is left empty, and a missing directory has nothing stale.
        fs::remove_file(out.join("trace/mine.txt")).unwrap();
        remove_stale_outputs(out, &bare).unwrap();
        assert!(!out.join("trace").exists());
        assert!(stale_outputs(&out.join("missing"), &bare).unwrap().is_empty());
    }
}
