//! What the workspace's tests and benchmarks share, written once: a `[dev-dependencies]`
//! entry of the crates that need it, never a dependency of a library or binary.
//!
//! | module       | what                                                                 | used by |
//! |--------------|----------------------------------------------------------------------|---------|
//! | [`ports`]    | a free loopback port; a free range below the ephemeral range; waiting until a port listens | every test that listens or connects |
//! | [`process`]  | a command run to its end with a time limit (output drained); a child killed on drop; a child started until it prints a marker | stanice's CLI and interoperability tests |
//! | [`peers`]    | the skip-or-fail rule for missing peers (`STANICE_REQUIRE_PEERS`); python3 modules; the c104 scripts of `tests/peer/`; a tshark capture checked by the dissectors | iec60870's c104 test and benchmark, stanice's dispatch, capture and IEC 103 tests |
//! | [`chromium`] | chromedriver and Chromium found, a driver on a free port, headless sessions, clicks and scripts (feature `chromium`) | hmi's browser tests and benchmarks |
//! | [`mqtt`]     | a mosquitto broker on a free port; the Sparkplug B consumer of `crates/sparkplug/tests/consumer.py`; a project that changes by itself | sparkplug's broker tests, stanice's `run --mqtt` test |
//! | [`smtp`]     | the aiosmtpd sink of `tests/support/smtp_sink.py`                     | notify's and station's mail tests |
//! | [`projects`] | project folders: the examples, a copy of one without its stores, a folder of given files, a lift fleet | stanice's CLI tests, station's runtime tests, the lift-fleet benchmarks |
//!
//! Test support fails loudly: a helper that cannot do its part (no free port, a child that
//! does not start) panics with what it saw, which fails the test that called it. Peers that
//! are missing are the exception: the test is skipped (it says SKIPPED and passes) unless
//! `STANICE_REQUIRE_PEERS=1` (set by `scripts/test.sh`, hence in CI), where it fails.

// Test support fails loudly by design (see above): unwrap, expect and panic are its way of
// failing the calling test with a message.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::path::{Path, PathBuf};

#[cfg(feature = "chromium")]
pub mod chromium;
pub mod mqtt;
pub mod peers;
pub mod ports;
pub mod process;
pub mod projects;
pub mod smtp;

/// The repository's root (canonical: no `crates/testkit/../..` in messages and paths
/// handed to children).
pub fn repository_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .canonicalize()
        .unwrap()
}
