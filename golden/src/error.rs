//! The one error type for bad input: it always names the file and the problem.

use std::path::{Path, PathBuf};

/// An input file (scene, cameras, image, config) that could not be used.
///
/// The message reads `PATH: PROBLEM`, so a user sees at once which file is at fault and why.
#[derive(Debug, thiserror::Error)]
#[error("{}: {problem}", path.display())]
pub struct InputError {
    /// The file at fault (or a pseudo-path such as `synthetic:outdoor?...` for generated input).
    pub path: PathBuf,
    /// What is wrong with it, in words a user can act on.
    pub problem: String,
}

impl InputError {
    /// Builds an error for `path` with the given problem description.
    pub fn new(path: impl AsRef<Path>, problem: impl Into<String>) -> Self {
        Self { path: path.as_ref().to_path_buf(), problem: problem.into() }
    }
}

/// Result alias for operations on input files.
pub type InputResult<T> = Result<T, InputError>;
