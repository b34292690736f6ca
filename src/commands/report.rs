//! `neo report`: the README's main job. For now: statistics and a render of the default scene.

use super::view::ViewArgs;
use crate::progress::spin;
use anyhow::{Context, Result};
use clap::Args;
use neo_golden::{render, scene_stats::SceneStats, source, synthetic};
use std::path::PathBuf;

/// Arguments of `neo report`.
#[derive(Args)]
pub struct ReportArgs {
    /// The scene to report on (file or synthetic spec).
    #[arg(long, default_value = synthetic::DEFAULT_SCENE)]
    pub scene: String,
    #[command(flatten)]
    pub view: ViewArgs,
    /// Output directory.
    #[arg(long, default_value = "out/report")]
    pub out: PathBuf,
}

/// Runs `neo report`.
pub fn run(mut a: ReportArgs) -> Result<()> {
    std::fs::create_dir_all(&a.out).with_context(|| format!("creating {}", a.out.display()))?;
    let (loaded, t_load) = spin(&format!("loading {}", a.scene), || source::load_scene(&a.scene, false));
    let (scene, report) = loaded?;
    println!("scene: {} (loaded in {:.2} s)", a.scene, t_load.as_secs_f64());
    println!("{}", SceneStats::of(&scene, &report));

    if a.view.camera.is_none() && a.view.width.is_none() && a.view.height.is_none() {
        a.view.width = Some(1280);
        a.view.height = Some(720);
    }
    let cam = a.view.camera(&scene)?;
    let (out, t_render) =
        spin("rendering", || render::render(&scene, &cam, &render::RenderOptions::default()));
    let png = a.out.join("render.png");
    out.image.to_rgb8().write_png(&png)?;
    println!(
        "render: {}x{}, {} visible Gaussians, {} tile pairs, {:.3} s ({}) -> {}",
        cam.width,
        cam.height,
        out.stats.visible,
        out.stats.pairs,
        t_render.as_secs_f64(),
        out.stats.timing_summary(),
        png.display()
    );
    Ok(())
}
