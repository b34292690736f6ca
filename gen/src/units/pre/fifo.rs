//! `neo_pre_fifo`: a first-in first-out queue of `DEPTH` words of `WIDTH` bits (one parametric
//! module; every use instantiates it with its own `WIDTH` and `DEPTH`, [`instance`]), with
//! valid/ready on both sides and a show-ahead head (the oldest word is on `pop_data_o` while
//! `pop_valid_o` is high). Storage is a register file with one synchronous write port and one
//! combinational read port, as `neo_chunk_ram`.

use crate::emit::{if_, set, Item, Module};

/// Module name.
pub const NAME: &str = "neo_pre_fifo";

/// Default word width (every instance sets its own, [`instance`]).
const DEFAULT_WIDTH: u32 = 32;
/// Default depth (every instance sets its own, [`instance`]).
const DEFAULT_DEPTH: u32 = 4;

/// An instance `name` of the queue of `depth` (a power of two, at least 2) words of `width` bits
/// with connections `conns` (`(port, expression)`).
///
/// # Panics
/// When `depth` is not a power of two of at least 2, or `width` is 0 (a generator error).
pub fn instance(width: u32, depth: u32, name: &str, conns: Vec<(String, String)>) -> Item {
    assert!(depth.is_power_of_two() && depth >= 2, "queue depth {depth} is not a power of two >= 2");
    assert!(width >= 1, "a queue of {width}-bit words");
    super::sized_instance(NAME, (width, depth), name, conns)
}

/// The queue, parametric in `WIDTH` (bits per word) and `DEPTH` (words, a power of two of at
/// least 2). Its pointers have `$clog2(DEPTH)` bits and wrap; its count has `$clog2(DEPTH + 1)`.
pub fn module() -> Module {
    let mut m = Module::new(NAME);
    m.doc("Queue of DEPTH words of WIDTH bits: valid/ready on both sides, show-ahead head.");
    m.doc("WIDTH: bits per word. DEPTH: words, a power of two of at least 2.");
    m.param("WIDTH", i64::from(DEFAULT_WIDTH)).param("DEPTH", i64::from(DEFAULT_DEPTH));
    m.clock_reset();
    m.input_c("push_valid_i", 1, "a word is offered");
    m.output_c("push_ready_o", 1, "the queue takes it (not full)");
    m.input_c("push_data_i", DEFAULT_WIDTH, "the word");
    m.output_c("pop_valid_o", 1, "the queue is not empty");
    m.input_c("pop_ready_i", 1, "the head is taken");
    m.output_c("pop_data_o", DEFAULT_WIDTH, "the head (the oldest word)");
    m.width_param("push_data_i", "WIDTH").width_param("pop_data_o", "WIDTH");
    m.localparam("PTR_BITS", 0, "$clog2(DEPTH)").localparam("CNT_BITS", 0, "$clog2(DEPTH + 1)");
    let (pb, cb) = (DEFAULT_DEPTH.ilog2(), DEFAULT_DEPTH.ilog2() + 1);
    m.reg("wr_ptr_q", pb).reg("rd_ptr_q", pb).reg("cnt_q", cb);
    m.width_param("wr_ptr_q", "PTR_BITS")
        .width_param("rd_ptr_q", "PTR_BITS")
        .width_param("cnt_q", "CNT_BITS");
    m.mem("mem", DEFAULT_WIDTH, DEFAULT_DEPTH).width_param("mem", "WIDTH").depth_param("mem", "DEPTH");
    m.assign("push_ready_o", "cnt_q != DEPTH[CNT_BITS-1:0]");
    m.assign("pop_valid_o", "cnt_q != {CNT_BITS{1'b0}}");
    m.wire_assign("push", 1, "push_valid_i & push_ready_o");
    m.wire_assign("pop", 1, "pop_valid_o & pop_ready_i");
    let step = |p: &str| format!("{p} + {{{{(PTR_BITS-1){{1'b0}}}}, 1'b1}}");
    let ext = |b: &str| format!("{{{{(CNT_BITS-1){{1'b0}}}}, {b}}}");
    let zero = |bits: &str| format!("{{{bits}{{1'b0}}}}");
    m.seq(
        vec![
            set("wr_ptr_q", zero("PTR_BITS")),
            set("rd_ptr_q", zero("PTR_BITS")),
            set("cnt_q", zero("CNT_BITS")),
        ],
        vec![
            if_("push", vec![set("wr_ptr_q", step("wr_ptr_q"))]),
            if_("pop", vec![set("rd_ptr_q", step("rd_ptr_q"))]),
            set("cnt_q", format!("cnt_q + {} - {}", ext("push"), ext("pop"))),
        ],
    );
    m.seq_noreset(vec![if_("push", vec![set("mem[wr_ptr_q]", "push_data_i")])]);
    m.assign("pop_data_o", "mem[rd_ptr_q]");
    m
}
