//! Sweeps: points (one workload each, evaluated on several architectures), the grid that
//! enumerates them, sharding (`--shard i/n`), and the result of one point.
//!
//! Every point is an independent job with its own JSON result, so a sweep runs under a job
//! array or GNU parallel as `--shard i/n` with `i = 0..n`: shard `i` takes the points whose index
//! in the grid's order is `i mod n`; the shards partition the grid.

use serde::{Deserialize, Serialize};

use neo_golden::pipeline::Strategy;
use neo_golden::scene::Scene;
use neo_golden::{source, trajectory};

use crate::config::{PipelineParams, SimConfig};
use crate::driver::{generate, generate_many, GoldenRaster, WorkloadSpec};
use crate::latency::Latency;
use crate::run::{simulate, Arch, ArchResult, RunOptions};
use crate::workload::Workload;

/// One point: a workload and the architectures to run on it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Point {
    /// Scene spec or path.
    pub scene: String,
    /// Trajectory spec (without `speed=`).
    pub trajectory: String,
    /// Camera speed multiplier.
    pub speed: f64,
    /// Frames.
    pub frames: usize,
    /// Resolution label (`hd`, `fhd`, `qhd` or `WxH`).
    pub res: String,
    /// Width.
    pub width: u32,
    /// Height.
    pub height: u32,
    /// Strategy on Neo's hardware.
    pub strategy: String,
    /// Chunk size.
    pub chunk: usize,
    /// DPS passes.
    pub passes: usize,
    /// Entries of the raster cores' reorder window (1: none; docs/adaptive.md section 7): the
    /// golden pipeline blends and writes back each tile in its order, and the model's engine
    /// has it (`EngineConfig::raster_window`). Left out of the JSON when 1, so results written
    /// before the field read as no window.
    #[serde(
        default = "neo_golden::raster::window::no_window",
        skip_serializing_if = "neo_golden::raster::window::is_no_window"
    )]
    pub raster_window: usize,
}

/// A strategy with the raster cores' reorder window as the report names it: `neo` without
/// one (`window` 1), `neo + window 256` with one.
pub fn strategy_label(strategy: &str, window: usize) -> String {
    if window > 1 {
        format!("{strategy} + window {window}")
    } else {
        strategy.to_string()
    }
}

/// `hd`, `fhd`, `qhd` or `WxH` to `(label, width, height)` (golden's
/// [`trajectory::parse_resolution`]; the label is the value trimmed and lowercased).
pub fn parse_res(s: &str) -> Result<(String, u32, u32), String> {
    let (w, h) = trajectory::parse_resolution(s)?;
    Ok((s.trim().to_ascii_lowercase(), w, h))
}

impl Point {
    /// A file-name-safe identifier, unique within a grid.
    pub fn id(&self) -> String {
        let scene: String = self
            .scene
            .rsplit('/')
            .next()
            .unwrap_or("")
            .chars()
            .map(|c| if c.is_ascii_alphanumeric() { c } else { '-' })
            .collect();
        let traj: String =
            self.trajectory.chars().map(|c| if c.is_ascii_alphanumeric() { c } else { '-' }).collect();
        let window = if self.raster_window > 1 { format!("_w{}", self.raster_window) } else { String::new() };
        format!(
            "{scene}_{traj}_{}_{}f_{}_c{}_p{}{window}_s{}x",
            self.res,
            self.frames,
            self.strategy.replace(':', "-"),
            self.chunk,
            self.passes,
            self.speed
        )
    }

    /// The strategy as the report names it ([`strategy_label`]): `neo`, or `neo + window 256`
    /// with a reorder window.
    pub fn strategy_label(&self) -> String {
        strategy_label(&self.strategy, self.raster_window)
    }

    /// The trajectory spec with the speed applied.
    pub fn trajectory_spec(&self) -> Result<String, String> {
        let t = self.trajectory.trim();
        if self.speed == 1.0 {
            return Ok(t.to_string());
        }
        if t.starts_with("file:") || t.to_ascii_lowercase().ends_with(".json") {
            return Err(format!("trajectory '{t}' is a file: its speed cannot be changed"));
        }
        if t.contains("speed=") {
            return Err(format!("trajectory '{t}' already sets speed=; give the speed with --speed only"));
        }
        Ok(if t.contains(':') {
            format!("{t},speed={}", self.speed)
        } else {
            format!("{t}:speed={}", self.speed)
        })
    }

    /// The strategy.
    pub fn strategy(&self) -> Result<Strategy, String> {
        self.strategy.parse()
    }

    /// What fixes the point's cameras: scene, trajectory, speed, size and frames. Points with
    /// the same key see the same frames and generate their workloads together
    /// ([`workloads`]).
    pub fn camera_key(&self) -> (&str, &str, u64, u32, u32, usize) {
        (&self.scene, &self.trajectory, self.speed.to_bits(), self.width, self.height, self.frames)
    }
}

/// A cartesian grid of points.
#[derive(Clone, Debug, PartialEq)]
pub struct Grid {
    /// Scenes.
    pub scenes: Vec<String>,
    /// Trajectory spec.
    pub trajectory: String,
    /// Frames.
    pub frames: usize,
    /// Resolutions.
    pub res: Vec<String>,
    /// Strategies.
    pub strategies: Vec<String>,
    /// Chunk sizes.
    pub chunks: Vec<usize>,
    /// DPS passes (only strategies with DPS, i.e. `neo`, take more than one value).
    pub passes: Vec<usize>,
    /// Camera speeds.
    pub speeds: Vec<f64>,
    /// The raster cores' reorder window of every point (1: none).
    pub raster_window: usize,
}

impl Grid {
    /// Every point, in a fixed order (scene, resolution, strategy, chunk, passes, speed).
    pub fn points(&self) -> Result<Vec<Point>, String> {
        let mut v = Vec::new();
        for scene in &self.scenes {
            for r in &self.res {
                let (label, w, h) = parse_res(r)?;
                for s in &self.strategies {
                    let strategy: Strategy = s.parse()?;
                    let passes: Vec<usize> = if strategy == Strategy::Neo {
                        self.passes.clone()
                    } else {
                        vec![self.passes.first().copied().unwrap_or(1)]
                    };
                    for &chunk in &self.chunks {
                        for &p in &passes {
                            for &speed in &self.speeds {
                                if !(speed > 0.0 && speed <= 64.0) {
                                    return Err(format!("speed {speed}: expected 0 < speed <= 64"));
                                }
                                v.push(Point {
                                    scene: scene.clone(),
                                    trajectory: self.trajectory.clone(),
                                    speed,
                                    frames: self.frames,
                                    res: label.clone(),
                                    width: w,
                                    height: h,
                                    strategy: strategy.to_string(),
                                    chunk,
                                    passes: p,
                                    raster_window: self.raster_window,
                                });
                            }
                        }
                    }
                }
            }
        }
        Ok(v)
    }
}

/// Parses `i/n` (`0 <= i < n`).
pub fn parse_shard(s: &str) -> Result<(usize, usize), String> {
    let (i, n) = s.split_once('/').ok_or_else(|| format!("--shard '{s}': expected i/n"))?;
    let i: usize = i.trim().parse().map_err(|_| format!("--shard '{s}': bad index"))?;
    let n: usize = n.trim().parse().map_err(|_| format!("--shard '{s}': bad count"))?;
    if n == 0 || i >= n {
        return Err(format!("--shard '{s}': need 0 <= i < n"));
    }
    Ok((i, n))
}

/// The items of shard `i` of `n`: those whose index is `i mod n`.
pub fn shard<T: Clone>(items: &[T], i: usize, n: usize) -> Vec<T> {
    items.iter().enumerate().filter(|(k, _)| k % n == i).map(|(_, x)| x.clone()).collect()
}

/// Image quality over a workload (golden statistics).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct QualitySummary {
    /// Frames with statistics.
    pub frames: usize,
    /// Frames identical to the exact-order frame.
    pub identical: usize,
    /// True when the order is exact by construction (`full`, `hierarchical`): every frame is the
    /// exact-order frame.
    pub exact_by_construction: bool,
    /// Mean PSNR vs the exact-order frame over the frames that differ.
    pub psnr_vs_exact_mean: Option<f64>,
    /// PSNR vs exact of the mean squared error over all frames (identical frames count as 0):
    /// the sweep's error axis; `None` when every frame is identical.
    pub psnr_vs_exact_pooled: Option<f64>,
    /// The worst frame's PSNR vs exact (`None` when every frame is identical).
    #[serde(default)]
    pub psnr_vs_exact_min: Option<f64>,
    /// Mean PSNR vs the float reference.
    pub psnr_vs_float_mean: Option<f64>,
    /// Mean PSNR of the exact-order frames vs the float reference.
    pub exact_psnr_vs_float_mean: Option<f64>,
}

fn mean(v: impl Iterator<Item = f64>) -> Option<f64> {
    let (s, n) = v.fold((0.0, 0usize), |(s, n), x| (s + x, n + 1));
    (n > 0).then(|| s / n as f64)
}

impl QualitySummary {
    /// From a workload.
    pub fn of(wl: &Workload, strategy: Strategy) -> Self {
        let q: Vec<_> = wl.frames.iter().filter_map(|f| f.quality).collect();
        let exact = strategy.is_exact();
        let identical = q.iter().filter(|x| x.identical_to_exact == Some(true)).count();
        let mse: Vec<f64> = q
            .iter()
            .map(|x| match (x.identical_to_exact, x.psnr_vs_exact) {
                (Some(true), _) => 0.0,
                (_, Some(p)) => 255.0f64.powi(2) / 10f64.powf(p / 10.0),
                _ => 0.0,
            })
            .collect();
        let pooled =
            mean(mse.iter().copied()).filter(|&m| m > 0.0).map(|m| 10.0 * (255.0f64.powi(2) / m).log10());
        QualitySummary {
            frames: q.len(),
            identical,
            exact_by_construction: exact,
            psnr_vs_exact_mean: mean(q.iter().filter_map(|x| x.psnr_vs_exact)),
            psnr_vs_exact_pooled: pooled,
            psnr_vs_exact_min: q
                .iter()
                .filter(|x| x.identical_to_exact != Some(true))
                .filter_map(|x| x.psnr_vs_exact)
                .reduce(f64::min),
            psnr_vs_float_mean: mean(q.iter().filter_map(|x| x.psnr_vs_float)),
            exact_psnr_vs_float_mean: mean(q.iter().filter_map(|x| x.exact_psnr_vs_float)),
        }
    }

    /// True when the frames are (known to be) the exact-order frames.
    pub fn is_exact(&self) -> bool {
        self.exact_by_construction || (self.frames > 0 && self.identical == self.frames)
    }
}

/// Workload statistics for reports.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct WorkloadSummary {
    /// Gaussians.
    pub gaussians: u64,
    /// Tiles.
    pub tiles: u64,
    /// Mean tile-Gaussian pairs per frame.
    pub pairs_mean: f64,
    /// Mean newly visible entries per frame (after the first).
    pub incoming_mean: f64,
    /// Mean SCU early-termination ratio.
    pub processed_ratio_mean: f64,
    /// Generation seconds.
    pub generation_s: f64,
    /// The golden raster ran.
    pub golden_raster: bool,
    /// Approximate workload memory (bytes).
    pub heap_bytes: usize,
}

/// The result of one point.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PointResult {
    /// The point.
    pub point: Point,
    /// Its workload.
    pub workload: WorkloadSummary,
    /// Image quality.
    pub quality: QualitySummary,
    /// One result per architecture.
    pub archs: Vec<ArchResult>,
    /// The disorder signals against the per-tile error (with the golden raster; issue 14).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub signals: Option<crate::signals::SignalSummary>,
}

impl PointResult {
    /// The result of `arch` (by name).
    pub fn arch(&self, name: &str) -> Option<&ArchResult> {
        self.archs.iter().find(|a| a.arch == name)
    }
}

/// Loads a scene (any spec `neo_golden::source` reads).
pub fn load_scene(spec: &str) -> Result<Scene, String> {
    source::load_scene(spec, false).map(|(s, _)| s).map_err(|e| e.to_string())
}

/// What generating the workload of `point` takes: the spec (strategy, parameters of `cfg` with
/// the point's chunk, passes and reorder window, golden raster mode) and the camera trajectory.
pub fn workload_spec(
    scene: &Scene,
    point: &Point,
    cfg: &SimConfig,
    golden: GoldenRaster,
    raster_sample: u32,
) -> Result<(WorkloadSpec, trajectory::Trajectory), String> {
    let spec = point.trajectory_spec()?;
    let mut traj = trajectory::parse_trajectory(&spec, source::robust_bounds(scene), point.frames)
        .map_err(|e| e.to_string())?;
    // A cameras.json, or a spec's frames=, may hold another number of frames than the point's.
    traj.take_first(point.frames).map_err(|e| format!("trajectory '{spec}' {e} (--frames)"))?;
    let traj = traj.with_resolution(point.width, point.height);
    if traj.is_empty() {
        return Err(format!("trajectory '{spec}' has no frames"));
    }
    let strategy = point.strategy()?;
    let mut ws = WorkloadSpec::new(&point.scene, &spec, strategy);
    ws.params = PipelineParams {
        chunk: point.chunk,
        dps_passes: point.passes,
        raster_window: point.raster_window,
        ..cfg.pipeline_params()
    };
    ws.golden_raster = if strategy.is_exact() { GoldenRaster::Off } else { golden };
    ws.raster_sample = raster_sample;
    Ok((ws, traj))
}

/// Generates the workload of `point` (`on_frame(i)` after each frame).
pub fn workload(
    scene: &Scene,
    point: &Point,
    cfg: &SimConfig,
    golden: GoldenRaster,
    raster_sample: u32,
    on_frame: impl FnMut(usize),
) -> Result<Workload, String> {
    let (ws, traj) = workload_spec(scene, point, cfg, golden, raster_sample)?;
    generate(scene, &traj.frames, &traj.cuts, &ws, on_frame).map_err(|e| e.to_string())
}

/// Generates the workloads of `points`, which share their cameras ([`Point::camera_key`]), in one
/// pass over the frames ([`generate_many`]: each frame is preprocessed and binned once for all
/// of them); each is the workload [`workload`] makes of its point alone. `on_frame(i)` after
/// each frame.
pub fn workloads(
    scene: &Scene,
    points: &[&Point],
    cfg: &SimConfig,
    golden: GoldenRaster,
    raster_sample: u32,
    on_frame: impl FnMut(usize),
) -> Result<Vec<Workload>, String> {
    workloads_with(scene, points, &vec![golden; points.len()], cfg, raster_sample, on_frame)
}

/// [`workloads`] with each point's golden raster mode (`golden[i]` for `points[i]`).
pub fn workloads_with(
    scene: &Scene,
    points: &[&Point],
    golden: &[GoldenRaster],
    cfg: &SimConfig,
    raster_sample: u32,
    on_frame: impl FnMut(usize),
) -> Result<Vec<Workload>, String> {
    if golden.len() != points.len() {
        return Err(format!("{} points, {} golden raster modes", points.len(), golden.len()));
    }
    let Some(first) = points.first() else {
        return Ok(Vec::new());
    };
    if let Some(p) = points.iter().find(|p| p.camera_key() != first.camera_key()) {
        return Err(format!("points {} and {} do not share their cameras", first.id(), p.id()));
    }
    let mut specs = Vec::with_capacity(points.len());
    let mut traj = None;
    for (p, &golden) in points.iter().zip(golden) {
        let (ws, t) = workload_spec(scene, p, cfg, golden, raster_sample)?;
        specs.push(ws);
        traj.get_or_insert(t);
    }
    let traj = traj.expect("at least one point");
    generate_many(scene, &traj.frames, &traj.cuts, &specs, on_frame).map_err(|e| e.to_string())
}

/// Runs `archs` on a workload of `point`.
pub fn evaluate(
    point: &Point,
    wl: &Workload,
    cfg: &SimConfig,
    lat: &Latency,
    archs: &[Arch],
) -> Result<PointResult, String> {
    let cfg = point_config(point, cfg);
    // Architectures are independent single-threaded simulations: run them in parallel.
    use rayon::prelude::*;
    let results: Vec<ArchResult> = archs
        .par_iter()
        .map(|&a| simulate(a, &cfg, lat, wl, RunOptions::default()))
        .collect::<Result<_, _>>()?;
    point_result(point, wl, results)
}

/// The model configuration of `point`: `cfg` with the point's chunk, DPS passes and reorder
/// window (the engine's `raster_window`, which the timing of its raster cores adds).
pub fn point_config(point: &Point, cfg: &SimConfig) -> SimConfig {
    let mut cfg = cfg.clone();
    cfg.engine.chunk = point.chunk;
    cfg.pipeline.dps_passes = point.passes;
    cfg.engine.raster_window = point.raster_window;
    cfg
}

/// Checks, before `point`'s workload is generated, that the sorting cores' I/O buffers of
/// `cfg` hold the double-buffered chunks of each architecture of `archs` (the check every
/// model makes on its workload).
pub fn check_point_buffers(point: &Point, cfg: &SimConfig, archs: &[Arch]) -> Result<(), String> {
    let cfg = point_config(point, cfg);
    let entry = crate::driver::sort_entry_bytes(point.chunk).map_err(|e| e.to_string())?;
    for accel in archs.iter().filter_map(|a| a.accel()) {
        cfg.check_buffers(accel.stored_sort_entry_bytes(&cfg, entry))?;
    }
    Ok(())
}

/// The result of `point` from its workload and its architectures' results (each from
/// [`simulate`] with [`point_config`]), as [`evaluate`] makes it.
pub fn point_result(point: &Point, wl: &Workload, results: Vec<ArchResult>) -> Result<PointResult, String> {
    let strategy = point.strategy()?;
    let n = wl.frames.len().max(1) as f64;
    let pairs: u64 = wl.frames.iter().flat_map(|f| f.tiles.iter().map(|t| t.current as u64)).sum();
    let incoming: u64 =
        wl.frames.iter().skip(1).flat_map(|f| f.tiles.iter().map(|t| t.incoming as u64)).sum();
    Ok(PointResult {
        point: point.clone(),
        workload: WorkloadSummary {
            gaussians: wl.info.gaussians,
            tiles: wl.info.grid[0] as u64 * wl.info.grid[1] as u64,
            pairs_mean: pairs as f64 / n,
            incoming_mean: if wl.frames.len() > 1 { incoming as f64 / (n - 1.0) } else { 0.0 },
            processed_ratio_mean: wl.frames.iter().map(|f| f.processed_ratio).sum::<f64>() / n,
            generation_s: wl.generation_s,
            golden_raster: wl.info.golden_raster,
            heap_bytes: wl.heap_bytes(),
        },
        quality: QualitySummary::of(wl, strategy),
        archs: results,
        signals: {
            let cols: Option<Vec<_>> = wl.frames.iter().map(|f| f.golden_tiles.as_ref()).collect();
            cols.and_then(|c| crate::signals::SignalSummary::of(&c))
        },
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid() -> Grid {
        Grid {
            scenes: vec!["synthetic:outdoor".into()],
            trajectory: "orbit".into(),
            frames: 4,
            res: vec!["320x180".into()],
            strategies: vec!["neo".into(), "periodic:4".into(), "background:2".into(), "hierarchical".into()],
            chunks: vec![64, 128, 256, 512],
            passes: vec![1, 2],
            speeds: vec![1.0, 2.0, 4.0, 8.0, 16.0],
            raster_window: 1,
        }
    }

    #[test]
    fn grid_enumerates_passes_only_for_neo() {
        let p = grid().points().unwrap();
        assert_eq!(p.len(), 4 * 2 * 5 + 3 * 4 * 5);
        let ids: std::collections::HashSet<String> = p.iter().map(Point::id).collect();
        assert_eq!(ids.len(), p.len(), "ids are unique");
    }

    #[test]
    fn shards_partition_the_points() {
        let p = grid().points().unwrap();
        for n in [1usize, 2, 3, 7, 100, 200] {
            let mut seen = vec![0u32; p.len()];
            for i in 0..n {
                for q in shard(&p, i, n) {
                    let k = p.iter().position(|x| x == &q).unwrap();
                    seen[k] += 1;
                }
            }
            assert!(seen.iter().all(|&c| c == 1), "n = {n}: union is all, pairwise disjoint");
        }
        assert_eq!(parse_shard("2/5").unwrap(), (2, 5));
        for bad in ["5/5", "1", "a/2", "0/0", "-1/3"] {
            assert!(parse_shard(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn a_point_without_a_window_reads_and_writes_as_before() {
        let plain = grid().points().unwrap().remove(0);
        assert_eq!(plain.raster_window, 1);
        let text = serde_json::to_string(&plain).unwrap();
        assert!(!text.contains("raster_window"), "{text}");
        assert_eq!(serde_json::from_str::<Point>(&text).unwrap(), plain);
        let window = Point { raster_window: 256, ..plain.clone() };
        let mut v = serde_json::to_value(&window).unwrap();
        assert_eq!(v["raster_window"], 256);
        assert_eq!(serde_json::from_value::<Point>(v.clone()).unwrap(), window);
        // A result written before the field: no window.
        v.as_object_mut().unwrap().remove("raster_window");
        assert_eq!(serde_json::from_value::<Point>(v).unwrap().raster_window, 1);
        // Labels: unchanged without a window, distinct with one.
        assert!(!plain.id().contains("_w"), "{}", plain.id());
        assert_eq!(window.id(), plain.id().replace("_p1_", "_p1_w256_"));
        assert_eq!(
            (plain.strategy_label(), window.strategy_label()),
            ("neo".into(), "neo + window 256".into())
        );
    }

    /// A point with a window: generated with its cameras' other points, its workload blends
    /// through the window (closer to the exact order), and the model's engine has it (the
    /// held-back loads cost time; the DRAM traffic is the same).
    #[test]
    fn a_window_point_blends_and_is_timed_through_its_window() {
        let spec = "synthetic:outdoor?gaussians=3000&seed=2";
        let scene = load_scene(spec).unwrap();
        let plain = Point {
            scene: spec.into(),
            trajectory: "orbit".into(),
            speed: 16.0,
            frames: 3,
            res: "128x64".into(),
            width: 128,
            height: 64,
            strategy: "neo".into(),
            chunk: 256,
            passes: 1,
            raster_window: 1,
        };
        let window = Point { raster_window: 256, ..plain.clone() };
        let cfg = SimConfig::default();
        let lat =
            Latency::from_file(&neo_golden::shared::workspace_root().join(crate::latency::DEFAULT_PATH))
                .expect("reports/latency.json");
        let wls = workloads(&scene, &[&plain, &window], &cfg, GoldenRaster::Exact, 16, |_| {}).unwrap();
        assert_eq!(wls.iter().map(|w| w.info.raster_window).collect::<Vec<_>>(), [1, 256]);
        let r: Vec<PointResult> = [&plain, &window]
            .iter()
            .zip(&wls)
            .map(|(p, wl)| evaluate(p, wl, &cfg, &lat, &[Arch::Neo]).unwrap())
            .collect();
        let (q0, q1) = (&r[0].quality, &r[1].quality);
        assert!(!q0.is_exact(), "the premise: neo at 16x is not exact");
        let pooled =
            |q: &QualitySummary| if q.is_exact() { f64::INFINITY } else { q.psnr_vs_exact_pooled.unwrap() };
        assert!(pooled(q1) > pooled(q0), "window {q1:?}, none {q0:?}");
        let (a0, a1) = (r[0].arch("neo").unwrap(), r[1].arch("neo").unwrap());
        assert_eq!(a1.traffic.total_bytes(), a0.traffic.total_bytes(), "the window moves no DRAM traffic");
        assert!(a1.total_ms > a0.total_ms, "held-back loads: {} ms against {} ms", a1.total_ms, a0.total_ms);
        assert_eq!(point_config(&window, &cfg).engine.raster_window, 256);
    }

    /// The check made before generation refuses exactly what the model refuses on the
    /// workload: at a buffer of exactly Neo's double-buffered chunks, Neo passes both and
    /// GSCore (whose entries carry a bitmap) fails both.
    #[test]
    fn buffers_are_checked_before_generation_as_the_model_checks_them() {
        let spec = "synthetic:outdoor?gaussians=500&seed=3";
        let scene = load_scene(spec).unwrap();
        let point = Point {
            scene: spec.into(),
            trajectory: "orbit".into(),
            speed: 1.0,
            frames: 1,
            res: "128x64".into(),
            width: 128,
            height: 64,
            strategy: "neo".into(),
            chunk: 128,
            passes: 1,
            raster_window: 1,
        };
        let mut cfg = SimConfig::default();
        let wl = workload(&scene, &point, &cfg, GoldenRaster::Off, 0, |_| {}).unwrap();
        let entry = crate::driver::sort_entry_bytes(point.chunk).unwrap();
        assert_eq!(entry, wl.info.sort_entry_bytes, "the bytes known before generation are the workload's");
        assert!(cfg.gscore.bitmap_bytes > 0, "the premise: GSCore's entries are larger");
        cfg.neo.sort_io_buffer_bytes = 4 * point.chunk as u64 * entry as u64;
        let lat =
            Latency::from_file(&neo_golden::shared::workspace_root().join(crate::latency::DEFAULT_PATH))
                .expect("reports/latency.json");
        for (arch, fits) in [(Arch::Neo, true), (Arch::Gscore(4), false), (Arch::Gpu, true)] {
            let early = check_point_buffers(&point, &cfg, &[arch]);
            assert_eq!(early.is_ok(), fits, "{arch:?}: {early:?}");
            if let Err(e) = early {
                assert!(e.contains("neo.sort_io_buffer_bytes"), "{e}");
                let late = evaluate(&point, &wl, &cfg, &lat, &[arch]).unwrap_err();
                assert_eq!(late, e, "the model refuses the workload with the same error");
            } else {
                evaluate(&point, &wl, &cfg, &lat, &[arch]).unwrap();
            }
        }
        cfg.neo.sort_io_buffer_bytes -= 1;
        assert!(check_point_buffers(&point, &cfg, &[Arch::Neo]).is_err(), "one byte short");
    }

    #[test]
    fn speed_is_appended_to_the_trajectory() {
        let mut p = grid().points().unwrap().remove(0);
        p.speed = 4.0;
        assert_eq!(p.trajectory_spec().unwrap(), "orbit:speed=4");
        p.trajectory = "orbit:radius=5".into();
        assert_eq!(p.trajectory_spec().unwrap(), "orbit:radius=5,speed=4");
        p.trajectory = "orbit:speed=2".into();
        assert!(p.trajectory_spec().is_err());
        assert_eq!(parse_res("QHD").unwrap(), ("qhd".into(), 2560, 1440));
        assert!(parse_res("0x3").is_err());
    }
}
