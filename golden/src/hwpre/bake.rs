//! The baked parameter format: what DRAM holds per Gaussian for the Preprocessing Engine,
//! computed offline (`neo scene bake`) from the activated scene.
//!
//! # What is baked (per Gaussian), and why
//! - **Geometry record** ([`GEOMETRY_FIELDS`], read for every Gaussian, [`geometry_bytes`]):
//!   - `position`: world-space mean, 3 x f32;
//!   - `cov3d`: the 3D covariance `R S S^T R^T` of the exp-activated scales and the normalised
//!     quaternion, upper triangle `[xx, xy, xz, yy, yz, zz]`, 6 x f32, computed exactly as
//!     [`crate::render::cov3d`] (so the projection sees the float reference's covariance);
//!   - `opacity`: the sigmoid-activated opacity, f32;
//!   - `k2`: the ITU cutoff's squared Mahalanobis radius [`Cutoff::radius_squared`] of this
//!     Gaussian's opacity (the larger of the float and the quantised one), computed in f64
//!     and rounded *up* to f32 (so the extents stay conservative). `ln` has no hardware, and
//!     `k2` depends only on the opacity, so it is baked.
//! - **SH record** (read only for Gaussians that survive culling, [`sh_bytes`]): the
//!   `3 (d + 1)^2` coefficients of the scene's degree `d`, `[coeff][rgb]`, as f32 or as IEEE
//!   binary16 ([`ShPrecision`]; the hardware widens a half exactly).
//!
//! Per frame (registers, computed by the host): the camera (view rotation and translation,
//! focal lengths, FOV clamp, principal point, tile grid) and the SH degree.
//!
//! # File layout (little-endian)
//! A 32-byte header, then `count` geometry records, then `count` SH records:
//!
//! | bytes | field |
//! | --- | --- |
//! | 0..8 | magic `NEOBAKE\0` |
//! | 8..12 | version (u32, 1) |
//! | 12 | SH degree (0..=3) |
//! | 13 | SH precision (0 f32, 1 f16) |
//! | 14 | cutoff kind (0 sigma, 1 alpha) |
//! | 15, 16 | the opacity format `k2` was baked for: bits, fraction bits |
//! | 17..20 | zero |
//! | 20..24 | cutoff parameter (f32: sigma `k`, or the alpha margin) |
//! | 24..32 | count (u64) |

use std::path::Path;

use crate::error::{InputError, InputResult};
use crate::formats::{Cutoff, FeatureFormat, QFormat};
use crate::render::cov3d;
use crate::scene::{sh_coeffs, Scene};

/// The file's first eight bytes.
pub const MAGIC: [u8; 8] = *b"NEOBAKE\0";
/// The format version this code reads and writes.
pub const VERSION: u32 = 1;
/// Bytes of the file header.
pub const HEADER_BYTES: usize = 32;

/// The fields of a geometry record, in order, with their f32 counts.
pub const GEOMETRY_FIELDS: [(&str, usize); 4] = [("position", 3), ("cov3d", 6), ("opacity", 1), ("k2", 1)];

/// Bytes of one geometry record (every field f32): 44.
pub const fn geometry_bytes() -> u32 {
    let mut n = 0;
    let mut i = 0;
    while i < GEOMETRY_FIELDS.len() {
        n += GEOMETRY_FIELDS[i].1;
        i += 1;
    }
    4 * n as u32
}

/// How the SH coefficients are stored.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize)]
pub enum ShPrecision {
    /// IEEE binary32.
    F32,
    /// IEEE binary16, rounded to nearest even from the f32 coefficient (saturating at
    /// +-65504); the hardware widens it exactly.
    F16,
}

impl ShPrecision {
    /// Bytes per coefficient.
    pub const fn bytes(self) -> u32 {
        match self {
            ShPrecision::F32 => 4,
            ShPrecision::F16 => 2,
        }
    }

    fn code(self) -> u8 {
        match self {
            ShPrecision::F32 => 0,
            ShPrecision::F16 => 1,
        }
    }
}

/// Bytes of one SH record at SH degree `degree` (`3 (d + 1)^2` coefficients).
pub const fn sh_bytes(degree: u8, precision: ShPrecision) -> u32 {
    3 * sh_coeffs(degree) as u32 * precision.bytes()
}

/// Bytes per Gaussian in DRAM: geometry plus SH.
pub const fn bytes_per_gaussian(degree: u8, precision: ShPrecision) -> u32 {
    geometry_bytes() + sh_bytes(degree, precision)
}

/// One Gaussian's geometry record.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BakedGeometry {
    /// World-space mean.
    pub position: [f32; 3],
    /// 3D covariance, upper triangle `[xx, xy, xz, yy, yz, zz]`.
    pub cov3d: [f32; 6],
    /// Activated opacity.
    pub opacity: f32,
    /// Cutoff radius squared (sigmas), rounded up; `+inf` means unbounded.
    pub k2: f32,
}

impl BakedGeometry {
    /// The record as DRAM holds it ([`geometry_bytes`] bytes): the fields of
    /// [`GEOMETRY_FIELDS`] in order, each f32 little-endian.
    pub fn to_le_bytes(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(geometry_bytes() as usize);
        for v in self.position.iter().chain(&self.cov3d).chain([&self.opacity, &self.k2]) {
            out.extend_from_slice(&v.to_le_bytes());
        }
        out
    }

    /// The record of [`geometry_bytes`] bytes `b` ([`BakedGeometry::to_le_bytes`]).
    ///
    /// # Panics
    /// When `b` is shorter than [`geometry_bytes`].
    pub fn from_le_bytes(b: &[u8]) -> BakedGeometry {
        let f = |k: usize| f32::from_le_bytes(b[4 * k..4 * k + 4].try_into().expect("4 bytes"));
        BakedGeometry {
            position: [f(0), f(1), f(2)],
            cov3d: [f(3), f(4), f(5), f(6), f(7), f(8)],
            opacity: f(9),
            k2: f(10),
        }
    }
}

/// A baked scene (see the module doc).
#[derive(Clone, Debug, PartialEq)]
pub struct Baked {
    /// SH degree, 0..=3.
    pub sh_degree: u8,
    /// SH storage.
    pub sh_precision: ShPrecision,
    /// The cutoff `k2` was baked with.
    pub cutoff: Cutoff,
    /// The opacity format `k2` was baked with.
    pub opacity_format: QFormat,
    /// One geometry record per Gaussian.
    pub geometry: Vec<BakedGeometry>,
    /// SH coefficients as stored: f32 bits, or binary16 bits in the low 16 bits;
    /// `3 (d + 1)^2` per Gaussian, `[gaussian][coeff][rgb]`.
    pub sh: Vec<u32>,
}

/// `v` rounded up to f32 (`+inf` stays, NaN gives `+inf`).
pub fn f32_round_up(v: f64) -> f32 {
    if v.is_nan() {
        return f32::INFINITY;
    }
    let f = v as f32;
    if (f as f64) < v {
        f.next_up()
    } else {
        f
    }
}

/// The binary16 bits of `v` (RNE, saturating at +-65504, NaN to 0x7BFF).
pub fn f16_bits(v: f32) -> u32 {
    let sign = if v.is_sign_negative() && !v.is_nan() { 0x8000 } else { 0 };
    sign | crate::sort::depth_key::f16_bits_saturating(v.abs())
}

/// The cutoff's `k2` for opacity `opacity` under `fmt` (the larger of the float and the
/// quantised opacity, as [`crate::formats::quantize`] uses), rounded up to f32.
pub fn bake_k2(opacity: f32, fmt: &FeatureFormat) -> f32 {
    let o = (opacity as f64).max(fmt.opacity.dequantize(fmt.opacity.quantize(opacity as f64)));
    f32_round_up(fmt.cutoff.radius_squared(o))
}

impl Baked {
    /// Bakes `scene` for the feature format `fmt` (its cutoff and opacity widths give `k2`).
    pub fn from_scene(scene: &Scene, fmt: &FeatureFormat, sh_precision: ShPrecision) -> Self {
        let geometry = (0..scene.len())
            .map(|i| BakedGeometry {
                position: scene.positions[i],
                cov3d: cov3d(scene.scales[i], scene.rotations[i]),
                opacity: scene.opacities[i],
                k2: bake_k2(scene.opacities[i], fmt),
            })
            .collect();
        let sh = scene
            .sh
            .iter()
            .map(|&v| match sh_precision {
                ShPrecision::F32 => v.to_bits(),
                ShPrecision::F16 => f16_bits(v),
            })
            .collect();
        Baked {
            sh_degree: scene.sh_degree,
            sh_precision,
            cutoff: fmt.cutoff,
            opacity_format: fmt.opacity,
            geometry,
            sh,
        }
    }

    /// Number of Gaussians.
    pub fn len(&self) -> usize {
        self.geometry.len()
    }

    /// True when there are no Gaussians.
    pub fn is_empty(&self) -> bool {
        self.geometry.is_empty()
    }

    /// Stored SH values per Gaussian.
    pub fn sh_per_gaussian(&self) -> usize {
        3 * sh_coeffs(self.sh_degree)
    }

    /// The stored SH words of Gaussian `i`.
    pub fn sh_of(&self, i: usize) -> &[u32] {
        let n = self.sh_per_gaussian();
        &self.sh[i * n..(i + 1) * n]
    }

    /// SH coefficient `k` of Gaussian `i` as the hardware sees it (widened from f16).
    pub fn sh_value(&self, i: usize, k: usize) -> f32 {
        let w = self.sh_of(i)[k];
        match self.sh_precision {
            ShPrecision::F32 => f32::from_bits(w),
            ShPrecision::F16 => crate::hwarith::Arith::widen_half(&mut crate::hwarith::Native, w as i32),
        }
    }

    /// Bytes per Gaussian of this scene in DRAM.
    pub fn bytes_per_gaussian(&self) -> u32 {
        bytes_per_gaussian(self.sh_degree, self.sh_precision)
    }

    /// Whether `k2` was baked for `fmt`'s cutoff and opacity widths.
    pub fn matches(&self, fmt: &FeatureFormat) -> bool {
        self.cutoff == fmt.cutoff && self.opacity_format == fmt.opacity
    }

    /// The file image (see the module doc).
    pub fn to_bytes(&self) -> Vec<u8> {
        let n = self.len();
        let mut out = Vec::with_capacity(HEADER_BYTES + n * self.bytes_per_gaussian() as usize);
        out.extend_from_slice(&MAGIC);
        out.extend_from_slice(&VERSION.to_le_bytes());
        let (kind, param) = match self.cutoff {
            Cutoff::Sigma(k) => (0u8, k),
            Cutoff::Alpha { margin } => (1u8, margin),
        };
        out.extend_from_slice(&[
            self.sh_degree,
            self.sh_precision.code(),
            kind,
            self.opacity_format.bits,
            self.opacity_format.frac,
            0,
            0,
            0,
        ]);
        out.extend_from_slice(&param.to_le_bytes());
        out.extend_from_slice(&(n as u64).to_le_bytes());
        for g in &self.geometry {
            for v in g.position.iter().chain(&g.cov3d).chain([&g.opacity, &g.k2]) {
                out.extend_from_slice(&v.to_le_bytes());
            }
        }
        for &w in &self.sh {
            match self.sh_precision {
                ShPrecision::F32 => out.extend_from_slice(&w.to_le_bytes()),
                ShPrecision::F16 => out.extend_from_slice(&(w as u16).to_le_bytes()),
            }
        }
        out
    }

    /// Writes the file.
    pub fn write(&self, path: &Path) -> InputResult<()> {
        std::fs::write(path, self.to_bytes()).map_err(|e| InputError::new(path, format!("cannot write: {e}")))
    }

    /// Reads a baked file.
    pub fn read(path: &Path) -> InputResult<Self> {
        let bytes = std::fs::read(path).map_err(|e| InputError::new(path, format!("cannot read: {e}")))?;
        Baked::from_bytes(&bytes, path)
    }

    /// Parses a file image; errors name `path`, the field and (for records) the Gaussian.
    pub fn from_bytes(bytes: &[u8], path: &Path) -> InputResult<Self> {
        let err = |p: String| InputError::new(path, p);
        if bytes.len() < HEADER_BYTES {
            return Err(err(format!(
                "truncated header: {} bytes, a baked file starts with {HEADER_BYTES}",
                bytes.len()
            )));
        }
        if bytes[0..8] != MAGIC {
            return Err(err("magic: not a baked scene (expected NEOBAKE)".into()));
        }
        let u32_at = |o: usize| u32::from_le_bytes(bytes[o..o + 4].try_into().expect("4 bytes"));
        let version = u32_at(8);
        if version != VERSION {
            return Err(err(format!("version: {version}, this neo reads version {VERSION}")));
        }
        let sh_degree = bytes[12];
        if sh_degree > 3 {
            return Err(err(format!("sh_degree: {sh_degree} is outside 0..=3")));
        }
        let sh_precision = match bytes[13] {
            0 => ShPrecision::F32,
            1 => ShPrecision::F16,
            p => return Err(err(format!("sh_precision: code {p} (expected 0 = f32 or 1 = f16)"))),
        };
        if bytes[17..20] != [0, 0, 0] {
            return Err(err("reserved header bytes 17..20 are not zero".into()));
        }
        let param = f32::from_le_bytes(bytes[20..24].try_into().expect("4 bytes"));
        let cutoff = match bytes[14] {
            0 if param.is_finite() && param > 0.0 => Cutoff::Sigma(param),
            1 if param.is_finite() && param >= 0.0 => Cutoff::Alpha { margin: param },
            0 | 1 => return Err(err(format!("cutoff: parameter {param} is out of range"))),
            k => return Err(err(format!("cutoff: kind {k} (expected 0 = sigma or 1 = alpha)"))),
        };
        let opacity_format = QFormat::unsigned(bytes[15], bytes[16]);
        opacity_format.check("opacity").map_err(|e| err(format!("opacity format: {e}")))?;
        let count = u64::from_le_bytes(bytes[24..32].try_into().expect("8 bytes"));
        let per = bytes_per_gaussian(sh_degree, sh_precision) as u64;
        let want = count.checked_mul(per).and_then(|b| b.checked_add(HEADER_BYTES as u64));
        if want != Some(bytes.len() as u64) {
            let want = want.map_or("more than 2^64".to_string(), |w| w.to_string());
            return Err(err(format!(
                "size: {} bytes, but {count} Gaussians of {per} bytes (SH degree {sh_degree}) need {want}",
                bytes.len()
            )));
        }
        let n = count as usize;
        let f32_at = |o: usize| f32::from_le_bytes(bytes[o..o + 4].try_into().expect("4 bytes"));
        let mut geometry = Vec::with_capacity(n);
        let gb = geometry_bytes() as usize;
        for i in 0..n {
            let o = HEADER_BYTES + i * gb;
            let v: Vec<f32> = (0..gb / 4).map(|k| f32_at(o + 4 * k)).collect();
            let g = BakedGeometry {
                position: [v[0], v[1], v[2]],
                cov3d: [v[3], v[4], v[5], v[6], v[7], v[8]],
                opacity: v[9],
                k2: v[10],
            };
            let bad = |field: &str, why: String| err(format!("gaussian {i}: {field}: {why}"));
            if !g.position.iter().all(|x| x.is_finite()) {
                return Err(bad("position", format!("{:?} is not finite", g.position)));
            }
            if !g.cov3d.iter().all(|x| x.is_finite())
                || g.cov3d[0] < 0.0
                || g.cov3d[3] < 0.0
                || g.cov3d[5] < 0.0
            {
                return Err(bad("cov3d", format!("{:?} is not a finite covariance", g.cov3d)));
            }
            if !(0.0..=1.0).contains(&g.opacity) {
                return Err(bad("opacity", format!("{} is outside [0, 1]", g.opacity)));
            }
            if g.k2.is_nan() || g.k2 < 0.0 {
                return Err(bad("k2", format!("{} is not a non-negative number", g.k2)));
            }
            geometry.push(g);
        }
        let sh_start = HEADER_BYTES + n * gb;
        let per_sh = 3 * sh_coeffs(sh_degree);
        let sh = match sh_precision {
            ShPrecision::F32 => (0..n * per_sh).map(|k| u32_at(sh_start + 4 * k)).collect::<Vec<_>>(),
            ShPrecision::F16 => (0..n * per_sh)
                .map(|k| u16::from_le_bytes([bytes[sh_start + 2 * k], bytes[sh_start + 2 * k + 1]]) as u32)
                .collect(),
        };
        let finite = |w: u32| match sh_precision {
            ShPrecision::F32 => f32::from_bits(w).is_finite(),
            ShPrecision::F16 => (w >> 10) & 0x1F != 0x1F,
        };
        if let Some(k) = sh.iter().position(|&w| !finite(w)) {
            return Err(err(format!("gaussian {}: sh[{}]: not a finite value", k / per_sh, k % per_sh)));
        }
        Ok(Baked { sh_degree, sh_precision, cutoff, opacity_format, geometry, sh })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn scene(degree: u8, n: usize) -> Scene {
        let mut s = Scene { sh_degree: degree, ..Scene::default() };
        for i in 0..n {
            let f = i as f32;
            s.positions.push([f, -f, 0.5 * f]);
            s.scales.push([0.1 + f, 0.2, 0.3]);
            s.rotations.push([1.0, 0.0, 0.0, 0.0]);
            s.opacities.push((i % 5) as f32 / 4.0);
        }
        s.sh = (0..n * 3 * sh_coeffs(degree)).map(|k| k as f32 * 0.01 - 0.3).collect();
        s
    }

    #[test]
    fn bytes_follow_the_format() {
        assert_eq!(geometry_bytes(), 44);
        let g = BakedGeometry {
            position: [1.0, -2.0, 3.5],
            cov3d: [0.1, 0.2, 0.3, 0.4, 0.5, 0.6],
            opacity: 0.75,
            k2: f32::INFINITY,
        };
        let b = g.to_le_bytes();
        assert_eq!(b.len(), geometry_bytes() as usize);
        assert_eq!(b[4..8], (-2.0f32).to_le_bytes(), "position[1] is the record's second f32");
        assert_eq!(b[36..40], 0.75f32.to_le_bytes(), "opacity after the 9 f32 of position and cov3d");
        assert_eq!(BakedGeometry::from_le_bytes(&b), g);
        assert_eq!(sh_bytes(3, ShPrecision::F32), 192);
        assert_eq!(sh_bytes(0, ShPrecision::F16), 6);
        assert_eq!(bytes_per_gaussian(1, ShPrecision::F16), 44 + 24);
        for d in 0..=3 {
            for p in [ShPrecision::F32, ShPrecision::F16] {
                let b = Baked::from_scene(&scene(d, 3), &FeatureFormat::default(), p);
                assert_eq!(b.to_bytes().len(), HEADER_BYTES + 3 * bytes_per_gaussian(d, p) as usize);
            }
        }
    }

    #[test]
    fn round_trips_and_keeps_k2_conservative() {
        let fmt = FeatureFormat::default();
        for p in [ShPrecision::F32, ShPrecision::F16] {
            let b = Baked::from_scene(&scene(3, 7), &fmt, p);
            let back = Baked::from_bytes(&b.to_bytes(), Path::new("x.bake")).unwrap();
            assert_eq!(back, b);
            assert!(back.matches(&fmt));
        }
        for o in [0.0f32, 0.003, 0.5, 0.999, 1.0] {
            let k2 = bake_k2(o, &fmt) as f64;
            let o2 = (o as f64).max(fmt.opacity.dequantize(fmt.opacity.quantize(o as f64)));
            assert!(k2 >= fmt.cutoff.radius_squared(o2), "{o}");
        }
        assert_eq!(f16_bits(-1.0), 0xBC00);
        let b = Baked::from_scene(&scene(1, 2), &fmt, ShPrecision::F16);
        let v = scene(1, 2).sh[1];
        assert!((b.sh_value(0, 1) - v).abs() <= 2f32.powi(-12) && b.sh_value(0, 1) != v);
        let b = Baked::from_scene(&scene(1, 2), &fmt, ShPrecision::F32);
        assert_eq!(b.sh_value(0, 1), v);
    }

    #[test]
    fn errors_name_the_file_and_field() {
        let b = Baked::from_scene(&scene(2, 3), &FeatureFormat::default(), ShPrecision::F32);
        let bytes = b.to_bytes();
        let msg = |bytes: &[u8]| Baked::from_bytes(bytes, Path::new("s.bake")).unwrap_err().to_string();
        assert!(msg(&bytes[..10]).starts_with("s.bake: truncated header"));
        assert!(msg(&bytes[..bytes.len() - 1]).contains("size:"));
        let mut bad = bytes.clone();
        bad[12] = 4;
        assert!(msg(&bad).contains("sh_degree"));
        let mut bad = bytes.clone();
        // Gaussian 1's opacity.
        let o = HEADER_BYTES + 44 + 36;
        bad[o..o + 4].copy_from_slice(&2.0f32.to_le_bytes());
        assert_eq!(msg(&bad), "s.bake: gaussian 1: opacity: 2 is outside [0, 1]");
        let mut bad = bytes;
        bad[0] = b'X';
        assert!(msg(&bad).contains("magic"));
    }

    proptest! {
        #[test]
        fn the_reader_never_panics(bytes in prop::collection::vec(any::<u8>(), 0..400), header in any::<bool>()) {
            let mut bytes = bytes;
            if header && bytes.len() >= HEADER_BYTES {
                let b = Baked::from_scene(&scene(0, 1), &FeatureFormat::default(), ShPrecision::F16);
                bytes[..HEADER_BYTES].copy_from_slice(&b.to_bytes()[..HEADER_BYTES]);
                let n = ((bytes.len() - HEADER_BYTES) / 50) as u64;
                bytes[24..32].copy_from_slice(&n.to_le_bytes());
            }
            let _ = Baked::from_bytes(&bytes, Path::new("f.bake"));
        }

        #[test]
        fn a_flipped_byte_is_rejected_or_read_back(pos in 0usize..(HEADER_BYTES + 2 * 68), v in any::<u8>()) {
            let b = Baked::from_scene(&scene(1, 2), &FeatureFormat::default(), ShPrecision::F16);
            let mut bytes = b.to_bytes();
            bytes[pos] = v;
            if let Ok(r) = Baked::from_bytes(&bytes, Path::new("f.bake")) {
                prop_assert_eq!(r.to_bytes(), bytes);
            }
        }
    }
}
