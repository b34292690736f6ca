//! `neo_axi_raster_bridge`: a `neo_raster_core` memory port as an AXI4 manager (engine client
//! `N+1..=N+M`).
//!
//! - Table reads (space 0): entry `a` at byte `8 a`, one entry per beat, cut at 4 KiB (as the
//!   sort bridge); the entry goes to the core in the low bits of `mem_rsp_data_o`.
//! - Feature reads (space 1, one word): word `w` at byte `32 w`, ARLEN 3; the 4 beats are
//!   assembled (beat `k` = bytes `8k..8k+8` of the word) and delivered as one response, the low
//!   feature-word bits of the 256.
//! - Writes: a table entry (space 0) is one single-beat AW + W at `8 a`; a pixel row (space 2) of
//!   `S` pixels at pixel address `p` is one burst of `S/2` beats at byte `4 p`, pixel `2j` in the
//!   low and `2j+1` in the high half of beat `j`, each as u32 `0x00BBGGRR` (golden
//!   `pixel_to_u32`). `p` must be even so the row starts on a beat (the engine's rows are
//!   `S`-aligned), and `4 p` a multiple of `4 S` for the burst to stay in one 4 KiB page.
//! - A FIFO of each burst's kind (table / feature) in AR order routes the R beats.
//! - W has two slots, so a port mux that forwards W a cycle after granting AW still takes one
//!   single-beat write per cycle.
//! - At most `axi_outstanding` read bursts and writes each in flight; `idle_o` and the pulses
//!   `rd_table_o`, `rd_feat_o`, `wr_table_o`, `wr_pixels_o`.

use super::{byte_addr, ports, read_issuer, unused_responses, w_slot_moves, write_constants, write_counter};
use crate::emit::expr::{bits_for, lit, slice, zext};
use crate::emit::{if_, if_else, set, Module};
use crate::units::raster_core::{feature_word_bits, wdata_bits};
use neo_golden::engine::{EngineConfig, AXI_DATA_BITS};
use neo_golden::raster::RGB_BITS;

/// Module name.
pub const NAME: &str = "neo_axi_raster_bridge";

/// Width of the raster core's `mem_req_len_o` (as in `neo_raster_core`).
fn len_bits(cfg: &EngineConfig) -> u32 {
    bits_for((cfg.burst as u64).max(u64::from(cfg.raster_config().subtile)))
}

/// Sizes of the raster bridge, from the configuration.
#[derive(Clone, Copy)]
struct Dims {
    /// Entry bits.
    eb: u32,
    /// Core address bits.
    aw: u32,
    /// AXI address bits.
    ab: u32,
    /// AXI data bits.
    db: u32,
    /// Feature word bits.
    fw: u32,
    /// Width of `mem_wdata_i`.
    wdb: u32,
    /// Width of `mem_req_len_i`.
    lb: u32,
    /// Subtile side `S` (pixels a row write).
    s: u32,
    /// Beats of a pixel row (`S / 2`).
    beats: u32,
    /// Width of the beat counter.
    bb: u32,
    /// Bits of two pixels.
    pw: u32,
    /// Depth of the burst-kind FIFO.
    depth: u32,
    /// Width of its pointers.
    kb: u32,
}

impl Dims {
    fn new(cfg: &EngineConfig) -> Self {
        let (eb, aw, ab, db) = (cfg.entry_bits(), cfg.addr_bits, cfg.axi_addr_bits, cfg.axi_data_bits);
        assert_eq!(
            db, AXI_DATA_BITS,
            "the raster bridge packs two pixels a beat: {AXI_DATA_BITS}-bit data only"
        );
        let fw = feature_word_bits(cfg);
        assert!(fw <= 256, "a feature word of {fw} bits does not fit 4 beats");
        let (wdb, lb) = (wdata_bits(cfg), len_bits(cfg));
        let s = cfg.raster_config().subtile;
        let beats = s / 2;
        let bb = bits_for(u64::from(beats - 1));
        let pw = 2 * RGB_BITS;
        let depth = cfg.axi_outstanding.max(2) as u32;
        let kb = bits_for(u64::from(depth - 1));
        Dims { eb, aw, ab, db, fw, wdb, lb, s, beats, bb, pw, depth, kb }
    }
}

/// The raster bridge for `cfg`.
///
/// # Panics
/// When the AXI data width is not [`AXI_DATA_BITS`] (validated by the configuration) or the feature word
/// does not fit 256 bits.
pub fn module(cfg: &EngineConfig) -> Module {
    let d = Dims::new(cfg);
    let mut m = Module::new(NAME);
    header(&mut m, cfg, &d);
    requests(&mut m, cfg, &d);
    read_path(&mut m, &d);
    write_path(&mut m, cfg, &d);
    let Dims { fw, db, .. } = d;
    m.blank();
    m.assign(
        "idle_o",
        format!("~ar_v_q & (rd_cnt_q == {c}) & (wr_cnt_q == {c})", c = lit(super::count_bits(cfg), 0)),
    );
    let unused = if fw < 4 * db { format!("feat_word[{}:{fw}]", 4 * db - 1) } else { String::new() };
    let extra: Vec<&str> = if fw < 4 * db { vec![unused.as_str()] } else { vec![] };
    unused_responses(&mut m, &extra);
    m
}

/// The header comment and the ports.
fn header(m: &mut Module, cfg: &EngineConfig, d: &Dims) {
    let Dims { aw, fw, wdb, lb, s, beats, .. } = *d;
    m.doc("Raster bridge: a neo_raster_core memory port (mem_*, the core's ports with _i/_o swapped) as an AXI4");
    m.doc("manager (m_axi_*, ID 0). Space 0 table entry a at byte 8a (bursts cut at 4 KiB), space 1 feature word w");
    m.doc(format!(
        "at byte 32w (4 beats assembled into one response), space 2 pixels p at byte 4p ({s} pixels = {beats} beats,"
    ));
    m.doc("u32 0x00BBGGRR each). At most axi_outstanding reads and writes each in flight. See docs/rtl.md.");
    m.clock_reset();
    m.input_c("mem_req_valid_i", 1, "core: request offered");
    m.output_c("mem_req_ready_o", 1, "request taken");
    m.input_c("mem_req_write_i", 1, "1: write; 0: read");
    m.input_c("mem_req_space_i", 2, "0 table, 1 feature, 2 pixel");
    m.input_c("mem_req_addr_i", aw, "address in units of the space's element");
    m.input_c("mem_req_len_i", lb, "table reads: entries (other requests: fixed size, ignored)");
    m.input_c("mem_wdata_i", wdb, "table entry (low bits) or S pixels, pixel k at [24k +: 24] = {b, g, r}");
    m.output_c("mem_rsp_valid_o", 1, "read response (table entry or whole feature word), in request order");
    m.input_c("mem_rsp_ready_i", 1, "the core takes the response (always 1 in neo_raster_core)");
    m.output_c("mem_rsp_data_o", fw, "table entry (low bits) or feature word {present, entry}");
    m.output_c("idle_o", 1, "no request pending, no read or write in flight");
    m.output_c("rd_table_o", 1, "pulse: a table entry delivered");
    m.output_c("rd_feat_o", 1, "pulse: a feature word delivered");
    m.output_c("wr_table_o", 1, "pulse: a table-entry write taken");
    m.output_c("wr_pixels_o", 1, "pulse: a pixel-row write taken");
    ports(m, cfg, "m_axi_", true);
}

/// Request decode and the read issuer.
fn requests(m: &mut Module, cfg: &EngineConfig, d: &Dims) {
    let Dims { aw, lb, .. } = *d;
    m.wire_assign("req_rd", 1, "mem_req_valid_i & ~mem_req_write_i");
    m.wire_assign("req_wr", 1, "mem_req_valid_i & mem_req_write_i");
    m.wire_assign("req_feat", 1, format!("mem_req_space_i == {}", lit(2, 1)));
    m.wire_assign("req_pix", 1, format!("mem_req_space_i == {}", lit(2, 2)));
    m.wire("ar_take", 1).wire("ar_new_addr", aw).wire("ar_new_len", lb).wire("ar_new_feat", 1);
    m.wire("wr_take", 1).wire("wr_ok", 1);
    read_issuer(m, cfg, lb, true);
    m.wire_assign("rd_ok", 1, "~ar_v_q | ar_done");
    m.assign("mem_req_ready_o", "mem_req_write_i ? wr_ok : rd_ok");
    m.assign("ar_take", "req_rd & rd_ok");
    m.assign("ar_new_addr", "mem_req_addr_i");
    m.assign("ar_new_len", "mem_req_len_i");
    m.assign("ar_new_feat", "req_feat");
}

/// The kind FIFO and the R path (table beats straight through, feature words assembled).
fn read_path(m: &mut Module, d: &Dims) {
    let Dims { eb, db, fw, depth, kb, .. } = *d;
    m.blank();
    m.comment(format!("Kind of each burst in flight (1: feature), in AR order ({depth} entries, at most axi_outstanding used)."));
    m.mem("kind_mem", 1, depth).reg("kind_wp_q", kb).reg("kind_rp_q", kb);
    m.wire_assign("r_feat", 1, "kind_mem[kind_rp_q]");
    m.seq(
        vec![set("kind_wp_q", lit(kb, 0)), set("kind_rp_q", lit(kb, 0))],
        vec![
            if_("ar_fire", vec![set("kind_wp_q", format!("kind_wp_q + {}", lit(kb, 1)))]),
            if_("r_end", vec![set("kind_rp_q", format!("kind_rp_q + {}", lit(kb, 1)))]),
        ],
    );
    m.seq_noreset(vec![if_("ar_fire", vec![set("kind_mem[kind_wp_q]", "ar_feat_q")])]);

    m.blank();
    m.comment(
        "R: table beats straight to the core; feature beats 0..2 collected, beat 3 completes the word.",
    );
    m.reg("fasm_q", 3 * db);
    m.wire_assign("r_deliver", 1, "~r_feat | m_axi_rlast_i");
    m.assign("m_axi_rready_o", "~r_deliver | mem_rsp_ready_i");
    m.assign("mem_rsp_valid_o", "m_axi_rvalid_i & r_deliver");
    m.wire_assign("feat_word", 4 * db, "{m_axi_rdata_i, fasm_q}");
    m.assign(
        "mem_rsp_data_o",
        format!(
            "r_feat ? {} : {}",
            slice("feat_word", fw - 1, 0),
            zext(&format!("m_axi_rdata_i[{}:0]", eb - 1), eb, fw)
        ),
    );
    m.seq_noreset(vec![if_(
        "r_fire & r_feat & ~m_axi_rlast_i",
        vec![set("fasm_q", format!("{{m_axi_rdata_i, {}}}", slice("fasm_q", 3 * db - 1, db)))],
    )]);
    m.wire_assign("rsp_fire", 1, "mem_rsp_valid_o & mem_rsp_ready_i");
    m.assign("rd_table_o", "rsp_fire & ~r_feat");
    m.assign("rd_feat_o", "rsp_fire & r_feat");
}

/// The AW and W path (table entries and pixel rows).
fn write_path(m: &mut Module, cfg: &EngineConfig, d: &Dims) {
    let Dims { eb, aw, ab, db, wdb, beats, bb, pw, .. } = *d;
    m.blank();
    m.comment(format!("AW + W: a table entry (1 beat) or a pixel row ({beats} beats of two pixels, shifted out of w_data_q)."));
    m.comment("W has a second slot (w2): a port mux forwards W in the cycle after it grants the AW, so with");
    m.comment("one slot single-beat writes would be taken only every other cycle.");
    write_counter(m, cfg);
    m.reg("aw_v_q", 1).reg("aw_pix_q", 1).reg("aw_addr_q", aw);
    m.reg("w_v_q", 1).reg("w_pix_q", 1).reg("w_left_q", bb).reg("w_data_q", wdb);
    m.reg("w2_v_q", 1).reg("w2_pix_q", 1).reg("w2_data_q", wdb);
    m.wire_assign("aw_fire", 1, "m_axi_awvalid_o & m_axi_awready_i");
    m.wire_assign("w_fire", 1, "m_axi_wvalid_o & m_axi_wready_i");
    m.wire_assign("w_last", 1, format!("w_left_q == {}", lit(bb, 0)));
    m.wire_assign("w_leave", 1, "w_fire & w_last");
    m.assign("wr_ok", "(~aw_v_q | aw_fire) & (~w2_v_q | w_leave) & wr_room");
    m.assign("wr_take", "req_wr & wr_ok");
    m.assign("wr_table_o", "wr_take & ~req_pix");
    m.assign("wr_pixels_o", "wr_take & req_pix");
    w_slot_moves(m, "w_leave");
    let first_left = |pix: &str| format!("{pix} ? {} : {}", lit(bb, u64::from(beats - 1)), lit(bb, 0));
    let shifted = if wdb > pw {
        format!("{{{}, {}}}", lit(pw, 0), slice("w_data_q", wdb - 1, pw))
    } else {
        "w_data_q".into()
    };
    m.seq(
        vec![
            set("aw_v_q", lit(1, 0)),
            set("aw_pix_q", lit(1, 0)),
            set("w_v_q", lit(1, 0)),
            set("w_pix_q", lit(1, 0)),
            set("w_left_q", lit(bb, 0)),
            set("w2_v_q", lit(1, 0)),
            set("w2_pix_q", lit(1, 0)),
        ],
        vec![
            if_("aw_fire", vec![set("aw_v_q", lit(1, 0))]),
            if_("wr_take", vec![set("aw_v_q", lit(1, 1)), set("aw_pix_q", "req_pix")]),
            if_(
                "w_fire",
                vec![if_else(
                    "w_last",
                    vec![
                        set("w_v_q", "w2_v_q"),
                        set("w_pix_q", "w2_pix_q"),
                        set("w_left_q", first_left("w2_pix_q")),
                        set("w2_v_q", lit(1, 0)),
                    ],
                    vec![set("w_left_q", format!("w_left_q - {}", lit(bb, 1)))],
                )],
            ),
            if_(
                "w_to_head",
                vec![
                    set("w_v_q", lit(1, 1)),
                    set("w_pix_q", "req_pix"),
                    set("w_left_q", first_left("req_pix")),
                ],
            ),
            if_("w_to_w2", vec![set("w2_v_q", lit(1, 1)), set("w2_pix_q", "req_pix")]),
        ],
    );
    m.seq_noreset(vec![
        if_("wr_take", vec![set("aw_addr_q", "mem_req_addr_i")]),
        if_else(
            "w_shift",
            vec![set("w_data_q", "w2_data_q")],
            vec![if_else(
                "w_to_head",
                vec![set("w_data_q", "mem_wdata_i")],
                vec![if_("w_fire", vec![set("w_data_q", shifted)])],
            )],
        ),
        if_("w_to_w2", vec![set("w2_data_q", "mem_wdata_i")]),
    ]);
    byte_addr(m, "aw_tbyte", "aw_addr_q", aw, 3, ab);
    byte_addr(m, "aw_pbyte", "aw_addr_q", aw, 2, ab);
    m.assign("m_axi_awvalid_o", "aw_v_q");
    m.assign("m_axi_awaddr_o", "aw_pix_q ? aw_pbyte : aw_tbyte");
    m.assign("m_axi_awlen_o", format!("aw_pix_q ? {} : {}", lit(8, u64::from(beats - 1)), lit(8, 0)));
    m.assign("m_axi_wvalid_o", "w_v_q");
    let pix = format!(
        "{{{z}, {}, {z}, {}}}",
        slice("w_data_q", pw - 1, RGB_BITS),
        slice("w_data_q", RGB_BITS - 1, 0),
        z = lit(8, 0)
    );
    m.assign("m_axi_wdata_o", format!("w_pix_q ? {pix} : {}", zext(&slice("w_data_q", eb - 1, 0), eb, db)));
    m.assign("m_axi_wlast_o", "w_last");
    write_constants(m, cfg);
}
