//! Per-Gaussian preprocessing (the reference's `preprocessCUDA`): view transform and culling,
//! 3D and 2D (EWA) covariance, conic, screen radius, tile rectangle and SH colour.
//!
//! Matrix products follow GLM's column-major evaluation order in f32 (`(a + b) + c` sums, no
//! fused multiply-add), so that results agree with the reference up to the last-bit effects of
//! FMA contraction by the CUDA compiler and `expf` accuracy.

use super::sh::{eval_sh, view_direction};
use crate::camera::Camera;
use crate::scene::Scene;
use rayon::prelude::*;

/// Gaussians with view-space depth at or below this are culled (the reference's `in_frustum`).
pub const NEAR_CULL: f32 = 0.2;
/// Low-pass dilation added to both diagonal terms of the 2D covariance.
pub const COV2D_DILATION: f32 = 0.3;
/// The view-space mean used for the Jacobian is clamped to this multiple of the half-FOV tangent.
pub const FOV_CLAMP: f32 = 1.3;

/// One Gaussian that survived preprocessing: everything the blending stage reads, plus the
/// intermediate 2D covariance for analysis and for the fixed-point model.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Projected {
    /// Index of the Gaussian in the scene.
    pub index: u32,
    /// Mean in pixel coordinates (pixel centres at integer coordinates).
    pub mean2d: [f32; 2],
    /// 2D covariance `[xx, xy, yy]` in pixels², including the +0.3 dilation.
    pub cov2d: [f32; 3],
    /// Inverse of `cov2d`: `[xx, xy, yy]` = `(c/det, -b/det, a/det)`.
    pub conic: [f32; 3],
    /// View-space depth (z), the sort key.
    pub depth: f32,
    /// Screen radius in pixels, `ceil(3 sqrt(lambda_max))`.
    pub radius: u32,
    /// Colour from SH for this view (+0.5, clamped at 0 below).
    pub rgb: [f32; 3],
    /// Opacity in [0, 1].
    pub opacity: f32,
    /// First tile `[x, y]` covered (inclusive), the reference's `getRect` `rect_min`.
    pub tile_min: [u32; 2],
    /// One past the last tile `[x, y]` covered, the reference's `rect_max`.
    pub tile_max: [u32; 2],
}

impl Projected {
    /// Number of tiles the Gaussian is binned into (`(max.x - min.x) * (max.y - min.y)`).
    pub fn tiles_touched(&self) -> u32 {
        (self.tile_max[0] - self.tile_min[0]) * (self.tile_max[1] - self.tile_min[1])
    }
}

/// A GLM-style 3x3 matrix: `m[c][r]` is column `c`, row `r`.
type Mat = [[f32; 3]; 3];

/// GLM's `m1 * m2`: `result[c][r] = m1[0][r]*m2[c][0] + m1[1][r]*m2[c][1] + m1[2][r]*m2[c][2]`.
fn mul(a: &Mat, b: &Mat) -> Mat {
    let mut out = [[0.0; 3]; 3];
    for (c, col) in out.iter_mut().enumerate() {
        for (r, v) in col.iter_mut().enumerate() {
            *v = a[0][r] * b[c][0] + a[1][r] * b[c][1] + a[2][r] * b[c][2];
        }
    }
    out
}

fn transpose(a: &Mat) -> Mat {
    let mut out = [[0.0; 3]; 3];
    for (c, col) in out.iter_mut().enumerate() {
        for (r, v) in col.iter_mut().enumerate() {
            *v = a[r][c];
        }
    }
    out
}

/// The 3D covariance `R S S^T R^T` as the reference's `computeCov3D` (scale modifier 1), as the
/// upper triangle `[xx, xy, xz, yy, yz, zz]`. `rot` is the w-first quaternion, used as given.
pub fn cov3d(scale: [f32; 3], rot: [f32; 4]) -> [f32; 6] {
    let s: Mat = [[scale[0], 0.0, 0.0], [0.0, scale[1], 0.0], [0.0, 0.0, scale[2]]];
    let [r, x, y, z] = rot;
    // GLM's mat3 constructor takes columns, so this is the transpose of the usual rotation.
    let rm: Mat = [
        [1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y - r * z), 2.0 * (x * z + r * y)],
        [2.0 * (x * y + r * z), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z - r * x)],
        [2.0 * (x * z - r * y), 2.0 * (y * z + r * x), 1.0 - 2.0 * (x * x + y * y)],
    ];
    let m = mul(&s, &rm);
    let sigma = mul(&transpose(&m), &m);
    [sigma[0][0], sigma[0][1], sigma[0][2], sigma[1][1], sigma[1][2], sigma[2][2]]
}

/// Camera quantities shared by all Gaussians of one view, in f32.
#[derive(Clone, Copy, Debug)]
pub struct ViewParams {
    /// World-to-view rotation, row-major (`w2v[r][c]`).
    pub w2v: [[f32; 3]; 3],
    /// World-to-view translation `-R_w2v c`, computed in f64 and rounded, as the reference's
    /// view matrix (built in double precision, then stored as f32).
    pub translation: [f32; 3],
    /// Camera centre in world space (for SH view directions).
    pub cam_pos: [f32; 3],
    /// Focal lengths in pixels.
    pub focal: [f32; 2],
    /// Tangents of the half fields of view, `W / (2 fx)` and `H / (2 fy)`.
    pub tan_half_fov: [f32; 2],
    /// Principal point `((W-1)/2, (H-1)/2)`.
    pub principal: [f32; 2],
    /// Tile grid size `[ceil(W/B), ceil(H/B)]`.
    pub grid: [u32; 2],
    /// Tile side `B` in pixels.
    pub tile_size: u32,
}

impl ViewParams {
    /// The f32 view parameters of `cam` for tiles of `tile_size` pixels (panics if 0).
    pub fn new(cam: &Camera, tile_size: u32) -> Self {
        assert!(tile_size > 0, "tile size must be positive");
        let m = cam.world_to_view_rotation();
        let (cx, cy) = cam.principal_point();
        ViewParams {
            w2v: [m.row(0).to_array(), m.row(1).to_array(), m.row(2).to_array()],
            translation: (-(cam.cam_to_world.transpose() * cam.position)).as_vec3().to_array(),
            cam_pos: cam.position.as_vec3().to_array(),
            focal: [cam.fx as f32, cam.fy as f32],
            tan_half_fov: [cam.tan_half_fov_x(), cam.tan_half_fov_y()],
            principal: [cx, cy],
            grid: [cam.width.div_ceil(tile_size), cam.height.div_ceil(tile_size)],
            tile_size,
        }
    }

    /// View-space position `R_w2v x + t`, as the reference's `transformPoint4x3` (row dot
    /// products summed left to right, then the translation).
    pub fn to_view(&self, p: [f32; 3]) -> [f32; 3] {
        let mut v = [0.0; 3];
        for (v, (row, t)) in v.iter_mut().zip(self.w2v.iter().zip(self.translation)) {
            *v = row[0] * p[0] + row[1] * p[1] + row[2] * p[2] + t;
        }
        v
    }

    /// The EWA 2D covariance `[xx, xy, yy]` of a Gaussian with view-space mean `t` and 3D
    /// covariance `cov3d`, including the +0.3 dilation (the reference's `computeCov2D`).
    pub fn cov2d(&self, t: [f32; 3], cov3d: &[f32; 6]) -> [f32; 3] {
        let [fx, fy] = self.focal;
        let limx = FOV_CLAMP * self.tan_half_fov[0];
        let limy = FOV_CLAMP * self.tan_half_fov[1];
        let tz = t[2];
        let tx = (t[0] / tz).max(-limx).min(limx) * tz;
        let ty = (t[1] / tz).max(-limy).min(limy) * tz;
        let j: Mat =
            [[fx / tz, 0.0, -(fx * tx) / (tz * tz)], [0.0, fy / tz, -(fy * ty) / (tz * tz)], [0.0; 3]];
        // GLM's W: its columns are the rows of the world-to-view rotation.
        let w: Mat = self.w2v;
        let t_mat = mul(&w, &j);
        let c = cov3d;
        let vrk: Mat = [[c[0], c[1], c[2]], [c[1], c[3], c[4]], [c[2], c[4], c[5]]];
        let cov = mul(&mul(&transpose(&t_mat), &transpose(&vrk)), &t_mat);
        [cov[0][0] + COV2D_DILATION, cov[0][1], cov[1][1] + COV2D_DILATION]
    }

    /// The reference's `getRect`: tiles `[min, max)` overlapped by the square of half-side
    /// `radius` around `mean2d`, clamped to the grid.
    pub fn tile_rect(&self, mean2d: [f32; 2], radius: u32) -> ([u32; 2], [u32; 2]) {
        let b = self.tile_size as f32;
        let r = radius as f32;
        let lo = |p: f32, g: u32| (((p - r) / b) as i32).max(0).min(g as i32) as u32;
        // C evaluates `p + r + B - 1` as `((p + r) + B) - 1`.
        let hi = |p: f32, g: u32| (((((p + r) + b) - 1.0) / b) as i32).max(0).min(g as i32) as u32;
        (
            [lo(mean2d[0], self.grid[0]), lo(mean2d[1], self.grid[1])],
            [hi(mean2d[0], self.grid[0]), hi(mean2d[1], self.grid[1])],
        )
    }
}

/// Preprocesses Gaussian `i` of `scene`; `None` when it is culled (view z <= 0.2, singular 2D
/// covariance, zero or non-finite radius or mean, or no tile covered).
pub fn project_one(scene: &Scene, view: &ViewParams, i: usize) -> Option<Projected> {
    let mean = scene.positions[i];
    let t = view.to_view(mean);
    if t[2].is_nan() || t[2] <= NEAR_CULL {
        return None;
    }
    let c3 = cov3d(scene.scales[i], scene.rotations[i]);
    let cov = view.cov2d(t, &c3);
    let det = cov[0] * cov[2] - cov[1] * cov[1];
    if det == 0.0 {
        return None;
    }
    let det_inv = 1.0 / det;
    let conic = [cov[2] * det_inv, -cov[1] * det_inv, cov[0] * det_inv];
    let mid = 0.5 * (cov[0] + cov[2]);
    let disc = (mid * mid - det).max(0.1).sqrt();
    let (lambda1, lambda2) = (mid + disc, mid - disc);
    // Saturating like CUDA's float-to-int conversion; NaN gives 0 and is culled below.
    let radius = (3.0 * lambda1.max(lambda2).sqrt()).ceil() as i32;
    let mean2d =
        [view.focal[0] * t[0] / t[2] + view.principal[0], view.focal[1] * t[1] / t[2] + view.principal[1]];
    // The reference only bins Gaussians with radius > 0; non-finite data cannot be drawn.
    if radius <= 0 || !mean2d.iter().chain(&conic).all(|v| v.is_finite()) {
        return None;
    }
    let radius = radius as u32;
    let (tile_min, tile_max) = view.tile_rect(mean2d, radius);
    if (tile_max[0] - tile_min[0]) * (tile_max[1] - tile_min[1]) == 0 {
        return None;
    }
    let dir = view_direction(mean, view.cam_pos);
    let rgb = eval_sh(scene.sh_degree, scene.sh_of(i), dir);
    Some(Projected {
        index: i as u32,
        mean2d,
        cov2d: cov,
        conic,
        depth: t[2],
        radius,
        rgb,
        opacity: scene.opacities[i],
        tile_min,
        tile_max,
    })
}

/// Preprocesses every Gaussian of `scene` for `cam` with tiles of `tile_size` pixels, in
/// parallel. Returns only the survivors, in Gaussian order. Panics if `tile_size` is 0.
pub fn preprocess(scene: &Scene, cam: &Camera, tile_size: u32) -> Vec<Projected> {
    let view = ViewParams::new(cam, tile_size);
    (0..scene.len()).into_par_iter().with_min_len(4096).filter_map(|i| project_one(scene, &view, i)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    #[test]
    fn cov3d_of_axis_aligned_and_rotated_gaussians() {
        let c = cov3d([1.0, 2.0, 3.0], [1.0, 0.0, 0.0, 0.0]);
        assert_eq!(c, [1.0, 0.0, 0.0, 4.0, 0.0, 9.0]);
        // 90 degrees about z: local x maps to world y, so the variances of x and y swap.
        let h = std::f32::consts::FRAC_1_SQRT_2;
        let c = cov3d([1.0, 2.0, 3.0], [h, 0.0, 0.0, h]);
        assert!((c[0] - 4.0).abs() < 1e-5 && (c[3] - 1.0).abs() < 1e-5 && (c[5] - 9.0).abs() < 1e-5);
        assert!(c[1].abs() < 1e-5 && c[2].abs() < 1e-5 && c[4].abs() < 1e-5);
    }

    /// A camera at the origin looking along +z with f = 50 px.
    fn forward_camera(width: u32, height: u32) -> Camera {
        Camera {
            name: "c".into(),
            width,
            height,
            fx: 50.0,
            fy: 50.0,
            position: DVec3::ZERO,
            cam_to_world: crate::camera::look_at_rotation(DVec3::ZERO, DVec3::Z, DVec3::NEG_Y),
        }
    }

    #[test]
    fn cov2d_of_a_centred_isotropic_gaussian() {
        let cam = forward_camera(64, 48);
        let view = ViewParams::new(&cam, 16);
        let s = 0.1f32;
        let c = view.cov2d([0.0, 0.0, 2.0], &cov3d([s; 3], [1.0, 0.0, 0.0, 0.0]));
        // sigma_pix = f * s / z = 2.5 px, so variance 6.25 (+0.3).
        assert!((c[0] - 6.55).abs() < 1e-5 && (c[2] - 6.55).abs() < 1e-5 && c[1].abs() < 1e-6, "{c:?}");
    }

    #[test]
    fn tile_rect_follows_get_rect() {
        let cam = forward_camera(100, 50);
        let view = ViewParams::new(&cam, 16);
        assert_eq!(view.grid, [7, 4]);
        // (20 - 3) / 16 -> 1, (20 + 3 + 15) / 16 -> 2.
        assert_eq!(view.tile_rect([20.0, 20.0], 3), ([1, 1], [2, 2]));
        // Truncation toward zero: (-5 - 3)/16 = -0.5 -> 0; clamping to the grid at the far side.
        assert_eq!(view.tile_rect([-5.0, 60.0], 3), ([0, 3], [0, 4]));
        assert_eq!(view.tile_rect([99.0, 10.0], 40), ([3, 0], [7, 4]));
    }
}
