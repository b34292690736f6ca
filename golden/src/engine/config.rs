//! [`EngineConfig`]: the one configuration of the Neo engine. Every count and size of the
//! generated RTL (cores, units, buffers, widths, memory ports) lives here and nowhere else; it is
//! read from JSON by `neo gen --config FILE` and the other commands that take `--config`.
//!
//! Widths, networks and padding are not re-derived here: they come from the golden model
//! ([`crate::sort`], [`crate::raster`]), which is the single source of truth.

use crate::error::InputError;
use crate::sort::{Network, SortConfig, SortFormat};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Which golden comparator network the BSU instantiates.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Topology {
    /// [`Network::bitonic`] (the paper's BSU; any power-of-two width).
    Bitonic,
    /// [`Network::odd_even_merge`] (Batcher's odd-even merge sort).
    OddEvenMerge,
    /// [`Network::best_16`] (60 comparators; width 16 only).
    #[serde(rename = "best_16")]
    Best16,
}

impl Topology {
    /// Every topology, in report order.
    pub const ALL: [Topology; 3] = [Topology::Bitonic, Topology::OddEvenMerge, Topology::Best16];

    /// The name used in JSON and reports.
    pub fn name(self) -> &'static str {
        match self {
            Topology::Bitonic => "bitonic",
            Topology::OddEvenMerge => "odd_even_merge",
            Topology::Best16 => "best_16",
        }
    }
}

/// How the engine's frame controller spreads tiles over the cores (see docs/rtl.md "Engine").
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SchedulerPolicy {
    /// Tiles in index order, each to the lowest-numbered idle core.
    FirstFree,
    /// Tile `t` to sorting core `t mod N` and raster core `t mod M`.
    RoundRobin,
}

impl SchedulerPolicy {
    /// The name used in JSON and reports.
    pub fn name(self) -> &'static str {
        match self {
            SchedulerPolicy::FirstFree => "first_free",
            SchedulerPolicy::RoundRobin => "round_robin",
        }
    }
}

/// Entries of the frame controller's completion queue (`neo_frame_ctrl`): finished sorts (and
/// overflowing tiles) wait there for a raster core; a sorting core whose completion finds the
/// queue full holds it, and takes no new tile, until a slot frees.
pub const COMPLETION_QUEUE_DEPTH: usize = 4;

/// Elements of each raster core's routing FIFO (`neo_raster_feeder`, one per SCU): how many
/// walked quads the ITUs may run ahead of an SCU.
pub const ROUTING_FIFO_DEPTH: u32 = 64;

/// Entries of each AXI4 port mux's W-order FIFO (`neo_axi_mux`): AWs accepted whose W beats have
/// not all passed; the mux grants no AW while it is full.
pub const MUX_W_FIFO_DEPTH: u32 = 4;

/// Write slots of each AXI4 bridge (`neo_axi_sort_bridge`, `neo_axi_raster_bridge`): one AW
/// register and two W registers (`w_v_q`, `w2_v_q`), so a single-beat write's W can wait for
/// the mux while the next write's AW goes out.
pub const BRIDGE_W_SLOTS: u32 = 2;

/// The largest raster reorder window the generator builds ([`EngineConfig::raster_window`]):
/// its cells compare in parallel, one comparator per entry.
pub const MAX_RASTER_WINDOW: usize = 4096;

/// Checks a raster core's reorder window ([`EngineConfig::raster_window`]): 1 (no window) or a
/// power of two in 4..=[`MAX_RASTER_WINDOW`]. The error starts with the window's value.
pub fn check_raster_window(w: usize) -> Result<(), String> {
    if w == 1 || (w.is_power_of_two() && (4..=MAX_RASTER_WINDOW).contains(&w)) {
        Ok(())
    } else {
        Err(format!("{w} is neither 1 (no window) nor a power of two in 4..={MAX_RASTER_WINDOW}"))
    }
}

/// Parameters of the generated RTL. [`EngineConfig::default`] is the paper's configuration.
///
/// JSON: an object with any subset of these fields (missing ones take the default), e.g.
/// `{"topology": "best_16", "register_every": 3}`. Unknown fields are rejected.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct EngineConfig {
    /// BSU comparator network.
    pub topology: Topology,
    /// BSU width `n` (entries per vector): a power of two >= 2; 16 for `best_16`.
    pub bsu_width: usize,
    /// `k`: a register stage after every `k` comparator layers (and after the last layer), so
    /// the BSU latency is `ceil(depth / k)` cycles. Must be >= 1 (`k >= depth`: one stage).
    pub register_every: usize,
    /// Key field width (golden [`SortFormat`]).
    pub key_bits: u8,
    /// Id field width (golden [`SortFormat`]).
    pub id_bits: u8,
    /// Chunk size `C` of the conventional sort and of Neo's DPS (entries): `n` times a power
    /// of two.
    pub chunk: usize,
    /// The wide DPS chunk `W = dps_wide * C` as a multiple of the chunk (a power of two in
    /// 1..=64; 1: none, the paper's engine). The Sorting Core's four buffers hold `W` entries
    /// ([`EngineConfig::sort_buffer`]), and a tile descriptor's `dps_wide` bit runs its DPS
    /// passes in chunks of `W` (golden `adaptive` with `wide` = this value). Area: the buffers
    /// grow `dps_wide` times (24 KiB a buffer at 16 and 48-bit entries).
    pub dps_wide: usize,
    /// Width of memory entry addresses and command addresses.
    pub addr_bits: u32,
    /// Width of command lengths and `done_len_o`.
    pub len_bits: u32,
    /// Longest memory read burst (entries), a power of two <= `chunk`.
    pub burst: usize,
    /// Read bursts in flight at most (depth of the response-routing queue), a power of two.
    pub max_outstanding: usize,
    /// Tile side in pixels (a power of two; 64 in the paper, Table 1).
    pub tile: u32,
    /// Subtile side in pixels (a power of two dividing `tile`, at most 64 subtiles per tile; 8
    /// in the paper).
    pub subtile: u32,
    /// ITU: width of the tile indices `tile_x_i` / `tile_y_i` (unsigned; the tile origin is
    /// `tile_x * tile` pixels). 10 bits cover images up to 65536 px wide at 64-pixel tiles.
    pub tile_bits: u32,
    /// ITU: width of the sideband tag carried from `tag_i` to `tag_o` unchanged.
    pub itu_tag_bits: u32,
    /// SCU: pixel lanes (a power of two dividing the subtile's pixel count; each Gaussian
    /// takes `pixels / scu_lanes` cycles). 16 by default (see docs/rtl.md "SCU").
    pub scu_lanes: usize,
    /// Raster core: ITUs (`neo_itu` instances; the table is tested this many entries per
    /// cycle). 4 in the paper (Table 1).
    pub raster_itus: usize,
    /// Raster core: SCUs (`neo_scu` instances), a power of two in 1..=32 dividing the subtile
    /// count: the subtiles are blended in groups of this many, one per SCU. 4 in the paper.
    pub raster_scus: usize,
    /// Raster core: entries of one feature-buffer bank (a power of two, a multiple of
    /// `raster_itus`). A longer table is processed in segments of this many entries, each
    /// loaded once and walked for every subtile group (see docs/rtl.md "Raster core").
    pub raster_feature_buffer: usize,
    /// Raster core: feature-buffer banks (a power of two in 2..=8): the loader fills the next
    /// banks while the walk and the SCUs use the oldest.
    pub raster_feature_banks: usize,
    /// Raster core: entries of the reorder window between the feature reads and the buffer
    /// banks (golden [`crate::raster::window`], docs/adaptive.md section 7): 1 (the default, the
    /// paper's core: no window, nothing of it is generated) or a power of two in
    /// 4..=[`MAX_RASTER_WINDOW`]. The core blends, and writes the table back, in the window's
    /// order. Left out of the JSON (and so of [`EngineConfig::hash`]) when 1, so every
    /// configuration written before the field keeps its hash.
    #[serde(skip_serializing_if = "crate::raster::window::is_no_window")]
    pub raster_window: usize,
    /// Engine: Sorting Cores (`neo_sort_core` instances). 16 in the paper (Table 1).
    pub sort_cores: usize,
    /// Engine: Rasterization Cores (`neo_raster_core` instances). 4 in the paper.
    pub raster_cores: usize,
    /// Engine: how tiles are spread over the cores.
    pub scheduler: SchedulerPolicy,
    /// Engine: entries of one tile's table region in memory. A merged table longer than this
    /// is cut to the nearest `table_capacity` entries and the overflow is reported.
    pub table_capacity: usize,
    /// Engine: AXI4 manager ports to memory (the memory channels).
    pub mem_channels: usize,
    /// Engine: AXI4 data width in bits: [`AXI_DATA_BITS`], the only width the raster bridge is
    /// generated for (the field names it in configurations and reports).
    pub axi_data_bits: u32,
    /// Engine: AXI4 byte-address width (32..=64).
    pub axi_addr_bits: u32,
    /// Engine: AXI4 ID width of each manager port.
    pub axi_id_bits: u32,
    /// Engine: AXI4 transactions a requester may have in flight (reads and writes each).
    pub axi_outstanding: usize,
    /// Preprocessing Engine: projection, colour, duplication and fetch units, one of each per
    /// lane (Table 1: 4). 0: an engine without a Preprocessing Engine (the host writes every
    /// frame's features and incoming lists; `PRE_CTRL` is stored and ignored).
    pub pre_units: usize,
    /// Preprocessing Engine: 64-byte lines each fetch unit (`neo_pre_fetch`) keeps in flight,
    /// its read window and the size of its beat buffer (a power of two). Little's law: one unit
    /// streaming a quarter of 51.2 GB/s through about 400 ns of read latency needs 80.
    pub pre_read_lines: usize,
    /// Preprocessing Engine: read bursts each fetch unit keeps in flight (a power of two). Its
    /// full bursts are the window over this, so streams fill the window; gathers of one SH
    /// record each (24 beats at degree 3) need `window / 24` of them.
    pub pre_outstanding: usize,
    /// Preprocessing Engine: tiles the list writer (`neo_pre_lists`) keeps a counter and a
    /// 64-byte line of incoming entries for (a power of two; QHD has 920 tiles of 64 pixels).
    /// Each tile's list region is `table_capacity` rounded up to whole 8-entry lines
    /// ([`EngineConfig::list_stride`]).
    pub pre_max_tiles: usize,
}

impl Default for EngineConfig {
    fn default() -> Self {
        let f = SortFormat::ARTIFACT;
        EngineConfig {
            topology: Topology::Bitonic,
            bsu_width: 16,
            register_every: 2,
            key_bits: f.key_bits(),
            id_bits: f.id_bits(),
            chunk: SortConfig::DEFAULT_CHUNK,
            dps_wide: 1,
            addr_bits: 32,
            len_bits: 32,
            burst: 16,
            max_outstanding: 4,
            tile: 64,
            subtile: 8,
            tile_bits: 10,
            itu_tag_bits: 16,
            scu_lanes: 16,
            raster_itus: 4,
            raster_scus: 4,
            raster_feature_buffer: 256,
            raster_feature_banks: 2,
            raster_window: 1,
            sort_cores: 16,
            raster_cores: 4,
            scheduler: SchedulerPolicy::FirstFree,
            table_capacity: 1 << 16,
            mem_channels: 4,
            axi_data_bits: AXI_DATA_BITS,
            axi_addr_bits: 32,
            axi_id_bits: 4,
            axi_outstanding: 8,
            pre_units: 4,
            pre_read_lines: 128,
            pre_outstanding: 64,
            pre_max_tiles: 2048,
        }
    }
}

/// The AXI4 data width of the engine's ports: the raster bridge packs two 32-bit pixels a beat.
pub const AXI_DATA_BITS: u32 = 64;

/// The most Sorting Cores an engine may have (`sort_cores`).
pub const MAX_SORT_CORES: usize = 64;

/// A configuration the generator cannot honour.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("invalid engine configuration: {0}")]
pub struct ConfigError(pub String);

impl EngineConfig {
    /// Reads a JSON configuration file; errors name the file and the problem.
    pub fn from_json_file(path: &Path) -> Result<EngineConfig, InputError> {
        let text =
            std::fs::read_to_string(path).map_err(|e| InputError::new(path, format!("cannot read: {e}")))?;
        let cfg: EngineConfig = crate::json_shape::parse_shaped(&text, &EngineConfig::default())
            .map_err(|e| InputError::new(path, format!("not a valid engine configuration: {e}")))?;
        cfg.validate().map_err(|e| InputError::new(path, e.0))?;
        Ok(cfg)
    }

    /// The entry format (golden).
    ///
    /// # Panics
    /// When the widths are invalid (call [`EngineConfig::validate`] first).
    pub fn format(&self) -> SortFormat {
        SortFormat::new(self.key_bits, self.id_bits).expect("validated key/id widths")
    }

    /// The BSU network (golden), for this topology and width.
    ///
    /// # Panics
    /// When the topology/width pair is invalid (call [`EngineConfig::validate`] first).
    pub fn network(&self) -> Network {
        match self.topology {
            Topology::Bitonic => Network::bitonic(self.bsu_width),
            Topology::OddEvenMerge => Network::odd_even_merge(self.bsu_width),
            Topology::Best16 => {
                assert_eq!(self.bsu_width, 16, "best_16 is a 16-input network");
                Network::best_16()
            }
        }
    }

    /// The golden Sorting Core configuration this RTL implements (format, chunk, network).
    ///
    /// # Panics
    /// When the configuration is invalid (call [`EngineConfig::validate`] first).
    pub fn sort_config(&self) -> SortConfig {
        SortConfig::new(self.format(), self.chunk, self.network()).expect("validated sort configuration")
    }

    /// A stable 64-bit hash of the configuration (FNV-1a over its canonical JSON, every field
    /// written): printed in every generated file's header and recorded with measurements.
    pub fn hash(&self) -> u64 {
        let text = serde_json::to_string(self).expect("a EngineConfig always serialises");
        text.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, b| (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3))
    }

    /// The first field (in alphabetical order) whose value differs from `other`'s, with this
    /// configuration's value and `other`'s, as JSON text.
    pub fn first_difference(&self, other: &EngineConfig) -> Option<(String, String, String)> {
        let (a, b) = (serde_json::to_value(self).ok()?, serde_json::to_value(other).ok()?);
        let (a, b) = (a.as_object()?, b.as_object()?);
        a.iter().find_map(|(k, va)| match b.get(k) {
            Some(vb) if vb == va => None,
            vb => Some((k.clone(), va.to_string(), vb.map_or("(absent)".to_string(), |v| v.to_string()))),
        })
    }

    /// Checks every constraint, naming the first one violated.
    pub fn validate(&self) -> Result<(), ConfigError> {
        let err = |s: String| Err(ConfigError(s));
        SortFormat::new(self.key_bits, self.id_bits).map_err(|e| ConfigError(e.to_string()))?;
        let n = self.bsu_width;
        if n < 2 || !n.is_power_of_two() || n > 64 {
            return err(format!("bsu_width {n} is not a power of two in 2..=64"));
        }
        if self.topology == Topology::Best16 && n != 16 {
            return err(format!("topology best_16 needs bsu_width 16, got {n}"));
        }
        if self.register_every == 0 {
            return err("register_every must be >= 1 (use a value >= the network depth for one stage)".into());
        }
        if self.chunk > 1 << 16 {
            return err(format!("chunk {} exceeds 65536 entries", self.chunk));
        }
        SortConfig::new(self.format(), self.chunk, self.network()).map_err(|e| ConfigError(e.to_string()))?;
        if !(8..=48).contains(&self.addr_bits) {
            return err(format!("addr_bits {} is outside 8..=48", self.addr_bits));
        }
        if !(12..=48).contains(&self.len_bits) {
            return err(format!("len_bits {} is outside 12..=48", self.len_bits));
        }
        if (self.chunk as u64) >= 1u64 << self.len_bits {
            return err(format!("chunk {} does not fit len_bits {}", self.chunk, self.len_bits));
        }
        self.validate_dps_wide()?;
        if !self.burst.is_power_of_two() || self.burst > self.chunk {
            return err(format!("burst {} is not a power of two <= chunk {}", self.burst, self.chunk));
        }
        if !self.max_outstanding.is_power_of_two() || !(2..=64).contains(&self.max_outstanding) {
            return err(format!("max_outstanding {} is not a power of two in 2..=64", self.max_outstanding));
        }
        let (t, st) = (self.tile, self.subtile);
        if !t.is_power_of_two() || !st.is_power_of_two() || !(2..=256).contains(&t) || st >= t || (t / st) > 8
        {
            return err(format!(
                "tile {t} and subtile {st} must be powers of two with 2 <= subtile < tile <= 256 and at most 64 subtiles"
            ));
        }
        if !(1..=16).contains(&self.tile_bits) {
            return err(format!("tile_bits {} is outside 1..=16", self.tile_bits));
        }
        if !(1..=64).contains(&self.itu_tag_bits) {
            return err(format!("itu_tag_bits {} is outside 1..=64", self.itu_tag_bits));
        }
        let pixels = (self.raster_config().subtile * self.raster_config().subtile) as usize;
        if !self.scu_lanes.is_power_of_two() || self.scu_lanes < 2 || self.scu_lanes > pixels {
            return err(format!("scu_lanes {} is not a power of two in 2..={pixels}", self.scu_lanes));
        }
        self.validate_raster_core()?;
        self.validate_engine()?;
        Ok(())
    }

    /// The wide DPS chunk: a power of two in 1..=64 whose buffer fits 65536 entries, `len_bits`
    /// and the table capacity.
    fn validate_dps_wide(&self) -> Result<(), ConfigError> {
        let w = self.dps_wide;
        if !w.is_power_of_two() || w > 64 {
            return Err(ConfigError(format!("dps_wide {w} is not a power of two in 1..=64")));
        }
        let b = self.chunk.saturating_mul(w);
        if w > 1 && (b > 1 << 16 || (b as u64) >= 1u64 << self.len_bits || b > self.table_capacity) {
            return Err(ConfigError(format!(
                "dps_wide {w}: the wide chunk of {b} entries (chunk {} x {w}) exceeds 65536 entries, len_bits {} or table_capacity {}",
                self.chunk, self.len_bits, self.table_capacity
            )));
        }
        Ok(())
    }

    /// Entries of each Sorting Core buffer: the wide DPS chunk `dps_wide * chunk` (the chunk
    /// without one). A chunk command sorts at most this many entries.
    pub fn sort_buffer(&self) -> usize {
        self.chunk * self.dps_wide
    }

    /// The DPS chunk of a tile whose descriptor's `dps_wide` bit is `wide`.
    pub fn dps_chunk(&self, wide: bool) -> usize {
        if wide {
            self.sort_buffer()
        } else {
            self.chunk
        }
    }

    /// A golden Sorting Core whose chunk is the buffer ([`EngineConfig::sort_buffer`]): what
    /// one chunk command of the RTL does.
    pub fn buffer_sort_config(&self) -> SortConfig {
        SortConfig::new(self.format(), self.sort_buffer(), self.network()).expect("validated sort buffer")
    }

    /// The engine's constraints: counts, the table region and the AXI4 ports.
    fn validate_engine(&self) -> Result<(), ConfigError> {
        let err = |s: String| Err(ConfigError(s));
        if !(1..=MAX_SORT_CORES).contains(&self.sort_cores) {
            return err(format!("sort_cores {} is outside 1..={MAX_SORT_CORES}", self.sort_cores));
        }
        if !(1..=16).contains(&self.raster_cores) {
            return err(format!("raster_cores {} is outside 1..=16", self.raster_cores));
        }
        if self.table_capacity < self.chunk || (self.table_capacity as u64) >= 1u64 << self.len_bits {
            return err(format!(
                "table_capacity {} is below chunk {} or does not fit len_bits {}",
                self.table_capacity, self.chunk, self.len_bits
            ));
        }
        // The frame controller places the cores' scratch regions, two of table_capacity entries
        // per core, one after the other at addr_bits-bit entry addresses.
        let scratch = 2 * self.sort_cores as u128 * self.table_capacity as u128;
        if scratch > 1u128 << self.addr_bits {
            return err(format!(
                "table_capacity {} does not fit addr_bits {}: the scratch regions of sort_cores {} (2 x table_capacity entries each) need {scratch} entry addresses",
                self.table_capacity, self.addr_bits, self.sort_cores
            ));
        }
        if !(1..=16).contains(&self.mem_channels) {
            return err(format!("mem_channels {} is outside 1..=16", self.mem_channels));
        }
        let d = self.axi_data_bits;
        if d != AXI_DATA_BITS {
            return err(format!(
                "axi_data_bits {d} is not {AXI_DATA_BITS}: the raster bridge packs two pixels a beat, so the engine is generated for {AXI_DATA_BITS}-bit data only"
            ));
        }
        if !(32..=64).contains(&self.axi_addr_bits) {
            return err(format!("axi_addr_bits {} is outside 32..=64", self.axi_addr_bits));
        }
        if !(1..=16).contains(&self.axi_id_bits) {
            return err(format!("axi_id_bits {} is outside 1..=16", self.axi_id_bits));
        }
        // Each port's mux prefixes the ID with the client's slot: ceil(clients / ports) slots.
        let clients = self.memory_clients();
        let slots = self.port_slots();
        let slot_bits = usize::BITS - (slots - 1).leading_zeros();
        if slot_bits > self.axi_id_bits {
            return err(format!(
                "axi_id_bits {} cannot hold the slot index: {clients} memory clients on {} ports need {slot_bits}",
                self.axi_id_bits, self.mem_channels
            ));
        }
        let o = self.axi_outstanding;
        if !o.is_power_of_two() || !(1..=64).contains(&o) {
            return err(format!("axi_outstanding {o} is not a power of two in 1..=64"));
        }
        self.validate_preprocessing()
    }

    /// The Preprocessing Engine's constraints: its unit count and the fetch units' window, which
    /// `pre_outstanding` bursts of at most 256 beats and 4 KiB must cover.
    fn validate_preprocessing(&self) -> Result<(), ConfigError> {
        let err = |s: String| Err(ConfigError(s));
        if self.pre_units != 0 && (!self.pre_units.is_power_of_two() || self.pre_units > 16) {
            return err(format!(
                "pre_units {} is neither 0 (no Preprocessing Engine) nor a power of two in 1..=16 (the lanes split the Gaussians by a shift)",
                self.pre_units
            ));
        }
        let (l, o) = (self.pre_read_lines, self.pre_outstanding);
        if !o.is_power_of_two() || !(1..=256).contains(&o) {
            return err(format!("pre_outstanding {o} is not a power of two in 1..=256"));
        }
        let beat = self.axi_data_bits as usize / 8;
        if !l.is_power_of_two() || !(1..=1024).contains(&l) || l * 64 < beat * o {
            return err(format!(
                "pre_read_lines {l} is not a power of two in 1..=1024 holding pre_outstanding {o} beats of {beat} bytes"
            ));
        }
        let t = self.pre_max_tiles;
        if !t.is_power_of_two() || !(2..=65536).contains(&t) {
            return err(format!("pre_max_tiles {t} is not a power of two in 2..=65536"));
        }
        if self.pre_burst_beats() > 256 || self.pre_burst_beats() * beat > 4096 {
            return err(format!(
                "pre_read_lines {l}: bursts of {} beats (the window over pre_outstanding {o}) exceed 256 beats or 4 KiB",
                self.pre_burst_beats()
            ));
        }
        Ok(())
    }

    /// Whether the engine has a Preprocessing Engine (`pre_units` > 0).
    pub fn has_preprocessing(&self) -> bool {
        self.pre_units > 0
    }

    /// The Preprocessing Engine's AXI4 managers: two per lane (lane `p`'s geometry and feature
    /// port at `p`, its SH and previous-word port at `pre_units + p`) and the list writer at
    /// `2 pre_units`; none without a Preprocessing Engine.
    pub fn pre_managers(&self) -> usize {
        if self.has_preprocessing() {
            2 * self.pre_units + 1
        } else {
            0
        }
    }

    /// The Gaussians lane `lane` of the Preprocessing Engine takes out of `gaussians`:
    /// `(first, count)`, consecutive ranges of `ceil(gaussians / pre_units)` (the last ones
    /// shorter or empty); `(0, 0)` without a Preprocessing Engine.
    pub fn pre_lane_range(&self, gaussians: u32, lane: usize) -> (u32, u32) {
        if !self.has_preprocessing() {
            return (0, 0);
        }
        let share = (gaussians as u64).div_ceil(self.pre_units as u64);
        let first = (share * lane as u64).min(gaussians as u64);
        let end = (first + share).min(gaussians as u64);
        (first as u32, (end - first) as u32)
    }

    /// The lane of the Preprocessing Engine that takes Gaussian `id` of `gaussians`: the one whose
    /// [`EngineConfig::pre_lane_range`] holds it (`id / ceil(gaussians / pre_units)`); 0 without a
    /// Preprocessing Engine or for an id past the last Gaussian.
    pub fn pre_lane_of(&self, gaussians: u32, id: u64) -> usize {
        if !self.has_preprocessing() || id >= gaussians as u64 {
            return 0;
        }
        (id / (gaussians as u64).div_ceil(self.pre_units as u64)) as usize
    }

    /// Entries between two tiles' incoming lists as the list writer lays them out:
    /// `table_capacity` rounded up to a whole number of 8-entry (64-byte) lines.
    pub fn list_stride(&self) -> usize {
        self.table_capacity.next_multiple_of(8)
    }

    /// Beats of a fetch unit's window (`pre_read_lines` lines of 64 bytes).
    pub fn pre_window_beats(&self) -> usize {
        self.pre_read_lines * 64 / (self.axi_data_bits as usize / 8)
    }

    /// Beats of a fetch unit's full burst: its window over `pre_outstanding`, so that the
    /// bursts in flight fill the window.
    pub fn pre_burst_beats(&self) -> usize {
        self.pre_window_beats() / self.pre_outstanding
    }

    /// The raster core's constraints (see the fields' docs).
    fn validate_raster_core(&self) -> Result<(), ConfigError> {
        let err = |s: String| Err(ConfigError(s));
        let subtiles = self.raster_config().subtiles_per_tile() as usize;
        if !(1..=16).contains(&self.raster_itus) {
            return err(format!("raster_itus {} is outside 1..=16", self.raster_itus));
        }
        let c = self.raster_scus;
        if !c.is_power_of_two() || c > 32 || !subtiles.is_multiple_of(c) || subtiles / c < 2 {
            return err(format!(
                "raster_scus {c} is not a power of two in 1..=32 leaving at least two groups of {subtiles} subtiles"
            ));
        }
        let f = self.raster_feature_buffer;
        if !f.is_power_of_two()
            || !f.is_multiple_of(self.raster_itus)
            || !(4..=4096).contains(&f)
            || f < 2 * self.raster_itus
        {
            return err(format!(
                "raster_feature_buffer {f} is not a power of two in 4..=4096, a multiple of raster_itus {} and at least twice it",
                self.raster_itus
            ));
        }
        let b = self.raster_feature_banks;
        if !b.is_power_of_two() || !(2..=8).contains(&b) {
            return err(format!("raster_feature_banks {b} is not a power of two in 2..=8"));
        }
        if (f as u64) >= 1u64 << self.len_bits {
            return err(format!("raster_feature_buffer {f} does not fit len_bits {}", self.len_bits));
        }
        check_raster_window(self.raster_window).map_err(|e| ConfigError(format!("raster_window {e}")))
    }

    /// The feature-entry format of the Rasterization Engine (golden default).
    pub fn feature_format(&self) -> crate::formats::feature::FeatureFormat {
        crate::formats::feature::FeatureFormat::default()
    }

    /// The tile geometry of the Rasterization Engine (`tile`, `subtile`) with golden's default
    /// SCU widths.
    pub fn raster_config(&self) -> crate::raster::RasterConfig {
        crate::raster::RasterConfig { tile: self.tile, subtile: self.subtile, ..Default::default() }
    }

    /// Width of a packed `{valid, key, id}` entry.
    pub fn entry_bits(&self) -> u32 {
        self.format().entry_bits()
    }

    /// Width of the comparison value (the low `key_bits + id_bits` bits).
    pub fn cmp_bits(&self) -> u32 {
        self.key_bits as u32 + self.id_bits as u32
    }

    /// BSU latency in cycles: the number of register stages, `ceil(depth / k)`.
    pub fn bsu_latency(&self) -> usize {
        self.network().depth().div_ceil(self.register_every)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_hash_changes_with_every_field_and_is_stable() {
        let base = EngineConfig::default();
        assert_eq!(base.hash(), EngineConfig::default().hash());
        let variants = [
            EngineConfig { bsu_width: 32, ..base.clone() },
            EngineConfig { scu_lanes: 8, ..base.clone() },
            EngineConfig { raster_feature_banks: 4, ..base.clone() },
            EngineConfig { topology: Topology::OddEvenMerge, ..base.clone() },
            EngineConfig { sort_cores: 8, ..base.clone() },
            EngineConfig { mem_channels: 2, ..base.clone() },
            EngineConfig { pre_units: 2, ..base.clone() },
            EngineConfig { pre_read_lines: 64, ..base.clone() },
            EngineConfig { pre_outstanding: 32, ..base.clone() },
            EngineConfig { pre_max_tiles: 1024, ..base.clone() },
            EngineConfig { raster_window: 16, ..base.clone() },
        ];
        for v in &variants {
            assert_ne!(v.hash(), base.hash(), "{v:?}");
        }
    }

    #[test]
    fn first_difference_names_the_field_and_both_values() {
        let base = EngineConfig::default();
        assert_eq!(base.first_difference(&base), None);
        let other = EngineConfig { bsu_width: 32, ..base.clone() };
        assert_eq!(base.first_difference(&other), Some(("bsu_width".into(), "16".into(), "32".into())));
        let other = EngineConfig { scheduler: SchedulerPolicy::RoundRobin, ..base.clone() };
        let d = base.first_difference(&other).unwrap();
        assert_eq!((d.0.as_str(), d.2.as_str()), ("scheduler", "\"round_robin\""));
    }

    #[test]
    fn default_is_the_paper_configuration() {
        let c = EngineConfig::default();
        c.validate().unwrap();
        assert_eq!(c.entry_bits(), SortFormat::ARTIFACT.entry_bits());
        assert_eq!(c.sort_config(), SortConfig::artifact());
        assert_eq!(c.network().comparator_count(), 80);
        assert_eq!(c.bsu_latency(), 5);
    }

    /// The window is left out of the JSON at 1, so the hash of every configuration written
    /// before the field is unchanged; any other accepted value is written and read back.
    #[test]
    fn the_raster_window_is_written_only_when_there_is_one() {
        let base = EngineConfig::default();
        assert!(!serde_json::to_string(&base).unwrap().contains("raster_window"));
        for w in [4, 64, MAX_RASTER_WINDOW] {
            let c = EngineConfig { raster_window: w, ..base.clone() };
            c.validate().unwrap();
            let text = serde_json::to_string(&c).unwrap();
            assert!(text.contains(&format!("\"raster_window\":{w}")), "{text}");
            assert_eq!(serde_json::from_str::<EngineConfig>(&text).unwrap(), c);
        }
        let e = EngineConfig { raster_window: 24, ..base }.validate().unwrap_err().to_string();
        assert!(e.contains("raster_window 24"), "{e}");
    }

    #[test]
    fn json_subset_overrides_defaults() {
        let c: EngineConfig =
            serde_json::from_str(r#"{"topology": "best_16", "register_every": 3}"#).unwrap();
        assert_eq!(c.topology, Topology::Best16);
        assert_eq!(c.register_every, 3);
        assert_eq!(c.chunk, 256);
        assert_eq!(c.bsu_latency(), 4);
        assert!(serde_json::from_str::<EngineConfig>(r#"{"topolgy": "bitonic"}"#).is_err());
        assert!(serde_json::from_str::<EngineConfig>(r#"{"topology": "odd_even_merge"}"#).is_ok());
    }

    #[test]
    fn invalid_configs_are_rejected() {
        let bad = [
            EngineConfig { register_every: 0, ..EngineConfig::default() },
            EngineConfig { bsu_width: 12, ..EngineConfig::default() },
            EngineConfig { topology: Topology::Best16, bsu_width: 8, chunk: 64, ..EngineConfig::default() },
            EngineConfig { chunk: 200, ..EngineConfig::default() },
            EngineConfig { key_bits: 0, ..EngineConfig::default() },
            EngineConfig { burst: 3, ..EngineConfig::default() },
            EngineConfig { max_outstanding: 1, ..EngineConfig::default() },
            EngineConfig { tile_bits: 0, ..EngineConfig::default() },
            EngineConfig { tile_bits: 17, ..EngineConfig::default() },
            EngineConfig { itu_tag_bits: 0, ..EngineConfig::default() },
            EngineConfig { sort_cores: 0, ..EngineConfig::default() },
            EngineConfig { tile: 48, ..EngineConfig::default() },
            EngineConfig { subtile: 2, ..EngineConfig::default() },
            EngineConfig { raster_cores: 0, ..EngineConfig::default() },
            EngineConfig { mem_channels: 0, ..EngineConfig::default() },
            EngineConfig { table_capacity: 100, ..EngineConfig::default() },
            EngineConfig { axi_data_bits: 48, ..EngineConfig::default() },
            EngineConfig { axi_outstanding: 3, ..EngineConfig::default() },
            EngineConfig { axi_id_bits: 2, ..EngineConfig::default() },
            EngineConfig { pre_units: 3, ..EngineConfig::default() },
            EngineConfig { pre_units: 32, ..EngineConfig::default() },
            // 1 + 16 + 4 + 2 x 16 + 1 = 54 clients on 2 ports: 27 slots need 5 ID bits.
            EngineConfig { pre_units: 16, mem_channels: 2, ..EngineConfig::default() },
            EngineConfig { pre_read_lines: 96, ..EngineConfig::default() },
            // 64 outstanding bursts do not fit a window of 1 line (8 beats).
            EngineConfig { pre_read_lines: 1, ..EngineConfig::default() },
            // 1 burst of 512 beats: above 256 beats.
            EngineConfig { pre_read_lines: 64, pre_outstanding: 1, ..EngineConfig::default() },
            EngineConfig { pre_outstanding: 48, ..EngineConfig::default() },
            EngineConfig { pre_max_tiles: 1000, ..EngineConfig::default() },
            EngineConfig { raster_window: 0, ..EngineConfig::default() },
            EngineConfig { raster_window: 2, ..EngineConfig::default() },
            EngineConfig { raster_window: 24, ..EngineConfig::default() },
            EngineConfig { raster_window: 2 * MAX_RASTER_WINDOW, ..EngineConfig::default() },
        ];
        for c in bad {
            assert!(c.validate().is_err(), "{c:?}");
        }
    }

    #[test]
    fn bad_file_errors_name_the_file() {
        let dir = std::env::temp_dir().join(format!("neo-gen-cfg-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("bad.json");
        std::fs::write(&p, "{\"bsu_width\": 12}").unwrap();
        let e = EngineConfig::from_json_file(&p).unwrap_err().to_string();
        assert!(e.starts_with(&p.display().to_string()) && e.contains("bsu_width 12"), "{e}");
        std::fs::write(&p, "not json").unwrap();
        let e = EngineConfig::from_json_file(&p).unwrap_err().to_string();
        assert!(e.contains("bad.json") && e.contains("not a valid engine configuration"), "{e}");
        let e = EngineConfig::from_json_file(&dir.join("missing.json")).unwrap_err().to_string();
        assert!(e.contains("missing.json") && e.contains("cannot read"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    proptest::proptest! {
        /// The lanes' ranges cover the Gaussians in order, each one once, and `pre_lane_of` names
        /// the lane whose range holds a Gaussian.
        #[test]
        fn lane_ranges_partition_the_gaussians(gaussians in 0u32..3_000_000, log_units in 0u32..5) {
            let c = EngineConfig { pre_units: 1 << log_units, ..EngineConfig::default() };
            let mut next = 0;
            for lane in 0..c.pre_units {
                let (first, count) = c.pre_lane_range(gaussians, lane);
                proptest::prop_assert_eq!(first, next);
                for id in [first, first + count / 2, (first + count).saturating_sub(1)] {
                    if count > 0 {
                        proptest::prop_assert_eq!(c.pre_lane_of(gaussians, id as u64), lane);
                    }
                }
                proptest::prop_assert!(count as u64 <= (gaussians as u64).div_ceil(c.pre_units as u64));
                next = first + count;
            }
            proptest::prop_assert_eq!(next, gaussians);
        }

        /// Any values of the fields: validation answers without panicking, and a configuration it
        /// accepts gives its derived values (format, network, sort and raster configs) without
        /// panicking either.
        #[test]
        fn validation_never_panics_and_accepted_configs_derive(
            bsu in 0usize..80, chunk in 0usize..5000, burst in 0usize..300, tile in 0u32..300,
            subtile in 0u32..40, lanes in 0usize..80, scus in 0usize..40, itus in 0usize..20,
            fbuf in 0usize..5000, cores in 0usize..70, cap in 0usize..70000, data in 0u32..2000,
            key in 0u8..40, id in 0u8..40, topo in 0usize..3, lines in 0usize..3000,
            outstanding in 0usize..300, wide_log in 0u32..8, window in 0usize..10_000,
        ) {
            let c = EngineConfig {
                topology: Topology::ALL[topo], bsu_width: bsu, chunk, burst, tile, subtile,
                scu_lanes: lanes, raster_scus: scus, raster_itus: itus, raster_feature_buffer: fbuf,
                sort_cores: cores, table_capacity: cap, axi_data_bits: data, key_bits: key,
                id_bits: id, pre_read_lines: lines, pre_outstanding: outstanding, dps_wide: 1 << wide_log,
                raster_window: window,
                ..EngineConfig::default()
            };
            if c.validate().is_ok() {
                let _ = (c.format(), c.network(), c.sort_config(), c.raster_config(), c.bsu_latency());
                let _ = c.buffer_sort_config();
                let (window, burst) = (c.pre_window_beats(), c.pre_burst_beats());
                proptest::prop_assert!((1..=256).contains(&burst) && burst * c.pre_outstanding == window);
                proptest::prop_assert!(c.raster_config().subtiles_per_tile() <= 64);
            }
        }
    }

    #[test]
    fn clients_are_dealt_round_the_ports_one_slot_each() {
        for (sort_cores, raster_cores, pre_units, mem_channels) in
            [(16, 4, 4, 4), (2, 1, 1, 2), (1, 1, 1, 1), (3, 2, 2, 4), (16, 4, 0, 3), (2, 1, 0, 16)]
        {
            let cfg =
                EngineConfig { sort_cores, raster_cores, pre_units, mem_channels, ..EngineConfig::default() };
            let (n, k, slots) = (cfg.memory_clients(), mem_channels, cfg.port_slots());
            let places: Vec<(usize, usize)> = (0..n).map(|c| cfg.client_port_slot(c)).collect();
            for (c, &(port, slot)) in places.iter().enumerate() {
                assert!(port < k && slot < slots, "{cfg:?}: client {c} at {port}, {slot}");
                assert_eq!(cfg.port_slot_client(port, slot), c, "{cfg:?}: client {c}");
            }
            let mut distinct = places.clone();
            distinct.sort_unstable();
            distinct.dedup();
            assert_eq!(distinct.len(), n, "{cfg:?}: two clients share a slot");
            // The ports' loads differ by one client at most; the fullest uses every slot.
            let load = |p: usize| places.iter().filter(|q| q.0 == p).count();
            let (lo, hi) = ((0..k).map(load).min().unwrap(), (0..k).map(load).max().unwrap());
            assert!(hi - lo <= 1 && hi == slots, "{cfg:?}: loads {lo}..{hi}, {slots} slots");
        }
        // The default engine: client 5 (sort core 4) on port 1, slot 1.
        assert_eq!(EngineConfig::default().client_port_slot(5), (1, 1));
    }
}
