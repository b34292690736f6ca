//! `neo_pre_fifo_w{W}_d{D}`: a first-in first-out queue of `D` words of `W` bits (one module per
//! distinct size), with valid/ready on both sides and a show-ahead head (the oldest word is on
//! `pop_data_o` while `pop_valid_o` is high). Storage is a register file with one synchronous
//! write port and one combinational read port, as `neo_chunk_ram`.

use crate::emit::expr::{bits_for, lit, zext};
use crate::emit::{if_, set, Module};

/// Module name of a queue of `depth` words of `width` bits.
pub fn name(width: u32, depth: u32) -> String {
    format!("neo_pre_fifo_w{width}_d{depth}")
}

/// The queue of `depth` (a power of two, at least 2) words of `width` bits.
///
/// # Panics
/// When `depth` is not a power of two of at least 2 (a generator error).
pub fn module(width: u32, depth: u32) -> Module {
    assert!(depth.is_power_of_two() && depth >= 2, "queue depth {depth} is not a power of two >= 2");
    let (pb, cb) = (bits_for(u64::from(depth) - 1), bits_for(u64::from(depth)));
    let mut m = Module::new(name(width, depth));
    m.doc(format!("Queue of {depth} words of {width} bits: valid/ready on both sides, show-ahead head."));
    m.clock_reset();
    m.input_c("push_valid_i", 1, "a word is offered");
    m.output_c("push_ready_o", 1, "the queue takes it (not full)");
    m.input_c("push_data_i", width, "the word");
    m.output_c("pop_valid_o", 1, "the queue is not empty");
    m.input_c("pop_ready_i", 1, "the head is taken");
    m.output_c("pop_data_o", width, "the head (the oldest word)");
    m.reg("wr_ptr_q", pb).reg("rd_ptr_q", pb).reg("cnt_q", cb);
    m.mem("mem", width, depth);
    m.assign("push_ready_o", format!("cnt_q != {}", lit(cb, u64::from(depth))));
    m.assign("pop_valid_o", format!("cnt_q != {}", lit(cb, 0)));
    m.wire_assign("push", 1, "push_valid_i & push_ready_o");
    m.wire_assign("pop", 1, "pop_valid_o & pop_ready_i");
    let step = |p: &str| format!("{p} + {}", lit(pb, 1));
    m.seq(
        vec![set("wr_ptr_q", lit(pb, 0)), set("rd_ptr_q", lit(pb, 0)), set("cnt_q", lit(cb, 0))],
        vec![
            if_("push", vec![set("wr_ptr_q", step("wr_ptr_q"))]),
            if_("pop", vec![set("rd_ptr_q", step("rd_ptr_q"))]),
            set("cnt_q", format!("cnt_q + {} - {}", zext("push", 1, cb), zext("pop", 1, cb))),
        ],
    );
    m.seq_noreset(vec![if_("push", vec![set("mem[wr_ptr_q]", "push_data_i")])]);
    m.assign("pop_data_o", "mem[rd_ptr_q]");
    m
}
