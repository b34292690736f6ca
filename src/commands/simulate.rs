//! `neo simulate`: the cycle model on golden workloads. Every combination of the list-valued
//! options (`--res`, `--sort`, `--chunk`, `--passes`, `--speed`) is one point: one workload,
//! evaluated on every `--arch`. `--shard i/n` runs only the points whose index is `i mod n`, so
//! a sweep runs as independent jobs (Slurm arrays, GNU parallel), each writing its own JSON.

use anyhow::{anyhow, bail, Context, Result};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use neo_golden::{scene::Scene, shared, synthetic};
use neo_sim::config::SimConfig;
use neo_sim::driver::GoldenRaster;
use neo_sim::latency::{self, Latency};
use neo_sim::report::point_table;
use neo_sim::run::Arch;
use neo_sim::suite::{self, Grid, Point, PointResult};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::time::Duration;

/// Arguments of `neo simulate`.
#[derive(Args)]
pub struct SimulateArgs {
    /// Scene: a .ply or a synthetic spec.
    #[arg(long, default_value = synthetic::DEFAULT_SCENE)]
    pub scene: String,
    /// Trajectory spec (`orbit`, `walk`, `shake` with parameters, or a cameras.json).
    #[arg(long, default_value = "orbit")]
    pub trajectory: String,
    /// Frames.
    #[arg(long, default_value_t = 30)]
    pub frames: usize,
    /// Resolutions, comma-separated: `hd`, `fhd`, `qhd` or `WxH`.
    #[arg(long, default_value = "qhd", value_delimiter = ',')]
    pub res: Vec<String>,
    /// Architectures, comma-separated: `neo`, `gscore` (4 and 16 cores), `gscoreN`, `gpu`, `all`.
    #[arg(long, default_value = "all")]
    pub arch: String,
    /// Strategies Neo's hardware runs, comma-separated: `neo`, `full`, `periodic:K`,
    /// `background:K`, `hierarchical`.
    #[arg(long, default_value = "neo", value_delimiter = ',')]
    pub sort: Vec<String>,
    /// Chunk sizes (default: the configuration's, 256).
    #[arg(long, value_delimiter = ',')]
    pub chunk: Vec<usize>,
    /// DPS passes per frame (default: the configuration's, 1).
    #[arg(long, value_delimiter = ',')]
    pub passes: Vec<usize>,
    /// Camera speed multipliers.
    #[arg(long, default_value = "1", value_delimiter = ',')]
    pub speed: Vec<f64>,
    /// Image quality from the golden raster: `auto` (on for small runs), `off`, `exact` (PSNR
    /// vs the exact order) or `full` (also vs the float reference).
    #[arg(long, default_value = "auto")]
    pub quality: String,
    /// Without the golden raster: measure early termination on every K-th tile.
    #[arg(long, default_value_t = 16)]
    pub raster_sample: u32,
    /// Model configuration (JSON; missing fields keep their defaults).
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// Measured unit timing.
    #[arg(long, default_value = latency::DEFAULT_PATH)]
    pub latency: PathBuf,
    /// Print JSON instead of tables.
    #[arg(long)]
    pub json: bool,
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

/// Reads the configuration file, or the defaults.
pub(crate) fn load_config(path: Option<&Path>) -> Result<SimConfig> {
    match path {
        Some(p) => Ok(SimConfig::from_file(p)?),
        None => Ok(SimConfig::default()),
    }
}

/// Reads `latency.json`: the path as given, else (for the default path) beside the sources.
pub(crate) fn load_latency(path: &Path) -> Result<Latency> {
    if !path.exists() && path == Path::new(latency::DEFAULT_PATH) {
        let alt = shared::workspace_root().join(latency::DEFAULT_PATH);
        if alt.exists() {
            return Ok(Latency::from_file(&alt)?);
        }
    }
    Ok(Latency::from_file(path)?)
}

/// Parses `--quality`; `auto` turns the golden raster on when `pixels x frames` is small.
pub(crate) fn golden_mode(q: &str, points: &[Point]) -> Result<GoldenRaster> {
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

/// Scenes loaded once per spec.
#[derive(Default)]
pub(crate) struct Scenes(HashMap<String, Scene>);

impl Scenes {
    pub(crate) fn get(&mut self, spec: &str) -> Result<&Scene> {
        if !self.0.contains_key(spec) {
            let (s, _) = crate::progress::spin(&format!("loading {spec}"), || suite::load_scene(spec));
            self.0.insert(spec.to_string(), s.map_err(|e| anyhow!(e))?);
        }
        Ok(&self.0[spec])
    }

    /// A scene already loaded by [`Scenes::get`].
    pub(crate) fn loaded(&self, spec: &str) -> Option<&Scene> {
        self.0.get(spec)
    }
}

/// Runs `points` two at a time (each workload is only partly parallel, the model not at all),
/// with one progress bar over the points; `log` reports each finished point. Results keep the
/// order of `points`.
#[allow(clippy::too_many_arguments)]
pub(crate) fn run_points_parallel(
    scenes: &mut Scenes,
    points: &[Point],
    cfg: &SimConfig,
    lat: &Latency,
    archs: &[Arch],
    golden: GoldenRaster,
    raster_sample: u32,
    what: &str,
    log: &(dyn Fn(&PointResult, &str) + Sync),
) -> Result<Vec<PointResult>> {
    use rayon::prelude::*;
    for p in points {
        scenes.get(&p.scene)?;
    }
    let scenes = &*scenes;
    let bar = ProgressBar::new(points.len() as u64);
    bar.set_style(
        ProgressStyle::with_template("{prefix} {bar:24} {pos}/{len} points [{elapsed} < {eta}]")
            .expect("valid template"),
    );
    bar.set_prefix(what.to_string());
    bar.enable_steady_tick(Duration::from_millis(200));
    let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build()?;
    let out: Result<Vec<PointResult>> = pool.install(|| {
        points
            .par_iter()
            .enumerate()
            .with_max_len(1)
            .map(|(k, p)| {
                let scene = scenes.loaded(&p.scene).expect("loaded above");
                let wl =
                    suite::workload(scene, p, cfg, golden, raster_sample, |_| {}).map_err(|e| anyhow!(e))?;
                let r = suite::evaluate(p, &wl, cfg, lat, archs).map_err(|e| anyhow!(e))?;
                bar.suspend(|| log(&r, &format!("[{what} {}/{}]", k + 1, points.len())));
                bar.inc(1);
                Ok(r)
            })
            .collect()
    });
    bar.finish_and_clear();
    out
}

/// Generates the workload of `point` (with a progress bar) and runs `archs` on it.
#[allow(clippy::too_many_arguments)]
pub(crate) fn run_point(
    scenes: &mut Scenes,
    point: &Point,
    cfg: &SimConfig,
    lat: &Latency,
    archs: &[Arch],
    golden: GoldenRaster,
    raster_sample: u32,
    label: &str,
) -> Result<PointResult> {
    let scene = scenes.get(&point.scene)?;
    let bar = ProgressBar::new(point.frames as u64);
    bar.set_style(
        ProgressStyle::with_template("{prefix} {bar:24} {pos}/{len} frames [{elapsed} < {eta}] {msg}")
            .expect("valid template"),
    );
    bar.set_prefix(label.to_string());
    bar.set_message(format!(
        "workload {} {} {}",
        point.res,
        point.strategy,
        if golden == GoldenRaster::Off { "" } else { "(golden raster)" }
    ));
    bar.enable_steady_tick(Duration::from_millis(200));
    let wl =
        suite::workload(scene, point, cfg, golden, raster_sample, |_| bar.inc(1)).map_err(|e| anyhow!(e))?;
    bar.set_message(format!("model: {}", archs.iter().map(Arch::name).collect::<Vec<_>>().join(", ")));
    let r = suite::evaluate(point, &wl, cfg, lat, archs).map_err(|e| anyhow!(e))?;
    bar.finish_and_clear();
    Ok(r)
}

/// Runs `neo simulate`.
pub fn run(a: SimulateArgs) -> Result<()> {
    let cfg = load_config(a.config.as_deref())?;
    let lat = load_latency(&a.latency)?;
    let archs = Arch::parse_list(&a.arch, &cfg).map_err(|e| anyhow!(e))?;
    let grid = Grid {
        scenes: vec![a.scene.clone()],
        trajectory: a.trajectory.clone(),
        frames: a.frames,
        res: a.res.clone(),
        strategies: a.sort.clone(),
        chunks: if a.chunk.is_empty() { vec![cfg.pipeline.chunk] } else { a.chunk.clone() },
        passes: if a.passes.is_empty() { vec![cfg.pipeline.dps_passes] } else { a.passes.clone() },
        speeds: a.speed.clone(),
    };
    if a.frames == 0 {
        bail!("--frames must be at least 1");
    }
    let all = grid.points().map_err(|e| anyhow!(e))?;
    let points = match &a.shard {
        Some(s) => {
            let (i, n) = suite::parse_shard(s).map_err(|e| anyhow!(e))?;
            suite::shard(&all, i, n)
        }
        None => all.clone(),
    };
    let mut golden = golden_mode(&a.quality, &points)?;
    if a.trace.is_some() && golden == GoldenRaster::Off {
        golden = GoldenRaster::Exact;
    }
    if let Some(dir) = &a.out {
        std::fs::create_dir_all(dir)
            .with_context(|| format!("{}: cannot create the directory", dir.display()))?;
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
    }
    let mut scenes = Scenes::default();
    let mut results = Vec::new();
    for (k, p) in points.iter().enumerate() {
        let mut point_cfg = cfg.clone();
        if let Some(dir) = &a.trace {
            // Trace through the golden pipeline: generate with the driver's trace option.
            let scene = scenes.get(&p.scene)?;
            let spec = p.trajectory_spec().map_err(|e| anyhow!(e))?;
            let traj = neo_golden::trajectory::parse_trajectory(
                &spec,
                neo_golden::source::robust_bounds(scene),
                p.frames,
            )?
            .with_resolution(p.width, p.height);
            let mut ws =
                neo_sim::driver::WorkloadSpec::new(&p.scene, &spec, p.strategy().map_err(|e| anyhow!(e))?);
            ws.params = neo_sim::config::PipelineParams {
                chunk: p.chunk,
                dps_passes: p.passes,
                ..cfg.pipeline.clone()
            };
            ws.golden_raster = golden;
            ws.trace = Some((dir.join(p.id()), a.trace_frames.clone()));
            let (wl, _) = crate::progress::spin("golden pipeline with trace export", || {
                neo_sim::driver::generate(scene, &traj.frames, &traj.cuts, &ws, |_| {})
            });
            let wl = wl?;
            point_cfg.pipeline.chunk = p.chunk;
            let r = suite::evaluate(p, &wl, &point_cfg, &lat, &archs).map_err(|e| anyhow!(e))?;
            eprintln!("wrote poc.trace files into {}", dir.join(p.id()).display());
            results.push(r);
        } else {
            let label = format!("[{}/{}]", k + 1, points.len());
            results.push(run_point(
                &mut scenes,
                p,
                &point_cfg,
                &lat,
                &archs,
                golden,
                a.raster_sample,
                &label,
            )?);
        }
        let r = results.last().expect("just pushed");
        if let Some(dir) = &a.out {
            let path = dir.join(format!("{}.json", p.id()));
            let f =
                std::fs::File::create(&path).with_context(|| format!("{}: cannot create", path.display()))?;
            serde_json::to_writer_pretty(std::io::BufWriter::new(f), r)?;
        }
        if !a.json {
            println!("{}", point_table(r));
        }
    }
    if a.json && a.out.is_none() {
        println!("{}", serde_json::to_string_pretty(&results)?);
    }
    Ok(())
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
