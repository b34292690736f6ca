//! `neo trajectory`: generate a camera trajectory and write it as an INRIA cameras.json.

use crate::args::{image_side, refuse_overwriting_input, spec_paths, SceneArg, TrajectoryArg};
use crate::progress::spin;
use anyhow::Result;
use clap::Args;
use neo_golden::{source, trajectory};
use std::path::PathBuf;

/// Arguments of `neo trajectory`.
#[derive(Args)]
pub struct TrajectoryArgs {
    #[command(flatten)]
    pub scene: SceneArg,
    #[command(flatten)]
    pub trajectory: TrajectoryArg,
    /// Number of frames (30 fps), unless the spec sets `frames=`.
    #[arg(long, default_value_t = 60)]
    pub frames: usize,
    /// Override the image width, 1 to 16384 (the field of view is kept).
    #[arg(long, value_parser = image_side)]
    pub width: Option<u32>,
    /// Override the image height, 1 to 16384 (the field of view is kept).
    #[arg(long, value_parser = image_side)]
    pub height: Option<u32>,
    /// The cameras.json to write.
    #[arg(long)]
    pub out: PathBuf,
}

/// Runs `neo trajectory`.
pub fn run(a: TrajectoryArgs) -> Result<()> {
    let mut inputs: Vec<(&str, PathBuf)> =
        spec_paths(&a.scene.scene).into_iter().map(|p| ("the --scene file", p)).collect();
    inputs.extend(spec_paths(&a.trajectory.trajectory).into_iter().map(|p| ("the --trajectory file", p)));
    refuse_overwriting_input(&a.out, "--out", &inputs)?;
    let (loaded, _) =
        spin(&format!("loading {}", a.scene.scene), || source::load_scene(&a.scene.scene, false));
    let (scene, _) = loaded?;
    let mut traj =
        trajectory::parse_trajectory(&a.trajectory.trajectory, source::robust_bounds(&scene), a.frames)?;
    if a.width.is_some() || a.height.is_some() {
        let first = &traj.frames[0];
        let (w, h) = (a.width.unwrap_or(first.width), a.height.unwrap_or(first.height));
        traj = traj.with_resolution(w, h);
    }
    traj.write(&a.out)?;
    println!(
        "wrote {} frames at {} fps ({} scene cuts) to {}",
        traj.frames.len(),
        traj.fps,
        traj.cuts.len(),
        a.out.display()
    );
    Ok(())
}
