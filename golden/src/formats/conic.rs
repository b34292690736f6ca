//! The conic `(a, b, c)` (inverse 2D covariance) as a block floating-point triple: one shared
//! exponent per entry and three integer mantissas.
//!
//! # Why block floating point
//! Conics span ten orders of magnitude: `~3.3` for a Gaussian shrunk to the 0.3 px² dilation,
//! `~1e-9` for a ground splat next to the camera. A plain fixed point would need ~45 bits to give
//! both ends relative precision. `power = -(a dx² + 2 b dx dy + c dy²) / 2` is a quadratic form
//! whose three terms share one scale, so one exponent per entry is enough: the largest
//! coefficient is normalised to `M` significant bits and the others share its LSB.
//!
//! # Encoding
//! `value = mantissa * 2^-s` with `s = M - top + exp`, `exp` an unsigned `exp_bits` field and
//! `top` the largest power of two the format represents (values are below `2^top`; the +0.3 px²
//! dilation keeps every conic eigenvalue at or below `1/0.3 = 3.33 < 4`, so `top = 2`).
//! `a` and `c` are unsigned `M`-bit mantissas, `b` a signed `M + 1`-bit one (`|b| < sqrt(ac)`).
//!
//! [`ConicFormat::quantize`] picks the largest `s` (in range) at which
//! `round(max(a, |b|, c) * 2^s) <= 2^M - 1`, then rounds each coefficient half up. So the
//! largest mantissa has `M` significant bits (relative error `<= 2^-M`) unless the conic is
//! below the exponent range (then it loses precision gradually, like a subnormal) or above it
//! (then mantissas saturate). Negative `a` or `c` (not a positive definite input) clamp to 0;
//! NaN gives the all-zero conic.
//!
//! # Alpha error it causes
//! Each coefficient is off by at most half an LSB, `2^-(s+1) <= lambda_max 2^-M`. In the region
//! that matters (`d^T Q d <= 2 ln 255 = 11.1`, so `|d|² <= 11.1 / lambda_min`),
//! `|delta power| <= 0.5 * 2^-(s+1) (|dx| + |dy|)² <= 2^-(s+1) |d|² <= 11.1 * 2^-M * lambda_max / lambda_min`,
//! and `|delta alpha| <= alpha * |delta power|`. The bound grows with the anisotropy
//! `lambda_max / lambda_min`; for a needle every fixed representation of the orientation has
//! the same behaviour (the far end of the needle moves by `|d| * angle error`). See
//! docs/formats.md for the measured effect per mantissa width.

use super::fixed::FormatError;

/// Widths of the block floating-point conic.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize)]
pub struct ConicFormat {
    /// Mantissa bits `M` of `a` and `c` (`b` has `M + 1`, with its sign). 4..=30.
    pub mantissa_bits: u8,
    /// Width of the shared exponent field. 1..=7.
    pub exp_bits: u8,
    /// Values are below `2^top`: exponent 0 means `s = M - top`. -8..=8.
    pub top: i8,
}

impl Default for ConicFormat {
    /// `M = 18`, a 6-bit exponent, `top = 2`: values from `2^-62` to `4`.
    fn default() -> Self {
        ConicFormat { mantissa_bits: 18, exp_bits: 6, top: 2 }
    }
}

/// A quantised conic: mantissas and the shared exponent field.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, serde::Serialize)]
pub struct QuantConic {
    /// Mantissa of `a` (the `xx` coefficient), unsigned.
    pub a: i32,
    /// Mantissa of `b` (the `xy` coefficient), signed.
    pub b: i32,
    /// Mantissa of `c` (the `yy` coefficient), unsigned.
    pub c: i32,
    /// Exponent field: the scale is `2^-(M - top + exp)`.
    pub exp: u32,
}

impl ConicFormat {
    /// Checks the widths.
    pub fn check(&self) -> Result<(), FormatError> {
        if !(4..=30).contains(&self.mantissa_bits) {
            return Err(FormatError::new(
                "conic.mantissa_bits",
                format!("{} is outside 4..=30", self.mantissa_bits),
            ));
        }
        if !(1..=7).contains(&self.exp_bits) {
            return Err(FormatError::new("conic.exp_bits", format!("{} is outside 1..=7", self.exp_bits)));
        }
        if !(-8..=8).contains(&self.top) {
            return Err(FormatError::new("conic.top", format!("{} is outside -8..=8", self.top)));
        }
        Ok(())
    }

    /// Largest exponent field value, `2^exp_bits - 1`.
    pub fn max_exp(&self) -> u32 {
        (1u32 << self.exp_bits) - 1
    }

    /// Largest unsigned mantissa, `2^M - 1` (also the largest `|b|`).
    pub fn max_mantissa(&self) -> i64 {
        (1i64 << self.mantissa_bits) - 1
    }

    /// The scale `s` of exponent field `exp`: values are `mantissa * 2^-s`.
    pub fn scale(&self, exp: u32) -> i32 {
        self.mantissa_bits as i32 - self.top as i32 + exp as i32
    }

    /// Quantises a conic `[a, b, c]` (see the module doc for the rule).
    pub fn quantize(&self, conic: [f32; 3]) -> QuantConic {
        let [a, b, c] = conic.map(f64::from);
        if a.is_nan() || b.is_nan() || c.is_nan() {
            return QuantConic { a: 0, b: 0, c: 0, exp: self.max_exp() };
        }
        let (a, c) = (a.max(0.0), c.max(0.0));
        let mx = a.max(b.abs()).max(c);
        let max_m = self.max_mantissa();
        let (s_min, s_max) = (self.scale(0), self.scale(self.max_exp()));
        let round = |v: f64, s: i32| (v * (s as f64).exp2() + 0.5).floor();
        let s = if mx == 0.0 || !mx.is_finite() {
            if mx == 0.0 {
                s_max
            } else {
                s_min
            }
        } else {
            // Start from the logarithm, then correct for its rounding and for rounding up.
            let mut s = ((max_m as f64 / mx).log2().floor() as i32).clamp(s_min - 1, s_max + 1);
            while s > s_min && round(mx, s) > max_m as f64 {
                s -= 1;
            }
            while s < s_max && round(mx, s + 1) <= max_m as f64 {
                s += 1;
            }
            s.clamp(s_min, s_max)
        };
        let q = |v: f64, lo: i64| round(v, s).clamp(lo as f64, max_m as f64) as i32;
        QuantConic { a: q(a, 0), b: q(b, -max_m), c: q(c, 0), exp: (s - s_min) as u32 }
    }

    /// The conic a quantised one stands for (exact).
    pub fn dequantize(&self, q: &QuantConic) -> [f64; 3] {
        let k = (-(self.scale(q.exp) as f64)).exp2();
        [q.a as f64 * k, q.b as f64 * k, q.c as f64 * k]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn normalises_the_largest_coefficient() {
        let f = ConicFormat { mantissa_bits: 16, exp_bits: 6, top: 2 };
        let q = f.quantize([3.3, -0.5, 1.0]);
        assert!(q.a >= 1 << 15 && q.a < 1 << 16, "{q:?}");
        let back = f.dequantize(&q);
        assert!((back[0] - 3.3).abs() <= 3.3 * 2f64.powi(-16));
        // A screen-filling Gaussian keeps its relative precision.
        let q = f.quantize([1e-7, 2e-8, 3e-8]);
        let back = f.dequantize(&q);
        assert!(q.a >= 1 << 15, "{q:?}");
        assert!((back[0] - 1e-7).abs() <= 1e-7 * 2f64.powi(-16) * 1.0001);
        // Zero and NaN.
        assert_eq!(f.quantize([0.0; 3]), QuantConic { a: 0, b: 0, c: 0, exp: 63 });
        assert_eq!(f.quantize([f32::NAN, 0.0, 1.0]).a, 0);
        // Above the range: saturate at exponent 0.
        let q = f.quantize([100.0, 0.0, 1.0]);
        assert_eq!((q.a as i64, q.exp), (f.max_mantissa(), 0));
        // Negative diagonal clamps to 0.
        assert_eq!(f.quantize([-1.0, 0.0, 1.0]).a, 0);
    }

    proptest! {
        #[test]
        fn relative_error_of_the_largest_is_2_pow_minus_m(
            la in -28.0f64..1.7, lc in -28.0f64..1.7, t in -0.999f64..0.999, m in 8u8..=24,
        ) {
            let f = ConicFormat { mantissa_bits: m, exp_bits: 6, top: 2 };
            let (a, c) = (la.exp2(), lc.exp2());
            let b = t * (a * c).sqrt();
            let conic = [a as f32, b as f32, c as f32];
            let q = f.quantize(conic);
            let back = f.dequantize(&q);
            let mx = (conic[0] as f64).max(conic[2] as f64);
            let lsb = (-(f.scale(q.exp) as f64)).exp2();
            for (v, w) in conic.iter().zip(back) {
                prop_assert!((*v as f64 - w).abs() <= lsb / 2.0, "{:?} {:?} {:?}", conic, back, q);
            }
            // The largest mantissa is normalised (at least 2^(M-1) after rounding), so
            // lsb (2^(M-1) - 1/2) <= mx.
            prop_assert!(lsb * (2f64.powi(m as i32 - 1) - 0.5) <= mx * 1.000001, "{:?} {}", q, lsb);
            prop_assert!((q.a as i64) <= f.max_mantissa() && (q.b as i64).abs() <= f.max_mantissa());
        }
    }
}
