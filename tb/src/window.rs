//! The reorder-window bench: streams of entries through `neo_raster_window` (built at run time
//! for a configuration with a window, [`crate::configs::build`]), every emission checked
//! against golden [`window_order`].
//!
//! - Driver: [`WindowBench::run`] pushes a stream's entries (`{key, id}` and a random feature
//!   word each) with random idle cycles, holds `pop_i` high on some pushes (it must be
//!   ignored), then drains with `pop_i` (random gaps, and pops past the end, which must emit
//!   nothing), then clears.
//! - Golden: [`window_order`] of the stream's order keys `{key, id}`.
//! - Checker: each emission's key, id and every word of its feature word, in order, at the
//!   cycle it leaves; then that nothing more leaves and the window reports empty.

use crate::check::Checker;
use crate::dut::Clocked;
use crate::dynmodel::DynModel;
use crate::rng::Rng;
use neo_gen::units::raster_core::feature_word_bits;
use neo_gen::EngineConfig;
use neo_golden::raster::window::window_order;
use neo_golden::sort::SortEntry;

/// One entry of a stream: its current key, its id and its feature word (little-endian words).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct WindowEntry {
    /// Current key.
    pub key: u32,
    /// Gaussian id.
    pub id: u32,
    /// Feature word.
    pub feat: Vec<u32>,
}

/// Ports of `neo_raster_window`.
struct Ports {
    clear: usize,
    push: usize,
    push_key: usize,
    push_id: usize,
    push_feat: usize,
    pop: usize,
    emit_valid: usize,
    emit_key: usize,
    emit_id: usize,
    emit_feat: usize,
    full: usize,
    empty: usize,
}

/// A window under test.
pub struct WindowBench<M: Clocked> {
    /// The model.
    pub dut: M,
    ports: Ports,
    window: usize,
    words: usize,
    rng: Rng,
    checker: Checker,
}

impl WindowBench<DynModel> {
    /// The window of `cfg` (its `raster_window` above 1), built or found in the cache.
    pub fn build(cfg: &EngineConfig, seed: u64) -> Result<Self, String> {
        let dut = crate::configs::build(cfg, neo_gen::units::raster_core::window::NAME)?;
        Ok(WindowBench::with_model(dut, cfg, seed))
    }
}

impl<M: Clocked> WindowBench<M> {
    /// A reset bench on `dut` (`neo_raster_window` of `cfg`).
    pub fn with_model(mut dut: M, cfg: &EngineConfig, seed: u64) -> Self {
        let p = |n: &str| dut.pin(n);
        let ports = Ports {
            clear: p("clear_i"),
            push: p("push_i"),
            push_key: p("push_key_i"),
            push_id: p("push_id_i"),
            push_feat: p("push_feat_i"),
            pop: p("pop_i"),
            emit_valid: p("emit_valid_o"),
            emit_key: p("emit_key_o"),
            emit_id: p("emit_id_o"),
            emit_feat: p("emit_feat_o"),
            full: p("full_o"),
            empty: p("empty_o"),
        };
        for port in [ports.clear, ports.push, ports.pop] {
            dut.io_set(port, 0);
        }
        dut.io_reset();
        let words = feature_word_bits(cfg).div_ceil(32) as usize;
        WindowBench {
            dut,
            ports,
            window: cfg.raster_window,
            words,
            rng: Rng::new(seed),
            checker: Checker::new(neo_gen::units::raster_core::window::NAME, seed),
        }
    }

    /// A random feature word (the top word cut to the port's width by the model).
    pub fn random_feat(&mut self) -> Vec<u32> {
        (0..self.words).map(|_| self.rng.next_u32()).collect()
    }

    /// Runs `stream` through the window and checks every emission against golden; returns the
    /// cycles it took.
    pub fn run(&mut self, stream: &[WindowEntry]) -> u64 {
        let keys: Vec<u64> = stream.iter().map(|e| SortEntry::new(e.key, e.id).order_key()).collect();
        let mut order = Vec::new();
        window_order(&keys, self.window, &mut order);
        let want: Vec<&WindowEntry> = order.iter().map(|&i| &stream[i as usize]).collect();
        let start = self.dut.io_cycle();
        let mut got = 0;
        for e in stream {
            while self.rng.percent(20) {
                self.idle_cycle(&want, &mut got, false);
            }
            let p = &self.ports;
            self.dut.io_set(p.push, 1);
            self.dut.io_set(p.push_key, e.key as u64);
            self.dut.io_set(p.push_id, e.id as u64);
            self.dut.io_set_words(p.push_feat, &e.feat);
            let pop_too = self.rng.percent(30);
            self.dut.io_set(p.pop, pop_too as u64);
            self.dut.io_eval();
            self.observe(&want, &mut got);
            self.dut.io_tick();
            self.dut.io_set(self.ports.push, 0);
            self.dut.io_set(self.ports.pop, 0);
        }
        self.checker.value(
            self.dut.io_cycle(),
            "emissions while pushing",
            (stream.len().saturating_sub(self.window - 1)) as u64,
            got as u64,
        );
        while got < want.len() {
            let pop = !self.rng.percent(25);
            self.idle_cycle(&want, &mut got, pop);
        }
        // Pops past the end emit nothing.
        for _ in 0..3 {
            self.idle_cycle(&want, &mut got, true);
        }
        self.checker.value(
            self.dut.io_cycle(),
            "empty_o after the drain",
            1,
            self.dut.io_get(self.ports.empty),
        );
        self.dut.io_set(self.ports.clear, 1);
        self.dut.io_tick();
        self.dut.io_set(self.ports.clear, 0);
        self.dut.io_cycle() - start
    }

    /// Pushes `stream` partly (at most `n` entries, no pops), then clears: the window must be
    /// empty and not full afterwards.
    pub fn abandon(&mut self, stream: &[WindowEntry], n: usize) {
        for e in stream.iter().take(n) {
            let p = &self.ports;
            self.dut.io_set(p.push, 1);
            self.dut.io_set(p.push_key, e.key as u64);
            self.dut.io_set(p.push_id, e.id as u64);
            self.dut.io_set_words(p.push_feat, &e.feat);
            self.dut.io_tick();
        }
        self.dut.io_set(self.ports.push, 0);
        self.dut.io_set(self.ports.clear, 1);
        self.dut.io_tick();
        self.dut.io_set(self.ports.clear, 0);
        self.dut.io_eval();
        let c = self.dut.io_cycle();
        self.checker.value(c, "empty_o after clear_i", 1, self.dut.io_get(self.ports.empty));
        self.checker.value(c, "full_o after clear_i", 0, self.dut.io_get(self.ports.full));
    }

    /// One cycle without a push, `pop_i` as given; checks what leaves.
    fn idle_cycle(&mut self, want: &[&WindowEntry], got: &mut usize, pop: bool) {
        self.dut.io_set(self.ports.pop, pop as u64);
        self.dut.io_eval();
        self.observe(want, got);
        self.dut.io_tick();
        self.dut.io_set(self.ports.pop, 0);
    }

    /// Checks an emission in the current cycle, if any, against the next expected entry.
    fn observe(&mut self, want: &[&WindowEntry], got: &mut usize) {
        let c = self.dut.io_cycle();
        if self.dut.io_get(self.ports.emit_valid) == 0 {
            return;
        }
        let Some(w) = want.get(*got) else {
            self.checker.fail(c, "emit_valid_o", "0 (every entry has left)", "1");
        };
        let at = format!("emission {}", *got);
        self.checker.value(
            c,
            &format!("{at} emit_key_o"),
            w.key as u64,
            self.dut.io_get(self.ports.emit_key),
        );
        self.checker.value(c, &format!("{at} emit_id_o"), w.id as u64, self.dut.io_get(self.ports.emit_id));
        let mut feat = vec![0u32; self.words];
        self.dut.io_get_words(self.ports.emit_feat, &mut feat);
        let bits = self.dut.io_width(self.ports.emit_feat);
        for (k, (&e, &a)) in w.feat.iter().zip(&feat).enumerate() {
            let mask = if (k as u32 + 1) * 32 > bits { (1u32 << (bits % 32)) - 1 } else { u32::MAX };
            self.checker.value(c, &format!("{at} emit_feat_o word {k}"), (e & mask) as u64, a as u64);
        }
        *got += 1;
    }
}
