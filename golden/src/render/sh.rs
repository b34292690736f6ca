//! View-dependent colour from spherical harmonics, as the reference's `computeColorFromSH`.

// The reference's constants, written with their full decimal expansion and rounded to f32 as
// the CUDA compiler does for its `float` literals.
/// Degree-0 SH basis constant.
pub const SH_C0: f32 = crate::scene::SH_C0 as f32;
/// Degree-1 SH basis constant.
pub const SH_C1: f32 = 0.488_602_511_902_919_9_f64 as f32;
/// Degree-2 SH basis constants.
pub const SH_C2: [f32; 5] = [
    1.092_548_430_592_079_2_f64 as f32,
    -1.092_548_430_592_079_2_f64 as f32,
    0.315_391_565_252_520_05_f64 as f32,
    -1.092_548_430_592_079_2_f64 as f32,
    0.546_274_215_296_039_6_f64 as f32,
];
/// Degree-3 SH basis constants.
pub const SH_C3: [f32; 7] = [
    -0.590_043_589_926_643_5_f64 as f32,
    2.890_611_442_640_554_f64 as f32,
    -0.457_045_799_464_465_8_f64 as f32,
    0.373_176_332_590_115_4_f64 as f32,
    -0.457_045_799_464_465_8_f64 as f32,
    1.445_305_721_320_277_f64 as f32,
    -0.590_043_589_926_643_5_f64 as f32,
];

/// `a * s` for a colour triple.
fn scale(s: f32, v: &[f32]) -> [f32; 3] {
    [s * v[0], s * v[1], s * v[2]]
}

fn add(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

fn sub(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// The unit view direction `(mean - cam) / |mean - cam|`, with the reference's operation order
/// (`glm::length` = `sqrt(x*x + y*y + z*z)`, then a division per component).
pub fn view_direction(mean: [f32; 3], cam: [f32; 3]) -> [f32; 3] {
    let d = [mean[0] - cam[0], mean[1] - cam[1], mean[2] - cam[2]];
    let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    [d[0] / len, d[1] / len, d[2] / len]
}

/// Evaluates the SH colour for unit direction `dir` from `sh` (`[coeff][rgb]` flattened, at
/// least `3 * (degree + 1)^2` values), adds 0.5 and clamps at 0 from below, operation for
/// operation as the reference (f32, left-to-right sums).
pub fn eval_sh(degree: u8, sh: &[f32], dir: [f32; 3]) -> [f32; 3] {
    let c = |k: usize| &sh[3 * k..3 * k + 3];
    let mut r = scale(SH_C0, c(0));
    if degree > 0 {
        let [x, y, z] = dir;
        r = sub(r, scale(SH_C1 * y, c(1)));
        r = add(r, scale(SH_C1 * z, c(2)));
        r = sub(r, scale(SH_C1 * x, c(3)));
        if degree > 1 {
            let (xx, yy, zz) = (x * x, y * y, z * z);
            let (xy, yz, xz) = (x * y, y * z, x * z);
            r = add(r, scale(SH_C2[0] * xy, c(4)));
            r = add(r, scale(SH_C2[1] * yz, c(5)));
            r = add(r, scale(SH_C2[2] * (2.0 * zz - xx - yy), c(6)));
            r = add(r, scale(SH_C2[3] * xz, c(7)));
            r = add(r, scale(SH_C2[4] * (xx - yy), c(8)));
            if degree > 2 {
                r = add(r, scale(SH_C3[0] * y * (3.0 * xx - yy), c(9)));
                r = add(r, scale(SH_C3[1] * xy * z, c(10)));
                r = add(r, scale(SH_C3[2] * y * (4.0 * zz - xx - yy), c(11)));
                r = add(r, scale(SH_C3[3] * z * (2.0 * zz - 3.0 * xx - 3.0 * yy), c(12)));
                r = add(r, scale(SH_C3[4] * x * (4.0 * zz - xx - yy), c(13)));
                r = add(r, scale(SH_C3[5] * z * (xx - yy), c(14)));
                r = add(r, scale(SH_C3[6] * x * (xx - 3.0 * yy), c(15)));
            }
        }
    }
    r.map(|v| (v + 0.5).max(0.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn degree_zero_is_dc_plus_half_clamped() {
        let sh = [1.0, -10.0, 0.0];
        assert_eq!(eval_sh(0, &sh, [0.0, 0.0, 1.0]), [SH_C0 + 0.5, 0.0, 0.5]);
    }

    #[test]
    fn degree_one_follows_the_sign_convention() {
        // Only coefficient 2 (the z term) set: colour = 0.5 + SH_C1 * z.
        let mut sh = [0.0f32; 12];
        sh[6] = 1.0;
        let up = eval_sh(1, &sh, [0.0, 0.0, 1.0]);
        assert_eq!(up[0], 0.5 + SH_C1);
        assert_eq!(up[1], 0.5);
        // Coefficient 1 (y term) enters with a minus sign.
        let mut sh = [0.0f32; 12];
        sh[3] = 1.0;
        assert_eq!(eval_sh(1, &sh, [0.0, 1.0, 0.0])[0], 0.5 - SH_C1);
    }

    #[test]
    fn higher_degrees_match_the_real_sh_basis() {
        // Each basis function at a generic direction, compared to an f64 evaluation of the
        // real SH polynomials (including the reference's sign conventions).
        let d = view_direction([0.3, -0.4, 1.2], [0.0, 0.0, 0.0]);
        let (x, y, z) = (d[0] as f64, d[1] as f64, d[2] as f64);
        let basis: [f64; 16] = [
            0.282_094_791_773_878_14,
            -0.488_602_511_902_919_9 * y,
            0.488_602_511_902_919_9 * z,
            -0.488_602_511_902_919_9 * x,
            1.092_548_430_592_079_2 * x * y,
            -1.092_548_430_592_079_2 * y * z,
            0.315_391_565_252_520_05 * (2.0 * z * z - x * x - y * y),
            -1.092_548_430_592_079_2 * x * z,
            0.546_274_215_296_039_6 * (x * x - y * y),
            -0.590_043_589_926_643_5 * y * (3.0 * x * x - y * y),
            2.890_611_442_640_554 * x * y * z,
            -0.457_045_799_464_465_8 * y * (4.0 * z * z - x * x - y * y),
            0.373_176_332_590_115_4 * z * (2.0 * z * z - 3.0 * x * x - 3.0 * y * y),
            -0.457_045_799_464_465_8 * x * (4.0 * z * z - x * x - y * y),
            1.445_305_721_320_277 * z * (x * x - y * y),
            -0.590_043_589_926_643_5 * x * (x * x - 3.0 * y * y),
        ];
        for (k, b) in basis.iter().enumerate() {
            let mut sh = [0.0f32; 48];
            sh[3 * k + 1] = 1.0;
            let got = eval_sh(3, &sh, d)[1] as f64;
            assert!((got - (0.5 + b).max(0.0)).abs() < 1e-6, "coefficient {k}: {got} vs {}", 0.5 + b);
        }
    }
}
