//! Arguments several commands share, defined once and flattened into each command's arguments
//! (`#[command(flatten)]`).

use anyhow::{bail, Result};
use clap::Args;
use neo_golden::scene::LoadReport;
use neo_golden::trajectory::parse_resolution;
use neo_golden::trajectory::resolution::{parse_side, MAX_SIDE};
use neo_golden::trajectory::spec::MAX_FRAMES;
use neo_golden::{camera::Camera, cameras_json, scene::Scene, source, synthetic, trajectory};
use neo_sim::latency;
use std::path::{Path, PathBuf};

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
    /// Treat Gaussians with non-finite (NaN or infinite) values as an error instead of dropping
    /// them.
    #[arg(long)]
    pub strict: bool,
}

/// Warns on stderr about the Gaussians loading dropped (with the words `neo scene info` uses).
pub fn warn_dropped(report: &LoadReport) {
    if report.dropped_non_finite > 0 {
        eprintln!("warning: dropped {} Gaussians with non-finite values", report.dropped_non_finite);
    }
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
    /// Number of frames: the trajectory's first N (a cameras.json, or a spec that sets
    /// `frames=`, must have at least N).
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
    /// Work-only workloads (no golden raster): measure early termination on every K-th tile
    /// (0: on none, every Gaussian counted as blended: termination ratio 1).
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

/// An image side (`--width`, `--height`): an integer from 1 to [`MAX_SIDE`], the bound of
/// `--res` and of cameras.json sizes.
pub fn image_side(s: &str) -> Result<u32, String> {
    parse_side(s.trim()).map_err(|_| format!("'{s}' is not an integer from 1 to {MAX_SIDE}"))
}

/// The files a scene, camera or trajectory argument may name: the spec itself, the path after
/// `file:` and the file before a `#SELECTOR`. Only the ones that exist matter to
/// [`refuse_overwriting_input`].
pub fn spec_paths(spec: &str) -> Vec<PathBuf> {
    let mut paths = vec![PathBuf::from(spec)];
    if let Some(p) = spec.trim().strip_prefix("file:") {
        paths.push(PathBuf::from(p));
    }
    if let Some((file, _)) = spec.rsplit_once('#') {
        paths.push(PathBuf::from(file));
    }
    paths
}

/// True when `a` and `b` both exist and are the same file (same canonical path, or on Unix the
/// same device and inode, which also catches hard links).
fn same_file(a: &Path, b: &Path) -> bool {
    let (Ok(ca), Ok(cb)) = (std::fs::canonicalize(a), std::fs::canonicalize(b)) else { return false };
    if ca == cb {
        return true;
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        if let (Ok(ma), Ok(mb)) = (std::fs::metadata(&ca), std::fs::metadata(&cb)) {
            return ma.dev() == mb.dev() && ma.ino() == mb.ino();
        }
    }
    false
}

/// Refuses to write `out` (given by `flag`) when it is the same file as one of `inputs`
/// (`(what, path)` pairs, e.g. `("the scene", path)`): the error names the file and the flag,
/// and is raised before anything is read or written.
pub fn refuse_overwriting_input(out: &Path, flag: &str, inputs: &[(&str, PathBuf)]) -> Result<()> {
    if let Some((what, _)) = inputs.iter().find(|(_, input)| same_file(out, input)) {
        bail!(
            "{}: {flag} is the same file as {what}; refusing to overwrite an input (nothing written)",
            out.display()
        );
    }
    Ok(())
}

/// Where the camera comes from.
#[derive(Args, Clone)]
pub struct ViewArgs {
    /// A camera from an INRIA cameras.json: `FILE#i` (index) or `FILE#name`.
    #[arg(long, conflicts_with_all = ["trajectory", "frame"])]
    pub camera: Option<String>,
    /// A trajectory spec (`orbit`, `orbit:radius=R,height=H,speed=S`, `walk`, `shake`, or a
    /// cameras.json); the default is `orbit`, which frames the whole scene.
    #[arg(long)]
    pub trajectory: Option<String>,
    /// Which frame of the trajectory.
    #[arg(long, default_value_t = 0)]
    pub frame: usize,
    /// Override the image width, 1 to 16384 (the field of view is kept).
    #[arg(long, value_parser = image_side)]
    pub width: Option<u32>,
    /// Override the image height, 1 to 16384 (the field of view is kept).
    #[arg(long, value_parser = image_side)]
    pub height: Option<u32>,
}

impl ViewArgs {
    /// The input files the camera or trajectory spec may name (see [`spec_paths`]).
    pub fn input_paths(&self) -> Vec<(&'static str, PathBuf)> {
        let mut paths = Vec::new();
        if let Some(spec) = &self.camera {
            paths.extend(spec_paths(spec).into_iter().map(|p| ("the --camera file", p)));
        }
        if let Some(spec) = &self.trajectory {
            paths.extend(spec_paths(spec).into_iter().map(|p| ("the --trajectory file", p)));
        }
        paths
    }

    /// Resolves the camera for `scene`.
    pub fn camera(&self, scene: &Scene) -> Result<Camera> {
        let cam = match &self.camera {
            Some(spec) => cameras_json::parse_camera_spec(spec)?,
            None => {
                let spec = self.trajectory.as_deref().unwrap_or("orbit");
                if self.frame >= MAX_FRAMES {
                    bail!(
                        "--frame {}: must be below {MAX_FRAMES}, the most frames a trajectory spec makes \
                         (for a longer cameras.json, use --camera FILE#INDEX)",
                        self.frame
                    );
                }
                let traj = trajectory::parse_trajectory(spec, source::robust_bounds(scene), self.frame + 1)?;
                match traj.frames.get(self.frame) {
                    Some(c) => c.clone(),
                    None => bail!(
                        "--frame {}: trajectory '{spec}' has {} frames, numbered 0 to {}",
                        self.frame,
                        traj.frames.len(),
                        traj.frames.len().saturating_sub(1)
                    ),
                }
            }
        };
        let (w, h) = (self.width.unwrap_or(cam.width), self.height.unwrap_or(cam.height));
        Ok(if (w, h) == (cam.width, cam.height) { cam } else { cam.with_resolution(w, h) })
    }
}
