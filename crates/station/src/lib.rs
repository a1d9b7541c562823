//! The Stanice station runtime.
//!
//! A station is a hierarchy of nodes (controllers) run from a project folder: PLC programs
//! feed point databases, nodes publish them over IEC 60870-5-104 and concentrate the nodes
//! below them, and every value change and command is recorded.
//!
//! | module        | what it does                                                      |
//! |---------------|-------------------------------------------------------------------|
//! | [`config`]    | the project folder: `station.toml`, nodes, points, links, tables; its errors: where ([`config::ConfigError`], file:line:col and key) and what, typed ([`config::ConfigProblem`]) |
//! | [`runtime`]   | runs a project: simulated clock, plant and PLCs, servers, links (concentration, commands down the hierarchy), recording |
//!
//! Points are the `points` crate's (the point model) and meet IEC 60870-5 in `points-iec`;
//! the event store and store addresses are the crate [`store`]'s, re-exported here
//! ([`store`], [`store_url`]). The
//! feature `store` turns on its backends, recorder and retention (what a controlling station
//! such as the HMI needs, without the soft PLC and the plant); `runtime` (the default)
//! brings the PLC and the plant as well.
#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]
#![cfg_attr(not(test), deny(clippy::indexing_slicing))]

pub mod config;
pub mod device;
#[cfg(feature = "runtime")]
pub mod runtime;

pub use ::store::{self, url as store_url};
