//! `neo_engine_regs`: the engine's control port, an AXI4-Lite subordinate (32-bit data, 12-bit
//! byte addresses) holding the register map of golden [`neo_golden::engine::regs`]. The decode
//! is generated from the golden tables ([`Reg::ALL`], [`Reg::offset`], [`Reg::access`],
//! [`Counter::offset`]), so the map has one definition.
//!
//! # Protocol
//! - Word addressed: address bits `[1:0]` are ignored (an access is to the 32-bit word holding
//!   the address). Unmapped words read 0 and ignore writes, with an OKAY response (like reads of
//!   write-only and writes of read-only registers); BRESP and RRESP are always OKAY.
//! - Write: AW and W are taken independently into one-entry buffers (`awready = ~aw_full`,
//!   `wready = ~w_full`), so they may arrive in either order or together. The write happens in
//!   the cycle both buffers are full and the B slot is free (or being emptied); B is valid from
//!   the next cycle. WSTRB selects the bytes written. One write per two cycles at most.
//! - Read: AR is taken when no R is pending (`arready = ~rvalid`); the word is sampled in that
//!   cycle (registered RDATA), valid from the next cycle. One read per two cycles at most.
//! - No ready depends combinationally on a valid.
//!
//! # Registers
//! RW registers keep all 32 bits written (read back exactly); the outputs take their low bits
//! (`width_o`, `height_o` 16 bits; each base `[axi_addr_bits-1:0]` of its `{HI, LO}` pair).
//! `CTRL` (write only): a write whose byte 0 is enabled with bit 0 (`CTRL_START`) set while
//! `busy_i` is low gives a one-cycle `start_o` pulse, the cycle after the write. STATUS,
//! FIRST_OVERFLOW and OVERFLOWS read `busy_i`/`done_i`/`overflow_i`, `first_overflow_i`,
//! `overflows_i` at the read; counter `k` reads `counters_i[64k +: 32]` (low word) and
//! `counters_i[64k+32 +: 32]` (high word), two separate reads (read the counters while the
//! engine is idle, when they do not move).

use crate::emit::expr::{lit, slice};
use crate::emit::{if_, set, Module, Stmt};
use neo_golden::engine::regs::{
    Access, Counter, Reg, ADDR_BITS, COUNTERS, COUNTER_BASE, CTRL_START, DATA_BITS, STATUS_BUSY, STATUS_DONE,
    STATUS_OVERFLOW,
};
use neo_golden::engine::regs::{CameraWord, PRE_ENABLE, PRE_FRESH, PRE_SH_HALF};
use neo_golden::engine::EngineConfig;

/// Module name.
pub const NAME: &str = "neo_engine_regs";

/// Address bits of a word (the byte address without its two low bits).
const WORD_BITS: u32 = ADDR_BITS - 2;

/// The storage register of a read/write register: `frame_q`, `desc_base_lo_q`, ...
fn storage(r: Reg) -> String {
    format!("{}_q", r.name().to_ascii_lowercase())
}

/// The word index of a byte offset, as a case label.
fn word(offset: u32) -> String {
    lit(WORD_BITS, (offset / 4) as u64)
}

/// `STATUS`: each status input at the bit its golden constant names, zeros elsewhere.
fn status_value() -> String {
    let bits = [(STATUS_BUSY, "busy_i"), (STATUS_DONE, "done_i"), (STATUS_OVERFLOW, "overflow_i")];
    let mut parts = Vec::new();
    let mut zeros = 0;
    for b in (0..DATA_BITS).rev() {
        match bits.iter().find(|(mask, _)| *mask == 1 << b) {
            Some((_, sig)) => {
                if zeros > 0 {
                    parts.push(lit(zeros, 0));
                    zeros = 0;
                }
                parts.push(sig.to_string());
            }
            None => zeros += 1,
        }
    }
    if zeros > 0 {
        parts.push(lit(zeros, 0));
    }
    format!("{{{}}}", parts.join(", "))
}

/// What a read of `r` returns (`None`: write only, reads 0).
fn read_value(r: Reg) -> Option<String> {
    match r.access() {
        Access::W => None,
        Access::RW => Some(storage(r)),
        Access::R => Some(match r {
            Reg::Status => status_value(),
            Reg::FirstOverflow => "first_overflow_i".into(),
            Reg::Overflows => "overflows_i".into(),
            other => panic!("read-only register {} has no input in {NAME}", other.name()),
        }),
    }
}

/// The outputs driven by the read/write registers: `(port, width, value)`.
fn outputs(cfg: &EngineConfig) -> Vec<(String, u32, String)> {
    let a = cfg.axi_addr_bits;
    let base = |lo: Reg, hi: Reg| {
        if a == DATA_BITS {
            storage(lo)
        } else {
            format!("{{{}, {}}}", slice(&storage(hi), a - DATA_BITS - 1, 0), storage(lo))
        }
    };
    let mut out = vec![
        ("frame_o".to_string(), DATA_BITS, storage(Reg::Frame)),
        ("tiles_o".to_string(), DATA_BITS, storage(Reg::Tiles)),
        ("width_o".to_string(), 16, slice(&storage(Reg::Width), 15, 0)),
        ("height_o".to_string(), 16, slice(&storage(Reg::Height), 15, 0)),
    ];
    for (name, lo, hi) in [
        ("desc_base_o", Reg::DescBaseLo, Reg::DescBaseHi),
        ("result_base_o", Reg::ResultBaseLo, Reg::ResultBaseHi),
        ("feat_base_o", Reg::FeatBaseLo, Reg::FeatBaseHi),
        ("fb_base_o", Reg::FbBaseLo, Reg::FbBaseHi),
        ("scratch_base_o", Reg::ScratchBaseLo, Reg::ScratchBaseHi),
    ] {
        out.push((name.to_string(), a, base(lo, hi)));
    }
    let ctrl = storage(Reg::PreCtrl);
    out.push(("pre_enable_o".into(), 1, format!("{ctrl}[{}]", PRE_ENABLE.trailing_zeros())));
    out.push(("pre_fresh_o".into(), 1, format!("{ctrl}[{}]", PRE_FRESH.trailing_zeros())));
    out.push(("pre_sh_half_o".into(), 1, format!("{ctrl}[{}]", PRE_SH_HALF.trailing_zeros())));
    out.push(("gaussians_o".into(), DATA_BITS, storage(Reg::Gaussians)));
    let db = crate::units::pre::engine::degree_bits(cfg);
    out.push(("sh_degree_o".into(), db, slice(&storage(Reg::ShDegree), db - 1, 0)));
    for (name, lo, hi) in [
        ("geo_base_o", Reg::GeoBaseLo, Reg::GeoBaseHi),
        ("sh_base_o", Reg::ShBaseLo, Reg::ShBaseHi),
        ("prev_feat_base_o", Reg::PrevFeatBaseLo, Reg::PrevFeatBaseHi),
        ("list_base_o", Reg::ListBaseLo, Reg::ListBaseHi),
    ] {
        out.push((name.to_string(), a, base(lo, hi)));
    }
    for c in CameraWord::all() {
        out.push((camera_port(c), DATA_BITS, storage(Reg::Camera(c))));
    }
    out.push(("adapt_ctrl_o".into(), DATA_BITS, storage(Reg::AdaptCtrl)));
    out
}

/// The output carrying camera word `c`: its name in lower case, `_o`.
pub fn camera_port(c: CameraWord) -> String {
    format!("{}_o", c.name().to_ascii_lowercase())
}

/// The control port for `cfg`.
pub fn module(cfg: &EngineConfig) -> Module {
    let (aw, dw, n) = (ADDR_BITS, DATA_BITS, COUNTERS as u32);
    let mut m = Module::new(NAME);
    m.doc("Engine control port: AXI4-Lite subordinate, 32-bit data, 12-bit byte addresses (word addressed),");
    m.doc("register map of golden engine::regs; unmapped words read 0 and ignore writes, responses always");
    m.doc("OKAY. AW and W are buffered independently (either order); WSTRB selects bytes. See docs/rtl.md.");
    m.clock_reset();
    m.input("s_axil_awvalid_i", 1).output("s_axil_awready_o", 1);
    m.input_c("s_axil_awaddr_i", aw, "byte address (bits [1:0] ignored)");
    m.input("s_axil_wvalid_i", 1).output("s_axil_wready_o", 1);
    m.input("s_axil_wdata_i", dw).input_c("s_axil_wstrb_i", dw / 8, "byte enables");
    m.output("s_axil_bvalid_o", 1).input("s_axil_bready_i", 1);
    m.output_c("s_axil_bresp_o", 2, "always OKAY");
    m.input("s_axil_arvalid_i", 1).output("s_axil_arready_o", 1);
    m.input_c("s_axil_araddr_i", aw, "byte address (bits [1:0] ignored)");
    m.output("s_axil_rvalid_o", 1).input("s_axil_rready_i", 1);
    m.output("s_axil_rdata_o", dw);
    m.output_c("s_axil_rresp_o", 2, "always OKAY");
    m.output_c("start_o", 1, "one-cycle pulse: CTRL.start written while not busy");
    for (port, width, _) in outputs(cfg) {
        m.output(port, width);
    }
    m.input_c("busy_i", 1, "STATUS.busy");
    m.input_c("done_i", 1, "STATUS.done");
    m.input_c("overflow_i", 1, "STATUS.overflow");
    m.input_c("first_overflow_i", dw, "FIRST_OVERFLOW");
    m.input_c("overflows_i", dw, "OVERFLOWS");
    m.input_c("counters_i", 64 * n, "counter k at [64k +: 64] (golden Counter::index)");

    let rw: Vec<Reg> = Reg::ALL.iter().copied().filter(|r| r.access() == Access::RW).collect();
    for r in Reg::ALL {
        assert!(
            r.access() != Access::W || r == Reg::Ctrl,
            "write-only register {} has no function in {NAME}",
            r.name()
        );
    }

    m.comment("Write channel: one-entry AW and W buffers, the B slot.");
    m.reg("aw_full_q", 1).reg("aw_addr_q", WORD_BITS);
    m.reg("w_full_q", 1).reg("w_data_q", dw).reg("w_strb_q", dw / 8);
    m.reg("b_valid_q", 1);
    m.comment("Read channel: the R slot.");
    m.reg("r_valid_q", 1).reg("r_data_q", dw);
    m.reg("start_q", 1);
    m.comment("Read/write registers (golden Reg::access RW), all 32 bits kept.");
    for &r in &rw {
        m.reg(storage(r), dw);
    }
    m.blank();
    m.wire_assign("aw_take", 1, "s_axil_awvalid_i & ~aw_full_q");
    m.wire_assign("w_take", 1, "s_axil_wvalid_i & ~w_full_q");
    m.comment("The buffered write happens once both halves are in and B is free.");
    m.wire_assign("wr_fire", 1, "aw_full_q & w_full_q & (~b_valid_q | s_axil_bready_i)");
    m.wire_assign("ar_take", 1, "s_axil_arvalid_i & ~r_valid_q");
    let strobes: Vec<String> = (0..dw / 8).rev().map(|b| format!("{{8{{w_strb_q[{b}]}}}}")).collect();
    m.wire_assign("w_mask", dw, format!("{{{}}}", strobes.join(", ")));
    let start_bit = CTRL_START.trailing_zeros();
    m.wire_assign(
        "start_d",
        1,
        format!(
            "wr_fire & (aw_addr_q == {}) & w_strb_q[{}] & w_data_q[{start_bit}] & ~busy_i",
            word(Reg::Ctrl.offset()),
            start_bit / 8
        ),
    );
    for &r in &rw {
        let name = r.name().to_ascii_lowercase();
        m.wire_assign(format!("we_{name}"), 1, format!("wr_fire & (aw_addr_q == {})", word(r.offset())));
    }
    m.blank();
    m.comment("Read decode (golden Reg::offset / Counter::offset): unmapped and write-only words read 0.");
    m.reg("r_data_d", dw);
    let mut arms: Vec<(String, Vec<Stmt>)> = Vec::new();
    for r in Reg::ALL {
        if let Some(v) = read_value(r) {
            arms.push((word(r.offset()), vec![set("r_data_d", v)]));
        }
    }
    for c in Counter::ALL {
        let k = c.index() as u32;
        debug_assert_eq!(c.offset(), COUNTER_BASE + 8 * k);
        arms.push((word(c.offset()), vec![set("r_data_d", format!("counters_i[{} +: 32]", 64 * k))]));
        arms.push((
            word(c.offset() + 4),
            vec![set("r_data_d", format!("counters_i[{} +: 32]", 64 * k + 32))],
        ));
    }
    m.comb(vec![
        set("r_data_d", lit(dw, 0)),
        Stmt::Case(slice("s_axil_araddr_i", aw - 1, 2), arms, Vec::new()),
    ]);
    m.blank();

    let reset = m.q_resets(&[]);
    let mut body = vec![
        if_(
            "aw_take",
            vec![set("aw_full_q", lit(1, 1)), set("aw_addr_q", slice("s_axil_awaddr_i", aw - 1, 2))],
        ),
        if_(
            "w_take",
            vec![
                set("w_full_q", lit(1, 1)),
                set("w_data_q", "s_axil_wdata_i"),
                set("w_strb_q", "s_axil_wstrb_i"),
            ],
        ),
        Stmt::If(
            "wr_fire".into(),
            vec![set("aw_full_q", lit(1, 0)), set("w_full_q", lit(1, 0)), set("b_valid_q", lit(1, 1))],
            vec![if_("s_axil_bready_i", vec![set("b_valid_q", lit(1, 0))])],
        ),
        Stmt::If(
            "ar_take".into(),
            vec![set("r_valid_q", lit(1, 1)), set("r_data_q", "r_data_d")],
            vec![if_("s_axil_rready_i", vec![set("r_valid_q", lit(1, 0))])],
        ),
        set("start_q", "start_d"),
    ];
    for &r in &rw {
        let (q, name) = (storage(r), r.name().to_ascii_lowercase());
        body.push(if_(format!("we_{name}"), vec![set(&q, format!("({q} & ~w_mask) | (w_data_q & w_mask)"))]));
    }
    m.seq(reset, body);
    m.blank();
    m.assign("s_axil_awready_o", "~aw_full_q");
    m.assign("s_axil_wready_o", "~w_full_q");
    m.assign("s_axil_bvalid_o", "b_valid_q");
    m.assign("s_axil_bresp_o", lit(2, 0));
    m.assign("s_axil_arready_o", "~r_valid_q");
    m.assign("s_axil_rvalid_o", "r_valid_q");
    m.assign("s_axil_rdata_o", "r_data_q");
    m.assign("s_axil_rresp_o", lit(2, 0));
    m.assign("start_o", "start_q");
    for (port, _, value) in outputs(cfg) {
        m.assign(port, value);
    }
    m.comment("Word addressed: the byte lanes of the addresses are not decoded.");
    m.wire_assign("unused_addr_lsbs", 1, "^{s_axil_awaddr_i[1:0], s_axil_araddr_i[1:0]}");
    m
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_decode_follows_the_golden_map() {
        let v = module(&EngineConfig::default()).to_verilog();
        // Every readable register and both words of every counter are a case arm.
        for r in Reg::ALL {
            let arm = format!("      {}: begin\n", word(r.offset()));
            assert_eq!(v.contains(&arm), r.access() != Access::W, "{}", r.name());
        }
        for c in Counter::ALL {
            for off in [c.offset(), c.offset() + 4] {
                assert!(v.contains(&format!("      {}: begin\n", word(off))), "{} {off:#x}", c.name());
            }
        }
        assert!(v.contains("r_data_d = {29'd0, overflow_i, done_i, busy_i};"), "{v}");
        assert!(v.contains("assign desc_base_o = desc_base_lo_q;"), "{v}");
    }

    #[test]
    fn wide_addresses_take_the_high_words() {
        let cfg = EngineConfig { axi_addr_bits: 40, ..EngineConfig::default() };
        let v = module(&cfg).to_verilog();
        assert!(v.contains("assign fb_base_o = {fb_base_hi_q[7:0], fb_base_lo_q};"), "{v}");
        assert!(v.lines().any(|l| l.contains("output wire [39:0]") && l.contains(" scratch_base_o,")), "{v}");
    }
}
