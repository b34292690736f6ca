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
    if std::env::var_os("CI").is_some() {
        panic!("{test}: required shared file {} is missing (CI is set, so this is an error)", path.display());
    }
    eprintln!(
        "SKIP {test}: {} not found (set NEO_SHARED or place shared/ beside the project)",
        path.display()
    );
    None
}
