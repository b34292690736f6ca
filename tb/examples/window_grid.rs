//! The raster-core grid of `reports/latency.json` (table lengths x subtile bits per Gaussian,
//! ideal memory, every tile checked against golden) on the default core and on the same core
//! with a reorder window of `W` entries, side by side (docs/cycle-model.md, "Reorder window").
//!
//! `cargo run --release -p neo-tb --example window_grid -- [W] [SEGMENTS]` (default 64 and 8;
//! `W` a power of two in 4..=4096; the longest table holds `SEGMENTS` feature-buffer segments).
//! The core with the window is built at run time (about 30 s at 64 entries).

use neo_tb::core::MemTiming;
use neo_tb::latency::{raster_grid_lengths, RASTER_GRID_BITS};
use neo_tb::raster::{measure_grid, measure_grid_on, RasterCore};

fn main() {
    if let Err(e) = run() {
        eprintln!("window_grid: {e}");
        std::process::exit(1);
    }
}

fn run() -> Result<(), String> {
    let arg = std::env::args().nth(1).unwrap_or_else(|| "64".into());
    let w: usize = arg.parse().map_err(|_| format!("window '{arg}': not a number"))?;
    let base = neo_gen::EngineConfig::default();
    let cfg = neo_gen::EngineConfig { raster_window: w, ..base.clone() };
    cfg.validate().map_err(|e| format!("window {w}: {e}"))?;
    let segs_arg = std::env::args().nth(2).unwrap_or_else(|| "8".into());
    let segs: u64 = segs_arg.parse().map_err(|_| format!("segments '{segs_arg}': not a number"))?;
    let f = base.raster_feature_buffer as u64;
    // The latency report's grid, its longest table `segs` segments long.
    let mut lengths = raster_grid_lengths(f);
    *lengths.last_mut().expect("a longest table") = segs.max(3) * f;
    let bits = RASTER_GRID_BITS;
    let plain = measure_grid(&base, 7, &lengths, &bits);
    let t0 = std::time::Instant::now();
    let mut core = RasterCore::build(&cfg, 7, MemTiming::IDEAL)?;
    println!("core with a {w}-entry window: built in {:.1} s", t0.elapsed().as_secs_f64());
    let windowed = measure_grid_on(&mut core, &cfg, &lengths, &bits);
    println!("bits entries | cycles: plain window (diff)     | last read: plain window");
    for (p, q) in plain.iter().zip(&windowed) {
        let diff = q.cycles as f64 - p.cycles as f64;
        println!(
            "{:>4} {:>7} | {:>7} {:>7} ({:+6.0}, {:+5.1}%) | {:>7} {:>7}",
            p.bits_per_gaussian,
            p.entries,
            p.cycles,
            q.cycles,
            diff,
            100.0 * diff / p.cycles.max(1) as f64,
            p.load_cycles,
            q.load_cycles
        );
    }
    Ok(())
}
