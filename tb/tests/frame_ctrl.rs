//! `neo_frame_ctrl` with Rust playing AXI client 0's memory, the sequencers, the raster cores
//! and the bridges (see `neo_tb::frame`): every tile sorted once (unless it overflows) by the
//! sequencer the scheduler names, rastered once after its sort with the right command, every
//! result written once, done only at the very end, overflow registers as golden's.

#[cfg(not(neo_has_verilator))]
#[test]
fn frame_ctrl_skipped_without_verilator() {
    // Prints SKIP (or fails when CI is set); the models must really be absent in this build.
    assert!(!neo_tb::require_models(
        "frame_ctrl_skipped_without_verilator: frame controller cosimulation did not run"
    ));
}

#[cfg(neo_has_verilator)]
mod cosim {
    use neo_golden::engine::adapt::{ADAPT_ENABLE, ADAPT_WIDE};
    use neo_tb::frame::{random_case, FrameBench};
    use neo_tb::rng::{for_each_seed, Rng};
    use neo_tb::waves::maybe_trace;

    #[test]
    fn frame_ctrl_random_frames() {
        let name = "frame_ctrl_random_frames";
        for_each_seed(name, |seed| {
            let cfg = neo_tb::config();
            let mut rng = Rng::new(seed);
            let mut b = FrameBench::new(&cfg, seed);
            maybe_trace(&mut b.dut, name);
            let (mut total, mut planned) = ((0, 0, 0), 0);
            // 4095 tiles, most of them overflowing: TILES, the tile counters and OVERFLOWS run
            // through their low 12 bits.
            for tiles in [0usize, 1, 2, 7, 40, 4095, 100, 3, 64] {
                let huge = if tiles > 1000 { 60 } else { 4 };
                let case = random_case(&cfg, &mut rng, tiles, huge);
                let r = b.run(&case);
                total = (total.0 + tiles, total.1 + r.overflows, total.2 + r.cycles);
                planned += r.planned_extra;
            }
            println!("{} tiles ({} overflowed) in {} cycles", total.0, total.1, total.2);
            assert!(total.1 > 0, "the random frames had no overflowing tile");
            assert!(planned > 0, "the controller planned more than one pass for some tile");
        });
    }

    /// Engines with a wide DPS chunk: the descriptors' wide bit is handed on, and in planned
    /// frames (`ADAPT_CTRL`'s wide bit random) each tile's passes and wide bit are golden
    /// `engine_passes` of its previous result, reaches drawn up to 6 wide chunks.
    #[test]
    fn frame_ctrl_wide_plans_in_other_configurations() {
        let name = "frame_ctrl_wide_plans_in_other_configurations";
        neo_tb::configs::run_in_other_configurations(
            name,
            neo_tb::configs::sort_wide(),
            |cfg| FrameBench::build(cfg, 0),
            |b| &mut b.dut,
            |b, cfg, seed| {
                b.reseed(seed);
                let mut rng = Rng::new(seed);
                let (mut planned, mut wide) = (0, 0);
                for (k, tiles) in [1usize, 40, 100, 64, 7, 200, 33, 90].into_iter().enumerate() {
                    // A third of the frames as drawn, a third planned with the wide bit, a third
                    // planned without it.
                    let mut case = random_case(cfg, &mut rng, tiles, 4);
                    let ctrl = &mut case.regs.adapt.ctrl;
                    match k % 3 {
                        1 => *ctrl |= ADAPT_ENABLE | ADAPT_WIDE,
                        2 => *ctrl = (*ctrl | ADAPT_ENABLE) & !ADAPT_WIDE,
                        _ => {}
                    }
                    let r = b.run(&case);
                    (planned, wide) = (planned + r.planned_extra, wide + r.planned_wide);
                }
                println!("{name}: {planned} tiles planned more than one pass, {wide} the wide chunk");
                assert!(planned > 0 && wide > 0, "the controller planned more passes and the wide chunk");
            },
        );
    }
}
