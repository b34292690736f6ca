//! The engine's control port: the AXI4-Lite register map (32-bit data, 12-bit byte addresses),
//! the STATUS bits and the performance counters (docs/formats.md "Engine control registers").
//!
//! This is the one definition of the map: the generator decodes [`Reg::offset`] and
//! [`Counter::offset`], the test benches program [`FrameRegs::writes`] and read the counters
//! back with [`Counter::ALL`].
//!
//! Port behaviour (the RTL `neo_engine_regs` and the test benches' model follow it): accesses are
//! to 32-bit words (byte address bits `[1:0]` ignored); WSTRB selects the bytes written, and a
//! start needs byte 0 enabled. Reads of write-only registers ([`Access::W`]) return 0, writes
//! to read-only ones ([`Access::R`]) are ignored, and an unmapped word (neither a [`Reg`] nor a
//! counter word) reads 0 and ignores writes. Every response is OKAY: the port never answers
//! SLVERR or DECERR, so a host that writes a wrong address learns it only from the read-back.

use super::adapt::AdaptRegs;
use super::config::EngineConfig;
use super::memory::{PIXEL_BYTES, RESULT_BYTES};
pub use super::pre_regs::{CameraWord, PreRegs, CAMERA_WORDS, PRE_ENABLE, PRE_FRESH, PRE_SH_HALF};
use serde::{Deserialize, Serialize};

/// Width of the control port's byte addresses (a 4 KiB register space).
pub const ADDR_BITS: u32 = 12;

/// Width of a control-port register (AXI4-Lite data width).
pub const DATA_BITS: u32 = 32;

/// `CTRL` bit 0: start a frame (write 1; ignored while busy).
pub const CTRL_START: u32 = 1 << 0;

/// `STATUS` bit 0: a frame is running.
pub const STATUS_BUSY: u32 = 1 << 0;
/// `STATUS` bit 1: the last frame is done (cleared by the next start).
pub const STATUS_DONE: u32 = 1 << 1;
/// `STATUS` bit 2: at least one tile of the last frame overflowed the table capacity.
pub const STATUS_OVERFLOW: u32 = 1 << 2;

/// `FIRST_OVERFLOW` when no tile overflowed.
pub const NO_OVERFLOW: u32 = u32::MAX;

/// Access of a register from the control port.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Access {
    /// Write only (reads return 0).
    W,
    /// Read only (writes are ignored).
    R,
    /// Read and write.
    RW,
}

/// A 32-bit register of the control port (the counters are [`Counter`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Reg {
    /// 0x000: bit 0 start ([`CTRL_START`]).
    Ctrl,
    /// 0x004: [`STATUS_BUSY`], [`STATUS_DONE`], [`STATUS_OVERFLOW`].
    Status,
    /// 0x008: frame index (the DPS parity of the frame: [`crate::sort::Parity::of`]).
    Frame,
    /// 0x00C: tile descriptors of the frame.
    Tiles,
    /// 0x010: image width in pixels.
    Width,
    /// 0x014: image height in pixels.
    Height,
    /// 0x018: descriptor base (bytes), low word.
    DescBaseLo,
    /// 0x01C: descriptor base, high word.
    DescBaseHi,
    /// 0x020: result base (bytes), low word.
    ResultBaseLo,
    /// 0x024: result base, high word.
    ResultBaseHi,
    /// 0x028: feature-table base (bytes, 32-byte aligned), low word.
    FeatBaseLo,
    /// 0x02C: feature-table base, high word.
    FeatBaseHi,
    /// 0x030: frame-buffer base (bytes, 4-byte aligned), low word.
    FbBaseLo,
    /// 0x034: frame-buffer base, high word.
    FbBaseHi,
    /// 0x038: sort scratch base (bytes, 8-byte aligned; `2 * table_capacity` entries per
    /// sorting core), low word.
    ScratchBaseLo,
    /// 0x03C: sort scratch base, high word.
    ScratchBaseHi,
    /// 0x040: lowest overflowing tile index of the last frame, [`NO_OVERFLOW`] when none.
    FirstOverflow,
    /// 0x044: tiles of the last frame that overflowed.
    Overflows,
    /// 0x048: [`PRE_ENABLE`], [`PRE_FRESH`], [`PRE_SH_HALF`] (the Preprocessing Engine's frame;
    /// [`PreRegs`]).
    PreCtrl,
    /// 0x04C: Gaussians of the baked scene.
    Gaussians,
    /// 0x050: the scene's SH degree (0 to 3; the records' precision is [`PRE_SH_HALF`]).
    ShDegree,
    /// 0x054: geometry array base (bytes, 8-byte aligned), low word.
    GeoBaseLo,
    /// 0x058: geometry array base, high word.
    GeoBaseHi,
    /// 0x05C: SH array base (bytes, 8-byte aligned), low word.
    ShBaseLo,
    /// 0x060: SH array base, high word.
    ShBaseHi,
    /// 0x064: the previous frame's feature-table base (bytes, 32-byte aligned), low word.
    PrevFeatBaseLo,
    /// 0x068: the previous frame's feature-table base, high word.
    PrevFeatBaseHi,
    /// 0x06C: incoming-list base (bytes, 64-byte aligned), low word.
    ListBaseLo,
    /// 0x070: incoming-list base, high word.
    ListBaseHi,
    /// 0x074 + 4 k: camera word `k` ([`CameraWord`]).
    Camera(CameraWord),
    /// 0x0D0: the frame controller's own `adaptive` decision ([`AdaptRegs`]:
    /// [`super::adapt::ADAPT_ENABLE`], budget, most passes).
    AdaptCtrl,
}

impl Reg {
    /// Every register, in address order.
    pub const ALL: [Reg; 18 + 11 + CAMERA_WORDS + 1] = [
        Reg::Ctrl,
        Reg::Status,
        Reg::Frame,
        Reg::Tiles,
        Reg::Width,
        Reg::Height,
        Reg::DescBaseLo,
        Reg::DescBaseHi,
        Reg::ResultBaseLo,
        Reg::ResultBaseHi,
        Reg::FeatBaseLo,
        Reg::FeatBaseHi,
        Reg::FbBaseLo,
        Reg::FbBaseHi,
        Reg::ScratchBaseLo,
        Reg::ScratchBaseHi,
        Reg::FirstOverflow,
        Reg::Overflows,
        Reg::PreCtrl,
        Reg::Gaussians,
        Reg::ShDegree,
        Reg::GeoBaseLo,
        Reg::GeoBaseHi,
        Reg::ShBaseLo,
        Reg::ShBaseHi,
        Reg::PrevFeatBaseLo,
        Reg::PrevFeatBaseHi,
        Reg::ListBaseLo,
        Reg::ListBaseHi,
        Reg::Camera(CameraWord(0)),
        Reg::Camera(CameraWord(1)),
        Reg::Camera(CameraWord(2)),
        Reg::Camera(CameraWord(3)),
        Reg::Camera(CameraWord(4)),
        Reg::Camera(CameraWord(5)),
        Reg::Camera(CameraWord(6)),
        Reg::Camera(CameraWord(7)),
        Reg::Camera(CameraWord(8)),
        Reg::Camera(CameraWord(9)),
        Reg::Camera(CameraWord(10)),
        Reg::Camera(CameraWord(11)),
        Reg::Camera(CameraWord(12)),
        Reg::Camera(CameraWord(13)),
        Reg::Camera(CameraWord(14)),
        Reg::Camera(CameraWord(15)),
        Reg::Camera(CameraWord(16)),
        Reg::Camera(CameraWord(17)),
        Reg::Camera(CameraWord(18)),
        Reg::Camera(CameraWord(19)),
        Reg::Camera(CameraWord(20)),
        Reg::Camera(CameraWord(21)),
        Reg::Camera(CameraWord(22)),
        Reg::AdaptCtrl,
    ];

    /// Byte address on the control port.
    pub const fn offset(self) -> u32 {
        4 * self.word()
    }

    /// The register's word index (its byte address over 4): 0 to `Reg::ALL.len() - 1`.
    pub const fn index(self) -> usize {
        self.word() as usize
    }

    /// Word address on the control port.
    const fn word(self) -> u32 {
        match self {
            Reg::Ctrl => 0,
            Reg::Status => 1,
            Reg::Frame => 2,
            Reg::Tiles => 3,
            Reg::Width => 4,
            Reg::Height => 5,
            Reg::DescBaseLo => 6,
            Reg::DescBaseHi => 7,
            Reg::ResultBaseLo => 8,
            Reg::ResultBaseHi => 9,
            Reg::FeatBaseLo => 10,
            Reg::FeatBaseHi => 11,
            Reg::FbBaseLo => 12,
            Reg::FbBaseHi => 13,
            Reg::ScratchBaseLo => 14,
            Reg::ScratchBaseHi => 15,
            Reg::FirstOverflow => 16,
            Reg::Overflows => 17,
            Reg::PreCtrl => 18,
            Reg::Gaussians => 19,
            Reg::ShDegree => 20,
            Reg::GeoBaseLo => 21,
            Reg::GeoBaseHi => 22,
            Reg::ShBaseLo => 23,
            Reg::ShBaseHi => 24,
            Reg::PrevFeatBaseLo => 25,
            Reg::PrevFeatBaseHi => 26,
            Reg::ListBaseLo => 27,
            Reg::ListBaseHi => 28,
            Reg::Camera(CameraWord(k)) => 29 + k as u32,
            Reg::AdaptCtrl => 29 + CAMERA_WORDS as u32,
        }
    }

    /// The register's name (as in docs and the RTL).
    pub const fn name(self) -> &'static str {
        match self {
            Reg::Ctrl => "CTRL",
            Reg::Status => "STATUS",
            Reg::Frame => "FRAME",
            Reg::Tiles => "TILES",
            Reg::Width => "WIDTH",
            Reg::Height => "HEIGHT",
            Reg::DescBaseLo => "DESC_BASE_LO",
            Reg::DescBaseHi => "DESC_BASE_HI",
            Reg::ResultBaseLo => "RESULT_BASE_LO",
            Reg::ResultBaseHi => "RESULT_BASE_HI",
            Reg::FeatBaseLo => "FEAT_BASE_LO",
            Reg::FeatBaseHi => "FEAT_BASE_HI",
            Reg::FbBaseLo => "FB_BASE_LO",
            Reg::FbBaseHi => "FB_BASE_HI",
            Reg::ScratchBaseLo => "SCRATCH_BASE_LO",
            Reg::ScratchBaseHi => "SCRATCH_BASE_HI",
            Reg::FirstOverflow => "FIRST_OVERFLOW",
            Reg::Overflows => "OVERFLOWS",
            Reg::PreCtrl => "PRE_CTRL",
            Reg::Gaussians => "GAUSSIANS",
            Reg::ShDegree => "SH_DEGREE",
            Reg::GeoBaseLo => "GEO_BASE_LO",
            Reg::GeoBaseHi => "GEO_BASE_HI",
            Reg::ShBaseLo => "SH_BASE_LO",
            Reg::ShBaseHi => "SH_BASE_HI",
            Reg::PrevFeatBaseLo => "PREV_FEAT_BASE_LO",
            Reg::PrevFeatBaseHi => "PREV_FEAT_BASE_HI",
            Reg::ListBaseLo => "LIST_BASE_LO",
            Reg::ListBaseHi => "LIST_BASE_HI",
            Reg::Camera(w) => w.name(),
            Reg::AdaptCtrl => "ADAPT_CTRL",
        }
    }

    /// Access from the control port.
    pub const fn access(self) -> Access {
        match self {
            Reg::Ctrl => Access::W,
            Reg::Status | Reg::FirstOverflow | Reg::Overflows => Access::R,
            _ => Access::RW,
        }
    }

    /// The register at byte address `offset`, if any.
    pub fn at(offset: u32) -> Option<Reg> {
        Reg::ALL.iter().copied().find(|r| r.offset() == offset)
    }
}

/// A 64-bit performance counter, read as two words at [`Counter::offset`] (low) and `+ 4`
/// (high). Every counter is reset by a start; the byte counters up to `WR_RESULT` count the bytes of the elements
/// the cores' bridges deliver or accept (entries 8, feature words 32, pixels 4, descriptors 32,
/// results 16), `RD_RESULT` the previous results the frame controller reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub enum Counter {
    /// 0: cycles from start to done.
    Cycles,
    /// 1: cycles with any sorting core busy.
    SortBusy,
    /// 2: cycles with any raster core busy.
    RasterBusy,
    /// 3: tiles sorted (overflowing tiles are not sorted).
    TilesSorted,
    /// 4: tiles rastered (every tile, overflowing ones too).
    TilesRastered,
    /// 5: sum of `list_len + prev_len` over the sorted tiles.
    EntriesSorted,
    /// 6: sum of `next_len` over the rastered tiles.
    EntriesRastered,
    /// 7: bytes of tile descriptors read.
    RdDesc,
    /// 8: bytes the sorting cores read.
    RdSort,
    /// 9: bytes the sorting cores wrote.
    WrSort,
    /// 10: bytes of table entries the raster cores read.
    RdTable,
    /// 11: bytes of feature words the raster cores read.
    RdFeat,
    /// 12: bytes of table entries the raster cores wrote back.
    WrTable,
    /// 13: bytes of pixels the raster cores wrote.
    WrPixel,
    /// 14: bytes of tile results written.
    WrResult,
    /// 15: cycles the Preprocessing Engine is busy (from start to its last list write's B).
    PreBusy,
    /// 16: bytes the Preprocessing Engine read (read beats times the beat bytes: geometry and
    /// SH records, previous feature words).
    RdPre,
    /// 17: bytes the Preprocessing Engine wrote (write beats times the beat bytes: feature
    /// words, list lines, list lengths).
    WrPre,
    /// 18: bytes of previous tile results the frame controller read (its own `adaptive`
    /// decision: 16 per tile in its scan and again in its walk, [`super::adapt`]).
    RdResult,
}

/// Number of performance counters.
pub const COUNTERS: usize = 19;

/// Byte address of counter 0's low word.
pub const COUNTER_BASE: u32 = 0x100;

impl Counter {
    /// Every counter, in index order.
    pub const ALL: [Counter; COUNTERS] = [
        Counter::Cycles,
        Counter::SortBusy,
        Counter::RasterBusy,
        Counter::TilesSorted,
        Counter::TilesRastered,
        Counter::EntriesSorted,
        Counter::EntriesRastered,
        Counter::RdDesc,
        Counter::RdSort,
        Counter::WrSort,
        Counter::RdTable,
        Counter::RdFeat,
        Counter::WrTable,
        Counter::WrPixel,
        Counter::WrResult,
        Counter::PreBusy,
        Counter::RdPre,
        Counter::WrPre,
        Counter::RdResult,
    ];

    /// The counter's index `k`.
    pub const fn index(self) -> usize {
        self as usize
    }

    /// Byte address of the low word (`0x100 + 8 k`); the high word is at `+ 4`.
    pub const fn offset(self) -> u32 {
        COUNTER_BASE + 8 * self as u32
    }

    /// The counter's name (as in docs and the RTL).
    pub const fn name(self) -> &'static str {
        match self {
            Counter::Cycles => "CYCLES",
            Counter::SortBusy => "SORT_BUSY",
            Counter::RasterBusy => "RASTER_BUSY",
            Counter::TilesSorted => "TILES_SORTED",
            Counter::TilesRastered => "TILES_RASTERED",
            Counter::EntriesSorted => "ENTRIES_SORTED",
            Counter::EntriesRastered => "ENTRIES_RASTERED",
            Counter::RdDesc => "RD_DESC",
            Counter::RdSort => "RD_SORT",
            Counter::WrSort => "WR_SORT",
            Counter::RdTable => "RD_TABLE",
            Counter::RdFeat => "RD_FEAT",
            Counter::WrTable => "WR_TABLE",
            Counter::WrPixel => "WR_PIXEL",
            Counter::WrResult => "WR_RESULT",
            Counter::PreBusy => "PRE_BUSY",
            Counter::RdPre => "RD_PRE",
            Counter::WrPre => "WR_PRE",
            Counter::RdResult => "RD_RESULT",
        }
    }

    /// Whether golden knows the counter exactly (every counter but the cycle counts, which
    /// depend on the RTL's timing).
    pub const fn is_golden(self) -> bool {
        !matches!(self, Counter::Cycles | Counter::SortBusy | Counter::RasterBusy | Counter::PreBusy)
    }

    /// Whether the counter counts bytes moved over the memory ports (`RD_*` and `WR_*`).
    pub const fn counts_bytes(self) -> bool {
        matches!(
            self,
            Counter::RdDesc
                | Counter::RdSort
                | Counter::WrSort
                | Counter::RdTable
                | Counter::RdFeat
                | Counter::WrTable
                | Counter::WrPixel
                | Counter::WrResult
                | Counter::RdPre
                | Counter::WrPre
                | Counter::RdResult
        )
    }
}

/// The values of every performance counter, indexed by [`Counter`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Counters(pub [u64; COUNTERS]);

impl Counters {
    /// The value of `c`.
    pub fn get(&self, c: Counter) -> u64 {
        self.0[c.index()]
    }

    /// Adds `v` to `c`.
    pub fn add(&mut self, c: Counter, v: u64) {
        self.0[c.index()] += v;
    }

    /// The first golden counter ([`Counter::is_golden`]) whose value differs between `self`
    /// (expected) and `actual`: `(counter, expected, actual)`.
    pub fn first_golden_mismatch(&self, actual: &Counters) -> Option<(Counter, u64, u64)> {
        Counter::ALL
            .iter()
            .copied()
            .filter(|c| c.is_golden())
            .find(|&c| self.get(c) != actual.get(c))
            .map(|c| (c, self.get(c), actual.get(c)))
    }
}

/// The programmable registers of one frame (what the host writes before `CTRL.start`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct FrameRegs {
    /// Frame index ([`Reg::Frame`]).
    pub frame: u32,
    /// Tile descriptors ([`Reg::Tiles`]).
    pub tiles: u32,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Descriptor base (bytes, 32-byte aligned).
    pub desc_base: u64,
    /// Result base (bytes, 8-byte aligned).
    pub result_base: u64,
    /// Feature-table base (bytes, 32-byte aligned).
    pub feat_base: u64,
    /// Frame-buffer base (bytes, a multiple of `4 subtile`: [`fb_base_alignment`]).
    pub fb_base: u64,
    /// Sort scratch base (bytes, 8-byte aligned).
    pub scratch_base: u64,
    /// The Preprocessing Engine's registers (disabled by default).
    pub pre: PreRegs,
    /// `ADAPT_CTRL`: the frame controller's own `adaptive` decision (disabled by default).
    pub adapt: AdaptRegs,
}

/// A base register the engine cannot use: not a multiple of the alignment its data needs.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{field} = 0x{value:x} is not a multiple of {align} bytes ({why})")]
pub struct MisalignedBase {
    /// The register's name (`FB_BASE`, ...).
    pub field: &'static str,
    /// The value programmed.
    pub value: u64,
    /// The alignment it needs, in bytes.
    pub align: u64,
    /// Why.
    pub why: &'static str,
}

/// The alignment `FB_BASE` needs for engine `cfg`: `4 subtile` bytes (one pixel row of a
/// subtile), which the raster bridge assumes: a subtile's pixel row is one write burst that
/// never crosses a 4 KiB page (docs/rtl.md "Memory map").
pub fn fb_base_alignment(cfg: &EngineConfig) -> u64 {
    PIXEL_BYTES * cfg.raster_config().subtile as u64
}

impl FrameRegs {
    /// Every base register with the alignment the engine needs (the RTL ignores the low bits of
    /// each, so a misaligned base would silently read or write elsewhere); the preprocessing
    /// bases only when [`PreRegs::enabled`].
    pub fn base_alignments(&self, cfg: &EngineConfig) -> Vec<(&'static str, u64, u64, &'static str)> {
        let mut v = vec![
            ("DESC_BASE", self.desc_base, 32, "a descriptor is one 32-byte burst"),
            ("RESULT_BASE", self.result_base, RESULT_BYTES, "a result is one 16-byte burst"),
            ("FEAT_BASE", self.feat_base, 32, "a feature word is 32 bytes"),
            (
                "FB_BASE",
                self.fb_base,
                fb_base_alignment(cfg),
                "4 x subtile: a subtile's pixel row must not cross a 4 KiB page",
            ),
            ("SCRATCH_BASE", self.scratch_base, 8, "an entry is 8 bytes"),
        ];
        if self.pre.enabled() {
            v.extend(self.pre.base_alignments());
        }
        v
    }

    /// Refuses a base register the engine `cfg` cannot use, naming the field and the
    /// alignment it needs ([`FrameRegs::base_alignments`]).
    pub fn check(&self, cfg: &EngineConfig) -> Result<(), MisalignedBase> {
        for (field, value, align, why) in self.base_alignments(cfg) {
            if value % align != 0 {
                return Err(MisalignedBase { field, value, align, why });
            }
        }
        Ok(())
    }

    /// The frame registers as programmed, from the read/write registers' values `get` (bases
    /// from their LO/HI pairs): the inverse of [`FrameRegs::writes`] (the preprocessing
    /// registers but `PRE_CTRL` read as they are, enabled or not).
    pub fn from_registers(get: impl Fn(Reg) -> u32) -> FrameRegs {
        let pair = |lo: Reg, hi: Reg| get(lo) as u64 | (get(hi) as u64) << 32;
        let mut camera = [0u32; CAMERA_WORDS];
        for c in CameraWord::all() {
            camera[c.0 as usize] = get(Reg::Camera(c));
        }
        FrameRegs {
            frame: get(Reg::Frame),
            tiles: get(Reg::Tiles),
            width: get(Reg::Width),
            height: get(Reg::Height),
            desc_base: pair(Reg::DescBaseLo, Reg::DescBaseHi),
            result_base: pair(Reg::ResultBaseLo, Reg::ResultBaseHi),
            feat_base: pair(Reg::FeatBaseLo, Reg::FeatBaseHi),
            fb_base: pair(Reg::FbBaseLo, Reg::FbBaseHi),
            scratch_base: pair(Reg::ScratchBaseLo, Reg::ScratchBaseHi),
            pre: PreRegs {
                ctrl: get(Reg::PreCtrl),
                gaussians: get(Reg::Gaussians),
                sh_degree: get(Reg::ShDegree),
                geo_base: pair(Reg::GeoBaseLo, Reg::GeoBaseHi),
                sh_base: pair(Reg::ShBaseLo, Reg::ShBaseHi),
                prev_feat_base: pair(Reg::PrevFeatBaseLo, Reg::PrevFeatBaseHi),
                list_base: pair(Reg::ListBaseLo, Reg::ListBaseHi),
                camera,
            },
            adapt: AdaptRegs { ctrl: get(Reg::AdaptCtrl) },
        }
    }

    /// The register writes that program this frame, in address order (`CTRL` not included).
    /// `PRE_CTRL` and `ADAPT_CTRL` are always written; the other preprocessing registers only
    /// when `PRE_CTRL` enables the Preprocessing Engine.
    pub fn writes(&self) -> Vec<(Reg, u32)> {
        let split = |lo: Reg, hi: Reg, v: u64| [(lo, v as u32), (hi, (v >> 32) as u32)];
        let mut w = vec![
            (Reg::Frame, self.frame),
            (Reg::Tiles, self.tiles),
            (Reg::Width, self.width),
            (Reg::Height, self.height),
        ];
        w.extend(split(Reg::DescBaseLo, Reg::DescBaseHi, self.desc_base));
        w.extend(split(Reg::ResultBaseLo, Reg::ResultBaseHi, self.result_base));
        w.extend(split(Reg::FeatBaseLo, Reg::FeatBaseHi, self.feat_base));
        w.extend(split(Reg::FbBaseLo, Reg::FbBaseHi, self.fb_base));
        w.extend(split(Reg::ScratchBaseLo, Reg::ScratchBaseHi, self.scratch_base));
        let p = &self.pre;
        w.push((Reg::PreCtrl, p.ctrl));
        if p.enabled() {
            w.push((Reg::Gaussians, p.gaussians));
            w.push((Reg::ShDegree, p.sh_degree));
            w.extend(split(Reg::GeoBaseLo, Reg::GeoBaseHi, p.geo_base));
            w.extend(split(Reg::ShBaseLo, Reg::ShBaseHi, p.sh_base));
            w.extend(split(Reg::PrevFeatBaseLo, Reg::PrevFeatBaseHi, p.prev_feat_base));
            w.extend(split(Reg::ListBaseLo, Reg::ListBaseHi, p.list_base));
            w.extend(CameraWord::all().map(|c| (Reg::Camera(c), p.camera[c.0 as usize])));
        }
        w.push((Reg::AdaptCtrl, self.adapt.ctrl));
        w
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_byte_counters_are_the_rd_and_wr_counters() {
        for c in Counter::ALL {
            let by_name = c.name().starts_with("RD_") || c.name().starts_with("WR_");
            assert_eq!(c.counts_bytes(), by_name, "{}", c.name());
        }
    }

    #[test]
    fn register_offsets_are_the_contract() {
        let map: Vec<(u32, &str)> = Reg::ALL.iter().map(|r| (r.offset(), r.name())).collect();
        assert_eq!(map[0], (0x000, "CTRL"));
        assert_eq!(map[1], (0x004, "STATUS"));
        assert_eq!(map[5], (0x014, "HEIGHT"));
        assert_eq!(map[14], (0x038, "SCRATCH_BASE_LO"));
        assert_eq!(map[16], (0x040, "FIRST_OVERFLOW"));
        assert_eq!(map[17], (0x044, "OVERFLOWS"));
        for r in Reg::ALL {
            assert_eq!(Reg::at(r.offset()), Some(r));
            assert!(r.offset() < 1 << ADDR_BITS);
        }
        assert_eq!(Reg::at(0x048), Some(Reg::PreCtrl));
        assert_eq!(Reg::at(0x070), Some(Reg::ListBaseHi));
        assert_eq!(Reg::at(0x074), Some(Reg::Camera(CameraWord(0))));
        assert_eq!(Reg::at(0x074 + 4 * 22), Some(Reg::Camera(CameraWord(22))));
        assert_eq!(Reg::at(0x074 + 4 * 23), Some(Reg::AdaptCtrl));
        assert_eq!(Reg::AdaptCtrl.offset(), 0x0D0);
        assert_eq!(Reg::at(0x0D4), None);
        assert_eq!(Reg::Camera(CameraWord(21)).name(), "GRID_X");
        let offsets: Vec<u32> = Reg::ALL.iter().map(|r| r.offset()).collect();
        assert!(offsets.windows(2).all(|w| w[1] == w[0] + 4), "dense, in address order");
        assert_eq!(Reg::Ctrl.access(), Access::W);
        assert_eq!(Reg::Overflows.access(), Access::R);
        assert_eq!(Reg::FbBaseHi.access(), Access::RW);
    }

    #[test]
    fn counters_follow_the_registers() {
        assert_eq!(Counter::Cycles.offset(), 0x100);
        assert_eq!(Counter::WrResult.offset(), 0x100 + 8 * 14);
        assert_eq!(Counter::EntriesRastered.name(), "ENTRIES_RASTERED");
        for (k, c) in Counter::ALL.iter().enumerate() {
            assert_eq!(c.index(), k);
            assert!(c.offset() + 4 < 1 << ADDR_BITS);
            assert!(Reg::at(c.offset()).is_none());
        }
        assert_eq!(Counter::ALL.iter().filter(|c| !c.is_golden()).count(), 4);
    }

    #[test]
    fn first_golden_mismatch_skips_cycle_counters() {
        let want = Counters::default();
        let mut got = Counters::default();
        got.add(Counter::Cycles, 1000);
        assert_eq!(want.first_golden_mismatch(&got), None);
        got.add(Counter::WrPixel, 4);
        got.add(Counter::RdFeat, 32);
        assert_eq!(want.first_golden_mismatch(&got), Some((Counter::RdFeat, 0, 32)));
    }

    #[test]
    fn misaligned_bases_are_refused_by_name() {
        let cfg = EngineConfig::default();
        let align = fb_base_alignment(&cfg);
        assert_eq!(align, PIXEL_BYTES * cfg.raster_config().subtile as u64);
        let ok = FrameRegs {
            desc_base: 0x1000,
            result_base: 0x2010,
            feat_base: 0x3020,
            fb_base: 0x4000 + 3 * align,
            scratch_base: 0x5008,
            ..FrameRegs::default()
        };
        assert_eq!(ok.check(&cfg), Ok(()));
        // A pixel-aligned but not subtile-row-aligned frame buffer (what the RTL would accept
        // silently) is refused, naming FB_BASE and the alignment.
        let bad = FrameRegs { fb_base: ok.fb_base + PIXEL_BYTES, ..ok };
        let e = bad.check(&cfg).unwrap_err();
        assert_eq!((e.field, e.value, e.align), ("FB_BASE", bad.fb_base, align));
        let msg = e.to_string();
        assert!(msg.contains("FB_BASE") && msg.contains(&format!("{align} bytes")), "{msg}");
        // The alignment follows the configuration's subtile.
        let mut wide = cfg.clone();
        wide.subtile *= 2;
        let half = FrameRegs { fb_base: 0x4000 + align, ..ok };
        assert_eq!(half.check(&cfg), Ok(()));
        assert_eq!(half.check(&wide).map_err(|e| (e.field, e.align)), Err(("FB_BASE", 2 * align)));
        let e = FrameRegs { feat_base: 0x3010, ..ok }.check(&cfg).unwrap_err();
        assert_eq!((e.field, e.align), ("FEAT_BASE", 32));
        // A result is a 2-beat burst: an 8-byte-aligned base could cross a 4 KiB page.
        let e = FrameRegs { result_base: 0x2008, ..ok }.check(&cfg).unwrap_err();
        assert_eq!((e.field, e.align), ("RESULT_BASE", 16));
    }

    #[test]
    fn frame_writes_split_the_bases() {
        let r = FrameRegs { frame: 3, fb_base: 0x1_2345_6780, ..FrameRegs::default() };
        let w = r.writes();
        assert_eq!(w.len(), 16);
        assert_eq!(w[14], (Reg::PreCtrl, 0), "a disabled Preprocessing Engine is written as such");
        assert_eq!(w[15], (Reg::AdaptCtrl, 0), "the descriptors' passes are written as such");
        assert_eq!(w[0], (Reg::Frame, 3));
        assert!(w.contains(&(Reg::FbBaseLo, 0x2345_6780)));
        assert!(w.contains(&(Reg::FbBaseHi, 1)));
        assert!(w.iter().all(|(r, _)| r.access() == Access::RW));
        let pre = PreRegs { ctrl: PRE_ENABLE, list_base: 0x7_0000_0040, ..PreRegs::default() };
        let w = FrameRegs { pre, ..r }.writes();
        assert_eq!(w.len(), 16 + 10 + CAMERA_WORDS);
        assert!(w.contains(&(Reg::ListBaseHi, 7)) && w.contains(&(Reg::ListBaseLo, 0x40)));
        let regs: Vec<Reg> = w.iter().map(|(r, _)| *r).collect();
        let mut sorted = regs.clone();
        sorted.sort_by_key(|r| r.offset());
        assert_eq!(regs, sorted, "in address order");
        let mut pre = pre;
        pre.camera[3] = 0xdead_beef;
        let on = FrameRegs { pre, ..r };
        let mut file = [0u32; Reg::ALL.len()];
        for (reg, v) in on.writes() {
            file[reg.index()] = v;
        }
        assert_eq!(
            FrameRegs::from_registers(|reg| file[reg.index()]),
            on,
            "writes and from_registers invert"
        );
    }

    #[test]
    fn preprocessing_bases_are_checked_only_when_enabled() {
        let cfg = EngineConfig::default();
        let pre = PreRegs { list_base: 0x1020, ..PreRegs::default() };
        let off = FrameRegs { pre, ..FrameRegs::default() };
        assert_eq!(off.check(&cfg), Ok(()));
        let on = FrameRegs { pre: PreRegs { ctrl: PRE_ENABLE, ..pre }, ..off };
        let e = on.check(&cfg).unwrap_err();
        assert_eq!((e.field, e.align), ("LIST_BASE", 64));
    }
}
