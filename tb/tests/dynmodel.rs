//! A model built and loaded at run time (`neo_tb::dynmodel`) behaves as the statically linked
//! one: the harness's adder fixture, built both ways, gives the same outputs cycle by cycle. Its
//! FST-traced build (`WAVES=fst`, `neo cosim --waves F.fst`) writes an FST file, also as a
//! bench does under `WAVES=fst` (`neo_tb::waves::trace_to`: `<test>.fst` and a `.gtkw` naming
//! it; the same cached model, so no extra build). Its
//! two-thread build (Verilator `--threads 2`, `neo bench engine --threads 2`) is a cache entry
//! of its own and gives the same outputs. A variant whose counter lacks its reset shows the X
//! check (`neo_tb::xinit`): the counter starts from a random value, the same for the same bench
//! seed and another for another seed, while the inputs start at zero.

use neo_gen::interface::ModuleInterface;
use neo_tb::dynmodel::DynModel;
use neo_tb::rng::Rng;
use neo_tb::waves::WaveFormat;

fn fixture() -> (ModuleInterface, Vec<(String, String)>) {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures");
    let json = std::fs::read_to_string(dir.join("neo_tb_adder.json")).expect("fixture json");
    let iface: ModuleInterface = serde_json::from_str(&json).expect("fixture interface");
    let text = std::fs::read_to_string(dir.join("neo_tb_adder.v")).expect("fixture verilog");
    (iface, vec![("neo_tb_adder.v".to_string(), text)])
}

/// Without Verilator the cosimulation below is compiled out: SKIP, or a failure when `CI` is set.
#[test]
fn models_present() {
    assert_eq!(
        neo_tb::require_models("models_present: run-time models against the static ones"),
        neo_tb::HAS_MODELS
    );
}

neo_tb::with_models! {
    use neo_tb::dut::Dut;
    use neo_tb::models::NeoTbAdder;

    #[test]
    fn a_run_time_model_matches_the_static_one_cycle_by_cycle() {
        let (iface, files) = fixture();
        let (dynm, info) = DynModel::build(&iface, &files, None).expect("build");
        matches_static(&iface, dynm, &info);
    }

    #[test]
    fn an_untraced_run_time_model_matches_the_static_one_and_writes_no_waves() {
        let (iface, files) = fixture();
        let (mut dynm, info) = DynModel::build_traced(&iface, &files, None, None).expect("build");
        assert!(info.library.parent().expect("dir").to_string_lossy().contains("dyn-neo_tb_adder-untraced-"));
        assert_eq!(dynm.wave_format(), None);
        let dir = neo_tb::waves::target_dir().join("waves");
        let e = dynm.trace_open(&dir.join("untraced.vcd")).expect_err("no tracing");
        assert!(e.to_string().contains("built to trace nothing"), "{e}");
        matches_static(&iface, dynm, &info);
    }

    #[test]
    fn a_two_thread_run_time_model_matches_the_static_one() {
        let (iface, files) = fixture();
        let e = DynModel::build_threaded(&iface, &files, None, None, 0).err().expect("0 threads refused");
        assert!(e.contains("at least 1"), "{e}");
        if std::thread::available_parallelism().map_or(1, |n| n.get()) < 2 {
            neo_tb::skip(
                "a_two_thread_run_time_model_matches_the_static_one",
                "Verilator --threads 2 needs two hardware threads",
            );
            return;
        }
        let (dynm, info) = DynModel::build_threaded(&iface, &files, None, None, 2).expect("build");
        let dir = info.library.parent().expect("dir").to_string_lossy().into_owned();
        assert!(dir.contains("dyn-neo_tb_adder-untraced-t2-"), "{dir}");
        matches_static(&iface, dynm, &info);
    }

    fn matches_static(iface: &ModuleInterface, mut dynm: DynModel, info: &neo_tb::dynmodel::BuildInfo) {
        println!("library {} (cached {}, {:.1} s)", info.library.display(), info.cached, info.seconds);
        let mut stat = NeoTbAdder::new();
        dynm.reset();
        Dut::reset(&mut stat);
        let seed = neo_tb::rng::test_seed("dynmodel");
        let mut rng = Rng::new(seed);
        for cycle in 0..500u64 {
            for (i, words) in random_inputs(iface, &mut rng) {
                dynm.set_words(i, &words);
                stat.set_words(i, &words);
            }
            dynm.tick();
            Dut::tick(&mut stat);
            for (i, p) in iface.ports.iter().enumerate() {
                let n = p.width.div_ceil(32) as usize;
                let (mut a, mut b) = (vec![0u32; n], vec![0u32; n]);
                dynm.get_words(i, &mut a);
                stat.get_words(i, &mut b);
                assert_eq!(a, b, "seed {seed} cycle {cycle}: port {} differs (run-time vs static)", p.name);
            }
        }
        assert_eq!(dynm.cycle(), 500);
        assert!(dynm.port("no_such_port").unwrap_err().contains("neo_tb_adder has no port no_such_port"));
    }

    /// The X check (`neo_tb::xinit`, `--x-initial unique`): the fixture with `count_q`'s reset
    /// removed counts from the value the model was constructed with, drawn from the bench seed
    /// (the same seed, the same value; another seed, another value), not from zero.
    #[test]
    fn an_unreset_register_starts_from_the_bench_seeds_random_value() {
        let (iface, mut files) = fixture();
        let reset = "      count_q    <= 64'd0;\n    end else begin";
        assert!(files[0].1.contains(reset), "the fixture's count_q reset moved");
        files[0].1 = files[0].1.replace(reset, "    end else begin");
        let (_, info) = DynModel::build_traced(&iface, &files, None, None).expect("build");
        println!("library {} (cached {}, {:.1} s)", info.library.display(), info.cached, info.seconds);
        let count = iface.ports.iter().position(|p| p.name == "out_count_o").expect("out_count_o");
        let tag = iface.ports.iter().position(|p| p.name == "in_tag_i").expect("in_tag_i");
        let start = |seed: u64| {
            neo_tb::xinit::enter("xinit", seed);
            let mut m = DynModel::load(&iface, &info.library, None).expect("load");
            assert_eq!(m.get_u64(tag), 0, "an input starts at zero");
            m.reset();
            m.get_u64(count)
        };
        let (a, b, c) = (start(1), start(1), start(2));
        println!("count_q after reset: 0x{a:016x} (seed 1, twice), 0x{c:016x} (seed 2)");
        match neo_tb::xinit::XInit::from_env() {
            neo_tb::xinit::XInit::Random => {
                assert_eq!(a, b, "the same bench seed gives the same initial value");
                assert_ne!(a, c, "another bench seed gives another initial value");
                assert_ne!(a, 0, "a random 64-bit initial value");
            }
            neo_tb::xinit::XInit::Zero => assert_eq!((a, c), (0, 0)),
            neo_tb::xinit::XInit::Ones => assert_eq!((a, c), (u64::MAX, u64::MAX)),
        }
    }

    /// Random words for every input port but the clock and reset: `(port index, words)`.
    fn random_inputs(iface: &ModuleInterface, rng: &mut Rng) -> Vec<(usize, Vec<u32>)> {
        let ports = iface.ports.iter().enumerate();
        ports
            .filter(|(_, p)| p.dir == neo_gen::interface::Dir::In && p.name != "clk_i" && p.name != "rst_ni")
            .map(|(i, p)| (i, (0..p.width.div_ceil(32)).map(|_| rng.next_u64() as u32).collect()))
            .collect()
    }

    /// Big-endian u64 at `at` (FST header fields).
    fn be64(b: &[u8], at: usize) -> u64 {
        u64::from_be_bytes(b[at..at + 8].try_into().expect("8 bytes"))
    }

    #[test]
    fn an_fst_traced_model_writes_an_fst_file() {
        let (iface, files) = fixture();
        let (mut m, info) = DynModel::build_traced(&iface, &files, None, Some(WaveFormat::Fst)).expect("build");
        println!("library {} (cached {}, {:.1} s) {}", info.library.display(), info.cached, info.seconds, info.log);
        assert!(info.library.parent().expect("dir").to_string_lossy().contains("dyn-neo_tb_adder-fst-"));
        assert_eq!(m.wave_format(), Some(WaveFormat::Fst));
        let dir = neo_tb::waves::target_dir().join("waves");
        std::fs::create_dir_all(&dir).expect("waves dir");
        let vcd = dir.join("dynmodel_adder_wrong.vcd");
        let e = m.trace_open(&vcd).expect_err("an FST model refuses a .vcd path");
        assert!(e.to_string().contains("built to trace FST"), "{e}");
        let fst = dir.join("dynmodel_adder.fst");
        let _ = std::fs::remove_file(&fst);
        m.trace_open(&fst).expect("trace_open");
        m.reset();
        let mut rng = Rng::new(7);
        for _ in 0..200 {
            for (i, words) in random_inputs(&iface, &mut rng) {
                m.set_words(i, &words);
            }
            m.tick();
        }
        m.trace_close();
        let b = std::fs::read(&fst).expect("the FST file exists");
        println!("{}: {} bytes", fst.display(), b.len());
        assert!(b.len() > 329, "more than the header block: {} bytes", b.len());
        // FST header block: tag FST_BL_HDR (0), section length 329, start time, end time, the
        // endian test double e (native order), ..., variable count at +49.
        assert_eq!(b[0], 0, "FST_BL_HDR");
        assert_eq!(be64(&b, 1), 329, "header section length");
        let e = f64::from_ne_bytes(b[25..33].try_into().expect("8 bytes"));
        assert_eq!(e, std::f64::consts::E, "endian test");
        // 4 reset cycles and 200 more, two dumps a cycle, 10 time units a cycle.
        assert!(be64(&b, 17) >= 10 * 200, "end time {} covers the run", be64(&b, 17));
        assert!(be64(&b, 49) >= iface.ports.len() as u64, "a variable per port at least: {}", be64(&b, 49));

        let (mut v, _) = DynModel::build(&iface, &files, None).expect("the VCD build");
        let e = v.trace_open(&fst).expect_err("a VCD model refuses an .fst path");
        assert!(e.to_string().contains("built to trace VCD"), "{e}");
    }

    #[test]
    fn waves_fst_writes_an_fst_and_a_save_file_naming_it() {
        let format = neo_tb::waves::format_of("fst").expect("WAVES=fst").expect("waves");
        assert_eq!(format, WaveFormat::Fst);
        let (iface, files) = fixture();
        let (mut m, info) = DynModel::build_traced(&iface, &files, None, Some(format)).expect("build");
        println!("library {} (cached {}, {:.1} s) {}", info.library.display(), info.cached, info.seconds, info.log);
        let dir = tempfile::tempdir().expect("tempdir");

        // A model that traces VCD refuses WAVES=fst, naming the fix.
        let mut stat = NeoTbAdder::new();
        if neo_tb::waves::MODEL_FORMAT == WaveFormat::Vcd {
            let e = neo_tb::waves::try_trace_to(&mut stat, dir.path(), "static", format).expect_err("VCD model");
            assert!(e.contains("WAVES=fst") && e.contains("traces VCD"), "{e}");
            assert!(!dir.path().join("static.fst").exists());
        }

        let fst = neo_tb::waves::trace_to(&mut m, dir.path(), "adder_bench", format);
        assert_eq!(fst, dir.path().join("adder_bench.fst"));
        m.reset();
        let mut rng = Rng::new(neo_tb::rng::test_seed("waves_fst"));
        for _ in 0..100 {
            for (i, words) in random_inputs(&iface, &mut rng) {
                m.set_words(i, &words);
            }
            m.tick();
        }
        m.trace_close();
        let b = std::fs::read(&fst).expect("the .fst exists");
        assert!(!b.is_empty(), "{} is empty", fst.display());
        // An FST file opens with its header block: block type FST_BL_HDR (0), then the section
        // length (329, big-endian).
        assert_eq!(b[0], 0, "FST_BL_HDR first");
        assert_eq!(be64(&b, 1), 329, "header section length");
        assert!(be64(&b, 17) >= 10 * 100, "end time {} covers the run", be64(&b, 17));
        let gtkw = std::fs::read_to_string(dir.path().join("adder_bench.gtkw")).expect("the .gtkw exists");
        assert!(gtkw.starts_with(&format!("[dumpfile] \"{}\"\n", fst.display())), "{gtkw}");
        assert!(gtkw.contains("TOP.neo_tb_adder.out_sum_o[99:0]"), "{gtkw}");
    }
}
