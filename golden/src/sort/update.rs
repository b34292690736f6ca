//! The per-tile, per-frame reuse-and-update step (paper Section 4.2, steps 1-3, and the Sorting
//! Engine's flow in Section 5.3):
//!
//! 1. **Reordering**: DPS of the reused table (its entries carry the depth keys written back
//!    during the previous frame's rasterization and the valid bits set there);
//! 2. **Insertion**: conventional sort of the incoming entries (newly visible Gaussians with
//!    current keys, unsorted);
//! 3. **Deletion**: `merge2(dps_table, incoming_sorted, drop_invalid = true)`, which inserts the
//!    incoming entries and removes every entry whose valid bit is 0, from either input;
//! 4. **Capacity**: when the merged table is longer than the tile's capacity, keep the first
//!    `capacity` entries in THE ORDER (the nearest) and report how many were dropped.
//!
//! Frame 0 and frames after a cut use [`full_frame_sort`]: a conventional sort of the tile's
//! entries, then the same capacity rule. That path has no MSU+ drop stage, so it keeps entries
//! whatever their valid bit (freshly binned entries are all valid).
//!
//! Nothing here deduplicates ids: an incoming id already in the table appears twice (the tile
//! binning must not produce that). The result is always sorted (given sorted merge inputs) and a
//! sub-multiset of the inputs; it is never corrupted by overflow.

use super::dps::DpsWork;
use super::entry::SortEntry;
use super::full_sort::{SortConfig, SortWork, Sorter};
use super::msu::{merge2_into, MergeStats};

/// Parameters of the update step.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct UpdateConfig {
    /// Sorting Core parameters (format, chunk size, BSU network).
    pub sort: SortConfig,
    /// Maximum entries a tile's table may hold.
    pub capacity: usize,
    /// DPS passes per frame (the paper uses one).
    pub dps_passes: usize,
}

impl UpdateConfig {
    /// One DPS pass per frame, as in the paper.
    pub fn new(sort: SortConfig, capacity: usize) -> Self {
        UpdateConfig { sort, capacity, dps_passes: 1 }
    }
}

/// Work counters of one tile update, for the cycle model.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct UpdateWork {
    /// DPS of the reused table (zero for a full-frame sort).
    pub dps: DpsWork,
    /// Conventional sort of the incoming entries (of all entries for a full-frame sort).
    pub incoming_sort: SortWork,
    /// The MSU+ merge: `in_a` table entries, `in_b` incoming entries, `out` emitted before the
    /// capacity cut (zero for a full-frame sort).
    pub merge: MergeStats,
    /// Entries removed for their valid bit (= `merge.dropped_invalid`).
    pub dropped_invalid: usize,
    /// Entries beyond the capacity, removed from the far end.
    pub dropped_capacity: usize,
    /// Entries in the resulting table (written to DRAM).
    pub table_len: usize,
}

/// The resulting table and the work it took.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct TileUpdate {
    /// The tile's table for this frame, in THE ORDER.
    pub table: Vec<SortEntry>,
    /// Work counters.
    pub work: UpdateWork,
}

/// The update step with reusable buffers (one per worker thread; tiles are independent).
#[derive(Clone, Debug)]
pub struct TileSorter {
    cfg: UpdateConfig,
    sorter: Sorter,
    /// A Sorting Core with a wider chunk for [`TileSorter::update_wide`] (`None`: not built).
    wide: Option<Sorter>,
    incoming: Vec<SortEntry>,
    merged: Vec<SortEntry>,
}

impl TileSorter {
    /// A tile sorter for `cfg`.
    pub fn new(cfg: UpdateConfig) -> Self {
        let sorter = Sorter::new(cfg.sort.clone());
        TileSorter { cfg, sorter, wide: None, incoming: Vec::new(), merged: Vec::new() }
    }

    /// The same sorter with a second chunk size `wide_chunk` for DPS ([`TileSorter::update_wide`]).
    /// Fails (and keeps the sorter without a wide chunk) when `wide_chunk` is not a valid chunk.
    pub fn set_wide_chunk(&mut self, wide_chunk: usize) -> Result<(), super::SortParamError> {
        let c = &self.cfg.sort;
        self.wide = Some(Sorter::new(SortConfig::new(c.format(), wide_chunk, c.network().clone())?));
        Ok(())
    }

    /// Its configuration.
    pub fn config(&self) -> &UpdateConfig {
        &self.cfg
    }

    /// Reuse-and-update of `table` (the previous frame's table, replaced by this frame's) with
    /// `incoming` at frame index `frame`.
    pub fn update(&mut self, table: &mut Vec<SortEntry>, incoming: &[SortEntry], frame: u64) -> UpdateWork {
        self.update_passes(table, incoming, frame, self.cfg.dps_passes)
    }

    /// [`TileSorter::update`] with `passes` DPS passes instead of the configured number.
    pub fn update_passes(
        &mut self,
        table: &mut Vec<SortEntry>,
        incoming: &[SortEntry],
        frame: u64,
        passes: usize,
    ) -> UpdateWork {
        self.update_wide(table, incoming, frame, passes, false)
    }

    /// [`TileSorter::update_passes`] whose DPS uses the wide chunk when `wide` (and a wide chunk
    /// was configured, [`TileSorter::set_wide_chunk`]); the incoming sort keeps the normal one.
    pub fn update_wide(
        &mut self,
        table: &mut Vec<SortEntry>,
        incoming: &[SortEntry],
        frame: u64,
        passes: usize,
        wide: bool,
    ) -> UpdateWork {
        let dps_sorter = match (&mut self.wide, wide) {
            (Some(w), true) => w,
            _ => &mut self.sorter,
        };
        let dps = dps_sorter.dps(table, frame, passes);
        let incoming_sort = self.sorter.full_sort(incoming, &mut self.incoming);
        self.merged.clear();
        let merge = merge2_into(table, &self.incoming, true, &mut self.merged);
        std::mem::swap(table, &mut self.merged);
        let dropped_capacity = truncate_to_capacity(table, self.cfg.capacity);
        UpdateWork {
            dps,
            incoming_sort,
            merge,
            dropped_invalid: merge.dropped_invalid,
            dropped_capacity,
            table_len: table.len(),
        }
    }

    /// Full-frame sort (frame 0, or after a cut): conventional sort of `entries` into `table`,
    /// then the capacity cut.
    pub fn full_frame_sort(&mut self, entries: &[SortEntry], table: &mut Vec<SortEntry>) -> UpdateWork {
        let incoming_sort = self.sorter.full_sort(entries, table);
        let dropped_capacity = truncate_to_capacity(table, self.cfg.capacity);
        UpdateWork { incoming_sort, dropped_capacity, table_len: table.len(), ..UpdateWork::default() }
    }
}

/// Keeps the first `capacity` entries; returns how many were removed.
fn truncate_to_capacity(table: &mut Vec<SortEntry>, capacity: usize) -> usize {
    let dropped = table.len().saturating_sub(capacity);
    table.truncate(capacity);
    dropped
}

/// Reuse-and-update of one tile (allocating convenience over [`TileSorter::update`]).
pub fn update_tile(prev: &[SortEntry], incoming: &[SortEntry], frame: u64, cfg: &UpdateConfig) -> TileUpdate {
    let mut table = prev.to_vec();
    let work = TileSorter::new(cfg.clone()).update(&mut table, incoming, frame);
    TileUpdate { table, work }
}

/// Full-frame sort of one tile (allocating convenience over [`TileSorter::full_frame_sort`]).
pub fn full_frame_sort(entries: &[SortEntry], cfg: &UpdateConfig) -> TileUpdate {
    let mut table = Vec::with_capacity(entries.len());
    let work = TileSorter::new(cfg.clone()).full_frame_sort(entries, &mut table);
    TileUpdate { table, work }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn e(key: u32, id: u32, valid: bool) -> SortEntry {
        SortEntry { key, id, valid }
    }

    #[test]
    fn update_inserts_deletes_and_counts() {
        let cfg = UpdateConfig::new(SortConfig::artifact(), 100);
        let prev = [e(1, 10, true), e(5, 11, false), e(3, 12, true)]; // stale order
        let incoming = [e(4, 20, true), e(0, 21, true)];
        let u = update_tile(&prev, &incoming, 7, &cfg);
        assert_eq!(u.table, vec![e(0, 21, true), e(1, 10, true), e(3, 12, true), e(4, 20, true)]);
        assert_eq!(u.work.dropped_invalid, 1);
        assert_eq!(u.work.dropped_capacity, 0);
        assert_eq!(
            u.work.merge,
            MergeStats { in_a: 3, in_b: 2, out: 4, dropped_invalid: 1, a_inversions: 0 }
        );
        assert_eq!(u.work.dps.passes, 1);
        assert_eq!(u.work.dps.chunk.entries, 3);
        assert_eq!(u.work.incoming_sort.entries, 2);
        assert_eq!(u.work.table_len, 4);
    }

    #[test]
    fn capacity_keeps_the_nearest() {
        let cfg = UpdateConfig::new(SortConfig::artifact(), 2);
        let u = update_tile(&[e(9, 1, true), e(2, 2, true)], &[e(5, 3, true)], 0, &cfg);
        assert_eq!(u.table, vec![e(2, 2, true), e(5, 3, true)]);
        assert_eq!(u.work.dropped_capacity, 1);
        let f = full_frame_sort(&[e(9, 1, true), e(2, 2, true), e(5, 3, false)], &cfg);
        assert_eq!(f.table, vec![e(2, 2, true), e(5, 3, false)]);
        assert_eq!(f.work.dropped_capacity, 1);
        assert_eq!(f.work.dropped_invalid, 0);
    }
}
