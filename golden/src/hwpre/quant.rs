//! Fixed-point quantisation in the hardware's arithmetic.

use crate::formats::fixed::QFormat;
use crate::hwarith::{Arith, Round};

/// `q.quantize(v)` in hardware arithmetic: `floor(v 2^frac + 1/2)` saturated to the format's
/// raw range, NaN giving 0. The product by `2^frac` is exact in binary32 unless it overflows
/// (then the saturation gives the same raw value) or underflows into the subnormals (then the
/// value rounds to 0 either way), so this equals [`QFormat::quantize`] of `v` as f64.
pub fn to_fixed<A: Arith>(a: &mut A, v: A::F, q: &QFormat) -> A::I {
    let scale = a.lit((q.frac as f32).exp2());
    let scaled = a.mul(v, scale);
    let raw = a.to_int(scaled, Round::HalfUp);
    let lo = a.ilit(q.min_raw() as i32);
    let hi = a.ilit(q.max_raw() as i32);
    let raw = a.imax(raw, lo);
    a.imin(raw, hi)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hwarith::Native;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn matches_the_f64_quantiser(bits in any::<u32>(), width in 2u8..=24, frac in 0u8..=20, signed in any::<bool>()) {
            let q = if signed { QFormat::signed(width, frac.min(width - 1)) } else { QFormat::unsigned(width, frac.min(width)) };
            let v = f32::from_bits(bits);
            prop_assert_eq!(to_fixed(&mut Native, v, &q) as i64, q.quantize(v as f64), "{} {:?}", v, q);
        }
    }
}
