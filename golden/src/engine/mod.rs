//! The Neo engine: its configuration (the one owner of every count and size of the generated
//! RTL, shared by the generator (`gen/`), the test benches (`tb/`), the latency report and the
//! cycle model (`sim/`)), its control registers ([`regs`]) and its memory formats ([`memory`]).

mod config;
pub mod memory;
pub mod regs;

pub use config::{ConfigError, EngineConfig, SchedulerPolicy, Topology};
pub use memory::{Memory, TileDescriptor, TileResult};
pub use regs::{Counter, Counters, FrameRegs, Reg};
