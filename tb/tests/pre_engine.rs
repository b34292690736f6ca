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
    use neo_tb::lane::{camera_straddling_depth_2, depth_split, sweep_camera, sweep_world, LaneFrame, LaneRange};
    use neo_tb::pre_engine::{EngineBases, EngineSetup, PreEngineBench};
    use neo_tb::rng::{for_each_seed, Rng};

    /// `tb/pre_engine.json`: two lanes (the split and the arbiter at work; a lane's C++ is
    /// compiled per instance, so the default four cost twice the build; `scripts/mutate-check`
    /// mutates this configuration's Verilog, its `pre:` files).
    fn config() -> neo_gen::EngineConfig {
        neo_tb::pre_engine::bench_config()
    }

    /// The baked synthetic scene and `frames` cameras of a fast walk through it.
    fn scene(gaussians: usize, seed: u64, frames: usize, degree: u8) -> (Baked, Vec<neo_golden::camera::Camera>) {
        scene_in(gaussians, seed, frames, degree, ShPrecision::F32)
    }

    /// [`scene`] with SH records of `precision` (`neo_tb::lane::walk_scene` for the bench's format).
    fn scene_in(
        gaussians: usize,
        seed: u64,
        frames: usize,
        degree: u8,
        precision: ShPrecision,
    ) -> (Baked, Vec<neo_golden::camera::Camera>) {
        neo_tb::lane::walk_scene(&config(), (gaussians, seed), frames, degree, precision)
    }

    #[test]
    fn pre_engine_writes_golden_features_lists_and_lengths() {
        let name = "pre_engine_writes_golden_features_lists_and_lengths";
        let cfg = config();
        let mut bench = PreEngineBench::build(&cfg).unwrap();
        neo_tb::waves::maybe_trace(bench.model_mut(), name);
        for_each_seed(name, |seed| {
            // Every per-frame input changes from frame to frame of the one model: the SH degree
            // (0, 1, 2, 3, 0: every bit of degree_i and the SH record size rises and falls), the
            // SH records' precision (binary16 on frames 5-9 of a 10-frame schedule: every degree
            // in both; each empty frame below flips it, so PRE_CTRL.sh_half and the record size
            // rise and fall on every frame), the
            // camera (neo_tb::lane::sweep_camera: orientations, focal lengths, tile grids up to
            // 1015 columns or rows), the base registers (complement maps over the 32-bit space,
            // alternating), GAUSSIANS (c, 1023 - c) and TILES (T, 2047 - T, at least the grid).
            // Three frames a seed, at phase g0 of the 5-frame schedule (degrees, grids): the fixed
            // seeds run frames 0-8 of it on the one model.
            let frames = 3;
            let g0 = neo_tb::rng::FIXED_SEEDS.iter().position(|&s| s == seed).map_or(seed as usize % 5, |k| 3 * k);
            let mut rng = Rng::new(seed ^ 0xe9e);
            let n = 601 + 2 * (seed % 50) as usize;
            let precisions = [ShPrecision::F32, ShPrecision::F16];
            let scenes: Vec<Vec<(Baked, Vec<neo_golden::camera::Camera>)>> = precisions
                .iter()
                .map(|&p| (0..4u8).map(|d| scene_in(n, seed % 1000, frames, d, p)).collect())
                .collect();
            // Odd and even counts: the last lane's share is one shorter on the odd ones.
            let c = rng.range(430, 594) as u32;
            // GAUSSIANS + 3 (share_sum) is 0 mod 8 on even seeds, 6 on odd ones (then 5 and 7
            // for 1023 - c): its bits 1 and 2 rise and fall.
            let c = (c & !7) | [5, 3][g0 / 3 % 2];
            let t = rng.range(80, 1032) as u32;
            let bases = EngineBases::complement_pair(&cfg, &mut rng, n as u64, 2047);
            let mut prev = vec![[0u8; 32]; n];
            for f in 0..frames {
                let g = g0 + f;
                let (baked, cams) = &scenes[g / 5 % 2][[0, 1, 2, 3, 0][g % 5]];
                let cam = sweep_camera(&cams[f], cfg.tile, g, &mut rng);
                // The world moved (neo_tb::lane::sweep_world), on the ordinary grids with a huge
                // Gaussian (id 0) half a unit in front of the camera.
                let (baked, cam) = sweep_world(baked, &cam, g, (g % 5 % 2 == 0).then_some(0), &mut rng);
                let baked = &baked;
                let check = Checker::new("neo_pre_engine", seed ^ f as u64);
                let frame = LaneFrame { cam: &cam, all_fresh: f == 0, prev: &prev };
                let at = EngineSetup {
                    bases: bases[f % 2],
                    gaussians: Some([c, 1023 - c][f % 2]),
                    // A strip's grid has more than 1032 tiles: its TILES is 2047 - T.
                    tiles: Some(if g % 5 % 2 == 1 || f % 2 == 1 { 2047 - t } else { t }),
                };
                let timing = if f % 2 == 0 { AxiTiming::RANDOM } else { AxiTiming::IDEAL };
                let run = bench.run_at(baked, &frame, &at, timing, &check);
                let mut regs = bench.frame_regs(baked, &frame, &at);
                eprintln!(
                    "{name}: frame {f}: {}x{} pixels, {} Gaussians (degree {}, {:?} SH), {} visible, {} incoming entries in {} tiles, {} cycles, {} / {} beats read / written",
                    cam.width, cam.height, run.gaussians, baked.sh_degree, baked.sh_precision, run.visible, run.hits, run.tiles, run.cycles, run.beats.0, run.beats.1
                );
                if g % 5 % 2 == 0 {
                    // The ordinary grids (the others are a strip of tiles).
                    assert!(run.visible > 0 && run.visible < run.gaussians, "the camera must cull some Gaussians and keep some");
                    assert!(f == 0 || run.hits > 0, "frame {f}: no incoming entry");
                }
                prev[..run.table.len()].copy_from_slice(&run.table);
                // Then an empty frame (GAUSSIANS and TILES 0) with the other SH precision, whose
                // camera words are the bitwise complement of this frame's: every camera bit rises
                // and falls (v, !v, w, !w) on the one model, and an empty frame must do nothing
                // whatever the words hold
                // (checked against golden, and here: no beat read or written, no entry, done_o
                // within 64 cycles).
                regs.pre.camera = regs.pre.camera.map(|w| !w);
                regs.pre.ctrl ^= neo_golden::engine::PRE_SH_HALF;
                (regs.pre.gaussians, regs.tiles) = (0, 0);
                let check = Checker::new("neo_pre_engine", seed ^ f as u64 ^ 0xe3);
                let empty = bench.run_regs(baked, &prev, &regs, AxiTiming::RANDOM, &check);
                eprintln!(
                    "{name}: frame {f}: an empty frame, complement camera words: {} cycles",
                    empty.cycles
                );
                let what = (empty.beats, empty.hits, empty.visible);
                assert_eq!(what, ((0, 0), 0, 0), "an empty frame: {empty:?}");
                assert!(empty.cycles <= 64, "an empty frame: {empty:?}");
            }
        });
    }

    /// A camera backed off along its view axis until the visible depths straddle 2: the FP16
    /// depth key's bit 14 set and clear in the lanes' hits, the arbiter's and the list lines
    /// (the walk's cameras see every Gaussian nearer than 2).
    #[test]
    fn depths_on_both_sides_of_2_reach_the_lists() {
        let name = "depths_on_both_sides_of_2_reach_the_lists";
        let cfg = config();
        let mut bench = PreEngineBench::build(&cfg).unwrap();
        neo_tb::waves::maybe_trace(bench.model_mut(), name);
        let (baked, cams) = scene(601, 11, 1, 0);
        let all = LaneRange { first: 0, count: baked.len() as u32 };
        let cam = camera_straddling_depth_2(&cfg, &baked, &cams[0], all, 0..=40);
        let (near, far) = depth_split(&cfg, &baked, &cam, all);
        assert!(near > 0 && far > 0, "visible depths below 2: {near}, at least 2: {far}");
        let check = Checker::new("neo_pre_engine", 11);
        let frame = LaneFrame { cam: &cam, all_fresh: true, prev: &[] };
        let run = bench.run(&baked, &frame, AxiTiming::RANDOM, &check);
        eprintln!(
            "{name}: {} Gaussians, {} visible ({near} nearer than 2), {} entries, {} cycles",
            run.gaussians, run.visible, run.hits, run.cycles
        );
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
