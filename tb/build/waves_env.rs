//! The `WAVES` environment variable, read by `build.rs` (which trace writer the statically
//! linked models get) and by `neo_tb::waves` (what a test writes). Depends on nothing but std.

/// The values `WAVES` accepts, for error messages.
pub const WAVES_VALUES: &str = "unset, empty or 0 (no waves), 1 or vcd (VCD), fst (FST)";

/// What a `WAVES` value asks for: `Ok(None)` for no waves (empty, `0`), `Ok(Some("vcd"))` for a
/// VCD (`1`, `vcd`), `Ok(Some("fst"))` for an FST (`fst`); letters in any case. Anything else is
/// an error naming `WAVES` and the accepted values.
pub fn parse_waves(value: &str) -> Result<Option<&'static str>, String> {
    match value.trim() {
        "" | "0" => Ok(None),
        "1" => Ok(Some("vcd")),
        v if v.eq_ignore_ascii_case("vcd") => Ok(Some("vcd")),
        v if v.eq_ignore_ascii_case("fst") => Ok(Some("fst")),
        v => Err(format!("WAVES={v} is not a waveform choice; WAVES accepts {WAVES_VALUES}")),
    }
}
