//! Where everything lives in DRAM: one region per data set, each rounded up to whole MiB, the
//! double-buffered ones (per frame parity) twice.

use neo_golden::engine::memory::{DESCRIPTOR_BYTES, ENTRY_BYTES, FEATURE_BYTES};
use neo_golden::hwpre::bake::{geometry_bytes, sh_bytes, ShPrecision};

use crate::config::SimConfig;
use crate::workload::Workload;

const MB: u64 = 1 << 20;

/// A region of `bytes` at `*next`, which moves on by the region rounded up to whole MiB.
fn region(next: &mut u64, bytes: u64) -> u64 {
    let base = *next;
    *next += bytes.div_ceil(MB).max(1) * MB;
    base
}

/// Where everything lives in DRAM.
#[derive(Clone, Debug)]
pub(super) struct Layout {
    pub(super) geometry: u64,
    pub(super) sh: u64,
    /// The feature tables (double-buffered): Neo's one golden feature word per Gaussian id
    /// (`neo_golden::engine::memory::FEATURE_BYTES`), a GSCore-style compacted table of the
    /// visible Gaussians' entries.
    pub(super) features: [u64; 2],
    /// The incoming lists (double-buffered): Neo's a slot of `list_stride` golden entries per
    /// tile (the engine's `LIST_BASE` layout), GSCore's packed.
    pub(super) lists: [u64; 2],
    /// The tile descriptors (the Preprocessing Engine writes each tile's `list_len` there).
    pub(super) descriptors: u64,
    /// Entries from one tile's incoming-list slot to the next (Neo).
    pub(super) list_stride: u64,
    pub(super) bg_lists: [u64; 2],
    pub(super) tables: [u64; 2],
    pub(super) bg_tables: [u64; 2],
    pub(super) slot: u64,
    pub(super) scratch: u64,
    pub(super) scratch_part: u64,
    pub(super) framebuffer: u64,
}

impl Layout {
    /// The address map for `wl` on `cfg` with sort entries of `eb` bytes, feature entries of `fb`
    /// bytes and `sort_cores` sorting cores (three scratch buffers each).
    pub(super) fn new(cfg: &SimConfig, wl: &Workload, eb: u64, fb: u64, sort_cores: u32) -> Self {
        let list_stride = cfg.engine.list_stride() as u64;
        let max_table = wl.max_table_len().max(wl.max_sort_len()) as u64;
        let max_sort = wl.max_sort_len() as u64;
        let tiles = wl.info.grid[0] as u64 * wl.info.grid[1] as u64;
        let max_visible = wl.frames.iter().map(|f| f.visible).max().unwrap_or(0);
        let max_lists = wl
            .frames
            .iter()
            .map(|f| f.tiles.iter().map(|t| t.current.max(t.sort_n) as u64).sum::<u64>())
            .max()
            .unwrap_or(0);
        let slot = (max_table * eb).div_ceil(4096).max(1) * 4096;
        let scratch_part = (max_sort.max(max_table) * eb).div_ceil(4096).max(1) * 4096;
        let g = wl.info.gaussians;
        let geometry = (geometry_bytes() as u64).max(cfg.sizes.geometry_bytes(&wl.info));
        let sh = (sh_bytes(wl.info.sh_degree, ShPrecision::F32) as u64).max(cfg.sizes.sh_bytes(&wl.info));
        let features = (g * FEATURE_BYTES.max(fb)).max(max_visible * fb);
        let lists = (tiles * list_stride * ENTRY_BYTES).max(max_lists * eb);
        let mut next = 0;
        Layout {
            geometry: region(&mut next, g * geometry),
            sh: region(&mut next, g * sh),
            features: [region(&mut next, features), region(&mut next, features)],
            lists: [region(&mut next, lists), region(&mut next, lists)],
            bg_lists: [region(&mut next, max_lists * eb), region(&mut next, max_lists * eb)],
            tables: [region(&mut next, tiles * slot), region(&mut next, tiles * slot)],
            bg_tables: [region(&mut next, tiles * slot), region(&mut next, tiles * slot)],
            slot,
            scratch: region(&mut next, sort_cores as u64 * 3 * scratch_part),
            scratch_part,
            framebuffer: region(
                &mut next,
                wl.info.width as u64 * wl.info.height as u64 * cfg.sizes.pixel_bytes as u64,
            ),
            descriptors: region(&mut next, tiles * DESCRIPTOR_BYTES),
            list_stride,
        }
    }

    /// The three scratch buffers of the sorting core on engine agent `agent` (agent 0 is the
    /// preprocessing engine).
    pub(super) fn scratch(&self, agent: usize) -> [u64; 3] {
        let core = agent.saturating_sub(1) as u64;
        let base = self.scratch + core * 3 * self.scratch_part;
        [base, base + self.scratch_part, base + 2 * self.scratch_part]
    }

    /// Neo's incoming list of tile `t` of frame `f` (its slot).
    pub(super) fn list_slot(&self, f: usize, t: usize) -> u64 {
        self.lists[f % 2] + ENTRY_BYTES * self.list_stride * t as u64
    }

    /// The sorted table of tile `t` of frame `f`.
    pub(super) fn table(&self, f: usize, t: usize) -> u64 {
        self.tables[f % 2] + t as u64 * self.slot
    }
}
