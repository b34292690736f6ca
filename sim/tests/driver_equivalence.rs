//! The work-only workload generator must produce exactly the golden pipeline's work counters
//! (the driver checks every frame against the golden statistics when the golden raster runs).

use neo_golden::pipeline::{Formats, Pipeline, Strategy};
use neo_golden::{source, trajectory};
use neo_sim::config::PipelineParams;
use neo_sim::driver::{generate, generate_many, pipeline_config, GoldenRaster, WorkDriver, WorkloadSpec};

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

/// Workloads generated together (one preprocessing and binning per frame, shared exact-order
/// rasters) are those generated alone, and those of pipelines that make their own frame inputs.
#[test]
fn workloads_generated_together_equal_those_generated_alone() {
    let (scene, traj) = setup(5, "orbit:speed=8,cut=3");
    let specs: Vec<WorkloadSpec> = [
        ("neo", 256, 1, None, GoldenRaster::Exact),
        ("neo", 64, 2, Some(300), GoldenRaster::Exact),
        ("periodic:3", 256, 1, None, GoldenRaster::Exact),
        ("background:2", 64, 1, Some(300), GoldenRaster::Off),
        ("hierarchical", 64, 1, None, GoldenRaster::Off),
        ("neo", 128, 1, None, GoldenRaster::Off),
    ]
    .into_iter()
    .map(|(strategy, chunk, passes, capacity, golden)| {
        let mut spec = WorkloadSpec::new("synthetic", "orbit", strategy.parse().unwrap());
        spec.params = PipelineParams { chunk, dps_passes: passes, capacity, ..PipelineParams::default() };
        spec.golden_raster = golden;
        spec
    })
    .collect();
    let together = generate_many(&scene, &traj.frames, &traj.cuts, &specs, |_| {}).unwrap();
    assert_eq!(together.len(), specs.len());
    let (w, h) = (traj.frames[0].width, traj.frames[0].height);
    for (spec, t) in specs.iter().zip(&together) {
        let what =
            format!("{} chunk {} capacity {:?}", spec.strategy, spec.params.chunk, spec.params.capacity);
        let alone = generate(&scene, &traj.frames, &traj.cuts, spec, |_| {}).unwrap();
        assert_eq!(t.info, alone.info, "{what}");
        assert_eq!(t.frames, alone.frames, "{what}");
        // Pipelines making their own inputs (`WorkDriver::new`, `Pipeline::new`).
        let mut drv =
            WorkDriver::new(&scene, spec.strategy, &spec.params, w, h, spec.hierarchical, spec.raster_sample)
                .unwrap();
        let mut golden = (spec.golden_raster != GoldenRaster::Off).then(|| {
            let cfg = pipeline_config(spec.strategy, &spec.params, spec.golden_raster);
            Pipeline::new(&scene, cfg, Formats::artifact(spec.params.chunk).unwrap(), w, h).unwrap()
        });
        for (i, cam) in traj.frames.iter().enumerate() {
            let cut = traj.cuts.contains(&i);
            let own = drv.step(cam, i, cut);
            let f = &t.frames[i];
            assert_eq!(own.tiles, f.tiles, "{what} frame {i}");
            assert_eq!(
                (&own.visible_set, own.gpu_pairs, own.gpu_visible, own.golden),
                (&f.visible_set, f.gpu_pairs, f.gpu_visible, f.golden),
                "{what} frame {i}"
            );
            if let Some(p) = golden.as_mut() {
                let s = p.render_frame(cam, i, cut).stats;
                let q = f.quality.expect("golden raster ran");
                assert_eq!(
                    (s.psnr_vs_exact, s.identical_to_exact),
                    (q.psnr_vs_exact, q.identical_to_exact),
                    "{what} frame {i}"
                );
            }
        }
    }
    // The mix must exercise the exact-order rasters: some frame differs from the exact order.
    assert!(together
        .iter()
        .flat_map(|t| &t.frames)
        .any(|f| f.quality.is_some_and(|q| q.psnr_vs_exact.is_some())));
}
