//! Conventional sort (BSU vectors + in-chunk merges + global merges) against a plain reference
//! sort by (key, id), for every network and several chunk sizes, plus its work counters.

use neo_golden::sort::{full_sort, Network, SortConfig, SortEntry, SortFormat, Sorter};
use neo_golden::synthetic::rng::HashRng as Rng;
use proptest::prelude::*;

fn reference(input: &[SortEntry]) -> Vec<SortEntry> {
    let mut v = input.to_vec();
    v.sort_unstable_by_key(|e| (e.key, e.id));
    v
}

/// `len` entries with unique shuffled ids, keys from `key`, random valid bits.
fn entries(rng: &mut Rng, len: usize, mut key: impl FnMut(&mut Rng, usize) -> u32) -> Vec<SortEntry> {
    let mut ids: Vec<u32> = (0..len as u32).collect();
    for i in (1..len).rev() {
        ids.swap(i, rng.below(i as u64 + 1) as usize);
    }
    (0..len).map(|i| SortEntry { key: key(rng, i), id: ids[i], valid: rng.below(4) != 0 }).collect()
}

fn configs() -> Vec<SortConfig> {
    let f = SortFormat::ARTIFACT;
    let mut v = Vec::new();
    for net in [Network::bitonic(16), Network::odd_even_merge(16), Network::best_16()] {
        for chunk in [16, 64, 256] {
            v.push(SortConfig::new(f, chunk, net.clone()).unwrap());
        }
    }
    v
}

const LENGTHS: [usize; 10] = [0, 1, 15, 16, 17, 255, 256, 257, 1000, 5000];

#[test]
fn random_inputs_match_reference_for_all_networks_and_chunks() {
    let mut rng = Rng::new(1, 0, 0);
    for cfg in configs() {
        let mut sorter = Sorter::new(cfg.clone());
        let mut out = Vec::new();
        for len in LENGTHS {
            let input = entries(&mut rng, len, |r, _| r.below(1 << 16) as u32);
            sorter.full_sort(&input, &mut out);
            assert_eq!(out, reference(&input), "len {len} cfg {cfg:?}");
        }
    }
}

#[test]
fn special_inputs_match_reference() {
    let mut rng = Rng::new(2, 0, 0);
    let f = SortFormat::ARTIFACT;
    type KeyFn = fn(&mut Rng, usize) -> u32;
    let cases: [(&str, KeyFn); 6] = [
        ("all equal keys", |_, _| 777),
        ("reversed", |_, i| 60_000 - i as u32),
        ("sorted", |_, i| i as u32),
        ("min and max keys", |r, _| if r.below(2) == 0 { 0 } else { 0xFFFF }),
        ("few distinct keys", |r, _| r.below(3) as u32),
        ("max key only", |_, _| 0xFFFF),
    ];
    for cfg in configs() {
        for (name, key) in cases {
            for len in LENGTHS {
                let mut input = entries(&mut rng, len, key);
                if name == "sorted" {
                    input = reference(&input);
                }
                let (out, _) = full_sort(&input, &cfg);
                assert_eq!(out, reference(&input), "{name} len {len} cfg {cfg:?}");
            }
        }
        // The largest real id next to padding: it must survive the padded BSU vector.
        let input: Vec<SortEntry> =
            (0..17u32).map(|i| SortEntry::new(0xFFFF, f.id_max() - 1 - i)).rev().collect();
        assert_eq!(full_sort(&input, &cfg).0, reference(&input));
    }
}

#[test]
fn all_equal_keys_come_out_in_id_order() {
    let mut rng = Rng::new(3, 0, 0);
    let input = entries(&mut rng, 1000, |_, _| 42);
    let (out, _) = full_sort(&input, &SortConfig::artifact());
    assert!(out.iter().enumerate().all(|(i, e)| e.id == i as u32 && e.key == 42));
}

#[test]
fn networks_agree_bit_exactly() {
    let mut rng = Rng::new(4, 0, 0);
    let input = entries(&mut rng, 3000, |r, _| r.below(50) as u32);
    let outs: Vec<_> = configs().iter().map(|c| full_sort(&input, c).0).collect();
    assert!(outs.windows(2).all(|w| w[0] == w[1]));
}

#[test]
fn work_counters_follow_the_chunk_structure() {
    let mut rng = Rng::new(5, 0, 0);
    for cfg in configs() {
        let (c, n) = (cfg.chunk(), cfg.bsu_width());
        for len in LENGTHS {
            let input = entries(&mut rng, len, |r, _| r.below(1000) as u32);
            let (_, w) = full_sort(&input, &cfg);
            let chunks = len.div_ceil(c);
            let chunk_lens: Vec<usize> = (0..chunks).map(|k| c.min(len - k * c)).collect();
            let vectors: Vec<usize> = chunk_lens.iter().map(|l| l.div_ceil(n)).collect();
            let ceil_log2 =
                |x: usize| if x <= 1 { 0 } else { (usize::BITS - (x - 1).leading_zeros()) as usize };
            assert_eq!(w.entries, len);
            assert_eq!(w.chunk.chunks, chunks);
            assert_eq!(w.chunk.entries, len);
            assert_eq!(w.chunk.bsu_vectors, vectors.iter().sum::<usize>());
            assert_eq!(w.chunk.padding_entries, vectors.iter().sum::<usize>() * n - len);
            assert_eq!(w.chunk.merge_passes, vectors.iter().map(|&v| ceil_log2(v)).sum::<usize>());
            // Each in-chunk pass streams every entry of its chunk once.
            let chunk_stream: usize = chunk_lens.iter().zip(&vectors).map(|(l, &v)| l * ceil_log2(v)).sum();
            assert_eq!(w.chunk.entries_merged + w.chunk.entries_copied, chunk_stream);
            assert_eq!(w.global_merge_passes(), ceil_log2(chunks), "len {len} chunk {c}");
            assert!(w.global_passes.iter().all(|p| p.entries() == len));
            let mut runs = chunks;
            for p in &w.global_passes {
                assert_eq!(p.runs_in, runs);
                assert_eq!(p.merges, runs / 2);
                runs = runs.div_ceil(2);
            }
            assert_eq!(w.dram_entries_read(), len * (1 + ceil_log2(chunks)));
        }
    }
}

#[test]
fn sorter_reuse_gives_the_same_result_as_fresh() {
    let mut rng = Rng::new(6, 0, 0);
    let cfg = SortConfig::artifact();
    let mut sorter = Sorter::new(cfg.clone());
    let mut out = Vec::new();
    for len in [5000, 3, 700, 0, 256] {
        let input = entries(&mut rng, len, |r, _| r.below(1 << 16) as u32);
        let w = sorter.full_sort(&input, &mut out);
        let (fresh, fresh_w) = full_sort(&input, &cfg);
        assert_eq!(out, fresh);
        assert_eq!(w, fresh_w);
    }
}

proptest! {
    #[test]
    fn full_sort_is_the_reference_sort(
        keys in proptest::collection::vec(0u32..64, 0..700),
        valid in any::<u64>(),
        chunk_pow in 0usize..4,
        net in 0usize..3,
    ) {
        let network = [Network::bitonic(16), Network::odd_even_merge(16), Network::best_16()][net].clone();
        let cfg = SortConfig::new(SortFormat::ARTIFACT, 16 << chunk_pow, network).unwrap();
        let input: Vec<SortEntry> = keys
            .iter()
            .enumerate()
            .map(|(i, &k)| SortEntry { key: k, id: (i as u32 * 7919) % 65_521, valid: (valid >> (i % 64)) & 1 == 1 })
            .collect();
        let (out, work) = full_sort(&input, &cfg);
        prop_assert_eq!(out, reference(&input));
        prop_assert_eq!(work.entries, input.len());
    }
}
