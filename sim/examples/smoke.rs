use neo_golden::pipeline::Strategy;
use neo_golden::{source, trajectory};
use neo_sim::config::SimConfig;
use neo_sim::driver::{generate, WorkloadSpec};
use neo_sim::latency::Latency;
use neo_sim::run::{simulate, Arch, RunOptions};
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let scene_spec = args.get(1).cloned().unwrap_or("synthetic:outdoor?gaussians=100k&seed=1".into());
    let res: Vec<u32> =
        args.get(2).map(|s| s.split('x').map(|v| v.parse().unwrap()).collect()).unwrap_or(vec![640, 360]);
    let frames: usize = args.get(3).map(|s| s.parse().unwrap()).unwrap_or(6);
    let strat: Strategy = args.get(4).map(|s| s.parse().unwrap()).unwrap_or(Strategy::Neo);
    let (scene, _) = source::load_scene(&scene_spec, false).unwrap();
    let traj = trajectory::parse_trajectory("orbit", source::robust_bounds(&scene), frames)
        .unwrap()
        .with_resolution(res[0], res[1]);
    let t = std::time::Instant::now();
    let spec = WorkloadSpec::new(&scene_spec, "orbit", strat);
    let wl = generate(&scene, &traj.frames, &traj.cuts, &spec, |_| {}).unwrap();
    eprintln!("workload {:.2}s", t.elapsed().as_secs_f64());
    let cfg = match std::env::var("CFG") {
        Ok(p) => SimConfig::from_file(std::path::Path::new(&p)).unwrap(),
        Err(_) => SimConfig::default(),
    };
    let lat = Latency::from_file(std::path::Path::new("reports/latency.json")).unwrap();
    for arch in [Arch::Neo, Arch::Gscore(4), Arch::Gscore(16), Arch::Gpu] {
        let r = simulate(arch, &cfg, &lat, &wl, RunOptions::default()).unwrap();
        eprintln!(
            "{:9} fps {:8.1} mean {:.3} ms p99 {:.3} lat {:.3} GB/60 {:.2} sort {:.2} util {:?} model {:.2}s",
            r.arch,
            r.fps,
            r.frame_ms_mean,
            r.frame_ms_p99,
            r.latency_ms_mean,
            r.gb_per_60(None),
            r.traffic.sorting_bytes() as f64 * 60.0 / wl.frames.len() as f64 / 1e9,
            r.utilisation,
            r.model_s
        );
        for s in neo_sim::traffic::Stage::ALL {
            let b = r.gb_per_60(Some(s));
            if b > 0.0 {
                eprint!("  {}={:.3}", s.name(), b);
            }
        }
        eprintln!();
        if let Some(d) = r.dram {
            eprintln!("  dram {:?} hit {:.2} lat {:.1}ns", d, d.row_hit_rate(), d.mean_read_latency_ns());
        }
    }
}
