//! Stimulus of the Preprocessing Engine's datapath benches (`neo_pre_color`,
//! `neo_pre_project`): items in each graph's input order, the benches of the generated units,
//! and their timing for `reports/latency.json`.

use crate::check::Checker;
use crate::datapath::DatapathBench;
use crate::rng::Rng;
use neo_gen::units::pre::datapath::Datapath;
use neo_gen::units::pre::library::PreLibrary;
use neo_gen::units::pre::{project_params, COLOR_NAME, PROJECT_NAME};
use neo_gen::EngineConfig;
use neo_golden::formats::latency::DatapathUnit;
use neo_golden::hwarith::graph::Graph;
use neo_golden::hwpre::bake::{Baked, BakedGeometry, ShPrecision};
use neo_golden::hwpre::color::color_graph;
use neo_golden::hwpre::project::{project_graph, CameraIn};

/// A unit's bench and the settle cycles of its per-frame inputs.
pub struct UnitBench {
    /// The bench.
    pub bench: DatapathBench,
    /// Cycles the per-frame inputs need ([`Datapath::settle_cycles`]).
    pub settle: u32,
    /// The emitted pipeline depth.
    pub depth: u32,
}

fn unit_bench(cfg: &EngineConfig, graph: Graph, top: &str) -> UnitBench {
    let d = Datapath::new(&graph, &PreLibrary);
    let (settle, depth) = (d.settle_cycles(), d.depth());
    let bench = DatapathBench::build_generated(graph, cfg, top).unwrap_or_else(|e| panic!("{top}: {e}"));
    UnitBench { bench, settle, depth }
}

/// The colour unit's bench.
pub fn color_bench(cfg: &EngineConfig) -> UnitBench {
    unit_bench(cfg, color_graph(&cfg.feature_format().color), COLOR_NAME)
}

/// The projection unit's bench.
pub fn project_bench(cfg: &EngineConfig) -> UnitBench {
    unit_bench(cfg, project_graph(&project_params(cfg)), PROJECT_NAME)
}

/// One colour-unit item: mean, 16 x 3 SH coefficients, camera, degree.
pub fn color_item(mean: [f32; 3], sh: &[f32], cam: [f32; 3], degree: u32) -> Vec<u32> {
    let mut v: Vec<u32> = mean.iter().chain(sh).map(|x| x.to_bits()).collect();
    v.extend(cam.map(f32::to_bits));
    v.push(degree);
    v
}

/// `n` random colour-unit items: means within 50 of the origin, DC coefficients within 4 and
/// the others within 1.
pub fn random_color_items(rng: &mut Rng, n: usize, cam: [f32; 3], degree: u32) -> Vec<Vec<u32>> {
    let f = |rng: &mut Rng, scale: f64| ((rng.below(2_000_001) as f64 / 1e6 - 1.0) * scale) as f32;
    (0..n)
        .map(|_| {
            let mean = [f(rng, 50.0), f(rng, 50.0), f(rng, 50.0)];
            let sh: Vec<f32> = (0..48).map(|k| if k < 3 { f(rng, 4.0) } else { f(rng, 1.0) }).collect();
            color_item(mean, &sh, cam, degree)
        })
        .collect()
}

/// One projection-unit item: position, 3D covariance, opacity, k2, then the camera registers.
pub fn project_item(g: &BakedGeometry, cam: &CameraIn<f32, i32>) -> Vec<u32> {
    let mut v: Vec<u32> =
        g.position.iter().chain(&g.cov3d).chain([&g.opacity, &g.k2]).map(|x| x.to_bits()).collect();
    let regs = cam.w2v.iter().flatten().chain(&cam.translation).chain(&cam.focal).chain(&cam.lim);
    v.extend(regs.chain(&cam.principal).map(|x| x.to_bits()));
    v.extend(cam.grid.map(|x| x as u32));
    v
}

/// The baked Gaussians of a synthetic scene (`gaussians`, `seed`) as projection items, one list
/// per frame of a fast 640x480 orbit.
pub fn scene_project_items(
    cfg: &EngineConfig,
    seed: u64,
    gaussians: usize,
    frames: usize,
) -> Vec<Vec<Vec<u32>>> {
    let spec = format!("synthetic:blobs?gaussians={gaussians}&seed={seed}");
    let (scene, _) = neo_golden::source::load_scene(&spec, false).expect("synthetic scene");
    let baked = Baked::from_scene(&scene, &cfg.feature_format(), ShPrecision::F32);
    let bounds = neo_golden::source::robust_bounds(&scene);
    let traj = neo_golden::trajectory::parse_trajectory("orbit:res=640x480,speed=20", bounds, frames)
        .expect("orbit trajectory");
    traj.frames
        .iter()
        .map(|cam| {
            let (regs, _) = neo_golden::hwpre::camera_registers(cam, cfg.tile);
            baked.geometry.iter().map(|g| project_item(g, &regs)).collect()
        })
        .collect()
}

/// Latency and rate of a unit on `items` at full rate (every output checked against golden).
pub fn measure(unit: &mut UnitBench, items: &[Vec<u32>], check: &Checker) -> DatapathUnit {
    let mut rng = Rng::new(check.seed);
    let run = unit.bench.run(items, unit.settle, &mut rng, (100, 100), check);
    let n = items.len() as u64;
    DatapathUnit {
        latency: run.first_latency,
        ii: (run.cycles - run.first_latency).div_ceil(n),
        items: n,
        cycles: run.cycles,
        settle: unit.settle as u64,
    }
}
