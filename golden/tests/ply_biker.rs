//! Decoding the real `biker.compressed.ply` agrees with the third-party converter's decode
//! (`biker.ply`, by `@playcanvas/splat-transform` 2.7.1) for every Gaussian and property.

use neo_golden::ply::read_raw;
use neo_golden::scene::RawSplats;
use neo_golden::shared::shared_file_for_test;

/// Relative tolerance. Both decoders evaluate the same formulas in `f64` and round to `f32`, so
/// they can differ only where the platform `ln`/`sqrt` differ in the last `f64` bit and that
/// survives rounding to `f32`: at most 1 `f32` ulp (2^-23 ~ 1.2e-7 relative). 1e-5 leaves margin
/// while still catching any formula change (e.g. a divisor of 2048 instead of 2047 moves values by
/// ~5e-4 relative). No absolute floor is needed: values equal to 0 must then match exactly.
const REL: f32 = 1e-5;

/// `a` and `b` agree: identical (including equal infinities), or both finite with
/// `|a - b| <= REL * max(|a|, |b|)`. Returns the relative error (0 when identical).
fn agree(a: f32, b: f32) -> Option<f32> {
    if a == b {
        return Some(0.0);
    }
    if !a.is_finite() || !b.is_finite() {
        return None;
    }
    let diff = (a - b).abs();
    let scale = a.abs().max(b.abs());
    (diff <= REL * scale).then_some(diff / scale)
}

/// Every property of one Gaussian, in a fixed order with its name.
fn props(r: &RawSplats, i: usize) -> Vec<(&'static str, f32)> {
    let mut v = Vec::new();
    for (k, name) in ["x", "y", "z"].into_iter().enumerate() {
        v.push((name, r.position[i][k]));
    }
    for (k, name) in ["f_dc_0", "f_dc_1", "f_dc_2"].into_iter().enumerate() {
        v.push((name, r.f_dc[i][k]));
    }
    v.push(("opacity", r.opacity[i]));
    for (k, name) in ["scale_0", "scale_1", "scale_2"].into_iter().enumerate() {
        v.push((name, r.log_scale[i][k]));
    }
    for (k, name) in ["rot_0", "rot_1", "rot_2", "rot_3"].into_iter().enumerate() {
        v.push((name, r.rotation[i][k]));
    }
    v
}

#[test]
fn compressed_biker_matches_converter_decode() {
    let Some(compressed) = shared_file_for_test("ply_biker", "scenes/biker.compressed.ply") else { return };
    let Some(standard) = shared_file_for_test("ply_biker", "scenes/biker.ply") else { return };
    let ours = read_raw(&compressed).unwrap();
    let theirs = read_raw(&standard).unwrap();
    assert_eq!(ours.len(), 152_746);
    assert_eq!(theirs.len(), 152_746);
    assert_eq!((ours.sh_degree, theirs.sh_degree), (0, 0));
    assert!(ours.f_rest.is_empty() && theirs.f_rest.is_empty());
    // Alpha byte 255 gives logit +inf (fully opaque); the README counts 198 such Gaussians.
    let infinite = ours.opacity.iter().filter(|o| o.is_infinite()).count();
    assert_eq!(infinite, 198);
    assert!(ours.opacity.iter().filter(|o| o.is_infinite()).all(|&o| o == f32::INFINITY));
    let (mut max_rel, mut max_abs, mut exact) = (0.0f32, 0.0f32, 0usize);
    let mut total = 0usize;
    for i in 0..ours.len() {
        for ((name, a), (_, b)) in props(&ours, i).into_iter().zip(props(&theirs, i)) {
            let rel =
                agree(a, b).unwrap_or_else(|| panic!("Gaussian {i} {name}: ours {a:e}, converter {b:e}"));
            if a == b {
                exact += 1;
            } else {
                max_abs = max_abs.max((a - b).abs());
            }
            max_rel = max_rel.max(rel);
            total += 1;
        }
    }
    // Same formulas in the same precision: nearly everything should be bit-identical.
    assert!(exact * 1000 >= total * 999, "only {exact} of {total} values bit-identical");
    println!("biker decode vs converter: {exact}/{total} values bit-identical, max rel {max_rel:e}, max abs {max_abs:e}");
}
