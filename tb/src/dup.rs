//! The duplication unit's bench (`neo_pre_dup` against golden `hwpre::duplicate::incoming`):
//! a [`Source`] offers Gaussians (this frame's and the previous frame's ITU fields, a
//! visibility bit, id and key) and a [`Sink`] takes the hits, under random valid/ready
//! backpressure; the golden model lists every tile each Gaussian enters with its incoming flag;
//! the checker compares the unit's stream of tiles with it in order and stops at the first
//! mismatch.

use crate::check::Checker;
use crate::dynmodel::DynModel;
use crate::itu::{job_beat, random_jobs, ItuJob};
use crate::rng::Rng;
use crate::stream::{Beat, Sink, Source};
use neo_gen::units::pre::dup::NAME;
use neo_gen::EngineConfig;
use neo_golden::formats::FeatureEntry;
use neo_golden::hwpre::duplicate::{incoming, TouchRecord};

/// One Gaussian offered to the unit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DupItem {
    /// Gaussian id and depth key.
    pub id: u32,
    /// Depth key.
    pub key: u32,
    /// This frame's feature entry.
    pub now: FeatureEntry,
    /// The previous frame's entry, when the Gaussian was visible then.
    pub prev: Option<FeatureEntry>,
}

/// One tile the unit reports.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DupHit {
    /// Tile column and row.
    pub tile: [u32; 2],
    /// Gaussian id.
    pub id: u32,
    /// Depth key.
    pub key: u32,
    /// Incoming flag.
    pub incoming: bool,
}

/// Per-frame inputs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DupFrame {
    /// Tile grid `[columns, rows]`.
    pub grid: [u32; 2],
    /// Every Gaussian incoming.
    pub all_fresh: bool,
}

/// The golden stream of hits for `items`.
pub fn expected(cfg: &EngineConfig, frame: DupFrame, items: &[DupItem]) -> Vec<DupHit> {
    let (fmt, r) = (cfg.feature_format(), cfg.raster_config());
    let size = (frame.grid[0] * r.tile, frame.grid[1] * r.tile);
    let mut out = Vec::new();
    for it in items {
        let prev = TouchRecord { entry: it.prev.as_ref() };
        for h in incoming(&it.now, prev, &fmt, &r, size, |_, _| frame.all_fresh) {
            out.push(DupHit { tile: [h.tile_x, h.tile_y], id: it.id, key: it.key, incoming: h.incoming });
        }
    }
    out
}

/// Random Gaussians: this frame's entry from the ITU bench's mix (quantised Gaussians, random
/// octagons, arbitrary field bits), the previous one the same, slightly moved, unrelated or
/// absent.
pub fn random_items(cfg: &EngineConfig, rng: &mut Rng, count: usize) -> Vec<DupItem> {
    let fmt = cfg.feature_format();
    let nows = random_jobs(cfg, rng, count);
    let others = random_jobs(cfg, rng, count);
    let (idm, keym) = ((1u64 << cfg.id_bits) - 1, (1u64 << cfg.key_bits) - 1);
    nows.iter()
        .zip(&others)
        .map(|(now, other)| {
            let prev = match rng.below(5) {
                0 => None,
                1 => Some(now.entry),
                2 => Some(other.entry),
                _ => {
                    let mut e = now.entry;
                    let step = 1i64 << fmt.mean.frac;
                    for m in &mut e.mean {
                        let d = rng.below(40 * step as u64) as i64 - 20 * step;
                        *m = fmt.mean.saturate(*m as i64 + d) as i32;
                    }
                    Some(e)
                }
            };
            DupItem { id: rng.below(idm) as u32, key: rng.below(keym + 1) as u32, now: now.entry, prev }
        })
        .collect()
}

/// The tile grid of run `k` of a per-frame-input sweep from `g` (each side in
/// `1..=2^tile_bits - 2`): `g`, its complement in the tile index bits (`1023 - g` by default),
/// `g` again (so every bit of `grid_x_i` and `grid_y_i` rises and falls in one model), then the
/// extreme strips `1023 x 1` and `1 x 1023`.
pub fn sweep_grid(cfg: &EngineConfig, g: [u32; 2], k: usize) -> [u32; 2] {
    let max = (1u32 << cfg.tile_bits) - 1;
    let c = g.map(|v| max - v);
    [g, c, g, [max, 1], [1, max]][k % 5]
}

/// `count` of [`random_items`] whose candidate rectangles on `grid` have at most `max_tiles`
/// tiles (the walker's cycles stay bounded on a 1023-tile grid: no unbounded or screen-sized
/// extents), three in four of them at least one (inside the grid: on a 1-tile-wide strip a
/// random mean rarely is). Their means spread over the whole tile index range (the ITU bench's
/// tiles), so on a large grid their tiles, rectangles and hits reach every tile index bit.
pub fn bounded_items(
    cfg: &EngineConfig,
    rng: &mut Rng,
    grid: [u32; 2],
    count: usize,
    max_tiles: u32,
) -> Vec<DupItem> {
    let (fmt, r) = (cfg.feature_format(), cfg.raster_config());
    let size = (grid[0] * r.tile, grid[1] * r.tile);
    let mut out = Vec::with_capacity(count);
    while out.len() < count {
        for it in random_items(cfg, rng, count) {
            let tiles = neo_golden::hwpre::duplicate::candidate_count(&it.now, &fmt, &r, size);
            let inside = tiles >= 1 || out.len() % 4 == 3;
            if tiles <= max_tiles && inside && out.len() < count {
                out.push(it);
            }
        }
    }
    out
}

/// A Verilated `neo_pre_dup` and its per-frame ports.
pub struct DupBench {
    cfg: EngineConfig,
    model: DynModel,
    grid_x: usize,
    grid_y: usize,
    all_fresh: usize,
}

/// The source's data ports (one [`DupItem`] a beat, see [`item_beat`]).
const IN_PORTS: [&str; 7] = [
    "in_id_i",
    "in_key_i",
    "in_mean_i",
    "in_geom_i",
    "in_prev_visible_i",
    "in_prev_mean_i",
    "in_prev_geom_i",
];

/// The sink's data ports (one [`DupHit`] a beat) and the fields they are checked as.
const OUT_PORTS: [(&str, &str); 5] = [
    ("out_tile_x_o", "tile_x"),
    ("out_tile_y_o", "tile_y"),
    ("out_id_o", "id"),
    ("out_key_o", "key"),
    ("out_incoming_o", "incoming"),
];

/// The stream agents of a run ([`crate::stream::unit_agents`] on [`IN_PORTS`], [`OUT_PORTS`]).
fn agents(m: &DynModel, rng: &mut Rng, mix: (u32, u32)) -> Result<(Source, Sink), String> {
    let outs: Vec<&str> = OUT_PORTS.iter().map(|p| p.0).collect();
    crate::stream::unit_agents(m, &IN_PORTS, &outs, rng, mix)
}

/// The input beat of `it` on [`IN_PORTS`] (the previous-frame fields repeat this frame's when
/// the Gaussian was not visible).
fn item_beat(cfg: &EngineConfig, it: &DupItem) -> Beat {
    let entry = |e: &FeatureEntry| job_beat(cfg, &ItuJob { entry: *e, tile: [0, 0] }, 0);
    let (now, prev) = (entry(&it.now), entry(&it.prev.unwrap_or(it.now)));
    vec![
        vec![it.id],
        vec![it.key],
        now[0].clone(),
        now[1].clone(),
        vec![it.prev.is_some() as u32],
        prev[0].clone(),
        prev[1].clone(),
    ]
}

/// What a run measured.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DupRun {
    /// Hits checked.
    pub hits: usize,
    /// Cycles from the first offer to the last hit.
    pub cycles: u64,
    /// Cycles from the first Gaussian's acceptance to the last one's.
    pub accept_span: u64,
    /// Edges from the first acceptance to the first hit offered (0 without hits).
    pub first_latency: u64,
}

impl DupBench {
    /// Builds (or loads from the cache) the unit of `cfg`.
    pub fn build(cfg: &EngineConfig) -> Result<Self, String> {
        let (files, vlt) = crate::dynmodel::generated_files(cfg, NAME)?;
        let iface = neo_gen::units::pre::dup::module(cfg).interface();
        let (model, _) = DynModel::build_traced(&iface, &files, Some(&vlt), None)?;
        let (grid_x, grid_y, all_fresh) =
            (model.port("grid_x_i")?, model.port("grid_y_i")?, model.port("all_fresh_i")?);
        agents(&model, &mut Rng::new(0), (100, 100))?;
        Ok(DupBench { cfg: cfg.clone(), model, grid_x, grid_y, all_fresh })
    }

    /// The model, for waves.
    pub fn model_mut(&mut self) -> &mut DynModel {
        &mut self.model
    }

    /// Runs `items`: a [`Source`] offers a Gaussian in `p_valid`% of cycles and holds it until
    /// taken, a [`Sink`] takes hits in `p_ready`% of cycles (both forked from `rng`) and checks
    /// the output handshake; every hit is checked against [`expected`]. Panics at the first
    /// mismatch.
    pub fn run(
        &mut self,
        frame: DupFrame,
        items: &[DupItem],
        rng: &mut Rng,
        (p_valid, p_ready): (u32, u32),
        check: &Checker,
    ) -> DupRun {
        let want = expected(&self.cfg, frame, items);
        let m = &mut self.model;
        let (mut src, mut sink) = agents(m, rng, (p_valid, p_ready)).unwrap_or_else(|e| panic!("{e}"));
        for it in items {
            src.push(item_beat(&self.cfg, it));
        }
        m.reset();
        m.set_u64(self.grid_x, frame.grid[0] as u64);
        m.set_u64(self.grid_y, frame.grid[1] as u64);
        m.set_u64(self.all_fresh, frame.all_fresh as u64);
        let (mut got, mut start) = (0usize, None);
        let (mut first_accept, mut last_accept, mut first_hit) = (None, 0u64, None);
        let tiles = (frame.grid[0] * frame.grid[1]) as u64;
        let limit = m.cycle() + (items.len() as u64 * (tiles + 8) + 100) * 100 / p_valid.min(p_ready) as u64;
        while !src.is_idle() || got < want.len() {
            let cycle = m.cycle();
            check.protocol(cycle, cycle < limit, "no progress");
            src.drive(m);
            if src.offering() {
                start.get_or_insert(cycle);
            }
            sink.drive(m);
            m.eval();
            if src.sample(m) {
                first_accept.get_or_insert(cycle);
                last_accept = cycle;
            }
            let hit = sink.sample(m, check);
            if sink.valid() && first_hit.is_none() {
                first_hit = Some(cycle);
            }
            if let Some(beat) = hit {
                check.protocol(cycle, got < want.len(), "a hit beyond the golden list");
                let w = want[got];
                let fields = [w.tile[0], w.tile[1], w.id, w.key, w.incoming as u32];
                for ((_, name), (&e, a)) in OUT_PORTS.iter().zip(fields.iter().zip(&beat)) {
                    check.value(cycle, &format!("hit {got} {name}"), e as u64, a[0] as u64);
                }
                got += 1;
            }
            m.tick();
        }
        // Drain: nothing more may come out.
        sink.ready_pct = 100;
        for _ in 0..8 {
            src.drive(m);
            sink.drive(m);
            m.eval();
            let hit = sink.sample(m, check);
            check.protocol(m.cycle(), hit.is_none(), "a hit beyond the golden list");
            m.tick();
        }
        DupRun {
            hits: want.len(),
            cycles: m.cycle() - 8 - start.unwrap_or(0),
            accept_span: last_accept - first_accept.unwrap_or(last_accept),
            first_latency: first_hit.map_or(0, |h| h - first_accept.unwrap_or(h)),
        }
    }
}

/// An axis-aligned entry at pixel `(x, y)` whose four extents are the raw value `extent`
/// (`1 << extent.frac` is one pixel; the format's unbounded value never separates).
pub fn square_gaussian(cfg: &EngineConfig, x: f64, y: f64, extent: i32) -> FeatureEntry {
    let fmt = cfg.feature_format();
    FeatureEntry {
        mean: [fmt.mean.quantize(x) as i32, fmt.mean.quantize(y) as i32],
        axis: [1 << fmt.axis.frac, 0],
        extent_xy: [extent, extent],
        extent_uv: [extent, extent],
        ..Default::default()
    }
}

/// A Gaussian of one pixel's extent at pixel `(x, y)` (for timing runs).
pub fn point_gaussian(cfg: &EngineConfig, x: f64, y: f64) -> FeatureEntry {
    square_gaussian(cfg, x, y, 1 << cfg.feature_format().extent.frac)
}

/// The unit's timing for `reports/latency.json` (every hit checked against golden on the way):
/// the latency of a Gaussian with one candidate tile, the walker's cycles per candidate tile
/// over random Gaussians, and its cycles for Gaussians outside the image.
pub fn measure_timing(bench: &mut DupBench, seed: u64) -> neo_golden::formats::latency::DupUnit {
    let cfg = bench.cfg.clone();
    let (fmt, r) = (cfg.feature_format(), cfg.raster_config());
    let frame = DupFrame { grid: [20, 12], all_fresh: false };
    let size = (frame.grid[0] * r.tile, frame.grid[1] * r.tile);
    let check = Checker::new(NAME, seed);
    let mut rng = Rng::new(seed);
    let centre = r.tile as f64 / 2.0;
    let one = DupItem { id: 1, key: 1, now: point_gaussian(&cfg, centre, centre), prev: None };
    let latency = bench.run(frame, &[one], &mut rng, (100, 100), &check).first_latency;
    let items: Vec<DupItem> = random_items(&cfg, &mut rng, 600)
        .into_iter()
        .filter(|it| neo_golden::hwpre::duplicate::candidate_count(&it.now, &fmt, &r, size) > 0)
        .collect();
    let candidates: u64 = items[..items.len() - 1]
        .iter()
        .map(|it| neo_golden::hwpre::duplicate::candidate_count(&it.now, &fmt, &r, size) as u64)
        .sum();
    let run = bench.run(frame, &items, &mut rng, (100, 100), &check);
    let outside: Vec<DupItem> = (0..64)
        .map(|k| DupItem { id: k, key: k, now: point_gaussian(&cfg, -1000.0, 10.0), prev: None })
        .collect();
    let empty = bench.run(frame, &outside, &mut rng, (100, 100), &check);
    neo_golden::formats::latency::DupUnit {
        latency,
        cycles_per_candidate: run.accept_span.div_ceil(candidates),
        min_cycles_per_gaussian: empty.accept_span.div_ceil(outside.len() as u64 - 1),
        gaussians: items.len() as u64,
        candidates,
        cycles: run.accept_span,
    }
}
