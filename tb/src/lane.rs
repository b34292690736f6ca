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
use neo_golden::hwpre::bake::{geometry_bytes, sh_bytes, Baked, ShPrecision};
use neo_golden::hwpre::project::ProjectParams;
use neo_golden::hwpre::{camera_registers, preprocess_one};
use neo_golden::sort::DepthKeyCodec;

/// Byte address of the geometry array, the SH array and the feature table in the bench memory.
pub const GEO_BASE: u64 = 0x0100_0000;
/// Byte address of the SH array.
pub const SH_BASE: u64 = 0x0400_0000;
/// Byte address of the feature table.
pub const FEAT_BASE: u64 = 0x0800_0000;
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

/// What a run measured.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LaneRun {
    /// Gaussians checked, and those of them visible.
    pub gaussians: u64,
    /// Visible Gaussians.
    pub visible: u64,
    /// Cycles from the start to `busy_o` falling.
    pub cycles: u64,
}

/// A Verilated `neo_pre_lane`.
pub struct LaneBench {
    cfg: EngineConfig,
    model: DynModel,
    ports: [AxiBinding; 2],
    start: usize,
    busy: usize,
}

impl LaneBench {
    /// Builds (or loads from the cache) the lane of `cfg`.
    pub fn build(cfg: &EngineConfig) -> Result<Self, String> {
        let (files, vlt) = crate::dynmodel::generated_files(cfg, NAME)?;
        let iface = neo_gen::units::pre::lane::module(cfg).interface();
        let (model, _) = DynModel::build_traced(&iface, &files, Some(&vlt), None)?;
        let ports = [AxiBinding::bind(&model, "ma_axi_", true)?, AxiBinding::bind(&model, "mb_axi_", true)?];
        let (start, busy) = (model.port("start_i")?, model.port("busy_o")?);
        Ok(LaneBench { cfg: cfg.clone(), model, ports, start, busy })
    }

    /// The model, for waves.
    pub fn model_mut(&mut self) -> &mut DynModel {
        &mut self.model
    }

    /// Programs the per-frame inputs of `cam` for `baked` and `range`.
    fn program(&mut self, baked: &Baked, cam: &Camera, range: LaneRange) -> Result<(), String> {
        let (regs, cam_pos) = camera_registers(cam, self.cfg.tile);
        let w2v = regs.w2v.iter().flatten().map(|v| v.to_bits());
        let named: Vec<(String, u64)> = ["00", "01", "02", "10", "11", "12", "20", "21", "22"]
            .iter()
            .map(|s| format!("w2v_{s}_i"))
            .zip(w2v)
            .map(|(n, v)| (n, u64::from(v)))
            .collect();
        let xy = |p: &str, v: [f32; 2]| {
            [(format!("{p}_x_i"), u64::from(v[0].to_bits())), (format!("{p}_y_i"), u64::from(v[1].to_bits()))]
        };
        let mut all = named;
        for (k, c) in ["x", "y", "z"].iter().enumerate() {
            all.push((format!("t_{c}_i"), u64::from(regs.translation[k].to_bits())));
            all.push((format!("cam_{c}_i"), u64::from(cam_pos[k].to_bits())));
        }
        all.extend(xy("focal", regs.focal));
        all.extend(xy("lim", regs.lim));
        all.extend(xy("principal", regs.principal));
        all.push(("grid_x_i".into(), regs.grid[0] as u32 as u64));
        all.push(("grid_y_i".into(), regs.grid[1] as u32 as u64));
        all.push(("degree_i".into(), u64::from(baked.sh_degree)));
        let gb = u64::from(geometry_bytes());
        all.push(("geo_base_i".into(), GEO_BASE + gb * u64::from(range.first)));
        all.push(("sh_base_i".into(), SH_BASE));
        all.push(("sh_words_i".into(), u64::from(sh_bytes(baked.sh_degree, ShPrecision::F32) / 4)));
        all.push(("feat_base_i".into(), FEAT_BASE));
        all.push(("first_i".into(), u64::from(range.first)));
        all.push(("count_i".into(), u64::from(range.count)));
        for (name, v) in all {
            let p = self.model.port(&name)?;
            self.model.set_u64(p, v);
        }
        Ok(())
    }

    /// Runs the lane over `range` of `baked` seen from `cam` with memory `timing`, and checks the
    /// feature table it leaves against golden. Stops the test at the first mismatch.
    pub fn run(
        &mut self,
        baked: &Baked,
        cam: &Camera,
        range: LaneRange,
        timing: AxiTiming,
        check: &Checker,
    ) -> LaneRun {
        let mut rng = Rng::new(check.seed);
        let mut mem = AxiMemory::new(2, scene_memory(baked, range), timing, rng.next_u64());
        self.program(baked, cam, range).unwrap_or_else(|e| panic!("{NAME}: {e}"));
        for p in &self.ports {
            p.set_subordinate(&mut self.model, &SubordinateSignals::default());
        }
        self.model.set_u64(self.start, 0);
        self.model.reset();
        let (ro, wo) = (self.cfg.pre_outstanding, self.cfg.axi_outstanding);
        let mut chk = [AxiChecker::new(0, "ma_axi", ro, wo), AxiChecker::new(1, "mb_axi", ro, wo)];
        let start = self.model.cycle();
        let limit = 2_000 + 200 * u64::from(range.count);
        let mut first = true;
        loop {
            self.model.set_u64(self.start, u64::from(first));
            let subs = [mem.outputs(0), mem.outputs(1)];
            for (p, s) in self.ports.iter().zip(&subs) {
                p.set_subordinate(&mut self.model, s);
            }
            self.model.eval();
            let cyc = self.model.cycle();
            let busy = self.model.get_u64(self.busy) == 1;
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
        for (k, c) in chk.iter().enumerate() {
            let (r, w) = c.in_flight();
            check.value(
                cycles,
                &format!("port {k}: AXI transactions open after busy_o fell"),
                0,
                (r + w) as u64,
            );
        }
        let visible = check_table(&self.cfg, baked, cam, range, mem.memory(), check, cycles);
        LaneRun { gaussians: u64::from(range.count), visible, cycles }
    }
}

/// The bench memory: the baked geometry and SH arrays, and canaries in the feature words just
/// outside `range`.
pub fn scene_memory(baked: &Baked, range: LaneRange) -> Memory {
    assert_eq!(baked.sh_precision, ShPrecision::F32, "the lane reads f32 SH");
    let mut mem = Memory::new();
    let words = |v: &mut Vec<u8>, w: &[f32]| v.extend(w.iter().flat_map(|x| x.to_le_bytes()));
    let mut geo = Vec::with_capacity(baked.len() * geometry_bytes() as usize);
    for g in &baked.geometry {
        words(&mut geo, &g.position);
        words(&mut geo, &g.cov3d);
        words(&mut geo, &[g.opacity, g.k2]);
    }
    mem.write(GEO_BASE, &geo);
    let sh: Vec<u8> = baked.sh.iter().flat_map(|w| w.to_le_bytes()).collect();
    mem.write(SH_BASE, &sh);
    let canary = [CANARY; FEATURE_BYTES as usize];
    if range.first > 0 {
        mem.write(FEAT_BASE + FEATURE_BYTES * u64::from(range.first - 1), &canary);
    }
    mem.write(FEAT_BASE + FEATURE_BYTES * u64::from(range.first + range.count), &canary);
    mem
}

/// Checks the feature words of `range` (and the canaries around it); returns the visible count.
fn check_table(
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
    let word_at = |i: u64| {
        let mut b = [0u8; FEATURE_BYTES as usize];
        mem.read(FEAT_BASE + FEATURE_BYTES * i, &mut b);
        b
    };
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
