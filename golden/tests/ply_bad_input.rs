//! Bad PLY input gives an error naming the file and the problem, never a panic.

mod ply_common;

use neo_golden::ply::{bench_splats, parse_raw, read_raw, standard_bytes};
use ply_common::*;
use proptest::prelude::*;
use std::path::Path;

const NAME: &str = "bad_case.ply";

/// A valid standard file: 5 Gaussians, SH degree 1, so 26 floats = 104 bytes per vertex.
fn valid_standard() -> Vec<u8> {
    standard_bytes(&bench_splats(5, 1))
}

/// Length of the header (offset of the first data byte).
fn header_len(bytes: &[u8]) -> usize {
    bytes.windows(11).position(|w| w == b"end_header\n").map_or(bytes.len(), |p| p + 11)
}

/// `bytes` with the first occurrence of `from` in the header replaced by `to`.
fn edit(bytes: &[u8], from: &str, to: &str) -> Vec<u8> {
    let h = header_len(bytes);
    let header = std::str::from_utf8(&bytes[..h]).unwrap();
    assert!(header.contains(from), "test bug: '{from}' not in header");
    let mut out = header.replacen(from, to, 1).into_bytes();
    out.extend_from_slice(&bytes[h..]);
    out
}

/// Asserts that parsing fails with `NAME: ...` mentioning every phrase.
fn fails_with(bytes: &[u8], phrases: &[&str]) {
    let e = match parse_raw(bytes, Path::new(NAME)) {
        Ok(r) => panic!("expected an error containing {phrases:?}, got {} Gaussians", r.len()),
        Err(e) => e.to_string(),
    };
    assert!(e.starts_with(&format!("{NAME}: ")), "{e}");
    for p in phrases {
        assert!(e.contains(p), "error '{e}' lacks '{p}'");
    }
}

#[test]
fn valid_inputs_parse() {
    assert_eq!(parse_raw(&valid_standard(), Path::new(NAME)).unwrap().len(), 5);
    assert_eq!(parse_raw(&small_compressed(), Path::new(NAME)).unwrap().len(), 300);
}

#[test]
fn not_a_ply() {
    fails_with(b"", &["not a PLY"]);
    fails_with(b"\x89PNG\r\n\x1a\n", &["not a PLY"]);
    fails_with(b"plyx\n", &["not a PLY"]);
}

#[test]
fn unsupported_formats() {
    let v = valid_standard();
    fails_with(&edit(&v, "binary_little_endian", "ascii"), &["ascii", "not supported"]);
    fails_with(
        &edit(&v, "binary_little_endian", "binary_big_endian"),
        &["binary_big_endian", "not supported"],
    );
    fails_with(&edit(&v, "binary_little_endian", "binary_middle_endian"), &["unknown PLY format"]);
}

#[test]
fn truncated_header() {
    let v = valid_standard();
    fails_with(&v[..header_len(&v) - 1], &["truncated header"]);
    fails_with(&v[..40], &["truncated header"]);
    fails_with(b"ply\n", &["truncated header"]);
}

#[test]
fn truncated_data_says_what_is_missing() {
    let v = valid_standard();
    fails_with(&v[..v.len() - 10], &["truncated data", "'vertex'", "10 bytes missing", "only 4 entries fit"]);
    fails_with(&v[..header_len(&v)], &["truncated data", "520 bytes missing", "only 0 entries fit"]);
}

#[test]
fn vertex_count_larger_than_data() {
    // 9 vertices need 936 bytes; 520 are present.
    let v = edit(&valid_standard(), "element vertex 5", "element vertex 9");
    fails_with(&v, &["truncated data", "declares 9 entries", "416 bytes missing", "only 5 entries fit"]);
    let huge = edit(&valid_standard(), "element vertex 5", "element vertex 18446744073709551615");
    fails_with(&huge, &["truncated data", "only 5 entries fit"]);
    fails_with(&edit(&valid_standard(), "element vertex 5", "element vertex 5e3"), &["bad element count"]);
}

#[test]
fn missing_required_property_is_named() {
    let v = valid_standard();
    fails_with(
        &edit(&v, "property float rot_3", "property float rot_x"),
        &["missing required property 'rot_3'"],
    );
    fails_with(
        &edit(&v, "property float opacity", "property float alpha"),
        &["missing required property 'opacity'"],
    );
    fails_with(&edit(&v, "element vertex", "element point"), &["no 'vertex' element"]);
}

#[test]
fn unknown_property_type() {
    let v = valid_standard();
    fails_with(
        &edit(&v, "property float scale_1", "property half scale_1"),
        &["unknown property type 'half'", "scale_1"],
    );
}

#[test]
fn bad_f_rest_count() {
    let v = valid_standard();
    fails_with(
        &edit(&v, "property float f_rest_8", "property float g_rest_8"),
        &["bad f_rest count", "8 f_rest"],
    );
    // Nine of them, but not f_rest_0..8.
    fails_with(
        &edit(&v, "property float f_rest_8", "property float f_rest_9"),
        &["missing required property 'f_rest_8'"],
    );
}

#[test]
fn list_property_in_vertex_and_duplicates() {
    let body = "element vertex 1\nproperty list uchar float x\n";
    fails_with(&ply(body, &[0]), &["list property 'x'", "not supported"]);
    let v = valid_standard();
    fails_with(&edit(&v, "property float nx", "property float x"), &["duplicate property 'x'"]);
    fails_with(&edit(&v, "property float x", "proprety float x"), &["unknown keyword 'proprety'"]);
    fails_with(
        &edit(&v, "element vertex 5\n", "property float q\nelement vertex 5\n"),
        &["property before any element"],
    );
}

#[test]
fn list_element_before_vertices_is_walked_and_truncation_reported() {
    let v = valid_standard();
    let h = header_len(&v);
    let mut with_faces = edit(
        &v[..h],
        "element vertex 5\n",
        "element face 2\nproperty list uchar int idx\nelement vertex 5\n",
    );
    with_faces.extend_from_slice(&[1, 0, 0, 0, 0, 2, 0, 0, 0, 0, 0, 0, 0, 0]);
    with_faces.extend_from_slice(&v[h..]);
    assert_eq!(parse_raw(&with_faces, Path::new(NAME)).unwrap().len(), 5);
    let cut = header_len(&with_faces) + 8;
    fails_with(&with_faces[..cut], &["truncated data", "'face'", "entry 1"]);
}

#[test]
fn compressed_errors() {
    let c = small_compressed();
    fails_with(&edit(&c, "element chunk 2", "element chunk 1"), &["1 chunks", "300 vertices need 2"]);
    fails_with(
        &edit(&c, "property uint packed_scale", "property uint packed_scal"),
        &["missing required property 'packed_scale'"],
    );
    fails_with(
        &edit(&c, "property float max_scale_y", "property float max_scale_q"),
        &["missing required property 'max_scale_y'"],
    );
    fails_with(
        &edit(&c, "property float max_g", "property float max_q"),
        &["some but not all", "colour bounds"],
    );
    fails_with(
        &edit(&c, "property uint packed_color", "property float packed_color"),
        &["'packed_color'", "uint"],
    );
    fails_with(
        &edit(&c, "property uchar f_rest_8", "property uchar f_rest_9"),
        &["missing required property 'f_rest_8'"],
    );
    fails_with(
        &edit(&c, "property uchar f_rest_8", "property char f_rest_8"),
        &["'f_rest_8' must be 'uchar'"],
    );
    fails_with(
        &edit(&c, "element sh 300", "element sh 299"),
        &["'sh' element has 299 entries", "300 vertices"],
    );
    fails_with(&c[..c.len() - 5], &["truncated data", "'sh'", "5 bytes missing"]);
    let h = header_len(&c);
    fails_with(&c[..h + 100], &["truncated data", "'chunk'"]);
}

#[test]
fn missing_file_is_named() {
    let e = read_raw(Path::new("/nonexistent/dir/no_such.ply")).unwrap_err().to_string();
    assert!(e.starts_with("/nonexistent/dir/no_such.ply: cannot read file"), "{e}");
}

/// Parses without caring about the outcome; a panic fails the property test.
fn no_panic(bytes: &[u8]) {
    let _ = parse_raw(bytes, Path::new(NAME));
}

/// Header lines a mutation may substitute.
fn header_line() -> impl Strategy<Value = String> {
    prop_oneof![
        any::<u64>().prop_map(|n| format!("element vertex {n}")),
        (0u64..400).prop_map(|n| format!("element vertex {n}")),
        (0u64..4).prop_map(|n| format!("element chunk {n}")),
        (0u64..400).prop_map(|n| format!("element sh {n}")),
        (0usize..12).prop_map(|t| format!(
            "property {} x",
            [
                "char",
                "uchar",
                "short",
                "ushort",
                "int",
                "uint",
                "float",
                "double",
                "list uchar int",
                "list float int",
                "int64",
                ""
            ][t]
        )),
        "[a-z_ 0-9]{0,30}",
        Just("end_header".to_string()),
        Just("format ascii 1.0".to_string()),
    ]
}

/// Replaces header line `index` (modulo the line count) of `bytes` with `line`.
fn replace_header_line(bytes: &[u8], index: usize, line: &str) -> Vec<u8> {
    let h = header_len(bytes);
    let header = String::from_utf8_lossy(&bytes[..h]).to_string();
    let mut lines: Vec<&str> = header.lines().collect();
    let i = index % lines.len();
    lines[i] = line;
    let mut out = (lines.join("\n") + "\n").into_bytes();
    out.extend_from_slice(&bytes[h..]);
    out
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 4000, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn random_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..600), prefix in any::<bool>()) {
        let mut data = if prefix { b"ply\nformat binary_little_endian 1.0\n".to_vec() } else { Vec::new() };
        data.extend_from_slice(&bytes);
        no_panic(&data);
    }

    #[test]
    fn truncations_never_panic(cut in any::<prop::sample::Index>(), compressed in any::<bool>()) {
        let v = if compressed { small_compressed() } else { valid_standard() };
        let at = cut.index(v.len() + 1);
        no_panic(&v[..at]);
        if at < v.len() {
            prop_assert!(parse_raw(&v[..at], Path::new(NAME)).is_err());
        }
    }

    #[test]
    fn byte_flips_never_panic(
        flips in proptest::collection::vec((any::<prop::sample::Index>(), any::<u8>()), 1..8),
        header_only in any::<bool>(),
        compressed in any::<bool>(),
    ) {
        let mut v = if compressed { small_compressed() } else { valid_standard() };
        let span = if header_only { header_len(&v) } else { v.len() };
        for (i, b) in flips {
            let at = i.index(span);
            v[at] ^= b;
        }
        no_panic(&v);
    }

    #[test]
    fn header_line_edits_never_panic(index in 0usize..64, line in header_line(), compressed in any::<bool>()) {
        let v = if compressed { small_compressed() } else { valid_standard() };
        no_panic(&replace_header_line(&v, index, &line));
    }
}
