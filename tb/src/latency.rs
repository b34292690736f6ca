//! Latency and throughput measured by cosimulation, written to `reports/latency.json` for the
//! cycle model.
//!
//! The document is a [`neo_golden::formats::latency::LatencyReport`] (schema and field docs
//! there, versioned by its `SCHEMA`). It holds raw measurements only: unit latencies and
//! rates, sorting-core command cycles over a grid of sizes and modes, the ITU's latency and
//! rate, and the raster core's cycles per tile over a grid of table lengths x subtile bits per
//! Gaussian (`raster.core.grid`). The cycle model (`neo_sim::latency`) does every fit next to
//! the formula it fits (the raster core's empty-tile cost, load rate and per-segment overhead
//! from the grid, with `neo_sim::arch::raster_tile_cycles`).
//!
//! `cycles` is one command alone (accept to `done_o`); `interval` is the steady-state cost per
//! command when identical commands stream back to back (see [`STREAM`]).
//!
//! All numbers are measured on the Verilated RTL with fixed stimulus (seeded), full-rate inputs,
//! an always-ready output and the ideal memory, so the file is reproducible bit for bit.

use crate::core::{layout, merge_cmd, queue_checked, sort_chunks_checked, Command, Core, MemTiming, Mode};
use crate::models::{NeoBsu, NeoMsu};
use crate::rng::Rng;
use crate::stimulus::{merge_stream, sorted_stream, tile_entries};
use neo_gen::EngineConfig;
use neo_golden::formats::latency::{
    BsuUnit, ChunkPoint, ItuUnit, LatencyReport, MemoryModel, MergeDeletePoint, MergePoint, MsuUnit, Raster,
    RasterCore, ScuUnit, SortCore, SortCoreUnit, Units, SCHEMA,
};
use neo_golden::sort::SortEntry;
use std::collections::BTreeMap;

/// Seed of the report's stimulus (fixed: the report must be reproducible).
const SEED: u64 = 0x4E45_4F5F_4C41_5431;

/// BSU: (latency, initiation interval, vectors, cycles). Latency is the number of rising edges
/// from the edge that accepts a vector to the first cycle its result is on `out_data_o` with
/// `out_valid_o` high; II is measured over `vectors` back-to-back vectors.
pub fn bsu_latency(cfg: &EngineConfig) -> (u64, u64, u64, u64) {
    let fmt = cfg.format();
    let mut dut = NeoBsu::new();
    dut.set_in_valid_i(false);
    dut.set_out_ready_i(true);
    dut.reset();
    let mut rng = Rng::new(SEED);
    let vectors = 64u64;
    let (mut accepted, mut outputs) = (Vec::new(), Vec::new());
    let mut words = [0u32; 24];
    while (outputs.len() as u64) < vectors {
        let sending = (accepted.len() as u64) < vectors;
        if sending {
            let v: Vec<SortEntry> = tile_entries(&fmt, &mut rng, cfg.bsu_width, false, 100);
            crate::lanes::pack_lanes(&fmt, &v, &mut words);
            dut.set_in_data_i(&words);
        }
        dut.set_in_valid_i(sending);
        dut.eval();
        if sending && dut.in_ready_o() {
            accepted.push(dut.cycle());
        }
        if dut.out_valid_o() {
            outputs.push(dut.cycle());
        }
        dut.tick();
        assert!(dut.cycle() < 10_000, "BSU produced {} of {vectors} outputs", outputs.len());
    }
    let latency = outputs[0] - accepted[0];
    let ii = (accepted[accepted.len() - 1] - accepted[0]) / (vectors - 1);
    let out_ii = (outputs[outputs.len() - 1] - outputs[0]) / (vectors - 1);
    assert_eq!(ii, out_ii, "input and output rates differ");
    (latency, ii, vectors, outputs[outputs.len() - 1] + 1)
}

/// MSU+: (latency, initiation interval, merge gap, entries, cycles) for two back-to-back merges of
/// all-valid streams of `len` entries each, every input beat offered as soon as possible and the
/// output always ready. Latency: edges from the first pop to the first output beat. II: cycles
/// per output entry within a merge. Merge gap: idle output cycles between the last beat of the
/// first merge and the first beat of the second (the end-of-merge flush). Entries and cycles
/// are the totals over both merges.
pub fn msu_latency(cfg: &EngineConfig, len: usize) -> (u64, u64, u64, u64, u64) {
    let fmt = cfg.format();
    let mut rng = Rng::new(SEED ^ 1);
    // Per stream: the beats (entry, last) of merge 1 then merge 2.
    let beats = |rng: &mut Rng| -> Vec<(SortEntry, bool)> {
        (0..2)
            .flat_map(|_| {
                let s = sorted_stream(&fmt, rng, len, 100, false);
                s.into_iter().enumerate().map(|(i, e)| (e, i + 1 == len)).collect::<Vec<_>>()
            })
            .collect()
    };
    let (a, b) = (beats(&mut rng), beats(&mut rng));
    let mut dut = NeoMsu::new();
    dut.set_a_valid_i(false);
    dut.set_b_valid_i(false);
    dut.set_out_ready_i(true);
    dut.set_drop_invalid_i(false);
    dut.reset();
    let (mut ia, mut ib) = (0usize, 0usize);
    let (mut first_pop, mut outs) = (None, Vec::new());
    let total = a.len() + b.len();
    while outs.len() < total {
        dut.set_a_valid_i(ia < a.len());
        dut.set_b_valid_i(ib < b.len());
        if let Some(&(e, last)) = a.get(ia) {
            dut.set_a_data_i(fmt.pack(&e));
            dut.set_a_last_i(last);
            dut.set_a_empty_i(false);
        }
        if let Some(&(e, last)) = b.get(ib) {
            dut.set_b_data_i(fmt.pack(&e));
            dut.set_b_last_i(last);
            dut.set_b_empty_i(false);
        }
        dut.eval();
        let pop_a = ia < a.len() && dut.a_ready_o();
        let pop_b = ib < b.len() && dut.b_ready_o();
        if (pop_a || pop_b) && first_pop.is_none() {
            first_pop = Some(dut.cycle());
        }
        ia += pop_a as usize;
        ib += pop_b as usize;
        if dut.out_valid_o() {
            outs.push((dut.cycle(), dut.out_last_o()));
        }
        dut.tick();
        assert!(dut.cycle() < 100 * total as u64 + 100, "MSU+ produced {} of {total} outputs", outs.len());
    }
    let first = first_pop.expect("an entry was popped");
    let per = 2 * len;
    let end1 = outs[per - 1];
    assert!(end1.1, "the merge's last beat carries out_last_o");
    let ii = ((end1.0 - outs[0].0) as f64 / (per - 1) as f64).round() as u64;
    let gap = outs[per].0 - end1.0 - 1;
    (outs[0].0 - first, ii, gap, total as u64, outs[total - 1].0 + 1)
}

/// Commands per back-to-back stream of the interval measurement: the interval is the mean
/// spacing of the `done_o` pulses of commands `2..STREAM` (the first is the fill).
pub const STREAM: usize = 6;

/// Steady-state interval from the `done_o` cycles of a stream (rounded to whole cycles).
fn stream_interval(done_at: &[u64]) -> u64 {
    let k = done_at.len();
    assert!(k >= 3, "a stream of at least 3 commands");
    ((done_at[k - 1] - done_at[1]) as f64 / (k - 2) as f64).round() as u64
}

/// Interval of `STREAM` chunk commands of `n` entries each, back to back with no gap (every
/// output checked against golden).
fn chunk_interval(core: &mut Core, cfg: &EngineConfig, mode: Mode, n: u64, rng: &mut Rng) -> u64 {
    let chunks: Vec<Vec<SortEntry>> =
        (0..STREAM).map(|_| tile_entries(&cfg.format(), rng, n as usize, false, 100)).collect();
    let q = sort_chunks_checked(core, cfg, &chunks, mode);
    stream_interval(&q.results.iter().map(|r| r.done_at).collect::<Vec<_>>())
}

/// Interval of `STREAM` copies of the same merge back to back (every output checked).
fn merge_interval(core: &mut Core, a: &[SortEntry], b: &[SortEntry], drop_invalid: bool) -> u64 {
    let cmds: Vec<_> = (0..STREAM as u64).map(|slot| merge_cmd(core, slot, a, b, drop_invalid)).collect();
    let q = queue_checked(core, &cmds);
    stream_interval(&q.results.iter().map(|r| r.done_at).collect::<Vec<_>>())
}

/// Cycles of one core command with the ideal memory, checked against golden on the way.
fn core_cycles(
    core: &mut Core,
    cfg: &EngineConfig,
    mode: Mode,
    a: &[SortEntry],
    b: &[SortEntry],
) -> (u64, u64) {
    let r = match mode {
        Mode::Sort | Mode::Dps => crate::core::sort_chunk_checked(core, cfg, a, mode),
        Mode::Merge => crate::core::merge_checked(core, a, b, false),
        Mode::MergeDelete => crate::core::merge_checked(core, a, b, true),
    };
    (r.cycles, r.done_len)
}

/// The whole report (see [`LatencyReport`] for the schema).
pub fn report(cfg: &EngineConfig) -> LatencyReport {
    let (latency, ii, vectors, cycles) = bsu_latency(cfg);
    let neo_bsu = BsuUnit { latency, ii, vectors, cycles };
    let (latency, ii, merge_gap, entries, cycles) = msu_latency(cfg, 64);
    let neo_msu = MsuUnit { latency, ii, merge_gap, entries, cycles };
    let (command_overhead, sort_core) = sort_core_timing(cfg);
    LatencyReport {
        schema: SCHEMA.into(),
        doc: doc(),
        config: cfg.clone(),
        memory: MemoryModel { read_latency: 1, req_ready: "always".into(), rsp_gaps: "none".into() },
        units: Units {
            neo_bsu,
            neo_msu,
            neo_sort_core: SortCoreUnit { command_overhead },
            neo_scu: Some(scu_unit(cfg)),
        },
        sort_core,
        raster: Some(raster_section(cfg)),
        preprocess: Some(preprocess_section(cfg)),
    }
}

/// The Sorting Core's part of the report: `units.neo_sort_core.command_overhead` and the
/// `sort_core` section, measured on one core with the ideal memory (a few seconds: the part of
/// the report a timing-only bug of the core changes, checked alone by the `latency_report`
/// target's `the_sort_core_timing_is_current`).
pub fn sort_core_timing(cfg: &EngineConfig) -> (u64, SortCore) {
    let mut core = Core::new(cfg, SEED, MemTiming::IDEAL);
    core.set_cmd_gap(0);
    // A zero-length command: the fixed cost of accepting and finishing.
    let command_overhead = core
        .run(Command { mode: Mode::Sort, src_a: layout::SRC, len_a: 0, src_b: 0, len_b: 0, dst: layout::DST })
        .cycles;
    (command_overhead, sort_core_section(cfg, &mut core))
}

/// The `preprocess` section: the Preprocessing Engine's units measured on the RTL (outputs
/// checked against golden on the way).
pub fn preprocess_section(cfg: &EngineConfig) -> neo_golden::formats::latency::Preprocess {
    use crate::check::Checker;
    use crate::pre::{color_bench, measure, project_bench, random_color_items, scene_project_items};
    use neo_gen::units::pre::{COLOR_NAME, PROJECT_NAME};
    let mut dup = crate::dup::DupBench::build(cfg).unwrap_or_else(|e| panic!("neo_pre_dup: {e}"));
    let mut color = color_bench(cfg);
    let color_items = random_color_items(&mut Rng::new(SEED ^ 12), 512, [0.5, -1.0, -3.0], 3);
    let mut project = project_bench(cfg);
    let project_items = &scene_project_items(cfg, 1, 512, 1)[0];
    neo_golden::formats::latency::Preprocess {
        projection: Some(measure(&mut project, project_items, &Checker::new(PROJECT_NAME, SEED ^ 13))),
        color: Some(measure(&mut color, &color_items, &Checker::new(COLOR_NAME, SEED ^ 12))),
        duplication: Some(crate::dup::measure_timing(&mut dup, SEED ^ 11)),
        fetch: Some(crate::fetch::measure_window(cfg, SEED ^ 14)),
    }
}

/// The `sort_core` section: chunk commands over a grid of sizes, merges over a grid of stream
/// lengths (every output checked against golden).
fn sort_core_section(cfg: &EngineConfig, core: &mut Core) -> SortCore {
    let fmt = cfg.format();
    let mut rng = Rng::new(SEED ^ 2);
    let sizes: Vec<u64> = [1, 16, 32, 64, 128, 256].into_iter().filter(|&n| n <= cfg.chunk as u64).collect();
    let mut chunk_rows = |mode: Mode, rng: &mut Rng| -> Vec<ChunkPoint> {
        sizes
            .iter()
            .map(|&n| {
                let v = tile_entries(&fmt, rng, n as usize, false, 100);
                let (cycles, _) = core_cycles(core, cfg, mode, &v, &[]);
                let interval = chunk_interval(core, cfg, mode, n, rng);
                ChunkPoint { entries: n, cycles, interval }
            })
            .collect()
    };
    let conventional = chunk_rows(Mode::Sort, &mut rng);
    let dps = chunk_rows(Mode::Dps, &mut rng);
    let merge_sizes = [(0u64, 0u64), (8, 8), (32, 32), (128, 128), (256, 256), (512, 512), (300, 0)];
    let mut merge = Vec::new();
    let mut merge_delete = Vec::new();
    for &(len_a, len_b) in &merge_sizes {
        let a = merge_stream(&fmt, &mut rng, len_a as usize, 100, false);
        let b = merge_stream(&fmt, &mut rng, len_b as usize, 100, false);
        let (cycles, _) = core_cycles(core, cfg, Mode::Merge, &a, &b);
        let interval = merge_interval(core, &a, &b, false);
        merge.push(MergePoint { entries: len_a + len_b, len_a, len_b, cycles, interval });
        // A quarter of the entries invalid (every fourth of each stream).
        let kill = |v: &[SortEntry]| -> Vec<SortEntry> {
            v.iter().enumerate().map(|(i, e)| e.with_valid(i % 4 != 3)).collect()
        };
        let (ka, kb) = (kill(&a), kill(&b));
        let invalid = ka.iter().chain(&kb).filter(|e| !e.valid).count() as u64;
        let (cycles, out) = core_cycles(core, cfg, Mode::MergeDelete, &ka, &kb);
        let interval = merge_interval(core, &ka, &kb, true);
        merge_delete.push(MergeDeletePoint {
            merge: MergePoint { entries: len_a + len_b, len_a, len_b, cycles, interval },
            invalid,
            out,
        });
    }
    SortCore { conventional, dps, merge, merge_delete }
}

/// The `doc` section: what each field measures, for a reader of the JSON.
fn doc() -> BTreeMap<String, String> {
    [
        ("config", "every field of the engine configuration (neo_golden::engine::EngineConfig) the measured RTL was generated from; the cycle model refuses a report of another configuration"),
        ("memory", "the memory model used for sort_core: request always accepted, first read beat the cycle after the request, one beat per cycle"),
        ("units.*.latency", "rising edges from the edge that accepts an input to the first cycle its result is offered (out_valid_o high)"),
        ("units.*.ii", "initiation interval: cycles between accepted inputs (BSU: vectors; MSU+: output entries) at full rate"),
        ("units.neo_msu.merge_gap", "idle output cycles between the last beat of a merge and the first beat of the next one fed back to back (the end-of-merge flush)"),
        ("units.neo_msu.entries", "output entries of the measurement: two back-to-back merges of two 64-entry streams"),
        ("units.neo_scu", "neo_scu (one subtile's blending): latency = rising edges from the edge that accepts a list's last Gaussian to the first cycle its 64 pixels are offered (pipeline otherwise empty); ii = cycles per Gaussian in a list that does not terminate (64 / scu_lanes passes); drain_ii = cycles per Gaussian once every pixel is done (the rest of the list is drained); lanes = scu_lanes"),
        ("units.neo_sort_core.command_overhead", "cycles from accepting a zero-length SORT to its done_o pulse"),
        ("preprocess.projection", "neo_pre_project on `items` Gaussians of a synthetic scene at full rate: latency = edges from accepting a Gaussian to its result offered; ii = cycles per Gaussian; cycles = first offer to last result; settle = cycles the camera registers need before the first Gaussian (every output checked against golden)"),
        ("preprocess.color", "neo_pre_color on `items` random Gaussians of SH degree 3 at full rate: fields as preprocess.projection"),
        ("preprocess.fetch", "neo_pre_fetch streaming `beats` beats of geometry records through a memory answering `read_latency` cycles after each request at one beat per cycle, records always taken (each checked against memory): lines_in_flight = most 64-byte lines requested and not yet received (the unit's read window, EngineConfig pre_read_lines); cycles = start to last record; the engine's window is units x lines_in_flight"),
        ("preprocess.duplication", "neo_pre_dup: latency = edges from accepting a Gaussian with one candidate tile, which it enters, to that tile offered; cycles_per_candidate = walker cycles per candidate tile over `gaussians` random Gaussians with `candidates` candidate tiles (all but the last) taking `cycles` from the first acceptance to the last; min_cycles_per_gaussian = walker cycles of a Gaussian outside the image"),
        ("raster.itu.latency", "neo_itu: rising edges from the edge that accepts a (Gaussian, tile) job to the first cycle its subtile bitmap is offered"),
        ("raster.itu.ii", "neo_itu: cycles per (Gaussian, tile) job back to back with the output always ready; each job tests every subtile of the tile at once"),
        ("raster.itu.jobs", "random jobs of the II measurement (every bitmap checked against golden subtile_bitmap)"),
        ("raster.core", "neo_raster_core (itus ITUs, scus SCUs, feature_buffer entries per segment, pixel_writes pixel-row writes per tile): measured only; the cycle model fits its empty-tile cost, load rate and per-segment overhead from the grid"),
        ("raster.core.grid", "one tile per point, pixels and write-back checked against golden: entries = table length, bits_per_gaussian = subtiles each Gaussian touches by construction, set_bits = set subtile bits of the table, group_max_routed = sum over subtile groups of the largest per-SCU routed count, cycles = command to done_o (ideal memory), load_cycles = command to the last read request"),
        ("sort_core.*.cycles", "one command alone: cycles from the edge that accepts the command (cmd_valid_i & cmd_ready_o) to the done_o pulse, ideal memory, output verified against golden"),
        ("sort_core.*.interval", "steady state: cycles per command when 6 identical commands stream back to back (each offered as soon as the previous one was taken; mean spacing of the done_o pulses of commands 2..6), ideal memory, outputs verified; chunk commands overlap (a chunk's load runs under the previous chunk's merge passes), merge commands serialise (interval = cycles + the turnaround)"),
        ("sort_core.conventional", "SORT of one chunk of `entries` entries: load, BSU vectors, in-chunk merge passes, write-back (golden full_sort of one chunk)"),
        ("sort_core.dps", "DPS command on one chunk (same datapath as SORT; golden dps_pass)"),
        ("sort_core.merge", "MERGE of sorted streams A and B (golden merge2(a, b, false))"),
        ("sort_core.merge_delete", "MERGE_DELETE with every fourth entry of each stream invalid (golden merge2(a, b, true)); `out` entries written"),
    ]
    .into_iter()
    .map(|(k, v)| (k.to_string(), v.to_string()))
    .collect()
}

/// The `units.neo_scu` entry: latency, II and drain rate of the SCU (outputs checked against
/// golden on the way).
pub fn scu_unit(cfg: &EngineConfig) -> ScuUnit {
    let mut dut = crate::models::NeoScu::new();
    let t = crate::scu::measure_timing(&mut dut, cfg, SEED ^ 5);
    ScuUnit {
        latency: t.latency,
        ii: t.ii,
        drain_ii: t.drain_ii,
        gaussians: t.gaussians,
        lanes: cfg.scu_lanes as u64,
    }
}

/// The `raster` section: the ITU's latency and II, measured on random jobs, and the raster
/// core's grid (checked against golden on the way).
pub fn raster_section(cfg: &EngineConfig) -> Raster {
    let jobs = 256usize;
    let mut dut = crate::models::NeoItu::new();
    let t = crate::itu::measure_timing(&mut dut, cfg, SEED ^ 3, jobs);
    let itu = ItuUnit {
        latency: t.latency,
        ii: t.ii,
        jobs: jobs as u64,
        subtiles_per_job: cfg.raster_config().subtiles_per_tile() as u64,
    };
    Raster { itu: Some(itu), core: Some(raster_core_section(cfg)) }
}

/// The subtile bits per Gaussian of the `raster.core` grid.
pub const RASTER_GRID_BITS: [u64; 4] = [1, 4, 16, 64];

/// The table lengths of the `raster.core` grid for a feature buffer of `f` entries: empty,
/// short, one segment, two and eight.
pub fn raster_grid_lengths(f: u64) -> [u64; 6] {
    [0, 16, 64, f, 2 * f, 8 * f]
}

/// The `raster.core` section: `neo_raster_core` cycles per tile (command to `done_o`, ideal
/// memory) over a grid of table lengths x subtile bits per Gaussian, and the shape of the
/// measured core. No fit: the cycle model fits its formula to the grid.
pub fn raster_core_section(cfg: &EngineConfig) -> RasterCore {
    let f = cfg.raster_feature_buffer as u64;
    let grid = crate::raster::measure_grid(cfg, SEED ^ 7, &raster_grid_lengths(f), &RASTER_GRID_BITS);
    let rc = cfg.raster_config();
    RasterCore {
        itus: cfg.raster_itus as u64,
        scus: cfg.raster_scus as u64,
        feature_buffer: f,
        pixel_writes: (rc.tile * rc.tile / rc.subtile) as u64,
        memory: "ideal: always ready, first response beat 1 cycle after the request".into(),
        grid,
    }
}

/// The report as the text written to `reports/latency.json` (pretty JSON, sorted keys and a
/// final newline).
pub fn report_text(cfg: &EngineConfig) -> String {
    report(cfg).to_text()
}
