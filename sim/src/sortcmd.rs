//! Sorting-core command sequences, as the RTL runs them (`gen/src/units/sort_core.rs`, driven
//! by `tb/src/core.rs`), and their measured cycles.
//!
//! - conventional sort of `n` entries: one `SORT` per chunk of at most `C`, then merge passes
//!   pairing runs of `C, 2C, ...` with `MERGE` (a lone last run is copied by a `MERGE` with an
//!   empty second stream): golden's plan `neo_golden::sort::conventional_sort_plan`, which
//!   `neo_golden::sort::full_sort` executes and `tb::core::full_sort_checked` drives;
//! - the reuse-and-update step of a tile: golden's tile commands (`neo_golden::engine::tile_steps`:
//!   the conventional sort of the incoming list, one `DPS` per chunk of each pass's parity,
//!   `MERGE_DELETE` of the two), placed by `tile_plan` for the RTL and by `crate::arch` for
//!   the model, whose commands convert to [`Cmd`]s.
//!
//! # Timing of commands issued back to back
//! The core takes a chunk command (SORT / DPS) while the previous one is still merging: its
//! load runs under the previous chunk's merge passes. Merge commands serialise. A **batch** is
//! a sequence issued back to back with no data dependency on a command still running (the next
//! DPS pass reads the previous pass's output, so it starts a new batch). A batch costs
//! ([`batch_cycles`]): the first command's single-command latency (the fill), then per later
//! command [`Cmd::charge`]: a chunk after a chunk its steady-state interval `I(n)` plus the part
//! of its load the previous command's time cannot hide, `max(0, load(n) - charge(prev))` with
//! `load(n) = T(n) - I(n)` (0 for equal chunks: the measured interval); a merge its measured
//! `interval` (single latency plus the turnaround); a chunk after a merge its single latency.
//! The engine (`crate::arch`, with `double_buffered_io`) gives the same with an ideal memory: a
//! chunk segment's load phase is `T(n) - I(n)`, started under the previous segment.

use neo_golden::engine::TileCmd;
use neo_golden::sort::{conventional_sort_plan, PlannedCommand};

use crate::latency::{ChunkMode, Latency};

/// A sorting-core command mode (golden's, with the RTL's codes).
pub use neo_golden::sort::SortMode as Mode;

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

    /// Whether this is a chunk command (SORT or DPS), which overlaps its neighbours.
    pub fn is_chunk(&self) -> bool {
        self.mode.is_chunk()
    }

    /// Measured (or interpolated) steady-state cycles per command of this shape back to back.
    pub fn interval(&self, lat: &Latency) -> u64 {
        match self.mode {
            Mode::Sort => lat.chunk_interval(ChunkMode::Sort, self.len_a),
            Mode::Dps => lat.chunk_interval(ChunkMode::Dps, self.len_a),
            Mode::Merge => lat.merge_interval(self.len_a, self.len_b, false),
            Mode::MergeDelete => lat.merge_interval(self.len_a, self.len_b, true),
        }
    }

    /// The part of a chunk command's single latency that overlaps the previous command when
    /// issued back to back (its load: memory reads, BSU, writes into the input buffer):
    /// `T(n) - I(n)`; 0 for merges (they serialise).
    pub fn overlappable(&self, lat: &Latency) -> u64 {
        if self.is_chunk() {
            self.cycles(lat).saturating_sub(self.interval(lat))
        } else {
            0
        }
    }

    /// Cycles this command adds to a batch after `prev`, given with the cycles it was charged
    /// (`None`: the batch's first command, charged its single latency). See the module docs.
    pub fn charge(&self, prev: Option<(&Cmd, u64)>, lat: &Latency) -> u64 {
        match prev {
            None => self.cycles(lat),
            Some((p, p_charge)) if self.is_chunk() && p.is_chunk() => {
                self.interval(lat) + self.overlappable(lat).saturating_sub(p_charge)
            }
            Some(_) if self.is_chunk() => self.cycles(lat),
            Some(_) => self.interval(lat),
        }
    }

    /// Measured (or interpolated) cycles of the command alone.
    pub fn cycles(&self, lat: &Latency) -> u64 {
        match self.mode {
            Mode::Sort => lat.chunk_cycles(ChunkMode::Sort, self.len_a),
            Mode::Dps => lat.chunk_cycles(ChunkMode::Dps, self.len_a),
            Mode::Merge => lat.merge_cycles(self.len_a, self.len_b, false),
            Mode::MergeDelete => lat.merge_cycles(self.len_a, self.len_b, true),
        }
    }
}

/// The commands of a conventional sort of `n` entries with chunk `c` (golden's plan,
/// [`conventional_sort_plan`]).
pub fn conventional_sort(n: u64, c: u64) -> Vec<Cmd> {
    conventional_sort_plan(n, c).map(|p| Cmd::from(&p)).collect()
}

impl From<&TileCmd> for Cmd {
    /// The command of one of golden's tile plans (its addresses aside).
    fn from(c: &TileCmd) -> Cmd {
        Cmd { mode: c.mode, len_a: c.len_a, len_b: c.len_b }
    }
}

impl From<&PlannedCommand> for Cmd {
    /// The command of a planned one (its placement aside).
    fn from(p: &PlannedCommand) -> Cmd {
        Cmd { mode: p.mode, len_a: p.len_a, len_b: p.len_b }
    }
}

/// Cycles of one batch `cmds` issued back to back (the cosimulation's ideal-memory queue, from
/// the first command's acceptance to the last `done_o`): the fill plus each later command's
/// [`Cmd::charge`].
pub fn batch_cycles(cmds: &[Cmd], lat: &Latency) -> u64 {
    let mut prev = None;
    let mut t = 0;
    for c in cmds {
        let x = c.charge(prev, lat);
        t += x;
        prev = Some((c, x));
    }
    t
}

/// Cycles of `cmds` run one at a time (each waiting for the previous `done_o`): the sum of the
/// single-command latencies.
pub fn serial_cycles(cmds: &[Cmd], lat: &Latency) -> u64 {
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
    fn back_to_back_batches_charge_one_fill_and_then_intervals() {
        let lat = Latency::from_file(
            &std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../reports/latency.json"),
        )
        .unwrap();
        let c = lat.config.chunk as u64;
        let chunk = Cmd { mode: Mode::Sort, len_a: c, len_b: 0 };
        let k = 8;
        let batch = vec![chunk; k];
        let t = batch_cycles(&batch, &lat);
        assert_eq!(t, chunk.cycles(&lat) + (k as u64 - 1) * chunk.interval(&lat));
        assert!(t < serial_cycles(&batch, &lat), "overlap makes a batch cheaper than serial commands");
        // A merge after chunks serialises: its single latency plus the turnaround.
        let m = Cmd { mode: Mode::Merge, len_a: c, len_b: c };
        let t2 = batch_cycles(&[chunk, chunk, m], &lat);
        assert_eq!(t2, chunk.cycles(&lat) + chunk.interval(&lat) + m.interval(&lat));
        assert!(m.interval(&lat) >= m.cycles(&lat));
        // A big chunk after a tiny one cannot hide its load: charged more than its interval.
        let tiny = Cmd { mode: Mode::Sort, len_a: 1, len_b: 0 };
        assert!(chunk.charge(Some((&tiny, tiny.cycles(&lat))), &lat) > chunk.interval(&lat));
    }
}
