//! The binary32 primitives (`neo_fp_*`, side by side in `neo_fp_bench`, one Verilator build)
//! against golden `hwarith::Native`, bit for bit: >= 200k random operand pairs per primitive
//! (`NEO_TB_VECTORS` for more) under `en_i` stalls, the directed classes, the measured latency
//! of each primitive against `neo_gen::units::fp::latency` and one operation per cycle.

#[cfg(not(neo_has_verilator))]
#[test]
fn fp_skipped_without_verilator() {
    assert!(!neo_tb::require_models(
        "fp_skipped_without_verilator: binary32 primitives cosimulation did not run"
    ));
}

#[cfg(neo_has_verilator)]
mod cosim {
    use neo_gen::units::fp::{label, latency, FpPrim};
    use neo_tb::fp::{directed, directed_vectors, expected, random_vectors, FpBench};
    use neo_tb::rng::{for_each_seed, seed_share, Rng};
    use neo_tb::waves::maybe_trace;
    use std::sync::Mutex;

    /// One model for the tests of this binary (built once; the tests take turns).
    static BENCH: Mutex<Option<FpBench>> = Mutex::new(None);

    fn with_bench(body: impl FnOnce(&mut FpBench)) {
        let mut g = BENCH.lock().unwrap_or_else(|e| e.into_inner());
        let b = g.get_or_insert_with(|| FpBench::build().unwrap_or_else(|e| panic!("neo_fp_bench: {e}")));
        body(b);
        if neo_tb::coverage::at_run_time() {
            // A coverage model writes its data when dropped, and a static is never dropped.
            g.take();
        }
    }

    fn vectors() -> usize {
        std::env::var("NEO_TB_VECTORS").ok().and_then(|v| v.parse().ok()).unwrap_or(200_000)
    }

    #[test]
    fn fp_random_operands_under_stalls() {
        let name = "fp_random_operands_under_stalls";
        with_bench(|b| {
            maybe_trace(&mut b.model, name);
            let mut total = 0;
            for_each_seed(name, |seed| {
                let mut rng = Rng::new(seed);
                let share = seed_share(vectors());
                let mut done = 0;
                for (k, stall) in [0u32, 30, 5, 60].iter().cycle().enumerate() {
                    if done >= share {
                        break;
                    }
                    let n = (share - done).min(share / 4 + 1);
                    let v = random_vectors(&mut rng, n);
                    let run = b.run_checked(seed.wrapping_add(k as u64), &v, *stall);
                    done += run.ops as usize;
                }
                total += done;
                println!("{name}: {done} operand pairs checked on {} primitives", FpPrim::ALL.len() + 1);
            });
            b.model.trace_close();
            // Without NEO_SEED every seed ran its share: the whole count.
            if std::env::var_os("NEO_SEED").is_none() && std::env::var_os("NEO_FIXED_SEEDS").is_none() {
                assert!(total >= vectors(), "{total} < {}", vectors());
            }
        });
    }

    #[test]
    fn fp_directed_classes() {
        let name = "fp_directed_classes";
        with_bench(|b| {
            maybe_trace(&mut b.model, name);
            for_each_seed(name, |seed| {
                for (class, pairs) in directed() {
                    println!("class {class}: {} operand pairs", pairs.len());
                }
                let all = directed_vectors();
                b.run_checked(seed, &all, 0);
                let run = b.run_checked(seed ^ 1, &all, 40);
                assert_eq!(run.ops as usize, all.len());
                assert!(run.cycles > run.ops, "stalls were inserted");
            });
            b.model.trace_close();
        });
    }

    #[test]
    fn fp_directed_classes_hit_their_cases() {
        // The directed operands really are the hard cases (checked on the golden side).
        let has = |class: &str| directed().into_iter().find(|(c, _)| *c == class).map(|(_, p)| p).unwrap();
        let ovf = has("results overflowing to inf");
        assert!(ovf.iter().any(|&(a, b)| expected(FpPrim::Add, a, b) == 0x7F80_0000));
        assert!(ovf.iter().any(|&(a, b)| expected(FpPrim::Mul, a, b) == 0x7F80_0000));
        let under = has("results underflowing into subnormal and to zero");
        assert!(under.iter().any(|&(a, b)| expected(FpPrim::Mul, a, b) == 0));
        assert!(under.iter().any(|&(a, b)| {
            let y = expected(FpPrim::Mul, a, b);
            y != 0 && y < 0x0080_0000
        }));
        let up = has("rounding from subnormal up to the smallest normal");
        assert!(up.iter().any(|&(a, b)| expected(FpPrim::Mul, a, b) == 0x0080_0000));
        let sat = has("to_int at +-2^31");
        assert!(sat
            .iter()
            .any(|&(a, _)| expected(FpPrim::ToInt(neo_golden::hwarith::Round::Floor), a, 0) == 0x8000_0000));
        let big = has("int_to_float of values above 2^24");
        assert!(big
            .iter()
            .any(|&(a, _)| f32::from_bits(expected(FpPrim::FromInt, a, 0)) as i64 != a as i32 as i64));
        assert_eq!(has("widen_half: every half").len(), 65536);
    }

    #[test]
    fn fp_latency_and_ii() {
        let name = "fp_latency_and_ii";
        with_bench(|b| {
            for_each_seed(name, |seed| {
                for (p, measured) in b.measure_latencies(seed) {
                    println!("{name}: {} latency {measured:?} (declared {})", label(p), latency(p));
                    assert_eq!(measured, Some(latency(p)), "{}", label(p));
                }
            });
        });
    }
}

/// `Native` (the bench's golden model) returns the canonical NaN from every arithmetic
/// primitive on the directed vectors, as the RTL does: an optimised build once folded its NaN
/// check after `sqrt` away.
#[test]
fn native_nan_results_are_canonical() {
    use neo_gen::units::fp::FpPrim;
    use neo_golden::hwarith::CANONICAL_NAN;
    use neo_tb::fp::{directed_vectors, native};
    for v in directed_vectors() {
        for p in FpPrim::ALL {
            let y = native(p, v.a, v.b);
            let arithmetic = !matches!(p, FpPrim::ToInt(_) | FpPrim::F16 | FpPrim::FromInt);
            if arithmetic && y & 0x7FFF_FFFF > 0x7F80_0000 {
                assert_eq!(y, CANONICAL_NAN, "{p:?}({:#x}, {:#x}) [{}]", v.a, v.b, v.class);
            }
        }
    }
}

/// The bench's golden operations (`neo_tb::fp::op`, `CMP_OPS`, evaluated by golden's
/// `graph::eval_op`) are the ones the datapath library lowers to the same primitive or
/// comparator output: the primitive bench and the datapath benches check the same mapping.
#[test]
fn golden_ops_round_trip_through_the_datapath_library() {
    use neo_gen::units::fp::{module_name, params, FpPrim};
    use neo_gen::units::pre::datapath::{Library, Lowering};
    use neo_gen::units::pre::library::PreLibrary;
    use neo_tb::fp::{op, CMP_OPS};
    for p in FpPrim::ALL {
        let (o, ty) = op(p);
        match PreLibrary.lower(&o, ty) {
            Lowering::Primitive(prim) => {
                assert_eq!(prim.module, module_name(p), "{p:?} as {o:?}");
                assert_eq!(prim.params, params(p), "{p:?} as {o:?}: parameters");
                assert_eq!(prim.ports.len(), o.args().len(), "{p:?}: operands");
            }
            other => panic!("{p:?} as {o:?} lowers to {other:?}, not a primitive"),
        }
    }
    for ((o, ty), port) in CMP_OPS.iter().zip(["lt_o", "le_o", "eq_o", "max_o", "min_o"]) {
        assert_eq!(PreLibrary.lower(o, *ty), Lowering::Compare { output: port }, "{o:?}");
    }
}

/// Every significand of selected binades (both signs) through every primitive: all subnormals,
/// the two smallest normal binades, f16's subnormal/normal boundary (exponent fields 102, 112,
/// 113) and saturation (142, 143), [0.5, 2) (`to_int`'s .5 boundaries, sqrt's two exponent
/// parities), [2^23, 2^24), [2^30, 2^32) (the integer boundaries) and the largest binade; b is
/// the pattern with its exponent's lowest bit flipped and bit 22 set. About 235 M operations
/// (6 minutes): `cargo test -p neo-tb --release --test fp -- --ignored fp_binade_sweeps`.
#[cfg(neo_has_verilator)]
#[test]
#[ignore]
fn fp_binade_sweeps() {
    use neo_tb::fp::{FpBench, Vector};
    let mut b = FpBench::build().unwrap_or_else(|e| panic!("neo_fp_bench: {e}"));
    let seed = neo_tb::rng::test_seed("fp_binade_sweeps");
    let mut total = 0u64;
    for e in [0u32, 1, 2, 102, 112, 113, 126, 127, 142, 143, 150, 157, 158, 254] {
        for sign in [0u32, 0x8000_0000] {
            let v: Vec<Vector> = (0..1u32 << 23)
                .map(|m| {
                    let a = sign | e << 23 | m;
                    Vector { a, b: (a ^ 0x0080_0000) | 0x0040_0000, class: "binade sweep" }
                })
                .collect();
            total += b.run_checked(seed ^ (e as u64) ^ sign as u64, &v, 0).ops;
        }
        println!("fp_binade_sweeps: exponent field {e} done ({total} operations)");
    }
}
