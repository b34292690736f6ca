//! The lowering of every [`Op`] for the Preprocessing Engine's datapaths: the binary32
//! arithmetic as pipelined primitives (`gen/src/units/fp`), compares as `neo_fp_cmp` behind
//! one register, everything else as inline logic (sign and exponent wiring unregistered;
//! selects, integer and boolean operations behind one register).

use super::datapath::{Library, Lowering, Primitive};
use crate::units::fp::{latency, module_name, params, FpPrim};
use neo_golden::hwarith::graph::{Op, Ty};

/// The Preprocessing Engine's library.
pub struct PreLibrary;

fn inline(expr: String, registered: bool) -> Lowering {
    Lowering::Inline { expr, registered }
}

fn prim(p: FpPrim) -> Lowering {
    let ports = if p.binary() { vec!["a_i", "b_i"] } else { vec!["a_i"] };
    Lowering::Primitive(Primitive {
        module: module_name(p).into(),
        latency: latency(p),
        ports,
        params: params(p),
    })
}

impl Library for PreLibrary {
    fn lower(&self, op: &Op, _ty: Ty) -> Lowering {
        use Op::*;
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
            IsNan(_) => inline("(&$0[30:23] & |$0[22:0])".into(), true),
            IsFinite(_) => inline("~&$0[30:23]".into(), true),
            // Compares: neo_fp_cmp (combinational), the output registered.
            Lt(..) => Lowering::Compare { output: "lt_o" },
            Le(..) => Lowering::Compare { output: "le_o" },
            Eq(..) => Lowering::Compare { output: "eq_o" },
            Max(..) => Lowering::Compare { output: "max_o" },
            Min(..) => Lowering::Compare { output: "min_o" },
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
            Add(..) => prim(FpPrim::Add),
            Sub(..) => prim(FpPrim::Sub),
            Mul(..) => prim(FpPrim::Mul),
            Div(..) => prim(FpPrim::Div),
            Sqrt(_) => prim(FpPrim::Sqrt),
            ToInt(_, r) => prim(FpPrim::ToInt(r)),
            IntToFloat(_) => prim(FpPrim::FromInt),
            F16Bits(_) => prim(FpPrim::F16),
            WidenHalf(_) => prim(FpPrim::WidenHalf),
        }
    }
}
