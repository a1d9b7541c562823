//! Integration tests of the plant crate: one binary, one module per area.
// Helpers used by the tests panic on error: their panics are the failure report.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

mod control;
mod devices;
mod faults;
mod lab;
mod lighting;
mod logo;
mod prop;
mod sorter;
mod sun;
mod topology;
mod transfer;
mod year;

use std::time::Duration;

use plant::{Plant, Value, VsetinPlant};

/// Milliseconds.
pub fn ms(x: u64) -> Duration {
    Duration::from_millis(x)
}

/// Seconds.
pub fn s(x: u64) -> Duration {
    Duration::from_secs(x)
}

/// Reads a digital signal.
pub fn get(p: &VsetinPlant, name: &str) -> bool {
    p.bool(name).unwrap()
}

/// Reads an analog signal.
pub fn real(p: &VsetinPlant, name: &str) -> f64 {
    p.real(name).unwrap()
}

/// Drives an output.
pub fn set(p: &mut VsetinPlant, name: &str, v: bool) {
    p.set_output(name, Value::Bool(v)).unwrap()
}

/// Advances to an absolute time.
pub fn at(p: &mut VsetinPlant, t: Duration) {
    p.advance_to(t).unwrap()
}
