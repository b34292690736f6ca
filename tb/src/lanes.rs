//! Packing sort entries into port words: lane `i` of a vector port is bits
//! `[i*W +: W]`, `W = 1 + key_bits + id_bits`, each lane the golden `{valid, key, id}` layout.

use neo_golden::sort::{SortEntry, SortFormat};

/// Packs `entries` into lanes `0..entries.len()` of `words`; bits above the last lane are
/// zeroed (one streaming pass, no per-field read-modify-write).
///
/// # Panics
/// When `words` is too short.
#[inline]
pub fn pack_lanes(fmt: &SortFormat, entries: &[SortEntry], words: &mut [u32]) {
    let w = fmt.entry_bits();
    assert!(
        entries.len() * w as usize <= words.len() * 32,
        "{} lanes do not fit {} words",
        entries.len(),
        words.len()
    );
    let (mut acc, mut nbits, mut k) = (0u128, 0u32, 0usize);
    for e in entries {
        acc |= (fmt.pack(e) as u128) << nbits;
        nbits += w;
        while nbits >= 32 {
            words[k] = acc as u32;
            k += 1;
            acc >>= 32;
            nbits -= 32;
        }
    }
    if nbits > 0 {
        words[k] = acc as u32;
        k += 1;
    }
    words[k..].fill(0);
}

/// Unpacks `out.len()` lanes of `words`.
///
/// # Panics
/// When `words` is too short.
#[inline]
pub fn unpack_lanes(fmt: &SortFormat, words: &[u32], out: &mut [SortEntry]) {
    let w = fmt.entry_bits();
    assert!(
        out.len() * w as usize <= words.len() * 32,
        "{} lanes do not fit {} words",
        out.len(),
        words.len()
    );
    let mask = (1u128 << w) - 1;
    let (mut acc, mut nbits, mut k) = (0u128, 0u32, 0usize);
    for e in out.iter_mut() {
        while nbits < w {
            acc |= (words[k] as u128) << nbits;
            k += 1;
            nbits += 32;
        }
        *e = fmt.unpack((acc & mask) as u64);
        acc >>= w;
        nbits -= w;
    }
}

/// `n` entries packed into a fresh word vector of `n * W` bits.
pub fn packed(fmt: &SortFormat, entries: &[SortEntry]) -> Vec<u32> {
    let mut words = vec![0u32; (entries.len() * fmt.entry_bits() as usize).div_ceil(32)];
    pack_lanes(fmt, entries, &mut words);
    words
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lanes_round_trip() {
        let fmt = SortFormat::ARTIFACT;
        let v: Vec<SortEntry> = (0..16u32)
            .map(|i| SortEntry { key: i * 4000, id: (i * 0x0777_7777) & fmt.id_max(), valid: i % 3 != 0 })
            .collect();
        let words = packed(&fmt, &v);
        assert_eq!(words.len(), 24);
        let mut back = vec![SortEntry::default(); 16];
        unpack_lanes(&fmt, &words, &mut back);
        assert_eq!(back, v);
        // Lane 1 starts at bit 48: its id's low bits are word 1's upper half.
        assert_eq!(words[1] >> 16, v[1].id & 0xFFFF);
        // The same layout as field-by-field packing, for an odd width too.
        for fmt in [fmt, SortFormat::new(5, 6).unwrap()] {
            let w = fmt.entry_bits() as usize;
            let v: Vec<SortEntry> = (0..7u32)
                .map(|i| SortEntry { key: i & fmt.key_max(), id: (i * 3) & fmt.id_max(), valid: i % 2 == 0 })
                .collect();
            let mut slow = vec![0u32; (7 * w).div_ceil(32)];
            for (i, e) in v.iter().enumerate() {
                crate::bits::set_bits(&mut slow, i * w, w, fmt.pack(e));
            }
            assert_eq!(packed(&fmt, &v), slow);
            for (i, e) in v.iter().enumerate() {
                assert_eq!(fmt.unpack(crate::bits::get_bits(&slow, i * w, w)), *e);
            }
        }
    }
}
