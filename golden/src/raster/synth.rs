//! Hand-made preprocessed Gaussians, for tests and examples of the fixed-point rasterizer.

use crate::render::Projected;

/// A [`Projected`] Gaussian built from its 2D covariance the way
/// [`crate::render::preprocess`] finishes one: the conic is the f32 inverse of `cov2d`, the
/// radius `ceil(3 sqrt(lambda_max))` (with the reference's 0.1 floor on the discriminant) and
/// the tile rectangle that of 16-pixel tiles, not clamped at the far side (so it only tells
/// whether the Gaussian would be culled). `cov2d` is `[xx, xy, yy]` in pixels² and is used as
/// given (no dilation is added).
pub fn projected_from_cov(
    index: u32,
    mean: [f32; 2],
    cov2d: [f32; 3],
    opacity: f32,
    rgb: [f32; 3],
    depth: f32,
) -> Projected {
    let [a, b, c] = cov2d;
    let det = a * c - b * b;
    let inv = 1.0 / det;
    let conic = [c * inv, -b * inv, a * inv];
    let mid = 0.5 * (a + c);
    let disc = (mid * mid - det).max(0.1).sqrt();
    let radius = (3.0 * (mid + disc).max(mid - disc).sqrt()).ceil().max(0.0) as u32;
    let r = radius as f32;
    let lo = |p: f32| ((p - r) / 16.0).max(0.0) as u32;
    let hi = |p: f32| ((p + r + 15.0) / 16.0).max(0.0) as u32;
    Projected {
        index,
        mean2d: mean,
        cov2d,
        conic,
        depth,
        radius,
        rgb,
        opacity,
        tile_min: [lo(mean[0]), lo(mean[1])],
        tile_max: [hi(mean[0]), hi(mean[1])],
    }
}

/// The covariance `[xx, xy, yy]` of a Gaussian with standard deviations `sigma_u` along the
/// direction at angle `theta` (radians, from +x toward +y) and `sigma_v` across it.
pub fn cov_from_axes(sigma_u: f64, sigma_v: f64, theta: f64) -> [f32; 3] {
    let (s, c) = theta.sin_cos();
    let (lu, lv) = (sigma_u * sigma_u, sigma_v * sigma_v);
    [(lu * c * c + lv * s * s) as f32, ((lu - lv) * c * s) as f32, (lu * s * s + lv * c * c) as f32]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn conic_inverts_the_covariance() {
        let cov = cov_from_axes(5.0, 1.0, 0.3);
        let p = projected_from_cov(7, [10.0, 20.0], cov, 0.5, [1.0; 3], 2.0);
        let [a, b, c] = cov.map(f64::from);
        let [ia, ib, ic] = p.conic.map(f64::from);
        // cov * conic = I.
        assert!((a * ia + b * ib - 1.0).abs() < 1e-5 && (a * ib + b * ic).abs() < 1e-5);
        assert!((b * ib + c * ic - 1.0).abs() < 1e-5);
        assert!((15..=16).contains(&p.radius), "{}", p.radius);
        assert_eq!((p.tile_min, p.tile_max), ([0, 0], [2, 3]));
    }
}
