//! Access to `../shared/` (the real scenes and the paper) for tests and benchmarks.
//!
//! Tests may read `../shared/`. When it is missing and `CI` is set they must fail loudly;
//! outside CI they skip with a message.

use std::path::PathBuf;

/// The workspace root (the directory holding the top-level `Cargo.toml`).
pub fn workspace_root() -> PathBuf {
    // golden/ sits directly below the workspace root.
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).parent().expect("golden/ has a parent directory").to_path_buf()
}

/// The `shared/` directory beside the project (`NEO_SHARED` overrides it).
pub fn shared_dir_path() -> PathBuf {
    match std::env::var_os("NEO_SHARED") {
        Some(p) => PathBuf::from(p),
        None => workspace_root().join("..").join("shared"),
    }
}

/// Returns the path of `shared/<rel>` for a test that needs it.
///
/// When the file is missing: panics if the `CI` environment variable is set (CI must have it),
/// otherwise prints a skip message naming `test` and returns `None`.
pub fn shared_file_for_test(test: &str, rel: &str) -> Option<PathBuf> {
    let path = shared_dir_path().join(rel);
    if path.exists() {
        return Some(path);
    }
    skip_or_fail(
        test,
        &format!("{} not found (set NEO_SHARED or place shared/ beside the project)", path.display()),
    );
    None
}

/// Whether the `CI` environment variable is set: then every test must run, and one that cannot
/// fails instead of skipping.
pub fn ci() -> bool {
    std::env::var_os("CI").is_some()
}

/// A test that cannot run here (a missing tool, file or hardware thread): prints
/// `SKIP <test>: <reason>`, or panics with the reason when `CI` is set. The caller returns after
/// it. Every skipping test in the workspace goes through this.
pub fn skip_or_fail(test: &str, reason: &str) {
    assert!(!ci(), "{test}: {reason} (CI is set, so this is an error)");
    eprintln!("SKIP {test}: {reason}");
}
