//! The engine's memory formats (byte-addressed, little-endian; docs/formats.md "Engine memory")
//! and [`Memory`], a sparse byte memory the reference ([`super::execute_frame`]) and the test
//! benches' AXI memory models use as backing store.
//!
//! | element | bytes | core address unit | byte address |
//! | --- | --- | --- | --- |
//! | table / list entry `{valid, key, id}` (low bits of a u64) | 8 | entry `a` | `8 a` |
//! | feature word `{present, entry}` (low bits of 32 bytes) | 32 | word `w` | `32 w` |
//! | pixel `{b, g, r}` (low bits of a u32: `0x00BBGGRR`) | 4 | pixel `p` | `4 p` |
//! | tile descriptor ([`TileDescriptor`], 4 u64) | 32 | | `DESC_BASE + 32 t` |
//! | tile result ([`TileResult`], 2 u64) | 16 | | `RESULT_BASE + 16 t` |

use crate::formats::feature::{FeatureEntry, FeatureFormat};
use crate::pipeline::adaptive::WritebackSignals;
use crate::sort::{SortEntry, SortFormat};
use std::collections::HashMap;

/// Bytes of a table or list entry.
pub const ENTRY_BYTES: u64 = 8;
/// Bytes of a feature word.
pub const FEATURE_BYTES: u64 = 32;
/// Bytes of a pixel.
pub const PIXEL_BYTES: u64 = 4;
/// Bytes of a tile descriptor.
pub const DESCRIPTOR_BYTES: u64 = 32;
/// Bytes of a tile result (two u64 words).
pub const RESULT_BYTES: u64 = 16;
/// Bit of the result's word 0 where the merge inversions start.
pub const INVERSIONS_LSB: u32 = 40;
/// Bits of the result's merge-inversion field (the count saturates at its largest value).
pub const INVERSIONS_BITS: u32 = 24;
/// The largest merge-inversion count a result holds: larger counts saturate to it.
pub const INVERSIONS_MAX: u32 = (1 << INVERSIONS_BITS) - 1;

/// One tile's descriptor: 4 little-endian u64 words at `DESC_BASE + 32 t`.
///
/// - word 0: `[15:0]` tile_x, `[31:16]` tile_y, `[32]` from_scratch, `[43:40]` dps_passes,
///   `[44]` dps_wide
/// - word 1: `[31:0]` prev table entry address, `[63:32]` prev_len
/// - word 2: `[31:0]` incoming list entry address, `[63:32]` list_len
/// - word 3: `[31:0]` next table entry address, `[63:32]` reserved 0
///
/// Decoding ignores the reserved bits (as the RTL does).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct TileDescriptor {
    /// Tile column.
    pub tile_x: u16,
    /// Tile row.
    pub tile_y: u16,
    /// No previous table (frame 0 or after a cut): the list holds every entry and is sorted
    /// conventionally into `next`.
    pub from_scratch: bool,
    /// Entry address of the previous table (ignored when `from_scratch`).
    pub prev: u32,
    /// Entries of the previous table.
    pub prev_len: u32,
    /// Entry address of the incoming list (unsorted).
    pub list: u32,
    /// Entries of the incoming list.
    pub list_len: u32,
    /// Entry address of the next table (the host double-buffers the tables).
    pub next: u32,
    /// DPS passes over the previous table of a reuse tile, pass `p` with golden
    /// [`Parity::of`](crate::sort::Parity::of)`(frame, p)` (Neo: 1; 0: none, the previous table
    /// is merged as it is); at most [`MAX_DPS_PASSES`] (a larger value is truncated to its
    /// [`DPS_PASSES_BITS`] bits, as the RTL reads it).
    pub dps_passes: u8,
    /// The DPS passes sort chunks of the wide chunk ([`EngineConfig::sort_buffer`]) instead
    /// of the chunk (golden `adaptive` with `wide`; no effect on an engine without one,
    /// `dps_wide` 1, whose wide chunk is the chunk).
    ///
    /// [`EngineConfig::sort_buffer`]: crate::engine::EngineConfig::sort_buffer
    pub dps_wide: bool,
}

/// The bit of `dps_wide` in descriptor word 0.
pub const DPS_WIDE_BIT: u32 = 44;

/// Bits of a descriptor's `dps_passes` field.
pub const DPS_PASSES_BITS: u32 = 4;
/// The most DPS passes a descriptor can ask for.
pub const MAX_DPS_PASSES: u8 = (1 << DPS_PASSES_BITS) - 1;
/// The lowest bit of `dps_passes` in descriptor word 0.
pub const DPS_PASSES_LSB: u32 = 40;

impl Default for TileDescriptor {
    /// An empty tile at (0, 0), reused with Neo's single DPS pass.
    fn default() -> TileDescriptor {
        TileDescriptor {
            tile_x: 0,
            tile_y: 0,
            from_scratch: false,
            prev: 0,
            prev_len: 0,
            list: 0,
            list_len: 0,
            next: 0,
            dps_passes: 1,
            dps_wide: false,
        }
    }
}

impl TileDescriptor {
    /// The DPS passes the engine runs: `dps_passes` as its [`DPS_PASSES_BITS`] bits of word 0
    /// hold it (the value the RTL reads).
    pub fn passes(&self) -> u64 {
        u64::from(self.dps_passes & MAX_DPS_PASSES)
    }

    /// The four words, word 0 first.
    pub fn to_words(&self) -> [u64; 4] {
        let passes = self.passes();
        [
            self.tile_x as u64
                | (self.tile_y as u64) << 16
                | (self.from_scratch as u64) << 32
                | passes << DPS_PASSES_LSB
                | (self.dps_wide as u64) << DPS_WIDE_BIT,
            self.prev as u64 | (self.prev_len as u64) << 32,
            self.list as u64 | (self.list_len as u64) << 32,
            self.next as u64,
        ]
    }

    /// Decodes four words (reserved bits ignored).
    pub fn from_words(w: &[u64; 4]) -> TileDescriptor {
        TileDescriptor {
            tile_x: w[0] as u16,
            tile_y: (w[0] >> 16) as u16,
            from_scratch: (w[0] >> 32) & 1 == 1,
            prev: w[1] as u32,
            prev_len: (w[1] >> 32) as u32,
            list: w[2] as u32,
            list_len: (w[2] >> 32) as u32,
            next: w[3] as u32,
            dps_passes: (w[0] >> DPS_PASSES_LSB) as u8 & MAX_DPS_PASSES,
            dps_wide: (w[0] >> DPS_WIDE_BIT) & 1 == 1,
        }
    }

    /// Entries the tile's sort takes in (`list_len`, plus `prev_len` unless from scratch):
    /// the tile overflows when this exceeds the table capacity.
    pub fn entries_in(&self) -> u64 {
        self.list_len as u64 + if self.from_scratch { 0 } else { self.prev_len as u64 }
    }
}

/// One tile's result: two little-endian u64 words at `RESULT_BASE + 16 t`, written once the
/// tile is rastered (one 2-beat burst):
///
/// - word 0: `[31:0]` next_len, `[32]` overflow, `[63:40]` merge_inversions (saturating)
/// - word 1: `[31:0]` wb_len, `[63:32]` wb_reach
///
/// The counters are the disorder signals of `pipeline::adaptive` the hardware counts for free
/// (issue 14): the MSU+ boundary inversions of the reused table in the tile's MERGE_DELETE
/// ([`crate::sort::MergeStats::a_inversions`]; 0 from scratch or on overflow), and the
/// write-back's valid entries and reach ([`crate::pipeline::adaptive::writeback_signals`] of
/// the table as rastered and written back). Decoding ignores bits `[39:33]`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct TileResult {
    /// Entries of the next table (0 when overflowed).
    pub next_len: u32,
    /// The tile did not fit the table capacity and was not sorted.
    pub overflow: bool,
    /// MSU+ boundary inversions of the reused table (at most `2^24 - 1`: saturating).
    pub merge_inversions: u32,
    /// Valid entries of the table after the write-back.
    pub wb_len: u32,
    /// Write-back reach: the largest distance from the running maximum to a later valid entry
    /// that precedes it.
    pub wb_reach: u32,
}

impl TileResult {
    /// The result of a tile with these counters (the inversions saturate at the field).
    pub fn new(next_len: u32, overflow: bool, merge_inversions: u64, wb: &WritebackSignals) -> Self {
        TileResult {
            next_len,
            overflow,
            merge_inversions: merge_inversions.min(INVERSIONS_MAX as u64) as u32,
            wb_len: wb.len,
            wb_reach: wb.reach,
        }
    }

    /// The result of an overflowing tile: nothing sorted, rastered empty.
    pub fn overflowed() -> Self {
        TileResult { overflow: true, ..TileResult::default() }
    }

    /// The result's two words.
    pub fn to_words(&self) -> [u64; 2] {
        let inv = self.merge_inversions.min(INVERSIONS_MAX) as u64;
        [
            self.next_len as u64 | (self.overflow as u64) << 32 | inv << INVERSIONS_LSB,
            self.wb_len as u64 | (self.wb_reach as u64) << 32,
        ]
    }

    /// Decodes a result's words.
    pub fn from_words(w: &[u64; 2]) -> TileResult {
        TileResult {
            next_len: w[0] as u32,
            overflow: (w[0] >> 32) & 1 == 1,
            merge_inversions: (w[0] >> INVERSIONS_LSB) as u32 & INVERSIONS_MAX,
            wb_len: w[1] as u32,
            wb_reach: (w[1] >> 32) as u32,
        }
    }
}

/// An entry as its memory word (the packed `{valid, key, id}` in the low bits).
pub fn entry_to_u64(fmt: &SortFormat, e: &SortEntry) -> u64 {
    fmt.pack(e)
}

/// The entry of a memory word (bits above the entry width ignored).
pub fn entry_from_u64(fmt: &SortFormat, w: u64) -> SortEntry {
    fmt.unpack(w)
}

/// Bits of a feature word: the packed entry plus the `present` bit on top.
pub fn feature_word_bits(fmt: &FeatureFormat) -> u32 {
    fmt.bits_per_entry() + 1
}

/// A feature word's 32 bytes: `{present, entry}`, `present` at bit `bits_per_entry`, 0 when
/// `f` is `None` (a Gaussian culled this frame: the entry bits are 0).
///
/// # Panics
/// When the format's word does not fit 256 bits (a configuration error).
pub fn feature_to_bytes(fmt: &FeatureFormat, f: Option<&FeatureEntry>) -> [u8; 32] {
    let bits = fmt.bits_per_entry();
    assert!(bits < 256, "feature word of {} bits does not fit {FEATURE_BYTES} bytes", bits + 1);
    let mut out = [0u8; 32];
    if let Some(f) = f {
        for (k, w) in f.pack(fmt).iter().enumerate() {
            out[8 * k..8 * k + 8].copy_from_slice(&w.to_le_bytes());
        }
        out[bits as usize / 8] |= 1 << (bits % 8);
    }
    out
}

/// The feature entry of a feature word, `None` when its `present` bit is clear.
pub fn feature_from_bytes(fmt: &FeatureFormat, b: &[u8; 32]) -> Option<FeatureEntry> {
    let bits = fmt.bits_per_entry();
    if (b[bits as usize / 8] >> (bits % 8)) & 1 == 0 {
        return None;
    }
    let words: Vec<u64> =
        b.chunks_exact(8).map(|c| u64::from_le_bytes(c.try_into().expect("8 bytes"))).collect();
    Some(FeatureEntry::unpack(&words, fmt))
}

/// A pixel `[r, g, b]` as its memory word `0x00BBGGRR`.
pub fn pixel_to_u32(p: [u8; 3]) -> u32 {
    p[0] as u32 | (p[1] as u32) << 8 | (p[2] as u32) << 16
}

/// The pixel `[r, g, b]` of a memory word (the top byte ignored).
pub fn pixel_from_u32(w: u32) -> [u8; 3] {
    [w as u8, (w >> 8) as u8, (w >> 16) as u8]
}

/// Bytes of a [`Memory`] page.
pub const PAGE_BYTES: u64 = 4096;

/// A sparse byte memory: 4 KiB pages allocated on first write; bytes never written read as 0.
#[derive(Clone, Debug, Default)]
pub struct Memory {
    pages: HashMap<u64, Box<[u8; PAGE_BYTES as usize]>>,
}

impl PartialEq for Memory {
    /// Equal when every byte reads the same (an absent page equals a page of zeros).
    fn eq(&self, other: &Memory) -> bool {
        let zero = [0u8; PAGE_BYTES as usize];
        let same = |a: &Memory, b: &Memory| {
            a.pages.iter().all(|(k, p)| b.pages.get(k).map_or(p[..] == zero[..], |q| p[..] == q[..]))
        };
        same(self, other) && same(other, self)
    }
}

impl Eq for Memory {}

impl Memory {
    /// An empty memory (every byte 0).
    pub fn new() -> Memory {
        Memory::default()
    }

    /// Whether any byte of `addr..addr + len` lies in a page that was written.
    pub fn touches(&self, addr: u64, len: u64) -> bool {
        (len > 0) && (addr / PAGE_BYTES..=(addr + len - 1) / PAGE_BYTES).any(|p| self.pages.contains_key(&p))
    }

    /// Pages written so far (their indices, `addr / PAGE_BYTES`), sorted.
    pub fn page_indices(&self) -> Vec<u64> {
        let mut v: Vec<u64> = self.pages.keys().copied().collect();
        v.sort_unstable();
        v
    }

    /// Reads `out.len()` bytes at `addr`.
    pub fn read(&self, addr: u64, out: &mut [u8]) {
        let mut done = 0;
        while done < out.len() {
            let a = addr + done as u64;
            let off = (a % PAGE_BYTES) as usize;
            let n = (PAGE_BYTES as usize - off).min(out.len() - done);
            match self.pages.get(&(a / PAGE_BYTES)) {
                Some(p) => out[done..done + n].copy_from_slice(&p[off..off + n]),
                None => out[done..done + n].fill(0),
            }
            done += n;
        }
    }

    /// Writes `data` at `addr`.
    pub fn write(&mut self, addr: u64, data: &[u8]) {
        let mut done = 0;
        while done < data.len() {
            let a = addr + done as u64;
            let off = (a % PAGE_BYTES) as usize;
            let n = (PAGE_BYTES as usize - off).min(data.len() - done);
            let page = self.pages.entry(a / PAGE_BYTES).or_insert_with(|| Box::new([0; PAGE_BYTES as usize]));
            page[off..off + n].copy_from_slice(&data[done..done + n]);
            done += n;
        }
    }

    /// Writes the bytes of `data` whose `strobe` bit is set (AXI `wstrb`: bit `i` for byte
    /// `i`), at `addr`.
    pub fn write_strobed(&mut self, addr: u64, data: &[u8], strobe: u128) {
        for (i, b) in data.iter().enumerate() {
            if i < 128 && (strobe >> i) & 1 == 1 {
                self.write(addr + i as u64, std::slice::from_ref(b));
            }
        }
    }

    /// The little-endian u64 at `addr`.
    pub fn read_u64(&self, addr: u64) -> u64 {
        let mut b = [0u8; 8];
        self.read(addr, &mut b);
        u64::from_le_bytes(b)
    }

    /// Writes a little-endian u64 at `addr`.
    pub fn write_u64(&mut self, addr: u64, v: u64) {
        self.write(addr, &v.to_le_bytes());
    }

    /// The little-endian u32 at `addr`.
    pub fn read_u32(&self, addr: u64) -> u32 {
        let mut b = [0u8; 4];
        self.read(addr, &mut b);
        u32::from_le_bytes(b)
    }

    /// Writes a little-endian u32 at `addr`.
    pub fn write_u32(&mut self, addr: u64, v: u32) {
        self.write(addr, &v.to_le_bytes());
    }

    /// `len` entries from entry address `a` (byte `8 a`).
    pub fn read_entries(&self, fmt: &SortFormat, a: u64, len: usize) -> Vec<SortEntry> {
        (0..len as u64).map(|i| entry_from_u64(fmt, self.read_u64(ENTRY_BYTES * (a + i)))).collect()
    }

    /// Writes `entries` from entry address `a` on.
    pub fn write_entries(&mut self, fmt: &SortFormat, a: u64, entries: &[SortEntry]) {
        for (i, e) in entries.iter().enumerate() {
            self.write_u64(ENTRY_BYTES * (a + i as u64), entry_to_u64(fmt, e));
        }
    }

    /// The feature word at word address `w` (byte `32 w`); `None` when not present.
    pub fn read_feature(&self, fmt: &FeatureFormat, w: u64) -> Option<FeatureEntry> {
        let mut b = [0u8; 32];
        self.read(FEATURE_BYTES * w, &mut b);
        feature_from_bytes(fmt, &b)
    }

    /// Writes the feature word at word address `w`.
    pub fn write_feature(&mut self, fmt: &FeatureFormat, w: u64, f: Option<&FeatureEntry>) {
        self.write(FEATURE_BYTES * w, &feature_to_bytes(fmt, f));
    }

    /// The pixel at pixel address `p` (byte `4 p`).
    pub fn read_pixel(&self, p: u64) -> [u8; 3] {
        pixel_from_u32(self.read_u32(PIXEL_BYTES * p))
    }

    /// Writes the pixel at pixel address `p`.
    pub fn write_pixel(&mut self, p: u64, px: [u8; 3]) {
        self.write_u32(PIXEL_BYTES * p, pixel_to_u32(px));
    }

    /// Descriptor `t` of the table at byte address `base`.
    pub fn read_descriptor(&self, base: u64, t: u64) -> TileDescriptor {
        let a = base + DESCRIPTOR_BYTES * t;
        TileDescriptor::from_words(&[0, 1, 2, 3].map(|k| self.read_u64(a + 8 * k)))
    }

    /// Writes descriptor `t` of the table at byte address `base`.
    pub fn write_descriptor(&mut self, base: u64, t: u64, d: &TileDescriptor) {
        for (k, w) in d.to_words().iter().enumerate() {
            self.write_u64(base + DESCRIPTOR_BYTES * t + 8 * k as u64, *w);
        }
    }

    /// Result `t` of the table at byte address `base`.
    pub fn read_result(&self, base: u64, t: u64) -> TileResult {
        let a = base + RESULT_BYTES * t;
        TileResult::from_words(&[self.read_u64(a), self.read_u64(a + 8)])
    }

    /// Writes result `t` of the table at byte address `base`.
    pub fn write_result(&mut self, base: u64, t: u64, r: &TileResult) {
        let [w0, w1] = r.to_words();
        self.write_u64(base + RESULT_BYTES * t, w0);
        self.write_u64(base + RESULT_BYTES * t + 8, w1);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn descriptor_layout_is_the_contract() {
        let d = TileDescriptor {
            tile_x: 0x12,
            tile_y: 0x34,
            from_scratch: true,
            prev: 0x1000,
            prev_len: 7,
            list: 0x2000,
            list_len: 9,
            next: 0x3000,
            dps_passes: 3,
            dps_wide: true,
        };
        assert_eq!(d.to_words(), [0x1301_0034_0012, 7 << 32 | 0x1000, 9 << 32 | 0x2000, 0x3000]);
        assert_eq!(d.entries_in(), 9);
        assert_eq!(TileDescriptor { from_scratch: false, ..d }.entries_in(), 16);
        // Reserved bits are ignored.
        let mut w = d.to_words();
        w[0] |= 0xFFFF_E0FE << 32;
        w[3] |= 0xABCD << 32;
        assert_eq!(TileDescriptor::from_words(&w), d);
    }

    #[test]
    fn result_and_pixel_layouts() {
        let r = TileResult { next_len: 5, overflow: true, merge_inversions: 0xAB, wb_len: 7, wb_reach: 2 };
        assert_eq!(r.to_words(), [0xAB01_0000_0005, 2 << 32 | 7]);
        // Bits 39:33 are ignored; the inversions saturate at 24 bits.
        let w = [0xFFFF_FFFE_0000_0003, 0];
        assert_eq!(
            TileResult::from_words(&w),
            TileResult { next_len: 3, merge_inversions: 0xFF_FFFF, ..TileResult::default() }
        );
        let wb = WritebackSignals { len: 9, reach: 4, ..WritebackSignals::default() };
        let big = TileResult::new(9, false, 1 << 30, &wb);
        assert_eq!((big.merge_inversions, big.wb_len, big.wb_reach), (0xFF_FFFF, 9, 4));
        assert_eq!(pixel_to_u32([0x11, 0x22, 0x33]), 0x0033_2211);
        assert_eq!(pixel_from_u32(0xFF33_2211), [0x11, 0x22, 0x33]);
    }

    #[test]
    fn feature_word_has_present_on_top() {
        let fmt = FeatureFormat::default();
        assert_eq!(feature_word_bits(&fmt), 255);
        assert_eq!(feature_to_bytes(&fmt, None), [0; 32]);
        let f = FeatureEntry { opacity: 3, depth_key: 0x1234, ..FeatureEntry::default() };
        let b = feature_to_bytes(&fmt, Some(&f));
        assert_eq!(b[254 / 8] >> (254 % 8) & 1, 1);
        assert_eq!(b[31] >> 7, 0, "nothing above bit 254");
        assert_eq!(feature_from_bytes(&fmt, &b), Some(f));
        let mut culled = b;
        culled[254 / 8] &= !(1 << (254 % 8));
        assert_eq!(feature_from_bytes(&fmt, &culled), None);
    }

    #[test]
    fn memory_reads_zero_and_crosses_pages() {
        let mut m = Memory::new();
        assert_eq!(m.read_u64(0x1234_5678), 0);
        assert!(!m.touches(0, 1 << 40));
        m.write_u64(PAGE_BYTES - 4, 0x0102_0304_0506_0708);
        assert_eq!(m.read_u64(PAGE_BYTES - 4), 0x0102_0304_0506_0708);
        assert_eq!(m.read_u32(PAGE_BYTES), 0x0102_0304);
        assert_eq!(m.page_indices(), vec![0, 1]);
        assert!(m.touches(PAGE_BYTES, 1) && !m.touches(2 * PAGE_BYTES, 8));
        m.write_strobed(0x10, &[1, 2, 3, 4], 0b1010);
        assert_eq!(m.read_u32(0x10), 0x0400_0200);
        let mut zeros = Memory::new();
        zeros.write_u64(5 * PAGE_BYTES, 0);
        assert_eq!(zeros, Memory::new());
        assert_ne!(m, Memory::new());
    }

    fn arb_feature() -> impl Strategy<Value = FeatureEntry> {
        let fmt = FeatureFormat::default();
        proptest::collection::vec(any::<u64>(), 4).prop_map(move |w| FeatureEntry::unpack(&w, &fmt))
    }

    proptest! {
        #[test]
        fn descriptor_round_trip(x in any::<u16>(), y in any::<u16>(), s in any::<bool>(), v in any::<[u32; 5]>(), p in 0..=MAX_DPS_PASSES, wide in any::<bool>()) {
            let d = TileDescriptor { tile_x: x, tile_y: y, from_scratch: s, prev: v[0], prev_len: v[1], list: v[2], list_len: v[3], next: v[4], dps_passes: p, dps_wide: wide };
            prop_assert_eq!(TileDescriptor::from_words(&d.to_words()), d);
            let mut m = Memory::new();
            m.write_descriptor(0x40, 3, &d);
            prop_assert_eq!(m.read_descriptor(0x40, 3), d);
            prop_assert_eq!(m.read_u64(0x40 + 96), d.to_words()[0]);
        }

        #[test]
        fn result_round_trip(
            n in any::<u32>(), o in any::<bool>(), inv in 0u32..1 << 24, l in any::<u32>(), r in any::<u32>()
        ) {
            let r = TileResult { next_len: n, overflow: o, merge_inversions: inv, wb_len: l, wb_reach: r };
            prop_assert_eq!(TileResult::from_words(&r.to_words()), r);
            prop_assert_eq!(r.to_words()[0] >> 33 & 0x7F, 0, "bits 39:33 stay 0");
            let mut m = Memory::new();
            m.write_result(0x100, 2, &r);
            prop_assert_eq!(m.read_result(0x100, 2), r);
            prop_assert_eq!(m.read_u64(0x100 + 48), 0, "a result is 16 bytes");
            prop_assert_eq!(m.read_u64(0x100 + 24), 0, "a result is 16 bytes");
        }

        #[test]
        fn entry_round_trip(key in any::<u16>(), id in 0u32..0x7FFF_FFFF, valid in any::<bool>(), a in 0u64..1 << 30) {
            let fmt = SortFormat::ARTIFACT;
            let e = SortEntry { key: key as u32, id, valid };
            prop_assert_eq!(entry_from_u64(&fmt, entry_to_u64(&fmt, &e)), e);
            let mut m = Memory::new();
            m.write_entries(&fmt, a, &[e, e.with_valid(!valid)]);
            prop_assert_eq!(m.read_u64(8 * a), entry_to_u64(&fmt, &e));
            prop_assert_eq!(m.read_entries(&fmt, a, 2), vec![e, e.with_valid(!valid)]);
        }

        #[test]
        fn feature_round_trip(f in arb_feature(), w in 0u64..1 << 20) {
            let fmt = FeatureFormat::default();
            let mut m = Memory::new();
            m.write_feature(&fmt, w, Some(&f));
            prop_assert_eq!(m.read_feature(&fmt, w), Some(f));
            m.write_feature(&fmt, w + 1, None);
            prop_assert_eq!(m.read_feature(&fmt, w + 1), None);
        }

        #[test]
        fn pixel_round_trip(p in any::<[u8; 3]>(), a in any::<u32>()) {
            prop_assert_eq!(pixel_from_u32(pixel_to_u32(p)), p);
            let mut m = Memory::new();
            m.write_pixel(a as u64, p);
            prop_assert_eq!(m.read_pixel(a as u64), p);
            prop_assert_eq!(m.read_u32(4 * a as u64) >> 24, 0);
        }

        #[test]
        fn bytes_round_trip(addr in 0u64..1 << 40, data in proptest::collection::vec(any::<u8>(), 0..10_000)) {
            let mut m = Memory::new();
            m.write(addr, &data);
            let mut back = vec![0u8; data.len()];
            m.read(addr, &mut back);
            prop_assert_eq!(back, data);
        }
    }
}
