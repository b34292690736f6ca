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

use std::fmt;
use std::str::FromStr;

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
        !matches!(self, Strategy::Periodic(_))
    }

    /// True when a frame's table is reused by the next frame (so the raster writes it back):
    /// `neo`, and `periodic:K` with `K > 1`.
    pub fn reuses_tables(&self) -> bool {
        match *self {
            Strategy::Neo => true,
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
                "periodic" | "background" => Err(format!("'{s}' needs a period, e.g. {s}:4")),
                _ => Err(format!(
                    "unknown sort strategy '{s}' (expected neo, full, periodic:K, background:K or hierarchical)"
                )),
            },
            Some(("periodic", v)) => period(v, "periodic").map(Strategy::Periodic),
            Some(("background", v)) => period(v, "background").map(Strategy::Background),
            Some(_) => Err(format!(
                "unknown sort strategy '{s}' (expected neo, full, periodic:K, background:K or hierarchical)"
            )),
        }
    }
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
        ] {
            assert_eq!(s.to_string().parse::<Strategy>(), Ok(s));
        }
        assert_eq!(" periodic:16 ".parse::<Strategy>(), Ok(Strategy::Periodic(16)));
        for bad in ["", "periodic", "periodic:0", "periodic:x", "background:-1", "neo:2", "fast"] {
            assert!(bad.parse::<Strategy>().is_err(), "{bad}");
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
