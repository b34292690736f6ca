//! `neo_msu`: the Merge Sort Unit+, a streaming two-way merge of sorted streams that can drop
//! invalid entries (golden [`neo_golden::sort::merge2`] / [`neo_golden::sort::MergeStream`]).
//!
//! # Stream protocol (inputs `a_*`, `b_*` and output `out_*`)
//! A stream is a sequence of beats, each transferred on `valid & ready`. A beat either carries
//! an entry (`empty = 0`, `data` valid) or carries none (`empty = 1`, `data` ignored). The beat
//! with `last = 1` ends the stream. A stream of `n >= 1` entries is `n` entry beats, `last` on
//! the `n`-th; an EMPTY stream is a single beat with `empty = 1, last = 1`. (Inputs may also
//! send `empty` beats with `last = 0`: they are consumed and ignored.) The output stream uses
//! the same protocol: its entries carry `out_empty_o = 0`, and a merge whose output has no entry
//! produces exactly one beat with `out_empty_o = 1, out_last_o = 1`.
//!
//! # Merge rule
//! Entries are compared on `(key, id)` (the low `key_bits + id_bits` bits, unsigned); on equal
//! `(key, id)` A goes first. With `drop_invalid_i = 1`, entries whose valid bit is 0 are
//! consumed and not emitted. `drop_invalid_i` must be stable for a whole merge.
//!
//! # Schedule and throughput
//! Each cycle follows one [`neo_golden::sort::MergeStream`] step on the current heads: if a head
//! is to be dropped (invalid with `drop_invalid_i`, or an empty beat) the dropping heads are
//! popped and nothing is selected; otherwise the head first in the order is popped (the other
//! stream may have ended; a head whose beat is not offered yet stalls the merge unless its
//! stream has ended). A selected entry waits in a one-entry pending register until the next
//! entry is selected (it then moves to the output register with `last = 0`) or both streams have
//! ended (it moves out with `last = 1`). So with both inputs offering beats and `out_ready_i`
//! high, the output carries one entry per cycle except for cycles that only drop; latency from
//! pop to `out_valid_o` is 2 cycles for all but the last entry; the end of a merge costs one
//! extra cycle (the done flags are registered), after which the next merge's beats are taken.
//!
//! `a_ready_o`/`b_ready_o` depend combinationally on both inputs' `valid`/`data` and on
//! `out_ready_i` (never the other way round); `out_valid_o` is registered.
//!
//! # Boundary inversions of A
//! One comparator on the entries selected from A counts those that precede the previous entry
//! selected from A in the same merge ([`neo_golden::sort::MergeStats::a_inversions`]: what the
//! DPS passes left unsorted in the reused table; dropped entries are not selected, so with
//! `drop_invalid_i` only kept entries count). `a_inv_o` is the count of the last finished merge:
//! it is updated at the end-of-merge flush, so it is valid with `out_last_o` and holds until the
//! next merge ends. The count saturates at its all-ones value.

use crate::emit::expr::{lit, slice};
use crate::emit::{if_, if_else, set, Module};
use neo_golden::engine::EngineConfig;

/// Module name.
pub const NAME: &str = "neo_msu";

/// The MSU+ for `cfg`.
pub fn module(cfg: &EngineConfig) -> Module {
    let w = cfg.entry_bits();
    let c = cfg.cmp_bits();
    let mut m = Module::new(NAME);
    m.doc("Merge Sort Unit+: two-way merge of sorted streams A (reused table) and B (incoming), ties to A,");
    m.doc("dropping entries with valid = 0 when drop_invalid_i. Stream beats: data or empty; last ends the stream;");
    m.doc("an empty stream is one beat with empty = 1, last = 1. See docs/rtl.md.");
    m.clock_reset();
    m.input_c("drop_invalid_i", 1, "drop entries whose valid bit is 0 (hold stable during a merge)");
    for s in ["a", "b"] {
        m.input(format!("{s}_valid_i"), 1);
        m.output(format!("{s}_ready_o"), 1);
        m.input_c(format!("{s}_data_i"), w, "{valid, key, id}");
        m.input_c(format!("{s}_last_i"), 1, "final beat of the stream");
        m.input_c(format!("{s}_empty_i"), 1, "beat carries no entry");
    }
    m.output("out_valid_o", 1);
    m.input("out_ready_i", 1);
    m.output("out_data_o", w);
    m.output("out_last_o", 1);
    m.output_c("out_empty_o", 1, "beat carries no entry (only as the single beat of an empty merge)");
    let lw = cfg.len_bits;
    m.output_c("a_inv_o", lw, "boundary inversions of A in the last finished merge");

    m.reg("a_done_q", 1).reg("b_done_q", 1).reg("pend_valid_q", 1).reg("pend_data_q", w);
    m.reg("out_valid_q", 1).reg("out_data_q", w).reg("out_last_q", 1).reg("out_empty_q", 1);
    m.blank();
    m.comment("Head fields: live = the entry's valid bit (0: deleted), rank = {key, id}, the merge order.");
    for s in ["a", "b"] {
        m.wire_assign(format!("{s}_live"), 1, slice(&format!("{s}_data_i"), w - 1, w - 1));
        m.wire_assign(format!("{s}_rank"), c, slice(&format!("{s}_data_i"), c - 1, 0));
    }
    m.comment("Heads: available, to be dropped, or carrying an entry to merge.");
    for s in ["a", "b"] {
        m.wire_assign(format!("{s}_avail"), 1, format!("{s}_valid_i & ~{s}_done_q"));
        m.wire_assign(
            format!("{s}_skip"),
            1,
            format!("{s}_avail & ({s}_empty_i | (drop_invalid_i & ~{s}_live))"),
        );
        m.wire_assign(format!("{s}_ent"), 1, format!("{s}_avail & ~{s}_skip"));
    }
    m.wire_assign("b_first", 1, "b_rank < a_rank");
    m.wire_assign("any_skip", 1, "a_skip | b_skip");
    m.wire_assign("take_a", 1, "~any_skip & a_ent & (b_done_q | (b_ent & ~b_first))");
    m.wire_assign("take_b", 1, "~any_skip & b_ent & (a_done_q | (a_ent & b_first))");
    m.wire_assign("out_free", 1, "~out_valid_q | out_ready_i");
    m.wire_assign("pend_free", 1, "~pend_valid_q | out_free");
    m.wire_assign("fire", 1, "(take_a | take_b) & pend_free");
    m.wire_assign("a_pop", 1, "a_skip | (take_a & pend_free)");
    m.wire_assign("b_pop", 1, "b_skip | (take_b & pend_free)");
    m.wire_assign("flush", 1, "a_done_q & b_done_q & out_free");
    m.wire_assign("shift_out", 1, "fire & pend_valid_q");
    m.assign("a_ready_o", "a_pop");
    m.assign("b_ready_o", "b_pop");
    m.blank();
    m.comment(
        "Boundary inversions of A: an entry selected from A that precedes the previous one selected from A.",
    );
    m.reg("last_a_valid_q", 1).reg("last_a_rank_q", c).reg("inv_q", lw).reg("a_inv_q", lw);
    m.wire_assign("a_descent", 1, "fire & take_a & last_a_valid_q & (a_rank < last_a_rank_q)");
    m.wire_assign("inv_full", 1, format!("inv_q == {{{lw}{{1'b1}}}}"));
    m.seq(
        vec![
            set("last_a_valid_q", lit(1, 0)),
            set("last_a_rank_q", lit(c, 0)),
            set("inv_q", lit(lw, 0)),
            set("a_inv_q", lit(lw, 0)),
        ],
        vec![if_else(
            "flush",
            vec![set("last_a_valid_q", lit(1, 0)), set("inv_q", lit(lw, 0)), set("a_inv_q", "inv_q")],
            vec![
                if_("fire & take_a", vec![set("last_a_valid_q", lit(1, 1)), set("last_a_rank_q", "a_rank")]),
                if_("a_descent & ~inv_full", vec![set("inv_q", format!("inv_q + {}", lit(lw, 1)))]),
            ],
        )],
    );
    m.assign("a_inv_o", "a_inv_q");
    m.blank();
    m.seq(
        vec![
            set("a_done_q", lit(1, 0)),
            set("b_done_q", lit(1, 0)),
            set("pend_valid_q", lit(1, 0)),
            set("out_valid_q", lit(1, 0)),
            set("out_last_q", lit(1, 0)),
            set("out_empty_q", lit(1, 0)),
        ],
        vec![
            if_else(
                "flush",
                vec![set("a_done_q", lit(1, 0)), set("b_done_q", lit(1, 0))],
                vec![
                    if_("a_pop & a_last_i", vec![set("a_done_q", lit(1, 1))]),
                    if_("b_pop & b_last_i", vec![set("b_done_q", lit(1, 1))]),
                ],
            ),
            if_else(
                "fire",
                vec![set("pend_valid_q", lit(1, 1))],
                vec![if_("flush", vec![set("pend_valid_q", lit(1, 0))])],
            ),
            if_else(
                "flush",
                vec![
                    set("out_valid_q", lit(1, 1)),
                    set("out_last_q", lit(1, 1)),
                    set("out_empty_q", "~pend_valid_q"),
                ],
                vec![if_else(
                    "shift_out",
                    vec![
                        set("out_valid_q", lit(1, 1)),
                        set("out_last_q", lit(1, 0)),
                        set("out_empty_q", lit(1, 0)),
                    ],
                    vec![if_("out_ready_i", vec![set("out_valid_q", lit(1, 0))])],
                )],
            ),
        ],
    );
    m.seq_noreset(vec![
        if_("fire", vec![set("pend_data_q", "take_b ? b_data_i : a_data_i")]),
        if_(
            "shift_out | flush",
            vec![set("out_data_q", format!("pend_valid_q ? pend_data_q : {}", lit(w, 0)))],
        ),
    ]);
    m.blank();
    m.assign("out_valid_o", "out_valid_q");
    m.assign("out_data_o", "out_data_q");
    m.assign("out_last_o", "out_last_q");
    m.assign("out_empty_o", "out_empty_q");
    m
}
