//! Deterministic synthetic scenes (the embedded default).
