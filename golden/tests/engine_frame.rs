//! The engine's memory-level reference (`execute_frame`) against the golden pipeline, frame after
//! frame, through the host session: every tile's result, next table (after the write-back) and
//! pixels, the registers and the golden counters, for every whole-frame case.

use neo_golden::engine::{
    execute_frame, execute_frame_traced, CaseScene, Counter, EngineCase, EngineConfig, EngineSession,
    HostMode, Memory, Place, TileCmd, TileDescriptor,
};
use neo_golden::scene::Scene;
use neo_golden::shared::shared_file_for_test;
use neo_golden::sort::SortMode;
use neo_golden::source::load_scene;

/// What a run saw, for the case-specific assertions.
#[derive(Debug, Default)]
struct Seen {
    frames: usize,
    tiles: usize,
    from_scratch: Vec<bool>,
    overflows: Vec<u32>,
    empty_tiles: usize,
    partial_tiles: usize,
    reused_entries: u64,
    /// Reuse tiles by their descriptor's DPS passes (index = passes).
    passes: [usize; 16],
    /// Tiles sorted from scratch in frames that reuse the others' tables (re-sorted tiles).
    resorted: usize,
    /// Scene mode: incoming entries the engine listed, and its preprocessing reads.
    incoming: u64,
    pre_read: u64,
    /// Summed over reuse frames' results: the MERGE_DELETEs' boundary inversions and the
    /// write-backs' reach (the disorder counters).
    inversions: u64,
    reach: u64,
    /// Reuse tiles by the DPS passes the engine planned itself (`ADAPT_CTRL`), and those it
    /// planned in the wide chunk.
    engine_passes: [usize; 16],
    engine_wide: usize,
    /// Reuse tiles whose descriptor asks for the wide chunk, and their DPS commands longer
    /// than a chunk.
    wide: usize,
    wide_cmds: usize,
}

/// A DPS command over more than a chunk: one of the wide chunk.
fn longer_than_a_chunk(cfg: &EngineConfig, c: &TileCmd) -> bool {
    c.mode == SortMode::Dps && c.len_a > cfg.chunk as u64
}

/// Runs every frame of `session` through `execute_frame` and checks it against the plan.
fn run(session: &mut EngineSession, cfg: &EngineConfig) -> Seen {
    let mut mem = Memory::new();
    let mut seen = Seen { tiles: session.tiles(), ..Seen::default() };
    while let Some(plan) = session.next_frame(&mut mem).expect("host frame") {
        let (out, trace) = execute_frame_traced(cfg, &plan.regs, &mut mem).expect("reference frame");
        if let Some(m) = plan.expected.compare(&mem) {
            panic!("frame {}: {m}", plan.frame);
        }
        if let Some(m) = plan.expected.compare_outcome(&out) {
            panic!("frame {}: {m}", plan.frame);
        }
        if plan.regs.adapt.enabled() {
            for (d, t) in plan.expected.descriptors.iter().zip(&trace.tiles) {
                if !d.from_scratch && d.prev_len > 0 {
                    seen.engine_passes[t.plan.dps_passes()] += 1;
                    seen.engine_wide += t.plan.commands().any(|c| longer_than_a_chunk(cfg, c)) as usize;
                }
            }
        }
        assert_eq!(out.results, plan.expected.outcome.results, "frame {}", plan.frame);
        if !plan.from_scratch {
            seen.inversions += out.results.iter().map(|r| r.merge_inversions as u64).sum::<u64>();
            seen.reach += out.results.iter().map(|r| r.wb_reach as u64).sum::<u64>();
        }
        if let Some(pre) = &plan.expected.pre {
            seen.incoming += pre.lists.iter().map(|l| l.len() as u64).sum::<u64>();
            seen.pre_read += out.counters.get(Counter::RdPre);
            assert!(out.counters.get(Counter::WrPre) > 0, "frame {}: the engine wrote", plan.frame);
        }
        let (w, h, tile) = (plan.regs.width, plan.regs.height, cfg.raster_config().tile);
        for d in &plan.expected.descriptors {
            let TileDescriptor { tile_x, tile_y, .. } = *d;
            seen.empty_tiles += (d.prev_len == 0 && d.list_len == 0) as usize;
            let full = (tile_x as u32 + 1) * tile <= w && (tile_y as u32 + 1) * tile <= h;
            seen.partial_tiles += !full as usize;
            seen.reused_entries += if d.from_scratch { 0 } else { d.prev_len as u64 };
            if !d.from_scratch && d.prev_len > 0 {
                seen.passes[d.dps_passes as usize] += 1;
            }
            seen.resorted += (d.from_scratch && !plan.from_scratch) as usize;
            seen.wide += (!d.from_scratch && d.prev_len > 0 && d.dps_wide) as usize;
        }
        for t in &trace.tiles {
            seen.wide_cmds += t.plan.commands().filter(|c| longer_than_a_chunk(cfg, c)).count();
        }
        if std::env::var_os("ENGINE_DEBUG").is_some() {
            let v: Vec<u64> = plan.expected.descriptors.iter().map(|d| d.entries_in()).collect();
            eprintln!("frame {} entries_in {v:?}", plan.frame);
        }
        seen.frames += 1;
        seen.from_scratch.push(plan.from_scratch);
        seen.overflows.push(out.overflows);
    }
    seen
}

fn case(
    scene: &Scene,
    how: &CaseScene,
    c: EngineCase,
    frames: usize,
    res: [u32; 2],
    base: &EngineConfig,
    mode: HostMode,
) -> Seen {
    let (traj, cfg) = c.setup(scene, how, frames, res, base).expect("case setup");
    let mut s = EngineSession::with_options(scene, traj, &cfg, c.options(mode)).expect("session");
    let seen = run(&mut s, &cfg);
    assert_eq!(seen.frames, frames, "{} ({mode:?})", c.name());
    if mode == HostMode::Scene {
        assert!(seen.incoming > 0 && seen.pre_read > 0, "{}: the engine preprocessed: {seen:?}", c.name());
    }
    check_case(c, &seen, &cfg);
    seen
}

/// What each case is for actually happens.
fn check_case(c: EngineCase, s: &Seen, cfg: &EngineConfig) {
    let name = c.name();
    assert!(s.from_scratch[0], "{name}: frame 0 from scratch");
    match c {
        EngineCase::Cut => assert_eq!(s.from_scratch, [true, true, false], "{name}"),
        EngineCase::Overflow => {
            let first = s.overflows[0];
            assert!(first > 0 && (first as usize) < s.tiles, "{name}: {first} of {} tiles overflow", s.tiles);
            assert!(s.from_scratch[1], "{name}: the frame after an overflow is from scratch");
        }
        EngineCase::EdgeTiles => {
            assert!(s.partial_tiles > 0 && s.empty_tiles > 0, "{name}: {s:?}");
        }
        EngineCase::ManyCores => assert!(s.tiles < cfg.sort_cores && s.tiles < cfg.raster_cores, "{name}"),
        EngineCase::Turn => {
            assert!(!s.from_scratch[1], "{name}: frame 1 reuses the tables: {s:?}");
            assert!(s.reach > 0, "{name}: a turn leaves disorder: {s:?}");
        }
        EngineCase::Adaptive => {
            assert!(s.from_scratch[1..].iter().all(|f| !f), "{name}: reuse after frame 0: {s:?}");
            let more = s.passes[2..].iter().sum::<usize>();
            assert!(s.passes[1] > 0 && more > 0, "{name}: tiles with one and with more DPS passes: {s:?}");
            assert_eq!(s.resorted, 0, "{name}: no re-sort without resort=1");
            assert!(s.inversions > 0 && s.reach > 0, "{name}: fast motion leaves disorder: {s:?}");
        }
        EngineCase::AdaptiveEngine => {
            assert!(s.from_scratch[1..].iter().all(|f| !f), "{name}: reuse after frame 0: {s:?}");
            // The host wrote no passes into the reuse descriptors: the engine planned them.
            assert!(s.passes[0] > 0 && s.passes[1..].iter().sum::<usize>() == 0, "{name}: {s:?}");
            assert!(
                s.engine_passes[1] > 0 && s.engine_passes[2..].iter().sum::<usize>() > 0,
                "{name}: {s:?}"
            );
        }
        EngineCase::Window => {
            assert!(s.from_scratch[1..].iter().all(|f| !f), "{name}: reuse after frame 0: {s:?}");
            assert!(
                s.passes[0] > 0 && s.passes[1..].iter().sum::<usize>() == 0,
                "{name}: the engine plans: {s:?}"
            );
            assert!(s.engine_passes[1] > 0, "{name}: {s:?}");
            assert!(s.reused_entries > 0 && s.overflows.iter().all(|&o| o == 0), "{name}: {s:?}");
        }
        EngineCase::AdaptiveEngineWide => {
            assert!(s.from_scratch[1..].iter().all(|f| !f), "{name}: reuse after frame 0: {s:?}");
            assert!(s.passes[0] > 0 && s.wide == 0, "{name}: the host wrote no plan: {s:?}");
            assert!(s.engine_wide > 0 && s.engine_passes[1] > s.engine_wide, "{name}: {s:?}");
        }
        EngineCase::AdaptiveWide => {
            assert!(s.from_scratch[1..].iter().all(|f| !f), "{name}: reuse after frame 0: {s:?}");
            assert!(s.wide > 0 && s.wide_cmds > 0, "{name}: DPS in wide chunks: {s:?}");
            assert!(s.passes[1] > s.wide, "{name}: and in chunks: {s:?}");
        }
        EngineCase::AdaptiveResort => {
            assert!(s.from_scratch[1..].iter().all(|f| !f), "{name}: reuse after frame 0: {s:?}");
            assert!(s.resorted > 0, "{name}: some tiles re-sorted: {s:?}");
        }
        _ => {
            assert_eq!(
                s.passes[2..].iter().sum::<usize>() + s.passes[0],
                0,
                "{name}: Neo's single pass: {s:?}"
            );
            assert!(s.from_scratch[1..].iter().all(|f| !f), "{name}: reuse after frame 0: {s:?}");
            assert!(s.reused_entries > 0, "{name}: tables reused");
            assert!(s.reach > 0, "{name}: the keys moved under the reused order: {s:?}");
            assert!(s.overflows.iter().all(|&o| o == 0), "{name}: no overflow");
        }
    }
}

/// The `window` case's reorder window is at work: the same trajectory, strategy and planner on
/// the same engine without the window writes back tables further out of the current order (the
/// write-back's reach, summed over the reuse frames, is larger), and the reference matches the
/// pipeline in both.
#[test]
fn the_window_case_writes_back_better_ordered_tables() {
    let (scene, _) = load_scene(CaseScene::SYNTHETIC, false).expect("synthetic scene");
    let how = CaseScene::synthetic();
    let c = EngineCase::Window;
    let (traj, cfg) = c.setup(&scene, &how, 3, [128, 128], &small_config()).expect("case setup");
    assert_eq!(cfg.raster_window, neo_golden::engine::WINDOW_CASE);
    let reach = |cfg: &EngineConfig| {
        let mut s = EngineSession::with_options(&scene, traj.clone(), cfg, c.options(HostMode::Lists))
            .expect("session");
        run(&mut s, cfg).reach
    };
    let (with, without) = (reach(&cfg), reach(&EngineConfig { raster_window: 1, ..cfg.clone() }));
    println!("window case: write-back reach {with} with the window, {without} without");
    assert!(with < without, "reach with the window {with}, without {without}");
}

/// A small CI engine: 2 sorting cores, 2 raster cores, chunk 256.
fn small_config() -> EngineConfig {
    EngineConfig { sort_cores: 2, raster_cores: 2, ..EngineConfig::default() }
}

#[test]
fn reference_matches_pipeline_on_every_case_synthetic() {
    let (scene, _) = load_scene(CaseScene::SYNTHETIC, false).expect("synthetic scene");
    let how = CaseScene::synthetic();
    let base = small_config();
    for c in EngineCase::ALL {
        case(&scene, &how, c, 3, [128, 128], &base, HostMode::Lists);
    }
}

/// Scene mode: the reference preprocesses the baked scene from memory (feature words, incoming
/// lists and their lengths, `RD_PRE` / `WR_PRE`) and must leave what the pipeline computed, on
/// every case (reuse frames, a cut, an overflow, partial tiles) and with 1, 2 and 4 lanes.
#[test]
fn reference_preprocessing_matches_pipeline_on_every_case_synthetic() {
    let (scene, _) = load_scene(CaseScene::SYNTHETIC, false).expect("synthetic scene");
    let how = CaseScene::synthetic();
    for (k, c) in EngineCase::ALL.into_iter().enumerate() {
        let base = EngineConfig { pre_units: [1, 2, 4][k % 3], ..small_config() };
        if c == EngineCase::AdaptiveResort {
            // The engine's lists hold the incoming Gaussians only: a re-sorted tile needs its
            // whole list, which only the host writes.
            let (traj, cfg) = c.setup(&scene, &how, 3, [128, 128], &base).expect("case setup");
            let e = EngineSession::with_strategy(&scene, traj, &cfg, HostMode::Scene, c.strategy()).err();
            assert!(e.expect("scene mode refuses re-sorts").to_string().contains("lists mode only"));
            continue;
        }
        case(&scene, &how, c, 3, [128, 128], &base, HostMode::Scene);
    }
}

/// Scene mode with binary16 SH records (`PRE_SH_HALF`): at every SH degree (degrees 0 and 2 have
/// padded records), the reference reads the packed records and leaves what the pipeline computed
/// with `hw:f16` preprocessing; the records are the f32 ones' size halved, rounded up to words.
#[test]
fn reference_preprocessing_reads_half_sh_records_at_every_degree() {
    use neo_golden::engine::{sh_record_words, SessionOptions, PRE_SH_HALF};
    use neo_golden::hwpre::ShPrecision;
    let how = CaseScene::synthetic();
    for degree in 0..=3u8 {
        let spec = format!("synthetic:blobs?gaussians=3000&seed=5&sh={degree}");
        let (scene, _) = load_scene(&spec, false).expect("synthetic scene");
        let c = [EngineCase::Orbit, EngineCase::Cut][degree as usize % 2];
        let base = EngineConfig { pre_units: 2, ..small_config() };
        let (traj, cfg) = c.setup(&scene, &how, 3, [128, 128], &base).expect("case setup");
        let opts = SessionOptions { sh: ShPrecision::F16, ..c.options(HostMode::Scene) };
        let mut s = EngineSession::with_options(&scene, traj, &cfg, opts).expect("session");
        let mut mem = Memory::new();
        let mut frames = 0;
        while let Some(plan) = s.next_frame(&mut mem).expect("host frame") {
            assert_ne!(plan.regs.pre.ctrl & PRE_SH_HALF, 0, "degree {degree}: the host says half records");
            let out = execute_frame(&cfg, &plan.regs, &mut mem).expect("reference frame");
            if let Some(m) = plan.expected.compare(&mem) {
                panic!("degree {degree}, frame {}: {m}", plan.frame);
            }
            if let Some(m) = plan.expected.compare_outcome(&out) {
                panic!("degree {degree}, frame {}: {m}", plan.frame);
            }
            frames += 1;
        }
        assert_eq!(frames, 3);
        let (w16, w32) =
            (sh_record_words(degree, ShPrecision::F16), sh_record_words(degree, ShPrecision::F32));
        assert_eq!(w16, w32.div_ceil(2), "degree {degree}");
    }
}

/// The binary16 record packing: two coefficients a word, the even one low, the odd count padded.
#[test]
fn half_sh_records_pack_two_coefficients_a_word() {
    use neo_golden::engine::pre::{pack_sh_record, unpack_sh_record};
    use neo_golden::hwpre::ShPrecision;
    let coeffs: Vec<u32> = (0..27).map(|k| 0x3c00 + k).collect();
    let words = pack_sh_record(&coeffs, ShPrecision::F16);
    assert_eq!(words.len(), 14);
    assert_eq!(words[0], 0x3c01_3c00);
    assert_eq!(words[13], 0x3c1a, "the last word's high half is padding");
    assert_eq!(unpack_sh_record(&words, 27, ShPrecision::F16), coeffs);
    assert_eq!(unpack_sh_record(&pack_sh_record(&coeffs, ShPrecision::F32), 27, ShPrecision::F32), coeffs);
}

/// An engine without a Preprocessing Engine (`pre_units` 0): lists mode runs as on any engine,
/// with `PRE_CTRL.enable` set (ignored: no preprocessing traffic); scene mode is refused.
#[test]
fn an_engine_without_preprocessing_ignores_pre_ctrl_and_refuses_scene_mode() {
    let (scene, _) = load_scene(CaseScene::SYNTHETIC, false).expect("synthetic scene");
    let how = CaseScene::synthetic();
    let base = EngineConfig { pre_units: 0, ..small_config() };
    assert_eq!(base.memory_clients(), 1 + 2 + 2, "no preprocessing managers");
    let (traj, cfg) = EngineCase::Orbit.setup(&scene, &how, 2, [128, 128], &base).expect("case setup");
    let mut s = EngineSession::with_mode(&scene, traj.clone(), &cfg, HostMode::Lists).expect("session");
    let mut mem = Memory::new();
    while let Some(mut plan) = s.next_frame(&mut mem).expect("host frame") {
        plan.regs.pre.ctrl = neo_golden::engine::PRE_ENABLE;
        let out = execute_frame(&cfg, &plan.regs, &mut mem).expect("reference frame");
        if let Some(m) = plan.expected.compare(&mem) {
            panic!("frame {}: {m}", plan.frame);
        }
        assert_eq!(out.counters.get(Counter::RdPre) + out.counters.get(Counter::WrPre), 0);
        assert_eq!(out.results, plan.expected.outcome.results, "frame {}", plan.frame);
    }
    let e = EngineSession::with_mode(&scene, traj, &cfg, HostMode::Scene).err().expect("scene mode refused");
    assert!(e.to_string().contains("pre_units 0"), "{e}");
}

#[test]
fn reference_matches_pipeline_on_biker() {
    let Some(path) = shared_file_for_test("reference_matches_pipeline_on_biker", "scenes/biker.ply") else {
        return;
    };
    let (scene, _) = load_scene(path.to_str().expect("utf-8 path"), false).expect("biker");
    let how = CaseScene::biker();
    for c in EngineCase::ALL {
        case(&scene, &how, c, 3, [256, 256], &small_config(), HostMode::Lists);
        if c != EngineCase::AdaptiveResort {
            case(&scene, &how, c, 3, [256, 256], &small_config(), HostMode::Scene);
        }
    }
}

/// The checker names a corrupted word (a table entry's key, a pixel, a counter).
#[test]
fn compare_names_the_first_corruption() {
    let (scene, _) = load_scene("synthetic:outdoor?gaussians=5000&seed=3", false).expect("synthetic scene");
    let cfg = small_config();
    let mut s =
        EngineCase::Orbit.session(&scene, &CaseScene::synthetic(), 1, [128, 64], &cfg).expect("session");
    let mut mem = Memory::new();
    let plan = s.next_frame(&mut mem).expect("frame").expect("one frame");
    let out = execute_frame(&cfg, &plan.regs, &mut mem).expect("frame");
    assert_eq!(plan.expected.compare(&mem), None);
    let (t, _) = plan.expected.tables.iter().enumerate().find(|(_, t)| t.len() > 3).expect("a busy tile");
    let addr = 8 * (plan.expected.descriptors[t].next as u64 + 3);
    let mut bad = mem.clone();
    bad.write_u64(addr, bad.read_u64(addr) ^ (1 << 40));
    let m = bad.clone();
    let m = plan.expected.compare(&m).expect("a mismatch");
    assert_eq!((m.tile, m.place, m.field, m.addr), (Some(t as u64), Place::Entry(3), "key", addr));
    assert!(m.to_string().contains("table[3]"), "{m}");
    let px = plan.regs.fb_base + 4 * (4096 * t as u64 + 65);
    let mut bad = mem.clone();
    bad.write_u32(px, bad.read_u32(px) ^ 0x0100_0000);
    let m = plan.expected.compare(&bad).expect("a mismatch");
    assert_eq!((m.place, m.field), (Place::Pixel(1, 1), "word"));
    let ra = plan.regs.result_base + 16 * t as u64;
    for (addr, bit, field) in [(ra, 41, "merge_inversions"), (ra + 8, 3, "wb_len"), (ra + 8, 35, "wb_reach")]
    {
        let mut bad = mem.clone();
        bad.write_u64(addr, bad.read_u64(addr) ^ (1 << bit));
        let m = plan.expected.compare(&bad).expect("a result mismatch");
        assert_eq!((m.tile, m.place, m.field), (Some(t as u64), Place::Result, field));
    }
    let mut wrong = out.clone();
    wrong.counters.0[11] += 32;
    let m = plan.expected.compare_outcome(&wrong).expect("a counter mismatch");
    assert_eq!(m.field, "RD_FEAT");
}

/// Scene mode: the checker accepts a list in another order and names a corrupted feature word,
/// list entry, zero slot, `list_len` and preprocessing counter.
#[test]
fn compare_names_preprocessing_corruption() {
    let (scene, _) = load_scene("synthetic:outdoor?gaussians=5000&seed=3", false).expect("synthetic scene");
    let cfg = small_config();
    let (traj, cfg) =
        EngineCase::Orbit.setup(&scene, &CaseScene::synthetic(), 2, [128, 64], &cfg).expect("case setup");
    let mut s = EngineSession::from_scene(&scene, traj, &cfg).expect("session");
    let mut mem = Memory::new();
    let mut last = None;
    while let Some(plan) = s.next_frame(&mut mem).expect("frame") {
        let out = execute_frame(&cfg, &plan.regs, &mut mem).expect("frame");
        if let Some(m) = plan.expected.compare(&mem) {
            panic!("frame {}: {m}", plan.frame);
        }
        last = Some((plan, out));
    }
    let (plan, out) = last.expect("two frames");
    assert!(!plan.from_scratch, "frame 1 reuses the tables");
    let pre = plan.expected.pre.as_ref().expect("scene mode");
    let fmt = cfg.format();
    // A list of at least 3 entries, not a multiple of 8 (its last line has zero slots).
    let (t, list) =
        pre.lists.iter().enumerate().find(|(_, l)| l.len() > 2 && l.len() % 8 != 0).expect("a list");
    let base = 8 * (pre.list_base / 8 + t as u64 * pre.list_stride);
    let mut swapped = mem.clone();
    let (a, b) = (swapped.read_u64(base), swapped.read_u64(base + 16));
    swapped.write_u64(base, b);
    swapped.write_u64(base + 16, a);
    assert_eq!(plan.expected.compare(&swapped), None, "the order within a list is free");
    let mut bad = mem.clone();
    let e = list[0];
    bad.write_u64(base, fmt.pack(&neo_golden::sort::SortEntry::new(e.key, e.id ^ 1)));
    let m = plan.expected.compare(&bad).expect("a wrong list entry");
    assert_eq!((m.tile, matches!(m.place, Place::List(_)), m.field), (Some(t as u64), true, "entry"), "{m}");
    let mut bad = mem.clone();
    let slot = base + 8 * list.len() as u64;
    bad.write_u64(slot, 1);
    let m = plan.expected.compare(&bad).expect("a non-zero slot");
    assert_eq!((m.place, m.addr), (Place::List(list.len() as u64), slot), "{m}");
    let mut bad = mem.clone();
    let len_at = plan.regs.desc_base + 32 * t as u64 + 20;
    bad.write_u32(len_at, bad.read_u32(len_at) + 1);
    let m = plan.expected.compare(&bad).expect("a wrong list_len");
    assert_eq!((m.place, m.field), (Place::Descriptor(2), "list_len"), "{m}");
    let i = (0..pre.features.len()).find(|&i| pre.features[i] != [0; 32]).expect("a visible Gaussian");
    let mut bad = mem.clone();
    let at = plan.regs.feat_base + 32 * i as u64 + 8;
    bad.write_u64(at, bad.read_u64(at) ^ 4);
    let m = plan.expected.compare(&bad).expect("a wrong feature word");
    assert_eq!((m.tile, m.place, m.field, m.addr), (None, Place::Feature(i as u32), "bits", at), "{m}");
    let mut wrong = out.clone();
    wrong.counters.add(Counter::RdPre, 8);
    let m = plan.expected.compare_outcome(&wrong).expect("a counter mismatch");
    assert_eq!(m.field, "RD_PRE");
}

/// The engine plans `adaptive` without re-sorts, with its own wide chunk or none, at most 15
/// passes: anything else is refused by name before a frame is rendered.
#[test]
fn the_engine_plans_only_what_it_can_run() {
    use neo_golden::engine::{Planner, SessionOptions};
    use neo_golden::pipeline::adaptive::AdaptiveParams;
    use neo_golden::pipeline::Strategy;
    let (scene, _) = load_scene("synthetic:blobs?gaussians=200&seed=1", false).expect("synthetic scene");
    let (traj, cfg) = EngineCase::Orbit
        .setup(&scene, &CaseScene::synthetic(), 1, [64, 64], &small_config())
        .expect("setup");
    let ok = AdaptiveParams { resort: false, wide: 1, ..AdaptiveParams::default() };
    for (strategy, want) in [
        (Strategy::Neo, "neo is not adaptive"),
        (Strategy::Adaptive(AdaptiveParams::default()), "without re-sorts"),
        (Strategy::Adaptive(AdaptiveParams { wide: 4, ..ok }), "wide = its dps_wide (1)"),
        (Strategy::Adaptive(AdaptiveParams { max_passes: 16, ..ok }), "at most 15 passes"),
    ] {
        let opts = SessionOptions { strategy, planner: Planner::Engine, ..SessionOptions::default() };
        let e = EngineSession::with_options(&scene, traj.clone(), &cfg, opts).err().expect("refused");
        let msg = e.to_string();
        assert!(msg.contains("the engine's own plan") && msg.contains(want), "{strategy}: {msg}");
    }
    let opts = SessionOptions {
        strategy: Strategy::Adaptive(ok),
        planner: Planner::Engine,
        ..SessionOptions::default()
    };
    assert!(EngineSession::with_options(&scene, traj.clone(), &cfg, opts).is_ok());
    let wide = EngineConfig { dps_wide: 4, ..cfg };
    let opts4 = SessionOptions { strategy: Strategy::Adaptive(AdaptiveParams { wide: 4, ..ok }), ..opts };
    assert!(EngineSession::with_options(&scene, traj, &wide, opts4).is_ok(), "its own wide chunk");
}

/// The engine's own plan stops with the camera: on a frame whose pose repeats the last one the
/// host leaves ADAPT_CTRL off and every reuse tile gets Neo's single pass (the pipeline's still
/// camera rule), so the cost is Neo's at once; the frame before, still moving, is the engine's.
#[test]
fn the_engine_plan_stops_with_the_camera() {
    use neo_golden::engine::{Planner, SessionOptions};
    let (scene, _) = load_scene(CaseScene::SYNTHETIC, false).expect("synthetic scene");
    let c = EngineCase::AdaptiveEngine;
    let (mut traj, cfg) =
        c.setup(&scene, &CaseScene::synthetic(), 3, [128, 128], &small_config()).expect("setup");
    let last = traj.frames.last().expect("frames").clone();
    traj.frames.push(last);
    let opts = SessionOptions { planner: Planner::Engine, ..c.options(HostMode::Lists) };
    let mut s = EngineSession::with_options(&scene, traj, &cfg, opts).expect("session");
    let mut mem = Memory::new();
    let mut planned = Vec::new();
    while let Some(plan) = s.next_frame(&mut mem).expect("host frame") {
        let out = execute_frame(&cfg, &plan.regs, &mut mem).expect("reference frame");
        assert_eq!(plan.expected.compare(&mem), None, "frame {}", plan.frame);
        assert_eq!(plan.expected.compare_outcome(&out), None, "frame {}", plan.frame);
        planned.push(plan.regs.adapt.enabled());
        if plan.frame == 3 {
            let reuse = plan.expected.descriptors.iter().filter(|d| !d.from_scratch && d.prev_len > 0);
            assert!(
                reuse.clone().count() > 0 && reuse.clone().all(|d| d.dps_passes == 1),
                "Neo's single pass"
            );
            assert_eq!(out.counters.get(Counter::RdResult), 0, "no result read");
        }
    }
    // Frame 0 from scratch, 1 and 2 moving (the engine plans), 3 still (the host's single pass).
    assert_eq!(planned, [false, true, true, false]);
}
