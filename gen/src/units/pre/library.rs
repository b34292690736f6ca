//! The lowering of every [`Op`] for the Preprocessing Engine's datapaths: the binary32
//! arithmetic as pipelined primitives (`gen/src/units/fp`), everything else as inline logic
//! (sign and exponent wiring unregistered; compares, selects, integer and boolean operations
//! behind one register).

use super::datapath::{Library, Lowering, Primitive};
use neo_golden::hwarith::graph::{Op, Ty};

/// The Preprocessing Engine's library.
pub struct PreLibrary;

/// `x` as an order-preserving unsigned key (non-NaN values; `-0` below `+0`).
fn ord(x: &str) -> String {
    format!("({x}[31] ? ~{x} : {{1'b1, {x}[30:0]}})")
}

/// `x` is a NaN.
fn nan(x: &str) -> String {
    format!("(&{x}[30:23] & |{x}[22:0])")
}

/// `a < b` for binary32 (IEEE: NaN unordered, `-0 == +0`).
fn less(a: &str, b: &str) -> String {
    format!(
        "(~{na} & ~{nb} & ~(~|{a}[30:0] & ~|{b}[30:0]) & ({oa} < {ob}))",
        na = nan(a),
        nb = nan(b),
        oa = ord(a),
        ob = ord(b)
    )
}

fn inline(expr: String, registered: bool) -> Lowering {
    Lowering::Inline { expr, registered }
}

fn prim(module: &str, latency: u32, ports: &[&'static str]) -> Lowering {
    Lowering::Primitive(Primitive { module: module.into(), latency, ports: ports.to_vec() })
}

impl Library for PreLibrary {
    fn lower(&self, op: &Op, _ty: Ty) -> Lowering {
        use Op::*;
        let both_zero = "(~|$0[30:0] & ~|$1[30:0])";
        match *op {
            Input(_) | Lit(_) => inline(String::new(), false),
            Neg(_) => inline("{~$0[31], $0[30:0]}".into(), false),
            Abs(_) => inline("{1'b0, $0[30:0]}".into(), false),
            ExpField(_) => inline("{24'h000000, $0[30:23]}".into(), false),
            Pow2Field(_) => inline(
                "{1'b0, (($signed($0) < 32'sd1) ? 8'h01 : (($signed($0) > 32'sd254) ? 8'hfe : $0[7:0])), 23'h000000}"
                    .into(),
                true,
            ),
            IsNan(_) => inline(nan("$0"), true),
            IsFinite(_) => inline("~&$0[30:23]".into(), true),
            Lt(..) => inline(less("$0", "$1"), true),
            Le(..) => inline(format!("(~{} & ~{} & ({both_zero} | ({} <= {})))", nan("$0"), nan("$1"), ord("$0"), ord("$1")), true),
            Eq(..) => inline(format!("(~{} & ~{} & ({both_zero} | ($0 == $1)))", nan("$0"), nan("$1")), true),
            Max(..) => inline(format!("(({} | {}) ? $1 : $0)", less("$0", "$1"), nan("$0")), true),
            Min(..) => inline(format!("(({} | {}) ? $1 : $0)", less("$1", "$0"), nan("$0")), true),
            IAdd(..) => inline("$0 + $1".into(), true),
            ISub(..) => inline("$0 - $1".into(), true),
            IMin(..) => inline("(($signed($1) < $signed($0)) ? $1 : $0)".into(), true),
            IMax(..) => inline("(($signed($1) > $signed($0)) ? $1 : $0)".into(), true),
            ILt(..) => inline("($signed($0) < $signed($1))".into(), true),
            IEq(..) => inline("($0 == $1)".into(), true),
            And(..) => inline("$0 & $1".into(), true),
            Or(..) => inline("$0 | $1".into(), true),
            Not(_) => inline("~$0".into(), true),
            Select(..) | ISelect(..) => inline("($0 ? $1 : $2)".into(), true),
            // The binary32 arithmetic: pipelined primitives.
            Add(..) => prim("neo_fp_add", 4, &["a_i", "b_i"]),
            Sub(..) => prim("neo_fp_sub", 4, &["a_i", "b_i"]),
            Mul(..) => prim("neo_fp_mul", 3, &["a_i", "b_i"]),
            Div(..) => prim("neo_fp_div", 28, &["a_i", "b_i"]),
            Sqrt(_) => prim("neo_fp_sqrt", 28, &["a_i"]),
            ToInt(_, r) => prim(&format!("neo_fp_to_int_{}", format!("{r:?}").to_lowercase()), 2, &["a_i"]),
            IntToFloat(_) => prim("neo_fp_from_int", 3, &["a_i"]),
            F16Bits(_) => prim("neo_fp_f16", 2, &["a_i"]),
            WidenHalf(_) => prim("neo_fp_widen_half", 2, &["a_i"]),
        }
    }
}
