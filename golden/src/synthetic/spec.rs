//! `synthetic:NAME?gaussians=N&seed=S&sh=D` spec strings.

use crate::error::{InputError, InputResult};

/// Prefix of every synthetic scene spec.
pub const PREFIX: &str = "synthetic:";
/// Largest accepted Gaussian count.
pub const MAX_GAUSSIANS: usize = 64_000_000;
/// SH degree when the spec has no `sh=` key: 3, as in trained scenes (the Tanks and Temples
/// models of the paper), so that per-Gaussian data and colour evaluation have the real size.
pub const DEFAULT_SH_DEGREE: u8 = 3;

/// Which synthetic scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SceneKind {
    /// A large outdoor-like scene (see [`super::outdoor`]); default 1M Gaussians.
    Outdoor,
    /// Random Gaussians in a box (see [`super::blobs`]); default 1000 Gaussians.
    Blobs,
}

impl SceneKind {
    /// The name used in specs.
    pub fn name(self) -> &'static str {
        match self {
            SceneKind::Outdoor => "outdoor",
            SceneKind::Blobs => "blobs",
        }
    }

    /// Gaussian count when the spec has no `gaussians=` key.
    pub fn default_gaussians(self) -> usize {
        match self {
            SceneKind::Outdoor => 1_000_000,
            SceneKind::Blobs => 1000,
        }
    }
}

/// A parsed synthetic scene spec: everything [`super::generate`] needs.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SyntheticSpec {
    /// The scene.
    pub kind: SceneKind,
    /// Exact number of Gaussians.
    pub gaussians: usize,
    /// Seed: the same spec always generates the same scene.
    pub seed: u64,
    /// SH degree, 0..=3.
    pub sh_degree: u8,
}

impl SyntheticSpec {
    /// The canonical spec string, e.g. `synthetic:outdoor?gaussians=1000000&seed=1&sh=3`.
    pub fn to_spec_string(&self) -> String {
        format!(
            "{PREFIX}{}?gaussians={}&seed={}&sh={}",
            self.kind.name(),
            self.gaussians,
            self.seed,
            self.sh_degree
        )
    }
}

/// True when `s` is a synthetic scene spec rather than a file path.
pub fn is_synthetic(s: &str) -> bool {
    s.starts_with(PREFIX)
}

/// Parses `synthetic:NAME[?KEY=VALUE&...]` with keys `gaussians` (a count with an optional
/// `k`/`K` (thousand) or `m`/`M` (million) suffix, e.g. `10k`, `1.5M`), `seed` (default 1) and
/// `sh` (0..=3, default [`DEFAULT_SH_DEGREE`]). Names: `outdoor`, `blobs`.
pub fn parse_spec(s: &str) -> InputResult<SyntheticSpec> {
    let err = |p: String| InputError::new(s, p);
    let Some(body) = s.strip_prefix(PREFIX) else {
        return Err(err(format!("a synthetic scene spec starts with '{PREFIX}'")));
    };
    let (name, query) = body.split_once('?').unwrap_or((body, ""));
    let kind = match name {
        "outdoor" => SceneKind::Outdoor,
        "blobs" => SceneKind::Blobs,
        _ => return Err(err(format!("unknown synthetic scene '{name}' (known: outdoor, blobs)"))),
    };
    let mut spec =
        SyntheticSpec { kind, gaussians: kind.default_gaussians(), seed: 1, sh_degree: DEFAULT_SH_DEGREE };
    let mut seen: Vec<&str> = Vec::new();
    for item in query.split('&').filter(|i| !i.is_empty()) {
        let Some((k, v)) = item.split_once('=') else {
            return Err(err(format!("'{item}' is not KEY=VALUE")));
        };
        if seen.contains(&k) {
            return Err(err(format!("key '{k}' given twice")));
        }
        seen.push(k);
        match k {
            "gaussians" => spec.gaussians = parse_count(v).map_err(err)?,
            "seed" => {
                spec.seed = v.parse().map_err(|_| err(format!("seed={v}: must be a non-negative integer")))?
            }
            "sh" => {
                spec.sh_degree = match v.parse::<u8>() {
                    Ok(d) if d <= 3 => d,
                    _ => return Err(err(format!("sh={v}: must be an SH degree from 0 to 3"))),
                }
            }
            _ => return Err(err(format!("unknown key '{k}' (accepted: gaussians, seed, sh)"))),
        }
    }
    Ok(spec)
}

/// A Gaussian count such as `1000`, `10k`, `1M` or `1.5M`.
fn parse_count(v: &str) -> Result<usize, String> {
    let bad =
        || format!("gaussians={v}: must be a whole count from 1 to {MAX_GAUSSIANS}, e.g. 5000, 10k or 1M");
    let (num, mult) = match v.char_indices().last() {
        Some((i, 'k' | 'K')) => (&v[..i], 1e3),
        Some((i, 'm' | 'M')) => (&v[..i], 1e6),
        _ => (v, 1.0),
    };
    if num.is_empty() || !num.chars().all(|c| c.is_ascii_digit() || c == '.') {
        return Err(bad());
    }
    let x = num.parse::<f64>().map_err(|_| bad())? * mult;
    let n = x.round();
    if (x - n).abs() > 1e-6 * mult || !(1.0..=MAX_GAUSSIANS as f64).contains(&n) {
        return Err(bad());
    }
    Ok(n as usize)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_with_suffixes() {
        for (s, n) in [
            ("1", 1),
            ("10k", 10_000),
            ("1M", 1_000_000),
            ("4m", 4_000_000),
            ("1.5K", 1500),
            ("2.25M", 2_250_000),
        ] {
            assert_eq!(parse_count(s), Ok(n), "{s}");
        }
        for s in ["", "k", "0", "-5", "1.0001k", "1e3", "65M", "1 k", "1.2.3", "NaN", "inf"] {
            assert!(parse_count(s).is_err(), "{s}");
        }
    }

    #[test]
    fn canonical_string_parses_back() {
        let s = SyntheticSpec { kind: SceneKind::Blobs, gaussians: 77, seed: 9, sh_degree: 2 };
        assert_eq!(parse_spec(&s.to_spec_string()).unwrap(), s);
        let d = parse_spec("synthetic:outdoor").unwrap();
        assert_eq!((d.gaussians, d.seed, d.sh_degree), (1_000_000, 1, DEFAULT_SH_DEGREE));
    }
}
