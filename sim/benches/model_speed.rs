//! Speed of the cycle model against its targets (a benchmark, not a test):
//! - the model alone simulates one QHD frame of a 1M-Gaussian workload in under 1 s;
//! - 60 QHD frames including the golden (work-only) workload generation in under 2 min.
//!
//! `cargo bench -p neo-sim --bench model_speed` (set `NEO_BENCH_FRAMES` for fewer frames).

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use neo_golden::pipeline::Strategy;
use neo_golden::{shared, source, synthetic, trajectory};
use neo_sim::config::SimConfig;
use neo_sim::driver::{generate, WorkloadSpec};
use neo_sim::latency::Latency;
use neo_sim::run::{simulate, Arch, RunOptions};

/// The system allocator, counting live and peak heap bytes (the model's own memory).
struct Counting;

static LIVE: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, l: Layout) -> *mut u8 {
        // SAFETY: forwarded to the system allocator with the caller's layout.
        let p = unsafe { System.alloc(l) };
        if !p.is_null() {
            let live = LIVE.fetch_add(l.size(), Ordering::Relaxed) + l.size();
            PEAK.fetch_max(live, Ordering::Relaxed);
        }
        p
    }

    unsafe fn dealloc(&self, p: *mut u8, l: Layout) {
        // SAFETY: `p` came from `alloc` with this layout.
        unsafe { System.dealloc(p, l) };
        LIVE.fetch_sub(l.size(), Ordering::Relaxed);
    }
}

#[global_allocator]
static ALLOC: Counting = Counting;

fn rss_mb(key: &str) -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with(key))
                .and_then(|l| l.split_whitespace().nth(1)?.parse::<f64>().ok())
        })
        .map_or(f64::NAN, |kb| kb / 1024.0)
}

fn main() {
    let frames: usize = std::env::var("NEO_BENCH_FRAMES").ok().and_then(|v| v.parse().ok()).unwrap_or(60);
    let t = Instant::now();
    let (scene, _) = source::load_scene(synthetic::DEFAULT_SCENE, false).expect("default scene");
    println!(
        "scene {} ({} Gaussians) in {:.1} s",
        synthetic::DEFAULT_SCENE,
        scene.len(),
        t.elapsed().as_secs_f64()
    );
    let traj = trajectory::parse_trajectory("orbit", source::robust_bounds(&scene), frames)
        .expect("orbit")
        .with_resolution(2560, 1440);
    let lat =
        Latency::from_file(&shared::workspace_root().join("reports/latency.json")).expect("latency.json");
    let cfg = SimConfig::default();

    let t = Instant::now();
    let wl = generate(
        &scene,
        &traj.frames,
        &traj.cuts,
        &WorkloadSpec::new("default", "orbit", Strategy::Neo),
        |_| {},
    )
    .expect("workload");
    let gen = t.elapsed().as_secs_f64();
    println!(
        "workload: {frames} QHD frames in {gen:.1} s ({:.2} s/frame), {:.1} MB held; peak RSS so far {:.0} MB",
        gen / frames as f64,
        wl.heap_bytes() as f64 / 1e6,
        rss_mb("VmHWM:")
    );
    let mut model_total = 0.0;
    for arch in [Arch::Neo, Arch::Gscore(16), Arch::Gpu] {
        let heap_before = LIVE.load(Ordering::Relaxed);
        PEAK.store(heap_before, Ordering::Relaxed);
        let t = Instant::now();
        let r = simulate(arch, &cfg, &lat, &wl, RunOptions::default()).expect("model");
        let s = t.elapsed().as_secs_f64();
        if arch == Arch::Neo {
            model_total = s;
            println!(
                "model neo memory: heap {:.0} MB before the run (scene, workload), peak {:.0} MB during it: the model allocates {:.1} MB at most",
                heap_before as f64 / 1e6,
                PEAK.load(Ordering::Relaxed) as f64 / 1e6,
                (PEAK.load(Ordering::Relaxed) - heap_before) as f64 / 1e6
            );
        }
        println!(
            "model {:9}: {:.3} s/frame ({} frames, {:.1} FPS simulated, {:.2} M DRAM requests/frame)",
            r.arch,
            s / frames as f64,
            frames,
            r.fps,
            r.traffic.total_requests() as f64 / frames as f64 / 1e6
        );
    }
    // The cost of the FR-FCFS read queue, measured in this run.
    let mut in_order = cfg.clone();
    in_order.dram.read_queue = 0;
    let t = Instant::now();
    let r = simulate(Arch::Neo, &in_order, &lat, &wl, RunOptions::default()).expect("model");
    let s = t.elapsed().as_secs_f64();
    println!(
        "model neo, DRAM reads in issue order: {:.3} s/frame ({:.1} FPS simulated); FR-FCFS costs {:.2}x the model time",
        s / frames as f64,
        r.fps,
        model_total / s
    );
    let per_frame = model_total / frames as f64;
    println!(
        "target: model < 1 s per QHD frame: {:.3} s -> {}",
        per_frame,
        if per_frame < 1.0 { "meets" } else { "MISSES" }
    );
    let total = gen + model_total;
    let scaled = total * 60.0 / frames as f64;
    println!(
        "target: 60 QHD frames with workload generation < 120 s: {scaled:.0} s (generation {:.0} s + model {:.0} s){} -> {}",
        gen * 60.0 / frames as f64,
        model_total * 60.0 / frames as f64,
        if frames == 60 { "" } else { " (scaled from the frames run)" },
        if scaled < 120.0 { "meets" } else { "MISSES" }
    );
    println!("memory: peak RSS {:.0} MB (current {:.0} MB)", rss_mb("VmHWM:"), rss_mb("VmRSS:"));
}
