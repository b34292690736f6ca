//! The official Neo artifact simulator's DRAM accounting (casys-kaist/Neo, `src/simulator/neo`),
//! restated from its documented behaviour (`../shared/reference/artifact/README.md`) so that
//! its figures can be reconciled with neo's.
//!
//! [`artifact_lines`] gives, for one `poc.trace` frame ([`poc::PocFrame`]), the 64-byte lines
//! each of the artifact's 15 request names sends, quirks included:
//! - every contiguous transfer moves `floor(bytes / 64)` lines (a partial last line is never
//!   moved, so a list of 10 or fewer 6-byte entries moves nothing);
//! - one line per feature-entry read and per projection store, even when the 22-byte entry
//!   straddles two lines; two lines per 112-byte parameter record;
//! - three line writes per incoming (Gaussian, tile) pair;
//! - the incoming sort's approximation passes: `L = max(1, ceil(log2(n_new / 256)))` with
//!   integer division (and one pass below 256 entries), a first load, then `L` stores and
//!   `L - 1` loads of the whole list;
//! - the precise sort's store has size 0 (nothing is written back);
//! - DPS (`Adaptive Sort`) loads and stores each chunk of at most 256 reused entries;
//! - the renderer loads and stores the table (`New Gaussian Order`) per chunk of 256 and reads
//!   one feature line per entry (`Projection Information`); no merge and no frame buffer.
//!
//! `tests/artifact_reference.rs` checks every count against the artifact's own counters on
//! neo's trace exports.

pub mod poc;
pub mod timing;
pub mod waterfall;

use poc::PocFrame;

/// The artifact's entry sizes and chunk parameters (`config.artifact_constants` and
/// `NEO.yaml` in the reference).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ArtifactSizes {
    /// Bytes of a request (`CacheLine`).
    pub line: u64,
    /// FP16 position bytes per Gaussian (`RAW_POSTION_SIZE`).
    pub position: u64,
    /// Other parameter bytes per Gaussian (`RAW_OTHERS_SIZE`).
    pub others: u64,
    /// Feature-entry bytes (`PROJECTION_ENTRY_SIZE`).
    pub feature: u64,
    /// Sort-entry bytes (`NEW_ENTRY_SIZE`, `REUSE_ENTRY_SIZE`).
    pub entry: u64,
    /// Incoming-sort chunk (`GlobalChunkSize`).
    pub global_chunk: u64,
    /// DPS chunk (`AdaptiveChunkSize`).
    pub adaptive_chunk: u64,
    /// Render chunk (`RenderChunkSize`).
    pub render_chunk: u64,
}

impl Default for ArtifactSizes {
    fn default() -> Self {
        ArtifactSizes {
            line: 64,
            position: 6,
            others: 112,
            feature: 22,
            entry: 6,
            global_chunk: 256,
            adaptive_chunk: 256,
            render_chunk: 256,
        }
    }
}

/// Which of the artifact's ways of charging a frame are replaced by neo's (all off: the
/// artifact). The waterfall ([`waterfall::waterfall`]) switches them on one at a time, in the
/// order of [`Rules::step`]; the timing restatement ([`timing::artifact_timing_with`]) issues
/// the requests each set of rules implies.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Rules {
    /// The precise sort's store writes its chunk (the artifact's has size 0).
    pub precise_store: bool,
    /// Contiguous lists move every line they need (the artifact rounds down).
    pub round_up: bool,
    /// A feature entry that straddles two lines costs both.
    pub straddle: bool,
    /// Duplication writes one sort entry per incoming pair, each tile's list contiguous (the
    /// artifact: three line writes per pair).
    pub dup_entries: bool,
    /// The incoming merge is charged as golden's accounting fuses it with DPS: the sorted
    /// incoming list is read and the merged table written instead of DPS's store.
    pub merge_fused: bool,
    /// Preprocessing writes the feature table as one stream (the artifact: a line per Gaussian).
    pub feature_stream: bool,
    /// The frame buffer is written, this many bytes per pixel.
    pub frame_buffer: Option<u64>,
    /// neo's parameter and feature-entry sizes replace the artifact's.
    pub neo_sizes: Option<waterfall::NeoSizes>,
    /// Preprocessing moves what the RTL Preprocessing Engine moves (neither the artifact nor
    /// its trace has it; [`waterfall::pre_engine_lines`], golden `engine::pre::pre_transfers`):
    /// every lane's geometry stream and each visible Gaussian's SH record read, on a frame
    /// that reuses tables each visible Gaussian's previous 32-byte feature word read (incoming
    /// detection), every Gaussian's feature word written, the lists in 8-byte entries and
    /// their lengths written; the raster gathers 32-byte words by id. Needs `neo_sizes`.
    pub pre_engine: bool,
}

impl Rules {
    /// The names of the steps, in order (step 0: the artifact).
    pub const STEPS: [&'static str; 10] = [
        "the artifact",
        "+ the precise sort's store is written (not size 0)",
        "+ partial lines are moved (lists round up, not down)",
        "+ straddling feature entries cost two lines",
        "+ duplication writes 6 B per pair, not 3 lines",
        "+ the incoming merge is charged, fused with DPS",
        "+ the feature table is written as one stream",
        "+ the frame buffer is written",
        "+ neo's byte sizes (parameters, feature entries)",
        "+ the RTL's preprocessing transfers (golden pre_transfers)",
    ];

    /// The rules after the first `k` steps of the waterfall, with neo's sizes `neo`.
    pub fn step(k: usize, neo: &waterfall::NeoSizes) -> Rules {
        Rules {
            precise_store: k >= 1,
            round_up: k >= 2,
            straddle: k >= 3,
            dup_entries: k >= 4,
            merge_fused: k >= 5,
            feature_stream: k >= 6,
            frame_buffer: (k >= 7).then_some(neo.pixel),
            neo_sizes: (k >= 8).then_some(*neo),
            pre_engine: k >= 9,
        }
    }
}

/// The artifact's request names, in the order of its source.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Request {
    /// FP16 positions of every Gaussian.
    FrustumCulling,
    /// Parameter records of the non-culled Gaussians.
    ProjectionLoad,
    /// Feature entries written by preprocessing.
    ProjectionStore,
    /// Incoming-list writes.
    Duplication,
    /// The incoming sort's first approximation load.
    ApproxFirstLoad,
    /// Approximation stores.
    ApproxStore,
    /// Approximation reloads.
    ApproxLoad,
    /// The precise sort's first chunk load.
    PreciseFirstLoad,
    /// The precise sort's later chunk loads.
    PreciseLoad,
    /// The precise sort's stores (size 0 in the artifact).
    PreciseStore,
    /// DPS chunk loads.
    AdaptiveLoad,
    /// DPS chunk stores.
    AdaptiveStore,
    /// Feature gathers by the renderer.
    FeatureGather,
    /// The renderer's table loads.
    OrderLoad,
    /// The renderer's table stores (depth write-back).
    OrderStore,
}

impl Request {
    /// Every request name, in source order.
    pub const ALL: [Request; 15] = [
        Request::FrustumCulling,
        Request::ProjectionLoad,
        Request::ProjectionStore,
        Request::Duplication,
        Request::ApproxFirstLoad,
        Request::ApproxStore,
        Request::ApproxLoad,
        Request::PreciseFirstLoad,
        Request::PreciseLoad,
        Request::PreciseStore,
        Request::AdaptiveLoad,
        Request::AdaptiveStore,
        Request::FeatureGather,
        Request::OrderLoad,
        Request::OrderStore,
    ];

    /// The name the artifact gives the request (its `memo` string).
    pub fn name(self) -> &'static str {
        match self {
            Request::FrustumCulling => "Frustum Culling",
            Request::ProjectionLoad => "Projection (Load)",
            Request::ProjectionStore => "Projection (Store)",
            Request::Duplication => "Duplication",
            Request::ApproxFirstLoad => "Global Approximation Sort (Load)",
            Request::ApproxStore => "Global Approximation Sort (STORE)",
            Request::ApproxLoad => "Global Approximation Sort (LOAD)",
            Request::PreciseFirstLoad => "Global Precise Sort (LOAD)",
            Request::PreciseLoad => "PRECISE (LOAD)",
            Request::PreciseStore => "Global Precise Sort (Store)",
            Request::AdaptiveLoad => "Adaptive Sort (Load)",
            Request::AdaptiveStore => "Adaptive Sort (Store)",
            Request::FeatureGather => "Projection Information",
            Request::OrderLoad => "New Gaussian Order (Load)",
            Request::OrderStore => "New Gaussian Order (Store)",
        }
    }

    /// True for writes.
    pub fn is_write(self) -> bool {
        matches!(
            self,
            Request::ProjectionStore
                | Request::Duplication
                | Request::ApproxStore
                | Request::PreciseStore
                | Request::AdaptiveStore
                | Request::OrderStore
        )
    }
}

/// Lines per request name ([`Request::ALL`] order).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ArtifactLines(pub [u64; 15]);

impl ArtifactLines {
    /// Lines of one request name.
    pub fn get(&self, r: Request) -> u64 {
        self.0[r as usize]
    }

    fn add(&mut self, r: Request, lines: u64) {
        self.0[r as usize] += lines;
    }

    /// Read lines of every name together.
    pub fn reads(&self) -> u64 {
        Request::ALL.iter().filter(|r| !r.is_write()).map(|&r| self.get(r)).sum()
    }

    /// Write lines of every name together.
    pub fn writes(&self) -> u64 {
        Request::ALL.iter().filter(|r| r.is_write()).map(|&r| self.get(r)).sum()
    }
}

/// The incoming sort's approximation passes for `n` entries: `max(1, ceil(log2(n / chunk)))`
/// with integer division; the artifact's `log2(0)` below one chunk also gives one.
pub fn approx_passes(n: u64, chunk: u64) -> u64 {
    let q = n / chunk.max(1);
    if q <= 1 {
        1
    } else {
        // ceil(log2(q)) for q >= 2.
        (64 - (q - 1).leading_zeros()) as u64
    }
}

/// The lines the artifact moves for `entries` sort entries in chunks of `chunk`: each chunk's
/// bytes rounded down to whole lines.
fn chunked_lines(entries: u64, chunk: u64, s: &ArtifactSizes) -> u64 {
    let full = entries / chunk;
    let rest = entries % chunk;
    full * (chunk * s.entry / s.line) + rest * s.entry / s.line
}

/// The artifact's lines per request name for one frame.
pub fn artifact_lines(f: &PocFrame, s: &ArtifactSizes) -> ArtifactLines {
    let mut l = ArtifactLines::default();
    let visible = f.visible();
    l.add(Request::FrustumCulling, f.culled.len() as u64 * s.position / s.line);
    l.add(Request::ProjectionLoad, visible * s.others.div_ceil(s.line));
    l.add(Request::ProjectionStore, visible);
    let pairs: u64 =
        f.culled.iter().zip(&f.incoming_tiles).filter(|(&c, _)| !c).map(|(_, &n)| n as u64).sum();
    l.add(Request::Duplication, 3 * pairs);
    for t in &f.tiles {
        let new = t.new as u64;
        if new > 0 {
            let list = new * s.entry / s.line;
            let passes = approx_passes(new, s.global_chunk);
            l.add(Request::ApproxFirstLoad, list);
            l.add(Request::ApproxStore, passes * list);
            l.add(Request::ApproxLoad, (passes - 1) * list);
            let first = new.min(s.global_chunk);
            l.add(Request::PreciseFirstLoad, first * s.entry / s.line);
            l.add(Request::PreciseLoad, chunked_lines(new - first, s.global_chunk, s));
        }
        let reused = t.reused as u64;
        l.add(Request::AdaptiveLoad, chunked_lines(reused, s.adaptive_chunk, s));
        l.add(Request::AdaptiveStore, chunked_lines(reused, s.adaptive_chunk, s));
        let count = t.count() as u64;
        l.add(Request::FeatureGather, count);
        l.add(Request::OrderLoad, chunked_lines(count, s.render_chunk, s));
        l.add(Request::OrderStore, chunked_lines(count, s.render_chunk, s));
    }
    l
}

#[cfg(test)]
mod tests {
    use super::poc::PocTile;
    use super::*;

    #[test]
    fn approximation_passes_follow_the_artifact() {
        // Below two chunks: one pass (log2(0) and log2(1) both give one).
        for n in [1, 255, 256, 511] {
            assert_eq!(approx_passes(n, 256), 1, "n = {n}");
        }
        assert_eq!(approx_passes(512, 256), 1);
        assert_eq!(approx_passes(768, 256), 2);
        assert_eq!(approx_passes(1024, 256), 2);
        assert_eq!(approx_passes(1280, 256), 3);
        assert_eq!(approx_passes(15720, 256), 6);
    }

    #[test]
    fn lines_of_a_small_frame() {
        let tile = |new: u32, reused: u32| {
            let n = (new + reused) as usize;
            PocTile { new, reused, entry_bits: vec![1; n], ids: vec![0; n] }
        };
        let f = PocFrame {
            culled: vec![false, true, false],
            incoming_tiles: vec![2, 5, 1],
            tiles: vec![tile(300, 0), tile(10, 700), tile(0, 0)],
            ..PocFrame::default()
        };
        let l = artifact_lines(&f, &ArtifactSizes::default());
        assert_eq!(l.get(Request::FrustumCulling), 0, "18 bytes round down to nothing");
        assert_eq!(l.get(Request::ProjectionLoad), 4);
        assert_eq!(l.get(Request::ProjectionStore), 2);
        assert_eq!(l.get(Request::Duplication), 9, "the culled Gaussian's pairs are not written");
        // Tile 0: 300 entries = 1800 B = 28 lines; tile 1: 10 entries = 60 B = 0 lines.
        assert_eq!(l.get(Request::ApproxFirstLoad), 28);
        assert_eq!(l.get(Request::ApproxStore), 28);
        assert_eq!(l.get(Request::ApproxLoad), 0);
        assert_eq!(l.get(Request::PreciseFirstLoad), 24);
        assert_eq!(l.get(Request::PreciseLoad), 4, "44 entries = 264 B = 4 lines");
        assert_eq!(l.get(Request::PreciseStore), 0);
        // 700 reused = 256 + 256 + 188: 24 + 24 + 17 lines.
        assert_eq!(l.get(Request::AdaptiveLoad), 65);
        assert_eq!(l.get(Request::AdaptiveStore), 65);
        assert_eq!(l.get(Request::FeatureGather), 1010);
        // 300 = 256 + 44: 24 + 4; 710 = 256 + 256 + 198: 24 + 24 + 18.
        assert_eq!(l.get(Request::OrderLoad), 94);
        assert_eq!(l.reads() + l.writes(), l.0.iter().sum::<u64>());
    }
}
