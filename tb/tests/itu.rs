//! `neo_itu` against golden `subtile_bitmap`: >= 10k random Gaussians (raw fields, octagons near
//! the tile, quantised Gaussians) under random stalls and backpressure, the directed hard cases,
//! and the pipeline's latency and II.

#[cfg(not(neo_has_verilator))]
#[test]
fn itu_skipped_without_verilator() {
    // Prints SKIP (or fails when CI is set); the models must really be absent in this build.
    assert!(!neo_tb::require_models("itu_skipped_without_verilator: ITU cosimulation did not run"));
}

#[cfg(neo_has_verilator)]
mod cosim {
    use neo_gen::units::itu::LATENCY;
    use neo_gen::EngineConfig;
    use neo_tb::dut::Clocked;
    use neo_tb::itu::{directed_jobs, full_bitmap, measure_timing, random_jobs, run_checked, ItuJob};
    use neo_tb::models::NeoItu;
    use neo_tb::rng::{for_each_seed, Rng};
    use neo_tb::waves::maybe_trace;

    fn vectors() -> usize {
        std::env::var("NEO_TB_VECTORS").ok().and_then(|v| v.parse().ok()).unwrap_or(20_000)
    }

    /// At least `vectors` random jobs (and every stall/backpressure mix once) through `dut`;
    /// returns the jobs checked.
    fn random_gaussians<M: Clocked>(dut: &mut M, cfg: &EngineConfig, seed: u64, vectors: usize) -> usize {
        let name = "itu_random_gaussians_under_stalls_and_backpressure";
        let mut rng = Rng::new(seed);
        let full = full_bitmap(cfg);
        let mixes = [(0, 100), (30, 70), (60, 100), (0, 30), (50, 50)];
        let (mut jobs, mut hits, mut bits, mut partial) = (0, 0, 0u64, 0);
        let mut k = 0;
        while jobs < vectors || k < mixes.len() {
            let (stall, ready) = mixes[k % mixes.len()];
            let batch = random_jobs(cfg, &mut rng, (vectors / mixes.len()).clamp(1, 1000));
            partial += batch
                .iter()
                .filter(|j| {
                    let b = j.expected(cfg);
                    b != 0 && b != full
                })
                .count();
            let run = run_checked(dut, cfg, seed.wrapping_add(k as u64), &batch, stall, ready);
            jobs += run.jobs;
            hits += run.hits;
            bits += run.set_bits;
            k += 1;
        }
        println!(
            "{name}: {jobs} jobs checked, {hits} with a non-empty bitmap, {partial} partial, {bits} set bits"
        );
        // The stimulus must exercise partial bitmaps, not just all-or-nothing: a fifth of the jobs
        // in the default 8 x 8 subtiles. With n x n, an octagon's edge falls in a partial
        // position over (n - 1) / n of the tile's side instead of 7 / 8 (the stimulus scales with
        // the tile), so the bar scales by that ratio.
        let n = cfg.raster_config().subtiles_per_side() as usize;
        assert!(partial * 5 * 7 * n >= jobs * 8 * (n - 1), "only {partial} of {jobs} bitmaps are partial");
        assert!(hits * 4 <= jobs * 3, "{hits} of {jobs} hit: too few misses");
        jobs
    }

    #[test]
    fn itu_random_gaussians_under_stalls_and_backpressure() {
        let name = "itu_random_gaussians_under_stalls_and_backpressure";
        for_each_seed(name, |seed| {
            let mut dut = NeoItu::new();
            maybe_trace(&mut dut, name);
            let jobs = random_gaussians(&mut dut, &neo_tb::config(), seed, vectors());
            assert!(jobs >= 10_000);
        });
    }

    /// The directed cases one by one and all together under stalls.
    fn directed<M: Clocked>(dut: &mut M, cfg: &EngineConfig, seed: u64) {
        let cases = directed_jobs(cfg);
        for (k, (case, job)) in cases.iter().enumerate() {
            println!("case {k}: {case}: expected 0x{:016x}", job.expected(cfg));
            run_checked(dut, cfg, seed ^ k as u64, std::slice::from_ref(job), 0, 100);
        }
        let all: Vec<ItuJob> = cases.iter().map(|(_, j)| *j).collect();
        let run = run_checked(dut, cfg, seed, &all, 40, 60);
        assert_eq!(run.jobs, all.len());
        // The border pairs must really sit on the border: touching and one LSB short differ.
        let bm =
            |n: &str| cases.iter().find(|(c, _)| c.starts_with(n)).map(|(_, j)| j.expected(cfg)).unwrap();
        for axis in ["x", "y", "uv"] {
            for t in ["t0 base", "t1 base"] {
                let b = format!("{axis} border {t}");
                let at = cases.iter().find(|(c, _)| c.starts_with(&b) && c.ends_with(" r0")).unwrap();
                let short = cases.iter().find(|(c, _)| c.starts_with(&b) && c.ends_with(" r1")).unwrap();
                assert_ne!(at.1.expected(cfg), short.1.expected(cfg), "{} / {}", at.0, short.0);
            }
        }
        assert_ne!(bm("outside left reaching"), bm("outside left short"));
        assert_eq!(bm("all unbounded"), full_bitmap(cfg));
        // An unbounded extent is told from the largest finite one on every axis.
        for k in 0..4 {
            let far = |n: &str| cases.iter().find(|(c, _)| *c == format!("{n} far on axis {k}"));
            if let (Some(unb), Some(bounded)) = (far("unbounded"), far("bounded")) {
                assert_ne!(unb.1.expected(cfg), 0, "{}", unb.0);
                assert_eq!(bounded.1.expected(cfg), 0, "{}", bounded.0);
            }
        }
    }

    #[test]
    fn itu_directed_cases() {
        let name = "itu_directed_cases";
        for_each_seed(name, |seed| {
            let mut dut = NeoItu::new();
            maybe_trace(&mut dut, name);
            directed(&mut dut, &neo_tb::config(), seed);
        });
    }

    fn latency_and_ii<M: Clocked>(dut: &mut M, cfg: &EngineConfig, seed: u64) {
        let t = measure_timing(dut, cfg, seed, 500);
        println!("itu_latency_and_ii: latency {} cycles, II {:.3}", t.latency, t.ii);
        assert_eq!(t.latency, LATENCY as u64);
        assert!((t.ii - 1.0).abs() < 1e-9, "II {}", t.ii);
    }

    #[test]
    fn itu_latency_and_ii() {
        let name = "itu_latency_and_ii";
        for_each_seed(name, |seed| latency_and_ii(&mut NeoItu::new(), &neo_tb::config(), seed));
    }

    /// The same benches (random jobs, fewer of them; the directed cases; latency and II) on
    /// `neo_itu` generated for each of [`neo_tb::configs::itu`].
    #[test]
    fn itu_in_other_configurations() {
        neo_tb::configs::run_in_other_configurations(
            "itu_in_other_configurations",
            neo_tb::configs::itu(),
            |cfg| neo_tb::configs::build(cfg, "neo_itu"),
            |dut| dut,
            |dut, cfg, seed| {
                random_gaussians(dut, cfg, seed, 10_000);
                directed(dut, cfg, seed);
                latency_and_ii(dut, cfg, seed);
            },
        );
    }

    #[test]
    fn itu_random_seeds_replay() {
        // The same seed gives the same stimulus (NEO_SEED replays a failure).
        let cfg = neo_tb::config();
        let a = random_jobs(&cfg, &mut Rng::new(42), 50);
        let b = random_jobs(&cfg, &mut Rng::new(42), 50);
        assert_eq!(a, b);
        assert_ne!(a, random_jobs(&cfg, &mut Rng::new(43), 50));
    }
}
