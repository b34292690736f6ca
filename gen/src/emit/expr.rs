//! Expression helpers: sized literals, slices and bit-width arithmetic.

/// A sized decimal literal, e.g. `lit(16, 3)` = `16'd3`; one-bit literals print as `1'b0`/`1'b1`.
///
/// # Panics
/// When `value` does not fit in `width` bits.
pub fn lit(width: u32, value: u64) -> String {
    assert!(width >= 1, "zero-width literal");
    assert!(width >= 64 || value >> width == 0, "{value} does not fit in {width} bits");
    if width == 1 {
        format!("1'b{value}")
    } else {
        format!("{width}'d{value}")
    }
}

/// A sized hexadecimal literal, e.g. `hex(48, 0x7fff)` = `48'h7fff`.
///
/// # Panics
/// When `value` does not fit in `width` bits.
pub fn hex(width: u32, value: u64) -> String {
    assert!(width >= 1, "zero-width literal");
    assert!(width >= 64 || value >> width == 0, "{value:#x} does not fit in {width} bits");
    format!("{width}'h{value:x}")
}

/// The constant slice `name[hi:lo]` (`name[lo]` when `hi == lo`).
pub fn slice(name: &str, hi: u32, lo: u32) -> String {
    assert!(hi >= lo, "slice {name}[{hi}:{lo}] is reversed");
    if hi == lo {
        format!("{name}[{lo}]")
    } else {
        format!("{name}[{hi}:{lo}]")
    }
}

/// Lane `i` of a vector of `width`-bit lanes packed LSB first: `name[(i+1)*width-1 : i*width]`.
pub fn lane(name: &str, i: u32, width: u32) -> String {
    slice(name, (i + 1) * width - 1, i * width)
}

/// `x` (`from` bits) zero-extended to `to` bits: `{N'd0, x}` (`x` itself when the widths match).
///
/// # Panics
/// When `to < from` (use [`resize`] to truncate).
pub fn zext(x: &str, from: u32, to: u32) -> String {
    assert!(to >= from, "zext {x}: {from} > {to} bits");
    if to == from {
        x.to_string()
    } else {
        format!("{{{}, {x}}}", lit(to - from, 0))
    }
}

/// `x` (`from` bits, a net name) sign-extended to `to` bits: `{{N{x[from-1]}}, x}` (`x` itself
/// when the widths match).
///
/// # Panics
/// When `to < from`.
pub fn sext(x: &str, from: u32, to: u32) -> String {
    assert!(to >= from, "sext {x}: {from} > {to} bits");
    if to == from {
        x.to_string()
    } else {
        format!("{{{{{}{{{}}}}}, {x}}}", to - from, slice(x, from - 1, from - 1))
    }
}

/// `x` (`from` bits, a net name) resized to `to` bits: zero-extended ([`zext`]) or truncated to
/// its low bits.
pub fn resize(x: &str, from: u32, to: u32) -> String {
    if from > to {
        format!("{x}[{}:0]", to - 1)
    } else {
        zext(x, from, to)
    }
}

/// Bits needed to hold the values `0..=max` (at least 1).
pub fn bits_for(max: u64) -> u32 {
    (64 - max.leading_zeros()).max(1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn literals_are_sized() {
        assert_eq!(lit(16, 3), "16'd3");
        assert_eq!(lit(1, 0), "1'b0");
        assert_eq!(lit(1, 1), "1'b1");
        assert_eq!(hex(48, 0x7fff_ffff_ffff), "48'h7fffffffffff");
    }

    #[test]
    #[should_panic(expected = "does not fit")]
    fn oversized_literal_panics() {
        let _ = lit(4, 16);
    }

    #[test]
    fn slices_and_lanes() {
        assert_eq!(slice("x", 7, 0), "x[7:0]");
        assert_eq!(slice("x", 3, 3), "x[3]");
        assert_eq!(lane("v", 0, 48), "v[47:0]");
        assert_eq!(lane("v", 2, 48), "v[143:96]");
    }

    #[test]
    fn extension_and_resize() {
        assert_eq!(zext("x", 4, 4), "x");
        assert_eq!(zext("x", 4, 6), "{2'd0, x}");
        assert_eq!(sext("x", 4, 6), "{{2{x[3]}}, x}");
        assert_eq!(sext("x", 4, 4), "x");
        assert_eq!(resize("x", 8, 3), "x[2:0]");
        assert_eq!(resize("x", 3, 8), "{5'd0, x}");
    }

    #[test]
    fn bit_counts() {
        assert_eq!(bits_for(0), 1);
        assert_eq!(bits_for(1), 1);
        assert_eq!(bits_for(255), 8);
        assert_eq!(bits_for(256), 9);
    }
}
