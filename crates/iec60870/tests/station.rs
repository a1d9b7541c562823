//! Integration tests of the IEC 104 server and client over real loopback TCP.
//!
//! Every test starts its own server on 127.0.0.1 port 0 and talks to it with the library's
//! client or with `RawPeer`, a hand-driven controlling station for what the client cannot
//! do (stay stopped, send garbage or raw ASDUs, act as a standby connection). Every wait is
//! bounded by a time-out.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing,
    missing_docs,
    // Tests and benchmarks measure and wait on the wall clock; the cores do not.
    clippy::disallowed_methods
)]

#[path = "station/common.rs"]
mod common;

#[path = "station/availability.rs"]
mod availability;
#[path = "station/client.rs"]
mod client;
#[path = "station/command_age.rs"]
mod command_age;
#[path = "station/command_sequence.rs"]
mod command_sequence;
#[path = "station/commands.rs"]
mod commands;
#[path = "station/events.rs"]
mod events;
#[path = "station/interrogation.rs"]
mod interrogation;
#[path = "station/link.rs"]
mod link;
#[path = "station/redundancy.rs"]
mod redundancy;
#[path = "station/redundancy_modes.rs"]
mod redundancy_modes;
#[path = "station/requests.rs"]
mod requests;
#[path = "station/robustness.rs"]
mod robustness;
#[path = "station/tls.rs"]
mod tls;
