//! What the end-to-end tests of the `neo` binary share: running it and reading its output.

use std::process::{Command, Output};

/// Runs `neo args` to its end.
pub fn neo(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_neo")).args(args).output().expect("run neo")
}

/// The standard output, as text.
pub fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// The standard error, as text.
pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Runs `neo args`, which must succeed.
pub fn succeeds(args: &[&str]) -> Output {
    let o = neo(args);
    assert!(o.status.success(), "neo {args:?} failed:\n{}", stderr(&o));
    o
}
