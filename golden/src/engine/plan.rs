//! The per-tile command plan of the engine: the one definition of the Sorting Core commands a
//! tile's sort issues, in entry addresses, grouped into stages separated by barriers.
//!
//! [`tile_plan`] is what the reference ([`super::execute_frame`]) executes and what the RTL's
//! per-core sequencer (`neo_sort_seq`) is checked against by its test bench (`tb/tests/sort_seq.rs`).
//!
//! For a tile that fits the table capacity (`entries_in() <= table_capacity`), with `n =
//! list_len`, chunk `C`, `P = merge_pass_count(n, C)` and the core's two scratch regions
//! `S0 = scratch_base / 8 + core * 2 * table_capacity`, `S1 = S0 + table_capacity`:
//! - stage 0 (when `n > 0`): one `SORT` per chunk of at most `C` entries of the list;
//! - stages `1..=P`: merge pass `s` pairs the runs of `C << (s - 1)` entries with one `MERGE`
//!   each (a lone last run is copied with an empty B; B follows A directly);
//! - stage `s` (`0..=P`) reads the list (`s = 0`) or `S[(s - 1) % 2]` and writes `S[s % 2]`,
//!   except the last (`s = P`) of a from-scratch tile, which writes `next`;
//! - a reuse tile (not from scratch) then has one DPS stage per pass `p` of its descriptor's
//!   `dps_passes` (when `prev_len > 0`): one `DPS` per chunk of parity `Parity::of(frame, p)`
//!   (golden [`Parity::chunks`]) over the previous table in place, and a last stage: one
//!   `MERGE_DELETE` of A = the previous table and B = the sorted list (`S[P % 2]`, `n`
//!   entries) into `next`.
//!
//! Every stage waits for the previous one to finish: all its commands done and the memory
//! bridge idle (its writes acknowledged). A tile that overflows has no stage.

use super::memory::{Memory, TileDescriptor, ENTRY_BYTES};
use super::regs::FrameRegs;
use super::EngineConfig;
use crate::sort::{
    conventional_sort_plan, merge2, merge_pass_count, ChunkWork, Parity, PlannedCommand, SortBuffer,
    SortMode, Sorter,
};

/// One Sorting Core command at entry addresses (the fields of `neo_sort_core`'s cmd port).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct TileCmd {
    /// The mode.
    pub mode: SortMode,
    /// Entry address of the chunk / stream A.
    pub src_a: u64,
    /// Entries of the chunk / stream A.
    pub len_a: u64,
    /// Entry address of stream B (merges; 0 for chunk commands).
    pub src_b: u64,
    /// Entries of stream B (0 for chunk commands).
    pub len_b: u64,
    /// Entry address of the output.
    pub dst: u64,
}

impl TileCmd {
    /// Command `c` of a conventional sort ([`conventional_sort_plan`]) placed in memory: its
    /// stage reads the data starting at entry address `src` and writes the data starting at
    /// `dst` (`c`'s offsets are relative to both).
    pub fn planned(c: &PlannedCommand, src: u64, dst: u64) -> TileCmd {
        let src_b = if c.mode == SortMode::Merge { src + c.start_b() } else { 0 };
        TileCmd {
            mode: c.mode,
            src_a: src + c.start,
            len_a: c.len_a,
            src_b,
            len_b: c.len_b,
            dst: dst + c.start,
        }
    }
}

/// A tile's commands (see the module docs).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct TilePlan {
    /// The tile does not fit the table capacity: it is not sorted (no stage).
    pub overflow: bool,
    /// The stages in order, none empty; a barrier separates two stages.
    pub stages: Vec<Vec<TileCmd>>,
}

impl TilePlan {
    /// Every command in issue order.
    pub fn commands(&self) -> impl Iterator<Item = &TileCmd> {
        self.stages.iter().flatten()
    }
}

/// Entry address of the first scratch region of sorting core `core` (the second follows it,
/// `table_capacity` entries later).
pub fn scratch_entry_base(cfg: &EngineConfig, regs: &FrameRegs, core: u64) -> u64 {
    regs.scratch_base / ENTRY_BYTES + core * 2 * cfg.table_capacity as u64
}

/// The plan of tile descriptor `d` on sorting core `core` in frame `regs.frame` (see the
/// module docs).
pub fn tile_plan(cfg: &EngineConfig, regs: &FrameRegs, d: &TileDescriptor, core: u64) -> TilePlan {
    let cap = cfg.table_capacity as u64;
    if d.entries_in() > cap {
        return TilePlan { overflow: true, stages: Vec::new() };
    }
    let chunk = cfg.chunk as u64;
    let s0 = scratch_entry_base(cfg, regs, core);
    let scratch = [s0, s0 + cap];
    let n = d.list_len as u64;
    let passes = merge_pass_count(n, chunk);
    let last = if d.from_scratch { d.next as u64 } else { scratch[(passes % 2) as usize] };
    let mut stages: Vec<Vec<TileCmd>> = Vec::new();
    let at = |b: SortBuffer| match b {
        SortBuffer::Input => d.list as u64,
        SortBuffer::Scratch(k) => scratch[k],
        SortBuffer::Output => last,
    };
    for c in conventional_sort_plan(n, chunk) {
        let cmd = TileCmd::planned(&c, at(c.source()), at(c.target(passes)));
        if stages.len() as u64 == c.stage {
            stages.push(Vec::new());
        }
        stages[c.stage as usize].push(cmd);
    }
    if !d.from_scratch {
        let prev = d.prev as u64;
        for p in 0..d.passes() as usize {
            let dps: Vec<TileCmd> = Parity::of(regs.frame as u64, p)
                .chunks(d.prev_len as usize, cfg.chunk)
                .map(|r| {
                    let at = prev + r.start as u64;
                    TileCmd {
                        mode: SortMode::Dps,
                        src_a: at,
                        len_a: r.len() as u64,
                        src_b: 0,
                        len_b: 0,
                        dst: at,
                    }
                })
                .collect();
            if !dps.is_empty() {
                stages.push(dps);
            }
        }
        stages.push(vec![TileCmd {
            mode: SortMode::MergeDelete,
            src_a: prev,
            len_a: d.prev_len as u64,
            src_b: last,
            len_b: n,
            dst: d.next as u64,
        }]);
    }
    TilePlan { overflow: false, stages }
}

/// What one executed command moved.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CmdEffect {
    /// Entries read.
    pub read: u64,
    /// Entries written (the core's `done_len`).
    pub written: u64,
}

/// Executes one command on `mem` as the Sorting Core does (golden `sort_chunk` for `SORT` /
/// `DPS` of `min(len_a, chunk)` entries, [`merge2`] for the merges). Returns the entries moved,
/// or the address of an entry carrying the reserved id (`id_max`), which a chunk command
/// refuses.
pub fn run_command(sorter: &mut Sorter, mem: &mut Memory, c: &TileCmd) -> Result<CmdEffect, u64> {
    let fmt = sorter.config().format();
    if c.mode.is_chunk() {
        let len = c.len_a.min(sorter.config().chunk() as u64);
        let mut chunk = mem.read_entries(&fmt, c.src_a, len as usize);
        if let Some(k) = chunk.iter().position(|e| e.id == fmt.id_max()) {
            return Err(c.src_a + k as u64);
        }
        sorter.sort_chunk(&mut chunk, &mut ChunkWork::default());
        mem.write_entries(&fmt, c.dst, &chunk);
        return Ok(CmdEffect { read: len, written: len });
    }
    let a = mem.read_entries(&fmt, c.src_a, c.len_a as usize);
    let b = mem.read_entries(&fmt, c.src_b, c.len_b as usize);
    let out = merge2(&a, &b, c.mode.drops_invalid());
    mem.write_entries(&fmt, c.dst, &out);
    Ok(CmdEffect { read: c.len_a + c.len_b, written: out.len() as u64 })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn regs(frame: u32) -> FrameRegs {
        FrameRegs { frame, scratch_base: 0x10_0000, ..FrameRegs::default() }
    }

    fn desc(from_scratch: bool, n: u32, prev_len: u32) -> TileDescriptor {
        TileDescriptor {
            from_scratch,
            prev: 0x4000,
            prev_len,
            list: 0x8000,
            list_len: n,
            next: 0x9000,
            ..Default::default()
        }
    }

    #[test]
    fn a_from_scratch_tile_ends_in_next_and_ping_pongs_the_scratch() {
        let cfg = EngineConfig::default();
        let p = tile_plan(&cfg, &regs(0), &desc(true, 700, 0), 1);
        let s0 = 0x10_0000 / 8 + 2 * cfg.table_capacity as u64;
        let s1 = s0 + cfg.table_capacity as u64;
        assert!(!p.overflow);
        assert_eq!(p.stages.len(), 3);
        assert_eq!(
            p.stages[0].iter().map(|c| (c.src_a, c.len_a, c.dst)).collect::<Vec<_>>(),
            [(0x8000, 256, s0), (0x8100, 256, s0 + 256), (0x8200, 188, s0 + 512)]
        );
        assert_eq!(
            p.stages[1].iter().map(|c| (c.src_a, c.src_b, c.len_b, c.dst)).collect::<Vec<_>>(),
            [(s0, s0 + 256, 256, s1), (s0 + 512, s0 + 700, 0, s1 + 512)]
        );
        assert_eq!(
            p.stages[2],
            vec![TileCmd {
                mode: SortMode::Merge,
                src_a: s1,
                len_a: 512,
                src_b: s1 + 512,
                len_b: 188,
                dst: 0x9000
            }]
        );
    }

    #[test]
    fn a_reuse_tile_adds_dps_with_the_parity_shift_then_merge_delete() {
        let cfg = EngineConfig::default();
        let s0 = 0x10_0000 / 8;
        for frame in [4, 5] {
            let p = tile_plan(&cfg, &regs(frame), &desc(false, 300, 600), 0);
            assert_eq!(p.stages.len(), 4, "sort, merge, dps, merge_delete");
            let dps: Vec<(u64, u64)> = p.stages[2].iter().map(|c| (c.src_a - 0x4000, c.len_a)).collect();
            let want: &[(u64, u64)] = if frame % 2 == 0 {
                &[(0, 256), (256, 256), (512, 88)]
            } else {
                &[(0, 128), (128, 256), (384, 216)]
            };
            assert_eq!(dps, want, "frame {frame}");
            let md = p.stages[3][0];
            assert_eq!(
                (md.mode, md.src_a, md.len_a, md.src_b, md.len_b, md.dst),
                (SortMode::MergeDelete, 0x4000, 600, s0 + cfg.table_capacity as u64, 300, 0x9000)
            );
        }
        // Nothing to sort and nothing to re-sort: the MERGE_DELETE alone (of empty streams).
        let p = tile_plan(&cfg, &regs(1), &desc(false, 0, 0), 0);
        assert_eq!(p.stages.len(), 1);
        assert_eq!((p.stages[0][0].len_a, p.stages[0][0].len_b, p.stages[0][0].src_b), (0, 0, s0));
        assert!(tile_plan(&cfg, &regs(1), &desc(true, 0, 9), 0).stages.is_empty());
    }

    #[test]
    fn every_dps_pass_is_a_stage_with_the_parity_of_its_pass() {
        let cfg = EngineConfig::default();
        let chunk_starts = |stage: &Vec<TileCmd>| stage.iter().map(|c| c.src_a - 0x4000).collect::<Vec<_>>();
        for frame in [4u32, 5] {
            for passes in [0u8, 1, 2, 3] {
                let d = TileDescriptor { dps_passes: passes, ..desc(false, 100, 600) };
                let p = tile_plan(&cfg, &regs(frame), &d, 0);
                // sort, the passes, merge_delete
                assert_eq!(p.stages.len(), 2 + passes as usize, "frame {frame}, {passes} passes");
                for k in 0..passes as usize {
                    assert!(p.stages[1 + k].iter().all(|c| c.mode == SortMode::Dps));
                    let odd = (frame as usize + k) % 2 == 1;
                    let want: &[u64] = if odd { &[0, 128, 384] } else { &[0, 256, 512] };
                    assert_eq!(chunk_starts(&p.stages[1 + k]), want, "frame {frame}, pass {k}");
                }
                assert_eq!(p.stages.last().unwrap()[0].mode, SortMode::MergeDelete);
            }
        }
    }

    #[test]
    fn a_tile_over_capacity_overflows_with_no_command() {
        let cfg = EngineConfig { table_capacity: 1024, ..EngineConfig::default() };
        let p = tile_plan(&cfg, &regs(0), &desc(false, 600, 425), 0);
        assert!(p.overflow && p.stages.is_empty());
        assert!(!tile_plan(&cfg, &regs(0), &desc(false, 600, 424), 0).overflow);
        assert!(!tile_plan(&cfg, &regs(0), &desc(true, 1024, 4000), 0).overflow);
    }
}
