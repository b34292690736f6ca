//! Comparator networks as data: what the BSU generator instantiates, layer by layer.
//!
//! A comparator `(i, j)` always has `i < j` and puts the entry that comes first in THE ORDER
//! (`(key, id)`, see [`crate::sort::entry`]) on wire `i` and the other on wire `j`; it swaps only
//! when `v[j]` strictly precedes `v[i]`. There is no direction flag: every network here sorts
//! ascending with min-at-the-lower-index comparators (for the bitonic sorter that is the
//! "no direction flips" form, where the first layer of each merge stage compares mirrored wires).
//! Each layer's comparators touch disjoint wires, so one layer is one pipeline stage.

use super::entry::SortEntry;

/// A comparator network on `n` wires: `layers[d]` holds the comparators of stage `d`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Network {
    /// Number of wires (inputs = outputs).
    pub n: usize,
    /// Stages in order; each comparator `(i, j)` has `i < j < n` and puts the smaller at `i`.
    pub layers: Vec<Vec<(usize, usize)>>,
}

impl Network {
    /// Batcher's bitonic sorter on `n = 2^m` wires, as in the paper's BSU: `m (m + 1) / 2` layers
    /// of `n / 2` comparators (n = 16: 10 layers, 80 comparators). Built with the XOR-partner
    /// construction: merge stage of block size `k` starts with the mirror layer
    /// `(i, i XOR (k - 1))` then half-cleaners `(i, i XOR s)` for `s = k/4, ..., 1`.
    ///
    /// # Panics
    /// When `n` is not a power of two.
    pub fn bitonic(n: usize) -> Network {
        assert!(n.is_power_of_two(), "bitonic network needs a power-of-two width, got {n}");
        let mut layers = Vec::new();
        let mut k = 2;
        while k <= n {
            layers.push(xor_layer(n, k - 1));
            let mut s = k / 4;
            while s >= 1 {
                layers.push(xor_layer(n, s));
                s /= 2;
            }
            k *= 2;
        }
        Network { n, layers }
    }

    /// Batcher's odd-even merge sort on `n` wires (any `n >= 1`; n = 16: 10 layers, 63
    /// comparators). One layer per `(p, k)` step of the standard iterative formulation.
    pub fn odd_even_merge(n: usize) -> Network {
        let mut layers = Vec::new();
        let mut p = 1;
        while p < n {
            let mut k = p;
            while k >= 1 {
                let mut layer = Vec::new();
                let mut j = k % p;
                while j + k < n {
                    for i in 0..k.min(n - j - k) {
                        if (i + j) / (2 * p) == (i + j + k) / (2 * p) {
                            layer.push((i + j, i + j + k));
                        }
                    }
                    j += 2 * k;
                }
                if !layer.is_empty() {
                    layers.push(layer);
                }
                k /= 2;
            }
            p *= 2;
        }
        Network { n, layers }
    }

    /// The best known 16-input network: 60 comparators in 10 layers (M. W. Green, 1969, as in
    /// Knuth TAOCP vol. 3 5.3.4): the 32 comparators of a 4-dimensional hypercube in 4 layers,
    /// then 28 more in 6 layers. Verified by the 0-1 principle in the tests.
    pub fn best_16() -> Network {
        let mut layers: Vec<Vec<(usize, usize)>> = Vec::new();
        for s in [1, 2, 4, 8] {
            layers.push(xor_layer(16, s));
        }
        let tail: [&[(usize, usize)]; 6] = [
            &[(5, 10), (6, 9), (3, 12), (13, 14), (7, 11), (1, 2), (4, 8)],
            &[(1, 4), (7, 13), (2, 8), (11, 14), (5, 6), (9, 10)],
            &[(2, 4), (11, 13), (3, 8), (7, 12)],
            &[(6, 8), (10, 12), (3, 5), (7, 9)],
            &[(3, 4), (5, 6), (7, 8), (9, 10), (11, 12)],
            &[(6, 7), (8, 9)],
        ];
        layers.extend(tail.iter().map(|l| l.to_vec()));
        Network { n: 16, layers }
    }

    /// Total number of comparators.
    pub fn comparator_count(&self) -> usize {
        self.layers.iter().map(Vec::len).sum()
    }

    /// Number of layers (pipeline stages).
    pub fn depth(&self) -> usize {
        self.layers.len()
    }

    /// True when every comparator has `i < j < n` and no wire appears twice in a layer.
    pub fn is_well_formed(&self) -> bool {
        self.layers.iter().all(|layer| {
            let mut used = vec![false; self.n];
            layer.iter().all(|&(i, j)| {
                let ok = i < j && j < self.n && !used[i] && !used[j];
                if ok {
                    used[i] = true;
                    used[j] = true;
                }
                ok
            })
        })
    }

    /// Applies the network in place, layer by layer, with THE ORDER `(key, id)`.
    ///
    /// # Panics
    /// When `v.len() != self.n`.
    pub fn apply(&self, v: &mut [SortEntry]) {
        assert_eq!(v.len(), self.n, "network width {} applied to {} entries", self.n, v.len());
        for layer in &self.layers {
            for &(i, j) in layer {
                if v[j].precedes(&v[i]) {
                    v.swap(i, j);
                }
            }
        }
    }

    /// Applies the network to a 0/1 vector packed in the low `n` bits of `x` (bit `w` is wire
    /// `w`): a comparator puts `AND` on wire `i` and `OR` on wire `j`.
    pub fn apply_bits(&self, mut x: u64) -> u64 {
        for layer in &self.layers {
            for &(i, j) in layer {
                let (a, b) = ((x >> i) & 1, (x >> j) & 1);
                x = (x & !(1 << i) & !(1 << j)) | ((a & b) << i) | ((a | b) << j);
            }
        }
        x
    }

    /// The 0-1 principle: true when the network sorts all `2^n` 0/1 inputs, which proves it
    /// sorts every input. Exhaustive, so only for `n <= 24`.
    ///
    /// # Panics
    /// When `n > 24`.
    pub fn sorts_all_zero_one_inputs(&self) -> bool {
        assert!(self.n <= 24, "exhaustive 0-1 check limited to 24 wires, got {}", self.n);
        (0u64..1 << self.n).all(|x| {
            let y = self.apply_bits(x);
            // Sorted ascending: all zeros on low wires, then ones, i.e. y = ones on the top wires.
            let ones = y.count_ones();
            y == ((1u64 << self.n) - 1) & !((1u64 << (self.n as u32 - ones)) - 1)
        })
    }
}

/// The layer `(i, i XOR mask)` over all `i` with `i < i XOR mask < n`.
fn xor_layer(n: usize, mask: usize) -> Vec<(usize, usize)> {
    (0..n).filter_map(|i| (i ^ mask > i && i ^ mask < n).then_some((i, i ^ mask))).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_and_depths_at_16() {
        let b = Network::bitonic(16);
        assert_eq!((b.comparator_count(), b.depth()), (80, 10));
        assert!(b.layers.iter().all(|l| l.len() == 8));
        let o = Network::odd_even_merge(16);
        assert_eq!((o.comparator_count(), o.depth()), (63, 10));
        let g = Network::best_16();
        assert_eq!((g.comparator_count(), g.depth()), (60, 10));
        assert!(g.layers[..4].iter().all(|l| l.len() == 8));
    }

    #[test]
    fn bitonic_counts_follow_formula() {
        for m in 0..=6u32 {
            let n = 1usize << m;
            let b = Network::bitonic(n);
            assert_eq!(b.depth(), (m * (m + 1) / 2) as usize);
            assert_eq!(b.comparator_count(), n / 2 * (m * (m + 1) / 2) as usize);
            assert!(b.is_well_formed());
        }
    }

    #[test]
    fn all_networks_are_well_formed_and_sort_zero_one() {
        for n in [1, 2, 4, 8, 16] {
            assert!(Network::bitonic(n).sorts_all_zero_one_inputs(), "bitonic {n}");
        }
        for n in 1..=16 {
            let o = Network::odd_even_merge(n);
            assert!(o.is_well_formed(), "odd-even {n}");
            assert!(o.sorts_all_zero_one_inputs(), "odd-even {n}");
        }
        let g = Network::best_16();
        assert!(g.is_well_formed());
        assert!(g.sorts_all_zero_one_inputs());
    }

    #[test]
    fn zero_one_check_catches_a_missing_comparator() {
        // Removing any single comparator of the 60-comparator network breaks it.
        let g = Network::best_16();
        for d in 0..g.depth() {
            for c in 0..g.layers[d].len() {
                let mut broken = g.clone();
                broken.layers[d].remove(c);
                assert!(!broken.sorts_all_zero_one_inputs(), "layer {d} comparator {c} is redundant?");
            }
        }
    }

    #[test]
    fn ill_formed_layers_are_detected() {
        let bad = Network { n: 4, layers: vec![vec![(0, 1), (1, 2)]] };
        assert!(!bad.is_well_formed());
        let reversed = Network { n: 4, layers: vec![vec![(2, 1)]] };
        assert!(!reversed.is_well_formed());
        let out_of_range = Network { n: 4, layers: vec![vec![(0, 4)]] };
        assert!(!out_of_range.is_well_formed());
    }

    #[test]
    fn apply_swaps_only_on_strict_precedence() {
        let net = Network { n: 2, layers: vec![vec![(0, 1)]] };
        let mut v = [SortEntry { key: 5, id: 1, valid: false }, SortEntry { key: 5, id: 1, valid: true }];
        net.apply(&mut v);
        assert!(!v[0].valid && v[1].valid, "equal (key, id) must not swap");
        let mut v = [SortEntry::new(5, 2), SortEntry::new(5, 1)];
        net.apply(&mut v);
        assert_eq!((v[0].id, v[1].id), (1, 2));
    }
}
