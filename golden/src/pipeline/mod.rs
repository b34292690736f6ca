//! The bit-exact per-frame golden pipeline of Neo, with its baselines and statistics.
//!
//! Per frame ([`Pipeline::render_frame`]):
//! 1. float preprocessing ([`crate::render::preprocess`], tiles of the raster's size);
//! 2. quantisation, once, into the feature table ([`crate::formats::quantize`]) with the run's
//!    depth-key codec (FP16 by default, or fitted to the trajectory, see [`Formats`]);
//! 3. binning into tiles with the ITU ([`binning`]): a Gaussian belongs to a tile when
//!    [`crate::raster::touches_tile`];
//! 4. per-tile sorting by the [`Strategy`] ([`tile`]): Neo's reuse-and-update (DPS of the reused
//!    table, conventional sort of the incoming list, MSU+ merge dropping invalid entries), or a
//!    baseline (`full`, `periodic:K`, `background:K`, `hierarchical`), all with work counters
//!    ([`work`]);
//! 5. fixed-point raster per tile ([`crate::raster::raster_tile`]) into the 8-bit frame, and the
//!    write-back of the current depth keys and the ITU valid bits into the tables, which are the
//!    next frame's reused tables (the one-frame-stale depth of the paper's deferred update);
//! 6. references and statistics ([`stats`]): the exact-order frame of the same pipeline, the
//!    float reference render, PSNR/SSIM against both, order displacement and inversions against
//!    the exact order ([`order`]), retention, work and timing.
//!
//! The work-only mode ([`Pipeline::work_frame`]) runs steps 1-4, then the write-back without
//! the raster (the valid bit is membership in the current list, which is what the ITU gives),
//! and returns the per-tile work counters ([`FrameWork`]) instead of pixels: the cycle model's
//! input.
//!
//! [`run_trajectory`] runs a trajectory; [`StatsFile`] is the `stats.json` document;
//! [`trace`] exports a frame as the artifact simulator's `poc.trace`.

pub mod adaptive;
pub mod binning;
pub mod config;
pub mod frame;
pub mod hierarchical;
pub mod order;
mod prefetch;
pub mod run;
pub mod stats;
pub mod strategy;
pub mod tile;
pub mod trace;
pub mod work;

pub use config::{
    check_passes, ConfigRecord, Formats, PipelineConfig, PipelineError, Preprocessing, RunInfo, MAX_PASSES,
};
pub use frame::{FrameOutput, FrameWork, Pipeline, SampledRaster, TileWork, WorkOptions};
pub use run::{bench_frames, formats_for, run_trajectory, StatsFile};
pub use stats::{FrameStats, Summary, TileColumns, Timing};
pub use strategy::{split_list as split_strategies, Strategy};
pub use work::StageWork;
