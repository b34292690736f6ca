//! Jobs sharing an AXI port, played as fluids (the engine-level model's port sharing,
//! [`crate::engine_frame`]).
//!
//! Each job starts at a known time and runs its phases in order (a sort's stages, a raster's
//! tile). A phase alone takes `alone` cycles and keeps each channel (R and W) busy a share of
//! them: its *demand*, a fraction of the channel's capacity. While several phases are active on
//! a port:
//! - each channel is divided by weighted max-min fairness ([`max_min_fair`]): a phase never
//!   gets more than its demand, and what the others leave is divided in proportion to the
//!   weights (on R, the beats each keeps in flight: the round-robin mux and the memory's order
//!   serve the requests they have outstanding);
//! - a *latency-bound* job (a raster core: its reads are bound by its reads in flight, not by
//!   the channel) reads at most its demand times the share of R the others leave: its requests
//!   wait behind theirs, whether or not the channel is full;
//! - each phase progresses at the lower of its two channels' fractions of its demand.
//!
//! Read off the RTL (2026-12-06, every AXI transfer of a frame logged on the CI engine): behind
//! the ideal memory a sort's merges and a raster split R 0.650 / 0.349 beats a cycle (their
//! beats in flight, 64 against 37.6, give 0.63 / 0.37); behind the random memory a raster that
//! reads 0.534 a cycle alone reads 0.386-0.421 beside a sort's 0.157-0.249 (the rule gives
//! 0.357-0.42), the channel not full, and the sort is not slowed.
//!
//! Between two events (a job starting, a phase ending) the rates are constant, so the play is
//! exact for this fluid model and costs a few operations per phase.

/// One phase of a job: its cycles alone and its demand on each channel (the share of the
/// channel's capacity it keeps busy alone, at most 1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FluidPhase {
    /// Cycles alone on the port.
    pub alone: f64,
    /// Read-channel demand while it runs alone.
    pub read: f64,
    /// Write-channel demand while it runs alone.
    pub write: f64,
}

/// A job on a port: its phases, and its weights on the R and W channels.
#[derive(Clone, Debug, PartialEq)]
pub struct FluidJob {
    /// Its phases, in order.
    pub phases: Vec<FluidPhase>,
    /// Weight on the R channel: the beats it keeps in flight.
    pub read_weight: f64,
    /// Weight on the W channel.
    pub write_weight: f64,
    /// Whether its reads are bound by its reads in flight (a raster core): beside others it
    /// reads at most its demand times the share of R they leave.
    pub latency_bound: bool,
}

/// Each job's phase durations when `jobs` (each with its start, in cycles) share one port.
pub fn play(jobs: &[(f64, &FluidJob)]) -> Vec<Vec<f64>> {
    let mut out: Vec<Vec<f64>> = jobs.iter().map(|(_, j)| Vec::with_capacity(j.phases.len())).collect();
    // Per job: the phase it is in, the progress left in it (cycles alone), and when it began.
    let mut at: Vec<usize> = vec![0; jobs.len()];
    let mut left: Vec<f64> = jobs.iter().map(|(_, j)| j.phases.first().map_or(0.0, |p| p.alone)).collect();
    let mut began: Vec<f64> = jobs.iter().map(|&(start, _)| start).collect();
    let mut t = jobs.iter().map(|&(start, _)| start).fold(f64::INFINITY, f64::min);
    loop {
        // Phases without work end where they begin.
        for (i, &(start, j)) in jobs.iter().enumerate() {
            while at[i] < j.phases.len() && start <= t && left[i] <= 0.0 {
                out[i].push(t.max(began[i]) - began[i]);
                at[i] += 1;
                began[i] = t.max(start);
                left[i] = j.phases.get(at[i]).map_or(0.0, |p| p.alone);
            }
        }
        let unfinished = |i: usize| at[i] < jobs[i].1.phases.len();
        let active: Vec<usize> = (0..jobs.len()).filter(|&i| unfinished(i) && jobs[i].0 <= t).collect();
        let next_start = (0..jobs.len())
            .filter(|&i| unfinished(i) && jobs[i].0 > t)
            .map(|i| jobs[i].0)
            .fold(f64::INFINITY, f64::min);
        if active.is_empty() {
            if next_start.is_infinite() {
                return out;
            }
            t = next_start;
            continue;
        }
        let phase = |i: usize| jobs[i].1.phases[at[i]];
        let rates = progress_rates(&active.iter().map(|&i| (phase(i), jobs[i].1)).collect::<Vec<_>>());
        let first_end = active.iter().zip(&rates).map(|(&i, &r)| left[i] / r).fold(f64::INFINITY, f64::min);
        let dt = first_end.min(next_start - t);
        for (&i, &r) in active.iter().zip(&rates) {
            left[i] = if left[i] / r <= dt { 0.0 } else { left[i] - r * dt };
        }
        t += dt;
    }
}

/// Each active phase's progress rate (at most 1; see the module docs).
fn progress_rates(active: &[(FluidPhase, &FluidJob)]) -> Vec<f64> {
    let reads = max_min_fair(&active.iter().map(|(p, j)| (p.read, j.read_weight)).collect::<Vec<_>>());
    let writes = max_min_fair(&active.iter().map(|(p, j)| (p.write, j.write_weight)).collect::<Vec<_>>());
    let total: f64 = reads.iter().sum();
    let fraction = |demand: f64, got: f64| if demand > 0.0 { (got / demand).clamp(1e-6, 1.0) } else { 1.0 };
    active
        .iter()
        .zip(reads.iter().zip(&writes))
        .map(|((p, j), (&r, &w))| {
            let r = if j.latency_bound { r.min(p.read * (1.0 - (total - r)).max(0.0)) } else { r };
            fraction(p.read, r).min(fraction(p.write, w))
        })
        .collect()
}

/// Weighted max-min fair shares of a channel of capacity 1 among `(demand, weight)` claims: no
/// claim gets more than its demand, and the capacity the others leave is divided in proportion
/// to the weights.
pub fn max_min_fair(claims: &[(f64, f64)]) -> Vec<f64> {
    let mut alloc = vec![0.0; claims.len()];
    let mut open: Vec<usize> = (0..claims.len()).filter(|&i| claims[i].0 > 0.0).collect();
    let mut capacity = 1.0f64;
    while !open.is_empty() && capacity > 0.0 {
        let weights: f64 = open.iter().map(|&i| claims[i].1.max(f64::MIN_POSITIVE)).sum();
        let share = |i: usize| capacity * claims[i].1.max(f64::MIN_POSITIVE) / weights;
        let (sated, hungry): (Vec<usize>, Vec<usize>) = open.iter().partition(|&&i| claims[i].0 <= share(i));
        if sated.is_empty() {
            for &i in &hungry {
                alloc[i] = share(i);
            }
            return alloc;
        }
        for &i in &sated {
            alloc[i] = claims[i].0;
            capacity -= claims[i].0;
        }
        open = hungry;
    }
    alloc
}

#[cfg(test)]
mod tests {
    use super::*;

    fn job(start: f64, phases: &[(f64, f64, f64)], read_weight: f64) -> (f64, FluidJob) {
        let job = FluidJob {
            phases: phases.iter().map(|&(alone, read, write)| FluidPhase { alone, read, write }).collect(),
            read_weight,
            write_weight: 1.0,
            latency_bound: false,
        };
        (start, job)
    }

    /// [`play`] on jobs held with their starts.
    fn play_owned(jobs: &[(f64, FluidJob)]) -> Vec<Vec<f64>> {
        play(&jobs.iter().map(|(start, j)| (*start, j)).collect::<Vec<_>>())
    }

    fn arb_job() -> impl proptest::strategy::Strategy<Value = (f64, FluidJob)> {
        use proptest::prelude::*;
        let phase = (0.0..2000.0f64, 0.0..=1.0f64, 0.0..=1.0f64)
            .prop_map(|(alone, read, write)| FluidPhase { alone, read, write });
        (0.0..3000.0f64, proptest::collection::vec(phase, 0..6), 0.5..100.0f64, 0.5..20.0f64, any::<bool>())
            .prop_map(|(start, phases, read_weight, write_weight, latency_bound)| {
                (start, FluidJob { phases, read_weight, write_weight, latency_bound })
            })
    }

    proptest::proptest! {
        /// Every phase ends, never sooner than alone; a job alone on its port takes its time
        /// alone; a phase that uses neither channel is never slowed; and no channel carries
        /// more than its capacity (the work done over the play fits in it).
        #[test]
        fn sharing_only_ever_slows_and_conserves_the_channels(
            jobs in proptest::collection::vec(arb_job(), 1..5)
        ) {
            let d = play_owned(&jobs);
            proptest::prop_assert_eq!(d.len(), jobs.len());
            for ((_, j), dj) in jobs.iter().zip(&d) {
                proptest::prop_assert_eq!(dj.len(), j.phases.len());
                for (p, &x) in j.phases.iter().zip(dj) {
                    proptest::prop_assert!(x >= p.alone - 1e-6 * (1.0 + p.alone), "{x} < {}", p.alone);
                    if p.read == 0.0 && p.write == 0.0 {
                        proptest::prop_assert!((x - p.alone).abs() <= 1e-6 * (1.0 + p.alone), "{x} vs {}", p.alone);
                    }
                }
            }
            let alone = play_owned(&jobs[..1]);
            for (x, p) in alone[0].iter().zip(&jobs[0].1.phases) {
                proptest::prop_assert!((x - p.alone).abs() <= 1e-6 * (1.0 + p.alone), "alone: {x} vs {}", p.alone);
            }
            // The beats a channel moved (demand times time alone, summed) fit in its capacity
            // over the span of the play.
            let start = jobs.iter().map(|(s, _)| *s).fold(f64::INFINITY, f64::min);
            let end = jobs.iter().zip(&d).map(|((s, _), dj)| s + dj.iter().sum::<f64>()).fold(start, f64::max);
            let work = |f: fn(&FluidPhase) -> f64| -> f64 {
                jobs.iter().flat_map(|(_, j)| j.phases.iter().map(move |p| f(p) * p.alone)).sum()
            };
            proptest::prop_assert!(work(|p| p.read) <= (end - start) + 1e-6 * (1.0 + end - start));
            proptest::prop_assert!(work(|p| p.write) <= (end - start) + 1e-6 * (1.0 + end - start));
        }
    }

    #[test]
    fn fair_shares_follow_weights_and_demands() {
        let a = max_min_fair(&[(1.0, 64.0), (0.9, 37.6)]);
        assert!((a[0] - 64.0 / 101.6).abs() < 1e-12 && (a[1] - 37.6 / 101.6).abs() < 1e-12, "{a:?}");
        // A claim below its share keeps its demand; the other takes the rest.
        let a = max_min_fair(&[(0.25, 64.0), (0.9, 37.6)]);
        assert!((a[0] - 0.25).abs() < 1e-12 && (a[1] - 0.75).abs() < 1e-12, "{a:?}");
        // Demands that fit are met.
        assert_eq!(max_min_fair(&[(0.3, 1.0), (0.5, 1.0)]), vec![0.3, 0.5]);
        assert_eq!(max_min_fair(&[(0.0, 1.0), (2.0, 1.0)]), vec![0.0, 1.0]);
    }

    #[test]
    fn a_lone_job_takes_its_phases_alone() {
        let d = play_owned(&[job(5.0, &[(10.0, 0.5, 0.5), (0.0, 1.0, 0.0), (20.0, 1.0, 1.0)], 1.0)]);
        assert_eq!(d, vec![vec![10.0, 0.0, 20.0]]);
    }

    #[test]
    fn two_saturating_jobs_share_the_channel_by_weight() {
        // Both read a beat a cycle alone; weights 3 and 1: while both run, a gets 3/4 of R.
        let d = play_owned(&[job(0.0, &[(300.0, 1.0, 0.0)], 3.0), job(0.0, &[(100.0, 1.0, 0.0)], 1.0)]);
        // b: 100 cycles of work at 1/4 -> 400 cycles; a does 300 in those 400 cycles.
        assert!((d[1][0] - 400.0).abs() < 1e-9, "{d:?}");
        assert!((d[0][0] - 400.0).abs() < 1e-9, "{d:?}");
    }

    #[test]
    fn a_light_phase_is_not_slowed_and_the_next_one_is() {
        // a: a light phase (0.25 a cycle) then a heavy one; b reads 0.9 a cycle throughout.
        let a = job(0.0, &[(100.0, 0.25, 0.0), (100.0, 1.0, 0.0)], 64.0);
        let b = job(0.0, &[(1000.0, 0.9, 0.0)], 36.0);
        let d = play_owned(&[a, b]);
        assert!((d[0][0] - 100.0).abs() < 1e-9, "the light phase fits beside b: {d:?}");
        // Then a gets 64% of R (its share), so its heavy phase takes 100 / 0.64.
        assert!((d[0][1] - 100.0 / 0.64).abs() < 1e-9, "{d:?}");
        // b: 0.75 of R for 100 cycles, 0.36 for 156.25, alone after.
        let done = 100.0 * 0.75 / 0.9 + 156.25 * 0.36 / 0.9;
        assert!((d[1][0] - (256.25 + (1000.0 - done))).abs() < 1e-6, "{d:?}");
    }

    #[test]
    fn a_latency_bound_reader_waits_behind_the_others_reads() {
        // The channel has room (0.6 + 0.3), but the raster's reads wait behind the sort's: it
        // reads 0.6 (1 - 0.3) a cycle; the sort is not slowed.
        let (start, raster) = job(0.0, &[(100.0, 0.6, 0.1)], 37.6);
        let raster = (start, FluidJob { latency_bound: true, ..raster });
        let sort = job(0.0, &[(1000.0, 0.3, 0.3)], 64.0);
        let d = play_owned(&[raster.clone(), sort.clone()]);
        assert!((d[0][0] - 100.0 / 0.7).abs() < 1e-9, "{d:?}");
        assert!((d[1][0] - 1000.0).abs() < 1e-9, "{d:?}");
        // Not latency-bound, the same reader fits beside the sort.
        let d = play_owned(&[(start, FluidJob { latency_bound: false, ..raster.1 }), sort]);
        assert!((d[0][0] - 100.0).abs() < 1e-9, "{d:?}");
    }

    #[test]
    fn the_slower_channel_sets_the_pace() {
        // Both write a beat a cycle with equal weights: half each, whatever the reads.
        let d = play_owned(&[job(0.0, &[(50.0, 0.1, 1.0)], 1.0), job(0.0, &[(50.0, 0.1, 1.0)], 1.0)]);
        assert!((d[0][0] - 100.0).abs() < 1e-9 && (d[1][0] - 100.0).abs() < 1e-9, "{d:?}");
    }
}
