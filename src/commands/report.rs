//! `neo report`: the README's main job. Runs the default suite on the default synthetic scene
//! (plus any `--scene`) and writes `reports/index.md` with its SVG figures: throughput per
//! resolution and architecture (paper Fig. 15), DRAM traffic by stage (Fig. 16), frame times of
//! the sorting strategies on Neo's hardware (Fig. 19), and speed against error over strategies,
//! chunk sizes, DPS passes and camera speeds with its Pareto front.

use super::simulate::{load_config, load_latency, run_point, run_points_parallel, Scenes};
use anyhow::{anyhow, bail, Context, Result};
use clap::Args;
use neo_golden::synthetic;
use neo_sim::driver::GoldenRaster;
use neo_sim::latency;
use neo_sim::report::{render, ReportData, ReportSettings};
use neo_sim::run::Arch;
use neo_sim::suite::{parse_res, Grid, Point, PointResult};
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `neo report`.
#[derive(Args)]
pub struct ReportArgs {
    /// Scenes to add to the default synthetic scene (files or synthetic specs; repeatable).
    #[arg(long)]
    pub scene: Vec<String>,
    /// Output directory of `index.md` and the figures.
    #[arg(long, default_value = "reports")]
    pub out: PathBuf,
    /// Trajectory of every run.
    #[arg(long, default_value = "orbit")]
    pub trajectory: String,
    /// Frames of the throughput, traffic and timeline runs.
    #[arg(long, default_value_t = 24)]
    pub frames: usize,
    /// Resolutions of the throughput and traffic runs.
    #[arg(long, default_value = "hd,fhd,qhd", value_delimiter = ',')]
    pub res: Vec<String>,
    /// Resolution of the strategy timelines (Fig. 19).
    #[arg(long, default_value = "fhd")]
    pub timeline_res: String,
    /// Strategies compared with `neo` in the timelines.
    #[arg(long, default_value = "periodic:4,background:2,hierarchical", value_delimiter = ',')]
    pub timeline_sort: Vec<String>,
    /// Scene of the speed/error sweep (smaller: every point runs the golden raster twice per
    /// frame for its PSNR).
    #[arg(long, default_value = "synthetic:outdoor?gaussians=100k&seed=1")]
    pub sweep_scene: String,
    /// Resolution of the sweep.
    #[arg(long, default_value = "448x256")]
    pub sweep_res: String,
    /// Frames per sweep point.
    #[arg(long, default_value_t = 5)]
    pub sweep_frames: usize,
    /// Strategies of the sweep.
    #[arg(long, default_value = "neo,periodic:4,background:2,hierarchical", value_delimiter = ',')]
    pub sweep_sort: Vec<String>,
    /// Chunk sizes of the sweep.
    #[arg(long, default_value = "64,128,256,512", value_delimiter = ',')]
    pub sweep_chunk: Vec<usize>,
    /// DPS passes of the sweep.
    #[arg(long, default_value = "1,2", value_delimiter = ',')]
    pub sweep_passes: Vec<usize>,
    /// Camera speeds of the sweep.
    #[arg(long, default_value = "1,2,4,8,16", value_delimiter = ',')]
    pub sweep_speed: Vec<f64>,
    /// Use the point results (`*.json` from `neo simulate --out DIR`) in this directory for the
    /// sweep instead of running it.
    #[arg(long)]
    pub sweep_results: Option<PathBuf>,
    /// Skip the sweep.
    #[arg(long)]
    pub no_sweep: bool,
    /// Early termination measured on every K-th tile (work-only workloads).
    #[arg(long, default_value_t = 16)]
    pub raster_sample: u32,
    /// Model configuration (JSON).
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// Measured unit timing.
    #[arg(long, default_value = latency::DEFAULT_PATH)]
    pub latency: PathBuf,
    /// Leave the default scene out (only the `--scene`s; for quick checks).
    #[arg(long, hide = true)]
    pub no_default_scene: bool,
}

fn peak_rss_mb() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = s.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb / 1024.0)
}

fn point(
    scene: &str,
    traj: &str,
    frames: usize,
    res: &str,
    strategy: &str,
    chunk: usize,
    passes: usize,
) -> Result<Point> {
    let (label, w, h) = parse_res(res).map_err(|e| anyhow!(e))?;
    Ok(Point {
        scene: scene.to_string(),
        trajectory: traj.to_string(),
        speed: 1.0,
        frames,
        res: label,
        width: w,
        height: h,
        strategy: strategy.to_string(),
        chunk,
        passes,
    })
}

/// Runs `neo report`.
pub fn run(a: ReportArgs) -> Result<()> {
    let t0 = Instant::now();
    if a.frames == 0 || a.sweep_frames == 0 {
        bail!("--frames and --sweep-frames must be at least 1");
    }
    let cfg = load_config(a.config.as_deref())?;
    let lat = load_latency(&a.latency)?;
    let (chunk, passes) = (cfg.pipeline.chunk, cfg.pipeline.dps_passes);
    let mut scenes_list =
        if a.no_default_scene { Vec::new() } else { vec![synthetic::DEFAULT_SCENE.to_string()] };
    for s in &a.scene {
        if !scenes_list.contains(s) {
            scenes_list.push(s.clone());
        }
    }
    let Some(main_scene) = scenes_list.first().cloned() else {
        bail!("no scene: give --scene when leaving the default scene out");
    };
    let all_archs = Arch::parse_list("all", &cfg).map_err(|e| anyhow!(e))?;

    // Plan.
    let mut head_points = Vec::new();
    for s in &scenes_list {
        for r in &a.res {
            head_points.push(point(s, &a.trajectory, a.frames, r, "neo", chunk, passes)?);
        }
    }
    let (tl_label, _, _) = parse_res(&a.timeline_res).map_err(|e| anyhow!(e))?;
    let mut tl_points = Vec::new();
    for s in &a.timeline_sort {
        tl_points.push(point(
            synthetic::DEFAULT_SCENE,
            &a.trajectory,
            a.frames,
            &a.timeline_res,
            s,
            chunk,
            passes,
        )?);
    }
    let sweep_points: Vec<Point> = if a.no_sweep || a.sweep_results.is_some() {
        Vec::new()
    } else {
        Grid {
            scenes: vec![a.sweep_scene.clone()],
            trajectory: a.trajectory.clone(),
            frames: a.sweep_frames,
            res: vec![a.sweep_res.clone()],
            strategies: a.sweep_sort.clone(),
            chunks: a.sweep_chunk.clone(),
            passes: a.sweep_passes.clone(),
            speeds: a.sweep_speed.clone(),
        }
        .points()
        .map_err(|e| anyhow!(e))?
    };
    let total = head_points.len();
    eprintln!(
        "neo report: {} throughput runs, {} strategy timelines, {} sweep points; {}",
        head_points.len(),
        tl_points.len() + 1,
        sweep_points.len(),
        lat.raster_source.label()
    );
    let mut scenes = Scenes::default();
    let started = Instant::now();
    let log = |r: &PointResult, label: &str| {
        let fps: Vec<String> = r.archs.iter().map(|a| format!("{} {:.1}", a.arch, a.fps)).collect();
        eprintln!(
            "{label} {} {} {} c{} p{} {}x: FPS {} (workload {:.1} s; {:.0} s elapsed)",
            r.point.res,
            r.point.strategy,
            r.point.frames,
            r.point.chunk,
            r.point.passes,
            r.point.speed,
            fps.join(", "),
            r.workload.generation_s,
            started.elapsed().as_secs_f64()
        );
    };
    let mut k = 0;
    let mut label = || {
        k += 1;
        format!("[{k}/{total}]")
    };

    // 1-2. Throughput and traffic.
    let t_head = Instant::now();
    let mut headline = Vec::new();
    for p in &head_points {
        let l = label();
        let r = run_point(&mut scenes, p, &cfg, &lat, &all_archs, GoldenRaster::Off, a.raster_sample, &l)?;
        log(&r, &l);
        headline.push(r);
    }
    let t_head = t_head.elapsed().as_secs_f64();

    // 3. Timelines (Neo's own run comes from the throughput runs when it matches).
    let t_tl = Instant::now();
    let mut timelines: Vec<PointResult> = Vec::new();
    let neo_tl = headline.iter().find(|r| r.point.scene == main_scene && r.point.res == tl_label).cloned();
    let neo_tl = match neo_tl {
        Some(mut r) => {
            r.archs.retain(|x| x.arch == "neo");
            r
        }
        None => {
            let p = point(
                synthetic::DEFAULT_SCENE,
                &a.trajectory,
                a.frames,
                &a.timeline_res,
                "neo",
                chunk,
                passes,
            )?;
            run_point(
                &mut scenes,
                &p,
                &cfg,
                &lat,
                &[Arch::Neo],
                GoldenRaster::Off,
                a.raster_sample,
                "[timeline]",
            )?
        }
    };
    timelines.push(neo_tl);
    timelines.extend(run_points_parallel(
        &mut scenes,
        &tl_points,
        &cfg,
        &lat,
        &[Arch::Neo],
        GoldenRaster::Off,
        a.raster_sample,
        "timelines",
        &log,
    )?);
    let t_tl = t_tl.elapsed().as_secs_f64();

    // 4. Sweep.
    let t_sw = Instant::now();
    let mut sweep = Vec::new();
    if let Some(dir) = &a.sweep_results {
        let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
            .with_context(|| format!("{}: cannot read the directory", dir.display()))?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|x| x == "json"))
            .collect();
        files.sort();
        for f in files {
            let text =
                std::fs::read_to_string(&f).with_context(|| format!("{}: cannot read", f.display()))?;
            let r: PointResult = serde_json::from_str(&text)
                .map_err(|e| anyhow!("{}: not a point result: {e}", f.display()))?;
            sweep.push(r);
        }
        if sweep.is_empty() {
            bail!("{}: no point results (*.json from `neo simulate --out DIR`)", dir.display());
        }
    }
    sweep.extend(run_points_parallel(
        &mut scenes,
        &sweep_points,
        &cfg,
        &lat,
        &[Arch::Neo],
        GoldenRaster::Exact,
        a.raster_sample,
        "sweep",
        &log,
    )?);
    let t_sw = t_sw.elapsed().as_secs_f64();

    // Render.
    let mut notes = vec![
        format!(
            "Throughput, traffic and timelines: {} frames of `{}` per run (the paper renders 60; DRAM per 60 frames is scaled from the frames run), chunk {chunk}, {passes} DPS pass(es), work-only golden workloads (no golden raster; SCU early termination measured on every {}-th tile).",
            a.frames, a.trajectory, a.raster_sample
        ),
        format!("Scenes: {}.", scenes_list.iter().map(|s| format!("`{s}`")).collect::<Vec<_>>().join(", ")),
    ];
    if !sweep.is_empty() {
        notes.push(format!(
            "Speed/error sweep on a smaller workload ({} points): `{}` at {}, {} frames, golden raster on (PSNR against the exact order).",
            sweep.len(),
            sweep[0].point.scene,
            sweep[0].point.res,
            sweep[0].point.frames
        ));
    }
    notes.push("GSCore-N: N sorting cores and N subtile units (N/4 raster cores of 4), hierarchical sort from scratch every frame, subtile bitmaps carried with every sort entry; GPU: Orin-AGX-like kernels with a global radix sort.".into());
    let data = ReportData {
        headline,
        timelines,
        sweep,
        settings: ReportSettings {
            command: "neo report".into(),
            raster_timing: lat.raster_source.label(),
            latency_file: latency::DEFAULT_PATH.into(),
            notes,
        },
    };
    let (md, svgs) = render(&data).map_err(|e| anyhow!(e))?;
    std::fs::create_dir_all(&a.out).with_context(|| format!("{}: cannot create", a.out.display()))?;
    let index = a.out.join("index.md");
    std::fs::write(&index, md).with_context(|| format!("{}: cannot write", index.display()))?;
    for (name, svg) in &svgs {
        let p = a.out.join(name);
        std::fs::write(&p, svg).with_context(|| format!("{}: cannot write", p.display()))?;
    }
    println!("wrote {} and {} figures", index.display(), svgs.len());
    for r in &data.headline {
        println!("{}", neo_sim::report::point_table(r));
    }
    println!(
        "time: throughput {t_head:.0} s, timelines {t_tl:.0} s, sweep {t_sw:.0} s, total {:.0} s; peak memory {}",
        t0.elapsed().as_secs_f64(),
        peak_rss_mb().map_or("unknown".into(), |m| format!("{m:.0} MB"))
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_tiny_report_writes_index_and_figures() {
        let dir = tempfile::tempdir().unwrap();
        let args = ReportArgs {
            scene: vec!["synthetic:outdoor?gaussians=10k&seed=2".into()],
            out: dir.path().to_path_buf(),
            trajectory: "orbit".into(),
            frames: 3,
            res: vec!["128x64".into()],
            timeline_res: "128x64".into(),
            timeline_sort: vec!["periodic:2".into()],
            sweep_scene: "synthetic:outdoor?gaussians=10k&seed=1".into(),
            sweep_res: "128x64".into(),
            sweep_frames: 2,
            sweep_sort: vec!["neo".into(), "hierarchical".into()],
            sweep_chunk: vec![64],
            sweep_passes: vec![1],
            sweep_speed: vec![1.0],
            sweep_results: None,
            no_sweep: false,
            raster_sample: 4,
            config: None,
            latency: PathBuf::from(latency::DEFAULT_PATH),
            no_default_scene: true,
        };
        run(args).unwrap();
        let md = std::fs::read_to_string(dir.path().join("index.md")).unwrap();
        for needle in [
            "## 1. Throughput",
            "gscore16",
            "## 2. DRAM traffic",
            "## 3. Sorting strategies",
            "periodic:2",
            "## 4. Speed against error",
            "hierarchical",
        ] {
            assert!(md.contains(needle), "index.md lacks {needle}");
        }
        for f in ["fig15_fps_0.svg", "fig16_dram_0.svg", "fig19_timeline.svg", "sweep_pareto.svg"] {
            let svg = std::fs::read_to_string(dir.path().join(f)).unwrap();
            assert!(svg.starts_with("<svg"), "{f}");
            assert!(md.contains(f), "index.md links {f}");
        }
    }
}
