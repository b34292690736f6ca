//! The SCU exp unit: error bound against f64 `exp` over the range that matters, monotonicity,
//! the table's definition, and behaviour below the 1/255 threshold.

use neo_golden::formats::{BlendFormat, ExpFormat, FeatureFormat};
use neo_golden::raster::ExpTable;

/// Formats to check: the default and a few neighbours (with and without interpolation).
fn formats() -> Vec<(ExpFormat, u8)> {
    let d = BlendFormat::default();
    vec![
        (d.exp, d.power_frac),
        (ExpFormat { table_bits: 4, interp_bits: 6, ..d.exp }, 10),
        (ExpFormat { table_bits: 6, interp_bits: 0, ..d.exp }, 8),
        (ExpFormat { table_bits: 5, interp_bits: 8, out_frac: 20, log2e_frac: 20 }, 14),
    ]
}

#[test]
fn default_error_over_the_visible_range() {
    let b = BlendFormat::default();
    let t = ExpTable::new(&b.exp, b.power_frac);
    // Every power in [-5.6, 0] (alpha >= 1/255 needs power >= ln(1/255) = -5.54).
    let e = t.error(-5.6, 0.0);
    assert_eq!(e.inputs, (5.6 * 1024.0) as u64 + 1);
    println!("default exp unit on [-5.6, 0]: {e:?}");
    // Design bounds (docs/formats.md): below one LSB of a 12-bit alpha in absolute terms, and
    // within 0.25% of exp where alpha is near 1/255 (2^-17 output rounding over exp(-5.6)).
    assert!(e.max_abs <= 1.2e-4, "{e:?}");
    assert!(e.max_rel <= 2.5e-3, "{e:?}");
    // Near power 0 the relative error is far smaller than near the threshold.
    let near0 = t.error(-1.0, 0.0);
    assert!(near0.max_rel <= 2.0e-4, "{near0:?}");
}

#[test]
fn table_follows_its_definition() {
    for (f, p) in formats() {
        let t = ExpTable::new(&f, p);
        let n = 1usize << f.table_bits;
        assert_eq!(t.table().len(), n + 1);
        for (j, &v) in t.table().iter().enumerate() {
            let exact = 2f64.powf(f.out_frac as f64 - j as f64 / n as f64);
            assert!((v as f64 - exact).abs() <= 0.5, "entry {j}: {v} vs {exact}");
        }
        assert!(
            (t.log2e_raw() as f64 - std::f64::consts::LOG2_E * 2f64.powi(f.log2e_frac as i32)).abs() <= 0.5
        );
        assert_eq!(t.eval(0), 1 << f.out_frac);
    }
}

#[test]
fn monotone_non_increasing_over_every_input() {
    for (f, p) in formats() {
        let t = ExpTable::new(&f, p);
        // Past power -16 every format is 0; include the saturation region.
        let last = 16i64 << p;
        let mut prev = t.eval(0);
        for np in 1..=last {
            let v = t.eval(np);
            assert!(v <= prev, "{f:?} P={p}: exp({np}) = {v} > exp({}) = {prev}", np - 1);
            assert!(v >= 0);
            prev = v;
        }
        assert_eq!(prev, 0);
    }
}

#[test]
fn below_the_threshold_alpha_stays_below_1_over_255() {
    // For power <= -5.6, even the largest opacity gives alpha < 1/255 through the unit.
    let b = BlendFormat::default();
    let fmt = FeatureFormat::default();
    let t = ExpTable::new(&b.exp, b.power_frac);
    let o_max = fmt.opacity.max_raw();
    let shift = fmt.opacity.frac as u32 + b.exp.out_frac as u32 - b.alpha_frac as u32;
    let first = (5.6 * 1024.0f64).ceil() as i64;
    for np in first..=b.max_neg_power() {
        let alpha = (o_max * t.eval(np) + (1 << (shift - 1))) >> shift;
        assert!(alpha < b.min_alpha_raw(), "np {np}: alpha {alpha}");
    }
    // And the saturated power is below the threshold for every opacity.
    assert!((o_max * t.eval(b.max_neg_power())) >> shift < b.min_alpha_raw());
}

#[test]
fn without_interpolation_the_error_is_the_table_step() {
    let f = ExpFormat { table_bits: 6, interp_bits: 0, out_frac: 16, log2e_frac: 14 };
    let t = ExpTable::new(&f, 10);
    let e = t.error(-5.6, 0.0);
    // `y` is rounded to the 1/64 grid of the table: up to half a step, 2^(1/128) - 1 = 0.54%
    // (plus the output rounding near the threshold).
    assert!(e.max_rel > 0.004 && e.max_rel < 0.0075, "{e:?}");
    let d = ExpTable::new(&BlendFormat::default().exp, 10).error(-5.6, 0.0);
    assert!(d.max_abs < e.max_abs / 4.0);
}
