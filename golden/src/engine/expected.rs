//! What a frame must leave in memory and in the registers ([`Expected`], built by the host
//! session from the golden pipeline), and the checker that names the first difference
//! ([`Expected::compare`], [`Expected::compare_outcome`], [`Mismatch`]).

use super::memory::{entry_to_u64, pixel_to_u32, Memory, TileDescriptor, ENTRY_BYTES, PIXEL_BYTES};
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

    /// The first memory difference: per tile in index order its result, its next table
    /// (valid, key, id, then the whole word), the regions it must not touch, then its pixels
    /// (red, green, blue, then the whole word).
    pub fn compare(&self, mem: &Memory) -> Option<Mismatch> {
        (0..self.descriptors.len() as u64).find_map(|t| {
            self.compare_result(mem, t)
                .or_else(|| self.compare_table(mem, t))
                .or_else(|| self.compare_untouched(mem, t))
                .or_else(|| self.compare_pixels(mem, t))
        })
    }

    fn compare_result(&self, mem: &Memory, t: u64) -> Option<Mismatch> {
        let want = self.outcome.results[t as usize];
        let addr = self.regs.result_base + 8 * t;
        let got = mem.read_result(self.regs.result_base, t);
        let raw = mem.read_u64(addr);
        self.at(t, Place::Result, addr, "next_len", want.next_len as u64, got.next_len as u64)
            .or_else(|| {
                self.at(t, Place::Result, addr, "overflow", want.overflow as u64, got.overflow as u64)
            })
            .or_else(|| self.at(t, Place::Result, addr, "word", want.to_word(), raw))
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
