//! Entry points for `neo bench` and `neo report` that exist whether or not the crate was built
//! with Verilator (they return `None` without it).

/// Result of the BSU throughput benchmark.
#[derive(Clone, Copy, Debug)]
pub struct Throughput {
    /// Random vectors checked against the golden network.
    pub vectors: u64,
    /// Clock cycles simulated (summed over models).
    pub cycles: u64,
    /// Wall-clock seconds.
    pub seconds: f64,
}

impl Throughput {
    /// Vectors checked per second.
    pub fn vectors_per_s(&self) -> f64 {
        self.vectors as f64 / self.seconds
    }

    /// Millions of simulated cycles per second.
    pub fn mcycles_per_s(&self) -> f64 {
        self.cycles as f64 / self.seconds / 1e6
    }
}

/// True when the crate was built with Verilated models.
pub const HAS_MODELS: bool = cfg!(neo_has_verilator);

/// The BSU cosimulation throughput: `vectors` random vectors at full rate over `threads`
/// independent models, each output compared with golden `Network::apply`. `None` without
/// Verilator.
///
/// # Panics
/// At the first mismatch (the RTL disagrees with the golden model).
pub fn bsu_throughput(vectors: u64, seed: u64, threads: usize) -> Option<Throughput> {
    #[cfg(neo_has_verilator)]
    {
        Some(crate::bsu::throughput(&crate::config(), vectors, seed, threads))
    }
    #[cfg(not(neo_has_verilator))]
    {
        let _ = (vectors, seed, threads);
        None
    }
}

/// The text of `reports/latency.json` measured now ([`crate::latency`]). `None` without
/// Verilator.
pub fn latency_report_text() -> Option<String> {
    #[cfg(neo_has_verilator)]
    {
        Some(crate::latency::report_text(&crate::config()))
    }
    #[cfg(not(neo_has_verilator))]
    {
        None
    }
}
