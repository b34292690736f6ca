//! The Preprocessing Engine's computation in the hardware's arithmetic ([`crate::hwarith`]):
//! generic over [`crate::hwarith::Arith`], evaluated natively by golden and traced into the
//! dataflow graphs that gen emits as the units' Verilog.

pub mod bake;
pub mod color;
pub mod quant;
