//! `neo_scu` itself: the ports, list tracking and the issue stage (S0), the beat pipeline
//! (S1..S5), the `L` lanes (`g_lane[l]`: `neo_scu_lane`, `neo_scu_blend` and `neo_scu_pixels`,
//! the states of the lane's `P` pixels), subtile termination and the output register.

use super::beat::Beat;
use super::{blend, gaussian_port, lane, pixel, ScuWidths, GAUSSIAN_FIELDS, LID_BITS, NAME, STAGES};
use crate::emit::expr::{bits_for, lit};
use crate::emit::{if_, if_else, set, Instance, Item, Module};
use neo_golden::engine::EngineConfig;
use neo_golden::raster::RGB_BITS;

/// The SCU for `cfg`.
pub fn module(cfg: &EngineConfig) -> Module {
    let w = ScuWidths::new(cfg);
    let beat = Beat::new(&w);
    let mut m = Module::new(NAME);
    ports(&mut m, &w);
    beat.declare(&mut m, &w);
    issue(&mut m, &w, &beat);
    pipeline(&mut m);
    lanes(&mut m, &w, &beat);
    termination_and_output(&mut m, &w, &beat);
    covers(&mut m, &beat);
    m
}

/// Named cover points (Verilator coverage builds only): early termination, a resumed subtile,
/// a saved piece, the output stall.
fn covers(m: &mut Module, beat: &Beat) {
    let f0 = |n: &str| beat.get("b0_q", n);
    let f5 = |n: &str| beat.get("d5_q", n);
    m.covers(&[
        (
            "cov_early_termination",
            format!("v0_q & term_match & ~{} & ~{}", f0("first"), f0("empty")),
            "a Gaussian is skipped: every pixel of its list is already done",
        ),
        (
            "cov_term_offered",
            "term_o & in_valid_i".into(),
            "term_o while a beat of the finished list is offered",
        ),
        (
            "cov_resumed_subtile",
            "in_fire & first_in_q & in_resume_i".into(),
            "a list resumes its subtile from the saved state",
        ),
        (
            "cov_saved_piece",
            format!("fin_b & ~{}", f5("final")),
            "a piece ends without finishing its subtile",
        ),
        (
            "cov_output_stall",
            "fin_out & out_valid_q & ~out_ready_i".into(),
            "a finished subtile waits for the output register",
        ),
    ]);
}

fn ports(m: &mut Module, w: &ScuWidths) {
    let (l_n, p_n, sb) = (w.lanes, w.passes, w.side_bits);
    m.doc(format!(
        "Subtile Compute Unit: alpha blending of one {s}x{s} subtile, {l_n} pixel lanes x {p_n} passes (II = {p_n} cycles",
        s = w.side
    ));
    m.doc(
        "per Gaussian), bit-exact with golden raster::scu. One beat per Gaussian; in_last_i ends the list;",
    );
    m.doc(format!(
        "origin/cols/rows are taken from a list's first beat. One out beat per list: pixel k at out_rgb_o[{RGB_BITS}k +: {RGB_BITS}]"
    ));
    m.doc("= {blue, green, red}. term_o: every pixel of the list being accepted is done. See docs/rtl.md.");
    m.doc("Submodules: g_lane[l].u_lane (neo_scu_lane, S0..S5), g_lane[l].u_blend (neo_scu_blend),");
    m.doc("g_lane[l].u_pixels (neo_scu_pixels: the lane's pixels' states, saved states, output colours).");
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
    m.output_c(
        "out_rgb_o",
        RGB_BITS * w.pixels(),
        &format!("pixel k at [{RGB_BITS}k +: {RGB_BITS}] = {{blue, green, red}}"),
    );
}

/// `pass == P - 1` of a pass expression (`1'b1` with one pass).
fn last_pass(w: &ScuWidths, pass: &str) -> String {
    if w.passes == 1 {
        lit(1, 1)
    } else {
        format!("{pass} == {}", lit(w.pass_bits(), w.passes as u64 - 1))
    }
}

/// List tracking and S0: the beat register, the pass counter, skipping and the global stall.
fn issue(m: &mut Module, w: &ScuWidths, beat: &Beat) {
    let pb = w.pass_bits();
    let f0 = |n: &str| beat.get("b0_q", n);
    let f5 = |n: &str| beat.get("d5_q", n);
    m.blank();
    m.comment("List tracking: the next beat is a list's first; the list id; the list's origin and slot.");
    m.reg("first_in_q", 1).reg("lid_in_q", LID_BITS);
    m.reg("origin_x_in_q", w.origin).reg("origin_y_in_q", w.origin).reg("sub_in_q", w.row_bits);
    m.comment("S0 (issue): the beat, held for its passes; p0_q is the pass being issued.");
    m.reg("v0_q", 1).reg("b0_q", beat.width).reg("p0_q", pb);
    m.comment(format!("S1..S{STAGES}: valid bit v<s>_q and beat d<s>_q of each stage."));
    for s in 1..=STAGES {
        m.reg(format!("v{s}_q"), 1).reg(format!("d{s}_q"), beat.width);
    }
    m.comment("Subtile termination: every pixel of list term_lid_q is done.");
    m.reg("term_q", 1).reg("term_lid_q", LID_BITS);
    m.comment("Output register: a finished subtile's colours are offered (they sit in the lanes' u_pixels).");
    m.reg("out_valid_q", 1);
    if w.passes > 1 {
        m.comment("The pass in S5.");
        m.wire_assign("pass5", w.pass_bits(), f5("pass"));
    }
    m.wire_assign("in_fire", 1, "in_valid_i & in_ready_o");
    m.comment("A beat after every pixel of its list is done (or an empty one) is skipped, not evaluated.");
    m.wire_assign("term_match", 1, format!("term_q & (term_lid_q == {})", f0("lid")));
    m.wire_assign("skip0", 1, format!("~{} & ({} | term_match)", f0("first"), f0("empty")));
    m.wire_assign("issue0", 1, format!("v0_q & ~(skip0 & ~{})", f0("last")));
    m.wire_assign("end0", 1, format!("skip0 | ({})", last_pass(w, "p0_q")));
    m.comment(
        "S5 holds the last pass of a list (piece); fin_out: a finished subtile enters the output register.",
    );
    m.wire_assign(
        "fin_b",
        1,
        format!("v{STAGES}_q & {} & ({} | ({}))", f5("last"), f5("nop"), last_pass(w, "pass5")),
    );
    m.wire_assign("fin_out", 1, format!("fin_b & {}", f5("final")));
    m.comment("The global stall: a finished subtile waits for the output register.");
    m.wire_assign("en", 1, "~(fin_out & out_valid_q & ~out_ready_i)");
    m.assign("in_ready_o", "en & (~v0_q | end0)");
    m.assign("term_o", "term_q & (term_lid_q == lid_in_q) & ~first_in_q");
    accepted_beat(m, w, beat);
    m.comment("d1_d: the issued pass, S0's beat with its pass number and skip flag (S1's next beat).");
    m.wire_assign("d1_d", beat.width, format!("{{skip0, p0_q, b0_q[{} - 1:0]}}", beat.offset("pass")));
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
                set("origin_x_in_q", "in_origin_x_i"),
                set("origin_y_in_q", "in_origin_y_i"),
                set("sub_in_q", "in_sub_i"),
            ],
        ),
        if_("in_fire", vec![set("b0_q", "b0_d")]),
    ]);
}

/// `b0_d`: the accepted beat, field by field; the origin and slot are the list's (first beat's).
fn accepted_beat(m: &mut Module, w: &ScuWidths, beat: &Beat) {
    let pb = w.pass_bits();
    m.comment("b0_d: the accepted beat (S0's next beat).");
    m.wire("b0_d", beat.width);
    for field in GAUSSIAN_FIELDS {
        m.assign(beat.get("b0_d", field), gaussian_port(field));
    }
    for (name, src) in [
        ("origin_x", "first_in_q ? in_origin_x_i : origin_x_in_q"),
        ("origin_y", "first_in_q ? in_origin_y_i : origin_y_in_q"),
        ("cols", "in_cols_i"),
        ("rows", "in_rows_i"),
        ("empty", "in_empty_i"),
        ("last", "in_last_i"),
        ("first", "first_in_q"),
        ("final", "in_final_i"),
        ("resume", "in_resume_i"),
        ("sub", "first_in_q ? in_sub_i : sub_in_q"),
        ("lid", "lid_in_q"),
        ("pass", &lit(pb, 0)),
        ("nop", &lit(1, 0)),
    ] {
        m.assign(beat.get("b0_d", name), src);
    }
    let names = beat.names();
    assert_eq!(names[names.len() - 2..], ["pass", "nop"], "the issue fields are the bundle's top");
}

/// S1..S5: the valid bits and the beat registers, all advancing on `en`.
fn pipeline(m: &mut Module) {
    m.blank();
    m.comment(format!("S1..S{STAGES} advance together."));
    let mut vres = Vec::new();
    let mut vsh = Vec::new();
    let mut dsh = Vec::new();
    for s in 1..=STAGES {
        vres.push(set(format!("v{s}_q"), lit(1, 0)));
        let (vsrc, dsrc) = if s == 1 {
            ("issue0".to_string(), "d1_d".to_string())
        } else {
            (format!("v{}_q", s - 1), format!("d{}_q", s - 1))
        };
        vsh.push(set(format!("v{s}_q"), vsrc));
        dsh.push(set(format!("d{s}_q"), dsrc));
    }
    m.seq(vres, vec![if_("en", vsh)]);
    m.seq_noreset(vec![if_("en", dsh)]);
}

/// `{pass, LANE}`: the pixel a lane evaluates in the pass of bundle `reg` (`LANE` alone with one
/// pass).
fn lane_pixel(w: &ScuWidths, beat: &Beat, reg: &str) -> String {
    if w.passes == 1 {
        "LANE".to_string()
    } else {
        format!("{{{}, LANE}}", beat.get(reg, "pass"))
    }
}

/// The `g_lane` block: lane `l`'s pipeline (`u_lane`), its blend (`u_blend`) and its pixels
/// (`u_pixels`: the states of pixels `p*L + l`, their saved states and output colours).
fn lanes(m: &mut Module, w: &ScuWidths, beat: &Beat) {
    let (l_n, p_n) = (w.lanes, w.passes);
    let n = w.pixels();
    m.blank();
    m.comment("Pixel k = p*L + l is written by lane l when pass p is blended in S5.");
    m.wire_assign("wr5", 1, format!("v{STAGES}_q & ~{}", beat.get("d5_q", "nop")));
    m.comment("save: a piece that does not end its subtile ends in S5; its pixels' states go to its slot.");
    m.wire_assign("save", 1, format!("fin_b & ~{}", beat.get("d5_q", "final")));
    m.comment("Every lane's next done bits (lane l at [l*P +: P]) and output colours (at [l*P*24 +: P*24]).");
    m.wire("done_d", n).wire("lane_rgb", RGB_BITS * n);
    let mut body = vec![
        Item::LocalParam { name: "LANE".into(), width: bits_for(l_n as u64 - 1), value: "l".into() },
        Item::Wire { name: "alpha".into(), width: w.alpha_frac },
        Item::Wire { name: "blend".into(), width: 1 },
    ];
    for (v, width) in state_fields(w) {
        for wire in [format!("cur_{v}"), format!("saved_{v}"), format!("new_{v}")] {
            body.push(Item::Wire { name: wire, width });
        }
    }
    for (module, name, conns) in [
        (lane::NAME, "u_lane", lane_conns(w, beat)),
        (blend::NAME, "u_blend", blend_conns(w, beat)),
        (pixel::NAME, "u_pixels", pixel_conns(w, beat)),
    ] {
        body.push(Item::Instance(Instance {
            module: module.into(),
            name: name.into(),
            params: Vec::new(),
            conns,
        }));
    }
    m.comment("Lane l evaluates pixel p*L + l in pass p, S0 -> S5, blends it and keeps its state.");
    m.gen_for("l", l_n, "g_lane", body);
    m.comment("Output pixel k = p*L + l: lane l's pixel p.");
    let out = Item::Assign {
        lhs: format!("out_rgb_o[k*{RGB_BITS} +: {RGB_BITS}]"),
        rhs: format!("lane_rgb[((k % {l_n})*{p_n} + k / {l_n})*{RGB_BITS} +: {RGB_BITS}]"),
    };
    m.gen_for("k", n, "g_out", vec![out]);
}

/// A pixel's state fields and their widths: transmittance, colour accumulators, done. Lane
/// `l` carries each as `cur_*` (the pass's pixel), `saved_*` (as saved in the slot) and `new_*`
/// (blended).
fn state_fields(w: &ScuWidths) -> [(&'static str, u32); 3] {
    [("t", w.t), ("c", 3 * w.c), ("done", 1)]
}

/// `u_lane`'s connections: S1..S5 of the pixel of the beat's pass.
fn lane_conns(w: &ScuWidths, beat: &Beat) -> Vec<(String, String)> {
    let f = |reg: &str, n: &str| beat.get(reg, n);
    named(vec![
        ("clk_i", "clk_i".to_string()),
        ("en_i", "en".into()),
        ("pixel_i", lane_pixel(w, beat, "d1_d")),
        ("mean_x_i", f("d1_d", "mean_x")),
        ("mean_y_i", f("d1_d", "mean_y")),
        ("origin_x_i", f("d1_d", "origin_x")),
        ("origin_y_i", f("d1_d", "origin_y")),
        ("conic_a_i", f("d1_q", "conic_a")),
        ("conic_b_i", f("d1_q", "conic_b")),
        ("conic_c_i", f("d1_q", "conic_c")),
        ("conic_exp_i", f("d2_q", "conic_exp")),
        ("empty_i", f("d2_q", "empty")),
        ("opacity_i", f("d4_q", "opacity")),
        ("alpha_o", "alpha".into()),
        ("blend_o", "blend".into()),
    ])
}

/// `u_blend`'s connections: S5's beat and alpha, the pixel's state now and as saved, its new
/// state.
fn blend_conns(w: &ScuWidths, beat: &Beat) -> Vec<(String, String)> {
    let mut conns = vec![("pixel_i".to_string(), lane_pixel(w, beat, "d5_q"))];
    for n in ["cols", "rows", "first", "resume"].into_iter().chain(blend::CHANNELS) {
        conns.push((format!("{n}_i"), beat.get("d5_q", n)));
    }
    conns.extend(named(vec![("alpha_i", "alpha".to_string()), ("blend_i", "blend".into())]));
    for (v, _) in state_fields(w) {
        conns.push((format!("{v}_i"), format!("cur_{v}")));
        conns.push((format!("saved_{v}_i"), format!("saved_{v}")));
        conns.push((format!("{v}_o"), format!("new_{v}")));
    }
    conns
}

/// `u_pixels`' connections: the write of S5's pass, the save, the output register's load; the
/// pass's pixel's state now and as saved, the lane's next done bits and output colours.
fn pixel_conns(w: &ScuWidths, beat: &Beat) -> Vec<(String, String)> {
    let p_n = w.passes;
    let mut conns = named(vec![
        ("clk_i", "clk_i".to_string()),
        ("rst_ni", "rst_ni".into()),
        ("en_i", "en".into()),
        ("wr_i", "wr5".into()),
    ]);
    if p_n > 1 {
        conns.push(("pass_i".into(), "pass5".into()));
    }
    for (v, _) in state_fields(w) {
        conns.push((format!("{v}_i"), format!("new_{v}")));
    }
    conns.extend(named(vec![
        ("save_i", "save".to_string()),
        ("slot_i", beat.get("d5_q", "sub")),
        ("out_i", "en & fin_out".into()),
    ]));
    for (v, _) in state_fields(w) {
        conns.push((format!("{v}_o"), format!("cur_{v}")));
    }
    for (v, _) in state_fields(w) {
        conns.push((format!("saved_{v}_o"), format!("saved_{v}")));
    }
    conns.extend(named(vec![
        ("done_d_o", format!("done_d[l*{p_n} +: {p_n}]")),
        ("rgb_o", format!("lane_rgb[l*{} +: {}]", RGB_BITS * p_n, RGB_BITS * p_n)),
    ]));
    conns
}

/// Named connections `(port, expression)` with owned port names.
fn named(pairs: Vec<(&str, String)>) -> Vec<(String, String)> {
    pairs.into_iter().map(|(p, e)| (p.to_string(), e)).collect()
}

/// Subtile termination (`term_q`) and the output register.
fn termination_and_output(m: &mut Module, w: &ScuWidths, beat: &Beat) {
    let f5 = |n: &str| beat.get("d5_q", n);
    m.blank();
    m.comment("After a Gaussian's last pass: is every pixel of the list done?");
    m.wire_assign("all_done", 1, "&done_d");
    m.seq(
        vec![set("term_q", lit(1, 0)), set("term_lid_q", lit(LID_BITS, 0))],
        vec![if_(
            format!("en & v{STAGES}_q & ~{}", f5("nop")),
            vec![if_else(
                last_pass(w, "pass5"),
                vec![set("term_q", "all_done"), set("term_lid_q", f5("lid"))],
                vec![if_(f5("first"), vec![set("term_q", lit(1, 0))])],
            )],
        )],
    );
    m.blank();
    m.comment("Output register.");
    m.seq(
        vec![set("out_valid_q", lit(1, 0))],
        vec![if_else(
            "en & fin_out",
            vec![set("out_valid_q", lit(1, 1))],
            vec![if_("out_ready_i", vec![set("out_valid_q", lit(1, 0))])],
        )],
    );
    m.assign("out_valid_o", "out_valid_q");
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::units::scu::exp;

    #[test]
    fn lanes_must_be_a_power_of_two_up_to_the_pixel_count() {
        for (lanes, ok) in [(1, false), (2, true), (3, false), (16, true), (64, true), (128, false)] {
            let cfg = EngineConfig { scu_lanes: lanes, ..EngineConfig::default() };
            assert_eq!(cfg.validate().is_ok(), ok, "{lanes}");
            if ok {
                let v = module(&cfg).to_verilog();
                assert!(
                    v.contains(&format!("for (l = 0; l < {lanes}; l = l + 1) begin : g_lane")),
                    "{lanes}"
                );
                assert!(v.contains("for (k = 0; k < 64; k = k + 1) begin : g_out"), "{lanes}");
                assert_eq!(v.matches("neo_scu_pixels u_pixels").count(), 1, "{lanes}");
                assert_eq!(v.matches("neo_scu_lane u_lane").count(), 1, "{lanes}");
            }
        }
        let lane = lane::module(&EngineConfig::default()).to_verilog();
        assert_eq!(lane.matches(&format!("{} u_exp", exp::NAME)).count(), 1);
    }

    /// Every access to a beat register goes through a named field (`reg[BEAT_NAME ...]`).
    #[test]
    fn beat_registers_are_read_by_named_fields_only() {
        for lanes in [2, 16, 64] {
            let cfg = EngineConfig { scu_lanes: lanes, ..EngineConfig::default() };
            let v = module(&cfg).to_verilog();
            for reg in ["b0_d", "b0_q", "d1_d", "d1_q", "d2_q", "d3_q", "d4_q", "d5_q"] {
                for (k, _) in v.match_indices(&format!("{reg}[")) {
                    let rest = &v[k + reg.len() + 1..];
                    assert!(rest.starts_with("BEAT_"), "{lanes} lanes: raw index {reg}[{}", &rest[..12]);
                }
            }
        }
    }

    /// The SCU and its submodules stay short enough to review.
    #[test]
    fn the_scu_fits_in_1500_lines() {
        let cfg = EngineConfig::default();
        let lines: usize =
            [module(&cfg), lane::module(&cfg), blend::module(&cfg), pixel::module(&cfg), exp::module(&cfg)]
                .iter()
                .map(|m| m.to_verilog().lines().count())
                .sum();
        assert!(lines < 1500, "{lines} lines");
    }
}
