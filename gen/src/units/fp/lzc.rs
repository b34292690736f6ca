//! `neo_fp_lzc #(WIDTH)`: the leading-zero counter the binary32 primitives normalise with
//! (`neo_fp_add`, `neo_fp_mul`, `neo_fp_div`, `neo_fp_sqrt`, `neo_fp_from_int`,
//! `neo_fp_widen_half_comb`; [`super::common::lzc`] places it).
//!
//! A binary tree of `LEVELS = log2(WIDTH)` levels, one generate block each. Level `l` has
//! `WIDTH >> (l + 1)` nodes; node `n` counts the leading zeros of the `2^(l+1)` input bits
//! `x_i[(n+1) 2^(l+1) - 1 -: 2^(l+1)]` on `l + 1` bits and says whether they are all zero:
//! - level 0 reads a pair of input bits: the count is `~x_i[2n+1]`;
//! - level `l > 0` joins nodes `2n + 1` (the upper half) and `2n` of level `l - 1`: when the
//!   upper half is zero the count is `{1, the lower half's count}`, else `{0, the upper half's}`.
//!
//! `cnt_o` is the root's count (`WIDTH - 1` when `x_i` is zero) and `zero_o` whether `x_i` is
//! zero. Each node's count has exactly the bits it needs, so a bit that never toggles comes from
//! a caller's constant input bits, not from the tree.

use crate::emit::{for_, gen_if, set, Item, Module};

/// Module name.
pub const NAME: &str = "neo_fp_lzc";

/// The default `WIDTH` (the adder's, divider's, square root's and converter's width).
pub const DEFAULT_WIDTH: u32 = 32;

/// The count's width for an input of `width` bits (a power of two, at least 2).
pub fn count_bits(width: u32) -> u32 {
    assert!(width.is_power_of_two() && width >= 2, "lzc width {width}");
    width.trailing_zeros()
}

/// The module.
pub fn module() -> Module {
    let mut m = Module::new(NAME);
    m.doc(
        "Leading-zero counter of x_i (WIDTH a power of two, at least 2): a binary tree, one generate block",
    );
    m.doc("per level with a combinational loop over its nodes (gen/src/units/fp/lzc.rs). cnt_o is WIDTH - 1");
    m.doc("when x_i is zero; zero_o says it is.");
    m.param("WIDTH", i64::from(DEFAULT_WIDTH));
    m.input_c("x_i", DEFAULT_WIDTH, "the value, most significant bit first").width_param("x_i", "WIDTH");
    m.output_c("cnt_o", count_bits(DEFAULT_WIDTH), "leading zeros of x_i")
        .width_param("cnt_o", "$clog2(WIDTH)");
    m.output_c("zero_o", 1, "x_i is zero");
    m.localparam("LEVELS", 0, "$clog2(WIDTH)");
    m.gen_loop("l", "LEVELS", "g_level", level_items());
    m.width_param("zero", "(WIDTH >> (l + 1))");
    m.width_param("cnt", "(WIDTH >> (l + 1)) * (l + 1)");
    m.assign("zero_o", "g_level[LEVELS-1].zero[0]");
    m.assign("cnt_o", "g_level[LEVELS-1].cnt");
    m
}

/// One level's nodes: `zero` (one bit a node) and `cnt` (`l + 1` bits a node, node `n` at
/// `cnt[n*(l+1) +: l+1]`), computed by one combinational loop over the nodes (a generate loop
/// per node would cost Icarus minutes on the Preprocessing Engine's hundreds of counters).
fn level_items() -> Vec<Item> {
    let nodes = "(WIDTH >> (l + 1))";
    let pair = vec![set("zero[n]", "~(x_i[2*n+1] | x_i[2*n])"), set("cnt[n]", "~x_i[2*n+1]")];
    let below = "g_level[l-1]";
    let join = vec![
        set("zero[n]", format!("{below}.zero[2*n+1] & {below}.zero[2*n]")),
        set(
            "cnt[n*(l+1) +: l+1]",
            format!(
                "{below}.zero[2*n+1] ? {{1'b1, {below}.cnt[2*n*l +: l]}} : {{1'b0, {below}.cnt[(2*n+1)*l +: l]}}"
            ),
        ),
    ];
    vec![
        Item::Comment("Node n covers x_i[(n+1)*2^(l+1)-1 -: 2^(l+1)].".into()),
        Item::Reg { name: "zero".into(), width: 1 },
        Item::Reg { name: "cnt".into(), width: 1 },
        Item::Integer("n".into()),
        gen_if(
            "l == 0",
            ("g_pair", vec![Item::Comb(vec![for_("n", nodes, pair)])]),
            ("g_join", vec![Item::Comb(vec![for_("n", nodes, join)])]),
        ),
    ]
}
