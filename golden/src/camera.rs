//! Pinhole cameras in the INRIA `cameras.json` convention.
//!
//! `position` is the camera centre in world space and `rotation` the camera-to-world rotation
//! given as rows. Camera axes: x right, y down, z forward. The principal point is the image
//! centre `((W-1)/2, (H-1)/2)` with pixel centres at integer coordinates, as in the reference
//! rasterizer.

use glam::{DMat3, DVec3, Mat3, Vec3};

/// One camera (intrinsics and pose).
#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    /// Free-form name (`img_name` in cameras.json).
    pub name: String,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Focal length along x, in pixels.
    pub fx: f64,
    /// Focal length along y, in pixels.
    pub fy: f64,
    /// Camera centre in world space.
    pub position: DVec3,
    /// Camera-to-world rotation: its columns are the camera's x, y, z axes in world space.
    pub cam_to_world: DMat3,
}

/// The camera-to-world rotation of a camera looking from `position` at `target`, with the world
/// direction `up` appearing at the top of the image (camera y points down, so it is `-up`).
/// When the view is along `up`, any perpendicular right axis is chosen.
pub fn look_at_rotation(position: DVec3, target: DVec3, up: DVec3) -> DMat3 {
    let z = (target - position).normalize();
    // Right-handed camera frame with x right, y down, z forward: x = y cross z = z cross up.
    let mut x = z.cross(up);
    if x.length_squared() < 1e-18 {
        x = z.any_orthonormal_vector();
    }
    let x = x.normalize();
    let y = z.cross(x);
    DMat3::from_cols(x, y, z)
}

impl Camera {
    /// World-to-view rotation (single precision), the transpose of `cam_to_world`.
    pub fn world_to_view_rotation(&self) -> Mat3 {
        self.cam_to_world.transpose().as_mat3()
    }

    /// Transforms a world point into view space (x right, y down, z forward).
    pub fn to_view(&self, p: Vec3) -> Vec3 {
        self.world_to_view_rotation() * (p - self.position.as_vec3())
    }

    /// The camera's forward axis in world space.
    pub fn forward(&self) -> DVec3 {
        self.cam_to_world.z_axis
    }

    /// `tan(fov_x / 2) = W / (2 fx)`.
    pub fn tan_half_fov_x(&self) -> f32 {
        (self.width as f64 / (2.0 * self.fx)) as f32
    }

    /// `tan(fov_y / 2) = H / (2 fy)`.
    pub fn tan_half_fov_y(&self) -> f32 {
        (self.height as f64 / (2.0 * self.fy)) as f32
    }

    /// Principal point `((W-1)/2, (H-1)/2)`.
    pub fn principal_point(&self) -> (f32, f32) {
        ((self.width as f32 - 1.0) * 0.5, (self.height as f32 - 1.0) * 0.5)
    }

    /// The same pose at another resolution, keeping the field of view.
    pub fn with_resolution(&self, width: u32, height: u32) -> Camera {
        let sx = width as f64 / self.width as f64;
        let sy = height as f64 / self.height as f64;
        Camera { width, height, fx: self.fx * sx, fy: self.fy * sy, ..self.clone() }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn look_at_puts_up_at_the_top_of_the_image() {
        // World y is down (INRIA convention), so "up" is -y.
        let r = look_at_rotation(DVec3::new(0.0, 0.0, -5.0), DVec3::ZERO, DVec3::NEG_Y);
        let cam = Camera {
            name: String::new(),
            width: 100,
            height: 100,
            fx: 100.0,
            fy: 100.0,
            position: DVec3::new(0.0, 0.0, -5.0),
            cam_to_world: r,
        };
        assert!((r.determinant() - 1.0).abs() < 1e-12, "proper rotation");
        // A point above the target (smaller world y) lands above the centre (smaller image y).
        assert!(cam.to_view(Vec3::new(0.0, -1.0, 0.0)).y < 0.0);
        // A point to the right (+x, seen from -z looking at +z) lands right of the centre.
        assert!(cam.to_view(Vec3::new(1.0, 0.0, 0.0)).x > 0.0);
        assert!(cam.to_view(Vec3::ZERO).z > 4.99);
    }
}
