//! Dynamic Partial Sorting: identity on sorted tables, the two-pass guarantee for displacements
//! up to C/2 (exhaustively for small chunks, by property test for the artifact's), convergence
//! of alternating boundaries, and non-convergence of fixed boundaries (paper Fig. 9).

use neo_golden::sort::{dps, dps_pass, Network, Parity, SortConfig, SortEntry, SortFormat, Sorter};
use neo_golden::synthetic::rng::HashRng as Rng;
use proptest::prelude::*;

fn cfg(bsu: usize, chunk: usize) -> SortConfig {
    SortConfig::new(SortFormat::ARTIFACT, chunk, Network::bitonic(bsu)).unwrap()
}

fn is_sorted(t: &[SortEntry]) -> bool {
    t.windows(2).all(|w| (w[0].key, w[0].id) <= (w[1].key, w[1].id))
}

/// Table whose entry at position `p` has rank `perm[p]` (key = rank, id = rank).
fn table_from_ranks(perm: &[usize]) -> Vec<SortEntry> {
    perm.iter().map(|&r| SortEntry::new(r as u32, r as u32)).collect()
}

fn max_displacement(perm: &[usize]) -> usize {
    perm.iter().enumerate().map(|(p, &r)| p.abs_diff(r)).max().unwrap_or(0)
}

/// All permutations of `0..n` (lexicographic next-permutation).
fn for_each_permutation(n: usize, mut f: impl FnMut(&[usize])) {
    let mut p: Vec<usize> = (0..n).collect();
    loop {
        f(&p);
        let Some(i) = (1..n).rev().find(|&i| p[i - 1] < p[i]) else { return };
        let j = (i..n).rev().find(|&j| p[j] > p[i - 1]).unwrap();
        p.swap(i - 1, j);
        p[i..].reverse();
    }
}

/// A permutation of `0..len` with every displacement below `d`: sort positions by `i + noise`,
/// noise in `[0, d)` (position `i` can only be overtaken by `i - d + 1 ..`).
fn displaced_ranks(rng: &mut Rng, len: usize, d: usize) -> Vec<usize> {
    let mut order: Vec<(usize, usize)> = (0..len).map(|i| (i + rng.below(d as u64) as usize, i)).collect();
    order.sort_unstable();
    order.into_iter().map(|(_, i)| i).collect()
}

#[test]
fn sorted_tables_are_left_unchanged() {
    let mut rng = Rng::new(11, 0, 0);
    for (bsu, chunk) in [(16, 16), (16, 64), (16, 256), (2, 4)] {
        let c = cfg(bsu, chunk);
        for len in [0, 1, 7, 16, 100, 128, 255, 256, 257, 1000, 3000] {
            let mut keys: Vec<u32> = (0..len).map(|_| rng.below(500) as u32).collect();
            keys.sort_unstable();
            let table: Vec<SortEntry> = keys
                .iter()
                .enumerate()
                .map(|(i, &k)| SortEntry { key: k, id: i as u32, valid: rng.below(3) != 0 })
                .collect();
            for frame in 0..3 {
                for passes in 1..3 {
                    let mut t = table.clone();
                    let w = dps(&mut t, frame, passes, &c);
                    assert_eq!(t, table, "len {len} chunk {chunk} frame {frame}");
                    assert_eq!(w.passes, passes);
                    assert_eq!(w.dram_entries_read(), passes * len);
                    assert_eq!(w.dram_entries_written(), passes * len);
                    let expect_chunks: usize =
                        (0..passes).map(|p| Parity::of(frame, p).chunks(len, chunk).count()).sum();
                    assert_eq!(w.chunk.chunks, expect_chunks);
                }
            }
        }
    }
}

#[test]
fn two_alternating_passes_fix_displacement_up_to_half_chunk_exhaustively() {
    // Every permutation of up to 9 entries, chunks of 4 (BSU 2) and 8 (BSU 4); checked in both
    // parity orders.
    // Expected counts of permutations of 1..=9 entries with displacement <= C/2 (enumerated
    // independently): 1631 for C = 4, 34692 for C = 8.
    for (bsu, chunk, expect) in [(2usize, 4usize, 1631usize), (4, 8, 34_692)] {
        let c = cfg(bsu, chunk);
        let mut sorter = Sorter::new(c);
        let mut checked = 0;
        for len in 1..=9 {
            for_each_permutation(len, |perm| {
                if max_displacement(perm) > chunk / 2 {
                    return;
                }
                for first in [Parity::Even, Parity::Odd] {
                    let second = if first == Parity::Even { Parity::Odd } else { Parity::Even };
                    let mut t = table_from_ranks(perm);
                    sorter.dps_pass(&mut t, first);
                    sorter.dps_pass(&mut t, second);
                    assert!(is_sorted(&t), "chunk {chunk} perm {perm:?} first {first:?}");
                }
                checked += 1;
            });
        }
        assert_eq!(checked, expect, "chunk {chunk}: permutations checked");
    }
}

#[test]
fn displacement_of_half_chunk_plus_one_can_need_more_than_two_passes() {
    // The C/2 bound is tight. Ranks 0..h-2 in place, ranks h..C shifted down one, rank h-1 at
    // position C (displaced by h + 1): an even pass then an odd pass leave ranks h and h-1
    // swapped (the odd-first order happens to sort it).
    for (bsu, chunk) in [(4usize, 8usize), (16, 16), (16, 256)] {
        let h = chunk / 2;
        let mut perm: Vec<usize> = (0..h - 1).collect();
        perm.extend(h..=chunk);
        perm.push(h - 1);
        assert_eq!(max_displacement(&perm), h + 1);
        let c = cfg(bsu, chunk);
        let mut t = table_from_ranks(&perm);
        dps_pass(&mut t, Parity::Even, &c);
        dps_pass(&mut t, Parity::Odd, &c);
        assert!(!is_sorted(&t), "chunk {chunk}");
        assert_eq!((t[h - 1].key, t[h].key), (h as u32, h as u32 - 1));
    }
}

#[test]
fn two_frames_fix_displacement_up_to_half_chunk_at_artifact_size() {
    let mut rng = Rng::new(12, 0, 0);
    let c = cfg(16, 256);
    let mut sorter = Sorter::new(c);
    for trial in 0..40 {
        let len = 1 + rng.below(3000) as usize;
        let d = 1 + rng.below(129) as usize; // displacement < d <= C/2 + 1
        let perm = displaced_ranks(&mut rng, len, d);
        assert!(max_displacement(&perm) <= 128);
        let frame = rng.below(10);
        let mut t = table_from_ranks(&perm);
        sorter.dps(&mut t, frame, 1);
        sorter.dps(&mut t, frame + 1, 1);
        assert!(is_sorted(&t), "trial {trial} len {len} d {d}");
        // Same with two passes in one frame.
        let mut t = table_from_ranks(&perm);
        sorter.dps(&mut t, frame, 2);
        assert!(is_sorted(&t), "trial {trial} (two passes)");
    }
}

#[test]
fn stale_keys_converge_within_the_block_transposition_bound() {
    // A table sorted by last frame's keys; the new keys are perturbed (some a lot), written back
    // into the entries; alternating DPS frames restore THE ORDER within ceil(L / (C/2)) + 1.
    let mut rng = Rng::new(13, 0, 0);
    // Keys stay within the artifact's 16-bit key field.
    for (chunk, len, jitter) in
        [(32usize, 500usize, 40u32), (64, 1000, 2000), (256, 3000, 300), (16, 200, 15_000)]
    {
        let c = cfg(16, chunk);
        let mut sorter = Sorter::new(c);
        let mut table: Vec<SortEntry> = (0..len as u32).map(|i| SortEntry::new(20_000 + 10 * i, i)).collect();
        for e in &mut table {
            e.key = (e.key as i64 + rng.below(2 * jitter as u64) as i64 - jitter as i64).max(0) as u32;
        }
        let bound = len.div_ceil(chunk / 2) + 1;
        let mut frames = 0;
        while !is_sorted(&table) {
            sorter.dps(&mut table, frames as u64 + 1, 1);
            frames += 1;
            assert!(frames <= bound, "chunk {chunk} len {len}: not sorted after {bound} frames");
        }
        assert!(frames >= 1, "the perturbation should have unsorted the table");
    }
}

#[test]
fn any_permutation_converges_within_the_bound() {
    let mut rng = Rng::new(14, 0, 0);
    let c = cfg(16, 32);
    let mut sorter = Sorter::new(c);
    for len in [1usize, 31, 32, 33, 100, 400] {
        for _ in 0..5 {
            let mut perm: Vec<usize> = (0..len).collect();
            for i in (1..len).rev() {
                perm.swap(i, rng.below(i as u64 + 1) as usize);
            }
            let mut t = table_from_ranks(&perm);
            let bound = len.div_ceil(16) + 1;
            for f in 0..bound {
                sorter.dps(&mut t, f as u64, 1);
            }
            assert!(is_sorted(&t), "len {len}");
        }
    }
}

#[test]
fn fixed_boundaries_never_converge_but_interleaved_do() {
    // Paper Fig. 9 in miniature: ten Gaussians, depths 0..9, chunks of 4. The table is in
    // reverse order, so Gaussians must cross chunk boundaries.
    let c = cfg(2, 4);
    let reversed: Vec<usize> = (0..10).rev().collect();
    for fixed in [Parity::Even, Parity::Odd] {
        let mut t = table_from_ranks(&reversed);
        for _ in 0..50 {
            dps_pass(&mut t, fixed, &c);
        }
        assert!(!is_sorted(&t), "fixed {fixed:?} boundaries sorted the table");
        // It is stuck: one more pass changes nothing.
        let before = t.clone();
        dps_pass(&mut t, fixed, &c);
        assert_eq!(t, before);
    }
    let mut t = table_from_ranks(&reversed);
    let mut frames = 0;
    while !is_sorted(&t) {
        dps(&mut t, frames, 1, &c);
        frames += 1;
        assert!(frames <= 6, "interleaved boundaries did not converge");
    }

    // At the artifact's size: the farthest Gaussian sits first in a 512-entry table.
    let c = cfg(16, 256);
    let mut perm: Vec<usize> = (0..512).collect();
    perm.rotate_right(1); // rank 511 at position 0
    let mut t = table_from_ranks(&perm);
    for _ in 0..10 {
        dps_pass(&mut t, Parity::Even, &c);
    }
    assert_eq!(t[255].key, 511, "stuck at the end of the first chunk");
    assert!(!is_sorted(&t));
    let mut t = table_from_ranks(&perm);
    dps(&mut t, 0, 1, &c);
    dps(&mut t, 1, 1, &c);
    assert!(!is_sorted(&t), "two frames cannot move it 511 places");
    for f in 2..6 {
        dps(&mut t, f, 1, &c);
    }
    assert!(is_sorted(&t));
}

#[test]
fn passes_parameter_alternates_parity() {
    let mut rng = Rng::new(15, 0, 0);
    let c = cfg(16, 64);
    let perm: Vec<usize> = {
        let mut p: Vec<usize> = (0..700).collect();
        for i in (1..700).rev() {
            p.swap(i, rng.below(i as u64 + 1) as usize);
        }
        p
    };
    for frame in [0u64, 1, 6, 7] {
        let mut a = table_from_ranks(&perm);
        let w = dps(&mut a, frame, 3, &c);
        let mut b = table_from_ranks(&perm);
        for p in 0..3 {
            dps_pass(&mut b, Parity::of(frame, p), &c);
        }
        assert_eq!(a, b, "frame {frame}");
        assert_eq!(w.passes, 3);
        assert_eq!(w.dram_entries_read(), 3 * 700);
    }
    // Frame parity: even frames cut at multiples of C, odd frames at C/2 + kC.
    let mut t = table_from_ranks(&(0..128).rev().collect::<Vec<_>>());
    dps(&mut t, 4, 1, &c);
    assert!(is_sorted(&t[..64]) && is_sorted(&t[64..]) && !is_sorted(&t[..65]));
    let mut t = table_from_ranks(&(0..128).rev().collect::<Vec<_>>());
    dps(&mut t, 5, 1, &c);
    assert!(is_sorted(&t[..32]) && is_sorted(&t[32..96]) && is_sorted(&t[96..]) && !is_sorted(&t[..33]));
}

proptest! {
    #[test]
    fn dps_pass_is_a_permutation_that_sorts_each_chunk(
        keys in proptest::collection::vec(0u32..200, 0..600),
        odd in any::<bool>(),
    ) {
        let c = cfg(16, 64);
        let parity = if odd { Parity::Odd } else { Parity::Even };
        let table: Vec<SortEntry> = keys.iter().enumerate().map(|(i, &k)| SortEntry::new(k, i as u32)).collect();
        let mut t = table.clone();
        dps_pass(&mut t, parity, &c);
        for r in parity.chunks(t.len(), 64) {
            let mut expect = table[r.clone()].to_vec();
            expect.sort_by_key(|e| (e.key, e.id));
            prop_assert_eq!(&t[r], &expect[..]);
        }
    }
}
