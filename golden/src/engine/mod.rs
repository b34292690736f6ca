//! The Neo engine's configuration: the one owner of every count and size of the generated RTL,
//! shared by the generator (`gen/`), the test benches (`tb/`), the latency report and the cycle
//! model (`sim/`).

mod config;

pub use config::{ConfigError, EngineConfig, SchedulerPolicy, Topology};
