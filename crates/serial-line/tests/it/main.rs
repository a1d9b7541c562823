//! The serial-line crate's integration tests, one binary: the transports over real
//! pseudo-terminals and TCP sockets, and the drive loop around an endpoint.
#![cfg(feature = "tokio")]
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing
)]

mod drive;
mod open;
