//! Drivers and simulators for field devices on serial lines.
//!
//! # Layout
//!
//! - [`balance`]: the remote sorting lab's Sartorius balance (the sorting-lab
//!   thesis, sections 6-7): the 15-character record, a reader, a simulator with the
//!   thesis's measured scatter.
//! - [`ekm66`]: the Rekoba EKM66 lift controller board's RS-232 protocol
//!   (the lift thesis, docs/THESES.md; docs/LIFT.md), read-only: the lift is never controlled.
//!   - [`ekm66::codec`]: the three queries and the four replies, the FT1.2-style
//!     frame (`68 L L 68 … CS 16`) and a deframer that cuts frames by their length
//!     octet, never by searching for 0x16, resynchronising on the next 0x68. The reply
//!     offsets are a table ([`ekm66::codec::StatusLayout`]: the spec's adopted 20-octet
//!     layout and the alternative 21-octet one), counters are 1, 2 or 4 octets, and the
//!     direction, time (binary or BCD) and year base decoders are configurable
//!     (spec EKM-A2..A8).
//!   - [`ekm66::tables`]: the 53 status codes and 75 fault codes, English and Czech, with
//!     the colour class of each status; the service mode of a status
//!     ([`ekm66::tables::lift_mode`]), the door state it implies
//!     ([`ekm66::tables::door_state`], the one door-state type, also the simulator's) and
//!     the minimum-fault-log group of a fault code ([`ekm66::tables::fault_group`]).
//!   - [`ekm66::figures`]: service figures of a lift and a fleet from the lift's history
//!     (status, position, direction, communication and counter changes, fault records)
//!     over a period, sans-IO and clock-free: time in service, availability, failures,
//!     callbacks, MTBF, MTTR, trips and door cycles per floor, the suggested parking
//!     floor, faults per group.
//!   - [`ekm66::poller`]: the polling state machine of spec §8, sans-IO: octets and
//!     `Instant`s in, query octets and events out. Reply time-out, retries, an error
//!     counter and the communication status; the fault-log synchronisation against an
//!     [`ekm66::poller::ArchiveCursor`] the caller stores, so that neither a restart of
//!     the monitor nor of the board nor the wrap-around of the stack index loses or
//!     repeats a record.
//!   - [`ekm66::simulator`]: the board without a line: a lift with N floors on a virtual
//!     clock (trips, door cycles, the status codes, trip counters), a fault stack of
//!     configurable size with wrap-around, fault injection, a seedable random source.
//!   - `ekm66::io` (feature `tokio`, on by default): the drive loops of the poller and
//!     the simulator over the transports of the serial-line crate (serial ports,
//!     pseudo-terminals, TCP to RS-232 converters).
//!
//! The poller and the simulator are [`serial_line::LineEndpoint`]s, so the serial-line
//! crate's drive loop (the one IEC 101/103 lines run on) runs them unchanged; the line
//! settings and the checksum are that crate's too. No IEC 60870 code is linked in.
//!
//! # Data flow
//!
//! ```text
//! Poller::poll_transmit -> query octets -> line -> Simulator::handle_bytes
//!   -> Deframer -> Query -> Board -> reply octets -> line
//!   -> Poller::handle_bytes -> Deframer -> decode_reply(expected query, CodecConfig)
//!   -> Event::{Status, Counters, Fault, Comm} -> caller (archive, UI, JSON lines)
//!                                 \-> ArchiveCursor (persisted by the caller)
//! ```
//!
//! The cores read no clock: `clippy.toml` bans `Instant::now`, `SystemTime::now` and
//! chrono's `now` in this crate; the adapters use tokio's clock.
#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]
#![cfg_attr(not(test), deny(clippy::indexing_slicing))]

pub mod balance;
pub mod ekm66;
