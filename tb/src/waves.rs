//! `WAVES=1`: a VCD of the test at `target/waves/<test>.vcd` and a GTKWave save file
//! `target/waves/<test>.gtkw` listing the unit's ports.
//!
//! `WAVES=fst` asks for FST instead ([`requested_format`]), for the models built at run time
//! (the whole-frame engine benches; whole-frame VCDs are large): they are verilated with
//! `--trace-fst` (a separate cached build, [`crate::dynmodel::DynModel::build_traced`]). The
//! statically linked unit models are VCD-traced only and write a VCD for any `WAVES`.

use crate::dut::{Dut, PortSpec};
use std::path::{Path, PathBuf};

/// The cargo target directory this crate was built into (`target/`).
pub fn target_dir() -> PathBuf {
    std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("NEO_TB_TARGET_DIR")))
}

/// True when `WAVES` is set to something other than empty or `0`.
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

/// The format `WAVES` asks for: `None` when unset, empty or `0`; FST for `fst` (any case);
/// VCD for anything else (`1`, `vcd`).
pub fn requested_format() -> Option<WaveFormat> {
    format_of(&std::env::var("WAVES").ok()?)
}

/// [`requested_format`] of a `WAVES` value.
fn format_of(v: &str) -> Option<WaveFormat> {
    match v {
        "" | "0" => None,
        v if v.eq_ignore_ascii_case("fst") => Some(WaveFormat::Fst),
        _ => Some(WaveFormat::Vcd),
    }
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

/// When `WAVES=1`, opens `target/waves/<test>.vcd` on `dut`, writes the `.gtkw` next to it and
/// prints both paths; returns the VCD path. Otherwise does nothing.
///
/// # Panics
/// When the files cannot be created.
pub fn maybe_trace<D: Dut>(dut: &mut D, test: &str) -> Option<PathBuf> {
    if !waves_requested() {
        return None;
    }
    Some(trace_to(dut, &target_dir().join("waves"), test))
}

/// Opens `<dir>/<test>.vcd` on `dut` and writes `<dir>/<test>.gtkw`; prints both paths.
///
/// # Panics
/// When the files cannot be created.
pub fn trace_to<D: Dut>(dut: &mut D, dir: &Path, test: &str) -> PathBuf {
    std::fs::create_dir_all(dir).unwrap_or_else(|e| panic!("cannot create {}: {e}", dir.display()));
    let vcd = dir.join(format!("{test}.vcd"));
    let gtkw = dir.join(format!("{test}.gtkw"));
    dut.trace_open(&vcd).unwrap_or_else(|e| panic!("{e}"));
    std::fs::write(&gtkw, gtkw_text(&vcd, &gtkw, D::NAME, D::PORTS))
        .unwrap_or_else(|e| panic!("cannot write {}: {e}", gtkw.display()));
    println!("waves: {}\nwaves: gtkwave {}", vcd.display(), gtkw.display());
    vcd
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
        assert_eq!(format_of("fst"), Some(WaveFormat::Fst));
        assert_eq!(format_of("1"), Some(WaveFormat::Vcd));
        assert_eq!(format_of("0"), None);
        assert_eq!(format_of(""), None);
        assert_eq!(gtkw_path(Path::new("/w/e.fst")), Path::new("/w/e.gtkw"));
    }
}
