//! `neo` writing to a closed pipe (`neo ... | head -1`) ends quietly instead of panicking.

use std::io::Read;
use std::process::{Command, Stdio};

/// A small simulation: its header line comes out before the run, its table after.
const SIMULATE: [&str; 12] = [
    "simulate",
    "--scene",
    "synthetic:outdoor?gaussians=2000&seed=1",
    "--frames",
    "2",
    "--res",
    "128x128",
    "--arch",
    "neo",
    "--quality",
    "off",
    "--per-frame",
];

/// The reader of `neo simulate`'s standard output goes away after one byte, before neo is
/// done: neo ends by `SIGPIPE` (or succeeds, had it written everything first), never with
/// Rust's "failed printing to stdout" panic (exit code 101).
#[test]
fn a_closed_stdout_ends_neo_without_a_panic() {
    for _ in 0..3 {
        let mut child = Command::new(env!("CARGO_BIN_EXE_neo"))
            .args(SIMULATE)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("run neo");
        let mut out = child.stdout.take().expect("stdout");
        let mut first = [0u8; 1];
        out.read_exact(&mut first).expect("neo prints something");
        drop(out);
        let o = child.wait_with_output().expect("wait for neo");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!err.contains("panicked"), "{err}");
        assert_ne!(o.status.code(), Some(101), "{err}");
    }
}
