//! The conventional sort as a Sorting Core performs it (paper Section 5.3):
//!
//! 1. split the input into chunks of `C` entries (default 256; the last may be shorter);
//! 2. per chunk, split it into BSU vectors of `n` entries (the network width, 16), pad the last
//!    partial vector with [`SortFormat::padding`] entries, sort each vector with the BSU network,
//!    and drop the padding again (it sorts last, so it is the vector's tail);
//! 3. per chunk, two-way MSU+ merge passes inside the chunk: runs of `n`, `2n`, ... until the
//!    chunk is one run;
//! 4. two-way merge passes across chunks: runs of `C`, `2C`, ... until one run remains.
//!
//! Every merge is [`merge2`](super::msu::merge2) with dropping disabled. A pass pairs runs left to right; an odd run
//! out at the end is passed through unchanged (counted as copied: it is still read and
//! written). Chunk sorting happens in the on-chip buffer (the chunk is read from and written to
//! DRAM once); each global pass reads and writes every entry once.

use super::command::{conventional_sort_plan, SortMode};
use super::entry::{SortEntry, SortFormat};
use super::error::SortParamError;
use super::msu::merge2_into;
use super::network::Network;

/// Parameters of a Sorting Core: entry format (for padding), chunk size and BSU network.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SortConfig {
    format: SortFormat,
    chunk: usize,
    network: Network,
}

impl SortConfig {
    /// The paper's default chunk size.
    pub const DEFAULT_CHUNK: usize = 256;

    /// A checked configuration: the network must have `n >= 2` wires and the chunk must be `n`
    /// times a power of two (so in-chunk merge passes pair up to exactly one chunk).
    pub fn new(format: SortFormat, chunk: usize, network: Network) -> Result<Self, SortParamError> {
        let n = network.n;
        if n < 2 {
            return Err(SortParamError::BsuWidth(n));
        }
        if chunk < n || (chunk / n) * n != chunk || !(chunk / n).is_power_of_two() {
            return Err(SortParamError::Chunk { chunk, bsu: n });
        }
        Ok(SortConfig { format, chunk, network })
    }

    /// The paper's configuration: [`SortFormat::ARTIFACT`], chunks of 256, the 16-input bitonic
    /// BSU.
    pub fn artifact() -> Self {
        SortConfig { format: SortFormat::ARTIFACT, chunk: Self::DEFAULT_CHUNK, network: Network::bitonic(16) }
    }

    /// Entry format.
    pub fn format(&self) -> SortFormat {
        self.format
    }

    /// Chunk size `C`.
    pub fn chunk(&self) -> usize {
        self.chunk
    }

    /// BSU network.
    pub fn network(&self) -> &Network {
        &self.network
    }

    /// BSU width `n` (entries per BSU vector).
    pub fn bsu_width(&self) -> usize {
        self.network.n
    }
}

impl Default for SortConfig {
    fn default() -> Self {
        SortConfig::artifact()
    }
}

/// Two-way merge passes that turn `items` entries in sorted runs of `run` entries into one run:
/// `ceil(log2(ceil(items / run)))`, 0 when one run (or none) is enough. The one definition of
/// the pass count, for the in-chunk passes (`run` = BSU width) and the passes across chunks
/// (`run` = chunk size) alike.
///
/// # Panics
/// When `run` is 0.
pub fn merge_pass_count(items: u64, run: u64) -> u64 {
    assert!(run > 0, "merge_pass_count: run length 0");
    let runs = items.div_ceil(run);
    if runs <= 1 {
        0
    } else {
        u64::from(64 - (runs - 1).leading_zeros())
    }
}

/// Work of the on-chip chunk sorts (BSU vectors and in-chunk merge passes), summed over chunks.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ChunkWork {
    /// Chunks sorted.
    pub chunks: usize,
    /// Entries in those chunks (each read from DRAM and written back once).
    pub entries: usize,
    /// BSU vectors sorted (`ceil(len / n)` per chunk).
    pub bsu_vectors: usize,
    /// Padding entries added to partial BSU vectors.
    pub padding_entries: usize,
    /// In-chunk merge passes, summed over chunks (`ceil(log2(vectors))` per chunk).
    pub merge_passes: usize,
    /// Two-way merges performed in those passes.
    pub merges: usize,
    /// Entries streamed through a merge in those passes.
    pub entries_merged: usize,
    /// Entries passed through unmerged (odd run out) in those passes.
    pub entries_copied: usize,
}

impl ChunkWork {
    /// Adds `other` into `self`.
    pub fn add(&mut self, other: &ChunkWork) {
        self.chunks += other.chunks;
        self.entries += other.entries;
        self.bsu_vectors += other.bsu_vectors;
        self.padding_entries += other.padding_entries;
        self.merge_passes += other.merge_passes;
        self.merges += other.merges;
        self.entries_merged += other.entries_merged;
        self.entries_copied += other.entries_copied;
    }
}

/// One merge pass over a sequence of runs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PassWork {
    /// Runs before the pass.
    pub runs_in: usize,
    /// Two-way merges performed (`runs_in / 2`).
    pub merges: usize,
    /// Entries streamed through a merge.
    pub entries_merged: usize,
    /// Entries of the odd run out, passed through.
    pub entries_copied: usize,
}

impl PassWork {
    /// Entries read (= written) by the pass.
    pub fn entries(&self) -> usize {
        self.entries_merged + self.entries_copied
    }
}

/// Work counters of one conventional sort, for the cycle model.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct SortWork {
    /// Entries sorted.
    pub entries: usize,
    /// Chunk phase (BSU + in-chunk merges).
    pub chunk: ChunkWork,
    /// Merge passes across chunks, in order.
    pub global_passes: Vec<PassWork>,
}

impl SortWork {
    /// Number of merge passes across chunks (`ceil(log2(chunks))`).
    pub fn global_merge_passes(&self) -> usize {
        self.global_passes.len()
    }

    /// Entries read from DRAM: each chunk once, then every global pass.
    pub fn dram_entries_read(&self) -> usize {
        self.chunk.entries + self.global_passes.iter().map(PassWork::entries).sum::<usize>()
    }

    /// Entries written to DRAM (equal to those read: nothing is dropped).
    pub fn dram_entries_written(&self) -> usize {
        self.dram_entries_read()
    }
}

/// A Sorting Core model with reusable scratch buffers (no allocation per call once warm).
#[derive(Clone, Debug)]
pub struct Sorter {
    cfg: SortConfig,
    vector: Vec<SortEntry>,
    scratch: Vec<SortEntry>,
}

impl Sorter {
    /// A sorter for `cfg`.
    pub fn new(cfg: SortConfig) -> Self {
        let n = cfg.network.n;
        Sorter { cfg, vector: vec![SortEntry::default(); n], scratch: Vec::new() }
    }

    /// Its configuration.
    pub fn config(&self) -> &SortConfig {
        &self.cfg
    }

    /// Sorts one chunk in place (the on-chip part): BSU vectors, then in-chunk merge passes.
    /// Adds its work to `work`.
    ///
    /// # Panics
    /// When `chunk.len()` exceeds the configured chunk size.
    pub fn sort_chunk(&mut self, chunk: &mut [SortEntry], work: &mut ChunkWork) {
        let len = chunk.len();
        assert!(len <= self.cfg.chunk, "chunk of {len} entries exceeds the chunk size {}", self.cfg.chunk);
        if len == 0 {
            return;
        }
        let n = self.cfg.network.n;
        work.chunks += 1;
        work.entries += len;
        for v in chunk.chunks_mut(n) {
            work.bsu_vectors += 1;
            if v.len() == n {
                self.cfg.network.apply(v);
            } else {
                let pad = self.cfg.format.padding();
                work.padding_entries += n - v.len();
                self.vector[..v.len()].copy_from_slice(v);
                self.vector[v.len()..].fill(pad);
                self.cfg.network.apply(&mut self.vector);
                // Padding sorts strictly last (reserved id, maximal key), so it is exactly the
                // tail, unless an entry breaks the format (see `SortFormat::holds`).
                assert!(
                    self.vector[v.len()..].iter().all(|e| *e == pad),
                    "an entry does not fit {:?} (key above key_max or the reserved id)",
                    self.cfg.format
                );
                v.copy_from_slice(&self.vector[..v.len()]);
            }
        }
        let mut run = n;
        while run < len {
            self.scratch.clear();
            let pass = merge_pass(chunk, run, &mut self.scratch);
            chunk.copy_from_slice(&self.scratch);
            work.merge_passes += 1;
            work.merges += pass.merges;
            work.entries_merged += pass.entries_merged;
            work.entries_copied += pass.entries_copied;
            run *= 2;
        }
    }

    /// Conventional sort of `input` into `out` (cleared first), executing the command plan
    /// ([`conventional_sort_plan`]): the chunk sorts, then the merge passes across chunks.
    /// Returns the work counters.
    pub fn full_sort(&mut self, input: &[SortEntry], out: &mut Vec<SortEntry>) -> SortWork {
        out.clear();
        out.extend_from_slice(input);
        let n = input.len();
        let mut work = SortWork { entries: n, ..SortWork::default() };
        for cmd in conventional_sort_plan(n as u64, self.cfg.chunk as u64) {
            let (start, len_a, len_b) = (cmd.start as usize, cmd.len_a as usize, cmd.len_b as usize);
            if cmd.mode == SortMode::Sort {
                self.sort_chunk(&mut out[start..start + len_a], &mut work.chunk);
                continue;
            }
            if start == 0 {
                self.scratch.clear();
                work.global_passes.push(PassWork::default());
            }
            let pass = work.global_passes.last_mut().expect("a merge pass starts at offset 0");
            let a = &out[start..start + len_a];
            if len_b == 0 {
                // A lone run: the MERGE with an empty stream B copies it.
                self.scratch.extend_from_slice(a);
                pass.runs_in += 1;
                pass.entries_copied += len_a;
            } else {
                merge2_into(a, &out[start + len_a..start + len_a + len_b], false, &mut self.scratch);
                pass.runs_in += 2;
                pass.merges += 1;
                pass.entries_merged += len_a + len_b;
            }
            if start + len_a + len_b == n {
                std::mem::swap(out, &mut self.scratch);
            }
        }
        work
    }
}

/// One two-way merge pass over runs of length `run` (the last may be shorter), appending the
/// result to `dst` (the in-chunk passes; the passes across chunks follow the command plan).
fn merge_pass(src: &[SortEntry], run: usize, dst: &mut Vec<SortEntry>) -> PassWork {
    let mut pass = PassWork { runs_in: src.len().div_ceil(run), ..PassWork::default() };
    for pair in src.chunks(2 * run) {
        if pair.len() <= run {
            dst.extend_from_slice(pair);
            pass.entries_copied += pair.len();
        } else {
            let (a, b) = pair.split_at(run);
            merge2_into(a, b, false, dst);
            pass.merges += 1;
            pass.entries_merged += pair.len();
        }
    }
    pass
}

/// Conventional sort of `input` with `cfg` (allocating convenience over [`Sorter::full_sort`]).
pub fn full_sort(input: &[SortEntry], cfg: &SortConfig) -> (Vec<SortEntry>, SortWork) {
    let mut out = Vec::with_capacity(input.len());
    let work = Sorter::new(cfg.clone()).full_sort(input, &mut out);
    (out, work)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn config_rejects_bad_chunks() {
        let f = SortFormat::ARTIFACT;
        assert!(SortConfig::new(f, 256, Network::bitonic(16)).is_ok());
        assert!(SortConfig::new(f, 16, Network::best_16()).is_ok());
        for chunk in [0, 8, 24, 48, 250] {
            assert_eq!(
                SortConfig::new(f, chunk, Network::bitonic(16)),
                Err(SortParamError::Chunk { chunk, bsu: 16 }),
                "chunk {chunk}"
            );
        }
        assert_eq!(SortConfig::new(f, 4, Network::bitonic(1)), Err(SortParamError::BsuWidth(1)));
    }

    #[test]
    fn merge_pass_pairs_runs_and_passes_the_odd_one_through() {
        let keys = |v: &[SortEntry]| v.iter().map(|e| e.key).collect::<Vec<u32>>();
        // Runs [3 5] [1 4] [2 9] [0]: two merges, the short last run merges too.
        let src: Vec<SortEntry> = [3, 5, 1, 4, 2, 9, 0].iter().map(|&k| SortEntry::new(k, 0)).collect();
        let mut dst = Vec::new();
        let pass = merge_pass(&src, 2, &mut dst);
        assert_eq!(keys(&dst), vec![1, 3, 4, 5, 0, 2, 9]);
        assert_eq!(pass, PassWork { runs_in: 4, merges: 2, entries_merged: 7, entries_copied: 0 });
        // Runs [3 5] [1 4] [2]: the odd run out is copied.
        let mut dst = Vec::new();
        let pass = merge_pass(&src[..5], 2, &mut dst);
        assert_eq!(keys(&dst), vec![1, 3, 4, 5, 2]);
        assert_eq!(pass, PassWork { runs_in: 3, merges: 1, entries_merged: 4, entries_copied: 1 });
    }

    #[test]
    #[should_panic(expected = "does not fit")]
    fn key_above_the_format_in_a_padded_vector_is_rejected() {
        // It would sort after the padding and be cut off with it.
        let mut s = Sorter::new(SortConfig::artifact());
        let mut chunk = vec![SortEntry::new(0x1_0000, 0), SortEntry::new(1, 1)];
        s.sort_chunk(&mut chunk, &mut ChunkWork::default());
    }

    #[test]
    fn partial_chunk_counts_padding_and_passes() {
        let mut s = Sorter::new(SortConfig::artifact());
        let mut chunk: Vec<SortEntry> = (0..37u32).rev().map(|k| SortEntry::new(k, k)).collect();
        let mut w = ChunkWork::default();
        s.sort_chunk(&mut chunk, &mut w);
        assert!(chunk.iter().enumerate().all(|(i, e)| e.key == i as u32));
        // 37 = 16 + 16 + 5: three vectors, 11 padding, passes 3 runs -> 2 -> 1.
        assert_eq!(w.bsu_vectors, 3);
        assert_eq!(w.padding_entries, 11);
        assert_eq!(w.merge_passes, 2);
        assert_eq!(w.merges, 2);
        assert_eq!(w.entries_merged, 32 + 37);
        assert_eq!(w.entries_copied, 5);
    }
}

#[cfg(test)]
mod pass_count_tests {
    use super::merge_pass_count;

    #[test]
    fn pass_count_is_ceil_log2_of_the_run_count() {
        let cases = [
            (0, 16, 0),
            (1, 16, 0),
            (16, 16, 0),
            (17, 16, 1),
            (32, 16, 1),
            (33, 16, 2),
            (256, 16, 4),
            (257, 256, 1),
        ];
        for (items, run, passes) in cases {
            assert_eq!(merge_pass_count(items, run), passes, "{items} items in runs of {run}");
        }
        for runs in 2u64..300 {
            let expected = (runs as f64).log2().ceil() as u64;
            assert_eq!(merge_pass_count(runs * 8, 8), expected, "{runs} runs");
        }
    }
}
