//! The plan of `neo report`: which points run, on which architectures, in which order, and the
//! report data they make (rendered by [`crate::report::render`]).
//!
//! 1. throughput and traffic (paper Figs. 15-16): Neo's strategy on every architecture, per
//!    scene and resolution, work-only workloads;
//! 2. strategy timelines (Fig. 19): Neo's run (taken from step 1 when it matches the timeline
//!    resolution) and the compared strategies on Neo's hardware;
//! 3. the speed/error sweep over strategies, chunk sizes, DPS passes and camera speeds, with the
//!    golden raster on for PSNR (or point results read from files), and `neo` with each of the
//!    raster cores' reorder windows asked for ([`SweepSpec::windows`]) at every speed.
//!
//! The steps run as jobs ([`PointJob`]) in two sets: the throughput runs (with the jobs that run
//! on their workloads: Neo-S) first, so that their table is out early, then the rest, which
//! starts as soon as the first set's last simulations have (no core waits for them). Within a
//! set, the architectures of one point run while the next workloads are generated (the largest
//! first), and points that share their cameras generate their workloads together, each frame
//! preprocessed and binned once ([`crate::suite::workloads`]): the compared strategies'
//! timelines, the sweep's points of one camera speed. The timelines are not generated with the
//! throughput run at their resolution: their strategy pipelines would delay its table by more
//! than the shared preprocessing saves. Every point's result is the one it has when run alone.
//!
//! How the jobs run (progress display, parallelism) is the caller's: a [`PointRunner`].

use std::path::Path;

use neo_golden::engine::{check_raster_window, MAX_RASTER_WINDOW};
use neo_golden::synthetic;

use crate::config::SimConfig;
use crate::driver::GoldenRaster;
use crate::latency::{self, Latency};
use crate::report::{ReportData, ReportSettings, SPEED_TABLE_CHUNK};
use crate::run::Arch;
use crate::suite::{parse_res, Grid, Point, PointResult};

/// What `neo report` runs.
#[derive(Clone, Debug, PartialEq)]
pub struct ReportSpec {
    /// Scenes besides the default synthetic scene.
    pub scenes: Vec<String>,
    /// Include the default synthetic scene (first).
    pub default_scene: bool,
    /// Trajectory of every run.
    pub trajectory: String,
    /// Frames of the throughput, traffic and timeline runs.
    pub frames: usize,
    /// Resolutions of the throughput and traffic runs.
    pub res: Vec<String>,
    /// Resolution of the strategy timelines.
    pub timeline_res: String,
    /// Strategies compared with `neo` in the timelines.
    pub timeline_sort: Vec<String>,
    /// The sweep's grid (scene, resolution, frames, strategies, chunks, passes, speeds; its
    /// trajectory is [`ReportSpec::trajectory`]), or `None` to run no sweep.
    pub sweep: Option<SweepSpec>,
    /// Early termination measured on every K-th tile (work-only workloads).
    pub raster_sample: u32,
}

/// The speed/error sweep of a report.
#[derive(Clone, Debug, PartialEq)]
pub struct SweepSpec {
    /// Scene.
    pub scene: String,
    /// Resolution.
    pub res: String,
    /// Frames per point.
    pub frames: usize,
    /// Strategies.
    pub strategies: Vec<String>,
    /// Chunk sizes.
    pub chunks: Vec<usize>,
    /// DPS passes.
    pub passes: Vec<usize>,
    /// Camera speeds.
    pub speeds: Vec<f64>,
    /// Reorder windows of the raster cores (`--sweep-window`; docs/adaptive.md section 7): for
    /// each, `neo` at the speed table's chunk ([`window_chunk`]), one DPS pass, every speed.
    /// Empty: none.
    pub windows: Vec<usize>,
}

/// Checks a `--sweep-window` entry as the engine's `raster_window` is checked
/// ([`check_raster_window`]: a power of two in `4..=4096`, or 1 for none).
pub fn check_sweep_window(w: usize) -> Result<(), String> {
    check_raster_window(w).map_err(|e| format!("--sweep-window {e}"))
}

/// Parses `--sweep-window`'s comma-separated list: an empty list or `1` is no window; every
/// other entry must pass [`check_sweep_window`]. Repeated windows are kept once, in order.
pub fn parse_sweep_windows(list: &str) -> Result<Vec<usize>, String> {
    let mut windows = Vec::new();
    for item in list.split(',').map(str::trim).filter(|x| !x.is_empty()) {
        let w: usize = item
            .parse()
            .map_err(|_| format!("--sweep-window '{item}': expected a number of entries (power of two in 4..={MAX_RASTER_WINDOW}, or 1: none)"))?;
        if w == 1 {
            continue;
        }
        check_sweep_window(w)?;
        if !windows.contains(&w) {
            windows.push(w);
        }
    }
    Ok(windows)
}

/// The chunk of the window points: the speed table's ([`SPEED_TABLE_CHUNK`]) when the sweep
/// has it, else the sweep's first chunk (the table shows that one then), so that they are
/// rows of that table.
pub fn window_chunk(chunks: &[usize]) -> usize {
    if chunks.contains(&SPEED_TABLE_CHUNK) {
        SPEED_TABLE_CHUNK
    } else {
        chunks.first().copied().unwrap_or(SPEED_TABLE_CHUNK)
    }
}

/// The sweep's points: the grid of `s` (on the engine's own window, `base_window`), then, for
/// each of `s.windows`, `neo` at [`window_chunk`] and one DPS pass at every speed with that
/// window (those already in the grid are not repeated).
fn sweep_points(s: &SweepSpec, trajectory: &str, base_window: usize) -> Result<Vec<Point>, String> {
    for &w in &s.windows {
        check_sweep_window(w)?;
    }
    let grid = |strategies: Vec<String>, chunks: Vec<usize>, passes: Vec<usize>, raster_window| Grid {
        scenes: vec![s.scene.clone()],
        trajectory: trajectory.to_string(),
        frames: s.frames,
        res: vec![s.res.clone()],
        strategies,
        chunks,
        passes,
        speeds: s.speeds.clone(),
        raster_window,
    };
    let mut points = grid(s.strategies.clone(), s.chunks.clone(), s.passes.clone(), base_window).points()?;
    let chunk = window_chunk(&s.chunks);
    for &w in &s.windows {
        for p in grid(vec!["neo".into()], vec![chunk], vec![1], w).points()? {
            if !points.contains(&p) {
                points.push(p);
            }
        }
    }
    Ok(points)
}

/// A point of the plan and the architectures that run on its workload.
#[derive(Clone, Debug, PartialEq)]
pub struct PointJob {
    /// The point.
    pub point: Point,
    /// Architectures.
    pub archs: Vec<Arch>,
    /// Whether the golden raster runs (the sweep's PSNR).
    pub golden: GoldenRaster,
    /// A throughput run: its table is shown as soon as it is done (the headline tables need not
    /// wait for the rest of the report).
    pub headline: bool,
}

impl PointJob {
    /// True when `other` runs on the same workload: the same point and golden raster.
    pub fn shares_workload(&self, other: &PointJob) -> bool {
        self.point == other.point && self.golden == other.golden
    }
}

/// Runs the plan's points.
pub trait PointRunner {
    /// Runs `sets` of jobs (each with its name in progress messages), their workloads generated
    /// with `raster_sample` (jobs sharing their cameras together, [`crate::suite::workloads`]),
    /// and each job's architectures on its workload ([`crate::suite::evaluate`]). The sets run in
    /// order: a set's generation starts once every simulation of the sets before it has started,
    /// and its simulations queue after theirs (no core idles while a set's last simulations
    /// run). Returns, per set and in the order of its jobs, each result and the seconds from the
    /// call to its end.
    fn run_sets(
        &mut self,
        sets: &[(&[PointJob], &str)],
        raster_sample: u32,
    ) -> Result<Vec<Vec<(PointResult, f64)>>, String>;
}

/// The points of a report.
#[derive(Clone, Debug, PartialEq)]
pub struct ReportPlan {
    /// What was asked.
    pub spec: ReportSpec,
    /// Scenes of the throughput runs (the first is the main one).
    pub scenes: Vec<String>,
    /// Chunk size of the non-sweep runs.
    pub chunk: usize,
    /// DPS passes of the non-sweep runs.
    pub passes: usize,
    /// Every architecture (throughput runs).
    pub archs: Vec<Arch>,
    /// Neo-S with the engine's sorting cores, run besides on the main scene's largest
    /// resolution (the paper's Fig. 18 ablation).
    pub neo_s: Arch,
    /// Throughput and traffic runs.
    pub headline: Vec<Point>,
    /// Timelines of the compared strategies.
    pub timelines: Vec<Point>,
    /// Neo's timeline, when no throughput run provides it.
    pub neo_timeline: Point,
    /// Label of the timeline resolution.
    pub timeline_res: String,
    /// Sweep points to run.
    pub sweep: Vec<Point>,
}

/// Wall-clock seconds of a report's steps.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ReportTimes {
    /// Throughput and traffic runs (until the last is done).
    pub headline_s: f64,
    /// Timelines: from the end of the throughput runs to the end of the last timeline (those
    /// that share the throughput runs' cameras run with them).
    pub timelines_s: f64,
    /// Sweep: from the end of the steps before to the end of the last sweep point.
    pub sweep_s: f64,
}

/// A point of `frames` frames of `trajectory` at speed 1, on the engine `cfg` (its chunk, DPS
/// passes and reorder window).
fn point(
    scene: &str,
    traj: &str,
    frames: usize,
    res: &str,
    strategy: &str,
    cfg: &SimConfig,
) -> Result<Point, String> {
    let (label, w, h) = parse_res(res)?;
    Ok(Point {
        scene: scene.to_string(),
        trajectory: traj.to_string(),
        speed: 1.0,
        frames,
        res: label,
        width: w,
        height: h,
        strategy: strategy.to_string(),
        chunk: cfg.engine.chunk,
        passes: cfg.pipeline.dps_passes,
        raster_window: cfg.engine.raster_window,
    })
}

impl ReportPlan {
    /// The plan of `spec` with the model configuration `cfg` (chunk and passes of the non-sweep
    /// runs, the architectures).
    pub fn new(spec: ReportSpec, cfg: &SimConfig) -> Result<Self, String> {
        if spec.frames == 0 || spec.sweep.as_ref().is_some_and(|s| s.frames == 0) {
            return Err("the runs and the sweep points need at least 1 frame".into());
        }
        let (chunk, passes) = (cfg.engine.chunk, cfg.pipeline.dps_passes);
        let mut scenes =
            if spec.default_scene { vec![synthetic::DEFAULT_SCENE.to_string()] } else { Vec::new() };
        for s in &spec.scenes {
            if !scenes.contains(s) {
                scenes.push(s.clone());
            }
        }
        if scenes.is_empty() {
            return Err("no scene: give --scene when leaving the default scene out".into());
        }
        let archs = Arch::parse_list("all", cfg)?;
        let traj = &spec.trajectory;
        let mut headline = Vec::new();
        for s in &scenes {
            for r in &spec.res {
                headline.push(point(s, traj, spec.frames, r, "neo", cfg)?);
            }
        }
        let (timeline_res, _, _) = parse_res(&spec.timeline_res)?;
        if spec.timeline_sort.iter().any(|s| s.trim() == "neo") {
            return Err(
                "--timeline-sort: neo is in the timelines always; give the strategies compared with it"
                    .into(),
            );
        }
        // The timelines run on the main scene, the one Neo's timeline may be taken from.
        let timeline =
            |strategy: &str| point(&scenes[0], traj, spec.frames, &spec.timeline_res, strategy, cfg);
        let timelines = spec.timeline_sort.iter().map(|s| timeline(s)).collect::<Result<Vec<_>, _>>()?;
        let neo_timeline = timeline("neo")?;
        let sweep = match &spec.sweep {
            None => Vec::new(),
            Some(s) => sweep_points(s, &spec.trajectory, cfg.engine.raster_window)?,
        };
        Ok(ReportPlan {
            spec,
            scenes,
            chunk,
            passes,
            archs,
            neo_s: Arch::NeoS(cfg.engine.sort_cores as u32),
            headline,
            timelines,
            neo_timeline,
            timeline_res,
            sweep,
        })
    }

    /// Runs the plan with `runner`; `sweep_results` (read from files) come before the sweep's
    /// own points. Returns the report data and the seconds of each step.
    pub fn run(
        &self,
        runner: &mut dyn PointRunner,
        lat: &Latency,
        sweep_results: Vec<PointResult>,
    ) -> Result<(ReportData, ReportTimes), String> {
        let mut times = ReportTimes::default();
        let sample = self.spec.raster_sample;
        let PlanJobs { jobs, ablation, neo_from } = self.jobs();
        let n_sweep = self.sweep.len();
        let mut done = run_headline_first(runner, &jobs, sample)?;
        let swept = done.split_off(done.len() - n_sweep);
        let mut timed = done.split_off(self.headline.len());
        let neo_s = ablation.map(|k| (k, timed.remove(0)));
        let last = |d: &[(PointResult, f64)]| d.iter().map(|x| x.1).fold(0.0, f64::max);
        times.headline_s = last(&done);
        times.timelines_s = (last(&timed) - times.headline_s).max(0.0);
        times.sweep_s = (last(&swept) - times.headline_s - times.timelines_s).max(0.0);
        let mut headline: Vec<PointResult> = done.into_iter().map(|d| d.0).collect();
        if let Some((k, (r, _))) = neo_s {
            headline[k].archs.extend(r.archs);
        }
        let mut timelines = Vec::with_capacity(timed.len() + 1);
        if let Some(k) = neo_from {
            let mut r = headline[k].clone();
            r.archs.retain(|x| x.arch == "neo");
            timelines.push(r);
        }
        timelines.extend(timed.into_iter().map(|d| d.0));
        let mut sweep = sweep_results;
        sweep.extend(swept.into_iter().map(|d| d.0));

        let data = ReportData {
            headline,
            timelines,
            settings: ReportSettings {
                command: "neo report".into(),
                raster_timing: lat.raster_source.label(),
                preprocess_timing: lat.preprocess.label(),
                latency_file: latency::DEFAULT_PATH.into(),
                notes: self.notes(&sweep),
            },
            sweep,
        };
        Ok((data, times))
    }

    /// Every step's jobs, in order: throughput runs, Neo-S, Neo's timeline unless a throughput
    /// run is it, the compared strategies' timelines, the sweep.
    fn jobs(&self) -> PlanJobs {
        let main_scene = &self.scenes[0];
        let job = |point: &Point, archs: Vec<Arch>, golden, headline| PointJob {
            point: point.clone(),
            archs,
            golden,
            headline,
        };
        let off = GoldenRaster::Off;
        let mut jobs: Vec<PointJob> =
            self.headline.iter().map(|p| job(p, self.archs.clone(), off, true)).collect();
        // Neo-S (the Fig. 18 ablation) on the main scene's largest resolution: a job of its own,
        // on the same workload, so that the throughput table need not wait for it.
        let ablation = (0..self.headline.len())
            .filter(|&k| &self.headline[k].scene == main_scene)
            .max_by_key(|&k| self.headline[k].width as u64 * self.headline[k].height as u64);
        if let Some(k) = ablation {
            jobs.push(job(&self.headline[k], vec![self.neo_s], off, false));
        }
        let neo_from =
            self.headline.iter().position(|p| &p.scene == main_scene && p.res == self.timeline_res);
        if neo_from.is_none() {
            jobs.push(job(&self.neo_timeline, vec![Arch::Neo], off, false));
        }
        jobs.extend(self.timelines.iter().map(|p| job(p, vec![Arch::Neo], off, false)));
        jobs.extend(self.sweep.iter().map(|p| job(p, vec![Arch::Neo], GoldenRaster::Exact, false)));
        PlanJobs { jobs, ablation, neo_from }
    }

    /// Every job of the plan, in the order [`ReportPlan::run`] runs them (its points and their
    /// architectures, e.g. for checks before any workload is generated).
    pub fn point_jobs(&self) -> Vec<PointJob> {
        self.jobs().jobs
    }

    /// The report's notes on the reduced sizes used.
    fn notes(&self, sweep: &[PointResult]) -> Vec<String> {
        let mut notes = vec![
            format!(
                "Throughput, traffic and timelines: {} frames of `{}` per run (the paper renders 60; DRAM per 60 frames is frame 0, sorted from scratch, plus 59 times the mean of the others), chunk {}, {} DPS pass(es), work-only golden workloads (no golden raster; SCU early termination measured on every {}-th tile).",
                self.spec.frames, self.spec.trajectory, self.chunk, self.passes, self.spec.raster_sample
            ),
            format!("Scenes: {}.", self.scenes.iter().map(|s| format!("`{s}`")).collect::<Vec<_>>().join(", ")),
        ];
        if let Some(first) = sweep.first() {
            notes.push(format!(
                "Speed/error sweep on a smaller workload ({} points): `{}` at {}, {} frames, golden raster on (PSNR against the exact order).",
                sweep.len(),
                first.point.scene,
                first.point.res,
                first.point.frames
            ));
        }
        notes.push("GSCore-N: N sorting cores and N subtile units (N/4 raster cores of 4), hierarchical sort from scratch every frame, subtile bitmaps carried with every sort entry; GPU: Orin-AGX-like kernels with a global radix sort.".into());
        notes
    }
}

/// A plan's jobs ([`ReportPlan::jobs`]).
struct PlanJobs {
    jobs: Vec<PointJob>,
    /// The throughput run that Neo-S runs on.
    ablation: Option<usize>,
    /// The throughput run that is Neo's timeline.
    neo_from: Option<usize>,
}

/// Runs `jobs` in two sets: first the throughput runs (`headline`) with the jobs that run on
/// their workloads (same point and golden raster), then the others, so that the throughput runs
/// are not slowed by the generation of other workloads (not even of those sharing their
/// cameras: a timeline's strategy pipeline costs more than the frames' preprocessing it
/// shares); the second set starts as the first's last simulations do ([`PointRunner::run_sets`]).
/// Returns, in the order of `jobs`, each result and the seconds from the start to its end.
fn run_headline_first(
    runner: &mut dyn PointRunner,
    jobs: &[PointJob],
    sample: u32,
) -> Result<Vec<(PointResult, f64)>, String> {
    let first_set = |j: &PointJob| j.headline || jobs.iter().any(|h| h.headline && h.shares_workload(j));
    let (first, rest): (Vec<usize>, Vec<usize>) = (0..jobs.len()).partition(|&k| first_set(&jobs[k]));
    let sets: Vec<(Vec<usize>, &str)> =
        [(first, "throughput"), (rest, "report")].into_iter().filter(|(set, _)| !set.is_empty()).collect();
    let picked: Vec<Vec<PointJob>> =
        sets.iter().map(|(set, _)| set.iter().map(|&k| jobs[k].clone()).collect()).collect();
    let named: Vec<(&[PointJob], &str)> =
        picked.iter().zip(&sets).map(|(p, (_, what))| (&p[..], *what)).collect();
    let mut out: Vec<Option<(PointResult, f64)>> = vec![None; jobs.len()];
    for ((set, _), results) in sets.iter().zip(runner.run_sets(&named, sample)?) {
        for (&k, r) in set.iter().zip(results) {
            out[k] = Some(r);
        }
    }
    Ok(out.into_iter().map(|r| r.expect("every job ran")).collect())
}

/// The point results (`*.json` written by `neo simulate --out DIR`) in `dir`, by file name.
pub fn read_point_results(dir: &Path) -> Result<Vec<PointResult>, String> {
    let entries =
        std::fs::read_dir(dir).map_err(|e| format!("{}: cannot read the directory: {e}", dir.display()))?;
    let mut files: Vec<_> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "json"))
        .collect();
    files.sort();
    let mut results = Vec::new();
    for f in files {
        let text = std::fs::read_to_string(&f).map_err(|e| format!("{}: cannot read: {e}", f.display()))?;
        let r: PointResult =
            serde_json::from_str(&text).map_err(|e| format!("{}: not a point result: {e}", f.display()))?;
        results.push(r);
    }
    if results.is_empty() {
        return Err(format!("{}: no point results (*.json from `neo simulate --out DIR`)", dir.display()));
    }
    Ok(results)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::run::ArchResult;

    /// Records each set of jobs it is given and returns a result per job, the `k`-th set's
    /// ending `k + 1` seconds after the start.
    #[derive(Default)]
    struct Recorder(Vec<Vec<PointJob>>);

    impl PointRunner for Recorder {
        fn run_sets(
            &mut self,
            sets: &[(&[PointJob], &str)],
            _: u32,
        ) -> Result<Vec<Vec<(PointResult, f64)>>, String> {
            let first = self.0.len();
            self.0.extend(sets.iter().map(|(jobs, _)| jobs.to_vec()));
            Ok(sets
                .iter()
                .enumerate()
                .map(|(k, (jobs, _))| self.results(jobs, (first + k + 1) as f64))
                .collect())
        }
    }

    impl Recorder {
        /// A result per job of `jobs`, each ending at `end` seconds.
        fn results(&self, jobs: &[PointJob], end: f64) -> Vec<(PointResult, f64)> {
            let result = |j: &PointJob| PointResult {
                point: j.point.clone(),
                workload: Default::default(),
                quality: Default::default(),
                signals: None,
                archs: j
                    .archs
                    .iter()
                    .map(|a| ArchResult { arch: a.name(), ..ArchResult::default() })
                    .collect(),
            };
            jobs.iter().map(|j| (result(j), end)).collect()
        }
    }

    fn spec() -> ReportSpec {
        ReportSpec {
            scenes: Vec::new(),
            default_scene: true,
            trajectory: "orbit".into(),
            frames: 3,
            res: vec!["hd".into(), "fhd".into()],
            timeline_res: "fhd".into(),
            timeline_sort: vec!["periodic:4".into(), "hierarchical".into()],
            sweep: Some(SweepSpec {
                scene: "synthetic:outdoor?gaussians=10k&seed=1".into(),
                res: "128x64".into(),
                frames: 2,
                strategies: vec!["neo".into()],
                chunks: vec![64, 128],
                passes: vec![1],
                speeds: vec![1.0],
                windows: Vec::new(),
            }),
            raster_sample: 16,
        }
    }

    /// `spec()` with the sweep's chunks, speeds and windows.
    fn sweep_spec(chunks: &[usize], speeds: &[f64], windows: &[usize]) -> ReportSpec {
        let mut s = spec();
        let sw = s.sweep.as_mut().expect("a sweep");
        sw.strategies = vec!["neo".into(), "periodic:4".into()];
        sw.chunks = chunks.to_vec();
        sw.passes = vec![1, 2];
        sw.speeds = speeds.to_vec();
        sw.windows = windows.to_vec();
        s
    }

    #[test]
    fn window_points_are_neo_at_the_table_chunk_one_pass_every_speed() {
        let speeds = [1.0, 4.0, 16.0];
        let cfg = SimConfig::default();
        let none = ReportPlan::new(sweep_spec(&[64, 256], &speeds, &[]), &cfg).unwrap().sweep;
        assert!(none.iter().all(|p| p.raster_window == 1));
        let plan = ReportPlan::new(sweep_spec(&[64, 256], &speeds, &[256, 1024]), &cfg).unwrap();
        // The grid first, unchanged, then each window's points.
        assert_eq!(plan.sweep[..none.len()], none[..]);
        let extra = &plan.sweep[none.len()..];
        assert_eq!(extra.len(), 2 * speeds.len());
        for (k, p) in extra.iter().enumerate() {
            let w = [256, 1024][k / speeds.len()];
            assert_eq!((p.strategy.as_str(), p.chunk, p.passes), ("neo", 256, 1), "{p:?}");
            assert_eq!((p.raster_window, p.speed), (w, speeds[k % speeds.len()]), "{p:?}");
            assert_eq!((p.scene.as_str(), p.frames), (none[0].scene.as_str(), none[0].frames));
        }
        // Without chunk 256 the speed table shows the sweep's first chunk: so do the windows.
        let plan = ReportPlan::new(sweep_spec(&[128, 512], &speeds, &[64]), &cfg).unwrap();
        assert!(plan.sweep.iter().filter(|p| p.raster_window == 64).all(|p| p.chunk == 128));
        // An engine configured with a window runs every point with it, and a window point the
        // grid already has is not repeated.
        let mut windowed = cfg.clone();
        windowed.engine.raster_window = 256;
        let plan = ReportPlan::new(sweep_spec(&[64, 256], &speeds, &[256]), &windowed).unwrap();
        assert_eq!(plan.sweep.len(), none.len());
        assert!(plan.sweep.iter().chain(&plan.headline).all(|p| p.raster_window == 256));
    }

    /// The timelines run on the main scene: the given one when the default scene is left out
    /// (they ran on the default scene, while Neo's row could come from the given one's
    /// throughput run, and the report named the given one); `neo` is not a compared strategy.
    #[test]
    fn timelines_run_on_the_main_scene() {
        let given = "synthetic:outdoor?gaussians=2000&seed=1".to_string();
        let mut s = spec();
        s.default_scene = false;
        s.scenes = vec![given.clone()];
        let plan = ReportPlan::new(s.clone(), &SimConfig::default()).expect("plan");
        assert!(plan.timelines.iter().chain([&plan.neo_timeline]).all(|p| p.scene == given));
        let default = ReportPlan::new(spec(), &SimConfig::default()).expect("plan");
        assert!(default.timelines.iter().all(|p| p.scene == synthetic::DEFAULT_SCENE));
        s.timeline_sort.push("neo".into());
        let e = ReportPlan::new(s, &SimConfig::default()).unwrap_err();
        assert!(e.contains("--timeline-sort") && e.contains("neo"), "{e}");
    }

    #[test]
    fn bad_windows_are_refused_by_name() {
        for w in [0, 2, 24, 8192] {
            let e = ReportPlan::new(sweep_spec(&[256], &[1.0], &[w]), &SimConfig::default()).unwrap_err();
            assert!(e.contains(&format!("--sweep-window {w}")), "{e}");
            assert!(parse_sweep_windows(&w.to_string()).is_err(), "{w}");
        }
        assert_eq!(parse_sweep_windows("").unwrap(), Vec::<usize>::new());
        assert_eq!(parse_sweep_windows("1").unwrap(), Vec::<usize>::new());
        assert_eq!(parse_sweep_windows(" 256,1, 1024,256").unwrap(), [256, 1024]);
        assert_eq!(parse_sweep_windows("4,4096").unwrap(), [4, MAX_RASTER_WINDOW]);
        let e = parse_sweep_windows("256,big").unwrap_err();
        assert!(e.contains("--sweep-window 'big'"), "{e}");
    }

    #[test]
    fn a_window_point_has_a_workload_of_its_own() {
        let plan = ReportPlan::new(sweep_spec(&[256], &[16.0], &[256]), &SimConfig::default()).unwrap();
        let mut runner = Recorder::default();
        let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("..").join(latency::DEFAULT_PATH);
        let lat = Latency::from_file(&file).expect("reports/latency.json");
        let (data, _) = plan.run(&mut runner, &lat, Vec::new()).expect("runs");
        let jobs: Vec<&PointJob> =
            runner.0.iter().flatten().filter(|j| j.golden == GoldenRaster::Exact).collect();
        let neo = |w: usize| {
            jobs.iter()
                .find(|j| j.point.strategy == "neo" && j.point.passes == 1 && j.point.raster_window == w)
                .expect("a neo point")
        };
        let (plain, window) = (neo(1), neo(256));
        assert_eq!(plain.point.camera_key(), window.point.camera_key(), "generated together");
        assert!(!plain.shares_workload(window) && !window.shares_workload(plain));
        assert_eq!(data.sweep.last().unwrap().point.raster_window, 256);
    }

    #[test]
    fn throughput_runs_and_the_jobs_sharing_their_workloads_run_first() {
        let plan = ReportPlan::new(spec(), &SimConfig::default()).expect("plan");
        let mut runner = Recorder::default();
        let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("..").join(latency::DEFAULT_PATH);
        let lat = Latency::from_file(&file).expect("reports/latency.json");
        let (data, times) = plan.run(&mut runner, &lat, Vec::new()).expect("runs");
        let strategies = |set: &[PointJob]| {
            set.iter().map(|j| (j.point.res.clone(), j.point.strategy.clone())).collect::<Vec<_>>()
        };
        assert_eq!(runner.0.len(), 2);
        let pairs =
            |p: &[(&str, &str)]| p.iter().map(|(r, s)| (r.to_string(), s.to_string())).collect::<Vec<_>>();
        assert_eq!(strategies(&runner.0[0]), pairs(&[("hd", "neo"), ("fhd", "neo"), ("fhd", "neo")]));
        // Neo-S runs as a job of its own on the largest resolution's point (its workload), after it.
        assert_eq!(runner.0[0][2].archs, [Arch::NeoS(16)]);
        assert!(!runner.0[0][2].headline && runner.0[0][2].point == runner.0[0][1].point);
        // The compared strategies' timelines share only the cameras: they run with the sweep.
        assert_eq!(strategies(&runner.0[1])[..2], pairs(&[("fhd", "periodic:4"), ("fhd", "hierarchical")]));
        let names = |r: &PointResult| r.archs.iter().map(|a| a.arch.clone()).collect::<Vec<_>>();
        assert_eq!(names(&data.headline[0]), ["neo", "gscore4", "gscore16", "gpu"]);
        assert_eq!(names(&data.headline[1]), ["neo", "gscore4", "gscore16", "gpu", "neos16"]);
        assert!(runner.0[1][2..].iter().all(|j| j.golden == GoldenRaster::Exact && !j.headline));
        assert_eq!(runner.0[1].len(), 4);
        // Results in the plan's order; the second set (timelines and sweep) ends 1 s after the first.
        assert_eq!(data.headline.iter().map(|r| r.point.res.as_str()).collect::<Vec<_>>(), ["hd", "fhd"]);
        let timeline: Vec<&str> = data.timelines.iter().map(|r| r.point.strategy.as_str()).collect();
        assert_eq!(timeline, ["neo", "periodic:4", "hierarchical"]);
        assert_eq!(data.sweep.iter().map(|r| r.point.chunk).collect::<Vec<_>>(), [64, 128]);
        assert_eq!((times.headline_s, times.timelines_s, times.sweep_s), (1.0, 1.0, 0.0));
    }
}
