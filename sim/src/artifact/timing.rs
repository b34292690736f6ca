//! The official artifact simulator's timing, restated on neo's DRAM model: what its cycle count
//! would be with neo's LPDDR4 model in place of Ramulator.
//!
//! The structure follows the artifact's documented behaviour
//! (`../shared/reference/artifact/README.md` and the published source's state machines):
//! - a 1 GHz core and the DRAM's clock; a *request list* is a set of line requests. At every
//!   DRAM clock each pending list, oldest first, offers its next requests until its channel's
//!   queue refuses one (no outstanding limit). A read list is finished when every read's data has
//!   returned, a write list when every write has entered a queue;
//! - the **common phase**: frustum culling reads, then the projection loads, then the
//!   projection stores, then the duplication writes, each waiting for the previous; then 8
//!   global sorters take tiles in Morton order: approximation passes (one list each, in
//!   sequence), then the precise sort's chunks in a load / sort / store pipeline that advances
//!   when every stage is done (sort: `depth x chunk` cycles);
//! - the **reuse phase**, from cycle 0: 8 adaptive sorters take tiles in Morton order and run
//!   their reused chunks through the same kind of pipeline;
//! - the **render phase**: a tile is queued once both its sorts are done; 4 renderers run its
//!   chunks through order load / feature gather / render (one cycle per set subtile bit) /
//!   order store.
//!
//! The frame ends when all three phases are done. Addresses follow the artifact's layout
//! (`config.artifact_constants`), so row hits are comparable.

use neo_golden::engine::memory::FEATURE_BYTES;
use std::collections::VecDeque;

use super::poc::PocFrame;
use super::waterfall::{pre_engine_lines, tile_pixels};
use super::{approx_passes, ArtifactSizes, Rules};
use crate::config::DramConfig;
use crate::dram::{Ps, Ticket};
use crate::dram_stream::QueueFeeder;

/// Byte bases of the artifact's regions (`config.artifact_constants`).
#[derive(Clone, Copy, Debug)]
pub struct ArtifactLayout {
    /// FP16 positions.
    pub positions: u64,
    /// Other parameters.
    pub others: u64,
    /// This frame's feature entries.
    pub features: u64,
    /// Per-tile reuse regions.
    pub reuse: u64,
    /// Per-tile incoming-list regions.
    pub new: u64,
    /// Entries per tile region (`MAX_GAUSSIAN_IN_TILE`).
    pub tile_entries: u64,
    /// The frame buffer (not in the artifact; for the waterfall's frame-buffer step).
    pub frame_buffer: u64,
    /// This frame's and the previous frame's feature words of the RTL Preprocessing Engine
    /// (not in the artifact; for the waterfall's last step).
    pub pre_features: [u64; 2],
    /// The RTL Preprocessing Engine's incoming-list slots (idem).
    pub pre_lists: u64,
    /// The tile descriptors, where it writes the lists' lengths (idem).
    pub pre_descriptors: u64,
}

impl Default for ArtifactLayout {
    fn default() -> Self {
        ArtifactLayout {
            positions: 0,
            others: 50_331_648,
            features: 150_994_944,
            reuse: 201_326_592,
            new: 251_658_240,
            tile_entries: 8198,
            frame_buffer: 0x4000_0000,
            pre_features: [0x1_0000_0000, 0x1_4000_0000],
            pre_lists: 0x1_8000_0000,
            pre_descriptors: 0x5000_0000,
        }
    }
}

/// Core clock period (1 GHz).
const CORE_PS: Ps = 1000;
/// Global and adaptive sorters, renderers (`NEO.yaml`).
const SORTERS: usize = 8;
const RENDERERS: usize = 4;
/// `SortGranularity`.
const SORT_GRANULARITY: u64 = 16;

/// Cycles of the in-chunk merge passes for `n` entries: `max(1, ceil(log2(n / 16))) x n`.
pub fn sort_cycles(n: u64) -> u64 {
    let q = n / SORT_GRANULARITY;
    let depth = if n <= SORT_GRANULARITY || q <= 1 { 1 } else { (64 - (q - 1).leading_zeros()) as u64 };
    depth * n
}

struct List {
    addrs: Vec<u64>,
    write: bool,
    sent: usize,
    tickets: Vec<Ticket>,
    retry_at: Ps,
    /// The latest data time of the reads resolved so far.
    last: Ps,
    done_at: Option<Ps>,
}

/// The request lists in flight over the DRAM model.
struct Wrapper {
    feeder: QueueFeeder,
    lists: Vec<Option<List>>,
    active: Vec<usize>,
}

type ListId = usize;

/// A request list to open: its line addresses and whether it writes.
type ReqList = (Vec<u64>, bool);

impl Wrapper {
    fn open(&mut self, addrs: Vec<u64>, write: bool) -> ListId {
        let done_at = addrs.is_empty().then_some(0);
        self.lists.push(Some(List {
            addrs,
            write,
            sent: 0,
            tickets: Vec::new(),
            retry_at: 0,
            last: 0,
            done_at,
        }));
        let id = self.lists.len() - 1;
        if done_at.is_none() {
            self.active.push(id);
        }
        id
    }

    /// One DRAM clock at `t`: every pending list offers requests until refused.
    fn tick(&mut self, t: Ps) {
        let mut i = 0;
        while i < self.active.len() {
            let id = self.active[i];
            let l = self.lists[id].as_mut().expect("active list");
            while l.sent < l.addrs.len() && l.retry_at <= t {
                let a = l.addrs[l.sent];
                let c = self.feeder.channel(a);
                let room = if l.write { self.feeder.write_room(t, c) } else { self.feeder.read_room(t, c) };
                match room {
                    Ok(()) => {
                        if l.write {
                            self.feeder.write(t, a);
                        } else {
                            l.tickets.push(self.feeder.submit_read(t, a));
                        }
                        l.sent += 1;
                    }
                    Err(next) => l.retry_at = next,
                }
            }
            if l.sent == l.addrs.len() && l.retry_at <= t {
                // A read list is done when every read's data time is known as of `t` (no channel
                // is advanced past `t`, so later requests of other lists enter in order).
                let f = &mut self.feeder;
                let mut wait = Ps::MAX;
                l.tickets.retain(|&k| match f.dram.poll(k, t) {
                    Ok(a) => {
                        l.last = l.last.max(a);
                        f.dram.release(k);
                        false
                    }
                    Err(later) => {
                        wait = wait.min(later);
                        true
                    }
                });
                if l.tickets.is_empty() {
                    l.done_at = Some(l.last.max(t));
                    self.active.remove(i);
                    continue;
                }
                l.retry_at = wait;
            }
            i += 1;
        }
    }

    fn finished(&self, id: ListId, now: Ps) -> bool {
        self.lists[id].as_ref().and_then(|l| l.done_at).is_some_and(|d| d <= now)
    }
}

/// One stage of a chunk: a request list or some compute cycles.
enum Work {
    Read(Vec<u64>),
    Write(Vec<u64>),
    Compute(u64),
}

/// What occupies a pipeline slot.
enum Busy {
    List(ListId),
    Until(Ps),
}

/// A tile's chunks through a lockstep pipeline: when every occupied stage is done, each chunk
/// moves one stage on and the next chunk enters the first stage (the artifact's sorters and
/// renderers).
struct Pipeline {
    chunks: VecDeque<Vec<Work>>,
    slots: Vec<Option<(Busy, Vec<Work>)>>,
}

impl Pipeline {
    fn new(chunks: Vec<Vec<Work>>, stages: usize) -> Self {
        Pipeline { chunks: chunks.into(), slots: (0..stages).map(|_| None).collect() }
    }

    fn start(w: &mut Wrapper, now: Ps, mut rest: Vec<Work>) -> (Busy, Vec<Work>) {
        let work = rest.remove(0);
        let busy = match work {
            Work::Read(a) => Busy::List(w.open(a, false)),
            Work::Write(a) => Busy::List(w.open(a, true)),
            Work::Compute(c) => Busy::Until(now + c * CORE_PS),
        };
        (busy, rest)
    }

    /// Advances at core time `now`; true when the tile is done.
    fn step(&mut self, w: &mut Wrapper, now: Ps) -> bool {
        let done = |b: &Busy| match *b {
            Busy::List(id) => w.finished(id, now),
            Busy::Until(t) => t <= now,
        };
        if !self.slots.iter().flatten().all(|(b, _)| done(b)) {
            return false;
        }
        if self.chunks.is_empty() && self.slots.iter().all(Option::is_none) {
            return true;
        }
        for k in (0..self.slots.len()).rev() {
            let moving = self.slots[k].take();
            if let Some((_, rest)) = moving {
                if k + 1 < self.slots.len() {
                    self.slots[k + 1] = Some(Self::start(w, now, rest));
                }
            }
        }
        if let Some(c) = self.chunks.pop_front() {
            self.slots[0] = Some(Self::start(w, now, c));
        }
        false
    }
}

/// The artifact's address of a tile's region.
fn tile_base(base: u64, t: usize, l: &ArtifactLayout, s: &ArtifactSizes) -> u64 {
    base + t as u64 * l.tile_entries * s.entry
}

fn align(a: u64, s: &ArtifactSizes) -> u64 {
    a / s.line * s.line
}

/// Tiles in the artifact's Morton order.
fn morton_tiles(f: &PocFrame) -> Vec<usize> {
    let tw = f.width.div_ceil(f.tile) as u64;
    let th = f.height.div_ceil(f.tile) as u64;
    let decode = |m: u64, shift: u32| (0..32).fold(0u64, |acc, i| acc | ((m >> (2 * i + shift)) & 1) << i);
    let mut out = Vec::with_capacity((tw * th) as usize);
    let mut m = 0u64;
    while out.len() < (tw * th) as usize {
        let (x, y) = (decode(m, 0), decode(m, 1));
        if x < tw && y < th {
            out.push((y * tw + x) as usize);
        }
        m += 1;
    }
    out
}

/// The artifact's frame on neo's DRAM model, its requests as `r` charges them.
struct Frame<'a> {
    f: &'a PocFrame,
    s: ArtifactSizes,
    l: ArtifactLayout,
    r: Rules,
}

impl Frame<'_> {
    /// Lines of a contiguous list of `bytes` from `base`: rounded down (the artifact) or up.
    fn lines(&self, base: u64, bytes: u64) -> Vec<u64> {
        let s = &self.s;
        let n = if self.r.round_up { bytes.div_ceil(s.line) } else { bytes / s.line };
        (0..n).map(|i| align(base, s) + i * s.line).collect()
    }

    /// Feature-entry bytes.
    fn feature_bytes(&self) -> u64 {
        self.r.neo_sizes.map_or(self.s.feature, |n| n.feature)
    }

    /// The lines one feature entry of Gaussian `id` costs: its first, and its second when it
    /// straddles and straddles are charged.
    fn feature_lines(&self, id: u64, out: &mut Vec<u64>) {
        if self.r.pre_engine {
            // The RTL's 32-byte feature word of Gaussian `id`: within one line.
            out.push(align(self.l.pre_features[0] + FEATURE_BYTES * id, &self.s));
            return;
        }
        let (s, fb) = (&self.s, self.feature_bytes());
        let at = self.l.features + id * fb;
        out.push(align(at, s));
        if self.r.straddle && align(at + fb - 1, s) != align(at, s) {
            out.push(align(at, s) + s.line);
        }
    }

    fn preprocess_lists(&self) -> Vec<ReqList> {
        let (f, s, l) = (self.f, &self.s, &self.l);
        if let (true, Some(n)) = (self.r.pre_engine, self.r.neo_sizes) {
            // The RTL Preprocessing Engine's transfers (as the waterfall's last step charges them).
            let pre = pre_engine_lines(f, l, n.sh_degree, s.line);
            return vec![(pre.params, false), (pre.previous, false), (pre.features, true), (pre.lists, true)];
        }
        let visible: Vec<usize> = (0..f.culled.len()).filter(|&i| !f.culled[i]).collect();
        let geometry = self.r.neo_sizes.map_or(s.position, |n| n.geometry);
        let cull = self.lines(l.positions, f.culled.len() as u64 * geometry);
        let load = match self.r.neo_sizes {
            // neo's parameters: the SH records of the visible Gaussians as one stream, as neo's
            // model and the waterfall charge them (for whole-line records such as 192 bytes this
            // is every line each record touches; the SH bytes follow the scene's degree).
            Some(n) => self.lines(l.others, visible.len() as u64 * n.sh),
            None => {
                let per = s.others.div_ceil(s.line);
                visible
                    .iter()
                    .flat_map(|&i| {
                        (0..per).map(move |j| align(l.others + i as u64 * s.others, s) + j * s.line)
                    })
                    .collect()
            }
        };
        let store = if self.r.feature_stream {
            self.lines(l.features, visible.len() as u64 * self.feature_bytes())
        } else {
            let mut v = Vec::new();
            for &i in &visible {
                self.feature_lines(i as u64, &mut v);
            }
            v
        };
        vec![(cull, false), (load, false), (store, true), (self.duplication(), true)]
    }

    /// The duplication writes: three lines per incoming pair (the artifact), or each tile's
    /// list of sort entries written contiguously.
    fn duplication(&self) -> Vec<u64> {
        let (f, s, l) = (self.f, &self.s, &self.l);
        let mut dup = Vec::new();
        let mut filled = vec![0u64; f.tiles.len()];
        let mut at = 0usize;
        for (g, &n) in f.incoming_tiles.iter().enumerate() {
            let tiles = &f.incoming_list[at..at + n as usize];
            at += n as usize;
            if f.culled[g] {
                continue;
            }
            for &t in tiles {
                let base = tile_base(l.new, t as usize, l, s);
                if !self.r.dup_entries {
                    dup.extend([
                        align(base, s),
                        align(base, s),
                        align(base + filled[t as usize] * s.entry, s),
                    ]);
                }
                filled[t as usize] += 1;
            }
        }
        if self.r.dup_entries {
            for (t, &n) in filled.iter().enumerate() {
                dup.extend(self.lines(tile_base(l.new, t, l, s), n * s.entry));
            }
        }
        dup
    }

    /// The incoming sort of tile `t`: its approximation lists, then its precise chunks.
    fn global_sort(&self, t: usize) -> (Vec<ReqList>, Vec<Vec<Work>>) {
        let s = &self.s;
        let n = self.f.tiles[t].new as u64;
        let base = tile_base(self.l.new, t, &self.l, s);
        let list = || self.lines(base, n * s.entry);
        let passes = approx_passes(n, s.global_chunk);
        let mut approx = vec![(list(), false)];
        for k in 0..2 * passes - 1 {
            approx.push((list(), k % 2 == 0));
        }
        let chunks = (0..n)
            .step_by(s.global_chunk as usize)
            .map(|a| {
                let c = (n - a).min(s.global_chunk);
                let store = if self.r.precise_store { self.lines(base, c * s.entry) } else { Vec::new() };
                vec![
                    Work::Read(self.lines(base, c * s.entry)),
                    Work::Compute(sort_cycles(c)),
                    Work::Write(store),
                ]
            })
            .collect();
        (approx, chunks)
    }

    /// DPS of tile `t`'s reused entries; with the merge fused, the first chunk also reads the
    /// sorted incoming list and the last writes the merged table (the other chunks write
    /// nothing).
    fn adaptive_sort(&self, t: usize) -> Vec<Vec<Work>> {
        let (s, l) = (&self.s, &self.l);
        let tile = &self.f.tiles[t];
        let m = tile.reused as u64;
        let base = tile_base(l.reuse, t, l, s);
        let starts: Vec<u64> = (0..m).step_by(s.adaptive_chunk as usize).collect();
        let last = starts.len().saturating_sub(1);
        starts
            .iter()
            .enumerate()
            .map(|(k, &a)| {
                let c = (m - a).min(s.adaptive_chunk);
                let lines = self.lines(base, c * s.entry);
                if !self.r.merge_fused {
                    return vec![
                        Work::Read(lines.clone()),
                        Work::Compute(sort_cycles(c)),
                        Work::Write(lines),
                    ];
                }
                let mut read = lines;
                if k == 0 {
                    read.extend(self.lines(tile_base(l.new, t, l, s), tile.new as u64 * s.entry));
                }
                let write =
                    if k == last { self.lines(base, tile.count() as u64 * s.entry) } else { Vec::new() };
                vec![Work::Read(read), Work::Compute(sort_cycles(c)), Work::Write(write)]
            })
            .collect()
    }

    /// The render of tile `t` (with the frame buffer, its pixels written after the last chunk).
    fn render(&self, t: usize) -> Vec<Vec<Work>> {
        let (s, l) = (&self.s, &self.l);
        let tile = &self.f.tiles[t];
        let base = tile_base(l.new, t, l, s);
        let n = tile.count() as usize;
        let rc = s.render_chunk as usize;
        let mut chunks: Vec<Vec<Work>> = (0..n)
            .step_by(rc)
            .map(|a| {
                let e = (a + rc).min(n);
                let order = self.lines(base, (e - a) as u64 * s.entry);
                let mut feats = Vec::with_capacity(e - a);
                for &id in &tile.ids[a..e] {
                    self.feature_lines(id as u64, &mut feats);
                }
                let bits: u64 = tile.entry_bits[a..e].iter().map(|&b| b as u64).sum();
                vec![Work::Read(order.clone()), Work::Read(feats), Work::Compute(bits), Work::Write(order)]
            })
            .collect();
        if let Some(px) = self.r.frame_buffer {
            let tile_bytes = (self.f.tile as u64).pow(2) * px;
            let pixels = self.lines(l.frame_buffer + t as u64 * tile_bytes, tile_pixels(self.f, t) * px);
            match chunks.last_mut() {
                Some(c) => {
                    if let Work::Write(w) = &mut c[3] {
                        w.extend(pixels);
                    }
                }
                None => chunks.push(vec![
                    Work::Read(Vec::new()),
                    Work::Read(Vec::new()),
                    Work::Compute(0),
                    Work::Write(pixels),
                ]),
            }
        }
        chunks
    }
}

/// The artifact's frame timed on neo's DRAM model.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ArtifactTiming {
    /// Core cycles (1 GHz) until the frame is done.
    pub core_cycles: u64,
    /// Reads the DRAM model served.
    pub reads: u64,
    /// Writes it took.
    pub writes: u64,
}

/// A global sorter's tile: approximation lists in sequence, then the precise pipeline.
enum Global {
    Approx { tile: usize, rest: VecDeque<ReqList>, cur: ListId, chunks: Vec<Vec<Work>> },
    Precise { tile: usize, p: Pipeline },
}

/// Per-tile completion of the two sorts, and the render queue they feed.
struct Ready {
    common: Vec<bool>,
    reuse: Vec<bool>,
    queue: VecDeque<usize>,
}

impl Ready {
    fn mark(&mut self, t: usize, common: bool) {
        if common {
            self.common[t] = true;
        } else {
            self.reuse[t] = true;
        }
        if self.common[t] && self.reuse[t] {
            self.queue.push_back(t);
        }
    }
}

/// Runs one trace frame the artifact's way on the DRAM model of `cfg`.
pub fn artifact_timing(f: &PocFrame, sizes: &ArtifactSizes, cfg: &DramConfig) -> ArtifactTiming {
    artifact_timing_with(f, sizes, &Rules::default(), cfg)
}

/// Runs one trace frame with the artifact's structure and the requests `rules` charge.
pub fn artifact_timing_with(
    f: &PocFrame,
    sizes: &ArtifactSizes,
    rules: &Rules,
    cfg: &DramConfig,
) -> ArtifactTiming {
    let fr = Frame { f, s: *sizes, l: ArtifactLayout::default(), r: *rules };
    let tiles = f.tiles.len();
    let order = morton_tiles(f);
    let mut w = Wrapper { feeder: QueueFeeder::new(cfg), lists: Vec::new(), active: Vec::new() };
    let mut pre: VecDeque<ReqList> = fr.preprocess_lists().into();
    let (a, wr) = pre.pop_front().expect("the preprocessing lists");
    let mut pre_cur = Some(w.open(a, wr));
    let mut global: Vec<Option<Global>> = (0..SORTERS).map(|_| None).collect();
    let mut adaptive: Vec<Option<(usize, Pipeline)>> = (0..SORTERS).map(|_| None).collect();
    let mut renderers: Vec<Option<Pipeline>> = (0..RENDERERS).map(|_| None).collect();
    let mut ready = Ready { common: vec![false; tiles], reuse: vec![false; tiles], queue: VecDeque::new() };
    let (mut global_next, mut adaptive_next, mut rendered) = (0usize, 0usize, 0usize);
    let ck = cfg.t_ck_ps;
    let (mut dram_t, mut core_t, mut cycle) = (0 as Ps, 0 as Ps, 0u64);
    loop {
        if dram_t <= core_t {
            w.tick(dram_t);
            dram_t += ck;
            continue;
        }
        cycle += 1;
        core_t += CORE_PS;
        let now = core_t;
        // Common phase: the preprocessing lists in sequence, then the global sorters.
        if let Some(id) = pre_cur {
            if w.finished(id, now) {
                pre_cur = pre.pop_front().map(|(a, wr)| w.open(a, wr));
            }
        }
        if pre_cur.is_none() {
            for slot in global.iter_mut() {
                step_global(slot, &fr, &mut w, &mut ready, now, &order, &mut global_next);
            }
        }
        for slot in adaptive.iter_mut() {
            if slot.is_none() && adaptive_next < tiles {
                let t = order[adaptive_next];
                adaptive_next += 1;
                *slot = Some((t, Pipeline::new(fr.adaptive_sort(t), 3)));
            }
            if let Some((t, p)) = slot {
                if p.step(&mut w, now) {
                    ready.mark(*t, false);
                    *slot = None;
                }
            }
        }
        for slot in renderers.iter_mut() {
            if slot.is_none() {
                if let Some(t) = ready.queue.pop_front() {
                    *slot = Some(Pipeline::new(fr.render(t), 4));
                }
            }
            if let Some(p) = slot {
                if p.step(&mut w, now) {
                    rendered += 1;
                    *slot = None;
                }
            }
        }
        if rendered == tiles {
            break;
        }
    }
    let st = w.feeder.dram.stats();
    ArtifactTiming { core_cycles: cycle, reads: st.reads, writes: st.writes }
}

fn step_global(
    slot: &mut Option<Global>,
    fr: &Frame<'_>,
    w: &mut Wrapper,
    ready: &mut Ready,
    now: Ps,
    order: &[usize],
    next: &mut usize,
) {
    if slot.is_none() && *next < order.len() {
        let t = order[*next];
        *next += 1;
        if fr.f.tiles[t].new == 0 {
            ready.mark(t, true);
            return;
        }
        let (approx, chunks) = fr.global_sort(t);
        let mut rest: VecDeque<_> = approx.into();
        let (a, wr) = rest.pop_front().expect("a first approximation load");
        *slot = Some(Global::Approx { tile: t, cur: w.open(a, wr), rest, chunks });
        return;
    }
    match slot {
        Some(Global::Approx { tile, rest, cur, chunks }) if w.finished(*cur, now) => match rest.pop_front() {
            Some((a, wr)) => *cur = w.open(a, wr),
            None => {
                let p = Pipeline::new(std::mem::take(chunks), 3);
                *slot = Some(Global::Precise { tile: *tile, p });
            }
        },
        Some(Global::Precise { tile, p }) => {
            let done = p.step(w, now).then_some(*tile);
            if let Some(t) = done {
                ready.mark(t, true);
                *slot = None;
            }
        }
        _ => {}
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sort_cycles_follow_the_artifact() {
        assert_eq!(sort_cycles(256), 1024);
        assert_eq!(sort_cycles(16), 16);
        assert_eq!(sort_cycles(100), 300);
        assert_eq!(sort_cycles(1), 1);
    }

    /// Every step of the waterfall issues, in the timing restatement, exactly the bytes the
    /// waterfall charges (the two read the same rules).
    #[test]
    fn each_waterfall_step_times_the_bytes_it_charges() {
        use crate::artifact::waterfall::{test_frame, waterfall, NeoSizes};
        let s = ArtifactSizes::default();
        let neo = NeoSizes { geometry: 44, sh: 192, feature: 31, pixel: 3, sh_degree: 3 };
        // A frame that reuses tables (previous words read) and one sorted from scratch.
        let scratch = PocFrame { tiles: vec![test_frame().tiles[0].clone(); 2], ..test_frame() };
        for f in [test_frame(), scratch] {
            let steps = waterfall(&f, &s, &neo);
            for (k, step) in steps.iter().enumerate() {
                let t = artifact_timing_with(&f, &s, &Rules::step(k, &neo), &DramConfig::default());
                assert_eq!((t.reads + t.writes) * s.line, step.bytes.total(), "step {k}: {}", step.name);
                assert!(t.core_cycles > 0);
            }
        }
    }

    #[test]
    fn morton_order_skips_tiles_outside_the_image() {
        let f = PocFrame { width: 192, height: 128, tile: 64, ..PocFrame::default() };
        // 3 x 2 tiles: Morton (0,0) (1,0) (0,1) (1,1) (2,0) (2,1) skipping (3,0) (3,1).
        assert_eq!(morton_tiles(&f), [0, 1, 3, 4, 2, 5]);
    }
}
