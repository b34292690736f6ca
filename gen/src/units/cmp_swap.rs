//! `neo_cmp_swap`: one compare-exchange of the BSU network.

use crate::emit::expr::slice;
use crate::emit::Module;
use neo_golden::engine::EngineConfig;

/// Module name.
pub const NAME: &str = "neo_cmp_swap";

/// The compare-exchange: `lo_o` gets the entry first in THE ORDER, `hi_o` the other. It swaps
/// only when `b_i` strictly precedes `a_i`, comparing the low `key_bits + id_bits` bits
/// unsigned (the valid bit is payload), exactly as golden `Network::apply`.
pub fn module(cfg: &EngineConfig) -> Module {
    let w = cfg.entry_bits();
    let c = cfg.cmp_bits();
    let mut m = Module::new(NAME);
    m.doc("Compare-exchange of two packed {valid, key, id} entries (combinational).");
    m.doc(format!("Swaps only when b_i strictly precedes a_i in (key, id) = bits [{}:0], unsigned;", c - 1));
    m.doc("the valid bit rides along. Equal (key, id) never swap (golden Network::apply).");
    m.input_c("a_i", w, "entry on the lower wire i");
    m.input_c("b_i", w, "entry on the upper wire j > i");
    m.output_c("lo_o", w, "the entry first in (key, id) order, to wire i");
    m.output_c("hi_o", w, "the other entry, to wire j");
    m.wire_assign("swap", 1, format!("{} < {}", slice("b_i", c - 1, 0), slice("a_i", c - 1, 0)));
    m.assign("lo_o", "swap ? b_i : a_i");
    m.assign("hi_o", "swap ? a_i : b_i");
    m
}
