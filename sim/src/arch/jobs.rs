//! The jobs each engine runs: preprocessing per frame, the sorting-core commands per tile
//! (timed by `latency.json`, [`crate::sortcmd`]) and the raster core per tile
//! ([`super::raster_tile_cycles`]), each with its DRAM reads and writes.

use neo_golden::engine::pre::{pre_transfers_of, PrePart, PreRecords};
use neo_golden::engine::{tile_steps, TileRegion, TileShape, TileStep};
use neo_golden::engine::{FrameRegs, PreRegs, PRE_ENABLE, PRE_FRESH};
use neo_golden::pipeline::Strategy;

use super::timing::raster_tile_cycles;
use super::{Accel, Model, K_BG, K_PRE, K_RASTER, K_SORT, K_UPDATE};
use crate::dram::Ps;
use crate::engine::{Access, AccessKind, Job, JobTag, Segment};
use crate::sortcmd::{Cmd, Mode};
use crate::traffic::Stage;
use crate::workload::TileWork;

impl Model<'_> {
    fn sort_port(&self) -> Ps {
        // One entry per cycle (latency.json: one beat per cycle).
        self.ps(self.line as f64 / self.eb as f64 * self.lat.msu_ii)
    }

    pub(super) fn list_len(&self, t: &TileWork) -> u64 {
        if self.hier {
            t.current as u64
        } else {
            t.sort_n as u64
        }
    }

    pub(super) fn preprocess_job(&self, f: usize) -> Job {
        let fw = &self.wl.frames[f];
        let p = &self.lat.preprocess.over(&self.cfg.preprocess);
        let n = &self.cfg.neo;
        let cyc = (fw.gaussians as f64 / n.projection_units as f64).ceil() * p.projection_ii;
        let cyc = cyc.max((fw.visible as f64 / n.color_units as f64).ceil() * p.color_ii);
        let cyc = cyc.max((fw.binning_tests as f64 / n.duplication_units as f64).ceil() * p.duplication_ii);
        let compute = self.ps(cyc + p.latency as f64);
        let l = &self.layout;
        let (reads, mut writes) = if self.neo_sorting() {
            self.pre_engine_accesses(f)
        } else {
            let s = &self.cfg.sizes;
            let lists: u64 = fw.tiles.iter().map(|t| self.list_len(t)).sum();
            (
                vec![
                    Access::seq(
                        Stage::Preprocess,
                        l.geometry,
                        fw.gaussians * s.geometry_bytes(&self.wl.info),
                    ),
                    Access::seq(Stage::Preprocess, l.sh, fw.visible * s.sh_bytes(&self.wl.info)),
                ],
                vec![
                    Access::seq(Stage::FeatureTable, l.features[f % 2], fw.visible * self.fb),
                    Access::seq(Stage::IncomingList, l.lists[f % 2], lists * self.eb),
                ],
            )
        };
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

    /// The Preprocessing Engine's registers for frame `f` in the model's memory map:
    /// `PRE_FRESH` unless the frame reuses tables ([`Model::detects_incoming`] and not from
    /// scratch), the feature words of frame `f` in buffer `f % 2` and the previous ones in the
    /// other, the lists in their slots.
    pub(super) fn pre_regs(&self, f: usize) -> FrameRegs {
        let (fw, l, info) = (&self.wl.frames[f], &self.layout, &self.wl.info);
        let fresh = !self.detects_incoming() || fw.from_scratch || f == 0;
        FrameRegs {
            frame: f as u32,
            tiles: fw.tiles.len() as u32,
            width: info.width,
            height: info.height,
            desc_base: l.descriptors,
            feat_base: l.features[f % 2],
            pre: PreRegs {
                ctrl: PRE_ENABLE | if fresh { PRE_FRESH } else { 0 },
                gaussians: fw.gaussians as u32,
                sh_degree: info.sh_degree as u32,
                geo_base: l.geometry,
                sh_base: l.sh,
                prev_feat_base: l.features[(f + 1) % 2],
                list_base: l.lists[f % 2],
                ..PreRegs::default()
            },
            ..FrameRegs::default()
        }
    }

    /// The records Neo's Preprocessing Engine moves: the engine's (golden
    /// [`PreRecords::engine`]: 44-byte geometry, SH by the scene's degree in the precision of
    /// `sizes.sh_half`, 32-byte feature words), each replaced by the configuration's byte-size
    /// preset when it sets one (`sizes.gaussian_geometry_bytes`, `gaussian_sh_bytes`,
    /// `feature_entry_bytes`).
    pub(super) fn pre_records(&self) -> PreRecords {
        let s = &self.cfg.sizes;
        let e = PreRecords::engine(self.wl.info.sh_degree, s.sh_precision());
        PreRecords {
            geometry: s.gaussian_geometry_bytes.map_or(e.geometry, u64::from),
            sh: s.sh_bytes(&self.wl.info),
            feature: s.feature_entry_bytes.map_or(e.feature, u64::from),
        }
    }

    /// Neo's preprocessing traffic in frame `f` as (reads, writes): the RTL Preprocessing
    /// Engine's transfers (golden `pre_transfers` for [`Model::pre_regs`], of
    /// [`Model::pre_records`] (`pre_transfers_of`), the frame's visible
    /// Gaussians and list lengths), each moving the DRAM lines it touches; consecutive
    /// transfers of one kind are one [`Access::records`] run. Geometry and SH records are
    /// charged to [`Stage::Preprocess`], the previous feature words (incoming detection) to
    /// [`Stage::IncomingDetection`], the feature words to [`Stage::FeatureTable`], the list
    /// lines and lengths to [`Stage::IncomingList`].
    pub(super) fn pre_engine_accesses(&self, f: usize) -> (Vec<Access>, Vec<Access>) {
        let fw = &self.wl.frames[f];
        let (mut reads, mut writes) = (Vec::new(), Vec::new());
        let lens = fw.tiles.iter().map(|t| self.list_len(t) as usize);
        let (cfg, regs) = (&self.cfg.engine, self.pre_regs(f));
        pre_transfers_of(cfg, &regs, self.pre_records(), fw.visible_ids(), lens, |t| {
            let stage = match t.part {
                PrePart::Geometry | PrePart::Sh => Stage::Preprocess,
                PrePart::PrevFeature => Stage::IncomingDetection,
                PrePart::Feature => Stage::FeatureTable,
                PrePart::ListLine | PrePart::ListLen => Stage::IncomingList,
            };
            let v = if t.part.is_write() { &mut writes } else { &mut reads };
            push_transfer(v, stage, t.addr, t.bytes);
        });
        (reads, writes)
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

    /// The segment of one of golden's tile commands ([`tile_steps`]) with its regions at `at`:
    /// a merge whose stream B follows A directly reads them as one run; the output is
    /// `written` entries (the command's input when `None`).
    fn step_segment(&self, s: &TileStep, at: &Regions, written: Option<u64>) -> Segment {
        let (a, b) = (s.a, s.b);
        let cmd = Cmd { mode: s.mode, len_a: a.2, len_b: b.2 };
        let reads = if s.mode.is_chunk() {
            vec![at.access(a.0, a.1, a.2)]
        } else if b.0 == a.0 && b.1 == a.1 + a.2 {
            vec![at.access(a.0, a.1, a.2 + b.2)]
        } else {
            vec![at.access(a.0, a.1, a.2), at.access(b.0, b.1, b.2)]
        };
        let writes = vec![at.access(s.dst.0, s.dst.1, written.unwrap_or(a.2 + b.2))];
        self.cmd_segment(cmd, reads, writes, 0.0)
    }

    /// The last DPS pass fused with the MSU+ merge (`fused_dps_merge`): each chunk of the pass
    /// `dps` streams into the `merge` with its share of the sorted list (stream B) and of the
    /// `out` entries written.
    fn fused_dps_merge(
        &self,
        segs: &mut Vec<Segment>,
        dps: &[TileStep],
        merge: &TileStep,
        at: &Regions,
        out: u64,
    ) {
        let ((_, _, a), (b_region, b_base, b)) = (merge.a, merge.b);
        let extra = (self.lat.merge_cycles(a, b, true) as f64 - a as f64).max(b as f64);
        let (mut b_done, mut o_done) = (0u64, 0u64);
        for step in dps {
            let (off, len) = (step.a.1, step.a.2);
            let end = off + len;
            let (b_to, o_to) = (b * end / a, out * end / a);
            let (bi, oi) = (b_to - b_done, o_to - o_done);
            let mut reads = vec![at.access(step.a.0, off, len)];
            if bi > 0 {
                reads.push(at.access(b_region, b_base + b_done, bi));
            }
            let writes = vec![at.access(merge.dst.0, merge.dst.1 + o_done, oi)];
            let share = extra * len as f64 / a as f64;
            let cmd = Cmd { mode: step.mode, len_a: len, len_b: 0 };
            let mut seg = self.cmd_segment(cmd, reads, writes, share);
            seg.load =
                self.ps(((len + bi) as f64 * self.lat.msu_ii).min(cmd.cycles(self.lat) as f64 + share));
            segs.push(seg);
            (b_done, o_done) = (b_to, o_to);
        }
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

    /// The chunk of a tile's DPS passes (the engine's unless the workload names another).
    fn dps_chunk(&self, tw: &TileWork) -> u64 {
        if tw.dps_chunk > 0 {
            tw.dps_chunk as u64
        } else {
            self.cfg.engine.chunk as u64
        }
    }

    /// The segments of golden's commands for a tile of `shape` ([`tile_steps`]) at `at`, the
    /// `MERGE_DELETE` writing `out` entries; the last DPS pass fused with the merge when the
    /// configuration says so (`fused_dps_merge`).
    fn tile_segments(&self, segs: &mut Vec<Segment>, shape: &TileShape, at: &Regions, out: u64) {
        let mut stages = tile_steps(shape);
        let reuse = !shape.from_scratch && shape.dps_passes > 0 && shape.prev_len > 0;
        let tail = if reuse && self.cfg.neo.fused_dps_merge {
            stages.split_off(stages.len() - 2)
        } else {
            Vec::new()
        };
        for step in stages.iter().flatten() {
            let written = (step.mode == Mode::MergeDelete).then_some(out);
            segs.push(self.step_segment(step, at, written));
        }
        if let [dps, merge] = &tail[..] {
            self.fused_dps_merge(segs, dps, &merge[0], at, out);
        }
    }

    pub(super) fn sort_job(&self, f: usize, t: usize, agent: usize, list_off: u64) -> Job {
        let tw = &self.wl.frames[f].tiles[t];
        let eb = self.eb;
        let sc = self.layout.scratch(agent);
        let list = if self.neo_sorting() {
            self.layout.list_slot(f, t)
        } else {
            self.layout.lists[f % 2] + list_off * eb
        };
        let cur = self.layout.table(f, t);
        let mut segs = Vec::new();
        if self.hier {
            self.hier_sort(&mut segs, tw, list, cur, sc);
        } else {
            let prev = match self.strategy {
                Strategy::Background(k) if !tw.from_scratch => {
                    let src = f.saturating_sub(k).max(self.shot_start[f]);
                    self.layout.bg_tables[src % 2] + t as u64 * self.layout.slot
                }
                _ => self.layout.table(f + 1, t),
            };
            let at = Regions {
                list: (list, Stage::IncomingList),
                scratch: [sc[0], sc[1]],
                prev,
                next: cur,
                stage: Stage::SortTable,
                eb,
            };
            let shape = TileShape {
                from_scratch: tw.from_scratch,
                list_len: tw.sort_n as u64,
                prev_len: tw.merge_a as u64,
                dps_passes: tw.dps_passes as u64,
                frame: f as u64,
                chunk: self.cfg.engine.chunk as u64,
                dps_chunk: self.dps_chunk(tw),
            };
            // The merge writes what survives the deletions and the capacity cut.
            let out = (tw.merge_out - tw.merge_out.min(tw.dropped_capacity)) as u64;
            self.tile_segments(&mut segs, &shape, &at, out);
        }
        if segs.is_empty() {
            segs.push(self.empty_segment());
        }
        Job { tag: JobTag { frame: f as u32, tile: t as u32, kind: K_SORT }, segments: segs }
    }

    fn hier_sort(&self, segs: &mut Vec<Segment>, tw: &TileWork, list: u64, cur: u64, sc: [u64; 3]) {
        let h = &tw.hier;
        let eb = self.eb;
        let c = self.cfg.engine.chunk as u64;
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

    pub(super) fn background_job(&self, f: usize, t: usize, agent: usize, off: u64) -> Job {
        let tw = &self.wl.frames[f].tiles[t];
        let sc = self.layout.scratch(agent);
        let mut segs = Vec::new();
        let src = self.layout.bg_lists[f % 2] + off * self.eb;
        let dst = self.layout.bg_tables[f % 2] + t as u64 * self.layout.slot;
        let at = Regions {
            list: (src, Stage::BackgroundSort),
            scratch: [sc[0], sc[1]],
            prev: dst,
            next: dst,
            stage: Stage::BackgroundSort,
            eb: self.eb,
        };
        let shape = TileShape {
            from_scratch: true,
            list_len: tw.background_n as u64,
            chunk: self.cfg.engine.chunk as u64,
            ..TileShape::default()
        };
        // A sort from scratch: no merge, so nothing is written but the sorted list.
        self.tile_segments(&mut segs, &shape, &at, 0);
        if segs.is_empty() {
            segs.push(self.empty_segment());
        }
        Job { tag: JobTag { frame: f as u32, tile: t as u32, kind: K_BG }, segments: segs }
    }

    pub(super) fn raster_job(&self, f: usize, t: usize) -> Job {
        let fw = &self.wl.frames[f];
        let tw = &fw.tiles[t];
        let info = &self.wl.info;
        // Neo's raster core (ITUs, write-back) only on Neo; Neo's tables and feature words
        // whenever the sorting engine is Neo's (Neo-S too).
        let neo = self.accel == Accel::Neo;
        let neo_tables = self.neo_sorting();
        let (entries, table_entries) = if neo_tables {
            (tw.raster_entries, tw.table_len as u64)
        } else {
            (tw.current, tw.current as u64)
        };
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
        let cur = self.layout.table(f, t);
        let mut reads = vec![Access::seq(Stage::RasterTable, cur, table_entries * self.eb)];
        if entries > 0 {
            // Neo's feature table is a word per Gaussian id, GSCore's the compacted entries.
            let (record_bytes, records) =
                if neo_tables { (self.pre_records().feature, fw.gaussians) } else { (self.fb, fw.visible) };
            let seed = crate::engine::mix(((f as u64) << 32) ^ t as u64);
            reads.push(self.feature_gather(
                Stage::FeatureTable,
                f,
                entries as u64,
                (record_bytes, records),
                seed,
            ));
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

    /// `count` random reads of frame `f`'s feature table, whose `records` are (bytes, count),
    /// charged to `stage`.
    fn feature_gather(&self, stage: Stage, f: usize, count: u64, records: (u64, u64), seed: u64) -> Access {
        Access {
            stage,
            base: self.layout.features[f % 2],
            kind: AccessKind::Gather {
                count,
                record_bytes: records.0 as u32,
                records_in_region: records.1.max(1),
                seed,
            },
        }
    }

    /// Neo-S's update pass of tile `t` in frame `f`, on a sorting core after the tile's raster:
    /// it reads the table, gathers every entry's feature word (its depth and visibility this
    /// frame) and writes the table back, one entry per cycle (the MSU+ rate), all charged to
    /// the depth write-back stage. Neo does this in its raster core (the write-back of
    /// [`Model::raster_job`]) from the features it reads anyway.
    pub(super) fn update_job(&self, f: usize, t: usize) -> Job {
        let fw = &self.wl.frames[f];
        let n = fw.tiles[t].table_len as u64;
        let cur = self.layout.table(f, t);
        let mut reads = vec![Access::seq(Stage::DepthWriteback, cur, n * self.eb)];
        if n > 0 {
            let seed = crate::engine::mix(((f as u64) << 32) ^ t as u64 ^ 0x5eed);
            let records = (self.pre_records().feature, fw.gaussians);
            reads.push(self.feature_gather(Stage::DepthWriteback, f, n, records, seed));
        }
        let compute = self.ps(n as f64 * self.lat.msu_ii + 1.0);
        Job {
            tag: JobTag { frame: f as u32, tile: t as u32, kind: K_UPDATE },
            segments: vec![Segment {
                compute,
                load: compute,
                serial: false,
                reads,
                writes: vec![Access::seq(Stage::DepthWriteback, cur, n * self.eb)],
                writes_at_end: true,
                min_interval: self.sort_port(),
                spread_reads: true,
            }],
        }
    }
}

/// Appends one transfer to `v`: it extends the last run when it has the same stage and size
/// and continues its stride, else it starts a run.
fn push_transfer(v: &mut Vec<Access>, stage: Stage, addr: u64, bytes: u64) {
    if let Some(Access { stage: s, base, kind: AccessKind::Records { count, record_bytes, stride } }) =
        v.last_mut()
    {
        if *s == stage && *record_bytes == bytes && addr > *base {
            if *count == 1 {
                (*stride, *count) = (addr - *base, 2);
                return;
            }
            if addr == *base + *stride * *count {
                *count += 1;
                return;
            }
        }
    }
    v.push(Access::records(stage, addr, 1, bytes, bytes));
}

/// Where the regions of a tile's commands are in the model's memory, and the stage their
/// traffic is charged to.
struct Regions {
    /// The list: its address and stage.
    list: (u64, Stage),
    /// The two scratch regions.
    scratch: [u64; 2],
    /// The previous table.
    prev: u64,
    /// The next table.
    next: u64,
    /// The stage of every region but the list.
    stage: Stage,
    /// Bytes per entry.
    eb: u64,
}

impl Regions {
    /// The access of `len` entries at entry offset `off` of `region`.
    fn access(&self, region: TileRegion, off: u64, len: u64) -> Access {
        let (base, stage) = match region {
            TileRegion::List => self.list,
            TileRegion::Scratch(k) => (self.scratch[k], self.stage),
            TileRegion::Prev => (self.prev, self.stage),
            TileRegion::Next => (self.next, self.stage),
        };
        Access::seq(stage, base + off * self.eb, len * self.eb)
    }
}
