//! `neo_pre_engine`: the Preprocessing Engine (paper Section 5.2, Table 1): `pre_units` lanes
//! (`g_lane[p].u_lane`, [`super::lane`]: projection, colour and duplication units each) and the
//! incoming-list writer `u_lists` ([`super::lists`]), between a start and a done.
//!
//! - **Ranges**: lane `p` takes Gaussians `first .. first + count` of golden
//!   `EngineConfig::pre_lane_range` (`share = ceil(gaussians_i / P)`, `P` a power of two, so the
//!   division is a shift); the ranges are registered on `start_i`, and a lane with no Gaussian is
//!   not started. Lane `p` reads its geometry from `geo_base_i + G first` (`G` = golden
//!   `hwpre::bake::geometry_bytes`, 44).
//! - **Hits**: a round-robin arbiter (`rr_q`: the lane after the last one served first) passes
//!   one lane's incoming hit a cycle to `u_lists`.
//! - **Phases** (`phase_q`): idle; start (the lanes and `u_lists` get their start pulse); run
//!   (until every lane is idle: its hits taken, its feature words' B back); flush (`flush` held
//!   until `u_lists` takes it); drain (until `u_lists` is idle), then `done_o` pulses and
//!   `busy_o` falls.
//! - **Memory**: `2 P + 1` AXI4 managers on packed buses `m_axi_<signal>` (manager `q` at
//!   `[q W +: W]`): `p` is lane `p`'s `ma_axi` (geometry reads, feature-word writes), `P + p`
//!   its `mb_axi` (SH and previous-word reads), `2 P` the list writer (golden
//!   `EngineConfig::pre_managers`). The lanes' SH ports are consecutive managers, so the engine's
//!   client interleave spreads their gathers over its memory ports.
//!
//! The per-frame inputs (camera words, degree, bases, `fresh_i`, `gaussians_i`, `tiles_i`) must
//! be stable from `start_i` to `done_o`.

use super::{fetch::COUNT_BITS, lane, lists};
use crate::emit::expr::{bits_for, lit, zext};
use crate::emit::{if_, set, Instance, Item, Module};
use crate::interface::Dir;
use crate::units::axi;
use neo_golden::engine::pre::sh_record_words;
use neo_golden::engine::{CameraWord, EngineConfig};
use neo_golden::hwpre::bake::{geometry_bytes, ShPrecision};

/// Module name.
pub const NAME: &str = "neo_pre_engine";

/// The modules `neo_pre_engine` instantiates directly.
pub const SUBMODULES: &[&str] = &[lane::NAME, lists::NAME];

/// Phases of `phase_q`.
const IDLE: u64 = 0;
const START: u64 = 1;
const RUN: u64 = 2;
const FLUSH: u64 = 3;
const DRAIN: u64 = 4;

/// The AXI4 managers of the engine for `cfg`: two per lane and the list writer (golden
/// `EngineConfig::pre_managers`).
pub fn managers(cfg: &EngineConfig) -> usize {
    cfg.pre_managers()
}

/// The lane's per-frame camera inputs (its `_i` ports named by a [`CameraWord`]) and the
/// degree input, as (name, width); panics if the lane has another per-frame input the engine
/// does not know (a generator bug).
pub fn camera_inputs(cfg: &EngineConfig) -> Vec<(String, u32)> {
    let known: Vec<String> = CameraWord::all().map(|c| c.port()).chain(["degree_i".to_string()]).collect();
    let own = [
        "clk_i",
        "rst_ni",
        "start_i",
        "geo_base_i",
        "sh_base_i",
        "sh_words_i",
        "sh_half_i",
        "feat_base_i",
        "prev_base_i",
        "all_fresh_i",
        "first_i",
        "count_i",
        "hit_ready_i",
    ];
    lane::module(cfg)
        .interface()
        .ports
        .into_iter()
        .filter(|p| p.dir == Dir::In && !own.contains(&p.name.as_str()) && !p.name.contains("_axi_"))
        .map(|p| {
            assert!(
                known.contains(&p.name),
                "{}: per-frame input {} is not a camera word",
                lane::NAME,
                p.name
            );
            (p.name, p.width)
        })
        .collect()
}

/// The Preprocessing Engine for `cfg`.
pub fn module(cfg: &EngineConfig) -> Module {
    let (p, ab) = (cfg.pre_units as u32, cfg.axi_addr_bits);
    let mut m = Module::new(NAME);
    m.doc(format!(
        "Preprocessing Engine: {p} lanes (projection, colour, duplication) and the incoming-list writer; from the"
    ));
    m.doc("baked scene and the camera to every feature word, the tiles' incoming lists and their lengths.");
    m.doc(
        "AXI4 managers on m_axi_* (manager q at [q*W +: W]): lane p's ma at p, mb at P+p, the lists at 2P.",
    );
    m.clock_reset();
    m.input_c("start_i", 1, "pulse: preprocess the frame (ignored while busy_o)");
    m.output_c("busy_o", 1, "from start_i to done_o");
    m.output_c("done_o", 1, "pulse: every feature word, list line and length written and acknowledged");
    for (name, w) in camera_inputs(cfg) {
        m.input_c(name, w, "per frame (camera word or SH degree)");
    }
    m.input_c("fresh_i", 1, "no table is reused: every Gaussian is incoming, no previous word read");
    m.input_c("sh_half_i", 1, "the SH records hold binary16 coefficients (PRE_CTRL.sh_half)");
    m.input_c("gaussians_i", COUNT_BITS, "Gaussians of the baked scene");
    for (name, what) in [
        ("geo_base_i", "geometry array (Gaussian 0's record)"),
        ("sh_base_i", "SH array (Gaussian 0's record)"),
        ("feat_base_i", "feature table written"),
        ("prev_base_i", "previous frame's feature table"),
        ("list_base_i", "tile 0's incoming list (64-byte aligned)"),
        ("desc_base_i", "tile 0's descriptor"),
    ] {
        m.input_c(name, ab, &format!("byte address: {what}"));
    }
    m.input_c("tiles_i", 32, "tiles of the frame (at most pre_max_tiles)");
    let n = managers(cfg) as u32;
    for s in axi::signals(cfg) {
        let name = axi::port_name("m_axi_", &s, true);
        if s.from_manager {
            m.output(name, n * s.width);
        } else {
            m.input(name, n * s.width);
        }
    }
    phases(&mut m);
    ranges(&mut m, cfg);
    lanes(&mut m, cfg);
    arbiter(&mut m, cfg);
    list_writer(&mut m, cfg);
    m
}

/// `phase_q`, the start and flush pulses, `busy_o`, `done_o`.
fn phases(m: &mut Module) {
    m.blank();
    m.comment(
        "Phases: idle, start (lanes and lists start), run, flush (until taken), drain (until lists idle).",
    );
    m.reg("phase_q", 3);
    for (name, v) in
        [("in_idle", IDLE), ("in_start", START), ("in_run", RUN), ("in_flush", FLUSH), ("in_drain", DRAIN)]
    {
        m.wire_assign(name, 1, format!("phase_q == {}", lit(3, v)));
    }
    m.wire("lanes_busy", 1).wire("lists_busy", 1).wire("lists_run", 1);
    m.wire_assign("take_start", 1, "start_i & in_idle");
    m.wire_assign("flush", 1, "in_flush & lists_run");
    m.wire_assign("finish", 1, "in_drain & ~lists_busy");
    m.seq(
        vec![set("phase_q", lit(3, IDLE))],
        vec![
            if_("take_start", vec![set("phase_q", lit(3, START))]),
            if_("in_start", vec![set("phase_q", lit(3, RUN))]),
            if_("in_run & ~lanes_busy", vec![set("phase_q", lit(3, FLUSH))]),
            if_("flush", vec![set("phase_q", lit(3, DRAIN))]),
            if_("finish", vec![set("phase_q", lit(3, IDLE))]),
        ],
    );
    m.assign("busy_o", "~in_idle");
    m.assign("done_o", "finish");
}

/// Each lane's range, registered on the start, and the SH record size of the degree.
fn ranges(m: &mut Module, cfg: &EngineConfig) {
    let p = cfg.pre_units as u64;
    let lb = p.trailing_zeros();
    let wide = COUNT_BITS + 1;
    m.blank();
    m.comment(format!(
        "Ranges (golden EngineConfig::pre_lane_range): share = ceil(gaussians_i / {p}), lane p from min(p share, N)."
    ));
    m.wire_assign("share_sum", wide, format!("{{1'b0, gaussians_i}} + {}", lit(wide, p - 1)));
    m.wire_assign("share", wide, format!("share_sum >> {lb}"));
    let wb = bits_for(u64::from(super::fetch::max_record_words()));
    let db = degree_bits(cfg);
    let table = |p: ShPrecision| {
        let words: Vec<String> = (0..3u8)
            .map(|d| {
                format!("(degree_i == {}) ? {}", lit(db, u64::from(d)), lit(wb, sh_record_words(d, p).into()))
            })
            .collect();
        format!("{} : {}", words.join(" : "), lit(wb, sh_record_words(3, p).into()))
    };
    m.comment("SH record words of the degree and precision (golden engine::pre::sh_record_words).");
    m.comment("A degree above 3 reads degree-3 records (SH_DEGREE is 0 to 3).");
    m.wire_assign("sh_words_f32", wb, table(ShPrecision::F32));
    m.wire_assign("sh_words_f16", wb, table(ShPrecision::F16));
    m.wire_assign("sh_words", wb, "sh_half_i ? sh_words_f16 : sh_words_f32");
}

/// Width of the lane's `degree_i`.
pub fn degree_bits(cfg: &EngineConfig) -> u32 {
    camera_inputs(cfg).iter().find(|(n, _)| n == "degree_i").map(|(_, w)| *w).expect("the lane has degree_i")
}

/// `g_lane[p]`: the range registers and the lane.
fn lanes(m: &mut Module, cfg: &EngineConfig) {
    let (p, ab, tb) = (cfg.pre_units as u32, cfg.axi_addr_bits, cfg.tile_bits);
    let (ib, kb) = (u32::from(cfg.id_bits), u32::from(cfg.key_bits));
    let wide = COUNT_BITS + 1;
    m.blank();
    m.comment("Lanes: hit buses (lane p at [p*W +: W]), busy bits.");
    m.wire("lane_busy", p).vector("lane_busy");
    for (name, w) in
        [("hit_valid", 1), ("hit_ready", 1), ("hit_tile_x", tb), ("hit_tile_y", tb), ("hit_id", ib)]
    {
        m.wire(format!("lane_{name}"), p * w).vector(format!("lane_{name}"));
    }
    m.wire("lane_hit_key", p * kb).vector("lane_hit_key");
    m.assign("lanes_busy", "|lane_busy");
    let gb = u64::from(geometry_bytes());
    let m1 = COUNT_BITS - 1;
    let mut items = vec![
        Item::Reg { name: "first_q".into(), width: COUNT_BITS },
        Item::Reg { name: "count_q".into(), width: COUNT_BITS },
        Item::Wire { name: "first_full".into(), width: wide },
        Item::Wire { name: "left".into(), width: wide },
        Item::Wire { name: "past".into(), width: 1 },
        Item::Wire { name: "geo_off".into(), width: ab },
        Item::Wire { name: "geo_base".into(), width: ab },
        Item::Wire { name: "unused_range".into(), width: 1 },
        assign("first_full", "share * p".into()),
        assign("left", "{1'b0, gaussians_i} - first_full".into()),
        assign("past", "first_full >= {1'b0, gaussians_i}".into()),
        assign("unused_range", format!("^{{first_full[{COUNT_BITS}], left[{COUNT_BITS}]}}")),
        Item::Seq {
            reset: Some(vec![set("first_q", lit(COUNT_BITS, 0)), set("count_q", lit(COUNT_BITS, 0))]),
            body: vec![if_(
                "take_start",
                vec![
                    set("first_q", format!("first_full[{m1}:0]")),
                    set(
                        "count_q",
                        format!(
                            "past ? {} : (left < share) ? left[{m1}:0] : share[{m1}:0]",
                            lit(COUNT_BITS, 0)
                        ),
                    ),
                ],
            )],
        },
        assign("geo_off", format!("{} * {}", zext("first_q", COUNT_BITS, ab), lit(ab, gb))),
        assign("geo_base", "geo_base_i + geo_off".into()),
    ];
    let mut c: Vec<(String, String)> = vec![pair("clk_i", "clk_i"), pair("rst_ni", "rst_ni")];
    c.push(pair("start_i", &format!("in_start & (count_q != {})", lit(COUNT_BITS, 0))));
    c.push(pair("busy_o", "lane_busy[p]"));
    for (name, _) in camera_inputs(cfg) {
        c.push((name.clone(), name));
    }
    for (port, net) in [
        ("geo_base_i", "geo_base"),
        ("sh_base_i", "sh_base_i"),
        ("sh_words_i", "sh_words"),
        ("sh_half_i", "sh_half_i"),
        ("feat_base_i", "feat_base_i"),
        ("prev_base_i", "prev_base_i"),
        ("all_fresh_i", "fresh_i"),
        ("first_i", "first_q"),
        ("count_i", "count_q"),
        ("hit_valid_o", "lane_hit_valid[p]"),
        ("hit_ready_i", "lane_hit_ready[p]"),
    ] {
        c.push(pair(port, net));
    }
    for (name, w) in [("tile_x", tb), ("tile_y", tb), ("id", ib), ("key", kb)] {
        c.push((format!("hit_{name}_o"), format!("lane_hit_{name}[p*{w} +: {w}]")));
    }
    c.extend(manager_conns(cfg, "ma_axi_", "p"));
    c.extend(manager_conns(cfg, "mb_axi_", &format!("{} + p", cfg.pre_units)));
    items.push(Item::Instance(Instance {
        module: lane::NAME.into(),
        name: "u_lane".into(),
        params: vec![],
        conns: c,
    }));
    m.gen_for("p", p, "g_lane", items);
}

fn assign(lhs: &str, rhs: String) -> Item {
    Item::Assign { lhs: lhs.into(), rhs }
}

fn pair(a: &str, b: &str) -> (String, String) {
    (a.to_string(), b.to_string())
}

/// Connections of an AXI4 manager interface `prefix` to manager `q` (a constant expression)
/// of the packed buses.
fn manager_conns(cfg: &EngineConfig, prefix: &str, q: &str) -> Vec<(String, String)> {
    axi::signals(cfg)
        .iter()
        .map(|s| {
            (
                axi::port_name(prefix, s, true),
                format!("m_axi_{}_{}[({q})*{w} +: {w}]", s.name, dir(s), w = s.width),
            )
        })
        .collect()
}

/// The packed port's suffix of signal `s` (the engine's side is the manager).
fn dir(s: &axi::AxiSignal) -> &'static str {
    if s.from_manager {
        "o"
    } else {
        "i"
    }
}

/// The round-robin arbiter of the lanes' hits.
fn arbiter(m: &mut Module, cfg: &EngineConfig) {
    let p = cfg.pre_units as u64;
    let (tb, ib, kb) = (cfg.tile_bits, u32::from(cfg.id_bits), u32::from(cfg.key_bits));
    m.blank();
    m.wire("hit_valid", 1).wire("hit_ready", 1).wire("hit_tile_x", tb).wire("hit_tile_y", tb);
    m.wire("hit_id", ib).wire("hit_key", kb);
    if p == 1 {
        m.comment("Hits: one lane, no arbiter.");
        for s in ["hit_valid", "hit_tile_x", "hit_tile_y", "hit_id", "hit_key"] {
            m.assign(s, format!("lane_{s}"));
        }
        m.assign("lane_hit_ready", "hit_ready");
        return;
    }
    let lb = p.trailing_zeros();
    m.comment("Hits: round robin from the lane after the last one served (rr_q).");
    m.reg("rr_q", lb);
    for k in 0..p {
        m.wire_assign(format!("cand{k}"), lb, format!("rr_q + {}", lit(lb, k)));
    }
    let mut sel = format!("cand{}", p - 1);
    for k in (0..p - 1).rev() {
        sel = format!("lane_hit_valid[cand{k}] ? cand{k} : {sel}");
    }
    m.wire_assign("sel", lb, sel);
    m.assign("hit_valid", "|lane_hit_valid");
    for (s, w) in [("tile_x", tb), ("tile_y", tb), ("id", ib), ("key", kb)] {
        m.assign(format!("hit_{s}"), format!("lane_hit_{s}[sel*{w} +: {w}]"));
    }
    for k in 0..p {
        m.assign(format!("lane_hit_ready[{k}]"), format!("hit_ready & (sel == {})", lit(lb, k)));
    }
    m.seq(
        vec![set("rr_q", lit(lb, 0))],
        vec![if_("hit_valid & hit_ready", vec![set("rr_q", format!("sel + {}", lit(lb, 1)))])],
    );
}

/// `u_lists`, the list writer (manager `2 P`).
fn list_writer(m: &mut Module, cfg: &EngineConfig) {
    let tb = cfg.tile_bits;
    let grid = CameraWord::all().find(|c| c.name() == "GRID_X").expect("GRID_X").port();
    let mut c: Vec<(String, String)> = vec![pair("clk_i", "clk_i"), pair("rst_ni", "rst_ni")];
    for (port, net) in [
        ("start_i", "in_start".to_string()),
        ("flush_i", "flush".to_string()),
        ("busy_o", "lists_busy".to_string()),
        ("run_o", "lists_run".to_string()),
        ("tiles_i", "tiles_i".to_string()),
        ("grid_x_i", format!("{grid}[{}:0]", tb - 1)),
        ("list_base_i", "list_base_i".to_string()),
        ("desc_base_i", "desc_base_i".to_string()),
    ] {
        c.push((port.to_string(), net));
    }
    for s in ["valid", "tile_x", "tile_y", "id", "key"] {
        c.push((format!("hit_{s}_i"), format!("hit_{s}")));
    }
    c.push(pair("hit_ready_o", "hit_ready"));
    c.extend(manager_conns(cfg, "m_axi_", &(2 * cfg.pre_units).to_string()));
    m.blank();
    m.comment("The incoming-list writer: manager 2P.");
    m.instance(lists::NAME, "u_lists", c);
}
