//! The initial values of the Verilated models: the X check.
//!
//! Verilator is two-state. The models are verilated with `--x-initial unique`
//! (`build/verilator.rs`), so every variable of the design (every register, every memory word)
//! starts from a value drawn when the model is constructed, as `VerilatedContext::randReset` and
//! `randSeed` say; the shim sets both before it constructs the model (`build/shim.rs`). By
//! default ([`XInit::Random`]) the values are random, drawn from a seed derived from the bench's
//! seed ([`crate::rng`]): a register without its reset, or a memory word read before it is
//! written, then holds a random value instead of zero, and the golden comparison sees any output
//! that depends on it. The same bench seed gives the same initial values, so `NEO_SEED=0x...`
//! replays them with the stimulus.
//!
//! The bench seed is the one [`crate::rng::for_each_seed`], [`crate::rng::test_seed`] or
//! [`crate::rng::SeedSplit::seed`] last handed out on the thread constructing the model, mixed
//! with the test's name ([`enter`]); the `k`-th model constructed under it takes the seed
//! `mix(bench seed, top, k)`.
//! A thread that has no bench seed (a model built outside those helpers, or on a thread of its
//! own) uses `$NEO_SEED` when set, else the first of [`crate::rng::FIXED_SEEDS`].
//!
//! `NEO_XINIT` chooses the values: `random` (the default), `zero` (every variable starts at 0,
//! as with the earlier `--x-initial fast`: what a bench saw before the X check) or `ones`.

use std::cell::Cell;
use std::sync::Mutex;

/// How the variables of a model start (`NEO_XINIT`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum XInit {
    /// All bits zero (`randReset(0)`).
    Zero,
    /// All bits one (`randReset(1)`).
    Ones,
    /// Random, from the derived seed (`randReset(2)`; the default).
    Random,
}

impl XInit {
    /// Parses a `NEO_XINIT` value (empty: the default, [`XInit::Random`]).
    pub fn parse(s: &str) -> Result<XInit, String> {
        match s.trim() {
            "" | "random" => Ok(XInit::Random),
            "zero" | "0" => Ok(XInit::Zero),
            "ones" | "1" => Ok(XInit::Ones),
            other => Err(format!("NEO_XINIT={other:?}: use random (the default), zero or ones")),
        }
    }

    /// `$NEO_XINIT`.
    ///
    /// # Panics
    /// When it is set to something else than `random`, `zero` or `ones`.
    pub fn from_env() -> XInit {
        XInit::parse(&std::env::var("NEO_XINIT").unwrap_or_default()).unwrap_or_else(|e| panic!("{e}"))
    }

    /// The value of `VerilatedContext::randReset`.
    pub fn rand_reset(self) -> u32 {
        match self {
            XInit::Zero => 0,
            XInit::Ones => 1,
            XInit::Random => 2,
        }
    }
}

thread_local! {
    /// The bench seed of this thread (mixed with its test's name) and the number of models
    /// constructed under it.
    static CURRENT: Cell<Option<(u64, u32)>> = const { Cell::new(None) };
}

/// Makes `seed` of test `test` the bench seed of this thread: the models constructed from now
/// on draw their initial values from both (called by the seed helpers of [`crate::rng`]), so
/// each test and seed starts its models from values of its own.
pub fn enter(test: &str, seed: u64) {
    CURRENT.with(|c| c.set(Some((seed ^ crate::rng::fnv(test), 0))));
}

/// The bench seed of a thread without one: `$NEO_SEED`, else the first fixed seed.
fn default_seed() -> u64 {
    std::env::var("NEO_SEED")
        .ok()
        .and_then(|s| crate::rng::parse_seed(&s))
        .unwrap_or(crate::rng::FIXED_SEEDS[0])
}

/// The seed of the `k`-th model constructed under bench seed `seed`, for top `top`: never zero
/// (Verilator's `randSeed(0)` means a seed from the clock).
pub fn model_seed(seed: u64, top: &str, k: u32) -> u32 {
    let mut h = seed ^ 0x5851_f42d_4c95_7f2d;
    for b in top.bytes().chain(k.to_le_bytes()) {
        h = (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3);
    }
    let r = crate::rng::Rng::new(h).next_u64();
    // 31 bits (Verilator takes an int), never zero.
    (((r ^ (r >> 32)) as u32) & 0x7fff_ffff).max(1)
}

/// Constructs a model of `top`: `new(rand_reset, seed)` calls the shim's `neo_T_new`, which sets
/// the context's `randReset` and `randSeed` and then constructs the model. Verilator reseeds its
/// (per-thread) generator whenever any context's seed changes, so constructions are serialised
/// across threads: the values are the same on every run.
pub fn construct<T>(top: &str, new: impl FnOnce(u32, u32) -> T) -> T {
    static LOCK: Mutex<()> = Mutex::new(());
    let mode = XInit::from_env();
    let (bench, k) = CURRENT.with(|c| {
        let (bench, k) = c.get().unwrap_or((default_seed(), 0));
        c.set(Some((bench, k + 1)));
        (bench, k)
    });
    let seed = model_seed(bench, top, k);
    if k == 0 && mode != XInit::Zero {
        let mode = format!("{mode:?}").to_lowercase();
        println!("{top}: initial values {mode} (NEO_XINIT), model seed 0x{seed:08x} from the test and its seed (NEO_SEED replays them)");
    }
    let _serial = LOCK.lock().unwrap_or_else(|e| e.into_inner());
    new(mode.rand_reset(), seed)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_parse_and_seeds_differ_by_top_and_order() {
        assert_eq!(XInit::parse("").unwrap(), XInit::Random);
        assert_eq!(XInit::parse("zero").unwrap().rand_reset(), 0);
        assert_eq!(XInit::parse("ones").unwrap().rand_reset(), 1);
        assert!(XInit::parse("x").unwrap_err().contains("NEO_XINIT"));
        let a = model_seed(1, "neo_msu", 0);
        assert_eq!(a, model_seed(1, "neo_msu", 0));
        assert_ne!(a, model_seed(1, "neo_msu", 1));
        assert_ne!(a, model_seed(1, "neo_bsu", 0));
        assert_ne!(a, model_seed(2, "neo_msu", 0));
        assert!((0..1000).all(|k| model_seed(k, "t", 0) != 0 && model_seed(k, "t", 0) <= 0x7fff_ffff));
    }
}
