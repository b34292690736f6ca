//! Writing generated files to a directory and checking a directory against fresh output.

use crate::emit::HEADER;
use crate::units::VerilogFile;
use std::path::Path;

/// One way a directory differs from the generated files.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Difference {
    /// A generated file is missing from the directory.
    Missing(String),
    /// The file exists but its text differs.
    Changed(String),
    /// A `.v` file carrying the generator's header is in the directory but no longer generated.
    Stale(String),
}

impl std::fmt::Display for Difference {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Difference::Missing(n) => write!(f, "{n}: missing"),
            Difference::Changed(n) => write!(f, "{n}: differs from the generator's output"),
            Difference::Stale(n) => write!(f, "{n}: generated earlier but no longer produced"),
        }
    }
}

/// `.v` files in `dir` whose first line is the generator's header.
fn generated_in(dir: &Path) -> std::io::Result<Vec<String>> {
    let mut names = Vec::new();
    if !dir.exists() {
        return Ok(names);
    }
    for e in std::fs::read_dir(dir)? {
        let e = e?;
        let name = e.file_name().to_string_lossy().into_owned();
        if name.ends_with(".v") {
            let text = std::fs::read_to_string(e.path()).unwrap_or_default();
            if text.starts_with(HEADER) {
                names.push(name);
            }
        }
    }
    names.sort();
    Ok(names)
}

/// Compares `dir` with `files` byte for byte; empty when they agree. Other files in `dir`
/// (e.g. `lint.vlt`, hand-written `.v` files without the header) are ignored.
pub fn check_dir(dir: &Path, files: &[VerilogFile]) -> std::io::Result<Vec<Difference>> {
    let mut diffs = Vec::new();
    for f in files {
        let p = dir.join(f.file_name());
        match std::fs::read(&p) {
            Ok(bytes) if bytes == f.text.as_bytes() => {}
            Ok(_) => diffs.push(Difference::Changed(f.file_name())),
            Err(_) => diffs.push(Difference::Missing(f.file_name())),
        }
    }
    for name in generated_in(dir)? {
        if !files.iter().any(|f| f.file_name() == name) {
            diffs.push(Difference::Stale(name));
        }
    }
    Ok(diffs)
}

/// Writes `files` into `dir` (created if needed) and removes stale generated files (`.v` files
/// with the generator's header that are no longer produced). Returns the names written.
pub fn write_dir(dir: &Path, files: &[VerilogFile]) -> std::io::Result<Vec<String>> {
    std::fs::create_dir_all(dir)?;
    for name in generated_in(dir)? {
        if !files.iter().any(|f| f.file_name() == name) {
            std::fs::remove_file(dir.join(name))?;
        }
    }
    let mut written = Vec::new();
    for f in files {
        std::fs::write(dir.join(f.file_name()), &f.text)?;
        written.push(f.file_name());
    }
    Ok(written)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn file(name: &str, body: &str) -> VerilogFile {
        VerilogFile { name: name.into(), text: format!("{HEADER}\n{body}\n") }
    }

    #[test]
    fn write_then_check_agrees_and_detects_every_difference() {
        let dir = std::env::temp_dir().join(format!("neo-gen-out-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let files = vec![file("a", "x"), file("b", "y")];
        assert_eq!(write_dir(&dir, &files).unwrap(), ["a.v", "b.v"]);
        std::fs::write(dir.join("lint.vlt"), "`verilator_config\n").unwrap();
        std::fs::write(dir.join("hand.v"), "module hand; endmodule\n").unwrap();
        assert!(check_dir(&dir, &files).unwrap().is_empty());
        let changed = vec![file("a", "x2"), file("c", "z")];
        let d = check_dir(&dir, &changed).unwrap();
        assert_eq!(
            d,
            vec![
                Difference::Changed("a.v".into()),
                Difference::Missing("c.v".into()),
                Difference::Stale("b.v".into())
            ]
        );
        write_dir(&dir, &changed).unwrap();
        assert!(check_dir(&dir, &changed).unwrap().is_empty());
        assert!(!dir.join("b.v").exists() && dir.join("hand.v").exists() && dir.join("lint.vlt").exists());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
