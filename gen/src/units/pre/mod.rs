//! The Preprocessing Engine's units, emitted from golden's dataflow graphs
//! ([`neo_golden::hwpre`]) by the datapath emitter ([`datapath`]) with the primitives of
//! [`library`].

pub mod datapath;
pub mod dup;
pub mod engine;
pub mod fetch;
pub mod fifo;
pub mod known_bits;
pub mod lane;
pub mod library;
pub mod lists;
pub mod ram;
pub mod writer;

use crate::emit::Module;
use datapath::Datapath;
use library::PreLibrary;
use neo_golden::engine::EngineConfig;
use neo_golden::hwpre::color::color_graph;
use neo_golden::hwpre::project::{project_graph, ProjectParams};

/// Module name of the colour unit.
pub const COLOR_NAME: &str = "neo_pre_color";

/// The colour unit: SH colour of degree 0 to 3 (the degree a per-frame input), `+0.5`,
/// clamped and quantised to the feature format's colour field (golden
/// `hwpre::color::color_graph`).
pub fn color_module(cfg: &EngineConfig) -> Module {
    let graph = color_graph(&cfg.feature_format().color);
    Datapath::new(&graph, &PreLibrary).module(
        COLOR_NAME,
        &["Colour unit (paper Section 5.2): view-dependent colour from spherical harmonics of degree 0 to 3,".into(),
          "+0.5, clamped at 0 and quantised to the feature entry's colour format; golden hwpre::color.".into()],
    )
}

/// The colour unit's per-frame input contracts ([`known_bits::InputContract`]): the SH degree
/// is 0 to 3.
pub fn color_contracts() -> Vec<known_bits::InputContract> {
    vec![known_bits::InputContract {
        input: "degree".into(),
        range: Some((0, 3)),
        mask: 0,
        value: 0,
        finite: false,
        why: "the SH degree is 0 to 3".into(),
    }]
}

/// The projection unit's per-frame input contracts ([`known_bits::InputContract`]), as the
/// host derives the registers from a camera (golden `hwpre::camera_registers`):
/// - the tile grid fits the `tile_bits`-bit tile indices: 1 to `2^tile_bits - 1` tiles per axis;
/// - focal lengths and FOV limits are positive and finite;
/// - the principal point is the image centre `(W - 1) / 2`, a multiple of 1/2 below `2^15` for
///   images of at most 65536 pixels, so at most 16 significant bits: the low 8 fraction bits are
///   zero, and it is non-negative;
/// - the rotation terms are those of an orthonormal matrix: `|w| <= 1`, so the exponent's top
///   bit (bit 30) is zero.
pub fn project_contracts(cfg: &EngineConfig) -> Vec<known_bits::InputContract> {
    let c = |input: String, range: Option<(i64, i64)>, mask: u32, finite: bool, why: &str| {
        known_bits::InputContract { input, range, mask, value: 0, finite, why: why.into() }
    };
    let max_grid = (1i64 << cfg.tile_bits.min(31)) - 1;
    let mut out = Vec::new();
    for a in ["x", "y"] {
        let grid_why =
            format!("the tile grid fits the {}-bit tile indices (1 to {max_grid} tiles)", cfg.tile_bits);
        out.push(c(format!("grid_{a}"), Some((1, max_grid)), 0, false, &grid_why));
        out.push(c(format!("focal_{a}"), None, 1 << 31, true, "focal lengths are positive and finite"));
        out.push(c(format!("lim_{a}"), None, 1 << 31, true, "FOV limits are positive and finite"));
        out.push(c(
            format!("principal_{a}"),
            None,
            1 << 31 | 0xFF,
            true,
            "the principal point is the image centre (W - 1) / 2 of an image of at most 65536 pixels: non-negative, at most 16 significant bits",
        ));
    }
    for r in 0..3 {
        for col in 0..3 {
            out.push(c(
                format!("w2v_{r}{col}"),
                None,
                1 << 30,
                true,
                "a rotation term of an orthonormal matrix: |w| <= 1, exponent bit 30 zero",
            ));
        }
    }
    out
}

/// Module name of the projection unit.
pub const PROJECT_NAME: &str = "neo_pre_project";

/// The projection unit's parameters for `cfg`: the feature format and the tile size.
pub fn project_params(cfg: &EngineConfig) -> ProjectParams {
    ProjectParams { feature: cfg.feature_format(), tile: cfg.tile }
}

/// The projection unit: view transform, culling, EWA 2D covariance, conic, radius, tile
/// rectangle, depth key and the feature entry's geometry fields (golden
/// `hwpre::project::project_graph`).
pub fn project_module(cfg: &EngineConfig) -> Module {
    let graph = project_graph(&project_params(cfg));
    Datapath::new(&graph, &PreLibrary).module(
        PROJECT_NAME,
        &[
            "Projection unit (paper Section 5.2): view transform, near-plane and frustum culling, EWA 2D covariance"
                .into(),
            "with the +0.3 dilation, conic, radius, tile rectangle, FP16 depth key and the feature entry's mean,"
                .into(),
            "conic, opacity, ITU axis and extents; golden hwpre::project.".into(),
        ],
    )
}

/// An instance `name` of `module` (the parametric queue or memory) at `WIDTH = width` and
/// `DEPTH = depth`, with connections `conns` (`(port, expression)`).
fn sized_instance(
    module: &str,
    (width, depth): (u32, u32),
    name: &str,
    conns: Vec<(String, String)>,
) -> crate::emit::Item {
    crate::emit::Item::Instance(crate::emit::Instance {
        module: module.into(),
        name: name.into(),
        params: vec![("WIDTH".into(), width.to_string()), ("DEPTH".into(), depth.to_string())],
        conns,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use neo_golden::hwarith::graph::Trace;
    use neo_golden::hwarith::Arith;

    /// A graph of inline operations only: `out = max(a, b) < c ? i + 1 : i`.
    fn small_graph() -> neo_golden::hwarith::graph::Graph {
        let mut t = Trace::new();
        let a = t.input_f("a", false);
        let b = t.input_f("b", false);
        let c = t.input_f("c", true);
        let i = t.input_i("i", false);
        let m = t.max(a, b);
        let lt = t.lt(m, c);
        let one = t.ilit(1);
        let inc = t.iadd(i, one);
        let inc = t.name_i(inc, "inc");
        let r = t.iselect(lt, inc, i);
        t.output_i("r", r);
        t.output_b("lt", lt);
        t.finish()
    }

    #[test]
    fn operands_are_delayed_to_their_users_and_outputs_aligned() {
        let g = small_graph();
        let d = Datapath::new(&g, &PreLibrary);
        // max (1) -> lt (2) -> select (3); i + 1 is ready at 1 and waits 1 cycle.
        assert_eq!(d.depth(), 3);
        let v = d.module("t", &[]).to_verilog();
        // The integer input waits two cycles for the select, the increment one. Nets carry
        // the input's, the program's or the output's name, else the operation's.
        assert!(v.contains("assign n3_i_d2 = n3_i_dly_q[63:32];"), "{v}");
        assert!(v.contains("n7_inc_q <= n3_i + n6_lit;"), "{v}");
        assert!(v.contains("reg  [31:0] n8_r_q;"), "{v}");
        assert!(v.contains("n4_max_q"), "{v}");
    }

    #[test]
    fn the_inline_logic_lints_clean() {
        if !crate::tools::require_for_test("verilator", "the_inline_logic_lints_clean") {
            return;
        }
        let g = small_graph();
        let mut m = Datapath::new(&g, &PreLibrary).module("neo_pre_small", &[]);
        m.config_hash = Some(0);
        let files = crate::units::files_for_module(&EngineConfig::default(), &m);
        let vlt = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../hdl/lint.vlt");
        crate::tools::verilator_lint(&files, "neo_pre_small", Some(&vlt)).unwrap();
    }
}
