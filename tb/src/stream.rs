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

/// The protocol checker of one valid/ready interface the DUT drives (an output stream, a memory
/// request or write port), bound to port indices: the reusable harness piece behind [`Sink`] and
/// the memory models. After each `eval` of a cycle, with ready as driven for that cycle,
/// [`Handshake::check`] asserts
///
/// - **valid and payload hold until taken**: after a cycle with valid high and ready low, valid
///   is still high and every payload port unchanged (no dropped valid, no data changing under
///   stall);
/// - **valid does not depend on ready**: ready is flipped, the model re-evaluated
///   (combinational settle only, no clock), and valid and payload must not have changed; ready is
///   then restored and the model re-evaluated, so the rest of the bench sees the cycle as driven.
///
/// A violation stops the run through [`Checker::protocol`] with the cycle, the interface and
/// the rule.
pub struct Handshake {
    name: String,
    valid: usize,
    ready: usize,
    data: Vec<(usize, usize)>,
    stalled: Option<Beat>,
    /// Check that valid and payload stay stable until taken (on by default).
    pub check_stable: bool,
    /// Check that valid and payload do not depend on ready (on by default).
    pub check_independent: bool,
}

fn hex_beat(b: &Beat) -> Vec<String> {
    b.iter().map(|w| crate::bits::hex(w)).collect()
}

impl Handshake {
    /// The checker of interface `name` on `D`'s ports `valid` (output), `ready` (input) and
    /// `data` (outputs).
    pub fn new<D: Dut>(name: &str, valid: &str, ready: &str, data: &[&str]) -> Self {
        Handshake {
            name: name.to_string(),
            valid: D::port(valid),
            ready: D::port(ready),
            data: data.iter().map(|d| (D::port(d), D::PORTS[D::port(d)].words())).collect(),
            stalled: None,
            check_stable: true,
            check_independent: true,
        }
    }

    /// The payload ports' values now.
    pub fn read<D: Dut>(&self, dut: &D) -> Beat {
        self.data
            .iter()
            .map(|&(port, words)| {
                let mut w = vec![0u32; words];
                dut.get_words(port, &mut w);
                w
            })
            .collect()
    }

    /// Forgets a stalled beat (after a reset of the DUT).
    pub fn clear(&mut self) {
        self.stalled = None;
    }

    /// After `eval`, with ready as driven this cycle (`ready`): checks the rules (see the type's
    /// docs) and returns the beat that transfers at this edge (valid and ready high), if any.
    pub fn check<D: Dut>(&mut self, dut: &mut D, ready: bool, checker: &Checker) -> Option<Beat> {
        let cycle = dut.cycle();
        let valid = dut.get_u64(self.valid) != 0;
        let beat = if valid || self.stalled.is_some() { Some(self.read(dut)) } else { None };
        if let Some(prev) = self.stalled.take() {
            if self.check_stable {
                checker.protocol(
                    cycle,
                    valid,
                    &format!(
                        "{}: valid dropped before it was taken (valid must hold until ready)",
                        self.name
                    ),
                );
                let now = beat.as_ref().expect("read above");
                if *now != prev {
                    checker.protocol(
                        cycle,
                        false,
                        &format!(
                            "{}: payload changed while valid and not ready (must hold until taken): was {:?}, now {:?}",
                            self.name,
                            hex_beat(&prev),
                            hex_beat(now)
                        ),
                    );
                }
            }
        }
        if self.check_independent {
            dut.set_u64(self.ready, !ready as u64);
            dut.eval();
            let flipped_valid = dut.get_u64(self.valid) != 0;
            let flipped = if valid || flipped_valid { Some(self.read(dut)) } else { None };
            dut.set_u64(self.ready, ready as u64);
            dut.eval();
            checker.protocol(
                cycle,
                flipped_valid == valid,
                &format!(
                    "{}: valid depends on ready (valid must not depend on ready): valid {} with ready {}, {} with ready {}",
                    self.name, valid as u8, ready as u8, flipped_valid as u8, !ready as u8
                ),
            );
            if valid {
                let (a, b) = (beat.as_ref().expect("valid"), flipped.as_ref().expect("valid"));
                checker.protocol(
                    cycle,
                    a == b,
                    &format!(
                        "{}: payload depends on ready while valid: {:?} with ready {}, {:?} with ready {}",
                        self.name,
                        hex_beat(a),
                        ready as u8,
                        hex_beat(b),
                        !ready as u8
                    ),
                );
            }
        }
        if !valid {
            return None;
        }
        let beat = beat.expect("valid");
        if ready {
            Some(beat)
        } else {
            self.stalled = Some(beat);
            None
        }
    }
}

/// Takes a valid/ready output stream under random backpressure (ready drawn at random each
/// cycle, independently of valid) and checks it with a [`Handshake`]: valid and data stable while
/// valid is high and ready low, and neither depending on ready.
pub struct Sink {
    hs: Handshake,
    ready: usize,
    rng: Rng,
    ready_now: bool,
    /// Probability (percent) of ready being high in a given cycle.
    pub ready_pct: u32,
    /// Beats received so far.
    pub received: u64,
}

impl Sink {
    /// A sink on `D`'s ports `valid` (output), `ready` (input) and `data` (outputs).
    pub fn new<D: Dut>(valid: &str, ready: &str, data: &[&str], rng: Rng, ready_pct: u32) -> Self {
        Sink {
            hs: Handshake::new::<D>(&format!("{valid}/{ready}"), valid, ready, data),
            ready: D::port(ready),
            rng,
            ready_now: false,
            ready_pct,
            received: 0,
        }
    }

    /// The protocol checker (to switch a rule off: `sink.handshake().check_stable = false`).
    pub fn handshake(&mut self) -> &mut Handshake {
        &mut self.hs
    }

    /// Sets ready for this cycle (call before `eval`).
    pub fn drive<D: Dut>(&mut self, dut: &mut D) {
        self.ready_now = self.rng.percent(self.ready_pct);
        dut.set_u64(self.ready, self.ready_now as u64);
    }

    /// After `eval`: the beat transferred at this edge, if any. Panics through `checker` when
    /// valid dropped or data changed while a beat was waiting for ready, or when valid or data
    /// depend on ready (see [`Handshake`]; ready is flipped and restored with two extra `eval`s).
    pub fn sample<D: Dut>(&mut self, dut: &mut D, checker: &Checker) -> Option<Beat> {
        let beat = self.hs.check(dut, self.ready_now, checker);
        if beat.is_some() {
            self.received += 1;
        }
        beat
    }
}
