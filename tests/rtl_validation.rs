//! The model's sorting-core cycles against the Verilated RTL (cosimulation with the test bench's
//! ideal memory): the same tiles, the same command sequences, within 5%.
//!
//! For every tile of a few small frames, the golden work-only driver gives the tables and lists;
//! the RTL runs them through `neo_tb` (conventional sort on frame 0; DPS pass, incoming sort and
//! MERGE_DELETE on later frames, as `tb::core::update_checked`, every output checked against
//! golden), each phase's commands issued back to back (the next offered as soon as the previous
//! one was taken, no idle gap), and the model times the same batches from
//! `reports/latency.json` ([`neo_sim::sortcmd::batch_cycles`]: one fill, then intervals). The
//! difference comes from interpolating between measured points and from mixing chunk sizes in
//! one batch.
//!
//! In the root package, which depends on both `neo-sim` and `neo-tb` (sim never depends on tb).
//! The cosimulation compiles when `neo-tb` has its Verilated models ([`neo_tb::with_models!`]);
//! without them [`models_present`] prints SKIP, or fails when `CI` is set.

#[test]
fn models_present() {
    assert_eq!(
        neo_tb::require_models("models_present: the sorting core's cycles against the model"),
        neo_tb::HAS_MODELS
    );
}

neo_tb::with_models! {
    use std::collections::HashSet;

    use neo_golden::engine::{tile_plan, EngineConfig, FrameRegs, TileDescriptor};
    use neo_golden::pipeline::Strategy;
    use neo_golden::scene::Scene;
    use neo_golden::sort::{full_sort, Parity, SortEntry};
    use neo_golden::trajectory::Trajectory;
    use neo_golden::{shared, source, trajectory};
    use neo_sim::config::PipelineParams;
    use neo_sim::driver::WorkDriver;
    use neo_sim::latency::Latency;
    use neo_sim::sortcmd::{batch_cycles, conventional_sort, Cmd, Mode};
    use neo_tb::core::{dps_pass_checked, full_sort_checked, merge_checked, Core, MemTiming};

    /// The commands of golden's plan for a reuse tile of `table` previous entries and
    /// `incoming` new ones in frame `frame`, with Neo's one DPS pass (the engine's table capacity
    /// raised to hold it: the plan of a tile that overflows is empty).
    fn reuse_plan(gen: &EngineConfig, table: usize, incoming: usize, frame: usize) -> Vec<Cmd> {
        let d = TileDescriptor {
            prev_len: table as u32,
            list_len: incoming as u32,
            dps_passes: 1,
            ..TileDescriptor::default()
        };
        let cfg = EngineConfig { table_capacity: gen.table_capacity.max(table + incoming), ..gen.clone() };
        let regs = FrameRegs { frame: frame as u32, ..FrameRegs::default() };
        tile_plan(&cfg, &regs, &d, 0).commands().map(Cmd::from).collect()
    }

    fn latency() -> Latency {
        Latency::from_file(&shared::workspace_root().join("reports/latency.json")).unwrap()
    }

    /// Model and RTL cycles of one kind of work.
    #[derive(Default, Debug)]
    struct Split {
        model: u64,
        rtl: u64,
    }

    impl Split {
        fn add(&mut self, model: u64, rtl: u64) {
            self.model += model;
            self.rtl += rtl;
        }
    }

    /// Returns (model cycles, RTL cycles, commands run).
    fn compare(scene: &Scene, traj: &Trajectory) -> (u64, u64, usize) {
        let mut parts: [(&str, Split); 3] = [
            ("conventional sorts", Split::default()),
            ("DPS passes", Split::default()),
            ("MERGE_DELETE", Split::default()),
        ];
        let lat = latency();
        let gen = neo_tb::config();
        let params = PipelineParams::default();
        assert_eq!(gen.chunk, params.chunk, "the RTL's chunk is the model's");
        let c = params.chunk as u64;
        let first = &traj.frames[0];
        let mut drv =
            WorkDriver::new(scene, Strategy::Neo, &params, first.width, first.height, false, 0).unwrap();
        let mut core = Core::new(&gen, 7, MemTiming::IDEAL);
        core.set_cmd_gap(0);
        let sort_cfg = gen.sort_config();
        let (mut model, mut rtl, mut cmds) = (0u64, 0u64, 0usize);
        let mut prev: Vec<Vec<SortEntry>> = Vec::new();
        for (f, cam) in traj.frames.iter().enumerate() {
            let fw = drv.step(cam, f, false);
            let lists: Vec<Vec<SortEntry>> = drv.current_lists().map(|l| l.to_vec()).collect();
            for (t, current) in lists.iter().enumerate() {
                if f == 0 {
                    let seq = conventional_sort(current.len() as u64, c);
                    cmds += seq.len();
                    let (m, r) = (batch_cycles(&seq, &lat), full_sort_checked(&mut core, &gen, current));
                    parts[0].1.add(m, r);
                    model += m;
                    rtl += r;
                    continue;
                }
                let table = &prev[t];
                let valid: HashSet<u32> = table.iter().filter(|e| e.valid).map(|e| e.id).collect();
                let incoming: Vec<SortEntry> =
                    current.iter().filter(|e| !valid.contains(&e.id)).copied().collect();
                assert_eq!(incoming.len() as u32, fw.tiles[t].sort_n, "tile {t}: incoming list");
                let plan = reuse_plan(&gen, table.len(), incoming.len(), f);
                cmds += plan.len();
                let (dps_table, c1) = dps_pass_checked(&mut core, &gen, table, Parity::of(f as u64, 0));
                let c2 = full_sort_checked(&mut core, &gen, &incoming);
                let (sorted, _) = full_sort(&incoming, &sort_cfg);
                let c3 = merge_checked(&mut core, &dps_table, &sorted, true).cycles;
                rtl += c1 + c2 + c3;
                let of_mode = |m: Mode| plan.iter().filter(|c| c.mode == m).copied().collect::<Vec<_>>();
                let (dps, md) = (of_mode(Mode::Dps), of_mode(Mode::MergeDelete));
                let conv: Vec<Cmd> =
                    plan.iter().filter(|c| !matches!(c.mode, Mode::Dps | Mode::MergeDelete)).copied().collect();
                assert_eq!(conv, conventional_sort(incoming.len() as u64, c), "the plan's sort of the list");
                let (m1, m2, m3) = (batch_cycles(&dps, &lat), batch_cycles(&conv, &lat), batch_cycles(&md, &lat));
                model += m1 + m2 + m3;
                parts[1].1.add(m1, c1);
                parts[0].1.add(m2, c2);
                parts[2].1.add(m3, c3);
            }
            prev = drv.tables().map(|t| t.to_vec()).collect();
        }
        for (what, p) in &parts {
            if p.rtl > 0 {
                let e = 100.0 * (p.model as f64 - p.rtl as f64) / p.rtl as f64;
                eprintln!("  {what}: model {} RTL {} ({e:+.2}%)", p.model, p.rtl);
            }
        }
        (model, rtl, cmds)
    }

    fn check(label: &str, scene: &Scene, traj: &Trajectory) {
        let start = std::time::Instant::now();
        let (model, rtl, cmds) = compare(scene, traj);
        let secs = start.elapsed().as_secs_f64();
        eprintln!(
            "{label}: {rtl} RTL cycles cosimulated (with golden checks and the work driver) in {secs:.2} s"
        );
        let err = (model as f64 - rtl as f64) / rtl as f64;
        eprintln!("{label}: {cmds} commands, model {model} cycles, RTL {rtl} cycles, error {:+.2}%", 100.0 * err);
        assert!(rtl > 10_000, "{label}: too little work to validate ({rtl} cycles)");
        assert!(err.abs() < 0.05, "{label}: model {model} vs RTL {rtl} cycles ({:+.2}%)", 100.0 * err);
    }

    #[test]
    fn sorting_core_cycles_match_the_rtl_on_biker_crops() {
        let Some(path) =
            shared::shared_file_for_test("sorting_core_cycles_match_the_rtl_on_biker_crops", "scenes/biker.ply")
        else {
            return;
        };
        let (scene, _) = source::load_scene(path.to_str().unwrap(), false).unwrap();
        // The subject at the centre of a 256x256 view, orbiting.
        let spec = "orbit:radius=5,height=0,target=0/-1.6/0,start=0,fov=56.145,speed=4";
        let traj = trajectory::parse_trajectory(spec, source::robust_bounds(&scene), 3)
            .unwrap()
            .with_resolution(256, 256);
        check("biker 256x256, 3 frames", &scene, &traj);
    }

    #[test]
    fn sorting_core_cycles_match_the_rtl_on_a_synthetic_scene() {
        let (scene, _) = source::load_scene("synthetic:outdoor?gaussians=50k&seed=5", false).unwrap();
        let traj = trajectory::parse_trajectory("orbit:speed=8", source::robust_bounds(&scene), 3)
            .unwrap()
            .with_resolution(256, 192);
        check("synthetic 256x192, 3 frames", &scene, &traj);
    }
}
