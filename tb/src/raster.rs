//! The raster-core test bench: whole tiles through `neo_raster_core` with a memory model (random
//! request stalls, response latency and gaps), every pixel of the 64x64 tile and every
//! written-back table entry checked against golden.
//!
//! - Driver / memory model: [`RasterCore`] (command port, memory port; tables, feature words and
//!   pixels live in three address spaces, see `gen/src/units/raster_core/mod.rs`).
//! - Golden: [`golden`]: golden [`raster_tile`] on the table's feature entries (culled ids are
//!   not passed) and the deferred write-back of golden `pipeline::frame` (`valid` = the
//!   entry's cumulative OR, 0 when culled; `key` = the feature's depth key, kept when culled).
//!   For biker tiles the expected values come from the golden pipeline itself.
//! - Checker: [`Checker`], first mismatch with cycle, field, expected and actual (hex).

use crate::bits::get_bits;
use crate::check::{Checker, WriteOnce};
use crate::core::MemTiming;
use crate::dut::Clocked;
use crate::dynmodel::DynModel;
use crate::itu::entry_words;
use crate::models::NeoRasterCore;
use crate::rng::Rng;
use crate::scu::{gaussian, random_gaussian};
use crate::stream::Handshake;
use neo_gen::units::raster_core::{feature_word_bits, space};
use neo_gen::EngineConfig;
use neo_golden::formats::feature::{FeatureEntry, FeatureFormat};
use neo_golden::formats::latency::GridPoint;
use neo_golden::raster::window::table_window_order;
use neo_golden::raster::{raster_tile, RasterConfig, RGB_BITS};
use neo_golden::sort::{SortEntry, SortFormat};
use std::collections::{HashMap, VecDeque};

/// One tile's job: the tile, the image size, the table (in raster order) and the feature
/// entries by id (an id without one is a Gaussian culled this frame).
#[derive(Clone, Debug, Default)]
pub struct TileCase {
    /// Tile `[x, y]`.
    pub tile: [u32; 2],
    /// Image `[width, height]` in pixels.
    pub size: [u32; 2],
    /// The table.
    pub table: Vec<SortEntry>,
    /// Feature entries by Gaussian id.
    pub features: HashMap<u32, FeatureEntry>,
}

/// What the core must produce.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Expected {
    /// `tile * tile` pixels, row-major (black outside the image).
    pub pixels: Vec<[u8; 3]>,
    /// The written-back table.
    pub table: Vec<SortEntry>,
}

/// Golden: [`raster_tile`] on the table's feature entries and the frame pipeline's write-back,
/// both in the order of `cfg`'s reorder window ([`neo_golden::raster::window`]; table order
/// without one).
pub fn golden(case: &TileCase, cfg: &EngineConfig) -> Expected {
    let (fmt, rc) = (cfg.feature_format(), cfg.raster_config());
    let order = window_order_of(case, cfg.raster_window);
    let feats: Vec<FeatureEntry> = order.iter().filter_map(|e| case.features.get(&e.id).copied()).collect();
    let r = raster_tile(&feats, &fmt, case.tile[0], case.tile[1], case.size[0], case.size[1], &rc);
    let mut j = 0;
    let table = order
        .iter()
        .map(|e| match case.features.get(&e.id) {
            None => SortEntry { valid: false, ..*e },
            Some(f) => {
                j += 1;
                SortEntry { valid: r.valid[j - 1], key: f.depth_key, id: e.id }
            }
        })
        .collect();
    Expected { pixels: r.pixels, table }
}

/// The case's table in the order a reorder window of `window` entries emits it (by each entry's
/// current key: its feature's depth key, its table key when culled).
pub fn window_order_of(case: &TileCase, window: usize) -> Vec<SortEntry> {
    let t = &case.table;
    let order = table_window_order(t, window, |i| case.features.get(&t[i].id).map(|f| f.depth_key));
    order.iter().map(|&i| t[i as usize]).collect()
}

/// Counters of one tile.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TileRun {
    /// Rising edges from the one accepting the command to the `done_o` cycle.
    pub cycles: u64,
    /// Read requests (table bursts and feature reads).
    pub reads: u64,
    /// Table entries written back.
    pub writebacks: u64,
    /// Pixel-row writes.
    pub pixel_writes: u64,
    /// Cycles from the command to the last read request taken (the end of the last LOAD).
    pub last_read: u64,
    /// `done_wb_reach_o` (checked against golden).
    pub wb_reach: u64,
}

/// Addresses of the three spaces for one tile.
#[derive(Clone, Copy, Debug)]
struct Bases {
    table: u64,
    feat: u64,
    pix: u64,
}

struct Memory {
    timing: MemTiming,
    rng: Rng,
    table: HashMap<u64, u64>,
    feats: HashMap<u64, Vec<u32>>,
    /// Pixel address -> (colour, write cycle).
    pixels: HashMap<u64, ([u8; 3], u64)>,
    written: WriteOnce,
    rsp: VecDeque<(u64, Vec<u32>)>,
    offering: bool,
    last_read: u64,
}

/// The raster core with its memory model, command driver and checker. `M` is the model: the
/// static one for [`crate::config`] ([`RasterCore::new`]), or one built at run time for another
/// configuration ([`RasterCore::build`]).
pub struct RasterCore<M: Clocked = NeoRasterCore> {
    /// The model.
    pub dut: M,
    /// Mismatch reporting.
    pub checker: Checker,
    mem: Memory,
    rng: Rng,
    fmt: FeatureFormat,
    rc: RasterConfig,
    sort: SortFormat,
    fwords: usize,
    burst: u64,
    /// `scu_lanes` and `raster_scus` (the hang budget: [`RasterCore::cycle_budget`]).
    scu_lanes: u64,
    scus: u64,
    ports: Ports,
    req_hs: Handshake,
}

/// The ports the bench drives and reads by index.
#[derive(Clone, Copy)]
struct Ports {
    rsp_data: usize,
    rsp_valid: usize,
    rsp_ready: usize,
    wdata: usize,
    req_valid: usize,
    req_ready: usize,
    req_write: usize,
    req_space: usize,
    req_addr: usize,
    req_len: usize,
    cmd_valid: usize,
    cmd_ready: usize,
    /// `cmd_tile_x_i`, `cmd_tile_y_i`, `cmd_width_i`, `cmd_height_i`, `cmd_table_i`, `cmd_len_i`,
    /// `cmd_feat_i`, `cmd_pix_i`.
    cmd: [usize; 8],
    done: usize,
    /// `done_wb_len_o`, `done_wb_reach_o`.
    wb_signals: [usize; 2],
}

impl Ports {
    fn of<M: Clocked>(dut: &M) -> Self {
        let p = |n: &str| dut.pin(n);
        Ports {
            rsp_data: p("mem_rsp_data_i"),
            rsp_valid: p("mem_rsp_valid_i"),
            rsp_ready: p("mem_rsp_ready_o"),
            wdata: p("mem_wdata_o"),
            req_valid: p("mem_req_valid_o"),
            req_ready: p("mem_req_ready_i"),
            req_write: p("mem_req_write_o"),
            req_space: p("mem_req_space_o"),
            req_addr: p("mem_req_addr_o"),
            req_len: p("mem_req_len_o"),
            cmd_valid: p("cmd_valid_i"),
            cmd_ready: p("cmd_ready_o"),
            cmd: [
                "cmd_tile_x_i",
                "cmd_tile_y_i",
                "cmd_width_i",
                "cmd_height_i",
                "cmd_table_i",
                "cmd_len_i",
                "cmd_feat_i",
                "cmd_pix_i",
            ]
            .map(p),
            done: p("done_o"),
            wb_signals: [p("done_wb_len_o"), p("done_wb_reach_o")],
        }
    }
}

impl RasterCore<NeoRasterCore> {
    /// A reset core (the static model of [`crate::config`]) whose memory follows `timing`.
    pub fn new(cfg: &EngineConfig, seed: u64, timing: MemTiming) -> Self {
        RasterCore::with_model(NeoRasterCore::new(), cfg, seed, timing)
    }
}

impl RasterCore<DynModel> {
    /// A reset core of any configuration `cfg` (`neo_raster_core` built at run time, or loaded
    /// from the cache: [`crate::configs::build`]) whose memory follows `timing`.
    pub fn build(cfg: &EngineConfig, seed: u64, timing: MemTiming) -> Result<Self, String> {
        let dut = crate::configs::build(cfg, "neo_raster_core")?;
        Ok(RasterCore::with_model(dut, cfg, seed, timing))
    }
}

impl<M: Clocked> RasterCore<M> {
    /// A reset core on model `dut` (`neo_raster_core` generated from `cfg`) whose memory
    /// follows `timing`.
    pub fn with_model(mut dut: M, cfg: &EngineConfig, seed: u64, timing: MemTiming) -> Self {
        let mut rng = Rng::new(seed);
        let ports = Ports::of(&dut);
        dut.io_set(ports.cmd_valid, 0);
        dut.io_set(ports.req_ready, 0);
        dut.io_set(ports.rsp_valid, 0);
        dut.io_reset();
        let mem = Memory {
            timing,
            rng: rng.fork(1),
            table: HashMap::new(),
            feats: HashMap::new(),
            pixels: HashMap::new(),
            written: WriteOnce::default(),
            rsp: VecDeque::new(),
            offering: false,
            last_read: 0,
        };
        // docs/rtl.md "Memory protocol": an offered request that is not taken may change in the
        // next cycle (fixed priority), so only "valid does not depend on ready" applies.
        let mut req_hs = Handshake::bind(
            &dut,
            "memory request port",
            "mem_req_valid_o",
            "mem_req_ready_i",
            &["mem_req_write_o", "mem_req_space_o", "mem_req_addr_o", "mem_req_len_o", "mem_wdata_o"],
        )
        .unwrap_or_else(|e| panic!("{e}"));
        req_hs.check_stable = false;
        let checker = Checker::new(dut.top(), seed);
        RasterCore {
            dut,
            checker,
            mem,
            rng: rng.fork(2),
            fmt: cfg.feature_format(),
            rc: cfg.raster_config(),
            sort: cfg.format(),
            fwords: feature_word_bits(cfg).div_ceil(32) as usize,
            burst: cfg.burst as u64,
            scu_lanes: cfg.scu_lanes as u64,
            scus: cfg.raster_scus as u64,
            ports,
            req_hs,
        }
    }

    /// Restarts the bench's random streams (memory timing, addresses) and its checker's seed
    /// from `seed`, as a core made with `seed` has them.
    pub fn reseed(&mut self, seed: u64) {
        let mut rng = Rng::new(seed);
        self.mem.rng = rng.fork(1);
        self.rng = rng.fork(2);
        self.checker = Checker::new(self.dut.top(), seed);
    }

    /// Changes the memory timing.
    pub fn set_timing(&mut self, timing: MemTiming) {
        self.mem.timing = timing;
    }

    /// One cycle of the memory model and the clock.
    fn step(&mut self, b: &Bases, len: u64) {
        let p = self.ports;
        let c = self.dut.io_cycle();
        let ready = self.mem.rng.percent(self.mem.timing.req_ready_pct);
        self.dut.io_set(p.req_ready, ready as u64);
        if !self.mem.offering {
            if let Some((due, data)) = self.mem.rsp.front() {
                if *due <= c && !self.mem.rng.percent(self.mem.timing.rsp_gap_pct) {
                    self.mem.offering = true;
                    let d = data.clone();
                    self.dut.io_set_words(p.rsp_data, &d);
                }
            }
        }
        if !self.mem.offering {
            let junk: Vec<u32> = (0..self.fwords).map(|_| self.mem.rng.next_u32()).collect();
            self.dut.io_set_words(p.rsp_data, &junk);
        }
        self.dut.io_set(p.rsp_valid, self.mem.offering as u64);
        self.dut.io_eval();
        self.req_hs.check(&mut self.dut, ready, &self.checker);
        if self.mem.offering {
            self.checker.protocol(c, self.dut.flag(p.rsp_ready), "mem_rsp_ready_o low");
            self.mem.rsp.pop_front();
            self.mem.offering = false;
        }
        if ready && self.dut.flag(p.req_valid) {
            self.request(c, b, len);
        }
        self.dut.io_tick();
    }

    fn request(&mut self, c: u64, b: &Bases, len: u64) {
        let p = self.ports;
        let addr = self.dut.io_get(p.req_addr);
        let n = self.dut.io_get(p.req_len);
        let sp = self.dut.io_get(p.req_space);
        let tile = self.rc.tile as u64;
        let side = self.rc.subtile as u64;
        if self.dut.flag(p.req_write) {
            let mut w = vec![0u32; (self.dut.io_width(p.wdata).div_ceil(32) as usize).max(2)];
            self.dut.io_get_words(p.wdata, &mut w);
            match sp {
                space::TABLE => {
                    self.checker.value(c, "mem_req_len_o (write-back)", 1, n);
                    let ok = (b.table..b.table + len).contains(&addr);
                    self.checker.protocol(c, ok, &format!("write-back to 0x{addr:x} outside the table"));
                    self.mem.written.record(&self.checker, c, "table entry", addr);
                    self.mem.table.insert(addr, w[0] as u64 | (w[1] as u64) << 32);
                }
                space::PIXEL => {
                    self.checker.value(c, "mem_req_len_o (pixels)", side, n);
                    let off = addr.wrapping_sub(b.pix);
                    let ok = off < tile * tile && off.is_multiple_of(side);
                    self.checker.protocol(c, ok, &format!("pixel write at 0x{addr:x} outside the tile"));
                    for k in 0..side {
                        let bit = RGB_BITS as usize * k as usize;
                        let px = |s: usize| get_bits(&w, bit + s, 8) as u8;
                        let prev = self.mem.pixels.insert(addr + k, ([px(0), px(8), px(16)], c));
                        self.checker.protocol(
                            c,
                            prev.is_none(),
                            &format!("pixel 0x{:x} written twice", addr + k),
                        );
                    }
                }
                s => self.checker.protocol(c, false, &format!("write to space {s}")),
            }
            return;
        }
        self.mem.last_read = c;
        let t = self.mem.timing;
        let mut due = c + self.mem.rng.range(t.min_latency as u64, t.max_latency.max(t.min_latency) as u64);
        if let Some((last, _)) = self.mem.rsp.back() {
            due = due.max(*last);
        }
        match sp {
            space::TABLE => {
                self.checker.protocol(c, (1..=self.burst).contains(&n), &format!("table burst of {n}"));
                let ok = addr >= b.table && addr + n <= b.table + len;
                self.checker.protocol(c, ok, &format!("table read of {n} at 0x{addr:x} outside the table"));
                for i in 0..n {
                    let v = self.mem.table[&(addr + i)];
                    self.mem.rsp.push_back((due, vec![v as u32, (v >> 32) as u32]));
                }
            }
            space::FEATURE => {
                self.checker.value(c, "mem_req_len_o (feature read)", 1, n);
                let w = self.mem.feats.get(&addr).cloned();
                self.checker.protocol(
                    c,
                    w.is_some(),
                    &format!("feature read at 0x{addr:x}: no Gaussian of the table"),
                );
                self.mem.rsp.push_back((due, w.unwrap_or_default()));
            }
            s => self.checker.protocol(c, false, &format!("read from space {s}")),
        }
    }

    /// Renders `case` and checks pixels and the written-back table against `want`; returns
    /// the counters.
    ///
    /// # Panics
    /// At the first mismatch, protocol violation or timeout.
    pub fn run(&mut self, case: &TileCase, want: &Expected) -> TileRun {
        let len = case.table.len() as u64;
        let b = Bases {
            table: 0x1000 + self.rng.below(0x1000),
            feat: 0x10_0000 + self.rng.below(0x1000),
            pix: 0x80_0000 + self.rng.below(0x1000),
        };
        self.mem.table.clear();
        self.mem.feats.clear();
        self.mem.pixels.clear();
        self.mem.written.clear();
        self.mem.last_read = 0;
        for (i, e) in case.table.iter().enumerate() {
            self.mem.table.insert(b.table + i as u64, self.sort.pack(e));
            let mut w = match case.features.get(&e.id) {
                Some(f) => entry_words(f, &self.fmt),
                None => Vec::new(),
            };
            w.resize(self.fwords, 0);
            if case.features.contains_key(&e.id) {
                let p = self.fmt.bits_per_entry() as usize;
                w[p / 32] |= 1 << (p % 32);
            }
            self.mem.feats.insert(b.feat + e.id as u64, w);
        }
        for _ in 0..self.rng.below(3) {
            self.step(&b, len);
        }
        let p = self.ports;
        let cmd = [case.tile[0] as u64, case.tile[1] as u64, case.size[0] as u64, case.size[1] as u64];
        for (k, v) in cmd.into_iter().chain([b.table, len, b.feat, b.pix]).enumerate() {
            self.dut.io_set(p.cmd[k], v);
        }
        self.dut.io_set(p.cmd_valid, 1);
        let limit = self.dut.io_cycle() + self.cycle_budget(len);
        let start;
        loop {
            self.dut.io_eval();
            let accepted = self.dut.flag(p.cmd_ready);
            let c = self.dut.io_cycle();
            self.checker.protocol(c, !self.dut.flag(p.done), "done_o while no command is running");
            self.step(&b, len);
            if accepted {
                start = c;
                break;
            }
        }
        self.dut.io_set(p.cmd_valid, 0);
        self.dut.io_set(p.cmd[5], self.rng.next_u64());
        self.dut.io_set(p.cmd[4], self.rng.next_u64());
        let mut reads = 0;
        loop {
            self.dut.io_eval();
            if self.dut.flag(p.done) {
                break;
            }
            let c = self.dut.io_cycle();
            if c > limit {
                self.checker.fail(c, "done_o", "a pulse", &format!("none after {} cycles", c - start));
            }
            if self.dut.flag(p.req_valid) && !self.dut.flag(p.req_write) {
                reads += 1;
            }
            self.step(&b, len);
        }
        let c = self.dut.io_cycle();
        self.checker.protocol(
            c,
            self.mem.rsp.is_empty() && !self.mem.offering,
            "done_o with responses pending",
        );
        let run = TileRun {
            cycles: c - start,
            reads,
            writebacks: self.mem.written.len() as u64,
            pixel_writes: self.mem.pixels.len() as u64 / self.rc.subtile as u64,
            last_read: self.mem.last_read.saturating_sub(start),
            wb_reach: self.dut.io_get(p.wb_signals[1]),
        };
        self.check(c, case, want, &b);
        self.step(&b, len);
        self.dut.io_eval();
        let c = self.dut.io_cycle();
        self.checker.protocol(c, !self.dut.flag(p.done), "done_o longer than one cycle");
        self.checker.protocol(c, self.dut.flag(p.cmd_ready), "cmd_ready_o low after done_o");
        run
    }

    /// Cycles a tile of `len` entries may take before the bench calls it a hang: 20k + 200 a
    /// entry in the default configuration, scaled by the SCU passes per Gaussian (pixels of a
    /// subtile over `scu_lanes`) against the default's 4, and by the subtile groups
    /// (`subtiles / raster_scus`) against the default's 16.
    fn cycle_budget(&self, len: u64) -> u64 {
        let passes = (self.rc.subtile * self.rc.subtile) as u64 / self.scu_lanes;
        let groups = self.rc.subtiles_per_tile() as u64 / self.scus;
        let scale = (passes * groups).div_ceil(4 * 16).max(1);
        (20_000 + 200 * len) * scale
    }

    /// Checker: every pixel and every table entry.
    fn check(&self, done: u64, case: &TileCase, want: &Expected, b: &Bases) {
        let t = self.rc.tile as usize;
        for (k, w) in want.pixels.iter().enumerate() {
            let (x, y) = (k % t, k / t);
            let Some((got, at)) = self.mem.pixels.get(&(b.pix + k as u64)) else {
                self.checker.fail(done, &format!("pixel ({x}, {y})"), &format!("{w:02x?}"), "never written");
            };
            for (ch, name) in ["red", "green", "blue"].iter().enumerate() {
                self.checker.value(*at, &format!("pixel ({x}, {y}).{name}"), w[ch] as u64, got[ch] as u64);
            }
        }
        for (i, w) in want.table.iter().enumerate() {
            let a = b.table + i as u64;
            let Some(at) = self.mem.written.get(a) else {
                self.checker.fail(
                    done,
                    &format!("table[{i}] (id {:#x})", case.table[i].id),
                    "written back",
                    "never written",
                );
            };
            let got = self.sort.unpack(self.mem.table[&a]);
            self.checker.entry(at, &format!("table[{i}]"), w, &got);
        }
        // The write-back's disorder signals, of the entries as written (the key field's width).
        let written: Vec<SortEntry> =
            want.table.iter().map(|e| self.sort.unpack(self.sort.pack(e))).collect();
        let wb = neo_golden::pipeline::adaptive::writeback_signals(&written);
        let [len, reach] = self.ports.wb_signals.map(|p| self.dut.io_get(p));
        self.checker.value(done, "done_wb_len_o", wb.len as u64, len);
        self.checker.value(done, "done_wb_reach_o", wb.reach as u64, reach);
    }
}

/// A random table of `n` entries for tile `tile`: Gaussians from the SCU bench's mix (near a
/// random subtile of the tile, raw fields, far, screen-filling), distinct random ids, random
/// keys and valid bits, random depth keys, `culled_pct` percent of the ids without a feature.
pub fn random_case(
    rng: &mut Rng,
    cfg: &EngineConfig,
    tile: [u32; 2],
    size: [u32; 2],
    n: usize,
    culled_pct: u32,
) -> TileCase {
    let fmt = cfg.feature_format();
    let rc = cfg.raster_config();
    let sort = cfg.format();
    let mut case = TileCase { tile, size, ..TileCase::default() };
    let mut ids = std::collections::HashSet::new();
    while case.table.len() < n {
        let id = rng.below(sort.id_max() as u64 + 1) as u32;
        if !ids.insert(id) {
            continue;
        }
        let key = rng.below(sort.key_max() as u64 + 1) as u32;
        case.table.push(SortEntry { valid: rng.percent(80), key, id });
        if !rng.percent(culled_pct) {
            let n = rc.subtiles_per_side() as u64;
            let o = [
                tile[0] * rc.tile + rng.below(n) as u32 * rc.subtile,
                tile[1] * rc.tile + rng.below(n) as u32 * rc.subtile,
            ];
            let mut f = random_gaussian(rng, &fmt, o);
            f.depth_key = rng.below(sort.key_max() as u64 + 1) as u32;
            case.features.insert(id, f);
        }
    }
    case
}

/// A case from explicit Gaussians (ids 1.., keys descending, all valid).
pub fn case_of(tile: [u32; 2], size: [u32; 2], gs: &[FeatureEntry]) -> TileCase {
    let mut case = TileCase { tile, size, ..TileCase::default() };
    for (i, g) in gs.iter().enumerate() {
        let id = 1 + 3 * i as u32;
        case.table.push(SortEntry { valid: true, key: (gs.len() - i) as u32, id });
        let mut f = *g;
        f.depth_key = (7 * i as u32 + 5) & 0xffff;
        case.features.insert(id, f);
    }
    case
}

/// The tile's pixel centre `(x, y)` offset by `(dx, dy)` pixels, as a mean.
pub fn at(tile: [u32; 2], rc: &RasterConfig, dx: f64, dy: f64) -> [f64; 2] {
    [(tile[0] * rc.tile) as f64 + dx, (tile[1] * rc.tile) as f64 + dy]
}

/// A Gaussian helper re-exported for the directed cases.
pub fn g(mean: [f64; 2], su: f64, sv: f64, th: f64, opacity: f64, rgb: [f64; 3]) -> FeatureEntry {
    gaussian(mean, su, sv, th, opacity, rgb)
}

/// One tile of a golden-pipeline frame: the table as the raster core gets it, and what the
/// golden pipeline produced (its frame's pixels, its written-back table).
#[derive(Clone, Debug)]
pub struct PipelineTile {
    /// Frame index.
    pub frame: usize,
    /// The job: the frame's table (ids in raster order; valid bits set, the keys of entries with
    /// a feature entry scrambled since the core must overwrite them, culled entries' keys kept).
    pub case: TileCase,
    /// Golden: the pipeline's pixels of the tile and its written-back table.
    pub want: Expected,
    /// Set subtile bits of the tile's table (golden bitmaps).
    pub set_bits: u64,
}

/// The biker scene at `res x res` along a short orbit (the camera the sorting-core validation
/// uses, 256x256 there), golden pipeline (Neo strategy) over `frames` consecutive frames; per
/// frame the `per_frame` tiles with the longest tables (the busiest first).
///
/// # Panics
/// When the scene cannot be loaded or the pipeline fails (a test-environment error).
pub fn biker_tiles(path: &std::path::Path, res: u32, frames: usize, per_frame: usize) -> Vec<PipelineTile> {
    use neo_golden::pipeline::{Formats, Pipeline, PipelineConfig};
    use neo_golden::{source, trajectory};
    let (scene, _) = source::load_scene(path.to_str().expect("utf-8 path"), false).expect("biker scene");
    let spec = "orbit:radius=5,height=0,target=0/-1.6/0,start=0,fov=56.145,speed=4";
    let traj = trajectory::parse_trajectory(spec, source::robust_bounds(&scene), frames)
        .expect("trajectory")
        .with_resolution(res, res);
    let cfg = PipelineConfig {
        compare_exact: false,
        compare_float: false,
        ssim: false,
        ..PipelineConfig::default()
    };
    let formats = Formats::artifact(cfg.chunk).expect("artifact formats");
    let tile = cfg.raster.tile;
    let mut p = Pipeline::new(&scene, cfg, formats, res, res).expect("pipeline");
    let key_max = p.formats().sort.format().key_max();
    let mut out = Vec::new();
    for (f, cam) in traj.frames.iter().enumerate() {
        let o = p.render_frame(cam, f, f == 0);
        let grid = p.grid();
        let tables: Vec<Vec<SortEntry>> = p.tables().map(|t| t.to_vec()).collect();
        let bits: Vec<u64> = p.bitmaps().map(|b| b.iter().map(|m| m.count_ones() as u64).sum()).collect();
        let mut order: Vec<usize> = (0..tables.len()).collect();
        order.sort_by_key(|&i| std::cmp::Reverse(tables[i].len()));
        for &ti in order.iter().take(per_frame) {
            let t = [ti as u32 % grid[0], ti as u32 / grid[0]];
            let mut case = TileCase { tile: t, size: [res, res], ..TileCase::default() };
            for e in &tables[ti] {
                let feat = p.feature(e.id).copied();
                let key = if feat.is_some() { (e.key ^ 0x5a5a) & key_max } else { e.key };
                case.table.push(SortEntry { valid: true, key, id: e.id });
                if let Some(fe) = feat {
                    case.features.insert(e.id, fe);
                }
            }
            let mut pixels = Vec::with_capacity((tile * tile) as usize);
            for y in 0..tile {
                for x in 0..tile {
                    let (gx, gy) = (t[0] * tile + x, t[1] * tile + y);
                    let px = if gx < res && gy < res {
                        let i = 3 * (gy as usize * res as usize + gx as usize);
                        [o.image.data[i], o.image.data[i + 1], o.image.data[i + 2]]
                    } else {
                        [0; 3]
                    };
                    pixels.push(px);
                }
            }
            out.push(PipelineTile {
                frame: f,
                case,
                want: Expected { pixels, table: tables[ti].clone() },
                set_bits: bits[ti],
            });
        }
    }
    out
}

/// Gaussian `i` of a grid table touching about `bits` subtiles (1, 4, 16 or 64) of tile `t`,
/// spread over the subtiles round-robin; low opacity so no pixel terminates.
fn grid_gaussian(t: [u32; 2], rc: &RasterConfig, i: u64, bits: u64) -> FeatureEntry {
    let n = rc.subtiles_per_side() as u64;
    let s = rc.subtile as f64;
    let k = i % (n * n);
    let (sx, sy) = ((k % n) as f64, (k / n) as f64);
    let (mean, sigma) = match bits {
        1 => ([sx * s + 3.5, sy * s + 3.5], 0.4),
        4 => ([(sx.min(n as f64 - 2.0) + 1.0) * s - 0.5, (sy.min(n as f64 - 2.0) + 1.0) * s - 0.5], 0.4),
        16 => {
            let (bx, by) = ((k % 3) as f64 * 2.0 + 2.0, (k / 3 % 3) as f64 * 2.0 + 2.0);
            ([bx * s - 0.5, by * s - 0.5], 6.0)
        }
        _ => ([31.5, 31.5], 400.0),
    };
    gaussian(at(t, rc, mean[0], mean[1]), sigma, sigma, 0.0, 0.02, [0.8, 0.4, 0.2])
}

/// The raster core's cycles per tile over a grid of table lengths and subtile bits per
/// Gaussian, ideal memory (every output checked against golden), as the latency report's
/// points.
pub fn measure_grid(cfg: &EngineConfig, seed: u64, lengths: &[u64], bits: &[u64]) -> Vec<GridPoint> {
    measure_grid_on(&mut RasterCore::new(cfg, seed, MemTiming::IDEAL), cfg, lengths, bits)
}

/// [`measure_grid`] on `core` (generated from `cfg`, ideal memory): a core of any
/// configuration, such as one with a reorder window ([`RasterCore::build`]).
pub fn measure_grid_on<M: Clocked>(
    core: &mut RasterCore<M>,
    cfg: &EngineConfig,
    lengths: &[u64],
    bits: &[u64],
) -> Vec<GridPoint> {
    let (fmt, rc) = (cfg.feature_format(), cfg.raster_config());
    let t = [4, 6];
    let mut out = Vec::new();
    for &b in bits {
        for &len in lengths {
            if len == 0 && b != bits[0] {
                continue;
            }
            let gs: Vec<FeatureEntry> = (0..len).map(|i| grid_gaussian(t, &rc, i, b)).collect();
            let case = case_of(t, [1024, 1024], &gs);
            let want = golden(&case, cfg);
            let r = raster_tile(&gs, &fmt, t[0], t[1], 1024, 1024, &rc);
            let set_bits = r.bitmaps.iter().map(|m| m.count_ones() as u64).sum();
            let routed: Vec<u64> = r.work.iter().map(|w| w.routed as u64).collect();
            let group_max_routed =
                routed.chunks(cfg.raster_scus).map(|g| g.iter().copied().max().unwrap_or(0)).sum();
            let run = core.run(&case, &want);
            out.push(GridPoint {
                entries: len,
                bits_per_gaussian: b,
                set_bits,
                group_max_routed,
                cycles: run.cycles,
                load_cycles: run.last_read,
            });
        }
    }
    out
}
