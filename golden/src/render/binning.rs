//! Tile binning: every projected Gaussian is listed in each tile of its rectangle, and each
//! tile's list is sorted front to back.
//!
//! The reference sorts `(tile << 32 | depth bits)` keys with a stable radix sort over
//! duplicates emitted in Gaussian order, so within a tile Gaussians are ordered by depth with
//! ties broken by Gaussian index. Here a counting sort groups the duplicates by tile and each
//! tile's `(depth bits, index)` keys are sorted in parallel: the same order, independent of
//! thread scheduling. Depths are > 0.2, so their IEEE bit patterns order like their values.

use super::preprocess::Projected;
use rayon::prelude::*;

/// Per-tile, front-to-back lists of projected Gaussians.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct TileBins {
    /// Tile grid size `[x, y]`.
    pub grid: [u32; 2],
    /// `grid[0] * grid[1] + 1` offsets into `entries`: tile `t` (row-major) owns
    /// `entries[offsets[t]..offsets[t + 1]]`.
    pub offsets: Vec<usize>,
    /// Indices into the projected list (not scene indices), sorted by depth then index within
    /// each tile.
    pub entries: Vec<u32>,
}

impl TileBins {
    /// Number of tile-Gaussian pairs (duplicates).
    pub fn pairs(&self) -> usize {
        self.entries.len()
    }

    /// The sorted projected-list indices of tile `(tx, ty)`.
    pub fn tile(&self, tx: u32, ty: u32) -> &[u32] {
        let t = (ty * self.grid[0] + tx) as usize;
        &self.entries[self.offsets[t]..self.offsets[t + 1]]
    }
}

/// Bins `projected` (as returned by `preprocess`, whose tile rectangles must lie in `grid`)
/// into tiles and sorts each tile front to back. Panics if a rectangle exceeds `grid`.
pub fn bin(projected: &[Projected], grid: [u32; 2]) -> TileBins {
    let tiles = grid[0] as usize * grid[1] as usize;
    // Counting sort by tile.
    let mut offsets = vec![0usize; tiles + 1];
    for p in projected {
        for ty in p.tile_min[1]..p.tile_max[1] {
            let row = ty as usize * grid[0] as usize;
            for tx in p.tile_min[0]..p.tile_max[0] {
                offsets[row + tx as usize + 1] += 1;
            }
        }
    }
    for t in 0..tiles {
        offsets[t + 1] += offsets[t];
    }
    let mut keys = vec![0u64; offsets[tiles]];
    let mut cursor = offsets[..tiles].to_vec();
    for (j, p) in projected.iter().enumerate() {
        let key = (u64::from(p.depth.to_bits()) << 32) | j as u64;
        for ty in p.tile_min[1]..p.tile_max[1] {
            let row = ty as usize * grid[0] as usize;
            for tx in p.tile_min[0]..p.tile_max[0] {
                let c = &mut cursor[row + tx as usize];
                keys[*c] = key;
                *c += 1;
            }
        }
    }
    // Sort every tile's keys in parallel; the key order is (depth, index), a total order.
    let mut slices = Vec::with_capacity(tiles);
    let mut rest = keys.as_mut_slice();
    for t in 0..tiles {
        let (head, tail) = rest.split_at_mut(offsets[t + 1] - offsets[t]);
        slices.push(head);
        rest = tail;
    }
    slices.into_par_iter().for_each(|s| s.sort_unstable());
    let entries = keys.par_iter().with_min_len(1 << 14).map(|&k| k as u32).collect();
    TileBins { grid, offsets, entries }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn splat(depth: f32, min: [u32; 2], max: [u32; 2]) -> Projected {
        Projected {
            index: 0,
            mean2d: [0.0; 2],
            cov2d: [1.0, 0.0, 1.0],
            conic: [1.0, 0.0, 1.0],
            depth,
            radius: 1,
            rgb: [1.0; 3],
            opacity: 0.5,
            tile_min: min,
            tile_max: max,
        }
    }

    #[test]
    fn tiles_are_sorted_by_depth_then_index() {
        let ps = vec![
            splat(3.0, [0, 0], [2, 1]),
            splat(1.0, [1, 0], [2, 2]),
            splat(3.0, [0, 0], [1, 1]),
            splat(0.5, [0, 1], [2, 2]),
        ];
        let bins = bin(&ps, [2, 2]);
        assert_eq!(bins.pairs(), 2 + 2 + 1 + 2);
        assert_eq!(bins.tile(0, 0), &[0, 2]);
        assert_eq!(bins.tile(1, 0), &[1, 0]);
        assert_eq!(bins.tile(0, 1), &[3]);
        assert_eq!(bins.tile(1, 1), &[3, 1]);
    }
}
