//! Trajectory generators, spec strings and the cameras.json round trip.

use glam::DVec3;
use neo_golden::camera::Camera;
use neo_golden::source::robust_bounds;
use neo_golden::synthetic::{generate, parse_spec};
use neo_golden::trajectory::{parse_trajectory, scene_unit, Trajectory, DEFAULT_FPS};
use std::path::PathBuf;

/// A scene-like box: 40 x 8 x 30 units, ground at y = 0, objects up to y = -8.
const BOX: ([f32; 3], [f32; 3]) = ([-20.0, -8.0, -15.0], [20.0, 0.0, 15.0]);

fn centre(b: ([f32; 3], [f32; 3])) -> DVec3 {
    (DVec3::from_array(b.0.map(f64::from)) + DVec3::from_array(b.1.map(f64::from))) * 0.5
}

/// Pixel coordinates and depth of world point `p`.
fn project(c: &Camera, p: DVec3) -> (f64, f64, f64) {
    let v = c.cam_to_world.transpose() * (p - c.position);
    let (cx, cy) = ((c.width as f64 - 1.0) / 2.0, (c.height as f64 - 1.0) / 2.0);
    (c.fx * v.x / v.z + cx, c.fy * v.y / v.z + cy, v.z)
}

fn in_image(c: &Camera, p: DVec3) -> bool {
    let (u, v, z) = project(c, p);
    z > 0.0 && u >= -0.5 && v >= -0.5 && u <= c.width as f64 - 0.5 && v <= c.height as f64 - 0.5
}

fn angle_deg(a: DVec3, b: DVec3) -> f64 {
    a.normalize().dot(b.normalize()).clamp(-1.0, 1.0).acos().to_degrees()
}

fn corners(b: ([f32; 3], [f32; 3])) -> Vec<DVec3> {
    (0..8)
        .map(|k| {
            DVec3::new(
                if k & 1 == 0 { b.0[0] } else { b.1[0] } as f64,
                if k & 2 == 0 { b.0[1] } else { b.1[1] } as f64,
                if k & 4 == 0 { b.0[2] } else { b.1[2] } as f64,
            )
        })
        .collect()
}

#[test]
fn orbit_looks_at_the_centre_from_above_with_default_intrinsics() {
    let t = parse_trajectory("orbit", BOX, 60).unwrap();
    assert_eq!((t.len(), t.fps, t.cuts.len()), (60, DEFAULT_FPS, 0));
    let c = centre(BOX);
    for cam in &t.frames {
        assert_eq!((cam.width, cam.height), (1280, 720));
        // 60 degree horizontal field of view, square pixels.
        assert!((cam.tan_half_fov_x() as f64 - 30f64.to_radians().tan()).abs() < 1e-6);
        assert_eq!(cam.fx, cam.fy);
        let (u, v, z) = project(cam, c);
        assert!((u - 639.5).abs() < 1e-6 && (v - 359.5).abs() < 1e-6 && z > 0.0, "{u} {v}");
        // Above the target (y is down) and upright: image "down" has a +y world component.
        assert!(cam.position.y < c.y);
        assert!(cam.cam_to_world.y_axis.y > 0.0);
    }
    // Frame 0 is on the -z side, looking towards +z.
    assert!(t.frames[0].position.z < c.z && t.frames[0].forward().z > 0.0);
}

#[test]
fn default_orbit_keeps_the_whole_box_in_frame() {
    for b in [BOX, ([-1.0, -3.2, -0.6], [0.5, 0.0, 0.6]), ([0.0, 0.0, 0.0], [100.0, 1.0, 1.0])] {
        let t = parse_trajectory("orbit:frames=100,speed=8", b, 0).unwrap();
        for cam in &t.frames {
            for p in corners(b) {
                assert!(in_image(cam, p), "{b:?}: corner {p} leaves the image of {}", cam.name);
            }
        }
        // ... and fills it: some corner is near the border on at least one frame.
        let fill = t
            .frames
            .iter()
            .flat_map(|cam| {
                corners(b).into_iter().map(move |p| {
                    let (u, v, _) = project(cam, p);
                    ((u - 639.5).abs() / 640.0).max((v - 359.5).abs() / 360.0)
                })
            })
            .fold(0.0, f64::max);
        assert!(fill > 0.9, "{b:?}: the box only fills {fill} of the half image");
    }
}

#[test]
fn default_orbit_of_the_outdoor_scene_frames_its_bulk_not_its_sky() {
    let scene = generate(&parse_spec("synthetic:outdoor?gaussians=20k&sh=0").unwrap());
    let b = robust_bounds(&scene);
    let t = parse_trajectory("orbit:frames=30,speed=16", b, 0).unwrap();
    let c = centre(b);
    let r = (t.frames[0].position - c).length();
    // Tens of metres away, not hundreds (the sky shell is 300 m away).
    assert!(r > 20.0 && r < 150.0, "{r}");
    for cam in &t.frames {
        assert!(corners(b).iter().all(|&p| in_image(cam, p)));
        // Most Gaussians of the scene are in view.
        let seen =
            scene.positions.iter().filter(|p| in_image(cam, DVec3::from_array(p.map(f64::from)))).count();
        assert!(seen as f64 > 0.8 * scene.len() as f64, "{seen} of {}", scene.len());
    }
}

#[test]
fn orbit_speed_multiplies_the_angle_per_frame() {
    let step = |speed: &str| {
        let t = parse_trajectory(&format!("orbit:frames=20,{speed}"), BOX, 0).unwrap();
        let c = centre(BOX);
        let a: Vec<f64> =
            t.frames.windows(2).map(|w| angle_deg(w[0].position - c, w[1].position - c)).collect();
        // Uniform motion.
        assert!(a.iter().all(|x| (x - a[0]).abs() < 1e-6), "{a:?}");
        a[0]
    };
    let one = step("speed=1");
    // 12 degrees per second at 30 fps, measured on the tilted circle (slightly less).
    assert!(one > 0.3 && one <= 0.4 + 1e-9, "{one}");
    let four = step("speed=4x");
    assert!((four / one - 4.0).abs() < 1e-3, "{four} vs {one}");
    assert!((step("speed=16") / one - 16.0).abs() < 1e-2);
}

#[test]
fn scene_cut_jumps_and_is_recorded() {
    for kind in ["orbit", "walk", "shake"] {
        let t = parse_trajectory(&format!("{kind}:frames=40,cut=25"), BOX, 0).unwrap();
        assert_eq!(t.cuts, vec![25], "{kind}");
        let moves: Vec<f64> = t.frames.windows(2).map(|w| (w[1].position - w[0].position).length()).collect();
        let turns: Vec<f64> =
            t.frames.windows(2).map(|w| angle_deg(w[0].forward(), w[1].forward())).collect();
        let jump = moves[24];
        let others = moves.iter().enumerate().filter(|&(i, _)| i != 24).map(|(_, &m)| m).fold(0.0, f64::max);
        assert!(
            jump > 20.0 * others.max(1e-9) && jump > 5.0,
            "{kind}: jump {jump}, other steps up to {others}"
        );
        assert!(turns[24] > 60.0, "{kind}: the view turns only {} degrees at the cut", turns[24]);
    }
}

#[test]
fn walk_moves_at_walking_pace_along_its_view() {
    let unit = scene_unit(BOX);
    for (speed, mult) in [("1", 1.0), ("4", 4.0)] {
        let t = parse_trajectory(&format!("walk:frames=90,speed={speed}"), BOX, 0).unwrap();
        for w in t.frames.windows(2) {
            let d = w[1].position - w[0].position;
            let expect = 1.4 * unit * mult / 30.0;
            assert!((d.length() - expect).abs() < 0.02 * expect, "{} vs {expect}", d.length());
            // Looking roughly along the motion: yaw (8) + pitch (5) + a curve, well under 30.
            assert!(angle_deg(DVec3::new(d.x, 0.0, d.z), w[0].forward()) < 30.0);
            // Level, at eye height above the ground (largest y).
            assert!((w[0].position.y - (BOX.1[1] as f64 - 1.6 * unit)).abs() < 1e-9);
            assert!(w[0].cam_to_world.y_axis.y > 0.9);
        }
        // The whole walk stays inside the scene's footprint.
        assert!(t.frames.iter().all(|c| c.position.x.abs() < 20.0 && c.position.z.abs() < 15.0));
    }
}

#[test]
fn shake_is_tiny_band_limited_and_deterministic_per_seed() {
    let a = parse_trajectory("shake:frames=90,seed=7", BOX, 0).unwrap();
    let b = parse_trajectory("shake:frames=90,seed=7", BOX, 0).unwrap();
    let c = parse_trajectory("shake:frames=90,seed=8", BOX, 0).unwrap();
    assert_eq!(a, b);
    assert_ne!(a.frames, c.frames);
    let unit = scene_unit(BOX);
    let rest = a.frames[0].position;
    let mut max_off: f64 = 0.0;
    let mut max_turn: f64 = 0.0;
    for cam in &a.frames {
        max_off = max_off.max((cam.position - rest).length());
        max_turn = max_turn.max(angle_deg(cam.forward(), a.frames[0].forward()));
        // The orientation stays a rotation.
        let r = cam.cam_to_world;
        assert!((r.transpose() * r - glam::DMat3::IDENTITY).to_cols_array().iter().all(|v| v.abs() < 1e-12));
    }
    // About 1 cm and 0.3 degrees RMS per axis: peaks of a few times that, and not zero.
    assert!(max_off > 0.005 * unit && max_off < 0.1 * unit, "{max_off} (unit {unit})");
    assert!(max_turn > 0.1 && max_turn < 2.5, "{max_turn}");
    // Band-limited: frame-to-frame motion is a fraction of the whole excursion.
    let step = a.frames.windows(2).map(|w| (w[1].position - w[0].position).length()).fold(0.0, f64::max);
    assert!(step < 0.5 * max_off, "{step} vs {max_off}");
    // amp=0 is perfectly still.
    let still = parse_trajectory("shake:frames=5,amp=0", BOX, 0).unwrap();
    assert!(still.frames.iter().all(|c| c.position == still.frames[0].position));
}

fn temp(name: &str) -> PathBuf {
    std::env::temp_dir().join(format!("neo_golden_trajectory_{}_{name}", std::process::id()))
}

#[test]
fn trajectories_round_trip_through_cameras_json() {
    for spec in
        ["orbit:frames=50,cut=10/30,speed=3,res=320x200", "walk:frames=20,cut=5", "shake:frames=10,fov=75"]
    {
        let t = parse_trajectory(spec, BOX, 0).unwrap();
        let path = temp("rt.json");
        t.write(&path).unwrap();
        let back = Trajectory::read(&path).unwrap();
        let via_spec = parse_trajectory(&format!("file:{}", path.display()), BOX, 999).unwrap();
        let via_json = parse_trajectory(&path.display().to_string(), BOX, 999).unwrap();
        std::fs::remove_file(&path).ok();
        assert_eq!(back.cuts, t.cuts, "{spec}");
        assert_eq!(back.fps, t.fps);
        assert_eq!(back.len(), t.len());
        for (a, b) in t.frames.iter().zip(&back.frames) {
            assert_eq!((a.width, a.height, &a.name), (b.width, b.height, &b.name));
            assert!((a.fx - b.fx).abs() < 1e-9 && (a.fy - b.fy).abs() < 1e-9);
            assert!((a.position - b.position).abs().max_element() < 1e-9);
            assert!((a.cam_to_world - b.cam_to_world).to_cols_array().iter().all(|v| v.abs() < 1e-9));
        }
        assert_eq!(via_spec, back);
        assert_eq!(via_json, back);
    }
}

#[test]
fn files_without_fps_default_to_30() {
    let t = parse_trajectory("orbit:frames=3", BOX, 0).unwrap();
    let path = temp("nofps.json");
    neo_golden::cameras_json::write_cameras(&path, &t.frames, &[], None).unwrap();
    let back = Trajectory::read(&path).unwrap();
    std::fs::remove_file(&path).ok();
    assert_eq!(back.fps, 30.0);
    assert!(back.cuts.is_empty());
}

#[test]
fn with_resolution_overrides_the_size_keeping_the_view() {
    let t = parse_trajectory("orbit:frames=4", BOX, 0).unwrap().with_resolution(2560, 1440);
    let c = centre(BOX);
    for cam in &t.frames {
        assert_eq!((cam.width, cam.height), (2560, 1440));
        let (u, v, _) = project(cam, c);
        assert!((u - 1279.5).abs() < 1e-6 && (v - 719.5).abs() < 1e-6);
        assert!((cam.tan_half_fov_x() as f64 - 30f64.to_radians().tan()).abs() < 1e-6);
    }
}

proptest::proptest! {
    #[test]
    fn spec_parser_never_panics(spec in "(orbit|walk|shake|spiral)?(:([a-z]{0,7}=[-0-9.x/eE]{0,8},?){0,4})?") {
        if let Err(e) = parse_trajectory(&spec, BOX, 5) {
            proptest::prop_assert!(e.to_string().starts_with(spec.trim()));
        }
    }

    #[test]
    fn spec_parser_never_panics_on_any_bounds(lo in proptest::array::uniform3(-1e6f32..1e6), ext in proptest::array::uniform3(0f32..1e6)) {
        let hi = [lo[0] + ext[0], lo[1] + ext[1], lo[2] + ext[2]];
        for kind in ["orbit", "walk", "shake"] {
            let t = parse_trajectory(kind, (lo, hi), 3).unwrap();
            proptest::prop_assert!(t.frames.iter().all(|c| c.position.is_finite() && c.cam_to_world.is_finite()));
        }
    }
}
