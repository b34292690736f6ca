//! Building blocks shared by the synthetic scenes: one Gaussian before conversion, surface and
//! volume shapes with trained-scene-like scale statistics, opacity mixtures and colours.
//!
//! The statistics follow the real trained scene `biker.ply` (152k Gaussians): the largest to
//! smallest axis ratio has a median near 19 and a long tail (10th/90th percentiles about 5 and
//! 75), the middle axis splits it roughly evenly in log space, and opacities are bimodal (about
//! 34% below 0.1, 8% above 0.9, median 0.17).

use super::rng::HashRng;
use glam::{DMat3, DQuat, DVec3};

/// One generated Gaussian in world units, before conversion to the [`crate::scene::Scene`]
/// arrays.
#[derive(Clone, Copy, Debug)]
pub struct Splat {
    /// Mean.
    pub position: DVec3,
    /// Natural log of the standard deviations along the local axes.
    pub log_scale: [f64; 3],
    /// Unit rotation quaternion (local axes to world).
    pub rotation: DQuat,
    /// Opacity in `[0, 1]`.
    pub opacity: f64,
    /// Base colour (linear RGB, `[0, 1]`), turned into the degree-0 SH coefficient.
    pub color: [f64; 3],
}

/// Standard deviation of the log of the in-plane size around its nominal value.
pub const LOG_SIZE_SIGMA: f64 = 0.55;
/// In-plane geometric-mean standard deviation as a fraction of the local spacing.
pub const SIZE_PER_SPACING: f64 = 0.7;
/// Mean of the normally distributed `ln(max / min)` (fitted to biker.ply: median ratio 18.7,
/// 10th/90th percentiles 5.1 and 75).
pub const LOG_ANISOTROPY_MEAN: f64 = 2.93;
/// Standard deviation of `ln(max / min)`.
pub const LOG_ANISOTROPY_SIGMA: f64 = 1.02;
/// Largest `ln(max / min)` (a ratio of about 1100).
pub const MAX_LOG_ANISOTROPY: f64 = 7.0;

/// Log-scales `[long, mid, short]` for a Gaussian whose in-plane size (geometric mean of the
/// long and mid axes) is about `SIZE_PER_SPACING * spacing`, log-normally distributed. The
/// anisotropy `ln(long / short)` is normal ([`LOG_ANISOTROPY_MEAN`], [`LOG_ANISOTROPY_SIGMA`])
/// and the mid axis splits it at a uniformly random point in log space.
pub fn log_scales(rng: &mut HashRng, spacing: f64) -> [f64; 3] {
    log_scales_with(rng, SIZE_PER_SPACING * spacing, LOG_ANISOTROPY_MEAN, LOG_ANISOTROPY_SIGMA)
}

/// Log-scales `[long, mid, short]` with in-plane size log-normal around `size` and
/// `ln(long / short)` normal with mean `aniso_mean` and deviation `aniso_sigma`, clamped to
/// `[0, MAX_LOG_ANISOTROPY]`; the mid axis splits it at a uniform point in log space.
pub fn log_scales_with(rng: &mut HashRng, size: f64, aniso_mean: f64, aniso_sigma: f64) -> [f64; 3] {
    let g = size.ln() + LOG_SIZE_SIGMA * rng.normal();
    let total = (aniso_mean + aniso_sigma * rng.normal()).clamp(0.0, MAX_LOG_ANISOTROPY);
    let split = rng.uniform();
    let elong = (1.0 - split) * total;
    let flat = split * total;
    let long = g + 0.5 * elong;
    let mid = g - 0.5 * elong;
    [long, mid, mid - flat]
}

/// Mean, log-scales `[long, mid, short]` and rotation of one Gaussian.
pub type Placed = (DVec3, [f64; 3], DQuat);

/// A flat Gaussian lying on a surface with unit normal `normal`: its shortest axis is the
/// normal, the in-plane orientation is random, the scales follow [`log_scales`].
pub fn on_surface(rng: &mut HashRng, position: DVec3, normal: DVec3, spacing: f64) -> Placed {
    let scales = log_scales(rng, spacing);
    oriented(rng, position, normal, scales)
}

/// A Gaussian with log-scales `scales` (`[long, mid, short]`) whose shortest axis is `normal`,
/// in-plane orientation random.
pub fn oriented(rng: &mut HashRng, position: DVec3, normal: DVec3, scales: [f64; 3]) -> Placed {
    let n = normal.normalize_or(DVec3::NEG_Y);
    let (t1, t2) = n.any_orthonormal_pair();
    let phi = rng.range(0.0, std::f64::consts::TAU);
    let u = t1 * phi.cos() + t2 * phi.sin();
    let v = n.cross(u);
    let q = DQuat::from_mat3(&DMat3::from_cols(u, v, n)).normalize();
    (position, scales, q)
}

/// A Gaussian with a uniformly random orientation (foliage), scales from [`log_scales`].
pub fn in_volume(rng: &mut HashRng, position: DVec3, spacing: f64) -> Placed {
    let scales = log_scales(rng, spacing);
    randomly_oriented(rng, position, scales)
}

/// A Gaussian with log-scales `scales` and a uniformly random orientation.
pub fn randomly_oriented(rng: &mut HashRng, position: DVec3, scales: [f64; 3]) -> Placed {
    let [w, x, y, z] = rng.unit_quaternion();
    (position, scales, DQuat::from_xyzw(x, y, z, w).normalize())
}

/// Opacity logit mixture fitted to the biker scene's opacity histogram:
/// 50% N(-2.25, 1), 38% N(-1, 1.5), 12% N(3, 2).
pub fn trained_opacity(rng: &mut HashRng) -> f64 {
    let c = rng.uniform();
    let (mu, sd) = if c < 0.5 {
        (-2.25, 1.0)
    } else if c < 0.88 {
        (-1.0, 1.5)
    } else {
        (3.0, 2.0)
    };
    sigmoid(mu + sd * rng.normal())
}

/// Opacity with a logit drawn from N(`mu`, `sd`).
pub fn opacity_around(rng: &mut HashRng, mu: f64, sd: f64) -> f64 {
    sigmoid(mu + sd * rng.normal())
}

fn sigmoid(x: f64) -> f64 {
    1.0 / (1.0 + (-x).exp())
}

/// `base` with per-Gaussian variation: brightness times `1 + 0.15 N`, each channel `+ 0.03 N`,
/// clamped to `[0, 1]`.
pub fn vary(rng: &mut HashRng, base: [f64; 3]) -> [f64; 3] {
    let b = 1.0 + 0.15 * rng.normal();
    base.map(|c| (c * b + 0.03 * rng.normal()).clamp(0.0, 1.0))
}

/// Linear interpolation between two colours.
pub fn mix(a: [f64; 3], b: [f64; 3], t: f64) -> [f64; 3] {
    let t = t.clamp(0.0, 1.0);
    [a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t, a[2] + (b[2] - a[2]) * t]
}

/// Builds a [`Splat`] from a shape and appearance.
pub fn splat(shape: Placed, opacity: f64, color: [f64; 3]) -> Splat {
    Splat { position: shape.0, log_scale: shape.1, rotation: shape.2, opacity, color }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn surface_gaussians_are_flat_along_the_normal() {
        let mut rng = HashRng::new(1, 2, 3);
        let n = DVec3::new(1.0, -2.0, 0.5).normalize();
        for _ in 0..100 {
            let (_, s, q) = on_surface(&mut rng, DVec3::ZERO, n, 0.1);
            assert!(s[2] <= s[1] && s[1] <= s[0]);
            // The third local axis (the shortest) maps to the normal.
            assert!((q * DVec3::Z - n).length() < 1e-9);
        }
    }

    #[test]
    fn opacity_mixture_is_bimodal() {
        let mut rng = HashRng::new(9, 0, 0);
        let v: Vec<f64> = (0..100_000).map(|_| trained_opacity(&mut rng)).collect();
        let low = v.iter().filter(|&&o| o < 0.1).count() as f64 / v.len() as f64;
        let high = v.iter().filter(|&&o| o > 0.9).count() as f64 / v.len() as f64;
        // biker.ply: 34.5% below 0.1 and 8.1% above 0.9.
        assert!((0.29..0.40).contains(&low), "{low}");
        assert!((0.05..0.11).contains(&high), "{high}");
    }
}
