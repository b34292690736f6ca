//! neo's DRAM model against Ramulator 1 (LPDDR4-3200, 4 channels, trace mode) on the request
//! streams of `../shared/reference/ramulator/` (see its README): for every stream, bandwidth
//! within 5%, mean read latency within 10% and row-hit rate within 5 points.
//!
//! The reference is read in place (never copied). Missing or malformed reference files fail the
//! test when `CI` is set and skip it otherwise, naming the file. A stream whose request counts
//! differ from the ones Ramulator recorded is a stale reference: reported, not compared.

use std::path::{Path, PathBuf};

use neo_golden::shared::shared_file_for_test;
use neo_sim::config::DramConfig;
use neo_sim::dram_stream::{read_stream, run_stream, StreamRun};
use proptest::prelude::*;
use serde_json::Value;

const REF: &str = "reference/ramulator";

/// Fails (in CI) or skips with a message naming `path`.
fn bad_reference(test: &str, path: &Path, why: &str) {
    neo_golden::shared::skip_or_fail(test, &format!("reference file {} is unusable: {why}", path.display()));
}

/// The Ramulator figures of one stream.
struct Reference {
    name: String,
    trace: PathBuf,
    requests: u64,
    reads: u64,
    writes: u64,
    bandwidth_gbs: f64,
    dram_cycles: u64,
    latency_ns: Option<f64>,
    hit_rate: f64,
    hits: u64,
    misses: u64,
    conflicts: u64,
}

fn load(test: &str) -> Option<Vec<Reference>> {
    let results = shared_file_for_test(test, &format!("{REF}/results.json"))?;
    let dir = results.parent().expect("results.json has a parent").to_path_buf();
    let text = match std::fs::read_to_string(&results) {
        Ok(t) => t,
        Err(e) => {
            bad_reference(test, &results, &e.to_string());
            return None;
        }
    };
    let parsed = (|| -> Result<Vec<Reference>, String> {
        let v: Value = serde_json::from_str(&text).map_err(|e| e.to_string())?;
        let streams = v["streams"].as_array().ok_or("no `streams` array")?;
        let u = |s: &Value, k: &str| s[k].as_u64().ok_or(format!("stream field `{k}` is not an integer"));
        streams
            .iter()
            .map(|s| {
                let name = s["name"].as_str().ok_or("a stream without `name`")?.to_string();
                let trace = s["trace_file"].as_str().ok_or(format!("{name}: no `trace_file`"))?;
                let requests = u(s, "requests")?;
                let hits = u(s, "row_hits")?;
                Ok(Reference {
                    trace: dir.join(trace),
                    requests,
                    reads: u(s, "reads")?,
                    dram_cycles: u(s, "dram_cycles")?,
                    writes: u(s, "writes")?,
                    bandwidth_gbs: s["bandwidth_gbs"]
                        .as_f64()
                        .ok_or(format!("{name}: no `bandwidth_gbs`"))?,
                    latency_ns: s["read_latency_avg_ns"].as_f64(),
                    hit_rate: hits as f64 / requests.max(1) as f64,
                    hits,
                    misses: u(s, "row_misses")?,
                    conflicts: u(s, "row_conflicts")?,
                    name,
                })
            })
            .collect()
    })();
    match parsed {
        Ok(r) if !r.is_empty() => Some(r),
        Ok(_) => {
            bad_reference(test, &results, "no streams");
            None
        }
        Err(e) => {
            bad_reference(test, &results, &e);
            None
        }
    }
}

fn row(name: &str, r: &Reference, n: &StreamRun) -> String {
    let lat = |x: Option<f64>| x.map_or("n/a".to_string(), |v| format!("{v:.1}"));
    format!(
        "{name:16} cycles {:8} vs {:8}  GB/s {:6.2} vs {:6.2} ({:+5.1}%)  lat ns {:>7} vs {:>7}  hits {:5.1}% vs {:5.1}%  h/m/c {}/{}/{} vs {}/{}/{}",
        n.dram_cycles,
        r.dram_cycles,
        n.bandwidth_gbs,
        r.bandwidth_gbs,
        (n.bandwidth_gbs / r.bandwidth_gbs - 1.0) * 100.0,
        lat(n.read_latency_avg_ns),
        lat(r.latency_ns),
        n.row_hit_rate() * 100.0,
        r.hit_rate * 100.0,
        n.row_hits,
        n.row_misses,
        n.row_conflicts,
        r.hits,
        r.misses,
        r.conflicts
    )
}

#[test]
fn dram_model_matches_ramulator_on_every_stream() {
    let test = "dram_model_matches_ramulator_on_every_stream";
    let Some(refs) = load(test) else { return };
    let cfg = DramConfig::default();
    let mut failures = Vec::new();
    for r in &refs {
        let reqs = match read_stream(&r.trace) {
            Ok(q) => q,
            Err(e) => {
                bad_reference(test, &r.trace, &e.to_string());
                return;
            }
        };
        let writes = reqs.iter().filter(|q| q.write).count() as u64;
        let (n, w) = (reqs.len() as u64, writes);
        if (n, n - w, w) != (r.requests, r.reads, r.writes) {
            failures.push(format!(
                "{}: stale reference: {} holds {n} requests ({} reads, {w} writes), results.json recorded {} ({} reads, {} writes)",
                r.name,
                r.trace.display(),
                n - w,
                r.requests,
                r.reads,
                r.writes
            ));
            continue;
        }
        let run = run_stream(&cfg, &reqs);
        let line = row(&r.name, r, &run);
        eprintln!("{line}");
        let mut off = Vec::new();
        let bw = run.bandwidth_gbs / r.bandwidth_gbs - 1.0;
        if bw.abs() > 0.05 {
            off.push(format!("bandwidth {:+.1}% (limit 5%)", bw * 100.0));
        }
        match (run.read_latency_avg_ns, r.latency_ns) {
            (Some(a), Some(b)) if (a / b - 1.0).abs() > 0.10 => {
                off.push(format!("read latency {:+.1}% (limit 10%)", (a / b - 1.0) * 100.0))
            }
            (Some(_), None) | (None, Some(_)) => off.push("reads in one run only".into()),
            _ => {}
        }
        let dh = (run.row_hit_rate() - r.hit_rate) * 100.0;
        if dh.abs() > 5.0 {
            off.push(format!("row-hit rate {dh:+.1} points (limit 5)"));
        }
        if !off.is_empty() {
            failures.push(format!("{}: {}", r.name, off.join(", ")));
        }
    }
    assert!(failures.is_empty(), "streams off Ramulator:\n{}", failures.join("\n"));
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    /// The parser never panics: any text is a stream or an error naming a line of it (the
    /// file as a whole, line 0, when it has no line: an empty stream).
    #[test]
    fn stream_parser_never_panics(text in "(0[xX])?[0-9a-fA-F ,xRW\\t\u{e9}-]{0,30}(\n[ 0-9a-fxRW]{0,20}){0,4}") {
        match neo_sim::dram_stream::parse_stream(&text, Path::new("fuzz.trace")) {
            Ok(reqs) => prop_assert_eq!(reqs.len(), text.lines().count()),
            Err(e) => {
                let lines = text.lines().count();
                let named = if lines == 0 { e.line == 0 } else { e.line >= 1 && e.line <= lines };
                prop_assert!(named, "{}", e);
                prop_assert!(e.to_string().starts_with("fuzz.trace:"));
            }
        }
    }

    /// Arbitrary bytes (any UTF-8) never panic the parser either.
    #[test]
    fn stream_parser_never_panics_on_any_string(text in any::<String>()) {
        let _ = neo_sim::dram_stream::parse_stream(&text, Path::new("fuzz.trace"));
    }

    /// Every well-formed line parses back to what was written.
    #[test]
    fn written_lines_parse_back(addr in any::<u64>(), write in any::<bool>()) {
        let line = format!("0x{addr:08x} {}", if write { 'W' } else { 'R' });
        let r = neo_sim::dram_stream::parse_line(&line).unwrap();
        prop_assert_eq!((r.addr, r.write), (addr, write));
    }
}
