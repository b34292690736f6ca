//! The memory-level reference of the engine: [`execute_frame`] runs one frame exactly as the
//! contract's per-tile sequence does (docs/formats.md "Engine memory"): it reads the descriptors,
//! lists, tables and feature words from a [`Memory`], issues the Sorting Core's commands (SORT,
//! MERGE, DPS, MERGE_DELETE) on data read from it with golden's sort functions, writes every
//! command's output back, rasterises every tile with golden [`raster_tile`], writes the pixels
//! (tile-major) and the table write-back (both in the order of the raster core's reorder window
//! when the configuration has one, [`crate::raster::window`]), then the tile's result with its disorder counters
//! (the MERGE_DELETE's boundary inversions, the write-back's length and reach).
//!
//! It also counts the performance counters golden knows exactly ([`Counter::is_golden`]), from
//! the elements each command (of [`tile_plan`]) and each raster tile
//! actually moves:
//! - a SORT / DPS of `L` entries reads and writes `L` entries; a MERGE reads and writes
//!   `len_a + len_b`; a MERGE_DELETE reads `len_a + len_b` and writes the entries it keeps;
//! - a raster tile of `len` entries reads its `len` table entries once (whatever its segments:
//!   each segment is loaded once), one feature word per entry, writes `len` entries back and
//!   all `tile * tile` pixels (`tile * tile / subtile` writes of `subtile` pixels), empty tiles
//!   and pixels outside the image (black) included;
//! - a descriptor read (32 bytes) and a result write (16 bytes) per tile.
//!
//! With [`ADAPT_ENABLE`](super::ADAPT_ENABLE) the frame controller plans every tile's DPS passes
//! from the previous frame's results ([`super::adapt`], `RD_RESULT`); the descriptors' passes are
//! ignored.
//!
//! With [`PRE_ENABLE`](super::PRE_ENABLE) the frame first runs the Preprocessing Engine
//! ([`super::pre::preprocess_frame`]: feature words, incoming lists and their lengths, the
//! counters `RD_PRE` and `WR_PRE`), then the tile walk as above. An engine without one
//! (`pre_units` 0) ignores `PRE_CTRL`.
//!
//! Which core runs a tile only moves its scratch buffers: the reference uses sorting core
//! `t mod N` (the round-robin schedule) for tile `t`; the scratch contents are not part of the
//! outcome.

use super::adapt::{engine_passes, EnginePlan};
use super::memory::{
    Memory, TileDescriptor, TileResult, DESCRIPTOR_BYTES, ENTRY_BYTES, FEATURE_BYTES, PIXEL_BYTES,
    RESULT_BYTES,
};
use super::plan::{run_command, tile_plan, TilePlan};
use super::pre::{preprocess_frame, PreWork};
use super::regs::{Counter, Counters, FrameRegs, Reg, NO_OVERFLOW, STATUS_DONE, STATUS_OVERFLOW};
use super::EngineConfig;
use crate::pipeline::adaptive::{writeback_signals, WritebackSignals};
use crate::raster::window::table_window_order;
use crate::raster::{raster_tile, SubtileWork};
use crate::sort::{merge_pass_count, SortEntry, SortMode, Sorter};

/// What a frame leaves besides memory: the registers and the golden counters.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct FrameOutcome {
    /// Every tile's result (as written to memory).
    pub results: Vec<TileResult>,
    /// `STATUS` after the frame ([`STATUS_DONE`], plus [`STATUS_OVERFLOW`] when a tile
    /// overflowed).
    pub status: u32,
    /// `FIRST_OVERFLOW` ([`NO_OVERFLOW`] when none).
    pub first_overflow: u32,
    /// `OVERFLOWS`.
    pub overflows: u32,
    /// The counters; the cycle counters ([`Counter::is_golden`] false) are 0.
    pub counters: Counters,
}

impl FrameOutcome {
    /// The outcome as the engine reports it: `read_reg(offset)` reads a 32-bit control
    /// register (`STATUS`, `FIRST_OVERFLOW`, `OVERFLOWS` and both words of every counter), the
    /// results come from `mem` at `regs.result_base`.
    pub fn read_back(regs: &FrameRegs, mem: &Memory, mut read_reg: impl FnMut(u32) -> u32) -> FrameOutcome {
        let mut counters = Counters::default();
        for c in Counter::ALL {
            let lo = read_reg(c.offset()) as u64;
            let hi = read_reg(c.offset() + 4) as u64;
            counters.0[c.index()] = lo | hi << 32;
        }
        FrameOutcome {
            results: (0..regs.tiles as u64).map(|t| mem.read_result(regs.result_base, t)).collect(),
            status: read_reg(Reg::Status.offset()),
            first_overflow: read_reg(Reg::FirstOverflow.offset()),
            overflows: read_reg(Reg::Overflows.offset()),
            counters,
        }
    }
}

/// A frame the reference cannot run (bad data in memory or registers).
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("engine frame: tile {tile}: {problem}")]
pub struct FrameError {
    /// The tile index.
    pub tile: u64,
    /// What is wrong.
    pub problem: String,
}

/// Adds the raster counters of one tile of `len` table entries and `pixels` pixels: the table
/// and one feature word per entry read, every entry written back, every pixel written.
pub fn add_raster_traffic(c: &mut Counters, len: u64, pixels: u64) {
    c.add(Counter::TilesRastered, 1);
    c.add(Counter::EntriesRastered, len);
    c.add(Counter::RdTable, ENTRY_BYTES * len);
    c.add(Counter::RdFeat, FEATURE_BYTES * len);
    c.add(Counter::WrTable, ENTRY_BYTES * len);
    c.add(Counter::WrPixel, PIXEL_BYTES * pixels);
}

/// The closed-form sort traffic of one sorted tile (entries read, entries written) for a tile
/// whose sort keeps `next_len` entries: the conventional sort reads and writes the list once per
/// stage (`1 + merge_pass_count` stages); a reuse tile adds the DPS (the previous table read
/// and written once per pass) and the MERGE_DELETE (both inputs read, `next_len` written).
pub fn sort_traffic(d: &TileDescriptor, next_len: u64, chunk: u64) -> (u64, u64) {
    let n = d.list_len as u64;
    let conventional = if n == 0 { 0 } else { n * (1 + merge_pass_count(n, chunk)) };
    if d.from_scratch {
        return (conventional, conventional);
    }
    let prev = d.prev_len as u64;
    let dps = prev * d.passes();
    (conventional + dps + prev + n, conventional + dps + next_len)
}

/// Runs one frame on `mem` (see the module docs).
pub fn execute_frame(
    cfg: &EngineConfig,
    regs: &FrameRegs,
    mem: &mut Memory,
) -> Result<FrameOutcome, FrameError> {
    execute_frame_traced(cfg, regs, mem).map(|(out, _)| out)
}

/// [`execute_frame`], also returning the work of every tile (what the cycle model times).
pub fn execute_frame_traced(
    cfg: &EngineConfig,
    regs: &FrameRegs,
    mem: &mut Memory,
) -> Result<(FrameOutcome, FrameTrace), FrameError> {
    let mut run = FrameRun::new(cfg, regs);
    let mut trace = FrameTrace::default();
    if regs.pre.enabled() && cfg.has_preprocessing() {
        trace.pre = Some(preprocess_frame(cfg, regs, mem, &mut run.out.counters)?);
    }
    let planned = regs.adapt.enabled().then(|| engine_plan(cfg, regs, mem, &mut run.out.counters));
    trace.planned = planned.is_some();
    for t in 0..regs.tiles as u64 {
        let mut d = mem.read_descriptor(regs.desc_base, t);
        run.out.counters.add(Counter::RdDesc, DESCRIPTOR_BYTES);
        if let Some(plans) = &planned {
            // The walk reads the tile's previous result again and plans its passes.
            let p = plans[t as usize];
            (d.dps_passes, d.dps_wide) = (p.passes as u8, p.wide);
            run.out.counters.add(Counter::RdResult, RESULT_BYTES);
        }
        let (sorted, plan) = run.sort_tile(mem, t, &d)?;
        let (raster, wb) = run.raster_tile(mem, t, &d, sorted.next_len);
        let result = match sorted.overflow {
            true => TileResult::overflowed(),
            false => TileResult::new(sorted.next_len as u32, false, sorted.merge_inversions, &wb),
        };
        mem.write_result(regs.result_base, t, &result);
        run.out.counters.add(Counter::WrResult, RESULT_BYTES);
        run.out.results.push(result);
        trace.tiles.push(TileTrace { plan, next_len: sorted.next_len, raster });
    }
    let o = &mut run.out;
    o.status = STATUS_DONE | if o.overflows > 0 { STATUS_OVERFLOW } else { 0 };
    Ok((run.out, trace))
}

/// The frame controller's own plan ([`super::adapt`]): every tile's previous result read (the
/// scan) and the passes golden's policy grants.
fn engine_plan(
    cfg: &EngineConfig,
    regs: &FrameRegs,
    mem: &Memory,
    counters: &mut Counters,
) -> Vec<EnginePlan> {
    let prev: Vec<TileResult> =
        (0..regs.tiles as u64).map(|t| mem.read_result(regs.result_base, t)).collect();
    counters.add(Counter::RdResult, RESULT_BYTES * prev.len() as u64);
    engine_passes(&regs.adapt, cfg, &prev)
}

/// The work of one frame, tile by tile in descriptor order ([`execute_frame_traced`]).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct FrameTrace {
    /// The Preprocessing Engine's work, when it ran ([`super::PreRegs::enabled`]).
    pub pre: Option<PreWork>,
    /// Whether the frame controller planned the DPS passes ([`super::AdaptRegs::enabled`]: it
    /// read every previous result before the walk, and each again with its descriptor).
    pub planned: bool,
    /// One record per tile.
    pub tiles: Vec<TileTrace>,
}

/// The work of one tile: its sort's commands and its raster.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct TileTrace {
    /// The sort's command plan (no stage when the tile overflows).
    pub plan: TilePlan,
    /// Entries of the tile's next table (what its last command wrote).
    pub next_len: u64,
    /// The raster.
    pub raster: RasterTrace,
}

/// The work of one tile's raster.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct RasterTrace {
    /// Table entries read (and written back).
    pub len: u64,
    /// Of those, entries with a feature word present.
    pub present: u64,
    /// Per subtile (row-major): the SCU's work counters.
    pub subtiles: Vec<SubtileWork>,
    /// Per segment of `raster_feature_buffer` table entries (the raster core loads and walks
    /// the table a segment at a time): each subtile's share of the work.
    pub segments: Vec<SegmentWork>,
}

/// One raster segment's work, per subtile (row-major).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct SegmentWork {
    /// Table entries of the segment.
    pub entries: u32,
    /// Entries of the segment routed to each subtile.
    pub routed: Vec<u32>,
    /// Of those, the entries the subtile's SCU processed (before it terminated).
    pub processed: Vec<u32>,
}

/// Splits a tile's raster work into segments of `seg` table entries: `present[p]` says whether
/// table entry `p` has a feature word (the rasterised entries are those, in table order),
/// `bitmaps` their subtile bitmaps and `work` the subtiles' counters (an SCU processes the first
/// `processed` entries of its list).
pub fn segment_work(present: &[bool], bitmaps: &[u64], work: &[SubtileWork], seg: usize) -> Vec<SegmentWork> {
    let subtiles = work.len();
    let mut seen = vec![0u32; subtiles];
    let mut next = bitmaps.iter();
    present
        .chunks(seg.max(1))
        .map(|chunk| {
            let mut w = SegmentWork {
                entries: chunk.len() as u32,
                routed: vec![0; subtiles],
                processed: vec![0; subtiles],
            };
            for &m in chunk.iter().filter(|&&p| p).filter_map(|_| next.next()) {
                let mut m = m;
                while m != 0 {
                    let j = m.trailing_zeros() as usize;
                    w.routed[j] += 1;
                    if seen[j] < work[j].processed {
                        w.processed[j] += 1;
                    }
                    seen[j] += 1;
                    m &= m - 1;
                }
            }
            w
        })
        .collect()
}

/// One frame in progress.
struct FrameRun<'c> {
    cfg: &'c EngineConfig,
    regs: FrameRegs,
    sorter: Sorter,
    out: FrameOutcome,
}

impl<'c> FrameRun<'c> {
    fn new(cfg: &'c EngineConfig, regs: &FrameRegs) -> Self {
        let out = FrameOutcome { first_overflow: NO_OVERFLOW, ..FrameOutcome::default() };
        FrameRun { cfg, regs: *regs, sorter: Sorter::new(cfg.buffer_sort_config()), out }
    }

    /// The tile's sort (or its overflow): [`tile_plan`] executed command by command.
    fn sort_tile(
        &mut self,
        mem: &mut Memory,
        t: u64,
        d: &TileDescriptor,
    ) -> Result<(SortedTile, TilePlan), FrameError> {
        let core = t % self.cfg.sort_cores as u64;
        let plan = tile_plan(self.cfg, &self.regs, d, core);
        if plan.overflow {
            if self.out.overflows == 0 {
                self.out.first_overflow = t as u32;
            }
            self.out.overflows += 1;
            return Ok((SortedTile { overflow: true, ..SortedTile::default() }, plan));
        }
        let mut next_len = d.list_len as u64;
        let mut merge_inversions = 0;
        for c in plan.commands() {
            let e = run_command(&mut self.sorter, mem, c).map_err(|at| FrameError {
                tile: t,
                problem: format!(
                    "entry at 0x{at:x} carries the reserved id 0x{:x}",
                    self.cfg.format().id_max()
                ),
            })?;
            self.out.counters.add(Counter::RdSort, ENTRY_BYTES * e.read);
            self.out.counters.add(Counter::WrSort, ENTRY_BYTES * e.written);
            if c.mode == SortMode::MergeDelete {
                next_len = e.written;
                merge_inversions = e.a_inversions;
            }
        }
        self.out.counters.add(Counter::TilesSorted, 1);
        self.out.counters.add(Counter::EntriesSorted, d.entries_in());
        Ok((SortedTile { next_len, overflow: false, merge_inversions }, plan))
    }

    /// The tile's raster: table `next` of `len` entries, write-back in place, pixels tile-major;
    /// with the write-back's disorder signals.
    fn raster_tile(
        &mut self,
        mem: &mut Memory,
        t: u64,
        d: &TileDescriptor,
        len: u64,
    ) -> (RasterTrace, WritebackSignals) {
        let (sfmt, ffmt, rc) = (self.cfg.format(), self.cfg.feature_format(), self.cfg.raster_config());
        let mut table = mem.read_entries(&sfmt, d.next as u64, len as usize);
        let feat_word = self.regs.feat_base / FEATURE_BYTES;
        let mut feats: Vec<_> =
            table.iter().map(|e| mem.read_feature(&ffmt, feat_word + e.id as u64)).collect();
        if self.cfg.raster_window > 1 {
            // The reorder window: blended and written back in the order it emits.
            let order = table_window_order(&table, self.cfg.raster_window, |i| feats[i].map(|f| f.depth_key));
            table = order.iter().map(|&i| table[i as usize]).collect();
            feats = order.iter().map(|&i| feats[i as usize]).collect();
        }
        let present: Vec<_> = feats.iter().flatten().copied().collect();
        let (w, h) = (self.regs.width, self.regs.height);
        let r = raster_tile(&present, &ffmt, d.tile_x as u32, d.tile_y as u32, w, h, &rc);
        let mut j = 0;
        let back: Vec<SortEntry> = table
            .iter()
            .zip(&feats)
            .map(|(e, f)| match f {
                None => e.with_valid(false),
                Some(f) => {
                    j += 1;
                    SortEntry { valid: r.valid[j - 1], key: f.depth_key, id: e.id }
                }
            })
            .collect();
        mem.write_entries(&sfmt, d.next as u64, &back);
        // The signals of the entries as written (the key field's width).
        let wb = writeback_signals(&mem.read_entries(&sfmt, d.next as u64, back.len()));
        let pixels = (rc.tile * rc.tile) as u64;
        let base = self.regs.fb_base / PIXEL_BYTES + t * pixels;
        for (k, p) in r.pixels.iter().enumerate() {
            mem.write_pixel(base + k as u64, *p);
        }
        add_raster_traffic(&mut self.out.counters, len, pixels);
        let index: Vec<bool> = feats.iter().map(Option::is_some).collect();
        let segments = segment_work(&index, &r.bitmaps, &r.work, self.cfg.raster_feature_buffer);
        (RasterTrace { len, present: present.len() as u64, subtiles: r.work, segments }, wb)
    }
}

/// What a tile's sort left for its result.
#[derive(Clone, Copy, Debug, Default)]
struct SortedTile {
    /// Entries of the next table.
    next_len: u64,
    /// The tile overflowed (not sorted).
    overflow: bool,
    /// The MERGE_DELETE's boundary inversions of the reused table.
    merge_inversions: u64,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn segment_work_splits_routed_and_processed_entries_by_table_position() {
        // Table positions 0..4; position 1 has no feature word. Subtile 0's list is entries 0, 1
        // (it processed 1), subtile 1's entries 1, 2 (it processed both).
        let present = [true, false, true, true];
        let bitmaps = [0b01, 0b11, 0b10];
        let work = [
            SubtileWork { routed: 2, processed: 1, ..SubtileWork::default() },
            SubtileWork { routed: 2, processed: 2, ..SubtileWork::default() },
        ];
        let segs = segment_work(&present, &bitmaps, &work, 2);
        assert_eq!(segs.len(), 2);
        assert_eq!((segs[0].entries, &segs[0].routed, &segs[0].processed), (2, &vec![1, 0], &vec![1, 0]));
        assert_eq!((segs[1].entries, &segs[1].routed, &segs[1].processed), (2, &vec![1, 2], &vec![0, 2]));
    }
    use crate::sort::SortFormat;

    fn one_tile(mem: &mut Memory, list: &[SortEntry]) -> FrameRegs {
        let regs = FrameRegs {
            tiles: 1,
            width: 64,
            height: 64,
            desc_base: 0x1000,
            result_base: 0x2000,
            feat_base: 0x10_0000,
            fb_base: 0x20_0000,
            scratch_base: 0x100_0000,
            ..FrameRegs::default()
        };
        let d = TileDescriptor {
            from_scratch: true,
            list: 0x8000,
            list_len: list.len() as u32,
            next: 0x9000,
            ..TileDescriptor::default()
        };
        mem.write_descriptor(regs.desc_base, 0, &d);
        mem.write_entries(&SortFormat::ARTIFACT, 0x8000, list);
        regs
    }

    #[test]
    fn a_culled_list_sorts_and_clears_every_valid_bit() {
        let cfg = EngineConfig::default();
        let list: Vec<SortEntry> = (0..600u32).map(|i| SortEntry::new((i * 7919) % 1000, i)).collect();
        let mut mem = Memory::new();
        let regs = one_tile(&mut mem, &list);
        let out = execute_frame(&cfg, &regs, &mut mem).expect("frame");
        // No entry is valid after the write-back: no write-back signal; from scratch, no merge.
        assert_eq!(out.results, vec![TileResult { next_len: 600, ..TileResult::default() }]);
        let table = mem.read_entries(&SortFormat::ARTIFACT, 0x9000, 600);
        let mut want = list.clone();
        want.sort_by_key(|e| e.order_key());
        // No feature is present: every entry keeps its key and loses its valid bit.
        assert_eq!(table, want.iter().map(|e| e.with_valid(false)).collect::<Vec<_>>());
        // 600 entries: 3 chunks, 2 merge passes, so 3 stages of 600 entries.
        assert_eq!(out.counters.get(Counter::RdSort), 8 * 3 * 600);
        assert_eq!(out.counters.get(Counter::RdFeat), 32 * 600);
        assert_eq!(out.counters.get(Counter::WrPixel), 4 * 4096);
        assert_eq!(mem.read_pixel(0x20_0000 / 4 + 4095), [0; 3]);
        assert_eq!(out.status, STATUS_DONE);
    }

    #[test]
    fn the_trace_holds_each_tiles_plan_and_raster_work() {
        let cfg = EngineConfig::default();
        let list: Vec<SortEntry> = (0..600u32).map(|i| SortEntry::new((i * 7919) % 1000, i)).collect();
        let mut mem = Memory::new();
        let regs = one_tile(&mut mem, &list);
        let d = mem.read_descriptor(regs.desc_base, 0);
        let (out, trace) = execute_frame_traced(&cfg, &regs, &mut mem).expect("frame");
        assert_eq!(trace.tiles.len(), 1);
        let t = &trace.tiles[0];
        assert_eq!(t.plan, tile_plan(&cfg, &regs, &d, 0));
        assert_eq!(t.next_len, 600);
        assert_eq!(t.raster.len, out.counters.get(Counter::EntriesRastered));
        assert_eq!(t.raster.present, 0, "no feature word is present");
        assert_eq!(t.raster.subtiles.len() as u64, (cfg.tile as u64 / cfg.subtile as u64).pow(2));
    }

    #[test]
    fn the_reserved_id_is_an_error_naming_the_tile() {
        let cfg = EngineConfig::default();
        let mut mem = Memory::new();
        let regs = one_tile(&mut mem, &[SortEntry::new(1, SortFormat::ARTIFACT.id_max())]);
        let e = execute_frame(&cfg, &regs, &mut mem).expect_err("reserved id");
        assert_eq!(e.tile, 0);
        assert!(e.to_string().contains("reserved id"), "{e}");
    }

    #[test]
    fn read_back_assembles_registers_and_results() {
        let mut mem = Memory::new();
        let regs = FrameRegs { tiles: 2, result_base: 0x100, ..FrameRegs::default() };
        let r = TileResult { next_len: 9, overflow: true, merge_inversions: 3, wb_len: 4, wb_reach: 5 };
        mem.write_result(0x100, 1, &r);
        let out = FrameOutcome::read_back(&regs, &mem, |a| match a {
            0x004 => 6,
            0x040 => 1,
            0x044 => 1,
            a if a == Counter::WrPixel.offset() + 4 => 2,
            _ => 0,
        });
        assert_eq!(out.results[1], r);
        assert_eq!((out.status, out.first_overflow, out.overflows), (6, 1, 1));
        assert_eq!(out.counters.get(Counter::WrPixel), 2 << 32);
    }
}
