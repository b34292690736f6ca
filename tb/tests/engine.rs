//! Whole-frame cosimulation of the verilated `neo_engine` against the golden engine, frame
//! after frame while the tables are reused (issue 11). Small engines (CI); the full 16 + 4 engine
//! runs in `neo bench engine`.
//!
//! Each case: the golden host session writes the frame's inputs, the engine runs it behind a
//! hostile AXI memory (latency, 3/4 bandwidth, random extra delays, reordering across IDs), and
//! the frame buffer, every tile's next table, the results, the status registers and the golden
//! counters must be bit-exact. `NEO_SEED` replays a run; `WAVES=1` writes a VCD per case and
//! `WAVES=fst` an FST (`target/waves/engine_<case>.{vcd,fst}` with a `.gtkw` beside it; the
//! FST-traced engine is a separate, cached build). Without `WAVES` the engine is built without
//! tracing (half the C++ to compile).
//! Without Verilator at build time the tests are absent (build.rs warns, and fails when `CI` is
//! set), as the other cosimulation benches.

/// Without Verilator the cosimulation below is compiled out: SKIP, or a failure when `CI` is set.
#[test]
fn models_present() {
    assert_eq!(neo_tb::require_models("models_present: whole-engine cosimulation"), neo_tb::HAS_MODELS);
}

neo_tb::with_models! {
use neo_golden::engine::memory::Memory;
use neo_golden::engine::{CaseScene, Counter, EngineCase, EngineConfig, EngineSession, HostMode, SessionOptions};
use neo_golden::hwpre::ShPrecision;
use neo_sim::engine_frame::{error_pct, EngineFrameModel, FramePrediction, PortTiming};
use neo_sim::latency::Latency;
use neo_golden::scene::Scene;
use neo_golden::shared::shared_file_for_test;
use neo_golden::source::load_scene;
use neo_tb::axi::AxiTiming;
use neo_tb::engine::{ci_config, quiet_limit, EngineModel, EngineRig, FrameWork, RunOptions};
use neo_tb::rng::SeedSplit;
use neo_tb::waves::WaveFormat;
use std::collections::HashMap;
use std::sync::Mutex;

/// Builds are serialised in this process (a second build of a configuration is a cache hit).
static BUILD: Mutex<()> = Mutex::new(());

/// The engine of `cfg`, traced in `format`, compiled for build time (`-O1`,
/// [`EngineModel::build_for_short_runs`]): on the CI engine the C++ compiles in about half the
/// time of `-O3`, and biker's 256x256 frames simulate no slower (docs/rtl.md).
fn model(cfg: &EngineConfig, format: Option<WaveFormat>) -> EngineModel {
    let _one_at_a_time = BUILD.lock().unwrap_or_else(|e| e.into_inner());
    let m = EngineModel::build_for_short_runs(cfg, format).unwrap_or_else(|e| panic!("building neo_engine: {e}"));
    let how = if m.build.cached { "cached" } else { "built" };
    println!(
        "neo_engine ({} + {} cores): {how} in {:.1} s {}",
        cfg.sort_cores, cfg.raster_cores, m.build.seconds, m.build.log
    );
    m
}

/// One frame: the RTL's cycles and busy counters, and the cycle model's prediction.
struct FrameCheck {
    from_scratch: bool,
    rtl_cycles: u64,
    sort_busy: u64,
    raster_busy: u64,
    /// The PRE_BUSY counter (scene mode).
    pre_busy: u64,
    /// The cycle model's prediction (`None`: a case the measured latencies cannot time).
    model: Option<FramePrediction>,
}

impl FrameCheck {
    /// The model's errors in percent: frame cycles, sort busy, raster busy.
    fn errors(&self) -> [f64; 3] {
        let m = self.timed();
        [
            error_pct(m.cycles, self.rtl_cycles),
            error_pct(m.sort_busy, self.sort_busy),
            error_pct(m.raster_busy, self.raster_busy),
        ]
    }

    /// The prediction of a timed case.
    fn timed(&self) -> &FramePrediction {
        self.model.as_ref().expect("a case the cycle model times")
    }

    /// The model's error on the Preprocessing Engine's phase, in percent.
    fn pre_error(&self) -> f64 {
        error_pct(self.timed().pre_busy, self.pre_busy)
    }
}

/// Issue 11's targets for the engine-level cycle model (docs/cycle-model.md section 8): every
/// frame's cycles within 5% of the RTL's, each engine's busy cycles within 10%.
fn assert_model_matches(what: &str, frames: &[FrameCheck]) {
    for (k, f) in frames.iter().enumerate() {
        let [cycles, sort, raster] = f.errors();
        let scratch = if f.from_scratch { " (from scratch)" } else { "" };
        assert!(cycles.abs() <= 5.0, "{what} frame {k}{scratch}: model cycles {cycles:+.2}% off the RTL's");
        assert!(sort.abs() <= 10.0, "{what} frame {k}: model sort busy {sort:+.2}% off the RTL's");
        assert!(raster.abs() <= 10.0, "{what} frame {k}: model raster busy {raster:+.2}% off the RTL's");
    }
}

/// The engine-level model's Preprocessing Engine phase (`EngineFrameModel::pre_cycles`) within
/// `bound` percent of the RTL's PRE_BUSY on every frame. The synthetic scenes' bound is 2%
/// (measured: -0.1% to -0.2% behind the hostile memory, one and two lanes, binary32 and
/// binary16 SH), biker's 5% (the frame target; measured -2.2% and -0.0%).
fn assert_pre_model_matches(what: &str, frames: &[FrameCheck], bound: f64) {
    for (k, f) in frames.iter().enumerate() {
        let e = f.pre_error();
        assert!(f.pre_busy > 0, "{what} frame {k}: the Preprocessing Engine ran");
        assert!(e.abs() <= bound, "{what} frame {k}: model preprocessing {e:+.2}% off the RTL's PRE_BUSY");
    }
}

/// The seed of case `k` of a test: whole frames are too long to repeat for every seed, so the
/// cases are split over the test's seeds (fixed ones and a fresh one; every case runs behind
/// `NEO_SEED` when it is set).
fn case_seed(seeds: &SeedSplit, k: usize, c: EngineCase) -> u64 {
    let seed = seeds.seed(k);
    println!("engine_{}: seed = 0x{seed:016x} (reproduce with NEO_SEED=0x{seed:016x})", c.name());
    seed
}

/// Runs every frame of `case` behind the hostile memory; panics at the first mismatch.
fn run_case(scene: &Scene, how: &CaseScene, c: EngineCase, frames: usize, res: [u32; 2], seed: u64) -> Vec<u64> {
    run_case_with(scene, how, c, frames, res, RunOptions::default(), seed).iter().map(|f| f.rtl_cycles).collect()
}

/// Runs every frame of `case` behind the hostile memory on an engine derived from `base`, the
/// host in `mode`; panics at the first mismatch.
fn run_case_in(
    scene: &Scene,
    how: &CaseScene,
    c: EngineCase,
    (frames, res): (usize, [u32; 2]),
    (base, mode, sh): (&EngineConfig, HostMode, ShPrecision),
    seed: u64,
) -> Vec<FrameCheck> {
    run_case_full(scene, how, c, (frames, res), (base, mode, sh), RunOptions::default(), seed)
}

/// Runs every frame of `case` behind a memory of `opts.timing` and returns each frame's check;
/// panics at the first mismatch.
fn run_case_with(
    scene: &Scene,
    how: &CaseScene,
    c: EngineCase,
    frames: usize,
    res: [u32; 2],
    opts: RunOptions,
    seed: u64,
) -> Vec<FrameCheck> {
    run_case_full(scene, how, c, (frames, res), (&ci_config(), HostMode::Lists, ShPrecision::F32), opts, seed)
}

/// [`run_case_with`] on an engine derived from `base`, the host in `mode`.
fn run_case_full(
    scene: &Scene,
    how: &CaseScene,
    c: EngineCase,
    (frames, res): (usize, [u32; 2]),
    (base, mode, sh): (&EngineConfig, HostMode, ShPrecision),
    opts: RunOptions,
    seed: u64,
) -> Vec<FrameCheck> {
    let (traj, cfg) = c.setup(scene, how, frames, res, base).expect("case setup");
    let opts_session = SessionOptions { sh, ..c.options(mode) };
    let mut session = EngineSession::with_options(scene, traj, &cfg, opts_session).expect("session");
    let format = neo_tb::waves::requested_format();
    let waves = format.map(|f| {
        neo_tb::waves::target_dir().join("waves").join(format!("engine_{}.{}", c.name(), f.extension()))
    });
    let engine = model(&cfg, format);
    let (latency, bandwidth, ready) = opts.timing.means();
    let mut rig = EngineRig::new(engine, opts, seed, waves.clone()).expect("rig");
    if let Some(w) = &waves {
        println!("waves: {}\nwaves: gtkwave {}", w.display(), neo_tb::waves::gtkw_path(w).display());
    }
    let mut cycles = Vec::new();
    let lat = Latency::from_file(&neo_golden::shared::workspace_root().join("reports/latency.json"))
        .expect("reports/latency.json");
    let (late_share, late_max) = opts.timing.late();
    let mem = PortTiming { latency, bandwidth, ready, late_share, late_max };
    let model = Some(EngineFrameModel::new(&cfg, &lat, mem).expect("cycle model"));
    let t0 = std::time::Instant::now();
    rig.record_transfers(true);
    while let Some(plan) = session.next_frame(rig.memory_mut()).expect("host frame") {
        let p = model.as_ref().map(|m| m.predict_frame(&plan.regs, rig.memory_mut()).expect("golden reference"));
        let beats_before = rig.port_beats();
        let r = rig
            .run_frame(&plan)
            .unwrap_or_else(|e| panic!("case {}: {e} (seed = 0x{seed:016x}; reproduce with NEO_SEED=0x{seed:016x})", c.name()));
        assert_transfers_account_for_the_beats(&mut rig, &beats_before, &format!("case {} frame {}", c.name(), r.frame));
        let timing = match &p {
            Some(p) => format!(
                "cycle model {:.0} ({:+.1}%), busy sort {:+.1}%, raster {:+.1}%",
                p.cycles,
                error_pct(p.cycles, r.rtl_cycles),
                error_pct(p.sort_busy, r.counters.get(Counter::SortBusy)),
                error_pct(p.raster_busy, r.counters.get(Counter::RasterBusy)),
            ),
            None => "not timed".into(),
        };
        println!(
            "case {} frame {}: {} tiles, {} cycles (harness {}), from scratch {} ({} tiles from scratch); {timing}",
            c.name(),
            r.frame,
            plan.regs.tiles,
            r.rtl_cycles,
            r.harness_cycles,
            r.from_scratch,
            plan.expected.descriptors.iter().filter(|d| d.from_scratch).count(),
        );
        println!(
            "case {} frame {}: hang limits: {} of the frame's bound {} cycles (measured/bound {:.3}; work {:?}), longest quiet stretch {} of the watchdog's {} ({:.3})",
            c.name(),
            r.frame,
            r.rtl_cycles,
            r.cycle_bound,
            r.rtl_cycles as f64 / r.cycle_bound as f64,
            FrameWork::of(&cfg, &plan),
            r.longest_quiet,
            quiet_limit(&cfg),
            r.longest_quiet as f64 / quiet_limit(&cfg) as f64,
        );
        if let (HostMode::Scene, Some(pc)) = (mode, &p) {
            println!(
                "case {} frame {}: preprocessing busy {} cycles (cycle model {:.0}, {:+.1}%), read {} B, wrote {} B",
                c.name(),
                r.frame,
                r.counters.get(Counter::PreBusy),
                pc.pre_busy,
                error_pct(pc.pre_busy, r.counters.get(Counter::PreBusy)),
                r.counters.get(Counter::RdPre),
                r.counters.get(Counter::WrPre),
            );
        }
        let check = FrameCheck {
            from_scratch: r.from_scratch,
            rtl_cycles: r.rtl_cycles,
            sort_busy: r.counters.get(Counter::SortBusy),
            raster_busy: r.counters.get(Counter::RasterBusy),
            pre_busy: r.counters.get(Counter::PreBusy),
            model: p,
        };
        if let Some(m) = r.mismatch {
            panic!(
                "case {} frame {}: MISMATCH {m} (seed = 0x{seed:016x}; reproduce with NEO_SEED=0x{seed:016x})",
                c.name(),
                r.frame
            );
        }
        cycles.push(check);
    }
    rig.finish();
    println!("case {}: {frames} frames in {:.1} s", c.name(), t0.elapsed().as_secs_f64());
    assert_eq!(cycles.len(), frames);
    cycles
}

/// The transfer log (`neo cosim --axi-log`) of the frame just run: its bursts' beats, per port
/// and direction, are the data beats the memory moved in the frame (`before`: the ports'
/// beats when the frame started), and each transfer names one of the engine's clients.
fn assert_transfers_account_for_the_beats(rig: &mut EngineRig, before: &[(u64, u64)], what: &str) {
    let after = rig.port_beats();
    let transfers = rig.take_transfers();
    let mut logged = vec![(0u64, 0u64); after.len()];
    let cfg = rig.config();
    for (t, client) in &transfers {
        let l = &mut logged[t.port];
        if t.write {
            l.1 += u64::from(t.beats);
        } else {
            l.0 += u64::from(t.beats);
        }
        assert!(cfg.memory_client(*client).is_some(), "{what}: {t:?} from no client ({client})");
    }
    let moved: Vec<(u64, u64)> = after.iter().zip(before).map(|(a, b)| (a.0 - b.0, a.1 - b.1)).collect();
    assert_eq!(logged, moved, "{what}: logged (read, write) beats per port against the beats moved");
    assert!(!transfers.is_empty(), "{what}: no transfer logged");
}

fn synthetic() -> Scene {
    load_scene(CaseScene::SYNTHETIC, false).expect("synthetic scene").0
}

/// The synthetic reuse cases on the CI engine, split over two tests (the suite runs them in
/// parallel; libtest starts tests in name order, so the two are named to start after the biker
/// check and before the overflow, which keeps both threads busy to the end); the seeds are one
/// split, named after the first test, so each case's seed is the same whichever test runs it.
const SYNTHETIC_CASES: [EngineCase; 10] = [
    EngineCase::Orbit,
    EngineCase::Cut,
    EngineCase::Turn,
    EngineCase::EdgeTiles,
    EngineCase::Adaptive,
    EngineCase::AdaptiveResort,
    EngineCase::AdaptiveEngine,
    EngineCase::AdaptiveWide,
    EngineCase::AdaptiveEngineWide,
    EngineCase::Window,
];

/// Runs `SYNTHETIC_CASES[range]`, 3 frames each at 128x128 behind the hostile memory.
fn synthetic_cases(range: std::ops::Range<usize>) {
    let scene = synthetic();
    let how = CaseScene::synthetic();
    let seeds = SeedSplit::new("synthetic_orbit_cut_and_turn_are_bit_exact_over_reuse_frames");
    let mut all = HashMap::new();
    for k in range {
        let c = SYNTHETIC_CASES[k];
        all.insert(c.name(), run_case(&scene, &how, c, 3, [128, 128], case_seed(&seeds, k, c)));
    }
    assert!(all.values().flatten().all(|&c| c > 0), "every frame takes cycles: {all:?}");
}

/// Reuse frames on the CI engine: the orbit, a cut and a 180-degree turn.
#[test]
fn synthetic_orbit_cut_and_turn_are_bit_exact_over_reuse_frames() {
    synthetic_cases(0..3);
}

/// Reuse frames on the CI engine: partial tiles at the frame's edges, and the adaptive cases
/// (per-tile DPS passes from the descriptors; with `resort=1`, single tiles sorted from scratch
/// in a reuse frame, the host writing their whole lists; and the passes planned by the frame
/// controller itself from the previous frame's results, `ADAPT_CTRL`).
#[test]
fn synthetic_orbit_with_edge_tiles_and_adaptive_passes_is_bit_exact_over_reuse_frames() {
    synthetic_cases(3..7);
}

/// Reuse frames on the CI engine with a wide DPS chunk (`dps_wide` 4): per-tile DPS passes in
/// chunks of 256 or of 1024 entries (`adaptive:wide=4`), as the descriptors say and as the frame
/// controller plans them itself (`ADAPT_CTRL` with its wide bit).
#[test]
fn synthetic_orbit_with_wide_dps_chunks_is_bit_exact_over_reuse_frames() {
    synthetic_cases(7..9);
}

/// Reuse frames on the CI engine with a reorder window in its raster core (`raster_window`
/// [`neo_golden::engine::WINDOW_CASE`]) at 16x, `adaptive` planned by the frame controller: every
/// tile blended and its table written back in the window's order.
#[test]
fn synthetic_orbit_with_a_raster_window_is_bit_exact_over_reuse_frames() {
    synthetic_cases(9..10);
}

/// What a case's reuse frames hold (golden host only): tiles whose previous table has 1 to
/// `short` entries and an empty incoming list (DPS, then `MERGE_DELETE` reading the table DPS
/// just wrote), and such tiles with an incoming list of 1 to `short` entries (SORT, DPS,
/// `MERGE_DELETE`).
fn short_reuse_tiles(
    scene: &Scene,
    how: &CaseScene,
    c: EngineCase,
    (frames, res): (usize, [u32; 2]),
    short: u32,
) -> [usize; 2] {
    let (traj, cfg) = c.setup(scene, how, frames, res, &ci_config()).expect("case setup");
    let mut session = EngineSession::with_mode(scene, traj, &cfg, HostMode::Lists).expect("session");
    let mut mem = Memory::new();
    let mut n = [0; 2];
    while let Some(plan) = session.next_frame(&mut mem).expect("host frame") {
        let reused = plan.expected.descriptors.iter().filter(|d| !d.from_scratch);
        for d in reused.filter(|d| (1..=short).contains(&d.prev_len)) {
            match d.list_len {
                0 => n[0] += 1,
                l if l <= short => n[1] += 1,
                _ => {}
            }
        }
    }
    n
}

/// Issue 16: reuse frames whose tiles are all short (a sparse scene, [`CaseScene::SPARSE`]: 8
/// Gaussians, 16 tiles of 2 to 8 entries at 256x256). A stage of such a tile writes at most the
/// sort bridge's `axi_outstanding` entries, so when the sequencer's barrier (every `done_i`,
/// then the bridge's `idle_i`) lets the next stage start, its first reads are of the lines the
/// last stage just wrote: DPS's table read back by `MERGE_DELETE`, the next table read by the
/// raster core once the tile completes (from frame 0 on). A barrier that skipped `idle_i` reads them before their B (the hazard checker's
/// RAW); on the long lists of the other cases the last writes and the next stage's first reads
/// are far apart. Orbit frames reuse every tile with an empty incoming list, turn frames with
/// lists of 1 to 4 entries. The frames are mostly the tiles' pixel writes behind the hostile
/// memory, so the engine-level cycle model's W rate is checked here too ([`assert_model_matches`]).
#[test]
fn sparse_short_tiles_are_bit_exact_over_reuse_frames() {
    let scene = load_scene(CaseScene::SPARSE, false).expect("sparse scene").0;
    let how = CaseScene::synthetic();
    let seeds = SeedSplit::new("sparse_short_tiles_are_bit_exact_over_reuse_frames");
    let (frames, res) = (3, [256, 256]);
    let short = ci_config().axi_outstanding as u32;
    for (k, c) in [EngineCase::Orbit, EngineCase::Turn].into_iter().enumerate() {
        let [empty, tiny] = short_reuse_tiles(&scene, &how, c, (frames, res), short);
        println!(
            "case {}: reuse tiles of at most {short} entries: {empty} with an empty list, {tiny} with 1 to {short} incoming",
            c.name()
        );
        let want = if c == EngineCase::Orbit { empty } else { tiny };
        assert!(
            want >= 8,
            "case {}: the sparse scene no longer gives short reuse tiles ({empty} empty, {tiny} tiny)",
            c.name()
        );
        let checks = run_case_with(&scene, &how, c, frames, res, RunOptions::default(), case_seed(&seeds, k, c));
        assert_model_matches(&format!("sparse {}", c.name()), &checks);
    }
}

/// The cases with their own engine configurations (a table capacity, core counts), on engines
/// without a Preprocessing Engine (`pre_units` 0: lists mode needs none, and each build compiles
/// in a third of the time without a lane). The overflow runs on one sorting core and one raster
/// core: that engine is `EngineCase::OneCore`'s, with the overflow's table capacity, so one build
/// covers both (the tiles that fit are sorted and rastered by the single cores).
#[test]
fn synthetic_overflow_and_core_counts_are_bit_exact() {
    let scene = synthetic();
    let how = CaseScene::synthetic();
    let seeds = SeedSplit::new("synthetic_overflow_and_core_counts_are_bit_exact");
    let base = EngineConfig { pre_units: 0, ..ci_config() };
    let one_core = EngineConfig { sort_cores: 1, raster_cores: 1, ..base.clone() };
    for (k, (c, cfg)) in [(EngineCase::Overflow, &one_core), (EngineCase::ManyCores, &base)].into_iter().enumerate() {
        let f = run_case_in(&scene, &how, c, (2, [128, 128]), (cfg, HostMode::Lists, ShPrecision::F32), case_seed(&seeds, k, c));
        assert!(f.iter().all(|f| f.rtl_cycles > 0));
    }
}

/// The synthetic scene of the scene-mode cases: 4000 Gaussians (preprocessing one Gaussian a
/// cycle on one lane, its SH gathers behind the hostile memory, is most of a 20000-Gaussian
/// frame's cycles).
fn small_synthetic() -> Scene {
    load_scene("synthetic:blobs?gaussians=4000&seed=3", false).expect("synthetic scene").0
}

/// Scene mode (issue 12): the engine preprocesses the baked scene (its lane reads geometry, SH
/// and previous feature words, writes the feature words, incoming lists and lengths), then walks
/// the tiles: feature words, lists (as multisets), lengths, the tile walk's outputs and every
/// golden counter (`RD_PRE`, `WR_PRE` included) bit-exact over reuse frames and a cut (binary16
/// SH records, `PRE_CTRL.sh_half`), on the
/// CI engine (one lane). Two lanes: `tb/tests/pre_engine.rs`; an overflow and two lanes in the
/// whole engine: the ignored tests below (each builds its own engine, 12 to 24 minutes).
#[test]
fn engine_scene_orbit_and_cut_are_bit_exact() {
    let scene = small_synthetic();
    let how = CaseScene::synthetic();
    let seeds = SeedSplit::new("engine_scene_orbit_and_cut_are_bit_exact");
    let base = ci_config();
    assert_eq!(base.pre_units, 1, "the CI engine has one lane");
    // The cut reads binary16 SH records (PRE_CTRL.sh_half), the orbit binary32 ones.
    for (k, (c, sh)) in [(EngineCase::Orbit, ShPrecision::F32), (EngineCase::Cut, ShPrecision::F16)].into_iter().enumerate() {
        let f = run_case_in(&scene, &how, c, (3, [128, 128]), (&base, HostMode::Scene, sh), case_seed(&seeds, k, c));
        assert!(f.iter().all(|f| f.rtl_cycles > 0));
        assert_pre_model_matches(c.name(), &f, 2.0);
    }
}

/// Scene mode with an overflow (a list longer than the table capacity: the list writer stops
/// writing, the length keeps counting, the next frame is from scratch). Its own engine
/// configuration (the capacity): `cargo test -p neo-tb --release --test engine -- --ignored`.
#[test]
#[ignore = "builds its own engine configuration (about 12 minutes); run with --ignored"]
fn engine_scene_overflow_is_bit_exact() {
    let scene = synthetic();
    let how = CaseScene::synthetic();
    let seeds = SeedSplit::new("engine_scene_overflow_is_bit_exact");
    let c = EngineCase::Overflow;
    let f = run_case_in(&scene, &how, c, (2, [128, 128]), (&ci_config(), HostMode::Scene, ShPrecision::F32), case_seed(&seeds, 0, c));
    assert!(f.iter().all(|f| f.rtl_cycles > 0));
}

/// Scene mode with two lanes (their hits interleave in the lists): reuse frames of the orbit.
/// A 2-lane engine build (about 20 minutes): `--ignored`.
#[test]
#[ignore = "builds a two-lane engine (about 24 minutes); run with --ignored"]
fn engine_scene_two_lanes_are_bit_exact() {
    let scene = small_synthetic();
    let how = CaseScene::synthetic();
    let seeds = SeedSplit::new("engine_scene_two_lanes_are_bit_exact");
    let base = EngineConfig { pre_units: 2, ..ci_config() };
    let c = EngineCase::Orbit;
    let f = run_case_in(&scene, &how, c, (3, [128, 128]), (&base, HostMode::Scene, ShPrecision::F32), case_seed(&seeds, 0, c));
    assert_pre_model_matches(c.name(), &f, 2.0);
}

/// Issue 11 item 5 in `neo cosim`'s default mode (scene mode: the engine preprocesses): biker
/// (`biker.compressed.ply`, whose small records leave the lane's burst writers, not a port's
/// bandwidth, to bound the Preprocessing Engine's phase) at 256x256, a frame from scratch and a
/// reuse frame behind the ideal memory. Frame cycles within 5%, each engine's busy cycles within
/// 10% (issue 11's targets) and the preprocessing phase within 5% of PRE_BUSY (measured on
/// 2026-12-06: frames -2.9% and +2.6%, sort busy -5.9% and +3.9%, raster busy -2.9% and +4.5%,
/// phase -2.2% and -0.0%; docs/cycle-model.md section 8). About 2 minutes of simulation.
#[test]
fn biker_scene_mode_cycle_model_matches_the_rtl() {
    let name = "biker_scene_mode_cycle_model_matches_the_rtl";
    let Some(path) = shared_file_for_test(name, "scenes/biker.compressed.ply") else {
        return;
    };
    let scene = load_scene(path.to_str().expect("utf-8 path"), false).expect("biker").0;
    let opts = RunOptions { timing: AxiTiming::IDEAL, ..RunOptions::default() };
    let seeds = SeedSplit::new(name);
    let c = EngineCase::Orbit;
    let how = CaseScene::biker();
    let frames =
        run_case_full(&scene, &how, c, (2, [256, 256]), (&ci_config(), HostMode::Scene, ShPrecision::F32), opts, case_seed(&seeds, 0, c));
    assert_model_matches("biker scene mode", &frames);
    assert_pre_model_matches("biker scene mode", &frames, 5.0);
}

/// Biker's orbit behind the hostile memory (about 5 minutes of simulation on two cores, the
/// longest CI test): `--ignored`. CI checks biker bit-exact over the same orbit's frames in
/// `biker_cycle_model_matches_the_rtl` (the ideal memory, at 256x256), and the hostile memory
/// in the synthetic cases.
#[test]
#[ignore = "biker behind the hostile memory (about 5 minutes); biker_cycle_model_matches_the_rtl checks biker in CI"]
fn biker_orbit_is_bit_exact_over_reuse_frames() {
    let Some(path) = shared_file_for_test("biker_orbit_is_bit_exact_over_reuse_frames", "scenes/biker.ply")
    else {
        return;
    };
    let scene = load_scene(path.to_str().expect("utf-8 path"), false).expect("biker").0;
    // A single case: it runs behind the first fixed seed (reproducible) unless NEO_SEED is set.
    let seeds = SeedSplit::new("biker_orbit_is_bit_exact_over_reuse_frames");
    let seed = case_seed(&seeds, 0, EngineCase::Orbit);
    run_case(&scene, &CaseScene::biker(), EngineCase::Orbit, 3, [128, 128], seed);
}

/// Issue 14 on biker: its orbit at 16x on the CI engine with a reorder window of
/// [`neo_golden::engine::WINDOW_CASE`] entries in the raster core, sorted by `adaptive` with the
/// DPS passes planned by the frame controller (the `window` case), 3 frames at 128x128 behind
/// the ideal memory: bit-exact frame after frame (tiles blended and written back in the window's
/// order), and the cycle model within issue 11's bounds.
#[test]
fn biker_orbit_with_a_raster_window_is_bit_exact() {
    let name = "biker_orbit_with_a_raster_window_is_bit_exact";
    let Some(path) = shared_file_for_test(name, "scenes/biker.ply") else {
        return;
    };
    let scene = load_scene(path.to_str().expect("utf-8 path"), false).expect("biker").0;
    let opts = RunOptions { timing: AxiTiming::IDEAL, ..RunOptions::default() };
    let seeds = SeedSplit::new(name);
    let c = EngineCase::Window;
    let frames = run_case_with(&scene, &CaseScene::biker(), c, 3, [128, 128], opts, case_seed(&seeds, 0, c));
    assert!(frames[1..].iter().all(|f| !f.from_scratch), "reuse after frame 0");
    // Issue 11's bounds hold with the window too (measured +0.8% to +1.5% frames, +0.9% to +2.2%
    // raster busy): the window loader's table bursts follow the last feature read, so none are
    // in flight during a write-back (docs/cycle-model.md, "Reorder window").
    assert_model_matches(name, &frames);
}

/// Issue 11 item 5: on biker at 256x256, 3 orbit frames, behind a memory of fixed timing (one
/// cycle, one beat a cycle: the harness's ideal memory, so that the model and the RTL see the
/// same timing), the cycle model's frame cycles are within 5% of the RTL's and each engine's
/// busy cycles within 10% (measured: -3.4%, +5.0%, +4.7%; docs/cycle-model.md section 8).
#[test]
fn biker_cycle_model_matches_the_rtl() {
    let Some(path) = shared_file_for_test("biker_cycle_model_matches_the_rtl", "scenes/biker.ply") else {
        return;
    };
    let scene = load_scene(path.to_str().expect("utf-8 path"), false).expect("biker").0;
    let opts = RunOptions { timing: AxiTiming::IDEAL, ..RunOptions::default() };
    let seeds = SeedSplit::new("biker_cycle_model_matches_the_rtl");
    let seed = case_seed(&seeds, 0, EngineCase::Orbit);
    let frames = run_case_with(&scene, &CaseScene::biker(), EngineCase::Orbit, 3, [256, 256], opts, seed);
    assert_model_matches("biker orbit", &frames);
}
}
