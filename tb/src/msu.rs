//! The MSU+ test bench: sequences of merges through `neo_msu` (streams A and B with `last` and
//! `empty` beats, random stalls on both inputs, random output backpressure), each output beat
//! checked against golden `merge2`, and each merge's boundary inversions of A (`a_inv_o`, with
//! its last beat) against golden `MergeStats::a_inversions`.
//!
//! Stream encoding (docs in `gen/src/units/msu.rs`): `n >= 1` entries are `n` beats with `last`
//! on the final one; an empty stream is one beat with `empty = 1, last = 1`; extra `empty` beats
//! with `last = 0` may be inserted anywhere and are ignored. The output of a merge is its entries
//! (`empty = 0`, `last` on the final one), or one `empty = 1, last = 1` beat when it has none.

use crate::bits::get_bits;
use crate::check::Checker;
use crate::lanes::packed;
use crate::models::NeoMsu;
use crate::rng::Rng;
use crate::stream::{Beat, Sink, Source};
use neo_gen::EngineConfig;
use neo_golden::sort::{merge2, merge2_into, SortEntry};
use std::collections::VecDeque;

/// One merge: streams A (the reused table) and B (incoming) and the `drop_invalid_i` flag.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Merge {
    /// Stream A (sorted in THE ORDER).
    pub a: Vec<SortEntry>,
    /// Stream B (sorted in THE ORDER).
    pub b: Vec<SortEntry>,
    /// Drop entries whose valid bit is 0.
    pub drop_invalid: bool,
}

/// A beat the checker expects on the output.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct OutBeat {
    /// `out_empty_o`.
    pub empty: bool,
    /// `out_last_o`.
    pub last: bool,
    /// The entry (ignored when `empty`).
    pub entry: SortEntry,
}

/// The golden output beats of a merge.
pub fn expected_beats(m: &Merge) -> Vec<OutBeat> {
    let out = merge2(&m.a, &m.b, m.drop_invalid);
    if out.is_empty() {
        return vec![OutBeat { empty: true, last: true, entry: SortEntry::default() }];
    }
    let n = out.len();
    out.into_iter().enumerate().map(|(i, entry)| OutBeat { empty: false, last: i + 1 == n, entry }).collect()
}

/// Golden's boundary inversions of A in merge `m`.
pub fn expected_inversions(m: &Merge) -> u64 {
    merge2_into(&m.a, &m.b, m.drop_invalid, &mut Vec::new()).a_inversions as u64
}

/// Input beats of one stream, with `empty` filler beats inserted at probability `filler_pct`.
fn stream_beats(cfg: &EngineConfig, s: &[SortEntry], rng: &mut Rng, filler_pct: u32) -> Vec<Beat> {
    let fmt = cfg.format();
    let words = cfg.entry_bits().div_ceil(32) as usize;
    let mut beats = Vec::new();
    let filler = |rng: &mut Rng, beats: &mut Vec<Beat>| {
        while rng.percent(filler_pct) {
            let junk: Vec<u32> = (0..words).map(|_| rng.next_u32()).collect();
            beats.push(vec![junk, vec![0], vec![1]]);
        }
    };
    if s.is_empty() {
        filler(rng, &mut beats);
        beats.push(vec![vec![rng.next_u32(); words], vec![1], vec![1]]);
        return beats;
    }
    for (i, e) in s.iter().enumerate() {
        filler(rng, &mut beats);
        beats.push(vec![packed(&fmt, std::slice::from_ref(e)), vec![(i + 1 == s.len()) as u32], vec![0]]);
    }
    beats
}

/// Statistics of a run.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MsuRun {
    /// Merges checked.
    pub merges: usize,
    /// Input entries (A and B).
    pub entries_in: usize,
    /// Output entries checked.
    pub entries_out: usize,
    /// Cycles from the end of reset to the last output.
    pub cycles: u64,
    /// Boundary inversions of A checked (summed over the merges).
    pub inversions: u64,
}

/// Runs `merges` through the MSU+ in order and checks every output beat. Consecutive merges with
/// the same `drop_invalid` stream back to back; the flag changes only once the MSU+ is drained.
/// `stall_pct` applies to both inputs, `ready_pct` to the output, `filler_pct` is the rate of
/// ignored `empty` beats in the inputs.
pub fn run_checked(
    dut: &mut NeoMsu,
    cfg: &EngineConfig,
    seed: u64,
    merges: &[Merge],
    stall_pct: u32,
    ready_pct: u32,
    filler_pct: u32,
) -> MsuRun {
    let fmt = cfg.format();
    let w = cfg.entry_bits() as usize;
    let mut rng = Rng::new(seed);
    let checker = Checker::new(NeoMsu::NAME, seed);
    let data = |s: &str| [format!("{s}_data_i"), format!("{s}_last_i"), format!("{s}_empty_i")];
    let [ad, al, ae] = data("a");
    let [bd, bl, be] = data("b");
    let mut src_a = Source::new::<NeoMsu>("a_valid_i", "a_ready_o", &[&ad, &al, &ae], rng.fork(1), stall_pct);
    let mut src_b = Source::new::<NeoMsu>("b_valid_i", "b_ready_o", &[&bd, &bl, &be], rng.fork(2), stall_pct);
    let mut sink = Sink::new::<NeoMsu>(
        "out_valid_o",
        "out_ready_i",
        &["out_data_o", "out_last_o", "out_empty_o"],
        rng.fork(3),
        ready_pct,
    );
    let mut beat_rng = rng.fork(4);

    dut.set_a_valid_i(false);
    dut.set_b_valid_i(false);
    dut.set_out_ready_i(false);
    dut.set_drop_invalid_i(false);
    dut.reset();

    let mut stats = MsuRun { merges: merges.len(), ..MsuRun::default() };
    let inversions: Vec<u64> = merges.iter().map(expected_inversions).collect();
    let mut expected: VecDeque<(usize, usize, OutBeat)> = VecDeque::new();
    let mut i = 0;
    while i < merges.len() {
        // A segment of merges sharing the drop flag.
        let drop = merges[i].drop_invalid;
        let mut j = i;
        while j < merges.len() && merges[j].drop_invalid == drop {
            let m = &merges[j];
            for b in stream_beats(cfg, &m.a, &mut beat_rng, filler_pct) {
                src_a.push(b);
            }
            for b in stream_beats(cfg, &m.b, &mut beat_rng, filler_pct) {
                src_b.push(b);
            }
            for (k, beat) in expected_beats(m).into_iter().enumerate() {
                expected.push_back((j, k, beat));
            }
            stats.entries_in += m.a.len() + m.b.len();
            j += 1;
        }
        dut.set_drop_invalid_i(drop);
        let budget =
            dut.cycle() + 200 + 40 * expected.len() as u64 + 40 * (src_a.pending() + src_b.pending()) as u64;
        while !expected.is_empty() {
            if dut.cycle() > budget {
                let (mi, k, _) = expected[0];
                checker.fail(
                    dut.cycle(),
                    "out_valid_o",
                    &format!("merge {mi} beat {k}"),
                    "no output (timeout)",
                );
            }
            src_a.drive(dut);
            src_b.drive(dut);
            sink.drive(dut);
            dut.eval();
            src_a.sample(dut);
            src_b.sample(dut);
            if let Some(beat) = sink.sample(dut, &checker) {
                let (mi, k, want) = expected.pop_front().expect("checked non-empty");
                let c = dut.cycle();
                let what = format!("merge {mi} beat {k}");
                checker.value(c, &format!("{what} out_empty_o"), want.empty as u64, beat[2][0] as u64);
                checker.value(c, &format!("{what} out_last_o"), want.last as u64, beat[1][0] as u64);
                if want.last {
                    checker.value(c, &format!("merge {mi} a_inv_o"), inversions[mi], dut.a_inv_o());
                    stats.inversions += inversions[mi];
                }
                if !want.empty {
                    let got = fmt.unpack(get_bits(&beat[0], 0, w));
                    checker.entry(c, &format!("{what} out_data_o"), &want.entry, &got);
                    stats.entries_out += 1;
                }
            }
            dut.tick();
        }
        // Drained: the inputs must all have been consumed, and nothing more may come out.
        checker.protocol(
            dut.cycle(),
            src_a.is_idle() && src_b.is_idle(),
            "input beats left after the last output",
        );
        for _ in 0..3 {
            src_a.drive(dut);
            src_b.drive(dut);
            dut.set_out_ready_i(true);
            dut.eval();
            checker.protocol(dut.cycle(), !dut.out_valid_o(), "an output beat after the merges ended");
            dut.tick();
        }
        i = j;
    }
    stats.cycles = dut.cycle();
    stats
}

/// `count` random merges (lengths `0..=max_len`, random valid densities, ties and duplicates
/// across A and B, both drop settings, empty streams). A quarter of the A streams are out of
/// order as a reused table after a DPS pass is: sorted runs in reversed order (boundary
/// inversions for `a_inv_o`).
pub fn random_merges(cfg: &EngineConfig, rng: &mut Rng, count: usize, max_len: usize) -> Vec<Merge> {
    use crate::stimulus::sorted_stream;
    let fmt = cfg.format();
    (0..count)
        .map(|_| {
            let len = |rng: &mut Rng| match rng.below(8) {
                0 => 0,
                1 => rng.range(1, 3) as usize,
                _ => rng.below(max_len as u64 + 1) as usize,
            };
            let (la, lb) = (len(rng), len(rng));
            let ties = rng.percent(30);
            let va = *rng.pick(&[100, 90, 50, 0]);
            let vb = *rng.pick(&[100, 90, 50, 0]);
            let a = sorted_stream(&fmt, rng, la, va, ties);
            let mut b = sorted_stream(&fmt, rng, lb, vb, ties);
            if rng.percent(10) {
                // B shares A's (key, id)s with flipped valid bits: the tie rule decides the order.
                b = a.iter().map(|e| e.with_valid(!e.valid)).collect();
            }
            let mut a = a;
            if rng.percent(25) && a.len() > 1 {
                let run = rng.range(1, a.len() as u64) as usize;
                a = a.chunks(run).rev().flatten().copied().collect();
            }
            Merge { a, b, drop_invalid: rng.percent(50) }
        })
        .collect()
}
