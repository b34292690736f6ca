use neo_golden::formats::FeatureFormat;
use neo_golden::hwpre::project::ProjectParams;
use neo_golden::hwpre::{camera_registers, preprocess_hw, preprocess_one, Baked, ShPrecision};
use neo_golden::sort::DepthKeyCodec;
use neo_golden::{source, trajectory};
use std::time::Instant;
fn main() {
    let mode = std::env::args().nth(1).unwrap_or_default();
    let n: usize = std::env::args().nth(2).map(|s| s.parse().unwrap()).unwrap_or(3);
    let (scene, _) = source::load_scene("synthetic:outdoor?gaussians=500000&seed=1", false).unwrap();
    let traj = trajectory::parse_trajectory("orbit", source::robust_bounds(&scene), 4)
        .unwrap()
        .with_resolution(2560, 1440);
    let fmt = FeatureFormat::default();
    let baked = Baked::from_scene(&scene, &fmt, ShPrecision::F32);
    let key = DepthKeyCodec::Fp16;
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
    pool.install(|| {
        for cam in traj.frames.iter().take(n) {
            let t = Instant::now();
            let v = if mode != "one" { preprocess_hw(&baked, cam, &fmt, &key, 64) } else { vec![] };
            let lanes_s = t.elapsed().as_secs_f64();
            let t = Instant::now();
            let (regs, pos) = camera_registers(cam, 64);
            let params = ProjectParams { feature: fmt, tile: 64 };
            let w: usize = (0..baked.len())
                .filter_map(|i| preprocess_one(&baked, &regs, pos, &params, &key, i))
                .map(|h| h.entry.mean[0] as usize & 1)
                .sum();
            std::hint::black_box(w);
            let one_s = t.elapsed().as_secs_f64();

            println!("{} visible: lanes {lanes_s:.3} s, one by one {one_s:.3} s", v.len());
        }
    });
}
