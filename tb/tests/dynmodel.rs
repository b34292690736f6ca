//! A model built and loaded at run time (`neo_tb::dynmodel`) behaves as the statically linked
//! one: the harness's adder fixture, built both ways, gives the same outputs cycle by cycle.

use neo_gen::interface::ModuleInterface;
use neo_tb::dynmodel::DynModel;
use neo_tb::rng::Rng;

fn fixture() -> (ModuleInterface, Vec<(String, String)>) {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures");
    let json = std::fs::read_to_string(dir.join("neo_tb_adder.json")).expect("fixture json");
    let iface: ModuleInterface = serde_json::from_str(&json).expect("fixture interface");
    let text = std::fs::read_to_string(dir.join("neo_tb_adder.v")).expect("fixture verilog");
    (iface, vec![("neo_tb_adder.v".to_string(), text)])
}

neo_tb::with_models! {
    use neo_tb::dut::Dut;
    use neo_tb::models::NeoTbAdder;

    #[test]
    fn a_run_time_model_matches_the_static_one_cycle_by_cycle() {
        let (iface, files) = fixture();
        let (mut dynm, info) = DynModel::build(&iface, &files, None).expect("build");
        println!("library {} (cached {}, {:.1} s)", info.library.display(), info.cached, info.seconds);
        let mut stat = NeoTbAdder::new();
        dynm.reset();
        Dut::reset(&mut stat);
        let seed = neo_tb::rng::test_seed("dynmodel");
        let mut rng = Rng::new(seed);
        for cycle in 0..500u64 {
            for (i, p) in iface.ports.iter().enumerate() {
                if p.dir != neo_gen::interface::Dir::In || p.name == "clk_i" || p.name == "rst_ni" {
                    continue;
                }
                let words: Vec<u32> = (0..p.width.div_ceil(32)).map(|_| rng.next_u64() as u32).collect();
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
}
