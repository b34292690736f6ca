//! The `adaptive` and `motion` strategies on hard camera motion (issue 14).
//!
//! On a small synthetic scene with a small chunk (tables span many chunks): a fast orbit, a
//! 180-degree turn in one frame, a scene cut, a camera that stops after moving at 16x, shake
//! and walk. Each case asserts `adaptive`'s sorting traffic against single-pass Neo on the same
//! frames and a PSNR floor per frame: Neo's PSNR on that frame less a small tolerance (on this
//! scene of large splats the one-frame-stale keys alone keep 16x below 45 dB: even the exact
//! order of the previous frame's keys, `background:1`, is; see docs/adaptive.md). The absolute
//! 45 dB floor is asserted on the real scene (biker, from `../shared/`).

mod pipeline_common;

use neo_golden::camera::Camera;
use neo_golden::pipeline::adaptive::AdaptiveParams;
use neo_golden::pipeline::{FrameStats, PipelineConfig, Strategy, WorkOptions};
use neo_golden::{source, trajectory};
use pipeline_common::{
    check_tables, config, dram, fast_motion_scene, min_psnr, pooled_psnr, psnr, run_frames,
};

/// Chunk of these tests: tables of a few hundred entries span many chunks.
const CHUNK: usize = 32;
/// The PSNR floor `adaptive` must hold in every frame on the real scene.
const FLOOR_DB: f64 = 45.0;
/// How far below Neo's PSNR `adaptive` may fall in the synthetic cases: sorting more
/// thoroughly by one-frame-stale keys is not always closer to the current order (measured: a
/// walk frame at 16x 4 dB below Neo's, with the worst frame and the pooled PSNR far above).
const TOLERANCE_DB: f64 = 0.5;
/// Most sorting traffic `adaptive` may spend, relative to single-pass Neo on the same frames.
const TRAFFIC_RATIO: f64 = 1.5;

fn traj(s: &neo_golden::scene::Scene, spec: &str, frames: usize) -> trajectory::Trajectory {
    trajectory::parse_trajectory(spec, source::robust_bounds(s), frames).unwrap()
}

fn adaptive() -> Strategy {
    Strategy::Adaptive(AdaptiveParams::default())
}

fn cfg(strategy: Strategy) -> PipelineConfig {
    PipelineConfig { chunk: CHUNK, compare_float: false, ..config(strategy) }
}

fn run(s: &neo_golden::scene::Scene, cams: &[Camera], cuts: &[usize], strategy: Strategy) -> Vec<FrameStats> {
    run_frames(s, cams, cuts, cfg(strategy), check_tables)
}

/// Runs neo and adaptive on `cams`; asserts adaptive's floor (its worst frame no worse than
/// Neo's worst, less the tolerance; its pooled PSNR no worse than Neo's) and the traffic ratio;
/// returns both.
fn check_case(name: &str, cams: &[Camera], cuts: &[usize]) -> (Vec<FrameStats>, Vec<FrameStats>) {
    let s = fast_motion_scene();
    let neo = run(&s, cams, cuts, Strategy::Neo);
    let ada = run(&s, cams, cuts, adaptive());
    let (an, nn) = (min_psnr(&ada), min_psnr(&neo));
    assert!(an >= nn - TOLERANCE_DB, "{name}: adaptive's worst frame {an:.2} dB < neo's {nn:.2} dB");
    let (ap, np) = (pooled_psnr(&ada), pooled_psnr(&neo));
    assert!(ap >= np - TOLERANCE_DB, "{name}: adaptive's pooled PSNR {ap:.2} dB < neo's {np:.2} dB");
    let ratio = dram(&ada) as f64 / dram(&neo) as f64;
    assert!(ratio <= TRAFFIC_RATIO, "{name}: adaptive sorting traffic {ratio:.3} x neo's");
    (neo, ada)
}

#[test]
fn fast_orbit_on_biker_holds_45_db_where_neo_does_not() {
    let Some(path) = neo_golden::shared::shared_file_for_test("pipeline_adaptive", "scenes/biker.ply") else {
        return;
    };
    let (s, _) = source::load_scene(path.to_str().unwrap(), false).unwrap();
    let t = traj(&s, "orbit:res=320x240,speed=16", 12);
    let c = |st: Strategy| PipelineConfig { compare_float: false, ..config(st) };
    let neo = run_frames(&s, &t.frames, &[], c(Strategy::Neo), check_tables);
    let ada = run_frames(&s, &t.frames, &[], c(adaptive()), check_tables);
    // The premise: single-pass Neo falls below the floor on this motion.
    assert!(min_psnr(&neo) < FLOOR_DB, "neo holds {:.2} dB: the case is too easy", min_psnr(&neo));
    for f in &ada {
        assert!(psnr(f) >= FLOOR_DB, "biker 16x: frame {} at {:.2} dB < {FLOOR_DB}", f.frame, psnr(f));
    }
    let ratio = dram(&ada) as f64 / dram(&neo) as f64;
    assert!(ratio <= TRAFFIC_RATIO, "biker 16x: adaptive sorting traffic {ratio:.3} x neo's");
}

#[test]
fn fast_orbit_never_does_worse_than_neo() {
    let s = fast_motion_scene();
    let t = traj(&s, "orbit:res=256x192,speed=16", 12);
    let (neo, ada) = check_case("orbit 16x", &t.frames, &t.cuts);
    assert!(min_psnr(&ada) >= min_psnr(&neo), "{:.2} < {:.2}", min_psnr(&ada), min_psnr(&neo));
    // The policy acted: wider chunks or more passes than Neo somewhere.
    assert!(ada
        .iter()
        .zip(&neo)
        .any(|(a, n)| a.work.dps_chunks != n.work.dps_chunks || a.tiles_multi_pass > 0));
}

#[test]
fn a_180_degree_turn_in_one_frame() {
    let s = fast_motion_scene();
    let t = traj(&s, "orbit:res=256x192", 8);
    // Frames 4.. look the opposite way from the same positions.
    let cams: Vec<Camera> = t
        .frames
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let mut c = c.clone();
            if i >= 4 {
                c.cam_to_world = glam::DMat3::from_cols(
                    -c.cam_to_world.x_axis,
                    c.cam_to_world.y_axis,
                    -c.cam_to_world.z_axis,
                );
            }
            c
        })
        .collect();
    let (_, ada) = check_case("turn", &cams, &[]);
    assert!(ada[4].camera.rotation_deg > 179.0, "the premise: a half turn ({})", ada[4].camera.rotation_deg);
}

#[test]
fn a_scene_cut_restarts_from_scratch() {
    let s = fast_motion_scene();
    let t = traj(&s, "orbit:res=256x192,speed=16,cut=5", 9);
    let (_, ada) = check_case("cut", &t.frames, &t.cuts);
    assert!(ada[5].cut && ada[5].from_scratch);
    assert_eq!(ada[5].identical_to_exact, Some(true));
}

#[test]
fn stopping_after_16x_falls_back_to_neo_cost() {
    let s = fast_motion_scene();
    let t = traj(&s, "orbit:res=256x192,speed=16", 6);
    let mut cams = t.frames.clone();
    cams.extend(std::iter::repeat_n(t.frames[5].clone(), 6));
    let (neo, ada) = check_case("stop", &cams, &[]);
    // While moving, the policy acts (wide chunks or more passes than Neo somewhere).
    let acts =
        |a: &FrameStats, n: &FrameStats| a.work.dps_chunks != n.work.dps_chunks || a.tiles_multi_pass > 0;
    assert!(ada[1..6].iter().zip(&neo[1..6]).any(|(a, n)| acts(a, n)));
    // From the first still frame (6, whose pose equals frame 5's) every frame is sorted as Neo
    // sorts it (one pass of the normal chunk per tile) and costs what Neo's does (within 2%).
    for f in 6..cams.len() {
        let (a, n) = (dram(&ada[f..=f]), dram(&neo[f..=f]));
        assert!(a as f64 <= 1.02 * n as f64, "frame {f}: adaptive {a} entries, neo {n}");
        assert!(!acts(&ada[f], &neo[f]), "frame {f}: still adapting after the stop");
    }
}

#[test]
fn shake_and_walk_hold_the_floor() {
    let s = fast_motion_scene();
    for spec in ["shake:res=256x192,amp=8", "walk:res=256x192,speed=16"] {
        let t = traj(&s, spec, 10);
        check_case(spec, &t.frames, &t.cuts);
    }
}

#[test]
fn slow_orbit_costs_what_neo_costs() {
    // With the default chunk (256): at 1x the reach stays below a chunk.
    let s = fast_motion_scene();
    let t = traj(&s, "orbit:res=256x192", 10);
    let c = |st: Strategy| PipelineConfig { compare_float: false, ..config(st) };
    let neo = run_frames(&s, &t.frames, &[], c(Strategy::Neo), check_tables);
    let ada = run_frames(&s, &t.frames, &[], c(adaptive()), check_tables);
    let ratio = dram(&ada) as f64 / dram(&neo) as f64;
    assert!(ratio <= 1.02, "adaptive at 1x: {ratio:.4} x neo's sorting traffic");
    assert!(min_psnr(&ada) >= min_psnr(&neo) - 0.5);
}

#[test]
fn motion_threshold_resorts_when_the_view_turned() {
    let s = fast_motion_scene();
    let t = traj(&s, "orbit:res=256x192,speed=16", 8);
    // 12 degrees/s x 16 / 30 fps = 6.4 degrees per frame: motion:10 re-sorts every second frame.
    let st = run(&s, &t.frames, &[], Strategy::Motion(10_000));
    let full: Vec<bool> = st.iter().map(|f| f.from_scratch).collect();
    for (f, w) in full.windows(2).enumerate() {
        assert!(w[0] || w[1], "frames {f} and {}: no full sort in two frames of 6.4 degrees", f + 1);
    }
    assert!(full.iter().filter(|&&b| !b).count() >= 2, "{full:?}");
    for f in st.iter().filter(|f| f.from_scratch) {
        assert_eq!(f.identical_to_exact, Some(true));
    }
}

#[test]
fn work_only_mode_sorts_the_same_tables() {
    let s = fast_motion_scene();
    let t = traj(&s, "orbit:res=256x192,speed=16", 5);
    let formats = neo_golden::pipeline::Formats::artifact(CHUNK).unwrap();
    let c = cfg(adaptive());
    let mut a = neo_golden::pipeline::Pipeline::new(&s, c.clone(), formats.clone(), 256, 192).unwrap();
    let mut b = neo_golden::pipeline::Pipeline::new(&s, c, formats, 256, 192).unwrap();
    let opts = WorkOptions { hierarchical: false, raster_sample: 0 };
    for (i, cam) in t.frames.iter().enumerate() {
        a.render_frame(cam, i, false);
        let w = b.work_frame(cam, i, false, &opts);
        assert!(a.tables().eq(b.tables()), "frame {i}: the work-only tables differ");
        let passes: u64 = w.tiles.iter().map(|t| t.sort.work.dps_passes).sum();
        assert!(i == 0 || passes > 0);
    }
}
