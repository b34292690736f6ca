//! `neo_raster_core` against golden: whole 64x64 tiles (every pixel) and the deferred
//! write-back (every table entry's valid bit and depth key) for random tiles under memory stalls,
//! the directed hard cases, tables longer than the feature buffer, edge tiles, and tiles of
//! three consecutive frames of the biker scene (expected values from the golden pipeline).

#[cfg(not(neo_has_verilator))]
#[test]
fn raster_core_skipped_without_verilator() {
    // Prints SKIP (or fails when CI is set); the models must really be absent in this build.
    assert!(!neo_tb::require_models(
        "raster_core_skipped_without_verilator: raster-core cosimulation did not run"
    ));
}

#[cfg(neo_has_verilator)]
mod cosim {
    use neo_gen::EngineConfig;
    use neo_golden::raster::raster_tile;
    use neo_golden::shared::shared_file_for_test;
    use neo_golden::{source, trajectory};
    use neo_tb::core::MemTiming;
    use neo_tb::dut::Clocked;
    use neo_tb::raster::{at, case_of, g, golden, random_case, window_order_of, RasterCore, TileCase};
    use neo_tb::rng::{for_each_seed, seed_share, Rng, SeedSplit};
    use neo_tb::scu::gaussian_with_alpha;
    use neo_tb::waves::maybe_trace;

    /// Random Gaussians (override with NEO_TB_VECTORS; the core test uses a fifth of the unit
    /// benches' count, each Gaussian covering up to the whole tile).
    fn gaussian_count() -> usize {
        std::env::var("NEO_TB_VECTORS").ok().and_then(|v| v.parse().ok()).unwrap_or(10_000) / 5
    }

    const TIMINGS: [MemTiming; 3] = [
        MemTiming::IDEAL,
        MemTiming::RANDOM,
        MemTiming { req_ready_pct: 90, wr_ready_pct: 90, min_latency: 4, max_latency: 12, rsp_gap_pct: 5 },
    ];

    /// Runs and checks `case`; returns its cycles and its write-back reach.
    fn check_case<M: Clocked>(core: &mut RasterCore<M>, cfg: &EngineConfig, case: &TileCase) -> (u64, u64) {
        let want = golden(case, cfg);
        let run = core.run(case, &want);
        (run.cycles, run.wb_reach)
    }

    #[test]
    fn raster_core_random_tiles_under_memory_stalls() {
        let name = "raster_core_random_tiles_under_memory_stalls";
        for_each_seed(name, |seed| {
            let cfg = neo_tb::config();
            let mut core = RasterCore::new(&cfg, seed, MemTiming::IDEAL);
            maybe_trace(&mut core.dut, name);
            // The Gaussians are split over the seeds (each seed its share: the same with NEO_SEED).
            random_tiles(&mut core, &cfg, seed, seed_share(gaussian_count()), 48);
        });
    }

    /// Random tables of up to `max_len` entries, at least `total` Gaussians, on random tiles
    /// (a quarter of them at the image's edge), the memory timings in turn.
    fn random_tiles<M: Clocked>(
        core: &mut RasterCore<M>,
        cfg: &EngineConfig,
        seed: u64,
        total: usize,
        max_len: u64,
    ) {
        let name = "raster_core_random_tiles_under_memory_stalls";
        let mut rng = Rng::new(seed);
        let t = cfg.raster_config().tile;
        let (mut sent, mut tiles, mut edge, mut reach) = (0, 0, 0, 0);
        while sent < total || edge == 0 {
            core.set_timing(TIMINGS[tiles % TIMINGS.len()]);
            let tile = [rng.below(40) as u32, rng.below(40) as u32];
            let mut size = [(tile[0] + 1 + rng.below(3) as u32) * t, (tile[1] + 1 + rng.below(3) as u32) * t];
            if rng.percent(25) {
                size = [
                    tile[0] * t + 1 + rng.below(t as u64) as u32,
                    tile[1] * t + 1 + rng.below(t as u64) as u32,
                ];
                edge += 1;
            }
            let n = rng.below(max_len) as usize;
            let case = random_case(&mut rng, cfg, tile, size, n, 5);
            reach += check_case(core, cfg, &case).1;
            sent += n;
            tiles += 1;
        }
        println!("{name}: {sent} Gaussians in {tiles} tiles ({edge} edge tiles) checked");
        assert!(reach > 0, "the random depth keys leave the written-back tables out of order");
    }

    #[test]
    fn raster_core_directed_cases() {
        let name = "raster_core_directed_cases";
        for_each_seed(name, |seed| {
            let cfg = neo_tb::config();
            let mut core = RasterCore::new(&cfg, seed, MemTiming::IDEAL);
            maybe_trace(&mut core.dut, name);
            directed(&mut core, &cfg, TIMINGS.len());
        });
    }

    /// The directed cases, each under `timings` of the memory timings (all of them: every case
    /// under every timing; fewer: case `k` under timings `k, k + 1, ...`).
    fn directed<M: Clocked>(core: &mut RasterCore<M>, cfg: &EngineConfig, timings: usize) {
        let name = "raster_core_directed_cases";
        let (fmt, rc) = (cfg.feature_format(), cfg.raster_config());
        let t = [5, 3];
        let size = [640, 480];
        let c = at(t, &rc, 31.5, 30.0);
        let mut cases: Vec<(&str, TileCase)> = vec![
            ("empty table", case_of(t, size, &[])),
            ("one entry", case_of(t, size, &[g(c, 9.0, 5.0, 0.4, 0.8, [1.0, 0.5, 0.25])])),
            (
                "centred outside the tile",
                case_of(t, size, &[g(at(t, &rc, -6.0, 12.0), 5.0, 3.0, 0.3, 0.9, [1.0; 3])]),
            ),
            ("screen-filling", case_of(t, size, &[g(c, 3000.0, 2500.0, 0.2, 0.5, [0.2, 0.9, 0.4])])),
            ("needle", case_of(t, size, &[g(c, 40.0, 0.3, 0.7, 0.9, [1.0, 1.0, 0.0])])),
        ];
        // Opaque stack: T of every pixel falls below 1e-4 (golden terminates every subtile).
        let stack: Vec<_> = (0..40)
            .map(|i| g(at(t, &rc, 30.0 + i as f64, 33.0), 200.0, 180.0, 0.1, 0.99, [0.9, 0.1, 0.3]))
            .collect();
        let opaque = case_of(t, size, &stack);
        let feats: Vec<_> = opaque.table.iter().map(|e| opaque.features[&e.id]).collect();
        let r = raster_tile(&feats, &fmt, t[0], t[1], size[0], size[1], &rc);
        assert!(r.work.iter().all(|w| w.terminated), "the opaque stack terminates every subtile");
        cases.push(("opaque stack", opaque));
        // Degenerate conics: non-positive-definite and zero mantissas.
        let mut d1 = g(c, 6.0, 6.0, 0.0, 0.8, [1.0; 3]);
        // b^2 > a c with every field inside its width (b has one more bit than a, c).
        d1.conic.b = d1.conic.a / 2;
        d1.conic.a /= 4;
        d1.conic.c /= 4;
        assert!((d1.conic.b as i64).pow(2) > d1.conic.a as i64 * d1.conic.c as i64);
        let mut d2 = g(at(t, &rc, 10.0, 50.0), 6.0, 6.0, 0.0, 0.8, [0.5; 3]);
        d2.conic.a = 0;
        d2.conic.b = 0;
        d2.conic.c = 0;
        cases.push(("non-positive-definite conic", case_of(t, size, &[d1])));
        cases.push(("zero conic", case_of(t, size, &[d2])));
        cases.push(("degenerate conics", case_of(t, size, &[d1, d2, g(c, 4.0, 4.0, 0.0, 0.7, [0.3; 3])])));
        // Alpha exactly 1/255 at a tile pixel (found with golden pixel_alpha).
        let (px, py) = ((t[0] * rc.tile) as i64 + 20, (t[1] * rc.tile) as i64 + 41);
        let exact = gaussian_with_alpha(&fmt, &rc, px, py, rc.blend.min_alpha_raw())
            .expect("a Gaussian with alpha exactly 1/255");
        let one = case_of(t, size, &[exact]);
        let k = ((py - (t[1] * rc.tile) as i64) * rc.tile as i64 + px - (t[0] * rc.tile) as i64) as usize;
        assert_ne!(golden(&one, cfg).pixels[k], [0; 3], "alpha 1/255 is blended");
        cases.push(("alpha exactly 1/255", one));
        // Culled Gaussians in the table (no feature entry): valid cleared, key kept.
        let mut culled = case_of(
            t,
            size,
            &[g(c, 9.0, 9.0, 0.0, 0.8, [1.0; 3]), g(c, 3.0, 3.0, 0.0, 0.8, [0.0, 1.0, 0.0])],
        );
        culled.features.remove(&culled.table[0].id);
        cases.push(("culled entry", culled));
        // Edge tile: partly outside the image; a tile far from the origin.
        let e = [3, 2];
        cases.push((
            "edge tile",
            case_of(
                e,
                [3 * 64 + 13, 2 * 64 + 40],
                &[g(at(e, &rc, 20.0, 20.0), 30.0, 30.0, 0.0, 0.8, [1.0; 3])],
            ),
        ));
        let far = [1000, 999];
        cases.push((
            "far tile",
            case_of(far, [64_000, 64_000], &[g(at(far, &rc, 20.0, 50.0), 12.0, 30.0, 1.0, 0.8, [1.0; 3])]),
        ));
        for (k, (label, case)) in cases.iter().enumerate() {
            for i in (k..k + timings).map(|i| i % TIMINGS.len()) {
                core.set_timing(TIMINGS[i]);
                let (cycles, _) = check_case(core, cfg, case);
                println!("{name}: {label} (memory {i}): {cycles} cycles");
            }
        }
    }

    #[test]
    fn raster_core_tables_longer_than_the_feature_buffer() {
        let name = "raster_core_tables_longer_than_the_feature_buffer";
        for_each_seed(name, |seed| {
            let cfg = neo_tb::config();
            let mut core = RasterCore::new(&cfg, seed, MemTiming::IDEAL);
            maybe_trace(&mut core.dut, name);
            longer_tables(&mut core, &cfg, seed);
        });
    }

    /// Tables one entry, 37 entries and a bank and 5 entries longer than a bank of the feature
    /// buffer, and (with more than two banks) one entry longer than every bank together.
    fn longer_tables<M: Clocked>(core: &mut RasterCore<M>, cfg: &EngineConfig, seed: u64) {
        let name = "raster_core_tables_longer_than_the_feature_buffer";
        let (f, b) = (cfg.raster_feature_buffer, cfg.raster_feature_banks);
        let mut rng = Rng::new(seed);
        let mut lengths = vec![f + 1, f + 37, 2 * f + 5];
        if b * f + 1 > 2 * f + 5 {
            lengths.push(b * f + 1);
        }
        for (i, n) in lengths.into_iter().enumerate() {
            core.set_timing(TIMINGS[i % TIMINGS.len()]);
            let case = random_case(&mut rng, cfg, [7, 9], [1024, 1024], n, 3);
            let (cycles, _) = check_case(core, cfg, &case);
            println!("{name}: {n} entries (buffer {b} x {f}): {cycles} cycles");
        }
    }

    /// The same benches (random tiles, fewer and shorter; the directed cases, each under one
    /// or two memory timings; tables longer than the feature buffer) on `neo_raster_core`
    /// generated for each of [`neo_tb::configs::raster_core`].
    #[test]
    fn raster_core_in_other_configurations() {
        neo_tb::configs::run_in_other_configurations(
            "raster_core_in_other_configurations",
            neo_tb::configs::raster_core(),
            |cfg| RasterCore::build(cfg, 0, MemTiming::IDEAL),
            |core| &mut core.dut,
            |core, cfg, seed| {
                core.reseed(seed);
                random_tiles(core, cfg, seed, 300, 48);
                directed(core, cfg, 1);
                longer_tables(core, cfg, seed);
            },
        );
    }

    /// The cycle model's cost of a reorder window against the RTL's: the default core with a
    /// 64-entry window on the raster-core grid of `reports/latency.json` (ideal memory), for
    /// tables of one to eight segments where the walk or the SCUs set the pace (4 and 16 subtile
    /// bits per Gaussian). The RTL's cost is its cycles less those of the same point in the
    /// report (the core without the window); the model's, `grid_point_cycles` with the window
    /// less without (docs/cycle-model.md, "Reorder window"): within 8 cycles or 5%. Measured
    /// 2026-12-07: 16 to 322 cycles more, the model 0 to 3 short.
    #[test]
    fn the_cycle_model_times_a_reorder_window_as_the_rtl_takes_it() {
        let name = "the_cycle_model_times_a_reorder_window_as_the_rtl_takes_it";
        if neo_tb::configs::excluded_from_coverage(name) {
            return;
        }
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../reports/latency.json");
        let report =
            neo_golden::formats::latency::LatencyReport::from_file(&path).expect("reports/latency.json");
        let lat = neo_sim::latency::Latency::from_file(&path).expect("reports/latency.json");
        let plain_core = report.raster.as_ref().and_then(|r| r.core.as_ref()).expect("raster.core");
        let subtiles = report.raster.as_ref().and_then(|r| r.itu).expect("raster.itu").subtiles_per_job;
        let w = 64;
        let cfg = EngineConfig { raster_window: w, ..lat.config.clone() };
        let f = cfg.raster_feature_buffer as u64;
        let mut core = RasterCore::build(&cfg, 7, MemTiming::IDEAL).unwrap_or_else(|e| panic!("{name}: {e}"));
        // The report's table lengths but the empty one, at the bits where the walk or SCUs lead.
        let lengths = &neo_tb::latency::raster_grid_lengths(f)[1..];
        let windowed = neo_tb::raster::measure_grid_on(&mut core, &cfg, lengths, &[4, 16]);
        let with_window = neo_sim::config::RasterTiming { window: w as u64, ..lat.raster.clone() };
        for q in &windowed {
            let p = plain_core
                .grid
                .iter()
                .find(|p| (p.entries, p.bits_per_gaussian) == (q.entries, q.bits_per_gaussian))
                .unwrap_or_else(|| {
                    panic!(
                        "{}: no point of {} entries, {} bits",
                        path.display(),
                        q.entries,
                        q.bits_per_gaussian
                    )
                });
            let rtl = q.cycles as f64 - p.cycles as f64;
            let model = neo_sim::arch::grid_point_cycles(plain_core, p, subtiles, &with_window)
                - neo_sim::arch::grid_point_cycles(plain_core, p, subtiles, &lat.raster);
            println!("{name}: {} entries, {} bits: the window costs the RTL {rtl:+.0}, the model {model:+.0} cycles", q.entries, q.bits_per_gaussian);
            assert!(rtl > 0.0, "{name}: a window costs cycles ({} entries)", q.entries);
            assert!(
                (model - rtl).abs() <= (0.05 * rtl).max(8.0),
                "{name}: {} entries, {} bits: the model's window costs {model:+.0} cycles, the RTL's {rtl:+.0}",
                q.entries,
                q.bits_per_gaussian
            );
        }
    }

    /// The same benches on a core with a reorder window ([`neo_tb::configs::raster_window`]: 16
    /// entries over banks of 4): the tile blended, and its table written back, in the order the
    /// window emits (golden `raster::window`). The random tables' current keys are random, so the
    /// window reorders every one longer than a few entries.
    #[test]
    fn raster_core_with_a_reorder_window() {
        let name = "raster_core_with_a_reorder_window";
        if neo_tb::configs::excluded_from_coverage(name) {
            return;
        }
        let cfg = neo_tb::configs::raster_window();
        for_each_seed(name, |seed| {
            let mut core =
                RasterCore::build(&cfg, seed, MemTiming::IDEAL).unwrap_or_else(|e| panic!("{name}: {e}"));
            maybe_trace(&mut core.dut, name);
            let mut rng = Rng::new(seed);
            let case = random_case(&mut rng, &cfg, [2, 3], [640, 480], 40, 5);
            assert_ne!(
                window_order_of(&case, cfg.raster_window),
                case.table,
                "the window reorders a random table"
            );
            random_tiles(&mut core, &cfg, seed, 600, 80);
            directed(&mut core, &cfg, 1);
            longer_tables(&mut core, &cfg, seed);
        });
    }

    #[test]
    fn raster_core_biker_tiles_of_three_frames() {
        let name = "raster_core_biker_tiles_of_three_frames";
        let Some(path) = shared_file_for_test(name, "scenes/biker.ply") else {
            return;
        };
        // The 9 tiles (golden pipeline: the slow part) are split over the seeds: tile k runs
        // behind seed k mod n (every tile behind NEO_SEED when it is set).
        let seeds = SeedSplit::new(name);
        let cfg = neo_tb::config();
        let mut checked = 0;
        for (k, tile) in neo_tb::raster::biker_tiles(&path, 256, 3, 3).into_iter().enumerate() {
            let seed = seeds.seed(k);
            let mut core = RasterCore::new(&cfg, seed, TIMINGS[k % TIMINGS.len()]);
            maybe_trace(&mut core.dut, name);
            let cycles = core.run(&tile.case, &tile.want).cycles;
            println!(
                "{name}: frame {} tile {:?} (seed 0x{seed:016x}): {} entries, {} set subtile bits, {cycles} cycles",
                tile.frame,
                tile.case.tile,
                tile.case.table.len(),
                tile.set_bits
            );
            checked += 1;
        }
        assert!(checked >= 9, "{checked} tiles");
        let _ = (source::robust_bounds, trajectory::parse_trajectory);
    }
}
