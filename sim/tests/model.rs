//! Properties of the cycle model: accounting, measured timing, scaling, and the behaviours the
//! paper reports (reuse saves DRAM traffic; periodic sorting spikes at refresh frames).

use neo_golden::pipeline::Strategy;
use neo_golden::{shared, source, trajectory};
use neo_sim::config::SimConfig;
use neo_sim::driver::{generate, WorkloadSpec};
use neo_sim::latency::{ChunkMode, Latency};
use neo_sim::run::{simulate, Arch, RunOptions};
use neo_sim::sortcmd::{batch_cycles, conventional_sort};
use neo_sim::traffic::{Dir, Stage};
use neo_sim::workload::{FrameWork, HierTile, TileWork, Workload, WorkloadInfo};

fn latency() -> Latency {
    Latency::from_file(&shared::workspace_root().join("reports/latency.json")).unwrap()
}

/// A workload of one frame whose tiles each sort `n` entries from scratch (no Gaussians to
/// preprocess), on a `tiles x 1` grid of 64-pixel tiles.
fn scratch_workload(tiles: u32, n: u32) -> Workload {
    let tile = TileWork {
        from_scratch: true,
        current: n,
        incoming: n,
        sort_n: n,
        table_len: n,
        raster_entries: n,
        hier: HierTile { entries: n, bin_sorts: n.div_ceil(256), bin_entries: n, ..HierTile::default() },
        routed: vec![n / 4; 64],
        ..TileWork::default()
    };
    Workload {
        info: WorkloadInfo {
            scene: "test".into(),
            trajectory: "none".into(),
            strategy: "full".into(),
            width: 64 * tiles,
            height: 64,
            grid: [tiles, 1],
            tile: 64,
            subtile: 8,
            chunk: 256,
            dps_passes: 1,
            capacity: None,
            raster_window: 1,
            sort_entry_bytes: 6,
            feature_entry_bytes: 31,
            sh_degree: 3,
            gaussian_geometry_bytes: 44,
            gaussian_sh_bytes: 192,
            gaussians: 1000,
            golden_raster: false,
        },
        frames: vec![FrameWork {
            frame: 0,
            from_scratch: true,
            gaussians: 1000,
            visible: 1000,
            processed_ratio: 1.0,
            tiles: vec![tile; tiles as usize],
            ..FrameWork::default()
        }],
        generation_s: 0.0,
    }
}

fn rtl_like() -> SimConfig {
    let mut c = SimConfig::default();
    c.neo.fused_dps_merge = false;
    c
}

/// Sorting time of frame 0 in cycles (1 GHz: 1000 ps per cycle).
fn sort_cycles(cfg: &SimConfig, lat: &Latency, wl: &Workload, ideal: bool) -> f64 {
    let r = simulate(Arch::Neo, cfg, lat, wl, RunOptions { ideal_memory: ideal }).unwrap();
    let f = &r.frames[0];
    (f.sort_done_ms - f.pre_done_ms) * 1e6
}

#[test]
fn a_chunk_sort_takes_exactly_the_measured_cycles_for_every_listed_size() {
    let lat = latency();
    let cfg = rtl_like();
    for p in lat.conventional.iter().filter(|p| p.entries > 0) {
        let wl = scratch_workload(1, p.entries as u32);
        let c = sort_cycles(&cfg, &lat, &wl, true);
        assert!(
            (c - p.cycles as f64).abs() < 1e-6,
            "SORT of {}: model {c} cycles, latency.json {}",
            p.entries,
            p.cycles
        );
    }
    for p in lat.dps.iter().filter(|p| p.entries > 0) {
        assert_eq!(lat.chunk_cycles(ChunkMode::Dps, p.entries), p.cycles);
    }
    // A longer list: chunks and merge passes, each timed from latency.json, back to back.
    let wl = scratch_workload(1, 1000);
    let want = batch_cycles(&conventional_sort(1000, 256), &lat) as f64;
    assert!((sort_cycles(&cfg, &lat, &wl, true) - want).abs() < 1e-6);
}

#[test]
fn changing_latency_json_changes_the_modelled_cycles() {
    let text = std::fs::read_to_string(shared::workspace_root().join("reports/latency.json")).unwrap();
    let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
    for p in v["sort_core"]["conventional"].as_array_mut().unwrap() {
        let c = p["cycles"].as_u64().unwrap();
        p["cycles"] = (c + 100).into();
        let i = p["interval"].as_u64().unwrap();
        p["interval"] = (i + 100).into();
    }
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("latency.json");
    std::fs::write(&path, v.to_string()).unwrap();
    let (base, changed) = (latency(), Latency::from_file(&path).unwrap());
    let cfg = rtl_like();
    // Two chunks of 256 entries and one merge: the first SORT (the fill, its single latency) and
    // the second (back to back, its interval) take 100 cycles more each.
    let wl = scratch_workload(1, 512);
    let d = sort_cycles(&cfg, &changed, &wl, true) - sort_cycles(&cfg, &base, &wl, true);
    assert!((d - 200.0).abs() < 1e-6, "two chunks, +100 cycles each: {d}");
    // Through the DRAM model too, the frame takes longer.
    let slow = simulate(Arch::Neo, &SimConfig::default(), &changed, &wl, RunOptions::default()).unwrap();
    let fast = simulate(Arch::Neo, &SimConfig::default(), &base, &wl, RunOptions::default()).unwrap();
    assert!(slow.frames[0].sort_done_ms > fast.frames[0].sort_done_ms);
}

#[test]
fn identical_independent_tiles_scale_with_the_core_count() {
    let lat = latency();
    let wl = scratch_workload(32, 2000);
    let mut t = Vec::new();
    for cores in [1u32, 2, 4, 8, 16] {
        let mut cfg = rtl_like();
        cfg.engine.sort_cores = cores as usize;
        t.push((cores, sort_cycles(&cfg, &lat, &wl, true)));
    }
    let one = t[0].1;
    for &(cores, c) in &t {
        // 32 tiles over `cores` cores: 32 / cores tiles in sequence each (to within the line
        // alignment of each core's scratch buffers, which can add a line to a read).
        let want = one / cores as f64;
        assert!((c - want).abs() / want < 2e-3, "{cores} cores: {c} cycles, expected {want}");
    }
    // With the DRAM model more cores help, never more than linearly, and sublinearly once
    // memory binds; more interleaved streams cost some row hits but never a collapse.
    let real: Vec<f64> = [1u32, 2, 4, 8, 16]
        .iter()
        .map(|&cores| {
            let mut cfg = SimConfig::default();
            cfg.engine.sort_cores = cores as usize;
            sort_cycles(&cfg, &lat, &wl, false)
        })
        .collect();
    assert!(real[1] < real[0] && real[2] < real[1], "1, 2, 4 cores: {real:?}");
    assert!(real[0] / real[2] > 2.0, "4 cores at least twice as fast as one: {real:?}");
    assert!(real.windows(2).all(|w| w[1] < 1.15 * w[0]), "no collapse with more cores: {real:?}");
    assert!(real[0] / real[4] < 12.0, "16 cores are memory-bound, well short of 16x: {real:?}");
    for (k, &c) in real.iter().enumerate() {
        assert!(real[0] / c <= (1u32 << k) as f64 + 1e-9, "{} cores faster than linear: {real:?}", 1 << k);
    }
}

/// Each frame's named stage bytes add up to its total, and over the frames to the run's stage
/// bytes; each frame's engine busy time adds up to the run's utilisation.
fn per_frame_records_add_up(r: &neo_sim::run::ArchResult) {
    for f in &r.frames {
        assert_eq!(f.stages.len(), Stage::ALL.len(), "every stage named");
        let sum: u64 = f.stages.iter().map(|s| s.read_bytes + s.write_bytes).sum();
        assert_eq!(sum, f.dram_bytes, "frame {}: stage bytes add up", f.frame);
    }
    for (k, s) in Stage::ALL.iter().enumerate() {
        assert!(r.frames.iter().all(|f| f.stages[k].stage == s.name()));
        let reads: u64 = r.frames.iter().map(|f| f.stages[k].read_bytes).sum();
        let writes: u64 = r.frames.iter().map(|f| f.stages[k].write_bytes).sum();
        assert_eq!((reads, writes), (r.traffic.bytes(*s, Dir::Read), r.traffic.bytes(*s, Dir::Write)), "{s}");
    }
    let u = r.utilisation.expect("accelerator");
    let busy = |get: fn(&neo_sim::run::EngineBusy) -> f64| -> f64 {
        r.frames.iter().map(|f| get(f.busy.as_ref().expect("busy"))).sum()
    };
    let sort = busy(|b| b.sort_ms);
    assert!(sort > 0.0, "the sorting cores worked");
    let pre = busy(|b| b.preprocess_ms);
    // One preprocessing engine: its busy time over the run is its utilisation times the run.
    let want = u.preprocess * r.total_ms;
    assert!((pre - want).abs() <= 1e-6 * r.total_ms.max(1.0), "preprocess busy {pre} ms vs {want} ms");
    assert!(busy(|b| b.raster_ms) > 0.0, "the raster cores worked");
}

#[test]
fn every_request_is_accounted_by_stage_and_frame() {
    let lat = latency();
    let (scene, _) = source::load_scene("synthetic:outdoor?gaussians=20k&seed=2", false).unwrap();
    let traj = trajectory::parse_trajectory("orbit:speed=4", source::robust_bounds(&scene), 4)
        .unwrap()
        .with_resolution(256, 192);
    for strategy in [Strategy::Neo, Strategy::Background(2)] {
        let wl =
            generate(&scene, &traj.frames, &traj.cuts, &WorkloadSpec::new("s", "orbit", strategy), |_| {})
                .unwrap();
        for arch in [Arch::Neo, Arch::Gscore(4)] {
            let r = simulate(arch, &SimConfig::default(), &lat, &wl, RunOptions::default()).unwrap();
            let d = r.dram.unwrap();
            let t = &r.traffic;
            assert_eq!(
                t.total_requests(),
                d.reads + d.writes,
                "{strategy} {}: every request reached the DRAM",
                r.arch
            );
            assert_eq!(t.total_bytes(), (d.reads + d.writes) * 64, "bytes are whole 64-byte requests");
            let by_stage: u64 = Stage::ALL.iter().map(|&s| t.stage_bytes(s)).sum();
            assert_eq!(by_stage, t.total_bytes());
            assert_eq!(t.dir_bytes(Dir::Read) + t.dir_bytes(Dir::Write), t.total_bytes());
            let per_frame: u64 = r.frames.iter().map(|f| f.dram_bytes).sum();
            assert_eq!(per_frame, t.total_bytes(), "per-frame attribution sums to the total");
            per_frame_records_add_up(&r);
            // The sorting stage moves at least the golden model's entries (whole lines round up).
            if arch == Arch::Neo && strategy == Strategy::Neo {
                let g: u64 = wl.frames.iter().map(|f| f.golden.sort_read + f.golden.sort_written).sum();
                let model = t.stage_bytes(Stage::SortTable) + t.bytes(Stage::IncomingList, Dir::Read);
                assert!(model >= g * 6, "sorting bytes {model} below the golden {}", g * 6);
                assert!(
                    (model as f64) < 1.5 * (g * 6) as f64 + 64.0 * 2000.0,
                    "sorting bytes {model} vs golden {}",
                    g * 6
                );
            }
        }
    }
}

#[test]
fn neo_moves_less_dram_than_gscore_and_periodic_spikes_at_refreshes() {
    let lat = latency();
    let cfg = SimConfig::default();
    let (scene, _) = source::load_scene("synthetic:outdoor?gaussians=60k&seed=4", false).unwrap();
    let traj = trajectory::parse_trajectory("orbit:speed=2", source::robust_bounds(&scene), 12)
        .unwrap()
        .with_resolution(512, 320);
    let neo =
        generate(&scene, &traj.frames, &traj.cuts, &WorkloadSpec::new("s", "orbit", Strategy::Neo), |_| {})
            .unwrap();
    let n = simulate(Arch::Neo, &cfg, &lat, &neo, RunOptions::default()).unwrap();
    let g = simulate(Arch::Gscore(16), &cfg, &lat, &neo, RunOptions::default()).unwrap();
    assert!(
        n.traffic.sorting_bytes() * 2 < g.traffic.sorting_bytes(),
        "sorting: neo {} vs gscore {}",
        n.traffic.sorting_bytes(),
        g.traffic.sorting_bytes()
    );
    assert!(n.traffic.total_bytes() < g.traffic.total_bytes());

    let per = generate(
        &scene,
        &traj.frames,
        &traj.cuts,
        &WorkloadSpec::new("s", "orbit", Strategy::Periodic(4)),
        |_| {},
    )
    .unwrap();
    let p = simulate(Arch::Neo, &cfg, &lat, &per, RunOptions::default()).unwrap();
    let sort_time = |f: &neo_sim::run::FrameResult| f.sort_done_ms - f.pre_done_ms;
    let refresh: Vec<f64> =
        p.frames.iter().filter(|f| f.frame > 0 && f.frame % 4 == 0).map(sort_time).collect();
    let between: Vec<f64> = p.frames.iter().filter(|f| f.frame % 4 != 0).map(sort_time).collect();
    let max_between = between.iter().copied().fold(0.0, f64::max);
    // The refresh frames sort from scratch: more than twice the sorting traffic, and a longer
    // sorting phase (between refreshes the phase also waits for the previous frame's raster,
    // whose write-back it reuses, so its length is not only sorting).
    let bytes = |pred: &dyn Fn(usize) -> bool| -> Vec<u64> {
        p.frames.iter().filter(|f| pred(f.frame)).map(|f| f.sort_bytes).collect()
    };
    let refresh_bytes = bytes(&|f| f > 0 && f % 4 == 0);
    let between_bytes = bytes(&|f| f % 4 != 0).into_iter().max().unwrap();
    assert!(
        refresh_bytes.iter().all(|&b| b > 2 * between_bytes),
        "refresh sorting traffic {refresh_bytes:?} vs at most {between_bytes} between refreshes"
    );
    for r in &refresh {
        assert!(*r > max_between, "refresh sorting {r} ms vs at most {max_between} ms between refreshes");
    }
    let lat_refresh: Vec<f64> =
        p.frames.iter().filter(|f| f.frame > 0 && f.frame % 4 == 0).map(|f| f.latency_ms).collect();
    let lat_between =
        p.frames.iter().filter(|f| f.frame % 4 != 0 && f.frame > 1).map(|f| f.latency_ms).fold(0.0, f64::max);
    assert!(
        lat_refresh.iter().all(|&l| l > lat_between),
        "latency spikes at refresh frames: {lat_refresh:?} vs {lat_between}"
    );
}

/// The duplication unit's incoming detection (golden `hwpre::duplicate`, the RTL's design),
/// charged to its own stage: on Neo, a frame that reuses its tables reads the previous feature
/// word of each of the `P` Gaussians visible now, one 32-byte transfer each, which moves a
/// whole 64-byte line; a frame sorted from scratch (frame 0, the cut) reads nothing, and no
/// frame writes anything for it (the feature words are the feature table's). The same work
/// labelled `full` (no table reuse) or run on GSCore charges nothing, and every other stage of
/// every frame moves exactly the same bytes.
#[test]
fn incoming_detection_reads_the_previous_word_of_each_visible_gaussian() {
    let lat = latency();
    let (scene, _) = source::load_scene("synthetic:outdoor?gaussians=20k&seed=2", false).unwrap();
    let traj = trajectory::parse_trajectory("orbit:speed=4,cut=2", source::robust_bounds(&scene), 4)
        .unwrap()
        .with_resolution(256, 192);
    let wl =
        generate(&scene, &traj.frames, &traj.cuts, &WorkloadSpec::new("s", "orbit", Strategy::Neo), |_| {})
            .unwrap();
    let scratch: Vec<bool> = wl.frames.iter().map(|f| f.from_scratch).collect();
    assert_eq!(scratch, [true, false, true, false], "frame 0 and the cut at 2 from scratch");
    let mut unlabelled = wl.clone();
    unlabelled.info.strategy = "full".into();
    let cfg = SimConfig::default();
    let run = |arch, w: &Workload| simulate(arch, &cfg, &lat, w, RunOptions::default()).unwrap();
    let (neo, full, gscore) = (run(Arch::Neo, &wl), run(Arch::Neo, &unlabelled), run(Arch::Gscore(4), &wl));
    let det = Stage::ALL.iter().position(|&s| s == Stage::IncomingDetection).unwrap();
    for (k, fw) in wl.frames.iter().enumerate() {
        let reads = if fw.from_scratch { 0 } else { 64 * fw.visible };
        assert!(fw.visible > 1000, "frame {k}: {} visible", fw.visible);
        let st = &neo.frames[k].stages[det];
        assert_eq!((st.read_bytes, st.write_bytes), (reads, 0), "frame {k}");
        for other in [&full, &gscore] {
            let st = &other.frames[k].stages[det];
            assert_eq!((st.read_bytes, st.write_bytes), (0, 0), "{} frame {k}", other.arch);
        }
        for (s, (a, b)) in neo.frames[k].stages.iter().zip(&full.frames[k].stages).enumerate() {
            if s != det {
                assert_eq!(a, b, "frame {k}: only the incoming detection moves");
            }
        }
        assert_eq!(neo.frames[k].dram_bytes - full.frames[k].dram_bytes, reads, "frame {k}");
    }
}

/// Neo-S (the paper's Fig. 18: GSCore with Neo's Sorting Engine, without its Rasterization
/// Engine) reuses the tables like Neo, so it sorts far fewer bytes than GSCore; but without the
/// raster core's write-back, a separate pass per tile reads the table, gathers every entry's
/// feature word (a whole line each) and writes the table back.
#[test]
fn neo_s_sorts_like_neo_and_pays_a_separate_update_pass() {
    let lat = latency();
    let cfg = SimConfig::default();
    let (scene, _) = source::load_scene("synthetic:outdoor?gaussians=20k&seed=2", false).unwrap();
    let traj = trajectory::parse_trajectory("orbit:speed=4", source::robust_bounds(&scene), 4)
        .unwrap()
        .with_resolution(256, 192);
    let spec = WorkloadSpec::new("s", "orbit", Strategy::Neo);
    let wl = generate(&scene, &traj.frames, &traj.cuts, &spec, |_| {}).unwrap();
    let run = |arch| simulate(arch, &cfg, &lat, &wl, RunOptions::default()).unwrap();
    let (neo, neos, gscore) = (run(Arch::Neo), run(Arch::NeoS(16)), run(Arch::Gscore(16)));
    assert_eq!(neos.arch, "neos16");
    per_frame_records_add_up(&neos);
    // Frame 0 sorts from scratch on both; the others reuse the tables on Neo-S.
    for (s, g) in neos.frames.iter().zip(&gscore.frames).skip(1) {
        assert!(
            s.sort_bytes * 2 < g.sort_bytes,
            "frame {}: sorting neo-s {} vs gscore {}",
            s.frame,
            s.sort_bytes,
            g.sort_bytes
        );
    }
    let entries: u64 = wl.frames.iter().flat_map(|f| &f.tiles).map(|t| t.table_len as u64).sum();
    let eb = (wl.info.sort_entry_bytes + cfg.gscore.bitmap_bytes) as u64;
    let (reads, writes) = (
        neos.traffic.bytes(Stage::DepthWriteback, Dir::Read),
        neos.traffic.bytes(Stage::DepthWriteback, Dir::Write),
    );
    assert!(reads >= entries * (64 + eb), "update reads {reads} B for {entries} entries");
    assert!(writes >= entries * eb, "update writes {writes} B for {entries} entries");
    assert!(writes > neo.traffic.bytes(Stage::DepthWriteback, Dir::Write), "more than Neo's write-back");
    assert_eq!(gscore.traffic.stage_bytes(Stage::DepthWriteback), 0);
    // The pass sits between a tile's raster and its next sort: Neo-S is slower than Neo.
    assert!(neos.fps > 0.0 && neos.fps < neo.fps, "neo-s {} FPS vs neo {}", neos.fps, neo.fps);
}
