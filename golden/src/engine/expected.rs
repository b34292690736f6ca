//! What a frame must leave in memory and in the registers ([`Expected`], built by the host
//! session from the golden pipeline), and the checker that names the first difference
//! ([`Expected::compare`], [`Expected::compare_outcome`], [`Mismatch`]).

use super::memory::{
    entry_to_u64, pixel_to_u32, Memory, TileDescriptor, DESCRIPTOR_BYTES, ENTRY_BYTES, FEATURE_BYTES,
    PIXEL_BYTES, RESULT_BYTES,
};
use super::reference::FrameOutcome;
use super::regs::{Counter, FrameRegs};
use crate::sort::{SortEntry, SortFormat};
use std::fmt;

/// Entries that must be unchanged by the frame (an overflowing tile's next region and previous
/// table): raw words from entry address `addr` on.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Untouched {
    /// The tile.
    pub tile: u64,
    /// Entry address of the first word.
    pub addr: u64,
    /// The words (as the host left them).
    pub words: Vec<u64>,
}

/// The expected state after one frame.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Expected {
    /// The frame's registers (bases, size, tile count).
    pub regs: FrameRegs,
    /// The descriptors the host wrote (tile `t` at index `t`).
    pub descriptors: Vec<TileDescriptor>,
    /// Every tile's table after the write-back, at the descriptor's `next` (empty when the
    /// tile overflowed).
    pub tables: Vec<Vec<SortEntry>>,
    /// Regions an overflowing tile must not touch.
    pub untouched: Vec<Untouched>,
    /// Every tile's `tile * tile` pixels, row-major (black outside the image), as the tile-major
    /// frame buffer holds them: tile `t`'s pixels from pixel address `FB_BASE / 4 + t tile^2`.
    pub pixels: Vec<Vec<[u8; 3]>>,
    /// Results, status, overflow registers and the golden counters.
    pub outcome: FrameOutcome,
    /// The entry format.
    pub format: SortFormat,
    /// Tile side in pixels.
    pub tile: u32,
    /// What the Preprocessing Engine must leave (scene mode; `None` when the host wrote the
    /// lists and feature words).
    pub pre: Option<PreExpected>,
}

/// What the Preprocessing Engine must leave besides the counters: every feature word of the
/// frame, every tile's incoming list and its length in the descriptor ([`Expected::descriptors`]
/// hold the lengths it must write; the rest of each descriptor must be as the host wrote it).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PreExpected {
    /// Feature word of Gaussian `i` (at `FEAT_BASE + 32 i`), for every Gaussian of the scene.
    pub features: Vec<[u8; FEATURE_BYTES as usize]>,
    /// Every tile's incoming list at its full length, in any order: the engine's list holds
    /// the same entries in an order of its choosing (all of them when the list fits the table
    /// capacity; else `table_capacity` distinct ones of them).
    pub lists: Vec<Vec<SortEntry>>,
    /// The list base (bytes).
    pub list_base: u64,
    /// Entries between two tiles' lists ([`super::EngineConfig::list_stride`]).
    pub list_stride: u64,
    /// Entries of a list the engine writes at most (`table_capacity`).
    pub capacity: u64,
    /// The feature word's `present` bit ([`super::memory::feature_word_bits`] - 1).
    pub present_bit: u32,
}

/// Where a mismatch is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Place {
    /// The tile's result word.
    Result,
    /// Entry `i` of the tile's next table (entry address in the mismatch's `addr`).
    Entry(u64),
    /// A word of a region the tile must not touch.
    Untouched,
    /// Pixel `(x, y)` of the tile (image pixel `(tile_x * tile + x, tile_y * tile + y)`).
    Pixel(u32, u32),
    /// A status or overflow register.
    Register,
    /// Word `k` (u64 `k` of 4) of the tile's descriptor (`list_len` is the high half of word 2).
    Descriptor(u32),
    /// The feature word of Gaussian `i` (the mismatch's `tile` is `None`).
    Feature(u32),
    /// Slot `k` of the tile's incoming list, the list and the engine's entries each sorted by
    /// `(key, id)` (the order within a list is the engine's choice).
    List(u64),
    /// A performance counter.
    Counter(Counter),
}

/// The first difference between the engine's state and [`Expected`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Mismatch {
    /// The tile (`None` for registers and counters).
    pub tile: Option<u64>,
    /// Tile `[x, y]` (when `tile` is some).
    pub tile_xy: [u16; 2],
    /// What differs.
    pub place: Place,
    /// The byte address (memory mismatches), 0 otherwise.
    pub addr: u64,
    /// The field (`next_len`, `overflow`, `valid`, `key`, `id`, `word`, `red`, `green`, `blue`,
    /// a register or counter name).
    pub field: &'static str,
    /// Expected value.
    pub expected: u64,
    /// Actual value.
    pub actual: u64,
}

impl fmt::Display for Mismatch {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if let Some(t) = self.tile {
            write!(f, "tile {t} ({}, {}) ", self.tile_xy[0], self.tile_xy[1])?;
        }
        match self.place {
            Place::Result => write!(f, "result")?,
            Place::Entry(i) => write!(f, "table[{i}]")?,
            Place::Untouched => write!(f, "untouched word")?,
            Place::Pixel(x, y) => write!(f, "pixel ({x}, {y})")?,
            Place::Register => write!(f, "register")?,
            Place::Descriptor(k) => write!(f, "descriptor word {k}")?,
            Place::Feature(i) => write!(f, "feature word of Gaussian {i}")?,
            Place::List(k) => write!(f, "incoming list (sorted) slot {k}")?,
            Place::Counter(_) => write!(f, "counter")?,
        }
        if self.addr != 0 {
            write!(f, " at 0x{:x}", self.addr)?;
        }
        write!(f, " {}: expected 0x{:x}, actual 0x{:x}", self.field, self.expected, self.actual)
    }
}

impl Expected {
    fn at(&self, t: u64, place: Place, addr: u64, field: &'static str, e: u64, a: u64) -> Option<Mismatch> {
        let d = &self.descriptors[t as usize];
        (e != a).then_some(Mismatch {
            tile: Some(t),
            tile_xy: [d.tile_x, d.tile_y],
            place,
            addr,
            field,
            expected: e,
            actual: a,
        })
    }

    /// The first memory difference: in scene mode first the Preprocessing Engine's output
    /// ([`Expected::compare_pre`]); then per tile in index order its result, its next table
    /// (valid, key, id, then the whole word), the regions it must not touch, then its pixels
    /// (red, green, blue, then the whole word).
    pub fn compare(&self, mem: &Memory) -> Option<Mismatch> {
        self.compare_pre(mem).or_else(|| self.compare_tiles(mem))
    }

    fn compare_tiles(&self, mem: &Memory) -> Option<Mismatch> {
        (0..self.descriptors.len() as u64).find_map(|t| {
            self.compare_result(mem, t)
                .or_else(|| self.compare_table(mem, t))
                .or_else(|| self.compare_untouched(mem, t))
                .or_else(|| self.compare_pixels(mem, t))
        })
    }

    /// The first difference in what the Preprocessing Engine leaves (`None` in lists mode):
    /// every feature word in Gaussian order (the present bit, then the u64 that differs, its
    /// byte address in the mismatch), then per tile its descriptor (`list_len`, then each word)
    /// and its incoming list ([`Place::List`]: the engine's entries sorted by `(key, id)`
    /// against the expected ones; with more entries than the capacity, each entry the engine
    /// wrote must be a distinct one of them), then the zero slots of its last line.
    pub fn compare_pre(&self, mem: &Memory) -> Option<Mismatch> {
        let pre = self.pre.as_ref()?;
        self.compare_features(mem, pre).or_else(|| {
            (0..self.descriptors.len() as u64)
                .find_map(|t| self.compare_descriptor(mem, t).or_else(|| self.compare_list(mem, pre, t)))
        })
    }

    fn compare_features(&self, mem: &Memory, pre: &PreExpected) -> Option<Mismatch> {
        let bit = pre.present_bit as usize;
        let present = |b: &[u8; FEATURE_BYTES as usize]| (b[bit / 8] >> (bit % 8)) & 1;
        pre.features.iter().enumerate().find_map(|(i, want)| {
            let addr = self.regs.feat_base + FEATURE_BYTES * i as u64;
            let mut got = [0u8; FEATURE_BYTES as usize];
            mem.read(addr, &mut got);
            let m = |field, addr, e, a| Mismatch {
                tile: None,
                tile_xy: [0, 0],
                place: Place::Feature(i as u32),
                addr,
                field,
                expected: e,
                actual: a,
            };
            let (pw, pg) = (present(want), present(&got));
            if pw != pg {
                return Some(m("present", addr, pw as u64, pg as u64));
            }
            (0..4).find_map(|k| {
                let w = u64::from_le_bytes(want[8 * k..8 * k + 8].try_into().expect("8 bytes"));
                let g = u64::from_le_bytes(got[8 * k..8 * k + 8].try_into().expect("8 bytes"));
                (w != g).then(|| m("bits", addr + 8 * k as u64, w, g))
            })
        })
    }

    fn compare_descriptor(&self, mem: &Memory, t: u64) -> Option<Mismatch> {
        let want = self.descriptors[t as usize];
        let addr = self.regs.desc_base + DESCRIPTOR_BYTES * t;
        let got = mem.read_descriptor(self.regs.desc_base, t);
        self.at(t, Place::Descriptor(2), addr + 16, "list_len", want.list_len as u64, got.list_len as u64)
            .or_else(|| {
                want.to_words().iter().enumerate().find_map(|(k, &w)| {
                    let a = addr + 8 * k as u64;
                    self.at(t, Place::Descriptor(k as u32), a, "word", w, mem.read_u64(a))
                })
            })
    }

    fn compare_list(&self, mem: &Memory, pre: &PreExpected, t: u64) -> Option<Mismatch> {
        let base = pre.list_base / ENTRY_BYTES + t * pre.list_stride;
        let want = &pre.lists[t as usize];
        let kept = (want.len() as u64).min(pre.capacity);
        let word = |k: u64| mem.read_u64(ENTRY_BYTES * (base + k));
        let mut got: Vec<u64> = (0..kept).map(word).collect();
        got.sort_unstable_by_key(|&w| self.format.unpack(w).order_key());
        let mut packed: Vec<u64> = want.iter().map(|e| entry_to_u64(&self.format, e)).collect();
        packed.sort_unstable_by_key(|&w| self.format.unpack(w).order_key());
        let first_bad = if kept == want.len() as u64 {
            got.iter().zip(&packed).position(|(g, w)| g != w).map(|k| (k, packed[k], "entry"))
        } else {
            let known: std::collections::HashSet<u64> = packed.iter().copied().collect();
            let dup = got.windows(2).position(|w| w[0] == w[1]).map(|k| (k + 1, got[k], "duplicate entry"));
            got.iter().position(|g| !known.contains(g)).map(|k| (k, 0, "entry not incoming")).or(dup)
        };
        if let Some((k, w, field)) = first_bad {
            let addr = ENTRY_BYTES * (base + k as u64);
            return self.at(t, Place::List(k as u64), addr, field, w, got[k]);
        }
        (kept..kept.next_multiple_of(8)).find_map(|k| {
            let addr = ENTRY_BYTES * (base + k);
            self.at(t, Place::List(k), addr, "zero slot past the length", 0, word(k))
        })
    }

    fn compare_result(&self, mem: &Memory, t: u64) -> Option<Mismatch> {
        let want = self.outcome.results[t as usize];
        let addr = self.regs.result_base + RESULT_BYTES * t;
        let got = mem.read_result(self.regs.result_base, t);
        let at = |field, w: u32, g: u32| self.at(t, Place::Result, addr, field, w as u64, g as u64);
        at("next_len", want.next_len, got.next_len)
            .or_else(|| at("overflow", want.overflow as u32, got.overflow as u32))
            .or_else(|| at("merge_inversions", want.merge_inversions, got.merge_inversions))
            .or_else(|| at("wb_len", want.wb_len, got.wb_len))
            .or_else(|| at("wb_reach", want.wb_reach, got.wb_reach))
            .or_else(|| {
                let words = want.to_words().into_iter().zip([addr, addr + 8]);
                words.into_iter().find_map(|(w, a)| self.at(t, Place::Result, a, "word", w, mem.read_u64(a)))
            })
    }

    fn compare_table(&self, mem: &Memory, t: u64) -> Option<Mismatch> {
        let base = self.descriptors[t as usize].next as u64;
        self.tables[t as usize].iter().enumerate().find_map(|(i, w)| {
            let addr = ENTRY_BYTES * (base + i as u64);
            let raw = mem.read_u64(addr);
            let g = self.format.unpack(raw);
            let p = Place::Entry(i as u64);
            self.at(t, p, addr, "valid", w.valid as u64, g.valid as u64)
                .or_else(|| self.at(t, p, addr, "key", w.key as u64, g.key as u64))
                .or_else(|| self.at(t, p, addr, "id", w.id as u64, g.id as u64))
                .or_else(|| self.at(t, p, addr, "word", entry_to_u64(&self.format, w), raw))
        })
    }

    fn compare_untouched(&self, mem: &Memory, t: u64) -> Option<Mismatch> {
        self.untouched.iter().filter(|u| u.tile == t).find_map(|u| {
            u.words.iter().enumerate().find_map(|(i, &w)| {
                let addr = ENTRY_BYTES * (u.addr + i as u64);
                self.at(t, Place::Untouched, addr, "word", w, mem.read_u64(addr))
            })
        })
    }

    fn compare_pixels(&self, mem: &Memory, t: u64) -> Option<Mismatch> {
        let n = (self.tile * self.tile) as u64;
        let base = self.regs.fb_base / PIXEL_BYTES + t * n;
        self.pixels[t as usize].iter().enumerate().find_map(|(k, w)| {
            let addr = PIXEL_BYTES * (base + k as u64);
            let raw = mem.read_u32(addr);
            let g = mem.read_pixel(base + k as u64);
            let p = Place::Pixel(k as u32 % self.tile, k as u32 / self.tile);
            ["red", "green", "blue"]
                .iter()
                .enumerate()
                .find_map(|(c, name)| self.at(t, p, addr, name, w[c] as u64, g[c] as u64))
                .or_else(|| self.at(t, p, addr, "word", pixel_to_u32(*w) as u64, raw as u64))
        })
    }

    /// The first difference in what the control port reports: `STATUS`, `FIRST_OVERFLOW`,
    /// `OVERFLOWS`, then the golden counters ([`Counter::is_golden`]). `actual.results` is not
    /// compared (the results are in memory: [`Expected::compare`]).
    pub fn compare_outcome(&self, actual: &FrameOutcome) -> Option<Mismatch> {
        let (w, a) = (&self.outcome, actual);
        let reg = |field, e: u32, g: u32| {
            (e != g).then_some(Mismatch {
                tile: None,
                tile_xy: [0, 0],
                place: Place::Register,
                addr: 0,
                field,
                expected: e as u64,
                actual: g as u64,
            })
        };
        reg("STATUS", w.status, a.status)
            .or_else(|| reg("FIRST_OVERFLOW", w.first_overflow, a.first_overflow))
            .or_else(|| reg("OVERFLOWS", w.overflows, a.overflows))
            .or_else(|| {
                w.counters.first_golden_mismatch(&a.counters).map(|(c, e, g)| Mismatch {
                    tile: None,
                    tile_xy: [0, 0],
                    place: Place::Counter(c),
                    addr: 0,
                    field: c.name(),
                    expected: e,
                    actual: g,
                })
            })
    }
}
