//! Sets `cfg(neo_sim_rtl)` when Verilator is available, with the same rule as `tb/build.rs`
//! (`$VERILATOR` or `verilator` on the PATH, with its runtime sources), so that the RTL
//! validation test compiles exactly when `neo_tb` has its Verilated models.

use std::path::PathBuf;
use std::process::Command;

fn main() {
    println!("cargo::rustc-check-cfg=cfg(neo_sim_rtl)");
    println!("cargo::rerun-if-env-changed=VERILATOR");
    println!("cargo::rerun-if-changed=build.rs");
    let exe = std::env::var_os("VERILATOR").map(PathBuf::from).unwrap_or_else(|| "verilator".into());
    let ok = Command::new(&exe).arg("--version").output().ok().filter(|o| o.status.success()).is_some()
        && Command::new(&exe)
            .args(["--getenv", "VERILATOR_ROOT"])
            .output()
            .ok()
            .map(|o| {
                PathBuf::from(String::from_utf8_lossy(&o.stdout).trim())
                    .join("include/verilated.cpp")
                    .is_file()
            })
            .unwrap_or(false);
    if ok {
        println!("cargo::rustc-cfg=neo_sim_rtl");
    } else {
        println!("cargo::rerun-if-changed=/usr/bin/verilator");
    }
}
