//! Load-throughput benchmark helper (called by `neo bench`) and its deterministic test data.

use super::{read_raw, write_standard};
use crate::error::{InputError, InputResult};
use crate::scene::RawSplats;
use std::time::Instant;

/// SplitMix64: a tiny deterministic generator, enough for plausible synthetic values.
struct SplitMix(u64);

impl SplitMix {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in `[lo, hi)`.
    fn range(&mut self, lo: f32, hi: f32) -> f32 {
        let u = (self.next() >> 40) as f32 / (1u64 << 24) as f32;
        lo + (hi - lo) * u
    }
}

/// `n` deterministic Gaussians of SH degree `sh_degree` (clamped to 3) with plausible values:
/// positions in a 20-unit cube, log-scales in [-6, 0], logits in [-6, 6], unnormalised rotations.
pub fn bench_splats(n: usize, sh_degree: u8) -> RawSplats {
    let mut rng = SplitMix(0x5EED ^ n as u64);
    let mut raw = RawSplats { sh_degree: sh_degree.min(3), ..Default::default() };
    let rest = raw.rest_per_gaussian();
    for _ in 0..n {
        raw.position.push([(); 3].map(|_| rng.range(-10.0, 10.0)));
        raw.f_dc.push([(); 3].map(|_| rng.range(-2.0, 2.0)));
        raw.opacity.push(rng.range(-6.0, 6.0));
        raw.log_scale.push([(); 3].map(|_| rng.range(-6.0, 0.0)));
        raw.rotation.push([(); 4].map(|_| rng.range(-1.0, 1.0)));
        raw.f_rest.extend((0..rest).map(|_| rng.range(-0.5, 0.5)));
    }
    raw
}

/// Writes an `n`-Gaussian degree-3 standard `.ply` to the temp directory, times [`read_raw`] on
/// it (best of 3), deletes it and returns `(MB/s, file bytes)` with 1 MB = 10^6 bytes.
pub fn bench_load_throughput(n: usize) -> InputResult<(f64, usize)> {
    let path = std::env::temp_dir().join(format!("neo_ply_bench_{}_{n}.ply", std::process::id()));
    let raw = bench_splats(n, 3);
    write_standard(&path, &raw)?;
    drop(raw);
    let bytes = std::fs::metadata(&path).map(|m| m.len() as usize).unwrap_or(0);
    let mut best = f64::INFINITY;
    let mut result = Ok(());
    for _ in 0..3 {
        let t = Instant::now();
        let loaded = read_raw(&path);
        best = best.min(t.elapsed().as_secs_f64());
        match loaded {
            Ok(r) if r.len() == n => {}
            Ok(r) => result = Err(InputError::new(&path, format!("read {} Gaussians, wrote {n}", r.len()))),
            Err(e) => result = Err(e),
        }
    }
    let _ = std::fs::remove_file(&path);
    result.map(|()| (bytes as f64 / 1e6 / best, bytes))
}
