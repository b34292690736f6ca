//! The error each width costs: PSNR of the fixed-point frame against the float reference when
//! one width is lowered and everything else is wide (and the depth key is 32 bits, so ordering
//! is not the limit). Slow (a minute); run by hand and copy the table into docs/formats.md:
//!
//! ```text
//! cargo test --release -p neo-golden --test raster_width_sweep -- --ignored --nocapture
//! ```

mod raster_common;

use neo_golden::formats::{BlendFormat, ConicFormat, Cutoff, ExpFormat, FeatureFormat, QFormat};
use neo_golden::image::Rgb8Image;
use neo_golden::metrics::psnr;
use neo_golden::raster::RasterConfig;
use neo_golden::render::{preprocess, render, Projected, RenderOptions};
use neo_golden::sort::DepthKeyCodec;

struct Case {
    name: String,
    projected: Vec<Projected>,
    reference: Rgb8Image,
    width: u32,
    height: u32,
}

fn case(name: &str, scene: &neo_golden::scene::Scene, cam: &neo_golden::camera::Camera) -> Case {
    Case {
        name: name.to_string(),
        projected: preprocess(scene, cam, 16),
        reference: render(scene, cam, &RenderOptions::default()).image.to_rgb8(),
        width: cam.width,
        height: cam.height,
    }
}

/// Every width far above what it costs: the baseline of the sweep.
fn wide() -> (FeatureFormat, RasterConfig) {
    let d = FeatureFormat::default();
    let f = FeatureFormat {
        mean: QFormat::signed(30, 12),
        conic: ConicFormat { mantissa_bits: 28, ..d.conic },
        opacity: QFormat::unsigned(14, 14),
        color: QFormat::unsigned(15, 14),
        axis: QFormat::signed(14, 12),
        depth_key_bits: 32,
        ..d
    };
    let blend = BlendFormat {
        power_frac: 16,
        alpha_frac: 18,
        transmittance_frac: 26,
        exp: ExpFormat { table_bits: 8, interp_bits: 8, out_frac: 22, log2e_frac: 20 },
        ..BlendFormat::default()
    };
    let c = RasterConfig { blend, ..RasterConfig::default() };
    (f, c)
}

#[test]
#[ignore = "slow measurement; run by hand (see the module doc)"]
fn psnr_per_width() {
    let mut cases = Vec::new();
    if let Some((scene, cams)) = raster_common::biker("raster_width_sweep") {
        cases.push(case("biker front", &scene, &cams[0]));
        cases.push(case("biker close 960", &scene, &cams[3].with_resolution(960, 720)));
    }
    let (scene, cam) = raster_common::outdoor(1_000_000, 1, 2560, 1440, "orbit");
    cases.push(case("outdoor 1M QHD", &scene, &cam));
    let (scene, cam) = raster_common::outdoor(1_000_000, 1, 1280, 720, "walk");
    cases.push(case("outdoor walk HD", &scene, &cam));

    let key16 = DepthKeyCodec::Fp16;
    let key32 = DepthKeyCodec::log(32, 0.05, 2e4).unwrap();
    let row = |label: &str, f: &FeatureFormat, c: &RasterConfig| {
        let key = if f.depth_key_bits == 32 { &key32 } else { &key16 };
        let mut s = format!("| {label:<34} |");
        for k in &cases {
            let (img, _) = raster_common::render_fixed(&k.projected, f, key, c, k.width, k.height);
            s += &format!(" {:>6.2} |", psnr(&img, &k.reference).unwrap());
        }
        println!("{s}");
    };
    let mut hdr = format!("| {:<34} |", "configuration (PSNR dB vs float)");
    for k in &cases {
        hdr += &format!(" {} |", k.name);
    }
    println!("{hdr}");
    let (wf, wc) = wide();
    let df = FeatureFormat::default();
    let dc = RasterConfig::default();
    row("default (FP16 key)", &df, &dc);
    row("default, 32-bit key", &FeatureFormat { depth_key_bits: 32, ..df }, &dc);
    row(
        "default, 32-bit key, Sigma(3)",
        &FeatureFormat { depth_key_bits: 32, cutoff: Cutoff::Sigma(3.0), ..df },
        &dc,
    );
    row("wide (32-bit key)", &wf, &wc);
    row("wide, FP16 key", &FeatureFormat { depth_key_bits: 16, ..wf }, &wc);
    row("wide, Sigma(3)", &FeatureFormat { cutoff: Cutoff::Sigma(3.0), ..wf }, &wc);
    for fm in [2u8, 4, 6, 8] {
        row(&format!("mean.frac = {fm}"), &FeatureFormat { mean: QFormat::signed(18 + fm, fm), ..wf }, &wc);
    }
    for m in [8u8, 10, 12, 14, 16, 18, 20] {
        let mut f = wf;
        f.conic.mantissa_bits = m;
        row(&format!("conic.mantissa_bits = {m}"), &f, &wc);
    }
    for o in [7u8, 8, 10] {
        row(&format!("opacity bits = {o}"), &FeatureFormat { opacity: QFormat::unsigned(o, o), ..wf }, &wc);
    }
    for cf in [6u8, 8, 10, 12] {
        row(
            &format!("color.frac = {cf}"),
            &FeatureFormat { color: QFormat::unsigned(cf + 1, cf), ..wf },
            &wc,
        );
    }
    for p in [6u8, 8, 10, 12] {
        let mut c = wc;
        c.blend.power_frac = p;
        row(&format!("power_frac = {p}"), &wf, &c);
    }
    for a in [8u8, 10, 12, 14, 16] {
        let mut c = wc;
        c.blend.alpha_frac = a;
        row(&format!("alpha_frac = {a}"), &wf, &c);
    }
    for t in [14u8, 16, 18, 20] {
        let mut c = wc;
        c.blend.transmittance_frac = t;
        row(&format!("transmittance_frac = {t}"), &wf, &c);
    }
    for (tb, ib) in [(4u8, 0u8), (6, 0), (8, 0), (4, 8), (5, 6), (5, 8)] {
        let mut c = wc;
        c.blend.exp = ExpFormat { table_bits: tb, interp_bits: ib, out_frac: 16, log2e_frac: 14 };
        row(&format!("exp table_bits = {tb}, interp_bits = {ib}"), &wf, &c);
    }
}
