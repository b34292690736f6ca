//! The baselines against each other and against Neo, the work counters, `stats.json` and the
//! `poc.trace` export.

mod pipeline_common;

use neo_golden::pipeline::{
    run_trajectory, ConfigRecord, Formats, PipelineConfig, PipelineError, RunInfo, StatsFile, Strategy,
};
use neo_golden::{source, trajectory};
use pipeline_common::{check_tables, config, run_frames};

fn scene(n: usize) -> neo_golden::scene::Scene {
    source::load_scene(&format!("synthetic:outdoor?gaussians={n}&seed=5"), false).unwrap().0
}

fn orbit(scene: &neo_golden::scene::Scene, spec: &str, frames: usize) -> trajectory::Trajectory {
    trajectory::parse_trajectory(spec, source::robust_bounds(scene), frames).unwrap()
}

fn dram(f: &neo_golden::pipeline::FrameStats) -> u64 {
    f.work.dram_read + f.work.dram_written
}

#[test]
fn periodic_every_frame_and_hierarchical_equal_full() {
    let s = scene(20_000);
    let t = orbit(&s, "orbit:res=256x192,speed=4", 4);
    let images = |st: Strategy| {
        let mut imgs = Vec::new();
        let stats =
            run_frames(&s, &t.frames, &[], PipelineConfig { compare_float: false, ..config(st) }, |p, o| {
                check_tables(p, o);
                imgs.push(o.image.clone());
            });
        (imgs, stats)
    };
    let (full, full_stats) = images(Strategy::Full);
    let (per1, per1_stats) = images(Strategy::Periodic(1));
    let (hier, hier_stats) = images(Strategy::Hierarchical);
    assert_eq!(full, per1);
    assert_eq!(full, hier);
    for ((f, p), h) in full_stats.iter().zip(&per1_stats).zip(&hier_stats) {
        assert_eq!(f.work, p.work, "periodic:1 does exactly what full does");
        assert!(f.from_scratch && h.from_scratch);
        assert_eq!(h.work.entries_sorted, f.work.entries_sorted);
        assert!(h.work.hier_approx_passes > 0 && f.work.hier_approx_passes == 0);
        // Big tables: GSCore's two levels read each entry twice, the merge sort more often.
        if f.tiles.table_len_max > 1024 {
            assert!(dram(h) < dram(f), "hierarchical {} vs full {}", dram(h), dram(f));
        }
    }
}

#[test]
fn background_and_periodic_lag_and_neo_saves_traffic() {
    let s = scene(20_000);
    let t = orbit(&s, "orbit:res=256x192,speed=2", 8);
    let run = |st: Strategy| {
        run_frames(&s, &t.frames, &[], PipelineConfig { compare_float: false, ..config(st) }, check_tables)
    };
    let neo = run(Strategy::Neo);
    let full = run(Strategy::Full);
    let per = run(Strategy::Periodic(4));
    let bg = run(Strategy::Background(3));
    let hier = run(Strategy::Hierarchical);
    // Periodic refreshes at 0 and 4 are exact; in between it is stale.
    for f in &per {
        assert_eq!(f.from_scratch, f.frame % 4 == 0, "frame {}", f.frame);
        if f.from_scratch {
            assert_eq!(f.order.inversions, 0);
        } else {
            assert_eq!(f.work.dps_passes, 0);
            assert_eq!(f.work.writeback, f.tiles.table_entries, "valid bits are written back");
        }
    }
    // Periodic's error grows between refreshes; Neo's DPS keeps it lower.
    assert!(per[3].order.inversions > per[1].order.inversions);
    assert!(neo[3].order.inversions < per[3].order.inversions);
    // Background: the background sorter sorts every frame; the frame's order lags.
    for f in &bg[1..] {
        assert!(f.work.background_entries_sorted > 0);
        assert!(f.order.inversions > 0, "frame {}", f.frame);
        assert_eq!(f.tiles.stale, 0, "entries that left are dropped before the raster");
    }
    // Neo after frame 0: DPS, incoming sort and merge cost less DRAM traffic than sorting from
    // scratch, and much less sorting.
    for ((n, f), h) in neo.iter().zip(&full).zip(&hier).skip(1) {
        assert!(dram(n) < dram(f), "frame {}: neo {} vs full {}", n.frame, dram(n), dram(f));
        assert!(dram(n) < dram(h), "frame {}: neo {} vs hierarchical {}", n.frame, dram(n), dram(h));
        assert!(n.work.entries_sorted * 5 < f.work.entries_sorted);
        assert_eq!(n.work.dps_entries, n.work.merge_in_table, "DPS covers the reused table");
        assert!(n.work.dps_chunks > 0 && n.tiles.dps_chunks == n.work.dps_chunks);
        assert!(n.retention.pooled.unwrap() > 0.9);
    }
}

#[test]
fn stats_json_has_the_fixed_names() {
    let s = scene(5_000);
    let t = orbit(&s, "orbit:res=160x96,cut=3", 5);
    let cfg = config(Strategy::Neo);
    let formats = Formats::artifact(cfg.chunk).unwrap();
    let run = RunInfo {
        scene: "s",
        trajectory: "orbit:cut=3",
        gaussians: s.len(),
        frames: 5,
        cuts: &t.cuts,
        size: (160, 96),
        fitted: false,
    };
    let record = ConfigRecord::new(&run, &cfg, &formats);
    let frames = run_trajectory::<PipelineError>(&s, &t, None, cfg, formats, |_, _| Ok(())).unwrap();
    let doc = StatsFile::new(record, frames);
    let v: serde_json::Value = serde_json::from_str(&serde_json::to_string(&doc).unwrap()).unwrap();
    let frames = v["frames"].as_array().unwrap();
    assert_eq!(frames.len(), 5);
    for (i, f) in frames.iter().enumerate() {
        assert_eq!(f["frame"], i);
        for k in
            ["psnr_vs_exact", "psnr_vs_float", "ssim_vs_exact", "ssim_vs_float", "cut", "dropped_capacity"]
        {
            assert!(f.get(k).is_some(), "missing {k}");
        }
        for k in
            ["displacement_p90", "displacement_p95", "displacement_p99", "displacement_max", "inversions"]
        {
            assert!(f["order"][k].is_u64(), "order.{k}");
        }
        assert!(f["psnr_vs_float"].is_f64());
        assert!(f["work"]["dram_read"].is_u64() && f["timing"]["raster_s"].is_f64());
        assert!(f["tiles"]["pairs"].is_u64() && f["retention"].get("pooled").is_some());
    }
    assert!(frames[0]["psnr_vs_exact"].is_null(), "identical images: null, not infinity");
    assert_eq!(frames[3]["cut"], true);
    assert_eq!(v["config"]["cuts"][0], 3);
    assert_eq!(v["summary"]["recovery"][0]["frames_to_exact"], 0);
}

/// Parses a poc.trace and checks it against the pipeline's state.
#[test]
fn poc_trace_matches_the_tables() {
    let s = scene(5_000);
    let t = orbit(&s, "orbit:res=200x130,speed=8", 3);
    let cfg = PipelineConfig { compare_float: false, ..config(Strategy::Neo) };
    run_frames(&s, &t.frames, &[], cfg, |p, o| {
        let mut buf = Vec::new();
        p.write_trace(&mut buf).unwrap();
        let text = String::from_utf8(buf).unwrap();
        let mut lines = text.lines();
        let head: Vec<usize> = lines.next().unwrap().split(' ').map(|v| v.parse().unwrap()).collect();
        let [gx, gy] = p.grid();
        assert_eq!(head, vec![200, 130, 64, 8, 256, s.len(), (gx * gy) as usize]);
        let mut culled = 0;
        let mut incoming_total = 0;
        for _ in 0..s.len() {
            let v: Vec<usize> = lines.next().unwrap().split(' ').map(|v| v.parse().unwrap()).collect();
            assert!(v[0] <= 1 && v.len() == 2 + v[1]);
            assert!(v[2..].windows(2).all(|w| w[0] < w[1]) && v[2..].iter().all(|&t| t < (gx * gy) as usize));
            culled += v[0];
            incoming_total += v[1];
            if v[0] == 1 {
                assert_eq!(v[1], 0, "a culled Gaussian is incoming nowhere");
            }
        }
        assert_eq!(culled as u64, o.stats.gaussians.culled);
        let mut new_total = 0;
        for (table, bitmaps) in p.tables().zip(p.bitmaps()) {
            let v: Vec<usize> = lines.next().unwrap().split(' ').map(|v| v.parse().unwrap()).collect();
            assert_eq!(v.len(), 3);
            assert_eq!(v[2], table.len());
            assert_eq!(v[0] + v[1], v[2]);
            new_total += v[0];
            for (e, &b) in table.iter().zip(bitmaps) {
                let l: Vec<u64> = lines.next().unwrap().split(' ').map(|v| v.parse().unwrap()).collect();
                assert_eq!(l.len(), 1 + 64);
                assert_eq!(l[0], e.id as u64);
                let bits = l[1..].iter().enumerate().fold(0u64, |acc, (j, &x)| acc | (x << j));
                assert_eq!(bits, b);
                assert_eq!(b != 0, e.valid, "valid bit = cumulative OR of the bitmap");
            }
        }
        assert!(lines.next().is_none());
        // No capacity cut: every incoming Gaussian is a new entry of its tile's table.
        assert_eq!(incoming_total, new_total);
        assert_eq!(
            new_total as u64,
            if o.stats.frame == 0 { o.stats.tiles.pairs } else { o.stats.tiles.incoming }
        );
    });
}

#[test]
fn fitted_formats_run_and_narrow_the_ids() {
    let s = scene(5_000);
    let t = orbit(&s, "orbit:res=160x96,speed=4", 3);
    let cfg = config(Strategy::Neo);
    let f = Formats::fitted(&s, &t.frames, cfg.raster.tile, cfg.chunk).unwrap();
    assert_eq!(f.sort.format().id_bits(), 13, "5000 ids + the reserved one fit 13 bits");
    assert!(matches!(f.key, neo_golden::sort::DepthKeyCodec::Log(_)));
    assert!(f.sort.format().bytes_per_entry() < 6);
    let stats = run_trajectory::<PipelineError>(&s, &t, None, cfg, f, |p, o| {
        check_tables(p, o);
        Ok(())
    })
    .unwrap();
    assert!(stats.iter().all(|f| f.psnr_vs_float.is_some_and(|p| p > 30.0)));
}

#[test]
fn exact_shortcut_only_saves_time() {
    let s = scene(20_000);
    let t = orbit(&s, "orbit:res=256x192,speed=8", 4);
    let exact_images = |shortcut: bool| {
        let mut v = Vec::new();
        let cfg = PipelineConfig { exact_shortcut: shortcut, compare_float: false, ..config(Strategy::Neo) };
        let stats = run_frames(&s, &t.frames, &[], cfg, |_, o| v.push(o.exact_image.clone().unwrap()));
        (v, stats)
    };
    let (with, stats) = exact_images(true);
    let (without, _) = exact_images(false);
    assert_eq!(with, without);
    assert!(stats[1..].iter().all(|f| f.psnr_vs_exact.is_some()), "the orders differ somewhere");
}
