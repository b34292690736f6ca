//! Dynamic Partial Sorting (paper Section 4.3, Algorithm 1): re-sort a reused table chunk by
//! chunk, each chunk read from DRAM, sorted on chip (BSU + in-chunk merges, exactly as
//! [`Sorter::sort_chunk`] in the conventional sort) and written back once, with no merge across
//! chunks.
//!
//! # Interleaved boundaries (parity)
//! - [`Parity::Even`]: chunks `[0, C), [C, 2C), ...`;
//! - [`Parity::Odd`]: chunks `[0, C/2), [C/2, 3C/2), [3C/2, 5C/2), ...`.
//!
//! The last chunk is cut at the table length. Pass `p` of frame `f` uses parity `(f + p) % 2`
//! (`Even` when 0), so successive passes and successive frames alternate.
//!
//! **Parity convention.** We follow the issue: boundaries at multiples of `C` on EVEN frames and
//! at `C/2 + kC` on ODD frames. Algorithm 1 in the paper states the opposite (its odd frames,
//! `I mod 2 = 1`, use `range = (0, C)`); the two conventions differ only by which frame number
//! starts the alternation.
//!
//! # Guarantees (proved in the docs of [`dps`], checked by property tests)
//! - A table already in THE ORDER is left unchanged by any pass.
//! - If every entry is at most `C/2` positions from its place in THE ORDER, two consecutive
//!   passes (one of each parity, either first) restore THE ORDER exactly. The bound is tight:
//!   a displacement of `C/2 + 1` can survive two passes.
//! - Any table is in THE ORDER after `ceil(L / (C/2)) + 1` consecutive alternating passes
//!   (block odd-even transposition sort on blocks of `C/2`).
//! - With a fixed parity an entry can never cross a chunk boundary, so it may never converge.

use std::ops::Range;

use super::entry::SortEntry;
use super::full_sort::{ChunkWork, SortConfig, Sorter};

/// Which chunk boundaries a DPS pass uses (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Parity {
    /// Boundaries at multiples of `C`.
    Even,
    /// Boundaries at `C/2 + kC` (the first chunk is `[0, C/2)`).
    Odd,
}

impl Parity {
    /// Parity of pass `pass` of frame `frame`: `(frame + pass) % 2`.
    pub fn of(frame: u64, pass: usize) -> Parity {
        if (frame ^ pass as u64) & 1 == 0 {
            Parity::Even
        } else {
            Parity::Odd
        }
    }

    /// The chunks of a table of `len` entries with chunk size `chunk`, in order.
    pub fn chunks(self, len: usize, chunk: usize) -> impl Iterator<Item = Range<usize>> {
        let first = match self {
            Parity::Even => chunk,
            Parity::Odd => chunk / 2,
        };
        let mut start = 0;
        let mut end = first.min(len);
        std::iter::from_fn(move || {
            if start >= len {
                return None;
            }
            let r = start..end;
            start = end;
            end = (end + chunk).min(len);
            Some(r)
        })
    }
}

/// Work counters of DPS, for the cycle model.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct DpsWork {
    /// Passes performed.
    pub passes: usize,
    /// Chunk sorts (BSU vectors, in-chunk merges) summed over passes; `chunk.chunks` is the
    /// number of chunks touched and `chunk.entries` the entries read (= written) from DRAM.
    pub chunk: ChunkWork,
}

impl DpsWork {
    /// Entries read from DRAM (each pass reads every entry once).
    pub fn dram_entries_read(&self) -> usize {
        self.chunk.entries
    }

    /// Entries written to DRAM (each pass writes every entry once).
    pub fn dram_entries_written(&self) -> usize {
        self.chunk.entries
    }
}

impl Sorter {
    /// One DPS pass over `table` in place with the given boundary parity.
    pub fn dps_pass(&mut self, table: &mut [SortEntry], parity: Parity) -> ChunkWork {
        let mut work = ChunkWork::default();
        let len = table.len();
        for r in parity.chunks(len, self.config().chunk()) {
            self.sort_chunk(&mut table[r], &mut work);
        }
        work
    }

    /// DPS of frame `frame`: `passes` passes in place, pass `p` with parity `(frame + p) % 2`.
    pub fn dps(&mut self, table: &mut [SortEntry], frame: u64, passes: usize) -> DpsWork {
        let mut work = DpsWork { passes, ..DpsWork::default() };
        for p in 0..passes {
            let w = self.dps_pass(table, Parity::of(frame, p));
            work.chunk.add(&w);
        }
        work
    }
}

/// DPS of frame `frame` on `table` in place (allocating convenience over [`Sorter::dps`]).
///
/// Why two alternating passes fix any displacement of at most `h = C/2` (0-1 principle: chunk
/// sorts are comparator networks, and an input is sorted iff all its 0/1 threshold images are):
/// in a threshold image with `z` zeros, ones lie at `>= z - h` and zeros at `<= z + h - 1`, so
/// only the window `W = [z - h, z + h - 1]` (`C` positions) can be out of place. One parity's
/// boundaries are `C` apart, so at most one boundary `b` splits `W`. If none does, one chunk
/// holds `W` and the first pass sorts it. Otherwise the chunks `A` (ending at `b`) and `B`
/// (starting at `b`) cover `W` and are sorted, leaving `1^oA` just before `b` and `0^zB` just
/// after it; with `z = b - oA + zB`, `oA <= b - z + h` (A's ones came from `[z - h, b)`) and
/// `zB <= z + h - b` (B's zeros from `[b, z + h - 1]`), both `oA <= h` and `zB <= h`. The other
/// parity has the chunk `[b - h, b + h)`, which holds all of that, and the second pass sorts it.
pub fn dps(table: &mut [SortEntry], frame: u64, passes: usize, cfg: &SortConfig) -> DpsWork {
    Sorter::new(cfg.clone()).dps(table, frame, passes)
}

/// One DPS pass with the given parity (allocating convenience over [`Sorter::dps_pass`]).
pub fn dps_pass(table: &mut [SortEntry], parity: Parity, cfg: &SortConfig) -> ChunkWork {
    Sorter::new(cfg.clone()).dps_pass(table, parity)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parity_alternates_over_frames_and_passes() {
        assert_eq!(Parity::of(0, 0), Parity::Even);
        assert_eq!(Parity::of(1, 0), Parity::Odd);
        assert_eq!(Parity::of(1, 1), Parity::Even);
        assert_eq!(Parity::of(4, 3), Parity::Odd);
        assert_eq!(Parity::of(u64::MAX, usize::MAX), Parity::Even);
    }

    #[test]
    fn chunk_boundaries_follow_parity() {
        let even: Vec<_> = Parity::Even.chunks(600, 256).collect();
        assert_eq!(even, vec![0..256, 256..512, 512..600]);
        let odd: Vec<_> = Parity::Odd.chunks(600, 256).collect();
        assert_eq!(odd, vec![0..128, 128..384, 384..600]);
        let odd: Vec<_> = Parity::Odd.chunks(640, 256).collect();
        assert_eq!(odd, vec![0..128, 128..384, 384..640]);
        assert_eq!(Parity::Odd.chunks(100, 256).collect::<Vec<_>>(), vec![0..100]);
        assert_eq!(Parity::Even.chunks(0, 256).count(), 0);
        assert_eq!(Parity::Odd.chunks(128, 256).collect::<Vec<_>>(), vec![0..128]);
    }

    #[test]
    fn pass_sorts_exactly_its_chunks() {
        let cfg = SortConfig::new(crate::sort::SortFormat::ARTIFACT, 32, crate::sort::Network::bitonic(16))
            .unwrap();
        // A fully reversed table: after one odd pass each chunk is sorted, nothing crosses.
        let mut t: Vec<SortEntry> = (0..80u32).rev().map(|k| SortEntry::new(k, k)).collect();
        let w = dps_pass(&mut t, Parity::Odd, &cfg);
        for r in Parity::Odd.chunks(80, 32) {
            let mut expect: Vec<u32> = (80 - r.end as u32..80 - r.start as u32).collect();
            expect.sort_unstable();
            let got: Vec<u32> = t[r.clone()].iter().map(|e| e.key).collect();
            assert_eq!(got, expect, "chunk {r:?}");
        }
        assert_eq!(w.chunks, 3);
        assert_eq!(w.entries, 80);
    }
}
