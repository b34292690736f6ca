//! Running sweep points with progress bars, for `neo simulate` and `neo report`: the model
//! inputs (configuration, measured timing), a scene cache, and a [`PointRunner`] that shows
//! each workload's frames or each group's points.

use crate::args::ModelArgs;
use anyhow::{anyhow, Result};
use indicatif::{MultiProgress, ProgressBar, ProgressDrawTarget, ProgressStyle};
use neo_golden::engine::EngineConfig;
use neo_golden::{scene::Scene, shared};
use neo_sim::config::SimConfig;
use neo_sim::driver::GoldenRaster;
use neo_sim::latency::{self, Latency};
use neo_sim::report_plan::{PointJob, PointRunner};
use neo_sim::run::{simulate, Arch, ArchResult, RunOptions};
use neo_sim::suite::{self, Point, PointResult};
use neo_sim::workload::Workload;
use std::collections::HashMap;
use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
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

/// Where the model configuration of `model` came from, to name in an error about its fields.
fn config_source(model: &ModelArgs) -> String {
    match (&model.config, &model.engine) {
        (Some(c), Some(e)) => format!("{} (engine {})", c.display(), e.display()),
        (Some(c), None) => c.display().to_string(),
        (None, Some(e)) => format!("the default configuration with engine {}", e.display()),
        (None, None) => "the default configuration".into(),
    }
}

/// Refuses, before any workload is generated, a configuration whose sorting-core buffers do
/// not hold the chunks of a point on one of its architectures, naming the configuration's files.
pub fn check_buffers<'p>(
    model: &ModelArgs,
    cfg: &SimConfig,
    jobs: impl IntoIterator<Item = (&'p Point, &'p [Arch])>,
) -> Result<()> {
    for (point, archs) in jobs {
        suite::check_point_buffers(point, cfg, archs)
            .map_err(|e| anyhow!("{}: {e}", config_source(model)))?;
    }
    Ok(())
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

/// A job's result and the seconds from the start to its end.
type Timed = (PointResult, f64);

/// One job's workload and architecture results while its simulations run.
struct JobRun {
    wl: Arc<Workload>,
    cfg: SimConfig,
    archs: Mutex<Vec<Option<Result<ArchResult, String>>>>,
    left: AtomicUsize,
}

/// Groups of the jobs sharing their cameras (indices into `jobs`), the largest first (pixels
/// times frames), else in the order of their first job.
fn camera_groups(jobs: &[PointJob]) -> Vec<Vec<usize>> {
    let mut groups: Vec<Vec<usize>> = Vec::new();
    for (k, j) in jobs.iter().enumerate() {
        match groups.iter_mut().find(|g| jobs[g[0]].point.camera_key() == j.point.camera_key()) {
            Some(g) => g.push(k),
            None => groups.push(vec![k]),
        }
    }
    // The largest first: its simulations are the longest, and the smaller groups' generation
    // and simulations fill the cores while they run (a set's last job ends sooner).
    groups.sort_by_key(|g| std::cmp::Reverse(group_cost(&jobs[g[0]].point)));
    groups
}

/// Pixels times frames of `point`: what its workload generation and its simulations grow with.
fn group_cost(point: &Point) -> u64 {
    point.width as u64 * point.height as u64 * point.frames as u64
}

/// The distinct workloads of `group` (jobs with the same point and golden raster share one):
/// the first job of each, and for every job of the group the index of its workload.
fn distinct_workloads(jobs: &[PointJob], group: &[usize]) -> (Vec<usize>, Vec<usize>) {
    let (mut unique, mut shared_by): (Vec<usize>, Vec<usize>) = (Vec::new(), Vec::new());
    for &k in group {
        let same = |&u: &usize| jobs[u].shares_workload(&jobs[k]);
        shared_by.push(unique.iter().position(same).unwrap_or_else(|| {
            unique.push(k);
            unique.len() - 1
        }));
    }
    (unique, shared_by)
}

/// The progress bar of `jobs`: a unit per frame generated and per frame simulated on each
/// accelerator (the GPU model is instant). Hidden until its set starts ([`JobSet::show`]).
fn jobs_bar(jobs: &[PointJob], what: &str) -> ProgressBar {
    let model_units =
        |j: &PointJob| (j.point.frames * j.archs.iter().filter(|a| **a != Arch::Gpu).count()) as u64;
    let total: u64 = jobs.iter().map(|j| j.point.frames as u64 + model_units(j)).sum();
    let bar = ProgressBar::with_draw_target(Some(total), ProgressDrawTarget::hidden());
    bar.set_style(
        ProgressStyle::with_template("{prefix} {bar:24} {percent:>3}% [{elapsed} < {eta}] {msg}")
            .expect("valid template"),
    );
    bar.set_prefix(what.to_string());
    bar
}

/// A set of jobs while they run: what their simulations need and where their results go.
struct JobSet<'a> {
    jobs: &'a [PointJob],
    cfg: &'a SimConfig,
    lat: &'a Latency,
    what: &'a str,
    log: &'a (dyn Fn(&PointJob, &PointResult, &str) + Sync),
    bar: ProgressBar,
    slots: Vec<Mutex<Option<Result<Timed>>>>,
    finished: AtomicUsize,
    started: Instant,
}

impl<'a> JobSet<'a> {
    /// Spawns job `k`'s simulations on `wl`, a task per architecture (each a sequential
    /// simulation, first in first out); the last of them makes the job's result.
    fn spawn<'s>(&'s self, s: &rayon::ScopeFifo<'s>, k: usize, wl: Arc<Workload>) {
        let job = &self.jobs[k];
        let run = Arc::new(JobRun {
            wl,
            cfg: suite::point_config(&job.point, self.cfg),
            archs: Mutex::new(vec![None; job.archs.len()]),
            left: AtomicUsize::new(job.archs.len()),
        });
        for (i, &arch) in job.archs.iter().enumerate() {
            let run = run.clone();
            s.spawn_fifo(move |_| {
                let r = simulate(arch, &run.cfg, self.lat, &run.wl, RunOptions::default());
                run.archs.lock().expect("arch results")[i] = Some(r);
                if arch != Arch::Gpu {
                    self.bar.inc(job.point.frames as u64);
                }
                if run.left.fetch_sub(1, Ordering::AcqRel) == 1 {
                    self.finish(k, &run);
                }
            });
        }
    }

    /// Job `k`'s result from its architectures' (all done), logged and put in its slot.
    fn finish(&self, k: usize, run: &JobRun) {
        let job = &self.jobs[k];
        let results = std::mem::take(&mut *run.archs.lock().expect("arch results"));
        let r = results
            .into_iter()
            .map(|r| r.expect("every architecture ran"))
            .collect::<Result<Vec<_>, String>>()
            .and_then(|a| suite::point_result(&job.point, &run.wl, a))
            .map_err(|e| anyhow!(e));
        let n = self.finished.fetch_add(1, Ordering::Relaxed) + 1;
        if let Ok(r) = &r {
            self.bar.suspend(|| (self.log)(job, r, &format!("[{} {n}/{}]", self.what, self.jobs.len())));
        }
        *self.slots[k].lock().expect("result slot") =
            Some(r.map(|r| (r, self.started.elapsed().as_secs_f64())));
        if n == self.jobs.len() {
            self.bar.finish_and_clear();
        }
    }

    /// Shows the set's progress bar in `multi` (its set starts).
    fn show(&self, multi: &MultiProgress) {
        multi.add(self.bar.clone());
        self.bar.enable_steady_tick(Duration::from_millis(200));
    }

    /// Generates the set's workloads, group after group (the largest first), and spawns each
    /// job's simulations on its workload as soon as it is made; with throughput runs
    /// (`headline`) in the set, the other jobs' simulations are spawned after all of theirs.
    fn generate<'s>(&'s self, s: &rayon::ScopeFifo<'s>, scenes: &Scenes, raster_sample: u32) -> Result<()> {
        let jobs = self.jobs;
        let any_headline = jobs.iter().any(|j| j.headline);
        let mut deferred = Vec::new();
        for g in camera_groups(jobs) {
            let (unique, shared_by) = distinct_workloads(jobs, &g);
            let points: Vec<&Point> = unique.iter().map(|&k| &jobs[k].point).collect();
            let first = points[0];
            let scene = scenes.loaded(&first.scene).expect("loaded by run_job_sets");
            let msg =
                format!("generating {} workload(s) at {} ({} frames)", points.len(), first.res, first.frames);
            self.bar.set_message(msg);
            let golden: Vec<GoldenRaster> = unique.iter().map(|&k| jobs[k].golden).collect();
            let wls = suite::workloads_with(scene, &points, &golden, self.cfg, raster_sample, |_| {
                self.bar.inc(g.len() as u64)
            })
            .map_err(|e| anyhow!(e))?;
            let wls: Vec<Arc<Workload>> = wls.into_iter().map(Arc::new).collect();
            for (&k, &i) in g.iter().zip(&shared_by) {
                if jobs[k].headline || !any_headline {
                    self.spawn(s, k, wls[i].clone());
                } else {
                    deferred.push((k, wls[i].clone()));
                }
            }
        }
        for (k, wl) in deferred {
            self.spawn(s, k, wl);
        }
        Ok(())
    }
}

/// [`JobSet`]s running in order on one pool ([`run_job_sets`]).
struct SetsRun<'a> {
    sets: Vec<JobSet<'a>>,
    scenes: &'a Scenes,
    raster_sample: u32,
    multi: MultiProgress,
    /// The first generation error (the sets after it do not start).
    failed: Mutex<Option<anyhow::Error>>,
}

impl SetsRun<'_> {
    /// Starts set `i`: generates its workloads and spawns its simulations, then queues the next
    /// set's start after them. The pool takes its tasks in order, so the next set starts once
    /// every simulation of this one has: on the first core they leave free.
    fn start<'s>(&'s self, s: &rayon::ScopeFifo<'s>, i: usize) {
        let set = &self.sets[i];
        set.show(&self.multi);
        if let Err(e) = set.generate(s, self.scenes, self.raster_sample) {
            self.failed.lock().expect("error slot").get_or_insert(e);
            return;
        }
        if i + 1 < self.sets.len() {
            s.spawn_fifo(move |s| self.start(s, i + 1));
        }
    }
}

/// Runs `jobs` on the machine's cores: the workloads of jobs that share their cameras are
/// generated together ([`suite::workloads`]), group after group, the largest first (jobs with
/// the same point and golden raster share one), and each job's architectures run on its workload
/// ([`suite::evaluate`]) while the next groups generate; in a set with throughput runs
/// (`headline`), the other jobs' simulations are queued after all of theirs. One progress bar
/// over the work with its ETA; `log` reports each finished job. Returns, in the order of
/// `jobs`, each result and the seconds from the start to its end.
#[allow(clippy::too_many_arguments)]
pub fn run_jobs(
    scenes: &mut Scenes,
    jobs: &[PointJob],
    cfg: &SimConfig,
    lat: &Latency,
    raster_sample: u32,
    what: &str,
    log: &(dyn Fn(&PointJob, &PointResult, &str) + Sync),
) -> Result<Vec<Timed>> {
    let mut sets = run_job_sets(scenes, &[(jobs, what)], cfg, lat, raster_sample, log)?;
    Ok(sets.pop().expect("one set"))
}

/// Runs `sets` of jobs (each with its name in progress messages) as [`run_jobs`] runs one, in
/// order, on one pool: a set's generation starts once every simulation of the sets before it
/// has started ([`SetsRun::start`]), and its simulations queue after theirs. So no core idles
/// while a set's last simulations run, and a set's work never delays the earlier sets'
/// simulations. A progress bar per set, shown while it runs. Returns, per set and in the order
/// of its jobs, each result and the seconds from the start to its end.
pub fn run_job_sets(
    scenes: &mut Scenes,
    sets: &[(&[PointJob], &str)],
    cfg: &SimConfig,
    lat: &Latency,
    raster_sample: u32,
    log: &(dyn Fn(&PointJob, &PointResult, &str) + Sync),
) -> Result<Vec<Vec<Timed>>> {
    for j in sets.iter().flat_map(|(jobs, _)| jobs.iter()) {
        scenes.get(&j.point.scene)?;
    }
    let scenes = &*scenes;
    let started = Instant::now();
    let sets = sets
        .iter()
        .map(|&(jobs, what)| JobSet {
            jobs,
            cfg,
            lat,
            what,
            log,
            bar: jobs_bar(jobs, what),
            slots: jobs.iter().map(|_| Mutex::new(None)).collect(),
            finished: AtomicUsize::new(0),
            started,
        })
        .collect();
    let run = SetsRun { sets, scenes, raster_sample, multi: MultiProgress::new(), failed: Mutex::new(None) };
    if !run.sets.is_empty() {
        rayon::scope_fifo(|s| run.start(s, 0));
    }
    for set in &run.sets {
        set.bar.finish_and_clear();
    }
    if let Some(e) = run.failed.into_inner().expect("error slot") {
        return Err(e);
    }
    run.sets
        .into_iter()
        .map(|set| {
            set.slots
                .into_iter()
                .map(|m| m.into_inner().expect("result slot").expect("every spawned job is done"))
                .collect()
        })
        .collect()
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

/// One log line (stderr) about a finished point: its FPS per architecture, its workload's
/// generation time and the seconds since `started`.
pub fn log_point(started: Instant, r: &PointResult, label: &str) {
    let fps: Vec<String> = r.archs.iter().map(|a| format!("{} {:.1}", a.arch, a.fps)).collect();
    eprintln!(
        "{label} {} {} {} c{} p{} {}x: FPS {} (workload {:.1} s; {:.0} s elapsed)",
        r.point.res,
        r.point.strategy_label(),
        r.point.frames,
        r.point.chunk,
        r.point.passes,
        r.point.speed,
        fps.join(", "),
        r.workload.generation_s,
        started.elapsed().as_secs_f64()
    );
}

impl PointRunner for ProgressRunner<'_> {
    fn run_sets(
        &mut self,
        sets: &[(&[PointJob], &str)],
        raster_sample: u32,
    ) -> Result<Vec<Vec<(PointResult, f64)>>, String> {
        let started = self.started;
        // Throughput runs print their table as soon as they are done, and the last of them the
        // table of all.
        let n_headline = sets.iter().flat_map(|(jobs, _)| jobs.iter()).filter(|j| j.headline).count();
        let headline = Mutex::new(Vec::new());
        let log = move |j: &PointJob, r: &PointResult, label: &str| {
            log_point(started, r, label);
            if !j.headline {
                return;
            }
            println!("{}", neo_sim::report::point_table(r));
            let mut done = headline.lock().expect("headline results");
            done.push(r.clone());
            if done.len() == n_headline {
                println!(
                    "throughput runs done in {:.0} s:\n{}",
                    started.elapsed().as_secs_f64(),
                    neo_sim::report::headline_table(&done)
                );
            }
        };
        run_job_sets(&mut self.scenes, sets, self.cfg, self.lat, raster_sample, &log)
            .map_err(|e| format!("{e:#}"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn job(res: &str, (width, height): (u32, u32), strategy: &str) -> PointJob {
        let point = Point {
            scene: "synthetic:outdoor".into(),
            trajectory: "orbit".into(),
            speed: 1.0,
            frames: 8,
            res: res.into(),
            width,
            height,
            strategy: strategy.into(),
            chunk: 256,
            passes: 1,
            raster_window: 1,
        };
        PointJob { point, archs: vec![Arch::Neo], golden: GoldenRaster::Off, headline: false }
    }

    #[test]
    fn camera_groups_come_largest_first_and_keep_their_order_on_ties() {
        let jobs = [
            job("hd", (1280, 720), "neo"),
            job("a", (640, 360), "neo"),
            job("qhd", (2560, 1440), "neo"),
            job("hd", (1280, 720), "periodic:4"),
            job("b", (360, 640), "neo"),
        ];
        assert_eq!(camera_groups(&jobs), [vec![2], vec![0, 3], vec![1], vec![4]]);
    }
}
