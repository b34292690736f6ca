//! Synthesis reports: Yosys cells and flip-flops per unit and per BSU topology
//! (`neo gen --stats`, written to `reports/synth.json`), and the engine's hierarchy
//! ([`tree`]: instances, Verilog lines, cells per instance, totals per engine).
//!
//! Every unit of [`stats_tops`] is synthesized on its own (flat), except the tops of
//! [`hierarchical_boxes`] (the raster core, the Preprocessing Engine, its lane, its projection,
//! colour and duplication units, and the engine), whose own logic is synthesized with their units
//! as black boxes and whose totals add the instances times the units' figures ([`Hierarchy`]). A
//! parametric box is a top once per parameterisation its parents use ([`unit_label`],
//! `neo_fp_to_int #(.ROUNDING(1))`, synthesized after `chparam`). An entry of the previous report whose Verilog hash and Yosys command match is
//! reused instead of synthesized again ([`unit_reports`]).

pub mod tree;

use crate::emit::{Module, Placement};
use crate::tools::{glue_synth_stats, synth_stats, synth_stats_with, SynthStats, ToolError};
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

/// The report's name of a top at the parameter overrides `params`: the module, followed by
/// ` #(.P(V), ...)` when there are overrides (a parametric black box measured once per
/// parameterisation its parent uses, `neo_fp_to_int #(.ROUNDING(1))`).
pub fn unit_label(module: &str, params: &[(String, String)]) -> String {
    if params.is_empty() {
        return module.to_string();
    }
    let p: Vec<String> = params.iter().map(|(n, v)| format!(".{n}({v})")).collect();
    format!("{module} #({})", p.join(", "))
}

/// The module and parameter overrides of a top named by [`unit_label`].
pub fn parse_unit_label(label: &str) -> (String, Vec<(String, String)>) {
    let Some((module, rest)) = label.split_once(" #(") else { return (label.to_string(), Vec::new()) };
    let params = rest
        .strip_suffix(')')
        .unwrap_or(rest)
        .split(", ")
        .filter_map(|p| {
            let (n, v) = p.strip_prefix('.')?.strip_suffix(')')?.split_once('(')?;
            Some((n.to_string(), v.to_string()))
        })
        .collect();
    (module.to_string(), params)
}

/// The tops `--stats` reports for `cfg`, in order: [`top_modules`]; the Preprocessing Engine's
/// units ([`add_subtree`] from `neo_pre_engine`: each module once, every box before the
/// hierarchical top that boxes it, a parametric box once per parameterisation); the port mux
/// (at its default `PORTS`, the engine's slots per port: the engine's instances), the clock
/// gate and `neo_engine` (hierarchical tops after the units they box).
///
/// # Panics
/// When `cfg` is invalid.
pub fn stats_tops(cfg: &EngineConfig) -> Vec<String> {
    let all = crate::units::modules(cfg).unwrap_or_else(|e| panic!("{e}"));
    let mut tops: Vec<String> = top_modules().iter().map(|s| s.to_string()).collect();
    add_subtree(&all, crate::units::pre::engine::NAME, &mut tops);
    tops.push(crate::units::axi::mux::NAME.to_string());
    tops.push(crate::units::clock_gate::NAME.to_string());
    tops.push(engine::NAME.to_string());
    tops
}

/// Adds `top` to `tops` (unless there), after its [`hierarchical_boxes`] as instantiated (in
/// first-use order; a box without parameter overrides with its own boxes first, one with
/// overrides as its [`unit_label`]).
fn add_subtree(all: &[Module], top: &str, tops: &mut Vec<String>) {
    if let (Some(boxes), Some(m)) = (hierarchical_boxes(top), all.iter().find(|m| m.name == top)) {
        for (module, params) in instances(&m.placements()) {
            if !boxes.contains(&module) {
                continue;
            }
            if params.is_empty() {
                add_subtree(all, &module, tops);
            } else if !tops.contains(&unit_label(&module, &params)) {
                tops.push(unit_label(&module, &params));
            }
        }
    }
    if !tops.iter().any(|t| t == top) {
        tops.push(top.to_string());
    }
}

/// The distinct (module, parameter overrides) of the instances in `ps`, generate loops looked
/// through, in first-use order.
fn instances(ps: &[Placement]) -> Vec<(String, Vec<(String, String)>)> {
    let mut out: Vec<(String, Vec<(String, String)>)> = Vec::new();
    for p in ps {
        let found = match p {
            Placement::Instance { module, params, .. } => vec![(module.clone(), params.clone())],
            Placement::Loop { body, .. } => instances(body),
        };
        for f in found {
            if !out.contains(&f) {
                out.push(f);
            }
        }
    }
    out
}

/// FNV-1a 64 (hex) of `top`'s files without their header lines, and of its black boxes (and of
/// its parameter overrides, for a top named with them, [`unit_label`]).
pub fn verilog_hash(cfg: &EngineConfig, top: &str) -> String {
    let (module, params) = parse_unit_label(top);
    let mut text = String::new();
    for f in files_for(cfg, &module) {
        text.push_str(&f.name);
        text.push('\n');
        text.push_str(f.body());
    }
    if let Some(boxes) = hierarchical_boxes(top) {
        text.push_str(&format!("blackbox {}", boxes.join(" ")));
    }
    if !params.is_empty() {
        text.push_str(&format!("\nparameters {top}"));
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
    let jobs: Vec<(String, String)> =
        stats_tops(cfg).into_iter().map(|t| (verilog_hash(cfg, &t), t)).collect();
    let mut reports: Vec<UnitReport> = parallel(jobs, |(hash, top)| {
        let old = previous.and_then(|p| p.units.iter().find(|u| u.unit == top && u.verilog_hash == hash));
        if let Some(old) = old {
            progress(old, true);
            return Ok(old.clone());
        }
        let t0 = Instant::now();
        let bsu = top == crate::units::bsu::NAME;
        let (module, params) = parse_unit_label(&top);
        let synth = match hierarchical_boxes(&top) {
            Some(boxes) => {
                let boxes: Vec<&str> = boxes.iter().map(|s| s.as_str()).collect();
                glue_synth_stats(&files_for(cfg, &top), &top, &boxes)?
            }
            None if params.is_empty() => synth_stats(&files_for(cfg, &top), &top)?,
            None => synth_stats_with(&files_for(cfg, &module), &module, &params)?,
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
    let all = crate::units::modules(cfg).map_err(|e| ToolError::Failed {
        tool: "neo gen".into(),
        top: engine::NAME.into(),
        output: e.to_string(),
    })?;
    for i in 0..reports.len() {
        let Some(boxes) = hierarchical_boxes(&reports[i].unit) else { continue };
        let m = all.iter().find(|m| m.name == reports[i].unit);
        let hierarchy = hierarchy(&reports, &reports[i].synth, &boxes, m)?;
        reports[i].hierarchy = Some(hierarchy);
    }
    Ok(reports)
}

/// The [`Hierarchy`] of a top whose glue synthesis is `glue`, with `boxes` black-boxed, from the
/// box units' reports in `reports` (earlier in the list). A box unit named without parameters
/// counts every black-box cell of its module; one named with parameters ([`unit_label`]) the
/// instances with those overrides in `m`, the top's module; the counts of each box module must
/// add up to its black-box cells in `glue` (no parameterisation left out).
fn hierarchy(
    reports: &[UnitReport],
    glue: &SynthStats,
    boxes: &[String],
    m: Option<&Module>,
) -> Result<Hierarchy, ToolError> {
    let mut instances: Vec<(String, u64, u64, u64)> = Vec::new();
    let mut latches = 0;
    let mut per_module: std::collections::BTreeMap<String, u64> = Default::default();
    for u in reports {
        let (module, params) = parse_unit_label(&u.unit);
        if !boxes.contains(&module) {
            continue;
        }
        let k = match (params.is_empty(), m) {
            (true, _) => glue.cells_by_type.get(&module).copied().unwrap_or(0),
            (false, Some(m)) => m.count_instances(&module, &params),
            (false, None) => 0,
        };
        *per_module.entry(module).or_default() += k;
        latches += k * u.total_latches();
        if k > 0 {
            instances.push((u.unit.clone(), k, u.total_cells(), u.total_flip_flops()));
        }
    }
    for b in boxes {
        let cells = glue.cells_by_type.get(b).copied().unwrap_or(0);
        let counted = per_module.get(b).copied().unwrap_or(0);
        if cells != counted {
            return Err(ToolError::Failed {
                tool: "yosys".into(),
                top: glue.top.clone(),
                output: format!(
                    "{cells} black-box cells of {b}, but the report's units of {b} count {counted}"
                ),
            });
        }
    }
    let boxed: u64 = instances.iter().map(|x| x.1).sum();
    let glue_cells = glue.cells - boxed;
    Ok(Hierarchy {
        total_cells: glue_cells + instances.iter().map(|x| x.1 * x.2).sum::<u64>(),
        total_flip_flops: glue.flip_flops + instances.iter().map(|x| x.1 * x.3).sum::<u64>(),
        glue_cells,
        instances,
        latches,
    })
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
        "{:<30} {:>9} {:>10} {:>7} {:>11} {:>6} {:>8}\n",
        "unit", "cells", "flip-flops", "latches", "comparators", "depth", "latency"
    );
    for u in &r.units {
        s += &format!(
            "{:<30} {:>9} {:>10} {:>7} {:>11} {:>6} {:>8}\n",
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unit_labels_round_trip_and_count_the_instances_with_their_parameters() {
        let p = vec![("WIDTH".to_string(), "48".to_string()), ("DEPTH".to_string(), "2048".to_string())];
        let label = unit_label("neo_pre_ram", &p);
        assert_eq!(label, "neo_pre_ram #(.WIDTH(48), .DEPTH(2048))");
        assert_eq!(parse_unit_label(&label), ("neo_pre_ram".to_string(), p.clone()));
        assert_eq!(parse_unit_label("neo_itu"), ("neo_itu".to_string(), Vec::new()));
        let all = crate::units::modules(&EngineConfig::default()).expect("modules");
        let lists = all.iter().find(|m| m.name == crate::units::pre::lists::NAME).expect("lists");
        assert_eq!(lists.count_instances("neo_pre_ram", &p), 7, "one line memory per slot, in a loop");
        let tops = stats_tops(&EngineConfig::default());
        let at = |t: &str| tops.iter().position(|x| x == t).unwrap_or_else(|| panic!("{t} in {tops:?}"));
        assert!(at("neo_fp_to_int #(.ROUNDING(3))") < at(crate::units::pre::PROJECT_NAME));
        assert!(at(crate::units::pre::lane::NAME) < at(crate::units::pre::engine::NAME));
        assert!(at(crate::units::pre::engine::NAME) < at(engine::NAME));
        assert_eq!(tops.iter().filter(|t| *t == crate::units::itu::NAME).count(), 1, "each module once");
    }
}
