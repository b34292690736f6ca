//! Running sweep points with progress bars, for `neo simulate` and `neo report`: the model
//! inputs (configuration, measured timing), a scene cache, and a [`PointRunner`] that shows
//! each workload's frames or each group's points.

use anyhow::{anyhow, Result};
use indicatif::{ProgressBar, ProgressStyle};
use neo_golden::engine::EngineConfig;
use neo_golden::{scene::Scene, shared};
use neo_sim::config::SimConfig;
use neo_sim::driver::GoldenRaster;
use neo_sim::latency::{self, Latency};
use neo_sim::report_plan::PointRunner;
use neo_sim::run::Arch;
use neo_sim::suite::{self, Point, PointResult};
use std::collections::HashMap;
use std::path::Path;
use std::time::{Duration, Instant};

/// Reads the configuration file, or the defaults.
/// With `engine`, the engine section comes from that file (`neo gen --config`'s format); with
/// `sizes`, the byte sizes are that preset's.
pub fn load_config(path: Option<&Path>, engine: Option<&Path>, sizes: Option<&str>) -> Result<SimConfig> {
    let mut cfg = match path {
        Some(p) => SimConfig::from_file(p)?,
        None => SimConfig::default(),
    };
    if let Some(e) = engine {
        cfg.engine = EngineConfig::from_json_file(e)?;
        cfg.check().map_err(|err| anyhow!("{}: {err}", e.display()))?;
    }
    if let Some(name) = sizes {
        cfg.sizes = neo_sim::config::DataSizes::preset(name).map_err(|err| anyhow!("--sizes: {err}"))?;
    }
    Ok(cfg)
}

/// Reads `latency.json` (the path as given, else, for the default path, beside the sources) and
/// refuses it when it was measured on another engine configuration than `cfg.engine`.
pub fn load_latency(path: &Path, cfg: &SimConfig) -> Result<Latency> {
    let lat = latency_file(path)?;
    lat.check_engine(&cfg.engine)?;
    Ok(lat)
}

/// Reads `latency.json` (the path as given, else, for the default path, beside the sources).
pub fn latency_file(path: &Path) -> Result<Latency> {
    let mut path = path.to_path_buf();
    if !path.exists() && path == Path::new(latency::DEFAULT_PATH) {
        let alt = shared::workspace_root().join(latency::DEFAULT_PATH);
        if alt.exists() {
            path = alt;
        }
    }
    Ok(Latency::from_file(&path)?)
}

/// Scenes loaded once per spec.
#[derive(Default)]
pub struct Scenes(HashMap<String, Scene>);

impl Scenes {
    /// The scene of `spec`, loaded on first use.
    pub fn get(&mut self, spec: &str) -> Result<&Scene> {
        if !self.0.contains_key(spec) {
            let (s, _) = crate::progress::spin(&format!("loading {spec}"), || suite::load_scene(spec));
            self.0.insert(spec.to_string(), s.map_err(|e| anyhow!(e))?);
        }
        Ok(&self.0[spec])
    }

    /// A scene already loaded by [`Scenes::get`].
    pub fn loaded(&self, spec: &str) -> Option<&Scene> {
        self.0.get(spec)
    }
}

/// Generates the workload of `point` (with a progress bar) and runs `archs` on it.
#[allow(clippy::too_many_arguments)]
pub fn run_point(
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

/// Runs `points` two at a time (each workload is only partly parallel, the model not at all),
/// with one progress bar over the points; `log` reports each finished point. Results keep the
/// order of `points`.
#[allow(clippy::too_many_arguments)]
pub fn run_points_parallel(
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

/// A [`PointRunner`] with progress bars that logs every finished point's FPS.
pub struct ProgressRunner<'a> {
    /// Scenes loaded so far.
    pub scenes: Scenes,
    /// Model configuration.
    pub cfg: &'a SimConfig,
    /// Measured timing.
    pub lat: &'a Latency,
    /// When the run started (for the log's elapsed time).
    pub started: Instant,
}

impl ProgressRunner<'_> {
    /// One log line about a finished point.
    fn log(started: Instant, r: &PointResult, label: &str) {
        let fps: Vec<String> = r.archs.iter().map(|a| format!("{} {:.1}", a.arch, a.fps)).collect();
        eprintln!(
            "{label} {} {} {} c{} p{} {}x: FPS {} (workload {:.1} s; {:.0} s elapsed)",
            r.point.res,
            r.point.strategy,
            r.point.frames,
            r.point.chunk,
            r.point.passes,
            r.point.speed,
            fps.join(", "),
            r.workload.generation_s,
            started.elapsed().as_secs_f64()
        );
    }
}

impl PointRunner for ProgressRunner<'_> {
    fn run_one(
        &mut self,
        point: &Point,
        archs: &[Arch],
        golden: GoldenRaster,
        raster_sample: u32,
        label: &str,
    ) -> Result<PointResult, String> {
        let r = run_point(&mut self.scenes, point, self.cfg, self.lat, archs, golden, raster_sample, label)
            .map_err(|e| format!("{e:#}"))?;
        Self::log(self.started, &r, label);
        Ok(r)
    }

    fn run_many(
        &mut self,
        points: &[Point],
        archs: &[Arch],
        golden: GoldenRaster,
        raster_sample: u32,
        what: &str,
    ) -> Result<Vec<PointResult>, String> {
        let started = self.started;
        let log = move |r: &PointResult, label: &str| Self::log(started, r, label);
        run_points_parallel(
            &mut self.scenes,
            points,
            self.cfg,
            self.lat,
            archs,
            golden,
            raster_sample,
            what,
            &log,
        )
        .map_err(|e| format!("{e:#}"))
    }

    fn headline_done(&mut self, result: &PointResult) {
        println!("{}", neo_sim::report::point_table(result));
    }
}
