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
//! previous frame's feature word. The feature table holds one 32-byte word per Gaussian id
//! (`crate::engine::memory::feature_to_bytes`), all zero (not present) when the Gaussian was
//! culled, so the word also says whether the Gaussian was visible then; the table is
//! double-buffered: frame `f` writes one buffer and the duplication unit reads the other. A
//! Gaussian is incoming in tile `t` iff it enters `t` now and did not enter `t` in the previous
//! frame (or was not visible, or the previous frame sorted `t` from scratch with drops: see
//! [`incoming`]).
//!
//! Memory per frame (the design the RTL's Preprocessing Engine implements, `neo_pre_lane`; its
//! transfers are [`crate::engine::pre::pre_transfers`]), for `N` Gaussians of which `P` are
//! visible now: every Gaussian's word written (`32 N` bytes; the feature table's writes), and on
//! a frame that reuses tables the previous word of each of the `P` read (`32 P` bytes, one
//! 32-byte read each, by id); a frame sorted from scratch reads none (`PRE_FRESH`). Storage:
//! a second feature table of `N` words. (An earlier design, kept by no model, compacted the
//! visible Gaussians' entries and kept a visibility bitmap of `N / 8` bytes per frame instead.)

use crate::formats::{FeatureEntry, FeatureFormat};
use crate::raster::{candidate_tiles, touches_tile, RasterConfig};

/// What the duplication unit reads of a Gaussian's previous frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TouchRecord<'a> {
    /// The previous frame's feature entry; `None` when the Gaussian was culled then (its
    /// previous feature word is zero: not present).
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
