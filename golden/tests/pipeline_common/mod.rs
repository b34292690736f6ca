//! Helpers shared by the pipeline tests: hand-made scenes and cameras, and a frame loop.
#![allow(dead_code)]

use glam::{DMat3, DVec3};
use neo_golden::camera::Camera;
use neo_golden::pipeline::{Formats, FrameOutput, FrameStats, Pipeline, PipelineConfig, Strategy};
use neo_golden::scene::Scene;
use neo_golden::sort::SortEntry;
use neo_golden::synthetic::SH_C0;
use std::collections::HashSet;

/// One hand-made Gaussian.
#[derive(Clone, Copy, Debug)]
pub struct G {
    pub pos: [f32; 3],
    pub scale: [f32; 3],
    pub rot: [f32; 4],
    pub opacity: f32,
    pub rgb: [f32; 3],
}

impl G {
    /// An isotropic Gaussian.
    pub fn round(pos: [f32; 3], sigma: f32, opacity: f32, rgb: [f32; 3]) -> G {
        G { pos, scale: [sigma; 3], rot: [1.0, 0.0, 0.0, 0.0], opacity, rgb }
    }
}

/// The small synthetic scene of the fast-motion tests (`pipeline_adaptive`, `pipeline_window`):
/// 20 000 large splats, so tables of a few thousand entries span many chunks of 32.
pub fn fast_motion_scene() -> Scene {
    neo_golden::source::load_scene("synthetic:outdoor?gaussians=20000&seed=3", false).unwrap().0
}

/// A degree-0 scene of the given Gaussians.
pub fn scene_of(gs: &[G]) -> Scene {
    Scene {
        positions: gs.iter().map(|g| g.pos).collect(),
        scales: gs.iter().map(|g| g.scale).collect(),
        rotations: gs.iter().map(|g| g.rot).collect(),
        opacities: gs.iter().map(|g| g.opacity).collect(),
        sh_degree: 0,
        sh: gs.iter().flat_map(|g| g.rgb.map(|c| ((c as f64 - 0.5) / SH_C0) as f32)).collect(),
    }
}

/// A camera at `position` with the world axes as its axes (x right, y down, z forward) and
/// focal `f`: a point `(x, y, z)` in front projects to `(f x / z + (W-1)/2, f y / z + (H-1)/2)`.
pub fn axis_camera(width: u32, height: u32, f: f64, position: [f64; 3]) -> Camera {
    Camera {
        name: "axis".into(),
        width,
        height,
        fx: f,
        fy: f,
        position: DVec3::from_array(position),
        cam_to_world: DMat3::IDENTITY,
    }
}

/// A camera at `position` looking at `target` (world up -y).
pub fn look_at(width: u32, height: u32, f: f64, position: [f64; 3], target: [f64; 3]) -> Camera {
    Camera {
        name: "look".into(),
        width,
        height,
        fx: f,
        fy: f,
        position: DVec3::from_array(position),
        cam_to_world: neo_golden::camera::look_at_rotation(
            DVec3::from_array(position),
            DVec3::from_array(target),
            DVec3::new(0.0, -1.0, 0.0),
        ),
    }
}

/// A configuration with the given strategy, comparisons on, SSIM off (speed).
pub fn config(strategy: Strategy) -> PipelineConfig {
    PipelineConfig { strategy, ssim: false, ..PipelineConfig::default() }
}

/// Runs `cams` in order (`cuts` marks scene cuts) and calls `check` after each frame.
pub fn run_frames(
    scene: &Scene,
    cams: &[Camera],
    cuts: &[usize],
    cfg: PipelineConfig,
    mut check: impl FnMut(&Pipeline, &FrameOutput),
) -> Vec<FrameStats> {
    let formats = Formats::artifact(cfg.chunk).expect("artifact formats");
    let mut p = Pipeline::new(scene, cfg, formats, cams[0].width, cams[0].height).expect("pipeline");
    let mut out = Vec::new();
    for (i, c) in cams.iter().enumerate() {
        let o = p.render_frame(c, i, cuts.contains(&i));
        check(&p, &o);
        out.push(o.stats);
    }
    out
}

/// The structural invariants after a frame's write-back, for every tile:
/// - ids are unique in the table;
/// - every Gaussian touching the tile now is in its table (capacity aside: checked only when
///   nothing was dropped);
/// - the valid entries are exactly the Gaussians touching the tile now;
/// - exact strategies: the table is the exact table.
pub fn check_tables(p: &Pipeline, o: &FrameOutput) {
    assert_eq!(o.stats.raster.itu_mismatch, 0, "binning and raster disagree (frame {})", o.stats.frame);
    let exact_strategy = p.config().strategy.is_exact();
    let no_drops = o.stats.dropped_capacity == 0;
    for (t, ((table, current), exact)) in p.tables().zip(p.current_lists()).zip(p.exact_tables()).enumerate()
    {
        let ids: HashSet<u32> = table.iter().map(|e| e.id).collect();
        assert_eq!(ids.len(), table.len(), "duplicate id in tile {t}");
        let cur: HashSet<u32> = current.iter().map(|e| e.id).collect();
        let valid: HashSet<u32> = table.iter().filter(|e| e.valid).map(|e| e.id).collect();
        if no_drops {
            assert!(cur.is_subset(&ids), "tile {t} misses a touching Gaussian (frame {})", o.stats.frame);
            assert_eq!(valid, cur, "tile {t}: valid entries != touching set (frame {})", o.stats.frame);
        } else {
            assert!(
                valid.is_subset(&cur),
                "tile {t}: a valid entry does not touch (frame {})",
                o.stats.frame
            );
        }
        if exact_strategy {
            let a: Vec<u32> = table.iter().map(|e| e.id).collect();
            let b: Vec<u32> = exact.iter().map(|e| e.id).collect();
            assert_eq!(a, b, "tile {t} is not in the exact order");
        }
    }
    if exact_strategy {
        assert_eq!(o.stats.order.inversions, 0);
        assert_eq!(o.stats.identical_to_exact, Some(true));
    }
}

/// Sorting DRAM traffic (bytes read and written) of a run.
pub fn dram(fs: &[FrameStats]) -> u64 {
    fs.iter().map(|f| f.work.dram_read + f.work.dram_written).sum()
}

/// PSNR vs exact of a frame; identical frames count as infinite.
pub fn psnr(f: &FrameStats) -> f64 {
    f.psnr_vs_exact.unwrap_or(f64::INFINITY)
}

/// The worst frame's PSNR vs exact.
pub fn min_psnr(fs: &[FrameStats]) -> f64 {
    fs.iter().map(psnr).fold(f64::INFINITY, f64::min)
}

/// PSNR of the mean squared error over all frames (from each frame's PSNR).
pub fn pooled_psnr(fs: &[FrameStats]) -> f64 {
    let mse: f64 = fs.iter().map(|f| 10f64.powf(-psnr(f) / 10.0)).sum::<f64>() / fs.len() as f64;
    -10.0 * mse.log10()
}

/// True when `t` is in THE ORDER.
pub fn is_sorted(t: &[SortEntry]) -> bool {
    t.windows(2).all(|w| w[0].order_key() < w[1].order_key())
}
