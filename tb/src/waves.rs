//! `WAVES=1`: a VCD of the test at `target/waves/<test>.vcd` and a GTKWave save file
//! `target/waves/<test>.gtkw` listing the unit's ports.

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
    std::env::var("WAVES").is_ok_and(|v| !v.is_empty() && v != "0")
}

/// The GTKWave save file text for `top`'s ports in `vcd` (signals as `TOP.<top>.<port>`).
pub fn gtkw_text(vcd: &Path, gtkw: &Path, top: &str, ports: &[PortSpec]) -> String {
    let mut s =
        format!("[dumpfile] \"{}\"\n[savefile] \"{}\"\n[timestart] 0\n", vcd.display(), gtkw.display());
    s.push_str("[sst_expanded] 1\n[signals_width] 260\n");
    for p in ports {
        if p.width == 1 {
            // 28: binary display, right-justified.
            s.push_str(&format!("@28\nTOP.{top}.{}\n", p.name));
        } else {
            // 22: hex display.
            s.push_str(&format!("@22\nTOP.{top}.{}[{}:0]\n", p.name, p.width - 1));
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
}
