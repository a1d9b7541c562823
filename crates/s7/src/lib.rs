//! Siemens S7 communication over ISO-on-TCP: reading and writing the memory of S7
//! PLCs as a client, and being one as a server.
//!
//! The use case is the railway-station thesis, section 3.3: LOGO! relays connect as S7
//! clients to an S7-1500 (the server) with configured TSAPs and exchange fixed transfer
//! areas; the station's tools read and write the same areas, and simulate either end.
//!
//! # Layout
//!
//! One module per concept, from the bytes up:
//!
//! | Module | Content |
//! |---|---|
//! | [`tpkt`] | RFC 1006 framing on TCP: [`tpkt::encode`], [`tpkt::Deframer`], [`tpkt::TpktError`] |
//! | [`cotp`] | ISO 8073 class 0: [`cotp::Tpdu`] (CR, CC, DT, DR, DC, ER), [`cotp::ConnectionParams`], [`cotp::TpduSize`], [`cotp::CotpError`] |
//! | [`pdu`] | S7comm: [`pdu::Pdu`] (job, ack, ack_data, userdata), setup communication, read and write var, [`pdu::ItemSpec`] (S7ANY), [`pdu::DataItem`], [`pdu::ReturnCode`], [`pdu::PduError`] |
//! | [`tsap`] | [`Tsap`], [`Tsaps`] (`0100:0301`), [`ConnectionType`] |
//! | [`address`] | [`Area`], [`Region`] (a bit or a byte run), [`Address`] as typed (`DB1.DBW2:INT`), [`AddressError`] |
//! | [`value`] | [`ValueType`], [`Value`]: parsed from text, shown as JSON, to and from big-endian bytes |
//! | [`split`] | cutting reads and writes into jobs that fit the PDU size, both ways: [`split::split_reads`], [`split::split_writes`], [`WriteItem`] |
//! | [`client`] | [`ClientConnection`], sans-IO: connect, setup, reads and writes split and put back together, [`ClientEvent`], [`ItemError`] |
//! | [`memory`] | [`Memory`]: inputs, outputs, markers and data blocks of a simulated PLC |
//! | [`server`] | [`ServerConnection`], sans-IO: any TSAP, setup, read and write var on a [`Memory`], [`ServerEvent`] and [`WriteEvent`] |
//! | [`io`] (feature `tokio`) | [`io::Client`] (`connect`, `read`, `write`, typed `read_values`, `write_values`), [`io::serve`] for many connections on one shared memory |
//! | `link` | the transport under both ends: TPKT and COTP data TPDUs to S7 PDUs and back, [`ConnectionError`] |
//!
//! # Data flow
//!
//! ```text
//! client                                              server
//! "DB1.DBW2:INT" -> Address -> Region                 Memory (shared, locked per call)
//! read(regions) -> split by PDU size -> jobs          ^
//!   job -> Pdu::encode -> DT TPDUs -> TPKT  --TCP-->  Deframer -> Tpdu -> Pdu::decode
//!                                                     ItemSpec -> Region -> Memory
//!   results per item <- ack_data  <--TCP--  ack_data (a return code per item)
//!                                                     writes -> WriteEvent
//! ```
//!
//! Both connections take bytes and hand out bytes and events; neither reads a clock or
//! a socket (`clippy.toml` bans `Instant::now` and `thread::sleep` in this crate). The
//! tokio adapter drives them over TCP; tests drive them over loopback TCP and, for
//! splitting and segmentation, directly against each other.
//!
//! # Why this is written here and not taken from a crate
//!
//! No maintained Rust crate provides both an S7 client and server with sans-IO cores.
//! On crates.io: `rust7` is a blocking, client-only port of Snap7; `rust-snap7` binds
//! the C library Snap7 through FFI (a native build, unsafe code behind it);
//! `snap7-client` and `snap7-server` (the rs-snap7 workspace) are young async crates tied
//! to their own tokio transports, without a core a simulation or a fuzzer can drive.
//! What is needed here is small — setup communication, read var, write var on S7ANY
//! items, the PDU-size splitting and a memory-model server — and is written from the
//! protocol's public descriptions (RFC 1006, ISO 8073 class 0, the S7comm dissector's
//! field documentation), no code copied.
//!
//! # Fuzzing
//!
//! [`fuzz_decode`] runs every decoder and both connections over arbitrary bytes; a
//! cargo-fuzz target needs only to call it.
#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]
#![cfg_attr(not(test), deny(clippy::indexing_slicing))]

pub mod address;
pub mod client;
pub mod cotp;
#[cfg(feature = "tokio")]
pub mod io;
mod link;
pub mod memory;
pub mod pdu;
pub mod server;
pub mod split;
pub mod tpkt;
pub mod tsap;
pub mod value;
mod wire;

pub use address::{Address, AddressError, AddressErrorKind, Area, Region, RegionError, Width};
pub use client::{
    ClientConfig, ClientConnection, ClientEvent, ItemError, OperationId, ReadResult, WriteResult,
};
pub use link::{ConnectionError, MAX_ASSEMBLED_PDU};
pub use memory::{Memory, MemoryError};
pub use server::{ServerConfig, ServerConnection, ServerEvent, WriteEvent};
pub use split::{RequestError, WriteItem};
pub use tsap::{ConnectionType, Tsap, TsapError, Tsaps};
pub use value::{Value, ValueError, ValueType};

/// Runs arbitrary bytes through every decoder and both connection state machines, for
/// fuzzing: nothing here may panic, loop forever or grow without bound.
pub fn fuzz_decode(bytes: &[u8]) {
    let _ = pdu::Pdu::decode(bytes);
    let _ = cotp::Tpdu::decode(bytes);
    let mut deframer = tpkt::Deframer::new();
    deframer.push(bytes);
    while let Ok(Some(frame)) = deframer.next_frame() {
        let _ = cotp::Tpdu::decode(&frame);
    }
    if let Ok(text) = std::str::from_utf8(bytes) {
        let _ = text.parse::<Address>();
        let _ = text.parse::<Tsaps>();
    }

    // Both ends fed the bytes as a stream, in two halves to exercise reassembly.
    let (first, second) = bytes.split_at(bytes.len() / 2);
    let mut memory = Memory::default();
    let _ = memory.add_data_block(1, 64);
    let mut server = ServerConnection::new(ServerConfig::default());
    let mut client = ClientConnection::new(ClientConfig::default());
    let _ = client.read(vec![Region::Bytes {
        area: Area::DataBlock(1),
        start: 0,
        len: 300,
    }]);
    let mut out = Vec::new();
    for half in [first, second] {
        server.handle_input(half, &mut memory);
        client.handle_input(half);
        while server.poll_transmit(&mut out) {}
        while server.poll_event().is_some() {}
        while client.poll_transmit(&mut out) {}
        while client.poll_event().is_some() {}
    }
}
