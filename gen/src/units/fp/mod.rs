//! The binary32 primitives of the Preprocessing Engine's datapath (golden `hwarith`: every one
//! bit-exact against `Native` for every input bit pattern).
//!
//! Each pipelined primitive is one module (the four roundings of `to_int` one module with a
//! `ROUNDING` parameter, [`params`]) with the interface
//! `neo_fp_X (input clk_i, input en_i, input [31:0] a_i, [input [31:0] b_i,] output [31:0] y_o)`:
//! the result of the operands presented while `en_i` is high appears on `y_o` [`latency`]
//! enabled cycles later (the registers advance only when `en_i` is 1; datapath registers have
//! no reset); every primitive accepts one operation per cycle. Integer operands and results
//! are 32-bit two's complement.
//!
//! | primitive          | module                      | golden op        |
//! |--------------------|-----------------------------|------------------|
//! | [`FpPrim::Add`]    | `neo_fp_add`                | `add`            |
//! | [`FpPrim::Sub`]    | `neo_fp_sub` (the adder, b negated) | `sub`    |
//! | [`FpPrim::Mul`]    | `neo_fp_mul`                | `mul`            |
//! | [`FpPrim::Div`]    | `neo_fp_div` (+ `neo_fp_div_stage`)   | `div`  |
//! | [`FpPrim::Sqrt`]   | `neo_fp_sqrt` (+ `neo_fp_sqrt_stage`) | `sqrt` |
//! | [`FpPrim::ToInt`]  | `neo_fp_to_int` (`ROUNDING`: the mode, [`conv::ROUNDINGS`]) | `to_int` |
//! | [`FpPrim::FromInt`]| `neo_fp_from_int`           | `int_to_float`   |
//! | [`FpPrim::F16`]    | `neo_fp_f16`                | `f16_bits`       |
//! | [`FpPrim::WidenHalf`] | `neo_fp_widen_half`      | `widen_half`     |
//!
//! The normalising primitives count leading zeros with `neo_fp_lzc #(WIDTH)` ([`lzc`]).
//!
//! `neo_fp_cmp` ([`cmp`]) is combinational (latency 0): `lt`, `le`, `eq`, `max`, `min` of two
//! operands. The remaining operations (`neg`, `abs`, `is_nan`, `is_finite`, `exp_field`,
//! `pow2_field`, `select`, the integer and boolean operations) are wiring and small logic the
//! datapath emitter writes inline. `neo_fp_bench` ([`bench`]) holds every primitive side by
//! side for the cosimulation bench.

pub mod add;
pub mod bench;
pub mod cmp;
pub mod common;
pub mod conv;
pub mod div;
pub mod lzc;
pub mod mul;
pub mod sqrt;

use crate::emit::Module;
use neo_golden::engine::EngineConfig;
use neo_golden::hwarith::Round;

/// A pipelined binary32 primitive.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum FpPrim {
    /// `a + b`.
    Add,
    /// `a - b`.
    Sub,
    /// `a * b`.
    Mul,
    /// `a / b`.
    Div,
    /// `sqrt(a)`.
    Sqrt,
    /// `to_int(a, mode)`.
    ToInt(Round),
    /// `int_to_float(a)`.
    FromInt,
    /// `f16_bits(a)`.
    F16,
    /// `widen_half(a)`.
    WidenHalf,
}

impl FpPrim {
    /// Every primitive, in the order [`modules`] emits them.
    pub const ALL: [FpPrim; 12] = [
        FpPrim::Add,
        FpPrim::Sub,
        FpPrim::Mul,
        FpPrim::Div,
        FpPrim::Sqrt,
        FpPrim::ToInt(Round::Trunc),
        FpPrim::ToInt(Round::Floor),
        FpPrim::ToInt(Round::Ceil),
        FpPrim::ToInt(Round::HalfUp),
        FpPrim::FromInt,
        FpPrim::F16,
        FpPrim::WidenHalf,
    ];

    /// True when the primitive has a second operand `b_i`.
    pub fn binary(self) -> bool {
        matches!(self, FpPrim::Add | FpPrim::Sub | FpPrim::Mul | FpPrim::Div)
    }

    /// A short name, unique per primitive: the module name without `neo_fp_` (`add`, ...), and
    /// the rounding for `to_int` (`to_int_floor`, ...).
    pub fn short(self) -> &'static str {
        match self {
            FpPrim::ToInt(Round::Trunc) => "to_int_trunc",
            FpPrim::ToInt(Round::Floor) => "to_int_floor",
            FpPrim::ToInt(Round::Ceil) => "to_int_ceil",
            FpPrim::ToInt(Round::HalfUp) => "to_int_halfup",
            _ => &module_name(self)["neo_fp_".len()..],
        }
    }
}

/// The Verilog module of primitive `p`.
pub fn module_name(p: FpPrim) -> &'static str {
    match p {
        FpPrim::Add => "neo_fp_add",
        FpPrim::Sub => "neo_fp_sub",
        FpPrim::Mul => "neo_fp_mul",
        FpPrim::Div => "neo_fp_div",
        FpPrim::Sqrt => "neo_fp_sqrt",
        FpPrim::ToInt(_) => conv::TO_INT_NAME,
        FpPrim::FromInt => "neo_fp_from_int",
        FpPrim::F16 => "neo_fp_f16",
        FpPrim::WidenHalf => "neo_fp_widen_half",
    }
}

/// Primitive `p` as messages and reports name it: its module, and for `to_int` the rounding's
/// `ROUNDING` value by name (`neo_fp_to_int #(ROUND_FLOOR)`).
pub fn label(p: FpPrim) -> String {
    match p {
        FpPrim::ToInt(mode) => {
            let name = conv::ROUNDINGS.iter().find(|r| r.0 == mode).map_or("?", |r| r.1);
            format!("{} #({name})", conv::TO_INT_NAME)
        }
        _ => module_name(p).to_string(),
    }
}

/// The parameter overrides an instance of primitive `p` needs: `ROUNDING` for `to_int`, none
/// for the others.
pub fn params(p: FpPrim) -> Vec<(String, String)> {
    match p {
        FpPrim::ToInt(mode) => vec![("ROUNDING".into(), conv::rounding_code(mode).to_string())],
        _ => Vec::new(),
    }
}

/// Enabled cycles from operands to result of primitive `p` (the one place a latency is
/// written: each generator asserts it emitted this many register stages, and the bench
/// measures it on the RTL).
pub fn latency(p: FpPrim) -> u32 {
    match p {
        FpPrim::Add | FpPrim::Sub | FpPrim::Mul => 4,
        FpPrim::Div => 1 + div::DIV_STAGES + 2,
        FpPrim::Sqrt => 1 + sqrt::SQRT_STAGES + 1,
        FpPrim::ToInt(_) => 2,
        FpPrim::FromInt => 3,
        FpPrim::F16 => 2,
        FpPrim::WidenHalf => 1,
    }
}

/// The module of primitive `p` (the same module for every rounding of `to_int`).
pub fn module(p: FpPrim) -> Module {
    match p {
        FpPrim::Add => add::add(),
        FpPrim::Sub => add::sub(),
        FpPrim::Mul => mul::module(),
        FpPrim::Div => div::module(),
        FpPrim::Sqrt => sqrt::module(),
        FpPrim::ToInt(_) => conv::to_int(),
        FpPrim::FromInt => conv::from_int(),
        FpPrim::F16 => conv::f16(),
        FpPrim::WidenHalf => conv::widen_half(),
    }
}

/// Places an instance `inst` of primitive `p` in `m` (with its [`params`]): `clk_i` from `clk_i`, `en_i` from `en`,
/// operands `a` (and `b`, required exactly when [`FpPrim::binary`]) and the result on `y`.
///
/// # Panics
/// When `b` is given for a unary primitive or missing for a binary one.
pub fn instantiate(m: &mut Module, p: FpPrim, inst: &str, en: &str, a: &str, b: Option<&str>, y: &str) {
    assert_eq!(b.is_some(), p.binary(), "{}: operand b", module_name(p));
    let mut c = vec![("clk_i", "clk_i".to_string()), ("en_i", en.to_string()), ("a_i", a.to_string())];
    if let Some(b) = b {
        c.push(("b_i", b.to_string()));
    }
    c.push(("y_o", y.to_string()));
    m.instance_with(module_name(p), inst, params(p), crate::emit::conns(&c));
}

/// Every module of the primitives, leaves first: the recurrence stages, the primitives, the
/// comparator and the bench top `neo_fp_bench`. They do not depend on the configuration.
pub fn modules(_cfg: &EngineConfig) -> Vec<Module> {
    let mut all = vec![lzc::module(), div::stage_module(), sqrt::stage_module(), conv::widen_half_comb()];
    for p in FpPrim::ALL {
        if !all.iter().any(|m| m.name == module_name(p)) {
            all.push(module(p));
        }
    }
    all.push(cmp::module());
    all.push(bench::module());
    all
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_unique_and_every_primitive_has_the_common_ports() {
        let mut shorts: Vec<&str> = FpPrim::ALL.iter().map(|&p| p.short()).collect();
        shorts.sort_unstable();
        shorts.dedup();
        assert_eq!(shorts.len(), FpPrim::ALL.len());
        // One module per primitive but the roundings of to_int, which share one (a parameter).
        let mut names: Vec<&str> = FpPrim::ALL.iter().map(|&p| module_name(p)).collect();
        names.sort_unstable();
        names.dedup();
        assert_eq!(names.len(), FpPrim::ALL.len() - 3);
        let codes: Vec<Vec<(String, String)>> = FpPrim::ALL.iter().map(|&p| params(p)).collect();
        for (k, c) in codes.iter().enumerate() {
            let to_int = matches!(FpPrim::ALL[k], FpPrim::ToInt(_));
            assert_eq!(c.len(), usize::from(to_int), "{:?}", FpPrim::ALL[k]);
            assert!(!to_int || codes.iter().filter(|o| *o == c).count() == 1, "ROUNDING codes are distinct");
        }
        for p in FpPrim::ALL {
            let i = module(p).interface();
            let ports: Vec<(&str, u32)> = i.ports.iter().map(|p| (p.name.as_str(), p.width)).collect();
            let mut want = vec![("clk_i", 1), ("en_i", 1), ("a_i", 32)];
            if p.binary() {
                want.push(("b_i", 32));
            }
            want.push(("y_o", 32));
            assert_eq!(ports, want, "{p:?}");
            assert!(latency(p) >= 1);
        }
    }

    #[test]
    fn instantiate_connects_the_common_ports() {
        let mut m = Module::new("t");
        instantiate(&mut m, FpPrim::Mul, "u_mul", "adv", "x", Some("w"), "p");
        instantiate(&mut m, FpPrim::Sqrt, "u_sqrt", "adv", "p", None, "r");
        let v = m.to_verilog();
        assert!(v.contains("neo_fp_mul u_mul (\n    .clk_i(clk_i),\n    .en_i(adv),\n    .a_i(x),\n    .b_i(w),\n    .y_o(p)\n  );"), "{v}");
        assert!(
            v.contains(
                "neo_fp_sqrt u_sqrt (\n    .clk_i(clk_i),\n    .en_i(adv),\n    .a_i(p),\n    .y_o(r)\n  );"
            ),
            "{v}"
        );
        assert_eq!(m.instantiated(), ["neo_fp_mul", "neo_fp_sqrt"]);
    }

    #[test]
    #[should_panic(expected = "operand b")]
    fn instantiate_refuses_a_missing_operand() {
        instantiate(&mut Module::new("t"), FpPrim::Add, "u", "en_i", "a", None, "y");
    }

    #[test]
    fn recurrences_have_one_stage_per_two_bits() {
        assert_eq!(latency(FpPrim::Div), 1 + 13 + 2);
        assert_eq!(latency(FpPrim::Sqrt), 1 + 13 + 1);
        let placed = module(FpPrim::Div).placements();
        let loops: Vec<_> =
            placed.iter().filter(|p| matches!(p, crate::emit::Placement::Loop { .. })).collect();
        assert!(matches!(loops.as_slice(), [crate::emit::Placement::Loop { count: 13, .. }]), "{placed:?}");
    }
}
