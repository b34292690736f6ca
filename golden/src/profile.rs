//! Phase marks for attributing CPU time in benchmarks (`neo bench model`): the pipeline and the
//! cycle model mark the phase they are in, and a sampler (the bench's) reads the mark.
//!
//! The mark is one process-wide value, so it names what the process does only while one phase
//! runs at a time (the parallel threads of a stage all work on that stage), as in the bench. A
//! mark costs a relaxed atomic load and two stores, so the marks stay in the code.

use std::sync::atomic::{AtomicU8, Ordering::Relaxed};

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

static CURRENT: AtomicU8 = AtomicU8::new(Phase::Other as u8);

/// The phase marked now (safe to call from a signal handler: one atomic load).
pub fn current() -> Phase {
    read(&CURRENT)
}

/// Marks `phase` until the returned guard drops; the mark before it comes back then.
#[must_use = "the mark lasts as long as the guard"]
#[inline]
pub fn enter(phase: Phase) -> PhaseGuard {
    enter_on(&CURRENT, phase)
}

fn read(mark: &AtomicU8) -> Phase {
    Phase::ALL.get(mark.load(Relaxed) as usize).copied().unwrap_or(Phase::Other)
}

#[inline]
fn enter_on(mark: &'static AtomicU8, phase: Phase) -> PhaseGuard {
    PhaseGuard { mark, before: mark.swap(phase as u8, Relaxed) }
}

/// Restores the previous mark when dropped ([`enter`]).
pub struct PhaseGuard {
    mark: &'static AtomicU8,
    before: u8,
}

impl Drop for PhaseGuard {
    #[inline]
    fn drop(&mut self) {
        self.mark.store(self.before, Relaxed);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// On a mark of its own: the process-wide one is shared with the tests running beside it.
    #[test]
    fn marks_nest_and_restore() {
        static MARK: AtomicU8 = AtomicU8::new(Phase::Other as u8);
        assert_eq!(Phase::ALL.map(|p| p as u8), [0, 1, 2, 3, 4, 5, 6]);
        {
            let _a = enter_on(&MARK, Phase::Engine);
            assert_eq!(read(&MARK), Phase::Engine);
            {
                let _b = enter_on(&MARK, Phase::Dram);
                assert_eq!(read(&MARK), Phase::Dram);
            }
            assert_eq!(read(&MARK), Phase::Engine);
        }
        assert_eq!(read(&MARK), Phase::Other);
        MARK.store(200, Relaxed);
        assert_eq!(read(&MARK), Phase::Other, "an unknown value reads as Other");
    }
}
