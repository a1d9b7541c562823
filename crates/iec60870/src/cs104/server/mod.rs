//! The IEC 104 controlled station (server).
//!
//! # Shape
//!
//! ```text
//!  accept loop ──(allow-list, connection cap, redundancy group, TLS)──> connection tasks
//!                                                                       │  own a Session
//!  ServerHandle::update ──> ProcessImage (current values) ──> GI / read │  and a socket
//!                      └──> every Group's event buffer ──> the group's started connection
//! ```
//!
//! - [`image`]: the process image, answering interrogation and read.
//! - [`group`]: redundancy groups ([`RedundancyMode`]: one group, a group per
//!   connection, or groups by client address); one started connection per group, one
//!   bounded event buffer per group that keeps events while nobody is started and survives
//!   switch-over.
//! - [`handler`]: the application's hooks (commands, refusals, the station's clock, clock
//!   sync, reset, parameters).
//! - `connection`: one task per TCP (or TLS) connection, driving a sans-IO
//!   [`Session`](super::session::Session) and answering requests.
//!
//! # Commands
//!
//! A command is checked here first (known address, type, double-command state,
//! select-before-operate, the maximum command delay of a time-tagged command measured on
//! [`StationHandler::now`]); what fails gets its negative confirmation and goes to
//! [`StationHandler::command_refused`]. The rest go to
//! [`StationHandler::handle_command`], and the connection keeps the standard's sequence
//! whatever the application does: ACT_CON, then the return information (cause 11) queued
//! since the command arrived, then ACT_TERM after every event queued before the
//! application terminated the command ([`CommandOutcome`]). Each event of a group carries
//! a sequence number for this.
//!
//! Time tags read or stamped by the server (commands' ages, points updated without a
//! time) follow [`ServerConfig::time_zone`] on the station's clock; the default is UTC on
//! the host's clock.

mod admission;
mod connection;
pub mod group;
pub mod handler;
pub mod image;

use std::collections::HashMap;
use std::net::{IpAddr, SocketAddr};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex, RwLock};
use std::time::Duration;

use tokio::net::TcpListener;
use tokio::sync::watch;

use crate::asdu::{
    AsduParams, Cause, CommonAddress, Element, InformationObject, Ioa, TimeTag, TypeId,
};
use crate::cs104::config::ApciConfig;
use crate::time::{Cp56Time2a, TimeZonePolicy};

pub use group::{GroupStats, OverflowPolicy, RedundancyGroupConfig, RedundancyMode};
pub use handler::{
    ready, Command, CommandFuture, CommandOutcome, CommandRefusal, ReadOnlyStation, StationHandler,
    TerminationFuture,
};
pub use image::{CommandPoint, ImageError, MonitorPoint, ProcessImage};

use group::{Group, QueuedEvent};

/// Configuration of a server.
#[derive(Debug, Clone)]
#[non_exhaustive]
pub struct ServerConfig {
    /// Address to listen on (port 2404 by standard).
    pub listen: SocketAddr,
    /// The station's common address.
    pub common_address: CommonAddress,
    /// APCI parameters (k, w, t1, t2, t3).
    pub apci: ApciConfig,
    /// ASDU field sizes (IEC 104: COT 2, CA 2, IOA 3 octets, 249 octets at most).
    pub asdu: AsduParams,
    /// How clients form redundancy groups (one group, a group per connection, or groups
    /// by client address).
    pub redundancy: RedundancyMode,
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
    /// Events each redundancy group buffers.
    pub event_buffer_capacity: usize,
    /// What a full event buffer does.
    pub overflow_policy: OverflowPolicy,
    /// How long a selection (select-before-operate) waits for its execute.
    pub select_timeout: Duration,
    /// The largest age of a time-tagged command (the interoperability list's maximum
    /// command delay), measured on [`StationHandler::now`] with the time tag read in
    /// [`ServerConfig::time_zone`]: an older command, or one further in the future, gets a
    /// negative confirmation. A command point may set its own. `None`: not checked.
    pub max_command_age: Option<Duration>,
    /// Accept commands with cause 5 (request) as activation, as some gateways do
    /// (spec IEC-A3). Off by default: such commands get a negative confirmation with
    /// cause 45.
    pub accept_request_as_activation: bool,
    /// Send an end of initialisation (M_EI_NA_1) to the first started connection.
    pub send_end_of_initialisation: bool,
    /// The zone of every time tag the server reads or stamps itself.
    pub time_zone: TimeZonePolicy,
    /// TLS (IEC 62351-3): when set, every connection must complete a TLS handshake.
    pub tls: Option<Arc<tokio_rustls::rustls::ServerConfig>>,
}

impl ServerConfig {
    /// A configuration with the standard's defaults for the given address and station.
    pub fn new(listen: SocketAddr, common_address: CommonAddress) -> Self {
        Self {
            listen,
            common_address,
            apci: ApciConfig::default(),
            asdu: AsduParams::IEC104,
            redundancy: RedundancyMode::SingleGroup,
            allowed_clients: Vec::new(),
            max_connections: 64,
            max_connections_per_address: None,
            max_connections_per_group: None,
            reserved_per_group: 0,
            start_timeout: None,
            event_buffer_capacity: 100_000,
            overflow_policy: OverflowPolicy::DropOldest,
            select_timeout: Duration::from_secs(10),
            max_command_age: None,
            accept_request_as_activation: false,
            send_end_of_initialisation: true,
            time_zone: TimeZonePolicy::Utc,
            tls: None,
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

/// A selection waiting for its execute.
#[derive(Debug, Clone)]
pub(crate) struct Selection {
    connection: u64,
    originator: u8,
    type_id: TypeId,
    element: Element,
    deadline: tokio::time::Instant,
}

/// State shared by the accept loop, the connections and the handle.
pub(crate) struct Shared {
    pub(crate) config: ServerConfig,
    pub(crate) image: RwLock<ProcessImage>,
    /// The redundancy groups: fixed at start (one group, or the configured groups by
    /// address), or one per open connection.
    pub(crate) groups: RwLock<Vec<Arc<Group>>>,
    /// Whether the end of initialisation still has to go to the first connection's own
    /// group (a group per connection: no group exists at start to queue it in).
    end_of_initialisation_pending: std::sync::atomic::AtomicBool,
    pub(crate) handler: Arc<dyn StationHandler>,
    pub(crate) selections: Mutex<HashMap<u32, Selection>>,
    next_connection_id: AtomicU64,
    slots: admission::Slots,
    /// Refusals are logged at most once a minute for each kind (a flood must not fill the
    /// log).
    refusal_warnings: Mutex<HashMap<&'static str, crate::cs104::repeated_warning::RepeatedWarning>>,
    accepted: AtomicU64,
    refused: AtomicU64,
}

impl Shared {
    pub(crate) fn read_image(&self) -> std::sync::RwLockReadGuard<'_, ProcessImage> {
        self.image
            .read()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    fn write_image(&self) -> std::sync::RwLockWriteGuard<'_, ProcessImage> {
        self.image
            .write()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    pub(crate) fn lock_selections(&self) -> std::sync::MutexGuard<'_, HashMap<u32, Selection>> {
        self.selections
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    fn read_groups(&self) -> std::sync::RwLockReadGuard<'_, Vec<Arc<Group>>> {
        self.groups
            .read()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    fn write_groups(&self) -> std::sync::RwLockWriteGuard<'_, Vec<Arc<Group>>> {
        self.groups
            .write()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    /// The group a new connection belongs to: in a group per connection a new group of
    /// its own; otherwise the first group naming its address, else the first catch-all
    /// group.
    fn group_for(&self, ip: IpAddr, connection: u64) -> Option<Arc<Group>> {
        if self.config.redundancy == RedundancyMode::ConnectionIsGroup {
            let group = Arc::new(Group::new(
                RedundancyGroupConfig::new(format!("connection-{connection}"), vec![ip]),
                self.config.event_buffer_capacity,
                self.config.overflow_policy,
            ));
            if self
                .end_of_initialisation_pending
                .swap(false, Ordering::Relaxed)
            {
                group.push(end_of_initialisation());
            }
            self.write_groups().push(Arc::clone(&group));
            return Some(group);
        }
        let groups = self.read_groups();
        groups
            .iter()
            .find(|group| group.accepts(ip))
            .or_else(|| groups.iter().find(|group| group.is_catch_all()))
            .cloned()
    }

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

    /// Forgets a connection's own group when the connection ends.
    fn release_connection_group(&self, group: &Arc<Group>) {
        if self.config.redundancy == RedundancyMode::ConnectionIsGroup {
            self.write_groups()
                .retain(|other| !Arc::ptr_eq(other, group));
        }
    }

    /// The station's time as a time tag in the server's zone.
    pub(crate) fn now_time_tag(&self) -> Cp56Time2a {
        self.config.time_zone.to_cp56(self.handler.now())
    }
}

/// The host's time as a CP56Time2a in the given zone. Outside the years the tag can hold
/// (2000..=2099) the tag says 2000-01-01 00:00 with IV set rather than lie.
pub fn time_tag_now(zone: TimeZonePolicy) -> Cp56Time2a {
    zone.to_cp56(chrono::Utc::now())
}

/// The end of initialisation (M_EI_NA_1, cause 4) a server sends after its start.
fn end_of_initialisation() -> QueuedEvent {
    QueuedEvent {
        type_id: TypeId::M_EI_NA_1,
        cause: Cause::INITIALISED,
        object: InformationObject {
            ioa: Ioa::default(),
            element: Element::EndOfInitialisation {
                cause: 0,
                after_parameter_change: false,
            },
            time: None,
        },
        seq: 0,
    }
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
    let groups: Vec<Arc<Group>> = match &config.redundancy {
        RedundancyMode::SingleGroup => vec![RedundancyGroupConfig::catch_all("default")],
        RedundancyMode::ConnectionIsGroup => Vec::new(),
        RedundancyMode::GroupsByAddress(groups) if groups.is_empty() => {
            return Err(ServerError::Config(
                "redundancy groups by client address need at least one group".to_owned(),
            ))
        }
        RedundancyMode::GroupsByAddress(groups) => groups.clone(),
    }
    .into_iter()
    .map(|group| {
        Arc::new(Group::new(
            group,
            config.event_buffer_capacity,
            config.overflow_policy,
        ))
    })
    .collect();
    if config.send_end_of_initialisation {
        for group in &groups {
            group.push(end_of_initialisation());
        }
    }
    let end_of_initialisation_pending =
        config.send_end_of_initialisation && config.redundancy == RedundancyMode::ConnectionIsGroup;
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
        image: RwLock::new(image),
        groups: RwLock::new(groups),
        end_of_initialisation_pending: std::sync::atomic::AtomicBool::new(
            end_of_initialisation_pending,
        ),
        handler,
        selections: Mutex::new(HashMap::new()),
        next_connection_id: AtomicU64::new(1),
        slots: admission::Slots::default(),
        refusal_warnings: Mutex::new(HashMap::new()),
        accepted: AtomicU64::new(0),
        refused: AtomicU64::new(0),
    });
    tracing::info!(%local_addr, common_address = %shared.config.common_address, "IEC 104 server listening");
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
        let Some(group) = shared.group_for(ip, id) else {
            shared.refuse(peer, "no-group", "no redundancy group takes this client");
            continue;
        };
        let _ = stream.set_nodelay(true);
        shared.accepted.fetch_add(1, Ordering::Relaxed);
        let shared = Arc::clone(&shared);
        let shutdown = shutdown.clone();
        let tls = tls.clone();
        tokio::spawn(async move {
            match tls {
                None => {
                    let group = Arc::clone(&group);
                    connection::run(
                        Arc::clone(&shared),
                        id,
                        group,
                        &slot,
                        peer,
                        stream,
                        shutdown,
                    )
                    .await
                }
                Some(acceptor) => {
                    let handshake =
                        tokio::time::timeout(shared.config.apci.t1, acceptor.accept(stream)).await;
                    match handshake {
                        Ok(Ok(stream)) => {
                            let group = Arc::clone(&group);
                            connection::run(
                                Arc::clone(&shared),
                                id,
                                group,
                                &slot,
                                peer,
                                stream,
                                shutdown,
                            )
                            .await
                        }
                        Ok(Err(error)) => tracing::warn!(%peer, %error, "TLS handshake failed"),
                        Err(_) => tracing::warn!(%peer, "TLS handshake timed out"),
                    }
                }
            }
            shared.release_connection_group(&group);
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
        self.update_with_cause(ioa, element, time, Cause::SPONTANEOUS)
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
        let type_id = self
            .shared
            .read_image()
            .monitor(ioa)
            .map(|point| point.event_type)
            .ok_or(ImageError::UnknownPoint(ioa))?;
        let time = match type_id.time_tag() {
            crate::asdu::TimeTagKind::Cp56 => Some(TimeTag::Cp56(
                time.unwrap_or_else(|| self.shared.now_time_tag()),
            )),
            crate::asdu::TimeTagKind::Cp24 => {
                let full = time.unwrap_or_else(|| self.shared.now_time_tag());
                Some(TimeTag::Cp24(
                    match crate::time::Cp24Time2a::new(full.minute(), full.millisecond()) {
                        Ok(short) => short.with_invalid(full.is_invalid()),
                        Err(_) => {
                            crate::time::Cp24Time2a::from_naive(chrono::NaiveDateTime::default())
                                .with_invalid(true)
                        }
                    },
                ))
            }
            crate::asdu::TimeTagKind::None => None,
        };
        // Queue while still holding the image's lock: concurrent updates of one point
        // then reach the clients in the order the image took them, so the last event a
        // client gets agrees with what interrogation and read report. (No code path takes
        // the image's lock while holding a group's, so this nesting cannot deadlock.)
        let mut image = self.shared.write_image();
        image.set(ioa, element.clone(), time)?;
        let object = InformationObject { ioa, element, time };
        for group in self.shared.read_groups().iter() {
            group.push(QueuedEvent {
                type_id,
                cause,
                object: object.clone(),
                seq: 0,
            });
        }
        drop(image);
        Ok(())
    }

    /// Sets a point's value without sending it: interrogation and read will show it.
    pub fn set(
        &self,
        ioa: Ioa,
        element: Element,
        time: Option<TimeTag>,
    ) -> Result<(), ServerError> {
        self.shared.write_image().set(ioa, element, time)?;
        Ok(())
    }

    /// The current value of a monitor point.
    pub fn get(&self, ioa: Ioa) -> Option<MonitorPoint> {
        self.shared.read_image().monitor(ioa).cloned()
    }

    /// Statistics: connections and event buffers.
    pub fn stats(&self) -> ServerStats {
        ServerStats {
            connections: self.shared.slots.open(),
            accepted: self.shared.accepted.load(Ordering::Relaxed),
            refused: self.shared.refused.load(Ordering::Relaxed),
            groups: self
                .shared
                .read_groups()
                .iter()
                .map(|group| group.stats())
                .collect(),
        }
    }

    /// Stops accepting and closes every connection.
    pub fn shutdown(&self) {
        let _ = self.shutdown.send(true);
    }
}
