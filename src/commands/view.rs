//! Choosing the view to render: one camera of a cameras.json, or one frame of a trajectory.

use anyhow::{bail, Result};
use clap::Args;
use neo_golden::{camera::Camera, cameras_json, scene::Scene, source, trajectory};

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
