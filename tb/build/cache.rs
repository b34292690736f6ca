//! The Verilator build cache: content-keyed directories that survive `cargo clean -p neo-tb`.
//!
//! A unit's directory is `<root>/<name>-<hash>/`, where the hash covers everything its output
//! depends on (Verilog text, flags, tool versions, shim version). Directories are built under a
//! temporary name and renamed into place, so a half-built entry is never seen and two builds
//! racing for the same key both end up with a complete one.

use std::fs;
use std::hash::{Hash, Hasher};
use std::path::{Path, PathBuf};

/// Accumulates the parts of a cache key; also keeps a readable description of them.
pub struct Key {
    sip: std::collections::hash_map::DefaultHasher,
    fnv: u64,
    description: String,
}

impl Key {
    /// An empty key.
    pub fn new() -> Self {
        Key { sip: Default::default(), fnv: 0xcbf2_9ce4_8422_2325, description: String::new() }
    }

    /// Adds a named part (its name and length are hashed too, so parts cannot run together).
    pub fn add(&mut self, name: &str, data: &[u8]) {
        for chunk in [name.as_bytes(), &(data.len() as u64).to_le_bytes(), data] {
            chunk.hash(&mut self.sip);
            for &b in chunk {
                self.fnv ^= b as u64;
                self.fnv = self.fnv.wrapping_mul(0x0000_0100_0000_01b3);
            }
        }
        let shown = if data.len() <= 200 && data.iter().all(|&b| b.is_ascii() && b != b'\n') {
            String::from_utf8_lossy(data).into_owned()
        } else {
            format!("<{} bytes>", data.len())
        };
        self.description.push_str(&format!("{name}: {shown}\n"));
    }

    /// The key as 32 hex digits.
    pub fn hex(&self) -> String {
        format!("{:016x}{:016x}", self.sip.finish(), self.fnv)
    }

    /// What went into the key, one part a line.
    pub fn description(&self) -> &str {
        &self.description
    }
}

/// The cache root: `$NEO_CACHE_DIR`, else `<target dir>/neo-verilator-cache`, where the target
/// dir is found from `OUT_DIR` (`<target>/<profile>/build/<pkg>-<hash>/out`).
pub fn root(out_dir: &Path) -> PathBuf {
    if let Some(dir) = std::env::var_os("NEO_CACHE_DIR").filter(|d| !d.is_empty()) {
        return PathBuf::from(dir);
    }
    target_dir(out_dir).join("neo-verilator-cache")
}

/// The cargo target directory (the parent of the profile directory holding `build/`).
pub fn target_dir(out_dir: &Path) -> PathBuf {
    out_dir
        .ancestors()
        .find(|a| a.file_name().is_some_and(|n| n == "build"))
        .and_then(|build| build.parent())
        .and_then(|profile| profile.parent())
        .map(Path::to_path_buf)
        .unwrap_or_else(|| out_dir.join("neo-target"))
}

/// Returns the complete entry `<root>/<name>-<hex>`, calling `build(tmp_dir)` to create it when
/// missing. `ready` names a file that exists only in complete entries.
pub fn get_or_build(
    root: &Path,
    name: &str,
    key: &Key,
    ready: &str,
    build: impl FnOnce(&Path) -> Result<(), String>,
) -> Result<(PathBuf, bool), String> {
    let dir = root.join(format!("{name}-{}", key.hex()));
    if dir.join(ready).is_file() {
        mark_used(&dir);
        return Ok((dir, true));
    }
    fs::create_dir_all(root).map_err(|e| format!("cannot create cache dir {}: {e}", root.display()))?;
    let tmp = root.join(format!(".tmp-{name}-{}-{}", key.hex(), std::process::id()));
    let _ = fs::remove_dir_all(&tmp);
    fs::create_dir_all(&tmp).map_err(|e| format!("cannot create {}: {e}", tmp.display()))?;
    fs::write(tmp.join("key.txt"), key.description()).map_err(|e| e.to_string())?;
    if let Err(e) = build(&tmp) {
        let _ = fs::remove_dir_all(&tmp);
        return Err(e);
    }
    if !tmp.join(ready).is_file() {
        return Err(format!("build of {name} did not produce {ready} in {}", tmp.display()));
    }
    if dir.exists() {
        // A stale incomplete entry, or one completed by a concurrent build.
        if dir.join(ready).is_file() {
            let _ = fs::remove_dir_all(&tmp);
            return Ok((dir, false));
        }
        let _ = fs::remove_dir_all(&dir);
    }
    match fs::rename(&tmp, &dir) {
        Ok(()) => {
            mark_used(&dir);
            prune(root, name, &dir);
            Ok((dir, false))
        }
        Err(_) if dir.join(ready).is_file() => {
            let _ = fs::remove_dir_all(&tmp);
            Ok((dir, false))
        }
        Err(e) => Err(format!("cannot move {} to {}: {e}", tmp.display(), dir.display())),
    }
}

/// Entries kept per unit name (the most recently used ones); older ones are deleted when a new
/// entry is added, so mutation runs and generator edits do not fill the disk.
pub const KEEP_PER_NAME: usize = 8;

/// Records that `dir` was used now (the `last_used` file's modification time).
fn mark_used(dir: &Path) {
    let _ = fs::write(dir.join("last_used"), b"");
}

/// Deletes all but the [`KEEP_PER_NAME`] most recently used entries of `name` (never `keep`).
fn prune(root: &Path, name: &str, keep: &Path) {
    let Ok(entries) = fs::read_dir(root) else { return };
    let prefix = format!("{name}-");
    let mut found: Vec<(std::time::SystemTime, PathBuf)> = entries
        .flatten()
        .map(|e| e.path())
        .filter(|p| {
            p.file_name().and_then(|n| n.to_str()).is_some_and(|n| {
                n.strip_prefix(&prefix)
                    .is_some_and(|h| h.len() == 32 && h.bytes().all(|b| b.is_ascii_hexdigit()))
            })
        })
        .map(|p| {
            let t =
                fs::metadata(p.join("last_used")).and_then(|m| m.modified()).unwrap_or(std::time::UNIX_EPOCH);
            (t, p)
        })
        .collect();
    found.sort_by_key(|e| std::cmp::Reverse(e.0));
    for (_, p) in found.into_iter().skip(KEEP_PER_NAME) {
        if p != keep {
            let _ = fs::remove_dir_all(&p);
        }
    }
}
