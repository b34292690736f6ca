//! Arguments several commands share, defined once and flattened into each command's arguments
//! (`#[command(flatten)]`).

use anyhow::{bail, Result};
use clap::Args;
use neo_golden::trajectory::parse_resolution;
use neo_golden::{camera::Camera, cameras_json, scene::Scene, source, synthetic, trajectory};
use neo_sim::latency;
use std::path::PathBuf;

/// The scene to load.
#[derive(Args, Clone)]
pub struct SceneArg {
    /// A .ply (standard or compressed) or a synthetic spec (`synthetic:NAME?gaussians=N&seed=S`).
    #[arg(long, default_value = synthetic::DEFAULT_SCENE)]
    pub scene: String,
}

/// How strictly the scene is read.
#[derive(Args, Clone)]
pub struct StrictArg {
    /// Treat Gaussians with NaN values as an error instead of dropping them.
    #[arg(long)]
    pub strict: bool,
}

/// The camera trajectory.
#[derive(Args, Clone)]
pub struct TrajectoryArg {
    /// Trajectory spec (`orbit[:...]`, `walk[:...]`, `shake[:...]`, `file:PATH` or a
    /// cameras.json); scene cuts come from its `cut=` key or the file's `"cut"` entries.
    #[arg(long, default_value = "orbit")]
    pub trajectory: String,
}

/// How many frames of the trajectory run.
#[derive(Args, Clone)]
pub struct FramesArg {
    /// Number of frames, unless the spec sets `frames=`.
    #[arg(long, default_value_t = 30)]
    pub frames: usize,
}

/// The cycle model's inputs.
#[derive(Args, Clone)]
pub struct ModelArgs {
    /// Model configuration (JSON; missing fields keep their defaults).
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// Engine configuration: the JSON file `neo gen --config` takes (any subset of its fields);
    /// replaces the `engine` section of the model configuration.
    #[arg(long)]
    pub engine: Option<PathBuf>,
    /// Measured unit timing.
    #[arg(long, default_value = latency::DEFAULT_PATH)]
    pub latency: PathBuf,
    /// Work-only workloads (no golden raster): measure early termination on every K-th tile.
    #[arg(long, default_value_t = 16)]
    pub raster_sample: u32,
    /// Byte-size preset replacing the configuration's `sizes`: `neo` (FP32 parameters, golden's
    /// feature entries), `neo-f16sh` (the same with binary16 SH records, the engine's
    /// `PRE_CTRL.sh_half`) or `artifact` (the official artifact's FP16 parameters and 22-byte
    /// feature entries).
    #[arg(long)]
    pub sizes: Option<String>,
}

/// A resolution argument (`hd`, `fhd`, `qhd` or `WxH`), checked by golden's parser and kept as
/// written (its label).
pub fn resolution(s: &str) -> Result<String, String> {
    parse_resolution(s).map(|_| s.to_string())
}

/// Where the camera comes from.
#[derive(Args, Clone)]
pub struct ViewArgs {
    /// A camera from an INRIA cameras.json: `FILE#i` (index) or `FILE#name`.
    #[arg(long, conflicts_with = "trajectory")]
    pub camera: Option<String>,
    /// A trajectory spec (`orbit`, `orbit:radius=R,height=H,speed=S`, `walk`, `shake`, or a
    /// cameras.json); the default is `orbit`, which frames the whole scene.
    #[arg(long)]
    pub trajectory: Option<String>,
    /// Which frame of the trajectory.
    #[arg(long, default_value_t = 0)]
    pub frame: usize,
    /// Override the image width (the field of view is kept).
    #[arg(long)]
    pub width: Option<u32>,
    /// Override the image height (the field of view is kept).
    #[arg(long)]
    pub height: Option<u32>,
}

impl ViewArgs {
    /// Resolves the camera for `scene`.
    pub fn camera(&self, scene: &Scene) -> Result<Camera> {
        let cam = match &self.camera {
            Some(spec) => cameras_json::parse_camera_spec(spec)?,
            None => {
                let spec = self.trajectory.as_deref().unwrap_or("orbit");
                let traj = trajectory::parse_trajectory(spec, source::robust_bounds(scene), self.frame + 1)?;
                match traj.frames.get(self.frame) {
                    Some(c) => c.clone(),
                    None => bail!(
                        "trajectory '{spec}' has {} frames; frame {} requested",
                        traj.frames.len(),
                        self.frame
                    ),
                }
            }
        };
        let (w, h) = (self.width.unwrap_or(cam.width), self.height.unwrap_or(cam.height));
        if w == 0 || h == 0 {
            bail!("image size must be positive, got {w}x{h}");
        }
        Ok(if (w, h) == (cam.width, cam.height) { cam } else { cam.with_resolution(w, h) })
    }
}
