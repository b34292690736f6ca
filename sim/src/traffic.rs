//! DRAM traffic accounting: every request is one whole line (64 bytes by default), attributed
//! to a pipeline stage and a direction. A partial line costs a whole line; nothing is lost:
//! `bytes == requests * line_bytes` for every cell.

use serde::{Deserialize, Serialize};
use std::fmt;

/// Pipeline stages that touch DRAM.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
pub enum Stage {
    /// Gaussian parameters read by preprocessing.
    Preprocess,
    /// Preprocessing's incoming detection (the duplication unit, paper Section 5.2): on a frame
    /// that reuses tables, the previous feature word of each visible Gaussian read
    /// (`neo_golden::hwpre::duplicate`, `neo_golden::engine::pre::pre_transfers`).
    IncomingDetection,
    /// The feature table: written by preprocessing (Neo: every Gaussian's word), read
    /// (gathered) by the raster.
    FeatureTable,
    /// Incoming (or, from scratch, all binned) lists: written by duplication, read by sorting.
    IncomingList,
    /// Sorted tables and sort temporaries: DPS, MSU+ merges, conventional-sort runs, hierarchical
    /// passes.
    SortTable,
    /// The sorted table read by the raster.
    RasterTable,
    /// Depth keys and valid bits written back into the table after the raster.
    DepthWriteback,
    /// The frame buffer.
    FrameBuffer,
    /// A background sorter's lists and sorts (`background:K`).
    BackgroundSort,
}

impl Stage {
    /// Number of stages.
    pub const COUNT: usize = 9;

    /// All stages in report order.
    pub const ALL: [Stage; Stage::COUNT] = [
        Stage::Preprocess,
        Stage::IncomingDetection,
        Stage::FeatureTable,
        Stage::IncomingList,
        Stage::SortTable,
        Stage::RasterTable,
        Stage::DepthWriteback,
        Stage::FrameBuffer,
        Stage::BackgroundSort,
    ];

    /// Short name for tables.
    pub fn name(self) -> &'static str {
        match self {
            Stage::Preprocess => "preprocess",
            Stage::IncomingDetection => "incoming detection",
            Stage::FeatureTable => "feature table",
            Stage::IncomingList => "incoming lists",
            Stage::SortTable => "sort tables",
            Stage::RasterTable => "raster table read",
            Stage::DepthWriteback => "depth write-back",
            Stage::FrameBuffer => "frame buffer",
            Stage::BackgroundSort => "background sort",
        }
    }

    /// One word for narrow column headers.
    pub fn short_name(self) -> &'static str {
        match self {
            Stage::Preprocess => "preprocess",
            Stage::IncomingDetection => "detection",
            Stage::FeatureTable => "feature",
            Stage::IncomingList => "incoming",
            Stage::SortTable => "sort",
            Stage::RasterTable => "raster",
            Stage::DepthWriteback => "depth",
            Stage::FrameBuffer => "frame",
            Stage::BackgroundSort => "background",
        }
    }

    /// True for the stages the paper counts as sorting (Fig. 5's "sorting" share).
    pub fn is_sorting(self) -> bool {
        matches!(self, Stage::IncomingList | Stage::SortTable | Stage::BackgroundSort)
    }

    fn index(self) -> usize {
        self as usize
    }
}

impl fmt::Display for Stage {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Read or write.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize)]
pub enum Dir {
    /// DRAM to chip.
    Read,
    /// Chip to DRAM.
    Write,
}

/// Requests and bytes per stage and direction.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Traffic {
    /// Line size the bytes were counted with.
    pub line_bytes: u64,
    /// `[stage][0 = read, 1 = write]` requests.
    pub requests: [[u64; 2]; Stage::COUNT],
}

impl Traffic {
    /// Empty accounting for `line_bytes` lines.
    pub fn new(line_bytes: u64) -> Self {
        Traffic { line_bytes, requests: [[0; 2]; Stage::COUNT] }
    }

    /// Counts `n` requests.
    #[inline]
    pub fn add(&mut self, stage: Stage, dir: Dir, n: u64) {
        self.requests[stage.index()][dir as usize] += n;
    }

    /// Adds `o` (same line size).
    pub fn merge(&mut self, o: &Traffic) {
        if self.line_bytes == 0 {
            self.line_bytes = o.line_bytes;
        }
        debug_assert!(o.line_bytes == self.line_bytes || o.total_requests() == 0);
        for s in 0..Stage::COUNT {
            for d in 0..2 {
                self.requests[s][d] += o.requests[s][d];
            }
        }
    }

    /// Bytes of `stage` in `dir`.
    pub fn bytes(&self, stage: Stage, dir: Dir) -> u64 {
        self.requests[stage.index()][dir as usize] * self.line_bytes
    }

    /// Bytes of `stage`, both directions.
    pub fn stage_bytes(&self, stage: Stage) -> u64 {
        self.bytes(stage, Dir::Read) + self.bytes(stage, Dir::Write)
    }

    /// All requests.
    pub fn total_requests(&self) -> u64 {
        self.requests.iter().map(|r| r[0] + r[1]).sum()
    }

    /// All bytes.
    pub fn total_bytes(&self) -> u64 {
        self.total_requests() * self.line_bytes
    }

    /// Bytes in one direction.
    pub fn dir_bytes(&self, dir: Dir) -> u64 {
        self.requests.iter().map(|r| r[dir as usize]).sum::<u64>() * self.line_bytes
    }

    /// Bytes of the sorting stages.
    pub fn sorting_bytes(&self) -> u64 {
        Stage::ALL.iter().filter(|s| s.is_sorting()).map(|&s| self.stage_bytes(s)).sum()
    }

    /// Scaled copy (for "per 60 frames" figures): `factor` times every count, rounded.
    pub fn scaled_bytes(&self, stage: Stage, factor: f64) -> f64 {
        self.stage_bytes(stage) as f64 * factor
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bytes_are_whole_lines() {
        let mut t = Traffic::new(64);
        t.add(Stage::SortTable, Dir::Read, 3);
        t.add(Stage::FrameBuffer, Dir::Write, 2);
        assert_eq!(t.total_bytes(), 5 * 64);
        assert_eq!(t.stage_bytes(Stage::SortTable), 192);
        assert_eq!(t.sorting_bytes(), 192);
        let mut u = Traffic::default();
        u.merge(&t);
        u.merge(&t);
        assert_eq!(u.dir_bytes(Dir::Write), 4 * 64);
    }
}
