//! Decoding the standard 3DGS vertex layout (`x y z f_dc_* f_rest_* opacity scale_* rot_*`).

use super::header::{Element, PropertyKind, ScalarType};
use crate::error::{InputError, InputResult};
use crate::scene::{sh_coeffs, RawSplats};
use rayon::prelude::*;
use std::path::Path;

/// Required scalar properties in the order of the destination slots used by [`decode_vertices`]:
/// position (3), f_dc (3), opacity (1), scale (3), rotation (4).
const REQUIRED: [&str; 14] = [
    "x", "y", "z", "f_dc_0", "f_dc_1", "f_dc_2", "opacity", "scale_0", "scale_1", "scale_2", "rot_0",
    "rot_1", "rot_2", "rot_3",
];

/// Gaussians decoded per parallel task.
const BLOCK: usize = 8192;

/// The SH degree whose `f_rest` count is `count`, if any (0, 9, 24, 45 for degrees 0..=3).
pub fn sh_degree_for_rest(count: usize) -> Option<u8> {
    (0..=3u8).find(|&d| 3 * (sh_coeffs(d) - 1) == count)
}

/// Where each destination value of one Gaussian lives within a vertex entry.
struct Layout {
    stride: usize,
    /// Offsets and types of the 14 [`REQUIRED`] properties.
    fixed: [(usize, ScalarType); 14],
    /// Offsets and types of `f_rest_0..`.
    rest: Vec<(usize, ScalarType)>,
    sh_degree: u8,
    all_f32: bool,
}

fn layout(vertex: &Element, path: &Path) -> InputResult<Layout> {
    let err = |p: String| InputError::new(path, p);
    if let Some(p) = vertex.properties.iter().find(|p| matches!(p.kind, PropertyKind::List(..))) {
        return Err(err(format!("list property '{}' in the vertex element is not supported", p.name)));
    }
    let stride = vertex.fixed_stride().unwrap_or(0);
    let mut fixed = [(0, ScalarType::F32); 14];
    for (slot, name) in fixed.iter_mut().zip(REQUIRED) {
        *slot = vertex
            .scalar_offset(name)
            .ok_or_else(|| err(format!("missing required property '{name}' in the vertex element")))?;
    }
    let rest_count = vertex.properties.iter().filter(|p| p.name.starts_with("f_rest_")).count();
    let sh_degree = sh_degree_for_rest(rest_count).ok_or_else(|| {
        err(format!(
            "bad f_rest count: {rest_count} f_rest_* properties (expected 0, 9, 24 or 45 for SH degree 0..3)"
        ))
    })?;
    let rest = (0..rest_count)
        .map(|i| {
            let name = format!("f_rest_{i}");
            vertex.scalar_offset(&name).ok_or_else(|| {
                err(format!(
                    "missing required property '{name}' (there are {rest_count} f_rest_* properties)"
                ))
            })
        })
        .collect::<InputResult<Vec<_>>>()?;
    let all_f32 = vertex.properties.iter().all(|p| p.kind == PropertyKind::Scalar(ScalarType::F32));
    Ok(Layout { stride, fixed, rest, sh_degree, all_f32 })
}

/// Mutable views of one block of Gaussians in the output.
struct OutBlock<'a> {
    position: &'a mut [[f32; 3]],
    f_dc: &'a mut [[f32; 3]],
    opacity: &'a mut [f32],
    log_scale: &'a mut [[f32; 3]],
    rotation: &'a mut [[f32; 4]],
    f_rest: &'a mut [f32],
}

fn split_blocks(raw: &mut RawSplats, rest: usize) -> Vec<OutBlock<'_>> {
    let mut blocks = Vec::new();
    let (mut p, mut d, mut o) = (&mut raw.position[..], &mut raw.f_dc[..], &mut raw.opacity[..]);
    let (mut s, mut r, mut f) = (&mut raw.log_scale[..], &mut raw.rotation[..], &mut raw.f_rest[..]);
    while !p.is_empty() {
        let k = BLOCK.min(p.len());
        let (p0, p1) = std::mem::take(&mut p).split_at_mut(k);
        let (d0, d1) = std::mem::take(&mut d).split_at_mut(k);
        let (o0, o1) = std::mem::take(&mut o).split_at_mut(k);
        let (s0, s1) = std::mem::take(&mut s).split_at_mut(k);
        let (r0, r1) = std::mem::take(&mut r).split_at_mut(k);
        let (f0, f1) = std::mem::take(&mut f).split_at_mut(k * rest);
        blocks.push(OutBlock {
            position: p0,
            f_dc: d0,
            opacity: o0,
            log_scale: s0,
            rotation: r0,
            f_rest: f0,
        });
        (p, d, o, s, r, f) = (p1, d1, o1, s1, r1, f1);
    }
    blocks
}

/// Decodes `data` (exactly the vertex element's bytes) into [`RawSplats`].
///
/// Properties are found by name in any order and converted to `f32`; unknown properties are
/// skipped. When every property is a `float`, a specialised loop is used.
pub fn decode_vertices(vertex: &Element, data: &[u8], path: &Path) -> InputResult<RawSplats> {
    let lay = layout(vertex, path)?;
    let n = usize::try_from(vertex.count)
        .ok()
        .filter(|&n| n.checked_mul(lay.stride) == Some(data.len()))
        .ok_or_else(|| InputError::new(path, "vertex data size does not match the header"))?;
    let rest = lay.rest.len();
    let mut raw = RawSplats {
        position: vec![[0.0; 3]; n],
        f_dc: vec![[0.0; 3]; n],
        sh_degree: lay.sh_degree,
        f_rest: vec![0.0; n * rest],
        opacity: vec![0.0; n],
        log_scale: vec![[0.0; 3]; n],
        rotation: vec![[0.0; 4]; n],
    };
    let blocks = split_blocks(&mut raw, rest);
    if lay.all_f32 {
        blocks.into_par_iter().enumerate().for_each(|(b, out)| fill_block(&lay, data, b, out, read_f32_only));
    } else {
        blocks.into_par_iter().enumerate().for_each(|(b, out)| fill_block(&lay, data, b, out, read_any));
    }
    Ok(raw)
}

/// Reads a little-endian `f32` at `off` (the layout guarantees it is in range; 0 otherwise).
#[inline(always)]
fn read_f32_only(row: &[u8], off: usize, _: ScalarType) -> f32 {
    match row.get(off..off + 4) {
        Some(s) => f32::from_le_bytes([s[0], s[1], s[2], s[3]]),
        None => 0.0,
    }
}

#[inline(always)]
fn read_any(row: &[u8], off: usize, ty: ScalarType) -> f32 {
    ty.read_f32(row, off).unwrap_or(0.0)
}

#[inline(always)]
fn fill_block(
    lay: &Layout,
    data: &[u8],
    block: usize,
    out: OutBlock<'_>,
    read: impl Fn(&[u8], usize, ScalarType) -> f32,
) {
    let first = block * BLOCK;
    let rest = lay.rest.len();
    let rows = data[first * lay.stride..].chunks_exact(lay.stride.max(1));
    for (j, row) in rows.take(out.position.len()).enumerate() {
        let v = |k: usize| read(row, lay.fixed[k].0, lay.fixed[k].1);
        out.position[j] = [v(0), v(1), v(2)];
        out.f_dc[j] = [v(3), v(4), v(5)];
        out.opacity[j] = v(6);
        out.log_scale[j] = [v(7), v(8), v(9)];
        out.rotation[j] = [v(10), v(11), v(12), v(13)];
        let dst = &mut out.f_rest[j * rest..(j + 1) * rest];
        for (d, &(off, ty)) in dst.iter_mut().zip(&lay.rest) {
            *d = read(row, off, ty);
        }
    }
}
