//! The Stanice station runtime.
//!
//! A station is a hierarchy of nodes (controllers) run from a project folder: PLC programs
//! feed point databases, nodes publish them over IEC 60870-5-104 and concentrate the nodes
//! below them, and every value change and command is recorded.
//!
//! | module        | what it does                                                      |
//! |---------------|-------------------------------------------------------------------|
//! | [`config`]    | the project folder: `station.toml`, nodes, points, links, tables, errors with file:line:col |
//! | [`pointdb`]   | per-node typed values with quality and source time, report by exception |
//! | [`runtime`]   | runs a project: simulated clock, plant and PLCs, servers, links (concentration, commands down the hierarchy), recording |
//! | [`store`]     | the event and command-audit store (SQLite, PostgreSQL), retention |
#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]
#![cfg_attr(not(test), deny(clippy::indexing_slicing))]

pub mod config;
#[cfg(feature = "store")]
pub mod pointdb;
#[cfg(feature = "runtime")]
pub mod runtime;
#[cfg(feature = "store")]
pub mod store;
pub mod store_url;
