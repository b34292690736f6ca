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
    use neo_golden::camera::Camera;
    use neo_golden::engine::CameraWord;
    use neo_tb::lane::{
        camera_straddling_depth_2, depth_split, sweep_camera, sweep_world, visible_entries, walk_scene, LaneBench,
        LaneFrame, LanePlacement, LaneRange,
    };
    use neo_tb::rng::{for_each_seed, Rng};

    /// The baked synthetic scene (`gaussians`, `seed`, SH `degree`) and `frames` cameras of a fast walk through it
    /// (cameras inside the scene, so some Gaussians are culled).
    fn scene(gaussians: usize, seed: u64, frames: usize, degree: u8) -> (Baked, Vec<Camera>) {
        scene_in(gaussians, seed, frames, degree, ShPrecision::F32)
    }

    /// [`scene`] with SH records of `precision` (`neo_tb::lane::walk_scene` for the lane's format).
    fn scene_in(gaussians: usize, seed: u64, frames: usize, degree: u8, precision: ShPrecision) -> (Baked, Vec<Camera>) {
        walk_scene(&neo_tb::config(), (gaussians, seed), frames, degree, precision)
    }

    #[test]
    fn lane_writes_golden_feature_words_and_incoming_hits() {
        let name = "lane_writes_golden_feature_words_and_incoming_hits";
        let cfg = neo_tb::config();
        let mut bench = LaneBench::build(&cfg).unwrap();
        neo_tb::waves::maybe_trace(bench.model_mut(), name);
        for_each_seed(name, |seed| {
            // Every per-frame input changes from frame to frame of the one model: the SH degree
            // (0, 1, 2, 3, 0: every bit of degree_i and sh_words_i rises and falls), the camera
            // (neo_tb::lane::sweep_camera), the arrays' bases and the lane's first id (complement
            // placements over the 32-bit space, alternating), the count (c, 1023 - c: 10-bit
            // complements).
            // Three frames a seed, at phase g0 of the 5-frame schedule (degrees, grids): the fixed
            // seeds run frames 0-8 of it on the one model.
            let frames = 3;
            let g0 = neo_tb::rng::FIXED_SEEDS.iter().position(|&s| s == seed).map_or(seed as usize % 5, |k| 3 * k);
            let mut rng = Rng::new(seed ^ 0x1a7e);
            let scenes: Vec<(Baked, Vec<Camera>)> =
                (0..4u8).map(|d| scene(700, seed % 1000, frames, d)).collect();
            let n = scenes[0].0.len() as u32;
            let first = (seed % 97) as u32;
            // The larger count on the ordinary grids, the smaller on the strips of tiles.
            let c = rng.range(420, 603) as u32;
            let counts = [c.max(1023 - c), c.min(1023 - c)];
            let mut places = LanePlacement::complement_pair(&mut rng, LaneRange { first, count: 0 }, c.max(1023 - c));
            // The higher ids first: frames 0 and 2 (the fixed seeds' degree-3 frames) read SH
            // records past 2^37 bytes from sh_base_i (sh_off[37]).
            if places[0].id0 < places[1].id0 {
                places.swap(0, 1);
            }
            let mut prev = vec![[0u8; 32]; n as usize];
            for f in 0..frames {
                let g = g0 + f;
                let (baked, cams) = &scenes[[0, 1, 2, 3, 0][g % 5]];
                let cam = sweep_camera(&cams[f], cfg.tile, g, &mut rng);
                // The world moved (camera position, translation, rotation patterns), and on the
                // ordinary grids a huge Gaussian half a unit in front of the camera.
                let near = (g % 5 % 2 == 0).then_some(first as usize);
                let (baked, cam) = sweep_world(baked, &cam, g, near, &mut rng);
                let baked = &baked;
                let range = LaneRange { first, count: counts[g % 2] };
                let check = Checker::new("neo_pre_lane", seed ^ f as u64);
                // Frame 0 from scratch; then reuse, on a hostile and on an ideal memory.
                let span = range.first as usize..(range.first + range.count) as usize;
                let frame = LaneFrame { cam: &cam, all_fresh: f == 0, prev: &prev[span.clone()] };
                // The ideal memory answers after 64 cycles: eight feature words wait for their B.
                let slow = AxiTiming { latency: 64, ..AxiTiming::IDEAL };
                let pace = if f % 2 == 0 { (AxiTiming::RANDOM, 60) } else { (slow, 100) };
                let run = bench.run_at(baked, &frame, range, &places[f % 2], pace, &check);
                eprintln!(
                    "{name}: frame {f}: {}x{} pixels, degree {}, {} Gaussians from id {}, {} visible, {} incoming hits, {} cycles",
                    cam.width, cam.height, baked.sh_degree, run.gaussians, places[f % 2].id0 + first, run.visible, run.hits, run.cycles
                );
                if g % 5 % 2 == 0 {
                    // The ordinary grids (the others are a strip of tiles).
                    assert!(run.visible > 0 && run.visible < run.gaussians, "the camera must cull some Gaussians and keep some");
                    assert!(f == 0 || run.hits > 0, "frame {f}: no incoming hit");
                }
                prev[span].copy_from_slice(&run.table);
                // Then an empty range (count 0) with the bitwise complement of the frame's camera
                // words: every camera bit rises and falls (v, !v, w, !w) on the one model, and an
                // empty range must do nothing whatever the words hold (checked: no read, write or
                // hit, busy_o falls).
                let words = CameraWord::values(&cam, cfg.tile).map(|w| !w);
                let check = Checker::new("neo_pre_lane", seed ^ f as u64 ^ 0xe3);
                let cycles = bench.run_empty(&words, baked.sh_degree, first, &places[f % 2], &check);
                eprintln!("{name}: frame {f}: an empty range, complement camera words: {cycles} cycles");
            }
        });
    }

    /// Binary16 SH records (`sh_half_i`, golden `engine::pre::sh_record_words`: two coefficients
    /// a word, degrees 0 and 2 padded) at every degree, alternating with binary32 records on the
    /// one model (so `sh_half_i` rises and falls). Some Gaussians carry directed halves in every
    /// coefficient: every subnormal significand bit, the largest subnormal and normal, both
    /// infinities, NaNs and both zeros, so each path of the widening (`neo_fp_widen_half_comb`)
    /// reaches the colour unit; the feature words are checked against golden `preprocess_one`
    /// on the same halves.
    #[test]
    fn lane_reads_half_sh_records_at_every_degree() {
        let name = "lane_reads_half_sh_records_at_every_degree";
        let cfg = neo_tb::config();
        let mut bench = LaneBench::build(&cfg).unwrap();
        neo_tb::waves::maybe_trace(bench.model_mut(), name);
        const HALVES: [u32; 16] = [
            0x0001, 0x0002, 0x0004, 0x0008, 0x0010, 0x0020, 0x0040, 0x0080, 0x0100, 0x0200, 0x83ff, 0x7bff,
            0xfc00, 0x7e01, 0x8000, 0x3c00,
        ];
        for_each_seed(name, |seed| {
            for (k, degree) in [0u8, 1, 2, 3, 3, 2, 1, 0].into_iter().enumerate() {
                let precision = if k % 2 == 0 { ShPrecision::F16 } else { ShPrecision::F32 };
                let (mut baked, cams) = scene_in(300, seed % 1000 + k as u64, 1, degree, precision);
                let per = baked.sh_per_gaussian();
                if precision == ShPrecision::F16 {
                    // Every fifth Gaussian: coefficient c of Gaussian g is HALVES[(g + c) % 16].
                    for g in (0..baked.len()).step_by(5) {
                        for c in 0..per {
                            baked.sh[g * per + c] = HALVES[(g / 5 + c) % HALVES.len()];
                        }
                    }
                }
                let check = Checker::new("neo_pre_lane", seed ^ k as u64);
                let frame = LaneFrame { cam: &cams[0], all_fresh: true, prev: &[] };
                let range = LaneRange { first: 1, count: baked.len() as u32 - 1 };
                let run = bench.run(&baked, &frame, range, (AxiTiming::RANDOM, 80), &check);
                eprintln!(
                    "{name}: degree {degree}, {precision:?}: {} Gaussians, {} visible, {} cycles",
                    run.gaussians, run.visible, run.cycles
                );
                assert!(run.visible > 0, "degree {degree}, {precision:?}: no visible Gaussian");
            }
        });
    }

    /// The fixed map (ids are the baked indices, the arrays at the bench's constant bases).
    #[test]
    fn lane_at_the_fixed_bases() {
        let cfg = neo_tb::config();
        let mut bench = LaneBench::build(&cfg).unwrap();
        let (baked, cams) = scene(200, 5, 1, 3);
        let check = Checker::new("neo_pre_lane", 5);
        let frame = LaneFrame { cam: &cams[0], all_fresh: true, prev: &[] };
        let run = bench.run(&baked, &frame, LaneRange { first: 3, count: 190 }, (AxiTiming::RANDOM, 70), &check);
        assert!(run.visible > 0 && run.hits > 0, "{run:?}");
    }

    /// A slow writer (AW and W ready 12 % of the cycles, full read bandwidth): the colour
    /// unit's output waits for each feature word's write, the pending queue fills, and the
    /// projection unit advances one stage per word written while the geometry fetch has a
    /// record ready at each advance, so its stages fill up and `u_posq` (one entry per Gaussian
    /// inside `u_project`) passes 128 entries and drains again. The camera moves along its view
    /// axis until the visible depths straddle 2 (the FP16 depth key's bit 14 set and clear in
    /// `u_colq`'s words), and one Gaussian (sigma 400, half a unit in front of the camera) is
    /// so wide that its conic exponent field reaches 32. Then the same frame again reusing the
    /// table just written (no incoming hit): every visible Gaussian takes its previous word into
    /// `prev_q`, whose depth keys and conic exponents (fields the duplication unit does not use)
    /// take both values of their bits 14 and 5.
    #[test]
    fn lane_fills_its_queues_behind_a_slow_writer() {
        let name = "lane_fills_its_queues_behind_a_slow_writer";
        let cfg = neo_tb::config();
        let mut bench = LaneBench::build(&cfg).unwrap();
        neo_tb::waves::maybe_trace(bench.model_mut(), name);
        let (mut baked, cams) = scene(400, 11, 1, 0);
        let range = LaneRange { first: 1, count: baked.len() as u32 - 1 };
        let cam = camera_straddling_depth_2(&cfg, &baked, &cams[0], range, -16..=40);
        let wide = &mut baked.geometry[5];
        let p = cam.position + cam.cam_to_world.z_axis * 0.5;
        wide.position = [p.x as f32, p.y as f32, p.z as f32];
        wide.cov3d = [160_000.0, 0.0, 0.0, 160_000.0, 0.0, 160_000.0];
        let baked = baked;
        let (near, far) = depth_split(&cfg, &baked, &cam, range);
        assert!(near > 0 && far > 0, "visible depths below 2: {near}, at least 2: {far}");
        let exps: Vec<u32> = visible_entries(&cfg, &baked, &cam, range).iter().map(|e| e.conic.exp).collect();
        assert!(exps.iter().any(|&e| e >= 32) && exps.iter().any(|&e| e < 32), "conic exponents {exps:?}");
        let slow = AxiTiming { ready_percent: 12, ..AxiTiming::IDEAL };
        for_each_seed(name, |seed| {
            let check = Checker::new("neo_pre_lane", seed);
            let frame = LaneFrame { cam: &cam, all_fresh: true, prev: &[] };
            let run = bench.run(&baked, &frame, range, (slow, 100), &check);
            eprintln!(
                "{name}: {} Gaussians, {} visible ({near} nearer than 2), {} cycles",
                run.gaussians, run.visible, run.cycles
            );
            assert!(run.visible > 0 && run.visible < run.gaussians, "{run:?}");
            let again = LaneFrame { cam: &cam, all_fresh: false, prev: &run.table };
            let reuse = bench.run(&baked, &again, range, (AxiTiming::IDEAL, 100), &check);
            assert_eq!((reuse.visible, reuse.hits), (run.visible, 0), "{reuse:?}");
        });
    }
}
