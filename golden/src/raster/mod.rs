//! Bit-exact model of Neo's Rasterization Engine (paper Section 5.4) on quantised feature
//! entries ([`crate::formats`]): integer arithmetic only (adds, multiplies, shifts, compares,
//! one small table).
//!
//! - [`itu`]: the Intersection Test Unit: per tile, the subtile bitmap of a Gaussian (separating
//!   axis test of its cutoff octagon against each subtile), the cumulative-OR valid bit, and a
//!   conservative tile range for binning;
//! - [`exp`]: the exp unit (table over one octave with linear interpolation);
//! - [`scu`]: the Subtile Compute Unit: per-pixel power, alpha, transmittance and colour, per
//!   subtile, in table order, with early termination;
//! - [`tile`]: the tile driver: [`tile::raster_tile`] routes a tile's table to its subtiles and
//!   renders the tile with the SCU ([`tile::tile_work_into`]: its work counters alone);
//! - [`window`]: the reorder window between the feature gather and the ITUs (off in the
//!   paper's engine);
//! - [`synth`]: hand-made preprocessed Gaussians for tests.
//!
//! Pixel centres are at integer coordinates. A subtile whose pixel columns are `x0..x0+S-1`
//! is the closed rectangle `[x0, x0+S-1]` (the pixel centres), see [`itu`].

pub mod exp;
pub mod itu;
pub mod scu;
pub mod synth;
pub mod tile;
pub mod window;

pub use exp::{ExpError, ExpTable};
pub use itu::{candidate_tiles, intersects_rect, subtile_bitmap, touches_tile};
pub use scu::{pixel_alpha, shade_pixel, PixelShade, SubtileWork};
pub use tile::{raster_tile, raster_tile_into, tile_work_into, TileAt, TileRaster};

use crate::formats::blend::BlendFormat;
use crate::formats::feature::FeatureFormat;
use crate::formats::fixed::FormatError;

/// Bits of one output pixel: 8-bit red, green and blue, packed `{blue, green, red}` (red in the
/// low byte) in the SCU's output, the raster core's pixel rows and the frame buffer.
pub const RGB_BITS: u32 = 24;

/// Tile geometry and the SCU datapath widths.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub struct RasterConfig {
    /// Tile side in pixels (64 in the paper).
    pub tile: u32,
    /// Subtile side in pixels (8 in the paper); divides `tile`, at most 64 subtiles per tile.
    pub subtile: u32,
    /// SCU widths.
    pub blend: BlendFormat,
}

impl Default for RasterConfig {
    /// 64x64 tiles of 8x8 subtiles (paper Table 1), default SCU widths.
    fn default() -> Self {
        RasterConfig { tile: 64, subtile: 8, blend: BlendFormat::default() }
    }
}

impl RasterConfig {
    /// Subtiles per tile side, `tile / subtile`.
    pub fn subtiles_per_side(&self) -> u32 {
        self.tile / self.subtile
    }

    /// Subtiles per tile (bitmap width).
    pub fn subtiles_per_tile(&self) -> u32 {
        self.subtiles_per_side() * self.subtiles_per_side()
    }

    /// Checks the geometry, the SCU widths, and the SCU's conic-to-power shift for `fmt`
    /// (`M - top + 2 mean.frac + 1 - power_frac >= 1`, so power is a right shift of the exact
    /// quadratic form).
    pub fn check(&self, fmt: &FeatureFormat) -> Result<(), FormatError> {
        fmt.check()?;
        self.blend.check()?;
        if self.subtile == 0 || self.tile == 0 || self.tile / self.subtile * self.subtile != self.tile {
            return Err(FormatError::new(
                "tile",
                format!("tile {} is not a positive multiple of subtile {}", self.tile, self.subtile),
            ));
        }
        if self.subtiles_per_tile() > 64 {
            return Err(FormatError::new("tile", format!("{} subtiles exceed 64", self.subtiles_per_tile())));
        }
        if self.tile > 1024 {
            return Err(FormatError::new("tile", format!("tile {} is above 1024", self.tile)));
        }
        let shift = scu::min_power_shift(fmt, &self.blend);
        if shift < 1 {
            return Err(FormatError::new(
                "blend.power_frac",
                format!("conic-to-power shift {shift} is below 1"),
            ));
        }
        Ok(())
    }
}
