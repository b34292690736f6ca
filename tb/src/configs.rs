//! The engine configurations the ITU, SCU and raster-core benches cosimulate besides the one
//! this crate was built with ([`crate::config`], the default), chosen at the awkward ends of the
//! fields that shape each unit (docs/verification.md "Configurations"), and their models, built
//! at run time ([`DynModel`]) and cached by content like every model.
//!
//! The benches run the same stimulus, golden model and checkers on them as on the default, with
//! fewer vectors (the tests `*_in_other_configurations`).

use crate::dynmodel::DynModel;
use neo_gen::EngineConfig;

/// A configuration cosimulated for one unit: a short name (printed by the benches), what makes
/// it awkward, and the configuration.
#[derive(Clone, Debug)]
pub struct UnitConfig {
    /// Short name, e.g. `itu-4px-tile`.
    pub name: &'static str,
    /// What it exercises.
    pub why: &'static str,
    /// The configuration (valid: [`EngineConfig::validate`]).
    pub cfg: EngineConfig,
}

/// The ITU's configurations: its shape is the tile and subtile sides (the bitmap's width, the
/// subtile steps and half-size), `tile_bits` and `itu_tag_bits`.
pub fn itu() -> Vec<UnitConfig> {
    let d = EngineConfig::default();
    vec![
        UnitConfig {
            name: "itu-smallest",
            why: "4-pixel tiles of 2x2 subtiles of 2 pixels (a 4-bit bitmap, the smallest subtile), 1-bit tile indices and tag",
            cfg: EngineConfig {
                tile: 4,
                subtile: 2,
                tile_bits: 1,
                itu_tag_bits: 1,
                // What the rest of the engine needs with 2x2 subtiles of 4 pixels.
                scu_lanes: 4,
                raster_scus: 2,
                ..d.clone()
            },
        },
        UnitConfig {
            name: "itu-largest",
            why: "256-pixel tiles of 8x8 subtiles of 32 pixels (the largest), 16-bit tile indices, 64-bit tag",
            cfg: EngineConfig { tile: 256, subtile: 32, tile_bits: 16, itu_tag_bits: 64, ..d },
        },
    ]
}

/// The SCU's configurations: its shape is `scu_lanes` (the passes per Gaussian) and the state
/// slots of interleaved subtiles (`subtiles / raster_scus`).
pub fn scu() -> Vec<UnitConfig> {
    let d = EngineConfig::default();
    vec![
        UnitConfig {
            name: "scu-2-lanes",
            why: "the fewest lanes (2: 32 passes per Gaussian) and the fewest state slots (2, with 32 SCUs)",
            cfg: EngineConfig { scu_lanes: 2, raster_scus: 32, ..d.clone() },
        },
        UnitConfig {
            name: "scu-64-lanes",
            why: "the most lanes (64: one pass per Gaussian) and the most state slots (64, with one SCU)",
            cfg: EngineConfig { scu_lanes: 64, raster_scus: 1, ..d },
        },
    ]
}

/// The raster core's configurations: its shape is the ITUs, the SCUs and their lanes, and the
/// feature buffer (entries per bank, banks). Not 32 SCUs: that core verilates to about 100 MB of
/// C++ (10 minutes of compiling); the SCU's side of it, 2 state slots, is in [`scu`].
pub fn raster_core() -> Vec<UnitConfig> {
    let d = EngineConfig::default();
    vec![
        UnitConfig {
            name: "raster-smallest",
            why: "one ITU, one SCU of 2 lanes (64 subtile groups), the smallest buffer (2 banks of 4 entries, below a 16-entry burst)",
            cfg: EngineConfig {
                raster_itus: 1,
                raster_scus: 1,
                scu_lanes: 2,
                raster_feature_buffer: 4,
                raster_feature_banks: 2,
                ..d.clone()
            },
        },
        UnitConfig {
            name: "raster-most-itus",
            why: "16 ITUs (quads of 16 lanes) over 2 SCUs of 2 lanes (32 subtile groups), 8 banks of the smallest buffer 16 ITUs allow (32 entries)",
            cfg: EngineConfig {
                raster_itus: 16,
                raster_scus: 2,
                scu_lanes: 2,
                raster_feature_buffer: 32,
                raster_feature_banks: 8,
                ..d.clone()
            },
        },
        UnitConfig {
            name: "raster-window-4",
            why: "the smallest reorder window (4 entries: 3 cells) on 4 ITUs and 2 SCUs, banks of 8 entries",
            cfg: EngineConfig {
                raster_scus: 2,
                scu_lanes: 2,
                raster_feature_buffer: 8,
                raster_window: 4,
                ..d
            },
        },
    ]
}

/// The raster core with a reorder window that the window benches run on (and whose Verilog
/// `scripts/mutate-check`'s `win:` mutants mutate): the smallest core (one ITU, one SCU of 2
/// lanes, 2 banks of 4 entries) with a window of 16, four segments, twice what the banks hold
/// (`tb/raster_window.json`).
pub fn raster_window() -> EngineConfig {
    serde_json::from_str(include_str!("../raster_window.json"))
        .expect("tb/raster_window.json is an engine configuration")
}

/// The Sorting Core's and its sequencer's configurations with a wide DPS chunk: the buffer
/// (`chunk * dps_wide`) and the sequencer's DPS chunks.
pub fn sort_wide() -> Vec<UnitConfig> {
    let d = EngineConfig::default();
    vec![
        UnitConfig {
            name: "sort-wide-4",
            why: "the adaptive_wide case's engine: a wide chunk of 4 x 256 (1024-entry buffers)",
            cfg: EngineConfig { dps_wide: 4, ..d.clone() },
        },
        UnitConfig {
            name: "sort-wide-64",
            why: "the widest multiple: 64 x a 32-entry chunk (2048-entry buffers, 7 more merge passes)",
            cfg: EngineConfig { chunk: 32, dps_wide: 64, ..d },
        },
    ]
}

/// True in a coverage run (`NEO_COVERAGE=1`, `scripts/coverage`), after printing why test
/// `test` does not run there: coverage counts the configuration the crate was built with, and
/// another configuration's Verilog has other lines under the same module names, which would
/// merge into that count.
pub fn excluded_from_coverage(test: &str) -> bool {
    let excluded = crate::coverage::at_run_time();
    if excluded {
        println!(
            "{test}: not run with NEO_COVERAGE=1 (coverage counts the built configuration only; \
             other configurations' modules have the same names and other lines)"
        );
    }
    excluded
}

/// The body of the benches' `*_in_other_configurations` tests: for each of `variants`, builds a
/// bench with `build` (a failure panics naming the variant), traces its model (`dut`) when
/// `WAVES` asks for waves, and runs `run` on it behind every seed of `test`
/// ([`crate::rng::for_each_seed`]), printing the variant and why it is awkward. Nothing runs in
/// a coverage run ([`excluded_from_coverage`]).
pub fn run_in_other_configurations<B>(
    test: &str,
    variants: Vec<UnitConfig>,
    build: impl Fn(&EngineConfig) -> Result<B, String>,
    dut: impl Fn(&mut B) -> &mut DynModel,
    mut run: impl FnMut(&mut B, &EngineConfig, u64),
) {
    if excluded_from_coverage(test) {
        return;
    }
    for u in variants {
        let mut bench = build(&u.cfg).unwrap_or_else(|e| panic!("{test}: {}: {e}", u.name));
        crate::waves::maybe_trace(dut(&mut bench), &format!("{test}_{}", u.name));
        crate::rng::for_each_seed(&format!("{test} {}", u.name), |seed| {
            println!("{test}: {} ({})", u.name, u.why);
            run(&mut bench, &u.cfg, seed);
        });
    }
}

/// Builds (or loads from the cache) top `top` of `cfg`, traced in the format `WAVES` asks for
/// (untraced without it: about half the C++), its per-cycle code compiled for build time
/// ([`DynModel::build_for_short_runs`]: these benches run seconds).
pub fn build(cfg: &EngineConfig, top: &str) -> Result<DynModel, String> {
    cfg.validate().map_err(|e| e.to_string())?;
    let (files, vlt) = crate::dynmodel::generated_files(cfg, top)?;
    let iface = crate::dynmodel::generated_interface(cfg, top)?;
    let format = crate::waves::try_requested_format()?;
    let (model, info) = DynModel::build_for_short_runs(&iface, &files, Some(&vlt), format)?;
    if !info.cached {
        println!("built {top} for {:016x} in {:.1} s: {}", cfg.hash(), info.seconds, info.log);
    }
    Ok(model)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every configuration is valid, differs from the default in a field that shapes its unit,
    /// and the names are distinct.
    #[test]
    fn the_configurations_are_valid_and_not_the_default() {
        let all: Vec<UnitConfig> = [itu(), scu(), raster_core(), sort_wide()].concat();
        for u in &all {
            u.cfg.validate().unwrap_or_else(|e| panic!("{}: {e}", u.name));
            assert_ne!(u.cfg, EngineConfig::default(), "{}", u.name);
        }
        let mut names: Vec<&str> = all.iter().map(|u| u.name).collect();
        names.sort_unstable();
        names.dedup();
        assert_eq!(names.len(), all.len());
        let d = EngineConfig::default();
        for u in itu() {
            let c = &u.cfg;
            assert!(
                (c.tile, c.subtile, c.tile_bits, c.itu_tag_bits)
                    != (d.tile, d.subtile, d.tile_bits, d.itu_tag_bits)
            );
        }
        for u in scu() {
            assert_ne!(u.cfg.scu_lanes, d.scu_lanes, "{}", u.name);
        }
        for u in raster_core() {
            let c = &u.cfg;
            assert!(c.raster_itus != d.raster_itus || c.raster_window != d.raster_window, "{}", u.name);
        }
        let w = raster_window();
        w.validate().unwrap();
        assert!(w.raster_window > 1 && w.raster_window > 2 * w.raster_feature_buffer, "{w:?}");
        for u in sort_wide() {
            assert!(u.cfg.dps_wide > 1, "{}", u.name);
        }
    }
}
