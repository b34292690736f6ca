//! `neo artifact`: the official artifact simulator's accounting of `poc.trace` frames (the lines
//! of each of its request names), the waterfall from its bytes to neo's way of charging them,
//! and optionally its timing on neo's DRAM model (docs/cycle-model.md section 5).

use anyhow::Result;
use clap::Args;
use neo_golden::hwpre::bake;
use neo_golden::pipeline::Formats;
use neo_sim::artifact::poc::{read_poc_trace, PocFrame};
use neo_sim::artifact::timing::artifact_timing_with;
use neo_sim::artifact::waterfall::{waterfall, NeoSizes};
use neo_sim::artifact::{artifact_lines, ArtifactSizes, Request, Rules};
use neo_sim::config::SimConfig;
use neo_sim::traffic::{Dir, Stage};
use std::fmt::Write as _;
use std::path::PathBuf;

/// Arguments of `neo artifact`.
#[derive(Args)]
pub struct ArtifactArgs {
    /// `poc.trace` files (`neo frames --trace` or `neo simulate --trace` write them). A trace
    /// that reuses tables reads its visible Gaussians' previous feature words in the
    /// waterfall's last step (the RTL Preprocessing Engine's incoming detection).
    #[arg(required = true)]
    pub traces: Vec<PathBuf>,
    /// Also time each frame, and each step of the waterfall, with the artifact's structure on
    /// neo's DRAM model (about a second per step and frame).
    #[arg(long)]
    pub time: bool,
    /// Model configuration (JSON; its `dram` section and frame-buffer pixel size are used).
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// SH degree of the traced scene: neo's SH bytes per Gaussian follow it (the baked
    /// format's), unless the configuration's `sizes` sets them.
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u8).range(0..=3))]
    pub sh_degree: u8,
}

/// Runs `neo artifact`.
pub fn run(a: ArtifactArgs) -> Result<()> {
    let cfg = match &a.config {
        Some(p) => SimConfig::from_file(p)?,
        None => SimConfig::default(),
    };
    let sizes = ArtifactSizes::default();
    let neo = NeoSizes {
        geometry: cfg.sizes.gaussian_geometry_bytes.unwrap_or(bake::geometry_bytes()) as u64,
        sh: cfg.sizes.sh_bytes_of_degree(a.sh_degree),
        feature: Formats::artifact(sizes.global_chunk as usize)?.feature.bytes_per_entry() as u64,
        pixel: cfg.sizes.pixel_bytes as u64,
        sh_degree: a.sh_degree,
    };
    for path in &a.traces {
        let f = read_poc_trace(path)?;
        let lines = artifact_lines(&f, &sizes);
        println!(
            "{} ({}x{}, {} Gaussians, {} tiles)",
            path.display(),
            f.width,
            f.height,
            f.culled.len(),
            f.tiles.len()
        );
        println!("artifact's 64-byte lines by request name:");
        for r in Request::ALL {
            println!("  {:<36} {} {:>10}", r.name(), if r.is_write() { "W" } else { "R" }, lines.get(r));
        }
        println!("  {:<36}   {:>10} read, {} written", "total", lines.reads(), lines.writes());
        let cycles: Vec<u64> = if a.time {
            (0..Rules::STEPS.len())
                .map(|k| artifact_timing_with(&f, &sizes, &Rules::step(k, &neo), &cfg.dram).core_cycles)
                .collect()
        } else {
            Vec::new()
        };
        println!("{}", waterfall_table(&f, &sizes, &neo, &cycles));
        if let Some(c) = cycles.first() {
            println!(
                "the artifact's timing on neo's DRAM model ({}): {c} core cycles at 1 GHz ({:.1} FPS)\n",
                cfg.dram.name,
                1e9 / *c as f64
            );
        }
    }
    Ok(())
}

/// The waterfall as a text table, MB (1e6 bytes) by neo stage, read + written.
/// The waterfall as a text table; `cycles` (one per step, or empty) adds the timing column.
fn waterfall_table(f: &PocFrame, sizes: &ArtifactSizes, neo: &NeoSizes, cycles: &[u64]) -> String {
    let steps = waterfall(f, sizes, neo);
    let mut s =
        String::from("from the artifact's bytes to neo's charging (MB read + written, cumulative):\n");
    let _ = write!(s, "  {:<60} {:>9}", "step", "total");
    if !cycles.is_empty() {
        let _ = write!(s, " {:>10}", "Mcycles");
    }
    for st in Stage::ALL {
        let _ = write!(s, " {:>10}", st.short_name());
    }
    s.push('\n');
    let mb = |b: u64| b as f64 / 1e6;
    for (k, step) in steps.iter().enumerate() {
        let _ = write!(s, "  {:<60} {:>9.3}", step.name, mb(step.bytes.total()));
        if let Some(c) = cycles.get(k) {
            let _ = write!(s, " {:>10.3}", *c as f64 / 1e6);
        }
        for st in Stage::ALL {
            let _ =
                write!(s, " {:>10.3}", mb(step.bytes.get(st, Dir::Read) + step.bytes.get(st, Dir::Write)));
        }
        s.push('\n');
    }
    s
}
