//! `neo_chunk_ram`: one on-chip chunk buffer (`chunk * dps_wide` entries: the wide DPS chunk, or
//! the chunk without one), one synchronous write port and two asynchronous (combinational) read
//! ports, register-file style. An SRAM macro with registered reads would need a one-entry
//! prefetch in front of each read port.

use crate::emit::expr::bits_for;
use crate::emit::{if_, set, Module};
use neo_golden::engine::EngineConfig;

/// Module name.
pub const NAME: &str = "neo_chunk_ram";

/// The chunk buffer for `cfg`.
pub fn module(cfg: &EngineConfig) -> Module {
    let w = cfg.entry_bits();
    let depth = cfg.sort_buffer() as u32;
    let aw = bits_for(depth as u64 - 1);
    let mut m = Module::new(NAME);
    m.doc(format!("Chunk buffer: {depth} entries of {w} bits, 1 write port, 2 combinational read ports."));
    m.input_c("clk_i", 1, "clock");
    m.input("we_i", 1).input("waddr_i", aw).input("wdata_i", w);
    m.input("raddr0_i", aw).output("rdata0_o", w);
    m.input("raddr1_i", aw).output("rdata1_o", w);
    m.mem("mem", w, depth);
    m.seq_noreset(vec![if_("we_i", vec![set("mem[waddr_i]", "wdata_i")])]);
    m.assign("rdata0_o", "mem[raddr0_i]");
    m.assign("rdata1_o", "mem[raddr1_i]");
    m
}
