//! The Preprocessing Engine's computation in the hardware's arithmetic ([`crate::hwarith`]):
//! generic over [`crate::hwarith::Arith`], evaluated natively by golden and traced into the
//! dataflow graphs that gen emits as the units' Verilog.
//!
//! - [`bake`]: the per-Gaussian parameter format in DRAM (`neo scene bake`);
//! - [`project`]: the projection unit (culling, 2D covariance, conic, radius, tile rectangle,
//!   depth key, the feature entry's geometric fields);
//! - [`color`]: the colour unit (SH of degree 0 to 3);
//! - [`duplicate`]: the duplication unit's tile walk;
//! - [`preprocess_hw`]: both evaluated with [`Native`] for every Gaussian of a baked scene, in
//!   parallel: what golden's bit-exact pipeline uses.

pub mod bake;
pub mod color;
pub mod duplicate;
pub mod project;
pub mod quant;

use rayon::prelude::*;

use crate::camera::Camera;
use crate::formats::{FeatureEntry, FeatureFormat, QuantConic};
use crate::hwarith::{Arith, Native};
use crate::render::{Projected, ViewParams, FOV_CLAMP};
use crate::sort::DepthKeyCodec;
pub use bake::{Baked, ShPrecision};
use color::{ColorInputs, ColorView, COEFFS};
use project::{CameraIn, GaussianIn, ProjectParams};

/// One Gaussian that survived the hardware preprocessing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HwProjected {
    /// The unit's float values (mean, covariance, conic, depth, radius, colour, opacity,
    /// tile rectangle), as the float reference's [`Projected`] holds them.
    pub projected: Projected,
    /// The feature entry.
    pub entry: FeatureEntry,
}

/// The per-frame camera registers of `cam` for tiles of `tile` pixels (the host's work).
pub fn camera_registers(cam: &Camera, tile: u32) -> (CameraIn<f32, i32>, [f32; 3]) {
    let v = ViewParams::new(cam, tile);
    let regs = CameraIn {
        w2v: v.w2v,
        translation: v.translation,
        focal: v.focal,
        lim: [FOV_CLAMP * v.tan_half_fov[0], FOV_CLAMP * v.tan_half_fov[1]],
        principal: v.principal,
        grid: [v.grid[0] as i32, v.grid[1] as i32],
    };
    (regs, v.cam_pos)
}

/// The unit inputs of Gaussian `i` of `baked`.
fn gaussian_in(baked: &Baked, i: usize) -> GaussianIn<f32> {
    let g = &baked.geometry[i];
    GaussianIn { position: g.position, cov3d: g.cov3d, opacity: g.opacity, k2: g.k2 }
}

/// The colour unit's SH inputs of Gaussian `i` (coefficients above the degree are zero: the
/// unit does not read them and selects the scene's degree).
fn sh_in(a: &mut Native, baked: &Baked, i: usize) -> [[f32; 3]; COEFFS] {
    let words = baked.sh_of(i);
    let mut sh = [[0.0f32; 3]; COEFFS];
    for (k, &w) in words.iter().enumerate() {
        sh[k / 3][k % 3] = match baked.sh_precision {
            ShPrecision::F32 => f32::from_bits(w),
            ShPrecision::F16 => a.widen_half(w as i32),
        };
    }
    sh
}

/// Preprocesses Gaussian `i` in the hardware's arithmetic; `None` when culled.
pub fn preprocess_one(
    baked: &Baked,
    cam: &CameraIn<f32, i32>,
    cam_pos: [f32; 3],
    params: &ProjectParams,
    key: &DepthKeyCodec,
    i: usize,
) -> Option<HwProjected> {
    let a = &mut Native;
    let p = project::project(a, &gaussian_in(baked, i), cam, params);
    if !p.visible {
        return None;
    }
    let g = ColorInputs { mean: baked.geometry[i].position, sh: sh_in(a, baked, i) };
    let view = ColorView { cam_pos, degree: baked.sh_degree as i32 };
    let rgb = color::color(a, &g, &view);
    let fmt = &params.feature;
    let rgb_q = rgb.map(|v| quant::to_fixed(a, v, &fmt.color));
    // The RTL computes the FP16 key; other codecs (log, linear) are the host model's.
    let depth_key = match key {
        DepthKeyCodec::Fp16 => p.depth_key as u32,
        _ => key.encode(p.depth),
    };
    let entry = FeatureEntry {
        mean: p.mean,
        conic: QuantConic { a: p.conic[0], b: p.conic[1], c: p.conic[2], exp: p.conic_exp as u32 },
        opacity: p.opacity,
        rgb: rgb_q,
        depth_key,
        axis: p.axis,
        extent_uv: p.extent_uv,
        extent_xy: p.extent_xy,
    };
    let projected = Projected {
        index: i as u32,
        mean2d: p.mean2d,
        cov2d: p.cov2d,
        conic: p.conic_f,
        depth: p.depth,
        radius: p.radius as u32,
        rgb,
        opacity: baked.geometry[i].opacity,
        tile_min: p.tile_min.map(|v| v as u32),
        tile_max: p.tile_max.map(|v| v as u32),
    };
    Some(HwProjected { projected, entry })
}

/// Preprocesses every Gaussian of `baked` for `cam` (tiles of `tile` pixels) in the hardware's
/// arithmetic, in parallel; the survivors in Gaussian order.
///
/// # Panics
/// When `key`'s width differs from `fmt.depth_key_bits` or the baked `k2` was made for another
/// cutoff or opacity format (configuration errors).
pub fn preprocess_hw(
    baked: &Baked,
    cam: &Camera,
    fmt: &FeatureFormat,
    key: &DepthKeyCodec,
    tile: u32,
) -> Vec<HwProjected> {
    assert_eq!(key.key_bits(), fmt.depth_key_bits, "depth key codec width differs from the feature format's");
    assert!(baked.matches(fmt), "the baked k2 was made for another cutoff or opacity format");
    let (regs, cam_pos) = camera_registers(cam, tile);
    let params = ProjectParams { feature: *fmt, tile };
    (0..baked.len())
        .into_par_iter()
        .with_min_len(4096)
        .filter_map(|i| preprocess_one(baked, &regs, cam_pos, &params, key, i))
        .collect()
}
