//! `neo_sort_core` against golden `full_sort`, `dps_pass`, `merge2` and `update_tile`, with the
//! memory served by the test bench's model (random request stalls, random response latency).
//!
//! Chunks of 1, 255, 256 entries are one `SORT` each; 257 entries is two chunks (256 + 1) plus
//! a `MERGE` of the two runs, exactly golden `full_sort`'s schedule. The flows issue their
//! commands back to back (several in flight); mixed random queues and directed chunks run back
//! to back too, and `core_back_to_back_chunks_overlap` shows the load of one chunk is hidden
//! under the previous chunk's merge passes. `core_merges_with_a_starved_stream_match_golden` is
//! the FIFO-capacity stress class (docs/rtl.md "Verification harness"): one merge input held
//! back for longer than its FIFO holds while the other goes out.

#[cfg(not(neo_has_verilator))]
#[test]
fn sort_core_skipped_without_verilator() {
    // Prints SKIP (or fails when CI is set); the models must really be absent in this build.
    assert!(!neo_tb::require_models(
        "sort_core_skipped_without_verilator: Sorting Core cosimulation did not run"
    ));
}

#[cfg(neo_has_verilator)]
mod cosim {
    use neo_golden::sort::{merge_pass_count, Parity, SortEntry};
    use neo_tb::core::{
        chunk_cmd, chunk_cmd_at, dps_pass_checked, full_sort_checked, layout, merge_checked, merge_cmd,
        merge_cmd_at, queue_checked, sort_chunk_checked, sort_chunks_checked, update_checked, CheckedCmd,
        Command, Core, MemTiming, MergeAt, Mode,
    };
    use neo_tb::rng::{for_each_seed, Rng};
    use neo_tb::stimulus::{
        entry_space, merge_stream, nearly_sorted, starved_merge, tile_entries, MergeShape,
    };
    use neo_tb::waves::maybe_trace;

    fn core(name: &str, seed: u64, timing: MemTiming) -> Core {
        let mut c = Core::new(&neo_tb::config(), seed, timing);
        maybe_trace(&mut c.dut, name);
        c
    }

    #[test]
    fn core_sorts_chunks_of_1_255_256() {
        let name = "core_sorts_chunks_of_1_255_256";
        for_each_seed(name, |seed| {
            let cfg = neo_tb::config();
            let mut rng = Rng::new(seed);
            let mut c = core(name, seed, MemTiming::RANDOM);
            for n in [1, 2, 15, 16, 17, 100, 255, 256] {
                for (ties, valid) in [(false, 100), (true, 70)] {
                    let v = tile_entries(&cfg.format(), &mut rng, n, ties, valid);
                    sort_chunk_checked(&mut c, &cfg, &v, Mode::Sort);
                }
            }
            // Random sizes under the hostile memory.
            for _ in 0..24 {
                let n = rng.range(1, cfg.chunk as u64) as usize;
                let ties = rng.percent(30);
                let v = tile_entries(&cfg.format(), &mut rng, n, ties, 80);
                sort_chunk_checked(&mut c, &cfg, &v, if rng.percent(50) { Mode::Sort } else { Mode::Dps });
            }
            c.set_timing(MemTiming::IDEAL);
            for n in [1, 255, 256] {
                let v = tile_entries(&cfg.format(), &mut rng, n, false, 90);
                sort_chunk_checked(&mut c, &cfg, &v, Mode::Sort);
            }
        });
    }

    #[test]
    fn core_sorts_257_as_two_chunks_plus_a_merge_and_longer_inputs_in_passes() {
        let name = "core_sorts_257_as_two_chunks_plus_a_merge_and_longer_inputs_in_passes";
        for_each_seed(name, |seed| {
            let cfg = neo_tb::config();
            let mut rng = Rng::new(seed);
            let mut c = core(name, seed, MemTiming::RANDOM);
            // 257: SORT 256 + SORT 1 + MERGE; 600: 3 chunks, a pass with a copied lone run, then a merge.
            for n in [257, 600] {
                let v = tile_entries(&cfg.format(), &mut rng, n, n == 600, 80);
                full_sort_checked(&mut c, &cfg, &v);
            }
        });
    }

    #[test]
    fn core_sort_takes_at_most_one_chunk() {
        let name = "core_sort_takes_at_most_one_chunk";
        for_each_seed(name, |seed| {
            let cfg = neo_tb::config();
            let mut rng = Rng::new(seed);
            let mut c = core(name, seed, MemTiming::IDEAL);
            // A SORT of 257 entries sorts src[0..256) only (documented clamp) and reports 256.
            let v = tile_entries(&cfg.format(), &mut rng, 257, false, 100);
            c.write_entries(layout::SRC, &v);
            let r = c.run(Command {
                mode: Mode::Sort,
                src_a: layout::SRC,
                len_a: 257,
                src_b: 0,
                len_b: 0,
                dst: layout::DST,
            });
            c.checker.value(c.dut.cycle(), "done_len_o (SORT of 257)", cfg.chunk as u64, r.done_len);
            let (want, _) = neo_golden::sort::full_sort(&v[..256], &cfg.sort_config());
            c.expect("clamped chunk", layout::DST, &want);
        });
    }

    #[test]
    fn core_directed_chunks() {
        let name = "core_directed_chunks";
        for_each_seed(name, |seed| {
            let cfg = neo_tb::config();
            let fmt = cfg.format();
            let mut c = core(name, seed, MemTiming::RANDOM);
            let n = cfg.chunk as u32;
            let cases: Vec<(&str, Vec<SortEntry>)> = vec![
                ("equal keys, ids descending", (0..n).map(|i| SortEntry::new(9, n - i)).collect()),
                ("reversed", (0..n).map(|i| SortEntry::new(n - i, i)).collect()),
                ("already sorted", (0..n).map(|i| SortEntry::new(i, 1000 + i)).collect()),
                (
                    "min and max keys",
                    (0..n).map(|i| SortEntry::new(if i % 2 == 0 { fmt.key_max() } else { 0 }, i)).collect(),
                ),
                ("all invalid", (0..n).map(|i| SortEntry { key: i % 7, id: i, valid: false }).collect()),
                ("one valid", (0..37).map(|i| SortEntry { key: 40 - i, id: i, valid: i == 20 }).collect()),
                (
                    "largest real id",
                    vec![SortEntry::new(fmt.key_max(), fmt.id_max() - 1), SortEntry::new(0, 0)],
                ),
            ];
            for (case, v) in &cases {
                println!("case: {case}");
                sort_chunk_checked(&mut c, &cfg, v, Mode::Sort);
                sort_chunk_checked(&mut c, &cfg, v, Mode::Dps);
            }
        });
    }

    #[test]
    fn core_dps_passes_match_golden() {
        let name = "core_dps_passes_match_golden";
        for_each_seed(name, |seed| {
            let cfg = neo_tb::config();
            let mut rng = Rng::new(seed);
            let mut c = core(name, seed, MemTiming::RANDOM);
            // A reused table slightly out of order (displacements <= C/2): two passes of opposite
            // parity restore the order, pass by pass as golden.
            let v = tile_entries(&cfg.format(), &mut rng, 700, false, 85);
            let table = nearly_sorted(v, &mut rng, cfg.chunk / 2, 120);
            let (t1, _) = dps_pass_checked(&mut c, &cfg, &table, Parity::Even);
            let (t2, _) = dps_pass_checked(&mut c, &cfg, &t1, Parity::Odd);
            assert!(t2.windows(2).all(|w| w[0].order_key() <= w[1].order_key()), "two passes sort it");
            // An unsorted table, odd parity first (chunks of C/2, C, ..., and a short last one).
            let v = tile_entries(&cfg.format(), &mut rng, 300, true, 60);
            dps_pass_checked(&mut c, &cfg, &v, Parity::Odd);
        });
    }

    #[test]
    fn core_merges_match_golden() {
        let name = "core_merges_match_golden";
        for_each_seed(name, |seed| {
            let cfg = neo_tb::config();
            let fmt = cfg.format();
            let mut rng = Rng::new(seed);
            let mut c = core(name, seed, MemTiming::RANDOM);
            let mut entries = 0;
            for k in 0..16 {
                let la = if k == 0 { 0 } else { rng.below(301) as usize };
                let lb = if k == 1 { 0 } else { rng.below(301) as usize };
                let ties = k % 3 == 0;
                let va = *rng.pick(&[100, 80, 30]);
                let a = merge_stream(&fmt, &mut rng, la, va, ties);
                let mut b = merge_stream(&fmt, &mut rng, lb, 70, ties);
                if k % 5 == 4 {
                    b = a.iter().map(|e| e.with_valid(!e.valid)).collect();
                }
                merge_checked(&mut c, &a, &b, k % 2 == 0);
                entries += a.len() + b.len();
            }
            // Empty both, and everything dropped.
            merge_checked(&mut c, &[], &[], true);
            merge_checked(&mut c, &[], &[], false);
            let dead =
                vec![SortEntry { key: 1, id: 1, valid: false }, SortEntry { key: 2, id: 2, valid: false }];
            let r = merge_checked(&mut c, &dead, &dead[1..], true);
            assert_eq!(r.done_len, 0);
            // A reused table out of order as DPS leaves it (sorted runs, reversed): the MSU+
            // counts its boundary inversions (`done_inv_o`), after the chunk command's 0.
            let sorted = merge_stream(&fmt, &mut rng, 300, 80, false);
            let runs: Vec<SortEntry> = sorted.chunks(64).rev().flatten().copied().collect();
            let b = merge_stream(&fmt, &mut rng, 100, 100, false);
            for drop in [true, false] {
                let r = merge_checked(&mut c, &runs, &b, drop);
                assert!(r.done_inv > 0, "out-of-order A counts inversions: {r:?}");
            }
            // A descending A of 2^k entries has 2^k - 1 inversions: each count's bits rise, and
            // fall again with the sorted A after it.
            for k in [1, 3, 6, 9, 12] {
                let desc: Vec<SortEntry> =
                    merge_stream(&fmt, &mut rng, 1 << k, 100, false).into_iter().rev().collect();
                let r = merge_checked(&mut c, &desc, &[], false);
                assert_eq!(r.done_inv, (1 << k) - 1, "descending A of 2^{k}");
                let r = merge_checked(&mut c, &sorted, &[], false);
                assert_eq!(r.done_inv, 0);
            }
            println!("{name}: {entries} entries merged");
        });
    }

    /// Stream lengths of the merge stress: around the burst (16) and the input FIFO (256)
    /// capacities, and thousands.
    const STRESS_LENGTHS: [usize; 9] = [0, 1, 15, 16, 17, 255, 256, 257, 3000];

    /// The FIFO-capacity class: merges where one stream is held back (all its keys above the
    /// other's, or long alternating runs) for longer than an input FIFO holds while the other
    /// goes out, from both sides, at every length of [`STRESS_LENGTHS`] against a stream longer
    /// than a FIFO (600) and against itself, under slow-write (the read side fills the FIFOs at
    /// full speed) and random memory timing, and a third of the cases (per seed) under long
    /// stalls.
    #[test]
    fn core_merges_with_a_starved_stream_match_golden() {
        let name = "core_merges_with_a_starved_stream_match_golden";
        for_each_seed(name, |seed| {
            let cfg = neo_tb::config();
            let fmt = cfg.format();
            let mut rng = Rng::new(seed);
            let mut c = core(name, seed, MemTiming::RANDOM);
            let (mut merges, mut entries) = (0, 0);
            for timing in [MemTiming::SLOW_WRITES, MemTiming::RANDOM, MemTiming::LONG_STALLS] {
                c.set_timing(timing);
                for &l in &STRESS_LENGTHS {
                    for shape in [MergeShape::ALow, MergeShape::BLow, MergeShape::Runs(300)] {
                        for (la, lb) in [(l, 600), (600, l), (l, l)] {
                            // The long-stall memory is slow to simulate: each seed runs a
                            // third of its cases (drawn from the seed, so a replay runs the same).
                            if timing == MemTiming::LONG_STALLS && !rng.percent(33) {
                                continue;
                            }
                            let (a, b) = starved_merge(&fmt, &mut rng, la, lb, shape, 85);
                            merge_checked(&mut c, &a, &b, merges % 2 == 0);
                            merges += 1;
                            entries += la + lb;
                        }
                    }
                }
            }
            println!("{name}: {merges} merges, {entries} entries");
        });
    }

    /// A merge streams whether or not its runs interleave: the read issuer serves the stream
    /// the merge drains (`b_drained`), so two runs whose keys do not interleave (every key of
    /// one below every key of the other, as in an early merge pass of a real tile) merge within
    /// 15% of the cycles of interleaved runs of the same lengths (1.09x measured), behind a
    /// memory that answers in 1 or in 8 cycles. An issuer that alternated the streams whatever
    /// the merge consumed took 757 cycles against 533 for 256 + 256 entries (1.42x).
    #[test]
    fn core_merges_runs_that_do_not_interleave_as_fast_as_interleaved_ones() {
        let name = "core_merges_runs_that_do_not_interleave_as_fast_as_interleaved_ones";
        for_each_seed(name, |seed| {
            let fmt = neo_tb::config().format();
            let mut rng = Rng::new(seed);
            let mut worst: f64 = 0.0;
            for latency in [1, 8] {
                let timing = MemTiming { min_latency: latency, max_latency: latency, ..MemTiming::IDEAL };
                let mut c = core(name, seed, timing);
                for n in [256, 1024] {
                    let cycles = |c: &mut Core, shape, rng: &mut Rng| {
                        let (a, b) = starved_merge(&fmt, rng, n, n, shape, 100);
                        merge_checked(c, &a, &b, false).cycles
                    };
                    let interleaved = cycles(&mut c, MergeShape::Runs(1), &mut rng);
                    for shape in [MergeShape::ALow, MergeShape::BLow] {
                        let got = cycles(&mut c, shape, &mut rng);
                        worst = worst.max(got as f64 / interleaved as f64);
                        assert!(
                            got * 100 <= interleaved * 115,
                            "{name}: latency {latency}, {n} + {n} entries, {shape:?}: {got} cycles, more than \
                             1.15x the {interleaved} of interleaved runs (seed {seed:#x})"
                        );
                    }
                }
            }
            println!(
                "{name}: runs that do not interleave took at most {worst:.3}x the cycles of interleaved ones"
            );
        });
    }

    /// Regions of the entry space below 2^29 (32-bit byte addresses of 8-byte entries) for
    /// commands that must not overlap: the first and the last region, then random ones, each of
    /// `4 table_capacity` entries, a command at a random offset below `3 table_capacity` in it
    /// (so that every address bit varies).
    struct Places {
        size: u64,
        count: u64,
        used: Vec<u64>,
    }

    impl Places {
        fn new(cfg: &neo_gen::EngineConfig) -> Places {
            let size = 4 * cfg.table_capacity as u64;
            Places { size, count: entry_space(cfg) / size, used: Vec::new() }
        }

        fn next(&mut self, rng: &mut Rng) -> u64 {
            let region = match self.used.len() {
                0 => 0,
                1 => self.count - 1,
                _ => loop {
                    let r = rng.below(self.count);
                    if !self.used.contains(&r) {
                        break r;
                    }
                },
            };
            self.used.push(region);
            region * self.size + rng.below(self.size / 4 * 3)
        }
    }

    /// Commands as long as a tile's table can be (`table_capacity` entries: lengths, remaining
    /// counts and the output count reach their top bits) at places spread over the whole entry
    /// space (every address bit), with chunks between them, back to back under the random memory.
    #[test]
    fn core_long_commands_across_the_entry_space() {
        let name = "core_long_commands_across_the_entry_space";
        for_each_seed(name, |seed| {
            let cfg = neo_tb::config();
            let fmt = cfg.format();
            let cap = cfg.table_capacity;
            let mut rng = Rng::new(seed);
            let mut c = core(name, seed, MemTiming::RANDOM);
            let mut places = Places::new(&cfg);
            // (len_a, len_b, delete): the capacity from A alone (deleting), from B alone, split so
            // that B's length has its upper bits (63/64 of it), and an output of 15/16 of it.
            let merges = [
                (cap, 0, true),
                (0, cap, false),
                (cap / 64, cap - cap / 64, false),
                (cap * 15 / 32, cap * 15 / 32, false),
            ];
            let mut jobs = Vec::new();
            for (k, &(la, lb, delete)) in merges.iter().enumerate() {
                let a = merge_stream(&fmt, &mut rng, la, 85, k % 2 == 0);
                let b = merge_stream(&fmt, &mut rng, lb, 85, false);
                let at = MergeAt {
                    src_a: places.next(&mut rng),
                    src_b: places.next(&mut rng),
                    dst: places.next(&mut rng),
                };
                jobs.push(merge_cmd_at(&mut c, at, &a, &b, delete));
                // Chunks between and after the merges, each input buffer's several times.
                for j in 0..4 {
                    let n = rng.range(1, cfg.chunk as u64 + 1) as usize;
                    let v = tile_entries(&fmt, &mut rng, n, false, 90);
                    let mode = if j % 2 == 0 { Mode::Sort } else { Mode::Dps };
                    let (src, dst) = (places.next(&mut rng), places.next(&mut rng));
                    jobs.push(chunk_cmd_at(&mut c, &cfg, src, dst, &v, mode));
                }
            }
            let q = queue_checked(&mut c, &jobs);
            let longest = jobs.iter().map(|j| j.want.len()).max().unwrap_or(0);
            assert_eq!(longest, cap, "a merge's output fills the capacity");
            println!("{name}: {} commands, {} cycles", jobs.len(), q.span);
        });
    }

    #[test]
    fn core_update_flow_matches_golden_update_tile() {
        let name = "core_update_flow_matches_golden_update_tile";
        for_each_seed(name, |seed| {
            let cfg = neo_tb::config();
            let mut rng = Rng::new(seed);
            let mut c = core(name, seed, MemTiming::RANDOM);
            let fmt = cfg.format();
            let all = tile_entries(&fmt, &mut rng, 900, false, 100);
            let (mut table, _) = neo_golden::sort::full_sort(&all[..400], &cfg.sort_config());
            let mut next = 400;
            for frame in 1..4u64 {
                // Depth keys drift, some Gaussians leave (valid = 0), new ones arrive.
                for e in table.iter_mut() {
                    e.key =
                        (e.key as i64 + rng.range(0, 200) as i64 - 100).clamp(0, fmt.key_max() as i64) as u32;
                    e.valid = !rng.percent(10);
                }
                let n_in = rng.range(0, 150) as usize;
                let incoming = all[next..next + n_in].to_vec();
                next += n_in;
                table = update_checked(&mut c, &cfg, &table, &incoming, frame);
            }
        });
    }

    /// Engines with a wide DPS chunk (`dps_wide` > 1), whose buffers hold `W = dps_wide x C`
    /// entries: chunk commands at the buffer's edges (`C`, `C + 1`, `W / 2`, `W - 1`, `W`, and
    /// `W + 1`, clamped to `W`), a DPS-like wide chunk (a sorted table displaced by up to
    /// `W / 2`), back-to-back queues of chunks up to `W` and merges whose streams fill the
    /// `W`-entry FIFOs, and a conventional sort across several wide chunks, behind the hostile
    /// memory.
    #[test]
    fn core_wide_chunks_in_other_configurations() {
        let name = "core_wide_chunks_in_other_configurations";
        neo_tb::configs::run_in_other_configurations(
            name,
            neo_tb::configs::sort_wide(),
            |cfg| Core::build(cfg, 0, MemTiming::RANDOM),
            |c| &mut c.dut,
            |c, cfg, seed| {
                c.reseed(seed);
                c.set_timing(MemTiming::RANDOM);
                let fmt = cfg.format();
                let (ch, w) = (cfg.chunk, cfg.sort_buffer());
                let mut rng = Rng::new(seed).fork(5);
                for n in [ch, ch + 1, w / 2, w - 1, w] {
                    let v = tile_entries(&fmt, &mut rng, n, n % 2 == 0, 80);
                    sort_chunk_checked(c, cfg, &v, if n % 2 == 0 { Mode::Dps } else { Mode::Sort });
                }
                let sorted = tile_entries(&fmt, &mut rng, w, false, 70);
                let table = nearly_sorted(sorted, &mut rng, w / 2, w / 8);
                sort_chunk_checked(c, cfg, &table, Mode::Dps);
                let v = tile_entries(&fmt, &mut rng, w + 1, false, 100);
                let clamped = chunk_cmd(c, cfg, 0, &v, Mode::Sort);
                assert_eq!(clamped.want.len(), w, "a chunk command sorts one buffer");
                queue_checked(c, &[clamped]);
                for gap in [0, 3] {
                    c.set_cmd_gap(gap);
                    let jobs: Vec<CheckedCmd> = (0..6)
                        .map(|slot| {
                            if rng.percent(70) {
                                let n = rng.range(1, w as u64 + 1) as usize;
                                let ties = rng.percent(30);
                                let v = tile_entries(&fmt, &mut rng, n, ties, 80);
                                chunk_cmd(
                                    c,
                                    cfg,
                                    slot,
                                    &v,
                                    if rng.percent(50) { Mode::Sort } else { Mode::Dps },
                                )
                            } else {
                                let (la, lb) = (rng.range(0, w as u64 + 1), rng.range(0, w as u64 + 1));
                                let a = merge_stream(&fmt, &mut rng, la as usize, 75, true);
                                let b = merge_stream(&fmt, &mut rng, lb as usize, 75, false);
                                merge_cmd(c, slot, &a, &b, rng.percent(50))
                            }
                        })
                        .collect();
                    queue_checked(c, &jobs);
                }
                c.set_cmd_gap(2);
                let v = tile_entries(&fmt, &mut rng, 2 * w + 5, true, 80);
                full_sort_checked(c, cfg, &v);
                println!("{name}: chunks of up to {w} entries sorted, merged and queued");
            },
        );
    }

    /// Random commands for a mixed queue: mostly chunks (SORT / DPS of 0..=C entries, some
    /// clamped), some merges of two sorted streams (with and without delete).
    fn random_queue(c: &mut Core, rng: &mut Rng, len: usize) -> Vec<CheckedCmd> {
        let cfg = neo_tb::config();
        let fmt = cfg.format();
        let chunk = cfg.chunk as u64;
        (0..len as u64)
            .map(|slot| {
                if rng.percent(80) {
                    let n = match rng.below(8) {
                        0 => *rng.pick(&[0, 1, 16, 17, chunk - 1, chunk, chunk + 1]),
                        _ => rng.range(1, chunk),
                    } as usize;
                    let ties = rng.percent(30);
                    let v = tile_entries(&fmt, rng, n, ties, 80);
                    chunk_cmd(c, &cfg, slot, &v, if rng.percent(50) { Mode::Sort } else { Mode::Dps })
                } else {
                    let (la, lb) = (rng.below(300) as usize, rng.below(300) as usize);
                    let ties = rng.percent(30);
                    let a = merge_stream(&fmt, rng, la, 75, ties);
                    let b = merge_stream(&fmt, rng, lb, 75, false);
                    merge_cmd(c, slot, &a, &b, rng.percent(50))
                }
            })
            .collect()
    }

    #[test]
    fn core_back_to_back_random_queues_match_golden() {
        let name = "core_back_to_back_random_queues_match_golden";
        for_each_seed(name, |seed| {
            let mut rng = Rng::new(seed);
            let mut c = core(name, seed, MemTiming::RANDOM);
            let mut cmds = 0;
            for q in 0..8 {
                // Alternate a hostile memory with gaps between commands and an ideal one with none.
                let ideal = q % 4 == 3;
                c.set_timing(if ideal { MemTiming::IDEAL } else { MemTiming::RANDOM });
                c.set_cmd_gap(if q % 2 == 0 { 0 } else { 3 });
                let jobs = random_queue(&mut c, &mut rng, 12);
                queue_checked(&mut c, &jobs);
                cmds += jobs.len();
            }
            println!("{name}: {cmds} commands back to back");
        });
    }

    #[test]
    fn core_back_to_back_directed_chunks() {
        let name = "core_back_to_back_directed_chunks";
        for_each_seed(name, |seed| {
            let cfg = neo_tb::config();
            let fmt = cfg.format();
            let mut rng = Rng::new(seed);
            let n = cfg.chunk as u32;
            let cases: Vec<(&str, Vec<SortEntry>)> = vec![
                ("1 entry", tile_entries(&fmt, &mut rng, 1, false, 100)),
                ("255 entries", tile_entries(&fmt, &mut rng, 255, true, 90)),
                ("256 entries", tile_entries(&fmt, &mut rng, 256, false, 90)),
                ("257 entries (clamped to one chunk)", tile_entries(&fmt, &mut rng, 257, false, 90)),
                ("empty", Vec::new()),
                ("all invalid", (0..n).map(|i| SortEntry { key: i % 7, id: i, valid: false }).collect()),
                ("one valid", (0..37).map(|i| SortEntry { key: 40 - i, id: i, valid: i == 20 }).collect()),
                ("equal keys, different ids", (0..n).map(|i| SortEntry::new(9, (i * 37) % n)).collect()),
                ("reversed", (0..n).map(|i| SortEntry::new(n - i, i)).collect()),
                ("already sorted", (0..n).map(|i| SortEntry::new(i, 1000 + i)).collect()),
            ];
            for (timing, gap) in [(MemTiming::RANDOM, 2), (MemTiming::IDEAL, 0)] {
                let mut c = core(name, seed, timing);
                c.set_cmd_gap(gap);
                for mode in [Mode::Sort, Mode::Dps] {
                    let jobs: Vec<CheckedCmd> = cases
                        .iter()
                        .enumerate()
                        .map(|(k, (case, v))| {
                            println!("case {k}: {case}");
                            chunk_cmd(&mut c, &cfg, k as u64, v, mode)
                        })
                        .collect();
                    queue_checked(&mut c, &jobs);
                }
            }
        });
    }

    /// The structural bound of one chunk's merge passes at one MSU+ output per cycle: `passes`
    /// passes of `n` entries, plus a few cycles per merge (pair set-up, end-of-merge flush) and
    /// per pass (pipeline drain).
    fn msu_bound(n: u64, bsu: u64) -> u64 {
        let vectors = n.div_ceil(bsu);
        let passes = merge_pass_count(n, bsu).max(1);
        let merges: u64 = (0..passes).map(|p| vectors.div_ceil(2 << p)).sum();
        passes * n + 4 * merges + 4 * passes + 16
    }

    #[test]
    fn core_back_to_back_chunks_overlap() {
        let name = "core_back_to_back_chunks_overlap";
        for_each_seed(name, |seed| {
            let cfg = neo_tb::config();
            let mut rng = Rng::new(seed);
            let bsu = cfg.bsu_width as u64;
            for n in [64u64, cfg.chunk as u64] {
                for mode in [Mode::Sort, Mode::Dps] {
                    let mut c = core(name, seed, MemTiming::IDEAL);
                    c.set_cmd_gap(0);
                    let v = tile_entries(&cfg.format(), &mut rng, n as usize, false, 100);
                    let single = sort_chunk_checked(&mut c, &cfg, &v, mode).cycles;
                    let k = 8;
                    let chunks: Vec<Vec<SortEntry>> =
                        (0..k).map(|_| tile_entries(&cfg.format(), &mut rng, n as usize, true, 90)).collect();
                    let q = sort_chunks_checked(&mut c, &cfg, &chunks, mode);
                    let d: Vec<u64> = q.results.iter().map(|r| r.done_at).collect();
                    let interval = (d[k - 1] - d[1]) / (k as u64 - 2);
                    let bound = msu_bound(n, bsu);
                    println!("{mode:?} of {n}: single {single} cycles, back to back {interval} cycles per chunk (MSU+ bound {bound})");
                    assert!(
                        interval <= bound,
                        "{mode:?} {n}: interval {interval} above the MSU+ bound {bound}"
                    );
                    // The load (n entries at one per cycle) no longer adds to the interval.
                    assert!(
                        interval + n <= single,
                        "{mode:?} {n}: load not hidden (interval {interval}, single {single})"
                    );
                }
            }
        });
    }

    #[test]
    fn core_input_buffer_is_not_reused_before_its_first_pass_ends() {
        // A 32-entry chunk whose first run sorts entirely after its second (its only pass, to
        // memory, pops B first and A's entries 0..15 last), written back at a quarter rate;
        // behind it a 1-entry chunk (loaded at once) and a 32-entry chunk that the LOAD engine
        // may only put into the first chunk's input buffer once that pass is over.
        let name = "core_input_buffer_is_not_reused_before_its_first_pass_ends";
        for_each_seed(name, |seed| {
            let cfg = neo_tb::config();
            let mut rng = Rng::new(seed);
            let w = cfg.bsu_width as u32;
            for round in 0..6u64 {
                let mut c = core(name, seed ^ round, MemTiming::SLOW_WRITES);
                c.set_cmd_gap(0);
                let first: Vec<SortEntry> =
                    (0..2 * w).map(|i| SortEntry::new(if i < w { 1000 + i } else { i }, i)).collect();
                let one = tile_entries(&cfg.format(), &mut rng, 1, false, 100);
                let third = tile_entries(&cfg.format(), &mut rng, 2 * w as usize, false, 100);
                let jobs = vec![
                    chunk_cmd(&mut c, &cfg, 3 * round, &first, Mode::Sort),
                    chunk_cmd(&mut c, &cfg, 3 * round + 1, &one, Mode::Sort),
                    chunk_cmd(&mut c, &cfg, 3 * round + 2, &third, Mode::Dps),
                ];
                queue_checked(&mut c, &jobs);
            }
        });
    }
}
