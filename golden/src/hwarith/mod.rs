//! The preprocessing hardware's arithmetic: the operations the Preprocessing Engine's RTL
//! performs, defined once so that golden, the Verilog generator and the benches agree bit for bit.
//!
//! Algorithms are written once, generic over [`Arith`]:
//! - [`Native`] evaluates them with Rust's `f32`, every operation as specified;
//! - [`Relaxed`] does the same but leaves a NaN result as the host made it, which is faster and
//!   gives [`Native`]'s results once the program's float outputs pass through [`canonical`]
//!   (golden's bit-exact preprocessing uses it so);
//! - a tracing implementation records the same calls as a dataflow graph, from which `gen`
//!   emits the pipelined Verilog (so the RTL performs exactly these operations, in this order).
//!
//! # Values
//! - `F`: an IEEE 754 binary32 value. Arithmetic ([`Arith::add`], [`Arith::sub`],
//!   [`Arith::mul`], [`Arith::div`], [`Arith::sqrt`]) is IEEE binary32 with round to nearest,
//!   ties to even, with subnormal inputs and results (no flush to zero). Rust's `f32`
//!   operations are exactly that on every platform neo supports. A NaN result is always the
//!   canonical quiet NaN [`CANONICAL_NAN`], so results compare bit for bit.
//! - `I`: a 32-bit two's-complement integer; integer arithmetic wraps.
//! - `B`: a boolean.
//!
//! Every other operation is defined below by its `Native` implementation, which is the
//! specification the RTL primitive must meet for every input bit pattern.

pub mod graph;
mod native;

pub use native::{canonical, Native, Relaxed};

/// The one NaN arithmetic produces (sign 0, quiet bit set, payload 0).
pub const CANONICAL_NAN: u32 = 0x7FC0_0000;

/// How [`Arith::to_int`] rounds a binary32 value to an integer. The rounding is exact (of the
/// real value, not of an intermediate float).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize)]
pub enum Round {
    /// Toward zero (Rust's `as i32`).
    Trunc,
    /// Toward minus infinity.
    Floor,
    /// Toward plus infinity.
    Ceil,
    /// To nearest, halves up: `floor(x + 1/2)` of the exact value.
    HalfUp,
}

impl Round {
    /// Every rounding mode, for benches that sweep them.
    pub const ALL: [Round; 4] = [Round::Trunc, Round::Floor, Round::Ceil, Round::HalfUp];
}

/// Names each of `values` after the name at the same place of `names` ([`Arith::name_f`]), for
/// the program's arrays (a vector's components, a colour's channels).
pub fn name_each<A: Arith + ?Sized, const N: usize>(
    a: &mut A,
    values: [A::F; N],
    names: [&'static str; N],
) -> [A::F; N] {
    std::array::from_fn(|k| a.name_f(values[k], names[k]))
}

/// The operations of the preprocessing datapath. Each call is one hardware operator (or, for
/// the sign and select operations, wiring and a multiplexer).
pub trait Arith {
    /// A binary32 value.
    type F: Copy;
    /// A 32-bit integer.
    type I: Copy;
    /// A boolean.
    type B: Copy;

    /// A binary32 constant.
    fn lit(&mut self, v: f32) -> Self::F;
    /// An integer constant.
    fn ilit(&mut self, v: i32) -> Self::I;
    /// A boolean constant.
    fn blit(&mut self, v: bool) -> Self::B;

    /// `a + b` (IEEE, RNE; NaN canonical).
    fn add(&mut self, a: Self::F, b: Self::F) -> Self::F;
    /// `a - b` (IEEE, RNE; NaN canonical).
    fn sub(&mut self, a: Self::F, b: Self::F) -> Self::F;
    /// `a * b` (IEEE, RNE; NaN canonical).
    fn mul(&mut self, a: Self::F, b: Self::F) -> Self::F;
    /// `a / b` (IEEE, RNE; NaN canonical).
    fn div(&mut self, a: Self::F, b: Self::F) -> Self::F;
    /// `sqrt(a)` (IEEE, RNE; `sqrt(-0) = -0`; negative gives NaN, canonical).
    fn sqrt(&mut self, a: Self::F) -> Self::F;
    /// `-a`: flips the sign bit (also of a NaN).
    fn neg(&mut self, a: Self::F) -> Self::F;
    /// `|a|`: clears the sign bit (also of a NaN).
    fn abs(&mut self, a: Self::F) -> Self::F;
    /// `b` if `b > a` or `a` is NaN, else `a` (so a NaN operand yields the other one, and
    /// `max(-0, +0) = -0`).
    fn max(&mut self, a: Self::F, b: Self::F) -> Self::F;
    /// `b` if `b < a` or `a` is NaN, else `a`.
    fn min(&mut self, a: Self::F, b: Self::F) -> Self::F;

    /// `a < b` (IEEE: false if either is NaN; `-0 == +0`).
    fn lt(&mut self, a: Self::F, b: Self::F) -> Self::B;
    /// `a <= b` (IEEE).
    fn le(&mut self, a: Self::F, b: Self::F) -> Self::B;
    /// `a == b` (IEEE).
    fn eq(&mut self, a: Self::F, b: Self::F) -> Self::B;
    /// `a` is a NaN.
    fn is_nan(&mut self, a: Self::F) -> Self::B;
    /// `a` is neither infinite nor NaN.
    fn is_finite(&mut self, a: Self::F) -> Self::B;

    /// `a` rounded to an integer as `mode` says, saturated to `[i32::MIN, i32::MAX]`; NaN
    /// gives 0.
    fn to_int(&mut self, a: Self::F, mode: Round) -> Self::I;
    /// `i` as binary32, RNE (Rust's `i as f32`).
    fn int_to_float(&mut self, i: Self::I) -> Self::F;
    /// The biased exponent field of `a` (bits 30..23, 0 for zeros and subnormals).
    fn exp_field(&mut self, a: Self::F) -> Self::I;
    /// `2^(e - 127)` for the biased exponent `e` clamped to `[1, 254]` (a positive power of
    /// two with a zero mantissa).
    fn pow2_field(&mut self, e: Self::I) -> Self::F;
    /// `|a|` as IEEE binary16 bits, rounded to nearest even, saturating at the largest finite
    /// half (0x7BFF); NaN and infinities also give 0x7BFF. The sort format's depth key.
    fn f16_bits(&mut self, a: Self::F) -> Self::I;
    /// The binary16 value in the low 16 bits of `h` (upper bits ignored), widened exactly
    /// (subnormal halves included; a half NaN gives the canonical NaN).
    fn widen_half(&mut self, h: Self::I) -> Self::F;

    /// `a + b`, wrapping.
    fn iadd(&mut self, a: Self::I, b: Self::I) -> Self::I;
    /// `a - b`, wrapping.
    fn isub(&mut self, a: Self::I, b: Self::I) -> Self::I;
    /// The smaller (signed).
    fn imin(&mut self, a: Self::I, b: Self::I) -> Self::I;
    /// The larger (signed).
    fn imax(&mut self, a: Self::I, b: Self::I) -> Self::I;
    /// `a < b` (signed).
    fn ilt(&mut self, a: Self::I, b: Self::I) -> Self::B;
    /// `a == b`.
    fn ieq(&mut self, a: Self::I, b: Self::I) -> Self::B;

    /// `a && b`.
    fn and(&mut self, a: Self::B, b: Self::B) -> Self::B;
    /// `a || b`.
    fn or(&mut self, a: Self::B, b: Self::B) -> Self::B;
    /// `!a`.
    fn not(&mut self, a: Self::B) -> Self::B;
    /// `c ? a : b` on binary32 values.
    fn select(&mut self, c: Self::B, a: Self::F, b: Self::F) -> Self::F;
    /// `c ? a : b` on integers.
    fn iselect(&mut self, c: Self::B, a: Self::I, b: Self::I) -> Self::I;

    /// A range the binary32 `x` always lies in, `lo <= x <= hi` (never NaN), proved by the
    /// program's author where `x` is made (`why`): no operation and no hardware. [`Native`]
    /// checks it in debug builds; a [`graph::Trace`] records it, [`graph::Graph::eval`] checks
    /// it on every item, and the datapath's known-bits analysis uses it.
    fn assume_f(&mut self, x: Self::F, lo: f32, hi: f32, why: &'static str);
    /// [`Arith::assume_f`] for an integer: `lo <= x <= hi`.
    fn assume_i(&mut self, x: Self::I, lo: i32, hi: i32, why: &'static str);
    /// [`Arith::assume_f`] for a binary32 that is a zero or of magnitude in `[lo, hi]`.
    fn assume_zero_or(&mut self, x: Self::F, lo: f32, hi: f32, why: &'static str);

    /// Names the binary32 `x` after the program's variable (lower case, digits and `_`), so
    /// the RTL's net for it reads `n<id>_<name>`: no operation, `x` unchanged. Only a
    /// [`graph::Trace`] records it; the first name given to a value wins.
    fn name_f(&mut self, x: Self::F, name: &'static str) -> Self::F {
        let _ = name;
        x
    }
    /// [`Arith::name_f`] for an integer.
    fn name_i(&mut self, x: Self::I, name: &'static str) -> Self::I {
        let _ = name;
        x
    }
    /// [`Arith::name_f`] for a boolean.
    fn name_b(&mut self, x: Self::B, name: &'static str) -> Self::B {
        let _ = name;
        x
    }
}
