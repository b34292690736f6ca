//! The duplication unit's incoming detection (golden `hwpre::duplicate`) equals the pipeline's
//! incoming lists: on random synthetic scenes and camera paths, for every tile of every frame
//! after the first, the Gaussians the unit sends to the tile are exactly its current list `S`,
//! and the ones it flags incoming are exactly `S \ V` (`V`: the valid ids of the tile's previous,
//! written-back table), from nothing but the previous frame's feature entries.

mod pipeline_common;

use neo_golden::formats::FeatureEntry;
use neo_golden::hwpre::duplicate::{incoming, TouchRecord};
use neo_golden::pipeline::Strategy;
use neo_golden::{source, trajectory};
use pipeline_common::{config, run_frames};
use std::collections::BTreeSet;

/// The previous frame as the unit sees it (feature entries by id) and as the pipeline keeps it
/// (each tile's valid ids).
type Previous = (Vec<Option<FeatureEntry>>, Vec<BTreeSet<u32>>);

fn check_scene(n: usize, seed: u64, path: &str) {
    let (scene, _) =
        source::load_scene(&format!("synthetic:blobs?gaussians={n}&seed={seed}"), false).unwrap();
    let traj = trajectory::parse_trajectory(path, source::robust_bounds(&scene), 6).unwrap();
    let mut prev: Option<Previous> = None;
    let (mut checked_tiles, mut retained, mut fresh_total) = (0, 0, 0);
    run_frames(&scene, &traj.frames, &[], config(Strategy::Neo), |p, o| {
        assert_eq!(o.stats.dropped_capacity, 0, "the test needs tables without capacity drops");
        let fmt = &p.formats().feature;
        let cfg = &p.config().raster;
        let grid = p.grid();
        let features: Vec<Option<FeatureEntry>> =
            (0..scene.len() as u32).map(|i| p.feature(i).copied()).collect();
        if let Some((prev_features, v)) = &prev {
            let tiles = grid[0] as usize * grid[1] as usize;
            let (mut entered, mut fresh) = (vec![BTreeSet::new(); tiles], vec![BTreeSet::new(); tiles]);
            for (id, now) in features.iter().enumerate() {
                let Some(now) = now else { continue };
                let record = TouchRecord { entry: prev_features[id].as_ref() };
                for h in incoming(now, record, fmt, cfg, p.size(), |_, _| false) {
                    let t = (h.tile_y * grid[0] + h.tile_x) as usize;
                    entered[t].insert(id as u32);
                    if h.incoming {
                        fresh[t].insert(id as u32);
                    }
                }
            }
            for (t, s) in p.current_lists().enumerate() {
                let s: BTreeSet<u32> = s.iter().map(|e| e.id).collect();
                assert_eq!(
                    entered[t], s,
                    "frame {}: tile {t}: the tiles entered differ from S",
                    o.stats.frame
                );
                let want: BTreeSet<u32> = s.difference(&v[t]).copied().collect();
                assert_eq!(fresh[t], want, "frame {}: tile {t}: incoming differs from S \\ V", o.stats.frame);
                checked_tiles += (!s.is_empty()) as usize;
                fresh_total += want.len();
                retained += s.len() - want.len();
            }
        }
        let v: Vec<BTreeSet<u32>> =
            p.tables().map(|t| t.iter().filter(|e| e.valid).map(|e| e.id).collect()).collect();
        prev = Some((features, v));
    });
    assert!(
        checked_tiles > 0 && retained > 0 && fresh_total > 0,
        "{checked_tiles} tiles, {retained} retained, {fresh_total} incoming: the case tests nothing"
    );
}

#[test]
fn incoming_detection_equals_the_pipelines_incoming_lists() {
    for (n, seed, path) in [
        (800, 3, "orbit:res=160x96,speed=4"),
        (1500, 11, "walk:res=160x96,speed=8"),
        (600, 29, "shake:res=160x96,amp=40"),
    ] {
        check_scene(n, seed, path);
    }
}
