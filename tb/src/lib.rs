//! Verilator builds and cosimulation test benches (filled in by the RTL issues).
