//! The project-folder tests of `station::config`, and the runtime recording into either
//! event store backend (the store's own tests are the crate `store`'s).
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing
)]

mod balance;
mod config;
mod field_device;
mod lift;
mod modbus_device;
/// The store tests' throwaway PostgreSQL helpers, one file for both crates.
#[path = "../../../store/tests/it/pg.rs"]
mod pg;
mod runtime_store;
mod s7_device;
mod sink;
mod task_isolation;
