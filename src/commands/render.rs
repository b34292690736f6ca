//! `neo render`: one view through the float reference renderer, written as an 8-bit PNG.

use crate::args::{refuse_overwriting_input, spec_paths, warn_dropped, SceneArg, StrictArg, ViewArgs};
use crate::progress::spin;
use anyhow::Result;
use clap::Args;
use neo_golden::{render, source};
use std::path::PathBuf;

/// Arguments of `neo render`.
#[derive(Args)]
pub struct RenderArgs {
    #[command(flatten)]
    pub scene: SceneArg,
    #[command(flatten)]
    pub view: ViewArgs,
    /// The PNG to write.
    #[arg(long)]
    pub out: PathBuf,
    #[command(flatten)]
    pub strict: StrictArg,
}

/// Runs `neo render`.
pub fn run(a: RenderArgs) -> Result<()> {
    let mut inputs: Vec<(&str, PathBuf)> =
        spec_paths(&a.scene.scene).into_iter().map(|p| ("the --scene file", p)).collect();
    inputs.extend(a.view.input_paths());
    refuse_overwriting_input(&a.out, "--out", &inputs)?;
    let (loaded, t_load) =
        spin(&format!("loading {}", a.scene.scene), || source::load_scene(&a.scene.scene, a.strict.strict));
    let (scene, report) = loaded?;
    warn_dropped(&report);
    let cam = a.view.camera(&scene)?;
    let opts = render::RenderOptions::default();
    let (out, t_render) = spin("rendering", || render::render(&scene, &cam, &opts));
    out.image.to_rgb8().write_png(&a.out)?;
    println!(
        "rendered {} Gaussians ({} visible, {} tile pairs) at {}x{} in {:.3} s (load {:.3} s) -> {}",
        scene.len(),
        out.stats.visible,
        out.stats.pairs,
        cam.width,
        cam.height,
        t_render.as_secs_f64(),
        t_load.as_secs_f64(),
        a.out.display()
    );
    Ok(())
}
