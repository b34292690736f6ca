//! `neo_raster_window` and its cell `neo_raster_window_cell`: the raster core's reorder window
//! (golden [`neo_golden::raster::window`], docs/adaptive.md section 7), generated when the
//! configuration's `raster_window` `W` is above 1.
//!
//! The window holds up to `W - 1` entries `{key, id}` in `W - 1` cells kept sorted ascending
//! (cell 0 the smallest), each with the slot of its feature word in a store of `W - 1` words.
//! Per cycle one of:
//! - **insert** (a push while not full): the new entry goes to its place, the larger cells move
//!   up one; its feature word to the next unused slot;
//! - **replace** (a push while full, the window then holds `W` entries and emits the smallest):
//!   when the new entry is the smallest it is emitted at once (its feature word passes by);
//!   else cell 0 is emitted with its stored feature word, the new entry takes its slot, the cells
//!   below the new entry's place move down one;
//! - **pop** (draining at the table's end): cell 0 is emitted, every cell moves down one.
//!
//! Each cell compares its own entry with the new one (one comparator per cell) and chooses
//! its next value from itself, its neighbours and the new entry with its neighbours' compare
//! results (the shift-register priority queue of compare-and-hold cells).

use super::Dims;
use crate::emit::bundle::Bundle;
use crate::emit::expr::lit;
use crate::emit::{if_, if_else, set, Instance, Item, Module, Stmt};
use neo_golden::engine::EngineConfig;

/// The window's module name.
pub const NAME: &str = "neo_raster_window";

/// The cell's module name.
pub const CELL_NAME: &str = "neo_raster_window_cell";

/// Cell operations (`op_i`).
const OP_HOLD: u64 = 0;
const OP_INSERT: u64 = 1;
const OP_REPLACE: u64 = 2;
const OP_POP: u64 = 3;

/// The window's widths: key, id, feature word, slot index, and its cells.
struct WindowDims {
    kb: u32,
    ib: u32,
    fw: u32,
    slot: u32,
    cells: u32,
}

impl WindowDims {
    fn new(cfg: &EngineConfig) -> Self {
        let d = Dims::new(cfg);
        let w = cfg.raster_window as u32;
        assert!(w.is_power_of_two() && w >= 4, "a window of {w} entries is not generated");
        WindowDims { kb: d.kb, ib: d.ib, fw: d.fw, slot: w.trailing_zeros(), cells: w - 1 }
    }

    /// A cell's word `{valid, slot, key, id}`: localparams `WC_*`.
    fn cell(&self) -> Bundle {
        Bundle::packed("WC", &[("id", self.ib), ("key", self.kb), ("slot", self.slot), ("valid", 1)])
    }
}

/// The cell's operation localparams (`OP_HOLD` only where it is used: the cell holds on any
/// other operation).
fn op_params(m: &mut Module, hold: bool) {
    let ops =
        [("OP_HOLD", OP_HOLD), ("OP_INSERT", OP_INSERT), ("OP_REPLACE", OP_REPLACE), ("OP_POP", OP_POP)];
    for (n, v) in ops.into_iter().filter(|&(n, _)| hold || n != "OP_HOLD") {
        m.localparam(n, 2, lit(2, v));
    }
}

/// `{key, id}` of cell word `sig`: the order the window sorts by.
fn order_of(b: &Bundle, sig: &str) -> String {
    format!("{{{}, {}}}", b.get(sig, "key"), b.get(sig, "id"))
}

/// One cell of the window for `cfg`.
pub fn cell_module(cfg: &EngineConfig) -> Module {
    let wd = WindowDims::new(cfg);
    let cw = wd.cell().width();
    let mut m = Module::new(CELL_NAME);
    m.doc("One cell of the raster core's reorder window: holds an entry {valid, slot, key, id}, compares it with");
    m.doc("the new entry and takes its next value from itself, its neighbours or the new entry.");
    m.clock_reset();
    m.input_c("clear_i", 1, "empty the cell (a new tile)");
    m.input_c("op_i", 2, "OP_HOLD, OP_INSERT, OP_REPLACE or OP_POP");
    m.input_c("new_i", cw, "the new entry (valid)");
    m.input_c("prev_i", cw, "the cell below (smaller; unused by cell 0)");
    m.input_c("next_i", cw, "the cell above (larger; empty above the last cell)");
    m.input_c("lt_prev_i", 1, "the cell below is before the new entry (1 for cell 0)");
    m.input_c("lt_next_i", 1, "the cell above is before the new entry (0 above the last cell)");
    m.output_c("cell_o", cw, "the entry held");
    m.output_c("lt_o", 1, "the entry held is valid and before the new entry by {key, id}");
    m.blank();
    op_params(&mut m, false);
    let b = wd.cell();
    b.subset(&["id", "key", "valid"]).declare(&mut m);
    m.reg("cell_q", cw);
    m.assign("cell_o", "cell_q");
    m.assign(
        "lt_o",
        format!("{} & ({} < {})", b.get("cell_q", "valid"), order_of(&b, "cell_q"), order_of(&b, "new_i")),
    );
    m.comment(
        "Insert: keep a smaller entry, else take the new one (below it a smaller one) or the one below.",
    );
    m.comment("Replace (cell 0 leaves): take the one above while it is smaller than the new entry, else the");
    m.comment("new one where this entry is smaller, else keep. Pop: take the one above.");
    let body = vec![if_else(
        "clear_i",
        vec![set("cell_q", lit(cw, 0))],
        vec![Stmt::Case(
            "op_i".into(),
            vec![
                ("OP_INSERT".into(), vec![if_("~lt_o", vec![set("cell_q", "lt_prev_i ? new_i : prev_i")])]),
                ("OP_REPLACE".into(), vec![set("cell_q", "lt_next_i ? next_i : (lt_o ? new_i : cell_q)")]),
                ("OP_POP".into(), vec![set("cell_q", "next_i")]),
            ],
            Vec::new(),
        )],
    )];
    m.seq_d(Some(vec![set("cell_q", lit(cw, 0))]), body);
    m
}

/// The window for `cfg`.
pub fn module(cfg: &EngineConfig) -> Module {
    let wd = WindowDims::new(cfg);
    let (kb, ib, fw, sb, n) = (wd.kb, wd.ib, wd.fw, wd.slot, wd.cells);
    let b = wd.cell();
    let cw = b.width();
    let mut m = Module::new(NAME);
    m.doc(format!(
        "Raster core reorder window of {} entries (golden raster::window): pushes in table order; once it holds",
        n + 1
    ));
    m.doc("that many it emits the smallest {key, id}; pops drain it smallest first. One entry per cycle.");
    m.clock_reset();
    m.input_c("clear_i", 1, "empty the window (a new tile)");
    m.input_c("push_i", 1, "an entry arrives (taken in the cycle)");
    m.input_c("push_key_i", kb, "its current key");
    m.input_c("push_id_i", ib, "its Gaussian id");
    m.input_c("push_feat_i", fw, "its feature word");
    m.input_c("pop_i", 1, "drain: emit the smallest (ignored with push_i or when empty)");
    m.output_c("emit_valid_o", 1, "an entry leaves (a push while full, or a pop)");
    m.output_c("emit_key_o", kb, "its key");
    m.output_c("emit_id_o", ib, "its id");
    m.output_c("emit_feat_o", fw, "its feature word");
    m.output_c("full_o", 1, "the window holds its cells' worth: the next push emits");
    m.output_c("empty_o", 1, "the window holds nothing");
    m.blank();
    op_params(&mut m, true);
    b.declare_bits(&mut m);
    b.declare(&mut m);
    m.localparam_int("CELLS", n);
    m.comment(format!("{n} cells, sorted ascending from cell 0, and the feature words they hold by slot."));
    m.wire("cells", n * cw).wire("cell_lt", n);
    m.vector("cell_lt");
    m.mem("store", fw, n);
    m.reg("fill_slot_q", sb);
    m.wire_assign("head", cw, format!("cells[0 +: {}]", b.bits()));
    m.wire_assign("full", 1, format!("cells[(CELLS - 1) * {} + {}]", b.bits(), b.offset("valid")));
    m.wire_assign("insert", 1, "push_i & ~full");
    m.wire_assign("replace", 1, "push_i & full");
    m.wire_assign("pop", 1, format!("pop_i & ~push_i & {}", b.get("head", "valid")));
    m.comment("The new entry is the smallest: it leaves at once.");
    m.wire_assign("bypass", 1, "replace & ~cell_lt[0]");
    m.wire_assign(
        "op",
        2,
        "insert ? OP_INSERT : ((replace & cell_lt[0]) ? OP_REPLACE : (pop ? OP_POP : OP_HOLD))",
    );
    m.wire("new_cell", cw);
    m.assign(b.get("new_cell", "valid"), lit(1, 1));
    m.assign(b.get("new_cell", "slot"), format!("insert ? fill_slot_q : {}", b.get("head", "slot")));
    m.assign(b.get("new_cell", "key"), "push_key_i");
    m.assign(b.get("new_cell", "id"), "push_id_i");
    m.comment(
        "The neighbours of cell i: below (cell 0: none, its lt_prev is 1) and above (the last: empty).",
    );
    m.wire_assign("prev_cells", (n + 1) * cw, format!("{{cells, {}}}", lit(cw, 0)));
    m.wire_assign("next_cells", (n + 1) * cw, format!("{{{}, cells}}", lit(cw, 0)));
    m.wire_assign("prev_lt", n + 1, format!("{{cell_lt, {}}}", lit(1, 1)));
    m.wire_assign("next_lt", n + 1, format!("{{{}, cell_lt}}", lit(1, 0)));
    m.comment("Ends of the neighbour vectors no cell reads.");
    m.wire_assign(
        "unused_ends",
        1,
        format!(
            "^{{prev_cells[CELLS * {b} +: {b}], next_cells[0 +: {b}], prev_lt[CELLS], next_lt[0]}}",
            b = b.bits()
        ),
    );
    let s = |p: &str, e: String| (p.to_string(), e);
    let slice = |v: &str, k: &str| format!("{v}[({k}) * {} +: {}]", b.bits(), b.bits());
    m.gen_for(
        "i",
        n,
        "g_cell",
        vec![Item::Instance(Instance {
            module: CELL_NAME.into(),
            name: "u_cell".into(),
            params: Vec::new(),
            conns: vec![
                s("clk_i", "clk_i".into()),
                s("rst_ni", "rst_ni".into()),
                s("clear_i", "clear_i".into()),
                s("op_i", "op".into()),
                s("new_i", "new_cell".into()),
                s("prev_i", slice("prev_cells", "i")),
                s("next_i", slice("next_cells", "i + 1")),
                s("lt_prev_i", "prev_lt[i]".into()),
                s("lt_next_i", "next_lt[i + 1]".into()),
                s("cell_o", slice("cells", "i")),
                s("lt_o", "cell_lt[i]".into()),
            ],
        })],
    );
    m.comment("Feature words: a push takes the next unused slot while filling, cell 0's slot on a replace.");
    let next = format!("fill_slot_q + {}", lit(sb, 1));
    m.seq_d(
        Some(vec![set("fill_slot_q", lit(sb, 0))]),
        vec![if_else(
            "clear_i",
            vec![set("fill_slot_q", lit(sb, 0))],
            vec![if_("insert", vec![set("fill_slot_q", next)])],
        )],
    );
    m.seq_noreset(vec![
        if_("insert", vec![set("store[fill_slot_q]", "push_feat_i")]),
        if_("replace & cell_lt[0]", vec![set(format!("store[{}]", b.get("head", "slot")), "push_feat_i")]),
    ]);
    m.assign("emit_valid_o", "replace | pop");
    m.assign("emit_key_o", format!("bypass ? push_key_i : {}", b.get("head", "key")));
    m.assign("emit_id_o", format!("bypass ? push_id_i : {}", b.get("head", "id")));
    m.assign("emit_feat_o", format!("bypass ? push_feat_i : store[{}]", b.get("head", "slot")));
    m.assign("full_o", "full");
    m.assign("empty_o", format!("~{}", b.get("head", "valid")));
    m
}
