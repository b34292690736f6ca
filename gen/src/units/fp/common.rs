//! Building blocks shared by the binary32 primitives: pipeline registers advanced by `en_i`,
//! operand unpacking, a leading-zero counter instance, the subnormal right shift with sticky and the
//! round-to-nearest-even packer.

use crate::emit::expr::hex;
use crate::emit::{conns, if_, set, Module};

/// The canonical quiet NaN every NaN result is replaced by (golden `hwarith::CANONICAL_NAN`).
pub const CANONICAL_NAN: &str = "32'h7fc00000";

/// A pipelined primitive under construction: the module and the number of register stages
/// emitted so far (the generator checks it against [`super::latency`]).
pub struct Pipe {
    /// The module.
    pub m: Module,
    /// Register stages emitted.
    pub stages: u32,
    /// Bits computed but not read (shifted-out halves, padding), collected into `unused_bits`
    /// by [`Pipe::finish`] (Verilator's convention for intentionally unused bits).
    pub unused: Vec<String>,
}

impl Pipe {
    /// The common ports of a pipelined primitive: `clk_i`, `en_i`, `a_i`, optionally `b_i`,
    /// and `y_o`.
    #[track_caller]
    pub fn new(name: &str, binary: bool) -> Pipe {
        let mut m = Module::new(name);
        m.input_c("clk_i", 1, "clock");
        m.input_c("en_i", 1, "advance the pipeline (registers hold while low)");
        m.input_c("a_i", 32, "operand a");
        if binary {
            m.input_c("b_i", 32, "operand b");
        }
        m.output_c("y_o", 32, "result of the operands presented LATENCY enabled cycles earlier");
        Pipe { m, stages: 0, unused: Vec::new() }
    }

    /// A combinational unary module: `a_i` and `y_o` only (no clock, no stage).
    pub fn combinational(name: &str) -> Pipe {
        let mut m = Module::new(name);
        m.input_c("a_i", 32, "operand a");
        m.output_c("y_o", 32, "result (combinational)");
        Pipe { m, stages: 0, unused: Vec::new() }
    }

    /// Records bits that are intentionally not read.
    pub fn unused(&mut self, bits: impl Into<String>) {
        self.unused.push(bits.into());
    }

    /// The finished module: the unused bits reduced into `unused_bits`.
    pub fn finish(mut self) -> Module {
        if !self.unused.is_empty() {
            self.m.wire_assign("unused_bits", 1, format!("^{{{}}}", self.unused.join(", ")));
        }
        self.m
    }

    /// A wire `name` of `width` bits driven by `rhs`.
    pub fn w(&mut self, name: &str, width: u32, rhs: impl Into<String>) {
        self.m.wire_assign(name, width, rhs);
    }

    /// One register stage: each `(name, width, next)` becomes `reg name` loaded with `next`
    /// on every clock edge with `en_i` high (datapath registers, no reset).
    pub fn stage(&mut self, comment: &str, regs: &[(String, u32, String)]) {
        self.stages += 1;
        self.m.comment(format!("Stage {}: {comment}", self.stages));
        for (name, width, _) in regs {
            self.m.reg(name.clone(), *width);
        }
        let body = regs.iter().map(|(n, _, e)| set(n.clone(), e.clone())).collect();
        self.m.seq_noreset(vec![if_("en_i", body)]);
    }
}

/// `(name, width, next)` of a pipeline register.
pub fn r(name: impl Into<String>, width: u32, next: impl Into<String>) -> (String, u32, String) {
    (name.into(), width, next.into())
}

/// Name of a register of stage `k` (1-based): `x_q`, `x_q2`, `x_q3`, ...
pub fn q(name: &str, k: u32) -> String {
    if k == 1 {
        format!("{name}_q")
    } else {
        format!("{name}_q{k}")
    }
}

/// Which fields of a binary32 operand a primitive reads ([`unpack`]).
#[derive(Clone, Copy, Default)]
pub struct Fields {
    /// `P_nan`.
    pub nan: bool,
    /// `P_inf`.
    pub inf: bool,
    /// `P_zero`.
    pub zero: bool,
    /// `P_m`: the 24-bit significand with its hidden bit (0 for zeros and subnormals).
    pub m: bool,
    /// `P_ee`: the effective biased exponent (1 for zeros and subnormals).
    pub ee: bool,
}

/// Unpacks the binary32 value `x` into wires prefixed `p_`: `p_s` (sign) always, and the
/// fields selected by `f`.
pub fn unpack(pp: &mut Pipe, p: &str, x: &str, f: Fields) {
    pp.w(&format!("{p}_s"), 1, format!("{x}[31]"));
    pp.w(&format!("{p}_enz"), 1, format!("|{x}[30:23]"));
    if f.nan || f.inf {
        pp.w(&format!("{p}_emax"), 1, format!("&{x}[30:23]"));
    }
    if f.nan || f.inf || f.zero {
        pp.w(&format!("{p}_fnz"), 1, format!("|{x}[22:0]"));
    }
    if f.nan {
        pp.w(&format!("{p}_nan"), 1, format!("{p}_emax & {p}_fnz"));
    }
    if f.inf {
        pp.w(&format!("{p}_inf"), 1, format!("{p}_emax & ~{p}_fnz"));
    }
    if f.zero {
        pp.w(&format!("{p}_zero"), 1, format!("~{p}_enz & ~{p}_fnz"));
    }
    if f.m {
        pp.w(&format!("{p}_m"), 24, format!("{{{p}_enz, {x}[22:0]}}"));
    }
    if f.ee {
        pp.w(&format!("{p}_ee"), 8, format!("{p}_enz ? {x}[30:23] : 8'd1"));
    }
}

/// A leading-zero counter over wire `x` of `width` bits (a power of two, at least 2): an
/// instance `u_{p}` of [`super::lzc`] driving wires `{p}_c` (the count, log2(width) bits;
/// `width - 1` when `x` is zero) and `{p}_z` (x is zero; recorded as unused unless `zero`).
/// Returns the count's width.
pub fn lzc(pp: &mut Pipe, p: &str, x: &str, width: u32, zero: bool) -> u32 {
    let cw = super::lzc::count_bits(width);
    let (c, z) = (format!("{p}_c"), format!("{p}_z"));
    pp.m.wire(c.clone(), cw);
    pp.m.wire(z.clone(), 1);
    pp.m.instance_with(
        super::lzc::NAME,
        format!("u_{p}"),
        vec![("WIDTH".to_string(), width.to_string())],
        conns(&[("x_i", x.to_string()), ("cnt_o", c), ("zero_o", z.clone())]),
    );
    if !zero {
        pp.unused(z);
    }
    cw
}

/// The subnormal right shift of a normalised significand: `sig` (wire of `width` >= 26 bits,
/// its leading one at bit `width - 1` unless the value is subnormal after a limited left
/// shift) with signed 10-bit biased exponent `e` (the exponent of bit `width - 1`). When
/// `e <= 0` the significand is shifted right by `1 - e` (at most 31) and the exponent becomes
/// one. Wires: `{p}_top` (24 bits: 23 fraction bits, guard), `{p}_stk` (sticky: every
/// lower bit, shifted out or not, ORed with `extra`), `{p}_fld` (the 8-bit exponent field
/// before rounding: the exponent when the hidden bit is set, else 0) and `{p}_ovf` (`e >= 255`:
/// the result overflows to infinity).
pub fn denorm(pp: &mut Pipe, p: &str, sig: &str, width: u32, e: &str, extra: Option<&str>) {
    assert!(width >= 26);
    pp.w(&format!("{p}_le0"), 1, format!("{e}[9] | ({e} == 10'd0)"));
    pp.w(&format!("{p}_rsw"), 10, format!("10'd1 - {e}"));
    pp.w(&format!("{p}_rs"), 5, format!("{p}_le0 ? (({p}_rsw > 10'd31) ? 5'd31 : {p}_rsw[4:0]) : 5'd0"));
    pp.w(&format!("{p}_sh"), width, format!("{sig} >> {p}_rs"));
    let ones = hex(width, (1u64 << width) - 1);
    pp.w(&format!("{p}_out"), 1, format!("|({sig} & ~({ones} << {p}_rs))"));
    let low = format!("|{p}_sh[{}:0]", width - 26);
    let stk = match extra {
        Some(x) => format!("{p}_out | {low} | {x}"),
        None => format!("{p}_out | {low}"),
    };
    pp.w(&format!("{p}_stk"), 1, stk);
    pp.w(&format!("{p}_top"), 24, format!("{p}_sh[{}:{}]", width - 2, width - 25));
    pp.w(&format!("{p}_fld"), 8, format!("({p}_le0 | ~{p}_sh[{}]) ? 8'd0 : {e}[7:0]", width - 1));
    pp.w(&format!("{p}_ovf"), 1, format!("~{e}[9] & ({e} >= 10'd255)"));
}

/// Round to nearest even and pack: `fld` (8-bit exponent field), `top` (24 bits: 23 fraction
/// bits, guard), `stk` (sticky). Wire `{p}_mag` (31 bits: exponent and fraction
/// after rounding; a carry out of the fraction bumps the exponent, up to infinity).
pub fn round_pack(pp: &mut Pipe, p: &str, fld: &str, top: &str, stk: &str) {
    pp.w(&format!("{p}_inc"), 1, format!("{top}[0] & ({stk} | {top}[1])"));
    pp.w(&format!("{p}_mag"), 31, format!("{{{fld}, {top}[23:1]}} + {{30'd0, {p}_inc}}"));
}
