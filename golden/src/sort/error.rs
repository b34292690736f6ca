//! Errors for sorting parameters (formats, codecs, chunk sizes) that cannot be honoured.

/// A sorting parameter that the model (and therefore the hardware) cannot use.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SortParamError {
    /// The key field must be 1..=32 bits wide.
    #[error("key width {0} bits is outside 1..=32")]
    KeyBits(u8),
    /// The id field must be 1..=32 bits wide.
    #[error("id width {0} bits is outside 1..=32")]
    IdBits(u8),
    /// `{valid, key, id}` must fit a 64-bit word: `1 + key_bits + id_bits <= 64`.
    #[error("entry of 1 + {key_bits} + {id_bits} bits does not fit 64 bits")]
    TooWide {
        /// Requested key width.
        key_bits: u8,
        /// Requested id width.
        id_bits: u8,
    },
    /// More Gaussians than a 32-bit id (with one reserved value) can name.
    #[error("{0} Gaussians need more than 32 id bits (one id value is reserved for padding)")]
    TooManyGaussians(u64),
    /// The chunk size must be the BSU width times a power of two (so in-chunk merges pair up).
    #[error("chunk size {chunk} is not the BSU width {bsu} times a power of two")]
    Chunk {
        /// Requested chunk size.
        chunk: usize,
        /// BSU (network) width.
        bsu: usize,
    },
    /// The BSU network must have at least two inputs.
    #[error("BSU network width {0} is below 2")]
    BsuWidth(usize),
    /// A depth range for a fitted key must satisfy `0 < near < far`, both finite.
    #[error("depth range [{near}, {far}] is not 0 < near < far with finite ends")]
    DepthRange {
        /// Near end.
        near: f32,
        /// Far end.
        far: f32,
    },
}
