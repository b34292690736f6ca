//! `neo_pre_lane`: one lane of the Preprocessing Engine, from baked Gaussians in memory to their
//! feature words in memory (paper Section 5.2: a projection and a colour unit per lane; the
//! duplication unit joins it with the incoming lists). The lane takes the Gaussians
//! `first_i .. first_i + count_i` in index order:
//!
//! 1. `u_geo` (`neo_pre_fetch`) streams their geometry records from `geo_base_i` (record of
//!    `first_i`) on port `ma_axi_*`; each goes to the projection unit `u_project`, its position
//!    to the queue `u_posq` (the colour unit needs it after the projection).
//! 2. A projected Gaussian enters the queue `u_pendq` with its feature fields and position; a
//!    visible one also asks `u_sh` (`neo_pre_fetch`, port `mb_axi_*`) for its SH record at
//!    `sh_base_i + 4 sh_words_i id` (one-record gathers: SH is read only for visible Gaussians).
//! 3. The head of `u_pendq` enters the colour unit `u_color` with its SH record (a culled one
//!    with zeros, its colour unused) and its fields move to `u_colq`.
//! 4. The colour and the head of `u_colq` make the feature word `{present, entry}` (golden
//!    `engine::memory::feature_to_bytes`; 0 for a culled Gaussian), written as one 4-beat burst at
//!    `feat_base_i + 32 id` on `ma_axi_*` (at most `axi_outstanding` writes without their B).
//!
//! Everything stays in index order, so ids are counters. `busy_o` rises on `start_i` and falls
//! when every word's B is back. The per-frame inputs (the camera, `degree_i`, the bases) must be
//! stable from `start_i` on; the lane waits the units' settle cycles before its first read.

use super::datapath::Datapath;
use super::fetch::{self, max_record_words, COUNT_BITS};
use super::library::PreLibrary;
use super::writer::{self, Writes};
use super::{fifo, COLOR_NAME, PROJECT_NAME};
use crate::emit::bundle::{Bundle, Field};
use crate::emit::expr::{bits_for, lit, zext};
use crate::emit::{if_, if_else, set, Instance, Item, Module};
use crate::interface::Dir;
use crate::units::axi;
use crate::units::fp::conv::WIDEN_HALF_COMB_NAME;
use neo_golden::engine::memory::FEATURE_BYTES;
use neo_golden::engine::EngineConfig;
use neo_golden::hwpre::bake::geometry_bytes;
use neo_golden::hwpre::color::color_graph;
use neo_golden::hwpre::project::project_graph;

/// Module name.
pub const NAME: &str = "neo_pre_lane";

/// Depth of the colour queue `u_colq` (Gaussians between the colour unit's input and output).
fn colq_depth(color_depth: u32) -> u32 {
    (color_depth + 4).next_power_of_two()
}

/// Depth of the position queue `u_posq` (Gaussians inside the projection unit).
fn posq_depth(project_depth: u32) -> u32 {
    (project_depth + 4).next_power_of_two()
}

/// Gaussians projected and waiting for their SH record (`u_pendq`): enough to cover the SH
/// fetch unit's window in records of degree 3.
pub const PEND_DEPTH: u32 = 64;

/// The lane's sizes: the units' depths and settle cycles, the queues' widths.
pub struct LaneDims {
    /// Projection and colour unit depths.
    pub project_depth: u32,
    /// Colour unit depth.
    pub color_depth: u32,
    /// Cycles the per-frame inputs need before the first Gaussian.
    pub settle: u32,
    /// The feature fields the projection makes (layout order, without the colour): (name, width).
    pub fields: Vec<(String, u32)>,
}

impl LaneDims {
    /// The sizes for `cfg`.
    pub fn new(cfg: &EngineConfig) -> LaneDims {
        let pg = project_graph(&super::project_params(cfg));
        let cg = color_graph(&cfg.feature_format().color);
        let (p, c) = (Datapath::new(&pg, &PreLibrary), Datapath::new(&cg, &PreLibrary));
        let fields = cfg
            .feature_format()
            .layout()
            .iter()
            .filter(|f| !COLOR_FIELDS.contains(&f.name))
            .map(|f| (f.name.to_string(), f.width))
            .collect();
        LaneDims {
            project_depth: p.depth(),
            color_depth: c.depth(),
            settle: p.settle_cycles().max(c.settle_cycles()),
            fields,
        }
    }

    /// Bits of the projection's feature fields.
    fn fields_bits(&self) -> u32 {
        self.fields.iter().map(|f| f.1).sum()
    }
}

/// Runs of feature fields the duplication unit takes whole: (name, first field, last field).
const ITU_RUNS: [(&str, &str, &str); 2] =
    [("itu_mean", "mean_x", "mean_y"), ("itu_geom", "extent_x", "extent_v")];

impl LaneDims {
    /// The fields' own layout from `base` up, then the `visible` bit, and the runs over them.
    fn entry_fields(&self, base: u32) -> Vec<Field> {
        let mut out = Vec::new();
        let mut lsb = base;
        for (n, w) in &self.fields {
            out.push(Field { name: n.clone(), lsb, width: *w });
            lsb += w;
        }
        out.push(Field { name: "visible".into(), lsb, width: 1 });
        out.push(Field { name: "fields".into(), lsb: base, width: lsb - base });
        out.push(Field { name: "entry".into(), lsb: base, width: lsb + 1 - base });
        for (run, a, b) in ITU_RUNS {
            let (lo, hi) = (out.iter().find(|f| f.name == a), out.iter().find(|f| f.name == b));
            let (lo, hi) = (lo.expect("run start").lsb, hi.map(|f| f.lsb + f.width).expect("run end"));
            out.push(Field { name: run.into(), lsb: lo, width: hi - lo });
        }
        out
    }

    /// `u_pendq`'s word: the position (`pos_x`, `pos_y`, `pos_z`), the fields, `visible`.
    fn pend(&self) -> Bundle {
        let mut f: Vec<Field> = ["pos_x", "pos_y", "pos_z"]
            .iter()
            .enumerate()
            .map(|(k, n)| Field { name: n.to_string(), lsb: 32 * k as u32, width: 32 })
            .collect();
        f.extend(self.entry_fields(96));
        Bundle::placed("PEND", f)
    }

    /// `u_colq`'s word: the fields and `visible`.
    fn colq(&self) -> Bundle {
        Bundle::placed("COLQ", self.entry_fields(0))
    }
}

/// The feature word in memory (golden's layout, `present` on top) as the duplication unit reads
/// the previous one: `present` and the ITU runs.
fn prev_word(cfg: &EngineConfig) -> Bundle {
    let fmt = cfg.feature_format();
    let lay = fmt.layout();
    let at = |n: &str| lay.iter().find(|f| f.name == n).unwrap_or_else(|| panic!("no feature field {n}"));
    let mut f = vec![Field { name: "present".into(), lsb: fmt.bits_per_entry(), width: 1 }];
    for (run, a, b) in ITU_RUNS {
        let (lo, hi) = (at(a).lsb, at(b).lsb + at(b).width);
        f.push(Field { name: run.into(), lsb: lo, width: hi - lo });
    }
    Bundle::placed("PREVW", f)
}

/// The feature fields the colour unit makes (its outputs `out_<name>_o`).
const COLOR_FIELDS: [&str; 3] = ["red", "green", "blue"];

/// The per-frame inputs of `module_name` (its `_i` ports other than the clock, reset and the
/// `in_*` / `out_*` handshakes), as (name, width).
fn frame_inputs(m: &Module) -> Vec<(String, u32)> {
    m.interface()
        .ports
        .into_iter()
        .filter(|p| p.dir == Dir::In && !p.name.starts_with("in_") && !p.name.starts_with("out_"))
        .filter(|p| p.name != "clk_i" && p.name != "rst_ni")
        .map(|p| (p.name, p.width))
        .collect()
}

/// The lane for `cfg`.
pub fn module(cfg: &EngineConfig) -> Module {
    let d = LaneDims::new(cfg);
    let (project, color) = (super::project_module(cfg), super::color_module(cfg));
    let mut m = Module::new(NAME);
    m.doc(
        "Preprocessing lane: baked Gaussians first_i .. first_i + count_i to their feature words: geometry",
    );
    m.doc("stream (u_geo) -> projection (u_project) -> SH gather of the visible ones (u_sh) -> colour (u_color)");
    m.doc("-> feature word at feat_base_i + 32 id. Reads and writes on ma_axi_*, SH reads on mb_axi_*.");
    m.clock_reset();
    m.input_c("start_i", 1, "pulse: process the Gaussians (ignored while busy_o)");
    m.output_c("busy_o", 1, "from start_i to the last feature word's B");
    let statics: Vec<(String, u32)> =
        frame_inputs(&project).into_iter().chain(frame_inputs(&color)).collect();
    for (name, w) in &statics {
        m.input_c(name.clone(), *w, "per frame");
    }
    let (ab, wb) = (cfg.axi_addr_bits, bits_for(u64::from(max_record_words())));
    m.input_c("geo_base_i", ab, "byte address of Gaussian first_i's geometry record");
    m.input_c("sh_base_i", ab, "byte address of Gaussian 0's SH record");
    m.input_c("sh_words_i", wb, "words of an SH record (golden engine::pre::sh_record_words)");
    m.input_c("sh_half_i", 1, "SH records hold binary16 coefficients (two a word, the even one low)");
    m.input_c("feat_base_i", ab, "byte address of Gaussian 0's feature word (32-byte aligned)");
    m.input_c("prev_base_i", ab, "byte address of Gaussian 0's previous feature word");
    m.input_c("all_fresh_i", 1, "no table is reused: every Gaussian is incoming, no previous word read");
    m.input_c("first_i", COUNT_BITS, "the lane's first Gaussian");
    m.input_c("count_i", COUNT_BITS, "the lane's Gaussians");
    m.output_c("hit_valid_o", 1, "an incoming (Gaussian, tile) is offered");
    m.input_c("hit_ready_i", 1, "it is taken");
    m.output_c("hit_tile_x_o", cfg.tile_bits, "tile column");
    m.output_c("hit_tile_y_o", cfg.tile_bits, "tile row");
    m.output_c("hit_id_o", u32::from(cfg.id_bits), "Gaussian id");
    m.output_c("hit_key_o", u32::from(cfg.key_bits), "depth key");
    axi::ports(&mut m, cfg, "ma_axi_", true);
    axi::ports(&mut m, cfg, "mb_axi_", true);
    control(&mut m, &d);
    geometry(&mut m, cfg, &project, &d);
    projected(&mut m, cfg, &project, &d);
    colour(&mut m, &color, &d);
    duplicate(&mut m, cfg, &d);
    writer(&mut m, cfg, &d);
    m
}

/// Start, settle and the counters; `busy_o`.
fn control(m: &mut Module, d: &LaneDims) {
    let sb = bits_for(u64::from(d.settle) + 1);
    m.blank();
    m.comment(format!("Control: after start_i, {} settle cycles, then the geometry command.", d.settle));
    m.reg("run_q", 1).reg("settle_q", sb).reg("geo_cmd_q", 1);
    m.reg("proj_idx_q", COUNT_BITS).reg("wr_idx_q", COUNT_BITS).reg("done_idx_q", COUNT_BITS);
    m.reg("join_idx_q", COUNT_BITS);
    m.wire_assign("take_start", 1, "start_i & ~run_q");
    m.wire_assign("settled", 1, format!("settle_q == {}", lit(sb, 0)));
    m.seq(
        vec![
            set("run_q", lit(1, 0)),
            set("settle_q", lit(sb, 0)),
            set("geo_cmd_q", lit(1, 0)),
            set("proj_idx_q", lit(COUNT_BITS, 0)),
            set("wr_idx_q", lit(COUNT_BITS, 0)),
            set("done_idx_q", lit(COUNT_BITS, 0)),
            set("join_idx_q", lit(COUNT_BITS, 0)),
        ],
        vec![if_else(
            "take_start",
            vec![
                set("run_q", lit(1, 1)),
                set("settle_q", lit(sb, u64::from(d.settle))),
                set("geo_cmd_q", lit(1, 1)),
                set("proj_idx_q", lit(COUNT_BITS, 0)),
                set("wr_idx_q", lit(COUNT_BITS, 0)),
                set("done_idx_q", lit(COUNT_BITS, 0)),
                set("join_idx_q", lit(COUNT_BITS, 0)),
            ],
            vec![
                if_("~settled", vec![set("settle_q", format!("settle_q - {}", lit(sb, 1)))]),
                if_("geo_cmd_take", vec![set("geo_cmd_q", lit(1, 0))]),
                if_("proj_take", vec![set("proj_idx_q", format!("proj_idx_q + {}", lit(COUNT_BITS, 1)))]),
                if_("word_take", vec![set("wr_idx_q", format!("wr_idx_q + {}", lit(COUNT_BITS, 1)))]),
                if_("b_fire", vec![set("done_idx_q", format!("done_idx_q + {}", lit(COUNT_BITS, 1)))]),
                if_("c_take", vec![set("join_idx_q", format!("join_idx_q + {}", lit(COUNT_BITS, 1)))]),
                if_(
                    "run_q & ~geo_cmd_q & (done_idx_q == count_i) & d_idle & wr_idle",
                    vec![set("run_q", lit(1, 0))],
                ),
            ],
        )],
    );
    m.assign("busy_o", "run_q");
}

/// Connections of a fetch unit's AXI4 port: its reads to `prefix` (`ma_axi_`), its idle write
/// channels to `<unit>_w_*` wires (outputs) and constants (inputs).
fn fetch_axi(m: &mut Module, cfg: &EngineConfig, unit: &str, prefix: &str) -> Vec<(String, String)> {
    let mut c = Vec::new();
    let mut idle = Vec::new();
    for s in axi::signals(cfg) {
        let port = axi::port_name("m_axi_", &s, true);
        let read = s.name.starts_with("ar") || s.name.starts_with('r');
        if read {
            c.push((port, axi::port_name(prefix, &s, true)));
        } else if s.from_manager {
            let w = format!("{unit}_w_{}", s.name);
            m.wire(w.clone(), s.width);
            idle.push(w.clone());
            c.push((port, w));
        } else {
            c.push((port, lit(s.width, 0)));
        }
    }
    m.wire_assign(format!("unused_{unit}_w"), 1, format!("^{{{}}}", idle.join(", ")));
    c
}

fn conn(a: &str, b: impl Into<String>) -> (String, String) {
    (a.to_string(), b.into())
}

/// `u_geo` -> `u_project` (and `u_posq`).
fn geometry(m: &mut Module, cfg: &EngineConfig, project: &Module, d: &LaneDims) {
    let (wb, gw) = (bits_for(u64::from(max_record_words())), geometry_bytes() / 4);
    let rw = max_record_words() * 32;
    m.blank();
    m.comment("Geometry: one command for the lane's records; each record to the projection unit.");
    m.wire("geo_cmd_ready", 1).wire("geo_busy", 1).wire("geo_valid", 1).wire("geo_ready", 1);
    m.wire("geo_rec", rw).wire("geo_index", COUNT_BITS);
    m.wire_assign("geo_cmd_take", 1, "geo_cmd_q & settled & geo_cmd_ready");
    let mut c = vec![conn("clk_i", "clk_i"), conn("rst_ni", "rst_ni")];
    c.push(conn("cmd_valid_i", "geo_cmd_q & settled"));
    c.push(conn("cmd_ready_o", "geo_cmd_ready"));
    c.push(conn("cmd_base_i", "geo_base_i"));
    c.push(conn("cmd_words_i", lit(wb, u64::from(gw))));
    c.push(conn("cmd_count_i", "count_i"));
    c.extend([
        conn("busy_o", "geo_busy"),
        conn("rec_valid_o", "geo_valid"),
        conn("rec_ready_i", "geo_ready"),
    ]);
    c.extend([conn("rec_data_o", "geo_rec"), conn("rec_index_o", "geo_index")]);
    c.extend(fetch_axi(m, cfg, "geo", "ma_axi_"));
    m.instance(fetch::NAME, "u_geo", c);
    m.wire_assign("unused_geo", 1, format!("^{{geo_busy, geo_index, geo_rec[{}:{}]}}", rw - 1, 32 * gw));

    m.wire("posq_ready", 1).wire("p_in_ready", 1).wire("proj_take", 1);
    m.assign("geo_ready", "p_in_ready & posq_ready");
    let pq = posq_depth(d.project_depth);
    m.wire("posq_valid", 1).wire("posq_data", 96);
    m.item(fifo::instance(
        96,
        pq,
        "u_posq",
        vec![
            conn("clk_i", "clk_i"),
            conn("rst_ni", "rst_ni"),
            conn("push_valid_i", "geo_valid & p_in_ready"),
            conn("push_ready_o", "posq_ready"),
            conn("push_data_i", "geo_rec[95:0]"),
            conn("pop_valid_o", "posq_valid"),
            conn("pop_ready_i", "proj_take"),
            conn("pop_data_o", "posq_data"),
        ],
    ));
    m.comment(
        "The position queue holds an entry for every Gaussian inside u_project: never empty at its output.",
    );
    m.wire_assign("unused_posq", 1, "posq_valid");
    let mut c = vec![conn("clk_i", "clk_i"), conn("rst_ni", "rst_ni")];
    let ins: Vec<String> = project
        .interface()
        .ports
        .into_iter()
        .filter(|p| p.dir == Dir::In && p.name.starts_with("in_") && p.name != "in_valid_i")
        .map(|p| p.name)
        .collect();
    assert_eq!(ins.len() as u32, gw, "{PROJECT_NAME} takes the geometry record's {gw} words");
    for (k, p) in ins.iter().enumerate() {
        c.push((p.clone(), format!("geo_rec[{}:{}]", 32 * k + 31, 32 * k)));
    }
    c.push(conn("in_valid_i", "geo_valid & posq_ready"));
    c.push(conn("in_ready_o", "p_in_ready"));
    for p in project.interface().ports.iter().filter(|p| p.dir == Dir::In && !p.name.starts_with("in_")) {
        if !["out_ready_i", "clk_i", "rst_ni"].contains(&p.name.as_str()) {
            c.push((p.name.clone(), p.name.clone()));
        }
    }
    c.push(conn("out_ready_i", "p_out_ready"));
    for p in project.interface().ports.iter().filter(|p| p.dir == Dir::Out && p.name != "in_ready_o") {
        let w = format!("p_{}", p.name.trim_start_matches("out_").trim_end_matches("_o"));
        m.wire(w.clone(), p.width);
        c.push((p.name.clone(), w));
    }
    m.wire("p_out_ready", 1);
    m.instance(PROJECT_NAME, "u_project", c);
}

/// The projected Gaussian: the pending queue and the SH gather.
fn projected(m: &mut Module, cfg: &EngineConfig, project: &Module, d: &LaneDims) {
    let (ab, fb) = (cfg.axi_addr_bits, d.fields_bits());
    let pw = 1 + fb + 96;
    m.blank();
    m.comment(
        "Projected: into u_pendq {visible, fields, position}; a visible Gaussian's SH record gathered.",
    );
    let fields: Vec<String> = d.fields.iter().rev().map(|(n, w)| format!("p_{n}[{}:0]", w - 1)).collect();
    m.wire_assign("p_fields", fb, format!("{{{}}}", fields.join(", ")));
    let used: Vec<String> = d
        .fields
        .iter()
        .filter(|(_, w)| *w < 32)
        .map(|(n, w)| format!("p_{n}[31:{w}]"))
        .chain(project_unused(project, d))
        .collect();
    m.wire_assign("unused_p", 1, format!("^{{{}}}", used.join(", ")));
    m.wire("pend_ready", 1).wire("sh_cmd_ready", 1);
    m.comment("A visible Gaussian asks u_sh for its previous feature word (unless all_fresh_i), then,");
    m.comment("the next cycle (shc_q), for its SH record: the records come back in that order.");
    m.reg("shc_q", 1).reg("shc_addr_q", ab);
    m.wire_assign("sh_cmd_valid", 1, "shc_q | (p_valid & p_visible & pend_ready)");
    m.assign("p_out_ready", "~shc_q & pend_ready & (~p_visible | sh_cmd_ready)");
    m.assign("proj_take", "p_valid & p_out_ready");
    m.wire_assign("proj_id", COUNT_BITS, "first_i + proj_idx_q");
    let fs = FEATURE_BYTES.trailing_zeros();
    m.wire_assign("prev_off", COUNT_BITS + fs, format!("{{proj_id, {}}}", lit(fs, 0)));
    m.wire_assign("prev_addr", ab, format!("prev_base_i + prev_off[{}:0]", ab - 1));
    m.wire_assign("unused_prev_off", 1, format!("^prev_off[{}:{ab}]", COUNT_BITS + fs - 1));
    let fw = FEATURE_BYTES / 4;
    m.wire_assign("sh_cmd_base", ab, "shc_q ? shc_addr_q : (all_fresh_i ? sh_addr : prev_addr)");
    m.wire_assign(
        "sh_cmd_words",
        bits_for(u64::from(max_record_words())),
        format!("(shc_q | all_fresh_i) ? sh_words_i : {}", lit(bits_for(u64::from(max_record_words())), fw)),
    );
    m.seq(
        vec![set("shc_q", lit(1, 0)), set("shc_addr_q", lit(ab, 0))],
        vec![if_else(
            "proj_take & p_visible & ~all_fresh_i",
            vec![set("shc_q", lit(1, 1)), set("shc_addr_q", "sh_addr")],
            vec![if_("sh_cmd_ready", vec![set("shc_q", lit(1, 0))])],
        )],
    );
    let lb = COUNT_BITS + 8;
    let wb = bits_for(u64::from(max_record_words()));
    m.wire_assign(
        "sh_off",
        lb,
        format!("{} * {} * {}", zext("proj_id", COUNT_BITS, lb), zext("sh_words_i", wb, lb), lit(lb, 4)),
    );
    m.wire_assign("sh_addr", ab, format!("sh_base_i + sh_off[{}:0]", ab - 1));
    m.wire_assign("unused_sh_off", 1, format!("^sh_off[{}:{ab}]", lb - 1));
    let pend = d.pend();
    m.comment("u_pendq's word: the position, the projection's feature fields, the visibility bit.");
    for f in ["pos_x", "pos_y", "pos_z", "visible", "entry", "itu_mean", "itu_geom", "depth_key"] {
        pend.declare_field(m, f);
    }
    debug_assert_eq!(pend.width(), pw);
    m.wire("pend_valid", 1).wire("pend_data", pw).wire("pend_pop", 1);
    m.item(fifo::instance(
        pw,
        PEND_DEPTH,
        "u_pendq",
        vec![
            conn("clk_i", "clk_i"),
            conn("rst_ni", "rst_ni"),
            conn("push_valid_i", "proj_take"),
            conn("push_ready_o", "pend_ready"),
            conn("push_data_i", "{p_visible, p_fields, posq_data}"),
            conn("pop_valid_o", "pend_valid"),
            conn("pop_ready_i", "pend_pop"),
            conn("pop_data_o", "pend_data"),
        ],
    ));
    let rw = max_record_words() * 32;
    m.wire("sh_busy", 1)
        .wire("sh_valid", 1)
        .wire("sh_ready", 1)
        .wire("sh_rec", rw)
        .wire("sh_index", COUNT_BITS);
    let mut c = vec![conn("clk_i", "clk_i"), conn("rst_ni", "rst_ni")];
    c.extend([conn("cmd_valid_i", "sh_cmd_valid"), conn("cmd_ready_o", "sh_cmd_ready")]);
    c.extend([conn("cmd_base_i", "sh_cmd_base"), conn("cmd_words_i", "sh_cmd_words")]);
    c.push(conn("cmd_count_i", lit(COUNT_BITS, 1)));
    c.extend([conn("busy_o", "sh_busy"), conn("rec_valid_o", "sh_valid"), conn("rec_ready_i", "sh_ready")]);
    c.extend([conn("rec_data_o", "sh_rec"), conn("rec_index_o", "sh_index")]);
    c.extend(fetch_axi(m, cfg, "sh", "mb_axi_"));
    m.instance(fetch::NAME, "u_sh", c);
    m.wire_assign("unused_sh", 1, "^{sh_busy, sh_index}");
    m.comment("Port mb_axi_ has no writes.");
    for s in axi::signals(cfg).iter().filter(|s| !(s.name.starts_with("ar") || s.name.starts_with('r'))) {
        if s.from_manager {
            let v = if s.name == "bready" { 1 } else { 0 };
            m.assign(axi::port_name("mb_axi_", s, true), lit(s.width, v));
        }
    }
    let ins: Vec<String> = axi::signals(cfg)
        .iter()
        .filter(|s| !(s.from_manager || s.name.starts_with("ar") || s.name.starts_with('r')))
        .map(|s| axi::port_name("mb_axi_", s, true))
        .collect();
    m.wire_assign("unused_mb_w", 1, format!("^{{{}}}", ins.join(", ")));
}

/// Projection outputs the lane does not use: the tile rectangle (the duplication unit's), the
/// visibility flag's upper bits.
fn project_unused(project: &Module, d: &LaneDims) -> Vec<String> {
    project
        .interface()
        .ports
        .into_iter()
        .filter(|p| p.dir == Dir::Out && p.name.starts_with("out_") && p.name != "out_valid_o")
        .map(|p| p.name.trim_start_matches("out_").trim_end_matches("_o").to_string())
        .filter(|n| n != "visible" && !d.fields.iter().any(|f| f.0 == *n))
        .map(|n| format!("p_{n}"))
        .collect()
}

/// `sh_coef`: the SH record's coefficients as binary32 (golden `hwpre::sh_in`): word `k` of
/// `sh_rec`, or with `sh_half_i` its half `k` widened exactly (`neo_fp_widen_half_comb`; golden
/// `engine::pre::unpack_sh_record`). A previous feature word also passes here, unread.
fn sh_unpack(m: &mut Module) {
    let n = max_record_words();
    m.comment(
        "SH coefficients: word k, or with sh_half_i half k widened (golden engine::pre::unpack_sh_record).",
    );
    m.wire("sh_coef", 32 * n);
    let items = vec![
        Item::Wire { name: "half".into(), width: 32 },
        Item::Wire { name: "wide".into(), width: 32 },
        Item::Assign { lhs: "half".into(), rhs: "{16'd0, sh_rec[16*k +: 16]}".into() },
        Item::Instance(Instance {
            module: WIDEN_HALF_COMB_NAME.into(),
            name: "u_widen".into(),
            params: vec![],
            conns: vec![("a_i".into(), "half".into()), ("y_o".into(), "wide".into())],
        }),
        Item::Assign {
            lhs: "sh_coef[32*k +: 32]".into(),
            rhs: "sh_half_i ? wide : sh_rec[32*k +: 32]".into(),
        },
    ];
    m.gen_for("k", n, "g_sh_coef", items);
}

/// The pending queue's head and its SH record -> `u_color`, its fields -> `u_colq`.
fn colour(m: &mut Module, color: &Module, d: &LaneDims) {
    let fb = d.fields_bits();
    let cw = 1 + fb;
    m.blank();
    m.comment(
        "Colour: the pending head (with its SH record when visible) enters u_color, its fields u_colq.",
    );
    let (pend, colq) = (d.pend(), d.colq());
    m.wire_assign("pend_visible", 1, pend.get("pend_data", "visible"));
    m.wire("colq_ready", 1).wire("c_in_ready", 1).wire("d_in_ready", 1);
    m.comment("A visible head first takes its previous feature word into prev_q (unless all_fresh_i),");
    m.comment("then enters u_color and u_dup together with its SH record.");
    m.reg("prev_have_q", 1).reg("prev_q", (FEATURE_BYTES * 8) as u32);
    m.wire_assign("prev_cap", 1, "pend_valid & pend_visible & ~all_fresh_i & ~prev_have_q & sh_valid");
    m.wire_assign(
        "join_ok",
        1,
        "pend_valid & (~pend_visible | (sh_valid & (all_fresh_i | prev_have_q))) & colq_ready",
    );
    m.wire_assign("c_in_valid", 1, "join_ok & (~pend_visible | d_in_ready)");
    m.wire_assign("d_in_valid", 1, "join_ok & pend_visible & c_in_ready");
    m.wire_assign("c_take", 1, "c_in_valid & c_in_ready");
    m.assign("pend_pop", "c_take");
    m.assign("sh_ready", "(c_take & pend_visible) | prev_cap");
    m.seq(
        vec![set("prev_have_q", lit(1, 0))],
        vec![if_else(
            "prev_cap",
            vec![set("prev_have_q", lit(1, 1))],
            vec![if_("c_take", vec![set("prev_have_q", lit(1, 0))])],
        )],
    );
    m.seq_noreset(vec![if_("prev_cap", vec![set("prev_q", format!("sh_rec[{}:0]", FEATURE_BYTES * 8 - 1))])]);
    sh_unpack(m);
    m.wire_assign(
        "c_sh",
        max_record_words() * 32,
        format!("pend_visible ? sh_coef : {}", lit(max_record_words() * 32, 0)),
    );
    let mut c = vec![conn("clk_i", "clk_i"), conn("rst_ni", "rst_ni")];
    let mut sh_k = 0u32;
    for p in color.interface().ports.iter().filter(|p| p.dir == Dir::In) {
        let n = p.name.as_str();
        let e = match n {
            "clk_i" | "rst_ni" => continue,
            "in_valid_i" => "c_in_valid".to_string(),
            "out_ready_i" => "c_out_ready".to_string(),
            "in_mean_x_i" => pend.get("pend_data", "pos_x"),
            "in_mean_y_i" => pend.get("pend_data", "pos_y"),
            "in_mean_z_i" => pend.get("pend_data", "pos_z"),
            _ if n.starts_with("in_sh") => {
                let e = format!("c_sh[{}:{}]", 32 * sh_k + 31, 32 * sh_k);
                sh_k += 1;
                e
            }
            _ => n.to_string(),
        };
        c.push((p.name.clone(), e));
    }
    assert_eq!(sh_k, max_record_words(), "{COLOR_NAME} takes {} SH words", max_record_words());
    c.push(conn("in_ready_o", "c_in_ready"));
    m.wire("c_out_ready", 1);
    for p in color.interface().ports.iter().filter(|p| p.dir == Dir::Out && p.name != "in_ready_o") {
        let w = format!("c_{}", p.name.trim_start_matches("out_").trim_end_matches("_o"));
        m.wire(w.clone(), p.width);
        c.push((p.name.clone(), w));
    }
    m.instance(COLOR_NAME, "u_color", c);
    m.comment("u_colq's word: the feature fields and the visibility bit.");
    let used: Vec<&str> = d.fields.iter().map(|f| f.0.as_str()).chain(["visible"]).collect();
    for f in used {
        colq.declare_field(m, f);
    }
    debug_assert_eq!(colq.width(), cw);
    m.wire("colq_valid", 1).wire("colq_data", cw).wire("word_take", 1);
    m.item(fifo::instance(
        cw,
        colq_depth(d.color_depth),
        "u_colq",
        vec![
            conn("clk_i", "clk_i"),
            conn("rst_ni", "rst_ni"),
            conn("push_valid_i", "c_take"),
            conn("push_ready_o", "colq_ready"),
            conn("push_data_i", pend.get("pend_data", "entry")),
            conn("pop_valid_o", "colq_valid"),
            conn("pop_ready_i", "word_take"),
            conn("pop_data_o", "colq_data"),
        ],
    ));
}

/// The feature word of the colour unit's output and the head of `u_colq`, and its write.
fn writer(m: &mut Module, cfg: &EngineConfig, d: &LaneDims) {
    let fmt = cfg.feature_format();
    let (ab, db) = (cfg.axi_addr_bits, cfg.axi_data_bits);
    let beats = (FEATURE_BYTES * 8) as u32 / db;
    let ww = (FEATURE_BYTES * 8) as u32;
    m.blank();
    m.comment(
        "Feature word: the layout's fields (golden FeatureFormat::layout), present on top; 0 when culled.",
    );
    let mut parts = Vec::new();
    for f in fmt.layout() {
        let src = if COLOR_FIELDS.contains(&f.name) {
            format!("c_{}[{}:0]", f.name, f.width - 1)
        } else {
            d.colq().get("colq_data", f.name)
        };
        parts.push(src);
    }
    parts.reverse();
    let eb = fmt.bits_per_entry();
    m.wire_assign("entry_bits", eb, format!("{{{}}}", parts.join(", ")));
    m.wire_assign("word_visible", 1, d.colq().get("colq_data", "visible"));
    m.wire_assign(
        "word",
        ww,
        format!("word_visible ? {{{}, 1'b1, entry_bits}} : {}", lit(ww - eb - 1, 0), lit(ww, 0)),
    );
    let cu: Vec<String> = COLOR_FIELDS
        .iter()
        .map(|n| (n, fmt.layout().iter().find(|f| f.name == *n).map(|f| f.width).unwrap_or(32)))
        .filter(|(_, w)| *w < 32)
        .map(|(n, w)| format!("c_{n}[31:{w}]"))
        .collect();
    if !cu.is_empty() {
        m.wire_assign("unused_c", 1, format!("^{{{}}}", cu.join(", ")));
    }
    m.blank();
    m.comment(format!(
        "Write: AW then {beats} W beats per word; at most {} words without their B.",
        cfg.axi_outstanding
    ));
    m.assign("word_take", "colq_valid & c_valid & wr_free");
    m.assign("c_out_ready", "word_take");
    m.wire_assign("wr_id", COUNT_BITS, "first_i + wr_idx_q");
    let shift = FEATURE_BYTES.trailing_zeros();
    let lb = COUNT_BITS + shift;
    m.wire_assign("wr_off", lb, format!("{{wr_id, {}}}", lit(shift, 0)));
    m.wire_assign("unused_wr_off", 1, format!("^wr_off[{}:{ab}]", lb - 1));
    let w = Writes {
        port: "ma_axi_",
        take: "word_take",
        addr: format!("feat_base_i + wr_off[{}:0]", ab - 1),
        data: "word".into(),
        width: ww,
        beats: lit(writer::beat_bits(beats), u64::from(beats)),
        max_beats: beats,
        awlen: lit(8, u64::from(beats - 1)),
        strb: writer::all_bytes(cfg),
        outstanding: cfg.axi_outstanding,
    };
    writer::writes(m, cfg, &w);
}

/// `u_dup`: the tiles a joined Gaussian enters; the incoming ones leave on `hit_*`.
fn duplicate(m: &mut Module, cfg: &EngineConfig, d: &LaneDims) {
    let (tb, ib, kb) = (cfg.tile_bits, u32::from(cfg.id_bits), u32::from(cfg.key_bits));
    let (pend, prev) = (d.pend(), prev_word(cfg));
    m.blank();
    m.comment("Duplication: the joined Gaussian's tiles; the incoming ones go out on hit_*.");
    m.comment("The previous feature word as the unit reads it: present bit, ITU runs.");
    prev.declare(m);
    m.wire_assign("join_id", COUNT_BITS, "first_i + join_idx_q");
    m.wire("d_out_valid", 1).wire("d_out_incoming", 1).wire("d_idle", 1);
    let kw = pend.width_of("depth_key");
    m.wire_assign("join_key_field", kw, pend.get("pend_data", "depth_key"));
    let key = if kw >= kb { format!("join_key_field[{}:0]", kb - 1) } else { zext("join_key_field", kw, kb) };
    let c = vec![
        conn("clk_i", "clk_i"),
        conn("rst_ni", "rst_ni"),
        conn("grid_x_i", format!("grid_x_i[{}:0]", tb - 1)),
        conn("grid_y_i", format!("grid_y_i[{}:0]", tb - 1)),
        conn("all_fresh_i", "all_fresh_i"),
        conn("in_valid_i", "d_in_valid"),
        conn("in_ready_o", "d_in_ready"),
        conn("in_id_i", format!("join_id[{}:0]", ib - 1)),
        conn("in_key_i", key),
        conn("in_mean_i", pend.get("pend_data", "itu_mean")),
        conn("in_geom_i", pend.get("pend_data", "itu_geom")),
        conn("in_prev_visible_i", prev.get("prev_q", "present")),
        conn("in_prev_mean_i", prev.get("prev_q", "itu_mean")),
        conn("in_prev_geom_i", prev.get("prev_q", "itu_geom")),
        conn("out_valid_o", "d_out_valid"),
        conn("out_ready_i", "hit_ready_i | ~d_out_incoming"),
        conn("out_tile_x_o", "hit_tile_x_o"),
        conn("out_tile_y_o", "hit_tile_y_o"),
        conn("out_id_o", "hit_id_o"),
        conn("out_key_o", "hit_key_o"),
        conn("out_incoming_o", "d_out_incoming"),
        conn("idle_o", "d_idle"),
    ];
    m.instance(super::dup::NAME, "u_dup", c);
    m.assign("hit_valid_o", "d_out_valid & d_out_incoming");
    let mut unused = vec![format!("grid_x_i[31:{tb}]"), format!("grid_y_i[31:{tb}]"), "prev_q".to_string()];
    if ib < COUNT_BITS {
        unused.push(format!("join_id[{}:{ib}]", COUNT_BITS - 1));
    }
    if kw > kb {
        unused.push(format!("join_key_field[{}:{kb}]", kw - 1));
    }
    m.wire_assign("unused_dup", 1, format!("^{{{}}}", unused.join(", ")));
}
