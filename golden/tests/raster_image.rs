//! Whole-image check of the fixed-point rasterizer: every 64x64 tile rendered with
//! `raster_tile` from tables sorted exactly by (depth key, id) must be within the documented
//! PSNR of the float reference renderer (docs/formats.md), at default widths.
//!
//! With the FP16 depth key the residual is dominated by the key's ordering (ties and inversions
//! of Gaussians closer than 2^-11 in relative depth); with a 32-bit key the widths alone cost
//! far less, which the second bound checks.

mod raster_common;

use neo_golden::camera::Camera;
use neo_golden::formats::FeatureFormat;
use neo_golden::metrics::psnr;
use neo_golden::raster::RasterConfig;
use neo_golden::render::{preprocess, render, RenderOptions};
use neo_golden::scene::Scene;
use neo_golden::sort::DepthKeyCodec;

/// PSNR of the fixed-point frame against the float reference, with the FP16 key and with a
/// 32-bit log key fitted to the frame's depths.
fn psnrs(scene: &Scene, cam: &Camera) -> (f64, f64) {
    let reference = render(scene, cam, &RenderOptions::default()).image.to_rgb8();
    let projected = preprocess(scene, cam, 16);
    let cfg = RasterConfig::default();
    let fmt = FeatureFormat::default();
    let (img, tot) =
        raster_common::render_fixed(&projected, &fmt, &DepthKeyCodec::Fp16, &cfg, cam.width, cam.height);
    let p16 = psnr(&img, &reference).unwrap();
    let key32 = DepthKeyCodec::fit(projected.iter().map(|p| p.depth), 32).unwrap();
    let fmt32 = FeatureFormat { depth_key_bits: 32, ..fmt };
    let (img32, _) = raster_common::render_fixed(&projected, &fmt32, &key32, &cfg, cam.width, cam.height);
    let p32 = psnr(&img32, &reference).unwrap();
    println!(
        "{} {}x{}: PSNR {p16:.2} dB (FP16 key), {p32:.2} dB (32-bit key); {} Gaussians, {} tile pairs, \
         {} subtile pairs, {} pixel evaluations, {} subtiles terminated early",
        cam.name,
        cam.width,
        cam.height,
        projected.len(),
        tot.pairs,
        tot.routed,
        tot.pixel_evals,
        tot.terminated
    );
    (p16, p32)
}

#[test]
fn random_scene_matches_the_float_renderer() {
    let (scene, cam) = raster_common::outdoor(200_000, 7, 1280, 720, "orbit");
    let (p16, p32) = psnrs(&scene, &cam);
    assert!(p16 >= 40.0, "PSNR {p16:.2} dB with the FP16 key");
    assert!(p32 >= 55.0, "PSNR {p32:.2} dB with a 32-bit key");
    // A close-up walk through the same scene: huge, smooth, near Gaussians.
    let (scene, cam) = raster_common::outdoor(200_000, 7, 640, 360, "walk");
    let (p16, p32) = psnrs(&scene, &cam);
    assert!(p16 >= 40.0 && p32 >= 55.0, "walk: {p16:.2} / {p32:.2} dB");
}

#[test]
fn biker_matches_the_float_renderer() {
    let Some((scene, cams)) = raster_common::biker("raster_image_biker") else { return };
    let mut all = cams.clone();
    all.push(cams[3].with_resolution(960, 720));
    for cam in &all {
        let (p16, p32) = psnrs(&scene, cam);
        assert!(p16 >= 40.0, "{}: PSNR {p16:.2} dB with the FP16 key", cam.name);
        assert!(p32 >= 55.0, "{}: PSNR {p32:.2} dB with a 32-bit key", cam.name);
    }
}
