//! The control port's model, derived from golden [`neo_golden::engine::regs`] (offsets, access,
//! STATUS bits, counter offsets), and the performance counters' model.
//!
//! [`RegModel`] is what a host sees on `neo_engine_regs`: read/write registers read back the
//! last 32 bits written (byte enables honoured), write-only registers read 0, writes to
//! read-only registers and to unmapped words are ignored, unmapped words read 0; every response
//! OKAY; address bits `[1:0]` ignored. A `CTRL` write with byte 0 enabled and `CTRL_START` set
//! starts a frame unless busy.

use neo_golden::engine::regs::{
    Access, Counter, Counters, FrameRegs, Reg, ADDR_BITS, COUNTERS, COUNTER_BASE, CTRL_START, STATUS_BUSY,
    STATUS_DONE, STATUS_OVERFLOW,
};

/// The inputs of the register block: status levels, overflow report, counters.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RegInputs {
    /// STATUS.busy.
    pub busy: bool,
    /// STATUS.done.
    pub done: bool,
    /// STATUS.overflow.
    pub overflow: bool,
    /// FIRST_OVERFLOW.
    pub first_overflow: u32,
    /// OVERFLOWS.
    pub overflows: u32,
    /// The counters.
    pub counters: Counters,
}

/// The register file as the host sees it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RegModel {
    /// The read/write registers' contents, indexed by [`Reg::index`].
    rw: Vec<u32>,
}

/// The word offset (`addr` within the 12-bit space, low two bits cleared).
pub fn word_offset(addr: u32) -> u32 {
    addr & ((1 << ADDR_BITS) - 1) & !3
}

/// The counter and word (0 low, 1 high) at word offset `off`, if any.
pub fn counter_at(off: u32) -> Option<(Counter, u32)> {
    let end = COUNTER_BASE + 8 * COUNTERS as u32;
    (COUNTER_BASE..end).contains(&off).then(|| {
        let k = ((off - COUNTER_BASE) / 8) as usize;
        (Counter::ALL[k], (off - Counter::ALL[k].offset()) / 4)
    })
}

impl Default for RegModel {
    fn default() -> Self {
        RegModel::new()
    }
}

impl RegModel {
    /// The reset state (every register 0).
    pub fn new() -> Self {
        RegModel { rw: vec![0; Reg::ALL.len()] }
    }

    /// The value of read/write register `r`.
    pub fn get(&self, r: Reg) -> u32 {
        self.rw[r.index()]
    }

    /// What a read of `addr` returns with inputs `inp`.
    pub fn read(&self, addr: u32, inp: &RegInputs) -> u32 {
        let off = word_offset(addr);
        if let Some(r) = Reg::at(off) {
            return match r.access() {
                Access::W => 0,
                Access::RW => self.rw[r.index()],
                Access::R => match r {
                    Reg::Status => {
                        (if inp.busy { STATUS_BUSY } else { 0 })
                            | (if inp.done { STATUS_DONE } else { 0 })
                            | (if inp.overflow { STATUS_OVERFLOW } else { 0 })
                    }
                    Reg::FirstOverflow => inp.first_overflow,
                    Reg::Overflows => inp.overflows,
                    other => panic!("read-only register {} not modelled", other.name()),
                },
            };
        }
        match counter_at(off) {
            Some((c, word)) => (inp.counters.get(c) >> (32 * word)) as u32,
            None => 0,
        }
    }

    /// Applies a write of `data` with byte enables `strb` to `addr`; returns true when it
    /// starts a frame (`CTRL.start` with `busy` low).
    pub fn write(&mut self, addr: u32, data: u32, strb: u8, busy: bool) -> bool {
        let Some(r) = Reg::at(word_offset(addr)) else { return false };
        let mask = (0..4).filter(|b| strb >> b & 1 != 0).fold(0u32, |m, b| m | 0xff << (8 * b));
        match r.access() {
            Access::RW => {
                let v = &mut self.rw[r.index()];
                *v = (*v & !mask) | (data & mask);
                false
            }
            Access::W => r == Reg::Ctrl && data & mask & CTRL_START != 0 && !busy,
            Access::R => false,
        }
    }

    /// The frame registers as programmed (golden [`FrameRegs::from_registers`]).
    pub fn frame_regs(&self) -> FrameRegs {
        FrameRegs::from_registers(|r| self.get(r))
    }
}

/// The performance counters' model: `clear` restarts every counter at this cycle's increment.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CounterModel {
    /// The counts.
    pub counts: Counters,
}

impl CounterModel {
    /// One rising edge with `clear` and per-counter increments `inc`.
    pub fn step(&mut self, clear: bool, inc: &[u32; COUNTERS]) {
        for (c, &i) in self.counts.0.iter_mut().zip(inc) {
            *c = if clear { 0 } else { *c }.wrapping_add(i as u64);
        }
    }
}

/// Packs 64-bit values into little-endian 32-bit words (`counters_i` / `counters_o`).
pub fn pack_u64s(v: &[u64]) -> Vec<u32> {
    v.iter().flat_map(|&x| [x as u32, (x >> 32) as u32]).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_model_follows_the_access_rules() {
        let mut m = RegModel::new();
        let mut inp =
            RegInputs { busy: true, overflow: true, first_overflow: 7, overflows: 2, ..Default::default() };
        inp.counters.add(Counter::RdFeat, 0x1_0000_0020);
        assert!(!m.write(Reg::Ctrl.offset(), 1, 0xf, true), "start ignored while busy");
        assert!(!m.write(Reg::Ctrl.offset(), 1, 0xe, false), "start needs byte 0");
        assert!(m.write(Reg::Ctrl.offset() + 2, 1, 0x1, false), "low address bits ignored");
        assert_eq!(m.read(Reg::Ctrl.offset(), &inp), 0);
        m.write(Reg::Width.offset(), 0xaabb_ccdd, 0xf, false);
        m.write(Reg::Width.offset(), 0x1122_3344, 0b0101, false);
        assert_eq!(m.read(Reg::Width.offset(), &inp), 0xaa22_cc44);
        m.write(Reg::Status.offset(), 0xffff_ffff, 0xf, false);
        assert_eq!(m.read(Reg::Status.offset(), &inp), STATUS_BUSY | STATUS_OVERFLOW);
        assert_eq!(m.read(Reg::FirstOverflow.offset(), &inp), 7);
        assert_eq!(m.read(Counter::RdFeat.offset(), &inp), 0x20);
        assert_eq!(m.read(Counter::RdFeat.offset() + 4, &inp), 1);
        assert_eq!(m.read(0x48, &inp), 0);
        assert_eq!(m.read(COUNTER_BASE + 8 * COUNTERS as u32, &inp), 0);
        m.write(Reg::FbBaseHi.offset(), 3, 0xf, false);
        assert_eq!(m.frame_regs().fb_base, 3 << 32);
    }

    #[test]
    fn counters_restart_at_the_clear_cycles_increment() {
        let mut c = CounterModel::default();
        let mut inc = [0u32; COUNTERS];
        inc[0] = 5;
        c.step(false, &inc);
        c.step(false, &inc);
        assert_eq!(c.counts.0[0], 10);
        inc[0] = 3;
        c.step(true, &inc);
        assert_eq!(c.counts.0[0], 3);
        assert_eq!(pack_u64s(&[0x1_0000_0002]), vec![2, 1]);
    }
}
