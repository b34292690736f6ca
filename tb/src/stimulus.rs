//! Stimulus generators: random and directed entry vectors and sorted streams.

use crate::rng::Rng;
use neo_golden::sort::{SortEntry, SortFormat};

/// How keys (and ids) are drawn, to cover both the full range and many ties.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum KeyDist {
    /// Uniform over the whole key field; ids uniform over the whole id field (reserved one
    /// included: the units must not treat it specially).
    Full,
    /// Keys in `0..8` (many equal keys) with distinct-ish ids in `0..64`.
    Ties,
    /// Keys and ids from `{0, 1, max-1, max}` (extremes).
    Extremes,
}

/// A random entry; `valid_pct` is the probability of the valid bit.
pub fn random_entry(fmt: &SortFormat, rng: &mut Rng, dist: KeyDist, valid_pct: u32) -> SortEntry {
    let (kmax, imax) = (fmt.key_max() as u64, fmt.id_max() as u64);
    let (key, id) = match dist {
        KeyDist::Full => (rng.below(kmax + 1), rng.below(imax + 1)),
        KeyDist::Ties => (rng.below(8.min(kmax + 1)), rng.below(64.min(imax + 1))),
        KeyDist::Extremes => {
            let pick = |rng: &mut Rng, max: u64| *rng.pick(&[0, 1.min(max), max.saturating_sub(1), max]);
            (pick(rng, kmax), pick(rng, imax))
        }
    };
    SortEntry { key: key as u32, id: id as u32, valid: rng.percent(valid_pct) }
}

/// A random vector of `n` entries with a randomly chosen distribution and valid density.
pub fn random_vector(fmt: &SortFormat, rng: &mut Rng, n: usize) -> Vec<SortEntry> {
    let dist = *rng.pick(&[KeyDist::Full, KeyDist::Full, KeyDist::Ties, KeyDist::Extremes]);
    let valid_pct = *rng.pick(&[100, 90, 50, 10, 0]);
    (0..n).map(|_| random_entry(fmt, rng, dist, valid_pct)).collect()
}

/// The directed BSU cases on `n` lanes, by name: all keys equal with different ids, reversed,
/// already sorted, min/max keys, all invalid, one valid, equal (key, id) with different valid
/// bits.
pub fn directed_vectors(fmt: &SortFormat, n: usize) -> Vec<(&'static str, Vec<SortEntry>)> {
    let n32 = n as u32;
    let kmax = fmt.key_max();
    let imax = fmt.id_max();
    let mut cases = vec![
        (
            "equal keys, ids descending",
            (0..n32).map(|i| SortEntry::new(7.min(kmax), (n32 - 1 - i) % imax)).collect(),
        ),
        ("equal keys, ids ascending", (0..n32).map(|i| SortEntry::new(kmax, i % imax)).collect()),
        ("reversed", (0..n32).map(|i| SortEntry::new((n32 - 1 - i) % (kmax + 1), i % imax)).collect()),
        ("already sorted", (0..n32).map(|i| SortEntry::new(i % (kmax + 1), (3 * i) % imax)).collect()),
        (
            "min and max keys",
            (0..n32).map(|i| SortEntry::new(if i % 2 == 0 { kmax } else { 0 }, (i * 7) % imax)).collect(),
        ),
        (
            "max key and reserved id",
            (0..n32).map(|i| SortEntry { key: kmax, id: imax - (i % 2), valid: i % 2 == 1 }).collect(),
        ),
        (
            "all invalid",
            (0..n32).map(|i| SortEntry { key: (n32 - i) % (kmax + 1), id: i, valid: false }).collect(),
        ),
        (
            "one valid",
            (0..n32)
                .map(|i| SortEntry { key: (i * 5) % (kmax + 1), id: i % imax, valid: i == n32 / 2 })
                .collect(),
        ),
        (
            "equal (key, id), valid bits differ",
            (0..n32).map(|i| SortEntry { key: 3.min(kmax), id: 9 % imax, valid: i % 3 == 0 }).collect(),
        ),
        ("all zero", vec![SortEntry { key: 0, id: 0, valid: false }; n]),
    ];
    for (_, v) in &mut cases {
        for e in v.iter_mut() {
            e.key &= kmax;
            e.id &= imax;
        }
    }
    cases
}

/// Entry addresses the engine reaches: its AXI4 byte addresses (at most 32 bits in the benches)
/// over 8-byte entries, `2^29` by default.
pub fn entry_space(cfg: &neo_gen::EngineConfig) -> u64 {
    (1u64 << cfg.axi_addr_bits.min(32)) / neo_golden::engine::memory::ENTRY_BYTES
}

/// A sorted stream of `len` entries (THE ORDER), with valid bits at density `valid_pct`.
/// With `ties`, keys repeat a lot (ids distinguish them, and may collide with the other stream).
pub fn sorted_stream(
    fmt: &SortFormat,
    rng: &mut Rng,
    len: usize,
    valid_pct: u32,
    ties: bool,
) -> Vec<SortEntry> {
    let dist = if ties { KeyDist::Ties } else { KeyDist::Full };
    let mut v: Vec<SortEntry> = (0..len).map(|_| random_entry(fmt, rng, dist, valid_pct)).collect();
    v.sort_by_key(|e| e.order_key());
    v
}

/// A merge input: [`sorted_stream`] with real ids only (the format's largest id is the reserved
/// padding id, which no stream in memory holds).
pub fn merge_stream(
    fmt: &SortFormat,
    rng: &mut Rng,
    len: usize,
    valid_pct: u32,
    ties: bool,
) -> Vec<SortEntry> {
    let mut v = sorted_stream(fmt, rng, len, valid_pct, ties);
    v.iter_mut().for_each(|e| e.id = e.id.min(fmt.id_max() - 1));
    v
}

/// `n` entries of one tile: distinct real ids (never the reserved one), keys uniform or (with
/// `ties`) in `0..8`, valid bits at density `valid_pct`, in random order.
pub fn tile_entries(fmt: &SortFormat, rng: &mut Rng, n: usize, ties: bool, valid_pct: u32) -> Vec<SortEntry> {
    let cap = fmt.id_capacity();
    assert!(n as u64 <= cap, "{n} distinct ids do not fit the format");
    let base = rng.below(cap);
    let mut v: Vec<SortEntry> = (0..n as u64)
        .map(|i| {
            let key = if ties {
                rng.below(8.min(fmt.key_max() as u64 + 1))
            } else {
                rng.below(fmt.key_max() as u64 + 1)
            };
            SortEntry { key: key as u32, id: ((base + i) % cap) as u32, valid: rng.percent(valid_pct) }
        })
        .collect();
    rng.shuffle(&mut v);
    v
}

/// `v` sorted in THE ORDER, then disturbed by up to `swaps` random swaps of entries at most
/// `max_dist` positions apart, each entry moved at most once (so no entry ends up more than
/// `max_dist` from its place: a reused table whose depths changed a little).
pub fn nearly_sorted(mut v: Vec<SortEntry>, rng: &mut Rng, max_dist: usize, swaps: usize) -> Vec<SortEntry> {
    v.sort_by_key(|e| e.order_key());
    if v.len() < 2 || max_dist == 0 {
        return v;
    }
    let mut moved = vec![false; v.len()];
    for _ in 0..swaps {
        let i = rng.below(v.len() as u64) as usize;
        let j = (i + 1 + rng.below(max_dist as u64) as usize).min(v.len() - 1);
        if i != j && !moved[i] && !moved[j] {
            v.swap(i, j);
            moved[i] = true;
            moved[j] = true;
        }
    }
    v
}

/// The shape of a merge-stress pair (see [`starved_merge`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MergeShape {
    /// Every key of A below every key of B: A drains first while B waits (B's input FIFO fills
    /// and stays full), then B runs alone.
    ALow,
    /// Every key of B below every key of A (the reverse).
    BLow,
    /// Alternating runs of `n` entries: `n` of A, then `n` of B, then `n` of A, ... (with `n`
    /// longer than an input FIFO, each stream in turn starves while the other waits full).
    Runs(usize),
}

/// Two sorted streams of `la` and `lb` entries shaped by `shape` (distinct real ids, keys spread
/// over the key field, about `valid_pct` percent valid): the merge-stress stimulus of the FIFO
/// capacity class, where one input stream is held back for longer than any buffer holds while
/// the other one goes out.
///
/// # Panics
/// When the key or id field cannot hold `la + lb` distinct values.
pub fn starved_merge(
    fmt: &SortFormat,
    rng: &mut Rng,
    la: usize,
    lb: usize,
    shape: MergeShape,
    valid_pct: u32,
) -> (Vec<SortEntry>, Vec<SortEntry>) {
    let total = (la + lb) as u64;
    assert!(total < fmt.id_capacity() && total <= fmt.key_max() as u64, "{total} entries do not fit");
    // Position p (0..total) of the merged order takes key p * stride + a small random offset
    // (keys strictly increase along the merged order); ids are distinct.
    let stride = (fmt.key_max() as u64 + 1) / total.max(1);
    let base = rng.below(fmt.id_capacity() - total);
    let slot = |p: u64, rng: &mut Rng| SortEntry {
        key: (p * stride + rng.below(stride)) as u32,
        id: (base + p) as u32,
        valid: rng.percent(valid_pct),
    };
    // Which stream position p of the merged order belongs to.
    let (mut a, mut b) = (Vec::with_capacity(la), Vec::with_capacity(lb));
    for p in 0..total {
        let to_a = match shape {
            MergeShape::ALow => a.len() < la,
            MergeShape::BLow => b.len() == lb,
            MergeShape::Runs(n) => {
                let turn_a = (p as usize / n.max(1)).is_multiple_of(2);
                if a.len() == la {
                    false
                } else if b.len() == lb {
                    true
                } else {
                    turn_a
                }
            }
        };
        let e = slot(p, rng);
        if to_a {
            a.push(e);
        } else {
            b.push(e);
        }
    }
    (a, b)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fmt() -> SortFormat {
        neo_gen::EngineConfig::default().format()
    }

    #[test]
    fn starved_merges_have_the_shape_they_promise() {
        let f = fmt();
        let mut rng = Rng::new(3);
        let sorted = |v: &[SortEntry]| v.windows(2).all(|w| w[0].order_key() < w[1].order_key());
        let (a, b) = starved_merge(&f, &mut rng, 300, 5, MergeShape::ALow, 80);
        assert_eq!((a.len(), b.len()), (300, 5));
        assert!(sorted(&a) && sorted(&b));
        assert!(a.last().unwrap().key < b[0].key, "every A key below every B key");
        let (a, b) = starved_merge(&f, &mut rng, 17, 257, MergeShape::BLow, 80);
        assert!(b.last().unwrap().key < a[0].key, "every B key below every A key");
        let (a, b) = starved_merge(&f, &mut rng, 700, 650, MergeShape::Runs(300), 100);
        assert!(sorted(&a) && sorted(&b));
        // A holds positions 0..300 and 600..900 of the merged order: B's first key lies between
        // A's 300th and 301st.
        assert!(a[299].key < b[0].key && b[299].key < a[300].key && a[599].key < b[300].key);
        let (a, b) = starved_merge(&f, &mut rng, 0, 0, MergeShape::Runs(16), 50);
        assert!(a.is_empty() && b.is_empty());
    }

    #[test]
    fn generated_entries_fit_the_format() {
        let fmt = SortFormat::ARTIFACT;
        let mut rng = Rng::new(5);
        for _ in 0..200 {
            for e in random_vector(&fmt, &mut rng, 16) {
                assert!(fmt.try_pack(&e).is_some());
            }
        }
        for (name, v) in directed_vectors(&fmt, 16) {
            assert_eq!(v.len(), 16, "{name}");
            assert!(v.iter().all(|e| fmt.try_pack(e).is_some()), "{name}");
        }
        let s = sorted_stream(&fmt, &mut rng, 100, 50, true);
        let t = nearly_sorted(tile_entries(&fmt, &mut rng, 300, false, 100), &mut rng, 10, 100);
        let mut sorted = t.clone();
        sorted.sort_by_key(|e| e.order_key());
        for (i, e) in t.iter().enumerate() {
            let home = sorted.iter().position(|x| x == e).unwrap();
            assert!(home.abs_diff(i) <= 10, "entry moved {} places", home.abs_diff(i));
        }
        let ids: std::collections::HashSet<u32> = t.iter().map(|e| e.id).collect();
        assert_eq!(ids.len(), 300, "tile ids are distinct");
        assert!(s.windows(2).all(|w| w[0].order_key() <= w[1].order_key()));
    }
}
