//! Image quality metrics: PSNR and SSIM (11x11 Gaussian window).
