//! The strategy-independent stages of a frame: preprocessing into the feature table and the
//! binning with the ITU ([`FrameInputs`], made by a [`FramePrep`]).
//!
//! They depend on the scene, the camera, the image size, the feature and depth-key formats and
//! the raster's tile geometry, never on the strategy, the chunk, the DPS passes or the capacity.
//! So pipelines of different strategies along the same cameras (a sweep, the strategy
//! timelines) and the work-only state beside a golden pipeline can share one [`FrameInputs`] per
//! frame ([`super::Pipeline::work_frame_with`], [`super::Pipeline::render_frame_with`]) instead
//! of each preprocessing and binning the frame again; the results are the same as with
//! [`super::Pipeline::render_frame`], which makes its own.
//!
//! The inputs also keep, per tile, the exact-order raster once a pipeline has made it
//! ([`FrameInputs::exact_pixels`]): the exact table depends only on the current list and the
//! capacity, so pipelines of the same capacity sharing the inputs raster it once.

use std::sync::{Arc, OnceLock};
use std::time::Instant;

use rayon::prelude::*;

use super::{gpu_duplication, gpu_duplication_of, CULLED, GPU_TILE};
use crate::camera::Camera;
use crate::formats::{quantize, FeatureEntry, FeatureFormat};
use crate::hwpre::{preprocess_hw, Baked};
use crate::pipeline::binning::Binning;
use crate::pipeline::config::{Formats, Preprocessing};
use crate::raster::RasterConfig;
use crate::render::{preprocess, Projected};
use crate::scene::Scene;

/// The exact-order pixels of one tile, for the capacity they were made with.
#[derive(Clone, Debug)]
pub struct ExactPixels {
    /// Capacity of the exact table (`usize::MAX`: unbounded).
    pub capacity: usize,
    /// `tile * tile` pixels.
    pub pixels: Vec<[u8; 3]>,
}

/// One frame's feature table and binning (see the module docs).
#[derive(Debug, Default)]
pub struct FrameInputs {
    /// Image size.
    pub(super) size: (u32, u32),
    /// Raster geometry the binning used.
    pub(super) raster: Option<RasterConfig>,
    /// Feature format of the table.
    pub(super) feature: Option<FeatureFormat>,
    /// The feature table (visible Gaussians in ascending id order).
    pub(super) features: Vec<FeatureEntry>,
    /// The Gaussian of each feature entry.
    pub(super) feature_ids: Vec<u32>,
    /// Per Gaussian, its feature entry or [`CULLED`].
    pub(super) feature_of: Vec<u32>,
    /// Every tile's current list and the entries' subtile bitmaps.
    pub(super) binning: Binning,
    /// The CUDA rasterizer's duplication over [`GPU_TILE`] tiles: (pairs, Gaussians).
    pub(super) gpu: (u64, u64),
    /// Seconds of the preprocessing and the quantisation (the hardware's: all in the first).
    pub(super) feature_s: (f64, f64),
    /// Seconds of the binning.
    pub(super) binning_s: f64,
    /// Per tile, the exact-order raster once made.
    pub(super) exact: Vec<OnceLock<ExactPixels>>,
}

impl FrameInputs {
    /// Visible Gaussians (feature entries).
    pub fn visible(&self) -> usize {
        self.features.len()
    }
}

/// Makes [`FrameInputs`] for one scene at one image size (the scene baked once for the
/// hardware preprocessing).
pub struct FramePrep<'s> {
    scene: &'s Scene,
    baked: Option<Arc<Baked>>,
    formats: Formats,
    raster: RasterConfig,
    width: u32,
    height: u32,
}

impl<'s> FramePrep<'s> {
    /// A preparer of `scene` at `width x height` with `formats`, the raster geometry `raster` and
    /// the preprocessing `pre` (the scene is baked here for the hardware's).
    pub fn new(
        scene: &'s Scene,
        formats: &Formats,
        raster: RasterConfig,
        pre: Preprocessing,
        width: u32,
        height: u32,
    ) -> Self {
        let baked = match pre {
            Preprocessing::Hardware(sh) => Some(Arc::new(Baked::from_scene(scene, &formats.feature, sh))),
            Preprocessing::Float => None,
        };
        FramePrep { scene, baked, formats: formats.clone(), raster, width, height }
    }

    /// The baked scene (`None` with [`Preprocessing::Float`]).
    pub fn baked(&self) -> Option<&Baked> {
        self.baked.as_deref()
    }

    /// The image size.
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// The inputs of the frame seen from `cam` (of the preparer's size).
    ///
    /// # Panics
    /// When the camera's size differs from the preparer's.
    pub fn prepare(&self, cam: &Camera) -> FrameInputs {
        let mut inp = FrameInputs::default();
        self.prepare_into(cam, &mut inp);
        inp
    }

    /// [`FramePrep::prepare`] into `inp`, reusing its buffers.
    pub fn prepare_into(&self, cam: &Camera, inp: &mut FrameInputs) {
        assert_eq!(
            (cam.width, cam.height),
            (self.width, self.height),
            "camera size differs from the pipeline's"
        );
        inp.size = (self.width, self.height);
        inp.raster = Some(self.raster);
        inp.feature = Some(self.formats.feature);
        inp.feature_s = self.feature_phase(cam, inp);
        let t = Instant::now();
        let fmt = &self.formats.feature;
        inp.binning.run(&inp.features, &inp.feature_ids, fmt, &self.raster, self.width, self.height);
        inp.binning_s = t.elapsed().as_secs_f64();
        inp.exact.clear();
        inp.exact.resize_with(inp.binning.tiles(), OnceLock::new);
    }

    /// Preprocessing into the feature table, and the GPU duplication of the projected
    /// Gaussians: the hardware's arithmetic on the baked scene, or the float preprocess and its
    /// quantisation. Returns the seconds of the two (the hardware's are one: all in the first).
    fn feature_phase(&self, cam: &Camera, inp: &mut FrameInputs) -> (f64, f64) {
        let t = Instant::now();
        let (fmt, key, tile) = (&self.formats.feature, &self.formats.key, self.raster.tile);
        let (w, h) = (self.width, self.height);
        let gpu = |p: &[Projected]| gpu_duplication(p, w, h, GPU_TILE);
        let (preprocess_s, t) = match &self.baked {
            Some(baked) => {
                let hw = preprocess_hw(baked, cam, fmt, key, tile);
                let preprocess_s = t.elapsed().as_secs_f64();
                inp.gpu = gpu_duplication_of(&hw, |x| &x.projected, w, h, GPU_TILE);
                let t = Instant::now();
                inp.features.clear();
                inp.features.extend(hw.iter().map(|h| h.entry));
                inp.feature_ids.clear();
                inp.feature_ids.extend(hw.iter().map(|h| h.projected.index));
                (preprocess_s, t)
            }
            None => {
                let projected = preprocess(self.scene, cam, tile);
                let preprocess_s = t.elapsed().as_secs_f64();
                inp.gpu = gpu(&projected);
                let t = Instant::now();
                projected.par_iter().map(|p| quantize(p, fmt, key)).collect_into_vec(&mut inp.features);
                inp.feature_ids.clear();
                inp.feature_ids.extend(projected.iter().map(|p| p.index));
                (preprocess_s, t)
            }
        };
        inp.feature_of.clear();
        inp.feature_of.resize(self.scene.len(), CULLED);
        for (i, &id) in inp.feature_ids.iter().enumerate() {
            inp.feature_of[id as usize] = i as u32;
        }
        (preprocess_s, t.elapsed().as_secs_f64())
    }
}
