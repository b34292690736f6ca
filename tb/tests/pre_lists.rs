//! The incoming-list writer (`neo_pre_lists`) against the lists its hits define: random hits on
//! grids of several shapes under a hostile memory, tiles with no hit, a flush with no hit at all,
//! and one tile receiving more than `table_capacity` entries (its list stops at the capacity, its
//! length keeps counting).

#[test]
fn models_present() {
    assert_eq!(neo_tb::require_models("pre_lists: list-writer cosimulation"), neo_tb::HAS_MODELS);
}

neo_tb::with_models! {
    use neo_tb::axi::AxiTiming;
    use neo_tb::check::Checker;
    use neo_tb::lists::{random_hits, Hit, ListsBench};
    use neo_tb::rng::{for_each_seed, Rng};

    #[test]
    fn lists_of_random_hits_and_their_lengths() {
        let name = "lists_of_random_hits_and_their_lengths";
        let cfg = neo_tb::config();
        let mut bench = ListsBench::build(&cfg).unwrap();
        neo_tb::waves::maybe_trace(bench.model_mut(), name);
        for_each_seed(name, |seed| {
            let mut rng = Rng::new(seed);
            // Strips of 1013 columns and 1015 rows (10-bit complements of the small grids' sides,
            // near pre_max_tiles), a frame of no tile at all.
            let grids = [[7u32, 5u32], [1, 1], [1013, 2], [40, 23], [2, 1015], [0, 4], [3, 9]];
            for (k, grid) in grids.into_iter().enumerate() {
                let check = Checker::new("neo_pre_lists", seed ^ k as u64);
                let n = [3000, 13, 600, 5000, 600, 0, 0][k];
                let hits = random_hits(&cfg, &mut rng, grid, n);
                let timing = if k % 2 == 0 { AxiTiming::RANDOM } else { AxiTiming::IDEAL };
                let run = bench.run(grid, &hits, [100, 50, 90, 80, 90, 100, 100][k], timing, &check);
                assert_eq!(run.hits, n as u64);
            }
        });
    }

    /// A capacity that is not a multiple of 8 entries: each tile's region is `list_stride` (the
    /// capacity rounded up to whole lines), not `table_capacity`, so the lines of tile `t > 0`
    /// start at `t * list_stride` (the writer used the capacity until e730618 and no bench saw
    /// it); full tiles stop at 261 entries with 3 zero slots in their last line (the smallest
    /// capacity is the chunk, 256).
    #[test]
    fn a_capacity_off_the_line_size_strides_by_whole_lines() {
        let name = "a_capacity_off_the_line_size_strides_by_whole_lines";
        let cfg = neo_gen::EngineConfig { table_capacity: 261, ..neo_tb::config() };
        assert_ne!(cfg.list_stride(), cfg.table_capacity);
        let mut bench = ListsBench::build(&cfg).unwrap();
        neo_tb::waves::maybe_trace(bench.model_mut(), name);
        for_each_seed(name, |seed| {
            let mut rng = Rng::new(seed);
            // About 330 hits per tile (past the capacity), then about 6 (below it).
            for (k, (grid, n)) in [([3u32, 2u32], 2000), ([7, 5], 200)].into_iter().enumerate() {
                let check = Checker::new("neo_pre_lists", seed ^ k as u64);
                let hits = random_hits(&cfg, &mut rng, grid, n);
                let run = bench.run(grid, &hits, 90, AxiTiming::RANDOM, &check);
                assert_eq!(run.hits, n as u64);
            }
        });
    }

    /// A memory whose B comes 1500 cycles after the last W beat: the writer issues writes until
    /// `pre_outstanding` of them wait for their B (its counter of open writes climbs to the
    /// limit and back to 0), then one per B, and loses nothing. 1200 hits on 2 x 2 tiles: about
    /// 150 full lines.
    #[test]
    fn writes_wait_for_a_slow_response_up_to_the_outstanding_limit() {
        let name = "writes_wait_for_a_slow_response_up_to_the_outstanding_limit";
        let cfg = neo_tb::config();
        let mut bench = ListsBench::build(&cfg).unwrap();
        neo_tb::waves::maybe_trace(bench.model_mut(), name);
        let check = Checker::new("neo_pre_lists", 13);
        let hits = random_hits(&cfg, &mut Rng::new(13), [2, 2], 1200);
        let slow = AxiTiming { latency: 1500, ..AxiTiming::IDEAL };
        let run = bench.run([2, 2], &hits, 100, slow, &check);
        eprintln!(
            "{name}: {} hits in {} cycles, {} writes open at most",
            run.hits, run.cycles, run.max_writes_in_flight
        );
        assert_eq!(run.max_writes_in_flight, cfg.pre_outstanding as u64, "{run:?}");
    }

    #[test]
    fn a_list_longer_than_the_capacity_stops_there_and_counts_on() {
        let cfg = neo_tb::config();
        let mut bench = ListsBench::build(&cfg).unwrap();
        let check = Checker::new("neo_pre_lists", 7);
        let n = cfg.table_capacity + 11;
        let mut hits: Vec<Hit> = (0..n).map(|k| Hit { tile: [1, 0], id: k as u32, key: (k * 7 % 65536) as u32 }).collect();
        hits.push(Hit { tile: [0, 1], id: 5, key: 9 });
        let run = bench.run([2, 2], &hits, 100, AxiTiming::IDEAL, &check);
        eprintln!("{} hits in {} cycles", run.hits, run.cycles);
        assert!(run.cycles < 2 * n as u64, "one hit per cycle: {} cycles for {} hits", run.cycles, n);
    }
}
