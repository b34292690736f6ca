//! The scheduler: which job runs next on an idle agent, under the dependencies of the module
//! docs of [`super`].

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use neo_golden::pipeline::Strategy;

use super::{Accel, Model, CLASS_PRE, CLASS_SORT, K_PRE, K_RASTER, K_SORT, K_UPDATE};
use crate::dram::Ps;
use crate::engine::{Job, JobTag, Scheduler};

/// Per-frame event times.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FrameTimes {
    /// Preprocessing started.
    pub pre_start: Ps,
    /// Preprocessing ended.
    pub pre_done: Ps,
    /// Last sort of the frame ended.
    pub sort_done: Ps,
    /// Last raster of the frame ended: the frame is complete.
    pub done: Ps,
}

/// The scheduler of a [`Model`] (see the module docs for the rules).
pub struct Sched<'m, 'a> {
    m: &'m Model<'a>,
    frames: usize,
    tiles: usize,
    pre_next: usize,
    pre_running: bool,
    pre_done: Vec<bool>,
    times: Vec<FrameTimes>,
    sort_queued: Vec<bool>,
    raster_done: Vec<bool>,
    /// The tile's table is ready for the next frame's sort (raster done, and Neo-S's update).
    reused_ready: Vec<bool>,
    bg_done: Vec<bool>,
    raster_left: Vec<usize>,
    sort_left: Vec<usize>,
    frame_done: Vec<bool>,
    bg_left: usize,
    sort_ready: BinaryHeap<Reverse<(u32, u32)>>,
    bg_ready: BinaryHeap<Reverse<(u32, u32)>>,
    raster_ready: BinaryHeap<Reverse<(u32, u32)>>,
    update_ready: BinaryHeap<Reverse<(u32, u32)>>,
    update_left: usize,
    offsets: Vec<Option<Vec<u64>>>,
    bg_offsets: Vec<Option<Vec<u64>>>,
    background: Option<usize>,
}

impl<'m, 'a> Sched<'m, 'a> {
    pub(super) fn new(m: &'m Model<'a>) -> Self {
        let frames = m.wl.frames.len();
        let tiles = m.wl.info.grid[0] as usize * m.wl.info.grid[1] as usize;
        let background = match (m.accel, m.strategy) {
            (Accel::Neo, Strategy::Background(k)) => Some(k),
            _ => None,
        };
        Sched {
            m,
            frames,
            tiles,
            pre_next: 0,
            pre_running: false,
            pre_done: vec![false; frames],
            times: vec![FrameTimes::default(); frames],
            sort_queued: vec![false; frames * tiles],
            raster_done: vec![false; frames * tiles],
            reused_ready: vec![false; frames * tiles],
            bg_done: vec![false; frames * tiles],
            raster_left: vec![tiles; frames],
            sort_left: vec![tiles; frames],
            frame_done: vec![false; frames],
            bg_left: if background.is_some() { frames * tiles } else { 0 },
            sort_ready: BinaryHeap::new(),
            bg_ready: BinaryHeap::new(),
            raster_ready: BinaryHeap::new(),
            update_ready: BinaryHeap::new(),
            update_left: 0,
            offsets: vec![None; frames],
            bg_offsets: vec![None; frames],
            background,
        }
    }

    /// Per-frame times (valid after the run).
    pub fn times(&self) -> &[FrameTimes] {
        &self.times
    }

    /// True when a tile's table is refreshed by an update pass after its raster (Neo-S).
    fn updates(&self) -> bool {
        matches!(self.m.accel, Accel::NeoS { .. }) && self.m.reuses()
    }

    fn sort_deps_met(&self, f: usize, t: usize) -> bool {
        if !self.pre_done[f] {
            return false;
        }
        let i = f * self.tiles + t;
        if f >= 2 && !self.raster_done[i - 2 * self.tiles] {
            return false;
        }
        if f >= 1 && self.m.reuses() && !self.reused_ready[i - self.tiles] {
            return false;
        }
        if let Some(k) = self.background {
            let s = self.m.shot_start[f];
            if f > s {
                let src = f.saturating_sub(k).max(s);
                if !self.bg_done[src * self.tiles + t] {
                    return false;
                }
            }
        }
        true
    }

    fn try_queue_sort(&mut self, f: usize, t: usize) {
        if f >= self.frames {
            return;
        }
        let i = f * self.tiles + t;
        if !self.sort_queued[i] && self.sort_deps_met(f, t) {
            self.sort_queued[i] = true;
            self.sort_ready.push(Reverse((f as u32, t as u32)));
        }
    }

    fn offsets_of(&mut self, f: usize, bg: bool) -> &[u64] {
        let m = self.m;
        let slot = if bg { &mut self.bg_offsets[f] } else { &mut self.offsets[f] };
        slot.get_or_insert_with(|| {
            let mut acc = 0;
            m.wl.frames[f]
                .tiles
                .iter()
                .map(|t| {
                    let o = acc;
                    acc += if bg { t.background_n as u64 } else { m.list_len(t) };
                    o
                })
                .collect()
        })
    }
}

impl Scheduler for Sched<'_, '_> {
    fn next_job(&mut self, agent: usize, class: u8, t: Ps) -> Option<Job> {
        match class {
            CLASS_PRE => {
                let f = self.pre_next;
                if self.pre_running || f >= self.frames {
                    return None;
                }
                let fb = self.m.cfg.neo.frame_buffers as usize;
                if f >= fb && !self.frame_done[f - fb] {
                    return None;
                }
                self.pre_running = true;
                self.times[f].pre_start = t;
                Some(self.m.preprocess_job(f))
            }
            CLASS_SORT => {
                // An update pass before the sorts of later frames (they wait for it).
                let update_first = match (self.update_ready.peek(), self.sort_ready.peek()) {
                    (Some(Reverse((fu, _))), Some(Reverse((fs, _)))) => fu < fs,
                    (Some(_), None) => true,
                    _ => false,
                };
                if update_first {
                    let Reverse((f, tile)) = self.update_ready.pop()?;
                    return Some(self.m.update_job(f as usize, tile as usize));
                }
                if let Some(Reverse((f, tile))) = self.sort_ready.pop() {
                    let off = self.offsets_of(f as usize, false)[tile as usize];
                    return Some(self.m.sort_job(f as usize, tile as usize, agent, off));
                }
                if let Some(Reverse((f, tile))) = self.bg_ready.pop() {
                    let off = self.offsets_of(f as usize, true)[tile as usize];
                    return Some(self.m.background_job(f as usize, tile as usize, agent, off));
                }
                None
            }
            _ => {
                let Reverse((f, tile)) = self.raster_ready.pop()?;
                Some(self.m.raster_job(f as usize, tile as usize))
            }
        }
    }

    fn job_done(&mut self, tag: JobTag, t: Ps) {
        let (f, tile) = (tag.frame as usize, tag.tile as usize);
        match tag.kind {
            K_PRE => {
                self.pre_running = false;
                self.pre_done[f] = true;
                self.times[f].pre_done = t;
                self.pre_next += 1;
                for tt in 0..self.tiles {
                    self.try_queue_sort(f, tt);
                    if self.background.is_some() {
                        self.bg_ready.push(Reverse((f as u32, tt as u32)));
                    }
                }
            }
            K_SORT => {
                self.raster_ready.push(Reverse((tag.frame, tag.tile)));
                self.sort_left[f] -= 1;
                if self.sort_left[f] == 0 {
                    self.times[f].sort_done = t;
                }
            }
            K_RASTER => {
                self.raster_done[f * self.tiles + tile] = true;
                self.raster_left[f] -= 1;
                if self.raster_left[f] == 0 {
                    self.frame_done[f] = true;
                    self.times[f].done = t;
                }
                if self.updates() {
                    self.update_ready.push(Reverse((tag.frame, tag.tile)));
                    self.update_left += 1;
                } else {
                    self.reused_ready[f * self.tiles + tile] = true;
                    self.try_queue_sort(f + 1, tile);
                }
                self.try_queue_sort(f + 2, tile);
            }
            K_UPDATE => {
                self.reused_ready[f * self.tiles + tile] = true;
                self.update_left -= 1;
                self.try_queue_sort(f + 1, tile);
            }
            _ => {
                self.bg_done[f * self.tiles + tile] = true;
                self.bg_left -= 1;
                if let Some(k) = self.background {
                    for g in f..(f + k + 1).min(self.frames) {
                        self.try_queue_sort(g, tile);
                    }
                }
            }
        }
    }

    fn finished(&self) -> bool {
        self.frame_done.iter().all(|&d| d) && self.bg_left == 0 && self.update_left == 0
    }
}
