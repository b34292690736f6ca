//! The raster core's reorder window: the table's entries, in table order, pass through a
//! buffer of `W` entries on their way from the feature gather to the ITUs; whenever the buffer
//! holds `W` entries it emits the smallest by the entry's **current** order key `{depth_key,
//! id}` (the key its feature entry carries this frame), and at the table's end it drains
//! smallest first. The emitted order is the order the tile is blended in and the order the
//! table is written back in.
//!
//! Why: a reused table is sorted by the keys the previous frame wrote back. When the camera
//! moves fast those keys are a frame stale, and no sorting pass over them can recover the
//! current order (docs/adaptive.md section 4). The window sorts by the current keys, on chip,
//! at no DRAM traffic: an entry that belongs up to `W - 1` places earlier than where the table
//! holds it is emitted in its place. A table already in the current order passes unchanged, and
//! `W = 1` is no window at all (each entry is emitted as it enters).
//!
//! In hardware it is a priority queue of the `W - 1` entries it holds plus the arriving one (one
//! insert and one extract of the minimum per entry: a shift-register queue of compare-and-hold
//! cells for small `W`, a pipelined heap for large), beside a store of the feature entries it
//! holds. In the RTL: `neo_raster_window` (a shift-register queue of compare-and-hold cells),
//! when the engine configuration's `raster_window` is above 1 (docs/adaptive.md section 7).

use crate::sort::SortEntry;
use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// The largest window (entries).
pub const MAX_WINDOW: usize = 1 << 16;

/// The window of 1 entry: no reordering (the serde default of a record written before its
/// window field).
pub fn no_window() -> usize {
    1
}

/// `true` for a window of 1 (no window): records leave the field out then, so those written
/// before it keep their text (and an engine configuration its hash).
pub fn is_no_window(w: &usize) -> bool {
    *w == 1
}

/// Checks a window size: `1` (no window) to [`MAX_WINDOW`] entries.
pub fn check_window(window: usize) -> Result<(), String> {
    match window {
        0 => Err("raster window 0: a window holds at least 1 entry (1: no reordering)".into()),
        w if w > MAX_WINDOW => Err(format!("raster window {w} is above {MAX_WINDOW} entries")),
        _ => Ok(()),
    }
}

/// The order key the window sorts a table entry by: `{current_key, id}` where the raster reads
/// a feature entry for the Gaussian this frame (`current_key`: that entry's depth key), the
/// entry's own `{key, id}` where it has none (culled).
pub fn current_order_key(entry: &SortEntry, current_key: Option<u32>) -> u64 {
    SortEntry::new(current_key.unwrap_or(entry.key), entry.id).order_key()
}

/// The emission order (indices into `table`) of a window of `window` entries over a tile's
/// table, entry `i` keyed by [`current_order_key`] with `current(i)`, its Gaussian's depth key
/// this frame (`None`: culled).
pub fn table_window_order(
    table: &[SortEntry],
    window: usize,
    current: impl Fn(usize) -> Option<u32>,
) -> Vec<u32> {
    let keys: Vec<u64> = table.iter().enumerate().map(|(i, e)| current_order_key(e, current(i))).collect();
    let mut order = Vec::with_capacity(keys.len());
    window_order(&keys, window, &mut order);
    order
}

/// The emission order of a window of `window` entries over a stream whose `i`-th entry has the
/// order key `keys[i]` (unique per stream, as `{key, id}` is within a tile): `out` receives the
/// stream's indices in the order the window emits them. `window <= 1` is the identity.
pub fn window_order(keys: &[u64], window: usize, out: &mut Vec<u32>) {
    out.clear();
    if window <= 1 {
        out.extend(0..keys.len() as u32);
        return;
    }
    let mut held: BinaryHeap<Reverse<(u64, u32)>> = BinaryHeap::with_capacity(window);
    for (i, &k) in keys.iter().enumerate() {
        held.push(Reverse((k, i as u32)));
        if held.len() == window {
            out.extend(held.pop().map(|Reverse((_, j))| j));
        }
    }
    while let Some(Reverse((_, j))) = held.pop() {
        out.push(j);
    }
}

/// The smallest window whose emission order of `keys` (unique) is sorted: one more than the
/// largest `position - rank` of an entry (how many places later than its sorted place the stream
/// holds it). At step `t` the window has seen the stream's first `t + W` entries and must emit
/// the entry of rank `t`, so the output is sorted exactly when no entry is more than `W - 1`
/// places late. `sorted` is scratch. 1 for a sorted or empty stream.
pub fn window_for_sorted(keys: &[u64], sorted: &mut Vec<(u64, u32)>) -> usize {
    sorted.clear();
    sorted.extend(keys.iter().enumerate().map(|(pos, &k)| (k, pos as u32)));
    sorted.sort_unstable();
    let late = sorted.iter().enumerate().map(|(rank, &(_, pos))| (pos as usize).saturating_sub(rank));
    late.max().unwrap_or(0) + 1
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn order(keys: &[u64], w: usize) -> Vec<u32> {
        let mut out = Vec::new();
        window_order(keys, w, &mut out);
        out
    }

    #[test]
    fn one_entry_is_no_window() {
        assert_eq!(order(&[5, 1, 4, 2], 1), vec![0, 1, 2, 3]);
        assert_eq!(order(&[5, 1, 4, 2], 0), vec![0, 1, 2, 3]);
    }

    #[test]
    fn a_window_of_two_swaps_neighbours() {
        // Enters 5, 1: emits 1; enters 4: emits 4; enters 2: emits 2; drains 5.
        assert_eq!(order(&[5, 1, 4, 2], 2), vec![1, 2, 3, 0]);
    }

    #[test]
    fn an_entry_late_by_less_than_the_window_is_put_in_place() {
        // 0 is 3 places late: a window of 4 emits it first, a window of 3 cannot.
        assert_eq!(order(&[10, 20, 30, 0, 40], 4), vec![3, 0, 1, 2, 4]);
        assert_eq!(order(&[10, 20, 30, 0, 40], 3), vec![0, 3, 1, 2, 4]);
    }

    #[test]
    fn checks_the_size() {
        assert!(check_window(0).unwrap_err().contains("at least 1"));
        assert!(check_window(MAX_WINDOW + 1).unwrap_err().contains("above"));
        assert!(check_window(1).is_ok() && check_window(MAX_WINDOW).is_ok());
    }

    #[test]
    fn the_window_for_sorted_is_the_lateness_plus_one() {
        let mut scratch = Vec::new();
        assert_eq!(window_for_sorted(&[], &mut scratch), 1);
        assert_eq!(window_for_sorted(&[1, 2, 3], &mut scratch), 1);
        // 0 is 3 places late; 40 is early (no window needed for it).
        assert_eq!(window_for_sorted(&[10, 20, 30, 0, 40], &mut scratch), 4);
        assert_eq!(window_for_sorted(&[40, 10, 20, 30], &mut scratch), 2);
    }

    proptest! {
        #[test]
        fn the_window_for_sorted_is_the_smallest_that_sorts(
            keys in proptest::collection::hash_set(any::<u32>(), 0..200),
        ) {
            let keys: Vec<u64> = keys.into_iter().map(u64::from).collect();
            let w = window_for_sorted(&keys, &mut Vec::new());
            let sorts = |w: usize| order(&keys, w).windows(2).all(|p| keys[p[0] as usize] < keys[p[1] as usize]);
            prop_assert!(sorts(w), "window {w} does not sort");
            prop_assert!(w == 1 || !sorts(w - 1), "window {} already sorts", w - 1);
        }

        #[test]
        fn emits_a_permutation_that_sorts_within_reach(
            mut keys in proptest::collection::vec(any::<u32>(), 0..300),
            w in 1usize..64,
        ) {
            keys.sort_unstable();
            keys.dedup();
            // Displace the sorted stream: one entry in every `w` moves `w - 1` places early, so
            // none is more than one place late.
            let sorted: Vec<u64> = keys.iter().map(|&k| k as u64).collect();
            let mut stream = sorted.clone();
            for i in (1..stream.len()).step_by(w.max(2)) {
                let j = i.saturating_sub(w - 1);
                let e = stream.remove(i);
                stream.insert(j, e);
            }
            let out = order(&stream, w);
            let mut seen = out.clone();
            seen.sort_unstable();
            prop_assert_eq!(seen, (0..stream.len() as u32).collect::<Vec<_>>());
            let emitted: Vec<u64> = out.iter().map(|&i| stream[i as usize]).collect();
            prop_assert_eq!(&emitted, &sorted);
            // A window as long as the stream sorts any order.
            let mut rev = sorted.clone();
            rev.reverse();
            let full: Vec<u64> = order(&rev, rev.len().max(1)).iter().map(|&i| rev[i as usize]).collect();
            prop_assert_eq!(full, sorted);
        }
    }
}
