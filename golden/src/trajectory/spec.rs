//! Trajectory spec strings.
//!
//! ```text
//! orbit[:KEY=VALUE,...]    circle the scene (default: frames the whole robust bounds)
//! walk[:KEY=VALUE,...]     walk a closed loop across the scene at eye height
//! shake[:KEY=VALUE,...]    hand-held camera at the default orbit's first pose
//! file:PATH | PATH.json    a trajectory read back from a cameras.json
//! ```
//!
//! Keys of every kind: `frames=N` (default: the caller's), `speed=S` or `speed=Sx` (multiplier,
//! 0 < S <= 64, default 1), `cut=K` or `cut=K1/K2/...` (scene cuts, each in `1..frames`),
//! `res=WxH` or `res=hd|fhd|qhd` ([`super::parse_resolution`], default 1280x720), `fov=DEG` (horizontal, default 60).
//!
//! - `orbit`: `radius=R`, `height=H` (camera height above the target, world up being -y),
//!   `start=DEG` (azimuth of frame 0; 0 is the -z side), `rate=DEG` (degrees per second at 1x,
//!   default 12), `target=X/Y/Z` (default: the bounds centre). With only `radius`, the height
//!   keeps the default 25 degree elevation; with only `height`, the radius is the default one.
//! - `walk`: `height=H` (eye height above the ground, default 1.6 scene units), `radius=R` (mean
//!   loop radius, default 30% of the extent), `pace=V` (units per second at 1x, default 1.4
//!   scene units), `yaw=DEG` (look-around amplitude, default 8), `pitch=DEG` (downward tilt,
//!   default 5), `seed=S` (loop shape, default 1).
//! - `shake`: `seed=S` (default 1), `amp=A` (jitter multiplier, default 1: 1 cm and 0.3 degrees
//!   RMS), and the orbit keys `radius`, `height`, `start`, `target` for the rest pose.
//!
//! A scene unit is [`super::scene_unit`] of the bounds. Unknown keys, repeated keys and bad
//! values are errors naming the spec.

use super::orbit::{self, OrbitParams};
use super::resolution::MAX_SIDE;
use super::shake::{self, ShakeParams};
use super::walk::{self, WalkParams};
use super::{Intrinsics, Shot, Trajectory};
use crate::cameras_json::check_camera;
use crate::error::{InputError, InputResult};
use glam::DVec3;
use std::path::Path;

/// Largest accepted speed multiplier.
pub const MAX_SPEED: f64 = 64.0;
/// Largest accepted frame count.
pub const MAX_FRAMES: usize = 1_000_000;

const COMMON_KEYS: [&str; 5] = ["frames", "speed", "cut", "res", "fov"];
const ORBIT_KEYS: [&str; 5] = ["radius", "height", "start", "rate", "target"];
const WALK_KEYS: [&str; 6] = ["height", "radius", "pace", "yaw", "pitch", "seed"];
const SHAKE_KEYS: [&str; 6] = ["seed", "amp", "radius", "height", "start", "target"];

/// Builds the trajectory a spec names, for a scene with (robust) bounds `bounds`; `frames` is
/// the frame count when the spec has no `frames=` key.
pub fn parse_trajectory(spec: &str, bounds: ([f32; 3], [f32; 3]), frames: usize) -> InputResult<Trajectory> {
    let s = spec.trim();
    if let Some(path) = s.strip_prefix("file:") {
        if path.trim().is_empty() {
            return Err(err(spec, "the path after 'file:' is empty (expected file:PATH to a cameras.json)"));
        }
        return Trajectory::read(Path::new(path));
    }
    let (kind, rest) = s.split_once(':').unwrap_or((s, ""));
    let specific: &[&str] = match kind {
        "orbit" => &ORBIT_KEYS,
        "walk" => &WALK_KEYS,
        "shake" => &SHAKE_KEYS,
        _ if s.to_ascii_lowercase().ends_with(".json") => return Trajectory::read(Path::new(s)),
        "" => return Err(err(spec, "empty trajectory spec (expected orbit, walk, shake or file:PATH)")),
        _ => {
            return Err(err(
                spec,
                format!(
                "unknown trajectory kind '{kind}' (expected orbit, walk, shake, file:PATH or a .json path)"
            ),
            ))
        }
    };
    let keys = Keys::parse(spec, kind, rest, specific)?;
    let shot = keys.shot(frames)?;
    let traj = match kind {
        "orbit" => orbit::orbit(&keys.orbit(bounds, &shot.intrinsics)?, &shot),
        "walk" => {
            let mut p = WalkParams::across(
                bounds,
                keys.uint("seed")?.unwrap_or(1),
                keys.number("height", |_| true, "a finite number")?,
                keys.number("radius", |v| v > 0.0, "a positive number")?,
            );
            if let Some(v) = keys.number("pace", |v| v > 0.0, "a positive number")? {
                p.pace = v;
            }
            if let Some(v) = keys.number("yaw", |v| v.abs() <= 90.0, "between -90 and 90")? {
                p.yaw_deg = v;
            }
            if let Some(v) = keys.number("pitch", |v| v.abs() < 89.0, "between -89 and 89")? {
                p.pitch_deg = v;
            }
            walk::walk(&p, &shot)
        }
        _ => {
            let o = keys.orbit(bounds, &shot.intrinsics)?;
            let seed = keys.uint("seed")?.unwrap_or(1);
            let amp = keys.number("amp", |v| v >= 0.0, "a number >= 0")?.unwrap_or(1.0);
            shake::shake(&ShakeParams::at_orbit_start(&o, bounds, seed, amp), &shot)
        }
    };
    check_frames(spec, &traj)?;
    Ok(traj)
}

/// Checks every generated camera as a cameras.json reader would ([`check_camera`]): extreme
/// values (`radius=1e-320`, `height=1e308`) give degenerate poses, which are errors naming the
/// spec rather than black frames or an unreadable output file.
fn check_frames(spec: &str, traj: &Trajectory) -> InputResult<()> {
    for (i, cam) in traj.frames.iter().enumerate() {
        check_camera(cam).map_err(|p| {
            err(
                spec,
                format!("camera {i} ('{}'): {p} (a value of the spec is too large or too small)", cam.name),
            )
        })?;
    }
    Ok(())
}

fn err(spec: &str, problem: impl Into<String>) -> InputError {
    InputError::new(spec, problem)
}

/// The `KEY=VALUE` pairs of a spec, checked against the kind's keys.
struct Keys<'a> {
    spec: &'a str,
    pairs: Vec<(&'a str, &'a str)>,
}

impl<'a> Keys<'a> {
    fn parse(spec: &'a str, kind: &str, rest: &'a str, specific: &[&str]) -> InputResult<Self> {
        let mut pairs: Vec<(&str, &str)> = Vec::new();
        for item in rest.split(',').map(str::trim).filter(|i| !i.is_empty()) {
            let Some((k, v)) = item.split_once('=') else {
                return Err(err(spec, format!("'{item}' is not KEY=VALUE")));
            };
            let (k, v) = (k.trim(), v.trim());
            if !COMMON_KEYS.contains(&k) && !specific.contains(&k) {
                let mut all: Vec<&str> = COMMON_KEYS.to_vec();
                all.extend_from_slice(specific);
                return Err(err(
                    spec,
                    format!("unknown key '{k}' for {kind} (accepted: {})", all.join(", ")),
                ));
            }
            if pairs.iter().any(|(pk, _)| *pk == k) {
                return Err(err(spec, format!("key '{k}' given twice")));
            }
            pairs.push((k, v));
        }
        Ok(Keys { spec, pairs })
    }

    fn get(&self, key: &str) -> Option<&'a str> {
        self.pairs.iter().find(|(k, _)| *k == key).map(|(_, v)| *v)
    }

    fn bad(&self, key: &str, value: &str, want: &str) -> InputError {
        err(self.spec, format!("{key}={value}: must be {want}"))
    }

    fn number(&self, key: &str, ok: impl Fn(f64) -> bool, want: &str) -> InputResult<Option<f64>> {
        let Some(v) = self.get(key) else { return Ok(None) };
        match v.parse::<f64>() {
            Ok(x) if x.is_finite() && ok(x) => Ok(Some(x)),
            _ => Err(self.bad(key, v, want)),
        }
    }

    fn uint(&self, key: &str) -> InputResult<Option<u64>> {
        let Some(v) = self.get(key) else { return Ok(None) };
        v.parse::<u64>().map(Some).map_err(|_| self.bad(key, v, "a non-negative integer"))
    }

    fn shot(&self, default_frames: usize) -> InputResult<Shot> {
        let frames = match self.get("frames") {
            Some(v) => match v.parse::<usize>() {
                Ok(n) if (1..=MAX_FRAMES).contains(&n) => n,
                _ => return Err(self.bad("frames", v, &format!("an integer from 1 to {MAX_FRAMES}"))),
            },
            None if (1..=MAX_FRAMES).contains(&default_frames) => default_frames,
            None => {
                return Err(err(
                    self.spec,
                    format!("frame count {default_frames} is not in 1..={MAX_FRAMES}"),
                ))
            }
        };
        let speed = match self.get("speed") {
            Some(v) => match v.strip_suffix(['x', 'X']).unwrap_or(v).parse::<f64>() {
                Ok(s) if s > 0.0 && s <= MAX_SPEED => s,
                _ => {
                    return Err(self.bad(
                        "speed",
                        v,
                        &format!("a multiplier in (0, {MAX_SPEED}], e.g. 4 or 4x"),
                    ))
                }
            },
            None => 1.0,
        };
        let mut cuts = Vec::new();
        if let Some(v) = self.get("cut") {
            for part in v.split('/') {
                match part.trim().parse::<usize>() {
                    Ok(k) if k >= 1 && k < frames => cuts.push(k),
                    _ => {
                        return Err(self.bad(
                            "cut",
                            v,
                            &format!(
                                "frame numbers K (or K1/K2/...) with 1 <= K < {frames} (the frame count)"
                            ),
                        ))
                    }
                }
            }
            cuts.sort_unstable();
            cuts.dedup();
        }
        let mut intrinsics = Intrinsics::default();
        if let Some(v) = self.get("res") {
            let (w, h) = super::parse_resolution(v).map_err(|_| {
                self.bad("res", v, &format!("WIDTHxHEIGHT with sizes from 1 to {MAX_SIDE}, e.g. 1920x1080"))
            })?;
            intrinsics.width = w;
            intrinsics.height = h;
        }
        if let Some(f) = self.number(
            "fov",
            |f| (1.0..=170.0).contains(&f),
            "a horizontal field of view from 1 to 170 degrees",
        )? {
            intrinsics.fov_x_deg = f;
        }
        Ok(Shot { frames, speed, cuts, intrinsics })
    }

    fn orbit(&self, bounds: ([f32; 3], [f32; 3]), intrinsics: &Intrinsics) -> InputResult<OrbitParams> {
        let mut p = OrbitParams::framing(bounds, intrinsics);
        if let Some(v) = self.get("target") {
            let xyz: Vec<Option<f64>> =
                v.split('/').map(|c| c.trim().parse::<f64>().ok().filter(|x| x.is_finite())).collect();
            match xyz[..] {
                [Some(x), Some(y), Some(z)] => p.target = DVec3::new(x, y, z),
                _ => return Err(self.bad("target", v, "three finite numbers X/Y/Z")),
            }
        }
        let radius = self.number("radius", |v| v > 0.0, "a positive number")?;
        let height = self.number("height", |_| true, "a finite number")?;
        match (radius, height) {
            (Some(r), None) => {
                p.radius = r;
                p.height = r * orbit::DEFAULT_ELEVATION_DEG.to_radians().tan();
            }
            (r, h) => {
                p.radius = r.unwrap_or(p.radius);
                p.height = h.unwrap_or(p.height);
            }
        }
        if let Some(v) = self.number("start", |_| true, "a finite angle in degrees")? {
            p.start_deg = v;
        }
        if let Some(v) = self.number("rate", |_| true, "a finite rate in degrees per second")? {
            p.deg_per_s = v;
        }
        Ok(p)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const B: ([f32; 3], [f32; 3]) = ([-1.0, -2.0, -1.0], [1.0, 0.0, 1.0]);

    #[test]
    fn keys_reach_the_generators() {
        let t = parse_trajectory("orbit:radius=5,height=2,frames=7,res=64x32,fov=90,start=90", B, 3).unwrap();
        assert_eq!(t.len(), 7);
        let c = &t.frames[0];
        assert_eq!((c.width, c.height), (64, 32));
        assert!((c.fx - 32.0).abs() < 1e-9);
        assert!((c.position - DVec3::new(5.0, -3.0, 0.0)).length() < 1e-9, "{:?}", c.position);
        assert_eq!(parse_trajectory("walk", B, 4).unwrap().len(), 4);
        assert_eq!(parse_trajectory("shake:seed=3,amp=2,speed=2x", B, 5).unwrap().len(), 5);
        let t = parse_trajectory("orbit:cut=4/2,frames=6", B, 3).unwrap();
        assert_eq!(t.cuts, vec![2, 4]);
    }

    #[test]
    fn bad_specs_name_the_problem() {
        let cases = [
            ("", "empty"),
            ("spiral", "unknown trajectory kind 'spiral'"),
            ("orbit:foo=1", "unknown key 'foo'"),
            ("walk:start=1", "unknown key 'start'"),
            ("orbit:radius", "not KEY=VALUE"),
            ("orbit:radius=-1", "radius=-1"),
            ("orbit:radius=1,radius=2", "given twice"),
            ("orbit:speed=0", "speed=0"),
            ("orbit:speed=65", "speed=65"),
            ("orbit:frames=0", "frames=0"),
            ("orbit:frames=10,cut=10", "cut=10"),
            ("orbit:cut=0", "cut=0"),
            ("orbit:res=12", "res=12"),
            ("orbit:fov=nan", "fov=nan"),
            ("orbit:target=1/2", "target=1/2"),
            ("shake:seed=-1", "seed=-1"),
            ("missing_file.json", "missing_file.json: cannot read"),
            ("file:", "the path after 'file:' is empty"),
            ("file: ", "the path after 'file:' is empty"),
            ("orbit:radius=1e-320", "camera 0 ('frame_00000'): rotation has non-finite entries"),
            ("orbit:radius=1e308", "camera 0 ('frame_00000'): "),
            ("orbit:height=1e308", "camera 0 ('frame_00000'): "),
            ("orbit:radius=1e39", "camera 0 ('frame_00000'): position"),
            ("walk:radius=1e308", "camera 0 ('frame_00000'): "),
            ("shake:radius=1e-320", "camera 0 ('frame_00000'): "),
        ];
        for (spec, want) in cases {
            let e = parse_trajectory(spec, B, 10).unwrap_err().to_string();
            assert!(e.contains(want), "{spec} -> {e}, wanted {want}");
            assert!(e.starts_with(spec), "{e} should start with the spec");
        }
    }
}
