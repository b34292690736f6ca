//! Front-to-back alpha blending per pixel (the reference's `renderCUDA`), parallel over tile
//! rows.

use super::binning::TileBins;
use super::preprocess::Projected;
use crate::image::Image;
use rayon::prelude::*;

/// Alpha is capped at this value.
pub const MAX_ALPHA: f32 = 0.99;
/// Contributions with alpha below this are skipped.
pub const MIN_ALPHA: f32 = 1.0 / 255.0;
/// A pixel is finished when its transmittance would drop below this.
pub const MIN_TRANSMITTANCE: f32 = 0.0001;

/// What blending reads of one Gaussian, packed for cache-friendly per-tile loops.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Splat {
    /// Mean in pixel coordinates.
    pub mean: [f32; 2],
    /// Conic `[xx, xy, yy]`.
    pub conic: [f32; 3],
    /// Opacity.
    pub opacity: f32,
    /// Colour.
    pub rgb: [f32; 3],
    /// A `power` below this certainly gives `alpha < 1/255`, so `exp` can be skipped. Only a
    /// shortcut: it is conservative by a margin far above f32 rounding, and results are the
    /// same as without it.
    pub power_cut: f32,
}

/// Margin (in `power` units) of [`Splat::power_cut`] and of tile culling. It covers the f32
/// rounding of `exp` and of the `opacity * exp` product (~1e-7 relative) many times over.
const POWER_MARGIN: f64 = 1e-4;

/// `ln(1/255 / opacity) - margin`: below it, `opacity * exp(power) < 1/255` for sure.
fn power_cut(opacity: f32) -> f64 {
    (MIN_ALPHA as f64 / opacity as f64).ln() - POWER_MARGIN
}

impl From<&Projected> for Splat {
    fn from(p: &Projected) -> Self {
        Splat {
            mean: p.mean2d,
            conic: p.conic,
            opacity: p.opacity,
            rgb: p.rgb,
            power_cut: power_cut(p.opacity) as f32,
        }
    }
}

/// Blends `splats` (front to back) at the pixel centre `(x, y)` over a black background,
/// operation for operation as the reference, and returns the colour.
pub fn blend_pixel(splats: &[Splat], x: u32, y: u32) -> [f32; 3] {
    let (pxf, pyf) = (x as f32, y as f32);
    let mut t = 1.0f32;
    let mut c = [0.0f32; 3];
    for s in splats {
        let dx = s.mean[0] - pxf;
        let dy = s.mean[1] - pyf;
        let power = -0.5 * (s.conic[0] * dx * dx + s.conic[2] * dy * dy) - s.conic[1] * dx * dy;
        // A NaN cut (NaN opacity) compares false and never skips.
        if power > 0.0 || power < s.power_cut {
            continue;
        }
        let alpha = MAX_ALPHA.min(s.opacity * power.exp());
        if alpha < MIN_ALPHA {
            continue;
        }
        let test_t = t * (1.0 - alpha);
        if test_t < MIN_TRANSMITTANCE {
            break;
        }
        for (c, rgb) in c.iter_mut().zip(s.rgb) {
            *c += rgb * alpha * t;
        }
        t = test_t;
    }
    c
}

/// Whether `p` can give `alpha >= 1/255` at some pixel centre of the rectangle
/// `[x0, x1] x [y0, y1]` (inclusive). Conservative: `false` only when every such pixel is
/// certainly skipped by [`blend_pixel`], including f32 rounding of its `power`.
pub fn may_touch(p: &Projected, x0: u32, x1: u32, y0: u32, y1: u32) -> bool {
    let [mx, my] = p.mean2d.map(f64::from);
    if mx.is_nan() || my.is_nan() || mx.abs() >= 1e5 || my.abs() >= 1e5 {
        return true;
    }
    let dx = (x0 as f64 - mx).max(mx - x1 as f64).max(0.0);
    let dy = (y0 as f64 - my).max(my - y1 as f64).max(0.0);
    // Slack for the rounding of `mean - pixel` in f32.
    let dist2 = ((dx * dx + dy * dy).sqrt() - 0.01).max(0.0).powi(2);
    let [a, b, c] = p.conic.map(f64::from);
    let lambda_min = 0.5 * (a + c) - (0.25 * (a - c) * (a - c) + b * b).sqrt();
    // -power >= |d|^2 (lambda_min / 2 - rounding), rounding bounded well above 4 ulp per term.
    let k = 0.5 * lambda_min - 1e-6 * (a.abs() + c.abs() + 2.0 * b.abs());
    let cut = power_cut(p.opacity);
    !(k > 0.0 && -k * dist2 < cut)
}

/// Renders the image from the binned Gaussians: every pixel blends its tile's list.
/// `tile_size` must be the one the bins were made with.
///
/// Before blending a tile, Gaussians that `may_touch` none of its pixels are dropped from its
/// list; this only saves time.
pub fn blend(projected: &[Projected], bins: &TileBins, width: u32, height: u32, tile_size: u32) -> Image {
    let mut image = Image::new(width, height);
    if width == 0 || height == 0 {
        return image;
    }
    let b = tile_size as usize;
    let w = width as usize;
    image.data.par_chunks_mut(b * w).enumerate().for_each_init(
        Vec::new,
        |scratch: &mut Vec<Splat>, (ty, rows)| {
            let y0 = ty * b;
            let nrows = rows.len() / w;
            for tx in 0..bins.grid[0] {
                let x0 = tx as usize * b;
                let x1 = (x0 + b).min(w);
                let (px0, px1, py0, py1) = (x0 as u32, x1 as u32 - 1, y0 as u32, (y0 + nrows) as u32 - 1);
                scratch.clear();
                scratch.extend(
                    bins.tile(tx, ty as u32)
                        .iter()
                        .map(|&j| &projected[j as usize])
                        .filter(|p| may_touch(p, px0, px1, py0, py1))
                        .map(Splat::from),
                );
                for r in 0..nrows {
                    for x in x0..x1 {
                        rows[r * w + x] = blend_pixel(scratch, x as u32, (y0 + r) as u32);
                    }
                }
            }
        },
    );
    image
}

#[cfg(test)]
mod tests {
    use super::*;

    fn s(mean: [f32; 2], opacity: f32, rgb: [f32; 3]) -> Splat {
        Splat { mean, conic: [0.5, 0.0, 0.5], opacity, rgb, power_cut: f32::NEG_INFINITY }
    }

    #[test]
    fn blending_is_front_to_back_over_black() {
        let a = s([3.0, 4.0], 0.5, [1.0, 0.0, 0.0]);
        let b = s([3.0, 4.0], 0.5, [0.0, 1.0, 0.0]);
        assert_eq!(blend_pixel(&[a, b], 3, 4), [0.5, 0.25, 0.0]);
        assert_eq!(blend_pixel(&[], 3, 4), [0.0; 3]);
    }

    #[test]
    fn alpha_is_capped_and_opaque_stacks_stop() {
        let white = s([0.0, 0.0], 2.0, [1.0; 3]);
        // Opacity 2 is capped to alpha 0.99.
        assert_eq!(blend_pixel(&[white], 0, 0), [0.99; 3]);
        // Alpha 0.95: T = 1, 0.05, 0.0025, 0.000125, then 6.25e-6 < 1e-4 stops the pixel, so
        // the red fourth layer is not added.
        let w = s([0.0, 0.0], 0.95, [1.0; 3]);
        let red = s([0.0, 0.0], 0.95, [1.0, 0.0, 0.0]);
        let c = blend_pixel(&[w, w, w, red, red], 0, 0);
        assert_eq!(c[0], c[1]);
        assert!((c[0] - 0.95 * (1.0 + 0.05 + 0.0025)).abs() < 1e-6, "{c:?}");
    }
}
