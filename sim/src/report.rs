//! The report (`reports/index.md` and its SVG figures) from point results, and the text tables
//! `neo simulate` prints. Everything here is a pure function of the results, so the same results
//! give byte-identical files.

use std::fmt::Write as _;

use crate::plot::{self, HLine};
use crate::run::ArchResult;
use crate::signals::{Signal, SignalSummary};
use crate::suite::{strategy_label, PointResult};
use crate::traffic::Stage;

/// Figures published in the paper, for comparison (its scenes differ from ours: compare
/// ratios, not absolute values). Every GSCore figure of the paper's Figs. 5, 15 and 16 is a
/// **published constant**: a number typed into the official artifact's plotting script
/// (`src/neo_ae/draw.py` in casys-kaist/Neo), not the output of any simulator the artifact has.
/// The report labels them so and never divides a simulated figure by one.
pub mod published {
    /// GSCore FPS at HD, FHD, QHD (4 cores, 51.2 GB/s; the paper's Section 3.1 text).
    pub const GSCORE_FPS: [(&str, f64); 3] = [("hd", 66.7), ("fhd", 31.1), ("qhd", 15.8)];
    /// GSCore frame time (ms) at HD, FHD, QHD, mean over the six scenes of Fig. 15: published
    /// constants (`draw.py`, figure 15).
    pub const GSCORE_FIG15_MS: [(&str, f64); 3] = [("hd", 13.68), ("fhd", 28.48), ("qhd", 56.00)];
    /// Neo's average FPS at QHD (Section 6.2; simulated by the artifact).
    pub const NEO_QHD_FPS: f64 = 99.3;
    /// Neo's speedup over GSCore at HD, FHD, QHD (Section 6.2): the artifact's simulated Neo
    /// over GSCore's published constants.
    pub const NEO_OVER_GSCORE: [(&str, f64); 3] = [("hd", 1.8), ("fhd", 3.3), ("qhd", 5.6)];
    /// Neo's speedup over Orin AGX at HD, FHD, QHD (measured on the GPU by the authors).
    pub const NEO_OVER_ORIN: [(&str, f64); 3] = [("hd", 5.0), ("fhd", 7.2), ("qhd", 10.0)];
    /// DRAM GB for 60 QHD frames: Orin AGX, GSCore, Neo (Fig. 16). GSCore's 104.6 GB is the
    /// mean of six per-scene published constants (`draw.py`, figure 16).
    pub const DRAM_60_QHD: [(&str, f64); 3] = [("Orin AGX", 346.5), ("GSCore", 104.6), ("Neo", 19.6)];
    /// GSCore's DRAM GB for 60 QHD frames in Fig. 5: a published constant (`draw.py`,
    /// figure 5: 16.0 feature extraction + 55.3 sorting + 8.5 rasterisation), which disagrees
    /// with Fig. 16's 104.6 GB.
    pub const GSCORE_FIG5_60_QHD_GB: f64 = 79.9;
    /// Fig. 18 (Section 6.3 text): Neo-S (GSCore with Neo's Sorting Engine) over GSCore, speedup
    /// and the fraction of DRAM traffic it removes. GSCore's side is the published constant.
    pub const NEO_S_OVER_GSCORE: (f64, f64) = (3.3, 0.711);
    /// Fig. 18 (Section 6.3 text): Neo over Neo-S, speedup and the fraction of DRAM traffic
    /// Neo's Rasterization Engine (depth update in the raster) removes further.
    pub const NEO_OVER_NEO_S: (f64, f64) = (1.7, 0.358);
}

/// What the report shows besides the results.
#[derive(Clone, Debug, Default)]
pub struct ReportSettings {
    /// The command that produced it.
    pub command: String,
    /// Raster-timing provenance label.
    pub raster_timing: String,
    /// What of the preprocessing timing is measured ([`crate::latency::PreprocessMeasured::label`]).
    pub preprocess_timing: String,
    /// `latency.json` used.
    pub latency_file: String,
    /// Free-form lines about the reduced sizes used (frames, Gaussians, resolutions).
    pub notes: Vec<String>,
}

/// Everything the report shows.
#[derive(Clone, Debug, Default)]
pub struct ReportData {
    /// Headline runs: per scene and resolution, Neo's strategy on every architecture.
    pub headline: Vec<PointResult>,
    /// Sorting strategies on Neo's hardware (Fig. 19).
    pub timelines: Vec<PointResult>,
    /// The speed/error sweep.
    pub sweep: Vec<PointResult>,
    /// Settings.
    pub settings: ReportSettings,
}

fn f1(v: f64) -> String {
    format!("{v:.1}")
}

fn f2(v: f64) -> String {
    format!("{v:.2}")
}

fn opt(v: Option<f64>) -> String {
    v.map_or("-".into(), |x| format!("{x:.2}"))
}

fn scene_name(s: &str) -> String {
    s.rsplit('/').next().unwrap_or(s).to_string()
}

fn res_order(r: &str) -> usize {
    match r {
        "hd" => 0,
        "fhd" => 1,
        "qhd" => 2,
        _ => 3,
    }
}

/// Architecture names in display order.
fn arch_order(a: &str) -> (usize, u32) {
    let count = |prefix: &str| a.strip_prefix(prefix).and_then(|c| c.parse().ok());
    match (a, count("neos"), count("gscore")) {
        ("neo", _, _) => (0, 0),
        (_, Some(c), _) => (1, c),
        (_, _, Some(c)) => (2, c),
        ("gpu", _, _) => (3, 0),
        _ => (4, 0),
    }
}

fn speedup(neo: &ArchResult, other: &ArchResult) -> f64 {
    if other.fps > 0.0 {
        neo.fps / other.fps
    } else {
        0.0
    }
}

/// Per-frame table of one architecture (`neo simulate --per-frame`): interval, engine busy
/// time and the MB each stage read / wrote, from the same records as `--json`.
pub fn frame_table(a: &ArchResult) -> String {
    let mut s = String::new();
    let used: Vec<usize> = (0..Stage::ALL.len())
        .filter(|&k| {
            a.frames.iter().any(|f| f.stages.get(k).is_some_and(|b| b.read_bytes + b.write_bytes > 0))
        })
        .collect();
    let _ = write!(
        s,
        "{:<6} {:>5} {:>9} {:>8} {:>8} {:>8}",
        a.arch, "frame", "interval", "pre ms", "sort ms", "rast ms"
    );
    for &k in &used {
        let _ = write!(s, " {:>22}", format!("{} R/W MB", Stage::ALL[k].name()));
    }
    s.push('\n');
    let mb = |b: u64| b as f64 / 1e6;
    for f in &a.frames {
        let busy = |get: fn(&crate::run::EngineBusy) -> f64| {
            f.busy.as_ref().map_or("-".into(), |b| format!("{:.4}", get(b)))
        };
        let _ = write!(
            s,
            "{:<6} {:>5} {:>9.4} {:>8} {:>8} {:>8}",
            "",
            f.frame,
            f.interval_ms,
            busy(|b| b.preprocess_ms),
            busy(|b| b.sort_ms),
            busy(|b| b.raster_ms)
        );
        for &k in &used {
            let st = &f.stages[k];
            let _ = write!(s, " {:>22}", format!("{:.3}/{:.3}", mb(st.read_bytes), mb(st.write_bytes)));
        }
        s.push('\n');
    }
    s
}

/// The chunk of the per-speed tables where the sweep has it (Neo's, Section 4.3).
pub const SPEED_TABLE_CHUNK: usize = 256;

/// The chunk of the per-speed tables: [`SPEED_TABLE_CHUNK`] where the sweep has it, else its
/// first point's.
fn speed_chunk(sweep: &[PointResult]) -> usize {
    sweep.iter().map(|r| r.point.chunk).find(|&c| c == SPEED_TABLE_CHUNK).unwrap_or(sweep[0].point.chunk)
}

/// A row of the per-speed tables: a strategy and the raster cores' reorder window (1: none).
type SpeedRow<'a> = (&'a str, usize);

/// The sweep's point of `row` at camera speed `speed`, chunk `chunk` and one DPS pass.
fn speed_point<'a>(
    sweep: &'a [PointResult],
    (strategy, window): SpeedRow,
    speed: f64,
    chunk: usize,
) -> Option<&'a PointResult> {
    sweep.iter().find(|r| {
        r.point.strategy == strategy
            && r.point.raster_window == window
            && r.point.speed == speed
            && r.point.chunk == chunk
            && r.point.passes == 1
    })
}

/// The rows of the speed table: each strategy in the order of its first point, followed by its
/// points with a reorder window, smallest window first.
fn speed_rows(sweep: &[PointResult]) -> Vec<SpeedRow<'_>> {
    let mut strategies: Vec<&str> = Vec::new();
    let mut rows: Vec<SpeedRow> = Vec::new();
    for r in sweep {
        let row = (r.point.strategy.as_str(), r.point.raster_window);
        if !strategies.contains(&row.0) {
            strategies.push(row.0);
        }
        if !rows.contains(&row) {
            rows.push(row);
        }
    }
    let rank = |s: &str| strategies.iter().position(|&x| x == s);
    rows.sort_by_key(|&(s, w)| (rank(s), w));
    rows
}

/// FPS and quality against camera speed (the paper's Fig. 17(b), which shows FPS only), per
/// strategy (and per reorder window: `neo + window 256`) at the sweep's default chunk and one
/// DPS pass: FPS, worst-frame and mean PSNR against the exact order ("exact" for exact
/// strategies; "-" when every frame matched it).
fn speed_table(md: &mut String, sweep: &[PointResult], speeds: &[f64]) {
    let chunk = speed_chunk(sweep);
    let _ = writeln!(
        md,
        "FPS and quality against camera speed (Fig. 17(b) with the quality it does not show), chunk {chunk}, one DPS pass; each cell: FPS / worst-frame PSNR / mean PSNR (dB vs the exact order):\n"
    );
    let _ = write!(md, "| strategy |");
    for sp in speeds {
        let _ = write!(md, " {sp}x |");
    }
    let _ = write!(md, "\n| --- |");
    for _ in speeds {
        md.push_str(" --- |");
    }
    md.push('\n');
    for row in speed_rows(sweep) {
        let _ = write!(md, "| {} |", strategy_label(row.0, row.1));
        for &sp in speeds {
            let r = speed_point(sweep, row, sp, chunk);
            let cell = match r.and_then(|r| r.arch("neo").map(|a| (r, a))) {
                None => "".to_string(),
                Some((r, a)) if r.quality.is_exact() => format!("{} / exact", f1(a.fps)),
                Some((r, a)) => format!(
                    "{} / {} / {}",
                    f1(a.fps),
                    r.quality.psnr_vs_exact_min.map_or("-".into(), f2),
                    r.quality.psnr_vs_exact_mean.map_or("-".into(), f2)
                ),
            };
            let _ = write!(md, " {cell} |");
        }
        md.push('\n');
    }
    md.push('\n');
}

/// The text table `neo simulate` prints for one point.
pub fn point_table(r: &PointResult) -> String {
    let mut s = String::new();
    let p = &r.point;
    let _ = writeln!(
        s,
        "{} | {} x{} | {} ({}x{}) | {} frames | strategy {} | chunk {} | passes {}{}",
        scene_name(&p.scene),
        p.trajectory,
        p.speed,
        p.res,
        p.width,
        p.height,
        p.frames,
        p.strategy,
        p.chunk,
        p.passes,
        if p.raster_window > 1 { format!(" | raster window {}", p.raster_window) } else { String::new() }
    );
    let w = &r.workload;
    let _ = writeln!(
        s,
        "workload: {} Gaussians, {} tiles, {:.0} pairs/frame, {:.0} incoming/frame, SCU termination ratio {:.2}{}",
        w.gaussians,
        w.tiles,
        w.pairs_mean,
        w.incoming_mean,
        w.processed_ratio_mean,
        if w.golden_raster { " (golden raster)" } else { " (sampled)" }
    );
    let neo = r.arch("neo");
    let _ = writeln!(
        s,
        "{:<9} {:>8} {:>9} {:>9} {:>9} {:>9}  DRAM GB per 60 frames by stage",
        "arch", "FPS", "mean ms", "p99 ms", "neo vs", "GB/60"
    );
    let mut archs: Vec<&ArchResult> = r.archs.iter().collect();
    archs.sort_by_key(|a| arch_order(&a.arch));
    for a in archs {
        let sp = neo.map_or("-".into(), |n| if n.arch == a.arch { "1.00".into() } else { f2(speedup(n, a)) });
        let stages: Vec<String> = Stage::ALL
            .iter()
            .filter(|&&st| a.traffic.stage_bytes(st) > 0)
            .map(|&st| format!("{} {:.2}", st.name(), a.gb_per_60(Some(st))))
            .collect();
        let _ = writeln!(
            s,
            "{:<9} {:>8.1} {:>9.3} {:>9.3} {:>9} {:>9.2}  {}",
            a.arch,
            a.fps,
            a.frame_ms_mean,
            a.frame_ms_p99,
            sp,
            a.gb_per_60(None),
            stages.join(", ")
        );
    }
    let q = &r.quality;
    if q.exact_by_construction {
        let _ = writeln!(s, "quality: exact order by construction (PSNR vs exact: identical)");
    } else if q.frames > 0 {
        let _ = writeln!(
            s,
            "quality ({} frames, {} identical to exact): PSNR vs exact mean {} dB (pooled {}), vs float {} dB (exact order: {})",
            q.frames,
            q.identical,
            opt(q.psnr_vs_exact_mean),
            opt(q.psnr_vs_exact_pooled),
            opt(q.psnr_vs_float_mean),
            opt(q.exact_psnr_vs_float_mean)
        );
    } else {
        let _ = writeln!(s, "quality: not computed (work-only workload; run with --quality for PSNR)");
    }
    if let Some(a) = r.archs.iter().find(|a| a.arch == "neo" || a.arch.starts_with("gscore")) {
        let _ = writeln!(s, "{}", a.raster_timing);
        let _ = writeln!(s, "{}", a.preprocess_timing);
    }
    s
}

/// The Fig. 18 ablation (after section 2): GSCore, Neo-S and Neo on the run that has Neo-S
/// (the largest resolution of the main scene), speedup and traffic against GSCore with the same
/// core count, beside the paper's Section 6.3 figures. Nothing when no run has Neo-S.
fn ablation(md: &mut String, head: &[&PointResult]) {
    let found = head.iter().find_map(|r| {
        let s = r.archs.iter().find(|a| a.arch.starts_with("neos"))?;
        let g = r.arch(&s.arch.replacen("neos", "gscore", 1))?;
        Some((r, g, s, r.arch("neo")?))
    });
    let Some((r, gscore, neos, neo)) = found else { return };
    let _ = writeln!(
        md,
        "### Ablation: Neo's Sorting Engine in GSCore (paper Fig. 18)
"
    );
    let _ = writeln!(
        md,
        "{} at {} ({}x{}), {} frames. `{}` is {} with Neo's Sorting Engine (the tables reused and updated) but not its Rasterization Engine: no ITU, no depth write-back in the raster, so a separate pass per tile after its raster reads the table, gathers every entry's feature word (its new depth and visibility) and writes the table back (the depth write-back row of section 2). The paper's figures come from the text of its Section 6.3; its GSCore is a published constant.\n",
        scene_name(&r.point.scene),
        r.point.res,
        r.point.width,
        r.point.height,
        r.point.frames,
        neos.arch,
        gscore.arch
    );
    let _ = writeln!(md, "| arch | FPS | speedup over {0} | DRAM GB / 60 | traffic vs {0} | paper: speedup over GSCore | paper: traffic vs GSCore |", gscore.arch);
    let _ = writeln!(md, "| --- | ---: | ---: | ---: | ---: | ---: | ---: |");
    let (ps, pn) = (published::NEO_S_OVER_GSCORE, published::NEO_OVER_NEO_S);
    let paper = [(1.0, 1.0), (ps.0, 1.0 - ps.1), (ps.0 * pn.0, (1.0 - ps.1) * (1.0 - pn.1))];
    for (a, (p_speed, p_traffic)) in [gscore, neos, neo].into_iter().zip(paper) {
        let _ = writeln!(
            md,
            "| {} | {} | {:.2}x | {} | {:.3} | {:.2}x | {:.3} |",
            a.arch,
            f1(a.fps),
            a.fps / gscore.fps.max(1e-12),
            f2(a.gb_per_60(None)),
            a.gb_per_60(None) / gscore.gb_per_60(None).max(1e-12),
            p_speed,
            p_traffic
        );
    }
    md.push('\n');
}

/// The throughput runs in one plain-text table (scene, resolution, architecture, FPS, speedup
/// of Neo, DRAM GB per 60 frames): what `neo report` prints as soon as they are done.
pub fn headline_table(runs: &[PointResult]) -> String {
    let mut s = String::new();
    let w = runs.iter().map(|r| scene_name(&r.point.scene).len()).max().unwrap_or(0).max(5);
    let _ =
        writeln!(s, "{:<w$} {:<9} {:<9} {:>8} {:>9} {:>9}", "scene", "res", "arch", "FPS", "Neo vs", "GB/60");
    let mut runs: Vec<&PointResult> = runs.iter().collect();
    runs.sort_by(|a, b| {
        (a.point.scene.as_str(), res_order(&a.point.res))
            .cmp(&(b.point.scene.as_str(), res_order(&b.point.res)))
    });
    for r in runs {
        let neo = r.arch("neo");
        let mut archs: Vec<&ArchResult> = r.archs.iter().collect();
        archs.sort_by_key(|a| arch_order(&a.arch));
        for a in archs {
            let sp = neo.map_or("-".into(), |n| format!("{:.2}x", speedup(n, a)));
            let _ = writeln!(
                s,
                "{:<w$} {:<9} {:<9} {:>8} {:>9} {:>9}",
                scene_name(&r.point.scene),
                r.point.res,
                a.arch,
                f1(a.fps),
                sp,
                f2(a.gb_per_60(None))
            );
        }
    }
    s
}

/// Renders the report: the markdown and the SVG files `(name, content)`.
pub fn render(d: &ReportData) -> Result<(String, Vec<(String, String)>), String> {
    let mut md = String::new();
    let mut svgs = Vec::new();
    let st = &d.settings;
    let _ = writeln!(md, "# Neo cycle-model report\n");
    let _ = writeln!(md, "Generated by `{}` (the model, its inputs and its limits: [docs/cycle-model.md](../docs/cycle-model.md)).\n", st.command);
    let _ = writeln!(md, "- **{}**", st.raster_timing);
    let _ = writeln!(md, "- **{}**", st.preprocess_timing);
    let _ = writeln!(md, "- Sorting-core timing: measured on the RTL (`{}`); the GPU baseline's rates are assumed (config `gpu.*`).", st.latency_file);
    for n in &st.notes {
        let _ = writeln!(md, "- {n}");
    }
    md.push('\n');

    // 1. Throughput.
    let mut head: Vec<&PointResult> = d.headline.iter().collect();
    head.sort_by(|a, b| {
        (a.point.scene.clone(), res_order(&a.point.res))
            .cmp(&(b.point.scene.clone(), res_order(&b.point.res)))
    });
    let _ = writeln!(md, "## 1. Throughput (paper Fig. 15)\n");
    let _ = writeln!(md, "| scene | res | arch | FPS | mean frame (ms) | p99 frame (ms) | Neo speedup | DRAM GB / 60 frames | of which sorting |");
    let _ = writeln!(md, "| --- | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: |");
    for r in &head {
        let neo = r.arch("neo");
        let mut archs: Vec<&ArchResult> = r.archs.iter().collect();
        archs.sort_by_key(|a| arch_order(&a.arch));
        for a in archs {
            let sp = neo.map_or("-".into(), |n| format!("{:.2}x", speedup(n, a)));
            let sorting = a.sorting_gb_per_60();
            let _ = writeln!(
                md,
                "| {} | {} | {} | {} | {:.3} | {:.3} | {} | {} | {} |",
                scene_name(&r.point.scene),
                r.point.res,
                a.arch,
                f1(a.fps),
                a.frame_ms_mean,
                a.frame_ms_p99,
                sp,
                f2(a.gb_per_60(None)),
                f2(sorting)
            );
        }
    }
    md.push('\n');
    let scenes: Vec<String> = {
        let mut v: Vec<String> = head.iter().map(|r| r.point.scene.clone()).collect();
        v.dedup();
        v
    };
    for (si, scene) in scenes.iter().enumerate() {
        let rs: Vec<&&PointResult> = head.iter().filter(|r| &r.point.scene == scene).collect();
        let groups: Vec<String> = rs.iter().map(|r| r.point.res.to_uppercase()).collect();
        let mut names: Vec<String> = rs.iter().flat_map(|r| r.archs.iter().map(|a| a.arch.clone())).collect();
        names.sort_by_key(|a| arch_order(a));
        names.dedup();
        // Only the architectures run at every resolution (Neo-S runs at one, section 3).
        names.retain(|n| rs.iter().all(|r| r.arch(n).is_some()));
        let series: Vec<(String, Vec<f64>)> = names
            .iter()
            .map(|n| (n.clone(), rs.iter().map(|r| r.arch(n).map_or(0.0, |a| a.fps)).collect()))
            .collect();
        let file = format!("fig15_fps_{si}.svg");
        svgs.push((
            file.clone(),
            plot::grouped_bars(
                &format!("Throughput, {}", scene_name(scene)),
                "frames per second",
                &groups,
                &series,
                Some(HLine { y: 60.0, label: "60 FPS SLO".into() }),
            )?,
        ));
        let _ = writeln!(md, "![throughput {}]({file})\n", scene_name(scene));
    }
    let _ = writeln!(md, "Speedup ratios beside the paper's (different scenes; the paper's GSCore is the 16-core scaled one). The paper's Neo / GSCore divides the artifact's simulated Neo by GSCore figures that are **published constants** (typed into the artifact's plotting script, not simulated): it is shown, never combined with ours.\n");
    let _ = writeln!(md, "| scene | res | Neo / GSCore-16 | Neo / GSCore-4 | Neo / GPU | paper: Neo / GSCore (published constant) | paper: Neo / Orin AGX |");
    let _ = writeln!(md, "| --- | --- | ---: | ---: | ---: | ---: | ---: |");
    for r in &head {
        let Some(neo) = r.arch("neo") else { continue };
        let ratio = |n: &str| r.arch(n).map_or("-".into(), |a| format!("{:.2}x", speedup(neo, a)));
        let pg = published::NEO_OVER_GSCORE
            .iter()
            .find(|x| x.0 == r.point.res)
            .map_or("-".into(), |x| format!("{}x", x.1));
        let po = published::NEO_OVER_ORIN
            .iter()
            .find(|x| x.0 == r.point.res)
            .map_or("-".into(), |x| format!("{}x", x.1));
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | {} | {} | {} |",
            scene_name(&r.point.scene),
            r.point.res,
            ratio("gscore16"),
            ratio("gscore4"),
            ratio("gpu"),
            pg,
            po
        );
    }
    let _ = writeln!(
        md,
        "\nPublished absolute figures: GSCore (4 cores, 51.2 GB/s) {} FPS at HD/FHD/QHD (Section 3.1); GSCore in Fig. 15 {} ms per frame at HD/FHD/QHD, mean of six scenes (published constants); Neo {} FPS average at QHD (simulated by the artifact).\n",
        published::GSCORE_FPS.iter().map(|x| x.1.to_string()).collect::<Vec<_>>().join(" / "),
        published::GSCORE_FIG15_MS.iter().map(|x| x.1.to_string()).collect::<Vec<_>>().join(" / "),
        published::NEO_QHD_FPS
    );

    // 2. DRAM traffic.
    let _ = writeln!(md, "## 2. DRAM traffic (paper Fig. 16)\n");
    for (si, scene) in scenes.iter().enumerate() {
        let Some(r) = head
            .iter()
            .filter(|r| &r.point.scene == scene)
            .max_by_key(|r| r.point.width as u64 * r.point.height as u64)
        else {
            continue;
        };
        let mut archs: Vec<&ArchResult> = r.archs.iter().collect();
        archs.sort_by_key(|a| arch_order(&a.arch));
        let _ = writeln!(
            md,
            "GB per 60 frames at {} ({}x{}), {}, by stage (read + write, whole 64-byte requests):\n",
            r.point.res,
            r.point.width,
            r.point.height,
            scene_name(scene)
        );
        let _ = write!(md, "| stage |");
        for a in &archs {
            let _ = write!(md, " {} |", a.arch);
        }
        let _ = write!(md, "\n| --- |");
        for _ in &archs {
            let _ = write!(md, " ---: |");
        }
        md.push('\n');
        let used: Vec<Stage> = Stage::ALL
            .iter()
            .copied()
            .filter(|&s| archs.iter().any(|a| a.traffic.stage_bytes(s) > 0))
            .collect();
        for &s in &used {
            let _ = write!(md, "| {} |", s.name());
            for a in &archs {
                let _ = write!(md, " {} |", f2(a.gb_per_60(Some(s))));
            }
            md.push('\n');
        }
        let _ = write!(md, "| **total** |");
        for a in &archs {
            let _ = write!(md, " **{}** |", f2(a.gb_per_60(None)));
        }
        md.push('\n');
        if let Some(neo) = r.arch("neo") {
            let ng = neo.gb_per_60(None);
            let mut line = String::from("\nNeo's traffic relative to:");
            for a in &archs {
                if a.arch != "neo" {
                    let _ = write!(line, " {} {:.3};", a.arch, ng / a.gb_per_60(None).max(1e-12));
                }
            }
            let p = published::DRAM_60_QHD;
            let _ = write!(
                line,
                " paper (QHD, 60 frames: Orin AGX {} GB, GSCore {} GB as a published constant (Fig. 5's constant says {} GB), Neo {} GB): Neo / GSCore {:.3} (over the published constant), Neo / Orin AGX {:.3}.",
                p[0].1,
                p[1].1,
                published::GSCORE_FIG5_60_QHD_GB,
                p[2].1,
                p[2].1 / p[1].1,
                p[2].1 / p[0].1
            );
            let _ = writeln!(md, "{line}\n");
        }
        let bars: Vec<String> = archs.iter().map(|a| a.arch.clone()).collect();
        let stacks: Vec<(String, Vec<f64>)> = used
            .iter()
            .map(|&s| (s.name().to_string(), archs.iter().map(|a| a.gb_per_60(Some(s))).collect()))
            .collect();
        let file = format!("fig16_dram_{si}.svg");
        svgs.push((
            file.clone(),
            plot::stacked_bars(
                &format!("DRAM per 60 frames, {} {}", scene_name(scene), r.point.res.to_uppercase()),
                "GB",
                &bars,
                &stacks,
            )?,
        ));
        let _ = writeln!(md, "![DRAM traffic]({file})\n");
    }

    ablation(&mut md, &head);

    // 3. Strategies on Neo's hardware.
    if !d.timelines.is_empty() {
        let p0 = &d.timelines[0].point;
        let _ = writeln!(md, "## 3. Sorting strategies on Neo's hardware (paper Fig. 19)\n");
        let _ = writeln!(
            md,
            "{} at {} ({}x{}), {} frames, camera speed {}x. Frame time is the interval between completed frames; the periodic strategy re-sorts from scratch at its refresh frames, the background sorter adds its full sort of every frame to the sorting cores and DRAM.\n",
            scene_name(&p0.scene),
            p0.res,
            p0.width,
            p0.height,
            p0.frames,
            p0.speed
        );
        let _ = writeln!(md, "| strategy | FPS | mean frame (ms) | p99 frame (ms) | max frame (ms) | DRAM GB / 60 | sorting GB / 60 |");
        let _ = writeln!(md, "| --- | ---: | ---: | ---: | ---: | ---: | ---: |");
        let mut series = Vec::new();
        for r in &d.timelines {
            let Some(a) = r.arch("neo") else { continue };
            let sorting = a.sorting_gb_per_60();
            let _ = writeln!(
                md,
                "| {} | {} | {:.3} | {:.3} | {:.3} | {} | {} |",
                r.point.strategy,
                f1(a.fps),
                a.frame_ms_mean,
                a.frame_ms_p99,
                a.frame_ms_max,
                f2(a.gb_per_60(None)),
                f2(sorting)
            );
            series.push((
                r.point.strategy.clone(),
                a.frames.iter().skip(1).map(|f| (f.frame as f64, f.interval_ms)).collect::<Vec<_>>(),
            ));
        }
        let file = "fig19_timeline.svg".to_string();
        svgs.push((
            file.clone(),
            plot::lines(
                "Frame time per frame on Neo's hardware",
                "frame",
                "frame time (ms)",
                &series,
                Some(HLine { y: 1000.0 / 60.0, label: "16.6 ms (60 FPS)".into() }),
            )?,
        ));
        let _ = writeln!(md, "\n![frame times]({file})\n");
    }

    // 4. Speed against error.
    if !d.sweep.is_empty() {
        let p0 = &d.sweep[0].point;
        let _ = writeln!(md, "## 4. Speed against error\n");
        let _ = writeln!(
            md,
            "One point per (strategy, chunk, DPS passes, camera speed) on Neo's hardware: {} at {}x{}, {} frames of `{}`. Speed: the model's FPS on that workload. Error: PSNR against the exact-order frame of the same fixed-point pipeline, from the mean squared error over all frames (higher is better; exact strategies are drawn at the top of the axis). DPS passes apply to `neo` only.\n",
            scene_name(&p0.scene),
            p0.width,
            p0.height,
            p0.frames,
            p0.trajectory
        );
        window_note(&mut md, &d.sweep);
        let finite: Vec<f64> = d.sweep.iter().filter_map(|r| r.quality.psnr_vs_exact_pooled).collect();
        let cap = finite.iter().copied().fold(30.0, f64::max).ceil() + 3.0;
        let y_of =
            |r: &PointResult| if r.quality.is_exact() { Some(cap) } else { r.quality.psnr_vs_exact_pooled };
        let mut by_strategy: Vec<(String, Vec<(f64, f64)>)> = Vec::new();
        let mut all = Vec::new();
        for r in &d.sweep {
            let (Some(a), Some(y)) = (r.arch("neo"), y_of(r)) else { continue };
            let key = r.point.strategy_label();
            match by_strategy.iter_mut().find(|g| g.0 == key) {
                Some(g) => g.1.push((a.fps, y)),
                None => by_strategy.push((key, vec![(a.fps, y)])),
            }
            all.push((a.fps, y));
        }
        let front = plot::pareto_front(&all);
        let file = "sweep_pareto.svg".to_string();
        svgs.push((
            file.clone(),
            plot::scatter_front(
                &format!("Speed against error (exact order drawn at {cap:.0} dB)"),
                "FPS (model)",
                "PSNR vs exact order (dB)",
                &by_strategy,
                &front,
            )?,
        ));
        let _ = writeln!(md, "![speed against error]({file})\n");
        // Sorting traffic against the worst frame, per camera speed (issue 14).
        let sort_gb = |a: &ArchResult| -> f64 {
            Stage::ALL.iter().filter(|s| s.is_sorting()).map(|&s| a.gb_per_60(Some(s))).sum()
        };
        let min_of =
            |r: &PointResult| if r.quality.is_exact() { Some(cap) } else { r.quality.psnr_vs_exact_min };
        let _ = writeln!(
            md,
            "Sorting DRAM traffic (incoming lists, sort tables, background sorter) against the worst frame's PSNR, per camera speed; the front is the least traffic for a given worst frame (issue 14's target: at least 45 dB in every frame for at most 1.5x `neo`'s traffic; docs/adaptive.md).\n"
        );
        let mut speeds: Vec<f64> = d.sweep.iter().map(|r| r.point.speed).collect();
        speeds.sort_by(f64::total_cmp);
        speeds.dedup();
        for (si, &speed) in speeds.iter().enumerate() {
            let mut groups: Vec<(String, Vec<(f64, f64)>)> = Vec::new();
            let mut pts = Vec::new();
            for r in d.sweep.iter().filter(|r| r.point.speed == speed) {
                let (Some(a), Some(y)) = (r.arch("neo"), min_of(r)) else { continue };
                // Less traffic is better: the front takes the negated traffic as its x.
                pts.push((-sort_gb(a), y));
                let key = r.point.strategy_label();
                match groups.iter_mut().find(|g| g.0 == key) {
                    Some(g) => g.1.push((sort_gb(a), y)),
                    None => groups.push((key, vec![(sort_gb(a), y)])),
                }
            }
            let front: Vec<(f64, f64)> = plot::pareto_front(&pts).into_iter().map(|(x, y)| (-x, y)).collect();
            let file = format!("sweep_traffic_min_psnr_{si}.svg");
            svgs.push((
                file.clone(),
                plot::scatter_front(
                    &format!("Sorting traffic against the worst frame at {speed}x (exact at {cap:.0} dB)"),
                    "sorting DRAM (GB per 60 frames)",
                    "min-frame PSNR vs exact order (dB)",
                    &groups,
                    &front,
                )?,
            ));
            let _ = writeln!(md, "![sorting traffic against the worst frame at {speed}x]({file})\n");
        }
        speed_table(&mut md, &d.sweep, &speeds);
        let _ = writeln!(md, "| strategy | chunk | passes | speed | FPS | p99 frame (ms) | DRAM GB / 60 | PSNR vs exact (dB) | frames identical to exact | Pareto |");
        let _ = writeln!(md, "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | --- |");
        for r in &d.sweep {
            let Some(a) = r.arch("neo") else { continue };
            let y = y_of(r);
            let on = y.is_some_and(|y| front.contains(&(a.fps, y)));
            let q =
                if r.quality.is_exact() { "exact".to_string() } else { opt(r.quality.psnr_vs_exact_pooled) };
            let _ = writeln!(
                md,
                "| {} | {} | {} | {}x | {} | {:.3} | {} | {} | {} | {} |",
                r.point.strategy_label(),
                r.point.chunk,
                r.point.passes,
                r.point.speed,
                f1(a.fps),
                a.frame_ms_p99,
                f2(a.gb_per_60(None)),
                q,
                if r.quality.exact_by_construction {
                    "all".to_string()
                } else {
                    format!("{} / {}", r.quality.identical, r.quality.frames)
                },
                if on { "yes" } else { "" }
            );
        }
        md.push('\n');
        signals_section(&mut md, &mut svgs, &d.sweep, &speeds)?;
    }
    Ok((md, svgs))
}

/// The sentence of section 4 on its reorder-window points (`neo + window W`), when it has any.
fn window_note(md: &mut String, sweep: &[PointResult]) {
    let mut labels: Vec<String> = Vec::new();
    for p in sweep.iter().map(|r| &r.point).filter(|p| p.raster_window > 1) {
        let label = format!("`{}`", p.strategy_label());
        if !labels.contains(&label) {
            labels.push(label);
        }
    }
    if labels.is_empty() {
        return;
    }
    let _ = writeln!(
        md,
        "{}: the strategy with a W-entry reorder window in each raster core, which blends and writes back each tile in the current depth order within W entries; it is on chip (a feature store of about 32 W bytes per raster core), moves no DRAM traffic, and its held-back loads are in the FPS (docs/adaptive.md section 7).\n",
        labels.join(", ")
    );
}

/// Section 5: how well the disorder signals rank the tiles by their error, from the sweep's
/// `neo` points (chunk 256 where swept, one DPS pass), one row per camera speed, and the
/// previous frame's reach against the error (issue 14; docs/adaptive.md section 1).
fn signals_section(
    md: &mut String,
    svgs: &mut Vec<(String, String)>,
    sweep: &[PointResult],
    speeds: &[f64],
) -> Result<(), String> {
    let chunk = speed_chunk(sweep);
    let rows: Vec<(f64, &SignalSummary)> = speeds
        .iter()
        .filter_map(|&sp| {
            speed_point(sweep, ("neo", 1), sp, chunk).and_then(|r| r.signals.as_ref()).map(|s| (sp, s))
        })
        .collect();
    if rows.is_empty() {
        return Ok(());
    }
    let _ = writeln!(md, "## 5. Disorder signals against the per-tile error\n");
    let _ = writeln!(
        md,
        "Spearman rank correlation over the tiles and frames of the sweep's `neo` points (chunk {chunk}, one DPS pass) between each signal the hardware counts and the tile's error (sum of |neo - exact order| over its pixels and channels). Tiles without Gaussians, tiles sorted from scratch and shot starts are left out. Each cell: the frame's own signal / the previous frame's (what the frame controller has before it sorts; the merge counter and the shares are always the frame's own). docs/adaptive.md section 1 has the same on biker.\n"
    );
    let _ = write!(md, "| speed | tiles (with error) |");
    for s in Signal::ALL {
        let _ = write!(md, " {} |", s.name());
    }
    let _ = write!(md, "\n| --- | ---: |");
    for _ in Signal::ALL {
        md.push_str(" ---: |");
    }
    md.push('\n');
    let rho = |v: Option<f64>| v.map_or("-".to_string(), |x| format!("{x:.2}"));
    for (sp, s) in &rows {
        let _ = write!(md, "| {sp}x | {} ({}) |", s.samples, s.with_error);
        for sig in Signal::ALL {
            let c = s.get(sig);
            let _ = write!(md, " {} / {} |", rho(c.and_then(|c| c.same)), rho(c.and_then(|c| c.next)));
        }
        md.push('\n');
    }
    let lg = |v: f64| (1.0 + v).log10();
    let groups: Vec<(String, Vec<(f64, f64)>)> = rows
        .iter()
        .map(|(sp, s)| (format!("{sp}x"), s.reach_vs_error.iter().map(|&(x, y)| (lg(x), lg(y))).collect()))
        .collect();
    let file = "signals_reach_error.svg".to_string();
    svgs.push((
        file.clone(),
        plot::scatter_front(
            "Previous frame's write-back reach against the tile's error",
            "log10(1 + reach)",
            "log10(1 + error)",
            &groups,
            &[],
        )?,
    ));
    let _ = writeln!(md, "\n![reach against error]({file})\n");
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::suite::{Point, QualitySummary};

    /// A sweep point's result with made-up figures that differ per point (`k`).
    fn result(strategy: &str, window: usize, speed: f64, chunk: usize, k: usize) -> PointResult {
        let point = Point {
            scene: "synthetic:outdoor?gaussians=10k".into(),
            trajectory: "orbit".into(),
            speed,
            frames: 4,
            res: "128x64".into(),
            width: 128,
            height: 64,
            strategy: strategy.into(),
            chunk,
            passes: 1,
            raster_window: window,
        };
        let x = k as f64;
        PointResult {
            point,
            workload: Default::default(),
            quality: QualitySummary {
                frames: 4,
                psnr_vs_exact_mean: Some(40.0 + 1.5 * x),
                psnr_vs_exact_pooled: Some(38.0 + 1.5 * x),
                psnr_vs_exact_min: Some(30.0 + 1.25 * x),
                ..QualitySummary::default()
            },
            archs: vec![ArchResult { arch: "neo".into(), fps: 100.0 + 7.0 * x, ..ArchResult::default() }],
            signals: None,
        }
    }

    /// Neo and periodic at 1x and 16x, one Neo point at another chunk, and Neo with a 256-entry
    /// window when `window`.
    fn sweep(window: bool) -> Vec<PointResult> {
        let mut v = Vec::new();
        let mut rows = vec![("neo", 1), ("periodic:4", 1)];
        if window {
            rows.push(("neo", 256));
        }
        for (strategy, w) in rows {
            for speed in [1.0, 16.0] {
                v.push(result(strategy, w, speed, 256, v.len()));
            }
        }
        v.push(result("neo", 1, 1.0, 64, v.len()));
        v
    }

    /// The speed table's cell of `r`, from its figures.
    fn cell(r: &PointResult) -> String {
        let q = &r.quality;
        let fps = f1(r.arch("neo").unwrap().fps);
        format!("{fps} / {} / {}", f2(q.psnr_vs_exact_min.unwrap()), f2(q.psnr_vs_exact_mean.unwrap()))
    }

    #[test]
    fn the_window_points_get_their_own_rows_labels_and_series() {
        let sweep = sweep(true);
        let (md, svgs) = render(&ReportData { sweep: sweep.clone(), ..ReportData::default() }).unwrap();
        let lines: Vec<&str> = md.lines().collect();
        let at = lines.iter().position(|l| *l == "| strategy | 1x | 16x |").expect("the speed table");
        // The window's row follows its strategy's, each row from its own points.
        for (k, (strategy, w)) in [("neo", 1), ("neo", 256), ("periodic:4", 1)].into_iter().enumerate() {
            let cells: Vec<&str> = lines[at + 2 + k].split('|').map(str::trim).collect();
            assert_eq!(cells[1], strategy_label(strategy, w), "{}", lines[at + 2 + k]);
            for (c, speed) in [1.0, 16.0].into_iter().enumerate() {
                let r = sweep
                    .iter()
                    .find(|r| {
                        let p = &r.point;
                        (p.strategy.as_str(), p.raster_window, p.speed, p.chunk) == (strategy, w, speed, 256)
                    })
                    .unwrap();
                assert_eq!(cells[2 + c], cell(r), "{strategy} window {w} at {speed}x");
            }
        }
        assert!(!lines[at + 5].starts_with('|'), "three rows: {}", lines[at + 5]);
        // The big table names the window in the strategy cell.
        let big = lines.iter().filter(|l| l.starts_with("| neo + window 256 | 256 | 1 |")).count();
        assert_eq!(big, 2, "{md}");
        // The figures draw the window points as a series of their own, and the text says what it is.
        for (name, svg) in svgs.iter().filter(|(n, _)| n.starts_with("sweep_")) {
            assert!(svg.contains("neo + window 256"), "{name}");
        }
        assert!(svgs.iter().filter(|(n, _)| n.starts_with("sweep_traffic_min_psnr_")).count() == 2);
        let note = lines.iter().find(|l| l.starts_with("`neo + window 256`")).expect("the window note");
        assert!(note.contains("reorder window") && note.contains("docs/adaptive.md section 7"), "{note}");
    }

    #[test]
    fn a_sweep_without_windows_renders_as_before() {
        let (md, svgs) = render(&ReportData { sweep: sweep(false), ..ReportData::default() }).unwrap();
        assert!(!md.contains("window"), "{md}");
        assert!(svgs.iter().all(|(_, svg)| !svg.contains("window")));
        // The same points with windows added: the rest of the speed table is unchanged.
        let (with, _) = render(&ReportData { sweep: sweep(true), ..ReportData::default() }).unwrap();
        let row =
            |md: &str, s: &str| md.lines().find(|l| l.starts_with(&format!("| {s} | "))).map(String::from);
        for s in ["neo", "periodic:4"] {
            assert_eq!(row(&md, s), row(&with, s), "{s}");
        }
    }
}
