//! The Neo engine: its configuration (the one owner of every count and size of the generated
//! RTL, shared by the generator (`gen/`), the test benches (`tb/`), the latency report and the
//! cycle model (`sim/`)), its control registers ([`regs`]), its memory formats ([`memory`]), the
//! memory-level reference of a frame ([`mod@reference`]), and the host side of a whole-frame
//! cosimulation ([`host`], [`expected`], [`cases`]).

pub mod adapt;
pub mod cases;
mod clients;
mod config;
pub mod expected;
pub mod host;
pub mod memory;
pub mod plan;
pub mod pre;
mod pre_regs;
pub mod reference;
pub mod regs;

pub use adapt::{engine_passes, AdaptRegs, EnginePlan, ADAPT_ENABLE};
pub use cases::{CaseScene, EngineCase, WINDOW_CASE};
pub use clients::{client_port_slot, port_slot_client, port_slots, MemoryClient};
pub use config::{
    check_raster_window, ConfigError, EngineConfig, SchedulerPolicy, Topology, AXI_DATA_BITS, BRIDGE_W_SLOTS,
    COMPLETION_QUEUE_DEPTH, MAX_RASTER_WINDOW, MAX_SORT_CORES, MUX_W_FIFO_DEPTH, ROUTING_FIFO_DEPTH,
};
pub use expected::{Expected, Mismatch, Place, PreExpected};
pub use host::{
    EngineSession, FramePlan, HostMode, MemoryLayout, Planner, SceneLayout, SessionError, SessionOptions,
};
pub use memory::{Memory, TileDescriptor, TileResult};
pub use plan::{run_command, tile_plan, tile_steps, TileCmd, TilePlan, TileRegion, TileShape, TileStep};
pub use pre::{
    beats_spanned, pre_traffic, pre_transfers, pre_transfers_of, preprocess_frame, sh_record_words, PrePart,
    PreRecords, PreTransfer, PreWork,
};
pub use reference::{
    execute_frame, execute_frame_traced, segment_work, FrameError, FrameOutcome, FrameTrace, RasterTrace,
    SegmentWork, TileTrace,
};
pub use regs::{
    fb_base_alignment, CameraWord, Counter, Counters, FrameRegs, MisalignedBase, PreRegs, Reg, CAMERA_WORDS,
    PRE_ENABLE, PRE_FRESH, PRE_SH_HALF,
};
