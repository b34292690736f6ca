//! [`Trace`]: records an [`Arith`] program as a dataflow [`Graph`], the form gen turns into a
//! pipelined datapath. Nodes are hash-consed (a repeated operation on the same operands is
//! one node), and [`Graph::eval`] evaluates a graph with [`Native`], so tests can check that
//! the recorded graph computes exactly what the program computes.

use super::{Arith, Native, Round};
use std::collections::HashMap;

/// The type of a node's value.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize)]
pub enum Ty {
    /// binary32.
    F,
    /// 32-bit integer.
    I,
    /// boolean.
    B,
}

impl Ty {
    /// Width of the value in bits.
    pub fn bits(self) -> u32 {
        match self {
            Ty::F | Ty::I => 32,
            Ty::B => 1,
        }
    }
}

/// Index of a node in [`Graph::nodes`].
pub type NodeId = usize;

/// One operation of the graph: an [`Arith`] method with its operands (node ids).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize)]
#[allow(missing_docs)] // each variant is the `Arith` method of the same name
pub enum Op {
    /// Input `k` of [`Graph::inputs`].
    Input(usize),
    /// A constant: binary32 bits, integer bits or 0/1, by [`Node::ty`].
    Lit(u32),
    Add(NodeId, NodeId),
    Sub(NodeId, NodeId),
    Mul(NodeId, NodeId),
    Div(NodeId, NodeId),
    Sqrt(NodeId),
    Neg(NodeId),
    Abs(NodeId),
    Max(NodeId, NodeId),
    Min(NodeId, NodeId),
    Lt(NodeId, NodeId),
    Le(NodeId, NodeId),
    Eq(NodeId, NodeId),
    IsNan(NodeId),
    IsFinite(NodeId),
    ToInt(NodeId, Round),
    IntToFloat(NodeId),
    ExpField(NodeId),
    Pow2Field(NodeId),
    F16Bits(NodeId),
    WidenHalf(NodeId),
    IAdd(NodeId, NodeId),
    ISub(NodeId, NodeId),
    IMin(NodeId, NodeId),
    IMax(NodeId, NodeId),
    ILt(NodeId, NodeId),
    IEq(NodeId, NodeId),
    And(NodeId, NodeId),
    Or(NodeId, NodeId),
    Not(NodeId),
    Select(NodeId, NodeId, NodeId),
    ISelect(NodeId, NodeId, NodeId),
}

impl Op {
    /// The operand node ids, in order.
    pub fn args(&self) -> Vec<NodeId> {
        use Op::*;
        match *self {
            Input(_) | Lit(_) => vec![],
            Sqrt(a)
            | Neg(a)
            | Abs(a)
            | IsNan(a)
            | IsFinite(a)
            | ToInt(a, _)
            | IntToFloat(a)
            | ExpField(a)
            | Pow2Field(a)
            | F16Bits(a)
            | WidenHalf(a)
            | Not(a) => vec![a],
            Add(a, b)
            | Sub(a, b)
            | Mul(a, b)
            | Div(a, b)
            | Max(a, b)
            | Min(a, b)
            | Lt(a, b)
            | Le(a, b)
            | Eq(a, b)
            | IAdd(a, b)
            | ISub(a, b)
            | IMin(a, b)
            | IMax(a, b)
            | ILt(a, b)
            | IEq(a, b)
            | And(a, b)
            | Or(a, b) => vec![a, b],
            Select(c, a, b) | ISelect(c, a, b) => vec![c, a, b],
        }
    }
}

/// A node: its operation and the type of its value.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize)]
pub struct Node {
    /// The operation.
    pub op: Op,
    /// The value's type.
    pub ty: Ty,
}

/// A named input of the graph.
#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize)]
pub struct Input {
    /// Port name (without direction suffix).
    pub name: String,
    /// The value's type.
    pub ty: Ty,
    /// Constant for a whole frame (a register the host writes), rather than one value per item.
    pub uniform: bool,
}

/// A dataflow graph: nodes in topological order (operands before users), named inputs and
/// outputs.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct Graph {
    /// Every node; a node's operands have smaller ids.
    pub nodes: Vec<Node>,
    /// The inputs ([`Op::Input`] `k` is `inputs[k]`).
    pub inputs: Vec<Input>,
    /// The outputs: name and node.
    pub outputs: Vec<(String, NodeId)>,
    /// The ranges the program asserts of its values ([`Arith::assume_f`], [`Arith::assume_i`]).
    pub assumptions: Vec<Assumption>,
    /// The names the program gives its values ([`Arith::name_f`]), one per node at most, in
    /// node order.
    pub names: Vec<(NodeId, String)>,
}

impl Graph {
    /// The name the program gave node `id`, if any.
    pub fn name_of(&self, id: NodeId) -> Option<&str> {
        self.names.binary_search_by_key(&id, |(n, _)| *n).ok().map(|k| self.names[k].1.as_str())
    }
}

/// A range a node's value always lies in, as the program asserts it ([`Arith::assume_f`]).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Assumption {
    /// The node.
    pub node: NodeId,
    /// The range.
    pub range: AssumedRange,
    /// Why it holds.
    pub why: &'static str,
}

/// The range of an [`Assumption`], inclusive.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub enum AssumedRange {
    /// A binary32 in `[lo, hi]` (never NaN).
    F(f32, f32),
    /// An integer in `[lo, hi]`.
    I(i32, i32),
    /// A binary32 that is a zero or of magnitude in `[lo, hi]` (`0 < lo`; never NaN).
    ZeroOr(f32, f32),
}

impl AssumedRange {
    /// Whether a node's raw bits `v` lie in the range.
    pub fn admits(&self, v: u32) -> bool {
        match *self {
            AssumedRange::F(lo, hi) => (lo..=hi).contains(&f32::from_bits(v)),
            AssumedRange::I(lo, hi) => (lo..=hi).contains(&(v as i32)),
            AssumedRange::ZeroOr(lo, hi) => {
                let x = f32::from_bits(v);
                x == 0.0 || (lo..=hi).contains(&x.abs())
            }
        }
    }
}

/// A binary32 value of a traced program.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FNode(pub NodeId);
/// An integer value of a traced program.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct INode(pub NodeId);
/// A boolean value of a traced program.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BNode(pub NodeId);

/// Records [`Arith`] calls into a [`Graph`].
#[derive(Debug, Default)]
pub struct Trace {
    graph: Graph,
    seen: HashMap<Node, NodeId>,
}

impl Trace {
    /// An empty trace.
    pub fn new() -> Self {
        Self::default()
    }

    fn node(&mut self, op: Op, ty: Ty) -> NodeId {
        let n = Node { op, ty };
        if let Some(&id) = self.seen.get(&n) {
            return id;
        }
        let id = self.graph.nodes.len();
        self.graph.nodes.push(n);
        self.seen.insert(n, id);
        id
    }

    fn input(&mut self, name: &str, ty: Ty, uniform: bool) -> NodeId {
        assert!(self.graph.inputs.iter().all(|i| i.name != name), "input {name} declared twice");
        self.graph.inputs.push(Input { name: name.into(), ty, uniform });
        self.node(Op::Input(self.graph.inputs.len() - 1), ty)
    }

    /// A binary32 input; `uniform` for a per-frame register.
    pub fn input_f(&mut self, name: &str, uniform: bool) -> FNode {
        FNode(self.input(name, Ty::F, uniform))
    }

    /// An integer input; `uniform` for a per-frame register.
    pub fn input_i(&mut self, name: &str, uniform: bool) -> INode {
        INode(self.input(name, Ty::I, uniform))
    }

    /// Records `name` for node `id` unless it has one; inputs and literals keep their own nets.
    fn name(&mut self, id: NodeId, name: &str) {
        let valid = name.bytes().next().is_some_and(|b| b.is_ascii_lowercase())
            && name.bytes().all(|b| b.is_ascii_lowercase() || b.is_ascii_digit() || b == b'_');
        assert!(valid, "value name {name:?}: lower case letters, digits and _, a letter first");
        let plain = !matches!(self.graph.nodes[id].op, Op::Input(_) | Op::Lit(_));
        if plain && self.graph.names.iter().all(|(n, _)| *n != id) {
            self.graph.names.push((id, name.to_string()));
        }
    }

    /// Declares output `name`; its node takes the name too if the program gave it none.
    fn output(&mut self, name: &str, id: NodeId) {
        assert!(self.graph.outputs.iter().all(|(n, _)| n != name), "output {name} declared twice");
        self.name(id, name);
        self.graph.outputs.push((name.into(), id));
    }

    /// Names a binary32 result as an output.
    pub fn output_f(&mut self, name: &str, v: FNode) {
        self.output(name, v.0)
    }

    /// Names an integer result as an output.
    pub fn output_i(&mut self, name: &str, v: INode) {
        self.output(name, v.0)
    }

    /// Names a boolean result as an output.
    pub fn output_b(&mut self, name: &str, v: BNode) {
        self.output(name, v.0)
    }

    /// The recorded graph, without the nodes no output depends on (ids renumbered, order kept;
    /// the assumptions of the nodes kept).
    pub fn finish(self) -> Graph {
        let g = self.graph;
        let mut live = vec![false; g.nodes.len()];
        for &(_, id) in &g.outputs {
            live[id] = true;
        }
        for id in (0..g.nodes.len()).rev() {
            if live[id] {
                for a in g.nodes[id].op.args() {
                    live[a] = true;
                }
            }
        }
        let mut new_id = vec![usize::MAX; g.nodes.len()];
        let mut nodes = Vec::new();
        for (id, n) in g.nodes.iter().enumerate() {
            if live[id] {
                new_id[id] = nodes.len();
                nodes.push(Node { op: renumber(n.op, &new_id), ty: n.ty });
            }
        }
        let outputs = g.outputs.iter().map(|(name, id)| (name.clone(), new_id[*id])).collect();
        let assumptions = g
            .assumptions
            .iter()
            .filter(|a| live[a.node])
            .map(|a| Assumption { node: new_id[a.node], ..*a })
            .collect();
        let mut names: Vec<(NodeId, String)> =
            g.names.into_iter().filter(|(id, _)| live[*id]).map(|(id, name)| (new_id[id], name)).collect();
        names.sort_unstable();
        Graph { nodes, inputs: g.inputs, outputs, assumptions, names }
    }
}

/// `op` with its operands mapped through `map`.
fn renumber(op: Op, map: &[NodeId]) -> Op {
    use Op::*;
    let m = |a: NodeId| map[a];
    match op {
        Input(k) => Input(k),
        Lit(v) => Lit(v),
        Add(a, b) => Add(m(a), m(b)),
        Sub(a, b) => Sub(m(a), m(b)),
        Mul(a, b) => Mul(m(a), m(b)),
        Div(a, b) => Div(m(a), m(b)),
        Sqrt(a) => Sqrt(m(a)),
        Neg(a) => Neg(m(a)),
        Abs(a) => Abs(m(a)),
        Max(a, b) => Max(m(a), m(b)),
        Min(a, b) => Min(m(a), m(b)),
        Lt(a, b) => Lt(m(a), m(b)),
        Le(a, b) => Le(m(a), m(b)),
        Eq(a, b) => Eq(m(a), m(b)),
        IsNan(a) => IsNan(m(a)),
        IsFinite(a) => IsFinite(m(a)),
        ToInt(a, r) => ToInt(m(a), r),
        IntToFloat(a) => IntToFloat(m(a)),
        ExpField(a) => ExpField(m(a)),
        Pow2Field(a) => Pow2Field(m(a)),
        F16Bits(a) => F16Bits(m(a)),
        WidenHalf(a) => WidenHalf(m(a)),
        IAdd(a, b) => IAdd(m(a), m(b)),
        ISub(a, b) => ISub(m(a), m(b)),
        IMin(a, b) => IMin(m(a), m(b)),
        IMax(a, b) => IMax(m(a), m(b)),
        ILt(a, b) => ILt(m(a), m(b)),
        IEq(a, b) => IEq(m(a), m(b)),
        And(a, b) => And(m(a), m(b)),
        Or(a, b) => Or(m(a), m(b)),
        Not(a) => Not(m(a)),
        Select(c, a, b) => Select(m(c), m(a), m(b)),
        ISelect(c, a, b) => ISelect(m(c), m(a), m(b)),
    }
}

/// One traced [`Arith`] method: `name, Op variant, result type, result handle, operands`.
macro_rules! traced {
    ($name:ident, $op:ident, $ty:ident, $handle:ident, $($arg:ident : $argty:ty),+) => {
        fn $name(&mut self, $($arg: $argty),+) -> $handle {
            $handle(self.node(Op::$op($($arg.0),+), Ty::$ty))
        }
    };
}

impl Arith for Trace {
    type F = FNode;
    type I = INode;
    type B = BNode;

    fn assume_f(&mut self, x: FNode, lo: f32, hi: f32, why: &'static str) {
        let range = AssumedRange::F(lo, hi);
        self.graph.assumptions.push(Assumption { node: x.0, range, why });
    }
    fn assume_i(&mut self, x: INode, lo: i32, hi: i32, why: &'static str) {
        let range = AssumedRange::I(lo, hi);
        self.graph.assumptions.push(Assumption { node: x.0, range, why });
    }
    fn assume_zero_or(&mut self, x: FNode, lo: f32, hi: f32, why: &'static str) {
        let range = AssumedRange::ZeroOr(lo, hi);
        self.graph.assumptions.push(Assumption { node: x.0, range, why });
    }

    fn name_f(&mut self, x: FNode, name: &'static str) -> FNode {
        self.name(x.0, name);
        x
    }
    fn name_i(&mut self, x: INode, name: &'static str) -> INode {
        self.name(x.0, name);
        x
    }
    fn name_b(&mut self, x: BNode, name: &'static str) -> BNode {
        self.name(x.0, name);
        x
    }

    fn lit(&mut self, v: f32) -> FNode {
        FNode(self.node(Op::Lit(v.to_bits()), Ty::F))
    }
    fn ilit(&mut self, v: i32) -> INode {
        INode(self.node(Op::Lit(v as u32), Ty::I))
    }
    fn blit(&mut self, v: bool) -> BNode {
        BNode(self.node(Op::Lit(v as u32), Ty::B))
    }
    traced!(add, Add, F, FNode, a: FNode, b: FNode);
    traced!(sub, Sub, F, FNode, a: FNode, b: FNode);
    traced!(mul, Mul, F, FNode, a: FNode, b: FNode);
    traced!(div, Div, F, FNode, a: FNode, b: FNode);
    traced!(sqrt, Sqrt, F, FNode, a: FNode);
    traced!(neg, Neg, F, FNode, a: FNode);
    traced!(abs, Abs, F, FNode, a: FNode);
    traced!(max, Max, F, FNode, a: FNode, b: FNode);
    traced!(min, Min, F, FNode, a: FNode, b: FNode);
    traced!(lt, Lt, B, BNode, a: FNode, b: FNode);
    traced!(le, Le, B, BNode, a: FNode, b: FNode);
    traced!(eq, Eq, B, BNode, a: FNode, b: FNode);
    traced!(is_nan, IsNan, B, BNode, a: FNode);
    traced!(is_finite, IsFinite, B, BNode, a: FNode);
    fn to_int(&mut self, a: FNode, mode: Round) -> INode {
        INode(self.node(Op::ToInt(a.0, mode), Ty::I))
    }
    traced!(int_to_float, IntToFloat, F, FNode, i: INode);
    traced!(exp_field, ExpField, I, INode, a: FNode);
    traced!(pow2_field, Pow2Field, F, FNode, e: INode);
    traced!(f16_bits, F16Bits, I, INode, a: FNode);
    traced!(widen_half, WidenHalf, F, FNode, h: INode);
    traced!(iadd, IAdd, I, INode, a: INode, b: INode);
    traced!(isub, ISub, I, INode, a: INode, b: INode);
    traced!(imin, IMin, I, INode, a: INode, b: INode);
    traced!(imax, IMax, I, INode, a: INode, b: INode);
    traced!(ilt, ILt, B, BNode, a: INode, b: INode);
    traced!(ieq, IEq, B, BNode, a: INode, b: INode);
    traced!(and, And, B, BNode, a: BNode, b: BNode);
    traced!(or, Or, B, BNode, a: BNode, b: BNode);
    traced!(not, Not, B, BNode, a: BNode);
    traced!(select, Select, F, FNode, c: BNode, a: FNode, b: FNode);
    traced!(iselect, ISelect, I, INode, c: BNode, a: INode, b: INode);
}

impl Graph {
    /// Evaluates the graph with [`Native`] on one item: `inputs[k]` is the raw bits of input `k`
    /// (binary32 bits, integer bits, or 0/1). Returns the outputs' raw bits in order.
    ///
    /// # Panics
    /// When `inputs` does not have one value per input, or a value breaks one of the graph's
    /// [`Assumption`]s (a wrong proof: the known-bits analysis relies on them).
    pub fn eval(&self, inputs: &[u32]) -> Vec<u32> {
        let v = self.eval_nodes(inputs);
        self.outputs.iter().map(|&(_, id)| v[id]).collect()
    }

    /// [`Graph::eval`]'s value of every node (the raw bits the datapath's node nets carry).
    ///
    /// # Panics
    /// As [`Graph::eval`].
    pub fn eval_nodes(&self, inputs: &[u32]) -> Vec<u32> {
        assert_eq!(inputs.len(), self.inputs.len(), "one value per graph input");
        let mut v: Vec<u32> = Vec::with_capacity(self.nodes.len());
        for n in &self.nodes {
            let x = eval_op(&n.op, n.ty, &v, inputs);
            v.push(x);
        }
        for a in &self.assumptions {
            assert!(
                a.range.admits(v[a.node]),
                "assumption of node {} broken: {} ({:?}, value {:#010x}; inputs {inputs:08x?})",
                a.node,
                a.why,
                a.range,
                v[a.node]
            );
        }
        v
    }
}

/// The raw bits of one node's value: operation `op` of result type `ty` evaluated with
/// [`Native`] on the raw bits `v` of the nodes before it (an operand id indexes `v`) and the
/// item's `inputs` (for [`Op::Input`]). The one mapping from an operation to its [`Native`]
/// arithmetic: [`Graph::eval`] runs it node by node, and the benches of single primitives
/// (`tb/src/fp.rs`) run it on their operands as nodes 0 and 1.
///
/// # Panics
/// When an operand id or input index is out of range.
pub fn eval_op(op: &Op, ty: Ty, v: &[u32], inputs: &[u32]) -> u32 {
    use Op::*;
    let a = &mut Native;
    let f = |id: NodeId| f32::from_bits(v[id]);
    let i = |id: NodeId| v[id] as i32;
    let b = |id: NodeId| v[id] != 0;
    let fb = |x: f32| x.to_bits();
    match *op {
        Input(k) => match ty {
            Ty::B => (inputs[k] != 0) as u32,
            _ => inputs[k],
        },
        Lit(x) => x,
        Add(x, y) => fb(a.add(f(x), f(y))),
        Sub(x, y) => fb(a.sub(f(x), f(y))),
        Mul(x, y) => fb(a.mul(f(x), f(y))),
        Div(x, y) => fb(a.div(f(x), f(y))),
        Sqrt(x) => fb(a.sqrt(f(x))),
        Neg(x) => fb(a.neg(f(x))),
        Abs(x) => fb(a.abs(f(x))),
        Max(x, y) => fb(a.max(f(x), f(y))),
        Min(x, y) => fb(a.min(f(x), f(y))),
        Lt(x, y) => a.lt(f(x), f(y)) as u32,
        Le(x, y) => a.le(f(x), f(y)) as u32,
        Eq(x, y) => a.eq(f(x), f(y)) as u32,
        IsNan(x) => a.is_nan(f(x)) as u32,
        IsFinite(x) => a.is_finite(f(x)) as u32,
        ToInt(x, r) => a.to_int(f(x), r) as u32,
        IntToFloat(x) => fb(a.int_to_float(i(x))),
        ExpField(x) => a.exp_field(f(x)) as u32,
        Pow2Field(x) => fb(a.pow2_field(i(x))),
        F16Bits(x) => a.f16_bits(f(x)) as u32,
        WidenHalf(x) => fb(a.widen_half(i(x))),
        IAdd(x, y) => a.iadd(i(x), i(y)) as u32,
        ISub(x, y) => a.isub(i(x), i(y)) as u32,
        IMin(x, y) => a.imin(i(x), i(y)) as u32,
        IMax(x, y) => a.imax(i(x), i(y)) as u32,
        ILt(x, y) => a.ilt(i(x), i(y)) as u32,
        IEq(x, y) => a.ieq(i(x), i(y)) as u32,
        And(x, y) => a.and(b(x), b(y)) as u32,
        Or(x, y) => a.or(b(x), b(y)) as u32,
        Not(x) => a.not(b(x)) as u32,
        Select(c, x, y) => fb(a.select(b(c), f(x), f(y))),
        ISelect(c, x, y) => a.iselect(b(c), i(x), i(y)) as u32,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn repeated_operations_share_a_node_and_dead_nodes_are_dropped() {
        let mut t = Trace::new();
        let x = t.input_f("x", false);
        let y = t.input_f("y", false);
        let s1 = t.add(x, y);
        let s2 = t.add(x, y);
        assert_eq!(s1, s2);
        let _dead = t.mul(x, y);
        let p = t.mul(s1, s2);
        t.output_f("p", p);
        let g = t.finish();
        assert_eq!(g.nodes.len(), 4);
        assert_eq!(g.eval(&[2f32.to_bits(), 1f32.to_bits()]), vec![9f32.to_bits()]);
    }

    #[test]
    fn names_follow_their_nodes_and_the_first_one_wins() {
        let mut t = Trace::new();
        let x = t.input_f("x", false);
        let y = t.input_f("y", false);
        let dead = t.mul(x, y);
        t.name_f(dead, "dead");
        let s = t.add(x, y);
        t.name_f(s, "sum");
        let again = t.add(x, y);
        t.name_f(again, "other");
        let named_input = t.name_f(x, "input_name");
        let p = t.mul(s, named_input);
        t.output_f("p", p);
        let g = t.finish();
        // x, y, s, p: the dead product and its name are gone, s renumbered from 3 to 2.
        assert_eq!(g.names, vec![(2, "sum".to_string()), (3, "p".to_string())]);
        assert_eq!(g.name_of(2), Some("sum"));
        assert_eq!(g.name_of(0), None, "an input keeps its port name");
    }

    #[test]
    #[should_panic(expected = "value name \"Sum\"")]
    fn a_name_that_is_no_verilog_identifier_is_refused() {
        let mut t = Trace::new();
        let x = t.input_f("x", false);
        let s = t.add(x, x);
        t.name_f(s, "Sum");
    }
}
