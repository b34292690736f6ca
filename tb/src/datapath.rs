//! The bench of every pipelined datapath emitted from a golden dataflow graph (the
//! Preprocessing Engine's units, `gen/src/units/pre`): the driver offers items under random
//! valid/ready backpressure, the golden model is [`Graph::eval`] (the graph's [`Native`]
//! evaluation, the same program golden's pipeline runs), and the checker compares every output
//! field of every item in order, stopping at the first mismatch.
//!
//! [`Native`]: neo_golden::hwarith::Native

use crate::check::Checker;
use crate::dynmodel::DynModel;
use crate::rng::Rng;
use neo_gen::emit::Module;
use neo_gen::units::VerilogFile;
use neo_golden::hwarith::graph::{Graph, Ty};

/// A Verilated datapath and the graph it was emitted from.
pub struct DatapathBench {
    graph: Graph,
    model: DynModel,
    /// Port index of each graph input.
    inputs: Vec<usize>,
    /// Port index of each graph output.
    outputs: Vec<usize>,
    in_valid: usize,
    in_ready: usize,
    out_valid: usize,
    out_ready: usize,
}

/// What a run measured.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RunStats {
    /// Items checked.
    pub items: usize,
    /// Cycles from the first item offered to the last result taken.
    pub cycles: u64,
    /// Cycles from the first item's acceptance to its result on the outputs.
    pub first_latency: u64,
}

impl DatapathBench {
    /// Verilates `top`, a module outside the configuration's set, from `files` (every module it
    /// instantiates; `top` itself is added). `graph` is the graph the top was emitted from.
    pub fn build(graph: Graph, top: &Module, files: &[VerilogFile]) -> Result<Self, String> {
        let mut files = files.to_vec();
        files.retain(|f| f.name != top.name);
        files.push(VerilogFile { name: top.name.clone(), text: top.to_verilog() });
        let files: Vec<(String, String)> = files.iter().map(|f| (f.file_name(), f.text.clone())).collect();
        Self::build_from(graph, &top.interface(), &files, crate::dynmodel::LINT_VLT)
    }

    /// Verilates `top`, a generated module of `cfg` emitted from `graph`, from the generated
    /// files (or `$NEO_HDL_DIR`'s copy of `top.v`: [`crate::dynmodel::generated_files`]).
    pub fn build_generated(graph: Graph, cfg: &neo_gen::EngineConfig, top: &str) -> Result<Self, String> {
        let (files, vlt) = crate::dynmodel::generated_files(cfg, top)?;
        let iface = neo_gen::units::modules(cfg)
            .map_err(|e| e.to_string())?
            .into_iter()
            .find(|m| m.name == top)
            .ok_or(format!("the generator emits no {top}"))?
            .interface();
        Self::build_from(graph, &iface, &files, &vlt)
    }

    fn build_from(
        graph: Graph,
        iface: &neo_gen::interface::ModuleInterface,
        files: &[(String, String)],
        vlt: &str,
    ) -> Result<Self, String> {
        let (model, _) = DynModel::build_traced(iface, files, Some(vlt), None)?;
        let port = |name: String| model.port(&name);
        let inputs = graph
            .inputs
            .iter()
            .map(|i| port(if i.uniform { format!("{}_i", i.name) } else { format!("in_{}_i", i.name) }))
            .collect::<Result<Vec<_>, _>>()?;
        let outputs =
            graph.outputs.iter().map(|(n, _)| port(format!("out_{n}_o"))).collect::<Result<Vec<_>, _>>()?;
        Ok(DatapathBench {
            in_valid: port("in_valid_i".into())?,
            in_ready: port("in_ready_o".into())?,
            out_valid: port("out_valid_o".into())?,
            out_ready: port("out_ready_i".into())?,
            graph,
            model,
            inputs,
            outputs,
        })
    }

    /// The model, for waves.
    pub fn model_mut(&mut self) -> &mut DynModel {
        &mut self.model
    }

    /// The graph under test.
    pub fn graph(&self) -> &Graph {
        &self.graph
    }

    /// Runs `items` (each one raw value per graph input, in [`Graph::inputs`] order; per-frame
    /// inputs must agree across items) through the unit: an item is offered in `p_valid`% of
    /// cycles and stays offered until taken, results are taken in `p_ready`%; every output is
    /// checked against [`Graph::eval`]. `settle` idle cycles follow the per-frame inputs.
    /// Panics at the first mismatch (see [`Checker`]).
    pub fn run(
        &mut self,
        items: &[Vec<u32>],
        settle: u32,
        rng: &mut Rng,
        (p_valid, p_ready): (u32, u32),
        check: &Checker,
    ) -> RunStats {
        let expected: Vec<Vec<u32>> = items.iter().map(|i| self.graph.eval(i)).collect();
        let m = &mut self.model;
        m.reset();
        if let Some(first) = items.first() {
            for (k, inp) in self.graph.inputs.iter().enumerate().filter(|(_, i)| i.uniform) {
                assert!(items.iter().all(|i| i[k] == first[k]), "per-frame input {} varies", inp.name);
                m.set_u64(self.inputs[k], first[k] as u64);
            }
        }
        m.set_u64(self.in_valid, 0);
        m.set_u64(self.out_ready, 1);
        for _ in 0..settle {
            m.tick();
        }
        let (mut next, mut done) = (0usize, 0usize);
        let (mut start, mut first_accept, mut first_latency) = (None, None, 0u64);
        let limit = m.cycle() + 64 * (items.len() as u64 + 1000) * 100 / p_valid.min(p_ready).max(1) as u64;
        let mut held = false;
        while done < items.len() {
            let cycle = m.cycle();
            check.protocol(cycle, cycle < limit, "no progress: the unit stopped producing results");
            // An offered item stays offered until taken (valid is never withdrawn).
            let offer = next < items.len() && (held || rng.percent(p_valid));
            m.set_u64(self.in_valid, offer as u64);
            if offer {
                start.get_or_insert(cycle);
                for (k, _) in self.graph.inputs.iter().enumerate().filter(|(_, i)| !i.uniform) {
                    m.set_u64(self.inputs[k], items[next][k] as u64);
                }
            }
            let take = rng.percent(p_ready);
            m.set_u64(self.out_ready, take as u64);
            m.eval();
            if m.get_u64(self.out_valid) == 1 && take {
                if done == 0 {
                    first_latency = cycle - first_accept.unwrap_or(cycle);
                }
                for (o, ((name, id), port)) in self.graph.outputs.iter().zip(&self.outputs).enumerate() {
                    let mask = if self.graph.nodes[*id].ty == Ty::B { 1 } else { u32::MAX };
                    let field = format!("item {done} {name}");
                    check.value(cycle, &field, expected[done][o] as u64, m.get_u64(*port) & mask as u64);
                }
                done += 1;
            }
            let taken = offer && m.get_u64(self.in_ready) == 1;
            held = offer && !taken;
            if taken {
                first_accept.get_or_insert(cycle);
                next += 1;
            }
            m.tick();
        }
        RunStats { items: items.len(), cycles: m.cycle() - start.unwrap_or(0), first_latency }
    }
}
