//! Plant simulations (placeholder docs, replaced below).
#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]
#![cfg_attr(not(test), deny(clippy::indexing_slicing))]

mod core;
mod devices;
mod fault;
mod station;
pub mod sun;
mod topology;

pub use crate::core::{
    Direction, Plant, PlantError, Reading, SignalInfo, SimTime, Value, ValueKind,
};
pub use crate::devices::{GeneratorConfig, GeneratorState};
pub use crate::fault::{Action, Fault};
pub use crate::station::{lighting_boards, Module, StationConfig, VsetinPlant};
pub use crate::topology::{
    BusState, LinkState, SafetyEvent, SafetyKind, SourceState, TopologySnapshot,
};
