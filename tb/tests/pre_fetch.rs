//! The Preprocessing Engine's fetch unit (`neo_pre_fetch`) against the bytes of memory: random
//! streams of every record size the baked format has under a hostile memory and output
//! backpressure, then the read window: through a long read latency the default window streams
//! at the port's full bandwidth, and through a longer one at the rate Little's law gives it.

#[test]
fn models_present() {
    assert_eq!(neo_tb::require_models("pre_fetch: fetch-unit cosimulation"), neo_tb::HAS_MODELS);
}

neo_tb::with_models! {
    use neo_gen::units::pre::fetch::max_record_words;
    use neo_gen::EngineConfig;
    use neo_golden::hwpre::bake::{geometry_bytes, sh_bytes, ShPrecision};
    use neo_tb::axi::{AxiMemory, AxiTiming};
    use neo_tb::check::Checker;
    use neo_tb::fetch::{random_memory, FetchBench, Stream};
    use neo_tb::rng::{for_each_seed, Rng};
    use neo_tb::waves::maybe_trace;

    /// Record sizes in words: the geometry record and every SH record that is a whole number of
    /// words, at least a beat.
    fn record_words(cfg: &EngineConfig) -> Vec<u32> {
        let beat_words = cfg.axi_data_bits / 32;
        let mut v = vec![geometry_bytes() / 4];
        for p in [ShPrecision::F32, ShPrecision::F16] {
            for d in 0..=3u8 {
                let b = sh_bytes(d, p);
                if b.is_multiple_of(4) && b / 4 >= beat_words {
                    v.push(b / 4);
                }
            }
        }
        v
    }

    /// A random stream: a record size of the format or any legal one, a base anywhere, often just
    /// below a 4 KiB page end or on an odd word, 0 to 300 records.
    fn random_stream(cfg: &EngineConfig, rng: &mut Rng) -> Stream {
        let sizes = record_words(cfg);
        let words = if rng.percent(70) {
            sizes[rng.below(sizes.len() as u64) as usize]
        } else {
            rng.range(u64::from(cfg.axi_data_bits / 32), u64::from(max_record_words())) as u32
        };
        // A 4 KiB page anywhere in the 32-bit space (below its last 2 MiB: no stream wraps).
        let page = 0x1000 * rng.below((1 << 20) - 512);
        let base = if rng.percent(40) { page + 0x1000 - 4 * rng.range(1, 40) } else { page + 4 * rng.below(1024) };
        let count = if rng.percent(5) { 0 } else { rng.range(1, 300) as u32 };
        Stream { base, words, count }
    }

    #[test]
    fn fetch_random_streams_under_backpressure() {
        let name = "fetch_random_streams_under_backpressure";
        let cfg = neo_tb::config();
        let mut bench = FetchBench::build(&cfg).unwrap();
        maybe_trace(bench.model_mut(), name);
        for_each_seed(name, |seed| {
            let check = Checker::new("neo_pre_fetch", seed);
            let mut rng = Rng::new(seed);
            bench.reset();
            let mut records = 0;
            for _ in 0..6 {
                // A few long streams, or many one-record gathers (as the SH fetch issues them).
                let cmds: Vec<Stream> = if rng.percent(50) {
                    (0..3).map(|_| random_stream(&cfg, &mut rng)).collect()
                } else {
                    (0..rng.range(1, 120)).map(|_| Stream { count: 1, ..random_stream(&cfg, &mut rng) }).collect()
                };
                let mut mem = AxiMemory::new(1, random_memory(&cmds, &mut rng), AxiTiming::RANDOM, rng.next_u64());
                let pace = [(100, 100), (60, 70), (30, 30)][rng.below(3) as usize];
                records += bench.run(&mut mem, &cmds, pace, &mut rng, &check).records;
            }
            assert!(records > 0, "seed {seed:#x}: no record was fetched");
        });
    }

    /// A geometry stream of `count` records through a memory of `latency` cycles at one beat
    /// per cycle, always taken: (beats per cycle, most beats in flight, cycles).
    fn stream_rate(cfg: &EngineConfig, latency: u32, count: u32) -> (f64, u64, u64) {
        let run = neo_tb::fetch::stream_through(cfg, latency, count, 1).unwrap();
        (run.beats as f64 / run.cycles as f64, run.max_beats_in_flight, run.cycles)
    }

    #[test]
    fn the_default_window_streams_at_full_bandwidth_through_400_cycles() {
        let cfg = neo_tb::config();
        let window = cfg.pre_window_beats() as u64;
        let (rate, in_flight, cycles) = stream_rate(&cfg, 400, 4000);
        eprintln!("window {window} beats: {rate:.3} beats/cycle over {cycles} cycles, {in_flight} beats in flight at most");
        assert!(in_flight <= window, "{in_flight} beats in flight above the window of {window}");
        assert!(window < 400 || rate > 0.9, "{rate:.3} beats/cycle with a window of {window} beats and latency 400");
    }

    #[test]
    fn through_a_longer_latency_the_window_sets_the_rate_littles_law_gives() {
        // The same unit with the memory 2000 cycles away: 1024 beats in flight give 0.51.
        let cfg = neo_tb::config();
        let window = cfg.pre_window_beats() as u64;
        let (rate, in_flight, _) = stream_rate(&cfg, 2000, 2000);
        let little = window as f64 / 2000.0;
        eprintln!("window {window} beats, latency 2000: {rate:.3} beats/cycle, Little's law {little:.3}");
        assert!(in_flight <= window, "{in_flight} beats in flight above the window of {window}");
        assert!((rate - little).abs() < 0.15 * little, "{rate:.3} beats/cycle, Little's law gives {little:.3}");
    }

    #[test]
    fn one_record_gathers_keep_the_window_full() {
        // SH records of degree 3 (48 words, 24 beats) gathered one command each, scattered.
        let cfg = neo_tb::config();
        let mut bench = FetchBench::build(&cfg).unwrap();
        bench.reset();
        let check = Checker::new("neo_pre_fetch", 2);
        let mut rng = Rng::new(2);
        let words = sh_bytes(3, ShPrecision::F32) / 4;
        let cmds: Vec<Stream> = (0..300)
            .map(|_| Stream { base: 0x40_0000 + 4 * u64::from(words) * rng.below(20_000), words, count: 1 })
            .collect();
        let timing = AxiTiming { latency: 400, ..AxiTiming::IDEAL };
        let mut mem = AxiMemory::new(1, random_memory(&cmds, &mut rng), timing, 2);
        let run = bench.run(&mut mem, &cmds, (100, 100), &mut rng, &check);
        let rate = run.beats as f64 / run.cycles as f64;
        eprintln!("gathers: {rate:.3} beats/cycle, {} beats in flight at most", run.max_beats_in_flight);
        assert!(rate > 0.85, "{rate:.3} beats/cycle for one-record gathers through 400 cycles");
    }

    #[test]
    fn a_slow_consumer_fills_the_buffer_and_loses_nothing() {
        // 200 SH records (4800 beats, above the 1024-beat window) taken 3% of the cycles: the
        // buffer fills, and reads must wait for room instead of overwriting it.
        let cfg = neo_tb::config();
        let mut bench = FetchBench::build(&cfg).unwrap();
        bench.reset();
        let check = Checker::new("neo_pre_fetch", 3);
        let mut rng = Rng::new(3);
        let words = sh_bytes(3, ShPrecision::F32) / 4;
        let cmds = [Stream { base: 0x50_0004, words, count: 200 }];
        let mut mem = AxiMemory::new(1, random_memory(&cmds, &mut rng), AxiTiming::RANDOM, 3);
        let run = bench.run(&mut mem, &cmds, (100, 3), &mut rng, &check);
        assert!(run.max_beats_in_flight <= cfg.pre_window_beats() as u64, "{run:?}");
    }
}
