//! Walk/fly-through: the camera moves along a smooth closed path at walking pace, looking along
//! the direction of motion with a gentle look-around (yaw) and a slight downward tilt.

use super::{bounds_f64, scene_unit, Shot, Trajectory, WORLD_UP};
use crate::synthetic::rng::HashRng;
use glam::{DQuat, DVec3};

/// Walking pace at 1x in scene units ([`scene_unit`]) per second.
pub const WALKING_PACE: f64 = 1.4;
/// Eye height above the ground in scene units.
pub const EYE_HEIGHT: f64 = 1.6;
/// Dense samples per spline segment for the arc-length table.
const SAMPLES_PER_SEGMENT: usize = 64;

/// A walk: a closed path and how the camera moves along it.
#[derive(Clone, Debug, PartialEq)]
pub struct WalkParams {
    /// Control points of a closed uniform Catmull-Rom spline (at least 3).
    pub waypoints: Vec<DVec3>,
    /// Speed along the path at 1x, world units per second.
    pub pace: f64,
    /// Amplitude of the look-around yaw, degrees.
    pub yaw_deg: f64,
    /// Period of the look-around, seconds of path time.
    pub yaw_period_s: f64,
    /// Downward tilt of the view, degrees.
    pub pitch_deg: f64,
}

impl WalkParams {
    /// A loop across a scene with bounds `bounds`: 8 waypoints on a seeded, irregular ellipse
    /// around the box centre covering 30% of the horizontal extent on each side (or of mean
    /// radius `radius`), at `eye_height` (default [`EYE_HEIGHT`] scene units) above the ground,
    /// which is the largest y of the box (y is down). Pace [`WALKING_PACE`] scene units per
    /// second, 8 degrees of look-around every 12 s, 5 degrees of downward tilt.
    pub fn across(
        bounds: ([f32; 3], [f32; 3]),
        seed: u64,
        eye_height: Option<f64>,
        radius: Option<f64>,
    ) -> Self {
        let unit = scene_unit(bounds);
        let (lo, hi) = bounds_f64(bounds);
        let c = (lo + hi) * 0.5;
        let y = hi.y - eye_height.unwrap_or(EYE_HEIGHT * unit);
        let (rx, rz) = match radius {
            Some(r) => (r, r),
            None => (((hi.x - lo.x) * 0.3).max(unit), ((hi.z - lo.z) * 0.3).max(unit)),
        };
        let mut rng = HashRng::new(seed, 0x7761_6c6b, 0);
        let n = 8;
        let waypoints = (0..n)
            .map(|k| {
                let a = (k as f64 + rng.range(-0.2, 0.2)) * std::f64::consts::TAU / n as f64;
                let s = rng.range(0.8, 1.2);
                DVec3::new(c.x + rx * s * a.sin(), y, c.z - rz * s * a.cos())
            })
            .collect();
        WalkParams { waypoints, pace: WALKING_PACE * unit, yaw_deg: 8.0, yaw_period_s: 12.0, pitch_deg: 5.0 }
    }
}

/// A closed uniform Catmull-Rom spline with an arc-length table.
struct Loop<'a> {
    points: &'a [DVec3],
    /// Cumulative length at dense parameter `k / SAMPLES_PER_SEGMENT`.
    lengths: Vec<f64>,
}

impl<'a> Loop<'a> {
    fn new(points: &'a [DVec3]) -> Self {
        let steps = points.len() * SAMPLES_PER_SEGMENT;
        let mut lengths = Vec::with_capacity(steps + 1);
        lengths.push(0.0);
        let mut prev = Self::eval(points, 0.0).0;
        for k in 1..=steps {
            let p = Self::eval(points, k as f64 / SAMPLES_PER_SEGMENT as f64).0;
            lengths.push(lengths[k - 1] + (p - prev).length());
            prev = p;
        }
        Loop { points, lengths }
    }

    fn total(&self) -> f64 {
        *self.lengths.last().unwrap_or(&0.0)
    }

    /// Position and derivative at spline parameter `t` in `[0, n)`.
    fn eval(points: &[DVec3], t: f64) -> (DVec3, DVec3) {
        let n = points.len();
        let i = (t.floor() as usize).min(n - 1);
        let u = t - i as f64;
        let p = |k: isize| points[(i as isize + k).rem_euclid(n as isize) as usize];
        let (p0, p1, p2, p3) = (p(-1), p(0), p(1), p(2));
        let a = p1 * 2.0;
        let b = p2 - p0;
        let c = p0 * 2.0 - p1 * 5.0 + p2 * 4.0 - p3;
        let d = p1 * 3.0 - p0 - p2 * 3.0 + p3;
        let pos = (a + b * u + c * (u * u) + d * (u * u * u)) * 0.5;
        let der = (b + c * (2.0 * u) + d * (3.0 * u * u)) * 0.5;
        (pos, der)
    }

    /// Position and unit tangent at arc length `s` (wrapped around the loop).
    fn at(&self, s: f64) -> (DVec3, DVec3) {
        let total = self.total();
        let s = s.rem_euclid(total);
        let k = self.lengths.partition_point(|&l| l <= s).clamp(1, self.lengths.len() - 1);
        let (l0, l1) = (self.lengths[k - 1], self.lengths[k]);
        let frac = if l1 > l0 { (s - l0) / (l1 - l0) } else { 0.0 };
        let t = ((k - 1) as f64 + frac) / SAMPLES_PER_SEGMENT as f64;
        let (pos, der) = Self::eval(self.points, t);
        (pos, der.normalize_or(DVec3::Z))
    }
}

/// Generates a walk: frame `f` is at arc length `pace * t(f)` plus half the loop per scene cut
/// at or before `f` (a cut jumps to the far side of the loop).
pub fn walk(p: &WalkParams, shot: &Shot) -> Trajectory {
    let path = Loop::new(&p.waypoints);
    let total = path.total();
    let frames = (0..shot.frames)
        .map(|f| {
            let name = Shot::frame_name(f);
            let t = shot.time(f);
            if !(total > 0.0 && total.is_finite()) {
                let pos = p.waypoints.first().copied().unwrap_or(DVec3::ZERO);
                return shot.intrinsics.look_at(&name, pos, pos + DVec3::Z);
            }
            let s = p.pace * t + 0.5 * total * shot.cuts_before(f) as f64;
            let (pos, tangent) = path.at(s);
            let level = DVec3::new(tangent.x, 0.0, tangent.z).normalize_or(DVec3::Z);
            let yaw = (p.yaw_deg * (std::f64::consts::TAU * t / p.yaw_period_s).sin()).to_radians();
            let heading = DQuat::from_axis_angle(WORLD_UP, yaw) * level;
            let pitch = p.pitch_deg.to_radians();
            let forward = heading * pitch.cos() - WORLD_UP * pitch.sin();
            shot.intrinsics.look_at(&name, pos, pos + forward)
        })
        .collect();
    shot.finish(frames)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spline_passes_through_waypoints_and_arc_length_is_uniform() {
        let pts: Vec<DVec3> = (0..6)
            .map(|k| {
                let a = k as f64 * std::f64::consts::TAU / 6.0;
                DVec3::new(10.0 * a.cos(), 0.0, 10.0 * a.sin())
            })
            .collect();
        let l = Loop::new(&pts);
        assert!((Loop::eval(&pts, 2.0).0 - pts[2]).length() < 1e-12);
        // Between the hexagon's perimeter and the circle's circumference.
        assert!(l.total() > 60.0 && l.total() < std::f64::consts::TAU * 10.0, "{}", l.total());
        let step = 0.05;
        let d: Vec<f64> =
            (0..200).map(|k| (l.at(k as f64 * step).0 - l.at((k + 1) as f64 * step).0).length()).collect();
        assert!(d.iter().all(|&x| (x - step).abs() < 0.01 * step), "{d:?}");
    }
}
