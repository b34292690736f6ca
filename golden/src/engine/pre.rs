//! The memory-level reference of the Preprocessing Engine ([`preprocess_frame`]): what a start
//! with [`PRE_ENABLE`](super::PRE_ENABLE) does before the tile walk, from memory and the
//! registers only ([`PreRegs`]).
//!
//! - Lane `p` takes Gaussians [`EngineConfig::pre_lane_range`] and reads their geometry
//!   records ([`geometry_bytes`] each, Gaussian `i` at `GEO_BASE + geometry_bytes() i`) as one
//!   stream; an empty lane reads nothing.
//! - Each visible (not culled) Gaussian's SH record ([`sh_record_words`] words of the degree and
//!   the precision [`PRE_SH_HALF`](super::PRE_SH_HALF) selects, at `SH_BASE + 4 sh_words i`) is
//!   read, one read per Gaussian; unless
//!   [`PRE_FRESH`](super::PRE_FRESH), so is its previous feature word (`PREV_FEAT_BASE + 32 i`).
//! - Every Gaussian's feature word is written at `FEAT_BASE + 32 i` (all zero when culled).
//! - A visible Gaussian is appended to the incoming list of every tile where golden
//!   [`incoming`] says it is incoming (every tile it enters when fresh). Tile `t`'s list is at
//!   entry address `LIST_BASE / 8 + t list_stride`; only its first `table_capacity` entries
//!   are written, as whole 64-byte lines (the slots of the last line past the length are 0); the
//!   length (which keeps counting) goes into the descriptor's `list_len` (bytes 20..24 of
//!   descriptor `t`), for every tile of the frame. The reference appends in Gaussian order (the
//!   RTL's lanes interleave: the order within a list is free, the sort does not depend on it).
//!
//! Counters ([`Counter::RdPre`], [`Counter::WrPre`]): the AXI beats of `axi_data_bits / 8`
//! bytes each transfer spans ([`beats_spanned`]) times the beat bytes: reads of the geometry
//! streams, SH records and previous words; writes of the feature words, the list lines and one
//! beat per length. The transfers are stated once, [`pre_transfers`]; [`pre_traffic`] counts
//! their beats and the cycle model (`neo_sim`) the DRAM lines they touch.

use super::memory::{
    feature_from_bytes, feature_to_bytes, Memory, DESCRIPTOR_BYTES, ENTRY_BYTES, FEATURE_BYTES,
};
use super::reference::FrameError;
use super::regs::{CameraWord, Counter, Counters, FrameRegs, PreRegs};
use super::EngineConfig;
use crate::hwpre::bake::{geometry_bytes, sh_bytes, Baked, BakedGeometry, ShPrecision};
use crate::hwpre::duplicate::{incoming, TouchRecord};
use crate::hwpre::preprocess_one;
use crate::hwpre::project::ProjectParams;
use crate::scene::sh_coeffs;
use crate::sort::{DepthKeyCodec, SortEntry};
use rayon::prelude::*;

/// Bytes of a list line (the list writer's write unit).
pub const LIST_LINE_BYTES: u64 = 64;

/// Byte offset of `list_len` in a tile descriptor (the high half of word 2).
pub const LIST_LEN_OFFSET: u64 = 20;

/// Beats of `beat` bytes (aligned to `beat`) that the `bytes` bytes from byte address `addr`
/// touch: an AXI transfer of them spans this many beats (0 for no byte).
pub fn beats_spanned(addr: u64, bytes: u64, beat: u64) -> u64 {
    if bytes == 0 {
        return 0;
    }
    (addr + bytes - 1) / beat - addr / beat + 1
}

/// What the Preprocessing Engine did in one frame.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct PreWork {
    /// The Gaussians not culled (ids, ascending): the ones whose SH record (and, unless fresh,
    /// previous feature word) the engine read.
    pub visible: Vec<u64>,
    /// Every tile's incoming list (in the reference's order: Gaussian, then tile row-major), at
    /// its full length (the memory holds the first `table_capacity` entries).
    pub lists: Vec<Vec<SortEntry>>,
}

/// Words (4 bytes each) of one SH record in the engine's memory: the `3 (degree + 1)^2`
/// coefficients in `precision`, packed in order (binary16: coefficient `2j` in the low half of
/// word `j`, `2j + 1` in the high half) and the last word padded with zeros. Binary32 records are
/// `sh_bytes / 4` words; binary16 records of degree 0 and 2 (6 and 54 bytes) get 2 pad bytes.
pub const fn sh_record_words(degree: u8, precision: ShPrecision) -> u32 {
    sh_bytes(degree, precision).div_ceil(4)
}

/// The engine-memory record ([`sh_record_words`]) of the coefficient words `coeffs` (one per
/// coefficient, as [`Baked::sh_of`] holds them: binary16 bits in the low half).
pub fn pack_sh_record(coeffs: &[u32], precision: ShPrecision) -> Vec<u32> {
    match precision {
        ShPrecision::F32 => coeffs.to_vec(),
        ShPrecision::F16 => {
            coeffs.chunks(2).map(|p| (p[0] & 0xFFFF) | p.get(1).map_or(0, |h| (h & 0xFFFF) << 16)).collect()
        }
    }
}

/// The SH array of `baked` as the engine's memory holds it from `SH_BASE`: every Gaussian's
/// record ([`pack_sh_record`]), back to back, little-endian.
pub fn sh_array_bytes(baked: &Baked) -> Vec<u8> {
    (0..baked.len())
        .flat_map(|i| pack_sh_record(baked.sh_of(i), baked.sh_precision))
        .flat_map(u32::to_le_bytes)
        .collect()
}

/// The coefficient words of record `words` holding `n` coefficients: the inverse of
/// [`pack_sh_record`].
pub fn unpack_sh_record(words: &[u32], n: usize, precision: ShPrecision) -> Vec<u32> {
    match precision {
        ShPrecision::F32 => words[..n].to_vec(),
        ShPrecision::F16 => (0..n).map(|k| (words[k / 2] >> (16 * (k % 2))) & 0xFFFF).collect(),
    }
}

/// The baked scene `regs` point at, decoded from `mem`: every geometry record and SH record
/// (the engine reads the SH records of visible Gaussians only; decoding them all here changes
/// nothing).
fn baked_from_memory(cfg: &EngineConfig, p: &PreRegs, mem: &Memory) -> Result<Baked, String> {
    let degree = u8::try_from(p.sh_degree)
        .ok()
        .filter(|d| *d <= 3)
        .ok_or_else(|| format!("SH_DEGREE {} is not 0 to 3", p.sh_degree))?;
    let n = p.gaussians as u64;
    let gb = geometry_bytes() as u64;
    let mut geo = vec![0u8; (n * gb) as usize];
    mem.read(p.geo_base, &mut geo);
    let geometry = geo.chunks_exact(gb as usize).map(BakedGeometry::from_le_bytes).collect();
    let precision = p.sh_precision();
    let words = sh_record_words(degree, precision) as usize;
    let mut sh = vec![0u8; n as usize * 4 * words];
    mem.read(p.sh_base, &mut sh);
    let sh: Vec<u32> =
        sh.chunks_exact(4).map(|c| u32::from_le_bytes(c.try_into().expect("4 bytes"))).collect();
    let coeffs = 3 * sh_coeffs(degree);
    let sh = sh.chunks_exact(words).flat_map(|r| unpack_sh_record(r, coeffs, precision)).collect();
    let fmt = cfg.feature_format();
    Ok(Baked {
        sh_degree: degree,
        sh_precision: precision,
        cutoff: fmt.cutoff,
        opacity_format: fmt.opacity,
        geometry,
        sh,
    })
}

/// Runs the Preprocessing Engine of `cfg` for `regs` on `mem` (see the module docs), adding
/// its golden counters to `counters`.
pub fn preprocess_frame(
    cfg: &EngineConfig,
    regs: &FrameRegs,
    mem: &mut Memory,
    counters: &mut Counters,
) -> Result<PreWork, FrameError> {
    let p = &regs.pre;
    let err = |problem: String| FrameError { tile: 0, problem: format!("preprocessing: {problem}") };
    if regs.tiles as usize > cfg.pre_max_tiles {
        return Err(err(format!("{} tiles exceed pre_max_tiles {}", regs.tiles, cfg.pre_max_tiles)));
    }
    let baked = baked_from_memory(cfg, p, mem).map_err(err)?;
    let (cam, cam_pos) = CameraWord::decode(&p.camera);
    let grid = cam.grid.map(|g| g.max(0) as u32);
    let max_grid = (1u64 << cfg.tile_bits.min(32)) - 1;
    if grid.iter().any(|&g| g as u64 > max_grid) {
        let bits = cfg.tile_bits;
        return Err(err(format!(
            "the camera's tile grid {grid:?} exceeds the {bits}-bit tile indices ({max_grid} a side)"
        )));
    }
    if grid[0] as u64 * grid[1] as u64 > regs.tiles as u64 {
        return Err(err(format!("the camera's tile grid {grid:?} has more tiles than TILES {}", regs.tiles)));
    }
    let (fmt, rc) = (cfg.feature_format(), cfg.raster_config());
    let params = ProjectParams { feature: fmt, tile: cfg.tile };
    let size = (grid[0] * cfg.tile, grid[1] * cfg.tile);
    let fresh = p.fresh();
    let n = p.gaussians as usize;
    let feat_word = regs.feat_base / FEATURE_BYTES;
    let prev_word = p.prev_feat_base / FEATURE_BYTES;
    let now: Vec<_> = (0..n)
        .into_par_iter()
        .with_min_len(1024)
        .map(|i| preprocess_one(&baked, &cam, cam_pos, &params, &DepthKeyCodec::Fp16, i))
        .collect();
    let mut lists = vec![Vec::new(); regs.tiles as usize];
    let mut visible = Vec::new();
    for (i, h) in now.iter().enumerate() {
        let w = feat_word + i as u64;
        let word = feature_to_bytes(&fmt, h.as_ref().map(|h| &h.entry));
        mem.write(FEATURE_BYTES * w, &word);
        let Some(h) = h else { continue };
        visible.push(i as u64);
        let prev = if fresh {
            None
        } else {
            let at = FEATURE_BYTES * (prev_word + i as u64);
            let mut b = [0u8; FEATURE_BYTES as usize];
            mem.read(at, &mut b);
            feature_from_bytes(&fmt, &b)
        };
        let record = TouchRecord { entry: prev.as_ref() };
        for hit in
            incoming(&h.entry, record, &fmt, &rc, size, |_, _| fresh).into_iter().filter(|t| t.incoming)
        {
            let t = (hit.tile_y * grid[0] + hit.tile_x) as usize;
            lists[t].push(SortEntry::new(h.entry.depth_key, i as u32));
        }
    }
    write_lists(cfg, regs, mem, &lists);
    let (rd, wr) = pre_traffic(cfg, regs, &visible, lists.iter().map(Vec::len));
    counters.add(Counter::RdPre, rd);
    counters.add(Counter::WrPre, wr);
    Ok(PreWork { visible, lists })
}

/// Byte address of tile `t`'s incoming list: `list_stride` entries per tile from `list_base`.
pub fn list_addr(cfg: &EngineConfig, list_base: u64, t: u64) -> u64 {
    list_base + ENTRY_BYTES * cfg.list_stride() as u64 * t
}

/// Byte address of tile `t`'s `list_len` in its descriptor.
pub fn list_len_addr(desc_base: u64, t: u64) -> u64 {
    desc_base + DESCRIPTOR_BYTES * t + LIST_LEN_OFFSET
}

/// What a Preprocessing Engine transfer moves ([`pre_transfers`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum PrePart {
    /// A lane's geometry stream (read): its Gaussians' geometry records back to back.
    Geometry,
    /// A visible Gaussian's SH record (read).
    Sh,
    /// A visible Gaussian's previous feature word (read, unless fresh): the incoming detection.
    PrevFeature,
    /// A Gaussian's feature word (written for every Gaussian, zero when culled).
    Feature,
    /// A 64-byte line of a tile's incoming list (written).
    ListLine,
    /// A tile's `list_len` in its descriptor (written).
    ListLen,
}

impl PrePart {
    /// Every part, in the order [`pre_transfers`] yields them.
    pub const ALL: [PrePart; 6] = [
        PrePart::Geometry,
        PrePart::Sh,
        PrePart::PrevFeature,
        PrePart::Feature,
        PrePart::ListLine,
        PrePart::ListLen,
    ];

    /// True for the parts the engine writes.
    pub fn is_write(self) -> bool {
        matches!(self, PrePart::Feature | PrePart::ListLine | PrePart::ListLen)
    }
}

/// One AXI transfer of the Preprocessing Engine: `bytes` bytes from byte address `addr`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PreTransfer {
    /// What it moves.
    pub part: PrePart,
    /// First byte.
    pub addr: u64,
    /// Bytes.
    pub bytes: u64,
}

/// Bytes of the records the Preprocessing Engine's transfers move.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PreRecords {
    /// A Gaussian's geometry record.
    pub geometry: u64,
    /// A visible Gaussian's SH record.
    pub sh: u64,
    /// A feature word (written per Gaussian, read back as the previous word).
    pub feature: u64,
}

impl PreRecords {
    /// The engine's records for SH degree `sh_degree` in `precision`: the baked geometry
    /// record, the SH record ([`sh_record_words`]) and the 32-byte feature word.
    pub fn engine(sh_degree: u8, precision: ShPrecision) -> Self {
        PreRecords {
            geometry: geometry_bytes() as u64,
            sh: 4 * sh_record_words(sh_degree, precision) as u64,
            feature: FEATURE_BYTES,
        }
    }
}

/// Every transfer the Preprocessing Engine makes for `regs`, part by part in [`PrePart::ALL`]'s
/// order (the RTL's lanes interleave them; nothing counted depends on the order): each lane's
/// geometry stream (one transfer, empty lanes none); per `visible` Gaussian (ascending ids) its
/// SH record, then, unless fresh, per visible Gaussian its previous feature word; every
/// Gaussian's feature word; per tile its list lines (the first `table_capacity` entries of a
/// list of `list_lens[t]`, whole 64-byte lines) and its length. The one statement of the
/// engine's traffic: [`pre_traffic`] counts its AXI beats, the cycle model
/// (`neo_sim::arch`) the DRAM lines each transfer touches.
pub fn pre_transfers<V>(
    cfg: &EngineConfig,
    regs: &FrameRegs,
    visible: V,
    list_lens: impl IntoIterator<Item = usize>,
    each: impl FnMut(PreTransfer),
) where
    V: IntoIterator<Item = u64>,
    V::IntoIter: Clone,
{
    let records = PreRecords::engine(regs.pre.sh_degree as u8, regs.pre.sh_precision());
    pre_transfers_of(cfg, regs, records, visible, list_lens, each)
}

/// [`pre_transfers`] with records of other sizes (a byte-size preset of the cycle model, such
/// as the artifact's): the same transfers, record `i` of each array at `base + bytes i`.
pub fn pre_transfers_of<V>(
    cfg: &EngineConfig,
    regs: &FrameRegs,
    records: PreRecords,
    visible: V,
    list_lens: impl IntoIterator<Item = usize>,
    mut each: impl FnMut(PreTransfer),
) where
    V: IntoIterator<Item = u64>,
    V::IntoIter: Clone,
{
    let p = &regs.pre;
    let mut out = |part, addr, bytes| each(PreTransfer { part, addr, bytes });
    let PreRecords { geometry: gb, sh, feature } = records;
    for lane in 0..cfg.pre_units {
        let (first, count) = cfg.pre_lane_range(p.gaussians, lane);
        if count > 0 {
            out(PrePart::Geometry, p.geo_base + gb * first as u64, gb * count as u64);
        }
    }
    let visible = visible.into_iter();
    for i in visible.clone() {
        out(PrePart::Sh, p.sh_base + sh * i, sh);
    }
    if !p.fresh() {
        for i in visible {
            out(PrePart::PrevFeature, p.prev_feat_base + feature * i, feature);
        }
    }
    for i in 0..p.gaussians as u64 {
        out(PrePart::Feature, regs.feat_base + feature * i, feature);
    }
    let per_line = LIST_LINE_BYTES / ENTRY_BYTES;
    let mut tiles = 0u64;
    for (t, len) in list_lens.into_iter().enumerate() {
        let base = list_addr(cfg, p.list_base, t as u64);
        let lines = (len as u64).min(cfg.table_capacity as u64).div_ceil(per_line);
        for k in 0..lines {
            out(PrePart::ListLine, base + LIST_LINE_BYTES * k, LIST_LINE_BYTES);
        }
        tiles += 1;
    }
    for t in 0..tiles {
        out(PrePart::ListLen, list_len_addr(regs.desc_base, t), 4);
    }
}

/// The Preprocessing Engine's `(RD_PRE, WR_PRE)` bytes for `regs`: the beats of
/// `axi_data_bits / 8` bytes each of its transfers ([`pre_transfers`]) spans ([`beats_spanned`]),
/// times the beat bytes.
pub fn pre_traffic(
    cfg: &EngineConfig,
    regs: &FrameRegs,
    visible: &[u64],
    list_lens: impl IntoIterator<Item = usize>,
) -> (u64, u64) {
    let beat = cfg.axi_data_bits as u64 / 8;
    let (mut rd, mut wr) = (0, 0);
    pre_transfers(cfg, regs, visible.iter().copied(), list_lens, |t| {
        let bytes = beat * beats_spanned(t.addr, t.bytes, beat);
        if t.part.is_write() {
            wr += bytes;
        } else {
            rd += bytes;
        }
    });
    (rd, wr)
}

/// Writes every tile's list (its first `table_capacity` entries, whole lines) and its length.
fn write_lists(cfg: &EngineConfig, regs: &FrameRegs, mem: &mut Memory, lists: &[Vec<SortEntry>]) {
    let sfmt = cfg.format();
    let per_line = (LIST_LINE_BYTES / ENTRY_BYTES) as usize;
    for (t, list) in lists.iter().enumerate() {
        let base = list_addr(cfg, regs.pre.list_base, t as u64);
        let kept = &list[..list.len().min(cfg.table_capacity)];
        for (k, line) in kept.chunks(per_line).enumerate() {
            let mut bytes = [0u8; LIST_LINE_BYTES as usize];
            for (slot, e) in bytes.chunks_exact_mut(ENTRY_BYTES as usize).zip(line) {
                slot.copy_from_slice(&sfmt.pack(e).to_le_bytes());
            }
            let at = base + LIST_LINE_BYTES * k as u64;
            mem.write(at, &bytes);
        }
        mem.write(list_len_addr(regs.desc_base, t as u64), &(list.len() as u32).to_le_bytes());
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn beats_spanned_counts_every_beat_touched() {
        assert_eq!(beats_spanned(0, 0, 8), 0);
        assert_eq!(beats_spanned(0, 8, 8), 1);
        assert_eq!(beats_spanned(4, 8, 8), 2);
        assert_eq!(beats_spanned(20, 4, 8), 1);
        assert_eq!(beats_spanned(44, 44, 8), 6, "bytes 44..88: beats 5 to 10");
        assert_eq!(beats_spanned(32, 32, 64), 1);
        assert_eq!(beats_spanned(48, 32, 64), 2);
    }

    /// The traffic of an aligned frame, counted by hand: a lane's stream, 192 bytes per visible
    /// Gaussian at SH degree 3 (and 32 of previous word on a reuse frame); 32 bytes per Gaussian,
    /// whole list lines up to the capacity and 8 bytes (a beat) per length.
    #[test]
    fn pre_traffic_counts_each_transfer_by_hand() {
        let cfg = EngineConfig { pre_units: 3, table_capacity: 20, ..EngineConfig::default() };
        let mut regs = FrameRegs { desc_base: 0x1000, feat_base: 0x2_0000, ..FrameRegs::default() };
        regs.pre = PreRegs {
            ctrl: super::super::PRE_ENABLE,
            gaussians: 10,
            sh_degree: 3,
            geo_base: 0x10_0000,
            sh_base: 0x20_0000,
            prev_feat_base: 0x30_0000,
            list_base: 0x40_0000,
            ..PreRegs::default()
        };
        let visible = [1u64, 2, 7];
        // Lists of 0, 9 and 30 entries: 0, 2 and (capacity 20) 3 lines.
        let lens = [0usize, 9, 30];
        // Lanes of 4, 4 and 2 Gaussians of 44 bytes from an aligned base: 22, 22 and 11 beats.
        let geo = 8 * (22 + 22 + 11);
        let (rd, wr) = pre_traffic(&cfg, &regs, &visible, lens);
        assert_eq!(rd, geo + 3 * 192 + 3 * 32);
        assert_eq!(wr, 10 * 32 + 5 * 64 + 3 * 8);
        regs.pre.ctrl |= super::super::PRE_FRESH;
        assert_eq!(pre_traffic(&cfg, &regs, &visible, lens).0, geo + 3 * 192, "fresh: no previous word");
        let mut parts = Vec::new();
        pre_transfers(&cfg, &regs, visible.iter().copied(), lens, |t| parts.push(t));
        let count = |p: PrePart| parts.iter().filter(|t| t.part == p).count();
        assert_eq!(
            PrePart::ALL.map(count),
            [3, 3, 0, 10, 5, 3],
            "geometry, SH, previous, feature, list lines, lengths"
        );
        assert!(parts.windows(2).all(|w| PrePart::ALL.iter().position(|&p| p == w[0].part)
            <= PrePart::ALL.iter().position(|&p| p == w[1].part)));
        let line = parts.iter().filter(|t| t.part == PrePart::ListLine).nth(2).expect("a third line");
        assert_eq!(line.addr, 0x40_0000 + 8 * 24 * 2, "tile 2's list, slot stride 24 entries");
    }
}
