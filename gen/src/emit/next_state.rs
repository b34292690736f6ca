//! Registers with a separate next state: `x_d` computed in an `always @*` block (default
//! `x_d = x_q`, then the update rules) and loaded into `x_q` by a clocked block on every edge
//! (the lowRISC `_d` / `_q` split). The rules are written once as clocked statements on the
//! `_q` names; [`Module::seq_d`] moves them into the combinational block, so the logic is the
//! same as the clocked block it replaces (a register that is not updated keeps its value through
//! the `x_d = x_q` default, which synthesis folds back into the flop's enable).

use super::{set, Item, Module, Stmt};

/// The register `x_q` an assignment target names (`x_q`, `x_q[3]`, `x_q[a +: w]`).
fn target(lhs: &str) -> &str {
    lhs.split('[').next().unwrap_or(lhs).trim()
}

/// `x_q` -> `x_d`.
fn next_name(q: &str) -> String {
    let base = q.strip_suffix("_q").unwrap_or_else(|| panic!("register {q} does not end in _q"));
    format!("{base}_d")
}

/// The registers the statements assign, in first-assignment order.
fn targets(body: &[Stmt], out: &mut Vec<String>) {
    for st in body {
        match st {
            Stmt::Set(l, _) => {
                let t = target(l).to_string();
                if !out.contains(&t) {
                    out.push(t);
                }
            }
            Stmt::If(_, then, els) => {
                targets(then, out);
                targets(els, out);
            }
            Stmt::Case(_, arms, default) => {
                for (_, b) in arms {
                    targets(b, out);
                }
                targets(default, out);
            }
            Stmt::For(_, _, b) => targets(b, out),
            Stmt::Comment(_) => {}
        }
    }
}

/// The statements with every target `x_q...` renamed `x_d...` (right-hand sides unchanged:
/// they read the registers' present values, as the clocked statements did).
fn to_next(body: &[Stmt]) -> Vec<Stmt> {
    body.iter()
        .map(|st| match st {
            Stmt::Set(l, r) => {
                let t = target(l);
                Stmt::Set(format!("{}{}", next_name(t), &l[t.len()..]), r.clone())
            }
            Stmt::If(c, then, els) => Stmt::If(c.clone(), to_next(then), to_next(els)),
            Stmt::Case(sel, arms, default) => Stmt::Case(
                sel.clone(),
                arms.iter().map(|(l, b)| (l.clone(), to_next(b))).collect(),
                to_next(default),
            ),
            Stmt::For(v, n, b) => Stmt::For(v.clone(), n.clone(), to_next(b)),
            Stmt::Comment(t) => Stmt::Comment(t.clone()),
        })
        .collect()
}

impl Module {
    /// Registers updated by `body` (clocked statements on `_q` registers declared at the top
    /// level), split into next state and flops: `reg x_d;`, an `always @*` block with
    /// `x_d = x_q;` and `body` on the `_d` names, and a clocked block that applies `reset`
    /// (`None`: no reset) and otherwise loads every `x_q <= x_d`.
    ///
    /// # Panics
    /// When a target does not end in `_q` or is not a declared top-level register (generator bugs).
    pub fn seq_d(&mut self, reset: Option<Vec<Stmt>>, body: Vec<Stmt>) -> &mut Self {
        let mut regs = Vec::new();
        targets(&body, &mut regs);
        let mut defaults = Vec::new();
        let mut loads = Vec::new();
        for q in &regs {
            let width = self
                .items
                .iter()
                .find_map(|i| match i {
                    Item::Reg { name, width } if name == q => Some(*width),
                    _ => None,
                })
                .unwrap_or_else(|| panic!("{}: {q} is not a declared register", self.name));
            let d = next_name(q);
            self.reg(d.clone(), width);
            defaults.push(set(d.clone(), q.clone()));
            loads.push(set(q.clone(), d));
        }
        defaults.extend(to_next(&body));
        self.comb(defaults);
        self.item(Item::Seq { reset, body: loads })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::emit::if_;

    #[test]
    fn next_state_is_computed_apart_and_loaded_every_edge() {
        let mut m = Module::new("t");
        m.clock_reset().input("en_i", 1);
        m.reg("cnt_q", 4).reg("flags_q", 2);
        m.seq_d(
            Some(vec![set("cnt_q", "4'd0")]),
            vec![if_("en_i", vec![set("cnt_q", "cnt_q + 4'd1"), set("flags_q[1]", "1'b1")])],
        );
        let v = m.to_verilog();
        for line in [
            "reg  [3:0] cnt_d;",
            "reg  [1:0] flags_d;",
            "    cnt_d = cnt_q;",
            "    flags_d = flags_q;",
            "      cnt_d = cnt_q + 4'd1;",
            "      flags_d[1] = 1'b1;",
            "      cnt_q <= cnt_d;",
            "      flags_q <= flags_d;",
        ] {
            assert!(v.contains(line), "{line} missing in\n{v}");
        }
        assert!(!v.contains("cnt_q <= cnt_q"), "{v}");
    }

    #[test]
    #[should_panic(expected = "not a declared register")]
    fn an_undeclared_target_is_a_generator_bug() {
        let mut m = Module::new("t");
        m.seq_d(None, vec![set("x_q", "1'b0")]);
    }
}
