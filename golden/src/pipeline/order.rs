//! Order quality of a tile's table against the exact order: per-entry displacement and the
//! inversion count.
//!
//! # Definitions
//! Both are taken over the **common set**: the Gaussians present in both the table under test
//! and the exact table (the current frame's intersecting set, fully sorted by the current
//! `(key, id)`). Entries only in the table under test (stale ones that left the tile, whose
//! valid bit the raster will clear) and entries only in the exact table (dropped by a capacity
//! cut) are not compared.
//!
//! - The **rank** of an entry in an order is its position among the common entries of that
//!   order (0-based). The **displacement** of a common entry is `|rank in table - rank in
//!   exact|`; it is 0 for every entry exactly when the two orders agree on the common set.
//! - An **inversion** is a pair of common entries whose relative order differs between the
//!   table and the exact order. It is counted in `O(n log n)` with a merge sort
//!   ([`count_inversions`]).

use crate::sort::SortEntry;

/// Order comparison of one tile.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TileOrder {
    /// Entries in the common set.
    pub compared: usize,
    /// Pairs of common entries out of order.
    pub inversions: u64,
    /// Largest displacement.
    pub displacement_max: u32,
    /// Sum of the displacements.
    pub displacement_sum: u64,
}

/// Reusable buffers of [`compare_orders`] (one per worker thread). Indexed by Gaussian id, so
/// they grow to the largest id seen; a stamp avoids clearing them between tiles.
#[derive(Clone, Debug, Default)]
pub struct OrderScratch {
    stamp: Vec<u32>,
    pos: Vec<u32>,
    current: u32,
    in_common: Vec<u32>,
    seq: Vec<u32>,
    tmp: Vec<u32>,
}

impl OrderScratch {
    /// Starts a new comparison: every id is unmarked afterwards.
    fn next_stamp(&mut self, max_id: usize) {
        if self.stamp.len() <= max_id {
            self.stamp.resize(max_id + 1, 0);
            self.pos.resize(max_id + 1, 0);
        }
        self.current = self.current.wrapping_add(1);
        if self.current == 0 {
            self.stamp.fill(0);
            self.current = 1;
        }
    }
}

/// Compares `table` against `exact` (see the module docs) and appends the displacement of every
/// common entry, in table order, to `displacements`. Ids must be unique within each slice.
pub fn compare_orders(
    table: &[SortEntry],
    exact: &[SortEntry],
    scratch: &mut OrderScratch,
    displacements: &mut Vec<u32>,
) -> TileOrder {
    let max_id = table.iter().chain(exact).map(|e| e.id as usize).max().unwrap_or(0);
    scratch.next_stamp(max_id);
    let s = scratch.current;
    for (p, e) in exact.iter().enumerate() {
        scratch.stamp[e.id as usize] = s;
        scratch.pos[e.id as usize] = p as u32;
    }
    // Exact positions of the common entries, in table order.
    scratch.seq.clear();
    scratch.in_common.clear();
    scratch.in_common.resize(exact.len() + 1, 0);
    for e in table {
        if scratch.stamp[e.id as usize] == s {
            let p = scratch.pos[e.id as usize];
            scratch.seq.push(p);
            scratch.in_common[p as usize + 1] = 1;
        }
    }
    // Prefix count: the exact rank of exact position p is in_common[p] after this.
    for i in 1..scratch.in_common.len() {
        scratch.in_common[i] += scratch.in_common[i - 1];
    }
    let mut out = TileOrder { compared: scratch.seq.len(), ..TileOrder::default() };
    for (rank, p) in scratch.seq.iter_mut().enumerate() {
        let exact_rank = scratch.in_common[*p as usize];
        let d = (rank as u32).abs_diff(exact_rank);
        out.displacement_max = out.displacement_max.max(d);
        out.displacement_sum += d as u64;
        displacements.push(d);
        *p = exact_rank;
    }
    out.inversions = count_inversions(&mut scratch.seq, &mut scratch.tmp);
    out
}

/// Number of pairs `i < j` with `seq[i] > seq[j]`, by a bottom-up merge sort (`seq` ends up
/// sorted; `tmp` is scratch). `O(n log n)`.
pub fn count_inversions(seq: &mut [u32], tmp: &mut Vec<u32>) -> u64 {
    let n = seq.len();
    tmp.clear();
    tmp.resize(n, 0);
    let mut inversions = 0u64;
    let mut width = 1;
    let (mut src, mut dst): (&mut [u32], &mut [u32]) = (seq, tmp.as_mut_slice());
    let mut in_tmp = false;
    while width < n {
        let mut start = 0;
        while start < n {
            let mid = (start + width).min(n);
            let end = (start + 2 * width).min(n);
            let (mut i, mut j, mut k) = (start, mid, start);
            while i < mid && j < end {
                if src[j] < src[i] {
                    // src[j] jumps over every remaining element of the left run.
                    inversions += (mid - i) as u64;
                    dst[k] = src[j];
                    j += 1;
                } else {
                    dst[k] = src[i];
                    i += 1;
                }
                k += 1;
            }
            dst[k..k + (mid - i)].copy_from_slice(&src[i..mid]);
            k += mid - i;
            dst[k..k + (end - j)].copy_from_slice(&src[j..end]);
            start = end;
        }
        std::mem::swap(&mut src, &mut dst);
        in_tmp = !in_tmp;
        width *= 2;
    }
    if in_tmp {
        dst.copy_from_slice(src);
    }
    inversions
}

/// The `q`-quantile (nearest rank, `q` in `[0, 1]`) of `v`, reordering `v`; 0 when empty.
pub fn percentile_u32(v: &mut [u32], q: f64) -> u32 {
    if v.is_empty() {
        return 0;
    }
    let k = ((v.len() - 1) as f64 * q.clamp(0.0, 1.0)).round() as usize;
    *v.select_nth_unstable(k).1
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn naive_inversions(v: &[u32]) -> u64 {
        let mut n = 0;
        for i in 0..v.len() {
            for j in i + 1..v.len() {
                n += (v[i] > v[j]) as u64;
            }
        }
        n
    }

    #[test]
    fn inversions_of_small_cases() {
        let mut tmp = Vec::new();
        assert_eq!(count_inversions(&mut [], &mut tmp), 0);
        assert_eq!(count_inversions(&mut [5], &mut tmp), 0);
        let mut v = [3, 2, 1, 0];
        assert_eq!(count_inversions(&mut v, &mut tmp), 6);
        assert_eq!(v, [0, 1, 2, 3]);
        let mut v = [0, 2, 1, 3, 5, 4];
        assert_eq!(count_inversions(&mut v, &mut tmp), 2);
    }

    #[test]
    fn displacement_uses_ranks_in_the_common_set() {
        let e = |key, id| SortEntry::new(key, id);
        let exact = [e(1, 10), e(2, 11), e(3, 12), e(4, 13)];
        // Table: 99 is stale (not in exact), 13 moved to the front, 11 missing (capacity).
        let table = [e(4, 13), e(0, 99), e(1, 10), e(3, 12)];
        let mut d = Vec::new();
        let o = compare_orders(&table, &exact, &mut OrderScratch::default(), &mut d);
        // Common: 13, 10, 12 with exact ranks 2, 0, 1.
        assert_eq!(o.compared, 3);
        assert_eq!(d, vec![2, 1, 1]);
        assert_eq!(o.inversions, 2);
        assert_eq!(o.displacement_max, 2);
        assert_eq!(o.displacement_sum, 4);
    }

    proptest! {
        #[test]
        fn inversions_match_the_quadratic_count(v in proptest::collection::vec(0u32..50, 0..200)) {
            let expect = naive_inversions(&v);
            let mut w = v.clone();
            prop_assert_eq!(count_inversions(&mut w, &mut Vec::new()), expect);
            let mut sorted = v.clone();
            sorted.sort_unstable();
            prop_assert_eq!(w, sorted);
        }

        #[test]
        fn identical_orders_compare_clean(ids in proptest::collection::btree_set(0u32..10_000, 0..300), seed in any::<u64>()) {
            let mut t: Vec<SortEntry> = ids.iter().map(|&id| SortEntry::new((id as u64).wrapping_mul(seed) as u32 % 97, id)).collect();
            t.sort_unstable_by_key(SortEntry::order_key);
            let mut scratch = OrderScratch::default();
            let mut d = Vec::new();
            let o = compare_orders(&t, &t, &mut scratch, &mut d);
            prop_assert_eq!(o.compared, t.len());
            prop_assert_eq!(o.inversions, 0);
            prop_assert!(d.iter().all(|&x| x == 0));
            // Reversed: every pair inverted.
            let r: Vec<SortEntry> = t.iter().rev().copied().collect();
            let o = compare_orders(&r, &t, &mut scratch, &mut d);
            let n = t.len() as u64;
            prop_assert_eq!(o.inversions, n * n.saturating_sub(1) / 2);
        }
    }

    #[test]
    fn percentile_is_nearest_rank() {
        let mut v: Vec<u32> = (0..101).rev().collect();
        assert_eq!(percentile_u32(&mut v, 0.9), 90);
        assert_eq!(percentile_u32(&mut v, 1.0), 100);
        assert_eq!(percentile_u32(&mut [], 0.5), 0);
    }
}
