//! `neo_scu_exp`: the SCU's exp unit, combinational `e_o = ExpTable::eval(np_i)` (golden
//! [`ExpTable`]; the ROM contents are generated from `ExpTable::table`). One per lane, in
//! `neo_scu_lane`'s S3 -> S4 step.

use super::ScuWidths;
use crate::emit::expr::{bits_for, lit, zext};
use crate::emit::{set, Module, Stmt};
use neo_golden::engine::EngineConfig;
use neo_golden::raster::ExpTable;

/// Module name of the exp unit.
pub const NAME: &str = "neo_scu_exp";

/// The exp unit for `cfg`: combinational `e_o = ExpTable::eval(np_i)`.
pub fn module(cfg: &EngineConfig) -> Module {
    let b = cfg.raster_config().blend;
    let t = ExpTable::new(&b.exp, b.power_frac);
    let w = ScuWidths::new(cfg);
    let (tb, ib) = (b.exp.table_bits as u32, b.exp.interp_bits as u32);
    let fe = b.exp.out_frac as u32;
    let ew = w.e;
    let l2e = t.log2e_raw() as u64;
    let lw = bits_for(l2e);
    let is = t.input_shift();
    let pw = w.np + lw; // product width
    let mut m = Module::new(NAME);
    m.doc(
        "SCU exp unit (golden ExpTable::eval): e_o = exp(-np_i 2^-power_frac) with out_frac fraction bits.",
    );
    m.doc(format!(
        "y = round(np * {l2e} >> {is}); n = y >> {}, table index y[{}:{ib}], weight y[{}:0]; ROM of {} entries.",
        tb + ib,
        tb + ib - 1,
        ib.max(1) - 1,
        t.table().len()
    ));
    m.input_c("np_i", w.np, "-power, unsigned, power_frac fraction bits");
    m.output_c("e_o", ew, "exp, out_frac fraction bits");
    m.wire_assign("prod", pw, format!("{} * {}", zext("np_i", w.np, pw), lit(pw, l2e)));
    // y: the rounding shift of the product (width yw).
    let yw = pw + 1 - is;
    if is == 0 {
        m.wire_assign("y", yw, zext("prod", pw, yw));
    } else {
        m.wire_assign(
            "prod_r",
            pw + 1,
            format!("{} + {}", zext("prod", pw, pw + 1), lit(pw + 1, 1 << (is - 1))),
        );
        m.wire_assign("y", yw, format!("prod_r[{}:{is}]", pw));
    }
    let f = tb + ib;
    let nw = yw - f;
    let sw = bits_for(fe as u64 + 1);
    m.wire_assign("n", nw, format!("y[{}:{f}]", yw - 1));
    if nw > sw || (fe as u64 + 2) < (1u64 << nw) {
        m.wire_assign("big", 1, format!("n >= {}", lit(nw, fe as u64 + 2)));
    } else {
        m.wire_assign("big", 1, lit(1, 0));
    }
    let ix = if tb == 1 { format!("y[{ib}]") } else { format!("y[{}:{ib}]", f - 1) };
    m.wire_assign("idx", tb, ix);
    rom(&mut m, &t, tb, ew);
    if ib == 0 {
        m.wire_assign("e0", ew, "t0");
    } else {
        let iw = ew + ib + 1;
        m.wire_assign("diff", ew, "t0 - t1");
        m.wire_assign(
            "ip",
            iw,
            format!(
                "{} * {} + {}",
                zext("diff", ew, iw),
                zext(&format!("y[{}:0]", ib - 1), ib, iw),
                lit(iw, 1 << (ib - 1))
            ),
        );
        m.wire_assign("e0", ew, format!("t0 - ip[{}:{ib}]", ew + ib - 1));
    }
    // shr_round(e0, n) = (({e0, 0} >> n) + 1) >> 1 for every n >= 0.
    m.wire_assign("ee", ew + 1, format!("{{e0, 1'b0}} >> n[{}:0]", sw - 1));
    m.wire_assign("er", ew + 1, format!("ee + {}", lit(ew + 1, 1)));
    m.assign("e_o", format!("big ? {} : er[{ew}:1]", lit(ew, 0)));
    m
}

/// The ROM: `t0 = T[idx]`, `t1 = T[idx + 1]` (golden `ExpTable::table`), `idx` of `tb` bits.
fn rom(m: &mut Module, t: &ExpTable, tb: u32, ew: u32) {
    m.reg("t0", ew).reg("t1", ew);
    m.comment("ROM: T[idx] and T[idx + 1] (golden ExpTable::table).");
    let arms = (0..(1u64 << tb))
        .map(|j| {
            (
                lit(tb, j),
                vec![
                    set("t0", lit(ew, t.table()[j as usize] as u64)),
                    set("t1", lit(ew, t.table()[j as usize + 1] as u64)),
                ],
            )
        })
        .collect();
    m.comb(vec![
        set("t0", lit(ew, 0)),
        set("t1", lit(ew, 0)),
        Stmt::Case("idx".into(), arms, vec![Stmt::Comment("every index is listed".into())]),
    ]);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exp_rom_holds_the_golden_table() {
        let cfg = EngineConfig::default();
        let b = cfg.raster_config().blend;
        let t = ExpTable::new(&b.exp, b.power_frac);
        let v = module(&cfg).to_verilog();
        for (j, e) in t.table().iter().enumerate().take(t.table().len() - 1) {
            assert!(v.contains(&format!("t0 = 17'd{e};")), "entry {j}");
        }
        assert!(v.contains(&format!("t1 = 17'd{};", t.table().last().unwrap())));
    }
}
