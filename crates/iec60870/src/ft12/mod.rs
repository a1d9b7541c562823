//! The FT1.2 link layer of IEC 60870-5-101 and -103 (IEC 60870-5-1/-2), sans-IO.
//!
//! # Layout
//!
//! | Module | Content |
//! |---|---|
//! | `frame` | [`Frame`] (fixed `10 C A CS 16`, variable `68 L L 68 C A ASDU CS 16`, single character `E5`), the [`Control`] field with its function codes, [`AddressSize`] |
//! | `deframer` | [`Deframer`]: frames out of a serial byte stream, resynchronising after noise and broken frames |
//! | `primary` | [`Primary`]: the unbalanced master of one line and many secondaries (start-up, FCB, class 1/2 polling, ACD, DFC, repeats, broadcast, failed stations) |
//! | `balanced` | [`Balanced`]: one end of a balanced point-to-point link (IEC 101): primary and secondary at once, direction bit, test of link when idle |
//! | `secondary` | [`Secondary`]: the unbalanced slave (repeat detection by FCB, ACD/DFC from its [`SecondaryApplication`]) |
//! | `endpoint` | the primary as a [`LineEndpoint`] (either end of a line as an adapter drives it: bytes and time in, bytes out); [`SecondaryStation`] = secondary + application, answering after the idle time; [`SharedLine`] |
//! | `simulated` | [`SimulatedLine`]: a primary and secondaries on a virtual clock with the line's timing and injected faults, for tests and benchmarks |
//!
//! The line itself is the `serial_line` crate's, re-exported here: [`LineSettings`] (baud
//! rate and character format, 8E1 for FT1.2, transmit and idle (33 bit) times),
//! [`Parity`], the [`LineEndpoint`] trait, the FT1.2 [`checksum`] (its `octet_sum`), and
//! as [`io`] (feature `tokio`) its transports (serial ports, pseudo-terminals, TCP as
//! [`io::Transport`]) and [`io::drive`], the loop around an endpoint.
//!
//! # Data flow
//!
//! ```text
//! serial/pty/TCP bytes -> Primary::handle_bytes -> Deframer -> answer to the request
//!     -> PrimaryEvent::Exchange { answer: UserData(asdu) } -> application (103 master)
//! application -> Primary::send / broadcast / request -> Primary::poll_transmit -> bytes
//! clock -> Primary::handle_timeout at Primary::next_deadline -> repeat or failed
//!
//! bytes -> Deframer -> Secondary::handle(frame, application) -> answer frame -> bytes
//! ```
//!
//! Nothing but [`io`] reads a clock or a port: the same cores run under the tokio loop
//! of [`io::drive`], under [`SimulatedLine`], the fuzzers and the scenario tests.
//!
//! # Timing
//!
//! The primary times its frames as the line would: a request occupies
//! [`LineSettings::transmit_time`], the answer is awaited for
//! [`PrimaryConfig::response_timeout`] after that, and 33 bit times of quiet
//! ([`LineSettings::idle_time`]) separate frames and follow every error.

mod balanced;
mod deframer;
mod endpoint;
mod frame;
mod primary;
mod secondary;
mod simulated;

pub use balanced::{Balanced, BalancedConfig, BalancedEvent};
pub use deframer::{DeframeError, Deframer};
pub use endpoint::{SecondaryStation, SharedLine, TimedApplication};
pub use frame::{
    checksum, AddressSize, Control, EncodeError, Frame, PrimaryFunction, SecondaryFunction, END,
    MAX_FRAME_LEN, MAX_LENGTH_FIELD, SINGLE_CHARACTER, START_FIXED, START_VARIABLE,
};
pub use primary::{
    Answer, LineError, LinkState, Primary, PrimaryConfig, PrimaryError, PrimaryEvent, StationStats,
};
pub use secondary::{Secondary, SecondaryApplication, SecondaryConfig, SecondaryStats};
pub use serial_line::{LineEndpoint, LineSettings, Parity};
pub use simulated::{Fault, SimulatedLine};

/// The transports and the drive loop of the serial-line crate (`serial_line::io`), where
/// the FT1.2 driver's callers have found them.
#[cfg(feature = "tokio")]
pub mod io {
    pub use serial_line::io::*;
}
