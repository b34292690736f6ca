//! A preprocessing lane (`neo_pre_lane`: fetch, projection, SH gather, colour, feature write)
//! against golden `hwpre::preprocess_one`: the baked Gaussians of a synthetic scene in memory,
//! the cameras of an orbit, the feature table the lane writes compared word by word.

#[test]
fn models_present() {
    assert_eq!(neo_tb::require_models("pre_lane: preprocessing-lane cosimulation"), neo_tb::HAS_MODELS);
}

neo_tb::with_models! {
    use neo_golden::hwpre::bake::{Baked, ShPrecision};
    use neo_tb::axi::AxiTiming;
    use neo_tb::check::Checker;
    use neo_tb::lane::{LaneBench, LaneFrame, LaneRange};
    use neo_tb::rng::for_each_seed;

    /// The baked synthetic scene (`gaussians`, `seed`) and `frames` cameras of a fast walk through it
    /// (cameras inside the scene, so some Gaussians are culled).
    fn scene(gaussians: usize, seed: u64, frames: usize) -> (Baked, Vec<neo_golden::camera::Camera>) {
        let cfg = neo_tb::config();
        let spec = format!("synthetic:blobs?gaussians={gaussians}&seed={seed}");
        let (scene, _) = neo_golden::source::load_scene(&spec, false).expect("synthetic scene");
        let baked = Baked::from_scene(&scene, &cfg.feature_format(), ShPrecision::F32);
        let bounds = neo_golden::source::robust_bounds(&scene);
        let traj = neo_golden::trajectory::parse_trajectory("walk:res=640x480,speed=20", bounds, frames)
            .expect("orbit trajectory");
        (baked, traj.frames)
    }

    #[test]
    fn lane_writes_golden_feature_words_and_incoming_hits() {
        let name = "lane_writes_golden_feature_words_and_incoming_hits";
        let cfg = neo_tb::config();
        let mut bench = LaneBench::build(&cfg).unwrap();
        neo_tb::waves::maybe_trace(bench.model_mut(), name);
        for_each_seed(name, |seed| {
            let (baked, cams) = scene(800, seed % 1000, 3);
            let n = baked.len() as u32;
            let first = (seed % 97) as u32;
            let range = LaneRange { first, count: n - first - (seed % 13) as u32 };
            let mut prev: Vec<[u8; 32]> = Vec::new();
            for (f, cam) in cams.iter().enumerate() {
                let check = Checker::new("neo_pre_lane", seed ^ f as u64);
                // Frame 0 from scratch; then reuse, on a hostile and on an ideal memory.
                let frame = LaneFrame { cam, all_fresh: f == 0, prev: &prev };
                let pace = if f % 2 == 0 { (AxiTiming::RANDOM, 60) } else { (AxiTiming::IDEAL, 100) };
                let run = bench.run(&baked, &frame, range, pace, &check);
                eprintln!(
                    "{name}: frame {f}: {} Gaussians, {} visible, {} incoming hits, {} cycles",
                    run.gaussians, run.visible, run.hits, run.cycles
                );
                assert!(run.visible > 0 && run.visible < run.gaussians, "the camera must cull some Gaussians and keep some");
                assert!(run.hits > 0, "frame {f}: no incoming hit");
                prev = run.table;
            }
        });
    }
}
