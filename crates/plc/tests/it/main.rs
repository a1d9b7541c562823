//! Integration tests of the plc crate (one test binary).

mod conformance;
mod fuzzish;
mod railway;
mod runtime;
