//! The Preprocessing Engine's arithmetic (golden/src/hwpre) against the float preprocessing:
//! on random and hard-case Gaussians it never panics, culls as the reference does, reproduces
//! its mean, conic, depth, radius and tile rectangle, quantises mean, conic, opacity, colour and
//! depth key exactly as the f64 quantiser, points the ITU axis along the f64 major axis, and
//! keeps every ITU extent conservative against the exact ellipse.
//!
//! Tolerances: x/y extents at most `1e-5` relative plus one LSB above the f64 quantiser's (the
//! hardware rounds `k2` up to f32 and adds a `2^-20` margin); the axis within one LSB of the
//! f64 one (up to sign) where the covariance is anisotropic; colour within one LSB with f16 SH.

use glam::{DVec3, Vec3};
use neo_golden::camera::{look_at_rotation, Camera};
use neo_golden::formats::{quantize, FeatureEntry, FeatureFormat};
use neo_golden::hwpre::bake::bake_k2;
use neo_golden::hwpre::project::ProjectParams;
use neo_golden::hwpre::{camera_registers, preprocess_one, Baked, HwProjected, ShPrecision};
use neo_golden::render::{project_one, Projected, ViewParams};
use neo_golden::scene::{sh_coeffs, Scene};
use neo_golden::sort::DepthKeyCodec;
use proptest::prelude::*;

const TILE: u32 = 64;

fn camera(pos: [f64; 3], target: [f64; 3], w: u32, h: u32, f: f64) -> Camera {
    let (p, t) = (DVec3::from(pos), DVec3::from(target));
    Camera {
        name: "c".into(),
        width: w,
        height: h,
        fx: f,
        fy: f,
        position: p,
        cam_to_world: look_at_rotation(p, t, DVec3::NEG_Y),
    }
}

/// One Gaussian.
#[derive(Clone, Debug)]
struct G {
    pos: [f32; 3],
    scale: [f32; 3],
    rot: [f32; 4],
    opacity: f32,
}

fn scene(gs: &[G], degree: u8, sh_seed: u32) -> Scene {
    let mut s = Scene { sh_degree: degree, ..Scene::default() };
    for g in gs {
        s.positions.push(g.pos);
        s.scales.push(g.scale);
        let q = Vec3::new(g.rot[1], g.rot[2], g.rot[3]);
        let n = (g.rot[0] * g.rot[0] + q.length_squared()).sqrt();
        s.rotations.push(if n > 0.0 { g.rot.map(|v| v / n) } else { [1.0, 0.0, 0.0, 0.0] });
        s.opacities.push(g.opacity);
    }
    let per = 3 * sh_coeffs(degree);
    s.sh = (0..gs.len() * per)
        .map(|k| {
            let x = (k as u32).wrapping_mul(2_654_435_761).wrapping_add(sh_seed);
            (x % 2001) as f32 / 1000.0 - 1.0
        })
        .collect();
    s
}

/// The exact (f64) support of `p`'s cutoff ellipse along `n`, seen from the quantised mean.
fn exact_support(p: &Projected, e: &FeatureEntry, fmt: &FeatureFormat, n: [f64; 2]) -> f64 {
    let o = (p.opacity as f64).max(fmt.opacity.dequantize(fmt.opacity.quantize(p.opacity as f64)));
    let k2 = fmt.cutoff.radius_squared(o);
    let [sxx, sxy, syy] = p.cov2d.map(f64::from);
    let var = n[0] * n[0] * sxx + 2.0 * n[0] * n[1] * sxy + n[1] * n[1] * syy;
    let m = e.mean_px(fmt);
    let dm = [p.mean2d[0] as f64 - m[0], p.mean2d[1] as f64 - m[1]];
    (k2 * var.max(0.0)).sqrt() + (dm[0] * n[0] + dm[1] * n[1]).abs()
}

/// Compares the hardware and float preprocessing of every Gaussian of `s` from `cam`.
fn compare(s: &Scene, cam: &Camera, sh: ShPrecision) -> Result<usize, TestCaseError> {
    let fmt = FeatureFormat::default();
    let key = DepthKeyCodec::Fp16;
    let baked = Baked::from_scene(s, &fmt, sh);
    let (regs, cam_pos) = camera_registers(cam, TILE);
    let params = ProjectParams { feature: fmt, tile: TILE };
    let view = ViewParams::new(cam, TILE);
    let mut visible = 0;
    for i in 0..s.len() {
        let hw = preprocess_one(&baked, &regs, cam_pos, &params, &key, i);
        let fl = project_one(s, &view, i);
        prop_assert_eq!(hw.is_some(), fl.is_some(), "culling differs for {}", i);
        let (Some(HwProjected { projected: h, entry: e }), Some(f)) = (hw, fl) else { continue };
        visible += 1;
        prop_assert!(h.mean2d == f.mean2d && h.conic == f.conic && h.cov2d == f.cov2d, "{:?} {:?}", h, f);
        prop_assert_eq!(
            (h.depth, h.radius, h.tile_min, h.tile_max),
            (f.depth, f.radius, f.tile_min, f.tile_max)
        );
        let q = quantize(&f, &fmt, &key);
        prop_assert_eq!((e.mean, e.conic, e.opacity, e.depth_key), (q.mean, q.conic, q.opacity, q.depth_key));
        match sh {
            ShPrecision::F32 => prop_assert_eq!(e.rgb, q.rgb),
            ShPrecision::F16 => {
                for c in 0..3 {
                    prop_assert!(
                        (e.rgb[c] - q.rgb[c]).abs() <= 1 + q.rgb[c] / 256,
                        "{:?} {:?}",
                        e.rgb,
                        q.rgb
                    );
                }
            }
        }
        // Conservative extents.
        let unb = fmt.unbounded_extent();
        let ext = |raw: i32| raw as f64 * fmt.extent.lsb();
        for (k, n) in [[1.0, 0.0], [0.0, 1.0]].into_iter().enumerate() {
            if e.extent_xy[k] < unb {
                prop_assert!(ext(e.extent_xy[k]) >= exact_support(&f, &e, &fmt, n), "xy {} {:?}", k, e);
            }
            prop_assert!(
                e.extent_xy[k] as f64 <= q.extent_xy[k] as f64 * (1.0 + 1e-5) + 1.0,
                "xy {} too loose: {} vs {}",
                k,
                e.extent_xy[k],
                q.extent_xy[k]
            );
        }
        let [c, sn] = e.axis.map(f64::from);
        let axis_scale = fmt.axis.lsb();
        for (k, n) in [[c, sn], [-sn, c]].into_iter().enumerate() {
            if e.extent_uv[k] < unb {
                let want = exact_support(&f, &e, &fmt, n) * axis_scale;
                prop_assert!(ext(e.extent_uv[k]) >= want, "uv {} {:?} {}", k, e, want);
            }
        }
        // The axis: the f64 quantiser's, up to sign, where the direction is defined.
        let [sxx, sxy, syy] = f.cov2d.map(f64::from);
        let aniso = (sxx - syy).hypot(2.0 * sxy) / (sxx + syy);
        if aniso > 1e-2 && aniso.is_finite() {
            let d = |x: [i32; 2], y: [i32; 2]| (x[0] - y[0]).abs().max((x[1] - y[1]).abs());
            let dist = d(e.axis, q.axis).min(d(e.axis.map(|v| -v), q.axis));
            prop_assert!(dist <= 1, "axis {:?} vs {:?} (cov {:?})", e.axis, q.axis, f.cov2d);
        }
    }
    Ok(visible)
}

fn arb_gaussian() -> impl Strategy<Value = G> {
    (
        prop::array::uniform3(-30.0f32..30.0),
        prop::array::uniform3(-9.0f32..4.0),
        prop::array::uniform4(-1.0f32..1.0),
        prop_oneof![Just(0.0f32), Just(1.0f32), 0.0f32..1.0],
    )
        .prop_map(|(pos, ls, rot, opacity)| G { pos, scale: ls.map(f32::exp), rot, opacity })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    #[test]
    fn agrees_with_the_float_preprocessing(
        gs in prop::collection::vec(arb_gaussian(), 1..40),
        cam_pos in prop::array::uniform3(-10.0f64..10.0),
        target in prop::array::uniform3(-10.0f64..10.0),
        degree in 0u8..=3,
        f16 in any::<bool>(),
        res in prop::sample::select(vec![(64u32, 48u32), (640, 480), (333, 97)]),
    ) {
        prop_assume!((DVec3::from(cam_pos) - DVec3::from(target)).length() > 0.1);
        let s = scene(&gs, degree, 7);
        let cam = camera(cam_pos, target, res.0, res.1, res.0 as f64 * 0.8);
        compare(&s, &cam, if f16 { ShPrecision::F16 } else { ShPrecision::F32 })?;
    }

    #[test]
    fn never_panics_on_any_bits(
        bits in prop::collection::vec(any::<u32>(), 12),
        degree in 0u8..=3,
    ) {
        let fmt = FeatureFormat::default();
        let v: Vec<f32> = bits.iter().map(|&b| f32::from_bits(b)).collect();
        let mut baked = Baked::from_scene(&scene(&[], degree, 0), &fmt, ShPrecision::F16);
        baked.geometry.push(neo_golden::hwpre::bake::BakedGeometry {
            position: [v[0], v[1], v[2]],
            cov3d: [v[3], v[4], v[5], v[6], v[7], v[8]],
            opacity: v[9],
            k2: v[10],
        });
        baked.sh = (0..3 * sh_coeffs(degree) as u32).map(|k| bits[11].rotate_left(k) & 0xFFFF).collect();
        let cam = camera([0.0; 3], [0.0, 0.0, 1.0], 640, 480, 500.0);
        let (regs, cam_pos) = camera_registers(&cam, TILE);
        let params = ProjectParams { feature: fmt, tile: TILE };
        let _ = preprocess_one(&baked, &regs, cam_pos, &params, &DepthKeyCodec::Fp16, 0);
    }
}

/// A camera at the origin looking along +z, 640 x 480, f = 500 px.
fn forward() -> Camera {
    camera([0.0; 3], [0.0, 0.0, 1.0], 640, 480, 500.0)
}

fn one(pos: [f32; 3], scale: [f32; 3], opacity: f32) -> G {
    G { pos, scale, rot: [0.9, 0.1, -0.3, 0.2], opacity }
}

fn check(gs: &[G], degree: u8) -> usize {
    let mut n = 0;
    for sh in [ShPrecision::F32, ShPrecision::F16] {
        n = compare(&scene(gs, degree, 3), &forward(), sh).unwrap_or_else(|e| panic!("{e}"));
    }
    n
}

#[test]
fn behind_the_camera_and_on_the_near_plane_are_culled() {
    assert_eq!(check(&[one([0.0, 0.0, -5.0], [0.1; 3], 0.9)], 3), 0);
    assert_eq!(check(&[one([0.0, 0.0, 0.2], [0.1; 3], 0.9)], 3), 0);
    assert_eq!(check(&[one([0.0, 0.0, 0.2f32.next_up()], [0.01; 3], 0.9)], 3), 1);
}

#[test]
fn exactly_on_a_tile_border() {
    // Pixel x = 64 (a tile border) is at view x = (64 - 319.5) z / f.
    let z = 10.0f32;
    let x = (64.0 - 319.5) * z / 500.0;
    let y = (128.0 - 239.5) * z / 500.0;
    let n = check(&[one([x, y, z], [0.001; 3], 0.5), one([x, y, z], [0.05; 3], 0.5)], 1);
    assert_eq!(n, 2);
}

#[test]
fn huge_tiny_and_degenerate_scales() {
    let gs = [
        one([0.0, 0.0, 5.0], [1e3; 3], 0.5),
        one([0.0, 0.0, 5.0], [1e-7; 3], 0.5),
        one([1.0, 0.0, 5.0], [1e-7, 1e-7, 2.0], 0.5),
        one([1.0, 1.0, 5.0], [3.0, 1e-6, 3.0], 0.5),
        one([0.0, 0.0, 1e5], [1.0; 3], 0.5),
        one([3e4, 0.0, 1.0], [1.0; 3], 0.5),
    ];
    check(&gs, 2);
}

#[test]
fn zero_opacity_and_every_sh_degree() {
    for d in 0..=3 {
        let n = check(&[one([0.5, 0.2, 4.0], [0.1; 3], 0.0), one([-0.5, 0.2, 4.0], [0.1; 3], 1.0)], d);
        assert_eq!(n, 2, "degree {d}");
    }
    let fmt = FeatureFormat::default();
    assert_eq!(bake_k2(0.0, &fmt), 0.0);
}

#[test]
fn largest_coordinates_do_not_panic() {
    let m = f32::MAX;
    let gs =
        [one([m, m, m], [1.0; 3], 0.5), one([0.0, 0.0, m], [m; 3], 0.5), one([-m, 0.0, 1.0], [1.0; 3], 1.0)];
    check(&gs, 3);
}
