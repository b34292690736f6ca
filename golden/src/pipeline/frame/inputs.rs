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
//! The inputs also keep, per tile, the rasters the pipelines sharing them have made
//! ([`TileRasters`]): a raster depends only on the feature entries it blends, in their order, the
//! tile and the geometry, which sharing pipelines have in common. So a table another pipeline
//! has already rastered this frame (the same order of the same entries: a sweep's strategies
//! often agree on a tile, and every exact-order reference of one capacity is the same) is not
//! rastered again.

use std::sync::{Arc, Mutex};
use std::time::Instant;

use rayon::prelude::*;

use super::{gpu_count, gpu_duplication, GpuGrid, CULLED, GPU_TILE};
use crate::camera::Camera;
use crate::formats::{quantize, FeatureEntry, FeatureFormat};
use crate::hwpre::{preprocess_hw_par, Baked};
use crate::pipeline::binning::Binning;
use crate::pipeline::config::{Formats, Preprocessing};
use crate::profile::{self, Phase};
use crate::raster::{RasterConfig, TileRaster};
use crate::render::{preprocess, Projected};
use crate::scene::Scene;

/// Rasters kept per tile at most (a sweep's pipelines of one camera speed make a few distinct
/// ones per tile; the cap bounds the memory of many pipelines that all differ).
const KEPT_PER_TILE: usize = 16;

/// The rasters of one tile made by the pipelines sharing a frame's inputs, each with the
/// feature entries it blended.
#[derive(Debug, Default)]
pub(super) struct TileRasters(Mutex<Vec<Arc<KeptRaster>>>);

/// A kept raster and the feature entries it blended: their indices into the feature table, in
/// blend order.
#[derive(Debug)]
pub(super) struct KeptRaster {
    pub(super) entries: Vec<u32>,
    pub(super) raster: TileRaster,
}

impl TileRasters {
    /// The raster of `entries` (indices into the feature table, in blend order), if kept.
    pub(super) fn find(&self, entries: &[u32]) -> Option<Arc<KeptRaster>> {
        self.0.lock().expect("tile rasters").iter().find(|k| k.entries == entries).cloned()
    }

    /// Keeps `raster`, made of `entries`, for the other pipelines (up to [`KEPT_PER_TILE`]).
    pub(super) fn keep(&self, entries: &[u32], raster: &TileRaster) {
        let mut kept = self.0.lock().expect("tile rasters");
        if kept.len() < KEPT_PER_TILE && !kept.iter().any(|k| k.entries == entries) {
            kept.push(Arc::new(KeptRaster { entries: entries.to_vec(), raster: raster.clone() }));
        }
    }
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
    /// Per Gaussian, its feature entry, id and GPU pairs, or `None` when culled (the hardware
    /// preprocessing's buffer, kept from frame to frame).
    outcomes: Vec<Option<(FeatureEntry, u32, u64)>>,
    /// Seconds of the preprocessing and the quantisation (the hardware's: all in the first).
    pub(super) feature_s: (f64, f64),
    /// Seconds of the binning.
    pub(super) binning_s: f64,
    /// Per tile, the rasters made by the pipelines sharing these inputs.
    pub(super) rasters: Vec<TileRasters>,
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
        let _phase = profile::enter(Phase::Binning);
        let t = Instant::now();
        let fmt = &self.formats.feature;
        inp.binning.run(&inp.features, &inp.feature_ids, fmt, &self.raster, self.width, self.height);
        inp.binning_s = t.elapsed().as_secs_f64();
        inp.rasters.clear();
        inp.rasters.resize_with(inp.binning.tiles(), TileRasters::default);
    }

    /// Preprocessing into the feature table, and the GPU duplication of the projected
    /// Gaussians: the hardware's arithmetic on the baked scene, or the float preprocess and its
    /// quantisation. Returns the seconds of the two (the hardware's are one: all in the first).
    fn feature_phase(&self, cam: &Camera, inp: &mut FrameInputs) -> (f64, f64) {
        let _phase = profile::enter(Phase::Preprocess);
        let t = Instant::now();
        let (fmt, key, tile) = (&self.formats.feature, &self.formats.key, self.raster.tile);
        let (w, h) = (self.width, self.height);
        let gpu = |p: &[Projected]| gpu_duplication(p, w, h, GPU_TILE);
        let (preprocess_s, t) = match &self.baked {
            Some(baked) => {
                // Each Gaussian's outcome in place (a buffer kept from frame to frame), then the
                // survivors in order: no survivor list is gathered and no buffer is allocated.
                let grid = GpuGrid::new(w, h, GPU_TILE);
                preprocess_hw_par(baked, cam, fmt, key, tile)
                    .map(|s| s.map(|s| (s.entry, s.projected.index, grid.pairs(&s.projected))))
                    .collect_into_vec(&mut inp.outcomes);
                inp.features.clear();
                inp.feature_ids.clear();
                inp.gpu = (0, 0);
                for &(entry, id, pairs) in inp.outcomes.iter().flatten() {
                    inp.features.push(entry);
                    inp.feature_ids.push(id);
                    inp.gpu = gpu_count(inp.gpu, pairs);
                }
                (t.elapsed().as_secs_f64(), Instant::now())
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

#[cfg(test)]
mod tests {
    use super::*;

    fn raster(mark: u8) -> TileRaster {
        TileRaster { pixels: vec![[mark; 3]; 4], valid: vec![true], bitmaps: vec![1], work: Vec::new() }
    }

    #[test]
    fn a_kept_raster_is_found_by_exactly_its_entries_in_their_order() {
        let kept = TileRasters::default();
        assert!(kept.find(&[1, 2, 3]).is_none());
        kept.keep(&[1, 2, 3], &raster(7));
        kept.keep(&[3, 2, 1], &raster(9));
        assert_eq!(kept.find(&[1, 2, 3]).expect("kept").raster, raster(7));
        assert_eq!(kept.find(&[3, 2, 1]).expect("kept").raster, raster(9));
        // Another order, a prefix, or more entries are other tables.
        for other in [&[2, 1, 3][..], &[1, 2], &[1, 2, 3, 4], &[]] {
            assert!(kept.find(other).is_none(), "{other:?}");
        }
        // The same entries again keep the first raster.
        kept.keep(&[1, 2, 3], &raster(8));
        assert_eq!(kept.find(&[1, 2, 3]).expect("kept").raster, raster(7));
    }

    #[test]
    fn a_tile_keeps_at_most_its_cap_of_rasters() {
        let kept = TileRasters::default();
        for k in 0..KEPT_PER_TILE as u32 + 4 {
            kept.keep(&[k], &raster(k as u8));
        }
        let last_kept = KEPT_PER_TILE as u32 - 1;
        assert_eq!(kept.find(&[last_kept]).expect("within the cap").raster, raster(last_kept as u8));
        assert!(kept.find(&[last_kept + 1]).is_none(), "beyond the cap");
    }
}
