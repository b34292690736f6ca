//! The BSU test bench: vectors through `neo_bsu` under random stalls and backpressure, each
//! output checked against golden `Network::apply`, plus the throughput benchmark.

use crate::check::Checker;
use crate::dut::Dut;
use crate::lanes::{pack_lanes, packed, unpack_lanes};
use crate::models::NeoBsu;
use crate::rng::Rng;
use crate::stream::{Sink, Source};
use neo_gen::EngineConfig;
use neo_golden::sort::SortEntry;
use std::collections::VecDeque;
use std::time::Instant;

pub use crate::bench::Throughput;

/// What a BSU run did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BsuRun {
    /// Vectors checked.
    pub vectors: usize,
    /// Cycles from the end of reset to the last output.
    pub cycles: u64,
}

/// Sends `vectors` through a fresh BSU (input stalls with probability `stall_pct`, output ready
/// with probability `ready_pct`), checking each output vector lane by lane against the golden
/// network of `cfg` and the valid/ready rules; panics at the first mismatch.
pub fn run_checked(
    dut: &mut NeoBsu,
    cfg: &EngineConfig,
    seed: u64,
    vectors: &[Vec<SortEntry>],
    stall_pct: u32,
    ready_pct: u32,
) -> BsuRun {
    let fmt = cfg.format();
    let net = cfg.network();
    let n = net.n;
    let mut rng = Rng::new(seed);
    let checker = Checker::new(NeoBsu::NAME, seed);
    let mut src = Source::new::<NeoBsu>("in_valid_i", "in_ready_o", &["in_data_i"], rng.fork(1), stall_pct);
    let mut sink = Sink::new::<NeoBsu>("out_valid_o", "out_ready_i", &["out_data_o"], rng.fork(2), ready_pct);
    let mut expected = VecDeque::with_capacity(vectors.len());
    for v in vectors {
        assert_eq!(v.len(), n, "BSU vectors have {n} entries");
        src.push(vec![packed(&fmt, v)]);
        let mut sorted = v.clone();
        net.apply(&mut sorted);
        expected.push_back(sorted);
    }
    dut.set_in_valid_i(false);
    dut.set_out_ready_i(false);
    dut.reset();
    let mut got = vec![SortEntry::default(); n];
    let mut index = 0usize;
    let limit = 1000 + 100 * vectors.len() as u64;
    while let Some(want) = expected.front() {
        if dut.cycle() > limit {
            checker.fail(dut.cycle(), "out_valid_o", "an output vector", &format!("none for {limit} cycles"));
        }
        src.drive(dut);
        sink.drive(dut);
        dut.eval();
        src.sample(dut);
        if let Some(beat) = sink.sample(dut, &checker) {
            unpack_lanes(&fmt, &beat[0], &mut got);
            for lane in 0..n {
                checker.entry(dut.cycle(), &format!("vector {index} out[{lane}]"), &want[lane], &got[lane]);
            }
            expected.pop_front();
            index += 1;
        }
        dut.tick();
    }
    // Nothing extra comes out.
    for _ in 0..cfg.bsu_latency() + 2 {
        dut.set_in_valid_i(false);
        dut.set_out_ready_i(true);
        dut.eval();
        checker.protocol(dut.cycle(), !dut.out_valid_o(), "an output vector with no input left");
        dut.tick();
    }
    BsuRun { vectors: vectors.len(), cycles: dut.cycle() }
}

/// The BSU at full rate (one random vector per cycle, output always ready), every output
/// compared with golden `Network::apply`: the cosimulation throughput figure. `threads`
/// independent models (each with its own stimulus and golden check) run in parallel and the
/// figures are summed; `vectors` is the total.
///
/// # Panics
/// At the first mismatch.
pub fn throughput(cfg: &EngineConfig, vectors: u64, seed: u64, threads: usize) -> Throughput {
    let threads = threads.max(1) as u64;
    let t = Instant::now();
    let parts: Vec<(u64, u64)> = std::thread::scope(|s| {
        let handles: Vec<_> = (0..threads)
            .map(|k| {
                let share = vectors / threads + u64::from(k < vectors % threads);
                s.spawn(move || full_rate(cfg, share, seed.wrapping_add(k)))
            })
            .collect();
        handles.into_iter().map(|h| h.join().unwrap_or_else(|e| std::panic::resume_unwind(e))).collect()
    });
    let seconds = t.elapsed().as_secs_f64();
    Throughput { vectors: parts.iter().map(|p| p.0).sum(), cycles: parts.iter().map(|p| p.1).sum(), seconds }
}

/// One model at full rate; returns (vectors checked, cycles).
fn full_rate(cfg: &EngineConfig, vectors: u64, seed: u64) -> (u64, u64) {
    let fmt = cfg.format();
    let net = cfg.network();
    let n = net.n;
    let checker = Checker::new(NeoBsu::NAME, seed);
    let mut rng = Rng::new(seed);
    let mut dut = NeoBsu::new();
    dut.set_in_valid_i(false);
    dut.set_out_ready_i(true);
    dut.reset();
    let mut words = [0u32; 24];
    assert_eq!(NeoBsu::PORTS[NeoBsu::port("in_data_i")].words(), words.len(), "bench sized for 16 x 48 bits");
    // Expected vectors in flight: a ring of `depth` vectors, flat.
    let depth = cfg.bsu_latency() + 2;
    let mut ring = vec![SortEntry::default(); depth * n];
    let (mut head, mut tail) = (0usize, 0usize);
    let mut v = vec![SortEntry::default(); n];
    let mut got = vec![SortEntry::default(); n];
    let (mut sent, mut checked) = (0u64, 0u64);
    while checked < vectors {
        // Outputs are registered: they are settled after the previous tick.
        if dut.out_valid_o() {
            unpack_lanes(&fmt, &dut.out_data_o(), &mut got);
            assert!(head < tail, "output without input");
            let want = &ring[(head % depth) * n..(head % depth + 1) * n];
            if got != want {
                for lane in 0..n {
                    checker.entry(
                        dut.cycle(),
                        &format!("vector {checked} out[{lane}]"),
                        &want[lane],
                        &got[lane],
                    );
                }
            }
            head += 1;
            checked += 1;
        }
        // in_ready_o = out_ready_i | ~out_valid_o: always high here.
        if sent < vectors {
            for e in v.iter_mut() {
                *e = random_entry_fast(&fmt, &mut rng);
            }
            pack_lanes(&fmt, &v, &mut words);
            dut.set_in_data_i(&words);
            dut.set_in_valid_i(true);
            net.apply(&mut v);
            ring[(tail % depth) * n..(tail % depth + 1) * n].copy_from_slice(&v);
            tail += 1;
            sent += 1;
        } else {
            dut.set_in_valid_i(false);
        }
        dut.tick();
        checker.protocol(dut.cycle(), dut.in_ready_o(), "in_ready_o low with out_ready_i high");
    }
    (checked, dut.cycle())
}

/// A random entry from one 64-bit draw: uniform key and id, valid with probability 3/4 (ties
/// are rare here; the checked test benches cover them).
#[inline]
fn random_entry_fast(fmt: &neo_golden::sort::SortFormat, rng: &mut Rng) -> SortEntry {
    let r = rng.next_u64();
    let valid = (r >> 62) != 0;
    fmt.unpack(r & ((1u64 << (fmt.entry_bits() - 1)) - 1)).with_valid(valid)
}
