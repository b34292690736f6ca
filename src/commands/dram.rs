//! `neo dram`: the DRAM model alone on a request stream (Ramulator's DRAM-trace format), fed
//! as Ramulator's `--mode=dram` feeds it.

use anyhow::Result;
use clap::Args;
use neo_sim::config::SimConfig;
use neo_sim::dram_stream::{check_addresses, read_stream, run_stream};
use std::path::PathBuf;

/// Arguments of `neo dram`.
#[derive(Args)]
pub struct DramArgs {
    /// Request stream: one `0xADDR R|W` per line (Ramulator's DRAM-trace format).
    #[arg(long)]
    pub stream: PathBuf,
    /// Model configuration (JSON; its `dram` section is used, missing fields keep their defaults).
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// Print JSON instead of text.
    #[arg(long)]
    pub json: bool,
}

/// Runs `neo dram`.
pub fn run(a: DramArgs) -> Result<()> {
    let cfg = match &a.config {
        Some(p) => SimConfig::from_file(p)?,
        None => SimConfig::default(),
    };
    let reqs = read_stream(&a.stream)?;
    check_addresses(&cfg.dram, &reqs, &a.stream)?;
    let r = run_stream(&cfg.dram, &reqs);
    if a.json {
        let mut v = serde_json::to_value(&r)?;
        v["stream"] = serde_json::json!(a.stream.display().to_string());
        v["dram"] = serde_json::json!(cfg.dram.name);
        v["row_hit_rate"] = serde_json::json!(r.row_hit_rate());
        println!("{}", serde_json::to_string_pretty(&v)?);
    } else {
        println!("stream        {} ({})", a.stream.display(), cfg.dram.name);
        println!("requests      {} ({} reads, {} writes)", r.requests, r.reads, r.writes);
        println!("time          {} DRAM cycles", r.dram_cycles);
        println!("bandwidth     {:.2} GB/s", r.bandwidth_gbs);
        match r.read_latency_avg_ns {
            Some(l) => println!("read latency  {l:.1} ns mean"),
            None => println!("read latency  n/a (no reads)"),
        }
        println!(
            "row hits      {} ({:.1}%), misses {}, conflicts {}",
            r.row_hits,
            r.row_hit_rate() * 100.0,
            r.row_misses,
            r.row_conflicts
        );
    }
    Ok(())
}
