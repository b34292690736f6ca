//! Synthetic scenes: determinism, exact counts, valid values, trained-scene-like statistics,
//! spec errors, and loading through `source`.

use neo_golden::scene::{sh_coeffs, Scene};
use neo_golden::shared::shared_file_for_test;
use neo_golden::source::{load_scene, percentile, robust_bounds};
use neo_golden::synthetic::{generate, parse_spec, SceneKind, SyntheticSpec, DEFAULT_SCENE};
use proptest::prelude::*;

fn scene(spec: &str) -> Scene {
    generate(&parse_spec(spec).unwrap())
}

#[test]
fn same_seed_same_scene_other_seed_other_scene() {
    for name in ["outdoor", "blobs"] {
        let a = scene(&format!("synthetic:{name}?gaussians=5k&seed=3"));
        let b = scene(&format!("synthetic:{name}?gaussians=5k&seed=3"));
        let c = scene(&format!("synthetic:{name}?gaussians=5k&seed=4"));
        assert_eq!(a, b, "{name}");
        assert_ne!(a.positions, c.positions, "{name}");
        assert_ne!(a.sh, c.sh, "{name}");
    }
}

#[test]
fn generation_does_not_depend_on_thread_count() {
    let spec = parse_spec("synthetic:outdoor?gaussians=20k&seed=11&sh=2").unwrap();
    let one = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap().install(|| generate(&spec));
    let three = rayon::ThreadPoolBuilder::new().num_threads(3).build().unwrap().install(|| generate(&spec));
    assert_eq!(one, three);
}

#[test]
fn a_prefix_of_a_larger_scene_is_not_a_different_scene() {
    // Gaussian i depends on (seed, i) and the layout; the count only changes sizes and density.
    let small = scene("synthetic:blobs?gaussians=100&seed=5&sh=0");
    let large = scene("synthetic:blobs?gaussians=1000&seed=5&sh=0");
    assert_eq!(small.positions[..], large.positions[..100]);
    assert_ne!(small.scales[..], large.scales[..100]);
}

#[test]
fn counts_are_exact_and_values_valid() {
    for (spec, n, sh) in [
        ("synthetic:outdoor?gaussians=1", 1, 3),
        ("synthetic:outdoor?gaussians=4097&sh=0", 4097, 0),
        ("synthetic:outdoor?gaussians=10k&sh=1", 10_000, 1),
        ("synthetic:blobs?gaussians=8191&sh=2", 8191, 2),
        ("synthetic:blobs", 1000, 3),
    ] {
        let s = scene(spec);
        assert_eq!(s.len(), n, "{spec}");
        assert_eq!(s.sh_degree, sh);
        assert_eq!((s.scales.len(), s.rotations.len(), s.opacities.len()), (n, n, n));
        assert_eq!(s.sh.len(), n * 3 * sh_coeffs(sh));
        assert!(s.positions.iter().flatten().all(|v| v.is_finite()), "{spec}");
        assert!(s.scales.iter().flatten().all(|v| v.is_finite() && *v > 0.0), "{spec}");
        assert!(s.sh.iter().all(|v| v.is_finite()), "{spec}");
        assert!(s.opacities.iter().all(|o| (0.0..=1.0).contains(o)), "{spec}");
        for q in &s.rotations {
            let n2: f32 = q.iter().map(|v| v * v).sum();
            assert!((n2 - 1.0).abs() < 1e-5 && q[0] >= 0.0, "{q:?}");
        }
        // The scene survives the file parameterisation (log scale, logit) unchanged in size.
        let raw = s.to_raw();
        assert_eq!(raw.len(), n);
        assert!(raw.log_scale.iter().flatten().all(|v| v.is_finite()));
    }
}

#[test]
fn outdoor_statistics_resemble_a_trained_scene() {
    let s = scene("synthetic:outdoor?gaussians=100k&seed=2");
    let n = s.len() as f64;
    assert!(s
        .sh
        .iter()
        .chain(s.positions.iter().flatten())
        .chain(s.scales.iter().flatten())
        .all(|v| v.is_finite()));
    // Anisotropy max/min: biker.ply has median 18.7, 10th/90th percentiles 5.1 and 75.
    let aniso: Vec<f32> = s
        .scales
        .iter()
        .map(|v| v.iter().fold(0f32, |m, x| m.max(*x)) / v.iter().fold(f32::MAX, |m, x| m.min(*x)))
        .collect();
    let med = percentile(aniso.clone(), 0.5);
    assert!((12.0..28.0).contains(&med), "median anisotropy {med}");
    assert!((2.5..8.0).contains(&percentile(aniso.clone(), 0.1)));
    assert!((45.0..120.0).contains(&percentile(aniso, 0.9)));
    // Opacity: many near-transparent and many near-opaque (biker: 34% < 0.1, 8% > 0.9).
    let low = s.opacities.iter().filter(|&&o| o < 0.1).count() as f64 / n;
    let high = s.opacities.iter().filter(|&&o| o > 0.9).count() as f64 / n;
    assert!((0.25..0.45).contains(&low), "{low}");
    assert!((0.05..0.2).contains(&high), "{high}");
    // Geometry: y down, ground at 0, objects above it (negative y), tens of metres across, a
    // far shell.
    let below_ground = s.positions.iter().filter(|p| p[1] > 0.2).count() as f64 / n;
    assert!(below_ground < 0.02, "{below_ground}");
    let near_ground = s.positions.iter().filter(|p| p[1].abs() < 0.1).count() as f64 / n;
    assert!((0.3..0.6).contains(&near_ground), "{near_ground}");
    let tall = s.positions.iter().filter(|p| p[1] < -2.0 && p[0].hypot(p[2]) < 40.0).count() as f64 / n;
    assert!(tall > 0.1, "{tall}");
    let far = s.positions.iter().filter(|p| p[0].hypot(p[2]).hypot(p[1]) > 200.0).count() as f64 / n;
    assert!((0.05..0.12).contains(&far), "{far}");
    let (lo, hi) = robust_bounds(&s);
    for a in [0, 2] {
        assert!(hi[a] - lo[a] > 30.0 && hi[a] - lo[a] < 80.0, "{lo:?} {hi:?}");
    }
    assert!(hi[1] < 0.2 && lo[1] < -3.0 && lo[1] > -20.0, "{lo:?} {hi:?}");
    // Scale: log-normal, centimetres to decimetres in the bulk; the sky has metre-sized ones.
    let max_scale: Vec<f32> = s.scales.iter().map(|v| v.iter().fold(0f32, |m, x| m.max(*x))).collect();
    let m = percentile(max_scale.clone(), 0.5);
    assert!((0.02..0.5).contains(&m), "{m}");
    assert!(percentile(max_scale, 0.99) > 1.0);
    // Colour: several distinct base colours (DC term), and small higher-order SH.
    let k = 3 * sh_coeffs(3);
    let rest_rms = (s.sh.chunks(k).flat_map(|g| g[3..].iter()).map(|v| v * v).sum::<f32>()
        / (s.len() * (k - 3)) as f32)
        .sqrt();
    assert!((0.02..0.1).contains(&rest_rms), "{rest_rms}");
    let greenish = s.sh.chunks(k).filter(|g| g[1] > g[0] + 0.2 && g[1] > g[2] + 0.2).count() as f64 / n;
    assert!(greenish > 0.1, "{greenish}");
}

#[test]
fn scales_shrink_as_the_count_grows() {
    let m = |spec: &str| {
        let s = scene(spec);
        percentile(s.scales.iter().map(|v| v[0].max(v[1]).max(v[2])).collect(), 0.5)
    };
    let (a, b) = (m("synthetic:outdoor?gaussians=10k&sh=0"), m("synthetic:outdoor?gaussians=160k&sh=0"));
    // Surface spacing goes as 1/sqrt(N): 16x the Gaussians, a quarter of the size.
    assert!((a / b - 4.0).abs() < 0.8, "{a} {b}");
}

#[test]
fn spec_errors_are_clear() {
    let cases = [
        ("synthetic:forest", "unknown synthetic scene 'forest'"),
        ("synthetic:outdoor?gaussians=lots", "gaussians=lots"),
        ("synthetic:outdoor?gaussians=0", "gaussians=0"),
        ("synthetic:outdoor?seed=x", "seed=x"),
        ("synthetic:outdoor?sh=4", "sh=4"),
        ("synthetic:outdoor?colour=red", "unknown key 'colour'"),
        ("synthetic:outdoor?seed", "not KEY=VALUE"),
        ("synthetic:outdoor?seed=1&seed=2", "given twice"),
        ("outdoor", "starts with 'synthetic:'"),
    ];
    for (spec, want) in cases {
        let e = parse_spec(spec).unwrap_err().to_string();
        assert!(e.starts_with(spec) && e.contains(want), "{spec} -> {e}");
    }
}

#[test]
fn default_scene_is_the_million_gaussian_outdoor_scene() {
    let d = parse_spec(DEFAULT_SCENE).unwrap();
    assert_eq!(d, SyntheticSpec { kind: SceneKind::Outdoor, gaussians: 1_000_000, seed: 1, sh_degree: 3 });
}

#[test]
fn load_scene_dispatches_on_the_spec() {
    let (s, report) = load_scene("synthetic:blobs?gaussians=300&seed=2", false).unwrap();
    assert_eq!(s.len(), 300);
    assert_eq!(report, Default::default());
    let e = load_scene("/no/such/scene.ply", false).unwrap_err().to_string();
    assert!(e.starts_with("/no/such/scene.ply"), "{e}");
    let e = load_scene("synthetic:nope", false).unwrap_err().to_string();
    assert!(e.contains("unknown synthetic scene"), "{e}");
}

#[test]
fn biker_loads_and_its_robust_bounds_hold_the_subject() {
    let Some(path) =
        shared_file_for_test("biker_loads_and_its_robust_bounds_hold_the_subject", "scenes/biker.ply")
    else {
        return;
    };
    let (s, _) = load_scene(path.to_str().unwrap(), false).unwrap();
    assert_eq!(s.len(), 152_746);
    let (lo, hi) = robust_bounds(&s);
    let (plo, phi) = s.bounds();
    for a in 0..3 {
        assert!(plo[a] <= lo[a] && lo[a] < hi[a] && hi[a] <= phi[a]);
    }
    // The subject stands along -y, about 3 units tall, about 1 unit wide.
    assert!(hi[1] > -0.1 && lo[1] < -2.5 && lo[1] > -3.3, "{lo:?} {hi:?}");
    assert!(hi[0] - lo[0] < 1.2 && hi[2] - lo[2] < 1.2);
}

proptest! {
    #[test]
    fn spec_parser_never_panics(s in "synthetic:[a-z]{0,8}(\\?[a-z=&0-9.kKmM]{0,30})?") {
        if let Err(e) = parse_spec(&s) {
            prop_assert!(e.to_string().starts_with(&s));
        }
    }

    #[test]
    fn spec_parser_never_panics_on_any_string(s in "\\PC{0,40}") {
        let _ = parse_spec(&s);
    }
}
