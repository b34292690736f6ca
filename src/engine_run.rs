//! Running the verilated `neo_engine` frame by frame against the golden model, for `neo cosim`
//! and `neo bench engine`: the engine configuration of `--config`, the trajectory at
//! `--frames`/`--res`, the build of the model behind a spinner, and the frame loop (the golden
//! host session writes each frame's inputs, the rig runs the RTL and compares bit-exactly).

use anyhow::{anyhow, Context, Result};
use indicatif::{ProgressBar, ProgressStyle};
use neo_golden::engine::host::FramePlan;
use neo_golden::engine::memory::Memory;
use neo_golden::engine::{EngineConfig, EngineSession, HostMode, SessionOptions};
use neo_golden::scene::Scene;
use neo_golden::source;
use neo_golden::trajectory::{parse_trajectory, Trajectory};
use neo_tb::axi::AddrRecord;
use neo_tb::engine::{EngineModel, EngineRig, FrameReport};
use neo_tb::waves::WaveFormat;
use std::path::Path;
use std::time::{Duration, Instant};

/// The engine configuration of `--config` (the JSON `neo gen --config` takes), or the default
/// 16 + 4 engine; validated, with an error naming the file and the field.
pub fn engine_config(path: Option<&Path>) -> Result<EngineConfig> {
    let cfg = match path {
        Some(p) => EngineConfig::from_json_file(p)?,
        None => EngineConfig::default(),
    };
    cfg.validate()
        .map_err(|e| anyhow!("{}: {e}", path.map_or("default".into(), |p| p.display().to_string())))?;
    Ok(cfg)
}

/// The trajectory `spec` of `scene` with its first `frames` frames at resolution `res`.
pub fn trajectory_at(spec: &str, scene: &Scene, frames: usize, res: (u32, u32)) -> Result<Trajectory> {
    let mut traj = parse_trajectory(spec, source::robust_bounds(scene), frames)?;
    traj.take_first(frames).map_err(|e| anyhow!("--trajectory {spec:?} {e}"))?;
    let (w, h) = res;
    traj.frames = traj.frames.iter().map(|c| c.with_resolution(w, h)).collect();
    Ok(traj)
}

/// The golden host session of `traj` on `scene` for engine `cfg`, feeding the engine as
/// `opts.mode` says, its tables sorted by `opts.strategy` (`neo`, or `adaptive` with per-tile
/// DPS passes), the scene's SH records in `opts.sh`.
pub fn session<'s>(
    scene: &'s Scene,
    traj: Trajectory,
    cfg: &EngineConfig,
    opts: SessionOptions,
) -> Result<EngineSession<'s>> {
    EngineSession::with_options(scene, traj, cfg, opts).context("engine session")
}

/// The host mode named by `--input`: `scene` or `lists`.
pub fn host_mode(input: &str) -> Result<HostMode> {
    match input {
        "scene" => Ok(HostMode::Scene),
        "lists" => Ok(HostMode::Lists),
        other => Err(anyhow!(
            "--input {other:?}: expected `scene` (the engine preprocesses the baked scene) or `lists` (the host writes the lists and feature words)"
        )),
    }
}

/// Builds (or finds in the cache) the verilated engine of `cfg`, traced in `format` (`None`:
/// untraced) and evaluated on `threads` Verilator threads, behind a spinner.
pub fn build_engine(cfg: &EngineConfig, format: Option<WaveFormat>, threads: usize) -> Result<EngineModel> {
    let spin = spinner("building the verilated engine (cached after the first build)");
    let engine = EngineModel::build_threaded(cfg, format, threads);
    spin.finish_and_clear();
    engine.map_err(|e| anyhow!("building neo_engine: {e}"))
}

/// One frame the rig ran.
pub struct FrameRun<T> {
    /// What the rig found.
    pub report: FrameReport,
    /// Wall time of the RTL run (the harness included, the golden host's work not).
    pub took: Duration,
    /// Tiles over the table capacity (reported, not sorted).
    pub overflowing: Vec<usize>,
    /// What `before` returned for this frame.
    pub before: T,
    /// Every AR and AW of the frame with its memory client's index, when the rig records them
    /// ([`EngineRig::record_transfers`]; else empty).
    pub transfers: Vec<(AddrRecord, usize)>,
}

/// Runs the remaining frames of `session` on `rig`. `before(plan, memory)` runs after the host
/// wrote the frame's inputs and before the RTL (e.g. the cycle model's prediction); `after`
/// gets each frame. Stops after the first frame that is not bit-exact and returns its index
/// (`None`: every frame bit-exact).
pub fn run_frames<T>(
    session: &mut EngineSession,
    rig: &mut EngineRig,
    mut before: impl FnMut(&FramePlan, &mut Memory) -> Result<T>,
    mut after: impl FnMut(FrameRun<T>),
) -> Result<Option<usize>> {
    while let Some(plan) = session.next_frame(rig.memory_mut())? {
        let overflowing: Vec<usize> = plan
            .expected
            .outcome
            .results
            .iter()
            .enumerate()
            .filter(|(_, r)| r.overflow)
            .map(|(t, _)| t)
            .collect();
        let b = before(&plan, rig.memory_mut())?;
        let t0 = Instant::now();
        let report = rig.run_frame(&plan).map_err(|e| anyhow!(e))?;
        let took = t0.elapsed();
        let failed = report.mismatch.is_some().then_some(report.frame);
        let transfers = rig.take_transfers();
        after(FrameRun { report, took, overflowing, before: b, transfers });
        if failed.is_some() {
            return Ok(failed);
        }
    }
    Ok(None)
}

/// A frame's verdict for the text output: `bit-exact`, or `MISMATCH` and the first mismatch.
pub fn frame_status(report: &FrameReport) -> String {
    match &report.mismatch {
        None => "bit-exact".to_string(),
        Some(m) => format!("MISMATCH {m}"),
    }
}

/// A spinner with `msg` on stderr.
pub fn spinner(msg: &str) -> ProgressBar {
    let p = ProgressBar::new_spinner();
    p.set_message(msg.to_string());
    p.enable_steady_tick(Duration::from_millis(200));
    p
}

/// A bar over `frames` frames (hidden when `hidden`, e.g. for JSON output).
pub fn frame_bar(frames: u64, hidden: bool) -> ProgressBar {
    if hidden {
        return ProgressBar::hidden();
    }
    let p = ProgressBar::new(frames);
    let style = ProgressStyle::with_template("{bar:30} frame {pos}/{len} {elapsed_precise} (eta {eta})")
        .unwrap_or_else(|_| ProgressStyle::default_bar());
    p.set_style(style);
    p.enable_steady_tick(Duration::from_millis(500));
    p
}
