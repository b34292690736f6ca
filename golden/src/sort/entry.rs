//! The sort entry `{valid, key, id}`, its bit layout, and THE ORDER every sorting unit uses.
//!
//! # The order
//! Entries are ordered by `(key, id)`: compare the keys as unsigned integers, and on equal keys
//! compare the ids as unsigned integers. Ids are unique within a tile, so the order is strict on
//! real entries. **The valid bit is payload**: it never takes part in a comparison, it only rides
//! along with its entry. This is what lets the BSU be a pure `(key, id)` comparator network and
//! leaves invalid-entry removal to the MSU+ ([`crate::sort::msu`]).
//!
//! # Bit layout (RTL ports and DRAM)
//! An entry packs into a `1 + key_bits + id_bits` bit vector, MSB to LSB `{valid, key, id}`:
//!
//! ```text
//!  bit  key_bits+id_bits | key_bits+id_bits-1 .. id_bits | id_bits-1 .. 0
//!       valid            | key                           | id
//! ```
//!
//! so the low `key_bits + id_bits` bits are exactly the comparison value: a comparator is one
//! unsigned compare of those bits. The valid bit has its own bit (it is not carved out of the key
//! or id field of a format). In DRAM an entry takes [`SortFormat::bytes_per_entry`] =
//! `ceil((1 + key_bits + id_bits) / 8)` bytes, the packed word in little-endian byte order with
//! the unused high bits zero.
//!
//! # Padding
//! Partial 16-entry BSU vectors are filled with [`SortFormat::padding`] = `(key = max, id = max,
//! valid = 0)`. The all-ones id is reserved (never a real id; [`SortFormat::fitted`] sizes the id
//! field so), hence padding sorts strictly after every real entry, and the sorters drop it again.

use super::error::SortParamError;

/// One entry of a Gaussian table: a depth key, a Gaussian id, and the valid bit (payload).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct SortEntry {
    /// Depth key (see [`crate::sort::depth_key`]); smaller is nearer.
    pub key: u32,
    /// Gaussian id, unique within a tile; the all-ones value of the format is reserved.
    pub id: u32,
    /// Valid bit: `false` marks an outgoing Gaussian that the next MSU+ merge removes.
    pub valid: bool,
}

impl SortEntry {
    /// A valid entry.
    pub const fn new(key: u32, id: u32) -> Self {
        SortEntry { key, id, valid: true }
    }

    /// The comparison value `key << 32 | id`: THE ORDER is the unsigned order of this value.
    /// The valid bit is not part of it.
    #[inline(always)]
    pub const fn order_key(&self) -> u64 {
        ((self.key as u64) << 32) | self.id as u64
    }

    /// True when `self` sorts strictly before `other` by `(key, id)`.
    #[inline(always)]
    pub const fn precedes(&self, other: &SortEntry) -> bool {
        self.order_key() < other.order_key()
    }

    /// The same entry with the valid bit set to `valid`.
    pub const fn with_valid(self, valid: bool) -> Self {
        SortEntry { valid, ..self }
    }
}

/// True when `entries` is non-decreasing in THE ORDER `(key, id)`.
pub fn is_sorted_by_order(entries: &[SortEntry]) -> bool {
    entries.windows(2).all(|w| w[0].order_key() <= w[1].order_key())
}

/// Field widths of an entry. Construct with [`SortFormat::new`], [`SortFormat::fitted`] or
/// [`SortFormat::ARTIFACT`]; the fields are private so every instance is valid:
/// `1 <= key_bits <= 32`, `1 <= id_bits <= 32`, `1 + key_bits + id_bits <= 64`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct SortFormat {
    key_bits: u8,
    id_bits: u8,
}

impl SortFormat {
    /// The Neo artifact's entry: an FP16 depth key and a 32-bit id word, 6 bytes an entry. The
    /// valid bit is the top bit of that 32-bit id word, so the id proper has 31 bits (2^31 - 1
    /// real ids, far more than any scene): `1 + 16 + 31 = 48` bits = 6 bytes.
    pub const ARTIFACT: SortFormat = SortFormat { key_bits: 16, id_bits: 31 };

    /// A format with the given widths, checked.
    pub fn new(key_bits: u8, id_bits: u8) -> Result<Self, SortParamError> {
        if !(1..=32).contains(&key_bits) {
            return Err(SortParamError::KeyBits(key_bits));
        }
        if !(1..=32).contains(&id_bits) {
            return Err(SortParamError::IdBits(id_bits));
        }
        if 1 + key_bits as u32 + id_bits as u32 > 64 {
            return Err(SortParamError::TooWide { key_bits, id_bits });
        }
        Ok(SortFormat { key_bits, id_bits })
    }

    /// The narrowest id field for a scene of `gaussian_count` Gaussians (ids `0..count`) with the
    /// all-ones value reserved for padding: the smallest `b >= 1` with `2^b - 1 >= count`,
    /// i.e. the bit length of `count`.
    pub fn fitted(gaussian_count: u64, key_bits: u8) -> Result<Self, SortParamError> {
        let bits = (64 - gaussian_count.leading_zeros()).max(1);
        if bits > 32 {
            return Err(SortParamError::TooManyGaussians(gaussian_count));
        }
        SortFormat::new(key_bits, bits as u8)
    }

    /// Width of the key field in bits.
    pub const fn key_bits(&self) -> u8 {
        self.key_bits
    }

    /// Width of the id field in bits.
    pub const fn id_bits(&self) -> u8 {
        self.id_bits
    }

    /// Width of the packed `{valid, key, id}` vector: `1 + key_bits + id_bits`.
    pub const fn entry_bits(&self) -> u32 {
        1 + self.key_bits as u32 + self.id_bits as u32
    }

    /// Bytes an entry takes in DRAM: the packed width rounded up to whole bytes.
    pub const fn bytes_per_entry(&self) -> usize {
        self.entry_bits().div_ceil(8) as usize
    }

    /// Largest key value (all ones); padding uses it.
    pub const fn key_max(&self) -> u32 {
        low_mask(self.key_bits as u32) as u32
    }

    /// The reserved id (all ones): only padding carries it, never a real Gaussian.
    pub const fn id_max(&self) -> u32 {
        low_mask(self.id_bits as u32) as u32
    }

    /// Number of real ids available: `0 ..= id_max() - 1`.
    pub const fn id_capacity(&self) -> u64 {
        self.id_max() as u64
    }

    /// The padding entry `(key_max, id_max, valid = 0)`; it sorts after every real entry.
    pub const fn padding(&self) -> SortEntry {
        SortEntry { key: self.key_max(), id: self.id_max(), valid: false }
    }

    /// True when the entry's fields fit this format and its id is not the reserved one.
    pub const fn holds(&self, e: &SortEntry) -> bool {
        e.key <= self.key_max() && e.id < self.id_max()
    }

    /// Packs `{valid, key, id}` MSB to LSB, or `None` when a field does not fit its width.
    /// (The reserved id is accepted here so that padding can be packed.)
    pub const fn try_pack(&self, e: &SortEntry) -> Option<u64> {
        if e.key > self.key_max() || e.id > self.id_max() {
            return None;
        }
        let id_bits = self.id_bits as u32;
        let valid_shift = id_bits + self.key_bits as u32;
        Some(((e.valid as u64) << valid_shift) | ((e.key as u64) << id_bits) | e.id as u64)
    }

    /// Packs `{valid, key, id}` MSB to LSB.
    ///
    /// # Panics
    /// When the key or id does not fit its field (a bug upstream: keys come from a codec of the
    /// same width and ids from a fitted format).
    pub fn pack(&self, e: &SortEntry) -> u64 {
        match self.try_pack(e) {
            Some(w) => w,
            None => panic!("entry {e:?} does not fit format {self:?}"),
        }
    }

    /// Unpacks a `{valid, key, id}` word. Total: bits above [`SortFormat::entry_bits`] are ignored.
    pub const fn unpack(&self, word: u64) -> SortEntry {
        let id_bits = self.id_bits as u32;
        let key_bits = self.key_bits as u32;
        SortEntry {
            id: (word & low_mask(id_bits)) as u32,
            key: ((word >> id_bits) & low_mask(key_bits)) as u32,
            valid: (word >> (id_bits + key_bits)) & 1 == 1,
        }
    }

    /// Appends the DRAM image of `e` ([`SortFormat::bytes_per_entry`] little-endian bytes).
    ///
    /// # Panics
    /// As [`SortFormat::pack`].
    pub fn write_bytes(&self, e: &SortEntry, out: &mut Vec<u8>) {
        let word = self.pack(e);
        out.extend_from_slice(&word.to_le_bytes()[..self.bytes_per_entry()]);
    }

    /// Reads one entry from the first [`SortFormat::bytes_per_entry`] bytes of `bytes`; `None`
    /// when there are fewer. Bits above the packed width are ignored. Never panics.
    pub fn read_bytes(&self, bytes: &[u8]) -> Option<SortEntry> {
        let n = self.bytes_per_entry();
        let src = bytes.get(..n)?;
        let mut word = [0u8; 8];
        word[..n].copy_from_slice(src);
        Some(self.unpack(u64::from_le_bytes(word)))
    }
}

/// `2^bits - 1` for `bits` in `0..=64`.
const fn low_mask(bits: u32) -> u64 {
    if bits >= 64 {
        u64::MAX
    } else {
        (1u64 << bits) - 1
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn artifact_is_six_bytes_with_fp16_key() {
        let f = SortFormat::ARTIFACT;
        assert_eq!(f.key_bits(), 16);
        assert_eq!(f.entry_bits(), 48);
        assert_eq!(f.bytes_per_entry(), 6);
        assert_eq!(f.key_max(), 0xFFFF);
        assert_eq!(f.id_max(), 0x7FFF_FFFF);
    }

    #[test]
    fn new_rejects_bad_widths() {
        assert_eq!(SortFormat::new(0, 8), Err(SortParamError::KeyBits(0)));
        assert_eq!(SortFormat::new(8, 33), Err(SortParamError::IdBits(33)));
        assert_eq!(SortFormat::new(32, 32), Err(SortParamError::TooWide { key_bits: 32, id_bits: 32 }));
        assert!(SortFormat::new(32, 31).is_ok());
    }

    #[test]
    fn fitted_reserves_the_all_ones_id() {
        // count -> bits: 2^b - 1 >= count, smallest b >= 1.
        for (count, bits) in
            [(0u64, 1u8), (1, 1), (2, 2), (3, 2), (4, 3), (152_746, 18), (262_143, 18), (262_144, 19)]
        {
            let f = SortFormat::fitted(count, 16).unwrap();
            assert_eq!(f.id_bits(), bits, "count {count}");
            assert!(f.id_capacity() >= count, "count {count}");
            if bits > 1 {
                // One bit fewer could not name every id plus the reserved value.
                assert!((1u64 << (bits - 1)) - 1 < count, "count {count} not minimal");
            }
        }
        assert_eq!(SortFormat::fitted(u32::MAX as u64, 16).unwrap().id_bits(), 32);
        assert_eq!(SortFormat::fitted(1 << 32, 16), Err(SortParamError::TooManyGaussians(1 << 32)));
    }

    #[test]
    fn layout_is_valid_key_id_msb_to_lsb() {
        let f = SortFormat::new(4, 8).unwrap();
        let w = f.pack(&SortEntry { key: 0xA, id: 0x5C, valid: true });
        assert_eq!(w, 0b1_1010_0101_1100);
        let w = f.pack(&SortEntry { key: 0xA, id: 0x5C, valid: false });
        assert_eq!(w, 0b0_1010_0101_1100);
        // The comparison value is the low key_bits + id_bits bits.
        let a = SortEntry { key: 3, id: 200, valid: true };
        let b = SortEntry { key: 4, id: 1, valid: false };
        assert!(a.precedes(&b));
        assert!((f.pack(&a) & 0xFFF) < (f.pack(&b) & 0xFFF));
    }

    #[test]
    fn pack_rejects_oversized_fields() {
        let f = SortFormat::new(4, 8).unwrap();
        assert_eq!(f.try_pack(&SortEntry::new(16, 0)), None);
        assert_eq!(f.try_pack(&SortEntry::new(0, 256)), None);
        assert!(f.try_pack(&f.padding()).is_some());
    }

    #[test]
    fn valid_bit_does_not_affect_order() {
        let a = SortEntry { key: 7, id: 3, valid: false };
        assert_eq!(a.order_key(), a.with_valid(true).order_key());
        assert!(!a.precedes(&a.with_valid(true)) && !a.with_valid(true).precedes(&a));
    }

    #[test]
    fn padding_sorts_after_every_real_entry() {
        for f in [SortFormat::ARTIFACT, SortFormat::new(3, 2).unwrap(), SortFormat::new(32, 31).unwrap()] {
            let pad = f.padding();
            assert!(!pad.valid);
            let last_real = SortEntry::new(f.key_max(), f.id_max() - 1);
            assert!(f.holds(&last_real) && !f.holds(&pad));
            assert!(last_real.precedes(&pad));
        }
    }

    /// The widest format fills the 64-bit word (found by the round-trip proptest: `w >> 64`).
    #[test]
    fn a_64_bit_entry_round_trips() {
        let f = SortFormat::new(32, 31).unwrap();
        assert_eq!(f.entry_bits(), 64);
        for e in [
            SortEntry { key: 0, id: 1, valid: false },
            SortEntry { key: f.key_max(), id: f.id_max(), valid: true },
        ] {
            assert_eq!(f.unpack(f.pack(&e)), e);
            let mut bytes = Vec::new();
            f.write_bytes(&e, &mut bytes);
            assert_eq!(bytes.len(), 8);
            assert_eq!(f.read_bytes(&bytes), Some(e));
        }
    }

    #[test]
    fn read_bytes_short_input_is_none() {
        let f = SortFormat::ARTIFACT;
        assert_eq!(f.read_bytes(&[0u8; 5]), None);
        assert!(f.read_bytes(&[0u8; 6]).is_some());
    }

    proptest! {
        #[test]
        fn pack_unpack_round_trip(key_bits in 1u8..=32, id_bits in 1u8..=31, key in any::<u32>(), id in any::<u32>(), valid in any::<bool>()) {
            prop_assume!(key_bits as u32 + id_bits as u32 <= 63);
            let f = SortFormat::new(key_bits, id_bits).unwrap();
            let e = SortEntry { key: key & f.key_max(), id: id & f.id_max(), valid };
            let w = f.pack(&e);
            // Nothing above the entry's width (a 64-bit entry fills the word).
            prop_assert!(w.checked_shr(f.entry_bits()).unwrap_or(0) == 0);
            prop_assert_eq!(f.unpack(w), e);
            let mut bytes = Vec::new();
            f.write_bytes(&e, &mut bytes);
            prop_assert_eq!(bytes.len(), f.bytes_per_entry());
            prop_assert_eq!(f.read_bytes(&bytes), Some(e));
        }

        #[test]
        fn unpack_is_total_and_canonical(word in any::<u64>(), bytes in proptest::collection::vec(any::<u8>(), 0..10)) {
            let f = SortFormat::ARTIFACT;
            let e = f.unpack(word);
            prop_assert_eq!(f.pack(&e), word & ((1u64 << 48) - 1));
            if let Some(e) = f.read_bytes(&bytes) {
                prop_assert!(f.try_pack(&e).is_some());
            }
        }

        #[test]
        fn packed_compare_equals_order(a in any::<(u16, u32, bool)>(), b in any::<(u16, u32, bool)>()) {
            let f = SortFormat::ARTIFACT;
            let ea = SortEntry { key: a.0 as u32, id: a.1 & f.id_max(), valid: a.2 };
            let eb = SortEntry { key: b.0 as u32, id: b.1 & f.id_max(), valid: b.2 };
            let mask = (1u64 << 47) - 1;
            prop_assert_eq!(ea.precedes(&eb), (f.pack(&ea) & mask) < (f.pack(&eb) & mask));
        }
    }
}
