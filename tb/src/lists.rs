//! The list writer's bench (`neo_pre_lists` against the lists and lengths the hits define): the
//! driver starts the writer, offers hits `{tile, id, key}` under random valid gaps and flushes;
//! an [`AxiMemory`] port takes the writes with the chosen timing, an [`AxiChecker`] watches it;
//! the checker then reads every tile's list (each entry `{valid = 1, key, id}` in hit order, up to
//! `table_capacity`, the rest of the last line 0) and its descriptor (the length in the high half
//! of word 2, every other byte untouched), stopping at the first mismatch.

use crate::axi::{AxiBinding, AxiChecker, AxiMemory, AxiTiming, SubordinateSignals};
use crate::check::Checker;
use crate::dynmodel::DynModel;
use crate::rng::Rng;
use neo_gen::units::pre::lists::NAME;
use neo_gen::EngineConfig;
use neo_golden::engine::memory::{Memory, DESCRIPTOR_BYTES, ENTRY_BYTES};
use neo_golden::sort::SortEntry;

/// Where a run's lists and descriptors start: drawn per run over the whole 32-bit address space
/// (the memory is sparse), one region in each half, so every address bit of the writer changes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Bases {
    /// Byte address of tile 0's list (64-byte aligned: a line of 8 entries).
    pub list: u64,
    /// Byte address of tile 0's descriptor (32-byte aligned).
    pub desc: u64,
}

impl Bases {
    /// Random bases for `tiles` tiles of `cfg`: the lists in one half of the address space, the
    /// descriptors in the other, each region inside its half.
    pub fn random(cfg: &EngineConfig, rng: &mut Rng, tiles: u64) -> Bases {
        const HALF: u64 = 1 << 31;
        let list_bytes = neo_golden::engine::pre::list_addr(cfg, 0, tiles);
        let desc_bytes = tiles * DESCRIPTOR_BYTES;
        let (list_half, desc_half) = if rng.percent(50) { (0, HALF) } else { (HALF, 0) };
        let list = list_half + (rng.below(HALF - list_bytes) & !63);
        let desc = desc_half + (rng.below(HALF - desc_bytes) & !31);
        Bases { list, desc }
    }
}
/// What untouched descriptor bytes hold.
const CANARY: u8 = 0x5a;

/// One incoming (Gaussian, tile).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Hit {
    /// Tile column and row.
    pub tile: [u32; 2],
    /// Gaussian id.
    pub id: u32,
    /// Depth key.
    pub key: u32,
}

/// What a run measured.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ListsRun {
    /// Hits taken.
    pub hits: u64,
    /// Cycles from the start to `busy_o` falling.
    pub cycles: u64,
    /// Most writes issued (AW accepted) and waiting for their B, over the run.
    pub max_writes_in_flight: u64,
}

/// A Verilated `neo_pre_lists`.
pub struct ListsBench {
    cfg: EngineConfig,
    model: DynModel,
    axi: AxiBinding,
    p: [usize; 12],
}

const NAMES: [&str; 12] = [
    "start_i",
    "flush_i",
    "busy_o",
    "tiles_i",
    "grid_x_i",
    "list_base_i",
    "desc_base_i",
    "hit_valid_i",
    "hit_ready_o",
    "hit_tile_x_i",
    "hit_tile_y_i",
    "hit_id_i",
];

impl ListsBench {
    /// Builds (or loads from the cache) the writer of `cfg`.
    pub fn build(cfg: &EngineConfig) -> Result<Self, String> {
        let (files, vlt) = crate::dynmodel::generated_files(cfg, NAME)?;
        let iface = neo_gen::units::pre::lists::module(cfg).interface();
        let (model, _) = DynModel::build_traced(&iface, &files, Some(&vlt), None)?;
        let mut p = [0usize; 12];
        for (k, n) in NAMES.iter().enumerate() {
            p[k] = model.port(n)?;
        }
        model.port("hit_key_i")?;
        let axi = AxiBinding::bind(&model, "m_axi_", true)?;
        Ok(ListsBench { cfg: cfg.clone(), model, axi, p })
    }

    /// The model, for waves.
    pub fn model_mut(&mut self) -> &mut DynModel {
        &mut self.model
    }

    fn set(&mut self, k: usize, v: u64) {
        self.model.set_u64(self.p[k], v);
    }

    fn get(&self, k: usize) -> u64 {
        self.model.get_u64(self.p[k])
    }

    /// Writes the lists of `hits` on a `grid` of tiles, offering a hit `offer_percent` of the
    /// cycles, with memory `timing`; checks the lists and descriptors. Stops the test at the first
    /// mismatch.
    pub fn run(
        &mut self,
        grid: [u32; 2],
        hits: &[Hit],
        offer_percent: u32,
        timing: AxiTiming,
        check: &Checker,
    ) -> ListsRun {
        let mut rng = Rng::new(check.seed);
        let tiles = u64::from(grid[0] * grid[1]);
        let bases = Bases::random(&self.cfg, &mut rng, tiles);
        let mut mem = AxiMemory::new(1, canaries(bases, tiles), timing, rng.next_u64());
        let key_port = self.model.port("hit_key_i").expect("hit_key_i");
        self.axi.set_subordinate(&mut self.model, &SubordinateSignals::default());
        for (k, v) in
            [(0, 0), (1, 0), (3, tiles), (4, u64::from(grid[0])), (5, bases.list), (6, bases.desc), (7, 0)]
        {
            self.set(k, v);
        }
        self.model.reset();
        let o = self.cfg.pre_outstanding;
        let mut chk = AxiChecker::new(0, "m_axi", o, o);
        let start = self.model.cycle();
        let limit = 4_000 + 20 * hits.len() as u64 + 8 * tiles;
        let (mut next, mut held, mut cyc_k, mut flushed) = (0usize, false, 0u64, false);
        let mut max_writes = 0;
        loop {
            let h = hits.get(next).copied();
            let offer = h.is_some() && (held || rng.percent(offer_percent));
            let h = h.unwrap_or(Hit { tile: [0, 0], id: 0, key: 0 });
            self.set(0, u64::from(cyc_k == 0));
            // Flush once every hit is taken and the writer takes hits (it is running).
            let flush = next == hits.len() && cyc_k > 0 && !flushed && self.get(8) == 1;
            self.set(1, u64::from(flush));
            self.set(7, u64::from(offer));
            self.set(9, u64::from(h.tile[0]));
            self.set(10, u64::from(h.tile[1]));
            self.set(11, u64::from(h.id));
            self.model.set_u64(key_port, u64::from(h.key));
            let sub = mem.outputs(0);
            self.axi.set_subordinate(&mut self.model, &sub);
            self.model.eval();
            let cyc = self.model.cycle();
            let man = self.axi.get_manager(&self.model);
            if let Err(v) = chk.observe(&man, &sub) {
                check.fail(cyc, "AXI protocol", "no violation", &v.to_string());
            }
            max_writes = max_writes.max(chk.in_flight().1 as u64);
            let taken = offer && self.get(8) == 1;
            held = offer && !taken;
            next += usize::from(taken);
            let done = flushed && self.get(2) == 0;
            flushed |= flush;
            mem.tick(0, &man);
            self.model.tick();
            cyc_k += 1;
            if done {
                break;
            }
            check.protocol(cyc, cyc - start < limit, "the writer finishes within its cycle budget");
        }
        let cycles = self.model.cycle() - start;
        check.value(cycles, "AXI writes open after busy_o fell", 0, chk.in_flight().1 as u64);
        check_lists(&self.cfg, bases, grid, hits, mem.memory(), check, cycles);
        ListsRun { hits: hits.len() as u64, cycles, max_writes_in_flight: max_writes }
    }
}

/// The bench memory: descriptors of `tiles` at `bases` full of canaries (the lists are checked
/// entry by entry, so they start empty).
fn canaries(bases: Bases, tiles: u64) -> Memory {
    let mut mem = Memory::new();
    mem.write(bases.desc, &vec![CANARY; (tiles * DESCRIPTOR_BYTES) as usize]);
    mem
}

/// Checks every tile's list and descriptor at `bases` against `hits`.
fn check_lists(
    cfg: &EngineConfig,
    bases: Bases,
    grid: [u32; 2],
    hits: &[Hit],
    mem: &Memory,
    check: &Checker,
    cycle: u64,
) {
    let fmt = cfg.format();
    let cap = cfg.table_capacity;
    let tiles = (grid[0] * grid[1]) as usize;
    let mut lists: Vec<Vec<SortEntry>> = vec![Vec::new(); tiles];
    for h in hits {
        lists[(h.tile[1] * grid[0] + h.tile[0]) as usize].push(SortEntry::new(h.key, h.id));
    }
    for (t, want) in lists.iter().enumerate() {
        let base = neo_golden::engine::pre::list_addr(cfg, bases.list, t as u64);
        let kept = want.len().min(cap);
        let line_end = kept.div_ceil(8) * 8;
        for k in 0..line_end {
            let got = mem.read_u64(base + ENTRY_BYTES * k as u64);
            let w = want.get(k).filter(|_| k < kept).map_or(0, |e| fmt.pack(e));
            check.value(cycle, &format!("tile {t} list entry {k}"), w, got);
        }
        let desc = bases.desc + DESCRIPTOR_BYTES * t as u64;
        let mut b = [0u8; DESCRIPTOR_BYTES as usize];
        mem.read(desc, &mut b);
        let len = u32::from_le_bytes([b[20], b[21], b[22], b[23]]);
        check.value(cycle, &format!("tile {t} descriptor list_len"), want.len() as u64, u64::from(len));
        for (k, &x) in b.iter().enumerate().filter(|(k, _)| !(20..24).contains(k)) {
            check.value(
                cycle,
                &format!("tile {t} descriptor byte {k} (not the length)"),
                u64::from(CANARY),
                u64::from(x),
            );
        }
    }
}

/// `n` random hits on `grid`, each tile's ids distinct (an id enters a tile once): hit `k`'s id
/// is `k` in its low 13 bits (`n` is at most 8192) under random upper bits of the id width.
pub fn random_hits(cfg: &EngineConfig, rng: &mut Rng, grid: [u32; 2], n: usize) -> Vec<Hit> {
    assert!(n <= 1 << 13, "{n} hits: ids are k in their low 13 bits");
    let keys = 1u64 << cfg.key_bits;
    let ids = (1u64 << cfg.id_bits) - 1;
    (0..n)
        .map(|k| Hit {
            tile: [rng.below(u64::from(grid[0])) as u32, rng.below(u64::from(grid[1])) as u32],
            id: ((rng.next_u64() & ids & !0x1fff) | k as u64) as u32,
            key: rng.below(keys) as u32,
        })
        .collect()
}
