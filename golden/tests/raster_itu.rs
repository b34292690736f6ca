//! The Intersection Test Unit: conservative against the exact f64 ellipse (never misses a
//! subtile it meets), lossless for the SCU (never drops a subtile where the SCU would blend),
//! few false positives, tile ranges, and the edge cases (borders, needles, huge Gaussians,
//! Gaussians centred outside the tile).

mod raster_common;

use neo_golden::formats::{quantize, Cutoff, FeatureEntry, FeatureFormat};
use neo_golden::raster::synth::{cov_from_axes, projected_from_cov};
use neo_golden::raster::{
    candidate_tiles, intersects_rect, pixel_alpha, subtile_bitmap, touches_tile, ExpTable, RasterConfig,
};
use neo_golden::render::{preprocess, Projected};
use neo_golden::sort::DepthKeyCodec;
use proptest::prelude::*;
use raster_common::ellipse_meets_rect;

fn sigma3() -> FeatureFormat {
    FeatureFormat { cutoff: Cutoff::Sigma(3.0), ..FeatureFormat::default() }
}

fn q(p: &Projected, fmt: &FeatureFormat) -> FeatureEntry {
    quantize(p, fmt, &DepthKeyCodec::Fp16)
}

/// Exact-ellipse subtile bitmap of `p` in a tile (f64, closed pixel-centre rectangles).
fn exact_bitmap(p: &Projected, k2: f64, tx: u32, ty: u32, cfg: &RasterConfig) -> u64 {
    let n = cfg.subtiles_per_side();
    let s = cfg.subtile as f64;
    let mut b = 0u64;
    for j in 0..n * n {
        let x0 = (tx * cfg.tile) as f64 + (j % n) as f64 * s;
        let y0 = (ty * cfg.tile) as f64 + (j / n) as f64 * s;
        let rect = [x0, y0, x0 + s - 1.0, y0 + s - 1.0];
        if ellipse_meets_rect(p.mean2d.map(f64::from), p.cov2d.map(f64::from), k2, rect) {
            b |= 1 << j;
        }
    }
    b
}

/// A Gaussian near tile (1, 1) of a 64-px grid: centre within 100 px of it, sigmas 0.55..200
/// px, any angle and opacity.
fn arb_near_tile() -> impl Strategy<Value = Projected> {
    ((-40.0f32..230.0, -40.0f32..230.0), (-0.26f64..2.3, 0.0f64..1.0, 0.0f64..3.2), 0.0f32..1.0).prop_map(
        |((x, y), (lu, ratio, theta), o)| {
            let su = 10f64.powf(lu).max(0.55);
            let sv = (su * ratio).max(0.55);
            projected_from_cov(1, [x, y], cov_from_axes(su, sv, theta), o, [0.5; 3], 2.0)
        },
    )
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(1500))]

    #[test]
    fn never_misses_a_subtile_the_exact_ellipse_meets(p in arb_near_tile(), alpha_cutoff: bool) {
        let fmt = if alpha_cutoff { FeatureFormat::default() } else { sigma3() };
        let cfg = RasterConfig::default();
        let e = q(&p, &fmt);
        let k2 = fmt.cutoff.radius_squared(p.opacity as f64);
        let (xr, yr) = candidate_tiles(&e, &fmt, &cfg, 320, 320);
        for ty in 0..4 {
            for tx in 0..4 {
                let exact = exact_bitmap(&p, k2, tx, ty, &cfg);
                let got = subtile_bitmap(&e, &fmt, tx, ty, &cfg);
                prop_assert_eq!(exact & !got, 0, "tile ({}, {}): exact {:#x} itu {:#x} {:?}", tx, ty, exact, got, p);
                prop_assert_eq!(touches_tile(&e, &fmt, tx, ty, &cfg), got != 0);
                if got != 0 {
                    prop_assert!(xr.contains(&tx) && yr.contains(&ty), "tile ({}, {}) outside {:?} {:?}", tx, ty, xr, yr);
                }
            }
        }
    }

    /// The tile's bitmap (stepped from subtile to subtile) is the rectangle test on each
    /// subtile, on quantised Gaussians and on raw garbage entries alike, with 8- and 16-pixel
    /// subtiles.
    #[test]
    fn bitmap_is_the_rectangle_test_of_each_subtile(
        p in arb_near_tile(),
        words in proptest::array::uniform4(any::<u64>()),
        raw: bool,
        subtile in prop_oneof![Just(8u32), Just(16)],
        (tx, ty) in (0u32..6, 0u32..6),
    ) {
        let fmt = FeatureFormat::default();
        let cfg = RasterConfig { subtile, ..RasterConfig::default() };
        let e = if raw { FeatureEntry::unpack(&words, &fmt) } else { q(&p, &fmt) };
        let (n, s) = (cfg.subtiles_per_side(), cfg.subtile as i64);
        let mut want = 0u64;
        for j in 0..n * n {
            let x0 = (tx * cfg.tile + j % n * cfg.subtile) as i64;
            let y0 = (ty * cfg.tile + j / n * cfg.subtile) as i64;
            if intersects_rect(&e, &fmt, x0, y0, x0 + s - 1, y0 + s - 1) {
                want |= 1 << j;
            }
        }
        prop_assert_eq!(subtile_bitmap(&e, &fmt, tx, ty, &cfg), want, "tile ({}, {}) {:?}", tx, ty, e);
    }

    #[test]
    fn never_drops_a_pixel_the_scu_blends(p in arb_near_tile()) {
        // Moderate anisotropy (the conic error grows with lambda_max / lambda_min, see
        // formats::conic); a sigma ratio <= 30 covers 99.9% of the biker scene's Gaussians.
        let [a, b, c] = p.cov2d.map(f64::from);
        let disc = (0.25 * (a - c) * (a - c) + b * b).sqrt();
        prop_assume!((0.5 * (a + c) + disc) / (0.5 * (a + c) - disc) <= 900.0);
        let fmt = FeatureFormat::default();
        let cfg = RasterConfig::default();
        let exp = ExpTable::new(&cfg.blend.exp, cfg.blend.power_frac);
        let e = q(&p, &fmt);
        let bits = subtile_bitmap(&e, &fmt, 1, 1, &cfg);
        for py in 64..128i64 {
            for px in 64..128i64 {
                let j = ((py - 64) / 8) * 8 + (px - 64) / 8;
                if bits >> j & 1 == 1 {
                    continue;
                }
                if let Some(alpha) = pixel_alpha(&e, &fmt, &cfg, &exp, px, py) {
                    prop_assert!(
                        alpha < cfg.blend.min_alpha_raw(),
                        "pixel ({}, {}) alpha {} but subtile {} clear {:#x}", px, py, alpha, j, bits
                    );
                }
            }
        }
    }
}

#[test]
fn false_positive_rate_on_a_real_scene_is_small() {
    let Some((scene, cams)) = raster_common::biker("raster_itu_false_positives") else { return };
    let cfg = RasterConfig::default();
    for fmt in [FeatureFormat::default(), sigma3()] {
        let (mut set, mut fp, mut tiles, mut tile_fp) = (0u64, 0u64, 0u64, 0u64);
        for cam in &cams {
            for p in preprocess(&scene, cam, 16) {
                let e = q(&p, &fmt);
                let k2 = fmt.cutoff.radius_squared(p.opacity as f64);
                let (xr, yr) = candidate_tiles(&e, &fmt, &cfg, cam.width, cam.height);
                for ty in yr {
                    for tx in xr.clone() {
                        let got = subtile_bitmap(&e, &fmt, tx, ty, &cfg);
                        let exact = exact_bitmap(&p, k2, tx, ty, &cfg);
                        assert_eq!(exact & !got, 0);
                        set += got.count_ones() as u64;
                        fp += (got & !exact).count_ones() as u64;
                        tiles += (got != 0) as u64;
                        tile_fp += (got != 0 && exact == 0) as u64;
                    }
                }
            }
        }
        let rate = fp as f64 / set as f64;
        let tile_rate = tile_fp as f64 / tiles as f64;
        println!(
            "{:?}: {set} subtile bits, {:.2}% false positives; {tiles} tiles, {:.2}% false positives",
            fmt.cutoff,
            100.0 * rate,
            100.0 * tile_rate
        );
        // Measured ~6% of subtile bits and <1% of tiles (docs/formats.md).
        assert!(rate < 0.10, "{rate}");
        assert!(tile_rate < 0.02, "{tile_rate}");
    }
}

#[test]
fn closed_pixel_centre_rectangles_at_borders() {
    let fmt = sigma3();
    let cfg = RasterConfig::default();
    let unit = [1.0f32, 0.0, 1.0];
    // sigma 1, 3 sigma = 3 px. Centre 13: reaches pixel column 16 exactly (a single point of the
    // ellipse), so subtile column 2 ([16, 23]) must be set.
    let e = q(&projected_from_cov(0, [13.0, 4.0], unit, 0.5, [1.0; 3], 1.0), &fmt);
    assert_eq!(subtile_bitmap(&e, &fmt, 0, 0, &cfg), 0b110);
    // Centre 12.5 reaches 15.5 (+ 0.25 px extent rounding): column 16 is not reached.
    let e = q(&projected_from_cov(0, [12.5, 4.0], unit, 0.5, [1.0; 3], 1.0), &fmt);
    assert_eq!(subtile_bitmap(&e, &fmt, 0, 0, &cfg), 0b10);
    // Exactly on the corner of four subtiles and on a tile border.
    let e = q(&projected_from_cov(0, [64.0, 8.0], [0.3, 0.0, 0.3], 0.5, [1.0; 3], 1.0), &fmt);
    assert_eq!(subtile_bitmap(&e, &fmt, 1, 0, &cfg), 1 | 1 << 8);
    assert_eq!(subtile_bitmap(&e, &fmt, 0, 0, &cfg), 1 << 7 | 1 << 15);
    // Half-way between pixel centres of two subtiles: both sides (7 and 8 are 0.5 px away).
    let e = q(&projected_from_cov(0, [7.5, 7.5], [0.3, 0.0, 0.3], 0.5, [1.0; 3], 1.0), &fmt);
    assert_eq!(subtile_bitmap(&e, &fmt, 0, 0, &cfg), 1 | 1 << 1 | 1 << 8 | 1 << 9);
    assert!(intersects_rect(&e, &fmt, 8, 8, 8, 8) && !intersects_rect(&e, &fmt, 10, 10, 20, 20));
}

#[test]
fn degenerate_needle_and_zero_scale() {
    let fmt = FeatureFormat::default();
    let cfg = RasterConfig::default();
    // Zero scale: only the 0.3 px^2 dilation is left, radius 3.33 * 0.548 = 1.8 px.
    let e = q(&projected_from_cov(0, [20.0, 20.0], [0.3, 0.0, 0.3], 1.0, [1.0; 3], 1.0), &fmt);
    assert_eq!(subtile_bitmap(&e, &fmt, 0, 0, &cfg), 1 << (2 * 8 + 2));
    // A needle 150 px long (sigma 50) and 0.55 px wide at 30 degrees through the tile centre:
    // conservative, and far tighter than its bounding box.
    let cov = cov_from_axes(50.0, 0.3f64.sqrt(), 30f64.to_radians());
    let p = projected_from_cov(0, [32.0, 32.0], cov, 0.9, [1.0; 3], 1.0);
    let e = q(&p, &fmt);
    let got = subtile_bitmap(&e, &fmt, 0, 0, &cfg);
    let exact = exact_bitmap(&p, fmt.cutoff.radius_squared(0.9), 0, 0, &cfg);
    assert_eq!(exact & !got, 0);
    assert!(got.count_ones() <= exact.count_ones() + 4, "{:#x} vs {:#x}", got, exact);
    assert!(got.count_ones() < 30, "{}", got.count_ones());
}

#[test]
fn screen_filling_gaussian_touches_every_subtile() {
    let fmt = FeatureFormat::default();
    let cfg = RasterConfig::default();
    // sigma 5000 px: conic ~4e-8, extents beyond the 13-bit field: unbounded.
    let p = projected_from_cov(0, [1280.0, 720.0], [2.5e7, 0.0, 2.5e7], 0.8, [1.0; 3], 1.0);
    let e = q(&p, &fmt);
    assert_eq!(e.extent_xy[0], fmt.unbounded_extent());
    assert_eq!(candidate_tiles(&e, &fmt, &cfg, 2560, 1440), (0..40, 0..23));
    for (tx, ty) in [(0, 0), (39, 22), (20, 11)] {
        assert_eq!(subtile_bitmap(&e, &fmt, tx, ty, &cfg), u64::MAX);
    }
    // Sigma 400 px, bounded: all subtiles within 1330 px of the centre.
    let p = projected_from_cov(0, [1280.0, 720.0], [1.6e5, 0.0, 1.6e5], 0.8, [1.0; 3], 1.0);
    let e = q(&p, &fmt);
    assert!(e.extent_xy[0] < fmt.unbounded_extent());
    assert_eq!(subtile_bitmap(&e, &fmt, 20, 11, &cfg), u64::MAX);
    assert_eq!(candidate_tiles(&e, &fmt, &cfg, 2560, 1440), (0..40, 0..23));
    // A tile beyond the cutoff radius (1311 px) along an axis is not touched.
    let far = projected_from_cov(0, [2000.0, 720.0], [1.6e5, 0.0, 1.6e5], 0.8, [1.0; 3], 1.0);
    assert!(!touches_tile(&q(&far, &fmt), &fmt, 0, 11, &cfg), "1937 px away");
}

#[test]
fn gaussian_centred_outside_the_tile_and_the_image() {
    let fmt = sigma3();
    let cfg = RasterConfig::default();
    // Centre 10 px left of the image, sigma 4: reaches x = 2 -> subtile column 0 only.
    let p = projected_from_cov(0, [-10.0, 100.0], [16.0, 0.0, 16.0], 0.5, [1.0; 3], 1.0);
    let e = q(&p, &fmt);
    assert_eq!(candidate_tiles(&e, &fmt, &cfg, 640, 480), (0..1, 1..2));
    let bits = subtile_bitmap(&e, &fmt, 0, 1, &cfg);
    // Rows 88..=112 -> subtile rows 3 (88..95) and 4, 5 (96..111), 6 (112).
    assert_eq!(bits, (1 << 24) | (1 << 32) | (1 << 40) | (1 << 48), "{bits:#x}");
    // Entirely off-screen: no tile range.
    let p = projected_from_cov(0, [-30.0, 100.0], [16.0, 0.0, 16.0], 0.5, [1.0; 3], 1.0);
    let (xr, _) = candidate_tiles(&q(&p, &fmt), &fmt, &cfg, 640, 480);
    assert!(xr.is_empty());
    // Centred in the neighbouring tile, reaching into this one.
    let p = projected_from_cov(0, [70.0, 30.0], [16.0, 0.0, 16.0], 0.5, [1.0; 3], 1.0);
    let e = q(&p, &fmt);
    // Column 7 ([56, 63]) for rows 18..=42 (subtile rows 2..=5).
    assert_eq!(subtile_bitmap(&e, &fmt, 0, 0, &cfg), (1 << 23) | (1 << 31) | (1 << 39) | (1 << 47));
}

#[test]
fn garbage_entries_do_not_panic() {
    let fmt = FeatureFormat::default();
    let cfg = RasterConfig::default();
    let mut p = projected_from_cov(0, [1.0, 2.0], [1.0, 0.0, 1.0], 0.5, [0.5; 3], 1.0);
    p.mean2d = [f32::NAN, 1e30];
    p.cov2d = [f32::INFINITY, f32::NAN, -1.0];
    let e = q(&p, &fmt);
    assert_eq!(subtile_bitmap(&e, &fmt, 0, 0, &cfg), u64::MAX);
    let _ = candidate_tiles(&e, &fmt, &cfg, 100, 100);
    // Extreme raw values straight from unpacked garbage.
    let raw = FeatureEntry::unpack(&[u64::MAX; 4], &fmt);
    let _ = subtile_bitmap(&raw, &fmt, 1000, 1000, &cfg);
    let _ = candidate_tiles(&raw, &fmt, &cfg, 8192, 8192);
}
