//! Work counters of the sorting stage and of the table traffic around it, per tile and summed
//! per frame, for the cycle model. All counts are in entries (multiply by
//! [`crate::sort::SortFormat::bytes_per_entry`] for bytes) or in operations.
//!
//! # DRAM accounting (entries)
//! - a conventional sort reads and writes every entry once for its chunk phase and once per
//!   global merge pass ([`crate::sort::SortWork`]);
//! - DPS and the MSU+ insert/delete merge are one stream: each DPS chunk, once sorted on chip,
//!   is final for the pass (no later chunk touches its entries), so the last pass feeds the
//!   MSU+ directly, which merges it with the sorted incoming list (read from DRAM) and writes
//!   the merged table once. So `p` DPS passes over `L` entries read `p L` and write
//!   `(p - 1) L`; the merge reads the `n` incoming entries (and the table, `L`, when there was
//!   no DPS pass: periodic and background) and writes its output minus the capacity cut. The
//!   component counters (`dps_entries`, `merge_in_*`, `merge_out`) allow other accountings;
//! - the hierarchical sort reads and writes every entry once per approximate pass and once in
//!   its bin sorts ([`super::hierarchical::HierWork`]);
//! - `binned_written`: entries the binning (duplication) stage writes for sorting: every pair
//!   for a from-scratch sort, only the incoming entries for a reuse frame;
//! - `raster_read`: table entries the raster reads; `writeback`: table entries written back
//!   after the raster (depth keys and/or valid bits; zero for from-scratch strategies, whose
//!   tables are not reused).
//!
//! The background sorter's own sort (strategy `background:K`) is counted in the `background_*`
//! fields, separately from the foreground sorting.

use super::hierarchical::HierWork;
use crate::sort::{SortWork, UpdateWork};

/// Additive work counters (see the module docs).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct StageWork {
    /// Conventional sorts run (full-frame sorts and incoming-list sorts of non-empty lists).
    pub sorts: u64,
    /// Entries fed to conventional sorts.
    pub entries_sorted: u64,
    /// BSU vectors sorted (conventional sorts, DPS and hierarchical bins).
    pub bsu_vectors: u64,
    /// Padding entries added to partial BSU vectors.
    pub padding_entries: u64,
    /// Chunks loaded into the on-chip buffer (conventional chunks, DPS chunks, hierarchical
    /// bins); each is stored back once, so this is also the number of chunk stores.
    pub chunk_loads: u64,
    /// Chunks stored back to DRAM (equal to `chunk_loads`).
    pub chunk_stores: u64,
    /// Entries in those chunks.
    pub chunk_entries: u64,
    /// In-chunk MSU merge passes, summed over chunks.
    pub in_chunk_merge_passes: u64,
    /// Global merge passes of conventional sorts.
    pub global_merge_passes: u64,
    /// Entries read (= written) by global merge passes.
    pub global_merge_entries: u64,
    /// DPS passes.
    pub dps_passes: u64,
    /// Chunks DPS touched.
    pub dps_chunks: u64,
    /// Entries DPS read (= wrote).
    pub dps_entries: u64,
    /// MSU+ insert/delete merges (one per reused tile).
    pub insert_merges: u64,
    /// Table entries entering those merges.
    pub merge_in_table: u64,
    /// Incoming entries entering those merges.
    pub merge_in_incoming: u64,
    /// Entries those merges emitted.
    pub merge_out: u64,
    /// Entries removed for a valid bit of 0.
    pub dropped_invalid: u64,
    /// Entries removed by the capacity cut.
    pub dropped_capacity: u64,
    /// Hierarchical approximate passes.
    pub hier_approx_passes: u64,
    /// Hierarchical depth bins created.
    pub hier_bins: u64,
    /// Hierarchical bins larger than a chunk.
    pub hier_bins_oversized: u64,
    /// Hierarchical bins sorted by the conventional fallback.
    pub hier_fallback_sorts: u64,
    /// Sorting-stage DRAM entries read.
    pub dram_read: u64,
    /// Sorting-stage DRAM entries written.
    pub dram_written: u64,
    /// Entries the binning stage writes for the sorter.
    pub binned_written: u64,
    /// Table entries the raster reads.
    pub raster_read: u64,
    /// Table entries written back after the raster.
    pub writeback: u64,
    /// Background sorter: entries sorted.
    pub background_entries_sorted: u64,
    /// Background sorter: DRAM entries read.
    pub background_dram_read: u64,
    /// Background sorter: DRAM entries written.
    pub background_dram_written: u64,
}

impl StageWork {
    /// Adds `o` into `self`.
    pub fn add(&mut self, o: &StageWork) {
        macro_rules! add {
            ($($f:ident),*) => { $( self.$f += o.$f; )* };
        }
        add!(
            sorts,
            entries_sorted,
            bsu_vectors,
            padding_entries,
            chunk_loads,
            chunk_stores,
            chunk_entries,
            in_chunk_merge_passes,
            global_merge_passes,
            global_merge_entries,
            dps_passes,
            dps_chunks,
            dps_entries,
            insert_merges,
            merge_in_table,
            merge_in_incoming,
            merge_out,
            dropped_invalid,
            dropped_capacity,
            hier_approx_passes,
            hier_bins,
            hier_bins_oversized,
            hier_fallback_sorts,
            dram_read,
            dram_written,
            binned_written,
            raster_read,
            writeback,
            background_entries_sorted,
            background_dram_read,
            background_dram_written
        );
    }

    /// Adds a conventional sort.
    pub fn add_sort(&mut self, w: &SortWork) {
        if w.entries > 0 {
            self.sorts += 1;
        }
        self.entries_sorted += w.entries as u64;
        self.add_chunks(&w.chunk);
        self.global_merge_passes += w.global_passes.len() as u64;
        let global: usize = w.global_passes.iter().map(|p| p.entries()).sum();
        self.global_merge_entries += global as u64;
        self.dram_read += w.dram_entries_read() as u64;
        self.dram_written += w.dram_entries_written() as u64;
    }

    /// Adds an update step (DPS, incoming sort, merge, capacity cut) or a full-frame sort.
    pub fn add_update(&mut self, w: &UpdateWork) {
        self.add_sort(&w.incoming_sort);
        let m = &w.merge;
        if w.dps.passes > 0 {
            self.dps_passes += w.dps.passes as u64;
            self.dps_chunks += w.dps.chunk.chunks as u64;
            self.dps_entries += w.dps.chunk.entries as u64;
            self.add_chunks(&w.dps.chunk);
            self.dram_read += w.dps.dram_entries_read() as u64;
            // The last pass streams into the MSU+ instead of back to DRAM.
            self.dram_written += (w.dps.dram_entries_written() - m.in_a) as u64;
        }
        if m.in_a + m.in_b > 0 {
            self.insert_merges += 1;
            self.merge_in_table += m.in_a as u64;
            self.merge_in_incoming += m.in_b as u64;
            self.merge_out += m.out as u64;
            self.dram_read += m.in_b as u64;
            if w.dps.passes == 0 {
                self.dram_read += m.in_a as u64;
            }
            // The capacity cut happens as the merge streams out: only kept entries are written.
            self.dram_written += (m.out - m.out.min(w.dropped_capacity)) as u64;
        }
        self.dropped_invalid += w.dropped_invalid as u64;
        self.dropped_capacity += w.dropped_capacity as u64;
    }

    /// Adds a hierarchical sort.
    pub fn add_hier(&mut self, w: &HierWork) {
        if w.entries > 0 {
            self.sorts += 1;
        }
        self.entries_sorted += w.entries as u64;
        self.add_chunks(&w.chunk);
        self.hier_approx_passes += w.approx_passes as u64;
        self.hier_bins += w.bins as u64;
        self.hier_bins_oversized += w.bins_oversized as u64;
        self.hier_fallback_sorts += w.fallback_sorts as u64;
        self.global_merge_entries += w.fallback_global_entries as u64;
        self.dram_read += w.dram_entries_read() as u64;
        self.dram_written += w.dram_entries_written() as u64;
    }

    /// Adds the background sorter's conventional sort.
    pub fn add_background(&mut self, w: &SortWork) {
        self.background_entries_sorted += w.entries as u64;
        self.background_dram_read += w.dram_entries_read() as u64;
        self.background_dram_written += w.dram_entries_written() as u64;
    }

    fn add_chunks(&mut self, c: &crate::sort::ChunkWork) {
        self.bsu_vectors += c.bsu_vectors as u64;
        self.padding_entries += c.padding_entries as u64;
        self.chunk_loads += c.chunks as u64;
        self.chunk_stores += c.chunks as u64;
        self.chunk_entries += c.entries as u64;
        self.in_chunk_merge_passes += c.merge_passes as u64;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sort::{update_tile, SortConfig, SortEntry, UpdateConfig};

    #[test]
    fn update_counts_dps_sort_and_merge_traffic() {
        let cfg = UpdateConfig::new(SortConfig::artifact(), 3);
        let prev: Vec<SortEntry> =
            (0..300u32).map(|i| SortEntry { key: 300 - i, id: i, valid: i % 2 == 0 }).collect();
        let incoming: Vec<SortEntry> = (0..20u32).map(|i| SortEntry::new(i, 1000 + i)).collect();
        let u = update_tile(&prev, &incoming, 1, &cfg);
        let mut w = StageWork::default();
        w.add_update(&u.work);
        assert_eq!(w.dps_passes, 1);
        assert_eq!(w.dps_entries, 300);
        // Odd frame: chunks [0,128) [128,300).
        assert_eq!(w.dps_chunks, 2);
        assert_eq!(w.entries_sorted, 20);
        assert_eq!(w.merge_in_table, 300);
        assert_eq!(w.merge_in_incoming, 20);
        assert_eq!(w.merge_out, 150 + 20);
        assert_eq!(w.dropped_invalid, 150);
        assert_eq!(w.dropped_capacity, 167);
        // DPS 300 (streamed into the merge) + incoming sort 20 (one chunk, no global pass) +
        // the merge's incoming 20; writes: incoming sort 20 + merged table 3 (capacity).
        assert_eq!(w.dram_read, 300 + 20 + 20);
        assert_eq!(w.dram_written, 20 + 3);
        // Without DPS the merge reads the table itself.
        let cfg0 = UpdateConfig { dps_passes: 0, ..cfg.clone() };
        let mut w0 = StageWork::default();
        w0.add_update(&update_tile(&prev, &incoming, 1, &cfg0).work);
        assert_eq!(w0.dram_read, 20 + 320);
        // Two passes: the first writes back.
        let cfg2 = UpdateConfig { dps_passes: 2, ..cfg };
        let mut w2 = StageWork::default();
        w2.add_update(&update_tile(&prev, &incoming, 1, &cfg2).work);
        assert_eq!((w2.dram_read, w2.dram_written), (600 + 20 + 20, 300 + 20 + 3));
        assert_eq!(w.chunk_loads, 3);
        let mut sum = StageWork::default();
        sum.add(&w);
        sum.add(&w);
        assert_eq!(sum.dram_read, 2 * w.dram_read);
    }
}
