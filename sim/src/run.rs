//! Running an architecture on a workload and summarising the result.

use serde::{Deserialize, Serialize};
use std::time::Instant;

use crate::arch::{Accel, Model, CLASS_PRE, CLASS_RASTER, CLASS_SORT};
use crate::config::SimConfig;
use crate::dram::{Dram, DramStats, Ps};
use crate::engine::Engine;
use crate::gpu;
use crate::latency::Latency;
use crate::traffic::{Dir, Stage, Traffic};
use crate::workload::Workload;

/// An architecture to evaluate.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize)]
pub enum Arch {
    /// Neo running the workload's strategy.
    Neo,
    /// GSCore-style with this many cores.
    Gscore(u32),
    /// GPU-style (Orin-AGX-like).
    Gpu,
    /// Neo-S with this many cores: GSCore-style with Neo's Sorting Engine (the paper's Fig. 18).
    NeoS(u32),
}

impl Arch {
    /// Name in tables and JSON: `neo`, `gscore4`, `gscore16`, `gpu`.
    pub fn name(&self) -> String {
        match self {
            Arch::Neo => "neo".into(),
            Arch::Gscore(c) => format!("gscore{c}"),
            Arch::Gpu => "gpu".into(),
            Arch::NeoS(c) => format!("neos{c}"),
        }
    }

    /// The accelerator the cycle model simulates (`None` for the GPU, whose model is analytic).
    pub fn accel(self) -> Option<Accel> {
        match self {
            Arch::Neo => Some(Accel::Neo),
            Arch::Gscore(c) => Some(Accel::Gscore { cores: c }),
            Arch::NeoS(c) => Some(Accel::NeoS { cores: c }),
            Arch::Gpu => None,
        }
    }

    /// Parses `neo`, `gscore` (every configured core count), `gscoreN`, `gpu`, `all` (these),
    /// `neos` (Neo-S with the engine's sorting-core count) or `neosN`, comma-separated.
    pub fn parse_list(s: &str, cfg: &SimConfig) -> Result<Vec<Arch>, String> {
        let mut v = Vec::new();
        for part in s.split(',').map(str::trim).filter(|p| !p.is_empty()) {
            match part {
                "neo" => v.push(Arch::Neo),
                "gpu" => v.push(Arch::Gpu),
                "gscore" => v.extend(cfg.gscore.core_counts.iter().map(|&c| Arch::Gscore(c))),
                "neos" => v.push(Arch::NeoS(cfg.engine.sort_cores as u32)),
                "all" => {
                    v.push(Arch::Neo);
                    v.extend(cfg.gscore.core_counts.iter().map(|&c| Arch::Gscore(c)));
                    v.push(Arch::Gpu);
                }
                other => {
                    let count = |prefix: &str| match other.strip_prefix(prefix).map(str::parse::<u32>) {
                        Some(Ok(c)) if c > 0 => Some(c),
                        _ => None,
                    };
                    match (count("gscore"), count("neos")) {
                        (Some(c), _) => v.push(Arch::Gscore(c)),
                        (_, Some(c)) => v.push(Arch::NeoS(c)),
                        _ => {
                            return Err(format!(
                                "unknown architecture '{other}' (expected neo, gscore, gscoreN, gpu, all, neos or neosN)"
                            ))
                        }
                    }
                }
            }
        }
        if v.is_empty() {
            return Err("no architecture given".into());
        }
        let mut seen = std::collections::HashSet::new();
        v.retain(|a| seen.insert(*a));
        Ok(v)
    }
}

/// One frame's result.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct FrameResult {
    /// Frame index.
    pub frame: usize,
    /// Preprocessing start (ms from the start of the run).
    pub pre_start_ms: f64,
    /// Preprocessing end.
    pub pre_done_ms: f64,
    /// Last sort end.
    pub sort_done_ms: f64,
    /// Frame complete.
    pub done_ms: f64,
    /// `done - pre_start`.
    pub latency_ms: f64,
    /// Time since the previous frame completed (frame 0: its latency).
    pub interval_ms: f64,
    /// DRAM bytes caused by this frame's jobs.
    pub dram_bytes: u64,
    /// Of which sorting stages.
    pub sort_bytes: u64,
    /// Every tile sorted from scratch.
    pub from_scratch: bool,
    /// Bytes read and written by stage (by the frame of the job that caused them; every stage,
    /// in report order).
    #[serde(default)]
    pub stages: Vec<StageBytes>,
    /// Busy time of each engine on this frame's jobs (accelerators; summed over the engine's
    /// units, so it can exceed the frame's interval).
    #[serde(default)]
    pub busy: Option<EngineBusy>,
}

/// DRAM bytes of one stage in one frame.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct StageBytes {
    /// Stage name ([`Stage::name`]).
    pub stage: String,
    /// Bytes read.
    pub read_bytes: u64,
    /// Bytes written.
    pub write_bytes: u64,
}

/// The stages of `t`, every one named.
pub fn stage_bytes(t: &Traffic) -> Vec<StageBytes> {
    Stage::ALL
        .iter()
        .map(|&s| StageBytes {
            stage: s.name().to_string(),
            read_bytes: t.bytes(s, Dir::Read),
            write_bytes: t.bytes(s, Dir::Write),
        })
        .collect()
}

/// Busy milliseconds of each engine, summed over its units.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct EngineBusy {
    /// Preprocessing engine.
    pub preprocess_ms: f64,
    /// Sorting cores together.
    pub sort_ms: f64,
    /// Raster cores together.
    pub raster_ms: f64,
}

/// Utilisation of each engine over the run (busy time / (agents x run time)).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Utilisation {
    /// Preprocessing engine.
    pub preprocess: f64,
    /// Sorting cores.
    pub sort: f64,
    /// Raster cores.
    pub raster: f64,
    /// DRAM data bus: bytes moved / (peak x run time).
    pub dram: f64,
}

/// One architecture on one workload.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ArchResult {
    /// Architecture name.
    pub arch: String,
    /// Strategy the workload ran (the sort GSCore and the GPU use is their own).
    pub strategy: String,
    /// Frames.
    pub frames: Vec<FrameResult>,
    /// Throughput: 1000 / mean frame interval (frames after the first).
    pub fps: f64,
    /// Mean frame interval (ms).
    pub frame_ms_mean: f64,
    /// 99th percentile frame interval (ms, nearest rank).
    pub frame_ms_p99: f64,
    /// Largest frame interval (ms).
    pub frame_ms_max: f64,
    /// Mean latency (ms).
    pub latency_ms_mean: f64,
    /// End of the run (ms).
    pub total_ms: f64,
    /// Traffic of the whole run.
    pub traffic: Traffic,
    /// DRAM counters (accelerators).
    pub dram: Option<DramStats>,
    /// Engine utilisation (accelerators).
    pub utilisation: Option<Utilisation>,
    /// Where the raster timing came from.
    pub raster_timing: String,
    /// What of the preprocessing timing was measured (accelerators; empty for the GPU).
    pub preprocess_timing: String,
    /// Wall-clock seconds of the model.
    pub model_s: f64,
}

impl ArchResult {
    /// DRAM GB of `stage` (all stages with `None`) in a 60-frame run (the paper's Fig. 16 unit),
    /// estimated by [`ArchResult::per_60`] from the frames run.
    pub fn gb_per_60(&self, stage: Option<Stage>) -> f64 {
        let bytes = match stage {
            Some(s) => self.per_60(self.traffic.stage_bytes(s), |f| {
                f.stages.iter().find(|b| b.stage == s.name()).map_or(0, |b| b.read_bytes + b.write_bytes)
            }),
            None => self.per_60(self.traffic.total_bytes(), |f| f.dram_bytes),
        };
        bytes / 1e9
    }

    /// DRAM GB of the sorting stages in a 60-frame run, estimated like [`ArchResult::gb_per_60`].
    pub fn sorting_gb_per_60(&self) -> f64 {
        self.per_60(self.traffic.sorting_bytes(), |f| f.sort_bytes) / 1e9
    }

    /// Bytes in a 60-frame run from the run's `total` and its frames' bytes (`per_frame`): frame
    /// 0 (the sort from scratch) plus 59 times the mean of the other frames, so that a short
    /// run does not weigh its first frame more than a 60-frame run does (exact for 60 frames).
    /// With one frame, or when the frames' bytes do not add up to `total` (a model without
    /// per-frame records), `total` scaled by 60 over the frames run.
    pub fn per_60(&self, total: u64, per_frame: impl Fn(&FrameResult) -> u64) -> f64 {
        let n = self.frames.len();
        let v: Vec<u64> = self.frames.iter().map(per_frame).collect();
        if n > 1 && v.iter().sum::<u64>() == total {
            let rest = v[1..].iter().sum::<u64>() as f64 / (n - 1) as f64;
            v[0] as f64 + 59.0 * rest
        } else {
            total as f64 * 60.0 / n.max(1) as f64
        }
    }
}

/// How to run.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RunOptions {
    /// An ideal memory (one cycle, no bandwidth limit) instead of the DRAM model.
    pub ideal_memory: bool,
}

fn percentile(v: &[f64], q: f64) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let k = ((q * s.len() as f64).ceil() as usize).clamp(1, s.len());
    s[k - 1]
}

fn summarise(
    arch: String,
    strategy: String,
    mut frames: Vec<FrameResult>,
) -> (Vec<FrameResult>, f64, f64, f64, f64, f64) {
    let mut last = 0.0;
    for (i, f) in frames.iter_mut().enumerate() {
        f.latency_ms = f.done_ms - f.pre_start_ms;
        f.interval_ms = if i == 0 { f.latency_ms } else { f.done_ms - last };
        last = f.done_ms;
    }
    let _ = (arch, strategy);
    let steady: Vec<f64> = if frames.len() > 1 {
        frames[1..].iter().map(|f| f.interval_ms).collect()
    } else {
        vec![frames[0].interval_ms]
    };
    let mean = steady.iter().sum::<f64>() / steady.len() as f64;
    let p99 = percentile(&steady, 0.99);
    let max = steady.iter().copied().fold(0.0, f64::max);
    let lat = frames.iter().map(|f| f.latency_ms).sum::<f64>() / frames.len() as f64;
    (frames, mean, p99, max, lat, if mean > 0.0 { 1000.0 / mean } else { 0.0 })
}

fn frame_busy(by_class: &[Ps]) -> EngineBusy {
    let ms = |class: u8| by_class.get(class as usize).map_or(0.0, |&p| p as f64 / 1e9);
    EngineBusy { preprocess_ms: ms(CLASS_PRE), sort_ms: ms(CLASS_SORT), raster_ms: ms(CLASS_RASTER) }
}

/// Runs `arch` on `wl`.
pub fn simulate(
    arch: Arch,
    cfg: &SimConfig,
    lat: &Latency,
    wl: &Workload,
    opt: RunOptions,
) -> Result<ArchResult, String> {
    if wl.frames.is_empty() {
        return Err("the workload has no frames".into());
    }
    let t0 = Instant::now();
    match arch {
        Arch::Gpu => {
            let mut traffic = Traffic::new(cfg.dram.line_bytes as u64);
            let mut frames = Vec::with_capacity(wl.frames.len());
            let mut t = 0.0;
            for fw in &wl.frames {
                let g = gpu::frame(cfg, &wl.info, fw);
                let ms = g.total_s() * 1e3;
                frames.push(FrameResult {
                    frame: fw.frame,
                    pre_start_ms: t,
                    pre_done_ms: t + g.kernel_s[0] * 1e3,
                    sort_done_ms: t + (g.kernel_s[0] + g.kernel_s[1] + g.kernel_s[2] + g.kernel_s[3]) * 1e3,
                    done_ms: t + ms,
                    dram_bytes: g.traffic.total_bytes(),
                    sort_bytes: g.traffic.sorting_bytes(),
                    from_scratch: true,
                    stages: stage_bytes(&g.traffic),
                    ..FrameResult::default()
                });
                t += ms;
                traffic.merge(&g.traffic);
            }
            let (frames, mean, p99, max, latm, fps) =
                summarise(arch.name(), wl.info.strategy.clone(), frames);
            Ok(ArchResult {
                arch: arch.name(),
                strategy: "radix (from scratch)".into(),
                frames,
                fps,
                frame_ms_mean: mean,
                frame_ms_p99: p99,
                frame_ms_max: max,
                latency_ms_mean: latm,
                total_ms: t,
                traffic,
                dram: None,
                utilisation: None,
                raster_timing: "GPU rates ASSUMED (config gpu.*)".into(),
                preprocess_timing: String::new(),
                model_s: t0.elapsed().as_secs_f64(),
            })
        }
        Arch::Neo | Arch::Gscore(_) | Arch::NeoS(_) => {
            let accel = arch.accel().expect("a cycle-modelled architecture");
            let model = Model::new(accel, cfg, lat, wl)?;
            let line = cfg.dram.line_bytes as u64;
            let dram = if opt.ideal_memory {
                Dram::ideal(cfg.dram.line_bytes, cfg.cycle_ps().round() as u64)
            } else {
                Dram::new(&cfg.dram)
            };
            let agents = model.agents();
            let mut engine = Engine::new(dram, line, agents, wl.frames.len());
            let mut sched = model.scheduler();
            let end = engine.run(&mut sched);
            let ms = |p: u64| p as f64 / 1e9;
            let frames: Vec<FrameResult> = sched
                .times()
                .iter()
                .enumerate()
                .map(|(i, t)| FrameResult {
                    frame: wl.frames[i].frame,
                    pre_start_ms: ms(t.pre_start),
                    pre_done_ms: ms(t.pre_done),
                    sort_done_ms: ms(t.sort_done),
                    done_ms: ms(t.done),
                    dram_bytes: engine.frame_traffic[i].total_bytes(),
                    sort_bytes: engine.frame_traffic[i].sorting_bytes(),
                    from_scratch: wl.frames[i].from_scratch,
                    stages: stage_bytes(&engine.frame_traffic[i]),
                    busy: Some(frame_busy(&engine.frame_busy[i])),
                    ..FrameResult::default()
                })
                .collect();
            let (frames, mean, p99, max, latm, fps) =
                summarise(arch.name(), wl.info.strategy.clone(), frames);
            let stats = engine.agent_stats();
            let util = |class: u8| {
                let (busy, n) = stats
                    .iter()
                    .filter(|s| s.class == class)
                    .fold((0u64, 0u64), |(b, n), s| (b + s.busy_ps, n + 1));
                if n == 0 || end == 0 {
                    0.0
                } else {
                    busy as f64 / (n as f64 * end as f64)
                }
            };
            let dstats = engine.dram().stats();
            let dram_util = if end == 0 {
                0.0
            } else {
                engine.traffic.total_bytes() as f64 / (cfg.dram.peak_bytes_per_s() * end as f64 * 1e-12)
            };
            Ok(ArchResult {
                arch: arch.name(),
                strategy: match accel {
                    Accel::Neo | Accel::NeoS { .. } => wl.info.strategy.clone(),
                    Accel::Gscore { .. } => "hierarchical (from scratch)".into(),
                },
                frames,
                fps,
                frame_ms_mean: mean,
                frame_ms_p99: p99,
                frame_ms_max: max,
                latency_ms_mean: latm,
                total_ms: ms(end),
                traffic: engine.traffic.clone(),
                dram: (!opt.ideal_memory).then_some(dstats),
                utilisation: Some(Utilisation {
                    preprocess: util(CLASS_PRE),
                    sort: util(CLASS_SORT),
                    raster: util(CLASS_RASTER),
                    dram: dram_util,
                }),
                raster_timing: lat.raster_source.label(),
                preprocess_timing: lat.preprocess.label(),
                model_s: t0.elapsed().as_secs_f64(),
            })
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_60_frame_run_is_frame_0_and_59_of_the_mean_of_the_others() {
        let frame = |b: u64| FrameResult { dram_bytes: b, ..FrameResult::default() };
        let r = ArchResult { frames: vec![frame(100), frame(10), frame(20)], ..ArchResult::default() };
        assert_eq!(r.per_60(130, |f| f.dram_bytes), 100.0 + 59.0 * 15.0);
        // 60 frames: exactly their sum.
        let sixty = ArchResult { frames: (0..60).map(|k| frame(k + 1)).collect(), ..ArchResult::default() };
        assert_eq!(sixty.per_60(1830, |f| f.dram_bytes), 1830.0);
        // Per-frame bytes that do not add up to the total, or one frame: scaled.
        assert_eq!(r.per_60(300, |f| f.dram_bytes), 300.0 * 20.0);
        let one = ArchResult { frames: vec![frame(7)], ..ArchResult::default() };
        assert_eq!(one.per_60(7, |f| f.dram_bytes), 420.0);
    }

    #[test]
    fn architecture_lists_parse_and_name_back() {
        let cfg = SimConfig::default();
        let names = |s: &str| Arch::parse_list(s, &cfg).map(|v| v.iter().map(Arch::name).collect::<Vec<_>>());
        assert_eq!(names("all").unwrap(), ["neo", "gscore4", "gscore16", "gpu"]);
        assert_eq!(names("neos, neos8,gscore4,neo").unwrap(), ["neos16", "neos8", "gscore4", "neo"]);
        assert_eq!(names("neo,neo").unwrap(), ["neo"], "duplicates dropped");
        for bad in ["", "neos0", "gscorex", "neo-s"] {
            let e = names(bad).unwrap_err();
            assert!(e.contains("architecture"), "{bad}: {e}");
        }
    }
}
