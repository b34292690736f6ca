//! Hardware number formats: how the float preprocessing is quantised, once, into the feature
//! table, and the widths of the Subtile Compute Unit's datapath.
//!
//! Every width is a parameter; the defaults and the image error each width costs are in
//! docs/formats.md ("Feature table and rasterization"). The Verilog generator reads widths,
//! constants, the packed layout and the exp table from here.
//!
//! - [`fixed`]: [`QFormat`] (Q-format description) and the rounding rules;
//! - [`conic`]: the block floating-point conic;
//! - [`feature`]: [`FeatureFormat`], [`FeatureEntry`], [`quantize`], packing;
//! - [`stats`]: [`FeatureStats`] and [`FeatureFormat::fitted`];
//! - [`blend`]: [`BlendFormat`], the SCU's power / exp / alpha / transmittance widths;
//! - [`latency`]: [`LatencyReport`], the timing contract `reports/latency.json` between the
//!   test bench (which measures the RTL) and the cycle model (which fits and uses it).

pub mod blend;
pub mod conic;
pub mod feature;
pub mod fixed;
pub mod latency;
pub mod stats;

pub use blend::{BlendFormat, ExpFormat};
pub use conic::{ConicFormat, QuantConic};
pub use feature::{quantize, Cutoff, FeatureEntry, FeatureFormat, FieldLayout};
pub use fixed::{FormatError, QFormat};
pub use latency::LatencyReport;
pub use stats::FeatureStats;
