//! The SCU's exp unit: `exp(power)` for `power <= 0` in fixed point, with no float and no
//! division.
//!
//! # Definition
//! The input is `np = -power` as an unsigned raw value with `P = power_frac` fraction bits
//! (already saturated by the SCU). With `tb = table_bits`, `ib = interp_bits`, `F = out_frac`:
//! 1. `y = shr_round(np * L, P + log2e_frac - (tb + ib))`, where `L = round(log2(e) 2^log2e_frac)`:
//!    `y ~ np log2(e)` with `tb + ib` fraction bits, so `exp(power) = 2^-y`.
//! 2. `n = y >> (tb + ib)` (integer part), `i` = the next `tb` bits, `r` = the low `ib` bits.
//! 3. `T[j] = floor(2^(F - j / 2^tb) + 0.5)` for `j = 0..=2^tb` (so `T[0] = 2^F`,
//!    `T[2^tb] = 2^(F-1)`): [`ExpTable::table`], the ROM the Verilog generator emits.
//! 4. `e0 = T[i] - shr_round((T[i] - T[i+1]) * r, ib)` (linear interpolation inside a segment).
//! 5. `exp = shr_round(e0, n)`, i.e. the `2^-n` part is a rounding right shift (0 once
//!    `n >= F + 2`).
//!
//! `shr_round` is the round-half-up shift of [`crate::formats::fixed::shr_round64`]. The result
//! has `F` fraction bits and lies in `[0, 2^F]`; it is non-increasing in `np` (tested
//! exhaustively). Errors against f64 `exp` are measured by [`ExpTable::error`] and recorded in
//! docs/formats.md.

use crate::formats::blend::ExpFormat;
use crate::formats::fixed::shr_round64;

/// The exp unit of one format: the constant, the table and the evaluation.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ExpTable {
    fmt: ExpFormat,
    power_frac: u8,
    log2e: i64,
    input_shift: u32,
    table: Vec<i64>,
}

/// Error of the exp unit against f64 `exp` over a range of inputs.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct ExpError {
    /// Largest `|approx - exp(power)|` (absolute, in value units).
    pub max_abs: f64,
    /// Power at which the absolute error is largest.
    pub max_abs_at: f64,
    /// Largest `|approx - exp(power)| / exp(power)`.
    pub max_rel: f64,
    /// Power at which the relative error is largest.
    pub max_rel_at: f64,
    /// Number of raw inputs checked.
    pub inputs: u64,
}

impl ExpTable {
    /// Builds the unit for `fmt` and inputs with `power_frac` fraction bits. Panics if
    /// `power_frac + log2e_frac < table_bits + interp_bits` (a format that
    /// [`crate::formats::BlendFormat::check`] rejects).
    pub fn new(fmt: &ExpFormat, power_frac: u8) -> Self {
        let fy = fmt.table_bits as u32 + fmt.interp_bits as u32;
        let inp = power_frac as u32 + fmt.log2e_frac as u32;
        assert!(inp >= fy, "exp unit: power_frac + log2e_frac ({inp}) < table_bits + interp_bits ({fy})");
        let log2e = (std::f64::consts::LOG2_E * (fmt.log2e_frac as f64).exp2() + 0.5).floor() as i64;
        let segments = 1usize << fmt.table_bits;
        let table = (0..=segments)
            .map(|j| {
                let x = fmt.out_frac as f64 - j as f64 / segments as f64;
                (x.exp2() + 0.5).floor() as i64
            })
            .collect();
        ExpTable { fmt: *fmt, power_frac, log2e, input_shift: inp - fy, table }
    }

    /// The table `T[0..=2^table_bits]` (the ROM contents, `out_frac` fraction bits).
    pub fn table(&self) -> &[i64] {
        &self.table
    }

    /// The `log2(e)` constant `L` (`log2e_frac` fraction bits).
    pub fn log2e_raw(&self) -> i64 {
        self.log2e
    }

    /// The rounding shift of step 1, `power_frac + log2e_frac - table_bits - interp_bits`.
    pub fn input_shift(&self) -> u32 {
        self.input_shift
    }

    /// The format.
    pub fn format(&self) -> &ExpFormat {
        &self.fmt
    }

    /// `exp(-np 2^-power_frac)` with `out_frac` fraction bits, for `0 <= np < 2^40`.
    #[inline(always)]
    pub fn eval(&self, np: i64) -> i64 {
        let (tb, ib) = (self.fmt.table_bits as u32, self.fmt.interp_bits as u32);
        let y = shr_round64(np * self.log2e, self.input_shift);
        let n = y >> (tb + ib);
        if n >= self.fmt.out_frac as i64 + 2 {
            return 0;
        }
        let f = y & ((1i64 << (tb + ib)) - 1);
        let i = (f >> ib) as usize;
        let r = f & ((1i64 << ib) - 1);
        let (t0, t1) = (self.table[i], self.table[i + 1]);
        let e0 = t0 - shr_round64((t0 - t1) * r, ib);
        shr_round64(e0, n as u32)
    }

    /// The value of [`ExpTable::eval`] as a real number.
    pub fn eval_f64(&self, np: i64) -> f64 {
        self.eval(np) as f64 * (-(self.fmt.out_frac as f64)).exp2()
    }

    /// Error against f64 `exp` over every representable power in `[lo, hi]` (`lo <= hi <= 0`),
    /// the input taken as exact (the power's own rounding is the SCU's, not the unit's).
    pub fn error(&self, lo: f64, hi: f64) -> ExpError {
        let scale = (self.power_frac as f64).exp2();
        let (first, last) = ((-hi * scale).ceil() as i64, (-lo * scale).floor() as i64);
        let mut e = ExpError { max_abs: 0.0, max_abs_at: 0.0, max_rel: 0.0, max_rel_at: 0.0, inputs: 0 };
        for np in first.max(0)..=last {
            let power = -(np as f64) / scale;
            let exact = power.exp();
            let abs = (self.eval_f64(np) - exact).abs();
            if abs > e.max_abs {
                e.max_abs = abs;
                e.max_abs_at = power;
            }
            if abs / exact > e.max_rel {
                e.max_rel = abs / exact;
                e.max_rel_at = power;
            }
            e.inputs += 1;
        }
        e
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::formats::blend::BlendFormat;

    #[test]
    fn table_endpoints_and_constant() {
        let f = BlendFormat::default();
        let t = ExpTable::new(&f.exp, f.power_frac);
        assert_eq!(t.table().len(), 33);
        assert_eq!(t.table()[0], 1 << 16);
        assert_eq!(t.table()[32], 1 << 15);
        assert_eq!(t.log2e_raw(), 23637); // 1.442695 * 2^14 = 23637.1
        assert_eq!(t.eval(0), 1 << 16);
        // ln 2 is 709.78 LSBs of power: exp(-ln 2) = 1/2 up to the rounding of the input.
        assert!((t.eval_f64(710) - 0.5).abs() < 1e-3);
        assert_eq!(t.eval(1 << 30), 0);
    }

    #[test]
    fn no_interpolation_uses_segment_left_entries() {
        let fmt = ExpFormat { table_bits: 4, interp_bits: 0, out_frac: 12, log2e_frac: 12 };
        let t = ExpTable::new(&fmt, 8);
        // In the first octave (n = 0) every result is a table entry, and all entries appear.
        let mut seen = std::collections::BTreeSet::new();
        for np in 0..=171 {
            // y = round(np * 5909 / 2^16) (4 fraction bits) stays below 16 up to np = 171.
            let v = t.eval(np);
            assert!(t.table().contains(&v), "np {np}: {v}");
            seen.insert(v);
        }
        assert_eq!(seen.len(), 16);
    }
}
