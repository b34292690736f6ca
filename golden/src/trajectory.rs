//! Camera trajectories at 30 fps: orbit, walk/fly-through and hand-held shake.
//!
//! World convention: y points DOWN (as in the INRIA captures and the biker scene), so world "up"
//! is [`WORLD_UP`] `= (0, -1, 0)` and the ground is at the largest y of a scene.
//!
//! Every generator takes a [`Shot`] (frame count, speed multiplier, scene cuts, intrinsics):
//! - the speed multiplier makes the path be traversed faster while the frame rate stays
//!   [`DEFAULT_FPS`] (frame `f` is taken at path time `speed * f / fps`);
//! - a scene cut at frame `K` makes frame `K` jump to a different viewpoint (the opposite side
//!   of an orbit, another part of a walk) and is recorded in [`Trajectory::cuts`].
//!
//! Spec strings ([`parse_trajectory`]) are documented in [`spec`].

pub mod orbit;
pub mod resolution;
pub mod shake;
pub mod spec;
pub mod walk;

pub use orbit::{orbit, OrbitParams};
pub use resolution::parse_resolution;
pub use shake::{shake, ShakeParams};
pub use spec::parse_trajectory;
pub use walk::{walk, WalkParams};

use crate::camera::{look_at_rotation, Camera};
use crate::cameras_json;
use crate::error::{InputError, InputResult};
use glam::DVec3;
use std::path::Path;

/// Frame rate of generated trajectories and of files without an `"fps"` field.
pub const DEFAULT_FPS: f64 = 30.0;
/// Default image width in pixels.
pub const DEFAULT_WIDTH: u32 = 1280;
/// Default image height in pixels.
pub const DEFAULT_HEIGHT: u32 = 720;
/// Default horizontal field of view in degrees.
pub const DEFAULT_FOV_X_DEG: f64 = 60.0;
/// World "up" (y is down in the INRIA convention).
pub const WORLD_UP: DVec3 = DVec3::new(0.0, -1.0, 0.0);
/// The horizontal scene extent that counts as 50 "metres" in [`scene_unit`].
pub const REFERENCE_EXTENT_UNITS: f64 = 50.0;

/// A camera sequence.
#[derive(Clone, Debug, PartialEq)]
pub struct Trajectory {
    /// Frames per second.
    pub fps: f64,
    /// One camera per frame.
    pub frames: Vec<Camera>,
    /// Frame indices that start a new shot (scene cuts), ascending.
    pub cuts: Vec<usize>,
}

impl Trajectory {
    /// Keeps the first `frames` frames and the scene cuts among them (what `--frames` runs of a
    /// cameras.json or of a spec that sets `frames=`); an error when there are fewer.
    pub fn take_first(&mut self, frames: usize) -> Result<(), String> {
        if self.frames.len() < frames {
            return Err(format!("has {} frame(s); {frames} requested", self.frames.len()));
        }
        self.frames.truncate(frames);
        self.cuts.retain(|&c| c < frames);
        Ok(())
    }

    /// Number of frames.
    pub fn len(&self) -> usize {
        self.frames.len()
    }

    /// True when there are no frames.
    pub fn is_empty(&self) -> bool {
        self.frames.is_empty()
    }

    /// The same poses at another resolution, keeping the horizontal field of view and the
    /// pixel aspect (`fx` and `fy` both scale by `width / old width`), which is what `--res`
    /// means.
    pub fn with_resolution(&self, width: u32, height: u32) -> Trajectory {
        let frames = self
            .frames
            .iter()
            .map(|c| {
                let s = width as f64 / c.width as f64;
                Camera { width, height, fx: c.fx * s, fy: c.fy * s, ..c.clone() }
            })
            .collect();
        Trajectory { frames, ..self.clone() }
    }

    /// Writes the trajectory as a `cameras.json` (with the `fps` and `cut` extension fields).
    pub fn write(&self, path: &Path) -> InputResult<()> {
        cameras_json::write_cameras(path, &self.frames, &self.cuts, Some(self.fps))
    }

    /// Reads a trajectory back from a `cameras.json`: the frame rate is the first `"fps"` field
    /// found ([`DEFAULT_FPS`] when there is none), the cuts are the entries with `"cut": true`.
    pub fn read(path: &Path) -> InputResult<Trajectory> {
        let entries = cameras_json::read_cameras(path)?;
        if entries.is_empty() {
            return Err(InputError::new(path, "the file holds no cameras"));
        }
        let fps = entries.iter().find_map(|e| e.fps).unwrap_or(DEFAULT_FPS);
        let cuts = entries.iter().enumerate().filter(|(_, e)| e.cut).map(|(i, _)| i).collect();
        Ok(Trajectory { fps, frames: entries.into_iter().map(|e| e.camera).collect(), cuts })
    }
}

/// Pinhole intrinsics of generated cameras: square pixels, principal point at the centre.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Intrinsics {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Horizontal field of view in degrees.
    pub fov_x_deg: f64,
}

impl Default for Intrinsics {
    fn default() -> Self {
        Intrinsics { width: DEFAULT_WIDTH, height: DEFAULT_HEIGHT, fov_x_deg: DEFAULT_FOV_X_DEG }
    }
}

impl Intrinsics {
    /// Focal length in pixels (`fx = fy`): `W / (2 tan(fov_x / 2))`.
    pub fn focal(&self) -> f64 {
        self.width as f64 / (2.0 * (self.fov_x_deg.to_radians() * 0.5).tan())
    }

    /// The smaller of the horizontal and vertical half fields of view, in radians.
    pub fn min_half_fov(&self) -> f64 {
        let f = self.focal();
        (self.width.min(self.height) as f64 / (2.0 * f)).atan()
    }

    /// A camera named `name` at `position` looking at `target`, upright: world up
    /// [`WORLD_UP`] appears at the top of the image (camera x right, y down, z forward).
    pub fn look_at(&self, name: &str, position: DVec3, target: DVec3) -> Camera {
        let f = self.focal();
        Camera {
            name: name.to_string(),
            width: self.width,
            height: self.height,
            fx: f,
            fy: f,
            position,
            cam_to_world: look_at_rotation(position, target, WORLD_UP),
        }
    }
}

/// What every generator needs besides its path: length, speed, cuts and intrinsics.
#[derive(Clone, Debug, PartialEq)]
pub struct Shot {
    /// Number of frames.
    pub frames: usize,
    /// Speed multiplier (1 = natural speed); the frame rate stays [`DEFAULT_FPS`].
    pub speed: f64,
    /// Frames that jump to a different viewpoint, ascending, each in `1..frames`.
    pub cuts: Vec<usize>,
    /// Camera intrinsics.
    pub intrinsics: Intrinsics,
}

impl Shot {
    /// `frames` frames at 1x, no cuts, default intrinsics.
    pub fn new(frames: usize) -> Self {
        Shot { frames, speed: 1.0, cuts: Vec::new(), intrinsics: Intrinsics::default() }
    }

    /// Path time in seconds of frame `f` (already multiplied by the speed).
    pub fn time(&self, f: usize) -> f64 {
        self.speed * f as f64 / DEFAULT_FPS
    }

    /// Number of cuts at or before frame `f` (how many jumps frame `f` has seen).
    pub fn cuts_before(&self, f: usize) -> usize {
        self.cuts.iter().filter(|&&c| c <= f).count()
    }

    /// Frame name used in `img_name`.
    pub fn frame_name(f: usize) -> String {
        format!("frame_{f:05}")
    }

    /// Assembles a trajectory from per-frame cameras.
    fn finish(&self, frames: Vec<Camera>) -> Trajectory {
        let mut cuts: Vec<usize> = self.cuts.iter().copied().filter(|&c| c < frames.len()).collect();
        cuts.sort_unstable();
        cuts.dedup();
        Trajectory { fps: DEFAULT_FPS, frames, cuts }
    }
}

/// The length that plays the part of one metre for a scene: its larger horizontal (x or z)
/// extent divided by [`REFERENCE_EXTENT_UNITS`] (typical outdoor captures span some 50 m).
/// Walking speed, eye height and hand-shake amplitude scale with it. Never below `1e-6`.
pub fn scene_unit(bounds: ([f32; 3], [f32; 3])) -> f64 {
    let (lo, hi) = bounds;
    let ext = ((hi[0] - lo[0]) as f64).max((hi[2] - lo[2]) as f64);
    if ext.is_finite() {
        (ext / REFERENCE_EXTENT_UNITS).max(1e-6)
    } else {
        1.0
    }
}

/// Bounds as double-precision `(min, max)` corners, with non-finite values replaced by 0.
pub(crate) fn bounds_f64(bounds: ([f32; 3], [f32; 3])) -> (DVec3, DVec3) {
    let f = |a: [f32; 3]| DVec3::from_array(a.map(|v| if v.is_finite() { v as f64 } else { 0.0 }));
    let (lo, hi) = (f(bounds.0), f(bounds.1));
    (lo.min(hi), lo.max(hi))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn look_at_is_upright_and_right_handed() {
        // Looking along +z from the -z side, like the biker "front" camera: x = +x, y = +y.
        let c = Intrinsics::default().look_at("c", DVec3::new(0.0, -1.6, -5.0), DVec3::new(0.0, -1.6, 0.0));
        assert!((c.cam_to_world.x_axis - DVec3::X).length() < 1e-12);
        assert!((c.cam_to_world.y_axis - DVec3::Y).length() < 1e-12);
        assert!((c.cam_to_world.determinant() - 1.0).abs() < 1e-12);
        // The biker "left" camera at x = -5 has x = (0, 0, -1).
        let c = Intrinsics::default().look_at("l", DVec3::new(-5.0, -1.6, 0.0), DVec3::new(0.0, -1.6, 0.0));
        assert!((c.cam_to_world.x_axis - DVec3::NEG_Z).length() < 1e-12);
    }

    #[test]
    fn focal_matches_the_field_of_view() {
        let i = Intrinsics::default();
        let c = i.look_at("c", DVec3::ZERO, DVec3::Z);
        assert!((c.tan_half_fov_x() as f64 - (30f64).to_radians().tan()).abs() < 1e-6);
        assert!((i.focal() - 640.0 / (30f64).to_radians().tan()).abs() < 1e-9);
        // Landscape: the vertical half fov is the smaller one.
        assert!((i.min_half_fov().tan() - 360.0 / i.focal()).abs() < 1e-12);
    }

    #[test]
    fn with_resolution_keeps_the_horizontal_fov() {
        let t = Trajectory {
            fps: 30.0,
            frames: vec![Intrinsics::default().look_at("a", DVec3::ZERO, DVec3::Z)],
            cuts: vec![],
        };
        let r = t.with_resolution(640, 640);
        assert_eq!((r.frames[0].width, r.frames[0].height), (640, 640));
        assert!((r.frames[0].tan_half_fov_x() - t.frames[0].tan_half_fov_x()).abs() < 1e-6);
        assert_eq!(r.frames[0].fx, r.frames[0].fy);
        assert_eq!(r.frames[0].cam_to_world, t.frames[0].cam_to_world);
    }

    #[test]
    fn scene_unit_uses_the_horizontal_extent() {
        assert_eq!(scene_unit(([-50.0, -3.0, -10.0], [50.0, 0.0, 10.0])), 2.0);
        assert_eq!(scene_unit(([0.0; 3], [0.0; 3])), 1e-6);
    }
}
