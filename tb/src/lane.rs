//! The preprocessing lane's bench (`neo_pre_lane` against golden `hwpre::preprocess_one`): the
//! baked scene sits in an [`AxiMemory`] of two ports (the lane's `ma_axi_*` and `mb_axi_*`),
//! the driver programs a camera and starts the lane, [`AxiChecker`]s watch both ports, and the
//! checker compares the feature table the lane wrote, word by word, with golden's feature words
//! (`engine::memory::feature_to_bytes`), stopping at the first mismatch with both entries
//! decoded. The words just outside the lane's range must keep their canary.

use crate::axi::{AxiBinding, AxiChecker, AxiMemory, AxiTiming, ManagerSignals, SubordinateSignals};
use crate::check::Checker;
use crate::dynmodel::DynModel;
use crate::rng::Rng;
use neo_gen::units::pre::lane::NAME;
use neo_gen::EngineConfig;
use neo_golden::camera::Camera;
use neo_golden::engine::memory::{feature_from_bytes, feature_to_bytes, Memory, FEATURE_BYTES};
use neo_golden::engine::pre::{pack_sh_record, sh_record_words};
use neo_golden::engine::{CameraWord, CAMERA_WORDS};
use neo_golden::formats::FeatureEntry;
use neo_golden::hwpre::bake::{geometry_bytes, Baked, ShPrecision};
use neo_golden::hwpre::duplicate::{incoming, TouchRecord};
use neo_golden::hwpre::project::ProjectParams;
use neo_golden::hwpre::{camera_registers, preprocess_one};
use neo_golden::sort::DepthKeyCodec;

/// Byte address of the geometry array, the SH array and the feature table in the bench memory.
pub const GEO_BASE: u64 = 0x0100_0000;
/// Byte address of the SH array.
pub const SH_BASE: u64 = 0x0400_0000;
/// Byte address of the feature table.
pub const FEAT_BASE: u64 = 0x0800_0000;
/// Byte address of the previous frame's feature table.
pub const PREV_BASE: u64 = 0x0c00_0000;
/// What the words around the lane's range hold (they must keep it).
const CANARY: u8 = 0xa5;

/// Where a lane run's arrays sit in the 32-bit address space, and the id of baked Gaussian 0
/// (the lane's ids are `id0 + k`): every address the lane forms wraps modulo 2^32, as the
/// RTL's 32-bit sums do, so the bench memory is written and read modulo 2^32 too.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LanePlacement {
    /// Id of baked Gaussian 0.
    pub id0: u32,
    /// `geo_base_i`: byte address of the range's first geometry record (4-byte aligned).
    pub geo: u32,
    /// `sh_base_i`: byte address of id 0's SH record (4-byte aligned).
    pub sh: u32,
    /// `feat_base_i`: byte address of id 0's feature word (32-byte aligned).
    pub feat: u32,
    /// `prev_base_i`: byte address of id 0's previous feature word (32-byte aligned).
    pub prev: u32,
}

impl LanePlacement {
    /// The fixed map: ids are baked indices, the arrays at [`GEO_BASE`] etc.
    pub fn fixed(range: LaneRange) -> LanePlacement {
        let gb = u64::from(geometry_bytes());
        LanePlacement {
            id0: 0,
            geo: (GEO_BASE + gb * u64::from(range.first)) as u32,
            sh: SH_BASE as u32,
            feat: FEAT_BASE as u32,
            prev: PREV_BASE as u32,
        }
    }

    /// Two placements for a lane running `range` (at most `max_count` Gaussians from
    /// `range.first`), each the bitwise complement of the other in every bit above the
    /// alignment (`first_i` over 31 bits), so that alternating them toggles every base and id
    /// bit; drawn until the arrays of each (feature words with their canaries) do not overlap.
    pub fn complement_pair(rng: &mut Rng, range: LaneRange, max_count: u32) -> [LanePlacement; 2] {
        const ID_MASK: u64 = (1 << 31) - 1;
        loop {
            let (geo, sh, feat, prev) = (
                complement_bases(rng.next_u64(), 4),
                complement_bases(rng.next_u64(), 4),
                complement_bases(rng.next_u64(), 32),
                complement_bases(rng.next_u64(), 32),
            );
            let r = rng.next_u64() & ID_MASK;
            let first = [r, !r & ID_MASK];
            // first_i + count stays below 2^31 (31-bit ids), id0 = first_i - range.first >= 0.
            let room = u64::from(range.first) + u64::from(max_count) + 1;
            if first.iter().any(|&f| f < room || f + room > ID_MASK) {
                continue;
            }
            let places: Vec<LanePlacement> = (0..2)
                .map(|k| LanePlacement {
                    id0: (first[k] - u64::from(range.first)) as u32,
                    geo: geo[k] as u32,
                    sh: sh[k] as u32,
                    feat: feat[k] as u32,
                    prev: prev[k] as u32,
                })
                .collect();
            if places.iter().all(|p| p.disjoint(range, max_count)) {
                return [places[0], places[1]];
            }
        }
    }

    /// Whether the arrays of `range` (up to `max_count` Gaussians, degree-3 SH records) are
    /// disjoint modulo 2^32.
    fn disjoint(&self, range: LaneRange, max_count: u32) -> bool {
        let n = u64::from(max_count) + 2;
        let first = u64::from(self.id0) + u64::from(range.first);
        let regions = [
            (u64::from(self.geo), u64::from(geometry_bytes()) * n),
            (u64::from(self.sh) + 4 * 48 * first, 4 * 48 * n),
            (u64::from(self.feat) + FEATURE_BYTES * (first.wrapping_sub(1)), FEATURE_BYTES * (n + 1)),
            (u64::from(self.prev) + FEATURE_BYTES * first, FEATURE_BYTES * n),
        ];
        let ring = |x: u64| x & 0xffff_ffff;
        regions.iter().enumerate().all(|(i, a)| {
            regions[i + 1..]
                .iter()
                .all(|b| ring(b.0.wrapping_sub(a.0)) >= a.1 && ring(a.0.wrapping_sub(b.0)) >= b.1)
        })
    }

    /// Byte address of id `id`'s feature word.
    fn feat_at(&self, id: u64) -> u64 {
        (u64::from(self.feat) + FEATURE_BYTES * id) & 0xffff_ffff
    }

    /// Id `id`'s feature word in `mem`.
    fn feature_word(&self, mem: &Memory, id: u64) -> [u8; 32] {
        let mut b = [0u8; FEATURE_BYTES as usize];
        read_wrapped(mem, self.feat_at(id), &mut b);
        b
    }

    /// The ids of the feature words just outside `range`, where the canaries go.
    fn canary_ids(&self, range: LaneRange) -> [u64; 2] {
        let first = u64::from(self.id0) + u64::from(range.first);
        [first.wrapping_sub(1), first + u64::from(range.count)]
    }

    /// Writes the canaries around `range`'s feature words.
    fn write_canaries(&self, mem: &mut Memory, range: LaneRange) {
        for id in self.canary_ids(range) {
            write_wrapped(mem, self.feat_at(id), &[CANARY; FEATURE_BYTES as usize]);
        }
    }

    /// Checks that the canaries around `range`'s feature words are intact.
    fn check_canaries(&self, mem: &Memory, range: LaneRange, check: &Checker, cycle: u64) {
        for id in self.canary_ids(range) {
            let intact = self.feature_word(mem, id) == [CANARY; FEATURE_BYTES as usize];
            check.value(
                cycle,
                &format!("canary word of id {id} outside the lane's range"),
                1,
                u64::from(intact),
            );
        }
    }
}

/// Two 32-bit base addresses aligned to `align` (a power of two), from the random bits `r`, each
/// the bitwise complement of the other above the alignment: alternating them makes every such
/// base bit rise and fall.
pub fn complement_bases(r: u64, align: u64) -> [u64; 2] {
    let keep = 0xffff_ffff & !(align - 1);
    [r & keep, !r & keep]
}

/// Writes `data` at `addr` modulo 2^32 (a write past the top wraps to address 0).
pub fn write_wrapped(mem: &mut Memory, addr: u64, data: &[u8]) {
    let a = addr & 0xffff_ffff;
    let head = data.len().min((0x1_0000_0000 - a) as usize);
    mem.write(a, &data[..head]);
    if head < data.len() {
        mem.write(0, &data[head..]);
    }
}

/// Reads `out.len()` bytes at `addr` modulo 2^32.
pub fn read_wrapped(mem: &Memory, addr: u64, out: &mut [u8]) {
    let a = addr & 0xffff_ffff;
    let head = out.len().min((0x1_0000_0000 - a) as usize);
    mem.read(a, &mut out[..head]);
    if head < out.len() {
        mem.read(0, &mut out[head..]);
    }
}

/// The signed unit axis nearest to `c` (not axis `not`), and its index.
fn snap_axis(c: [f64; 3], not: Option<usize>) -> ([f64; 3], usize) {
    let k = (0..3)
        .filter(|&k| Some(k) != not)
        .max_by(|&a, &b| c[a].abs().total_cmp(&c[b].abs()))
        .expect("an axis");
    let mut u = [0.0; 3];
    u[k] = c[k].signum();
    (u, k)
}

/// The camera of frame `f` of a per-frame-input sweep from `base` (its position kept): a
/// random orientation (rolled, so the w2v words of the camera's x and y axes take every sign
/// and size, and turned up to 45 degrees) except on frames 1 and 4 of every five, the nearest
/// axis-aligned one (w2v words exactly 0 and 1; [`sweep_world`] turns them into two patterns);
/// a random focal length (short on the strips); and a resolution whose tile grid runs x through
/// 10, 1013, 10, 1, 10 and y through 8, 1, 8, 1015, 8 (10-bit complements: every bit of the
/// 10-bit tile indices rises and falls) with at most 2048 tiles (`pre_max_tiles`), the other
/// side of a huge grid one tile.
pub fn sweep_camera(base: &Camera, tile: u32, f: usize, rng: &mut Rng) -> Camera {
    let gx = [10u32, 1013, 10, 1, 10][f % 5];
    let gy = [8u32, 1, 8, 1015, 8][f % 5];
    let size = |g: u32, rng: &mut Rng| g * tile - rng.below(u64::from(tile)) as u32;
    let (width, height) = (size(gx, rng), size(gy, rng));
    // A strip of tiles at a short focal length: its Gaussians touch few tiles (cheap frames).
    let (lo, hi) = if f % 5 % 2 == 1 { (60, 300) } else { (200, 2000) };
    let focal = rng.range(lo, hi) as f64 + rng.below(1000) as f64 / 1000.0;
    let aspect = 0.8 + rng.below(400) as f64 / 1000.0;
    let mut m = base.cam_to_world;
    if f % 5 == 4 || f % 5 == 1 {
        // The axis-aligned rotation nearest to base's: forward snapped to its largest world
        // axis, right to the largest of the others, down = forward x right.
        let (zc, xc) = ([m.z_axis.x, m.z_axis.y, m.z_axis.z], [m.x_axis.x, m.x_axis.y, m.x_axis.z]);
        let (z, kz) = snap_axis(zc, None);
        let (x, _) = snap_axis(xc, Some(kz));
        (m.z_axis.x, m.z_axis.y, m.z_axis.z) = (z[0], z[1], z[2]);
        (m.x_axis.x, m.x_axis.y, m.x_axis.z) = (x[0], x[1], x[2]);
        m.y_axis = m.z_axis.cross(m.x_axis);
    } else {
        // Roll about the view axis, then a turn of up to 45 degrees about a random axis.
        let (s, c) = (rng.below(1_000_000) as f64 * std::f64::consts::TAU / 1e6).sin_cos();
        let (x, y) = (m.x_axis, m.y_axis);
        (m.x_axis, m.y_axis) = (x * c + y * s, y * c - x * s);
        let mut k = m.z_axis;
        let mut u = || rng.below(2_000_001) as f64 / 1e6 - 1.0;
        (k.x, k.y, k.z) = (u(), u(), u() + 1e-3);
        let k = k.normalize();
        let (s, c) = (u() * std::f64::consts::FRAC_PI_4).sin_cos();
        for col in [&mut m.x_axis, &mut m.y_axis, &mut m.z_axis] {
            let v = *col;
            *col = v * c + k.cross(v) * s + k * (k.dot(v) * (1.0 - c));
        }
    }
    let cam_to_world = m;
    Camera { width, height, fx: focal, fy: focal * aspect, cam_to_world, ..base.clone() }
}

/// Frame `f` of a sweep ([`sweep_camera`]'s `cam`) in a moved world: the scene and the camera
/// turned by one signed permutation of the world axes and shifted by one vector, so the view
/// is the same (up to f32 rounding of the moved means) while the per-frame inputs change: the
/// camera sits at a new position whose coordinates have either sign and a random 23-bit
/// mantissa, of magnitude 1/8 to 1/4 on even frames and 16 to 32 on odd ones (every exponent
/// bit of the camera position rises and falls, and the translation's with it); the axis-aligned
/// cameras become the identity (frame 4 of five) or a cyclic permutation of the axes (frame 1:
/// zero w2v terms where frame 4 has ones), the others turn by a random one. When `near` is
/// given, that Gaussian is moved half a unit in front of the camera and made huge (sigma 15):
/// a depth below 2 (key bit 14 clear) and a splat over the whole image (the largest extents and
/// conic exponents).
pub fn sweep_world(
    baked: &Baked,
    cam: &Camera,
    f: usize,
    near: Option<usize>,
    rng: &mut Rng,
) -> (Baked, Camera) {
    use glam::{DMat3, DVec3};
    let r = cam.cam_to_world;
    let perm = |p: [usize; 3], s: [f64; 3]| {
        let col = |k: usize| {
            let mut v = DVec3::ZERO;
            v[p[k]] = s[k];
            v
        };
        DMat3::from_cols(col(0), col(1), col(2))
    };
    let q = match f % 5 {
        4 => DMat3::IDENTITY * r.transpose(),
        1 => perm([1, 2, 0], [1.0; 3]) * r.transpose(),
        _ => {
            const PERMS: [[usize; 3]; 6] = [[0, 1, 2], [0, 2, 1], [1, 0, 2], [1, 2, 0], [2, 0, 1], [2, 1, 0]];
            let mut s = [(); 3].map(|_| if rng.percent(50) { -1.0 } else { 1.0 });
            let p = *rng.pick(&PERMS);
            if perm(p, s).determinant() < 0.0 {
                // A rotation, not a reflection.
                s[2] = -s[2];
            }
            perm(p, s)
        }
    };
    let mag = if f.is_multiple_of(2) { 0.125 } else { 16.0 };
    let coord = |rng: &mut Rng| {
        let m = mag * (1.0 + rng.below(1 << 23) as f64 / f64::from(1u32 << 23));
        if rng.percent(50) {
            -m
        } else {
            m
        }
    };
    let position = DVec3::new(coord(rng), coord(rng), coord(rng));
    let cam_to_world = q * r;
    let shift = position - q * cam.position;
    let mut out = baked.clone();
    for g in &mut out.geometry {
        let p = DVec3::new(g.position[0].into(), g.position[1].into(), g.position[2].into());
        let p = q * p + shift;
        g.position = [p.x as f32, p.y as f32, p.z as f32];
        let [xx, xy, xz, yy, yz, zz] = g.cov3d.map(f64::from);
        let c = q
            * DMat3::from_cols(DVec3::new(xx, xy, xz), DVec3::new(xy, yy, yz), DVec3::new(xz, yz, zz))
            * q.transpose();
        g.cov3d = [c.x_axis.x, c.x_axis.y, c.x_axis.z, c.y_axis.y, c.y_axis.z, c.z_axis.z].map(|v| v as f32);
    }
    if let Some(i) = near {
        let g = &mut out.geometry[i];
        let p = position + cam_to_world.z_axis * 0.5;
        g.position = [p.x as f32, p.y as f32, p.z as f32];
        g.cov3d = [225.0, 0.0, 0.0, 225.0, 0.0, 225.0];
    }
    (out, Camera { position, cam_to_world, ..cam.clone() })
}

/// The feature entries golden gives the visible Gaussians of `range` of `baked` for `cam`.
pub fn visible_entries(
    cfg: &EngineConfig,
    baked: &Baked,
    cam: &Camera,
    range: LaneRange,
) -> Vec<FeatureEntry> {
    let (regs, pos) = camera_registers(cam, cfg.tile);
    let params = ProjectParams { feature: cfg.feature_format(), tile: cfg.tile };
    (range.first..range.first + range.count)
        .filter_map(|i| preprocess_one(baked, &regs, pos, &params, &DepthKeyCodec::Fp16, i as usize))
        .map(|h| h.entry)
        .collect()
}

/// Of the visible Gaussians of `range` for `cam`: (depths below 2, depths of at least 2), the
/// FP16 depth key's bit 14 clear and set.
pub fn depth_split(cfg: &EngineConfig, baked: &Baked, cam: &Camera, range: LaneRange) -> (usize, usize) {
    let entries = visible_entries(cfg, baked, cam, range);
    let far = entries.iter().filter(|e| e.depth_key >= 0x4000).count();
    (entries.len() - far, far)
}

/// `cam` moved back along its view axis by a quarter unit times each of `steps`: the one whose
/// visible Gaussians of `range` fall most evenly on both sides of depth 2 ([`depth_split`]).
pub fn camera_straddling_depth_2(
    cfg: &EngineConfig,
    baked: &Baked,
    cam: &Camera,
    range: LaneRange,
    steps: std::ops::RangeInclusive<i32>,
) -> Camera {
    steps
        .map(|k| {
            let mut c = cam.clone();
            c.position -= c.cam_to_world.z_axis * (0.25 * f64::from(k));
            c
        })
        .max_by_key(|c| {
            let (near, far) = depth_split(cfg, baked, c, range);
            near.min(far)
        })
        .expect("at least one step")
}

/// A synthetic scene (`synthetic:blobs`, `gaussians`, `seed`, SH `degree`) baked for `cfg`'s
/// feature format with SH records of `precision`, and `frames` cameras of a fast walk through it
/// (cameras inside the scene, so some Gaussians are culled): the lane and Preprocessing Engine
/// benches' scenes.
pub fn walk_scene(
    cfg: &EngineConfig,
    (gaussians, seed): (usize, u64),
    frames: usize,
    degree: u8,
    precision: ShPrecision,
) -> (Baked, Vec<Camera>) {
    let spec = format!("synthetic:blobs?gaussians={gaussians}&seed={seed}&sh={degree}");
    let (scene, _) = neo_golden::source::load_scene(&spec, false).expect("synthetic scene");
    let baked = Baked::from_scene(&scene, &cfg.feature_format(), precision);
    let bounds = neo_golden::source::robust_bounds(&scene);
    let traj = neo_golden::trajectory::parse_trajectory("walk:res=640x480,speed=20", bounds, frames)
        .expect("walk trajectory");
    (baked, traj.frames)
}

/// The Gaussians a lane run covers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LaneRange {
    /// First Gaussian.
    pub first: u32,
    /// Gaussians.
    pub count: u32,
}

/// One frame of a lane run.
#[derive(Clone, Debug)]
pub struct LaneFrame<'a> {
    /// The camera.
    pub cam: &'a Camera,
    /// No table reused: every Gaussian incoming, no previous word read.
    pub all_fresh: bool,
    /// The previous frame's feature words of the range (ignored when `all_fresh`).
    pub prev: &'a [[u8; 32]],
}

/// One incoming (Gaussian, tile) the lane reports.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LaneHit {
    /// Tile column and row.
    pub tile: [u32; 2],
    /// Gaussian id.
    pub id: u32,
    /// Depth key.
    pub key: u32,
}

/// What a run measured.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct LaneRun {
    /// Gaussians checked, and those of them visible.
    pub gaussians: u64,
    /// Visible Gaussians.
    pub visible: u64,
    /// Incoming hits checked.
    pub hits: u64,
    /// Cycles from the start to `busy_o` falling.
    pub cycles: u64,
    /// The feature words the lane wrote (the next frame's previous words).
    pub table: Vec<[u8; 32]>,
}

/// A Verilated `neo_pre_lane`.
pub struct LaneBench {
    cfg: EngineConfig,
    model: DynModel,
    ports: [AxiBinding; 2],
    start: usize,
    busy: usize,
    hit: [usize; 6],
}

impl LaneBench {
    /// Builds (or loads from the cache) the lane of `cfg`.
    pub fn build(cfg: &EngineConfig) -> Result<Self, String> {
        let (files, vlt) = crate::dynmodel::generated_files(cfg, NAME)?;
        let iface = neo_gen::units::pre::lane::module(cfg).interface();
        let (model, _) = DynModel::build_for_short_runs(&iface, &files, Some(&vlt), None)?;
        let ports = [AxiBinding::bind(&model, "ma_axi_", true)?, AxiBinding::bind(&model, "mb_axi_", true)?];
        let (start, busy) = (model.port("start_i")?, model.port("busy_o")?);
        let q = |n: &str| model.port(&format!("hit_{n}"));
        let hit = [q("valid_o")?, q("ready_i")?, q("tile_x_o")?, q("tile_y_o")?, q("id_o")?, q("key_o")?];
        Ok(LaneBench { cfg: cfg.clone(), model, ports, start, busy, hit })
    }

    /// The model, for waves.
    pub fn model_mut(&mut self) -> &mut DynModel {
        &mut self.model
    }

    /// Programs the per-frame inputs of `cam` for `baked` and `range`.
    fn program(
        &mut self,
        baked: &Baked,
        cam: &Camera,
        all_fresh: bool,
        range: LaneRange,
        place: &LanePlacement,
    ) -> Result<(), String> {
        let words = CameraWord::values(cam, self.cfg.tile);
        self.program_words(&words, (baked.sh_degree, baked.sh_precision), all_fresh, range, place)
    }

    /// Programs the per-frame inputs: the camera words `words` as they are (any bits, in
    /// [`CameraWord`] order), SH `degree` and records' `precision`, `all_fresh`, `range` at
    /// `place`.
    fn program_words(
        &mut self,
        words: &[u32; CAMERA_WORDS],
        (degree, precision): (u8, ShPrecision),
        all_fresh: bool,
        range: LaneRange,
        place: &LanePlacement,
    ) -> Result<(), String> {
        let mut all: Vec<(String, u64)> =
            CameraWord::all().map(|c| (c.port(), u64::from(words[c.0 as usize]))).collect();
        all.push(("degree_i".into(), u64::from(degree)));
        all.push(("geo_base_i".into(), u64::from(place.geo)));
        all.push(("sh_base_i".into(), u64::from(place.sh)));
        all.push(("sh_words_i".into(), u64::from(sh_record_words(degree, precision))));
        all.push(("sh_half_i".into(), u64::from(precision == ShPrecision::F16)));
        all.push(("feat_base_i".into(), u64::from(place.feat)));
        all.push(("prev_base_i".into(), u64::from(place.prev)));
        all.push(("all_fresh_i".into(), u64::from(all_fresh)));
        all.push(("first_i".into(), u64::from(place.id0 + range.first)));
        all.push(("count_i".into(), u64::from(range.count)));
        for (name, v) in all {
            let p = self.model.port(&name)?;
            self.model.set_u64(p, v);
        }
        Ok(())
    }

    /// Runs the lane over no Gaussian (`count_i` 0 from `first`, at `place`, SH `degree`) with
    /// the camera words `words` as they are: any bits at all (the complement of a real frame's
    /// words, say), since an empty range must do nothing whatever its per-frame inputs hold.
    /// Checks, every cycle, that neither port issues a read or a write and no hit is offered,
    /// and that `busy_o` falls within 2000 cycles (the budget of a run of 0 Gaussians); the
    /// memory (canaries around `first`) must be left as it was. Returns the cycles.
    pub fn run_empty(
        &mut self,
        words: &[u32; CAMERA_WORDS],
        degree: u8,
        first: u32,
        place: &LanePlacement,
        check: &Checker,
    ) -> u64 {
        let mut rng = Rng::new(check.seed);
        let range = LaneRange { first, count: 0 };
        let mut mem = Memory::new();
        place.write_canaries(&mut mem, range);
        let mut mem = AxiMemory::new(2, mem, AxiTiming::RANDOM, rng.next_u64());
        self.program_words(words, (degree, ShPrecision::F32), false, range, place)
            .unwrap_or_else(|e| panic!("{NAME}: {e}"));
        let mut chk = self.reset_for_run();
        let start = self.model.cycle();
        let (mut first_cycle, mut rose) = (true, false);
        loop {
            let subs = self.drive_cycle(&mem, first_cycle, rng.percent(50));
            let cyc = self.model.cycle();
            let busy = self.model.get_u64(self.busy) == 1;
            rose |= busy;
            check.protocol(cyc, self.model.get_u64(self.hit[0]) == 0, "an empty range offers no hit");
            for (k, man) in self.observe_ports(&mut mem, &mut chk, &subs, check, cyc).iter().enumerate() {
                check.protocol(
                    cyc,
                    man.ar.is_none() && man.aw.is_none() && man.w.is_none(),
                    &format!("port {k}: an empty range neither reads nor writes"),
                );
            }
            self.model.tick();
            if !first_cycle && !busy {
                break;
            }
            first_cycle = false;
            check.protocol(cyc, cyc - start < 2_000, "the lane finishes an empty range within 2000 cycles");
        }
        let cycles = self.model.cycle() - start;
        check.value(cycles, "busy_o rose after start_i", 1, u64::from(rose));
        place.check_canaries(mem.memory(), range, check, cycles);
        cycles
    }

    /// One cycle's inputs: `start_i`, the hit port's ready, both ports' subordinate signals from
    /// `mem` (returned, for the protocol checkers); then evaluates.
    fn drive_cycle(&mut self, mem: &AxiMemory, start: bool, hit_ready: bool) -> [SubordinateSignals; 2] {
        self.model.set_u64(self.start, u64::from(start));
        self.model.set_u64(self.hit[1], u64::from(hit_ready));
        let subs = [mem.outputs(0), mem.outputs(1)];
        for (p, s) in self.ports.iter().zip(&subs) {
            p.set_subordinate(&mut self.model, s);
        }
        self.model.eval();
        subs
    }

    /// The ports' half of a cycle at `cyc`: each manager's signals checked by its protocol
    /// checker against the subordinate signals `subs` and handed to `mem`; returned.
    fn observe_ports(
        &self,
        mem: &mut AxiMemory,
        chk: &mut [AxiChecker; 2],
        subs: &[SubordinateSignals; 2],
        check: &Checker,
        cyc: u64,
    ) -> [ManagerSignals; 2] {
        [0, 1].map(|k| {
            let man = self.ports[k].get_manager(&self.model);
            if let Err(v) = chk[k].observe(&man, &subs[k]) {
                check.fail(cyc, "AXI protocol", "no violation", &v.to_string());
            }
            mem.tick(k, &man);
            man
        })
    }

    /// Drives both ports idle, resets the lane (keeping its programmed registers) and returns
    /// the two ports' protocol checkers.
    fn reset_for_run(&mut self) -> [AxiChecker; 2] {
        for p in &self.ports {
            p.set_subordinate(&mut self.model, &SubordinateSignals::default());
        }
        self.model.set_u64(self.start, 0);
        self.model.reset();
        let (ro, wo) = (self.cfg.pre_outstanding, self.cfg.axi_outstanding);
        [AxiChecker::new(0, "ma_axi", ro, wo), AxiChecker::new(1, "mb_axi", ro, wo)]
    }

    /// Runs the lane over `range` of `baked` for `frame` with memory `timing`, taking hits
    /// `ready_percent` of the cycles, and checks the feature table and the incoming hits it
    /// leaves against golden. Stops the test at the first mismatch.
    pub fn run(
        &mut self,
        baked: &Baked,
        frame: &LaneFrame,
        range: LaneRange,
        pace: (AxiTiming, u32),
        check: &Checker,
    ) -> LaneRun {
        self.run_at(baked, frame, range, &LanePlacement::fixed(range), pace, check)
    }

    /// [`LaneBench::run`] with the arrays and ids of `place`.
    pub fn run_at(
        &mut self,
        baked: &Baked,
        frame: &LaneFrame,
        range: LaneRange,
        place: &LanePlacement,
        (timing, ready_percent): (AxiTiming, u32),
        check: &Checker,
    ) -> LaneRun {
        let mut rng = Rng::new(check.seed);
        let mem = placed_memory(baked, range, frame.prev, place);
        let mut mem = AxiMemory::new(2, mem, timing, rng.next_u64());
        self.program(baked, frame.cam, frame.all_fresh, range, place)
            .unwrap_or_else(|e| panic!("{NAME}: {e}"));
        let mut chk = self.reset_for_run();
        let want_hits = expected_hits_at(&self.cfg, baked, frame, range, place.id0);
        let start = self.model.cycle();
        let limit = 2_000 + 200 * u64::from(range.count) + 4 * want_hits.len() as u64;
        let (mut first, mut hits) = (true, 0usize);
        loop {
            let ready = rng.percent(ready_percent);
            let subs = self.drive_cycle(&mem, first, ready);
            let cyc = self.model.cycle();
            let busy = self.model.get_u64(self.busy) == 1;
            if ready && self.model.get_u64(self.hit[0]) == 1 {
                self.check_hit(check, cyc, want_hits.get(hits), hits);
                hits += 1;
            }
            self.observe_ports(&mut mem, &mut chk, &subs, check, cyc);
            self.model.tick();
            if !first && !busy {
                break;
            }
            first = false;
            check.protocol(cyc, cyc - start < limit, "the lane finishes within its cycle budget");
        }
        let cycles = self.model.cycle() - start;
        check.value(cycles, "incoming hits", want_hits.len() as u64, hits as u64);
        for (k, c) in chk.iter().enumerate() {
            let (r, w) = c.in_flight();
            check.value(
                cycles,
                &format!("port {k}: AXI transactions open after busy_o fell"),
                0,
                (r + w) as u64,
            );
        }
        let visible = check_words_at(&self.cfg, baked, frame.cam, range, place, mem.memory(), check, cycles);
        let table = (range.first..range.first + range.count)
            .map(|i| place.feature_word(mem.memory(), u64::from(place.id0 + i)))
            .collect();
        LaneRun { gaussians: u64::from(range.count), visible, hits: hits as u64, cycles, table }
    }

    /// Checks the offered hit (the `k`-th) against golden's `want`.
    fn check_hit(&self, check: &Checker, cyc: u64, want: Option<&LaneHit>, k: usize) {
        let m = &self.model;
        let got = LaneHit {
            tile: [m.get_u64(self.hit[2]) as u32, m.get_u64(self.hit[3]) as u32],
            id: m.get_u64(self.hit[4]) as u32,
            key: m.get_u64(self.hit[5]) as u32,
        };
        let Some(want) = want else {
            check.fail(cyc, &format!("hit {k}"), "no more hits", &format!("{got:?}"))
        };
        if got != *want {
            check.fail(cyc, &format!("hit {k} (tile, id, key)"), &format!("{want:x?}"), &format!("{got:x?}"));
        }
    }
}

/// The incoming hits of `range` in the lane's order (Gaussians in index order, each one's tiles
/// row-major): golden `hwpre::duplicate::incoming` with the previous entries of `frame`.
pub fn expected_hits(cfg: &EngineConfig, baked: &Baked, frame: &LaneFrame, range: LaneRange) -> Vec<LaneHit> {
    expected_hits_at(cfg, baked, frame, range, 0)
}

/// [`expected_hits`] with baked Gaussian `k`'s id `id0 + k`.
pub fn expected_hits_at(
    cfg: &EngineConfig,
    baked: &Baked,
    frame: &LaneFrame,
    range: LaneRange,
    id0: u32,
) -> Vec<LaneHit> {
    let (fmt, r) = (cfg.feature_format(), cfg.raster_config());
    let (regs, cam_pos) = camera_registers(frame.cam, cfg.tile);
    let params = ProjectParams { feature: fmt, tile: cfg.tile };
    let size = (regs.grid[0] as u32 * cfg.tile, regs.grid[1] as u32 * cfg.tile);
    let mut out = Vec::new();
    for i in range.first..range.first + range.count {
        let Some(now) = preprocess_one(baked, &regs, cam_pos, &params, &DepthKeyCodec::Fp16, i as usize)
        else {
            continue;
        };
        let prev_entry = if frame.all_fresh {
            None
        } else {
            feature_from_bytes(&fmt, &frame.prev[(i - range.first) as usize])
        };
        let prev = TouchRecord { entry: prev_entry.as_ref() };
        for h in incoming(&now.entry, prev, &fmt, &r, size, |_, _| frame.all_fresh) {
            if h.incoming {
                out.push(LaneHit { tile: [h.tile_x, h.tile_y], id: id0 + i, key: now.entry.depth_key });
            }
        }
    }
    out
}

/// The bench memory of a lane run at `place`: the geometry records of `range` from
/// `place.geo`, their SH records and previous feature words (when given) at their ids'
/// addresses, canaries in the feature words just outside the range, every address modulo 2^32.
pub fn placed_memory(baked: &Baked, range: LaneRange, prev: &[[u8; 32]], place: &LanePlacement) -> Memory {
    let mut mem = Memory::new();
    let sb = 4 * u64::from(sh_record_words(baked.sh_degree, baked.sh_precision));
    let (gb, first) = (u64::from(geometry_bytes()), u64::from(place.id0) + u64::from(range.first));
    for (j, k) in (range.first..range.first + range.count).enumerate() {
        let g: Vec<u8> = baked.geometry[k as usize].to_le_bytes().into_iter().collect();
        write_wrapped(&mut mem, u64::from(place.geo) + gb * j as u64, &g);
        let id = first + j as u64;
        let record = pack_sh_record(baked.sh_of(k as usize), baked.sh_precision);
        let sh: Vec<u8> = record.iter().flat_map(|w| w.to_le_bytes()).collect();
        write_wrapped(&mut mem, u64::from(place.sh) + sb * id, &sh);
        if let Some(w) = prev.get(j) {
            write_wrapped(&mut mem, u64::from(place.prev) + FEATURE_BYTES * id, w);
        }
    }
    place.write_canaries(&mut mem, range);
    mem
}

/// Checks the feature words of `range` at `place` (baked Gaussian `k`'s word at id
/// `place.id0 + k`) and the canaries around them; returns the visible count.
#[allow(clippy::too_many_arguments)]
pub fn check_words_at(
    cfg: &EngineConfig,
    baked: &Baked,
    cam: &Camera,
    range: LaneRange,
    place: &LanePlacement,
    mem: &Memory,
    check: &Checker,
    cycle: u64,
) -> u64 {
    let fmt = cfg.feature_format();
    let (regs, cam_pos) = camera_registers(cam, cfg.tile);
    let params = ProjectParams { feature: fmt, tile: cfg.tile };
    let id0 = u64::from(place.id0);
    let mut visible = 0;
    for i in range.first..range.first + range.count {
        let want = preprocess_one(baked, &regs, cam_pos, &params, &DepthKeyCodec::Fp16, i as usize);
        visible += u64::from(want.is_some());
        let want_bytes = feature_to_bytes(&fmt, want.as_ref().map(|h| &h.entry));
        let got = place.feature_word(mem, id0 + u64::from(i));
        if got != want_bytes {
            let show = |b: &[u8; 32]| format!("{:?} (0x{})", feature_from_bytes(&fmt, b), hex(b));
            check.fail(
                cycle,
                &format!("feature word of Gaussian {i} (id {})", id0 + u64::from(i)),
                &show(&want_bytes),
                &show(&got),
            );
        }
    }
    place.check_canaries(mem, range, check, cycle);
    visible
}

fn hex(b: &[u8; 32]) -> String {
    b.iter().rev().map(|x| format!("{x:02x}")).collect()
}
