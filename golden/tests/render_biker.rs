//! Acceptance test of the float reference renderer: rendering the real biker scene from each of
//! its four cameras must reach PSNR >= 40 dB against the independent reference renders in
//! `../shared/scenes/biker_ref_<name>.png`.

use glam::{DMat3, DVec3};
use neo_golden::camera::Camera;
use neo_golden::image::{Image, Rgb8Image};
use neo_golden::metrics::{psnr, ssim};
use neo_golden::render::{render, RenderOptions};
use neo_golden::scene::Scene;
use neo_golden::shared::shared_file_for_test;
use std::path::Path;

/// One entry of an INRIA `cameras.json`.
#[derive(serde::Deserialize)]
struct JsonCamera {
    img_name: String,
    width: u32,
    height: u32,
    position: [f64; 3],
    rotation: [[f64; 3]; 3],
    fx: f64,
    fy: f64,
}

/// Reads the cameras file directly (independently of `neo_golden::cameras_json`).
fn read_cameras(path: &Path) -> Vec<Camera> {
    let text = std::fs::read_to_string(path).unwrap();
    let cams: Vec<JsonCamera> = serde_json::from_str(&text).unwrap();
    cams.into_iter()
        .map(|c| Camera {
            name: c.img_name,
            width: c.width,
            height: c.height,
            fx: c.fx,
            fy: c.fy,
            position: DVec3::from_array(c.position),
            // `rotation` lists the rows of camera-to-world; glam takes columns.
            cam_to_world: DMat3::from_cols_array_2d(&c.rotation).transpose(),
        })
        .collect()
}

/// The 8-bit image with truncation instead of rounding (only to compare quantisation rules).
fn truncated(img: &Image) -> Rgb8Image {
    let data = img.data.iter().flat_map(|p| p.map(|v| (v.clamp(0.0, 1.0) * 255.0) as u8)).collect();
    Rgb8Image { width: img.width, height: img.height, data }
}

#[test]
fn biker_matches_the_reference_renders() {
    let test = "render_biker";
    let Some(ply) = shared_file_for_test(test, "scenes/biker.ply") else { return };
    let Some(cams_path) = shared_file_for_test(test, "scenes/biker_cameras.json") else { return };
    let raw = neo_golden::ply::read_raw(&ply).unwrap();
    let (scene, _) = Scene::from_raw(&raw, &ply, false).unwrap();
    let cams = read_cameras(&cams_path);
    assert_eq!(cams.len(), 4);
    // Convention check: the front camera at (0, -1.6, -5) looks toward +z and the left camera
    // at (-5, -1.6, 0) toward +x.
    assert!(cams[0].forward().z > 0.99, "{:?}", cams[0].forward());
    assert!(cams[1].forward().x > 0.99, "{:?}", cams[1].forward());
    let mut failures = Vec::new();
    for cam in &cams {
        let rel = format!("scenes/biker_ref_{}.png", cam.name);
        let Some(ref_path) = shared_file_for_test(test, &rel) else { return };
        let reference = Rgb8Image::read_png(&ref_path).unwrap();
        let out = render(&scene, cam, &RenderOptions::default());
        let ours = out.image.to_rgb8();
        let p = psnr(&ours, &reference).unwrap();
        let s = ssim(&ours, &reference).unwrap();
        let p_trunc = psnr(&truncated(&out.image), &reference).unwrap();
        println!(
            "{:>14}: PSNR {p:.2} dB (truncating: {p_trunc:.2} dB), SSIM {s:.6}, visible {}, pairs {}",
            cam.name, out.stats.visible, out.stats.pairs
        );
        // Rounding is the documented quantisation rule: it must fit the reference better.
        assert!(p >= p_trunc, "{}: truncation fits the reference better ({p_trunc} > {p})", cam.name);
        if p < 40.0 {
            failures.push(format!("{}: PSNR {p:.2} dB < 40 dB", cam.name));
        }
    }
    assert!(failures.is_empty(), "{failures:?}");
}
