//! The generic view of a Verilated model: ports by index, words in and out, clock and reset.
//!
//! Every generated wrapper in [`crate::models`] implements [`Dut`], so drivers, monitors and wave
//! tooling can be written once and bound to port names at run time.

use crate::waves::Traceable;
use std::path::Path;

/// One port of a Verilated top.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PortSpec {
    /// Verilog name, e.g. `in_valid_i`.
    pub name: &'static str,
    /// True for inputs.
    pub input: bool,
    /// Width in bits.
    pub width: u32,
}

impl PortSpec {
    /// Number of little-endian 32-bit words holding the port.
    pub const fn words(&self) -> usize {
        self.width.div_ceil(32) as usize
    }
}

/// A Verilated model driven through port indices (positions in [`Dut::PORTS`]).
pub trait Dut {
    /// Module name.
    const NAME: &'static str;
    /// Ports in declaration order.
    const PORTS: &'static [PortSpec];

    /// Drives input `port` with little-endian words (missing words are zero, extra bits ignored).
    ///
    /// # Panics
    /// When `port` is not an input.
    fn set_words(&mut self, port: usize, words: &[u32]);
    /// Reads `port` into `out` (words beyond the port are zeroed).
    fn get_words(&self, port: usize, out: &mut [u32]);
    /// Settles combinational logic.
    fn eval(&mut self);
    /// One clock cycle (see the wrappers' `tick`).
    fn tick(&mut self);
    /// Reset sequence; restarts [`Dut::cycle`] at zero.
    fn reset(&mut self);
    /// Rising edges since the last reset.
    fn cycle(&self) -> u64;
    /// Starts a VCD trace.
    fn trace_open(&mut self, path: &Path) -> std::io::Result<()>;
    /// Closes the trace.
    fn trace_close(&mut self);

    /// Index of the port called `name`.
    ///
    /// # Panics
    /// When there is none (a test bench bound to the wrong interface).
    fn port(name: &str) -> usize {
        Self::PORTS
            .iter()
            .position(|p| p.name == name)
            .unwrap_or_else(|| panic!("{} has no port {name}", Self::NAME))
    }

    /// Drives a port of at most 64 bits.
    fn set_u64(&mut self, port: usize, v: u64) {
        self.set_words(port, &[v as u32, (v >> 32) as u32]);
    }

    /// Reads a port of at most 64 bits.
    fn get_u64(&self, port: usize) -> u64 {
        let mut w = [0u32; 2];
        self.get_words(port, &mut w);
        w[0] as u64 | ((w[1] as u64) << 32)
    }
}

/// Port access by index for drivers shared by statically linked models ([`Dut`]) and models
/// loaded at run time ([`crate::dynmodel::DynModel`]).
pub trait PortIo {
    /// Index of the port called `name`, or an error naming it.
    fn io_port(&self, name: &str) -> Result<usize, String>;
    /// Drives a port of at most 64 bits.
    fn io_set(&mut self, port: usize, v: u64);
    /// Reads a port of at most 64 bits.
    fn io_get(&self, port: usize) -> u64;
    /// Rising edges since the last reset.
    fn io_cycle(&self) -> u64;
    /// Width of `port` in bits.
    fn io_width(&self, port: usize) -> u32;
    /// Drives input `port` with little-endian words (missing words are zero, extra bits ignored).
    fn io_set_words(&mut self, port: usize, words: &[u32]);
    /// Reads `port` into `out` (words beyond the port are zeroed).
    fn io_get_words(&self, port: usize, out: &mut [u32]);
    /// Settles combinational logic.
    fn io_eval(&mut self);
}

impl<D: Dut> PortIo for D {
    fn io_port(&self, name: &str) -> Result<usize, String> {
        D::PORTS.iter().position(|p| p.name == name).ok_or_else(|| format!("{} has no port {name}", D::NAME))
    }

    fn io_set(&mut self, port: usize, v: u64) {
        self.set_u64(port, v);
    }

    fn io_get(&self, port: usize) -> u64 {
        self.get_u64(port)
    }

    fn io_cycle(&self) -> u64 {
        self.cycle()
    }

    fn io_width(&self, port: usize) -> u32 {
        D::PORTS[port].width
    }

    fn io_set_words(&mut self, port: usize, words: &[u32]) {
        self.set_words(port, words);
    }

    fn io_get_words(&self, port: usize, out: &mut [u32]) {
        self.get_words(port, out);
    }

    fn io_eval(&mut self) {
        self.eval();
    }
}

/// A model the unit benches (ITU, SCU, raster core) drive in any engine configuration: ports by
/// index ([`PortIo`]), the clock, the reset and waves ([`Traceable`]). The statically linked
/// models ([`Dut`], the configuration this crate was built with) and the models built at run
/// time ([`crate::dynmodel::DynModel`], any configuration) both are.
pub trait Clocked: PortIo + Traceable {
    /// One clock cycle (the static wrappers' `tick`).
    fn io_tick(&mut self);
    /// The reset sequence; restarts the cycle count at zero.
    fn io_reset(&mut self);

    /// Index of the port called `name`.
    ///
    /// # Panics
    /// When there is none (a bench bound to the wrong interface), naming the module and port.
    fn pin(&self, name: &str) -> usize {
        self.io_port(name).unwrap_or_else(|e| panic!("{e}"))
    }

    /// Reads a 1-bit (or any up to 64-bit) port as a flag: nonzero.
    fn flag(&self, port: usize) -> bool {
        self.io_get(port) != 0
    }
}

impl<D: Dut> Clocked for D {
    fn io_tick(&mut self) {
        self.tick();
    }

    fn io_reset(&mut self) {
        self.reset();
    }
}

impl Clocked for crate::dynmodel::DynModel {
    fn io_tick(&mut self) {
        self.tick();
    }

    fn io_reset(&mut self) {
        self.reset();
    }
}

impl PortIo for crate::dynmodel::DynModel {
    fn io_port(&self, name: &str) -> Result<usize, String> {
        self.port(name)
    }

    fn io_set(&mut self, port: usize, v: u64) {
        self.set_u64(port, v);
    }

    fn io_get(&self, port: usize) -> u64 {
        self.get_u64(port)
    }

    fn io_cycle(&self) -> u64 {
        self.cycle()
    }

    fn io_width(&self, port: usize) -> u32 {
        self.interface().ports[port].width
    }

    fn io_set_words(&mut self, port: usize, words: &[u32]) {
        self.set_words(port, words);
    }

    fn io_get_words(&self, port: usize, out: &mut [u32]) {
        self.get_words(port, out);
    }

    fn io_eval(&mut self) {
        self.eval();
    }
}
