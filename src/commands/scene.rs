//! `neo scene info` and `neo scene convert`.

use crate::progress::spin;
use anyhow::{Context, Result};
use clap::{Args, Subcommand};
use neo_golden::{ply, scene_stats::SceneStats, source};
use std::path::PathBuf;

/// Scene subcommands.
#[derive(Subcommand)]
pub enum SceneCommand {
    /// Count, SH degree, bounds and opacity/scale statistics.
    Info(InfoArgs),
    /// Write a scene (any readable form) as a standard binary 3DGS .ply.
    Convert(ConvertArgs),
}

/// Arguments of `neo scene info`.
#[derive(Args)]
pub struct InfoArgs {
    /// A .ply (standard or compressed) or a `synthetic:NAME?gaussians=N&seed=S` spec.
    pub scene: String,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
    /// Treat Gaussians with NaN values as an error instead of dropping them.
    #[arg(long)]
    pub strict: bool,
}

/// Arguments of `neo scene convert`.
#[derive(Args)]
pub struct ConvertArgs {
    /// The input scene (file or synthetic spec).
    pub input: String,
    /// The standard-layout .ply to write.
    pub output: PathBuf,
    /// Treat Gaussians with NaN values as an error instead of dropping them.
    #[arg(long)]
    pub strict: bool,
}

/// Runs a scene subcommand.
pub fn run(cmd: SceneCommand) -> Result<()> {
    match cmd {
        SceneCommand::Info(a) => {
            let (loaded, _) =
                spin(&format!("loading {}", a.scene), || source::load_scene(&a.scene, a.strict));
            let (scene, report) = loaded?;
            let stats = SceneStats::of(&scene, &report);
            if a.json {
                println!("{}", serde_json::to_string_pretty(&stats)?);
            } else {
                println!("scene: {}", a.scene);
                println!("{stats}");
            }
            Ok(())
        }
        SceneCommand::Convert(a) => {
            let (loaded, _) =
                spin(&format!("loading {}", a.input), || source::load_scene(&a.input, a.strict));
            let (scene, report) = loaded?;
            if report.dropped_non_finite > 0 {
                eprintln!("warning: dropped {} Gaussians with NaN values", report.dropped_non_finite);
            }
            ply::write_standard(&a.output, &scene.to_raw())
                .with_context(|| format!("converting {}", a.input))?;
            println!(
                "wrote {} Gaussians (SH degree {}) to {}",
                scene.len(),
                scene.sh_degree,
                a.output.display()
            );
            Ok(())
        }
    }
}
