//! `neo_raster_window` (the raster core's reorder window, generated for configurations whose
//! `raster_window` is above 1) against golden `raster::window::window_order`: random streams,
//! and the adversarial ones (already in order, reversed, one key with ids reversed, the smallest
//! entry last, a stream shorter than the window, an empty one), at windows of 4, 16 and 64, with idle cycles, ignored pops during pushes, pops past the end, and a clear
//! in the middle of a stream. Every emission's key, id and feature word is checked in order.

/// Without Verilator the cosimulation below is compiled out: SKIP, or a failure when `CI` is set.
#[test]
fn window_models_present() {
    assert_eq!(
        neo_tb::require_models("window_models_present: reorder-window cosimulation"),
        neo_tb::HAS_MODELS
    );
}

neo_tb::with_models! {
use neo_gen::EngineConfig;
use neo_tb::dut::Clocked;
use neo_tb::rng::{for_each_seed, Rng};
use neo_tb::waves::maybe_trace;
use neo_tb::window::{WindowBench, WindowEntry};

/// The windows benched: the window benches' core (16 entries, [`neo_tb::configs::raster_window`],
/// whose Verilog `scripts/mutate-check` mutates), the smallest (4) and a larger one (64).
fn configs() -> Vec<EngineConfig> {
    let mut all = vec![neo_tb::configs::raster_window()];
    all.extend([4, 64].map(|w| EngineConfig { raster_window: w, ..EngineConfig::default() }));
    all
}

/// A stream of `n` entries with keys from `key`, distinct ids and random feature words.
fn stream<M: Clocked>(b: &mut WindowBench<M>, rng: &mut Rng, n: usize, key: impl Fn(usize, &mut Rng) -> u32) -> Vec<WindowEntry> {
    let mut ids: Vec<u32> = (0..n as u32).map(|i| i * 7 + 3).collect();
    rng.shuffle(&mut ids);
    (0..n).map(|i| WindowEntry { key: key(i, rng), id: ids[i], feat: b.random_feat() }).collect()
}

#[test]
fn raster_window_emits_golden_order() {
    let name = "raster_window_emits_golden_order";
    for cfg in configs() {
        let w = cfg.raster_window;
        for_each_seed(name, |seed| {
            let mut b = WindowBench::build(&cfg, seed).unwrap_or_else(|e| panic!("window {w}: {e}"));
            maybe_trace(&mut b.dut, &format!("{name}_{w}"));
            let mut rng = Rng::new(seed ^ 0x5eed);
            let mut cases: Vec<(String, Vec<WindowEntry>)> = Vec::new();
            for k in 0..12 {
                let n = rng.below(4 * w as u64) as usize;
                let s = stream(&mut b, &mut rng, n, |_, r| r.below(1 << 16) as u32);
                cases.push((format!("random {k} ({n} entries)"), s));
            }
            let n = 3 * w + 5;
            cases.push(("in order".into(), stream(&mut b, &mut rng, n, |i, _| i as u32 * 3)));
            cases.push(("reversed".into(), stream(&mut b, &mut rng, n, |i, _| (n - i) as u32)));
            let mut same = stream(&mut b, &mut rng, n, |_, _| 77);
            for (i, e) in same.iter_mut().enumerate() {
                e.id = (n - i) as u32;
            }
            cases.push(("one key, ids reversed".into(), same));
            cases.push(("smallest last".into(), stream(&mut b, &mut rng, n, |i, _| if i == n - 1 { 0 } else { 100 + i as u32 })));
            cases.push(("shorter than the window".into(), stream(&mut b, &mut rng, w - 2, |_, r| r.below(50) as u32)));
            cases.push(("empty".into(), Vec::new()));
            let mut cycles = 0;
            for (label, s) in &cases {
                if rng.percent(25) && !s.is_empty() {
                    let part = rng.below(s.len() as u64) as usize;
                    b.abandon(s, part);
                }
                cycles += b.run(s);
                let _ = label;
            }
            let entries: usize = cases.iter().map(|(_, s)| s.len()).sum();
            println!("{name}: window {w}: {} streams, {entries} entries in {cycles} cycles", cases.len());
            assert!(entries > 0 && cycles as usize >= entries, "every entry takes a cycle");
        });
    }
}
}
