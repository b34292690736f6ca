//! `neo_axi_mux #(.PORTS(P))` at P = 3 and P = 8 (the engine's ports) between P Rust-driven
//! random AXI4 managers ([`RandomManager`]) and an [`AxiMemory`] port: random reads and writes
//! (bursts of 1..16 beats, partial strobes) under contention, with random request rates,
//! backpressure, latencies and responses reordered across IDs. Every R beat is checked against
//! the manager's shadow, the memory against the shadows at the end, and every port (the P client
//! ports and the memory port) by an [`AxiChecker`]. The model is built at run time from
//! `neo_axi_mux.v` and a wrapper naming each client's signals ([`neo_tb::axi::mux`]).

#[cfg(not(neo_has_verilator))]
#[test]
fn axi_skipped_without_verilator() {
    // Prints SKIP (or fails when CI is set); the models must really be absent in this build.
    assert!(!neo_tb::require_models("axi_skipped_without_verilator: AXI mux cosimulation did not run"));
}

#[cfg(neo_has_verilator)]
mod cosim {
    use neo_golden::engine::memory::Memory;
    use neo_tb::axi::manager::{RandomManager, Traffic};
    use neo_tb::axi::{AxiBinding, AxiChecker, AxiMemory, AxiTiming, ManagerSignals, SubordinateSignals};
    use neo_tb::check::Checker;
    use neo_tb::dynmodel::DynModel;
    use neo_tb::rng::{for_each_seed, Rng};
    use neo_tb::waves::maybe_trace;

    /// 4 KiB pages of each manager.
    const PAGES: usize = 4;

    /// Transactions per manager (NEO_TB_VECTORS scales them: a tenth of it, at least 100).
    fn transactions(default: usize) -> usize {
        std::env::var("NEO_TB_VECTORS")
            .ok()
            .and_then(|v| v.parse::<usize>().ok())
            .map_or(default, |v| (v / 10).max(100))
    }

    struct Bench {
        dut: DynModel,
        s_ports: Vec<AxiBinding>,
        m_port: AxiBinding,
        mem: AxiMemory,
        mgrs: Vec<RandomManager>,
        s_chk: Vec<AxiChecker>,
        m_chk: AxiChecker,
        chk: Checker,
        beats: u64,
    }

    impl Bench {
        /// A mux of one client per entry of `traffic`.
        fn new(name: &str, seed: u64, timing: AxiTiming, traffic: &[Traffic]) -> Bench {
            let cfg = neo_tb::config();
            let p = traffic.len();
            let o = cfg.axi_outstanding;
            let mut rng = Rng::new(seed);
            let mut mem = Memory::new();
            let mut mgrs = Vec::new();
            // Each manager's PAGES pages at random pages of the 32-bit address space, all apart
            // (every address bit of every port toggles).
            let mut taken = std::collections::HashSet::new();
            for (i, t) in traffic.iter().enumerate() {
                let pages: Vec<u64> = (0..PAGES)
                    .map(|_| loop {
                        let b = 4096 * rng.below((1u64 << 32) / 4096);
                        if taken.insert(b) {
                            break b;
                        }
                    })
                    .collect();
                let mut init = Memory::new();
                for &page in &pages {
                    for w in 0..512 {
                        let v = rng.next_u64();
                        init.write(page + 8 * w, &v.to_le_bytes());
                        mem.write(page + 8 * w, &v.to_le_bytes());
                    }
                }
                mgrs.push(RandomManager::new(&format!("s{i}_axi"), &pages, 0, o, *t, rng.next_u64(), init));
            }
            let mut dut = neo_tb::axi::mux::build(&cfg, p).unwrap_or_else(|e| panic!("{e}"));
            maybe_trace(&mut dut, name);
            let bind = |prefix: &str, manager| AxiBinding::bind(&dut, prefix, manager).expect("port");
            let mut b = Bench {
                s_ports: (0..p).map(|i| bind(&format!("s{i}_axi_"), false)).collect(),
                m_port: bind("m_axi_", true),
                mem: AxiMemory::new(1, mem, timing, rng.next_u64()),
                s_chk: (0..p).map(|i| AxiChecker::new(i, &format!("s{i}_axi"), o, o)).collect(),
                m_chk: AxiChecker::new(p, "m_axi", p * o, p * o),
                chk: Checker::new(&format!("neo_axi_mux #(.PORTS({p}))"), seed),
                mgrs,
                beats: 0,
                dut,
            };
            for i in 0..p {
                b.s_ports[i].set_manager(&mut b.dut, &ManagerSignals::default());
            }
            b.m_port.set_subordinate(&mut b.dut, &SubordinateSignals::default());
            b.dut.reset();
            b
        }

        fn violation(&self, v: Box<neo_tb::axi::Violation>) -> ! {
            panic!("{v} (seed = 0x{s:016x}; reproduce with NEO_SEED=0x{s:016x})", s = self.chk.seed)
        }

        /// One clock cycle of the whole bench.
        fn cycle(&mut self) {
            let ms: Vec<ManagerSignals> = self.mgrs.iter_mut().map(|m| m.drive()).collect();
            for (i, m) in ms.iter().enumerate() {
                self.s_ports[i].set_manager(&mut self.dut, m);
            }
            let mem_out = self.mem.outputs(0);
            self.m_port.set_subordinate(&mut self.dut, &mem_out);
            self.dut.eval();
            let cycle = self.dut.cycle();
            for (i, m) in ms.iter().enumerate() {
                let s = self.s_ports[i].get_subordinate(&self.dut);
                if let Err(v) = self.s_chk[i].observe(m, &s) {
                    self.violation(v);
                }
                self.mgrs[i].clock(m, &s, &self.chk, cycle);
            }
            let down = self.m_port.get_manager(&self.dut);
            if let Err(v) = self.m_chk.observe(&down, &mem_out) {
                self.violation(v);
            }
            self.beats += u64::from(mem_out.r.is_some() && down.rready);
            self.mem.tick(0, &down);
            self.dut.tick();
        }

        /// Runs until every manager is finished and the memory idle; returns the cycles.
        fn run(&mut self, limit: u64) -> u64 {
            let start = self.dut.cycle();
            while !(self.mgrs.iter().all(RandomManager::finished) && self.mem.idle(0)) {
                if self.dut.cycle() - start > limit {
                    let done: Vec<_> = self.mgrs.iter().map(RandomManager::done).collect();
                    self.chk.fail(
                        self.dut.cycle(),
                        "progress (timeout)",
                        &format!("finished within {limit} cycles"),
                        &format!("done (reads, writes) per manager: {done:?}"),
                    );
                }
                self.cycle();
            }
            // The memory holds every manager's shadow.
            for (i, m) in self.mgrs.iter().enumerate() {
                for a in m.pages().iter().flat_map(|&page| (0..512).map(move |w| page + 8 * w)) {
                    self.chk.value(
                        self.dut.cycle(),
                        &format!("memory word at 0x{a:x} (s{i}_axi's page)"),
                        m.shadow().read_u64(a),
                        self.mem.memory().read_u64(a),
                    );
                }
            }
            self.dut.cycle() - start
        }
    }

    fn traffic(n: usize, issue: u32, ready: u32) -> Traffic {
        Traffic {
            reads: n,
            writes: n,
            issue_percent: issue,
            ready_percent: ready,
            max_beats: 16,
            partial_strobe_percent: 25,
        }
    }

    /// The client counts benched: the cosimulated 3 and the engine's 8 slots per port.
    const PORTS: [usize; 2] = [3, 8];

    /// Random traffic, a mix of request rates and backpressure, on `p` clients.
    fn random_traffic_under_contention(p: usize) {
        let name = format!("axi_mux_random_traffic_under_contention_p{p}");
        for_each_seed(&name, |seed| {
            let n = transactions(600);
            let mix = [traffic(n, 90, 80), traffic(n, 60, 50), traffic(n, 95, 95)];
            let mut t: Vec<Traffic> = (0..p).map(|i| mix[i % mix.len()]).collect();
            // With a multiple of 4 clients all requesting, the round robin puts client c's AW in
            // W-queue slot c mod 4 only: the last client's writes end early, then the others
            // rotate through every slot.
            if p.is_multiple_of(4) {
                t[p - 1].writes = n / 4;
            }
            let mut b = Bench::new(&name, seed, AxiTiming::RANDOM, &t);
            let cycles = b.run(400 * (p * n) as u64 / 3);
            let all: usize = t.iter().map(|t| t.reads + t.writes).sum();
            println!("{name}: {all} transactions in {cycles} cycles, {} R beats", b.beats);
        });
    }

    /// Single-beat reads and writes from every one of `p` clients on a fast memory.
    fn single_beat_storm_on_a_fast_memory(p: usize) {
        let name = format!("axi_mux_single_beat_storm_on_a_fast_memory_p{p}");
        for_each_seed(&name, |seed| {
            let n = transactions(1500);
            let t = Traffic { max_beats: 1, partial_strobe_percent: 0, ..traffic(n, 100, 100) };
            let fast = AxiTiming { latency: 2, ..AxiTiming::IDEAL };
            // With a multiple of 4 clients the first one's writes end early (the random-traffic
            // test ends the last one's): the others then rotate through every W-queue slot.
            let mut ts = vec![t; p];
            if p.is_multiple_of(4) {
                ts[0].writes = n / 4;
            }
            let mut b = Bench::new(&name, seed, fast, &ts);
            let cycles = b.run(100 * (p * n) as u64 / 3);
            // Reads and writes go through the port in parallel, one beat per cycle each at best (p n
            // cycles); a mux that took two cycles a write (or serialised reads and writes) needs
            // about 2 p n (1.8 p n with the short client).
            let writes: usize = ts.iter().map(|t| t.writes).sum();
            println!("{name}: {} single-beat transactions in {cycles} cycles", p * n + writes);
            let bound = (p * n) as u64 * 3 / 2;
            assert!(
                cycles < bound,
                "{cycles} cycles (bound {bound}) for {} reads + {writes} writes: the mux serialises",
                p * n,
            );
        });
    }

    /// Long bursts (up to AXI4's 256 beats: every ARLEN/AWLEN bit) from the first client alone,
    /// the last alone, then all `p` together.
    fn long_bursts_one_client_at_a_time_and_all_together(p: usize) {
        let name = format!("axi_mux_long_bursts_one_client_at_a_time_and_all_together_p{p}");
        for_each_seed(&name, |seed| {
            // As many beats as 200 bursts of up to 16 beats each.
            let n = transactions(200) / 16;
            let long = Traffic { max_beats: 256, ..traffic(n, 100, 100) };
            let idle = Traffic { reads: 0, writes: 0, ..long };
            let alone = |k: usize| (0..p).map(|i| if i == k { long } else { idle }).collect::<Vec<_>>();
            for (k, t) in [alone(0), alone(p - 1), vec![long; p]].iter().enumerate() {
                let mut b = Bench::new(
                    &format!("{name}_{k}"),
                    seed ^ k as u64,
                    AxiTiming { reorder: true, ..AxiTiming::IDEAL },
                    t,
                );
                b.run(200 * 16 * (p * n) as u64 / 3);
            }
        });
    }

    #[test]
    fn axi_mux_random_traffic_under_contention() {
        for p in PORTS {
            random_traffic_under_contention(p);
        }
    }

    #[test]
    fn axi_mux_single_beat_storm_on_a_fast_memory() {
        for p in PORTS {
            single_beat_storm_on_a_fast_memory(p);
        }
    }

    #[test]
    fn axi_mux_long_bursts_one_client_at_a_time_and_all_together() {
        for p in PORTS {
            long_bursts_one_client_at_a_time_and_all_together(p);
        }
    }
}
