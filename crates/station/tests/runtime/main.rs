//! Scenario tests of the station runtime on the Vsetín project: every node in one
//! process, real IEC 104 links on loopback between them, the plant and the PLCs on a
//! manually advanced simulated clock, and a dispatch client on the top node.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing
)]

mod command_sequence;
mod continuity;
mod distributed;
mod harness;
mod hierarchy;
mod lighting;
mod power;
mod s7_concentrator;
mod sorting_lab;
mod storage;
mod time;
mod tls;
mod vsetin_s7;
mod whole_station;
