//! PSNR and SSIM agree with scikit-image 0.26 on real images.
//!
//! The expected values were computed once with
//! `skimage.metrics.structural_similarity(a, b, channel_axis=-1, data_range=255,
//! gaussian_weights=True, sigma=1.5, use_sample_covariance=False)` and
//! `peak_signal_noise_ratio(a, b, data_range=255)` on pairs of the shared reference renders
//! (which are different views, so the scores are far from the identical-image limits).

use neo_golden::image::Rgb8Image;
use neo_golden::metrics::{psnr, ssim};
use neo_golden::shared::shared_file_for_test;

#[test]
fn metrics_match_scikit_image() {
    let cases = [
        ("front", "left", 0.844_542_397_3, 22.440_799_810_0),
        ("left", "three_quarter", 0.840_496_155_0, 21.894_767_934_1),
        ("three_quarter", "close", 0.650_511_478_9, 18.857_990_389_5),
    ];
    for (a, b, want_ssim, want_psnr) in cases {
        let test = "metrics_match_scikit_image";
        let Some(pa) = shared_file_for_test(test, &format!("scenes/biker_ref_{a}.png")) else { return };
        let Some(pb) = shared_file_for_test(test, &format!("scenes/biker_ref_{b}.png")) else { return };
        let (ia, ib) = (Rgb8Image::read_png(&pa).unwrap(), Rgb8Image::read_png(&pb).unwrap());
        let s = ssim(&ia, &ib).unwrap();
        let p = psnr(&ia, &ib).unwrap();
        assert!((s - want_ssim).abs() < 1e-9, "{a} vs {b}: SSIM {s} != scikit-image {want_ssim}");
        assert!((p - want_psnr).abs() < 1e-9, "{a} vs {b}: PSNR {p} != scikit-image {want_psnr}");
    }
}
