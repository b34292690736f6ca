//! Binning: the current list of every tile, from the feature table and the ITU.
//!
//! A Gaussian belongs to tile `t` when [`touches_tile`](crate::raster::touches_tile) (its subtile bitmap in `t` is not
//! empty); only the tiles of [`candidate_tiles`] are tested. Each tile's list holds `{key =
//! depth key of the feature entry, id = Gaussian index in the scene, valid = 1}` in ascending id
//! order (the feature table is in Gaussian order). Each entry's subtile bitmap in its tile,
//! which the test computes, is kept beside it ([`Binning::tile_bitmaps`]).

use rayon::prelude::*;

use crate::formats::{FeatureEntry, FeatureFormat};
use crate::raster::{candidate_tiles, subtile_bitmap, RasterConfig};
use crate::sort::SortEntry;

/// Features per parallel work item.
const CHUNK: usize = 2048;

/// Per-tile current lists in one flat buffer (CSR), reused from frame to frame.
#[derive(Clone, Debug, Default)]
pub struct Binning {
    /// Tile grid `[x, y]`.
    pub grid: [u32; 2],
    /// `tiles + 1` offsets: tile `t` (row-major) owns `entries[offsets[t]..offsets[t + 1]]`.
    pub offsets: Vec<usize>,
    /// The lists.
    pub entries: Vec<SortEntry>,
    /// The subtile bitmap of each entry of `entries` in its tile (never 0).
    pub bitmaps: Vec<u64>,
    /// Candidate tiles tested (ITU work of the binning).
    pub tiles_tested: u64,
    pairs: Vec<Vec<(u32, u32, u64)>>,
}

impl Binning {
    /// The current list of tile `t` (row-major index).
    pub fn tile(&self, t: usize) -> &[SortEntry] {
        &self.entries[self.offsets[t]..self.offsets[t + 1]]
    }

    /// The subtile bitmaps of tile `t`'s current list, entry by entry.
    pub fn tile_bitmaps(&self, t: usize) -> &[u64] {
        &self.bitmaps[self.offsets[t]..self.offsets[t + 1]]
    }

    /// Number of tiles.
    pub fn tiles(&self) -> usize {
        self.offsets.len().saturating_sub(1)
    }

    /// Bins `features` (`ids[i]` is the Gaussian index of `features[i]`) for a `width x height`
    /// image.
    pub fn run(
        &mut self,
        features: &[FeatureEntry],
        ids: &[u32],
        fmt: &FeatureFormat,
        cfg: &RasterConfig,
        width: u32,
        height: u32,
    ) {
        assert_eq!(features.len(), ids.len(), "one id per feature entry");
        self.grid = [width.div_ceil(cfg.tile), height.div_ceil(cfg.tile)];
        let gx = self.grid[0];
        let tiles = gx as usize * self.grid[1] as usize;
        let nchunks = features.len().div_ceil(CHUNK);
        self.pairs.resize_with(nchunks, Vec::new);
        self.pairs.truncate(nchunks);
        let tested: u64 = features
            .par_chunks(CHUNK)
            .zip(self.pairs.par_iter_mut())
            .enumerate()
            .map(|(c, (fs, out))| {
                out.clear();
                let mut tested = 0u64;
                for (j, f) in fs.iter().enumerate() {
                    let (xr, yr) = candidate_tiles(f, fmt, cfg, width, height);
                    for ty in yr {
                        for tx in xr.clone() {
                            tested += 1;
                            // `touches_tile`: the bitmap is not empty.
                            let b = subtile_bitmap(f, fmt, tx, ty, cfg);
                            if b != 0 {
                                out.push((ty * gx + tx, (c * CHUNK + j) as u32, b));
                            }
                        }
                    }
                }
                tested
            })
            .sum();
        self.tiles_tested = tested;
        self.offsets.clear();
        self.offsets.resize(tiles + 1, 0);
        for list in &self.pairs {
            for &(t, _, _) in list {
                self.offsets[t as usize + 1] += 1;
            }
        }
        for t in 0..tiles {
            self.offsets[t + 1] += self.offsets[t];
        }
        self.entries.clear();
        self.entries.resize(self.offsets[tiles], SortEntry::default());
        self.bitmaps.clear();
        self.bitmaps.resize(self.offsets[tiles], 0);
        let mut cursor = self.offsets[..tiles].to_vec();
        for list in &self.pairs {
            for &(t, i, b) in list {
                let c = &mut cursor[t as usize];
                self.entries[*c] = SortEntry::new(features[i as usize].depth_key, ids[i as usize]);
                self.bitmaps[*c] = b;
                *c += 1;
            }
        }
    }
}
