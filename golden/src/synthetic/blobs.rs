//! The `blobs` scene: Gaussians scattered uniformly in the box `[-1, 1]^3`, with random
//! orientations, random colours and the trained-scene scale and opacity statistics. Small and
//! simple, for unit tests.

use super::rng::HashRng;
use super::splat::{in_volume, splat, trained_opacity, Splat};
use glam::DVec3;

/// Half the side of the box.
pub const HALF_SIDE: f64 = 1.0;

/// One Gaussian of a `blobs` scene of `n` Gaussians.
pub fn sample(n: usize, rng: &mut HashRng) -> Splat {
    let p = DVec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0)) * HALF_SIDE;
    let spacing = (8.0 * HALF_SIDE.powi(3) / n.max(1) as f64).cbrt();
    let color = [rng.uniform(), rng.uniform(), rng.uniform()];
    splat(in_volume(rng, p, spacing), trained_opacity(rng), color)
}
