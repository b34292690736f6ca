//! The Preprocessing Engine's burst writers on one AXI4 port, played cycle by cycle: the lanes'
//! feature writers (`neo_pre_lane`, a 4-beat word each) and the list writer (`neo_pre_lists`,
//! an 8-beat line each).
//!
//! Structure read off the RTL: a writer takes its next transfer only when the previous one's AW
//! has left and all its W beats are out, with fewer than its limit of writes awaiting their B;
//! its AW goes out the cycle after it takes the transfer. The port mux
//! (`neo_axi_mux`) grants one AW at a time, round robin, while its W-order FIFO
//! ([`MUX_W_FIFO_DEPTH`]) has room, and forwards the W beats of the FIFO's head. The memory is
//! the harness's (as in [`PortTiming::single_write_rate`]): it takes an AW on `ready` of its
//! cycles, a W beat only for an AW it took, with a beat of credit and on `ready` of its cycles,
//! and answers a write [`PortTiming::b_delay`] cycles after its last beat, later by
//! [`PortTiming::late_delay`], in order per writer (its ID).
//!
//! Behind the ideal memory a lone writer of `b`-beat transfers takes `b + 2` cycles a transfer;
//! another writer's burst on the same port fills two of those cycles and delays it by the rest.
//! The list writer's lines become ready as the lanes make them: the played writers keep pace
//! with the one that has the most cycles to spend (the lane's feature writer), so a line waits
//! until the lead writer has done its share of the frame.

use std::collections::VecDeque;

use neo_golden::engine::MUX_W_FIFO_DEPTH;

use crate::engine_frame::{PortTiming, XorShift};

/// The most transfers of the lead writer one play covers; a longer frame is played at this
/// length, every writer's count scaled alike, and its cycles scaled back.
const PLAY_TRANSFERS: u64 = 20_000;

/// One writer's work in a frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct WriterLoad {
    /// Transfers (AW + W bursts).
    pub transfers: u64,
    /// W beats of all of them.
    pub beats: u64,
    /// Writes it may have awaiting their B.
    pub outstanding: usize,
}

impl WriterLoad {
    /// The beats of transfer `i`: `beats` spread over the transfers as evenly as integers go,
    /// at least one (a transfer without beats would never leave the mux's W order).
    fn beats_of(&self, i: u64) -> u64 {
        let n = self.transfers.max(1);
        (self.beats * (i + 1) / n - self.beats * i / n).max(1)
    }
}

/// The played state of one writer.
#[derive(Default)]
struct Writer {
    /// Transfers taken so far.
    taken: u64,
    /// The AW of the last taken transfer waits for its grant.
    aw_valid: bool,
    /// W beats of the last taken transfer still to go.
    w_left: u64,
    /// Writes awaiting their B.
    in_flight: usize,
    /// Due cycles of the B responses, in order.
    b_due: VecDeque<u64>,
    /// The due cycle of the last B (one ID: a B never overtakes the one before it).
    last_due: u64,
}

/// Cycles the writers `loads` (on one port) take for their frame's transfers behind `mem`;
/// 0 without transfers. The first writer with the most `transfers * (beats / transfer + 2)`
/// leads: the others' transfer `i` of `n` waits until the lead has taken `i / n` of its own.
pub fn pre_writer_cycles(mem: &PortTiming, loads: &[WriterLoad]) -> f64 {
    let cost = |l: &WriterLoad| l.beats + 2 * l.transfers;
    let Some(lead) = (0..loads.len())
        .filter(|&c| loads[c].transfers > 0)
        .max_by_key(|&c| (cost(&loads[c]), std::cmp::Reverse(c)))
    else {
        return 0.0;
    };
    let scale = (loads[lead].transfers as f64 / PLAY_TRANSFERS as f64).max(1.0);
    let played: Vec<WriterLoad> = loads
        .iter()
        .map(|l| {
            let transfers = (l.transfers as f64 / scale).round() as u64;
            let beats = (l.beats as f64 * transfers as f64 / l.transfers.max(1) as f64).round() as u64;
            WriterLoad { transfers, beats, ..*l }
        })
        .collect();
    play(mem, &played, lead) as f64 * scale
}

/// Cycles until every transfer of `loads` is out (its last W beat taken), played from an idle
/// port; `lead` paces the others.
fn play(mem: &PortTiming, loads: &[WriterLoad], lead: usize) -> u64 {
    let (n, d) = mem.credit();
    let mut draws = XorShift(0x9E37_79B9_7F4A_7C15);
    let b_delay = mem.b_delay();
    let mut writers: Vec<Writer> = loads.iter().map(|_| Writer::default()).collect();
    // The mux's W order: the writers of the AWs taken (by the memory too), until their last W.
    let mut w_order: VecDeque<usize> = VecDeque::new();
    let (mut credit, mut last_grant) = (2 * d, loads.len().saturating_sub(1));
    let (mut aw_ready, mut w_ready) = (draws.ready(mem.ready), false);
    let mut takes = vec![false; loads.len()];
    let done = |ws: &[Writer]| {
        ws.iter().zip(loads).all(|(w, l)| w.taken == l.transfers && !w.aw_valid && w.w_left == 0)
    };
    let mut t = 0u64;
    while !done(&writers) {
        for w in &mut writers {
            while w.b_due.front().is_some_and(|&due| due <= t) {
                w.b_due.pop_front();
                w.in_flight -= 1;
            }
        }
        // W: the head of the W order, when its writer drives a beat and the memory takes it.
        let w_head = w_order.front().copied().filter(|&c| writers[c].w_left > 0);
        let w_fire = w_head.filter(|_| w_ready);
        // AW: round robin from the writer after the last granted.
        let aw_fire = if aw_ready && (w_order.len() as u32) < MUX_W_FIFO_DEPTH {
            (1..=loads.len()).map(|k| (last_grant + k) % loads.len()).find(|&c| writers[c].aw_valid)
        } else {
            None
        };
        let lead_share = writers[lead].taken as f64 / loads[lead].transfers.max(1) as f64;
        for (c, (w, l)) in writers.iter().zip(loads).enumerate() {
            let due = c == lead || (w.taken as f64) < lead_share * l.transfers as f64;
            takes[c] =
                !w.aw_valid && w.w_left == 0 && w.in_flight < l.outstanding && w.taken < l.transfers && due;
        }
        if let Some(c) = w_fire {
            let w = &mut writers[c];
            w.w_left -= 1;
            credit -= d;
            if w.w_left == 0 {
                w_order.pop_front();
                let late = mem.late_delay(&mut draws);
                w.last_due = w.last_due.max(t + b_delay + late);
                let due = w.last_due;
                w.b_due.push_back(due);
            }
        }
        if let Some(c) = aw_fire {
            writers[c].aw_valid = false;
            w_order.push_back(c);
            last_grant = c;
        }
        for ((w, l), &take) in writers.iter_mut().zip(loads).zip(&takes) {
            if take {
                w.aw_valid = true;
                w.w_left = l.beats_of(w.taken);
                w.taken += 1;
                w.in_flight += 1;
            }
        }
        credit = (credit + n).min(2 * d);
        aw_ready = draws.ready(mem.ready);
        w_ready = !w_order.is_empty() && credit >= d && draws.ready(mem.ready);
        t += 1;
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;

    fn load(transfers: u64, beats_each: u64) -> WriterLoad {
        WriterLoad { transfers, beats: transfers * beats_each, outstanding: 8 }
    }

    #[test]
    fn a_lone_writer_behind_the_ideal_memory_takes_its_beats_plus_two_cycles_a_transfer() {
        let cycles = pre_writer_cycles(&PortTiming::IDEAL, &[load(1000, 4)]);
        assert!((cycles - 6000.0).abs() <= 2.0, "{cycles}");
    }

    #[test]
    fn a_paced_burst_on_the_same_port_delays_the_lead_by_its_beats_less_two() {
        let alone = pre_writer_cycles(&PortTiming::IDEAL, &[load(6400, 4)]);
        let shared = pre_writer_cycles(&PortTiming::IDEAL, &[load(6400, 4), load(1000, 8)]);
        let added = shared - alone;
        assert!((added - 6000.0).abs() < 300.0, "{alone} {shared}");
    }

    #[test]
    fn the_random_memory_is_slower_and_no_writer_is_faster_than_its_port() {
        let random =
            PortTiming { latency: 6.0, bandwidth: 0.75, ready: 0.6, late_share: 0.3, late_max: 24.0 };
        let loads = [load(5000, 4), load(800, 8)];
        let ideal = pre_writer_cycles(&PortTiming::IDEAL, &loads);
        let slow = pre_writer_cycles(&random, &loads);
        assert!(slow > ideal * 1.2, "{ideal} {slow}");
        assert!(slow >= (5000.0 * 4.0 + 800.0 * 8.0) / random.write_rate(), "{slow}");
    }

    #[test]
    fn transfers_without_beats_still_finish() {
        let empty = WriterLoad { transfers: 10, beats: 0, outstanding: 8 };
        let cycles = pre_writer_cycles(&PortTiming::IDEAL, &[empty]);
        assert!(cycles > 0.0 && cycles <= 70.0, "{cycles}");
    }

    #[test]
    fn a_long_frame_is_played_at_the_play_length_and_scaled() {
        let short = pre_writer_cycles(&PortTiming::IDEAL, &[load(PLAY_TRANSFERS, 4)]);
        let long = pre_writer_cycles(&PortTiming::IDEAL, &[load(10 * PLAY_TRANSFERS, 4)]);
        assert!((long / short - 10.0).abs() < 0.01, "{short} {long}");
        assert_eq!(pre_writer_cycles(&PortTiming::IDEAL, &[load(0, 4)]), 0.0);
    }
}
