//! Bit-exact model of Neo's sorting engine (paper Sections 4.2-4.3 and 5.3).
//!
//! This is the single source of truth for the sorting hardware: the RTL generator reads the
//! comparator networks ([`network`]) and the entry layout ([`entry`]), the test benches call
//! these functions as the reference, and the cycle model reads the work counters.
//!
//! Everything here is integer code mirroring what the hardware does:
//! - [`entry`]: the `{valid, key, id}` entry, its bit layout and THE ORDER (key, then id);
//! - [`depth_key`]: depth (view-space z) to sort-key encodings;
//! - [`network`]: comparator networks as data (the 16-input Bitonic Sort Unit, BSU);
//! - [`msu`]: the two-way Merge Sort Unit+ (MSU+) `merge2`, with optional invalid dropping;
//! - [`command`]: the core's command modes and the conventional sort's command plan;
//! - [`full_sort`](mod@full_sort): the conventional sort (BSU vectors, in-chunk merges, global merges);
//! - [`dps`](mod@dps): Dynamic Partial Sorting of a reused table with interleaved chunk boundaries;
//! - [`update`]: the per-tile, per-frame reuse-and-update step (DPS, insert, delete, capacity).

pub mod command;
pub mod depth_key;
pub mod dps;
pub mod entry;
pub mod error;
pub mod full_sort;
pub mod msu;
pub mod network;
pub mod update;

pub use command::{conventional_sort_plan, PlannedCommand, SortBuffer, SortMode};
pub use depth_key::DepthKeyCodec;
pub use dps::{dps, dps_pass, DpsWork, Parity};
pub use entry::{SortEntry, SortFormat};
pub use error::SortParamError;
pub use full_sort::{full_sort, merge_pass_count, ChunkWork, PassWork, SortConfig, SortWork, Sorter};
pub use msu::{merge2, merge2_into, MergeStats, MergeStep, MergeStream};
pub use network::Network;
pub use update::{full_frame_sort, update_tile, TileSorter, TileUpdate, UpdateConfig, UpdateWork};
