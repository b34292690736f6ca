//! The bench of every pipelined datapath emitted from a golden dataflow graph (the
//! Preprocessing Engine's units, `gen/src/units/pre`): the stream agents ([`Source`],
//! [`Sink`]) offer items and take results under random valid/ready backpressure, the golden
//! model is [`Graph::eval`] (the graph's [`Native`] evaluation, the same program golden's
//! pipeline runs), and the checker compares every output field of every item in order,
//! stopping at the first mismatch.
//!
//! [`Native`]: neo_golden::hwarith::Native

use crate::check::Checker;
use crate::dynmodel::DynModel;
use crate::rng::Rng;
use crate::stream::{Sink, Source};
use neo_gen::emit::Module;
use neo_gen::units::VerilogFile;
use neo_golden::hwarith::graph::{Graph, Ty};

/// A Verilated datapath and the graph it was emitted from.
pub struct DatapathBench {
    graph: Graph,
    model: DynModel,
    /// Port index of each per-frame graph input.
    uniform: Vec<(usize, usize)>,
    /// Port name of each per-item graph input (the source's data, in graph order).
    items_in: Vec<String>,
    /// Port name of each graph output (the sink's data, in graph order).
    outputs: Vec<String>,
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
        let iface = crate::dynmodel::generated_interface(cfg, top)?;
        Self::build_from(graph, &iface, &files, &vlt)
    }

    fn build_from(
        graph: Graph,
        iface: &neo_gen::interface::ModuleInterface,
        files: &[(String, String)],
        vlt: &str,
    ) -> Result<Self, String> {
        let (model, _) = DynModel::build_for_short_runs(iface, files, Some(vlt), None)?;
        let mut uniform = Vec::new();
        let mut items_in = Vec::new();
        for (k, i) in graph.inputs.iter().enumerate() {
            if i.uniform {
                uniform.push((k, model.port(&format!("{}_i", i.name))?));
            } else {
                items_in.push(format!("in_{}_i", i.name));
            }
        }
        let outputs = graph.outputs.iter().map(|(n, _)| format!("out_{n}_o")).collect();
        let bench =
            DatapathBench { out_ready: model.port("out_ready_i")?, graph, model, uniform, items_in, outputs };
        bench.agents(&mut Rng::new(0), (100, 100))?;
        Ok(bench)
    }

    /// The stream agents of a run ([`crate::stream::unit_agents`]).
    fn agents(&self, rng: &mut Rng, mix: (u32, u32)) -> Result<(Source, Sink), String> {
        let (ins, outs) = (strs(&self.items_in), strs(&self.outputs));
        crate::stream::unit_agents(&self.model, &ins, &outs, rng, mix)
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
    /// inputs must agree across items) through the unit: a [`Source`] offers an item in
    /// `p_valid`% of cycles and holds it until taken, a [`Sink`] takes results in `p_ready`%
    /// (both forked from `rng`) and checks the output handshake; every output is checked
    /// against [`Graph::eval`]. `settle` idle cycles follow the per-frame inputs. Panics at the
    /// first mismatch (see [`Checker`]).
    pub fn run(
        &mut self,
        items: &[Vec<u32>],
        settle: u32,
        rng: &mut Rng,
        (p_valid, p_ready): (u32, u32),
        check: &Checker,
    ) -> RunStats {
        let expected: Vec<Vec<u32>> = items.iter().map(|i| self.graph.eval(i)).collect();
        let (mut src, mut sink) = self.agents(rng, (p_valid, p_ready)).unwrap_or_else(|e| panic!("{e}"));
        let m = &mut self.model;
        m.reset();
        if let Some(first) = items.first() {
            for &(k, port) in &self.uniform {
                let name = &self.graph.inputs[k].name;
                assert!(items.iter().all(|i| i[k] == first[k]), "per-frame input {name} varies");
                m.set_u64(port, first[k] as u64);
            }
        }
        // Idle during the settle cycles: valid low, random data.
        src.drive(m);
        m.set_u64(self.out_ready, 1);
        for _ in 0..settle {
            m.tick();
        }
        for item in items {
            let per_item = self.graph.inputs.iter().zip(item).filter(|(i, _)| !i.uniform);
            src.push(per_item.map(|(_, &v)| vec![v]).collect());
        }
        let mut done = 0usize;
        let (mut start, mut first_accept, mut first_latency) = (None, None, 0u64);
        let limit = m.cycle() + 64 * (items.len() as u64 + 1000) * 100 / p_valid.min(p_ready).max(1) as u64;
        while done < items.len() {
            let cycle = m.cycle();
            check.protocol(cycle, cycle < limit, "no progress: the unit stopped producing results");
            src.drive(m);
            if src.offering() {
                start.get_or_insert(cycle);
            }
            sink.drive(m);
            m.eval();
            if src.sample(m) {
                first_accept.get_or_insert(cycle);
            }
            if let Some(beat) = sink.sample(m, check) {
                if done == 0 {
                    first_latency = cycle - first_accept.unwrap_or(cycle);
                }
                for (o, ((name, id), got)) in self.graph.outputs.iter().zip(&beat).enumerate() {
                    let mask = if self.graph.nodes[*id].ty == Ty::B { 1 } else { u32::MAX };
                    let field = format!("item {done} {name}");
                    check.value(cycle, &field, expected[done][o] as u64, (got[0] & mask) as u64);
                }
                done += 1;
            }
            m.tick();
        }
        RunStats { items: items.len(), cycles: m.cycle() - start.unwrap_or(0), first_latency }
    }
}

fn strs(v: &[String]) -> Vec<&str> {
    v.iter().map(String::as_str).collect()
}
