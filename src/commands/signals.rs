//! `neo signals`: how well each per-tile disorder signal ranks the tiles by their error, from
//! `neo frames --tile-stats` runs (docs/adaptive.md section 1).

use anyhow::Result;
use clap::Args;
use neo_sim::signals::{correlation_row, read_tiles, Lag, Signal, Target};
use std::path::PathBuf;

/// Arguments of `neo signals`.
#[derive(Args)]
pub struct SignalsArgs {
    /// Output directories of `neo frames ... --tile-stats` (each holds a `tiles.jsonl`).
    #[arg(required = true)]
    pub dirs: Vec<PathBuf>,
}

/// Runs `neo signals`: one table row per run, signal lag (`same`: the frame's own; `next`: the
/// frame before, as the frame controller has it) and target (the tile's error, or its
/// inversions against the exact order).
pub fn run(a: SignalsArgs) -> Result<()> {
    let names: Vec<&str> = Signal::ALL.iter().map(|s| s.name()).collect();
    println!("| run | samples | target | {} |", names.join(" | "));
    println!("|---|---|---|{}", "---|".repeat(names.len()));
    for dir in &a.dirs {
        let frames = read_tiles(&dir.join("tiles.jsonl"))?;
        let refs: Vec<_> = frames.iter().collect();
        let run =
            dir.file_name().map_or_else(|| dir.display().to_string(), |n| n.to_string_lossy().into_owned());
        for (lag, lag_name) in [(Lag::Same, "same"), (Lag::Next, "next")] {
            for target in [Target::AbsError, Target::Inversions] {
                let (reach, rhos) = correlation_row(&refs, lag, target);
                let cells: Vec<String> =
                    rhos.iter().map(|r| r.map_or("-".into(), |r| format!("{r:.2}"))).collect();
                println!(
                    "| {run} ({lag_name}) | {} | {} | {} |",
                    reach.len(),
                    target.name(),
                    cells.join(" | ")
                );
            }
        }
    }
    Ok(())
}
