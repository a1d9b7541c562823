//! IEC 60870-5-101/104 protocol library.
//!
//! # Layout
//!
//! One module per concept, from the bytes up:
//!
//! - [`time`]: the time tags CP56Time2a, CP24Time2a and CP16Time2a.
//! - [`asdu`]: the application layer, sans-IO. Type identifications, causes of
//!   transmission, addresses, information elements and the ASDU codec. Field sizes (COT,
//!   common address, IOA) are [`asdu::AsduParams`], so IEC 101 reuses the codec.
//! - [`apci`]: IEC 104 framing. I, S and U control fields, 15-bit sequence numbers and a
//!   deframer that cuts APDUs out of a TCP byte stream.
//! - [`cs104`]: IEC 104 stations.
//!   - `session`: the sans-IO APCI state machine of one connection: STARTDT/STOPDT/TESTFR,
//!     k/w windows, t1/t2/t3 timers. It takes bytes and `Instant`s and hands out bytes,
//!     events and its next deadline; it never reads a clock or a socket.
//!   - `server` and `client`: tokio drivers around sessions. The server owns a process
//!     image (the current value of every point), redundancy groups with their event
//!     buffers, and answers interrogation, read, clock sync and commands. The client
//!     connects with back-off, starts data transfer and awaits command confirmations.
//!   - `tls`: rustls configuration for mutual authentication (IEC 62351-3).
//!
//! # Data flow
//!
//! ```text
//! TCP bytes -> apci::Deframer -> cs104::Session (sequence numbers, windows, timers)
//!           -> ASDU bytes -> asdu::Asdu::decode -> server/client logic -> user
//! user -> server/client logic -> asdu::Asdu::encode -> Session::send_asdu -> TCP bytes
//! ```
#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]
#![cfg_attr(not(test), deny(clippy::indexing_slicing))]

pub mod apci;
pub mod asdu;
pub mod cs104;
pub mod outstation;
pub mod time;
