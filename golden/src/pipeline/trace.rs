//! Export of one frame in the Neo artifact simulator's text format (`poc.trace`).
//!
//! ```text
//! W H tile_size sub_tile_size chunk_size num_gaussian num_tile
//! culled count tile_0 ... tile_{count-1}          (one line per Gaussian of the scene, by id)
//! num_new num_reuse count                         (one block per tile, row-major)
//! id b_0 b_1 ... b_{m-1}                          (count lines, in table order)
//! ```
//!
//! Resolved ambiguities (our reading):
//! - `culled` is 1 when the Gaussian has no feature entry this frame (culled by preprocessing:
//!   behind the near plane, degenerate, off screen). A Gaussian that survives preprocessing but
//!   touches no tile has `culled = 0, count = 0`.
//! - A Gaussian's tiles are those where it is **incoming** this frame (its id is in the tile's
//!   incoming list: touching the tile now and not valid in its previous table), ascending
//!   row-major tile index `ty * tiles_x + tx`. On a frame sorted from scratch (frame 0, a cut, a
//!   periodic refresh) every tile it touches is listed.
//! - Per tile, `count` is the length of the table the raster reads this frame (after DPS,
//!   insertion, deletion and the capacity cut); `num_reuse` of its entries came from the
//!   previous frame's table and `num_new = count - num_reuse` from the incoming list.
//!   (With a capacity cut, an incoming Gaussian may be listed for a tile whose table dropped it.)
//! - Each entry line is the Gaussian id and its subtile bitmap in this tile, `m = (tile /
//!   sub_tile)^2` values `0`/`1` separated by spaces, row-major (subtile `(sx, sy)` at position
//!   `sy * n + sx`). Entries of Gaussians culled this frame (still in a reused table) have an
//!   all-zero bitmap.

use std::io::{self, Write};

use crate::sort::SortEntry;

/// The end of a trace file's name ([`file_name`]).
pub const FILE_SUFFIX: &str = ".poc.trace";

/// The file name of frame `frame`'s trace in a directory of traces: `frame_NNNNN.poc.trace`.
pub fn file_name(frame: usize) -> String {
    format!("frame_{frame:05}{FILE_SUFFIX}")
}

/// The header fields of a trace.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TraceHeader {
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Tile side.
    pub tile: u32,
    /// Subtile side.
    pub subtile: u32,
    /// Chunk size.
    pub chunk: usize,
}

/// Writes a trace. Per Gaussian id: `culled[id]`; per tile (row-major): the table
/// (`tables[t]`), the subtile bitmap of each entry (`bitmaps[t]`, same length), the incoming
/// ids (`incoming[t]`) and the number of table entries reused from the previous table
/// (`reused[t]`).
pub fn write_trace(
    out: &mut dyn Write,
    header: &TraceHeader,
    culled: &[bool],
    tables: &[&[SortEntry]],
    bitmaps: &[&[u64]],
    incoming: &[&[u32]],
    reused: &[u32],
) -> io::Result<()> {
    let tiles = tables.len();
    assert!(bitmaps.len() == tiles && incoming.len() == tiles && reused.len() == tiles, "one entry per tile");
    let n = header.tile / header.subtile.max(1);
    let m = (n * n) as usize;
    let mut w = io::BufWriter::with_capacity(1 << 20, out);
    writeln!(
        w,
        "{} {} {} {} {} {} {}",
        header.width,
        header.height,
        header.tile,
        header.subtile,
        header.chunk,
        culled.len(),
        tiles
    )?;
    // Incoming tiles per Gaussian (CSR, ascending tile index).
    let mut offsets = vec![0usize; culled.len() + 1];
    for list in incoming {
        for &id in *list {
            offsets[id as usize + 1] += 1;
        }
    }
    for i in 0..culled.len() {
        offsets[i + 1] += offsets[i];
    }
    let mut cursor = offsets[..culled.len()].to_vec();
    let mut tiles_of = vec![0u32; offsets[culled.len()]];
    for (t, list) in incoming.iter().enumerate() {
        for &id in *list {
            tiles_of[cursor[id as usize]] = t as u32;
            cursor[id as usize] += 1;
        }
    }
    let mut line = Vec::with_capacity(256);
    for (id, &c) in culled.iter().enumerate() {
        line.clear();
        let ts = &tiles_of[offsets[id]..offsets[id + 1]];
        write!(line, "{} {}", c as u8, ts.len())?;
        for t in ts {
            write!(line, " {t}")?;
        }
        line.push(b'\n');
        w.write_all(&line)?;
    }
    for t in 0..tiles {
        let (table, bits) = (tables[t], bitmaps[t]);
        assert_eq!(table.len(), bits.len(), "one bitmap per table entry (tile {t})");
        let count = table.len();
        let reuse = (reused[t] as usize).min(count);
        writeln!(w, "{} {} {}", count - reuse, reuse, count)?;
        for (e, &b) in table.iter().zip(bits) {
            line.clear();
            write!(line, "{}", e.id)?;
            for j in 0..m {
                line.extend_from_slice(if b >> j & 1 == 1 { b" 1" } else { b" 0" });
            }
            line.push(b'\n');
            w.write_all(&line)?;
        }
    }
    w.flush()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn small_trace_layout() {
        let h = TraceHeader { width: 32, height: 16, tile: 16, subtile: 8, chunk: 256 };
        let culled = [false, true, false];
        let t0 = [SortEntry::new(1, 2), SortEntry::new(3, 0)];
        let t1 = [SortEntry::new(1, 0)];
        let mut out = Vec::new();
        write_trace(
            &mut out,
            &h,
            &culled,
            &[&t0, &t1],
            &[&[0b1001, 0b0001], &[0b0110]],
            &[&[0, 2], &[0]],
            &[0, 1],
        )
        .unwrap();
        let text = String::from_utf8(out).unwrap();
        let expect = "32 16 16 8 256 3 2\n\
                      0 2 0 1\n\
                      1 0\n\
                      0 1 0\n\
                      2 0 2\n\
                      2 1 0 0 1\n\
                      0 1 0 0 0\n\
                      0 1 1\n\
                      0 0 1 1 0\n";
        assert_eq!(text, expect);
    }
}
