//! Waves of a test: `WAVES=1` (or `vcd`) writes a VCD at `target/waves/<test>.vcd`, `WAVES=fst`
//! an FST at `target/waves/<test>.fst`, each with a GTKWave save file `target/waves/<test>.gtkw`
//! listing the unit's ports ([`maybe_trace`]); any other value but empty or `0` is an error
//! naming `WAVES` and the accepted values ([`try_requested_format`]).
//!
//! The statically linked unit models ([`crate::models`]) trace in one format, fixed when the
//! crate is built: FST when `WAVES=fst` is in cargo's environment (`build.rs` then verilates
//! every top with `--trace-fst`, as cache entries of their own), else VCD ([`MODEL_FORMAT`]);
//! `WAVES=fst cargo test ...` therefore builds (once) and runs FST models. The models built at
//! run time (the whole-frame engine benches) choose theirs per build
//! ([`crate::dynmodel::DynModel::build_traced`]).

#[path = "../build/waves_env.rs"]
mod waves_env;

pub use waves_env::WAVES_VALUES;

use crate::dut::{Dut, PortSpec};
use crate::dynmodel::DynModel;
use std::path::{Path, PathBuf};

/// The cargo target directory this crate was built into (`target/`).
pub fn target_dir() -> PathBuf {
    std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("NEO_TB_TARGET_DIR")))
}

/// The format the statically linked models trace in: FST when the crate was built with
/// `WAVES=fst`, else VCD.
pub const MODEL_FORMAT: WaveFormat = match env!("NEO_TB_MODEL_WAVES").as_bytes() {
    b"fst" => WaveFormat::Fst,
    _ => WaveFormat::Vcd,
};

/// True when `WAVES` asks for waves ([`requested_format`]).
///
/// # Panics
/// When `WAVES` is not a waveform choice.
pub fn waves_requested() -> bool {
    requested_format().is_some()
}

/// A waveform file format.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum WaveFormat {
    /// Value Change Dump (text; Verilator `--trace`).
    #[default]
    Vcd,
    /// GTKWave's Fast Signal Trace (compressed; Verilator `--trace-fst`).
    Fst,
}

impl WaveFormat {
    /// The file extension (`vcd`, `fst`).
    pub fn extension(self) -> &'static str {
        match self {
            WaveFormat::Vcd => "vcd",
            WaveFormat::Fst => "fst",
        }
    }

    /// The format a path's extension names: `.fst` is FST, anything else VCD.
    pub fn of_path(path: &Path) -> WaveFormat {
        match path.extension().and_then(|e| e.to_str()) {
            Some(e) if e.eq_ignore_ascii_case("fst") => WaveFormat::Fst,
            _ => WaveFormat::Vcd,
        }
    }
}

/// The format `WAVES` asks for: `None` when unset, empty or `0`; VCD for `1` or `vcd`; FST for
/// `fst` (letters in any case).
///
/// # Panics
/// When `WAVES` is anything else (the message names `WAVES` and the accepted values).
pub fn requested_format() -> Option<WaveFormat> {
    try_requested_format().unwrap_or_else(|e| panic!("{e}"))
}

/// [`requested_format`], with an error for a `WAVES` value that is not a waveform choice.
pub fn try_requested_format() -> Result<Option<WaveFormat>, String> {
    match std::env::var("WAVES") {
        Ok(v) => format_of(&v),
        Err(std::env::VarError::NotPresent) => Ok(None),
        Err(std::env::VarError::NotUnicode(v)) => format_of(&v.to_string_lossy()),
    }
}

/// The format a `WAVES` value asks for ([`requested_format`]).
pub fn format_of(value: &str) -> Result<Option<WaveFormat>, String> {
    Ok(waves_env::parse_waves(value)?.map(|f| if f == "fst" { WaveFormat::Fst } else { WaveFormat::Vcd }))
}

/// The `.gtkw` beside a waveform file (same stem).
pub fn gtkw_path(waves: &Path) -> PathBuf {
    waves.with_extension("gtkw")
}

/// Writes the GTKWave save file for `top`'s `ports` (name, width) beside `waves` and returns its
/// path.
pub fn write_gtkw<'a>(
    waves: &Path,
    top: &str,
    ports: impl IntoIterator<Item = (&'a str, u32)>,
) -> std::io::Result<PathBuf> {
    let gtkw = gtkw_path(waves);
    std::fs::write(&gtkw, gtkw_text_of(waves, &gtkw, top, ports))?;
    Ok(gtkw)
}

/// The GTKWave save file text for `top`'s ports in `vcd` (signals as `TOP.<top>.<port>`).
pub fn gtkw_text(vcd: &Path, gtkw: &Path, top: &str, ports: &[PortSpec]) -> String {
    gtkw_text_of(vcd, gtkw, top, ports.iter().map(|p| (p.name, p.width)))
}

/// [`gtkw_text`] for ports given as (name, width), e.g. a run-time model's interface; `waves`
/// may be a VCD or an FST (GTKWave reads both, and names the signals alike).
pub fn gtkw_text_of<'a>(
    waves: &Path,
    gtkw: &Path,
    top: &str,
    ports: impl IntoIterator<Item = (&'a str, u32)>,
) -> String {
    let mut s =
        format!("[dumpfile] \"{}\"\n[savefile] \"{}\"\n[timestart] 0\n", waves.display(), gtkw.display());
    s.push_str("[sst_expanded] 1\n[signals_width] 260\n");
    for (name, width) in ports {
        if width == 1 {
            // 28: binary display, right-justified.
            s.push_str(&format!("@28\nTOP.{top}.{name}\n"));
        } else {
            // 22: hex display.
            s.push_str(&format!("@22\nTOP.{top}.{name}[{}:0]\n", width - 1));
        }
    }
    s
}

/// A model that can write waves: the statically linked ones ([`Dut`]) and the ones built at run
/// time ([`DynModel`]).
pub trait Traceable {
    /// The top module's name.
    fn top(&self) -> &str;
    /// The ports (name, width), for the GTKWave save file.
    fn wave_ports(&self) -> Vec<(&str, u32)>;
    /// The format the model was built to trace in (`None`: untraced).
    fn traces(&self) -> Option<WaveFormat>;
    /// Starts a trace at `path`.
    fn open_trace(&mut self, path: &Path) -> std::io::Result<()>;
}

impl<D: Dut> Traceable for D {
    fn top(&self) -> &str {
        D::NAME
    }

    fn wave_ports(&self) -> Vec<(&str, u32)> {
        D::PORTS.iter().map(|p| (p.name, p.width)).collect()
    }

    fn traces(&self) -> Option<WaveFormat> {
        Some(MODEL_FORMAT)
    }

    fn open_trace(&mut self, path: &Path) -> std::io::Result<()> {
        self.trace_open(path)
    }
}

impl Traceable for DynModel {
    fn top(&self) -> &str {
        &self.interface().name
    }

    fn wave_ports(&self) -> Vec<(&str, u32)> {
        self.interface().ports.iter().map(|p| (p.name.as_str(), p.width)).collect()
    }

    fn traces(&self) -> Option<WaveFormat> {
        self.wave_format()
    }

    fn open_trace(&mut self, path: &Path) -> std::io::Result<()> {
        self.trace_open(path)
    }
}

/// When `WAVES` asks for waves, opens `target/waves/<test>.vcd` (`WAVES=1`, `vcd`) or
/// `target/waves/<test>.fst` (`WAVES=fst`) on `dut`, writes the `.gtkw` next to it and prints
/// both paths; returns the waves path. Otherwise does nothing.
///
/// # Panics
/// When `WAVES` is not a waveform choice, when the model does not trace in the requested format
/// (a crate built without `WAVES=fst` runs with it: the message says to rebuild), or when the
/// files cannot be created.
pub fn maybe_trace<T: Traceable>(dut: &mut T, test: &str) -> Option<PathBuf> {
    let format = requested_format()?;
    Some(trace_to(dut, &target_dir().join("waves"), test, format))
}

/// [`try_trace_to`], panicking on its error.
///
/// # Panics
/// When [`try_trace_to`] fails.
pub fn trace_to<T: Traceable>(dut: &mut T, dir: &Path, test: &str, format: WaveFormat) -> PathBuf {
    try_trace_to(dut, dir, test, format).unwrap_or_else(|e| panic!("{e}"))
}

/// Opens `<dir>/<test>.<vcd|fst>` (`format`) on `dut` and writes `<dir>/<test>.gtkw` naming it;
/// prints both paths and returns the waves path. Fails when `dut` does not trace in `format`
/// or a file cannot be created.
pub fn try_trace_to<T: Traceable>(
    dut: &mut T,
    dir: &Path,
    test: &str,
    format: WaveFormat,
) -> Result<PathBuf, String> {
    let ext = format.extension();
    if dut.traces() != Some(format) {
        let built = dut.traces().map_or("nothing".to_string(), |f| f.extension().to_uppercase());
        return Err(format!(
            "WAVES={ext}: the {} model of this build traces {built}; the statically linked models \
             trace FST only when the crate is built with WAVES=fst in cargo's environment \
             (`WAVES=fst cargo test -p neo-tb ...` rebuilds them; without it they trace VCD)",
            dut.top()
        ));
    }
    std::fs::create_dir_all(dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    let waves = dir.join(format!("{test}.{ext}"));
    dut.open_trace(&waves).map_err(|e| format!("{}: {e}", waves.display()))?;
    let gtkw = gtkw_path(&waves);
    let text = gtkw_text_of(&waves, &gtkw, dut.top(), dut.wave_ports());
    std::fs::write(&gtkw, text).map_err(|e| format!("cannot write {}: {e}", gtkw.display()))?;
    println!("waves: {}\nwaves: gtkwave {}", waves.display(), gtkw.display());
    Ok(waves)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gtkw_lists_ports_with_ranges() {
        let ports = [
            PortSpec { name: "clk_i", input: true, width: 1 },
            PortSpec { name: "in_data_i", input: true, width: 768 },
        ];
        let t = gtkw_text(Path::new("/w/a.vcd"), Path::new("/w/a.gtkw"), "neo_bsu", &ports);
        assert!(t.starts_with("[dumpfile] \"/w/a.vcd\"\n"));
        assert!(t.contains("@28\nTOP.neo_bsu.clk_i\n"));
        assert!(t.contains("@22\nTOP.neo_bsu.in_data_i[767:0]\n"));
    }

    #[test]
    fn the_extension_and_waves_choose_the_format() {
        assert_eq!(WaveFormat::of_path(Path::new("/w/a.fst")), WaveFormat::Fst);
        assert_eq!(WaveFormat::of_path(Path::new("/w/a.FST")), WaveFormat::Fst);
        assert_eq!(WaveFormat::of_path(Path::new("/w/a.vcd")), WaveFormat::Vcd);
        assert_eq!(WaveFormat::of_path(Path::new("/w/a")), WaveFormat::Vcd);
        assert_eq!(format_of("fst"), Ok(Some(WaveFormat::Fst)));
        assert_eq!(format_of("FST"), Ok(Some(WaveFormat::Fst)));
        assert_eq!(format_of("1"), Ok(Some(WaveFormat::Vcd)));
        assert_eq!(format_of("vcd"), Ok(Some(WaveFormat::Vcd)));
        assert_eq!(format_of("0"), Ok(None));
        assert_eq!(format_of(""), Ok(None));
        assert_eq!(gtkw_path(Path::new("/w/e.fst")), Path::new("/w/e.gtkw"));
    }

    #[test]
    fn a_bad_waves_value_names_waves_and_the_accepted_values() {
        for bad in ["foo", "2", "yes", "fsdb"] {
            let e = format_of(bad).expect_err(bad);
            assert!(e.contains(&format!("WAVES={bad}")), "{e}");
            for accepted in ["0", "1", "vcd", "fst"] {
                assert!(e.contains(accepted), "{e} lacks {accepted}");
            }
        }
    }
}
