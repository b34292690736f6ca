//! `neo_perf_counters`: the engine's performance counters (golden
//! [`neo_golden::engine::regs::Counter`]), one `neo_perf_counter` per counter in the generate
//! loop `g_counter`.
//!
//! Each cycle counter `i` adds `inc_i[32i +: 32]` ([`INC_BITS`]). `clear_i` (the frame's start) restarts every
//! counter at that cycle's increment: `count <= (clear_i ? 0 : count) + inc`, so an event in
//! the start cycle itself is counted. Counters are 64 bits and wrap modulo 2^64. Counter `i` is
//! `counters_o[64i +: 64]`, registered (its value after the last rising edge).

use crate::emit::expr::lit;
use crate::emit::{conns, set, Instance, Item, Module};
use neo_golden::engine::regs::COUNTERS;
use neo_golden::engine::EngineConfig;

/// Module name of the bank of counters.
pub const NAME: &str = "neo_perf_counters";

/// Module name of one counter.
pub const COUNTER_NAME: &str = "neo_perf_counter";

/// Width of one counter.
pub const COUNT_BITS: u32 = 64;

/// Width of one counter's increment per cycle.
pub const INC_BITS: u32 = 32;

/// One 64-bit counter with a 32-bit increment and a synchronous clear.
pub fn counter_module(_cfg: &EngineConfig) -> Module {
    let (w, iw) = (COUNT_BITS, INC_BITS);
    let mut m = Module::new(COUNTER_NAME);
    m.doc(format!("One {w}-bit performance counter: adds inc_i every cycle; clear_i restarts it at this"));
    m.doc("cycle's increment (count <= (clear_i ? 0 : count) + inc_i). Wraps modulo 2^64.");
    m.clock_reset();
    m.input_c("clear_i", 1, "restart the count (the frame's start)");
    m.input_c("inc_i", iw, "amount added this cycle");
    m.output_c("count_o", w, "the count after the last rising edge");
    m.reg("count_q", w);
    m.wire_assign("base", w, format!("clear_i ? {} : count_q", lit(w, 0)));
    m.wire_assign("count_d", w, format!("base + {{{}, inc_i}}", lit(w - iw, 0)));
    let reset = m.q_resets(&[]);
    m.seq(reset, vec![set("count_q", "count_d")]);
    m.assign("count_o", "count_q");
    m
}

/// The bank of [`COUNTERS`] counters.
pub fn module(_cfg: &EngineConfig) -> Module {
    let n = COUNTERS as u32;
    let (w, iw) = (COUNT_BITS, INC_BITS);
    let mut m = Module::new(NAME);
    m.doc(format!("Performance counters: {n} x {w} bits (golden engine::regs::Counter, counter i at"));
    m.doc(format!("counters_o[{w}i +: {w}], its increment at inc_i[{iw}i +: {iw}]); clear_i restarts every"));
    m.doc("counter at this cycle's increment. See docs/rtl.md.");
    m.clock_reset();
    m.input_c("clear_i", 1, "restart every counter (the frame's start)");
    m.input_c("inc_i", iw * n, "per counter: amount added this cycle");
    m.output_c("counters_o", w * n, "per counter: the count");
    let items = vec![Item::Instance(Instance {
        module: COUNTER_NAME.into(),
        name: "u_counter".into(),
        params: Vec::new(),
        conns: conns(&[
            ("clk_i", "clk_i".into()),
            ("rst_ni", "rst_ni".into()),
            ("clear_i", "clear_i".into()),
            ("inc_i", format!("inc_i[i*{iw} +: {iw}]")),
            ("count_o", format!("counters_o[i*{w} +: {w}]")),
        ]),
    })];
    m.gen_for("i", n, "g_counter", items);
    m
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_counter_per_golden_counter() {
        let cfg = EngineConfig::default();
        let v = module(&cfg).to_verilog();
        assert!(v.contains(&format!("i < {COUNTERS}; i = i + 1) begin : g_counter")), "{v}");
        assert!(v.contains(&format!("output wire [{}:0] counters_o", 64 * COUNTERS - 1)), "{v}");
        assert_eq!(module(&cfg).instantiated(), vec![COUNTER_NAME.to_string()]);
        let c = counter_module(&cfg).to_verilog();
        assert!(
            c.contains(&format!("assign count_d = base + {{{}'d0, inc_i}};", COUNT_BITS - INC_BITS)),
            "{c}"
        );
    }
}
