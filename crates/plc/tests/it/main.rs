//! Integration tests of the plc crate (one test binary).
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing
)]

mod conformance;
mod diagnostics;
mod fused;
mod fuzzish;
mod jit;
mod railway;
mod runtime;
mod safe_stop;
mod support;
