//! cameras.json reading, writing, camera selection, and the reader's robustness.

use glam::{DMat3, DVec3};
use neo_golden::camera::{look_at_rotation, Camera};
use neo_golden::cameras_json::{parse_camera_spec, parse_cameras, read_cameras, write_cameras};
use neo_golden::shared::shared_file_for_test;
use proptest::prelude::*;
use std::path::{Path, PathBuf};

fn temp(name: &str) -> PathBuf {
    std::env::temp_dir().join(format!("neo_golden_camera_{}_{name}", std::process::id()))
}

/// Pixel coordinates of world point `p` (pinhole, principal point at the image centre).
fn project(c: &Camera, p: DVec3) -> (f64, f64, f64) {
    let v = c.cam_to_world.transpose() * (p - c.position);
    let (cx, cy) = ((c.width as f64 - 1.0) / 2.0, (c.height as f64 - 1.0) / 2.0);
    (c.fx * v.x / v.z + cx, c.fy * v.y / v.z + cy, v.z)
}

#[test]
fn biker_cameras_have_the_documented_poses() {
    let Some(path) =
        shared_file_for_test("biker_cameras_have_the_documented_poses", "scenes/biker_cameras.json")
    else {
        return;
    };
    let e = read_cameras(&path).unwrap();
    assert_eq!(e.len(), 4);
    let names: Vec<&str> = e.iter().map(|e| e.camera.name.as_str()).collect();
    assert_eq!(names, ["front", "left", "three_quarter", "close"]);
    let front = &e[0].camera;
    assert_eq!((front.width, front.height, front.fx, front.fy), (320, 240, 300.0, 300.0));
    assert_eq!(front.position, DVec3::new(0.0, -1.6, -5.0));
    // The front camera looks towards +z (nearly exactly), with image y pointing down (+y world).
    assert!(front.forward().z > 0.9999 && front.forward().x.abs() < 0.011, "{:?}", front.forward());
    assert!(front.cam_to_world.y_axis.y > 0.9999);
    // The left camera, at x = -5, looks towards +x.
    assert!(e[1].camera.forward().x > 0.9999);
    // Every camera sees the subject (on the -y axis, y from 0 to about -3) in its image.
    for entry in &e {
        let c = &entry.camera;
        let (u, v, z) = project(c, DVec3::new(0.0, -1.5, 0.0));
        assert!(z > 0.0 && (0.0..320.0).contains(&u) && (0.0..240.0).contains(&v), "{}: {u} {v} {z}", c.name);
    }
}

fn some_cameras() -> Vec<Camera> {
    (0..5)
        .map(|i| {
            let a = i as f64 * 0.7 + 0.123_456_789;
            let pos = DVec3::new(3.0 * a.sin(), -1.0 - 0.1 * i as f64, -3.0 * a.cos());
            Camera {
                name: format!("cam {i}"),
                width: 640,
                height: 360,
                fx: 555.5,
                fy: 555.25,
                position: pos + DVec3::splat(1e-13 * i as f64),
                cam_to_world: look_at_rotation(pos, DVec3::ZERO, DVec3::NEG_Y),
            }
        })
        .collect()
}

#[test]
fn round_trip_preserves_cameras_cuts_and_fps() {
    let cams = some_cameras();
    let path = temp("round_trip.json");
    write_cameras(&path, &cams, &[2, 4], Some(29.97)).unwrap();
    let back = read_cameras(&path).unwrap();
    std::fs::remove_file(&path).ok();
    assert_eq!(back.len(), cams.len());
    for (i, (a, b)) in cams.iter().zip(&back).enumerate() {
        assert_eq!(b.id, i as i64);
        assert_eq!(b.cut, i == 2 || i == 4);
        assert_eq!(b.fps, Some(29.97));
        // Exact, not just close: the writer prints shortest round-trip decimals.
        assert_eq!(&b.camera, a);
    }
}

#[test]
fn written_rotation_rows_follow_the_inria_convention() {
    let pos = DVec3::new(-5.0, 0.0, 0.0);
    let rot = look_at_rotation(pos, DVec3::ZERO, DVec3::NEG_Y);
    let c =
        Camera { name: "x".into(), width: 8, height: 8, fx: 4.0, fy: 4.0, position: pos, cam_to_world: rot };
    let path = temp("convention.json");
    write_cameras(&path, std::slice::from_ref(&c), &[], None).unwrap();
    let v: serde_json::Value = serde_json::from_slice(&std::fs::read(&path).unwrap()).unwrap();
    std::fs::remove_file(&path).ok();
    let rot = &v[0]["rotation"];
    // Column 2 of the rows (the forward axis) is (+1, 0, 0): rows[0][2] = 1.
    assert!((rot[0][2].as_f64().unwrap() - 1.0).abs() < 1e-12, "{rot}");
    assert_eq!(v[0]["img_name"], "x");
    assert!(v[0].get("cut").is_none() && v[0].get("fps").is_none());
}

#[test]
fn camera_spec_selects_by_index_name_or_default() {
    let cams = some_cameras();
    let path = temp("spec.json");
    write_cameras(&path, &cams, &[], None).unwrap();
    let p = path.display().to_string();
    assert_eq!(parse_camera_spec(&p).unwrap(), cams[0]);
    assert_eq!(parse_camera_spec(&format!("{p}#3")).unwrap(), cams[3]);
    assert_eq!(parse_camera_spec(&format!("{p}#cam 2")).unwrap(), cams[2]);
    let e = parse_camera_spec(&format!("{p}#7")).unwrap_err().to_string();
    assert!(e.contains(&format!("camera 7 requested but {p} has 5")), "{e}");
    assert!(e.starts_with(&p));
    let e = parse_camera_spec(&format!("{p}#nope")).unwrap_err().to_string();
    assert!(e.contains("no camera named 'nope'") && e.contains("cam 0"), "{e}");
    std::fs::remove_file(&path).ok();
    let e = parse_camera_spec("/no/such/cams.json#1").unwrap_err().to_string();
    assert!(e.starts_with("/no/such/cams.json: cannot read"), "{e}");
}

#[test]
fn reader_errors_name_the_file_and_the_camera() {
    let bad = br#"[{"width": 2, "height": 2, "position": [0,0,0], "rotation": [[1,0,0],[0,1,0],[0,0,1]], "fx": 1, "fy": 1},
                   {"width": 2, "height": 2, "position": [0,0,0], "rotation": [[1,0,0],[0,1,0],[0,0,1]], "fy": 1}]"#;
    let e = parse_cameras(bad, Path::new("x/cams.json")).unwrap_err().to_string();
    assert_eq!(e, "x/cams.json: camera 1: missing field 'fx'");
    let e = parse_cameras(b"[\n{\"id\": 0,,}]", Path::new("j.json")).unwrap_err().to_string();
    assert!(e.starts_with("j.json: not valid JSON") && e.contains("line 2 column"), "{e}");
    // Slightly off rotations (within 1e-3) are accepted, larger errors are not.
    let r = DMat3::from_rotation_y(0.3);
    for (eps, ok) in [(5e-4, true), (5e-3, false)] {
        let rows = [r.row(0).to_array(), r.row(1).to_array(), (r.row(2) * (1.0 + eps)).to_array()];
        let text = format!(
            r#"[{{"width": 2, "height": 2, "position": [0,0,0], "rotation": {}, "fx": 1, "fy": 1}}]"#,
            serde_json::to_string(&rows).unwrap()
        );
        assert_eq!(parse_cameras(text.as_bytes(), Path::new("r.json")).is_ok(), ok, "{eps}");
    }
}

const SAMPLE: &str = r#"[{"id": 0, "img_name": "front", "width": 320, "height": 240, "position": [0.0, -1.6, -5.0],
 "rotation": [[0.99995, 0.0, -0.0099995], [-0.0, 1.0, 0.0], [0.0099995, 0.0, 0.99995]], "fx": 300.0, "fy": 300.0,
 "cut": true, "fps": 30}]"#;

proptest! {
    #[test]
    fn reader_never_panics_on_random_bytes(bytes in proptest::collection::vec(any::<u8>(), 0..400)) {
        let _ = parse_cameras(&bytes, Path::new("random.json"));
    }

    #[test]
    fn reader_never_panics_on_mutated_json(edits in proptest::collection::vec((any::<usize>(), any::<u8>(), 0u8..3), 1..8)) {
        let mut bytes = SAMPLE.as_bytes().to_vec();
        for (pos, b, op) in edits {
            let i = pos % (bytes.len() + 1);
            match op {
                0 if i < bytes.len() => bytes[i] = b,
                1 => bytes.insert(i, b),
                _ if i < bytes.len() => { bytes.remove(i); }
                _ => {}
            }
        }
        if let Err(e) = parse_cameras(&bytes, Path::new("mutated.json")) {
            prop_assert!(e.to_string().starts_with("mutated.json: "));
        }
    }

    #[test]
    fn reader_never_panics_on_json_like_text(text in r#"[\[\]{}",:0-9a-z_\-.eE ]{0,200}"#) {
        let _ = parse_cameras(text.as_bytes(), Path::new("text.json"));
    }
}

#[test]
fn sample_is_valid() {
    let e = parse_cameras(SAMPLE.as_bytes(), Path::new("s")).unwrap();
    assert!(e[0].cut);
    assert_eq!(e[0].fps, Some(30.0));
}
