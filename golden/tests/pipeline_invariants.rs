//! Invariants of the golden pipeline, property-tested on random small scenes and trajectories:
//! tables hold exactly the Gaussians that touch their tile, exact strategies are exact, a frame
//! that needs no more than the raster's reorder window is exact, a still camera keeps Neo exact
//! (with or without a window), and Neo's order converges once the camera stops.

mod pipeline_common;

use neo_golden::pipeline::{PipelineConfig, Strategy};
use neo_golden::{source, trajectory};
use pipeline_common::{check_tables, config, run_frames};
use proptest::prelude::*;

fn strategy_of(i: u8) -> Strategy {
    match i % 5 {
        0 => Strategy::Neo,
        1 => Strategy::Full,
        2 => Strategy::Periodic(3),
        3 => Strategy::Background(2),
        _ => Strategy::Hierarchical,
    }
}

fn traj_spec(kind: u8, speed: f64) -> String {
    match kind % 3 {
        0 => format!("orbit:res=160x96,speed={speed}"),
        1 => format!("shake:res=160x96,amp={}", 20.0 * speed),
        _ => format!("walk:res=160x96,speed={speed}"),
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 12, ..ProptestConfig::default() })]

    /// After every frame's write-back, each tile's valid entries are exactly the Gaussians that
    /// touch it, every touching Gaussian is in its table, ids are unique, and exact strategies
    /// are in the exact order; with a reorder window (strategies that write keys back), every
    /// frame that needs no more than the window is the exact-order frame.
    #[test]
    fn tables_hold_exactly_the_touching_gaussians(
        n in 200usize..1500,
        seed in 1u64..1000,
        kind in 0u8..3,
        speed in 0.5f64..16.0,
        strat in 0u8..5,
        geometry in 0u8..3,
        chunk_log in 0u32..3,
        window_log in 0u32..9,
    ) {
        let (scene, _) = source::load_scene(&format!("synthetic:blobs?gaussians={n}&seed={seed}"), false).unwrap();
        let traj = trajectory::parse_trajectory(&traj_spec(kind, speed), source::robust_bounds(&scene), 5).unwrap();
        let strategy = strategy_of(strat);
        let window = if strategy.writes_back_keys() { 1 << window_log } else { 1 };
        let mut cfg = PipelineConfig { chunk: 32 << chunk_log, raster_window: window, compare_float: false, ..config(strategy) };
        (cfg.raster.tile, cfg.raster.subtile) = [(64, 8), (32, 8), (16, 4)][geometry as usize];
        let stats = run_frames(&scene, &traj.frames, &[], cfg, check_tables);
        for f in &stats {
            prop_assert_eq!(f.tiles.pairs, f.tiles.incoming + f.tiles.retained);
            prop_assert!(serde_json::to_string(f).is_ok());
            prop_assert!(f.order.window_needed >= 1, "frame {}: not measured", f.frame);
            if f.order.window_needed as usize <= window {
                prop_assert_eq!(f.identical_to_exact, Some(true), "frame {} needs {} <= {}", f.frame, f.order.window_needed, window);
            }
        }
    }

    /// With the camera still, Neo's frames are the exact-order frames from the first one on
    /// (one DPS pass of an already sorted table changes nothing, and nothing enters or leaves).
    #[test]
    fn still_camera_keeps_neo_exact(
        n in 200usize..1500,
        seed in 1u64..1000,
        frame in 0usize..20,
        chunk_log in 0u32..3,
        window_log in 0u32..9,
    ) {
        let (scene, _) = source::load_scene(&format!("synthetic:blobs?gaussians={n}&seed={seed}"), false).unwrap();
        let traj = trajectory::parse_trajectory("orbit:res=160x96", source::robust_bounds(&scene), frame + 1).unwrap();
        let cams = vec![traj.frames[frame].clone(); 4];
        let cfg = PipelineConfig {
            chunk: 32 << chunk_log,
            raster_window: 1 << window_log,
            compare_float: false,
            ..config(Strategy::Neo)
        };
        let stats = run_frames(&scene, &cams, &[], cfg, check_tables);
        for f in &stats {
            prop_assert_eq!(f.order.inversions, 0, "frame {}", f.frame);
            prop_assert_eq!(f.order.window_needed, 1, "frame {}", f.frame);
            prop_assert_eq!(f.identical_to_exact, Some(true));
            prop_assert_eq!(f.tiles.incoming, if f.frame == 0 { f.tiles.pairs } else { 0 });
        }
    }

}

proptest! {
    #![proptest_config(ProptestConfig { cases: 6, ..ProptestConfig::default() })]

    /// After the camera stops, Neo's order is exact within `ceil(L / (C/2)) + 2` frames (`L`
    /// the longest table): one frame for the written-back keys to be current, then DPS's
    /// alternating passes (a block odd-even transposition sort).
    #[test]
    fn order_converges_after_the_camera_stops(
        n in 300usize..800,
        seed in 1u64..1000,
        speed in 1.0f64..16.0,
        moving in 2usize..6,
        chunk_log in 0u32..2,
    ) {
        let (scene, _) = source::load_scene(&format!("synthetic:blobs?gaussians={n}&seed={seed}"), false).unwrap();
        let traj = trajectory::parse_trajectory(&format!("orbit:res=160x96,speed={speed}"), source::robust_bounds(&scene), moving).unwrap();
        let chunk = 32usize << chunk_log;
        let mut cams = traj.frames.clone();
        let longest = n;
        let bound = longest.div_ceil(chunk / 2) + 2;
        cams.extend(std::iter::repeat_n(traj.frames[moving - 1].clone(), bound + 1));
        let cfg = PipelineConfig { chunk, compare_float: false, ..config(Strategy::Neo) };
        let stats = run_frames(&scene, &cams, &[], cfg, check_tables);
        let table_max = stats.iter().map(|f| f.tiles.table_len_max as usize).max().unwrap();
        let bound = table_max.div_ceil(chunk / 2) + 2;
        let stop = moving - 1;
        let exact_at = stats.iter().skip(stop).position(|f| f.order.inversions == 0);
        prop_assert!(exact_at.is_some_and(|k| k <= bound), "exact after {:?} still frames, bound {}", exact_at, bound);
        // Once exact with a still camera, it stays exact.
        let k = stop + exact_at.unwrap();
        prop_assert!(stats[k..].iter().all(|f| f.order.inversions == 0 && f.identical_to_exact == Some(true)));
    }
}
