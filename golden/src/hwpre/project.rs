//! The projection unit's computation, generic over [`Arith`]: view transform, near-plane and
//! frustum culling, the EWA 2D covariance with the +0.3 dilation, det, conic, radius, tile
//! rectangle, depth key, and the feature entry's geometric fields (mean, conic, opacity, ITU
//! axis and extents) in the hardware's arithmetic.
//!
//! # Operation order
//! Up to the conic, radius and tile rectangle, the operations are those of
//! [`crate::render::project_one`] in the same order (IEEE binary32, RNE), so the mean, 2D
//! covariance, conic, depth and radius are the float reference's, bit for bit except the sign
//! of zero products the reference's GLM matrix products add to its Jacobian's zero entries
//! (which no quantised field sees). The culling decision is the reference's.
//!
//! # Quantisation without transcendentals
//! - mean, opacity: [`to_fixed`] (exactly [`crate::formats::QFormat::quantize`]);
//! - conic: block floating point with the exponent from [`Arith::exp_field`] instead of
//!   `log2` (exactly [`crate::formats::ConicFormat::quantize`]);
//! - ITU axis: the major-axis eigenvector from the half-angle identities (no atan2/cos/sin):
//!   with `a = sxx - syy`, `b = 2 sxy`, `r = sqrt(a^2 + b^2)`, `w = r + |a|`,
//!   `n = sqrt(2 r w)`, the unit vector is `(w / n, b / n)` when `a >= 0`, else `(|b| / n,
//!   sign(b) w / n)`; isotropic or non-finite covariances take `(1, 0)`. Any direction keeps
//!   the ITU conservative: the axis only sets how tight the octagon is.
//! - extents: `sqrt(k2 var) + |dm . n|` along `n` = x, y, U, V, where `var = n^T cov n`
//!   plus a bound on its f32 rounding error (`2^-20 (C^2 sxx + 2 |C S sxy| + S^2 syy)`, which
//!   covers the cancellation along the minor axis of a needle), `|dm . n|` bounded by
//!   `|dm_x| |n_x| + |dm_y| |n_y|`, the total times `1 + 2^-20` (the f32 roundings of the sum,
//!   square root and products are below `5 2^-24` relative), then rounded up; NaN or overflow
//!   gives the unbounded extent. So every extent bounds the exact ellipse of the unit's 2D
//!   covariance around its float mean, seen from the quantised mean.

use crate::formats::{ConicFormat, FeatureFormat};
use crate::hwarith::{name_each, Arith, Round};
use crate::render::{COV2D_DILATION, NEAR_CULL};

use super::quant::to_fixed;

/// Relative margin of the ITU extents and of the variance error bound: `2^-20`.
pub const EXTENT_MARGIN: f32 = 1.0 / 1_048_576.0;

/// One Gaussian's baked geometry as the unit reads it.
#[derive(Clone, Copy, Debug)]
pub struct GaussianIn<F> {
    /// World-space mean.
    pub position: [F; 3],
    /// 3D covariance `[xx, xy, xz, yy, yz, zz]`.
    pub cov3d: [F; 6],
    /// Opacity.
    pub opacity: F,
    /// Cutoff radius squared (sigmas).
    pub k2: F,
}

/// The per-frame camera registers (computed by the host, as [`crate::render::ViewParams`]).
#[derive(Clone, Copy, Debug)]
pub struct CameraIn<F, I> {
    /// World-to-view rotation, row-major.
    pub w2v: [[F; 3]; 3],
    /// World-to-view translation.
    pub translation: [F; 3],
    /// Focal lengths (pixels).
    pub focal: [F; 2],
    /// The Jacobian's clamp `FOV_CLAMP tan(fov / 2)` in x and y.
    pub lim: [F; 2],
    /// Principal point (pixels).
    pub principal: [F; 2],
    /// Tile grid `[x, y]`.
    pub grid: [I; 2],
}

/// The unit's compile-time parameters: formats and tile size.
#[derive(Clone, Copy, Debug)]
pub struct ProjectParams {
    /// Feature-table widths.
    pub feature: FeatureFormat,
    /// Tile side (a power of two in the hardware: `/ B` is then a multiply).
    pub tile: u32,
}

/// What the projection unit produces for one Gaussian.
#[derive(Clone, Copy, Debug)]
pub struct Projection<F, I, B> {
    /// Survives culling (in front of the near plane, invertible finite 2D covariance, positive
    /// radius, finite mean and conic, at least one tile).
    pub visible: B,
    /// First tile `[x, y]` (inclusive).
    pub tile_min: [I; 2],
    /// One past the last tile `[x, y]`.
    pub tile_max: [I; 2],
    /// Screen radius (pixels).
    pub radius: I,
    /// View-space depth.
    pub depth: F,
    /// The FP16 depth key (`f16_bits(depth)`).
    pub depth_key: I,
    /// Mean in pixels (float).
    pub mean2d: [F; 2],
    /// 2D covariance `[xx, xy, yy]` with the dilation.
    pub cov2d: [F; 3],
    /// Conic (float).
    pub conic_f: [F; 3],
    /// Mean, raw.
    pub mean: [I; 2],
    /// Conic mantissas `a, b, c`.
    pub conic: [I; 3],
    /// Conic exponent field.
    pub conic_exp: I,
    /// Opacity, raw.
    pub opacity: I,
    /// ITU axis `[C, S]`, raw.
    pub axis: [I; 2],
    /// Extents along U and V (over `2^axis.frac`), raw.
    pub extent_uv: [I; 2],
    /// Extents along x and y, raw.
    pub extent_xy: [I; 2],
}

/// `a0 b0 + a1 b1 + a2 b2`, summed left to right.
fn dot3<A: Arith>(a: &mut A, x: [A::F; 3], y: [A::F; 3]) -> A::F {
    let p0 = a.mul(x[0], y[0]);
    let p1 = a.mul(x[1], y[1]);
    let p2 = a.mul(x[2], y[2]);
    let s = a.add(p0, p1);
    a.add(s, p2)
}

/// `2^s` as a product of two exact powers of two (`s` in `[-126, 227]`).
fn scale_pow2<A: Arith>(a: &mut A, v: A::F, s: A::I) -> A::F {
    let hundred = a.ilit(100);
    let bias = a.ilit(127);
    let s1 = a.imin(s, hundred);
    let s2 = a.isub(s, s1);
    let e1 = a.iadd(s1, bias);
    let e2 = a.iadd(s2, bias);
    let p1 = a.pow2_field(e1);
    let p2 = a.pow2_field(e2);
    let v = a.mul(v, p1);
    a.mul(v, p2)
}

/// The block floating-point conic of `[ca, cb, cc]`: mantissas and exponent field, exactly
/// [`ConicFormat::quantize`].
pub fn conic_bfp<A: Arith>(a: &mut A, conic: [A::F; 3], f: &ConicFormat) -> ([A::I; 3], A::I) {
    let zero = a.lit(0.0);
    let nan_a = a.is_nan(conic[0]);
    let nan_b = a.is_nan(conic[1]);
    let nan_c = a.is_nan(conic[2]);
    let any_nan = a.or(nan_a, nan_b);
    let any_nan = a.or(any_nan, nan_c);
    let ca = a.max(conic[0], zero);
    let cc = a.max(conic[2], zero);
    let ab = a.abs(conic[1]);
    let mx = a.max(ca, ab);
    let mx = a.max(mx, cc);
    let mx = a.name_f(mx, "conic_max");
    // The exponent of mx, subnormals normalised by 2^64 first.
    let tiny = a.lit(2f32.powi(-62));
    let small = a.lt(mx, tiny);
    let big = a.lit(2f32.powi(64));
    let mx_up = a.mul(mx, big);
    let e_up = a.exp_field(mx_up);
    let sixty4 = a.ilit(64);
    let e_up = a.isub(e_up, sixty4);
    let e_n = a.exp_field(mx);
    let e = a.iselect(small, e_up, e_n);
    // mx 2^s0 in [2^(M-1), 2^M), clamped to the format's range.
    let m = f.mantissa_bits as i32;
    let k = a.ilit(m + 126);
    let s0 = a.isub(k, e);
    let (s_min, s_max) = (f.scale(0), f.scale(f.max_exp()));
    let lo = a.ilit(s_min);
    let hi = a.ilit(s_max);
    let s0 = a.imax(s0, lo);
    let s0 = a.imin(s0, hi);
    let max_m = a.ilit(f.max_mantissa() as i32);
    let scaled = scale_pow2(a, mx, s0);
    let r = a.to_int(scaled, Round::HalfUp);
    let over = a.ilt(max_m, r);
    let above_min = a.ilt(lo, s0);
    let dec = a.and(over, above_min);
    let one = a.ilit(1);
    let s0m = a.isub(s0, one);
    let s = a.iselect(dec, s0m, s0);
    let s = a.name_i(s, "conic_shift");
    let izero = a.ilit(0);
    let neg_max = a.ilit(-(f.max_mantissa() as i32));
    let q = |a: &mut A, v: A::F, lo: A::I| {
        let x = scale_pow2(a, v, s);
        let r = a.to_int(x, Round::HalfUp);
        let r = a.imax(r, lo);
        let r = a.imin(r, max_m);
        a.iselect(any_nan, izero, r)
    };
    let qa = q(a, ca, izero);
    let qb = q(a, conic[1], neg_max);
    let qc = q(a, cc, izero);
    let exp = a.isub(s, lo);
    // s0 is clamped to [lo, hi] and decremented only above lo (`above_min`).
    a.assume_i(
        exp,
        0,
        s_max - s_min,
        "the conic exponent s - s_min: s in [s_min, s_max], decremented only above s_min",
    );
    let max_exp = a.ilit(f.max_exp() as i32);
    let exp = a.iselect(any_nan, max_exp, exp);
    ([qa, qb, qc], exp)
}

/// The unit's ITU major-axis direction `(C, S)` (unit length up to rounding) of the 2D
/// covariance (see the module doc).
pub fn major_axis<A: Arith>(a: &mut A, cov: [A::F; 3]) -> [A::F; 2] {
    let [sxx, sxy, syy] = cov;
    let d = a.sub(sxx, syy);
    let two = a.lit(2.0);
    let b = a.mul(two, sxy);
    let dd = a.mul(d, d);
    let bb = a.mul(b, b);
    let rr = a.add(dd, bb);
    let r = a.sqrt(rr);
    let r = a.name_f(r, "axis_r");
    let ad = a.abs(d);
    let w = a.add(r, ad);
    let rw = a.mul(r, w);
    let rw2 = a.mul(two, rw);
    let n = a.sqrt(rw2);
    let n = a.name_f(n, "axis_n");
    let big = a.div(w, n);
    let ab = a.abs(b);
    let small = a.div(ab, n);
    let sb = a.div(b, n);
    let zero = a.lit(0.0);
    let b_neg = a.lt(b, zero);
    let nbig = a.neg(big);
    let sbig = a.select(b_neg, nbig, big);
    let d_neg = a.lt(d, zero);
    let c = a.select(d_neg, small, big);
    let s = a.select(d_neg, sbig, sb);
    // Isotropic (n = 0) or non-finite: (1, 0).
    let ok_c = a.is_finite(c);
    let ok_s = a.is_finite(s);
    let ok = a.and(ok_c, ok_s);
    let pos = a.lt(zero, n);
    let ok = a.and(ok, pos);
    let one = a.lit(1.0);
    let (c, s) = (a.select(ok, c, one), a.select(ok, s, zero));
    // A unit vector up to rounding: big = w / n = sqrt(w / 2r) with r <= w <= 2r, in
    // [sqrt(1/2), 1]; small = |b| / n = sqrt((r - |d|) / 2r) (b^2 = (r - |d|) w), in
    // [0, sqrt(1/2)]; c is one of them or 1, and |s| the other or 0. The bound leaves 2^-16
    // for rounding. Asserted, not proved for every input (subnormal products round coarsely):
    // every evaluation of the traced graph checks it (`Graph::eval`), and the known-bits
    // soundness test runs it on random, edge and adversarial inputs.
    a.assume_f(c, 0.0, AXIS_BOUND, "the major axis' C: big or small (in [0, 1] up to rounding), or 1");
    a.assume_f(
        s,
        -AXIS_BOUND,
        AXIS_BOUND,
        "the major axis' S: +-big, b / n (in [-1, 1] up to rounding) or 0",
    );
    [c, s]
}

/// The bound [`major_axis`] asserts of `|C|` and `|S|`: 1, with 2^-16 for rounding.
const AXIS_BOUND: f32 = 1.0 + 1.0 / 65536.0;

/// Conservative support (pixels) of the ellipse `d^T cov^-1 d <= k2` around the float mean
/// along `n` (not necessarily unit), seen from the quantised mean (`dm = mean - mean_q`).
fn support<A: Arith>(
    a: &mut A,
    cov: [A::F; 3],
    k2: A::F,
    dm: [A::F; 2],
    n: [A::F; 2],
    axis_frac: u8,
) -> A::F {
    let [sxx, sxy, syy] = cov;
    let xx = a.mul(n[0], n[0]);
    let yy = a.mul(n[1], n[1]);
    let xy = a.mul(n[0], n[1]);
    let two = a.lit(2.0);
    let xy2 = a.mul(two, xy);
    // n is (1, 0), (0, 1) or the quantised major axis (C, S) or (-S, C) of major_axis (a unit
    // vector up to rounding) times 2^frac: integers of magnitude at most 2^frac, not both
    // nonzero and 1 in magnitude (one is at least about 0.7 2^frac), nor both 2^frac.
    let full = 2f32.powi(2 * i32::from(axis_frac));
    let why = "x y of a support direction: 0, or in [2, 2^2frac - 1] (asserted like major_axis' bound)";
    a.assume_zero_or(xy, 2.0, full - 1.0, why);
    a.assume_zero_or(xy2, 4.0, 2.0 * (full - 1.0), "2 x y of a support direction");
    let t0 = a.mul(xx, sxx);
    let t1 = a.mul(xy2, sxy);
    let t2 = a.mul(yy, syy);
    let var = a.add(t0, t1);
    let var = a.add(var, t2);
    // Rounding-error bound of var: 2^-20 (|t0| + |t1| + |t2|).
    let a0 = a.abs(t0);
    let a1 = a.abs(t1);
    let a2 = a.abs(t2);
    let mag = a.add(a0, a1);
    let mag = a.add(mag, a2);
    let eps = a.lit(EXTENT_MARGIN);
    let err = a.mul(mag, eps);
    let var = a.add(var, err);
    let zero = a.lit(0.0);
    let var = a.max(var, zero);
    let var = a.name_f(var, "support_var");
    let kv = a.mul(k2, var);
    let sd = a.sqrt(kv);
    let sd = a.name_f(sd, "support_sd");
    let nx = a.abs(n[0]);
    let ny = a.abs(n[1]);
    let dx = a.abs(dm[0]);
    let dy = a.abs(dm[1]);
    let ex = a.mul(dx, nx);
    let ey = a.mul(dy, ny);
    let e = a.add(ex, ey);
    let s = a.add(sd, e);
    let one_eps = a.lit(1.0 + EXTENT_MARGIN);
    a.mul(s, one_eps)
}

/// `v` (pixels) rounded up to the extent format, saturating; NaN gives the unbounded value.
fn extent_ceil<A: Arith>(a: &mut A, v: A::F, f: &FeatureFormat) -> A::I {
    let scale = a.lit((f.extent.frac as f32).exp2());
    let x = a.mul(v, scale);
    let r = a.to_int(x, Round::Ceil);
    let lo = a.ilit(0);
    let hi = a.ilit(f.unbounded_extent());
    let r = a.imax(r, lo);
    let r = a.imin(r, hi);
    let nan = a.is_nan(x);
    a.iselect(nan, hi, r)
}

/// The reference's `getRect` along one axis: `[lo, hi)` tiles, clamped to `[0, grid]`.
/// `/ B` is a multiply by the exact `1 / B` for a power-of-two tile (the same IEEE result),
/// a division otherwise.
fn rect_axis<A: Arith>(a: &mut A, p: A::F, r: A::F, grid: A::I, tile: u32) -> (A::I, A::I) {
    let b = a.lit(tile as f32);
    let inv_b = a.lit(1.0 / tile as f32);
    let per_tile = |a: &mut A, v: A::F| if tile.is_power_of_two() { a.mul(v, inv_b) } else { a.div(v, b) };
    let one = a.lit(1.0);
    let zero = a.ilit(0);
    let pr = a.sub(p, r);
    let lo = per_tile(a, pr);
    let lo = a.to_int(lo, Round::Trunc);
    let lo = a.imax(lo, zero);
    let lo = a.imin(lo, grid);
    let hi = a.add(p, r);
    let hi = a.add(hi, b);
    let hi = a.sub(hi, one);
    let hi = per_tile(a, hi);
    let hi = a.to_int(hi, Round::Trunc);
    let hi = a.imax(hi, zero);
    let hi = a.imin(hi, grid);
    (lo, hi)
}

/// The projection unit for one Gaussian (see the module doc).
pub fn project<A: Arith>(
    a: &mut A,
    g: &GaussianIn<A::F>,
    cam: &CameraIn<A::F, A::I>,
    params: &ProjectParams,
) -> Projection<A::F, A::I, A::B> {
    let fmt = &params.feature;
    // View transform: R p + t.
    let t = [0, 1, 2].map(|r| {
        let d = dot3(a, cam.w2v[r], g.position);
        let v = a.add(d, cam.translation[r]);
        a.name_f(v, ["view_x", "view_y", "view_z"][r])
    });
    let near = a.lit(NEAR_CULL);
    let in_front = a.lt(near, t[2]);
    let in_front = a.name_b(in_front, "in_front");
    let tz = t[2];

    // EWA Jacobian with the FOV clamp.
    let [fx, fy] = cam.focal;
    let clamp = |a: &mut A, v: A::F, lim: A::F| {
        let q = a.div(v, tz);
        let nl = a.neg(lim);
        let q = a.max(q, nl);
        let q = a.min(q, lim);
        a.mul(q, tz)
    };
    let tx = clamp(a, t[0], cam.lim[0]);
    let tx = a.name_f(tx, "view_x_clamped");
    let ty = clamp(a, t[1], cam.lim[1]);
    let ty = a.name_f(ty, "view_y_clamped");
    let tz2 = a.mul(tz, tz);
    let tz2 = a.name_f(tz2, "view_z_sq");
    let j00 = a.div(fx, tz);
    let j00 = a.name_f(j00, "jac_00");
    let j11 = a.div(fy, tz);
    let j11 = a.name_f(j11, "jac_11");
    let fxtx = a.mul(fx, tx);
    let j02 = a.div(fxtx, tz2);
    let j02 = a.neg(j02);
    let j02 = a.name_f(j02, "jac_02");
    let fyty = a.mul(fy, ty);
    let j12 = a.div(fyty, tz2);
    let j12 = a.neg(j12);
    let j12 = a.name_f(j12, "jac_12");
    // T = W J (GLM, W's columns the rows of w2v): T[c][r] = sum_k w2v[k][r] J[c][k]; J's zero
    // entries dropped. Only T's columns 0 and 1 reach the 2x2 result.
    let w = &cam.w2v;
    let tcol0 = [0, 1, 2].map(|r| {
        let p0 = a.mul(w[0][r], j00);
        let p2 = a.mul(w[2][r], j02);
        let v = a.add(p0, p2);
        a.name_f(v, ["t_00", "t_01", "t_02"][r])
    });
    let tcol1 = [0, 1, 2].map(|r| {
        let p1 = a.mul(w[1][r], j11);
        let p2 = a.mul(w[2][r], j12);
        let v = a.add(p1, p2);
        a.name_f(v, ["t_10", "t_11", "t_12"][r])
    });
    let c = &g.cov3d;
    let vrk = [[c[0], c[1], c[2]], [c[1], c[3], c[4]], [c[2], c[4], c[5]]];
    // M = T^T Vrk^T: M[k][r] = sum_j T[r][j] Vrk[k][j] (r = 0, 1).
    let tcols = [tcol0, tcol1];
    let mut m = [[tz; 2]; 3];
    for (k, row) in m.iter_mut().enumerate() {
        for (r, v) in row.iter_mut().enumerate() {
            let name = [["m_00", "m_01"], ["m_10", "m_11"], ["m_20", "m_21"]][k][r];
            *v = dot3(a, tcols[r], vrk[k]);
            *v = a.name_f(*v, name);
        }
    }
    // cov[c][r] = sum_k M[k][r] T[c][k].
    let cov_cr = |a: &mut A, c: usize, r: usize| dot3(a, [m[0][r], m[1][r], m[2][r]], tcols[c]);
    let c00 = cov_cr(a, 0, 0);
    let c01 = cov_cr(a, 0, 1);
    let c11 = cov_cr(a, 1, 1);
    let dil = a.lit(COV2D_DILATION);
    let cov = [a.add(c00, dil), c01, a.add(c11, dil)];
    let cov = name_each(a, cov, ["cov2d_xx", "cov2d_xy", "cov2d_yy"]);

    // det, conic, radius.
    let p02 = a.mul(cov[0], cov[2]);
    let p11 = a.mul(cov[1], cov[1]);
    let det = a.sub(p02, p11);
    let det = a.name_f(det, "det");
    let fzero = a.lit(0.0);
    let det_zero = a.eq(det, fzero);
    let one = a.lit(1.0);
    let det_inv = a.div(one, det);
    let det_inv = a.name_f(det_inv, "det_inv");
    let nb = a.neg(cov[1]);
    let conic_f = [a.mul(cov[2], det_inv), a.mul(nb, det_inv), a.mul(cov[0], det_inv)];
    let conic_f = name_each(a, conic_f, ["conic_a_f", "conic_b_f", "conic_c_f"]);
    let half = a.lit(0.5);
    let sum = a.add(cov[0], cov[2]);
    let mid = a.mul(half, sum);
    let mid = a.name_f(mid, "eig_mid");
    let mm = a.mul(mid, mid);
    let disc = a.sub(mm, det);
    let tenth = a.lit(0.1);
    let disc = a.max(disc, tenth);
    let disc = a.sqrt(disc);
    let disc = a.name_f(disc, "eig_disc");
    let l1 = a.add(mid, disc);
    let l2 = a.sub(mid, disc);
    let lmax = a.max(l1, l2);
    let lmax = a.name_f(lmax, "eig_max");
    let sl = a.sqrt(lmax);
    let three = a.lit(3.0);
    let r3 = a.mul(three, sl);
    let radius = a.to_int(r3, Round::Ceil);
    let radius = a.name_i(radius, "radius");

    // Mean in pixels.
    let mean2d = [0, 1].map(|k| {
        let ft = a.mul(cam.focal[k], t[k]);
        let q = a.div(ft, tz);
        let v = a.add(q, cam.principal[k]);
        a.name_f(v, ["mean2d_x", "mean2d_y"][k])
    });
    let izero = a.ilit(0);
    let r_pos = a.ilt(izero, radius);
    let finite = [mean2d[0], mean2d[1], conic_f[0], conic_f[1], conic_f[2]].map(|v| a.is_finite(v));
    let mut ok = a.and(in_front, r_pos);
    let not_det_zero = a.not(det_zero);
    ok = a.and(ok, not_det_zero);
    for f in finite {
        ok = a.and(ok, f);
    }
    let ok = a.name_b(ok, "projected");
    let rf = a.int_to_float(radius);
    let (x0, x1) = rect_axis(a, mean2d[0], rf, cam.grid[0], params.tile);
    let (y0, y1) = rect_axis(a, mean2d[1], rf, cam.grid[1], params.tile);
    let (x0, x1) = (a.name_i(x0, "tile_min_x"), a.name_i(x1, "tile_max_x"));
    let (y0, y1) = (a.name_i(y0, "tile_min_y"), a.name_i(y1, "tile_max_y"));
    let ex = a.ieq(x0, x1);
    let ey = a.ieq(y0, y1);
    let empty = a.or(ex, ey);
    let has_tiles = a.not(empty);
    let visible = a.and(ok, has_tiles);
    let visible = a.name_b(visible, "visible");

    // Feature entry fields.
    let mean = [0, 1].map(|k| {
        let v = to_fixed(a, mean2d[k], &fmt.mean);
        a.name_i(v, ["mean_x", "mean_y"][k])
    });
    let lsb = a.lit((-(fmt.mean.frac as f32)).exp2());
    let dm = [0, 1].map(|k| {
        let mf = a.int_to_float(mean[k]);
        let mq = a.mul(mf, lsb);
        let v = a.sub(mean2d[k], mq);
        a.name_f(v, ["mean_err_x", "mean_err_y"][k])
    });
    let opacity = to_fixed(a, g.opacity, &fmt.opacity);
    let (conic, conic_exp) = conic_bfp(a, conic_f, &fmt.conic);
    let axis_f = major_axis(a, cov);
    let axis_f = name_each(a, axis_f, ["axis_c_f", "axis_s_f"]);
    let axis = [0, 1].map(|k| {
        let v = to_fixed(a, axis_f[k], &fmt.axis);
        a.name_i(v, ["axis_c", "axis_s"][k])
    });
    let cs = axis.map(|v| a.int_to_float(v));
    let ncs = a.neg(cs[1]);
    let inv_axis = a.lit((-(fmt.axis.frac as f32)).exp2());
    let frac = fmt.axis.frac;
    let su = support(a, cov, g.k2, dm, cs, frac);
    let su = a.mul(su, inv_axis);
    let su = a.name_f(su, "support_u");
    let sv = support(a, cov, g.k2, dm, [ncs, cs[0]], frac);
    let sv = a.mul(sv, inv_axis);
    let sv = a.name_f(sv, "support_v");
    let sx = support(a, cov, g.k2, dm, [one, fzero], frac);
    let sx = a.name_f(sx, "support_x");
    let sy = support(a, cov, g.k2, dm, [fzero, one], frac);
    let sy = a.name_f(sy, "support_y");
    let extent_uv = [extent_ceil(a, su, fmt), extent_ceil(a, sv, fmt)];
    let extent_xy = [extent_ceil(a, sx, fmt), extent_ceil(a, sy, fmt)];
    let depth_key = a.f16_bits(tz);
    Projection {
        visible,
        tile_min: [x0, y0],
        tile_max: [x1, y1],
        radius,
        depth: tz,
        depth_key,
        mean2d,
        cov2d: cov,
        conic_f,
        mean,
        conic,
        conic_exp,
        opacity,
        axis,
        extent_uv,
        extent_xy,
    }
}

/// The projection unit as a dataflow graph. Per-Gaussian inputs: `pos_{x,y,z}`,
/// `cov_{xx,xy,xz,yy,yz,zz}`, `opacity`, `k2`; per-frame inputs: `w2v_{r}{c}` (row `r`,
/// column `c`), `t_{x,y,z}`, `focal_{x,y}`, `lim_{x,y}`, `principal_{x,y}`, `grid_{x,y}`.
/// Outputs: `visible`, `tile_min_{x,y}`, `tile_max_{x,y}`, `depth_key`, `mean_{x,y}`,
/// `conic_{a,b,c}`, `conic_exp`, `opacity`, `axis_{c,s}`, `extent_{u,v}`, `extent_{x,y}`
/// (raw integers as [`Projection`] holds them).
pub fn project_graph(params: &ProjectParams) -> crate::hwarith::graph::Graph {
    use crate::hwarith::graph::Trace;
    let mut t = Trace::new();
    let xyz = ["x", "y", "z"];
    let xy = ["x", "y"];
    let position = xyz.map(|k| t.input_f(&format!("pos_{k}"), false));
    let cov3d = ["xx", "xy", "xz", "yy", "yz", "zz"].map(|k| t.input_f(&format!("cov_{k}"), false));
    let opacity = t.input_f("opacity", false);
    let k2 = t.input_f("k2", false);
    let w2v = [0, 1, 2].map(|r| [0, 1, 2].map(|c| t.input_f(&format!("w2v_{r}{c}"), true)));
    let translation = xyz.map(|k| t.input_f(&format!("t_{k}"), true));
    let focal = xy.map(|k| t.input_f(&format!("focal_{k}"), true));
    let lim = xy.map(|k| t.input_f(&format!("lim_{k}"), true));
    let principal = xy.map(|k| t.input_f(&format!("principal_{k}"), true));
    let grid = xy.map(|k| t.input_i(&format!("grid_{k}"), true));
    let g = GaussianIn { position, cov3d, opacity, k2 };
    let cam = CameraIn { w2v, translation, focal, lim, principal, grid };
    let p = project(&mut t, &g, &cam, params);
    t.output_b("visible", p.visible);
    for (k, n) in xy.iter().enumerate() {
        t.output_i(&format!("tile_min_{n}"), p.tile_min[k]);
        t.output_i(&format!("tile_max_{n}"), p.tile_max[k]);
    }
    t.output_i("depth_key", p.depth_key);
    for (k, n) in xy.iter().enumerate() {
        t.output_i(&format!("mean_{n}"), p.mean[k]);
    }
    for (k, n) in ["a", "b", "c"].iter().enumerate() {
        t.output_i(&format!("conic_{n}"), p.conic[k]);
    }
    t.output_i("conic_exp", p.conic_exp);
    t.output_i("opacity", p.opacity);
    t.output_i("axis_c", p.axis[0]);
    t.output_i("axis_s", p.axis[1]);
    t.output_i("extent_u", p.extent_uv[0]);
    t.output_i("extent_v", p.extent_uv[1]);
    t.output_i("extent_x", p.extent_xy[0]);
    t.output_i("extent_y", p.extent_xy[1]);
    t.finish()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hwarith::Native;
    use proptest::prelude::*;

    fn check_conic(conic: [f32; 3], f: &ConicFormat) -> Result<(), TestCaseError> {
        let (m, e) = conic_bfp(&mut Native, conic, f);
        let want = f.quantize(conic);
        prop_assert_eq!((m, e as u32), ([want.a, want.b, want.c], want.exp), "{:?} {:?}", conic, f);
        Ok(())
    }

    proptest! {
        #[test]
        fn conic_matches_the_f64_quantiser_on_any_bits(bits in prop::array::uniform3(any::<u32>())) {
            check_conic(bits.map(f32::from_bits), &ConicFormat::default())?;
        }

        #[test]
        fn conic_matches_on_conics_and_formats(
            la in -60.0f32..3.0, lc in -60.0f32..3.0, t in -1.0f32..1.0, m in 4u8..=30, e in 1u8..=7, top in -8i8..=8,
        ) {
            let (a, c) = (la.exp2(), lc.exp2());
            let b = t * (a * c).sqrt();
            check_conic([a, b, c], &ConicFormat { mantissa_bits: m, exp_bits: e, top })?;
            check_conic([a, -b, 0.0], &ConicFormat { mantissa_bits: m, exp_bits: e, top })?;
        }

        #[test]
        fn major_axis_is_the_unit_eigenvector(sxx in 0.3f32..1e4, syy in 0.3f32..1e4, t in -0.999f32..0.999) {
            let sxy = t * (sxx * syy).sqrt();
            let [c, s] = major_axis(&mut Native, [sxx, sxy, syy]);
            let theta = 0.5 * (2.0 * sxy as f64).atan2(sxx as f64 - syy as f64);
            let (ct, st) = (theta.cos(), theta.sin());
            prop_assert!(((c as f64).hypot(s as f64) - 1.0).abs() < 1e-5);
            // The same line (up to sign), unless the covariance is nearly isotropic.
            let cross = (c as f64 * st - s as f64 * ct).abs();
            let aniso = ((sxx - syy) as f64).hypot(2.0 * sxy as f64) / (sxx + syy) as f64;
            prop_assert!(cross < 1e-5 / aniso.max(1e-3), "{} {} vs {} {}", c, s, ct, st);
        }
    }

    #[test]
    fn the_graph_computes_the_projection() {
        let params = ProjectParams { feature: FeatureFormat::default(), tile: 64 };
        let g = project_graph(&params);
        assert_eq!(g.inputs.len(), 11 + 9 + 3 + 2 + 2 + 2 + 2);
        let mut rng = crate::synthetic::rng::HashRng::new(11, 0, 0);
        let mut visible = 0;
        for _ in 0..500 {
            let f: Vec<f32> = (0..28).map(|_| rng.range(-3.0, 3.0) as f32).collect();
            let cov =
                [f[3].abs() + 0.01, f[4] * 0.1, f[5] * 0.1, f[6].abs() + 0.01, f[7] * 0.1, f[8].abs() + 0.01];
            let position = [f[0], f[1], f[2].abs() * 3.0];
            let (opacity, k2) = (f[9].abs() / 3.0, f[10].abs() * 4.0);
            // An upright camera: identity rotation, a small translation.
            let w2v = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
            let translation = [f[11] * 0.1, f[12] * 0.1, f[13] * 0.1];
            let cam = CameraIn {
                w2v,
                translation,
                focal: [500.0, 500.0],
                lim: [0.83, 0.62],
                principal: [319.5, 239.5],
                grid: [10, 8],
            };
            let gin = GaussianIn { position, cov3d: cov, opacity, k2 };
            let p = project(&mut Native, &gin, &cam, &params);
            visible += p.visible as usize;
            let mut inputs: Vec<u32> =
                position.iter().chain(&cov).chain([&opacity, &k2]).map(|v| v.to_bits()).collect();
            inputs.extend(
                w2v.iter()
                    .flatten()
                    .chain(&translation)
                    .chain(&cam.focal)
                    .chain(&cam.lim)
                    .chain(&cam.principal)
                    .map(|v| v.to_bits()),
            );
            inputs.extend(cam.grid.map(|v| v as u32));
            let want: Vec<u32> =
                [p.visible as i32, p.tile_min[0], p.tile_max[0], p.tile_min[1], p.tile_max[1], p.depth_key]
                    .into_iter()
                    .chain(p.mean)
                    .chain(p.conic)
                    .chain([p.conic_exp, p.opacity])
                    .chain(p.axis)
                    .chain(p.extent_uv)
                    .chain(p.extent_xy)
                    .map(|v| v as u32)
                    .collect();
            assert_eq!(g.eval(&inputs), want);
        }
        assert!(visible > 100, "{visible} visible");
    }

    #[test]
    fn isotropic_and_degenerate_axes_fall_back_to_x() {
        assert_eq!(major_axis(&mut Native, [2.0, 0.0, 2.0]), [1.0, 0.0]);
        assert_eq!(major_axis(&mut Native, [f32::NAN, 0.0, 2.0]), [1.0, 0.0]);
        assert_eq!(major_axis(&mut Native, [1.0, 0.0, 3.0]), [0.0, 1.0]);
        assert_eq!(major_axis(&mut Native, [3.0, 0.0, 1.0]), [1.0, 0.0]);
    }
}
