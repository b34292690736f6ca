//! `neo gen`: writes the generated Verilog (one file per module), checks a directory against
//! fresh output, and reports Yosys synthesis statistics.

use anyhow::{bail, Context, Result};
use clap::Args;
use neo_gen::output::{check_dir, write_dir};
use neo_gen::report::{
    table, topology_reports, tree, unit_reports, SynthReport, TopologyReport, UnitReport, YOSYS_COMMAND,
};
use neo_gen::units::bsu;
use neo_gen::EngineConfig;
use std::path::PathBuf;

/// Arguments of `neo gen`.
#[derive(Args)]
pub struct GenArgs {
    /// JSON generator configuration (any subset of the fields; default: the paper's core).
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// Output directory.
    #[arg(long, default_value = "hdl")]
    pub out: PathBuf,
    /// Compare OUT against fresh output instead of writing; fails listing differing files.
    #[arg(long)]
    pub check: bool,
    /// Synthesize every top with Yosys (the raster core and `neo_engine` hierarchically), print
    /// cells / flip-flops / depth and the engine's hierarchy (instances, Verilog lines, cells,
    /// totals per part), write the JSON report. Units whose Verilog is unchanged since the
    /// report at --report are taken from it.
    #[arg(long)]
    pub stats: bool,
    /// With --stats: synthesize every top again (ignore the previous report).
    #[arg(long)]
    pub fresh: bool,
    /// With --stats: also synthesize the BSU of every topology.
    #[arg(long)]
    pub all_topologies: bool,
    /// With --stats: where to write the JSON report.
    #[arg(long, default_value = "reports/synth.json")]
    pub report: PathBuf,
}

/// Runs `neo gen`.
pub fn run(a: GenArgs) -> Result<()> {
    let cfg = match &a.config {
        Some(p) => EngineConfig::from_json_file(p)?,
        None => EngineConfig::default(),
    };
    let files = neo_gen::try_generate(&cfg)?;
    if a.check {
        if a.out.exists() && !a.out.is_dir() {
            bail!("{}: --out is not a directory", a.out.display());
        }
        if !a.out.exists() {
            let config = a.config.as_ref().map(|p| format!(" --config {}", p.display())).unwrap_or_default();
            bail!(
                "{}: the directory does not exist; `neo gen{config} --out {}` writes it",
                a.out.display(),
                a.out.display()
            );
        }
        let diffs = check_dir(&a.out, &files).with_context(|| format!("reading {}", a.out.display()))?;
        if !diffs.is_empty() {
            let list: Vec<String> =
                diffs.iter().map(|d| format!("  {}", a.out.join(d.to_string()).display())).collect();
            let config = a.config.as_ref().map(|p| format!(" --config {}", p.display())).unwrap_or_default();
            bail!(
                "{} is out of date ({} file(s)); run `neo gen{config} --out {}`:\n{}",
                a.out.display(),
                diffs.len(),
                a.out.display(),
                list.join("\n")
            );
        }
        println!("{}: {} files up to date", a.out.display(), files.len());
    } else {
        let written = write_dir(&a.out, &files).with_context(|| format!("writing {}", a.out.display()))?;
        println!("wrote {} files to {}: {}", written.len(), a.out.display(), written.join(" "));
    }
    if a.stats {
        let previous: Option<SynthReport> = if a.fresh {
            None
        } else {
            std::fs::read_to_string(&a.report).ok().and_then(|t| serde_json::from_str(&t).ok())
        };
        let t0 = std::time::Instant::now();
        let progress = |u: &neo_gen::report::UnitReport, reused: bool| {
            let how = if reused { "unchanged, from the previous report" } else { "synthesized" };
            eprintln!("  {:<24} {how} ({:.0} s)", u.unit, u.seconds);
        };
        let units = unit_reports(&cfg, previous.as_ref(), &progress)?;
        eprintln!("synthesis: {:.0} s", t0.elapsed().as_secs_f64());
        let bsu_topologies = if a.all_topologies {
            topology_reports(&cfg)?
        } else {
            kept_topologies(previous.as_ref(), &units)
        };
        let report = SynthReport { config: cfg, command: YOSYS_COMMAND.to_string(), units, bsu_topologies };
        print!("{}", table(&report));
        println!();
        print!("{}", tree::build(&report.config, Some(&report))?.text(&report.config));
        if let Some(dir) = a.report.parent() {
            std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        }
        let json = serde_json::to_string_pretty(&report)?;
        std::fs::write(&a.report, json + "\n").with_context(|| format!("writing {}", a.report.display()))?;
        println!("report: {}", a.report.display());
    }
    Ok(())
}

/// Without `--all-topologies`: the previous report's BSU topologies, kept when its BSU's
/// Verilog is the same as now (same configuration, same generator), else none (with a note to
/// synthesize them again).
fn kept_topologies(previous: Option<&SynthReport>, units: &[UnitReport]) -> Vec<TopologyReport> {
    let Some(prev) = previous.filter(|p| !p.bsu_topologies.is_empty()) else { return Vec::new() };
    fn bsu_hash(units: &[UnitReport]) -> Option<&str> {
        units.iter().find(|u| u.unit == bsu::NAME).map(|u| u.verilog_hash.as_str())
    }
    if matches!((bsu_hash(&prev.units), bsu_hash(units)), (Some(a), Some(b)) if a == b) {
        eprintln!("  {:<24} the BSU is unchanged: kept from the previous report", "BSU topologies");
        prev.bsu_topologies.clone()
    } else {
        eprintln!("  {:<24} the BSU changed: dropped (--all-topologies synthesizes them)", "BSU topologies");
        Vec::new()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `neo gen --stats` without `--all-topologies` keeps the committed report's topologies
    /// while the BSU is unchanged, and drops them when it changed.
    #[test]
    fn topologies_are_kept_only_while_the_bsu_is_unchanged() {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/reports/synth.json");
        let text = std::fs::read_to_string(path).expect("reports/synth.json");
        let prev: SynthReport = serde_json::from_str(&text).expect("a synthesis report");
        assert!(!prev.bsu_topologies.is_empty(), "the committed report has the BSU topologies");
        let kept = kept_topologies(Some(&prev), &prev.units);
        assert_eq!(kept.len(), prev.bsu_topologies.len());
        let mut units = prev.units.clone();
        let bsu = units.iter_mut().find(|u| u.unit == bsu::NAME).expect("the BSU's row");
        bsu.verilog_hash.push('x');
        assert!(kept_topologies(Some(&prev), &units).is_empty());
        assert!(kept_topologies(None, &prev.units).is_empty());
    }
}
