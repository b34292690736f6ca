//! Verilog emitter and one generator per Neo unit (filled in by the RTL issues).
