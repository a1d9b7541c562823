//! The devices crate's integration tests, one binary: spec vectors, negative tests,
//! property tests, poller against simulator on a virtual clock, and both over a real
//! pseudo-terminal pair.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing
)]

mod figures;
mod properties;
mod pty;
mod scenario;
mod tables;
mod vectors;
