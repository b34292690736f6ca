//! The fetch unit's bench (`neo_pre_fetch` against the bytes of memory): the driver offers a
//! list of commands (streams of records) under random valid gaps, an [`AxiMemory`] port serves
//! the reads with the chosen timing, an [`AxiChecker`] watches the AXI side, and the checker
//! compares every record (its command, its index, then each word) with the memory's bytes,
//! stopping at the first mismatch. The run reports the beats in flight (the read window the
//! unit really keeps) and the cycles the commands took.

use crate::axi::{AxiBinding, AxiChecker, AxiMemory, ManagerSignals, SubordinateSignals};
use crate::check::Checker;
use crate::dynmodel::DynModel;
use crate::rng::Rng;
use neo_gen::units::pre::fetch::{max_record_words, NAME};
use neo_gen::EngineConfig;

/// One command: a stream of records the unit fetches.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Stream {
    /// Byte address of record 0 (4-byte aligned).
    pub base: u64,
    /// Words per record.
    pub words: u32,
    /// Records.
    pub count: u32,
}

impl Stream {
    /// Bytes the stream covers.
    pub fn bytes(&self) -> u64 {
        4 * u64::from(self.words) * u64::from(self.count)
    }
}

/// What a run measured.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FetchRun {
    /// Records checked.
    pub records: u64,
    /// R beats the unit received.
    pub beats: u64,
    /// Cycles from the start to the last record taken.
    pub cycles: u64,
    /// Most beats requested (AR accepted) and not yet received, over the run.
    pub max_beats_in_flight: u64,
}

/// A Verilated `neo_pre_fetch` and its ports.
pub struct FetchBench {
    cfg: EngineConfig,
    model: DynModel,
    axi: AxiBinding,
    p: Ports,
}

struct Ports {
    cmd_valid: usize,
    cmd_ready: usize,
    base: usize,
    words: usize,
    count: usize,
    busy: usize,
    rec_valid: usize,
    rec_ready: usize,
    rec_data: usize,
    rec_index: usize,
}

impl FetchBench {
    /// Builds (or loads from the cache) the unit of `cfg`.
    pub fn build(cfg: &EngineConfig) -> Result<Self, String> {
        let (files, vlt) = crate::dynmodel::generated_files(cfg, NAME)?;
        let iface = neo_gen::units::pre::fetch::module(cfg).interface();
        let (model, _) = DynModel::build_traced(&iface, &files, Some(&vlt), None)?;
        let q = |n: &str| model.port(n);
        let p = Ports {
            cmd_valid: q("cmd_valid_i")?,
            cmd_ready: q("cmd_ready_o")?,
            base: q("cmd_base_i")?,
            words: q("cmd_words_i")?,
            count: q("cmd_count_i")?,
            busy: q("busy_o")?,
            rec_valid: q("rec_valid_o")?,
            rec_ready: q("rec_ready_i")?,
            rec_data: q("rec_data_o")?,
            rec_index: q("rec_index_o")?,
        };
        let axi = AxiBinding::bind(&model, "m_axi_", true)?;
        Ok(FetchBench { cfg: cfg.clone(), model, axi, p })
    }

    /// The model, for waves.
    pub fn model_mut(&mut self) -> &mut DynModel {
        &mut self.model
    }

    /// Resets the unit.
    pub fn reset(&mut self) {
        self.axi.set_subordinate(&mut self.model, &SubordinateSignals::default());
        self.model.set_u64(self.p.cmd_valid, 0);
        self.model.set_u64(self.p.rec_ready, 0);
        self.model.reset();
    }

    /// Runs `cmds` against port 0 of `mem`, offering a command `offer_percent` of the cycles
    /// and taking records `ready_percent` of them; checks every record and the AXI protocol.
    /// Stops the test at the first mismatch.
    pub fn run(
        &mut self,
        mem: &mut AxiMemory,
        cmds: &[Stream],
        (offer_percent, ready_percent): (u32, u32),
        rng: &mut Rng,
        check: &Checker,
    ) -> FetchRun {
        let o = self.cfg.pre_outstanding;
        let mut axi_chk = AxiChecker::new(0, "m_axi", o, o);
        let start = self.model.cycle();
        let bytes: u64 = cmds.iter().map(|s| s.bytes() + 64).sum();
        let limit = 64 * (bytes / 8 + 1) + 20_000;
        let mut owed: std::collections::VecDeque<(usize, u32)> =
            cmds.iter().enumerate().flat_map(|(c, s)| (0..s.count).map(move |i| (c, i))).collect();
        let (mut run, mut in_flight, mut next, mut held) = (FetchRun::default(), 0u64, 0usize, false);
        let mut words = vec![0u32; max_record_words() as usize];
        loop {
            let (m, p) = (&mut self.model, &self.p);
            let offer = next < cmds.len() && (held || rng.percent(offer_percent));
            let s = cmds.get(next).copied().unwrap_or(Stream { base: 0, words: 0, count: 0 });
            m.set_u64(p.cmd_valid, u64::from(offer));
            m.set_u64(p.base, s.base);
            m.set_u64(p.words, u64::from(s.words));
            m.set_u64(p.count, u64::from(s.count));
            let ready = rng.percent(ready_percent);
            m.set_u64(p.rec_ready, u64::from(ready));
            let sub = mem.outputs(0);
            self.axi.set_subordinate(m, &sub);
            m.eval();
            let cyc = m.cycle();
            let man: ManagerSignals = self.axi.get_manager(m);
            if let Err(v) = axi_chk.observe(&man, &sub) {
                check.fail(cyc, "AXI protocol", "no violation", &v.to_string());
            }
            in_flight = track_in_flight(in_flight, &man, &sub, &mut run);
            let taken = offer && m.get_u64(p.cmd_ready) == 1;
            held = offer && !taken;
            let done = next == cmds.len() && m.get_u64(p.busy) == 0;
            next += usize::from(taken);
            if m.get_u64(p.rec_valid) == 1 && ready {
                let Some((c, i)) = owed.pop_front() else {
                    check.fail(cyc, "rec_valid_o", "no record owed", "1")
                };
                m.get_words(p.rec_data, &mut words);
                check_record(check, cyc, mem, cmds[c], (i, m.get_u64(p.rec_index)), &words);
                run.records += 1;
                run.cycles = cyc + 1 - start;
            }
            mem.tick(0, &man);
            m.tick();
            if done {
                break;
            }
            check.protocol(cyc, cyc - start < limit, "the commands finish within their cycle budget");
        }
        check.value(self.model.cycle(), "records owed after busy_o fell", 0, owed.len() as u64);
        check.value(self.model.cycle(), "AXI reads open after busy_o fell", 0, axi_chk.in_flight().0 as u64);
        run
    }
}

/// The beats in flight after this cycle's handshakes (and the run's beat count and maximum).
fn track_in_flight(mut n: u64, man: &ManagerSignals, sub: &SubordinateSignals, run: &mut FetchRun) -> u64 {
    if let (Some(a), true) = (man.ar, sub.arready) {
        n += u64::from(a.beats());
    }
    if sub.r.is_some() && man.rready {
        n -= 1;
        run.beats += 1;
    }
    run.max_beats_in_flight = run.max_beats_in_flight.max(n);
    n
}

/// Checks record `want` of command `s` (the unit says `index`) against the memory's bytes.
fn check_record(
    check: &Checker,
    cyc: u64,
    mem: &AxiMemory,
    s: Stream,
    (want, index): (u32, u64),
    words: &[u32],
) {
    check.value(cyc, "rec_index_o", u64::from(want), index);
    let index = u64::from(want);
    for (k, &w) in words.iter().enumerate() {
        let want = if (k as u32) < s.words {
            mem.memory().read_u32(s.base + 4 * (index * u64::from(s.words) + k as u64))
        } else {
            0
        };
        check.value(cyc, &format!("record {index} word {k}"), u64::from(want), u64::from(w));
    }
}

/// A memory holding random words over the bytes of `cmds` (and one beat either side).
pub fn random_memory(cmds: &[Stream], rng: &mut Rng) -> neo_golden::engine::memory::Memory {
    let mut mem = neo_golden::engine::memory::Memory::new();
    for s in cmds {
        let (lo, hi) = ((s.base & !7).saturating_sub(8), s.base + s.bytes() + 16);
        let mut a = lo;
        while a < hi {
            mem.write_u64(a, rng.next_u64());
            a += 8;
        }
    }
    mem
}

/// Cycles of read latency the window measurement streams through (about 400 ns at 1 GHz).
pub const MEASURE_LATENCY: u32 = 400;

/// One unit of `cfg` streaming `count` geometry records through a memory of `latency` cycles
/// at one beat per cycle, its records always taken (each one checked).
pub fn stream_through(cfg: &EngineConfig, latency: u32, count: u32, seed: u64) -> Result<FetchRun, String> {
    let mut bench = FetchBench::build(cfg)?;
    bench.reset();
    let check = Checker::new(NAME, seed);
    let mut rng = Rng::new(seed);
    let s = Stream { base: 0x20_0000, words: neo_golden::hwpre::bake::geometry_bytes() / 4, count };
    let timing = crate::axi::AxiTiming { latency, ..crate::axi::AxiTiming::IDEAL };
    let mut mem = AxiMemory::new(1, random_memory(&[s], &mut rng), timing, seed);
    Ok(bench.run(&mut mem, &[s], (100, 100), &mut rng, &check))
}

/// The fetch units' window for `reports/latency.json`: the lines one unit keeps in flight
/// streaming through [`MEASURE_LATENCY`] cycles, times `pre_units`.
pub fn measure_window(cfg: &EngineConfig, seed: u64) -> neo_golden::formats::latency::FetchUnit {
    let run = stream_through(cfg, MEASURE_LATENCY, 4000, seed).unwrap_or_else(|e| panic!("{NAME}: {e}"));
    let beat = u64::from(cfg.axi_data_bits / 8);
    neo_golden::formats::latency::FetchUnit {
        units: cfg.pre_units as u64,
        lines_in_flight: (run.max_beats_in_flight * beat).div_ceil(64),
        read_latency: u64::from(MEASURE_LATENCY),
        beats: run.beats,
        cycles: run.cycles,
    }
}
