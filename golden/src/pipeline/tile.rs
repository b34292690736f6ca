//! The per-tile sorting step of every strategy ([`super::strategy`]) and the per-tile state
//! carried from frame to frame.
//!
//! # Per-tile sets and counts
//! For tile `t` at frame `f`: `S` is the current list (the Gaussians whose feature entry
//! [`crate::raster::touches_tile`], with their current keys, ascending id), `V` the ids whose
//! entry is valid in the tile's previous, written-back table (the Gaussians the previous frame's
//! raster found touching the tile, minus capacity drops). Then ([`TileCounts`]):
//! `incoming = |S \ V|`, `retained = |S ∩ V|`, `outgoing = |V \ S|` for every strategy; the
//! retention of Fig. 6 is `retained / |S|`.

use std::collections::VecDeque;

use super::adaptive::{TilePlan, WritebackSignals};
use super::hierarchical::hierarchical_sort;
use super::order::OrderScratch;
use super::strategy::Strategy;
use super::work::StageWork;
use crate::sort::{SortConfig, SortEntry, Sorter, TileSorter, UpdateConfig};

/// What one tile carries from frame to frame.
#[derive(Clone, Debug, Default)]
pub struct TileState {
    /// The table rastered this frame; after the write-back, the next frame's reused table
    /// (depth keys of the current frame unless the strategy freezes them, ITU valid bits).
    pub table: Vec<SortEntry>,
    /// `background:K`: exact tables of the last frames, `(frame, table)`, oldest first.
    background: VecDeque<(usize, Vec<SortEntry>)>,
    /// This frame's plan, set by the frame driver before the sort (`adaptive`, `motion`).
    pub plan: TilePlan,
    /// The last write-back's disorder signals (of the table the next frame reuses).
    pub writeback: WritebackSignals,
    /// The MSU+ boundary inversions of the last sort (0 after a sort from scratch).
    pub merge_inversions: u32,
}

impl TileState {
    /// Valid entries of the table.
    pub fn valid_len(&self) -> usize {
        self.table.iter().filter(|e| e.valid).count()
    }
}

/// Per-tile counts of one frame (see the module docs).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TileCounts {
    /// `|S|`: Gaussians touching the tile now.
    pub current: u32,
    /// `|S \ V|`.
    pub incoming: u32,
    /// `|S ∩ V|`.
    pub retained: u32,
    /// `|V \ S|`.
    pub outgoing: u32,
    /// Entries of the rastered table.
    pub table_len: u32,
    /// Entries of the rastered table taken over from a reused table (0 for a sort from
    /// scratch).
    pub reused: u32,
    /// Entries of the rastered table that are not in `S` (left the tile or culled; the raster
    /// clears their valid bit).
    pub stale: u32,
    /// Entries removed by the capacity cut.
    pub dropped_capacity: u32,
    /// Chunks DPS touched.
    pub dps_chunks: u32,
    /// Set bits over the subtile bitmaps of the rastered table (filled by the raster phase).
    pub bitmap_popcount: u32,
    /// DPS passes run on the tile.
    pub dps_passes: u32,
    /// Whether those passes used the wide chunk (`adaptive` with `wide > 1`).
    pub dps_wide: bool,
    /// MSU+ boundary inversions of the reused stream ([`crate::sort::MergeStats::a_inversions`]).
    pub merge_inversions: u32,
    /// Write-back descents of the rastered table against the current keys (filled at the
    /// write-back; see [`super::adaptive::WritebackSignals`]).
    pub wb_descents: u32,
    /// Write-back entries behind the running maximum.
    pub wb_behind: u32,
    /// Write-back reach.
    pub wb_reach: u32,
}

/// What the sorting step tells the frame driver about one tile.
#[derive(Clone, Debug, Default)]
pub struct TileSortOutput {
    /// Counts (the bitmap popcount is filled later).
    pub counts: TileCounts,
    /// Work counters.
    pub work: StageWork,
    /// True when the tile was sorted from scratch this frame.
    pub from_scratch: bool,
}

/// A set of ids with O(1) membership, cleared in O(1) by a stamp.
#[derive(Clone, Debug, Default)]
pub struct IdMarks {
    stamp: Vec<u32>,
    current: u32,
}

impl IdMarks {
    /// Clears the set.
    pub fn clear(&mut self) {
        self.current = self.current.wrapping_add(1);
        if self.current == 0 {
            self.stamp.fill(0);
            self.current = 1;
        }
    }

    /// Adds `id`.
    #[inline]
    pub fn insert(&mut self, id: u32) {
        let i = id as usize;
        if i >= self.stamp.len() {
            self.stamp.resize((i + 1).next_power_of_two(), 0);
        }
        self.stamp[i] = self.current;
    }

    /// Whether `id` is in the set.
    #[inline]
    pub fn contains(&self, id: u32) -> bool {
        self.stamp.get(id as usize).is_some_and(|&s| s == self.current && s != 0)
    }
}

/// Per-thread buffers of the sorting step (no allocation per tile once warm).
#[derive(Clone, Debug)]
pub struct TileCtx {
    /// Reuse-and-update with the strategy's DPS passes (0 for periodic and background).
    pub updater: TileSorter,
    /// Conventional sorts from scratch (full-frame and background sorts; capacity applied
    /// separately).
    pub scratch_sorter: TileSorter,
    /// Sorting Core for the hierarchical model.
    pub sorter: Sorter,
    /// Ids valid in the previous table.
    pub prev: IdMarks,
    /// Other id sets.
    pub marks: IdMarks,
    /// The incoming list of the tile.
    pub incoming: Vec<SortEntry>,
    /// Scratch table.
    pub table: Vec<SortEntry>,
    /// Bins of the hierarchical model.
    pub bins: Vec<Vec<SortEntry>>,
    /// Order comparison buffers.
    pub order: OrderScratch,
}

impl TileCtx {
    /// Buffers for `strategy` with sorting parameters `sort`, `dps_passes` and `capacity`.
    pub fn new(strategy: Strategy, sort: &SortConfig, dps_passes: usize, capacity: usize) -> Self {
        let passes = if matches!(strategy, Strategy::Neo | Strategy::Adaptive(_)) { dps_passes } else { 0 };
        let mut updater = TileSorter::new(UpdateConfig { sort: sort.clone(), capacity, dps_passes: passes });
        if let Strategy::Adaptive(p) = strategy {
            if p.wide > 1 {
                // A chunk times a power of two is a valid chunk; were it not, no wide chunk.
                let _ = updater.set_wide_chunk(sort.chunk() * p.wide as usize);
            }
        }
        let scratch_sorter = TileSorter::new(UpdateConfig { sort: sort.clone(), capacity, dps_passes: 0 });
        TileCtx {
            updater,
            scratch_sorter,
            sorter: Sorter::new(sort.clone()),
            prev: IdMarks::default(),
            marks: IdMarks::default(),
            incoming: Vec::new(),
            table: Vec::new(),
            bins: Vec::new(),
            order: OrderScratch::default(),
        }
    }

    fn capacity(&self) -> usize {
        self.updater.config().capacity
    }
}

/// Where a frame sits in its shot, for the sorting step.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FramePos {
    /// Frame index in the trajectory (sets the DPS parity).
    pub frame: usize,
    /// First frame of the current shot (0 or the last cut at or before `frame`).
    pub shot_start: usize,
}

/// The sorting step of one tile: replaces `state.table` by the table to raster this frame, from
/// the current list `current` (ascending ids, current keys, all valid).
pub fn sort_tile(
    strategy: Strategy,
    pos: FramePos,
    state: &mut TileState,
    current: &[SortEntry],
    ctx: &mut TileCtx,
) -> TileSortOutput {
    let mut out = TileSortOutput::default();
    let c = &mut out.counts;
    c.current = current.len() as u32;
    // V: ids valid in the previous table.
    ctx.prev.clear();
    let mut v_len = 0u32;
    for e in state.table.iter().filter(|e| e.valid) {
        ctx.prev.insert(e.id);
        v_len += 1;
    }
    ctx.incoming.clear();
    ctx.incoming.extend(current.iter().filter(|e| !ctx.prev.contains(e.id)));
    c.incoming = ctx.incoming.len() as u32;
    c.retained = c.current - c.incoming;
    c.outgoing = v_len - c.retained;

    let plan = std::mem::take(&mut state.plan);
    let from_scratch = strategy == Strategy::Hierarchical
        || strategy.full_sort_at(pos.frame, pos.shot_start)
        || plan == TilePlan::Resort;
    out.from_scratch = from_scratch;
    let w = &mut out.work;
    if strategy == Strategy::Hierarchical {
        let hw = hierarchical_sort(current, &mut state.table, &mut ctx.sorter, &mut ctx.bins);
        w.add_hier(&hw);
        let cap = ctx.capacity();
        let dropped = state.table.len().saturating_sub(cap);
        state.table.truncate(cap);
        w.dropped_capacity += dropped as u64;
        w.binned_written += current.len() as u64;
    } else if from_scratch {
        let uw = ctx.scratch_sorter.full_frame_sort(current, &mut state.table);
        w.add_update(&uw);
        w.binned_written += current.len() as u64;
        if let Strategy::Background(_) = strategy {
            state.background.clear();
            state.background.push_back((pos.frame, state.table.clone()));
        }
    } else {
        match strategy {
            Strategy::Neo | Strategy::Periodic(_) | Strategy::Adaptive(_) | Strategy::Motion(_) => {
                let passes = plan.passes_or(ctx.updater.config().dps_passes);
                let frame = pos.frame as u64;
                let uw =
                    ctx.updater.update_wide(&mut state.table, &ctx.incoming, frame, passes, plan.is_wide());
                w.add_update(&uw);
                w.binned_written += ctx.incoming.len() as u64;
                c.dps_chunks = uw.dps.chunk.chunks as u32;
                c.dps_passes = uw.dps.passes as u32;
                c.dps_wide = plan.is_wide();
                c.merge_inversions = uw.merge.a_inversions as u32;
            }
            Strategy::Background(k) => background_step(k, pos, state, current, ctx, w),
            Strategy::Full | Strategy::Hierarchical => unreachable!("sorted from scratch above"),
        }
    }
    state.merge_inversions = out.counts.merge_inversions;
    // Composition of the rastered table.
    let c = &mut out.counts;
    c.table_len = state.table.len() as u32;
    c.dropped_capacity = out.work.dropped_capacity as u32;
    ctx.marks.clear();
    for e in current {
        ctx.marks.insert(e.id);
    }
    c.stale = state.table.iter().filter(|e| !ctx.marks.contains(e.id)).count() as u32;
    if !from_scratch {
        // Incoming entries are never in V; for background the reused table is the background
        // one, whose entries are the non-incoming ones too.
        ctx.marks.clear();
        for e in &ctx.incoming {
            ctx.marks.insert(e.id);
        }
        c.reused = state.table.iter().filter(|e| !ctx.marks.contains(e.id)).count() as u32;
    }
    out
}

/// `background:K` on a frame after the shot start: the exact table of frame `max(f - K, s)`,
/// filtered to the current list, merged with the newly visible Gaussians; then the background
/// sorter's exact sort of this frame for later frames.
fn background_step(
    k: usize,
    pos: FramePos,
    state: &mut TileState,
    current: &[SortEntry],
    ctx: &mut TileCtx,
    w: &mut StageWork,
) {
    let source = pos.frame.saturating_sub(k).max(pos.shot_start);
    while state.background.len() > 1 && state.background.front().is_some_and(|(f, _)| *f < source) {
        state.background.pop_front();
    }
    // Filter: valid iff still in the current list; incoming: current entries not in it.
    ctx.marks.clear();
    for e in current {
        ctx.marks.insert(e.id);
    }
    ctx.table.clear();
    let mut bg_ids = IdMarks::default();
    std::mem::swap(&mut bg_ids, &mut ctx.prev);
    bg_ids.clear();
    if let Some((_, bg)) = state.background.front() {
        for e in bg {
            ctx.table.push(e.with_valid(ctx.marks.contains(e.id)));
            bg_ids.insert(e.id);
        }
    }
    ctx.incoming.clear();
    ctx.incoming.extend(current.iter().filter(|e| !bg_ids.contains(e.id)));
    std::mem::swap(&mut bg_ids, &mut ctx.prev);
    let uw = ctx.updater.update(&mut ctx.table, &ctx.incoming, pos.frame as u64);
    w.add_update(&uw);
    w.binned_written += ctx.incoming.len() as u64;
    std::mem::swap(&mut state.table, &mut ctx.table);
    // The background sorter sorts this frame's list for frame f + K.
    let mut sorted = Vec::with_capacity(current.len());
    let bw = ctx.scratch_sorter.full_frame_sort(current, &mut sorted);
    w.add_background(&bw.incoming_sort);
    state.background.push_back((pos.frame, sorted));
}

/// The exact table of a tile: `current` by THE ORDER `(key, id)`, cut to `capacity`.
pub fn exact_table(current: &[SortEntry], capacity: usize, out: &mut Vec<SortEntry>) {
    out.clear();
    out.extend_from_slice(current);
    out.sort_unstable_by_key(SortEntry::order_key);
    out.truncate(capacity);
}

#[cfg(test)]
mod tests {
    use super::*;

    fn e(key: u32, id: u32) -> SortEntry {
        SortEntry::new(key, id)
    }

    fn ctx(s: Strategy) -> TileCtx {
        TileCtx::new(s, &SortConfig::artifact(), 1, usize::MAX)
    }

    fn exact(current: &[SortEntry]) -> Vec<SortEntry> {
        let mut v = Vec::new();
        exact_table(current, usize::MAX, &mut v);
        v
    }

    #[test]
    fn neo_inserts_incoming_and_counts_sets() {
        let s = Strategy::Neo;
        let mut c = ctx(s);
        let mut st = TileState::default();
        let f0 = [e(5, 1), e(3, 2), e(9, 3)];
        let o = sort_tile(s, FramePos { frame: 0, shot_start: 0 }, &mut st, &f0, &mut c);
        assert!(o.from_scratch);
        assert_eq!(st.table, exact(&f0));
        assert_eq!((o.counts.incoming, o.counts.retained, o.counts.reused), (3, 0, 0));
        // Raster write-back: Gaussian 3 left the tile.
        for t in st.table.iter_mut() {
            t.valid = t.id != 3;
        }
        let f1 = [e(5, 1), e(4, 2), e(1, 7)];
        let o = sort_tile(s, FramePos { frame: 1, shot_start: 0 }, &mut st, &f1, &mut c);
        assert!(!o.from_scratch);
        // Keys of 1 and 2 are the written-back (stale) ones: 3 and 5.
        assert_eq!(st.table, vec![e(1, 7), e(3, 2), e(5, 1)]);
        let k = o.counts;
        assert_eq!((k.current, k.incoming, k.retained, k.outgoing), (3, 1, 2, 0));
        assert_eq!((k.table_len, k.reused, k.stale), (3, 2, 0));
        assert_eq!(o.work.dropped_invalid, 1);
        assert_eq!(o.work.dps_passes, 1);
        assert_eq!(o.work.binned_written, 1);
    }

    #[test]
    fn stale_entries_stay_until_the_raster_clears_them() {
        let s = Strategy::Neo;
        let mut c = ctx(s);
        let mut st = TileState::default();
        sort_tile(s, FramePos { frame: 0, shot_start: 0 }, &mut st, &[e(1, 1), e(2, 2)], &mut c);
        // Gaussian 2 still valid from the last raster but not touching now.
        let o = sort_tile(s, FramePos { frame: 1, shot_start: 0 }, &mut st, &[e(1, 1)], &mut c);
        assert_eq!(st.table.len(), 2);
        assert_eq!((o.counts.stale, o.counts.outgoing, o.counts.incoming), (1, 1, 0));
    }

    #[test]
    fn background_uses_the_order_of_k_frames_earlier() {
        let s = Strategy::Background(2);
        let mut c = ctx(s);
        let mut st = TileState::default();
        // Keys of Gaussians 1 and 2 swap order every frame; 9 appears at frame 3.
        let frames: Vec<Vec<SortEntry>> = vec![
            vec![e(1, 1), e(2, 2)],
            vec![e(2, 1), e(1, 2)],
            vec![e(1, 1), e(2, 2)],
            vec![e(2, 1), e(1, 2), e(0, 9)],
        ];
        let mut orders = Vec::new();
        for (f, cur) in frames.iter().enumerate() {
            let o = sort_tile(s, FramePos { frame: f, shot_start: 0 }, &mut st, cur, &mut c);
            orders.push(st.table.iter().map(|e| e.id).collect::<Vec<u32>>());
            if f > 0 {
                assert!(o.work.background_entries_sorted > 0);
            }
        }
        // Frame 0: exact. Frame 1: lag 1 (shot start) -> frame 0's order. Frame 2: frame 0's.
        // Frame 3: frame 1's order [2, 1], with 9 (key 0) merged in front.
        assert_eq!(orders, vec![vec![1, 2], vec![1, 2], vec![1, 2], vec![9, 2, 1]]);
    }

    #[test]
    fn periodic_freezes_between_refreshes() {
        let s = Strategy::Periodic(2);
        let mut c = ctx(s);
        let mut st = TileState::default();
        let a = [e(1, 1), e(2, 2)];
        let b = [e(2, 1), e(1, 2)];
        sort_tile(s, FramePos { frame: 0, shot_start: 0 }, &mut st, &a, &mut c);
        let o = sort_tile(s, FramePos { frame: 1, shot_start: 0 }, &mut st, &b, &mut c);
        assert_eq!(o.work.dps_passes, 0);
        assert_eq!(st.table.iter().map(|e| e.id).collect::<Vec<_>>(), vec![1, 2]);
        let o = sort_tile(s, FramePos { frame: 2, shot_start: 0 }, &mut st, &b, &mut c);
        assert!(o.from_scratch);
        assert_eq!(st.table, exact(&b));
    }

    #[test]
    fn hierarchical_and_full_are_exact_with_capacity() {
        let cur: Vec<SortEntry> = (0..1000u32).map(|i| e((i * 7919) % 613, i)).collect();
        for s in [Strategy::Full, Strategy::Hierarchical] {
            let mut c = TileCtx::new(s, &SortConfig::artifact(), 1, 700);
            let mut st = TileState::default();
            for f in 0..2 {
                let o = sort_tile(s, FramePos { frame: f, shot_start: 0 }, &mut st, &cur, &mut c);
                let mut x = Vec::new();
                exact_table(&cur, 700, &mut x);
                assert_eq!(st.table, x, "{s}");
                assert_eq!(o.counts.dropped_capacity, 300);
            }
        }
    }

    #[test]
    fn id_marks_clear_by_stamp() {
        let mut m = IdMarks::default();
        m.clear();
        m.insert(5);
        assert!(m.contains(5) && !m.contains(4) && !m.contains(1 << 20));
        m.clear();
        assert!(!m.contains(5));
    }
}
