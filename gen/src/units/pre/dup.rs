//! `neo_pre_dup`: the duplication unit (paper Section 5.2), bit-exact with golden
//! [`neo_golden::hwpre::duplicate::incoming`]: for each visible Gaussian, every tile it enters
//! (row-major over its candidate rectangle, one tile tested per cycle) with its incoming flag.
//!
//! # Ports
//! - per frame: `grid_x_i`, `grid_y_i` (tile grid), `all_fresh_i` (no table is reused: every
//!   Gaussian is incoming, e.g. a frame sorted from scratch);
//! - `in_*`: one Gaussian: `id`, depth `key`, this frame's ITU fields (`mean`, `geom`, as
//!   [`crate::units::itu`]) and the previous frame's (`prev_mean`, `prev_geom`) with
//!   `prev_visible` (its visibility bit; the fields are ignored when 0);
//! - `out_*`: one tile entered: `tile_x`, `tile_y`, `id`, `key`, `incoming`.
//!
//! # Structure
//! 1. On acceptance, the candidate rectangle (golden `raster::candidate_tiles`: the AABB
//!    `mean +- extent_xy` in tiles, clamped to the grid; the whole grid on an unbounded extent;
//!    one `neo_pre_dup_range` per axis, `g_axis[a].u_range`) is registered with the Gaussian.
//! 2. The walker offers one tile per cycle to two `neo_itu` instances in lockstep: `u_itu_now`
//!    tests this frame's entry, `u_itu_prev` the previous frame's.
//! 3. A sideband pipeline (`sb_q`, `sb_q2`, ...) as deep as the ITU and advancing with it
//!    carries each test's tile, id, key and visibility bit to the ITU outputs.
//! 4. A test that misses is dropped; a hit goes out with `incoming = all_fresh_i |
//!    ~(prev_visible & hit_prev)`.
//!
//! A Gaussian with `k` candidate tiles occupies the walker `max(k, 1)` cycles: the next one is
//! accepted in the cycle its last tile is offered. `idle_o`: the walker is free and no test is in
//! the ITUs (every hit of the Gaussians taken so far has left).

use super::super::itu::{self, geom_bits_lsb, mean_bits};
use crate::emit::expr::lit;
use crate::emit::{conns, if_, if_else, set, Instance, Item, Module};
use neo_golden::engine::EngineConfig;

/// Module name.
pub const NAME: &str = "neo_pre_dup";
/// The per-axis candidate range, [`range_module`].
pub const RANGE_NAME: &str = "neo_pre_dup_range";

/// Widths of the unit.
struct Dims {
    /// Tile index bits and the ITU's tag bits (its tag is unused: the sideband pipeline
    /// carries the test's context).
    tb: u32,
    tg: u32,
    /// Id and key bits.
    ib: u32,
    kb: u32,
    /// `mean_i` and `geom_i` bits; one mean field's and one extent field's bits.
    mb: u32,
    gb: u32,
    m1: u32,
    eb: u32,
    /// Signed width of the rectangle arithmetic.
    w: u32,
    /// `G = mean.frac + 1` and the extent shift `G - extent.frac`.
    g: u32,
    eshift: u32,
    /// Subtiles per tile (the ITU bitmap's width).
    nb: u32,
    /// `log2(tile)`.
    log2t: u32,
    /// The raw extent that means unbounded.
    unb: u64,
}

impl Dims {
    fn new(cfg: &EngineConfig) -> Self {
        let fmt = cfg.feature_format();
        let g = fmt.mean.frac as u32 + 1;
        let eshift = g.checked_sub(fmt.extent.frac as u32).expect("extent.frac <= mean.frac + 1");
        let (m1, eb) = (fmt.mean.bits as u32, fmt.extent.bits as u32);
        Dims {
            tb: cfg.tile_bits,
            tg: cfg.itu_tag_bits,
            ib: cfg.id_bits as u32,
            kb: cfg.key_bits as u32,
            mb: mean_bits(cfg),
            gb: geom_bits_lsb(cfg).0,
            m1,
            eb,
            w: (m1 + 1).max(eb + eshift) + 3,
            g,
            eshift,
            log2t: cfg.tile.trailing_zeros(),
            nb: cfg.raster_config().subtiles_per_tile(),
            unb: fmt.unbounded_extent() as u64,
        }
    }
}

/// The duplication unit for `cfg`.
pub fn module(cfg: &EngineConfig) -> Module {
    let d = Dims::new(cfg);
    let mut m = Module::new(NAME);
    m.doc("Duplication unit (paper Section 5.2): every tile a Gaussian enters (ITU test over its candidate");
    m.doc(
        "rectangle, one tile per cycle) and whether it is incoming there (it did not enter the tile in the",
    );
    m.doc(
        "previous frame); bit-exact with golden hwpre::duplicate::incoming. See docs/rtl.md (Preprocessing).",
    );
    ports(&mut m, &d);
    rectangle(&mut m, &d);
    walker(&mut m, &d);
    itus(&mut m, &d);
    sideband(&mut m, &d);
    m
}

fn ports(m: &mut Module, d: &Dims) {
    m.clock_reset();
    m.input_c("grid_x_i", d.tb, "per frame: tile columns");
    m.input_c("grid_y_i", d.tb, "per frame: tile rows");
    m.input_c("all_fresh_i", 1, "per frame: no table is reused (every Gaussian incoming)");
    m.input("in_valid_i", 1);
    m.output("in_ready_o", 1);
    m.input_c("in_id_i", d.ib, "Gaussian id");
    m.input_c("in_key_i", d.kb, "depth key");
    m.input_c("in_mean_i", d.mb, "this frame's {mean_y, mean_x}");
    m.input_c("in_geom_i", d.gb, "this frame's ITU block of the feature entry");
    m.input_c("in_prev_visible_i", 1, "visible in the previous frame");
    m.input_c("in_prev_mean_i", d.mb, "the previous frame's {mean_y, mean_x}");
    m.input_c("in_prev_geom_i", d.gb, "the previous frame's ITU block");
    m.output("out_valid_o", 1);
    m.input("out_ready_i", 1);
    m.output("out_tile_x_o", d.tb);
    m.output("out_tile_y_o", d.tb);
    m.output("out_id_o", d.ib);
    m.output("out_key_o", d.kb);
    m.output_c("out_incoming_o", 1, "not in the tile's previous table");
    m.output_c("idle_o", 1, "no Gaussian being walked, no test in the ITUs");
}

/// The candidate range along both axes: one [`range_module`] per axis in a generate loop
/// (`g_axis[AXIS_X]`, `g_axis[AXIS_Y]`), giving `x0`, `x1`, `y0`, `y1` (`x1`, `y1` one past the
/// last).
fn rectangle(m: &mut Module, d: &Dims) {
    let Dims { m1, eb, tb, .. } = *d;
    m.comment(
        "Candidate tiles: [x0, x1) x [y0, y1), one range per axis (the mean's and the extent's field order).",
    );
    m.localparam_int("AXIS_X", 0);
    m.localparam_int("AXIS_Y", 1);
    m.wire_assign("grid", 2 * tb, "{grid_y_i, grid_x_i}");
    m.wire("range_first", 2 * tb).wire("range_end", 2 * tb);
    let field = |bus: &str, w: u32| format!("{bus}[a*{w} +: {w}]");
    let c = [
        ("mean_i", field("in_mean_i", m1)),
        ("ext_i", field("in_geom_i", eb)),
        ("grid_i", field("grid", tb)),
        ("first_o", field("range_first", tb)),
        ("end_o", field("range_end", tb)),
    ];
    let range = Item::Instance(Instance {
        module: RANGE_NAME.into(),
        name: "u_range".into(),
        params: Vec::new(),
        conns: conns(&c),
    });
    m.gen_for("a", 2, "g_axis", vec![range]);
    for (axis, a) in [("AXIS_X", "x"), ("AXIS_Y", "y")] {
        m.wire_assign(format!("{a}0"), tb, format!("range_first[{axis}*{tb} +: {tb}]"));
        m.wire_assign(format!("{a}1"), tb, format!("range_end[{axis}*{tb} +: {tb}]"));
    }
}

/// `neo_pre_dup_range`: a Gaussian's candidate tiles along one axis, `[first, end)`: the
/// tiles the AABB `mean +- extent` enters, clamped to the grid; the whole axis on an unbounded
/// extent (golden `raster::candidate_tiles`). Combinational; `neo_pre_dup` places one per axis.
pub fn range_module(cfg: &EngineConfig) -> Module {
    let d = Dims::new(cfg);
    let Dims { w, m1, eb, g, eshift, log2t, tb, .. } = d;
    let mut m = Module::new(RANGE_NAME);
    m.doc("Duplication unit: a Gaussian's candidate tiles along one axis, [first, end): the tiles the AABB");
    m.doc("mean +- extent enters, clamped to the grid; the whole axis on an unbounded extent (golden");
    m.doc("raster::candidate_tiles). Combinational; neo_pre_dup places one per axis.");
    m.input_c("mean_i", m1, "mean along the axis (ITU mean field)");
    m.input_c("ext_i", eb, "extent along the axis (ITU extent field)");
    m.input_c("grid_i", tb, "tiles along the axis");
    m.output_c("first_o", tb, "first candidate tile");
    m.output_c("end_o", tb, "one past the last candidate tile");
    m.wire_assign("m", w, format!("{{{{{}{{mean_i[{}]}}}}, mean_i, 1'b0}}", w - m1 - 1, m1 - 1));
    let shifted = if eshift == 0 { "ext_i".to_string() } else { format!("{{ext_i, {}}}", lit(eshift, 0)) };
    m.wire_assign("r", w, format!("{{{}, {shifted}}}", lit(w - eb - eshift, 0)));
    m.wire_assign("unbounded", 1, format!("ext_i == {}", lit(eb, d.unb)));
    // Each arithmetic shift gets its own assignment: in a wider expression with an unsigned
    // operand Verilog would make the shift logical.
    m.wire_assign("below", w, "r - m");
    m.wire_assign("below_g", w, format!("$signed(below) >>> {g}"));
    m.wire_assign("lo", w, format!("{} - below_g", lit(w, 0)));
    m.wire_assign("above", w, "m + r");
    m.wire_assign("hi", w, format!("$signed(above) >>> {g}"));
    m.wire_assign("tile_first", w, format!("$signed(lo) >>> {log2t}"));
    m.wire_assign("tile_last", w, format!("$signed(hi) >>> {log2t}"));
    m.wire_assign("tile_end", w, format!("tile_last + {}", lit(w, 1)));
    let grid = format!("{{{}, grid_i}}", lit(w - tb, 0));
    let clamp = |v: &str| {
        format!("({v}[{}] ? {} : (({v} > {grid}) ? grid_i : {v}[{}:0]))", w - 1, lit(tb, 0), tb - 1)
    };
    m.assign("first_o", format!("unbounded ? {} : {}", lit(tb, 0), clamp("tile_first")));
    m.assign("end_o", format!("unbounded ? grid_i : {}", clamp("tile_end")));
    m
}

/// The Gaussian registers and the tile walker.
fn walker(m: &mut Module, d: &Dims) {
    let Dims { tb, ib, kb, mb, gb, .. } = *d;
    m.comment("Walker: one candidate tile per cycle, row-major.");
    for (name, w) in [
        ("busy_q", 1),
        ("tx_q", tb),
        ("ty_q", tb),
        ("x0_q", tb),
        ("x1_q", tb),
        ("y1_q", tb),
        ("id_q", ib),
        ("key_q", kb),
        ("mean_q", mb),
        ("geom_q", gb),
        ("prev_visible_q", 1),
        ("prev_mean_q", mb),
        ("prev_geom_q", gb),
    ] {
        m.reg(name, w);
    }
    m.wire("itu_ready", 1);
    m.wire_assign("issue", 1, "busy_q & itu_ready");
    m.wire_assign("row_end", 1, format!("tx_q + {} == x1_q", lit(tb, 1)));
    m.wire_assign("last", 1, format!("row_end & (ty_q + {} == y1_q)", lit(tb, 1)));
    m.assign("in_ready_o", "~busy_q | (issue & last)");
    m.wire_assign("accept", 1, "in_valid_i & in_ready_o");
    m.wire_assign("nonempty", 1, "(x0 < x1) & (y0 < y1)");
    let load = vec![
        set("busy_q", "nonempty"),
        set("tx_q", "x0"),
        set("ty_q", "y0"),
        set("x0_q", "x0"),
        set("x1_q", "x1"),
        set("y1_q", "y1"),
        set("id_q", "in_id_i"),
        set("key_q", "in_key_i"),
        set("mean_q", "in_mean_i"),
        set("geom_q", "in_geom_i"),
        set("prev_visible_q", "in_prev_visible_i"),
        set("prev_mean_q", "in_prev_mean_i"),
        set("prev_geom_q", "in_prev_geom_i"),
    ];
    let step = vec![if_else(
        "last",
        vec![set("busy_q", lit(1, 0))],
        vec![if_else(
            "row_end",
            vec![set("tx_q", "x0_q"), set("ty_q", format!("ty_q + {}", lit(tb, 1)))],
            vec![set("tx_q", format!("tx_q + {}", lit(tb, 1)))],
        )],
    )];
    let reset = m.q_resets(&[]);
    m.seq(reset, vec![if_else("accept", load, vec![if_("issue", step)])]);
}

/// The two ITUs in lockstep and the output filter.
fn itus(m: &mut Module, d: &Dims) {
    m.comment("Two ITUs in lockstep: this frame's entry and the previous frame's.");
    for w in ["now", "prev"] {
        m.wire(format!("{w}_in_ready"), 1);
        m.wire(format!("{w}_out_valid"), 1);
        m.wire(format!("{w}_bitmap"), d.nb);
        m.wire(format!("{w}_hit"), 1);
        m.wire(format!("{w}_tag"), d.tg);
    }
    m.assign("itu_ready", "now_in_ready");
    m.wire_assign("itu_out_ready", 1, "~now_hit | out_ready_i");
    for (w, mean, geom) in [("now", "mean_q", "geom_q"), ("prev", "prev_mean_q", "prev_geom_q")] {
        m.item(Item::Instance(Instance {
            module: itu::NAME.into(),
            name: format!("u_itu_{w}"),
            params: Vec::new(),
            conns: conns(&[
                ("clk_i", "clk_i".into()),
                ("rst_ni", "rst_ni".into()),
                ("in_valid_i", "busy_q".into()),
                ("in_ready_o", format!("{w}_in_ready")),
                ("mean_i", mean.into()),
                ("geom_i", geom.into()),
                ("tile_x_i", "tx_q".into()),
                ("tile_y_i", "ty_q".into()),
                ("tag_i", lit(d.tg, 0)),
                ("out_valid_o", format!("{w}_out_valid")),
                ("out_ready_i", "itu_out_ready".into()),
                ("bitmap_o", format!("{w}_bitmap")),
                ("hit_o", format!("{w}_hit")),
                ("tag_o", format!("{w}_tag")),
            ]),
        }));
    }
}

/// The sideband pipeline beside the ITUs, and the outputs.
fn sideband(m: &mut Module, d: &Dims) {
    let Dims { tb, ib, kb, .. } = *d;
    let sb = 2 * tb + ib + kb + 1;
    m.comment(
        "Sideband of each test, advancing with the ITU pipeline ({tile_y, tile_x, key, id, prev_visible}): fields SB_*.",
    );
    let fields =
        [("SB_PREV_VISIBLE", 1), ("SB_ID", ib), ("SB_KEY", kb), ("SB_TILE_X", tb), ("SB_TILE_Y", tb)];
    let mut at = 0;
    for (name, w) in fields {
        m.localparam_int(name, at);
        if w > 1 {
            m.localparam_int(format!("{name}_W"), w);
        }
        at += w;
    }
    m.wire_assign("sb_in", sb, "{ty_q, tx_q, key_q, id_q, prev_visible_q}");
    let names: Vec<String> =
        (1..=itu::LATENCY).map(|k| if k == 1 { "sb_q".to_string() } else { format!("sb_q{k}") }).collect();
    for n in &names {
        m.reg(n, sb);
    }
    m.wire_assign("itu_adv", 1, "~now_out_valid | itu_out_ready");
    let mut body = Vec::new();
    for (k, n) in names.iter().enumerate() {
        body.push(set(n, if k == 0 { "sb_in".to_string() } else { names[k - 1].clone() }));
    }
    m.seq_noreset(vec![if_("itu_adv", body)]);
    m.comment("A valid bit per sideband stage (a test issued), for idle_o.");
    m.reg("sbv_q", itu::LATENCY);
    let shift = if itu::LATENCY == 1 {
        "busy_q".to_string()
    } else {
        format!("{{sbv_q[{}:0], busy_q}}", itu::LATENCY - 2)
    };
    m.seq(vec![set("sbv_q", lit(itu::LATENCY, 0))], vec![if_("itu_adv", vec![set("sbv_q", shift)])]);
    m.assign("idle_o", format!("~busy_q & (sbv_q == {})", lit(itu::LATENCY, 0)));
    let out = names.last().expect("the ITU has stages");
    m.wire_assign("out_prev_visible", 1, format!("{out}[SB_PREV_VISIBLE]"));
    m.assign("out_id_o", format!("{out}[SB_ID +: SB_ID_W]"));
    m.assign("out_key_o", format!("{out}[SB_KEY +: SB_KEY_W]"));
    m.assign("out_tile_x_o", format!("{out}[SB_TILE_X +: SB_TILE_X_W]"));
    m.assign("out_tile_y_o", format!("{out}[SB_TILE_Y +: SB_TILE_Y_W]"));
    m.assign("out_valid_o", "now_out_valid & now_hit");
    m.assign("out_incoming_o", "all_fresh_i | ~(out_prev_visible & prev_hit)");
    m.wire_assign(
        "unused_itu",
        1,
        "^{prev_in_ready, prev_out_valid, now_bitmap, prev_bitmap, now_tag, prev_tag}",
    );
}
