//! Shared helpers of the fixed-point rasterizer tests: a straightforward whole-frame renderer
//! on top of `quantize`, `candidate_tiles`, `touches_tile` and `raster_tile` (tables built by
//! an exact sort by (depth key, id)), the exact f64 ellipse-rectangle test, and scene loading.
#![allow(dead_code)]

use neo_golden::camera::Camera;
use neo_golden::formats::{quantize, FeatureEntry, FeatureFormat};
use neo_golden::image::Rgb8Image;
use neo_golden::raster::{candidate_tiles, raster_tile, touches_tile, RasterConfig};
use neo_golden::render::Projected;
use neo_golden::scene::Scene;
use neo_golden::shared::shared_file_for_test;
use neo_golden::sort::DepthKeyCodec;
use rayon::prelude::*;

/// Totals of one fixed-point frame.
#[derive(Clone, Copy, Debug, Default)]
pub struct FrameTotals {
    /// Tile-Gaussian pairs (table entries over all tiles).
    pub pairs: u64,
    /// Subtile-Gaussian pairs (set bitmap bits).
    pub routed: u64,
    /// Pixel-Gaussian evaluations.
    pub pixel_evals: u64,
    /// Subtiles that terminated early.
    pub terminated: u64,
}

/// Renders a frame with the fixed-point pipeline: quantise every Gaussian, bin it into the tiles
/// it touches, sort each tile's table by (depth key, scene index), rasterise every tile.
pub fn render_fixed(
    projected: &[Projected],
    fmt: &FeatureFormat,
    key: &DepthKeyCodec,
    cfg: &RasterConfig,
    width: u32,
    height: u32,
) -> (Rgb8Image, FrameTotals) {
    cfg.check(fmt).unwrap();
    let entries: Vec<FeatureEntry> = projected.par_iter().map(|p| quantize(p, fmt, key)).collect();
    let gx = width.div_ceil(cfg.tile);
    let gy = height.div_ceil(cfg.tile);
    // (tile, key, id, index) sorted: tables in exact (key, id) order.
    let mut pairs: Vec<(u32, u32, u32, u32)> = entries
        .par_iter()
        .enumerate()
        .flat_map_iter(|(i, e)| {
            let (xr, yr) = candidate_tiles(e, fmt, cfg, width, height);
            let mut v = Vec::new();
            for ty in yr {
                for tx in xr.clone() {
                    if touches_tile(e, fmt, tx, ty, cfg) {
                        v.push((ty * gx + tx, e.depth_key, projected[i].index, i as u32));
                    }
                }
            }
            v
        })
        .collect();
    pairs.par_sort_unstable();
    let mut offsets = vec![0usize; (gx * gy) as usize + 1];
    for p in &pairs {
        offsets[p.0 as usize + 1] += 1;
    }
    for t in 0..(gx * gy) as usize {
        offsets[t + 1] += offsets[t];
    }
    let tiles: Vec<_> = (0..gx * gy)
        .into_par_iter()
        .map_init(Vec::new, |table: &mut Vec<FeatureEntry>, t| {
            let s = &pairs[offsets[t as usize]..offsets[t as usize + 1]];
            table.clear();
            table.extend(s.iter().map(|p| entries[p.3 as usize]));
            raster_tile(table, fmt, t % gx, t / gx, width, height, cfg)
        })
        .collect();
    let mut img = Rgb8Image::new(width, height);
    let mut tot = FrameTotals { pairs: pairs.len() as u64, ..FrameTotals::default() };
    let ts = cfg.tile as usize;
    for (t, r) in tiles.iter().enumerate() {
        let (x0, y0) = ((t as u32 % gx) as usize * ts, (t as u32 / gx) as usize * ts);
        for ly in 0..ts {
            let y = y0 + ly;
            if y >= height as usize {
                break;
            }
            for lx in 0..ts {
                let x = x0 + lx;
                if x >= width as usize {
                    break;
                }
                let o = 3 * (y * width as usize + x);
                img.data[o..o + 3].copy_from_slice(&r.pixels[ly * ts + lx]);
            }
        }
        for w in &r.work {
            tot.routed += w.routed as u64;
            tot.pixel_evals += w.pixel_evals as u64;
            tot.terminated += w.terminated as u64;
        }
    }
    (img, tot)
}

/// Whether the ellipse `{d : d^T cov^-1 d <= k2}` around `mean` meets the closed rectangle
/// `[x0, x1] x [y0, y1]`, in f64: the minimum of the quadratic form over the rectangle (inside:
/// zero; else on one of the four edges, where it is a 1D quadratic) compared with `k2`.
pub fn ellipse_meets_rect(mean: [f64; 2], cov: [f64; 3], k2: f64, rect: [f64; 4]) -> bool {
    let [x0, y0, x1, y1] = rect;
    if mean[0] >= x0 && mean[0] <= x1 && mean[1] >= y0 && mean[1] <= y1 {
        return true;
    }
    let det = cov[0] * cov[2] - cov[1] * cov[1];
    let (a, b, c) = (cov[2] / det, -cov[1] / det, cov[0] / det);
    let q = |x: f64, y: f64| {
        let (dx, dy) = (x - mean[0], y - mean[1]);
        a * dx * dx + 2.0 * b * dx * dy + c * dy * dy
    };
    // Minimum over x in [x0, x1] at fixed y: the vertex of a dx^2 + 2 b dx dy, clamped.
    let on_h = |y: f64| {
        let dy = y - mean[1];
        let x = (mean[0] - b * dy / a).clamp(x0, x1);
        q(x, y)
    };
    let on_v = |x: f64| {
        let dx = x - mean[0];
        let y = (mean[1] - b * dx / c).clamp(y0, y1);
        q(x, y)
    };
    let m = on_h(y0).min(on_h(y1)).min(on_v(x0)).min(on_v(x1));
    m <= k2
}

/// The biker scene and its four cameras, or `None` (skip) when ../shared is missing.
pub fn biker(test: &str) -> Option<(Scene, Vec<Camera>)> {
    let ply = shared_file_for_test(test, "scenes/biker.ply")?;
    let cams = shared_file_for_test(test, "scenes/biker_cameras.json")?;
    let raw = neo_golden::ply::read_raw(&ply).unwrap();
    let (scene, _) = Scene::from_raw(&raw, &ply, false).unwrap();
    let cams = neo_golden::cameras_json::read_cameras(&cams).unwrap().into_iter().map(|e| e.camera).collect();
    Some((scene, cams))
}

/// A synthetic outdoor scene of `n` Gaussians and a camera of its default orbit at `w x h`.
pub fn outdoor(n: usize, seed: u64, w: u32, h: u32, spec: &str) -> (Scene, Camera) {
    let s = neo_golden::synthetic::parse_spec(&format!("synthetic:outdoor?gaussians={n}&seed={seed}&sh=1"))
        .unwrap();
    let scene = neo_golden::synthetic::generate(&s);
    let t = neo_golden::trajectory::spec::parse_trajectory(&format!("{spec}:res={w}x{h}"), scene.bounds(), 1)
        .unwrap();
    let cam = t.frames[0].clone();
    (scene, cam)
}
