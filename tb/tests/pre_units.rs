//! The Preprocessing Engine's datapaths (`gen/src/units/pre`) against golden's graphs
//! (`Graph::eval`, the `Native` evaluation): the inline logic of the datapath library on edge
//! values, then the units on random and directed inputs, under random valid/ready backpressure,
//! with their depth and one-item-per-cycle rate checked.

#[test]
fn models_present() {
    assert_eq!(neo_tb::require_models("pre_units: datapath cosimulation"), neo_tb::HAS_MODELS);
}

neo_tb::with_models! {
    use neo_gen::units::pre::datapath::Datapath;
    use neo_gen::units::pre::library::PreLibrary;
    use neo_golden::hwarith::graph::{Graph, Trace};
    use neo_golden::hwarith::Arith;
    use neo_tb::check::Checker;
    use neo_tb::datapath::DatapathBench;
    use neo_tb::rng::{for_each_seed, Rng};

    /// Every inline operation of the library on two floats and two integers.
    fn inline_graph() -> Graph {
        let mut t = Trace::new();
        let a = t.input_f("a", false);
        let b = t.input_f("b", false);
        let i = t.input_i("i", false);
        let j = t.input_i("j", false);
        let outs_f = [
            ("neg", t.neg(a)),
            ("abs", t.abs(b)),
            ("max", t.max(a, b)),
            ("min", t.min(a, b)),
            ("pow2", t.pow2_field(i)),
        ];
        let lt = t.lt(a, b);
        let le = t.le(a, b);
        let eq = t.eq(a, b);
        let nan = t.is_nan(a);
        let fin = t.is_finite(b);
        let ilt = t.ilt(i, j);
        let ieq = t.ieq(i, j);
        let and = t.and(lt, ilt);
        let or = t.or(eq, ieq);
        let not = t.not(le);
        let sel = t.select(ilt, a, b);
        let outs_i = [
            ("exp", t.exp_field(a)),
            ("iadd", t.iadd(i, j)),
            ("isub", t.isub(i, j)),
            ("imin", t.imin(i, j)),
            ("imax", t.imax(i, j)),
            ("isel", t.iselect(lt, i, j)),
        ];
        for (n, v) in outs_f {
            t.output_f(n, v);
        }
        t.output_f("sel", sel);
        for (n, v) in outs_i {
            t.output_i(n, v);
        }
        for (n, v) in [("lt", lt), ("le", le), ("eq", eq), ("nan", nan), ("fin", fin), ("and", and), ("or", or), ("not", not)] {
            t.output_b(n, v);
        }
        t.finish()
    }

    /// Floats that stress compares and sign handling.
    const EDGE_F: [u32; 14] = [
        0x0000_0000, 0x8000_0000, 0x0000_0001, 0x8000_0001, 0x007F_FFFF, 0x0080_0000, 0x3F80_0000,
        0xBF80_0000, 0x7F7F_FFFF, 0x7F80_0000, 0xFF80_0000, 0x7FC0_0000, 0xFFC1_2345, 0x7F80_0001,
    ];
    const EDGE_I: [u32; 9] = [0, 1, 0xFFFF_FFFF, 0x8000_0000, 0x7FFF_FFFF, 254, 255, 127, 0xFFFF_FF00];

    #[test]
    fn inline_logic_on_edge_and_random_values() {
        let name = "inline_logic_on_edge_and_random_values";
        let g = inline_graph();
        let top = Datapath::new(&g, &PreLibrary).module("neo_pre_inline_bench", &[]);
        let mut bench = DatapathBench::build(g, &top, &[]).expect("build");
        for_each_seed(name, |seed| {
            let mut rng = Rng::new(seed);
            let mut items = Vec::new();
            for &a in &EDGE_F {
                for &b in &EDGE_F {
                    let (i, j) = (*rng.pick(&EDGE_I), *rng.pick(&EDGE_I));
                    items.push(vec![a, b, i, j]);
                }
            }
            for _ in 0..5000 {
                let f = |rng: &mut Rng| if rng.percent(30) { *rng.pick(&EDGE_F) } else { rng.next_u32() };
                let small = |rng: &mut Rng| if rng.percent(50) { rng.below(300) as u32 } else { rng.next_u32() };
                items.push(vec![f(&mut rng), f(&mut rng), small(&mut rng), small(&mut rng)]);
            }
            let check = Checker::new("neo_pre_inline_bench", seed);
            for mix in [(100, 100), (60, 70), (30, 100)] {
                bench.run(&items, 0, &mut rng, mix, &check);
            }
        });
    }
}
