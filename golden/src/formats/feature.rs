//! The feature table entry: everything the Rasterization Engine reads of one Gaussian, quantised
//! once from the float preprocessing ([`Projected`]).
//!
//! # Fields (see docs/formats.md for the default widths and why)
//! - `mean`: 2D mean in pixels, signed fixed point ([`FeatureFormat::mean`]); saturates.
//! - `conic`: block floating point ([`ConicFormat`]).
//! - `opacity`: unsigned fraction ([`FeatureFormat::opacity`], values below 1; 1.0 saturates to
//!   the largest value, which the 0.99 alpha cap makes harmless for 7 or more fraction bits).
//! - `rgb`: unsigned fixed point with integer bits (SH colours may exceed 1).
//! - `depth_key`: the sort key of the depth, from a [`DepthKeyCodec`] (for the deferred depth
//!   update).
//! - ITU data, describing a conservative octagon around the cutoff ellipse
//!   `{d : d^T cov^-1 d <= k^2}` (`k` from [`Cutoff`]):
//!   - `extent_xy`: the ellipse's half-extents along x and y (its AABB), in pixels;
//!   - `axis`: a quantised direction `U = (C, S) ~ 2^axis.frac (cos t, sin t)` of the major axis
//!     (`V = (-S, C)` is exactly orthogonal);
//!   - `extent_uv`: the ellipse's support along `U` and `V` divided by `2^axis.frac`, in pixels.
//!
//!   Every extent is rounded up, and includes the rounding error of the mean, so it bounds the
//!   exact (f64) ellipse around the *float* mean as seen from the *quantised* mean. The largest
//!   raw value of an extent field means "unbounded": the ITU never separates on that axis.
//!
//! # Bit layout (RTL ports and DRAM)
//! Fields are packed LSB first in the order of [`FeatureFormat::layout`]:
//! `mean_x, mean_y, conic_a, conic_b, conic_c, conic_exp, opacity, red, green, blue,
//! extent_x, extent_y, axis_c, axis_s, extent_u, extent_v, depth_key`, each in its format's
//! width, signed fields in two's complement. As words: bit `i` of the entry is bit `i % 64` of
//! word `i / 64`. In DRAM an entry takes [`FeatureFormat::bytes_per_entry`] bytes, the bit
//! vector in little-endian byte order with unused high bits zero.

use super::conic::{ConicFormat, QuantConic};
use super::fixed::{FormatError, QFormat};
use crate::render::Projected;
use crate::sort::DepthKeyCodec;

/// How far the ITU's ellipse reaches: its squared Mahalanobis radius `k^2`.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub enum Cutoff {
    /// A fixed `k` sigma (the paper's 3-sigma ellipse is `Sigma(3.0)`).
    Sigma(f32),
    /// Where `opacity * exp(-k^2 / 2)` falls to `1/255`, plus `margin` in power units:
    /// `k^2 = 2 (ln(255 * opacity) + margin)`, clamped at 0. The opacity is the larger of the
    /// float and the quantised one. This is exactly the set of pixels where the blend can reach
    /// `alpha >= 1/255` (up to the margin, which absorbs the fixed-point errors): it is up to
    /// 3.33 sigma for opaque Gaussians and shrinks for faint ones.
    Alpha {
        /// Extra `-power` allowed beyond the ideal cutoff.
        margin: f32,
    },
}

impl Cutoff {
    /// `k^2` for a Gaussian of opacity `opacity` (the cutoff radius squared, in sigmas).
    pub fn radius_squared(&self, opacity: f64) -> f64 {
        match *self {
            Cutoff::Sigma(k) => (k as f64) * (k as f64),
            Cutoff::Alpha { margin } => {
                let v = 2.0 * ((255.0 * opacity).ln() + margin as f64);
                if v.is_nan() {
                    f64::INFINITY
                } else {
                    v.max(0.0)
                }
            }
        }
    }
}

/// Widths of every field of a feature entry. Construct with [`FeatureFormat::default`] or
/// [`FeatureFormat::fitted`] and validate custom ones with [`FeatureFormat::check`]; the
/// quantiser, ITU and SCU assume a checked format.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct FeatureFormat {
    /// Mean (pixels), signed.
    pub mean: QFormat,
    /// Conic, block floating point.
    pub conic: ConicFormat,
    /// Opacity, unsigned, `int_bits() == 0` (values below 1).
    pub opacity: QFormat,
    /// Each colour channel, unsigned.
    pub color: QFormat,
    /// Width of the depth-key field; must equal the codec's `key_bits()`.
    pub depth_key_bits: u8,
    /// The ITU axis `(C, S)`, signed; `frac` sets the angular resolution, and it needs at least
    /// one integer bit (`C` or `S` may be `+-2^frac`).
    pub axis: QFormat,
    /// ITU extents (pixels), unsigned; the largest raw value means "unbounded".
    pub extent: QFormat,
    /// The ITU's ellipse.
    pub cutoff: Cutoff,
}

impl Default for FeatureFormat {
    /// The defaults justified in docs/formats.md: mean signed Q19.8 (28 bits, +-2^19 px), conic
    /// 18-bit mantissas with a 6-bit exponent, opacity 0.8, colour 1.10, FP16 depth key, axis
    /// with 8 fraction bits, extents 13.2 (15 bits), `Cutoff::Alpha { margin: 0.05 }`.
    fn default() -> Self {
        FeatureFormat {
            mean: QFormat::signed(28, 8),
            conic: ConicFormat::default(),
            opacity: QFormat::unsigned(8, 8),
            color: QFormat::unsigned(11, 10),
            depth_key_bits: 16,
            axis: QFormat::signed(10, 8),
            extent: QFormat::unsigned(15, 2),
            cutoff: Cutoff::Alpha { margin: 0.05 },
        }
    }
}

/// One field of the packed entry: name, first bit and width.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub struct FieldLayout {
    /// Field name (as in the RTL).
    pub name: &'static str,
    /// Bit position of the field's LSB in the entry.
    pub lsb: u32,
    /// Width in bits.
    pub width: u32,
}

/// A quantised feature-table entry (raw integers; see the module doc for their meaning).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, serde::Serialize)]
pub struct FeatureEntry {
    /// Mean `[x, y]`, raw in [`FeatureFormat::mean`].
    pub mean: [i32; 2],
    /// Conic mantissas and exponent.
    pub conic: QuantConic,
    /// Opacity, raw in [`FeatureFormat::opacity`].
    pub opacity: i32,
    /// Colour `[r, g, b]`, raw in [`FeatureFormat::color`].
    pub rgb: [i32; 3],
    /// Depth key.
    pub depth_key: u32,
    /// ITU axis `[C, S]`, raw in [`FeatureFormat::axis`].
    pub axis: [i32; 2],
    /// Support of the ellipse along `U` and `V` over `2^axis.frac`, raw in
    /// [`FeatureFormat::extent`] (max = unbounded).
    pub extent_uv: [i32; 2],
    /// Half-extents along x and y, raw in [`FeatureFormat::extent`] (max = unbounded).
    pub extent_xy: [i32; 2],
}

/// Field names in packing order (LSB first).
const FIELD_NAMES: [&str; 17] = [
    "mean_x",
    "mean_y",
    "conic_a",
    "conic_b",
    "conic_c",
    "conic_exp",
    "opacity",
    "red",
    "green",
    "blue",
    "extent_x",
    "extent_y",
    "axis_c",
    "axis_s",
    "extent_u",
    "extent_v",
    "depth_key",
];

impl FeatureFormat {
    /// Checks every field and the constraints between them: the ITU works in units of
    /// `2^-(mean.frac + 1)` pixels, so `extent.frac <= mean.frac + 1`; the axis needs an
    /// integer bit; the opacity has no integer bits; the SCU's conic-to-power shift is computed
    /// by [`crate::raster::RasterConfig::check`].
    pub fn check(&self) -> Result<(), FormatError> {
        self.mean.check("mean")?;
        self.conic.check()?;
        self.opacity.check("opacity")?;
        self.color.check("color")?;
        self.axis.check("axis")?;
        self.extent.check("extent")?;
        if !self.mean.signed || self.mean.int_bits() < 1 || self.mean.frac > 16 {
            return Err(FormatError::new(
                "mean",
                "must be signed with >= 1 integer bit and <= 16 fraction bits",
            ));
        }
        if self.opacity.signed || self.opacity.int_bits() != 0 || self.opacity.frac < 7 {
            return Err(FormatError::new("opacity", "must be unsigned, all fraction, >= 7 bits"));
        }
        if self.color.signed || self.color.frac < 1 {
            return Err(FormatError::new("color", "must be unsigned with >= 1 fraction bit"));
        }
        if !self.axis.signed || self.axis.int_bits() < 1 || self.axis.frac > 16 {
            return Err(FormatError::new(
                "axis",
                "must be signed with >= 1 integer bit and <= 16 fraction bits",
            ));
        }
        if self.extent.signed || self.extent.frac > self.mean.frac + 1 || self.extent.bits > 24 {
            return Err(FormatError::new(
                "extent",
                "must be unsigned, <= 24 bits, with at most mean.frac + 1 fraction bits",
            ));
        }
        if !(1..=32).contains(&self.depth_key_bits) {
            return Err(FormatError::new(
                "depth_key_bits",
                format!("{} is outside 1..=32", self.depth_key_bits),
            ));
        }
        match self.cutoff {
            Cutoff::Sigma(k) if !(k.is_finite() && k > 0.0) => {
                Err(FormatError::new("cutoff", format!("sigma {k} is not a positive number")))
            }
            Cutoff::Alpha { margin } if !(margin.is_finite() && margin >= 0.0) => {
                Err(FormatError::new("cutoff", format!("margin {margin} is not a non-negative number")))
            }
            _ => Ok(()),
        }
    }

    /// The packed layout, LSB first (see the module doc).
    pub fn layout(&self) -> Vec<FieldLayout> {
        let m = self.conic.mantissa_bits as u32;
        let widths = [
            self.mean.bits as u32,
            self.mean.bits as u32,
            m,
            m + 1,
            m,
            self.conic.exp_bits as u32,
            self.opacity.bits as u32,
            self.color.bits as u32,
            self.color.bits as u32,
            self.color.bits as u32,
            self.extent.bits as u32,
            self.extent.bits as u32,
            self.axis.bits as u32,
            self.axis.bits as u32,
            self.extent.bits as u32,
            self.extent.bits as u32,
            self.depth_key_bits as u32,
        ];
        let mut lsb = 0;
        FIELD_NAMES
            .iter()
            .zip(widths)
            .map(|(&name, width)| {
                let f = FieldLayout { name, lsb, width };
                lsb += width;
                f
            })
            .collect()
    }

    /// Bits of one packed entry.
    pub fn bits_per_entry(&self) -> u32 {
        self.layout().iter().map(|f| f.width).sum()
    }

    /// Bytes of one entry in DRAM (whole bytes): `ceil(bits_per_entry / 8)`.
    pub fn bytes_per_entry(&self) -> u32 {
        self.bits_per_entry().div_ceil(8)
    }

    /// 64-bit words of one packed entry: `ceil(bits_per_entry / 64)`.
    pub fn words_per_entry(&self) -> usize {
        self.bits_per_entry().div_ceil(64) as usize
    }

    /// The extent raw value that means "unbounded".
    pub fn unbounded_extent(&self) -> i32 {
        self.extent.max_raw() as i32
    }
}

/// Quantises one preprocessed Gaussian. `key` encodes the depth; its `key_bits()` must equal
/// `fmt.depth_key_bits` (panics otherwise: that is a configuration error, not bad data).
/// Never panics on any float values (NaN saturates as documented per field).
pub fn quantize(p: &Projected, fmt: &FeatureFormat, key: &DepthKeyCodec) -> FeatureEntry {
    assert_eq!(
        key.key_bits(),
        fmt.depth_key_bits,
        "depth key codec width {} != FeatureFormat::depth_key_bits {}",
        key.key_bits(),
        fmt.depth_key_bits
    );
    let mean = p.mean2d.map(|v| fmt.mean.quantize(v as f64));
    let dm = [0, 1].map(|i| p.mean2d[i] as f64 - fmt.mean.dequantize(mean[i]));
    let opacity = fmt.opacity.quantize(p.opacity as f64);
    let rgb = p.rgb.map(|v| fmt.color.quantize(v as f64) as i32);
    let conic = fmt.conic.quantize(p.conic);

    // ITU geometry, in f64 from the float covariance.
    let o = (p.opacity as f64).max(fmt.opacity.dequantize(opacity));
    let k2 = fmt.cutoff.radius_squared(o);
    let [sxx, sxy, syy] = p.cov2d.map(f64::from);
    let theta = 0.5 * (2.0 * sxy).atan2(sxx - syy);
    let axis = [fmt.axis.quantize(theta.cos()), fmt.axis.quantize(theta.sin())];
    let (c, s) = (axis[0] as f64, axis[1] as f64);
    // Support of the ellipse around the float mean along direction n, seen from the quantised
    // mean: k sqrt(n^T cov n) + (m - m_q) . n, rounded up with a relative margin for f64 rounding.
    let support = |nx: f64, ny: f64| {
        let var = nx * nx * sxx + 2.0 * nx * ny * sxy + ny * ny * syy;
        let s = (k2 * var.max(0.0)).sqrt() + (dm[0] * nx + dm[1] * ny).abs();
        s * (1.0 + 1e-9)
    };
    let scale = (-(fmt.axis.frac as f64)).exp2();
    let ext = |v: f64| fmt.extent.quantize_ceil(v) as i32;
    FeatureEntry {
        mean: mean.map(|v| v as i32),
        conic,
        opacity: opacity as i32,
        rgb,
        depth_key: key.encode(p.depth),
        axis: axis.map(|v| v as i32),
        extent_uv: [ext(support(c, s) * scale), ext(support(-s, c) * scale)],
        extent_xy: [ext(support(1.0, 0.0)), ext(support(0.0, 1.0))],
    }
}

impl FeatureEntry {
    /// Packs the entry into `fmt.words_per_entry()` little-endian 64-bit words (see the module
    /// doc for the layout). Raw values are masked to their field widths.
    pub fn pack(&self, fmt: &FeatureFormat) -> Vec<u64> {
        let mut words = vec![0u64; fmt.words_per_entry()];
        for (f, v) in fmt.layout().iter().zip(self.field_values(fmt)) {
            put_bits(&mut words, f.lsb, f.width, v);
        }
        words
    }

    /// Unpacks an entry packed by [`FeatureEntry::pack`]; missing words read as zero, extra
    /// bits are ignored.
    pub fn unpack(words: &[u64], fmt: &FeatureFormat) -> FeatureEntry {
        let v: Vec<u64> = fmt.layout().iter().map(|f| get_bits(words, f.lsb, f.width)).collect();
        let m = QFormat::unsigned(fmt.conic.mantissa_bits, 0);
        let b = QFormat::signed(fmt.conic.mantissa_bits + 1, 0);
        let mean = |x: u64| fmt.mean.from_field(x) as i32;
        let col = |x: u64| fmt.color.from_field(x) as i32;
        let axis = |x: u64| fmt.axis.from_field(x) as i32;
        let ext = |x: u64| fmt.extent.from_field(x) as i32;
        FeatureEntry {
            mean: [mean(v[0]), mean(v[1])],
            conic: QuantConic {
                a: m.from_field(v[2]) as i32,
                b: b.from_field(v[3]) as i32,
                c: m.from_field(v[4]) as i32,
                exp: v[5] as u32,
            },
            opacity: fmt.opacity.from_field(v[6]) as i32,
            rgb: [col(v[7]), col(v[8]), col(v[9])],
            extent_xy: [ext(v[10]), ext(v[11])],
            axis: [axis(v[12]), axis(v[13])],
            extent_uv: [ext(v[14]), ext(v[15])],
            depth_key: v[16] as u32,
        }
    }

    /// The field values as unsigned bit fields, in layout order.
    fn field_values(&self, fmt: &FeatureFormat) -> [u64; 17] {
        let m = QFormat::unsigned(fmt.conic.mantissa_bits, 0);
        let b = QFormat::signed(fmt.conic.mantissa_bits + 1, 0);
        let e = QFormat::unsigned(fmt.conic.exp_bits, 0);
        let mean = |x: i32| fmt.mean.to_field(x as i64);
        let col = |x: i32| fmt.color.to_field(x as i64);
        let axis = |x: i32| fmt.axis.to_field(x as i64);
        let ext = |x: i32| fmt.extent.to_field(x as i64);
        let key_mask = if fmt.depth_key_bits >= 32 { u32::MAX } else { (1u32 << fmt.depth_key_bits) - 1 };
        [
            mean(self.mean[0]),
            mean(self.mean[1]),
            m.to_field(self.conic.a as i64),
            b.to_field(self.conic.b as i64),
            m.to_field(self.conic.c as i64),
            e.to_field(self.conic.exp as i64),
            fmt.opacity.to_field(self.opacity as i64),
            col(self.rgb[0]),
            col(self.rgb[1]),
            col(self.rgb[2]),
            ext(self.extent_xy[0]),
            ext(self.extent_xy[1]),
            axis(self.axis[0]),
            axis(self.axis[1]),
            ext(self.extent_uv[0]),
            ext(self.extent_uv[1]),
            (self.depth_key & key_mask) as u64,
        ]
    }

    /// The mean in pixels.
    pub fn mean_px(&self, fmt: &FeatureFormat) -> [f64; 2] {
        self.mean.map(|v| fmt.mean.dequantize(v as i64))
    }

    /// The conic `[a, b, c]`.
    pub fn conic_f64(&self, fmt: &FeatureFormat) -> [f64; 3] {
        fmt.conic.dequantize(&self.conic)
    }

    /// The opacity.
    pub fn opacity_f64(&self, fmt: &FeatureFormat) -> f64 {
        fmt.opacity.dequantize(self.opacity as i64)
    }

    /// The colour.
    pub fn rgb_f64(&self, fmt: &FeatureFormat) -> [f64; 3] {
        self.rgb.map(|v| fmt.color.dequantize(v as i64))
    }
}

/// Writes the low `width` bits of `v` at bit `lsb` of `words` (LSB-first words).
fn put_bits(words: &mut [u64], lsb: u32, width: u32, v: u64) {
    let v = if width >= 64 { v } else { v & ((1u64 << width) - 1) };
    let (w, o) = ((lsb / 64) as usize, lsb % 64);
    words[w] |= v << o;
    if o + width > 64 {
        words[w + 1] |= v >> (64 - o);
    }
}

/// Reads `width` bits at bit `lsb` of `words`; bits beyond the slice read as zero.
fn get_bits(words: &[u64], lsb: u32, width: u32) -> u64 {
    let (w, o) = ((lsb / 64) as usize, lsb % 64);
    let lo = words.get(w).copied().unwrap_or(0) >> o;
    let hi = if o + width > 64 && o > 0 { words.get(w + 1).copied().unwrap_or(0) << (64 - o) } else { 0 };
    let v = lo | hi;
    if width >= 64 {
        v
    } else {
        v & ((1u64 << width) - 1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_layout_is_contiguous_and_fits_32_bytes() {
        let f = FeatureFormat::default();
        f.check().unwrap();
        let l = f.layout();
        assert_eq!(l.len(), FIELD_NAMES.len());
        for w in l.windows(2) {
            assert_eq!(w[0].lsb + w[0].width, w[1].lsb);
        }
        assert_eq!(f.bits_per_entry(), l.last().map(|x| x.lsb + x.width).unwrap());
        assert!(f.bytes_per_entry() <= 32, "{} bytes", f.bytes_per_entry());
        assert_eq!(f.bytes_per_entry(), f.bits_per_entry().div_ceil(8));
    }

    #[test]
    fn check_rejects_inconsistent_formats() {
        let d = FeatureFormat::default();
        assert!(FeatureFormat { mean: QFormat::unsigned(24, 8), ..d }.check().is_err());
        assert!(FeatureFormat { opacity: QFormat::unsigned(9, 8), ..d }.check().is_err());
        assert!(FeatureFormat { extent: QFormat::unsigned(15, 10), ..d }.check().is_err());
        assert!(FeatureFormat { axis: QFormat::signed(9, 8), ..d }.check().is_err());
        assert!(FeatureFormat { cutoff: Cutoff::Sigma(0.0), ..d }.check().is_err());
        assert!(FeatureFormat { cutoff: Cutoff::Alpha { margin: f32::NAN }, ..d }.check().is_err());
    }

    #[test]
    fn bit_helpers_cross_word_boundaries() {
        let mut w = vec![0u64; 2];
        put_bits(&mut w, 60, 10, 0x3FF);
        assert_eq!(w, vec![0xF << 60, 0x3F]);
        assert_eq!(get_bits(&w, 60, 10), 0x3FF);
        assert_eq!(get_bits(&w, 62, 4), 0xF);
        assert_eq!(get_bits(&[], 5, 7), 0);
    }

    #[test]
    fn cutoff_radius() {
        assert_eq!(Cutoff::Sigma(3.0).radius_squared(0.1), 9.0);
        let a = Cutoff::Alpha { margin: 0.0 };
        assert!((a.radius_squared(1.0) - 2.0 * 255f64.ln()).abs() < 1e-12);
        assert_eq!(a.radius_squared(1.0 / 300.0), 0.0);
        assert_eq!(a.radius_squared(f64::NAN), f64::INFINITY);
    }
}
