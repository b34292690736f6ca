//! The duplication unit's bench (`neo_pre_dup` against golden `hwpre::duplicate::incoming`):
//! the driver offers Gaussians (this frame's and the previous frame's ITU fields, a visibility
//! bit, id and key) under random valid/ready backpressure; the golden model lists every tile
//! each Gaussian enters with its incoming flag; the checker compares the unit's stream of tiles
//! with it in order and stops at the first mismatch.

use crate::check::Checker;
use crate::dynmodel::DynModel;
use crate::itu::{job_beat, random_jobs, ItuJob};
use crate::rng::Rng;
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

/// A Verilated `neo_pre_dup` and its ports.
pub struct DupBench {
    cfg: EngineConfig,
    model: DynModel,
    p: Ports,
}

struct Ports {
    grid_x: usize,
    grid_y: usize,
    all_fresh: usize,
    in_valid: usize,
    in_ready: usize,
    id: usize,
    key: usize,
    mean: usize,
    geom: usize,
    prev_visible: usize,
    prev_mean: usize,
    prev_geom: usize,
    out_valid: usize,
    out_ready: usize,
    out_tile_x: usize,
    out_tile_y: usize,
    out_id: usize,
    out_key: usize,
    out_incoming: usize,
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
        let q = |n: &str| model.port(n);
        let p = Ports {
            grid_x: q("grid_x_i")?,
            grid_y: q("grid_y_i")?,
            all_fresh: q("all_fresh_i")?,
            in_valid: q("in_valid_i")?,
            in_ready: q("in_ready_o")?,
            id: q("in_id_i")?,
            key: q("in_key_i")?,
            mean: q("in_mean_i")?,
            geom: q("in_geom_i")?,
            prev_visible: q("in_prev_visible_i")?,
            prev_mean: q("in_prev_mean_i")?,
            prev_geom: q("in_prev_geom_i")?,
            out_valid: q("out_valid_o")?,
            out_ready: q("out_ready_i")?,
            out_tile_x: q("out_tile_x_o")?,
            out_tile_y: q("out_tile_y_o")?,
            out_id: q("out_id_o")?,
            out_key: q("out_key_o")?,
            out_incoming: q("out_incoming_o")?,
        };
        Ok(DupBench { cfg: cfg.clone(), model, p })
    }

    /// The model, for waves.
    pub fn model_mut(&mut self) -> &mut DynModel {
        &mut self.model
    }

    fn drive(&mut self, it: &DupItem) {
        let (m, p) = (&mut self.model, &self.p);
        let beat = |e: &FeatureEntry| job_beat(&self.cfg, &ItuJob { entry: *e, tile: [0, 0] }, 0);
        let now = beat(&it.now);
        m.set_u64(p.id, it.id as u64);
        m.set_u64(p.key, it.key as u64);
        m.set_words(p.mean, &now[0]);
        m.set_words(p.geom, &now[1]);
        m.set_u64(p.prev_visible, it.prev.is_some() as u64);
        let prev = beat(&it.prev.unwrap_or(it.now));
        m.set_words(p.prev_mean, &prev[0]);
        m.set_words(p.prev_geom, &prev[1]);
    }

    /// Runs `items`: a Gaussian is offered in `p_valid`% of cycles and stays offered until
    /// taken, hits are taken in `p_ready`% of cycles; checks every hit against [`expected`].
    /// Panics at the first mismatch.
    pub fn run(
        &mut self,
        frame: DupFrame,
        items: &[DupItem],
        rng: &mut Rng,
        (p_valid, p_ready): (u32, u32),
        check: &Checker,
    ) -> DupRun {
        let want = expected(&self.cfg, frame, items);
        self.model.reset();
        let p = &self.p;
        self.model.set_u64(p.grid_x, frame.grid[0] as u64);
        self.model.set_u64(p.grid_y, frame.grid[1] as u64);
        self.model.set_u64(p.all_fresh, frame.all_fresh as u64);
        let (mut next, mut got, mut start) = (0usize, 0usize, None);
        let (mut first_accept, mut last_accept, mut first_hit) = (None, 0u64, None);
        let tiles = (frame.grid[0] * frame.grid[1]) as u64;
        let limit =
            self.model.cycle() + (items.len() as u64 * (tiles + 8) + 100) * 100 / p_valid.min(p_ready) as u64;
        let mut held = false;
        while next < items.len() || got < want.len() {
            let cycle = self.model.cycle();
            check.protocol(cycle, cycle < limit, "no progress");
            // An offered item stays offered until taken (valid is never withdrawn).
            let offer = next < items.len() && (held || rng.percent(p_valid));
            self.model.set_u64(self.p.in_valid, offer as u64);
            if offer {
                start.get_or_insert(cycle);
                let it = items[next];
                self.drive(&it);
            }
            let take = rng.percent(p_ready);
            let (m, p) = (&mut self.model, &self.p);
            m.set_u64(p.out_ready, take as u64);
            m.eval();
            if m.get_u64(p.out_valid) == 1 && first_hit.is_none() {
                first_hit = Some(cycle);
            }
            if m.get_u64(p.out_valid) == 1 && take {
                check.protocol(cycle, got < want.len(), "a hit beyond the golden list");
                let w = want[got];
                let f = |n: &str| format!("hit {got} {n}");
                check.value(cycle, &f("tile_x"), w.tile[0] as u64, m.get_u64(p.out_tile_x));
                check.value(cycle, &f("tile_y"), w.tile[1] as u64, m.get_u64(p.out_tile_y));
                check.value(cycle, &f("id"), w.id as u64, m.get_u64(p.out_id));
                check.value(cycle, &f("key"), w.key as u64, m.get_u64(p.out_key));
                check.value(cycle, &f("incoming"), w.incoming as u64, m.get_u64(p.out_incoming));
                got += 1;
            }
            let taken = offer && m.get_u64(p.in_ready) == 1;
            held = offer && !taken;
            if taken {
                first_accept.get_or_insert(cycle);
                last_accept = cycle;
                next += 1;
            }
            m.tick();
        }
        // Drain: nothing more may come out.
        for _ in 0..8 {
            let (m, p) = (&mut self.model, &self.p);
            m.set_u64(p.in_valid, 0);
            m.set_u64(p.out_ready, 1);
            m.eval();
            check.protocol(m.cycle(), m.get_u64(p.out_valid) == 0, "a hit beyond the golden list");
            m.tick();
        }
        DupRun {
            hits: want.len(),
            cycles: self.model.cycle() - 8 - start.unwrap_or(0),
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
