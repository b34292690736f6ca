//! The Sorting Core's commands: the mode codes of `cmd_mode_i` and the conventional-sort command
//! plan.
//!
//! This is the one definition of both. The RTL generator (`gen/src/units/sort_core.rs`) decodes
//! [`SortMode::code`], the test bench (`tb/src/core.rs`) drives the plan into the core, the cycle
//! model (`sim/src/sortcmd.rs`) charges it, and [`Sorter::full_sort`](super::Sorter::full_sort)
//! executes it.
//!
//! # The conventional sort of `n` entries with chunk `C`
//! Stage 0 sorts every chunk of at most `C` entries with one `SORT` each (into runs). Stage
//! `p + 1` is merge pass `p`: it pairs the runs of `C * 2^p` entries left to right with one
//! `MERGE` per pair; a lone last run is copied by a `MERGE` with an empty stream B. There are
//! [`merge_pass_count`]`(n, C)` merge passes. Stage `s` reads what stage `s - 1` wrote; a
//! command's entry offsets are relative to the start of the data in either stage's buffer.

use super::full_sort::merge_pass_count;

/// A Sorting Core command mode, with its `cmd_mode_i` code.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SortMode {
    /// 0: sort one chunk (the conventional sort's first stage).
    Sort = 0,
    /// 1: one chunk of a DPS pass (same datapath as `Sort`).
    Dps = 1,
    /// 2: merge streams A and B dropping invalid entries (the update's delete).
    MergeDelete = 2,
    /// 3: merge streams A and B keeping every entry (the conventional sort's merge passes).
    Merge = 3,
}

impl SortMode {
    /// Every mode, in code order.
    pub const ALL: [SortMode; 4] = [SortMode::Sort, SortMode::Dps, SortMode::MergeDelete, SortMode::Merge];

    /// The `cmd_mode_i` code.
    pub const fn code(self) -> u64 {
        self as u64
    }

    /// Width of `cmd_mode_i` in bits.
    pub const BITS: u32 = 2;

    /// Whether this is a chunk command (`Sort` or `Dps`) rather than a merge.
    pub const fn is_chunk(self) -> bool {
        matches!(self, SortMode::Sort | SortMode::Dps)
    }

    /// Whether a merge drops invalid entries.
    pub const fn drops_invalid(self) -> bool {
        matches!(self, SortMode::MergeDelete)
    }
}

/// One command of a conventional sort ([`conventional_sort_plan`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PlannedCommand {
    /// `Sort` (stage 0) or `Merge` (later stages).
    pub mode: SortMode,
    /// 0: the chunk sorts; `p + 1`: merge pass `p`. Reads stage `stage - 1`'s output.
    pub stage: u64,
    /// Offset of the chunk / stream A (stream B follows it directly); also the offset of the
    /// output.
    pub start: u64,
    /// Entries of the chunk / stream A.
    pub len_a: u64,
    /// Entries of stream B (0 for chunks and for a lone run copied through).
    pub len_b: u64,
}

impl PlannedCommand {
    /// Offset of stream B.
    pub fn start_b(&self) -> u64 {
        self.start + self.len_a
    }

    /// Entries read (and written).
    pub fn entries(&self) -> u64 {
        self.len_a + self.len_b
    }
}

/// A buffer of a conventional sort: its input, one of two scratch regions (the stages
/// ping-pong between them), or its output.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SortBuffer {
    /// The entries to sort (read by stage 0).
    Input,
    /// Scratch region 0 or 1.
    Scratch(usize),
    /// Where the sorted entries go (written by the last stage).
    Output,
}

impl PlannedCommand {
    /// The buffer the command reads: the input in stage 0, else scratch region
    /// `(stage - 1) % 2` (what the previous stage wrote).
    pub fn source(&self) -> SortBuffer {
        match self.stage {
            0 => SortBuffer::Input,
            s => SortBuffer::Scratch(((s - 1) % 2) as usize),
        }
    }

    /// The buffer the command writes: the output in the last stage (`stage == passes`, with
    /// `passes` = [`merge_pass_count`] of the sort), else scratch region `stage % 2`.
    pub fn target(&self, passes: u64) -> SortBuffer {
        if self.stage == passes {
            SortBuffer::Output
        } else {
            SortBuffer::Scratch((self.stage % 2) as usize)
        }
    }
}

/// The commands of a conventional sort of `n` entries with chunk `chunk`, in issue order: one
/// `Sort` per chunk, then the merge passes (see the module docs).
///
/// # Panics
/// When `chunk` is 0.
pub fn conventional_sort_plan(n: u64, chunk: u64) -> impl Iterator<Item = PlannedCommand> + Clone {
    let sorts = (0..n.div_ceil(chunk)).map(move |k| {
        let start = k * chunk;
        PlannedCommand { mode: SortMode::Sort, stage: 0, start, len_a: chunk.min(n - start), len_b: 0 }
    });
    let merges = (0..merge_pass_count(n, chunk)).flat_map(move |pass| {
        let run = chunk << pass;
        (0..n.div_ceil(2 * run)).map(move |j| {
            let start = j * 2 * run;
            let len_a = run.min(n - start);
            let len_b = run.min(n - start - len_a);
            PlannedCommand { mode: SortMode::Merge, stage: pass + 1, start, len_a, len_b }
        })
    });
    sorts.chain(merges)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mode_codes_are_the_rtl_encoding() {
        let codes: Vec<u64> = SortMode::ALL.iter().map(|m| m.code()).collect();
        assert_eq!(codes, vec![0, 1, 2, 3]);
        assert!(SortMode::ALL.iter().all(|m| m.code() < 1 << SortMode::BITS));
        assert!(SortMode::Sort.is_chunk() && SortMode::Dps.is_chunk());
        assert!(!SortMode::Merge.is_chunk() && SortMode::MergeDelete.drops_invalid());
    }

    #[test]
    fn plan_covers_every_entry_once_per_stage() {
        for n in [0u64, 1, 255, 256, 257, 700, 1024, 1500, 4097] {
            let plan: Vec<_> = conventional_sort_plan(n, 256).collect();
            let stages = 1 + merge_pass_count(n, 256);
            for stage in 0..if n == 0 { 0 } else { stages } {
                let mut next = 0;
                for c in plan.iter().filter(|c| c.stage == stage) {
                    assert_eq!(c.start, next, "n = {n}, stage {stage}: contiguous");
                    next += c.entries();
                }
                assert_eq!(next, n, "n = {n}, stage {stage}: every entry");
            }
            assert!(plan.iter().all(|c| (c.mode == SortMode::Sort) == (c.stage == 0)));
            assert_eq!(plan.iter().filter(|c| c.mode == SortMode::Sort).count() as u64, n.div_ceil(256));
        }
    }

    #[test]
    fn stages_ping_pong_between_the_scratch_regions_and_end_in_the_output() {
        let passes = merge_pass_count(700, 256);
        let bufs: Vec<(u64, SortBuffer, SortBuffer)> =
            conventional_sort_plan(700, 256).map(|c| (c.stage, c.source(), c.target(passes))).collect();
        use SortBuffer::{Input, Output, Scratch};
        assert_eq!(
            bufs,
            [
                (0, Input, Scratch(0)),
                (0, Input, Scratch(0)),
                (0, Input, Scratch(0)),
                (1, Scratch(0), Scratch(1)),
                (1, Scratch(0), Scratch(1)),
                (2, Scratch(1), Output)
            ]
        );
        let one: Vec<_> = conventional_sort_plan(100, 256).map(|c| (c.source(), c.target(0))).collect();
        assert_eq!(one, [(Input, Output)], "a single chunk sorts straight into the output");
    }

    #[test]
    fn lone_last_run_is_copied_by_a_merge_with_empty_b() {
        let plan: Vec<_> = conventional_sort_plan(700, 256).collect();
        let merges: Vec<(u64, u64, u64, u64)> =
            plan.iter().filter(|c| c.stage > 0).map(|c| (c.stage, c.start, c.len_a, c.len_b)).collect();
        assert_eq!(merges, vec![(1, 0, 256, 256), (1, 512, 188, 0), (2, 0, 512, 188)]);
    }
}
