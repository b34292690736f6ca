//! The engine's own `adaptive` decision (issue 14): with [`ADAPT_ENABLE`] in `ADAPT_CTRL`, the
//! frame controller reads every tile's previous result (the disorder counters the RTL counted
//! in the last frame, [`TileResult`]) and plans each tile's DPS passes itself, with golden's
//! policy ([`request`], [`allocate`]); the descriptors' `dps_passes` are ignored.
//!
//! # `ADAPT_CTRL` (0x0D0)
//! `[0]` enable, `[13:4]` budget (percent of one pass over every table, `0..=1000`),
//! `[19:16]` the most passes per tile (`1..=15`, the descriptor field's range), `[20]` wide:
//! tiles whose reach is at least a chunk take their passes in the wide chunk (ignored by an
//! engine without one, `dps_wide` 1). The engine decides
//! `adaptive:budget=B,max=M,resort=0,wide=W` with `W` 1 or its `dps_wide`: a re-sort needs the
//! tile's whole list, which the engine's lists do not hold.
//!
//! # What the frame controller does
//! `RESULT_BASE` must hold the previous frame's results (the host keeps one result region).
//! 1. **Scan**: for every tile (empty ones too) it reads the previous result and forms the
//!    request: `p = 1 + wb_reach / U` (a shift; `U` the wide chunk `W` when wide and
//!    `wb_reach >= C`, the tile's passes then wide, else `C`), `+ 1` when `p > 1` and the merge saw
//!    inversions, at most `max`; the pass cost `max(2 wb_len, 1)`. It sums the costs (`S`)
//!    and, per level `l = 2..=15`, the costs of the tiles asking for at least `l` passes (`H[l]`).
//! 2. **Cap**: the largest `c` such that `100 (H[2] + ... + H[c]) <= S budget` (the extra cost of
//!    granting every tile `min(p, c)`, against `floor(S budget / 100)` without a divider).
//! 3. **Walk**: with each tile's descriptor it reads the previous result again, re-forms the
//!    request and grants `min(p, c)`, or `c + 1` when `p > c` and `100 (spent + cost) <= S
//!    budget` (then `spent += cost`), in tile order: [`allocate`]'s raise of tiles above the cap;
//!    the tile's passes use the wide chunk when its request does.
//!
//! The result reads are counted in `RD_RESULT` (16 bytes per tile per read: 32 per tile and
//! frame). [`engine_passes`] is the reference: golden's own policy functions on the results.

use super::memory::{TileResult, MAX_DPS_PASSES};
use super::EngineConfig;
use crate::pipeline::adaptive::{allocate, request, AdaptiveParams, WritebackSignals};
use serde::{Deserialize, Serialize};

/// `ADAPT_CTRL` bit 0: the frame controller plans the DPS passes.
pub const ADAPT_ENABLE: u32 = 1;
/// `ADAPT_CTRL` budget field: lowest bit.
pub const ADAPT_BUDGET_LSB: u32 = 4;
/// `ADAPT_CTRL` budget field: bits.
pub const ADAPT_BUDGET_BITS: u32 = 10;
/// `ADAPT_CTRL` max-passes field: lowest bit.
pub const ADAPT_MAX_LSB: u32 = 16;
/// `ADAPT_CTRL` max-passes field: bits (the descriptor's `dps_passes` width).
pub const ADAPT_MAX_BITS: u32 = 4;
/// `ADAPT_CTRL` bit 20: requests use the wide chunk (the engine's `dps_wide`).
pub const ADAPT_WIDE: u32 = 1 << 20;
/// The largest budget (percent).
pub const ADAPT_MAX_BUDGET: u32 = 1000;

/// The `ADAPT_CTRL` register of one frame (0: the descriptors' passes).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct AdaptRegs {
    /// `ADAPT_CTRL`.
    pub ctrl: u32,
}

impl AdaptRegs {
    /// The register deciding `p` in an engine whose wide chunk is `dps_wide` chunks, or why the
    /// engine cannot (a re-sort, a wide chunk it does not have, more passes than a descriptor
    /// holds, a budget above [`ADAPT_MAX_BUDGET`]).
    pub fn deciding(p: &AdaptiveParams, dps_wide: usize) -> Result<AdaptRegs, String> {
        if p.resort || (p.wide != 1 && p.wide as usize != dps_wide) {
            return Err(format!(
                "the engine decides adaptive without re-sorts and with wide=1 or wide = its dps_wide ({dps_wide}), not {p}"
            ));
        }
        if !(1..=MAX_DPS_PASSES as u32).contains(&p.max_passes) || p.budget > ADAPT_MAX_BUDGET {
            return Err(format!(
                "the engine decides at most {MAX_DPS_PASSES} passes and a budget of at most {ADAPT_MAX_BUDGET}, not {p}"
            ));
        }
        let wide = if p.wide > 1 { ADAPT_WIDE } else { 0 };
        let ctrl = ADAPT_ENABLE | p.budget << ADAPT_BUDGET_LSB | p.max_passes << ADAPT_MAX_LSB | wide;
        Ok(AdaptRegs { ctrl })
    }

    /// Whether the frame controller plans the passes.
    pub fn enabled(&self) -> bool {
        self.ctrl & ADAPT_ENABLE != 0
    }

    /// The parameters the register selects in an engine whose wide chunk is `dps_wide` chunks
    /// (the fields as the RTL reads them).
    pub fn params(&self, dps_wide: usize) -> AdaptiveParams {
        let field = |lsb: u32, bits: u32| (self.ctrl >> lsb) & ((1 << bits) - 1);
        AdaptiveParams {
            budget: field(ADAPT_BUDGET_LSB, ADAPT_BUDGET_BITS),
            max_passes: field(ADAPT_MAX_LSB, ADAPT_MAX_BITS),
            resort: false,
            wide: if self.ctrl & ADAPT_WIDE != 0 { dps_wide as u32 } else { 1 },
        }
    }
}

/// One tile's DPS as the engine plans it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EnginePlan {
    /// Passes.
    pub passes: u32,
    /// In the wide chunk.
    pub wide: bool,
}

/// The DPS the engine plans for every tile from the previous frame's results `prev` (tile
/// order) in engine `cfg` (its chunk and wide chunk): golden [`request`] and [`allocate`] on
/// the counters the results hold.
pub fn engine_passes(regs: &AdaptRegs, cfg: &EngineConfig, prev: &[TileResult]) -> Vec<EnginePlan> {
    let p = regs.params(cfg.dps_wide);
    let requests: Vec<_> = prev
        .iter()
        .map(|r| {
            let wb = WritebackSignals { len: r.wb_len, reach: r.wb_reach, ..WritebackSignals::default() };
            request(&p, &wb, r.merge_inversions, 0, cfg.chunk as u32)
        })
        .collect();
    allocate(&p, &requests)
        .iter()
        .map(|plan| EnginePlan { passes: plan.passes_or(1) as u32, wide: plan.is_wide() })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn result(len: u32, reach: u32, inv: u32) -> TileResult {
        TileResult {
            next_len: len,
            wb_len: len,
            wb_reach: reach,
            merge_inversions: inv,
            ..TileResult::default()
        }
    }

    fn cfg(dps_wide: usize) -> EngineConfig {
        EngineConfig { dps_wide, ..EngineConfig::default() }
    }

    fn passes(plans: &[EnginePlan]) -> Vec<u32> {
        plans.iter().map(|p| p.passes).collect()
    }

    #[test]
    fn the_register_round_trips_and_refuses_what_the_engine_cannot_run() {
        let p = AdaptiveParams { budget: 70, max_passes: 6, resort: false, wide: 1 };
        let r = AdaptRegs::deciding(&p, 1).expect("engine-decidable");
        assert!(r.enabled());
        assert_eq!(r.params(1), p);
        assert_eq!(r.ctrl, 1 | 70 << 4 | 6 << 16);
        let w = AdaptRegs::deciding(&AdaptiveParams { wide: 16, ..p }, 16).expect("the engine's wide chunk");
        assert_eq!(w.ctrl, r.ctrl | ADAPT_WIDE);
        assert_eq!(w.params(16), AdaptiveParams { wide: 16, ..p });
        assert_eq!(w.params(1).wide, 1, "an engine without a wide chunk ignores the bit");
        for (bad, dps_wide) in [
            (AdaptiveParams { resort: true, ..p }, 1),
            (AdaptiveParams { wide: 16, ..p }, 1),
            (AdaptiveParams { wide: 8, ..p }, 16),
            (AdaptiveParams { max_passes: 16, ..p }, 1),
        ] {
            let e = AdaptRegs::deciding(&bad, dps_wide).expect_err("refused");
            assert!(e.contains(&bad.to_string()), "{e}");
        }
        assert!(!AdaptRegs::default().enabled());
    }

    #[test]
    fn passes_follow_reach_inversions_and_budget() {
        let all = AdaptiveParams { budget: 1000, max_passes: 4, resort: false, wide: 1 };
        let r = AdaptRegs::deciding(&all, 1).expect("regs");
        // Sorted (1), reach of two chunks (3), two chunks with merge inversions (4), empty (1).
        let prev = [result(1000, 0, 0), result(1000, 512, 0), result(1000, 512, 5), result(0, 0, 0)];
        assert_eq!(passes(&engine_passes(&r, &cfg(1), &prev)), vec![1, 3, 4, 1]);
        // 100 %: one extra pass each fits (cap 2) and the rest raises the first tile above it.
        let r100 = AdaptRegs::deciding(&AdaptiveParams { budget: 100, ..all }, 1).expect("regs");
        assert_eq!(passes(&engine_passes(&r100, &cfg(1), &prev)), vec![1, 3, 2, 1]);
        // No budget: one pass everywhere.
        let none = AdaptRegs { ctrl: r.ctrl & !(0x3FF << ADAPT_BUDGET_LSB) };
        assert_eq!(passes(&engine_passes(&none, &cfg(1), &prev)), vec![1; 4]);
        assert!(engine_passes(&r, &cfg(1), &prev).iter().all(|p| !p.wide));
    }

    #[test]
    fn wide_requests_take_the_wide_chunk_from_a_reach_of_one_chunk() {
        // Wide chunk of 4 x 256: reach 255 stays narrow (1 pass); 256 and 1023 are one wide
        // pass; 2048 is 1 + 2048 / 1024 = 3 wide passes, 4 with merge inversions.
        let p = AdaptiveParams { budget: 1000, max_passes: 6, resort: false, wide: 4 };
        let r = AdaptRegs::deciding(&p, 4).expect("regs");
        let prev = [
            result(900, 255, 0),
            result(900, 256, 0),
            result(900, 1023, 7),
            result(900, 2048, 0),
            result(900, 2048, 1),
        ];
        let got: Vec<(u32, bool)> =
            engine_passes(&r, &cfg(4), &prev).iter().map(|p| (p.passes, p.wide)).collect();
        assert_eq!(got, [(1, false), (1, true), (1, true), (3, true), (4, true)]);
        // The same register on an engine without the wide chunk: chunk passes, 1 + reach / 256.
        let narrow = passes(&engine_passes(&r, &cfg(1), &prev));
        assert_eq!(narrow, [1, 2, 5, 6, 6]);
    }

    proptest! {
        #[test]
        fn the_plan_stays_within_max_and_the_budget(
            budget in 0u32..=1000,
            max in 1u32..=15,
            wide_log in 0u32..=4,
            tiles in prop::collection::vec((0u32..5000, 0u32..20_000, 0u32..3), 1..40),
        ) {
            let wide = 1 << wide_log;
            let p = AdaptiveParams { budget, max_passes: max, resort: false, wide };
            let r = AdaptRegs::deciding(&p, wide as usize).expect("regs");
            let prev: Vec<TileResult> = tiles.iter().map(|&(l, r, i)| result(l, r, i)).collect();
            let plans = engine_passes(&r, &cfg(wide as usize), &prev);
            let passes = passes(&plans);
            let cost = |r: &TileResult| (2 * r.wb_len as u64).max(1);
            let sum: u64 = prev.iter().map(cost).sum();
            let extra: u64 = prev.iter().zip(&passes).map(|(r, &p)| (p as u64 - 1) * cost(r)).sum();
            prop_assert!(passes.iter().all(|&p| (1..=max).contains(&p)));
            prop_assert!(100 * extra <= sum * budget as u64, "{passes:?}");
            for (r, plan) in prev.iter().zip(&plans) {
                prop_assert_eq!(plan.wide, wide > 1 && r.wb_reach >= 256);
            }
        }
    }
}
