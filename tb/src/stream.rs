//! Valid/ready stream agents bound to port names: a [`Source`] (driver) that offers beats with
//! random stalls and a [`Sink`] (monitor) that takes them under random backpressure and checks
//! the handshake rules ([`Handshake`]).
//!
//! The agents work on any [`PortIo`]: the statically linked models ([`crate::dut::Dut`], bound
//! with `new::<D>`) and the models built at run time ([`crate::dynmodel::DynModel`], bound with
//! `bind`).
//!
//! Per cycle a test bench calls, in order: `source.drive`, `sink.drive`, `eval`,
//! `source.sample`, `sink.sample`, `tick`. Transfers happen on the rising edge when valid and
//! ready are both high after the eval.

use crate::check::Checker;
use crate::dut::{Dut, PortIo};
use crate::rng::Rng;
use std::collections::VecDeque;

/// One beat: the words of each data port, in the order the agent was given the port names.
pub type Beat = Vec<Vec<u32>>;

/// A port bound by name: index, 32-bit words, name.
#[derive(Clone, Debug)]
struct Bound {
    index: usize,
    words: usize,
    name: String,
}

/// Resolves port names to [`Bound`] ports.
trait Lookup {
    fn bound(&self, name: &str) -> Result<Bound, String>;
}

/// Port lookup on a static model type.
struct Static<D>(std::marker::PhantomData<D>);

impl<D: Dut> Lookup for Static<D> {
    fn bound(&self, name: &str) -> Result<Bound, String> {
        let index =
            D::PORTS.iter().position(|p| p.name == name).ok_or(format!("{} has no port {name}", D::NAME))?;
        Ok(Bound { index, words: D::PORTS[index].words(), name: name.to_string() })
    }
}

/// Port lookup on a model instance.
struct Instance<'a, P: ?Sized>(&'a P);

impl<P: PortIo + ?Sized> Lookup for Instance<'_, P> {
    fn bound(&self, name: &str) -> Result<Bound, String> {
        let index = self.0.io_port(name)?;
        Ok(Bound { index, words: self.0.io_width(index).div_ceil(32) as usize, name: name.to_string() })
    }
}

fn bind_all(l: &impl Lookup, names: &[&str]) -> Result<Vec<Bound>, String> {
    names.iter().map(|n| l.bound(n)).collect()
}

/// A port value in hex: `0x...` unpadded up to 64 bits, word by word above.
fn hex_value(words: &[u32]) -> String {
    if words.len() <= 2 {
        let v = words.iter().rev().fold(0u64, |v, &w| v << 32 | w as u64);
        format!("0x{v:x}")
    } else {
        crate::bits::hex(words)
    }
}

/// Drives a valid/ready input stream. Once it raises valid it holds valid and the data until
/// the transfer (AXI-style: an offered beat is never withdrawn); while idle it drives random
/// data, so a DUT that samples data without valid is caught by the checkers. Gaps between
/// beats are random (`stall_pct`), drawn from the agent's own [`Rng`] (fork it from the bench's
/// seeded one).
pub struct Source {
    valid: usize,
    ready: usize,
    data: Vec<Bound>,
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
    ///
    /// # Panics
    /// When `D` lacks one of the ports.
    pub fn new<D: Dut>(valid: &str, ready: &str, data: &[&str], rng: Rng, stall_pct: u32) -> Self {
        Self::with(&Static::<D>(Default::default()), valid, ready, data, rng, stall_pct)
            .unwrap_or_else(|e| panic!("{e}"))
    }

    /// A source on `io`'s ports `valid` (input), `ready` (output) and `data` (inputs), or an
    /// error naming a missing port.
    pub fn bind<P: PortIo + ?Sized>(
        io: &P,
        valid: &str,
        ready: &str,
        data: &[&str],
        rng: Rng,
        stall_pct: u32,
    ) -> Result<Self, String> {
        Self::with(&Instance(io), valid, ready, data, rng, stall_pct)
    }

    fn with(
        l: &impl Lookup,
        valid: &str,
        ready: &str,
        data: &[&str],
        rng: Rng,
        stall_pct: u32,
    ) -> Result<Self, String> {
        Ok(Source {
            valid: l.bound(valid)?.index,
            ready: l.bound(ready)?.index,
            data: bind_all(l, data)?,
            queue: VecDeque::new(),
            presenting: false,
            rng,
            stall_pct,
            sent: 0,
            last_sent_cycle: None,
        })
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

    /// True when a beat is on the wires (valid driven high this cycle).
    pub fn offering(&self) -> bool {
        self.presenting
    }

    /// Sets valid and data for this cycle (call before `eval`).
    pub fn drive<P: PortIo + ?Sized>(&mut self, dut: &mut P) {
        if !self.presenting && !self.queue.is_empty() && !self.rng.percent(self.stall_pct) {
            self.presenting = true;
            let beat = &self.queue[0];
            for (k, port) in self.data.iter().enumerate() {
                dut.io_set_words(port.index, &beat[k]);
            }
        }
        if !self.presenting {
            for port in &self.data {
                let junk: Vec<u32> = (0..port.words).map(|_| self.rng.next_u32()).collect();
                dut.io_set_words(port.index, &junk);
            }
        }
        dut.io_set(self.valid, self.presenting as u64);
    }

    /// After `eval`: true when the beat on the wires transfers at this edge.
    pub fn sample<P: PortIo + ?Sized>(&mut self, dut: &P) -> bool {
        if self.presenting && dut.io_get(self.ready) != 0 {
            self.presenting = false;
            self.queue.pop_front();
            self.sent += 1;
            self.last_sent_cycle = Some(dut.io_cycle());
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
/// A violation stops the run at the first one through [`Checker::protocol_field`]: the cycle,
/// the unit, the port (field), the value the rule requires (expected) and the one seen (actual),
/// in hex.
pub struct Handshake {
    name: String,
    valid: Bound,
    ready: usize,
    data: Vec<Bound>,
    stalled: Option<Beat>,
    valid_now: bool,
    /// Check that valid and payload stay stable until taken (on by default).
    pub check_stable: bool,
    /// Check that valid and payload do not depend on ready (on by default).
    pub check_independent: bool,
}

impl Handshake {
    /// The checker of interface `name` on `D`'s ports `valid` (output), `ready` (input) and
    /// `data` (outputs).
    ///
    /// # Panics
    /// When `D` lacks one of the ports.
    pub fn new<D: Dut>(name: &str, valid: &str, ready: &str, data: &[&str]) -> Self {
        Self::with(&Static::<D>(Default::default()), name, valid, ready, data)
            .unwrap_or_else(|e| panic!("{e}"))
    }

    /// The checker of interface `name` on `io`'s ports `valid` (output), `ready` (input) and
    /// `data` (outputs), or an error naming a missing port.
    pub fn bind<P: PortIo + ?Sized>(
        io: &P,
        name: &str,
        valid: &str,
        ready: &str,
        data: &[&str],
    ) -> Result<Self, String> {
        Self::with(&Instance(io), name, valid, ready, data)
    }

    fn with(l: &impl Lookup, name: &str, valid: &str, ready: &str, data: &[&str]) -> Result<Self, String> {
        Ok(Handshake {
            name: name.to_string(),
            valid: l.bound(valid)?,
            ready: l.bound(ready)?.index,
            data: bind_all(l, data)?,
            stalled: None,
            valid_now: false,
            check_stable: true,
            check_independent: true,
        })
    }

    /// The payload ports' values now.
    pub fn read<P: PortIo + ?Sized>(&self, dut: &P) -> Beat {
        self.data
            .iter()
            .map(|port| {
                let mut w = vec![0u32; port.words];
                dut.io_get_words(port.index, &mut w);
                w
            })
            .collect()
    }

    /// Forgets a stalled beat (after a reset of the DUT).
    pub fn clear(&mut self) {
        self.stalled = None;
        self.valid_now = false;
    }

    /// Valid as seen by the last [`Handshake::check`].
    pub fn valid(&self) -> bool {
        self.valid_now
    }

    /// Stops the run at the first payload port whose value differs between `want` and `got`.
    #[track_caller]
    fn same_payload(&self, checker: &Checker, cycle: u64, want: &Beat, got: &Beat, rule: &str) {
        if let Some(k) = (0..self.data.len()).find(|&k| want[k] != got[k]) {
            let rule = format!("{}: {rule}", self.name);
            checker.protocol_field(
                cycle,
                &self.data[k].name,
                &hex_value(&want[k]),
                &hex_value(&got[k]),
                &rule,
            );
        }
    }

    /// After `eval`, with ready as driven this cycle (`ready`): checks the rules (see the type's
    /// docs) and returns the beat that transfers at this edge (valid and ready high), if any.
    #[track_caller]
    pub fn check<P: PortIo + ?Sized>(&mut self, dut: &mut P, ready: bool, checker: &Checker) -> Option<Beat> {
        let cycle = dut.io_cycle();
        let valid = dut.io_get(self.valid.index) != 0;
        self.valid_now = valid;
        let beat = if valid || self.stalled.is_some() { Some(self.read(dut)) } else { None };
        if let Some(prev) = self.stalled.take() {
            if self.check_stable {
                if !valid {
                    let rule =
                        format!("{}: valid dropped before it was taken; it must hold until ready", self.name);
                    checker.protocol_field(cycle, &self.valid.name, "0x1", "0x0", &rule);
                }
                let now = beat.as_ref().expect("read above");
                self.same_payload(
                    checker,
                    cycle,
                    &prev,
                    now,
                    "data changed while valid and not ready; it must hold until taken",
                );
            }
        }
        if self.check_independent {
            dut.io_set(self.ready, !ready as u64);
            dut.io_eval();
            let flipped_valid = dut.io_get(self.valid.index) != 0;
            let flipped = if valid || flipped_valid { Some(self.read(dut)) } else { None };
            dut.io_set(self.ready, ready as u64);
            dut.io_eval();
            if flipped_valid != valid {
                let rule = format!(
                    "{}: valid depends on ready (ready {} gives the expected value, ready {} the actual one)",
                    self.name, ready as u8, !ready as u8
                );
                let v = |b: bool| format!("0x{:x}", b as u8);
                checker.protocol_field(cycle, &self.valid.name, &v(valid), &v(flipped_valid), &rule);
            }
            if valid {
                let (a, b) = (beat.as_ref().expect("valid"), flipped.as_ref().expect("valid"));
                let rule = format!(
                    "data depends on ready while valid (ready {} gives the expected value, ready {} the actual one)",
                    ready as u8, !ready as u8
                );
                self.same_payload(checker, cycle, a, b, &rule);
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
/// cycle from the agent's own [`Rng`], independently of valid) and checks it with a
/// [`Handshake`]: valid and data stable while valid is high and ready low, and neither
/// depending on ready.
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
    ///
    /// # Panics
    /// When `D` lacks one of the ports.
    pub fn new<D: Dut>(valid: &str, ready: &str, data: &[&str], rng: Rng, ready_pct: u32) -> Self {
        Self::from_handshake(
            Handshake::new::<D>(&format!("{valid}/{ready}"), valid, ready, data),
            rng,
            ready_pct,
        )
    }

    /// A sink on `io`'s ports `valid` (output), `ready` (input) and `data` (outputs), or an error
    /// naming a missing port.
    pub fn bind<P: PortIo + ?Sized>(
        io: &P,
        valid: &str,
        ready: &str,
        data: &[&str],
        rng: Rng,
        ready_pct: u32,
    ) -> Result<Self, String> {
        let hs = Handshake::bind(io, &format!("{valid}/{ready}"), valid, ready, data)?;
        Ok(Self::from_handshake(hs, rng, ready_pct))
    }

    fn from_handshake(hs: Handshake, rng: Rng, ready_pct: u32) -> Self {
        let ready = hs.ready;
        Sink { hs, ready, rng, ready_now: false, ready_pct, received: 0 }
    }

    /// The protocol checker (to switch a rule off: `sink.handshake().check_stable = false`).
    pub fn handshake(&mut self) -> &mut Handshake {
        &mut self.hs
    }

    /// Valid as seen by the last [`Sink::sample`].
    pub fn valid(&self) -> bool {
        self.hs.valid()
    }

    /// Sets ready for this cycle (call before `eval`).
    pub fn drive<P: PortIo + ?Sized>(&mut self, dut: &mut P) {
        self.ready_now = self.rng.percent(self.ready_pct);
        dut.io_set(self.ready, self.ready_now as u64);
    }

    /// After `eval`: the beat transferred at this edge, if any. Panics through `checker` when
    /// valid dropped or data changed while a beat was waiting for ready, or when valid or data
    /// depend on ready (see [`Handshake`]; ready is flipped and restored with two extra `eval`s).
    #[track_caller]
    pub fn sample<P: PortIo + ?Sized>(&mut self, dut: &mut P, checker: &Checker) -> Option<Beat> {
        let beat = self.hs.check(dut, self.ready_now, checker);
        if beat.is_some() {
            self.received += 1;
        }
        beat
    }
}

/// The agents of a unit with one input stream `in_valid_i` / `in_ready_o` (data ports `ins`)
/// and one output stream `out_valid_o` / `out_ready_i` (data ports `outs`): a [`Source`] that
/// offers a beat in `p_valid`% of cycles and a [`Sink`] ready in `p_ready`%, their random
/// streams forked from `rng` (1 and 2). An error names a missing port.
pub fn unit_agents<P: PortIo + ?Sized>(
    io: &P,
    ins: &[&str],
    outs: &[&str],
    rng: &mut Rng,
    (p_valid, p_ready): (u32, u32),
) -> Result<(Source, Sink), String> {
    let src = Source::bind(io, "in_valid_i", "in_ready_o", ins, rng.fork(1), 100u32.saturating_sub(p_valid))?;
    Ok((src, Sink::bind(io, "out_valid_o", "out_ready_i", outs, rng.fork(2), p_ready)?))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A model without logic: ports hold what is set, and a test plays a trace into its
    /// outputs cycle by cycle.
    struct Trace {
        ports: Vec<(&'static str, u32, Vec<u32>)>,
        cycle: u64,
    }

    impl Trace {
        fn new(ports: &[(&'static str, u32)]) -> Self {
            let ports = ports.iter().map(|&(n, w)| (n, w, vec![0; w.div_ceil(32) as usize])).collect();
            Trace { ports, cycle: 0 }
        }

        fn put(&mut self, name: &str, words: &[u32]) {
            let p = self.io_port(name).expect("port");
            self.io_set_words(p, words);
        }
    }

    impl PortIo for Trace {
        fn io_port(&self, name: &str) -> Result<usize, String> {
            self.ports.iter().position(|p| p.0 == name).ok_or(format!("no port {name}"))
        }
        fn io_set(&mut self, port: usize, v: u64) {
            self.io_set_words(port, &[v as u32, (v >> 32) as u32]);
        }
        fn io_get(&self, port: usize) -> u64 {
            let mut w = [0u32; 2];
            self.io_get_words(port, &mut w);
            w[0] as u64 | (w[1] as u64) << 32
        }
        fn io_cycle(&self) -> u64 {
            self.cycle
        }
        fn io_width(&self, port: usize) -> u32 {
            self.ports[port].1
        }
        fn io_set_words(&mut self, port: usize, words: &[u32]) {
            for (k, w) in self.ports[port].2.iter_mut().enumerate() {
                *w = words.get(k).copied().unwrap_or(0);
            }
        }
        fn io_get_words(&self, port: usize, out: &mut [u32]) {
            for (k, o) in out.iter_mut().enumerate() {
                *o = self.ports[port].2.get(k).copied().unwrap_or(0);
            }
        }
        fn io_eval(&mut self) {}
    }

    const OUT: [(&str, u32); 4] =
        [("out_valid_o", 1), ("out_ready_i", 1), ("out_x_o", 32), ("out_wide_o", 96)];

    /// Plays `(valid, ready, x, wide)` per cycle through a [`Handshake`]; returns the beats taken.
    fn play(trace: &[(bool, bool, u32, [u32; 3])]) -> Vec<Beat> {
        let mut m = Trace::new(&OUT);
        let mut hs =
            Handshake::bind(&m, "out", "out_valid_o", "out_ready_i", &["out_x_o", "out_wide_o"]).unwrap();
        let check = Checker::new("neo_unit", 0x5eed);
        let mut taken = Vec::new();
        for &(valid, ready, x, wide) in trace {
            m.put("out_valid_o", &[valid as u32]);
            m.put("out_ready_i", &[ready as u32]);
            m.put("out_x_o", &[x]);
            m.put("out_wide_o", &wide);
            taken.extend(hs.check(&mut m, ready, &check));
            m.cycle += 1;
        }
        taken
    }

    #[test]
    fn held_data_passes_and_transfers_are_returned() {
        let w = [1, 2, 3];
        let taken = play(&[
            (true, false, 0x12, w),
            (true, false, 0x12, w),
            (true, true, 0x12, w),
            (false, false, 0x99, [9, 9, 9]),
            (true, true, 0x13, w),
        ]);
        assert_eq!(taken, vec![vec![vec![0x12], w.to_vec()], vec![vec![0x13], w.to_vec()]]);
    }

    #[test]
    #[should_panic(
        expected = "PROTOCOL VIOLATION at cycle 2: unit neo_unit, field out_x_o: expected 0x12, actual 0x13 \
                    (out: data changed while valid and not ready"
    )]
    fn data_changing_while_valid_and_not_ready_is_caught() {
        let w = [1, 2, 3];
        play(&[(false, false, 0, w), (true, false, 0x12, w), (true, false, 0x13, w), (true, true, 0x13, w)]);
    }

    #[test]
    #[should_panic(expected = "PROTOCOL VIOLATION at cycle 1: unit neo_unit, field out_wide_o: expected \
                    0x000000030000000200000001, actual 0x000000030000000000000001")]
    fn a_change_in_a_wide_field_is_caught() {
        play(&[(true, false, 0x12, [1, 2, 3]), (true, true, 0x12, [1, 0, 3])]);
    }

    #[test]
    #[should_panic(
        expected = "PROTOCOL VIOLATION at cycle 1: unit neo_unit, field out_valid_o: expected 0x1, actual 0x0 \
                    (out: valid dropped"
    )]
    fn valid_withdrawn_before_it_was_taken_is_caught() {
        play(&[(true, false, 0x12, [0; 3]), (false, true, 0x12, [0; 3])]);
    }

    /// The source offers every beat in order, holds valid and data until ready, and leaves
    /// random gaps.
    #[test]
    fn the_source_holds_an_offered_beat_until_it_is_taken() {
        let mut m = Trace::new(&[("in_valid_i", 1), ("in_ready_o", 1), ("in_x_i", 32)]);
        let mut src = Source::bind(&m, "in_valid_i", "in_ready_o", &["in_x_i"], Rng::new(7), 50).unwrap();
        for k in 0..50u32 {
            src.push(vec![vec![0x100 + k]]);
        }
        let mut ready_rng = Rng::new(8);
        let (mut got, mut held, mut gaps) = (Vec::new(), None, 0);
        while !src.is_idle() {
            assert!(m.cycle < 10_000, "no progress");
            src.drive(&mut m);
            let ready = ready_rng.percent(40);
            m.put("in_ready_o", &[ready as u32]);
            let (valid, x) = (m.io_get(0) != 0, m.io_get(2) as u32);
            assert_eq!(valid, src.offering());
            if let Some(h) = held {
                assert!(valid && x == h, "cycle {}: withdrew or changed 0x{h:x}", m.cycle);
            }
            gaps += !valid as u32;
            if src.sample(&m) {
                assert!(valid && ready);
                got.push(x);
                held = None;
            } else {
                held = valid.then_some(x);
            }
            m.cycle += 1;
        }
        assert_eq!(got, (0..50).map(|k| 0x100 + k).collect::<Vec<_>>());
        assert_eq!((src.sent, src.pending()), (50, 0));
        assert!(gaps > 5, "{gaps} idle cycles at 50% stalls");
    }
}
