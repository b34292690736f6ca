//! `neo_itu`: the Intersection Test Unit (paper Section 5.4), bit-exact with golden
//! [`neo_golden::raster::subtile_bitmap`]: the separating-axis test of one Gaussian's cutoff
//! octagon against every subtile of one tile, one Gaussian per cycle.
//!
//! # Ports
//! - `in_valid_i` / `in_ready_o`: one Gaussian and one tile per transfer;
//!   - `mean_i` = bits `[2 mean.bits - 1 : 0]` of the packed feature entry (`{mean_y, mean_x}`),
//!   - `geom_i` = the contiguous ITU block of the entry, from `extent_x` to `extent_v`
//!     (`{extent_v, extent_u, axis_s, axis_c, extent_y, extent_x}`, LSB first as in
//!     [`neo_golden::formats::feature`]),
//!   - `tile_x_i`, `tile_y_i`: tile indices (unsigned, [`EngineConfig::tile_bits`]); the tile's
//!     first pixel is `(tile_x * tile, tile_y * tile)`,
//!   - `tag_i`: a sideband tag returned unchanged with the result;
//! - `out_valid_o` / `out_ready_i`: the result, in input order:
//!   - `bitmap_o`: bit `sy * n + sx` set iff subtile `(sx, sy)` may be touched (golden order),
//!   - `hit_o`: the cumulative OR of the bitmap (the table entry's valid bit),
//!   - `tag_o`.
//!
//! # Pipeline
//! Three register stages, all advancing together when `~out_valid_o | out_ready_i`
//! (`in_ready_o` is that signal, so it depends combinationally on `out_ready_i`). Latency: a
//! Gaussian accepted at edge `t` is on the output from edge `t + 3`; II = 1 while `out_ready_i`
//! is high. Bubbles are not squeezed out.
//! 1. offsets `d0 = mean - centre(subtile (0, 0))`, the per-Gaussian thresholds
//!    (`x`/`y`: `R + w`, `U`/`V`: `H 2^axis.frac + w (|C| + |S|)`, `w` the subtile half-size
//!    term) and the unbounded flags;
//! 2. the `x` test per column and the `y` test per row, and the projections of `d0` on `U`
//!    and `V` (4 multipliers);
//! 3. per subtile, the projections are stepped by constant multiples of `C` and `S` (the
//!    centre moves by `2 S 2^mean.frac` units per subtile): `|pu0 - kc[sx] - ks[sy]| > Tu` is
//!    tested as `kc[sx]` outside the window `[ru - Tu, ru + Tu]`, `ru = pu0 - ks[sy]`, one
//!    window per row (likewise for V), so each subtile costs four signed comparisons. The steps
//!    fit in [`step_bits`] bits and the windows are saturated to that width (a window edge beyond
//!    every step compares the same way saturated), so the 256 comparators are narrow.
//!
//! All arithmetic is in `W`-bit two's complement (see [`datapath_bits`]), wide enough for every
//! input bit pattern, so the unit matches golden on arbitrary field values, not just on
//! quantised Gaussians.

use crate::emit::expr::{bits_for, lit, sext, slice, zext};
use crate::emit::{conns, if_, set, Instance, Item, Module};
use neo_golden::engine::EngineConfig;

/// Module name.
pub const NAME: &str = "neo_itu";

/// The per-column (per-row) centre test, [`centre_module`].
pub const CENTRE_NAME: &str = "neo_itu_centre";

/// The per-step products and windows, [`window_module`].
pub const WINDOW_NAME: &str = "neo_itu_window";

/// Pipeline latency in cycles (input transfer edge to output valid).
pub const LATENCY: u32 = 3;

/// Width of `mean_i` for `cfg`.
pub fn mean_bits(cfg: &EngineConfig) -> u32 {
    2 * cfg.feature_format().mean.bits as u32
}

/// Width of `geom_i` for `cfg`, and its first bit in the packed entry.
pub fn geom_bits_lsb(cfg: &EngineConfig) -> (u32, u32) {
    let layout = cfg.feature_format().layout();
    let first = layout.iter().find(|f| f.name == "extent_x").expect("extent_x field");
    let last = layout.iter().find(|f| f.name == "extent_v").expect("extent_v field");
    (last.lsb + last.width - first.lsb, first.lsb)
}

/// Width `W` of the signed datapath: bounds every offset, projection and threshold for any
/// input bits and any tile index below `2^tile_bits`, plus a sign bit and two bits of margin (stage 3 adds a
/// projection, a threshold and a subtile step).
pub fn datapath_bits(cfg: &EngineConfig) -> u32 {
    let fmt = cfg.feature_format();
    let r = cfg.raster_config();
    let fm = fmt.mean.frac as u32;
    let g = fm + 1;
    let mean_max: u128 = 1u128 << fmt.mean.bits; // |mean << 1|
    let centre_max: u128 = ((2u128 << cfg.tile_bits) * r.tile as u128 + 2 * r.tile as u128) << fm;
    let d_max = mean_max + centre_max;
    let axis_max: u128 = 1u128 << (fmt.axis.bits - 1);
    let p_max = 2 * d_max * axis_max;
    let w = ((r.subtile as u128) - 1) << fm;
    let ext_max: u128 = (1u128 << fmt.extent.bits) - 1;
    let t_max = (ext_max << (g - fmt.extent.frac as u32 + fmt.axis.frac as u32)) + 2 * w * axis_max;
    bits_for(p_max.max(t_max) as u64) + 3
}

/// Width `K` of the stage-3 comparisons: the subtile steps `kc[k] = 2 S 2^mean.frac k C` (and
/// `ks`) fit in `K - 1` signed bits, and the per-row windows are saturated to `K` bits (their
/// extreme values then still compare the same way against every step).
pub fn step_bits(cfg: &EngineConfig) -> u32 {
    let fmt = cfg.feature_format();
    let r = cfg.raster_config();
    let step = (2 * r.subtile as u64) << fmt.mean.frac;
    let kmax = (r.subtiles_per_side() as u64 - 1) * step * (1u64 << (fmt.axis.bits - 1));
    bits_for(kmax) + 2
}

/// `|x|` of a `w`-bit two's complement expression (a net name).
fn abs(x: &str, w: u32) -> String {
    format!("({x}[{}] ? ({} - {x}) : {x})", w - 1, lit(w, 0))
}

/// Counts and widths of the ITU datapath.
#[derive(Clone, Copy)]
struct Dims {
    /// Subtiles per side and per tile.
    n: u32,
    nb: u32,
    /// Subtile side (pixels).
    s: u64,
    /// Mean fraction bits `F` and the datapath's `G = F + 1`.
    fm: u32,
    g: u32,
    /// Mean, extent and axis field bits.
    mb: u32,
    eb: u32,
    ab: u32,
    /// Datapath bits, step-product bits, tile-index bits, tag bits, `geom_i` bits.
    w: u32,
    kb: u32,
    tb: u32,
    tg: u32,
    gb: u32,
    /// Subtile size term `w = h` and centre step per subtile, in `2^-G` px.
    half: u64,
    step: u64,
}

impl Dims {
    fn new(cfg: &EngineConfig) -> Self {
        let fmt = cfg.feature_format();
        let r = cfg.raster_config();
        let s = r.subtile as u64;
        let fm = fmt.mean.frac as u32;
        Dims {
            n: r.subtiles_per_side(),
            nb: r.subtiles_per_tile(),
            s,
            fm,
            g: fm + 1,
            mb: fmt.mean.bits as u32,
            eb: fmt.extent.bits as u32,
            ab: fmt.axis.bits as u32,
            w: datapath_bits(cfg),
            kb: step_bits(cfg),
            tb: cfg.tile_bits,
            tg: cfg.itu_tag_bits,
            gb: geom_bits_lsb(cfg).0,
            half: (s - 1) << fm,
            step: (2 * s) << fm,
        }
    }
}

/// The ITU for `cfg` (see the module doc).
pub fn module(cfg: &EngineConfig) -> Module {
    let d = Dims::new(cfg);
    let mut m = Module::new(NAME);
    ports(&mut m, &d);
    fields(&mut m, &d);
    handshake(&mut m);
    stage1(&mut m, cfg, &d);
    stage2(&mut m, &d);
    stage3(&mut m, &d);
    m
}

/// The header comment and the ports.
fn ports(m: &mut Module, d: &Dims) {
    let Dims { nb, mb, w, tb, tg, gb, .. } = *d;
    m.doc(
        "Intersection Test Unit: subtile bitmap of one Gaussian's cutoff octagon in one tile, bit-exact with",
    );
    m.doc("golden raster::subtile_bitmap (bit sy*N+sx), and its OR (the table entry's valid bit).");
    m.doc(format!(
        "{LATENCY}-stage pipeline, II = 1, all stages advance on ~out_valid_o | out_ready_i. {w}-bit signed datapath."
    ));
    m.doc(format!(
        "Submodules: g_centre[c].u_col / u_row ({CENTRE_NAME}: a column's x test, a row's y test), g_window[k].u_window"
    ));
    m.doc(format!("({WINDOW_NAME}: step k's products and row k's U / V windows). See docs/rtl.md (ITU)."));
    m.clock_reset();
    m.input("in_valid_i", 1);
    m.output("in_ready_o", 1);
    m.input_c("mean_i", 2 * mb, "{mean_y, mean_x}: entry bits of mean_x and mean_y");
    m.input_c("geom_i", gb, "{extent_v, extent_u, axis_s, axis_c, extent_y, extent_x}");
    m.input_c("tile_x_i", tb, "tile column index");
    m.input_c("tile_y_i", tb, "tile row index");
    m.input_c("tag_i", tg, "sideband, returned on tag_o");
    m.output("out_valid_o", 1);
    m.input("out_ready_i", 1);
    m.output_c("bitmap_o", nb, "bit sy*N+sx: subtile (sx, sy) may be touched");
    m.output_c("hit_o", 1, "OR of bitmap_o");
    m.output("tag_o", tg);
}

/// The fields of `geom_i` and `mean_i`.
fn fields(m: &mut Module, d: &Dims) {
    let Dims { mb, eb, ab, .. } = *d;
    // Field slices of geom_i.
    let mut off = 0;
    let mut field = |name: &str, width: u32, m: &mut Module| {
        m.wire_assign(name, width, slice("geom_i", off + width - 1, off));
        off += width;
    };
    m.blank();
    m.comment("Fields.");
    field("ext_x", eb, m);
    field("ext_y", eb, m);
    field("axis_c", ab, m);
    field("axis_s", ab, m);
    field("ext_u", eb, m);
    field("ext_v", eb, m);
    m.wire_assign("mean_x", mb, slice("mean_i", mb - 1, 0));
    m.wire_assign("mean_y", mb, slice("mean_i", 2 * mb - 1, mb));
}

/// The handshake: one global stage enable.
fn handshake(m: &mut Module) {
    m.blank();
    m.comment("Handshake: one global stage enable.");
    m.reg("v1_q", 1).reg("v2_q", 1).reg("v3_q", 1);
    m.wire_assign("adv", 1, "~v3_q | out_ready_i");
    m.assign("in_ready_o", "adv");
    m.seq(
        vec![set("v1_q", lit(1, 0)), set("v2_q", lit(1, 0)), set("v3_q", lit(1, 0))],
        vec![if_("adv", vec![set("v1_q", "in_valid_i"), set("v2_q", "v1_q"), set("v3_q", "v2_q")])],
    );
}

/// Stage 1: offsets from the centre of subtile (0, 0) and the thresholds.
fn stage1(m: &mut Module, cfg: &EngineConfig, d: &Dims) {
    let Dims { s, fm, g, mb, eb, ab, w, tb, tg, half, .. } = *d;
    let fmt = cfg.feature_format();
    let r = cfg.raster_config();
    let l = |v: u64| lit(w, v);
    // Stage 1.
    m.blank();
    m.comment(format!(
        "Stage 1: offsets from the centre of subtile (0, 0), in 2^-{g} px: mean << 1 minus ((2 T + {}) << {fm}).",
        s - 1
    ));
    for (a, t, mean) in [("x", "tile_x_i", "mean_x"), ("y", "tile_y_i", "mean_y")] {
        m.wire_assign(format!("m{a}"), w, format!("{{{}, 1'b0}}", sext(mean, mb, w - 1)));
        m.wire_assign(
            format!("c{a}"),
            w,
            format!("({} * {} + {}) << {fm}", zext(t, tb, w), l(2 * r.tile as u64), l(s - 1)),
        );
        m.wire_assign(format!("d{a}0"), w, format!("m{a} - c{a}"));
    }
    m.comment(format!(
        "Thresholds: R << {} + {half} (x, y); H << {} + {half} (|C| + |S|) (U, V).",
        g - fmt.extent.frac as u32,
        g - fmt.extent.frac as u32 + fmt.axis.frac as u32
    ));
    m.wire_assign("cw", w, sext("axis_c", ab, w));
    m.wire_assign("sw", w, sext("axis_s", ab, w));
    m.wire_assign("abs_cs", w, format!("{} + {}", abs("cw", w), abs("sw", w)));
    let sh_xy = g - fmt.extent.frac as u32;
    let sh_uv = sh_xy + fmt.axis.frac as u32;
    for (a, e, sh) in
        [("x", "ext_x", sh_xy), ("y", "ext_y", sh_xy), ("u", "ext_u", sh_uv), ("v", "ext_v", sh_uv)]
    {
        let term = if sh_xy == sh { l(half) } else { format!("{} * abs_cs", l(half)) };
        m.wire_assign(format!("t{a}"), w, format!("({} << {sh}) + {term}", zext(e, eb, w)));
        m.wire_assign(format!("unb_{a}"), 1, format!("&{e}"));
    }
    let s1 = [
        ("dx0_q", w, "dx0"),
        ("dy0_q", w, "dy0"),
        ("c1_q", w, "cw"),
        ("s1_q", w, "sw"),
        ("tx1_q", w, "tx"),
        ("ty1_q", w, "ty"),
        ("tu1_q", w, "tu"),
        ("tv1_q", w, "tv"),
        ("ux1_q", 1, "unb_x"),
        ("uy1_q", 1, "unb_y"),
        ("uu1_q", 1, "unb_u"),
        ("uv1_q", 1, "unb_v"),
        ("tag1_q", tg, "tag_i"),
    ];
    for (q, width, _) in s1 {
        m.reg(q, width);
    }
    m.seq_noreset(vec![if_("adv", s1.iter().map(|(q, _, d)| set(*q, *d)).collect())]);
}

/// Stage 2: the x / y tests per column / row and the U / V projections.
fn stage2(m: &mut Module, d: &Dims) {
    let Dims { n, w, kb, tg, step, .. } = *d;
    // Stage 2.
    m.blank();
    m.comment(format!(
        "Stage 2: x test per column, y test per row (centre steps of {step}); projections on U = (C, S), V = (-S, C)."
    ));
    m.wire("col_ok", n).wire("row_ok", n);
    let centre = |name: &str, a: &str, ok: &str| {
        let c = [
            ("d0_i", format!("d{a}0_q")),
            ("t_i", format!("t{a}1_q")),
            ("unb_i", format!("u{a}1_q")),
            ("ok_o", format!("{ok}[c]")),
        ];
        step_instance(CENTRE_NAME, name, "c", conns(&c))
    };
    m.gen_for("c", n, "g_centre", vec![centre("u_col", "x", "col_ok"), centre("u_row", "y", "row_ok")]);
    m.comment("Signed products (the same low W bits as unsigned ones): synthesis then drops the operands'");
    m.comment("sign-extension bits, so the multipliers are W x axis.bits, not W x W.");
    m.wire_assign("pu0", w, "$signed(dx0_q) * $signed(c1_q) + $signed(dy0_q) * $signed(s1_q)");
    m.wire_assign("pv0", w, "$signed(dy0_q) * $signed(c1_q) - $signed(dx0_q) * $signed(s1_q)");
    let (c1_low, s1_low) = (slice("c1_q", kb - 1, 0), slice("s1_q", kb - 1, 0));
    let s2 = [
        ("col2_q", n, "col_ok"),
        ("row2_q", n, "row_ok"),
        ("pu2_q", w, "pu0"),
        ("pv2_q", w, "pv0"),
        ("c2_q", kb, c1_low.as_str()),
        ("s2_q", kb, s1_low.as_str()),
        ("tu2_q", w, "tu1_q"),
        ("tv2_q", w, "tv1_q"),
        ("uu2_q", 1, "uu1_q"),
        ("uv2_q", 1, "uv1_q"),
        ("tag2_q", tg, "tag1_q"),
    ];
    for (q, width, _) in s2 {
        m.reg(q, width);
    }
    m.seq_noreset(vec![if_("adv", s2.iter().map(|(q, _, d)| set(*q, *d)).collect())]);
}

/// Stage 3: the U / V windows per row and the bitmap.
fn stage3(m: &mut Module, d: &Dims) {
    let Dims { n, nb, kb, tg, step, .. } = *d;
    // Stage 3.
    m.blank();
    m.comment(format!(
        "Stage 3: pu = pu0 - kc[sx] - ks[sy], pv = pv0 - kc[sy] + ks[sx] (kc[k] = {step} k C, ks[k] = {step} k S):"
    ));
    m.comment("|pu| > Tu iff kc[sx] lies outside [ru - Tu, ru + Tu], ru = pu0 - ks[sy] (one window per row), likewise V.");
    m.wire("kc", n * kb).wire("ks", n * kb);
    m.wire("lu", n * kb).wire("hu", n * kb).wire("lv", n * kb).wire("hv", n * kb);
    let inputs = [
        ("c_i", "c2_q"),
        ("s_i", "s2_q"),
        ("pu_i", "pu2_q"),
        ("pv_i", "pv2_q"),
        ("tu_i", "tu2_q"),
        ("tv_i", "tv2_q"),
    ];
    let outputs =
        [("kc_o", "kc"), ("ks_o", "ks"), ("lu_o", "lu"), ("hu_o", "hu"), ("lv_o", "lv"), ("hv_o", "hv")];
    let c: Vec<(&str, String)> = inputs
        .into_iter()
        .map(|(p, net)| (p, net.to_string()))
        .chain(outputs.into_iter().map(|(p, v)| (p, format!("{v}[k*{kb} +: {kb}]"))))
        .collect();
    m.gen_for("k", n, "g_window", vec![step_instance(WINDOW_NAME, "u_window", "k", conns(&c))]);
    m.wire("bitmap_d", nb);
    let lane = |v: &str, idx: &str| format!("$signed({v}[({idx})*{kb} +: {kb}])");
    let (col, row) = (format!("gi % {n}"), format!("gi / {n}"));
    m.gen_for(
        "gi",
        nb,
        "g_subtile",
        vec![
            Item::Wire { name: "sep_u".into(), width: 1 },
            Item::Wire { name: "sep_v".into(), width: 1 },
            Item::Assign {
                lhs: "sep_u".into(),
                rhs: format!(
                    "~uu2_q & (({kc} < {lu}) | ({kc} > {hu}))",
                    kc = lane("kc", &col),
                    lu = lane("lu", &row),
                    hu = lane("hu", &row)
                ),
            },
            Item::Assign {
                lhs: "sep_v".into(),
                rhs: format!(
                    "~uv2_q & (({ks} < {lv}) | ({ks} > {hv}))",
                    ks = lane("ks", &col),
                    lv = lane("lv", &row),
                    hv = lane("hv", &row)
                ),
            },
            Item::Assign {
                lhs: "bitmap_d[gi]".into(),
                rhs: format!("col2_q[{col}] & row2_q[{row}] & ~sep_u & ~sep_v"),
            },
        ],
    );
    m.reg("bitmap3_q", nb).reg("tag3_q", tg);
    m.seq_noreset(vec![if_("adv", vec![set("bitmap3_q", "bitmap_d"), set("tag3_q", "tag2_q")])]);
    m.blank();
    m.assign("out_valid_o", "v3_q");
    m.assign("bitmap_o", "bitmap3_q");
    m.assign("hit_o", "|bitmap3_q");
    m.assign("tag_o", "tag3_q");
}

/// An instance `name` of the step module `module` inside a generate loop over `var`, its `K`
/// the loop's index.
fn step_instance(module: &str, name: &str, var: &str, conns: Vec<(String, String)>) -> Item {
    Item::Instance(Instance {
        module: module.into(),
        name: name.into(),
        params: vec![("K".into(), var.into())],
        conns,
    })
}

/// `neo_itu_centre #(K)`: the `x` test of subtile column `K` (or the `y` test of row `K`):
/// the offset from the column's centre, `d0 - K step`, is within the threshold, or the
/// extent is unbounded. Combinational; `neo_itu` places two per column in stage 2.
pub fn centre_module(cfg: &EngineConfig) -> Module {
    let Dims { w, step, .. } = Dims::new(cfg);
    let mut m = Module::new(CENTRE_NAME);
    m.doc("ITU centre test of subtile column (or row) K: |d0 - K step| <= T, or the extent is unbounded.");
    m.doc(format!("Combinational; neo_itu's stage 2 places one per column and one per row (step {step})."));
    m.param("K", 0);
    m.input_c("d0_i", w, "offset from the centre of subtile 0 (dx0 or dy0)");
    m.input_c("t_i", w, "threshold R + w (tx or ty)");
    m.input_c("unb_i", 1, "the extent is unbounded");
    m.output_c("ok_o", 1, "the column (row) may be touched");
    m.localparam("OFFSET", w, format!("{} * K", lit(w, step)));
    m.wire_assign("d", w, "d0_i - OFFSET");
    m.assign("ok_o", format!("unb_i | ~({} > t_i)", abs("d", w)));
    m
}

/// `neo_itu_window #(K)`: the subtile steps of index `K`, `kc = K step C` and `ks = K step
/// S`, and row `K`'s windows: `[ru - Tu, ru + Tu]` with `ru = pu0 - ks`, and `[-Tv - rv, Tv -
/// rv]` with `rv = pv0 - kc`, saturated to [`step_bits`] bits. Combinational; `neo_itu`
/// places one per step in stage 3.
pub fn window_module(cfg: &EngineConfig) -> Module {
    let Dims { w, kb, step, .. } = Dims::new(cfg);
    let mut m = Module::new(WINDOW_NAME);
    m.doc("ITU step K: kc = K step C and ks = K step S (subtile column or row K), and row K's U / V windows");
    m.doc(format!(
        "[ru - Tu, ru + Tu], ru = pu0 - ks, and [-Tv - rv, Tv - rv], rv = pv0 - kc, saturated to {kb} bits."
    ));
    m.doc(format!("Combinational; neo_itu's stage 3 places one per step (step {step})."));
    m.param("K", 0);
    m.input_c("c_i", kb, "axis C, low bits");
    m.input_c("s_i", kb, "axis S, low bits");
    m.input_c("pu_i", w, "projection of d0 on U");
    m.input_c("pv_i", w, "projection of d0 on V");
    m.input_c("tu_i", w, "threshold along U");
    m.input_c("tv_i", w, "threshold along V");
    for (v, what) in [("kc", "K step C"), ("ks", "K step S")] {
        m.output_c(format!("{v}_o"), kb, what);
    }
    for (v, what) in [
        ("lu", "U window, low, saturated"),
        ("hu", "U window, high, saturated"),
        ("lv", "V window, low, saturated"),
        ("hv", "V window, high, saturated"),
    ] {
        m.output_c(format!("{v}_o"), kb, what);
    }
    m.localparam("STEP_K_INT", 0, format!("{step} * K"));
    m.localparam("STEP_K", kb, slice("STEP_K_INT", kb - 1, 0));
    m.wire_assign("kc", kb, "$signed(c_i) * $signed(STEP_K)");
    m.wire_assign("ks", kb, "$signed(s_i) * $signed(STEP_K)");
    m.assign("kc_o", "kc");
    m.assign("ks_o", "ks");
    m.wire_assign("ru", w, format!("pu_i - {}", sext("ks", kb, w)));
    m.wire_assign("rv", w, format!("pv_i - {}", sext("kc", kb, w)));
    m.wire_assign("lu", w, "ru - tu_i");
    m.wire_assign("hu", w, "ru + tu_i");
    m.wire_assign("lv", w, format!("{} - tv_i - rv", lit(w, 0)));
    m.wire_assign("hv", w, "tv_i - rv");
    for v in ["lu", "hu", "lv", "hv"] {
        m.assign(format!("{v}_o"), saturate(v, w, kb));
    }
    m
}

/// The `w`-bit value `x` saturated to `kb` signed bits.
fn saturate(x: &str, w: u32, kb: u32) -> String {
    let top = slice(x, w - 1, kb - 1);
    format!(
        "(&{top} | ~|{top}) ? {} : ({x}[{}] ? {} : {})",
        slice(x, kb - 1, 0),
        w - 1,
        lit(kb, 1 << (kb - 1)),
        lit(kb, (1 << (kb - 1)) - 1)
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn widths_follow_the_formats() {
        let cfg = EngineConfig::default();
        assert_eq!(mean_bits(&cfg), 56, "2 x 28");
        let (gb, lsb) = geom_bits_lsb(&cfg);
        assert_eq!(gb, 4 * 15 + 2 * 10);
        let fmt = cfg.feature_format();
        let dk = fmt.layout().into_iter().find(|f| f.name == "depth_key").unwrap();
        assert_eq!(lsb + gb, dk.lsb, "the ITU block ends where the depth key starts");
        assert_eq!(lsb, 158, "after mean (56), conic (61), opacity (8) and colour (33)");
        let w = datapath_bits(&cfg);
        assert!((36..=44).contains(&w), "{w}");
        let narrow = EngineConfig { tile_bits: 4, ..cfg };
        assert!(datapath_bits(&narrow) <= w);
    }

    #[test]
    fn ports_and_subtile_generate_block() {
        let v = module(&EngineConfig::default()).to_verilog();
        assert!(v.contains("output wire [63:0] bitmap_o"), "{v}");
        assert!(v.contains("for (gi = 0; gi < 64; gi = gi + 1) begin : g_subtile"), "{v}");
        assert!(v.contains("assign hit_o = |bitmap3_q;"), "{v}");
    }
}
