//! Named fields of a packed bundle. A bundle's layout is declared once in the Verilog as
//! `localparam` offsets (`PREFIX_NAME`, and `PREFIX_NAME_W` for a field wider than one bit), and
//! every access goes through them (`sig[PREFIX_NAME +: PREFIX_NAME_W]`), so no raw bit index of
//! the bundle appears outside its declaration.

use super::Module;

/// One field: name (lower case), least significant bit, width.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Field {
    /// Name, lower case (the localparam is its upper-case form behind the prefix).
    pub name: String,
    /// Least significant bit.
    pub lsb: u32,
    /// Width in bits.
    pub width: u32,
}

/// The layout of a packed bundle.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Bundle {
    prefix: String,
    fields: Vec<Field>,
}

impl Bundle {
    /// Fields `(name, width)` packed in order from bit 0 up.
    pub fn packed<S: AsRef<str>>(prefix: &str, fields: &[(S, u32)]) -> Self {
        let mut lsb = 0;
        let mut out = Vec::new();
        for (name, width) in fields {
            out.push(Field { name: name.as_ref().to_string(), lsb, width: *width });
            lsb += width;
        }
        Bundle { prefix: prefix.to_string(), fields: out }
    }

    /// Fields at given positions (they may overlap: a field can name a run of others).
    pub fn placed(prefix: &str, fields: impl IntoIterator<Item = Field>) -> Self {
        Bundle { prefix: prefix.to_string(), fields: fields.into_iter().collect() }
    }

    /// Total width: up to the highest field's top bit.
    pub fn width(&self) -> u32 {
        self.fields.iter().map(|f| f.lsb + f.width).max().unwrap_or(0)
    }

    /// The fields in layout order.
    pub fn fields(&self) -> &[Field] {
        &self.fields
    }

    fn field(&self, name: &str) -> &Field {
        self.fields
            .iter()
            .find(|f| f.name == name)
            .unwrap_or_else(|| panic!("no field {name} in bundle {}", self.prefix))
    }

    /// `PREFIX_NAME`: the localparam holding the field's least significant bit.
    pub fn offset(&self, name: &str) -> String {
        format!("{}_{}", self.prefix, self.field(name).name.to_uppercase())
    }

    /// `PREFIX_BITS`: the localparam holding the bundle's width (declared by
    /// [`Bundle::declare_bits`]).
    pub fn bits(&self) -> String {
        format!("{}_BITS", self.prefix)
    }

    /// Width of field `name`.
    pub fn width_of(&self, name: &str) -> u32 {
        self.field(name).width
    }

    /// Declares field `name`'s offset (and its width when wider than one bit).
    pub fn declare_field(&self, m: &mut Module, name: &str) {
        let f = self.field(name);
        m.localparam_int(self.offset(name), f.lsb);
        if f.width > 1 {
            m.localparam_int(format!("{}_W", self.offset(name)), f.width);
        }
    }

    /// Declares the bundle's width, `PREFIX_BITS`.
    pub fn declare_bits(&self, m: &mut Module) {
        m.localparam_int(self.bits(), self.width());
    }

    /// The bundle restricted to the fields `names` (in layout order): the ones a module reads,
    /// so that it declares no unused localparam.
    pub fn subset(&self, names: &[&str]) -> Bundle {
        for n in names {
            self.field(n);
        }
        let fields = self.fields.iter().filter(|f| names.contains(&f.name.as_str())).cloned().collect();
        Bundle { prefix: self.prefix.clone(), fields }
    }

    /// Declares every field.
    pub fn declare(&self, m: &mut Module) {
        for f in &self.fields {
            self.declare_field(m, &f.name);
        }
    }

    /// Field `name` of bundle signal `sig`: `sig[PREFIX_NAME +: PREFIX_NAME_W]` (`sig[PREFIX_NAME]`
    /// for a one-bit field).
    pub fn get(&self, sig: &str, name: &str) -> String {
        let o = self.offset(name);
        if self.field(name).width == 1 {
            format!("{sig}[{o}]")
        } else {
            format!("{sig}[{o} +: {o}_W]")
        }
    }

    /// The bundle with field `name` cut to its low `width` bits (the part a module reads).
    pub fn narrowed(mut self, name: &str, width: u32) -> Bundle {
        let f = self.fields.iter_mut().find(|f| f.name == name).unwrap_or_else(|| panic!("no field {name}"));
        assert!(width >= 1 && width <= f.width, "{width} bits of field {name} ({} bits)", f.width);
        f.width = width;
        self
    }

    /// The whole bundle in the low bits of the wider signal `sig`: `sig[0 +: PREFIX_BITS]`.
    pub fn low_of(&self, sig: &str) -> String {
        format!("{sig}[0 +: {}]", self.bits())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fields_are_named_by_offset_and_width() {
        let b = Bundle::packed("EL", &[("base", 9), ("mask", 4), ("last", 1)]);
        assert_eq!(b.width(), 14);
        assert_eq!(b.get("head", "mask"), "head[EL_MASK +: EL_MASK_W]");
        assert_eq!(b.get("head", "last"), "head[EL_LAST]");
        assert_eq!(b.clone().narrowed("base", 3).get("head", "base"), "head[EL_BASE +: EL_BASE_W]");
        let mut m = Module::new("t");
        b.declare_bits(&mut m);
        b.declare(&mut m);
        let v = m.to_verilog();
        for l in ["localparam EL_BITS = 14;", "localparam EL_MASK = 9;", "localparam EL_MASK_W = 4;"] {
            assert!(v.contains(l), "{l} missing in\n{v}");
        }
        assert!(!v.contains("EL_LAST_W"));
        let s = b.subset(&["last", "base"]);
        assert_eq!(s.fields().iter().map(|f| f.name.as_str()).collect::<Vec<_>>(), ["base", "last"]);
    }

    #[test]
    #[should_panic(expected = "no field")]
    fn an_unknown_field_is_a_generator_bug() {
        Bundle::packed("EL", &[("base", 9)]).get("x", "mask");
    }
}
