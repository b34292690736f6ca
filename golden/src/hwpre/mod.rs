//! The Preprocessing Engine's computation in the hardware's arithmetic ([`crate::hwarith`]):
//! generic over [`crate::hwarith::Arith`], evaluated natively by golden and traced into the
//! dataflow graphs that gen emits as the units' Verilog.
//!
//! - [`bake`]: the per-Gaussian parameter format in DRAM (`neo scene bake`);
//! - [`project`]: the projection unit (culling, 2D covariance, conic, radius, tile rectangle,
//!   depth key, the feature entry's geometric fields);
//! - [`color`]: the colour unit (SH of degree 0 to 3);
//! - [`duplicate`]: the duplication unit's tile walk;
//! - [`preprocess_hw`]: both evaluated with [`Relaxed`] (so [`crate::hwarith::Native`]'s
//!   results) for every Gaussian of a baked scene, in parallel: what golden's bit-exact pipeline
//!   uses.

pub mod bake;
pub mod color;
pub mod duplicate;
pub mod project;
pub mod quant;

use rayon::prelude::*;

use crate::camera::Camera;
use crate::formats::{FeatureEntry, FeatureFormat, QuantConic};
use crate::hwarith::{canonical, Arith, Relaxed};
use crate::render::{Projected, ViewParams, FOV_CLAMP};
use crate::sort::DepthKeyCodec;
pub use bake::{Baked, ShPrecision};
use color::{ColorInputs, ColorView, COEFFS};
use project::{CameraIn, GaussianIn, ProjectParams, Projection};

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
fn sh_in(a: &mut Relaxed, baked: &Baked, i: usize) -> [[f32; 3]; COEFFS] {
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

/// `p` with its float outputs' NaNs made canonical (the projection evaluated with [`Relaxed`]
/// then equals [`crate::hwarith::Native`]'s bit for bit).
fn canonical_outputs(mut p: Projection<f32, i32, bool>) -> Projection<f32, i32, bool> {
    // Every field named (no `..`), so that a new float output cannot be missed.
    let Projection {
        visible: _,
        tile_min: _,
        tile_max: _,
        radius: _,
        depth,
        depth_key: _,
        mean2d,
        cov2d,
        conic_f,
        mean: _,
        conic: _,
        conic_exp: _,
        opacity: _,
        axis: _,
        extent_uv: _,
        extent_xy: _,
    } = &mut p;
    *depth = canonical(*depth);
    for v in mean2d.iter_mut().chain(cov2d.iter_mut()).chain(conic_f.iter_mut()) {
        *v = canonical(*v);
    }
    p
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
    // Relaxed, with the float outputs made canonical: Native's results, bit for bit.
    let a = &mut Relaxed;
    let p = canonical_outputs(project::project(a, &gaussian_in(baked, i), cam, params));
    if !p.visible {
        return None;
    }
    let g = ColorInputs { mean: baked.geometry[i].position, sh: sh_in(a, baked, i) };
    let view = ColorView { cam_pos, degree: baked.sh_degree as i32 };
    let rgb = color::color(a, &g, &view).map(canonical);
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
    preprocess_hw_par(baked, cam, fmt, key, tile).flatten().collect()
}

/// [`preprocess_hw`] as a parallel iterator over every Gaussian of `baked` (`None` when culled),
/// for callers that keep only part of each survivor: the survivors are not gathered.
///
/// # Panics
/// As [`preprocess_hw`].
pub fn preprocess_hw_par<'a>(
    baked: &'a Baked,
    cam: &Camera,
    fmt: &FeatureFormat,
    key: &'a DepthKeyCodec,
    tile: u32,
) -> impl IndexedParallelIterator<Item = Option<HwProjected>> + 'a {
    assert_eq!(key.key_bits(), fmt.depth_key_bits, "depth key codec width differs from the feature format's");
    assert!(baked.matches(fmt), "the baked k2 was made for another cutoff or opacity format");
    let (regs, cam_pos) = camera_registers(cam, tile);
    let params = ProjectParams { feature: *fmt, tile };
    (0..baked.len())
        .into_par_iter()
        .with_min_len(4096)
        .map(move |i| preprocess_one(baked, &regs, cam_pos, &params, key, i))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hwarith::Native;
    use proptest::prelude::*;

    /// Every output of a projection, as bits.
    fn bits(p: &Projection<f32, i32, bool>) -> Vec<u32> {
        let floats = [p.depth].into_iter().chain(p.mean2d).chain(p.cov2d).chain(p.conic_f).map(f32::to_bits);
        let ints = [p.visible as i32, p.radius, p.depth_key, p.conic_exp, p.opacity]
            .into_iter()
            .chain(p.tile_min)
            .chain(p.tile_max)
            .chain(p.mean)
            .chain(p.conic)
            .chain(p.axis)
            .chain(p.extent_uv)
            .chain(p.extent_xy)
            .map(|v| v as u32);
        floats.chain(ints).collect()
    }

    /// A float that is ordinary, special (zeros, infinities, NaNs with any payload, subnormals)
    /// or any bit pattern.
    fn value(lo: f32, hi: f32) -> impl Strategy<Value = f32> {
        prop_oneof![
            4 => lo..hi,
            1 => prop::sample::select(vec![0.0, -0.0, f32::INFINITY, f32::NEG_INFINITY, 1e-40, -1e-42, f32::MAX]),
            1 => any::<u32>().prop_map(|b| f32::from_bits(b | 0x7F80_0001)),
            1 => any::<u32>().prop_map(f32::from_bits),
        ]
    }

    fn gaussian() -> impl Strategy<Value = GaussianIn<f32>> {
        (
            prop::array::uniform3(value(-20.0, 20.0)),
            prop::array::uniform6(value(-2.0, 2.0)),
            value(0.0, 1.0),
            value(0.0, 12.0),
        )
            .prop_map(|(position, cov3d, opacity, k2)| GaussianIn { position, cov3d, opacity, k2 })
    }

    fn camera() -> impl Strategy<Value = CameraIn<f32, i32>> {
        (
            prop::array::uniform9(value(-1.0, 1.0)),
            prop::array::uniform3(value(-5.0, 5.0)),
            value(100.0, 2000.0),
        )
            .prop_map(|(r, translation, focal)| CameraIn {
                w2v: [[r[0], r[1], r[2]], [r[3], r[4], r[5]], [r[6], r[7], r[8]]],
                translation,
                focal: [focal, focal],
                lim: [0.83, 0.62],
                principal: [639.5, 359.5],
                grid: [20, 12],
            })
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(2000))]

        /// `preprocess_one`'s evaluation ([`Relaxed`], float outputs made canonical) is
        /// [`Native`]'s bit for bit, NaNs and all.
        #[test]
        fn relaxed_projection_and_colour_are_native_bit_for_bit(
            g in gaussian(),
            cam in camera(),
            sh in prop::array::uniform32(value(-1.0, 1.0)),
            cam_pos in prop::array::uniform3(value(-5.0, 5.0)),
            degree in 0i32..=3,
        ) {
            let params = ProjectParams { feature: FeatureFormat::default(), tile: 64 };
            let want = project::project(&mut Native, &g, &cam, &params);
            let got = canonical_outputs(project::project(&mut Relaxed, &g, &cam, &params));
            prop_assert_eq!(bits(&got), bits(&want));
            let sh: [[f32; 3]; COEFFS] = std::array::from_fn(|k| [0, 1, 2].map(|c| sh[(3 * k + c) % 32]));
            let inputs = ColorInputs { mean: g.position, sh };
            let view = ColorView { cam_pos, degree };
            let want = color::color(&mut Native, &inputs, &view).map(f32::to_bits);
            let got = color::color(&mut Relaxed, &inputs, &view).map(|v| canonical(v).to_bits());
            prop_assert_eq!(got, want);
        }
    }
}
