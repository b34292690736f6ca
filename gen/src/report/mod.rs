//! Synthesis reports: Yosys cells and flip-flops per unit and per BSU topology
//! (`neo gen --stats`, written to `reports/synth.json`), and the engine's hierarchy
//! ([`tree`]: instances, Verilog lines, cells per instance, totals per engine).
//!
//! Every unit of [`stats_tops`] is synthesized on its own (flat), except the tops of
//! [`hierarchical_boxes`] (the raster core, the engine), whose own logic is synthesized with their
//! units as black boxes and whose totals add the instances times the units' figures
//! ([`Hierarchy`]). An entry of the previous report whose Verilog hash and Yosys command match is
//! reused instead of synthesized again ([`unit_reports`]).

pub mod tree;

use crate::tools::{glue_synth_stats, synth_stats, SynthStats, ToolError};
use crate::units::{engine, files_for, top_modules};
use neo_golden::engine::{EngineConfig, Topology};
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// One synthesized unit of a configuration.
#[derive(Clone, Debug, Serialize, Deserialize)]
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
    /// For a top too large to synthesize flat (the raster core, the engine): its glue plus, per
    /// unit, the instance count times the unit's cells (flat, or its own hierarchical total).
    pub hierarchy: Option<Hierarchy>,
    /// FNV-1a 64 (hex) of what was synthesized: every file of the top without its header line
    /// (which names the configuration hash), and the black boxes ([`verilog_hash`]).
    #[serde(default)]
    pub verilog_hash: String,
    /// Wall seconds of the Yosys run that produced the figures.
    #[serde(default)]
    pub seconds: f64,
}

impl UnitReport {
    /// Cells of one instance: the hierarchical total, else the flat count.
    pub fn total_cells(&self) -> u64 {
        self.hierarchy.as_ref().map_or(self.synth.cells, |h| h.total_cells)
    }

    /// Flip-flops of one instance: the hierarchical total, else the flat count.
    pub fn total_flip_flops(&self) -> u64 {
        self.hierarchy.as_ref().map_or(self.synth.flip_flops, |h| h.total_flip_flops)
    }

    /// Latches of one instance: its own, plus the black-boxed units' (hierarchical tops).
    pub fn total_latches(&self) -> u64 {
        self.synth.latches + self.hierarchy.as_ref().map_or(0, |h| h.latches)
    }
}

/// A core reported hierarchically.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Hierarchy {
    /// Per instantiated unit: (module, instances, cells of one, flip-flops of one); a unit's
    /// cells are its hierarchical total when it has one.
    pub instances: Vec<(String, u64, u64, u64)>,
    /// Glue cells (the core's own logic, black-box instances excluded).
    pub glue_cells: u64,
    /// Glue cells plus instances x unit cells.
    pub total_cells: u64,
    /// Glue flip-flops plus instances x unit flip-flops.
    pub total_flip_flops: u64,
    /// Latches of the black-boxed units (each unit's total; the glue's are in `synth`).
    #[serde(default)]
    pub latches: u64,
}

/// The BSU of one topology (other parameters from the base configuration).
#[derive(Clone, Debug, Serialize, Deserialize)]
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
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct SynthReport {
    /// The configuration synthesized.
    pub config: EngineConfig,
    /// The Yosys script per top (`TOP` replaced by the module name).
    pub command: String,
    /// Per-unit results, in [`stats_tops`] order.
    pub units: Vec<UnitReport>,
    /// Per-topology BSU results (empty unless requested).
    pub bsu_topologies: Vec<TopologyReport>,
}

/// The Yosys flow used for every figure.
pub const YOSYS_COMMAND: &str = "yosys -q -p \"read_verilog FILES; synth -flatten -top TOP; stat -json\"";

/// Runs `jobs` on up to two threads (the build machine has two cores), each taking the next job
/// when it is free (so two long jobs run side by side); results in the jobs' order.
fn parallel<T: Send, R: Send>(jobs: Vec<T>, f: impl Fn(T) -> R + Sync) -> Vec<R> {
    use std::sync::Mutex;
    let n = jobs.len();
    let queue = Mutex::new(jobs.into_iter().enumerate().collect::<std::collections::VecDeque<_>>());
    let out: Mutex<Vec<Option<R>>> = Mutex::new((0..n).map(|_| None).collect());
    let work = || loop {
        let Some((i, j)) = queue.lock().unwrap_or_else(|e| e.into_inner()).pop_front() else {
            break;
        };
        let r = f(j);
        out.lock().unwrap_or_else(|e| e.into_inner())[i] = Some(r);
    };
    std::thread::scope(|s| {
        let h = s.spawn(work);
        work();
        h.join().expect("synthesis thread");
    });
    out.into_inner()
        .unwrap_or_else(|e| e.into_inner())
        .into_iter()
        .map(|r| r.expect("every job ran"))
        .collect()
}

/// Tops synthesized hierarchically with a fixed set of black boxes (a flat synthesis of 4 SCUs,
/// ~2 M cells, takes too long): (top, units kept as black boxes; their figures come from their
/// own reports). The engine's and the preprocessing units' boxes are in [`hierarchical_boxes`].
pub const HIERARCHICAL: &[(&str, &[&str])] = &[(
    crate::units::raster_core::NAME,
    &[crate::units::itu::NAME, crate::units::scu::NAME, crate::units::scu::EXP_NAME],
)];

/// The black boxes of `top` when it is synthesized hierarchically: the raster core's units,
/// the preprocessing datapaths' binary32 primitives (each checked as its own top), the
/// duplication unit's ITUs, or every module the engine instantiates; `None` for the tops
/// synthesized flat.
pub fn hierarchical_boxes(top: &str) -> Option<Vec<String>> {
    use crate::units::{fp, itu, pre};
    if top == pre::COLOR_NAME || top == pre::PROJECT_NAME {
        let mut boxes: Vec<String> = Vec::new();
        for name in fp::FpPrim::ALL.iter().map(|&p| fp::module_name(p)).chain([fp::cmp::NAME]) {
            if !boxes.iter().any(|b| b == name) {
                boxes.push(name.to_string());
            }
        }
        return Some(boxes);
    }
    if top == pre::dup::NAME {
        return Some(vec![itu::NAME.to_string()]);
    }
    if top == pre::lane::NAME {
        return Some(
            [pre::COLOR_NAME, pre::PROJECT_NAME, pre::fetch::NAME, pre::dup::NAME]
                .iter()
                .map(|s| s.to_string())
                .collect(),
        );
    }
    if top == pre::engine::NAME {
        return Some(pre::engine::SUBMODULES.iter().map(|s| s.to_string()).collect());
    }
    if top == engine::NAME {
        let mut boxes: Vec<String> = engine::SUBMODULES.iter().map(|s| s.to_string()).collect();
        boxes.push(crate::units::axi::mux::NAME.to_string());
        return Some(boxes);
    }
    HIERARCHICAL.iter().find(|(t, _)| *t == top).map(|(_, b)| b.iter().map(|s| s.to_string()).collect())
}

/// The tops `--stats` reports, in order: [`top_modules`], the port mux (at its default `PORTS`,
/// the engine's slots per port: the engine's instances), the clock gate and `neo_engine`
/// (hierarchical tops after the units they box).
pub fn stats_tops() -> Vec<String> {
    let mut tops: Vec<String> = top_modules().iter().map(|s| s.to_string()).collect();
    tops.push(crate::units::axi::mux::NAME.to_string());
    tops.push(crate::units::clock_gate::NAME.to_string());
    tops.push(engine::NAME.to_string());
    tops
}

/// FNV-1a 64 (hex) of `top`'s files without their header lines, and of its black boxes.
pub fn verilog_hash(cfg: &EngineConfig, top: &str) -> String {
    let mut text = String::new();
    for f in files_for(cfg, top) {
        text.push_str(&f.name);
        text.push('\n');
        text.push_str(f.body());
    }
    if let Some(boxes) = hierarchical_boxes(top) {
        text.push_str(&format!("blackbox {}", boxes.join(" ")));
    }
    let h =
        text.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, b| (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3));
    format!("{h:016x}")
}

/// Synthesizes every top of [`stats_tops`] (flat; the hierarchical ones with their units as
/// black boxes, see [`Hierarchy`]). An entry of `previous` (an earlier report, e.g. the one
/// being replaced) with the same Yosys command, unit and [`verilog_hash`] is reused as it is;
/// `progress` is told each top as it is done (reused or synthesized, with the seconds).
pub fn unit_reports(
    cfg: &EngineConfig,
    previous: Option<&SynthReport>,
    progress: &(dyn Fn(&UnitReport, bool) + Sync),
) -> Result<Vec<UnitReport>, ToolError> {
    let net = cfg.network();
    let previous = previous.filter(|p| p.command == YOSYS_COMMAND);
    let jobs: Vec<(String, String)> = stats_tops().into_iter().map(|t| (verilog_hash(cfg, &t), t)).collect();
    let mut reports: Vec<UnitReport> = parallel(jobs, |(hash, top)| {
        let old = previous.and_then(|p| p.units.iter().find(|u| u.unit == top && u.verilog_hash == hash));
        if let Some(old) = old {
            progress(old, true);
            return Ok(old.clone());
        }
        let t0 = Instant::now();
        let bsu = top == crate::units::bsu::NAME;
        let synth = match hierarchical_boxes(&top) {
            Some(boxes) => {
                let boxes: Vec<&str> = boxes.iter().map(|s| s.as_str()).collect();
                glue_synth_stats(&files_for(cfg, &top), &top, &boxes)?
            }
            None => synth_stats(&files_for(cfg, &top), &top)?,
        };
        let r = UnitReport {
            unit: top.clone(),
            comparators: bsu.then(|| net.comparator_count()),
            depth: bsu.then(|| net.depth()),
            latency: bsu.then(|| cfg.bsu_latency()),
            synth,
            hierarchy: None,
            verilog_hash: hash,
            seconds: t0.elapsed().as_secs_f64(),
        };
        progress(&r, false);
        Ok(r)
    })
    .into_iter()
    .collect::<Result<_, ToolError>>()?;
    for i in 0..reports.len() {
        let Some(boxes) = hierarchical_boxes(&reports[i].unit) else { continue };
        let instances: Vec<(String, u64, u64, u64)> = reports
            .iter()
            .filter(|u| boxes.contains(&u.unit))
            .map(|u| {
                let k = reports[i].synth.cells_by_type.get(&u.unit).copied().unwrap_or(0);
                (u.unit.clone(), k, u.total_cells(), u.total_flip_flops())
            })
            .filter(|x| x.1 > 0)
            .collect();
        let latches: u64 = reports
            .iter()
            .filter(|u| boxes.contains(&u.unit))
            .map(|u| reports[i].synth.cells_by_type.get(&u.unit).copied().unwrap_or(0) * u.total_latches())
            .sum();
        let core = &mut reports[i];
        let boxed: u64 = instances.iter().map(|x| x.1).sum();
        let glue_cells = core.synth.cells - boxed;
        core.hierarchy = Some(Hierarchy {
            total_cells: glue_cells + instances.iter().map(|x| x.1 * x.2).sum::<u64>(),
            total_flip_flops: core.synth.flip_flops + instances.iter().map(|x| x.1 * x.3).sum::<u64>(),
            glue_cells,
            instances,
            latches,
        });
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
        "{:<22} {:>9} {:>10} {:>7} {:>11} {:>6} {:>8}\n",
        "unit", "cells", "flip-flops", "latches", "comparators", "depth", "latency"
    );
    for u in &r.units {
        s += &format!(
            "{:<22} {:>9} {:>10} {:>7} {:>11} {:>6} {:>8}\n",
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
                "  hierarchical: {} glue cells + {} = {} cells, {} flip-flops, {} latches\n",
                h.glue_cells,
                parts.join(" + "),
                h.total_cells,
                h.total_flip_flops,
                u.total_latches()
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
