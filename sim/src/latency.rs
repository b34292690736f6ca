//! Unit timing measured on the RTL, read from `reports/latency.json`: a
//! [`neo_golden::formats::latency::LatencyReport`] (the typed, versioned schema), written by the
//! test bench from cosimulation (`tb/src/latency.rs`). The file holds raw measurements; every fit
//! is done here or next to the formula it fits.
//!
//! Nothing here is typed in: every sorting-core cycle count the model uses is a measured point
//! of the file or an interpolation between measured points, as follows.
//!
//! - **SORT / DPS of one chunk of `n` entries**: the measured `cycles` when `n` is listed.
//!   Otherwise `T(n) = ii * n * (1 + p(n)) + c(n)`, where `p(n) = ceil(log2(ceil(n / w)))` is
//!   the number of in-chunk merge passes (`w` = `config.bsu_width`, `ii` = `units.neo_msu.ii`):
//!   the load streams `n` entries and every pass streams `n` entries through the MSU+, one per
//!   `ii` cycles ([`neo_golden::sort::merge_pass_count`]). The remainder `c(n) = cycles - ii n (1 + p(n))` (BSU fill, merge gaps, command
//!   overhead) is interpolated linearly in `n` between the two nearest measured points
//!   (extrapolated from the last two beyond the largest one).
//! - **Back to back** (`interval` of each point: cycles per command when identical commands
//!   stream): SORT / DPS `I(n) = ii * n * max(1, p(n)) + c_I(n)` (the MSU+ passes; the load is
//!   hidden under the previous chunk's passes), `c_I` interpolated as above; MERGE /
//!   MERGE_DELETE (which serialise) `T + t`, `t` the mean measured turnaround `interval - cycles`
//!   of the mode. [`crate::sortcmd`] charges a batch of commands issued back to back as one fill
//!   (the first command's single latency) plus the later commands' intervals.
//! - **MERGE / MERGE_DELETE of streams `a` and `b`**: `T = in + c`, `in = a + b`, where the
//!   overhead `c` is interpolated linearly in `in` over the measured points of the same mode with
//!   both streams non-empty, and, when one stream is empty (a copy), over the points with an
//!   empty stream (falling back to the two-stream points when there are none); `c` per entry
//!   is kept from the nearest point beyond the measured range.
//! - **Raster units** (written when the raster units are measured): `raster.itu.{ii, latency}`,
//!   `units.neo_scu.{ii, drain_ii, latency}`, and the raster core's `raster.core` grid, to which
//!   [`crate::arch::fit_raster_core`] fits the constants of
//!   [`crate::arch::raster_tile_cycles`] (empty-tile cost, load rate, per-segment overhead).
//!   Sections present replace the assumed values of [`crate::config::RasterTiming`];
//!   [`RasterSource`] records which were measured and which are still assumed.

use serde::Serialize;
use std::path::{Path, PathBuf};

use crate::config::{check_unit_cycles, check_unit_ii, RasterTiming};
use neo_golden::engine::EngineConfig;
use neo_golden::error::{InputError, InputResult};
use neo_golden::formats::latency::{self as latency_file, LatencyReport};
use neo_golden::sort::merge_pass_count;

/// The schema this reader understands (the one golden defines).
pub const SCHEMA: &str = latency_file::SCHEMA;

/// The default location, relative to the project root.
pub const DEFAULT_PATH: &str = "reports/latency.json";

/// One measured chunk command.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct ChunkPoint {
    /// Entries in the chunk.
    pub entries: u64,
    /// Measured cycles of one command alone.
    pub cycles: u64,
    /// Measured steady-state cycles per command back to back.
    pub interval: u64,
}

/// One measured merge command.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct MergePoint {
    /// Entries of stream A.
    pub len_a: u64,
    /// Entries of stream B.
    pub len_b: u64,
    /// Measured cycles of one command alone.
    pub cycles: u64,
    /// Measured steady-state cycles per command back to back.
    pub interval: u64,
}

/// Where the raster-core timing came from.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub enum RasterSource {
    /// No `raster` section: every raster number is assumed, not measured.
    Assumed,
    /// From `latency.json`: the `fields` were measured, the `assumed` ones were not.
    Measured {
        /// Fields read from the file (e.g. `raster.itu.ii`).
        fields: Vec<String>,
        /// Raster parameters still assumed (e.g. `tile_overhead`).
        assumed: Vec<String>,
    },
}

impl RasterSource {
    /// A one-line label for reports.
    pub fn label(&self) -> String {
        match self {
            RasterSource::Assumed => "raster-core timing ASSUMED, not measured (no raster figures in latency.json)".into(),
            RasterSource::Measured { fields, assumed } if assumed.is_empty() => {
                format!("raster-core timing measured (latency.json: {})", fields.join(", "))
            }
            RasterSource::Measured { fields, assumed } => format!(
                "raster-core timing measured for {} (latency.json); ASSUMED, not measured: {} (config raster_assumed)",
                fields.join(", "),
                assumed.join(", ")
            ),
        }
    }
}

/// The Preprocessing Engine's timing measured on the RTL (`preprocess` of the file); each
/// `None` was not measured and stays assumed (config `preprocess.*`).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct PreprocessMeasured {
    /// Projection unit: cycles per Gaussian and pipeline latency.
    pub projection: Option<(f64, u64)>,
    /// Colour unit: cycles per visible Gaussian and pipeline latency.
    pub color: Option<(f64, u64)>,
    /// Duplication unit: walker cycles per candidate tile and latency.
    pub duplication: Option<(f64, u64)>,
    /// The fetch units' outstanding-read window, in 64-byte lines (all units together).
    pub read_window: Option<u32>,
}

impl PreprocessMeasured {
    fn from_report(r: &LatencyReport) -> Result<Self, String> {
        let Some(p) = &r.preprocess else { return Ok(Self::default()) };
        let unit =
            |u: Option<latency_file::DatapathUnit>, name: &str| -> Result<Option<(f64, u64)>, String> {
                match u {
                    Some(u) if u.ii == 0 => Err(format!("`preprocess.{name}.ii` must be positive")),
                    Some(u) => Ok(Some((u.ii as f64, u.latency))),
                    None => Ok(None),
                }
            };
        let duplication = match p.duplication {
            Some(d) if d.cycles_per_candidate == 0 => {
                return Err("`preprocess.duplication.cycles_per_candidate` must be positive".into())
            }
            Some(d) => Some((d.cycles_per_candidate as f64, d.latency)),
            None => None,
        };
        let read_window = match p.fetch {
            Some(f) if f.window_lines() == 0 || f.window_lines() > u64::from(u32::MAX) => {
                return Err(format!("`preprocess.fetch` gives a window of {} lines", f.window_lines()))
            }
            Some(f) => Some(f.window_lines() as u32),
            None => None,
        };
        Ok(PreprocessMeasured {
            projection: unit(p.projection, "projection")?,
            color: unit(p.color, "color")?,
            duplication,
            read_window,
        })
    }

    /// `assumed` with every measured field replaced. The pipeline fill is the projection's
    /// latency plus the longer of the colour's and the duplication's (they follow it side by
    /// side) once all three are measured.
    pub fn over(&self, assumed: &crate::config::PreprocessTiming) -> crate::config::PreprocessTiming {
        let mut t = assumed.clone();
        if let Some((ii, _)) = self.projection {
            t.projection_ii = ii;
        }
        if let Some((ii, _)) = self.color {
            t.color_ii = ii;
        }
        if let Some((ii, _)) = self.duplication {
            t.duplication_ii = ii;
        }
        if let (Some(p), Some(c), Some(d)) = (self.projection, self.color, self.duplication) {
            t.latency = p.1 + c.1.max(d.1);
        }
        t
    }

    /// The preprocessing engine's outstanding-read window in lines: the measured one, else
    /// `assumed` (config `neo.preprocess_read_window`).
    pub fn window(&self, assumed: u32) -> u32 {
        self.read_window.unwrap_or(assumed)
    }

    /// A one-line label for reports: what is measured, what is still assumed.
    pub fn label(&self) -> String {
        let units =
            [("projection", self.projection), ("colour", self.color), ("duplication", self.duplication)];
        let measured: Vec<&str> = units.iter().filter(|u| u.1.is_some()).map(|u| u.0).collect();
        let assumed: Vec<&str> = units.iter().filter(|u| u.1.is_none()).map(|u| u.0).collect();
        match (measured.is_empty(), assumed.is_empty()) {
            (true, _) => "preprocessing-engine timing ASSUMED, not measured (config preprocess.*)".into(),
            (false, true) => match self.read_window {
                Some(w) => format!(
                    "preprocessing-engine timing measured on the RTL ({}, and the fetch units' read window of {w} lines; latency.json preprocess)",
                    measured.join(", ")
                ),
                None => format!(
                    "preprocessing-engine timing measured on the RTL ({}; latency.json preprocess); its outstanding-read window is assumed (config neo.preprocess_read_window)",
                    measured.join(", ")
                ),
            },
            (false, false) => format!(
                "preprocessing-engine timing measured for {} (latency.json preprocess); ASSUMED, not measured: {} (config preprocess.*)",
                measured.join(", "),
                assumed.join(", ")
            ),
        }
    }
}

/// Chunk command kind.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ChunkMode {
    /// Conventional SORT of one chunk.
    Sort,
    /// DPS of one chunk.
    Dps,
}

/// The measured timing the model uses.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Latency {
    /// The file read.
    pub source: PathBuf,
    /// The engine configuration the RTL was measured on (BSU width, chunk, ...).
    pub config: EngineConfig,
    /// MSU+ initiation interval (cycles per output entry).
    pub msu_ii: f64,
    /// BSU latency.
    pub bsu_latency: u64,
    /// Cycles from accepting a zero-length command to `done_o`.
    pub command_overhead: u64,
    /// SORT points, ascending entries.
    pub conventional: Vec<ChunkPoint>,
    /// DPS points, ascending entries.
    pub dps: Vec<ChunkPoint>,
    /// MERGE points.
    pub merge: Vec<MergePoint>,
    /// MERGE_DELETE points (every fourth entry invalid).
    pub merge_delete: Vec<MergePoint>,
    /// Raster timing: measured fields over the assumed defaults.
    pub raster: RasterTiming,
    /// Where the raster timing came from.
    pub raster_source: RasterSource,
    /// The preprocessing units measured so far.
    pub preprocess: PreprocessMeasured,
    /// The measured SCU (`units.neo_scu`), refitted over other assumed values by
    /// [`Latency::raster_over`].
    #[serde(skip)]
    scu: Option<latency_file::ScuUnit>,
    /// The measured raster section (`raster`), as `scu`.
    #[serde(skip)]
    raster_measured: Option<latency_file::Raster>,
}

fn chunk_points(points: &[latency_file::ChunkPoint], key: &str) -> Result<Vec<ChunkPoint>, String> {
    let mut out: Vec<ChunkPoint> = points
        .iter()
        .map(|p| ChunkPoint { entries: p.entries, cycles: p.cycles, interval: p.interval })
        .collect();
    out.sort_by_key(|p| p.entries);
    out.dedup_by_key(|p| p.entries);
    if out.iter().filter(|p| p.entries > 0).count() < 2 {
        return Err(format!("`sort_core.{key}` needs at least two measured chunk sizes"));
    }
    Ok(out)
}

fn merge_points<'p>(
    points: impl Iterator<Item = &'p latency_file::MergePoint>,
    key: &str,
) -> Result<Vec<MergePoint>, String> {
    let out: Vec<MergePoint> = points
        .map(|p| MergePoint { len_a: p.len_a, len_b: p.len_b, cycles: p.cycles, interval: p.interval })
        .collect();
    if out.iter().filter(|p| p.len_a > 0 && p.len_b > 0).count() < 2 {
        return Err(format!("`sort_core.{key}` needs at least two measured merges of two non-empty streams"));
    }
    Ok(out)
}

/// Linear interpolation of `y` at `x` over points sorted by `x` (extrapolating from the two
/// nearest at either end).
fn interp(points: &[(f64, f64)], x: f64) -> f64 {
    debug_assert!(points.len() >= 2);
    let i = points.partition_point(|p| p.0 <= x).clamp(1, points.len() - 1);
    let (x0, y0) = points[i - 1];
    let (x1, y1) = points[i];
    if x1 == x0 {
        return y0;
    }
    y0 + (y1 - y0) * (x - x0) / (x1 - x0)
}

impl Latency {
    /// Reads and checks `path`.
    pub fn from_file(path: &Path) -> InputResult<Self> {
        let text = std::fs::read_to_string(path).map_err(|e| InputError::new(path, e.to_string()))?;
        Self::from_json_str(&text, path)
    }

    /// Parses the document `text` (named `path` in errors): the schema version, every field's
    /// type (golden's [`LatencyReport`]), then what the model needs of the values.
    pub fn from_json_str(text: &str, path: &Path) -> InputResult<Self> {
        let report = LatencyReport::from_json_str(text, path)?;
        // serde reads an array as a struct, field by field: the document must have the shape of
        // the report it was read as.
        let value: serde_json::Value =
            serde_json::from_str(text).map_err(|e| InputError::new(path, format!("not JSON: {e}")))?;
        let shape = serde_json::to_value(&report).map_err(|e| InputError::new(path, e.to_string()))?;
        neo_golden::json_shape::check_shape(&value, &shape).map_err(|e| InputError::new(path, e))?;
        Self::from_report(&report, path).map_err(|e| InputError::new(path, e))
    }

    /// The model's timing from a parsed report (read from `path`).
    pub fn from_report(r: &LatencyReport, path: &Path) -> Result<Self, String> {
        if r.config.bsu_width == 0 {
            return Err("`config.bsu_width` must be positive".into());
        }
        if r.units.neo_msu.ii == 0 {
            return Err("`units.neo_msu.ii` must be positive".into());
        }
        check_measured_bounds(r)?;
        let (raster, raster_source) =
            raster_timing(r.units.neo_scu.as_ref(), r.raster.as_ref(), &RasterTiming::default())?;
        let sc = &r.sort_core;
        Ok(Latency {
            source: path.to_path_buf(),
            config: r.config.clone(),
            msu_ii: r.units.neo_msu.ii as f64,
            bsu_latency: r.units.neo_bsu.latency,
            command_overhead: r.units.neo_sort_core.command_overhead,
            conventional: chunk_points(&sc.conventional, "conventional")?,
            dps: chunk_points(&sc.dps, "dps")?,
            merge: merge_points(sc.merge.iter(), "merge")?,
            merge_delete: merge_points(sc.merge_delete.iter().map(|p| &p.merge), "merge_delete")?,
            raster,
            raster_source,
            preprocess: PreprocessMeasured::from_report(r)?,
            scu: r.units.neo_scu,
            raster_measured: r.raster.clone(),
        })
    }

    /// The raster timing over `assumed` (config `raster_assumed`): the measured fields replace
    /// its values, the raster core's constants are fitted over it; over the default assumed
    /// values this is [`Latency::raster`].
    pub fn raster_over(&self, assumed: &RasterTiming) -> Result<RasterTiming, String> {
        raster_timing(self.scu.as_ref(), self.raster_measured.as_ref(), assumed)
            .map(|(t, _)| t)
            .map_err(|e| format!("{}: {e}", self.source.display()))
    }

    /// Refuses to time `engine` with these measurements when they were made on another
    /// configuration: the error names the file, the first field that differs and both values.
    /// The wide DPS chunk (`dps_wide`) may differ: it deepens the sorting core's buffers, not
    /// its datapath, and a chunk longer than the measured points is timed as any unmeasured
    /// length ([`Latency::chunk_cycles`]). So may the raster core's reorder window
    /// (`raster_window`): it delays a tile's loads by the entries it holds, timed at the
    /// measured load rate ([`crate::arch::raster_tile_cycles`]; checked against the RTL by the
    /// engine benches' window cases).
    pub fn check_engine(&self, engine: &EngineConfig) -> InputResult<()> {
        let engine = EngineConfig {
            dps_wide: self.config.dps_wide,
            raster_window: self.config.raster_window,
            ..engine.clone()
        };
        match engine.first_difference(&self.config) {
            None => Ok(()),
            Some((field, ours, measured)) => Err(InputError::new(
                &self.source,
                format!(
                    "measured on an engine with {field} = {measured}, but the model's engine.{field} = {ours}; \
                     measure that configuration (NEO_UPDATE_REPORTS=1 with its config) or simulate the measured one"
                ),
            )),
        }
    }

    /// In-chunk merge passes of an `n`-entry chunk.
    pub fn passes(&self, n: u64) -> u64 {
        merge_pass_count(n, self.config.bsu_width as u64)
    }

    /// The Neo artifact's cycle model of an `n`-entry chunk's sort, for comparison
    /// (docs/cycle-model.md): the in-chunk merge passes only, one entry per cycle,
    /// `ceil(log2(n / bsu_width)) * n`. A model, not a measurement: derived here, not stored in
    /// `latency.json`.
    pub fn artifact_chunk_cycles(&self, n: u64) -> u64 {
        self.passes(n) * n
    }

    fn structural(&self, n: u64) -> f64 {
        self.msu_ii * n as f64 * (1 + self.passes(n)) as f64
    }

    /// The MSU+ work of an `n`-entry chunk: `max(1, passes)` passes of `n` entries.
    fn structural_interval(&self, n: u64) -> f64 {
        self.msu_ii * n as f64 * self.passes(n).max(1) as f64
    }

    fn chunk_points(&self, mode: ChunkMode) -> &[ChunkPoint] {
        match mode {
            ChunkMode::Sort => &self.conventional,
            ChunkMode::Dps => &self.dps,
        }
    }

    /// `value` of the measured point at `n`, else `structural(n)` plus the remainder
    /// interpolated between the measured points.
    fn chunk_interp(
        &self,
        mode: ChunkMode,
        n: u64,
        value: impl Fn(&ChunkPoint) -> u64,
        structural: impl Fn(u64) -> f64,
    ) -> u64 {
        if n == 0 {
            return 0;
        }
        let pts = self.chunk_points(mode);
        if let Some(p) = pts.iter().find(|p| p.entries == n) {
            return value(p);
        }
        let rem: Vec<(f64, f64)> = pts
            .iter()
            .filter(|p| p.entries > 0)
            .map(|p| (p.entries as f64, value(p) as f64 - structural(p.entries)))
            .collect();
        let c = interp(&rem, n as f64);
        (structural(n) + c).round().max(1.0) as u64
    }

    /// Cycles of one SORT or DPS command on an `n`-entry chunk alone (0 for an empty chunk: no
    /// command is issued). See the module docs for the interpolation.
    pub fn chunk_cycles(&self, mode: ChunkMode, n: u64) -> u64 {
        self.chunk_interp(mode, n, |p| p.cycles, |n| self.structural(n))
    }

    /// Steady-state cycles per SORT or DPS command of `n` entries issued back to back (0 for an
    /// empty chunk). See the module docs for the interpolation.
    pub fn chunk_interval(&self, mode: ChunkMode, n: u64) -> u64 {
        self.chunk_interp(mode, n, |p| p.interval, |n| self.structural_interval(n))
    }

    /// Steady-state cycles per MERGE / MERGE_DELETE command back to back: the measured
    /// `interval` of the point, else [`Latency::merge_cycles`] plus the mode's mean measured
    /// turnaround (`interval - cycles`).
    pub fn merge_interval(&self, a: u64, b: u64, drop_invalid: bool) -> u64 {
        let pts = if drop_invalid { &self.merge_delete } else { &self.merge };
        if let Some(p) = pts.iter().find(|p| p.len_a == a && p.len_b == b) {
            return p.interval;
        }
        let turn = pts.iter().map(|p| p.interval as f64 - p.cycles as f64).sum::<f64>() / pts.len() as f64;
        (self.merge_cycles(a, b, drop_invalid) as f64 + turn.max(0.0)).round() as u64
    }

    /// Cycles of a MERGE (`drop_invalid = false`) or MERGE_DELETE command of streams of `a` and
    /// `b` entries. See the module docs for the interpolation.
    pub fn merge_cycles(&self, a: u64, b: u64, drop_invalid: bool) -> u64 {
        let pts = if drop_invalid { &self.merge_delete } else { &self.merge };
        if let Some(p) = pts.iter().find(|p| p.len_a == a && p.len_b == b) {
            return p.cycles;
        }
        let n = a + b;
        let copy = a == 0 || b == 0;
        let select = |want_copy: bool| -> Vec<(f64, f64)> {
            let mut v: Vec<(f64, f64)> = pts
                .iter()
                .filter(|p| p.len_a + p.len_b > 0 && ((p.len_a == 0 || p.len_b == 0) == want_copy))
                .map(|p| ((p.len_a + p.len_b) as f64, p.cycles as f64 - (p.len_a + p.len_b) as f64))
                .collect();
            v.sort_by(|x, y| x.0.total_cmp(&y.0));
            v.dedup_by(|x, y| x.0 == y.0);
            v
        };
        let mut pts2 = if copy { select(true) } else { Vec::new() };
        if pts2.is_empty() {
            pts2 = select(false);
        }
        let zero = pts.iter().find(|p| p.len_a + p.len_b == 0).map(|p| p.cycles);
        if n == 0 {
            return zero.unwrap_or(self.command_overhead.max(1));
        }
        let x = n as f64;
        let c = if pts2.len() == 1 {
            pts2[0].1 / pts2[0].0 * x
        } else if x > pts2.last().map_or(0.0, |p| p.0) {
            let last = pts2[pts2.len() - 1];
            last.1 / last.0 * x
        } else if x < pts2[0].0 {
            // Between the empty merge (if measured) and the smallest point.
            let (x1, c1) = pts2[0];
            let c0 = zero.map_or(0.0, |z| z as f64);
            c0 + (c1 - c0) * x / x1
        } else {
            interp(&pts2, x)
        };
        (x + c).round().max(1.0) as u64
    }
}

/// The keys of `latency.json`'s measured sections (`units`, `sort_core`, `raster`,
/// `preprocess`) holding an initiation interval: each at most [`crate::config::MAX_UNIT_II`] cycles per item.
const II_KEYS: [&str; 4] = ["ii", "drain_ii", "cycles_per_candidate", "min_cycles_per_gaussian"];

/// The keys of the measured sections holding a cycle count (a latency, a command's cycles, an
/// interval, an overhead): each at most [`crate::config::MAX_UNIT_CYCLES`].
const CYCLE_KEYS: [&str; 9] = [
    "latency",
    "cycles",
    "interval",
    "load_cycles",
    "pixel_writes",
    "command_overhead",
    "settle",
    "merge_gap",
    "read_latency",
];

/// Checks every measured timing of `r` (by key, [`II_KEYS`] and [`CYCLE_KEYS`], wherever it
/// is in the measured sections) against the bounds of any unit timing; the error names the
/// field's path (`sort_core.merge[3].cycles`).
fn check_measured_bounds(r: &LatencyReport) -> Result<(), String> {
    fn walk(v: &serde_json::Value, path: &str) -> Result<(), String> {
        match v {
            serde_json::Value::Object(m) => m.iter().try_for_each(|(k, v)| {
                let at = format!("{path}.{k}");
                match v.as_f64() {
                    Some(x) if II_KEYS.contains(&k.as_str()) => check_unit_ii(x, &format!("`{at}`"), false),
                    Some(x) if CYCLE_KEYS.contains(&k.as_str()) => check_unit_cycles(x, &format!("`{at}`")),
                    _ => walk(v, &at),
                }
            }),
            serde_json::Value::Array(a) => {
                a.iter().enumerate().try_for_each(|(i, v)| walk(v, &format!("{path}[{i}]")))
            }
            _ => Ok(()),
        }
    }
    let v = serde_json::to_value(r).map_err(|e| e.to_string())?;
    for section in ["units", "sort_core", "raster", "preprocess"] {
        if let Some(s) = v.get(section) {
            walk(s, section)?;
        }
    }
    Ok(())
}

/// Raster timing: the measured fields (`scu`: `units.neo_scu`; `raster`) over the `assumed`
/// values (config `raster_assumed`), the raster core's fitted with its formula
/// ([`crate::arch::fit_raster_core`]).
fn raster_timing(
    scu: Option<&latency_file::ScuUnit>,
    raster: Option<&latency_file::Raster>,
    assumed: &RasterTiming,
) -> Result<(RasterTiming, RasterSource), String> {
    let mut t = assumed.clone();
    let mut measured: Vec<String> = Vec::new();
    let itu = raster.and_then(|x| x.itu);
    if let Some(itu) = itu {
        if !(itu.ii > 0.0 && itu.ii.is_finite()) {
            return Err(format!("`raster.itu.ii` = {}: must be positive", itu.ii));
        }
        t.itu_ii = itu.ii;
        t.itu_latency = itu.latency;
        measured.extend(["raster.itu.ii".into(), "raster.itu.latency".into()]);
    }
    if let Some(scu) = scu {
        if scu.ii == 0 {
            return Err("`units.neo_scu.ii` must be positive".into());
        }
        t.scu_cycles_per_pair = scu.ii as f64;
        t.scu_drain_ii = scu.drain_ii as f64;
        t.scu_latency = scu.latency;
        measured.extend([
            "units.neo_scu.ii".into(),
            "units.neo_scu.drain_ii".into(),
            "units.neo_scu.latency".into(),
        ]);
    }
    let core = raster.and_then(|x| x.core.as_ref());
    if let Some(core) = core {
        let itu = itu.ok_or("`raster.core` needs `raster.itu` (the subtiles per tile)")?;
        t = crate::arch::fit_raster_core(core, itu.subtiles_per_job, &t)
            .map_err(|e| format!("`raster.core`: {e}"))?;
        measured.extend([
            "raster.core.pixel_writes".into(),
            "raster.core.feature_buffer".into(),
            "raster.core.grid (fitted: tile_overhead, load_cycles_per_entry, segment_overhead)".into(),
        ]);
    }
    if raster.is_some() && itu.is_none() && core.is_none() {
        return Err("`raster` has neither `itu` nor `core` (see docs/cycle-model.md)".into());
    }
    let assumed: Vec<String> = [
        (itu.is_none(), &["itu_ii", "itu_latency"][..]),
        (scu.is_none(), &["scu_cycles_per_pair", "scu_drain_ii", "scu_latency"][..]),
        (
            core.is_none(),
            &[
                "tile_overhead",
                "load_cycles_per_entry",
                "pixel_write_cycles",
                "feature_buffer",
                "segment_overhead",
            ][..],
        ),
    ]
    .into_iter()
    .filter(|(absent, _)| *absent)
    .flat_map(|(_, names)| names.iter().map(|n| n.to_string()))
    .collect();
    let src = if measured.is_empty() {
        RasterSource::Assumed
    } else {
        RasterSource::Measured { fields: measured, assumed }
    };
    Ok((t, src))
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::Value;

    fn project_file() -> PathBuf {
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..").join(DEFAULT_PATH)
    }

    #[test]
    fn the_artifact_model_counts_the_merge_passes_at_one_entry_a_cycle() {
        let l = Latency::from_file(&project_file()).unwrap();
        assert_eq!(l.config.bsu_width, 16);
        for (n, cycles) in [(1, 0), (16, 0), (32, 32), (100, 3 * 100), (256, 4 * 256)] {
            assert_eq!(l.artifact_chunk_cycles(n), cycles, "n = {n}");
        }
    }

    #[test]
    fn measured_points_are_returned_exactly() {
        let l = Latency::from_file(&project_file()).unwrap();
        for p in &l.conventional {
            assert_eq!(l.chunk_cycles(ChunkMode::Sort, p.entries), if p.entries == 0 { 0 } else { p.cycles });
            assert_eq!(
                l.chunk_interval(ChunkMode::Sort, p.entries),
                if p.entries == 0 { 0 } else { p.interval }
            );
        }
        for p in &l.dps {
            assert_eq!(l.chunk_cycles(ChunkMode::Dps, p.entries), if p.entries == 0 { 0 } else { p.cycles });
        }
        for p in &l.merge {
            assert_eq!(l.merge_cycles(p.len_a, p.len_b, false), p.cycles);
            assert_eq!(l.merge_interval(p.len_a, p.len_b, false), p.interval);
        }
        for p in &l.merge_delete {
            assert_eq!(l.merge_cycles(p.len_a, p.len_b, true), p.cycles);
        }
    }

    #[test]
    fn a_report_of_another_engine_is_refused_naming_the_field_and_both_values() {
        let l = Latency::from_file(&project_file()).unwrap();
        l.check_engine(&EngineConfig::default()).expect("the project's report is of the default engine");
        let other = EngineConfig { bsu_width: 32, ..EngineConfig::default() };
        let e = l.check_engine(&other).unwrap_err().to_string();
        assert!(e.contains("latency.json"), "{e}");
        assert!(e.contains("bsu_width = 16") && e.contains("engine.bsu_width = 32"), "{e}");
        let other = EngineConfig { sort_cores: 8, ..EngineConfig::default() };
        let e = l.check_engine(&other).unwrap_err().to_string();
        assert!(e.contains("sort_cores = 16") && e.contains("engine.sort_cores = 8"), "{e}");
        let wide = EngineConfig { dps_wide: 16, ..EngineConfig::default() };
        l.check_engine(&wide).expect("the wide chunk keeps the measured datapath");
    }

    #[test]
    fn interpolation_is_monotone_and_between_neighbours() {
        let l = Latency::from_file(&project_file()).unwrap();
        let mut last = 0;
        for n in 1..=l.config.chunk as u64 {
            let c = l.chunk_cycles(ChunkMode::Sort, n);
            assert!(c >= last, "SORT cycles not monotone at {n}: {c} < {last}");
            assert!(c as f64 >= l.msu_ii * n as f64, "a chunk cannot beat one entry per cycle");
            let i = l.chunk_interval(ChunkMode::Sort, n);
            assert!(i as f64 >= l.msu_ii * n as f64, "back to back, a chunk still takes one MSU+ pass: {n}");
            assert!(i <= c, "the interval at {n} ({i}) exceeds the single-command latency ({c})");
            last = c;
        }
        assert!(l.merge_interval(300, 200, true) >= l.merge_cycles(300, 200, true));
        let mut last = 0;
        for n in (0..3000).step_by(7) {
            let c = l.merge_cycles(n / 2, n - n / 2, false);
            assert!(c >= last && c >= n, "MERGE cycles at {n}: {c}");
            last = c;
        }
        assert!(l.merge_cycles(1000, 0, true) >= 1000);
    }

    #[test]
    fn errors_name_the_file_and_field() {
        let p = Path::new("lat.json");
        let bad = |s: &str| Latency::from_json_str(s, p).unwrap_err().to_string();
        assert!(bad("{").contains("lat.json: not JSON"));
        let e = bad(r#"{"schema": "neo-latency/1"}"#);
        assert!(e.starts_with("lat.json: ") && e.contains("'neo-latency/1'") && e.contains(SCHEMA), "{e}");
        let text = std::fs::read_to_string(project_file()).unwrap();
        let mut v: Value = serde_json::from_str(&text).unwrap();
        v["units"]["neo_msu"].as_object_mut().unwrap().remove("ii");
        let e = bad(&v.to_string());
        assert!(e.contains("units.neo_msu") && e.contains("`ii`"), "{e}");
        v["units"]["neo_msu"]["ii"] = 0.into();
        assert!(bad(&v.to_string()).contains("`units.neo_msu.ii` must be positive"));
        for key in ["conventional", "merge_delete"] {
            let mut v: Value = serde_json::from_str(&text).unwrap();
            v["sort_core"][key][1].as_object_mut().unwrap().remove("interval");
            let e = bad(&v.to_string());
            assert!(
                e.contains("lat.json")
                    && e.contains(&format!("sort_core.{key}[1]"))
                    && e.contains("interval"),
                "{e}"
            );
        }
        let mut v: Value = serde_json::from_str(&text).unwrap();
        v["sort_core"]["dps"].as_array_mut().unwrap().truncate(1);
        assert!(bad(&v.to_string()).contains("`sort_core.dps` needs at least two"));
        let mut v: Value = serde_json::from_str(&text).unwrap();
        v.as_object_mut().unwrap().remove("raster");
        v["units"].as_object_mut().unwrap().remove("neo_scu");
        let l = Latency::from_json_str(&v.to_string(), p).unwrap();
        assert_eq!(l.raster_source, RasterSource::Assumed);
        assert_eq!(l.raster, RasterTiming::default());
        v["raster"] =
            serde_json::json!({"itu": {"ii": 0.5, "latency": 2, "jobs": 1, "subtiles_per_job": 64}});
        let l = Latency::from_json_str(&v.to_string(), p).unwrap();
        assert_eq!((l.raster.itu_ii, l.raster.itu_latency), (0.5, 2));
        match &l.raster_source {
            RasterSource::Measured { fields, assumed } => {
                assert_eq!(fields, &vec!["raster.itu.ii".to_string(), "raster.itu.latency".into()]);
                assert!(assumed.contains(&"tile_overhead".to_string()));
                assert!(assumed.contains(&"scu_cycles_per_pair".to_string()));
            }
            other => panic!("{other:?}"),
        }
        assert!(l.raster_source.label().contains("ASSUMED"));
        v["raster"] = serde_json::json!({});
        assert!(bad(&v.to_string()).contains("`raster` has neither"));
        let mut v: Value = serde_json::from_str(&text).unwrap();
        v["raster"]["core"]["grid"].as_array_mut().unwrap().retain(|p| p["entries"] != 0);
        let e = bad(&v.to_string());
        assert!(e.contains("raster.core") && e.contains("no empty table"), "{e}");
    }

    #[test]
    fn the_raster_core_is_fitted_from_the_grid() {
        let l = Latency::from_file(&project_file()).unwrap();
        let r = LatencyReport::from_file(&project_file()).unwrap();
        let core = r.raster.as_ref().and_then(|x| x.core.as_ref()).unwrap();
        let empty = core.grid.iter().find(|p| p.entries == 0).unwrap();
        assert_eq!(l.raster.tile_overhead, empty.cycles - core.pixel_writes);
        assert_eq!(
            (l.raster.pixel_write_cycles, l.raster.feature_buffer),
            (core.pixel_writes, core.feature_buffer)
        );
        // Every one-segment point of one bit per Gaussian loads at the fitted rate after the first.
        let first =
            core.grid.iter().filter(|p| p.bits_per_gaussian == 1 && p.entries > 0).min_by_key(|p| p.entries);
        for p in core
            .grid
            .iter()
            .filter(|p| p.bits_per_gaussian == 1 && p.entries > 0 && p.entries <= core.feature_buffer)
        {
            let f = first.unwrap();
            let predicted =
                f.load_cycles as f64 + l.raster.load_cycles_per_entry * (p.entries - f.entries) as f64;
            assert_eq!(predicted, p.load_cycles as f64, "loads of {} entries", p.entries);
        }
        assert!(l.raster.segment_overhead >= 0.0 && l.raster.segment_overhead.fract() == 0.0);
        match &l.raster_source {
            RasterSource::Measured { assumed, .. } => assert!(assumed.is_empty(), "{assumed:?}"),
            other => panic!("{other:?}"),
        }
    }

    /// Measured timings beyond any unit's (1e15 or 2^64 - 1 cycles hung the model) are refused
    /// naming the file and the field's path; so is an array in place of a section.
    #[test]
    fn absurd_measurements_and_arrays_are_refused_naming_the_field() {
        let p = Path::new("lat.json");
        let text = std::fs::read_to_string(project_file()).unwrap();
        let bad = |f: &dyn Fn(&mut Value)| {
            let mut v: Value = serde_json::from_str(&text).unwrap();
            f(&mut v);
            Latency::from_json_str(&v.to_string(), p).unwrap_err().to_string()
        };
        let big = 1_000_000_000_000_000u64;
        for (want, f) in [
            (
                "`units.neo_scu.ii`",
                &(|v: &mut Value| v["units"]["neo_scu"]["ii"] = u64::MAX.into()) as &dyn Fn(&mut Value),
            ),
            ("`units.neo_msu.ii`", &|v: &mut Value| v["units"]["neo_msu"]["ii"] = big.into()),
            ("`raster.itu.ii`", &|v: &mut Value| v["raster"]["itu"]["ii"] = 1e15.into()),
            ("`preprocess.projection.ii`", &|v: &mut Value| v["preprocess"]["projection"]["ii"] = big.into()),
            ("`preprocess.color.latency`", &|v: &mut Value| v["preprocess"]["color"]["latency"] = big.into()),
            ("`raster.core.pixel_writes`", &|v: &mut Value| v["raster"]["core"]["pixel_writes"] = big.into()),
            ("`raster.core.grid[0].cycles`", &|v: &mut Value| {
                v["raster"]["core"]["grid"][0]["cycles"] = big.into()
            }),
            ("`sort_core.conventional[2].cycles`", &|v: &mut Value| {
                v["sort_core"]["conventional"][2]["cycles"] = u64::MAX.into()
            }),
            ("`sort_core.merge[3].interval`", &|v: &mut Value| {
                v["sort_core"]["merge"][3]["interval"] = big.into()
            }),
            ("units.neo_msu: expected an object, found an array", &|v: &mut Value| {
                v["units"]["neo_msu"] = serde_json::json!([1, 1, 1, 1, 1])
            }),
        ] {
            let e = bad(f);
            assert!(e.starts_with("lat.json: ") && e.contains(want), "{want}: {e}");
        }
        let mut v: Value = serde_json::from_str(&text).unwrap();
        v["sort_core"]["merge"][3]["interval"] = (crate::config::MAX_UNIT_CYCLES).into();
        Latency::from_json_str(&v.to_string(), p).expect("the bound itself is accepted");
    }

    /// Without measured raster figures the config's `raster_assumed` is the raster timing (it was
    /// ignored: the reader started from the defaults); measured fields still replace it, and
    /// over the default assumed values it is the reader's own.
    #[test]
    fn the_assumed_raster_timing_is_the_configs() {
        let l = Latency::from_file(&project_file()).unwrap();
        assert_eq!(l.raster_over(&RasterTiming::default()).unwrap(), l.raster);
        let assumed = RasterTiming {
            itu_ii: 1000.0,
            scu_cycles_per_pair: 1000.0,
            tile_overhead: 100_000,
            ..RasterTiming::default()
        };
        let measured = l.raster_over(&assumed).unwrap();
        assert_eq!(
            (measured.itu_ii, measured.scu_cycles_per_pair),
            (l.raster.itu_ii, l.raster.scu_cycles_per_pair)
        );
        let text = std::fs::read_to_string(project_file()).unwrap();
        let mut v: Value = serde_json::from_str(&text).unwrap();
        v.as_object_mut().unwrap().remove("raster");
        v["units"].as_object_mut().unwrap().remove("neo_scu");
        let l = Latency::from_json_str(&v.to_string(), Path::new("lat.json")).unwrap();
        assert_eq!(l.raster_over(&assumed).unwrap(), assumed);
        assert_eq!(l.raster_over(&RasterTiming::default()).unwrap(), RasterTiming::default());
    }

    proptest::proptest! {
        #[test]
        fn never_panics_on_mutated_documents(cut in 0usize..12000, byte in 0u8..128) {
            let text = std::fs::read_to_string(project_file()).unwrap();
            let mut b = text.into_bytes();
            if cut < b.len() {
                b[cut] = byte;
            }
            let s = String::from_utf8_lossy(&b);
            if let Ok(l) = Latency::from_json_str(&s, Path::new("x.json")) {
                for n in [0u64, 1, 17, 200, 256, 300] {
                    let _ = l.chunk_cycles(ChunkMode::Sort, n);
                    let _ = l.chunk_interval(ChunkMode::Dps, n);
                    let _ = l.merge_interval(n, n / 2, false);
                    let _ = l.merge_cycles(n, n / 3, true);
                    let _ = l.merge_cycles(n, 0, false);
                }
            }
        }
    }
}
