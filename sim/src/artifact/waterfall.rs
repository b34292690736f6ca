//! From the artifact's DRAM bytes to neo's accounting of the same work, one assumption at a
//! time (the reconciliation waterfall, bytes only).
//!
//! Every step keeps the artifact's structure and byte sizes (FP16 parameters, 22-byte feature
//! entries, 6-byte sort entries) and changes one way of charging. Each row is cumulative and
//! split into neo's stages ([`Stage`]), so the last row can be set beside neo's own figure for
//! the same frame: what is left between them is neo's byte sizes and neo's sorting work (its
//! exact per-tile commands instead of the artifact's approximation passes).

use neo_golden::engine::pre::{pre_transfers, PrePart};
use neo_golden::engine::{beats_spanned, EngineConfig, FrameRegs, PreRegs, PRE_ENABLE, PRE_FRESH};

use super::poc::PocFrame;
use super::timing::ArtifactLayout;
use super::{approx_passes, artifact_lines, ArtifactSizes, Request, Rules};
use crate::traffic::{Dir, Stage};

/// Bytes by neo stage and direction ([`Stage::ALL`] order; read, write).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StageBytes(pub [[u64; 2]; Stage::COUNT]);

impl StageBytes {
    fn add(&mut self, stage: Stage, dir: Dir, bytes: u64) {
        self.0[stage as usize][dir as usize] += bytes;
    }

    /// Bytes of one stage and direction.
    pub fn get(&self, stage: Stage, dir: Dir) -> u64 {
        self.0[stage as usize][dir as usize]
    }

    /// All bytes.
    pub fn total(&self) -> u64 {
        self.0.iter().map(|s| s[0] + s[1]).sum()
    }
}

/// The neo stage and direction the artifact's request name is charged to.
pub fn stage_of(r: Request) -> (Stage, Dir) {
    use Request::*;
    let dir = if r.is_write() { Dir::Write } else { Dir::Read };
    let stage = match r {
        FrustumCulling | ProjectionLoad => Stage::Preprocess,
        ProjectionStore | FeatureGather => Stage::FeatureTable,
        Duplication | ApproxFirstLoad => Stage::IncomingList,
        ApproxStore | ApproxLoad | PreciseFirstLoad | PreciseLoad | PreciseStore | AdaptiveLoad
        | AdaptiveStore => Stage::SortTable,
        OrderLoad => Stage::RasterTable,
        OrderStore => Stage::DepthWriteback,
    };
    (stage, dir)
}

/// One row of the waterfall: the assumption changed and the cumulative bytes after it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Step {
    /// What this step changes.
    pub name: &'static str,
    /// Bytes by stage after the change.
    pub bytes: StageBytes,
}

/// Lines covering `bytes` from byte `base`: every line touched.
fn touched(base: u64, bytes: u64, line: u64) -> u64 {
    if bytes == 0 {
        0
    } else {
        (base + bytes - 1) / line - base / line + 1
    }
}

/// Pixels of tile `t` (row-major) inside the image.
pub fn tile_pixels(f: &PocFrame, t: usize) -> u64 {
    let tw = f.width.div_ceil(f.tile.max(1)) as usize;
    let (tx, ty) = ((t % tw) as u32, (t / tw) as u32);
    let w = f.width.min((tx + 1) * f.tile) - tx * f.tile;
    let h = f.height.min((ty + 1) * f.tile) - ty * f.tile;
    w as u64 * h as u64
}

/// Chunks of `n` entries by `chunk`, each `f(chunk length)`, summed.
fn per_chunk(n: u64, chunk: u64, f: impl Fn(u64) -> u64) -> u64 {
    (0..n).step_by(chunk.max(1) as usize).map(|a| f((n - a).min(chunk))).sum()
}

/// neo's byte sizes, for the waterfall's last step (`SimConfig::sizes` and golden's feature
/// format).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct NeoSizes {
    /// Geometry bytes read for every Gaussian.
    pub geometry: u64,
    /// SH bytes read for every non-culled Gaussian.
    pub sh: u64,
    /// Feature-entry bytes.
    pub feature: u64,
    /// Frame-buffer bytes per pixel.
    pub pixel: u64,
    /// The scene's SH degree (the Preprocessing Engine's f32 SH records, the last step).
    pub sh_degree: u8,
}

/// Per tile, the incoming pairs of visible Gaussians the trace's duplication lists (the
/// length of the tile's incoming list).
pub fn incoming_per_tile(f: &PocFrame) -> Vec<u64> {
    let mut per_tile = vec![0u64; f.tiles.len()];
    let mut at = 0;
    for (g, &n) in f.incoming_tiles.iter().enumerate() {
        for &t in &f.incoming_list[at..at + n as usize] {
            per_tile[t as usize] += !f.culled[g] as u64;
        }
        at += n as usize;
    }
    per_tile
}

/// The DRAM lines (addresses) the RTL Preprocessing Engine's transfers touch in frame `f`, as
/// neo's model charges them (`neo_sim::arch`): golden `engine::pre::pre_transfers` for the
/// default engine, each transfer the `line`-byte lines it touches, by stage.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct PreEngineLines {
    /// Geometry streams and SH records (stage `preprocess`).
    pub params: Vec<u64>,
    /// The previous feature words of the visible Gaussians on a frame that reuses tables
    /// (`incoming detection`).
    pub previous: Vec<u64>,
    /// Every Gaussian's feature word (`feature table`, written).
    pub features: Vec<u64>,
    /// The incoming lists' lines and lengths (`incoming lists`, written).
    pub lists: Vec<u64>,
}

/// The RTL Preprocessing Engine's lines in frame `f` (see [`PreEngineLines`]) at the bases of
/// `l`, for a scene of SH degree `sh_degree`. The frame is fresh (no previous word read) unless
/// it reuses tables.
pub fn pre_engine_lines(f: &PocFrame, l: &ArtifactLayout, sh_degree: u8, line: u64) -> PreEngineLines {
    let cfg = EngineConfig::default();
    let fresh = if f.reuses_tables() { 0 } else { PRE_FRESH };
    let regs = FrameRegs {
        tiles: f.tiles.len() as u32,
        desc_base: l.pre_descriptors,
        feat_base: l.pre_features[0],
        pre: PreRegs {
            ctrl: PRE_ENABLE | fresh,
            gaussians: f.culled.len() as u32,
            sh_degree: sh_degree as u32,
            geo_base: l.positions,
            sh_base: l.others,
            prev_feat_base: l.pre_features[1],
            list_base: l.pre_lists,
            ..PreRegs::default()
        },
        ..FrameRegs::default()
    };
    let visible = (0..f.culled.len() as u64).filter(|&i| !f.culled[i as usize]);
    let lens = incoming_per_tile(f).into_iter().map(|n| n as usize);
    let mut out = PreEngineLines::default();
    pre_transfers(&cfg, &regs, visible, lens, |t| {
        let v = match t.part {
            PrePart::Geometry | PrePart::Sh => &mut out.params,
            PrePart::PrevFeature => &mut out.previous,
            PrePart::Feature => &mut out.features,
            PrePart::ListLine | PrePart::ListLen => &mut out.lists,
        };
        let first = t.addr / line;
        v.extend((first..first + beats_spanned(t.addr, t.bytes, line)).map(|k| k * line));
    });
    out
}

/// The waterfall of one frame, ending with neo's byte sizes `neo`.
pub fn waterfall(f: &PocFrame, s: &ArtifactSizes, neo: &NeoSizes) -> Vec<Step> {
    let line = s.line;
    let mut b = StageBytes::default();
    let lines = artifact_lines(f, s);
    for r in Request::ALL {
        let (stage, dir) = stage_of(r);
        b.add(stage, dir, lines.get(r) * line);
    }
    let mut steps = vec![Step { name: Rules::STEPS[0], bytes: b }];
    let mut push = |name, b: &StageBytes| steps.push(Step { name, bytes: *b });
    // (first loads, other sorting reads, sorting writes) in lines, each list rounded by `round`.
    let sort_lists = |round: &dyn Fn(u64) -> u64| -> (u64, u64, u64) {
        let (mut first, mut read, mut write) = (0, 0, 0);
        for t in &f.tiles {
            let n = t.new as u64;
            if n > 0 {
                let (list, passes) = (round(n), approx_passes(n, s.global_chunk));
                let precise = per_chunk(n, s.global_chunk, round);
                first += list;
                read += (passes - 1) * list + precise;
                write += passes * list + precise;
            }
            let dps = per_chunk(t.reused as u64, s.adaptive_chunk, round);
            read += dps;
            write += dps;
        }
        (first, read, write)
    };
    // 1. The precise sort writes its chunks back.
    let precise: u64 =
        f.tiles.iter().map(|t| per_chunk(t.new as u64, s.global_chunk, |c| c * s.entry / line)).sum();
    b.add(Stage::SortTable, Dir::Write, precise * line);
    push(Rules::STEPS[1], &b);
    // 2. Partial lines move: every contiguous list costs the lines it touches.
    let floor = |n: u64| n * s.entry / line;
    let ceil = |n: u64| (n * s.entry).div_ceil(line);
    let (f0, r0, w0) = sort_lists(&floor);
    let (f1, r1, w1) = sort_lists(&ceil);
    b.add(Stage::IncomingList, Dir::Read, (f1 - f0) * line);
    b.add(Stage::SortTable, Dir::Read, (r1 - r0) * line);
    b.add(Stage::SortTable, Dir::Write, (w1 - w0) * line);
    let order = |round: &dyn Fn(u64) -> u64| -> u64 {
        f.tiles.iter().map(|t| per_chunk(t.count() as u64, s.render_chunk, round)).sum()
    };
    let extra = (order(&ceil) - order(&floor)) * line;
    b.add(Stage::RasterTable, Dir::Read, extra);
    b.add(Stage::DepthWriteback, Dir::Write, extra);
    let pos = f.culled.len() as u64 * s.position;
    b.add(Stage::Preprocess, Dir::Read, (pos.div_ceil(line) - pos / line) * line);
    push(Rules::STEPS[2], &b);
    // 3. A feature entry that straddles two lines costs two, written and gathered.
    let feat = |id: u64| touched(id * s.feature, s.feature, line) - 1;
    let stores: u64 = (0..f.culled.len() as u64).filter(|&i| !f.culled[i as usize]).map(feat).sum();
    let gathers: u64 = f.tiles.iter().flat_map(|t| &t.ids).map(|&id| feat(id as u64)).sum();
    b.add(Stage::FeatureTable, Dir::Write, stores * line);
    b.add(Stage::FeatureTable, Dir::Read, gathers * line);
    push(Rules::STEPS[3], &b);
    // 4. Duplication writes one entry per incoming pair, each tile's list contiguous.
    let dup: u64 = incoming_per_tile(f).iter().map(|&n| ceil(n)).sum();
    b.0[Stage::IncomingList as usize][Dir::Write as usize] = dup * line;
    push(Rules::STEPS[4], &b);
    // 5. The merge is charged the way neo's golden accounting fuses it with DPS: the last DPS
    // pass feeds the MSU+, which reads the sorted incoming list and writes the merged table
    // (instead of DPS writing the reused entries back).
    for t in &f.tiles {
        let (n, m) = (t.new as u64, t.reused as u64);
        if m > 0 {
            b.add(Stage::SortTable, Dir::Read, ceil(n) * line);
            let dps_store = per_chunk(m, s.adaptive_chunk, ceil);
            let merged = ceil(t.count() as u64);
            let w = &mut b.0[Stage::SortTable as usize][Dir::Write as usize];
            *w = *w + merged * line - dps_store * line;
        }
    }
    push(Rules::STEPS[5], &b);
    // 6. Preprocessing writes the feature table as one stream (not a line per Gaussian).
    let visible = f.visible();
    let stream = (visible * s.feature).div_ceil(line);
    let per_gaussian = lines.get(Request::ProjectionStore) + stores;
    let w = &mut b.0[Stage::FeatureTable as usize][Dir::Write as usize];
    *w = *w + stream * line - per_gaussian * line;
    push(Rules::STEPS[6], &b);
    // 7. The frame buffer is written, tile by tile.
    let fb: u64 = (0..f.tiles.len()).map(|t| tile_pixels(f, t) * neo.pixel).map(|b| b.div_ceil(line)).sum();
    b.add(Stage::FrameBuffer, Dir::Write, fb * line);
    push(Rules::STEPS[7], &b);
    // 8. neo's byte sizes: parameters and feature entries.
    let params = (f.culled.len() as u64 * neo.geometry).div_ceil(line) + (visible * neo.sh).div_ceil(line);
    b.0[Stage::Preprocess as usize][Dir::Read as usize] = params * line;
    let gathers: u64 = f
        .tiles
        .iter()
        .flat_map(|t| &t.ids)
        .map(|&id| touched(id as u64 * neo.feature, neo.feature, line))
        .sum();
    b.0[Stage::FeatureTable as usize] = [gathers * line, (visible * neo.feature).div_ceil(line) * line];
    push(Rules::STEPS[8], &b);
    // 9. The RTL Preprocessing Engine's transfers: parameters, previous words (incoming
    // detection), a feature word per Gaussian, the lists in 8-byte entries and their lengths;
    // the raster gathers 32-byte words by id (each within one line).
    let pre = pre_engine_lines(f, &ArtifactLayout::default(), neo.sh_degree, line);
    let n = |v: &Vec<u64>| v.len() as u64 * line;
    b.0[Stage::Preprocess as usize][Dir::Read as usize] = n(&pre.params);
    b.0[Stage::IncomingDetection as usize] = [n(&pre.previous), 0];
    let gathers: u64 = f.tiles.iter().map(|t| t.ids.len() as u64).sum();
    b.0[Stage::FeatureTable as usize] = [gathers * line, n(&pre.features)];
    b.0[Stage::IncomingList as usize][Dir::Write as usize] = n(&pre.lists);
    push(Rules::STEPS[9], &b);
    steps
}

/// A two-tile frame with a culled Gaussian, reused and incoming entries (unit tests).
#[cfg(test)]
pub(crate) fn test_frame() -> PocFrame {
    use super::poc::PocTile;

    let tile = |new: u32, reused: u32, ids: Vec<u32>| {
        let n = (new + reused) as usize;
        assert_eq!(ids.len(), n);
        PocTile { new, reused, entry_bits: vec![1; n], ids }
    };
    PocFrame {
        width: 128,
        height: 64,
        tile: 64,
        subtile: 8,
        chunk: 256,
        culled: vec![false, false, true, false],
        incoming_tiles: vec![2, 1, 1, 0],
        incoming_list: vec![0, 1, 0, 1],
        tiles: vec![tile(2, 0, vec![0, 1]), tile(1, 2, vec![3, 0, 1])],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const NEO: NeoSizes = NeoSizes { geometry: 44, sh: 192, feature: 31, pixel: 3, sh_degree: 3 };

    #[test]
    fn the_first_row_is_the_artifacts_accounting() {
        let f = test_frame();
        let s = ArtifactSizes::default();
        let steps = waterfall(&f, &s, &NEO);
        let lines = artifact_lines(&f, &s);
        assert_eq!(steps[0].bytes.total(), (lines.reads() + lines.writes()) * 64);
        assert_eq!(steps.len(), Rules::STEPS.len());
    }

    #[test]
    fn each_step_changes_what_it_names() {
        let f = test_frame();
        let steps = waterfall(&f, &ArtifactSizes::default(), &NEO);
        let d = |k: usize, st: Stage, dir: Dir| {
            steps[k].bytes.get(st, dir) as i64 - steps[k - 1].bytes.get(st, dir) as i64
        };
        // Tile 0: 2 new entries (12 B: 0 lines floor, 1 line ceil); tile 1: 1 new, 2 reused.
        assert_eq!(d(1, Stage::SortTable, Dir::Write), 0, "lists of 1-2 entries round down to nothing");
        // Ceil: first loads 1 + 1 lines; approx store 1 + 1, precise load 1 + 1, DPS 1 load 1 store.
        assert_eq!(d(2, Stage::IncomingList, Dir::Read), 2 * 64);
        assert_eq!(d(2, Stage::SortTable, Dir::Read), (2 + 1) * 64, "precise loads and the DPS load");
        assert_eq!(
            d(2, Stage::SortTable, Dir::Write),
            (2 + 2 + 1) * 64,
            "approximation and precise stores, DPS"
        );
        assert_eq!(d(2, Stage::RasterTable, Dir::Read), 2 * 64);
        assert_eq!(d(2, Stage::Preprocess, Dir::Read), 64, "24 B of positions");
        // Entries of ids 0, 1 and 3 (bytes 0, 22, 66) sit in one line each; only the culled
        // id 2 (bytes 44..66) would straddle.
        assert_eq!(d(3, Stage::FeatureTable, Dir::Write), 0);
        assert_eq!(d(4, Stage::IncomingList, Dir::Write), 2 * 64 - 3 * 3 * 64, "3 pairs: 9 lines become 2");
        // Tile 1: the DPS store of 2 entries (1 line) becomes the merged table's (3 entries, 1
        // line); the incoming entry is read (1 line).
        assert_eq!(d(5, Stage::SortTable, Dir::Write), 0);
        assert_eq!(d(5, Stage::SortTable, Dir::Read), 64);
        assert_eq!(d(6, Stage::FeatureTable, Dir::Write), 2 * 64 - 3 * 64, "66 B in 2 lines, not 3");
        assert_eq!(d(7, Stage::FrameBuffer, Dir::Write), 128 * 64 * 3);
        // 4 x 44 B of geometry (3 lines) and 3 x 192 B of SH (9 lines); 3 x 31 B of features
        // (2 lines) and gathers of ids 0, 1, 3, 0, 1 (bytes 0..31, 31..62, 93..124: a line each).
        assert_eq!(steps[8].bytes.get(Stage::Preprocess, Dir::Read), 12 * 64);
        assert_eq!(steps[8].bytes.get(Stage::FeatureTable, Dir::Write), 2 * 64);
        assert_eq!(steps[8].bytes.get(Stage::FeatureTable, Dir::Read), 5 * 64);
        // The RTL Preprocessing Engine (tile 1 reuses entries: not fresh). Four lanes of one
        // 44-byte record each (bytes 0..44, 44..88, 88..132, 132..176: 1 + 2 + 2 + 1 lines) and
        // 3 SH records of 192 B (9 lines): 3 lines more than one stream each; 3 previous words
        // (a line each); 4 feature words (a line each, 2 more than 93 B as a stream); the lists
        // of 2 and 1 entries (a line each, as before) and 2 lengths (a line each); the
        // gathers of 32-byte words stay a line each.
        assert_eq!(d(9, Stage::Preprocess, Dir::Read), 3 * 64);
        assert_eq!(d(9, Stage::IncomingDetection, Dir::Read), 3 * 64);
        assert_eq!(d(9, Stage::IncomingDetection, Dir::Write), 0, "no bitmap");
        assert_eq!(d(9, Stage::FeatureTable, Dir::Write), 2 * 64);
        assert_eq!(d(9, Stage::FeatureTable, Dir::Read), 0);
        assert_eq!(d(9, Stage::IncomingList, Dir::Write), 2 * 64);
        assert_eq!(steps[9].bytes.total() - steps[8].bytes.total(), 10 * 64, "nothing else moves");
    }

    #[test]
    fn the_pre_engine_reads_previous_words_only_when_tables_are_reused() {
        let f = test_frame();
        assert!(f.reuses_tables(), "tile 1 reuses 2 entries");
        let l = ArtifactLayout::default();
        let reuse = pre_engine_lines(&f, &l, 3, 64);
        assert_eq!(reuse.previous.len(), 3, "the 3 visible Gaussians' previous words");
        assert_eq!(
            reuse.previous[2],
            l.pre_features[1] + 64,
            "Gaussian 3's word: bytes 96..128, the second line"
        );
        assert_eq!((reuse.params.len(), reuse.features.len(), reuse.lists.len()), (15, 4, 4));
        // A frame sorted from scratch reads no previous word; the rest is the same.
        let scratch = PocFrame { tiles: vec![f.tiles[0].clone(); 2], ..test_frame() };
        assert!(!scratch.reuses_tables());
        let fresh = pre_engine_lines(&scratch, &l, 3, 64);
        assert!(fresh.previous.is_empty());
        assert_eq!(PreEngineLines { previous: Vec::new(), ..reuse }, fresh);
        // SH degree 0: 12-byte records of ids 0, 1, 3 (bytes 0..12, 12..24, 36..48): a line each.
        assert_eq!(pre_engine_lines(&f, &l, 0, 64).params.len(), 6 + 3);
    }
}
