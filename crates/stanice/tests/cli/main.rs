//! The `stanice` binary as a user runs it: real processes on loopback.

#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing
)]

mod support;

mod balance;
mod dispatch;
mod iec104;
mod lab;
mod messages;
mod modbus;
mod plc;
mod points_and_events;
mod run;
mod s7;
mod serial;
mod shutdown;
mod sorting;
mod sparkplug;
mod stats;
mod users;
