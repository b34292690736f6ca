//! [`Native`]: the hardware arithmetic evaluated with Rust's `f32`, and the specification of
//! every operation the RTL primitives implement.

use super::{Arith, Round, CANONICAL_NAN};

/// Evaluates [`Arith`] programs directly (one value per call, no state).
#[derive(Clone, Copy, Debug, Default)]
pub struct Native;

/// [`Native`] without the canonicalisation of NaN results: an arithmetic NaN keeps whatever
/// sign and payload the host's float unit gives it. Every result is [`Native`]'s but for the
/// bits of a NaN, and no operation's result depends on those bits: arithmetic on a NaN gives
/// a NaN, the comparisons, `is_nan`, `is_finite`, `min`/`max` (which test `is_nan`), `to_int`
/// (NaN gives 0), `exp_field` (255 for every NaN) and `f16_bits` (0x7BFF for every NaN) look
/// only at NaN-ness, and `neg`, `abs` and `select` keep a NaN a NaN. So a program evaluated
/// with `Relaxed` gives [`Native`]'s results bit for bit once its float outputs pass through
/// [`canonical`]; it skips a test and a select per operation, most of the preprocessing's
/// instructions. `hwpre::preprocess_one` uses it so; its tests compare it with [`Native`].
#[derive(Clone, Copy, Debug, Default)]
pub struct Relaxed;

/// `v`, with any NaN replaced by the canonical one. Tested on the bits: Rust leaves the payload
/// of an operation's NaN unspecified, and an optimiser may fold a float-level `is_nan` select
/// into the operation's own NaN.
pub fn canonical(v: f32) -> f32 {
    if v.to_bits() & 0x7FFF_FFFF > 0x7F80_0000 {
        f32::from_bits(CANONICAL_NAN)
    } else {
        v
    }
}

/// The exact rounding of `a` to an integer, saturated to `i32` (NaN gives 0).
pub(crate) fn round_to_i32(a: f32, mode: Round) -> i32 {
    if a.is_nan() {
        return 0;
    }
    // f32 -> f64 is exact; the f64 floor/ceil/trunc are exact, and `x + 0.5` is exact for
    // every f32 that matters (an inexact sum only happens for |x| < 2^-29, where the floor
    // is 0 either way, or for even integers >= 2^52, which saturate).
    let x = a as f64;
    let r = match mode {
        Round::Trunc => x.trunc(),
        Round::Floor => x.floor(),
        Round::Ceil => x.ceil(),
        Round::HalfUp => (x + 0.5).floor(),
    };
    r.clamp(i32::MIN as f64, i32::MAX as f64) as i32
}

/// The exact binary32 value of binary16 bits `h` (low 16 bits), by moving its fields (no
/// `powi`): a normal half's exponent is rebiased from 15 to 127 and its mantissa widened by 13
/// bits; a subnormal half is its mantissa times 2^-24 (exact: the mantissa has 10 bits);
/// exponent 31 keeps its mantissa (infinity or NaN).
fn half_to_f32(h: u32) -> f32 {
    let sign = (h & 0x8000) << 16;
    let (exp, mant) = ((h >> 10) & 0x1F, h & 0x3FF);
    let normal = ((h & 0x7FFF) << 13) + ((127 - 15) << 23);
    let subnormal = (mant as f32 * f32::from_bits(0x3380_0000)).to_bits();
    let special = 0x7F80_0000 | (mant << 13);
    let magnitude = if exp == 0 {
        subnormal
    } else if exp == 0x1F {
        special
    } else {
        normal
    };
    f32::from_bits(sign | magnitude)
}

/// `v` as the host made it ([`Relaxed`]'s results).
fn as_made(v: f32) -> f32 {
    v
}

/// The [`Arith`] implementation of [`Native`] and [`Relaxed`], one body: `$nan` is applied to
/// every arithmetic result.
macro_rules! native_arith {
    ($ty:ty, $nan:path) => {
        impl Arith for $ty {
            type F = f32;
            type I = i32;
            type B = bool;

            fn assume_f(&mut self, x: f32, lo: f32, hi: f32, why: &'static str) {
                debug_assert!((lo..=hi).contains(&x), "{why}: {x} outside [{lo}, {hi}]");
            }
            fn assume_i(&mut self, x: i32, lo: i32, hi: i32, why: &'static str) {
                debug_assert!((lo..=hi).contains(&x), "{why}: {x} outside [{lo}, {hi}]");
            }
            fn assume_zero_or(&mut self, x: f32, lo: f32, hi: f32, why: &'static str) {
                debug_assert!(
                    x == 0.0 || (lo..=hi).contains(&x.abs()),
                    "{why}: {x} is not 0 nor in [{lo}, {hi}]"
                );
            }

            fn lit(&mut self, v: f32) -> f32 {
                v
            }
            fn ilit(&mut self, v: i32) -> i32 {
                v
            }
            fn blit(&mut self, v: bool) -> bool {
                v
            }
            fn add(&mut self, a: f32, b: f32) -> f32 {
                $nan(a + b)
            }
            fn sub(&mut self, a: f32, b: f32) -> f32 {
                $nan(a - b)
            }
            fn mul(&mut self, a: f32, b: f32) -> f32 {
                $nan(a * b)
            }
            fn div(&mut self, a: f32, b: f32) -> f32 {
                $nan(a / b)
            }
            fn sqrt(&mut self, a: f32) -> f32 {
                $nan(a.sqrt())
            }
            fn neg(&mut self, a: f32) -> f32 {
                f32::from_bits(a.to_bits() ^ 0x8000_0000)
            }
            fn abs(&mut self, a: f32) -> f32 {
                f32::from_bits(a.to_bits() & 0x7FFF_FFFF)
            }
            fn max(&mut self, a: f32, b: f32) -> f32 {
                if b > a || a.is_nan() {
                    b
                } else {
                    a
                }
            }
            fn min(&mut self, a: f32, b: f32) -> f32 {
                if b < a || a.is_nan() {
                    b
                } else {
                    a
                }
            }
            fn lt(&mut self, a: f32, b: f32) -> bool {
                a < b
            }
            fn le(&mut self, a: f32, b: f32) -> bool {
                a <= b
            }
            fn eq(&mut self, a: f32, b: f32) -> bool {
                a == b
            }
            fn is_nan(&mut self, a: f32) -> bool {
                a.is_nan()
            }
            fn is_finite(&mut self, a: f32) -> bool {
                a.is_finite()
            }
            fn to_int(&mut self, a: f32, mode: Round) -> i32 {
                round_to_i32(a, mode)
            }
            fn int_to_float(&mut self, i: i32) -> f32 {
                i as f32
            }
            fn exp_field(&mut self, a: f32) -> i32 {
                ((a.to_bits() >> 23) & 0xFF) as i32
            }
            fn pow2_field(&mut self, e: i32) -> f32 {
                f32::from_bits((e.clamp(1, 254) as u32) << 23)
            }
            fn f16_bits(&mut self, a: f32) -> i32 {
                crate::sort::depth_key::f16_bits_saturating(a.abs()) as i32
            }
            fn widen_half(&mut self, h: i32) -> f32 {
                $nan(half_to_f32(h as u32 & 0xFFFF))
            }
            fn iadd(&mut self, a: i32, b: i32) -> i32 {
                a.wrapping_add(b)
            }
            fn isub(&mut self, a: i32, b: i32) -> i32 {
                a.wrapping_sub(b)
            }
            fn imin(&mut self, a: i32, b: i32) -> i32 {
                a.min(b)
            }
            fn imax(&mut self, a: i32, b: i32) -> i32 {
                a.max(b)
            }
            fn ilt(&mut self, a: i32, b: i32) -> bool {
                a < b
            }
            fn ieq(&mut self, a: i32, b: i32) -> bool {
                a == b
            }
            fn and(&mut self, a: bool, b: bool) -> bool {
                a && b
            }
            fn or(&mut self, a: bool, b: bool) -> bool {
                a || b
            }
            fn not(&mut self, a: bool) -> bool {
                !a
            }
            fn select(&mut self, c: bool, a: f32, b: f32) -> f32 {
                if c {
                    a
                } else {
                    b
                }
            }
            fn iselect(&mut self, c: bool, a: i32, b: i32) -> i32 {
                if c {
                    a
                } else {
                    b
                }
            }
        }
    };
}

native_arith!(Native, canonical);
native_arith!(Relaxed, as_made);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nan_results_are_canonical_and_min_max_skip_nan() {
        let mut a = Native;
        let nan = f32::from_bits(0xFFC1_2345);
        assert_eq!(a.add(nan, 1.0).to_bits(), CANONICAL_NAN);
        assert_eq!(a.sqrt(-1.0).to_bits(), CANONICAL_NAN);
        assert_eq!(a.sqrt(-0.0).to_bits(), 0x8000_0000);
        assert_eq!(a.max(nan, 2.0), 2.0);
        assert_eq!(a.max(2.0, nan), 2.0);
        assert_eq!(a.max(-0.0, 0.0).to_bits(), 0x8000_0000);
        assert_eq!(a.min(3.0, -1.0), -1.0);
    }

    #[test]
    fn nan_results_of_run_time_operands_are_canonical() {
        let mut a = Native;
        for bits in [0xBF80_0000u32, 0xC2F6_E979, 0xFF80_0000, 0x7FC1_2345, 0xFFC0_0001] {
            let x = std::hint::black_box(f32::from_bits(bits));
            assert_eq!(a.sqrt(x).to_bits(), CANONICAL_NAN, "sqrt {bits:#x}");
            let y = std::hint::black_box(f32::INFINITY);
            let nan = a.sub(y, y);
            assert_eq!(nan.to_bits(), CANONICAL_NAN);
            assert_eq!(a.mul(nan, x).to_bits(), CANONICAL_NAN, "NaN times {bits:#x}");
            assert_eq!(a.div(x, nan).to_bits(), CANONICAL_NAN);
        }
    }

    #[test]
    fn rounding_to_int_is_exact_and_saturates() {
        let mut a = Native;
        assert_eq!(a.to_int(-2.5, Round::HalfUp), -2);
        assert_eq!(a.to_int(2.5, Round::HalfUp), 3);
        assert_eq!(a.to_int(0.49999997, Round::HalfUp), 0);
        assert_eq!(a.to_int(-1.5, Round::Trunc), -1);
        assert_eq!(a.to_int(-1.5, Round::Floor), -2);
        assert_eq!(a.to_int(1.000_000_1, Round::Ceil), 2);
        assert_eq!(a.to_int(3e9, Round::Trunc), i32::MAX);
        assert_eq!(a.to_int(f32::NEG_INFINITY, Round::Ceil), i32::MIN);
        assert_eq!(a.to_int(f32::NAN, Round::Floor), 0);
    }

    #[test]
    fn exponent_fields_and_half_bits() {
        let mut a = Native;
        assert_eq!(a.exp_field(1.0), 127);
        assert_eq!(a.exp_field(1e-40), 0);
        assert_eq!(a.pow2_field(130), 8.0);
        assert_eq!(a.pow2_field(0).to_bits(), 1 << 23);
        assert_eq!(a.f16_bits(-1.0), 0x3C00);
        assert_eq!(a.f16_bits(f32::INFINITY), 0x7BFF);
        assert_eq!(a.widen_half(0x3C00), 1.0);
        assert_eq!(a.widen_half(0x1_8001), -(2f32.powi(-24)));
        assert_eq!(a.widen_half(0x7E01).to_bits(), CANONICAL_NAN);
    }

    #[test]
    fn every_half_widens_to_its_exact_value() {
        let mut a = Native;
        for h in 0..=0xFFFFu32 {
            let (exp, mant) = ((h >> 10) & 0x1F, h & 0x3FF);
            let sign = if h & 0x8000 != 0 { -1.0 } else { 1.0 };
            let want = match exp {
                0 => sign * mant as f64 * (-24f64).exp2(),
                0x1F if mant == 0 => sign * f64::INFINITY,
                0x1F => f64::NAN,
                _ => sign * (1024 + mant) as f64 * (exp as f64 - 25.0).exp2(),
            };
            let got = a.widen_half(h as i32 | 0x5A_0000);
            if want.is_nan() {
                assert_eq!(got.to_bits(), CANONICAL_NAN, "{h:#06x}");
            } else {
                assert_eq!(got.to_bits(), (want as f32).to_bits(), "{h:#06x}");
                assert_eq!(got as f64, want, "{h:#06x} is not exact");
            }
        }
    }
}
