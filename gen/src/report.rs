//! Synthesis reports: Yosys cells and flip-flops per unit and per BSU topology
//! (`neo gen --stats`, written to `reports/synth.json`).

use crate::tools::{glue_synth_stats, synth_stats, SynthStats, ToolError};
use crate::units::{files_for, top_modules};
use neo_golden::engine::{EngineConfig, Topology};
use serde::Serialize;

/// One synthesized unit of a configuration.
#[derive(Clone, Debug, Serialize)]
pub struct UnitReport {
    /// Module name.
    pub unit: String,
    /// BSU comparator count (BSU only).
    pub comparators: Option<usize>,
    /// BSU network depth in comparator layers (BSU only).
    pub depth: Option<usize>,
    /// BSU latency in cycles (BSU only).
    pub latency: Option<usize>,
    /// Yosys statistics (for a core reported hierarchically: its own glue, see `hierarchy`).
    pub synth: SynthStats,
    /// For a core too large to synthesize flat (the raster core): its glue plus, per unit, the
    /// instance count times the unit's flat cells.
    pub hierarchy: Option<Hierarchy>,
}

/// A core reported hierarchically.
#[derive(Clone, Debug, Serialize)]
pub struct Hierarchy {
    /// Per instantiated unit: (module, instances, flat cells of one, flip-flops of one).
    pub instances: Vec<(String, u64, u64, u64)>,
    /// Glue cells (the core's own logic, black-box instances excluded).
    pub glue_cells: u64,
    /// Glue cells plus instances x unit cells.
    pub total_cells: u64,
    /// Glue flip-flops plus instances x unit flip-flops.
    pub total_flip_flops: u64,
}

/// The BSU of one topology (other parameters from the base configuration).
#[derive(Clone, Debug, Serialize)]
pub struct TopologyReport {
    /// Topology name.
    pub topology: String,
    /// Network width.
    pub bsu_width: usize,
    /// Register stage every `k` layers.
    pub register_every: usize,
    /// Comparators (golden network).
    pub comparators: usize,
    /// Layers (golden network).
    pub depth: usize,
    /// Latency in cycles.
    pub latency: usize,
    /// Yosys cells (flattened, generic gates).
    pub cells: u64,
    /// Yosys flip-flops.
    pub flip_flops: u64,
    /// Yosys latches (0).
    pub latches: u64,
}

/// Everything `neo gen --stats` measured.
#[derive(Clone, Debug, Serialize)]
pub struct SynthReport {
    /// The configuration synthesized.
    pub config: EngineConfig,
    /// The Yosys script per top (`TOP` replaced by the module name).
    pub command: String,
    /// Per-unit results, in [`top_modules`] order.
    pub units: Vec<UnitReport>,
    /// Per-topology BSU results (empty unless requested).
    pub bsu_topologies: Vec<TopologyReport>,
}

/// The Yosys flow used for every figure.
pub const YOSYS_COMMAND: &str = "yosys -q -p \"read_verilog FILES; synth -flatten -top TOP; stat -json\"";

/// Runs `jobs` on up to two threads (the build machine has two cores), keeping their order.
fn parallel<T: Send, R: Send>(jobs: Vec<T>, f: impl Fn(T) -> R + Sync) -> Vec<R> {
    let mut jobs: Vec<(usize, T)> = jobs.into_iter().enumerate().collect();
    let half = jobs.len().div_ceil(2);
    let second = jobs.split_off(half);
    let mut out: Vec<(usize, R)> = std::thread::scope(|s| {
        let f = &f;
        let h = s.spawn(move || second.into_iter().map(|(i, j)| (i, f(j))).collect::<Vec<_>>());
        let mut a: Vec<(usize, R)> = jobs.into_iter().map(|(i, j)| (i, f(j))).collect();
        a.extend(h.join().expect("synthesis thread"));
        a
    });
    out.sort_by_key(|(i, _)| *i);
    out.into_iter().map(|(_, r)| r).collect()
}

/// Tops synthesized hierarchically (a flat synthesis of 4 SCUs, ~2 M cells, takes too long):
/// (top, units kept as black boxes; their flat figures come from their own reports).
pub const HIERARCHICAL: &[(&str, &[&str])] = &[(
    crate::units::raster_core::NAME,
    &[crate::units::itu::NAME, crate::units::scu::NAME, crate::units::scu::EXP_NAME],
)];

/// Synthesizes every top of `cfg` (flat; the raster core hierarchically, see [`Hierarchy`]).
pub fn unit_reports(cfg: &EngineConfig) -> Result<Vec<UnitReport>, ToolError> {
    let net = cfg.network();
    let mut reports: Vec<UnitReport> = parallel(top_modules().to_vec(), |top| {
        let bsu = top == crate::units::bsu::NAME;
        let synth = match HIERARCHICAL.iter().find(|(t, _)| *t == top) {
            Some((_, boxes)) => glue_synth_stats(&files_for(cfg, top), top, boxes)?,
            None => synth_stats(&files_for(cfg, top), top)?,
        };
        Ok(UnitReport {
            unit: top.to_string(),
            comparators: bsu.then(|| net.comparator_count()),
            depth: bsu.then(|| net.depth()),
            latency: bsu.then(|| cfg.bsu_latency()),
            synth,
            hierarchy: None,
        })
    })
    .into_iter()
    .collect::<Result<_, ToolError>>()?;
    for (top, boxes) in HIERARCHICAL {
        let flat: Vec<(String, u64, u64)> = reports
            .iter()
            .filter(|u| boxes.contains(&u.unit.as_str()))
            .map(|u| (u.unit.clone(), u.synth.cells, u.synth.flip_flops))
            .collect();
        if let Some(core) = reports.iter_mut().find(|u| u.unit == *top) {
            let instances: Vec<(String, u64, u64, u64)> = flat
                .iter()
                .map(|(n, c, f)| (n.clone(), core.synth.cells_by_type.get(n).copied().unwrap_or(0), *c, *f))
                .filter(|i| i.1 > 0)
                .collect();
            let boxed: u64 = instances.iter().map(|i| i.1).sum();
            let glue_cells = core.synth.cells - boxed;
            core.hierarchy = Some(Hierarchy {
                total_cells: glue_cells + instances.iter().map(|i| i.1 * i.2).sum::<u64>(),
                total_flip_flops: core.synth.flip_flops + instances.iter().map(|i| i.1 * i.3).sum::<u64>(),
                glue_cells,
                instances,
            });
        }
    }
    Ok(reports)
}

/// Synthesizes the BSU of every topology valid at `cfg.bsu_width`.
pub fn topology_reports(cfg: &EngineConfig) -> Result<Vec<TopologyReport>, ToolError> {
    let cfgs: Vec<EngineConfig> = Topology::ALL
        .iter()
        .map(|&topology| EngineConfig { topology, ..cfg.clone() })
        .filter(|c| c.validate().is_ok())
        .collect();
    parallel(cfgs, |c| {
        let top = crate::units::bsu::NAME;
        let s = synth_stats(&files_for(&c, top), top)?;
        let net = c.network();
        Ok(TopologyReport {
            topology: c.topology.name().to_string(),
            bsu_width: c.bsu_width,
            register_every: c.register_every,
            comparators: net.comparator_count(),
            depth: net.depth(),
            latency: c.bsu_latency(),
            cells: s.cells,
            flip_flops: s.flip_flops,
            latches: s.latches,
        })
    })
    .into_iter()
    .collect()
}

/// A plain-text table of a report.
pub fn table(r: &SynthReport) -> String {
    let dash = |o: Option<usize>| o.map_or("-".to_string(), |v| v.to_string());
    let mut s = format!(
        "{:<14} {:>9} {:>10} {:>7} {:>11} {:>6} {:>8}\n",
        "unit", "cells", "flip-flops", "latches", "comparators", "depth", "latency"
    );
    for u in &r.units {
        s += &format!(
            "{:<14} {:>9} {:>10} {:>7} {:>11} {:>6} {:>8}\n",
            u.unit,
            u.synth.cells,
            u.synth.flip_flops,
            u.synth.latches,
            dash(u.comparators),
            dash(u.depth),
            dash(u.latency)
        );
        if let Some(h) = &u.hierarchy {
            let parts: Vec<String> =
                h.instances.iter().map(|(n, k, c, _)| format!("{k} x {n} ({c})")).collect();
            s += &format!(
                "  hierarchical: {} glue cells + {} = {} cells, {} flip-flops\n",
                h.glue_cells,
                parts.join(" + "),
                h.total_cells,
                h.total_flip_flops
            );
        }
    }
    if !r.bsu_topologies.is_empty() {
        s += &format!(
            "\n{:<16} {:>11} {:>6} {:>2} {:>8} {:>9} {:>10}\n",
            "bsu topology", "comparators", "depth", "k", "latency", "cells", "flip-flops"
        );
        for t in &r.bsu_topologies {
            s += &format!(
                "{:<16} {:>11} {:>6} {:>2} {:>8} {:>9} {:>10}\n",
                t.topology, t.comparators, t.depth, t.register_every, t.latency, t.cells, t.flip_flops
            );
        }
    }
    s
}
