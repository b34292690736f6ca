//! Builders of small PLY files for the `ply_*` integration tests.
#![allow(dead_code)]

/// A binary little-endian PLY: the `element`/`property` lines in `body`, then `data`.
pub fn ply(body: &str, data: &[u8]) -> Vec<u8> {
    let mut out = format!("ply\nformat binary_little_endian 1.0\n{body}end_header\n").into_bytes();
    out.extend_from_slice(data);
    out
}

/// Appends little-endian `f32`s.
pub fn put_f32(out: &mut Vec<u8>, values: &[f32]) {
    values.iter().for_each(|v| out.extend_from_slice(&v.to_le_bytes()));
}

/// Packs three values already quantised to 11, 10 and 11 bits.
pub fn pack_111011(x: u32, y: u32, z: u32) -> u32 {
    (x << 21) | (y << 11) | z
}

/// Packs the largest-component index and three 10-bit components.
pub fn pack_rot(largest: u32, a: u32, b: u32, c: u32) -> u32 {
    (largest << 30) | (a << 20) | (b << 10) | c
}

/// Packs four bytes r, g, b, a (r in the top byte).
pub fn pack_rgba(r: u32, g: u32, b: u32, a: u32) -> u32 {
    (r << 24) | (g << 16) | (b << 8) | a
}

/// A compressed PLY. `chunks` rows hold `min_x y z, max_x y z, min_scale_x y z, max_scale_x y z`
/// and, when `colour` is set, `min_r g b, max_r g b`; `vertices` hold the four packed words;
/// `sh` holds `(properties per vertex, bytes)`.
pub fn compressed(
    chunks: &[Vec<f32>],
    colour: bool,
    vertices: &[[u32; 4]],
    sh: Option<(usize, &[u8])>,
) -> Vec<u8> {
    let mut body = format!("element chunk {}\n", chunks.len());
    let mut names: Vec<&str> = vec![
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
    if colour {
        names.extend(["min_r", "min_g", "min_b", "max_r", "max_g", "max_b"]);
    }
    for n in &names {
        body += &format!("property float {n}\n");
    }
    body += &format!("element vertex {}\n", vertices.len());
    for n in ["packed_position", "packed_rotation", "packed_scale", "packed_color"] {
        body += &format!("property uint {n}\n");
    }
    let mut data = Vec::new();
    for c in chunks {
        assert_eq!(c.len(), names.len(), "chunk row width");
        put_f32(&mut data, c);
    }
    for v in vertices {
        v.iter().for_each(|w| data.extend_from_slice(&w.to_le_bytes()));
    }
    if let Some((k, bytes)) = sh {
        body += &format!("element sh {}\n", vertices.len());
        for i in 0..k {
            body += &format!("property uchar f_rest_{i}\n");
        }
        data.extend_from_slice(bytes);
    }
    ply(&body, &data)
}

/// A valid small compressed PLY: 300 vertices (2 chunks), colour bounds, SH degree 1.
pub fn small_compressed() -> Vec<u8> {
    let chunk = |k: f32| {
        vec![
            -1.0,
            -2.0,
            -3.0,
            1.0,
            2.0,
            3.0 + k,
            -5.0,
            -5.0,
            -5.0,
            -1.0,
            -2.0,
            -3.0,
            0.0,
            0.1,
            0.2,
            1.0,
            0.9,
            0.8,
        ]
    };
    let vertices: Vec<[u32; 4]> = (0..300u32)
        .map(|i| {
            [
                pack_111011(i % 2048, (i * 7) % 1024, (i * 13) % 2048),
                pack_rot(i % 4, (i * 3) % 1024, (i * 5) % 1024, (i * 11) % 1024),
                pack_111011((i * 17) % 2048, (i * 19) % 1024, (i * 23) % 2048),
                pack_rgba(i % 256, (i * 3) % 256, (i * 7) % 256, (i * 29) % 256),
            ]
        })
        .collect();
    let sh: Vec<u8> = (0..300 * 9).map(|i| (i * 37 % 256) as u8).collect();
    compressed(&[chunk(0.0), chunk(1.0)], true, &vertices, Some((9, &sh)))
}
