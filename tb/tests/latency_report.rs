//! `reports/latency.json` is regenerated from cosimulation and must match the checked-in file
//! (the cycle model reads it). `NEO_UPDATE_REPORTS=1` rewrites it instead. With `NEO_HDL_DIR`
//! the comparison still runs, so `scripts/mutate-check` sees timing-only bugs.

#[cfg(not(neo_has_verilator))]
#[test]
fn latency_report_skipped_without_verilator() {
    // Prints SKIP (or fails when CI is set); the models must really be absent in this build.
    assert!(!neo_tb::require_models(
        "latency_report_skipped_without_verilator: reports/latency.json was not checked"
    ));
}

#[cfg(neo_has_verilator)]
mod cosim {
    use std::path::PathBuf;

    /// `NEO_LATENCY_REPORT`, else the project's report (of the default configuration only: a
    /// build for another `NEO_CONFIG` has no checked-in report to compare with).
    fn report_path() -> Option<PathBuf> {
        if let Some(p) = std::env::var_os("NEO_LATENCY_REPORT").filter(|p| !p.is_empty()) {
            return Some(PathBuf::from(p));
        }
        if neo_tb::config() != neo_gen::EngineConfig::default() {
            println!("SKIP: built for a non-default NEO_CONFIG; set NEO_LATENCY_REPORT=FILE to write or compare its report");
            return None;
        }
        Some(PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../reports/latency.json"))
    }

    #[test]
    fn measured_unit_latencies_match_the_generator() {
        let cfg = neo_tb::config();
        let (latency, ii, _, _) = neo_tb::latency::bsu_latency(&cfg);
        assert_eq!(latency, cfg.bsu_latency() as u64, "BSU latency is ceil(depth / register_every)");
        assert_eq!(ii, 1, "the BSU takes a vector every cycle");
        let (_, msu_ii, _, entries, _) = neo_tb::latency::msu_latency(&cfg, 64);
        assert_eq!(entries, 256, "two merges of 2 x 64 entries");
        assert_eq!(msu_ii, 1, "the MSU+ emits an entry every cycle at full rate");
    }

    /// How a stale report is brought up to date.
    const REGENERATE: &str =
        "regenerate it with\n  NEO_UPDATE_REPORTS=1 cargo test -p neo-tb --release --test latency_report";

    /// The Sorting Core's cycles alone against the checked-in report (seconds, where the whole
    /// report takes minutes): `scripts/mutate-check`'s timing-only mutants of the core run this.
    #[test]
    fn the_sort_core_timing_is_current() {
        let Some(path) = report_path() else { return };
        let current =
            neo_golden::formats::latency::LatencyReport::from_file(&path).unwrap_or_else(|e| panic!("{e}"));
        let (overhead, sort_core) = neo_tb::latency::sort_core_timing(&neo_tb::config());
        assert_eq!(
            overhead,
            current.units.neo_sort_core.command_overhead,
            "{}: units.neo_sort_core.command_overhead is out of date with the RTL; {REGENERATE}",
            path.display()
        );
        assert!(
            sort_core == current.sort_core,
            "{}: sort_core is out of date with the RTL (measured: {sort_core:?}); {REGENERATE}",
            path.display()
        );
    }

    #[test]
    fn latency_report_is_current() {
        let Some(path) = report_path() else { return };
        let text = neo_tb::latency::report_text(&neo_tb::config());
        let tmp = tempfile::NamedTempFile::new().unwrap();
        std::fs::write(tmp.path(), &text).unwrap();
        let update = std::env::var("NEO_UPDATE_REPORTS").is_ok_and(|v| !v.is_empty() && v != "0");
        if update {
            std::fs::create_dir_all(path.parent().unwrap()).unwrap();
            std::fs::write(&path, &text).unwrap();
            println!("wrote {}", path.display());
            return;
        }
        let current = std::fs::read_to_string(&path).unwrap_or_default();
        assert!(
            current == text,
            "{} is out of date with the RTL (fresh measurement in {}); {REGENERATE}",
            path.display(),
            tmp.into_temp_path().keep().unwrap().display()
        );
    }
}
