//! The Merge Sort Unit+ (MSU+): a two-way merge of sorted streams that can drop invalid entries.
//!
//! Semantics (shared by every merge in the model, so hardware and model have one definition):
//! - the output is the merge of `a` and `b` by THE ORDER `(key, id)`;
//! - on equal `(key, id)` (not expected for distinct ids, but defined) `a`'s entry goes first;
//! - with `drop_invalid`, entries whose valid bit is 0 are consumed from either input and not
//!   emitted (the merge does not stop at them); an invalid head is consumed **before** it is
//!   compared, so it never decides which input goes next. On sorted inputs this makes no
//!   difference; on inputs that are not sorted (a reused table after a DPS pass may be locally
//!   out of order next to an invalid entry) it is the hardware's rule ([`MergeStream`], the
//!   MSU+ RTL), and [`merge2`] follows it;
//! - the output is sorted whenever both inputs are; the merge never reorders entries of one
//!   input relative to each other.

use super::entry::SortEntry;

/// What one [`merge2_into`] consumed and produced.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MergeStats {
    /// Entries consumed from `a`.
    pub in_a: usize,
    /// Entries consumed from `b`.
    pub in_b: usize,
    /// Entries emitted.
    pub out: usize,
    /// Entries dropped because their valid bit was 0 (only with `drop_invalid`).
    pub dropped_invalid: usize,
    /// Boundary inversions of the reused stream `a`: emitted `a` entries that precede the
    /// previous emitted `a` entry in THE ORDER (0 when `a` is sorted). One comparator on the
    /// MSU+'s `a` output register counts them at no extra traffic: the disorder a DPS pass left.
    pub a_inversions: usize,
}

/// MSU+ merge of two sorted streams into a new vector (see the module docs).
pub fn merge2(a: &[SortEntry], b: &[SortEntry], drop_invalid: bool) -> Vec<SortEntry> {
    let mut out = Vec::with_capacity(a.len() + b.len());
    merge2_into(a, b, drop_invalid, &mut out);
    out
}

/// MSU+ merge appending to `out` (which is not cleared), for buffer reuse.
pub fn merge2_into(
    a: &[SortEntry],
    b: &[SortEntry],
    drop_invalid: bool,
    out: &mut Vec<SortEntry>,
) -> MergeStats {
    let start = out.len();
    out.reserve(a.len() + b.len());
    let (mut i, mut j) = (0, 0);
    let keep = |e: &SortEntry| !drop_invalid || e.valid;
    let mut last_a: Option<SortEntry> = None;
    let mut a_inversions = 0;
    let mut count_a = |e: &SortEntry| {
        if last_a.is_some_and(|l| e.precedes(&l)) {
            a_inversions += 1;
        }
        last_a = Some(*e);
    };
    while i < a.len() && j < b.len() {
        // Invalid heads are consumed first (as the MSU+ does), never compared.
        if drop_invalid && !(a[i].valid && b[j].valid) {
            i += !a[i].valid as usize;
            j += !b[j].valid as usize;
            continue;
        }
        // Take `a` unless `b` strictly precedes it: ties go to `a`.
        let e = if b[j].precedes(&a[i]) {
            j += 1;
            b[j - 1]
        } else {
            i += 1;
            if keep(&a[i - 1]) {
                count_a(&a[i - 1]);
            }
            a[i - 1]
        };
        if keep(&e) {
            out.push(e);
        }
    }
    for e in a[i..].iter().filter(|e| keep(e)) {
        count_a(e);
    }
    if drop_invalid {
        out.extend(a[i..].iter().chain(&b[j..]).filter(|e| e.valid));
    } else {
        out.extend_from_slice(&a[i..]);
        out.extend_from_slice(&b[j..]);
    }
    let emitted = out.len() - start;
    MergeStats {
        in_a: a.len(),
        in_b: b.len(),
        out: emitted,
        dropped_invalid: a.len() + b.len() - emitted,
        a_inversions,
    }
}

/// One cycle of [`MergeStream`]: which input heads were popped and what was emitted.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MergeStep {
    /// The head of `a` was consumed this cycle.
    pub pop_a: bool,
    /// The head of `b` was consumed this cycle.
    pub pop_b: bool,
    /// The entry emitted this cycle, if any.
    pub out: Option<SortEntry>,
}

/// A cycle-level reference of the MSU+ fed at full rate (both input heads always available until
/// their stream ends). Each cycle it looks at the two heads and:
/// 1. with `drop_invalid`, pops every head whose valid bit is 0 and emits nothing (a bubble);
/// 2. otherwise, if both streams have a head, emits and pops the one first in THE ORDER (`a` on
///    ties);
/// 3. otherwise emits and pops the head of the stream that remains.
///
/// It yields `None` once both streams are exhausted. Its output sequence equals [`merge2`]; its
/// cycle count is `out + (cycles that only dropped)`. This is one schedule an RTL MSU+ may follow
/// (cycle-exact comparison only applies to an RTL built on it); the output stream is the contract.
#[derive(Clone, Debug)]
pub struct MergeStream<'a> {
    a: &'a [SortEntry],
    b: &'a [SortEntry],
    drop_invalid: bool,
    cycles: usize,
}

impl<'a> MergeStream<'a> {
    /// A merge of `a` and `b` starting at cycle 0.
    pub fn new(a: &'a [SortEntry], b: &'a [SortEntry], drop_invalid: bool) -> Self {
        MergeStream { a, b, drop_invalid, cycles: 0 }
    }

    /// Cycles stepped so far.
    pub fn cycles(&self) -> usize {
        self.cycles
    }
}

impl Iterator for MergeStream<'_> {
    type Item = MergeStep;

    fn next(&mut self) -> Option<MergeStep> {
        let (ha, hb) = (self.a.first().copied(), self.b.first().copied());
        if ha.is_none() && hb.is_none() {
            return None;
        }
        self.cycles += 1;
        let drop_a = self.drop_invalid && ha.is_some_and(|e| !e.valid);
        let drop_b = self.drop_invalid && hb.is_some_and(|e| !e.valid);
        let step = if drop_a || drop_b {
            MergeStep { pop_a: drop_a, pop_b: drop_b, out: None }
        } else {
            match (ha, hb) {
                (Some(x), Some(y)) if y.precedes(&x) => MergeStep { pop_a: false, pop_b: true, out: Some(y) },
                (Some(x), _) => MergeStep { pop_a: true, pop_b: false, out: Some(x) },
                (None, y) => MergeStep { pop_a: false, pop_b: true, out: y },
            }
        };
        if step.pop_a {
            self.a = &self.a[1..];
        }
        if step.pop_b {
            self.b = &self.b[1..];
        }
        Some(step)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn e(key: u32, id: u32, valid: bool) -> SortEntry {
        SortEntry { key, id, valid }
    }

    #[test]
    fn ties_take_a_first() {
        let a = [e(1, 1, true), e(2, 5, false)];
        let b = [e(1, 1, false), e(2, 5, true)];
        let out = merge2(&a, &b, false);
        assert_eq!(out, vec![e(1, 1, true), e(1, 1, false), e(2, 5, false), e(2, 5, true)]);
    }

    #[test]
    fn drop_invalid_consumes_without_emitting() {
        let a = [e(1, 0, false), e(3, 0, true), e(9, 0, false)];
        let b = [e(2, 1, true), e(4, 1, false), e(5, 1, true)];
        let mut out = vec![e(0, 7, true)];
        let s = merge2_into(&a, &b, true, &mut out);
        assert_eq!(out, vec![e(0, 7, true), e(2, 1, true), e(3, 0, true), e(5, 1, true)]);
        assert_eq!(s, MergeStats { in_a: 3, in_b: 3, out: 3, dropped_invalid: 3, a_inversions: 0 });
        assert_eq!(merge2(&a, &b, false).len(), 6);
    }

    #[test]
    fn counts_boundary_inversions_of_the_reused_stream() {
        // `a` is out of order at 7 -> 4 (and 4 -> 2 across an invalid entry); `b` never counts.
        let a = [e(1, 0, true), e(7, 0, true), e(4, 0, true), e(9, 0, false), e(2, 1, true)];
        let b = [e(3, 2, true), e(0, 3, true)];
        let mut out = Vec::new();
        let s = merge2_into(&a, &b, true, &mut out);
        assert_eq!(s.a_inversions, 2);
        let sorted = [e(1, 0, true), e(4, 0, true)];
        assert_eq!(merge2_into(&sorted, &b, true, &mut out).a_inversions, 0);
    }

    #[test]
    fn stream_matches_merge2_and_counts_cycles() {
        let a = [e(1, 0, false), e(3, 0, true), e(9, 0, false), e(10, 0, true)];
        let b = [e(2, 1, true), e(4, 1, false), e(5, 1, true)];
        for drop in [false, true] {
            let mut s = MergeStream::new(&a, &b, drop);
            let steps: Vec<MergeStep> = s.by_ref().collect();
            let out: Vec<SortEntry> = steps.iter().filter_map(|st| st.out).collect();
            assert_eq!(out, merge2(&a, &b, drop));
            assert!(steps.iter().all(|st| st.pop_a || st.pop_b));
            assert_eq!(steps.iter().filter(|st| st.pop_a).count(), a.len());
            assert_eq!(steps.iter().filter(|st| st.pop_b).count(), b.len());
            assert_eq!(s.cycles(), steps.len());
        }
        // Without dropping, one cycle per entry.
        assert_eq!(MergeStream::new(&a, &b, false).count(), 7);
        // With dropping: 4 emits + 3 cycles that only drop (the invalid heads never coincide).
        assert_eq!(MergeStream::new(&a, &b, true).count(), 4 + 3);
        // Invalid heads on both sides are dropped in the same cycle.
        let a = [e(1, 0, false), e(3, 0, true)];
        let b = [e(2, 1, false), e(5, 1, true)];
        let steps: Vec<MergeStep> = MergeStream::new(&a, &b, true).collect();
        assert_eq!(steps[0], MergeStep { pop_a: true, pop_b: true, out: None });
        assert_eq!(steps.len(), 3);
    }

    #[test]
    fn an_invalid_head_never_decides_the_order_of_unsorted_inputs() {
        // `a` is out of order next to its invalid head: dropping it first lets 1 compete.
        let a = [e(5, 0, false), e(1, 0, true)];
        let b = [e(3, 1, true)];
        assert_eq!(merge2(&a, &b, true), vec![e(1, 0, true), e(3, 1, true)]);
        // Without dropping the invalid head competes like any entry.
        assert_eq!(merge2(&a, &b, false), vec![e(3, 1, true), e(5, 0, false), e(1, 0, true)]);
    }

    proptest::proptest! {
        /// The merge and the cycle-level stream emit the same entries on any inputs, sorted
        /// or not (the RTL is checked against the stream's schedule and the merge's output).
        #[test]
        fn merge2_equals_the_stream_on_any_input(
            a in proptest::collection::vec((0u32..6, 0u32..4, proptest::bool::ANY), 0..12),
            b in proptest::collection::vec((0u32..6, 0u32..4, proptest::bool::ANY), 0..12),
            drop in proptest::bool::ANY,
        ) {
            let a: Vec<SortEntry> = a.into_iter().map(|(k, i, v)| e(k, i, v)).collect();
            let b: Vec<SortEntry> = b.into_iter().map(|(k, i, v)| e(k, i, v)).collect();
            let stream: Vec<SortEntry> = MergeStream::new(&a, &b, drop).filter_map(|st| st.out).collect();
            proptest::prop_assert_eq!(stream, merge2(&a, &b, drop));
        }
    }
}
