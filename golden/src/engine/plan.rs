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
//!   (golden [`Parity::chunks`], of the wide chunk `W` when the descriptor's `dps_wide` is set,
//!   [`EngineConfig::dps_chunk`]) over the previous table in place, and a last stage: one
//!   `MERGE_DELETE` of A = the previous table and B = the sorted list (`S[P % 2]`, `n`
//!   entries) into `next`.
//!
//! Every stage waits for the previous one to finish: all its commands done and the memory
//! bridge idle (its writes acknowledged). A tile that overflows has no stage.

use super::memory::{Memory, TileDescriptor, ENTRY_BYTES};
use super::regs::FrameRegs;
use super::EngineConfig;
use crate::sort::{
    conventional_sort_plan, merge2_into, merge_pass_count, ChunkWork, Parity, SortBuffer, SortMode, Sorter,
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

/// A tile's commands (see the module docs).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct TilePlan {
    /// The tile does not fit the table capacity: it is not sorted (no stage).
    pub overflow: bool,
    /// The stages in order, none empty; a barrier separates two stages.
    pub stages: Vec<Vec<TileCmd>>,
    /// The DPS passes use the wide chunk (the descriptor's `dps_wide`, in an engine with one).
    pub wide: bool,
}

impl TilePlan {
    /// Every command in issue order.
    pub fn commands(&self) -> impl Iterator<Item = &TileCmd> {
        self.stages.iter().flatten()
    }

    /// The DPS passes of the plan (its DPS stages).
    pub fn dps_passes(&self) -> usize {
        self.stages.iter().filter(|s| s.first().is_some_and(|c| c.mode == SortMode::Dps)).count()
    }
}

/// Entry address of the first scratch region of sorting core `core` (the second follows it,
/// `table_capacity` entries later).
pub fn scratch_entry_base(cfg: &EngineConfig, regs: &FrameRegs, core: u64) -> u64 {
    regs.scratch_base / ENTRY_BYTES + core * 2 * cfg.table_capacity as u64
}

/// What decides a tile's commands, whatever its placement in memory: the one input of
/// [`tile_steps`], filled from a descriptor by [`tile_plan`] and from a workload by the cycle
/// model.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TileShape {
    /// The tile is sorted from scratch (no previous table, no DPS, no merge with it).
    pub from_scratch: bool,
    /// Entries of the incoming list (the whole tile from scratch).
    pub list_len: u64,
    /// Entries of the previous table (a reuse tile).
    pub prev_len: u64,
    /// DPS passes over the previous table (a reuse tile).
    pub dps_passes: u64,
    /// The frame (the parity of the DPS passes, [`Parity::of`]).
    pub frame: u64,
    /// Chunk of the conventional sort.
    pub chunk: u64,
    /// Chunk of the DPS passes (the engine's chunk in the RTL; wider in an adaptive model).
    pub dps_chunk: u64,
}

/// A region a tile's command reads or writes (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum TileRegion {
    /// The incoming list.
    List,
    /// Scratch region 0 or 1 of the core.
    Scratch(usize),
    /// The previous table (DPS sorts it in place).
    Prev,
    /// The next table.
    Next,
}

/// One command of a tile in regions and offsets: [`tile_plan`] places it at entry addresses,
/// the cycle model at its own layout's.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TileStep {
    /// The mode.
    pub mode: SortMode,
    /// The chunk / stream A: region, offset in it, entries.
    pub a: (TileRegion, u64, u64),
    /// Stream B of a merge (entries 0 for a chunk command).
    pub b: (TileRegion, u64, u64),
    /// The output: region and offset.
    pub dst: (TileRegion, u64),
}

impl TileStep {
    /// The command at entry addresses, with region `r` starting at entry address `base(r)`
    /// (`src_b` 0 for a chunk command, as the core's cmd port has it).
    pub fn place(&self, base: impl Fn(TileRegion) -> u64) -> TileCmd {
        TileCmd {
            mode: self.mode,
            src_a: base(self.a.0) + self.a.1,
            len_a: self.a.2,
            src_b: if self.mode.is_chunk() { 0 } else { base(self.b.0) + self.b.1 },
            len_b: self.b.2,
            dst: base(self.dst.0) + self.dst.1,
        }
    }
}

/// The commands of a tile of `shape`, in stages (see the module docs): the conventional sort of
/// the list (into [`TileRegion::Next`] from scratch, else into the scratch region of its last
/// pass), then for a reuse tile its DPS passes and the `MERGE_DELETE` into the next table. The
/// one statement of Neo's per-tile sequence: [`tile_plan`] (the reference and the RTL's
/// sequencer) and the cycle model's sort jobs both take it from here.
pub fn tile_steps(shape: &TileShape) -> Vec<Vec<TileStep>> {
    let n = shape.list_len;
    let passes = merge_pass_count(n, shape.chunk);
    let sorted =
        if shape.from_scratch { TileRegion::Next } else { TileRegion::Scratch((passes % 2) as usize) };
    let region = |b: SortBuffer| match b {
        SortBuffer::Input => TileRegion::List,
        SortBuffer::Scratch(k) => TileRegion::Scratch(k),
        SortBuffer::Output => sorted,
    };
    let mut stages: Vec<Vec<TileStep>> = Vec::new();
    for c in conventional_sort_plan(n, shape.chunk) {
        let src = region(c.source());
        let step = TileStep {
            mode: c.mode,
            a: (src, c.start, c.len_a),
            b: (src, c.start_b(), c.len_b),
            dst: (region(c.target(passes)), c.start),
        };
        if stages.len() as u64 == c.stage {
            stages.push(Vec::new());
        }
        stages[c.stage as usize].push(step);
    }
    if shape.from_scratch {
        return stages;
    }
    for p in 0..shape.dps_passes as usize {
        let parity = Parity::of(shape.frame, p);
        let dps: Vec<TileStep> = parity
            .chunks(shape.prev_len as usize, shape.dps_chunk as usize)
            .map(|r| TileStep {
                mode: SortMode::Dps,
                a: (TileRegion::Prev, r.start as u64, r.len() as u64),
                b: (TileRegion::Prev, r.end as u64, 0),
                dst: (TileRegion::Prev, r.start as u64),
            })
            .collect();
        if !dps.is_empty() {
            stages.push(dps);
        }
    }
    stages.push(vec![TileStep {
        mode: SortMode::MergeDelete,
        a: (TileRegion::Prev, 0, shape.prev_len),
        b: (sorted, 0, n),
        dst: (TileRegion::Next, 0),
    }]);
    stages
}

/// The plan of tile descriptor `d` on sorting core `core` in frame `regs.frame` (see the
/// module docs): [`tile_steps`] at the descriptor's and the core's scratch addresses.
pub fn tile_plan(cfg: &EngineConfig, regs: &FrameRegs, d: &TileDescriptor, core: u64) -> TilePlan {
    let cap = cfg.table_capacity as u64;
    if d.entries_in() > cap {
        return TilePlan { overflow: true, ..TilePlan::default() };
    }
    let shape = TileShape {
        from_scratch: d.from_scratch,
        list_len: d.list_len as u64,
        prev_len: d.prev_len as u64,
        dps_passes: d.passes(),
        frame: regs.frame as u64,
        chunk: cfg.chunk as u64,
        dps_chunk: cfg.dps_chunk(d.dps_wide) as u64,
    };
    let s0 = scratch_entry_base(cfg, regs, core);
    let base = |region| match region {
        TileRegion::List => d.list as u64,
        TileRegion::Scratch(k) => s0 + k as u64 * cap,
        TileRegion::Prev => d.prev as u64,
        TileRegion::Next => d.next as u64,
    };
    let stages =
        tile_steps(&shape).iter().map(|stage| stage.iter().map(|s| s.place(base)).collect()).collect();
    TilePlan { overflow: false, stages, wide: d.dps_wide && cfg.dps_wide > 1 }
}

/// What one executed command moved.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CmdEffect {
    /// Entries read.
    pub read: u64,
    /// Entries written (the core's `done_len`).
    pub written: u64,
    /// MSU+ boundary inversions of stream A (merges; 0 for chunk commands).
    pub a_inversions: u64,
}

/// Executes one command on `mem` as the Sorting Core does (golden `sort_chunk` for `SORT` /
/// `DPS` of `min(len_a, chunk)` entries, with `sorter`'s chunk the core's buffer,
/// [`EngineConfig::buffer_sort_config`]; [`merge2_into`] for the merges). Returns the entries moved,
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
        return Ok(CmdEffect { read: len, written: len, a_inversions: 0 });
    }
    let a = mem.read_entries(&fmt, c.src_a, c.len_a as usize);
    let b = mem.read_entries(&fmt, c.src_b, c.len_b as usize);
    let mut out = Vec::new();
    let stats = merge2_into(&a, &b, c.mode.drops_invalid(), &mut out);
    mem.write_entries(&fmt, c.dst, &out);
    Ok(CmdEffect {
        read: c.len_a + c.len_b,
        written: out.len() as u64,
        a_inversions: stats.a_inversions as u64,
    })
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
    fn a_reuse_tile_merges_the_list_from_the_scratch_region_of_its_last_pass() {
        let shape = |n| TileShape {
            list_len: n,
            prev_len: 600,
            dps_passes: 1,
            frame: 3,
            chunk: 256,
            dps_chunk: 256,
            ..TileShape::default()
        };
        for (n, passes) in [(0u64, 0u64), (200, 0), (300, 1), (600, 2), (1100, 3)] {
            let steps = tile_steps(&shape(n));
            let merge = steps.last().unwrap()[0];
            let sorted = TileRegion::Scratch((passes % 2) as usize);
            assert_eq!(merge.b, (sorted, 0, n), "{n} entries");
            assert_eq!((merge.a, merge.dst), ((TileRegion::Prev, 0, 600), (TileRegion::Next, 0)));
            let last_sort = steps.iter().flatten().rfind(|s| s.a.0 != TileRegion::Prev);
            assert!(last_sort.is_none_or(|s| s.dst.0 == sorted), "{n} entries: {last_sort:?}");
        }
    }

    #[test]
    fn a_wider_dps_chunk_changes_only_the_dps_stages() {
        let narrow = TileShape {
            list_len: 700,
            prev_len: 3000,
            dps_passes: 2,
            frame: 5,
            chunk: 256,
            dps_chunk: 256,
            ..TileShape::default()
        };
        let wide = TileShape { dps_chunk: 1024, ..narrow };
        let (a, b) = (tile_steps(&narrow), tile_steps(&wide));
        assert_eq!(a.len(), b.len());
        let dps_lens = |stage: &Vec<TileStep>| stage.iter().map(|s| s.a.2).collect::<Vec<_>>();
        // Frame 5: pass 0 odd (a half chunk first), pass 1 even.
        assert_eq!(dps_lens(&b[3]), [512, 1024, 1024, 440]);
        assert_eq!(dps_lens(&b[4]), [1024, 1024, 952]);
        for k in [0, 1, 2, 5] {
            assert_eq!(a[k], b[k], "stage {k}");
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
