//! How well the per-tile disorder signals predict the per-tile error (issue 14,
//! docs/adaptive.md section 1): Spearman rank correlations over a run's tiles and frames, from
//! the golden pipeline's per-tile columns ([`TileColumns`]).
//!
//! A sample is one tile of one frame that has Gaussians, was not sorted from scratch, and is
//! not in a frame that starts a shot (every tile from scratch). Its target is the tile's
//! `abs_error` (the sum over its pixels and channels of |strategy - exact|). Its signal is taken
//! from the frame itself (`same`) or from the frame before (`next`: what the frame controller
//! has before it sorts; the first frame of the run has no `next` sample). The shares are always
//! the frame's own (the merge counts them as it runs).

use std::path::Path;

use neo_golden::pipeline::stats::TileColumns;
use serde::{Deserialize, Serialize};

use crate::file_error::LineError;

/// A per-tile disorder signal.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Signal {
    /// Valid entries that precede the previous valid entry in the write-back.
    WbDescents,
    /// Valid entries that precede the write-back's running maximum.
    WbBehind,
    /// The write-back's reach (how far the running maximum must move at least).
    WbReach,
    /// MSU+ boundary inversions of the reused stream.
    MergeInversions,
    /// Incoming entries over the current list.
    IncomingShare,
    /// Outgoing entries over the current list.
    OutgoingShare,
}

impl Signal {
    /// Every signal, in the order of the tables.
    pub const ALL: [Signal; 6] = [
        Signal::WbDescents,
        Signal::WbBehind,
        Signal::WbReach,
        Signal::MergeInversions,
        Signal::IncomingShare,
        Signal::OutgoingShare,
    ];

    /// The column name (as in `tiles.jsonl`, the shares derived).
    pub fn name(self) -> &'static str {
        match self {
            Signal::WbDescents => "wb_descents",
            Signal::WbBehind => "wb_behind",
            Signal::WbReach => "wb_reach",
            Signal::MergeInversions => "merge_inversions",
            Signal::IncomingShare => "incoming_share",
            Signal::OutgoingShare => "outgoing_share",
        }
    }

    /// True for the signals of the write-back, which the next frame's controller reads.
    fn is_write_back(self) -> bool {
        matches!(self, Signal::WbDescents | Signal::WbBehind | Signal::WbReach)
    }

    /// The signal of tile `i` in `cols`.
    pub fn value(self, cols: &TileColumns, i: usize) -> f64 {
        let share = |n: u32| n as f64 / cols.current[i].max(1) as f64;
        match self {
            Signal::WbDescents => cols.wb_descents[i] as f64,
            Signal::WbBehind => cols.wb_behind[i] as f64,
            Signal::WbReach => cols.wb_reach[i] as f64,
            Signal::MergeInversions => cols.merge_inversions[i] as f64,
            Signal::IncomingShare => share(cols.incoming[i]),
            Signal::OutgoingShare => share(cols.outgoing[i]),
        }
    }
}

/// Where a sample's signal comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Lag {
    /// The frame itself.
    Same,
    /// The frame before (the write-back signals; the others stay the frame's own).
    Next,
}

/// What a signal is to predict, per tile.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Target {
    /// The sum over the tile's pixels and channels of |strategy - exact|.
    AbsError,
    /// Inversions of the tile's order against the exact order.
    Inversions,
}

impl Target {
    /// The column name.
    pub fn name(self) -> &'static str {
        match self {
            Target::AbsError => "abs_error",
            Target::Inversions => "inversions",
        }
    }

    fn value(self, cols: &TileColumns, i: usize) -> f64 {
        match self {
            Target::AbsError => cols.abs_error[i] as f64,
            Target::Inversions => cols.inversions[i] as f64,
        }
    }
}

/// `(signal, error)` pairs of `signal` over a run's frames (in order).
pub fn samples(frames: &[&TileColumns], signal: Signal, lag: Lag) -> Vec<(f64, f64)> {
    samples_of(frames, signal, lag, Target::AbsError)
}

/// `(signal, target)` pairs of `signal` over a run's frames (in order). With [`Lag::Next`] a
/// frame's write-back signal comes from the frame numbered just before it; a frame after a gap
/// in the numbers (a `tiles.jsonl` of every K-th frame) has none.
pub fn samples_of(frames: &[&TileColumns], signal: Signal, lag: Lag, target: Target) -> Vec<(f64, f64)> {
    let mut out = Vec::new();
    for (k, f) in frames.iter().enumerate() {
        if f.from_scratch.iter().all(|&s| s == 1) {
            continue;
        }
        let src = match lag {
            Lag::Next if signal.is_write_back() => match k.checked_sub(1).map(|p| frames[p]) {
                Some(p) if p.frame + 1 == f.frame && p.current.len() == f.current.len() => p,
                _ => continue,
            },
            _ => f,
        };
        for i in 0..f.current.len() {
            if f.current[i] == 0 || f.from_scratch[i] == 1 {
                continue;
            }
            out.push((signal.value(src, i), target.value(f, i)));
        }
    }
    out
}

/// Ranks of `v` from 0, ties sharing their mean rank.
pub fn ranks(v: &[f64]) -> Vec<f64> {
    let mut order: Vec<usize> = (0..v.len()).collect();
    order.sort_by(|&a, &b| v[a].total_cmp(&v[b]));
    let mut r = vec![0.0; v.len()];
    let mut i = 0;
    while i < order.len() {
        let mut j = i;
        while j + 1 < order.len() && v[order[j + 1]] == v[order[i]] {
            j += 1;
        }
        for &o in &order[i..=j] {
            r[o] = (i + j) as f64 / 2.0;
        }
        i = j + 1;
    }
    r
}

/// Spearman's rank correlation of the pairs (`None` with fewer than 3 pairs or a constant side).
pub fn spearman(pairs: &[(f64, f64)]) -> Option<f64> {
    if pairs.len() < 3 {
        return None;
    }
    let rx = ranks(&pairs.iter().map(|p| p.0).collect::<Vec<_>>());
    let ry = ranks(&pairs.iter().map(|p| p.1).collect::<Vec<_>>());
    let n = rx.len() as f64;
    let (mx, my) = (rx.iter().sum::<f64>() / n, ry.iter().sum::<f64>() / n);
    let (mut sxy, mut sxx, mut syy) = (0.0, 0.0, 0.0);
    for (a, b) in rx.iter().zip(&ry) {
        sxy += (a - mx) * (b - my);
        sxx += (a - mx) * (a - mx);
        syy += (b - my) * (b - my);
    }
    (sxx > 0.0 && syy > 0.0).then(|| sxy / (sxx * syy).sqrt())
}

/// Most `(reach, error)` pairs a summary keeps for its scatter plot.
pub const MAX_SCATTER: usize = 2000;

/// At most `n` of `v`, evenly spaced (all of them when there are no more).
fn thin<T: Copy>(v: Vec<T>, n: usize) -> Vec<T> {
    if v.len() <= n {
        return v;
    }
    (0..n).map(|k| v[k * v.len() / n]).collect()
}

/// One row of the correlation table.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SignalCorrelation {
    /// The signal's column name.
    pub signal: String,
    /// Against the error of the same frame.
    pub same: Option<f64>,
    /// The frame before's signal against the error.
    pub next: Option<f64>,
}

/// The signals of one run against its per-tile error.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct SignalSummary {
    /// Samples (tiles of frames) of the `same` correlations.
    pub samples: usize,
    /// Tiles with an error above zero among them.
    pub with_error: usize,
    /// One row per signal of [`Signal::ALL`].
    pub correlations: Vec<SignalCorrelation>,
    /// `(previous frame's write-back reach, error)` of the `next` samples, for a scatter plot
    /// (at most [`MAX_SCATTER`], evenly spaced).
    pub reach_vs_error: Vec<(f64, f64)>,
}

/// One row of a correlation table: Spearman's rho of every signal of [`Signal::ALL`] against
/// `target` at `lag`, with the write-back reach's samples (the row's sample count).
pub fn correlation_row(
    frames: &[&TileColumns],
    lag: Lag,
    target: Target,
) -> (Vec<(f64, f64)>, Vec<Option<f64>>) {
    let mut reach = Vec::new();
    let rhos = Signal::ALL
        .iter()
        .map(|&s| {
            let pairs = samples_of(frames, s, lag, target);
            let rho = spearman(&pairs);
            if s == Signal::WbReach {
                reach = pairs;
            }
            rho
        })
        .collect();
    (reach, rhos)
}

impl SignalSummary {
    /// The summary of a run's frames; `None` without frames.
    pub fn of(frames: &[&TileColumns]) -> Option<Self> {
        if frames.is_empty() {
            return None;
        }
        let (same_reach, same) = correlation_row(frames, Lag::Same, Target::AbsError);
        let (next_reach, next) = correlation_row(frames, Lag::Next, Target::AbsError);
        let correlations = Signal::ALL
            .iter()
            .zip(same.into_iter().zip(next))
            .map(|(s, (same, next))| SignalCorrelation { signal: s.name().to_string(), same, next })
            .collect();
        Some(SignalSummary {
            samples: same_reach.len(),
            with_error: same_reach.iter().filter(|p| p.1 > 0.0).count(),
            correlations,
            reach_vs_error: thin(next_reach, MAX_SCATTER),
        })
    }

    /// The row of `signal`.
    pub fn get(&self, signal: Signal) -> Option<&SignalCorrelation> {
        self.correlations.iter().find(|c| c.signal == signal.name())
    }
}

/// Checks that every column of `cols` has one value per tile (`current`'s length) and that
/// the grid holds that many tiles.
fn check_columns(cols: &TileColumns) -> Result<(), String> {
    let n = cols.current.len();
    if cols.grid[0] as usize * cols.grid[1] as usize != n {
        return Err(format!("grid {}x{} but {n} tiles in `current`", cols.grid[0], cols.grid[1]));
    }
    let lens = [
        ("table_len", cols.table_len.len()),
        ("incoming", cols.incoming.len()),
        ("outgoing", cols.outgoing.len()),
        ("retained", cols.retained.len()),
        ("reused", cols.reused.len()),
        ("bitmap_popcount", cols.bitmap_popcount.len()),
        ("dps_chunks", cols.dps_chunks.len()),
        ("inversions", cols.inversions.len()),
        ("dps_passes", cols.dps_passes.len()),
        ("dps_wide", cols.dps_wide.len()),
        ("from_scratch", cols.from_scratch.len()),
        ("merge_inversions", cols.merge_inversions.len()),
        ("wb_descents", cols.wb_descents.len()),
        ("wb_behind", cols.wb_behind.len()),
        ("wb_reach", cols.wb_reach.len()),
        ("abs_error", cols.abs_error.len()),
    ];
    match lens.iter().find(|(_, l)| *l != n) {
        Some((name, l)) => Err(format!("column `{name}` has {l} values for {n} tiles")),
        None => Ok(()),
    }
}

/// The frames of a `tiles.jsonl` (one [`TileColumns`] per line, as `neo frames --tile-stats`
/// writes it; blank lines are skipped), in order.
pub fn parse_tiles(text: &str, path: &Path) -> Result<Vec<TileColumns>, LineError> {
    let err = |line: usize, message: String| LineError { path: path.to_path_buf(), line, message };
    let mut frames = Vec::new();
    for (i, l) in text.lines().enumerate() {
        if l.trim().is_empty() {
            continue;
        }
        let cols: TileColumns = serde_json::from_str(l).map_err(|e| err(i + 1, e.to_string()))?;
        check_columns(&cols).map_err(|m| err(i + 1, m))?;
        if let Some(prev) = frames.last() {
            let prev: &TileColumns = prev;
            if cols.grid != prev.grid || cols.frame <= prev.frame {
                return Err(err(
                    i + 1,
                    format!(
                        "frame {} (grid {:?}) after frame {} (grid {:?}): frames must ascend on one grid",
                        cols.frame, cols.grid, prev.frame, prev.grid
                    ),
                ));
            }
        }
        frames.push(cols);
    }
    if frames.is_empty() {
        return Err(err(0, "no frame".into()));
    }
    Ok(frames)
}

/// [`parse_tiles`] of the file at `path`.
pub fn read_tiles(path: &Path) -> Result<Vec<TileColumns>, LineError> {
    let text = std::fs::read_to_string(path).map_err(|e| LineError {
        path: path.to_path_buf(),
        line: 0,
        message: e.to_string(),
    })?;
    parse_tiles(&text, path)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cols(current: &[u32], reach: &[u32], error: &[u64], scratch: &[u8]) -> TileColumns {
        let n = current.len();
        TileColumns {
            current: current.to_vec(),
            incoming: vec![1; n],
            outgoing: vec![0; n],
            merge_inversions: reach.to_vec(),
            wb_descents: reach.to_vec(),
            wb_behind: reach.to_vec(),
            wb_reach: reach.to_vec(),
            abs_error: error.to_vec(),
            from_scratch: scratch.to_vec(),
            ..TileColumns::default()
        }
    }

    fn line(frame: usize, reach: &[u32]) -> String {
        let mut c = cols(&vec![5; reach.len()], reach, &vec![1; reach.len()], &vec![0; reach.len()]);
        let n = reach.len();
        c.frame = frame;
        c.grid = [n as u32, 1];
        for v in [&mut c.table_len, &mut c.retained, &mut c.reused, &mut c.bitmap_popcount, &mut c.dps_chunks]
        {
            *v = vec![0; n];
        }
        c.dps_passes = vec![1; n];
        c.inversions = vec![0; n];
        c.dps_wide = vec![0; n];
        serde_json::to_string(&c).unwrap()
    }

    #[test]
    fn tiles_files_parse_and_bad_ones_name_the_line_and_the_problem() {
        let p = Path::new("run/tiles.jsonl");
        let text = format!("{}\n\n{}\n", line(0, &[1, 2]), line(1, &[3, 4]));
        let frames = parse_tiles(&text, p).unwrap();
        assert_eq!((frames.len(), frames[1].wb_reach.clone()), (2, vec![3, 4]));
        let short = line(1, &[3, 4]).replace("\"wb_reach\":[3,4]", "\"wb_reach\":[3]");
        let e = parse_tiles(&format!("{}\n{short}\n", line(0, &[1, 2])), p).unwrap_err();
        assert_eq!((e.line, e.message.as_str()), (2, "column `wb_reach` has 1 values for 2 tiles"));
        assert_eq!(e.to_string(), "run/tiles.jsonl:2: column `wb_reach` has 1 values for 2 tiles");
        let e = parse_tiles(&format!("{}\n{}\n", line(1, &[1, 2]), line(1, &[3, 4])), p).unwrap_err();
        assert!(e.message.contains("frames must ascend"), "{e}");
        let e = parse_tiles(&format!("{}\n{}\n", line(0, &[1, 2]), line(1, &[3, 4, 5])), p).unwrap_err();
        assert!(e.message.contains("one grid"), "{e}");
        let e = parse_tiles("{\"frame\": 0}", p).unwrap_err();
        assert!(e.line == 1 && e.message.contains("missing field"), "{e}");
        assert_eq!(parse_tiles("\n", p).unwrap_err().to_string(), "run/tiles.jsonl: no frame");
        let e = read_tiles(Path::new("/nonexistent/tiles.jsonl")).unwrap_err();
        assert!(e.to_string().starts_with("/nonexistent/tiles.jsonl: "), "{e}");
    }

    proptest::proptest! {
        /// No input makes the parser panic: any text, and any valid file cut or with a byte
        /// changed, is either frames or an error naming a line.
        #[test]
        fn no_tiles_file_makes_the_parser_panic(
            junk in ".{0,200}",
            cut in 0usize..400,
            at in 0usize..400,
            byte in 0u8..128,
        ) {
            let p = Path::new("t.jsonl");
            let _ = parse_tiles(&junk, p);
            let good = format!("{}\n{}\n", line(0, &[1, 2, 3]), line(1, &[3, 4, 5]));
            let _ = parse_tiles(&good[..cut.min(good.len())], p);
            let mut bytes = good.into_bytes();
            let i = at % bytes.len();
            bytes[i] = byte;
            if let Ok(text) = String::from_utf8(bytes) {
                if let Ok(frames) = parse_tiles(&text, p) {
                    for f in &frames {
                        proptest::prop_assert!(check_columns(f).is_ok());
                    }
                    let refs: Vec<&TileColumns> = frames.iter().collect();
                    let _ = SignalSummary::of(&refs);
                }
            }
        }
    }

    #[test]
    fn thin_keeps_at_most_n_evenly_spaced() {
        assert_eq!(thin(vec![1, 2, 3], 5), vec![1, 2, 3]);
        assert_eq!(thin((0..10).collect(), 5), vec![0, 2, 4, 6, 8]);
        assert_eq!(thin((0..10_000).collect::<Vec<u32>>(), MAX_SCATTER).len(), MAX_SCATTER);
    }

    #[test]
    fn ranks_share_ties() {
        assert_eq!(ranks(&[3.0, 1.0, 3.0, 2.0]), vec![2.5, 0.0, 2.5, 1.0]);
        assert_eq!(ranks(&[]), Vec::<f64>::new());
    }

    #[test]
    fn spearman_of_monotone_and_reversed_pairs() {
        let up: Vec<(f64, f64)> = (0..10).map(|i| (i as f64, (i * i) as f64)).collect();
        assert!((spearman(&up).unwrap() - 1.0).abs() < 1e-12);
        let down: Vec<(f64, f64)> = (0..10).map(|i| (i as f64, -(i as f64).exp())).collect();
        assert!((spearman(&down).unwrap() + 1.0).abs() < 1e-12);
        assert_eq!(spearman(&[(1.0, 2.0), (2.0, 3.0)]), None, "too few pairs");
        assert_eq!(spearman(&[(1.0, 2.0), (1.0, 3.0), (1.0, 4.0)]), None, "a constant side");
        // A known value: ranks (1 2 3 4 5) against (2 1 4 3 5): 1 - 6 * 4 / (5 * 24) = 0.8.
        let p = [(1.0, 2.0), (2.0, 1.0), (3.0, 4.0), (4.0, 3.0), (5.0, 5.0)];
        assert!((spearman(&p).unwrap() - 0.8).abs() < 1e-12);
    }

    #[test]
    fn samples_skip_shot_starts_empty_and_fresh_tiles_and_lag_the_write_back() {
        let f0 = cols(&[5, 5, 5], &[1, 2, 3], &[0, 0, 0], &[1, 1, 1]);
        let f1 = TileColumns { frame: 1, ..cols(&[5, 0, 5], &[7, 8, 9], &[10, 20, 30], &[0, 0, 1]) };
        let f2 = TileColumns { frame: 2, ..cols(&[5, 5, 5], &[4, 5, 6], &[40, 50, 60], &[0, 0, 0]) };
        let frames = [&f0, &f1, &f2];
        // Frame 0 starts the shot; in frame 1 tile 1 is empty and tile 2 fresh.
        assert_eq!(
            samples(&frames, Signal::WbReach, Lag::Same),
            vec![(7.0, 10.0), (4.0, 40.0), (5.0, 50.0), (6.0, 60.0)]
        );
        assert_eq!(
            samples(&frames, Signal::WbReach, Lag::Next),
            vec![(1.0, 10.0), (7.0, 40.0), (8.0, 50.0), (9.0, 60.0)]
        );
        // The merge's counter is the frame's own either way.
        assert_eq!(
            samples(&frames, Signal::MergeInversions, Lag::Next),
            samples(&frames, Signal::MergeInversions, Lag::Same)
        );
        let s = SignalSummary::of(&frames).expect("frames");
        assert_eq!((s.samples, s.with_error), (4, 4));
        assert_eq!(s.reach_vs_error.len(), 4);
        assert!((s.get(Signal::WbReach).unwrap().next.unwrap() - 1.0).abs() < 1e-12);
        assert_eq!(SignalSummary::of(&[]), None);
    }

    /// The `next` lag pairs a frame only with the one numbered just before it (a file of frames
    /// 0, 1, 1000 and 1001 paired 1000 with 1).
    #[test]
    fn the_next_lag_pairs_only_consecutive_frames() {
        let frame = |n: usize, scratch: u8| TileColumns {
            frame: n,
            ..cols(&[5; 4], &[1, 2, 3, 4], &[1, 2, 3, 4], &[scratch; 4])
        };
        let frames = [frame(0, 1), frame(1, 0), frame(1000, 0), frame(1001, 0)];
        let refs: Vec<&TileColumns> = frames.iter().collect();
        // Same lag: every frame but the one sorted from scratch; next: 1 after 0 and 1001 after
        // 1000, not 1000 after 1.
        assert_eq!(samples(&refs, Signal::WbReach, Lag::Same).len(), 12);
        assert_eq!(samples(&refs, Signal::WbReach, Lag::Next).len(), 8);
        assert_eq!(samples(&refs[..2], Signal::WbReach, Lag::Next).len(), 4, "1 pairs with 0");
    }
}
