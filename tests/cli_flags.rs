//! End-to-end tests of the `neo` binary's flag checks: `neo frames`, `neo signals`, `neo bench`
//! and `neo gen --check` refuse bad flags with an error naming the flag, before they print or
//! write anything, and `neo frames` leaves no earlier run's files behind.

use std::path::Path;
use std::process::Output;

mod common;
use common::{neo, stderr, stdout, succeeds as ok};

const SCENE: &str = "synthetic:outdoor?gaussians=1000&seed=1";

/// `neo args` fails with exit 1 and an error containing every one of `phrases`, saying its
/// problem once (no part of the message repeated after a `: `), without a panic and without
/// printing anything on stdout. Returns the error.
fn refused(args: &[&str], phrases: &[&str]) -> String {
    let o = neo(args);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "neo {args:?} should fail with exit 1, stderr:\n{err}");
    assert!(!err.contains("panicked"), "panic instead of an error:\n{err}");
    for p in phrases {
        assert!(err.contains(p), "neo {args:?}: the error lacks '{p}':\n{err}");
    }
    let line = err.lines().find(|l| l.starts_with("error: ")).expect("an error line");
    let parts: Vec<&str> = line.split(": ").filter(|p| p.len() > 12).collect();
    for (i, p) in parts.iter().enumerate() {
        assert!(!parts[i + 1..].contains(p), "neo {args:?}: the error repeats '{p}':\n{line}");
    }
    assert!(stdout(&o).is_empty(), "neo {args:?} printed before failing:\n{}", stdout(&o));
    err
}

fn frames_args<'a>(out: &'a Path, frames: &'a str, extra: &[&'a str]) -> Vec<&'a str> {
    let mut args = vec![
        "frames",
        "--scene",
        SCENE,
        "--res",
        "64x64",
        "--frames",
        frames,
        "--no-float",
        "--no-ssim",
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    args
}

/// `--passes` has one limit (16, adaptive's `max` too) in `neo frames`, `neo simulate` and the
/// model configuration; a tile geometry the raster cannot run and `--trace-frames` beyond the
/// run are refused. Each is refused before the output directory is made or the banner printed,
/// with the error naming the flag and saying its problem once.
#[test]
fn frames_refuses_bad_flags_before_writing_anything() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let cases: [(&[&str], &[&str]); 8] = [
        (&["--passes", "18446744073709551615"], &["--passes", "above the limit of 16"]),
        (&["--passes", "17"], &["--passes", "above the limit of 16"]),
        (&["--tile", "0"], &["--tile", "tile 0 is not a positive multiple of subtile 8"]),
        (&["--subtile", "0"], &["--subtile", "tile 64 is not a positive multiple of subtile 0"]),
        (&["--tile", "8", "--subtile", "16"], &["--tile", "not a positive multiple of subtile 16"]),
        (&["--fitted", "--tile", "0"], &["--tile", "not a positive multiple"]),
        (&["--trace-frames", "1,99"], &["--trace-frames 99", "2 frame(s)"]),
        (&["--chunk", "0"], &["chunk size 0 is not the BSU width 16 times a power of two"]),
    ];
    for (extra, phrases) in cases {
        refused(&frames_args(&out, "2", extra), phrases);
        assert!(!out.exists(), "{extra:?}: the output directory was made");
    }
    // The limit itself runs.
    ok(&frames_args(&out, "2", &["--passes", "16"]));
    let simulate = ["simulate", "--scene", SCENE, "--res", "64x64", "--frames", "2", "--arch", "neo"];
    refused(&[&simulate[..], &["--passes", "1,17"]].concat(), &["--passes", "17 DPS passes", "limit of 16"]);
    // The chunk error of the traced golden pipeline reads once too.
    let trace = dir.path().join("trace");
    let traced = [&simulate[..], &["--chunk", "0", "--trace", trace.to_str().unwrap()]].concat();
    refused(&traced, &["chunk size 0 is not the BSU width 16 times a power of two"]);
    let cfg = dir.path().join("model.json");
    std::fs::write(&cfg, r#"{"pipeline": {"dps_passes": 1000000}}"#).unwrap();
    let cfg_arg = cfg.to_str().unwrap();
    refused(
        &[&simulate[..], &["--config", cfg_arg]].concat(),
        &[cfg_arg, "pipeline.dps_passes", "limit of 16"],
    );
}

/// A run removes the files an earlier run wrote into its directory and it does not: a 2-frame
/// run without `--png --tile-stats --trace` after a 4-frame run with them leaves only its own
/// `stats.json` (and files that are not neo's), so `neo signals` no longer reads a stale
/// `tiles.jsonl`.
#[test]
fn frames_removes_the_stale_output_of_an_earlier_run() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    ok(&frames_args(&out, "4", &["--png", "--tile-stats", "--trace"]));
    for f in ["frame_00003.png", "tiles.jsonl", "trace/frame_00003.poc.trace", "stats.json"] {
        assert!(out.join(f).is_file(), "{f}");
    }
    std::fs::write(out.join("notes.txt"), "mine").unwrap();
    std::fs::write(out.join("trace/notes.txt"), "mine").unwrap();
    let o = ok(&frames_args(&out, "2", &["--trace-frames", "1"]));
    assert!(stderr(&o).contains("removed 8 file(s)"), "{}", stderr(&o));
    let mut left: Vec<String> = walk(&out);
    left.sort();
    assert_eq!(left, ["notes.txt", "stats.json", "trace/frame_00001.poc.trace", "trace/notes.txt"]);
    let stats: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("stats.json")).unwrap()).unwrap();
    assert_eq!(stats["frames"].as_array().unwrap().len(), 2);
    refused(&["signals", out.to_str().unwrap()], &["tiles.jsonl"]);
}

/// Files under `dir`, relative to it.
fn walk(dir: &Path) -> Vec<String> {
    let mut names = Vec::new();
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            let sub = p.file_name().unwrap().to_string_lossy().into_owned();
            names.extend(walk(&p).into_iter().map(|n| format!("{sub}/{n}")));
        } else {
            names.push(p.file_name().unwrap().to_string_lossy().into_owned());
        }
    }
    names
}

/// `--frames 2` on a trajectory of one camera is refused (as by `neo simulate` and `neo cosim`):
/// the run would not be the one asked for.
#[test]
fn frames_refuses_a_trajectory_with_fewer_frames_than_asked() {
    let dir = tempfile::tempdir().unwrap();
    let cams = dir.path().join("cameras.json");
    std::fs::write(
        &cams,
        r#"[{"id": 0, "img_name": "front", "width": 64, "height": 48, "position": [0, 0, -3],
            "rotation": [[1, 0, 0], [0, 1, 0], [0, 0, 1]], "fx": 60.0, "fy": 60.0}]"#,
    )
    .unwrap();
    let out = dir.path().join("run");
    refused(
        &frames_args(&out, "2", &["--trajectory", cams.to_str().unwrap()]),
        &["has 1 frame(s); 2 requested (--frames)"],
    );
    ok(&frames_args(&out, "1", &["--trajectory", cams.to_str().unwrap()]));
    // The frame beyond it cannot be traced.
    refused(
        &frames_args(&out, "1", &["--trajectory", cams.to_str().unwrap(), "--trace-frames", "1"]),
        &["--trace-frames 1", "1 frame(s)"],
    );
}

/// `neo signals` reads every directory before printing (a bad one prints no table), and the
/// `next` lag pairs a frame only with the one numbered just before it.
#[test]
fn signals_reads_every_run_first_and_pairs_only_consecutive_frames() {
    let dir = tempfile::tempdir().unwrap();
    let run = dir.path().join("run");
    ok(&frames_args(&run, "3", &["--tile-stats", "--tile", "16", "--trajectory", "orbit:speed=16"]));
    let missing = dir.path().join("missing");
    refused(&["signals", run.to_str().unwrap(), missing.to_str().unwrap()], &["missing/tiles.jsonl"]);
    let samples = |o: &Output| -> Vec<usize> {
        stdout(o)
            .lines()
            .filter(|l| l.starts_with("| ") && l.contains("(next)"))
            .map(|l| l.split('|').nth(2).unwrap().trim().parse().unwrap())
            .collect()
    };
    let whole = samples(&ok(&["signals", run.to_str().unwrap()]));
    assert!(whole[0] > 0, "{whole:?}");
    // Frames 0, 1, 1000: frame 1000 does not pair with frame 1.
    let tiles = run.join("tiles.jsonl");
    let text = std::fs::read_to_string(&tiles).unwrap();
    let lines: Vec<String> = text.lines().map(str::to_string).collect();
    assert_eq!(lines.len(), 3);
    let moved = lines[2].replacen("\"frame\":2,", "\"frame\":1000,", 1);
    assert_ne!(moved, lines[2], "{}", &lines[2][..40]);
    std::fs::write(&tiles, [lines[0].clone(), lines[1].clone(), moved].join("\n")).unwrap();
    let o = ok(&["signals", run.to_str().unwrap()]);
    assert!(stderr(&o).contains("frame 1000 follows frame 1"), "{}", stderr(&o));
    let gap = samples(&o);
    assert!(gap[0] < whole[0], "the gap still pairs: {gap:?} vs {whole:?}");
}

/// `neo bench` checks its flags before the first measurement: `--repeat 0` and `--gaussians 0`
/// are refused (also by `neo bench model`); `--raster-sample 0` means what it means to `neo
/// simulate` (no sampled tile, termination ratio 1) and is said so.
#[test]
fn bench_checks_its_flags_before_measuring() {
    refused(&["bench", "--repeat", "0"], &["--repeat 0"]);
    refused(&["bench", "--gaussians", "0"], &["--gaussians", "gaussians=0"]);
    refused(&["bench", "model", "--gaussians", "0"], &["--gaussians", "gaussians=0"]);
    let model = ["bench", "model", "--gaussians", "1000", "--frames", "1", "--res", "64x64", "--arch", "neo"];
    let o = ok(&[&model[..], &["--raster-sample", "0"]].concat());
    assert!(stdout(&o).contains("early termination not sampled (--raster-sample 0"), "{}", stdout(&o));
    let help = stdout(&ok(&["simulate", "--help"]));
    assert!(help.contains("0: on none"), "{help}");
}

/// `neo gen --check` on a directory that does not exist says so (not that it is out of date).
#[test]
fn gen_check_of_a_missing_directory_says_it_does_not_exist() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("hdl");
    let err = refused(&["gen", "--check", "--out", missing.to_str().unwrap()], &["does not exist"]);
    assert!(!err.contains("out of date"), "{err}");
    let file = dir.path().join("file");
    std::fs::write(&file, "x").unwrap();
    refused(&["gen", "--check", "--out", file.to_str().unwrap()], &["not a directory"]);
}

/// `neo simulate` runs exactly `--frames` frames of a trajectory: the first ones of a longer
/// cameras.json (it ran all three of three for `--frames 2`, and the record said 2), and a
/// shorter one is refused (it ran one for `--frames 2`).
#[test]
fn simulate_runs_the_frames_asked_for_or_refuses() {
    let dir = tempfile::tempdir().unwrap();
    let cams = dir.path().join("three.json");
    let scene = "synthetic:outdoor?gaussians=2000&seed=1";
    let c = cams.to_str().unwrap();
    ok(&["trajectory", "--scene", scene, "--trajectory", "orbit:frames=3", "--out", c]);
    let sim = |frames: &str| {
        let args = ["simulate", "--scene", scene, "--res", "128x128", "--arch", "neo", "--quality", "off"];
        let mut v: Vec<&str> = args.to_vec();
        v.extend(["--trajectory", c, "--frames", frames, "--json"]);
        v.into_iter().map(String::from).collect::<Vec<_>>()
    };
    let two = sim("2");
    let o = ok(&two.iter().map(String::as_str).collect::<Vec<_>>());
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).expect("JSON");
    let p = if v.is_array() { &v[0] } else { &v };
    assert_eq!(p["point"]["frames"], 2);
    assert_eq!(p["archs"][0]["frames"].as_array().expect("per-frame records").len(), 2);
    let four = sim("4");
    refused(
        &four.iter().map(String::as_str).collect::<Vec<_>>(),
        &["has 3 frame(s); 4 requested (--frames)"],
    );
}

/// `neo simulate` refuses an empty `--sort` (it ran no point and exited 0) and a
/// `--trace-frames` beyond the run (it wrote no trace), before any work.
#[test]
fn simulate_refuses_an_empty_sort_and_a_trace_frame_beyond_the_run() {
    let dir = tempfile::tempdir().unwrap();
    let trace = dir.path().join("trace");
    let base = [
        "simulate",
        "--scene",
        "synthetic:outdoor?gaussians=2000&seed=1",
        "--res",
        "128x128",
        "--frames",
        "2",
    ];
    for sort in ["", ","] {
        let mut args = base.to_vec();
        args.extend(["--sort", sort]);
        refused(&args, &["--sort", "no strategy given"]);
    }
    let mut args = base.to_vec();
    args.extend(["--trace", trace.to_str().unwrap(), "--trace-frames", "5"]);
    refused(&args, &["--trace-frames 5", "2 frame(s)"]);
    assert!(!trace.exists(), "nothing written");
}
