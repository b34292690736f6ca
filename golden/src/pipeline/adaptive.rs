//! Disorder signals the hardware counts for free, and the `adaptive` and `motion` strategies
//! built on them (issue 14).
//!
//! # Signals (per tile and frame, no extra memory traffic)
//! - **Write-back disorder** ([`WritebackSignals`]): the raster writes the current depth keys
//!   back in table order, so comparators on that stream see the table's order against the
//!   *current* keys: `descents` (valid entries that precede the previous valid entry), `behind`
//!   (valid entries that precede the running maximum) and `reach` (the largest distance, in
//!   valid entries, from the running maximum's position to a later entry that precedes it: a
//!   lower bound on how far that maximum must move, since every entry in between is at most
//!   it). The table rastered in frame `f` is the table DPS sorts in frame `f + 1`, so these are
//!   the disorder the next sort faces, known to the frame controller before it sorts.
//! - **Merge disorder** ([`crate::sort::MergeStats::a_inversions`]): boundary inversions of
//!   the reused stream seen by the MSU+ (what the DPS passes left unsorted, on the stale keys).
//! - **Set churn**: incoming and outgoing shares ([`super::tile::TileCounts`]).
//! - **Camera motion** ([`CameraMotion`]): rotation and translation since the last frame.
//!
//! # `adaptive[:params]`
//! Per tile and frame the frame controller chooses a [`TilePlan`] from the tile's previous
//! write-back signals (and the previous frame's merge inversions), within a traffic budget for
//! the frame. All decisions are integer functions of integer counters:
//!
//! 1. **Request** ([`request`]): with `R` the tile's write-back reach and `C` the chunk, a tile
//!    with `R < C` asks for Neo's single pass. Beyond, it asks for `p = 1 + R / U` passes
//!    (integer division) with `U = wide * C` on the wide chunk when the core has one
//!    (`wide > 1`), else `U = C` on the normal chunk; plus one when the previous frame's merge
//!    still saw inversions (`M > 0`) and `p > 1`; at most `max`. A full re-sort of the tile's
//!    list costs `2 L (1 + ceil(log2(ceil(L / C))))` entries of traffic (chunk phase plus global
//!    merge passes) against `2 L p` for `p` passes of either chunk; the tile asks for a re-sort
//!    instead when `p > 1` and the re-sort is no dearer (`resort=1`), or when `p` exceeded `max`.
//! 2. **Budget** ([`allocate`]): the frame may spend `budget` percent of `2 sum(L)` (one pass
//!    per tile, Neo's traffic) on top of one pass per tile. Each plan has a level
//!    `ceil(cost / 2L)` (passes, or the re-sort's pass equivalent). The controller takes the
//!    largest cap `c` such that granting every tile `min(request, c)` (a re-sort above the cap
//!    becomes `c` passes) fits the budget, then raises tiles above the cap by one level in
//!    tile order while the rest of the budget lasts. One pass over the tiles builds a
//!    histogram of extra cost per level, a second picks `c`: a frame controller does this from
//!    per-tile counters in its result records (a few adders per level), with no sort of the
//!    tiles.
//! 3. **Still camera** (in the frame driver): a frame whose camera pose equals the previous
//!    frame's (rotation and translation both zero; the host knows it) adds no disorder, and
//!    every tile gets Neo's single pass: the cost falls back to Neo's at once when the camera
//!    stops. (Disorder left from fast motion converges slowly, `O(L / C)` passes, and is not
//!    chased then.)
//!
//! Parameters (`adaptive:budget=50,max=4,resort=1,wide=16`, any subset): `budget` percent
//! (0..=1000, default 50), `max` passes per tile (1..=16, default 4), `resort` (0 or 1,
//! default 1) allows full re-sorts, `wide` the wide chunk as a multiple of `C` (a power of
//! two up to 64, default 16; 1: none). A wide pass costs the same DRAM traffic as a normal one (each
//! entry read and written once) but needs a chunk buffer of `wide * C` entries in the sorting
//! core (4096 entries, 24 KiB at 6-byte entries, for the default) and `log2(wide)` more
//! in-chunk merge passes on chip; the cycle model times it with that chunk.
//!
//! The frame controller's part: before a frame it holds, per tile, the previous result
//! record's counters (`len`, `reach`, merge inversions, current length); it computes each
//! request with a divider-free comparison chain (`R / U` by shifts: `C` and `wide` are powers
//! of two), accumulates the per-level extra costs, picks the cap, and writes each tile's plan
//! (passes, wide flag, re-sort flag) into the tile's job descriptor.
//!
//! # `motion:DEG`
//! The web viewers' rule: a full sort of every tile whenever the view direction has turned more
//! than `DEG` degrees since the last full sort; in between the last order is reused as by
//! `periodic` (valid bits and MSU+ insertion of newly visible Gaussians, frozen keys, no DPS).

use std::fmt;

use glam::DVec3;
use serde::Serialize;

use crate::camera::Camera;
use crate::sort::SortEntry;

/// Disorder of a table against the keys written back into it (see the module docs).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct WritebackSignals {
    /// Valid entries in the table.
    pub len: u32,
    /// Valid entries preceding the previous valid entry.
    pub descents: u32,
    /// Valid entries preceding the running maximum.
    pub behind: u32,
    /// Largest distance from the running maximum to a later valid entry preceding it.
    pub reach: u32,
}

/// The write-back signals of `table` (its valid entries in table order, with the keys written
/// back): one comparator with the previous entry, one with a running maximum and its position.
pub fn writeback_signals(table: &[SortEntry]) -> WritebackSignals {
    let mut s = WritebackSignals::default();
    let mut prev: Option<SortEntry> = None;
    let mut max: Option<(SortEntry, u32)> = None;
    for e in table.iter().filter(|e| e.valid) {
        let i = s.len;
        s.len += 1;
        if prev.is_some_and(|p| e.precedes(&p)) {
            s.descents += 1;
        }
        prev = Some(*e);
        match max {
            Some((m, at)) if e.precedes(&m) => {
                s.behind += 1;
                s.reach = s.reach.max(i - at);
            }
            _ => max = Some((*e, i)),
        }
    }
    s
}

/// What the sorting step does with one tile this frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize)]
pub enum TilePlan {
    /// The strategy's own step.
    #[default]
    Default,
    /// Reuse-and-update with this many DPS passes (alternating parity).
    Passes(u32),
    /// The same with the wide chunk (`wide` times the chunk).
    Wide(u32),
    /// Conventional sort of the tile's current list from scratch.
    Resort,
}

impl TilePlan {
    /// Pass count of the plan (0 for a re-sort, `default` for [`TilePlan::Default`]).
    pub fn passes_or(self, default: usize) -> usize {
        match self {
            TilePlan::Default => default,
            TilePlan::Passes(p) | TilePlan::Wide(p) => p as usize,
            TilePlan::Resort => 0,
        }
    }

    /// Whether the plan's DPS uses the wide chunk.
    pub fn is_wide(self) -> bool {
        matches!(self, TilePlan::Wide(_))
    }
}

/// Parameters of `adaptive` (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct AdaptiveParams {
    /// Extra sorting traffic allowed per frame, in percent of one pass over every table.
    pub budget: u32,
    /// Most DPS passes per tile.
    pub max_passes: u32,
    /// Whether a tile may be re-sorted from scratch.
    pub resort: bool,
    /// The wide chunk as a multiple of the chunk (a power of two, 1 for none).
    pub wide: u32,
}

impl Default for AdaptiveParams {
    fn default() -> Self {
        AdaptiveParams { budget: 50, max_passes: 4, resort: true, wide: 16 }
    }
}

impl fmt::Display for AdaptiveParams {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "budget={},max={},resort={},wide={}",
            self.budget, self.max_passes, self.resort as u8, self.wide
        )
    }
}

impl AdaptiveParams {
    /// Parses `key=value` pairs separated by commas (any subset, defaults for the rest).
    pub fn parse(s: &str) -> Result<Self, String> {
        let mut p = AdaptiveParams::default();
        let mut seen: Vec<&str> = Vec::new();
        for kv in s.split(',').map(str::trim).filter(|kv| !kv.is_empty()) {
            let (k, v) = kv.split_once('=').ok_or_else(|| {
                format!("adaptive: '{kv}' is not key=value (budget=, max=, resort=, wide=)")
            })?;
            let (k, v) = (k.trim(), v.trim());
            if seen.contains(&k) {
                return Err(format!("adaptive: parameter '{k}' is given twice"));
            }
            seen.push(k);
            let num = |lo: u32, hi: u32| -> Result<u32, String> {
                match v.parse::<u32>() {
                    Ok(n) if (lo..=hi).contains(&n) => Ok(n),
                    _ => Err(format!("adaptive: parameter '{k}' needs an integer in {lo}..={hi}, got '{v}'")),
                }
            };
            match k {
                "budget" => p.budget = num(0, 1000)?,
                "max" => p.max_passes = num(1, super::config::MAX_PASSES as u32)?,
                "resort" => p.resort = num(0, 1)? == 1,
                "wide" => {
                    p.wide = num(1, 64)?;
                    if !p.wide.is_power_of_two() {
                        return Err(format!(
                            "adaptive: parameter 'wide' needs a power of two in 1..=64, got '{v}'"
                        ));
                    }
                }
                _ => {
                    return Err(format!(
                        "adaptive: unknown parameter '{k}' (expected budget, max, resort or wide)"
                    ))
                }
            }
        }
        Ok(p)
    }
}

/// Traffic (entries read + written) of a conventional sort of `len` entries with chunk `chunk`:
/// the chunk phase and `ceil(log2(chunks))` global merge passes, each reading and writing all.
pub fn resort_cost(len: u64, chunk: u64) -> u64 {
    let chunks = len.div_ceil(chunk.max(1)).max(1);
    let passes = 64 - (chunks - 1).leading_zeros() as u64;
    2 * len * (1 + passes)
}

/// A tile's request: its desired plan and that plan's level (pass equivalents).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Request {
    /// Passes asked for (at least 1, at most the parameter `max`).
    pub passes: u32,
    /// Whether they use the wide chunk.
    pub wide: bool,
    /// Whether the tile asks for a re-sort instead.
    pub resort: bool,
    /// Entries of one pass over the tile (`2 L`, at least 1 so levels are defined).
    pub pass_cost: u64,
    /// The re-sort's traffic.
    pub resort_cost: u64,
}

impl Request {
    /// Level of the re-sort: `ceil(resort_cost / pass_cost)`.
    pub fn resort_level(&self) -> u32 {
        self.resort_cost.div_ceil(self.pass_cost).min(u32::MAX as u64) as u32
    }

    /// The plan granted under cap `c >= 1` and its extra cost over one pass.
    pub fn capped(&self, c: u32) -> (TilePlan, u64) {
        if self.resort && self.resort_level() <= c {
            return (TilePlan::Resort, self.resort_cost.saturating_sub(self.pass_cost));
        }
        let p = if self.resort { c } else { self.passes.min(c) }.max(1);
        let plan = if self.wide { TilePlan::Wide(p) } else { TilePlan::Passes(p) };
        (plan, (p as u64 - 1) * self.pass_cost)
    }
}

/// A tile's request from its previous write-back signals `wb` (of the table it reuses), the
/// previous frame's merge inversions `merge`, the current list length and the chunk size.
pub fn request(p: &AdaptiveParams, wb: &WritebackSignals, merge: u32, current: u32, chunk: u32) -> Request {
    let chunk = chunk.max(1);
    // Neo's single pass while the reach is below a chunk; beyond, the wide chunk if there is one.
    let wide = p.wide > 1 && wb.reach >= chunk;
    let unit = if wide { chunk.saturating_mul(p.wide) } else { chunk };
    // A pass of chunk U can carry an entry across U positions; more passes only when the reach
    // exceeds that (a finer rule, R / (U / 2), spent 10% more traffic on biker at 16x for
    // +0.1 dB mean and the same minimum, and spent traffic at 1x).
    let mut passes = 1 + wb.reach / unit;
    if passes > 1 && merge > 0 {
        passes += 1;
    }
    let len = wb.len as u64;
    let pass_cost = (2 * len).max(1);
    let resort_cost = resort_cost(current as u64, chunk as u64);
    let resort =
        p.resort && passes > 1 && (resort_cost <= pass_cost * passes as u64 || passes > p.max_passes);
    Request { passes: passes.min(p.max_passes), wide, resort, pass_cost, resort_cost }
}

/// The budget allocation of one frame (see the module docs): the plans granted to `requests`.
pub fn allocate(p: &AdaptiveParams, requests: &[Request]) -> Vec<TilePlan> {
    let budget = requests.iter().map(|r| r.pass_cost).sum::<u64>() * p.budget as u64 / 100;
    let top = requests
        .iter()
        .map(|r| if r.resort { r.resort_level().max(r.passes) } else { r.passes })
        .max()
        .unwrap_or(1)
        .max(1);
    let extra = |c: u32| requests.iter().map(|r| r.capped(c).1).sum::<u64>();
    // The extra cost grows with the cap; the largest cap within the budget (1 always fits).
    let (mut lo, mut hi) = (1u32, top);
    while lo < hi {
        let mid = lo + (hi - lo).div_ceil(2);
        if extra(mid) <= budget {
            lo = mid;
        } else {
            hi = mid - 1;
        }
    }
    // The rest of the budget raises tiles above the cap by one level, in tile order.
    let mut left = budget - extra(lo);
    requests
        .iter()
        .map(|r| {
            let (plan, x) = r.capped(lo);
            let (up, y) = r.capped(lo + 1);
            if up != plan && y - x <= left {
                left -= y - x;
                up
            } else {
                plan
            }
        })
        .collect()
}

/// Camera motion between two frames.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct CameraMotion {
    /// Angle between the view directions, degrees.
    pub rotation_deg: f64,
    /// Distance between the camera positions (scene units).
    pub translation: f64,
}

impl CameraMotion {
    /// Motion from `a` to `b`.
    pub fn between(a: &Camera, b: &Camera) -> Self {
        CameraMotion {
            rotation_deg: angle_deg(a.forward(), b.forward()),
            translation: a.position.distance(b.position),
        }
    }
}

/// Angle between two directions in degrees.
pub fn angle_deg(a: DVec3, b: DVec3) -> f64 {
    let (a, b) = (a.normalize_or_zero(), b.normalize_or_zero());
    a.dot(b).clamp(-1.0, 1.0).acos().to_degrees()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn e(key: u32, id: u32) -> SortEntry {
        SortEntry::new(key, id)
    }

    #[test]
    fn writeback_signals_count_descents_behind_and_reach() {
        let sorted: Vec<SortEntry> = (0..10).map(|k| e(k, k)).collect();
        assert_eq!(writeback_signals(&sorted), WritebackSignals { len: 10, ..Default::default() });
        // 9 at the front must move past the 5 entries after it.
        let t = [e(9, 0), e(1, 1), e(2, 2), e(3, 3), e(4, 4), e(5, 5)];
        let s = writeback_signals(&t);
        assert_eq!((s.descents, s.behind, s.reach), (1, 5, 5));
        // Invalid entries are skipped.
        let mut t2 = t.to_vec();
        t2[0].valid = false;
        assert_eq!(writeback_signals(&t2).behind, 0);
    }

    #[test]
    fn params_parse_print_and_reject() {
        let p = AdaptiveParams::parse("budget=30, max=6,resort=0,wide=8").unwrap();
        assert_eq!(p, AdaptiveParams { budget: 30, max_passes: 6, resort: false, wide: 8 });
        assert_eq!(AdaptiveParams::parse(&p.to_string()), Ok(p));
        assert_eq!(AdaptiveParams::parse(""), Ok(AdaptiveParams::default()));
        for (bad, name) in [
            ("max=0", "max"),
            ("budget=x", "budget"),
            ("resort=2", "resort"),
            ("speed=1", "speed"),
            ("wide=3", "wide"),
            ("budget=1,budget=2", "budget"),
        ] {
            let err = AdaptiveParams::parse(bad).unwrap_err();
            assert!(err.contains(&format!("'{name}'")), "{bad}: {err}");
        }
        assert!(AdaptiveParams::parse("budget").is_err());
    }

    #[test]
    fn resort_cost_counts_global_passes() {
        assert_eq!(resort_cost(100, 256), 200);
        assert_eq!(resort_cost(256, 256), 512);
        assert_eq!(resort_cost(257, 256), 2 * 257 * 2);
        assert_eq!(resort_cost(1024, 256), 2 * 1024 * 3);
    }

    #[test]
    fn allocation_fits_the_budget_and_serves_small_requests_first() {
        let p = AdaptiveParams { budget: 50, max_passes: 8, resort: false, wide: 1 };
        let wb = |len, reach| WritebackSignals { len, reach, ..Default::default() };
        let reqs: Vec<Request> = [wb(1000, 0), wb(1000, 256), wb(1000, 2000)]
            .iter()
            .map(|w| request(&p, w, 0, 1000, 256))
            .collect();
        assert_eq!(reqs.iter().map(|r| r.passes).collect::<Vec<_>>(), vec![1, 2, 8]);
        // With a wide chunk of 4 x 256 the far tile asks for 1 + 2000 / 1024 = 2 wide passes.
        let w4 = request(&AdaptiveParams { wide: 4, ..p }, &wb(1000, 2000), 0, 1000, 256);
        assert_eq!((w4.passes, w4.wide), (2, true));
        assert_eq!(w4.capped(1).0, TilePlan::Wide(1));
        let plans = allocate(&p, &reqs);
        let extra: u64 =
            reqs.iter().zip(&plans).map(|(r, pl)| (pl.passes_or(1) as u64 - 1) * r.pass_cost).sum();
        assert!(extra <= 3000, "{plans:?}");
        assert_eq!(plans[0], TilePlan::Passes(1));
        assert_eq!(plans[1], TilePlan::Passes(2));
        assert_eq!(plans[2], TilePlan::Passes(1));
        // No budget: everything one pass.
        let none = allocate(&AdaptiveParams { budget: 0, ..p }, &reqs);
        assert!(none.iter().all(|pl| *pl == TilePlan::Passes(1)));
        // A small tile far out of order is re-sorted (no dearer than its passes).
        let narrow = AdaptiveParams { wide: 1, ..AdaptiveParams::default() };
        let r = request(&narrow, &wb(200, 300), 0, 200, 256);
        assert!(r.resort);
        assert_eq!(allocate(&narrow, &[r, reqs[0]]), vec![TilePlan::Resort, TilePlan::Passes(1)]);
    }

    proptest::proptest! {
        #[test]
        fn any_valid_params_round_trip(
            budget in 0u32..=1000,
            max_passes in 1u32..=16,
            resort: bool,
            wide_log in 0u32..=6,
        ) {
            let p = AdaptiveParams { budget, max_passes, resort, wide: 1 << wide_log };
            proptest::prop_assert_eq!(AdaptiveParams::parse(&p.to_string()), Ok(p));
            let s = crate::pipeline::Strategy::Adaptive(p);
            proptest::prop_assert_eq!(s.to_string().parse::<crate::pipeline::Strategy>(), Ok(s));
        }

        #[test]
        fn out_of_range_values_name_their_parameter(
            key in proptest::sample::select(vec!["budget", "max", "resort", "wide"]),
            v in 0u64..100_000,
        ) {
            let ok = match key {
                "budget" => v <= 1000,
                "max" => (1..=16).contains(&v),
                "resort" => v <= 1,
                _ => v <= 64 && v.is_power_of_two(),
            };
            let r = AdaptiveParams::parse(&format!("{key}={v}"));
            proptest::prop_assert_eq!(r.is_ok(), ok);
            if let Err(e) = r {
                proptest::prop_assert!(e.contains(&format!("'{key}'")), "{}", e);
            }
        }

        #[test]
        fn any_text_parses_or_errs_without_panicking(s in "[a-z=,0-9 .:-]{0,24}") {
            let _ = AdaptiveParams::parse(&s);
            let _ = format!("adaptive:{s}").parse::<crate::pipeline::Strategy>();
            let _ = format!("motion:{s}").parse::<crate::pipeline::Strategy>();
        }
    }
}
