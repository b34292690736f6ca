//! GSCore-style hierarchical sorting (Lee et al., ASPLOS 2024), modelled for its work counters.
//!
//! GSCore sorts each tile's list from scratch every frame in two levels: a coarse,
//! approximate sort that scatters the entries into depth bins whose key ranges do not overlap,
//! then a precise on-chip sort of each bin with the bitonic sorting unit. Because bins partition
//! the key axis, concatenating the sorted bins gives exactly THE ORDER `(key, id)`; the value of
//! this model is the work it counts, not its order.
//!
//! # The model (our reading of GSCore; its parameters are ours)
//! 1. **Approximate pass.** The tile's `n` entries are streamed from DRAM once (`n` read) and
//!    scattered into `B = ceil(n / (C / 2))` bins of equal key width over `[min key, max key]`
//!    (the duplication stage can track a tile's key range for free), written back to DRAM
//!    bin by bin (`n` written). Bins are sized for half a chunk on average so that most fit.
//! 2. **Fine pass.** Each bin of at most `C` entries is loaded into the on-chip buffer, sorted
//!    there exactly as a chunk of the conventional sort ([`Sorter::sort_chunk`]: BSU vectors,
//!    in-chunk MSU merges) and written back (`len` read, `len` written).
//! 3. A bin of more than `C` entries is binned again (another approximate pass over just that
//!    bin, with its own key range), up to [`MAX_LEVELS`] levels. A bin that cannot be split
//!    (all its keys equal) or that is still too large at the last level is sorted with the
//!    conventional sort ([`Sorter::full_sort`]: chunks plus global merge passes), counted as a
//!    fallback.

use crate::sort::{ChunkWork, SortEntry, Sorter};

/// Deepest approximate-pass level before a large bin falls back to the conventional sort.
pub const MAX_LEVELS: usize = 4;

/// Work counters of one hierarchical sort.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct HierWork {
    /// Entries sorted.
    pub entries: usize,
    /// Approximate (binning) passes, counted once per bin list scattered (level 0 counts 1).
    pub approx_passes: usize,
    /// Entries streamed through approximate passes (each read once and written once).
    pub approx_entries: usize,
    /// Bins created, over all levels.
    pub bins: usize,
    /// Bins larger than a chunk that had to be split again or fall back.
    pub bins_oversized: usize,
    /// Largest level reached (0 when one pass sufficed).
    pub max_level: usize,
    /// Bins sorted with the conventional sort because they could not be split.
    pub fallback_sorts: usize,
    /// Entries sorted by the fallback.
    pub fallback_entries: usize,
    /// DRAM entries read by fallback global merge passes.
    pub fallback_global_entries: usize,
    /// On-chip sorts of bins (BSU vectors and in-chunk merges), including fallback chunks.
    pub chunk: ChunkWork,
}

impl HierWork {
    /// Entries read from DRAM: approximate passes, bin loads, fallback merge passes.
    pub fn dram_entries_read(&self) -> usize {
        self.approx_entries + self.chunk.entries + self.fallback_global_entries
    }

    /// Entries written to DRAM (equal to those read).
    pub fn dram_entries_written(&self) -> usize {
        self.dram_entries_read()
    }
}

/// Hierarchical sort of `input` into `out` (cleared first) with `sorter`'s chunk size and BSU.
/// `bins` is scratch. The result is THE ORDER.
pub fn hierarchical_sort(
    input: &[SortEntry],
    out: &mut Vec<SortEntry>,
    sorter: &mut Sorter,
    bins: &mut Vec<Vec<SortEntry>>,
) -> HierWork {
    let mut work = HierWork { entries: input.len(), ..HierWork::default() };
    out.clear();
    out.reserve(input.len());
    if input.is_empty() {
        return work;
    }
    let chunk = sorter.config().chunk();
    if input.len() <= chunk {
        // One bin: no approximate pass needed.
        let start = out.len();
        out.extend_from_slice(input);
        sorter.sort_chunk(&mut out[start..], &mut work.chunk);
        return work;
    }
    sort_level(input, 0, out, sorter, bins, &mut work);
    work
}

fn sort_level(
    input: &[SortEntry],
    level: usize,
    out: &mut Vec<SortEntry>,
    sorter: &mut Sorter,
    pool: &mut Vec<Vec<SortEntry>>,
    work: &mut HierWork,
) {
    let chunk = sorter.config().chunk();
    let lo = input.iter().map(|e| e.key).min().unwrap_or(0);
    let hi = input.iter().map(|e| e.key).max().unwrap_or(0);
    if lo == hi || level >= MAX_LEVELS {
        work.fallback_sorts += 1;
        work.fallback_entries += input.len();
        let mut tmp = take_bin(pool);
        let w = sorter.full_sort(input, &mut tmp);
        work.chunk.add(&w.chunk);
        work.fallback_global_entries += w.global_passes.iter().map(|p| p.entries()).sum::<usize>();
        out.extend_from_slice(&tmp);
        give_bin(pool, tmp);
        return;
    }
    work.approx_passes += 1;
    work.approx_entries += input.len();
    work.max_level = work.max_level.max(level);
    let nbins = input.len().div_ceil((chunk / 2).max(1)).max(2);
    let width = (hi - lo) as u64 + 1;
    let mut bins: Vec<Vec<SortEntry>> = (0..nbins).map(|_| take_bin(pool)).collect();
    for e in input {
        let b = ((e.key - lo) as u64 * nbins as u64 / width) as usize;
        bins[b].push(*e);
    }
    work.bins += nbins;
    for mut bin in bins {
        if bin.len() <= chunk {
            let start = out.len();
            out.extend_from_slice(&bin);
            sorter.sort_chunk(&mut out[start..], &mut work.chunk);
        } else {
            work.bins_oversized += 1;
            let sub = std::mem::take(&mut bin);
            sort_level(&sub, level + 1, out, sorter, pool, work);
            bin = sub;
        }
        give_bin(pool, bin);
    }
}

fn take_bin(pool: &mut Vec<Vec<SortEntry>>) -> Vec<SortEntry> {
    let mut v = pool.pop().unwrap_or_default();
    v.clear();
    v
}

fn give_bin(pool: &mut Vec<Vec<SortEntry>>, v: Vec<SortEntry>) {
    if pool.len() < 4096 {
        pool.push(v);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sort::SortConfig;
    use proptest::prelude::*;

    fn sorted(v: &[SortEntry]) -> Vec<SortEntry> {
        let mut s = v.to_vec();
        s.sort_unstable_by_key(SortEntry::order_key);
        s
    }

    #[test]
    fn uniform_keys_take_one_approximate_pass() {
        let input: Vec<SortEntry> = (0..4096u32).map(|i| SortEntry::new((i * 7919) % 4096, i)).collect();
        let mut sorter = Sorter::new(SortConfig::artifact());
        let mut out = Vec::new();
        let w = hierarchical_sort(&input, &mut out, &mut sorter, &mut Vec::new());
        assert_eq!(out, sorted(&input));
        assert_eq!(w.approx_passes, 1);
        assert_eq!(w.bins, 32);
        assert_eq!(w.bins_oversized, 0);
        assert_eq!(w.fallback_sorts, 0);
        // One approximate pass plus one bin pass: 2n read.
        assert_eq!(w.dram_entries_read(), 2 * 4096);
    }

    #[test]
    fn equal_keys_fall_back_to_the_conventional_sort() {
        let input: Vec<SortEntry> = (0..1000u32).rev().map(|i| SortEntry::new(5, i)).collect();
        let mut sorter = Sorter::new(SortConfig::artifact());
        let mut out = Vec::new();
        let w = hierarchical_sort(&input, &mut out, &mut sorter, &mut Vec::new());
        assert_eq!(out, sorted(&input));
        assert_eq!(w.fallback_sorts, 1);
        assert_eq!(w.approx_passes, 0);
        assert!(w.fallback_global_entries > 0);
    }

    proptest! {
        #[test]
        fn order_is_exact(keys in proptest::collection::vec(0u32..3000, 0..3000), skew in 0u32..4) {
            let input: Vec<SortEntry> = keys.iter().enumerate()
                .map(|(i, &k)| SortEntry::new(if skew == 0 { k } else { k.pow(skew.min(2)) % 60000 }, i as u32))
                .collect();
            let mut sorter = Sorter::new(SortConfig::artifact());
            let mut out = Vec::new();
            let w = hierarchical_sort(&input, &mut out, &mut sorter, &mut Vec::new());
            prop_assert_eq!(&out, &sorted(&input));
            prop_assert_eq!(w.entries, input.len());
            prop_assert!(w.dram_entries_read() >= input.len());
        }
    }
}
