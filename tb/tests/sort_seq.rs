//! `neo_sort_seq` against golden `tile_plan`: every command field by field, the barrier before
//! every stage and before the completion, and the completion's `next_len` (golden `merge2` /
//! `sort_chunk` run on a golden memory), with Rust playing the Sorting Core and its bridge.
//!
//! Directed tiles cover from-scratch and reuse tiles, both frame parities, list lengths 0, 1,
//! `C - 1`, `C`, `C + 1` and many chunks, previous tables of 0, 1, `C/2 +- 1` and several chunks;
//! random tiles run back to back under random stalls, late done pulses and long bridge drains.

#[cfg(not(neo_has_verilator))]
#[test]
fn sort_seq_skipped_without_verilator() {
    // Prints SKIP (or fails when CI is set); the models must really be absent in this build.
    assert!(!neo_tb::require_models(
        "sort_seq_skipped_without_verilator: sequencer cosimulation did not run"
    ));
}

#[cfg(neo_has_verilator)]
mod cosim {
    use neo_golden::engine::{EngineConfig, FrameRegs, TileDescriptor};
    use neo_golden::sort::SortMode;
    use neo_tb::configs::run_in_other_configurations;
    use neo_tb::dut::Clocked;
    use neo_tb::rng::{for_each_seed, Rng};
    use neo_tb::seq::{fill, random_desc, random_scratch_base, SeqBench, SeqJob, SeqTiming};
    use neo_tb::waves::maybe_trace;

    fn bench(name: &str, seed: u64, timing: SeqTiming) -> SeqBench {
        let mut b = SeqBench::new(&neo_tb::config(), seed, timing);
        maybe_trace(&mut b.dut, name);
        b
    }

    fn regs(frame: u32, d: &TileDescriptor, rng: &mut Rng) -> FrameRegs {
        regs_of(&neo_tb::config(), frame, d, rng)
    }

    fn regs_of(cfg: &EngineConfig, frame: u32, d: &TileDescriptor, rng: &mut Rng) -> FrameRegs {
        FrameRegs { frame, scratch_base: random_scratch_base(cfg, rng, d), ..FrameRegs::default() }
    }

    #[test]
    fn seq_directed_tiles_follow_the_plan() {
        let name = "seq_directed_tiles_follow_the_plan";
        for_each_seed(name, |seed| {
            let cfg = neo_tb::config();
            let c = cfg.chunk as u32;
            let mut rng = Rng::new(seed);
            let mut b = bench(name, seed, SeqTiming::RANDOM);
            let lists = [0, 1, c - 1, c, c + 1, 3 * c + 7, 9 * c];
            let prevs = [0, 1, c / 2 - 1, c / 2 + 1, c, 2 * c + 3];
            let mut tiles = 0;
            for frame in [6u32, 7] {
                for &n in &lists {
                    for (k, from_scratch) in [(0, true), (1, false)] {
                        for &p in if from_scratch { &prevs[..1] } else { &prevs[..] } {
                            let d = TileDescriptor {
                                tile_x: 3,
                                tile_y: frame as u16,
                                from_scratch,
                                prev: 0x10_0000 + k * 0x40,
                                prev_len: p,
                                list: 0x20_0000 + n,
                                list_len: n,
                                next: 0x30_0000 + 8 * p,
                                dps_passes: 1,
                                dps_wide: false,
                            };
                            fill(&cfg, &mut rng, &mut b.mem, &d);
                            let job = SeqJob {
                                desc: d,
                                regs: regs(frame, &d, &mut rng),
                                core: rng.below(cfg.sort_cores as u64),
                            };
                            let r = b.run(&job);
                            tiles += 1;
                            assert_eq!(r.commands > 0, !(from_scratch && n == 0), "{d:?}");
                        }
                    }
                }
            }
            println!("{tiles} directed tiles");
        });
    }

    /// The DPS chunks of a previous table of `len` entries, restated plainly (independent of
    /// golden `Parity::chunks`, which drives the plan the bench compares against): an even frame
    /// cuts at every multiple of the chunk size `c`, an odd frame at `c/2`, `c/2 + c`, ...;
    /// every piece between two cuts (or the table's ends) is one chunk.
    fn restated_dps_chunks(len: u64, c: u64, odd_frame: bool) -> Vec<(u64, u64)> {
        let mut cuts = vec![0];
        let mut cut = if odd_frame { c / 2 } else { c };
        while cut < len {
            cuts.push(cut);
            cut += c;
        }
        cuts.push(len);
        cuts.windows(2).filter(|w| w[1] > w[0]).map(|w| (w[0], w[1] - w[0])).collect()
    }

    /// Every DPS chunk boundary position on both parities, for a descriptor asking for the DPS
    /// chunk `D` of `wide` (the wide chunk `W` or the chunk `C`, [`EngineConfig::dps_chunk`]):
    /// previous tables whose length ends one before, on and one after every boundary of either
    /// parity up to 4 chunks of `D`; the DPS commands the sequencer issues (offset from the
    /// table, length) must be the plainly restated chunks.
    fn dps_boundaries<M: Clocked>(b: &mut SeqBench<M>, cfg: &EngineConfig, seed: u64, wide: bool) -> usize {
        let c = cfg.dps_chunk(wide) as u64;
        let mut rng = Rng::new(seed);
        let mut lens = vec![0u64, 1, 2];
        for k in 1..=8 {
            let boundary = k * c / 2;
            lens.extend([boundary - 1, boundary, boundary + 1]);
        }
        let mut checked = 0;
        for frame in [10u32, 11] {
            for &p in &lens {
                let d = TileDescriptor {
                    tile_x: 1,
                    tile_y: 2,
                    from_scratch: false,
                    prev: 0x10_0000,
                    prev_len: p as u32,
                    list: 0x20_0000,
                    list_len: rng.below(3) as u32,
                    next: 0x30_0000,
                    dps_passes: 1,
                    dps_wide: wide,
                };
                fill(cfg, &mut rng, &mut b.mem, &d);
                let job = SeqJob { desc: d, regs: regs_of(cfg, frame, &d, &mut rng), core: 0 };
                let r = b.run(&job);
                let got: Vec<(u64, u64)> = r
                    .cmds
                    .iter()
                    .filter(|x| x.mode == SortMode::Dps)
                    .map(|x| {
                        assert_eq!(x.dst, x.src_a, "DPS sorts in place");
                        (x.src_a - d.prev as u64, x.len_a)
                    })
                    .collect();
                let want = restated_dps_chunks(p, c, frame % 2 == 1);
                assert_eq!(
                    got, want,
                    "DPS chunks (wide: {wide}) of a {p}-entry table, frame {frame} (seed 0x{seed:016x})"
                );
                checked += 1;
            }
        }
        checked
    }

    /// [`dps_boundaries`] on the crate's configuration: chunks of `C`, and the wide bit, which
    /// an engine without a wide chunk (`dps_wide` 1) ignores.
    #[test]
    fn seq_dps_chunks_at_every_boundary_on_both_parities() {
        let name = "seq_dps_chunks_at_every_boundary_on_both_parities";
        for_each_seed(name, |seed| {
            let cfg = neo_tb::config();
            let mut b = bench(name, seed, SeqTiming::FAST);
            let checked = dps_boundaries(&mut b, &cfg, seed, false);
            assert_eq!(cfg.dps_chunk(true), cfg.dps_chunk(false), "the crate's engine has no wide chunk");
            let wide = dps_boundaries(&mut b, &cfg, seed, true);
            assert_eq!(restated_dps_chunks(600, 256, false), [(0, 256), (256, 256), (512, 88)]);
            assert_eq!(restated_dps_chunks(600, 256, true), [(0, 128), (128, 256), (384, 216)]);
            println!("{name}: {checked} + {wide} tiles");
        });
    }

    /// Engines with a wide DPS chunk (`dps_wide` > 1): every boundary of the wide chunk and of
    /// the chunk on both parities, several passes of either, and random tiles back to back
    /// (lengths at the wide chunk's edges too) under random timing.
    #[test]
    fn seq_wide_chunks_in_other_configurations() {
        let name = "seq_wide_chunks_in_other_configurations";
        run_in_other_configurations(
            name,
            neo_tb::configs::sort_wide(),
            |cfg| SeqBench::build(cfg, 0, SeqTiming::FAST),
            |b| &mut b.dut,
            |b, cfg, seed| {
                b.reseed(seed);
                b.set_timing(SeqTiming::FAST);
                let n = dps_boundaries(b, cfg, seed, true) + dps_boundaries(b, cfg, seed, false);
                let w = cfg.sort_buffer() as u64;
                let mut rng = Rng::new(seed).fork(3);
                for (frame, passes) in [(4u32, 2u8), (7, 3)] {
                    let p = 2 * w + 3;
                    let d = TileDescriptor {
                        prev: 0x10_0000,
                        prev_len: p as u32,
                        list: 0x20_0000,
                        list_len: rng.below(3) as u32,
                        next: 0x30_0000,
                        dps_passes: passes,
                        dps_wide: true,
                        ..TileDescriptor::default()
                    };
                    fill(cfg, &mut rng, &mut b.mem, &d);
                    let r = b.run(&SeqJob { desc: d, regs: regs_of(cfg, frame, &d, &mut rng), core: 0 });
                    let got: Vec<(u64, u64)> = r
                        .cmds
                        .iter()
                        .filter(|x| x.mode == SortMode::Dps)
                        .map(|x| (x.src_a - 0x10_0000, x.len_a))
                        .collect();
                    let want: Vec<(u64, u64)> = (0..passes as u32)
                        .flat_map(|k| restated_dps_chunks(p, w, (frame + k) % 2 == 1))
                        .collect();
                    assert_eq!(got, want, "{passes} wide passes, frame {frame} (seed 0x{seed:016x})");
                }
                b.set_timing(SeqTiming::RANDOM);
                for _ in 0..40 {
                    let d = random_desc(cfg, &mut rng, 3 * cfg.dps_wide as u64);
                    fill(cfg, &mut rng, &mut b.mem, &d);
                    let job = SeqJob {
                        desc: d,
                        regs: regs_of(cfg, rng.next_u32(), &d, &mut rng),
                        core: rng.below(cfg.sort_cores as u64),
                    };
                    b.run(&job);
                }
                println!("{name}: {n} boundary tiles, 2 multi-pass tiles, 40 random tiles");
            },
        );
    }

    /// Several DPS passes: pass `k` of frame `f` cuts with the parity of `f + k` (restated
    /// plainly), each pass a stage of its own, none for 0 passes, then the merge.
    #[test]
    fn seq_dps_passes_alternate_the_parity() {
        let name = "seq_dps_passes_alternate_the_parity";
        for_each_seed(name, |seed| {
            let cfg = neo_tb::config();
            let c = cfg.chunk as u64;
            let mut rng = Rng::new(seed);
            let mut b = bench(name, seed, SeqTiming::RANDOM);
            for frame in [10u32, 11] {
                for passes in [0u8, 1, 2, 3, 5, 8, 15] {
                    let p = 2 * c + 3;
                    let d = TileDescriptor {
                        prev: 0x10_0000,
                        prev_len: p as u32,
                        list: 0x20_0000,
                        list_len: rng.below(3) as u32,
                        next: 0x30_0000,
                        dps_passes: passes,
                        ..TileDescriptor::default()
                    };
                    fill(&cfg, &mut rng, &mut b.mem, &d);
                    let r = b.run(&SeqJob { desc: d, regs: regs(frame, &d, &mut rng), core: 0 });
                    let got: Vec<(u64, u64)> = r
                        .cmds
                        .iter()
                        .filter(|x| x.mode == SortMode::Dps)
                        .map(|x| (x.src_a - d.prev as u64, x.len_a))
                        .collect();
                    let want: Vec<(u64, u64)> = (0..passes as u32)
                        .flat_map(|k| restated_dps_chunks(p, c, (frame + k) % 2 == 1))
                        .collect();
                    assert_eq!(got, want, "{passes} passes, frame {frame} (seed 0x{seed:016x})");
                    let sort_stages = if d.list_len == 0 { 0 } else { 1 };
                    assert_eq!(r.stages, sort_stages + passes as usize + 1, "{passes} passes, frame {frame}");
                }
            }
        });
    }

    #[test]
    fn seq_random_tiles_back_to_back() {
        let name = "seq_random_tiles_back_to_back";
        for_each_seed(name, |seed| {
            let cfg = neo_tb::config();
            let mut rng = Rng::new(seed);
            let mut b = bench(name, seed, SeqTiming::RANDOM);
            let (mut cmds, mut cycles) = (0, 0);
            for i in 0..150 {
                b.set_timing(if i % 10 == 9 { SeqTiming::FAST } else { SeqTiming::RANDOM });
                let d = random_desc(&cfg, &mut rng, 12);
                fill(&cfg, &mut rng, &mut b.mem, &d);
                let frame = rng.next_u32();
                let job = SeqJob {
                    desc: d,
                    regs: regs(frame, &d, &mut rng),
                    core: rng.below(cfg.sort_cores as u64),
                };
                let r = b.run(&job);
                cmds += r.commands;
                cycles += r.cycles;
            }
            println!("150 random tiles: {cmds} commands in {cycles} cycles");
        });
    }

    /// Tiles at exactly the table capacity (an empty table with a full list, a list sorted from
    /// scratch, a reused table with an empty list) at the top of the entry space: lengths and
    /// positions reach the capacity's bit, addresses their upper bits. The core holds its done
    /// pulses until a whole stage is in flight (`capacity / C` SORT chunks, `capacity / C + 1`
    /// DPS chunks on an odd frame), so the in-flight count reaches its top bit.
    #[test]
    fn seq_tiles_at_the_table_capacity() {
        let name = "seq_tiles_at_the_table_capacity";
        for_each_seed(name, |seed| {
            let cfg = neo_tb::config();
            let cap = cfg.table_capacity as u32;
            let chunks = (cap / cfg.chunk as u32) as usize;
            let mut rng = Rng::new(seed);
            let mut b = bench(name, seed, SeqTiming::LATE_DONE);
            let top = (1u32 << 28) - 3 * cap;
            // A short tile last, so that every long field falls again. Frame 5 is odd: the DPS
            // of the full table starts with a half chunk.
            for (from_scratch, prev_len, list_len, in_flight) in [
                (false, 0, cap, chunks),
                (true, 0, cap, chunks),
                (false, cap, 0, chunks + 1),
                (false, 1, 1, 1),
            ] {
                let d = TileDescriptor {
                    from_scratch,
                    prev: top,
                    prev_len,
                    list: top + cap,
                    list_len,
                    next: top + 2 * cap,
                    ..TileDescriptor::default()
                };
                fill(&cfg, &mut rng, &mut b.mem, &d);
                let r = b.run(&SeqJob {
                    desc: d,
                    regs: regs(5, &d, &mut rng),
                    core: rng.below(cfg.sort_cores as u64),
                });
                assert_eq!(r.max_in_flight, in_flight, "commands in flight at once: {d:?}");
            }
        });
    }

    #[test]
    fn seq_waits_for_the_bridge_after_the_last_done() {
        // An always-ready core with done pulses at once and a bridge that drains for long: the
        // barrier is all idle_i, so a sequencer that skips it issues early.
        let name = "seq_waits_for_the_bridge_after_the_last_done";
        for_each_seed(name, |seed| {
            let cfg = neo_tb::config();
            let mut rng = Rng::new(seed);
            let timing = SeqTiming { max_drain: 40, ..SeqTiming::FAST };
            let mut b = bench(name, seed, timing);
            let c = cfg.chunk as u32;
            for from_scratch in [false, true] {
                let d = TileDescriptor {
                    from_scratch,
                    prev: 0x10_0000,
                    prev_len: 2 * c,
                    list: 0x20_0000,
                    list_len: 5 * c,
                    next: 0x30_0000,
                    ..TileDescriptor::default()
                };
                fill(&cfg, &mut rng, &mut b.mem, &d);
                let r = b.run(&SeqJob { desc: d, regs: regs(1, &d, &mut rng), core: 0 });
                assert_eq!(r.stages, if from_scratch { 4 } else { 6 });
            }
        });
    }
}
