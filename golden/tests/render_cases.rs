//! Hand-checkable cases of the float reference renderer, and its invariances (tile size, thread
//! count, the blending shortcuts).

use glam::{DMat3, DVec3};
use neo_golden::camera::Camera;
use neo_golden::image::Image;
use neo_golden::render::{
    bin, blend_pixel, preprocess, render, RenderOptions, Splat, MIN_ALPHA, NEAR_CULL, SH_C0,
};
use neo_golden::scene::Scene;

/// A camera at the origin looking down +z with x right and y down (identity rotation).
fn camera(width: u32, height: u32, f: f64) -> Camera {
    Camera {
        name: "test".into(),
        width,
        height,
        fx: f,
        fy: f,
        position: DVec3::ZERO,
        cam_to_world: DMat3::IDENTITY,
    }
}

/// One Gaussian: position, isotropic scale, opacity and (view-independent) colour.
struct G {
    pos: [f32; 3],
    scale: f32,
    opacity: f32,
    rgb: [f32; 3],
}

/// A degree-0 scene; the DC coefficients are chosen so that the colour is `rgb`.
fn scene(gs: &[G]) -> Scene {
    let mut s = Scene { sh_degree: 0, ..Default::default() };
    for g in gs {
        s.positions.push(g.pos);
        s.scales.push([g.scale; 3]);
        s.rotations.push([1.0, 0.0, 0.0, 0.0]);
        s.opacities.push(g.opacity);
        s.sh.extend(g.rgb.map(|c| (c - 0.5) / SH_C0));
    }
    s
}

fn close(a: [f32; 3], b: [f32; 3], tol: f32) -> bool {
    a.iter().zip(&b).all(|(x, y)| (x - y).abs() <= tol)
}

/// A deterministic pseudo-random number in [0, 1).
fn next(state: &mut u64) -> f32 {
    *state = state.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
    (*state >> 40) as f32 / (1u64 << 24) as f32
}

/// Random anisotropic, rotated Gaussians of SH degree 3 spread over (and beyond) the view of
/// `camera(.., f)`, opacities in `[0, max_opacity)`.
fn random_scene(n: usize, seed: u64, max_opacity: f32) -> Scene {
    let mut st = seed;
    let mut s = Scene { sh_degree: 3, ..Default::default() };
    for _ in 0..n {
        let z = 1.0 + 9.0 * next(&mut st);
        s.positions.push([(next(&mut st) - 0.5) * 1.4 * z, (next(&mut st) - 0.5) * 1.1 * z, z]);
        let base = (next(&mut st) * 4.0 - 5.5).exp();
        s.scales.push([
            base * (0.2 + next(&mut st)),
            base * (0.2 + next(&mut st)),
            base * (0.2 + next(&mut st)),
        ]);
        let q = [next(&mut st) - 0.5, next(&mut st) - 0.5, next(&mut st) - 0.5, next(&mut st) - 0.5];
        let len = q.iter().map(|v| v * v).sum::<f32>().sqrt();
        s.rotations.push(q.map(|v| v / len));
        s.opacities.push(max_opacity * next(&mut st));
        for k in 0..48 {
            let amp = if k < 3 { 2.0 } else { 0.4 };
            s.sh.push((next(&mut st) - 0.5) * amp);
        }
    }
    s
}

fn bits(img: &Image) -> Vec<[u32; 3]> {
    img.data.iter().map(|p| p.map(f32::to_bits)).collect()
}

#[test]
fn single_isotropic_gaussian_peak_and_falloff() {
    // 65x49 puts the principal point on the pixel centre (32, 24). Scale 0.04 at depth 2 with
    // f = 50 gives sigma = 1 px, so the 2D variance is 1 + 0.3 = 1.3.
    let cam = camera(65, 49, 50.0);
    let rgb = [0.9, 0.5, 0.2];
    let s = scene(&[G { pos: [0.0, 0.0, 2.0], scale: 0.04, opacity: 0.8, rgb }]);
    let p = preprocess(&s, &cam, 16);
    assert_eq!(p.len(), 1);
    let p = p[0];
    assert_eq!(p.mean2d, [32.0, 24.0]);
    assert!((p.cov2d[0] - 1.3).abs() < 1e-5 && (p.cov2d[2] - 1.3).abs() < 1e-5 && p.cov2d[1] == 0.0);
    assert!((p.conic[0] - 1.0 / 1.3).abs() < 1e-5);
    assert_eq!(p.depth, 2.0);
    // ceil(3 sqrt(1.3)) = ceil(3.42) = 4; tiles x: (32-4)/16 -> 1 .. (32+4+15)/16 -> 3,
    // y: (24-4)/16 -> 1 .. (24+4+15)/16 -> 2.
    assert_eq!(p.radius, 4);
    assert_eq!((p.tile_min, p.tile_max), ([1, 1], [3, 2]));
    assert!(close(p.rgb, rgb, 1e-6));

    let img = render(&s, &cam, &RenderOptions::default()).image;
    assert!(close(img.pixel(32, 24), rgb.map(|c| c * 0.8), 1e-6), "{:?}", img.pixel(32, 24));
    let one = 0.8 * (-0.5f32 / 1.3).exp();
    assert!(close(img.pixel(33, 24), rgb.map(|c| c * one), 1e-5));
    assert!(close(img.pixel(32, 23), rgb.map(|c| c * one), 1e-5));
    let diag = 0.8 * (-1.0f32 / 1.3).exp();
    assert!(close(img.pixel(31, 25), rgb.map(|c| c * diag), 1e-5));
    // Far away: nothing.
    assert_eq!(img.pixel(0, 0), [0.0; 3]);

    // An opaque Gaussian is capped at alpha 0.99.
    let s = scene(&[G { pos: [0.0, 0.0, 2.0], scale: 0.04, opacity: 1.0, rgb }]);
    let img = render(&s, &cam, &RenderOptions::default()).image;
    assert!(close(img.pixel(32, 24), rgb.map(|c| c * 0.99), 1e-6));
}

#[test]
fn gaussians_at_or_behind_the_near_limit_are_culled() {
    let cam = camera(65, 49, 50.0);
    let g = |z: f32| G { pos: [0.0, 0.0, z], scale: 0.001, opacity: 0.5, rgb: [1.0; 3] };
    let s = scene(&[g(NEAR_CULL), g(-1.0), g(0.25), g(0.0)]);
    let p = preprocess(&s, &cam, 16);
    assert_eq!(p.iter().map(|p| p.index).collect::<Vec<_>>(), vec![2]);
    let out = render(&s, &cam, &RenderOptions::default());
    assert_eq!(out.stats.visible, 1);
    assert!(out.image.pixel(32, 24)[0] > 0.0);
}

#[test]
fn opaque_stack_stops_below_min_transmittance() {
    // Five large Gaussians on the axis; listed back to front so that sorting matters.
    // Alpha 0.95 each: T = 1, 0.05, 0.0025, 0.000125, then 6.25e-6 < 1e-4 stops the pixel
    // before the fourth (red) layer; the fifth (blue) is never reached.
    let cam = camera(65, 49, 50.0);
    let g = |z: f32, rgb: [f32; 3]| G { pos: [0.0, 0.0, z], scale: 0.5 * z, opacity: 0.95, rgb };
    let s = scene(&[
        g(5.0, [0.0, 0.0, 1.0]),
        g(4.0, [1.0, 0.0, 0.0]),
        g(3.0, [1.0; 3]),
        g(2.0, [1.0; 3]),
        g(1.0, [1.0; 3]),
    ]);
    let c = render(&s, &cam, &RenderOptions::default()).image.pixel(32, 24);
    assert_eq!(c[0], c[1]);
    assert_eq!(c[1], c[2]);
    assert!((c[0] - 0.95 * (1.0 + 0.05 + 0.0025)).abs() < 1e-5, "{c:?}");
}

#[test]
fn alpha_below_one_over_255_is_skipped() {
    let cam = camera(65, 49, 50.0);
    let g = |opacity: f32| G { pos: [0.0, 0.0, 2.0], scale: 0.04, opacity, rgb: [1.0; 3] };
    let below = render(&scene(&[g(0.999 * MIN_ALPHA)]), &cam, &RenderOptions::default()).image;
    assert_eq!(below.pixel(32, 24), [0.0; 3]);
    let above = render(&scene(&[g(1.001 * MIN_ALPHA)]), &cam, &RenderOptions::default()).image;
    assert!(close(above.pixel(32, 24), [1.001 * MIN_ALPHA; 3], 1e-8));
    // One pixel off the centre the same Gaussian is below the threshold again.
    assert_eq!(above.pixel(33, 24), [0.0; 3]);
}

#[test]
fn equal_depths_are_ordered_by_gaussian_index() {
    let cam = camera(65, 49, 50.0);
    let red = G { pos: [0.0, 0.0, 2.0], scale: 0.04, opacity: 0.5, rgb: [1.0, 0.0, 0.0] };
    let green = G { pos: [0.0, 0.0, 2.0], scale: 0.04, opacity: 0.5, rgb: [0.0, 1.0, 0.0] };
    let blue = G { pos: [0.0, 0.0, 2.0], scale: 0.04, opacity: 0.5, rgb: [0.0, 0.0, 1.0] };
    let c = render(&scene(&[red, green, blue]), &cam, &RenderOptions::default()).image.pixel(32, 24);
    assert!(close(c, [0.5, 0.25, 0.125], 1e-6), "{c:?}");
}

/// The Gaussians of `s` with the given indices.
fn subset(s: &Scene, keep: &[usize]) -> Scene {
    let k = s.sh_per_gaussian();
    Scene {
        positions: keep.iter().map(|&i| s.positions[i]).collect(),
        scales: keep.iter().map(|&i| s.scales[i]).collect(),
        rotations: keep.iter().map(|&i| s.rotations[i]).collect(),
        opacities: keep.iter().map(|&i| s.opacities[i]).collect(),
        sh_degree: s.sh_degree,
        sh: keep.iter().flat_map(|&i| s.sh[i * k..(i + 1) * k].iter().copied()).collect(),
    }
}

#[test]
fn tile_size_only_matters_through_get_rect() {
    // getRect's `rect_max = (int)((p + r + B - 1) / B)` with a float `p` leaves out the tile
    // starting at pixel `tB` when `tB <= p + r < tB + 1`, although that pixel is within the
    // radius. Keeping Gaussians whose `p + r` avoids [tB, tB + 1) for every tile size tested
    // (8 divides 16 and 32), and opacities < 0.3 (so nothing beyond the 3-sigma square reaches
    // alpha 1/255), every tile size must give the same bits.
    let cam = camera(200, 150, 160.0);
    let all = random_scene(6000, 11, 0.3);
    let safe = |v: f32, r: u32| (v + r as f32).rem_euclid(8.0) >= 1.0;
    let keep: Vec<usize> = preprocess(&all, &cam, 16)
        .iter()
        .filter(|p| safe(p.mean2d[0], p.radius) && safe(p.mean2d[1], p.radius))
        .map(|p| p.index as usize)
        .collect();
    let s = subset(&all, &keep);
    let reference = render(&s, &cam, &RenderOptions { tile_size: 16 });
    assert!(reference.stats.visible > 1000, "{:?}", reference.stats);
    let lit = reference.image.data.iter().filter(|p| p[0] + p[1] + p[2] > 0.05).count();
    assert!(lit > 10_000, "scene too sparse to be a test: {lit} lit pixels");
    for tile_size in [8, 32] {
        let other = render(&s, &cam, &RenderOptions { tile_size });
        assert!(bits(&other.image) == bits(&reference.image), "tile size {tile_size} differs from 16");
        assert!(other.stats.pairs != reference.stats.pairs);
    }
    // The unfiltered scene does show the quirk (otherwise the filter above tests nothing).
    let a = render(&all, &cam, &RenderOptions { tile_size: 16 }).image;
    let b = render(&all, &cam, &RenderOptions { tile_size: 8 }).image;
    assert!(bits(&a) != bits(&b));
}

#[test]
fn thread_count_does_not_change_the_image() {
    let cam = camera(160, 120, 120.0);
    let s = random_scene(3000, 5, 1.0);
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
    let single = pool.install(|| render(&s, &cam, &RenderOptions::default()));
    let pool3 = rayon::ThreadPoolBuilder::new().num_threads(3).build().unwrap();
    let three = pool3.install(|| render(&s, &cam, &RenderOptions::default()));
    let default = render(&s, &cam, &RenderOptions::default());
    assert!(single.stats.visible > 1000);
    assert!(bits(&single.image) == bits(&default.image));
    assert!(bits(&three.image) == bits(&default.image));
    assert_eq!(single.stats.pairs, default.stats.pairs);
}

#[test]
fn blending_shortcuts_do_not_change_the_image() {
    // The straightforward loop: every pixel walks its whole tile list, `exp` always evaluated.
    for (seed, tile_size) in [(3u64, 16u32), (4, 8)] {
        let cam = camera(150, 100, 110.0);
        let s = random_scene(3000, seed, 1.0);
        let projected = preprocess(&s, &cam, tile_size);
        let grid = [cam.width.div_ceil(tile_size), cam.height.div_ceil(tile_size)];
        let bins = bin(&projected, grid);
        let mut naive = Image::new(cam.width, cam.height);
        for y in 0..cam.height {
            for x in 0..cam.width {
                let list: Vec<Splat> = bins
                    .tile(x / tile_size, y / tile_size)
                    .iter()
                    .map(|&j| Splat { power_cut: f32::NEG_INFINITY, ..Splat::from(&projected[j as usize]) })
                    .collect();
                naive.data[(y * cam.width + x) as usize] = blend_pixel(&list, x, y);
            }
        }
        let fast = render(&s, &cam, &RenderOptions { tile_size }).image;
        assert!(bits(&fast) == bits(&naive), "seed {seed}, tile size {tile_size}");
        assert!(naive.data.iter().filter(|p| p[1] > 0.1).count() > 5000);
    }
}
