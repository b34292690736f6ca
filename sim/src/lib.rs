//! Cycle model, DRAM model, baselines and reports (filled in by the cycle-model issue).
