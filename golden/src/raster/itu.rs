//! The Intersection Test Unit: does a Gaussian's cutoff ellipse reach a rectangle of pixels?
//!
//! # The test
//! The feature entry describes an octagon containing the cutoff ellipse (see
//! [`crate::formats::feature`]): its supports along x, y (`extent_xy`) and along the quantised
//! axes `U = (C, S)`, `V = (-S, C)` (`extent_uv`). A rectangle with centre `r` and half-sizes
//! `(w, h)` is *separated* from the Gaussian when, on one of these four axes, the distance
//! between the centres exceeds the sum of the supports (the separating axis theorem, with the
//! ellipse's exact support on each axis rather than a box's):
//! - x: `|dx| > w + Rx`; y: `|dy| > h + Ry`;
//! - U: `|dx C + dy S| > Hu 2^axis.frac + w |C| + h |S|`;
//! - V: `|dy C - dx S| > Hv 2^axis.frac + w |S| + h |C|`;
//!
//! with `d = mean - r`. An unbounded extent (largest raw value) never separates. Since every
//! support is rounded up and includes the mean's rounding error, the test never reports
//! "separated" when the exact f64 ellipse meets the rectangle (property-tested); it may report
//! an overlap that is not there near the octagon's corners (false positives, measured in
//! docs/formats.md).
//!
//! # Rectangles
//! Pixel centres are at integer coordinates and a pixel is shaded iff its *centre* is in the
//! ellipse, so the subtile with pixel columns `x0..=x0+S-1` and rows `y0..=y0+S-1` is the closed
//! rectangle `[x0, x0+S-1] x [y0, y0+S-1]`. (The half-pixel-wider `[x0-0.5, x0+S-0.5]` would
//! only add false positives: an ellipse meeting it but not the pixel-centre rectangle contains
//! no pixel centre of the subtile.)
//!
//! # Arithmetic
//! All in integers in units of `2^-G` pixels, `G = mean.frac + 1` (so rectangle centres
//! `(x0 + x1) / 2` are exact): the mean is `mean_raw << 1`, `x`/`y` extents
//! `raw << (G - extent.frac)`, `U`/`V` extents `raw << (G - extent.frac + axis.frac)`. Widths
//! (defaults): `d` 27 bits signed, `d . U` 37 bits, all comparisons below 40 bits.

use super::RasterConfig;
use crate::formats::feature::{FeatureEntry, FeatureFormat};
use std::ops::Range;

/// A support that never separates.
const UNBOUNDED: i64 = i64::MAX / 4;

/// The ITU operands of one entry, in units of `2^-G` pixels (see the module doc).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct ItuGeom {
    /// `mean.frac`: rectangle coordinates are scaled by `2^(G-1) = 2^fm`.
    fm: u32,
    /// Mean, `2^-G` px.
    m: [i64; 2],
    /// x / y supports, `2^-G` px, or [`UNBOUNDED`].
    r: [i64; 2],
    /// Axis `(C, S)`.
    cs: [i64; 2],
    /// U / V supports, `2^-G` px times the axis scale, or [`UNBOUNDED`].
    h: [i64; 2],
}

impl ItuGeom {
    /// The operands of `f`.
    pub(crate) fn new(f: &FeatureEntry, fmt: &FeatureFormat) -> Self {
        let fm = fmt.mean.frac as u32;
        let g = fm + 1;
        let unb = fmt.unbounded_extent();
        let up = |raw: i32, extra: u32| {
            if raw >= unb {
                UNBOUNDED
            } else {
                (raw as i64) << (g - fmt.extent.frac as u32 + extra)
            }
        };
        let fr = fmt.axis.frac as u32;
        ItuGeom {
            fm,
            m: f.mean.map(|v| (v as i64) << 1),
            r: [up(f.extent_xy[0], 0), up(f.extent_xy[1], 0)],
            cs: f.axis.map(|v| v as i64),
            h: [up(f.extent_uv[0], fr), up(f.extent_uv[1], fr)],
        }
    }

    /// Whether the x extent separates the Gaussian from pixel columns `[x0, x1]`.
    #[inline]
    fn separated_x(&self, x0: i64, x1: i64) -> bool {
        let (c, w) = ((x0 + x1) << self.fm, (x1 - x0) << self.fm);
        (self.m[0] - c).abs() > w + self.r[0]
    }

    /// Whether the y extent separates the Gaussian from pixel rows `[y0, y1]`.
    #[inline]
    fn separated_y(&self, y0: i64, y1: i64) -> bool {
        let (c, h) = ((y0 + y1) << self.fm, (y1 - y0) << self.fm);
        (self.m[1] - c).abs() > h + self.r[1]
    }

    /// Whether the U or V support separates the Gaussian from `[x0, x1] x [y0, y1]`.
    #[inline]
    fn separated_uv(&self, x0: i64, y0: i64, x1: i64, y1: i64) -> bool {
        let (dx, dy) = (self.m[0] - ((x0 + x1) << self.fm), self.m[1] - ((y0 + y1) << self.fm));
        let (w, h) = ((x1 - x0) << self.fm, (y1 - y0) << self.fm);
        let [c, s] = self.cs;
        let pu = dx * c + dy * s;
        let pv = dy * c - dx * s;
        pu.abs() > self.h[0] + w * c.abs() + h * s.abs() || pv.abs() > self.h[1] + w * s.abs() + h * c.abs()
    }

    /// Whether the Gaussian may reach the closed pixel-centre rectangle `[x0, x1] x [y0, y1]`.
    #[inline]
    pub(crate) fn overlaps(&self, x0: i64, y0: i64, x1: i64, y1: i64) -> bool {
        !(self.separated_x(x0, x1) || self.separated_y(y0, y1) || self.separated_uv(x0, y0, x1, y1))
    }
}

/// Whether `f` may reach a pixel centre of the closed rectangle `[x0, x1] x [y0, y1]` (pixel
/// coordinates, `x0 <= x1`, `y0 <= y1`, magnitudes below `2^24`): the ITU test of the module
/// doc.
pub fn intersects_rect(f: &FeatureEntry, fmt: &FeatureFormat, x0: i64, y0: i64, x1: i64, y1: i64) -> bool {
    ItuGeom::new(f, fmt).overlaps(x0, y0, x1, y1)
}

/// The subtile bitmap of `f` in tile `(tile_x, tile_y)`: bit `sy * n + sx` (`n = tile /
/// subtile`, row-major) is set iff the ITU test passes for subtile `(sx, sy)`, the rectangle
/// `[X + sx S, X + sx S + S - 1] x [Y + sy S, ...]` with `X = tile_x * tile`. The test is
/// geometric only: subtiles outside the image are tested like the others.
pub fn subtile_bitmap(
    f: &FeatureEntry,
    fmt: &FeatureFormat,
    tile_x: u32,
    tile_y: u32,
    cfg: &RasterConfig,
) -> u64 {
    bitmap_of(&ItuGeom::new(f, fmt), tile_x, tile_y, cfg)
}

/// [`subtile_bitmap`] on precomputed operands. The x and y tests depend only on the column and
/// the row; the U and V tests' projections `d . U`, `d . V` change by a constant from one
/// subtile to the next (all subtiles have the same size, so the same supports), and are stepped
/// in exact integer arithmetic: the same values as [`ItuGeom::overlaps`] on each subtile.
pub(crate) fn bitmap_of(g: &ItuGeom, tile_x: u32, tile_y: u32, cfg: &RasterConfig) -> u64 {
    let n = cfg.subtiles_per_side() as i64;
    let s = cfg.subtile as i64;
    let (tx0, ty0) = (tile_x as i64 * cfg.tile as i64, tile_y as i64 * cfg.tile as i64);
    let mut cols = 0u64;
    for sx in 0..n {
        let x0 = tx0 + sx * s;
        if !g.separated_x(x0, x0 + s - 1) {
            cols |= 1 << sx;
        }
    }
    if cols == 0 {
        return 0;
    }
    // Subtile (sx, sy): centre offset d = d00 - (sx, sy) step, half-sizes w = h = half.
    let (step, half) = ((2 * s) << g.fm, (s - 1) << g.fm);
    let [c, sn] = g.cs;
    let (dx0, dy00) = (g.m[0] - ((2 * tx0 + s - 1) << g.fm), g.m[1] - ((2 * ty0 + s - 1) << g.fm));
    let (tu, tv) = (g.h[0] + half * (c.abs() + sn.abs()), g.h[1] + half * (sn.abs() + c.abs()));
    let (du, dv) = (step * c, step * sn);
    // The columns the x test passes are one run (an interval of centres).
    let (first, last) = (cols.trailing_zeros() as i64, 63 - cols.leading_zeros() as i64);
    let mut bits = 0u64;
    for sy in 0..n {
        let y0 = ty0 + sy * s;
        if g.separated_y(y0, y0 + s - 1) {
            continue;
        }
        let dy = dy00 - sy * step;
        let dx = dx0 - first * step;
        let (mut pu, mut pv) = (dx * c + dy * sn, dy * c - dx * sn);
        let mut row = 0u64;
        for sx in first..=last {
            row |= (((pu.abs() <= tu) & (pv.abs() <= tv)) as u64) << sx;
            pu -= du;
            pv += dv;
        }
        bits |= (row & cols) << (sy * n);
    }
    bits
}

/// Whether `f` touches tile `(tile_x, tile_y)`: its bitmap is not empty (the cumulative OR of
/// the subtile tests, the valid bit of the Gaussian table entry).
pub fn touches_tile(
    f: &FeatureEntry,
    fmt: &FeatureFormat,
    tile_x: u32,
    tile_y: u32,
    cfg: &RasterConfig,
) -> bool {
    subtile_bitmap(f, fmt, tile_x, tile_y, cfg) != 0
}

/// The tiles `(x range, y range)` of a `width x height` image worth testing for `f`: those
/// whose pixel centres meet the ellipse's AABB `mean +- extent_xy`, clamped to the tile grid
/// (`ceil(width / tile)` by `ceil(height / tile)`). Conservative: every tile where
/// [`touches_tile`] can be true is inside. Empty ranges when the AABB misses the image.
pub fn candidate_tiles(
    f: &FeatureEntry,
    fmt: &FeatureFormat,
    cfg: &RasterConfig,
    width: u32,
    height: u32,
) -> (Range<u32>, Range<u32>) {
    let g = ItuGeom::new(f, fmt);
    let gshift = g.fm + 1;
    let t = cfg.tile as i64;
    let range = |axis: usize, grid: u32| -> Range<u32> {
        let grid = grid as i64;
        if g.r[axis] >= UNBOUNDED {
            return 0..grid as u32;
        }
        // First and last pixel centres inside [m - r, m + r].
        let lo = -((g.r[axis] - g.m[axis]) >> gshift);
        let hi = (g.m[axis] + g.r[axis]) >> gshift;
        let a = lo.div_euclid(t).clamp(0, grid);
        let b = (hi.div_euclid(t) + 1).clamp(0, grid);
        if a < b {
            a as u32..b as u32
        } else {
            0..0
        }
    };
    (range(0, width.div_ceil(cfg.tile)), range(1, height.div_ceil(cfg.tile)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::formats::feature::quantize;
    use crate::raster::scu::tests::projected;
    use crate::sort::DepthKeyCodec;

    fn entry(mean: [f32; 2], cov: [f32; 3]) -> (FeatureEntry, FeatureFormat) {
        let fmt = FeatureFormat { cutoff: crate::formats::Cutoff::Sigma(3.0), ..FeatureFormat::default() };
        (quantize(&projected(mean, cov, 0.5, [1.0; 3]), &fmt, &DepthKeyCodec::Fp16), fmt)
    }

    #[test]
    fn round_gaussian_inside_one_subtile() {
        // sigma 1 px at (12, 12): 3 sigma reaches 9..15, all inside subtile (1, 1) = [8, 15].
        let (e, fmt) = entry([12.0, 12.0], [1.0, 0.0, 1.0]);
        let cfg = RasterConfig::default();
        assert_eq!(subtile_bitmap(&e, &fmt, 0, 0, &cfg), 1 << 9);
        assert!(touches_tile(&e, &fmt, 0, 0, &cfg));
        assert!(!touches_tile(&e, &fmt, 1, 0, &cfg));
        assert_eq!(candidate_tiles(&e, &fmt, &cfg, 1000, 1000), (0..1, 0..1));
        // Moved to (15.5, 12): 3 sigma reaches 18.5, into subtile (2, 1) = [16, 23].
        let (e, fmt) = entry([15.5, 12.0], [1.0, 0.0, 1.0]);
        assert_eq!(subtile_bitmap(&e, &fmt, 0, 0, &cfg), (1 << 9) | (1 << 10));
    }

    #[test]
    fn diagonal_needle_is_cut_by_the_axis_tests() {
        // A needle along the diagonal (sigma 20 px along (1, 1), 0.55 px across), centred on a
        // subtile corner: the AABB covers a 7x7 block of subtiles, the octagon only the
        // diagonal band.
        let l = 400.0f32;
        let s = 0.3f32;
        let cov = [(l + s) / 2.0, (l - s) / 2.0, (l + s) / 2.0];
        let (e, fmt) = entry([32.0, 32.0], cov);
        let cfg = RasterConfig::default();
        let bits = subtile_bitmap(&e, &fmt, 0, 0, &cfg);
        for sy in 0..8i32 {
            for sx in 0..8i32 {
                let set = bits >> (sy * 8 + sx) & 1 == 1;
                let far = (sx - sy).abs() >= 2;
                assert!(!(set && far), "subtile ({sx}, {sy}) off the diagonal is set: {bits:#x}");
            }
        }
        assert!(bits >> (4 * 8 + 4) & 1 == 1 && bits >> (3 * 8 + 3) & 1 == 1);
    }
}
