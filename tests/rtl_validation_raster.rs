//! The model's raster-core cycles per tile against the Verilated RTL: tiles of three consecutive
//! biker frames (256x256, the busiest tiles of each frame) through `neo_raster_core` with the test
//! bench's ideal memory (pixels and write-back checked against the golden pipeline), and the
//! model's [`neo_sim::arch::raster_tile_cycles`] on the same tiles with the `raster` timing read
//! from `reports/latency.json`, within 5% in total and per frame.
//!
//! In the root package, which depends on both `neo-sim` and `neo-tb` (sim never depends on tb).
//! The cosimulation compiles when `neo-tb` has its Verilated models ([`neo_tb::with_models!`]);
//! without them [`models_present`] prints SKIP, or fails when `CI` is set.

#[test]
fn models_present() {
    assert_eq!(
        neo_tb::require_models("models_present: the raster core's cycles against the model"),
        neo_tb::HAS_MODELS
    );
}

neo_tb::with_models! {
    use neo_golden::raster::raster_tile;
    use neo_golden::shared;
    use neo_golden::engine::segment_work;
    use neo_sim::arch::raster_tile_cycles_in_segments;
    use neo_sim::latency::Latency;
    use neo_tb::core::MemTiming;
    use neo_tb::raster::{biker_tiles, RasterCore};

    #[test]
    fn raster_core_cycles_match_the_rtl_on_biker_tiles_of_three_frames() {
        let name = "raster_core_cycles_match_the_rtl_on_biker_tiles_of_three_frames";
        let Some(path) = shared::shared_file_for_test(name, "scenes/biker.ply") else {
            return;
        };
        let lat = Latency::from_file(&shared::workspace_root().join("reports/latency.json")).unwrap();
        let rt = lat.raster.clone();
        assert!(
            rt.pixel_write_cycles > 0 && rt.load_cycles_per_entry > 0.0,
            "latency.json lacks raster.core: {rt:?}"
        );
        let cfg = neo_tb::config();
        let (fmt, rc) = (cfg.feature_format(), cfg.raster_config());
        let mut core = RasterCore::new(&cfg, 0x5eed, MemTiming::IDEAL);
        let mut frames = [(0u64, 0f64); 3];
        for tile in biker_tiles(&path, 256, 3, 3) {
            let rtl = core.run(&tile.case, &tile.want).cycles;
            let feats: Vec<_> =
                tile.case.table.iter().filter_map(|e| tile.case.features.get(&e.id).copied()).collect();
            let r = raster_tile(&feats, &fmt, tile.case.tile[0], tile.case.tile[1], 256, 256, &rc);
            let routed: Vec<u32> = r.work.iter().map(|w| w.routed).collect();
            let (sum_r, sum_p) =
                r.work.iter().fold((0u64, 0u64), |(a, b), w| (a + w.routed as u64, b + w.processed as u64));
            let ratio = if sum_r == 0 { 1.0 } else { sum_p as f64 / sum_r as f64 };
            let index: Vec<bool> =
                tile.case.table.iter().map(|e| tile.case.features.contains_key(&e.id)).collect();
            let segments = segment_work(&index, &r.bitmaps, &r.work, cfg.raster_feature_buffer);
            let (model, _) = raster_tile_cycles_in_segments(
                &routed,
                ratio,
                feats.len() as u32,
                tile.case.table.len() as u32,
                &rt,
                cfg.raster_itus as u32,
                cfg.raster_scus as u32,
                true,
                Some(&segments),
            );
            eprintln!(
                "frame {} tile {:?}: {} entries, RTL {rtl} cycles, model {model:.0} ({:+.2}%)",
                tile.frame,
                tile.case.tile,
                tile.case.table.len(),
                100.0 * (model - rtl as f64) / rtl as f64
            );
            frames[tile.frame].0 += rtl;
            frames[tile.frame].1 += model;
        }
        for (f, (rtl, model)) in frames.iter().enumerate() {
            let err = (model - *rtl as f64) / *rtl as f64;
            eprintln!("frame {f}: RTL {rtl} cycles, model {model:.0} ({:+.2}%)", 100.0 * err);
            assert!(*rtl > 10_000, "frame {f}: too little work ({rtl} cycles)");
            assert!(err.abs() < 0.05, "frame {f}: model {model:.0} vs RTL {rtl} cycles ({:+.2}%)", 100.0 * err);
        }
    }
}
