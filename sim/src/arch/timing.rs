//! The raster core's timing: the cycles of one tile ([`raster_tile_cycles`]) and the fit of its
//! measured constants to the grid of `reports/latency.json` ([`fit_raster_core`]).

use neo_golden::formats::latency::RasterCore;

use crate::config::RasterTiming;
use crate::dram::Ps;

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
/// `reports/latency.json`): the loads (`load_cycles_per_entry` per table entry) come first, then
/// `max(ITU walk, busiest SCU, pixel writes)` (the RTL's SCUs are decoupled by their routing
/// FIFOs, so an SCU's cost is the sum over its subtiles of all groups; a lower bound when the
/// busiest SCU changes from group to group by more than a FIFO's worth), and `tile_overhead`
/// (the empty tile) holds the latencies and the pixel writes. The ITUs walk every quad for group
/// 0 and, for a later group, a cycle finding the first quad that touches it plus those quads
/// (at least one; estimated from the group's busiest subtile). A table longer than
/// `rt.feature_buffer` is processed segment by segment, each segment loaded once (into a bank,
/// while the previous segment is walked and blended) and walked for every group (the SCUs save
/// and resume their subtiles' pixel state between segments): after the first segment's loads,
/// each segment costs `max(the sum over groups of max(its walk, the segment's share of the
/// group's slowest SCU), the memory port: the segment's write-back and the next segment's
/// loads)` (the routing FIFOs do not hide a busy subtile behind the next group's walk) plus
/// `segment_overhead`. Returns (total, tail after the last input arrives).
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
        let load = rt.load_cycles_per_entry * len as f64;
        let pix = rt.pixel_write_cycles as f64;
        let segmented = rt.feature_buffer > 0 && len as u64 > rt.feature_buffer;
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
        let body = if segmented {
            // Banks: segment s + 1 loads while segment s is walked and blended. Per segment, a
            // group takes the longer of its walk and its slowest SCU's share (the walk of the
            // next group waits for FIFO space); the port carries the segment's write-back and the
            // next segment's loads.
            let f = rt.feature_buffer;
            let segs = (len as u64).div_ceil(f);
            let n_of = |s: u64| (len as u64 - s * f).min(f) as f64;
            let mut body = rt.load_cycles_per_entry * n_of(0) + segs as f64 * rt.segment_overhead;
            for s in 0..segs {
                let n = n_of(s);
                let work: f64 =
                    walk_of(n).iter().zip(&groups).map(|(&w, &g)| w.max(g * n / len as f64)).sum();
                let next = if s + 1 < segs { rt.load_cycles_per_entry * n_of(s + 1) } else { 0.0 };
                body += work.max(next + n);
            }
            body.max(load + pix)
        } else {
            // One segment: each SCU runs through its subtiles of every group, decoupled from the
            // others by its routing FIFO, so the blending takes the busiest SCU's sum.
            let walks: f64 = walk_of(len as f64).iter().sum();
            load + walks.max(busiest_scu(routed, scus, &cost)).max(pix)
        };
        body - pix + rt.tile_overhead as f64
    };
    (total, tail.min(total))
}

/// The busiest SCU's blending: SCU `j` takes subtiles `j, j + scus, ...` (one per group), each
/// costing `cost(routed)`.
fn busiest_scu(routed: &[u32], scus: u32, cost: &dyn Fn(u32) -> f64) -> f64 {
    let s = scus.max(1) as usize;
    (0..s).map(|j| routed.iter().skip(j).step_by(s).map(|&r| cost(r)).sum::<f64>()).fold(0.0, f64::max)
}

/// The measured raster core's timing: `base` (the ITU and SCU figures) completed from the grid
/// of `raster.core` (`reports/latency.json`) with the formula of [`raster_tile_cycles`]:
///
/// - `tile_overhead`: the cycles of the empty table (loads of nothing, one empty list per
///   subtile, the pixel writes, the pipeline latencies);
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
        tile_overhead: empty.cycles,
        load_cycles_per_entry: load,
        pixel_write_cycles: core.pixel_writes,
        feature_buffer: f,
        segment_overhead: 0.0,
        ..base.clone()
    };
    let groups = subtiles / scus;
    let per_segment: Vec<f64> = core
        .grid
        .iter()
        .filter(|p| p.entries > 2 * f && p.bits_per_gaussian < 16)
        .map(|p| {
            let routed: Vec<u32> = (0..subtiles)
                .map(|s| {
                    let g = s / scus;
                    (p.group_max_routed / groups + u64::from(g < p.group_max_routed % groups))
                        .min(u32::MAX.into()) as u32
                })
                .collect();
            let n = p.entries as u32;
            let (model, _) = raster_tile_cycles(&routed, 1.0, n, n, &rt, core.itus as u32, scus as u32, true);
            (p.cycles as f64 - model) / p.entries.div_ceil(f) as f64
        })
        .collect();
    if !per_segment.is_empty() {
        rt.segment_overhead = (per_segment.iter().sum::<f64>() / per_segment.len() as f64).round().max(0.0);
    }
    Ok(rt)
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
            feature_buffer: 0,
            segment_overhead: 0.0,
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
        // Empty tile: the overhead.
        assert_eq!(raster_tile_cycles(&[0; 64], 1.0, 0, 0, &shaped, 4, 4, true).0, 535.0);
        // Light tile: loads, then the pixel writes bound the body.
        assert_eq!(raster_tile_cycles(&[1; 64], 1.0, 20, 20, &shaped, 4, 4, true).0, 40.0 + 535.0);
        // Heavy tile: 16 groups of 4 SCUs with 50 routed each = 16 x 200 cycles.
        let (h, _) = raster_tile_cycles(&[50; 64], 1.0, 80, 80, &shaped, 4, 4, true);
        assert_eq!(h, 160.0 + 3200.0 - 512.0 + 535.0);
        // 200 entries > 100, two segments: the first segment's loads (200), then per segment
        // and group the walk (25 quads for group 0, 18.1 for a later one: 1 + the 68% of the
        // quads that touch it) against half the group's slowest SCU (200 / 2); the port (the
        // write-backs and the second segment's loads) hides under the blending.
        let (s, _) = raster_tile_cycles(&[50; 64], 1.0, 200, 200, &shaped, 4, 4, true);
        assert_eq!(s, 200.0 + 2.0 * 16.0 * 100.0 - 512.0 + 535.0);
        // Light long table, 30 segments: port-bound (each segment's 55 cycles of walks, 25 for
        // group 0 and 2 for each later group, hide under its 100 write-backs and the next
        // segment's 200 cycles of loads), plus the segment overhead.
        let o = RasterTiming { segment_overhead: 30.0, ..shaped };
        let (w, _) = raster_tile_cycles(&[1; 64], 1.0, 3000, 3000, &o, 4, 4, true);
        assert_eq!(w, 200.0 + 30.0 * 30.0 + 29.0 * 300.0 + 100.0 - 512.0 + 535.0);
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
        assert_eq!(fit.tile_overhead, raster_tile_cycles(&[0; 64], 1.0, 0, 0, &truth, 4, 4, true).0 as u64);
        assert_eq!(fit.load_cycles_per_entry, 3.0);
        assert_eq!(fit.segment_overhead, 7.0);
        assert_eq!((fit.pixel_write_cycles, fit.feature_buffer), (512, 100));
        let mut broken = core.clone();
        broken.grid.retain(|p| p.entries != 0);
        assert!(fit_raster_core(&broken, subtiles, &rt()).unwrap_err().contains("no empty table"));
        assert!(fit_raster_core(&core, 63, &rt()).is_err());
    }
}
