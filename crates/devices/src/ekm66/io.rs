//! The tokio drive loops of the poller and the simulator (feature `tokio`).
//!
//! The transports are the serial-line crate's: a serial port ([`Transport::Serial`],
//! 9600 8E1 by default, every setting of [`serial_line::LineSettings`], a setting the
//! port does not keep an error), a new pseudo-terminal pair ([`Transport::Pty`]),
//! a TCP connection to an RS-232-to-Ethernet converter ([`Transport::Connect`]) or a
//! listener ([`Transport::Listen`]). [`run_poller`] and [`run_simulator`] are the loop
//! of [`drive`] with the events handed to the caller: feed octets, drain transmits,
//! sleep until the next deadline, repeat.

use std::io;
use std::ops::ControlFlow;
use std::pin::Pin;

use tokio::sync::mpsc;

pub use serial_line::io::{
    drive, DriveEnd, EndpointAction, LineListener, LineStream, OpenError, OpenLine, Transport,
};

use super::poller::{ArchiveCursor, Event, Poller};
use super::simulator::{SimEvent, Simulator};

/// Runs a poller on a stream until `on_event` breaks, the stream closes or fails.
/// `on_event` sees each event with the cursor as it stands after it (store it after an
/// [`Event::Fault`]). `actions` reach the poller between two wake-ups.
pub async fn run_poller(
    stream: Pin<Box<dyn LineStream>>,
    poller: &mut Poller,
    actions: &mut mpsc::UnboundedReceiver<EndpointAction<Poller>>,
    mut on_event: impl FnMut(Event, &ArchiveCursor) -> ControlFlow<()>,
) -> io::Result<DriveEnd> {
    drive(stream, poller, actions, |poller| {
        while let Some(event) = poller.poll_event() {
            on_event(event, poller.cursor())?;
        }
        ControlFlow::Continue(())
    })
    .await
}

/// Runs a simulator on a stream until `on_event` breaks, the stream closes or fails.
/// Console operations come through `actions`.
pub async fn run_simulator(
    stream: Pin<Box<dyn LineStream>>,
    simulator: &mut Simulator,
    actions: &mut mpsc::UnboundedReceiver<EndpointAction<Simulator>>,
    mut on_event: impl FnMut(SimEvent) -> ControlFlow<()>,
) -> io::Result<DriveEnd> {
    drive(stream, simulator, actions, |simulator| {
        while let Some(event) = simulator.poll_event() {
            on_event(event)?;
        }
        ControlFlow::Continue(())
    })
    .await
}
