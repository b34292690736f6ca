//! Image quality metrics on 8-bit RGB images: PSNR and SSIM (11x11 Gaussian window).
//!
//! Both compare two [`Rgb8Image`]s of the same size and treat the three channels alike.
//!
//! SSIM follows Wang, Bovik, Sheikh and Simoncelli (2004) and their reference MATLAB code
//! (`ssim_index.m`): an 11x11 Gaussian window with sigma 1.5 (normalised to sum 1),
//! `K1 = 0.01`, `K2 = 0.03`, dynamic range `L = 255`, Gaussian-weighted (population, not sample)
//! variances, and the SSIM map evaluated only where the window lies fully inside the image (the
//! "valid" region: no padding). The map is averaged per channel and the three channel means are
//! averaged. This equals scikit-image's
//! `structural_similarity(a, b, channel_axis=-1, data_range=255, gaussian_weights=True,
//! sigma=1.5, use_sample_covariance=False)`. It differs slightly from the 3DGS training code's
//! `ssim`, which zero-pads the borders. No automatic down-sampling is applied.

use crate::image::Rgb8Image;

/// Why two images could not be compared.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum MetricError {
    /// The images have different dimensions.
    #[error("image sizes differ: {0}x{1} vs {2}x{3}")]
    SizeMismatch(u32, u32, u32, u32),
    /// An image's buffer does not hold `width * height * 3` bytes.
    #[error("image buffer holds {len} bytes, {width}x{height} RGB needs {}", *width as usize * *height as usize * 3)]
    BadBuffer {
        /// Width in pixels.
        width: u32,
        /// Height in pixels.
        height: u32,
        /// Actual buffer length.
        len: usize,
    },
    /// The images are empty, or too small for the SSIM window.
    #[error("images of {0}x{1} are too small (need at least {2}x{2})")]
    TooSmall(u32, u32, u32),
}

/// SSIM window side.
pub const SSIM_WINDOW: usize = 11;
/// SSIM Gaussian window standard deviation.
pub const SSIM_SIGMA: f64 = 1.5;
/// SSIM stabiliser constant `K1`.
pub const SSIM_K1: f64 = 0.01;
/// SSIM stabiliser constant `K2`.
pub const SSIM_K2: f64 = 0.03;
/// Dynamic range of 8-bit samples.
pub const MAX_VALUE: f64 = 255.0;

fn check_pair(a: &Rgb8Image, b: &Rgb8Image) -> Result<(), MetricError> {
    for img in [a, b] {
        if img.data.len() != img.width as usize * img.height as usize * 3 {
            return Err(MetricError::BadBuffer { width: img.width, height: img.height, len: img.data.len() });
        }
    }
    if (a.width, a.height) != (b.width, b.height) {
        return Err(MetricError::SizeMismatch(a.width, a.height, b.width, b.height));
    }
    Ok(())
}

/// Mean squared error over all pixels and channels, in 8-bit units squared.
pub fn mse(a: &Rgb8Image, b: &Rgb8Image) -> Result<f64, MetricError> {
    check_pair(a, b)?;
    if a.data.is_empty() {
        return Err(MetricError::TooSmall(a.width, a.height, 1));
    }
    let sum: u64 = a
        .data
        .iter()
        .zip(&b.data)
        .map(|(&x, &y)| {
            let d = x as i64 - y as i64;
            (d * d) as u64
        })
        .sum();
    Ok(sum as f64 / a.data.len() as f64)
}

/// Peak signal-to-noise ratio in dB, `10 log10(255^2 / MSE)` with the MSE over all channels.
/// Identical images give `f64::INFINITY`.
pub fn psnr(a: &Rgb8Image, b: &Rgb8Image) -> Result<f64, MetricError> {
    let m = mse(a, b)?;
    if m == 0.0 {
        return Ok(f64::INFINITY);
    }
    Ok(10.0 * (MAX_VALUE * MAX_VALUE / m).log10())
}

/// The normalised 1-D Gaussian window (the 2-D window is its outer product with itself).
fn gaussian_window() -> [f64; SSIM_WINDOW] {
    let mut w = [0.0; SSIM_WINDOW];
    let c = (SSIM_WINDOW / 2) as f64;
    for (i, v) in w.iter_mut().enumerate() {
        let x = i as f64 - c;
        *v = (-x * x / (2.0 * SSIM_SIGMA * SSIM_SIGMA)).exp();
    }
    let s: f64 = w.iter().sum();
    w.map(|v| v / s)
}

/// Structural similarity (see the module documentation for the exact definition). 1 for
/// identical images; needs images of at least 11x11.
pub fn ssim(a: &Rgb8Image, b: &Rgb8Image) -> Result<f64, MetricError> {
    check_pair(a, b)?;
    let (w, h) = (a.width as usize, a.height as usize);
    if w < SSIM_WINDOW || h < SSIM_WINDOW {
        return Err(MetricError::TooSmall(a.width, a.height, SSIM_WINDOW as u32));
    }
    let win = gaussian_window();
    let c1 = (SSIM_K1 * MAX_VALUE).powi(2);
    let c2 = (SSIM_K2 * MAX_VALUE).powi(2);
    let (ow, oh) = (w - SSIM_WINDOW + 1, h - SSIM_WINDOW + 1);
    let mut total = 0.0;
    for ch in 0..3 {
        // Horizontal pass: the five moment images filtered along x, each ow x h.
        let mut horiz = vec![[0.0f64; 5]; ow * h];
        for y in 0..h {
            for ox in 0..ow {
                let mut acc = [0.0f64; 5];
                for (k, &wk) in win.iter().enumerate() {
                    let i = 3 * (y * w + ox + k) + ch;
                    let (x1, y1) = (a.data[i] as f64, b.data[i] as f64);
                    acc[0] += wk * x1;
                    acc[1] += wk * y1;
                    acc[2] += wk * x1 * x1;
                    acc[3] += wk * y1 * y1;
                    acc[4] += wk * x1 * y1;
                }
                horiz[y * ow + ox] = acc;
            }
        }
        // Vertical pass and the SSIM map over the valid region.
        let mut sum = 0.0;
        for oy in 0..oh {
            for ox in 0..ow {
                let mut m = [0.0f64; 5];
                for (k, &wk) in win.iter().enumerate() {
                    let hv = &horiz[(oy + k) * ow + ox];
                    for j in 0..5 {
                        m[j] += wk * hv[j];
                    }
                }
                let (mx, my) = (m[0], m[1]);
                let vx = m[2] - mx * mx;
                let vy = m[3] - my * my;
                let cxy = m[4] - mx * my;
                sum +=
                    ((2.0 * mx * my + c1) * (2.0 * cxy + c2)) / ((mx * mx + my * my + c1) * (vx + vy + c2));
            }
        }
        total += sum / (ow * oh) as f64;
    }
    Ok(total / 3.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A deterministic test pattern with texture (so SSIM is sensitive to noise).
    fn pattern(w: u32, h: u32) -> Rgb8Image {
        let mut img = Rgb8Image::new(w, h);
        for y in 0..h {
            for x in 0..w {
                let i = 3 * (y * w + x) as usize;
                img.data[i] = ((x * 7 + y * 3) % 200 + 20) as u8;
                img.data[i + 1] = (((x / 4 + y / 4) % 2) * 150 + 50) as u8;
                img.data[i + 2] = ((x * y) % 251) as u8;
            }
        }
        img
    }

    /// Adds deterministic pseudo-random noise of amplitude `amp`.
    fn noisy(img: &Rgb8Image, amp: i32, seed: u64) -> Rgb8Image {
        let mut s = seed;
        let mut out = img.clone();
        for v in &mut out.data {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            let r = ((s >> 33) % (2 * amp as u64 + 1)) as i32 - amp;
            *v = (*v as i32 + r).clamp(0, 255) as u8;
        }
        out
    }

    #[test]
    fn psnr_of_constant_offset() {
        let a = pattern(32, 16);
        let mut b = a.clone();
        for v in &mut b.data {
            *v += 1; // pattern values stay <= 250
        }
        let p = psnr(&a, &b).unwrap();
        // 10 log10(255^2) = 48.1308...
        assert!((p - 48.1308).abs() < 1e-3, "{p}");
        assert_eq!(psnr(&a, &a).unwrap(), f64::INFINITY);
        // An offset of 2 everywhere quadruples the MSE: 6.02 dB less.
        let c = Rgb8Image { data: a.data.iter().map(|v| v + 2).collect(), ..a.clone() };
        assert!((psnr(&a, &c).unwrap() - (48.1308 - 6.0206)).abs() < 1e-3);
    }

    #[test]
    fn ssim_identical_is_one_and_decreases_with_noise() {
        let a = pattern(40, 30);
        assert!((ssim(&a, &a).unwrap() - 1.0).abs() < 1e-12);
        let s_small = ssim(&a, &noisy(&a, 5, 1)).unwrap();
        let s_big = ssim(&a, &noisy(&a, 40, 1)).unwrap();
        assert!(s_small < 1.0 && s_big < s_small, "{s_small} {s_big}");
        assert!(s_big > -1.0);
    }

    #[test]
    fn metrics_are_symmetric() {
        let a = pattern(23, 17);
        let b = noisy(&a, 20, 7);
        assert_eq!(psnr(&a, &b).unwrap(), psnr(&b, &a).unwrap());
        assert!((ssim(&a, &b).unwrap() - ssim(&b, &a).unwrap()).abs() < 1e-12);
    }

    #[test]
    fn ssim_of_constant_images_matches_the_formula() {
        // Flat images: variances are 0, so SSIM = (2 m1 m2 + C1) / (m1^2 + m2^2 + C1).
        let a = Rgb8Image { width: 12, height: 11, data: vec![100; 12 * 11 * 3] };
        let b = Rgb8Image { width: 12, height: 11, data: vec![120; 12 * 11 * 3] };
        let c1 = (0.01f64 * 255.0).powi(2);
        let expect = (2.0 * 100.0 * 120.0 + c1) / (100.0f64 * 100.0 + 120.0 * 120.0 + c1);
        assert!((ssim(&a, &b).unwrap() - expect).abs() < 1e-9);
    }

    #[test]
    fn mismatches_are_errors() {
        let a = pattern(20, 20);
        let b = pattern(20, 21);
        assert_eq!(psnr(&a, &b).unwrap_err(), MetricError::SizeMismatch(20, 20, 20, 21));
        assert!(ssim(&a, &b).unwrap_err().to_string().contains("20x20 vs 20x21"));
        let small = pattern(10, 20);
        assert_eq!(ssim(&small, &small).unwrap_err(), MetricError::TooSmall(10, 20, 11));
        let broken = Rgb8Image { width: 2, height: 2, data: vec![0; 5] };
        assert!(matches!(psnr(&broken, &broken), Err(MetricError::BadBuffer { len: 5, .. })));
    }
}
