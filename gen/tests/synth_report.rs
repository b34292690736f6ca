//! `reports/synth.json` is the synthesis of the Verilog the generator emits now: the same tops
//! (`report::stats_tops`), each entry's Verilog hash the hash of that top's files today, for the
//! default configuration. A change to a synthesized top's Verilog (or a renamed, added or removed
//! top) fails this test until `neo gen --stats --all-topologies` is run again; that run reuses
//! every entry whose hash still matches, so only the changed tops are synthesized. Checking is
//! cheap (no tool runs: the files are generated and hashed, in under a second).

use neo_gen::report::{stats_tops, verilog_hash, SynthReport, YOSYS_COMMAND};
use neo_gen::EngineConfig;
use std::path::PathBuf;

fn report() -> SynthReport {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../reports/synth.json");
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    serde_json::from_str(&text).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

#[test]
fn the_synthesis_report_is_of_the_current_verilog() {
    let r = report();
    let cfg = EngineConfig::default();
    let rerun =
        "run `neo gen --stats --all-topologies` (unchanged tops are reused) and commit reports/synth.json";
    assert_eq!(r.config, cfg, "reports/synth.json is not of the default configuration: {rerun}");
    assert_eq!(r.command, YOSYS_COMMAND, "reports/synth.json used another Yosys flow: {rerun}");
    let units: Vec<&str> = r.units.iter().map(|u| u.unit.as_str()).collect();
    assert_eq!(
        units,
        stats_tops(&cfg),
        "reports/synth.json reports other tops than neo gen --stats: {rerun}"
    );
    let stale: Vec<String> = r
        .units
        .iter()
        .filter(|u| u.verilog_hash != verilog_hash(&cfg, &u.unit))
        .map(|u| u.unit.clone())
        .collect();
    assert!(stale.is_empty(), "reports/synth.json is stale for {stale:?} (their Verilog changed): {rerun}");
    assert!(!r.bsu_topologies.is_empty(), "reports/synth.json has no BSU topologies: {rerun}");
}

/// The report's figures hold together: no unit has a latch (its own synthesis, and for a
/// hierarchical top its boxed units), and the engine's total counts every module it instantiates,
/// the Preprocessing Engine's lanes included.
#[test]
fn the_synthesis_report_has_no_latch_and_the_whole_engine() {
    let r = report();
    let latched: Vec<&str> =
        r.units.iter().filter(|u| u.total_latches() != 0).map(|u| u.unit.as_str()).collect();
    assert!(latched.is_empty(), "latches in {latched:?}");
    let unit = |name: &str| r.units.iter().find(|u| u.unit == name).unwrap_or_else(|| panic!("no {name}"));
    let engine = unit(neo_gen::units::engine::NAME).hierarchy.as_ref().expect("the engine is hierarchical");
    for m in neo_gen::units::engine::SUBMODULES {
        assert!(engine.instances.iter().any(|i| i.0 == *m && i.1 > 0), "the engine's total leaves out {m}");
    }
    let pre = unit(neo_gen::units::pre::engine::NAME).hierarchy.as_ref().expect("hierarchical");
    let lanes = pre.instances.iter().find(|i| i.0 == neo_gen::units::pre::lane::NAME).expect("lanes");
    assert_eq!(lanes.1, EngineConfig::default().pre_units as u64);
}
