//! Known bits of a datapath's values: a sound forward analysis of a golden dataflow [`Graph`]
//! that proves, per node, which bits of its value are the same for every input (literals, the
//! sign of a square, the upper bits of a clamped integer, an exponent field's upper 24 bits).
//! The coverage report (`neo_tb::coverage`) takes the bits it proves constant in the emitted
//! nets ([`super::datapath::Datapath::constant_bits`]) as justified toggle holes.
//!
//! Sound with respect to golden's semantics of each operation ([`eval_op`]: `Native`, NaN
//! results canonical and positive, `max`/`min` passing the other operand when the first is a
//! NaN, `sqrt(-0) = -0`, `to_int` saturating with NaN giving 0), which the RTL primitives meet
//! bit for bit (their benches, `tb/src/fp.rs`). Abstract values:
//! - binary32: the set of classes the value may be in (±0, ±finite nonzero, ±inf, NaN of
//!   either sign), plus bits an operation fixes (a literal, `abs` clears the sign, `pow2_field`
//!   has a zero mantissa);
//! - integers and booleans: a signed interval (booleans `[0, 1]`), plus bits an operation fixes;
//! - a binary operation on the same node twice (`x * x`, `x - x`) pairs each class with itself.
//!
//! When unsure the analysis says unknown. The tests evaluate the project and colour graphs on
//! random and edge inputs and check every node against its known bits.
//!
//! [`eval_op`]: neo_golden::hwarith::graph::eval_op

use neo_golden::hwarith::graph::{eval_op, AssumedRange, Assumption, Graph, NodeId, Op, Ty};
use neo_golden::hwarith::{Round, CANONICAL_NAN};

/// The bits of a value proven constant: `mask` has the constant bits, `value` their values
/// (zero outside `mask`), `reason` says why (empty when nothing is known).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct KnownBits {
    /// The constant bits.
    pub mask: u32,
    /// Their values.
    pub value: u32,
    /// Why they are constant.
    pub reason: String,
}

impl KnownBits {
    /// Whether `v` agrees with the known bits.
    pub fn admits(&self, v: u32) -> bool {
        v & self.mask == self.value
    }
}

// The binary32 classes (a bit set).
const NAN_P: u16 = 1; // NaN, sign 0, not the canonical one
const NAN_N: u16 = 2; // NaN, sign 1
const NINF: u16 = 4;
const NFIN: u16 = 8; // negative, nonzero, finite (subnormals included)
const NZERO: u16 = 16;
const PZERO: u16 = 32;
const PFIN: u16 = 64;
const PINF: u16 = 128;
const NAN_C: u16 = 256; // the canonical NaN (every arithmetic NaN)
const ALL: u16 = 0x1FF;
const NAN: u16 = NAN_P | NAN_N | NAN_C;
const ZERO: u16 = NZERO | PZERO;
const INF: u16 = NINF | PINF;
/// The classes whose sign bit is 0.
const SIGN0: u16 = NAN_C | NAN_P | PZERO | PFIN | PINF;
/// The classes whose sign bit is 1.
const SIGN1: u16 = NAN_N | NINF | NFIN | NZERO;

const I32: (i64, i64) = (i32::MIN as i64, i32::MAX as i64);

/// The class of binary32 bits `v`.
fn class_of(v: u32) -> u16 {
    let neg = v >> 31 != 0;
    let (exp, mant) = ((v >> 23) & 0xFF, v & 0x7F_FFFF);
    match (exp, mant, neg) {
        (0xFF, 0, false) => PINF,
        (0xFF, 0, true) => NINF,
        (0xFF, _, false) if v == CANONICAL_NAN => NAN_C,
        (0xFF, _, false) => NAN_P,
        (0xFF, _, true) => NAN_N,
        (0, 0, false) => PZERO,
        (0, 0, true) => NZERO,
        (_, _, false) => PFIN,
        (_, _, true) => NFIN,
    }
}

/// The classes of `set`, one at a time.
fn each(set: u16) -> impl Iterator<Item = u16> {
    (0..9).map(|i| 1u16 << i).filter(move |c| set & c != 0)
}

/// The classes of class `c` with the other sign (`-NaN` may be the canonical NaN).
fn negc(c: u16) -> u16 {
    match c {
        NAN_P | NAN_C => NAN_N,
        NAN_N => NAN_P | NAN_C,
        NINF => PINF,
        PINF => NINF,
        NFIN => PFIN,
        PFIN => NFIN,
        NZERO => PZERO,
        _ => NZERO,
    }
}

/// Classes of `set` with the signs flipped.
fn neg_set(set: u16) -> u16 {
    each(set).fold(0, |s, c| s | negc(c))
}

/// Order of the ordered classes (the zeros equal).
fn rank(c: u16) -> u16 {
    match c {
        NINF => 0,
        NFIN => 1,
        NZERO | PZERO => 2,
        PFIN => 3,
        _ => 4,
    }
}

/// `zero`, `fin` or `inf` with sign `neg`.
fn signed(neg: bool, pos: u16) -> u16 {
    if neg {
        neg_set(pos)
    } else {
        pos
    }
}

fn add1(a: u16, b: u16) -> u16 {
    if (a | b) & NAN != 0 {
        return NAN_C;
    }
    match (a, b) {
        (PINF, NINF) | (NINF, PINF) => NAN_C,
        (PINF, _) | (_, PINF) => PINF,
        (NINF, _) | (_, NINF) => NINF,
        (NZERO, NZERO) => NZERO,
        _ if a & ZERO != 0 && b & ZERO != 0 => PZERO,
        // x + 0 is x exactly.
        _ if a & ZERO != 0 => b,
        _ if b & ZERO != 0 => a,
        (PFIN, PFIN) => PFIN | PINF,
        (NFIN, NFIN) => NFIN | NINF,
        // Opposite signs: no overflow; exact cancellation gives +0 (RNE).
        _ => PFIN | NFIN | PZERO,
    }
}

fn mul1(a: u16, b: u16) -> u16 {
    if (a | b) & NAN != 0 || (a & INF != 0 && b & ZERO != 0) || (a & ZERO != 0 && b & INF != 0) {
        return NAN_C;
    }
    let neg = (a & SIGN1 != 0) != (b & SIGN1 != 0);
    let pos = if (a | b) & INF != 0 {
        PINF
    } else if (a | b) & ZERO != 0 {
        PZERO
    } else {
        PFIN | PZERO | PINF // underflow, overflow
    };
    signed(neg, pos)
}

fn div1(a: u16, b: u16) -> u16 {
    if (a | b) & NAN != 0 || (a & INF != 0 && b & INF != 0) || (a & ZERO != 0 && b & ZERO != 0) {
        return NAN_C;
    }
    let neg = (a & SIGN1 != 0) != (b & SIGN1 != 0);
    let pos = if a & INF != 0 || b & ZERO != 0 {
        PINF
    } else if a & ZERO != 0 || b & INF != 0 {
        PZERO
    } else {
        PFIN | PZERO | PINF
    };
    signed(neg, pos)
}

fn sqrt1(a: u16) -> u16 {
    match a {
        NZERO | PZERO | PFIN | PINF => a,
        _ => NAN_C,
    }
}

/// `max` (`b` if `b > a` or `a` is NaN, else `a`) or `min` (`b` if `b < a` or `a` is NaN).
fn maxmin1(a: u16, b: u16, same: bool, max: bool) -> u16 {
    if a & NAN != 0 {
        return b;
    }
    if b & NAN != 0 || same {
        return a;
    }
    let (ra, rb) = (rank(a), rank(b));
    // b when strictly beyond a; else a (equal zeros included: max(-0, +0) = -0).
    if (max && rb > ra) || (!max && rb < ra) {
        b
    } else {
        a
    }
}

/// The possible results of a compare (bit 0: false possible, bit 1: true possible).
fn cmp1(a: u16, b: u16, same: bool, op: &Op) -> u16 {
    const F: u16 = 1;
    const T: u16 = 2;
    let tf = |t: bool| if t { T } else { F };
    if (a | b) & NAN != 0 {
        return F;
    }
    let (ra, rb) = (rank(a), rank(b));
    let equal_values = same || (ra == rb && (a & (ZERO | INF) != 0));
    match op {
        Op::Lt(..) if equal_values => F,
        Op::Le(..) | Op::Eq(..) if equal_values => T,
        _ if ra != rb => match op {
            Op::Lt(..) | Op::Le(..) => tf(ra < rb),
            _ => F,
        },
        _ => F | T, // both finite of one sign
    }
}

/// Union of a binary class function over the pairs of `a` and `b` (`same`: one node twice, so
/// only equal classes pair).
fn pairs(a: u16, b: u16, same: bool, f: impl Fn(u16, u16) -> u16) -> u16 {
    let mut out = 0;
    for ca in each(a) {
        for cb in each(b) {
            if !same || ca == cb {
                out |= f(ca, cb);
            }
        }
    }
    out
}

/// The abstract value of one node.
#[derive(Clone, Debug)]
struct Fact {
    /// binary32: the classes it may be in.
    classes: u16,
    /// Integer or boolean: its signed range.
    range: (i64, i64),
    /// Bits the operation fixes, beyond what the classes or the range say.
    mask: u32,
    value: u32,
    /// binary32: the value is an integer (or a zero) of at most this many significant bits,
    /// exactly.
    int_sig: Option<u32>,
    /// binary32: a bound on its magnitude (a finite value's; NaN and infinities are classes).
    mag: Option<f64>,
    /// What the operation is, for the reason.
    what: String,
}

impl Fact {
    fn f(classes: u16, what: impl Into<String>) -> Self {
        Fact { classes, range: I32, mask: 0, value: 0, int_sig: None, mag: None, what: what.into() }
    }

    fn i(range: (i64, i64), what: impl Into<String>) -> Self {
        let range = if range.0 < I32.0 || range.1 > I32.1 { I32 } else { range };
        Fact { classes: ALL, range, mask: 0, value: 0, int_sig: None, mag: None, what: what.into() }
    }

    /// The value is an integer of at most `k` significant bits (exactly): its mantissa's low
    /// `24 - k` bits are zero.
    fn integer(mut self, k: u32) -> Self {
        self.int_sig = Some(k);
        if k <= 23 {
            self = self.bits((1 << (24 - k)) - 1, 0);
        }
        self
    }

    fn bits(mut self, mask: u32, value: u32) -> Self {
        self.mask |= mask;
        self.value = (self.value & !mask) | (value & mask);
        self
    }
}

/// The known bits of a value of type `ty` with abstract value `f`.
fn known(f: &Fact, ty: Ty) -> (u32, u32) {
    let (mut mask, mut value) = (f.mask, f.value);
    match ty {
        Ty::F => {
            let c = f.classes;
            // Classes of one value each: the bits those values agree on.
            let single = |c: u16| match c {
                PZERO => Some(0),
                NZERO => Some(0x8000_0000),
                PINF => Some(0x7F80_0000),
                NINF => Some(0xFF80_0000),
                NAN_C => Some(CANONICAL_NAN),
                _ => None,
            };
            if each(c).all(|c| single(c).is_some()) {
                let (m, v) = common_bits(each(c).filter_map(single));
                mask |= m;
                value = (value & !m) | v;
            }
            if c & !ZERO == 0 {
                mask |= 0x7FFF_FFFF;
                value &= 0x8000_0000;
            }
            if c & !SIGN0 == 0 {
                mask |= 1 << 31;
                value &= !(1 << 31);
            } else if c & !SIGN1 == 0 {
                mask |= 1 << 31;
                value |= 1 << 31;
            }
        }
        Ty::I | Ty::B => {
            let (lo, hi) = f.range;
            if lo >= 0 || hi < 0 {
                // Every value between lo and hi shares their common leading bits.
                let (l, h) = (lo as i32 as u32, hi as i32 as u32);
                let common = if l == h { u32::MAX } else { !(u32::MAX >> (l ^ h).leading_zeros()) };
                mask |= common;
                value = (value & !common) | (l & common);
            }
            if ty == Ty::B {
                mask &= 1;
                value &= 1;
            }
        }
    }
    (mask, value)
}

/// The bits every value of `values` agrees on: (mask, value).
fn common_bits(values: impl Iterator<Item = u32>) -> (u32, u32) {
    let mut first = None;
    let mut diff = 0u32;
    for v in values {
        match first {
            None => first = Some(v),
            Some(f) => diff |= f ^ v,
        }
    }
    first.map_or((0, 0), |f| (!diff, f & !diff))
}

/// What the classes `c` say of a value's sign.
fn sign_word(c: u16) -> &'static str {
    if c == PZERO {
        "+0"
    } else if c & !ZERO == 0 {
        "±0"
    } else if c & !(ZERO | NAN_C) == 0 {
        "±0 or the canonical NaN"
    } else if c & !(PFIN | PINF) == 0 {
        "positive"
    } else if c & !(PFIN | PINF | NAN_C | NAN_P) == 0 {
        "positive or NaN"
    } else if c & !SIGN0 == 0 {
        "non-negative (sign 0)"
    } else if c & !SIGN1 == 0 {
        "negative (sign 1)"
    } else if c & (NZERO | NAN_N) == 0 {
        "never -0"
    } else {
        "of any sign"
    }
}

/// The fact of an input of type `ty` bounded by contract `c`.
fn contracted(ty: Ty, c: &InputContract) -> Fact {
    let what = format!("input contract: {}", c.why);
    match (ty, c.range) {
        (Ty::F, _) => {
            let mut classes = ALL;
            if c.finite {
                classes &= !(NAN | INF);
            }
            if c.mask >> 31 & 1 == 1 {
                classes &= if c.value >> 31 & 1 == 0 { SIGN0 } else { !SIGN0 & ALL };
            }
            Fact::f(classes, what).bits(c.mask, c.value)
        }
        (_, Some(range)) => Fact::i(range, what).bits(c.mask, c.value),
        (_, None) => Fact::i(I32, what).bits(c.mask, c.value),
    }
}

/// `f` narrowed by the program's assumption `x` (checked by `Graph::eval` on every item).
fn assume(mut f: Fact, x: &Assumption) -> Fact {
    f.what = format!("{} (asserted: {})", f.what, x.why);
    match x.range {
        AssumedRange::I(lo, hi) => {
            f.range = (f.range.0.max(lo as i64), f.range.1.min(hi as i64));
            f
        }
        AssumedRange::F(lo, hi) => {
            // Finite, never NaN; the signs the range excludes (-0 is in any range holding 0).
            f.classes &= !(NAN | INF);
            if lo >= 0.0 {
                f.classes &= !(NFIN | if lo > 0.0 { ZERO } else { 0 });
            }
            if hi <= 0.0 {
                f.classes &= !(PFIN | if hi < 0.0 { ZERO } else { 0 });
            }
            // |x| <= the larger bound: the exponent field at most its exponent field, so that
            // field's leading zeros are zero.
            f.mag = Some(lo.abs().max(hi.abs()) as f64);
            let e_max = (lo.abs().max(hi.abs()).to_bits() >> 23) & 0xFF;
            let lead = !(0xFFu32 >> (e_max.leading_zeros() - 24)) & 0xFF;
            f.bits(lead << 23, 0)
        }
        AssumedRange::ZeroOr(lo, hi) => {
            // Finite; exponent field 0 (a zero) or from lo's to hi's.
            f.classes &= !(NAN | INF);
            f.mag = Some(hi as f64);
            let field = |x: f32| (x.to_bits() >> 23) & 0xFF;
            let (em, ev) = common_bits(std::iter::once(0).chain(field(lo)..=field(hi)));
            f.bits((em & 0xFF) << 23, (ev & 0xFF) << 23)
        }
    }
}

/// The most significant bits of any integer in `[lo, hi]` (`lo <= hi`): a power of two has
/// one, so the largest magnitude counts only when it is not one.
fn max_sig(lo: i64, hi: i64) -> u32 {
    let side = |a: i64, b: i64| -> u32 {
        // Magnitudes a..=b, 0 <= a <= b.
        if b == 0 {
            0
        } else if a == b {
            bitlen(b) - b.trailing_zeros()
        } else if b.count_ones() == 1 {
            bitlen(b - 1).max(1)
        } else {
            bitlen(b)
        }
    };
    let pos = if hi >= 0 { side(lo.max(0), hi) } else { 0 };
    let neg = if lo < 0 { side((-hi).max(0), -lo) } else { 0 };
    pos.max(neg)
}

fn bitlen(v: i64) -> u32 {
    64 - (v as u64).leading_zeros()
}

/// What a unit's interface promises about one of its per-frame inputs (the host programs it
/// within these bounds), for [`Analysis::with_contracts`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct InputContract {
    /// The graph input's name.
    pub input: String,
    /// An integer input's signed range (inclusive); `None` for a binary32 input.
    pub range: Option<(i64, i64)>,
    /// Bits of the input that are fixed (`mask`) and their values (`value`): a binary32's sign,
    /// or the high exponent bit of a value of magnitude at most 1.
    pub mask: u32,
    /// Their values (zero outside `mask`).
    pub value: u32,
    /// A binary32 input is finite (never NaN or infinite).
    pub finite: bool,
    /// The promise, in words (the reason of every bit it fixes).
    pub why: String,
}

/// The known-bits analysis of a graph: one abstract value per node.
pub struct Analysis {
    facts: Vec<Fact>,
    tys: Vec<Ty>,
    /// Per node, the earliest node proven to hold the same value (itself if none): an `imin`
    /// or `imax` whose one operand's range decides it is that operand.
    same: Vec<NodeId>,
}

impl Analysis {
    /// Analyses `graph` (operands before users).
    pub fn of(graph: &Graph) -> Self {
        Self::with_contracts(graph, &[])
    }

    /// Analyses `graph` with its per-frame inputs bounded by `contracts` (inputs without one
    /// are unknown).
    pub fn with_contracts(graph: &Graph, contracts: &[InputContract]) -> Self {
        let mut a =
            Analysis { facts: Vec::with_capacity(graph.nodes.len()), tys: Vec::new(), same: Vec::new() };
        for (id, n) in graph.nodes.iter().enumerate() {
            let mut f = a.transfer(&n.op, n.ty);
            if let Op::Input(k) = n.op {
                if let Some(c) = contracts.iter().find(|c| c.input == graph.inputs[k].name) {
                    f = contracted(n.ty, c);
                }
            }
            for assumed in graph.assumptions.iter().filter(|x| x.node == id) {
                f = assume(f, assumed);
            }
            a.facts.push(f);
            a.tys.push(n.ty);
            let same = a.same_as(&n.op).unwrap_or(id);
            a.same.push(same);
        }
        a
    }

    /// The node that `op` (an `imin` or `imax` of analysed nodes) returns whatever the values,
    /// when one operand's range is entirely on the chosen side of the other's.
    fn same_as(&self, op: &Op) -> Option<NodeId> {
        let r = |id: NodeId| self.facts[id].range;
        let (a, b, min) = match *op {
            Op::IMin(a, b) => (a, b, true),
            Op::IMax(a, b) => (a, b, false),
            _ => return None,
        };
        let (lo_side, hi_side) = if r(a).1 <= r(b).0 {
            (a, b)
        } else if r(b).1 <= r(a).0 {
            (b, a)
        } else {
            return None;
        };
        // Every value of `lo_side` is at most every value of `hi_side`.
        Some(self.same[if min { lo_side } else { hi_side }])
    }

    /// The known bits of node `id`.
    pub fn node(&self, id: NodeId) -> KnownBits {
        self.report(&self.facts[id], self.tys[id])
    }

    /// The known bits of operation `op` of type `ty` on the analysed nodes (a compare node's
    /// other comparator outputs: `Op::Min` of a `max` node's operands).
    pub fn op(&self, op: &Op, ty: Ty) -> KnownBits {
        self.report(&self.transfer(op, ty), ty)
    }

    fn report(&self, f: &Fact, ty: Ty) -> KnownBits {
        let (mask, value) = known(f, ty);
        let reason = if mask == 0 { String::new() } else { f.what.clone() };
        KnownBits { mask, value, reason }
    }

    fn bits_of(&self, id: NodeId) -> (u32, u32) {
        known(&self.facts[id], self.tys[id])
    }

    fn transfer(&self, op: &Op, ty: Ty) -> Fact {
        use Op::*;
        let fc = |id: NodeId| self.facts[id].classes;
        let r = |id: NodeId| self.facts[id].range;
        let bool_of = |id: NodeId| match r(id) {
            (0, 0) => Some(false),
            (1, 1) => Some(true),
            _ => None,
        };
        let sw = |id: NodeId| sign_word(fc(id));
        let args = op.args();
        let constant = |a: &NodeId| self.bits_of(*a).0 == if self.tys[*a] == Ty::B { 1 } else { u32::MAX };
        if !args.is_empty() && args.iter().all(constant) {
            // An operation on constants: golden's value (the RTL computes it bit for bit).
            let mut v = vec![0; args.iter().max().map_or(0, |m| m + 1)];
            for &a in &args {
                v[a] = self.bits_of(a).1;
            }
            let x = eval_op(op, ty, &v, &[]);
            let what = "an operation on constants (its golden value)";
            return match ty {
                Ty::F => Fact::f(class_of(x), what).bits(u32::MAX, x),
                _ => Fact::i((x as i32 as i64, x as i32 as i64), what),
            };
        }
        match *op {
            Input(_) => match ty {
                Ty::F => Fact::f(ALL, "input"),
                Ty::I => Fact::i(I32, "input"),
                Ty::B => Fact::i((0, 1), "input"),
            },
            Lit(v) => match ty {
                Ty::F => {
                    let mut lit = Fact::f(class_of(v), "literal").bits(u32::MAX, v);
                    let x = f32::from_bits(v);
                    lit.mag = x.is_finite().then_some(x.abs() as f64);
                    if x.is_finite() && x.fract() == 0.0 && x.abs() < (1 << 24) as f32 {
                        let n = x.abs() as i64;
                        lit.integer(max_sig(n, n))
                    } else {
                        lit
                    }
                }
                Ty::I => Fact::i((v as i32 as i64, v as i32 as i64), "literal"),
                Ty::B => Fact::i((v as i64, v as i64), "literal"),
            },
            Add(a, b) => Fact::f(
                pairs(fc(a), fc(b), a == b, add1),
                format!("x + y with x {}, y {} (NaN results canonical, +0 on cancellation)", sw(a), sw(b)),
            ),
            Sub(a, b) => Fact::f(
                pairs(fc(a), fc(b), a == b, |x, y| add1(x, negc(y))),
                format!("x - y with x {}, y {} (NaN results canonical, +0 on cancellation)", sw(a), sw(b)),
            ),
            Mul(a, b) => {
                let what = if a == b {
                    format!("a square x * x, x {} (NaN results canonical)", sw(a))
                } else {
                    format!("x * y with x {}, y {} (NaN results canonical)", sw(a), sw(b))
                };
                let mut f = Fact::f(pairs(fc(a), fc(b), a == b, mul1), what);
                // |x y| <= |x| |y|, rounded up by at most half an ulp (2^-24 relative).
                f.mag = self.facts[a].mag.zip(self.facts[b].mag).map(|(x, y)| x * y * (1.0 + 2f64.powi(-23)));
                if (fc(a) | fc(b)) & INF == 0 && f.mag.is_some_and(|m| m < f32::MAX as f64) {
                    // Finite operands whose product stays below the largest finite: no overflow.
                    f.classes &= !INF;
                }
                // Integers of ka and kb significant bits: a product of at most ka + kb (ka when
                // y is a power of two), exact when that is at most 24.
                let sig = self.facts[a].int_sig.zip(self.facts[b].int_sig).map(|(ka, kb)| {
                    if ka.min(kb) <= 1 {
                        ka.max(kb)
                    } else {
                        ka + kb
                    }
                });
                match sig {
                    Some(k) if k <= 24 => {
                        let mut f = f.integer(k);
                        f.what =
                            format!("{} of integers: an integer of at most {k} significant bits", f.what);
                        f
                    }
                    _ => f,
                }
            }
            Div(a, b) => Fact::f(
                pairs(fc(a), fc(b), a == b, div1),
                format!("x / y with x {}, y {} (NaN results canonical)", sw(a), sw(b)),
            ),
            Sqrt(a) => Fact::f(
                pairs(fc(a), fc(a), true, |x, _| sqrt1(x)),
                format!("sqrt(x) with x {} (sqrt(-0) = -0, NaN results canonical)", sw(a)),
            ),
            Neg(a) => {
                let (m, v) = self.bits_of(a);
                let mut f = Fact::f(neg_set(fc(a)), "-x (sign flipped) of an x with known bits")
                    .bits(m, v ^ (1 << 31));
                f.int_sig = self.facts[a].int_sig;
                f.mag = self.facts[a].mag;
                f
            }
            Abs(a) => {
                let (m, v) = self.bits_of(a);
                let what = if m & 0x7FFF_FFFF == 0 {
                    "|x|: sign cleared"
                } else {
                    "|x| of an x with known bits, sign cleared"
                };
                let mut f = Fact::f(each(fc(a)).fold(0, |s, c| s | (c & SIGN0) | neg_set(c & SIGN1)), what)
                    .bits(m | (1 << 31), v & 0x7FFF_FFFF);
                f.int_sig = self.facts[a].int_sig;
                f.mag = self.facts[a].mag;
                f
            }
            Max(a, b) | Min(a, b) => {
                let max = matches!(op, Max(..));
                let ((ma, va), (mb, vb)) = (self.bits_of(a), self.bits_of(b));
                let agree = ma & mb & !(va ^ vb);
                let name = if max { "max" } else { "min" };
                Fact::f(
                    pairs(fc(a), fc(b), a == b, |x, y| maxmin1(x, y, a == b, max)),
                    format!("{name}(x, y) with x {}, y {} (the result is x or y: y when x is NaN; max(-0, +0) = -0)", sw(a), sw(b)),
                )
                .bits(agree, va)
            }
            Lt(a, b) | Le(a, b) | Eq(a, b) => {
                let t = pairs(fc(a), fc(b), a == b, |x, y| cmp1(x, y, a == b, op));
                let range = match t {
                    1 => (0, 0),
                    2 => (1, 1),
                    _ => (0, 1),
                };
                Fact::i(range, format!("compare of x {} and y {}, decided by their classes", sw(a), sw(b)))
            }
            IsNan(a) | IsFinite(a) => {
                let hit = if matches!(op, IsNan(_)) { NAN } else { ZERO | NFIN | PFIN };
                let c = fc(a);
                let range = if c & !hit == 0 {
                    (1, 1)
                } else if c & hit == 0 {
                    (0, 0)
                } else {
                    (0, 1)
                };
                Fact::i(range, "class test decided by the operand's classes")
            }
            ToInt(a, mode) => {
                let (mut lo, mut hi) = (i64::MAX, i64::MIN);
                for c in each(fc(a)) {
                    let (l, h) = match c {
                        PINF => (I32.1, I32.1),
                        NINF => (I32.0, I32.0),
                        PFIN => (if mode == Round::Ceil { 1 } else { 0 }, I32.1),
                        NFIN => (I32.0, if mode == Round::Floor { -1 } else { 0 }),
                        _ => (0, 0), // zeros; NaN gives 0
                    };
                    (lo, hi) = (lo.min(l), hi.max(h));
                }
                if let Some(m) = self.facts[a].mag.filter(|m| *m < I32.1 as f64 && fc(a) & INF == 0) {
                    // A finite |x| <= m rounds to an integer of magnitude at most this.
                    let m = match mode {
                        Round::Trunc => m.floor(),
                        Round::HalfUp => (m + 0.5).floor(),
                        Round::Floor | Round::Ceil => m.ceil(),
                    } as i64;
                    (lo, hi) = (lo.max(-m), hi.min(m));
                }
                Fact::i(
                    (lo, hi),
                    format!("to_int(x) with x {} (saturating, NaN gives 0): in [{lo}, {hi}]", sw(a)),
                )
            }
            IntToFloat(i) => {
                let (lo, hi) = r(i);
                let mut classes = 0;
                if lo < 0 {
                    classes |= NFIN;
                }
                if lo <= 0 && hi >= 0 {
                    classes |= PZERO;
                }
                if hi > 0 {
                    classes |= PFIN;
                }
                let big = lo.abs().max(hi.abs());
                let small = if lo > 0 {
                    lo
                } else if hi < 0 {
                    -hi
                } else {
                    1
                };
                // Nonzero magnitudes in [small, big]: exponents from small's, to big's (one more
                // when the conversion rounds, above 2^24).
                let exact = big < 1 << 24;
                let e_lo = 126 + bitlen(small);
                let e_hi = 126 + bitlen(big) + u32::from(!exact);
                let zero = classes & PZERO != 0;
                let (em, ev) = common_bits((e_lo..=e_hi).chain(zero.then_some(0)));
                let mut f = Fact::f(classes, format!("int_to_float of an integer in [{lo}, {hi}]"))
                    .bits((em & 0xFF) << 23, ev << 23);
                if exact && big > 0 {
                    // An integer of at most max_sig significant bits: the mantissa's low bits are
                    // zero.
                    f = f.integer(max_sig(lo, hi));
                }
                f
            }
            ExpField(a) => {
                let (m, v) = self.bits_of(a);
                let (fm, fv) = ((m >> 23) & 0xFF, (v >> 23) & 0xFF);
                let lo = fv;
                let mut hi = fv | (!fm & 0xFF);
                if fc(a) & (NAN | INF) == 0 {
                    hi = hi.min(254);
                }
                Fact::i((lo as i64, hi as i64), "exponent field: 8 bits").bits(0xFFFF_FF00 | fm, fv)
            }
            Pow2Field(e) => {
                let (lo, hi) = r(e);
                let (lo, hi) = (lo.clamp(1, 254) as u32, hi.clamp(1, 254) as u32);
                let (em, ev) = common_bits(lo..=hi);
                Fact::f(PFIN, format!("pow2_field: a power of two, exponent field in [{lo}, {hi}]"))
                    .bits(0x807F_FFFF | ((em & 0xFF) << 23), ev << 23)
            }
            F16Bits(a) => {
                let range = if fc(a) & !ZERO == 0 { (0, 0) } else { (0, 0x7BFF) };
                Fact::i(range, "f16_bits: |x| as half bits, at most 0x7BFF")
            }
            WidenHalf(h) => {
                let (m, v) = self.bits_of(h);
                let mut classes = NAN_C | ZERO | INF | NFIN | PFIN;
                if m & 0x8000 != 0 {
                    classes &= if v & 0x8000 == 0 { SIGN0 } else { SIGN1 | NAN_C };
                }
                Fact::f(classes, "widened half: at most 11 significant bits, 13 low mantissa bits zero")
                    .bits(0x1FFF, 0)
            }
            IAdd(a, b) => {
                let ((al, ah), (bl, bh)) = (r(a), r(b));
                Fact::i((al + bl, ah + bh), format!("iadd of [{al}, {ah}] and [{bl}, {bh}]"))
            }
            ISub(a, b) => {
                let ((al, ah), (bl, bh)) = (r(a), r(b));
                if self.same[a] == self.same[b] {
                    Fact::i(
                        (0, 0),
                        "isub of two nets that hold the same value (an imin or imax its ranges decide)",
                    )
                } else {
                    Fact::i((al - bh, ah - bl), format!("isub of [{al}, {ah}] and [{bl}, {bh}]"))
                }
            }
            IMin(a, b) | IMax(a, b) => {
                let ((al, ah), (bl, bh)) = (r(a), r(b));
                let (range, name) = if matches!(op, IMin(..)) {
                    ((al.min(bl), ah.min(bh)), "imin")
                } else {
                    ((al.max(bl), ah.max(bh)), "imax")
                };
                Fact::i(
                    range,
                    format!("{name} of [{al}, {ah}] and [{bl}, {bh}]: in [{}, {}]", range.0, range.1),
                )
            }
            ILt(a, b) | IEq(a, b) => {
                let ((al, ah), (bl, bh)) = (r(a), r(b));
                let range = match op {
                    ILt(..) if a == b || al >= bh => (0, 0),
                    ILt(..) if ah < bl => (1, 1),
                    IEq(..) if a == b || (al == ah && bl == bh && al == bl) => (1, 1),
                    IEq(..) if ah < bl || bh < al => (0, 0),
                    _ => (0, 1),
                };
                Fact::i(range, format!("integer compare of [{al}, {ah}] and [{bl}, {bh}]"))
            }
            And(a, b) | Or(a, b) => {
                let and = matches!(op, And(..));
                let v = match (bool_of(a), bool_of(b)) {
                    (Some(x), _) | (_, Some(x)) if x != and => Some(x),
                    (Some(x), Some(y)) => Some(if and { x && y } else { x || y }),
                    _ => None,
                };
                let range = v.map_or((0, 1), |v| (v as i64, v as i64));
                Fact::i(range, "boolean of a constant operand")
            }
            Not(a) => {
                let (lo, hi) = r(a);
                Fact::i((1 - hi, 1 - lo), "not of a constant")
            }
            Select(c, a, b) | ISelect(c, a, b) => match bool_of(c) {
                Some(true) => self.facts[a].clone(),
                Some(false) => self.facts[b].clone(),
                None => {
                    let (fa, fb) = (&self.facts[a], &self.facts[b]);
                    let ((ma, va), (mb, vb)) = (self.bits_of(a), self.bits_of(b));
                    let agree = ma & mb & !(va ^ vb);
                    let range = (fa.range.0.min(fb.range.0), fa.range.1.max(fb.range.1));
                    let what = match ty {
                        Ty::F => format!("select of x {} and y {}", sw(a), sw(b)),
                        _ => format!(
                            "select of [{}, {}] and [{}, {}]",
                            fa.range.0, fa.range.1, fb.range.0, fb.range.1
                        ),
                    };
                    let int_sig = fa.int_sig.zip(fb.int_sig).map(|(x, y)| x.max(y));
                    let mag = fa.mag.zip(fb.mag).map(|(x, y)| x.max(y));
                    Fact { classes: fa.classes | fb.classes, range, mask: 0, value: 0, int_sig, mag, what }
                        .bits(agree, va)
                }
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use neo_golden::hwarith::graph::Trace;
    use neo_golden::hwarith::Arith;

    fn kb(g: &Graph, name: &str) -> KnownBits {
        let id = g.outputs.iter().find(|(n, _)| n == name).unwrap().1;
        Analysis::of(g).node(id)
    }

    #[test]
    fn signs_of_squares_sums_and_roots() {
        let mut t = Trace::new();
        let x = t.input_f("x", false);
        let y = t.input_f("y", false);
        let xx = t.mul(x, x);
        let xy = t.mul(x, y);
        let s = t.add(xx, xx);
        let r = t.sqrt(s);
        let a = t.abs(x);
        let d = t.sub(x, y);
        let zero = t.lit(0.0);
        let m = t.max(x, zero);
        let half = t.lit(0.5);
        let xh = t.add(xx, half);
        let mh = t.max(xh, zero);
        for (n, v) in [("xx", xx), ("xy", xy), ("s", s), ("r", r), ("a", a), ("d", d), ("m", m), ("mh", mh)] {
            t.output_f(n, v);
        }
        let g = t.finish();
        for n in ["xx", "s", "r", "a", "mh"] {
            let k = kb(&g, n);
            assert_eq!((k.mask, k.value), (1 << 31, 0), "{n}: {k:?}");
        }
        assert!(kb(&g, "xx").reason.contains("square"));
        // A product of unknowns, a difference, and max(x, +0) (max(-0, +0) = -0) say nothing.
        for n in ["xy", "d", "m"] {
            assert_eq!(kb(&g, n).mask, 0, "{n}");
        }
    }

    #[test]
    fn integer_clamps_exponents_and_powers_of_two() {
        let mut t = Trace::new();
        let x = t.input_f("x", false);
        let i = t.to_int(x, Round::Floor);
        let zero = t.ilit(0);
        let fifteen = t.ilit(15);
        let lo = t.imax(i, zero);
        let c = t.imin(lo, fifteen);
        let e = t.exp_field(x);
        let p = t.pow2_field(c);
        let f = t.int_to_float(c);
        let h = t.f16_bits(x);
        let lt = t.ilt(c, zero);
        t.output_i("c", c);
        t.output_i("e", e);
        t.output_f("p", p);
        t.output_f("f", f);
        t.output_i("h", h);
        t.output_b("lt", lt);
        t.output_i("lo", lo);
        let g = t.finish();
        assert_eq!(kb(&g, "c").mask, !0xF);
        assert_eq!(kb(&g, "c").value, 0);
        assert!(kb(&g, "c").reason.contains("[0, 15]"), "{:?}", kb(&g, "c"));
        assert_eq!(kb(&g, "lo").mask, 1 << 31);
        assert_eq!((kb(&g, "e").mask, kb(&g, "e").value), (0xFFFF_FF00, 0));
        // 2^(c - 127) for c in [1, 15]: sign, mantissa and exponent bits 4..7 zero.
        let p = kb(&g, "p");
        assert_eq!((p.mask, p.value), (0x807F_FFFF | (0xF0 << 23), 0));
        // 0..15 as binary32: sign 0, at most 4 significant bits.
        let f = kb(&g, "f");
        assert_eq!(f.mask & 0x800F_FFFF, 0x800F_FFFF);
        assert_eq!(f.value & 0x800F_FFFF, 0);
        assert_eq!(kb(&g, "h").mask, 0xFFFF_8000);
        let lt = kb(&g, "lt");
        assert_eq!((lt.mask, lt.value), (1, 0));
    }

    #[test]
    fn literals_selects_and_booleans() {
        let mut t = Trace::new();
        let x = t.input_f("x", false);
        let b = t.input_f("b", false);
        let one = t.lit(1.0);
        let two = t.lit(2.0);
        let c = t.lt(x, b);
        let s = t.select(c, one, two);
        let n = t.neg(s);
        let k = t.blit(false);
        let a = t.and(c, k);
        let nan = t.is_nan(s);
        t.output_f("one", one);
        t.output_f("s", s);
        t.output_f("n", n);
        t.output_b("a", a);
        t.output_b("c", c);
        t.output_b("nan", nan);
        let g = t.finish();
        assert_eq!(
            (kb(&g, "one").mask, kb(&g, "one").value, kb(&g, "one").reason.as_str()),
            (!0, 0x3F80_0000, "literal")
        );
        // 1.0 = 0x3F800000, 2.0 = 0x40000000: they agree on bits 0..22 (zero) and 31 (zero).
        let s = kb(&g, "s");
        assert_eq!((s.mask, s.value), (0x807F_FFFF, 0));
        let n = kb(&g, "n");
        assert_eq!((n.mask, n.value), (0x807F_FFFF, 0x8000_0000));
        assert_eq!((kb(&g, "a").mask, kb(&g, "a").value), (1, 0));
        assert_eq!(kb(&g, "c").mask, 0);
        assert_eq!((kb(&g, "nan").mask, kb(&g, "nan").value), (1, 0));
    }

    /// A small xorshift generator (gen has no random crate).
    struct Rng(u64);

    impl Rng {
        fn next(&mut self) -> u32 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            (self.0 >> 16) as u32
        }

        fn pick<T: Copy>(&mut self, xs: &[T]) -> T {
            xs[self.next() as usize % xs.len()]
        }
    }

    const EDGE_F: [u32; 22] = [
        0x0000_0000,
        0x8000_0000,
        0x7F80_0000,
        0xFF80_0000,
        0x7FC0_0000,
        0xFFC0_0000,
        0x7F80_0001,
        0xFFFF_FFFF,
        0x0000_0001,
        0x8000_0001,
        0x007F_FFFF,
        0x807F_FFFF,
        0x0080_0000,
        0x7F7F_FFFF,
        0xFF7F_FFFF,
        0x3F80_0000,
        0xBF80_0000,
        0x3F00_0000,
        0x4F00_0000,
        0xCF00_0000,
        0x3A80_0000,
        0xC2F6_E979,
    ];
    const EDGE_I: [u32; 12] = [0, 1, 2, 3, 0xFFFF_FFFF, 0x7FFF_FFFF, 0x8000_0000, 15, 16, 254, 255, 0x7C00];

    /// One input value of type `ty`: an edge value, a random bit pattern, or a value of
    /// moderate magnitude of either sign.
    fn draw(rng: &mut Rng, ty: Ty) -> u32 {
        match (ty, rng.next() % 4) {
            (Ty::B, _) => rng.next() & 1,
            (Ty::F, 0) => rng.pick(&EDGE_F),
            (Ty::F, 1) => rng.next(),
            (Ty::F, _) => {
                let mag =
                    ((rng.next() % 40) as f32 - 20.0).exp2() * (1.0 + (rng.next() % 1000) as f32 / 1000.0);
                (if rng.next() & 1 == 0 { mag } else { -mag }).to_bits()
            }
            (Ty::I, 0) => rng.pick(&EDGE_I),
            (Ty::I, 1) => rng.next(),
            (Ty::I, _) => (rng.next() % 600).wrapping_sub(300),
        }
    }

    /// Every claim of `known` (per node, and each compare node's five comparator outputs)
    /// checked against the graph's values on `inputs`: the violations.
    fn violations(g: &Graph, a: &Analysis, known: &[KnownBits], inputs: &[u32]) -> Vec<String> {
        let mut v: Vec<u32> = Vec::with_capacity(g.nodes.len());
        let mut bad = Vec::new();
        for (id, n) in g.nodes.iter().enumerate() {
            let x = eval_op(&n.op, n.ty, &v, inputs);
            for x_assumed in g.assumptions.iter().filter(|a| a.node == id && !a.range.admits(x)) {
                bad.push(format!("n{id} = {x:#010x} breaks the assumption {x_assumed:?}"));
            }
            if !known[id].admits(x) {
                bad.push(format!(
                    "n{id} {:?} = {x:#010x}, known {:?} (inputs {inputs:08x?})",
                    n.op, known[id]
                ));
            }
            v.push(x);
            if let Op::Lt(p, q) | Op::Le(p, q) | Op::Eq(p, q) | Op::Max(p, q) | Op::Min(p, q) = n.op {
                for (op, ty) in compare_ops(p, q) {
                    let y = eval_op(&op, ty, &v, inputs);
                    let k = a.op(&op, ty);
                    if !k.admits(y) {
                        bad.push(format!("n{id} comparator {op:?} = {y:#010x}, known {k:?}"));
                    }
                }
            }
        }
        bad
    }

    fn compare_ops(p: NodeId, q: NodeId) -> [(Op, Ty); 5] {
        [
            (Op::Lt(p, q), Ty::B),
            (Op::Le(p, q), Ty::B),
            (Op::Eq(p, q), Ty::B),
            (Op::Max(p, q), Ty::F),
            (Op::Min(p, q), Ty::F),
        ]
    }

    /// An input value within contract `c`: a range end or a value inside the range, or a drawn
    /// binary32 with the contract's bits forced (drawn again until finite, if it must be).
    fn draw_within(rng: &mut Rng, ty: Ty, c: &InputContract) -> u32 {
        if let Some((lo, hi)) = c.range {
            let span = (hi - lo) as u64 + 1;
            return match rng.next() % 4 {
                0 => lo as u32,
                1 => hi as u32,
                _ => (lo + (rng.next() as u64 % span) as i64) as u32,
            };
        }
        loop {
            let x = (draw(rng, ty) & !c.mask) | c.value;
            if !c.finite || f32::from_bits(x).is_finite() {
                return x;
            }
        }
    }

    fn check_sound(g: &Graph, seed: u64, items: usize) -> usize {
        check_sound_with(g, &[], seed, items)
    }

    /// [`check_sound`] with the per-frame inputs bounded by `contracts` (and drawn within them).
    fn check_sound_with(g: &Graph, contracts: &[InputContract], seed: u64, items: usize) -> usize {
        let a = Analysis::with_contracts(g, contracts);
        let known: Vec<KnownBits> = (0..g.nodes.len()).map(|id| a.node(id)).collect();
        let mut rng = Rng(seed);
        for _ in 0..items {
            let inputs: Vec<u32> = g
                .inputs
                .iter()
                .map(|i| match contracts.iter().find(|c| c.input == i.name) {
                    Some(c) => draw_within(&mut rng, i.ty, c),
                    None => draw(&mut rng, i.ty),
                })
                .collect();
            let bad = violations(g, &a, &known, &inputs);
            assert!(bad.is_empty(), "unsound known bits:\n{}", bad[..bad.len().min(10)].join("\n"));
        }
        known.iter().map(|k| k.mask.count_ones() as usize).sum()
    }

    #[test]
    fn the_project_and_colour_graphs_agree_with_their_known_bits() {
        let cfg = neo_golden::engine::EngineConfig::default();
        let project = neo_golden::hwpre::project::project_graph(&super::super::project_params(&cfg));
        let color = neo_golden::hwpre::color::color_graph(&cfg.feature_format().color);
        let p = check_sound(&project, 0x9E37_79B9_7F4A_7C15, 20_000);
        let c = check_sound(&color, 0x2545_F491_4F6C_DD1D, 20_000);
        // The analysis proves something (the numbers only grow as it gets sharper).
        assert!(p > 2000 && c > 700, "known bits: project {p}, colour {c}");
    }

    #[test]
    fn significant_bits_of_integer_ranges_and_products() {
        assert_eq!(max_sig(0, 256), 8, "256 has one significant bit, 255 eight");
        assert_eq!(max_sig(-256, 256), 8);
        assert_eq!(max_sig(-257, 3), 9);
        assert_eq!(max_sig(256, 256), 1);
        assert_eq!(max_sig(0, 0), 0);
        assert_eq!(max_sig(5, 7), 3);
        // float(c) * float(c) and 2 * float(c) * float(s) for c in [0, 256], s in [-256, 256].
        let mut t = Trace::new();
        let (c, s) = (t.input_i("c", false), t.input_i("s", false));
        let (zero, lo, hi) = (t.ilit(0), t.ilit(-256), t.ilit(256));
        let (c, s) = (t.imax(c, zero), t.imax(s, lo));
        let (c, s) = (t.imin(c, hi), t.imin(s, hi));
        let (cf, sf) = (t.int_to_float(c), t.int_to_float(s));
        let cc = t.mul(cf, cf);
        let cs = t.mul(cf, sf);
        let two = t.lit(2.0);
        let cs2 = t.mul(two, cs);
        t.output_f("cf", cf);
        t.output_f("cc", cc);
        t.output_f("cs2", cs2);
        let g = t.finish();
        assert_eq!(kb(&g, "cf").mask & 0xFFFF, 0xFFFF, "8 significant bits: mantissa bits 15..0 zero");
        assert_eq!(kb(&g, "cc").mask & 0xFF, 0xFF, "16 significant bits: mantissa bits 7..0 zero");
        assert_eq!(kb(&g, "cs2").mask & 0xFF, 0xFF, "times 2 adds no significant bit");
        assert!(check_sound(&g, 5, 5000) > 0);
    }

    #[test]
    fn an_assumed_range_narrows_and_is_checked() {
        let mut t = Trace::new();
        let x = t.input_f("x", false);
        let ax = t.abs(x);
        let one = t.lit(1.0);
        let m = t.min(ax, one);
        t.assume_f(m, 0.0, 1.0, "min(|x|, 1)");
        let q = t.to_int(m, Round::Trunc);
        t.assume_i(q, 0, 1, "trunc of [0, 1]");
        t.output_f("m", m);
        t.output_i("q", q);
        let g = t.finish();
        assert_eq!(kb(&g, "m").mask & (1 << 30), 1 << 30, "|m| <= 1: exponent bit 30 zero");
        assert_eq!(kb(&g, "q").mask, u32::MAX - 1, "q in [0, 1]");
        let a = Analysis::of(&g);
        let known: Vec<KnownBits> = (0..g.nodes.len()).map(|id| a.node(id)).collect();
        assert!(violations(&g, &a, &known, &[0x4000_0000]).is_empty(), "min(2, 1) = 1");
        // A broken assumption is reported (here: min(|NaN|, 1) is 1, but claim [0, 0.5]).
        let mut g2 = g.clone();
        g2.assumptions[0].range = neo_golden::hwarith::graph::AssumedRange::F(0.0, 0.5);
        assert!(!violations(&g2, &a, &known, &[0x4000_0000]).is_empty());
    }

    #[test]
    fn a_decided_imin_or_imax_is_its_operand() {
        // scale_pow2's split: s in [-5, 79], s - imin(s, 100) is 0; and imax(s, -9) is s.
        let mut t = Trace::new();
        let x = t.input_i("x", false);
        let (lo, hi, hundred, low) = (t.ilit(-5), t.ilit(79), t.ilit(100), t.ilit(-9));
        let s = t.imax(x, lo);
        let s = t.imin(s, hi);
        let s1 = t.imin(s, hundred);
        let rest = t.isub(s, s1);
        t.output_i("rest", rest);
        let s2 = t.imax(low, s);
        let same = t.isub(s2, s);
        t.output_i("same", same);
        let open = t.imin(s, lo);
        let diff = t.isub(s, open);
        t.output_i("diff", diff);
        let g = t.finish();
        assert_eq!((kb(&g, "rest").mask, kb(&g, "rest").value), (u32::MAX, 0));
        assert_eq!((kb(&g, "same").mask, kb(&g, "same").value), (u32::MAX, 0));
        // imin(s, -5) is decided too (it is the literal -5), but s - (-5) varies.
        assert_ne!(kb(&g, "diff").mask, u32::MAX);
    }

    #[test]
    fn the_input_contracts_are_sound_and_prove_more() {
        let cfg = neo_golden::engine::EngineConfig::default();
        let project = neo_golden::hwpre::project::project_graph(&super::super::project_params(&cfg));
        let color = neo_golden::hwpre::color::color_graph(&cfg.feature_format().color);
        let (pc, cc) = (super::super::project_contracts(&cfg), super::super::color_contracts());
        let p = check_sound_with(&project, &pc, 0x51_7CC1_B727_220A, 20_000);
        let c = check_sound_with(&color, &cc, 0x94D0_49BB_1331_11EB, 20_000);
        let (p0, c0) = (check_sound(&project, 1, 1), check_sound(&color, 1, 1));
        assert!(
            p > p0 && c > c0,
            "known bits with contracts: project {p} (without {p0}), colour {c} (without {c0})"
        );
        // Every contract names an input of its graph.
        for (g, cs) in [(&project, &pc), (&color, &cc)] {
            for k in cs.iter() {
                assert!(
                    g.inputs.iter().any(|i| i.uniform && i.name == k.input),
                    "no per-frame input {}",
                    k.input
                );
            }
        }
    }

    #[test]
    fn the_soundness_check_catches_a_wrong_claim() {
        // max(x, +0) is -0 for x = -0: a claim of sign 0 must fail on that input.
        let mut t = Trace::new();
        let x = t.input_f("x", false);
        let zero = t.lit(0.0);
        let m = t.max(x, zero);
        t.output_f("m", m);
        let g = t.finish();
        let a = Analysis::of(&g);
        let mut known: Vec<KnownBits> = (0..g.nodes.len()).map(|id| a.node(id)).collect();
        assert!(violations(&g, &a, &known, &[0x8000_0000]).is_empty());
        known[2] = KnownBits { mask: 1 << 31, value: 0, reason: "wrong".into() };
        assert_eq!(violations(&g, &a, &known, &[0x8000_0000]).len(), 1);
        assert!(violations(&g, &a, &known, &[0xBF80_0000]).is_empty(), "max(-1, +0) = +0");
    }
}
