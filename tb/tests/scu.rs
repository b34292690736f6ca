//! `neo_scu` against golden `shade_pixel` / `raster_tile`: random lists (>= 10k Gaussians)
//! under random stalls and backpressure, directed corner cases, and the termination drain.

#[cfg(not(neo_has_verilator))]
#[test]
fn scu_skipped_without_verilator() {
    // Prints SKIP (or fails when CI is set); the models must really be absent in this build.
    assert!(!neo_tb::require_models("scu_skipped_without_verilator: SCU cosimulation did not run"));
}

#[cfg(neo_has_verilator)]
mod cosim {
    use neo_gen::EngineConfig;
    use neo_golden::formats::feature::FeatureEntry;
    use neo_golden::raster::{pixel_alpha, raster_tile, ExpTable};
    use neo_tb::dut::Clocked;
    use neo_tb::models::NeoScu;
    use neo_tb::rng::{for_each_seed, Rng};
    use neo_tb::scu::{
        far_gaussians, gaussian, gaussian_with_alpha, lists_of, measure_timing, run_checked,
        run_pieces_checked, top_origin, ScuList,
    };
    use neo_tb::waves::maybe_trace;

    /// Random Gaussians in CI: at least 10k (override with NEO_TB_VECTORS).
    fn gaussian_count() -> usize {
        std::env::var("NEO_TB_VECTORS").ok().and_then(|v| v.parse().ok()).unwrap_or(10_000)
    }

    /// The default configuration, with `scu_lanes` from NEO_SCU_LANES when set (to cosimulate
    /// RTL generated with other lanes through NEO_HDL_DIR).
    fn scu_config() -> neo_gen::EngineConfig {
        let mut cfg = neo_tb::config();
        if let Some(l) = std::env::var("NEO_SCU_LANES").ok().and_then(|v| v.parse().ok()) {
            cfg.scu_lanes = l;
        }
        cfg
    }

    fn full(origin: [u32; 2], entries: Vec<FeatureEntry>) -> ScuList {
        ScuList { origin, cols: 8, rows: 8, entries }
    }

    #[test]
    fn scu_random_lists_under_stalls_and_backpressure() {
        let name = "scu_random_lists_under_stalls_and_backpressure";
        for_each_seed(name, |seed| {
            let mut dut = NeoScu::new();
            maybe_trace(&mut dut, name);
            random_lists(&mut dut, &scu_config(), seed, gaussian_count());
        });
    }

    /// At least `total` Gaussians in random lists under every stall/backpressure mix.
    fn random_lists<M: Clocked>(dut: &mut M, cfg: &EngineConfig, seed: u64, total: usize) {
        let name = "scu_random_lists_under_stalls_and_backpressure";
        let mut rng = Rng::new(seed);
        let mixes = [(0, 100), (30, 100), (0, 40), (50, 50), (10, 90)];
        let mut sent = 0;
        let mut k = 0u64;
        while sent < total {
            let (stall, ready) = mixes[k as usize % mixes.len()];
            let lists = lists_of(&mut rng, cfg, 40, 24);
            let run = run_checked(dut, cfg, seed.wrapping_add(k), &lists, stall, ready);
            sent += run.gaussians;
            k += 1;
        }
        assert!(sent >= total, "{sent} Gaussians, wanted {total}");
        println!("{name}: {sent} Gaussians in {k} runs checked");
    }

    #[test]
    fn scu_directed_corner_cases() {
        let name = "scu_directed_corner_cases";
        for_each_seed(name, |seed| {
            let mut dut = NeoScu::new();
            maybe_trace(&mut dut, name);
            directed(&mut dut, &scu_config(), seed);
        });
    }

    /// The directed corner cases one by one and all together under stalls.
    fn directed<M: Clocked>(dut: &mut M, cfg: &EngineConfig, seed: u64) {
        let fmt = cfg.feature_format();
        let rc = cfg.raster_config();
        let o = [96u32, 40u32];
        let c = [o[0] as f64 + 3.5, o[1] as f64 + 3.5];
        let mut cases: Vec<(&str, ScuList)> = Vec::new();
        cases.push(("empty list", full(o, vec![])));
        cases.push(("list of one", full(o, vec![gaussian(c, 2.0, 1.5, 0.3, 0.7, [1.0, 0.5, 0.25])])));
        // An opaque stack drives T below 1e-4 (pixels finish; the rest is drained).
        let stack: Vec<_> =
            (0..40).map(|i| gaussian(c, 30.0, 30.0, 0.0, 0.99, [0.1 * (i % 10) as f64, 0.9, 0.3])).collect();
        cases.push(("opaque stack", full(o, stack)));
        cases.push(("needle", full(o, vec![gaussian(c, 40.0, 0.05, 0.7, 0.95, [0.9, 0.9, 0.1])])));
        cases.push((
            "screen filling",
            full(o, vec![gaussian([5000.0, -3000.0], 9000.0, 7000.0, 0.2, 0.5, [0.3, 0.6, 0.9])]),
        ));
        cases.push((
            "centred outside",
            full(o, vec![gaussian([o[0] as f64 - 6.0, o[1] as f64 + 12.0], 3.0, 2.0, 0.5, 0.9, [1.0; 3])]),
        ));
        cases.push((
            "partly outside the image",
            ScuList { origin: o, cols: 5, rows: 3, entries: vec![gaussian(c, 6.0, 6.0, 0.0, 0.8, [1.0; 3])] },
        ));
        cases.push((
            "subtile outside the image",
            ScuList { origin: o, cols: 0, rows: 8, entries: vec![gaussian(c, 6.0, 6.0, 0.0, 0.8, [1.0; 3])] },
        ));
        // The far end of the lane datapath: the subtile at the top of the origin range, means at
        // the most negative value (|dx|, |dy| up to 3 2^27 - 2^8, q up to 2^76), largest
        // mantissas and exponents from the largest down: np from 0 (alpha at the cap) to the
        // saturation (skipped), checked here with golden pixel_alpha at the origin pixel.
        let side = rc.subtile;
        let far =
            ScuList { origin: top_origin(&fmt, side), cols: side, rows: side, entries: far_gaussians(&fmt) };
        let exp = ExpTable::new(&rc.blend.exp, rc.blend.power_frac);
        let (fx, fy) = (far.origin[0] as i64, far.origin[1] as i64);
        let alphas: Vec<i64> = far
            .entries
            .iter()
            .map(|e| pixel_alpha(e, &fmt, &rc, &exp, fx, fy).expect("a positive definite conic"))
            .collect();
        let (min_alpha, max_alpha) = (rc.blend.min_alpha_raw(), rc.blend.max_alpha_raw());
        assert!(alphas.contains(&max_alpha), "far: an entry at the alpha cap: {alphas:?}");
        assert!(
            alphas.iter().any(|&a| (min_alpha..max_alpha).contains(&a)),
            "far: below the cap: {alphas:?}"
        );
        assert!(alphas.iter().any(|&a| a < min_alpha), "far: an entry below 1/255: {alphas:?}");
        assert!(
            neo_tb::scu::golden_pixels(&far, &fmt, &rc).iter().any(|p| *p != [0; 3]),
            "far: some pixel is blended"
        );
        cases.push(("far end: top origin, means at the far end", far));
        // Alpha exactly at 1/255 (min_alpha_raw) and one LSB below, at a subtile pixel: search
        // the opacity and offset with golden pixel_alpha, then check the golden decision.
        let (px, py) = (o[0] as i64 + 2, o[1] as i64 + 5);
        let at = gaussian_with_alpha(&fmt, &rc, px, py, min_alpha).expect("an entry at 1/255");
        let below = gaussian_with_alpha(&fmt, &rc, px, py, min_alpha - 1).expect("an entry one LSB below");
        let at_list = full(o, vec![at]);
        let below_list = full(o, vec![below]);
        let k = ((py - o[1] as i64) * 8 + (px - o[0] as i64)) as usize;
        let g_at = neo_tb::scu::golden_pixels(&at_list, &fmt, &rc)[k];
        let g_below = neo_tb::scu::golden_pixels(&below_list, &fmt, &rc)[k];
        assert_ne!(g_at, [0; 3], "alpha = 1/255 is blended");
        assert_eq!(g_below, [0; 3], "alpha one LSB below 1/255 is skipped");
        cases.push(("alpha exactly 1/255", at_list));
        cases.push(("alpha one LSB below 1/255", below_list));
        for (k, (case, list)) in cases.iter().enumerate() {
            println!("case: {case}");
            run_checked(dut, cfg, seed ^ k as u64, std::slice::from_ref(list), 0, 100);
        }
        let all: Vec<_> = cases.iter().map(|(_, l)| l.clone()).collect();
        let run = run_checked(dut, cfg, seed, &all, 40, 50);
        assert_eq!(run.lists, cases.len());
    }

    /// Lists cut into pieces (empty ones included) interleaved over the state slots, as the
    /// raster core sends a long table's segments: each subtile saved at a piece's end and resumed
    /// at its next piece gives golden's pixels of the whole list. Opaque stacks terminate in one
    /// piece and are drained in the later ones.
    #[test]
    fn scu_resumes_subtiles_from_saved_state_across_pieces() {
        let name = "scu_resumes_subtiles_from_saved_state_across_pieces";
        for_each_seed(name, |seed| {
            let mut dut = NeoScu::new();
            maybe_trace(&mut dut, name);
            resumes(&mut dut, &scu_config(), seed, gaussian_count() / 2);
        });
    }

    /// At least `total` Gaussians in lists cut into interleaved pieces.
    fn resumes<M: Clocked>(dut: &mut M, cfg: &EngineConfig, seed: u64, total: usize) {
        let name = "scu_resumes_subtiles_from_saved_state_across_pieces";
        let slots = neo_gen::units::scu::ScuWidths::new(cfg).rows as usize;
        let mut rng = Rng::new(seed);
        let mixes = [(0, 100), (30, 60), (10, 90)];
        let (mut sent, mut runs) = (0, 0u64);
        while sent < total {
            let (stall, ready) = mixes[runs as usize % mixes.len()];
            let count = 1 + rng.below(slots as u64) as usize;
            let mut lists = lists_of(&mut rng, cfg, count, 40);
            if runs % 4 == 3 {
                let o = lists[0].origin;
                let c = [o[0] as f64 + 4.0, o[1] as f64 + 4.0];
                lists[0].entries =
                    (0..60).map(|_| gaussian(c, 40.0, 40.0, 0.0, 0.95, [0.3, 0.6, 0.9])).collect();
            }
            let pieces = 1 + rng.below(6) as usize;
            let run = run_pieces_checked(dut, cfg, seed.wrapping_add(runs), &lists, pieces, stall, ready);
            sent += run.gaussians;
            runs += 1;
        }
        println!("{name}: {sent} Gaussians in {runs} runs of up to {slots} interleaved subtiles checked");
    }

    #[test]
    fn scu_terminates_early_and_drains_the_rest() {
        let name = "scu_terminates_early_and_drains_the_rest";
        for_each_seed(name, |seed| {
            let mut dut = NeoScu::new();
            maybe_trace(&mut dut, name);
            terminates(&mut dut, &scu_config(), seed);
        });
    }

    /// An opaque stack terminates and the rest drains at one Gaussian a cycle; the II is the
    /// passes per Gaussian.
    fn terminates<M: Clocked>(dut: &mut M, cfg: &EngineConfig, seed: u64) {
        let name = "scu_terminates_early_and_drains_the_rest";
        let o = [8u32, 8u32];
        let n = 200;
        let stack: Vec<_> =
            (0..n).map(|_| gaussian([12.0, 12.0], 50.0, 50.0, 0.0, 0.99, [0.5, 0.5, 0.5])).collect();
        let run = run_checked(dut, cfg, seed, &[full(o, stack)], 0, 100);
        let passes = 64 / cfg.scu_lanes as u64;
        // Without the drain it would take n * passes cycles (with one pass, II is 1 anyway).
        if passes > 1 {
            assert!(run.cycles < n as u64 * passes / 2 + 40, "{} cycles for {n} Gaussians", run.cycles);
        }
        assert!(run.term_cycles > n as u64 / 2, "term_o high for {} cycles", run.term_cycles);
        let t = measure_timing(dut, cfg, seed);
        assert_eq!(t.ii, passes, "{t:?}");
        assert_eq!(t.drain_ii, 1, "{t:?}");
        println!("{name}: {t:?}");
    }

    /// The SCU fed with raster_tile's routing (the ITU bitmaps) reproduces raster_tile's pixels.
    #[test]
    fn scu_reproduces_raster_tile() {
        let name = "scu_reproduces_raster_tile";
        for_each_seed(name, |seed| {
            let mut dut = NeoScu::new();
            maybe_trace(&mut dut, name);
            reproduces_raster_tile(&mut dut, &scu_config(), seed, 300);
        });
    }

    /// `count` Gaussians of one tile routed by raster_tile's bitmaps.
    fn reproduces_raster_tile<M: Clocked>(dut: &mut M, cfg: &EngineConfig, seed: u64, count: usize) {
        let name = "scu_reproduces_raster_tile";
        let fmt = cfg.feature_format();
        let rc = cfg.raster_config();
        let mut rng = Rng::new(seed);
        let (tx, ty, width, height) = (1u32, 2u32, 100u32, 170u32);
        let (x0, y0) = (tx * rc.tile, ty * rc.tile);
        let entries: Vec<FeatureEntry> = (0..count)
            .map(|_| {
                let o = [x0 + rng.below(rc.tile as u64) as u32, y0 + rng.below(rc.tile as u64) as u32];
                neo_tb::scu::random_gaussian(&mut rng, &fmt, o)
            })
            .collect();
        let tile = raster_tile(&entries, &fmt, tx, ty, width, height, &rc);
        let n = rc.subtiles_per_side();
        let s = rc.subtile;
        let mut lists = Vec::new();
        for j in 0..n * n {
            let (sx, sy) = (j % n, j / n);
            let origin = [x0 + sx * s, y0 + sy * s];
            let routed: Vec<FeatureEntry> = entries
                .iter()
                .zip(&tile.bitmaps)
                .filter(|(_, &b)| b >> j & 1 == 1)
                .map(|(e, _)| *e)
                .collect();
            let cols = width.saturating_sub(origin[0]).min(s);
            let rows = height.saturating_sub(origin[1]).min(s);
            lists.push(ScuList { origin, cols, rows, entries: routed });
        }
        // The golden per-pixel view of these lists equals raster_tile (routing is exact).
        for (j, l) in lists.iter().enumerate() {
            let g = neo_tb::scu::golden_pixels(l, &fmt, &rc);
            let (sx, sy) = (j as u32 % n, j as u32 / n);
            for (k, px) in g.iter().enumerate() {
                let (lx, ly) = (k as u32 % s, k as u32 / s);
                let t = tile.pixels[((sy * s + ly) * rc.tile + sx * s + lx) as usize];
                assert_eq!(*px, t, "subtile {j} pixel {k}");
            }
        }
        let run = run_checked(dut, cfg, seed, &lists, 20, 70);
        assert_eq!(run.lists, (n * n) as usize);
        println!("{name}: {} Gaussians routed over {} subtiles", run.gaussians, n * n);
    }

    /// The same benches (random lists and interleaved pieces, fewer Gaussians; the directed
    /// cases; termination, drain and II; raster_tile's routing) on `neo_scu` generated for each
    /// of [`neo_tb::configs::scu`].
    #[test]
    fn scu_in_other_configurations() {
        neo_tb::configs::run_in_other_configurations(
            "scu_in_other_configurations",
            neo_tb::configs::scu(),
            |cfg| neo_tb::configs::build(cfg, "neo_scu"),
            |dut| dut,
            |dut, cfg, seed| {
                random_lists(dut, cfg, seed, 2000);
                resumes(dut, cfg, seed, 1000);
                directed(dut, cfg, seed);
                terminates(dut, cfg, seed);
                reproduces_raster_tile(dut, cfg, seed, 150);
            },
        );
    }
}
