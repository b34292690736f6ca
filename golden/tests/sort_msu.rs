//! MSU+ merge semantics: ordering, invalid dropping, empty inputs, ties, and the cycle-level
//! stream's agreement with `merge2`.

use neo_golden::sort::{full_sort, merge2, MergeStream, Network, SortConfig, SortEntry, SortFormat};
use proptest::prelude::*;

fn sorted(mut v: Vec<SortEntry>) -> Vec<SortEntry> {
    v.sort_by_key(|e| (e.key, e.id));
    v
}

/// A sorted stream from (key, valid) pairs with ids `base, base + 2, ...` (so two streams built
/// from bases 0 and 1 have distinct ids).
fn stream(pairs: &[(u32, bool)], base: u32) -> Vec<SortEntry> {
    sorted(
        pairs
            .iter()
            .enumerate()
            .map(|(i, &(key, valid))| SortEntry { key, id: base + 2 * i as u32, valid })
            .collect(),
    )
}

#[test]
fn empty_inputs() {
    let a = stream(&[(3, true), (5, false)], 0);
    assert!(merge2(&[], &[], true).is_empty());
    assert!(merge2(&[], &[], false).is_empty());
    assert_eq!(merge2(&a, &[], false), a);
    assert_eq!(merge2(&[], &a, false), a);
    assert_eq!(merge2(&a, &[], true), vec![a[0]]);
    assert_eq!(merge2(&[], &a, true), vec![a[0]]);
    let all_invalid = stream(&[(1, false), (2, false)], 0);
    assert!(merge2(&all_invalid, &all_invalid, true).is_empty());
}

#[test]
fn many_equal_keys_interleave_by_id() {
    // Both inputs hold key 9 only; ids interleave (even in a, odd in b).
    let a = stream(&[(9, true); 300], 0);
    let b = stream(&[(9, true); 200], 1);
    let out = merge2(&a, &b, false);
    let ids: Vec<u32> = out.iter().map(|e| e.id).collect();
    let mut expect: Vec<u32> = (0..400).collect();
    expect.extend((400..600).step_by(2));
    assert_eq!(ids, expect);
}

#[test]
fn ties_across_chunk_boundaries_sort_by_id() {
    // 2000 entries with 3 keys: every chunk and every global merge sees long runs of ties.
    let input: Vec<SortEntry> = (0..2000u32).map(|i| SortEntry::new(i % 3, (i * 1237) % 2003)).collect();
    for chunk in [16, 32, 256] {
        let cfg = SortConfig::new(SortFormat::ARTIFACT, chunk, Network::bitonic(16)).unwrap();
        let (out, _) = full_sort(&input, &cfg);
        assert_eq!(out, sorted(input.clone()), "chunk {chunk}");
    }
}

#[test]
fn identical_key_and_id_take_a_first() {
    let a = [SortEntry { key: 4, id: 4, valid: true }];
    let b = [SortEntry { key: 4, id: 4, valid: false }];
    assert_eq!(merge2(&a, &b, false), vec![a[0], b[0]]);
    assert_eq!(merge2(&b, &a, false), vec![b[0], a[0]]);
}

proptest! {
    #[test]
    fn merge2_keeps_exactly_the_valid_entries_sorted(
        pa in proptest::collection::vec((0u32..40, any::<bool>()), 0..80),
        pb in proptest::collection::vec((0u32..40, any::<bool>()), 0..80),
    ) {
        let a = stream(&pa, 0);
        let b = stream(&pb, 1);
        let all = sorted(a.iter().chain(&b).copied().collect());
        prop_assert_eq!(merge2(&a, &b, false), all.clone());
        let valid: Vec<SortEntry> = all.iter().filter(|e| e.valid).copied().collect();
        prop_assert_eq!(merge2(&a, &b, true), valid);
    }

    #[test]
    fn merge_stream_matches_merge2(
        pa in proptest::collection::vec((0u32..40, any::<bool>()), 0..60),
        pb in proptest::collection::vec((0u32..40, any::<bool>()), 0..60),
        drop in any::<bool>(),
    ) {
        let a = stream(&pa, 0);
        let b = stream(&pb, 1);
        let mut s = MergeStream::new(&a, &b, drop);
        let out: Vec<SortEntry> = s.by_ref().filter_map(|st| st.out).collect();
        prop_assert_eq!(&out, &merge2(&a, &b, drop));
        // At most one entry per cycle; never more cycles than entries in.
        prop_assert!(s.cycles() >= out.len() && s.cycles() <= a.len() + b.len());
        if !drop {
            prop_assert_eq!(s.cycles(), a.len() + b.len());
        }
    }
}
