//! `neo signals`: how well each per-tile disorder signal ranks the tiles by their error, from
//! `neo frames --tile-stats` runs (docs/adaptive.md section 1).

use anyhow::Result;
use clap::Args;
use neo_golden::pipeline::TileColumns;
use neo_sim::signals::{correlation_row, read_tiles, Lag, Signal, Target};
use std::path::PathBuf;

/// Arguments of `neo signals`.
#[derive(Args)]
pub struct SignalsArgs {
    /// Output directories of `neo frames ... --tile-stats` (each holds a `tiles.jsonl`).
    #[arg(required = true)]
    pub dirs: Vec<PathBuf>,
}

/// The frame-number gaps of `frames` (`(before, after)`), for the note that `next` skips them.
fn gaps(frames: &[TileColumns]) -> Vec<(usize, usize)> {
    frames.windows(2).filter(|w| w[0].frame + 1 != w[1].frame).map(|w| (w[0].frame, w[1].frame)).collect()
}

/// Runs `neo signals`: one table row per run, signal lag (`same`: the frame's own; `next`: the
/// frame before, as the frame controller has it; only a frame numbered one before pairs, so a
/// file with a gap in its frame numbers is noted and the gap skipped) and target (the tile's
/// error, or its inversions against the exact order). Every directory is read before anything
/// is printed.
pub fn run(a: SignalsArgs) -> Result<()> {
    let mut runs = Vec::with_capacity(a.dirs.len());
    for dir in &a.dirs {
        let path = dir.join("tiles.jsonl");
        let frames = read_tiles(&path)?;
        for (before, after) in gaps(&frames) {
            eprintln!(
                "note: {}: frame {after} follows frame {before}: the `next` lag does not pair them",
                path.display()
            );
        }
        runs.push((dir, frames));
    }
    let names: Vec<&str> = Signal::ALL.iter().map(|s| s.name()).collect();
    println!("| run | samples | target | {} |", names.join(" | "));
    println!("|---|---|---|{}", "---|".repeat(names.len()));
    for (dir, frames) in &runs {
        let refs: Vec<&TileColumns> = frames.iter().collect();
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
