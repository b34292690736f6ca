//! A small, fast, seedable PRNG (xoshiro256**, seeded through SplitMix64) and the per-test seed.
//!
//! Every cosimulation test runs a fixed list of seeds ([`FIXED_SEEDS`], the same on every run, so
//! a result is reproducible) and then one fresh seed drawn from the clock ([`test_seeds`],
//! [`for_each_seed`]). Each seed is printed as `seed = 0x...`; running the test again with
//! `NEO_SEED=0x...` replays exactly that seed's stimulus, stalls and backpressure (and only that
//! seed), and with it the models' random initial values ([`crate::xinit`]). `NEO_FIXED_SEEDS=1`
//! drops the fresh seed (`scripts/mutate-check`: a mutant counts as caught only when the fixed
//! seeds catch it).

/// xoshiro256** (Blackman and Vigna): good statistical quality, a few ns per draw.
#[derive(Clone, Debug)]
pub struct Rng {
    s: [u64; 4],
}

fn splitmix64(x: &mut u64) -> u64 {
    *x = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
    let mut z = *x;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

impl Rng {
    /// A generator seeded from `seed` (any value, zero included).
    pub fn new(seed: u64) -> Self {
        let mut x = seed;
        Rng { s: [splitmix64(&mut x), splitmix64(&mut x), splitmix64(&mut x), splitmix64(&mut x)] }
    }

    /// A generator for a sub-stream (e.g. stalls vs data), independent of the parent's draws.
    pub fn fork(&mut self, stream: u64) -> Rng {
        Rng::new(self.next_u64() ^ stream.wrapping_mul(0xD6E8_FEB8_6659_FD93))
    }

    /// The next 64 random bits.
    #[inline]
    pub fn next_u64(&mut self) -> u64 {
        let r = self.s[1].wrapping_mul(5).rotate_left(7).wrapping_mul(9);
        let t = self.s[1] << 17;
        self.s[2] ^= self.s[0];
        self.s[3] ^= self.s[1];
        self.s[1] ^= self.s[2];
        self.s[0] ^= self.s[3];
        self.s[2] ^= t;
        self.s[3] = self.s[3].rotate_left(45);
        r
    }

    /// The next 32 random bits.
    #[inline]
    pub fn next_u32(&mut self) -> u32 {
        (self.next_u64() >> 32) as u32
    }

    /// Uniform in `0..n` (`n > 0`), by multiply-shift (bias below 2^-32 for the sizes used here).
    #[inline]
    pub fn below(&mut self, n: u64) -> u64 {
        debug_assert!(n > 0);
        ((self.next_u64() >> 32) * n) >> 32
    }

    /// Uniform in `lo..=hi`.
    #[inline]
    pub fn range(&mut self, lo: u64, hi: u64) -> u64 {
        lo + self.below(hi - lo + 1)
    }

    /// True with probability `percent / 100`.
    #[inline]
    pub fn percent(&mut self, percent: u32) -> bool {
        self.below(100) < percent as u64
    }

    /// A uniformly random element of `items` (non-empty).
    pub fn pick<'a, T>(&mut self, items: &'a [T]) -> &'a T {
        &items[self.below(items.len() as u64) as usize]
    }

    /// Fisher-Yates shuffle.
    pub fn shuffle<T>(&mut self, v: &mut [T]) {
        for i in (1..v.len()).rev() {
            let j = self.below(i as u64 + 1) as usize;
            v.swap(i, j);
        }
    }
}

/// Parses `0x...` (hex) or decimal.
pub fn parse_seed(s: &str) -> Option<u64> {
    let s = s.trim();
    match s.strip_prefix("0x").or_else(|| s.strip_prefix("0X")) {
        Some(hex) => u64::from_str_radix(&hex.replace('_', ""), 16).ok(),
        None => s.replace('_', "").parse().ok(),
    }
}

/// The seeds every cosimulation test runs when `NEO_SEED` is not set, before one fresh seed.
pub const FIXED_SEEDS: [u64; 3] = [0x0000_0000_5eed_0001, 0x9e37_79b9_7f4a_7c15, 0xc0de_d00d_f00d_beef];

/// The number of seeds a test runs without `NEO_SEED`: the fixed ones and a fresh one. A bench
/// that splits a fixed amount of work over its seeds gives each [`seed_share`] of it, whatever
/// the number of seeds actually run, so that `NEO_SEED` replays exactly the failing run.
pub const SEED_RUNS: usize = FIXED_SEEDS.len() + 1;

/// `total` work items split over [`SEED_RUNS`] seeds: the share of one seed (rounded up, at
/// least one).
pub fn seed_share(total: usize) -> usize {
    total.div_ceil(SEED_RUNS).max(1)
}

fn env_flag(name: &str) -> bool {
    std::env::var(name).is_ok_and(|v| !v.is_empty() && v != "0" && v != "false")
}

/// The seeds of test `test`: `$NEO_SEED` alone when set; else [`FIXED_SEEDS`] and one fresh seed
/// (left out when `NEO_FIXED_SEEDS` is set). Prints the list and how to replay one.
///
/// # Panics
/// When `NEO_SEED` is set but not a number.
pub fn test_seeds(test: &str) -> Vec<u64> {
    let seeds = match replay_seed() {
        Some(seed) => vec![seed],
        None => {
            let mut v = FIXED_SEEDS.to_vec();
            if !env_flag("NEO_FIXED_SEEDS") {
                v.push(fresh_seed(test));
            }
            v
        }
    };
    let list: Vec<String> = seeds.iter().map(|s| format!("0x{s:016x}")).collect();
    println!("{test}: seeds = [{}] (replay one with NEO_SEED=0x...)", list.join(", "));
    seeds
}

/// Runs `body(seed)` for each of [`test_seeds`]`(test)`, in order. A panic in a run is raised
/// again with the test, the seed and how to replay it in front of the original message.
pub fn for_each_seed(test: &str, mut body: impl FnMut(u64)) {
    for seed in test_seeds(test) {
        println!("{test}: seed = 0x{seed:016x}");
        crate::xinit::enter(test, seed);
        let run = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| body(seed)));
        if let Err(e) = run {
            let msg = e
                .downcast_ref::<String>()
                .map(String::as_str)
                .or_else(|| e.downcast_ref::<&str>().copied())
                .unwrap_or("(non-text panic)");
            panic!("{test} FAILED with seed 0x{seed:016x} (replay with NEO_SEED=0x{seed:016x}): {msg}");
        }
    }
}

/// A seed per work item of a test whose items are too long to repeat for every seed (whole
/// engine frames, biker tiles): item `k` runs with seed `k mod n` of [`test_seeds`], so each seed
/// takes a share of the items; with `NEO_SEED` every item runs with that seed.
#[derive(Clone, Debug)]
pub struct SeedSplit {
    /// The test's seeds.
    pub seeds: Vec<u64>,
    /// The test's name (with the seed, it chooses the models' initial values).
    test: String,
}

impl SeedSplit {
    /// The seeds of `test` ([`test_seeds`]).
    pub fn new(test: &str) -> Self {
        SeedSplit { seeds: test_seeds(test), test: test.to_string() }
    }

    /// The seed of item `k`; it also becomes the thread's bench seed, from which the models
    /// constructed next draw their initial values ([`crate::xinit::enter`]).
    pub fn seed(&self, k: usize) -> u64 {
        let seed = self.seeds[k % self.seeds.len()];
        crate::xinit::enter(&self.test, seed);
        seed
    }
}

fn replay_seed() -> Option<u64> {
    match std::env::var("NEO_SEED") {
        Ok(s) if !s.trim().is_empty() => Some(
            parse_seed(&s).unwrap_or_else(|| panic!("NEO_SEED={s:?} is not a number (use 0x... or decimal)")),
        ),
        _ => None,
    }
}

fn fresh_seed(test: &str) -> u64 {
    let t = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_nanos() as u64)
        .unwrap_or(0);
    let mut x = t ^ ((std::process::id() as u64) << 32) ^ fnv(test);
    splitmix64(&mut x)
}

/// One seed for a command (`neo cosim`, a benchmark): `$NEO_SEED` when set, else a fresh one from the clock and the
/// process id. Prints `seed = 0x...` and how to reproduce it.
///
/// # Panics
/// When `NEO_SEED` is set but not a number.
pub fn test_seed(test: &str) -> u64 {
    let seed = draw_seed(test);
    println!("{}", seed_line(test, seed));
    seed
}

/// [`test_seed`] for a command whose standard output is its data (`neo cosim --json`): the
/// seed's line goes to standard error.
///
/// # Panics
/// When `NEO_SEED` is set but not a number.
pub fn command_seed(command: &str) -> u64 {
    let seed = draw_seed(command);
    eprintln!("{}", seed_line(command, seed));
    seed
}

/// `$NEO_SEED` when set, else a fresh seed for `name`; made this thread's bench seed
/// ([`crate::xinit::enter`]).
fn draw_seed(name: &str) -> u64 {
    let seed = replay_seed().unwrap_or_else(|| fresh_seed(name));
    crate::xinit::enter(name, seed);
    seed
}

/// `NAME: seed = 0x... (reproduce with NEO_SEED=0x...)`.
fn seed_line(name: &str, seed: u64) -> String {
    format!("{name}: seed = 0x{seed:016x} (reproduce with NEO_SEED=0x{seed:016x})")
}

/// FNV-1a of a string (mixes the test name into fresh seeds).
pub(crate) fn fnv(s: &str) -> u64 {
    s.bytes().fold(0xcbf2_9ce4_8422_2325, |h, b| (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn same_seed_same_stream_and_ranges_hold() {
        let (mut a, mut b) = (Rng::new(42), Rng::new(42));
        for _ in 0..100 {
            assert_eq!(a.next_u64(), b.next_u64());
        }
        assert_ne!(Rng::new(1).next_u64(), Rng::new(2).next_u64());
        let mut r = Rng::new(7);
        let mut seen = [false; 5];
        for _ in 0..1000 {
            let x = r.range(3, 7);
            assert!((3..=7).contains(&x));
            seen[(x - 3) as usize] = true;
        }
        assert!(seen.iter().all(|&s| s), "every value of a small range appears");
        let hits = (0..10_000).filter(|_| r.percent(30)).count();
        assert!((2_700..3_300).contains(&hits), "30% came out as {hits} / 10000");
    }

    #[test]
    fn a_failing_run_names_its_seed() {
        let first = FIXED_SEEDS[0];
        let r = std::panic::catch_unwind(|| {
            for_each_seed("t", |seed| assert_ne!(seed, FIXED_SEEDS[1], "boom"));
        });
        let e = r.expect_err("the second fixed seed fails");
        let msg = e.downcast_ref::<String>().expect("a formatted message");
        let second = format!("0x{:016x}", FIXED_SEEDS[1]);
        assert!(msg.contains(&format!("t FAILED with seed {second}")), "{msg}");
        assert!(msg.contains(&format!("NEO_SEED={second}")) && msg.contains("boom"), "{msg}");
        assert!(!msg.contains(&format!("0x{first:016x}")), "{msg}");
        assert_eq!(seed_share(10), 3);
        assert_eq!(seed_share(0), 1);
    }

    #[test]
    fn seeds_parse_in_hex_and_decimal() {
        assert_eq!(parse_seed("0x1F"), Some(31));
        assert_eq!(parse_seed(" 0Xdead_beef "), Some(0xdead_beef));
        assert_eq!(parse_seed("123"), Some(123));
        assert_eq!(parse_seed("zz"), None);
    }
}
