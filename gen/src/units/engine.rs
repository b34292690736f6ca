//! `neo_engine`: the Neo engine's top level (docs/rtl.md "Engine").
//!
//! - `u_regs` (`neo_engine_regs`): the AXI4-Lite control port; `u_counters`
//!   (`neo_perf_counters`): the performance counters it reads;
//! - `u_ctrl` (`neo_frame_ctrl`): descriptors, the tile scheduler, results, raster dispatch; it
//!   is memory client 0;
//! - `g_sort[i]`: sequencer `u_seq` (`neo_sort_seq`), Sorting Core `u_core` and its AXI4 bridge
//!   `u_bridge`; memory client `1 + i`; the sequencer's and core's clock is gated by `u_gate`
//!   while the sequencer is idle and no job is offered;
//! - `g_raster[j]`: Rasterization Core `u_core` and its AXI4 bridge `u_bridge`; memory client
//!   `1 + N + j`; the core's clock is gated by `u_gate` (`neo_clock_gate`) while it is idle (no
//!   command offered or running, its done given), so an idle core holds every register;
//! - `u_pre` (`neo_pre_engine`): the Preprocessing Engine, run before the frame controller when
//!   `PRE_CTRL.enable` is set (its `done_o` starts `u_ctrl`), on a clock gated by `u_pre_gate`
//!   (`neo_clock_gate`) from its start to its done; its managers `q` are memory clients
//!   `1 + N + M + q` (`g_pre_client[q]` moves them between its packed buses and the client buses);
//!   absent with `pre_units` 0 (the host writes the lists; a start starts `u_ctrl`);
//! - `g_port[k]`: the port mux `u_mux` of AXI4 manager port `m{k}_axi_*`.
//!
//! Client `c` is served by port `c mod K` in slot `c div K`; every port's mux has
//! `P = ceil(C / K)` slots (unused slots are tied idle), so one mux module serves every port.
//! The client buses `cl_<signal>` hold slot `s` of port `k` at index `k P + s`.

use super::axi;
use super::{clock_gate, engine_regs, frame_ctrl, perf_counters, pre, raster_core, sort_core, sort_seq};
use crate::emit::expr::lit;
use crate::emit::{Instance, Item, Module};
use crate::interface::Dir;
use neo_golden::engine::memory::{
    DESCRIPTOR_BYTES, DPS_PASSES_BITS, ENTRY_BYTES, FEATURE_BYTES, PIXEL_BYTES, RESULT_BYTES,
};
use neo_golden::engine::regs::{CameraWord, Counter, COUNTERS};
use neo_golden::engine::{EngineConfig, MemoryClient};

/// Module name.
pub const NAME: &str = "neo_engine";

/// The modules `neo_engine` instantiates directly (black boxes when its own glue is checked).
pub const SUBMODULES: &[&str] = &[
    engine_regs::NAME,
    perf_counters::NAME,
    frame_ctrl::NAME,
    sort_seq::NAME,
    sort_core::NAME,
    axi::sort_bridge::NAME,
    raster_core::NAME,
    axi::raster_bridge::NAME,
    pre::engine::NAME,
    clock_gate::NAME,
];

/// The engine's memory clients and ports: golden's client numbering
/// ([`neo_golden::engine::MemoryClient`]) laid out on the client buses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Clients {
    /// Sorting cores `N`.
    pub sort: usize,
    /// Raster cores `M`.
    pub raster: usize,
    /// The Preprocessing Engine's managers `Q` (`2 pre_units + 1`, or none).
    pub pre: usize,
    /// AXI4 ports `K`.
    pub ports: usize,
    /// Clients `C` ([`EngineConfig::memory_clients`]).
    count: usize,
    /// The client index of sorting core 0, raster core 0 and the Preprocessing Engine's first
    /// manager (its managers are consecutive, in the Preprocessing Engine's order).
    first_sort: usize,
    first_raster: usize,
    first_pre: usize,
}

impl Clients {
    /// The clients of `cfg`'s engine.
    pub fn of(cfg: &EngineConfig) -> Clients {
        Clients {
            sort: cfg.sort_cores,
            raster: cfg.raster_cores,
            pre: pre::engine::managers(cfg),
            ports: cfg.mem_channels,
            count: cfg.memory_clients(),
            first_sort: cfg.client_index(MemoryClient::SortCore(0)),
            first_raster: cfg.client_index(MemoryClient::RasterCore(0)),
            first_pre: cfg.client_index(MemoryClient::PreGeometry(0)),
        }
    }

    /// Clients `C`: the frame controller, the sort bridges, the raster bridges, the
    /// Preprocessing Engine's managers.
    pub fn count(&self) -> usize {
        self.count
    }

    /// Slots per port mux, `ceil(C / K)`.
    pub fn slots(&self) -> usize {
        neo_golden::engine::port_slots(self.count, self.ports)
    }

    /// Index of client `c` in the client buses, `port * slots + slot`: port `k`'s mux takes
    /// entries `k*slots ..`, client `c` at its (port, slot) of golden's
    /// [`neo_golden::engine::client_port_slot`].
    pub fn position(&self, c: usize) -> usize {
        let (port, slot) = neo_golden::engine::client_port_slot(c, self.ports);
        port * self.slots() + slot
    }

    /// [`Clients::position`] as a Verilog constant expression, for the client `first + var` of
    /// a generate loop's variable `var`.
    fn position_expr(&self, var: &str, first: usize) -> String {
        let (k, p) = (self.ports, self.slots());
        format!("(({var} + {first}) % {k}) * {p} + ({var} + {first}) / {k}")
    }
}

/// The ports of `module` whose names start with `prefix`: (name, is an output, width).
fn ports_of(module: &Module, prefix: &str) -> Vec<(String, bool, u32)> {
    module
        .interface()
        .ports
        .into_iter()
        .filter(|p| p.name.starts_with(prefix))
        .map(|p| (p.name, p.dir == Dir::Out, p.width))
        .collect()
}

/// A port's name without its `_i` / `_o` suffix (the wire that connects it).
fn wire_of(port: &str) -> &str {
    port.strip_suffix("_i").or_else(|| port.strip_suffix("_o")).unwrap_or(port)
}

/// Connections of an AXI4 manager interface (`prefix`, e.g. `m_axi_`) to position `pos` (a
/// Verilog constant expression) of the client buses.
fn client_conns(cfg: &EngineConfig, prefix: &str, pos: &str) -> Vec<(String, String)> {
    axi::signals(cfg)
        .iter()
        .map(|s| (axi::port_name(prefix, s, true), format!("cl_{}[({pos})*{w} +: {w}]", s.name, w = s.width)))
        .collect()
}

/// The engine for `cfg`.
pub fn module(cfg: &EngineConfig) -> Module {
    let cl = Clients::of(cfg);
    let mut m = Module::new(NAME);
    m.doc(format!(
        "Neo engine: {} Sorting Cores, {} Rasterization Cores, {} AXI4 manager ports (m<k>_axi_*), an",
        cl.sort, cl.raster, cl.ports
    ));
    m.doc(if cfg.has_preprocessing() {
        "AXI4-Lite control port (s_axil_*). A frame: preprocessing (when PRE_CTRL.enable), then per tile:"
    } else {
        "AXI4-Lite control port (s_axil_*), no Preprocessing Engine (pre_units 0). A frame, per tile:"
    });
    m.doc(
        "conventional sort of the incoming list, DPS of the previous table, merge-with-delete, rasterisation",
    );
    m.doc("with the table write-back. See docs/rtl.md.");
    m.clock_reset();
    control_ports(&mut m, cfg);
    for k in 0..cl.ports {
        axi::ports(&mut m, cfg, &format!("m{k}_axi_"), true);
    }
    m.output_c("busy_o", 1, "STATUS.busy");
    m.output_c("done_o", 1, "STATUS.done (an interrupt source)");
    client_buses(&mut m, cfg, &cl);
    control(&mut m, cfg, &cl);
    sort_cores(&mut m, cfg, &cl);
    raster_cores(&mut m, cfg, &cl);
    preprocessing(&mut m, cfg, &cl);
    ports(&mut m, cfg, &cl);
    counters(&mut m, cfg, &cl);
    m
}

/// The AXI4-Lite control port (`neo_engine_regs`'s, passed through).
fn control_ports(m: &mut Module, cfg: &EngineConfig) {
    for (name, out, w) in ports_of(&engine_regs::module(cfg), "s_axil_") {
        if out {
            m.output(name, w);
        } else {
            m.input(name, w);
        }
    }
}

/// The client buses, and the idle values of the unused slots.
fn client_buses(m: &mut Module, cfg: &EngineConfig, cl: &Clients) {
    let total = cl.ports * cl.slots();
    m.comment(format!(
        "Client buses: {} clients on {} ports of {} slots; client c at index (c % {}) * {} + c / {}.",
        cl.count(),
        cl.ports,
        cl.slots(),
        cl.ports,
        cl.slots(),
        cl.ports
    ));
    for s in axi::signals(cfg) {
        m.wire(format!("cl_{}", s.name), total as u32 * s.width).vector(format!("cl_{}", s.name));
    }
    let used: Vec<usize> = (0..cl.count()).map(|c| cl.position(c)).collect();
    for pos in (0..total).filter(|p| !used.contains(p)) {
        m.comment(format!("Slot {pos} has no client: idle."));
        for s in axi::signals(cfg).iter().filter(|s| s.from_manager) {
            let v = if s.name == "rready" || s.name == "bready" { 1 } else { 0 };
            m.assign(format!("cl_{}[{pos}*{w} +: {w}]", s.name, w = s.width), lit(s.width, v));
        }
        m.wire_assign(format!("unused_slot{pos}"), 1, unused_slot(cfg, pos));
    }
}

/// XOR of the responses an unused slot receives (lint: read somewhere).
fn unused_slot(cfg: &EngineConfig, pos: usize) -> String {
    let v: Vec<String> = axi::signals(cfg)
        .iter()
        .filter(|s| !s.from_manager)
        .map(|s| format!("cl_{}[{pos}*{w} +: {w}]", s.name, w = s.width))
        .collect();
    format!("^{{{}}}", v.join(", "))
}

/// The control port, the frame controller and the wires between them and the cores.
fn control(m: &mut Module, cfg: &EngineConfig, cl: &Clients) {
    let (n, mm) = (cl.sort as u32, cl.raster as u32);
    let (aw, lw, xa) = (cfg.addr_bits, cfg.len_bits, cfg.axi_addr_bits);
    m.blank();
    m.comment("Control port -> frame controller.");
    m.wire("start", 1).wire("frame", 32).wire("tiles", 32).wire("width", 16).wire("height", 16);
    for b in BASES {
        m.wire(format!("{b}_base"), xa);
    }
    m.wire("frame_busy", 1).wire("frame_done", 1).wire("frame_overflow", 1);
    m.wire("first_overflow", 32).wire("overflows", 32);
    m.wire("counters", 64 * COUNTERS as u32);
    m.wire("adapt_ctrl", 32);
    let mut c: Vec<(String, String)> = vec![pair("clk_i", "clk_i"), pair("rst_ni", "rst_ni")];
    c.extend(
        ports_of(&engine_regs::module(cfg), "s_axil_").into_iter().map(|(name, _, _)| (name.clone(), name)),
    );
    c.push(pair("start_o", "start"));
    for r in ["frame", "tiles", "width", "height"] {
        c.push((format!("{r}_o"), r.to_string()));
    }
    c.extend(BASES.iter().map(|b| (format!("{b}_base_o"), format!("{b}_base"))));
    c.extend(pre_registers(m, cfg));
    c.push(pair("adapt_ctrl_o", "adapt_ctrl"));
    for s in ["busy", "done", "overflow"] {
        c.push((format!("{s}_i"), format!("frame_{s}")));
    }
    for s in ["first_overflow", "overflows", "counters"] {
        c.push((format!("{s}_i"), s.to_string()));
    }
    m.instance(engine_regs::NAME, "u_regs", c);
    m.blank();
    m.wire("ctrl_busy", 1).wire("ctrl_done", 1);
    if cfg.has_preprocessing() {
        m.comment(
            "A start goes to the Preprocessing Engine when PRE_CTRL.enable, and its done starts the walk.",
        );
        m.wire("pre_busy", 1).wire("pre_done", 1);
        m.wire_assign("pre_start", 1, "start & pre_enable");
        m.wire_assign("ctrl_start", 1, "pre_enable ? pre_done : start");
    } else {
        m.comment("No Preprocessing Engine (pre_units 0): a start starts the walk; PRE_CTRL is ignored.");
        m.wire_assign("pre_busy", 1, "1'b0");
        m.wire_assign("ctrl_start", 1, "start");
    }
    m.comment("STATUS: busy from the start to the walk's end; the walk's done (held) hidden until then.");
    m.assign("frame_busy", "pre_busy | ctrl_busy");
    m.assign("frame_done", "ctrl_done & ~pre_busy & ~start");
    m.assign("busy_o", "frame_busy");
    m.assign("done_o", "frame_done");

    m.blank();
    m.comment("Frame controller <-> sequencers, raster cores, bridges.");
    m.wire("job_valid", n).wire("job_ready", n).wire("job_from_scratch", 1);
    m.wire("job_prev", aw).wire("job_prev_len", lw).wire("job_list", aw).wire("job_list_len", lw);
    m.wire("job_next", aw)
        .wire("job_dps_passes", DPS_PASSES_BITS)
        .wire("job_dps_wide", 1)
        .wire("job_odd", 1)
        .wire("job_scratch", n * aw);
    m.wire("cpl_valid", n).wire("cpl_ready", n).wire("cpl_len", n * lw).wire("cpl_inv", n * lw);
    m.wire("ras_valid", mm).wire("ras_ready", mm).wire("ras_done", mm);
    m.wire("ras_wb_len", mm * lw).wire("ras_wb_reach", mm * lw);
    m.wire("ras_tile_x", cfg.tile_bits).wire("ras_tile_y", cfg.tile_bits);
    m.wire("ras_width", 16).wire("ras_height", 16);
    m.wire("ras_table", aw).wire("ras_len", lw).wire("ras_feat", aw).wire("ras_pix", aw);
    m.wire("idle", n + mm);
    for v in ["job_valid", "job_ready", "cpl_valid", "cpl_ready", "ras_valid", "ras_ready", "ras_done"] {
        m.vector(v);
    }
    let events = ports_of(&frame_ctrl::module(cfg), "ev_");
    for (e, _, w) in &events {
        m.wire(wire_of(e), *w);
    }
    let mut c: Vec<(String, String)> = vec![pair("clk_i", "clk_i"), pair("rst_ni", "rst_ni")];
    c.push(pair("start_i", "ctrl_start"));
    for r in ["frame", "tiles", "width", "height"] {
        c.push((format!("{r}_i"), r.to_string()));
    }
    c.extend(BASES.iter().map(|b| (format!("{b}_base_i"), format!("{b}_base"))));
    c.push(pair("adapt_ctrl_i", "adapt_ctrl"));
    c.push(pair("busy_o", "ctrl_busy"));
    c.push(pair("done_o", "ctrl_done"));
    c.push(pair("overflow_o", "frame_overflow"));
    for s in ["first_overflow", "overflows"] {
        c.push((format!("{s}_o"), s.to_string()));
    }
    c.extend(client_conns(cfg, "m_axi_", &cl.position(0).to_string()));
    for s in ["job_valid", "job_from_scratch", "job_prev", "job_prev_len", "job_list", "job_list_len"] {
        c.push((format!("{s}_o"), s.to_string()));
    }
    for s in [
        "job_next",
        "job_dps_passes",
        "job_dps_wide",
        "job_odd",
        "job_scratch",
        "cpl_ready",
        "ras_valid",
        "ras_tile_x",
    ] {
        c.push((format!("{s}_o"), s.to_string()));
    }
    for s in ["ras_tile_y", "ras_width", "ras_height", "ras_table", "ras_len", "ras_feat", "ras_pix"] {
        c.push((format!("{s}_o"), s.to_string()));
    }
    for s in ["job_ready", "cpl_valid", "cpl_len", "cpl_inv", "ras_ready", "ras_done", "ras_wb_len"] {
        c.push((format!("{s}_i"), s.to_string()));
    }
    for s in ["ras_wb_reach", "idle"] {
        c.push((format!("{s}_i"), s.to_string()));
    }
    c.extend(events.iter().map(|(e, _, _)| (e.clone(), wire_of(e).to_string())));
    m.instance(frame_ctrl::NAME, "u_ctrl", c);
}

/// The Preprocessing Engine's register wires (`pre_<output>`), declared; the connections of
/// `u_regs`'s outputs to them.
fn pre_registers(m: &mut Module, cfg: &EngineConfig) -> Vec<(String, String)> {
    let regs = engine_regs::module(cfg);
    let mut c = Vec::new();
    for (port, _, w) in pre_register_ports(&regs) {
        let net = pre_register_net(&port);
        m.wire(net.clone(), w);
        c.push((port, net));
    }
    c
}

/// `u_regs`'s outputs for the Preprocessing Engine: the PRE_CTRL bits, GAUSSIANS, SH_DEGREE, the
/// four bases and the camera words.
fn pre_register_ports(regs: &Module) -> Vec<(String, bool, u32)> {
    let mut v: Vec<(String, bool, u32)> = Vec::new();
    for p in [
        "pre_enable_o",
        "pre_fresh_o",
        "pre_sh_half_o",
        "gaussians_o",
        "sh_degree_o",
        "geo_base_o",
        "sh_base_o",
    ] {
        v.extend(ports_of(regs, p));
    }
    v.extend(ports_of(regs, "prev_feat_base_o"));
    v.extend(ports_of(regs, "list_base_o"));
    for c in CameraWord::all() {
        v.extend(ports_of(regs, &engine_regs::camera_port(c)));
    }
    v
}

/// The engine's wire of `u_regs` output `port`: `pre_enable`, `pre_gaussians`, `pre_w2v_00`, ...
fn pre_register_net(port: &str) -> String {
    let base = wire_of(port);
    if base.starts_with("pre_") {
        base.to_string()
    } else {
        format!("pre_{base}")
    }
}

/// `u_pre`, the Preprocessing Engine, and `g_pre_client[q]`: its managers on the client buses.
/// Without one (`pre_units` 0), only a lint sink of its register wires.
fn preprocessing(m: &mut Module, cfg: &EngineConfig, cl: &Clients) {
    if !cfg.has_preprocessing() {
        let nets: Vec<String> = pre_register_ports(&engine_regs::module(cfg))
            .into_iter()
            .map(|(port, _, _)| pre_register_net(&port))
            .collect();
        m.blank();
        m.comment("No Preprocessing Engine: its registers are stored and read back, and unused here.");
        m.wire_assign("unused_pre_regs", 1, format!("^{{{}}}", nets.join(", ")));
        return;
    }
    let q = cl.pre as u32;
    let sigs = axi::signals(cfg);
    m.blank();
    m.comment(format!(
        "Preprocessing Engine: its {q} managers on packed buses pre_<signal> (manager q at [q*W +: W])."
    ));
    for s in &sigs {
        m.wire(format!("pre_{}", s.name), q * s.width).vector(format!("pre_{}", s.name));
    }
    m.comment("Its clock runs from its start to its done only (u_pre_gate).");
    m.wire("pre_clk", 1);
    m.instance(
        clock_gate::NAME,
        "u_pre_gate",
        vec![
            pair("clk_i", "clk_i"),
            pair("rst_ni", "rst_ni"),
            pair("en_i", "pre_start | pre_busy"),
            pair("clk_o", "pre_clk"),
        ],
    );
    let mut c: Vec<(String, String)> = vec![pair("clk_i", "pre_clk"), pair("rst_ni", "rst_ni")];
    c.push(pair("start_i", "pre_start"));
    c.push(pair("busy_o", "pre_busy"));
    c.push(pair("done_o", "pre_done"));
    for (name, _) in pre::engine::camera_inputs(cfg) {
        let reg_port =
            if name == "degree_i" { "sh_degree_o".to_string() } else { format!("{}_o", wire_of(&name)) };
        c.push((name, pre_register_net(&reg_port)));
    }
    for (port, net) in [
        ("fresh_i", "pre_fresh"),
        ("sh_half_i", "pre_sh_half"),
        ("gaussians_i", "pre_gaussians"),
        ("geo_base_i", "pre_geo_base"),
        ("sh_base_i", "pre_sh_base"),
        ("feat_base_i", "feat_base"),
        ("prev_base_i", "pre_prev_feat_base"),
        ("list_base_i", "pre_list_base"),
        ("desc_base_i", "desc_base"),
        ("tiles_i", "tiles"),
    ] {
        c.push(pair(port, net));
    }
    for s in &sigs {
        c.push((axi::port_name("m_axi_", s, true), format!("pre_{}", s.name)));
    }
    m.instance(pre::engine::NAME, "u_pre", c);
    let pos = cl.position_expr("q", cl.first_pre);
    let items = sigs
        .iter()
        .map(|s| {
            let (cl_bus, pre_bus) = (
                format!("cl_{}[({pos})*{w} +: {w}]", s.name, w = s.width),
                format!("pre_{}[q*{w} +: {w}]", s.name, w = s.width),
            );
            let (lhs, rhs) = if s.from_manager { (cl_bus, pre_bus) } else { (pre_bus, cl_bus) };
            Item::Assign { lhs, rhs }
        })
        .collect();
    m.gen_for("q", q, "g_pre_client", items);
}

/// The register pairs holding byte addresses.
const BASES: [&str; 5] = ["desc", "result", "feat", "fb", "scratch"];

fn pair(a: &str, b: &str) -> (String, String) {
    (a.to_string(), b.to_string())
}

/// A core's clock gate `u_gate` in a generate block: the wire `core_clk`, running while `en`.
fn core_clock_gate(en: &str) -> [Item; 2] {
    let ports =
        vec![pair("clk_i", "clk_i"), pair("rst_ni", "rst_ni"), pair("en_i", en), pair("clk_o", "core_clk")];
    [Item::Wire { name: "core_clk".into(), width: 1 }, inst(clock_gate::NAME, "u_gate", ports)]
}

/// `g_sort[i]`: sequencer, Sorting Core, bridge. The sequencer and the core are clocked by
/// `u_gate` from the cycle a job is offered until the sequencer is idle again: it completes a job
/// only after every command's done and an idle bridge, so the core is idle whenever the clock
/// stops.
fn sort_cores(m: &mut Module, cfg: &EngineConfig, cl: &Clients) {
    let (n, aw, lw) = (cl.sort as u32, cfg.addr_bits, cfg.len_bits);
    m.blank();
    m.comment("Sort bridges' events (one bit per core).");
    m.wire("sort_rd", n).wire("sort_wr", n).vector("sort_rd").vector("sort_wr");
    let mut items = Vec::new();
    let w = |name: &str, width: u32| Item::Wire { name: name.into(), width };
    let core_ports: Vec<(String, bool, u32)> = ports_of(&sort_core::module(cfg), "")
        .into_iter()
        .filter(|(p, _, _)| p != "clk_i" && p != "rst_ni")
        .collect();
    for (port, _, width) in &core_ports {
        items.push(w(wire_of(port), *width));
    }
    items.extend(core_clock_gate("job_valid[i] | ~job_ready[i]"));
    let mut seq = vec![pair("clk_i", "core_clk"), pair("rst_ni", "rst_ni")];
    seq.push(pair("job_valid_i", "job_valid[i]"));
    seq.push(pair("job_ready_o", "job_ready[i]"));
    for s in ["from_scratch", "prev", "prev_len", "list", "list_len", "next", "dps_passes", "dps_wide", "odd"]
    {
        seq.push((format!("job_{s}_i"), format!("job_{s}")));
    }
    seq.push(pair("job_scratch_i", &format!("job_scratch[i*{aw} +: {aw}]")));
    for (port, _, _) in core_ports.iter().filter(|(p, _, _)| p.starts_with("cmd_")) {
        seq.push((flip(port), wire_of(port).to_string()));
    }
    seq.push(pair("done_i", "done"));
    seq.push(pair("done_len_i", "done_len"));
    seq.push(pair("done_inv_i", "done_inv"));
    seq.push(pair("idle_i", "idle[i]"));
    seq.push(pair("cpl_valid_o", "cpl_valid[i]"));
    seq.push(pair("cpl_ready_i", "cpl_ready[i]"));
    seq.push(pair("cpl_len_o", &format!("cpl_len[i*{lw} +: {lw}]")));
    seq.push(pair("cpl_inv_o", &format!("cpl_inv[i*{lw} +: {lw}]")));
    items.push(inst(sort_seq::NAME, "u_seq", seq));
    let mut core = vec![pair("clk_i", "core_clk"), pair("rst_ni", "rst_ni")];
    core.extend(core_ports.iter().map(|(p, _, _)| (p.clone(), wire_of(p).to_string())));
    items.push(inst(sort_core::NAME, "u_core", core));
    let mut br = vec![pair("clk_i", "clk_i"), pair("rst_ni", "rst_ni")];
    let mem = core_ports.iter().filter(|(p, _, _)| p.starts_with("mem_"));
    br.extend(mem.map(|(p, _, _)| (flip(p), wire_of(p).to_string())));
    br.push(pair("idle_o", "idle[i]"));
    br.push(pair("rd_beat_o", "sort_rd[i]"));
    br.push(pair("wr_beat_o", "sort_wr[i]"));
    br.extend(client_conns(cfg, "m_axi_", &cl.position_expr("i", cl.first_sort)));
    items.push(inst(axi::sort_bridge::NAME, "u_bridge", br));
    m.gen_for("i", n, "g_sort", items);
}

/// `g_raster[j]`: Rasterization Core and bridge. The core's clock is gated (`u_gate`) while it
/// is idle with no command offered and its done pulse given: it runs from the cycle a command is
/// offered to the cycle after its done.
fn raster_cores(m: &mut Module, cfg: &EngineConfig, cl: &Clients) {
    let (n, mm, lw) = (cl.sort, cl.raster as u32, cfg.len_bits);
    m.blank();
    m.comment("Raster bridges' events (one bit per core).");
    for e in ["ras_rd_table", "ras_rd_feat", "ras_wr_table", "ras_wr_pixels"] {
        m.wire(e, mm).vector(e);
    }
    let core_ports = ports_of(&raster_core::module(cfg), "mem_");
    let mut items: Vec<Item> = core_ports
        .iter()
        .map(|(p, _, width)| Item::Wire { name: wire_of(p).into(), width: *width })
        .collect();
    items.extend(core_clock_gate("ras_valid[j] | ~ras_ready[j] | ras_done[j]"));
    let mut core = vec![pair("clk_i", "core_clk"), pair("rst_ni", "rst_ni")];
    core.push(pair("cmd_valid_i", "ras_valid[j]"));
    core.push(pair("cmd_ready_o", "ras_ready[j]"));
    for s in ["tile_x", "tile_y", "width", "height", "table", "len", "feat", "pix"] {
        core.push((format!("cmd_{s}_i"), format!("ras_{s}")));
    }
    core.push(pair("done_o", "ras_done[j]"));
    core.push(pair("done_wb_len_o", &format!("ras_wb_len[j*{lw} +: {lw}]")));
    core.push(pair("done_wb_reach_o", &format!("ras_wb_reach[j*{lw} +: {lw}]")));
    core.extend(core_ports.iter().map(|(p, _, _)| (p.clone(), wire_of(p).to_string())));
    items.push(inst(raster_core::NAME, "u_core", core));
    let mut br = vec![pair("clk_i", "clk_i"), pair("rst_ni", "rst_ni")];
    br.extend(core_ports.iter().map(|(p, _, _)| (flip(p), wire_of(p).to_string())));
    br.push(pair("idle_o", &format!("idle[{n} + j]")));
    br.push(pair("rd_table_o", "ras_rd_table[j]"));
    br.push(pair("rd_feat_o", "ras_rd_feat[j]"));
    br.push(pair("wr_table_o", "ras_wr_table[j]"));
    br.push(pair("wr_pixels_o", "ras_wr_pixels[j]"));
    br.extend(client_conns(cfg, "m_axi_", &cl.position_expr("j", cl.first_raster)));
    items.push(inst(axi::raster_bridge::NAME, "u_bridge", br));
    m.gen_for("j", mm, "g_raster", items);
}

/// A port of a core as seen from its bridge (`_i` and `_o` swapped).
fn flip(port: &str) -> String {
    if let Some(b) = port.strip_suffix("_i") {
        format!("{b}_o")
    } else if let Some(b) = port.strip_suffix("_o") {
        format!("{b}_i")
    } else {
        port.to_string()
    }
}

fn inst(module: &str, name: &str, conns: Vec<(String, String)>) -> Item {
    Item::Instance(Instance { module: module.into(), name: name.into(), params: Vec::new(), conns })
}

/// `g_port[k]`: the muxes, and the top-level ports from the port buses.
fn ports(m: &mut Module, cfg: &EngineConfig, cl: &Clients) {
    let (k, p) = (cl.ports as u32, cl.slots());
    let sigs = axi::signals(cfg);
    m.blank();
    m.comment("Port buses: port k's AXI4 signals at [k*W +: W].");
    for s in &sigs {
        m.wire(format!("port_{}", s.name), k * s.width).vector(format!("port_{}", s.name));
    }
    let mut c = vec![pair("clk_i", "clk_i"), pair("rst_ni", "rst_ni")];
    for s in &sigs {
        // Port k's P clients are clients k*P .. k*P+P-1 of the client buses.
        let bus = format!("cl_{}[k*{p}*{w} +: {p}*{w}]", s.name, w = s.width);
        c.push((axi::mux::client_port(s), bus));
    }
    for s in &sigs {
        c.push((axi::port_name("m_axi_", s, true), format!("port_{}[k*{w} +: {w}]", s.name, w = s.width)));
    }
    let mux = Item::Instance(Instance {
        module: axi::mux::NAME.into(),
        name: "u_mux".into(),
        params: vec![("PORTS".into(), p.to_string())],
        conns: c,
    });
    m.gen_for("k", k, "g_port", vec![mux]);
    for port in 0..k {
        for s in &sigs {
            let top = axi::port_name(&format!("m{port}_axi_"), s, true);
            let bus = format!("port_{}[{port}*{w} +: {w}]", s.name, w = s.width);
            if s.from_manager {
                m.assign(top, bus);
            } else {
                m.assign(bus, top);
            }
        }
    }
}

/// A sum of the bits of `v` (`n` bits wide) as a `w`-bit value.
fn popcount(v: &str, n: u32, w: u32) -> String {
    if n == 1 {
        return format!("{{{}, {v}}}", lit(w - 1, 0));
    }
    let terms: Vec<String> = (0..n).map(|i| format!("{{{}, {v}[{i}]}}", lit(w - 1, 0))).collect();
    terms.join(" + ")
}

/// The counters' increments.
fn counters(m: &mut Module, cfg: &EngineConfig, cl: &Clients) {
    let iw = perf_counters::INC_BITS;
    let (n, mm) = (cl.sort as u32, cl.raster as u32);
    m.blank();
    m.comment("Performance counters: each one's increment this cycle (golden engine::regs::Counter).");
    m.wire("inc", iw * COUNTERS as u32);
    let pixels = u64::from(cfg.subtile) * PIXEL_BYTES;
    let (q, beat) = (cl.pre as u32, u64::from(cfg.axi_data_bits / 8));
    if q > 0 {
        m.wire_assign("pre_r_beat", q, "pre_rvalid & pre_rready");
        m.wire_assign("pre_w_beat", q, "pre_wvalid & pre_wready");
    }
    let bytes = |v: &str, count: u32, b: u64| {
        if count == 0 {
            lit(iw, 0)
        } else {
            format!("({}) * {}", popcount(v, count, iw), lit(iw, b))
        }
    };
    let ev = |e: &str| format!("ev_{e}");
    let events = ports_of(&frame_ctrl::module(cfg), "ev_");
    let ew = |e: &str| {
        let port = format!("ev_{e}_o");
        events
            .iter()
            .find(|(p, _, _)| *p == port)
            .map(|(_, _, w)| *w)
            .unwrap_or_else(|| panic!("{} has no {port}", frame_ctrl::NAME))
    };
    for c in Counter::ALL {
        let rhs = match c {
            Counter::Cycles => format!("{{{}, frame_busy}}", lit(iw - 1, 0)),
            Counter::SortBusy => format!("{{{}, frame_busy & ~(&job_ready)}}", lit(iw - 1, 0)),
            Counter::RasterBusy => format!("{{{}, frame_busy & ~(&ras_ready)}}", lit(iw - 1, 0)),
            Counter::TilesSorted => widen(&ev("tile_sorted"), ew("tile_sorted"), iw),
            Counter::TilesRastered => widen(&ev("tile_rastered"), ew("tile_rastered"), iw),
            Counter::EntriesSorted => widen(&ev("entries_sorted"), ew("entries_sorted"), iw),
            Counter::EntriesRastered => widen(&ev("entries_rastered"), ew("entries_rastered"), iw),
            Counter::RdDesc => bytes(&ev("desc_read"), 1, DESCRIPTOR_BYTES),
            Counter::RdSort => bytes("sort_rd", n, ENTRY_BYTES),
            Counter::WrSort => bytes("sort_wr", n, ENTRY_BYTES),
            Counter::RdTable => bytes("ras_rd_table", mm, ENTRY_BYTES),
            Counter::RdFeat => bytes("ras_rd_feat", mm, FEATURE_BYTES),
            Counter::WrTable => bytes("ras_wr_table", mm, ENTRY_BYTES),
            Counter::WrPixel => bytes("ras_wr_pixels", mm, pixels),
            Counter::WrResult => bytes(&ev("result_written"), 1, RESULT_BYTES),
            Counter::PreBusy => format!("{{{}, pre_busy}}", lit(iw - 1, 0)),
            Counter::RdPre => bytes("pre_r_beat", q, beat),
            Counter::WrPre => bytes("pre_w_beat", q, beat),
            Counter::RdResult => bytes(&ev("result_read"), 1, RESULT_BYTES),
        };
        m.assign(format!("inc[{}*{iw} +: {iw}]", c.index()), rhs);
    }
    for e in ["tile_sorted", "tile_rastered", "entries_sorted", "entries_rastered"] {
        let w = ew(e);
        if w > iw {
            m.comment(format!(
                "ev_{e} above bit {}: never set (a sorted tile holds at most table_capacity entries).",
                iw - 1
            ));
            m.wire_assign(format!("unused_ev_{e}"), 1, format!("|ev_{e}[{} : {iw}]", w - 1));
        }
    }
    let c = vec![
        pair("clk_i", "clk_i"),
        pair("rst_ni", "rst_ni"),
        pair("clear_i", "start"),
        pair("inc_i", "inc"),
        pair("counters_o", "counters"),
    ];
    m.instance(perf_counters::NAME, "u_counters", c);
}

/// `v` (`w_in` bits) zero-extended or cut to `w` bits.
fn widen(v: &str, w_in: u32, w: u32) -> String {
    match w_in.cmp(&w) {
        std::cmp::Ordering::Less => format!("{{{}, {v}}}", lit(w - w_in, 0)),
        std::cmp::Ordering::Equal => v.to_string(),
        std::cmp::Ordering::Greater => format!("{v}[{} : 0]", w - 1),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_client_has_its_own_slot_and_ports_share_the_load() {
        for (sort_cores, raster_cores, pre_units, ports) in
            [(16, 4, 4, 4), (2, 1, 1, 2), (1, 1, 1, 1), (3, 2, 2, 4), (16, 4, 16, 1), (2, 1, 0, 2)]
        {
            let cfg = EngineConfig {
                sort_cores,
                raster_cores,
                pre_units,
                mem_channels: ports,
                ..EngineConfig::default()
            };
            let cl = Clients::of(&cfg);
            let mut seen: Vec<usize> = (0..cl.count()).map(|c| cl.position(c)).collect();
            seen.sort_unstable();
            seen.dedup();
            assert_eq!(seen.len(), cl.count(), "{cl:?}");
            assert!(seen.iter().all(|&p| p < cl.ports * cl.slots()), "{cl:?}");
            let per_port = |k: usize| (0..cl.count()).filter(|&c| cl.position(c) / cl.slots() == k).count();
            let (lo, hi) = ((0..ports).map(per_port).min().unwrap(), (0..ports).map(per_port).max().unwrap());
            assert!(hi - lo <= 1 && hi == cl.slots(), "{cl:?}: {lo}..{hi}");
        }
    }
}
