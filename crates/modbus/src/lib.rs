//! Modbus TCP and RTU: a client (master) that polls devices, and servers (a TCP server,
//! an RTU slave) that serve a shared data model, over the serial-line crate's transports
//! (serial ports, pseudo-terminals, TCP).
//!
//! Function codes 1, 2, 3, 4 (reads), 5, 6, 15, 16 (writes) and 23 (read/write
//! registers); exception responses; unit ids (per-unit or single-unit servers, RTU
//! broadcast); timeouts and repeats in the client.
//!
//! # Layout
//!
//! | Module | Content |
//! |---|---|
//! | [`pdu`] | [`Request`], [`Response`], [`Answer`] (a response or an [`ExceptionCode`]), [`FunctionCode`], their encoding and decoding with the specification's limits, [`PduError`] |
//! | [`model`] | [`DataModel`]: the four [`Table`]s of 10,000 entries, one set or one per unit ([`Units`], [`ModelConfig`]), shared by every connection; [`Values`]; a [`WriteEvent`] per write by a client |
//! | [`server`] | [`server::answer`]: one request PDU to its answer PDU, with the unit id as the [`Framing`] reads it |
//! | [`tcp`] | the MBAP header, [`tcp::MbapDeframer`], [`tcp::TcpServerConnection`] (sans-IO) |
//! | [`rtu`] | [`rtu::crc16`], frames, the frame gap, [`rtu::RtuDeframer`], [`RtuSlave`] (a sans-IO `LineEndpoint`) |
//! | [`client`] (feature `tokio`) | [`Client`]: reads and writes with timeouts and repeats on tokio-modbus, [`ClientConfig`], [`ClientError`] |
//! | [`io`] (feature `tokio`) | [`io::serve_tcp`] (many connections, one model), [`io::serve_rtu`] (the slave's drive loop) |
//!
//! # Data flow
//!
//! ```text
//! client (tokio-modbus framing)                 server (ours, sans-IO cores)
//! Client::read(unit, table, address, count)
//!   -> tokio-modbus Request -> MBAP or RTU frame
//!   --TCP / serial line / pty-->                TCP: MbapDeframer -> TcpServerConnection
//!                                               RTU: RtuDeframer (length + CRC, line pause)
//!                                                    -> RtuSlave (answers after the frame gap)
//!                                               server::answer(model, framing, unit, pdu)
//!                                                 Request::decode (exception 1, 3)
//!                                                 DataModel::execute (exception 2, 0x0B)
//!                                                   writes -> WriteEvent -> subscribers
//!   <-- response or exception frame --          Answer::encode -> frame
//! timeout -> repeat (retries) -> ClientError::Timeout naming peer, unit and time
//! counts and echoes checked -> Values
//! ```
//!
//! The cores (codecs, model, server connections, slave) read no clock and no socket
//! (`clippy.toml` bans `Instant::now` and `thread::sleep` here); the adapters in
//! [`client`] and [`io`] use tokio's clock.
//!
//! # Why this is written here and what is taken from tokio-modbus
//!
//! The client is tokio-modbus 0.17's (`tokio_modbus::client::{tcp, rtu}::attach_slave`
//! on the serial-line crate's stream): its framing, transaction ids and header checks.
//! Around it [`Client`] adds a timeout per attempt, repeats, the RTU master's frame gap,
//! reopening a transport after its stream failed (tokio-modbus's framed stream ends at
//! the first decoding error), and checks of the answer's counts and echoes against the
//! request; it calls `Client::call` and never tokio-modbus's `Reader`/`Writer` helpers,
//! whose `debug_assert`s and `unreachable!` would panic a debug build on a server that
//! answers fewer registers than asked.
//!
//! The servers are written here, on the request codec of [`pdu`], because
//! tokio-modbus's do not fit: (1) its request decoder panics on peer input: FC 15 with
//! a quantity above eight times its byte count indexes past the data
//! (`decode_packed_coils`, in release builds too), and FC 16 and 23 compute
//! `quantity * 2` in `u16`, which overflows for a quantity of 0x8000 or more (a panic
//! in debug builds); (2) a request it cannot decode (a bad coil value, a byte count that does
//! not fit) ends the connection instead of being answered with exception 3; (3) its RTU
//! server takes only a `tokio_serial::SerialStream`, not a pseudo-terminal's or a
//! terminal server's stream, cuts frames by length and CRC alone with no inter-frame
//! timing, drops a request of an unknown function code octet by octet instead of
//! answering exception 1, and stops serving after twenty undecodable octets in a row.
//! What is written: the PDU codec with the specification's limits and exception order,
//! the MBAP deframer, the RTU deframer (length and CRC as octets come, the line pause
//! as the frame boundary, resynchronising on the next silence; a slave's own echo
//! ignored), the frame gap before an answer, the data model with its write events,
//! unit-id handling (0x0B on TCP, silence and broadcast on RTU), and the TCP accept
//! loop. FC 23 is tokio-modbus's in the client and this crate's in the server. The RTU
//! client sends no broadcast (unit 0): tokio-modbus waits for an answer that never
//! comes.
//!
//! # Fuzzing
//!
//! [`fuzz_decode`] runs every decoder and both server connections over arbitrary
//! octets; the cargo-fuzz target `modbus_frame` calls it.
#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]
#![cfg_attr(not(test), deny(clippy::indexing_slicing))]

#[cfg(feature = "tokio")]
pub mod client;
#[cfg(feature = "tokio")]
pub mod io;
pub mod model;
pub mod pdu;
pub mod rtu;
pub mod server;
pub mod tcp;

#[cfg(feature = "tokio")]
pub use client::{Client, ClientConfig, ClientError};
pub use model::{
    AccessError, DataModel, ModelConfig, Table, TableError, Units, Values, WriteEvent,
};
pub use pdu::{Answer, ExceptionCode, FunctionCode, PduError, Request, Response};
pub use rtu::RtuSlave;
#[cfg(feature = "tokio")]
pub use serial_line::io::{OpenError, OpenLine, Transport};
pub use serial_line::{LineSettings, Parity, Refused, Setting};
pub use server::Framing;

/// Runs arbitrary octets through every decoder and both server connections, for
/// fuzzing: nothing may panic, loop forever or grow without bound, and what decodes must
/// encode back to what decodes the same. `start` is the RTU slave's clock at the first
/// octet (the crate reads no clock).
pub fn fuzz_decode(octets: &[u8], start: std::time::Instant) {
    use std::time::Duration;

    use serial_line::LineEndpoint as _;

    // A request PDU as a server decodes it; a valid one round-trips.
    if let Ok(request) = Request::decode(octets) {
        if let Ok(pdu) = request.to_pdu() {
            assert_eq!(Request::decode(&pdu).as_ref(), Ok(&request));
        }
    }
    // The octets as the answer to a few requests; an answer round-trips.
    for request in [
        Request::read(Table::Coils, 0, 10),
        Request::read(Table::HoldingRegisters, 0, 3),
        Request::WriteSingleCoil {
            address: 1,
            value: true,
        },
        Request::WriteMultipleRegisters {
            address: 2,
            values: vec![1, 2],
        },
        Request::ReadWriteMultipleRegisters {
            read_address: 0,
            read_count: 2,
            write_address: 5,
            values: vec![7],
        },
    ] {
        if let Ok(answer) = Answer::decode(&request, octets) {
            let mut pdu = Vec::new();
            answer.encode(request.function(), &mut pdu);
            assert_eq!(Answer::decode(&request, &pdu).as_ref(), Ok(&answer));
        }
    }
    let _ = rtu::decode_frame(octets);

    let model = DataModel::new(ModelConfig {
        units: Units::PerUnit(vec![1, 2]),
        size: 100,
    });
    // A TCP server connection fed the octets in two pieces.
    let (first, second) = octets.split_at(octets.len() / 2);
    let mut connection = tcp::TcpServerConnection::new(model.clone());
    for piece in [first, second] {
        connection.handle_input(piece);
        while connection.poll_transmit().is_some() {}
    }
    // An RTU slave fed 7-octet pieces, a line pause wherever a piece starts with 0xFF.
    let line = rtu::DEFAULT_LINE;
    let mut slave = RtuSlave::new(model, line);
    let mut now = start;
    for piece in octets.chunks(7) {
        now += Duration::from_millis(1);
        if piece.first() == Some(&0xFF) {
            slave.handle_line_pause(now);
        }
        slave.handle_bytes(now, piece);
        now = slave
            .next_deadline()
            .map_or(now, |deadline| deadline.max(now));
        slave.handle_timeout(now);
        while let Some(frame) = slave.poll_transmit(now) {
            assert!(rtu::decode_frame(&frame).is_some());
        }
    }
    slave.handle_line_pause(now);
}
