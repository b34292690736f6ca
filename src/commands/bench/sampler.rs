//! Where a benchmark's CPU goes: `SIGPROF` every millisecond of the process's CPU time (all
//! threads, `setitimer(ITIMER_PROF)`; the kernel's tick may make the period longer), each sample
//! counted against the phase the code has marked ([`neo_golden::profile`]). The samples give
//! each phase's share; the seconds come from the CPU time measured around the whole.

use neo_golden::profile::{self, Phase};
use std::sync::atomic::{AtomicU64, Ordering::Relaxed};

/// Samples per phase, indexed by `Phase as u8`.
static SAMPLES: [AtomicU64; Phase::ALL.len()] = [const { AtomicU64::new(0) }; Phase::ALL.len()];

/// Milliseconds of CPU time between samples.
const PERIOD_MS: i64 = 1;

extern "C" fn on_sample(_signal: libc::c_int) {
    // Async-signal-safe: an atomic load and an atomic add.
    SAMPLES[profile::current() as usize].fetch_add(1, Relaxed);
}

/// Samples per phase since the sampler started.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Counts([u64; Phase::ALL.len()]);

impl Counts {
    /// Samples in `phase`.
    pub fn of(&self, phase: Phase) -> u64 {
        self.0[phase as usize]
    }

    /// Samples in any phase.
    pub fn total(&self) -> u64 {
        self.0.iter().sum()
    }

    /// The samples taken between `earlier` and these.
    pub fn since(&self, earlier: &Counts) -> Counts {
        Counts(std::array::from_fn(|i| self.0[i] - earlier.0[i]))
    }
}

/// The sampler: samples from [`Sampler::start`] until it is dropped.
pub struct Sampler(());

impl Sampler {
    /// Turns the phase marks on, installs the `SIGPROF` handler and starts the timer; an error
    /// naming the call if the system refuses either.
    pub fn start() -> Result<Sampler, String> {
        // SAFETY: a zeroed sigaction is valid; the handler only touches atomics.
        let mut act: libc::sigaction = unsafe { std::mem::zeroed() };
        act.sa_sigaction = on_sample as *const () as libc::sighandler_t;
        act.sa_flags = libc::SA_RESTART;
        // SAFETY: `act` is a valid sigaction; the old action is not needed.
        if unsafe { libc::sigaction(libc::SIGPROF, &act, std::ptr::null_mut()) } != 0 {
            return Err(format!("sigaction(SIGPROF): {}", std::io::Error::last_os_error()));
        }
        let period = libc::timeval { tv_sec: 0, tv_usec: (PERIOD_MS * 1000) as libc::suseconds_t };
        let timer = libc::itimerval { it_interval: period, it_value: period };
        // SAFETY: `timer` is a valid itimerval.
        if unsafe { libc::setitimer(libc::ITIMER_PROF, &timer, std::ptr::null_mut()) } != 0 {
            return Err(format!("setitimer(ITIMER_PROF): {}", std::io::Error::last_os_error()));
        }
        profile::set_enabled(true);
        Ok(Sampler(()))
    }

    /// The samples so far.
    pub fn counts(&self) -> Counts {
        Counts(std::array::from_fn(|i| SAMPLES[i].load(Relaxed)))
    }
}

impl Drop for Sampler {
    fn drop(&mut self) {
        let off = libc::itimerval {
            it_interval: libc::timeval { tv_sec: 0, tv_usec: 0 },
            it_value: libc::timeval { tv_sec: 0, tv_usec: 0 },
        };
        // SAFETY: `off` is a valid itimerval; a zero value disarms the timer.
        unsafe { libc::setitimer(libc::ITIMER_PROF, &off, std::ptr::null_mut()) };
        profile::set_enabled(false);
    }
}

/// `phase 0.123 (45%)` for each phase of `phases` with samples: its share of `counts`' total,
/// and that share of `cpu_s` (the CPU seconds the samples were taken in, per frame).
pub fn split(counts: &Counts, phases: &[Phase], cpu_s: f64) -> String {
    let total = counts.total().max(1) as f64;
    phases
        .iter()
        .filter(|&&p| counts.of(p) > 0)
        .map(|&p| {
            let share = counts.of(p) as f64 / total;
            format!("{} {:.3} ({:.0}%)", p.name(), share * cpu_s, 100.0 * share)
        })
        .collect::<Vec<_>>()
        .join(", ")
}

#[cfg(test)]
mod tests {
    use super::*;

    /// (The signal path is tested end to end by `tests/cli.rs`, in a process of its own: the
    /// mark is process-wide, and the unit tests beside this one mark phases too.)
    #[test]
    fn split_gives_seconds_per_frame_and_shares_of_the_phases_with_samples() {
        let mut before = Counts::default();
        before.0[Phase::Dram as usize] = 10;
        let mut now = before;
        now.0[Phase::Dram as usize] += 600;
        now.0[Phase::Engine as usize] += 200;
        now.0[Phase::Other as usize] += 200;
        let c = now.since(&before);
        assert_eq!((c.of(Phase::Dram), c.total()), (600, 1000));
        assert_eq!(
            split(&c, &[Phase::Engine, Phase::Dram, Phase::Sort], 2.0),
            "engine 0.400 (20%), DRAM model 1.200 (60%)"
        );
    }
}
