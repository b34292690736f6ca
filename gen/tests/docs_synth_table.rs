//! The section "Synthesis" of `docs/rtl.md` quotes `reports/synth.json`: its unit table (cells,
//! flip-flops, latches; comparators, depth and latency where the report has them), the engine's
//! totals per part and the BSU topologies must be the report's figures, so a regenerated report
//! fails this test until the doc follows it. Only figures are compared, never the Verilog hashes
//! (`synth_report.rs` ties the report to the Verilog).
//!
//! A unit row is named `` `TOP` `` followed by an optional parenthesis: `(glue)`, a hierarchical
//! top's own synthesis (its black boxes one cell each, the report's `synth`); `(with ...)` or
//! `(..., hierarchical)`, its whole hierarchy (`UnitReport::total_cells`, `total_flip_flops`,
//! `total_latches`: what `neo gen --stats` prints as "hierarchical: ... = N cells"); anything else
//! (`(ceil)`, `` (`PORTS` 8, the engine's) ``) describes a flat top, whose figures are its
//! `synth`. `TOP` is the report's unit label (`report::unit_label`: `neo_fp_to_int
//! #(.ROUNDING(2))`). Every row must name a report unit, and every report unit must have its
//! rows (a hierarchical one a glue row and a total row): no unit is excluded, the table lists
//! every top `--stats` synthesizes. A total row `(with its N ...)` must box N instances.

use neo_gen::report::tree::{self, engine_total, Part};
use neo_gen::report::{parse_unit_label, unit_label, SynthReport, UnitReport};
use std::collections::BTreeSet;
use std::path::PathBuf;

/// The heading of the section the tables are in.
const SECTION: &str = "## Synthesis (Yosys 0.23, generic gates)";

/// A file of the workspace, by its path from the workspace root.
fn read(rel: &str) -> String {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..").join(rel);
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// `reports/synth.json`.
fn report() -> SynthReport {
    serde_json::from_str(&read("reports/synth.json")).unwrap_or_else(|e| panic!("reports/synth.json: {e}"))
}

/// The text of the section under [`SECTION`], up to the next `## ` heading.
fn section(doc: &str) -> &str {
    let start = doc.find(SECTION).unwrap_or_else(|| panic!("docs/rtl.md has no section {SECTION:?}"));
    let body = &doc[start + SECTION.len()..];
    body.find("\n## ").map_or(body, |end| &body[..end])
}

/// A markdown table: its header cells and its rows' cells (the separator line dropped).
struct Table {
    header: Vec<String>,
    rows: Vec<Vec<String>>,
}

impl Table {
    /// The index of the column headed `name`.
    fn column(&self, name: &str) -> usize {
        self.header
            .iter()
            .position(|h| h == name)
            .unwrap_or_else(|| panic!("the table headed {:?} has no column {name:?}", self.header))
    }
}

/// The cell `i` of a table row, empty when the row is short.
fn cell(row: &[String], i: usize) -> &str {
    row.get(i).map_or("", String::as_str)
}

/// The cells of a table line (`| a | b |`), trimmed.
fn cells(line: &str) -> Vec<String> {
    let inner = line.trim().trim_start_matches('|').trim_end_matches('|');
    inner.split('|').map(|c| c.trim().to_string()).collect()
}

/// The one table of `text` whose first header cell is `first`.
fn table(text: &str, first: &str) -> Table {
    let mut tables: Vec<Vec<&str>> = Vec::new();
    let mut in_table = false;
    for line in text.lines() {
        let is_row = line.trim_start().starts_with('|');
        match (is_row, in_table) {
            (true, true) => tables.last_mut().expect("open table").push(line),
            (true, false) => tables.push(vec![line]),
            _ => {}
        }
        in_table = is_row;
    }
    let mut found = tables.into_iter().filter(|t| cells(t[0]).first().is_some_and(|c| c == first));
    let lines = found.next().unwrap_or_else(|| panic!("{SECTION} has no table headed {first:?}"));
    assert!(found.next().is_none(), "{SECTION} has two tables headed {first:?}");
    Table { header: cells(lines[0]), rows: lines.iter().skip(2).map(|l| cells(l)).collect() }
}

/// A figure of the doc: `-` is none; else a number with spaces (thin or not) between its digit
/// groups (`31 479`), optionally followed by a parenthesis (`10 (II 4)`, `0 (combinational)`).
fn figure(cell: &str) -> Result<Option<u64>, String> {
    let number = cell.split('(').next().unwrap_or_default().trim();
    if number == "-" {
        return Ok(None);
    }
    let digits: String = number.chars().filter(|c| !c.is_whitespace()).collect();
    digits.parse().map(Some).map_err(|_| format!("{cell:?} is not a figure"))
}

/// Which of a unit's figures a row quotes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
enum Kind {
    /// A flat top's synthesis.
    Flat,
    /// A hierarchical top's own logic with its boxes (`(glue)`).
    Glue,
    /// A hierarchical top's whole hierarchy (`(with ...)`, `(..., hierarchical)`).
    Total,
}

impl Kind {
    /// How a row of this kind is written, for the messages.
    fn form(self) -> &'static str {
        match self {
            Kind::Flat => "flat `TOP`",
            Kind::Glue => "`TOP` (glue)",
            Kind::Total => "`TOP` (with ...)",
        }
    }
}

/// A unit row's first cell: the report unit it names, which figures, and its parenthesis.
#[derive(Debug)]
struct RowName {
    unit: String,
    kind: Kind,
    note: String,
}

/// Parses a unit row's first cell (`` `neo_pre_dup` (with 2 ITUs) ``); the name is normalised
/// through `report::unit_label`.
fn row_name(cell: &str) -> Result<RowName, String> {
    let mut parts = cell.splitn(3, '`');
    let (Some(""), Some(name), Some(rest)) = (parts.next(), parts.next(), parts.next()) else {
        return Err(format!("row {cell:?} does not start with a `unit`"));
    };
    let (module, params) = parse_unit_label(name);
    let note = rest.trim().to_string();
    let kind = if note == "(glue)" {
        Kind::Glue
    } else if note.starts_with("(with ") || note.contains("hierarchical") {
        Kind::Total
    } else {
        Kind::Flat
    };
    Ok(RowName { unit: unit_label(&module, &params), kind, note })
}

/// The report's figures a row of `kind` quotes for `u`, by column: cells, flip-flops and latches
/// always; comparators, depth and latency only where the report has them (`None`: not checked).
fn expected(u: &UnitReport, kind: Kind) -> Result<Vec<(&'static str, Option<u64>)>, String> {
    let whole = match (kind, u.hierarchy.is_some()) {
        (Kind::Flat, true) => return Err("hierarchical in the report: write `(glue)` or `(with ...)`".into()),
        (Kind::Glue | Kind::Total, false) => return Err("not hierarchical in the report".into()),
        (Kind::Total, true) => true,
        _ => false,
    };
    let (cells, flip_flops, latches) = if whole {
        (u.total_cells(), u.total_flip_flops(), u.total_latches())
    } else {
        (u.synth.cells, u.synth.flip_flops, u.synth.latches)
    };
    let bsu = |v: Option<usize>| v.map(|v| v as u64);
    Ok(vec![
        ("cells", Some(cells)),
        ("flip-flops", Some(flip_flops)),
        ("latches", Some(latches)),
        ("comparators", bsu(u.comparators)),
        ("depth", bsu(u.depth)),
        ("latency", bsu(u.latency)),
    ])
}

/// `v` as the doc writes it, digit groups of three apart (`31 479`).
fn grouped(v: u64) -> String {
    let digits = v.to_string();
    let mut out = String::new();
    for (i, c) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i).is_multiple_of(3) {
            out.push(' ');
        }
        out.push(c);
    }
    out
}

/// Compares one row's `cell` under `column` with the report's `want` (`None`: not checked).
fn compare(row: &str, column: &str, cell: &str, want: Option<u64>) -> Option<String> {
    let want = want?;
    match figure(cell) {
        Ok(Some(v)) if v == want => None,
        Ok(_) => Some(format!("row {row}: {column}: doc {cell:?}, report \"{}\"", grouped(want))),
        Err(e) => Some(format!("row {row}: {column}: {e}, report \"{}\"", grouped(want))),
    }
}

/// The instance count a total row claims as `(with its N ...)`, if it does.
fn claimed_instances(note: &str) -> Option<u64> {
    let rest = note.strip_prefix("(with its ")?;
    let n: String = rest.chars().take_while(|c| c.is_ascii_digit() || c.is_whitespace()).collect();
    figure(&n).ok().flatten()
}

/// Checks a total row's `(with its N ...)` against the instances the report's hierarchy boxes.
fn check_claim(row: &str, note: &str, u: &UnitReport) -> Option<String> {
    let n = claimed_instances(note)?;
    let boxed: u64 = u.hierarchy.as_ref().map_or(0, |h| h.instances.iter().map(|i| i.1).sum());
    (n != boxed).then(|| format!("row {row}: boxed instances: doc {n}, report {boxed}"))
}

/// Every mismatch between the unit table of `section` and `report`: a wrong figure (row, column,
/// doc, report), a row naming no report unit or the wrong kind of figures, a row twice, a report
/// unit without its rows.
fn unit_table_mismatches(section: &str, report: &SynthReport) -> Vec<String> {
    let t = table(section, "unit");
    let mut errors = Vec::new();
    let mut seen: BTreeSet<(String, Kind)> = BTreeSet::new();
    for row in &t.rows {
        let name = match row_name(&row[0]) {
            Ok(n) => n,
            Err(e) => {
                errors.push(e);
                continue;
            }
        };
        let label = &row[0];
        let Some(u) = report.units.iter().find(|u| u.unit == name.unit) else {
            errors.push(format!("row {label}: reports/synth.json has no unit {:?}", name.unit));
            continue;
        };
        if !seen.insert((name.unit.clone(), name.kind)) {
            errors.push(format!("row {label}: a second {} row of {}", name.kind.form(), name.unit));
        }
        match expected(u, name.kind) {
            Ok(want) => {
                for (column, v) in want {
                    errors.extend(compare(label, column, cell(row, t.column(column)), v));
                }
            }
            Err(e) => errors.push(format!("row {label}: {e}")),
        }
        errors.extend(check_claim(label, &name.note, u));
    }
    for u in &report.units {
        let kinds: &[Kind] = if u.hierarchy.is_some() { &[Kind::Glue, Kind::Total] } else { &[Kind::Flat] };
        for k in kinds {
            if !seen.contains(&(u.unit.clone(), *k)) {
                errors.push(format!("report unit {:?} has no {} row in the doc table", u.unit, k.form()));
            }
        }
    }
    errors
}

/// A part's cells and flip-flops (`None` where a module has no figure).
type PartFigures = (Option<u64>, Option<u64>);

/// Every mismatch between the engine's per-part table of `section` (cells, flip-flops; its
/// lines are the Verilog's, not the report's) and `report.units` through `report::tree`, the
/// totals `neo gen --stats` prints.
fn parts_table_mismatches(section: &str, report: &SynthReport) -> Vec<String> {
    let t = table(section, "part");
    let totals = tree::build(&report.config, Some(report)).expect("the report's configuration").totals();
    let mut want: Vec<(String, PartFigures)> =
        totals.iter().map(|(p, t)| (p.name().to_string(), (t.cells, t.flip_flops))).collect();
    want.push(("engine".to_string(), engine_total(&totals)));
    let (cells, ffs) = (t.column("cells"), t.column("flip-flops"));
    let mut errors = Vec::new();
    for row in &t.rows {
        let Some((_, (c, f))) = want.iter().find(|(p, _)| *p == row[0]) else {
            errors.push(format!("row {}: not a part of the engine ({:?})", row[0], Part::ALL));
            continue;
        };
        errors.extend(compare(&row[0], "cells", cell(row, cells), *c));
        errors.extend(compare(&row[0], "flip-flops", cell(row, ffs), *f));
    }
    for (p, _) in &want {
        if !t.rows.iter().any(|r| r[0] == *p) {
            errors.push(format!("part {p} has no row in the doc table"));
        }
    }
    errors
}

/// Every mismatch between the BSU topology table of `section` and `report.bsu_topologies`.
fn topology_table_mismatches(section: &str, report: &SynthReport) -> Vec<String> {
    let t = table(section, "topology");
    let mut errors = Vec::new();
    for row in &t.rows {
        let name = row[0].trim_matches('`');
        let Some(r) = report.bsu_topologies.iter().find(|r| r.topology == name) else {
            errors.push(format!("row {}: reports/synth.json has no BSU topology {name:?}", row[0]));
            continue;
        };
        let want = [
            ("comparators", r.comparators as u64),
            ("depth", r.depth as u64),
            ("latency", r.latency as u64),
            ("cells", r.cells),
            ("flip-flops", r.flip_flops),
        ];
        for (column, v) in want {
            errors.extend(compare(&row[0], column, cell(row, t.column(column)), Some(v)));
        }
    }
    for r in &report.bsu_topologies {
        if !t.rows.iter().any(|row| row[0].trim_matches('`') == r.topology) {
            errors.push(format!("BSU topology {} has no row in the doc table", r.topology));
        }
    }
    errors
}

/// Fails listing `errors`, one a line, if there are any.
fn assert_none(what: &str, errors: &[String]) {
    assert!(
        errors.is_empty(),
        "docs/rtl.md {SECTION:?}, {what}, does not quote reports/synth.json \
         (copy the report's figures, as `neo gen --stats` prints them):\n  {}",
        errors.join("\n  ")
    );
}

#[test]
fn the_unit_table_quotes_the_synthesis_report() {
    let doc = read("docs/rtl.md");
    assert_none("the unit table", &unit_table_mismatches(section(&doc), &report()));
}

#[test]
fn the_engine_parts_table_quotes_the_synthesis_report() {
    let doc = read("docs/rtl.md");
    assert_none("the engine's per-part table", &parts_table_mismatches(section(&doc), &report()));
}

#[test]
fn the_bsu_topology_table_quotes_the_synthesis_report() {
    let doc = read("docs/rtl.md");
    assert_none("the BSU topology table", &topology_table_mismatches(section(&doc), &report()));
}

#[test]
fn figures_and_row_names_parse() {
    assert_eq!(figure("31 479"), Ok(Some(31_479)));
    assert_eq!(figure("3\u{2009}908\u{202f}161"), Ok(Some(3_908_161)), "thin spaces");
    assert_eq!(figure("10 (II 4)"), Ok(Some(10)));
    assert_eq!(figure("-"), Ok(None));
    assert!(figure("~1.73 M").is_err());
    let n = row_name("`neo_fp_to_int #(.ROUNDING(2))` (ceil)").expect("name");
    assert_eq!((n.unit.as_str(), n.kind), ("neo_fp_to_int #(.ROUNDING(2))", Kind::Flat));
    assert_eq!(row_name("`neo_pre_dup` (glue)").expect("name").kind, Kind::Glue);
    let n = row_name("`neo_engine` (16 + 4 + 4 preprocessing lanes, hierarchical)").expect("name");
    assert_eq!(n.kind, Kind::Total);
    assert_eq!(claimed_instances("(with its 1 234 primitives)"), Some(1234));
    assert_eq!(claimed_instances("(with 2 ITUs)"), None);
    assert_eq!(claimed_instances("(with its boxes)"), None);
    assert_eq!(
        (grouped(887), grouped(30_277_553), grouped(190_560)),
        ("887".into(), "30 277 553".into(), "190 560".into())
    );
    assert!(row_name("neo_bsu").is_err());
}

/// The checks fire: on a table written from the report itself, a changed figure, a dropped row,
/// a glue row quoting the total, a wrong instance count and an unknown unit are each reported,
/// naming the row and the column.
#[test]
fn a_changed_figure_or_a_missing_row_is_reported() {
    let r = report();
    let row = |label: &str, u: &UnitReport, kind: Kind| {
        let f: Vec<String> = expected(u, kind)
            .expect("kind")
            .into_iter()
            .map(|(_, v)| v.map_or("-".to_string(), |v| v.to_string()))
            .collect();
        format!("| {label} | {} |\n", f.join(" | "))
    };
    let mut good = String::from(
        "| unit | cells | flip-flops | latches | comparators | depth | latency |\n|-|-|-|-|-|-|-|\n",
    );
    for u in &r.units {
        if u.hierarchy.is_some() {
            good += &row(&format!("`{}` (glue)", u.unit), u, Kind::Glue);
            good += &row(&format!("`{}` (with its boxes, hierarchical)", u.unit), u, Kind::Total);
        } else {
            good += &row(&format!("`{}`", u.unit), u, Kind::Flat);
        }
    }
    assert_eq!(unit_table_mismatches(&good, &r), Vec::<String>::new());

    let msu = r.units.iter().find(|u| u.unit == "neo_msu").expect("neo_msu");
    let (cells, ffs) = (msu.synth.cells, msu.synth.flip_flops);
    let changed = good.replace(
        &row("`neo_msu`", msu, Kind::Flat),
        &format!("| `neo_msu` | {} | {ffs} | 0 | - | - | - |\n", grouped(cells + 1)),
    );
    assert_eq!(
        unit_table_mismatches(&changed, &r),
        [format!("row `neo_msu`: cells: doc \"{}\", report \"{}\"", grouped(cells + 1), grouped(cells))]
    );

    let dropped = good.replace(&row("`neo_msu`", msu, Kind::Flat), "");
    assert_eq!(
        unit_table_mismatches(&dropped, &r),
        ["report unit \"neo_msu\" has no flat `TOP` row in the doc table"]
    );

    let engine = r.units.iter().find(|u| u.unit == "neo_engine").expect("neo_engine");
    let glue_as_total = good.replace(
        &row("`neo_engine` (glue)", engine, Kind::Glue),
        &row("`neo_engine` (glue)", engine, Kind::Total),
    );
    let errors = unit_table_mismatches(&glue_as_total, &r);
    assert!(errors.iter().any(|e| e.starts_with("row `neo_engine` (glue): cells: doc")), "{errors:?}");

    let dup = r.units.iter().find(|u| u.unit == "neo_pre_dup").expect("neo_pre_dup");
    let boxed: u64 = dup.hierarchy.as_ref().map_or(0, |h| h.instances.iter().map(|i| i.1).sum());
    let wrong = boxed + 1;
    let claim =
        good.replace("`neo_pre_dup` (with its boxes", &format!("`neo_pre_dup` (with its {wrong} ITUs"));
    assert_eq!(
        unit_table_mismatches(&claim, &r),
        [format!(
            "row `neo_pre_dup` (with its {wrong} ITUs, hierarchical): boxed instances: doc {wrong}, \
             report {boxed}"
        )]
    );

    let unknown = format!("{good}| `neo_nothing` | 1 | 0 | 0 | - | - | - |\n");
    assert_eq!(
        unit_table_mismatches(&unknown, &r),
        ["row `neo_nothing`: reports/synth.json has no unit \"neo_nothing\""]
    );
}
