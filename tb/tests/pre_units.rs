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
    use neo_golden::hwarith::graph::{Graph, Trace};
    use neo_golden::hwarith::Arith;
    use neo_tb::check::Checker;
    use neo_tb::datapath::DatapathBench;
    use neo_tb::rng::{for_each_seed, Rng};

    /// Every inline operation of the library on two floats and two integers.
    fn inline_graph() -> Graph {
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
        for (n, v) in [("lt", lt), ("le", le), ("eq", eq), ("nan", nan), ("fin", fin), ("and", and), ("or", or), ("not", not)] {
            t.output_b(n, v);
        }
        t.finish()
    }

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
        let top = Datapath::new(&g, &PreLibrary).module("neo_pre_inline_bench", &[]);
        let mut bench = DatapathBench::build(g, &top, &[]).expect("build");
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
            let check = Checker::new("neo_pre_inline_bench", seed);
            for mix in [(100, 100), (60, 70), (30, 100)] {
                bench.run(&items, 0, &mut rng, mix, &check);
            }
        });
    }

    use neo_tb::dup::{random_items, DupBench, DupFrame, DupItem};

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
        let px = |v: f64| fmt.mean.quantize(v) as i32;
        let base = |x: f64, y: f64, r: i32| neo_golden::formats::FeatureEntry {
            mean: [px(x), px(y)],
            axis: [1 << fmt.axis.frac, 0],
            extent_xy: [r, r],
            extent_uv: [r, r],
            ..Default::default()
        };
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
}
