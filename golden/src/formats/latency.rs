//! The timing contract: the typed form of `reports/latency.json`.
//!
//! The test bench (`neo_tb::latency`) measures the RTL by cosimulation and writes a
//! [`LatencyReport`]; the cycle model (`neo_sim::latency`) reads it. The file holds raw
//! measurements only: every fit (interpolations, the raster core's load rate and per-segment
//! overhead) is done by the reader, next to the formula it fits.
//!
//! The schema is versioned ([`SCHEMA`]): [`LatencyReport::from_json_str`] refuses a document of
//! another version with an error naming the file and the version, and a malformed one with an
//! error naming the file and the field (`sort_core.merge[1].interval: missing field ...`).
//!
//! # Schema `neo-latency/6`
//! ```text
//! {
//!   "schema": "neo-latency/6",
//!   "doc": { field: explanation, ... },
//!   "config": { every field of the EngineConfig the RTL was generated from },
//!   "memory": { "read_latency": 1, "req_ready": "always", "rsp_gaps": "none" },
//!   "units": {
//!     "neo_bsu": { "latency", "ii", "vectors", "cycles" },
//!     "neo_msu": { "latency", "ii", "merge_gap", "entries", "cycles" },
//!     "neo_sort_core": { "command_overhead" },
//!     "neo_scu": { "latency", "ii", "drain_ii", "gaussians", "lanes" }
//!   },
//!   "sort_core": {
//!     "conventional" | "dps": [ { "entries", "cycles", "interval" }, ... ],
//!     "merge": [ { "entries", "len_a", "len_b", "cycles", "interval" }, ... ],
//!     "merge_delete": [ { ...as merge, "invalid", "out" }, ... ]
//!   },
//!   "raster": {
//!     "itu": { "latency", "ii", "jobs", "subtiles_per_job" },
//!     "core": { "itus", "scus", "feature_buffer", "pixel_writes", "memory",
//!               "grid": [ { "entries", "bits_per_gaussian", "set_bits", "group_max_routed",
//!                           "cycles", "load_cycles" }, ... ] }
//!   },
//!   "preprocess": {
//!     "projection" | "color": { "latency", "ii", "items", "cycles", "settle" },
//!     "duplication": { "latency", "cycles_per_candidate", "min_cycles_per_gaussian",
//!                      "gaussians", "candidates", "cycles" },
//!     "fetch": { "units", "lines_in_flight", "read_latency", "beats", "cycles" }
//!   }
//! }
//! ```
//! Keys are written sorted (the document goes through a `serde_json::Value`), so the file is
//! reproducible bit for bit. `units.neo_scu`, `raster` (and its `itu` and `core`) and
//! `preprocess` (and each of its units) are optional: a reader assumes what is absent.

use std::collections::BTreeMap;
use std::path::Path;

use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

use crate::engine::EngineConfig;
use crate::error::{InputError, InputResult};

/// The schema identifier (and version) this crate writes and reads.
pub const SCHEMA: &str = "neo-latency/6";

/// The whole of `reports/latency.json`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LatencyReport {
    /// Always [`SCHEMA`].
    pub schema: String,
    /// Field path to explanation, for a reader of the JSON.
    pub doc: BTreeMap<String, String>,
    /// The engine configuration of the measured RTL (every field).
    pub config: EngineConfig,
    /// The memory model of the sorting-core measurements.
    pub memory: MemoryModel,
    /// Unit-level latency and throughput.
    pub units: Units,
    /// Sorting-core command cycles.
    pub sort_core: SortCore,
    /// The Rasterization Engine's measurements (absent: assumed by the reader).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub raster: Option<Raster>,
    /// The Preprocessing Engine's measurements (absent, or a unit absent: assumed by the
    /// reader).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub preprocess: Option<Preprocess>,
}

/// The memory model the sorting core was measured with.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct MemoryModel {
    /// Cycles from a read request to its first beat.
    pub read_latency: u64,
    /// When requests are accepted (`always`).
    pub req_ready: String,
    /// Gaps between response beats (`none`).
    pub rsp_gaps: String,
}

/// Unit-level measurements.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Units {
    /// The Bitonic Sorting Unit.
    pub neo_bsu: BsuUnit,
    /// The MSU+ merge unit.
    pub neo_msu: MsuUnit,
    /// The sorting core's fixed command cost.
    pub neo_sort_core: SortCoreUnit,
    /// The Subtile Compute Unit (absent: assumed by the reader).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub neo_scu: Option<ScuUnit>,
}

/// BSU latency and rate.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct BsuUnit {
    /// Edges from accepting a vector to its result on the output.
    pub latency: u64,
    /// Cycles between accepted vectors at full rate.
    pub ii: u64,
    /// Vectors of the measurement.
    pub vectors: u64,
    /// Total cycles of the measurement.
    pub cycles: u64,
}

/// MSU+ latency and rate.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct MsuUnit {
    /// Edges from the first pop to the first output beat.
    pub latency: u64,
    /// Cycles per output entry within a merge.
    pub ii: u64,
    /// Idle output cycles between two back-to-back merges.
    pub merge_gap: u64,
    /// Output entries of the measurement.
    pub entries: u64,
    /// Total cycles of the measurement.
    pub cycles: u64,
}

/// The sorting core's fixed cost.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct SortCoreUnit {
    /// Cycles from accepting a zero-length SORT to its `done_o` pulse.
    pub command_overhead: u64,
}

/// SCU latency and rates.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct ScuUnit {
    /// Edges from accepting a list's last Gaussian to its pixels on the output.
    pub latency: u64,
    /// Cycles per Gaussian while pixels are active.
    pub ii: u64,
    /// Cycles per Gaussian once every pixel is done.
    pub drain_ii: u64,
    /// Gaussians of the measurement.
    pub gaussians: u64,
    /// SCU lanes of the measured RTL.
    pub lanes: u64,
}

/// Sorting-core commands, each measured alone and back to back.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct SortCore {
    /// SORT of one chunk.
    pub conventional: Vec<ChunkPoint>,
    /// DPS of one chunk.
    pub dps: Vec<ChunkPoint>,
    /// MERGE of two sorted streams.
    pub merge: Vec<MergePoint>,
    /// MERGE_DELETE with every fourth entry invalid.
    pub merge_delete: Vec<MergeDeletePoint>,
}

/// One measured chunk command (SORT or DPS).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct ChunkPoint {
    /// Entries in the chunk.
    pub entries: u64,
    /// Cycles of one command alone.
    pub cycles: u64,
    /// Steady-state cycles per command back to back.
    pub interval: u64,
}

/// One measured MERGE command.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct MergePoint {
    /// `len_a + len_b`.
    pub entries: u64,
    /// Entries of stream A.
    pub len_a: u64,
    /// Entries of stream B.
    pub len_b: u64,
    /// Cycles of one command alone.
    pub cycles: u64,
    /// Steady-state cycles per command back to back.
    pub interval: u64,
}

/// One measured MERGE_DELETE command.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct MergeDeletePoint {
    /// The command's streams and cycles.
    #[serde(flatten)]
    pub merge: MergePoint,
    /// Invalid input entries.
    pub invalid: u64,
    /// Entries written.
    pub out: u64,
}

/// The Rasterization Engine's measurements.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Raster {
    /// The Intersection Test Unit.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub itu: Option<ItuUnit>,
    /// The raster core's cycles per tile.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub core: Option<RasterCore>,
}

/// The Preprocessing Engine's units.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Preprocess {
    /// The projection unit (`neo_pre_project`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub projection: Option<DatapathUnit>,
    /// The colour unit (`neo_pre_color`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub color: Option<DatapathUnit>,
    /// The duplication unit (`neo_pre_dup`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub duplication: Option<DupUnit>,
    /// The fetch units (`neo_pre_fetch`): the engine's outstanding-read window.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fetch: Option<FetchUnit>,
}

/// The fetch units' read window, measured on one unit streaming through a long read latency.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FetchUnit {
    /// Fetch units of the engine (`pre_units`, one per lane).
    pub units: u64,
    /// 64-byte lines one unit had in flight at most (its window, as the RTL keeps it).
    pub lines_in_flight: u64,
    /// Cycles from a read request to its first data beat in the measurement.
    pub read_latency: u64,
    /// Data beats the unit received, and the cycles from its start to its last record taken.
    pub beats: u64,
    /// Cycles of the measurement.
    pub cycles: u64,
}

impl FetchUnit {
    /// Lines the engine's fetch units keep in flight together.
    pub fn window_lines(&self) -> u64 {
        self.units * self.lines_in_flight
    }
}

/// A pipelined datapath's latency and rate.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DatapathUnit {
    /// Edges from accepting an item to its result on the outputs.
    pub latency: u64,
    /// Cycles between accepted items at full rate.
    pub ii: u64,
    /// Items of the measurement.
    pub items: u64,
    /// Cycles of the measurement (first item offered to last result taken).
    pub cycles: u64,
    /// Cycles the per-frame inputs need to settle before the first item.
    pub settle: u64,
}

/// The duplication unit's latency and rates.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DupUnit {
    /// Edges from accepting a Gaussian with one candidate tile, which it enters, to that
    /// tile on the output.
    pub latency: u64,
    /// Walker cycles per candidate tile at full rate.
    pub cycles_per_candidate: u64,
    /// Walker cycles of a Gaussian without candidate tiles.
    pub min_cycles_per_gaussian: u64,
    /// Gaussians of the rate measurement.
    pub gaussians: u64,
    /// Their candidate tiles.
    pub candidates: u64,
    /// Cycles from the first acceptance to the last.
    pub cycles: u64,
}

/// ITU latency and rate.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ItuUnit {
    /// Edges from accepting a (Gaussian, tile) job to its bitmap on the output.
    pub latency: u64,
    /// Cycles per job at full rate.
    pub ii: f64,
    /// Random jobs of the measurement.
    pub jobs: u64,
    /// Subtiles tested per job.
    pub subtiles_per_job: u64,
}

/// The raster core's cycles per tile over a grid of table lengths and subtile bits per
/// Gaussian, and the shape of the measured core.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RasterCore {
    /// ITUs of the measured core.
    pub itus: u64,
    /// SCUs of the measured core.
    pub scus: u64,
    /// Feature-buffer entries (one segment) of the measured core.
    pub feature_buffer: u64,
    /// Pixel-row writes per tile of the measured core.
    pub pixel_writes: u64,
    /// The memory model of the measurement.
    pub memory: String,
    /// The measured points.
    pub grid: Vec<GridPoint>,
}

/// One measured raster-core tile.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct GridPoint {
    /// Table entries.
    pub entries: u64,
    /// Subtile bits set per Gaussian, by construction.
    pub bits_per_gaussian: u64,
    /// Set subtile bits of the whole table.
    pub set_bits: u64,
    /// Sum over the subtile groups of the largest per-SCU routed count.
    pub group_max_routed: u64,
    /// Cycles from the command to `done_o`.
    pub cycles: u64,
    /// Cycles from the command to the last read request (the loads).
    pub load_cycles: u64,
}

impl LatencyReport {
    /// The document as written to `reports/latency.json`: pretty JSON, keys sorted, a final
    /// newline.
    pub fn to_text(&self) -> String {
        let v = serde_json::to_value(self).expect("a latency report serialises");
        let mut s = serde_json::to_string_pretty(&v).expect("JSON");
        s.push('\n');
        s
    }

    /// Reads `path`.
    pub fn from_file(path: &Path) -> InputResult<Self> {
        let text = std::fs::read_to_string(path).map_err(|e| InputError::new(path, e.to_string()))?;
        Self::from_json_str(&text, path)
    }

    /// Parses the document `text` (named `path` in errors): refuses a schema other than
    /// [`SCHEMA`], and names the field of any malformed one.
    pub fn from_json_str(text: &str, path: &Path) -> InputResult<Self> {
        let v: serde_json::Value =
            serde_json::from_str(text).map_err(|e| InputError::new(path, format!("not JSON: {e}")))?;
        match v.get("schema") {
            Some(serde_json::Value::String(s)) if s == SCHEMA => {}
            Some(serde_json::Value::String(s)) => {
                return Err(InputError::new(
                    path,
                    format!(
                        "schema '{s}' is not supported (this reader knows '{SCHEMA}'; regenerate the file)"
                    ),
                ))
            }
            Some(other) => {
                return Err(InputError::new(path, format!("`schema` = {other}: expected '{SCHEMA}'")))
            }
            None => return Err(InputError::new(path, format!("missing `schema` (expected '{SCHEMA}')"))),
        }
        typed(v).map_err(|e| InputError::new(path, e))
    }
}

/// `v` as a `T`, or an error naming the field at fault.
fn typed<T: DeserializeOwned>(v: serde_json::Value) -> Result<T, String> {
    serde_path_to_error::deserialize(v).map_err(|e| {
        let at = e.path().to_string();
        let inner = e.into_inner();
        if at == "." {
            inner.to_string()
        } else {
            format!("`{at}`: {inner}")
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn project_text() -> String {
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../reports/latency.json")).unwrap()
    }

    #[test]
    fn the_project_file_round_trips_byte_for_byte() {
        let text = project_text();
        let r = LatencyReport::from_json_str(&text, Path::new("latency.json")).unwrap();
        assert_eq!(r.schema, SCHEMA);
        assert_eq!(r.to_text(), text);
    }

    #[test]
    fn an_unknown_version_is_refused_naming_file_and_version() {
        let text = project_text().replacen(SCHEMA, "neo-latency/1", 1);
        let e = LatencyReport::from_json_str(&text, Path::new("lat.json")).unwrap_err().to_string();
        assert!(e.starts_with("lat.json: ") && e.contains("'neo-latency/1'"), "{e}");
        let e = LatencyReport::from_json_str("{}", Path::new("lat.json")).unwrap_err().to_string();
        assert!(e.contains("missing `schema`"), "{e}");
    }

    #[test]
    fn a_malformed_field_is_named() {
        let mut v: serde_json::Value = serde_json::from_str(&project_text()).unwrap();
        v["sort_core"]["merge"][1]["interval"] = serde_json::json!("x");
        let e = LatencyReport::from_json_str(&v.to_string(), Path::new("lat.json")).unwrap_err().to_string();
        assert!(e.contains("lat.json") && e.contains("sort_core.merge[1].interval"), "{e}");
        let mut v: serde_json::Value = serde_json::from_str(&project_text()).unwrap();
        v["units"]["neo_msu"].as_object_mut().unwrap().remove("ii");
        let e = LatencyReport::from_json_str(&v.to_string(), Path::new("lat.json")).unwrap_err().to_string();
        assert!(e.contains("units.neo_msu") && e.contains("`ii`"), "{e}");
    }
}
