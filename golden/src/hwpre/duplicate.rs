//! The duplication unit's algorithm: which tiles a Gaussian enters, and in which of them it is
//! *incoming* (paper Section 5.2: not in the tile's previous table), from per-Gaussian state
//! the hardware can keep.
//!
//! # Tiles
//! A Gaussian enters tile `t` iff the ITU test finds its cutoff octagon touching a subtile of
//! `t` ([`crate::raster::touches_tile`], the same test the raster's ITUs run, so the tables
//! the sorting engine builds hold exactly the Gaussians the raster will find there). Only the
//! candidate tiles of [`crate::raster::candidate_tiles`] (the octagon's AABB) are tested, one
//! tile per cycle, in row-major order.
//!
//! # Incoming detection
//! The tile's previous table holds `V`: the Gaussians the previous frame's raster found
//! touching the tile (its valid write-back), which is the set of Gaussians that entered the tile
//! in the previous frame, unless the tile dropped entries for capacity. So the hardware keeps,
//! per Gaussian, what it needs to repeat the previous frame's test ([`TouchRecord`]): the
//! previous frame's feature entry (the feature table is double-buffered: frame `f` writes one
//! buffer and the duplication unit reads the other) and one bit saying whether the Gaussian was
//! visible then (a bitmap of `N` bits, also double-buffered). A Gaussian is incoming in tile `t`
//! iff it enters `t` now and did not enter `t` in the previous frame (or was not visible, or
//! the previous frame sorted `t` from scratch with drops: see [`incoming`]).
//!
//! Memory per frame, for `N` Gaussians of which `P` were visible in the previous frame:
//! `P x` [`crate::formats::FeatureFormat::bytes_per_entry`] bytes read (the previous entries,
//! by id) plus `2 N / 8` bytes of visibility bitmap (read and written, sequentially); storage
//! is a second feature table and two bitmaps.

use crate::formats::{FeatureEntry, FeatureFormat};
use crate::raster::{candidate_tiles, touches_tile, RasterConfig};

/// What the duplication unit reads of a Gaussian's previous frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TouchRecord<'a> {
    /// The previous frame's feature entry; `None` when the Gaussian was culled then (its
    /// visibility bit is 0).
    pub entry: Option<&'a FeatureEntry>,
}

/// One tile a Gaussian enters.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TileHit {
    /// Tile column.
    pub tile_x: u32,
    /// Tile row.
    pub tile_y: u32,
    /// Not in the tile's previous table: goes to the tile's incoming list.
    pub incoming: bool,
}

/// The duplication of one visible Gaussian with feature entry `now` for a `width x height`
/// image: every tile it enters, row-major, each with its incoming flag. `fresh(x, y)` is true
/// for tiles whose previous table is not reused (sorted from scratch this frame, or emptied
/// by an overflow), where every Gaussian is incoming.
pub fn incoming(
    now: &FeatureEntry,
    prev: TouchRecord,
    fmt: &FeatureFormat,
    cfg: &RasterConfig,
    (width, height): (u32, u32),
    fresh: impl Fn(u32, u32) -> bool,
) -> Vec<TileHit> {
    let (xs, ys) = candidate_tiles(now, fmt, cfg, width, height);
    let mut hits = Vec::new();
    for tile_y in ys {
        for tile_x in xs.clone() {
            if !touches_tile(now, fmt, tile_x, tile_y, cfg) {
                continue;
            }
            let before = prev.entry.is_some_and(|e| touches_tile(e, fmt, tile_x, tile_y, cfg));
            hits.push(TileHit { tile_x, tile_y, incoming: !before || fresh(tile_x, tile_y) });
        }
    }
    hits
}

/// Candidate tiles the unit walks for `now` (its cycles at one tile per cycle).
pub fn candidate_count(now: &FeatureEntry, fmt: &FeatureFormat, cfg: &RasterConfig, size: (u32, u32)) -> u32 {
    let (xs, ys) = candidate_tiles(now, fmt, cfg, size.0, size.1);
    xs.len() as u32 * ys.len() as u32
}
