//! Phase marks for attributing CPU time in benchmarks (`neo bench model`): the pipeline and the
//! cycle model mark the phase they are in, and a sampler (the bench's) reads the mark.
//!
//! The mark is one process-wide value, so it names what the process does only while one phase
//! runs at a time (the parallel threads of a stage all work on that stage), as in the bench.
//! Marking is off unless a sampler turns it on ([`set_enabled`]). Off, a mark costs one relaxed
//! load; on, a load, a swap and a store.

use std::sync::atomic::{AtomicBool, AtomicU8, Ordering::Relaxed};

/// What the process is doing.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum Phase {
    /// Anything not marked.
    Other,
    /// The preprocessing of a frame into its feature table (and the GPU duplication).
    Preprocess,
    /// The ITU binning of a frame's feature entries into tiles.
    Binning,
    /// The strategy's sorting step of every tile.
    Sort,
    /// The per-tile work after the sort: write-back, raster (or its sample) and counters.
    TileWork,
    /// The cycle model's engine: the event loop, its jobs and their address walks.
    Engine,
    /// The cycle model's DRAM model.
    Dram,
}

impl Phase {
    /// Every phase, in the order of their `u8` values.
    pub const ALL: [Phase; 7] = [
        Phase::Other,
        Phase::Preprocess,
        Phase::Binning,
        Phase::Sort,
        Phase::TileWork,
        Phase::Engine,
        Phase::Dram,
    ];

    /// A short name for tables.
    pub fn name(self) -> &'static str {
        match self {
            Phase::Other => "other",
            Phase::Preprocess => "preprocess",
            Phase::Binning => "binning",
            Phase::Sort => "sort",
            Phase::TileWork => "tile work",
            Phase::Engine => "engine",
            Phase::Dram => "DRAM model",
        }
    }
}

/// Process-wide marks: off (no writes) until a sampler turns them on.
static MARKS: Marks = Marks::new();

/// Turns marking on or off. Off (the default), [`enter`] writes nothing: the model's threads
/// would otherwise contend for the mark's cache line (measured: `neo report`, whose two threads
/// run two DRAM models at once, took 8% more CPU with marks always written).
pub fn set_enabled(on: bool) {
    MARKS.enabled.store(on, Relaxed);
}

/// The phase marked now (safe to call from a signal handler: one atomic load).
pub fn current() -> Phase {
    MARKS.current()
}

/// Marks `phase` until the returned guard drops (the mark before it comes back then), if
/// marking is on ([`set_enabled`]).
#[must_use = "the mark lasts as long as the guard"]
#[inline]
pub fn enter(phase: Phase) -> PhaseGuard {
    MARKS.enter(phase)
}

/// A mark and whether it is written.
struct Marks {
    enabled: AtomicBool,
    current: AtomicU8,
}

impl Marks {
    const fn new() -> Self {
        Marks { enabled: AtomicBool::new(false), current: AtomicU8::new(Phase::Other as u8) }
    }

    fn current(&self) -> Phase {
        Phase::ALL.get(self.current.load(Relaxed) as usize).copied().unwrap_or(Phase::Other)
    }

    #[inline]
    fn enter(&'static self, phase: Phase) -> PhaseGuard {
        if !self.enabled.load(Relaxed) {
            return PhaseGuard(None);
        }
        PhaseGuard(Some((&self.current, self.current.swap(phase as u8, Relaxed))))
    }
}

/// Restores the previous mark when dropped ([`enter`]).
pub struct PhaseGuard(Option<(&'static AtomicU8, u8)>);

impl Drop for PhaseGuard {
    #[inline]
    fn drop(&mut self) {
        if let Some((mark, before)) = self.0 {
            mark.store(before, Relaxed);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// On marks of their own: the process-wide ones are shared with the tests running beside it.
    #[test]
    fn marks_nest_and_restore_and_stay_unwritten_when_off() {
        static MARKS: Marks = Marks::new();
        assert_eq!(Phase::ALL.map(|p| p as u8), [0, 1, 2, 3, 4, 5, 6]);
        {
            let _off = MARKS.enter(Phase::Sort);
            assert_eq!(MARKS.current(), Phase::Other, "off: nothing written");
        }
        MARKS.enabled.store(true, Relaxed);
        {
            let _a = MARKS.enter(Phase::Engine);
            assert_eq!(MARKS.current(), Phase::Engine);
            {
                let _b = MARKS.enter(Phase::Dram);
                assert_eq!(MARKS.current(), Phase::Dram);
            }
            assert_eq!(MARKS.current(), Phase::Engine);
        }
        assert_eq!(MARKS.current(), Phase::Other);
        MARKS.current.store(200, Relaxed);
        assert_eq!(MARKS.current(), Phase::Other, "an unknown value reads as Other");
    }
}
