//! The notify crate against real servers on loopback: an aiosmtpd SMTP server
//! (`testkit::smtp`), axum webhook receivers, a refused port; and the TOML
//! configuration.
//!
//! Without python3 and aiosmtpd (installed by `scripts/install-test-deps.sh`) the SMTP
//! tests say so and pass, unless `STANICE_REQUIRE_PEERS=1`, where they fail.

#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing,
    // Tests wait on the wall clock; the policy does not.
    clippy::disallowed_methods
)]

mod config;
mod notifier;
mod smtp;
mod support;
mod webhook;
