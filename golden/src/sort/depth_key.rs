//! Depth (view-space `z`, positive in front of the camera) to sort-key encodings.
//!
//! Every codec is order-preserving: `z1 <= z2` implies `encode(z1) <= encode(z2)` for all
//! positive finite depths, so sorting by key never inverts two Gaussians (it may tie them, and
//! ties are broken by id). Each codec documents its rounding, saturation and error bound.
//!
//! **Invalid input** (NaN, infinities, `z <= 0`, including `-0.0`) maps to
//! [`DepthKeyCodec::invalid_key`], the largest key the codec produces. Such a depth means the
//! Gaussian is at or behind the camera plane and should have been culled upstream; sorting it
//! *last* composites it behind every valid Gaussian, where front-to-back blending gives it the
//! least influence (and early termination usually skips it), rather than letting it occlude the
//! scene as key 0 would. For FP16 this key is `0x7C00` (+inf), one above the largest finite
//! depth key, so invalid depths stay distinguishable from far-saturated ones; for the fitted
//! fixed-point codecs it equals the far-saturation key `2^k - 1`.

use super::error::SortParamError;

/// Largest finite IEEE half (65504) as bits.
const F16_MAX_FINITE: u32 = 0x7BFF;
/// IEEE half +infinity as bits: the FP16 codec's key for invalid depths.
const F16_INF: u32 = 0x7C00;

/// Multiplicative margin [`DepthKeyCodec::fit`] adds at both ends of the observed depth range:
/// `near = min / FIT_MARGIN`, `far = max * FIT_MARGIN` (about +-0.049 in `ln z`).
pub const FIT_MARGIN: f32 = 1.05;

/// Depth range [`DepthKeyCodec::fit`] falls back to when it sees no valid depth.
pub const FIT_FALLBACK_RANGE: (f32, f32) = (0.01, 1000.0);

/// A `k`-bit fixed-point key over a depth range `[near, far]`, `0 < near < far`, both finite.
/// Construct with [`DepthKeyCodec::log`], [`DepthKeyCodec::linear`] or [`DepthKeyCodec::fit`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KeyRange {
    key_bits: u8,
    near: f32,
    far: f32,
}

impl KeyRange {
    fn new(key_bits: u8, near: f32, far: f32) -> Result<Self, SortParamError> {
        if !(1..=32).contains(&key_bits) {
            return Err(SortParamError::KeyBits(key_bits));
        }
        if !(near.is_finite() && far.is_finite() && near > 0.0 && near < far) {
            return Err(SortParamError::DepthRange { near, far });
        }
        Ok(KeyRange { key_bits, near, far })
    }

    /// Key width in bits.
    pub fn key_bits(&self) -> u8 {
        self.key_bits
    }

    /// Near end of the range (key 0).
    pub fn near(&self) -> f32 {
        self.near
    }

    /// Far end of the range (key `2^k - 1`).
    pub fn far(&self) -> f32 {
        self.far
    }

    /// `2^k - 1`, the largest key, as f64.
    fn max_key_f64(&self) -> f64 {
        ((1u64 << self.key_bits) - 1) as f64
    }

    /// Rounds a key-space coordinate `t` (ideally in `[0, 2^k - 1]`) to the key: clamp, then
    /// round half away from zero (`f64::round`). Monotone in `t`.
    fn quantize(&self, t: f64) -> u32 {
        let max = self.max_key_f64();
        if t.is_nan() || t <= 0.0 {
            0
        } else if t >= max {
            max as u32
        } else {
            t.round() as u32
        }
    }
}

/// How a depth becomes a sort key. All arithmetic of the fixed-point codecs is in f64; the key,
/// not the depth, is what the hardware sees.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum DepthKeyCodec {
    /// The artifact's key: the IEEE binary16 bits of `z` (16-bit keys). Positive halves are
    /// monotone as unsigned integers. Rounding is to nearest, ties to even; depths that would
    /// round to +inf (`z >= 65520`) saturate to the largest finite half (65504, key `0x7BFF`);
    /// depths that round to zero (`z <= 2^-25`, half the smallest subnormal) flush to key 0.
    /// Error: relative `<= 2^-11` on the normal range `[2^-14, 65504]`, absolute `<= 2^-25`
    /// below it.
    Fp16,
    /// `key = round((ln z - ln near) / (ln far - ln near) * (2^k - 1))`, clamped to
    /// `[0, 2^k - 1]` (so `z < near` gives 0, `z > far` gives `2^k - 1`). Computed in f64 as
    /// `(ln z - ln near) * s` with `s = (2^k - 1) / (ln far - ln near)`. Error on `[near, far]`:
    /// `|ln decode(encode(z)) - ln z| <= 0.5 / s` (plus f32 rounding of the decoded value).
    Log(KeyRange),
    /// `key = round((z - near) / (far - near) * (2^k - 1))`, clamped like [`DepthKeyCodec::Log`].
    /// Computed in f64 as `(z - near) * s` with `s = (2^k - 1) / (far - near)`. Error on
    /// `[near, far]`: `|decode(encode(z)) - z| <= 0.5 / s` (plus f32 rounding of the decoded value).
    Linear(KeyRange),
}

impl DepthKeyCodec {
    /// A log-space key of `key_bits` bits over `[near, far]`.
    pub fn log(key_bits: u8, near: f32, far: f32) -> Result<Self, SortParamError> {
        KeyRange::new(key_bits, near, far).map(DepthKeyCodec::Log)
    }

    /// A linear key of `key_bits` bits over `[near, far]`.
    pub fn linear(key_bits: u8, near: f32, far: f32) -> Result<Self, SortParamError> {
        KeyRange::new(key_bits, near, far).map(DepthKeyCodec::Linear)
    }

    /// Fits a log-space key of `key_bits` bits to the depths seen along a trajectory: the range
    /// is `[min / FIT_MARGIN, max * FIT_MARGIN]` over the valid (finite, positive) depths, or
    /// [`FIT_FALLBACK_RANGE`] when there are none (or the widened range degenerates).
    pub fn fit(depths: impl Iterator<Item = f32>, key_bits: u8) -> Result<Self, SortParamError> {
        let (near, far) = fitted_range(depths);
        DepthKeyCodec::log(key_bits, near, far)
    }

    /// As [`DepthKeyCodec::fit`] but a linear key.
    pub fn fit_linear(depths: impl Iterator<Item = f32>, key_bits: u8) -> Result<Self, SortParamError> {
        let (near, far) = fitted_range(depths);
        DepthKeyCodec::linear(key_bits, near, far)
    }

    /// Key width in bits (16 for FP16).
    pub fn key_bits(&self) -> u8 {
        match self {
            DepthKeyCodec::Fp16 => 16,
            DepthKeyCodec::Log(r) | DepthKeyCodec::Linear(r) => r.key_bits,
        }
    }

    /// Largest key [`DepthKeyCodec::encode`] returns for a valid depth.
    pub fn max_key(&self) -> u32 {
        match self {
            DepthKeyCodec::Fp16 => F16_MAX_FINITE,
            DepthKeyCodec::Log(r) | DepthKeyCodec::Linear(r) => r.max_key_f64() as u32,
        }
    }

    /// Key of an invalid depth (non-finite or `<= 0`): the largest key the codec produces.
    pub fn invalid_key(&self) -> u32 {
        match self {
            DepthKeyCodec::Fp16 => F16_INF,
            DepthKeyCodec::Log(_) | DepthKeyCodec::Linear(_) => self.max_key(),
        }
    }

    /// The key of depth `z` (see the variant docs for rounding and saturation).
    pub fn encode(&self, z: f32) -> u32 {
        if !(z.is_finite() && z > 0.0) {
            return self.invalid_key();
        }
        match self {
            DepthKeyCodec::Fp16 => f16_bits_saturating(z),
            DepthKeyCodec::Log(r) => {
                let s = r.max_key_f64() / ((r.far as f64).ln() - (r.near as f64).ln());
                r.quantize(((z as f64).ln() - (r.near as f64).ln()) * s)
            }
            DepthKeyCodec::Linear(r) => {
                let s = r.max_key_f64() / (r.far as f64 - r.near as f64);
                r.quantize((z as f64 - r.near as f64) * s)
            }
        }
    }

    /// The depth a key stands for: the exact half value for FP16, the bucket centre (the depth
    /// whose unrounded key is exactly `key`) for the fixed-point codecs. Monotone
    /// non-decreasing in `key`; keys above [`DepthKeyCodec::invalid_key`] decode like it
    /// (+inf for FP16, `far` otherwise).
    pub fn decode(&self, key: u32) -> f32 {
        match self {
            DepthKeyCodec::Fp16 => f16_bits_to_f32(key),
            DepthKeyCodec::Log(r) => {
                let q = (key as f64).min(r.max_key_f64());
                let (ln_near, ln_far) = ((r.near as f64).ln(), (r.far as f64).ln());
                (ln_near + q * (ln_far - ln_near) / r.max_key_f64()).exp() as f32
            }
            DepthKeyCodec::Linear(r) => {
                let q = (key as f64).min(r.max_key_f64());
                (r.near as f64 + q * (r.far as f64 - r.near as f64) / r.max_key_f64()) as f32
            }
        }
    }
}

/// `[min / FIT_MARGIN, max * FIT_MARGIN]` over the valid depths, or the fallback.
fn fitted_range(depths: impl Iterator<Item = f32>) -> (f32, f32) {
    let (mut lo, mut hi) = (f32::INFINITY, 0.0f32);
    for z in depths.filter(|z| z.is_finite() && *z > 0.0) {
        lo = lo.min(z);
        hi = hi.max(z);
    }
    let near = lo / FIT_MARGIN;
    let far = (hi * FIT_MARGIN).min(f32::MAX);
    if near > 0.0 && near.is_finite() && near < far {
        (near, far)
    } else {
        FIT_FALLBACK_RANGE
    }
}

/// IEEE binary16 bits of a positive finite `z`: round to nearest even, saturate to the largest
/// finite half, flush to zero what rounds to zero. Integer-only on the f32 bits.
pub(crate) fn f16_bits_saturating(z: f32) -> u32 {
    let bits = z.to_bits();
    let exp_field = (bits >> 23) & 0xFF;
    let mant = bits & 0x7F_FFFF;
    if exp_field == 0 {
        return 0; // f32 subnormal (< 2^-126): far below half the smallest half subnormal.
    }
    let e = exp_field as i32 - 127;
    if e > 15 {
        return F16_MAX_FINITE;
    }
    if e >= -14 {
        // Normal half: drop 13 mantissa bits; a carry out of the mantissa bumps the exponent,
        // which is the correct result (and 0x7C00 means overflow, saturated below).
        let h = (((e + 15) as u32) << 10) | (mant >> 13);
        let h = round_nearest_even(h, mant & 0x1FFF, 0x1000);
        return h.min(F16_MAX_FINITE);
    }
    // Subnormal half: value / 2^-24 = (1.mant * 2^23) * 2^(e + 1), a right shift by -(e + 1).
    let m = mant | 0x80_0000;
    let shift = (-(e + 1)) as u32; // >= 14
    if shift > 24 {
        return 0; // m < 2^24, so value < 2^-25: rounds to zero.
    }
    round_nearest_even(m >> shift, m & ((1 << shift) - 1), 1 << (shift - 1))
}

/// Adds one to `q` when the discarded `rem` exceeds `half`, or equals it and `q` is odd.
fn round_nearest_even(q: u32, rem: u32, half: u32) -> u32 {
    if rem > half || (rem == half && q & 1 == 1) {
        q + 1
    } else {
        q
    }
}

/// Exact value of a non-negative half (bits `0..=0x7C00`); larger keys decode as +inf.
fn f16_bits_to_f32(h: u32) -> f32 {
    if h >= F16_INF {
        return f32::INFINITY;
    }
    let exp = h >> 10;
    let mant = h & 0x3FF;
    if exp == 0 {
        mant as f32 * f32::from_bits((127 - 24) << 23) // mant * 2^-24, exact
    } else {
        f32::from_bits(((exp + 127 - 15) << 23) | (mant << 13))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn codecs() -> Vec<DepthKeyCodec> {
        vec![
            DepthKeyCodec::Fp16,
            DepthKeyCodec::log(16, 0.2, 200.0).unwrap(),
            DepthKeyCodec::log(8, 0.5, 50.0).unwrap(),
            DepthKeyCodec::log(32, 0.01, 1e4).unwrap(),
            DepthKeyCodec::linear(16, 0.2, 200.0).unwrap(),
            DepthKeyCodec::linear(10, 1.0, 3.0).unwrap(),
        ]
    }

    #[test]
    fn fp16_matches_exhaustive_half_table() {
        let c = DepthKeyCodec::Fp16;
        // Every positive finite half decodes exactly and encodes back to itself; the midpoint to
        // the next half (exact in f32) goes to the even one, its f32 neighbours to the nearer.
        for h in 1..F16_MAX_FINITE {
            let v = c.decode(h);
            let next = c.decode(h + 1);
            assert!(v > 0.0 && v < next, "h {h:#x}");
            assert_eq!(c.encode(v), h, "h {h:#x}");
            let mid = ((v as f64 + next as f64) / 2.0) as f32;
            assert_eq!(mid as f64, (v as f64 + next as f64) / 2.0, "midpoint not exact");
            let even = if h % 2 == 0 { h } else { h + 1 };
            assert_eq!(c.encode(mid), even, "tie at h {h:#x}");
            assert_eq!(c.encode(f32::from_bits(mid.to_bits() - 1)), h);
            assert_eq!(c.encode(f32::from_bits(mid.to_bits() + 1)), h + 1);
        }
        assert_eq!(c.decode(F16_MAX_FINITE), 65504.0);
        assert_eq!(c.decode(1), 2f32.powi(-24));
        assert_eq!(c.decode(0x3C00), 1.0);
        assert_eq!(c.encode(1.0), 0x3C00);
    }

    #[test]
    fn fp16_saturates_and_flushes() {
        let c = DepthKeyCodec::Fp16;
        assert_eq!(c.encode(65504.0), F16_MAX_FINITE);
        assert_eq!(c.encode(65519.0), F16_MAX_FINITE);
        assert_eq!(c.encode(65520.0), F16_MAX_FINITE); // IEEE would give +inf
        assert_eq!(c.encode(1e30), F16_MAX_FINITE);
        assert_eq!(c.encode(f32::MAX), F16_MAX_FINITE);
        assert_eq!(c.encode(2f32.powi(-25)), 0); // tie, to even (zero)
        assert_eq!(c.encode(f32::from_bits(2f32.powi(-25).to_bits() + 1)), 1);
        assert_eq!(c.encode(1e-30), 0);
        assert_eq!(c.encode(f32::from_bits(1)), 0); // f32 subnormal
    }

    #[test]
    fn invalid_depths_take_the_invalid_key() {
        for c in codecs() {
            for z in [f32::NAN, -f32::NAN, f32::INFINITY, f32::NEG_INFINITY, 0.0, -0.0, -1.0, -1e-30] {
                assert_eq!(c.encode(z), c.invalid_key(), "{c:?} z {z}");
            }
            assert!(c.invalid_key() >= c.max_key());
            assert!(c.invalid_key() < (1u64 << c.key_bits()) as u32 || c.key_bits() == 32);
        }
        assert_eq!(DepthKeyCodec::Fp16.invalid_key(), 0x7C00);
        assert_eq!(DepthKeyCodec::Fp16.decode(0x7C00), f32::INFINITY);
        assert_eq!(DepthKeyCodec::Fp16.decode(0xFFFF), f32::INFINITY);
    }

    #[test]
    fn fixed_point_saturates_at_range_ends() {
        for c in codecs().into_iter().skip(1) {
            let (DepthKeyCodec::Log(r) | DepthKeyCodec::Linear(r)) = c else { unreachable!() };
            assert_eq!(c.encode(r.near()), 0);
            assert_eq!(c.encode(r.near() * 0.5), 0);
            assert_eq!(c.encode(1e-30), 0);
            assert_eq!(c.encode(r.far()), c.max_key());
            assert_eq!(c.encode(r.far() * 2.0), c.max_key());
            assert_eq!(c.encode(f32::MAX), c.max_key());
            assert_eq!(c.max_key() as u64, (1u64 << r.key_bits()) - 1);
            assert_eq!(c.decode(0), r.near());
            assert!((c.decode(c.max_key()) - r.far()).abs() <= r.far() * 1e-6);
            assert_eq!(c.decode(u32::MAX), c.decode(c.max_key()));
        }
    }

    #[test]
    fn constructors_reject_bad_ranges() {
        assert!(DepthKeyCodec::log(16, 0.0, 1.0).is_err());
        assert!(DepthKeyCodec::log(16, 2.0, 1.0).is_err());
        assert!(DepthKeyCodec::log(16, 1.0, 1.0).is_err());
        assert!(DepthKeyCodec::linear(16, 1.0, f32::INFINITY).is_err());
        assert!(DepthKeyCodec::linear(0, 1.0, 2.0).is_err());
        assert!(DepthKeyCodec::linear(33, 1.0, 2.0).is_err());
    }

    #[test]
    fn fit_covers_observed_depths_with_margin() {
        let depths = [3.0f32, 0.7, f32::NAN, -2.0, 40.0, 12.5];
        let c = DepthKeyCodec::fit(depths.iter().copied(), 12).unwrap();
        let DepthKeyCodec::Log(r) = c else { panic!("fit must give a log key") };
        assert!((r.near() - 0.7 / FIT_MARGIN).abs() < 1e-6);
        assert!((r.far() - 40.0 * FIT_MARGIN).abs() < 1e-4);
        // The extremes are strictly inside the range, so they do not saturate.
        assert!(c.encode(0.7) > 0 && c.encode(40.0) < c.max_key());
        let empty = DepthKeyCodec::fit(std::iter::empty(), 12).unwrap();
        assert_eq!(empty, DepthKeyCodec::log(12, FIT_FALLBACK_RANGE.0, FIT_FALLBACK_RANGE.1).unwrap());
        let single = DepthKeyCodec::fit_linear([5.0f32].into_iter(), 8).unwrap();
        assert!(single.encode(5.0) > 0 && single.encode(5.0) < single.max_key());
    }

    /// Positive finite f32 values spread over the whole range (bit patterns are monotone).
    fn positive_f32() -> impl Strategy<Value = f32> {
        (1u32..0x7F80_0000).prop_map(f32::from_bits)
    }

    proptest! {
        #[test]
        fn encode_is_monotone(a in positive_f32(), b in positive_f32(), scale in 0.01f32..1000.0) {
            let (lo, hi) = if a <= b { (a, b) } else { (b, a) };
            for c in codecs() {
                prop_assert!(c.encode(lo) <= c.encode(hi), "{:?} {} {}", c, lo, hi);
                prop_assert!(c.encode(hi) <= c.max_key());
            }
            // Also densely inside a typical depth range.
            let (x, y) = ((lo.to_bits() % 1000) as f32 * 0.001 * scale, (hi.to_bits() % 1000) as f32 * 0.001 * scale);
            let (x, y) = if x <= y { (x, y) } else { (y, x) };
            for c in codecs() {
                if x > 0.0 {
                    prop_assert!(c.encode(x) <= c.encode(y));
                }
            }
        }

        #[test]
        fn decode_is_monotone(a in any::<u32>(), b in any::<u32>()) {
            let (lo, hi) = if a <= b { (a, b) } else { (b, a) };
            for c in codecs() {
                prop_assert!(c.decode(lo) <= c.decode(hi), "{:?} {} {}", c, lo, hi);
            }
        }

        #[test]
        fn fp16_round_trip_error_bound(z in 1e-9f32..65504.0) {
            let c = DepthKeyCodec::Fp16;
            let back = c.decode(c.encode(z)) as f64;
            let z = z as f64;
            if z >= 2f64.powi(-14) {
                prop_assert!((back - z).abs() <= z * 2f64.powi(-11), "z {} back {}", z, back);
            } else {
                prop_assert!((back - z).abs() <= 2f64.powi(-25), "z {} back {}", z, back);
            }
        }

        #[test]
        fn fixed_point_round_trip_error_bound(t in 0.0f64..=1.0) {
            for c in codecs().into_iter().skip(1) {
                match c {
                    DepthKeyCodec::Log(r) => {
                        let (ln_n, ln_f) = ((r.near() as f64).ln(), (r.far() as f64).ln());
                        let z = (ln_n + t * (ln_f - ln_n)).exp() as f32;
                        prop_assume!(z >= r.near() && z <= r.far());
                        let back = c.decode(c.encode(z)) as f64;
                        let bound = 0.5 * (ln_f - ln_n) / r.max_key_f64();
                        // f32 rounding of the decoded value adds at most 2^-24 relative.
                        prop_assert!((back.ln() - (z as f64).ln()).abs() <= bound + 2f64.powi(-23), "{:?} z {}", c, z);
                    }
                    DepthKeyCodec::Linear(r) => {
                        let z = (r.near() as f64 + t * (r.far() as f64 - r.near() as f64)) as f32;
                        prop_assume!(z >= r.near() && z <= r.far());
                        let back = c.decode(c.encode(z)) as f64;
                        let bound = 0.5 * (r.far() as f64 - r.near() as f64) / r.max_key_f64();
                        prop_assert!((back - z as f64).abs() <= bound + r.far() as f64 * 2f64.powi(-23), "{:?} z {}", c, z);
                    }
                    DepthKeyCodec::Fp16 => unreachable!(),
                }
            }
        }
    }
}
