//! `cargo bench -p neo-golden --bench ply_load [-- N]`: standard `.ply` load throughput.

fn main() {
    let n = std::env::args().skip(1).find_map(|a| a.parse::<usize>().ok()).unwrap_or(1_000_000);
    match neo_golden::ply::bench_load_throughput(n) {
        Ok((mbps, bytes)) => println!("ply load: {n} Gaussians (SH degree 3), {bytes} bytes: {mbps:.0} MB/s"),
        Err(e) => {
            eprintln!("ply load benchmark failed: {e}");
            std::process::exit(1);
        }
    }
}
