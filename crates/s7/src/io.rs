//! The tokio adapters: a client handle over one TCP connection, and a server accepting
//! any number of connections on one shared memory image.
//!
//! ```text
//! Client::connect(addr, config, timeout)
//!   TCP connect -> spawned driver task owning the socket and a ClientConnection
//!   Client (Clone) --mpsc(command + oneshot)--> driver --bytes--> PLC
//!   driver: read socket -> handle_input -> transmits to the socket, events to the
//!           oneshots of the waiting calls; all handles dropped -> socket closed
//!
//! serve(listener, memory, config, events)
//!   accept -> one task per connection: read -> lock memory -> handle_input -> unlock
//!          -> transmits to the socket, events (peer attached) to the channel
//!   a bad frame closes that connection only; the others go on
//! ```

use std::collections::BTreeMap;
use std::net::SocketAddr;
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::Duration;

use thiserror::Error;
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::{TcpListener, TcpStream, ToSocketAddrs};
use tokio::sync::{mpsc, oneshot};
use tokio::task::JoinSet;
use tracing::Instrument;

use crate::address::{Address, AddressErrorKind, Region};
use crate::client::{
    ClientConfig, ClientConnection, ClientEvent, ItemError, OperationId, ReadResult, WriteResult,
};
use crate::link::ConnectionError;
use crate::memory::Memory;
use crate::server::{ServerConfig, ServerConnection, ServerEvent};
use crate::split::{RequestError, WriteItem};
use crate::value::Value;

/// The ISO-on-TCP port.
pub const ISO_TCP_PORT: u16 = 102;

/// Memory shared by a server's connections; each locks it only while it handles what it
/// received, never across an await.
pub type SharedMemory = Arc<Mutex<Memory>>;

/// Why a client call failed as a whole.
#[derive(Debug, Clone, Error)]
pub enum ClientError {
    /// The socket failed (connect, read or write).
    #[error("S7 connection: {0}")]
    Io(Arc<std::io::Error>),
    /// No answer within the timeout.
    #[error("S7 connection: no answer within {0:?}")]
    Timeout(Duration),
    /// The connection ended, for this reason.
    #[error("S7 connection closed: {0}")]
    Closed(ConnectionError),
    /// The request cannot be sent.
    #[error(transparent)]
    Request(#[from] RequestError),
    /// A value that does not fit its address.
    #[error("item {item}: {error}")]
    Value {
        /// The item's index.
        item: usize,
        /// What does not fit.
        error: AddressErrorKind,
    },
}

impl From<std::io::Error> for ClientError {
    fn from(error: std::io::Error) -> Self {
        ClientError::Io(Arc::new(error))
    }
}

/// What the connection is, once connected.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Negotiated {
    /// The PDU size in force.
    pub pdu_size: u16,
    /// Jobs open at once.
    pub max_jobs: u16,
}

enum Command {
    Read {
        regions: Vec<Region>,
        reply: oneshot::Sender<Result<Vec<ReadResult>, ClientError>>,
    },
    Write {
        items: Vec<WriteItem>,
        reply: oneshot::Sender<Result<Vec<WriteResult>, ClientError>>,
    },
}

enum Waiting {
    Read(oneshot::Sender<Result<Vec<ReadResult>, ClientError>>),
    Write(oneshot::Sender<Result<Vec<WriteResult>, ClientError>>),
}

/// A connection to a PLC. Clones share the connection; it closes when the last is
/// dropped.
#[derive(Debug, Clone)]
pub struct Client {
    commands: mpsc::Sender<Command>,
    negotiated: Negotiated,
    timeout: Duration,
}

impl Client {
    /// Connects to `addr` (port 102 for a PLC): TCP, COTP connection with the config's
    /// TSAPs, setup communication. `timeout` bounds the whole connect and, later, each
    /// read and write.
    pub async fn connect(
        addr: impl ToSocketAddrs,
        config: ClientConfig,
        timeout: Duration,
    ) -> Result<Client, ClientError> {
        let connecting = async {
            let stream = TcpStream::connect(addr).await?;
            stream.set_nodelay(true)?;
            let peer = stream.peer_addr()?;
            let (commands, command_receiver) = mpsc::channel(16);
            let (connected, connected_receiver) = oneshot::channel();
            let span = tracing::info_span!("s7 client", %peer);
            tokio::spawn(
                drive_client(
                    stream,
                    ClientConnection::new(config),
                    command_receiver,
                    connected,
                )
                .instrument(span),
            );
            let negotiated = connected_receiver
                .await
                .map_err(|_| ClientError::Closed(ConnectionError::PeerClosed))??;
            Ok::<_, ClientError>(Client {
                commands,
                negotiated,
                timeout,
            })
        };
        // On timeout the future is dropped with the command sender, which ends the
        // driver and closes the socket.
        tokio::time::timeout(timeout, connecting)
            .await
            .map_err(|_| ClientError::Timeout(timeout))?
    }

    /// The PDU size and parallel jobs in force.
    pub fn negotiated(&self) -> Negotiated {
        self.negotiated
    }

    /// Reads regions: one result per region, in order, with the bytes (one byte, 0 or
    /// 1, for a bit). Split into as many jobs as the PDU size needs.
    pub async fn read(&self, regions: Vec<Region>) -> Result<Vec<ReadResult>, ClientError> {
        let (reply, answer) = oneshot::channel();
        self.call(Command::Read { regions, reply }, answer).await
    }

    /// Writes items: one result per item, in order. A bit is written alone.
    pub async fn write(&self, items: Vec<WriteItem>) -> Result<Vec<WriteResult>, ClientError> {
        let (reply, answer) = oneshot::channel();
        self.call(Command::Write { items, reply }, answer).await
    }

    /// Reads addresses as typed values.
    pub async fn read_values(
        &self,
        addresses: &[Address],
    ) -> Result<Vec<Result<Value, ItemError>>, ClientError> {
        let results = self
            .read(addresses.iter().map(Address::region).collect())
            .await?;
        Ok(addresses
            .iter()
            .zip(results)
            .map(|(address, result)| {
                let bytes = result?;
                address.decode(&bytes).map_err(|_| ItemError::Length {
                    expected: address.value_type().size(),
                    got: bytes.len(),
                })
            })
            .collect())
    }

    /// Writes typed values, each of its address's size.
    pub async fn write_values(
        &self,
        items: &[(Address, Value)],
    ) -> Result<Vec<WriteResult>, ClientError> {
        let items = items
            .iter()
            .enumerate()
            .map(|(index, (address, value))| {
                Ok(WriteItem {
                    region: address.region(),
                    data: address
                        .encode(value)
                        .map_err(|error| ClientError::Value { item: index, error })?,
                })
            })
            .collect::<Result<Vec<_>, ClientError>>()?;
        self.write(items).await
    }

    async fn call<T>(
        &self,
        command: Command,
        answer: oneshot::Receiver<Result<T, ClientError>>,
    ) -> Result<T, ClientError> {
        let closed = || ClientError::Closed(ConnectionError::PeerClosed);
        let exchange = async {
            self.commands.send(command).await.map_err(|_| closed())?;
            answer.await.map_err(|_| closed())?
        };
        tokio::time::timeout(self.timeout, exchange)
            .await
            .map_err(|_| ClientError::Timeout(self.timeout))?
    }
}

/// The client's driver loop: one task per connection.
async fn drive_client(
    mut stream: TcpStream,
    mut connection: ClientConnection,
    mut commands: mpsc::Receiver<Command>,
    connected: oneshot::Sender<Result<Negotiated, ClientError>>,
) {
    let mut connected = Some(connected);
    let mut waiting: BTreeMap<OperationId, Waiting> = BTreeMap::new();
    let mut frame = Vec::new();
    let mut buffer = vec![0u8; 4096];
    let failure = 'drive: loop {
        while connection.poll_transmit(&mut frame) {
            if let Err(error) = stream.write_all(&frame).await {
                break 'drive ClientError::from(error);
            }
        }
        let mut closed = None;
        while let Some(event) = connection.poll_event() {
            match event {
                ClientEvent::Connected { pdu_size, max_jobs } => {
                    tracing::debug!(pdu_size, max_jobs, "connected");
                    if let Some(connected) = connected.take() {
                        let _ = connected.send(Ok(Negotiated { pdu_size, max_jobs }));
                    }
                }
                ClientEvent::ReadDone { id, results } => {
                    if let Some(Waiting::Read(reply)) = waiting.remove(&id) {
                        let _ = reply.send(Ok(results));
                    }
                }
                ClientEvent::WriteDone { id, results } => {
                    if let Some(Waiting::Write(reply)) = waiting.remove(&id) {
                        let _ = reply.send(Ok(results));
                    }
                }
                ClientEvent::Closed(error) => closed = Some(ClientError::Closed(error)),
            }
        }
        if let Some(error) = closed {
            break error;
        }
        tokio::select! {
            received = stream.read(&mut buffer) => match received {
                Ok(0) => connection.handle_eof(),
                Ok(len) => connection.handle_input(buffer.get(..len).unwrap_or_default()),
                Err(error) => break ClientError::from(error),
            },
            command = commands.recv() => match command {
                // Every handle is gone: nobody can ask anything any more.
                None => return,
                Some(Command::Read { regions, reply }) => match connection.read(regions) {
                    Ok(id) => {
                        waiting.insert(id, Waiting::Read(reply));
                    }
                    Err(error) => {
                        let _ = reply.send(Err(error.into()));
                    }
                },
                Some(Command::Write { items, reply }) => match connection.write(items) {
                    Ok(id) => {
                        waiting.insert(id, Waiting::Write(reply));
                    }
                    Err(error) => {
                        let _ = reply.send(Err(error.into()));
                    }
                },
            },
        }
    };
    tracing::debug!(error = %failure, "connection ended");
    if let Some(connected) = connected {
        let _ = connected.send(Err(failure.clone()));
    }
    for (_, waiter) in waiting {
        match waiter {
            Waiting::Read(reply) => {
                let _ = reply.send(Err(failure.clone()));
            }
            Waiting::Write(reply) => {
                let _ = reply.send(Err(failure.clone()));
            }
        }
    }
    // Calls still queued, or made later, find the channel closed.
    commands.close();
    while let Ok(command) = commands.try_recv() {
        match command {
            Command::Read { reply, .. } => {
                let _ = reply.send(Err(failure.clone()));
            }
            Command::Write { reply, .. } => {
                let _ = reply.send(Err(failure.clone()));
            }
        }
    }
}

/// A server event with the client it concerns.
#[derive(Debug, Clone, PartialEq)]
pub struct ServeEvent {
    /// The client's address.
    pub peer: SocketAddr,
    /// What happened.
    pub event: ServerEvent,
}

/// Serves S7 clients on `listener` from `memory`, each connection in its own task, until
/// the returned future is dropped (which ends every connection with it). Events go to
/// `events`, the client's address attached; keep receiving them, or a full channel
/// holds the connections up (a dropped receiver is fine: events are then discarded).
pub async fn serve(
    listener: TcpListener,
    memory: SharedMemory,
    config: ServerConfig,
    events: mpsc::Sender<ServeEvent>,
) {
    let mut connections = JoinSet::new();
    loop {
        tokio::select! {
            accepted = listener.accept() => match accepted {
                Ok((stream, peer)) => {
                    let span = tracing::info_span!("s7 server connection", %peer);
                    connections.spawn(
                        serve_connection(
                            stream,
                            peer,
                            Arc::clone(&memory),
                            ServerConnection::new(config.clone()),
                            events.clone(),
                        )
                        .instrument(span),
                    );
                }
                Err(error) => {
                    // Mostly out of file descriptors: wait for connections to end rather
                    // than spin.
                    tracing::warn!(%error, "accept failed");
                    tokio::time::sleep(Duration::from_millis(100)).await;
                }
            },
            Some(_) = connections.join_next(), if !connections.is_empty() => {}
        }
    }
}

fn lock(memory: &SharedMemory) -> MutexGuard<'_, Memory> {
    // A connection task that panicked mid-write leaves bytes a client could have
    // written anyway: the image stays usable.
    memory
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner())
}

async fn serve_connection(
    mut stream: TcpStream,
    peer: SocketAddr,
    memory: SharedMemory,
    mut connection: ServerConnection,
    events: mpsc::Sender<ServeEvent>,
) {
    let _ = stream.set_nodelay(true);
    tracing::debug!("accepted");
    let mut frame = Vec::new();
    let mut buffer = vec![0u8; 4096];
    loop {
        while connection.poll_transmit(&mut frame) {
            if let Err(error) = stream.write_all(&frame).await {
                tracing::debug!(%error, "write failed");
                connection.handle_eof();
                break;
            }
        }
        while let Some(event) = connection.poll_event() {
            if let ServerEvent::Closed(error) = &event {
                match error {
                    ConnectionError::PeerClosed | ConnectionError::Disconnected { .. } => {
                        tracing::debug!(%error, "closed");
                    }
                    other => tracing::warn!(error = %other, "closing the connection"),
                }
            }
            // A dropped receiver only means nobody listens.
            let _ = events.send(ServeEvent { peer, event }).await;
        }
        if connection.is_closed() {
            let _ = stream.shutdown().await;
            return;
        }
        match stream.read(&mut buffer).await {
            Ok(0) => connection.handle_eof(),
            Ok(len) => {
                let received = buffer.get(..len).unwrap_or_default();
                let mut memory = lock(&memory);
                connection.handle_input(received, &mut memory);
            }
            Err(error) => {
                tracing::debug!(%error, "read failed");
                connection.handle_eof();
            }
        }
    }
}
