//! The engine's hierarchy (`neo gen --stats`): every instance under `neo_engine` with its
//! generate loops (`g_sort[16]`, `g_raster[4]`, `g_port[4]`, ...), how many there are in the
//! whole engine, the lines of its module's Verilog and, where the synthesis report has the
//! module as a top, Yosys cells and flip-flops of one instance; then totals per engine part
//! ([`Part`]: sorting, rasterization, interconnect, control).

use super::{unit_label, SynthReport, UnitReport};
use crate::emit::{Module, Placement};
use crate::units::{axi, engine, raster_core, sort_core, sort_seq};
use neo_golden::engine::{ConfigError, EngineConfig};
use std::collections::BTreeSet;

/// One row of the tree: an instance (or a generate loop, `module` `None`).
#[derive(Clone, Debug)]
pub struct Node {
    /// Instance name (`u_core`), or a loop's label and count (`g_sort[16]`); the top's name.
    pub label: String,
    /// The instantiated module (`None` for a generate loop).
    pub module: Option<String>,
    /// The instance's parameter overrides (its report unit is then the module's
    /// [`super::unit_label`] with them, when the report has one).
    pub params: Vec<(String, String)>,
    /// Instances (or loop iterations) in the whole engine.
    pub count: u64,
    /// Lines of the module's Verilog file.
    pub lines: Option<usize>,
    /// The module's entry in the synthesis report, if it was a top there.
    pub unit: Option<UnitReport>,
    /// Instances and loops inside.
    pub children: Vec<Node>,
}

/// The parts of the engine the totals are split into.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Part {
    /// Sequencers and Sorting Cores (with their BSU, MSU+, buffers).
    Sorting,
    /// Rasterization Cores (with their ITUs, SCUs, loader, feeders).
    Rasterization,
    /// AXI4 bridges and port muxes.
    Interconnect,
    /// Frame controller, control port, performance counters and the engine's own glue.
    Control,
    /// The Preprocessing Engine (lanes with projection, colour, fetch and duplication units, and
    /// the list writer).
    Preprocessing,
}

impl Part {
    /// Every part, in report order.
    pub const ALL: [Part; 5] =
        [Part::Sorting, Part::Rasterization, Part::Interconnect, Part::Control, Part::Preprocessing];

    /// The part a module instantiated by `neo_engine` belongs to.
    pub fn of(module: &str) -> Part {
        match module {
            m if m == sort_seq::NAME || m == sort_core::NAME => Part::Sorting,
            m if m == raster_core::NAME => Part::Rasterization,
            m if m == crate::units::pre::engine::NAME => Part::Preprocessing,
            m if m == axi::sort_bridge::NAME || m == axi::raster_bridge::NAME || m == axi::mux::NAME => {
                Part::Interconnect
            }
            // The frame controller, the control port, the counters, the clock gates of the
            // cores and of the Preprocessing Engine (and anything else).
            _ => Part::Control,
        }
    }

    /// Lower-case name.
    pub fn name(self) -> &'static str {
        match self {
            Part::Sorting => "sorting",
            Part::Rasterization => "rasterization",
            Part::Interconnect => "interconnect",
            Part::Control => "control",
            Part::Preprocessing => "preprocessing",
        }
    }
}

/// The totals of one part.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct PartTotal {
    /// Modules instantiated directly by the engine in this part.
    pub modules: BTreeSet<String>,
    /// Verilog lines of every module in the part's subtrees, each module once.
    pub lines: usize,
    /// Instances x cells of one (`None` when a module has no synthesis figure).
    pub cells: Option<u64>,
    /// Instances x flip-flops of one.
    pub flip_flops: Option<u64>,
}

/// The whole engine's row under the per-part totals of [`Node::totals`]: the parts' cells and
/// flip-flops added up, `None` where a part has no figure (as `neo gen --stats` prints it).
pub fn engine_total(totals: &[(Part, PartTotal)]) -> (Option<u64>, Option<u64>) {
    let sum = |f: fn(&PartTotal) -> Option<u64>| {
        totals.iter().map(|(_, t)| f(t)).try_fold(0u64, |a, v| v.map(|v| a + v))
    };
    (sum(|t| t.cells), sum(|t| t.flip_flops))
}

/// The tree of `neo_engine` for `cfg`, with the figures of `report` where it has the module.
pub fn build(cfg: &EngineConfig, report: Option<&SynthReport>) -> Result<Node, ConfigError> {
    let all = crate::units::modules(cfg)?;
    Ok(node(&all, report, engine::NAME, (engine::NAME, &[]), 1))
}

/// The node of an instance `label` of `module` at parameter overrides `params`; its report
/// unit is the one named [`unit_label`]`(module, params)`, else the module's own.
fn node(
    all: &[Module],
    report: Option<&SynthReport>,
    label: &str,
    (module, params): (&str, &[(String, String)]),
    count: u64,
) -> Node {
    let m = all.iter().find(|m| m.name == module);
    let children = m.map_or_else(Vec::new, |m| placed(all, report, &m.placements(), count));
    let find = |name: &str| report.and_then(|r| r.units.iter().find(|u| u.unit == name)).cloned();
    Node {
        label: label.to_string(),
        module: Some(module.to_string()),
        params: params.to_vec(),
        count,
        lines: m.map(|m| m.to_verilog().lines().count()),
        unit: find(&unit_label(module, params)).or_else(|| find(module)),
        children,
    }
}

/// The placements of a body as nodes; sibling instances of one module (the BSU's
/// compare-exchanges, the core's chunk buffers) are one row `<common prefix>* (k)`.
fn placed(all: &[Module], report: Option<&SynthReport>, ps: &[Placement], count: u64) -> Vec<Node> {
    let mut out: Vec<Node> = Vec::new();
    let mut names: Vec<Vec<String>> = Vec::new();
    for n in placed_each(all, report, ps, count) {
        let same =
            out.iter().position(|o| o.module.is_some() && o.module == n.module && o.params == n.params);
        match same {
            Some(i) => {
                names[i].push(n.label.clone());
                out[i].absorb(n);
            }
            None => {
                names.push(vec![n.label.clone()]);
                out.push(n);
            }
        }
    }
    for (o, names) in out.iter_mut().zip(names) {
        if names.len() > 1 {
            let first = &names[0];
            let common = names.iter().fold(first.len(), |l, n| {
                first.bytes().zip(n.bytes()).take(l).take_while(|(a, b)| a == b).count()
            });
            o.label = format!("{}* ({})", &first[..common], names.len());
        }
    }
    out
}

fn placed_each(all: &[Module], report: Option<&SynthReport>, ps: &[Placement], count: u64) -> Vec<Node> {
    ps.iter()
        .map(|p| match p {
            Placement::Instance { name, module, params } => node(all, report, name, (module, params), count),
            Placement::Loop { label, count: c, body } => {
                let n = count * u64::from(*c);
                Node {
                    label: format!("{label}[{c}]"),
                    module: None,
                    params: Vec::new(),
                    count: n,
                    lines: None,
                    unit: None,
                    children: placed(all, report, body, n),
                }
            }
        })
        .collect()
}

impl Node {
    /// Adds a sibling instance of the same module and parameters to this row: its count and,
    /// level by level, its subtree's counts (the two subtrees have the same shape).
    fn absorb(&mut self, other: Node) {
        self.count += other.count;
        for (c, o) in self.children.iter_mut().zip(other.children) {
            c.absorb(o);
        }
    }

    /// The module instances directly below (looking through generate loops).
    pub fn instances(&self) -> Vec<&Node> {
        let mut out = Vec::new();
        for c in &self.children {
            if c.module.is_some() {
                out.push(c);
            } else {
                out.extend(c.instances());
            }
        }
        out
    }

    /// Every module in this subtree (itself included) with its lines.
    fn modules(&self, out: &mut std::collections::BTreeMap<String, usize>) {
        if let (Some(m), Some(l)) = (&self.module, self.lines) {
            out.insert(m.clone(), l);
        }
        for c in &self.children {
            c.modules(out);
        }
    }

    /// Totals per part of the engine: its direct instances by [`Part::of`], the engine's own
    /// glue (the report's hierarchical glue) and lines in [`Part::Control`].
    pub fn totals(&self) -> Vec<(Part, PartTotal)> {
        let mut totals: Vec<(Part, PartTotal)> =
            Part::ALL.iter().map(|&p| (p, PartTotal::default())).collect();
        let mut lines: Vec<std::collections::BTreeMap<String, usize>> =
            vec![Default::default(); Part::ALL.len()];
        let add = |t: &mut PartTotal, cells: Option<u64>, ffs: Option<u64>, first: bool| {
            let start = |v: Option<u64>| if first { Some(0) } else { v };
            t.cells = start(t.cells).zip(cells).map(|(a, b)| a + b);
            t.flip_flops = start(t.flip_flops).zip(ffs).map(|(a, b)| a + b);
        };
        let control = Part::ALL.iter().position(|&p| p == Part::Control).expect("control");
        let mut seen = [false; Part::ALL.len()];
        for n in self.instances() {
            let module = n.module.as_deref().unwrap_or_default();
            let i = Part::ALL.iter().position(|&p| p == Part::of(module)).unwrap_or(control);
            let (t, first) = (&mut totals[i].1, !seen[i]);
            seen[i] = true;
            t.modules.insert(module.to_string());
            let per = n.unit.as_ref();
            add(
                t,
                per.map(|u| n.count * u.total_cells()),
                per.map(|u| n.count * u.total_flip_flops()),
                first,
            );
            n.modules(&mut lines[i]);
        }
        if let (Some(m), Some(l)) = (&self.module, self.lines) {
            lines[control].insert(m.clone(), l);
        }
        let glue =
            self.unit.as_ref().and_then(|u| u.hierarchy.as_ref().map(|h| (h.glue_cells, u.synth.flip_flops)));
        let first = !seen[control];
        add(&mut totals[control].1, glue.map(|g| g.0), glue.map(|g| g.1), first);
        for (i, (_, t)) in totals.iter_mut().enumerate() {
            t.lines = lines[i].values().sum();
        }
        totals
    }

    /// The tree and the totals as text.
    pub fn text(&self, cfg: &EngineConfig) -> String {
        let mut s = format!(
            "{} hierarchy: {} sorting + {} raster cores, {} AXI4 ports (count: instances in the engine; \
             lines: the module's Verilog; cells, flip-flops: Yosys, one instance)\n",
            self.label, cfg.sort_cores, cfg.raster_cores, cfg.mem_channels
        );
        s += &format!(
            "{:<34} {:<30} {:>6} {:>6} {:>10} {:>10}\n",
            "instance", "module", "count", "lines", "cells", "flip-flops"
        );
        self.rows(0, &mut s);
        let all_lines: usize = {
            let mut m = Default::default();
            self.modules(&mut m);
            m.values().sum()
        };
        s += &format!("\nper part of the engine ({} lines of Verilog in all):\n", all_lines);
        s += &format!(
            "{:<14} {:<60} {:>6} {:>10} {:>10}\n",
            "part", "modules", "lines", "cells", "flip-flops"
        );
        let opt = |v: Option<u64>| v.map_or("-".to_string(), |v| v.to_string());
        let totals = self.totals();
        for (p, t) in &totals {
            let mut mods: Vec<&str> = t.modules.iter().map(|m| m.as_str()).collect();
            if *p == Part::Control {
                mods.push("+ engine glue");
            }
            s += &format!(
                "{:<14} {:<60} {:>6} {:>10} {:>10}\n",
                p.name(),
                mods.join(" "),
                t.lines,
                opt(t.cells),
                opt(t.flip_flops)
            );
        }
        let (cells, flip_flops) = engine_total(&totals);
        s += &format!(
            "{:<14} {:<60} {:>6} {:>10} {:>10}\n",
            "engine",
            "",
            all_lines,
            opt(cells),
            opt(flip_flops)
        );
        s
    }

    fn rows(&self, depth: usize, s: &mut String) {
        let opt = |v: Option<u64>| v.map_or("-".to_string(), |v| v.to_string());
        let label = format!("{}{}", "  ".repeat(depth), self.label);
        let u = self.unit.as_ref();
        *s += &format!(
            "{:<34} {:<30} {:>6} {:>6} {:>10} {:>10}\n",
            label,
            self.module.as_deref().map_or(String::new(), |m| unit_label(m, &self.params)),
            self.count,
            self.lines.map_or(String::new(), |l| l.to_string()),
            if self.module.is_some() { opt(u.map(|u| u.total_cells())) } else { String::new() },
            if self.module.is_some() { opt(u.map(|u| u.total_flip_flops())) } else { String::new() },
        );
        if let Some(h) = u.and_then(|u| u.hierarchy.as_ref()) {
            *s += &format!(
                "{:<34} {:<30} {:>6} {:>6} {:>10} {:>10}\n",
                format!("{}  (own logic)", "  ".repeat(depth)),
                "",
                "",
                "",
                h.glue_cells,
                u.map_or(0, |u| u.synth.flip_flops)
            );
        }
        for c in &self.children {
            c.rows(depth + 1, s);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::{stats_tops, Hierarchy, UnitReport, YOSYS_COMMAND};
    use crate::tools::SynthStats;
    use crate::units::{clock_gate, engine_regs, frame_ctrl, perf_counters};

    fn unit(name: &str, cells: u64, ffs: u64) -> UnitReport {
        UnitReport {
            unit: name.to_string(),
            comparators: None,
            depth: None,
            latency: None,
            synth: SynthStats {
                top: name.to_string(),
                cells,
                flip_flops: ffs,
                latches: 0,
                cells_by_type: Default::default(),
            },
            hierarchy: None,
            verilog_hash: String::new(),
            seconds: 0.0,
        }
    }

    /// A report with made-up figures: unit i has 1000 (i + 1) cells and 10 (i + 1) flip-flops;
    /// the engine's glue 7 cells, 3 flip-flops.
    fn fake_report(cfg: &EngineConfig) -> SynthReport {
        let mut units: Vec<UnitReport> = stats_tops(cfg)
            .iter()
            .enumerate()
            .map(|(i, t)| unit(t, 1000 * (i as u64 + 1), 10 * (i as u64 + 1)))
            .collect();
        let e = units.iter_mut().find(|u| u.unit == engine::NAME).expect("engine");
        e.synth.flip_flops = 3;
        e.hierarchy = Some(Hierarchy {
            instances: vec![],
            glue_cells: 7,
            total_cells: 0,
            total_flip_flops: 0,
            latches: 0,
        });
        SynthReport { config: cfg.clone(), command: YOSYS_COMMAND.into(), units, bsu_topologies: vec![] }
    }

    fn cells(r: &SynthReport, m: &str) -> u64 {
        r.units.iter().find(|u| u.unit == m).map(|u| u.total_cells()).expect("unit")
    }

    #[test]
    fn the_default_engine_tree_has_its_cores_ports_and_counts() {
        let cfg = EngineConfig::default();
        let r = fake_report(&cfg);
        let t = build(&cfg, Some(&r)).expect("tree");
        let find =
            |label: &str| t.children.iter().find(|c| c.label == label).unwrap_or_else(|| panic!("{label}"));
        let sort = find(&format!("g_sort[{}]", cfg.sort_cores));
        assert_eq!(sort.count, cfg.sort_cores as u64);
        let core = sort.children.iter().find(|c| c.module.as_deref() == Some(sort_core::NAME)).expect("core");
        assert_eq!(core.count, cfg.sort_cores as u64);
        assert!(core.children.iter().any(|c| c.module.as_deref() == Some("neo_bsu") && c.count == 16));
        let ram =
            core.children.iter().find(|c| c.module.as_deref() == Some("neo_chunk_ram")).expect("buffers");
        assert_eq!(
            (ram.label.as_str(), ram.count),
            ("u_* (4)", 4 * 16),
            "four chunk buffers per core, one row"
        );
        let pre = find("u_pre");
        let lanes = pre.children.iter().find(|c| c.module.is_none()).expect("the lane loop");
        let project = lanes.children[0]
            .children
            .iter()
            .find(|c| c.module.as_deref() == Some("neo_pre_project"))
            .expect("projection unit");
        let muls = project.children.iter().find(|c| c.module.as_deref() == Some("neo_fp_mul")).expect("muls");
        assert!(muls.count > project.count, "{} multipliers", muls.count);
        assert_eq!(muls.children[0].count, muls.count, "a counter in each of the grouped multipliers");
        let divs = project.children.iter().find(|c| c.module.as_deref() == Some("neo_fp_div")).expect("divs");
        let stages = divs.children.iter().find(|c| c.module.is_none()).expect("the divider's stage loop");
        assert_eq!(stages.count, 13 * divs.count, "13 stages in each grouped divider");
        let raster = find(&format!("g_raster[{}]", cfg.raster_cores));
        assert_eq!(raster.count, cfg.raster_cores as u64);
        let port = find(&format!("g_port[{}]", cfg.mem_channels));
        let mux = axi::mux::NAME;
        assert_eq!(port.children[0].module.as_deref(), Some(mux));
        assert_eq!(port.children[0].count, cfg.mem_channels as u64);
        let text = t.text(&cfg);
        println!("{text}");
        assert!(text.contains("g_sort[16]") && text.contains(mux), "{text}");

        let totals = t.totals();
        let get = |p: Part| totals.iter().find(|(q, _)| *q == p).map(|(_, t)| t.clone()).expect("part");
        let n = cfg.sort_cores as u64;
        let m = cfg.raster_cores as u64;
        let k = cfg.mem_channels as u64;
        assert_eq!(
            get(Part::Sorting).cells,
            Some(n * (cells(&r, sort_seq::NAME) + cells(&r, sort_core::NAME)))
        );
        assert_eq!(get(Part::Rasterization).cells, Some(m * cells(&r, raster_core::NAME)));
        assert_eq!(
            get(Part::Interconnect).cells,
            Some(
                n * cells(&r, axi::sort_bridge::NAME)
                    + m * cells(&r, axi::raster_bridge::NAME)
                    + k * cells(&r, mux)
            )
        );
        assert_eq!(
            get(Part::Control).cells,
            Some(
                cells(&r, frame_ctrl::NAME)
                    + cells(&r, engine_regs::NAME)
                    + cells(&r, perf_counters::NAME)
                    + (n + m + 1) * cells(&r, clock_gate::NAME)
                    + 7
            )
        );
        assert_eq!(get(Part::Preprocessing).cells, Some(cells(&r, crate::units::pre::engine::NAME)));
        assert!(get(Part::Sorting).lines > 0 && get(Part::Control).lines > 0);
        // The lanes, and the parametric primitives' rows by their parameters.
        let pre =
            t.instances().into_iter().find(|n| n.module.as_deref() == Some(crate::units::pre::engine::NAME));
        let lanes = pre.expect("pre engine").instances()[0].clone();
        assert_eq!(lanes.count, cfg.pre_units as u64);
        let project = lanes
            .instances()
            .into_iter()
            .find(|n| n.module.as_deref() == Some(crate::units::pre::PROJECT_NAME))
            .expect("projection unit")
            .clone();
        let to_int: Vec<&Node> = project
            .instances()
            .into_iter()
            .filter(|n| n.module.as_deref() == Some("neo_fp_to_int"))
            .collect();
        assert!(
            to_int.len() > 1 && to_int.iter().all(|n| n.unit.is_some() && !n.params.is_empty()),
            "{text}"
        );
        let all: usize = totals.iter().map(|(_, t)| t.lines).sum();
        assert!(all >= get(Part::Sorting).lines);
    }

    #[test]
    fn without_a_report_the_tree_has_lines_but_no_cells() {
        let cfg = EngineConfig { sort_cores: 2, raster_cores: 1, mem_channels: 2, ..EngineConfig::default() };
        let t = build(&cfg, None).expect("tree");
        assert!(t.lines.is_some_and(|l| l > 0));
        assert!(t.totals().iter().all(|(_, p)| p.cells.is_none()));
        assert!(t.text(&cfg).contains("g_sort[2]"));
    }
}
