//! The golden crate: scenes, cameras and trajectories, the float reference renderer, and (later)
//! the number formats and the bit-exact model of Neo's pipeline.
//!
//! Everything downstream (generators, test benches, cycle model) consumes these definitions rather
//! than re-deriving them.

pub mod camera;
pub mod cameras_json;
pub mod engine;
pub mod error;
pub mod formats;
pub mod hwarith;
pub mod hwpre;
pub mod image;
pub mod json_shape;
pub mod metrics;
pub mod pipeline;
pub mod ply;
pub mod profile;
pub mod raster;
pub mod render;
pub mod scene;
pub mod scene_stats;
pub mod shared;
pub mod sort;
pub mod source;
pub mod synthetic;
pub mod trajectory;
