//! Scene mode of the host session ([`HostMode::Scene`]): the memory map with the baked scene,
//! two feature arenas and fixed-stride lists and tables, the Preprocessing Engine's registers,
//! and what the frame must leave besides the tile walk's outputs (from the PIPELINE: its
//! feature words, its incoming lists).

use super::{
    address_top, EngineSession, Expected, HostMode, MemoryLayout, Regions, SceneLayout, SessionError,
};
use crate::camera::Camera;
use crate::engine::expected::PreExpected;
use crate::engine::memory::{feature_to_bytes, feature_word_bits, Memory, TileDescriptor, ENTRY_BYTES};
use crate::engine::pre::{pre_traffic, sh_array_bytes, sh_record_words};
use crate::engine::regs::{CameraWord, Counter, FrameRegs, PreRegs, PRE_ENABLE, PRE_FRESH};
use crate::engine::EngineConfig;
use crate::hwpre::bake::{geometry_bytes, Baked, ShPrecision};
use crate::pipeline::FrameOutput;
use crate::sort::SortEntry;

/// What the host leaves in a descriptor's `list_len` (the engine must overwrite it).
pub const LIST_LEN_CANARY: u32 = 0xA5A5_A5A5;

impl MemoryLayout {
    /// The scene-mode map (4 KiB-aligned regions, in this order): descriptors, results, frame
    /// buffer, the two feature arenas, sort scratch, the two table arenas (`table_capacity`
    /// entries per tile), geometry records, SH records of degree `sh_degree` in `sh_precision`
    /// (golden [`sh_record_words`]), incoming lists (`list_stride` entries per tile). Refuses more
    /// tiles than `pre_max_tiles`.
    pub fn for_scene(
        cfg: &EngineConfig,
        tiles: u64,
        gaussians: u64,
        (sh_degree, sh_precision): (u8, ShPrecision),
    ) -> Result<MemoryLayout, SessionError> {
        if tiles > cfg.pre_max_tiles as u64 {
            return Err(SessionError::Layout(format!(
                "{tiles} tiles exceed pre_max_tiles {} (the list writer's tile count)",
                cfg.pre_max_tiles
            )));
        }
        let cap = cfg.table_capacity as u64;
        let mut regions = Regions::new();
        let f = regions.frame(cfg, tiles, gaussians, 2);
        let (desc_base, result_base, fb_base, scratch_base, table_bases) =
            (f.desc_base, f.result_base, f.fb_base, f.scratch_base, f.table_bases);
        let feat_bases = [f.feat_bases[0], f.feat_bases[1]];
        let geo_base = regions.take(gaussians * geometry_bytes() as u64);
        let sh_base = regions.take(gaussians * 4 * sh_record_words(sh_degree, sh_precision) as u64);
        let list_bytes = tiles * cfg.list_stride() as u64 * ENTRY_BYTES;
        let list_base = regions.take(list_bytes);
        let top = address_top(cfg);
        if list_base + list_bytes > top {
            return Err(SessionError::Layout(format!(
                "{tiles} tiles, {gaussians} Gaussians and table_capacity {cap} need 0x{:x} bytes, above \
                 the 0x{top:x} the address widths reach",
                list_base + list_bytes
            )));
        }
        Ok(MemoryLayout {
            desc_base,
            result_base,
            fb_base,
            feat_base: feat_bases[0],
            scratch_base,
            table_bases,
            list_base,
            list_bytes,
            scene: Some(SceneLayout { geo_base, sh_base, feat_bases }),
        })
    }
}

impl EngineSession<'_> {
    /// The baked scene (binary32 or binary16 SH: the engine reads either).
    fn baked(&self) -> Result<&Baked, SessionError> {
        self.pipeline.baked().ok_or_else(|| {
            SessionError::Inconsistent("scene mode needs the pipeline's hardware preprocessing".into())
        })
    }

    /// Frame `f`'s registers in scene mode (`cut`: from scratch, [`PRE_FRESH`]).
    pub(super) fn scene_regs(&self, s: &SceneLayout, f: usize, cam: &Camera, cut: bool) -> FrameRegs {
        let l = &self.layout;
        let baked = self.pipeline.baked();
        let sh_degree = baked.map_or(0, |b| b.sh_degree as u32);
        let sh_ctrl = baked.map_or(0, |b| PreRegs::sh_ctrl(b.sh_precision));
        FrameRegs {
            frame: f as u32,
            tiles: self.prev.len() as u32,
            width: cam.width,
            height: cam.height,
            desc_base: l.desc_base,
            result_base: l.result_base,
            feat_base: s.feat_bases[f % 2],
            fb_base: l.fb_base,
            scratch_base: l.scratch_base,
            pre: PreRegs {
                ctrl: PRE_ENABLE | sh_ctrl | if cut { PRE_FRESH } else { 0 },
                gaussians: self.gaussians as u32,
                sh_degree,
                geo_base: s.geo_base,
                sh_base: s.sh_base,
                prev_feat_base: s.feat_bases[(f + 1) % 2],
                list_base: l.list_base,
                camera: CameraWord::values(cam, self.cfg.tile),
            },
            adapt: Default::default(),
        }
    }

    /// Writes the baked scene (once) and frame `f`'s descriptors (`list_len` a canary), and
    /// returns what the frame must leave; `lists` are the tiles' incoming lists.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn scene_frame(
        &mut self,
        mem: &mut Memory,
        regs: FrameRegs,
        f: usize,
        cut: bool,
        lists: Vec<Vec<SortEntry>>,
        prev_tables: &[Vec<SortEntry>],
        out: &FrameOutput,
    ) -> Result<Expected, SessionError> {
        debug_assert_eq!(self.mode, HostMode::Scene);
        if !self.scene_written {
            let b = self.baked()?;
            let geo: Vec<u8> = b.geometry.iter().flat_map(|g| g.to_le_bytes()).collect();
            mem.write(regs.pre.geo_base, &geo);
            mem.write(regs.pre.sh_base, &sh_array_bytes(b));
            self.scene_written = true;
        }
        let cap = self.cfg.table_capacity as u64;
        let stride = self.cfg.list_stride() as u64;
        let gx = self.pipeline.grid()[0] as usize;
        let next_base = self.layout.table_bases[f % 2] / ENTRY_BYTES;
        let descriptors: Vec<TileDescriptor> = lists
            .iter()
            .enumerate()
            .map(|(t, list)| {
                let prev = if cut { Default::default() } else { self.prev[t] };
                Ok(TileDescriptor {
                    tile_x: (t % gx) as u16,
                    tile_y: (t / gx) as u16,
                    from_scratch: cut,
                    prev: prev.addr as u32,
                    prev_len: prev.len,
                    list: (crate::engine::pre::list_addr(&self.cfg, regs.pre.list_base, t as u64)
                        / ENTRY_BYTES) as u32,
                    list_len: list.len() as u32,
                    next: (next_base + t as u64 * cap) as u32,
                    dps_passes: super::dps_passes(out, t)?,
                    dps_wide: out.tiles.dps_wide[t] == 1,
                })
            })
            .collect::<Result<_, SessionError>>()?;
        for (t, d) in descriptors.iter().enumerate() {
            mem.write_descriptor(
                regs.desc_base,
                t as u64,
                &TileDescriptor { list_len: LIST_LEN_CANARY, ..super::as_written(&regs, d) },
            );
        }
        let mut e = self.expected(mem, regs, descriptors, prev_tables, out);
        let ffmt = self.cfg.feature_format();
        let features: Vec<[u8; 32]> =
            (0..self.gaussians as u32).map(|i| feature_to_bytes(&ffmt, self.pipeline.feature(i))).collect();
        let visible: Vec<u64> =
            (0..self.gaussians as u64).filter(|&i| self.pipeline.feature(i as u32).is_some()).collect();
        let (rd, wr) = pre_traffic(&self.cfg, &regs, &visible, lists.iter().map(Vec::len));
        e.outcome.counters.add(Counter::RdPre, rd);
        e.outcome.counters.add(Counter::WrPre, wr);
        e.pre = Some(PreExpected {
            features,
            lists,
            list_base: regs.pre.list_base,
            list_stride: stride,
            capacity: cap,
            present_bit: feature_word_bits(&ffmt) - 1,
        });
        Ok(e)
    }
}
