//! The raster core's timing: the cycles of one tile ([`raster_tile_cycles`]) and the fit of its
//! measured constants to the grid of `reports/latency.json` ([`fit_raster_core`]).

use neo_golden::formats::latency::{GridPoint, RasterCore};

use crate::config::RasterTiming;
use crate::dram::Ps;
use neo_golden::engine::{SegmentWork, ROUTING_FIFO_DEPTH};

/// The raster core's cycles for one tile of `table_len` entries, `entries` of them with a
/// feature entry. The ITUs test every table entry against all subtiles of the tile at once,
/// `itus` per cycle, once per subtile group (`ceil(table_len / itus) * itu_ii` per group, Fig. 14:
/// they test the next group while the SCUs blend the current one; skipped when the bitmaps come
/// from memory, `itu = false`); the SCUs take the subtiles in groups of `scus`, each SCU blending
/// its subtile's routed entries: `processed * scu_ii + (routed - processed) * drain_ii`, with
/// `processed = ceil(routed * ratio)` (early termination). A group lasts as long as its slowest
/// SCU.
///
/// With the measured raster core's shape (`rt.pixel_write_cycles > 0`, from
/// `reports/latency.json`), the table is processed in segments of at most `rt.feature_buffer`
/// entries (one when it fits), each loaded once into a bank while the previous one is walked and
/// blended, and walked for every group (the SCUs save and resume their subtiles' pixel state
/// between segments). After the first segment's loads (`load_cycles_per_entry` per entry), each
/// segment costs the longer of the two below, plus `segment_overhead` when there are several:
/// - its work: the walks of all groups (every quad for group 0; for a later group a cycle finding
///   the first quad that touches it plus those quads, at least one, estimated from the group's
///   busiest subtile) or the segment's share of the busiest SCU, whichever is longer (the routing
///   FIFOs decouple the walker from the SCUs and the SCUs from each other, so an SCU's cost is
///   the sum over its subtiles of every group: a lower bound when the busiest SCU changes from
///   group to group by more than a FIFO's worth);
/// - the request port: the segment's write-back plus the next segment's loads or, after the last
///   segment (which finishes every subtile), the pixel writes.
///
/// A reorder window (`rt.window` above 1) holds `W - 1` entries back: see [`segment_pipeline`].
/// `tile_overhead` (the empty tile beyond its pixel writes) adds the
/// latencies. Returns (total,
/// tail after the last input arrives).
#[allow(clippy::too_many_arguments)]
pub fn raster_tile_cycles(
    routed: &[u32],
    ratio: f64,
    entries: u32,
    table_len: u32,
    rt: &RasterTiming,
    itus: u32,
    scus: u32,
    itu: bool,
) -> (f64, f64) {
    raster_tile_cycles_in_segments(routed, ratio, entries, table_len, rt, itus, scus, itu, None)
}

/// [`raster_tile_cycles`] with each segment's own work (`segments`, from golden's engine trace)
/// instead of an even share of the tile's, for the measured raster core's shape.
#[allow(clippy::too_many_arguments)]
pub fn raster_tile_cycles_in_segments(
    routed: &[u32],
    ratio: f64,
    entries: u32,
    table_len: u32,
    rt: &RasterTiming,
    itus: u32,
    scus: u32,
    itu: bool,
    segments: Option<&[SegmentWork]>,
) -> (f64, f64) {
    let cost = |r: u32| {
        let p = (r as f64 * ratio).ceil().min(r as f64);
        p * rt.scu_cycles_per_pair + (r as f64 - p) * rt.scu_drain_ii
    };
    let groups: Vec<f64> =
        routed.chunks(scus.max(1) as usize).map(|g| g.iter().map(|&r| cost(r)).fold(0.0, f64::max)).collect();
    let scu_total: f64 = groups.iter().sum();
    let tail = groups.last().copied().unwrap_or(0.0) + rt.scu_latency as f64;
    let len = if itu { table_len.max(entries) } else { entries };
    let walk = if itu { (len as f64 / itus.max(1) as f64).ceil().max(1.0) * rt.itu_ii } else { 0.0 };
    let itu_total = walk * groups.len().max(1) as f64;
    let total = if rt.pixel_write_cycles == 0 {
        let lat =
            if itu { rt.itu_latency as f64 } else { 0.0 } + rt.scu_latency as f64 + rt.tile_overhead as f64;
        rt.load_cycles_per_entry * len as f64 + itu_total.max(scu_total) + lat
    } else {
        // Quad skipping: group 0 walks every quad; a later group walks, after a cycle finding the
        // first, only the quads that touch it: with `n_g` of the table's entries touching the
        // group (at least its busiest subtile's), a fraction `1 - (1 - n_g / len)^itus` of them.
        let hit: Vec<f64> = routed
            .chunks(scus.max(1) as usize)
            .map(|g| {
                let n_g = g.iter().copied().max().unwrap_or(0) as f64;
                1.0 - (1.0 - (n_g / len.max(1) as f64).min(1.0)).powi(itus.max(1) as i32)
            })
            .collect();
        let walk_of = |n: f64| -> Vec<f64> {
            let quads = (n / itus.max(1) as f64).ceil().max(1.0);
            hit.iter()
                .enumerate()
                .map(|(k, &h)| if k == 0 { quads } else { 1.0 + (h * quads).max(1.0) } * rt.itu_ii)
                .collect()
        };
        let f = if rt.feature_buffer > 0 { rt.feature_buffer } else { u64::from(len.max(1)) };
        let segs = segments.map_or(u64::from(len).div_ceil(f).max(1), |v| v.len().max(1) as u64);
        let seg_overhead = if segs > 1 { segs as f64 * rt.segment_overhead } else { 0.0 };
        let shape = TileShape { routed, segments, len: len as f64, f: f as f64, segs, itus, scus };
        let body = segment_pipeline(&shape, rt, &cost, &walk_of);
        body + seg_overhead + rt.tile_overhead as f64
    };
    (total, tail.min(total))
}

/// The load cycles of a tile's first `c` entries (of `len`, in segments of `f`) at `rate` cycles
/// an entry: whole segments at the rate; a segment loaded only in part (`k` of its entries, as
/// a reorder window needs them) costs its whole table phase and `k` feature reads, each half the
/// rate (an entry's table beat and its feature word).
fn window_loads(c: f64, len: f64, f: f64, rate: f64) -> f64 {
    let whole = (c / f).floor() * f;
    let k = c - whole;
    if k <= 0.0 {
        return rate * c;
    }
    rate * whole + rate / 2.0 * ((len - whole).min(f) + k)
}

/// The entries a reorder window of `rt.window` entries holds back in a tile of `len` entries
/// (all of a shorter table; 0 without a window).
fn window_hold(len: f64, rt: &RasterTiming) -> f64 {
    (rt.window.saturating_sub(1) as f64).min(len)
}

/// A tile's work as [`segment_pipeline`] sees it.
struct TileShape<'a> {
    routed: &'a [u32],
    /// Each segment's own work, when known.
    segments: Option<&'a [SegmentWork]>,
    len: f64,
    /// Entries per segment.
    f: f64,
    segs: u64,
    itus: u32,
    scus: u32,
}

/// The measured raster core's body, piece by piece: segment `s + 1` loads (after the first
/// segment's loads, on the request port with segment `s`'s write-back) while segment `s` is
/// walked group by group; each walked group hands every SCU its *piece* (the segment's share of
/// its subtile's routed entries) through the SCU's routing FIFO of
/// [`ROUTING_FIFO_DEPTH`] elements (one per walked quad that touches the subtile). The walker
/// moves on from a group once every SCU's FIFO has room, that is once each SCU is within a
/// FIFO's worth of the end of its piece, so a busy SCU holds the others back only by what
/// exceeds its FIFO. After the last segment, whose groups finish the subtiles, the pixel writes.
///
/// A reorder window holding `h` entries back ([`window_hold`]) emits segment `s`'s last entry
/// only once the entries up to `h` past it are loaded: the loads run `h` entries ahead of the
/// segments (the first segment waits for `F + h` loads, each later one for the next `F`), and
/// the entries still held when the last load arrives drain one a cycle (measured on the unit
/// bench: a one-segment table takes `h` cycles more; docs/cycle-model.md, "Reorder window").
fn segment_pipeline(
    t: &TileShape,
    rt: &RasterTiming,
    cost: &dyn Fn(u32) -> f64,
    walk_of: &dyn Fn(f64) -> Vec<f64>,
) -> f64 {
    let n_of = |s: u64| match t.segments {
        Some(v) => v.get(s as usize).map_or(0.0, |w| f64::from(w.entries)),
        None => (t.len - s as f64 * t.f).min(t.f).max(0.0),
    };
    // Segment `s`'s piece of subtile `j`: its routed entries and its SCU's cycles.
    let piece = |s: u64, j: usize, n: f64| -> (f64, f64) {
        let r_all = t.routed.get(j).copied().unwrap_or(0);
        match t.segments.and_then(|v| v.get(s as usize)) {
            Some(w) => {
                let (r, p) =
                    (w.routed.get(j).copied().unwrap_or(0), w.processed.get(j).copied().unwrap_or(0));
                let p = p.min(r);
                (f64::from(r), f64::from(p) * rt.scu_cycles_per_pair + f64::from(r - p) * rt.scu_drain_ii)
            }
            None => {
                let share = if t.len > 0.0 { n / t.len } else { 0.0 };
                (f64::from(r_all) * share, cost(r_all) * share)
            }
        }
    };
    let itus = f64::from(t.itus.max(1));
    let fifo = f64::from(ROUTING_FIFO_DEPTH);
    let scus = t.scus.max(1) as usize;
    let mut scu_free = vec![0.0f64; scus];
    // Entries loaded by the time segment `s` is complete (`cum`: its end in the table), and
    // when the last entry still held after the last load has drained.
    let hold = window_hold(t.len, rt);
    let needed = |cum: f64| (cum + hold).min(t.len);
    let loads = |c: f64| window_loads(c, t.len, t.f, rt.load_cycles_per_entry);
    let drained = |cum: f64, last_load: f64| last_load + (cum - (t.len - hold)).max(0.0);
    let mut cum = n_of(0);
    let (mut walker, mut loaded) = (0.0f64, loads(needed(cum)));
    let mut last_load = (needed(cum) >= t.len).then_some(loaded);
    let mut end = 0.0f64;
    for s in 0..t.segs {
        let n = n_of(s);
        walker = walker.max(loaded);
        if let Some(last) = last_load {
            // Without a window, `last` is an earlier `loaded`: nothing changes.
            walker = walker.max(drained(cum, last));
        }
        let seg_start = walker;
        for (g, walk) in walk_of(n).iter().enumerate() {
            let start = walker;
            let mut leave = start + walk;
            for (jj, free) in scu_free.iter_mut().enumerate() {
                let (r, c) = piece(s, g * scus + jj, n);
                if r <= 0.0 {
                    continue;
                }
                let elements = (n / itus * (1.0 - (1.0 - (r / n).min(1.0)).powf(itus))).max(1.0);
                *free = free.max(start) + c;
                leave = leave.max(*free - fifo * c / elements);
            }
            walker = leave;
        }
        if s + 1 < t.segs {
            let next = cum + n_of(s + 1);
            loaded += loads(needed(next)) - loads(needed(cum))
                + (rt.write_back_cycles_per_entry * n - rt.write_back_overlap).max(0.0);
            if last_load.is_none() && needed(next) >= t.len {
                last_load = Some(loaded);
            }
            cum = next;
        } else {
            let blended = scu_free.iter().copied().fold(walker, f64::max);
            end = blended.max(loaded.max(seg_start) + n + rt.pixel_write_cycles as f64);
        }
    }
    end
}

/// The measured raster core's timing: `base` (the ITU and SCU figures) completed from the grid
/// of `raster.core` (`reports/latency.json`) with the formula of [`raster_tile_cycles`]:
///
/// - `tile_overhead`: the cycles of the empty table (loads of nothing, one empty list per
///   subtile, the pipeline latencies) beyond its pixel writes;
/// - `load_cycles_per_entry`: the slope of the loads (the last read's cycle) over the table
///   length, between the shortest non-empty table and the longest one-segment table of the
///   fewest subtile bits per Gaussian;
/// - `segment_overhead`: what the tables of more than two segments cost per segment beyond
///   [`raster_tile_cycles`] with no segment overhead, averaged over the points where the walk or
///   the port, not a burst of blending, sets the pace (fewer than 16 subtile bits per Gaussian),
///   rounded and at least 0. A point's routed counts are rebuilt from its `group_max_routed`:
///   every subtile of a group routes the group's share (the grid's Gaussians spread evenly).
///
/// `subtiles` is the number of subtiles per tile of the measured RTL.
pub fn fit_raster_core(
    core: &RasterCore,
    subtiles: u64,
    base: &RasterTiming,
) -> Result<RasterTiming, String> {
    let (scus, f) = (core.scus, core.feature_buffer);
    if core.itus == 0 || scus == 0 || subtiles == 0 || !subtiles.is_multiple_of(scus) || subtiles > 4096 {
        return Err(format!(
            "itus {}, scus {} and {subtiles} subtiles per tile: expected positive counts, subtiles a multiple of scus",
            core.itus, scus
        ));
    }
    if f == 0 {
        return Err("`feature_buffer` must be positive".into());
    }
    if let Some(p) = core.grid.iter().find(|p| p.entries > 1 << 20) {
        return Err(format!("`grid`: a table of {} entries (at most 2^20)", p.entries));
    }
    let empty = core.grid.iter().find(|p| p.entries == 0).ok_or("`grid` has no empty table")?;
    let fewest_bits = core.grid.iter().map(|p| p.bits_per_gaussian).min().unwrap_or(0);
    let one_segment: Vec<_> = core
        .grid
        .iter()
        .filter(|p| p.bits_per_gaussian == fewest_bits && p.entries > 0 && p.entries <= f)
        .collect();
    let (first, last) =
        match (one_segment.iter().min_by_key(|p| p.entries), one_segment.iter().max_by_key(|p| p.entries)) {
            (Some(a), Some(b)) if a.entries < b.entries => (*a, *b),
            _ => return Err("`grid` needs two one-segment tables of the fewest bits per Gaussian".into()),
        };
    let load = (last.load_cycles as f64 - first.load_cycles as f64) / (last.entries - first.entries) as f64;
    if load < 0.0 {
        return Err(format!(
            "`grid`: the loads of {} entries end before those of {}",
            last.entries, first.entries
        ));
    }
    let mut rt = RasterTiming {
        tile_overhead: empty.cycles.saturating_sub(core.pixel_writes),
        load_cycles_per_entry: load,
        pixel_write_cycles: core.pixel_writes,
        feature_buffer: f,
        segment_overhead: 0.0,
        ..base.clone()
    };
    let per_segment: Vec<f64> = core
        .grid
        .iter()
        .filter(|p| p.entries > 2 * f && p.bits_per_gaussian < 16)
        .map(|p| (p.cycles as f64 - grid_point_cycles(core, p, subtiles, &rt)) / p.entries.div_ceil(f) as f64)
        .collect();
    if !per_segment.is_empty() {
        rt.segment_overhead = (per_segment.iter().sum::<f64>() / per_segment.len() as f64).round().max(0.0);
    }
    Ok(rt)
}

/// [`raster_tile_cycles`] of grid point `p` of `core` (`subtiles` per tile) with timing `rt`: the
/// point's routed counts rebuilt from its `group_max_routed`, every subtile of a group routing
/// the group's share (the grid's Gaussians spread evenly).
pub fn grid_point_cycles(core: &RasterCore, p: &GridPoint, subtiles: u64, rt: &RasterTiming) -> f64 {
    let scus = core.scus.max(1);
    let groups = (subtiles / scus).max(1);
    let routed: Vec<u32> = (0..subtiles)
        .map(|s| {
            let g = s / scus;
            (p.group_max_routed / groups + u64::from(g < p.group_max_routed % groups)).min(u32::MAX.into())
                as u32
        })
        .collect();
    let n = p.entries as u32;
    raster_tile_cycles(&routed, 1.0, n, n, rt, core.itus as u32, scus as u32, true).0
}

/// `cycles` clock cycles of `cyc` picoseconds, in whole picoseconds.
pub(super) fn round_ps(cycles: f64, cyc: f64) -> Ps {
    (cycles * cyc).round().max(0.0) as Ps
}

#[cfg(test)]
mod tests {
    use super::*;
    use neo_golden::formats::latency::GridPoint;

    fn rt() -> RasterTiming {
        RasterTiming {
            itu_ii: 1.0,
            itu_latency: 3,
            scu_cycles_per_pair: 4.0,
            scu_drain_ii: 1.0,
            scu_latency: 10,
            tile_overhead: 0,
            load_cycles_per_entry: 0.0,
            pixel_write_cycles: 0,
            write_back_cycles_per_entry: 1.0,
            write_back_overlap: 0.0,
            feature_buffer: 0,
            segment_overhead: 0.0,
            window: 0,
        }
    }

    #[test]
    fn raster_groups_take_their_slowest_scu_and_overlap_the_itus() {
        // 8 subtiles in two groups of 4: group maxima 10 and 20 routed entries, no termination.
        let routed = [1, 10, 3, 0, 20, 5, 5, 5];
        let (t, tail) = raster_tile_cycles(&routed, 1.0, 40, 40, &rt(), 4, 4, true);
        // SCUs: (10 + 20) x 4 = 120; ITUs: 2 groups x 40 / 4 = 20, hidden; latencies 3 + 10.
        assert_eq!(t, 120.0 + 13.0);
        assert_eq!(tail, 20.0 * 4.0 + 10.0);
        // Half the pairs terminate early: processed at 4 cycles, the rest drained at 1.
        let (h, _) = raster_tile_cycles(&routed, 0.5, 40, 40, &rt(), 4, 4, true);
        assert_eq!(h, (5.0 * 4.0 + 5.0) + (10.0 * 4.0 + 10.0) + 13.0);
        // Many entries and few routed pairs: the ITUs (one walk per group) bound the tile.
        let (i, _) = raster_tile_cycles(&[1; 8], 1.0, 4000, 4000, &rt(), 4, 4, true);
        assert_eq!(i, 2.0 * 1000.0 + 13.0);
        // Without ITUs (bitmaps from memory) only the SCUs and their latency count.
        let (g, _) = raster_tile_cycles(&[1; 8], 1.0, 4000, 4000, &rt(), 4, 4, false);
        assert_eq!(g, 8.0 + 10.0);
    }

    #[test]
    fn measured_raster_core_shape_loads_then_overlaps_writes_and_segments_per_group() {
        let shaped = RasterTiming {
            load_cycles_per_entry: 2.0,
            pixel_write_cycles: 512,
            feature_buffer: 100,
            tile_overhead: 535,
            ..rt()
        };
        // Empty tile: the pixel writes and the overhead.
        assert_eq!(raster_tile_cycles(&[0; 64], 1.0, 0, 0, &shaped, 4, 4, true).0, 512.0 + 535.0);
        // Light tile: loads, then the port (the write-back and the pixel writes) bounds the body.
        assert_eq!(
            raster_tile_cycles(&[1; 64], 1.0, 20, 20, &shaped, 4, 4, true).0,
            40.0 + 20.0 + 512.0 + 535.0
        );
        // Heavy tile: the busiest SCU takes 16 subtiles of 50 routed entries = 3,200 cycles, and
        // hides the port.
        let (h, _) = raster_tile_cycles(&[50; 64], 1.0, 80, 80, &shaped, 4, 4, true);
        assert_eq!(h, 160.0 + 3200.0 + 535.0);
        // 200 entries > 100, two segments: the first segment's loads (200), then per segment the
        // busiest SCU's half (1,600) against the walks (25 quads for group 0, 18.1 for a later one)
        // and the port (the write-back and the next segment's loads, or the pixel writes).
        let (s, _) = raster_tile_cycles(&[50; 64], 1.0, 200, 200, &shaped, 4, 4, true);
        assert_eq!(s, 200.0 + 2.0 * 1600.0 + 535.0);
        // Light long table, 30 segments: port-bound (each segment's 55 cycles of walks, 25 for
        // group 0 and 2 for each later group, hide under its 100 write-backs and the next
        // segment's 200 cycles of loads; the last one's under its write-back and the 512 pixel
        // writes), plus the segment overhead.
        let o = RasterTiming { segment_overhead: 30.0, ..shaped };
        let (w, _) = raster_tile_cycles(&[1; 64], 1.0, 3000, 3000, &o, 4, 4, true);
        assert_eq!(w, 200.0 + 30.0 * 30.0 + 29.0 * 300.0 + 612.0 + 535.0);
    }

    /// A reorder window holds `window - 1` entries back (all of a shorter table): the tile's
    /// walk starts that many loads later; no window (0 or 1) changes nothing.
    #[test]
    fn a_reorder_window_delays_the_walk_by_the_loads_it_holds() {
        // Segments of 100 entries, 2 load cycles an entry (a table beat and a feature word).
        let shaped =
            RasterTiming { load_cycles_per_entry: 2.0, pixel_write_cycles: 512, feature_buffer: 100, ..rt() };
        let cycles = |window: u64, len: u32, routed: u32| {
            let r = RasterTiming { window, ..shaped.clone() };
            raster_tile_cycles(&[routed; 64], 1.0, len, len, &r, 4, 4, true).0
        };
        let extra = |window, len, routed| cycles(window, len, routed) - cycles(1, len, routed);
        for len in [0, 20, 3000] {
            assert_eq!(cycles(0, len, 50), cycles(1, len, 50), "{len}");
        }
        // One segment: the held entries drain one a cycle after the last load.
        for len in [0, 20, 100] {
            assert_eq!(extra(64, len, 50), f64::from(len.min(63)), "{len}");
        }
        // Walk-bound (the SCUs' work dwarfs the loads): the first walk waits for the held loads.
        // The held entries' whole segments at the load rate; the segment they end in, its whole
        // table phase and their feature reads, a cycle each (its table bursts come first).
        assert_eq!(extra(64, 3000, 20_000), 100.0 + 63.0);
        assert_eq!(extra(1024, 3000, 20_000), 1000.0 * 2.0 + 100.0 + 23.0);
        // Load-bound (little work): the loads run ahead, and only the drain at the end shows.
        let light = extra(1024, 3000, 10);
        assert!((0.0..=1023.0).contains(&light), "{light}");
    }

    #[test]
    fn the_raster_core_fit_recovers_the_constants_of_a_grid_made_by_the_formula() {
        let truth = RasterTiming {
            tile_overhead: 600,
            load_cycles_per_entry: 3.0,
            pixel_write_cycles: 512,
            feature_buffer: 100,
            segment_overhead: 7.0,
            ..rt()
        };
        let (itus, scus, subtiles) = (4u64, 4u64, 64u64);
        let mut grid = Vec::new();
        for bits in [1u64, 4, 16] {
            for entries in [0u64, 16, 64, 100, 200, 800] {
                // Every subtile routes the same share: 2 groups' worth of the table per bit.
                let per = (entries * bits / subtiles) as u32;
                let routed = vec![per; subtiles as usize];
                let n = entries as u32;
                let (cycles, _) =
                    raster_tile_cycles(&routed, 1.0, n, n, &truth, itus as u32, scus as u32, true);
                grid.push(GridPoint {
                    entries,
                    bits_per_gaussian: bits,
                    set_bits: entries * bits,
                    group_max_routed: per as u64 * subtiles / scus,
                    cycles: cycles as u64,
                    load_cycles: 9 + 3 * entries,
                });
            }
        }
        let core =
            RasterCore { itus, scus, feature_buffer: 100, pixel_writes: 512, memory: String::new(), grid };
        let fit = fit_raster_core(&core, subtiles, &rt()).unwrap();
        assert_eq!(fit.tile_overhead, truth.tile_overhead);
        assert_eq!(fit.load_cycles_per_entry, 3.0);
        assert_eq!(fit.segment_overhead, 7.0);
        assert_eq!((fit.pixel_write_cycles, fit.feature_buffer), (512, 100));
        let mut broken = core.clone();
        broken.grid.retain(|p| p.entries != 0);
        assert!(fit_raster_core(&broken, subtiles, &rt()).unwrap_err().contains("no empty table"));
        assert!(fit_raster_core(&core, 63, &rt()).is_err());
    }
}
