//! The Preprocessing Engine's bench (`neo_pre_engine` against golden
//! `engine::preprocess_frame`): the baked scene in an [`AxiMemory`] with one port per AXI4
//! manager of the engine (two per lane, the list writer), the driver programs a camera and starts
//! it, [`AxiChecker`]s watch every port, and the checker compares what the engine leaves in memory
//! with what golden's memory-level reference leaves in a copy of the same memory, programmed with
//! the same registers ([`FrameRegs`], from which the bench also drives the ports):
//!
//! - every Gaussian's feature word (and the canary word after the last);
//! - every tile's descriptor (the list length in bytes 20..24; the rest keeps its canary);
//! - every tile's incoming list as a multiset (the lanes interleave their hits; golden appends in
//!   Gaussian order), the rest of its last line zero.
//!
//! The engine's managers are packed buses; the bench verilates it inside a wrapper
//! (`neo_pre_engine_tb`, built here, not in `hdl/`) that names manager `q`'s signals
//! `m{q}_axi_*`.

use crate::axi::{AxiBinding, AxiChecker, AxiMemory, AxiTiming, SubordinateSignals};
use crate::check::Checker;
use crate::dynmodel::DynModel;
use crate::lane::{complement_bases, LaneFrame};
use crate::lane::{FEAT_BASE, GEO_BASE, PREV_BASE, SH_BASE};
use crate::rng::Rng;
use neo_gen::emit::Module;
use neo_gen::units::axi;
use neo_gen::units::pre::engine::{managers, NAME};
use neo_gen::EngineConfig;
use neo_golden::engine::memory::{
    entry_from_u64, entry_to_u64, feature_from_bytes, Memory, DESCRIPTOR_BYTES, ENTRY_BYTES, FEATURE_BYTES,
};
use neo_golden::engine::pre::sh_array_bytes;
use neo_golden::engine::{
    preprocess_frame, CameraWord, Counters, FrameRegs, PreRegs, PreWork, PRE_ENABLE, PRE_FRESH,
};
use neo_golden::hwpre::bake::{Baked, ShPrecision};
use neo_golden::hwpre::camera_registers;

/// The configuration the bench runs (`tb/pre_engine.json`: two lanes).
pub fn bench_config() -> EngineConfig {
    serde_json::from_str(include_str!("../pre_engine.json"))
        .expect("tb/pre_engine.json is an engine configuration")
}

/// Name of the bench wrapper.
const WRAPPER: &str = "neo_pre_engine_tb";
/// Byte address of the incoming lists.
pub const LIST_BASE: u64 = 0x1000_0000;
/// Byte address of the descriptors.
pub const DESC_BASE: u64 = 0x0f00_0000;
/// What the descriptors hold before the run (the engine writes only the list lengths).
const DESC_CANARY: u8 = 0x5c;
/// What the feature word after the last Gaussian holds (the engine must keep it).
const FEAT_CANARY: u8 = 0xa5;

/// A run's map and sizes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EngineSetup {
    /// The base registers.
    pub bases: EngineBases,
    /// GAUSSIANS (`None`: the scene's).
    pub gaussians: Option<u32>,
    /// TILES (`None`: the camera's grid; more: the extra tiles' lists are empty).
    pub tiles: Option<u32>,
}

/// Where a run's arrays sit (the engine's base registers).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EngineBases {
    /// Geometry array (4-byte aligned).
    pub geo: u64,
    /// SH array (4-byte aligned).
    pub sh: u64,
    /// Feature table (32-byte aligned).
    pub feat: u64,
    /// Previous feature table (32-byte aligned).
    pub prev: u64,
    /// Tile 0's incoming list (64-byte aligned).
    pub list: u64,
    /// Tile 0's descriptor (32-byte aligned).
    pub desc: u64,
}

impl EngineBases {
    /// The bench's constant map.
    pub const FIXED: EngineBases = EngineBases {
        geo: GEO_BASE,
        sh: SH_BASE,
        feat: FEAT_BASE,
        prev: PREV_BASE,
        list: LIST_BASE,
        desc: DESC_BASE,
    };

    /// Two maps for up to `n` Gaussians and `tiles` tiles of `cfg`, each base the bitwise
    /// complement of the other's above its alignment (alternating them toggles every base bit),
    /// drawn until every array of each fits below 2^32 and none overlaps another.
    pub fn complement_pair(cfg: &EngineConfig, rng: &mut Rng, n: u64, tiles: u64) -> [EngineBases; 2] {
        let gb = u64::from(neo_golden::hwpre::bake::geometry_bytes());
        let sizes = [
            (gb * n, 4),
            (4 * 48 * n, 4),
            (FEATURE_BYTES * (n + 1), 32),
            (FEATURE_BYTES * n, 32),
            (neo_golden::engine::pre::list_addr(cfg, 0, tiles), 64),
            (DESCRIPTOR_BYTES * tiles, 32),
        ];
        loop {
            let pairs: Vec<[u64; 2]> =
                sizes.iter().map(|&(_, a)| complement_bases(rng.next_u64(), a)).collect();
            let pick = |k: usize| -> Vec<u64> { pairs.iter().map(|p| p[k]).collect() };
            let fits = |v: &[u64]| {
                v.iter().zip(&sizes).all(|(&b, &(s, _))| b + s <= 1 << 32)
                    && (0..6)
                        .all(|i| (i + 1..6).all(|j| v[i] + sizes[i].0 <= v[j] || v[j] + sizes[j].0 <= v[i]))
            };
            let (a, b) = (pick(0), pick(1));
            if fits(&a) && fits(&b) {
                let mk = |v: &[u64]| EngineBases {
                    geo: v[0],
                    sh: v[1],
                    feat: v[2],
                    prev: v[3],
                    list: v[4],
                    desc: v[5],
                };
                return [mk(&a), mk(&b)];
            }
        }
    }
}

/// What a run measured.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct PreRun {
    /// Gaussians, and those of them visible.
    pub gaussians: u64,
    /// Visible Gaussians.
    pub visible: u64,
    /// Incoming (Gaussian, tile) entries written.
    pub hits: u64,
    /// Tiles of the frame.
    pub tiles: u64,
    /// Cycles from the start to `done_o`.
    pub cycles: u64,
    /// Read and write beats over all ports.
    pub beats: (u64, u64),
    /// The feature words written (the next frame's previous words).
    pub table: Vec<[u8; 32]>,
}

/// A Verilated `neo_pre_engine` in its wrapper.
pub struct PreEngineBench {
    cfg: EngineConfig,
    model: DynModel,
    ports: Vec<AxiBinding>,
    start: usize,
    busy: usize,
    done: usize,
}

/// The wrapper: `neo_pre_engine` with manager `q`'s signals as ports `m{q}_axi_*`.
fn wrapper(cfg: &EngineConfig) -> Module {
    let inner = neo_gen::units::pre::engine::module(cfg);
    let mut m = Module::new(WRAPPER);
    m.doc("Bench wrapper of neo_pre_engine: manager q's AXI4 signals as ports m<q>_axi_*.");
    let mut conns = Vec::new();
    for p in inner.interface().ports.iter().filter(|p| !p.name.starts_with("m_axi_")) {
        if p.dir == neo_gen::interface::Dir::In {
            m.input(p.name.clone(), p.width);
        } else {
            m.output(p.name.clone(), p.width);
        }
        conns.push((p.name.clone(), p.name.clone()));
    }
    let n = managers(cfg);
    for s in axi::signals(cfg) {
        let bus = format!("bus_{}", s.name);
        m.wire(bus.clone(), n as u32 * s.width);
        conns.push((axi::port_name("m_axi_", &s, true), bus.clone()));
        for q in 0..n {
            let port = axi::port_name(&format!("m{q}_axi_"), &s, true);
            let slice = format!("{bus}[{} +: {}]", q as u32 * s.width, s.width);
            if s.from_manager {
                m.output(port.clone(), s.width);
                m.assign(port, slice);
            } else {
                m.input(port.clone(), s.width);
                m.assign(slice, port);
            }
        }
    }
    m.instance(NAME, "u_pre", conns);
    m.config_hash = Some(cfg.hash());
    m
}

impl PreEngineBench {
    /// Builds (or loads from the cache) the Preprocessing Engine of `cfg`.
    pub fn build(cfg: &EngineConfig) -> Result<Self, String> {
        let (mut files, vlt) = crate::dynmodel::generated_files(cfg, NAME)?;
        let w = wrapper(cfg);
        files.push((format!("{WRAPPER}.v"), w.to_verilog()));
        let iface = w.interface();
        let vlt = crate::coverage::only_in(
            vlt,
            &files,
            &[format!("{NAME}.v").as_str(), format!("{WRAPPER}.v").as_str()],
        );
        let (model, _) = DynModel::build_for_short_runs(&iface, &files, Some(&vlt), None)?;
        let ports = (0..managers(cfg))
            .map(|q| AxiBinding::bind(&model, &format!("m{q}_axi_"), true))
            .collect::<Result<_, _>>()?;
        let (start, busy, done) = (model.port("start_i")?, model.port("busy_o")?, model.port("done_o")?);
        Ok(PreEngineBench { cfg: cfg.clone(), model, ports, start, busy, done })
    }

    /// The model, for waves.
    pub fn model_mut(&mut self) -> &mut DynModel {
        &mut self.model
    }

    /// The registers of a frame of `baked` for `frame` (the engine's memory map of the bench):
    /// what golden's reference reads, and what [`PreEngineBench::program`] drives.
    pub fn frame_regs(&self, baked: &Baked, frame: &LaneFrame, at: &EngineSetup) -> FrameRegs {
        let (regs, _) = camera_registers(frame.cam, self.cfg.tile);
        let tiles = at.tiles.unwrap_or(regs.grid[0] as u32 * regs.grid[1] as u32);
        let fresh = if frame.all_fresh { PRE_FRESH } else { 0 };
        let b = &at.bases;
        FrameRegs {
            tiles,
            desc_base: b.desc,
            feat_base: b.feat,
            pre: PreRegs {
                ctrl: PRE_ENABLE | fresh | PreRegs::sh_ctrl(baked.sh_precision),
                gaussians: at.gaussians.unwrap_or(baked.len() as u32),
                sh_degree: u32::from(baked.sh_degree),
                geo_base: b.geo,
                sh_base: b.sh,
                prev_feat_base: b.prev,
                list_base: b.list,
                camera: CameraWord::values(frame.cam, self.cfg.tile),
            },
            ..FrameRegs::default()
        }
    }

    /// Drives the engine's per-frame inputs from `regs`.
    fn program(&mut self, regs: &FrameRegs) -> Result<(), String> {
        let p = &regs.pre;
        let mut all: Vec<(String, u64)> =
            CameraWord::all().map(|c| (c.port(), u64::from(p.camera[c.0 as usize]))).collect();
        all.push(("degree_i".into(), u64::from(p.sh_degree)));
        all.push(("fresh_i".into(), u64::from(p.fresh())));
        all.push(("sh_half_i".into(), u64::from(p.sh_precision() == ShPrecision::F16)));
        all.push(("gaussians_i".into(), u64::from(p.gaussians)));
        all.push(("geo_base_i".into(), p.geo_base));
        all.push(("sh_base_i".into(), p.sh_base));
        all.push(("feat_base_i".into(), regs.feat_base));
        all.push(("prev_base_i".into(), p.prev_feat_base));
        all.push(("list_base_i".into(), p.list_base));
        all.push(("desc_base_i".into(), regs.desc_base));
        all.push(("tiles_i".into(), u64::from(regs.tiles)));
        for (name, v) in all {
            let port = self.model.port(&name)?;
            self.model.set_u64(port, v);
        }
        Ok(())
    }

    /// Runs the engine over `baked` for `frame` with memory `timing` and checks what it leaves
    /// against golden. Stops the test at the first mismatch.
    pub fn run(&mut self, baked: &Baked, frame: &LaneFrame, timing: AxiTiming, check: &Checker) -> PreRun {
        let at = EngineSetup { bases: EngineBases::FIXED, gaussians: None, tiles: None };
        self.run_at(baked, frame, &at, timing, check)
    }

    /// [`PreEngineBench::run`] with the bases, Gaussian count and tile count of `at`.
    pub fn run_at(
        &mut self,
        baked: &Baked,
        frame: &LaneFrame,
        at: &EngineSetup,
        timing: AxiTiming,
        check: &Checker,
    ) -> PreRun {
        let regs = self.frame_regs(baked, frame, at);
        self.run_regs(baked, frame.prev, &regs, timing, check)
    }

    /// Runs the engine with the registers `regs` as they are (any camera words: golden decodes
    /// the same ones) over `baked` placed at the bases of `regs`, `prev` the previous feature
    /// words, and checks what it leaves against golden. Stops the test at the first mismatch.
    pub fn run_regs(
        &mut self,
        baked: &Baked,
        prev: &[[u8; 32]],
        regs: &FrameRegs,
        timing: AxiTiming,
        check: &Checker,
    ) -> PreRun {
        let n = managers(&self.cfg);
        let mut rng = Rng::new(check.seed);
        let p = &regs.pre;
        let b = EngineBases {
            geo: p.geo_base,
            sh: p.sh_base,
            feat: regs.feat_base,
            prev: p.prev_feat_base,
            list: p.list_base,
            desc: regs.desc_base,
        };
        let mut mem = Memory::new();
        let geo: Vec<u8> = baked.geometry.iter().flat_map(|g| g.to_le_bytes()).collect();
        mem.write(b.geo, &geo);
        mem.write(b.sh, &sh_array_bytes(baked));
        for (k, w) in prev.iter().enumerate() {
            mem.write(b.prev + FEATURE_BYTES * k as u64, w);
        }
        let count = u64::from(regs.pre.gaussians);
        mem.write(b.feat + FEATURE_BYTES * count, &[FEAT_CANARY; FEATURE_BYTES as usize]);
        let tiles = u64::from(regs.tiles);
        self.program(regs).unwrap_or_else(|e| panic!("{NAME}: {e}"));
        mem.write(b.desc, &vec![DESC_CANARY; (DESCRIPTOR_BYTES * tiles) as usize]);
        let mut golden = mem.clone();
        let work = preprocess_frame(&self.cfg, regs, &mut golden, &mut Counters::default())
            .unwrap_or_else(|e| panic!("golden preprocess_frame: {e}"));
        let mut mem = AxiMemory::new(n, mem, timing, rng.next_u64());
        for p in &self.ports {
            p.set_subordinate(&mut self.model, &SubordinateSignals::default());
        }
        self.model.set_u64(self.start, 0);
        self.model.reset();
        let (ro, wo) = (self.cfg.pre_outstanding, self.cfg.pre_outstanding.max(self.cfg.axi_outstanding));
        let mut chk: Vec<AxiChecker> =
            (0..n).map(|q| AxiChecker::new(q, &format!("m{q}_axi"), ro, wo)).collect();
        let hits: u64 = work.lists.iter().map(|l| l.len() as u64).sum();
        let start = self.model.cycle();
        let limit = 5_000 + 200 * count + 4 * hits + 4 * tiles;
        let mut first = true;
        loop {
            self.model.set_u64(self.start, u64::from(first));
            let subs: Vec<SubordinateSignals> = (0..n).map(|q| mem.outputs(q)).collect();
            for (p, s) in self.ports.iter().zip(&subs) {
                p.set_subordinate(&mut self.model, s);
            }
            self.model.eval();
            let cyc = self.model.cycle();
            let (busy, done) = (self.model.get_u64(self.busy) == 1, self.model.get_u64(self.done) == 1);
            check.protocol(cyc, !done || busy, "done_o pulses while busy_o is high");
            for q in 0..n {
                let man = self.ports[q].get_manager(&self.model);
                if let Err(v) = chk[q].observe(&man, &subs[q]) {
                    check.fail(cyc, "AXI protocol", "no violation", &v.to_string());
                }
                mem.tick(q, &man);
            }
            self.model.tick();
            if done {
                break;
            }
            check.protocol(cyc, first || busy, "busy_o stays high until done_o");
            first = false;
            check.protocol(cyc, cyc - start < limit, "the engine finishes within its cycle budget");
        }
        let cycles = self.model.cycle() - start;
        for (q, c) in chk.iter().enumerate() {
            let (r, w) = c.in_flight();
            check.value(cycles, &format!("manager {q}: AXI transactions open at done_o"), 0, (r + w) as u64);
        }
        self.check_feature_words(mem.memory(), &golden, b.feat, count, check, cycles);
        let hits = self.check_lists(mem.memory(), &golden, &work, &b, check, cycles);
        let beats = (0..n).map(|q| mem.beats(q)).fold((0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
        let table = (0..count)
            .map(|i| {
                let mut w = [0u8; 32];
                mem.memory().read(b.feat + 32 * i, &mut w);
                w
            })
            .collect();
        PreRun { gaussians: count, visible: work.visible.len() as u64, hits, tiles, cycles, beats, table }
    }

    /// Checks the feature words of the `n` Gaussians, and the canary word after them, against
    /// golden's memory.
    fn check_feature_words(
        &self,
        mem: &Memory,
        golden: &Memory,
        feat: u64,
        n: u64,
        check: &Checker,
        cycle: u64,
    ) {
        let fmt = self.cfg.feature_format();
        for i in 0..=n {
            let (mut want, mut got) = ([0u8; FEATURE_BYTES as usize], [0u8; FEATURE_BYTES as usize]);
            golden.read(feat + FEATURE_BYTES * i, &mut want);
            mem.read(feat + FEATURE_BYTES * i, &mut got);
            if got != want {
                let show = |b: &[u8; 32]| format!("{:?} (0x{})", feature_from_bytes(&fmt, b), hex(b));
                let what = if i == n {
                    "canary word after the last Gaussian".to_string()
                } else {
                    format!("feature word of Gaussian {i}")
                };
                check.fail(cycle, &what, &show(&want), &show(&got));
            }
        }
    }

    /// Checks every tile's descriptor and list against golden's memory and lists; returns the
    /// entries checked.
    fn check_lists(
        &self,
        mem: &Memory,
        golden: &Memory,
        work: &PreWork,
        b: &EngineBases,
        check: &Checker,
        cycle: u64,
    ) -> u64 {
        let fmt = self.cfg.format();
        let (cap, stride) = (self.cfg.table_capacity as u64, self.cfg.list_stride() as u64);
        let mut checked = 0;
        for (t, want_t) in work.lists.iter().enumerate() {
            let t = t as u64;
            let d = b.desc + DESCRIPTOR_BYTES * t;
            let (mut want_d, mut desc) = ([0u8; DESCRIPTOR_BYTES as usize], [0u8; DESCRIPTOR_BYTES as usize]);
            golden.read(d, &mut want_d);
            mem.read(d, &mut desc);
            let len_at = |b: &[u8; DESCRIPTOR_BYTES as usize]| {
                u64::from(u32::from_le_bytes(b[20..24].try_into().expect("4 bytes")))
            };
            let len = len_at(&desc);
            check.value(
                cycle,
                &format!("tile {t}: list_len (descriptor bytes 20..24)"),
                len_at(&want_d),
                len,
            );
            for (k, (w, b)) in want_d.iter().zip(&desc).enumerate().filter(|(k, _)| !(20..24).contains(k)) {
                check.value(
                    cycle,
                    &format!("tile {t}: descriptor byte {k} (not the engine's)"),
                    u64::from(*w),
                    u64::from(*b),
                );
            }
            let kept = len.min(cap);
            let base = b.list + ENTRY_BYTES * t * stride;
            let mut got: Vec<u64> = (0..kept).map(|i| mem.read_u64(base + ENTRY_BYTES * i)).collect();
            got.sort_unstable_by_key(|w| order(&fmt, *w));
            if (want_t.len() as u64) > cap {
                // Which entries a long list keeps depends on the arrival order: only its length
                // is the contract (the tile overflows).
                checked += kept;
                continue;
            }
            let mut want_kept: Vec<u64> = want_t.iter().map(|e| entry_to_u64(&fmt, e)).collect();
            want_kept.sort_unstable_by_key(|w| order(&fmt, *w));
            for (i, (w, g)) in want_kept.iter().zip(&got).enumerate() {
                if w != g {
                    let show = |x: &u64| format!("{:?} (0x{x:016x})", entry_from_u64(&fmt, *x));
                    check.fail(
                        cycle,
                        &format!("tile {t}: incoming entry {i} (by key, id)"),
                        &show(w),
                        &show(g),
                    );
                }
            }
            for i in kept..kept.next_multiple_of(8) {
                let at = base + ENTRY_BYTES * i;
                check.value(
                    cycle,
                    &format!("tile {t}: list slot {i} past the length"),
                    golden.read_u64(at),
                    mem.read_u64(at),
                );
            }
            checked += kept;
        }
        checked
    }
}

fn hex(b: &[u8; 32]) -> String {
    b.iter().rev().map(|x| format!("{x:02x}")).collect()
}

/// A list word's sort order: key, then id.
fn order(fmt: &neo_golden::sort::SortFormat, w: u64) -> (u32, u32) {
    let e = entry_from_u64(fmt, w);
    (e.key, e.id)
}
