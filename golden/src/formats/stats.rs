//! Range statistics of projected Gaussians, and [`FeatureFormat::fitted`] from them.
//!
//! Fitting only changes the *integer* (range) part of each field; the precision (fraction bits,
//! conic mantissa) comes from the base format, since it is set by the image error it causes, not
//! by the data range (docs/formats.md).

use super::feature::FeatureFormat;
use super::fixed::QFormat;
use crate::render::Projected;

/// Multiplicative margin on the observed ranges (as [`crate::sort::depth_key::FIT_MARGIN`]).
pub const RANGE_MARGIN: f64 = 1.05;

/// Ranges seen over one or more frames of projected Gaussians. Non-finite values are ignored.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct FeatureStats {
    /// Gaussians observed.
    pub count: u64,
    /// Largest `|mean|` coordinate, pixels.
    pub max_abs_mean: f64,
    /// Largest conic coefficient `max(a, |b|, c)` of any Gaussian.
    pub max_conic: f64,
    /// Smallest per-Gaussian `max(a, |b|, c)` (the exponent range must reach it).
    pub min_conic: f64,
    /// Largest colour channel.
    pub max_color: f64,
    /// Largest standard deviation along the major axis, `sqrt(lambda_max(cov))`, pixels.
    pub max_sigma: f64,
}

impl Default for FeatureStats {
    fn default() -> Self {
        FeatureStats {
            count: 0,
            max_abs_mean: 0.0,
            max_conic: 0.0,
            min_conic: f64::INFINITY,
            max_color: 0.0,
            max_sigma: 0.0,
        }
    }
}

/// `max` that ignores a NaN second argument.
fn fmax(a: f64, b: f64) -> f64 {
    if b > a {
        b
    } else {
        a
    }
}

impl FeatureStats {
    /// Statistics of `projected`.
    pub fn from_projected(projected: &[Projected]) -> Self {
        let mut s = FeatureStats::default();
        for p in projected {
            s.add(p);
        }
        s
    }

    /// Adds one Gaussian.
    pub fn add(&mut self, p: &Projected) {
        self.count += 1;
        for m in p.mean2d {
            if m.is_finite() {
                self.max_abs_mean = fmax(self.max_abs_mean, (m as f64).abs());
            }
        }
        let [a, b, c] = p.conic.map(f64::from);
        let mx = a.abs().max(b.abs()).max(c.abs());
        if mx.is_finite() && mx > 0.0 {
            self.max_conic = fmax(self.max_conic, mx);
            self.min_conic = self.min_conic.min(mx);
        }
        for v in p.rgb {
            if v.is_finite() {
                self.max_color = fmax(self.max_color, v as f64);
            }
        }
        let [sxx, sxy, syy] = p.cov2d.map(f64::from);
        let lmax = 0.5 * (sxx + syy) + (0.25 * (sxx - syy) * (sxx - syy) + sxy * sxy).sqrt();
        if lmax.is_finite() {
            self.max_sigma = fmax(self.max_sigma, lmax.max(0.0).sqrt());
        }
    }

    /// Combines two sets of statistics.
    pub fn merge(&self, other: &FeatureStats) -> FeatureStats {
        FeatureStats {
            count: self.count + other.count,
            max_abs_mean: self.max_abs_mean.max(other.max_abs_mean),
            max_conic: self.max_conic.max(other.max_conic),
            min_conic: self.min_conic.min(other.min_conic),
            max_color: self.max_color.max(other.max_color),
            max_sigma: self.max_sigma.max(other.max_sigma),
        }
    }
}

/// Bits needed for the integer part of values up to `v` (at least `min`): the smallest `i`
/// with `2^i > v`.
fn int_bits_for(v: f64, min: i32) -> i32 {
    if !(v.is_finite() && v > 0.0) {
        return min;
    }
    ((v.log2().floor() as i32) + 1).max(min)
}

impl FeatureFormat {
    /// `base` with its ranges fitted to `stats` (each widened by [`RANGE_MARGIN`]):
    /// - mean: integer bits to hold `max_abs_mean` (at most 31 bits in all);
    /// - conic: `top` just above `max_conic`, exponent bits to reach `min_conic` at full
    ///   precision (1..=7);
    /// - colour: integer bits to hold `max_color` (0 when all colours are below 1);
    /// - extents: integer bits to hold the cutoff radius of the widest Gaussian, `k sigma_max`
    ///   with `k` that of an opaque Gaussian, but no more than the mean's integer bits + 2
    ///   (beyond, "unbounded" is exact enough); at most 24 bits in all.
    ///
    /// Fraction bits, the conic mantissa, the axis, the depth key and the cutoff come from
    /// `base`. With no Gaussians observed, returns `base`.
    pub fn fitted(stats: &FeatureStats, base: &FeatureFormat) -> FeatureFormat {
        if stats.count == 0 {
            return *base;
        }
        let mut f = *base;
        let mi = int_bits_for(stats.max_abs_mean * RANGE_MARGIN, 1).min(31 - base.mean.frac as i32);
        f.mean = QFormat::signed((1 + mi + base.mean.frac as i32) as u8, base.mean.frac);
        if stats.max_conic > 0.0 && stats.min_conic.is_finite() {
            let top = int_bits_for(stats.max_conic * RANGE_MARGIN, -8).min(8);
            // Exponent field of the smallest: s = M - 1 - floor(log2 min) at normalisation.
            let lo = (stats.min_conic / RANGE_MARGIN).log2().floor() as i32;
            let e_max = (top - 1 - lo).max(1);
            let bits = int_bits_for(e_max as f64, 1).min(7);
            f.conic.top = top as i8;
            f.conic.exp_bits = bits as u8;
        }
        let ci = int_bits_for(stats.max_color * RANGE_MARGIN, 0).min(31 - base.color.frac as i32);
        f.color = QFormat::unsigned((ci + base.color.frac as i32).max(1) as u8, base.color.frac);
        let k = base.cutoff.radius_squared(1.0).sqrt();
        let ei = int_bits_for(k * stats.max_sigma * RANGE_MARGIN + 1.0, 1)
            .min(mi + 2)
            .min(24 - base.extent.frac as i32);
        f.extent = QFormat::unsigned((ei + base.extent.frac as i32) as u8, base.extent.frac);
        f
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(mean: [f32; 2], conic: [f32; 3], rgb: [f32; 3]) -> Projected {
        let [a, b, c] = conic;
        let det = a * c - b * b;
        Projected {
            index: 0,
            mean2d: mean,
            cov2d: [c / det, -b / det, a / det],
            conic,
            depth: 1.0,
            radius: 1,
            rgb,
            opacity: 0.5,
            tile_min: [0, 0],
            tile_max: [1, 1],
        }
    }

    #[test]
    fn fitted_covers_the_observed_ranges() {
        let ps = [
            p([100.0, -3000.0], [2.0, 0.1, 1.0], [0.2, 1.4, 0.0]),
            p([5.0, 5.0], [1e-6, 0.0, 4e-7], [0.1, 0.1, f32::NAN]),
        ];
        let s = FeatureStats::from_projected(&ps);
        assert_eq!(s.count, 2);
        assert_eq!(s.max_abs_mean, 3000.0);
        assert!((s.min_conic - 1e-6).abs() < 1e-12 && s.max_conic == 2.0);
        let base = FeatureFormat::default();
        let f = FeatureFormat::fitted(&s, &base);
        f.check().unwrap();
        assert!(f.mean.max_value() >= 3000.0 * RANGE_MARGIN && f.mean.bits < base.mean.bits);
        assert!(f.color.max_value() >= 1.4 && f.color.frac == base.color.frac);
        assert!(2f64.powi(f.conic.top as i32) > 2.0);
        // The smallest conic is normalised: its exponent field fits.
        let q = f.conic.quantize([1e-6, 0.0, 4e-7]);
        assert!(q.exp < f.conic.max_exp() && q.a >= 1 << (f.conic.mantissa_bits - 1), "{q:?} {f:?}");
        // sigma_max = 1000 px (conic 1e-6): the extent holds 3.33 * 1000 px.
        assert!(f.extent.max_value() >= 3330.0, "{:?}", f.extent);
        assert_eq!(FeatureFormat::fitted(&FeatureStats::default(), &base), base);
        let m = s.merge(&FeatureStats::from_projected(&ps[..1]));
        assert_eq!((m.count, m.max_abs_mean), (3, 3000.0));
    }
}
