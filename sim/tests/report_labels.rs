//! The report sets the paper's published figures beside neo's simulated ones and labels the
//! GSCore figures that are published constants (typed into the official artifact's plotting
//! script), never combining them with a simulated figure.

use neo_golden::{shared, source};
use neo_sim::config::SimConfig;
use neo_sim::latency::Latency;
use neo_sim::report::{published, render, ReportData};
use neo_sim::run::Arch;
use neo_sim::suite::{evaluate, workload, Point};

#[test]
fn published_constants_are_labelled_and_kept_apart() {
    let lat = Latency::from_file(&shared::workspace_root().join("reports/latency.json")).unwrap();
    let cfg = SimConfig::default();
    let scene_spec = "synthetic:outdoor?gaussians=3000&seed=2";
    let (scene, _) = source::load_scene(scene_spec, false).unwrap();
    let point = Point {
        scene: scene_spec.into(),
        trajectory: "orbit".into(),
        speed: 1.0,
        frames: 2,
        res: "qhd".into(),
        width: 2560,
        height: 1440,
        strategy: "neo".into(),
        chunk: 256,
        passes: 1,
        raster_window: 1,
    };
    let wl = workload(&scene, &point, &cfg, neo_sim::driver::GoldenRaster::Off, 16, |_| {}).unwrap();
    let r = evaluate(&point, &wl, &cfg, &lat, &[Arch::Neo, Arch::Gscore(16), Arch::NeoS(16)]).unwrap();
    let data = ReportData { headline: vec![r.clone()], ..ReportData::default() };
    let (md, _) = render(&data).unwrap();
    ablation_rows_are_simulated_beside_the_papers(&md, &r);
    // The speed-up table names the paper's ratio as one over a published constant, with the
    // paper's value, beside neo's own simulated ratio.
    let lines: Vec<&str> = md.lines().collect();
    let at =
        lines.iter().position(|l| l.starts_with("| scene | res | Neo / GSCore-16")).expect("speed-up table");
    assert!(lines[at].contains("paper: Neo / GSCore (published constant)"), "{}", lines[at]);
    let row = lines[at + 2];
    let cells: Vec<&str> = row.split('|').map(str::trim).collect();
    let paper = published::NEO_OVER_GSCORE.iter().find(|x| x.0 == "qhd").unwrap().1;
    assert_eq!(cells[6], format!("{paper}x"), "{row}");
    assert_ne!(cells[3], cells[6], "neo's simulated ratio is its own: {row}");
    // The absolute figures and the DRAM comparison say which GSCore numbers are constants.
    assert!(
        md.contains("published constants); Neo 99.3 FPS average at QHD (simulated by the artifact)"),
        "{md}"
    );
    assert!(md.contains("GSCore 104.6 GB as a published constant (Fig. 5's constant says 79.9 GB)"), "{md}");
}

/// The Fig. 18 table: GSCore-16, Neo-S and Neo with their simulated speedups and traffic over
/// GSCore-16, and the paper's Section 6.3 figures in their own columns.
fn ablation_rows_are_simulated_beside_the_papers(md: &str, r: &neo_sim::suite::PointResult) {
    let lines: Vec<&str> = md.lines().collect();
    let at = lines
        .iter()
        .position(|l| l.starts_with("| arch | FPS | speedup over gscore16"))
        .expect("ablation table");
    assert!(lines[at].contains("paper: speedup over GSCore"), "{}", lines[at]);
    let (g, s) = (r.arch("gscore16").unwrap(), r.arch("neos16").unwrap());
    let (ps, pn) = (published::NEO_S_OVER_GSCORE, published::NEO_OVER_NEO_S);
    for (k, (name, paper)) in
        [("gscore16", 1.0), ("neos16", ps.0), ("neo", ps.0 * pn.0)].into_iter().enumerate()
    {
        let cells: Vec<&str> = lines[at + 2 + k].split('|').map(str::trim).collect();
        let a = r.arch(name).unwrap();
        assert_eq!(cells[1], name);
        assert_eq!(cells[3], format!("{:.2}x", a.fps / g.fps), "{name}: simulated speedup");
        assert_eq!(cells[6], format!("{paper:.2}x"), "{name}: the paper's");
    }
    assert!(s.gb_per_60(None) > 0.0);
}

#[test]
fn the_speed_table_gives_fps_and_quality_per_camera_speed() {
    let lat = Latency::from_file(&shared::workspace_root().join("reports/latency.json")).unwrap();
    let cfg = SimConfig::default();
    let scene_spec = "synthetic:outdoor?gaussians=3000&seed=2";
    let (scene, _) = source::load_scene(scene_spec, false).unwrap();
    let mut sweep = Vec::new();
    for strategy in ["neo", "hierarchical"] {
        for speed in [1.0, 16.0] {
            let point = Point {
                scene: scene_spec.into(),
                trajectory: "orbit".into(),
                speed,
                frames: 3,
                res: "128x64".into(),
                width: 128,
                height: 64,
                strategy: strategy.into(),
                chunk: 256,
                passes: 1,
                raster_window: 1,
            };
            let wl =
                workload(&scene, &point, &cfg, neo_sim::driver::GoldenRaster::Exact, 16, |_| {}).unwrap();
            sweep.push(evaluate(&point, &wl, &cfg, &lat, &[Arch::Neo]).unwrap());
        }
    }
    let data = ReportData { sweep: sweep.clone(), ..ReportData::default() };
    let (md, svgs) = render(&data).unwrap();
    signal_rows_come_from_the_neo_points(&md, &svgs, &sweep);
    let lines: Vec<&str> = md.lines().collect();
    let at = lines.iter().position(|l| *l == "| strategy | 1x | 16x |").expect("the speed table");
    let neo: Vec<&str> = lines[at + 2].split('|').map(str::trim).collect();
    assert_eq!(neo[1], "neo", "{}", lines[at + 2]);
    for cell in &neo[2..4] {
        // FPS / worst frame / mean: three fields, the FPS a number.
        let f: Vec<&str> = cell.split(" / ").collect();
        assert_eq!(f.len(), 3, "{cell}");
        assert!(f[0].parse::<f64>().unwrap() > 0.0, "{cell}");
    }
    let hier: Vec<&str> = lines[at + 3].split('|').map(str::trim).collect();
    assert_eq!(hier[1], "hierarchical");
    assert!(hier[2].ends_with(" / exact") && hier[3].ends_with(" / exact"), "{}", lines[at + 3]);
}

/// Section 5: one row per camera speed from the `neo` point's signal summary (samples, tiles
/// with an error, a same / next cell per signal), and the reach-against-error scatter.
fn signal_rows_come_from_the_neo_points(
    md: &str,
    svgs: &[(String, String)],
    sweep: &[neo_sim::suite::PointResult],
) {
    use neo_sim::signals::Signal;
    let lines: Vec<&str> = md.lines().collect();
    let at =
        lines.iter().position(|l| l.starts_with("| speed | tiles (with error) |")).expect("signal table");
    for (k, speed) in [1.0, 16.0].into_iter().enumerate() {
        let r = sweep.iter().find(|r| r.point.strategy == "neo" && r.point.speed == speed).unwrap();
        let s = r.signals.as_ref().expect("the golden raster ran: signals");
        let cells: Vec<&str> = lines[at + 2 + k].split('|').map(str::trim).collect();
        assert_eq!(cells[1], format!("{speed}x"));
        assert_eq!(cells[2], format!("{} ({})", s.samples, s.with_error));
        assert_eq!(cells.len(), 3 + Signal::ALL.len() + 1, "{}", lines[at + 2 + k]);
        for c in &cells[3..3 + Signal::ALL.len()] {
            assert_eq!(c.split(" / ").count(), 2, "{c}");
        }
    }
    let svg = svgs.iter().find(|(n, _)| n == "signals_reach_error.svg").expect("the scatter");
    assert!(svg.1.starts_with("<svg") && svg.1.contains("16x"));
}
