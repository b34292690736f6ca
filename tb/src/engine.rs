//! Whole-frame cosimulation of `neo_engine` (issue 11): the golden host session
//! ([`EngineSession`](neo_golden::engine::host::EngineSession)) writes each frame's inputs into
//! memory, the harness programs the control port through an AXI4-Lite driver, an [`AxiMemory`]
//! serves the engine's AXI4 ports (with its latency, bandwidth, random delays and reordering across
//! IDs) under an [`AxiChecker`] per port and a [`HazardChecker`] over all ports (no RAW, WAR or WAW
//! between transactions in flight at once; nothing in flight when `done` rises), and after `done`
//! the frame buffer, every tile's next table, the results, the status registers and the golden
//! counters are compared with [`Expected`](neo_golden::engine::expected::Expected). A frame is
//! declared hung after [`quiet_limit`] cycles without a handshake on any port, or after its
//! [`frame_cycle_bound`] (from its work).
//!
//! Driver (AXI4-Lite manager, memory ports), golden model (the session's
//! [`Expected`](neo_golden::engine::expected::Expected)) and checker (`Expected::compare`, the AXI
//! checkers) are apart. The engine model is built at run time for any configuration
//! ([`EngineModel::build`]) and cached by content hash.

use crate::axi::{
    AddrRecord, AxiBinding, AxiChecker, AxiMemory, AxiTiming, HazardChecker, ManagerSignals,
    SubordinateSignals,
};
use crate::axil::{AxilManager, AxilOp};
use crate::check::Checker;
use crate::dut::PortIo;
use crate::dynmodel::{BuildInfo, DynModel};
pub use crate::engine_budget::{frame_cycle_bound, quiet_limit, FrameWork};
use crate::rng::Rng;
use crate::waves::WaveFormat;
use neo_gen::interface::ModuleInterface;
use neo_gen::EngineConfig;
use neo_golden::engine::expected::Mismatch;
use neo_golden::engine::host::FramePlan;
use neo_golden::engine::memory::Memory;
use neo_golden::engine::reference::FrameOutcome;
use neo_golden::engine::regs::{Counter, Counters, Reg, CTRL_START};
use neo_golden::engine::MemoryClient;
use std::collections::HashMap;
use std::path::PathBuf;

/// The engine's top module.
pub const TOP: &str = "neo_engine";

/// The engine the CI benches build (`tb/engine_ci.json`, also what `scripts/mutate-check`
/// generates for engine mutations): the default units with 2 Sorting Cores, 1 Rasterization
/// Core and 2 memory ports.
pub fn ci_config() -> EngineConfig {
    serde_json::from_str(include_str!("../engine_ci.json"))
        .expect("tb/engine_ci.json is an engine configuration")
}

/// The verilated engine of one configuration.
pub struct EngineModel {
    /// The configuration it was generated from.
    pub cfg: EngineConfig,
    /// The model.
    pub model: DynModel,
    /// How it was built.
    pub build: BuildInfo,
}

impl EngineModel {
    /// Generates `neo_engine` for `cfg`, verilates and compiles it (or finds it in the cache).
    /// With `NEO_HDL_DIR=DIR` (mutation testing) whose `neo_engine.v` was generated from this
    /// very configuration (its header names `cfg.hash()`), that file is read from `DIR` (the
    /// units come from the generator: `DIR` holds the default configuration's units for the
    /// static models); engines of other configurations are generated as usual.
    /// The model is built without tracing (about half the C++ of a traced one); see
    /// [`EngineModel::build_traced`] for waves.
    pub fn build(cfg: &EngineConfig) -> Result<EngineModel, String> {
        Self::build_traced(cfg, None)
    }

    /// [`EngineModel::build`] tracing in `format` (`None`: untraced); each is a separate build
    /// and cache entry, and [`EngineRig::new`] takes a waves path of the model's format only.
    pub fn build_traced(cfg: &EngineConfig, format: Option<WaveFormat>) -> Result<EngineModel, String> {
        Self::build_threaded(cfg, format, 1)
    }

    /// [`EngineModel::build_traced`] with the per-cycle code compiled for build time rather
    /// than speed ([`DynModel::build_for_short_runs`], `-O1`; its own cache entry): for the
    /// benches' small engines, whose frames simulate about as fast as at `-O3`.
    pub fn build_for_short_runs(
        cfg: &EngineConfig,
        format: Option<WaveFormat>,
    ) -> Result<EngineModel, String> {
        let (files, vlt, iface) = engine_sources(cfg)?;
        let (model, build) = DynModel::build_for_short_runs(&iface, &files, Some(&vlt), format)?;
        Ok(EngineModel { cfg: cfg.clone(), model, build })
    }

    /// [`EngineModel::build_traced`] verilated with `--threads threads` (1: the usual
    /// single-threaded model); see [`DynModel::build_threaded`].
    pub fn build_threaded(
        cfg: &EngineConfig,
        format: Option<WaveFormat>,
        threads: usize,
    ) -> Result<EngineModel, String> {
        let (files, vlt, iface) = engine_sources(cfg)?;
        let (model, build) = DynModel::build_threaded(&iface, &files, Some(&vlt), format, threads)?;
        Ok(EngineModel { cfg: cfg.clone(), model, build })
    }
}

/// The Verilog files (name, text) of a top.
type Files = Vec<(String, String)>;

/// The Verilog files, the lint waivers and the interface of `neo_engine` for `cfg` (see
/// [`EngineModel::build`] for `NEO_HDL_DIR`).
fn engine_sources(cfg: &EngineConfig) -> Result<(Files, String, ModuleInterface), String> {
    cfg.validate().map_err(|e| e.to_string())?;
    let (files, vlt) = crate::dynmodel::generated_files(cfg, TOP)?;
    // In coverage mode the engine's bench measures neo_engine.v itself: its units have benches
    // of their own (and the whole engine with coverage is C++ that takes long to compile).
    let vlt = crate::coverage::only_in(vlt, &files, &[&format!("{TOP}.v")]);
    Ok((files, vlt, crate::dynmodel::generated_interface(cfg, TOP)?))
}

/// The transactions each memory client may have in flight, `(reads, writes)`, in client order
/// ([`MemoryClient`]): the frame controller and the bridges `axi_outstanding` each; the
/// Preprocessing Engine's lane ports read `pre_outstanding` bursts and write `axi_outstanding`,
/// its list writer `pre_outstanding` each.
pub fn client_limits(cfg: &EngineConfig) -> Vec<(usize, usize)> {
    let (a, p) = (cfg.axi_outstanding, cfg.pre_outstanding);
    let limits = |client: &MemoryClient| match client {
        MemoryClient::PreGeometry(_) | MemoryClient::PreSh(_) => (p, a),
        MemoryClient::PreListWriter => (p, p),
        _ => (a, a),
    };
    cfg.memory_client_list().iter().map(limits).collect()
}

/// The transactions in flight each AXI port may carry, `(reads, writes)`: the sums of its
/// clients' limits ([`client_limits`]; client `c` on its port of
/// [`EngineConfig::client_port_slot`]).
pub fn port_limits(cfg: &EngineConfig) -> Vec<(usize, usize)> {
    let mut ports = vec![(0, 0); cfg.mem_channels];
    for (c, (r, w)) in client_limits(cfg).into_iter().enumerate() {
        let (port, _) = cfg.client_port_slot(c);
        ports[port].0 += r;
        ports[port].1 += w;
    }
    ports
}

/// The name of memory client `c` ([`MemoryClient`]'s), or `no client (c)` past the last.
pub fn client_name(cfg: &EngineConfig, c: usize) -> String {
    cfg.memory_client(c).map_or_else(|| format!("no client ({c})"), |client| client.to_string())
}

/// Names `(port, id)` by its memory client: the port mux's ID is the client's slot
/// ([`EngineConfig::port_slot_client`]).
fn client_namer(cfg: &EngineConfig) -> crate::axi::hazard::Namer {
    let cfg = cfg.clone();
    Box::new(move |port, id| {
        let c = cfg.port_slot_client(port, id as usize);
        format!("client {c}: {}", client_name(&cfg, c))
    })
}

/// Whether one port had a handshake (AR, AW, W, R or B) this cycle.
fn any_handshake(m: &ManagerSignals, s: &SubordinateSignals) -> bool {
    (m.ar.is_some() && s.arready)
        || (m.aw.is_some() && s.awready)
        || (m.w.is_some() && s.wready)
        || (s.r.is_some() && m.rready)
        || (s.b.is_some() && m.bready)
}

/// Memory timing and stimulus of a run, and when a frame is declared hung.
#[derive(Clone, Copy, Debug)]
pub struct RunOptions {
    /// The memory's timing on every port.
    pub timing: AxiTiming,
    /// Cycles a frame may take before the run is declared hung; `None` (the default): the
    /// frame's own bound from its work, [`frame_cycle_bound`].
    pub max_cycles: Option<u64>,
    /// Cycles without a handshake on any AXI4 port and without a change of `done` before the
    /// run is declared hung; `None` (the default): the configuration's [`quiet_limit`].
    pub max_quiet: Option<u64>,
}

impl Default for RunOptions {
    fn default() -> Self {
        RunOptions { timing: AxiTiming::RANDOM, max_cycles: None, max_quiet: None }
    }
}

/// The outcome of one frame.
#[derive(Clone, Debug)]
pub struct FrameReport {
    /// Frame index.
    pub frame: usize,
    /// Whether the frame was sorted from scratch.
    pub from_scratch: bool,
    /// The first difference from golden, `None` when bit-exact.
    pub mismatch: Option<Mismatch>,
    /// Cycles from start to done (the `CYCLES` counter).
    pub rtl_cycles: u64,
    /// Every counter as the engine reports it.
    pub counters: Counters,
    /// Cycles the harness ran (programming and read-back included).
    pub harness_cycles: u64,
    /// The cycles the frame was allowed before it counted as hung (the frame's
    /// [`frame_cycle_bound`] or `RunOptions::max_cycles`).
    pub cycle_bound: u64,
    /// The longest stretch of the frame without a handshake on any AXI4 port (cycles), against
    /// the watchdog's limit ([`quiet_limit`] or `RunOptions::max_quiet`).
    pub longest_quiet: u64,
}

/// The engine under test, its memory and its control-port driver.
pub struct EngineRig {
    engine: EngineModel,
    axi: Vec<AxiBinding>,
    checkers: Vec<AxiChecker>,
    hazards: HazardChecker,
    mem: AxiMemory,
    lite: AxilManager,
    checker: Checker,
    done: usize,
    opts: RunOptions,
    waves: Option<PathBuf>,
}

impl EngineRig {
    /// A rig around `engine` with an empty memory; resets the engine. `waves`: a trace of the
    /// whole run, VCD or FST by its extension, which must be the format the model was built
    /// for ([`EngineModel::build_traced`]); a GTKWave save file listing the engine's ports is
    /// written beside it ([`crate::waves::write_gtkw`]).
    pub fn new(
        engine: EngineModel,
        opts: RunOptions,
        seed: u64,
        waves: Option<PathBuf>,
    ) -> Result<EngineRig, String> {
        let mut engine = engine;
        let k = engine.cfg.mem_channels;
        let m = &engine.model;
        let axi: Vec<AxiBinding> =
            (0..k).map(|p| AxiBinding::bind(m, &format!("m{p}_axi_"), true)).collect::<Result<_, _>>()?;
        let limits = port_limits(&engine.cfg);
        let checkers = limits
            .iter()
            .enumerate()
            .map(|(p, &(reads, writes))| AxiChecker::new(p, &format!("m{p}_axi"), reads, writes))
            .collect();
        let hazards = HazardChecker::new(k).with_namer(client_namer(&engine.cfg));
        let mut rng = Rng::new(seed);
        let lite = AxilManager::bind(m, "s_axil_", rng.fork(1))?;
        let done = m.port("done_o")?;
        if let Some(path) = &waves {
            if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
                std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
            }
            engine.model.trace_open(path).map_err(|e| e.to_string())?;
            let ports = engine.model.interface().ports.iter().map(|p| (p.name.as_str(), p.width));
            crate::waves::write_gtkw(path, TOP, ports).map_err(|e| format!("{}: {e}", path.display()))?;
        }
        engine.model.reset();
        let mem = AxiMemory::new(k, Memory::new(), opts.timing, rng.next_u64());
        Ok(EngineRig {
            engine,
            axi,
            checkers,
            hazards,
            mem,
            lite,
            checker: Checker::new(TOP, seed),
            done,
            opts,
            waves,
        })
    }

    /// The memory the engine sees (the host writes a frame's inputs here).
    pub fn memory_mut(&mut self) -> &mut Memory {
        self.mem.memory_mut()
    }

    /// The memory.
    pub fn memory(&self) -> &Memory {
        self.mem.memory()
    }

    /// The engine's configuration.
    pub fn config(&self) -> &EngineConfig {
        &self.engine.cfg
    }

    /// Starts (`true`) or stops recording every AR and AW the memory takes: a transfer log
    /// ([`EngineRig::take_transfers`]), lighter than a trace for finding when each tile's
    /// traffic ran on which port.
    pub fn record_transfers(&mut self, on: bool) {
        self.mem.record_addresses(on);
    }

    /// The transfers recorded since the last call, each with its memory client's index
    /// (name it with [`client_name`]; the port mux's ID is the client's slot on its port).
    pub fn take_transfers(&mut self) -> Vec<(AddrRecord, usize)> {
        let cfg = &self.engine.cfg;
        self.mem
            .take_addresses()
            .into_iter()
            .map(|r| (r, cfg.port_slot_client(r.port, r.id as usize)))
            .collect()
    }

    /// Read and write data beats each port has moved so far.
    pub fn port_beats(&self) -> Vec<(u64, u64)> {
        (0..self.engine.cfg.mem_channels).map(|k| self.mem.beats(k)).collect()
    }

    /// The trace being written (VCD or FST), if any.
    pub fn waves(&self) -> Option<&PathBuf> {
        self.waves.as_ref()
    }

    /// One clock cycle: drive the control port and the memory's outputs, settle, check and
    /// sample every port (the protocol checker of each, the ordering checker of all), then the
    /// edge. Returns whether any AXI4 port had a handshake this cycle.
    fn cycle(&mut self) -> Result<bool, String> {
        let model = &mut self.engine.model;
        self.lite.drive(model);
        for (k, b) in self.axi.iter().enumerate() {
            b.set_subordinate(model, &self.mem.outputs(k));
        }
        model.eval();
        let cycle = model.cycle();
        let seed = self.checker.seed;
        let mut ports: Vec<(ManagerSignals, SubordinateSignals)> = Vec::with_capacity(self.axi.len());
        for (k, b) in self.axi.iter().enumerate() {
            let m = b.get_manager(model);
            let s = self.mem.outputs(k);
            if let Err(v) = self.checkers[k].observe(&m, &s) {
                return Err(format!("cycle {cycle}: {v} (seed 0x{seed:016x})"));
            }
            ports.push((m, s));
        }
        if let Err(h) = self.hazards.observe(&ports) {
            return Err(format!("cycle {cycle}: {h} (seed 0x{seed:016x})"));
        }
        self.lite.sample(model, &self.checker);
        let mut handshake = false;
        for (k, (m, s)) in ports.iter().enumerate() {
            handshake |= any_handshake(m, s);
            self.mem.tick(k, m);
        }
        model.tick();
        Ok(handshake)
    }

    /// Runs cycles until the control-port driver has finished every queued operation.
    fn settle_lite(&mut self) -> Result<(), String> {
        let start = self.engine.model.cycle();
        while !self.lite.is_idle() {
            self.cycle()?;
            if self.engine.model.cycle() - start > 100_000 {
                return Err("the control port does not answer (100000 cycles)".into());
            }
        }
        Ok(())
    }

    /// Runs one frame of `plan` (its inputs already in memory): programs the registers,
    /// starts, waits for `done`, reads the registers back and compares with golden.
    pub fn run_frame(&mut self, plan: &FramePlan) -> Result<FrameReport, String> {
        // The RTL ignores a base's low bits: refuse a misaligned one rather than run elsewhere.
        plan.regs.check(&self.engine.cfg).map_err(|e| format!("frame {}: {e}", plan.frame))?;
        let t0 = self.engine.model.cycle();
        for (r, v) in plan.regs.writes() {
            self.lite.write(r.offset(), v, 0xf);
        }
        self.lite.write(Reg::Ctrl.offset(), CTRL_START, 0xf);
        self.settle_lite()?;
        while self.lite.pop().is_some() {}
        let started = self.engine.model.cycle();
        let bound = self
            .opts
            .max_cycles
            .unwrap_or_else(|| frame_cycle_bound(&self.engine.cfg, plan, &self.opts.timing));
        let quiet_max = self.opts.max_quiet.unwrap_or_else(|| quiet_limit(&self.engine.cfg));
        let (mut last_progress, mut longest_quiet) = (started, 0);
        while self.engine.model.io_get(self.done) == 0 {
            let progress = self.cycle()?;
            let now = self.engine.model.cycle();
            if progress {
                last_progress = now;
            }
            longest_quiet = longest_quiet.max(now - last_progress);
            if now - last_progress > quiet_max {
                return Err(self.hung(plan, &format!("no AXI4 handshake on any port for {quiet_max} cycles (the watchdog's limit, quiet_limit)")));
            }
            if now - started > bound {
                return Err(self.hung(
                    plan,
                    &format!(
                        "no done after {bound} cycles (the frame's bound from its work, frame_cycle_bound)"
                    ),
                ));
            }
        }
        if let Err(busy) = self.hazards.check_quiescent() {
            let why = "done raised while transactions are in flight or offered";
            return Err(self.stopped(plan, "EARLY DONE", why, &busy));
        }
        let regs = self.read_registers()?;
        let outcome =
            FrameOutcome::read_back(&plan.regs, self.mem.memory(), |a| regs.get(&a).copied().unwrap_or(0));
        let mismatch =
            plan.expected.compare(self.mem.memory()).or_else(|| plan.expected.compare_outcome(&outcome));
        Ok(FrameReport {
            frame: plan.frame,
            from_scratch: plan.from_scratch,
            mismatch,
            rtl_cycles: outcome.counters.get(Counter::Cycles),
            counters: outcome.counters,
            harness_cycles: self.engine.model.cycle() - t0,
            cycle_bound: bound,
            longest_quiet,
        })
    }

    /// The error of a frame stopped as `what` (HUNG, EARLY DONE): `why`, the frame, cycle and
    /// seed, and what each port has in flight (`in_flight`).
    fn stopped(&self, plan: &FramePlan, what: &str, why: &str, in_flight: &str) -> String {
        format!(
            "frame {}: {what} at cycle {}: {why} (seed 0x{:016x}); in flight:{in_flight}",
            plan.frame,
            self.engine.model.cycle(),
            self.checker.seed
        )
    }

    /// The error of a hung frame: [`Self::stopped`] with every port's transactions.
    fn hung(&self, plan: &FramePlan, why: &str) -> String {
        self.stopped(plan, "HUNG", why, &self.hazards.describe())
    }

    /// Reads STATUS, FIRST_OVERFLOW, OVERFLOWS and both words of every counter.
    fn read_registers(&mut self) -> Result<HashMap<u32, u32>, String> {
        let mut addrs = vec![Reg::Status.offset(), Reg::FirstOverflow.offset(), Reg::Overflows.offset()];
        for c in Counter::ALL {
            addrs.extend([c.offset(), c.offset() + 4]);
        }
        for &a in &addrs {
            self.lite.read(a);
        }
        self.settle_lite()?;
        let mut out = HashMap::new();
        while let Some(d) = self.lite.pop() {
            if let AxilOp::Read { addr } = d.op {
                out.insert(addr, d.data);
            }
        }
        Ok(out)
    }

    /// Closes the trace, if one is open.
    pub fn finish(&mut self) {
        self.engine.model.trace_close();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn port_limits_sum_each_ports_clients() {
        let cfg = EngineConfig { pre_units: 2, pre_outstanding: 64, ..ci_config() };
        let c = client_limits(&cfg);
        assert_eq!(c.len(), cfg.memory_clients(), "1 + 2 + 1 + 2 * 2 + 1");
        assert_eq!((c[0], c[3], c[4], c[5], c[8]), ((8, 8), (8, 8), (64, 8), (64, 8), (64, 64)));
        // Port 0: clients 0, 2, 4, 6, 8; port 1: clients 1, 3, 5, 7.
        assert_eq!(
            port_limits(&cfg),
            vec![(8 + 8 + 64 + 64 + 64, 8 + 8 + 8 + 8 + 64), (8 + 8 + 64 + 64, 32)]
        );
    }
}
