//! The remote sorting lab's balance, a Sartorius 1612MP8 (the sorting-lab thesis,
//! sections 6 and 7), on a serial line at 1200 Bd sending a 15-character record 2-4 times
//! a second; read only (its RxD is not connected; it is zeroed by a relay on its Tare
//! key).
//!
//! - [`record`]: the record's layout, the reference parsing with the platform's checks
//!   (bit 7 masked, resynchronisation on LF, character classes, the point anywhere in
//!   positions 3-10), [`record::Agreement`] of two parses for a window without time
//!   consistency, and the record a simulator sends.
//! - [`reader`]: the sans-IO reader on a serial line: records cut at LF, illegal ones
//!   counted, silence after 2 s without a legal record.
//! - [`simulator`]: the balance with the thesis's measured behaviour (never stable with a
//!   ball, the 3-s and 15-s scatter of table 5.1, stable 5-10 s after the pan empties,
//!   tare only when stable, 30 s of disturbance after the blower, dust).
//! - `io` (feature `tokio`): both over the serial-line crate's transports.
//!
//! ```text
//!  BalanceSimulator --poll_transmit: record every 1/3 s--> line --> BalanceReader
//!        ^ console: ball red 1, remove, blower, tare              | ReaderEvent::Record
//!                                                                 v
//!                                   stanice balance read (JSON lines) / a station device
//! ```

#[cfg(feature = "tokio")]
pub mod io;
pub mod reader;
pub mod record;
pub mod simulator;
