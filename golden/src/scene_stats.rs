//! Scene statistics for `neo scene info`: counts, bounds, and the distributions of opacity,
//! scale and anisotropy. [`SceneStats`] serialises to JSON and displays as a text table.

use crate::scene::{LoadReport, Scene};
use std::fmt;

/// Distribution summary of one quantity over all Gaussians. Percentiles interpolate linearly
/// between the closest ranks of the sorted values (the numpy default). All zeros when empty.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct Summary {
    /// Smallest value.
    pub min: f32,
    /// 5th percentile.
    pub p5: f32,
    /// Median.
    pub median: f32,
    /// 95th percentile.
    pub p95: f32,
    /// Largest value.
    pub max: f32,
    /// Arithmetic mean (accumulated in `f64`).
    pub mean: f32,
}

impl Summary {
    /// Summarises `values` (sorted in place; NaNs sort last and should not be present).
    pub fn of(values: &mut [f32]) -> Summary {
        if values.is_empty() {
            return Summary::default();
        }
        values.sort_unstable_by(f32::total_cmp);
        let mean = values.iter().map(|&v| v as f64).sum::<f64>() / values.len() as f64;
        Summary {
            min: values[0],
            p5: percentile(values, 0.05),
            median: percentile(values, 0.5),
            p95: percentile(values, 0.95),
            max: values[values.len() - 1],
            mean: mean as f32,
        }
    }
}

/// The `q`-quantile (0..=1) of sorted, non-empty `sorted`, linearly interpolated.
pub fn percentile(sorted: &[f32], q: f64) -> f32 {
    let pos = q.clamp(0.0, 1.0) * (sorted.len() - 1) as f64;
    let lo = pos.floor() as usize;
    let hi = (lo + 1).min(sorted.len() - 1);
    let t = pos - lo as f64;
    (sorted[lo] as f64 * (1.0 - t) + sorted[hi] as f64 * t) as f32
}

/// Statistics of a loaded scene.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct SceneStats {
    /// Gaussians in the scene (after dropping non-finite ones).
    pub count: usize,
    /// SH degree (0..=3).
    pub sh_degree: u8,
    /// Gaussians dropped at load because a property was NaN or infinite.
    pub dropped_non_finite: usize,
    /// Gaussians whose opacity logit was infinite (opacity exactly 0 or 1).
    pub infinite_opacity: usize,
    /// Per-axis minimum of the means.
    pub bounds_min: [f32; 3],
    /// Per-axis maximum of the means.
    pub bounds_max: [f32; 3],
    /// Per-axis 1st percentile of the means (bounds without far outliers).
    pub bounds_p1: [f32; 3],
    /// Per-axis 99th percentile of the means.
    pub bounds_p99: [f32; 3],
    /// Activated opacity in [0, 1].
    pub opacity: Summary,
    /// Fraction of Gaussians with opacity below 1/255 (they can never pass the reference
    /// rasterizer's alpha >= 1/255 test, so they never contribute).
    pub opacity_below_1_255: f64,
    /// Fraction with opacity above 0.99 (the rasterizer clamps alpha to 0.99).
    pub opacity_above_0_99: f64,
    /// Largest of the three standard deviations of each Gaussian.
    pub scale_max_axis: Summary,
    /// Smallest of the three standard deviations of each Gaussian.
    pub scale_min_axis: Summary,
    /// Anisotropy: largest over smallest standard deviation (the smallest is clamped to
    /// `f32::MIN_POSITIVE` so the ratio stays finite).
    pub anisotropy: Summary,
}

impl SceneStats {
    /// Computes the statistics of `scene`; `report` supplies the load counts.
    pub fn of(scene: &Scene, report: &LoadReport) -> SceneStats {
        let n = scene.len();
        let (bounds_min, bounds_max) = scene.bounds();
        let mut bounds_p1 = [0.0; 3];
        let mut bounds_p99 = [0.0; 3];
        if n > 0 {
            for a in 0..3 {
                let mut axis: Vec<f32> = scene.positions.iter().map(|p| p[a]).collect();
                axis.sort_unstable_by(f32::total_cmp);
                bounds_p1[a] = percentile(&axis, 0.01);
                bounds_p99[a] = percentile(&axis, 0.99);
            }
        }
        let fraction = |pred: &dyn Fn(f32) -> bool| {
            if n == 0 {
                0.0
            } else {
                scene.opacities.iter().filter(|&&o| pred(o)).count() as f64 / n as f64
            }
        };
        let opacity_below_1_255 = fraction(&|o| o < 1.0 / 255.0);
        let opacity_above_0_99 = fraction(&|o| o > 0.99);
        let max_axis = |s: &[f32; 3]| s[0].max(s[1]).max(s[2]);
        let min_axis = |s: &[f32; 3]| s[0].min(s[1]).min(s[2]);
        let mut scale_max: Vec<f32> = scene.scales.iter().map(max_axis).collect();
        let mut scale_min: Vec<f32> = scene.scales.iter().map(min_axis).collect();
        let mut aniso: Vec<f32> =
            scene.scales.iter().map(|s| max_axis(s) / min_axis(s).max(f32::MIN_POSITIVE)).collect();
        SceneStats {
            count: n,
            sh_degree: scene.sh_degree,
            dropped_non_finite: report.dropped_non_finite,
            infinite_opacity: report.infinite_opacity,
            bounds_min,
            bounds_max,
            bounds_p1,
            bounds_p99,
            opacity: Summary::of(&mut scene.opacities.clone()),
            opacity_below_1_255,
            opacity_above_0_99,
            scale_max_axis: Summary::of(&mut scale_max),
            scale_min_axis: Summary::of(&mut scale_min),
            anisotropy: Summary::of(&mut aniso),
        }
    }
}

/// A number in a fixed-width column: plain decimals for ordinary magnitudes, scientific otherwise.
fn num(v: f32) -> String {
    let a = v.abs();
    if a == 0.0 || (1e-3..1e5).contains(&a) {
        format!("{v:.4}")
    } else {
        format!("{v:.3e}")
    }
}

impl fmt::Display for SceneStats {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "{:<22}{} (SH degree {})", "Gaussians", self.count, self.sh_degree)?;
        writeln!(f, "{:<22}{}", "dropped (non-finite)", self.dropped_non_finite)?;
        writeln!(f, "{:<22}{}", "infinite opacity", self.infinite_opacity)?;
        writeln!(f, "{:<22}{:>12}{:>12}{:>12}{:>12}", "bounds", "min", "p1", "p99", "max")?;
        for (a, axis) in ["x", "y", "z"].iter().enumerate() {
            writeln!(
                f,
                "  {:<20}{:>12}{:>12}{:>12}{:>12}",
                axis,
                num(self.bounds_min[a]),
                num(self.bounds_p1[a]),
                num(self.bounds_p99[a]),
                num(self.bounds_max[a])
            )?;
        }
        writeln!(
            f,
            "{:<22}{:>12}{:>12}{:>12}{:>12}{:>12}{:>12}",
            "", "min", "p5", "median", "p95", "max", "mean"
        )?;
        let rows = [
            ("opacity", &self.opacity),
            ("scale (largest axis)", &self.scale_max_axis),
            ("scale (smallest axis)", &self.scale_min_axis),
            ("anisotropy max/min", &self.anisotropy),
        ];
        for (name, s) in rows {
            writeln!(
                f,
                "{:<22}{:>12}{:>12}{:>12}{:>12}{:>12}{:>12}",
                name,
                num(s.min),
                num(s.p5),
                num(s.median),
                num(s.p95),
                num(s.max),
                num(s.mean)
            )?;
        }
        writeln!(f, "{:<22}{:.2}%", "opacity < 1/255", 100.0 * self.opacity_below_1_255)?;
        write!(f, "{:<22}{:.2}%", "opacity > 0.99", 100.0 * self.opacity_above_0_99)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Five Gaussians along x with hand-picked opacities and scales.
    fn scene() -> Scene {
        Scene {
            positions: vec![
                [0.0, 0.0, -1.0],
                [1.0, 5.0, 0.0],
                [2.0, 0.0, 0.0],
                [3.0, 0.0, 0.0],
                [4.0, -5.0, 1.0],
            ],
            scales: vec![[1.0, 1.0, 1.0], [2.0, 1.0, 0.5], [0.1, 0.1, 0.4], [3.0, 3.0, 3.0], [8.0, 0.5, 1.0]],
            rotations: vec![[1.0, 0.0, 0.0, 0.0]; 5],
            opacities: vec![0.0, 0.001, 0.5, 0.995, 1.0],
            sh_degree: 0,
            sh: vec![0.0; 15],
        }
    }

    #[test]
    fn percentiles_interpolate_between_ranks() {
        let v = [10.0, 20.0, 30.0, 40.0, 50.0];
        assert_eq!(percentile(&v, 0.0), 10.0);
        assert_eq!(percentile(&v, 0.5), 30.0);
        assert_eq!(percentile(&v, 1.0), 50.0);
        // Position 0.05 * 4 = 0.2 between 10 and 20.
        assert!((percentile(&v, 0.05) - 12.0).abs() < 1e-5);
        assert!((percentile(&v, 0.95) - 48.0).abs() < 1e-5);
        assert_eq!(Summary::of(&mut []), Summary::default());
    }

    #[test]
    fn stats_of_a_hand_made_scene() {
        let report = LoadReport { dropped_non_finite: 2, infinite_opacity: 2 };
        let s = SceneStats::of(&scene(), &report);
        assert_eq!((s.count, s.sh_degree, s.dropped_non_finite, s.infinite_opacity), (5, 0, 2, 2));
        assert_eq!(s.bounds_min, [0.0, -5.0, -1.0]);
        assert_eq!(s.bounds_max, [4.0, 5.0, 1.0]);
        // x sorted 0..4: p1 at position 0.04, p99 at 3.96.
        assert!((s.bounds_p1[0] - 0.04).abs() < 1e-6 && (s.bounds_p99[0] - 3.96).abs() < 1e-6);
        assert_eq!((s.opacity.min, s.opacity.median, s.opacity.max), (0.0, 0.5, 1.0));
        assert!((s.opacity.mean - 2.496 / 5.0).abs() < 1e-6);
        // 0 and 0.001 are below 1/255 = 0.0039; 0.995 and 1 are above 0.99.
        assert_eq!((s.opacity_below_1_255, s.opacity_above_0_99), (0.4, 0.4));
        // Largest axes 1, 2, 0.4, 3, 8; smallest 1, 0.5, 0.1, 3, 0.5; ratios 1, 4, 4, 1, 16.
        assert_eq!((s.scale_max_axis.min, s.scale_max_axis.median, s.scale_max_axis.max), (0.4, 2.0, 8.0));
        assert_eq!((s.scale_min_axis.min, s.scale_min_axis.median, s.scale_min_axis.max), (0.1, 0.5, 3.0));
        assert_eq!((s.anisotropy.min, s.anisotropy.median, s.anisotropy.max), (1.0, 4.0, 16.0));
        assert!((s.anisotropy.mean - 26.0 / 5.0).abs() < 1e-5);
        // p95 at position 3.8 of [1, 1, 4, 4, 16]: 4 + 0.8 * 12.
        assert!((s.anisotropy.p95 - 13.6).abs() < 1e-5);
    }

    #[test]
    fn display_and_json_show_the_numbers() {
        let s = SceneStats::of(&scene(), &LoadReport::default());
        let text = s.to_string();
        assert!(text.starts_with("Gaussians             5 (SH degree 0)\n"), "{text}");
        assert!(text.lines().any(|l| l.starts_with("anisotropy max/min") && l.contains("16.0000")), "{text}");
        assert!(text.contains("opacity < 1/255       40.00%"), "{text}");
        let json = serde_json::to_value(&s).unwrap();
        assert_eq!(json["count"], 5);
        assert_eq!(json["anisotropy"]["max"], 16.0);
        let empty = SceneStats::of(&Scene::default(), &LoadReport::default());
        assert_eq!(empty.count, 0);
        assert_eq!(empty.opacity, Summary::default());
        assert!(empty.to_string().contains("Gaussians             0"));
    }
}
