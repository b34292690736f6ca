//! Running the pipeline along a trajectory, and the `stats.json` document.

use serde::Serialize;

use super::config::{ConfigRecord, Formats, PipelineConfig, PipelineError};
use super::frame::{FrameOutput, Pipeline};
use super::stats::{FrameStats, Summary, Timing};
use crate::camera::Camera;
use crate::scene::Scene;
use crate::trajectory::Trajectory;

/// The `stats.json` document: `{"config": ..., "frames": [...], "summary": ...}`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StatsFile {
    /// The run's parameters.
    pub config: ConfigRecord,
    /// One record per frame.
    pub frames: Vec<FrameStats>,
    /// Summary over the frames.
    pub summary: Summary,
}

impl StatsFile {
    /// Assembles the document.
    pub fn new(config: ConfigRecord, frames: Vec<FrameStats>) -> Self {
        let summary = Summary::new(&frames, config.sort_entry_bytes);
        StatsFile { config, frames, summary }
    }
}

/// Renders the first `frames` frames of `traj` (all when `None`), calling `on_frame` after
/// each; returns the per-frame statistics. Cuts come from [`Trajectory::cuts`].
pub fn run_trajectory<E: From<PipelineError>>(
    scene: &Scene,
    traj: &Trajectory,
    frames: Option<usize>,
    cfg: PipelineConfig,
    formats: Formats,
    mut on_frame: impl FnMut(&Pipeline, &FrameOutput) -> Result<(), E>,
) -> Result<Vec<FrameStats>, E> {
    let n = frames.unwrap_or(traj.len()).min(traj.len());
    let Some(first) = traj.frames.first() else {
        return Ok(Vec::new());
    };
    let mut p = Pipeline::new(scene, cfg, formats, first.width, first.height)?;
    let mut stats = Vec::with_capacity(n);
    for (i, cam) in traj.frames.iter().take(n).enumerate() {
        let out = p.render_frame(cam, i, traj.cuts.contains(&i));
        on_frame(&p, &out)?;
        stats.push(out.stats);
    }
    Ok(stats)
}

/// The formats a run uses: the artifact's, or fitted to the cameras when `fitted`.
pub fn formats_for(
    scene: &Scene,
    cams: &[Camera],
    cfg: &PipelineConfig,
    fitted: bool,
) -> Result<Formats, PipelineError> {
    if fitted {
        Formats::fitted(scene, cams, cfg.raster.tile, cfg.chunk)
    } else {
        Formats::artifact(cfg.chunk)
    }
}

/// Timing of the golden pipeline alone (no references, no metrics) over `cams` in sequence,
/// one [`Timing`] per frame. The first frame sorts from scratch; later ones run the strategy's
/// steady state. For `neo bench`.
pub fn bench_frames(
    scene: &Scene,
    cams: &[Camera],
    cfg: &PipelineConfig,
) -> Result<Vec<Timing>, PipelineError> {
    let Some(first) = cams.first() else {
        return Ok(Vec::new());
    };
    let cfg = PipelineConfig { compare_exact: false, compare_float: false, ssim: false, ..cfg.clone() };
    let formats = Formats::artifact(cfg.chunk)?;
    let mut p = Pipeline::new(scene, cfg, formats, first.width, first.height)?;
    Ok(cams.iter().enumerate().map(|(i, c)| p.render_frame(c, i, false).stats.timing).collect())
}
