//! Reader of the Neo artifact simulator's `poc.trace` text format, the format
//! `neo_golden::pipeline::trace::write_trace` writes (docs/formats.md).
//!
//! Only what the artifact's accounting and timing use is kept: per Gaussian the culling flag
//! and how many tiles it is incoming in; per tile the new, reused and table counts and each
//! table entry's number of set subtile bits. Every malformed line is an error naming the file,
//! the 1-based line and the problem.

use neo_golden::trajectory::resolution::MAX_SIDE;
use std::path::Path;

/// The largest chunk a trace may name (the engine configuration's limit).
const MAX_CHUNK: u64 = 1 << 16;

/// One tile of a trace.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct PocTile {
    /// Table entries that came from the incoming list (`num_new`).
    pub new: u32,
    /// Table entries reused from the previous table (`num_reuse`).
    pub reused: u32,
    /// Set subtile bits of each table entry, in table order (`count` entries).
    pub entry_bits: Vec<u8>,
    /// The Gaussian id of each table entry, in table order.
    pub ids: Vec<u32>,
}

impl PocTile {
    /// The table length (`count`).
    pub fn count(&self) -> u32 {
        self.entry_bits.len() as u32
    }
}

/// One frame of a trace.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct PocFrame {
    /// Image width and height.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Tile side in pixels.
    pub tile: u32,
    /// Subtile side in pixels.
    pub subtile: u32,
    /// Chunk size of the header.
    pub chunk: u32,
    /// Per Gaussian: culled this frame.
    pub culled: Vec<bool>,
    /// Per Gaussian: the number of tiles it is incoming in.
    pub incoming_tiles: Vec<u32>,
    /// The tiles each Gaussian is incoming in, Gaussian after Gaussian (`incoming_tiles[g]`
    /// each, ascending).
    pub incoming_list: Vec<u32>,
    /// Per tile, row-major.
    pub tiles: Vec<PocTile>,
}

/// Statistics of a trace, the fields of the artifact reference's `trace_stats`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PocStats {
    /// Sum of the table lengths.
    pub table_entries: u64,
    /// Sum of `num_new`.
    pub incoming_entries: u64,
    /// Sum of `num_reuse`.
    pub reused_entries: u64,
    /// Tiles with a non-empty table.
    pub nonempty_tiles: u64,
    /// Gaussians in the scene.
    pub gaussians: u64,
    /// Gaussians culled.
    pub culled: u64,
    /// Sum of the per-Gaussian incoming tile lists.
    pub incoming_pairs: u64,
    /// The longest table.
    pub max_table_len: u64,
    /// Set subtile bits over every table entry.
    pub bitmap_popcount: u64,
}

impl PocFrame {
    /// Gaussians not culled.
    pub fn visible(&self) -> u64 {
        self.culled.iter().filter(|&&c| !c).count() as u64
    }

    /// True when some tile reused entries of the previous table (a frame sorted from scratch
    /// lists every entry as new).
    pub fn reuses_tables(&self) -> bool {
        self.tiles.iter().any(|t| t.reused > 0)
    }

    /// The trace's statistics.
    pub fn stats(&self) -> PocStats {
        let mut s = PocStats {
            gaussians: self.culled.len() as u64,
            culled: self.culled.iter().filter(|&&c| c).count() as u64,
            incoming_pairs: self.incoming_tiles.iter().map(|&n| n as u64).sum(),
            ..PocStats::default()
        };
        for t in &self.tiles {
            let count = t.count() as u64;
            s.table_entries += count;
            s.incoming_entries += t.new as u64;
            s.reused_entries += t.reused as u64;
            s.nonempty_tiles += (count > 0) as u64;
            s.max_table_len = s.max_table_len.max(count);
            s.bitmap_popcount += t.entry_bits.iter().map(|&b| b as u64).sum::<u64>();
        }
        s
    }
}

/// A malformed trace: the file, the 1-based line (0: the file as a whole) and why.
pub type PocError = crate::file_error::LineError;

/// Reads the trace file at `path`.
pub fn read_poc_trace(path: &Path) -> Result<PocFrame, PocError> {
    let text = std::fs::read_to_string(path).map_err(|e| PocError {
        path: path.to_path_buf(),
        line: 0,
        message: format!("cannot read: {e}"),
    })?;
    parse_poc_trace(&text, path)
}

/// Parses a trace's text; `path` names it in errors.
pub fn parse_poc_trace(text: &str, path: &Path) -> Result<PocFrame, PocError> {
    let mut lines = Lines { it: text.lines(), line: 0, path };
    let h = lines.numbers("the header", 7)?;
    let [width, height, tile, subtile, chunk, gaussians, tiles] = [h[0], h[1], h[2], h[3], h[4], h[5], h[6]];
    let side = u64::from(MAX_SIDE);
    if !(1..=side).contains(&width) || !(1..=side).contains(&height) {
        return Err(lines.err(format!("image {width}x{height}: each side must be 1 to {side} pixels")));
    }
    if tile == 0 || subtile == 0 || tile % subtile != 0 || tile / subtile > 8 || tile > side {
        return Err(
            lines.err(format!("tile {tile} and subtile {subtile}: need a tile of at most 8 x 8 subtiles"))
        );
    }
    if !(1..=MAX_CHUNK).contains(&chunk) {
        return Err(lines.err(format!("chunk {chunk} is not in 1..={MAX_CHUNK}")));
    }
    if gaussians > u64::from(u32::MAX) {
        return Err(lines.err(format!("{gaussians} Gaussians: ids are 32-bit, at most {}", u32::MAX)));
    }
    let expect_tiles = width.div_ceil(tile) * height.div_ceil(tile);
    if tiles != expect_tiles {
        return Err(lines
            .err(format!("{tiles} tiles, but a {width}x{height} image has {expect_tiles} tiles of {tile}")));
    }
    // Each Gaussian line and tile header takes at least 4 bytes: no larger reservation than the
    // text could fill, whatever the header claims.
    let n = gaussians as usize;
    let room = |count: usize| count.min(text.len() / 4);
    let mut frame = PocFrame {
        width: width as u32,
        height: height as u32,
        tile: tile as u32,
        subtile: subtile as u32,
        chunk: chunk as u32,
        culled: Vec::with_capacity(room(n)),
        incoming_tiles: Vec::with_capacity(room(n)),
        incoming_list: Vec::new(),
        tiles: Vec::with_capacity(room(tiles as usize)),
    };
    for _ in 0..n {
        let g = lines.numbers_at_least("a Gaussian line", 2)?;
        if g[0] > 1 {
            return Err(lines.err(format!("culled flag {} is not 0 or 1", g[0])));
        }
        if g.len() as u64 != 2 + g[1] {
            return Err(lines.err(format!("tile count {} but {} tiles listed", g[1], g.len() - 2)));
        }
        if let Some(&t) = g[2..].iter().find(|&&t| t >= tiles) {
            return Err(lines.err(format!("tile {t} is outside the {tiles} tiles")));
        }
        // A Gaussian is incoming in a tile once: a repeat would be counted as another entry.
        let mut listed = g[2..].to_vec();
        listed.sort_unstable();
        if let Some(w) = listed.windows(2).find(|w| w[0] == w[1]) {
            return Err(lines.err(format!("tile {} is listed twice", w[0])));
        }
        frame.culled.push(g[0] == 1);
        frame.incoming_tiles.push(g[1] as u32);
        frame.incoming_list.extend(g[2..].iter().map(|&t| t as u32));
    }
    let bits = ((tile / subtile) * (tile / subtile)) as usize;
    for _ in 0..tiles {
        frame.tiles.push(tile_block(&mut lines, gaussians, bits)?);
    }
    if let Some(extra) = lines.next_nonblank() {
        return Err(lines.err(format!("unexpected text after the last tile: {:?}", truncate(extra))));
    }
    Ok(frame)
}

fn tile_block(lines: &mut Lines<'_>, gaussians: u64, bits: usize) -> Result<PocTile, PocError> {
    let h = lines.numbers("a tile header (num_new num_reuse count)", 3)?;
    if h[0].checked_add(h[1]) != Some(h[2]) {
        return Err(lines.err(format!("num_new {} + num_reuse {} is not count {}", h[0], h[1], h[2])));
    }
    if h[2] > u64::from(u32::MAX) {
        return Err(lines.err(format!("count {} exceeds a 32-bit table length", h[2])));
    }
    // Reserved up to a bound: the count is only a claim until its lines are read.
    let n = (h[2] as usize).min(1 << 16);
    let mut t = PocTile {
        new: h[0] as u32,
        reused: h[1] as u32,
        entry_bits: Vec::with_capacity(n),
        ids: Vec::with_capacity(n),
    };
    for _ in 0..h[2] {
        let e = lines.numbers("a table entry (id and subtile bits)", 1 + bits)?;
        if e[0] >= gaussians {
            return Err(lines.err(format!("Gaussian id {} is outside the {gaussians} Gaussians", e[0])));
        }
        if e[1..].iter().any(|&b| b > 1) {
            return Err(lines.err("subtile bits must be 0 or 1".to_string()));
        }
        t.entry_bits.push(e[1..].iter().sum::<u64>() as u8);
        t.ids.push(e[0] as u32);
    }
    Ok(t)
}

fn truncate(s: &str) -> &str {
    &s[..s.char_indices().nth(40).map_or(s.len(), |(i, _)| i)]
}

struct Lines<'a> {
    it: std::str::Lines<'a>,
    line: usize,
    path: &'a Path,
}

impl<'a> Lines<'a> {
    fn err(&self, msg: String) -> PocError {
        PocError { path: self.path.to_path_buf(), line: self.line, message: msg }
    }

    fn next_nonblank(&mut self) -> Option<&'a str> {
        for l in self.it.by_ref() {
            self.line += 1;
            if !l.trim().is_empty() {
                return Some(l);
            }
        }
        None
    }

    fn numbers_at_least(&mut self, what: &str, min: usize) -> Result<Vec<u64>, PocError> {
        let Some(l) = self.next_nonblank() else {
            self.line += 1;
            return Err(self.err(format!("the file ends where {what} was expected")));
        };
        let v: Result<Vec<u64>, _> = l.split_whitespace().map(str::parse::<u64>).collect();
        let v =
            v.map_err(|_| self.err(format!("{what}: expected unsigned integers, found {:?}", truncate(l))))?;
        if v.len() < min {
            return Err(self.err(format!("{what}: expected at least {min} numbers, found {}", v.len())));
        }
        Ok(v)
    }

    fn numbers(&mut self, what: &str, n: usize) -> Result<Vec<u64>, PocError> {
        let v = self.numbers_at_least(what, n)?;
        if v.len() != n {
            return Err(self.err(format!("{what}: expected {n} numbers, found {}", v.len())));
        }
        Ok(v)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use neo_golden::pipeline::trace::{write_trace, TraceHeader};
    use neo_golden::sort::SortEntry;
    use proptest::prelude::*;

    fn small() -> String {
        let h = TraceHeader { width: 32, height: 16, tile: 16, subtile: 8, chunk: 256 };
        let t0 = [SortEntry::new(1, 2), SortEntry::new(3, 0)];
        let t1 = [SortEntry::new(1, 0)];
        let mut out = Vec::new();
        write_trace(
            &mut out,
            &h,
            &[false, true, false, false],
            &[&t0, &t1],
            &[&[0b1001, 0b0001], &[0b0110]],
            &[&[0, 2], &[0]],
            &[1, 1],
        )
        .unwrap();
        String::from_utf8(out).unwrap()
    }

    #[test]
    fn reads_what_golden_writes() {
        let f = parse_poc_trace(&small(), Path::new("t.trace")).unwrap();
        assert_eq!((f.width, f.height, f.tile, f.subtile, f.chunk), (32, 16, 16, 8, 256));
        assert_eq!(f.culled, [false, true, false, false]);
        assert_eq!(f.incoming_tiles, [2, 0, 1, 0]);
        assert_eq!(f.incoming_list, [0, 1, 0]);
        assert_eq!(f.tiles[0], PocTile { new: 1, reused: 1, entry_bits: vec![2, 1], ids: vec![2, 0] });
        assert_eq!(f.tiles[1], PocTile { new: 0, reused: 1, entry_bits: vec![2], ids: vec![0] });
        let s = f.stats();
        assert_eq!((s.table_entries, s.incoming_entries, s.reused_entries), (3, 1, 2));
        assert_eq!((s.culled, s.incoming_pairs, s.max_table_len, s.bitmap_popcount), (1, 3, 2, 5));
    }

    #[test]
    fn errors_name_file_line_and_problem() {
        let good = small();
        let cases: [(&str, &str, usize, &str); 7] = [
            ("32 16 16 8 256 4 2", "32 16 16 8 256 4 3", 1, "3 tiles"),
            ("1 0\n", "2 0\n", 3, "culled flag"),
            ("0 2 0 1", "0 2 0 9", 2, "tile 9"),
            ("0 2 0 1", "0 2 1 1", 2, "tile 1 is listed twice"),
            ("1 1 2\n", "1 1 3\n", 6, "is not count 3"),
            ("\n0 1 0 0 0", "\n7 1 0 0 0", 8, "Gaussian id 7"),
            ("\n0 1 0 0 0", "\n0 1 0 x 0", 8, "unsigned integers"),
        ];
        for (from, to, line, phrase) in cases {
            let bad = good.replacen(from, to, 1);
            assert_ne!(bad, good, "{from} not found");
            let e = parse_poc_trace(&bad, Path::new("t.trace")).unwrap_err();
            assert_eq!(e.line, line, "{e}");
            assert!(e.to_string().starts_with(&format!("t.trace:{line}: ")), "{e}");
            assert!(e.message.contains(phrase), "{e}");
        }
        let header_cases = [
            ("32 16 16 8 256 4 2", "0 0 16 8 256 4 0", "image 0x0"),
            ("32 16 16 8 256 4 2", "18446744073709551615 18446744073709551615 1 1 256 1 1", "each side"),
            ("32 16 16 8 256 4 2", "32 16 16 8 0 4 2", "chunk 0"),
            ("32 16 16 8 256 4 2", "32 16 16 8 4294967552 4 2", "chunk 4294967552"),
            ("32 16 16 8 256 4 2", "32 16 16 8 256 99999999999999 2", "ids are 32-bit"),
            ("32 16 16 8 256 4 2", "6400000000 6400000000 64 8 256 1 10000000000000000", "each side"),
        ];
        for (from, to, phrase) in header_cases {
            let e = parse_poc_trace(&good.replacen(from, to, 1), Path::new("t.trace")).unwrap_err();
            assert_eq!(e.line, 1, "{e}");
            assert!(e.message.contains(phrase), "{to}: {e}");
        }
        // A huge count on the header (4 Gaussians claimed as 4e9) or a tile header fails on the
        // lines that follow, without reserving for the claim first.
        let e = parse_poc_trace(&good.replacen(" 4 2\n", " 4000000000 2\n", 1), Path::new("t.trace"))
            .unwrap_err();
        assert!(e.line > 1, "{e}");
        let e =
            parse_poc_trace(&good.replacen("1 1 2\n", "18446744073709551615 1 0\n", 1), Path::new("t.trace"))
                .unwrap_err();
        assert!(e.message.contains("is not count 0"), "{e}");
        let e = parse_poc_trace(
            &good.replacen("1 1 2\n", "4294967295 4294967295 8589934590\n", 1),
            Path::new("t.trace"),
        )
        .unwrap_err();
        assert!(e.message.contains("exceeds a 32-bit table length"), "{e}");
        let cut = &good[..good.len() - 12];
        assert!(parse_poc_trace(cut, Path::new("t.trace")).unwrap_err().message.contains("expected"));
        let e = read_poc_trace(Path::new("/nonexistent/t.trace")).unwrap_err();
        assert!(e.to_string().contains("/nonexistent/t.trace: cannot read"), "{e}");
    }

    proptest! {
        /// Any text is either a frame or an error; never a panic.
        #[test]
        fn never_panics(text in "[0-9 \n]{0,200}") {
            let _ = parse_poc_trace(&text, Path::new("p.trace"));
        }

        /// Every mutation of one character of a valid trace parses or fails with a line number
        /// inside the file.
        #[test]
        fn mutations_fail_cleanly(pos in 0usize..100, c in "[0-9a-z \n]") {
            let good = small();
            let pos = pos % good.len();
            let mut bad = good.clone();
            bad.replace_range(pos..pos + 1, &c);
            if let Err(e) = parse_poc_trace(&bad, Path::new("p.trace")) {
                prop_assert!(e.line >= 1 && e.line <= bad.lines().count() + 1, "{e}");
            }
        }
    }
}
