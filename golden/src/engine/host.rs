//! The host side of a frame: from a scene and a trajectory, the golden pipeline (Neo strategy)
//! produces every frame's preprocessing outputs; [`EngineSession::next_frame`] writes them into
//! a [`Memory`] as the host would (descriptors, incoming lists, the feature table), returns the
//! registers to program and what the frame must leave ([`Expected`], from the PIPELINE, not from
//! [`super::execute_frame`]).
//!
//! # A harness, in outline
//! ```text
//! let mut session = EngineCase::Orbit.session(&scene, &CaseScene::biker(), 3, [256, 256], &cfg)?;
//! let mut mem = Memory::new();                 // the AXI memory model's backing store
//! while let Some(plan) = session.next_frame(&mut mem)? {
//!     for (reg, v) in plan.regs.writes() { axil_write(reg.offset(), v) }
//!     axil_write(Reg::Ctrl.offset(), CTRL_START);   // then run until STATUS has STATUS_DONE
//!     if let Some(m) = plan.expected.compare(&mem) { fail(frame, m) }
//!     let out = FrameOutcome::read_back(&plan.regs, &mem, axil_read);
//!     if let Some(m) = plan.expected.compare_outcome(&out) { fail(frame, m) }
//! }
//! ```
//! ([`super::execute_frame`] in place of the RTL passes the same checks: `golden/tests/engine_frame.rs`.)
//!
//! # Memory map ([`MemoryLayout`], 4 KiB-aligned regions, in this order)
//! descriptors, results, frame buffer (tile-major), feature table (one word per Gaussian id),
//! sort scratch (`2 * table_capacity` entries per sorting core), two table arenas
//! (`tiles * table_capacity` entries each; frame `f` writes its next tables into arena `f % 2`
//! and reads its previous tables from the other), incoming lists (compact, rewritten each frame).
//!
//! Tables are placed compactly: tile `t`'s next region follows tile `t - 1`'s and holds
//! `min(prev_len + list_len, table_capacity)` entries (at most what the engine may write: a
//! longer tile overflows and writes nothing). The previous table of a tile is the engine's own
//! write-back of the previous frame (nothing is copied).
//!
//! # Scene mode ([`HostMode::Scene`], [`EngineSession::from_scene`])
//! The engine preprocesses the scene itself ([`super::PreRegs`]): the host writes the baked
//! scene once (geometry records and SH records, binary32 or, with [`SessionOptions::sh`],
//! binary16 and `PRE_SH_HALF`; [`SceneLayout`]) and, each frame, only the
//! descriptors (their `list_len` a canary the engine overwrites), and programs the camera.
//! Frame `f` writes its feature words into feature arena `f % 2` (`FEAT_BASE`) and reads the
//! previous frame's from the other (`PREV_FEAT_BASE`); tile `t`'s incoming list is at
//! `LIST_BASE / 8 + t list_stride` and its next table at `table_bases[f % 2] / 8 + t
//! table_capacity` (nothing depends on list lengths the host cannot know before the frame).
//! `PRE_FRESH` is set exactly on the frames sorted from scratch. [`Expected`] then also holds
//! the feature words, the lists and their lengths ([`super::expected::PreExpected`]) and the
//! counters `RD_PRE` / `WR_PRE`.
//!
//! # Cuts, re-sorts and overflow
//! Frame 0 and the trajectory's cuts are sorted from scratch (every tile's list is its current
//! list). In lists mode, a tile the strategy re-sorts in a reuse frame (`adaptive` with
//! `resort=1`) is sorted from scratch alone: its descriptor says so and its list is its
//! current list. A tile that overflows has no next table, so the frame after a frame with an overflow
//! is sorted from scratch too (the host re-bins; the pipeline is told it is a cut). The
//! overflowing tile's next region is filled with a canary and must be left as it is, its
//! previous table too ([`super::expected::Untouched`]).

use super::adapt::AdaptRegs;
use super::expected::{Expected, Untouched};
use super::memory::{
    entry_to_u64, Memory, TileDescriptor, TileResult, DESCRIPTOR_BYTES, ENTRY_BYTES, FEATURE_BYTES,
    MAX_DPS_PASSES, PIXEL_BYTES, RESULT_BYTES,
};
use super::reference::{add_raster_traffic, sort_traffic, FrameOutcome};
use super::regs::{Counter, FrameRegs, PreRegs, NO_OVERFLOW, STATUS_DONE, STATUS_OVERFLOW};
use super::EngineConfig;
use crate::hwpre::ShPrecision;
use crate::pipeline::adaptive::CameraMotion;
use crate::pipeline::{Formats, FrameOutput, Pipeline, PipelineConfig, Preprocessing, Strategy};
use crate::scene::Scene;
use crate::sort::{DepthKeyCodec, SortEntry};
use crate::trajectory::Trajectory;

mod scene;

/// A session the host cannot set up or continue.
#[derive(Debug, thiserror::Error)]
pub enum SessionError {
    /// The configuration does not validate.
    #[error(transparent)]
    Config(#[from] super::ConfigError),
    /// The golden pipeline refuses the scene or formats (its message holds the cause's, so the
    /// cause is no error source: a chain printed whole would repeat it).
    #[error("golden pipeline: {0}")]
    Pipeline(crate::pipeline::PipelineError),
    /// The memory map does not fit the address widths.
    #[error("memory map: {0}")]
    Layout(String),
    /// A case's trajectory cannot be built.
    #[error("trajectory: {0}")]
    Trajectory(String),
    /// The pipeline did not do what the host assumed (a bug).
    #[error("host/pipeline disagreement: {0}")]
    Inconsistent(String),
    /// The trajectory has no frame.
    #[error("the trajectory has no frame")]
    NoFrames,
    /// Scene mode on an engine without a Preprocessing Engine.
    #[error("scene mode needs a Preprocessing Engine: the configuration has pre_units 0 (use lists mode)")]
    NoPreprocessing,
    /// The engine cannot plan the passes of this strategy itself ([`Planner::Engine`]).
    #[error("the engine's own plan: {0}")]
    Planner(String),
    /// A sorting strategy the engine does not run.
    #[error(
        "strategy {0}: the engine runs `neo` and `adaptive` with wide=1 or wide = its dps_wide (DPS passes per tile, in chunks or wide chunks; re-sorts of single tiles with resort=1 in lists mode only, where the host writes a re-sorted tile's whole list)"
    )]
    Strategy(String),
}

impl From<crate::pipeline::PipelineError> for SessionError {
    fn from(e: crate::pipeline::PipelineError) -> Self {
        SessionError::Pipeline(e)
    }
}

/// How the host feeds the engine (see the module docs).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum HostMode {
    /// The host writes every frame's incoming lists and feature words (golden's preprocessing);
    /// the Preprocessing Engine is off.
    #[default]
    Lists,
    /// The host writes the baked scene once; the engine preprocesses every frame.
    Scene,
}

/// Who plans each tile's DPS passes (`adaptive`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Planner {
    /// The host: each descriptor carries the pipeline's passes.
    #[default]
    Host,
    /// The frame controller, from the previous frame's results (`ADAPT_CTRL`,
    /// [`super::adapt`]): the host enables it on every frame that reuses the tables with the
    /// camera moving, and writes 0 passes into those frames' descriptors (a canary: an engine
    /// that read them would run no DPS pass). A still camera or a shot start is planned by the
    /// host, as the pipeline does.
    Engine,
}

/// The regions of scene mode (byte addresses, 4 KiB aligned).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SceneLayout {
    /// Geometry records (`GEO_BASE`).
    pub geo_base: u64,
    /// f32 SH records (`SH_BASE`).
    pub sh_base: u64,
    /// The two feature arenas: frame `f` writes `feat_bases[f % 2]` and reads the other
    /// (`feat_bases[0]` is [`MemoryLayout::feat_base`]).
    pub feat_bases: [u64; 2],
}

/// Where the host puts everything (byte addresses; see the module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MemoryLayout {
    /// Tile descriptors.
    pub desc_base: u64,
    /// Tile results.
    pub result_base: u64,
    /// Frame buffer (tile-major).
    pub fb_base: u64,
    /// Feature table.
    pub feat_base: u64,
    /// Sort scratch.
    pub scratch_base: u64,
    /// The two table arenas.
    pub table_bases: [u64; 2],
    /// Incoming lists.
    pub list_base: u64,
    /// Bytes available for the incoming lists of one frame.
    pub list_bytes: u64,
    /// Scene mode's regions (`None` in lists mode).
    pub scene: Option<SceneLayout>,
}

const PAGE: u64 = 4096;

impl MemoryLayout {
    /// The map for `tiles` tiles and `gaussians` feature words; lists get the rest of the
    /// address space (at most 4 GiB: entry addresses are 32-bit descriptor fields).
    pub fn new(cfg: &EngineConfig, tiles: u64, gaussians: u64) -> Result<MemoryLayout, SessionError> {
        let cap = cfg.table_capacity as u64;
        let mut regions = Regions::new();
        let f = regions.frame(cfg, tiles, gaussians, 1);
        let (desc_base, result_base, fb_base, scratch_base, table_bases) =
            (f.desc_base, f.result_base, f.fb_base, f.scratch_base, f.table_bases);
        let feat_base = f.feat_bases[0];
        let list_base = regions.take(0);
        let top = address_top(cfg);
        if list_base >= top {
            return Err(SessionError::Layout(format!(
                "{tiles} tiles, {gaussians} Gaussians and table_capacity {cap} need 0x{list_base:x} bytes before \
                 the lists, above the 0x{top:x} the address widths reach"
            )));
        }
        Ok(MemoryLayout {
            desc_base,
            result_base,
            fb_base,
            feat_base,
            scratch_base,
            table_bases,
            list_base,
            list_bytes: top - list_base,
            scene: None,
        })
    }
}

/// Page-aligned regions handed out in order from the first page.
struct Regions {
    at: u64,
}

/// The regions both memory maps start with.
struct FrameRegions {
    desc_base: u64,
    result_base: u64,
    fb_base: u64,
    feat_bases: Vec<u64>,
    scratch_base: u64,
    table_bases: [u64; 2],
}

impl Regions {
    fn new() -> Regions {
        Regions { at: PAGE }
    }

    /// The next region of `bytes` bytes.
    fn take(&mut self, bytes: u64) -> u64 {
        let base = self.at;
        self.at = (self.at + bytes).div_ceil(PAGE) * PAGE;
        base
    }

    /// Descriptors, results, frame buffer (tile-major), `feature_arenas` feature tables, sort
    /// scratch (`2 table_capacity` entries per sorting core), two table arenas (`table_capacity`
    /// entries per tile).
    fn frame(
        &mut self,
        cfg: &EngineConfig,
        tiles: u64,
        gaussians: u64,
        feature_arenas: usize,
    ) -> FrameRegions {
        let rc = cfg.raster_config();
        let cap = cfg.table_capacity as u64;
        let desc_base = self.take(tiles * DESCRIPTOR_BYTES);
        let result_base = self.take(tiles * RESULT_BYTES);
        let fb_base = self.take(tiles * (rc.tile * rc.tile) as u64 * PIXEL_BYTES);
        let feat_bases = (0..feature_arenas).map(|_| self.take(gaussians * FEATURE_BYTES)).collect();
        let scratch_base = self.take(cfg.sort_cores as u64 * 2 * cap * ENTRY_BYTES);
        let table_bases = [self.take(tiles * cap * ENTRY_BYTES), self.take(tiles * cap * ENTRY_BYTES)];
        FrameRegions { desc_base, result_base, fb_base, feat_bases, scratch_base, table_bases }
    }
}

/// The first byte address the engine cannot reach (AXI address width; entry addresses are
/// 32-bit descriptor fields of `addr_bits`).
fn address_top(cfg: &EngineConfig) -> u64 {
    (1u64 << cfg.axi_addr_bits.min(64 - 1)).min(ENTRY_BYTES << cfg.addr_bits.min(32))
}

/// How a session runs ([`EngineSession::with_options`]); the default is lists mode, Neo's
/// strategy and binary32 SH records.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SessionOptions {
    /// Who preprocesses.
    pub mode: HostMode,
    /// The pipeline's sorting strategy.
    pub strategy: Strategy,
    /// The baked SH records' precision (scene mode: what the engine reads, [`super::PRE_SH_HALF`]).
    pub sh: ShPrecision,
    /// Who plans the DPS passes (`adaptive` without re-sorts and the wide chunk).
    pub planner: Planner,
}

impl Default for SessionOptions {
    fn default() -> Self {
        SessionOptions {
            mode: HostMode::Lists,
            strategy: Strategy::Neo,
            sh: Preprocessing::DEFAULT_SH,
            planner: Planner::Host,
        }
    }
}

/// One frame for the engine: the host's writes are already in the memory passed to
/// [`EngineSession::next_frame`]; program `regs`, start, then check against `expected`.
#[derive(Clone, Debug)]
pub struct FramePlan {
    /// Frame index in the trajectory.
    pub frame: usize,
    /// Whether every tile is sorted from scratch.
    pub from_scratch: bool,
    /// The registers to program.
    pub regs: FrameRegs,
    /// What the frame must leave.
    pub expected: Expected,
}

/// A table the engine left in memory: entry address and length.
#[derive(Clone, Copy, Debug, Default)]
struct Placed {
    addr: u64,
    len: u32,
}

/// Frames of one scene along one trajectory, for the engine (see the module docs).
pub struct EngineSession<'s> {
    cfg: EngineConfig,
    traj: Trajectory,
    pipeline: Pipeline<'s>,
    layout: MemoryLayout,
    gaussians: usize,
    next: usize,
    prev: Vec<Placed>,
    present: Vec<bool>,
    force_cut: bool,
    mode: HostMode,
    scene_written: bool,
    /// `ADAPT_CTRL` when the engine plans ([`Planner::Engine`]).
    adapt: Option<AdaptRegs>,
}

impl<'s> EngineSession<'s> {
    /// A session rendering `traj` (its cameras' resolution) of `scene` for engine `cfg`, the
    /// host writing the lists and feature words ([`HostMode::Lists`]).
    pub fn new(scene: &'s Scene, traj: Trajectory, cfg: &EngineConfig) -> Result<Self, SessionError> {
        Self::with_mode(scene, traj, cfg, HostMode::Lists)
    }

    /// [`EngineSession::new`] in scene mode: the engine preprocesses the baked scene
    /// ([`HostMode::Scene`]).
    pub fn from_scene(scene: &'s Scene, traj: Trajectory, cfg: &EngineConfig) -> Result<Self, SessionError> {
        Self::with_mode(scene, traj, cfg, HostMode::Scene)
    }

    /// A session in `mode` (see the module docs), Neo's strategy.
    pub fn with_mode(
        scene: &'s Scene,
        traj: Trajectory,
        cfg: &EngineConfig,
        mode: HostMode,
    ) -> Result<Self, SessionError> {
        Self::with_strategy(scene, traj, cfg, mode, Strategy::Neo)
    }

    /// A session in `mode` whose pipeline sorts with `strategy`: `neo`, or `adaptive` without
    /// the wide chunk and the re-sort, whose per-tile DPS passes go into the descriptors.
    pub fn with_strategy(
        scene: &'s Scene,
        traj: Trajectory,
        cfg: &EngineConfig,
        mode: HostMode,
        strategy: Strategy,
    ) -> Result<Self, SessionError> {
        Self::with_options(scene, traj, cfg, SessionOptions { mode, strategy, ..SessionOptions::default() })
    }

    /// A session of `opts` ([`EngineSession::with_strategy`], with the SH records' precision).
    pub fn with_options(
        scene: &'s Scene,
        traj: Trajectory,
        cfg: &EngineConfig,
        opts: SessionOptions,
    ) -> Result<Self, SessionError> {
        let SessionOptions { mode, strategy, sh, planner } = opts;
        cfg.validate()?;
        let adapt = match (planner, strategy) {
            (Planner::Host, _) => None,
            (Planner::Engine, Strategy::Adaptive(p)) => {
                Some(AdaptRegs::deciding(&p, cfg.dps_wide).map_err(SessionError::Planner)?)
            }
            (Planner::Engine, s) => {
                return Err(SessionError::Planner(format!("{s} is not adaptive: there is nothing to plan")))
            }
        };
        let runs = match strategy {
            Strategy::Neo => true,
            Strategy::Adaptive(p) => {
                (p.wide == 1 || p.wide as usize == cfg.dps_wide)
                    && (!p.resort || mode == HostMode::Lists)
                    && p.max_passes <= MAX_DPS_PASSES as u32
            }
            _ => false,
        };
        if !runs {
            return Err(SessionError::Strategy(format!(
                "{strategy} on an engine with dps_wide {}",
                cfg.dps_wide
            )));
        }
        if mode == HostMode::Scene && !cfg.has_preprocessing() {
            return Err(SessionError::NoPreprocessing);
        }
        let first = traj.frames.first().ok_or(SessionError::NoFrames)?;
        let pipeline = pipeline_for(scene, cfg, (first.width, first.height), strategy, sh)?;
        let [gx, gy] = pipeline.grid();
        let max_grid = (1u64 << cfg.tile_bits.min(32)) - 1;
        if gx as u64 > max_grid || gy as u64 > max_grid {
            return Err(SessionError::Layout(format!(
                "{}x{} px gives a {gx}x{gy} tile grid: the {}-bit tile indices (tile_bits) hold at most {max_grid} tiles a side",
                first.width, first.height, cfg.tile_bits
            )));
        }
        let tiles = gx as u64 * gy as u64;
        let layout = match mode {
            HostMode::Lists => MemoryLayout::new(cfg, tiles, scene.len() as u64)?,
            HostMode::Scene => {
                MemoryLayout::for_scene(cfg, tiles, scene.len() as u64, (scene.sh_degree, sh))?
            }
        };
        let session = EngineSession {
            cfg: cfg.clone(),
            traj,
            pipeline,
            layout,
            gaussians: scene.len(),
            next: 0,
            prev: vec![Placed::default(); tiles as usize],
            present: vec![false; scene.len()],
            force_cut: false,
            mode,
            scene_written: false,
            adapt,
        };
        // The bases are the same every frame: refuse a map the engine cannot use up front.
        let cam = session.traj.frames[0].clone();
        session.regs(0, &cam, true).check(cfg).map_err(|e| SessionError::Layout(e.to_string()))?;
        Ok(session)
    }

    /// The memory map.
    pub fn layout(&self) -> &MemoryLayout {
        &self.layout
    }

    /// The engine configuration.
    pub fn config(&self) -> &EngineConfig {
        &self.cfg
    }

    /// Frames in the trajectory.
    pub fn frames(&self) -> usize {
        self.traj.len()
    }

    /// Tiles per frame.
    pub fn tiles(&self) -> usize {
        self.prev.len()
    }

    /// How the host feeds the engine.
    pub fn mode(&self) -> HostMode {
        self.mode
    }

    /// Renders the next frame with the golden pipeline, writes the host's inputs for it into
    /// `mem` (which holds the engine's previous frame) and returns the plan; `None` after the
    /// last frame.
    pub fn next_frame(&mut self, mem: &mut Memory) -> Result<Option<FramePlan>, SessionError> {
        let f = self.next;
        let Some(cam) = self.traj.frames.get(f).cloned() else { return Ok(None) };
        self.next += 1;
        let cut = f == 0 || self.traj.cuts.contains(&f) || self.force_cut;
        let prev_tables: Vec<Vec<SortEntry>> = self.pipeline.tables().map(|t| t.to_vec()).collect();
        let out = self.pipeline.render_frame(&cam, f, cut);
        if out.stats.from_scratch != cut {
            return Err(SessionError::Inconsistent(format!(
                "frame {f}: the pipeline sorted from scratch = {}, the host expected {cut}",
                out.stats.from_scratch
            )));
        }
        let mut regs = self.regs(f, &cam, cut);
        regs.check(&self.cfg).map_err(|e| SessionError::Layout(e.to_string()))?;
        // The engine plans a reuse frame with the camera moving (the pipeline plans the others
        // as a still camera or a shot start).
        let moving = out.stats.camera != CameraMotion::default();
        if let (false, true, Some(a)) = (cut, moving, self.adapt) {
            regs.adapt = a;
        }
        let scratch: Vec<bool> =
            (0..self.prev.len()).map(|t| cut || out.tiles.from_scratch[t] != 0).collect();
        let lists = self.incoming_lists(&scratch, &prev_tables);
        let expected = match self.mode {
            HostMode::Lists => {
                let descriptors = self.write_lists(mem, f, &scratch, &lists, &out)?;
                for (t, d) in descriptors.iter().enumerate() {
                    mem.write_descriptor(regs.desc_base, t as u64, &as_written(&regs, d));
                }
                self.write_features(mem);
                self.expected(mem, regs, descriptors, &prev_tables, &out)
            }
            HostMode::Scene => self.scene_frame(mem, regs, f, cut, lists, &prev_tables, &out)?,
        };
        self.force_cut = expected.outcome.overflows > 0;
        for (t, d) in expected.descriptors.iter().enumerate() {
            self.prev[t] = Placed { addr: d.next as u64, len: expected.outcome.results[t].next_len };
        }
        Ok(Some(FramePlan { frame: f, from_scratch: cut, regs, expected }))
    }

    fn regs(&self, f: usize, cam: &crate::camera::Camera, cut: bool) -> FrameRegs {
        let l = &self.layout;
        if let Some(s) = &l.scene {
            return self.scene_regs(s, f, cam, cut);
        }
        FrameRegs {
            frame: f as u32,
            tiles: self.prev.len() as u32,
            width: cam.width,
            height: cam.height,
            desc_base: l.desc_base,
            result_base: l.result_base,
            feat_base: l.feat_base,
            fb_base: l.fb_base,
            scratch_base: l.scratch_base,
            pre: PreRegs::default(),
            adapt: AdaptRegs::default(),
        }
    }

    /// Every tile's incoming list of the frame the pipeline just rendered: its current list
    /// (`scratch[t]`: a cut, or the strategy re-sorted the tile), or the entries of it not valid
    /// in the tile's previous table.
    fn incoming_lists(&self, scratch: &[bool], prev_tables: &[Vec<SortEntry>]) -> Vec<Vec<SortEntry>> {
        self.pipeline
            .current_lists()
            .enumerate()
            .map(|(t, current)| {
                if scratch[t] {
                    current.to_vec()
                } else {
                    let valid: std::collections::HashSet<u32> =
                        prev_tables[t].iter().filter(|e| e.valid).map(|e| e.id).collect();
                    current.iter().filter(|e| !valid.contains(&e.id)).copied().collect()
                }
            })
            .collect()
    }

    /// Writes every tile's incoming list (compact) and returns the descriptors (`scratch[t]`:
    /// tile `t` is sorted from scratch, its previous table dropped).
    fn write_lists(
        &self,
        mem: &mut Memory,
        f: usize,
        scratch: &[bool],
        lists: &[Vec<SortEntry>],
        frame: &FrameOutput,
    ) -> Result<Vec<TileDescriptor>, SessionError> {
        let fmt = self.cfg.format();
        let cap = self.cfg.table_capacity as u64;
        let gx = self.pipeline.grid()[0] as usize;
        let mut list_at = self.layout.list_base / ENTRY_BYTES;
        let list_end = list_at + self.layout.list_bytes / ENTRY_BYTES;
        let mut next_at = self.layout.table_bases[f % 2] / ENTRY_BYTES;
        let mut out = Vec::with_capacity(self.prev.len());
        for (t, list) in lists.iter().enumerate() {
            if list_at + list.len() as u64 > list_end {
                return Err(SessionError::Layout(format!(
                    "frame {f}: the incoming lists exceed the address space"
                )));
            }
            mem.write_entries(&fmt, list_at, list);
            let prev = if scratch[t] { Placed::default() } else { self.prev[t] };
            let d = TileDescriptor {
                tile_x: (t % gx) as u16,
                tile_y: (t / gx) as u16,
                from_scratch: scratch[t],
                prev: prev.addr as u32,
                prev_len: prev.len,
                list: list_at as u32,
                list_len: list.len() as u32,
                next: next_at as u32,
                dps_passes: dps_passes(frame, t)?,
                dps_wide: frame.tiles.dps_wide[t] == 1,
            };
            list_at += list.len() as u64;
            next_at += (prev.len as u64 + list.len() as u64).min(cap);
            out.push(d);
        }
        Ok(out)
    }

    /// Writes the feature word of every Gaussian present this frame and clears those present
    /// in the previous frame only (the rest are still zero).
    fn write_features(&mut self, mem: &mut Memory) {
        let fmt = self.cfg.feature_format();
        let word = self.layout.feat_base / FEATURE_BYTES;
        for id in 0..self.gaussians {
            let f = self.pipeline.feature(id as u32);
            if f.is_some() || self.present[id] {
                mem.write_feature(&fmt, word + id as u64, f);
            }
            self.present[id] = f.is_some();
        }
    }

    /// The expected state from the pipeline's tables and frame; writes the canaries of
    /// overflowing tiles.
    fn expected(
        &self,
        mem: &mut Memory,
        regs: FrameRegs,
        descriptors: Vec<TileDescriptor>,
        prev_tables: &[Vec<SortEntry>],
        out: &FrameOutput,
    ) -> Expected {
        let (fmt, rc) = (self.cfg.format(), self.cfg.raster_config());
        let (cap, chunk) = (self.cfg.table_capacity as u64, self.cfg.chunk as u64);
        let mut o =
            FrameOutcome { status: STATUS_DONE, first_overflow: NO_OVERFLOW, ..FrameOutcome::default() };
        let (mut tables, mut untouched, mut pixels) = (Vec::new(), Vec::new(), Vec::new());
        let tiles = descriptors.iter().enumerate().zip(self.pipeline.tables().zip(self.pipeline.disorder()));
        for ((t, d), (table, (inversions, wb))) in tiles {
            let t64 = t as u64;
            let overflow = d.entries_in() > cap;
            let table = if overflow { Vec::new() } else { table.to_vec() };
            if overflow {
                untouched.extend(self.overflow_regions(mem, t64, d, prev_tables));
                o.status |= STATUS_OVERFLOW;
                if o.overflows == 0 {
                    o.first_overflow = t as u32;
                }
                o.overflows += 1;
            } else {
                let (rd, wr) = sort_traffic(d, table.len() as u64, chunk);
                o.counters.add(Counter::TilesSorted, 1);
                o.counters.add(Counter::EntriesSorted, d.entries_in());
                o.counters.add(Counter::RdSort, ENTRY_BYTES * rd);
                o.counters.add(Counter::WrSort, ENTRY_BYTES * wr);
            }
            add_raster_traffic(&mut o.counters, table.len() as u64, (rc.tile * rc.tile) as u64);
            o.results.push(match overflow {
                true => TileResult::overflowed(),
                false => TileResult::new(table.len() as u32, false, inversions as u64, &wb),
            });
            pixels.push(if overflow {
                vec![[0; 3]; (rc.tile * rc.tile) as usize]
            } else {
                tile_pixels(out, d, rc.tile)
            });
            tables.push(table);
        }
        let tiles = descriptors.len() as u64;
        o.counters.add(Counter::RdDesc, DESCRIPTOR_BYTES * tiles);
        o.counters.add(Counter::WrResult, RESULT_BYTES * tiles);
        if regs.adapt.enabled() {
            // The previous results, read in the scan and again in the walk.
            o.counters.add(Counter::RdResult, 2 * RESULT_BYTES * tiles);
        }
        let descriptors = descriptors.iter().map(|d| as_written(&regs, d)).collect();
        Expected {
            regs,
            descriptors,
            tables,
            untouched,
            pixels,
            outcome: o,
            format: fmt,
            tile: rc.tile,
            pre: None,
        }
    }

    /// An overflowing tile's next region (filled with a canary now) and previous table.
    fn overflow_regions(
        &self,
        mem: &mut Memory,
        t: u64,
        d: &TileDescriptor,
        prev_tables: &[Vec<SortEntry>],
    ) -> Vec<Untouched> {
        let fmt = self.cfg.format();
        let len = (d.prev_len as u64 + d.list_len as u64).min(self.cfg.table_capacity as u64);
        let canary: Vec<u64> = (0..len).map(|i| 0xCA7A_0000_0000_0000 | (t << 32) | i).collect();
        for (i, w) in canary.iter().enumerate() {
            mem.write_u64(ENTRY_BYTES * (d.next as u64 + i as u64), *w);
        }
        let mut v = vec![Untouched { tile: t, addr: d.next as u64, words: canary }];
        if !d.from_scratch && d.prev_len > 0 {
            let words = prev_tables[t as usize].iter().map(|e| entry_to_u64(&fmt, e)).collect();
            v.push(Untouched { tile: t, addr: d.prev as u64, words });
        }
        v
    }
}

/// A descriptor as the host writes it for a frame of `regs`: without DPS passes (0, not wide)
/// when the engine plans them (`ADAPT_CTRL`).
pub(super) fn as_written(regs: &FrameRegs, d: &TileDescriptor) -> TileDescriptor {
    match regs.adapt.enabled() {
        true => TileDescriptor { dps_passes: 0, dps_wide: false, ..*d },
        false => *d,
    }
}

/// The DPS passes the pipeline ran on tile `t` this frame (0 for a sort from scratch), as a
/// descriptor carries them.
fn dps_passes(out: &FrameOutput, t: usize) -> Result<u8, SessionError> {
    let p = out.tiles.dps_passes[t];
    u8::try_from(p).ok().filter(|&p| p <= MAX_DPS_PASSES).ok_or_else(|| {
        SessionError::Inconsistent(format!(
            "tile {t}: {p} DPS passes, a descriptor holds at most {MAX_DPS_PASSES}"
        ))
    })
}

/// The golden pipeline (`strategy`, no capacity cut, no references) for engine `cfg` at
/// `width x height`.
pub(crate) fn pipeline_for<'s>(
    scene: &'s Scene,
    cfg: &EngineConfig,
    (width, height): (u32, u32),
    strategy: Strategy,
    sh: ShPrecision,
) -> Result<Pipeline<'s>, SessionError> {
    let pcfg = PipelineConfig {
        strategy,
        raster: cfg.raster_config(),
        chunk: cfg.chunk,
        dps_passes: 1,
        raster_window: cfg.raster_window,
        capacity: None,
        compare_exact: false,
        compare_float: false,
        ssim: false,
        window_needed: false,
        exact_shortcut: true,
        preprocess: Preprocessing::Hardware(sh),
    };
    let formats =
        Formats { feature: cfg.feature_format(), key: DepthKeyCodec::Fp16, sort: cfg.sort_config() };
    Ok(Pipeline::new(scene, pcfg, formats, width, height)?)
}

/// Tile `d`'s pixels of the pipeline's frame (row-major, black outside the image).
fn tile_pixels(out: &FrameOutput, d: &TileDescriptor, tile: u32) -> Vec<[u8; 3]> {
    let img = &out.image;
    let mut px = Vec::with_capacity((tile * tile) as usize);
    for y in 0..tile {
        for x in 0..tile {
            let (gx, gy) = (d.tile_x as u32 * tile + x, d.tile_y as u32 * tile + y);
            px.push(if gx < img.width && gy < img.height {
                let i = 3 * (gy as usize * img.width as usize + gx as usize);
                [img.data[i], img.data[i + 1], img.data[i + 2]]
            } else {
                [0; 3]
            });
        }
    }
    px
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The golden pipeline's refusal says its cause once, also where the whole chain of
    /// sources is printed: it has none.
    #[test]
    fn a_pipeline_refusal_says_its_cause_once() {
        use crate::pipeline::PipelineError;
        let e = SessionError::from(PipelineError::Other("image size 0x4 is empty".into()));
        assert_eq!(e.to_string(), "golden pipeline: image size 0x4 is empty");
        assert!(std::error::Error::source(&e).is_none());
    }

    #[test]
    fn layout_regions_are_ordered_aligned_and_disjoint() {
        let cfg = EngineConfig::default();
        let l = MemoryLayout::new(&cfg, 80, 150_000).expect("fits 4 GiB");
        let bases = [l.desc_base, l.result_base, l.fb_base, l.feat_base, l.scratch_base, l.table_bases[0]];
        assert!(bases.windows(2).all(|w| w[0] < w[1]));
        assert!(bases.iter().all(|b| b % PAGE == 0 && *b > 0));
        assert_eq!(l.fb_base - l.result_base, PAGE, "80 results (16 bytes each) fit a page");
        assert_eq!(l.table_bases[1] - l.table_bases[0], 80 * 65536 * 8);
        assert_eq!(l.list_base + l.list_bytes, 1 << 32);
    }

    #[test]
    fn scene_layout_adds_aligned_disjoint_scene_regions() {
        let cfg = EngineConfig { table_capacity: 61, ..EngineConfig::default() };
        let l = MemoryLayout::for_scene(&cfg, 80, 150_000, (3, ShPrecision::F32)).expect("fits 4 GiB");
        let s = l.scene.expect("scene regions");
        assert_eq!(s.feat_bases[0], l.feat_base);
        let bases = [
            l.desc_base,
            l.fb_base,
            s.feat_bases[0],
            s.feat_bases[1],
            l.scratch_base,
            l.table_bases[0],
            l.table_bases[1],
            s.geo_base,
            s.sh_base,
            l.list_base,
        ];
        assert!(bases.windows(2).all(|w| w[0] < w[1]) && bases.iter().all(|b| b % PAGE == 0));
        assert!(s.feat_bases[1] - s.feat_bases[0] >= 150_000 * 32);
        assert!(s.sh_base - s.geo_base >= 150_000 * 44 && l.list_base - s.sh_base >= 150_000 * 48 * 4);
        assert_eq!(l.list_bytes, 80 * 64 * 8, "61 entries round up to 8 lines of 8");
        let e = MemoryLayout::for_scene(&cfg, 4096, 10, (0, ShPrecision::F32)).expect_err("too many tiles");
        assert!(e.to_string().contains("pre_max_tiles 2048"), "{e}");
    }

    #[test]
    fn a_tile_grid_wider_than_the_tile_indices_is_refused() {
        let (scene, _) =
            crate::source::load_scene("synthetic:blobs?gaussians=10&seed=1", false).expect("scene");
        let bounds = crate::source::robust_bounds(&scene);
        let traj = crate::trajectory::parse_trajectory("orbit:res=640x480", bounds, 1).expect("orbit");
        // 640x480 at 64-pixel tiles is a 10x8 grid; 3-bit tile indices hold at most 7.
        let cfg = EngineConfig { tile_bits: 3, ..EngineConfig::default() };
        let e = EngineSession::new(&scene, traj.clone(), &cfg)
            .err()
            .expect("a 10x8 grid with 3-bit tile indices");
        assert!(e.to_string().contains("10x8 tile grid") && e.to_string().contains("at most 7"), "{e}");
        let cfg = EngineConfig { tile_bits: 4, ..EngineConfig::default() };
        assert!(EngineSession::new(&scene, traj, &cfg).is_ok(), "4 bits hold 15 tiles a side");
    }

    #[test]
    fn a_map_beyond_the_address_width_is_refused() {
        let cfg = EngineConfig { addr_bits: 16, ..EngineConfig::default() };
        let e = MemoryLayout::new(&cfg, 4, 1000).expect_err("16-bit entry addresses");
        assert!(e.to_string().contains("address widths"), "{e}");
    }
}
