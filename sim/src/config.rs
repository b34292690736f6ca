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
use std::path::Path;

use neo_golden::engine::pre::sh_record_words;
use neo_golden::engine::EngineConfig;
use neo_golden::error::{InputError, InputResult};
use neo_golden::hwpre::ShPrecision;
use neo_golden::pipeline::Preprocessing;

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

    /// Checks the organisation and that a request is one burst of `n_bl` clocks.
    pub fn check(&self) -> Result<(), String> {
        let pow2 = |v: u32, what: &str| {
            if v == 0 || !v.is_power_of_two() {
                Err(format!("dram.{what} = {v}: must be a power of two"))
            } else {
                Ok(())
            }
        };
        pow2(self.channels, "channels")?;
        pow2(self.banks, "banks")?;
        pow2(self.line_bytes, "line_bytes")?;
        pow2(self.row_bytes, "row_bytes")?;
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
        let beats = self.line_bytes as u64 * 8 / self.channel_bits as u64;
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
        if self.read_queue > 1024 {
            return Err(format!("dram.read_queue = {}: at most 1024 entries", self.read_queue));
        }
        if self.write_queue == 0 {
            return Err("dram.write_queue must be at least 1".into());
        }
        Ok(())
    }
}

impl SimConfig {
    /// Reads a JSON configuration (missing fields keep their defaults).
    pub fn from_file(path: &Path) -> InputResult<Self> {
        let text = std::fs::read_to_string(path).map_err(|e| InputError::new(path, e.to_string()))?;
        let cfg: SimConfig = serde_json::from_str(&text)
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

    /// Checks counts and sizes against each other.
    pub fn check(&self) -> Result<(), String> {
        self.dram.check()?;
        if !(self.clock_mhz > 0.0 && self.clock_mhz.is_finite()) {
            return Err(format!("clock_mhz = {}: must be positive", self.clock_mhz));
        }
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
        self.engine.validate().map_err(|e| format!("engine: {}", e.0))?;
        if self.gscore.core_counts.contains(&0) {
            return Err("gscore.core_counts must be positive".into());
        }
        if self.gscore.approx_entries_per_cycle.is_nan() || self.gscore.approx_entries_per_cycle <= 0.0 {
            return Err("gscore.approx_entries_per_cycle must be positive".into());
        }
        let g = &self.gpu;
        for (v, what) in [
            (g.peak_gbs, "gpu.peak_gbs"),
            (g.stream_efficiency, "gpu.stream_efficiency"),
            (g.gather_efficiency, "gpu.gather_efficiency"),
            (g.raster_evals_per_s, "gpu.raster_evals_per_s"),
            (g.preprocess_per_s, "gpu.preprocess_per_s"),
        ] {
            if !(v > 0.0 && v.is_finite()) {
                return Err(format!("{what} = {v}: must be positive"));
            }
        }
        if g.tile == 0 || g.radix_bits == 0 {
            return Err("gpu.tile and gpu.radix_bits must be positive".into());
        }
        let r = &self.raster_assumed;
        if !(r.itu_ii > 0.0 && r.scu_cycles_per_pair > 0.0) {
            return Err("raster_assumed.itu_ii and scu_cycles_per_pair must be positive".into());
        }
        let pp = &self.preprocess;
        if !(pp.projection_ii > 0.0 && pp.color_ii > 0.0 && pp.duplication_ii > 0.0) {
            return Err("preprocess.*_ii must be positive".into());
        }
        if self.sizes.gaussian_geometry_bytes == Some(0) || self.sizes.gaussian_sh_bytes == Some(0) {
            return Err("sizes.gaussian_*_bytes = 0: must be positive (or absent: the baked format's)".into());
        }
        if self.sizes.feature_entry_bytes == Some(0) {
            return Err("sizes.feature_entry_bytes = 0: must be positive (or absent: golden's format)".into());
        }
        Ok(())
    }

    /// Checks that the sorting-core buffers hold the double-buffered chunks of `entry_bytes`.
    pub fn check_buffers(&self, entry_bytes: u32) -> Result<(), String> {
        let need = 4 * self.engine.chunk as u64 * entry_bytes as u64;
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
}
