//! The Subtile Compute Unit's internal number formats: power, the exp unit, alpha,
//! transmittance and the colour accumulator (the datapath itself is [`crate::raster::scu`]).
//!
//! All constants the reference compares against (`0.99`, `1/255`, `1e-4`) become integers here,
//! once, with the rule stated on each method, so that the fixed-point comparisons are exact
//! statements about the fixed-point values.

use super::fixed::FormatError;

/// The reference's alpha cap.
pub const MAX_ALPHA: f64 = 0.99;
/// The reference's smallest blended alpha.
pub const MIN_ALPHA: f64 = 1.0 / 255.0;
/// The reference's transmittance floor.
pub const MIN_TRANSMITTANCE: f64 = 1e-4;

/// The exp unit: `2^-y` by a table over one octave with linear interpolation (see
/// [`crate::raster::exp`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize)]
pub struct ExpFormat {
    /// The octave is split into `2^table_bits` segments: the table has `2^table_bits + 1`
    /// entries. 1..=10.
    pub table_bits: u8,
    /// Fraction bits of the position inside a segment (the interpolation weight). 0..=12;
    /// 0 means no interpolation (the segment's left entry).
    pub interp_bits: u8,
    /// Fraction bits of the result (and of the table entries); `1.0` is `2^out_frac`. 8..=24.
    pub out_frac: u8,
    /// Fraction bits of the `log2(e)` constant. 4..=24.
    pub log2e_frac: u8,
}

impl Default for ExpFormat {
    /// 33 entries of 16-bit fraction, 8 interpolation bits, `log2 e` with 14 fraction bits.
    fn default() -> Self {
        ExpFormat { table_bits: 5, interp_bits: 8, out_frac: 16, log2e_frac: 14 }
    }
}

/// Widths of the SCU datapath after the conic: power, exp, alpha, transmittance.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize)]
pub struct BlendFormat {
    /// Fraction bits of `-power` (unsigned after the `power > 0` test). 4..=20.
    pub power_frac: u8,
    /// Integer bits of `-power`: it saturates at `2^power_int - 2^-power_frac`. 3..=6 (3 is
    /// the least for which `exp(-saturated) < 1/255`).
    pub power_int: u8,
    /// Fraction bits of alpha (unsigned, below 1). 8..=20.
    pub alpha_frac: u8,
    /// Fraction bits of the transmittance `T` (unsigned, `1.0` is `2^frac`). 14..=30.
    pub transmittance_frac: u8,
    /// The exp unit.
    pub exp: ExpFormat,
}

impl Default for BlendFormat {
    /// `-power` in Q3.10, alpha in 0.12, `T` in 1.16 (see docs/formats.md for the choice).
    fn default() -> Self {
        BlendFormat {
            power_frac: 10,
            power_int: 3,
            alpha_frac: 12,
            transmittance_frac: 16,
            exp: ExpFormat::default(),
        }
    }
}

fn range(field: &'static str, v: u8, lo: u8, hi: u8) -> Result<(), FormatError> {
    if (lo..=hi).contains(&v) {
        Ok(())
    } else {
        Err(FormatError::new(field, format!("{v} is outside {lo}..={hi}")))
    }
}

impl BlendFormat {
    /// Checks every width and the one cross-constraint: the `log2 e` product must have at
    /// least the exp unit's input fraction bits.
    pub fn check(&self) -> Result<(), FormatError> {
        range("blend.power_frac", self.power_frac, 4, 20)?;
        range("blend.power_int", self.power_int, 3, 6)?;
        range("blend.alpha_frac", self.alpha_frac, 8, 20)?;
        range("blend.transmittance_frac", self.transmittance_frac, 14, 30)?;
        range("blend.exp.table_bits", self.exp.table_bits, 1, 10)?;
        range("blend.exp.interp_bits", self.exp.interp_bits, 0, 12)?;
        range("blend.exp.out_frac", self.exp.out_frac, 8, 24)?;
        range("blend.exp.log2e_frac", self.exp.log2e_frac, 4, 24)?;
        let y = self.exp.table_bits + self.exp.interp_bits;
        if self.power_frac + self.exp.log2e_frac < y {
            return Err(FormatError::new(
                "blend.exp",
                format!(
                    "power_frac + log2e_frac = {} is below table_bits + interp_bits = {y}",
                    self.power_frac + self.exp.log2e_frac
                ),
            ));
        }
        Ok(())
    }

    /// Largest `-power` raw value (saturation): `2^(power_int + power_frac) - 1`.
    pub fn max_neg_power(&self) -> i64 {
        (1i64 << (self.power_int + self.power_frac)) - 1
    }

    /// `alpha` cap: `floor(0.99 * 2^alpha_frac + 0.5)` (0.99 rounded half up).
    pub fn max_alpha_raw(&self) -> i64 {
        (MAX_ALPHA * (self.alpha_frac as f64).exp2() + 0.5).floor() as i64
    }

    /// Smallest blended alpha: `ceil(2^alpha_frac / 255)`. A Gaussian is skipped at a pixel iff
    /// `alpha_raw < min_alpha_raw()`, which is exactly `alpha_raw * 2^-alpha_frac < 1/255` for
    /// the fixed-point value (since `2^alpha_frac / 255` is never an integer).
    pub fn min_alpha_raw(&self) -> i64 {
        ((1i64 << self.alpha_frac) + 254) / 255
    }

    /// `1.0` as a transmittance raw value, `2^transmittance_frac`.
    pub fn one_transmittance(&self) -> i64 {
        1i64 << self.transmittance_frac
    }

    /// Transmittance floor: `ceil(1e-4 * 2^transmittance_frac)`. A pixel finishes iff
    /// `test_T_raw < min_transmittance_raw()`, which is exactly `test_T < 1e-4` for the
    /// fixed-point value.
    pub fn min_transmittance_raw(&self) -> i64 {
        (MIN_TRANSMITTANCE * (self.transmittance_frac as f64).exp2()).ceil() as i64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thresholds_are_exact_statements_about_fixed_values() {
        let f = BlendFormat::default();
        f.check().unwrap();
        let a = f.min_alpha_raw();
        // a / 2^12 >= 1/255 > (a - 1) / 2^12, checked in integers.
        assert!(a * 255 >= 1 << 12 && (a - 1) * 255 < 1 << 12, "{a}");
        let t = f.min_transmittance_raw();
        assert!(t as f64 >= 1e-4 * 65536.0 && ((t - 1) as f64) < 1e-4 * 65536.0, "{t}");
        assert_eq!(f.max_alpha_raw(), 4055); // 0.99 * 4096 = 4055.04
        assert_eq!(f.max_neg_power(), 8191);
        // exp(-saturated power) is below 1/255, so saturation never changes a decision.
        assert!((-(f.max_neg_power() as f64) / 1024.0).exp() < MIN_ALPHA);
        let bad = BlendFormat { power_int: 2, ..f };
        assert!(bad.check().is_err());
        let bad =
            BlendFormat { power_frac: 4, exp: ExpFormat { log2e_frac: 4, table_bits: 8, ..f.exp }, ..f };
        assert!(bad.check().is_err());
    }
}
