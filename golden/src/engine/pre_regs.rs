//! The Preprocessing Engine's control registers (docs/formats.md "Engine control registers"):
//! what the host programs so that the engine starts a frame from the baked scene and a camera
//! instead of from host-written incoming lists and feature words.
//!
//! With [`PRE_ENABLE`] set, a start first runs the Preprocessing Engine: its lanes read the
//! baked geometry and SH arrays (golden [`crate::hwpre::bake`]), write every Gaussian's feature
//! word at `FEAT_BASE` (double-buffered: the previous frame's words are read at
//! `PREV_FEAT_BASE` for incoming detection, unless [`PRE_FRESH`]), and write the tiles'
//! incoming lists (tile `t` at `LIST_BASE + 8 t list_stride`) and their lengths (into the
//! descriptors). The tile walk then starts. With [`PRE_ENABLE`] clear the walk starts at once,
//! on lists and feature words the host wrote.

use crate::camera::Camera;
use crate::hwpre::camera_registers;
use crate::hwpre::project::CameraIn;
use crate::hwpre::ShPrecision;
use serde::{Deserialize, Serialize};

/// `PRE_CTRL` bit 0: preprocess the scene before the tile walk.
pub const PRE_ENABLE: u32 = 1 << 0;
/// `PRE_CTRL` bit 1: no table is reused this frame: every (Gaussian, tile) is incoming and no
/// previous feature word is read (the frame's descriptors say `from_scratch`).
pub const PRE_FRESH: u32 = 1 << 1;
/// `PRE_CTRL` bit 2: the SH records hold binary16 coefficients (golden
/// [`ShPrecision::F16`]: two per word, the even one in the low half, each record padded to whole
/// words; the lanes widen them exactly); clear: binary32 ([`crate::engine::pre::sh_record_words`]).
pub const PRE_SH_HALF: u32 = 1 << 2;

/// Number of camera words.
pub const CAMERA_WORDS: usize = 23;

/// The camera words' names, in address order (the units' per-frame inputs are these names in
/// lower case with `_i`).
const CAMERA_NAMES: [&str; CAMERA_WORDS] = [
    "W2V_00",
    "W2V_01",
    "W2V_02",
    "W2V_10",
    "W2V_11",
    "W2V_12",
    "W2V_20",
    "W2V_21",
    "W2V_22",
    "T_X",
    "T_Y",
    "T_Z",
    "CAM_X",
    "CAM_Y",
    "CAM_Z",
    "FOCAL_X",
    "FOCAL_Y",
    "LIM_X",
    "LIM_Y",
    "PRINCIPAL_X",
    "PRINCIPAL_Y",
    "GRID_X",
    "GRID_Y",
];

/// Camera word `k` (f32 bits, but `GRID_X` and `GRID_Y`: integers), as golden
/// [`camera_registers`] computes it: the world-to-view rotation (row-major) and translation,
/// the camera centre, focal lengths, the Jacobian's clamp, the principal point, the tile grid.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct CameraWord(pub u8);

impl CameraWord {
    /// Every camera word, in address order.
    pub fn all() -> impl Iterator<Item = CameraWord> {
        (0..CAMERA_WORDS as u8).map(CameraWord)
    }

    /// The register's name (`W2V_00`, ..., `GRID_Y`).
    pub const fn name(self) -> &'static str {
        CAMERA_NAMES[self.0 as usize]
    }

    /// The per-frame input of the preprocessing units it drives (`w2v_00_i`, ...).
    pub fn port(self) -> String {
        format!("{}_i", self.name().to_ascii_lowercase())
    }

    /// Whether the word is an integer (the grid), not f32 bits.
    pub const fn is_integer(self) -> bool {
        self.0 as usize >= CAMERA_WORDS - 2
    }

    /// The words of `cam` for tiles of `tile` pixels, in address order.
    pub fn values(cam: &Camera, tile: u32) -> [u32; CAMERA_WORDS] {
        let (r, pos) = camera_registers(cam, tile);
        let mut f: Vec<f32> = r.w2v.iter().flatten().copied().collect();
        f.extend(r.translation);
        f.extend(pos);
        f.extend(r.focal);
        f.extend(r.lim);
        f.extend(r.principal);
        let mut v = [0u32; CAMERA_WORDS];
        for (slot, x) in v.iter_mut().zip(f) {
            *slot = x.to_bits();
        }
        v[CAMERA_WORDS - 2] = r.grid[0] as u32;
        v[CAMERA_WORDS - 1] = r.grid[1] as u32;
        v
    }

    /// The projection unit's camera inputs and the camera centre (the colour unit's) that the
    /// words `v` program: the inverse of [`CameraWord::values`].
    pub fn decode(v: &[u32; CAMERA_WORDS]) -> (CameraIn<f32, i32>, [f32; 3]) {
        let f = |k: usize| f32::from_bits(v[k]);
        let regs = CameraIn {
            w2v: [[f(0), f(1), f(2)], [f(3), f(4), f(5)], [f(6), f(7), f(8)]],
            translation: [f(9), f(10), f(11)],
            focal: [f(15), f(16)],
            lim: [f(17), f(18)],
            principal: [f(19), f(20)],
            grid: [v[CAMERA_WORDS - 2] as i32, v[CAMERA_WORDS - 1] as i32],
        };
        (regs, [f(12), f(13), f(14)])
    }
}

/// The Preprocessing Engine's registers of one frame ([`super::FrameRegs::pre`]); the default
/// is disabled (the host writes the lists and feature words).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct PreRegs {
    /// `PRE_CTRL` ([`PRE_ENABLE`], [`PRE_FRESH`], [`PRE_SH_HALF`]).
    pub ctrl: u32,
    /// Gaussians of the baked scene.
    pub gaussians: u32,
    /// SH degree of the baked scene (its records' precision: [`PRE_SH_HALF`]).
    pub sh_degree: u32,
    /// Geometry array base (bytes, 8-byte aligned).
    pub geo_base: u64,
    /// SH array base (bytes, 8-byte aligned).
    pub sh_base: u64,
    /// The previous frame's feature-table base (bytes, 32-byte aligned).
    pub prev_feat_base: u64,
    /// Incoming-list base (bytes, 64-byte aligned).
    pub list_base: u64,
    /// Camera words ([`CameraWord::values`]).
    pub camera: [u32; CAMERA_WORDS],
}

impl PreRegs {
    /// Whether the frame is preprocessed by the engine.
    pub fn enabled(&self) -> bool {
        self.ctrl & PRE_ENABLE != 0
    }

    /// Whether every (Gaussian, tile) is incoming.
    pub fn fresh(&self) -> bool {
        self.ctrl & PRE_FRESH != 0
    }

    /// The SH records' precision ([`PRE_SH_HALF`]).
    pub fn sh_precision(&self) -> ShPrecision {
        if self.ctrl & PRE_SH_HALF != 0 {
            ShPrecision::F16
        } else {
            ShPrecision::F32
        }
    }

    /// The `PRE_CTRL` bit of SH records of `precision`.
    pub fn sh_ctrl(precision: ShPrecision) -> u32 {
        match precision {
            ShPrecision::F32 => 0,
            ShPrecision::F16 => PRE_SH_HALF,
        }
    }

    /// The base registers with the alignment the engine needs: `(name, value, align, why)`.
    pub fn base_alignments(&self) -> [(&'static str, u64, u64, &'static str); 4] {
        [
            ("GEO_BASE", self.geo_base, 8, "geometry records are read in 8-byte beats from the base"),
            ("SH_BASE", self.sh_base, 8, "SH records are read in 8-byte beats from the base"),
            ("PREV_FEAT_BASE", self.prev_feat_base, 32, "a feature word is 32 bytes"),
            ("LIST_BASE", self.list_base, 64, "lists are written a 64-byte line at a time"),
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::{look_at_rotation, Camera};
    use glam::DVec3;

    #[test]
    fn camera_words_follow_camera_registers() {
        let position = DVec3::new(0.5, -1.0, 4.0);
        let cam = Camera {
            name: "test".into(),
            width: 320,
            height: 200,
            fx: 300.0,
            fy: 310.0,
            position,
            cam_to_world: look_at_rotation(position, DVec3::ZERO, DVec3::Y),
        };
        let (r, pos) = camera_registers(&cam, 64);
        let v = CameraWord::values(&cam, 64);
        assert_eq!(v[0], r.w2v[0][0].to_bits());
        assert_eq!(v[5], r.w2v[1][2].to_bits());
        assert_eq!(v[11], r.translation[2].to_bits());
        assert_eq!(v[12], pos[0].to_bits());
        assert_eq!(v[16], r.focal[1].to_bits());
        assert_eq!(v[17], r.lim[0].to_bits());
        assert_eq!(v[20], r.principal[1].to_bits());
        assert_eq!((v[21], v[22]), (5, 4), "a 320 x 200 image is 5 x 4 tiles of 64");
        assert_eq!(CameraWord(0).port(), "w2v_00_i");
        assert_eq!(CameraWord(19).port(), "principal_x_i");
        assert!(CameraWord(21).is_integer() && !CameraWord(20).is_integer());
        assert_eq!(CameraWord::all().count(), CAMERA_WORDS);
        let (back, back_pos) = CameraWord::decode(&v);
        assert_eq!(back_pos, pos);
        assert_eq!((back.w2v, back.translation, back.focal), (r.w2v, r.translation, r.focal));
        assert_eq!((back.lim, back.principal, back.grid), (r.lim, r.principal, r.grid));
    }
}
