//! The preprocessing lane's bench (`neo_pre_lane` against golden `hwpre::preprocess_one`): the
//! baked scene sits in an [`AxiMemory`] of two ports (the lane's `ma_axi_*` and `mb_axi_*`),
//! the driver programs a camera and starts the lane, [`AxiChecker`]s watch both ports, and the
//! checker compares the feature table the lane wrote, word by word, with golden's feature words
//! (`engine::memory::feature_to_bytes`), stopping at the first mismatch with both entries
//! decoded. The words just outside the lane's range must keep their canary.

use crate::axi::{AxiBinding, AxiChecker, AxiMemory, AxiTiming, SubordinateSignals};
use crate::check::Checker;
use crate::dynmodel::DynModel;
use crate::rng::Rng;
use neo_gen::units::pre::lane::NAME;
use neo_gen::EngineConfig;
use neo_golden::camera::Camera;
use neo_golden::engine::memory::{feature_from_bytes, feature_to_bytes, Memory, FEATURE_BYTES};
use neo_golden::engine::CameraWord;
use neo_golden::hwpre::bake::{geometry_bytes, sh_bytes, Baked, ShPrecision};
use neo_golden::hwpre::duplicate::{incoming, TouchRecord};
use neo_golden::hwpre::project::ProjectParams;
use neo_golden::hwpre::{camera_registers, preprocess_one};
use neo_golden::sort::DepthKeyCodec;

/// Byte address of the geometry array, the SH array and the feature table in the bench memory.
pub const GEO_BASE: u64 = 0x0100_0000;
/// Byte address of the SH array.
pub const SH_BASE: u64 = 0x0400_0000;
/// Byte address of the feature table.
pub const FEAT_BASE: u64 = 0x0800_0000;
/// Byte address of the previous frame's feature table.
pub const PREV_BASE: u64 = 0x0c00_0000;
/// What the words around the lane's range hold (they must keep it).
const CANARY: u8 = 0xa5;

/// The Gaussians a lane run covers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LaneRange {
    /// First Gaussian.
    pub first: u32,
    /// Gaussians.
    pub count: u32,
}

/// One frame of a lane run.
#[derive(Clone, Debug)]
pub struct LaneFrame<'a> {
    /// The camera.
    pub cam: &'a Camera,
    /// No table reused: every Gaussian incoming, no previous word read.
    pub all_fresh: bool,
    /// The previous frame's feature words of the range (ignored when `all_fresh`).
    pub prev: &'a [[u8; 32]],
}

/// One incoming (Gaussian, tile) the lane reports.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LaneHit {
    /// Tile column and row.
    pub tile: [u32; 2],
    /// Gaussian id.
    pub id: u32,
    /// Depth key.
    pub key: u32,
}

/// What a run measured.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct LaneRun {
    /// Gaussians checked, and those of them visible.
    pub gaussians: u64,
    /// Visible Gaussians.
    pub visible: u64,
    /// Incoming hits checked.
    pub hits: u64,
    /// Cycles from the start to `busy_o` falling.
    pub cycles: u64,
    /// The feature words the lane wrote (the next frame's previous words).
    pub table: Vec<[u8; 32]>,
}

/// A Verilated `neo_pre_lane`.
pub struct LaneBench {
    cfg: EngineConfig,
    model: DynModel,
    ports: [AxiBinding; 2],
    start: usize,
    busy: usize,
    hit: [usize; 6],
}

impl LaneBench {
    /// Builds (or loads from the cache) the lane of `cfg`.
    pub fn build(cfg: &EngineConfig) -> Result<Self, String> {
        let (files, vlt) = crate::dynmodel::generated_files(cfg, NAME)?;
        let iface = neo_gen::units::pre::lane::module(cfg).interface();
        let (model, _) = DynModel::build_for_short_runs(&iface, &files, Some(&vlt), None)?;
        let ports = [AxiBinding::bind(&model, "ma_axi_", true)?, AxiBinding::bind(&model, "mb_axi_", true)?];
        let (start, busy) = (model.port("start_i")?, model.port("busy_o")?);
        let q = |n: &str| model.port(&format!("hit_{n}"));
        let hit = [q("valid_o")?, q("ready_i")?, q("tile_x_o")?, q("tile_y_o")?, q("id_o")?, q("key_o")?];
        Ok(LaneBench { cfg: cfg.clone(), model, ports, start, busy, hit })
    }

    /// The model, for waves.
    pub fn model_mut(&mut self) -> &mut DynModel {
        &mut self.model
    }

    /// Programs the per-frame inputs of `cam` for `baked` and `range`.
    fn program(
        &mut self,
        baked: &Baked,
        cam: &Camera,
        all_fresh: bool,
        range: LaneRange,
    ) -> Result<(), String> {
        let words = CameraWord::values(cam, self.cfg.tile);
        let mut all: Vec<(String, u64)> =
            CameraWord::all().map(|c| (c.port(), u64::from(words[c.0 as usize]))).collect();
        all.push(("degree_i".into(), u64::from(baked.sh_degree)));
        let gb = u64::from(geometry_bytes());
        all.push(("geo_base_i".into(), GEO_BASE + gb * u64::from(range.first)));
        all.push(("sh_base_i".into(), SH_BASE));
        all.push(("sh_words_i".into(), u64::from(sh_bytes(baked.sh_degree, ShPrecision::F32) / 4)));
        all.push(("feat_base_i".into(), FEAT_BASE));
        all.push(("prev_base_i".into(), PREV_BASE));
        all.push(("all_fresh_i".into(), u64::from(all_fresh)));
        all.push(("first_i".into(), u64::from(range.first)));
        all.push(("count_i".into(), u64::from(range.count)));
        for (name, v) in all {
            let p = self.model.port(&name)?;
            self.model.set_u64(p, v);
        }
        Ok(())
    }

    /// Runs the lane over `range` of `baked` for `frame` with memory `timing`, taking hits
    /// `ready_percent` of the cycles, and checks the feature table and the incoming hits it
    /// leaves against golden. Stops the test at the first mismatch.
    pub fn run(
        &mut self,
        baked: &Baked,
        frame: &LaneFrame,
        range: LaneRange,
        (timing, ready_percent): (AxiTiming, u32),
        check: &Checker,
    ) -> LaneRun {
        let mut rng = Rng::new(check.seed);
        let mut mem = AxiMemory::new(2, scene_memory(baked, range, frame.prev), timing, rng.next_u64());
        self.program(baked, frame.cam, frame.all_fresh, range).unwrap_or_else(|e| panic!("{NAME}: {e}"));
        for p in &self.ports {
            p.set_subordinate(&mut self.model, &SubordinateSignals::default());
        }
        self.model.set_u64(self.start, 0);
        self.model.reset();
        let (ro, wo) = (self.cfg.pre_outstanding, self.cfg.axi_outstanding);
        let mut chk = [AxiChecker::new(0, "ma_axi", ro, wo), AxiChecker::new(1, "mb_axi", ro, wo)];
        let want_hits = expected_hits(&self.cfg, baked, frame, range);
        let start = self.model.cycle();
        let limit = 2_000 + 200 * u64::from(range.count) + 4 * want_hits.len() as u64;
        let (mut first, mut hits) = (true, 0usize);
        loop {
            self.model.set_u64(self.start, u64::from(first));
            let ready = rng.percent(ready_percent);
            self.model.set_u64(self.hit[1], u64::from(ready));
            let subs = [mem.outputs(0), mem.outputs(1)];
            for (p, s) in self.ports.iter().zip(&subs) {
                p.set_subordinate(&mut self.model, s);
            }
            self.model.eval();
            let cyc = self.model.cycle();
            let busy = self.model.get_u64(self.busy) == 1;
            if ready && self.model.get_u64(self.hit[0]) == 1 {
                self.check_hit(check, cyc, want_hits.get(hits), hits);
                hits += 1;
            }
            for k in 0..2 {
                let man = self.ports[k].get_manager(&self.model);
                if let Err(v) = chk[k].observe(&man, &subs[k]) {
                    check.fail(cyc, "AXI protocol", "no violation", &v.to_string());
                }
                mem.tick(k, &man);
            }
            self.model.tick();
            if !first && !busy {
                break;
            }
            first = false;
            check.protocol(cyc, cyc - start < limit, "the lane finishes within its cycle budget");
        }
        let cycles = self.model.cycle() - start;
        check.value(cycles, "incoming hits", want_hits.len() as u64, hits as u64);
        for (k, c) in chk.iter().enumerate() {
            let (r, w) = c.in_flight();
            check.value(
                cycles,
                &format!("port {k}: AXI transactions open after busy_o fell"),
                0,
                (r + w) as u64,
            );
        }
        let visible = check_feature_words(&self.cfg, baked, frame.cam, range, mem.memory(), check, cycles);
        let table =
            (range.first..range.first + range.count).map(|i| word_at(mem.memory(), FEAT_BASE, i)).collect();
        LaneRun { gaussians: u64::from(range.count), visible, hits: hits as u64, cycles, table }
    }

    /// Checks the offered hit (the `k`-th) against golden's `want`.
    fn check_hit(&self, check: &Checker, cyc: u64, want: Option<&LaneHit>, k: usize) {
        let m = &self.model;
        let got = LaneHit {
            tile: [m.get_u64(self.hit[2]) as u32, m.get_u64(self.hit[3]) as u32],
            id: m.get_u64(self.hit[4]) as u32,
            key: m.get_u64(self.hit[5]) as u32,
        };
        let Some(want) = want else {
            check.fail(cyc, &format!("hit {k}"), "no more hits", &format!("{got:?}"))
        };
        if got != *want {
            check.fail(cyc, &format!("hit {k} (tile, id, key)"), &format!("{want:x?}"), &format!("{got:x?}"));
        }
    }
}

/// The incoming hits of `range` in the lane's order (Gaussians in index order, each one's tiles
/// row-major): golden `hwpre::duplicate::incoming` with the previous entries of `frame`.
pub fn expected_hits(cfg: &EngineConfig, baked: &Baked, frame: &LaneFrame, range: LaneRange) -> Vec<LaneHit> {
    let (fmt, r) = (cfg.feature_format(), cfg.raster_config());
    let (regs, cam_pos) = camera_registers(frame.cam, cfg.tile);
    let params = ProjectParams { feature: fmt, tile: cfg.tile };
    let size = (regs.grid[0] as u32 * cfg.tile, regs.grid[1] as u32 * cfg.tile);
    let mut out = Vec::new();
    for i in range.first..range.first + range.count {
        let Some(now) = preprocess_one(baked, &regs, cam_pos, &params, &DepthKeyCodec::Fp16, i as usize)
        else {
            continue;
        };
        let prev_entry = if frame.all_fresh {
            None
        } else {
            feature_from_bytes(&fmt, &frame.prev[(i - range.first) as usize])
        };
        let prev = TouchRecord { entry: prev_entry.as_ref() };
        for h in incoming(&now.entry, prev, &fmt, &r, size, |_, _| frame.all_fresh) {
            if h.incoming {
                out.push(LaneHit { tile: [h.tile_x, h.tile_y], id: i, key: now.entry.depth_key });
            }
        }
    }
    out
}

fn word_at(mem: &Memory, base: u64, i: u32) -> [u8; 32] {
    let mut b = [0u8; FEATURE_BYTES as usize];
    mem.read(base + FEATURE_BYTES * u64::from(i), &mut b);
    b
}

/// The bench memory: the baked geometry and SH arrays, the previous feature words of `range`
/// (when given), and canaries in the feature words just outside `range`.
pub fn scene_memory(baked: &Baked, range: LaneRange, prev: &[[u8; 32]]) -> Memory {
    assert_eq!(baked.sh_precision, ShPrecision::F32, "the lane reads f32 SH");
    let mut mem = Memory::new();
    let geo: Vec<u8> = baked.geometry.iter().flat_map(|g| g.to_le_bytes()).collect();
    mem.write(GEO_BASE, &geo);
    let sh: Vec<u8> = baked.sh.iter().flat_map(|w| w.to_le_bytes()).collect();
    mem.write(SH_BASE, &sh);
    for (k, w) in prev.iter().enumerate() {
        mem.write(PREV_BASE + FEATURE_BYTES * (u64::from(range.first) + k as u64), w);
    }
    let canary = [CANARY; FEATURE_BYTES as usize];
    if range.first > 0 {
        mem.write(FEAT_BASE + FEATURE_BYTES * u64::from(range.first - 1), &canary);
    }
    mem.write(FEAT_BASE + FEATURE_BYTES * u64::from(range.first + range.count), &canary);
    mem
}

/// Checks the feature words of `range` at [`FEAT_BASE`] (and the canaries around it); returns
/// the visible count.
pub fn check_feature_words(
    cfg: &EngineConfig,
    baked: &Baked,
    cam: &Camera,
    range: LaneRange,
    mem: &Memory,
    check: &Checker,
    cycle: u64,
) -> u64 {
    let fmt = cfg.feature_format();
    let (regs, cam_pos) = camera_registers(cam, cfg.tile);
    let params = ProjectParams { feature: fmt, tile: cfg.tile };
    let mut visible = 0;
    let word_at = |i: u64| word_at(mem, FEAT_BASE, i as u32);
    for i in range.first..range.first + range.count {
        let want = preprocess_one(baked, &regs, cam_pos, &params, &DepthKeyCodec::Fp16, i as usize);
        visible += u64::from(want.is_some());
        let want_bytes = feature_to_bytes(&fmt, want.as_ref().map(|h| &h.entry));
        let got = word_at(u64::from(i));
        if got != want_bytes {
            let show = |b: &[u8; 32]| format!("{:?} (0x{})", feature_from_bytes(&fmt, b), hex(b));
            check.fail(cycle, &format!("feature word of Gaussian {i}"), &show(&want_bytes), &show(&got));
        }
    }
    let canary = [CANARY; FEATURE_BYTES as usize];
    let around = [range.first.checked_sub(1), Some(range.first + range.count)];
    for i in around.into_iter().flatten() {
        let got = word_at(u64::from(i));
        check.value(cycle, &format!("canary word {i} outside the lane's range"), 1, u64::from(got == canary));
    }
    visible
}

fn hex(b: &[u8; 32]) -> String {
    b.iter().rev().map(|x| format!("{x:02x}")).collect()
}
