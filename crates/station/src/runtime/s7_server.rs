//! A node's soft PLC served over S7 (`[node.s7_server]`), as an S7 CPU serves its memory:
//! the thesis's LOGO! boards connect to the S7-1500 concentrators as clients and write
//! their inputs into its markers, read their commands from them (the railway-station
//! thesis, section 3.3); a Stanice node takes the S7-1500's place.
//!
//! ```text
//!  S7 clients --ISO-on-TCP--> s7::io::serve --writes--> Memory (I, Q, M bytes)
//!                                  |  events: connected (TSAP), write, closed
//!                                  v
//!  simulation thread, the node's cycle:
//!    before: each write -> the PLC's image (%MB20 ...)
//!            each connection's status BOOL := no client of its TSAP connected
//!    PLC cycle
//!    after:  each image byte the PLC changed (its program, a command) -> Memory
//! ```
//!
//! The image goes out byte by byte only where the PLC changed it since it last went out
//! or a client's write came in: a byte a client wrote stays as written until the PLC
//! writes it (so a read never sees a client's write undone by a cycle that ran before the
//! write reached the image), and a marker a client once wrote still carries the PLC's
//! next command. Reads see the image as the last cycle left it. The served sizes are the project's (`inputs`, `outputs`,
//! `markers` bytes); data blocks are not served (the soft PLC has none), so a DB item is
//! answered "object does not exist" and the connection goes on.

use std::collections::HashMap;
use std::net::SocketAddr;
use std::sync::{Arc, Mutex};

use plc::task::Leaf;
use plc::vm::Val;
use plc::Plc;
use s7::io::{serve, ServeEvent, SharedMemory};
use s7::{Area, Memory, ServerConfig, ServerEvent};

use super::RuntimeError;
use crate::config::{NodeConfig, S7ServerConfig};

/// Events waiting for the node's next cycle before the server waits too.
const EVENT_BACKLOG: usize = 4096;

/// The areas served, with their image letter.
const AREAS: [(Area, char); 3] = [
    (Area::Inputs, 'I'),
    (Area::Outputs, 'Q'),
    (Area::Markers, 'M'),
];

/// The memory and the event channel of a node's S7 server, made before the simulation
/// thread (which keeps the receiving end) and the server task (the sending end).
pub(crate) struct S7Prepared {
    pub(crate) node: String,
    pub(crate) config: S7ServerConfig,
    pub(crate) memory: SharedMemory,
    pub(crate) sender: tokio::sync::mpsc::Sender<ServeEvent>,
    pub(crate) receiver: tokio::sync::mpsc::Receiver<ServeEvent>,
}

impl S7Prepared {
    pub(crate) fn new(node: &NodeConfig) -> Option<S7Prepared> {
        let config = node.s7_server.clone()?;
        let memory = Arc::new(Mutex::new(Memory::new(
            config.inputs,
            config.outputs,
            config.markers,
        )));
        let (sender, receiver) = tokio::sync::mpsc::channel(EVENT_BACKLOG);
        Some(S7Prepared {
            node: node.name.clone(),
            config,
            memory,
            sender,
            receiver,
        })
    }
}

/// A node's running S7 server.
#[derive(Debug)]
pub struct S7ServerHandle {
    local_addr: SocketAddr,
    task: tokio::task::AbortHandle,
}

impl S7ServerHandle {
    /// The address it listens on.
    pub fn local_addr(&self) -> SocketAddr {
        self.local_addr
    }

    /// Stops it (every connection with it).
    pub fn stop(&self) {
        self.task.abort();
    }
}

/// Binds the server of `node` on `bind:port` and serves its memory.
pub(crate) async fn start(
    node: &str,
    address: SocketAddr,
    config: &S7ServerConfig,
    memory: SharedMemory,
    sender: tokio::sync::mpsc::Sender<ServeEvent>,
) -> Result<S7ServerHandle, RuntimeError> {
    let listener = tokio::net::TcpListener::bind(address)
        .await
        .map_err(|error| {
            RuntimeError::Setup(format!("node `{node}`: S7 server on {address}: {error}"))
        })?;
    let local_addr = listener
        .local_addr()
        .map_err(|error| RuntimeError::Setup(format!("node `{node}`: S7 server: {error}")))?;
    let mut server = ServerConfig::default();
    server.max_pdu_size = config.pdu_size;
    let task = tokio::spawn(serve(listener, memory, server, sender)).abort_handle();
    tracing::info!(node, %local_addr, "S7 server listening");
    Ok(S7ServerHandle { local_addr, task })
}

/// The server's side on the simulation thread, kept by the node.
pub(crate) struct S7Served {
    memory: SharedMemory,
    events: tokio::sync::mpsc::Receiver<ServeEvent>,
    /// The TSAP each connected client called.
    peers: HashMap<SocketAddr, Option<u16>>,
    /// Per area (I, Q, M): each byte as the memory and the image last agreed on it (after
    /// a copy out, or a client's write in); `None` before the first copy.
    agreed: [Vec<Option<u8>>; 3],
    /// Per area: each served byte's image address (`%MB20`), made once.
    addresses: [Vec<String>; 3],
    /// Each connection's TSAP and its status BOOL.
    connections: Vec<(String, u16, Option<Leaf>)>,
}

impl S7Served {
    /// The served side of `prepared` for `plc` (the status variables resolved).
    pub(crate) fn new(
        config: &S7ServerConfig,
        memory: SharedMemory,
        events: tokio::sync::mpsc::Receiver<ServeEvent>,
        plc: &Plc,
    ) -> Result<S7Served, String> {
        Ok(S7Served {
            connections: resolve(config, plc)?,
            memory,
            events,
            peers: HashMap::new(),
            agreed: [
                vec![None; config.inputs],
                vec![None; config.outputs],
                vec![None; config.markers],
            ],
            addresses: [
                byte_addresses('I', config.inputs),
                byte_addresses('Q', config.outputs),
                byte_addresses('M', config.markers),
            ],
        })
    }

    /// The same server for a new program of the node: its status variables resolved in
    /// the new PLC (nothing changes if one is missing).
    pub(crate) fn rebind(&mut self, config: &S7ServerConfig, plc: &Plc) -> Result<(), String> {
        self.connections = resolve(config, plc)?;
        Ok(())
    }

    /// Before the node's cycle: what the clients wrote into the image, and each
    /// connection's status.
    pub(crate) fn before_cycle(&mut self, plc: &mut Plc) {
        while let Ok(ServeEvent { peer, event }) = self.events.try_recv() {
            match event {
                ServerEvent::Connected { called_tsap, .. } => {
                    let tsap = called_tsap.as_ref().and_then(s7::Tsap::as_u16);
                    let known = self.connections.iter().find(|(_, t, _)| Some(*t) == tsap);
                    match known {
                        Some((name, _, _)) => {
                            tracing::info!(%peer, connection = %name, "S7 client connected")
                        }
                        None => tracing::info!(
                            %peer,
                            tsap = ?called_tsap.map(|t| t.to_string()),
                            "S7 client connected on no configured connection"
                        ),
                    }
                    self.peers.insert(peer, tsap);
                }
                ServerEvent::Closed(reason) => {
                    tracing::info!(%peer, %reason, "S7 client gone");
                    self.peers.remove(&peer);
                }
                ServerEvent::Write(write) => self.apply(plc, &write),
                ServerEvent::Negotiated { .. } => {}
            }
        }
        for (_, tsap, status) in &self.connections {
            if let Some(leaf) = status {
                let connected = self.peers.values().any(|t| *t == Some(*tsap));
                plc.write_leaf(leaf, Val::Int(i64::from(!connected)));
            }
        }
    }

    /// A client's write into the image; memory and image agree on its bytes again.
    fn apply(&mut self, plc: &mut Plc, write: &s7::WriteEvent) {
        let Some(index) = AREAS.iter().position(|(area, _)| *area == write.area) else {
            return;
        };
        let Some((_, letter)) = AREAS.get(index) else {
            return;
        };
        let start = usize::try_from(write.start).unwrap_or(usize::MAX);
        match write.bit {
            Some(bit) => {
                let value = write.data.first().copied().unwrap_or(0);
                let _ = plc.set_io(&format!("%{letter}X{start}.{bit}"), i64::from(value != 0));
            }
            None => {
                for (offset, value) in write.data.iter().enumerate() {
                    let _ = plc.set_io(&format!("%{letter}B{}", start + offset), i64::from(*value));
                }
            }
        }
        if let (Some(agreed), Some(addresses)) =
            (self.agreed.get_mut(index), self.addresses.get(index))
        {
            for byte in start..start.saturating_add(write.data.len()) {
                if let (Some(slot), Some(address)) = (agreed.get_mut(byte), addresses.get(byte)) {
                    *slot = plc
                        .get_io(address)
                        .ok()
                        .and_then(|value| u8::try_from(value & 0xFF).ok());
                }
            }
        }
    }

    /// After the node's cycle: the bytes the PLC changed into the served memory.
    pub(crate) fn after_cycle(&mut self, plc: &Plc) {
        let mut memory = self
            .memory
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner());
        for (((area, _), agreed), addresses) in
            AREAS.iter().zip(&mut self.agreed).zip(&self.addresses)
        {
            let Some(bytes) = memory.area_mut(*area) else {
                continue;
            };
            for ((slot, last), address) in bytes.iter_mut().zip(agreed.iter_mut()).zip(addresses) {
                let Some(value) = plc
                    .get_io(address)
                    .ok()
                    .and_then(|value| u8::try_from(value & 0xFF).ok())
                else {
                    continue;
                };
                if *last != Some(value) {
                    *slot = value;
                    *last = Some(value);
                }
            }
        }
    }
}

/// Each connection's name, TSAP and status BOOL in `plc`.
fn resolve(config: &S7ServerConfig, plc: &Plc) -> Result<Vec<(String, u16, Option<Leaf>)>, String> {
    config
        .connections
        .iter()
        .map(|connection| {
            let status = connection
                .status
                .as_deref()
                .map(|path| {
                    plc.leaf(path).map_err(|error| {
                        format!(
                            "S7 connection `{}` status `{path}`: {error}",
                            connection.name
                        )
                    })
                })
                .transpose()?;
            Ok((connection.name.clone(), connection.tsap, status))
        })
        .collect()
}

/// The image addresses of the first `count` bytes of an area (`%MB0`, `%MB1`, ...).
fn byte_addresses(letter: char, count: usize) -> Vec<String> {
    (0..count).map(|byte| format!("%{letter}B{byte}")).collect()
}
