//! The port list of a generated module: what the Verilator shim and the Rust bindings are
//! generated from.

use serde::{Deserialize, Serialize};

/// Direction of a port.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Dir {
    /// An input (`_i` suffix by convention).
    In,
    /// An output (`_o` suffix by convention).
    Out,
}

/// One port: a packed vector `[width-1:0]` (width 1 is a scalar).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Port {
    /// The Verilog name, e.g. `in_valid_i`.
    pub name: String,
    /// Input or output.
    pub dir: Dir,
    /// Width in bits (>= 1). Verilator maps 1..=8 to `CData`, ..=16 `SData`, ..=32 `IData`,
    /// ..=64 `QData`, and wider to `VlWide<(width+31)/32>` (little-endian 32-bit words).
    pub width: u32,
}

/// A module's name and ports, in declaration order.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct ModuleInterface {
    /// The module name (also its file name, `NAME.v`).
    pub name: String,
    /// The ports, clock (`clk_i`) and reset (`rst_ni`) included.
    pub ports: Vec<Port>,
}

impl ModuleInterface {
    /// The port called `name`, if any.
    pub fn port(&self, name: &str) -> Option<&Port> {
        self.ports.iter().find(|p| p.name == name)
    }
}
