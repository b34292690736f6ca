//! `neo_raster_core`: one Rasterization Core (paper Section 5.4, Fig. 14): `raster_itus`
//! [`super::itu`] units and `raster_scus` [`super::scu`] units, a banked feature buffer, a command port
//! and a memory-request port. Renders one 64x64 tile from its sorted table, bit-exact with golden
//! [`neo_golden::raster::raster_tile`], and writes each table entry back with the current depth
//! key and the ITU's cumulative-OR valid bit (golden `pipeline::frame`'s deferred write-back).
//! The protocols, the schedule and the timing are documented in `docs/rtl.md` ("Raster core").
//!
//! # Schedule
//! The table is processed in *segments* of at most `F = raster_feature_buffer` entries (one
//! segment when the table fits). LOAD ([`loader`], `neo_raster_loader`) reads the segment's
//! table entries (bursts) and then, per entry, its feature word (`feature base + id`) into the
//! buffers. The subtiles are blended in `G = subtiles / raster_scus` *groups* of `raster_scus`
//! consecutive subtiles (row-major, SCU `j` takes subtile `g * raster_scus + j`). WALK
//! ([`walker`]) issues the segment to the ITUs, `raster_itus` entries (a *quad*) per cycle, once
//! per group (group 0 every quad, a later group only the quads group 0's results showed to touch
//! it); each ITU result is routed, per SCU, into a FIFO of `{final, last, resume, lane mask,
//! base}` elements, and a feeder per SCU ([`feeder`], `neo_raster_feeder`) sends the masked
//! entries' features to its SCU in table order. The FIFOs decouple the two: the ITUs test the
//! next group while the SCUs blend the current one (Fig. 14). Each segment is loaded once and
//! walked for every group (paper Section 5.4: "writes the intermediate pixel values to the pixel
//! buffer and proceeds to the next group"): one group's walk of a segment is a *piece* of each
//! of its subtiles' lists. A piece that is not the subtile's last saves the subtile's pixel
//! state in its SCU's state bank (`neo_scu` `in_final_i` low), and the next segment's piece
//! resumes from it (`in_resume_i`). The segments go round `raster_feature_banks` banks: the
//! loader fills the next bank while the current one is walked and blended, and a bank is
//! refilled once its segment is walked, every SCU has taken its last piece and its write-back
//! is done.
//!
//! Group 0's ITU results give every entry's valid bit (the bitmap covers all subtiles); the
//! write-back of entry `i` (`{valid = present & |bitmap, key = present ? depth_key : old key,
//! id}`) follows once the segment's group-0 results are in. A feature word with its `present`
//! bit clear is a Gaussian culled this frame (no feature entry): it is not rasterised, its
//! valid bit is cleared and its key kept (golden `raster_phase`). Finished subtiles are written
//! one pixel row (`S` pixels, [`RGB_BITS`] bits each) per request ([`writer`]).

pub mod feeder;
pub mod loader;
mod walker;
pub mod window;
pub mod window_loader;
mod writer;

use crate::emit::bundle::{Bundle, Field};
use crate::emit::expr::{bits_for, lit};
use crate::emit::{if_, if_else, set, Item, Module};
use crate::units::{itu, scu};
use neo_golden::engine::EngineConfig;
use neo_golden::raster::RGB_BITS;

/// Module name.
pub const NAME: &str = "neo_raster_core";

/// Entries per routing FIFO (one per SCU): how far the ITUs may run ahead of an SCU.
pub const FIFO_DEPTH: u32 = neo_golden::engine::ROUTING_FIFO_DEPTH;

/// Memory spaces (`mem_req_space_o`).
pub mod space {
    /// Table entries `{valid, key, id}` (read in bursts, written back one per request).
    pub const TABLE: u64 = 0;
    /// Feature words `{present, entry}` indexed by Gaussian id (read one per request).
    pub const FEATURE: u64 = 1;
    /// Pixels (write: one subtile row of `S` pixels at a pixel address).
    pub const PIXEL: u64 = 2;
}

/// Localparams: the bits of an SCU's subtile of pixels and of one pixel row.
const SUB_RGB: &str = "SUB_RGB_BITS";
const ROW_RGB: &str = "ROW_RGB_BITS";

const S_IDLE: u64 = 0;
const S_RUN: u64 = 1;
const S_DRAIN: u64 = 2;
const L_IDLE: u64 = 0;
const L_TABLE: u64 = 1;
const L_FEAT: u64 = 2;

/// Width of a feature word: the packed entry plus the `present` bit on top.
pub fn feature_word_bits(cfg: &EngineConfig) -> u32 {
    cfg.feature_format().bits_per_entry() + 1
}

/// Width of the command's image width / height: pixels of `2^tile_bits` tiles.
pub fn image_bits(cfg: &EngineConfig) -> u32 {
    cfg.tile_bits + cfg.raster_config().tile.trailing_zeros()
}

/// Width of `mem_wdata_o`: a pixel row (`S` x [`RGB_BITS`] bits) or a table entry, whichever is
/// wider.
pub fn wdata_bits(cfg: &EngineConfig) -> u32 {
    (cfg.raster_config().subtile * RGB_BITS).max(cfg.entry_bits())
}

/// Counts and widths shared by the raster core's sub-generators.
pub(crate) struct Dims {
    /// ITUs (lanes of a quad) and SCUs.
    ni: u32,
    nc: u32,
    /// Subtiles per tile, subtile groups and their index width.
    nsub: u32,
    groups: u32,
    gw: u32,
    /// SCU index bits (0 with one SCU).
    cb: u32,
    /// Subtile index bits and per-side subtile index bits.
    sub_w: u32,
    side_w: u32,
    /// Subtile side `S`, `log2 S`, `log2 tile`.
    s: u32,
    sb: u32,
    tl: u32,
    /// Feature-buffer entries per bank `F`, banks, bank index bits.
    f: u32,
    nbk: u32,
    bkb: u32,
    /// Segment counters (segments in flight), entry index bits, buffer index `{bank, entry}`
    /// bits, segment length bits (`0..=F`).
    rsw: u32,
    fa: u32,
    fx: u32,
    sl: u32,
    /// Feature word bits; key, id, table-buffer word `{key, id}` and entry bits.
    fw: u32,
    kb: u32,
    ib: u32,
    tw: u32,
    eb: u32,
    /// Address, length, tile-coordinate, image-size and pixel-origin bits.
    aw: u32,
    lw: u32,
    tb: u32,
    wd: u32,
    ow: u32,
    /// Request length bits, write-data bits, pixel-row bits.
    bl: u32,
    wdb: u32,
    rw: u32,
    /// Routing FIFO element bits and FIFO pointer bits.
    ew: u32,
    db: u32,
    /// Quads per bank and their index bits.
    nq: u32,
    qb: u32,
}

impl Dims {
    fn new(cfg: &EngineConfig) -> Self {
        let rc = cfg.raster_config();
        let (ni, nc) = (cfg.raster_itus as u32, cfg.raster_scus as u32);
        let nsub = rc.subtiles_per_tile();
        let groups = nsub / nc;
        let f = cfg.raster_feature_buffer as u32;
        let nbk = cfg.raster_feature_banks as u32;
        let bkb = nbk.trailing_zeros();
        let fa = bits_for(f as u64 - 1);
        let (kb, ib) = (cfg.key_bits as u32, cfg.id_bits as u32);
        let wd = image_bits(cfg);
        let nq = f / ni;
        Dims {
            ni,
            nc,
            nsub,
            groups,
            gw: bits_for(groups as u64 - 1),
            cb: nc.trailing_zeros(),
            sub_w: nsub.trailing_zeros(),
            side_w: rc.subtiles_per_side().trailing_zeros(),
            s: rc.subtile,
            sb: rc.subtile.trailing_zeros(),
            tl: rc.tile.trailing_zeros(),
            f,
            nbk,
            bkb,
            rsw: bkb + 2,
            fa,
            fx: fa + bkb,
            sl: bits_for(f as u64),
            fw: feature_word_bits(cfg),
            kb,
            ib,
            tw: kb + ib,
            eb: cfg.entry_bits(),
            aw: cfg.addr_bits,
            lw: cfg.len_bits,
            tb: cfg.tile_bits,
            wd,
            ow: wd + 1,
            bl: bits_for((cfg.burst as u64).max(rc.subtile as u64)),
            wdb: wdata_bits(cfg),
            rw: rc.subtile * RGB_BITS,
            ew: 3 + ni + fa + bkb,
            db: bits_for(FIFO_DEPTH as u64 - 1),
            nq,
            qb: bits_for(nq as u64 - 1),
        }
    }

    /// Width of the ITUs' in-flight counter.
    fn inflight_bits(&self) -> u32 {
        bits_for(itu::LATENCY as u64 + 1)
    }
}

/// The table-buffer word `{key, id}` (golden's sort entry without its valid bit): localparams
/// `TW_*`.
fn table_word(d: &Dims) -> Bundle {
    Bundle::packed("TW", &[("id", d.ib), ("key", d.kb)])
}

/// The feature word `{present, entry}`: the fields of golden's feature format (`FEAT_*`), the
/// `present` bit on top, and the runs the ITU takes whole (`FEAT_ITU_MEAN`, `FEAT_ITU_GEOM`).
fn feature_word(cfg: &EngineConfig, d: &Dims) -> Bundle {
    let fmt = cfg.feature_format();
    let mut fields: Vec<Field> =
        fmt.layout().iter().map(|f| Field { name: f.name.to_string(), lsb: f.lsb, width: f.width }).collect();
    fields.push(Field { name: "present".into(), lsb: fmt.bits_per_entry(), width: 1 });
    let mean_lsb = fields.iter().find(|f| f.name == "mean_x").expect("mean_x field").lsb;
    fields.push(Field { name: "itu_mean".into(), lsb: mean_lsb, width: itu::mean_bits(cfg) });
    let (geom_w, geom_lsb) = itu::geom_bits_lsb(cfg);
    fields.push(Field { name: "itu_geom".into(), lsb: geom_lsb, width: geom_w });
    let b = Bundle::placed("FEAT", fields);
    debug_assert_eq!(b.width(), feature_word_bits(cfg));
    // Only the fields the core reads (no unused localparam); of the depth key, the low key bits.
    let mut used: Vec<&str> = scu::GAUSSIAN_FIELDS.to_vec();
    used.extend(["depth_key", "present", "itu_mean", "itu_geom"]);
    let dk = b.width_of("depth_key").min(d.kb);
    b.subset(&used).narrowed("depth_key", dk)
}

/// The raster core for `cfg`.
pub fn module(cfg: &EngineConfig) -> Module {
    let d = Dims::new(cfg);
    let mut m = Module::new(NAME);
    m.doc(format!(
        "Rasterization core: {} ITUs + {} SCUs (Fig. 14), {} feature-buffer banks of {} entries, bit-exact with golden",
        d.ni, d.nc, d.nbk, d.f
    ));
    m.doc("raster_tile plus the deferred write-back {valid = ITU OR, key = depth key, id} of every table entry.");
    m.doc(
        "Command: one tile; memory: table / feature reads, write-back and pixel-row writes. See docs/rtl.md.",
    );
    ports(&mut m, &d);
    command(&mut m, &d);
    buffers(&mut m, cfg, &d);
    writer::arbitration(&mut m, &d);
    if cfg.raster_window > 1 {
        load_through_window(&mut m, &d);
    } else {
        load(&mut m, &d);
    }
    walker::walk(&mut m, &d);
    walker::itus(&mut m, cfg, &d);
    walker::results(&mut m, &d);
    scus(&mut m, cfg, &d);
    writer::pixels(&mut m, &d);
    writer::write_back(&mut m, cfg, &d);
    writer::wb_signals(&mut m, &d);
    writer::requests(&mut m, &d);
    control(&mut m, &d);
    walker::walk_state(&mut m, &d);
    m
}

fn ports(m: &mut Module, d: &Dims) {
    m.clock_reset();
    m.input_c("cmd_valid_i", 1, "command handshake");
    m.output_c("cmd_ready_o", 1, "idle");
    m.input_c("cmd_tile_x_i", d.tb, "tile column (origin x = tile_x * tile)");
    m.input_c("cmd_tile_y_i", d.tb, "tile row");
    m.input_c("cmd_width_i", d.wd, "image width in pixels (edge tiles: pixels beyond stay black)");
    m.input_c("cmd_height_i", d.wd, "image height in pixels");
    m.input_c("cmd_table_i", d.aw, "table address (entries); written back in place");
    m.input_c("cmd_len_i", d.lw, "table entries");
    m.input_c("cmd_feat_i", d.aw, "feature base address (feature words; word = base + id)");
    m.input_c("cmd_pix_i", d.aw, "pixel address of the tile's first pixel; pixel (x, y) at + y * tile + x");
    m.output_c("done_o", 1, "one-cycle pulse: tile finished, every write taken");
    m.output_c(
        "done_wb_len_o",
        d.lw,
        "write-back signals (valid with done_o, held): valid entries written back",
    );
    m.output_c("done_wb_reach_o", d.lw, "... and the reach (golden adaptive::writeback_signals)");
    m.output_c("mem_req_valid_o", 1, "request offered");
    m.input_c("mem_req_ready_i", 1, "request taken");
    m.output_c("mem_req_write_o", 1, "1: write; 0: read");
    m.output_c("mem_req_space_o", 2, "0 table, 1 feature, 2 pixel");
    m.output_c("mem_req_addr_o", d.aw, "address in units of the space's element");
    m.output_c(
        "mem_req_len_o",
        d.bl,
        "reads: elements (table bursts, features 1); writes: 1 entry or S pixels",
    );
    m.output_c(
        "mem_wdata_o",
        d.wdb,
        "table entry (low bits) or S pixels, pixel k at [24k +: 24] = {b, g, r}",
    );
    m.input_c("mem_rsp_valid_i", 1, "read response beat, in request order");
    m.output_c("mem_rsp_ready_o", 1, "always 1: buffer space is reserved before a read is issued");
    m.input_c("mem_rsp_data_i", d.fw, "table entry (low bits) or feature word {present, entry}");
}

/// The command registers and the main state.
fn command(m: &mut Module, d: &Dims) {
    m.blank();
    m.comment("Command registers and the main state (IDLE -> RUN -> DRAIN -> IDLE).");
    m.reg("state_q", 2)
        .reg("tile_x_q", d.tb)
        .reg("tile_y_q", d.tb)
        .reg("width_q", d.wd)
        .reg("height_q", d.wd);
    m.reg("table_q", d.aw).reg("feat_base_q", d.aw).reg("pix_base_q", d.aw).reg("len_q", d.lw);
    m.reg("done_q", 1);
    for (n, v) in [("S_IDLE", S_IDLE), ("S_RUN", S_RUN), ("S_DRAIN", S_DRAIN)] {
        m.localparam(n, 2, lit(2, v));
    }
    m.wire_assign("cmd_fire", 1, "cmd_valid_i & cmd_ready_o");
    m.assign("cmd_ready_o", "state_q == S_IDLE");
    m.wire_assign("running", 1, "state_q == S_RUN");
}

/// The banked buffers and the per-bank state.
fn buffers(m: &mut Module, cfg: &EngineConfig, d: &Dims) {
    let n = d.nbk * d.f;
    m.blank();
    m.comment(format!(
        "{} banks of {} entries: the loader fills the next ones while the walk and the SCUs use the oldest.",
        d.nbk, d.f
    ));
    m.comment("Table words {key, id}, feature words {present, entry}, and each entry's ITU OR (group 0):");
    m.comment(
        "RAMs (one write port, no reset). Their words' fields (golden's formats): TW_*, and the FEAT_*",
    );
    m.comment("this core reads (ITU_MEAN / ITU_GEOM: the runs of fields the ITUs take whole).");
    let tw = table_word(d);
    if cfg.raster_window == 1 {
        // The loader's responses are cut to it (the window's loader writes whole table words).
        tw.declare_bits(m);
    }
    tw.declare(m);
    feature_word(cfg, d).declare(m);
    m.mem("tbuf", d.tw, n).mem("fbuf", d.fw, n).mem("hbuf", 1, n);
    m.comment("Per bank: loaded, walked (every group), and its segment's length and first entry.");
    m.reg("bank_full_q", d.nbk).reg("bank_walked_q", d.nbk);
    m.mem("bank_len_q", d.sl, d.nbk).mem("bank_start_q", d.lw, d.nbk);
    m.comment("Segments released so far (segment k uses bank k mod banks; released in order).");
    m.reg("rel_seg_q", d.rsw);
}

/// The loader instance and the buffer writes.
fn load(m: &mut Module, d: &Dims) {
    m.blank();
    m.comment("LOAD: table bursts into tbuf, then one feature read per entry into fbuf.");
    load_wires(m, d);
    m.wire("ld_iss_idx", d.fx).wire("ld_rcv_idx", d.fx);
    m.comment("The id of the next feature read's table entry.");
    m.wire_assign("ld_iss_id", d.ib, table_word(d).get("tbuf[ld_iss_idx]", "id"));
    m.wire_assign("ld_bank_free", 1, "~bank_full_q[ld_bank]");
    let mut conns = loader_conns();
    for (p, e) in [
        ("iss_idx_o", "ld_iss_idx"),
        ("iss_id_i", "ld_iss_id"),
        ("rsp_valid_i", "mem_rsp_valid_i"),
        ("rcv_idx_o", "ld_rcv_idx"),
    ] {
        conns.push((p.to_string(), e.to_string()));
    }
    m.instance(loader::NAME, "u_loader", conns);
    m.seq_noreset(vec![if_(
        "mem_rsp_valid_i",
        vec![if_else(
            "rd_table",
            vec![set("tbuf[ld_rcv_idx]", table_word(d).low_of("mem_rsp_data_i"))],
            vec![set("fbuf[ld_rcv_idx]", "mem_rsp_data_i")],
        )],
    )]);
}

/// The wires of the ports both loaders have.
fn load_wires(m: &mut Module, d: &Dims) {
    m.wire("ld_bank", d.bkb).wire("ld_start", d.lw).wire("ld_seg_len", d.sl).wire("ld_done", 1);
    m.wire("rd_table", 1).wire("rd_addr", d.aw).wire("rd_len", d.bl);
}

/// The connections of the ports both loaders have ([`loader::segment_ports`]).
fn loader_conns() -> Vec<(String, String)> {
    [
        ("clk_i", "clk_i"),
        ("rst_ni", "rst_ni"),
        ("clear_i", "cmd_fire"),
        ("cmd_len_i", "cmd_len_i"),
        ("len_i", "len_q"),
        ("run_i", "running"),
        ("bank_free_i", "ld_bank_free"),
        ("table_i", "table_q"),
        ("feat_i", "feat_base_q"),
        ("bank_o", "ld_bank"),
        ("start_o", "ld_start"),
        ("seg_len_o", "ld_seg_len"),
        ("done_o", "ld_done"),
        ("rd_valid_o", "rd_valid"),
        ("rd_grant_i", "rd_grant"),
        ("rd_table_o", "rd_table"),
        ("rd_addr_o", "rd_addr"),
        ("rd_len_o", "rd_len"),
    ]
    .iter()
    .map(|(p, e)| (p.to_string(), e.to_string()))
    .collect()
}

/// The loader with a reorder window ([`window_loader`], `raster_window` above 1) and the buffer
/// writes of its emissions.
fn load_through_window(m: &mut Module, d: &Dims) {
    m.blank();
    m.comment("LOAD: table bursts and feature reads through the reorder window; its emissions fill the banks in order.");
    load_wires(m, d);
    m.wire("ld_wr_valid", 1).wire("ld_wr_idx", d.fx).wire("ld_wr_table", d.tw).wire("ld_wr_feat", d.fw);
    m.wire_assign("ld_bank_free", 1, "~bank_full_q[ld_bank]");
    m.wire_assign("ld_next_free", 1, format!("~bank_full_q[ld_bank + {}]", lit(d.bkb, 1)));
    let mut conns = loader_conns();
    for (p, e) in [
        ("next_free_i", "ld_next_free"),
        ("rsp_valid_i", "mem_rsp_valid_i"),
        ("rsp_data_i", "mem_rsp_data_i"),
        ("wr_valid_o", "ld_wr_valid"),
        ("wr_idx_o", "ld_wr_idx"),
        ("wr_table_o", "ld_wr_table"),
        ("wr_feat_o", "ld_wr_feat"),
    ] {
        conns.push((p.to_string(), e.to_string()));
    }
    m.instance(window_loader::NAME, "u_loader", conns);
    m.seq_noreset(vec![if_(
        "ld_wr_valid",
        vec![set("tbuf[ld_wr_idx]", "ld_wr_table"), set("fbuf[ld_wr_idx]", "ld_wr_feat")],
    )]);
}

/// The SCUs, each behind its routing FIFO and feeder.
fn scus(m: &mut Module, cfg: &EngineConfig, d: &Dims) {
    let nc = d.nc;
    let px = RGB_BITS * d.s * d.s;
    m.blank();
    m.comment("SCUs: SCU j blends subtile {group, j}; its feeder routes the ITU results and feeds it.");
    m.comment(format!(
        "An SCU's subtile ({0}x{0} pixels of {RGB_BITS} bits, row-major) and a row of it.",
        d.s
    ));
    m.localparam_int(SUB_RGB, px).localparam_int(ROW_RGB, d.rw);
    m.wire("feeder_full", nc).wire("feeder_busy", nc).wire("seg_taken", nc).wire("scu_taken", nc);
    m.wire("scu_out_valid", nc).wire("scu_rgb", nc * px).wire("scu_term", nc);
    // One bit per SCU, indexed even with one SCU.
    for v in ["feeder_full", "feeder_busy", "seg_taken", "scu_taken", "scu_out_valid", "scu_term"] {
        m.vector(v);
    }
    let w = scu::ScuWidths::new(cfg);
    let mut items: Vec<Item> = Vec::new();
    let wire = |n: &str, wi: u32| Item::Wire { name: n.into(), width: wi };
    for (n, wi) in [
        ("feat_idx", d.fx),
        ("valid", 1),
        ("ready", 1),
        ("empty", 1),
        ("last", 1),
        ("is_final", 1),
        ("resume", 1),
        ("sub", w.row_bits),
        ("origin_x", w.origin),
        ("origin_y", w.origin),
        ("cols", d.sb + 1),
        ("rows", d.sb + 1),
        ("segs_done", d.rsw),
    ] {
        items.push(wire(n, wi));
    }
    items.push(Item::Comment("The beat's Gaussian: its feature-word fields.".into()));
    let feat = feature_word(cfg, d);
    for fname in scu::GAUSSIAN_FIELDS {
        let name = format!("feat_{fname}");
        items.push(Item::Wire { name: name.clone(), width: feat.width_of(fname) });
        items.push(Item::Assign { lhs: name, rhs: feat.get("fbuf[feat_idx]", fname) });
    }
    let s = |p: &str, e: &str| (p.to_string(), e.to_string());
    let sel = |v: &str| format!("{v}[j]");
    items.push(Item::Instance(crate::emit::Instance {
        module: feeder::NAME.into(),
        name: "u_feeder".into(),
        params: vec![("SCU".into(), "j".into())],
        conns: vec![
            s("clk_i", "clk_i"),
            s("rst_ni", "rst_ni"),
            s("clear_i", "cmd_fire"),
            s("res_fire_i", "res_fire"),
            s("res_lanes_i", "res_lanes"),
            s("res_bitmaps_i", "itu_bitmaps"),
            s("res_group_i", "res_group"),
            s("res_base_i", "res_base"),
            s("res_seg_last_i", "res_seg_last"),
            s("res_list_last_i", "res_list_last"),
            s("res_resume_i", "res_resume"),
            ("full_o".into(), sel("feeder_full")),
            ("busy_o".into(), sel("feeder_busy")),
            s("tile_x_i", "tile_x_q"),
            s("tile_y_i", "tile_y_q"),
            s("width_i", "width_q"),
            s("height_i", "height_q"),
            s("pix_taken_i", "pix_grant & pix_last_row"),
            s("pix_scu_i", "pix_scu"),
            s("segs_done_o", "segs_done"),
            s("feat_idx_o", "feat_idx"),
            s("scu_valid_o", "valid"),
            s("scu_ready_i", "ready"),
            s("scu_empty_o", "empty"),
            s("scu_last_o", "last"),
            s("scu_final_o", "is_final"),
            s("scu_resume_o", "resume"),
            s("scu_sub_o", "sub"),
            s("scu_origin_x_o", "origin_x"),
            s("scu_origin_y_o", "origin_y"),
            s("scu_cols_o", "cols"),
            s("scu_rows_o", "rows"),
            ("scu_out_ready_o".into(), sel("scu_taken")),
        ],
    }));
    let mut conns =
        vec![s("clk_i", "clk_i"), s("rst_ni", "rst_ni"), s("in_valid_i", "valid"), s("in_ready_o", "ready")];
    for fname in scu::GAUSSIAN_FIELDS {
        conns.push((scu::gaussian_port(fname), format!("feat_{fname}")));
    }
    for (p, e) in [
        ("in_empty_i", "empty"),
        ("in_last_i", "last"),
        ("in_final_i", "is_final"),
        ("in_resume_i", "resume"),
        ("in_sub_i", "sub"),
        ("in_origin_x_i", "origin_x"),
        ("in_origin_y_i", "origin_y"),
        ("in_cols_i", "cols"),
        ("in_rows_i", "rows"),
    ] {
        conns.push(s(p, e));
    }
    conns.push(("term_o".into(), sel("scu_term")));
    conns.push(("out_valid_o".into(), sel("scu_out_valid")));
    conns.push(("out_ready_i".into(), sel("scu_taken")));
    conns.push(("out_rgb_o".into(), format!("scu_rgb[j*{SUB_RGB} +: {SUB_RGB}]")));
    items.push(Item::Instance(crate::emit::Instance {
        module: scu::NAME.into(),
        name: "u_scu".into(),
        params: Vec::new(),
        conns,
    }));
    items.push(Item::Comment("Segments whose last piece this SCU has not yet taken hold their bank.".into()));
    items.push(Item::Assign { lhs: "seg_taken[j]".into(), rhs: "segs_done != rel_seg_q".into() });
    m.gen_for("j", nc, "g_scu", items);
    m.assign("itu_out_ready", "~(|feeder_full)");
    m.wire_assign("unused_term", 1, "^scu_term");
}

/// Release of the banks and the main state.
fn control(m: &mut Module, d: &Dims) {
    let (nbk, bkb, rsw) = (d.nbk, d.bkb, d.rsw);
    m.blank();
    m.comment("Control: RUN while the loader and the walk work through the segments, then DRAIN.");
    m.wire_assign("drained", 1, "~route_busy & ~wb_busy_q");
    m.wire_assign("route_busy", 1, format!("(inflight_q != {}) | (|feeder_busy)", lit(d.inflight_bits(), 0)));
    m.comment("A bank is released once its segment is walked, every SCU has taken its last piece and");
    m.comment("its write-back is done.");
    m.wire_assign("rel_bank", bkb, format!("rel_seg_q[{}:0]", bkb - 1));
    m.wire_assign(
        "rel_ok",
        1,
        "bank_full_q[rel_bank] & bank_walked_q[rel_bank] & (&seg_taken) & ~(wb_busy_q & (wb_bank_q == rel_bank))",
    );
    m.assign(
        "walk_start",
        "running & ~walk_on_q & bank_full_q[walk_bank_q] & ~bank_walked_q[walk_bank_q] & ~wb_busy_q",
    );
    m.wire_assign("walk_end", 1, "itu_fire & last_quad & last_group");
    let mut banks = vec![if_("rel_ok", vec![set("rel_seg_q", format!("rel_seg_q + {}", lit(rsw, 1)))])];
    for b in 0..nbk {
        let bl_ = lit(bkb, b as u64);
        banks.extend([
            if_(format!("ld_done & (ld_bank == {bl_})"), vec![set(format!("bank_full_q[{b}]"), lit(1, 1))]),
            if_(
                format!("walk_end & (walk_bank_q == {bl_})"),
                vec![set(format!("bank_walked_q[{b}]"), lit(1, 1))],
            ),
            if_(
                format!("rel_ok & (rel_bank == {bl_})"),
                vec![
                    set(format!("bank_full_q[{b}]"), lit(1, 0)),
                    set(format!("bank_walked_q[{b}]"), lit(1, 0)),
                ],
            ),
        ]);
    }
    let clear = vec![
        set("rel_seg_q", lit(rsw, 0)),
        set("bank_full_q", lit(nbk, 0)),
        set("bank_walked_q", lit(nbk, 0)),
    ];
    m.seq_d(Some(clear.clone()), vec![if_else("cmd_fire", clear, banks)]);
    m.seq_noreset(vec![if_(
        "ld_done",
        vec![set("bank_len_q[ld_bank]", "ld_seg_len"), set("bank_start_q[ld_bank]", "ld_start")],
    )]);
}

/// A `width`-bit hex literal whose bit `q` is `bit(q)` (any width).
fn mask_lit(width: u32, bit: impl Fn(u32) -> bool) -> String {
    let digits: String = (0..width.div_ceil(4))
        .rev()
        .map(|d| {
            let v = (0..4).filter(|&k| d * 4 + k < width && bit(d * 4 + k)).fold(0u32, |a, k| a | 1 << k);
            char::from_digit(v, 16).expect("hex digit")
        })
        .collect();
    format!("{width}'h{digits}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn widths_and_ports() {
        let cfg = EngineConfig::default();
        assert_eq!(feature_word_bits(&cfg), cfg.feature_format().bits_per_entry() + 1);
        assert_eq!(image_bits(&cfg), cfg.tile_bits + 6);
        assert_eq!(wdata_bits(&cfg), 192);
        let v = module(&cfg).to_verilog();
        for i in [
            "for (u = 0; u < 4; u = u + 1) begin : g_itu",
            "for (j = 0; j < 4; j = j + 1) begin : g_scu",
            "neo_itu u_itu (",
            "neo_scu u_scu (",
            "neo_raster_feeder #(",
            "neo_raster_loader u_loader (",
            "reg  [254:0] fbuf [0:511];",
            "reg  [15:0] quad_hit [0:127];",
        ] {
            assert!(v.contains(i), "{i} missing");
        }
    }

    #[test]
    fn unit_counts_follow_the_config() {
        let cfg = EngineConfig {
            raster_itus: 2,
            raster_scus: 8,
            raster_feature_buffer: 64,
            ..EngineConfig::default()
        };
        cfg.validate().unwrap();
        let v = module(&cfg).to_verilog();
        assert!(v.contains("u < 2; u = u + 1") && v.contains("j < 8; j = j + 1"));
        assert!(EngineConfig { raster_scus: 3, ..EngineConfig::default() }.validate().is_err());
        assert!(EngineConfig { raster_feature_buffer: 100, ..EngineConfig::default() }.validate().is_err());
        assert!(EngineConfig { raster_feature_banks: 3, ..EngineConfig::default() }.validate().is_err());
        assert!(EngineConfig { raster_feature_banks: 1, ..EngineConfig::default() }.validate().is_err());
        let four =
            EngineConfig { raster_feature_banks: 4, raster_feature_buffer: 64, ..EngineConfig::default() };
        four.validate().unwrap();
        let v = module(&four).to_verilog();
        assert!(v.contains("reg  [3:0] bank_full_q;") && v.contains("fbuf [0:255]"));
        assert!(EngineConfig { raster_itus: 0, ..EngineConfig::default() }.validate().is_err());
    }
}
