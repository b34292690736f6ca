//! The whole-frame cosimulation cases (issue 11): each is a trajectory, a resolution and an
//! engine configuration derived from the caller's, for an [`EngineSession`] of a scene.
//!
//! | case | what it exercises |
//! | --- | --- |
//! | `orbit` | reuse frame after frame (DPS, insert, delete) |
//! | `cut` | a scene cut at frame 1: every table from scratch, then reused |
//! | `turn` | the camera orbits 180 degrees per frame with no cut: reuse across a full change of view and back |
//! | `edge_tiles` | a resolution that is not a multiple of the tile, far camera: partial and empty tiles |
//! | `overflow` | a small `table_capacity`: some tiles overflow (reported, nothing else written), the next frame from scratch |
//! | `one_core` | one sorting core and one raster core: every tile on the same cores |
//! | `many_cores` | one tile, more cores (3 + 2) than busy tiles |
//! | `adaptive` | the orbit 4x faster, sorted by `adaptive:wide=1,resort=0`: per-tile DPS passes (1 to 4) from the descriptors |
//! | `adaptive_resort` | the orbit 16x faster, `adaptive:wide=1,resort=1,max=2,budget=1000`: passes and single tiles re-sorted from scratch in reuse frames (lists mode only) |
//! | `adaptive_wide` | the orbit 16x faster on an engine with a wide DPS chunk (`dps_wide` 4), `adaptive:wide=4,resort=0`: per-tile DPS passes in chunks or wide chunks from the descriptors |
//! | `adaptive_engine_wide` | the `adaptive_wide` orbit, engine and strategy, planned by the frame controller (`ADAPT_CTRL` with its wide bit) |
//! | `adaptive_engine` | the `adaptive` orbit and strategy, planned by the frame controller from the previous frame's results ([`Planner::Engine`]; `ADAPT_CTRL`) |
//! | `window` | the `adaptive_engine` orbit (4x faster) and strategy, planned by the frame controller, on an engine whose raster cores have a reorder window of [`WINDOW_CASE`] entries (`raster_window`): tiles blended and written back in the window's order (issue 14's adaptive strategy with the window) |

use super::host::{pipeline_for, EngineSession, HostMode, Planner, SessionError, SessionOptions};
use super::EngineConfig;
use crate::pipeline::adaptive::AdaptiveParams;
use crate::pipeline::{Preprocessing, Strategy};
use crate::scene::Scene;
use crate::source::robust_bounds;
use crate::trajectory::{parse_trajectory, Trajectory};

/// A whole-frame case.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum EngineCase {
    /// Orbit, reuse every frame.
    Orbit,
    /// A cut at frame 1.
    Cut,
    /// 180 degrees per frame, no cut.
    Turn,
    /// Partial and empty tiles.
    EdgeTiles,
    /// Tiles longer than the table capacity.
    Overflow,
    /// One sorting core, one raster core.
    OneCore,
    /// More cores than busy tiles.
    ManyCores,
    /// A fast orbit with per-tile DPS passes (`adaptive` without the wide chunk or the re-sort).
    Adaptive,
    /// A faster orbit with per-tile DPS passes and re-sorts of single tiles (`adaptive` with
    /// `resort=1`, without the wide chunk): a re-sorted tile's descriptor says from scratch and
    /// its list is the tile's whole list (lists mode only).
    AdaptiveResort,
    /// [`EngineCase::Adaptive`] planned by the frame controller itself ([`Planner::Engine`]).
    AdaptiveEngine,
    /// A faster orbit with per-tile DPS passes, some in the wide chunk (`adaptive` with
    /// `wide` = [`WIDE_CASE`], `resort=0`), on an engine whose `dps_wide` is that.
    AdaptiveWide,
    /// [`EngineCase::AdaptiveWide`] planned by the frame controller itself ([`Planner::Engine`]).
    AdaptiveEngineWide,
    /// [`EngineCase::AdaptiveEngine`] on an engine whose raster cores reorder through a window
    /// of [`WINDOW_CASE`] entries (`raster_window`).
    Window,
}

/// The reorder window of the `window` case's raster cores: a quarter of a 256-entry segment, so
/// the CI scenes' tables (hundreds of entries) go through it several times over.
pub const WINDOW_CASE: usize = 64;

/// The wide chunk (a multiple of the chunk) of the `adaptive_wide` case: four chunks, so the
/// CI scenes' tables span one to a few wide chunks and the odd parity's first chunk (`2 C`)
/// differs from a chunk.
pub const WIDE_CASE: u32 = 4;

/// How to film a scene for the cases: orbit keys (`radius`, `height`, `target`, `fov`; no
/// `start`, `rate`, `speed`, `frames`, `res` or `cut`, which the cases set), the same for a
/// camera far enough that border tiles are empty, and the speed multiplier.
#[derive(Clone, Debug, PartialEq)]
pub struct CaseScene {
    /// Keys of the orbit.
    pub orbit: String,
    /// Keys of the far orbit (`edge_tiles`).
    pub far_orbit: String,
    /// Speed multiplier of the orbit (frame to frame motion).
    pub speed: f64,
}

impl CaseScene {
    /// The biker scene (`../shared/scenes/biker.ply`), framed as the raster-core bench frames it.
    pub fn biker() -> CaseScene {
        CaseScene {
            orbit: "radius=5,height=0,target=0/-1.6/0,fov=56.145".into(),
            far_orbit: "radius=14,height=0,target=0/-1.6/0,fov=56.145".into(),
            speed: 4.0,
        }
    }

    /// A synthetic scene at its default framing: [`CaseScene::SYNTHETIC`] (a box of random
    /// Gaussians: the far orbit leaves border tiles empty).
    pub fn synthetic() -> CaseScene {
        CaseScene { orbit: String::new(), far_orbit: "radius=60".into(), speed: 4.0 }
    }

    /// The synthetic scene [`CaseScene::synthetic`] is made for (20000 Gaussians).
    pub const SYNTHETIC: &'static str = "synthetic:blobs?gaussians=20000&seed=3";

    /// A sparse synthetic scene for [`CaseScene::synthetic`]'s framing: 8 Gaussians (large ones:
    /// the blobs scale with the spacing), so at 256x256 every one of the 16 tiles holds 2 to 8
    /// entries, orbit frames reuse them with empty incoming lists and turn frames with lists of 1
    /// to 4 entries. Each stage of a tile then writes no more entries than a sort bridge may have
    /// in flight (`axi_outstanding` = 8), so the next stage's first reads hit its last writes.
    pub const SPARSE: &'static str = "synthetic:blobs?gaussians=8&seed=3";
}

impl EngineCase {
    /// Every case.
    pub const ALL: [EngineCase; 13] = [
        EngineCase::Orbit,
        EngineCase::Cut,
        EngineCase::Turn,
        EngineCase::EdgeTiles,
        EngineCase::Overflow,
        EngineCase::OneCore,
        EngineCase::ManyCores,
        EngineCase::Adaptive,
        EngineCase::AdaptiveResort,
        EngineCase::AdaptiveEngine,
        EngineCase::AdaptiveWide,
        EngineCase::AdaptiveEngineWide,
        EngineCase::Window,
    ];

    /// The case's name.
    pub fn name(self) -> &'static str {
        match self {
            EngineCase::Orbit => "orbit",
            EngineCase::Cut => "cut",
            EngineCase::Turn => "turn",
            EngineCase::EdgeTiles => "edge_tiles",
            EngineCase::Overflow => "overflow",
            EngineCase::OneCore => "one_core",
            EngineCase::ManyCores => "many_cores",
            EngineCase::Adaptive => "adaptive",
            EngineCase::AdaptiveResort => "adaptive_resort",
            EngineCase::AdaptiveEngine => "adaptive_engine",
            EngineCase::AdaptiveWide => "adaptive_wide",
            EngineCase::AdaptiveEngineWide => "adaptive_engine_wide",
            EngineCase::Window => "window",
        }
    }

    /// The sorting strategy of the case's pipeline (the host's per-tile DPS passes follow it).
    pub fn strategy(self) -> Strategy {
        match self {
            EngineCase::Adaptive | EngineCase::AdaptiveEngine | EngineCase::Window => {
                Strategy::Adaptive(AdaptiveParams { resort: false, wide: 1, ..AdaptiveParams::default() })
            }
            // At most 2 passes and the whole budget: a tile whose reach asks for a third pass is
            // re-sorted.
            EngineCase::AdaptiveResort => {
                Strategy::Adaptive(AdaptiveParams { resort: true, wide: 1, max_passes: 2, budget: 1000 })
            }
            EngineCase::AdaptiveWide | EngineCase::AdaptiveEngineWide => Strategy::Adaptive(AdaptiveParams {
                resort: false,
                wide: WIDE_CASE,
                ..AdaptiveParams::default()
            }),
            _ => Strategy::Neo,
        }
    }

    /// Who plans the case's DPS passes.
    pub fn planner(self) -> Planner {
        match self {
            EngineCase::AdaptiveEngine | EngineCase::AdaptiveEngineWide | EngineCase::Window => {
                Planner::Engine
            }
            _ => Planner::Host,
        }
    }

    /// The session options of the case in `mode` (its strategy and planner).
    pub fn options(self, mode: HostMode) -> SessionOptions {
        SessionOptions {
            mode,
            strategy: self.strategy(),
            planner: self.planner(),
            ..SessionOptions::default()
        }
    }

    /// The case's trajectory of `frames` frames at about `res` (`[width, height]`) and its engine
    /// configuration derived from `base`.
    pub fn setup(
        self,
        scene: &Scene,
        how: &CaseScene,
        frames: usize,
        res: [u32; 2],
        base: &EngineConfig,
    ) -> Result<(Trajectory, EngineConfig), SessionError> {
        let mut cfg = base.clone();
        let mut keys = how.orbit.clone();
        let mut extra = format!("speed={}", how.speed);
        let mut res = res;
        match self {
            EngineCase::Orbit => {}
            EngineCase::Cut => extra.push_str(",cut=1"),
            EngineCase::Turn => extra = "rate=5400".into(),
            EngineCase::EdgeTiles => {
                keys = how.far_orbit.clone();
                res = [res[0].saturating_sub(27).max(8), res[1].saturating_sub(53).max(8)];
            }
            EngineCase::Overflow => {}
            EngineCase::OneCore => (cfg.sort_cores, cfg.raster_cores) = (1, 1),
            EngineCase::ManyCores => {
                res = [64, 64];
                (cfg.sort_cores, cfg.raster_cores) = (3, 2);
            }
            EngineCase::Adaptive | EngineCase::AdaptiveEngine => extra = format!("speed={}", 4.0 * how.speed),
            EngineCase::AdaptiveResort => extra = format!("speed={}", RESORT_SPEED * how.speed),
            EngineCase::AdaptiveWide | EngineCase::AdaptiveEngineWide => {
                extra = format!("speed={}", RESORT_SPEED * how.speed);
                cfg.dps_wide = WIDE_CASE as usize;
            }
            EngineCase::Window => {
                extra = format!("speed={}", 4.0 * how.speed);
                cfg.raster_window = WINDOW_CASE;
            }
        }
        let sep = if keys.is_empty() { "" } else { "," };
        let spec = format!("orbit:{keys}{sep}start=0,{extra},frames={frames},res={}x{}", res[0], res[1]);
        let traj = parse_trajectory(&spec, robust_bounds(scene), frames)
            .map_err(|e| SessionError::Trajectory(format!("case {}: {e}", self.name())))?;
        if self == EngineCase::Overflow {
            cfg.table_capacity = overflow_capacity(scene, &traj, &cfg)?;
        }
        cfg.validate()?;
        Ok((traj, cfg))
    }

    /// [`EngineCase::setup`] and the session.
    pub fn session<'s>(
        self,
        scene: &'s Scene,
        how: &CaseScene,
        frames: usize,
        res: [u32; 2],
        base: &EngineConfig,
    ) -> Result<EngineSession<'s>, SessionError> {
        let (traj, cfg) = self.setup(scene, how, frames, res, base)?;
        EngineSession::with_options(scene, traj, &cfg, self.options(HostMode::Lists))
    }
}

/// The `adaptive_resort` case's orbit speed, as a multiple of the scene's: fast enough that
/// some tiles' write-back reach asks for more passes than `max` (a re-sort) and others for
/// passes (measured on the synthetic scene and biker).
const RESORT_SPEED: f64 = 16.0;

/// A table capacity that some tiles of the first frame exceed but not all: the median of the
/// tiles' list lengths (every tile is sorted from scratch in frame 0), at least the chunk.
fn overflow_capacity(scene: &Scene, traj: &Trajectory, cfg: &EngineConfig) -> Result<usize, SessionError> {
    let cam = traj.frames.first().ok_or(SessionError::NoFrames)?;
    let mut p = pipeline_for(scene, cfg, (cam.width, cam.height), Strategy::Neo, Preprocessing::DEFAULT_SH)?;
    p.render_frame(cam, 0, true);
    let mut lens: Vec<usize> = p.current_lists().map(|l| l.len()).collect();
    lens.sort_unstable();
    let cap = lens[(lens.len() - 1) / 2].max(cfg.chunk);
    if cap >= lens[lens.len() - 1] {
        return Err(SessionError::Trajectory(format!(
            "case overflow: no capacity >= chunk {} lets some tiles of {lens:?} overflow but not all",
            cfg.chunk
        )));
    }
    Ok(cap)
}
