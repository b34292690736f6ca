//! Printing a [`Module`] as Verilog-2005 text.

use super::{Instance, Item, Module, Stmt};
use crate::interface::Dir;
use std::fmt::Write;

const IND: &str = "  ";

fn range(width: u32) -> String {
    vec_range(width, false)
}

/// `[W-1:0]`, or nothing for one bit unless `vector`.
fn vec_range(width: u32, vector: bool) -> String {
    if width == 1 && !vector {
        String::new()
    } else {
        format!("[{}:0]", width - 1)
    }
}

fn indent(level: usize) -> String {
    IND.repeat(level)
}

/// The whole file text of `m`.
pub(super) fn module(m: &Module) -> String {
    let mut s = String::new();
    s.push_str(&m.header());
    s.push('\n');
    for line in &m.doc {
        push_comment(&mut s, 0, line);
    }
    write!(s, "module {}", m.name).unwrap();
    if !m.params.is_empty() {
        s.push_str(" #(\n");
        for (k, p) in m.params.iter().enumerate() {
            let sep = if k + 1 < m.params.len() { "," } else { "" };
            writeln!(s, "{IND}parameter integer {} = {}{sep}", p.name, p.value).unwrap();
        }
        s.push(')');
    }
    s.push_str(" (\n");
    let pr = |p: &super::PortDecl| match m.param_widths.get(&p.name) {
        Some(w) => format!("[{w}-1:0]"),
        None => vec_range(p.width, m.vectors.contains(&p.name)),
    };
    let rw = m.ports.iter().map(|p| pr(p).len()).max().unwrap_or(0);
    let decls: Vec<String> = m
        .ports
        .iter()
        .enumerate()
        .map(|(k, p)| {
            let dir = match p.dir {
                Dir::In => "input ",
                Dir::Out => "output",
            };
            let sep = if k + 1 < m.ports.len() { "," } else { "" };
            format!("{IND}{dir} wire {:<rw$} {}{sep}", pr(p), p.name)
        })
        .collect();
    // Trailing comments line up one column after the longest commented declaration.
    let cw = m.ports.iter().zip(&decls).filter(|(p, _)| p.comment.is_some()).map(|(_, d)| d.len()).max();
    for (p, d) in m.ports.iter().zip(&decls) {
        match (&p.comment, cw) {
            (Some(c), Some(cw)) => writeln!(s, "{d:<cw$}  // {c}").unwrap(),
            _ => writeln!(s, "{d}").unwrap(),
        }
    }
    s.push_str(");\n\n");
    items(&mut s, 1, &m.items, m, false);
    s.push_str("\nendmodule\n");
    s
}

fn push_comment(s: &mut String, level: usize, text: &str) {
    for line in text.lines() {
        if line.is_empty() {
            writeln!(s, "{}//", indent(level)).unwrap();
        } else {
            writeln!(s, "{}// {line}", indent(level)).unwrap();
        }
    }
    if text.is_empty() {
        writeln!(s, "{}//", indent(level)).unwrap();
    }
}

/// `KIND [W-1:0] name` (`[EXPR-1:0]` for a width of [`Module::param_widths`]).
fn decl(m: &Module, kind: &str, width: u32, name: &str) -> String {
    if let Some(w) = m.param_widths.get(name) {
        format!("{kind:<4} [{w}-1:0] {name}")
    } else if width == 1 {
        format!("{kind:<4} {name}")
    } else {
        format!("{kind:<4} {} {name}", range(width))
    }
}

/// Prints `list` at indent `level`; `in_generate` when inside a generate loop (no nested
/// `generate ... endgenerate`, for [`Item::GenFor`] and [`Item::GenLoop`] alike).
fn items(s: &mut String, level: usize, list: &[Item], m: &Module, in_generate: bool) {
    let ind = indent(level);
    for it in list {
        match it {
            Item::Comment(t) => push_comment(s, level, t),
            Item::Blank => s.push('\n'),
            Item::LocalParam { name, width, value } => {
                let r = match m.param_widths.get(name) {
                    Some(w) => format!("[{w}-1:0] "),
                    None if *width == 0 => String::new(),
                    None => format!("{} ", vec_range(*width, true)),
                };
                writeln!(s, "{ind}localparam {r}{name} = {value};").unwrap();
            }
            Item::Integer(name) => writeln!(s, "{ind}integer {name};").unwrap(),
            Item::Wire { name, width } if *width == 1 && m.vectors.contains(name) => {
                writeln!(s, "{ind}wire [0:0] {name};").unwrap()
            }
            Item::Wire { name, width } => writeln!(s, "{ind}{};", decl(m, "wire", *width, name)).unwrap(),
            Item::Reg { name, width } => writeln!(s, "{ind}{};", decl(m, "reg", *width, name)).unwrap(),
            Item::Mem { name, width, depth } => {
                let last =
                    m.param_depths.get(name).map_or_else(|| (depth - 1).to_string(), |d| format!("{d}-1"));
                writeln!(s, "{ind}{} [0:{last}];", decl(m, "reg", *width, name)).unwrap()
            }
            Item::Assign { lhs, rhs } => writeln!(s, "{ind}assign {lhs} = {rhs};").unwrap(),
            Item::Seq { reset: Some(reset), body } => with_reset(s, level, "posedge", reset, body),
            Item::Seq { reset: None, body } => {
                writeln!(s, "{ind}always @(posedge clk_i) begin").unwrap();
                stmts(s, level + 1, body, "<=");
                writeln!(s, "{ind}end").unwrap();
            }
            Item::SeqFalling { reset, body } => with_reset(s, level, "negedge", reset, body),
            Item::Comb(body) => {
                writeln!(s, "{ind}always @* begin").unwrap();
                stmts(s, level + 1, body, "=");
                writeln!(s, "{ind}end").unwrap();
            }
            Item::Instance(i) => instance(s, level, i),
            Item::GenFor { var, count, label, items: body } => {
                generate_loop(s, level, (var, &count.to_string(), label), body, m, in_generate)
            }
            Item::GenLoop { var, bound, label, items: body } => {
                generate_loop(s, level, (var, bound, label), body, m, in_generate)
            }
            Item::GenIf { cond, label, then, else_label, els } => {
                assert!(in_generate, "a generate if ({label}) belongs in a generate loop");
                writeln!(s, "{ind}if ({cond}) begin : {label}").unwrap();
                items(s, level + 1, then, m, true);
                writeln!(s, "{ind}end else begin : {else_label}").unwrap();
                items(s, level + 1, els, m, true);
                writeln!(s, "{ind}end").unwrap();
            }
            Item::Covers(points) => {
                writeln!(s, "`ifdef VERILATOR").unwrap();
                push_comment(s, level, "Named cover points (Verilator --coverage-user: scripts/coverage).");
                for c in points {
                    push_comment(s, level, &c.what);
                    writeln!(s, "{ind}{}: cover property (@(posedge clk_i) ({}));", c.label, c.cond).unwrap();
                }
                writeln!(s, "`endif").unwrap();
            }
        }
    }
}

/// `genvar VAR;` and `for (VAR = 0; VAR < BOUND; VAR = VAR + 1) begin : LABEL BODY end`, wrapped
/// in `generate ... endgenerate` unless already inside a generate loop ([`Item::GenFor`],
/// [`Item::GenLoop`]).
fn generate_loop(
    s: &mut String,
    level: usize,
    (var, bound, label): (&str, &str, &str),
    body: &[Item],
    m: &Module,
    in_generate: bool,
) {
    let ind = indent(level);
    writeln!(s, "{ind}genvar {var};").unwrap();
    let inner = if in_generate { level } else { level + 1 };
    if !in_generate {
        writeln!(s, "{ind}generate").unwrap();
    }
    let lind = indent(inner);
    writeln!(s, "{lind}for ({var} = 0; {var} < {bound}; {var} = {var} + 1) begin : {label}").unwrap();
    items(s, inner + 1, body, m, true);
    writeln!(s, "{lind}end").unwrap();
    if !in_generate {
        writeln!(s, "{ind}endgenerate").unwrap();
    }
}

fn instance(s: &mut String, level: usize, i: &Instance) {
    let ind = indent(level);
    write!(s, "{ind}{}", i.module).unwrap();
    if !i.params.is_empty() {
        s.push_str(" #(\n");
        for (k, (p, v)) in i.params.iter().enumerate() {
            let sep = if k + 1 < i.params.len() { "," } else { "" };
            writeln!(s, "{ind}{IND}.{p}({v}){sep}").unwrap();
        }
        write!(s, "{ind})").unwrap();
    }
    writeln!(s, " {} (", i.name).unwrap();
    for (k, (p, e)) in i.conns.iter().enumerate() {
        let sep = if k + 1 < i.conns.len() { "," } else { "" };
        writeln!(s, "{ind}{IND}.{p}({e}){sep}").unwrap();
    }
    writeln!(s, "{ind});").unwrap();
}

/// `always @(EDGE clk_i or negedge rst_ni)` with `reset` while `rst_ni` is low, else `body`.
fn with_reset(s: &mut String, level: usize, edge: &str, reset: &[Stmt], body: &[Stmt]) {
    let ind = indent(level);
    writeln!(s, "{ind}always @({edge} clk_i or negedge rst_ni) begin").unwrap();
    writeln!(s, "{ind}{IND}if (!rst_ni) begin").unwrap();
    stmts(s, level + 2, reset, "<=");
    writeln!(s, "{ind}{IND}end else begin").unwrap();
    stmts(s, level + 2, body, "<=");
    writeln!(s, "{ind}{IND}end").unwrap();
    writeln!(s, "{ind}end").unwrap();
}

fn stmts(s: &mut String, level: usize, list: &[Stmt], op: &str) {
    let ind = indent(level);
    for st in list {
        match st {
            Stmt::Set(l, r) => writeln!(s, "{ind}{l} {op} {r};").unwrap(),
            Stmt::Comment(t) => push_comment(s, level, t),
            Stmt::If(c, then, els) => {
                writeln!(s, "{ind}if ({c}) begin").unwrap();
                stmts(s, level + 1, then, op);
                if els.is_empty() {
                    writeln!(s, "{ind}end").unwrap();
                } else if let [Stmt::If(..)] = els.as_slice() {
                    // `else if` chains print flat.
                    s.push_str(&ind);
                    s.push_str("end else ");
                    let mut inner = String::new();
                    stmts(&mut inner, level, els, op);
                    s.push_str(inner.trim_start());
                } else {
                    writeln!(s, "{ind}end else begin").unwrap();
                    stmts(s, level + 1, els, op);
                    writeln!(s, "{ind}end").unwrap();
                }
            }
            Stmt::For(var, bound, body) => {
                writeln!(s, "{ind}for ({var} = 0; {var} < {bound}; {var} = {var} + 1) begin").unwrap();
                stmts(s, level + 1, body, op);
                writeln!(s, "{ind}end").unwrap();
            }
            Stmt::Case(sel, arms, default) => {
                writeln!(s, "{ind}case ({sel})").unwrap();
                for (label, body) in arms {
                    writeln!(s, "{ind}{IND}{label}: begin").unwrap();
                    stmts(s, level + 2, body, op);
                    writeln!(s, "{ind}{IND}end").unwrap();
                }
                writeln!(s, "{ind}{IND}default: begin").unwrap();
                stmts(s, level + 2, default, op);
                writeln!(s, "{ind}{IND}end").unwrap();
                writeln!(s, "{ind}endcase").unwrap();
            }
        }
    }
}
