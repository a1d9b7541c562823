//! The station runtime: runs the nodes of a project.
//!
//! ```text
//!              simulation thread (clock, plant, PLCs)          tokio tasks
//!  plant ──inputs──> PLC of node N ──points──> NodePoints N ──> IEC 104 server N ──> upper node / dispatch
//!    ^                   ^    │                  ^   │ store records ──> Recorder ──> EventStore
//!    └──── outputs ──────┘    └ commands <── NodeHandler N <──── commands from above
//!                                                ^   └──── forwarded commands ──> link client ──> lower node
//!                                  link task ────┘ (values of the lower node, IV on loss, status point)
//! ```
//!
//! - [`clock`]: simulated time ([`SimClock`]) and each node's own clock, set by clock
//!   synchronisation ([`NodeClock`]).
//! - [`simulation`]: the thread that owns the plant and every node's soft PLC, steps
//!   them on the simulated clock and feeds PLC-sourced points.
//! - [`node`]: a node's point database with its sinks and recorder ([`NodePoints`]).
//! - [`sink`]: where a node's changes go upward (its IEC 104 server; an IEC 101 slave or MQTT later).
//! - [`link`]: the IEC 104 client links to lower nodes (concentration, invalidation,
//!   status points, time source).
//! - [`line`]: the serial lines to protection devices (IEC 103 master, the gateway role:
//!   their signals become points, commands become general commands).
//! - [`lift`]: the lifts watched through their EKM66 boards (lift monitoring: their
//!   values become points, their fault logs go into the store's archive).
//! - [`notification`]: e-mail and webhook notices of what the lifts report, each delivery
//!   recorded.
//! - `command`: the server hooks — commands routed to a PLC variable (refused in local
//!   mode) or down a link, each audited; clock synchronisation passed down.
//!
//! [`Runtime::start`] brings a project (or some of its nodes) up: store, point databases,
//! PLCs (compiled on the simulation thread, errors with file:line:col), one server per
//! node (its image holds the values of the first PLC scan), then the links, then the
//! clock starts.

pub mod clock;
mod command;
pub mod field;
mod forwarded;
pub mod lift;
pub mod line;
pub mod link;
pub mod node;
pub mod notification;
pub mod operation;
pub mod simulation;
pub mod sink;

use std::collections::HashMap;
use std::sync::{mpsc, Arc};
use std::time::Duration;

use chrono::{DateTime, Utc};
use iec60870::cs104::server::{
    spawn_server, CommandPoint, ServerConfig, ServerError, ServerHandle,
};
use tokio::sync::oneshot;

use crate::config::{CommandTarget, NodeConfig, PointSource, Project};
use crate::device::DeviceKinds;
use crate::store::{
    open_store, spawn_retention, EventStore, Retention, RetentionHandle, StoreError,
};
use iec60870::time::TimeZonePolicy;
use points::{LineSignal, PointDb, PointSpec};

pub use crate::store::Recorder;
pub use clock::{NodeClock, Pacing, SimClock};
pub use link::LinkHandle;
pub use node::NodePoints;
pub use simulation::{CommandRefusal, OutputChange, Simulation};
pub use sink::{Iec104Sink, PointSink};

use command::{NodeHandler, Route, RoutedCommand};
use link::LinkSpec;
pub use operation::{Operation, OperationError};
use simulation::SimRequest;

/// Why the runtime could not start or a request failed.
#[derive(Debug, thiserror::Error)]
pub enum RuntimeError {
    /// The project does not fit together at run time (unknown node or plant signal, a
    /// variable the PLC does not have, ...).
    #[error("{0}")]
    Setup(String),
    /// A node's Structured Text does not compile; the diagnostics as `file:line:col`.
    #[error("{0}")]
    Plc(String),
    /// The event store could not be opened.
    #[error("event store: {0}")]
    Store(#[from] StoreError),
    /// A server could not start (TLS files, an address that cannot be bound). Its cause is
    /// in the message, not chained as a source: printed with its chain, it read twice.
    #[error("node `{node}`: {error}")]
    Server {
        /// The node.
        node: String,
        /// Why.
        error: ServerError,
    },
    /// A server's port is held by another program (another station, an example already
    /// running): the caller can say how to move the project's ports.
    #[error("node `{node}` cannot listen on {address}: the port is in use")]
    PortInUse {
        /// The node.
        node: String,
        /// The address it was to listen on.
        address: std::net::SocketAddr,
    },
    /// The simulation thread has ended.
    #[error("the simulation has stopped")]
    Stopped,
}

/// Where events go.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub enum StoreChoice {
    /// The project's `store` setting (a relative SQLite path resolves in the project folder).
    #[default]
    Project,
    /// This URL instead.
    Url(String),
    /// No store: events and commands are not recorded.
    Disabled,
}

/// How a node's server shares its connection slots (64 in all).
#[derive(Debug, Clone, Copy)]
pub struct ServerSlots {
    /// Connections from one client address at once.
    pub per_address: usize,
    /// Connections in one redundancy group at once.
    pub per_group: usize,
    /// Slots kept for each redundancy group that names its clients.
    pub reserved_per_group: usize,
    /// A client no group names must start data transfer within this time.
    pub start_timeout: Duration,
}

/// The slots of every node's server: a control centre's main and standby connection
/// (and a few tools) from one address, and a group's reserve for them.
pub const NODE_SERVER_SLOTS: ServerSlots = ServerSlots {
    per_address: 8,
    per_group: 32,
    reserved_per_group: 2,
    start_timeout: Duration::from_secs(30),
};

/// How to run a project.
#[derive(Debug, Clone)]
pub struct RuntimeOptions {
    /// The nodes to run here; empty runs them all.
    pub nodes: Vec<String>,
    /// How simulated time moves.
    pub pacing: Pacing,
    /// UTC at simulated time zero.
    pub start: DateTime<Utc>,
    /// The event store.
    pub store: StoreChoice,
    /// The kinds of device `[[node.device]]` may name: give the ones the project was
    /// loaded with ([`Project::load_with`]).
    pub device_kinds: DeviceKinds,
}

impl Default for RuntimeOptions {
    fn default() -> Self {
        RuntimeOptions {
            nodes: Vec::new(),
            pacing: Pacing::RealTime { speed: 1.0 },
            start: Utc::now(),
            store: StoreChoice::Project,
            device_kinds: DeviceKinds::builtin(),
        }
    }
}

/// A running node.
#[derive(Debug)]
pub struct NodeRuntime {
    /// Its points (with server and recorder).
    pub points: Arc<NodePoints>,
    /// Its IEC 104 server, if it has one.
    pub server: Option<ServerHandle>,
    /// Its links to lower nodes.
    pub links: Vec<LinkHandle>,
    /// Its serial lines to protection devices.
    pub lines: Vec<line::LineHandle>,
    /// The lifts it watches.
    pub lifts: Vec<lift::LiftHandle>,
    /// Its profiled devices (`[[node.device]]`).
    pub devices: Vec<field::FieldDeviceHandle>,
}

impl NodeRuntime {
    /// The link called `name`.
    pub fn link(&self, name: &str) -> Option<&LinkHandle> {
        self.links.iter().find(|l| l.name() == name)
    }
}

/// How many archived faults wait for a slow subscriber before it misses some.
const ARCHIVED_FAULTS_BACKLOG: usize = 1024;

/// A running project.
pub struct Runtime {
    project: Project,
    clock: Arc<SimClock>,
    nodes: Vec<NodeRuntime>,
    simulation: mpsc::Sender<SimRequest>,
    thread: Option<std::thread::JoinHandle<()>>,
    store: Option<Arc<dyn EventStore>>,
    recorder: Recorder,
    retention: Option<RetentionHandle>,
    archived_faults: tokio::sync::broadcast::Sender<lift::ArchivedFault>,
}

impl std::fmt::Debug for Runtime {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Runtime")
            .field("station", &self.project.station.name)
            .field("nodes", &self.nodes.len())
            .finish_non_exhaustive()
    }
}

/// The time-tag zone of the project's nodes.
fn zone_of(project: &Project) -> TimeZonePolicy {
    TimeZonePolicy::Zone(project.station.time_zone)
}

/// The point database declarations of a node.
pub fn point_specs(node: &NodeConfig) -> Vec<PointSpec> {
    node.points
        .iter()
        .map(|point| PointSpec {
            name: point.name.clone(),
            point_type: point.point_type,
            address: point.ioa.get(),
            transmission: point.transmission,
            groups: point
                .groups
                .iter()
                .filter(|g| (1..=16).contains(*g))
                .fold(0u16, |bits, g| bits | (1 << (g - 1))),
            deadband: point.deadband,
            source: point.source.clone(),
            storage_interval: point.storage_interval,
            description: point.description.clone(),
        })
        .collect()
}

/// Starts the node's profiled devices (`[[node.device]]`) under the field-source
/// supervisor.
fn start_devices(
    config: &NodeConfig,
    points: &Arc<NodePoints>,
    kinds: &DeviceKinds,
) -> Result<Vec<field::FieldDeviceHandle>, RuntimeError> {
    let setup = |device: &str, why: String| {
        RuntimeError::Setup(format!("node `{}`: device `{device}`: {why}", config.name))
    };
    config
        .devices
        .iter()
        .map(|device| {
            let kind = kinds.get(&device.kind).ok_or_else(|| {
                setup(
                    &device.name,
                    format!(
                        "no device kind `{}` here (start the runtime with the kinds the project was loaded with)",
                        device.kind
                    ),
                )
            })?;
            let driver = kind
                .driver(device)
                .map_err(|error| setup(&device.name, error.to_string()))?;
            Ok(field::spawn_device(device, driver, Arc::clone(points)))
        })
        .collect()
}

impl Runtime {
    /// Starts `project` (or the nodes `options.nodes` of it) on the current tokio runtime.
    pub async fn start(project: Project, options: RuntimeOptions) -> Result<Runtime, RuntimeError> {
        let selected: Vec<usize> = if options.nodes.is_empty() {
            (0..project.nodes.len()).collect()
        } else {
            let mut selected = Vec::new();
            for name in &options.nodes {
                let index = project
                    .nodes
                    .iter()
                    .position(|n| &n.name == name)
                    .ok_or_else(|| {
                        let names = project.nodes.iter().map(|n| n.name.as_str());
                        RuntimeError::Setup(format!(
                            "no node `{name}` in the project{} (nodes: {})",
                            plc::suggest::did_you_mean(name, names.clone()),
                            names.collect::<Vec<_>>().join(", ")
                        ))
                    })?;
                selected.push(index);
            }
            selected
        };
        let store_url = match &options.store {
            StoreChoice::Disabled => None,
            StoreChoice::Url(url) => Some(url.clone()),
            StoreChoice::Project => Some(project.station.store.clone()),
        };
        let store: Option<Arc<dyn EventStore>> = match store_url {
            Some(url) => Some(Arc::from(open_store(&url).await?)),
            None => None,
        };
        let recorder = match &store {
            Some(store) => Recorder::spawn(Arc::clone(store)),
            None => Recorder::disabled(),
        };
        let clock = SimClock::new(options.start);
        let zone = zone_of(&project);
        let (archived_faults, _) = tokio::sync::broadcast::channel(ARCHIVED_FAULTS_BACKLOG);
        let mut shared = Vec::new();
        for &index in &selected {
            let Some(node) = project.nodes.get(index) else {
                continue;
            };
            let db = PointDb::new(&node.name, point_specs(node))
                .map_err(|error| RuntimeError::Setup(format!("node `{}`: {error}", node.name)))?;
            let node_clock = NodeClock::new(Arc::clone(&clock), project.station.time_zone);
            shared.push((
                index,
                NodePoints::new(&node.name, db, zone, recorder.clone(), node_clock),
            ));
        }

        // The simulation thread builds the PLCs (they cannot leave it) and runs the first
        // scan, so that each server starts with real values in its image.
        let (requests, receiver) = mpsc::channel();
        let (built, built_answer) = oneshot::channel();
        let thread = {
            let project = project.clone();
            let shared = shared.clone();
            let clock = Arc::clone(&clock);
            let pacing = options.pacing;
            std::thread::Builder::new()
                .name("stanice-simulation".into())
                .spawn(move || match Simulation::build(&project, &shared, clock) {
                    Ok(simulation) => {
                        let _ = built.send(Ok(()));
                        simulation::run(simulation, pacing, receiver);
                    }
                    Err(error) => {
                        let _ = built.send(Err(error));
                    }
                })
                .map_err(|error| {
                    RuntimeError::Setup(format!("cannot start the simulation thread: {error}"))
                })?
        };
        built_answer.await.map_err(|_| RuntimeError::Stopped)??;
        // Wait for the first scan (the thread runs it before reading requests).
        let (scanned, scan_answer) = oneshot::channel();
        requests
            .send(SimRequest::With(Box::new(move |sim: &mut Simulation| {
                let _ = scanned.send(sim.now());
            })))
            .map_err(|_| RuntimeError::Stopped)?;
        scan_answer.await.map_err(|_| RuntimeError::Stopped)?;

        // The clocks of the nodes in this process, for links that set them directly.
        let local_clocks: HashMap<String, Arc<NodeClock>> = shared
            .iter()
            .map(|(_, points)| (points.name().to_owned(), Arc::clone(points.clock())))
            .collect();
        let lower_clock = |link: &crate::config::LinkConfig| match &link.target {
            crate::config::LinkTarget::Node(name) => local_clocks.get(name).cloned(),
            crate::config::LinkTarget::Address(_) => None,
        };
        for (index, points) in &shared {
            let Some(config) = project.nodes.get(*index) else {
                continue;
            };
            for link in config.links.iter().filter(|l| l.clock_sync) {
                if let Some(lower) = lower_clock(link) {
                    points.clock().add_follower(lower);
                }
            }
        }
        let mut nodes = Vec::new();
        let mut handlers = Vec::new();
        for (sim_index, (index, points)) in shared.iter().enumerate() {
            let Some(config) = project.nodes.get(*index) else {
                continue;
            };
            let commands = config
                .commands
                .iter()
                .map(|command| {
                    let route = match &command.target {
                        CommandTarget::Variable(_) => Route::Plc {
                            node: sim_index,
                            pulse: command.pulse,
                        },
                        CommandTarget::Link { link, ioa } => Route::Link {
                            link: link.clone(),
                            ioa: *ioa,
                        },
                        CommandTarget::Line {
                            line,
                            device,
                            fun,
                            inf,
                            value,
                        } => Route::Line {
                            line: line.clone(),
                            device: device.clone(),
                            fun: *fun,
                            inf: *inf,
                            value: *value,
                        },
                        CommandTarget::LineObject { line, device, ioa } => Route::LineObject {
                            line: line.clone(),
                            device: device.clone(),
                            ioa: *ioa,
                        },
                    };
                    (
                        command.ioa.get(),
                        RoutedCommand {
                            name: command.name.clone(),
                            route,
                            from_groups: command.from_groups.clone(),
                            feedback: command.feedback.clone(),
                            range: command.range.clone(),
                        },
                    )
                })
                .collect();
            let handler = Arc::new(NodeHandler {
                points: Arc::clone(points),
                commands,
                links: std::sync::OnceLock::new(),
                lines: std::sync::OnceLock::new(),
                sync_links: config
                    .links
                    .iter()
                    .filter(|l| l.clock_sync)
                    .map(|l| (l.name.clone(), lower_clock(l)))
                    .collect(),
                simulation: requests.clone(),
                groups: config
                    .server
                    .as_ref()
                    .map(|s| s.redundancy_groups.clone())
                    .unwrap_or_default(),
                sim_node: sim_index,
                connected: std::sync::Mutex::default(),
            });
            let server = match (&config.server, config.server_address(&project.station)) {
                (Some(server_config), Some(address)) => {
                    let mut server = ServerConfig::new(address, config.common_address);
                    server.allowed_clients = server_config.allowed_clients.clone();
                    server.outstation.redundancy = server_config.redundancy.clone();
                    // Slots for the controlling stations they are meant for: idle clients
                    // cannot hold every connection (iec60870::cs104::server, admission).
                    server.max_connections_per_address = Some(NODE_SERVER_SLOTS.per_address);
                    server.max_connections_per_group = Some(NODE_SERVER_SLOTS.per_group);
                    server.reserved_per_group = NODE_SERVER_SLOTS.reserved_per_group;
                    server.start_timeout = Some(NODE_SERVER_SLOTS.start_timeout);
                    server.outstation.max_command_age = server_config.max_command_age;
                    server.outstation.time_zone = zone;
                    if let Some(files) = &server_config.tls {
                        // Already resolved against the project folder by the configuration.
                        let tls = files
                            .load()
                            .and_then(|pem| iec60870::cs104::tls::server_config(&pem))
                            .map_err(|error| {
                                RuntimeError::Setup(format!("node `{}`: TLS: {error}", config.name))
                            })?;
                        server.tls = Some(tls);
                    }
                    let mut image =
                        points_iec::process_image(&points.lock(), zone).map_err(|error| {
                            RuntimeError::Setup(format!("node `{}`: {error}", config.name))
                        })?;
                    for command in &config.commands {
                        image
                            .add_command(CommandPoint {
                                ioa: command.ioa,
                                command_type: command.type_id,
                                select_required: command.select_required,
                                max_age: command.max_age,
                            })
                            .map_err(|error| {
                                RuntimeError::Setup(format!("node `{}`: {error}", config.name))
                            })?;
                    }
                    let handle = spawn_server(server, image, handler.clone() as Arc<_>)
                        .await
                        .map_err(|error| match error {
                            ServerError::Listen { address, source }
                                if source.kind() == std::io::ErrorKind::AddrInUse =>
                            {
                                RuntimeError::PortInUse {
                                    node: config.name.clone(),
                                    address,
                                }
                            }
                            error => RuntimeError::Server {
                                node: config.name.clone(),
                                error,
                            },
                        })?;
                    points.attach_sink(Arc::new(sink::Iec104Sink {
                        server: handle.clone(),
                        zone,
                    }));
                    // No controlling station is connected yet.
                    let origin = config.name.clone();
                    points.change_with(&origin, |db, now| {
                        server_config
                            .redundancy_groups
                            .iter()
                            .filter_map(|g| g.status_point.as_deref())
                            .filter_map(|p| db.set_link_status(p, false, now).ok().flatten())
                            .collect()
                    });
                    Some(handle)
                }
                _ => None,
            };
            handlers.push(handler);
            nodes.push(NodeRuntime {
                points: Arc::clone(points),
                server,
                links: Vec::new(),
                lines: Vec::new(),
                lifts: Vec::new(),
                devices: Vec::new(),
            });
        }

        // Links, once every server of this process listens.
        for ((index, points), (node, handler)) in shared.iter().zip(nodes.iter_mut().zip(&handlers))
        {
            let Some(config) = project.nodes.get(*index) else {
                continue;
            };
            let mut by_name = HashMap::new();
            for link in &config.links {
                let Some(address) = project.link_address(link) else {
                    return Err(RuntimeError::Setup(format!(
                        "node `{}`: link `{}` has no address",
                        config.name, link.name
                    )));
                };
                let mut map: HashMap<u32, Vec<points::PointId>> = HashMap::new();
                {
                    let db = points.lock();
                    for point in &config.points {
                        if let PointSource::Link { link: name, ioa } = &point.source {
                            if name == &link.name {
                                if let Some(id) = db.id(point.name.as_str()) {
                                    map.entry(*ioa).or_default().push(id);
                                }
                            }
                        }
                    }
                }
                let tls = match &link.tls {
                    None => None,
                    Some(files) => {
                        let setup = |error: iec60870::cs104::tls::TlsError| {
                            RuntimeError::Setup(format!(
                                "node `{}`: link `{}`: TLS: {error}",
                                config.name, link.name
                            ))
                        };
                        let client = files
                            .load()
                            .and_then(|pem| iec60870::cs104::tls::client_config(&pem))
                            .map_err(setup)?;
                        // The lower node's certificate names the address it is reached at.
                        let name = iec60870::cs104::tls::server_name(&address.ip().to_string())
                            .map_err(setup)?;
                        Some((client, name))
                    }
                };
                let spec = LinkSpec {
                    tls,
                    name: link.name.clone(),
                    address,
                    common_address: link.common_address,
                    interrogate_on_start: link.interrogate_on_start,
                    clock_sync: link.clock_sync,
                    status_point: link.status_point.clone(),
                    points: map,
                    local_clock: lower_clock(link),
                };
                let handle = link::spawn_link(spec, Arc::clone(points));
                by_name.insert(link.name.clone(), handle.clone());
                node.links.push(handle);
            }
            let _ = handler.links.set(by_name);
            let mut lines_by_name = HashMap::new();
            for line in &config.lines {
                let mut signals: HashMap<(u8, u8, u8, Option<u8>), Vec<line::LinePoint>> =
                    HashMap::new();
                let mut objects = line::ObjectPoints::new();
                {
                    let db = points.lock();
                    for point in &config.points {
                        let PointSource::Line {
                            line: name,
                            device,
                            signal,
                        } = &point.source
                        else {
                            continue;
                        };
                        let address = line
                            .devices
                            .iter()
                            .find(|d| &d.name == device)
                            .map(|d| d.address);
                        let (true, Some(address), Some(id)) =
                            (name == &line.name, address, db.id(point.name.as_str()))
                        else {
                            continue;
                        };
                        match signal {
                            LineSignal::Iec103 { fun, inf, index } => signals
                                .entry((address, *fun, *inf, *index))
                                .or_default()
                                .push(line::LinePoint {
                                    id,
                                    kind: point.point_type.kind,
                                    scaling: point.scaling,
                                }),
                            LineSignal::Iec101 { ioa } => {
                                objects.entry((address, *ioa)).or_default().push(id)
                            }
                        }
                    }
                }
                let spec = line::LineSpec {
                    config: line.clone(),
                    signals,
                    objects,
                };
                let handle = line::spawn_line(spec, Arc::clone(points));
                lines_by_name.insert(line.name.clone(), handle.clone());
                node.lines.push(handle);
            }
            let _ = handler.lines.set(lines_by_name);
            let notifications = match (&config.notify, config.lifts.is_empty()) {
                (Some(notify), false) => Some(
                    notification::Notifications::spawn(&config.name, notify.clone(), store.clone())
                        .map_err(|error| {
                            RuntimeError::Setup(format!("node `{}`: notify: {error}", config.name))
                        })?,
                ),
                _ => None,
            };
            for lift in &config.lifts {
                let spec = lift::LiftSpec::new(lift, points);
                node.lifts.push(lift::spawn_lift(
                    spec,
                    Arc::clone(points),
                    store.clone(),
                    archived_faults.clone(),
                    notifications.clone(),
                ));
            }
            node.devices = start_devices(config, points, &options.device_kinds)?;
        }
        requests
            .send(SimRequest::Go)
            .map_err(|_| RuntimeError::Stopped)?;

        let retention = store.as_ref().map(|store| {
            let days = u64::from(project.station.retention_days.max(1));
            let node_clock = NodeClock::new(Arc::clone(&clock), project.station.time_zone);
            spawn_retention(
                Arc::clone(store),
                Retention::new(Duration::from_secs(days * 86_400)),
                move || node_clock.now(),
            )
        });
        tracing::info!(station = %project.station.name, nodes = nodes.len(), "station running");
        Ok(Runtime {
            project,
            clock,
            nodes,
            simulation: requests,
            thread: Some(thread),
            store,
            recorder,
            retention,
            archived_faults,
        })
    }

    /// Every fault archived from now on, by any lift of the running nodes, once it is in
    /// the store (notifications, the HMI's live archive).
    pub fn archived_faults(&self) -> tokio::sync::broadcast::Receiver<lift::ArchivedFault> {
        self.archived_faults.subscribe()
    }

    /// A running lift by name (lift names are unique per node; the first node's wins).
    pub fn lift(&self, name: &str) -> Option<&lift::LiftHandle> {
        self.nodes
            .iter()
            .flat_map(|node| &node.lifts)
            .find(|lift| lift.name().eq_ignore_ascii_case(name))
    }

    /// The project.
    pub fn project(&self) -> &Project {
        &self.project
    }

    /// The simulated clock.
    pub fn clock(&self) -> &Arc<SimClock> {
        &self.clock
    }

    /// The running nodes.
    pub fn nodes(&self) -> &[NodeRuntime] {
        &self.nodes
    }

    /// A running node by name.
    pub fn node(&self, name: &str) -> Option<&NodeRuntime> {
        self.nodes.iter().find(|n| n.points.name() == name)
    }

    /// A node's link by names.
    pub fn link(&self, node: &str, link: &str) -> Option<&LinkHandle> {
        self.node(node)?.link(link)
    }

    /// The event store, if one is configured.
    pub fn store(&self) -> Option<Arc<dyn EventStore>> {
        self.store.clone()
    }

    /// The recorder feeding the store ([`Recorder::flush`] before querying it).
    pub fn recorder(&self) -> &Recorder {
        &self.recorder
    }

    /// With [`Pacing::Manual`]: runs the simulation `by` further, as fast as it goes, and
    /// returns the new simulated time.
    pub async fn advance(&self, by: Duration) -> Result<Duration, RuntimeError> {
        let (reply, answer) = oneshot::channel();
        self.simulation
            .send(SimRequest::Advance { by, reply })
            .map_err(|_| RuntimeError::Stopped)?;
        answer.await.map_err(|_| RuntimeError::Stopped)
    }

    /// Runs `f` on the simulation thread between two steps (plant faults, PLC
    /// monitoring and forcing) and returns its result.
    pub async fn with_simulation<R: Send + 'static>(
        &self,
        f: impl FnOnce(&mut Simulation) -> R + Send + 'static,
    ) -> Result<R, RuntimeError> {
        let (reply, answer) = oneshot::channel();
        self.simulation
            .send(SimRequest::With(Box::new(move |sim: &mut Simulation| {
                let _ = reply.send(f(sim));
            })))
            .map_err(|_| RuntimeError::Stopped)?;
        answer.await.map_err(|_| RuntimeError::Stopped)
    }

    /// Reads one console line ([`Operation::parse`]) and performs it ([`Runtime::perform`]).
    pub async fn operate(&self, text: &str) -> Result<String, OperationError> {
        self.perform(Operation::parse(text)?).await
    }

    /// Performs an operation: injects a fault or a hand operation on the plant
    /// ([`Simulation::operate`]), cuts or restores a link, stops or starts a node's PLC
    /// ([`Simulation::run_plc`]), or operates a simulated lift board or line device.
    /// Returns what the simulated board or device answered (empty for the others).
    pub async fn perform(&self, operation: Operation) -> Result<String, OperationError> {
        let stopped = |_| OperationError::Stopped("the simulation".to_owned());
        match operation {
            Operation::Link { node, link, cut } => {
                let handle = self
                    .link(&node, &link)
                    .ok_or(OperationError::NoLink { node, link })?;
                if cut {
                    handle.cut();
                } else {
                    handle.restore();
                }
                Ok(String::new())
            }
            Operation::Plc { node, run } => {
                self.with_simulation(move |sim| sim.run_plc(&node, run))
                    .await
                    .map_err(stopped)??;
                Ok(String::new())
            }
            Operation::Lift { lift, words } => {
                let handle = self.lift(&lift).ok_or(OperationError::NoLift(lift))?;
                let words: Vec<&str> = words.iter().map(String::as_str).collect();
                handle.operate(&words).await
            }
            Operation::Device { device, words } => {
                let words: Vec<&str> = words.iter().map(String::as_str).collect();
                for line in self.nodes.iter().flat_map(|node| &node.lines) {
                    match line.operate(&device, &words) {
                        // Another line's device, perhaps.
                        Err(OperationError::NoDevice(_)) => {}
                        done => return done,
                    }
                }
                Err(OperationError::NoDevice(device))
            }
            Operation::Plant(text) => {
                self.with_simulation(move |sim| sim.operate(&text))
                    .await
                    .map_err(stopped)??;
                Ok(String::new())
            }
        }
    }

    /// Stops everything: links, servers, the simulation thread; waits until the store
    /// has every record.
    pub async fn shutdown(mut self) {
        for device in self.nodes.iter().flat_map(|node| &node.devices) {
            device.stop();
        }
        // Links first, so that no node reports its lower nodes lost while stopping.
        for node in &self.nodes {
            for link in &node.links {
                link.stop();
                if let Some(client) = link.client() {
                    client.close().await;
                }
            }
        }
        for node in &self.nodes {
            if let Some(server) = &node.server {
                server.shutdown();
            }
        }
        for lift in self.nodes.iter().flat_map(|node| &node.lifts) {
            lift.stop();
        }
        for lift in self.nodes.iter().flat_map(|node| &node.lifts) {
            lift.stopped().await;
        }
        let _ = self.simulation.send(SimRequest::Stop);
        if let Some(thread) = self.thread.take() {
            let _ = tokio::task::spawn_blocking(move || thread.join()).await;
        }
        if let Some(retention) = self.retention.take() {
            retention.stop();
        }
        // Writes what is queued and closes the store (the SQLite write-ahead log merged).
        self.recorder.close().await;
    }
}

impl Drop for Runtime {
    fn drop(&mut self) {
        for lift in self.nodes.iter().flat_map(|node| &node.lifts) {
            lift.stop();
        }
        let _ = self.simulation.send(SimRequest::Stop);
        for node in &self.nodes {
            if let Some(server) = &node.server {
                server.shutdown();
            }
        }
    }
}
