//! The Subtile Compute Unit: the 1/255 threshold at its exact boundary, early termination,
//! agreement with the float blend on single Gaussians (needle, screen-filling, centred
//! outside), empty tables, pixels outside the image, work counters, and that tile rendering
//! equals unfiltered per-pixel blending (the ITU drops nothing the SCU would blend).

use neo_golden::formats::{quantize, FeatureEntry, FeatureFormat, QFormat};
use neo_golden::raster::synth::{cov_from_axes, projected_from_cov};
use neo_golden::raster::{raster_tile, shade_pixel, subtile_bitmap, RasterConfig, TileRaster};
use neo_golden::render::{blend_pixel, Projected, Splat};
use neo_golden::sort::DepthKeyCodec;
use proptest::prelude::*;

fn q(p: &Projected, fmt: &FeatureFormat) -> FeatureEntry {
    quantize(p, fmt, &DepthKeyCodec::Fp16)
}

/// The float reference's 8-bit pixel for `ps` (front to back) at `(x, y)`.
fn float_pixel(ps: &[Projected], x: u32, y: u32) -> [u8; 3] {
    let splats: Vec<Splat> = ps.iter().map(Splat::from).collect();
    blend_pixel(&splats, x, y).map(neo_golden::image::quantize_channel)
}

/// Largest per-channel difference between a tile and the float reference over the pixels of
/// tile `(tx, ty)` inside a `w x h` image.
fn max_diff_to_float(
    r: &TileRaster,
    ps: &[Projected],
    tx: u32,
    ty: u32,
    cfg: &RasterConfig,
    w: u32,
    h: u32,
) -> u8 {
    let t = cfg.tile;
    let mut worst = 0u8;
    for ly in 0..t {
        for lx in 0..t {
            let (x, y) = (tx * t + lx, ty * t + ly);
            if x >= w || y >= h {
                continue;
            }
            let f = float_pixel(ps, x, y);
            let g = r.pixels[(ly * t + lx) as usize];
            for c in 0..3 {
                worst = worst.max(f[c].abs_diff(g[c]));
            }
        }
    }
    worst
}

#[test]
fn alpha_threshold_is_exact_at_its_boundary() {
    // Opacity with the alpha's 12 fraction bits: at the Gaussian's centre (power 0, exp = 1)
    // alpha_raw equals the opacity raw value.
    let fmt = FeatureFormat { opacity: QFormat::unsigned(12, 12), ..FeatureFormat::default() };
    let cfg = RasterConfig::default();
    let min = cfg.blend.min_alpha_raw();
    assert_eq!(min, 17);
    // 17/4096 >= 1/255 > 16/4096: the fixed-point threshold is exactly "alpha < 1/255".
    assert!(min as f64 / 4096.0 >= 1.0 / 255.0 && ((min - 1) as f64 / 4096.0) < 1.0 / 255.0);
    let at = |raw: i64| {
        let p = projected_from_cov(0, [20.0, 20.0], [4.0, 0.0, 4.0], raw as f32 / 4096.0, [1.0; 3], 1.0);
        let e = q(&p, &fmt);
        assert_eq!(e.opacity as i64, raw);
        raster_tile(&[e], &fmt, 0, 0, 64, 64, &cfg).pixels[20 * 64 + 20]
    };
    // Exactly at the threshold: kept (round(17/4096 * 255) = 1). One LSB below: skipped.
    assert_eq!(at(min), [1, 1, 1]);
    assert_eq!(at(min - 1), [0, 0, 0]);
    // And larger opacities are kept.
    assert_eq!(at(100), [6, 6, 6]); // 100/4096 * 255 = 6.2
}

#[test]
fn opaque_stack_terminates_and_later_gaussians_do_not_matter() {
    let fmt = FeatureFormat::default();
    let cfg = RasterConfig::default();
    // sigma 1000 px: alpha ~ 0.949 (opacity 243/256) over the whole tile. T after three layers
    // is ~0.051^3 = 1.4e-4, after four ~7e-6 < 1e-4: every pixel finishes at the fourth entry,
    // which is not added.
    let layer = |rgb: [f32; 3], i: u32| projected_from_cov(i, [32.0, 32.0], [1e6, 0.0, 1e6], 0.95, rgb, 1.0);
    let mut a: Vec<Projected> = (0..3).map(|i| layer([0.5; 3], i)).collect();
    let mut b = a.clone();
    a.extend((3..10).map(|i| layer([1.0, 0.0, 0.0], i)));
    b.extend((3..10).map(|i| layer([0.0, 0.0, 1.0], i)));
    let ea: Vec<FeatureEntry> = a.iter().map(|p| q(p, &fmt)).collect();
    let eb: Vec<FeatureEntry> = b.iter().map(|p| q(p, &fmt)).collect();
    let ra = raster_tile(&ea, &fmt, 0, 0, 64, 64, &cfg);
    let rb = raster_tile(&eb, &fmt, 0, 0, 64, 64, &cfg);
    assert_eq!(ra, rb, "entries after termination changed the tile");
    for px in &ra.pixels {
        assert_eq!(px[0], px[1]);
        assert_eq!(px[1], px[2]);
        assert_eq!(px[0], 127); // 0.5 * (1 - T), T ~ 1.4e-4
    }
    for w in &ra.work {
        assert_eq!((w.routed, w.processed, w.finished_pixels, w.pixel_evals), (10, 4, 64, 256), "{w:?}");
        assert!(w.terminated);
    }
    let s = shade_pixel(&ea, &fmt, &cfg, 10, 50);
    assert_eq!(s.finished_at, Some(3));
    assert!(s.transmittance >= cfg.blend.min_transmittance_raw());
    // The float reference stops at the same layer.
    assert_eq!(float_pixel(&a, 10, 50), [127; 3]);
}

#[test]
fn single_gaussians_match_the_float_blend() {
    let fmt = FeatureFormat::default();
    let cfg = RasterConfig::default();
    let cases = [
        // A needle: 30 px by 0.6 px at 20 degrees.
        ("needle", [40.0f32, 30.0], cov_from_axes(30.0, 0.6, 20f64.to_radians()), 0.8f32),
        // Zero scale: only the dilation.
        ("dilation only", [33.0, 33.3], [0.3, 0.0, 0.3], 0.99),
        // Screen-filling.
        ("screen filling", [1000.0, -500.0], cov_from_axes(2000.0, 1500.0, 0.4), 0.7),
        // Centred outside the tile (and the image), reaching into it.
        ("centred outside", [-12.0, 20.0], cov_from_axes(8.0, 5.0, 0.7), 0.9),
    ];
    for (name, mean, cov, o) in cases {
        let p = projected_from_cov(0, mean, cov, o, [0.9, 0.4, 0.1], 1.0);
        let e = q(&p, &fmt);
        let r = raster_tile(&[e], &fmt, 0, 0, 64, 64, &cfg);
        let d = max_diff_to_float(&r, &[p], 0, 0, &cfg, 64, 64);
        assert!(d <= 1, "{name}: max difference {d} LSB");
        assert!(r.valid[0], "{name}");
        assert!(r.pixels.iter().any(|px| px[0] > 0), "{name}: blank tile");
    }
}

#[test]
fn empty_table_is_black() {
    let fmt = FeatureFormat::default();
    let cfg = RasterConfig::default();
    let r = raster_tile(&[], &fmt, 3, 2, 1000, 1000, &cfg);
    assert_eq!(r.pixels.len(), 64 * 64);
    assert!(r.pixels.iter().all(|p| *p == [0, 0, 0]));
    assert!(r.valid.is_empty() && r.bitmaps.is_empty());
    assert_eq!(r.work.len(), 64);
    assert!(r.work.iter().all(|w| w.routed == 0 && w.processed == 0 && w.pixel_evals == 0 && !w.terminated));
}

#[test]
fn pixels_outside_the_image_are_black_and_skipped() {
    let fmt = FeatureFormat::default();
    let cfg = RasterConfig::default();
    let p = projected_from_cov(0, [32.0, 32.0], [1e4, 0.0, 1e4], 0.6, [1.0; 3], 1.0);
    let r = raster_tile(&[q(&p, &fmt)], &fmt, 0, 0, 40, 30, &cfg);
    for y in 0..64 {
        for x in 0..64 {
            let v = r.pixels[y * 64 + x];
            if x >= 40 || y >= 30 {
                assert_eq!(v, [0, 0, 0], "({x}, {y})");
            } else {
                assert!(v[0] > 100, "({x}, {y}) {v:?}");
            }
        }
    }
    // Subtile (7, 7) has no pixel in the image: routed but not processed. Subtile (4, 3)
    // (x 32..39, y 24..31) has 8 x 6 pixels inside.
    assert_eq!(r.work[63].routed, 1);
    assert_eq!(r.work[63].processed, 0);
    assert_eq!(r.work[3 * 8 + 4].pixel_evals, 48);
    assert_eq!(r.bitmaps, vec![u64::MAX]);
}

/// A random tile table: Gaussians around tile (1, 1), sigma ratio at most 30, in table order.
fn arb_table() -> impl Strategy<Value = Vec<Projected>> {
    proptest::collection::vec(
        (
            (20.0f32..172.0, 20.0f32..172.0),
            (-0.26f64..1.6, 0.033f64..1.0, 0.0f64..3.2),
            0.0f32..1.0,
            (0.0f32..1.2, 0.0f32..1.2, 0.0f32..1.2),
        ),
        0..24,
    )
    .prop_map(|v| {
        v.into_iter()
            .enumerate()
            .map(|(i, ((x, y), (lu, ratio, th), o, (r, g, b)))| {
                let su = 10f64.powf(lu).max(0.55);
                projected_from_cov(
                    i as u32,
                    [x, y],
                    cov_from_axes(su, (su * ratio).max(0.55), th),
                    o,
                    [r, g, b],
                    1.0,
                )
            })
            .collect()
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    #[test]
    fn tile_equals_unfiltered_blend_and_is_close_to_float(ps in arb_table()) {
        let fmt = FeatureFormat::default();
        let cfg = RasterConfig::default();
        let es: Vec<FeatureEntry> = ps.iter().map(|p| q(p, &fmt)).collect();
        let r = raster_tile(&es, &fmt, 1, 1, 1000, 1000, &cfg);
        // Bitmaps, valid bits and routing counts follow the ITU.
        for (i, e) in es.iter().enumerate() {
            prop_assert_eq!(r.bitmaps[i], subtile_bitmap(e, &fmt, 1, 1, &cfg));
            prop_assert_eq!(r.valid[i], r.bitmaps[i] != 0);
        }
        for (j, w) in r.work.iter().enumerate() {
            prop_assert_eq!(w.routed as usize, r.bitmaps.iter().filter(|&&b| b >> j & 1 == 1).count());
            prop_assert!(w.processed <= w.routed && w.pixel_evals <= 64 * w.processed);
        }
        // Filtering by the bitmaps changes no pixel.
        for ly in 0..64 {
            for lx in 0..64 {
                let s = shade_pixel(&es, &fmt, &cfg, 64 + lx, 64 + ly);
                prop_assert_eq!(r.pixels[(ly * 64 + lx) as usize], s.color, "pixel ({}, {})", lx, ly);
            }
        }
        // And the image is close to the float blend in the same order.
        let d = max_diff_to_float(&r, &ps, 1, 1, &cfg, 1000, 1000);
        prop_assert!(d <= 3, "max difference {} LSB", d);
    }
}
