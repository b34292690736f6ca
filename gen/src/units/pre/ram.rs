//! `neo_pre_ram_w{W}_d{D}`: `D` words of `W` bits, one synchronous write port and one
//! combinational read port (register-file style, as `neo_chunk_ram`), one module per size.

use crate::emit::expr::bits_for;
use crate::emit::{if_, set, Module};

/// Module name of a memory of `depth` words of `width` bits.
pub fn name(width: u32, depth: u32) -> String {
    format!("neo_pre_ram_w{width}_d{depth}")
}

/// Bits of an address of a memory of `depth` words.
pub fn addr_bits(depth: u32) -> u32 {
    bits_for(u64::from(depth) - 1)
}

/// The memory of `depth` (at least 2) words of `width` bits.
pub fn module(width: u32, depth: u32) -> Module {
    assert!(depth >= 2, "a memory of {depth} words");
    let ab = addr_bits(depth);
    let mut m = Module::new(name(width, depth));
    m.doc(format!("Memory of {depth} words of {width} bits: 1 write port, 1 combinational read port."));
    m.input_c("clk_i", 1, "clock");
    m.input("we_i", 1).input("waddr_i", ab).input("wdata_i", width);
    m.input("raddr_i", ab).output("rdata_o", width);
    m.mem("mem", width, depth);
    m.seq_noreset(vec![if_("we_i", vec![set("mem[waddr_i]", "wdata_i")])]);
    m.assign("rdata_o", "mem[raddr_i]");
    m
}
