//! IEC 60870-5-101/104 protocol library.
//!
//! # Layout
//!
//! One module per concept, from the bytes up:
//!
//! - [`time`]: the time tags CP56Time2a, CP32Time2a (IEC 103), CP24Time2a and CP16Time2a.
//! - [`asdu`]: the application layer, sans-IO. Type identifications, causes of
//!   transmission, addresses, information elements and the ASDU codec. Field sizes (COT,
//!   common address, IOA) are [`asdu::AsduParams`], so IEC 101 reuses the codec.
//! - [`apci`]: IEC 104 framing. I, S and U control fields, 15-bit sequence numbers and a
//!   deframer that cuts APDUs out of a TCP byte stream.
//! - [`outstation`]: the controlled station without a transport, sans-IO: the process
//!   image, redundancy groups with their event buffers, interrogation, read, clock sync,
//!   commands with their checks and their sequence (ACT_CON, return information,
//!   ACT_TERM). [`outstation::LinkCore`] is one link's part; a link layer (IEC 104's APCI
//!   session, the FT1.2 link layer of IEC 101) plugs in through
//!   [`outstation::LinkLayer`]. A fuzz target and `tests/outstation.rs` drive it with no
//!   socket at all.
//! - [`point_list`]: the CSV point lists (address, type, value, name, description,
//!   select, groups) of the test tools' outstations and the HMI, read once.
//! - [`controlling`]: the controlling station's part without a transport: open requests
//!   and how received ASDUs finish them (confirmation, termination, timeouts), what it
//!   sends when data transfer starts (clock sync, interrogation).
//! - [`ft12`]: the FT1.2 link layer of IEC 101 and 103 over serial lines, sans-IO:
//!   frames and a resynchronising deframer, the unbalanced primary polling many
//!   secondaries and the secondary, and a simulated line on a virtual clock.
//! - [`iec101`]: IEC 101 over FT1.2: the outstation core behind an unbalanced
//!   secondary ([`iec101::Slave`]) and a master polling outstations
//!   ([`iec101::Master`]).
//! - [`iec103`]: IEC 103, the protection-equipment companion standard: its ASDU codec
//!   (FUN/INF, measurands, identification, GI, general command, disturbance transfer).
//! - [`cs104`]: IEC 104.
//!   - `session`: the sans-IO APCI state machine of one connection: STARTDT/STOPDT/TESTFR,
//!     k/w windows, t1/t2/t3 timers. It takes bytes and `Instant`s and hands out bytes,
//!     events and its next deadline; it never reads a clock or a socket.
//!   - `server` and `client` (feature `tokio`, on by default): tokio adapters. The server
//!     accepts TCP/TLS connections and drives a `Session` and an outstation `LinkCore`
//!     for each; the client connects with back-off, drives a `Session` and the
//!     controlling core's `OpenRequests`, and probes a quiet standby connection.
//!   - `link` (feature `tokio`): a controlling station's link kept up for its owner
//!     (cut, restore, stop, state and data to a `LinkObserver`): the station's
//!     concentrator links and the HMI use it.
//!   - `tls` (feature `tokio`): rustls configuration for mutual authentication
//!     (IEC 62351-3).
//!
//! The cores read no clock: `clippy.toml` bans `Instant::now`, `SystemTime::now` and
//! chrono's `now` in this crate; the adapters use tokio's clock, the outstation the
//! station's ([`outstation::StationHandler::now`]).
//!
//! # Data flow
//!
//! ```text
//! TCP bytes -> apci::Deframer -> cs104::Session (sequence numbers, windows, timers)
//!           -> ASDU bytes -> outstation::LinkCore (or the client) -> the application
//! application -> Outstation::update -> group buffers -> LinkCore::fill
//!           -> Session::send_asdu -> TCP bytes
//! ```
#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]
#![cfg_attr(not(test), deny(clippy::indexing_slicing))]

pub mod apci;
pub mod asdu;
pub mod controlling;
pub mod cs104;
pub mod ft12;
pub mod iec101;
pub mod iec103;
pub mod outstation;
pub mod point_list;
pub mod time;
