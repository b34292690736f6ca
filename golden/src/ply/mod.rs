//! Standard 3DGS `.ply` and PlayCanvas/SuperSplat `compressed.ply` reading and writing.
//!
//! [`read_raw`] accepts `binary_little_endian 1.0` files in either layout and returns the standard
//! raw parameterisation ([`RawSplats`]). Elements other than the ones used are skipped by size;
//! elements with `list` properties (e.g. mesh faces) are skipped by walking their entries, but a
//! list property inside the `vertex`, `chunk` or `sh` element is an error. Bytes after the last
//! element used are ignored. Every problem is an [`InputError`] naming the file; no input panics.

pub mod bench;
pub mod compressed;
pub mod header;
pub mod standard;
pub mod write;

pub use bench::{bench_load_throughput, bench_splats};
pub use write::{standard_bytes, write_standard};

use crate::error::{InputError, InputResult};
use crate::scene::RawSplats;
use compressed::Table;
use std::path::Path;

/// Reads a `.ply` file (standard or compressed layout) into the standard raw parameterisation.
pub fn read_raw(path: &Path) -> InputResult<RawSplats> {
    let bytes = std::fs::read(path).map_err(|e| InputError::new(path, format!("cannot read file: {e}")))?;
    parse_raw(&bytes, path)
}

/// Like [`read_raw`], from the file's bytes in memory; `path` is used in error messages only.
pub fn parse_raw(bytes: &[u8], path: &Path) -> InputResult<RawSplats> {
    let header = header::parse_header(bytes, path)?;
    let index = |name: &str| header.elements.iter().position(|e| e.name == name);
    let vi = index("vertex").ok_or_else(|| InputError::new(path, "no 'vertex' element in the header"))?;
    let vertex = &header.elements[vi];
    let chunk_index = index("chunk");
    if compressed::is_compressed(chunk_index.map(|i| &header.elements[i]), vertex) {
        let ci = chunk_index.unwrap_or(vi);
        let si = index("sh");
        let last = vi.max(ci).max(si.unwrap_or(0));
        let ranges = header::element_ranges(&header, bytes, last, path)?;
        let table = |i: usize| Table::new(&header.elements[i], &bytes[ranges[i].clone()]);
        compressed::decode(table(ci), table(vi), si.map(table), path)
    } else {
        let ranges = header::element_ranges(&header, bytes, vi, path)?;
        standard::decode_vertices(vertex, &bytes[ranges[vi].clone()], path)
    }
}
