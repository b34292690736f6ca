//! The float reference renderer, following the published 3DGS rasterizer forward pass
//! (`diff-gaussian-rasterization`, Kerbl et al. 2023) in f32.
//!
//! Three stages, each a public function so later models can reuse or replace one:
//! 1. [`preprocess`]: per Gaussian, view transform, culling, EWA 2D covariance, conic, radius,
//!    tile rectangle and SH colour ([`Projected`]).
//! 2. [`bin`]: tile lists sorted by depth, ties by Gaussian index ([`TileBins`]).
//! 3. [`blend`]: per-pixel front-to-back alpha blending over black.
//!
//! Conventions (those of the reference): pixel centres at integer coordinates, principal point
//! `((W-1)/2, (H-1)/2)`, view-space x right, y down, z forward.
//!
//! Images do not depend on the number of threads. They depend on the tile size (16 in the
//! reference) only through the reference's `getRect`, which decides the tiles a Gaussian is
//! blended in: pixels outside its `radius` square but inside a covered tile still see it (this
//! matters for opacities above ~0.35, where alpha at 3 sigma exceeds 1/255), and because
//! `rect_max = (int)((p + r + B - 1) / B)` is taken of a float `p`, the tile starting at pixel
//! `tB` is left out when `tB <= p + r < tB + 1`, although that column (row) is within the radius.
//! Both are faithful to the reference.
//!
//! Known, deliberate differences from the CUDA code, all at the last-bit level: the pixel mean
//! is `fx * x / z + (W-1)/2` rather than going through the projection matrix and `ndc2Pix`, f32
//! products are not fused into FMAs, and `exp` is the platform's `expf`. The view-space mean is
//! `R x + t` with `t = -R c` rounded from f64, as the reference's view matrix: against the shared
//! reference renders this gives fewer 1-LSB differences than `R (x - c)` in f32.

mod binning;
mod blend;
mod preprocess;
pub mod sh;

pub use binning::{bin, TileBins};
pub use blend::{blend, blend_pixel, Splat, MAX_ALPHA, MIN_ALPHA, MIN_TRANSMITTANCE};
pub use preprocess::{
    cov3d, preprocess, project_one, Projected, ViewParams, COV2D_DILATION, FOV_CLAMP, NEAR_CULL,
};
pub use sh::{eval_sh, view_direction, SH_C0, SH_C1, SH_C2, SH_C3};

use crate::camera::Camera;
use crate::image::Image;
use crate::scene::Scene;
use std::time::Instant;

/// The reference's tile side.
pub const DEFAULT_TILE_SIZE: u32 = 16;

/// Renderer settings.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RenderOptions {
    /// Tile side in pixels (the reference uses 16); must be positive.
    pub tile_size: u32,
}

impl Default for RenderOptions {
    fn default() -> Self {
        RenderOptions { tile_size: DEFAULT_TILE_SIZE }
    }
}

/// Counts and timings of one render.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct RenderStats {
    /// Gaussians in the scene.
    pub gaussians: usize,
    /// Gaussians that survived preprocessing (cover at least one tile).
    pub visible: usize,
    /// Tile-Gaussian pairs (each visible Gaussian counted once per tile it covers).
    pub pairs: usize,
    /// Wall-clock seconds spent in preprocessing.
    pub preprocess_s: f64,
    /// Wall-clock seconds spent binning and sorting.
    pub binning_s: f64,
    /// Wall-clock seconds spent blending.
    pub blend_s: f64,
}

impl RenderStats {
    /// One line with the time per stage, e.g. `preprocess 0.21 s, binning 0.06 s, blend 0.80 s`.
    pub fn timing_summary(&self) -> String {
        format!(
            "preprocess {:.3} s, binning {:.3} s, blend {:.3} s",
            self.preprocess_s, self.binning_s, self.blend_s
        )
    }
}

/// A rendered image with its statistics.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderOutput {
    /// Linear float RGB, black background.
    pub image: Image,
    /// Counts and timings.
    pub stats: RenderStats,
}

/// Renders `scene` from `cam` with the reference forward pass, in parallel on the current rayon
/// pool. Panics if `opts.tile_size` is 0.
pub fn render(scene: &Scene, cam: &Camera, opts: &RenderOptions) -> RenderOutput {
    assert!(opts.tile_size > 0, "RenderOptions::tile_size must be positive");
    let t0 = Instant::now();
    let projected = preprocess(scene, cam, opts.tile_size);
    let t1 = Instant::now();
    let grid = [cam.width.div_ceil(opts.tile_size), cam.height.div_ceil(opts.tile_size)];
    let bins = bin(&projected, grid);
    let t2 = Instant::now();
    let image = blend(&projected, &bins, cam.width, cam.height, opts.tile_size);
    let t3 = Instant::now();
    let stats = RenderStats {
        gaussians: scene.len(),
        visible: projected.len(),
        pairs: bins.pairs(),
        preprocess_s: (t1 - t0).as_secs_f64(),
        binning_s: (t2 - t1).as_secs_f64(),
        blend_s: (t3 - t2).as_secs_f64(),
    };
    RenderOutput { image, stats }
}
