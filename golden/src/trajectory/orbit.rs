//! Orbits: the camera circles a target at a fixed radius and height, always looking at it.

use super::{bounds_f64, Intrinsics, Shot, Trajectory, WORLD_UP};
use glam::DVec3;

/// Angular speed of an orbit at 1x, degrees per second (a full turn in 30 s, about walking pace
/// around a subject 7 m away).
pub const DEFAULT_DEG_PER_S: f64 = 12.0;
/// Elevation of the default orbit above the target, degrees.
pub const DEFAULT_ELEVATION_DEG: f64 = 25.0;
/// Fraction of the half image kept free around the framed box on each side.
pub const FRAMING_MARGIN: f64 = 0.05;

/// An orbit: where it circles and how fast.
#[derive(Clone, Debug, PartialEq)]
pub struct OrbitParams {
    /// The orbit centre and look-at point.
    pub target: DVec3,
    /// Horizontal distance from the target.
    pub radius: f64,
    /// Height of the camera above the target (along world up, i.e. towards -y).
    pub height: f64,
    /// Azimuth of frame 0 in degrees: 0 puts the camera on the -z side looking towards +z,
    /// 90 on the +x side.
    pub start_deg: f64,
    /// Angular speed at 1x in degrees per second.
    pub deg_per_s: f64,
}

impl OrbitParams {
    /// The default orbit of a scene with bounds `bounds`: around the box centre at
    /// [`DEFAULT_ELEVATION_DEG`], as close as possible while all 8 box corners stay inside the
    /// image (with [`FRAMING_MARGIN`]) from every azimuth.
    pub fn framing(bounds: ([f32; 3], [f32; 3]), intrinsics: &Intrinsics) -> OrbitParams {
        let (lo, hi) = bounds_f64(bounds);
        let target = (lo + hi) * 0.5;
        let d = fit_distance(bounds, intrinsics, DEFAULT_ELEVATION_DEG);
        let e = DEFAULT_ELEVATION_DEG.to_radians();
        OrbitParams {
            target,
            radius: d * e.cos(),
            height: d * e.sin(),
            start_deg: 0.0,
            deg_per_s: DEFAULT_DEG_PER_S,
        }
    }

    /// Camera centre at azimuth `deg`.
    pub fn position(&self, deg: f64) -> DVec3 {
        let a = deg.to_radians();
        self.target + DVec3::new(a.sin(), 0.0, -a.cos()) * self.radius + WORLD_UP * self.height
    }
}

/// The smallest distance from the centre of `bounds` at which, looking at that centre from
/// elevation `elevation_deg` and any azimuth (sampled every 2.5 degrees), all 8 corners of the
/// box lie in the image with [`FRAMING_MARGIN`]. 1 for an empty (point) box.
pub fn fit_distance(bounds: ([f32; 3], [f32; 3]), intrinsics: &Intrinsics, elevation_deg: f64) -> f64 {
    let (lo, hi) = bounds_f64(bounds);
    let target = (lo + hi) * 0.5;
    let f = intrinsics.focal();
    let kx = intrinsics.width as f64 * 0.5 * (1.0 - FRAMING_MARGIN) / f;
    let ky = intrinsics.height as f64 * 0.5 * (1.0 - FRAMING_MARGIN) / f;
    let e = elevation_deg.to_radians();
    let mut d: f64 = 0.0;
    for step in 0..144 {
        let a = (step as f64 * 2.5).to_radians();
        let dir = DVec3::new(e.cos() * a.sin(), 0.0, -e.cos() * a.cos()) + WORLD_UP * e.sin();
        let cam = intrinsics.look_at("fit", target + dir, target);
        let to_view = cam.cam_to_world.transpose();
        for corner in 0..8 {
            let p = DVec3::new(
                if corner & 1 == 0 { lo.x } else { hi.x },
                if corner & 2 == 0 { lo.y } else { hi.y },
                if corner & 4 == 0 { lo.z } else { hi.z },
            );
            // In view space the corner sits at v + (0, 0, d) for a camera at distance d.
            let v = to_view * (p - target);
            d = d.max(v.x.abs() / kx - v.z).max(v.y.abs() / ky - v.z);
        }
    }
    if d > 1e-9 && d.is_finite() {
        d
    } else {
        1.0
    }
}

/// Generates an orbit: frame `f` is at azimuth `start + deg_per_s * t(f)` plus 180 degrees per
/// scene cut at or before `f` (a cut jumps to the opposite side).
pub fn orbit(p: &OrbitParams, shot: &Shot) -> Trajectory {
    let frames = (0..shot.frames)
        .map(|f| {
            let deg = p.start_deg + p.deg_per_s * shot.time(f) + 180.0 * shot.cuts_before(f) as f64;
            shot.intrinsics.look_at(&Shot::frame_name(f), p.position(deg), p.target)
        })
        .collect();
    shot.finish(frames)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn azimuth_zero_is_on_the_minus_z_side_above_the_target() {
        let p =
            OrbitParams { target: DVec3::ZERO, radius: 5.0, height: 2.0, start_deg: 0.0, deg_per_s: 12.0 };
        let c = p.position(0.0);
        assert!((c - DVec3::new(0.0, -2.0, -5.0)).length() < 1e-12);
        assert!((p.position(90.0) - DVec3::new(5.0, -2.0, 0.0)).length() < 1e-12);
    }

    #[test]
    fn fit_distance_is_tight() {
        let b = ([-1.0, -1.0, -1.0], [1.0, 1.0, 1.0]);
        let i = Intrinsics::default();
        let d = fit_distance(b, &i, 25.0);
        // Closer than the circumscribed-sphere distance, farther than the inscribed one (with
        // the framing margin taken off the field of view).
        let half = (i.min_half_fov().tan() * (1.0 - FRAMING_MARGIN)).atan();
        assert!(d < 3f64.sqrt() / half.sin() && d > 1.0 / half.tan(), "{d}");
        assert_eq!(fit_distance(([2.0; 3], [2.0; 3]), &i, 25.0), 1.0);
    }
}
