//! Writing the standard 3DGS `.ply` layout (binary little endian), as the reference exporter does.

use crate::error::{InputError, InputResult};
use crate::scene::RawSplats;
use std::path::Path;

/// The header of a standard `.ply` holding `n` Gaussians with `rest` `f_rest_*` values each:
/// `x y z nx ny nz f_dc_0..2 f_rest_* opacity scale_0..2 rot_0..3`, all `float`.
pub fn standard_header(n: usize, rest: usize) -> String {
    let mut h = format!("ply\nformat binary_little_endian 1.0\nelement vertex {n}\n");
    let mut names: Vec<String> = ["x", "y", "z", "nx", "ny", "nz", "f_dc_0", "f_dc_1", "f_dc_2"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    names.extend((0..rest).map(|i| format!("f_rest_{i}")));
    names.extend(
        ["opacity", "scale_0", "scale_1", "scale_2", "rot_0", "rot_1", "rot_2", "rot_3"]
            .iter()
            .map(|s| s.to_string()),
    );
    for name in names {
        h.push_str("property float ");
        h.push_str(&name);
        h.push('\n');
    }
    h.push_str("end_header\n");
    h
}

/// True when all property arrays of `raw` have lengths consistent with its Gaussian count.
fn consistent(raw: &RawSplats) -> bool {
    let n = raw.len();
    raw.f_dc.len() == n
        && raw.opacity.len() == n
        && raw.log_scale.len() == n
        && raw.rotation.len() == n
        && raw.f_rest.len() == n * raw.rest_per_gaussian()
        && raw.sh_degree <= 3
}

/// The bytes of a standard `.ply` holding `raw` (normals written as 0). Values are stored
/// bit-exactly, including infinite opacity logits.
///
/// # Panics
/// If the arrays of `raw` have inconsistent lengths or `sh_degree > 3` (a programming error;
/// [`write_standard`] reports it as an error instead).
pub fn standard_bytes(raw: &RawSplats) -> Vec<u8> {
    assert!(consistent(raw), "standard_bytes: RawSplats arrays have inconsistent lengths");
    let n = raw.len();
    let rest = raw.rest_per_gaussian();
    let header = standard_header(n, rest);
    let floats = 17 + rest;
    let mut out = Vec::with_capacity(header.len() + n * floats * 4);
    out.extend_from_slice(header.as_bytes());
    for i in 0..n {
        let mut put = |v: f32| out.extend_from_slice(&v.to_le_bytes());
        raw.position[i].into_iter().for_each(&mut put);
        [0.0; 3].into_iter().for_each(&mut put);
        raw.f_dc[i].into_iter().for_each(&mut put);
        raw.f_rest[i * rest..(i + 1) * rest].iter().copied().for_each(&mut put);
        put(raw.opacity[i]);
        raw.log_scale[i].into_iter().for_each(&mut put);
        raw.rotation[i].into_iter().for_each(&mut put);
    }
    out
}

/// Writes `raw` as a standard `.ply` to `path`.
pub fn write_standard(path: &Path, raw: &RawSplats) -> InputResult<()> {
    if !consistent(raw) {
        return Err(InputError::new(path, "cannot write: property arrays have inconsistent lengths"));
    }
    std::fs::write(path, standard_bytes(raw))
        .map_err(|e| InputError::new(path, format!("cannot write file: {e}")))
}
