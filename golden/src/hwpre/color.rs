//! The colour unit's computation: view-dependent colour from spherical harmonics of degree 0 to
//! 3, generic over [`Arith`], operation for operation the reference's `computeColorFromSH`
//! (as [`crate::render::sh::eval_sh`], whose constants it uses).
//!
//! The SH degree is a per-frame input (a register), not a branch: the unit evaluates every band
//! and selects the result of the scene's degree, so a scene of degree `d` costs nothing for its
//! missing coefficients (they are not read) and the bands above `d` cannot disturb the result
//! (not even when the view direction is NaN, for a Gaussian at the camera centre).

use super::quant::to_fixed;
use crate::formats::fixed::QFormat;
use crate::hwarith::graph::{FNode, Graph, Trace};
use crate::hwarith::{name_each, Arith};
use crate::render::sh::{SH_C0, SH_C1, SH_C2, SH_C3};

/// SH coefficients per colour channel at degree 3.
pub const COEFFS: usize = 16;

/// The colour unit's inputs for one Gaussian.
#[derive(Clone, Copy, Debug)]
pub struct ColorInputs<F> {
    /// World-space mean.
    pub mean: [F; 3],
    /// SH coefficients `[coeff][rgb]`; coefficients above the scene's degree are ignored.
    pub sh: [[F; 3]; COEFFS],
}

/// The per-frame inputs of the colour unit.
#[derive(Clone, Copy, Debug)]
pub struct ColorView<F, I> {
    /// Camera centre in world space.
    pub cam_pos: [F; 3],
    /// The scene's SH degree, 0 to 3.
    pub degree: I,
}

/// `c + s * v` (or `c - s * v`) for each channel, as the reference's `result +/- SH_C * v`.
fn accumulate<A: Arith>(a: &mut A, r: [A::F; 3], s: A::F, v: [A::F; 3], minus: bool) -> [A::F; 3] {
    let mut out = r;
    for ch in 0..3 {
        let term = a.mul(s, v[ch]);
        out[ch] = if minus { a.sub(r[ch], term) } else { a.add(r[ch], term) };
    }
    out
}

/// The unit view direction `(mean - cam) / |mean - cam|` ([`crate::render::sh::view_direction`]).
pub fn view_direction<A: Arith>(a: &mut A, mean: [A::F; 3], cam: [A::F; 3]) -> [A::F; 3] {
    let d = [0, 1, 2].map(|k| a.sub(mean[k], cam[k]));
    let xx = a.mul(d[0], d[0]);
    let yy = a.mul(d[1], d[1]);
    let zz = a.mul(d[2], d[2]);
    let sum = a.add(xx, yy);
    let sum = a.add(sum, zz);
    let len = a.sqrt(sum);
    d.map(|v| a.div(v, len))
}

/// `lit(k) * x`.
fn kmul<A: Arith>(a: &mut A, k: f32, x: A::F) -> A::F {
    let k = a.lit(k);
    a.mul(k, x)
}

/// The degree-1 band added to `r`.
fn band1<A: Arith>(a: &mut A, r: [A::F; 3], sh: &[[A::F; 3]; COEFFS], [x, y, z]: [A::F; 3]) -> [A::F; 3] {
    let sy = kmul(a, SH_C1, y);
    let r = accumulate(a, r, sy, sh[1], true);
    let sz = kmul(a, SH_C1, z);
    let r = accumulate(a, r, sz, sh[2], false);
    let sx = kmul(a, SH_C1, x);
    accumulate(a, r, sx, sh[3], true)
}

/// The squares and products of the direction's components: `xx, yy, zz, xy, yz, xz`.
struct Products<F> {
    xx: F,
    yy: F,
    zz: F,
    xy: F,
    yz: F,
    xz: F,
}

/// The degree-2 band added to `r`.
fn band2<A: Arith>(a: &mut A, r: [A::F; 3], sh: &[[A::F; 3]; COEFFS], p: &Products<A::F>) -> [A::F; 3] {
    let s = kmul(a, SH_C2[0], p.xy);
    let r = accumulate(a, r, s, sh[4], false);
    let s = kmul(a, SH_C2[1], p.yz);
    let r = accumulate(a, r, s, sh[5], false);
    // 2 zz - xx - yy, left to right.
    let t = kmul(a, 2.0, p.zz);
    let t = a.sub(t, p.xx);
    let t = a.sub(t, p.yy);
    let s = kmul(a, SH_C2[2], t);
    let r = accumulate(a, r, s, sh[6], false);
    let s = kmul(a, SH_C2[3], p.xz);
    let r = accumulate(a, r, s, sh[7], false);
    let t = a.sub(p.xx, p.yy);
    let s = kmul(a, SH_C2[4], t);
    accumulate(a, r, s, sh[8], false)
}

/// `k * u * w`, evaluated `(k * u) * w` as the reference's `SH_C3[i] * y * (...)`.
fn kmul2<A: Arith>(a: &mut A, k: f32, u: A::F, w: A::F) -> A::F {
    let ku = kmul(a, k, u);
    a.mul(ku, w)
}

/// The degree-3 band added to `r`.
fn band3<A: Arith>(
    a: &mut A,
    r: [A::F; 3],
    sh: &[[A::F; 3]; COEFFS],
    [x, y, z]: [A::F; 3],
    p: &Products<A::F>,
) -> [A::F; 3] {
    // 3 xx - yy
    let t = kmul(a, 3.0, p.xx);
    let t = a.sub(t, p.yy);
    let s = kmul2(a, SH_C3[0], y, t);
    let r = accumulate(a, r, s, sh[9], false);
    let s = kmul2(a, SH_C3[1], p.xy, z);
    let r = accumulate(a, r, s, sh[10], false);
    // 4 zz - xx - yy
    let t4 = kmul(a, 4.0, p.zz);
    let t4 = a.sub(t4, p.xx);
    let t4 = a.sub(t4, p.yy);
    let s = kmul2(a, SH_C3[2], y, t4);
    let r = accumulate(a, r, s, sh[11], false);
    // 2 zz - 3 xx - 3 yy
    let t = kmul(a, 2.0, p.zz);
    let u = kmul(a, 3.0, p.xx);
    let t = a.sub(t, u);
    let u = kmul(a, 3.0, p.yy);
    let t = a.sub(t, u);
    let s = kmul2(a, SH_C3[3], z, t);
    let r = accumulate(a, r, s, sh[12], false);
    let s = kmul2(a, SH_C3[4], x, t4);
    let r = accumulate(a, r, s, sh[13], false);
    let t = a.sub(p.xx, p.yy);
    let s = kmul2(a, SH_C3[5], z, t);
    let r = accumulate(a, r, s, sh[14], false);
    // xx - 3 yy
    let u = kmul(a, 3.0, p.yy);
    let t = a.sub(p.xx, u);
    let s = kmul2(a, SH_C3[6], x, t);
    accumulate(a, r, s, sh[15], false)
}

/// The colour of one Gaussian: SH of the view's degree, `+ 0.5`, clamped at 0 from below
/// (bit for bit [`crate::render::sh::eval_sh`] for degrees 0 to 3).
pub fn color<A: Arith>(a: &mut A, g: &ColorInputs<A::F>, view: &ColorView<A::F, A::I>) -> [A::F; 3] {
    let c0 = a.lit(SH_C0);
    let r0 = g.sh[0].map(|v| a.mul(c0, v));
    let r0 = name_each(a, r0, ["band0_red", "band0_green", "band0_blue"]);
    let dir = view_direction(a, g.mean, view.cam_pos);
    let dir = name_each(a, dir, ["dir_x", "dir_y", "dir_z"]);
    let r1 = band1(a, r0, &g.sh, dir);
    let r1 = name_each(a, r1, ["band1_red", "band1_green", "band1_blue"]);
    let [x, y, z] = dir;
    let p = Products {
        xx: product(a, x, x, "dir_xx"),
        yy: product(a, y, y, "dir_yy"),
        zz: product(a, z, z, "dir_zz"),
        xy: product(a, x, y, "dir_xy"),
        yz: product(a, y, z, "dir_yz"),
        xz: product(a, x, z, "dir_xz"),
    };
    let r2 = band2(a, r1, &g.sh, &p);
    let r2 = name_each(a, r2, ["band2_red", "band2_green", "band2_blue"]);
    let r3 = band3(a, r2, &g.sh, dir, &p);
    let r3 = name_each(a, r3, ["band3_red", "band3_green", "band3_blue"]);
    // Select the scene's degree.
    let (one, two, three) = (a.ilit(1), a.ilit(2), a.ilit(3));
    let ge1 = a.ilt(view.degree, one);
    let ge1 = a.not(ge1);
    let ge2 = a.ilt(view.degree, two);
    let ge2 = a.not(ge2);
    let ge3 = a.ilt(view.degree, three);
    let ge3 = a.not(ge3);
    let (half, zero) = (a.lit(0.5), a.lit(0.0));
    let mut out = r0;
    for ch in 0..3 {
        let v = a.select(ge1, r1[ch], r0[ch]);
        let v = a.select(ge2, r2[ch], v);
        let v = a.select(ge3, r3[ch], v);
        let v = a.add(v, half);
        out[ch] = a.max(v, zero);
    }
    name_each(a, out, ["rgb_red", "rgb_green", "rgb_blue"])
}

/// `u w`, named `name` for the hardware's nets.
fn product<A: Arith>(a: &mut A, u: A::F, w: A::F, name: &'static str) -> A::F {
    let p = a.mul(u, w);
    a.name_f(p, name)
}

/// Names of the colour channels, in order (port names).
pub const CHANNELS: [&str; 3] = ["red", "green", "blue"];

/// The colour unit as a dataflow graph: per-Gaussian inputs `mean_{x,y,z}` and
/// `sh{k}_{red,green,blue}`, per-frame inputs `cam_{x,y,z}` and `degree`; outputs the
/// colour channels quantised to `format` (`red`, `green`, `blue`, raw fixed point).
pub fn color_graph(format: &QFormat) -> Graph {
    let mut t = Trace::new();
    let axes = ["x", "y", "z"];
    let mean = axes.map(|x| t.input_f(&format!("mean_{x}"), false));
    let sh: [[FNode; 3]; COEFFS] =
        std::array::from_fn(|k| CHANNELS.map(|c| t.input_f(&format!("sh{k}_{c}"), false)));
    let cam_pos = axes.map(|x| t.input_f(&format!("cam_{x}"), true));
    let degree = t.input_i("degree", true);
    let rgb = color(&mut t, &ColorInputs { mean, sh }, &ColorView { cam_pos, degree });
    for (c, v) in CHANNELS.iter().zip(rgb) {
        let q = to_fixed(&mut t, v, format);
        t.output_i(c, q);
    }
    t.finish()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hwarith::Native;
    use crate::render::sh::{eval_sh, view_direction as float_direction};
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn matches_the_float_evaluation_bit_for_bit(
            mean in prop::array::uniform3(-50.0f32..50.0),
            cam in prop::array::uniform3(-5.0f32..5.0),
            coeffs in prop::collection::vec(-2.0f32..2.0, 48),
            degree in 0u8..=3,
        ) {
            let mut sh = [[0.0f32; 3]; COEFFS];
            for (k, c) in sh.iter_mut().enumerate() {
                *c = [coeffs[3 * k], coeffs[3 * k + 1], coeffs[3 * k + 2]];
            }
            let g = ColorInputs { mean, sh };
            let view = ColorView { cam_pos: cam, degree: degree as i32 };
            let got = color(&mut Native, &g, &view);
            let want = eval_sh(degree, &coeffs, float_direction(mean, cam));
            prop_assert_eq!(got.map(f32::to_bits), want.map(f32::to_bits));
        }
    }

    #[test]
    fn the_graph_computes_the_quantised_colour() {
        let fmt = crate::formats::feature::FeatureFormat::default().color;
        let g = color_graph(&fmt);
        assert_eq!(g.inputs.len(), 3 + 48 + 4);
        let mut rng = crate::synthetic::rng::HashRng::new(5, 0, 0);
        for _ in 0..200 {
            let vals: Vec<f32> = (0..51).map(|_| rng.range(-2.0, 2.0) as f32).collect();
            let cam = [0.1, -0.2, 0.3];
            let degree = rng.below(4) as i32;
            let mut inputs: Vec<u32> = vals.iter().map(|v| v.to_bits()).collect();
            inputs.extend(cam.map(f32::to_bits));
            inputs.push(degree as u32);
            let want = eval_sh(degree as u8, &vals[3..], float_direction([vals[0], vals[1], vals[2]], cam));
            let want: Vec<u32> = want.iter().map(|&v| fmt.quantize(v as f64) as u32).collect();
            assert_eq!(g.eval(&inputs), want);
        }
    }

    #[test]
    fn a_gaussian_at_the_camera_keeps_its_degree_zero_colour() {
        let mut sh = [[f32::NAN; 3]; COEFFS];
        sh[0] = [1.0, 0.0, -1.0];
        let g = ColorInputs { mean: [1.0, 2.0, 3.0], sh };
        let view = ColorView { cam_pos: [1.0, 2.0, 3.0], degree: 0 };
        let got = color(&mut Native, &g, &view);
        assert_eq!(got, eval_sh(0, &[1.0, 0.0, -1.0], [f32::NAN; 3]));
    }
}
