//! Sorting-core command sequences, as the RTL runs them (`gen/src/units/sort_core.rs`, driven
//! by `tb/src/core.rs`), and their measured cycles.
//!
//! - conventional sort of `n` entries: one `SORT` per chunk of at most `C`, then merge passes
//!   pairing runs of `C, 2C, ...` with `MERGE` (a lone last run is copied by a `MERGE` with an
//!   empty second stream), as `neo_golden::sort::full_sort` and `tb::core::full_sort_checked`;
//! - a DPS pass over `L` entries: one `DPS` per chunk of the pass's parity
//!   ([`Parity::chunks`]);
//! - the reuse-and-update step of a tile: DPS passes, the conventional sort of the incoming
//!   list, `MERGE_DELETE` of the two (`tb::core::update_checked`).

use neo_golden::sort::Parity;

use crate::latency::{ChunkMode, Latency};

/// A sorting-core command mode.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Mode {
    /// Sort one chunk.
    Sort,
    /// DPS of one chunk.
    Dps,
    /// Merge keeping every entry.
    Merge,
    /// Merge dropping invalid entries.
    MergeDelete,
}

/// One command: `len_a` entries (the chunk, or stream A) and `len_b` (stream B).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Cmd {
    /// Mode.
    pub mode: Mode,
    /// Chunk or stream A entries.
    pub len_a: u64,
    /// Stream B entries.
    pub len_b: u64,
}

impl Cmd {
    /// Entries read.
    pub fn entries_in(&self) -> u64 {
        self.len_a + self.len_b
    }

    /// Measured (or interpolated) cycles of the command.
    pub fn cycles(&self, lat: &Latency) -> u64 {
        match self.mode {
            Mode::Sort => lat.chunk_cycles(ChunkMode::Sort, self.len_a),
            Mode::Dps => lat.chunk_cycles(ChunkMode::Dps, self.len_a),
            Mode::Merge => lat.merge_cycles(self.len_a, self.len_b, false),
            Mode::MergeDelete => lat.merge_cycles(self.len_a, self.len_b, true),
        }
    }
}

/// The commands of a conventional sort of `n` entries with chunk `c`.
pub fn conventional_sort(n: u64, c: u64) -> Vec<Cmd> {
    let mut v = Vec::new();
    if n == 0 {
        return v;
    }
    let mut start = 0;
    while start < n {
        let len = c.min(n - start);
        v.push(Cmd { mode: Mode::Sort, len_a: len, len_b: 0 });
        start += len;
    }
    let mut run = c;
    while run < n {
        let mut start = 0;
        while start < n {
            let la = run.min(n - start);
            let lb = run.min(n - start - la);
            v.push(Cmd { mode: Mode::Merge, len_a: la, len_b: lb });
            start += la + lb;
        }
        run *= 2;
    }
    v
}

/// Number of `SORT` commands (chunks) of a conventional sort; the rest are merges.
pub fn chunk_count(n: u64, c: u64) -> u64 {
    n.div_ceil(c)
}

/// The `DPS` commands of one pass over `len` entries with chunk `c` and `parity`.
pub fn dps_pass(len: u64, c: u64, parity: Parity) -> Vec<Cmd> {
    parity
        .chunks(len as usize, c as usize)
        .map(|r| Cmd { mode: Mode::Dps, len_a: r.len() as u64, len_b: 0 })
        .filter(|c| c.len_a > 0)
        .collect()
}

/// The RTL command sequence of one reuse-and-update step (`tb::core::update_checked`): DPS
/// passes over the `table` reused entries (pass `p` with parity `(frame + p) % 2`), the
/// conventional sort of `incoming` entries, and the `MERGE_DELETE` of the two.
pub fn update(table: u64, incoming: u64, frame: u64, passes: usize, c: u64) -> Vec<Cmd> {
    let mut v = Vec::new();
    for p in 0..passes {
        v.extend(dps_pass(table, c, Parity::of(frame, p)));
    }
    v.extend(conventional_sort(incoming, c));
    v.push(Cmd { mode: Mode::MergeDelete, len_a: table, len_b: incoming });
    v
}

/// Total cycles of `cmds` run back to back (the cosimulation's ideal-memory sequence).
pub fn total_cycles(cmds: &[Cmd], lat: &Latency) -> u64 {
    cmds.iter().map(|c| c.cycles(lat)).sum()
}

#[cfg(test)]
mod tests {
    use super::*;
    use neo_golden::sort::{full_sort, SortConfig, SortEntry};

    #[test]
    fn conventional_sort_matches_the_golden_work_counters() {
        let cfg = SortConfig::artifact();
        for n in [0u64, 1, 255, 256, 257, 700, 1024, 1500] {
            let input: Vec<SortEntry> = (0..n as u32).map(|i| SortEntry::new((i * 7919) % 1000, i)).collect();
            let (_, w) = full_sort(&input, &cfg);
            let cmds = conventional_sort(n, 256);
            let sorts = cmds.iter().filter(|c| c.mode == Mode::Sort).count();
            assert_eq!(sorts, w.chunk.chunks, "n = {n}");
            let merged: u64 = cmds.iter().filter(|c| c.mode == Mode::Merge).map(|c| c.entries_in()).sum();
            assert_eq!(
                merged as usize,
                w.global_passes.iter().map(|p| p.entries()).sum::<usize>(),
                "n = {n}"
            );
            // Every command reads what it writes: DRAM entries equal the golden accounting.
            let read: u64 = cmds.iter().map(|c| c.entries_in()).sum();
            assert_eq!(read as usize, w.dram_entries_read());
        }
    }

    #[test]
    fn dps_chunks_follow_the_parity() {
        let even = dps_pass(600, 256, Parity::Even);
        assert_eq!(even.iter().map(|c| c.len_a).collect::<Vec<_>>(), vec![256, 256, 88]);
        let odd = dps_pass(600, 256, Parity::Odd);
        assert_eq!(odd.iter().map(|c| c.len_a).collect::<Vec<_>>(), vec![128, 256, 216]);
        let u = update(600, 40, 1, 1, 256);
        assert_eq!(u.len(), 3 + 1 + 1);
        assert_eq!(u.last().unwrap().mode, Mode::MergeDelete);
    }
}
