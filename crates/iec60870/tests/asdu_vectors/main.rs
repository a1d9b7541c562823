//! ASDU codec against known bytes: the decoded logs of spec §7.3, one derived vector per
//! element family, hardening cases, display and packing.
#![allow(
    clippy::unwrap_used,
    clippy::panic,
    clippy::indexing_slicing,
    missing_docs,
    // Tests and benchmarks measure and wait on the wall clock; the cores do not.
    clippy::disallowed_methods
)]

mod support;

mod derived;
mod hardening;
mod packing;
mod spec;
