//! The work-only driver's table pass (prefetched gathers, binary searches, routed counts) must
//! equal a straightforward recomputation from the golden functions: for every tile and every
//! entry of its table after the write-back, the feature entry by a hash map of the frame's
//! Gaussians preprocessed in the hardware's arithmetic (golden's default), membership in the current list by a linear search, and the subtile
//! routing by the golden `subtile_bitmap`.

use std::collections::HashMap;

use neo_golden::hwpre::{preprocess_hw, Baked};
use neo_golden::pipeline::{Preprocessing, Strategy};
use neo_golden::raster::subtile_bitmap;
use neo_golden::{source, trajectory};
use neo_sim::config::PipelineParams;
use neo_sim::driver::{pipeline_config, GoldenRaster, WorkDriver};

#[test]
fn table_pass_equals_a_straightforward_recomputation() {
    let (scene, _) = source::load_scene("synthetic:outdoor?gaussians=20k&seed=5", false).unwrap();
    let (w, h) = (200, 136);
    let traj = trajectory::parse_trajectory("orbit:speed=8", source::robust_bounds(&scene), 3)
        .unwrap()
        .with_resolution(w, h);
    for strategy in [Strategy::Neo, Strategy::Full] {
        let params = PipelineParams::default();
        let rcfg = pipeline_config(strategy, &params, GoldenRaster::Off).raster;
        let mut drv = WorkDriver::new(&scene, strategy, &params, w, h, false, 16).unwrap();
        let gx = drv.grid()[0];
        let (n, s) = (rcfg.subtiles_per_side(), rcfg.subtile);
        let mut checked = 0u64;
        for (f, cam) in traj.frames.iter().enumerate() {
            let fw = drv.step(cam, f, false);
            let fmt = &drv.formats().feature;
            let key = &drv.formats().key;
            let baked = Baked::from_scene(&scene, fmt, Preprocessing::DEFAULT_SH);
            let feats: HashMap<u32, _> = preprocess_hw(&baked, cam, fmt, key, rcfg.tile)
                .iter()
                .map(|p| (p.projected.index, p.entry))
                .collect();
            let lists: Vec<Vec<u32>> =
                drv.current_lists().map(|l| l.iter().map(|e| e.id).collect()).collect();
            for (ti, (table, tw)) in drv.tables().zip(&fw.tiles).enumerate() {
                let (tx, ty) = (ti as u32 % gx, ti as u32 / gx);
                let mut routed = vec![0u32; (n * n) as usize];
                let mut raster_entries = 0;
                for e in table {
                    let Some(fe) = feats.get(&e.id) else {
                        assert!(!e.valid, "frame {f} tile {ti}: culled Gaussian {} valid", e.id);
                        continue;
                    };
                    raster_entries += 1;
                    let member = lists[ti].contains(&e.id);
                    assert_eq!(e.valid, member, "frame {f} tile {ti}: valid bit of {}", e.id);
                    if strategy.writes_back_keys() {
                        assert_eq!(e.key, fe.depth_key, "frame {f} tile {ti}: key of {}", e.id);
                    }
                    if member {
                        let bits = subtile_bitmap(fe, fmt, tx, ty, &rcfg);
                        for sy in 0..n {
                            for sx in 0..n {
                                let inside = tx * rcfg.tile + sx * s < w && ty * rcfg.tile + sy * s < h;
                                if inside && bits >> (sy * n + sx) & 1 == 1 {
                                    routed[(sy * n + sx) as usize] += 1;
                                }
                            }
                        }
                    }
                }
                assert_eq!(tw.raster_entries, raster_entries, "frame {f} tile {ti}: raster entries");
                assert_eq!(tw.routed, routed, "frame {f} tile {ti}: routed entries per subtile");
                checked += routed.iter().map(|&r| r as u64).sum::<u64>();
            }
        }
        assert!(checked > 10_000, "{strategy:?}: the workload must route real work ({checked})");
    }
}
