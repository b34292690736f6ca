//! `neo-coverage MERGED.dat OUT.md [HDL_DIR] [WAIVERS]`: the coverage report of `scripts/coverage`
//! (`neo_tb::coverage`): per module, lines and branches, toggle bits and named cover points, and
//! every hole, justified by a waiver (default `tb/coverage-waivers.txt`) or marked open. Source
//! lines are read from `HDL_DIR` (default `hdl`). Extra text for the report's header (the benches
//! run, the commands) comes from `$NEO_COVERAGE_NOTE`. The Preprocessing Engine's datapaths get
//! automatic waivers for the bits their known-bits analysis proves constant
//! (`coverage::known_bits_waivers`).

use neo_tb::coverage;
use std::process::ExitCode;

fn main() -> ExitCode {
    match run() {
        Ok(open) => {
            eprintln!("neo-coverage: {open} open hole(s)");
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("neo-coverage: {e}");
            ExitCode::from(2)
        }
    }
}

fn run() -> Result<usize, String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [dat, out, rest @ ..] = args.as_slice() else {
        return Err("usage: neo-coverage MERGED.dat OUT.md [HDL_DIR] [WAIVERS]".into());
    };
    let hdl = rest.first().map_or("hdl", String::as_str);
    let waivers_path = rest.get(1).map_or("tb/coverage-waivers.txt", String::as_str);
    let read = |p: &str| std::fs::read_to_string(p).map_err(|e| format!("{p}: {e}"));
    let points = coverage::parse_dat(&read(dat)?).map_err(|e| format!("{dat}: {e}"))?;
    let mut waivers =
        coverage::parse_waivers(&read(waivers_path)?).map_err(|e| format!("{waivers_path}: {e}"))?;
    // The known-bits waivers name the nets of this build's datapaths: only for a module whose
    // file in HDL_DIR is that text (past the header line, which names the configuration).
    let cfg = neo_tb::config();
    let body = |t: &str| t.split_once('\n').map_or("", |(_, rest)| rest).to_string();
    let mut auto = coverage::known_bits_waivers(&cfg);
    for (module, text) in coverage::pre_datapaths(&cfg) {
        let file = std::path::Path::new(hdl).join(format!("{module}.v"));
        let on_disk = std::fs::read_to_string(&file).unwrap_or_default();
        if body(&on_disk) != body(&text) {
            eprintln!(
                "neo-coverage: {} is not this build's {module}: no known-bits waivers for it",
                file.display()
            );
            auto.retain(|w| w.module != module);
        }
    }
    waivers.extend(auto);
    let modules = coverage::summarise(&points);
    let mut sources = std::collections::HashMap::new();
    for p in modules.values().flatten() {
        sources.entry(p.file.clone()).or_insert_with(|| {
            std::fs::read_to_string(std::path::Path::new(hdl).join(&p.file)).unwrap_or_default()
        });
    }
    let source = |file: &str, line: u32| -> String {
        let text = sources.get(file).map_or("", String::as_str);
        text.lines().nth(line.saturating_sub(1) as usize).unwrap_or("").to_string()
    };
    let note = std::env::var("NEO_COVERAGE_NOTE").unwrap_or_default();
    let header = format!("{}{note}\n", coverage::REPORT_HEADER);
    let report = coverage::markdown(&modules, &waivers, &source, &header);
    std::fs::write(out, &report).map_err(|e| format!("{out}: {e}"))?;
    let open = report
        .lines()
        .find_map(|l| l.strip_prefix("Open holes in all: "))
        .and_then(|n| n.trim_end_matches('.').parse().ok())
        .unwrap_or(0);
    Ok(open)
}
