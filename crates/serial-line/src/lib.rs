//! Serial lines without a protocol: where a field device's octets come from and go to,
//! how long they take on the line, and the loop that runs a protocol's endpoint on them.
//!
//! The protocols live elsewhere and use this crate: the FT1.2 link layer of IEC
//! 60870-5-101/-103 (`iec60870::ft12`), the Rekoba EKM66 lift board (`devices::ekm66`);
//! Modbus RTU and other serial devices are meant to be the next. Nothing here knows a
//! frame.
//!
//! # Layout
//!
//! | Module | Content |
//! |---|---|
//! | `settings` | [`LineSettings`] (speed, [`Parity`], stop bits; always 8 data bits) with the times they imply (a character, `n` octets, the 33-bit idle time), [`SettingsError`], [`ParityError`]; [`Refused`], a setting a port kept at another value than asked |
//! | `endpoint` | [`LineEndpoint`]: a protocol's end of a line, sans-IO: octets and `Instant`s in, octets out, the next deadline |
//! | `sum` | [`octet_sum`]: the arithmetic sum modulo 256 that FT1.2 and devices framed like it check |
//! | [`io`] (feature `tokio`) | [`io::Transport`] (a serial port, a new pseudo-terminal pair, a TCP connection, a TCP listener) opened as an [`io::OpenLine`] over a [`io::LineStream`], or an [`io::OpenError`] naming what failed; [`io::drive`], the loop around an endpoint |
//!
//! # Data flow
//!
//! ```text
//! Transport::open -> serial port: settings applied, read back, a refused one an error
//!                 -> OpenLine { stream, pty_path, peer }
//!
//! drive(stream, endpoint, actions, observe), one turn:
//!   clock             -> LineEndpoint::handle_timeout(now)
//!   observe(&mut E)   -> the caller takes the endpoint's events (or stops the loop)
//!   poll_transmit(now) -> octets -> stream
//!   then it sleeps until the first of:
//!     octets read         -> handle_bytes(now, octets)
//!     4 characters quiet  -> handle_line_pause(now)   (a frame may not pause inside)
//!     next_deadline()     -> the next turn
//!     an action (mpsc)    -> FnOnce(&mut E): a command from outside the loop
//!     poll_wake ready     -> the next turn: an application has news
//! ```
//!
//! The endpoint never reads a clock or a port: the same endpoint runs under [`io::drive`],
//! under a simulated line on a virtual clock, and under a fuzzer.
//!
//! # Why this is written here and not taken from a crate
//!
//! The ports themselves are `tokio-serial`'s (`serialport` underneath, termios on Unix).
//! What is written here is what no serial crate does: checking that the port kept the
//! settings (termios takes what a driver cannot do without a word: a pseudo-terminal drops
//! parity), opening the four transports behind one stream type, and the drive loop with
//! the line-pause detection a framed serial protocol needs, some sixty lines over tokio.
#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]
#![cfg_attr(not(test), deny(clippy::indexing_slicing))]

mod endpoint;
#[cfg(feature = "tokio")]
pub mod io;
mod settings;
mod sum;

pub use endpoint::LineEndpoint;
pub use settings::{LineSettings, Parity, ParityError, Refused, Setting, SettingsError};
pub use sum::octet_sum;
