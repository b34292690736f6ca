//! `neo_bsu`: the Bitonic Sorting Unit, a pipelined comparator network on packed entries.
//!
//! The network is the golden [`neo_golden::sort::Network`] of the configured topology, layer by
//! layer; each comparator `(i, j)` is a `neo_cmp_swap` with wire `i` on `a_i`/`lo_o`. A register
//! stage follows every `k = register_every` layers and the last layer, so the latency is
//! `ceil(depth / k)` cycles with one vector accepted per cycle (II = 1).
//!
//! Flow control is a global stall: the whole pipeline (valid bits and data) advances when
//! `en = out_ready_i | ~valid_qS` (the output stage is empty or being taken); `in_ready_o = en`.
//! Nothing is lost or duplicated under any backpressure: a stage only overwrites its register
//! when the next stage takes its content in the same cycle. (Bubbles inside the pipeline are not
//! squeezed out while the output is stalled.) Data registers have no reset; valid bits do.

use crate::emit::expr::{lane, lit};
use crate::emit::{conns, if_, set, Module};
use neo_golden::engine::EngineConfig;

/// Module name.
pub const NAME: &str = "neo_bsu";

/// Suffix of register stage `t` (1-based): `_q`, `_q2`, `_q3`, ...
fn stage_suffix(t: usize) -> String {
    if t == 1 {
        "_q".to_string()
    } else {
        format!("_q{t}")
    }
}

/// The BSU for `cfg`.
pub fn module(cfg: &EngineConfig) -> Module {
    let net = cfg.network();
    let n = net.n as u32;
    let w = cfg.entry_bits();
    let vw = n * w;
    let k = cfg.register_every;
    let depth = net.depth();
    let stages = cfg.bsu_latency();
    let mut m = Module::new(NAME);
    m.doc(format!(
        "Bitonic Sorting Unit: {} network on {n} entries of {w} bits ({} comparators, {depth} layers).",
        cfg.topology.name(),
        net.comparator_count()
    ));
    m.doc(format!("A register stage every {k} layers: latency {stages} cycles, one vector per cycle."));
    m.doc("Entry i is in_data_i[i*W +: W]; out_data_o holds the entries in (key, id) order, lane 0 first.");
    m.doc("Global stall: everything advances when out_ready_i | ~out_valid_o; in_ready_o is that enable.");
    m.clock_reset();
    m.input_c("in_valid_i", 1, "a vector is offered");
    m.output_c("in_ready_o", 1, "the vector is taken when in_valid_i & in_ready_o");
    m.input_c("in_data_i", vw, "entry i at [i*W +: W]");
    m.output_c("out_valid_o", 1, "a sorted vector is offered");
    m.input_c("out_ready_i", 1, "the sorted vector is taken when out_valid_o & out_ready_i");
    m.output_c("out_data_o", vw, "sorted entries, lane 0 first");

    let last_valid = format!("valid{}", stage_suffix(stages));
    m.wire_assign("en", 1, format!("out_ready_i | ~{last_valid}"));
    m.assign("in_ready_o", "en");

    // Valid chain.
    for t in 1..=stages {
        m.reg(format!("valid{}", stage_suffix(t)), 1);
    }
    let resets = (1..=stages).map(|t| set(format!("valid{}", stage_suffix(t)), lit(1, 0))).collect();
    let shifts = (1..=stages)
        .map(|t| {
            let src = if t == 1 { "in_valid_i".to_string() } else { format!("valid{}", stage_suffix(t - 1)) };
            set(format!("valid{}", stage_suffix(t)), src)
        })
        .collect();
    m.seq(resets, vec![if_("en", shifts)]);

    // Layers and data stages.
    let mut src = "in_data_i".to_string();
    let mut stage = 0;
    for (d, layer) in net.layers.iter().enumerate() {
        let out = format!("l{d}_data");
        m.blank();
        m.comment(format!("layer {d}: {} comparators", layer.len()));
        m.wire(&out, vw);
        let mut touched = vec![false; n as usize];
        for &(i, j) in layer {
            touched[i] = true;
            touched[j] = true;
            let (i, j) = (i as u32, j as u32);
            m.instance(
                "neo_cmp_swap",
                format!("u_cmp_l{d}_{i}_{j}"),
                conns(&[
                    ("a_i", lane(&src, i, w)),
                    ("b_i", lane(&src, j, w)),
                    ("lo_o", lane(&out, i, w)),
                    ("hi_o", lane(&out, j, w)),
                ]),
            );
        }
        for (i, t) in touched.iter().enumerate() {
            if !t {
                m.assign(lane(&out, i as u32, w), lane(&src, i as u32, w));
            }
        }
        src = out;
        if (d + 1) % k == 0 || d + 1 == depth {
            stage += 1;
            let q = format!("data{}", stage_suffix(stage));
            m.reg(&q, vw);
            m.seq_noreset(vec![if_("en", vec![set(&q, &src)])]);
            src = q;
        }
    }
    debug_assert_eq!(stage, stages);
    m.blank();
    m.assign("out_valid_o", last_valid);
    m.assign("out_data_o", src);
    m
}

#[cfg(test)]
mod tests {
    use super::*;
    use neo_golden::engine::Topology;

    #[test]
    fn one_cmp_swap_per_comparator_and_one_register_per_stage() {
        for topology in Topology::ALL {
            for k in [1, 2, 3, 10] {
                let cfg = EngineConfig { topology, register_every: k, ..EngineConfig::default() };
                let v = module(&cfg).to_verilog();
                let net = cfg.network();
                assert_eq!(v.matches("neo_cmp_swap u_cmp_").count(), net.comparator_count());
                for layer in 0..net.depth() {
                    for &(i, j) in &net.layers[layer] {
                        assert!(
                            v.contains(&format!("u_cmp_l{layer}_{i}_{j} (")),
                            "{topology:?} {layer} {i} {j}"
                        );
                    }
                }
                assert_eq!(
                    v.matches("  reg  [767:0] data_q").count(),
                    cfg.bsu_latency(),
                    "{topology:?} k={k}"
                );
                assert_eq!(v.matches("  reg  valid_q").count(), cfg.bsu_latency());
            }
        }
    }

    #[test]
    fn registers_follow_every_k_layers() {
        let cfg = EngineConfig { register_every: 3, ..EngineConfig::default() };
        let v = module(&cfg).to_verilog();
        // Layers 0..=2 feed data_q; layer 3 reads it; the last layer (9) feeds data_q4.
        assert!(v.contains("data_q <= l2_data;"), "{v}");
        assert!(v.contains(".a_i(data_q[47:0])"));
        assert!(v.contains("data_q4 <= l9_data;"));
        assert!(v.contains("assign out_data_o = data_q4;"));
        assert!(v.contains("assign en = out_ready_i | ~valid_q4;"));
    }
}
