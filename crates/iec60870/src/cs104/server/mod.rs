//! The IEC 104 controlled station (server).
//!
//! A tokio adapter around the transport-free [`outstation`](crate::outstation) core:
//!
//! ```text
//!  accept loop ──(allow-list, admission slots, redundancy group, TLS)──> connection tasks
//!                                                      │ Session (APCI) + LinkCore
//!  ServerHandle::update ──> Outstation: ProcessImage, every group's event buffer
//! ```
//!
//! - `admission`: connection slots per address and per redundancy group.
//! - `connection`: one task per TCP (or TLS) connection, driving the sans-IO APCI
//!   [`Session`](super::session::Session) and the outstation's
//!   [`LinkCore`](crate::outstation::LinkCore) (answers, interrogation, commands and their
//!   sequence, the group's events).
//!
//! The process image, redundancy groups, command checks and the application's hooks are
//! the outstation's, re-exported here: see [`crate::outstation`].
//!
//! Time tags read or stamped by the server (commands' ages, points updated without a
//! time) follow [`OutstationConfig::time_zone`] on the station's clock; the default is UTC on
//! the host's clock.

mod admission;
mod connection;

use std::collections::HashMap;
use std::net::{IpAddr, SocketAddr};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use tokio::net::TcpListener;
use tokio::sync::watch;

use crate::asdu::{AsduParams, Cause, CommonAddress, Element, Ioa, TimeTag};
use crate::cs104::config::ApciConfig;
use crate::outstation::{Outstation, OutstationConfig, OutstationError, Peer};
use crate::time::{Cp56Time2a, TimeZonePolicy};

pub use crate::outstation::{group, handler, image};
pub use crate::outstation::{
    ready, Command, CommandFuture, CommandOutcome, CommandPoint, CommandRefusal, GroupStats,
    ImageError, MonitorPoint, OverflowPolicy, ProcessImage, ReadOnlyStation, RedundancyGroupConfig,
    RedundancyMode, StationHandler, TerminationFuture,
};

/// Configuration of a server: the transport's settings, and the outstation's.
#[derive(Debug, Clone)]
#[non_exhaustive]
pub struct ServerConfig {
    /// Address to listen on (port 2404 by standard).
    pub listen: SocketAddr,
    /// APCI parameters (k, w, t1, t2, t3).
    pub apci: ApciConfig,
    /// Clients allowed to connect; empty allows every client.
    pub allowed_clients: Vec<IpAddr>,
    /// Connections served at once; further clients are refused.
    pub max_connections: usize,
    /// Connections from one client address at once (`None`: no limit of its own).
    pub max_connections_per_address: Option<usize>,
    /// Connections in one redundancy group at once, with groups by address (`None`: no
    /// limit of its own).
    pub max_connections_per_group: Option<usize>,
    /// Slots of [`max_connections`](Self::max_connections) kept for each redundancy
    /// group that names its clients' addresses: other clients never take them.
    pub reserved_per_group: usize,
    /// A connection from a client no redundancy group names is closed when it has not
    /// started data transfer (STARTDT) within this time (`None`: never).
    pub start_timeout: Option<Duration>,
    /// Connections that never started data transfer a redundancy group keeps when the
    /// table (or the group's share of it) is full: beyond them, a newcomer evicts the
    /// longest-idle one. Started connections are never evicted by newcomers.
    pub standbys_per_group: usize,
    /// TLS (IEC 62351-3): when set, every connection must complete a TLS handshake.
    pub tls: Option<Arc<tokio_rustls::rustls::ServerConfig>>,
    /// What the station does whatever its transport: common address, ASDU field sizes
    /// (IEC 104's), redundancy groups and their buffers, command checks, time zone.
    pub outstation: OutstationConfig,
}

impl ServerConfig {
    /// A configuration with the standard's defaults for the given address and station.
    pub fn new(listen: SocketAddr, common_address: CommonAddress) -> Self {
        Self {
            listen,
            apci: ApciConfig::default(),
            allowed_clients: Vec::new(),
            max_connections: 64,
            max_connections_per_address: None,
            max_connections_per_group: None,
            reserved_per_group: 0,
            start_timeout: None,
            standbys_per_group: 2,
            tls: None,
            outstation: OutstationConfig::new(common_address, AsduParams::IEC104),
        }
    }
}

/// Why a server could not start or a request to it failed.
#[derive(Debug, thiserror::Error)]
pub enum ServerError {
    /// The listening socket could not be opened.
    #[error("cannot listen on {address}: {source}")]
    Listen {
        /// The address.
        address: SocketAddr,
        /// The cause.
        source: std::io::Error,
    },
    /// The configuration is inconsistent.
    #[error("invalid server configuration: {0}")]
    Config(String),
    /// A point update did not fit the process image.
    #[error(transparent)]
    Image(#[from] ImageError),
}

impl From<OutstationError> for ServerError {
    fn from(error: OutstationError) -> Self {
        match error {
            OutstationError::Config(why) => ServerError::Config(why),
            OutstationError::Image(error) => ServerError::Image(error),
        }
    }
}

/// Statistics of a running server.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ServerStats {
    /// Connections open now.
    pub connections: usize,
    /// Connections accepted since start.
    pub accepted: u64,
    /// Connections refused (allow-list, cap, no group) since start.
    pub refused: u64,
    /// Per redundancy group.
    pub groups: Vec<GroupStats>,
}

/// State shared by the accept loop, the connections and the handle.
pub(crate) struct Shared {
    pub(crate) config: ServerConfig,
    pub(crate) outstation: Arc<Outstation>,
    next_connection_id: AtomicU64,
    slots: admission::Slots,
    /// Refusals are logged at most once a minute for each kind (a flood must not fill the
    /// log).
    refusal_warnings: Mutex<HashMap<&'static str, crate::cs104::repeated_warning::RepeatedWarning>>,
    accepted: AtomicU64,
    refused: AtomicU64,
}

impl Shared {
    /// Counts and logs (rate-limited) a refused connection.
    fn refuse(&self, peer: SocketAddr, kind: &'static str, why: &str) {
        self.refused.fetch_add(1, Ordering::Relaxed);
        let due = self
            .refusal_warnings
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
            .entry(kind)
            .or_default()
            .due(tokio::time::Instant::now());
        match due {
            Some(repeats) => {
                tracing::warn!(%peer, repeats, "connection refused: {why}")
            }
            None => tracing::debug!(%peer, "connection refused: {why}"),
        }
    }
}

/// The host's time as a CP56Time2a in the given zone. Outside the years the tag can hold
/// (2000..=2099) the tag says 2000-01-01 00:00 with IV set rather than lie.
#[allow(clippy::disallowed_methods)] // the adapter's helper for tools: the host's clock
pub fn time_tag_now(zone: TimeZonePolicy) -> Cp56Time2a {
    zone.to_cp56(chrono::Utc::now())
}

/// A handle to a running server: update points, read statistics, shut down.
/// Cloning is cheap; the server runs until [`ServerHandle::shutdown`] or until every
/// handle is dropped.
#[derive(Clone)]
pub struct ServerHandle {
    shared: Arc<Shared>,
    local_addr: SocketAddr,
    shutdown: Arc<watch::Sender<bool>>,
}

impl std::fmt::Debug for ServerHandle {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ServerHandle")
            .field("local_addr", &self.local_addr)
            .finish_non_exhaustive()
    }
}

/// Starts a server: binds the listening socket and spawns the accept loop on the current
/// tokio runtime.
pub async fn spawn_server(
    config: ServerConfig,
    image: ProcessImage,
    handler: Arc<dyn StationHandler>,
) -> Result<ServerHandle, ServerError> {
    config
        .apci
        .validate()
        .map_err(|error| ServerError::Config(error.to_string()))?;
    let outstation = Arc::new(Outstation::new(config.outstation.clone(), image, handler)?);
    let listener =
        TcpListener::bind(config.listen)
            .await
            .map_err(|source| ServerError::Listen {
                address: config.listen,
                source,
            })?;
    let local_addr = listener
        .local_addr()
        .map_err(|source| ServerError::Listen {
            address: config.listen,
            source,
        })?;
    let (shutdown_tx, shutdown_rx) = watch::channel(false);
    let shared = Arc::new(Shared {
        config,
        outstation,
        next_connection_id: AtomicU64::new(1),
        slots: admission::Slots::default(),
        refusal_warnings: Mutex::new(HashMap::new()),
        accepted: AtomicU64::new(0),
        refused: AtomicU64::new(0),
    });
    tracing::info!(%local_addr, common_address = %shared.config.outstation.common_address, "IEC 104 server listening");
    tokio::spawn(accept_loop(listener, Arc::clone(&shared), shutdown_rx));
    Ok(ServerHandle {
        shared,
        local_addr,
        shutdown: Arc::new(shutdown_tx),
    })
}

async fn accept_loop(
    listener: TcpListener,
    shared: Arc<Shared>,
    mut shutdown: watch::Receiver<bool>,
) {
    let tls = shared
        .config
        .tls
        .clone()
        .map(tokio_rustls::TlsAcceptor::from);
    loop {
        let (stream, peer) = tokio::select! {
            accepted = listener.accept() => match accepted {
                Ok(pair) => pair,
                Err(error) => {
                    // Out of file descriptors and the like: back off instead of spinning.
                    tracing::warn!(%error, "accept failed");
                    tokio::time::sleep(Duration::from_millis(100)).await;
                    continue;
                }
            },
            _ = shutdown.changed() => break,
        };
        let ip = peer.ip().to_canonical();
        let allowed = &shared.config.allowed_clients;
        if !allowed.is_empty() && !allowed.contains(&ip) {
            shared.refuse(peer, "allow-list", "client not in the allow-list");
            continue;
        }
        let slot = match shared.slots.admit(&shared.config, ip) {
            Ok(slot) => slot,
            Err(refusal) => {
                shared.refuse(peer, refusal.kind(), &refusal.to_string());
                continue;
            }
        };
        let id = shared.next_connection_id.fetch_add(1, Ordering::Relaxed);
        if !shared.outstation.takes(&Peer::Tcp(peer)) {
            shared.refuse(peer, "no-group", "no redundancy group takes this client");
            continue;
        }
        let _ = stream.set_nodelay(true);
        shared.accepted.fetch_add(1, Ordering::Relaxed);
        let shared = Arc::clone(&shared);
        let shutdown = shutdown.clone();
        let tls = tls.clone();
        tokio::spawn(async move {
            match tls {
                None => connection::run(shared, id, &slot, peer, stream, shutdown).await,
                Some(acceptor) => {
                    let handshake =
                        tokio::time::timeout(shared.config.apci.t1, acceptor.accept(stream)).await;
                    match handshake {
                        Ok(Ok(stream)) => {
                            connection::run(shared, id, &slot, peer, stream, shutdown).await
                        }
                        Ok(Err(error)) => tracing::warn!(%peer, %error, "TLS handshake failed"),
                        Err(_) => tracing::warn!(%peer, "TLS handshake timed out"),
                    }
                }
            }
            drop(slot);
        });
    }
    tracing::info!("IEC 104 server stopped accepting");
}

impl ServerHandle {
    /// The address the server listens on (useful with port 0).
    pub fn local_addr(&self) -> SocketAddr {
        self.local_addr
    }

    /// Sets a point's value and sends it spontaneously (cause 3) to every redundancy
    /// group. A point whose type carries a time tag and is given none is stamped now.
    pub fn update(
        &self,
        ioa: Ioa,
        element: Element,
        time: Option<Cp56Time2a>,
    ) -> Result<(), ServerError> {
        Ok(self.shared.outstation.update(ioa, element, time)?)
    }

    /// As [`update`](Self::update), with another cause: 1 periodic, 11 return information
    /// after a remote command, 12 after a local command.
    pub fn update_with_cause(
        &self,
        ioa: Ioa,
        element: Element,
        time: Option<Cp56Time2a>,
        cause: Cause,
    ) -> Result<(), ServerError> {
        Ok(self
            .shared
            .outstation
            .update_with_cause(ioa, element, time, cause)?)
    }

    /// Sets a point's value without sending it: interrogation and read will show it.
    pub fn set(
        &self,
        ioa: Ioa,
        element: Element,
        time: Option<TimeTag>,
    ) -> Result<(), ServerError> {
        Ok(self.shared.outstation.set(ioa, element, time)?)
    }

    /// The current value of a monitor point.
    pub fn get(&self, ioa: Ioa) -> Option<MonitorPoint> {
        self.shared.outstation.get(ioa)
    }

    /// The outstation behind the server (shared with other links of the same station).
    pub fn outstation(&self) -> &Arc<Outstation> {
        &self.shared.outstation
    }

    /// Statistics: connections and event buffers.
    pub fn stats(&self) -> ServerStats {
        ServerStats {
            connections: self.shared.slots.open(),
            accepted: self.shared.accepted.load(Ordering::Relaxed),
            refused: self.shared.refused.load(Ordering::Relaxed),
            groups: self.shared.outstation.group_stats(),
        }
    }

    /// Stops accepting and closes every connection.
    pub fn shutdown(&self) {
        let _ = self.shutdown.send(true);
    }
}
