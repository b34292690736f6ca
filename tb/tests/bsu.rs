//! `neo_bsu` against golden `Network::apply`: random vectors under random stalls and
//! backpressure, directed corner cases, and a VCD read back for the handshake rules.

#[cfg(not(neo_has_verilator))]
#[test]
fn bsu_skipped_without_verilator() {
    // Prints SKIP (or fails when CI is set); the models must really be absent in this build.
    assert!(!neo_tb::require_models("bsu_skipped_without_verilator: BSU cosimulation did not run"));
}

#[cfg(neo_has_verilator)]
mod common;

#[cfg(neo_has_verilator)]
mod cosim {
    use super::common::{check_handshake, pre_edge_samples};
    use neo_tb::bsu::run_checked;
    use neo_tb::models::NeoBsu;
    use neo_tb::rng::{for_each_seed, seed_share, Rng};
    use neo_tb::stimulus::{directed_vectors, random_vector};
    use neo_tb::waves::{maybe_trace, WaveFormat};

    /// Random vectors in CI: at least 10k over the seeds together (override with NEO_TB_VECTORS).
    fn vector_count() -> usize {
        std::env::var("NEO_TB_VECTORS").ok().and_then(|v| v.parse().ok()).unwrap_or(10_000)
    }

    #[test]
    fn bsu_random_vectors_under_stalls_and_backpressure() {
        let name = "bsu_random_vectors_under_stalls_and_backpressure";
        for_each_seed(name, |seed| {
            let cfg = neo_tb::config();
            let mut rng = Rng::new(seed);
            let mut dut = NeoBsu::new();
            maybe_trace(&mut dut, name);
            // The vectors are split over the seeds (each seed its share: the same with NEO_SEED).
            let total = seed_share(vector_count());
            // (input stall %, output ready %) per segment; each segment starts from reset.
            let mixes = [(0, 100), (30, 100), (0, 50), (40, 60), (80, 20), (10, 90)];
            let per = total.div_ceil(mixes.len());
            let mut checked = 0;
            for (k, &(stall, ready)) in mixes.iter().enumerate() {
                let vectors: Vec<_> =
                    (0..per).map(|_| random_vector(&cfg.format(), &mut rng, cfg.bsu_width)).collect();
                let run = run_checked(&mut dut, &cfg, seed.wrapping_add(k as u64), &vectors, stall, ready);
                checked += run.vectors;
                if (stall, ready) == (0, 100) {
                    // Full rate: one vector a cycle after the pipeline fills.
                    let latency = cfg.bsu_latency() as u64;
                    assert!(
                        run.cycles <= per as u64 + latency + 8,
                        "full rate took {} cycles for {per}",
                        run.cycles
                    );
                }
            }
            assert!(checked >= total, "{checked} vectors checked, wanted {total}");
            println!("{name}: {checked} vectors checked");
        });
    }

    #[test]
    fn bsu_directed_corner_cases() {
        let name = "bsu_directed_corner_cases";
        for_each_seed(name, |seed| {
            let cfg = neo_tb::config();
            let cases = directed_vectors(&cfg.format(), cfg.bsu_width);
            let mut dut = NeoBsu::new();
            maybe_trace(&mut dut, name);
            for (k, (case, v)) in cases.iter().enumerate() {
                println!("case: {case}");
                run_checked(&mut dut, &cfg, seed ^ k as u64, std::slice::from_ref(v), 0, 100);
            }
            // All of them back to back, under stalls and backpressure.
            let all: Vec<_> = cases.iter().map(|(_, v)| v.clone()).collect();
            let run = run_checked(&mut dut, &cfg, seed, &all, 50, 50);
            assert_eq!(run.vectors, cases.len());
        });
    }

    #[test]
    fn bsu_vcd_shows_handshake_rules_and_every_transfer() {
        let name = "bsu_vcd_shows_handshake_rules_and_every_transfer";
        if neo_tb::coverage::STATIC_MODELS {
            neo_tb::skip(name, "this build's models are coverage models (NEO_COVERAGE=1): untraced");
            return;
        }
        if neo_tb::waves::MODEL_FORMAT != WaveFormat::Vcd {
            neo_tb::skip(
                name,
                "this build's models trace FST (built with WAVES=fst); the VCD read-back needs a VCD build",
            );
            return;
        }
        for_each_seed(name, |seed| {
            let cfg = neo_tb::config();
            let mut rng = Rng::new(seed);
            let dir = tempfile::tempdir().unwrap();
            let mut dut = NeoBsu::new();
            let vcd = neo_tb::waves::trace_to(&mut dut, dir.path(), "bsu", WaveFormat::Vcd);
            let vectors: Vec<_> =
                (0..300).map(|_| random_vector(&cfg.format(), &mut rng, cfg.bsu_width)).collect();
            run_checked(&mut dut, &cfg, seed, &vectors, 40, 40);
            dut.trace_close();
            let s = pre_edge_samples(
                &vcd,
                "neo_bsu",
                &["in_valid_i", "in_ready_o", "in_data_i", "out_valid_o", "out_ready_i", "out_data_o"],
            );
            assert!(s.rows.len() > 600, "expected one row per cycle, got {}", s.rows.len());
            // out_data_o is stable while out_valid_o && !out_ready_i; every vector crosses each
            // interface exactly once (no transfer without valid && ready).
            assert_eq!(check_handshake(&s, "in_valid_i", "in_ready_o", &["in_data_i"]), 300);
            assert_eq!(check_handshake(&s, "out_valid_o", "out_ready_i", &["out_data_o"]), 300);
        });
    }
}
