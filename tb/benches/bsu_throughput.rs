//! BSU cosimulation throughput: random 16-entry vectors through the Verilated `neo_bsu` at full
//! rate, every output compared with golden `Network::apply`. Target: >= 1M vectors/s.
//!
//! `cargo bench -p neo-tb --bench bsu_throughput [-- VECTORS]` (default 2M; `NEO_SEED` fixes the seed).

#[cfg(neo_has_verilator)]
fn main() {
    let vectors = std::env::args().skip(1).find_map(|a| a.parse::<u64>().ok()).unwrap_or(2_000_000);
    let seed = neo_tb::rng::test_seed("bsu_throughput");
    let cfg = neo_tb::config();
    // Warm-up (page faults, caches), then the measured run.
    neo_tb::bsu::throughput(&cfg, 20_000, seed ^ 1, 1);
    let threads = std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1);
    for k in [1, threads] {
        let t = neo_tb::bsu::throughput(&cfg, vectors, seed, k);
        println!(
            "bsu_throughput: {k} model(s): {} vectors checked in {:.3} s: {:.2} M vectors/s, {:.2} Mcycles/s \
             (target >= 1 M vectors/s)",
            t.vectors,
            t.seconds,
            t.vectors_per_s() / 1e6,
            t.mcycles_per_s()
        );
        if k == threads {
            break;
        }
    }
}

#[cfg(not(neo_has_verilator))]
fn main() {
    println!("bsu_throughput: SKIP (neo-tb built without Verilator)");
}
