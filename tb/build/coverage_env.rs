//! The `NEO_COVERAGE` environment variable, read by `build.rs` (whether the statically linked
//! models are built with Verilator coverage) and by `neo_tb::coverage` (whether the models built
//! at run time are, and where the data goes). Depends on nothing but std.

/// The values `NEO_COVERAGE` accepts, for error messages.
pub const COVERAGE_VALUES: &str = "unset, empty or 0 (no coverage), 1 (line, toggle and user coverage)";

/// Whether a `NEO_COVERAGE` value asks for coverage models: `Ok(false)` for unset / empty /
/// `0`, `Ok(true)` for `1`; anything else is an error naming the variable and its values.
pub fn parse_coverage(value: &str) -> Result<bool, String> {
    match value.trim() {
        "" | "0" => Ok(false),
        "1" => Ok(true),
        v => {
            Err(format!("NEO_COVERAGE={v} is not a coverage choice; NEO_COVERAGE accepts {COVERAGE_VALUES}"))
        }
    }
}
