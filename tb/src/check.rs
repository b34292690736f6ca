//! Checkers: compare DUT outputs with the golden model and stop at the FIRST mismatch with a
//! message naming the cycle, unit, field, expected and actual values (hex) and the seed.

use neo_golden::sort::SortEntry;

/// Context for mismatch messages.
#[derive(Clone, Debug)]
pub struct Checker {
    /// Unit (module) name.
    pub unit: String,
    /// The test's seed (printed with every failure).
    pub seed: u64,
}

impl Checker {
    /// A checker for `unit` in a test seeded with `seed`.
    pub fn new(unit: &str, seed: u64) -> Self {
        Checker { unit: unit.to_string(), seed }
    }

    /// Panics with the standard mismatch message.
    #[track_caller]
    pub fn fail(&self, cycle: u64, field: &str, expected: &str, actual: &str) -> ! {
        panic!(
            "MISMATCH at cycle {cycle}: unit {unit}, field {field}: expected {expected}, actual {actual} \
             (seed = 0x{seed:016x}; reproduce with NEO_SEED=0x{seed:016x})",
            unit = self.unit,
            seed = self.seed
        )
    }

    /// Checks one scalar field.
    #[track_caller]
    pub fn value(&self, cycle: u64, field: &str, expected: u64, actual: u64) {
        if expected != actual {
            self.fail(cycle, field, &format!("0x{expected:x}"), &format!("0x{actual:x}"));
        }
    }

    /// Checks one entry field by field (`valid`, `key`, `id`); `what` names it (e.g. `out[3]`).
    #[track_caller]
    pub fn entry(&self, cycle: u64, what: &str, expected: &SortEntry, actual: &SortEntry) {
        self.value(cycle, &format!("{what}.valid"), expected.valid as u64, actual.valid as u64);
        self.value(cycle, &format!("{what}.key"), expected.key as u64, actual.key as u64);
        self.value(cycle, &format!("{what}.id"), expected.id as u64, actual.id as u64);
    }

    /// Checks a protocol property that must always hold.
    #[track_caller]
    pub fn protocol(&self, cycle: u64, ok: bool, what: &str) {
        if !ok {
            panic!(
                "PROTOCOL VIOLATION at cycle {cycle}: unit {}: {what} (seed = 0x{:016x}; reproduce with \
                 NEO_SEED=0x{:016x})",
                self.unit, self.seed, self.seed
            );
        }
    }

    /// Panics with a protocol violation on one field: the value the rule `rule` required
    /// (`expected`) and the one seen (`actual`), both already formatted (hex).
    #[track_caller]
    pub fn protocol_field(&self, cycle: u64, field: &str, expected: &str, actual: &str, rule: &str) -> ! {
        panic!(
            "PROTOCOL VIOLATION at cycle {cycle}: unit {unit}, field {field}: expected {expected}, actual \
             {actual} ({rule}) (seed = 0x{seed:016x}; reproduce with NEO_SEED=0x{seed:016x})",
            unit = self.unit,
            seed = self.seed
        );
    }
}

/// The memory-port rule "no write is duplicated": every address a run (a command, a tile) writes,
/// with the cycle of its write. A second write to an address is a protocol violation (no unit
/// documents one). Shared by the Sorting Core's and the raster core's memory models.
#[derive(Clone, Debug, Default)]
pub struct WriteOnce {
    at: std::collections::HashMap<u64, u64>,
}

impl WriteOnce {
    /// Records a write of `what` at `addr` in `cycle`; panics through `checker` when `addr` was
    /// written before in this run.
    #[track_caller]
    pub fn record(&mut self, checker: &Checker, cycle: u64, what: &str, addr: u64) {
        if let Some(first) = self.at.insert(addr, cycle) {
            checker.protocol(
                cycle,
                false,
                &format!(
                    "{what} 0x{addr:x} written twice (first in cycle {first}; no write may be duplicated)"
                ),
            );
        }
    }

    /// The cycle `addr` was written in, if it was.
    pub fn get(&self, addr: u64) -> Option<u64> {
        self.at.get(&addr).copied()
    }

    /// Addresses written.
    pub fn len(&self) -> usize {
        self.at.len()
    }

    /// True when nothing was written.
    pub fn is_empty(&self) -> bool {
        self.at.is_empty()
    }

    /// Starts a new run.
    pub fn clear(&mut self) {
        self.at.clear();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    #[should_panic(
        expected = "MISMATCH at cycle 7: unit neo_bsu, field out[2].key: expected 0x1f, actual 0x20"
    )]
    fn entry_mismatch_names_the_field() {
        let c = Checker::new("neo_bsu", 0xabc);
        c.entry(7, "out[2]", &SortEntry::new(0x1f, 3), &SortEntry::new(0x20, 3));
    }

    #[test]
    #[should_panic(
        expected = "PROTOCOL VIOLATION at cycle 9: unit u: table entry 0x40 written twice (first in cycle 3"
    )]
    fn a_second_write_to_an_address_is_a_violation() {
        let c = Checker::new("u", 1);
        let mut w = WriteOnce::default();
        w.record(&c, 3, "table entry", 0x40);
        w.record(&c, 5, "table entry", 0x41);
        assert_eq!((w.len(), w.get(0x40)), (2, Some(3)));
        w.record(&c, 9, "table entry", 0x40);
    }

    #[test]
    fn equal_entries_pass() {
        let c = Checker::new("u", 1);
        c.entry(0, "x", &SortEntry::new(1, 2), &SortEntry::new(1, 2));
    }
}
