//! Fixed-point (Q-format) descriptions and the two rounding rules every hardware format uses.
//!
//! A [`QFormat`] is `bits` total bits of which `frac` are fraction bits, two's complement when
//! `signed`. A raw integer `r` stands for the value `r * 2^-frac`.
//!
//! **Rounding.** Conversions from real values use *round half up*, `floor(v * 2^frac + 0.5)`
//! (ties go toward +infinity, also for negative values), or, where a bound must stay
//! conservative, *round up* (`ceil`). Integer right shifts inside the datapaths use the same
//! round-half-up rule, [`shr_round`]: `floor(x / 2^s + 1/2)` = `(x + 2^(s-1)) >> s` with an
//! arithmetic shift. One rule everywhere keeps the RTL small (an adder before each shift).
//!
//! **Saturation.** Values beyond the range clamp to the smallest or largest raw value; NaN
//! quantises to 0.

/// A fixed-point format: `bits` total bits, `frac` fraction bits, optionally signed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize)]
pub struct QFormat {
    /// Total width in bits (1..=32; a signed format needs at least 2).
    pub bits: u8,
    /// Fraction bits: one LSB is `2^-frac`.
    pub frac: u8,
    /// Two's complement when true, unsigned otherwise.
    pub signed: bool,
}

/// Why a format cannot be used.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{field}: {problem}")]
pub struct FormatError {
    /// The field or format at fault.
    pub field: &'static str,
    /// What is wrong with it.
    pub problem: String,
}

impl FormatError {
    /// An error about `field`.
    pub fn new(field: &'static str, problem: impl Into<String>) -> Self {
        FormatError { field, problem: problem.into() }
    }
}

impl QFormat {
    /// A signed format of `bits` bits with `frac` fraction bits.
    pub const fn signed(bits: u8, frac: u8) -> Self {
        QFormat { bits, frac, signed: true }
    }

    /// An unsigned format of `bits` bits with `frac` fraction bits.
    pub const fn unsigned(bits: u8, frac: u8) -> Self {
        QFormat { bits, frac, signed: false }
    }

    /// Checks the widths: `1 <= bits <= 32` (`2..=32` when signed), `frac <= 40`. `name` labels
    /// the error.
    pub fn check(&self, name: &'static str) -> Result<(), FormatError> {
        let min = if self.signed { 2 } else { 1 };
        if !(min..=32).contains(&self.bits) {
            return Err(FormatError::new(name, format!("width {} bits is outside {min}..=32", self.bits)));
        }
        if self.frac > 40 {
            return Err(FormatError::new(name, format!("{} fraction bits is above 40", self.frac)));
        }
        Ok(())
    }

    /// Integer bits (excluding the sign bit): `bits - frac - signed`. May be negative.
    pub fn int_bits(&self) -> i32 {
        self.bits as i32 - self.frac as i32 - self.signed as i32
    }

    /// Smallest raw value: `-2^(bits-1)` when signed, else 0.
    pub fn min_raw(&self) -> i64 {
        if self.signed {
            -(1i64 << (self.bits - 1))
        } else {
            0
        }
    }

    /// Largest raw value: `2^(bits-1) - 1` when signed, else `2^bits - 1`.
    pub fn max_raw(&self) -> i64 {
        if self.signed {
            (1i64 << (self.bits - 1)) - 1
        } else {
            (1i64 << self.bits) - 1
        }
    }

    /// Value of one LSB, `2^-frac`.
    pub fn lsb(&self) -> f64 {
        (-(self.frac as f64)).exp2()
    }

    /// Smallest representable value.
    pub fn min_value(&self) -> f64 {
        self.dequantize(self.min_raw())
    }

    /// Largest representable value.
    pub fn max_value(&self) -> f64 {
        self.dequantize(self.max_raw())
    }

    /// `v` to raw, rounding half up (`floor(v * 2^frac + 0.5)`) and saturating; NaN gives 0.
    /// Error `<= lsb / 2` inside `[min_value, max_value]`.
    pub fn quantize(&self, v: f64) -> i64 {
        self.saturate_real((v * (self.frac as f64).exp2() + 0.5).floor())
    }

    /// `v` to raw, rounding up (`ceil(v * 2^frac)`) and saturating; NaN gives the largest raw
    /// value (used for conservative bounds). The result is `>= v` unless saturated at the top.
    pub fn quantize_ceil(&self, v: f64) -> i64 {
        if v.is_nan() {
            return self.max_raw();
        }
        self.saturate_real((v * (self.frac as f64).exp2()).ceil())
    }

    /// The value of raw `r`: `r * 2^-frac` (exact for every raw value of a valid format).
    pub fn dequantize(&self, r: i64) -> f64 {
        r as f64 * self.lsb()
    }

    /// Clamps a raw integer into range.
    pub fn saturate(&self, r: i64) -> i64 {
        r.clamp(self.min_raw(), self.max_raw())
    }

    /// Clamps an already rounded real to the raw range (NaN gives 0).
    fn saturate_real(&self, r: f64) -> i64 {
        if r.is_nan() {
            0
        } else {
            r.clamp(self.min_raw() as f64, self.max_raw() as f64) as i64
        }
    }

    /// The `bits`-wide field holding raw `r` (two's complement for signed formats).
    pub fn to_field(&self, r: i64) -> u64 {
        (r as u64) & ((1u64 << self.bits) - 1)
    }

    /// The raw value of a `bits`-wide field (sign-extended for signed formats).
    pub fn from_field(&self, field: u64) -> i64 {
        let field = field & ((1u64 << self.bits) - 1);
        if self.signed {
            let shift = 64 - self.bits as u32;
            ((field << shift) as i64) >> shift
        } else {
            field as i64
        }
    }
}

/// Round-half-up right shift: `floor(x / 2^s + 1/2)`, i.e. `(x + 2^(s-1)) >> s` (arithmetic).
/// `s = 0` returns `x`. Panics in debug builds if `s >= 127`.
#[inline(always)]
pub fn shr_round(x: i128, s: u32) -> i128 {
    if s == 0 {
        x
    } else {
        (x + (1i128 << (s - 1))) >> s
    }
}

/// [`shr_round`] on `i64` (same rule); `s` must be below 63.
#[inline(always)]
pub fn shr_round64(x: i64, s: u32) -> i64 {
    if s == 0 {
        x
    } else {
        (x + (1i64 << (s - 1))) >> s
    }
}

/// `ceil(x / 2^s)` for any integer `x` (arithmetic shift of the negation).
#[inline(always)]
pub fn shr_ceil64(x: i64, s: u32) -> i64 {
    -((-x) >> s)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn ranges_and_fields() {
        let s = QFormat::signed(8, 4);
        assert_eq!((s.min_raw(), s.max_raw()), (-128, 127));
        assert_eq!((s.min_value(), s.max_value()), (-8.0, 7.9375));
        assert_eq!(s.int_bits(), 3);
        let u = QFormat::unsigned(8, 8);
        assert_eq!((u.min_raw(), u.max_raw()), (0, 255));
        assert_eq!(s.to_field(-1), 0xFF);
        assert_eq!(s.from_field(0xFF), -1);
        assert_eq!(s.from_field(0x80), -128);
        assert_eq!(u.from_field(0x1FF), 255);
        assert!(QFormat::signed(1, 0).check("x").is_err());
        assert!(QFormat::unsigned(33, 0).check("x").is_err());
        assert!(QFormat::unsigned(32, 41).check("x").is_err());
        assert!(QFormat::unsigned(32, 40).check("x").is_ok());
    }

    #[test]
    fn rounding_is_half_up_and_saturating() {
        let f = QFormat::signed(8, 1);
        assert_eq!(f.quantize(0.25), 1); // 0.5 -> 1 (tie up)
        assert_eq!(f.quantize(-0.25), 0); // -0.5 -> 0 (tie up, toward +inf)
        assert_eq!(f.quantize(-0.26), -1);
        assert_eq!(f.quantize(1e9), 127);
        assert_eq!(f.quantize(-1e9), -128);
        assert_eq!(f.quantize(f64::NAN), 0);
        assert_eq!(f.quantize_ceil(0.01), 1);
        assert_eq!(f.quantize_ceil(-0.49), 0);
        assert_eq!(f.quantize_ceil(f64::NAN), 127);
        assert_eq!(shr_round(5, 1), 3); // 2.5 -> 3
        assert_eq!(shr_round(-5, 1), -2); // -2.5 -> -2
        assert_eq!(shr_round(-6, 2), -1); // -1.5 -> -1
        assert_eq!(shr_round64(7, 0), 7);
        assert_eq!(shr_ceil64(5, 1), 3);
        assert_eq!(shr_ceil64(-5, 1), -2);
    }

    proptest! {
        #[test]
        fn quantise_error_is_half_an_lsb(v in -200.0f64..200.0, bits in 10u8..=32, frac in 0u8..=16, signed: bool) {
            let f = QFormat { bits, frac, signed };
            let r = f.quantize(v);
            prop_assert!(r >= f.min_raw() && r <= f.max_raw());
            let back = f.dequantize(r);
            if v >= f.min_value() && v <= f.max_value() {
                prop_assert!((back - v).abs() <= f.lsb() / 2.0, "{:?} {} {}", f, v, back);
            } else {
                prop_assert!(r == f.min_raw() || r == f.max_raw());
            }
            let c = f.quantize_ceil(v);
            if v <= f.max_value() && v >= f.min_value() {
                prop_assert!(f.dequantize(c) >= v && f.dequantize(c) - v < f.lsb());
            }
            prop_assert_eq!(f.from_field(f.to_field(r)), r);
        }

        #[test]
        fn shifts_match_real_rounding(x in -1_000_000i64..1_000_000, s in 0u32..20) {
            let exact = x as f64 / (s as f64).exp2();
            prop_assert_eq!(shr_round64(x, s) as f64, (exact + 0.5).floor());
            prop_assert_eq!(shr_round(x as i128, s) as f64, (exact + 0.5).floor());
            prop_assert_eq!(shr_ceil64(x, s) as f64, exact.ceil());
        }
    }
}
