//! The model charges preprocessing's DRAM traffic as the RTL Preprocessing Engine moves it.
//!
//! A small synthetic scene along an orbit (frame 0 from scratch, frames 1 and 2 reusing their
//! tables) runs twice: through golden's engine reference in scene mode (the RTL's counters
//! `RD_PRE` / `WR_PRE`, bit-exact with the RTL in cosimulation) and through the work-only
//! workload generator and the cycle model. The model's preprocessing bytes per frame (reads:
//! stages `preprocess` and `incoming detection`; writes: `feature table` and `incoming lists`)
//! must follow the engine's by the model's line rule: every AXI transfer the engine makes
//! (golden `pre_transfers`) moves the 64-byte DRAM lines it touches, where the counters count
//! the 8-byte beats it touches. At SH degree 3 with aligned bases that is, by hand: reads
//! `RD_PRE + 32 P` on a reuse frame (each previous 32-byte word a whole line) plus the
//! geometry streams' rounding to lines, writes `WR_PRE + 32 N + 56 T` (each 32-byte feature
//! word and each 4-byte length a whole line; list lines are whole lines already).

use neo_golden::engine::{
    beats_spanned, execute_frame, pre_traffic, pre_transfers, CaseScene, Counter, EngineCase, EngineSession,
    FrameRegs, Memory,
};
use neo_golden::hwpre::bake::geometry_bytes;
use neo_golden::pipeline::Strategy;
use neo_golden::{shared, source};
use neo_sim::config::SimConfig;
use neo_sim::driver::{generate, WorkloadSpec};
use neo_sim::latency::Latency;
use neo_sim::run::{simulate, Arch, RunOptions};
use neo_sim::traffic::Stage;

/// One frame as golden's engine reference ran it.
struct EngineFrame {
    from_scratch: bool,
    regs: FrameRegs,
    rd_pre: u64,
    wr_pre: u64,
    visible: Vec<u64>,
    lens: Vec<usize>,
}

#[test]
fn model_preprocessing_bytes_are_the_engines_transfers_in_lines() {
    let (scene, _) = source::load_scene("synthetic:outdoor?gaussians=6000&seed=3", false).unwrap();
    assert_eq!(scene.sh_degree, 3, "the by-hand rule below is for 192-byte SH records");
    let cfg = SimConfig::default();
    let (traj, ecfg) =
        EngineCase::Orbit.setup(&scene, &CaseScene::synthetic(), 3, [256, 128], &cfg.engine).unwrap();
    assert_eq!(ecfg, cfg.engine, "the orbit case keeps the model's engine");

    let mut session = EngineSession::from_scene(&scene, traj.clone(), &ecfg).unwrap();
    let mut mem = Memory::new();
    let mut engine = Vec::new();
    while let Some(plan) = session.next_frame(&mut mem).unwrap() {
        let out = execute_frame(&ecfg, &plan.regs, &mut mem).unwrap();
        let pre = plan.expected.pre.as_ref().expect("scene mode");
        let visible =
            pre.features.iter().enumerate().filter(|(_, w)| w.iter().any(|&b| b != 0)).map(|(i, _)| i as u64);
        engine.push(EngineFrame {
            from_scratch: plan.from_scratch,
            regs: plan.regs,
            rd_pre: out.counters.get(Counter::RdPre),
            wr_pre: out.counters.get(Counter::WrPre),
            visible: visible.collect(),
            lens: pre.lists.iter().map(Vec::len).collect(),
        });
    }
    assert_eq!(engine.len(), 3);
    assert!(engine[0].from_scratch && !engine[1].from_scratch && !engine[2].from_scratch);

    let spec = WorkloadSpec::new("synthetic", "orbit", Strategy::Neo);
    let wl = generate(&scene, &traj.frames, &traj.cuts, &spec, |_| {}).unwrap();
    let lat = Latency::from_file(&shared::workspace_root().join("reports/latency.json")).unwrap();
    let run = simulate(Arch::Neo, &cfg, &lat, &wl, RunOptions { ideal_memory: true }).unwrap();

    let line = cfg.dram.line_bytes as u64;
    let beat = ecfg.axi_data_bits as u64 / 8;
    assert_eq!((line, beat), (64, 8));
    for (f, e) in engine.iter().enumerate() {
        let fw = &wl.frames[f];
        // The same frame: the workload's visible Gaussians and lists are the engine's.
        assert_eq!(fw.from_scratch, e.from_scratch, "frame {f}");
        assert_eq!(fw.visible_ids().collect::<Vec<_>>(), e.visible, "frame {f}: visible Gaussians");
        let lens: Vec<usize> = fw.tiles.iter().map(|t| t.sort_n as usize).collect();
        assert_eq!(lens, e.lens, "frame {f}: incoming-list lengths");
        assert!(e.visible.len() > 1000, "frame {f}: a real frame ({} visible)", e.visible.len());
        assert_eq!(
            pre_traffic(&ecfg, &e.regs, &e.visible, e.lens.iter().copied()),
            (e.rd_pre, e.wr_pre),
            "frame {f}: the counters are golden's transfers in beats"
        );

        let stage = |s: &Stage| {
            let b = run.frames[f].stages.iter().find(|b| b.stage == s.name()).expect("every stage");
            (b.read_bytes, b.write_bytes)
        };
        let model_rd = stage(&Stage::Preprocess).0 + stage(&Stage::IncomingDetection).0;
        let model_wr = stage(&Stage::FeatureTable).1 + stage(&Stage::IncomingList).1;

        // The rule, transfer by transfer: lines for the model, beats for the counters.
        let (mut rd, mut wr) = (0, 0);
        pre_transfers(&ecfg, &e.regs, e.visible.iter().copied(), e.lens.iter().copied(), |t| {
            let d = line * beats_spanned(t.addr, t.bytes, line) - beat * beats_spanned(t.addr, t.bytes, beat);
            *if t.part.is_write() { &mut wr } else { &mut rd } += d;
        });
        assert_eq!((model_rd, model_wr), (e.rd_pre + rd, e.wr_pre + wr), "frame {f}");

        // The same rule by hand.
        let (n, p, tiles) = (fw.gaussians, e.visible.len() as u64, e.lens.len() as u64);
        let gb = geometry_bytes() as u64;
        let geo_rounding: u64 = (0..ecfg.pre_units)
            .map(|lane| {
                let (first, count) = ecfg.pre_lane_range(n as u32, lane);
                let (a, b) = (gb * first as u64, gb * count as u64);
                line * beats_spanned(a, b, line) - beat * beats_spanned(a, b, beat)
            })
            .sum();
        let prev = if e.from_scratch { 0 } else { 32 * p };
        assert_eq!(model_rd, e.rd_pre + prev + geo_rounding, "frame {f}: reads");
        assert_eq!(model_wr, e.wr_pre + 32 * n + 56 * tiles, "frame {f}: writes");
        let detection = stage(&Stage::IncomingDetection).0;
        assert_eq!(detection, if e.from_scratch { 0 } else { line * p }, "frame {f}: previous words");
    }
}
