//! APCI session scenarios on a virtual clock: a client and a server `Session` pumping
//! bytes into each other, or one `Session` against hand-made bytes ("raw peer").
//! Deterministic: time is a base `Instant` plus durations, nothing sleeps.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing,
    missing_docs,
    // Tests and benchmarks measure and wait on the wall clock; the cores do not.
    clippy::disallowed_methods
)]

mod support;

mod api;
mod flow_control;
mod malformed;
mod random;
mod redundancy;
mod sequence_numbers;
mod startdt_stopdt;
mod t1;
mod u_frames;
mod wrong_state;
