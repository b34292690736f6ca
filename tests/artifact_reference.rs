//! neo's restatement of the official artifact simulator's DRAM accounting
//! (`neo_sim::artifact`) against the artifact's own counters, `../shared/reference/artifact/`
//! (see its README): the reference's `neo frames --trace` commands are rerun, and on every frame
//! the lines of each of the artifact's 15 request names must be equal, and the timing
//! restatement (`neo_sim::artifact::timing`) must issue exactly those requests, in a number of
//! core cycles within 5% of the artifact's (docs/cycle-model.md section 5).
//!
//! The reference is read in place. Missing or malformed, it fails the test when `CI` is set and
//! skips it otherwise, naming the file. A regenerated trace whose statistics differ from the
//! recorded ones means the reference is stale: that run is reported and not compared, and the
//! test fails when no run is left to compare.

use std::path::{Path, PathBuf};
use std::process::Command;

use neo_golden::hwpre::ShPrecision;
use neo_golden::shared::{shared_dir_path, shared_file_for_test};
use neo_sim::artifact::poc::{read_poc_trace, PocStats};
use neo_sim::artifact::timing::{artifact_timing, artifact_timing_with};
use neo_sim::artifact::waterfall::{waterfall, NeoSizes};
use neo_sim::artifact::{artifact_lines, ArtifactSizes, Request, Rules};
use neo_sim::config::DramConfig;
use neo_sim::traffic::{Dir, Stage};
use serde_json::Value;

const TEST: &str = "artifact_lines_match_the_artifact";

/// The reference's `results.json`, parsed; `None` when skipped.
fn reference() -> Option<(PathBuf, Value)> {
    let path = shared_file_for_test(TEST, "reference/artifact/results.json")?;
    let text =
        std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: cannot read: {e}", path.display()));
    let v: Value =
        serde_json::from_str(&text).unwrap_or_else(|e| panic!("{}: malformed JSON: {e}", path.display()));
    assert_eq!(v["schema"], "neo-artifact-reference/1", "{}: unknown schema {}", path.display(), v["schema"]);
    Some((path, v))
}

/// Splits a shell command line with single-quoted words (the form the reference records).
fn shell_words(cmd: &str) -> Vec<String> {
    let mut words = Vec::new();
    let mut cur = String::new();
    let mut quoted = false;
    let mut any = false;
    for c in cmd.chars() {
        match c {
            '\'' => {
                quoted = !quoted;
                any = true;
            }
            c if c.is_whitespace() && !quoted => {
                if any || !cur.is_empty() {
                    words.push(std::mem::take(&mut cur));
                }
                any = false;
            }
            c => cur.push(c),
        }
    }
    if any || !cur.is_empty() {
        words.push(cur);
    }
    words
}

/// Reruns a recorded `neo frames` command with its output in `out` and the shared directory
/// where this machine has it.
fn rerun(cmd: &str, out: &Path, file: &Path) {
    let words = shell_words(cmd);
    assert_eq!(words.first().map(String::as_str), Some("neo"), "{}: command {cmd:?}", file.display());
    let shared = shared_dir_path();
    let mut args: Vec<String> = Vec::new();
    let mut it = words[1..].iter();
    while let Some(w) = it.next() {
        args.push(w.replace("../shared/", &format!("{}/", shared.display())));
        if w == "--out" {
            it.next();
            args.push(out.display().to_string());
        }
    }
    // The reference's traces predate the hardware-arithmetic preprocessing (its binary used the
    // float preprocess, whose ITU extents differ in the last bit): reproduce that work.
    if words.get(1).map(String::as_str) == Some("frames") && !words.iter().any(|w| w == "--preprocess") {
        args.extend(["--preprocess".to_string(), "float".to_string()]);
    }
    let o = Command::new(env!("CARGO_BIN_EXE_neo")).args(&args).output().expect("run neo");
    assert!(o.status.success(), "neo {args:?} failed:\n{}", String::from_utf8_lossy(&o.stderr));
}

fn recorded_stats(s: &Value) -> PocStats {
    let n = |k: &str| s[k].as_u64().unwrap_or_else(|| panic!("trace_stats.{k} missing"));
    PocStats {
        table_entries: n("table_entries"),
        incoming_entries: n("incoming_entries"),
        reused_entries: n("reused_entries"),
        nonempty_tiles: n("nonempty_tiles"),
        gaussians: n("gaussians"),
        culled: n("culled"),
        incoming_pairs: n("incoming_pairs_per_gaussian_lists"),
        max_table_len: n("max_table_len"),
        bitmap_popcount: n("bitmap_popcount"),
    }
}

/// The timing restatement's cycles are within this fraction of the artifact's, on every frame
/// compared (issue 13 item 3; docs/cycle-model.md section 5).
const CYCLE_TOLERANCE: f64 = 0.05;

/// Compares one run; false when its trace is stale.
fn check_run(run: &Value, dir: &Path, file: &Path) -> bool {
    let label = format!("{} {} frame {}", run["scene"], run["res"], run["frame"]);
    let trace = dir.join(run["trace_file"].as_str().expect("trace_file"));
    let frame = read_poc_trace(&trace).unwrap_or_else(|e| panic!("{label}: {e}"));
    let stats = frame.stats();
    let want = recorded_stats(&run["trace_stats"]);
    if stats != want {
        eprintln!(
            "STALE {label}: {} was made from other work: recorded {want:?}, now {stats:?}",
            file.display()
        );
        return false;
    }
    let lines = artifact_lines(&frame, &ArtifactSizes::default());
    let per = &run["artifact"]["dram"]["per_request_type"];
    for r in Request::ALL {
        let rec = &per[r.name()];
        let dir = if r.is_write() { "W" } else { "R" };
        assert_eq!(rec["direction"], dir, "{label}: {} direction", r.name());
        let key = if r.is_write() { "write_lines" } else { "read_lines" };
        let artifact = rec[key].as_u64().unwrap_or_else(|| panic!("{label}: {} {key} missing", r.name()));
        assert_eq!(lines.get(r), artifact, "{label}: {} lines, neo's accounting vs the artifact", r.name());
    }
    let dram = &run["artifact"]["dram"];
    assert_eq!(Some(lines.reads()), dram["read_lines"].as_u64(), "{label}: read lines");
    assert_eq!(Some(lines.writes()), dram["write_lines"].as_u64(), "{label}: write lines");
    eprintln!("{label}: {} read and {} write lines, all 15 names equal", lines.reads(), lines.writes());
    let timing = artifact_timing(&frame, &ArtifactSizes::default(), &DramConfig::default());
    let want = run["artifact"]["core_cycles"].as_u64().expect("core_cycles");
    assert_eq!((timing.reads, timing.writes), (lines.reads(), lines.writes()), "{label}: the timed requests");
    let err = timing.core_cycles as f64 / want as f64 - 1.0;
    eprintln!("{label}: cycles {} vs the artifact's {want} ({:+.1}%)", timing.core_cycles, 100.0 * err);
    assert!(
        err.abs() <= CYCLE_TOLERANCE,
        "{label}: cycles {} vs the artifact's {want}: {:+.1}%, more than {:.0}% off",
        timing.core_cycles,
        100.0 * err,
        100.0 * CYCLE_TOLERANCE
    );
    true
}

#[test]
fn artifact_lines_match_the_artifact() {
    let Some((file, reference)) = reference() else { return };
    let runs = reference["runs"].as_array().unwrap_or_else(|| panic!("{}: no runs", file.display()));
    let tmp = tempfile::tempdir().expect("temp dir");
    let mut commands: Vec<&str> =
        runs.iter().map(|r| r["neo_command"].as_str().expect("neo_command")).collect();
    commands.dedup();
    let (mut compared, mut stale) = (0, 0);
    for (i, cmd) in commands.iter().enumerate() {
        let out = tmp.path().join(format!("run{i}"));
        rerun(cmd, &out, &file);
        for run in runs.iter().filter(|r| r["neo_command"] == *cmd) {
            if check_run(run, &out, &file) {
                compared += 1;
            } else {
                stale += 1;
            }
        }
    }
    assert!(
        compared > 0,
        "{}: all {stale} runs are stale; regenerate the reference (its README)",
        file.display()
    );
}

/// The waterfall's last row (the artifact's structure with neo's charging and byte sizes)
/// against neo's own model of the same frames (`neo simulate --json`, per-frame stage bytes):
/// the stages whose work both see the same way are equal; the feature gathers (neo's model
/// estimates straddles over pseudo-random records, the waterfall counts the trace's ids) within
/// 0.5%; the sorting stages (neo's exact per-tile commands against the artifact's approximation
/// passes and 256-entry chunks) within 5%.
#[test]
fn waterfall_reaches_neos_own_bytes() {
    let Some((file, reference)) = reference() else { return };
    let runs = reference["runs"].as_array().unwrap_or_else(|| panic!("{}: no runs", file.display()));
    let run0 = &runs[0];
    let cmd = run0["neo_command"].as_str().expect("neo_command");
    let tmp = tempfile::tempdir().expect("temp dir");
    rerun(cmd, tmp.path(), &file);
    let words = shell_words(cmd);
    let arg = |k: &str| words.iter().position(|w| w == k).map(|i| words[i + 1].clone()).expect(k);
    let scene = arg("--scene").replace("../shared/", &format!("{}/", shared_dir_path().display()));
    let args = ["simulate", "--scene", &scene, "--res", &arg("--res"), "--frames", &arg("--frames")];
    let o = Command::new(env!("CARGO_BIN_EXE_neo"))
        .args(args)
        .args(["--trajectory", &arg("--trajectory"), "--arch", "neo", "--quality", "off", "--json"])
        .output()
        .expect("run neo");
    assert!(o.status.success(), "neo simulate failed:\n{}", String::from_utf8_lossy(&o.stderr));
    let v: Value = serde_json::from_slice(&o.stdout).expect("JSON");
    let frames = v[0]["archs"][0]["frames"].as_array().expect("frames");
    // Neo's byte sizes: the baked format's, by the scene's SH degree (biker: degree 0, 12 bytes).
    let degree = neo_golden::source::load_scene(&scene, false).expect("scene").0.sh_degree;
    let neo_sizes = NeoSizes {
        geometry: 44,
        sh: 12 * (degree as u64 + 1).pow(2),
        feature: 31,
        pixel: 3,
        sh_degree: degree,
    };
    let cfg = neo_sim::config::SimConfig::default();
    assert_eq!(
        (neo_sizes.geometry, neo_sizes.sh, neo_sizes.pixel),
        (
            cfg.sizes.gaussian_geometry_bytes.unwrap_or(neo_golden::hwpre::bake::geometry_bytes()) as u64,
            cfg.sizes.gaussian_sh_bytes.unwrap_or(neo_golden::hwpre::bake::sh_bytes(degree, ShPrecision::F32))
                as u64,
            cfg.sizes.pixel_bytes as u64
        ),
        "neo's default sizes"
    );
    for run in runs.iter().filter(|r| r["neo_command"] == cmd) {
        let k = run["frame"].as_u64().expect("frame") as usize;
        let trace = tmp.path().join(run["trace_file"].as_str().expect("trace_file"));
        let frame = read_poc_trace(&trace).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(frame.reuses_tables(), k > 0, "frame {k} of `--sort neo`");
        let steps = waterfall(&frame, &ArtifactSizes::default(), &neo_sizes);
        if k == 1 {
            // The timing restatement issues exactly each step's bytes (same rules, same frame).
            for (j, step) in steps.iter().enumerate() {
                let rules = Rules::step(j, &neo_sizes);
                let t =
                    artifact_timing_with(&frame, &ArtifactSizes::default(), &rules, &DramConfig::default());
                assert_eq!(
                    (t.reads + t.writes) * 64,
                    step.bytes.total(),
                    "frame {k} step {j}: {}",
                    step.name
                );
                eprintln!(
                    "frame {k} step {j}: {:.3} MB, {} cycles ({})",
                    step.bytes.total() as f64 / 1e6,
                    t.core_cycles,
                    step.name
                );
            }
        }
        let last = steps.last().expect("steps").bytes;
        let neo = &frames[k]["stages"];
        for (i, st) in Stage::ALL.iter().enumerate() {
            let got = last.get(*st, Dir::Read) + last.get(*st, Dir::Write);
            let n = &neo[i];
            assert_eq!(n["stage"], st.name());
            let want = n["read_bytes"].as_u64().unwrap() + n["write_bytes"].as_u64().unwrap();
            let tol = match st {
                Stage::FeatureTable => 0.005,
                Stage::IncomingList | Stage::SortTable => 0.05,
                _ => 0.0,
            };
            let err = if want == 0 { got as f64 } else { got as f64 / want as f64 - 1.0 };
            eprintln!("frame {k} {st}: waterfall {got} vs neo {want} ({:+.2}%)", 100.0 * err);
            assert!(err.abs() <= tol, "frame {k} {st}: waterfall {got} B vs neo's model {want} B");
        }
    }
}

#[test]
fn shell_words_keep_quoted_arguments() {
    let w = shell_words("neo frames --scene 'synthetic:outdoor?gaussians=200k&seed=1' --out out/x");
    assert_eq!(w, ["neo", "frames", "--scene", "synthetic:outdoor?gaussians=200k&seed=1", "--out", "out/x"]);
    assert_eq!(shell_words("a ''  b"), ["a", "", "b"]);
}
