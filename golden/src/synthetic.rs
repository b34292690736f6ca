//! Deterministic synthetic scenes (the embedded default).
//!
//! A spec `synthetic:NAME?gaussians=N&seed=S&sh=D` ([`parse_spec`]) names a scene that
//! [`generate`] builds identically on every machine: Gaussian `i` is a pure function of
//! `(seed, i)` (a counter-based hash generator, [`rng::HashRng`]), so neither thread count nor
//! scheduling changes a bit. Generation runs in parallel with rayon.
//!
//! Scenes: `outdoor` ([`outdoor`], metres, y down, ground at y = 0, tens of metres across plus a
//! far background shell) and `blobs` ([`blobs`], a box of random Gaussians for unit tests).
//! Scales, anisotropy and opacities follow a real trained scene (see [`splat`]). The SH degree
//! defaults to [`DEFAULT_SH_DEGREE`]; higher-order coefficients are small and random
//! (standard deviation 0.05, 0.03, 0.02 for degrees 1, 2, 3).

pub mod blobs;
pub mod outdoor;
pub mod rng;
pub mod spec;
pub mod splat;

pub use spec::{
    is_synthetic, parse_spec, SceneKind, SyntheticSpec, DEFAULT_SH_DEGREE, MAX_GAUSSIANS, PREFIX,
};

use crate::scene::{sh_coeffs, Scene};
use rayon::prelude::*;
use rng::HashRng;
use splat::Splat;

/// The default scene: the outdoor scene with 1M Gaussians, seed 1, SH degree 3.
pub const DEFAULT_SCENE: &str = "synthetic:outdoor?gaussians=1M&seed=1";

pub use crate::scene::SH_C0;
/// Standard deviation of the random SH coefficients of degree 1, 2, 3.
const SH_SIGMA: [f64; 3] = [0.05, 0.03, 0.02];
/// Gaussians per parallel work item.
const CHUNK: usize = 4096;
/// Stream ids of the per-Gaussian generators.
const STREAM_SPLAT: u64 = 1;
const STREAM_SH: u64 = 2;

/// Generates the scene a spec names; exactly `spec.gaussians` Gaussians.
pub fn generate(spec: &SyntheticSpec) -> Scene {
    let n = spec.gaussians;
    let outdoor = match spec.kind {
        SceneKind::Outdoor => Some(outdoor::Outdoor::new(spec.seed, n)),
        SceneKind::Blobs => None,
    };
    let sample = |i: usize| {
        let mut rng = HashRng::new(spec.seed, STREAM_SPLAT, i as u64);
        match &outdoor {
            Some(o) => o.sample(&mut rng),
            None => blobs::sample(n, &mut rng),
        }
    };
    let stride = 3 * sh_coeffs(spec.sh_degree);
    let mut scene = Scene {
        positions: vec![[0.0; 3]; n],
        scales: vec![[0.0; 3]; n],
        rotations: vec![[0.0; 4]; n],
        opacities: vec![0.0; n],
        sh_degree: spec.sh_degree,
        sh: vec![0.0; n * stride],
    };
    (
        scene.positions.par_chunks_mut(CHUNK),
        scene.scales.par_chunks_mut(CHUNK),
        scene.rotations.par_chunks_mut(CHUNK),
        scene.opacities.par_chunks_mut(CHUNK),
        scene.sh.par_chunks_mut(CHUNK * stride),
    )
        .into_par_iter()
        .enumerate()
        .for_each(|(c, (pos, scale, rot, opa, sh))| {
            for j in 0..pos.len() {
                let i = c * CHUNK + j;
                let s = sample(i);
                store(&s, &mut pos[j], &mut scale[j], &mut rot[j], &mut opa[j]);
                fill_sh(&s, spec.seed, i, &mut sh[j * stride..(j + 1) * stride]);
            }
        });
    scene
}

/// Converts one splat into the scene's single-precision fields.
fn store(s: &Splat, pos: &mut [f32; 3], scale: &mut [f32; 3], rot: &mut [f32; 4], opacity: &mut f32) {
    *pos = s.position.as_vec3().to_array();
    *scale = s.log_scale.map(|l| l.exp() as f32);
    let q = s.rotation.normalize();
    let q = if q.w < 0.0 { -q } else { q };
    *rot = [q.w as f32, q.x as f32, q.y as f32, q.z as f32];
    *opacity = s.opacity.clamp(0.0, 1.0) as f32;
}

/// Writes the `[coeff][rgb]` SH coefficients of Gaussian `i`: the colour in coefficient 0, small
/// random values above.
fn fill_sh(s: &Splat, seed: u64, i: usize, out: &mut [f32]) {
    for (v, c) in out.iter_mut().zip(s.color) {
        *v = ((c - 0.5) / SH_C0) as f32;
    }
    if out.len() > 3 {
        let mut rng = HashRng::new(seed, STREAM_SH, i as u64);
        for (k, v) in out[3..].iter_mut().enumerate() {
            // Coefficient 1 + k / 3; degree l covers coefficients l^2 .. (l+1)^2 - 1.
            let degree = match 1 + k / 3 {
                1..=3 => 0,
                4..=8 => 1,
                _ => 2,
            };
            *v = (SH_SIGMA[degree] * fast_normal(&mut rng)) as f32;
        }
    }
}

/// An approximately standard normal sample from one 64-bit draw (Irwin-Hall sum of four 16-bit
/// uniforms, rescaled to unit variance; bounded by +-3.46).
fn fast_normal(rng: &mut HashRng) -> f64 {
    let b = rng.next_u64();
    let sum = (b & 0xFFFF) + ((b >> 16) & 0xFFFF) + ((b >> 32) & 0xFFFF) + (b >> 48);
    const SCALE: f64 = 1.732_050_807_568_877_2 / 65535.0; // sqrt(3) / 65535
    (sum as f64 - 2.0 * 65535.0) * SCALE
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fast_normal_has_unit_variance() {
        let mut rng = HashRng::new(4, 4, 4);
        let v: Vec<f64> = (0..100_000).map(|_| fast_normal(&mut rng)).collect();
        let m = v.iter().sum::<f64>() / v.len() as f64;
        let var = v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / v.len() as f64;
        assert!(m.abs() < 0.01 && (var - 1.0).abs() < 0.02, "{m} {var}");
    }

    #[test]
    fn dc_coefficient_encodes_the_colour() {
        let s = Splat {
            position: glam::DVec3::ZERO,
            log_scale: [0.0; 3],
            rotation: glam::DQuat::IDENTITY,
            opacity: 0.5,
            color: [0.0, 0.5, 1.0],
        };
        let mut out = vec![0.0f32; 48];
        fill_sh(&s, 1, 0, &mut out);
        for (v, c) in out.iter().zip(s.color) {
            assert!((*v as f64 * SH_C0 + 0.5 - c).abs() < 1e-6);
        }
        assert!(out[3..].iter().all(|v| v.abs() < 0.2) && out[3..].iter().any(|&v| v != 0.0));
    }
}
