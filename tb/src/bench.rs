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

/// Result of the raster-core benchmark.
#[derive(Clone, Copy, Debug)]
pub struct TileThroughput {
    /// Tiles rendered (each checked against the golden pipeline).
    pub tiles: u64,
    /// Table entries of the tiles.
    pub entries: u64,
    /// Clock cycles simulated.
    pub cycles: u64,
    /// Wall-clock seconds of the cosimulation (golden pipeline excluded).
    pub seconds: f64,
}

impl TileThroughput {
    /// Tiles per second.
    pub fn tiles_per_s(&self) -> f64 {
        self.tiles as f64 / self.seconds
    }

    /// Simulated cycles per second.
    pub fn cycles_per_s(&self) -> f64 {
        self.cycles as f64 / self.seconds
    }
}

/// The raster-core cosimulation speed on the busiest `tiles` 64x64 tiles of one `res x res`
/// biker frame (`scene`: the biker .ply), ideal memory, every pixel and write-back checked
/// against the golden pipeline. `None` without Verilator.
///
/// # Panics
/// At the first mismatch, or when the scene cannot be loaded.
pub fn raster_tile_throughput(scene: &std::path::Path, res: u32, tiles: usize) -> Option<TileThroughput> {
    #[cfg(neo_has_verilator)]
    {
        let cfg = crate::config();
        let jobs = crate::raster::biker_tiles(scene, res, 1, tiles);
        let mut core = crate::raster::RasterCore::new(&cfg, 0x5eed, crate::core::MemTiming::IDEAL);
        let t = std::time::Instant::now();
        let mut cycles = 0;
        for j in &jobs {
            cycles += core.run(&j.case, &j.want).cycles;
        }
        Some(TileThroughput {
            tiles: jobs.len() as u64,
            entries: jobs.iter().map(|j| j.case.table.len() as u64).sum(),
            cycles,
            seconds: t.elapsed().as_secs_f64(),
        })
    }
    #[cfg(not(neo_has_verilator))]
    {
        let _ = (scene, res, tiles);
        None
    }
}
