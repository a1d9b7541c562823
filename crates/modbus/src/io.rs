//! The tokio adapters of the servers: a Modbus TCP server taking many connections on one
//! data model, and the RTU slave's drive loop on a serial-line stream.
//!
//! ```text
//! serve_tcp(listener, model): accept -> a task per connection (at most MAX_CONNECTIONS)
//!   read -> TcpServerConnection::handle_input -> poll_transmit -> write
//!   a broken MBAP length -> the connection closes
//! serve_rtu(stream, slave): serial_line::io::drive(stream, RtuSlave)
//! ```
//!
//! The client is [`crate::client::Client`].

use std::io;
use std::ops::ControlFlow;
use std::pin::Pin;
use std::time::Duration;

use serial_line::io::{drive, DriveEnd, LineStream};
use tokio::io::{AsyncRead, AsyncReadExt as _, AsyncWrite, AsyncWriteExt as _};
use tokio::net::TcpListener;
use tokio::sync::mpsc;
use tokio::task::JoinSet;
use tracing::Instrument as _;

use crate::model::DataModel;
use crate::rtu::RtuSlave;
use crate::tcp::TcpServerConnection;

/// Connections a TCP server serves at once; one more is closed as soon as it is
/// accepted.
pub const MAX_CONNECTIONS: usize = 64;

/// Serves `model` to every client that connects to `listener`, each connection a task,
/// until the future is dropped (which ends the connections too) or accepting fails
/// other than for a lack of resources.
pub async fn serve_tcp(listener: TcpListener, model: DataModel) -> io::Result<()> {
    let mut connections = JoinSet::new();
    loop {
        tokio::select! {
            accepted = listener.accept() => {
                let (stream, peer) = match accepted {
                    Ok(accepted) => accepted,
                    Err(error) if is_transient(&error) => {
                        tracing::warn!(%error, "accept failed; retrying");
                        tokio::time::sleep(Duration::from_millis(100)).await;
                        continue;
                    }
                    Err(error) => return Err(error),
                };
                if connections.len() >= MAX_CONNECTIONS {
                    tracing::warn!(%peer, "too many connections; closed");
                    continue;
                }
                let _ = stream.set_nodelay(true);
                let model = model.clone();
                let span = tracing::debug_span!("modbus tcp", %peer);
                connections.spawn(
                    async move {
                        tracing::debug!("connected");
                        match serve_tcp_connection(stream, model).await {
                            Ok(()) => tracing::debug!("closed by the client"),
                            Err(error) => tracing::debug!(%error, "closed"),
                        }
                    }
                    .instrument(span),
                );
            }
            Some(_) = connections.join_next(), if !connections.is_empty() => {}
        }
    }
}

/// Errors of `accept` that concern one connection or a passing lack of descriptors, not
/// the listener.
fn is_transient(error: &io::Error) -> bool {
    matches!(
        error.kind(),
        io::ErrorKind::ConnectionAborted
            | io::ErrorKind::ConnectionReset
            | io::ErrorKind::Interrupted
            | io::ErrorKind::WouldBlock
    ) || error
        .raw_os_error()
        .is_some_and(|code| code == 23 || code == 24)
}

/// Serves `model` on one connection until the client closes it (`Ok`), it fails, or
/// its framing breaks (`InvalidData`).
pub async fn serve_tcp_connection<S: AsyncRead + AsyncWrite + Unpin>(
    mut stream: S,
    model: DataModel,
) -> io::Result<()> {
    let mut connection = TcpServerConnection::new(model);
    let mut buf = vec![0u8; 4096];
    loop {
        let count = stream.read(&mut buf).await?;
        if count == 0 {
            return Ok(());
        }
        connection.handle_input(buf.get(..count).unwrap_or_default());
        while let Some(octets) = connection.poll_transmit() {
            stream.write_all(&octets).await?;
        }
        stream.flush().await?;
        if let Some(error) = connection.error() {
            return Err(io::Error::new(io::ErrorKind::InvalidData, error.clone()));
        }
    }
}

/// Runs `slave` on a serial line's stream until the stream closes or fails (see
/// `serial_line::io::drive`).
pub async fn serve_rtu(
    stream: Pin<Box<dyn LineStream>>,
    slave: &mut RtuSlave,
) -> io::Result<DriveEnd> {
    let (_actions, mut receiver) = mpsc::unbounded_channel();
    drive(stream, slave, &mut receiver, |_| ControlFlow::Continue(())).await
}
