//! The GPU-style baseline (Orin-AGX-like, every rate assumed): the 3DGS CUDA pipeline as a
//! sequence of kernels per frame, each taking `max(bytes / effective bandwidth, work / rate)`
//! plus a launch overhead:
//!
//! 1. preprocess: read every Gaussian's geometry and the visible ones' SH, write a 48-byte
//!    record per visible Gaussian;
//! 2. duplicate: read each visible Gaussian's screen data (16 bytes), write one 8-byte key
//!    (tile id, depth) and one 4-byte value (Gaussian index) per tile-Gaussian pair of 16-pixel
//!    tiles (the workload's `gpu_pairs`, the rasterizer's bounding-rectangle duplication);
//! 3. global radix sort of all pairs: a histogram pass reading the keys, then one pass per
//!    `radix_bits` of the key (32 depth bits plus the tile-id bits) reading and writing keys and
//!    values;
//! 4. tile ranges: read the keys;
//! 5. raster: read every pair's value and gather its 48-byte record (two 32-byte sectors, 64
//!    bytes, no cache reuse assumed), evaluate 256 pixels per pair scaled by the workload's
//!    early-termination ratio, write the frame.
//!
//! Traffic is counted in whole 64-byte lines per stream (gathers: one line per record).

use crate::config::{GpuArch, SimConfig};
use crate::traffic::{Dir, Stage, Traffic};
use crate::workload::{FrameWork, WorkloadInfo};

/// Time and traffic of one GPU frame.
#[derive(Clone, Debug, PartialEq)]
pub struct GpuFrame {
    /// Seconds per kernel: preprocess, duplicate, sort, ranges, raster.
    pub kernel_s: [f64; 5],
    /// Traffic.
    pub traffic: Traffic,
}

impl GpuFrame {
    /// Frame time in seconds.
    pub fn total_s(&self) -> f64 {
        self.kernel_s.iter().sum()
    }
}

fn lines(bytes: u64, line: u64) -> u64 {
    bytes.div_ceil(line)
}

/// Radix passes over the pair keys of a `width x height` image with `tile`-pixel tiles.
pub fn radix_passes(g: &GpuArch, width: u32, height: u32) -> u32 {
    let tiles = width.div_ceil(g.tile) as u64 * height.div_ceil(g.tile) as u64;
    let tile_bits = 64 - tiles.max(1).leading_zeros();
    (32 + tile_bits).div_ceil(g.radix_bits)
}

/// One frame of the GPU model (the workload `info` gives the image size and the parameter
/// bytes: the reference reads 11 FP32 of geometry and the FP32 SH of the scene's degree, the
/// same bytes as the baked format's default).
pub fn frame(cfg: &SimConfig, info: &WorkloadInfo, fw: &FrameWork) -> GpuFrame {
    let (width, height) = (info.width, info.height);
    let g = &cfg.gpu;
    let s = &cfg.sizes;
    let line = cfg.dram.line_bytes as u64;
    let mut tr = Traffic::new(line);
    let stream_bw = g.peak_gbs * 1e9 * g.stream_efficiency;
    let gather_bw = g.peak_gbs * 1e9 * g.gather_efficiency;
    let launch = g.kernel_overhead_us * 1e-6;
    let kv = (g.key_bytes + g.value_bytes) as u64;
    let pairs = fw.gpu_pairs;
    let vis = fw.visible;

    // 1. Preprocess.
    let r = lines(fw.gaussians * s.geometry_bytes(info), line) + lines(vis * s.sh_bytes(info), line);
    let w = lines(vis * g.record_bytes as u64, line);
    tr.add(Stage::Preprocess, Dir::Read, r);
    tr.add(Stage::FeatureTable, Dir::Write, w);
    let pre = ((r + w) * line) as f64 / stream_bw;
    let pre = pre.max(fw.gaussians as f64 / g.preprocess_per_s) + launch;

    // 2. Duplicate.
    let r = lines(vis * 16, line);
    let w = lines(pairs * kv, line);
    tr.add(Stage::FeatureTable, Dir::Read, r);
    tr.add(Stage::IncomingList, Dir::Write, w);
    let dup = ((r + w) * line) as f64 / stream_bw + launch;

    // 3. Radix sort.
    let passes = radix_passes(g, width, height) as u64;
    let hist = lines(pairs * g.key_bytes as u64, line);
    let per_pass = lines(pairs * kv, line);
    tr.add(Stage::SortTable, Dir::Read, hist + passes * per_pass);
    tr.add(Stage::SortTable, Dir::Write, passes * per_pass);
    let sort = ((hist + 2 * passes * per_pass) * line) as f64 / stream_bw + (passes + 1) as f64 * launch;

    // 4. Tile ranges.
    let r = lines(pairs * g.key_bytes as u64, line);
    tr.add(Stage::SortTable, Dir::Read, r);
    let ranges = (r * line) as f64 / stream_bw + launch;

    // 5. Raster.
    let values = lines(pairs * g.value_bytes as u64, line);
    let gathers = pairs;
    let fbw = lines(width as u64 * height as u64 * s.pixel_bytes as u64, line);
    tr.add(Stage::RasterTable, Dir::Read, values);
    tr.add(Stage::FeatureTable, Dir::Read, gathers);
    tr.add(Stage::FrameBuffer, Dir::Write, fbw);
    let mem = ((values + fbw) * line) as f64 / stream_bw + (gathers * line) as f64 / gather_bw;
    let evals = pairs as f64 * (g.tile * g.tile) as f64 * fw.processed_ratio;
    let raster = mem.max(evals / g.raster_evals_per_s) + launch;

    GpuFrame { kernel_s: [pre, dup, sort, ranges, raster], traffic: tr }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sort_traffic_scales_with_pairs_and_passes() {
        let cfg = SimConfig::default();
        let mut fw = FrameWork {
            gaussians: 1000,
            visible: 800,
            gpu_pairs: 1 << 20,
            processed_ratio: 0.5,
            ..FrameWork::default()
        };
        let info = WorkloadInfo { width: 2560, height: 1440, ..WorkloadInfo::default() };
        let a = frame(&cfg, &info, &fw);
        // QHD, 16-pixel tiles: 160 x 90 = 14400 tiles, 14 bits: (32 + 14) / 8 -> 6 passes.
        assert_eq!(radix_passes(&cfg.gpu, 2560, 1440), 6);
        let sort = a.traffic.stage_bytes(Stage::SortTable);
        assert_eq!(sort, (1 << 20) * 8 + 6 * 2 * (1 << 20) * 12 + (1 << 20) * 8);
        fw.gpu_pairs *= 2;
        let b = frame(&cfg, &info, &fw);
        assert_eq!(b.traffic.stage_bytes(Stage::SortTable), 2 * sort);
        assert!(b.total_s() > a.total_s());
    }

    #[test]
    fn parameter_bytes_follow_the_sh_degree() {
        let cfg = SimConfig::default();
        let fw = FrameWork { gaussians: 1000, visible: 1000, ..FrameWork::default() };
        let read = |degree: u8| {
            let info = WorkloadInfo {
                width: 640,
                height: 480,
                sh_degree: degree,
                gaussian_geometry_bytes: neo_golden::hwpre::bake::geometry_bytes(),
                gaussian_sh_bytes: neo_golden::hwpre::bake::sh_bytes(
                    degree,
                    neo_golden::hwpre::ShPrecision::F32,
                ),
                ..WorkloadInfo::default()
            };
            frame(&cfg, &info, &fw).traffic.stage_bytes(Stage::Preprocess)
        };
        // 1000 x (44 + 12) bytes at degree 0, 1000 x (44 + 192) at degree 3, in 64-byte lines.
        assert_eq!(read(0), (44_000u64.div_ceil(64) + 12_000u64.div_ceil(64)) * 64);
        assert_eq!(read(3), (44_000u64.div_ceil(64) + 192_000u64.div_ceil(64)) * 64);
    }
}
