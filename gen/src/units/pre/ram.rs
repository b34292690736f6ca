//! `neo_pre_ram`: `DEPTH` words of `WIDTH` bits, one synchronous write port and one
//! combinational read port (register-file style, as `neo_chunk_ram`): one parametric module,
//! every use instantiates it with its own `WIDTH` and `DEPTH` ([`instance`]).

use crate::emit::expr::bits_for;
use crate::emit::{if_, set, Item, Module};

/// Module name.
pub const NAME: &str = "neo_pre_ram";

/// Default word width (every instance sets its own, [`instance`]).
const DEFAULT_WIDTH: u32 = 32;
/// Default depth (every instance sets its own, [`instance`]).
const DEFAULT_DEPTH: u32 = 4;

/// Bits of an address of a memory of `depth` words (the module's `$clog2(DEPTH)`).
pub fn addr_bits(depth: u32) -> u32 {
    bits_for(u64::from(depth) - 1)
}

/// An instance `name` of the memory of `depth` (at least 2) words of `width` bits with
/// connections `conns` (`(port, expression)`).
///
/// # Panics
/// When `depth` is below 2 or `width` is 0 (a generator error).
pub fn instance(width: u32, depth: u32, name: &str, conns: Vec<(String, String)>) -> Item {
    assert!(depth >= 2, "a memory of {depth} words");
    assert!(width >= 1, "a memory of {width}-bit words");
    super::sized_instance(NAME, (width, depth), name, conns)
}

/// The memory, parametric in `WIDTH` (bits per word) and `DEPTH` (words, at least 2; addresses
/// of `$clog2(DEPTH)` bits).
pub fn module() -> Module {
    let ab = addr_bits(DEFAULT_DEPTH);
    let mut m = Module::new(NAME);
    m.doc("Memory of DEPTH words of WIDTH bits: 1 write port, 1 combinational read port.");
    m.doc("WIDTH: bits per word. DEPTH: words, at least 2.");
    m.param("WIDTH", i64::from(DEFAULT_WIDTH)).param("DEPTH", i64::from(DEFAULT_DEPTH));
    m.input_c("clk_i", 1, "clock");
    m.input("we_i", 1).input("waddr_i", ab).input("wdata_i", DEFAULT_WIDTH);
    m.input("raddr_i", ab).output("rdata_o", DEFAULT_WIDTH);
    for p in ["waddr_i", "raddr_i"] {
        m.width_param(p, "$clog2(DEPTH)");
    }
    m.width_param("wdata_i", "WIDTH").width_param("rdata_o", "WIDTH");
    m.mem("mem", DEFAULT_WIDTH, DEFAULT_DEPTH).width_param("mem", "WIDTH").depth_param("mem", "DEPTH");
    m.seq_noreset(vec![if_("we_i", vec![set("mem[waddr_i]", "wdata_i")])]);
    m.assign("rdata_o", "mem[raddr_i]");
    m
}
