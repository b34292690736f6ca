//! `neo scene info`, `neo scene convert` and `neo scene bake`.

use crate::args::{refuse_overwriting_input, warn_dropped};
use crate::progress::spin;
use anyhow::{Context, Result};
use clap::{Args, Subcommand};
use neo_golden::formats::FeatureFormat;
use neo_golden::hwpre::bake::{geometry_bytes, sh_bytes, Baked};
use neo_golden::hwpre::ShPrecision;
use neo_golden::{ply, scene_stats::SceneStats, source};
use std::path::PathBuf;

/// Scene subcommands.
#[derive(Subcommand)]
pub enum SceneCommand {
    /// Count, SH degree, bounds and opacity/scale statistics.
    Info(InfoArgs),
    /// Write a scene (any readable form) as a standard binary 3DGS .ply.
    Convert(ConvertArgs),
    /// Bake a scene for the Preprocessing Engine (docs/formats.md, "Baked parameters").
    Bake(BakeArgs),
}

/// Arguments of `neo scene bake`.
#[derive(Args)]
pub struct BakeArgs {
    /// The input scene (file or synthetic spec).
    pub input: String,
    /// The baked file to write.
    pub output: PathBuf,
    /// SH storage: `f32` or `f16`.
    #[arg(long, default_value = "f32", value_parser = parse_sh)]
    pub sh: ShPrecision,
    /// Treat Gaussians with non-finite (NaN or infinite) values as an error instead of dropping
    /// them.
    #[arg(long)]
    pub strict: bool,
}

/// Parses an SH precision argument (`f32`, `f16`): `neo scene bake --sh`, `neo cosim --sh`.
pub fn parse_sh(s: &str) -> Result<ShPrecision, String> {
    match s {
        "f32" => Ok(ShPrecision::F32),
        "f16" => Ok(ShPrecision::F16),
        _ => Err(format!("unknown SH precision {s:?}: expected f32 or f16")),
    }
}

/// Arguments of `neo scene info`.
#[derive(Args)]
pub struct InfoArgs {
    /// A .ply (standard or compressed) or a `synthetic:NAME?gaussians=N&seed=S` spec.
    pub scene: String,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
    /// Treat Gaussians with non-finite (NaN or infinite) values as an error instead of dropping
    /// them.
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
    /// Treat Gaussians with non-finite (NaN or infinite) values as an error instead of dropping
    /// them.
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
            refuse_overwriting_input(&a.output, "OUTPUT", &[("INPUT", PathBuf::from(&a.input))])?;
            let (loaded, _) =
                spin(&format!("loading {}", a.input), || source::load_scene(&a.input, a.strict));
            let (scene, report) = loaded?;
            warn_dropped(&report);
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
        SceneCommand::Bake(a) => {
            refuse_overwriting_input(&a.output, "OUTPUT", &[("INPUT", PathBuf::from(&a.input))])?;
            let (loaded, _) =
                spin(&format!("loading {}", a.input), || source::load_scene(&a.input, a.strict));
            let (scene, report) = loaded?;
            warn_dropped(&report);
            let baked = Baked::from_scene(&scene, &FeatureFormat::default(), a.sh);
            baked.write(&a.output)?;
            println!(
                "wrote {} Gaussians (SH degree {}) to {}: {} bytes each ({} geometry + {} SH)",
                baked.len(),
                baked.sh_degree,
                a.output.display(),
                baked.bytes_per_gaussian(),
                geometry_bytes(),
                sh_bytes(baked.sh_degree, baked.sh_precision)
            );
            Ok(())
        }
    }
}
