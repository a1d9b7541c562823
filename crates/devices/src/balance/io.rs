//! The tokio drive loops of the balance's reader and simulator (feature `tokio`), over
//! the serial-line crate's transports: the loop of [`drive`] with the events handed to
//! the caller.

use std::io;
use std::ops::ControlFlow;
use std::pin::Pin;

use tokio::sync::mpsc;

pub use serial_line::io::{drive, DriveEnd, EndpointAction, LineStream, OpenError, Transport};

use super::reader::{BalanceReader, ReaderEvent};
use super::simulator::{BalanceEvent, BalanceSimulator};

/// Reads a balance on `stream` until `on_event` breaks, the stream closes or fails.
pub async fn run_reader(
    stream: Pin<Box<dyn LineStream>>,
    reader: &mut BalanceReader,
    mut on_event: impl FnMut(ReaderEvent) -> ControlFlow<()>,
) -> io::Result<DriveEnd> {
    let mut no_actions = mpsc::unbounded_channel().1;
    drive(stream, reader, &mut no_actions, |reader| {
        while let Some(event) = reader.poll_event() {
            on_event(event)?;
        }
        ControlFlow::Continue(())
    })
    .await
}

/// Runs a simulated balance on `stream`; `actions` (console operations) reach it
/// between two records.
pub async fn run_simulator(
    stream: Pin<Box<dyn LineStream>>,
    balance: &mut BalanceSimulator,
    actions: &mut mpsc::UnboundedReceiver<EndpointAction<BalanceSimulator>>,
    mut on_event: impl FnMut(BalanceEvent) -> ControlFlow<()>,
) -> io::Result<DriveEnd> {
    drive(stream, balance, actions, |balance| {
        while let Some(event) = balance.poll_event() {
            on_event(event)?;
        }
        ControlFlow::Continue(())
    })
    .await
}
