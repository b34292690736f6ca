//! `neo_engine` (run-time cosim top, not in `top_modules`): Verilator-lint clean with the
//! waivers of `hdl/lint.vlt` (the submodules that `hdl_gates.rs` lints as tops of their own, with
//! the same text, boxed: `neo_gen::units::lint_boxes`), and its own glue and its port mux
//! latch-free, for the default
//! 16 + 4 engine and the small engines the benches build (every other module of the engine is a
//! `top_modules` unit, checked by `hdl_gates.rs`; `neo gen --stats` synthesizes them all in full
//! for the default engine and reports their latches).

use neo_gen::tools::{coarse_glue_synth_stats, coarse_synth_stats, require_for_test, verilator_lint_boxed};
use neo_gen::units::engine::NAME;
use neo_gen::units::lint_boxes;
use neo_gen::{files_for, EngineConfig};
use std::path::PathBuf;

fn configs() -> Vec<(&'static str, EngineConfig)> {
    let base = EngineConfig::default();
    vec![
        ("default 16 + 4, 4 ports", base.clone()),
        (
            "2 + 1, 2 ports, 1 preprocessing lane (the CI engine)",
            EngineConfig { sort_cores: 2, raster_cores: 1, mem_channels: 2, pre_units: 1, ..base.clone() },
        ),
        (
            "2 + 1, 2 ports, 2 preprocessing lanes",
            EngineConfig { sort_cores: 2, raster_cores: 1, mem_channels: 2, pre_units: 2, ..base.clone() },
        ),
        (
            "1 + 1, 1 port, no Preprocessing Engine",
            EngineConfig { sort_cores: 1, raster_cores: 1, mem_channels: 1, pre_units: 0, ..base.clone() },
        ),
        (
            "2 + 1, 4 ports (one client a port)",
            EngineConfig { sort_cores: 2, raster_cores: 1, mem_channels: 4, ..base.clone() },
        ),
        (
            "4 + 3, 3 ports, round robin, no Preprocessing Engine",
            EngineConfig {
                sort_cores: 4,
                raster_cores: 3,
                mem_channels: 3,
                pre_units: 0,
                scheduler: neo_gen::SchedulerPolicy::RoundRobin,
                ..base
            },
        ),
    ]
}

#[test]
fn the_engine_is_lint_clean() {
    if !require_for_test("verilator", "the_engine_is_lint_clean") {
        return;
    }
    let vlt = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../hdl/lint.vlt");
    for (what, cfg) in configs() {
        let boxes = lint_boxes(&cfg, NAME);
        verilator_lint_boxed(&files_for(&cfg, NAME), NAME, Some(&vlt), &boxes)
            .unwrap_or_else(|e| panic!("{what}: {e}"));
    }
}

#[test]
fn the_engine_glue_is_latch_free() {
    if !require_for_test("yosys", "the_engine_glue_is_latch_free") {
        return;
    }
    for (what, cfg) in configs() {
        let mux = neo_gen::units::axi::mux::NAME;
        let mut boxes: Vec<&str> = neo_gen::units::engine::SUBMODULES.to_vec();
        boxes.push(mux);
        let s = coarse_glue_synth_stats(&files_for(&cfg, NAME), NAME, &boxes)
            .unwrap_or_else(|e| panic!("{what}: {e}"));
        assert_eq!(s.latches, 0, "{what}: {:?}", s.cells_by_type);
        // The glue instantiates every submodule (the black boxes are counted as cells).
        let n = |m: &str| s.cells_by_type.get(m).copied().unwrap_or(0);
        assert_eq!(n(neo_gen::units::sort_core::NAME), cfg.sort_cores as u64, "{what}");
        assert_eq!(n(neo_gen::units::raster_core::NAME), cfg.raster_cores as u64, "{what}");
        assert_eq!(n(mux), cfg.mem_channels as u64, "{what}");
        let has_pre = u64::from(cfg.has_preprocessing());
        assert_eq!(n(neo_gen::units::pre::engine::NAME), has_pre, "{what}");
        // One gate per sorting and raster core, and the Preprocessing Engine's.
        assert_eq!(
            n(neo_gen::units::clock_gate::NAME),
            (cfg.sort_cores + cfg.raster_cores) as u64 + has_pre,
            "{what}"
        );
        let m = coarse_synth_stats(&files_for(&cfg, mux), mux).unwrap_or_else(|e| panic!("{what}: {e}"));
        assert_eq!(m.latches, 0, "{what}: {mux}: {:?}", m.cells_by_type);
        if !cfg.has_preprocessing() {
            continue;
        }
        // The Preprocessing Engine's own logic: the lanes and the list writer as black boxes.
        let pre = neo_gen::units::pre::engine::NAME;
        let boxes = neo_gen::units::pre::engine::SUBMODULES;
        let p = coarse_glue_synth_stats(&files_for(&cfg, pre), pre, boxes)
            .unwrap_or_else(|e| panic!("{what}: {e}"));
        assert_eq!(p.latches, 0, "{what}: {pre}: {:?}", p.cells_by_type);
        assert_eq!(
            p.cells_by_type.get(neo_gen::units::pre::lane::NAME).copied(),
            Some(cfg.pre_units as u64),
            "{what}"
        );
    }
    // The clock gate: one falling-edge flop and an AND, no latch.
    let gate = neo_gen::units::clock_gate::NAME;
    let g =
        coarse_synth_stats(&files_for(&EngineConfig::default(), gate), gate).expect("clock gate synthesis");
    assert_eq!((g.latches, g.flip_flops), (0, 1), "{gate}: {:?}", g.cells_by_type);
}
