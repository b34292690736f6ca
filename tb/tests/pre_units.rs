//! The Preprocessing Engine's datapaths (`gen/src/units/pre`) against golden's graphs
//! (`Graph::eval`, the `Native` evaluation): the inline logic of the datapath library on edge
//! values, then the units on random and directed inputs, under random valid/ready backpressure,
//! with their depth and one-item-per-cycle rate checked.

#[test]
fn models_present() {
    assert_eq!(neo_tb::require_models("pre_units: datapath cosimulation"), neo_tb::HAS_MODELS);
}

neo_tb::with_models! {
    use neo_gen::units::pre::datapath::Datapath;
    use neo_gen::units::pre::library::PreLibrary;
    use neo_tb::check::Checker;
    use neo_tb::pre::{inline_graph, INLINE_BENCH_NAME};
    use neo_tb::datapath::DatapathBench;
    use neo_tb::rng::{for_each_seed, Rng};

    /// Floats that stress compares and sign handling.
    const EDGE_F: [u32; 14] = [
        0x0000_0000, 0x8000_0000, 0x0000_0001, 0x8000_0001, 0x007F_FFFF, 0x0080_0000, 0x3F80_0000,
        0xBF80_0000, 0x7F7F_FFFF, 0x7F80_0000, 0xFF80_0000, 0x7FC0_0000, 0xFFC1_2345, 0x7F80_0001,
    ];
    const EDGE_I: [u32; 9] = [0, 1, 0xFFFF_FFFF, 0x8000_0000, 0x7FFF_FFFF, 254, 255, 127, 0xFFFF_FF00];

    #[test]
    fn inline_logic_on_edge_and_random_values() {
        let name = "inline_logic_on_edge_and_random_values";
        let g = inline_graph();
        let top = Datapath::new(&g, &PreLibrary).module(INLINE_BENCH_NAME, &[]);
        let files = neo_gen::units::files_for_module(&neo_tb::config(), &top);
        let mut bench = DatapathBench::build(g, &top, &files).expect("build");
        for_each_seed(name, |seed| {
            let mut rng = Rng::new(seed);
            let mut items = Vec::new();
            for &a in &EDGE_F {
                for &b in &EDGE_F {
                    let (i, j) = (*rng.pick(&EDGE_I), *rng.pick(&EDGE_I));
                    items.push(vec![a, b, i, j]);
                }
            }
            for _ in 0..5000 {
                let f = |rng: &mut Rng| if rng.percent(30) { *rng.pick(&EDGE_F) } else { rng.next_u32() };
                let small = |rng: &mut Rng| if rng.percent(50) { rng.below(300) as u32 } else { rng.next_u32() };
                items.push(vec![f(&mut rng), f(&mut rng), small(&mut rng), small(&mut rng)]);
            }
            let check = Checker::new(INLINE_BENCH_NAME, seed);
            for mix in [(100, 100), (60, 70), (30, 100)] {
                bench.run(&items, 0, &mut rng, mix, &check);
            }
        });
    }

    use neo_tb::dup::{bounded_items, random_items, sweep_grid, DupBench, DupFrame, DupItem};

    fn dup_vectors() -> usize {
        std::env::var("NEO_TB_VECTORS").ok().and_then(|v| v.parse().ok()).unwrap_or(3000)
    }

    #[test]
    fn dup_random_gaussians_under_backpressure() {
        let name = "dup_random_gaussians_under_backpressure";
        let cfg = neo_tb::config();
        let mut bench = DupBench::build(&cfg).expect("build neo_pre_dup");
        neo_tb::waves::maybe_trace(bench.model_mut(), name);
        for_each_seed(name, |seed| {
            let mut rng = Rng::new(seed);
            let check = Checker::new("neo_pre_dup", seed);
            let (mut hits, mut incoming) = (0, 0);
            for (k, mix) in [(100, 100), (50, 80), (100, 30), (30, 50)].into_iter().enumerate() {
                let items = random_items(&cfg, &mut rng, neo_tb::rng::seed_share(dup_vectors()) / 4 + 1);
                let frame = DupFrame { grid: [20 + k as u32, 12], all_fresh: k == 3 };
                let want = neo_tb::dup::expected(&cfg, frame, &items);
                hits += want.len();
                incoming += want.iter().filter(|h| h.incoming).count();
                bench.run(frame, &items, &mut rng, mix, &check);
            }
            // The mix exercises both outcomes of the incoming test.
            assert!(hits > 100 && incoming > 0 && incoming < hits, "{hits} hits, {incoming} incoming");
        });
    }

    /// Named hard cases: a Gaussian exactly on a tile corner, one outside the image, unbounded
    /// extents (the whole grid), the previous frame invisible, identical or one tile away.
    #[test]
    fn dup_directed_cases() {
        let name = "dup_directed_cases";
        let cfg = neo_tb::config();
        let fmt = cfg.feature_format();
        let mut bench = DupBench::build(&cfg).expect("build neo_pre_dup");
        let base = |x: f64, y: f64, r: i32| neo_tb::dup::square_gaussian(&cfg, x, y, r);
        let unb = fmt.unbounded_extent();
        let one = 1 << fmt.extent.frac;
        let cases: Vec<(&str, DupItem)> = vec![
            ("on a tile corner", DupItem { id: 1, key: 5, now: base(64.0, 64.0, one), prev: None }),
            ("outside the image", DupItem { id: 2, key: 6, now: base(-500.0, 40.0, one), prev: None }),
            ("unbounded extents", DupItem { id: 3, key: 7, now: base(100.0, 100.0, unb), prev: Some(base(100.0, 100.0, one)) }),
            ("identical previous", DupItem { id: 4, key: 8, now: base(300.0, 200.0, 40 * one), prev: Some(base(300.0, 200.0, 40 * one)) }),
            ("one tile away", DupItem { id: 5, key: 9, now: base(300.0, 200.0, 20 * one), prev: Some(base(364.0, 200.0, 20 * one)) }),
            ("last tile of the grid", DupItem { id: 6, key: 10, now: base(1279.0, 767.0, one), prev: None }),
        ];
        for_each_seed(name, |seed| {
            let mut rng = Rng::new(seed);
            let check = Checker::new("neo_pre_dup", seed);
            for (case, item) in &cases {
                println!("{name}: {case}");
                let frame = DupFrame { grid: [20, 12], all_fresh: false };
                bench.run(frame, std::slice::from_ref(item), &mut rng, (100, 100), &check);
                bench.run(frame, std::slice::from_ref(item), &mut rng, (40, 40), &check);
            }
            let all: Vec<DupItem> = cases.iter().map(|c| c.1).collect();
            bench.run(DupFrame { grid: [20, 12], all_fresh: false }, &all, &mut rng, (70, 60), &check);
        });
    }

    /// At full rate a Gaussian occupies the walker one cycle per candidate tile (at least one):
    /// the next is accepted exactly that many cycles later.
    #[test]
    fn dup_tests_one_candidate_tile_per_cycle() {
        let cfg = neo_tb::config();
        let (fmt, r) = (cfg.feature_format(), cfg.raster_config());
        let mut bench = DupBench::build(&cfg).expect("build neo_pre_dup");
        let mut rng = Rng::new(7);
        let items = random_items(&cfg, &mut rng, 400);
        let frame = DupFrame { grid: [20, 12], all_fresh: false };
        let size = (20 * r.tile, 12 * r.tile);
        let walker: u64 = items[..items.len() - 1]
            .iter()
            .map(|it| neo_golden::hwpre::duplicate::candidate_count(&it.now, &fmt, &r, size).max(1) as u64)
            .sum();
        let run = bench.run(frame, &items, &mut rng, (100, 100), &Checker::new("neo_pre_dup", 7));
        assert_eq!(run.accept_span, walker, "{} hits over {walker} walker cycles", run.hits);
    }

    /// The per-frame grid swept over the tile index range in one model
    /// (`neo_tb::dup::sweep_grid`: a random grid, its 10-bit complement, the grid again, the
    /// 1023 x 1 and 1 x 1023 strips), with Gaussians spread over the whole index range (their
    /// candidate rectangles bounded to keep the walker short): every bit of the grid, of the
    /// rectangles, of the walker's tile and of the hits' tiles rises and falls.
    #[test]
    fn dup_grids_swept_over_the_tile_range() {
        let name = "dup_grids_swept_over_the_tile_range";
        let cfg = neo_tb::config();
        let mut bench = DupBench::build(&cfg).expect("build neo_pre_dup");
        neo_tb::waves::maybe_trace(bench.model_mut(), name);
        let top = (1u64 << cfg.tile_bits) - 2;
        let half = 1u32 << (cfg.tile_bits - 1);
        for_each_seed(name, |seed| {
            let mut rng = Rng::new(seed);
            let check = Checker::new("neo_pre_dup", seed);
            let g = [rng.range(1, top) as u32, rng.range(1, top) as u32];
            let mut far = [0usize; 2];
            for k in 0..5 {
                let grid = sweep_grid(&cfg, g, k);
                let frame = DupFrame { grid, all_fresh: k % 2 == 1 };
                let items = bounded_items(&cfg, &mut rng, grid, 150, 64);
                for h in neo_tb::dup::expected(&cfg, frame, &items) {
                    far[0] += usize::from(h.tile[0] >= half);
                    far[1] += usize::from(h.tile[1] >= half);
                }
                bench.run(frame, &items, &mut rng, [(100, 100), (60, 50), (90, 40)][k % 3], &check);
            }
            // Hits in the upper half of the index range on both axes (tile index bit 9).
            println!("{name}: hits beyond tile {half}: {far:?}");
            assert!(far[0] > 0 && far[1] > 0, "hits beyond tile {half}: {far:?}");
        });
    }

    use neo_gen::units::pre::{COLOR_NAME, PROJECT_NAME};
    use neo_golden::hwpre::bake::BakedGeometry;
    use neo_tb::pre::{
        axis_camera, color_bench, color_item, items_with_unseen_bits, node_bits_seen, on_axis_project_items, project_bench,
        project_item, random_camera_position, random_camera_project_items, random_color_items, scene_project_items,
        UnitBench,
    };

    /// At least 10k random Gaussians per seed share over the four SH degrees and backpressure mixes.
    #[test]
    fn color_random_gaussians_every_degree() {
        let name = "color_random_gaussians_every_degree";
        let UnitBench { mut bench, settle, .. } = color_bench(&neo_tb::config());
        neo_tb::waves::maybe_trace(bench.model_mut(), name);
        for_each_seed(name, |seed| {
            let mut rng = Rng::new(seed);
            let check = Checker::new(COLOR_NAME, seed);
            let per_degree = neo_tb::rng::seed_share(dup_vectors().max(10_000) * neo_tb::rng::SEED_RUNS) / 4;
            // Two camera positions per degree, drawn over their range (per-frame inputs).
            for degree in 0..4u32 {
                for half in 0..2 {
                    let cam = if degree + half == 0 { [0.5, -1.0, -3.0] } else { random_camera_position(&mut rng) };
                    let items = random_color_items(&mut rng, per_degree / 2, cam, degree);
                    let mix = [(100, 100), (70, 50), (40, 90), (90, 30)][degree as usize];
                    bench.run(&items, settle, &mut rng, mix, &check);
                }
            }
        });
    }

    /// Named hard cases: the Gaussian at the camera (no view direction), far away, huge and NaN
    /// coefficients, colours clamped at 0, each degree.
    #[test]
    fn color_directed_cases() {
        let name = "color_directed_cases";
        let UnitBench { mut bench, settle, .. } = color_bench(&neo_tb::config());
        let cam = [1.0f32, 2.0, 3.0];
        let mut ramp: Vec<f32> = (0..48).map(|k| (k as f32 - 24.0) / 10.0).collect();
        let cases: Vec<(&str, Vec<f32>, [f32; 3])> = vec![
            ("at the camera", ramp.clone(), cam),
            ("far away", ramp.clone(), [1e20, -3e19, 7e18]),
            ("huge coefficients", vec![3e38; 48], [4.0, 5.0, 6.0]),
            ("NaN coefficient", { let mut v = ramp.clone(); v[7] = f32::NAN; v }, [0.0, 0.0, 0.0]),
            ("negative colour", vec![-5.0; 48], [2.0, 2.0, 9.0]),
            ("subnormal coefficients", vec![1e-40; 48], [1.5, 2.5, 3.5]),
        ];
        ramp[0] = 1.0;
        for_each_seed(name, |seed| {
            let mut rng = Rng::new(seed);
            let check = Checker::new(COLOR_NAME, seed);
            for degree in 0..4u32 {
                let items: Vec<Vec<u32>> = cases.iter().map(|(_, sh, mean)| color_item(*mean, sh, cam, degree)).collect();
                for (case, item) in cases.iter().map(|c| c.0).zip(&items) {
                    println!("{name}: degree {degree}: {case}");
                    bench.run(std::slice::from_ref(item), settle, &mut rng, (100, 100), &check);
                }
                bench.run(&items, settle, &mut rng, (60, 60), &check);
            }
        });
    }

    /// The colour unit takes one Gaussian per cycle, and its latency is the emitted depth.
    #[test]
    fn color_one_gaussian_per_cycle() {
        let mut unit = color_bench(&neo_tb::config());
        let items = random_color_items(&mut Rng::new(3), 500, [0.0; 3], 3);
        let t = neo_tb::pre::measure(&mut unit, &items, &Checker::new(COLOR_NAME, 3));
        assert_eq!((t.latency, t.ii), (unit.depth as u64, 1));
        assert_eq!(t.cycles, items.len() as u64 + unit.depth as u64, "one item per cycle plus the fill");
    }

    #[test]
    fn project_scene_gaussians_under_backpressure() {
        let name = "project_scene_gaussians_under_backpressure";
        let UnitBench { mut bench, settle, .. } = project_bench(&neo_tb::config());
        neo_tb::waves::maybe_trace(bench.model_mut(), name);
        for_each_seed(name, |seed| {
            let mut rng = Rng::new(seed);
            let check = Checker::new(PROJECT_NAME, seed);
            let n = neo_tb::rng::seed_share(dup_vectors().max(10_000) * neo_tb::rng::SEED_RUNS) / 3;
            for (k, items) in scene_project_items(&neo_tb::config(), seed % 1000 + 1, n, 3).iter().enumerate() {
                bench.run(items, settle, &mut rng, [(100, 100), (60, 80), (90, 40)][k], &check);
            }
        });
    }

    /// Random cameras (every orientation, roll included; resolutions up to the largest tile grid;
    /// focal lengths of 0.3 to 3 image widths): the per-frame inputs over their range.
    #[test]
    fn project_random_cameras() {
        let name = "project_random_cameras";
        let cfg = neo_tb::config();
        let UnitBench { mut bench, settle, .. } = project_bench(&cfg);
        for_each_seed(name, |seed| {
            let mut rng = Rng::new(seed);
            let check = Checker::new(PROJECT_NAME, seed);
            let per_camera = neo_tb::rng::seed_share(500 * neo_tb::rng::SEED_RUNS);
            for (k, items) in random_camera_project_items(&cfg, &mut rng, per_camera, 16).iter().enumerate() {
                bench.run(items, settle, &mut rng, [(100, 100), (60, 80), (90, 40)][k % 3], &check);
            }
        });
    }

    /// Coverage-directed stimulus: hard on-axis geometry (`on_axis_project_items`: equal
    /// diagonal 2D covariances with a subnormal-squared cross term, every scale and depth) kept
    /// only when golden says it drives a node net bit that no item before it did
    /// (`items_with_unseen_bits`, from 100k candidates a seed); each kept item runs between
    /// ordinary ones, so such a bit rises and falls.
    #[test]
    fn project_items_that_drive_unseen_bits() {
        let name = "project_items_that_drive_unseen_bits";
        let cfg = neo_tb::config();
        let graph = neo_golden::hwpre::project::project_graph(&neo_gen::units::pre::project_params(&cfg));
        let UnitBench { mut bench, settle, .. } = project_bench(&cfg);
        for_each_seed(name, |seed| {
            let mut rng = Rng::new(seed);
            let check = Checker::new(PROJECT_NAME, seed);
            let base = on_axis_project_items(&mut rng, 400);
            let mut seen = node_bits_seen(&graph, &base);
            // 100k candidates at a time until 3 are found or 400k are drawn. How many exist depends
            // on how much the seed's 400 base items already drive: most seeds find 3 to 10 in the
            // first 100k; seed 0x59949d2964ac8512 finds 2, and no more in 800k (measured
            // 2026-12-06), so the premise is that the search finds some, not a count.
            let mut found = Vec::new();
            let mut drawn = 0;
            while found.len() < 3 && drawn < 400_000 {
                let candidates = on_axis_project_items(&mut rng, 100_000);
                drawn += 100_000;
                found.extend(items_with_unseen_bits(&graph, &mut seen, candidates.into_iter(), 300 - found.len()));
            }
            println!(
                "{name}: {} items drive bits the {} before them did not ({drawn} candidates)",
                found.len(),
                base.len()
            );
            assert!(!found.is_empty(), "the search found no item in {drawn} candidates");
            let mut items = Vec::new();
            for (f, b) in found.iter().zip(base.iter().cycle()) {
                items.push(b.clone());
                items.push(f.clone());
            }
            items.extend(base.iter().cloned());
            bench.run(&items, settle, &mut rng, (100, 100), &check);
        });
    }

    /// Named hard cases (golden `hwpre_project`'s classes, at the unit).
    #[test]
    fn project_directed_cases() {
        let name = "project_directed_cases";
        let UnitBench { mut bench, settle, .. } = project_bench(&neo_tb::config());
        let cam = axis_camera();
        let iso = |s: f32| [s, 0.0, 0.0, s, 0.0, s];
        let g = |position: [f32; 3], cov3d: [f32; 6], opacity: f32, k2: f32| BakedGeometry { position, cov3d, opacity, k2 };
        // Pixel x of a point at depth 1: 500 x + 319.5; x = 0.3 lands the mean 30.5 px into tile 7.
        let cases: Vec<(&str, BakedGeometry)> = vec![
            ("ordinary", g([0.1, -0.05, 2.0], iso(1e-4), 0.8, 11.0)),
            ("behind the camera", g([0.0, 0.0, -2.0], iso(1e-4), 0.8, 11.0)),
            ("on the near plane", g([0.0, 0.0, 0.2], iso(1e-4), 0.8, 11.0)),
            ("just past the near plane", g([0.0, 0.0, 0.200_000_02], iso(1e-4), 0.8, 11.0)),
            ("on a tile border", g([(64.0 - 319.5) / 500.0, 0.0, 1.0], iso(1e-6), 0.8, 11.0)),
            ("huge scale", g([0.0, 0.0, 3.0], iso(1e6), 0.8, 11.0)),
            ("tiny scale", g([0.0, 0.0, 3.0], iso(1e-14), 0.8, 11.0)),
            ("degenerate covariance", g([0.05, 0.0, 2.0], [1e-3, 1e-3, 1e-3, 1e-3, 1e-3, 1e-3], 0.8, 11.0)),
            ("needle", g([0.0, 0.1, 2.0], [1e-2, 0.0, 0.0, 1e-9, 0.0, 1e-9], 0.8, 11.0)),
            ("zero opacity", g([0.0, 0.0, 2.0], iso(1e-4), 0.0, 0.0)),
            ("unbounded cutoff", g([0.0, 0.0, 2.0], iso(1e-4), 0.8, f32::INFINITY)),
            ("largest coordinates", g([f32::MAX, -f32::MAX, f32::MAX], iso(1e-4), 0.8, 11.0)),
            ("far off screen", g([1e4, -1e4, 1.0], iso(1e-2), 0.8, 11.0)),
            ("NaN position", g([f32::NAN, 0.0, 2.0], iso(1e-4), 0.8, 11.0)),
            ("subnormal covariance", g([0.0, 0.0, 2.0], iso(1e-40), 0.8, 11.0)),
        ];
        for_each_seed(name, |seed| {
            let mut rng = Rng::new(seed);
            let check = Checker::new(PROJECT_NAME, seed);
            let items: Vec<Vec<u32>> = cases.iter().map(|(_, g)| project_item(g, &cam)).collect();
            for ((case, _), item) in cases.iter().zip(&items) {
                println!("{name}: {case}");
                bench.run(std::slice::from_ref(item), settle, &mut rng, (100, 100), &check);
            }
            bench.run(&items, settle, &mut rng, (50, 50), &check);
        });
    }

    /// The projection unit takes one Gaussian per cycle at the emitted depth.
    #[test]
    fn project_one_gaussian_per_cycle() {
        let cfg = neo_tb::config();
        let mut unit = project_bench(&cfg);
        let items = &scene_project_items(&cfg, 5, 600, 1)[0];
        let t = neo_tb::pre::measure(&mut unit, items, &Checker::new(PROJECT_NAME, 5));
        assert_eq!((t.latency, t.ii), (unit.depth as u64, 1));
        assert_eq!(t.cycles, items.len() as u64 + unit.depth as u64, "one item per cycle plus the fill");
    }
}
