//! Hand-held shake: a mostly still camera with small, band-limited, seeded jitter of position
//! and orientation, like a camera held by hand.
//!
//! Each of the six channels (x, y, z offset; pitch, yaw, roll) is a sum of four sinusoids near
//! 0.7, 1.3, 2.9 and 5.3 Hz (each frequency varied by up to 15% and each phase drawn from the
//! seed), normalised to unit RMS and scaled by the amplitude.

use super::{orbit::OrbitParams, scene_unit, Intrinsics, Shot, Trajectory};
use crate::synthetic::rng::HashRng;
use glam::{DMat3, DVec3, EulerRot};

/// Positional jitter at 1x, RMS per axis, in scene units ([`scene_unit`]): 1 cm.
pub const POSITION_JITTER: f64 = 0.01;
/// Rotational jitter at 1x, RMS per axis, degrees.
pub const ANGLE_JITTER_DEG: f64 = 0.3;
/// Centre frequencies of the jitter components, Hz.
const FREQUENCIES_HZ: [f64; 4] = [0.7, 1.3, 2.9, 5.3];
/// Relative amplitudes of the jitter components.
const WEIGHTS: [f64; 4] = [1.0, 0.6, 0.35, 0.2];

/// A hand-held shot: where the camera is held and how much it shakes.
#[derive(Clone, Debug, PartialEq)]
pub struct ShakeParams {
    /// Rest position of the camera centre.
    pub position: DVec3,
    /// Point the camera looks at when at rest.
    pub target: DVec3,
    /// RMS positional jitter per world axis, world units.
    pub amplitude: f64,
    /// RMS rotational jitter per camera axis, degrees.
    pub angle_deg: f64,
    /// Seed of the jitter frequencies and phases.
    pub seed: u64,
}

impl ShakeParams {
    /// Held at the pose of frame 0 of `orbit`, with `amp` times the 1x jitter
    /// ([`POSITION_JITTER`] scene units, [`ANGLE_JITTER_DEG`]).
    pub fn at_orbit_start(orbit: &OrbitParams, bounds: ([f32; 3], [f32; 3]), seed: u64, amp: f64) -> Self {
        ShakeParams {
            position: orbit.position(orbit.start_deg),
            target: orbit.target,
            amplitude: POSITION_JITTER * scene_unit(bounds) * amp,
            angle_deg: ANGLE_JITTER_DEG * amp,
            seed,
        }
    }

    /// The default: the default orbit's first pose of a scene with these bounds.
    pub fn framing(bounds: ([f32; 3], [f32; 3]), intrinsics: &Intrinsics, seed: u64) -> Self {
        Self::at_orbit_start(&OrbitParams::framing(bounds, intrinsics), bounds, seed, 1.0)
    }
}

/// One band-limited jitter channel with unit RMS.
struct Channel {
    parts: [(f64, f64, f64); 4],
}

impl Channel {
    fn new(seed: u64, index: u64) -> Self {
        let mut rng = HashRng::new(seed, 0x7368_616b, index);
        let norm = (WEIGHTS.iter().map(|w| w * w * 0.5).sum::<f64>()).sqrt();
        let parts = std::array::from_fn(|k| {
            let f = FREQUENCIES_HZ[k] * rng.range(0.85, 1.15);
            let phase = rng.range(0.0, std::f64::consts::TAU);
            (WEIGHTS[k] / norm, f, phase)
        });
        Channel { parts }
    }

    fn at(&self, t: f64) -> f64 {
        self.parts.iter().map(|&(a, f, ph)| a * (std::f64::consts::TAU * f * t + ph).sin()).sum()
    }
}

/// Generates a hand-held shot. A scene cut moves the rest pose to the opposite side of the
/// target (its horizontal offset is mirrored), and each further cut moves it back.
pub fn shake(p: &ShakeParams, shot: &Shot) -> Trajectory {
    let ch: Vec<Channel> = (0..6).map(|i| Channel::new(p.seed, i)).collect();
    let mirrored = {
        let d = p.position - p.target;
        p.target + DVec3::new(-d.x, d.y, -d.z)
    };
    let frames = (0..shot.frames)
        .map(|f| {
            let t = shot.time(f);
            let rest = if shot.cuts_before(f) % 2 == 1 { mirrored } else { p.position };
            let base = shot.intrinsics.look_at(&Shot::frame_name(f), rest, p.target);
            let offset = DVec3::new(ch[0].at(t), ch[1].at(t), ch[2].at(t)) * p.amplitude;
            let a = p.angle_deg.to_radians();
            let jitter = DMat3::from_euler(EulerRot::XYZ, ch[3].at(t) * a, ch[4].at(t) * a, ch[5].at(t) * a);
            let mut cam = base;
            cam.position += offset;
            cam.cam_to_world *= jitter;
            cam
        })
        .collect();
    shot.finish(frames)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn channels_have_unit_rms_and_are_band_limited() {
        let c = Channel::new(3, 0);
        let n = 30_000;
        let dt = 1.0 / 300.0;
        let rms = ((0..n).map(|k| c.at(k as f64 * dt).powi(2)).sum::<f64>() / n as f64).sqrt();
        assert!((rms - 1.0).abs() < 0.05, "{rms}");
        // The fastest component is below 6.1 Hz, so the slope is bounded by 2 pi 6.1 sum(a).
        let bound: f64 = c.parts.iter().map(|p| p.0 * std::f64::consts::TAU * 6.1).sum();
        let max_slope =
            (0..n).map(|k| (c.at((k + 1) as f64 * dt) - c.at(k as f64 * dt)).abs() / dt).fold(0.0, f64::max);
        assert!(max_slope <= bound, "{max_slope} > {bound}");
    }
}
