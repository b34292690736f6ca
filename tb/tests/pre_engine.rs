//! The Preprocessing Engine (`neo_pre_engine`: lanes, hit arbiter, list writer) against golden
//! `hwpre`: the baked Gaussians of a synthetic scene in memory, the cameras of a walk, the
//! feature table, the tiles' incoming lists and their lengths compared with golden's.

#[test]
fn models_present() {
    assert_eq!(neo_tb::require_models("pre_engine: Preprocessing Engine cosimulation"), neo_tb::HAS_MODELS);
}

neo_tb::with_models! {
    use neo_golden::hwpre::bake::{Baked, ShPrecision};
    use neo_tb::axi::AxiTiming;
    use neo_tb::check::Checker;
    use neo_tb::lane::LaneFrame;
    use neo_tb::pre_engine::PreEngineBench;
    use neo_tb::rng::for_each_seed;

    /// `tb/pre_engine.json`: two lanes (the split and the arbiter at work; a lane's C++ is
    /// compiled per instance, so the default four cost twice the build; `scripts/mutate-check`
    /// mutates this configuration's Verilog, its `pre:` files).
    fn config() -> neo_gen::EngineConfig {
        neo_tb::pre_engine::bench_config()
    }

    /// The baked synthetic scene and `frames` cameras of a fast walk through it.
    fn scene(gaussians: usize, seed: u64, frames: usize, degree: u8) -> (Baked, Vec<neo_golden::camera::Camera>) {
        let spec = format!("synthetic:blobs?gaussians={gaussians}&seed={seed}&sh={degree}");
        let (scene, _) = neo_golden::source::load_scene(&spec, false).expect("synthetic scene");
        let baked = Baked::from_scene(&scene, &config().feature_format(), ShPrecision::F32);
        let bounds = neo_golden::source::robust_bounds(&scene);
        let traj = neo_golden::trajectory::parse_trajectory("walk:res=640x480,speed=20", bounds, frames)
            .expect("walk trajectory");
        (baked, traj.frames)
    }

    #[test]
    fn pre_engine_writes_golden_features_lists_and_lengths() {
        let name = "pre_engine_writes_golden_features_lists_and_lengths";
        let mut bench = PreEngineBench::build(&config()).unwrap();
        neo_tb::waves::maybe_trace(bench.model_mut(), name);
        for_each_seed(name, |seed| {
            // Odd counts: the last lane's share is one shorter.
            let n = 601 + 2 * (seed % 200) as usize;
            // SH degrees 0, 2 and 3 on the fixed seeds (1 in the one-Gaussian test).
            let (baked, cams) = scene(n, seed % 1000, 3, ((seed >> 1) % 4) as u8);
            let mut prev: Vec<[u8; 32]> = Vec::new();
            for (f, cam) in cams.iter().enumerate() {
                let check = Checker::new("neo_pre_engine", seed ^ f as u64);
                let frame = LaneFrame { cam, all_fresh: f == 0, prev: &prev };
                let timing = if f % 2 == 0 { AxiTiming::RANDOM } else { AxiTiming::IDEAL };
                let run = bench.run(&baked, &frame, timing, &check);
                eprintln!(
                    "{name}: frame {f}: {} Gaussians (degree {}), {} visible, {} incoming entries in {} tiles, {} cycles, {} / {} beats read / written",
                    run.gaussians, baked.sh_degree, run.visible, run.hits, run.tiles, run.cycles, run.beats.0, run.beats.1
                );
                assert!(run.visible > 0 && run.visible < run.gaussians, "the camera must cull some Gaussians and keep some");
                assert!(run.hits > 0, "frame {f}: no incoming entry");
                prev = run.table;
            }
        });
    }

    #[test]
    fn a_scene_smaller_than_the_lanes_leaves_a_lane_idle() {
        let mut bench = PreEngineBench::build(&config()).unwrap();
        let (baked, cams) = scene(1, 7, 1, 1);
        let check = Checker::new("neo_pre_engine", 7);
        let frame = LaneFrame { cam: &cams[0], all_fresh: true, prev: &[] };
        let run = bench.run(&baked, &frame, AxiTiming::RANDOM, &check);
        assert_eq!(run.gaussians, 1);
        assert_eq!(run.table.len(), 1);
    }
}
