//! Neo and the GSCore-style baseline on the engine: the address map, the jobs each engine runs
//! per frame and tile, and the scheduler with the real dependencies between them.
//!
//! # Engines and jobs
//! - **Preprocessing** (one agent): per frame, reads every Gaussian's geometry and the SH of the
//!   visible ones, writes the feature table and the per-tile lists (Neo: incoming lists; GSCore:
//!   every pair, with its subtile bitmap). Compute: the slowest of projection, colour and
//!   duplication units (assumed timing).
//! - **Sorting** (`sort_cores` agents): per tile, the sorting-core commands of the strategy
//!   ([`crate::sortcmd`]), each a segment timed by `latency.json`: Neo's DPS (the last pass
//!   fused with the MSU+ insert/delete merge when `fused_dps_merge`), conventional sorts of the
//!   incoming lists, or, from scratch, of the whole list; GSCore's hierarchical sort (an
//!   approximate binning pass, then one on-chip sort per bin).
//! - **Raster** (`raster_cores` agents): per tile, reads the sorted table and gathers the
//!   features, runs the ITU/SCU pipeline over subtile groups, writes the depth keys and valid
//!   bits back (Neo) and the tile's pixels.
//!
//! # Dependencies
//! - preprocessing of frame `f` after that of `f - 1` and after every raster of frame
//!   `f - frame_buffers` (its feature table and lists are double-buffered);
//! - sorting of tile `(f, t)` after preprocessing of `f`, after the raster of `(f - 2, t)` (tables
//!   are double-buffered) and, when the strategy reuses tables (Neo hardware), after the raster
//!   of `(f - 1, t)`, whose write-back it reads; `background:K` also after the background sort of
//!   the frame whose order it uses;
//! - the raster of `(f, t)` after its sort.
//!
//! Ready jobs run in (frame, tile) order on the first idle agent of their engine; background
//! sorts run on idle sorting cores after every ready foreground sort.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use neo_golden::pipeline::Strategy;
use neo_golden::sort::Parity;

use crate::config::{RasterTiming, SimConfig};
use crate::dram::Ps;
use crate::engine::{Access, AccessKind, AgentSpec, Job, JobTag, Scheduler, Segment};
use crate::latency::Latency;
use crate::sortcmd::{conventional_sort, dps_pass, Cmd, Mode};
use crate::traffic::Stage;
use crate::workload::{TileWork, Workload};

/// Agent classes.
pub const CLASS_PRE: u8 = 0;
/// Sorting cores.
pub const CLASS_SORT: u8 = 1;
/// Raster cores.
pub const CLASS_RASTER: u8 = 2;

const K_PRE: u8 = 0;
const K_SORT: u8 = 1;
const K_RASTER: u8 = 2;
const K_BG: u8 = 3;

/// Which accelerator.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Accel {
    /// Neo (the workload's strategy on Neo's hardware).
    Neo,
    /// GSCore-style with `cores` sorting cores and `cores` subtile units.
    Gscore {
        /// Core count.
        cores: u32,
    },
}

/// The raster core's cycles for one tile of `table_len` entries, `entries` of them with a
/// feature entry. The ITUs test every table entry against all subtiles of the tile at once,
/// `itus` per cycle, once per subtile group (`ceil(table_len / itus) * itu_ii` per group, Fig. 14:
/// they test the next group while the SCUs blend the current one; skipped when the bitmaps come
/// from memory, `itu = false`); the SCUs take the subtiles in groups of `scus`, each SCU blending
/// its subtile's routed entries: `processed * scu_ii + (routed - processed) * drain_ii`, with
/// `processed = ceil(routed * ratio)` (early termination). A group lasts as long as its slowest
/// SCU.
///
/// With the measured raster core's shape (`rt.pixel_write_cycles > 0`, from
/// `reports/latency.json`): the loads (`load_cycles_per_entry` per table entry) come first, then
/// `max(ITU walk, busiest SCU, pixel writes)` (the RTL's SCUs are decoupled by their routing
/// FIFOs, so an SCU's cost is the sum over its subtiles of all groups; a lower bound when the
/// busiest SCU changes from group to group by more than a FIFO's worth), and `tile_overhead`
/// (the empty tile) holds the latencies and the pixel writes. The ITUs walk every quad for group
/// 0 and, for a later group, a cycle finding the first quad that touches it plus those quads
/// (at least one; estimated from the group's busiest subtile). A table longer than
/// `rt.feature_buffer` is processed segment by segment, each segment loaded once (into a bank,
/// while the previous segment is walked and blended) and walked for every group (the SCUs save
/// and resume their subtiles' pixel state between segments): after the first segment's loads,
/// each segment costs `max(the sum over groups of max(its walk, the segment's share of the
/// group's slowest SCU), the memory port: the segment's write-back and the next segment's
/// loads)` (the routing FIFOs do not hide a busy subtile behind the next group's walk) plus
/// `segment_overhead`. Returns (total, tail after the last input arrives).
#[allow(clippy::too_many_arguments)]
pub fn raster_tile_cycles(
    routed: &[u32],
    ratio: f64,
    entries: u32,
    table_len: u32,
    rt: &RasterTiming,
    itus: u32,
    scus: u32,
    itu: bool,
) -> (f64, f64) {
    let cost = |r: u32| {
        let p = (r as f64 * ratio).ceil().min(r as f64);
        p * rt.scu_cycles_per_pair + (r as f64 - p) * rt.scu_drain_ii
    };
    let groups: Vec<f64> =
        routed.chunks(scus.max(1) as usize).map(|g| g.iter().map(|&r| cost(r)).fold(0.0, f64::max)).collect();
    let scu_total: f64 = groups.iter().sum();
    let tail = groups.last().copied().unwrap_or(0.0) + rt.scu_latency as f64;
    let len = if itu { table_len.max(entries) } else { entries };
    let walk = if itu { (len as f64 / itus.max(1) as f64).ceil().max(1.0) * rt.itu_ii } else { 0.0 };
    let itu_total = walk * groups.len().max(1) as f64;
    let total = if rt.pixel_write_cycles == 0 {
        let lat =
            if itu { rt.itu_latency as f64 } else { 0.0 } + rt.scu_latency as f64 + rt.tile_overhead as f64;
        rt.load_cycles_per_entry * len as f64 + itu_total.max(scu_total) + lat
    } else {
        let load = rt.load_cycles_per_entry * len as f64;
        let pix = rt.pixel_write_cycles as f64;
        let segmented = rt.feature_buffer > 0 && len as u64 > rt.feature_buffer;
        // Quad skipping: group 0 walks every quad; a later group walks, after a cycle finding the
        // first, only the quads that touch it: with `n_g` of the table's entries touching the
        // group (at least its busiest subtile's), a fraction `1 - (1 - n_g / len)^itus` of them.
        let hit: Vec<f64> = routed
            .chunks(scus.max(1) as usize)
            .map(|g| {
                let n_g = g.iter().copied().max().unwrap_or(0) as f64;
                1.0 - (1.0 - (n_g / len.max(1) as f64).min(1.0)).powi(itus.max(1) as i32)
            })
            .collect();
        let walk_of = |n: f64| -> Vec<f64> {
            let quads = (n / itus.max(1) as f64).ceil().max(1.0);
            hit.iter()
                .enumerate()
                .map(|(k, &h)| if k == 0 { quads } else { 1.0 + (h * quads).max(1.0) } * rt.itu_ii)
                .collect()
        };
        let body = if segmented {
            // Banks: segment s + 1 loads while segment s is walked and blended. Per segment, a
            // group takes the longer of its walk and its slowest SCU's share (the walk of the
            // next group waits for FIFO space); the port carries the segment's write-back and the
            // next segment's loads.
            let f = rt.feature_buffer;
            let segs = (len as u64).div_ceil(f);
            let n_of = |s: u64| (len as u64 - s * f).min(f) as f64;
            let mut body = rt.load_cycles_per_entry * n_of(0) + segs as f64 * rt.segment_overhead;
            for s in 0..segs {
                let n = n_of(s);
                let work: f64 =
                    walk_of(n).iter().zip(&groups).map(|(&w, &g)| w.max(g * n / len as f64)).sum();
                let next = if s + 1 < segs { rt.load_cycles_per_entry * n_of(s + 1) } else { 0.0 };
                body += work.max(next + n);
            }
            body.max(load + pix)
        } else {
            // One segment: each SCU runs through its subtiles of every group, decoupled from the
            // others by its routing FIFO, so the blending takes the busiest SCU's sum.
            let walks: f64 = walk_of(len as f64).iter().sum();
            load + walks.max(busiest_scu(routed, scus, &cost)).max(pix)
        };
        body - pix + rt.tile_overhead as f64
    };
    (total, tail.min(total))
}

/// The busiest SCU's blending: SCU `j` takes subtiles `j, j + scus, ...` (one per group), each
/// costing `cost(routed)`.
fn busiest_scu(routed: &[u32], scus: u32, cost: &dyn Fn(u32) -> f64) -> f64 {
    let s = scus.max(1) as usize;
    (0..s).map(|j| routed.iter().skip(j).step_by(s).map(|&r| cost(r)).sum::<f64>()).fold(0.0, f64::max)
}

const MB: u64 = 1 << 20;

fn region(next: &mut u64, bytes: u64) -> u64 {
    let base = *next;
    *next += bytes.div_ceil(MB).max(1) * MB;
    base
}

/// Where everything lives in DRAM.
#[derive(Clone, Debug)]
struct Layout {
    geometry: u64,
    sh: u64,
    features: [u64; 2],
    lists: [u64; 2],
    bg_lists: [u64; 2],
    tables: [u64; 2],
    bg_tables: [u64; 2],
    slot: u64,
    scratch: u64,
    scratch_part: u64,
    framebuffer: u64,
}

/// The model of one accelerator on one workload.
pub struct Model<'a> {
    accel: Accel,
    cfg: &'a SimConfig,
    lat: &'a Latency,
    wl: &'a Workload,
    raster: RasterTiming,
    strategy: Strategy,
    /// Sort entry bytes as stored (GSCore: with the bitmap).
    eb: u64,
    fb: u64,
    line: u64,
    cyc: f64,
    layout: Layout,
    sort_cores: u32,
    raster_cores: u32,
    scus_per_core: u32,
    itus_per_core: u32,
    hier: bool,
    shot_start: Vec<usize>,
}

fn round_ps(cycles: f64, cyc: f64) -> Ps {
    (cycles * cyc).round().max(0.0) as Ps
}

impl<'a> Model<'a> {
    /// The model of `accel` running `wl`.
    pub fn new(accel: Accel, cfg: &'a SimConfig, lat: &'a Latency, wl: &'a Workload) -> Result<Self, String> {
        let strategy: Strategy = wl.info.strategy.parse().map_err(|e: String| e)?;
        let (eb, sort_cores, raster_cores, scus_per_core, itus_per_core, hier) = match accel {
            Accel::Neo => (
                wl.info.sort_entry_bytes as u64,
                cfg.neo.sort_cores,
                cfg.neo.raster_cores,
                cfg.neo.scus_per_core,
                cfg.neo.itus_per_core,
                strategy == Strategy::Hierarchical,
            ),
            Accel::Gscore { cores } => (
                (wl.info.sort_entry_bytes + cfg.gscore.bitmap_bytes) as u64,
                cores,
                cores.div_ceil(4).max(1),
                cores.min(4),
                0,
                true,
            ),
        };
        if hier && wl.frames.iter().any(|f| f.tiles.iter().any(|t| t.hier.entries != t.current)) {
            return Err(
                "the workload has no hierarchical-sort record (generate it with hierarchical on)".into()
            );
        }
        cfg.check_buffers(eb as u32)?;
        if wl.info.chunk != cfg.pipeline.chunk {
            return Err(format!(
                "workload chunk {} differs from the configuration's pipeline.chunk {}",
                wl.info.chunk, cfg.pipeline.chunk
            ));
        }
        let line = cfg.dram.line_bytes as u64;
        let fb = wl.info.feature_entry_bytes as u64;
        let max_table = wl.max_table_len().max(wl.max_sort_len()) as u64;
        let max_sort = wl.max_sort_len() as u64;
        let tiles = wl.info.grid[0] as u64 * wl.info.grid[1] as u64;
        let max_visible = wl.frames.iter().map(|f| f.visible).max().unwrap_or(0);
        let max_lists = wl
            .frames
            .iter()
            .map(|f| f.tiles.iter().map(|t| t.current.max(t.sort_n) as u64).sum::<u64>())
            .max()
            .unwrap_or(0);
        let slot = (max_table * eb).div_ceil(4096).max(1) * 4096;
        let scratch_part = (max_sort.max(max_table) * eb).div_ceil(4096).max(1) * 4096;
        let g = wl.info.gaussians;
        let mut next = 0;
        let layout = Layout {
            geometry: region(&mut next, g * cfg.sizes.gaussian_geometry_bytes as u64),
            sh: region(&mut next, g * cfg.sizes.gaussian_sh_bytes as u64),
            features: [region(&mut next, max_visible * fb), region(&mut next, max_visible * fb)],
            lists: [region(&mut next, max_lists * eb), region(&mut next, max_lists * eb)],
            bg_lists: [region(&mut next, max_lists * eb), region(&mut next, max_lists * eb)],
            tables: [region(&mut next, tiles * slot), region(&mut next, tiles * slot)],
            bg_tables: [region(&mut next, tiles * slot), region(&mut next, tiles * slot)],
            slot,
            scratch: region(&mut next, sort_cores as u64 * 3 * scratch_part),
            scratch_part,
            framebuffer: region(
                &mut next,
                wl.info.width as u64 * wl.info.height as u64 * cfg.sizes.pixel_bytes as u64,
            ),
        };
        let mut shot_start = Vec::with_capacity(wl.frames.len());
        let mut s = 0;
        for (i, f) in wl.frames.iter().enumerate() {
            if i == 0 || f.cut {
                s = i;
            }
            shot_start.push(s);
        }
        // The simulated core's feature buffer is half the architecture's raster buffer (the other
        // half double-buffers the prefetch) when that is larger than the measured RTL's
        // (`raster.core.feature_buffer`); the RTL structure of the rest of the raster timing is
        // kept.
        let mut raster = lat.raster.clone();
        if raster.feature_buffer > 0 {
            raster.feature_buffer = raster.feature_buffer.max(cfg.neo.raster_buffer_bytes / 2 / fb.max(1));
        }
        Ok(Model {
            accel,
            cfg,
            lat,
            wl,
            raster,
            strategy,
            eb,
            fb,
            line,
            cyc: cfg.cycle_ps(),
            layout,
            sort_cores,
            raster_cores,
            scus_per_core,
            itus_per_core,
            hier,
            shot_start,
        })
    }

    /// The agents: preprocessing, sorting cores, raster cores.
    pub fn agents(&self) -> Vec<AgentSpec> {
        let n = &self.cfg.neo;
        let mut v = vec![AgentSpec { class: CLASS_PRE, window: n.preprocess_read_window, overlap: false }];
        for _ in 0..self.sort_cores {
            v.push(AgentSpec {
                class: CLASS_SORT,
                window: n.sort_read_window,
                overlap: n.double_buffered_io,
            });
        }
        let rwin = ((n.raster_buffer_bytes / 2 / self.line).max(1) as u32).min(n.raster_read_window);
        for _ in 0..self.raster_cores {
            v.push(AgentSpec { class: CLASS_RASTER, window: rwin, overlap: false });
        }
        v
    }

    /// The scheduler for this model.
    pub fn scheduler(&self) -> Sched<'_, 'a> {
        Sched::new(self)
    }

    fn ps(&self, cycles: f64) -> Ps {
        round_ps(cycles, self.cyc)
    }

    fn sort_port(&self) -> Ps {
        // One entry per cycle (latency.json: one beat per cycle).
        self.ps(self.line as f64 / self.eb as f64 * self.lat.msu_ii)
    }

    fn list_len(&self, t: &TileWork) -> u64 {
        if self.hier {
            t.current as u64
        } else {
            t.sort_n as u64
        }
    }

    fn preprocess_job(&self, f: usize) -> Job {
        let fw = &self.wl.frames[f];
        let p = &self.cfg.preprocess;
        let n = &self.cfg.neo;
        let cyc = (fw.gaussians as f64 / n.projection_units as f64).ceil() * p.projection_ii;
        let cyc = cyc.max((fw.visible as f64 / n.color_units as f64).ceil() * p.color_ii);
        let cyc = cyc.max((fw.binning_tests as f64 / n.duplication_units as f64).ceil() * p.duplication_ii);
        let compute = self.ps(cyc + p.latency as f64);
        let s = &self.cfg.sizes;
        let l = &self.layout;
        let reads = vec![
            Access::seq(Stage::Preprocess, l.geometry, fw.gaussians * s.gaussian_geometry_bytes as u64),
            Access::seq(Stage::Preprocess, l.sh, fw.visible * s.gaussian_sh_bytes as u64),
        ];
        let lists: u64 = fw.tiles.iter().map(|t| self.list_len(t)).sum();
        let mut writes = vec![
            Access::seq(Stage::FeatureTable, l.features[f % 2], fw.visible * self.fb),
            Access::seq(Stage::IncomingList, l.lists[f % 2], lists * self.eb),
        ];
        if self.accel == Accel::Neo && matches!(self.strategy, Strategy::Background(_)) {
            let all: u64 = fw.tiles.iter().map(|t| t.background_n as u64).sum();
            writes.push(Access::seq(Stage::BackgroundSort, l.bg_lists[f % 2], all * self.eb));
        }
        Job {
            tag: JobTag { frame: f as u32, tile: 0, kind: K_PRE },
            segments: vec![Segment {
                compute,
                load: compute,
                serial: false,
                reads,
                writes,
                writes_at_end: false,
                min_interval: self.ps(1.0),
                spread_reads: true,
            }],
        }
    }

    /// A sorting-core command. Chunk commands (serial segments) take their single latency `T`
    /// with the load phase `T - I` (the measured part a back-to-back command overlaps with the
    /// previous one: with `double_buffered_io` the engine starts it under the previous segment,
    /// so a steady stream costs the measured interval `I` each); merges (streaming, they
    /// serialise on the core) take their measured back-to-back `interval`.
    fn cmd_segment(&self, cmd: Cmd, reads: Vec<Access>, writes: Vec<Access>, extra_cycles: f64) -> Segment {
        let serial = cmd.is_chunk();
        let (t, load) = if serial {
            (cmd.cycles(self.lat) as f64 + extra_cycles, cmd.overlappable(self.lat) as f64)
        } else {
            let t = cmd.interval(self.lat) as f64 + extra_cycles;
            (t, cmd.entries_in() as f64 * self.lat.msu_ii)
        };
        Segment {
            compute: self.ps(t.max(1.0)),
            load: self.ps(load.min(t)),
            serial,
            reads,
            writes,
            writes_at_end: serial,
            min_interval: self.sort_port(),
            spread_reads: false,
        }
    }

    /// Conventional sort of `n` entries from `src` (charged to `src_stage`) into `dst`, with
    /// temporaries in `scratch` (two run buffers); `stage` for everything after the first read.
    #[allow(clippy::too_many_arguments)]
    fn conv_sort(
        &self,
        segs: &mut Vec<Segment>,
        n: u64,
        src: u64,
        src_stage: Stage,
        dst: u64,
        scratch: [u64; 2],
        stage: Stage,
    ) {
        let c = self.cfg.pipeline.chunk as u64;
        let eb = self.eb;
        let cmds = conventional_sort(n, c);
        let chunks = n.div_ceil(c);
        let mut off = 0;
        let mut it = cmds.into_iter().peekable();
        for _ in 0..chunks {
            let cmd = it.next().expect("a chunk command");
            let out = if chunks == 1 { dst } else { scratch[0] };
            segs.push(self.cmd_segment(
                cmd,
                vec![Access::seq(src_stage, src + off * eb, cmd.len_a * eb)],
                vec![Access::seq(stage, out + off * eb, cmd.len_a * eb)],
                0.0,
            ));
            off += cmd.len_a;
        }
        // Merge passes: runs of C, 2C, ... alternate between the scratch buffers; the last pass
        // writes `dst`.
        let passes = if chunks > 1 { 64 - (chunks - 1).leading_zeros() } else { 0 };
        let mut from = 0usize;
        for p in 0..passes {
            let to_last = p + 1 == passes;
            let mut start = 0;
            while start < n {
                let cmd = it.next().expect("a merge command");
                let len = cmd.entries_in();
                let out = if to_last { dst } else { scratch[1 - from] };
                segs.push(self.cmd_segment(
                    cmd,
                    vec![Access::seq(stage, scratch[from] + start * eb, len * eb)],
                    vec![Access::seq(stage, out + start * eb, len * eb)],
                    0.0,
                ));
                start += len;
            }
            from = 1 - from;
        }
        debug_assert!(it.next().is_none());
    }

    fn scratch(&self, agent: usize) -> [u64; 3] {
        let core = agent.saturating_sub(1) as u64;
        let base = self.layout.scratch + core * 3 * self.layout.scratch_part;
        [base, base + self.layout.scratch_part, base + 2 * self.layout.scratch_part]
    }

    fn table(&self, f: usize, t: usize) -> u64 {
        self.layout.tables[f % 2] + t as u64 * self.layout.slot
    }

    fn empty_segment(&self) -> Segment {
        Segment {
            compute: self.ps(self.lat.command_overhead.max(1) as f64),
            load: 0,
            serial: true,
            reads: Vec::new(),
            writes: Vec::new(),
            writes_at_end: true,
            min_interval: self.sort_port(),
            spread_reads: false,
        }
    }

    fn sort_job(&self, f: usize, t: usize, agent: usize, list_off: u64) -> Job {
        let tw = &self.wl.frames[f].tiles[t];
        let eb = self.eb;
        let sc = self.scratch(agent);
        let list = self.layout.lists[f % 2] + list_off * eb;
        let cur = self.table(f, t);
        let mut segs = Vec::new();
        if self.hier {
            self.hier_sort(&mut segs, tw, list, cur, sc);
        } else if tw.from_scratch {
            self.conv_sort(
                &mut segs,
                tw.sort_n as u64,
                list,
                Stage::IncomingList,
                cur,
                [sc[0], sc[1]],
                Stage::SortTable,
            );
        } else {
            let (prev, prev_stage) = match self.strategy {
                Strategy::Background(k) => {
                    let src = f.saturating_sub(k).max(self.shot_start[f]);
                    (self.layout.bg_tables[src % 2] + t as u64 * self.layout.slot, Stage::SortTable)
                }
                _ => (self.table(f + 1, t), Stage::SortTable),
            };
            let c = self.cfg.pipeline.chunk as u64;
            let (a, b) = (tw.merge_a as u64, tw.merge_b as u64);
            let out = (tw.merge_out - tw.merge_out.min(tw.dropped_capacity)) as u64;
            let passes = tw.dps_passes as usize;
            let fused = self.cfg.neo.fused_dps_merge && passes > 0 && tw.dps_len > 0;
            if fused {
                // Sorted incoming list first; DPS passes; the last pass feeds the MSU+.
                self.conv_sort(
                    &mut segs,
                    b,
                    list,
                    Stage::IncomingList,
                    sc[2],
                    [sc[0], sc[1]],
                    Stage::SortTable,
                );
                let len = tw.dps_len as u64;
                for p in 0..passes - 1 {
                    let mut off = 0;
                    for cmd in dps_pass(len, c, Parity::of(f as u64, p)) {
                        let acc = Access::seq(Stage::SortTable, prev + off * eb, cmd.len_a * eb);
                        segs.push(self.cmd_segment(cmd, vec![acc], vec![acc], 0.0));
                        off += cmd.len_a;
                    }
                }
                let extra = (self.lat.merge_cycles(a, b, true) as f64 - a as f64).max(b as f64);
                let (mut off, mut b_done, mut o_done) = (0u64, 0u64, 0u64);
                for cmd in dps_pass(len, c, Parity::of(f as u64, passes - 1)) {
                    let end = off + cmd.len_a;
                    let b_to = b * end / len;
                    let o_to = out * end / len;
                    let (bi, oi) = (b_to - b_done, o_to - o_done);
                    let mut reads = vec![Access::seq(prev_stage, prev + off * eb, cmd.len_a * eb)];
                    if bi > 0 {
                        reads.push(Access::seq(Stage::SortTable, sc[2] + b_done * eb, bi * eb));
                    }
                    let writes = vec![Access::seq(Stage::SortTable, cur + o_done * eb, oi * eb)];
                    let share = extra * cmd.len_a as f64 / len as f64;
                    let mut s = self.cmd_segment(cmd, reads, writes, share);
                    s.load = self
                        .ps(((cmd.len_a + bi) as f64 * self.lat.msu_ii)
                            .min(cmd.cycles(self.lat) as f64 + share));
                    segs.push(s);
                    (off, b_done, o_done) = (end, b_to, o_to);
                }
            } else {
                let len = tw.dps_len as u64;
                for p in 0..passes {
                    let mut off = 0;
                    for cmd in dps_pass(len, c, Parity::of(f as u64, p)) {
                        let acc = Access::seq(Stage::SortTable, prev + off * eb, cmd.len_a * eb);
                        segs.push(self.cmd_segment(cmd, vec![acc], vec![acc], 0.0));
                        off += cmd.len_a;
                    }
                }
                self.conv_sort(
                    &mut segs,
                    b,
                    list,
                    Stage::IncomingList,
                    sc[2],
                    [sc[0], sc[1]],
                    Stage::SortTable,
                );
                if a + b > 0 {
                    let cmd = Cmd { mode: Mode::MergeDelete, len_a: a, len_b: b };
                    segs.push(self.cmd_segment(
                        cmd,
                        vec![
                            Access::seq(prev_stage, prev, a * eb),
                            Access::seq(Stage::SortTable, sc[2], b * eb),
                        ],
                        vec![Access::seq(Stage::SortTable, cur, out * eb)],
                        0.0,
                    ));
                }
            }
        }
        if segs.is_empty() {
            segs.push(self.empty_segment());
        }
        Job { tag: JobTag { frame: f as u32, tile: t as u32, kind: K_SORT }, segments: segs }
    }

    fn hier_sort(&self, segs: &mut Vec<Segment>, tw: &TileWork, list: u64, cur: u64, sc: [u64; 3]) {
        let h = &tw.hier;
        let eb = self.eb;
        let c = self.cfg.pipeline.chunk as u64;
        if h.entries == 0 {
            return;
        }
        let g = &self.cfg.gscore;
        let binned = h.approx_passes > 0;
        if binned {
            let n = h.entries as u64;
            let deeper = h.approx_entries as u64 - n.min(h.approx_entries as u64);
            let stream = h.approx_entries as f64 / g.approx_entries_per_cycle;
            let lat = (g.approx_latency * h.approx_passes as u64) as f64;
            let mut reads = vec![Access::seq(Stage::IncomingList, list, n * eb)];
            if deeper > 0 {
                reads.push(Access::seq(Stage::SortTable, sc[1], deeper * eb));
            }
            segs.push(Segment {
                compute: self.ps(stream + lat),
                load: self.ps(stream),
                serial: false,
                reads,
                writes: vec![Access::seq(Stage::SortTable, sc[0], h.approx_entries as u64 * eb)],
                writes_at_end: false,
                min_interval: self.sort_port(),
                spread_reads: false,
            });
        }
        let k = h.bin_sorts.max(1) as u64;
        let total = h.bin_entries as u64;
        let (q, rem) = (total / k, total % k);
        let mut off = 0;
        for i in 0..k {
            let len = (q + (i < rem) as u64).min(c);
            if len == 0 {
                continue;
            }
            let (src, stage) = if binned { (sc[0], Stage::SortTable) } else { (list, Stage::IncomingList) };
            let cmd = Cmd { mode: Mode::Sort, len_a: len, len_b: 0 };
            segs.push(self.cmd_segment(
                cmd,
                vec![Access::seq(stage, src + off * eb, len * eb)],
                vec![Access::seq(Stage::SortTable, cur + off * eb, len * eb)],
                0.0,
            ));
            off += len;
        }
        if h.fallback_global > 0 {
            let n = h.fallback_global as u64;
            let cmd = Cmd { mode: Mode::Merge, len_a: n / 2, len_b: n - n / 2 };
            segs.push(self.cmd_segment(
                cmd,
                vec![Access::seq(Stage::SortTable, sc[1], n * eb)],
                vec![Access::seq(Stage::SortTable, cur, n * eb)],
                0.0,
            ));
        }
    }

    fn background_job(&self, f: usize, t: usize, agent: usize, off: u64) -> Job {
        let tw = &self.wl.frames[f].tiles[t];
        let sc = self.scratch(agent);
        let mut segs = Vec::new();
        let src = self.layout.bg_lists[f % 2] + off * self.eb;
        let dst = self.layout.bg_tables[f % 2] + t as u64 * self.layout.slot;
        self.conv_sort(
            &mut segs,
            tw.background_n as u64,
            src,
            Stage::BackgroundSort,
            dst,
            [sc[0], sc[1]],
            Stage::BackgroundSort,
        );
        if segs.is_empty() {
            segs.push(self.empty_segment());
        }
        Job { tag: JobTag { frame: f as u32, tile: t as u32, kind: K_BG }, segments: segs }
    }

    fn raster_job(&self, f: usize, t: usize) -> Job {
        let fw = &self.wl.frames[f];
        let tw = &fw.tiles[t];
        let info = &self.wl.info;
        let neo = self.accel == Accel::Neo;
        let (entries, table_entries) =
            if neo { (tw.raster_entries, tw.table_len as u64) } else { (tw.current, tw.current as u64) };
        let (cyc, tail) = raster_tile_cycles(
            &tw.routed,
            fw.processed_ratio,
            entries,
            table_entries as u32,
            &self.raster,
            self.itus_per_core.max(1),
            self.scus_per_core,
            neo,
        );
        let cur = self.table(f, t);
        let mut reads = vec![Access::seq(Stage::RasterTable, cur, table_entries * self.eb)];
        if entries > 0 {
            reads.push(Access {
                stage: Stage::FeatureTable,
                base: self.layout.features[f % 2],
                kind: AccessKind::Gather {
                    count: entries as u64,
                    record_bytes: self.fb as u32,
                    records_in_region: fw.visible.max(1),
                    seed: crate::engine::mix(((f as u64) << 32) ^ t as u64),
                },
            });
        }
        let mut writes = Vec::new();
        if neo && tw.writeback > 0 {
            writes.push(Access::seq(Stage::DepthWriteback, cur, tw.writeback as u64 * self.eb));
        }
        let (gx, ts) = (info.grid[0] as u64, info.tile as u64);
        let (tx, ty) = (t as u64 % gx, t as u64 / gx);
        let (w, h) = (info.width as u64, info.height as u64);
        let pb = self.cfg.sizes.pixel_bytes as u64;
        let x0 = tx * ts;
        let cols = ts.min(w.saturating_sub(x0));
        for y in ty * ts..(ty * ts + ts).min(h) {
            writes.push(Access::seq(
                Stage::FrameBuffer,
                self.layout.framebuffer + (y * w + x0) * pb,
                cols * pb,
            ));
        }
        let compute = self.ps(cyc);
        Job {
            tag: JobTag { frame: f as u32, tile: t as u32, kind: K_RASTER },
            segments: vec![Segment {
                compute,
                load: compute - self.ps(tail).min(compute),
                serial: false,
                reads,
                writes,
                writes_at_end: true,
                min_interval: self.ps(1.0),
                spread_reads: true,
            }],
        }
    }
}

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
    bg_done: Vec<bool>,
    raster_left: Vec<usize>,
    sort_left: Vec<usize>,
    frame_done: Vec<bool>,
    bg_left: usize,
    sort_ready: BinaryHeap<Reverse<(u32, u32)>>,
    bg_ready: BinaryHeap<Reverse<(u32, u32)>>,
    raster_ready: BinaryHeap<Reverse<(u32, u32)>>,
    offsets: Vec<Option<Vec<u64>>>,
    bg_offsets: Vec<Option<Vec<u64>>>,
    background: Option<usize>,
}

impl<'m, 'a> Sched<'m, 'a> {
    fn new(m: &'m Model<'a>) -> Self {
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
            bg_done: vec![false; frames * tiles],
            raster_left: vec![tiles; frames],
            sort_left: vec![tiles; frames],
            frame_done: vec![false; frames],
            bg_left: if background.is_some() { frames * tiles } else { 0 },
            sort_ready: BinaryHeap::new(),
            bg_ready: BinaryHeap::new(),
            raster_ready: BinaryHeap::new(),
            offsets: vec![None; frames],
            bg_offsets: vec![None; frames],
            background,
        }
    }

    /// Per-frame times (valid after the run).
    pub fn times(&self) -> &[FrameTimes] {
        &self.times
    }

    fn reuses(&self) -> bool {
        self.m.accel == Accel::Neo && !self.m.hier && self.m.strategy != Strategy::Full
    }

    fn sort_deps_met(&self, f: usize, t: usize) -> bool {
        if !self.pre_done[f] {
            return false;
        }
        let i = f * self.tiles + t;
        if f >= 2 && !self.raster_done[i - 2 * self.tiles] {
            return false;
        }
        if f >= 1 && self.reuses() && !self.raster_done[i - self.tiles] {
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
                self.try_queue_sort(f + 1, tile);
                self.try_queue_sort(f + 2, tile);
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
        self.frame_done.iter().all(|&d| d) && self.bg_left == 0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rt() -> RasterTiming {
        RasterTiming {
            itu_ii: 1.0,
            itu_latency: 3,
            scu_cycles_per_pair: 4.0,
            scu_drain_ii: 1.0,
            scu_latency: 10,
            tile_overhead: 0,
            load_cycles_per_entry: 0.0,
            pixel_write_cycles: 0,
            feature_buffer: 0,
            segment_overhead: 0.0,
        }
    }

    #[test]
    fn raster_groups_take_their_slowest_scu_and_overlap_the_itus() {
        // 8 subtiles in two groups of 4: group maxima 10 and 20 routed entries, no termination.
        let routed = [1, 10, 3, 0, 20, 5, 5, 5];
        let (t, tail) = raster_tile_cycles(&routed, 1.0, 40, 40, &rt(), 4, 4, true);
        // SCUs: (10 + 20) x 4 = 120; ITUs: 2 groups x 40 / 4 = 20, hidden; latencies 3 + 10.
        assert_eq!(t, 120.0 + 13.0);
        assert_eq!(tail, 20.0 * 4.0 + 10.0);
        // Half the pairs terminate early: processed at 4 cycles, the rest drained at 1.
        let (h, _) = raster_tile_cycles(&routed, 0.5, 40, 40, &rt(), 4, 4, true);
        assert_eq!(h, (5.0 * 4.0 + 5.0) + (10.0 * 4.0 + 10.0) + 13.0);
        // Many entries and few routed pairs: the ITUs (one walk per group) bound the tile.
        let (i, _) = raster_tile_cycles(&[1; 8], 1.0, 4000, 4000, &rt(), 4, 4, true);
        assert_eq!(i, 2.0 * 1000.0 + 13.0);
        // Without ITUs (bitmaps from memory) only the SCUs and their latency count.
        let (g, _) = raster_tile_cycles(&[1; 8], 1.0, 4000, 4000, &rt(), 4, 4, false);
        assert_eq!(g, 8.0 + 10.0);
    }

    #[test]
    fn measured_raster_core_shape_loads_then_overlaps_writes_and_segments_per_group() {
        let shaped = RasterTiming {
            load_cycles_per_entry: 2.0,
            pixel_write_cycles: 512,
            feature_buffer: 100,
            tile_overhead: 535,
            ..rt()
        };
        // Empty tile: the overhead.
        assert_eq!(raster_tile_cycles(&[0; 64], 1.0, 0, 0, &shaped, 4, 4, true).0, 535.0);
        // Light tile: loads, then the pixel writes bound the body.
        assert_eq!(raster_tile_cycles(&[1; 64], 1.0, 20, 20, &shaped, 4, 4, true).0, 40.0 + 535.0);
        // Heavy tile: 16 groups of 4 SCUs with 50 routed each = 16 x 200 cycles.
        let (h, _) = raster_tile_cycles(&[50; 64], 1.0, 80, 80, &shaped, 4, 4, true);
        assert_eq!(h, 160.0 + 3200.0 - 512.0 + 535.0);
        // 200 entries > 100, two segments: the first segment's loads (200), then per segment
        // and group the walk (25 quads for group 0, 18.1 for a later one: 1 + the 68% of the
        // quads that touch it) against half the group's slowest SCU (200 / 2); the port (the
        // write-backs and the second segment's loads) hides under the blending.
        let (s, _) = raster_tile_cycles(&[50; 64], 1.0, 200, 200, &shaped, 4, 4, true);
        assert_eq!(s, 200.0 + 2.0 * 16.0 * 100.0 - 512.0 + 535.0);
        // Light long table, 30 segments: port-bound (each segment's 55 cycles of walks, 25 for
        // group 0 and 2 for each later group, hide under its 100 write-backs and the next
        // segment's 200 cycles of loads), plus the segment overhead.
        let o = RasterTiming { segment_overhead: 30.0, ..shaped };
        let (w, _) = raster_tile_cycles(&[1; 64], 1.0, 3000, 3000, &o, 4, 4, true);
        assert_eq!(w, 200.0 + 30.0 * 30.0 + 29.0 * 300.0 + 100.0 - 512.0 + 535.0);
    }
}
