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
    println!("SKIP: neo-tb was built without Verilator; sequencer cosimulation did not run");
}

#[cfg(neo_has_verilator)]
mod cosim {
    use neo_golden::engine::{FrameRegs, TileDescriptor};
    use neo_tb::rng::{for_each_seed, Rng};
    use neo_tb::seq::{fill, random_desc, SeqBench, SeqJob, SeqTiming};
    use neo_tb::waves::maybe_trace;

    fn bench(name: &str, seed: u64, timing: SeqTiming) -> SeqBench {
        let mut b = SeqBench::new(&neo_tb::config(), seed, timing);
        maybe_trace(&mut b.dut, name);
        b
    }

    fn regs(frame: u32, rng: &mut Rng) -> FrameRegs {
        FrameRegs { frame, scratch_base: 0x800_0000 + 8 * rng.below(1 << 12), ..FrameRegs::default() }
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
                            };
                            fill(&cfg, &mut rng, &mut b.mem, &d);
                            let job = SeqJob {
                                desc: d,
                                regs: regs(frame, &mut rng),
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
                let job =
                    SeqJob { desc: d, regs: regs(frame, &mut rng), core: rng.below(cfg.sort_cores as u64) };
                let r = b.run(&job);
                cmds += r.commands;
                cycles += r.cycles;
            }
            println!("150 random tiles: {cmds} commands in {cycles} cycles");
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
                let r = b.run(&SeqJob { desc: d, regs: regs(1, &mut rng), core: 0 });
                assert_eq!(r.stages, if from_scratch { 4 } else { 6 });
            }
        });
    }
}
