//! `neo cosim`: the verilated `neo_engine` on a user's scene, frame by frame, checked bit-exactly
//! against the golden model (frame buffer, next tables, results, registers, golden counters).
//!
//! The engine of the configuration is generated, verilated and compiled on first use and cached
//! by content hash (`neo_tb::dynmodel`); the golden host session writes each frame's inputs into
//! the harness's AXI memory. `--model-only` prints the engine-level cycle model's prediction of
//! each frame instead, with golden's reference in the engine's place.

use crate::args::{SceneArg, StrictArg, TrajectoryArg};
use crate::engine_run;
use anyhow::{anyhow, bail, Context, Result};
use clap::Args;
use indicatif::ProgressBar;
use neo_golden::engine::host::MemoryLayout;
use neo_golden::engine::{
    execute_frame, Counter, EngineConfig, EngineSession, Memory, Planner, SessionOptions,
};
use neo_golden::hwpre::ShPrecision;
use neo_golden::pipeline::Strategy;
use neo_golden::source;
use neo_golden::trajectory::parse_resolution;
use neo_sim::engine_frame::{error_pct, EngineFrameModel, FramePrediction, PortTiming};
use neo_sim::latency;
use neo_tb::axi::{AddrRecord, AxiTiming};
use neo_tb::engine::{client_name, EngineRig, FrameReport, RunOptions};
use neo_tb::waves::WaveFormat;
use std::path::{Path, PathBuf};
use std::time::Duration;

/// Arguments of `neo cosim`.
#[derive(Args)]
pub struct CosimArgs {
    #[command(flatten)]
    pub scene: SceneArg,
    #[command(flatten)]
    pub trajectory: TrajectoryArg,
    /// Frames to run.
    #[arg(long, default_value_t = 3)]
    pub frames: usize,
    /// Resolution `WxH` (or `hd`, `fhd`, `qhd`).
    #[arg(long, default_value = "256x256", value_parser = parse_resolution)]
    pub res: (u32, u32),
    /// Engine configuration (the JSON `neo gen --config` takes); default: the paper's 16 + 4
    /// engine (its first build takes several minutes).
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// Memory timing of the harness: `random` (latency, 3/4 bandwidth, random delays,
    /// reordering across IDs) or `ideal` (one cycle, full bandwidth, in order).
    #[arg(long, default_value = "random")]
    pub memory: String,
    /// Seed of the harness's random timing (default: from the clock; printed).
    #[arg(long)]
    pub seed: Option<String>,
    /// Write a trace of the whole run to this path: FST when it ends in `.fst` (compressed; an
    /// FST-traced engine is a separate, cached build), else VCD; a GTKWave save file (`.gtkw`)
    /// is written beside it.
    #[arg(long)]
    pub waves: Option<PathBuf>,
    /// Where the engine's inputs come from: `scene` (the host writes the baked scene once and
    /// programs the camera; the engine's Preprocessing Engine makes every frame's feature words,
    /// incoming lists and their lengths) or `lists` (the host writes golden's incoming lists and
    /// feature words; the Preprocessing Engine is off).
    #[arg(long, default_value = "scene")]
    pub input: String,
    /// SH records the engine reads in scene mode: `f32` or `f16` (binary16, two coefficients a
    /// word: `PRE_CTRL.sh_half`; the golden pipeline preprocesses with `hw:f16`).
    #[arg(long, default_value = "f32", value_parser = super::scene::parse_sh)]
    pub sh: ShPrecision,
    /// The sorting strategy the host plans and the engine runs: `neo` (one DPS pass per reuse
    /// tile) or `adaptive:wide=W,resort=0[,budget=B,max=P]` (the per-tile DPS passes of golden's
    /// adaptive policy and whether they use the wide chunk, written into the descriptors; `W` 1 or
    /// the engine's `dps_wide`: a `--config` file with `"dps_wide": 16` for `wide=16`); with
    /// `--input lists` also `resort=1` (a re-sorted tile's descriptor says from scratch, the host
    /// writes its whole list).
    #[arg(long, default_value = "neo")]
    pub sort: String,
    /// Who plans the `adaptive` DPS passes: `host` (written into the descriptors) or `engine`
    /// (the frame controller plans them from the previous frame's results, `ADAPT_CTRL`;
    /// `adaptive` with `resort=0,max<=15` and `wide` 1 or the engine's `dps_wide`).
    #[arg(long, default_value = "host", value_parser = parse_planner)]
    pub planner: Planner,
    /// Print one JSON record per frame instead of text.
    #[arg(long)]
    pub json: bool,
    /// Write every AXI4 address handshake (AR, AW) of the run to this CSV file: frame, cycle,
    /// port, memory client, kind, byte address, beats; the memory map in its header. Lighter
    /// than `--waves` for finding when each tile's traffic ran on which port.
    #[arg(long)]
    pub axi_log: Option<PathBuf>,
    /// Measured unit timing for the cycle model's prediction.
    #[arg(long, default_value = latency::DEFAULT_PATH)]
    pub latency: PathBuf,
    /// Print the engine-level cycle model's prediction of every frame without building or
    /// running the RTL (golden's memory-level reference runs each frame in its place): seconds
    /// where a large engine simulates for minutes or hours.
    #[arg(long, conflicts_with_all = ["waves", "axi_log"])]
    pub model_only: bool,
    #[command(flatten)]
    pub strict: StrictArg,
}

/// Parses `--planner`.
fn parse_planner(s: &str) -> Result<Planner, String> {
    match s {
        "host" => Ok(Planner::Host),
        "engine" => Ok(Planner::Engine),
        _ => Err(format!("unknown planner {s:?}: expected host or engine")),
    }
}

/// Runs `neo cosim`.
pub fn run(a: CosimArgs) -> Result<()> {
    let mode = engine_run::host_mode(&a.input)?;
    let cfg = engine_run::engine_config(a.config.as_deref())?;
    let timing = match a.memory.as_str() {
        "random" => AxiTiming::RANDOM,
        "ideal" => AxiTiming::IDEAL,
        other => bail!("--memory {other:?}: expected `random` or `ideal`"),
    };
    let given = match &a.seed {
        Some(s) => Some(neo_tb::rng::parse_seed(s).ok_or_else(|| anyhow!("--seed {s:?} is not a number"))?),
        None => None,
    };
    // The harness's seed drives only the RTL run's memory: `--model-only` has none.
    let seed = (!a.model_only).then(|| given.unwrap_or_else(|| neo_tb::rng::command_seed("neo cosim")));
    let (scene, _) = source::load_scene(&a.scene.scene, a.strict.strict)?;
    let traj = engine_run::trajectory_at(&a.trajectory.trajectory, &scene, a.frames, a.res)?;
    let strategy: Strategy = a.sort.parse().map_err(|e| anyhow!("--sort {:?}: {e}", a.sort))?;
    let opts = SessionOptions { mode, strategy, sh: a.sh, planner: a.planner };
    let mut session = engine_run::session(&scene, traj, &cfg, opts)?;
    eprintln!(
        "neo cosim: {} Gaussians, {} tiles, {} frames, engine {} + {} cores, {} ports{}",
        scene.len(),
        session.tiles(),
        session.frames(),
        cfg.sort_cores,
        cfg.raster_cores,
        cfg.mem_channels,
        seed.map_or(String::new(), |s| format!(", seed 0x{s:016x}"))
    );
    let Some(seed) = seed else {
        return model_only(&a, &cfg, &timing, &mut session);
    };
    // Before the engine's build: a path that cannot be written fails at once.
    let mut log = match &a.axi_log {
        Some(path) => Some(TransferLog::create(path, session.layout(), &cfg)?),
        None => None,
    };
    let format = a.waves.as_deref().map(WaveFormat::of_path);
    let engine = engine_run::build_engine(&cfg, format, 1)?;
    let b = &engine.build;
    eprintln!("engine model: {} in {:.1} s {}", if b.cached { "cached" } else { "built" }, b.seconds, b.log);
    let lat = crate::points::latency_file(&a.latency)?;
    let model = EngineFrameModel::new(&cfg, &lat, port_timing(&timing)).map_err(|e| anyhow!(e))?;
    let opts = RunOptions { timing, ..RunOptions::default() };
    let mut rig = EngineRig::new(engine, opts, seed, a.waves.clone()).map_err(|e| anyhow!(e))?;
    if let Some(w) = &a.waves {
        eprintln!("waves: {}\nwaves: gtkwave {}", w.display(), neo_tb::waves::gtkw_path(w).display());
    }
    rig.record_transfers(log.is_some());
    let bar = engine_run::frame_bar(session.frames() as u64, a.json);
    let mut log_error = None;
    let failed = engine_run::run_frames(
        &mut session,
        &mut rig,
        |plan, mem| Ok(model.predict_frame(&plan.regs, mem)?),
        |f| {
            bar.inc(1);
            if let Some(l) = log.as_mut().filter(|_| log_error.is_none()) {
                log_error = l.write_frame(f.report.frame, &f.transfers).err();
            }
            print_frame(&a, &f.report, &f.before, f.took, &f.overflowing, &bar);
        },
    );
    rig.finish();
    bar.finish_and_clear();
    if let Some(e) = log_error {
        return Err(e);
    }
    if let Some(l) = log {
        l.finish()?;
    }
    match failed? {
        Some(f) => bail!("frame {f} is not bit-exact (seed 0x{seed:016x}; replay with --seed 0x{seed:016x})"),
        None => Ok(()),
    }
}

/// `--model-only`: the cycle model's prediction of every frame of `session`, golden's reference
/// standing in for the engine (it leaves the memory as the RTL does, bit for bit).
fn model_only(
    a: &CosimArgs,
    cfg: &EngineConfig,
    timing: &AxiTiming,
    session: &mut EngineSession,
) -> Result<()> {
    let lat = crate::points::latency_file(&a.latency)?;
    let model = EngineFrameModel::new(cfg, &lat, port_timing(timing)).map_err(|e| anyhow!(e))?;
    let mut mem = Memory::new();
    let mut frame = 0;
    while let Some(plan) = session.next_frame(&mut mem)? {
        let p = model.predict_frame(&plan.regs, &mem)?;
        execute_frame(cfg, &plan.regs, &mut mem)?;
        if a.json {
            let v = serde_json::json!({
                "frame": frame,
                "model_cycles": p.cycles.round(),
                "model_preprocess_cycles": p.pre_busy.round(),
                "model_sort_busy": p.sort_busy.round(),
                "model_raster_busy": p.raster_busy.round(),
                "planned_by_engine": p.scan > 0.0,
                "dps_passes": &p.dps_passes,
                "dps_wide": &p.dps_wide,
            });
            println!("{v}");
        } else {
            println!(
                "frame {frame:>3}: model {:.0} cycles (busy sort {:.0}, raster {:.0}, preprocessing {:.0}); DPS passes per tile {:?}{}",
                p.cycles,
                p.sort_busy,
                p.raster_busy,
                p.pre_busy,
                p.dps_passes,
                if p.scan > 0.0 { " planned by the engine" } else { "" }
            );
        }
        frame += 1;
    }
    Ok(())
}

/// The `--axi-log` file: a CSV of every AR and AW, frame by frame.
struct TransferLog {
    path: PathBuf,
    out: std::io::BufWriter<std::fs::File>,
    /// Each memory client's name as a CSV field (quoted: names hold commas).
    clients: Vec<String>,
}

impl TransferLog {
    /// Creates `path` and writes its header: the memory map, then the columns.
    fn create(path: &Path, layout: &MemoryLayout, cfg: &EngineConfig) -> Result<TransferLog> {
        let file = std::fs::File::create(path).with_context(|| format!("--axi-log {}", path.display()))?;
        let clients = (0..cfg.memory_clients()).map(|c| csv_field(&client_name(cfg, c))).collect();
        let mut log = TransferLog { path: path.to_path_buf(), out: std::io::BufWriter::new(file), clients };
        let l = layout;
        let mut header = vec![
            "# neo cosim: every AXI4 address handshake (AR, AW) the harness's memory took".to_string(),
            "# cycle: the port's clock since the memory was created; client: the memory client on that port"
                .into(),
            format!(
                "# desc_base 0x{:x} result_base 0x{:x} fb_base 0x{:x}",
                l.desc_base, l.result_base, l.fb_base
            ),
            format!(
                "# feat_base 0x{:x} scratch_base 0x{:x} list_base 0x{:x}",
                l.feat_base, l.scratch_base, l.list_base
            ),
            format!("# table_bases 0x{:x} 0x{:x}", l.table_bases[0], l.table_bases[1]),
        ];
        if let Some(s) = &l.scene {
            header.push(format!(
                "# geo_base 0x{:x} sh_base 0x{:x} feat_bases 0x{:x} 0x{:x}",
                s.geo_base, s.sh_base, s.feat_bases[0], s.feat_bases[1]
            ));
        }
        header.push("frame,cycle,port,client,kind,addr,beats".into());
        for line in &header {
            Self::write_line(&mut log.out, &log.path, format_args!("{line}"))?;
        }
        Ok(log)
    }

    /// Appends frame `frame`'s transfers.
    fn write_frame(&mut self, frame: usize, transfers: &[(AddrRecord, usize)]) -> Result<()> {
        for &(r, c) in transfers {
            let kind = if r.write { "AW" } else { "AR" };
            let client = match self.clients.get(c) {
                Some(name) => std::borrow::Cow::Borrowed(name.as_str()),
                None => std::borrow::Cow::Owned(csv_field(&format!("no client ({c})"))),
            };
            Self::write_line(
                &mut self.out,
                &self.path,
                format_args!("{frame},{},{},{client},{kind},0x{:x},{}", r.cycle, r.port, r.addr, r.beats),
            )?;
        }
        Ok(())
    }

    /// One line of the file at `path` into `out`.
    fn write_line(
        out: &mut std::io::BufWriter<std::fs::File>,
        path: &Path,
        line: std::fmt::Arguments,
    ) -> Result<()> {
        use std::io::Write;
        writeln!(out, "{line}").with_context(|| format!("--axi-log {}", path.display()))
    }

    /// Flushes the file.
    fn finish(mut self) -> Result<()> {
        use std::io::Write;
        self.out.flush().with_context(|| format!("--axi-log {}", self.path.display()))
    }
}

/// `s` as a quoted CSV field.
fn csv_field(s: &str) -> String {
    format!("\"{}\"", s.replace('"', "\"\""))
}

/// The cycle model's timing of the harness's memory (its means).
fn port_timing(t: &AxiTiming) -> PortTiming {
    let (latency, bandwidth, ready) = t.means();
    let (late_share, late_max) = t.late();
    PortTiming { latency, bandwidth, ready, late_share, late_max }
}

/// One frame's line (or JSON record).
fn print_frame(
    a: &CosimArgs,
    r: &FrameReport,
    p: &FramePrediction,
    took: Duration,
    overflowing: &[usize],
    bar: &ProgressBar,
) {
    let mismatch = r.mismatch.as_ref().map(|m| m.to_string());
    // The Preprocessing Engine's cycles come before the tile walk, in the RTL and the model.
    let pre = r.counters.get(Counter::PreBusy);
    let walk = r.rtl_cycles.saturating_sub(pre);
    let model_walk = p.cycles - p.pre_busy;
    let model_error = error_pct(p.cycles, r.rtl_cycles);
    let sort_busy = r.counters.get(Counter::SortBusy);
    let raster_busy = r.counters.get(Counter::RasterBusy);
    if a.json {
        let v = serde_json::json!({
            "frame": r.frame,
            "from_scratch": r.from_scratch,
            "bit_exact": r.mismatch.is_none(),
            "rtl_cycles": r.rtl_cycles,
            "rtl_preprocess_cycles": pre,
            "rtl_walk_cycles": walk,
            "rtl_preprocess_read_bytes": r.counters.get(Counter::RdPre),
            "rtl_preprocess_write_bytes": r.counters.get(Counter::WrPre),
            "model_cycles": p.cycles.round(),
            "model_error_pct": model_error,
            "model_preprocess_cycles": p.pre_busy.round(),
            "preprocess_error_pct": if pre > 0 { Some(error_pct(p.pre_busy, pre)) } else { None },
            "model_walk_cycles": model_walk.round(),
            "walk_error_pct": error_pct(model_walk, walk),
            "rtl_sort_busy": sort_busy,
            "model_sort_busy": p.sort_busy.round(),
            "sort_busy_error_pct": error_pct(p.sort_busy, sort_busy),
            "rtl_raster_busy": raster_busy,
            "model_raster_busy": p.raster_busy.round(),
            "raster_busy_error_pct": error_pct(p.raster_busy, raster_busy),
            "planned_by_engine": p.scan > 0.0,
            "dps_passes": &p.dps_passes,
            "dps_wide": &p.dps_wide,
            "rtl_result_read_bytes": r.counters.get(Counter::RdResult),
            "model_scan_cycles": p.scan.round(),
            "mismatch": mismatch,
            "overflowing_tiles": overflowing,
            "wall_seconds": took.as_secs_f64(),
        });
        println!("{v}");
        return;
    }
    let status = crate::engine_run::frame_status(r);
    let cps = r.harness_cycles as f64 / took.as_secs_f64().max(1e-9);
    let pre_text = if pre > 0 {
        format!(
            " ({pre} preprocessing, {} B read, {} B written; {walk} tile walk)",
            r.counters.get(Counter::RdPre),
            r.counters.get(Counter::WrPre)
        )
    } else {
        String::new()
    };
    let model_pre = if pre > 0 {
        format!(
            "; preprocessing {:.0}, {:+.1}%; walk {:.0}, {:+.1}%",
            p.pre_busy,
            error_pct(p.pre_busy, pre),
            model_walk,
            error_pct(model_walk, walk)
        )
    } else {
        String::new()
    };
    let line = format!(
        "frame {:3}{}: {status}, {} RTL cycles{pre_text}, model {:.0} ({:+.1}%{model_pre}; busy sort {:+.1}%, raster {:+.1}%), {:.1} s ({:.0} cycles/s)",
        r.frame,
        if r.from_scratch { " (from scratch)" } else { "" },
        r.rtl_cycles,
        p.cycles,
        model_error,
        error_pct(p.sort_busy, sort_busy),
        error_pct(p.raster_busy, raster_busy),
        took.as_secs_f64(),
        cps
    );
    // `suspend`, not `println`: a hidden bar (output not a terminal) would drop the line.
    bar.suspend(|| println!("{line}"));
    if !overflowing.is_empty() {
        bar.suspend(|| println!("  tiles over the table capacity (reported, not sorted): {overflowing:?}"));
    }
    let wide = p.dps_wide.iter().filter(|&&w| w).count();
    if p.scan > 0.0 {
        let plan = format!(
            "  planned by the engine (ADAPT_CTRL): DPS passes per tile {}, {} B of previous results read, scan {:.0} cycles in the model",
            passes_text(&p.dps_passes, &p.dps_wide),
            r.counters.get(Counter::RdResult),
            p.scan
        );
        bar.suspend(|| println!("{plan}"));
    } else if wide > 0 {
        let plan = format!("  DPS passes per tile {}", passes_text(&p.dps_passes, &p.dps_wide));
        bar.suspend(|| println!("{plan}"));
    }
}

/// Each tile's DPS passes, `w` after those in the wide chunk: `[1, 2w, 0, ...]`.
fn passes_text(passes: &[usize], wide: &[bool]) -> String {
    let v: Vec<String> = passes
        .iter()
        .zip(wide.iter().chain(std::iter::repeat(&false)))
        .map(|(p, &w)| format!("{p}{}", if w { "w" } else { "" }))
        .collect();
    format!("[{}]", v.join(", "))
}
