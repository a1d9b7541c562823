//! The s7 crate's integration tests, one binary: address and value spelling, frame
//! vectors written from the protocol description, the sans-IO client against the sans-IO
//! server, property tests of the codecs and the splitting, and client and server over
//! loopback TCP.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing
)]

mod address;
mod frames;
#[cfg(feature = "tokio")]
mod loopback;
mod pair;
#[cfg(feature = "tokio")]
mod peer;
mod props;
