//! `neo signals`: how well each per-tile disorder signal ranks the tiles by their error, from
//! `neo frames --tile-stats` runs (docs/adaptive.md section 1).

use anyhow::Result;
use clap::Args;
use neo_golden::pipeline::TileColumns;
use neo_sim::signals::{read_tiles, samples_of, spearman, Lag, Signal, Target};
use std::path::PathBuf;

/// Arguments of `neo signals`.
#[derive(Args)]
pub struct SignalsArgs {
    /// Output directories of `neo frames ... --tile-stats` (each holds a `tiles.jsonl`).
    #[arg(required = true)]
    pub dirs: Vec<PathBuf>,
}

/// The runs of consecutive frame numbers of `frames` (which ascend, as [`read_tiles`] checks):
/// a signal of the frame before pairs with a frame only within one.
fn consecutive_runs(frames: &[TileColumns]) -> Vec<Vec<&TileColumns>> {
    let mut runs: Vec<Vec<&TileColumns>> = Vec::new();
    for f in frames {
        match runs.last_mut() {
            Some(run) if run.last().is_some_and(|p| p.frame + 1 == f.frame) => run.push(f),
            _ => runs.push(vec![f]),
        }
    }
    runs
}

/// The frame-number gaps of `frames` (`(before, after)`), for the note that `next` skips them.
fn gaps(frames: &[TileColumns]) -> Vec<(usize, usize)> {
    frames.windows(2).filter(|w| w[0].frame + 1 != w[1].frame).map(|w| (w[0].frame, w[1].frame)).collect()
}

/// [`neo_sim::signals::correlation_row`] over `runs` of consecutive frames: each run's samples (so `next` pairs a
/// frame only with the one numbered just before it), ranked together.
fn row(runs: &[Vec<&TileColumns>], lag: Lag, target: Target) -> (usize, Vec<Option<f64>>) {
    let rhos = Signal::ALL
        .iter()
        .map(|&s| spearman(&runs.iter().flat_map(|r| samples_of(r, s, lag, target)).collect::<Vec<_>>()))
        .collect();
    let reach = runs.iter().map(|r| samples_of(r, Signal::WbReach, lag, target).len()).sum();
    (reach, rhos)
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
        let consecutive = consecutive_runs(frames);
        let run =
            dir.file_name().map_or_else(|| dir.display().to_string(), |n| n.to_string_lossy().into_owned());
        for (lag, lag_name) in [(Lag::Same, "same"), (Lag::Next, "next")] {
            for target in [Target::AbsError, Target::Inversions] {
                let (samples, rhos) = row(&consecutive, lag, target);
                let cells: Vec<String> =
                    rhos.iter().map(|r| r.map_or("-".into(), |r| format!("{r:.2}"))).collect();
                println!("| {run} ({lag_name}) | {samples} | {} | {} |", target.name(), cells.join(" | "));
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(frame: usize, scratch: u8) -> TileColumns {
        let n = 4;
        TileColumns {
            frame,
            grid: [n as u32, 1],
            current: vec![5; n],
            incoming: vec![1; n],
            outgoing: vec![0; n],
            wb_descents: vec![1, 2, 3, 4],
            wb_behind: vec![1, 2, 3, 4],
            wb_reach: vec![1, 2, 3, 4],
            merge_inversions: vec![1, 2, 3, 4],
            abs_error: vec![1, 2, 3, 4],
            inversions: vec![0; n],
            from_scratch: vec![scratch; n],
            ..TileColumns::default()
        }
    }

    /// The `next` lag pairs a frame only with the one numbered just before it.
    #[test]
    fn the_next_lag_pairs_only_consecutive_frames() {
        let frames = vec![frame(0, 1), frame(1, 0), frame(1000, 0), frame(1001, 0)];
        assert_eq!(gaps(&frames), [(1, 1000)]);
        let runs = consecutive_runs(&frames);
        assert_eq!(
            runs.iter().map(|r| r.iter().map(|f| f.frame).collect()).collect::<Vec<Vec<_>>>(),
            [vec![0, 1], vec![1000, 1001]]
        );
        // Same lag: every frame but the one sorted from scratch; next: 1 after 0 and 1001 after
        // 1000, not 1000 after 1.
        assert_eq!(row(&runs, Lag::Same, Target::AbsError).0, 12);
        assert_eq!(row(&runs, Lag::Next, Target::AbsError).0, 8);
        let whole = [frames.iter().collect::<Vec<_>>()];
        assert_eq!(row(&whole, Lag::Next, Target::AbsError).0, 12, "without the split, 1 pairs with 1000");
    }
}
