//! Decoding the PlayCanvas/SuperSplat `compressed.ply` layout to the standard raw parameterisation.
//!
//! Layout: a `chunk` element with per-256-Gaussian bounds (`min_/max_x y z`, `min_/max_scale_x y z`
//! and optionally `min_/max_r g b`), a `vertex` element of four `uint`s (`packed_position`,
//! `packed_rotation`, `packed_scale`, `packed_color`) and an optional `sh` element of `uchar`
//! `f_rest_*`. The arithmetic follows `@playcanvas/splat-transform` (computed in `f64`, stored as
//! `f32`), so our decode matches its output to float rounding.

use super::header::{Element, PropertyKind, ScalarType};
use super::standard::sh_degree_for_rest;
use crate::error::{InputError, InputResult};
use crate::scene::RawSplats;
use std::path::Path;

/// Gaussians per chunk.
pub const CHUNK_SIZE: usize = 256;

pub use crate::scene::SH_C0;

const CHUNK_REQUIRED: [&str; 12] = [
    "min_x",
    "min_y",
    "min_z",
    "max_x",
    "max_y",
    "max_z",
    "min_scale_x",
    "min_scale_y",
    "min_scale_z",
    "max_scale_x",
    "max_scale_y",
    "max_scale_z",
];
const CHUNK_COLOUR: [&str; 6] = ["min_r", "min_g", "min_b", "max_r", "max_g", "max_b"];
const PACKED: [&str; 4] = ["packed_position", "packed_rotation", "packed_scale", "packed_color"];

/// True when the header describes the compressed layout (a `chunk` element and a vertex element
/// with `packed_position`).
pub fn is_compressed(chunk: Option<&Element>, vertex: &Element) -> bool {
    chunk.is_some() && vertex.has("packed_position")
}

/// One element's data with its layout, for reading values by row and property.
pub struct Table<'a> {
    data: &'a [u8],
    element: &'a Element,
    stride: usize,
}

impl<'a> Table<'a> {
    /// Wraps an element and exactly its data bytes.
    pub fn new(element: &'a Element, data: &'a [u8]) -> Self {
        Self { data, element, stride: element.fixed_stride().unwrap_or(0) }
    }

    /// Offsets and types of `names`, or an error naming the first one that is missing.
    fn columns<const N: usize>(
        &self,
        names: [&str; N],
        path: &Path,
    ) -> InputResult<[(usize, ScalarType); N]> {
        let el = self.element;
        if let Some(p) = el.properties.iter().find(|p| matches!(p.kind, PropertyKind::List(..))) {
            return Err(InputError::new(
                path,
                format!("list property '{}' in the '{}' element is not supported", p.name, el.name),
            ));
        }
        let mut out = [(0, ScalarType::F32); N];
        for (slot, name) in out.iter_mut().zip(names) {
            *slot = el.scalar_offset(name).ok_or_else(|| {
                InputError::new(
                    path,
                    format!("missing required property '{name}' in the '{}' element", el.name),
                )
            })?;
        }
        Ok(out)
    }

    fn get(&self, row: usize, (off, ty): (usize, ScalarType)) -> f64 {
        ty.read_f64(self.data, row * self.stride + off).unwrap_or(0.0)
    }
}

/// Reads the 32-bit word of a packed property (declared `uint` or `int`).
fn packed_word(t: &Table<'_>, row: usize, (off, _): (usize, ScalarType)) -> u32 {
    match t.data.get(row * t.stride + off..row * t.stride + off + 4) {
        Some(s) => u32::from_le_bytes([s[0], s[1], s[2], s[3]]),
        None => 0,
    }
}

/// `bits`-wide unsigned field at `shift`, mapped to [0, 1] by dividing by `2^bits - 1`.
fn unorm(v: u32, shift: u32, bits: u32) -> f64 {
    let max = (1u32 << bits) - 1;
    ((v >> shift) & max) as f64 / max as f64
}

fn lerp(a: f64, b: f64, t: f64) -> f64 {
    a * (1.0 - t) + b * t
}

/// 11/10/11-bit vector (x in the top 11 bits).
fn unpack_111011(v: u32) -> [f64; 3] {
    [unorm(v, 21, 11), unorm(v, 11, 10), unorm(v, 0, 11)]
}

/// "Smallest three" quaternion: top 2 bits index the largest component, then three 10-bit
/// components in order of the remaining indices, each scaled from [0, 1] to +-1/sqrt(2). The
/// component index is the `rot_*` index (w first).
pub fn unpack_rotation(v: u32) -> [f32; 4] {
    let norm = std::f64::consts::SQRT_2; // 1 / (sqrt(2) / 2)
    let a = (unorm(v, 20, 10) - 0.5) * norm;
    let b = (unorm(v, 10, 10) - 0.5) * norm;
    let c = (unorm(v, 0, 10) - 0.5) * norm;
    let m = (1.0 - (a * a + b * b + c * c)).max(0.0).sqrt();
    let q = match v >> 30 {
        0 => [m, a, b, c],
        1 => [a, m, b, c],
        2 => [a, b, m, c],
        _ => [a, b, c, m],
    };
    q.map(|x| x as f32)
}

/// Dequantises one `sh` byte to an `f_rest` value in [-4, 4] (0 and 255 map to the ends exactly).
pub fn sh_value(b: u8) -> f32 {
    let n = match b {
        0 => 0.0,
        255 => 1.0,
        _ => (b as f64 + 0.5) / 256.0,
    };
    ((n - 0.5) * 8.0) as f32
}

/// Decodes the compressed layout. `sh` is the optional `sh` element's table.
pub fn decode(
    chunk: Table<'_>,
    vertex: Table<'_>,
    sh: Option<Table<'_>>,
    path: &Path,
) -> InputResult<RawSplats> {
    let err = |p: String| InputError::new(path, p);
    let n = usize::try_from(vertex.element.count).map_err(|_| err("vertex count too large".into()))?;
    let need_chunks = n.div_ceil(CHUNK_SIZE) as u64;
    if chunk.element.count < need_chunks {
        return Err(err(format!(
            "compressed PLY has {} chunks but {n} vertices need {need_chunks} (one per {CHUNK_SIZE})",
            chunk.element.count
        )));
    }
    let bounds = chunk.columns(CHUNK_REQUIRED, path)?;
    let colour_present = CHUNK_COLOUR.iter().filter(|c| chunk.element.has(c)).count();
    let colour = match colour_present {
        0 => None,
        6 => Some(chunk.columns(CHUNK_COLOUR, path)?),
        _ => return Err(err("chunk element has some but not all of min_r..max_b colour bounds".into())),
    };
    let packed = vertex.columns(PACKED, path)?;
    for (name, (_, ty)) in PACKED.iter().zip(packed) {
        if !matches!(ty, ScalarType::U32 | ScalarType::I32) {
            return Err(err(format!("property '{name}' must be a 32-bit 'uint', not {ty:?}")));
        }
    }
    let mut raw = RawSplats::default();
    raw.position.reserve(n);
    raw.f_dc.reserve(n);
    raw.opacity.reserve(n);
    raw.log_scale.reserve(n);
    raw.rotation.reserve(n);
    for i in 0..n {
        let ci = i / CHUNK_SIZE;
        let b = |k: usize| chunk.get(ci, bounds[k]);
        let p = unpack_111011(packed_word(&vertex, i, packed[0]));
        raw.position.push([0, 1, 2].map(|a| lerp(b(a), b(a + 3), p[a]) as f32));
        raw.rotation.push(unpack_rotation(packed_word(&vertex, i, packed[1])));
        let s = unpack_111011(packed_word(&vertex, i, packed[2]));
        raw.log_scale.push([0, 1, 2].map(|a| lerp(b(a + 6), b(a + 9), s[a]) as f32));
        let c = packed_word(&vertex, i, packed[3]);
        let rgba = [unorm(c, 24, 8), unorm(c, 16, 8), unorm(c, 8, 8), unorm(c, 0, 8)];
        raw.f_dc.push([0, 1, 2].map(|a| {
            let v = match &colour {
                Some(cols) => lerp(chunk.get(ci, cols[a]), chunk.get(ci, cols[a + 3]), rgba[a]),
                None => rgba[a],
            };
            ((v - 0.5) / SH_C0) as f32
        }));
        raw.opacity.push(-(1.0 / rgba[3] - 1.0).ln() as f32);
    }
    if let Some(sh) = sh {
        decode_sh(&sh, n, &mut raw, path)?;
    }
    Ok(raw)
}

fn decode_sh(sh: &Table<'_>, n: usize, raw: &mut RawSplats, path: &Path) -> InputResult<()> {
    let err = |p: String| InputError::new(path, p);
    if sh.element.count != n as u64 {
        return Err(err(format!("'sh' element has {} entries but there are {n} vertices", sh.element.count)));
    }
    if sh.element.fixed_stride().is_none() {
        return Err(err("list properties in the 'sh' element are not supported".into()));
    }
    let count = sh.element.properties.len();
    raw.sh_degree = sh_degree_for_rest(count).ok_or_else(|| {
        err(format!("bad f_rest count: 'sh' element has {count} properties (expected 9, 24 or 45)"))
    })?;
    let mut cols = Vec::with_capacity(count);
    for k in 0..count {
        let name = format!("f_rest_{k}");
        match sh.element.scalar_offset(&name) {
            Some((off, ScalarType::U8)) => cols.push(off),
            Some(_) => return Err(err(format!("'sh' property '{name}' must be 'uchar'"))),
            None => return Err(err(format!("missing required property '{name}' in the 'sh' element"))),
        }
    }
    let stride = sh.stride;
    raw.f_rest = sh
        .data
        .chunks_exact(stride.max(1))
        .take(n)
        .flat_map(|row| cols.iter().map(|&off| sh_value(row.get(off).copied().unwrap_or(0))))
        .collect();
    if raw.f_rest.len() != n * count {
        return Err(err("'sh' element data is shorter than declared".into()));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rotation_places_largest_component_by_index() {
        // Index 0 (w) largest, the other three at mid-scale (0.5 -> 0): identity, w first.
        let mid = 511u32; // 511/1023 is just below 0.5
        let v = (mid << 20) | (mid << 10) | mid;
        let q = unpack_rotation(v);
        assert!((q[0] - 1.0).abs() < 1e-5 && q[1].abs() < 2e-3, "{q:?}");
        let q = unpack_rotation((3 << 30) | v);
        assert!((q[3] - 1.0).abs() < 1e-5 && q[0].abs() < 2e-3, "{q:?}");
        // Full-scale first small component is 1/sqrt(2) * sqrt(2) * 0.5 = +0.7071.
        let q = unpack_rotation((1 << 30) | (1023 << 20) | (mid << 10) | mid);
        assert!((q[0] - std::f32::consts::FRAC_1_SQRT_2).abs() < 1e-6, "{q:?}");
        assert!((q[1] - std::f32::consts::FRAC_1_SQRT_2).abs() < 2e-3, "{q:?}");
    }

    #[test]
    fn sh_bytes_map_to_plus_minus_four() {
        assert_eq!(sh_value(0), -4.0);
        assert_eq!(sh_value(255), 4.0);
        assert_eq!(sh_value(128), (128.5 / 256.0 - 0.5) * 8.0);
    }
}
