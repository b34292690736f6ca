//! The reuse-and-update step: insertion, deletion by valid bit, the capacity cut, its work
//! counters, and a multi-frame run against the exact order.

use std::collections::HashMap;

use neo_golden::sort::{
    full_frame_sort, full_sort, update_tile, SortConfig, SortEntry, TileSorter, UpdateConfig,
};
use proptest::prelude::*;

fn sorted(mut v: Vec<SortEntry>) -> Vec<SortEntry> {
    v.sort_by_key(|e| (e.key, e.id));
    v
}

fn is_sorted(t: &[SortEntry]) -> bool {
    t.windows(2).all(|w| (w[0].key, w[0].id) <= (w[1].key, w[1].id))
}

/// Multiset of entries (with valid bits).
fn multiset(v: &[SortEntry]) -> HashMap<SortEntry, usize> {
    let mut m = HashMap::new();
    for e in v {
        *m.entry(*e).or_insert(0) += 1;
    }
    m
}

fn is_sub_multiset(part: &[SortEntry], whole: &[SortEntry]) -> bool {
    let w = multiset(whole);
    multiset(part).iter().all(|(e, n)| w.get(e).is_some_and(|m| m >= n))
}

/// Previous table entries from (key, valid) pairs, ids `0..`; incoming from keys, ids `10_000..`.
fn build(prev: &[(u32, bool)], incoming: &[u32]) -> (Vec<SortEntry>, Vec<SortEntry>) {
    let p =
        prev.iter().enumerate().map(|(i, &(key, valid))| SortEntry { key, id: i as u32, valid }).collect();
    let n = incoming.iter().enumerate().map(|(i, &key)| SortEntry::new(key, 10_000 + i as u32)).collect();
    (p, n)
}

#[test]
fn capacity_overflow_keeps_the_nearest_and_reports_the_count() {
    let prev_pairs: Vec<(u32, bool)> = (0..600u32).map(|i| (i * 3, i % 7 != 0)).collect();
    let incoming_keys: Vec<u32> = (0..300u32).map(|i| (i * 7919) % 2000).collect();
    let (prev, incoming) = build(&prev_pairs, &incoming_keys);
    let live: Vec<SortEntry> = prev.iter().filter(|e| e.valid).chain(&incoming).copied().collect();
    for capacity in [0, 1, 100, 500, 700, live.len() - 1, live.len(), live.len() + 10] {
        let cfg = UpdateConfig::new(SortConfig::artifact(), capacity);
        let u = update_tile(&prev, &incoming, 3, &cfg);
        let expect: Vec<SortEntry> = sorted(live.clone()).into_iter().take(capacity).collect();
        assert_eq!(u.table, expect, "capacity {capacity}");
        assert!(is_sorted(&u.table));
        assert!(is_sub_multiset(&u.table, &live));
        assert_eq!(u.work.dropped_capacity, live.len().saturating_sub(capacity));
        assert_eq!(u.work.dropped_invalid, prev.len() - prev.iter().filter(|e| e.valid).count());
        assert_eq!(u.work.table_len, u.table.len());
        assert_eq!(u.work.merge.out, live.len());
        assert_eq!(u.work.merge.in_a, prev.len());
        assert_eq!(u.work.merge.in_b, incoming.len());
        assert_eq!(u.work.dps.dram_entries_read(), prev.len());
        assert_eq!(u.work.incoming_sort.entries, incoming.len());
    }
}

#[test]
fn full_frame_sort_is_full_sort_then_capacity() {
    let entries: Vec<SortEntry> = (0..1500u32).map(|i| SortEntry::new((i * 7919) % 1009, i)).collect();
    for capacity in [0, 10, 1499, 1500, 5000] {
        let cfg = UpdateConfig::new(SortConfig::artifact(), capacity);
        let f = full_frame_sort(&entries, &cfg);
        let (all, work) = full_sort(&entries, &cfg.sort);
        assert_eq!(f.table, all[..capacity.min(1500)]);
        assert_eq!(f.work.incoming_sort, work);
        assert_eq!(f.work.dropped_capacity, 1500usize.saturating_sub(capacity));
        assert_eq!(f.work.dps.passes, 0);
    }
}

#[test]
fn tile_sorter_reuse_matches_the_free_functions() {
    let cfg = UpdateConfig::new(SortConfig::artifact(), 800);
    let mut ts = TileSorter::new(cfg.clone());
    let mut table = Vec::new();
    let first: Vec<SortEntry> = (0..900u32).map(|i| SortEntry::new((i * 31) % 977, i)).collect();
    let w0 = ts.full_frame_sort(&first, &mut table);
    let f = full_frame_sort(&first, &cfg);
    assert_eq!(table, f.table);
    assert_eq!(w0, f.work);
    for frame in 1..4u64 {
        let incoming: Vec<SortEntry> = (0..50u32)
            .map(|i| SortEntry::new((i * 13 + frame as u32) % 977, 1000 * frame as u32 + i))
            .collect();
        for (i, e) in table.iter_mut().enumerate() {
            e.valid = (i as u64 + frame) % 11 != 3;
        }
        let expect = update_tile(&table, &incoming, frame, &cfg);
        let w = ts.update(&mut table, &incoming, frame);
        assert_eq!(table, expect.table, "frame {frame}");
        assert_eq!(w, expect.work);
    }
}

#[test]
fn moving_then_still_camera_reaches_the_exact_order() {
    // A tile of 2000 Gaussians whose depths drift each frame (deferred depth update: the keys
    // written into the table are the ones rasterization saw, used by the next frame's sort).
    // Some leave (valid bit cleared during rasterization), some arrive. Once the camera stops,
    // two frames restore the exact order of the live set.
    let cfg = UpdateConfig::new(SortConfig::artifact(), 1 << 20);
    let mut ts = TileSorter::new(cfg);
    let mut depth: Vec<i64> = (0..3000i64).map(|i| 5_000 + 17 * i - (i * i) % 97).collect();
    let mut table = Vec::new();
    let initial: Vec<SortEntry> = (0..2000u32).map(|i| SortEntry::new(depth[i as usize] as u32, i)).collect();
    ts.full_frame_sort(&initial, &mut table);
    let mut next_id = 2000u32;
    let mut unsorted_while_moving = false;
    for frame in 1..=12u64 {
        let moving = frame <= 8;
        if moving {
            for (i, d) in depth.iter_mut().enumerate() {
                *d += ((i as i64 * 7 + frame as i64 * 13) % 61) - 30;
            }
        }
        // Rasterization of the previous frame: write back current depths, clear leavers.
        for e in table.iter_mut() {
            e.key = depth[e.id as usize] as u32;
            if moving && (e.id as u64 + frame) % 53 == 5 {
                e.valid = false;
            }
        }
        let incoming: Vec<SortEntry> = if moving {
            (0..20).map(|k| next_id + k).map(|id| SortEntry::new(depth[id as usize] as u32, id)).collect()
        } else {
            Vec::new()
        };
        next_id += incoming.len() as u32;
        let live: Vec<SortEntry> = table.iter().filter(|e| e.valid).chain(&incoming).copied().collect();
        ts.update(&mut table, &incoming, frame);
        assert_eq!(multiset(&table), multiset(&live), "frame {frame}: not a permutation of the live set");
        if frame >= 10 {
            assert!(is_sorted(&table), "frame {frame}: still camera should have converged");
        }
        unsorted_while_moving |= moving && !is_sorted(&table);
    }
    // One DPS pass per frame lags behind the motion (so the convergence above is not trivial).
    assert!(unsorted_while_moving);
}

proptest! {
    #[test]
    fn update_of_a_sorted_table_is_the_truncated_sorted_union(
        prev in proptest::collection::vec((0u32..100, any::<bool>()), 0..400),
        incoming in proptest::collection::vec(0u32..100, 0..200),
        capacity in 0usize..700,
        frame in 0u64..4,
    ) {
        let (mut p, n) = build(&prev, &incoming);
        p = sorted(p); // a table in THE ORDER (still camera)
        let cfg = UpdateConfig::new(SortConfig::artifact(), capacity);
        let u = update_tile(&p, &n, frame, &cfg);
        let live: Vec<SortEntry> = p.iter().filter(|e| e.valid).chain(&n).copied().collect();
        let expect: Vec<SortEntry> = sorted(live.clone()).into_iter().take(capacity).collect();
        prop_assert_eq!(&u.table, &expect);
        prop_assert_eq!(u.work.dropped_capacity, live.len().saturating_sub(capacity));
    }

    #[test]
    fn update_of_any_table_never_corrupts(
        prev in proptest::collection::vec((0u32..100, any::<bool>()), 0..400),
        incoming in proptest::collection::vec(0u32..100, 0..200),
        capacity in 0usize..700,
        frame in 0u64..4,
    ) {
        // Arbitrary (stale) order: the result is a subset of the live entries, of the right
        // length, with the incoming entries in order, and exactly the live set without overflow.
        let (p, n) = build(&prev, &incoming);
        let cfg = UpdateConfig::new(SortConfig::new(neo_golden::sort::SortFormat::ARTIFACT, 32, neo_golden::sort::Network::best_16()).unwrap(), capacity);
        let u = update_tile(&p, &n, frame, &cfg);
        let live: Vec<SortEntry> = p.iter().filter(|e| e.valid).chain(&n).copied().collect();
        prop_assert_eq!(u.table.len(), live.len().min(capacity));
        prop_assert!(u.table.iter().all(|e| e.valid));
        prop_assert!(is_sub_multiset(&u.table, &live));
        prop_assert_eq!(u.work.dropped_capacity + u.table.len(), live.len());
        if live.len() <= capacity {
            prop_assert_eq!(multiset(&u.table), multiset(&live));
        }
        let inserted: Vec<SortEntry> = u.table.iter().filter(|e| e.id >= 10_000).copied().collect();
        prop_assert!(is_sorted(&inserted));
    }
}
