//! Valid/ready stream agents bound to port names: a [`Source`] (driver) that offers beats with
//! random stalls and a [`Sink`] (monitor) that takes them under random backpressure and checks
//! the handshake rules.
//!
//! Per cycle a test bench calls, in order: `source.drive`, `sink.drive`, `dut.eval()`,
//! `source.sample`, `sink.sample`, `dut.tick()`. Transfers happen on the rising edge when valid
//! and ready are both high after the eval.

use crate::check::Checker;
use crate::dut::Dut;
use crate::rng::Rng;
use std::collections::VecDeque;

/// One beat: the words of each data port, in the order the agent was given the port names.
pub type Beat = Vec<Vec<u32>>;

/// Drives a valid/ready input stream. Once it raises valid it holds valid and the data until
/// the transfer (AXI-style); while idle it drives random data, so a DUT that samples data without
/// valid is caught by the checkers.
pub struct Source {
    valid: usize,
    ready: usize,
    data: Vec<(usize, usize)>,
    queue: VecDeque<Beat>,
    presenting: bool,
    rng: Rng,
    /// Probability (percent) of NOT offering an available beat in a given cycle.
    pub stall_pct: u32,
    /// Beats transferred so far.
    pub sent: u64,
    /// Cycle of the last transfer.
    pub last_sent_cycle: Option<u64>,
}

impl Source {
    /// A source on `D`'s ports `valid` (input), `ready` (output) and `data` (inputs).
    pub fn new<D: Dut>(valid: &str, ready: &str, data: &[&str], rng: Rng, stall_pct: u32) -> Self {
        Source {
            valid: D::port(valid),
            ready: D::port(ready),
            data: data.iter().map(|d| (D::port(d), D::PORTS[D::port(d)].words())).collect(),
            queue: VecDeque::new(),
            presenting: false,
            rng,
            stall_pct,
            sent: 0,
            last_sent_cycle: None,
        }
    }

    /// Queues a beat.
    pub fn push(&mut self, beat: Beat) {
        debug_assert_eq!(beat.len(), self.data.len());
        self.queue.push_back(beat);
    }

    /// Beats not yet transferred (the one on the wires included).
    pub fn pending(&self) -> usize {
        self.queue.len()
    }

    /// True when everything queued has been transferred.
    pub fn is_idle(&self) -> bool {
        self.queue.is_empty()
    }

    /// Sets valid and data for this cycle (call before `eval`).
    pub fn drive<D: Dut>(&mut self, dut: &mut D) {
        if !self.presenting && !self.queue.is_empty() && !self.rng.percent(self.stall_pct) {
            self.presenting = true;
            let beat = &self.queue[0];
            for (k, &(port, _)) in self.data.iter().enumerate() {
                dut.set_words(port, &beat[k]);
            }
        }
        if !self.presenting {
            for &(port, words) in &self.data {
                let junk: Vec<u32> = (0..words).map(|_| self.rng.next_u32()).collect();
                dut.set_words(port, &junk);
            }
        }
        dut.set_u64(self.valid, self.presenting as u64);
    }

    /// After `eval`: true when the beat on the wires transfers at this edge.
    pub fn sample<D: Dut>(&mut self, dut: &D) -> bool {
        if self.presenting && dut.get_u64(self.ready) != 0 {
            self.presenting = false;
            self.queue.pop_front();
            self.sent += 1;
            self.last_sent_cycle = Some(dut.cycle());
            true
        } else {
            false
        }
    }
}

/// Takes a valid/ready output stream under random backpressure and checks that valid and data
/// stay stable while valid is high and ready low.
pub struct Sink {
    valid: usize,
    ready: usize,
    data: Vec<(usize, usize)>,
    rng: Rng,
    ready_now: bool,
    stalled: Option<Beat>,
    /// Probability (percent) of ready being high in a given cycle.
    pub ready_pct: u32,
    /// Beats received so far.
    pub received: u64,
    /// Check valid/data stability under backpressure (on by default).
    pub check_stable: bool,
}

impl Sink {
    /// A sink on `D`'s ports `valid` (output), `ready` (input) and `data` (outputs).
    pub fn new<D: Dut>(valid: &str, ready: &str, data: &[&str], rng: Rng, ready_pct: u32) -> Self {
        Sink {
            valid: D::port(valid),
            ready: D::port(ready),
            data: data.iter().map(|d| (D::port(d), D::PORTS[D::port(d)].words())).collect(),
            rng,
            ready_now: false,
            stalled: None,
            ready_pct,
            received: 0,
            check_stable: true,
        }
    }

    /// Sets ready for this cycle (call before `eval`).
    pub fn drive<D: Dut>(&mut self, dut: &mut D) {
        self.ready_now = self.rng.percent(self.ready_pct);
        dut.set_u64(self.ready, self.ready_now as u64);
    }

    fn read<D: Dut>(&self, dut: &D) -> Beat {
        self.data
            .iter()
            .map(|&(port, words)| {
                let mut w = vec![0u32; words];
                dut.get_words(port, &mut w);
                w
            })
            .collect()
    }

    /// After `eval`: the beat transferred at this edge, if any. Panics through `checker` when
    /// valid dropped or data changed while a beat was waiting for ready.
    pub fn sample<D: Dut>(&mut self, dut: &D, checker: &Checker) -> Option<Beat> {
        let valid = dut.get_u64(self.valid) != 0;
        if let Some(prev) = self.stalled.take() {
            if self.check_stable {
                checker.protocol(
                    dut.cycle(),
                    valid,
                    "output valid dropped before ready (no transfer happened)",
                );
                let now = self.read(dut);
                if now != prev {
                    checker.protocol(
                        dut.cycle(),
                        false,
                        &format!(
                            "output data changed while valid and not ready: was {:?}, now {:?}",
                            prev.iter().map(|w| crate::bits::hex(w)).collect::<Vec<_>>(),
                            now.iter().map(|w| crate::bits::hex(w)).collect::<Vec<_>>()
                        ),
                    );
                }
            }
        }
        if !valid {
            return None;
        }
        let beat = self.read(dut);
        if self.ready_now {
            self.received += 1;
            Some(beat)
        } else {
            self.stalled = Some(beat);
            None
        }
    }
}
