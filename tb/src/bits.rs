//! Bit fields inside little-endian 32-bit word vectors (Verilator's `VlWide` layout).

/// Writes the low `width` bits of `value` at bit `lo` of `words` (`width <= 64`).
///
/// # Panics
/// When the field does not fit in `words`.
#[inline]
pub fn set_bits(words: &mut [u32], lo: usize, width: usize, value: u64) {
    debug_assert!(width <= 64);
    assert!(lo + width <= words.len() * 32, "field {lo}+{width} beyond {} words", words.len());
    let mut done = 0;
    while done < width {
        let bit = lo + done;
        let (w, off) = (bit / 32, bit % 32);
        let n = (32 - off).min(width - done);
        let mask = if n == 32 { u32::MAX } else { ((1u32 << n) - 1) << off };
        let part = ((value >> done) as u32) << off;
        words[w] = (words[w] & !mask) | (part & mask);
        done += n;
    }
}

/// Reads `width` bits at bit `lo` of `words` (`width <= 64`).
///
/// # Panics
/// When the field does not fit in `words`.
#[inline]
pub fn get_bits(words: &[u32], lo: usize, width: usize) -> u64 {
    debug_assert!(width <= 64);
    assert!(lo + width <= words.len() * 32, "field {lo}+{width} beyond {} words", words.len());
    let mut v = 0u64;
    let mut done = 0;
    while done < width {
        let bit = lo + done;
        let (w, off) = (bit / 32, bit % 32);
        let n = (32 - off).min(width - done);
        let part = (words[w] >> off) as u64 & ((1u64 << n) - 1);
        v |= part << done;
        done += n;
    }
    v
}

/// The low `bits` bits set (all 64 for `bits >= 64`).
pub fn mask(bits: u32) -> u64 {
    if bits >= 64 {
        u64::MAX
    } else {
        (1u64 << bits) - 1
    }
}

/// Formats words as one hex number, most significant word first.
pub fn hex(words: &[u32]) -> String {
    let mut s = String::from("0x");
    for w in words.iter().rev() {
        s.push_str(&format!("{w:08x}"));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fields_round_trip_across_word_boundaries() {
        let mut w = [0u32; 4];
        set_bits(&mut w, 30, 48, 0xABCD_1234_5678);
        set_bits(&mut w, 0, 30, 0x3FFF_FFFF);
        set_bits(&mut w, 78, 50, 0x3_0000_0000_0001);
        assert_eq!(get_bits(&w, 30, 48), 0xABCD_1234_5678);
        assert_eq!(get_bits(&w, 0, 30), 0x3FFF_FFFF);
        assert_eq!(get_bits(&w, 78, 50), 0x3_0000_0000_0001);
        // Overwrite in the middle leaves the neighbours alone.
        set_bits(&mut w, 30, 48, 0);
        assert_eq!(get_bits(&w, 0, 30), 0x3FFF_FFFF);
        assert_eq!(get_bits(&w, 78, 50), 0x3_0000_0000_0001);
        assert_eq!(hex(&[1, 0xA]), "0x0000000a00000001");
    }
}
