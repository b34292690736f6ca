//! The error of a text input read line by line: the file, the 1-based line and the problem
//! (request streams, `poc.trace` files).

use std::fmt;
use std::path::PathBuf;

/// A malformed input file: the file, the 1-based line (0 for the file as a whole, e.g. when it
/// cannot be read) and what is wrong. Displays as `FILE:LINE: message`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LineError {
    /// The file.
    pub path: PathBuf,
    /// 1-based line number, 0 for the whole file.
    pub line: usize,
    /// What is wrong.
    pub message: String,
}

impl fmt::Display for LineError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.line == 0 {
            write!(f, "{}: {}", self.path.display(), self.message)
        } else {
            write!(f, "{}:{}: {}", self.path.display(), self.line, self.message)
        }
    }
}

impl std::error::Error for LineError {}
