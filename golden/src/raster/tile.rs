//! The raster tile driver: one tile of an image from the tile's table, as the raster core runs
//! it. The ITU computes every entry's subtile bitmap ([`super::itu`]); entries are routed to
//! their subtiles in table order and each subtile is blended by the SCU ([`super::scu`]).

use super::exp::ExpTable;
use super::itu::{bitmap_of, ItuGeom};
use super::scu::{to_u8, Consts, NpCutCache, Prep, SubtileState, SubtileWork};
use super::RasterConfig;
use crate::formats::blend::ExpFormat;
use crate::formats::feature::{FeatureEntry, FeatureFormat};

/// The output of [`raster_tile`].
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct TileRaster {
    /// `tile * tile` pixels, row-major; pixels outside the image are black.
    pub pixels: Vec<[u8; 3]>,
    /// Per table entry: the cumulative OR of its subtile bits (false = outgoing).
    pub valid: Vec<bool>,
    /// Per table entry: its subtile bitmap (bit `sy * n + sx`).
    pub bitmaps: Vec<u64>,
    /// Per subtile (row-major, `n * n`): work counters.
    pub work: Vec<SubtileWork>,
}

/// Rasterises tile `(tile_x, tile_y)` of a `width x height` image from the tile's table
/// (`entries`, in table order). `cfg` must pass [`RasterConfig::check`] for `fmt`.
pub fn raster_tile(
    entries: &[FeatureEntry],
    fmt: &FeatureFormat,
    tile_x: u32,
    tile_y: u32,
    width: u32,
    height: u32,
    cfg: &RasterConfig,
) -> TileRaster {
    let mut out = TileRaster::default();
    raster_tile_into(entries, fmt, tile_x, tile_y, width, height, cfg, &mut out);
    out
}

/// [`raster_tile`] into `out`, reusing its buffers.
#[allow(clippy::too_many_arguments)]
pub fn raster_tile_into(
    entries: &[FeatureEntry],
    fmt: &FeatureFormat,
    tile_x: u32,
    tile_y: u32,
    width: u32,
    height: u32,
    cfg: &RasterConfig,
    out: &mut TileRaster,
) {
    let t = cfg.tile as usize;
    out.bitmaps.clear();
    out.bitmaps.extend(entries.iter().map(|f| bitmap_of(&ItuGeom::new(f, fmt), tile_x, tile_y, cfg)));
    out.valid.clear();
    out.valid.extend(out.bitmaps.iter().map(|&b| b != 0));
    out.pixels.clear();
    out.pixels.resize(t * t, [0; 3]);
    let tile = TileAt { tile_x, tile_y, width, height };
    blend_tile::<true>(entries, &out.bitmaps, fmt, tile, cfg, &mut out.work, &mut out.pixels);
}

/// The SCUs' work counters of [`raster_tile`] (its `work`), without its pixels: the same
/// routing and the same transmittance per pixel, so the same early termination, with no colour
/// accumulated. `bitmaps` are the entries' subtile bitmaps in the tile ([`super::subtile_bitmap`],
/// as the binning computed them; 0 for an entry that does not touch the tile).
pub fn tile_work_into(
    entries: &[FeatureEntry],
    bitmaps: &[u64],
    fmt: &FeatureFormat,
    at: TileAt,
    cfg: &RasterConfig,
    work: &mut Vec<SubtileWork>,
) {
    blend_tile::<false>(entries, bitmaps, fmt, at, cfg, work, &mut Vec::new());
}

/// A tile of an image: its position in the tile grid and the image's size in pixels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TileAt {
    /// Tile column.
    pub tile_x: u32,
    /// Tile row.
    pub tile_y: u32,
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
}

/// Routes `entries` (with their subtile `bitmaps`) to the tile's subtiles and blends each with
/// the SCU, into `work` (per subtile) and, with `COLOR`, `pixels` (`tile * tile`, zeroed).
fn blend_tile<const COLOR: bool>(
    entries: &[FeatureEntry],
    bitmaps: &[u64],
    fmt: &FeatureFormat,
    at: TileAt,
    cfg: &RasterConfig,
    work: &mut Vec<SubtileWork>,
    pixels: &mut [[u8; 3]],
) {
    let TileAt { tile_x, tile_y, width, height } = at;
    let t = cfg.tile as i64;
    let s = cfg.subtile as i64;
    let n = cfg.subtiles_per_side() as i64;
    let (x0, y0) = (tile_x as i64 * t, tile_y as i64 * t);
    let k = Consts::new(fmt, &cfg.blend);
    let exp = ExpTable::new(&cfg.blend.exp, cfg.blend.power_frac);
    work.clear();
    work.resize((n * n) as usize, SubtileWork::default());

    // Route entries to subtiles (a counting sort by subtile that keeps table order), and
    // prepare the operands of every routed entry once per tile.
    let nsub = (n * n) as usize;
    let mut offsets = [0u32; 65];
    for &b in bitmaps {
        let mut m = b;
        while m != 0 {
            offsets[m.trailing_zeros() as usize + 1] += 1;
            m &= m - 1;
        }
    }
    for j in 0..nsub {
        offsets[j + 1] += offsets[j];
    }
    let mut cursor = offsets;
    let mut routed = vec![0u32; offsets[nsub] as usize];
    let rect = [x0, y0, x0 + t - 1, y0 + t - 1];
    let mut cuts = NpCutCache::new();
    let mut preps: Vec<Prep> = Vec::with_capacity(entries.len());
    for (f, &b) in entries.iter().zip(bitmaps) {
        let i = preps.len() as u32;
        if b == 0 {
            continue;
        }
        preps.push(Prep::new(f, fmt, &cfg.blend, cuts.get(f.opacity as i64, fmt, &k, &exp), rect));
        let mut m = b;
        while m != 0 {
            let j = m.trailing_zeros() as usize;
            routed[cursor[j] as usize] = i;
            cursor[j] += 1;
            m &= m - 1;
        }
    }
    let lut = exp_lut(&exp, k.max_np);
    let mut list: Vec<Prep> = Vec::with_capacity(preps.len());
    let mut st = SubtileState::default();
    for sy in 0..n {
        for sx in 0..n {
            let j = (sy * n + sx) as usize;
            list.clear();
            list.extend(
                routed[offsets[j] as usize..offsets[j + 1] as usize].iter().map(|&i| preps[i as usize]),
            );
            let origin = [x0 + sx * s, y0 + sy * s];
            work[j] = st.run::<COLOR>(&list, &k, &lut, origin, s, [width as i64, height as i64]);
            if !COLOR {
                continue;
            }
            for ly in 0..s {
                for lx in 0..s {
                    let p = st.px[(ly * s + lx) as usize];
                    let c = [p[1], p[2], p[3]];
                    pixels[((sy * s + ly) * t + sx * s + lx) as usize] = c.map(|c| to_u8(c, k.out_shift));
                }
            }
        }
    }
}

/// A cached exp table: the unit's format, its input shift, and `exp(np)` for every `np`.
type CachedLut = (ExpFormat, u32, std::rc::Rc<Vec<i32>>);

thread_local! {
    /// The last exp lookup table built on this thread (only saves time).
    static EXP_LUT: std::cell::RefCell<Option<CachedLut>> =
        const { std::cell::RefCell::new(None) };
}

/// `exp.eval(np)` for every `np` in `[0, max_np]`, as a table (the same function, evaluated
/// ahead; only saves time). Cached per thread.
fn exp_lut(exp: &ExpTable, max_np: i64) -> std::rc::Rc<Vec<i32>> {
    let key = (*exp.format(), exp.input_shift());
    EXP_LUT.with(|cell| {
        let mut cell = cell.borrow_mut();
        if let Some((f, sh, lut)) = cell.as_ref() {
            if (*f, *sh) == key && lut.len() == max_np as usize + 1 {
                return lut.clone();
            }
        }
        // Values are at most 2^out_frac <= 2^24.
        let lut = std::rc::Rc::new((0..=max_np).map(|np| exp.eval(np) as i32).collect::<Vec<i32>>());
        *cell = Some((key.0, key.1, lut.clone()));
        lut
    })
}
