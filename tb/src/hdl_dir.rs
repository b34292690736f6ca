//! `$NEO_HDL_DIR` at run time: the benches cosimulate the Verilog in that directory instead of
//! the generator's, with no rebuild of this crate (`scripts/mutate-check` runs its mutants this
//! way: one build of the test binaries, a mutated copy of `hdl/` per run).
//!
//! - A statically linked model ([`crate::models`]) compares, when it is created, the files it
//!   was built from (its top's and every submodule's, header lines left out: the wrapper's
//!   `HDL_FILES` and `HDL_HASH`) with the files of the same names in the directory
//!   ([`substitute`]). When they differ it runs a model of the directory's files instead,
//!   verilated and compiled then ([`DynModel::build_for_short_runs`], cached by content hash
//!   like every model); when they are the same it runs the linked model. Only the tops a test
//!   creates are compared and built. A missing file is an error naming it.
//! - The models built at run time anyway (the engine, the Preprocessing Engine, its units and
//!   datapaths, the fp bench) read the directory's copy of their files themselves
//!   ([`crate::dynmodel::generated_files`], [`crate::fp::FpBench::build`]).
//! - Every file of the directory that went into a simulated model is listed in
//!   `DIR/`[`READ_LIST`] ([`note_read`]): `scripts/mutate-check` checks that the mutated file is
//!   there, so a mutant the benches never read is not reported as missed or caught.

use crate::dut::PortSpec;
use crate::dynmodel::DynModel;
use crate::waves::WaveFormat;
use neo_gen::interface::{Dir, ModuleInterface, Port};
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

#[allow(dead_code)]
#[path = "../build/hdl_hash.rs"]
mod hdl_hash;

/// The file in `$NEO_HDL_DIR` listing the files read into simulated models, one a line.
pub const READ_LIST: &str = "neo-tb-read.txt";

/// `$NEO_HDL_DIR` when it is set and not empty.
pub fn dir() -> Option<PathBuf> {
    std::env::var_os("NEO_HDL_DIR").filter(|d| !d.is_empty()).map(PathBuf::from)
}

/// Appends `files` (names in `dir`) to `dir/`[`READ_LIST`].
///
/// # Panics
/// When the list cannot be written (the mutation check relies on it).
pub fn note_read<'a>(dir: &Path, files: impl IntoIterator<Item = &'a str>) {
    let text: String = files.into_iter().map(|f| format!("{f}\n")).collect();
    let path = dir.join(READ_LIST);
    let written = std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(&path)
        .and_then(|mut f| f.write_all(text.as_bytes()));
    if let Err(e) = written {
        panic!("NEO_HDL_DIR: cannot write {}: {e}", path.display());
    }
}

/// What a top runs for one directory: the linked model, or a library built from the directory.
#[derive(Clone)]
enum Choice {
    Linked,
    Built { library: PathBuf, iface: ModuleInterface, format: Option<WaveFormat> },
}

/// The choices made in this process, by top and directory (each top is compared and built once).
static CHOICES: Mutex<Vec<(String, PathBuf, Choice)>> = Mutex::new(Vec::new());

/// For the wrapper of top `top` (ports `ports`, built from `files` whose hash is `hash`): with
/// `$NEO_HDL_DIR` set and its copies of `files` different from them, a model of the copies
/// (built on first use, then loaded from the cache); otherwise `None` (run the linked model).
///
/// # Panics
/// When a file is missing from the directory, or the model of its files does not build (the
/// message holds [`crate::dynmodel::MODEL_DOES_NOT_BUILD`]) or load.
pub fn substitute(top: &str, ports: &[PortSpec], files: &[&str], hash: &str) -> Option<DynModel> {
    let dir = dir()?;
    let model = match choose(&dir, top, ports, files, hash) {
        Ok((_, Some(built))) => Ok(Some(built)),
        Ok((choice, None)) => open(&choice),
        Err(e) => Err(e),
    };
    model.unwrap_or_else(|e| panic!("{e}"))
}

fn open(choice: &Choice) -> Result<Option<DynModel>, String> {
    match choice {
        Choice::Linked => Ok(None),
        Choice::Built { library, iface, format } => DynModel::load(iface, library, *format).map(Some),
    }
}

/// The choice for `top` and `dir`, made (and recorded) on first use; with the model when this
/// call built it (it is loaded already).
fn choose(
    dir: &Path,
    top: &str,
    ports: &[PortSpec],
    files: &[&str],
    hash: &str,
) -> Result<(Choice, Option<DynModel>), String> {
    let mut choices = CHOICES.lock().unwrap_or_else(|e| e.into_inner());
    if let Some((_, _, c)) = choices.iter().find(|(t, d, _)| t == top && d == dir) {
        return Ok((c.clone(), None));
    }
    let texts = files
        .iter()
        .map(|f| {
            let p = dir.join(f);
            let text = std::fs::read_to_string(&p)
                .map_err(|e| format!("NEO_HDL_DIR: cannot read {} (a file of {top}): {e}", p.display()))?;
            Ok((f.to_string(), text))
        })
        .collect::<Result<Vec<_>, String>>()?;
    note_read(dir, files.iter().copied());
    let (choice, model) =
        if hdl_hash::verilog_hash(texts.iter().map(|(n, t)| (n.as_str(), t.as_str()))) == hash {
            (Choice::Linked, None)
        } else {
            let (choice, model) = build(dir, top, ports, &texts)?;
            (choice, Some(model))
        };
    choices.push((top.to_string(), dir.to_path_buf(), choice.clone()));
    Ok((choice, model))
}

/// Builds (or finds in the cache) the model of `top` from `dir`'s `texts`: traced in this
/// build's format, as the linked model it stands for (a bench may open a trace without `WAVES`:
/// `bsu_vcd_shows_handshake_rules_and_every_transfer`; an untraced stand-in failed it on any
/// change, so every BSU mutant counted as caught), its per-cycle code compiled for build time
/// (the benches run seconds). A `WAVES` value that is not a waveform choice is an error. Returns the choice (for later
/// models of `top`) and the loaded model.
fn build(
    dir: &Path,
    top: &str,
    ports: &[PortSpec],
    texts: &[(String, String)],
) -> Result<(Choice, DynModel), String> {
    let iface = ModuleInterface {
        name: top.to_string(),
        ports: ports
            .iter()
            .map(|p| Port {
                name: p.name.to_string(),
                dir: if p.input { Dir::In } else { Dir::Out },
                width: p.width,
            })
            .collect(),
    };
    let vlt = std::fs::read_to_string(dir.join("lint.vlt"))
        .unwrap_or_else(|_| crate::dynmodel::LINT_VLT.to_string());
    crate::waves::try_requested_format()?;
    let format = Some(crate::waves::MODEL_FORMAT);
    let (model, info) = DynModel::build_for_short_runs(&iface, texts, Some(&vlt), format)
        .map_err(|e| format!("NEO_HDL_DIR={}: {top}: {e}", dir.display()))?;
    println!(
        "NEO_HDL_DIR: {top}: {}'s Verilog differs from this build's; running a model of it ({})",
        dir.display(),
        if info.cached { "from the cache".to_string() } else { format!("built in {:.1} s", info.seconds) }
    );
    let choice = Choice::Built { library: info.library, iface, format: model.wave_format() };
    Ok((choice, model))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The hash ignores the header line (it names the whole configuration) and nothing else.
    #[test]
    fn the_hash_covers_names_and_bodies_not_headers() {
        let h = |files: &[(&str, &str)]| hdl_hash::verilog_hash(files.iter().copied());
        let a = h(&[("a.v", "// generated by neo gen (x, config 0x1); do not edit\nmodule a;\n")]);
        assert_eq!(a, h(&[("a.v", "// generated by neo gen (x, config 0x2); do not edit\nmodule a;\n")]));
        assert_ne!(a, h(&[("a.v", "// generated by neo gen (x, config 0x1); do not edit\nmodule b;\n")]));
        assert_ne!(a, h(&[("b.v", "// generated by neo gen (x, config 0x1); do not edit\nmodule a;\n")]));
        // Names and texts cannot run together.
        assert_ne!(h(&[("a", "bc")]), h(&[("ab", "c")]));
    }
}
