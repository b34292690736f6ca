//! Generates, from a [`ModuleInterface`], the `extern "C"` C++ shim around a Verilated model and
//! the safe Rust wrapper that calls it.
//!
//! C side, for a top `T` (every symbol prefixed `neo_T_`):
//! `void* neo_T_new(uint32_t rand_reset, uint32_t seed)` (one `VerilatedContext` per model, owned
//! by it; its `randReset` and `randSeed` set before the model is constructed, which draws the
//! initial values of every variable from them: `crate::xinit`; inputs start at zero), `neo_T_free`,
//! `neo_T_eval`, `neo_T_set_P(void*, uint64_t)` / `uint64_t neo_T_get_P(void*)` for ports of
//! at most 64 bits, `neo_T_set_P_words(void*, const uint32_t*, size_t)` /
//! `neo_T_get_P_words(void*, uint32_t*, size_t)` for wider ones (little-endian 32-bit words),
//! `int neo_T_trace_open(void*, const char*)`, `neo_T_trace_dump(void*, uint64_t)`,
//! `neo_T_trace_close(void*)`; [`cpp_by_index`] adds `neo_T_set_port` / `neo_T_get_port` taking
//! a port's index in the interface (for models loaded at run time). Setters mask the value to the port width (Verilator requires the
//! unused high bits of a port to be zero).
//!
//! Rust side: a struct named after the top in CamelCase (`neo_bsu` -> `NeoBsu`) with typed
//! setters and getters (`bool` for 1 bit, `u64` up to 64 bits, `[u32; W]` above), `eval`, `tick`,
//! `reset`, `cycle`, tracing, `Drop`, and an implementation of `crate::dut::Dut`. A generated
//! top's wrapper ([`HdlFiles`]) runs, when `$NEO_HDL_DIR` holds other Verilog for it, a model of
//! that Verilog built at run time (`crate::hdl_dir::substitute`, a `crate::dynmodel::DynModel`)
//! instead of the linked one: every method then dispatches to it (ports by index).

use neo_gen::interface::{Dir, ModuleInterface, Port};
use std::fmt::Write;

/// Bump whenever the generated C++ changes: it is part of the cache key (the Rust wrapper is
/// regenerated on every build).
pub const SHIM_VERSION: u32 = 5;

/// The Verilog a generated top's static model is built from: the file names (the top's and
/// every module it instantiates) and their hash (`build/hdl_hash.rs`). Its wrapper compares
/// them with `$NEO_HDL_DIR`'s at run time (`neo_tb::hdl_dir`).
pub struct HdlFiles {
    /// The file names, e.g. `neo_bsu.v`.
    pub names: Vec<String>,
    /// `hdl_hash::verilog_hash` of the files.
    pub hash: String,
}

/// Number of 32-bit words of a `width`-bit port.
fn words(width: u32) -> u32 {
    width.div_ceil(32)
}

/// Mask of the valid bits of the top word (or of the whole value for narrow ports).
fn top_mask(width: u32) -> u64 {
    let bits = if width > 64 { width - 32 * (words(width) - 1) } else { width };
    if bits >= 64 {
        u64::MAX
    } else {
        (1u64 << bits) - 1
    }
}

/// The Verilator C type of a port of at most 64 bits.
fn c_type(width: u32) -> &'static str {
    match width {
        0..=8 => "CData",
        9..=16 => "SData",
        17..=32 => "IData",
        _ => "QData",
    }
}

/// `neo_bsu` -> `NeoBsu`.
pub fn struct_name(top: &str) -> String {
    top.split('_')
        .filter(|s| !s.is_empty())
        .map(|s| {
            let mut c = s.chars();
            match c.next() {
                Some(f) => f.to_ascii_uppercase().to_string() + c.as_str(),
                None => String::new(),
            }
        })
        .collect()
}

/// Checks that names are usable as C and Rust identifiers and widths are sane.
pub fn validate(iface: &ModuleInterface) -> Result<(), String> {
    let ident = |s: &str| {
        !s.is_empty()
            && s.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
            && !s.starts_with(|c: char| c.is_ascii_digit())
    };
    if !ident(&iface.name) {
        return Err(format!("module name {:?} is not an identifier", iface.name));
    }
    for p in &iface.ports {
        if !ident(&p.name) {
            return Err(format!("{}: port name {:?} is not an identifier", iface.name, p.name));
        }
        if p.width == 0 || p.width > 4096 {
            return Err(format!("{}: port {} has width {}", iface.name, p.name, p.width));
        }
    }
    Ok(())
}

/// How the model behind a shim is traced.
#[allow(dead_code)] // build.rs builds traced models only (no `Off`)
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShimTrace {
    /// Verilated without tracing: `neo_T_trace_open` returns 0, dump and close do nothing.
    Off,
    /// `--trace`: a `VerilatedVcdC` writer.
    Vcd,
    /// `--trace-fst`: a `VerilatedFstC` writer.
    Fst,
}

/// The C++ shim for one top with the trace writer of `--trace` (VCD), `--trace-fst` (FST) or
/// none; the entry points are the same (untraced, `neo_T_trace_open` returns 0 and dump and
/// close do nothing).
pub fn cpp_traced(iface: &ModuleInterface, trace: ShimTrace) -> String {
    let t = &iface.name;
    let v = format!("V{t}");
    let writer = match trace {
        ShimTrace::Off => None,
        ShimTrace::Vcd => Some(("verilated_vcd_c.h", "VerilatedVcdC")),
        ShimTrace::Fst => Some(("verilated_fst_c.h", "VerilatedFstC")),
    };
    let mut s = String::new();
    let _ = match writer {
        Some(_) => {
            writeln!(s, "// Generated by neo-tb/build.rs (shim v{SHIM_VERSION}) from the interface of `{t}`.")
        }
        None => writeln!(
            s,
            "// Generated by neo-tb (shim v{SHIM_VERSION}, untraced) from the interface of `{t}`."
        ),
    };
    s.push_str("// Do not edit: it is regenerated on every cache miss.\n");
    s.push_str("#include <cstddef>\n#include <cstdint>\n#include \"verilated.h\"\n");
    if let Some((header, _)) = writer {
        let _ = writeln!(s, "#include \"{header}\"");
    }
    let _ = writeln!(s, "#include \"{v}.h\"\n");
    let _ = writeln!(s, "namespace {{\nstruct Model_{t} {{\n  VerilatedContext ctx;\n  {v}* top = nullptr;");
    if let Some((_, w)) = writer {
        let _ = writeln!(s, "  {w}* vcd = nullptr;");
    }
    let _ = writeln!(
        s,
        "}};\ninline Model_{t}* m(void* p) {{ return static_cast<Model_{t}*>(p); }}\n}}  // namespace\n"
    );
    s.push_str("extern \"C\" {\n\n");
    let trace_on = if writer.is_some() { "  mm->ctx.traceEverOn(true);\n" } else { "" };
    // The initial values (`--x-initial unique`) are drawn by `VL_RAND_RESET` in the model's
    // constructor, from the thread's context (the context just constructed sets itself as that),
    // as its randReset says (0 zeros, 1 ones, 2 random from randSeed). The inputs are the
    // bench's: they start at zero whatever the mode.
    let mut zero_inputs = String::new();
    for p in iface.ports.iter().filter(|p| p.dir == Dir::In) {
        if p.width <= 64 {
            let _ = writeln!(zero_inputs, "  mm->top->{} = 0;", p.name);
        } else {
            let _ = writeln!(
                zero_inputs,
                "  for (size_t i = 0; i < {}; ++i) mm->top->{}[i] = 0u;",
                words(p.width),
                p.name
            );
        }
    }
    let _ = writeln!(
        s,
        "void* neo_{t}_new(uint32_t rand_reset, uint32_t seed) {{\n  Model_{t}* mm = new Model_{t};\n  Verilated::threadContextp(&mm->ctx);\n  mm->ctx.randReset((int)rand_reset);\n  mm->ctx.randSeed((int)seed);\n{trace_on}  mm->top = new {v}(&mm->ctx, \"TOP\");\n{zero_inputs}  return mm;\n}}\n"
    );
    let close = if writer.is_some() { "  if (mm->vcd) { mm->vcd->close(); delete mm->vcd; }\n" } else { "" };
    let _ = writeln!(
        s,
        "void neo_{t}_free(void* p) {{\n  Model_{t}* mm = m(p);\n{close}  mm->top->final();\n  delete mm->top;\n  delete mm;\n}}\n"
    );
    let _ = writeln!(s, "void neo_{t}_eval(void* p) {{ m(p)->top->eval(); }}\n");
    for p in &iface.ports {
        cpp_port(&mut s, t, p);
    }
    match writer {
        Some((_, w)) => cpp_trace_calls(&mut s, t, w),
        None => {
            let _ = writeln!(s, "int neo_{t}_trace_open(void*, const char*) {{ return 0; }}\n");
            let _ = writeln!(s, "void neo_{t}_trace_dump(void*, uint64_t) {{}}\n");
            let _ = writeln!(s, "void neo_{t}_trace_close(void*) {{}}\n");
        }
    }
    s.push_str("}  // extern \"C\"\n");
    s
}

/// The trace entry points of a traced shim, writing through a `writer` (VCD or FST).
fn cpp_trace_calls(s: &mut String, t: &str, writer: &str) {
    let _ = writeln!(
        s,
        "int neo_{t}_trace_open(void* p, const char* path) {{\n  Model_{t}* mm = m(p);\n  if (mm->vcd) {{ mm->vcd->close(); delete mm->vcd; }}\n  mm->vcd = new {writer};\n  mm->top->trace(mm->vcd, 99);\n  mm->vcd->open(path);\n  if (!mm->vcd->isOpen()) {{ delete mm->vcd; mm->vcd = nullptr; return 0; }}\n  return 1;\n}}\n"
    );
    let _ = writeln!(
        s,
        "void neo_{t}_trace_dump(void* p, uint64_t time) {{\n  Model_{t}* mm = m(p);\n  if (mm->vcd) {{ mm->ctx.time(time); mm->vcd->dump(time); }}\n}}\n"
    );
    let _ = writeln!(
        s,
        "void neo_{t}_trace_close(void* p) {{\n  Model_{t}* mm = m(p);\n  if (mm->vcd) {{ mm->vcd->close(); delete mm->vcd; mm->vcd = nullptr; }}\n}}\n"
    );
}

/// Appended to the shim of a coverage model (`--coverage`, `VM_COVERAGE=1`):
/// `void neo_T_coverage_write(void*, const char* path)` writes the model's coverage counts
/// (`VerilatedCovContext::write`, Verilator's `.dat` format) to `path`.
pub fn cpp_coverage(s: &mut String, iface: &ModuleInterface) {
    let t = &iface.name;
    s.push_str("#include \"verilated_cov.h\"\n\nextern \"C\" {\n\n");
    let _ = writeln!(
        s,
        "void neo_{t}_coverage_write(void* p, const char* path) {{ m(p)->ctx.coveragep()->write(path); }}\n"
    );
    s.push_str("}  // extern \"C\"\n");
}

/// Appended to [`cpp`] for models loaded at run time (a second `extern "C"` block):
/// `neo_T_set_port(void*, size_t index, const uint32_t* words, size_t n)` and
/// `neo_T_get_port(void*, size_t index, uint32_t* words, size_t n)`: every port by its index in
/// the interface (little-endian 32-bit words; setting an output or an unknown index does
/// nothing), for callers that bind ports at run time (`neo_tb::dynmodel`).
#[allow(dead_code)] // used by neo_tb::dynmodel, not by build.rs
pub fn cpp_by_index(s: &mut String, iface: &ModuleInterface) {
    let t = &iface.name;
    s.push_str("extern \"C\" {\n\n");
    let _ = writeln!(
        s,
        "void neo_{t}_set_port(void* p, size_t idx, const uint32_t* w, size_t n) {{\n  switch (idx) {{"
    );
    for (i, p) in iface.ports.iter().enumerate().filter(|(_, p)| p.dir == Dir::In) {
        let n = &p.name;
        if p.width <= 64 {
            let _ = writeln!(
                s,
                "    case {i}: neo_{t}_set_{n}(p, (n > 0 ? (uint64_t)w[0] : 0u) | (n > 1 ? (uint64_t)w[1] << 32 : 0u)); break;"
            );
        } else {
            let _ = writeln!(s, "    case {i}: neo_{t}_set_{n}_words(p, w, n); break;");
        }
    }
    s.push_str("    default: break;\n  }\n}\n\n");
    let _ = writeln!(
        s,
        "void neo_{t}_get_port(void* p, size_t idx, uint32_t* w, size_t n) {{\n  switch (idx) {{"
    );
    for (i, p) in iface.ports.iter().enumerate() {
        let n = &p.name;
        if p.width <= 64 {
            let _ = writeln!(
                s,
                "    case {i}: {{ uint64_t v = neo_{t}_get_{n}(p); if (n > 0) w[0] = (uint32_t)v; if (n > 1) w[1] = (uint32_t)(v >> 32); break; }}"
            );
        } else {
            let _ = writeln!(s, "    case {i}: neo_{t}_get_{n}_words(p, w, n); break;");
        }
    }
    s.push_str("    default: break;\n  }\n}\n\n");
    s.push_str("}  // extern \"C\"\n");
}

fn cpp_port(s: &mut String, t: &str, p: &Port) {
    let n = &p.name;
    if p.width <= 64 {
        if p.dir == Dir::In {
            let _ = writeln!(
                s,
                "void neo_{t}_set_{n}(void* p, uint64_t v) {{ m(p)->top->{n} = ({ty})(v & 0x{mask:x}ULL); }}",
                ty = c_type(p.width),
                mask = top_mask(p.width)
            );
        }
        let _ = writeln!(s, "uint64_t neo_{t}_get_{n}(void* p) {{ return (uint64_t)m(p)->top->{n}; }}\n");
    } else {
        let w = words(p.width);
        if p.dir == Dir::In {
            let _ = writeln!(
                s,
                "void neo_{t}_set_{n}_words(void* p, const uint32_t* w, size_t n) {{\n  auto& port = m(p)->top->{n};\n  for (size_t i = 0; i < {w}; ++i) port[i] = i < n ? w[i] : 0u;\n  port[{last}] &= 0x{mask:x}u;\n}}",
                last = w - 1,
                mask = top_mask(p.width)
            );
        }
        let _ = writeln!(
            s,
            "void neo_{t}_get_{n}_words(void* p, uint32_t* w, size_t n) {{\n  const auto& port = m(p)->top->{n};\n  for (size_t i = 0; i < {w} && i < n; ++i) w[i] = port[i];\n}}\n"
        );
    }
}

/// The Rust wrapper for one top (module-level items, to be `include!`d in `crate::models`).
/// With `coverage` (the shim has [`cpp_coverage`]), dropping a model writes its coverage data
/// to `crate::coverage::next_path` first.
pub fn rust(iface: &ModuleInterface, coverage: bool, hdl: Option<&HdlFiles>) -> String {
    let t = &iface.name;
    let sn = struct_name(t);
    let has = |name: &str| iface.ports.iter().any(|p| p.name == name && p.dir == Dir::In && p.width == 1);
    let (has_clk, has_rst) = (has("clk_i"), has("rst_ni"));
    let mut s = String::new();

    // FFI declarations.
    let _ = writeln!(s, "mod ffi_{t} {{\n    use std::ffi::{{c_char, c_int, c_void}};\n    extern \"C\" {{");
    let _ = writeln!(s, "        pub fn neo_{t}_new(rand_reset: u32, seed: u32) -> *mut c_void;");
    let _ = writeln!(s, "        pub fn neo_{t}_free(p: *mut c_void);");
    let _ = writeln!(s, "        pub fn neo_{t}_eval(p: *mut c_void);");
    for p in &iface.ports {
        let n = &p.name;
        if p.width <= 64 {
            if p.dir == Dir::In {
                let _ = writeln!(s, "        pub fn neo_{t}_set_{n}(p: *mut c_void, v: u64);");
            }
            let _ = writeln!(s, "        pub fn neo_{t}_get_{n}(p: *mut c_void) -> u64;");
        } else {
            if p.dir == Dir::In {
                let _ = writeln!(
                    s,
                    "        pub fn neo_{t}_set_{n}_words(p: *mut c_void, w: *const u32, n: usize);"
                );
            }
            let _ =
                writeln!(s, "        pub fn neo_{t}_get_{n}_words(p: *mut c_void, w: *mut u32, n: usize);");
        }
    }
    let _ = writeln!(s, "        pub fn neo_{t}_trace_open(p: *mut c_void, path: *const c_char) -> c_int;");
    let _ = writeln!(s, "        pub fn neo_{t}_trace_dump(p: *mut c_void, time: u64);");
    let _ = writeln!(s, "        pub fn neo_{t}_trace_close(p: *mut c_void);");
    if coverage {
        let _ = writeln!(s, "        pub fn neo_{t}_coverage_write(p: *mut c_void, path: *const c_char);");
    }
    s.push_str("    }\n}\n\n");

    // The struct.
    let _ = writeln!(
        s,
        "/// The Verilated `{t}` (generated from its `ModuleInterface`; one `VerilatedContext` each)."
    );
    let _ = writeln!(s, "///\n/// Ports:");
    for p in &iface.ports {
        let _ = writeln!(s, "/// - `{}`: {:?}, {} bit(s)", p.name, p.dir, p.width);
    }
    let _ = writeln!(
        s,
        "pub struct {sn} {{\n    raw: std::ptr::NonNull<std::ffi::c_void>,\n    /// The model of `$NEO_HDL_DIR`'s Verilog, when it differs from the linked model's.\n    alt: Option<Box<crate::dynmodel::DynModel>>,\n    cycle: u64,\n    time: u64,\n    tracing: bool,\n    /// Coverage models: the toggle baseline's file (`crate::coverage::write_baseline`).\n    #[allow(dead_code)]\n    cov_base: Option<std::path::PathBuf>,\n}}\n"
    );
    let _ = writeln!(s, "// SAFETY: the model (and its VerilatedContext) is owned by this value alone; Verilator\n// supports one context per thread, and `&mut self` serialises every call.\nunsafe impl Send for {sn} {{}}\n");

    let _ = writeln!(s, "impl {sn} {{");
    let _ = writeln!(s, "    /// The module name.\n    pub const NAME: &'static str = \"{t}\";");
    s.push_str("    /// The ports, in declaration order.\n    pub const PORTS: &'static [crate::dut::PortSpec] = &[\n");
    for p in &iface.ports {
        let _ = writeln!(
            s,
            "        crate::dut::PortSpec {{ name: \"{}\", input: {}, width: {} }},",
            p.name,
            p.dir == Dir::In,
            p.width
        );
    }
    s.push_str("    ];\n\n");
    rust_hdl_consts(&mut s, hdl);
    let alt = if hdl.is_some() {
        "crate::hdl_dir::substitute(Self::NAME, Self::PORTS, Self::HDL_FILES, Self::HDL_HASH).map(Box::new)"
    } else {
        "None"
    };
    let _ = writeln!(
        s,
        "    /// A new model, clock low, reset released, all other inputs zero, every variable of the\n    /// design at its initial value (random by default, from the bench seed: `crate::xinit`;\n    /// call [`Self::reset`]).\n    /// With `$NEO_HDL_DIR` set, a model of its Verilog when that differs from this build's\n    /// (`crate::hdl_dir::substitute`).\n    ///\n    /// # Panics\n    /// When `$NEO_HDL_DIR` lacks one of the files or its model does not build.\n    #[allow(clippy::new_without_default)]\n    pub fn new() -> Self {{\n        // SAFETY: plain constructor; a null return is checked.\n        let raw = crate::xinit::construct(Self::NAME, |mode, seed| unsafe {{ ffi_{t}::neo_{t}_new(mode, seed) }});\n        let raw = std::ptr::NonNull::new(raw).expect(\"Verilated model allocation failed\");\n        let alt = {alt};\n        let mut m = {sn} {{ raw, alt, cycle: 0, time: 0, tracing: false, cov_base: None }};"
    );
    if has_clk {
        s.push_str("        m.set_clk_i(false);\n");
    }
    if has_rst {
        s.push_str("        m.set_rst_ni(true);\n");
    }
    s.push_str("        m.eval();\n");
    if coverage && !has_rst {
        // No reset: the baseline is the first evaluation's.
        s.push_str("        m.coverage_baseline();\n");
    }
    s.push_str("        m\n    }\n\n");
    if coverage {
        let _ = writeln!(
            s,
            "    /// Writes the toggle baseline once (`crate::coverage::write_baseline`).\n    fn coverage_baseline(&mut self) {{\n        if self.alt.is_none() && self.cov_base.is_none() {{\n            self.cov_base = Some(crate::coverage::write_baseline(Self::NAME, |path| {{\n                // SAFETY: `raw` is live; `path` outlives the call.\n                unsafe {{ ffi_{t}::neo_{t}_coverage_write(self.raw.as_ptr(), path.as_ptr()) }}\n            }}));\n        }}\n    }}\n"
        );
    }
    s.push_str("    /// True when this model runs `$NEO_HDL_DIR`'s Verilog (it differs from the linked model's).\n    pub fn is_substituted(&self) -> bool {\n        self.alt.is_some()\n    }\n\n");
    let _ = writeln!(
        s,
        "    /// Evaluates the model (settles combinational logic after input changes).\n    #[inline]\n    pub fn eval(&mut self) {{\n        if let Some(d) = self.alt.as_deref_mut() {{\n            return d.eval();\n        }}\n        // SAFETY: `raw` is a live model owned by `self`.\n        unsafe {{ ffi_{t}::neo_{t}_eval(self.raw.as_ptr()) }}\n    }}\n"
    );
    s.push_str("    #[inline]\n    fn dump(&mut self) {\n        if self.tracing {\n");
    let _ = writeln!(
        s,
        "            // SAFETY: `raw` is a live model owned by `self`.\n            unsafe {{ ffi_{t}::neo_{t}_trace_dump(self.raw.as_ptr(), self.time) }}"
    );
    s.push_str("        }\n    }\n\n");
    s.push_str("    /// One clock cycle: clock low, eval, dump; clock high (the rising edge), eval, dump.\n");
    s.push_str("    /// Simulation time advances by 10 units a cycle (5 per half period).\n");
    s.push_str("    #[inline]\n    pub fn tick(&mut self) {\n");
    s.push_str("        if let Some(d) = self.alt.as_deref_mut() {\n            d.tick();\n            self.time += 10;\n            self.cycle += 1;\n            return;\n        }\n");
    if has_clk {
        s.push_str("        self.set_clk_i(false);\n");
    }
    s.push_str("        self.eval();\n        self.dump();\n        self.time += 5;\n");
    if has_clk {
        s.push_str("        self.set_clk_i(true);\n");
    }
    s.push_str("        self.eval();\n        self.dump();\n        self.time += 5;\n        self.cycle += 1;\n    }\n\n");
    s.push_str(
        "    /// Asserts the active-low asynchronous reset for four cycles, releases it, and restarts\n",
    );
    s.push_str("    /// [`Self::cycle`] at zero. Set the inputs to their idle values first.\n");
    s.push_str("    pub fn reset(&mut self) {\n");
    // The run-time model's reset is the same sequence (four ticks).
    s.push_str("        if let Some(d) = self.alt.as_deref_mut() {\n            d.reset();\n            self.time += 40;\n            self.cycle = 0;\n            return;\n        }\n");
    if has_rst {
        s.push_str("        self.set_rst_ni(true);\n        self.eval();\n        self.set_rst_ni(false);\n        self.eval();\n        for _ in 0..4 {\n            self.tick();\n        }\n        self.set_rst_ni(true);\n");
    } else {
        s.push_str("        for _ in 0..4 {\n            self.tick();\n        }\n");
    }
    if has_clk {
        s.push_str("        self.set_clk_i(false);\n");
    }
    s.push_str("        self.eval();\n        self.cycle = 0;\n");
    if coverage {
        s.push_str("        self.coverage_baseline();\n");
    }
    s.push_str("    }\n\n");
    s.push_str("    /// Rising clock edges since the end of the last [`Self::reset`] (or since creation).\n");
    s.push_str("    #[inline]\n    pub fn cycle(&self) -> u64 {\n        self.cycle\n    }\n\n");
    s.push_str("    /// Simulation time (10 units a cycle), as written to the trace.\n");
    s.push_str("    #[inline]\n    pub fn time(&self) -> u64 {\n        self.time\n    }\n\n");
    let _ = writeln!(
        s,
        "    /// Starts writing a trace to `path` (replacing an open one): a VCD, or an FST when the crate\n    /// was built with `WAVES=fst` (`neo_tb::waves::MODEL_FORMAT`); every later half cycle is dumped.\n    pub fn trace_open(&mut self, path: &std::path::Path) -> std::io::Result<()> {{\n        if let Some(d) = self.alt.as_deref_mut() {{\n            return d.trace_open(path);\n        }}\n        let c = std::ffi::CString::new(path.as_os_str().to_string_lossy().as_bytes())\n            .map_err(|e| std::io::Error::new(std::io::ErrorKind::InvalidInput, e))?;\n        // SAFETY: `raw` is live; `c` outlives the call.\n        let ok = unsafe {{ ffi_{t}::neo_{t}_trace_open(self.raw.as_ptr(), c.as_ptr()) }};\n        if ok == 0 {{\n            return Err(std::io::Error::other(format!(\"cannot open trace {{}}\", path.display())));\n        }}\n        self.tracing = true;\n        Ok(())\n    }}\n"
    );
    let _ = writeln!(
        s,
        "    /// Flushes and closes the trace, if one is open.\n    pub fn trace_close(&mut self) {{\n        if let Some(d) = self.alt.as_deref_mut() {{\n            return d.trace_close();\n        }}\n        if self.tracing {{\n            // SAFETY: `raw` is a live model owned by `self`.\n            unsafe {{ ffi_{t}::neo_{t}_trace_close(self.raw.as_ptr()) }};\n            self.tracing = false;\n        }}\n    }}\n"
    );

    for (i, p) in iface.ports.iter().enumerate() {
        rust_port(&mut s, t, i, p);
    }
    s.push_str("}\n\n");

    // A substituted model writes its own coverage (crate::dynmodel); the linked one, unused, none.
    let cov = if coverage {
        format!(
            "        if self.alt.is_none() {{\n            crate::coverage::write_model(Self::NAME, self.cov_base.as_deref(), |path| {{\n                // SAFETY: `raw` is live; `path` outlives the call.\n                unsafe {{ ffi_{t}::neo_{t}_coverage_write(self.raw.as_ptr(), path.as_ptr()) }}\n            }});\n        }}\n"
        )
    } else {
        String::new()
    };
    let _ = writeln!(
        s,
        "impl Drop for {sn} {{\n    fn drop(&mut self) {{\n{cov}        // SAFETY: `raw` came from `neo_{t}_new` and is freed exactly once.\n        unsafe {{ ffi_{t}::neo_{t}_free(self.raw.as_ptr()) }}\n    }}\n}}\n"
    );

    // The generic Dut implementation.
    let _ = writeln!(s, "impl crate::dut::Dut for {sn} {{");
    s.push_str("    const NAME: &'static str = Self::NAME;\n    const PORTS: &'static [crate::dut::PortSpec] = Self::PORTS;\n\n");
    s.push_str("    fn set_words(&mut self, port: usize, words: &[u32]) {\n");
    let _ = writeln!(
        s,
        "        if let Some(d) = self.alt.as_deref_mut() {{\n            assert!(Self::PORTS.get(port).is_some_and(|p| p.input), \"{t}: port {{port}} is not an input\");\n            return d.set_words(port, words);\n        }}"
    );
    s.push_str("        let lo = |i: usize| words.get(i).copied().unwrap_or(0) as u64;\n        let _ = lo;\n        match port {\n");
    for (i, p) in iface.ports.iter().enumerate() {
        if p.dir != Dir::In {
            continue;
        }
        let n = &p.name;
        if p.width <= 64 {
            let _ = writeln!(
                s,
                "            {i} => unsafe {{ ffi_{t}::neo_{t}_set_{n}(self.raw.as_ptr(), lo(0) | (lo(1) << 32)) }},"
            );
        } else {
            let _ = writeln!(
                s,
                "            {i} => unsafe {{ ffi_{t}::neo_{t}_set_{n}_words(self.raw.as_ptr(), words.as_ptr(), words.len()) }},"
            );
        }
    }
    let _ =
        writeln!(s, "            _ => panic!(\"{t}: port {{port}} is not an input\"),\n        }}\n    }}\n");
    s.push_str("    fn get_words(&self, port: usize, out: &mut [u32]) {\n");
    let _ = writeln!(
        s,
        "        if let Some(d) = self.alt.as_deref() {{\n            assert!(port < Self::PORTS.len(), \"{t}: no port {{port}}\");\n            out.fill(0);\n            return d.get_words(port, out);\n        }}"
    );
    s.push_str("        match port {\n");
    for (i, p) in iface.ports.iter().enumerate() {
        let n = &p.name;
        if p.width <= 64 {
            let _ = writeln!(
                s,
                "            {i} => {{\n                let v = unsafe {{ ffi_{t}::neo_{t}_get_{n}(self.raw.as_ptr()) }};\n                for (k, w) in out.iter_mut().enumerate() {{\n                    *w = if k < 2 {{ (v >> (32 * k)) as u32 }} else {{ 0 }};\n                }}\n            }}"
            );
        } else {
            let _ = writeln!(
                s,
                "            {i} => {{\n                out.fill(0);\n                unsafe {{ ffi_{t}::neo_{t}_get_{n}_words(self.raw.as_ptr(), out.as_mut_ptr(), out.len()) }}\n            }}"
            );
        }
    }
    let _ = writeln!(s, "            _ => panic!(\"{t}: no port {{port}}\"),\n        }}\n    }}\n");
    s.push_str("    fn eval(&mut self) {\n        Self::eval(self)\n    }\n\n");
    s.push_str("    fn tick(&mut self) {\n        Self::tick(self)\n    }\n\n");
    s.push_str("    fn reset(&mut self) {\n        Self::reset(self)\n    }\n\n");
    s.push_str("    fn cycle(&self) -> u64 {\n        Self::cycle(self)\n    }\n\n");
    s.push_str("    fn trace_open(&mut self, path: &std::path::Path) -> std::io::Result<()> {\n        Self::trace_open(self, path)\n    }\n\n");
    s.push_str("    fn trace_close(&mut self) {\n        Self::trace_close(self)\n    }\n}\n\n");
    s
}

/// The wrapper's constants naming the Verilog its model is built from (for generated tops).
fn rust_hdl_consts(s: &mut String, hdl: Option<&HdlFiles>) {
    if let Some(h) = hdl {
        let _ = writeln!(
            s,
            "    /// The Verilog files this model is built from (the top's and its submodules').\n    pub const HDL_FILES: &'static [&'static str] = &{:?};\n    /// Their content hash, headers left out (`build/hdl_hash.rs`).\n    pub const HDL_HASH: &'static str = \"{}\";\n",
            h.names, h.hash
        );
    }
}

/// The typed accessors of port `p` (index `i`): the linked model's shim, or the run-time
/// model's port `i` when the wrapper has one.
fn rust_port(s: &mut String, t: &str, i: usize, p: &Port) {
    let n = &p.name;
    let w = words(p.width);
    if p.dir == Dir::In {
        let doc =
            format!("    /// Drives input `{n}` ({} bit(s)); bits above the width are ignored.", p.width);
        match p.width {
            1 => {
                let _ = writeln!(
                    s,
                    "{doc}\n    #[inline]\n    pub fn set_{n}(&mut self, v: bool) {{\n        if let Some(d) = self.alt.as_deref_mut() {{\n            return d.set_u64({i}, v as u64);\n        }}\n        // SAFETY: `raw` is a live model owned by `self`.\n        unsafe {{ ffi_{t}::neo_{t}_set_{n}(self.raw.as_ptr(), v as u64) }}\n    }}\n"
                );
            }
            2..=64 => {
                let _ = writeln!(
                    s,
                    "{doc}\n    #[inline]\n    pub fn set_{n}(&mut self, v: u64) {{\n        if let Some(d) = self.alt.as_deref_mut() {{\n            return d.set_u64({i}, v);\n        }}\n        // SAFETY: `raw` is a live model owned by `self`.\n        unsafe {{ ffi_{t}::neo_{t}_set_{n}(self.raw.as_ptr(), v) }}\n    }}\n"
                );
            }
            _ => {
                let _ = writeln!(
                    s,
                    "{doc}\n    /// Words are little-endian: `v[0]` holds bits 31..0.\n    #[inline]\n    pub fn set_{n}(&mut self, v: &[u32; {w}]) {{\n        if let Some(d) = self.alt.as_deref_mut() {{\n            return d.set_words({i}, v);\n        }}\n        // SAFETY: `raw` is live and `v` holds exactly the port's {w} words.\n        unsafe {{ ffi_{t}::neo_{t}_set_{n}_words(self.raw.as_ptr(), v.as_ptr(), {w}) }}\n    }}\n"
                );
            }
        }
    }
    let doc = format!("    /// Reads port `{n}` ({:?}, {} bit(s)).", p.dir, p.width);
    match p.width {
        1 => {
            let _ = writeln!(
                s,
                "{doc}\n    #[inline]\n    pub fn {n}(&self) -> bool {{\n        if let Some(d) = self.alt.as_deref() {{\n            return d.get_u64({i}) != 0;\n        }}\n        // SAFETY: `raw` is a live model owned by `self`.\n        unsafe {{ ffi_{t}::neo_{t}_get_{n}(self.raw.as_ptr()) != 0 }}\n    }}\n"
            );
        }
        2..=64 => {
            let _ = writeln!(
                s,
                "{doc}\n    #[inline]\n    pub fn {n}(&self) -> u64 {{\n        if let Some(d) = self.alt.as_deref() {{\n            return d.get_u64({i});\n        }}\n        // SAFETY: `raw` is a live model owned by `self`.\n        unsafe {{ ffi_{t}::neo_{t}_get_{n}(self.raw.as_ptr()) }}\n    }}\n"
            );
        }
        _ => {
            let _ = writeln!(
                s,
                "{doc}\n    /// Words are little-endian: element 0 holds bits 31..0.\n    #[inline]\n    pub fn {n}(&self) -> [u32; {w}] {{\n        let mut v = [0u32; {w}];\n        if let Some(d) = self.alt.as_deref() {{\n            d.get_words({i}, &mut v);\n            return v;\n        }}\n        // SAFETY: `raw` is live and `v` has room for the port's {w} words.\n        unsafe {{ ffi_{t}::neo_{t}_get_{n}_words(self.raw.as_ptr(), v.as_mut_ptr(), {w}) }};\n        v\n    }}\n"
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_and_masks() {
        assert_eq!(struct_name("neo_sort_core"), "NeoSortCore");
        assert_eq!(top_mask(1), 1);
        assert_eq!(top_mask(64), u64::MAX);
        assert_eq!(top_mask(100), 0xF);
        assert_eq!(top_mask(96), 0xFFFF_FFFF);
    }
}
