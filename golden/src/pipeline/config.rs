//! Pipeline parameters and the number formats a run uses.

use serde::Serialize;

use super::strategy::Strategy;
use crate::camera::Camera;
use crate::formats::{FeatureFormat, FeatureStats, FormatError};
use crate::hwpre::ShPrecision;
use crate::raster::RasterConfig;
use crate::render::preprocess;
use crate::scene::Scene;
use crate::sort::{DepthKeyCodec, Network, SortConfig, SortFormat, SortParamError};

/// Pipeline parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct PipelineConfig {
    /// Sorting strategy.
    pub strategy: Strategy,
    /// Tile and subtile geometry and SCU widths (64 / 8 by default).
    pub raster: RasterConfig,
    /// DPS and conventional-sort chunk size `C` (256).
    pub chunk: usize,
    /// DPS passes per frame (1; 0 merges the reused table as it is; at most [`MAX_PASSES`]).
    pub dps_passes: usize,
    /// Entries in the raster core's reorder window ([`crate::raster::window`]); 1 (the paper's
    /// engine) reorders nothing. Needs a strategy that writes keys back.
    pub raster_window: usize,
    /// Largest table per tile; `None` is unbounded.
    pub capacity: Option<usize>,
    /// Render the exact-order frame and compare against it (PSNR/SSIM vs exact).
    pub compare_exact: bool,
    /// Render the float reference and compare against it.
    pub compare_float: bool,
    /// Compute SSIM as well as PSNR.
    pub ssim: bool,
    /// With `compare_exact`, measure each frame's `order.window_needed` (one more sort per tile).
    pub window_needed: bool,
    /// Skip the exact-order raster of a tile whose table, restricted to the Gaussians touching
    /// it, is already in the exact order (its pixels are then the same: entries that do not
    /// touch a tile have empty subtile bitmaps and are never blended). Only saves time.
    pub exact_shortcut: bool,
    /// How Gaussians are preprocessed into feature entries.
    pub preprocess: Preprocessing,
}

/// How the pipeline preprocesses Gaussians into feature entries.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum Preprocessing {
    /// The Preprocessing Engine's arithmetic ([`crate::hwpre::preprocess_hw`]) on the scene
    /// baked with SH in the given precision: exactly what the RTL computes. The default, with
    /// [`Preprocessing::DEFAULT_SH`].
    Hardware(ShPrecision),
    /// The float reference's preprocessing, quantised in f64 ([`crate::formats::quantize`],
    /// with `atan2`/`cos`/`sin`/`ln`): the model before the hardware's arithmetic was defined,
    /// kept for the error comparison.
    Float,
}

impl Preprocessing {
    /// The SH precision of the default baked format.
    pub const DEFAULT_SH: ShPrecision = ShPrecision::F32;

    /// Parses `hw` (the default SH precision), `hw:f32`, `hw:f16` or `float`.
    pub fn parse(s: &str) -> Result<Self, String> {
        match s {
            "hw" => Ok(Preprocessing::Hardware(Self::DEFAULT_SH)),
            "hw:f32" => Ok(Preprocessing::Hardware(ShPrecision::F32)),
            "hw:f16" => Ok(Preprocessing::Hardware(ShPrecision::F16)),
            "float" => Ok(Preprocessing::Float),
            _ => Err(format!("unknown preprocessing {s:?}: expected hw, hw:f32, hw:f16 or float")),
        }
    }
}

impl Default for PipelineConfig {
    fn default() -> Self {
        PipelineConfig {
            strategy: Strategy::Neo,
            raster: RasterConfig::default(),
            chunk: SortConfig::DEFAULT_CHUNK,
            dps_passes: 1,
            raster_window: 1,
            capacity: None,
            compare_exact: true,
            compare_float: true,
            ssim: true,
            window_needed: true,
            exact_shortcut: true,
            preprocess: Preprocessing::Hardware(Preprocessing::DEFAULT_SH),
        }
    }
}

/// The most DPS passes per tile and frame the golden pipeline runs: the one limit of `--passes`
/// (`neo frames`, `neo simulate`), of the model configuration's `pipeline.dps_passes` and of
/// `adaptive`'s `max` ([`super::adaptive::AdaptiveParams`]). Each pass costs about as much as
/// the sort of a reused table, and the tables are usually in order after a few. (The engine's
/// tile descriptor holds up to 15, `engine::memory::MAX_DPS_PASSES`.)
pub const MAX_PASSES: usize = 16;

/// Checks a number of DPS passes per frame: 0 (the reused table is merged as it is) to
/// [`MAX_PASSES`].
pub fn check_passes(passes: usize) -> Result<(), String> {
    if passes > MAX_PASSES {
        return Err(format!("{passes} DPS passes per frame is above the limit of {MAX_PASSES}"));
    }
    Ok(())
}

impl PipelineConfig {
    /// The table capacity as a number (`usize::MAX` when unbounded).
    pub fn capacity_or_max(&self) -> usize {
        self.capacity.unwrap_or(usize::MAX)
    }

    /// Checks the reorder window: its size, and that the strategy writes the current keys back
    /// (the window writes the table back in the order it emits, so a table whose keys stay
    /// frozen, `periodic` and `motion`, would no longer be sorted by them).
    pub fn check_window(&self) -> Result<(), PipelineError> {
        crate::raster::window::check_window(self.raster_window).map_err(PipelineError::Other)?;
        if self.raster_window > 1 && !self.strategy.writes_back_keys() {
            return Err(PipelineError::Other(format!(
                "raster window {}: strategy {} keeps its keys frozen, and the window would write its \
                 table back out of their order (use a window of 1)",
                self.raster_window, self.strategy
            )));
        }
        Ok(())
    }

    /// Checks the DPS passes per frame ([`check_passes`]).
    pub fn check_passes(&self) -> Result<(), PipelineError> {
        check_passes(self.dps_passes).map_err(PipelineError::Other)
    }
}

/// Why a configuration cannot run.
///
/// The message holds the cause's own (`sorting parameters: chunk size 0 is ...`), so the cause
/// is not also given as [`std::error::Error::source`]: a report that prints an error with its
/// chain of sources (`anyhow`'s `{:#}`) would repeat it.
#[derive(Debug, thiserror::Error)]
pub enum PipelineError {
    /// A sorting parameter (chunk size, key or id width).
    #[error("sorting parameters: {0}")]
    Sort(SortParamError),
    /// A feature-table or raster parameter.
    #[error("feature/raster format: {0}")]
    Format(FormatError),
    /// Anything else.
    #[error("{0}")]
    Other(String),
}

impl From<SortParamError> for PipelineError {
    fn from(e: SortParamError) -> Self {
        PipelineError::Sort(e)
    }
}

impl From<FormatError> for PipelineError {
    fn from(e: FormatError) -> Self {
        PipelineError::Format(e)
    }
}

/// The number formats of a run: feature table, depth key, sort entry.
#[derive(Clone, Debug, PartialEq)]
pub struct Formats {
    /// Feature-table widths.
    pub feature: FeatureFormat,
    /// Depth-key codec (its width equals `feature.depth_key_bits`).
    pub key: DepthKeyCodec,
    /// Sorting Core parameters (entry format, chunk size, 16-input bitonic BSU).
    pub sort: SortConfig,
}

impl Formats {
    /// The artifact's formats: default feature widths, FP16 depth key, 6-byte sort entries.
    pub fn artifact(chunk: usize) -> Result<Self, PipelineError> {
        let feature = FeatureFormat::default();
        let key = DepthKeyCodec::Fp16;
        let sort = SortConfig::new(
            SortFormat::new(key.key_bits(), SortFormat::ARTIFACT.id_bits())?,
            chunk,
            Network::bitonic(16),
        )?;
        Ok(Formats { feature, key, sort })
    }

    /// Formats fitted to a run: feature ranges ([`FeatureFormat::fitted`]) and a log depth key
    /// of the default width ([`DepthKeyCodec::fit`]) over every frame's preprocessed Gaussians,
    /// and an id field as narrow as the Gaussian count allows ([`SortFormat::fitted`]).
    /// Preprocesses every camera once (in parallel per frame).
    pub fn fitted(scene: &Scene, cams: &[Camera], tile: u32, chunk: usize) -> Result<Self, PipelineError> {
        let base = FeatureFormat::default();
        let mut stats = FeatureStats::default();
        let (mut lo, mut hi) = (f32::INFINITY, 0.0f32);
        for cam in cams {
            let p = preprocess(scene, cam, tile);
            stats = stats.merge(&FeatureStats::from_projected(&p));
            for q in &p {
                if q.depth.is_finite() && q.depth > 0.0 {
                    lo = lo.min(q.depth);
                    hi = hi.max(q.depth);
                }
            }
        }
        let feature = FeatureFormat::fitted(&stats, &base);
        let key = DepthKeyCodec::fit(
            [lo, hi].into_iter().filter(|z| z.is_finite() && *z > 0.0),
            base.depth_key_bits,
        )?;
        let format = SortFormat::fitted(scene.len() as u64, key.key_bits())?;
        let sort = SortConfig::new(format, chunk, Network::bitonic(16))?;
        Ok(Formats { feature, key, sort })
    }

    /// Checks the formats against each other, the raster configuration and the scene size.
    pub fn check(&self, raster: &RasterConfig, gaussians: usize) -> Result<(), PipelineError> {
        raster.check(&self.feature)?;
        if self.key.key_bits() != self.feature.depth_key_bits
            || self.key.key_bits() != self.sort.format().key_bits()
        {
            return Err(PipelineError::Other(format!(
                "depth key widths differ: codec {}, feature table {}, sort entry {}",
                self.key.key_bits(),
                self.feature.depth_key_bits,
                self.sort.format().key_bits()
            )));
        }
        if gaussians as u64 > self.sort.format().id_capacity() {
            return Err(SortParamError::TooManyGaussians(gaussians as u64).into());
        }
        Ok(())
    }
}

/// The configuration block of `stats.json`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ConfigRecord {
    /// Scene spec or path.
    pub scene: String,
    /// Trajectory spec.
    pub trajectory: String,
    /// Gaussians in the scene.
    pub gaussians: usize,
    /// Strategy, as parsed (`neo`, `periodic:4`, ...).
    pub strategy: String,
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Frames rendered.
    pub frames: usize,
    /// Scene cuts of the trajectory.
    pub cuts: Vec<usize>,
    /// Tile side.
    pub tile: u32,
    /// Subtile side.
    pub subtile: u32,
    /// Chunk size.
    pub chunk: usize,
    /// DPS passes per frame.
    pub dps_passes: usize,
    /// Entries in the raster core's reorder window (1: none).
    pub raster_window: usize,
    /// Table capacity (`null`: unbounded).
    pub capacity: Option<usize>,
    /// Whether the formats were fitted to the run.
    pub fitted: bool,
    /// Depth-key codec, e.g. `Fp16` or `Log(KeyRange { .. })`.
    pub key_codec: String,
    /// Sort entry `[key_bits, id_bits]`.
    pub sort_entry_bits: [u8; 2],
    /// Bytes per sort entry in DRAM.
    pub sort_entry_bytes: usize,
    /// Feature-table widths.
    pub feature_format: FeatureFormat,
    /// Bytes per feature entry in DRAM.
    pub feature_entry_bytes: u32,
    /// Comparisons enabled.
    pub compare_exact: bool,
    /// Comparisons enabled.
    pub compare_float: bool,
    /// SSIM enabled.
    pub ssim: bool,
    /// Rayon threads.
    pub threads: usize,
    /// Preprocessing (`Hardware(F32)`: the RTL's arithmetic, SH as f32; `Float`).
    pub preprocess: Preprocessing,
}

/// What a run is besides its configuration and formats (for [`ConfigRecord::new`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RunInfo<'a> {
    /// Scene spec or path.
    pub scene: &'a str,
    /// Trajectory spec.
    pub trajectory: &'a str,
    /// Gaussians in the scene.
    pub gaussians: usize,
    /// Frames rendered.
    pub frames: usize,
    /// Scene cuts.
    pub cuts: &'a [usize],
    /// Image size.
    pub size: (u32, u32),
    /// Whether the formats were fitted to the run.
    pub fitted: bool,
}

impl ConfigRecord {
    /// The record of a run.
    pub fn new(run: &RunInfo, cfg: &PipelineConfig, f: &Formats) -> Self {
        let RunInfo { scene, trajectory, gaussians, frames, cuts, size, fitted } = *run;
        ConfigRecord {
            scene: scene.to_string(),
            trajectory: trajectory.to_string(),
            gaussians,
            strategy: cfg.strategy.to_string(),
            width: size.0,
            height: size.1,
            frames,
            cuts: cuts.to_vec(),
            tile: cfg.raster.tile,
            subtile: cfg.raster.subtile,
            chunk: cfg.chunk,
            dps_passes: cfg.dps_passes,
            raster_window: cfg.raster_window,
            capacity: cfg.capacity,
            fitted,
            key_codec: format!("{:?}", f.key),
            sort_entry_bits: [f.sort.format().key_bits(), f.sort.format().id_bits()],
            sort_entry_bytes: f.sort.format().bytes_per_entry(),
            feature_format: f.feature,
            feature_entry_bytes: f.feature.bytes_per_entry(),
            compare_exact: cfg.compare_exact,
            compare_float: cfg.compare_float,
            ssim: cfg.ssim,
            threads: rayon::current_num_threads(),
            preprocess: cfg.preprocess,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The full report of an error: its message and those of its sources, as `anyhow`'s `{:#}`
    /// prints them.
    fn report(e: &dyn std::error::Error) -> String {
        let mut text = e.to_string();
        let mut source = e.source();
        while let Some(s) = source {
            text += &format!(": {s}");
            source = s.source();
        }
        text
    }

    /// A pipeline error says its cause once, also where the chain of sources is printed.
    #[test]
    fn pipeline_errors_say_their_cause_once() {
        let sort = PipelineError::from(SortParamError::Chunk { chunk: 0, bsu: 16 });
        assert_eq!(
            report(&sort),
            "sorting parameters: chunk size 0 is not the BSU width 16 times a power of two"
        );
        let format =
            PipelineError::from(FormatError::new("tile", "tile 0 is not a positive multiple of subtile 8"));
        assert_eq!(
            report(&format),
            "feature/raster format: tile: tile 0 is not a positive multiple of subtile 8"
        );
    }

    /// DPS passes run from 0 to [`MAX_PASSES`], the limit of adaptive's `max` as well.
    #[test]
    fn passes_are_bounded_by_the_one_limit() {
        assert!(check_passes(0).is_ok() && check_passes(MAX_PASSES).is_ok());
        let e = check_passes(usize::MAX).unwrap_err();
        assert!(e.contains(&usize::MAX.to_string()) && e.contains("above the limit of 16"), "{e}");
        let cfg = PipelineConfig { dps_passes: MAX_PASSES + 1, ..PipelineConfig::default() };
        assert!(cfg.check_passes().is_err());
        assert!(super::super::adaptive::AdaptiveParams::parse(&format!("max={MAX_PASSES}")).is_ok());
        assert!(super::super::adaptive::AdaptiveParams::parse(&format!("max={}", MAX_PASSES + 1)).is_err());
    }
}
