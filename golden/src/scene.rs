//! The in-memory scene: Gaussians in the standard 3DGS parameterisation ([`RawSplats`], as stored
//! in a `.ply`) and after the reference activations ([`Scene`], what renderers consume).

use crate::error::{InputError, InputResult};
use std::path::Path;

/// The degree-0 real SH basis constant `1 / (2 sqrt(pi))`: colour = `SH_C0 * f_dc + 0.5`.
pub const SH_C0: f64 = 0.282_094_791_773_878_14;

/// Number of SH coefficients per colour channel for a degree (1, 4, 9 or 16).
pub const fn sh_coeffs(degree: u8) -> usize {
    (degree as usize + 1) * (degree as usize + 1)
}

/// Gaussians exactly as the standard 3DGS `.ply` stores them: before activations.
///
/// Field names follow the PLY property names. `f_rest` is channel-major per Gaussian, as in the
/// file: `f_rest_{c * (K - 1) + (k - 1)}` for channel `c` and coefficient `k >= 1`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RawSplats {
    /// `x y z`.
    pub position: Vec<[f32; 3]>,
    /// `f_dc_0..2`: the degree-0 SH coefficient per channel.
    pub f_dc: Vec<[f32; 3]>,
    /// SH degree (0..=3); `f_rest` holds `3 * (sh_coeffs(degree) - 1)` values per Gaussian.
    pub sh_degree: u8,
    /// `f_rest_*`, `3 * (K - 1)` per Gaussian, channel-major.
    pub f_rest: Vec<f32>,
    /// `opacity`: the logit. `+inf`/`-inf` are legal and mean fully opaque / transparent.
    pub opacity: Vec<f32>,
    /// `scale_0..2`: natural log of the standard deviations.
    pub log_scale: Vec<[f32; 3]>,
    /// `rot_0..3`: quaternion, w first, not necessarily normalised.
    pub rotation: Vec<[f32; 4]>,
}

impl RawSplats {
    /// Number of Gaussians.
    pub fn len(&self) -> usize {
        self.position.len()
    }

    /// True when there are no Gaussians.
    pub fn is_empty(&self) -> bool {
        self.position.is_empty()
    }

    /// `f_rest` values per Gaussian.
    pub fn rest_per_gaussian(&self) -> usize {
        3 * (sh_coeffs(self.sh_degree) - 1)
    }
}

/// What loading did besides producing the scene.
#[derive(Clone, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct LoadReport {
    /// Gaussians dropped because a property was NaN (or infinite, other than the opacity logit).
    pub dropped_non_finite: usize,
    /// Gaussians whose opacity logit was infinite (legal; they became opacity 0 or 1).
    pub infinite_opacity: usize,
}

/// A scene after the reference activations, structure-of-arrays.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Scene {
    /// World-space means.
    pub positions: Vec<[f32; 3]>,
    /// Standard deviations along the local axes (`exp` of the stored log-scale).
    pub scales: Vec<[f32; 3]>,
    /// Unit quaternions, w first.
    pub rotations: Vec<[f32; 4]>,
    /// Opacity in [0, 1] (`sigmoid` of the stored logit).
    pub opacities: Vec<f32>,
    /// SH degree (0..=3).
    pub sh_degree: u8,
    /// SH coefficients, `sh_coeffs(sh_degree)` per channel, laid out `[gaussian][coeff][rgb]`
    /// as the reference rasterizer reads them.
    pub sh: Vec<f32>,
}

/// Logistic sigmoid with the infinite limits made exact.
pub fn sigmoid(x: f32) -> f32 {
    if x == f32::INFINITY {
        1.0
    } else if x == f32::NEG_INFINITY {
        0.0
    } else {
        1.0 / (1.0 + (-x).exp())
    }
}

/// Inverse of [`sigmoid`]: 0 and 1 map to -inf and +inf.
pub fn logit(p: f32) -> f32 {
    (p / (1.0 - p)).ln()
}

impl Scene {
    /// Number of Gaussians.
    pub fn len(&self) -> usize {
        self.positions.len()
    }

    /// True when there are no Gaussians.
    pub fn is_empty(&self) -> bool {
        self.positions.is_empty()
    }

    /// SH values per Gaussian (`3 * sh_coeffs(sh_degree)`).
    pub fn sh_per_gaussian(&self) -> usize {
        3 * sh_coeffs(self.sh_degree)
    }

    /// The SH coefficients of Gaussian `i`, `[coeff][rgb]` flattened.
    pub fn sh_of(&self, i: usize) -> &[f32] {
        let n = self.sh_per_gaussian();
        &self.sh[i * n..(i + 1) * n]
    }

    /// Axis-aligned bounds of the means: `(min, max)`. Empty scenes give zeros.
    pub fn bounds(&self) -> ([f32; 3], [f32; 3]) {
        if self.is_empty() {
            return ([0.0; 3], [0.0; 3]);
        }
        let mut lo = [f32::INFINITY; 3];
        let mut hi = [f32::NEG_INFINITY; 3];
        for p in &self.positions {
            for a in 0..3 {
                lo[a] = lo[a].min(p[a]);
                hi[a] = hi[a].max(p[a]);
            }
        }
        (lo, hi)
    }

    /// Applies the reference activations to `raw`: sigmoid opacity, exp scale and normalised
    /// w-first quaternion.
    ///
    /// Gaussians with a NaN (or an infinite value anywhere but the opacity logit) are dropped
    /// and counted, or rejected when `strict`. A zero quaternion is always an error, since it
    /// names no rotation. `path` is used in error messages.
    pub fn from_raw(raw: &RawSplats, path: &Path, strict: bool) -> InputResult<(Scene, LoadReport)> {
        let n = raw.len();
        let rest = raw.rest_per_gaussian();
        let k = sh_coeffs(raw.sh_degree);
        let consistent = raw.f_dc.len() == n
            && raw.opacity.len() == n
            && raw.log_scale.len() == n
            && raw.rotation.len() == n
            && raw.f_rest.len() == n * rest;
        if !consistent {
            return Err(InputError::new(path, "property arrays have different lengths"));
        }
        let mut scene = Scene { sh_degree: raw.sh_degree, ..Default::default() };
        scene.positions.reserve(n);
        scene.scales.reserve(n);
        scene.rotations.reserve(n);
        scene.opacities.reserve(n);
        scene.sh.reserve(n * 3 * k);
        let mut report = LoadReport::default();
        for i in 0..n {
            let f_rest = &raw.f_rest[i * rest..(i + 1) * rest];
            let finite = raw.position[i].iter().all(|v| v.is_finite())
                && raw.f_dc[i].iter().all(|v| v.is_finite())
                && raw.log_scale[i].iter().all(|v| v.is_finite())
                && raw.rotation[i].iter().all(|v| v.is_finite())
                && f_rest.iter().all(|v| v.is_finite())
                && !raw.opacity[i].is_nan();
            if !finite {
                if strict {
                    return Err(InputError::new(
                        path,
                        format!("Gaussian {i} has a NaN or infinite property (--strict)"),
                    ));
                }
                report.dropped_non_finite += 1;
                continue;
            }
            let q = raw.rotation[i];
            let norm2: f32 = q.iter().map(|v| v * v).sum();
            if norm2 == 0.0 {
                return Err(InputError::new(
                    path,
                    format!("Gaussian {i} has a zero quaternion (rot_0..3 all 0)"),
                ));
            }
            let inv = 1.0 / norm2.sqrt();
            if raw.opacity[i].is_infinite() {
                report.infinite_opacity += 1;
            }
            scene.positions.push(raw.position[i]);
            scene.scales.push(raw.log_scale[i].map(f32::exp));
            scene.rotations.push(q.map(|v| v * inv));
            scene.opacities.push(sigmoid(raw.opacity[i]));
            scene.sh.extend_from_slice(&raw.f_dc[i]);
            for coeff in 1..k {
                for c in 0..3 {
                    scene.sh.push(f_rest[c * (k - 1) + (coeff - 1)]);
                }
            }
        }
        Ok((scene, report))
    }

    /// Converts back to the stored parameterisation (log scale, opacity logit, channel-major
    /// `f_rest`), for writing a standard `.ply`.
    pub fn to_raw(&self) -> RawSplats {
        let k = sh_coeffs(self.sh_degree);
        let n = self.len();
        let mut raw = RawSplats { sh_degree: self.sh_degree, ..Default::default() };
        raw.position = self.positions.clone();
        raw.log_scale = self.scales.iter().map(|s| s.map(f32::ln)).collect();
        raw.rotation = self.rotations.clone();
        raw.opacity = self.opacities.iter().map(|&o| logit(o)).collect();
        raw.f_dc.reserve(n);
        raw.f_rest.reserve(n * 3 * (k - 1));
        for i in 0..n {
            let sh = self.sh_of(i);
            raw.f_dc.push([sh[0], sh[1], sh[2]]);
            for c in 0..3 {
                for coeff in 1..k {
                    raw.f_rest.push(sh[coeff * 3 + c]);
                }
            }
        }
        raw
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn one(raw_opacity: f32, q: [f32; 4]) -> RawSplats {
        RawSplats {
            position: vec![[1.0, 2.0, 3.0]],
            f_dc: vec![[0.1, 0.2, 0.3]],
            sh_degree: 1,
            f_rest: (0..9).map(|v| v as f32).collect(),
            opacity: vec![raw_opacity],
            log_scale: vec![[0.0, -1.0, 1.0]],
            rotation: vec![q],
        }
    }

    #[test]
    fn activations_and_round_trip() {
        let raw = one(0.5, [2.0, 0.0, 0.0, 0.0]);
        let (s, rep) = Scene::from_raw(&raw, Path::new("t.ply"), false).unwrap();
        assert_eq!(rep, LoadReport::default());
        assert_eq!(s.rotations[0], [1.0, 0.0, 0.0, 0.0]);
        assert!((s.opacities[0] - 0.622_459_3).abs() < 1e-6);
        assert!((s.scales[0][2] - std::f32::consts::E).abs() < 1e-6);
        // [coeff][rgb]: coefficient 1 of channel 1 is f_rest_3.
        assert_eq!(s.sh_of(0)[3 + 1], 3.0);
        let back = s.to_raw();
        assert_eq!(back.f_rest, raw.f_rest);
        assert!((back.opacity[0] - 0.5).abs() < 1e-5);
    }

    #[test]
    fn infinite_logits_are_legal_and_nan_is_dropped() {
        let (s, rep) =
            Scene::from_raw(&one(f32::INFINITY, [1.0, 0.0, 0.0, 0.0]), Path::new("t"), false).unwrap();
        assert_eq!(s.opacities, vec![1.0]);
        assert_eq!(rep.infinite_opacity, 1);
        let (s, _) =
            Scene::from_raw(&one(f32::NEG_INFINITY, [1.0, 0.0, 0.0, 0.0]), Path::new("t"), false).unwrap();
        assert_eq!(s.opacities, vec![0.0]);
        let mut raw = one(0.0, [1.0, 0.0, 0.0, 0.0]);
        raw.position[0][1] = f32::NAN;
        let (s, rep) = Scene::from_raw(&raw, Path::new("t"), false).unwrap();
        assert!(s.is_empty());
        assert_eq!(rep.dropped_non_finite, 1);
        let err = Scene::from_raw(&raw, Path::new("bad.ply"), true).unwrap_err();
        assert!(err.to_string().starts_with("bad.ply: Gaussian 0"), "{err}");
    }

    #[test]
    fn zero_quaternion_is_an_error() {
        let err = Scene::from_raw(&one(0.0, [0.0; 4]), Path::new("z.ply"), false).unwrap_err();
        assert!(err.to_string().contains("z.ply") && err.to_string().contains("zero quaternion"));
    }
}
