//! `neo_clock_gate`: a glitch-free clock gate for a block that is idle most of the time (the
//! Preprocessing Engine between frames and during the tile walk). The enable is sampled on the
//! falling edge (`en_q`), so it changes only while the clock is low and `clk_o = clk_i & en_q`
//! has no glitch; an ASIC flow maps this onto its integrated clock-gating cell.
//!
//! Besides power, the gate is what keeps simulation fast: Verilator evaluates a clock domain's
//! logic only when its clock ticks, so an idle, gated block costs nothing per cycle.

use crate::emit::expr::lit;
use crate::emit::{set, Item, Module};
use neo_golden::engine::EngineConfig;

/// Module name.
pub const NAME: &str = "neo_clock_gate";

/// The clock gate (the same for every configuration).
pub fn module(_cfg: &EngineConfig) -> Module {
    let mut m = Module::new(NAME);
    m.doc("Clock gate: clk_o = clk_i while en_i (sampled on the falling edge, so clk_o never glitches).");
    m.clock_reset();
    m.input_c("en_i", 1, "enable for the next rising edge (sampled while clk_i is low)");
    m.output_c("clk_o", 1, "gated clock");
    m.reg("en_q", 1);
    m.item(Item::SeqFalling { reset: vec![set("en_q", lit(1, 0))], body: vec![set("en_q", "en_i")] });
    m.assign("clk_o", "clk_i & en_q");
    m
}
