//! Feature-table quantisation: error bounds of every field, conservative ITU extents, packing,
//! robustness on garbage, and fitting to a real scene.

mod raster_common;

use neo_golden::formats::{quantize, Cutoff, FeatureEntry, FeatureFormat, FeatureStats, QFormat};
use neo_golden::raster::synth::{cov_from_axes, projected_from_cov};
use neo_golden::render::{preprocess, Projected};
use neo_golden::sort::DepthKeyCodec;
use proptest::prelude::*;

/// A random preprocessed Gaussian: mean within +-40000 px, sigmas 0.55..3000 px, any angle.
fn arb_projected() -> impl Strategy<Value = Projected> {
    (
        (-40_000.0f32..40_000.0, -40_000.0f32..40_000.0),
        (-0.6f64..3.5, 0.0f64..1.0, 0.0f64..std::f64::consts::PI),
        (0.0f32..1.0, 0.0f32..1.9, 0.0f32..1.9, 0.0f32..1.9),
        0.25f32..500.0,
    )
        .prop_map(|((mx, my), (lu, ratio, theta), (o, r, g, b), depth)| {
            let su = 10f64.powf(lu).max(0.55);
            let sv = (su * ratio).max(0.55);
            projected_from_cov(3, [mx, my], cov_from_axes(su, sv, theta), o, [r, g, b], depth)
        })
}

/// The support of the ellipse `k2`-cutoff around the float mean along `n`, minus the quantised
/// mean's offset along `n` (what an extent must cover).
fn needed_support(p: &Projected, k2: f64, mq: [f64; 2], n: [f64; 2]) -> f64 {
    let [a, b, c] = p.cov2d.map(f64::from);
    let var = n[0] * n[0] * a + 2.0 * n[0] * n[1] * b + n[1] * n[1] * c;
    let centre = (p.mean2d[0] as f64 - mq[0]) * n[0] + (p.mean2d[1] as f64 - mq[1]) * n[1];
    (k2 * var).sqrt() + centre.abs()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    #[test]
    fn every_field_within_its_rounding_bound(p in arb_projected()) {
        let fmt = FeatureFormat::default();
        let key = DepthKeyCodec::Fp16;
        let e = quantize(&p, &fmt, &key);
        // Mean: half an LSB inside the range, saturated outside.
        for (q, m) in e.mean_px(&fmt).iter().zip(p.mean2d) {
            let m = m as f64;
            if m.abs() < fmt.mean.max_value() {
                prop_assert!((q - m).abs() <= fmt.mean.lsb() / 2.0, "{} {}", q, m);
            } else {
                prop_assert!(*q == fmt.mean.min_value() || *q == fmt.mean.max_value());
            }
        }
        // Opacity and colour: half an LSB (colour is below 2); opacity saturates just below 1.
        if (p.opacity as f64) < fmt.opacity.max_value() + fmt.opacity.lsb() / 2.0 {
            prop_assert!((e.opacity_f64(&fmt) - p.opacity as f64).abs() <= fmt.opacity.lsb() / 2.0);
        } else {
            prop_assert_eq!(e.opacity as i64, fmt.opacity.max_raw());
        }
        for (q, c) in e.rgb_f64(&fmt).iter().zip(p.rgb) {
            prop_assert!((q - c as f64).abs() <= fmt.color.lsb() / 2.0);
        }
        // Conic: each coefficient within half an LSB of the shared scale, the scale within
        // 2^-(M-1) of the largest coefficient.
        let lsb = (-(fmt.conic.scale(e.conic.exp) as f64)).exp2();
        let back = e.conic_f64(&fmt);
        let mx = p.conic.iter().fold(0.0f64, |m, &v| m.max((v as f64).abs()));
        for (q, c) in back.iter().zip(p.conic) {
            prop_assert!((q - c as f64).abs() <= lsb / 2.0, "{:?} {:?}", back, p.conic);
        }
        prop_assert!(lsb * (2f64.powi(fmt.conic.mantissa_bits as i32 - 1) - 0.5) <= mx * (1.0 + 1e-9));
        prop_assert_eq!(e.depth_key, key.encode(p.depth));
        // Extents are conservative: they bound the exact ellipse around the float mean, seen
        // from the quantised mean, along x, y and the (non-unit) quantised axes.
        let k2 = fmt.cutoff.radius_squared(p.opacity as f64);
        let mq = e.mean_px(&fmt);
        let unb = fmt.unbounded_extent();
        let ext = |raw: i32| if raw >= unb { f64::INFINITY } else { fmt.extent.dequantize(raw as i64) };
        prop_assert!(ext(e.extent_xy[0]) >= needed_support(&p, k2, mq, [1.0, 0.0]));
        prop_assert!(ext(e.extent_xy[1]) >= needed_support(&p, k2, mq, [0.0, 1.0]));
        let s = fmt.axis.lsb();
        let (c, sn) = (e.axis[0] as f64 * s, e.axis[1] as f64 * s);
        prop_assert!(ext(e.extent_uv[0]) >= needed_support(&p, k2, mq, [c, sn]));
        prop_assert!(ext(e.extent_uv[1]) >= needed_support(&p, k2, mq, [-sn, c]));
        // The axis is a near-unit vector along the major axis.
        prop_assert!(((c * c + sn * sn).sqrt() - 1.0).abs() < 2.0 * s);
    }

    #[test]
    fn pack_unpack_round_trips(p in arb_projected(), mant in 6u8..=26, mfrac in 0u8..=12, cfrac in 1u8..=14) {
        let mut fmt = FeatureFormat::default();
        fmt.conic.mantissa_bits = mant;
        fmt.mean = QFormat::signed(17 + mfrac, mfrac);
        fmt.color = QFormat::unsigned(cfrac + 1, cfrac);
        fmt.extent = QFormat::unsigned(15, mfrac.min(2));
        fmt.check().unwrap();
        let e = quantize(&p, &fmt, &DepthKeyCodec::Fp16);
        let words = e.pack(&fmt);
        prop_assert_eq!(words.len(), fmt.words_per_entry());
        prop_assert_eq!(FeatureEntry::unpack(&words, &fmt), e);
        // Nothing above bits_per_entry is set.
        let bits = fmt.bits_per_entry() as usize;
        for (i, w) in words.iter().enumerate() {
            let lo = i * 64;
            if bits < lo + 64 {
                prop_assert_eq!(w >> (bits - lo), 0);
            }
        }
    }

    #[test]
    fn unpack_never_panics(words in proptest::collection::vec(any::<u64>(), 0..6)) {
        let fmt = FeatureFormat::default();
        let e = FeatureEntry::unpack(&words, &fmt);
        // What was read re-packs to the same bits (masked to the entry).
        let again = FeatureEntry::unpack(&e.pack(&fmt), &fmt);
        prop_assert_eq!(again, e);
    }
}

#[test]
fn layout_is_documented_order_and_byte_size() {
    let fmt = FeatureFormat::default();
    let names: Vec<&str> = fmt.layout().iter().map(|f| f.name).collect();
    assert_eq!(
        names,
        [
            "mean_x",
            "mean_y",
            "conic_a",
            "conic_b",
            "conic_c",
            "conic_exp",
            "opacity",
            "red",
            "green",
            "blue",
            "extent_x",
            "extent_y",
            "axis_c",
            "axis_s",
            "extent_u",
            "extent_v",
            "depth_key"
        ]
    );
    let bits: u32 = fmt.layout().iter().map(|f| f.width).sum();
    assert_eq!(fmt.bits_per_entry(), bits);
    assert_eq!(fmt.bytes_per_entry(), bits.div_ceil(8));
    // Default widths: 2x28 + (18 + 19 + 18 + 6) + 8 + 3x11 + 4x15 + 2x10 + 16: 254 bits, 32 bytes.
    assert_eq!(bits, 56 + 61 + 8 + 33 + 60 + 20 + 16);
    assert_eq!(fmt.bytes_per_entry(), 32);
    // A field of known value lands where the layout says.
    let e = FeatureEntry { opacity: 0xA5, ..FeatureEntry::default() };
    let w = e.pack(&fmt);
    let op = fmt.layout()[6];
    let word = w[(op.lsb / 64) as usize] >> (op.lsb % 64);
    assert_eq!(word & 0xFF, 0xA5);
}

#[test]
fn garbage_floats_do_not_panic_and_extents_become_unbounded() {
    let fmt = FeatureFormat::default();
    let mut p = projected_from_cov(0, [1.0, 2.0], [1.0, 0.0, 1.0], 0.5, [0.5; 3], 1.0);
    p.mean2d = [f32::NAN, f32::INFINITY];
    p.cov2d = [f32::NAN, 0.0, 1.0];
    p.conic = [f32::INFINITY, f32::NAN, -1.0];
    p.opacity = f32::NAN;
    p.rgb = [f32::NAN, -1.0, 1e30];
    p.depth = f32::NAN;
    let e = quantize(&p, &fmt, &DepthKeyCodec::Fp16);
    assert_eq!(e.mean[0], 0);
    assert_eq!(e.mean[1] as i64, fmt.mean.max_raw());
    assert_eq!(e.extent_xy[0], fmt.unbounded_extent());
    assert_eq!(e.rgb, [0, 0, fmt.color.max_raw() as i32]);
    assert_eq!(e.depth_key, DepthKeyCodec::Fp16.invalid_key());
    assert_eq!(FeatureEntry::unpack(&e.pack(&fmt), &fmt), e);
}

#[test]
fn faint_gaussians_get_tight_extents_with_the_alpha_cutoff() {
    let alpha = FeatureFormat::default();
    let sigma3 = FeatureFormat { cutoff: Cutoff::Sigma(3.0), ..alpha };
    let key = DepthKeyCodec::Fp16;
    let faint = projected_from_cov(0, [100.0, 100.0], [100.0, 0.0, 100.0], 0.02, [1.0; 3], 1.0);
    let opaque = projected_from_cov(0, [100.0, 100.0], [100.0, 0.0, 100.0], 1.0, [1.0; 3], 1.0);
    let x = |f: &FeatureFormat, p: &Projected| f.extent.dequantize(quantize(p, f, &key).extent_xy[0] as i64);
    // sigma 10 px: 3 sigma = 30 px; opacity 0.02 reaches 1/255 at sqrt(2 ln 5.1) = 1.80 sigma,
    // opacity 1 at sqrt(2 ln 255) = 3.33 sigma.
    assert!((x(&sigma3, &faint) - 30.0).abs() <= 0.3);
    assert!(x(&alpha, &faint) < 19.0 && x(&alpha, &faint) > 18.0, "{}", x(&alpha, &faint));
    assert!(x(&alpha, &opaque) > 33.3 && x(&alpha, &opaque) < 33.7, "{}", x(&alpha, &opaque));
}

#[test]
fn fitted_format_holds_the_biker_scene_without_saturation() {
    let Some((scene, cams)) = raster_common::biker("formats_fitted_biker") else { return };
    let mut stats = FeatureStats::default();
    let mut all = Vec::new();
    for cam in &cams {
        let ps = preprocess(&scene, cam, 16);
        stats = stats.merge(&FeatureStats::from_projected(&ps));
        all.extend(ps);
    }
    let base = FeatureFormat::default();
    let fmt = FeatureFormat::fitted(&stats, &base);
    fmt.check().unwrap();
    // 320x240 views: the mean needs far fewer integer bits than the QHD default.
    assert!(fmt.mean.bits < base.mean.bits && fmt.bits_per_entry() < base.bits_per_entry());
    let key = DepthKeyCodec::Fp16;
    for p in &all {
        let e = quantize(p, &fmt, &key);
        assert!(e.mean.iter().all(|&m| (m as i64) > fmt.mean.min_raw() && (m as i64) < fmt.mean.max_raw()));
        assert!(e.rgb.iter().all(|&c| (c as i64) < fmt.color.max_raw()));
        // The conic keeps full precision (the exponent is in range, not clamped).
        assert!(e.conic.exp < fmt.conic.max_exp());
        assert!(e.conic.a.max(e.conic.c) >= 1 << (fmt.conic.mantissa_bits - 1));
    }
}
