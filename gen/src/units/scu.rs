//! `neo_scu`: the Subtile Compute Unit, front-to-back alpha blending of the Gaussians routed to
//! one subtile, bit-exact with golden [`neo_golden::raster::scu`] (`shade_pixel` /
//! `raster_tile`); and `neo_scu_exp`, its exp unit (golden [`ExpTable`], ROM contents generated
//! from `ExpTable::table`).
//!
//! Every width and constant comes from the golden formats ([`GenConfig::feature_format`],
//! [`GenConfig::raster_config`]); nothing is retyped here.
//!
//! # Stream protocol
//! One input beat per Gaussian (`in_valid_i`/`in_ready_o`) with its feature-entry fields; a
//! subtile's list is the beats up to and including the one with `in_last_i`. The first beat of a
//! list (the first after reset or after a `last` beat) starts the subtile: its origin (pixel
//! coordinates of the top-left pixel) and `in_cols_i`/`in_rows_i` (how many columns / rows of
//! the subtile are inside the image; pixels outside start done and come out black) are taken,
//! and the state is cleared; those fields are ignored on the other beats. A beat with
//! `in_empty_i` carries no Gaussian; an empty list is one beat with `in_empty_i = in_last_i = 1`.
//! Per list one output beat (`out_valid_o`/`out_ready_i`) carries the subtile's pixels, pixel
//! `k = ly * S + lx` at `out_rgb_o[24k +: 24]` as `{blue, green, red}`.
//!
//! # Schedule
//! `L = scu_lanes` pixel lanes, `P = S*S / L` passes: a Gaussian occupies the issue stage for
//! `P` cycles (pass `p` evaluates pixels `p*L .. p*L+L-1`), so II = `P` cycles per Gaussian.
//! Stages: issue (S0), squares of `|dx|, |dy|` (S1), the exact quadratic form `q` (S2), `np` by
//! the rounding shift and saturation (S3), exp (S4), alpha with the 1/255 test (S5), then the
//! blend from S5's registers into the pixel state (transmittance and colour update, a
//! read-modify-write of the pass's pixels in one cycle, so there is no hazard). Latency from
//! accepting a list's last beat to `out_valid_o`: `P + 6` cycles. When every pixel of the list is done (`term_o` high while the list is still being
//! accepted) the rest of the list is drained at one beat per cycle without evaluation. A global
//! stall holds everything only while a finished list waits for the output register.

use crate::config::GenConfig;
use crate::emit::expr::{bits_for, lit};
use crate::emit::{if_, if_else, set, Item, Module, Stmt};
use neo_golden::raster::scu::min_power_shift;
use neo_golden::raster::ExpTable;

/// Module name of the SCU.
pub const NAME: &str = "neo_scu";
/// Module name of the exp unit.
pub const EXP_NAME: &str = "neo_scu_exp";
/// Pipeline stages after issue (S1..=S5).
pub const STAGES: u32 = 5;
/// Width of the list counter that tags beats (more lists than fit in the pipeline).
const LID_BITS: u32 = 3;

/// Widths and constants of the SCU datapath, all derived from the golden formats.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ScuWidths {
    /// Mean field width.
    pub mean: u32,
    /// Mean fraction bits.
    pub mean_frac: u32,
    /// Conic mantissa bits `M` (`b` has `M + 1`).
    pub mant: u32,
    /// Conic exponent field width.
    pub cexp: u32,
    /// Opacity width (all fraction).
    pub opacity: u32,
    /// Colour channel width.
    pub color: u32,
    /// Origin coordinate width (pixels).
    pub origin: u32,
    /// Subtile side `S` and `log2 S`.
    pub side: u32,
    /// `log2 S`.
    pub side_bits: u32,
    /// Pixel lanes.
    pub lanes: u32,
    /// Passes per Gaussian, `S*S / lanes`.
    pub passes: u32,
    /// Signed `dx`/`dy` width.
    pub d: u32,
    /// `|dx|` width.
    pub u: u32,
    /// Signed width of the quadratic form `q`.
    pub q: u32,
    /// Conic-to-power shift at exponent 0.
    pub sh0: u32,
    /// `-power` width (`power_int + power_frac`) and its saturation value.
    pub np: u32,
    /// Largest `np`.
    pub max_np: u64,
    /// Exp result width (`out_frac + 1`).
    pub e: u32,
    /// Alpha fraction bits, cap and threshold.
    pub alpha_frac: u32,
    /// Alpha cap (raw).
    pub max_alpha: u64,
    /// Smallest blended alpha (raw).
    pub min_alpha: u64,
    /// `opacity.frac + out_frac - alpha_frac` (negative: a left shift).
    pub alpha_shift: i32,
    /// Transmittance width (`frac + 1`), 1.0 and the floor.
    pub t: u32,
    /// Transmittance fraction bits.
    pub t_frac: u32,
    /// Transmittance floor (raw).
    pub min_t: u64,
    /// Colour accumulator width `color.bits + t_frac + 1`.
    pub c: u32,
    /// Output shift `color.frac + t_frac`.
    pub out_shift: u32,
    /// Subtiles whose state the SCU keeps between pieces of their lists (the tile's subtiles
    /// over `raster_scus`: one per subtile group), and the width of their index.
    pub rows: u32,
    /// Width of `in_sub_i`.
    pub row_bits: u32,
}

impl ScuWidths {
    /// The widths for `cfg`.
    pub fn new(cfg: &GenConfig) -> Self {
        let fmt = cfg.feature_format();
        let rc = cfg.raster_config();
        let b = rc.blend;
        let side = rc.subtile;
        assert!(side.is_power_of_two(), "subtile side {side} is not a power of two");
        let mean = fmt.mean.bits as u32;
        let mean_frac = fmt.mean.frac as u32;
        let mant = fmt.conic.mantissa_bits as u32;
        // px < 2^(origin + 1) so (px << Fm) < 2^(mean + 1): dx fits mean + 3 signed bits.
        let origin = mean - mean_frac;
        let d = mean + 3;
        let u = d - 1;
        let lanes = cfg.scu_lanes as u32;
        GenConfig::validate(cfg).expect("valid configuration");
        let sh0 = min_power_shift(&fmt, &b);
        assert!(sh0 >= 1, "conic-to-power shift {sh0} < 1");
        ScuWidths {
            mean,
            mean_frac,
            mant,
            cexp: fmt.conic.exp_bits as u32,
            opacity: fmt.opacity.bits as u32,
            color: fmt.color.bits as u32,
            origin,
            side,
            side_bits: side.trailing_zeros(),
            lanes,
            passes: side * side / lanes,
            d,
            u,
            q: mant + 2 * u + 3,
            sh0: sh0 as u32,
            np: b.power_int as u32 + b.power_frac as u32,
            max_np: b.max_neg_power() as u64,
            e: b.exp.out_frac as u32 + 1,
            alpha_frac: b.alpha_frac as u32,
            max_alpha: b.max_alpha_raw() as u64,
            min_alpha: b.min_alpha_raw() as u64,
            alpha_shift: fmt.opacity.frac as i32 + b.exp.out_frac as i32 - b.alpha_frac as i32,
            t: b.transmittance_frac as u32 + 1,
            t_frac: b.transmittance_frac as u32,
            min_t: b.min_transmittance_raw() as u64,
            c: fmt.color.bits as u32 + b.transmittance_frac as u32 + 1,
            out_shift: fmt.color.frac as u32 + b.transmittance_frac as u32,
            rows: rc.subtiles_per_tile() / cfg.raster_scus as u32,
            row_bits: bits_for((rc.subtiles_per_tile() / cfg.raster_scus as u32).max(2) as u64 - 1),
        }
    }

    /// Pixels per subtile.
    pub fn pixels(&self) -> u32 {
        self.side * self.side
    }

    /// Bits of one pixel's saved state `{done, colour, T}`.
    pub fn state_bits(&self) -> u32 {
        self.t + 3 * self.c + 1
    }

    /// Width of the pass counter (at least 1).
    pub fn pass_bits(&self) -> u32 {
        bits_for(self.passes as u64 - 1)
    }
}

/// `{{n{1'b0}}, x}`: `x` (`w` bits) zero-extended to `to` bits.
fn zx(x: &str, w: u32, to: u32) -> String {
    assert!(to >= w, "zx {x}: {w} > {to}");
    if to == w {
        x.to_string()
    } else {
        format!("{{{}, {x}}}", lit(to - w, 0))
    }
}

/// A one-line sequence of `always` statements guarded by `en`.
fn on_en(stmts: Vec<Stmt>) -> Item {
    Item::Seq { reset: None, body: vec![if_("en", stmts)] }
}

/// The per-beat fields carried down the pipeline: (name, width).
fn beat_fields(w: &ScuWidths) -> Vec<(&'static str, u32)> {
    vec![
        ("mx", w.mean),
        ("my", w.mean),
        ("ca", w.mant),
        ("cb", w.mant + 1),
        ("cc", w.mant),
        ("ce", w.cexp),
        ("op", w.opacity),
        ("r", w.color),
        ("g", w.color),
        ("b", w.color),
        ("ox", w.origin),
        ("oy", w.origin),
        ("cols", w.side_bits + 1),
        ("rows", w.side_bits + 1),
        ("empty", 1),
        ("last", 1),
        ("first", 1),
        ("fin", 1),
        ("resume", 1),
        ("sub", w.row_bits),
        ("lid", LID_BITS),
        ("pass", w.pass_bits()),
        ("nop", 1),
    ]
}

/// Layout of the bundle: name -> (lsb, width); total width.
struct Bundle {
    fields: Vec<(&'static str, u32, u32)>,
    width: u32,
}

impl Bundle {
    fn new(w: &ScuWidths) -> Self {
        let mut lsb = 0;
        let mut fields = Vec::new();
        for (n, wd) in beat_fields(w) {
            fields.push((n, lsb, wd));
            lsb += wd;
        }
        Bundle { fields, width: lsb }
    }

    /// Bit `i` of field `name` of bundle register `reg`.
    fn bit(&self, reg: &str, name: &str, i: u32) -> String {
        let &(_, lsb, _) = self.fields.iter().find(|f| f.0 == name).expect("known field");
        format!("{reg}[{}]", lsb + i)
    }

    /// Field `name` of bundle register `reg`.
    fn f(&self, reg: &str, name: &str) -> String {
        let &(_, lsb, wd) = self.fields.iter().find(|f| f.0 == name).expect("known field");
        if wd == 1 {
            format!("{reg}[{lsb}]")
        } else {
            format!("{reg}[{}:{lsb}]", lsb + wd - 1)
        }
    }
}

/// The exp unit for `cfg`: combinational `e_o = ExpTable::eval(np_i)`.
pub fn exp_module(cfg: &GenConfig) -> Module {
    let b = cfg.raster_config().blend;
    let t = ExpTable::new(&b.exp, b.power_frac);
    let w = ScuWidths::new(cfg);
    let (tb, ib) = (b.exp.table_bits as u32, b.exp.interp_bits as u32);
    let fe = b.exp.out_frac as u32;
    let ew = w.e;
    let l2e = t.log2e_raw() as u64;
    let lw = bits_for(l2e);
    let is = t.input_shift();
    let pw = w.np + lw; // product width
    let mut m = Module::new(EXP_NAME);
    m.doc(
        "SCU exp unit (golden ExpTable::eval): e_o = exp(-np_i 2^-power_frac) with out_frac fraction bits.",
    );
    m.doc(format!(
        "y = round(np * {l2e} >> {is}); n = y >> {}, table index y[{}:{ib}], weight y[{}:0]; ROM of {} entries.",
        tb + ib,
        tb + ib - 1,
        ib.max(1) - 1,
        t.table().len()
    ));
    m.input_c("np_i", w.np, "-power, unsigned, power_frac fraction bits");
    m.output_c("e_o", ew, "exp, out_frac fraction bits");
    m.wire_assign("prod", pw, format!("{} * {}", zx("np_i", w.np, pw), lit(pw, l2e)));
    // y: the rounding shift of the product (width yw).
    let yw = pw + 1 - is;
    if is == 0 {
        m.wire_assign("y", yw, zx("prod", pw, yw));
    } else {
        m.wire_assign(
            "prod_r",
            pw + 1,
            format!("{} + {}", zx("prod", pw, pw + 1), lit(pw + 1, 1 << (is - 1))),
        );
        m.wire_assign("y", yw, format!("prod_r[{}:{is}]", pw));
    }
    let f = tb + ib;
    let nw = yw - f;
    let sw = bits_for(fe as u64 + 1);
    m.wire_assign("n", nw, format!("y[{}:{f}]", yw - 1));
    if nw > sw || (fe as u64 + 2) < (1u64 << nw) {
        m.wire_assign("big", 1, format!("n >= {}", lit(nw, fe as u64 + 2)));
    } else {
        m.wire_assign("big", 1, lit(1, 0));
    }
    let ix = if tb == 1 { format!("y[{ib}]") } else { format!("y[{}:{ib}]", f - 1) };
    m.wire_assign("idx", tb, ix);
    m.reg("t0", ew).reg("t1", ew);
    m.comment("ROM: T[idx] and T[idx + 1] (golden ExpTable::table).");
    let arms = (0..(1u64 << tb))
        .map(|j| {
            (
                lit(tb, j),
                vec![
                    set("t0", lit(ew, t.table()[j as usize] as u64)),
                    set("t1", lit(ew, t.table()[j as usize + 1] as u64)),
                ],
            )
        })
        .collect();
    m.comb(vec![
        set("t0", lit(ew, 0)),
        set("t1", lit(ew, 0)),
        Stmt::Case("idx".into(), arms, vec![Stmt::Comment("every index is listed".into())]),
    ]);
    if ib == 0 {
        m.wire_assign("e0", ew, "t0");
    } else {
        let iw = ew + ib + 1;
        m.wire_assign("diff", ew, "t0 - t1");
        m.wire_assign(
            "ip",
            iw,
            format!(
                "{} * {} + {}",
                zx("diff", ew, iw),
                zx(&format!("y[{}:0]", ib - 1), ib, iw),
                lit(iw, 1 << (ib - 1))
            ),
        );
        m.wire_assign("e0", ew, format!("t0 - ip[{}:{ib}]", ew + ib - 1));
    }
    // shr_round(e0, n) = (({e0, 0} >> n) + 1) >> 1 for every n >= 0.
    m.wire_assign("ee", ew + 1, format!("{{e0, 1'b0}} >> n[{}:0]", sw - 1));
    m.wire_assign("er", ew + 1, format!("ee + {}", lit(ew + 1, 1)));
    m.assign("e_o", format!("big ? {} : er[{ew}:1]", lit(ew, 0)));
    m
}

/// The SCU for `cfg`.
pub fn module(cfg: &GenConfig) -> Module {
    let w = ScuWidths::new(cfg);
    let bd = Bundle::new(&w);
    let bw = bd.width;
    let (l_n, p_n, pb) = (w.lanes, w.passes, w.pass_bits());
    let npix = w.pixels();
    let sb = w.side_bits;
    let mut m = Module::new(NAME);
    m.doc(format!(
        "Subtile Compute Unit: alpha blending of one {s}x{s} subtile, {l_n} pixel lanes x {p_n} passes (II = {p_n} cycles",
        s = w.side
    ));
    m.doc(
        "per Gaussian), bit-exact with golden raster::scu. One beat per Gaussian; in_last_i ends the list;",
    );
    m.doc("origin/cols/rows are taken from a list's first beat. One out beat per list: pixel k at out_rgb_o[24k +: 24]");
    m.doc("= {blue, green, red}. term_o: every pixel of the list being accepted is done. See docs/rtl.md.");
    m.clock_reset();
    m.input_c("in_valid_i", 1, "a Gaussian beat is offered");
    m.output_c("in_ready_o", 1, "taken when in_valid_i & in_ready_o");
    m.input_c("in_mean_x_i", w.mean, "mean x, signed, mean.frac fraction bits");
    m.input_c("in_mean_y_i", w.mean, "mean y");
    m.input_c("in_conic_a_i", w.mant, "conic a mantissa, unsigned");
    m.input_c("in_conic_b_i", w.mant + 1, "conic b mantissa, signed");
    m.input_c("in_conic_c_i", w.mant, "conic c mantissa, unsigned");
    m.input_c("in_conic_exp_i", w.cexp, "shared conic exponent field");
    m.input_c("in_opacity_i", w.opacity, "opacity, unsigned fraction");
    m.input_c("in_red_i", w.color, "colour, unsigned");
    m.input_c("in_green_i", w.color, "");
    m.input_c("in_blue_i", w.color, "");
    m.input_c("in_empty_i", 1, "beat carries no Gaussian");
    m.input_c("in_last_i", 1, "final beat of the subtile's list");
    m.input_c("in_origin_x_i", w.origin, "subtile top-left pixel x (first beat of a list)");
    m.input_c("in_origin_y_i", w.origin, "subtile top-left pixel y (first beat of a list)");
    m.input_c("in_cols_i", sb + 1, "columns inside the image, 0..=S (first beat)");
    m.input_c("in_rows_i", sb + 1, "rows inside the image, 0..=S (first beat)");
    m.input_c("in_final_i", 1, "with in_last_i: the piece ends the subtile (output it); else save its state");
    m.input_c(
        "in_resume_i",
        1,
        "first beat: continue subtile in_sub_i from its saved state (else start fresh)",
    );
    m.input_c(
        "in_sub_i",
        w.row_bits,
        "first beat: the subtile's state slot (pieces of several subtiles interleave)",
    );
    m.output_c("term_o", 1, "every pixel of the list being accepted is done: the rest may be skipped");
    m.output_c("out_valid_o", 1, "a finished subtile is offered");
    m.input_c("out_ready_i", 1, "taken when out_valid_o & out_ready_i");
    m.output_c("out_rgb_o", 24 * npix, "pixel k at [24k +: 24] = {blue, green, red}");

    // ---- input side: list tracking ----
    m.blank();
    m.comment("List tracking: first beat of a list, list id, the list's origin.");
    m.reg("first_in_q", 1).reg("lid_in_q", LID_BITS).reg("ox_in_q", w.origin).reg("oy_in_q", w.origin);
    m.reg("sub_in_q", w.row_bits);
    m.reg("v0_q", 1).reg("b0_q", bw).reg("p0_q", pb);
    m.reg("term_q", 1).reg("term_lid_q", LID_BITS);
    for s in 1..=STAGES {
        m.reg(format!("v{s}_q"), 1).reg(format!("d{s}_q"), bw);
    }
    m.reg("out_valid_q", 1).reg("out_rgb_q", 24 * npix);
    let f0 = |n: &str| bd.f("b0_q", n);
    let fb = |n: &str| bd.f("d5_q", n);
    m.wire_assign("in_fire", 1, "in_valid_i & in_ready_o");
    m.wire_assign("term_match", 1, format!("term_q & (term_lid_q == {})", f0("lid")));
    m.wire_assign("skip0", 1, format!("~{} & ({} | term_match)", f0("first"), f0("empty")));
    m.wire_assign("issue0", 1, format!("v0_q & ~(skip0 & ~{})", f0("last")));
    let last_pass =
        if p_n == 1 { "1'b1".to_string() } else { format!("p0_q == {}", lit(pb, p_n as u64 - 1)) };
    m.wire_assign("end0", 1, format!("skip0 | ({last_pass})"));
    m.wire_assign(
        "fin_b",
        1,
        format!(
            "v{STAGES}_q & {} & ({} | ({}))",
            fb("last"),
            fb("nop"),
            if p_n == 1 {
                "1'b1".to_string()
            } else {
                format!("{} == {}", fb("pass"), lit(pb, p_n as u64 - 1))
            }
        ),
    );
    m.wire_assign("fin_out", 1, format!("fin_b & {}", fb("fin")));
    m.wire_assign("en", 1, "~(fin_out & out_valid_q & ~out_ready_i)");
    m.assign("in_ready_o", "en & (~v0_q | end0)");
    m.assign("term_o", "term_q & (term_lid_q == lid_in_q) & ~first_in_q");
    // The beat as stored in S0.
    let mut beat: Vec<(&str, String)> = vec![
        ("mx", "in_mean_x_i".into()),
        ("my", "in_mean_y_i".into()),
        ("ca", "in_conic_a_i".into()),
        ("cb", "in_conic_b_i".into()),
        ("cc", "in_conic_c_i".into()),
        ("ce", "in_conic_exp_i".into()),
        ("op", "in_opacity_i".into()),
        ("r", "in_red_i".into()),
        ("g", "in_green_i".into()),
        ("b", "in_blue_i".into()),
        ("ox", "first_in_q ? in_origin_x_i : ox_in_q".into()),
        ("oy", "first_in_q ? in_origin_y_i : oy_in_q".into()),
        ("cols", "in_cols_i".into()),
        ("rows", "in_rows_i".into()),
        ("empty", "in_empty_i".into()),
        ("last", "in_last_i".into()),
        ("first", "first_in_q".into()),
        ("fin", "in_final_i".into()),
        ("resume", "in_resume_i".into()),
        ("sub", "first_in_q ? in_sub_i : sub_in_q".into()),
        ("lid", "lid_in_q".into()),
        ("pass", lit(pb, 0)),
        ("nop", lit(1, 0)),
    ];
    m.wire_assign(
        "beat_in",
        bw,
        format!("{{{}}}", beat.iter().rev().map(|(_, e)| format!("({e})")).collect::<Vec<_>>().join(", ")),
    );
    beat.clear();
    // The issued pass: S0's beat with its pass number and nop flag.
    let issued: Vec<String> = bd
        .fields
        .iter()
        .rev()
        .map(|&(n, _, _)| match n {
            "pass" => "p0_q".to_string(),
            "nop" => "skip0".to_string(),
            _ => f0(n),
        })
        .collect();
    m.wire_assign("issue_bundle", bw, format!("{{{}}}", issued.join(", ")));
    m.seq(
        vec![
            set("first_in_q", lit(1, 1)),
            set("lid_in_q", lit(LID_BITS, 0)),
            set("v0_q", lit(1, 0)),
            set("p0_q", lit(pb, 0)),
        ],
        vec![
            if_(
                "in_fire",
                vec![
                    set("first_in_q", "in_last_i"),
                    if_("in_last_i", vec![set("lid_in_q", format!("lid_in_q + {}", lit(LID_BITS, 1)))]),
                ],
            ),
            if_(
                "en",
                vec![if_else(
                    "v0_q & ~end0",
                    vec![set("p0_q", format!("p0_q + {}", lit(pb, 1)))],
                    vec![set("p0_q", lit(pb, 0)), set("v0_q", "in_fire")],
                )],
            ),
        ],
    );
    m.seq_noreset(vec![
        if_(
            "in_fire & first_in_q",
            vec![
                set("ox_in_q", "in_origin_x_i"),
                set("oy_in_q", "in_origin_y_i"),
                set("sub_in_q", "in_sub_i"),
            ],
        ),
        if_("in_fire", vec![set("b0_q", "beat_in")]),
    ]);
    // Valid and bundle chain.
    let mut vres = Vec::new();
    let mut vsh = Vec::new();
    let mut dsh = Vec::new();
    for s in 1..=STAGES {
        vres.push(set(format!("v{s}_q"), lit(1, 0)));
        let (vsrc, dsrc) = if s == 1 {
            ("issue0".to_string(), "issue_bundle".to_string())
        } else {
            (format!("v{}_q", s - 1), format!("d{}_q", s - 1))
        };
        vsh.push(set(format!("v{s}_q"), vsrc));
        dsh.push(set(format!("d{s}_q"), dsrc));
    }
    m.seq(vres, vec![if_("en", vsh)]);
    m.seq_noreset(vec![if_("en", dsh)]);

    // ---- lanes ----
    for l in 0..l_n {
        lane(&mut m, &w, &bd, l);
    }

    // ---- pixel state ----
    m.blank();
    m.comment("Pixel state: T, colour accumulators, done; pixel k is lane k % L of pass k / L.");
    let mut dn_all = Vec::new();
    let mut rgb_all = Vec::new();
    for k in 0..npix {
        let (g, l) = (k / l_n, k % l_n);
        let sel = if p_n == 1 {
            format!("v5_q & ~{}", fb("nop"))
        } else {
            format!("v5_q & ~{} & ({} == {})", fb("nop"), fb("pass"), lit(pb, g as u64))
        };
        m.reg(format!("t_q{k}"), w.t).reg(format!("c_q{k}"), 3 * w.c).reg(format!("dn_q{k}"), 1);
        m.wire_assign(format!("wr{k}"), 1, sel);
        m.wire_assign(format!("t_nx{k}"), w.t, format!("wr{k} ? l{l}_t_new : t_q{k}"));
        m.wire_assign(format!("c_nx{k}"), 3 * w.c, format!("wr{k} ? l{l}_c_new : c_q{k}"));
        m.wire_assign(format!("dn_nx{k}"), 1, format!("wr{k} ? l{l}_dn_new : dn_q{k}"));
        m.seq(
            vec![set(format!("dn_q{k}"), lit(1, 1))],
            vec![if_(format!("en & wr{k}"), vec![set(format!("dn_q{k}"), format!("l{l}_dn_new"))])],
        );
        m.item(on_en(vec![if_(
            format!("wr{k}"),
            vec![
                set(format!("t_q{k}"), format!("l{l}_t_new")),
                set(format!("c_q{k}"), format!("l{l}_c_new")),
            ],
        )]));
        dn_all.push(format!("dn_nx{k}"));
        let mut ch = |c: u32| {
            convert(&mut m, &w, &format!("c_nx{k}[{}:{}]", (c + 1) * w.c - 1, c * w.c), &format!("o{k}_{c}"))
        };
        let (r, g_, b) = (ch(0), ch(1), ch(2));
        rgb_all.push(format!("{b}, {g_}, {r}"));
    }
    // Lane reads: the state of pixel pass*L + l.
    for l in 0..l_n {
        let pick = |what: &str| lane_pixel(&fb("pass"), &w, l, |k| format!("{what}_q{k}"));
        m.wire_assign(format!("rd_t{l}"), w.t, pick("t"));
        m.wire_assign(format!("rd_c{l}"), 3 * w.c, pick("c"));
        m.wire_assign(format!("rd_dn{l}"), 1, pick("dn"));
    }
    m.wire_assign("all_done", 1, format!("&{{{}}}", dn_all.join(", ")));
    // Saved subtile states: a piece that ends without in_final_i stores every pixel's state,
    // and a resumed piece's first beat reads it back, both in S5, so they stay in order. One
    // small memory per pixel (one write port each; a row per subtile would be one wide memory
    // with a write port per pixel).
    let sw = w.state_bits();
    let slots = 1u32 << w.row_bits;
    m.blank();
    m.comment(format!(
        "State bank: per pixel k, bank{{k}}[slot] = {{done, colour, T}} ({sw} bits) of {} subtiles.",
        w.rows
    ));
    let mut saves = Vec::new();
    for k in 0..npix {
        m.mem(format!("bank{k}"), sw, slots);
        saves.push(set(format!("bank{k}[{}]", fb("sub")), format!("{{dn_nx{k}, c_nx{k}, t_nx{k}}}")));
    }
    m.item(on_en(vec![if_(format!("fin_b & ~{}", fb("fin")), saves)]));
    for l in 0..l_n {
        let e = lane_pixel(&fb("pass"), &w, l, |k| format!("bank{k}[{}]", fb("sub")));
        m.wire_assign(format!("bk{l}"), sw, e);
        m.wire_assign(format!("bk_t{l}"), w.t, format!("bk{l}[{}:0]", w.t - 1));
        m.wire_assign(format!("bk_c{l}"), 3 * w.c, format!("bk{l}[{}:{}]", w.t + 3 * w.c - 1, w.t));
        m.wire_assign(format!("bk_dn{l}"), 1, format!("bk{l}[{}]", sw - 1));
    }
    let last_b =
        if p_n == 1 { "1'b1".to_string() } else { format!("{} == {}", fb("pass"), lit(pb, p_n as u64 - 1)) };
    m.seq(
        vec![set("term_q", lit(1, 0)), set("term_lid_q", lit(LID_BITS, 0))],
        vec![if_(
            format!("en & v5_q & ~{}", fb("nop")),
            vec![if_else(
                last_b,
                vec![set("term_q", "all_done"), set("term_lid_q", fb("lid"))],
                vec![if_(fb("first"), vec![set("term_q", lit(1, 0))])],
            )],
        )],
    );
    m.wire_assign(
        "rgb_nx",
        24 * npix,
        format!("{{{}}}", rgb_all.iter().rev().cloned().collect::<Vec<_>>().join(", ")),
    );
    m.seq(
        vec![set("out_valid_q", lit(1, 0))],
        vec![if_else(
            "en & fin_out",
            vec![set("out_valid_q", lit(1, 1))],
            vec![if_("out_ready_i", vec![set("out_valid_q", lit(1, 0))])],
        )],
    );
    m.seq_noreset(vec![if_("en & fin_out", vec![set("out_rgb_q", "rgb_nx")])]);
    m.assign("out_valid_o", "out_valid_q");
    m.assign("out_rgb_o", "out_rgb_q");
    m
}

/// Lane `l`'s pixel of the current pass (`pass`, the bundle's pass field): `pixel(pass * L +
/// l)` selected by the pass.
fn lane_pixel(pass: &str, w: &ScuWidths, l: u32, pixel: impl Fn(u32) -> String) -> String {
    let (l_n, p_n) = (w.lanes, w.passes);
    let mut e = pixel((p_n - 1) * l_n + l);
    for g in (0..p_n - 1).rev() {
        e = format!("({pass} == {}) ? {} : {e}", lit(w.pass_bits(), g as u64), pixel(g * l_n + l));
    }
    e
}

/// `min(255, (c * 255 + 2^(K-1)) >> K)` of accumulator expression `c`; returns the 8-bit wire.
fn convert(m: &mut Module, w: &ScuWidths, c: &str, name: &str) -> String {
    let k = w.out_shift;
    let xw = w.c + 9;
    assert!(xw > k + 8, "output conversion needs more than 8 bits");
    m.wire_assign(
        format!("{name}_x"),
        xw,
        format!("{{1'b0, {c}, 8'd0}} - {} + {}", zx(c, w.c, xw), lit(xw, 1 << (k - 1))),
    );
    m.wire_assign(name, 8, format!("(|{name}_x[{}:{}]) ? 8'd255 : {name}_x[{}:{k}]", xw - 1, k + 8, k + 7));
    name.to_string()
}

/// Lane `l`: stages S1..S5 and the blend for pixel `pass * L + l`.
fn lane(m: &mut Module, w: &ScuWidths, bd: &Bundle, l: u32) {
    let (pb, lb) = (w.pass_bits(), bits_for(w.lanes as u64 - 1));
    let sb = w.side_bits;
    let ib = 2 * sb; // pixel index width
    let idx = |reg: &str| -> String {
        if w.passes == 1 {
            lit(ib, l as u64)
        } else {
            format!("{{{}, {}}}", bd.f(reg, "pass"), lit(lb, l as u64))
        }
    };
    let _ = pb;
    let s = |n: &str| format!("l{l}_{n}");
    m.blank();
    m.comment(format!("lane {l}"));
    // S0 -> S1: |dx|, |dy| and their products.
    let (d, u) = (w.d, w.u);
    let f0 = |n: &str| bd.f("issue_bundle", n);
    m.wire_assign(s("ix"), ib, idx("issue_bundle"));
    for (axis, org, mean, bits) in
        [("x", "ox", "mx", format!("[{}:0]", sb - 1)), ("y", "oy", "my", format!("[{}:{sb}]", ib - 1))]
    {
        let pxw = w.origin + 1;
        let pos = if sb == 1 {
            format!("{}[{}]", s("ix"), if axis == "x" { 0 } else { 1 })
        } else {
            format!("{}{bits}", s("ix"))
        };
        m.wire_assign(
            s(&format!("px{axis}")),
            pxw,
            format!("{} + {}", zx(&f0(org), w.origin, pxw), zx(&pos, sb, pxw)),
        );
        let mext =
            format!("{{{{{}{{{}}}}}, {}}}", d - w.mean, bd.bit("issue_bundle", mean, w.mean - 1), f0(mean));
        let pfull = format!("{{{}, l{l}_px{axis}, {}}}", lit(d - pxw - w.mean_frac, 0), lit(w.mean_frac, 0));
        m.wire_assign(s(&format!("d{axis}")), d, format!("{mext} - {pfull}"));
        m.wire_assign(
            s(&format!("a{axis}")),
            u,
            format!(
                "l{l}_d{axis}[{}] ? (~l{l}_d{axis}[{}:0] + {}) : l{l}_d{axis}[{}:0]",
                d - 1,
                u - 1,
                lit(u, 1),
                u - 1
            ),
        );
    }
    m.reg(s("sxx"), 2 * u).reg(s("syy"), 2 * u).reg(s("sxy"), 2 * u).reg(s("sneg"), 1);
    m.item(on_en(vec![
        set(s("sxx"), format!("{} * {}", zx(&s("ax"), u, 2 * u), zx(&s("ax"), u, 2 * u))),
        set(s("syy"), format!("{} * {}", zx(&s("ay"), u, 2 * u), zx(&s("ay"), u, 2 * u))),
        set(s("sxy"), format!("{} * {}", zx(&s("ax"), u, 2 * u), zx(&s("ay"), u, 2 * u))),
        set(
            s("sneg"),
            format!("{} ^ {}", format_args!("l{l}_dx[{}]", d - 1), format_args!("l{l}_dy[{}]", d - 1)),
        ),
    ]));
    // S1 -> S2: q = a dx^2 + 2 b dx dy + c dy^2, exact.
    let mt = w.mant;
    let f1 = |n: &str| bd.f("d1_q", n);
    let qw = w.q;
    let tw = mt + 2 * u + 1;
    let cb = f1("cb");
    m.wire_assign(s("cbs"), 1, sign_bit(bd, "d1_q", mt));
    m.wire_assign(s("babs"), mt + 1, format!("{} ? (~{cb} + {}) : {cb}", s("cbs"), lit(mt + 1, 1)));
    m.wire_assign(s("ta"), tw, format!("{} * {}", zx(&f1("ca"), mt, tw), zx(&s("sxx"), 2 * u, tw)));
    m.wire_assign(s("tc"), tw, format!("{} * {}", zx(&f1("cc"), mt, tw), zx(&s("syy"), 2 * u, tw)));
    m.wire_assign(
        s("tb"),
        tw + 1,
        format!("{} * {}", zx(&s("babs"), mt + 1, tw + 1), zx(&s("sxy"), 2 * u, tw + 1)),
    );
    // 2 |b| |dx dy| (the quadratic form's cross term is 2 b dx dy).
    m.wire_assign(s("tbx"), qw, zx(&format!("{{{}, 1'b0}}", s("tb")), tw + 2, qw));
    m.reg(s("q"), qw);
    m.item(on_en(vec![set(
        s("q"),
        format!(
            "{} + {} + (({} ^ {}) ? (~{} + {}) : {})",
            zx(&s("ta"), tw, qw),
            zx(&s("tc"), tw, qw),
            s("sneg"),
            s("cbs"),
            s("tbx"),
            lit(qw, 1),
            s("tbx")
        ),
    )]));
    // S2 -> S3: np = shr_round(q, sh) = ((q >>> (sh - 1)) + 1) >>> 1, saturated; skip if < 0.
    let f2 = |n: &str| bd.f("d2_q", n);
    let shw = bits_for(w.sh0 as u64 - 1 + (1u64 << w.cexp) - 1);
    m.wire_assign(s("shm1"), shw, format!("{} + {}", lit(shw, w.sh0 as u64 - 1), zx(&f2("ce"), w.cexp, shw)));
    m.wire_assign(s("qt"), qw, format!("$signed({}) >>> {}", s("q"), s("shm1")));
    m.wire_assign(s("qt1"), qw, format!("{} + {}", s("qt"), lit(qw, 1)));
    m.wire_assign(s("npf"), qw, format!("$signed({}) >>> 1", s("qt1")));
    let np = w.np;
    m.reg(s("np"), np).reg(s("pos"), 1);
    m.item(on_en(vec![
        set(
            s("np"),
            format!("(|{}[{}:{np}]) ? {} : {}[{}:0]", s("npf"), qw - 2, lit(np, w.max_np), s("npf"), np - 1),
        ),
        set(s("pos"), format!("~{}[{}] & ~{}", s("npf"), qw - 1, f2("empty"))),
    ]));
    // S3 -> S4: exp.
    m.wire(s("ex"), w.e);
    m.instance(EXP_NAME, format!("u_exp{l}"), vec![("np_i".into(), s("np")), ("e_o".into(), s("ex"))]);
    m.reg(s("e"), w.e).reg(s("ok4_"), 1);
    m.item(on_en(vec![set(s("e"), s("ex")), set(s("ok4_"), s("pos"))]));
    // S4 -> S5: alpha = min(shr_round(o * e, AS), cap); blended iff alpha >= min_alpha.
    let f4 = |n: &str| bd.f("d4_q", n);
    let ow = w.opacity;
    let pw = ow + w.e + 1;
    let a = w.alpha_frac;
    m.wire_assign(s("oe"), pw, format!("{} * {}", zx(&f4("op"), ow, pw), zx(&s("e"), w.e, pw)));
    let aw;
    if w.alpha_shift > 0 {
        let sh = w.alpha_shift as u32;
        m.wire_assign(s("oer"), pw, format!("{} + {}", s("oe"), lit(pw, 1 << (sh - 1))));
        aw = pw - sh;
        m.wire_assign(s("ar"), aw, format!("{}[{}:{sh}]", s("oer"), pw - 1));
    } else {
        let sh = (-w.alpha_shift) as u32;
        aw = pw + sh;
        m.wire_assign(
            s("ar"),
            aw,
            if sh == 0 { s("oe") } else { format!("{{{}, {}}}", s("oe"), lit(sh, 0)) },
        );
    }
    let aw2 = aw.max(a);
    m.wire_assign(s("arx"), aw2, zx(&s("ar"), aw, aw2));
    m.wire_assign(
        s("acap"),
        a,
        format!(
            "({} > {}) ? {} : {}[{}:0]",
            s("arx"),
            lit(aw2, w.max_alpha),
            lit(a, w.max_alpha),
            s("arx"),
            a - 1
        ),
    );
    m.reg(s("alpha"), a).reg(s("ok5_"), 1);
    m.item(on_en(vec![
        set(s("alpha"), s("acap")),
        set(s("ok5_"), format!("{} & ({} >= {})", s("ok4_"), s("acap"), lit(a, w.min_alpha))),
    ]));
    // Blend from S5's registers (state read-modify-write).
    let fb = |n: &str| bd.f("d5_q", n);
    let (t, c) = (w.t, w.c);
    m.wire_assign(s("ix6_"), ib, idx("d5_q"));
    let (lx, ly) = if sb == 1 {
        (format!("{}[0]", s("ix6_")), format!("{}[1]", s("ix6_")))
    } else {
        (format!("{}[{}:0]", s("ix6_"), sb - 1), format!("{}[{}:{sb}]", s("ix6_"), ib - 1))
    };
    m.wire_assign(
        s("inside"),
        1,
        format!("({} < {}) & ({} < {})", zx(&lx, sb, sb + 1), fb("cols"), zx(&ly, sb, sb + 1), fb("rows")),
    );
    let (fr, rs) = (fb("first"), fb("resume"));
    m.wire_assign(s("t_old"), t, format!("{fr} ? ({rs} ? bk_t{l} : {}) : rd_t{l}", lit(t, 1 << w.t_frac)));
    m.wire_assign(s("c_old"), 3 * c, format!("{fr} ? ({rs} ? bk_c{l} : {}) : rd_c{l}", lit(3 * c, 0)));
    m.wire_assign(s("dn_old"), 1, format!("{fr} ? ({rs} ? bk_dn{l} : ~{}) : rd_dn{l}", s("inside")));
    m.wire_assign(s("bl"), 1, format!("{} & ~{}", s("ok5_"), s("dn_old")));
    let ww = a + t + 1;
    m.wire_assign(
        s("wp"),
        ww,
        format!("{} * {} + {}", zx(&s("alpha"), a, ww), zx(&s("t_old"), t, ww), lit(ww, 1 << (a - 1))),
    );
    m.wire_assign(s("wt"), t, format!("{}[{}:{a}]", s("wp"), a + t - 1));
    m.wire_assign(s("tt"), t, format!("{} - {}", s("t_old"), s("wt")));
    m.wire_assign(s("fin"), 1, format!("{} < {}", s("tt"), lit(t, w.min_t)));
    m.wire_assign(s("add"), 1, format!("{} & ~{}", s("bl"), s("fin")));
    m.wire_assign(s("t_new"), t, format!("{} ? {} : {}", s("add"), s("tt"), s("t_old")));
    m.wire_assign(s("dn_new"), 1, format!("{} | ({} & {})", s("dn_old"), s("bl"), s("fin")));
    let mut parts = Vec::new();
    for (ch, name) in ["r", "g", "b"].iter().enumerate() {
        let ch = ch as u32;
        let old = format!("{}[{}:{}]", s("c_old"), (ch + 1) * c - 1, ch * c);
        let col = fb(name);
        m.wire_assign(
            s(&format!("cs{name}")),
            c,
            format!("{old} + {} * {}", zx(&col, w.color, c), zx(&s("wt"), t, c)),
        );
        parts.push(s(&format!("cs{name}")));
    }
    parts.reverse();
    m.wire_assign(s("c_new"), 3 * c, format!("{} ? {{{}}} : {}", s("add"), parts.join(", "), s("c_old")));
}

/// The sign bit of the conic `b` field of bundle register `reg`.
fn sign_bit(bd: &Bundle, reg: &str, mant: u32) -> String {
    let &(_, lsb, _) = bd.fields.iter().find(|f| f.0 == "cb").expect("cb field");
    format!("{reg}[{}]", lsb + mant)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exp_rom_holds_the_golden_table() {
        let cfg = GenConfig::default();
        let b = cfg.raster_config().blend;
        let t = ExpTable::new(&b.exp, b.power_frac);
        let v = exp_module(&cfg).to_verilog();
        for (j, e) in t.table().iter().enumerate().take(t.table().len() - 1) {
            assert!(v.contains(&format!("t0 = 17'd{e};")), "entry {j}");
        }
        assert!(v.contains(&format!("t1 = 17'd{};", t.table().last().unwrap())));
    }

    #[test]
    fn lanes_must_be_a_power_of_two_up_to_the_pixel_count() {
        for (lanes, ok) in [(1, false), (2, true), (3, false), (16, true), (64, true), (128, false)] {
            let cfg = GenConfig { scu_lanes: lanes, ..GenConfig::default() };
            assert_eq!(cfg.validate().is_ok(), ok, "{lanes}");
            if ok {
                let v = module(&cfg).to_verilog();
                assert_eq!(v.matches("neo_scu_exp u_exp").count(), lanes, "{lanes}");
            }
        }
    }

    #[test]
    fn widths_follow_the_golden_formats() {
        let w = ScuWidths::new(&GenConfig::default());
        assert_eq!(w.passes * w.lanes, 64);
        assert_eq!(w.max_alpha, 4055);
        assert_eq!(w.sh0, 23);
        // q: a 70-bit exact form at default widths needs no more than w.q bits.
        assert!(w.q >= 70, "{}", w.q);
        let v = module(&GenConfig::default()).to_verilog();
        assert_eq!(v.matches("neo_scu_exp u_exp").count() as u32, w.lanes);
    }
}
