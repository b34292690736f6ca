//! Reading and writing INRIA `cameras.json` files, and `FILE#i` camera selection.
//!
//! A `cameras.json` is an array of objects
//! `{id, img_name, width, height, position: [3], rotation: [[3]; 3], fx, fy}`:
//! `position` is the camera centre in world space and `rotation` the camera-to-world rotation
//! written as three ROWS, so its columns are the camera x (right), y (down) and z (forward) axes
//! in world space. That is exactly [`Camera::cam_to_world`], stored row by row.
//!
//! Required fields: `width`, `height`, `position`, `rotation`, `fx`, `fy`. `id` (an integer) and
//! `img_name` (a string) are optional on input (they default to the array index and
//! `camera_<index>`) and always written. Unknown fields are ignored.
//!
//! Two optional extension fields, ignored by other tools, let a [`crate::trajectory::Trajectory`]
//! round-trip:
//! - `"cut": true` on the first frame of a new shot (a scene cut);
//! - `"fps": 30.0`, the frame rate of the sequence. [`write_cameras`] puts it on every entry; a
//!   reader takes the first entry that has one, else [`crate::trajectory::DEFAULT_FPS`].

use crate::camera::Camera;
use crate::error::{InputError, InputResult};
use crate::trajectory::resolution::MAX_SIDE;
use glam::{DMat3, DVec3};
use serde_json::Value;
use std::path::Path;

/// Largest accepted deviation of `R^T R` from the identity (per element) for a rotation.
pub const ROTATION_TOLERANCE: f64 = 1e-3;

/// One camera read from a `cameras.json`, with the extension fields.
#[derive(Clone, Debug, PartialEq)]
pub struct CameraEntry {
    /// The `id` field (the array index when absent).
    pub id: i64,
    /// Intrinsics and pose; `camera.name` is `img_name`.
    pub camera: Camera,
    /// `"cut": true`: this frame starts a new shot.
    pub cut: bool,
    /// The optional `"fps"` field.
    pub fps: Option<f64>,
}

/// Reads and validates every camera of a `cameras.json`.
pub fn read_cameras(path: &Path) -> InputResult<Vec<CameraEntry>> {
    let bytes = std::fs::read(path).map_err(|e| InputError::new(path, format!("cannot read: {e}")))?;
    parse_cameras(&bytes, path)
}

/// Parses and validates the bytes of a `cameras.json`; `path` names it in errors.
///
/// Never panics, whatever the bytes.
pub fn parse_cameras(bytes: &[u8], path: &Path) -> InputResult<Vec<CameraEntry>> {
    let value: Value =
        serde_json::from_slice(bytes).map_err(|e| InputError::new(path, format!("not valid JSON: {e}")))?;
    let Value::Array(items) = value else {
        return Err(InputError::new(path, "expected a JSON array of cameras at the top level"));
    };
    items
        .iter()
        .enumerate()
        .map(|(i, item)| parse_entry(i, item).map_err(|p| InputError::new(path, format!("camera {i}: {p}"))))
        .collect()
}

/// Selects one camera from a `FILE#SELECTOR` spec.
///
/// `SELECTOR` is an index into the file's array (`cams.json#2`) or an `img_name`
/// (`cams.json#front`); without `#` the first camera is used. A spec that names an existing
/// file as a whole (a path containing `#`) is taken as that file.
pub fn parse_camera_spec(spec: &str) -> InputResult<Camera> {
    let (file, selector) = match spec.rsplit_once('#') {
        Some((file, sel)) if !Path::new(spec).is_file() => (file, Some(sel)),
        _ => (spec, None),
    };
    let path = Path::new(file);
    let entries = read_cameras(path)?;
    if entries.is_empty() {
        return Err(InputError::new(path, "the file holds no cameras"));
    }
    let Some(sel) = selector else {
        return Ok(entries[0].camera.clone());
    };
    if let Ok(index) = sel.parse::<usize>() {
        return entries.get(index).map(|e| e.camera.clone()).ok_or_else(|| {
            InputError::new(path, format!("camera {index} requested but {file} has {}", entries.len()))
        });
    }
    if let Some(e) = entries.iter().find(|e| e.camera.name == sel) {
        return Ok(e.camera.clone());
    }
    let names: Vec<&str> = entries.iter().take(8).map(|e| e.camera.name.as_str()).collect();
    let more = if entries.len() > names.len() { ", ..." } else { "" };
    Err(InputError::new(
        path,
        format!("no camera named '{sel}' (and it is not an index); names: {}{more}", names.join(", ")),
    ))
}

/// Writes `cams` as a `cameras.json`: `cuts` lists the frames marked `"cut": true`, and `fps`
/// (when given) is written on every entry.
///
/// Cameras with non-finite numbers, a zero size or a non-orthonormal rotation are refused
/// (they could not be read back).
pub fn write_cameras(path: &Path, cams: &[Camera], cuts: &[usize], fps: Option<f64>) -> InputResult<()> {
    let text = cameras_to_json(cams, cuts, fps).map_err(|p| InputError::new(path, p))?;
    std::fs::write(path, text).map_err(|e| InputError::new(path, format!("cannot write: {e}")))
}

/// The text of a `cameras.json` for `cams` (see [`write_cameras`]); the error names the bad
/// camera or cut.
pub fn cameras_to_json(cams: &[Camera], cuts: &[usize], fps: Option<f64>) -> Result<String, String> {
    if let Some(f) = fps {
        if !(f.is_finite() && f > 0.0) {
            return Err(format!("fps must be a positive finite number, not {f}"));
        }
    }
    if let Some(&c) = cuts.iter().find(|&&c| c >= cams.len()) {
        return Err(format!("cut at frame {c} but there are only {} cameras", cams.len()));
    }
    let mut out = Vec::with_capacity(cams.len());
    for (i, cam) in cams.iter().enumerate() {
        check_camera(cam).map_err(|p| format!("camera {i} ('{}'): {p}", cam.name))?;
        let r = cam.cam_to_world;
        let entry = EntryOut {
            id: i,
            img_name: &cam.name,
            width: cam.width,
            height: cam.height,
            position: cam.position.to_array(),
            rotation: [r.row(0).to_array(), r.row(1).to_array(), r.row(2).to_array()],
            fx: cam.fx,
            fy: cam.fy,
            fps,
            cut: cuts.contains(&i),
        };
        out.push(entry);
    }
    serde_json::to_string_pretty(&out).map_err(|e| format!("cannot encode JSON: {e}"))
}

/// The serialised form of one entry (field order as in INRIA files).
#[derive(serde::Serialize)]
struct EntryOut<'a> {
    id: usize,
    img_name: &'a str,
    width: u32,
    height: u32,
    position: [f64; 3],
    rotation: [[f64; 3]; 3],
    fx: f64,
    fy: f64,
    #[serde(skip_serializing_if = "Option::is_none")]
    fps: Option<f64>,
    #[serde(skip_serializing_if = "is_false")]
    cut: bool,
}

fn is_false(b: &bool) -> bool {
    !*b
}

/// Checks what a reader would check: finite numbers, a size of 1 to
/// [`MAX_SIDE`](crate::trajectory::resolution::MAX_SIDE) pixels a side, positive focal lengths,
/// a position within single precision (the renderers' own), an orthonormal right-handed rotation.
pub fn check_camera(cam: &Camera) -> Result<(), String> {
    if cam.width == 0 || cam.height == 0 {
        return Err(format!("image size {}x{} is empty", cam.width, cam.height));
    }
    if cam.width > MAX_SIDE || cam.height > MAX_SIDE {
        return Err(format!(
            "image size {}x{} is too large (at most {MAX_SIDE} pixels a side)",
            cam.width, cam.height
        ));
    }
    for (name, f) in [("fx", cam.fx), ("fy", cam.fy)] {
        if !(f.is_finite() && f > 0.0) {
            return Err(format!("{name} must be a positive finite number, not {f}"));
        }
    }
    if !cam.position.is_finite() {
        return Err(format!("position {:?} is not finite", cam.position.to_array()));
    }
    if !cam.position.as_vec3().is_finite() {
        return Err(format!(
            "position {:?} is beyond single precision (each coordinate must be below {:e})",
            cam.position.to_array(),
            f32::MAX
        ));
    }
    check_rotation(&cam.cam_to_world)
}

/// Checks that `r` is a rotation: finite, `R^T R = I` within [`ROTATION_TOLERANCE`], det > 0.
pub fn check_rotation(r: &DMat3) -> Result<(), String> {
    if !r.is_finite() {
        return Err("rotation has non-finite entries".into());
    }
    let g = r.transpose() * *r;
    let dev = (g - DMat3::IDENTITY).to_cols_array().iter().fold(0.0f64, |m, v| m.max(v.abs()));
    if dev.is_nan() || dev > ROTATION_TOLERANCE {
        return Err(format!(
            "rotation is not orthonormal (R^T R differs from the identity by {dev:.3e}, tolerance {ROTATION_TOLERANCE:e})"
        ));
    }
    if r.determinant() <= 0.0 {
        return Err("rotation is a reflection (determinant < 0), not a rotation".into());
    }
    Ok(())
}

fn parse_entry(index: usize, item: &Value) -> Result<CameraEntry, String> {
    let Value::Object(obj) = item else {
        return Err("expected a JSON object".into());
    };
    let field = |name: &str| obj.get(name).ok_or_else(|| format!("missing field '{name}'"));
    let id = match obj.get("id") {
        None => index as i64,
        Some(v) => v.as_i64().ok_or_else(|| format!("field 'id' must be an integer, not {v}"))?,
    };
    let name = match obj.get("img_name") {
        None => format!("camera_{index}"),
        Some(Value::String(s)) => s.clone(),
        Some(v) => return Err(format!("field 'img_name' must be a string, not {v}")),
    };
    let width = size(field("width")?, "width")?;
    let height = size(field("height")?, "height")?;
    let fx = number(field("fx")?, "fx")?;
    let fy = number(field("fy")?, "fy")?;
    let position = DVec3::from_array(vec3(field("position")?, "position")?);
    let rows = match field("rotation")? {
        Value::Array(rows) if rows.len() == 3 => {
            [vec3(&rows[0], "rotation[0]")?, vec3(&rows[1], "rotation[1]")?, vec3(&rows[2], "rotation[2]")?]
        }
        v => return Err(format!("field 'rotation' must be 3 rows of 3 numbers, not {}", short(v))),
    };
    // The rows are the rows of cam_to_world: transpose the column-built matrix.
    let cam_to_world = DMat3::from_cols_array_2d(&rows).transpose();
    let fps = match obj.get("fps") {
        None | Some(Value::Null) => None,
        Some(v) => Some(number(v, "fps")?),
    };
    let cut = match obj.get("cut") {
        None | Some(Value::Null) => false,
        Some(Value::Bool(b)) => *b,
        Some(v) => return Err(format!("field 'cut' must be true or false, not {}", short(v))),
    };
    let camera = Camera { name, width, height, fx, fy, position, cam_to_world };
    check_camera(&camera)?;
    if let Some(f) = fps {
        if f <= 0.0 {
            return Err(format!("field 'fps' must be positive, not {f}"));
        }
    }
    Ok(CameraEntry { id, camera, cut, fps })
}

fn number(v: &Value, name: &str) -> Result<f64, String> {
    match v.as_f64() {
        Some(f) if f.is_finite() => Ok(f),
        _ => Err(format!("field '{name}' must be a finite number, not {}", short(v))),
    }
}

fn size(v: &Value, name: &str) -> Result<u32, String> {
    match v.as_u64() {
        Some(0) => Err(format!("field '{name}' is zero")),
        Some(n) if n <= u32::MAX as u64 => Ok(n as u32),
        _ => Err(format!("field '{name}' must be a positive integer, not {}", short(v))),
    }
}

fn vec3(v: &Value, name: &str) -> Result<[f64; 3], String> {
    match v {
        Value::Array(a) if a.len() == 3 => {
            Ok([number(&a[0], name)?, number(&a[1], name)?, number(&a[2], name)?])
        }
        _ => Err(format!("field '{name}' must be an array of 3 numbers, not {}", short(v))),
    }
}

/// A JSON value shortened for an error message.
fn short(v: &Value) -> String {
    let s = v.to_string();
    if s.chars().count() > 40 {
        format!("{}...", s.chars().take(40).collect::<String>())
    } else {
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const ONE: &str = r#"[{"id": 3, "img_name": "a", "width": 4, "height": 2,
        "position": [1, 2, 3], "rotation": [[0, -1, 0], [1, 0, 0], [0, 0, 1]], "fx": 5, "fy": 6}]"#;

    #[test]
    fn rows_become_the_transpose_of_columns() {
        let e = parse_cameras(ONE.as_bytes(), Path::new("c.json")).unwrap();
        let c = &e[0].camera;
        assert_eq!(e[0].id, 3);
        assert_eq!((c.width, c.height, c.fx, c.fy), (4, 2, 5.0, 6.0));
        // Row 0 is [0, -1, 0]: the camera x axis (column 0) is (0, 1, 0).
        assert_eq!(c.cam_to_world.x_axis, DVec3::new(0.0, 1.0, 0.0));
        assert_eq!(c.cam_to_world.y_axis, DVec3::new(-1.0, 0.0, 0.0));
        assert!(!e[0].cut && e[0].fps.is_none());
    }

    #[test]
    fn errors_name_the_problem() {
        let cases = [
            ("[{", "line 1 column 2"),
            ("{}", "JSON array"),
            (r#"[{"width": 1}]"#, "missing field 'height'"),
            (&ONE.replace("\"width\": 4", "\"width\": 0"), "'width' is zero"),
            (&ONE.replace("\"width\": 4", "\"width\": 100000"), "camera 0: image size 100000x2 is too large"),
            (&ONE.replace("\"height\": 2", "\"height\": 4294967295"), "image size 4x4294967295 is too large"),
            (
                &ONE.replace("[1, 2, 3]", "[1e300, 2, 3]"),
                "camera 0: position [1e300, 2.0, 3.0] is beyond single",
            ),
            (&ONE.replace("\"fx\": 5", "\"fx\": \"5\""), "'fx' must be a finite number"),
            (&ONE.replace("[0, -1, 0]", "[0, -2, 0]"), "not orthonormal"),
            (&ONE.replace("[0, 0, 1]", "[0, 0, -1]"), "reflection"),
            (&ONE.replace("\"fy\": 6", "\"fy\": 6, \"cut\": 1"), "'cut' must be true or false"),
            (&ONE.replace("\"fy\": 6", "\"fy\": 1e999"), "not valid JSON"),
        ];
        for (text, want) in cases {
            let err = parse_cameras(text.as_bytes(), Path::new("bad.json")).unwrap_err().to_string();
            assert!(err.starts_with("bad.json: "), "{err}");
            assert!(err.contains(want), "{text} -> {err}, wanted {want}");
        }
    }

    #[test]
    fn writer_refuses_unreadable_cameras() {
        let mut c = parse_cameras(ONE.as_bytes(), Path::new("c")).unwrap().remove(0).camera;
        c.position.x = f64::NAN;
        assert!(cameras_to_json(&[c.clone()], &[], None).unwrap_err().contains("not finite"));
        c.position.x = 0.0;
        assert!(cameras_to_json(&[c.clone()], &[1], None).unwrap_err().contains("cut at frame 1"));
        assert!(cameras_to_json(&[c], &[], Some(0.0)).unwrap_err().contains("fps"));
    }
}
