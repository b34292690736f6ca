//! The work-only workload generator must produce exactly the golden pipeline's work counters
//! (the driver checks every frame against the golden statistics when the golden raster runs).

use neo_golden::pipeline::Strategy;
use neo_golden::{source, trajectory};
use neo_sim::config::PipelineParams;
use neo_sim::driver::{generate, GoldenRaster, WorkloadSpec};

fn setup(frames: usize, traj: &str) -> (neo_golden::scene::Scene, trajectory::Trajectory) {
    let (scene, _) = source::load_scene("synthetic:outdoor?gaussians=20k&seed=3", false).unwrap();
    let t = trajectory::parse_trajectory(traj, source::robust_bounds(&scene), frames)
        .unwrap()
        .with_resolution(200, 136);
    (scene, t)
}

#[test]
fn work_only_counters_equal_the_golden_pipeline_for_every_strategy() {
    let (scene, traj) = setup(6, "orbit:speed=8,cut=4");
    for (strategy, chunk, passes, capacity) in [
        ("neo", 256, 1, None),
        ("neo", 64, 2, Some(300)),
        ("full", 128, 1, None),
        ("periodic:3", 256, 1, None),
        ("background:2", 64, 1, None),
        ("hierarchical", 64, 1, Some(500)),
    ] {
        let s: Strategy = strategy.parse().unwrap();
        let mut spec = WorkloadSpec::new("synthetic", "orbit", s);
        spec.params = PipelineParams { chunk, dps_passes: passes, capacity, ..PipelineParams::default() };
        spec.golden_raster = GoldenRaster::Exact;
        let w = generate(&scene, &traj.frames, &traj.cuts, &spec, |_| {})
            .unwrap_or_else(|e| panic!("{strategy} chunk {chunk} passes {passes}: {e}"));
        assert_eq!(w.frames.len(), 6);
        assert!(w.frames[0].from_scratch && w.frames[4].cut, "{strategy}");
        let pairs: u64 = w.frames[1].tiles.iter().map(|t| t.current as u64).sum();
        assert!(pairs > 1000, "{strategy}: the scene must give real work ({pairs} pairs)");
        for f in &w.frames {
            assert!(f.processed_ratio > 0.0 && f.processed_ratio <= 1.0, "{strategy}: {}", f.processed_ratio);
            assert!(f.quality.is_some());
        }
    }
}

#[test]
fn work_only_sampled_termination_is_close_to_the_whole_frame() {
    let (scene, traj) = setup(2, "orbit");
    let mut spec = WorkloadSpec::new("synthetic", "orbit", Strategy::Neo);
    spec.raster_sample = 1;
    let all = generate(&scene, &traj.frames, &traj.cuts, &spec, |_| {}).unwrap();
    spec.golden_raster = GoldenRaster::Exact;
    let golden = generate(&scene, &traj.frames, &traj.cuts, &spec, |_| {}).unwrap();
    for (a, g) in all.frames.iter().zip(&golden.frames) {
        // Sampling every tile is the whole frame.
        assert!(
            (a.processed_ratio - g.processed_ratio).abs() < 1e-9,
            "{} vs {}",
            a.processed_ratio,
            g.processed_ratio
        );
        assert_eq!(a.tiles, g.tiles);
    }
}
