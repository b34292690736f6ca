//! The beat bundle: the fields of one Gaussian beat carried down `neo_scu`'s pipeline (S0 to
//! S5) as one packed register per stage. In the Verilog every field is named by `localparam`
//! offsets (`BEAT_NAME`, and `BEAT_NAME_W` for a field wider than one bit), so no raw bit index
//! of a bundle appears outside this layout.

use super::{ScuWidths, LID_BITS};
use crate::emit::bundle::Bundle;
use crate::emit::Module;

/// The layout of the beat bundle, fields packed from bit 0 in declaration order.
pub(super) struct Beat {
    bundle: Bundle,
    /// Total width.
    pub width: u32,
}

/// The fields: (name, width, what it is).
fn fields(w: &ScuWidths) -> Vec<(&'static str, u32, &'static str)> {
    vec![
        ("mean_x", w.mean, "mean x"),
        ("mean_y", w.mean, "mean y"),
        ("conic_a", w.mant, "conic a mantissa"),
        ("conic_b", w.mant + 1, "conic b mantissa (signed)"),
        ("conic_c", w.mant, "conic c mantissa"),
        ("conic_exp", w.cexp, "shared conic exponent"),
        ("opacity", w.opacity, "opacity"),
        ("red", w.color, "colour"),
        ("green", w.color, ""),
        ("blue", w.color, ""),
        ("origin_x", w.origin, "the list's subtile origin (pixels)"),
        ("origin_y", w.origin, ""),
        ("cols", w.side_bits + 1, "columns / rows inside the image"),
        ("rows", w.side_bits + 1, ""),
        ("empty", 1, "the beat carries no Gaussian"),
        ("last", 1, "the list's (piece's) last beat"),
        ("first", 1, "the list's first beat"),
        ("final", 1, "the piece ends the subtile"),
        ("resume", 1, "continue from the saved state"),
        ("sub", w.row_bits, "the subtile's state slot"),
        ("lid", LID_BITS, "list id"),
        ("pass", w.pass_bits(), "the pass (set at issue)"),
        ("nop", 1, "a skipped beat: no evaluation (set at issue)"),
    ]
}

impl Beat {
    /// The layout for `w`.
    pub fn new(w: &ScuWidths) -> Self {
        let named: Vec<(&str, u32)> = fields(w).into_iter().map(|(n, width, _)| (n, width)).collect();
        let bundle = Bundle::packed("BEAT", &named);
        Beat { width: bundle.width(), bundle }
    }

    /// The field names in layout order.
    pub fn names(&self) -> Vec<&str> {
        self.bundle.fields().iter().map(|f| f.name.as_str()).collect()
    }

    /// `BEAT_NAME`: the localparam holding the field's least significant bit.
    pub fn offset(&self, name: &str) -> String {
        self.bundle.offset(name)
    }

    /// Declares the layout as localparams (with a comment per field group).
    pub fn declare(&self, m: &mut Module, w: &ScuWidths) {
        m.comment(format!("Beat bundle ({} bits): field offsets BEAT_*, widths BEAT_*_W.", self.width));
        for (name, _, what) in fields(w) {
            if !what.is_empty() {
                m.comment(what);
            }
            self.bundle.declare_field(m, name);
        }
    }

    /// Field `name` of bundle signal `reg`: `reg[BEAT_NAME +: BEAT_NAME_W]` (`reg[BEAT_NAME]`
    /// for a one-bit field).
    pub fn get(&self, reg: &str, name: &str) -> String {
        self.bundle.get(reg, name)
    }
}
