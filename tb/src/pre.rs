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
use neo_golden::hwarith::graph::{Graph, Trace};
use neo_golden::hwarith::Arith;
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

/// Resolutions of [`random_camera`]: tiny images, the common ones, an odd one, and one whose
/// tile grid is the largest the 10-bit tile indices allow (1023 x 1023 tiles of 64 pixels).
const CAMERA_RESOLUTIONS: [(u32, u32); 8] =
    [(3, 2), (64, 48), (640, 480), (1280, 720), (2560, 1440), (3840, 2160), (1001, 77), (65_472, 65_472)];

/// A magnitude between `10^lo` and `10^hi`, log-uniform.
fn log_uniform(rng: &mut Rng, lo: f64, hi: f64) -> f64 {
    10f64.powf(lo + (hi - lo) * rng.below(1 << 20) as f64 / (1 << 20) as f64)
}

/// A unit vector in a uniformly random direction.
fn random_direction(rng: &mut Rng) -> glam::DVec3 {
    loop {
        let mut c = || rng.below(2_000_001) as f64 / 1e6 - 1.0;
        let v = glam::DVec3::new(c(), c(), c());
        if (1e-3..=1.0).contains(&v.length_squared()) {
            return v.normalize();
        }
    }
}

/// A signed axis of world space, uniformly.
fn random_axis(rng: &mut Rng) -> glam::DVec3 {
    let mut v = glam::DVec3::ZERO;
    v[rng.below(3) as usize] = if rng.percent(50) { 1.0 } else { -1.0 };
    v
}

/// How [`random_camera`] places a camera.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CameraPlacement {
    /// From a random direction with a random up vector (every rotation term varies, roll
    /// included).
    Random,
    /// Along a world axis with an axis as up: rotation terms exact zeros and ones.
    AxisAligned,
    /// Within 10^-3 of the world origin, on a 3x2 image with focal lengths of 0.03 to 1 image
    /// widths: a translation of magnitude below 2, focal lengths below 2.
    NearOrigin,
}

/// A camera that looks at `center`, placed by `placement`; a [`CameraPlacement::Random`] or
/// [`CameraPlacement::AxisAligned`] one mostly 1.5 to 6 `radius` away (one in four anywhere from
/// inside the scene to 1000 radii away), with a resolution of [`CAMERA_RESOLUTIONS`] and focal
/// lengths of 0.03 to 30 image widths (x and y apart): the per-frame inputs of the projection
/// unit drawn over their range, with a scene in view.
pub fn random_camera(
    rng: &mut Rng,
    center: [f32; 3],
    radius: f64,
    placement: CameraPlacement,
) -> neo_golden::camera::Camera {
    let center = glam::DVec3::new(center[0] as f64, center[1] as f64, center[2] as f64);
    let distance = radius.max(1e-3)
        * if rng.percent(75) {
            1.5 + 4.5 * rng.below(1001) as f64 / 1000.0
        } else {
            log_uniform(rng, -2.0, 3.0)
        };
    let ((width, height), focal_range, position, up) = match placement {
        CameraPlacement::Random => {
            let position = center + random_direction(rng) * distance;
            (*rng.pick(&CAMERA_RESOLUTIONS), (-1.5, 1.5), position, random_direction(rng))
        }
        CameraPlacement::AxisAligned => {
            let position = center + random_axis(rng) * distance;
            (*rng.pick(&CAMERA_RESOLUTIONS), (-1.5, 1.5), position, random_axis(rng))
        }
        CameraPlacement::NearOrigin => {
            ((3, 2), (-1.5, 0.0), random_direction(rng) * 1e-3, random_direction(rng))
        }
    };
    let focal = |rng: &mut Rng| width as f64 * log_uniform(rng, focal_range.0, focal_range.1);
    let (fx, fy) = (focal(rng), focal(rng));
    let cam_to_world = neo_golden::camera::look_at_rotation(position, center, up);
    neo_golden::camera::Camera { name: "random".into(), width, height, fx, fy, position, cam_to_world }
}

/// The baked Gaussians of a synthetic scene (`gaussians`, `seed`) as projection items, one list
/// per camera of `cameras` [`random_camera`]s (of every eight, two axis-aligned and one near the
/// world origin).
pub fn random_camera_project_items(
    cfg: &EngineConfig,
    rng: &mut Rng,
    gaussians: usize,
    cameras: usize,
) -> Vec<Vec<Vec<u32>>> {
    let spec = format!("synthetic:blobs?gaussians={gaussians}&seed={}", rng.below(1000) + 1);
    let (scene, _) = neo_golden::source::load_scene(&spec, false).expect("synthetic scene");
    let baked = Baked::from_scene(&scene, &cfg.feature_format(), ShPrecision::F32);
    let (lo, hi) = neo_golden::source::robust_bounds(&scene);
    let center = [0, 1, 2].map(|k| (lo[k] + hi[k]) / 2.0);
    let radius = (0..3).map(|k| (hi[k] - lo[k]) as f64).fold(0.0, f64::max) / 2.0;
    (0..cameras)
        .map(|k| {
            let placement = match k % 8 {
                1 | 5 => CameraPlacement::AxisAligned,
                3 => CameraPlacement::NearOrigin,
                _ => CameraPlacement::Random,
            };
            let cam = random_camera(rng, center, radius, placement);
            let (regs, _) = neo_golden::hwpre::camera_registers(&cam, cfg.tile);
            baked.geometry.iter().map(|g| project_item(g, &regs)).collect()
        })
        .collect()
}

/// A colour unit's camera position: each coordinate of either sign and of magnitude 10^-3 to
/// 10^4 (per-frame input drawn over its range).
pub fn random_camera_position(rng: &mut Rng) -> [f32; 3] {
    [(); 3].map(|_| {
        let m = log_uniform(rng, -3.0, 4.0) as f32;
        if rng.percent(50) {
            -m
        } else {
            m
        }
    })
}

/// Module name of the bench of the datapath library's inline logic (`pre_units`).
pub const INLINE_BENCH_NAME: &str = "neo_pre_inline_bench";

/// The inline logic bench's graph ([`INLINE_BENCH_NAME`]): every inline operation of the
/// datapath library on two floats and two integers.
pub fn inline_graph() -> Graph {
    let mut t = Trace::new();
    let a = t.input_f("a", false);
    let b = t.input_f("b", false);
    let i = t.input_i("i", false);
    let j = t.input_i("j", false);
    let outs_f = [
        ("neg", t.neg(a)),
        ("abs", t.abs(b)),
        ("max", t.max(a, b)),
        ("min", t.min(a, b)),
        ("pow2", t.pow2_field(i)),
    ];
    let lt = t.lt(a, b);
    let le = t.le(a, b);
    let eq = t.eq(a, b);
    let nan = t.is_nan(a);
    let fin = t.is_finite(b);
    let ilt = t.ilt(i, j);
    let ieq = t.ieq(i, j);
    let and = t.and(lt, ilt);
    let or = t.or(eq, ieq);
    let not = t.not(le);
    let sel = t.select(ilt, a, b);
    let outs_i = [
        ("exp", t.exp_field(a)),
        ("iadd", t.iadd(i, j)),
        ("isub", t.isub(i, j)),
        ("imin", t.imin(i, j)),
        ("imax", t.imax(i, j)),
        ("isel", t.iselect(lt, i, j)),
    ];
    for (n, v) in outs_f {
        t.output_f(n, v);
    }
    t.output_f("sel", sel);
    for (n, v) in outs_i {
        t.output_i(n, v);
    }
    for (n, v) in [
        ("lt", lt),
        ("le", le),
        ("eq", eq),
        ("nan", nan),
        ("fin", fin),
        ("and", and),
        ("or", or),
        ("not", not),
    ] {
        t.output_b(n, v);
    }
    t.finish()
}

/// The bit values (`[seen 0, seen 1]` masks per node) that `items` give the nodes of `graph`.
pub fn node_bits_seen(graph: &Graph, items: &[Vec<u32>]) -> Vec<[u32; 2]> {
    let mut seen = vec![[0u32; 2]; graph.nodes.len()];
    for item in items {
        for (s, v) in seen.iter_mut().zip(graph.eval_nodes(item)) {
            s[0] |= !v;
            s[1] |= v;
        }
    }
    seen
}

/// Coverage-directed stimulus: of `candidates`, in order, the items that give some node of
/// `graph` a bit value none of the items before gave it (`seen`, from [`node_bits_seen`], is
/// updated), at most `max`. Golden's node values are the datapath's node nets, so each item
/// kept drives a net bit the bench had not driven to that value.
pub fn items_with_unseen_bits(
    graph: &Graph,
    seen: &mut [[u32; 2]],
    candidates: impl Iterator<Item = Vec<u32>>,
    max: usize,
) -> Vec<Vec<u32>> {
    let mut kept = Vec::new();
    for item in candidates {
        if kept.len() == max {
            break;
        }
        let v = graph.eval_nodes(&item);
        if seen.iter().zip(&v).any(|(s, &x)| x & !s[1] != 0 || !x & !s[0] != 0) {
            for (s, x) in seen.iter_mut().zip(&v) {
                s[0] |= !x;
                s[1] |= x;
            }
            kept.push(item);
        }
    }
    kept
}

/// A camera at the origin looking down +z (world = view coordinates), f = 500 px, 640x480.
pub fn axis_camera() -> CameraIn<f32, i32> {
    let (w, h, f) = (640.0f32, 480.0f32, 500.0f32);
    CameraIn {
        w2v: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        translation: [0.0; 3],
        focal: [f, f],
        lim: [1.3 * w / (2.0 * f), 1.3 * h / (2.0 * f)],
        principal: [(w - 1.0) / 2.0, (h - 1.0) / 2.0],
        grid: [10, 8],
    }
}

/// Projection items of hard geometry on the axis of a camera at the origin looking down +z (f =
/// 500 px, 640x480): isotropic covariances of every scale with a cross term `xy` from 10^-32
/// to 10^-20 of either sign, so that the 2D covariance's diagonal terms are equal and its
/// off-diagonal term's square is subnormal (the major axis where rounding is coarsest), half
/// of them with a 2D variance just above a power of two (a conic whose block-float mantissa
/// rounds up to the next exponent), and depths from the near plane to 10^4.
pub fn on_axis_project_items(rng: &mut Rng, n: usize) -> Vec<Vec<u32>> {
    let cam = axis_camera();
    let f = cam.focal[0];
    (0..n)
        .map(|_| {
            let z = log_uniform(rng, -0.6, 4.0) as f32;
            let s = if rng.percent(50) {
                log_uniform(rng, -12.0, 2.0) as f32
            } else {
                // The 2D variance (f / z)^2 s + 0.3 just above a power of two 2^k: the conic
                // 1 / v just below 2^-k, whose block-float mantissa rounds up to the next
                // exponent (conic_bfp's decrement).
                let k = rng.below(12) as i32 - 1;
                let v = 2f64.powi(k) * (1.0 + rng.below(1 << 10) as f64 * 2f64.powi(-28));
                ((v - 0.3) * (z as f64 / f as f64).powi(2)) as f32
            };
            let xy = log_uniform(rng, -32.0, -20.0) as f32 * if rng.percent(50) { 1.0 } else { -1.0 };
            let g = BakedGeometry {
                position: [0.0, 0.0, z],
                cov3d: [s, xy, 0.0, s, 0.0, s],
                opacity: 0.8,
                k2: 11.0,
            };
            project_item(&g, &cam)
        })
        .collect()
}
