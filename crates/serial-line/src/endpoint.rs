//! One end of a line as an adapter sees it: bytes and time in, bytes out.

use std::task::{Context, Poll};
use std::time::Instant;

use crate::settings::LineSettings;

/// A sans-IO endpoint of a serial line (a protocol's master or slave, a device or its
/// simulator), driven by an adapter: `io::drive` (feature `tokio`) over a serial port, a
/// pseudo-terminal or TCP; a simulated line on a virtual clock; a fuzzer.
///
/// After each `handle_*` call the adapter drains [`LineEndpoint::poll_transmit`] and
/// asks [`LineEndpoint::next_deadline`] again.
pub trait LineEndpoint {
    /// Octets received.
    fn handle_bytes(&mut self, now: Instant, bytes: &[u8]);
    /// The line has been quiet for longer than a frame may pause.
    fn handle_line_pause(&mut self, now: Instant);
    /// The clock reached [`LineEndpoint::next_deadline`].
    fn handle_timeout(&mut self, now: Instant);
    /// Octets to write now.
    fn poll_transmit(&mut self, now: Instant) -> Option<Vec<u8>>;
    /// When to call [`LineEndpoint::handle_timeout`] and [`LineEndpoint::poll_transmit`]
    /// again without new octets.
    fn next_deadline(&self) -> Option<Instant>;
    /// The line's settings, for the pause detection of the adapter.
    fn line(&self) -> LineSettings;
    /// Ready when something outside the line wants the endpoint's attention (an
    /// application's event, a command's outcome); the adapter then runs another turn.
    /// Registers the context's waker otherwise. Never ready by default.
    fn poll_wake(&mut self, _context: &mut Context<'_>) -> Poll<()> {
        Poll::Pending
    }
}
