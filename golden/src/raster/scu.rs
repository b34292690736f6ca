//! The Subtile Compute Unit: front-to-back blending of one tile's Gaussian table in fixed point.
//!
//! # Per tile
//! The ITU computes each entry's subtile bitmap ([`super::itu::subtile_bitmap`]); the valid bit
//! of entry `i` is `bitmap != 0`. Each subtile then blends, in table order, only the entries
//! whose bit is set. The order matters per pixel only, so pixel lanes are free.
//!
//! # Per pixel `(px, py)` and entry (names as in [`crate::formats`]; `Fm = mean.frac`,
//! `s = M - top + exp` the conic scale, `P = power_frac`, `A = alpha_frac`, `Tf =
//! transmittance_frac`, `Fc = color.frac`, `Fo = opacity.frac`, `Fe = exp.out_frac`)
//! 1. `dx = mean_x - (px << Fm)`, `dy = mean_y - (py << Fm)` (exact).
//! 2. `q = a dx² + 2 b dx dy + c dy²` with the conic mantissas, **exact** (any exact evaluation
//!    order, e.g. incremental over the subtile, gives the same bits). Width: `2 W_d + M + 2` bits
//!    with `W_d = mean.bits + 1`.
//! 3. `np = shr_round(q, s + 2 Fm + 1 - P)`: `-power = q / 2` with `P` fraction bits, rounded
//!    half up (a shift of 127 or more gives 0). If `np < 0` (`power > 0`, only possible when the
//!    quantised conic is not positive definite) the entry is skipped. Else
//!    `np = min(np, 2^(power_int + P) - 1)` (saturation).
//! 4. `e = exp(np)` by [`super::exp::ExpTable::eval`] (`Fe` fraction bits).
//! 5. `alpha = min(shr_round(opacity * e, Fo + Fe - A), max_alpha_raw)` (a left shift when
//!    `Fo + Fe < A`). Skipped iff `alpha < min_alpha_raw = ceil(2^A / 255)`, i.e. exactly when
//!    the fixed-point alpha is below 1/255.
//! 6. `w = shr_round(alpha * T, A)` (`Tf` fraction bits), `test_T = T - w`. If
//!    `test_T < min_transmittance_raw = ceil(1e-4 2^Tf)` the pixel is done and this entry is
//!    not added (the reference's rule). Else `C += rgb * w` (exact, `Fc + Tf` fraction bits,
//!    `color.bits + Tf + 1` bits) and `T = test_T`. `T` starts at `2^Tf`.
//! 7. Output: `min(255, (C * 255 + 2^(K-1)) >> K)`, `K = Fc + Tf`: the 8-bit rule of
//!    [`crate::image::quantize_channel`] (round half up of `255 C`, clamp) applied exactly to
//!    the fixed-point `C`, over black.
//!
//! A subtile terminates when all its pixels inside the image are done. Pixels outside the image
//! are never blended: they start done and come out black.
//!
//! # How this model evaluates it (speed only; the bits are those of the steps above)
//! [`raster_tile`] walks entry by entry over a subtile's pixels (the hardware's order). Since
//! `alpha` is non-increasing in `np`, `alpha >= min_alpha` is exactly `q < q_cut` for a
//! per-entry integer `q_cut`; for a positive definite conic `q` is convex along a row, so those
//! pixels form one run around the row's minimum, which is found and walked with exact integer
//! increments (rows and pixels outside it are skipped; float is used only to *guess* where to
//! start, every decision is an exact integer comparison). `exp` comes from a table of
//! [`super::exp::ExpTable::eval`] over every `np`. [`shade_pixel`] is the plain per-pixel
//! evaluation of the steps; the tests check that both give the same pixels.

use super::exp::ExpTable;
/// The tile driver, re-exported at its former path (it lives in [`super::tile`]).
pub use super::tile::{raster_tile, raster_tile_into, TileRaster};
use super::RasterConfig;
use crate::formats::blend::BlendFormat;
use crate::formats::feature::{FeatureEntry, FeatureFormat};
use crate::formats::fixed::{shr_round, shr_round64};

/// Work of one subtile (what the cycle model needs).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct SubtileWork {
    /// Entries routed to the subtile (set bits in its column of the bitmaps).
    pub routed: u32,
    /// Entries the SCU processed before the subtile terminated (`routed` unless every pixel
    /// finished earlier; 0 when no pixel of the subtile is inside the image).
    pub processed: u32,
    /// Pixel-entry evaluations: for each processed entry, the pixels still active.
    pub pixel_evals: u32,
    /// Pixels (inside the image) whose transmittance reached the floor.
    pub finished_pixels: u32,
    /// The subtile stopped before its last routed entry (`processed < routed`).
    pub terminated: bool,
}

/// The conic-to-power shift at exponent field 0 (the smallest), `M - top + 2 mean.frac + 1 -
/// power_frac`; [`RasterConfig::check`] requires it to be at least 1.
pub fn min_power_shift(fmt: &FeatureFormat, blend: &BlendFormat) -> i32 {
    fmt.conic.scale(0) + 2 * fmt.mean.frac as i32 + 1 - blend.power_frac as i32
}

/// Integer constants of the datapath.
#[derive(Clone, Copy, Debug)]
pub(super) struct Consts {
    fm: u32,
    power_frac: u32,
    pub(super) max_np: i64,
    alpha_shift: i32,
    max_alpha: i64,
    min_alpha: i64,
    alpha_frac: u32,
    one_t: i64,
    min_t: i64,
    pub(super) out_shift: u32,
}

impl Consts {
    pub(super) fn new(fmt: &FeatureFormat, b: &BlendFormat) -> Self {
        Consts {
            fm: fmt.mean.frac as u32,
            power_frac: b.power_frac as u32,
            max_np: b.max_neg_power(),
            alpha_shift: fmt.opacity.frac as i32 + b.exp.out_frac as i32 - b.alpha_frac as i32,
            max_alpha: b.max_alpha_raw(),
            min_alpha: b.min_alpha_raw(),
            alpha_frac: b.alpha_frac as u32,
            one_t: b.one_transmittance(),
            min_t: b.min_transmittance_raw(),
            out_shift: fmt.color.frac as u32 + b.transmittance_frac as u32,
        }
    }
}

/// One entry's SCU operands.
#[derive(Clone, Copy, Debug)]
pub(super) struct Prep {
    m: [i64; 2],
    a: i64,
    b2: i64,
    c: i64,
    /// Conic-to-power shift `s + 2 Fm + 1 - P`.
    sh: u32,
    /// `|q|` may reach `2^60` over this tile: use `i128` (below, `q`, its row increments and
    /// the rounding shift all fit `i64`).
    wide: bool,
    o: i64,
    /// Largest `np` at which `alpha >= min_alpha` (-1: never). Only a shortcut: alpha is
    /// non-increasing in `np`, so `np > np_cut` is exactly `alpha < min_alpha`.
    np_cut: i64,
    /// `q < q_cut` is exactly `np <= np_cut` (for `np >= 0`): `(2 np_cut + 1) 2^(sh - 1)`, or
    /// `None` when that does not hold through saturation or huge shifts (no span culling).
    q_cut: Option<i128>,
    /// The quantised conic is positive definite: `q` is convex along every row.
    pd: bool,
    /// Span culling (only with `q_cut` and `pd`): rows with `|dy| >= row_reach` (raw mean
    /// units) have no pixel with `q < q_cut`; the real minimum of a row is at pixel column
    /// `x_at0 - x_slope * py`.
    row_reach: f64,
    x_at0: f64,
    x_slope: f64,
    /// Increments of `q` between neighbouring pixels of a row: `a h^2` and `2 a h`, `h = 2^Fm`.
    a_h2: i128,
    two_a_h: i128,
    rgb: [i64; 3],
}

impl Prep {
    /// Operands of `f` for pixels in `[x0, x1] x [y0, y1]` (decides `wide`).
    pub(super) fn new(
        f: &FeatureEntry,
        fmt: &FeatureFormat,
        b: &BlendFormat,
        np_cut: i64,
        rect: [i64; 4],
    ) -> Self {
        let fm = fmt.mean.frac as u32;
        let m = f.mean.map(|v| v as i64);
        let (a, b2, c) = (f.conic.a as i64, 2 * f.conic.b as i64, f.conic.c as i64);
        let sh = fmt.conic.scale(f.conic.exp) + 2 * fm as i32 + 1 - b.power_frac as i32;
        let [x0, y0, x1, y1] = rect;
        let dmax = |m: i64, lo: i64, hi: i64| {
            (m - (lo << fm)).unsigned_abs().max((m - (hi << fm)).unsigned_abs()) as u128
        };
        let (dx, dy) = (dmax(m[0], x0, x1), dmax(m[1], y0, y1));
        let bound = a as u128 * dx * dx + b2.unsigned_abs() as u128 * dx * dy + c as u128 * dy * dy;
        let sh = sh.max(0) as u32;
        let max_np = b.max_neg_power();
        let q_cut = ((1..100).contains(&sh) && np_cut < max_np).then(|| (2 * np_cut as i128 + 1) << (sh - 1));
        let pd = a > 0 && c > 0 && (a as i128) * (c as i128) * 4 > (b2 as i128) * (b2 as i128);
        let h = (fm as f64).exp2();
        // Row minimum dy^2 (4ac - b2^2) / 4a >= q_cut iff |dy| >= sqrt(4a q_cut / (4ac - b2^2));
        // widened by 1e-9 relative (f64 is accurate to ~1e-15 here) and one raw unit.
        let row_reach = match q_cut {
            Some(qc) if pd && qc <= 0 => -1.0,
            Some(qc) if pd => {
                let det4 = 4.0 * a as f64 * c as f64 - (b2 as f64) * (b2 as f64);
                (4.0 * a as f64 * qc as f64 / det4).sqrt() * (1.0 + 1e-9) + 1.0
            }
            _ => f64::INFINITY,
        };
        Prep {
            m,
            a,
            b2,
            c,
            sh,
            wide: bound >= 1 << 60,
            o: f.opacity as i64,
            np_cut,
            q_cut,
            pd,
            row_reach,
            x_at0: (m[0] as f64 + b2 as f64 * m[1] as f64 / (2.0 * a as f64)) / h,
            x_slope: b2 as f64 / (2.0 * a as f64),
            a_h2: (a as i128) << (2 * fm),
            two_a_h: (2 * a as i128) << fm,
            rgb: f.rgb.map(|v| v as i64),
        }
    }

    /// Steps 1-2: the exact quadratic form `q` at pixel `(px, py)`.
    #[inline(always)]
    fn q(&self, fm: u32, px: i64, py: i64) -> i128 {
        let dx = self.m[0] - (px << fm);
        let dy = self.m[1] - (py << fm);
        if self.wide {
            let (dx, dy) = (dx as i128, dy as i128);
            self.a as i128 * dx * dx + self.b2 as i128 * dx * dy + self.c as i128 * dy * dy
        } else {
            (self.a * dx * dx + self.b2 * dx * dy + self.c * dy * dy) as i128
        }
    }

    /// [`Prep::np_of`] for a non-wide entry (`|q| < 2^60`).
    #[inline(always)]
    fn np_of64(&self, k: &Consts, q: i64) -> i64 {
        if self.sh >= 63 {
            return 0;
        }
        // sh >= 1 (RasterConfig::check), so this is shr_round64 without its s == 0 case.
        ((q + (1i64 << (self.sh - 1))) >> self.sh).clamp(-1, k.max_np)
    }

    /// Step 3 from `q`: `np`, saturated, or -1 when `power > 0`.
    #[inline(always)]
    fn np_of(&self, k: &Consts, q: i128) -> i64 {
        if self.sh >= 127 {
            return 0;
        }
        shr_round(q, self.sh).clamp(-1, k.max_np as i128) as i64
    }

    /// Steps 1-3: `np` at pixel `(px, py)`, saturated, or -1 when `power > 0`.
    #[inline(always)]
    fn neg_power(&self, k: &Consts, px: i64, py: i64) -> i64 {
        let dx = self.m[0] - (px << k.fm);
        let dy = self.m[1] - (py << k.fm);
        if self.wide {
            if self.sh >= 127 {
                return 0;
            }
            let (dx, dy) = (dx as i128, dy as i128);
            let q = self.a as i128 * dx * dx + self.b2 as i128 * dx * dy + self.c as i128 * dy * dy;
            shr_round(q, self.sh).clamp(-1, k.max_np as i128) as i64
        } else {
            // |q| < 2^60 here, so a shift of 63 or more rounds to 0.
            if self.sh >= 63 {
                return 0;
            }
            let q = self.a * dx * dx + self.b2 * dx * dy + self.c * dy * dy;
            shr_round64(q, self.sh).clamp(-1, k.max_np)
        }
    }

    /// Steps 1-5: the capped alpha at pixel `(px, py)`, or `None` when `power > 0`.
    #[inline(always)]
    fn alpha(&self, k: &Consts, exp: &ExpTable, px: i64, py: i64) -> Option<i64> {
        let np = self.neg_power(k, px, py);
        if np < 0 {
            return None;
        }
        Some(alpha_of(self.o, exp.eval(np), k))
    }
}

/// Step 5: the capped alpha of opacity `o` where the exp unit gives `e`.
#[inline(always)]
fn alpha_of(o: i64, e: i64, k: &Consts) -> i64 {
    let prod = o * e;
    let alpha =
        if k.alpha_shift >= 0 { shr_round64(prod, k.alpha_shift as u32) } else { prod << -k.alpha_shift };
    alpha.min(k.max_alpha)
}

/// The largest `np` in `[0, max_np]` with `alpha_of(o, np) >= min_alpha`, or -1. Exact: an f64
/// estimate is corrected by stepping with the integer function, which is non-increasing in `np`.
fn np_cut(o: i64, fmt: &FeatureFormat, k: &Consts, exp: &ExpTable) -> i64 {
    let ok = |np: i64| alpha_of(o, exp.eval(np), k) >= k.min_alpha;
    if !ok(0) {
        return -1;
    }
    let ov = fmt.opacity.dequantize(o);
    let min = k.min_alpha as f64 / (k.alpha_frac as f64).exp2();
    let scale = (k.power_frac as f64).exp2();
    let est = ((ov / min).ln() * scale).floor();
    let mut np = if est.is_finite() { (est as i64).clamp(0, k.max_np) } else { 0 };
    while np < k.max_np && ok(np + 1) {
        np += 1;
    }
    while np > 0 && !ok(np) {
        np -= 1;
    }
    np
}

/// A direct-mapped cache of [`np_cut`] by opacity (only saves time).
pub(super) struct NpCutCache {
    slots: [(i64, i64); 256],
}

impl NpCutCache {
    pub(super) fn new() -> Self {
        NpCutCache { slots: [(-1, 0); 256] }
    }

    pub(super) fn get(&mut self, o: i64, fmt: &FeatureFormat, k: &Consts, exp: &ExpTable) -> i64 {
        let slot = &mut self.slots[(o & 255) as usize];
        if slot.0 != o {
            *slot = (o, np_cut(o, fmt, k, exp));
        }
        slot.1
    }
}

/// The state of one pixel.
#[derive(Clone, Copy, Debug)]
struct PixelState {
    t: i64,
    c: [i64; 3],
}

/// Blends `list` (the routed entries' operands, in table order) at `(px, py)`. Returns the
/// colour accumulator, the final transmittance and the list position where the pixel finished.
#[inline]
fn blend(list: &[Prep], k: &Consts, exp: &ExpTable, px: i64, py: i64) -> (PixelState, Option<usize>) {
    let mut st = PixelState { t: k.one_t, c: [0; 3] };
    for (pos, p) in list.iter().enumerate() {
        let np = p.neg_power(k, px, py);
        // np > np_cut is exactly alpha < min_alpha (see `np_cut`).
        if np < 0 || np > p.np_cut {
            continue;
        }
        let alpha = alpha_of(p.o, exp.eval(np), k);
        let w = shr_round64(alpha * st.t, k.alpha_frac);
        let test_t = st.t - w;
        if test_t < k.min_t {
            return (st, Some(pos));
        }
        for (c, rgb) in st.c.iter_mut().zip(p.rgb) {
            *c += rgb * w;
        }
        st.t = test_t;
    }
    (st, None)
}

/// Step 7: one 8-bit channel from the accumulator.
#[inline]
pub(super) fn to_u8(c: i64, out_shift: u32) -> u8 {
    (((c * 255) + (1i64 << (out_shift - 1))) >> out_shift).clamp(0, 255) as u8
}

/// Result of [`shade_pixel`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PixelShade {
    /// The 8-bit colour.
    pub color: [u8; 3],
    /// Colour accumulators (`color.frac + transmittance_frac` fraction bits).
    pub accum: [i64; 3],
    /// Final transmittance, raw.
    pub transmittance: i64,
    /// Index of the entry at which the pixel finished (that entry was not added).
    pub finished_at: Option<usize>,
}

/// Blends every entry of `entries` (no ITU filtering) at pixel `(px, py)` with the SCU
/// arithmetic. Inside a tile, [`raster_tile`] gives the same pixel whenever the ITU routes
/// every entry that can reach `alpha >= 1/255` at the pixel.
pub fn shade_pixel(
    entries: &[FeatureEntry],
    fmt: &FeatureFormat,
    cfg: &RasterConfig,
    px: i64,
    py: i64,
) -> PixelShade {
    let k = Consts::new(fmt, &cfg.blend);
    let exp = ExpTable::new(&cfg.blend.exp, cfg.blend.power_frac);
    let preps: Vec<Prep> = entries
        .iter()
        .map(|f| Prep::new(f, fmt, &cfg.blend, np_cut(f.opacity as i64, fmt, &k, &exp), [px, py, px, py]))
        .collect();
    let (st, fin) = blend(&preps, &k, &exp, px, py);
    PixelShade {
        color: st.c.map(|c| to_u8(c, k.out_shift)),
        accum: st.c,
        transmittance: st.t,
        finished_at: fin,
    }
}

/// Steps 1-5 for one entry at pixel `(px, py)`: the capped alpha (raw, `alpha_frac` bits), or
/// `None` when `power > 0`. The entry is blended iff the result is at least
/// [`BlendFormat::min_alpha_raw`].
pub fn pixel_alpha(
    f: &FeatureEntry,
    fmt: &FeatureFormat,
    cfg: &RasterConfig,
    exp: &ExpTable,
    px: i64,
    py: i64,
) -> Option<i64> {
    let k = Consts::new(fmt, &cfg.blend);
    Prep::new(f, fmt, &cfg.blend, 0, [px, py, px, py]).alpha(&k, exp, px, py)
}

/// `ceil(v)` as an integer without libm (NaN gives `i64::MIN / 2`, beyond +-1e15 clamps).
fn ceil_i64(v: f64) -> i64 {
    if v.is_nan() {
        return i64::MIN / 2;
    }
    let v = v.clamp(-1e15, 1e15);
    let t = v as i64;
    t + ((t as f64) < v) as i64
}

/// `floor(v)` as an integer without libm (NaN gives `i64::MAX / 2`, beyond +-1e15 clamps).
fn floor_i64(v: f64) -> i64 {
    if v.is_nan() {
        return i64::MAX / 2;
    }
    let v = v.clamp(-1e15, 1e15);
    let t = v as i64;
    t - ((t as f64) > v) as i64
}

/// The pixels of one subtile while the SCU blends it (row-major, `side * side`).
#[derive(Debug, Default)]
pub(super) struct SubtileState {
    /// Per pixel: `[T, C_r, C_g, C_b, active]` (active: inside the image and not finished).
    pub(super) px: Vec<[i64; 5]>,
    /// Active pixels per row.
    row_active: Vec<u32>,
}

impl SubtileState {
    /// Blends `list` (the routed entries in table order) into the subtile whose top-left pixel
    /// is `origin`, entry by entry over the subtile's pixels (the hardware's order; per pixel it
    /// is the same sequence as [`blend`]). Only the pixels of a row where `q < q_cut` can blend:
    /// for a positive definite conic they form one run around the row's minimum, found with
    /// exact evaluations, so the others are skipped without changing any result. Without
    /// `COLOR` only the transmittance is blended: the same work counters, no colour.
    pub(super) fn run<const COLOR: bool>(
        &mut self,
        list: &[Prep],
        k: &Consts,
        lut: &[i32],
        origin: [i64; 2],
        side: i64,
        size: [i64; 2],
    ) -> SubtileWork {
        self.px.clear();
        self.row_active.clear();
        let mut remaining = 0u32;
        for ly in 0..side {
            let mut count = 0;
            for lx in 0..side {
                let inside = origin[0] + lx < size[0] && origin[1] + ly < size[1];
                self.px.push([k.one_t, 0, 0, 0, inside as i64]);
                count += inside as u32;
            }
            self.row_active.push(count);
            remaining += count;
        }
        let mut work = SubtileWork { routed: list.len() as u32, ..SubtileWork::default() };
        if remaining == 0 {
            work.terminated = work.routed > 0;
            return work;
        }
        let (xs, xe) = (origin[0], origin[0] + side - 1);
        let h = (k.fm as f64).exp2();
        for (pos, g) in list.iter().enumerate() {
            work.pixel_evals += remaining;
            let span = g.pd && g.q_cut.is_some();
            // Rows that can hold a blending pixel (all rows without span culling).
            let (ly0, ly1) = if span {
                let lo = ceil_i64((g.m[1] as f64 - g.row_reach) / h);
                let hi = floor_i64((g.m[1] as f64 + g.row_reach) / h);
                ((lo - origin[1]).max(0), (hi - origin[1]).min(side - 1))
            } else {
                (0, side - 1)
            };
            let shift = k.fm;
            for ly in ly0..=ly1 {
                if self.row_active[ly as usize] == 0 {
                    continue;
                }
                let py = origin[1] + ly;
                if !span {
                    for x in xs..=xe {
                        let np = g.np_of(k, g.q(k.fm, x, py));
                        self.blend_at::<COLOR>(g, k, lut, x - xs, ly, side, np, &mut remaining, &mut work);
                    }
                    continue;
                }
                // Seed: the row's integer minimum is within one pixel of the truncated real
                // minimum (clamped to the subtile); the pixels with q < q_cut are one run
                // around it, walked with exact increments (in i64 unless the entry is wide).
                let xm = g.x_at0 - g.x_slope * py as f64;
                let c0 = if xm.is_finite() { (xm.clamp(-1e15, 1e15) as i64).clamp(xs, xe) } else { xs };
                macro_rules! run {
                    ($t:ty, $np:ident) => {{
                        let (q_cut, a_h2, two_a_h) = (
                            g.q_cut.unwrap_or(0).clamp(<$t>::MIN as i128, <$t>::MAX as i128) as $t,
                            g.a_h2 as $t,
                            g.two_a_h as $t,
                        );
                        let dx = (g.m[0] - (c0 << shift)) as $t;
                        let dy = (g.m[1] - (py << shift)) as $t;
                        let (a, b2, c) = (g.a as $t, g.b2 as $t, g.c as $t);
                        let q0 = a * dx * dx + b2 * dx * dy + c * dy * dy;
                        let l0 = 2 * a * dx + b2 * dy;
                        let seed = if q0 < q_cut {
                            Some((c0, q0, l0))
                        } else if c0 > xs && q0 + (l0 << shift) + a_h2 < q_cut {
                            Some((c0 - 1, q0 + (l0 << shift) + a_h2, l0 + two_a_h))
                        } else if c0 < xe && q0 - (l0 << shift) + a_h2 < q_cut {
                            Some((c0 + 1, q0 - (l0 << shift) + a_h2, l0 - two_a_h))
                        } else {
                            None
                        };
                        if let Some((x, q, l)) = seed {
                            self.blend_at::<COLOR>(
                                g,
                                k,
                                lut,
                                x - xs,
                                ly,
                                side,
                                g.$np(k, q),
                                &mut remaining,
                                &mut work,
                            );
                            let (mut xl, mut ql, mut ll) = (x, q, l);
                            while xl > xs {
                                ql += (ll << shift) + a_h2;
                                ll += two_a_h;
                                xl -= 1;
                                if ql >= q_cut {
                                    break;
                                }
                                let np = g.$np(k, ql);
                                self.blend_at::<COLOR>(
                                    g,
                                    k,
                                    lut,
                                    xl - xs,
                                    ly,
                                    side,
                                    np,
                                    &mut remaining,
                                    &mut work,
                                );
                            }
                            let (mut xr, mut qr, mut lr) = (x, q, l);
                            while xr < xe {
                                qr += a_h2 - (lr << shift);
                                lr -= two_a_h;
                                xr += 1;
                                if qr >= q_cut {
                                    break;
                                }
                                let np = g.$np(k, qr);
                                self.blend_at::<COLOR>(
                                    g,
                                    k,
                                    lut,
                                    xr - xs,
                                    ly,
                                    side,
                                    np,
                                    &mut remaining,
                                    &mut work,
                                );
                            }
                        }
                    }};
                }
                if g.wide {
                    run!(i128, np_of);
                } else {
                    run!(i64, np_of64);
                }
            }
            if remaining == 0 {
                work.processed = pos as u32 + 1;
                work.terminated = work.processed < work.routed;
                return work;
            }
        }
        work.processed = work.routed;
        work
    }

    /// Steps 4-6 for entry `g` at pixel `(lx, ly)` of the subtile, given its `np` (step 6's
    /// colour only with `COLOR`).
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn blend_at<const COLOR: bool>(
        &mut self,
        g: &Prep,
        k: &Consts,
        lut: &[i32],
        lx: i64,
        ly: i64,
        side: i64,
        np: i64,
        remaining: &mut u32,
        work: &mut SubtileWork,
    ) {
        let p = &mut self.px[(ly * side + lx) as usize];
        if p[4] == 0 || np < 0 || np > g.np_cut {
            return;
        }
        let alpha = alpha_of(g.o, lut[np as usize] as i64, k);
        // alpha_frac >= 8: shr_round64 without its s == 0 case.
        let w = (alpha * p[0] + (1i64 << (k.alpha_frac - 1))) >> k.alpha_frac;
        let test_t = p[0] - w;
        if test_t < k.min_t {
            p[4] = 0;
            self.row_active[ly as usize] -= 1;
            *remaining -= 1;
            work.finished_pixels += 1;
            return;
        }
        p[0] = test_t;
        if COLOR {
            p[1] += g.rgb[0] * w;
            p[2] += g.rgb[1] * w;
            p[3] += g.rgb[2] * w;
        }
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::formats::feature::quantize;
    use crate::raster::synth::projected_from_cov;
    use crate::render::Projected;
    use crate::sort::DepthKeyCodec;

    /// A Gaussian with covariance `cov` at `mean`.
    pub(crate) fn projected(mean: [f32; 2], cov: [f32; 3], opacity: f32, rgb: [f32; 3]) -> Projected {
        projected_from_cov(0, mean, cov, opacity, rgb, 1.0)
    }

    fn entry(mean: [f32; 2], cov: [f32; 3], opacity: f32, rgb: [f32; 3]) -> FeatureEntry {
        quantize(&projected(mean, cov, opacity, rgb), &FeatureFormat::default(), &DepthKeyCodec::Fp16)
    }

    #[test]
    fn single_gaussian_matches_float_at_its_centre() {
        let fmt = FeatureFormat::default();
        let cfg = RasterConfig::default();
        cfg.check(&fmt).unwrap();
        let e = entry([10.0, 20.0], [4.0, 1.0, 3.0], 0.6, [1.0, 0.5, 0.25]);
        let r = raster_tile(&[e], &fmt, 0, 0, 64, 64, &cfg);
        // At the centre alpha = 0.6 (quantised to 154/256 = 0.6016); colours are exact.
        let expect = [1.0, 0.5, 0.25].map(|c: f64| (c * (154.0 / 256.0) * 255.0 + 0.5).floor() as u8);
        assert_eq!(r.pixels[20 * 64 + 10], expect);
        assert_eq!(r.valid, vec![true]);
        assert_eq!(shade_pixel(&[e], &fmt, &cfg, 10, 20).color, expect);
        // The subtile of the centre saw one entry.
        assert_eq!(r.work[2 * 8 + 1].routed, 1);
        assert_eq!(r.work[2 * 8 + 1].processed, 1);
        assert_eq!(r.work[0].routed, 0);
    }

    #[test]
    fn min_power_shift_of_the_default_is_positive() {
        let s = min_power_shift(&FeatureFormat::default(), &BlendFormat::default());
        assert_eq!(s, 18 - 2 + 16 + 1 - 10);
    }
}
