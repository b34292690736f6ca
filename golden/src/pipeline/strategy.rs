//! The sorting strategies the pipeline can run, and what each does per tile and frame.
//!
//! Every strategy runs in the same fixed-point pipeline (same feature table, binning, raster);
//! only the order of each tile's table differs. Frame `s` is a **shot start** when it is frame 0
//! or a scene cut ([`crate::trajectory::Trajectory::cuts`]); every strategy sorts conventionally
//! there, since nothing from before a cut is worth reusing.
//!
//! - [`Strategy::Neo`]: reuse-and-update. DPS of the reused table (keys written back by the
//!   previous frame's raster, so one frame stale), conventional sort of the incoming list
//!   (Gaussians that touch the tile now and are not valid in its table), MSU+ merge dropping
//!   invalid entries; the raster writes the current keys and the ITU valid bits back.
//! - [`Strategy::Full`]: conventional sort of the tile's current list by the current
//!   `(key, id)` every frame: the exact order, the error reference.
//! - [`Strategy::Periodic`]`(K)`: a conventional sort every `K` frames (counted from the shot
//!   start); in between the last order is reused without any re-sorting and without the depth
//!   update: entries that left are removed by their valid bit (as in Neo), and newly visible
//!   Gaussians are sorted by their current key and merged (MSU+) into the stale table, whose
//!   keys stay those of the frame they were sorted or inserted in. This is Neo minus DPS and
//!   minus the depth write-back, which is what a periodic-sorting system on Neo's hardware does
//!   between refreshes (the alternative, appending newcomers at the back, would put every
//!   newly visible Gaussian behind the whole tile and is strictly worse).
//! - [`Strategy::Background`]`(K)`: a background sorter sorts every frame's list exactly; frame
//!   `f` renders with the result for frame `max(f - K, s)` (the order computed from the camera
//!   `K` frames earlier, or from the shot start while fewer than `K` frames have passed): that
//!   table's entries that no longer touch the tile are removed, newly visible ones are sorted
//!   by their current key and merged in (MSU+).
//! - [`Strategy::Hierarchical`]: GSCore's hierarchical sort from scratch every frame (see
//!   [`super::hierarchical`]); its order is exact, its value is the work counters.
//! - [`Strategy::Adaptive`]: Neo with a per-tile choice, each frame, of one or more DPS passes
//!   or a re-sort from scratch, from disorder counted at the write-back, within a per-frame
//!   traffic budget ([`super::adaptive`]).
//! - [`Strategy::Motion`]`(mdeg)`: the web viewers' rule: a full sort whenever the view
//!   direction has turned more than the threshold since the last full sort, `periodic`-style
//!   reuse in between ([`super::adaptive`]).

use std::fmt;
use std::str::FromStr;

use super::adaptive::AdaptiveParams;

/// A sorting strategy (see the module docs). Parses from `neo`, `full`, `periodic:K`,
/// `background:K`, `hierarchical`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Strategy {
    /// Neo's reuse-and-update sorting.
    Neo,
    /// Exact conventional sort every frame.
    Full,
    /// Conventional sort every `K >= 1` frames, reuse in between.
    Periodic(usize),
    /// The exact order of the frame `K >= 1` frames earlier.
    Background(usize),
    /// GSCore's hierarchical sort every frame.
    Hierarchical,
    /// Adaptive reuse-and-update ([`super::adaptive`]).
    Adaptive(AdaptiveParams),
    /// Full sort when the view has turned more than this many millidegrees since the last.
    Motion(u32),
}

impl Strategy {
    /// True when frame `f` of a shot starting at `shot_start` sorts its tables conventionally
    /// from scratch (shot starts, every frame of `full`, refresh frames of `periodic`).
    pub fn full_sort_at(&self, f: usize, shot_start: usize) -> bool {
        match *self {
            Strategy::Full => true,
            Strategy::Periodic(k) => (f - shot_start).is_multiple_of(k.max(1)),
            _ => f == shot_start,
        }
    }

    /// True when the raster writes the current depth keys back into the table (every strategy
    /// except `periodic`, whose keys stay frozen between refreshes). Valid bits are always
    /// written back.
    pub fn writes_back_keys(&self) -> bool {
        !matches!(self, Strategy::Periodic(_) | Strategy::Motion(_))
    }

    /// True when a frame's table is reused by the next frame (so the raster writes it back):
    /// `neo`, and `periodic:K` with `K > 1`.
    pub fn reuses_tables(&self) -> bool {
        match *self {
            Strategy::Neo | Strategy::Adaptive(_) | Strategy::Motion(_) => true,
            Strategy::Periodic(k) => k > 1,
            _ => false,
        }
    }

    /// True when the table's order is the exact order by construction every frame.
    pub fn is_exact(&self) -> bool {
        matches!(self, Strategy::Full | Strategy::Hierarchical)
    }
}

impl fmt::Display for Strategy {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Strategy::Neo => write!(f, "neo"),
            Strategy::Full => write!(f, "full"),
            Strategy::Periodic(k) => write!(f, "periodic:{k}"),
            Strategy::Background(k) => write!(f, "background:{k}"),
            Strategy::Hierarchical => write!(f, "hierarchical"),
            Strategy::Adaptive(p) => write!(f, "adaptive:{p}"),
            Strategy::Motion(m) => {
                write!(f, "motion:{}", m / 1000)?;
                if m % 1000 != 0 {
                    write!(f, ".{:03}", m % 1000)?;
                }
                Ok(())
            }
        }
    }
}

impl FromStr for Strategy {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        let s = s.trim();
        let period = |v: &str, what: &str| -> Result<usize, String> {
            match v.trim().parse::<usize>() {
                Ok(k) if k >= 1 => Ok(k),
                _ => Err(format!("'{s}': {what} needs a period K >= 1 (e.g. {what}:4), got '{v}'")),
            }
        };
        match s.split_once(':') {
            None => match s {
                "neo" => Ok(Strategy::Neo),
                "full" => Ok(Strategy::Full),
                "hierarchical" => Ok(Strategy::Hierarchical),
                "adaptive" => Ok(Strategy::Adaptive(AdaptiveParams::default())),
                "periodic" | "background" => Err(format!("'{s}' needs a period, e.g. {s}:4")),
                "motion" => Err(format!("'{s}' needs a threshold in degrees, e.g. motion:5")),
                _ => Err(unknown(s)),
            },
            Some(("periodic", v)) => period(v, "periodic").map(Strategy::Periodic),
            Some(("background", v)) => period(v, "background").map(Strategy::Background),
            Some(("adaptive", v)) => AdaptiveParams::parse(v).map(Strategy::Adaptive),
            Some(("motion", v)) => parse_mdeg(v.trim()).map(Strategy::Motion).ok_or_else(|| {
                format!("'{s}': motion needs a threshold DEG in (0, 360] (e.g. motion:5), got '{v}'")
            }),
            Some(_) => Err(unknown(s)),
        }
    }
}

/// Splits a comma-separated list of strategies, keeping `adaptive`'s own comma-separated
/// parameters with it: a piece with `=` but no `:` continues the previous strategy
/// (`neo,adaptive:budget=30,max=2,periodic:4` is three strategies).
pub fn split_list(s: &str) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    for piece in s.split(',').map(str::trim).filter(|p| !p.is_empty()) {
        match out.last_mut() {
            Some(last) if piece.contains('=') && !piece.contains(':') && last.contains('=') => {
                last.push(',');
                last.push_str(piece);
            }
            _ => out.push(piece.to_string()),
        }
    }
    out
}

fn unknown(s: &str) -> String {
    format!(
        "unknown sort strategy '{s}' (expected neo, full, periodic:K, background:K, hierarchical, \
         adaptive[:budget=B,max=P,resort=0|1,wide=W] or motion:DEG)"
    )
}

/// Degrees with at most three decimals, in (0, 360], as millidegrees.
fn parse_mdeg(v: &str) -> Option<u32> {
    let (int, frac) = v.split_once('.').unwrap_or((v, ""));
    if int.is_empty() || frac.len() > 3 || !int.bytes().chain(frac.bytes()).all(|b| b.is_ascii_digit()) {
        return None;
    }
    let int: u32 = int.parse().ok()?;
    let frac: u32 = if frac.is_empty() { 0 } else { format!("{frac:0<3}").parse().ok()? };
    let m = int.checked_mul(1000)?.checked_add(frac)?;
    (1..=360_000).contains(&m).then_some(m)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_and_prints_round_trip() {
        for s in [
            Strategy::Neo,
            Strategy::Full,
            Strategy::Periodic(4),
            Strategy::Background(2),
            Strategy::Hierarchical,
            Strategy::Adaptive(AdaptiveParams::default()),
            Strategy::Adaptive(AdaptiveParams { budget: 20, max_passes: 3, resort: false, wide: 16 }),
            Strategy::Motion(5000),
            Strategy::Motion(2500),
            Strategy::Motion(1),
        ] {
            assert_eq!(s.to_string().parse::<Strategy>(), Ok(s));
        }
        assert_eq!(" periodic:16 ".parse::<Strategy>(), Ok(Strategy::Periodic(16)));
        assert_eq!("motion:2.5".parse::<Strategy>(), Ok(Strategy::Motion(2500)));
        assert_eq!(
            "adaptive:max=2".parse::<Strategy>().unwrap().to_string(),
            "adaptive:budget=50,max=2,resort=1,wide=16"
        );
        for bad in [
            "",
            "periodic",
            "periodic:0",
            "periodic:x",
            "background:-1",
            "neo:2",
            "fast",
            "motion",
            "motion:0",
            "motion:-1",
            "motion:400",
            "motion:1.2345",
            "motion:.5",
            "adaptive:max=99",
            "adaptive:foo=1",
        ] {
            assert!(bad.parse::<Strategy>().is_err(), "{bad}");
        }
    }

    #[test]
    fn lists_keep_adaptive_parameters_together() {
        assert_eq!(
            split_list("neo, adaptive:budget=30,max=2,periodic:4,adaptive,motion:5"),
            vec!["neo", "adaptive:budget=30,max=2", "periodic:4", "adaptive", "motion:5"]
        );
        for s in split_list("adaptive:wide=4,budget=20,full") {
            assert!(s.parse::<Strategy>().is_ok(), "{s}");
        }
    }

    #[test]
    fn refresh_frames() {
        let p = Strategy::Periodic(3);
        let refresh: Vec<usize> = (5..12).filter(|&f| p.full_sort_at(f, 5)).collect();
        assert_eq!(refresh, vec![5, 8, 11]);
        assert!(Strategy::Neo.full_sort_at(5, 5) && !Strategy::Neo.full_sort_at(6, 5));
        assert!(Strategy::Full.full_sort_at(6, 5));
        assert!(!Strategy::Hierarchical.full_sort_at(6, 5));
    }
}
