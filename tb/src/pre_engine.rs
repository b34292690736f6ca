//! The Preprocessing Engine's bench (`neo_pre_engine` against golden `hwpre`): the baked scene
//! in an [`AxiMemory`] with one port per AXI4 manager of the engine (two per lane, the list
//! writer), the driver programs a camera and starts it, [`AxiChecker`]s watch every port, and the
//! checker compares what the engine leaves in memory with golden:
//!
//! - every Gaussian's feature word (as the lane bench checks it, [`crate::lane`]);
//! - every tile's list length in its descriptor (bytes 20..24; the rest of the descriptor keeps
//!   its canary);
//! - every tile's incoming list as a multiset (the lanes interleave their hits), the rest of its
//!   last line zero.
//!
//! The engine's managers are packed buses; the bench verilates it inside a wrapper
//! (`neo_pre_engine_tb`, built here, not in `hdl/`) that names manager `q`'s signals
//! `m{q}_axi_*`.

use crate::axi::{AxiBinding, AxiChecker, AxiMemory, AxiTiming, SubordinateSignals};
use crate::check::Checker;
use crate::dynmodel::DynModel;
use crate::lane::{check_feature_words, expected_hits, scene_memory, LaneFrame, LaneHit, LaneRange};
use crate::lane::{FEAT_BASE, GEO_BASE, PREV_BASE, SH_BASE};
use crate::rng::Rng;
use neo_gen::emit::Module;
use neo_gen::units::axi;
use neo_gen::units::pre::engine::{managers, NAME};
use neo_gen::EngineConfig;
use neo_golden::engine::memory::{entry_from_u64, entry_to_u64, Memory, DESCRIPTOR_BYTES, ENTRY_BYTES};
use neo_golden::engine::CameraWord;
use neo_golden::hwpre::bake::Baked;
use neo_golden::hwpre::camera_registers;
use neo_golden::sort::SortEntry;
use std::collections::BTreeMap;

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

    /// Programs the per-frame inputs of `frame` for `baked`; returns the tiles.
    fn program(&mut self, baked: &Baked, frame: &LaneFrame) -> Result<u64, String> {
        let cam = frame.cam;
        let words = CameraWord::values(cam, self.cfg.tile);
        let mut all: Vec<(String, u64)> =
            CameraWord::all().map(|c| (c.port(), u64::from(words[c.0 as usize]))).collect();
        let (regs, _) = camera_registers(cam, self.cfg.tile);
        let tiles = regs.grid[0] as u64 * regs.grid[1] as u64;
        all.push(("degree_i".into(), u64::from(baked.sh_degree)));
        all.push(("fresh_i".into(), u64::from(frame.all_fresh)));
        all.push(("gaussians_i".into(), baked.len() as u64));
        all.push(("geo_base_i".into(), GEO_BASE));
        all.push(("sh_base_i".into(), SH_BASE));
        all.push(("feat_base_i".into(), FEAT_BASE));
        all.push(("prev_base_i".into(), PREV_BASE));
        all.push(("list_base_i".into(), LIST_BASE));
        all.push(("desc_base_i".into(), DESC_BASE));
        all.push(("tiles_i".into(), tiles));
        for (name, v) in all {
            let p = self.model.port(&name)?;
            self.model.set_u64(p, v);
        }
        Ok(tiles)
    }

    /// Runs the engine over `baked` for `frame` with memory `timing` and checks what it leaves
    /// against golden. Stops the test at the first mismatch.
    pub fn run(&mut self, baked: &Baked, frame: &LaneFrame, timing: AxiTiming, check: &Checker) -> PreRun {
        let n = managers(&self.cfg);
        let mut rng = Rng::new(check.seed);
        let all = LaneRange { first: 0, count: baked.len() as u32 };
        let mut mem = scene_memory(baked, all, frame.prev);
        let tiles = self.program(baked, frame).unwrap_or_else(|e| panic!("{NAME}: {e}"));
        mem.write(DESC_BASE, &vec![DESC_CANARY; (DESCRIPTOR_BYTES * tiles) as usize]);
        let mut mem = AxiMemory::new(n, mem, timing, rng.next_u64());
        for p in &self.ports {
            p.set_subordinate(&mut self.model, &SubordinateSignals::default());
        }
        self.model.set_u64(self.start, 0);
        self.model.reset();
        let (ro, wo) = (self.cfg.pre_outstanding, self.cfg.pre_outstanding.max(self.cfg.axi_outstanding));
        let mut chk: Vec<AxiChecker> =
            (0..n).map(|q| AxiChecker::new(q, &format!("m{q}_axi"), ro, wo)).collect();
        let want = expected_hits(&self.cfg, baked, frame, all);
        let start = self.model.cycle();
        let limit = 5_000 + 200 * baked.len() as u64 + 4 * want.len() as u64 + 4 * tiles;
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
        let visible = check_feature_words(&self.cfg, baked, frame.cam, all, mem.memory(), check, cycles);
        let hits = self.check_lists(mem.memory(), &self.want_by_tile(&want, frame), tiles, check, cycles);
        let beats = (0..n).map(|q| mem.beats(q)).fold((0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
        let table = (0..baked.len() as u64)
            .map(|i| {
                let mut b = [0u8; 32];
                mem.memory().read(FEAT_BASE + 32 * i, &mut b);
                b
            })
            .collect();
        PreRun { gaussians: baked.len() as u64, visible, hits, tiles, cycles, beats, table }
    }

    /// Golden's incoming entries, as list words by tile index.
    fn want_by_tile(&self, hits: &[LaneHit], frame: &LaneFrame) -> BTreeMap<u64, Vec<u64>> {
        let fmt = self.cfg.format();
        let (regs, _) = camera_registers(frame.cam, self.cfg.tile);
        let gx = regs.grid[0] as u64;
        let mut by: BTreeMap<u64, Vec<u64>> = BTreeMap::new();
        for h in hits {
            let e = SortEntry { key: h.key, id: h.id, valid: true };
            by.entry(h.tile[1] as u64 * gx + h.tile[0] as u64).or_default().push(entry_to_u64(&fmt, &e));
        }
        by
    }

    /// Checks every tile's list length and entries; returns the entries checked.
    fn check_lists(
        &self,
        mem: &Memory,
        want: &BTreeMap<u64, Vec<u64>>,
        tiles: u64,
        check: &Checker,
        cycle: u64,
    ) -> u64 {
        let fmt = self.cfg.format();
        let (cap, stride) = (self.cfg.table_capacity as u64, self.cfg.list_stride() as u64);
        let mut checked = 0;
        for t in 0..tiles {
            let d = DESC_BASE + DESCRIPTOR_BYTES * t;
            let mut desc = [0u8; DESCRIPTOR_BYTES as usize];
            mem.read(d, &mut desc);
            let none = Vec::new();
            let want_t = want.get(&t).unwrap_or(&none);
            let len = u32::from_le_bytes(desc[20..24].try_into().expect("4 bytes")) as u64;
            check.value(
                cycle,
                &format!("tile {t}: list_len (descriptor bytes 20..24)"),
                want_t.len() as u64,
                len,
            );
            for (k, b) in desc.iter().enumerate().filter(|(k, _)| !(20..24).contains(k)) {
                check.value(
                    cycle,
                    &format!("tile {t}: descriptor byte {k} (not the engine's)"),
                    u64::from(DESC_CANARY),
                    u64::from(*b),
                );
            }
            let kept = len.min(cap);
            let base = LIST_BASE + ENTRY_BYTES * t * stride;
            let mut got: Vec<u64> = (0..kept).map(|i| mem.read_u64(base + ENTRY_BYTES * i)).collect();
            got.sort_unstable_by_key(|w| order(&fmt, *w));
            let mut want_kept: Vec<u64> = want_t.clone();
            if (want_kept.len() as u64) > cap {
                // Which entries a long list keeps depends on the arrival order: only its length
                // is the contract (the tile overflows).
                checked += kept;
                continue;
            }
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
                check.value(
                    cycle,
                    &format!("tile {t}: list slot {i} past the length"),
                    0,
                    mem.read_u64(base + ENTRY_BYTES * i),
                );
            }
            checked += kept;
        }
        checked
    }
}

/// A list word's sort order: key, then id.
fn order(fmt: &neo_golden::sort::SortFormat, w: u64) -> (u32, u32) {
    let e = entry_from_u64(fmt, w);
    (e.key, e.id)
}
