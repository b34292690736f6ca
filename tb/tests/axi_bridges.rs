//! `neo_axi_sort_bridge` and `neo_axi_raster_bridge` between a Rust model of their core's memory
//! port (random requests, random response backpressure) and an [`AxiMemory`] port, with an
//! [`AxiChecker`] on the AXI side (4 KiB, outstanding limits, WLAST, ...).
//!
//! Reads come from read-only regions (bursts straddling 4 KiB pages are common) and are checked
//! beat by beat; writes go to their own regions and are checked in memory once the bridge is idle.
//! Every cycle: the pulses match the core-side handshakes, and `idle_o` implies nothing is in
//! flight (no response owed to the core, the memory and the checker see no open transaction).

#[cfg(not(neo_has_verilator))]
#[test]
fn axi_bridges_skipped_without_verilator() {
    // Prints SKIP (or fails when CI is set); the models must really be absent in this build.
    assert!(!neo_tb::require_models(
        "axi_bridges_skipped_without_verilator: AXI bridge cosimulation did not run"
    ));
}

#[cfg(neo_has_verilator)]
mod cosim {
    use neo_golden::engine::memory::{pixel_to_u32, Memory};
    use neo_golden::raster::RGB_BITS;
    use neo_tb::axi::{AxiBinding, AxiChecker, AxiMemory, AxiTiming, SubordinateSignals};
    use neo_tb::bits::{mask, set_bits};
    use neo_tb::check::Checker;
    use neo_tb::dut::Dut;
    use neo_tb::models::{NeoAxiRasterBridge, NeoAxiSortBridge};
    use neo_tb::rng::{for_each_seed, Rng};
    use neo_tb::waves::maybe_trace;
    use std::collections::{HashMap, VecDeque};

    fn requests() -> usize {
        std::env::var("NEO_TB_VECTORS")
            .ok()
            .and_then(|v| v.parse::<usize>().ok())
            .map_or(3000, |v| (v / 3).max(300))
    }

    /// Read-only table regions of 2 pages (1024 entries) each.
    const RD_REGIONS: usize = 8;
    const RD_ENTRIES: u64 = 1024;
    /// Write regions of 2 pages (1024 entries) each.
    const WR_REGIONS: usize = 8;
    const WR_ENTRIES: u64 = 1024;
    /// Read-only feature regions (feature words).
    const FEAT_REGIONS: usize = 4;
    const FEAT_WORDS: u64 = 256;
    /// Pixel regions (rows of S pixels).
    const PIX_REGIONS: usize = 8;
    const PIX_ROWS: u64 = 64;

    /// The regions, spread over the whole 32-bit byte address space (random 4 KiB pages, apart
    /// from each other): entry addresses below 2^29, feature words below 2^27, pixels below
    /// 2^30, as 32-bit byte addresses allow. The memories are sparse ([`Memory`]).
    struct Regions {
        /// First entry of each table region.
        rd: Vec<u64>,
        /// First entry of each write region.
        wr: Vec<u64>,
        /// First word of each feature region.
        feat: Vec<u64>,
        /// First pixel of each pixel region.
        pix: Vec<u64>,
    }

    impl Regions {
        fn new(rng: &mut Rng, s: u64) -> Regions {
            let mut taken: Vec<(u64, u64)> = Vec::new();
            // A random page-aligned byte range of `bytes`, clear of the others.
            let mut place = |rng: &mut Rng, bytes: u64| loop {
                let b = 4096 * rng.below(((1u64 << 32) - bytes) / 4096);
                if taken.iter().all(|&(lo, hi)| b + bytes <= lo || hi <= b) {
                    taken.push((b, b + bytes));
                    break b;
                }
            };
            let rd = (0..RD_REGIONS).map(|_| place(rng, 8 * RD_ENTRIES) / 8).collect();
            let wr = (0..WR_REGIONS).map(|_| place(rng, 8 * WR_ENTRIES) / 8).collect();
            let feat = (0..FEAT_REGIONS).map(|_| place(rng, 32 * FEAT_WORDS) / 32).collect();
            let pix = (0..PIX_REGIONS).map(|_| place(rng, 4 * s * PIX_ROWS) / 4).collect();
            Regions { rd, wr, feat, pix }
        }

        /// A random burst start: often just below a 4 KiB page end, so the burst straddles it.
        fn table_addr(&self, rng: &mut Rng, len: u64) -> u64 {
            let base = *rng.pick(&self.rd);
            let page = rng.below(RD_ENTRIES / 512);
            let off = if rng.percent(40) { 512 - rng.range(1, 20) } else { rng.below(512) };
            (base + 512 * page + off).min(base + RD_ENTRIES - len)
        }

        fn write_addr(&self, rng: &mut Rng) -> u64 {
            rng.pick(&self.wr) + rng.below(WR_ENTRIES)
        }

        fn feature(&self, rng: &mut Rng) -> u64 {
            rng.pick(&self.feat) + rng.below(FEAT_WORDS)
        }

        fn pixels(&self, rng: &mut Rng, s: u64) -> u64 {
            rng.pick(&self.pix) + s * rng.below(PIX_ROWS)
        }

        /// The memory with random table entries and feature words.
        fn preload(&self, rng: &mut Rng) -> Memory {
            let mut mem = Memory::new();
            for &b in &self.rd {
                for a in b..b + RD_ENTRIES {
                    mem.write(8 * a, &rng.next_u64().to_le_bytes());
                }
            }
            for &b in &self.feat {
                for w in 4 * b..4 * (b + FEAT_WORDS) {
                    mem.write(8 * w, &rng.next_u64().to_le_bytes());
                }
            }
            mem
        }
    }

    #[test]
    fn axi_sort_bridge_reads_and_writes() {
        let name = "axi_sort_bridge_reads_and_writes";
        for_each_seed(name, |seed| {
            let cfg = neo_tb::config();
            let (eb, o) = (cfg.entry_bits(), cfg.axi_outstanding);
            let chk = Checker::new("neo_axi_sort_bridge", seed);
            let mut rng = Rng::new(seed);
            let reg = Regions::new(&mut rng, 0);
            let mut mem = AxiMemory::new(1, reg.preload(&mut rng), AxiTiming::RANDOM, rng.next_u64());
            let golden = mem.memory().clone();
            let mut axi_chk = AxiChecker::new(0, "m_axi", o, o);
            let port = AxiBinding::new::<NeoAxiSortBridge>("m_axi_", true);
            let mut dut = NeoAxiSortBridge::new();
            maybe_trace(&mut dut, name);
            port.set_subordinate(&mut dut, &SubordinateSignals::default());
            dut.reset();
            let n = requests();
            let (mut reads_left, mut writes_left) = (n, n);
            let mut req: Option<(u64, u64)> = None;
            let mut wr: Option<(u64, u64)> = None;
            let mut expected: VecDeque<u64> = VecDeque::new();
            let mut written: HashMap<u64, u64> = HashMap::new();
            let mut idle_seen = 0u64;
            let mut cycles = 0u64;
            loop {
                if req.is_none() && reads_left > 0 && rng.percent(60) {
                    let len = rng.range(1, cfg.burst as u64);
                    req = Some((reg.table_addr(&mut rng, len), len));
                    reads_left -= 1;
                }
                if wr.is_none() && writes_left > 0 && rng.percent(60) {
                    wr = Some((reg.write_addr(&mut rng), rng.next_u64() & mask(eb)));
                    writes_left -= 1;
                }
                let (ra, rl) = req.unwrap_or_default();
                dut.set_mem_req_valid_i(req.is_some());
                dut.set_mem_req_addr_i(ra);
                dut.set_mem_req_len_i(rl);
                let rsp_ready = rng.percent(75);
                dut.set_mem_rsp_ready_i(rsp_ready);
                let (wa, wd) = wr.unwrap_or_default();
                dut.set_mem_wr_valid_i(wr.is_some());
                dut.set_mem_wr_addr_i(wa);
                dut.set_mem_wr_data_i(wd);
                let mem_out = mem.outputs(0);
                port.set_subordinate(&mut dut, &mem_out);
                dut.eval();
                let cyc = dut.cycle();
                let req_fire = req.is_some() && dut.mem_req_ready_o();
                let rsp_fire = dut.mem_rsp_valid_o() && rsp_ready;
                let wr_fire = wr.is_some() && dut.mem_wr_ready_o();
                chk.value(cyc, "rd_beat_o (= entry delivered)", rsp_fire.into(), dut.rd_beat_o().into());
                chk.value(cyc, "wr_beat_o (= write taken)", wr_fire.into(), dut.wr_beat_o().into());
                if dut.idle_o() {
                    idle_seen += 1;
                    chk.value(cyc, "entries owed to the core while idle_o", 0, expected.len() as u64);
                    chk.value(cyc, "AXI reads/writes open while idle_o", 0, {
                        let (r, w) = axi_chk.in_flight();
                        (r + w) as u64
                    });
                    chk.value(cyc, "AxiMemory idle while idle_o", 1, mem.idle(0).into());
                }
                if rsp_fire {
                    let Some(a) = expected.pop_front() else {
                        chk.fail(cyc, "mem_rsp_valid_o", "no entry owed", "1")
                    };
                    chk.value(
                        cyc,
                        &format!("mem_rsp_data_o (entry 0x{a:x})"),
                        golden.read_u64(8 * a) & mask(eb),
                        dut.mem_rsp_data_o(),
                    );
                }
                if req_fire {
                    expected.extend(ra..ra + rl);
                    req = None;
                }
                if wr_fire {
                    written.insert(wa, wd);
                    wr = None;
                }
                let down = port.get_manager(&dut);
                if let Err(v) = axi_chk.observe(&down, &mem_out) {
                    panic!("{v} (seed = 0x{seed:016x}; reproduce with NEO_SEED=0x{seed:016x})");
                }
                mem.tick(0, &down);
                dut.tick();
                cycles += 1;
                if reads_left == 0
                    && writes_left == 0
                    && req.is_none()
                    && wr.is_none()
                    && expected.is_empty()
                    && dut.idle_o()
                {
                    break;
                }
                if cycles > 400 * n as u64 {
                    chk.fail(
                        cyc,
                        "progress (timeout)",
                        "every request answered",
                        &format!("{} entries owed", expected.len()),
                    );
                }
            }
            for (a, d) in &written {
                chk.value(dut.cycle(), &format!("memory entry 0x{a:x}"), *d, mem.memory().read_u64(8 * a));
            }
            assert!(idle_seen > 0, "idle_o never seen");
            println!("{name}: {n} read bursts and {n} writes in {cycles} cycles");
        });
    }

    /// A request of the raster core's port.
    #[derive(Clone, Copy, Debug)]
    enum Req {
        Table(u64, u64),
        Feature(u64),
        WriteEntry(u64, u64),
        Pixels(u64, [u32; 16]),
    }

    #[test]
    fn axi_raster_bridge_tables_features_entries_and_pixels() {
        let name = "axi_raster_bridge_tables_features_entries_and_pixels";
        for_each_seed(name, |seed| {
            let cfg = neo_tb::config();
            let (eb, o) = (cfg.entry_bits(), cfg.axi_outstanding);
            let s = cfg.raster_config().subtile as usize;
            assert!(s <= 16, "the bench holds at most 16 pixels a row");
            let fw = neo_golden::engine::memory::feature_word_bits(&cfg.feature_format());
            let chk = Checker::new("neo_axi_raster_bridge", seed);
            let mut rng = Rng::new(seed);
            let reg = Regions::new(&mut rng, s as u64);
            let mut mem = AxiMemory::new(1, reg.preload(&mut rng), AxiTiming::RANDOM, rng.next_u64());
            let golden = mem.memory().clone();
            let mut axi_chk = AxiChecker::new(0, "m_axi", o, o);
            let port = AxiBinding::new::<NeoAxiRasterBridge>("m_axi_", true);
            let mut dut = NeoAxiRasterBridge::new();
            maybe_trace(&mut dut, name);
            port.set_subordinate(&mut dut, &SubordinateSignals::default());
            dut.reset();
            let wdata_port = NeoAxiRasterBridge::port("mem_wdata_i");
            let rsp_port = NeoAxiRasterBridge::port("mem_rsp_data_o");
            let rsp_words = NeoAxiRasterBridge::PORTS[rsp_port].words();
            let wdata_words = NeoAxiRasterBridge::PORTS[wdata_port].words();
            let n = requests();
            let mut left = n;
            let mut req: Option<Req> = None;
            // Owed responses: the expected response words.
            let mut expected: VecDeque<(String, Vec<u32>)> = VecDeque::new();
            let mut entries: HashMap<u64, u64> = HashMap::new();
            let mut pixels: HashMap<u64, u32> = HashMap::new();
            let (mut cycles, mut idle_seen) = (0u64, 0u64);
            let words_of = |bytes: &[u8], bits: u32| -> Vec<u32> {
                (0..rsp_words)
                    .map(|k| {
                        let mut w = [0u8; 4];
                        for (j, b) in w.iter_mut().enumerate() {
                            *b = bytes.get(4 * k + j).copied().unwrap_or(0);
                        }
                        let v = u32::from_le_bytes(w);
                        let lo = 32 * k as u32;
                        if bits <= lo {
                            0
                        } else if bits - lo >= 32 {
                            v
                        } else {
                            v & ((1u32 << (bits - lo)) - 1)
                        }
                    })
                    .collect()
            };
            loop {
                if req.is_none() && left > 0 && rng.percent(70) {
                    left -= 1;
                    req = Some(match rng.below(4) {
                        0 => {
                            let len = rng.range(1, cfg.burst as u64);
                            Req::Table(reg.table_addr(&mut rng, len), len)
                        }
                        1 => Req::Feature(reg.feature(&mut rng)),
                        2 => Req::WriteEntry(reg.write_addr(&mut rng), rng.next_u64() & mask(eb)),
                        _ => {
                            let mut px = [0u32; 16];
                            for p in px.iter_mut().take(s) {
                                *p = rng.next_u32() & 0xff_ffff;
                            }
                            Req::Pixels(reg.pixels(&mut rng, s as u64), px)
                        }
                    });
                }
                let (write, space, addr, len, wdata) = match req {
                    None => (false, 0, 0, 0, vec![0u32; wdata_words]),
                    Some(Req::Table(a, l)) => (false, 0, a, l, vec![0; wdata_words]),
                    Some(Req::Feature(w)) => (false, 1, w, 1, vec![0; wdata_words]),
                    Some(Req::WriteEntry(a, d)) => {
                        let mut v = vec![0u32; wdata_words];
                        v[0] = d as u32;
                        v[1] = (d >> 32) as u32;
                        (true, 0, a, 1, v)
                    }
                    Some(Req::Pixels(p, px)) => {
                        // Pixel k at [24k +: 24].
                        let mut v = vec![0u32; wdata_words];
                        let pw = RGB_BITS as usize;
                        for (k, &c) in px.iter().take(s).enumerate() {
                            set_bits(&mut v, pw * k, pw, u64::from(c));
                        }
                        (true, 2, p, s as u64, v)
                    }
                };
                dut.set_mem_req_valid_i(req.is_some());
                dut.set_mem_req_write_i(write);
                dut.set_mem_req_space_i(space);
                dut.set_mem_req_addr_i(addr);
                dut.set_mem_req_len_i(len);
                dut.set_words(wdata_port, &wdata);
                let rsp_ready = rng.percent(85);
                dut.set_mem_rsp_ready_i(rsp_ready);
                let mem_out = mem.outputs(0);
                port.set_subordinate(&mut dut, &mem_out);
                dut.eval();
                let cyc = dut.cycle();
                let fire = req.is_some() && dut.mem_req_ready_o();
                let rsp_fire = dut.mem_rsp_valid_o() && rsp_ready;
                let kind = |f: fn(&Req) -> bool| fire && req.as_ref().is_some_and(f);
                chk.value(
                    cyc,
                    "wr_table_o",
                    kind(|r| matches!(r, Req::WriteEntry(..))).into(),
                    dut.wr_table_o().into(),
                );
                chk.value(
                    cyc,
                    "wr_pixels_o",
                    kind(|r| matches!(r, Req::Pixels(..))).into(),
                    dut.wr_pixels_o().into(),
                );
                let head_feat = expected.front().is_some_and(|(what, _)| what.starts_with("feature"));
                chk.value(cyc, "rd_table_o", (rsp_fire && !head_feat).into(), dut.rd_table_o().into());
                chk.value(cyc, "rd_feat_o", (rsp_fire && head_feat).into(), dut.rd_feat_o().into());
                if dut.idle_o() {
                    idle_seen += 1;
                    chk.value(cyc, "responses owed to the core while idle_o", 0, expected.len() as u64);
                    let (r, w) = axi_chk.in_flight();
                    chk.value(cyc, "AXI reads/writes open while idle_o", 0, (r + w) as u64);
                    chk.value(cyc, "AxiMemory idle while idle_o", 1, mem.idle(0).into());
                }
                if rsp_fire {
                    let Some((what, want)) = expected.pop_front() else {
                        chk.fail(cyc, "mem_rsp_valid_o", "no response owed", "1")
                    };
                    let mut got = vec![0u32; rsp_words];
                    dut.get_words(rsp_port, &mut got);
                    for k in 0..rsp_words {
                        chk.value(
                            cyc,
                            &format!("mem_rsp_data_o[{} +: 32] ({what})", 32 * k),
                            want[k].into(),
                            got[k].into(),
                        );
                    }
                }
                if fire {
                    match req.take().expect("fire needs a request") {
                        Req::Table(a, l) => {
                            for e in a..a + l {
                                let b = golden.read_u64(8 * e).to_le_bytes();
                                expected.push_back((format!("table entry 0x{e:x}"), words_of(&b, eb)));
                            }
                        }
                        Req::Feature(w) => {
                            let mut b = [0u8; 32];
                            golden.read(32 * w, &mut b);
                            expected.push_back((format!("feature word 0x{w:x}"), words_of(&b, fw)));
                        }
                        Req::WriteEntry(a, d) => {
                            entries.insert(a, d);
                        }
                        Req::Pixels(p, px) => {
                            for (k, &c) in px.iter().take(s).enumerate() {
                                pixels.insert(p + k as u64, c);
                            }
                        }
                    }
                }
                let down = port.get_manager(&dut);
                if let Err(v) = axi_chk.observe(&down, &mem_out) {
                    panic!("{v} (seed = 0x{seed:016x}; reproduce with NEO_SEED=0x{seed:016x})");
                }
                mem.tick(0, &down);
                dut.tick();
                cycles += 1;
                if left == 0 && req.is_none() && expected.is_empty() && dut.idle_o() {
                    break;
                }
                if cycles > 400 * n as u64 {
                    chk.fail(
                        cyc,
                        "progress (timeout)",
                        "every request answered",
                        &format!("{} responses owed", expected.len()),
                    );
                }
            }
            for (a, d) in &entries {
                chk.value(dut.cycle(), &format!("memory entry 0x{a:x}"), *d, mem.memory().read_u64(8 * a));
            }
            for (p, c) in &pixels {
                let mut b = [0u8; 4];
                mem.memory().read(4 * p, &mut b);
                let want = pixel_to_u32([*c as u8, (*c >> 8) as u8, (*c >> 16) as u8]);
                chk.value(
                    dut.cycle(),
                    &format!("memory pixel 0x{p:x}"),
                    want.into(),
                    u32::from_le_bytes(b).into(),
                );
            }
            assert!(idle_seen > 0, "idle_o never seen");
            println!("{name}: {n} requests in {cycles} cycles");
        });
    }
}
