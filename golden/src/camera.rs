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

impl Camera {
    /// A camera at `position` looking at `target`, with world "up" `up` (for the INRIA
    /// convention with y down, pass the world direction that should appear at the top).
    pub fn look_at(name: &str, width: u32, height: u32, fx: f64, fy: f64, position: DVec3, target: DVec3, up: DVec3) -> Self {
        let z = (target - position).normalize();
        // Camera y points down in the image, i.e. opposite to `up`.
        let mut x = z.cross(-up);
        if x.length_squared() < 1e-18 {
            // Looking straight along `up`: pick any perpendicular axis.
            x = z.any_orthonormal_vector();
        }
        let x = x.normalize();
        let y = z.cross(x);
        Camera {
            name: name.to_string(),
            width,
            height,
            fx,
            fy,
            position,
            cam_to_world: DMat3::from_cols(x, y, z),
        }
    }

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
