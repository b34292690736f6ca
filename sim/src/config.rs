//! Every parameter of the model in one serde document (`--config FILE`, JSON; absent fields keep
//! their defaults, unknown fields are errors).
//!
//! Two kinds of numbers live here:
//! - **architecture counts and sizes**: the engine's (cores, units, chunk, tile, subtile,
//!   buffers) are the one engine configuration, [`EngineConfig`] (`engine`), shared with the RTL
//!   generator and the latency report; the rest (preprocessing units, data sizes) default from
//!   the paper's Table 1 and the golden model's formats;
//! - **assumed timings** of units without measured RTL (preprocessing units, the raster core's
//!   ITU/SCU until `reports/latency.json` has a `raster` section, the GPU baseline): clearly
//!   marked `assumed` here and in every report.
//!
//! Sorting-core timing is never here: it comes from `reports/latency.json` ([`crate::latency`]).
//! DRAM timing defaults are the published LPDDR4-3200 speed bin (see [`DramConfig`]).

use serde::{Deserialize, Serialize};
use std::ops::RangeInclusive;
use std::path::Path;

use neo_golden::engine::pre::sh_record_words;
use neo_golden::engine::EngineConfig;
use neo_golden::error::{InputError, InputResult};
use neo_golden::hwpre::ShPrecision;
use neo_golden::json_shape::parse_shaped;
use neo_golden::pipeline::Preprocessing;

/// The accelerator clock range in MHz: 1 MHz to 10 GHz. Slower clocks make a frame millions of
/// DRAM refresh intervals long (a 1e-300 MHz clock never finishes); faster ones are no silicon.
pub const CLOCK_MHZ: RangeInclusive<f64> = 1.0..=10_000.0;

/// The largest DRAM timing parameter (every `n_*` of [`DramConfig`]), in DRAM clocks: 2^16.
/// Real speed bins need far less (LPDDR4-3200's tREFI is 6247 clocks, DDR4-3200's 12480,
/// DDR5-8800's about 17200; tRFC stays below 1500, every other parameter below 200); a larger
/// value makes a latency wrap around or a run hang.
pub const MAX_DRAM_CLOCKS: u64 = 1 << 16;

/// The DRAM data-rate range in MT/s: 100 (below DDR's slowest bin, 200) to 100 000 (twice
/// GDDR7's). It fixes the clock period `t_ck_ps`.
pub const DRAM_DATA_RATE_MTS: RangeInclusive<u32> = 100..=100_000;

/// Most DRAM channels: 64 (four HBM3 stacks of 16).
pub const MAX_DRAM_CHANNELS: u32 = 64;

/// Most banks per DRAM channel: 256 (DDR5 has 32; the DRAM model's stress tests use 128).
pub const MAX_DRAM_BANKS: u32 = 256;

/// Most entries of a DRAM channel's read or write queue.
pub const MAX_DRAM_QUEUE: u32 = 1024;

/// Most cores of a GSCore-style baseline (`gscore.core_counts`): as many sorting cores as the
/// engine may have ([`neo_golden::engine::MAX_SORT_CORES`]).
pub const MAX_GSCORE_CORES: u32 = neo_golden::engine::MAX_SORT_CORES as u32;

/// The largest byte size of one record: a Gaussian's geometry or SH coefficients, a feature
/// entry, a pixel, a GSCore bitmap, a GPU key, value or per-Gaussian record (4 KiB; the largest
/// real one, degree-3 FP32 SH, is 192 bytes).
pub const MAX_RECORD_BYTES: u32 = 4096;

/// The largest initiation interval of a unit, in cycles per item, assumed (config
/// `preprocess`, `raster_assumed`) or measured (`latency.json`): 1024 (the RTL's are 1 to 4).
pub const MAX_UNIT_II: f64 = 1024.0;

/// The largest cycle count of a unit's timing, assumed or measured: a pipeline latency, a fixed
/// overhead, one measured command (`latency.json`): 2^24 (the RTL's longest measured command
/// takes a few thousand cycles). Larger values make runs hang.
pub const MAX_UNIT_CYCLES: u64 = 1 << 24;

/// Checks that `v` (named `what`) is finite and in `min..=max` (`min` excluded when
/// `positive`).
fn check_f64(v: f64, what: &str, positive: bool, min: f64, max: f64) -> Result<(), String> {
    let low_ok = if positive { v > min } else { v >= min };
    if low_ok && v <= max {
        Ok(())
    } else {
        let low = if positive { format!("above {min}") } else { format!("at least {min}") };
        Err(format!("{what} = {}: must be {low} and at most {max}", readable(v)))
    }
}

/// `v` as a person reads it: in exponent form when very large or very small (`1e300`, not its
/// 301 digits).
fn readable(v: f64) -> String {
    if v != 0.0 && v.is_finite() && !(1e-6..1e9).contains(&v.abs()) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

/// Checks that `v` (named `what`) is in `range`.
fn check_range<T: PartialOrd + std::fmt::Display>(
    v: T,
    what: &str,
    range: RangeInclusive<T>,
) -> Result<(), String> {
    if range.contains(&v) {
        Ok(())
    } else {
        Err(format!("{what} = {v}: outside {}..={}", range.start(), range.end()))
    }
}

/// Checks a unit's assumed or measured initiation interval `ii` (named `what`): positive (when
/// `positive`, else at least 0) and at most [`MAX_UNIT_II`].
pub fn check_unit_ii(ii: f64, what: &str, positive: bool) -> Result<(), String> {
    check_f64(ii, what, positive, 0.0, MAX_UNIT_II)
}

/// Checks a unit's assumed or measured cycle count `cycles` (named `what`): at most
/// [`MAX_UNIT_CYCLES`].
pub fn check_unit_cycles(cycles: f64, what: &str) -> Result<(), String> {
    check_f64(cycles, what, false, 0.0, MAX_UNIT_CYCLES as f64)
}

/// The whole model configuration.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SimConfig {
    /// Accelerator clock in MHz (the paper's 1 GHz, Table 3).
    pub clock_mhz: f64,
    /// The engine: every count and size of the RTL (cores, units, chunk, tile, subtile).
    pub engine: EngineConfig,
    /// Sorting-policy parameters of the golden pipeline the workload is generated with.
    pub pipeline: UpdateParams,
    /// Neo's engines (paper Table 1).
    pub neo: NeoArch,
    /// The GSCore-style baseline.
    pub gscore: GscoreArch,
    /// The GPU-style baseline (Orin-AGX-like).
    pub gpu: GpuArch,
    /// Preprocessing engine timing (assumed, not measured).
    pub preprocess: PreprocessTiming,
    /// Raster core timing (assumed, not measured) used until `latency.json` has `raster`.
    pub raster_assumed: RasterTiming,
    /// Bytes of the data structures in DRAM.
    pub sizes: DataSizes,
    /// The DRAM of the accelerators.
    pub dram: DramConfig,
}

impl Default for SimConfig {
    fn default() -> Self {
        SimConfig {
            clock_mhz: 1000.0,
            engine: EngineConfig::default(),
            pipeline: UpdateParams::default(),
            neo: NeoArch::default(),
            gscore: GscoreArch::default(),
            gpu: GpuArch::default(),
            preprocess: PreprocessTiming::default(),
            raster_assumed: RasterTiming::default(),
            sizes: DataSizes::default(),
            dram: DramConfig::default(),
        }
    }
}

/// The sorting policy of the golden pipeline (the geometry and the chunk are the engine's).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct UpdateParams {
    /// DPS passes per frame (1).
    pub dps_passes: usize,
    /// Largest table per tile (`null`: unbounded).
    pub capacity: Option<usize>,
}

impl Default for UpdateParams {
    fn default() -> Self {
        UpdateParams { dps_passes: 1, capacity: None }
    }
}

/// Every golden pipeline parameter a workload is generated with: the engine's geometry and chunk
/// ([`SimConfig::pipeline_params`]) and the sorting policy.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PipelineParams {
    /// Tile side in pixels (Table 1: 64).
    pub tile: u32,
    /// Subtile side in pixels (Table 1: 8).
    pub subtile: u32,
    /// DPS and conventional-sort chunk (Section 4.3: 256).
    pub chunk: usize,
    /// DPS passes per frame (1).
    pub dps_passes: usize,
    /// Largest table per tile (`null`: unbounded).
    pub capacity: Option<usize>,
    /// Entries of the raster cores' reorder window (the engine's `raster_window`; 1: none): the
    /// golden pipeline blends and writes back in its order.
    pub raster_window: usize,
}

impl PipelineParams {
    /// The parameters of `engine` with the sorting policy `update`.
    pub fn new(engine: &EngineConfig, update: &UpdateParams) -> Self {
        PipelineParams {
            tile: engine.tile,
            subtile: engine.subtile,
            chunk: engine.chunk,
            dps_passes: update.dps_passes,
            capacity: update.capacity,
            raster_window: engine.raster_window,
        }
    }
}

impl Default for PipelineParams {
    /// The default engine's geometry and chunk with the default policy.
    fn default() -> Self {
        PipelineParams::new(&EngineConfig::default(), &UpdateParams::default())
    }
}

/// Neo's engines (paper Table 1 and Section 5).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct NeoArch {
    /// Projection units of the preprocessing engine (4).
    pub projection_units: u32,
    /// Colour units (4).
    pub color_units: u32,
    /// Duplication units (4).
    pub duplication_units: u32,
    /// Sorting-core I/O buffer in bytes (64 KB); the double-buffered input and output chunks
    /// (`4 x chunk x entry bytes`) must fit.
    pub sort_io_buffer_bytes: u64,
    /// Raster-core buffer in bytes (200 KB); bounds the feature prefetch window.
    pub raster_buffer_bytes: u64,
    /// Double-buffered sorting-core I/O: the next chunk command's load overlaps the current
    /// one's passes (the paper's design and the RTL's: `latency.json`'s `interval`); `false`
    /// runs every command alone (its single-command latency).
    pub double_buffered_io: bool,
    /// DPS and the MSU+ insert/delete merge are one stream (the last DPS pass feeds the MSU+,
    /// as in the golden accounting); `false` runs the RTL's separate DPS and MERGE_DELETE
    /// commands through DRAM.
    pub fused_dps_merge: bool,
    /// Frames whose feature tables and incoming lists can be live at once (2: double buffering
    /// lets frame `f + 1` preprocess while frame `f` sorts and rasters).
    pub frame_buffers: u32,
    /// Outstanding read lines per sorting core (the RTL's `max_outstanding` bursts of 16
    /// entries, in 64-byte lines).
    pub sort_read_window: u32,
    /// Outstanding read lines of the preprocessing engine.
    pub preprocess_read_window: u32,
    /// Outstanding read lines (feature gathers, table reads) per raster core; the prefetch is
    /// also bounded by half the raster buffer.
    pub raster_read_window: u32,
}

impl Default for NeoArch {
    fn default() -> Self {
        NeoArch {
            projection_units: 4,
            color_units: 4,
            duplication_units: 4,
            sort_io_buffer_bytes: 64 * 1024,
            raster_buffer_bytes: 200 * 1024,
            double_buffered_io: true,
            fused_dps_merge: true,
            frame_buffers: 2,
            sort_read_window: 6,
            preprocess_read_window: 64,
            raster_read_window: 64,
        }
    }
}

/// The GSCore-style baseline: hierarchical sort from scratch every frame, subtile bitmaps made
/// in preprocessing and carried through sorting to the raster, no reuse, no depth update.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct GscoreArch {
    /// Core counts evaluated (the paper: 4 as published, 16 scaled); each count `N` means `N`
    /// sorting cores and `N` subtile units (`N / 4` raster cores of 4).
    pub core_counts: Vec<u32>,
    /// Subtile bitmap bytes carried with every sort entry (64 subtiles: 8 bytes).
    pub bitmap_bytes: u32,
    /// Approximate (binning) pass: entries per cycle per core (assumed, not measured).
    pub approx_entries_per_cycle: f64,
    /// Approximate pass pipeline latency in cycles (assumed).
    pub approx_latency: u64,
}

impl Default for GscoreArch {
    fn default() -> Self {
        GscoreArch {
            core_counts: vec![4, 16],
            bitmap_bytes: 8,
            approx_entries_per_cycle: 1.0,
            approx_latency: 8,
        }
    }
}

/// The GPU-style baseline (all assumed; Orin-AGX-like): kernels in sequence, each bound by
/// memory (bytes / effective bandwidth) or by its compute rate.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct GpuArch {
    /// Peak DRAM bandwidth in GB/s (Orin AGX: 204.8).
    pub peak_gbs: f64,
    /// Achieved fraction of peak for streaming kernels (assumed).
    pub stream_efficiency: f64,
    /// Achieved fraction of peak for gathers of 64-byte lines (assumed).
    pub gather_efficiency: f64,
    /// Tile side of the CUDA rasterizer (16).
    pub tile: u32,
    /// Radix bits per sort pass (8: onesweep-style passes).
    pub radix_bits: u32,
    /// Sort key bytes (tile id and depth: 8) and value bytes (Gaussian index: 4).
    pub key_bytes: u32,
    /// Value bytes.
    pub value_bytes: u32,
    /// Per-Gaussian record written by preprocessing and gathered by the raster (mean, depth,
    /// radius, conic and opacity, colour, tile count: 48 bytes).
    pub record_bytes: u32,
    /// Pixel-Gaussian evaluations per second of the raster kernel (assumed).
    pub raster_evals_per_s: f64,
    /// Gaussians preprocessed per second (assumed).
    pub preprocess_per_s: f64,
    /// Fixed cost per kernel launch in microseconds (assumed).
    pub kernel_overhead_us: f64,
}

impl Default for GpuArch {
    fn default() -> Self {
        GpuArch {
            peak_gbs: 204.8,
            stream_efficiency: 0.8,
            gather_efficiency: 0.5,
            tile: 16,
            radix_bits: 8,
            key_bytes: 8,
            value_bytes: 4,
            record_bytes: 48,
            raster_evals_per_s: 30e9,
            preprocess_per_s: 2e9,
            kernel_overhead_us: 10.0,
        }
    }
}

/// Preprocessing-engine timing: every unit accepts one item per `*_ii` cycles (assumed, not
/// measured: no RTL of the preprocessing engine exists yet).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PreprocessTiming {
    /// Cycles per Gaussian per projection unit.
    pub projection_ii: f64,
    /// Cycles per visible Gaussian per colour unit.
    pub color_ii: f64,
    /// Cycles per candidate tile test per duplication unit.
    pub duplication_ii: f64,
    /// Pipeline fill in cycles.
    pub latency: u64,
}

impl Default for PreprocessTiming {
    fn default() -> Self {
        PreprocessTiming { projection_ii: 1.0, color_ii: 1.0, duplication_ii: 1.0, latency: 100 }
    }
}

/// Raster-core unit timing. The defaults are **assumed, not measured**; the fields that
/// `reports/latency.json` measures replace them ([`crate::latency::Latency::raster`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RasterTiming {
    /// Cycles an ITU needs per table entry (one entry tested against every subtile of the tile).
    pub itu_ii: f64,
    /// ITU pipeline latency in cycles.
    pub itu_latency: u64,
    /// Cycles an SCU spends per routed entry while pixels of its subtile are active (8x8
    /// pixels on 16 lanes: 4).
    pub scu_cycles_per_pair: f64,
    /// Cycles per routed entry once every pixel of the subtile has terminated (the rest of the
    /// list drains).
    pub scu_drain_ii: f64,
    /// SCU pipeline latency in cycles.
    pub scu_latency: u64,
    /// Fixed cycles per tile (setup, pixel-buffer drain). The measured raster core's value is
    /// its empty tile (loads of nothing, one empty list per subtile, the pipeline latencies)
    /// beyond its `pixel_write_cycles`.
    pub tile_overhead: u64,
    /// Cycles per table entry of the loads before the ITU walk (table beat + feature beat in the
    /// RTL: 2); 0 models loads overlapped with the rest (the assumed default).
    pub load_cycles_per_entry: f64,
    /// Pixel-row writes per tile (`tile^2 / subtile` in the RTL, 512), after the last segment's
    /// walk starts; 0 (the assumed default) ignores them.
    pub pixel_write_cycles: u64,
    /// Request-port cycles of one entry's write-back, beside the loads (the measured core: 1,
    /// one request port; 0 where the loads' read beats, not the requests, set the pace).
    pub write_back_cycles_per_entry: f64,
    /// Cycles of a segment's write-back during which the loads' reads already in flight still
    /// arrive (the write-back stops the read requests, not their data): 0 (the default, and
    /// the unit bench's memory, which answers in a cycle); the engine model sets it from its
    /// bridge's outstanding reads.
    pub write_back_overlap: f64,
    /// Feature-buffer entries of a raster core: a longer table is reloaded and walked once per
    /// subtile group, segment by segment (the RTL's schedule); 0 (the assumed default) is
    /// unbounded.
    pub feature_buffer: u64,
    /// Fixed cycles per segment of a table longer than `feature_buffer` (the reload's
    /// handshakes, the ITU latency and the drain of the SCUs' FIFOs before the buffer is
    /// reused).
    pub segment_overhead: f64,
    /// Entries of the raster core's reorder window (the engine's `raster_window`; 0 or 1: none).
    /// The window holds `window - 1` entries back, so a tile's first segment is complete, and
    /// its walk starts, that many loads later ([`crate::arch::raster_tile_cycles`]).
    pub window: u64,
}

impl RasterTiming {
    /// Checks every field (named `section.field`): the per-entry cycles are finite, at least 0
    /// (`itu_ii`, `scu_cycles_per_pair` above 0) and at most [`MAX_UNIT_II`]; the cycle counts
    /// at most [`MAX_UNIT_CYCLES`]; the feature buffer at most 2^20 entries and the window at
    /// most the engine's [`neo_golden::engine::MAX_RASTER_WINDOW`].
    pub fn check(&self, section: &str) -> Result<(), String> {
        let at = |f: &str| format!("{section}.{f}");
        check_unit_ii(self.itu_ii, &at("itu_ii"), true)?;
        check_unit_ii(self.scu_cycles_per_pair, &at("scu_cycles_per_pair"), true)?;
        check_unit_ii(self.scu_drain_ii, &at("scu_drain_ii"), false)?;
        check_unit_ii(self.load_cycles_per_entry, &at("load_cycles_per_entry"), false)?;
        check_unit_ii(self.write_back_cycles_per_entry, &at("write_back_cycles_per_entry"), false)?;
        for (v, f) in [
            (self.itu_latency as f64, "itu_latency"),
            (self.scu_latency as f64, "scu_latency"),
            (self.tile_overhead as f64, "tile_overhead"),
            (self.pixel_write_cycles as f64, "pixel_write_cycles"),
            (self.write_back_overlap, "write_back_overlap"),
            (self.segment_overhead, "segment_overhead"),
        ] {
            check_unit_cycles(v, &at(f))?;
        }
        check_range(self.feature_buffer, &at("feature_buffer"), 0..=1 << 20)?;
        check_range(self.window, &at("window"), 0..=neo_golden::engine::MAX_RASTER_WINDOW as u64)?;
        Ok(())
    }
}

impl Default for RasterTiming {
    fn default() -> Self {
        RasterTiming {
            itu_ii: 1.0,
            itu_latency: 6,
            scu_cycles_per_pair: 4.0,
            scu_drain_ii: 1.0,
            scu_latency: 12,
            tile_overhead: 64,
            load_cycles_per_entry: 0.0,
            pixel_write_cycles: 0,
            write_back_cycles_per_entry: 1.0,
            write_back_overlap: 0.0,
            feature_buffer: 0,
            segment_overhead: 0.0,
            window: 0,
        }
    }
}

/// Sizes of the data in DRAM. Sort entries, feature entries and the per-Gaussian parameters
/// come from the golden formats of the workload (`sort_entry_bytes`, `feature_entry_bytes`, and
/// the baked parameter format's `gaussian_geometry_bytes`, `gaussian_sh_bytes` by the scene's SH
/// degree) unless set here (a byte-size preset such as [`DataSizes::artifact`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct DataSizes {
    /// Per-Gaussian geometry read for every Gaussian (`None`: the baked format's geometry
    /// record, `neo_golden::hwpre::bake::geometry_bytes`: position, 3D covariance, opacity and
    /// cutoff as FP32, 44 bytes).
    pub gaussian_geometry_bytes: Option<u32>,
    /// Per-Gaussian SH coefficients read for Gaussians that survive culling (`None`: the baked
    /// format's SH record at the scene's SH degree, `neo_golden::hwpre::bake::sh_bytes`: 192
    /// bytes at degree 3, 12 at degree 0).
    pub gaussian_sh_bytes: Option<u32>,
    /// Frame-buffer bytes per pixel (RGB8, the golden frame).
    pub pixel_bytes: u32,
    /// Feature-entry bytes in place of the golden format's (`None`: the format's).
    pub feature_entry_bytes: Option<u32>,
    /// SH records of binary16 coefficients (the engine's `PRE_CTRL.sh_half`): unless
    /// `gaussian_sh_bytes` sets them, a visible Gaussian's SH bytes are the binary16 record's at
    /// the scene's degree (golden `engine::pre::sh_record_words`: 8, 24, 56 and 96 bytes at
    /// degrees 0 to 3).
    pub sh_half: bool,
}

impl Default for DataSizes {
    fn default() -> Self {
        DataSizes {
            gaussian_geometry_bytes: None,
            gaussian_sh_bytes: None,
            pixel_bytes: 3,
            feature_entry_bytes: None,
            sh_half: false,
        }
    }
}

impl DataSizes {
    /// The official artifact's byte sizes (`config.artifact_constants` of the artifact
    /// reference): FP16 positions (6 B) read for every Gaussian, 112 B of other FP16 parameters
    /// for each non-culled one, 22-byte feature entries. Its 6-byte sort entries are golden's.
    pub fn artifact() -> Self {
        DataSizes {
            gaussian_geometry_bytes: Some(6),
            gaussian_sh_bytes: Some(112),
            pixel_bytes: 3,
            feature_entry_bytes: Some(22),
            sh_half: false,
        }
    }

    /// The precision of the SH records ([`DataSizes::sh_half`]).
    pub fn sh_precision(&self) -> ShPrecision {
        if self.sh_half {
            ShPrecision::F16
        } else {
            Preprocessing::DEFAULT_SH
        }
    }

    /// Geometry bytes per Gaussian for a workload.
    pub fn geometry_bytes(&self, info: &crate::workload::WorkloadInfo) -> u64 {
        self.gaussian_geometry_bytes.unwrap_or(info.gaussian_geometry_bytes) as u64
    }

    /// SH bytes per visible Gaussian for a workload.
    pub fn sh_bytes(&self, info: &crate::workload::WorkloadInfo) -> u64 {
        self.sh_bytes_of_degree(info.sh_degree)
    }

    /// SH bytes per visible Gaussian of a scene of SH degree `degree`: `gaussian_sh_bytes`, else
    /// the engine's SH record in [`DataSizes::sh_precision`] (golden `sh_record_words`; a binary32
    /// record is the baked format's SH bytes).
    pub fn sh_bytes_of_degree(&self, degree: u8) -> u64 {
        match self.gaussian_sh_bytes {
            Some(b) => b as u64,
            None => 4 * sh_record_words(degree, self.sh_precision()) as u64,
        }
    }

    /// The named preset: `neo` (the default), `neo-f16sh` (the same with binary16 SH records) or
    /// `artifact`.
    pub fn preset(name: &str) -> Result<Self, String> {
        match name {
            "neo" => Ok(DataSizes::default()),
            "neo-f16sh" => Ok(DataSizes { sh_half: true, ..DataSizes::default() }),
            "artifact" => Ok(DataSizes::artifact()),
            _ => Err(format!("unknown byte-size preset {name:?}: expected neo, neo-f16sh or artifact")),
        }
    }
}

/// One DRAM: organisation, address mapping and timing in DRAM clock cycles (`n_*` fields).
///
/// Defaults: LPDDR4-3200, 4 channels x 32 bits (51.2 GB/s), 8 banks, 4 KB rows per channel,
/// 64-byte requests (one BL16 burst on a 32-bit channel). Timing numbers are the LPDDR4-3200
/// speed bin as Ramulator's `LPDDR4_3200` lists it (JESD209-4 core timings converted to
/// single-cycle commands): CL 32 (RL 28 + tDQSCK 3 + 1), CWL 18, RCD 29, RPpb 27, RAS 68, RC 95,
/// RTP 14, WTR 16, WR 28, RRD 16, FAW 64, CCD 8, BL 8 (16 beats), RTRS 2, REFI 6247 (3.9 us),
/// RFCab 288 (8 Gb die: 180 ns), RPab 32, PPD 4. See docs/cycle-model.md for what is modelled.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct DramConfig {
    /// Name for reports.
    pub name: String,
    /// Channels.
    pub channels: u32,
    /// Data bits per channel.
    pub channel_bits: u32,
    /// Transfers per second, in MT/s.
    pub data_rate_mts: u32,
    /// Banks per channel.
    pub banks: u32,
    /// Row (page) bytes per channel.
    pub row_bytes: u32,
    /// Request size in bytes (64): every access moves whole requests.
    pub line_bytes: u32,
    /// Address mapping, most significant first: `RoBaCoCh` (row, bank, column, channel: lines
    /// interleave over channels, consecutive lines of a channel share a row; Ramulator's default
    /// `RoBaRaCoCh` with one rank, also accepted under that name) or `RoCoBaCh` (consecutive lines
    /// of a channel rotate over banks).
    pub mapping: String,
    /// XOR the bank index with the low row bits (permutation-based interleaving: streams whose
    /// bases are aligned alike then fall into different banks). Ramulator's mapping does not
    /// (`false`, the default).
    pub bank_xor: bool,
    /// Clock period in picoseconds (LPDDR4-3200: 625).
    pub t_ck_ps: u64,
    /// Read latency (command to first data).
    pub n_cl: u64,
    /// DQS output access time: added to every read's data return (Ramulator's
    /// `read_latency = nCL + nDQSCK + nBL`), not to the data bus occupancy.
    pub n_dqsck: u64,
    /// Write latency.
    pub n_cwl: u64,
    /// Activate to column command.
    pub n_rcd: u64,
    /// Precharge period (per bank).
    pub n_rp: u64,
    /// Activate to precharge.
    pub n_ras: u64,
    /// Activate to activate, same bank.
    pub n_rc: u64,
    /// Read to precharge.
    pub n_rtp: u64,
    /// End of write data to read command.
    pub n_wtr: u64,
    /// Write recovery (end of write data to precharge).
    pub n_wr: u64,
    /// Activate to activate, different banks.
    pub n_rrd: u64,
    /// Four-activate window.
    pub n_faw: u64,
    /// Column to column command (bursts are `n_bl` apart on the bus, which must satisfy it).
    pub n_ccd: u64,
    /// Data-bus cycles per request.
    pub n_bl: u64,
    /// Bus turnaround.
    pub n_rtrs: u64,
    /// Refresh interval (`0` disables refresh).
    pub n_refi: u64,
    /// All-bank refresh time.
    pub n_rfc: u64,
    /// All-bank precharge period (before a refresh, or an activate after an all-bank precharge).
    pub n_rpab: u64,
    /// Precharge to precharge, any banks of the channel.
    pub n_ppd: u64,
    /// Write-queue entries per channel: write mode starts when more than 80% of them wait (or no
    /// read waits) and ends when fewer than 20% wait and a read waits (Ramulator's watermarks);
    /// `neo dram` also blocks a stream on a full queue.
    pub write_queue: u32,
    /// Read-queue entries per channel the scheduler looks at (FR-FCFS: the oldest request whose
    /// next command can issue goes first); `0` serves reads strictly in issue order.
    pub read_queue: u32,
    /// Accesses an open row serves before its further hits stop counting as ready (Ramulator's
    /// FRFCFS_Cap cap), so an older request to another row of the bank can close it.
    pub bypass_cap: u32,
}

impl Default for DramConfig {
    fn default() -> Self {
        DramConfig {
            name: "LPDDR4-3200 4x32".into(),
            channels: 4,
            channel_bits: 32,
            data_rate_mts: 3200,
            banks: 8,
            row_bytes: 4096,
            line_bytes: 64,
            mapping: "RoBaCoCh".into(),
            bank_xor: false,
            t_ck_ps: 625,
            n_cl: 32,
            n_dqsck: 3,
            n_cwl: 18,
            n_rcd: 29,
            n_rp: 27,
            n_ras: 68,
            n_rc: 95,
            n_rtp: 14,
            n_wtr: 16,
            n_wr: 28,
            n_rrd: 16,
            n_faw: 64,
            n_ccd: 8,
            n_bl: 8,
            n_rtrs: 2,
            n_refi: 6247,
            n_rfc: 288,
            n_rpab: 32,
            n_ppd: 4,
            write_queue: 32,
            read_queue: 32,
            bypass_cap: 16,
        }
    }
}

impl DramConfig {
    /// Peak bandwidth in bytes per second.
    pub fn peak_bytes_per_s(&self) -> f64 {
        self.channels as f64 * self.channel_bits as f64 / 8.0 * self.data_rate_mts as f64 * 1e6
    }

    /// Every timing parameter (`n_*`) by name.
    fn timings(&self) -> [(u64, &'static str); 19] {
        [
            (self.n_cl, "n_cl"),
            (self.n_dqsck, "n_dqsck"),
            (self.n_cwl, "n_cwl"),
            (self.n_rcd, "n_rcd"),
            (self.n_rp, "n_rp"),
            (self.n_ras, "n_ras"),
            (self.n_rc, "n_rc"),
            (self.n_rtp, "n_rtp"),
            (self.n_wtr, "n_wtr"),
            (self.n_wr, "n_wr"),
            (self.n_rrd, "n_rrd"),
            (self.n_faw, "n_faw"),
            (self.n_ccd, "n_ccd"),
            (self.n_bl, "n_bl"),
            (self.n_rtrs, "n_rtrs"),
            (self.n_refi, "n_refi"),
            (self.n_rfc, "n_rfc"),
            (self.n_rpab, "n_rpab"),
            (self.n_ppd, "n_ppd"),
        ]
    }

    /// Checks the organisation (powers of two, at most [`MAX_DRAM_CHANNELS`] channels and
    /// [`MAX_DRAM_BANKS`] banks), the data rate ([`DRAM_DATA_RATE_MTS`]), that a request is one
    /// burst of `n_bl` clocks, every timing parameter against [`MAX_DRAM_CLOCKS`], that a
    /// refresh interval leaves room for a row cycle, and the queues (at most
    /// [`MAX_DRAM_QUEUE`] entries; a write queue whose low watermark is not 0).
    pub fn check(&self) -> Result<(), String> {
        let pow2 = |v: u32, what: &str, max: u32| {
            if v == 0 || !v.is_power_of_two() || v > max {
                Err(format!("dram.{what} = {v}: must be a power of two of at most {max}"))
            } else {
                Ok(())
            }
        };
        pow2(self.channels, "channels", MAX_DRAM_CHANNELS)?;
        pow2(self.banks, "banks", MAX_DRAM_BANKS)?;
        pow2(self.line_bytes, "line_bytes", u32::MAX)?;
        pow2(self.row_bytes, "row_bytes", u32::MAX)?;
        if self.row_bytes < self.line_bytes {
            return Err("dram.row_bytes must be at least dram.line_bytes".into());
        }
        if !["RoBaCoCh", "RoBaRaCoCh", "RoCoBaCh"].contains(&self.mapping.as_str()) {
            return Err(format!(
                "dram.mapping '{}': expected RoBaCoCh (RoBaRaCoCh) or RoCoBaCh",
                self.mapping
            ));
        }
        if self.channel_bits == 0 || self.data_rate_mts == 0 || self.t_ck_ps == 0 {
            return Err("dram.channel_bits, data_rate_mts and t_ck_ps must be positive".into());
        }
        check_range(self.data_rate_mts, "dram.data_rate_mts", DRAM_DATA_RATE_MTS)?;
        for (v, what) in self.timings() {
            if v > MAX_DRAM_CLOCKS {
                return Err(format!("dram.{what} = {v}: at most {MAX_DRAM_CLOCKS} clocks"));
            }
        }
        if self.n_bl == 0 {
            return Err("dram.n_bl = 0: a request takes at least one clock of the data bus".into());
        }
        let line_bits = self.line_bytes as u64 * 8;
        if !line_bits.is_multiple_of(self.channel_bits as u64) {
            return Err(format!(
                "dram: a {}-byte request is not a whole number of beats on a {}-bit channel",
                self.line_bytes, self.channel_bits
            ));
        }
        let beats = line_bits / self.channel_bits as u64;
        if beats != 2 * self.n_bl {
            return Err(format!(
                "dram: a {}-byte request is {beats} beats on a {}-bit channel, but n_bl = {} clocks ({} beats)",
                self.line_bytes,
                self.channel_bits,
                self.n_bl,
                2 * self.n_bl
            ));
        }
        let ck_from_rate = 2_000_000 / self.data_rate_mts as u64;
        if ck_from_rate.abs_diff(self.t_ck_ps) > 1 {
            return Err(format!(
                "dram: t_ck_ps = {} but {} MT/s (double data rate) gives {ck_from_rate} ps",
                self.t_ck_ps, self.data_rate_mts
            ));
        }
        if self.n_ccd > self.n_bl {
            return Err(format!(
                "dram.n_ccd = {} > n_bl = {}: not modelled (bursts are n_bl apart)",
                self.n_ccd, self.n_bl
            ));
        }
        // The standard's order of the row timings (every speed bin keeps it): a row's column
        // command may issue before it may be closed (tRCD <= tRAS; else another row's precharge
        // closes it first, forever), a row cycle holds its active time (tRAS <= tRC), and a
        // precharge-to-precharge gap is within a precharge (tPPD <= tRP).
        for (a, an, b, bn) in [
            (self.n_rcd, "n_rcd", self.n_ras, "n_ras"),
            (self.n_ras, "n_ras", self.n_rc, "n_rc"),
            (self.n_ppd, "n_ppd", self.n_rp, "n_rp"),
        ] {
            if a > b {
                return Err(format!("dram.{an} = {a} > {bn} = {b}: must be at most dram.{bn}"));
            }
        }
        // Every refresh interval must leave room, after the refresh (all-bank precharge, then
        // tRFC), for an activate (the longest activate-to-activate spacing) and its column
        // command (tRCD): otherwise refreshes close every row before it is used and no access is
        // ever served.
        let busy = self.n_rpab + self.n_rfc + self.n_rc.max(self.n_rrd).max(self.n_faw) + self.n_rcd;
        if self.n_refi != 0 && self.n_refi <= busy {
            return Err(format!(
                "dram.n_refi = {}: the refresh interval must exceed n_rpab + n_rfc + max(n_rc, n_rrd, n_faw) \
                 + n_rcd = {busy} (a refresh, an activate and its column command), or be 0 (no refresh)",
                self.n_refi
            ));
        }
        if self.read_queue > MAX_DRAM_QUEUE {
            return Err(format!("dram.read_queue = {}: at most {MAX_DRAM_QUEUE} entries", self.read_queue));
        }
        if self.write_queue > MAX_DRAM_QUEUE {
            return Err(format!("dram.write_queue = {}: at most {MAX_DRAM_QUEUE} entries", self.write_queue));
        }
        if crate::dram::write_watermarks(self.write_queue).1 == 0 {
            let least = (1..).find(|&q| crate::dram::write_watermarks(q).1 > 0).unwrap_or(u32::MAX);
            return Err(format!(
                "dram.write_queue = {}: at least {least} entries (write mode ends only when fewer than \
                 int(0.2 x write_queue) writes wait, which must not be 0)",
                self.write_queue
            ));
        }
        Ok(())
    }
}

impl SimConfig {
    /// Reads a JSON configuration (missing fields keep their defaults).
    pub fn from_file(path: &Path) -> InputResult<Self> {
        let text = std::fs::read_to_string(path).map_err(|e| InputError::new(path, e.to_string()))?;
        let cfg: SimConfig = parse_shaped(&text, &SimConfig::default())
            .map_err(|e| InputError::new(path, format!("bad configuration: {e}")))?;
        cfg.check().map_err(|e| InputError::new(path, e))?;
        Ok(cfg)
    }

    /// The golden pipeline parameters of this configuration (engine geometry and chunk, policy).
    pub fn pipeline_params(&self) -> PipelineParams {
        PipelineParams::new(&self.engine, &self.pipeline)
    }

    /// Picoseconds per accelerator cycle.
    pub fn cycle_ps(&self) -> f64 {
        1e6 / self.clock_mhz
    }

    /// Checks counts and sizes against each other and every value against its range: the clock
    /// ([`CLOCK_MHZ`]), the DRAM ([`DramConfig::check`]), the engine, the GSCore core counts
    /// (1..=[`MAX_GSCORE_CORES`]), the byte sizes (1..=[`MAX_RECORD_BYTES`]), the GPU's
    /// rates and sizes, and the assumed unit timings ([`check_unit_ii`],
    /// [`check_unit_cycles`]).
    pub fn check(&self) -> Result<(), String> {
        self.dram.check()?;
        check_f64(self.clock_mhz, "clock_mhz", false, *CLOCK_MHZ.start(), *CLOCK_MHZ.end())?;
        let n = &self.neo;
        for (v, what) in [
            (n.projection_units, "neo.projection_units"),
            (n.color_units, "neo.color_units"),
            (n.duplication_units, "neo.duplication_units"),
            (n.frame_buffers, "neo.frame_buffers"),
            (n.sort_read_window, "neo.sort_read_window"),
            (n.preprocess_read_window, "neo.preprocess_read_window"),
            (n.raster_read_window, "neo.raster_read_window"),
        ] {
            if v == 0 {
                return Err(format!("{what} must be at least 1"));
            }
        }
        // Half the raster buffer holds the feature prefetch: at least one line.
        let least_raster_buffer = 2 * self.dram.line_bytes as u64;
        if n.raster_buffer_bytes < least_raster_buffer {
            return Err(format!(
                "neo.raster_buffer_bytes = {}: at least two dram.line_bytes ({least_raster_buffer}; half of \
                 it holds the feature prefetch)",
                n.raster_buffer_bytes
            ));
        }
        self.engine.validate().map_err(|e| format!("engine: {}", e.0))?;
        for &c in &self.gscore.core_counts {
            check_range(c, "gscore.core_counts: a count", 1..=MAX_GSCORE_CORES)?;
        }
        let g = &self.gscore;
        check_f64(
            g.approx_entries_per_cycle,
            "gscore.approx_entries_per_cycle",
            true,
            1.0 / MAX_UNIT_II,
            MAX_UNIT_II,
        )?;
        check_unit_cycles(g.approx_latency as f64, "gscore.approx_latency")?;
        let g = &self.gpu;
        for (v, what) in [
            (g.peak_gbs, "gpu.peak_gbs"),
            (g.raster_evals_per_s, "gpu.raster_evals_per_s"),
            (g.preprocess_per_s, "gpu.preprocess_per_s"),
        ] {
            if !(v > 0.0 && v.is_finite()) {
                return Err(format!("{what} = {v}: must be positive"));
            }
        }
        check_f64(g.stream_efficiency, "gpu.stream_efficiency", true, 0.0, 1.0)?;
        check_f64(g.gather_efficiency, "gpu.gather_efficiency", true, 0.0, 1.0)?;
        // One second per kernel launch is already far beyond any GPU's.
        check_f64(g.kernel_overhead_us, "gpu.kernel_overhead_us", false, 0.0, 1e6)?;
        // A CUDA block has at most 1024 threads, one per pixel of the tile.
        check_range(g.tile, "gpu.tile", 1..=32)?;
        // 2^16 buckets per pass is the largest histogram a GPU radix sort keeps on chip.
        check_range(g.radix_bits, "gpu.radix_bits", 1..=16)?;
        let s = &self.sizes;
        for (v, what) in [
            (Some(g.key_bytes), "gpu.key_bytes"),
            (Some(g.value_bytes), "gpu.value_bytes"),
            (Some(g.record_bytes), "gpu.record_bytes"),
            (Some(s.pixel_bytes), "sizes.pixel_bytes"),
            (s.gaussian_geometry_bytes, "sizes.gaussian_geometry_bytes"),
            (s.gaussian_sh_bytes, "sizes.gaussian_sh_bytes"),
            (s.feature_entry_bytes, "sizes.feature_entry_bytes"),
        ] {
            if let Some(v) = v {
                check_range(v, what, 1..=MAX_RECORD_BYTES)?;
            }
        }
        check_range(self.gscore.bitmap_bytes, "gscore.bitmap_bytes", 0..=MAX_RECORD_BYTES)?;
        self.raster_assumed.check("raster_assumed")?;
        let pp = &self.preprocess;
        check_unit_ii(pp.projection_ii, "preprocess.projection_ii", true)?;
        check_unit_ii(pp.color_ii, "preprocess.color_ii", true)?;
        check_unit_ii(pp.duplication_ii, "preprocess.duplication_ii", true)?;
        check_unit_cycles(pp.latency as f64, "preprocess.latency")?;
        neo_golden::pipeline::check_passes(self.pipeline.dps_passes)
            .map_err(|e| format!("pipeline.dps_passes: {e}"))?;
        Ok(())
    }

    /// Checks that the sorting-core buffers hold the double-buffered chunks of `entry_bytes`.
    pub fn check_buffers(&self, entry_bytes: u64) -> Result<(), String> {
        let need = 4 * self.engine.chunk as u64 * entry_bytes;
        if need > self.neo.sort_io_buffer_bytes {
            return Err(format!(
                "chunk {} of {entry_bytes}-byte entries needs {need} bytes of double-buffered I/O, more than \
                 neo.sort_io_buffer_bytes = {}",
                self.engine.chunk, self.neo.sort_io_buffer_bytes
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_consistent_and_round_trip() {
        let c = SimConfig::default();
        c.check().unwrap();
        assert_eq!(c.dram.peak_bytes_per_s(), 51.2e9);
        let j = serde_json::to_string(&c).unwrap();
        let back: SimConfig = serde_json::from_str(&j).unwrap();
        assert_eq!(back, c);
        // Partial documents keep defaults.
        let p: SimConfig = serde_json::from_str(r#"{"engine": {"sort_cores": 4}}"#).unwrap();
        assert_eq!(p.engine.sort_cores, 4);
        assert_eq!(p.engine.raster_cores, 4);
        assert!(serde_json::from_str::<SimConfig>(r#"{"engine": {"sort_core": 4}}"#).is_err());
        // The engine's counts live only in `engine`.
        assert!(serde_json::from_str::<SimConfig>(r#"{"neo": {"sort_cores": 4}}"#).is_err());
        assert!(serde_json::from_str::<SimConfig>(r#"{"pipeline": {"chunk": 128}}"#).is_err());
    }

    /// The byte-size presets: `neo-f16sh` charges the engine's binary16 SH records (padded to
    /// whole words) at every degree, a set `gaussian_sh_bytes` wins, and an unknown name is an
    /// error naming the presets.
    #[test]
    fn size_presets_charge_their_sh_records() {
        let neo = DataSizes::preset("neo").unwrap();
        let half = DataSizes::preset("neo-f16sh").unwrap();
        assert_eq!((0..=3).map(|d| neo.sh_bytes_of_degree(d)).collect::<Vec<_>>(), [12, 48, 108, 192]);
        assert_eq!((0..=3).map(|d| half.sh_bytes_of_degree(d)).collect::<Vec<_>>(), [8, 24, 56, 96]);
        assert_eq!((neo.sh_precision(), half.sh_precision()), (ShPrecision::F32, ShPrecision::F16));
        let set = DataSizes { gaussian_sh_bytes: Some(100), ..half.clone() };
        assert_eq!(set.sh_bytes_of_degree(3), 100);
        let from_json: SimConfig = serde_json::from_str(r#"{"sizes": {"sh_half": true}}"#).unwrap();
        assert_eq!(from_json.sizes, half);
        let e = DataSizes::preset("f16").unwrap_err();
        assert!(e.contains("neo-f16sh") && e.contains("\"f16\""), "{e}");
    }

    #[test]
    fn bad_values_are_rejected_with_their_name() {
        let mut c = SimConfig::default();
        c.dram.n_bl = 4;
        assert!(c.check().unwrap_err().contains("n_bl"));
        let mut c = SimConfig::default();
        c.engine.sort_cores = 0;
        assert!(c.check().unwrap_err().contains("engine: sort_cores 0 is outside"));
        let mut c = SimConfig::default();
        c.engine.chunk = 4096;
        assert!(c.check_buffers(6).unwrap_err().contains("sort_io_buffer_bytes"));
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("c.json");
        std::fs::write(&p, "{\"clock_mhz\": -1}").unwrap();
        let e = SimConfig::from_file(&p).unwrap_err().to_string();
        assert!(e.contains("c.json") && e.contains("clock_mhz"), "{e}");
    }

    /// Values that hang, wrap, abort or give absurd results are refused naming the file and
    /// the field: DRAM queues, refresh, timings, clocks, organisation and bursts; GSCore core
    /// counts; byte sizes; GPU rates and sizes; assumed unit timings.
    #[test]
    fn nonsense_values_are_refused_naming_the_file_and_field() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("c.json");
        let load = |text: &str| {
            std::fs::write(&p, text).unwrap();
            SimConfig::from_file(&p)
        };
        for (text, field) in [
            (r#"{"dram":{"write_queue":4}}"#, "dram.write_queue = 4"),
            (r#"{"dram":{"write_queue":1}}"#, "dram.write_queue = 1"),
            (r#"{"dram":{"write_queue":4294967295}}"#, "dram.write_queue"),
            (r#"{"dram":{"n_refi":288}}"#, "dram.n_refi = 288"),
            (r#"{"dram":{"n_refi":1}}"#, "dram.n_refi = 1"),
            (r#"{"dram":{"n_cl":1000000000000}}"#, "dram.n_cl"),
            (r#"{"dram":{"n_cl":18446744073709551615}}"#, "dram.n_cl"),
            (r#"{"dram":{"n_rcd":18446744073709551615}}"#, "dram.n_rcd"),
            (r#"{"dram":{"n_rcd":2000}}"#, "dram.n_rcd = 2000 > n_ras"),
            (r#"{"dram":{"n_ppd":40000}}"#, "dram.n_ppd"),
            (r#"{"dram":{"data_rate_mts":4000000,"t_ck_ps":1}}"#, "dram.data_rate_mts"),
            (r#"{"dram":{"banks":2147483648}}"#, "dram.banks"),
            (r#"{"dram":{"channels":1073741824}}"#, "dram.channels"),
            (r#"{"dram":{"line_bytes":1,"channel_bits":32,"n_bl":0,"n_ccd":0}}"#, "dram.n_bl = 0"),
            (r#"{"dram":{"line_bytes":2,"channel_bits":32,"n_bl":1,"n_ccd":0}}"#, "whole number of beats"),
            (r#"{"clock_mhz":1e-300}"#, "clock_mhz"),
            (r#"{"clock_mhz":1e308}"#, "clock_mhz"),
            (r#"{"gscore":{"core_counts":[4294967295]}}"#, "gscore.core_counts"),
            (r#"{"gscore":{"bitmap_bytes":4294967295}}"#, "gscore.bitmap_bytes"),
            (r#"{"sizes":{"gaussian_geometry_bytes":4294967295}}"#, "sizes.gaussian_geometry_bytes"),
            (r#"{"sizes":{"gaussian_sh_bytes":4294967295}}"#, "sizes.gaussian_sh_bytes"),
            (r#"{"sizes":{"feature_entry_bytes":4294967295}}"#, "sizes.feature_entry_bytes"),
            (r#"{"sizes":{"pixel_bytes":0}}"#, "sizes.pixel_bytes"),
            (r#"{"neo":{"raster_buffer_bytes":0}}"#, "neo.raster_buffer_bytes"),
            (r#"{"gpu":{"kernel_overhead_us":-1e9}}"#, "gpu.kernel_overhead_us"),
            (r#"{"gpu":{"stream_efficiency":100}}"#, "gpu.stream_efficiency"),
            (r#"{"gpu":{"key_bytes":0}}"#, "gpu.key_bytes"),
            (r#"{"gpu":{"value_bytes":0}}"#, "gpu.value_bytes"),
            (r#"{"gpu":{"record_bytes":0}}"#, "gpu.record_bytes"),
            (r#"{"gpu":{"radix_bits":4294967295}}"#, "gpu.radix_bits"),
            (r#"{"gpu":{"tile":4294967295}}"#, "gpu.tile"),
            (r#"{"preprocess":{"projection_ii":1e308}}"#, "preprocess.projection_ii"),
            (r#"{"preprocess":{"latency":18446744073709551615}}"#, "preprocess.latency"),
            (r#"{"raster_assumed":{"itu_ii":1e308}}"#, "raster_assumed.itu_ii"),
            (r#"{"raster_assumed":{"load_cycles_per_entry":-100}}"#, "raster_assumed.load_cycles_per_entry"),
            (r#"{"raster_assumed":{"scu_drain_ii":-5}}"#, "raster_assumed.scu_drain_ii"),
            (r#"{"raster_assumed":{"segment_overhead":-1e9}}"#, "raster_assumed.segment_overhead"),
        ] {
            let e = load(text).unwrap_err().to_string();
            assert!(e.contains("c.json") && e.contains(field), "{text}: {e}");
        }
        // The nearest sound values pass.
        for text in [
            r#"{"dram":{"write_queue":5}}"#,
            r#"{"dram":{"write_queue":1024}}"#,
            r#"{"dram":{"n_refi":0}}"#,
            r#"{"dram":{"banks":256,"channels":64}}"#,
            r#"{"gscore":{"core_counts":[1,64]}}"#,
            r#"{"clock_mhz":1}"#,
            r#"{"gpu":{"stream_efficiency":1}}"#,
        ] {
            load(text).unwrap_or_else(|e| panic!("{text}: {e}"));
        }
        // A huge or tiny value is echoed in exponent form, not as hundreds of digits.
        let e = load(r#"{"clock_mhz":1e300}"#).unwrap_err().to_string();
        assert!(e.contains("clock_mhz") && e.len() < 200, "{e}");
    }

    /// serde reads an array as a struct field by field: `[500]` was a 500 MHz clock and
    /// `{"dram": ["x", 2]}` a DRAM named `x` of 2 channels. Both, and `[]`, are refused.
    #[test]
    fn arrays_are_not_read_as_sections() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("C.json");
        for (text, want) in [
            ("[500]", "C.json: bad configuration: expected an object, found an array"),
            ("[]", "expected an object, found an array"),
            (r#"{"dram":["x",2]}"#, "C.json: bad configuration: dram: expected an object, found an array"),
            (r#"{"engine":[4]}"#, "engine: expected an object, found an array"),
        ] {
            std::fs::write(&p, text).unwrap();
            let e = SimConfig::from_file(&p).unwrap_err().to_string();
            assert!(e.contains(want), "{text}: {e}");
        }
    }

    /// The default configuration passes every bound, and its assumed raster timing is the one
    /// the latency reader falls back to, so using `raster_assumed` changes no default result.
    #[test]
    fn the_default_passes_the_bounds_and_assumes_the_default_raster_timing() {
        let c = SimConfig::default();
        c.check().unwrap();
        assert_eq!(c.raster_assumed, RasterTiming::default());
        for (v, what) in c.dram.timings() {
            assert!(v <= MAX_DRAM_CLOCKS, "{what}");
        }
    }
}
