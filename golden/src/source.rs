//! Scene sources: a file path or a `synthetic:NAME?gaussians=N&seed=S` spec, and the robust
//! bounds that default camera framings use.

use crate::error::InputResult;
use crate::scene::{LoadReport, Scene};
use crate::synthetic;
use std::path::Path;

/// Loads a scene: `synthetic:...` specs are generated ([`synthetic::generate`]), anything else
/// is a `.ply` path (standard or compressed) read with [`crate::ply::read_raw`] and activated
/// with [`Scene::from_raw`] (`strict` rejects Gaussians with NaN/infinite values instead of
/// dropping them).
pub fn load_scene(spec: &str, strict: bool) -> InputResult<(Scene, LoadReport)> {
    if synthetic::is_synthetic(spec) {
        let s = synthetic::parse_spec(spec)?;
        return Ok((synthetic::generate(&s), LoadReport::default()));
    }
    let path = Path::new(spec);
    let raw = crate::ply::read_raw(path)?;
    Scene::from_raw(&raw, path, strict)
}

/// Lower and upper percentiles used by [`robust_bounds`].
pub const ROBUST_PERCENTILES: (f64, f64) = (0.02, 0.98);
/// Means farther from the median point than this many times the 80th-percentile distance are
/// outliers for [`robust_bounds`] (a far background shell, stray floaters).
pub const OUTLIER_DISTANCE_FACTOR: f32 = 3.0;

/// Bounds of the bulk of a scene, `(min, max)`, for framing cameras: Gaussians farther from the
/// per-axis median than [`OUTLIER_DISTANCE_FACTOR`] times the 80th-percentile distance are
/// dropped (so a background shell of up to ~20% of the Gaussians does not count), then each axis
/// takes the 2nd and 98th percentiles of the rest. Non-finite means are ignored; a scene with
/// none gives zeros.
pub fn robust_bounds(scene: &Scene) -> ([f32; 3], [f32; 3]) {
    let pts: Vec<[f32; 3]> =
        scene.positions.iter().copied().filter(|p| p.iter().all(|v| v.is_finite())).collect();
    if pts.is_empty() {
        return ([0.0; 3], [0.0; 3]);
    }
    let median: [f32; 3] = std::array::from_fn(|a| percentile(pts.iter().map(|p| p[a]).collect(), 0.5));
    let dist = |p: &[f32; 3]| (0..3).map(|a| (p[a] - median[a]).powi(2)).sum::<f32>().sqrt();
    let cutoff = OUTLIER_DISTANCE_FACTOR * percentile(pts.iter().map(dist).collect(), 0.8);
    let kept: Vec<[f32; 3]> = pts.iter().copied().filter(|p| dist(p) <= cutoff).collect();
    let kept = if kept.is_empty() { pts } else { kept };
    let (lo, hi) = ROBUST_PERCENTILES;
    let axis = |a: usize| -> Vec<f32> { kept.iter().map(|p| p[a]).collect() };
    (std::array::from_fn(|a| percentile(axis(a), lo)), std::array::from_fn(|a| percentile(axis(a), hi)))
}

/// The `q`-quantile (`0..=1`, nearest rank) of non-empty `v`; 0 for an empty vector.
pub fn percentile(mut v: Vec<f32>, q: f64) -> f32 {
    if v.is_empty() {
        return 0.0;
    }
    let k = ((v.len() - 1) as f64 * q.clamp(0.0, 1.0)).round() as usize;
    *v.select_nth_unstable_by(k, f32::total_cmp).1
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percentile_is_nearest_rank() {
        let v: Vec<f32> = (0..101).rev().map(|x| x as f32).collect();
        assert_eq!(percentile(v.clone(), 0.02), 2.0);
        assert_eq!(percentile(v.clone(), 0.5), 50.0);
        assert_eq!(percentile(v, 1.0), 100.0);
        assert_eq!(percentile(vec![], 0.5), 0.0);
    }

    #[test]
    fn far_outliers_do_not_stretch_the_bounds() {
        let mut positions: Vec<[f32; 3]> =
            (0..1000).map(|i| [(i % 10) as f32, -((i / 10) % 10) as f32, (i / 100) as f32]).collect();
        // 10% of the points on a far shell, plus a NaN.
        positions.extend(
            (0..100).map(|i| [1000.0 * ((i as f32) * 0.1).cos(), -500.0, 1000.0 * ((i as f32) * 0.1).sin()]),
        );
        positions.push([f32::NAN, 0.0, 0.0]);
        let scene = Scene { positions, ..Default::default() };
        let (lo, hi) = robust_bounds(&scene);
        assert!(lo.iter().zip(&hi).all(|(l, h)| l <= h));
        assert!(lo[0] >= 0.0 && hi[0] <= 9.0 && hi[0] >= 8.0, "{lo:?} {hi:?}");
        assert!(lo[1] >= -9.0 && hi[1] <= 0.0);
        assert_eq!(scene.bounds().1[0], 1000.0 * 0f32.cos()); // the plain bounds do stretch
    }
}
