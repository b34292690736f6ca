//! `neo compare`: PSNR and SSIM between two PNG images.

use anyhow::Result;
use clap::Args;
use neo_golden::{image::Rgb8Image, metrics};
use std::path::PathBuf;

/// Arguments of `neo compare`.
#[derive(Args)]
pub struct CompareArgs {
    /// First image (PNG).
    pub a: PathBuf,
    /// Second image (PNG), same size.
    pub b: PathBuf,
    /// Print JSON instead of text.
    #[arg(long)]
    pub json: bool,
}

/// Runs `neo compare`.
pub fn run(a: CompareArgs) -> Result<()> {
    let ia = Rgb8Image::read_png(&a.a)?;
    let ib = Rgb8Image::read_png(&a.b)?;
    let psnr = metrics::psnr(&ia, &ib)?;
    let ssim = metrics::ssim(&ia, &ib)?;
    if a.json {
        // JSON has no infinity: identical images report psnr as null.
        let psnr_json = if psnr.is_finite() { serde_json::json!(psnr) } else { serde_json::Value::Null };
        println!("{}", serde_json::json!({ "psnr": psnr_json, "ssim": ssim }));
    } else {
        println!("PSNR {psnr:.3} dB");
        println!("SSIM {ssim:.5}");
    }
    Ok(())
}
