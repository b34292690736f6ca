//! Decoding standard and compressed PLY files built by hand, and the write/read round trip.

mod ply_common;

use neo_golden::ply::{bench_splats, parse_raw, read_raw, standard_bytes, write_standard};
use neo_golden::scene::RawSplats;
use ply_common::*;
use std::path::Path;

fn p() -> &'static Path {
    Path::new("test.ply")
}

/// All values of `r` as bit patterns, for bit-exact comparison (NaN-safe, -0 distinct).
fn bits(r: &RawSplats) -> Vec<u32> {
    let mut v = Vec::new();
    for i in 0..r.len() {
        v.extend(r.position[i].iter().chain(&r.f_dc[i]).chain(&r.log_scale[i]).chain(&r.rotation[i]));
        v.push(r.opacity[i]);
    }
    v.extend(&r.f_rest);
    v.into_iter().map(f32::to_bits).collect()
}

#[test]
fn write_then_read_is_bit_exact_for_every_degree() {
    for degree in 0..=3u8 {
        let mut raw = bench_splats(37, degree);
        raw.opacity[0] = f32::INFINITY;
        raw.opacity[1] = f32::NEG_INFINITY;
        raw.position[2][0] = -0.0;
        raw.log_scale[3][1] = f32::MIN_POSITIVE / 8.0; // subnormal
        raw.rotation[4][3] = f32::MAX;
        let back = parse_raw(&standard_bytes(&raw), p()).unwrap();
        assert_eq!(back.sh_degree, degree);
        assert_eq!(back.len(), 37);
        assert_eq!(bits(&back), bits(&raw), "degree {degree}");
    }
}

#[test]
fn write_standard_writes_a_readable_file_with_zero_normals() {
    let raw = bench_splats(5, 2);
    let path = std::env::temp_dir().join(format!("neo_ply_decode_{}.ply", std::process::id()));
    write_standard(&path, &raw).unwrap();
    let bytes = std::fs::read(&path).unwrap();
    let back = read_raw(&path).unwrap();
    std::fs::remove_file(&path).unwrap();
    assert_eq!(bits(&back), bits(&raw));
    let text = String::from_utf8_lossy(&bytes[..bytes.len().min(400)]).to_string();
    assert!(
        text.contains("property float x\nproperty float y\nproperty float z\nproperty float nx\n"),
        "{text}"
    );
    // Gaussian 0 starts right after the header: x y z, then nx ny nz = 0.
    let start = bytes.windows(11).position(|w| w == b"end_header\n").unwrap() + 11;
    assert_eq!(&bytes[start + 12..start + 24], &[0u8; 12]);
    let mut bad = raw.clone();
    bad.opacity.pop();
    let e = write_standard(&path, &bad).unwrap_err().to_string();
    assert!(e.contains("inconsistent"), "{e}");
    assert!(!path.exists());
}

#[test]
fn properties_are_found_by_name_with_any_type_and_order() {
    // A list element before the vertices, mixed scalar types, f_rest declared out of order and an
    // unknown property; the `face` element after the vertices is never read (it is absent).
    let mut body = String::from("element camera 2\nproperty list uchar float params\nproperty uchar id\n");
    body += "element vertex 2\nproperty double opacity\nproperty uchar x\nproperty short y\nproperty int z\n";
    body += "property char f_dc_0\nproperty ushort f_dc_1\nproperty uint f_dc_2\nproperty float nx\n";
    for k in (0..9).rev() {
        body += &format!("property float32 f_rest_{k}\n");
    }
    for n in ["scale_0", "scale_1", "scale_2", "rot_0", "rot_1", "rot_2"] {
        body += &format!("property float {n}\n");
    }
    body += "property int8 rot_3\nelement face 1\nproperty list uchar int vertex_indices\n";
    let mut data = vec![2u8];
    put_f32(&mut data, &[1.5, 2.5]);
    data.push(7);
    data.push(0u8);
    data.push(8);
    for g in 0..2u8 {
        data.extend_from_slice(&(-0.25f64 - g as f64).to_le_bytes());
        data.push(200 + g);
        data.extend_from_slice(&(-300i16).to_le_bytes());
        data.extend_from_slice(&(-70000i32).to_le_bytes());
        data.push((-5i8) as u8);
        data.extend_from_slice(&60000u16.to_le_bytes());
        data.extend_from_slice(&4_000_000_000u32.to_le_bytes());
        put_f32(&mut data, &[9.0]);
        let rest: Vec<f32> = (0..9).rev().map(|k| k as f32 + 10.0 * g as f32).collect();
        put_f32(&mut data, &rest);
        put_f32(&mut data, &[-1.0, -2.0, -3.0, 0.5, 0.25, 0.125]);
        data.push((-1i8) as u8);
    }
    let raw = parse_raw(&ply(&body, &data), p()).unwrap();
    assert_eq!(raw.len(), 2);
    assert_eq!(raw.sh_degree, 1);
    assert_eq!(raw.position[1], [201.0, -300.0, -70000.0]);
    assert_eq!(raw.f_dc[0], [-5.0, 60000.0, 4e9]);
    assert_eq!(raw.opacity, vec![-0.25, -1.25]);
    assert_eq!(raw.log_scale[0], [-1.0, -2.0, -3.0]);
    assert_eq!(raw.rotation[1], [0.5, 0.25, 0.125, -1.0]);
    let expect_rest: Vec<f32> =
        (0..2).flat_map(|g| (0..9).map(move |k| k as f32 + 10.0 * g as f32)).collect();
    assert_eq!(raw.f_rest, expect_rest);
}

#[test]
fn trailing_bytes_and_empty_vertex_elements_are_accepted() {
    let mut bytes = standard_bytes(&bench_splats(3, 0));
    bytes.extend_from_slice(b"trailing junk");
    assert_eq!(parse_raw(&bytes, p()).unwrap().len(), 3);
    let empty = parse_raw(&standard_bytes(&bench_splats(0, 3)), p()).unwrap();
    assert!(empty.is_empty());
    assert_eq!(empty.sh_degree, 3);
}

const SH_C0: f64 = 0.282_094_791_773_878_14;

fn close(a: f32, b: f64, tol: f64) -> bool {
    (a as f64 - b).abs() <= tol
}

#[test]
fn compressed_fields_decode_to_chunk_bounds() {
    let chunk = vec![
        -1.0, -2.0, -3.0, 1.0, 2.0, 5.0, -6.0, -5.0, -4.0, -2.0, -1.0, 0.0, 0.0, 0.2, 0.4, 1.0, 0.6, 0.4,
    ];
    let v = [
        // x at max, y at min, z at 1023/2047 (just below the middle).
        pack_111011(2047, 0, 1023),
        // Largest component rot_2; rot_0 = +1/sqrt(2) (full scale), rot_1 = rot_3 = (511/1023 - 0.5) * sqrt(2).
        pack_rot(2, 1023, 511, 511),
        pack_111011(0, 1023, 2047),
        // r full, g zero, b middle-ish, alpha 255 (opaque -> +inf logit).
        pack_rgba(255, 0, 51, 255),
    ];
    let w = [0, 0, 0, pack_rgba(0, 0, 0, 0)];
    let x = [0, 0, 0, pack_rgba(0, 0, 0, 51)];
    let raw = parse_raw(&compressed(&[chunk], true, &[v, w, x], None), p()).unwrap();
    assert_eq!(raw.len(), 3);
    assert_eq!(raw.sh_degree, 0);
    assert!(close(raw.position[0][0], 1.0, 1e-7));
    assert!(close(raw.position[0][1], -2.0, 1e-7));
    assert!(close(raw.position[0][2], -3.0 + 8.0 * 1023.0 / 2047.0, 1e-6));
    assert_eq!(raw.log_scale[0], [-6.0, -1.0, 0.0]);
    let small = (511.0 / 1023.0 - 0.5) * 2f64.sqrt();
    assert!(close(raw.rotation[0][0], std::f64::consts::FRAC_1_SQRT_2, 1e-6), "{:?}", raw.rotation[0]);
    assert!(close(raw.rotation[0][1], small, 1e-6) && close(raw.rotation[0][3], small, 1e-6));
    assert!(close(raw.rotation[0][2], (0.5 - 2.0 * small * small).sqrt(), 1e-6));
    // Colour lerps between the chunk's colour bounds, then f_dc = (c - 0.5) / SH_C0.
    assert!(close(raw.f_dc[0][0], 0.5 / SH_C0, 1e-6));
    assert!(close(raw.f_dc[0][1], (0.2 - 0.5) / SH_C0, 1e-6));
    assert!(close(raw.f_dc[0][2], (0.4 - 0.5) / SH_C0, 1e-6)); // min_b == max_b
    assert_eq!(raw.opacity[0], f32::INFINITY);
    assert_eq!(raw.opacity[1], f32::NEG_INFINITY);
    // alpha 51/255 = 0.2: logit = ln(0.2 / 0.8).
    assert!(close(raw.opacity[2], (0.25f64).ln(), 1e-6));
}

#[test]
fn compressed_without_colour_bounds_uses_plain_colour() {
    let chunk = vec![0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0];
    let v = [0, pack_rot(0, 511, 511, 511), 0, pack_rgba(255, 0, 102, 128)];
    let raw = parse_raw(&compressed(&[chunk], false, &[v], None), p()).unwrap();
    assert!(close(raw.f_dc[0][0], 0.5 / SH_C0, 1e-6));
    assert!(close(raw.f_dc[0][1], -0.5 / SH_C0, 1e-6));
    assert!(close(raw.f_dc[0][2], (0.4 - 0.5) / SH_C0, 1e-6));
    assert!(close(raw.opacity[0], (128.0f64 / 127.0).ln(), 1e-6));
    assert!(close(raw.rotation[0][0], 1.0, 1e-5));
}

#[test]
fn compressed_sh_bytes_become_f_rest_in_order() {
    let bytes = small_compressed();
    let raw = parse_raw(&bytes, p()).unwrap();
    assert_eq!(raw.len(), 300);
    assert_eq!(raw.sh_degree, 1);
    assert_eq!(raw.f_rest.len(), 300 * 9);
    for (i, &v) in raw.f_rest.iter().enumerate() {
        let b = (i * 37 % 256) as f64;
        let want = match b as u32 {
            0 => -4.0,
            255 => 4.0,
            _ => ((b + 0.5) / 256.0 - 0.5) * 8.0,
        };
        assert!(close(v, want, 1e-6), "f_rest[{i}] = {v}, want {want}");
    }
    // The second chunk (vertices 256..) uses its own bounds: max_z is 4 there, 3 in chunk 0.
    let z_max = |range: std::ops::Range<usize>| range.map(|i| raw.position[i][2]).fold(f32::MIN, f32::max);
    assert!(z_max(0..256) <= 3.0 && z_max(256..300) > 3.0);
}
