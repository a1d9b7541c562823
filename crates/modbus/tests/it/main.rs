//! The modbus crate's integration tests, one binary: frame vectors from the published
//! layouts, property tests of the codecs, our client against our servers over loopback
//! TCP and over a pseudo-terminal pair (RTU), and interoperability with pymodbus both
//! ways on both transports.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing
)]

mod loopback;
mod props;
mod pty;
mod pymodbus;
mod support;
mod vectors;
mod wireshark;
