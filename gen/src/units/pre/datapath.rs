//! The datapath emitter: a golden dataflow [`Graph`] (an [`neo_golden::hwarith::Arith`]
//! program traced by [`neo_golden::hwarith::graph::Trace`]) as one pipelined Verilog module.
//!
//! # Schedule
//! Every node gets the cycle at which its value is ready (ASAP): a per-item input at 0, an
//! operation at the latest of its operands plus its latency ([`Lowering::latency`]). Operands
//! that are ready earlier wait in a per-node shift register (`n<id>_dly_q`, tapped at every
//! depth a user needs). The outputs are aligned to the pipeline's depth, and a valid bit runs
//! alongside (`valid_q`).
//!
//! Nodes that depend only on per-frame inputs and constants are *static*: they run with their
//! enable tied high and feed every user directly, so they settle [`Datapath::settle_cycles`]
//! cycles after a per-frame input changes. Per-frame inputs may change only while the unit is
//! empty, that many cycles before the next item.
//!
//! # Flow control
//! One enable stalls the whole pipeline: `en = out_ready_i | ~out_valid_o`, and
//! `in_ready_o = en`. So the unit accepts one item per cycle while its output is taken.

use super::known_bits::{Analysis, InputContract, KnownBits};
use crate::emit::expr::hex;
use crate::emit::{conns, if_, set, Instance, Item, Module};
use neo_golden::hwarith::graph::{Graph, NodeId, Op, Ty};

/// The combinational comparator and its outputs.
const COMPARE_MODULE: &str = crate::units::fp::cmp::NAME;
const COMPARE_OUTPUTS: [&str; 5] = ["lt_o", "le_o", "eq_o", "max_o", "min_o"];

/// A pipelined primitive module: `module(clk_i, en_i, a_i[, b_i], y_o)`, result `latency`
/// enabled cycles after its operands.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Primitive {
    /// Module name.
    pub module: String,
    /// Enabled cycles from operands to result (at least 1).
    pub latency: u32,
    /// Operand port names, in the operation's operand order.
    pub ports: Vec<&'static str>,
    /// Parameter overrides of every instance (`(parameter, value)`: `to_int`'s `ROUNDING`).
    pub params: Vec<(String, String)>,
}

/// How the datapath realises one operation.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Lowering {
    /// An instance of a pipelined primitive.
    Primitive(Primitive),
    /// One output of the combinational comparator `neo_fp_cmp` (operands `a_i`, `b_i`),
    /// registered (latency 1).
    Compare {
        /// The output port used (`lt_o`, `le_o`, `eq_o`, `max_o`, `min_o`).
        output: &'static str,
    },
    /// A combinational expression of the operand wires `$0`, `$1`, `$2`; `registered`
    /// puts one register behind it (latency 1), else it is wiring (latency 0).
    Inline {
        /// The expression template.
        expr: String,
        /// Whether the result is registered.
        registered: bool,
    },
}

impl Lowering {
    /// Cycles from operands to result.
    pub fn latency(&self) -> u32 {
        match self {
            Lowering::Primitive(p) => p.latency,
            Lowering::Inline { registered, .. } => *registered as u32,
            Lowering::Compare { .. } => 1,
        }
    }
}

/// The library the emitter lowers operations with: pipelined primitives for the arithmetic,
/// inline logic for the rest.
pub trait Library {
    /// The lowering of `op` (operands are node ids; the lowering refers to them by position).
    fn lower(&self, op: &Op, ty: Ty) -> Lowering;
}

/// A scheduled graph, ready to print.
pub struct Datapath<'a> {
    graph: &'a Graph,
    lowering: Vec<Lowering>,
    /// Cycle at which each node is ready (`None`: static).
    ready: Vec<Option<u32>>,
    /// Pipeline depth: the cycle at which every output is ready.
    depth: u32,
}

impl<'a> Datapath<'a> {
    /// Schedules `graph` with `lib`.
    ///
    /// # Panics
    /// When the graph has no per-item output (a depth of 0 is not a pipeline).
    pub fn new(graph: &'a Graph, lib: &dyn Library) -> Self {
        let lowering: Vec<Lowering> = graph.nodes.iter().map(|n| lib.lower(&n.op, n.ty)).collect();
        let mut ready: Vec<Option<u32>> = Vec::with_capacity(graph.nodes.len());
        for (id, n) in graph.nodes.iter().enumerate() {
            let r = match n.op {
                Op::Input(k) => (!graph.inputs[k].uniform).then_some(0),
                Op::Lit(_) => None,
                op => op.args().iter().filter_map(|&a| ready[a]).max().map(|s| s + lowering[id].latency()),
            };
            ready.push(r);
        }
        let depth = graph.outputs.iter().filter_map(|&(_, id)| ready[id]).max().unwrap_or(0).max(1);
        Datapath { graph, lowering, ready, depth }
    }

    /// Cycles from an item's acceptance to its result on the outputs (with the output taken).
    pub fn depth(&self) -> u32 {
        self.depth
    }

    /// Cycles static nodes need to settle after a per-frame input changes.
    pub fn settle_cycles(&self) -> u32 {
        let mut settle = vec![0u32; self.graph.nodes.len()];
        for (id, n) in self.graph.nodes.iter().enumerate() {
            if self.ready[id].is_none() {
                let s = n.op.args().iter().map(|&a| settle[a]).max().unwrap_or(0);
                settle[id] = s + self.lowering[id].latency();
            }
        }
        settle.into_iter().max().unwrap_or(0)
    }

    /// The cycle at which operation `id` starts (its operands are needed).
    fn start(&self, id: NodeId) -> Option<u32> {
        self.ready[id].map(|r| r - self.lowering[id].latency())
    }

    /// The delays at which each node's value is needed beyond its ready cycle.
    fn taps(&self) -> Vec<Vec<u32>> {
        let mut taps = vec![Vec::new(); self.graph.nodes.len()];
        let need = |node: NodeId, at: u32, taps: &mut Vec<Vec<u32>>| {
            if let Some(r) = self.ready[node] {
                if at > r && !taps[node].contains(&(at - r)) {
                    taps[node].push(at - r);
                }
            }
        };
        for id in 0..self.graph.nodes.len() {
            if let Some(s) = self.start(id) {
                for a in self.graph.nodes[id].op.args() {
                    need(a, s, &mut taps);
                }
            }
        }
        for &(_, id) in &self.graph.outputs {
            need(id, self.depth, &mut taps);
        }
        for t in &mut taps {
            t.sort_unstable();
        }
        taps
    }

    /// The name of node `id`'s value: the input's, or the one the program gave it
    /// ([`neo_golden::hwarith::Arith::name_f`], an output's name otherwise), if any.
    fn value_name(&self, id: NodeId) -> Option<&str> {
        match self.graph.nodes[id].op {
            Op::Input(k) => Some(&self.graph.inputs[k].name),
            _ => self.graph.name_of(id),
        }
    }

    /// The stem of node `id`'s nets and instance: `n<id>_<name>` for a named value, else `n<id>`.
    fn stem(&self, id: NodeId) -> String {
        match self.value_name(id) {
            Some(name) => format!("n{id}_{name}"),
            None => format!("n{id}"),
        }
    }

    /// The net holding node `id`'s value: the stem, with the operation (`n<id>_<op>`) when the
    /// value has no name, and `_q` when it is a register.
    fn name(&self, id: NodeId) -> String {
        let mut net = self.stem(id);
        if self.value_name(id).is_none() {
            let op = format!("{:?}", self.graph.nodes[id].op);
            net = format!("{net}_{}", op.split('(').next().unwrap_or("").to_lowercase());
        }
        let registered =
            matches!(self.lowering[id], Lowering::Inline { registered: true, .. } | Lowering::Compare { .. })
                && !matches!(self.graph.nodes[id].op, Op::Input(_) | Op::Lit(_));
        if registered {
            net.push_str("_q");
        }
        net
    }

    /// The delay line's tap of node `id` `t` cycles after its value is ready.
    fn tap(&self, id: NodeId, t: u32) -> String {
        format!("{}_d{t}", self.stem(id))
    }

    /// The shift register of node `id`'s delay line.
    fn delay_reg(&self, id: NodeId) -> String {
        format!("{}_dly_q", self.stem(id))
    }

    /// The wire of node `id`'s comparator output `port` (`lt_o` -> `<stem>_cmp_lt`).
    fn compare_net(&self, id: NodeId, port: &str) -> String {
        format!("{}_cmp_{}", self.stem(id), port.trim_end_matches("_o"))
    }

    /// The net carrying node `node`'s value as seen at cycle `at`.
    fn value_at(&self, node: NodeId, at: u32) -> String {
        match self.ready[node] {
            Some(r) if at > r => self.tap(node, at - r),
            _ => self.name(node),
        }
    }

    /// Prints the datapath as module `name` with the doc lines `doc`.
    #[track_caller]
    pub fn module(&self, name: &str, doc: &[String]) -> Module {
        let mut m = Module::new(name);
        for d in doc {
            m.doc(d);
        }
        m.doc(format!(
            "Pipelined datapath (gen/src/units/pre/datapath.rs): depth {} cycles, one item per cycle; \
             per-frame inputs settle in {} cycles.",
            self.depth,
            self.settle_cycles()
        ));
        self.ports(&mut m);
        self.control(&mut m);
        let taps = self.taps();
        for (id, node_taps) in taps.iter().enumerate() {
            self.node(&mut m, id);
            self.delay_line(&mut m, id, node_taps);
        }
        for (name, id) in &self.graph.outputs {
            let v = self.value_at(*id, self.depth);
            m.assign(format!("out_{name}_o"), v);
        }
        let unused: Vec<String> = self.unread_compare_nets().into_iter().map(|(net, _)| net).collect();
        if !unused.is_empty() {
            m.wire_assign("unused_cmp", 1, format!("^{{{}}}", unused.join(", ")));
        }
        let partial = self.partially_read();
        if !partial.is_empty() {
            m.wire_assign("unused_bits", 1, format!("^{{{}}}", partial.join(", ")));
        }
        m
    }

    /// The comparator outputs no logic reads, with their widths (each compare node uses one of
    /// the five; the others are reduced into the `unused_cmp` lint sink).
    pub fn unread_compare_nets(&self) -> Vec<(String, u32)> {
        self.lowering
            .iter()
            .enumerate()
            .filter_map(|(id, l)| match l {
                Lowering::Compare { output } => Some(
                    COMPARE_OUTPUTS
                        .iter()
                        .filter(move |o| *o != output)
                        .map(move |o| (self.compare_net(id, o), compare_ty(o).bits())),
                ),
                _ => None,
            })
            .flatten()
            .collect()
    }

    /// The operand nets of operations that read only some of their bits (`abs` and `is_nan`
    /// drop the sign, `exp_field` and `is_finite` read the exponent): reduced into
    /// `unused_bits`, Verilator's convention for bits left unread by design.
    fn partially_read(&self) -> Vec<String> {
        let mut nets: Vec<String> = Vec::new();
        for (id, n) in self.graph.nodes.iter().enumerate() {
            if let Op::Abs(a) | Op::IsNan(a) | Op::ExpField(a) | Op::IsFinite(a) = n.op {
                let net = self.operand(id, a);
                if !nets.contains(&net) {
                    nets.push(net);
                }
            }
        }
        nets
    }

    fn ports(&self, m: &mut Module) {
        m.clock_reset();
        for i in self.graph.inputs.iter().filter(|i| i.uniform) {
            m.input_c(format!("{}_i", i.name), i.ty.bits(), "per frame");
        }
        m.input_c("in_valid_i", 1, "an item is offered");
        m.output_c("in_ready_o", 1, "the item is taken");
        for i in self.graph.inputs.iter().filter(|i| !i.uniform) {
            m.input(format!("in_{}_i", i.name), i.ty.bits());
        }
        m.output_c("out_valid_o", 1, "a result is offered");
        m.input_c("out_ready_i", 1, "the result is taken");
        for (name, id) in &self.graph.outputs {
            m.output(format!("out_{name}_o"), self.graph.nodes[*id].ty.bits());
        }
    }

    fn control(&self, m: &mut Module) {
        let d = self.depth;
        m.reg("valid_q", d);
        m.wire_assign("en", 1, "out_ready_i | ~out_valid_o");
        m.assign("in_ready_o", "en");
        let shifted =
            if d == 1 { "in_valid_i".to_string() } else { format!("{{valid_q[{}:0], in_valid_i}}", d - 2) };
        let reset = m.q_resets(&[]);
        m.seq(reset, vec![if_("en", vec![set("valid_q", shifted)])]);
        m.assign("out_valid_o", format!("valid_q[{}]", d - 1));
    }

    /// The net through which node `id` reads its operand `a`: `a` delayed to the cycle `id`
    /// starts, or `a` itself when `id` is static.
    fn operand(&self, id: NodeId, a: NodeId) -> String {
        match self.start(id) {
            Some(s) => self.value_at(a, s),
            None => self.name(a),
        }
    }

    /// Declares and drives `n<id>`.
    fn node(&self, m: &mut Module, id: NodeId) {
        let n = &self.graph.nodes[id];
        let w = n.ty.bits();
        let args: Vec<String> = n.op.args().into_iter().map(|a| self.operand(id, a)).collect();
        let en = if self.ready[id].is_some() { "en" } else { "1'b1" };
        let out = self.name(id);
        match (&n.op, &self.lowering[id]) {
            (Op::Input(k), _) => {
                let i = &self.graph.inputs[*k];
                let port = if i.uniform { format!("{}_i", i.name) } else { format!("in_{}_i", i.name) };
                m.wire_assign(out, w, port);
            }
            (Op::Lit(v), _) => {
                m.wire_assign(out, w, hex(w, *v as u64));
            }
            (_, Lowering::Inline { expr, registered }) => {
                let e = fill(expr, &args);
                if *registered {
                    m.reg(&out, w);
                    let update = set(&out, e);
                    m.seq_noreset(if self.ready[id].is_some() {
                        vec![if_("en", vec![update])]
                    } else {
                        vec![update]
                    });
                } else {
                    m.wire_assign(out, w, e);
                }
            }
            (_, Lowering::Compare { output }) => {
                let mut c: Vec<(&str, String)> = vec![("a_i", args[0].clone()), ("b_i", args[1].clone())];
                for o in COMPARE_OUTPUTS {
                    let wire = self.compare_net(id, o);
                    m.wire(&wire, compare_ty(o).bits());
                    c.push((o, wire));
                }
                m.item(Item::Instance(Instance {
                    module: COMPARE_MODULE.into(),
                    name: format!("u_{}", self.stem(id)),
                    params: Vec::new(),
                    conns: conns(&c),
                }));
                m.reg(&out, w);
                let update = set(&out, self.compare_net(id, output));
                m.seq_noreset(if self.ready[id].is_some() {
                    vec![if_("en", vec![update])]
                } else {
                    vec![update]
                });
            }
            (_, Lowering::Primitive(p)) => {
                m.wire(&out, w);
                let mut c: Vec<(&str, String)> = vec![("clk_i", "clk_i".into()), ("en_i", en.into())];
                for (port, a) in p.ports.iter().zip(&args) {
                    c.push((port, a.clone()));
                }
                c.push(("y_o", out));
                m.item(Item::Instance(Instance {
                    module: p.module.clone(),
                    name: format!("u_{}", self.stem(id)),
                    params: p.params.clone(),
                    conns: conns(&c),
                }));
            }
        }
    }

    /// The shift register delaying node `id` by each of `taps` (ascending) cycles.
    fn delay_line(&self, m: &mut Module, id: NodeId, taps: &[u32]) {
        let Some(&longest) = taps.last() else { return };
        let w = self.graph.nodes[id].ty.bits();
        let src = self.name(id);
        let reg = self.delay_reg(id);
        m.reg(&reg, w * longest);
        let next = if longest == 1 { src } else { format!("{{{reg}[{}:0], {src}}}", w * (longest - 1) - 1) };
        m.seq_noreset(vec![if_("en", vec![set(&reg, next)])]);
        for &t in taps {
            let tap =
                if w * longest == 1 { reg.clone() } else { format!("{reg}[{}:{}]", w * t - 1, w * (t - 1)) };
            m.wire_assign(self.tap(id, t), w, tap);
        }
    }
}

/// Bits of one net of a datapath proven constant ([`Datapath::constant_bits`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ConstantBits {
    /// The net (a node's net, its delay taps and shift register, a comparator output, an
    /// output port).
    pub net: String,
    /// Its width.
    pub width: u32,
    /// The constant bits, as inclusive `(hi, lo)` ranges, ascending.
    pub ranges: Vec<(u32, u32)>,
    /// Why ([`KnownBits::reason`]).
    pub reason: String,
}

impl Datapath<'_> {
    /// The bits of the module's nets that the known-bits analysis ([`Analysis`]) proves
    /// constant: every node's net, its delay taps `n<id>_d<t>` and every copy in its shift
    /// register `n<id>_dly_q`, each comparator's five outputs `n<id>_cmp_*` (of the node's
    /// operands), and the output ports `out_<name>_o`. Inputs are constant only where
    /// `contracts` bound them (then their ports `<name>_i` are listed too).
    pub fn constant_bits(&self, contracts: &[InputContract]) -> Vec<ConstantBits> {
        let a = Analysis::with_contracts(self.graph, contracts);
        let mut out = Vec::new();
        let mut push = |net: String, width: u32, k: &KnownBits, copies: u32| {
            let mask = if width == 32 { k.mask } else { k.mask & ((1 << width) - 1) };
            if mask == 0 {
                return;
            }
            let mut ranges = Vec::new();
            for c in 0..copies {
                let mut b = 0;
                while b < width {
                    if mask >> b & 1 == 0 {
                        b += 1;
                        continue;
                    }
                    let lo = b;
                    while b < width && mask >> b & 1 == 1 {
                        b += 1;
                    }
                    ranges.push((c * width + b - 1, c * width + lo));
                }
            }
            out.push(ConstantBits { net, width: width * copies, ranges, reason: k.reason.clone() });
        };
        let taps = self.taps();
        for (id, n) in self.graph.nodes.iter().enumerate() {
            let w = n.ty.bits();
            let k = a.node(id);
            match n.op {
                Op::Input(i) => {
                    let input = &self.graph.inputs[i];
                    if contracts.iter().any(|c| c.input == input.name) {
                        push(self.name(id), w, &k, 1);
                        push(format!("{}_i", input.name), w, &k, 1);
                    }
                }
                _ => push(self.name(id), w, &k, 1),
            }
            if let Some(&longest) = taps[id].last() {
                for t in &taps[id] {
                    push(self.tap(id, *t), w, &k, 1);
                }
                push(self.delay_reg(id), w, &k, longest);
            }
            if let (Lowering::Compare { .. }, [p, q]) = (&self.lowering[id], n.op.args().as_slice()) {
                let (p, q) = (*p, *q);
                let ops = [Op::Lt(p, q), Op::Le(p, q), Op::Eq(p, q), Op::Max(p, q), Op::Min(p, q)];
                for (port, op) in COMPARE_OUTPUTS.iter().zip(ops) {
                    let ty = compare_ty(port);
                    push(self.compare_net(id, port), ty.bits(), &a.op(&op, ty), 1);
                }
            }
        }
        for (name, id) in &self.graph.outputs {
            push(format!("out_{name}_o"), self.graph.nodes[*id].ty.bits(), &a.node(*id), 1);
        }
        out
    }
}

/// The type of the comparator's output `port`: `max_o` and `min_o` are binary32, the others
/// booleans.
fn compare_ty(port: &str) -> Ty {
    if port.starts_with('m') {
        Ty::F
    } else {
        Ty::B
    }
}

/// `template` with `$k` replaced by `args[k]` (highest k first, so `$1` never eats `$10`).
fn fill(template: &str, args: &[String]) -> String {
    let mut s = template.to_string();
    for (k, a) in args.iter().enumerate().rev() {
        s = s.replace(&format!("${k}"), a);
    }
    s
}
