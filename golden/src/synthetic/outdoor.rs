//! The `outdoor` scene: a large outdoor-like capture in metres, y down, ground at y = 0.
//!
//! Composition (each Gaussian picks its part from its own hash, so counts are exact in total
//! and close to these fractions per part):
//! - 38% ground: a disc of radius [`GROUND_RADIUS`] of flat, disc-like Gaussians lying in the
//!   ground plane, denser towards the centre (as captures are), grass/dirt patches and a road;
//! - 3% far ground: the ground plane continued out to [`FAR_GROUND_RADIUS`] with ever larger,
//!   sparser Gaussians fading into the haze;
//! - 47% objects standing on the ground: a building at the centre (the subject) and about 30
//!   trees, rocks, buildings and vehicles around it, each a cluster of surface Gaussians
//!   (foliage is volumetric);
//! - 8% background shell: large, rounder Gaussians on a hemisphere [`SHELL_RADIUS`] away (sky
//!   with clouds, hills on the horizon);
//! - 4% floaters: small, mostly transparent blobs in the air, as training leaves them.

use super::rng::HashRng;
use super::splat::{
    in_volume, log_scales_with, mix, on_surface, opacity_around, oriented, randomly_oriented, splat,
    trained_opacity, vary, Splat,
};
use glam::DVec3;
use std::f64::consts::TAU;

/// Radius of the ground disc, metres.
pub const GROUND_RADIUS: f64 = 30.0;
/// Outer radius of the far ground, metres.
pub const FAR_GROUND_RADIUS: f64 = 250.0;
/// Distance of the background shell, metres.
pub const SHELL_RADIUS: f64 = 300.0;
/// Number of objects besides the central subject.
const OBJECTS: usize = 30;

const GROUND_FRACTION: f64 = 0.38;
const FAR_GROUND_FRACTION: f64 = 0.03;
const OBJECT_FRACTION: f64 = 0.47;
const SHELL_FRACTION: f64 = 0.08;
const FLOATER_FRACTION: f64 = 1.0 - GROUND_FRACTION - FAR_GROUND_FRACTION - OBJECT_FRACTION - SHELL_FRACTION;
/// Exponent `a` of the ground radius `R u^a`: area density falls off as `r^(1/a - 2)`.
const GROUND_RADIAL_EXPONENT: f64 = 0.625;
/// Lowest shell elevation, degrees (a little below the horizon).
const SHELL_MIN_ELEVATION_DEG: f64 = -5.0;
/// Floater box: |x|, |z| below this, -FLOATER_HEIGHT < y < 0.
const FLOATER_HALF_WIDTH: f64 = 25.0;
const FLOATER_HEIGHT: f64 = 12.0;

/// What an object is made of.
#[derive(Clone, Debug)]
enum Shape {
    /// Trunk (cylinder) and crown (ellipsoid of foliage).
    Tree { trunk_radius: f64, trunk_height: f64, crown: DVec3, trunk_color: [f64; 3], leaf_color: [f64; 3] },
    /// Half-buried ellipsoid.
    Rock { radii: DVec3, color: [f64; 3] },
    /// Walls with windows and a flat roof.
    Building { size: DVec3, wall: [f64; 3], roof: [f64; 3] },
    /// Lower body and cabin with windows, dark tyres at the bottom.
    Vehicle { size: DVec3, paint: [f64; 3] },
}

/// One object standing on the ground.
#[derive(Clone, Debug)]
struct Object {
    /// Footprint centre (x, z) on the ground.
    x: f64,
    z: f64,
    /// Rotation about the vertical axis, radians.
    yaw: f64,
    shape: Shape,
    /// Share of the object Gaussians (relative).
    weight: f64,
    /// Surface area in m^2 (for the spacing).
    area: f64,
}

/// The seeded layout plus what per-Gaussian sampling needs.
pub struct Outdoor {
    objects: Vec<Object>,
    /// Cumulative object weights, normalised to end at 1.
    cumulative: Vec<f64>,
    /// Expected Gaussian count of the whole scene.
    n: f64,
    /// Phases of the ground and sky colour patterns.
    phases: [f64; 8],
}

impl Outdoor {
    /// The layout for `seed`, for a scene of `n` Gaussians.
    pub fn new(seed: u64, n: usize) -> Self {
        let mut rng = HashRng::new(seed, 0x6c61_796f, 0);
        let mut objects = vec![Object {
            x: 0.0,
            z: 0.0,
            yaw: rng.range(0.0, TAU),
            shape: Shape::Building {
                size: DVec3::new(7.0, 5.5, 6.0),
                wall: [0.78, 0.7, 0.58],
                roof: [0.45, 0.2, 0.15],
            },
            weight: 0.0,
            area: 0.0,
        }];
        let mut tries = 0;
        while objects.len() < OBJECTS + 1 && tries < 10_000 {
            tries += 1;
            let r = rng.range(8.0, GROUND_RADIUS - 3.0);
            let a = rng.range(0.0, TAU);
            let (x, z) = (r * a.sin(), r * a.cos());
            let shape = random_shape(&mut rng);
            let reach = footprint_radius(&shape);
            if objects.iter().any(|o| {
                ((o.x - x).powi(2) + (o.z - z).powi(2)).sqrt() < reach + footprint_radius(&o.shape) + 1.0
            }) {
                continue;
            }
            objects.push(Object { x, z, yaw: rng.range(0.0, TAU), shape, weight: 0.0, area: 0.0 });
        }
        for (k, o) in objects.iter_mut().enumerate() {
            o.area = area(&o.shape);
            // Trained scenes spend Gaussians on detail: sub-linear in area, subject favoured.
            o.weight = o.area.powf(0.8) * if k == 0 { 3.0 } else { 1.0 };
        }
        let total: f64 = objects.iter().map(|o| o.weight).sum();
        let mut acc = 0.0;
        let cumulative = objects
            .iter()
            .map(|o| {
                acc += o.weight / total;
                acc
            })
            .collect();
        let phases = std::array::from_fn(|_| rng.range(0.0, TAU));
        Outdoor { objects, cumulative, n: n.max(1) as f64, phases }
    }

    /// One Gaussian drawn with `rng` (the caller seeds it from the scene seed and the index).
    pub fn sample(&self, rng: &mut HashRng) -> Splat {
        let mut part = rng.uniform();
        if part < GROUND_FRACTION {
            return self.ground(rng);
        }
        part -= GROUND_FRACTION;
        if part < FAR_GROUND_FRACTION {
            return self.far_ground(rng);
        }
        part -= FAR_GROUND_FRACTION;
        if part < OBJECT_FRACTION {
            let u = rng.uniform();
            let k = self.cumulative.partition_point(|&c| c <= u).min(self.objects.len() - 1);
            return self.object(k, rng);
        }
        part -= OBJECT_FRACTION;
        if part < SHELL_FRACTION {
            self.shell(rng)
        } else {
            self.floater(rng)
        }
    }

    /// A smooth pattern in [-1, 1] over the ground (two octaves of crossed sines).
    fn pattern(&self, x: f64, z: f64, k: usize) -> f64 {
        let p = &self.phases;
        0.5 * ((0.21 * x + p[k]).sin() * (0.17 * z + p[k + 1]).sin()
            + (0.53 * x - 0.31 * z + p[k + 2]).sin() * (0.47 * z + 0.29 * x + p[k + 3]).sin())
    }

    fn ground(&self, rng: &mut HashRng) -> Splat {
        let r = GROUND_RADIUS * rng.uniform().powf(GROUND_RADIAL_EXPONENT);
        let a = rng.range(0.0, TAU);
        let (x, z) = (r * a.sin(), r * a.cos());
        // Area density: n_ground * (1/a) (r/R)^(1/a - 1) / (R 2 pi r).
        let inv_a = 1.0 / GROUND_RADIAL_EXPONENT;
        let rr = r.max(0.5);
        let density = self.n * GROUND_FRACTION * inv_a * (rr / GROUND_RADIUS).powf(inv_a - 1.0)
            / (GROUND_RADIUS * TAU * rr);
        let spacing = 1.0 / density.sqrt();
        let y = 0.02 * rng.normal();
        let normal = DVec3::new(0.08 * rng.normal(), -1.0, 0.08 * rng.normal());
        let road = (x - 4.0 + 3.0 * (z * 0.05 + self.phases[6]).sin()).abs() < 2.5;
        let base = if road { [0.3, 0.3, 0.31] } else { self.ground_color(x, z) };
        splat(on_surface(rng, DVec3::new(x, y, z), normal, spacing), trained_opacity(rng), vary(rng, base))
    }

    fn shell(&self, rng: &mut HashRng) -> Splat {
        let s0 = SHELL_MIN_ELEVATION_DEG.to_radians().sin();
        let s = rng.range(s0, 1.0); // sin(elevation): uniform in area
        let az = rng.range(0.0, TAU);
        let c = (1.0 - s * s).sqrt();
        let dir = DVec3::new(c * az.sin(), -s, c * az.cos());
        let area = TAU * SHELL_RADIUS * SHELL_RADIUS * (1.0 - s0);
        let spacing = (area / (self.n * SHELL_FRACTION)).sqrt();
        let hill = (3.0 + 2.5 * (3.0 * az + self.phases[4]).sin() + 1.5 * (7.0 * az + self.phases[5]).sin())
            .to_radians();
        let elevation = s.asin();
        let (base, opacity) = if elevation < hill {
            let far = [0.36, 0.42, 0.38];
            (mix([0.24, 0.32, 0.18], far, rng.uniform()), opacity_around(rng, 3.0, 1.5))
        } else {
            let sky = mix([0.78, 0.84, 0.9], [0.36, 0.55, 0.86], s.max(0.0).sqrt());
            let cloud = (self.pattern(az * 40.0, elevation * 60.0, 2) - 0.3).max(0.0) * 1.6;
            (mix(sky, [0.95, 0.95, 0.97], cloud), opacity_around(rng, 2.0, 1.5))
        };
        // Background Gaussians are big and rounder than surface detail.
        let scales = log_scales_with(rng, spacing, 1.0, 0.5);
        splat(oriented(rng, dir * SHELL_RADIUS, -dir, scales), opacity, vary(rng, base))
    }

    /// The ground colour at (x, z): grass and dirt patches.
    fn ground_color(&self, x: f64, z: f64) -> [f64; 3] {
        mix([0.26, 0.36, 0.14], [0.46, 0.38, 0.27], 0.5 + 0.8 * self.pattern(x, z, 0))
    }

    fn far_ground(&self, rng: &mut HashRng) -> Splat {
        // Log-uniform radius: area density n / (2 pi r^2 ln(R_far / R)).
        let k = FAR_GROUND_RADIUS / GROUND_RADIUS;
        let r = GROUND_RADIUS * k.powf(rng.uniform());
        let a = rng.range(0.0, TAU);
        let (x, z) = (r * a.sin(), r * a.cos());
        let density = self.n * FAR_GROUND_FRACTION / (TAU * r * r * k.ln());
        let spacing = 1.0 / density.sqrt();
        let haze = ((r - GROUND_RADIUS) / (FAR_GROUND_RADIUS - GROUND_RADIUS)).sqrt();
        let base = mix(self.ground_color(x, z), [0.36, 0.42, 0.38], haze);
        let normal = DVec3::new(0.05 * rng.normal(), -1.0, 0.05 * rng.normal());
        let scales = log_scales_with(rng, spacing, 2.0, 0.8);
        splat(
            oriented(rng, DVec3::new(x, 0.0, z), normal, scales),
            opacity_around(rng, 2.0, 1.5),
            vary(rng, base),
        )
    }

    fn floater(&self, rng: &mut HashRng) -> Splat {
        let p = DVec3::new(
            rng.range(-FLOATER_HALF_WIDTH, FLOATER_HALF_WIDTH),
            -FLOATER_HEIGHT * rng.uniform(),
            rng.range(-FLOATER_HALF_WIDTH, FLOATER_HALF_WIDTH),
        );
        let volume = 4.0 * FLOATER_HALF_WIDTH * FLOATER_HALF_WIDTH * FLOATER_HEIGHT;
        // Small, roundish blobs: a tenth of their mean spacing.
        let size = 0.1 * (volume / (self.n * FLOATER_FRACTION)).cbrt();
        let g = rng.range(0.3, 0.7);
        let scales = log_scales_with(rng, size, 1.2, 0.6);
        splat(randomly_oriented(rng, p, scales), opacity_around(rng, -3.0, 1.0), vary(rng, [g, g, g]))
    }

    fn object(&self, k: usize, rng: &mut HashRng) -> Splat {
        let o = &self.objects[k];
        let count = self.n
            * OBJECT_FRACTION
            * (self.cumulative[k] - if k == 0 { 0.0 } else { self.cumulative[k - 1] });
        let spacing = (o.area / count.max(1.0)).sqrt();
        let (local, normal, color, volume) = match &o.shape {
            Shape::Tree { trunk_radius, trunk_height, crown, trunk_color, leaf_color } => {
                let trunk_area = TAU * trunk_radius * trunk_height;
                if rng.uniform() * area(&o.shape) < trunk_area {
                    let a = rng.range(0.0, TAU);
                    let n = DVec3::new(a.cos(), 0.0, a.sin());
                    let p = n * *trunk_radius + DVec3::new(0.0, -trunk_height * rng.uniform(), 0.0);
                    (p, n, *trunk_color, false)
                } else {
                    let d = unit_vector(rng);
                    // Foliage: a fuzzy shell, not a hard surface.
                    let depth = 1.0 - 0.35 * rng.uniform().powi(2);
                    let centre = DVec3::new(0.0, -trunk_height - 0.7 * crown.y, 0.0);
                    let shade = 0.75 + 0.25 * (-d.y);
                    (centre + d * *crown * depth, d, leaf_color.map(|c| c * shade), true)
                }
            }
            Shape::Rock { radii, color } => {
                let mut d = unit_vector(rng);
                // The upper half: the rest is buried.
                d.y = -d.y.abs();
                (d * *radii, (d / *radii).normalize(), *color, false)
            }
            Shape::Building { size, wall, roof } => {
                let (p, n, face) = box_surface(rng, *size, 0.0);
                let color = if face == 4 { *roof } else { windows(p, n, *size, *wall) };
                (p, n, color, false)
            }
            Shape::Vehicle { size, paint } => vehicle(rng, *size, *paint),
        };
        let (s, c) = o.yaw.sin_cos();
        let rot = |v: DVec3| DVec3::new(c * v.x + s * v.z, v.y, -s * v.x + c * v.z);
        let world = rot(local) + DVec3::new(o.x, 0.0, o.z);
        let color = vary(rng, color);
        let shape = if volume {
            in_volume(rng, world, spacing * 1.3)
        } else {
            on_surface(rng, world, rot(normal), spacing)
        };
        splat(shape, trained_opacity(rng), color)
    }
}

fn unit_vector(rng: &mut HashRng) -> DVec3 {
    let y = rng.range(-1.0, 1.0);
    let a = rng.range(0.0, TAU);
    let r = (1.0 - y * y).sqrt();
    DVec3::new(r * a.cos(), y, r * a.sin())
}

fn random_shape(rng: &mut HashRng) -> Shape {
    let k = rng.uniform();
    if k < 0.4 {
        let g = rng.range(0.25, 0.5);
        Shape::Tree {
            trunk_radius: rng.range(0.15, 0.35),
            trunk_height: rng.range(1.5, 3.5),
            crown: DVec3::new(rng.range(1.5, 3.0), rng.range(1.5, 3.5), rng.range(1.5, 3.0)),
            trunk_color: [0.33, 0.24, 0.15],
            leaf_color: [rng.range(0.1, 0.25), g, rng.range(0.05, 0.18)],
        }
    } else if k < 0.65 {
        let g = rng.range(0.35, 0.6);
        Shape::Rock {
            radii: DVec3::new(rng.range(0.4, 1.6), rng.range(0.3, 1.0), rng.range(0.4, 1.6)),
            color: [g * rng.range(0.95, 1.1), g, g * rng.range(0.85, 1.0)],
        }
    } else if k < 0.8 {
        const WALLS: [[f64; 3]; 4] =
            [[0.85, 0.82, 0.75], [0.62, 0.3, 0.22], [0.55, 0.56, 0.58], [0.8, 0.7, 0.5]];
        Shape::Building {
            size: DVec3::new(rng.range(4.0, 10.0), rng.range(3.0, 9.0), rng.range(4.0, 10.0)),
            wall: WALLS[rng.below(4) as usize],
            roof: [0.25, 0.25, 0.27],
        }
    } else {
        const PAINTS: [[f64; 3]; 6] = [
            [0.7, 0.1, 0.1],
            [0.1, 0.2, 0.6],
            [0.9, 0.9, 0.9],
            [0.08, 0.08, 0.08],
            [0.6, 0.6, 0.62],
            [0.9, 0.75, 0.1],
        ];
        Shape::Vehicle {
            size: DVec3::new(rng.range(4.2, 4.8), rng.range(1.4, 1.6), rng.range(1.7, 1.9)),
            paint: PAINTS[rng.below(6) as usize],
        }
    }
}

/// Horizontal radius an object occupies.
fn footprint_radius(shape: &Shape) -> f64 {
    match shape {
        Shape::Tree { crown, .. } => crown.x.max(crown.z),
        Shape::Rock { radii, .. } => radii.x.max(radii.z),
        Shape::Building { size, .. } | Shape::Vehicle { size, .. } => 0.5 * size.x.hypot(size.z),
    }
}

/// Visible surface area, m^2.
fn area(shape: &Shape) -> f64 {
    match shape {
        Shape::Tree { trunk_radius, trunk_height, crown, .. } => {
            TAU * trunk_radius * trunk_height + ellipsoid_area(*crown)
        }
        Shape::Rock { radii, .. } => 0.5 * ellipsoid_area(*radii),
        Shape::Building { size, .. } | Shape::Vehicle { size, .. } => {
            2.0 * size.y * (size.x + size.z) + size.x * size.z
        }
    }
}

/// Thomsen's approximation of an ellipsoid's surface area.
fn ellipsoid_area(r: DVec3) -> f64 {
    let p = 1.6075;
    let (a, b, c) = (r.x.powf(p), r.y.powf(p), r.z.powf(p));
    2.0 * TAU * ((a * b + a * c + b * c) / 3.0).powf(1.0 / p)
}

/// A point on the walls or roof of a box of `size` (x, height, z) standing on y = `base`
/// (extending towards -y), with its outward normal and face (0..3 walls, 4 roof).
fn box_surface(rng: &mut HashRng, size: DVec3, base: f64) -> (DVec3, DVec3, usize) {
    let (sx, h, sz) = (size.x, size.y, size.z);
    let areas = [sx * h, sx * h, sz * h, sz * h, sx * sz];
    let total: f64 = areas.iter().sum();
    let mut pick = rng.uniform() * total;
    let mut face = 4;
    for (f, a) in areas.iter().enumerate() {
        if pick < *a {
            face = f;
            break;
        }
        pick -= a;
    }
    let (u, v) = (rng.range(-0.5, 0.5), rng.uniform());
    let y = base - v * h;
    let (p, n) = match face {
        0 => (DVec3::new(u * sx, y, -0.5 * sz), DVec3::NEG_Z),
        1 => (DVec3::new(u * sx, y, 0.5 * sz), DVec3::Z),
        2 => (DVec3::new(-0.5 * sx, y, u * sz), DVec3::NEG_X),
        3 => (DVec3::new(0.5 * sx, y, u * sz), DVec3::X),
        _ => (DVec3::new(u * sx, base - h, rng.range(-0.5, 0.5) * sz), DVec3::NEG_Y),
    };
    (p, n, face)
}

/// Wall colour with a grid of dark windows (1.2 m wide every 3 m, storeys of 3 m).
fn windows(p: DVec3, n: DVec3, size: DVec3, wall: [f64; 3]) -> [f64; 3] {
    let along = if n.x.abs() > 0.5 { p.z + 0.5 * size.z } else { p.x + 0.5 * size.x };
    let up = -p.y;
    let in_window = (along / 3.0).fract() > 0.3
        && (along / 3.0).fract() < 0.7
        && (up / 3.0).fract() > 0.35
        && (up / 3.0).fract() < 0.75
        && up > 0.8
        && up < size.y - 0.5;
    if in_window {
        [0.14, 0.18, 0.24]
    } else {
        wall
    }
}

/// A car: a body box from 0.3 m to 1 m height, a cabin on top, tyres at the bottom.
fn vehicle(rng: &mut HashRng, size: DVec3, paint: [f64; 3]) -> (DVec3, DVec3, [f64; 3], bool) {
    let body = DVec3::new(size.x, 0.7, size.z);
    let cabin = DVec3::new(size.x * 0.55, size.y - 1.0, size.z * 0.9);
    let body_area = 2.0 * body.y * (body.x + body.z) + body.x * body.z;
    let cabin_area = 2.0 * cabin.y * (cabin.x + cabin.z) + cabin.x * cabin.z;
    let tyre_band = 0.3 * 2.0 * (body.x + body.z);
    let pick = rng.uniform() * (body_area + cabin_area + tyre_band);
    if pick < body_area {
        let (p, n, _) = box_surface(rng, body, -0.3);
        (p, n, paint, false)
    } else if pick < body_area + cabin_area {
        let (p, n, face) = box_surface(rng, cabin, -1.0);
        let glass = face < 4 && p.y > -1.0 - 0.85 * cabin.y && p.y < -1.0 - 0.15 * cabin.y;
        (p + DVec3::new(-0.1 * size.x, 0.0, 0.0), n, if glass { [0.1, 0.12, 0.15] } else { paint }, false)
    } else {
        let (mut p, n, _) = box_surface(rng, DVec3::new(body.x, 0.3, body.z), 0.0);
        if n.y != 0.0 {
            p.y = -0.3;
        }
        (p, n, [0.05, 0.05, 0.05], false)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layout_has_the_subject_and_separated_objects() {
        let o = Outdoor::new(5, 100_000);
        assert!(o.objects.len() > OBJECTS / 2, "{}", o.objects.len());
        assert!(matches!(o.objects[0].shape, Shape::Building { .. }));
        assert!((o.cumulative.last().unwrap() - 1.0).abs() < 1e-12);
        for (i, a) in o.objects.iter().enumerate() {
            for b in &o.objects[i + 1..] {
                let d = ((a.x - b.x).powi(2) + (a.z - b.z).powi(2)).sqrt();
                assert!(d > footprint_radius(&a.shape) + footprint_radius(&b.shape), "objects overlap");
            }
        }
    }

    #[test]
    fn ellipsoid_area_of_a_sphere() {
        let a = ellipsoid_area(DVec3::splat(2.0));
        assert!((a - 2.0 * TAU * 4.0).abs() / a < 1e-9);
    }
}
