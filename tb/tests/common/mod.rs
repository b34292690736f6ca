//! Helpers shared by the cosimulation tests: reading a dumped VCD back.
#![allow(dead_code)]

use std::collections::HashMap;
use std::path::Path;

/// The values of some signals just before each rising clock edge (one row per cycle), read from
/// a VCD written by the harness (every half period has a clock change, so every timestamp is
/// present; the clock-low timestamps hold the values the edge samples).
pub struct Samples {
    /// Signal names, in column order.
    pub names: Vec<String>,
    /// One row per cycle: each signal's value as a bit string (MSB first).
    pub rows: Vec<Vec<String>>,
}

impl Samples {
    /// Column of signal `name`.
    pub fn col(&self, name: &str) -> usize {
        self.names.iter().position(|n| n == name).unwrap_or_else(|| panic!("no column {name}"))
    }

    /// True when signal `name` is `1` in row `row`.
    pub fn high(&self, row: usize, name: &str) -> bool {
        self.rows[row][self.col(name)] == "1"
    }
}

fn bits(v: &vcd::Vector) -> String {
    v.iter().map(|b| b.to_string()).collect()
}

/// Reads `TOP.<top>.<signal>` for each of `signals` (and `clk_i`) from `path`.
pub fn pre_edge_samples(path: &Path, top: &str, signals: &[&str]) -> Samples {
    let file = std::fs::File::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut parser = vcd::Parser::new(std::io::BufReader::new(file));
    let header = parser.parse_header().unwrap_or_else(|e| panic!("{}: bad VCD header: {e}", path.display()));
    let code = |sig: &str| {
        header
            .find_var(&["TOP", top, sig])
            .unwrap_or_else(|| panic!("{}: no TOP.{top}.{sig} in the VCD", path.display()))
            .code
    };
    let clk = code("clk_i");
    let codes: Vec<_> = signals.iter().map(|s| code(s)).collect();
    let mut current: HashMap<vcd::IdCode, String> = HashMap::new();
    let mut rows = Vec::new();
    let mut started = false;
    let flush = |current: &HashMap<vcd::IdCode, String>, rows: &mut Vec<Vec<String>>| {
        if current.get(&clk).map(String::as_str) == Some("0") {
            rows.push(codes.iter().map(|c| current.get(c).cloned().unwrap_or_default()).collect());
        }
    };
    for cmd in parser {
        match cmd.unwrap_or_else(|e| panic!("{}: bad VCD body: {e}", path.display())) {
            vcd::Command::Timestamp(_) => {
                if started {
                    flush(&current, &mut rows);
                }
                started = true;
            }
            vcd::Command::ChangeScalar(c, v) => {
                current.insert(c, v.to_string());
            }
            vcd::Command::ChangeVector(c, v) => {
                current.insert(c, bits(&v));
            }
            _ => {}
        }
    }
    if started {
        flush(&current, &mut rows);
    }
    Samples { names: signals.iter().map(|s| s.to_string()).collect(), rows }
}

/// Checks the valid/ready rules on one stream of `s` and returns the number of transfers: while
/// `valid && !ready`, the next cycle must still have `valid` and the same `data`.
pub fn check_handshake(s: &Samples, valid: &str, ready: &str, data: &[&str]) -> usize {
    let mut transfers = 0;
    for k in 0..s.rows.len() {
        let (v, r) = (s.high(k, valid), s.high(k, ready));
        if v && r {
            transfers += 1;
        }
        if v && !r && k + 1 < s.rows.len() {
            assert!(s.high(k + 1, valid), "VCD row {k}: {valid} dropped while {ready} was low");
            for d in data {
                let c = s.col(d);
                assert_eq!(s.rows[k + 1][c], s.rows[k][c], "VCD row {k}: {d} changed while stalled");
            }
        }
    }
    transfers
}
