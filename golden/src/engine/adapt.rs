//! The engine's own `adaptive` decision (issue 14): with [`ADAPT_ENABLE`] in `ADAPT_CTRL`, the
//! frame controller reads every tile's previous result (the disorder counters the RTL counted
//! in the last frame, [`TileResult`]) and plans each tile's DPS passes itself, with golden's
//! policy ([`request`], [`allocate`]); the descriptors' `dps_passes` are ignored.
//!
//! # `ADAPT_CTRL` (0x0D0)
//! `[0]` enable, `[13:4]` budget (percent of one pass over every table, `0..=1000`),
//! `[19:16]` the most passes per tile (`1..=15`, the descriptor field's range). The engine
//! decides `adaptive:budget=B,max=M,resort=0,wide=1`: a re-sort needs the tile's whole list
//! (which the engine's lists do not hold) and a wide pass the wide chunk buffer (not built).
//!
//! # What the frame controller does
//! `RESULT_BASE` must hold the previous frame's results (the host keeps one result region).
//! 1. **Scan**: for every tile (empty ones too) it reads the previous result and forms the
//!    request: `p = 1 + wb_reach / C` (a shift), `+ 1` when `p > 1` and the merge saw
//!    inversions, at most `max`; the pass cost `max(2 wb_len, 1)`. It sums the costs (`S`)
//!    and, per level `l = 2..=15`, the costs of the tiles asking for at least `l` passes (`H[l]`).
//! 2. **Cap**: the largest `c` such that `100 (H[2] + ... + H[c]) <= S budget` (the extra cost of
//!    granting every tile `min(p, c)`, against `floor(S budget / 100)` without a divider).
//! 3. **Walk**: with each tile's descriptor it reads the previous result again, re-forms the
//!    request and grants `min(p, c)`, or `c + 1` when `p > c` and `100 (spent + cost) <= S
//!    budget` (then `spent += cost`), in tile order: [`allocate`]'s raise of tiles above the cap.
//!
//! The result reads are counted in `RD_RESULT` (16 bytes per tile per read: 32 per tile and
//! frame). [`engine_passes`] is the reference: golden's own policy functions on the results.

use super::memory::{TileResult, MAX_DPS_PASSES};
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
/// The largest budget (percent).
pub const ADAPT_MAX_BUDGET: u32 = 1000;

/// The `ADAPT_CTRL` register of one frame (0: the descriptors' passes).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct AdaptRegs {
    /// `ADAPT_CTRL`.
    pub ctrl: u32,
}

impl AdaptRegs {
    /// The register deciding `p` in the engine, or why the engine cannot (a re-sort, a wide
    /// chunk, more passes than a descriptor holds, a budget above [`ADAPT_MAX_BUDGET`]).
    pub fn deciding(p: &AdaptiveParams) -> Result<AdaptRegs, String> {
        if p.resort || p.wide != 1 {
            return Err(format!(
                "the engine decides adaptive without re-sorts and the wide chunk (resort=0,wide=1), not {p}"
            ));
        }
        if !(1..=MAX_DPS_PASSES as u32).contains(&p.max_passes) || p.budget > ADAPT_MAX_BUDGET {
            return Err(format!(
                "the engine decides at most {MAX_DPS_PASSES} passes and a budget of at most {ADAPT_MAX_BUDGET}, not {p}"
            ));
        }
        let ctrl = ADAPT_ENABLE | p.budget << ADAPT_BUDGET_LSB | p.max_passes << ADAPT_MAX_LSB;
        Ok(AdaptRegs { ctrl })
    }

    /// Whether the frame controller plans the passes.
    pub fn enabled(&self) -> bool {
        self.ctrl & ADAPT_ENABLE != 0
    }

    /// The parameters the register selects (the fields as the RTL reads them).
    pub fn params(&self) -> AdaptiveParams {
        let field = |lsb: u32, bits: u32| (self.ctrl >> lsb) & ((1 << bits) - 1);
        AdaptiveParams {
            budget: field(ADAPT_BUDGET_LSB, ADAPT_BUDGET_BITS),
            max_passes: field(ADAPT_MAX_LSB, ADAPT_MAX_BITS),
            resort: false,
            wide: 1,
        }
    }
}

/// The DPS passes the engine plans for every tile from the previous frame's results `prev`
/// (tile order) with chunk `chunk`: golden [`request`] and [`allocate`] on the counters the
/// results hold.
pub fn engine_passes(regs: &AdaptRegs, chunk: u32, prev: &[TileResult]) -> Vec<u32> {
    let p = regs.params();
    let requests: Vec<_> = prev
        .iter()
        .map(|r| {
            let wb = WritebackSignals { len: r.wb_len, reach: r.wb_reach, ..WritebackSignals::default() };
            request(&p, &wb, r.merge_inversions, 0, chunk)
        })
        .collect();
    allocate(&p, &requests).iter().map(|plan| plan.passes_or(1) as u32).collect()
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

    #[test]
    fn the_register_round_trips_and_refuses_what_the_engine_cannot_run() {
        let p = AdaptiveParams { budget: 70, max_passes: 6, resort: false, wide: 1 };
        let r = AdaptRegs::deciding(&p).expect("engine-decidable");
        assert!(r.enabled());
        assert_eq!(r.params(), p);
        assert_eq!(r.ctrl, 1 | 70 << 4 | 6 << 16);
        for bad in [
            AdaptiveParams { resort: true, ..p },
            AdaptiveParams { wide: 16, ..p },
            AdaptiveParams { max_passes: 16, ..p },
        ] {
            assert!(AdaptRegs::deciding(&bad).is_err(), "{bad}");
        }
        assert!(!AdaptRegs::default().enabled());
    }

    #[test]
    fn passes_follow_reach_inversions_and_budget() {
        let all = AdaptiveParams { budget: 1000, max_passes: 4, resort: false, wide: 1 };
        let r = AdaptRegs::deciding(&all).expect("regs");
        // Sorted (1), reach of two chunks (3), two chunks with merge inversions (4), empty (1).
        let prev = [result(1000, 0, 0), result(1000, 512, 0), result(1000, 512, 5), result(0, 0, 0)];
        assert_eq!(engine_passes(&r, 256, &prev), vec![1, 3, 4, 1]);
        // 100 %: one extra pass each fits (cap 2) and the rest raises the first tile above it.
        let r100 = AdaptRegs::deciding(&AdaptiveParams { budget: 100, ..all }).expect("regs");
        assert_eq!(engine_passes(&r100, 256, &prev), vec![1, 3, 2, 1]);
        // No budget: one pass everywhere.
        let none = AdaptRegs { ctrl: r.ctrl & !(0x3FF << ADAPT_BUDGET_LSB) };
        assert_eq!(engine_passes(&none, 256, &prev), vec![1; 4]);
    }

    proptest! {
        #[test]
        fn the_plan_stays_within_max_and_the_budget(
            budget in 0u32..=1000,
            max in 1u32..=15,
            tiles in prop::collection::vec((0u32..5000, 0u32..20_000, 0u32..3), 1..40),
        ) {
            let p = AdaptiveParams { budget, max_passes: max, resort: false, wide: 1 };
            let r = AdaptRegs::deciding(&p).expect("regs");
            let prev: Vec<TileResult> = tiles.iter().map(|&(l, r, i)| result(l, r, i)).collect();
            let passes = engine_passes(&r, 256, &prev);
            let cost = |r: &TileResult| (2 * r.wb_len as u64).max(1);
            let sum: u64 = prev.iter().map(cost).sum();
            let extra: u64 = prev.iter().zip(&passes).map(|(r, &p)| (p as u64 - 1) * cost(r)).sum();
            prop_assert!(passes.iter().all(|&p| (1..=max).contains(&p)));
            prop_assert!(100 * extra <= sum * budget as u64, "{passes:?}");
        }
    }
}
