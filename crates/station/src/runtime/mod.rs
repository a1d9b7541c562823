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
//! - [`sink`]: where a node's changes go upward (its IEC 104 server; the MQTT Sparkplug B
//!   publisher of crate `sparkplug` attaches one more).
//! - [`link`]: the IEC 104 client links to lower nodes (concentration, invalidation,
//!   status points, time source).
//! - [`line`]: the serial lines to protection devices (IEC 103 master, the gateway role:
//!   their signals become points, commands become general commands).
//! - [`lift`]: the lifts watched through their EKM66 boards (lift monitoring: their
//!   values become points, their fault logs go into the store's archive).
//! - [`plant_port`]: the plant's serial ports (a device of the plant on its RS-232) on
//!   pseudo-terminals, for the project's device drivers.
//! - [`s7_server`]: a node's PLC memory served over S7 (the S7-1500 concentrator that
//!   LOGO! boards connect to), connection status per TSAP.
//! - [`program`]: a new program loaded into a running node's PLC (a lab's student
//!   program on the lab itself), and the project's own put back.
//! - [`notification`]: e-mail and webhook notices of what the lifts report, each delivery
//!   recorded.
//! - `command`: the server hooks — a command's authority, range and audit, then its
//!   target executes it; clock synchronisation passed down. [`CommandPort`] takes the
//!   same path for other protocols (an MQTT host's write), naming their actor.
//! - `target`: where a command goes, one `Target` per kind (a PLC variable, refused in
//!   local mode; an object down a link; a line device's general command; an IEC 101
//!   outstation's object).
//! - `server`: a node's IEC 104 server (settings, TLS, process image with the commands,
//!   the sink feeding it, its redundancy groups' status points).
//!
//! [`Runtime::start`] brings a project (or some of its nodes) up, one step a function
//! here: the event store and recorder (`open_event_store`), the point databases
//! (`node_points`), the PLCs (compiled on the simulation thread, errors with
//! file:line:col: `start_simulation`, then `first_scan`), one server per node
//! (`start_servers`: its image holds the values of the first PLC scan, see `server`; its
//! handler is `command`'s `NodeHandler::new`), then the links (`start_links`, each spec
//! from [`link`]'s `LinkSpec::new`), the serial lines (`start_lines`, their point maps
//! from [`line`]'s `LineSpec::new`), notifications and lifts (`start_notifications`,
//! `start_lifts`), the plant's serial ports on pseudo-terminals (`plant_port`) and the
//! profiled devices on them or on lines of their own (`start_devices`), then the clock starts and
//! retention runs (`start_retention`).

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
pub mod plant_port;
pub mod program;
pub mod s7_server;
mod server;
pub mod simulation;
pub mod sink;
mod target;

use std::collections::HashMap;
use std::sync::{mpsc, Arc};
use std::time::Duration;

use chrono::{DateTime, Utc};
use iec60870::cs104::server::{ServerError, ServerHandle};
use tokio::sync::oneshot;

use crate::config::{FieldDeviceConfig, NodeConfig, Project};
use crate::device::DeviceKinds;
use crate::store::{
    open_store, spawn_retention, EventStore, Retention, RetentionHandle, StoreError,
};
use iec60870::time::TimeZonePolicy;
use points::{PointDb, PointSpec};

pub use crate::store::Recorder;
pub use clock::{NodeClock, Pacing, SimClock};
pub use link::LinkHandle;
pub use node::NodePoints;
pub use simulation::{CommandRefusal, OutputChange, Simulation};
pub use sink::{Iec104Sink, PointSink};

use clock::LocalClocks;
use command::NodeHandler;
pub use command::{CommandError, CommandPort};
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
    /// The event store could not be opened. Its cause is in the message, not chained as
    /// a source: printed with its chain, it read twice ("bad store URL ...: bad store
    /// URL ...").
    #[error("event store: {0}")]
    Store(StoreError),
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

impl From<StoreError> for RuntimeError {
    fn from(error: StoreError) -> RuntimeError {
        RuntimeError::Store(error)
    }
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
    /// Its PLC memory served over S7 (`[node.s7_server]`).
    pub s7_server: Option<s7_server::S7ServerHandle>,
    /// Its commands for other protocols (MQTT), through its routing, authority and audit.
    pub commands: CommandPort,
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
    plant_ports: Vec<plant_port::PlantPortHandle>,
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
            storage: point.storage,
            description: point.description.clone(),
        })
        .collect()
}

/// The project indices of the nodes `names` (all of them when it is empty).
fn select_nodes(project: &Project, names: &[String]) -> Result<Vec<usize>, RuntimeError> {
    if names.is_empty() {
        return Ok((0..project.nodes.len()).collect());
    }
    names
        .iter()
        .map(|name| {
            project
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
                })
        })
        .collect()
}

/// Opens the event store `choice` names, if any.
async fn open_event_store(
    project: &Project,
    choice: &StoreChoice,
) -> Result<Option<Arc<dyn EventStore>>, RuntimeError> {
    let url = match choice {
        StoreChoice::Disabled => return Ok(None),
        StoreChoice::Url(url) => url.clone(),
        StoreChoice::Project => project.station.store.clone(),
    };
    Ok(Some(Arc::from(open_store(&url).await?)))
}

/// The point database of each selected node (by project index), with its recorder and
/// its clock on `clock`.
fn node_points(
    project: &Project,
    selected: &[usize],
    clock: &Arc<SimClock>,
    recorder: &Recorder,
) -> Result<Vec<(usize, Arc<NodePoints>)>, RuntimeError> {
    let zone = zone_of(project);
    let mut shared = Vec::new();
    for &index in selected {
        let Some(node) = project.nodes.get(index) else {
            continue;
        };
        let db = PointDb::new(&node.name, point_specs(node))
            .map_err(|error| RuntimeError::Setup(format!("node `{}`: {error}", node.name)))?;
        let node_clock = NodeClock::new(Arc::clone(clock), project.station.time_zone);
        shared.push((
            index,
            NodePoints::new(&node.name, db, zone, recorder.clone(), node_clock),
        ));
    }
    Ok(shared)
}

/// Starts the simulation thread, which builds the plant and the PLCs of `nodes` and runs
/// the first scan; returns once they are built (or why they could not be), with the
/// channel of its requests.
async fn start_simulation(
    project: &Project,
    nodes: &[(usize, Arc<NodePoints>)],
    clock: &Arc<SimClock>,
    (pacing, started): (Pacing, std::time::Instant),
    images: simulation::DeviceImages,
    served: Vec<s7_server::S7Prepared>,
) -> Result<(mpsc::Sender<SimRequest>, std::thread::JoinHandle<()>), RuntimeError> {
    let (requests, receiver) = mpsc::channel();
    let (built, built_answer) = oneshot::channel();
    let thread = {
        let project = project.clone();
        let shared = nodes.to_vec();
        let clock = Arc::clone(clock);
        std::thread::Builder::new()
            .name("stanice-simulation".into())
            .spawn(
                move || match Simulation::build(&project, &shared, clock, images, served) {
                    Ok(simulation) => {
                        let _ = built.send(Ok(()));
                        simulation::run(simulation, pacing, started, receiver);
                    }
                    Err(error) => {
                        let _ = built.send(Err(error));
                    }
                },
            )
            .map_err(|error| {
                RuntimeError::Setup(format!("cannot start the simulation thread: {error}"))
            })?
    };
    built_answer.await.map_err(|_| RuntimeError::Stopped)??;
    Ok((requests, thread))
}

/// Waits for the first scan (the thread runs it before reading requests).
async fn first_scan(requests: &mpsc::Sender<SimRequest>) -> Result<(), RuntimeError> {
    let (scanned, scan_answer) = oneshot::channel();
    requests
        .send(SimRequest::With(Box::new(move |sim: &mut Simulation| {
            let _ = scanned.send(sim.now());
        })))
        .map_err(|_| RuntimeError::Stopped)?;
    scan_answer.await.map_err(|_| RuntimeError::Stopped)?;
    Ok(())
}

/// Makes the clock of each lower node in this process follow the node above it, over the
/// links that synchronise clocks.
fn follow_lower_clocks(
    project: &Project,
    nodes: &[(usize, Arc<NodePoints>)],
    clocks: &LocalClocks,
) {
    for (index, points) in nodes {
        let Some(config) = project.nodes.get(*index) else {
            continue;
        };
        for link in config.links.iter().filter(|l| l.clock_sync) {
            if let Some(lower) = clocks.lower(link) {
                points.clock().add_follower(lower);
            }
        }
    }
}

/// Starts each node's server (if it has one) with its command handler; returns the
/// nodes, their links, lines, lifts and devices still to start, and the handlers.
async fn start_servers(
    project: &Project,
    nodes: &[(usize, Arc<NodePoints>)],
    requests: &mpsc::Sender<SimRequest>,
    clocks: &LocalClocks,
    zone: TimeZonePolicy,
) -> Result<(Vec<NodeRuntime>, Vec<Arc<NodeHandler>>), RuntimeError> {
    let mut started = Vec::new();
    let mut handlers = Vec::new();
    for (sim_index, (index, points)) in nodes.iter().enumerate() {
        let Some(config) = project.nodes.get(*index) else {
            continue;
        };
        let handler = Arc::new(NodeHandler::new(
            config,
            sim_index,
            points,
            requests.clone(),
            clocks,
        ));
        let server = server::start_server(project, config, points, &handler, zone).await?;
        let commands = CommandPort::new(config, &handler);
        handlers.push(handler);
        started.push(NodeRuntime {
            points: Arc::clone(points),
            server,
            links: Vec::new(),
            lines: Vec::new(),
            lifts: Vec::new(),
            devices: Vec::new(),
            s7_server: None,
            commands,
        });
    }
    Ok((started, handlers))
}

/// Starts the node's links to lower nodes (once every server of this process listens).
fn start_links(
    project: &Project,
    config: &NodeConfig,
    points: &Arc<NodePoints>,
    clocks: &LocalClocks,
) -> Result<Vec<LinkHandle>, RuntimeError> {
    config
        .links
        .iter()
        .map(|link| {
            let spec = LinkSpec::new(project, config, link, points, clocks)?;
            Ok(link::spawn_link(spec, Arc::clone(points)))
        })
        .collect()
}

/// Starts the node's serial lines to protection devices.
fn start_lines(config: &NodeConfig, points: &Arc<NodePoints>) -> Vec<line::LineHandle> {
    config
        .lines
        .iter()
        .map(|line| {
            let spec = line::LineSpec::new(line, &config.points, points);
            line::spawn_line(spec, Arc::clone(points))
        })
        .collect()
}

/// The handles by name, for the server's hooks.
fn by_name<H: Clone>(handles: &[H], name: impl Fn(&H) -> &str) -> HashMap<String, H> {
    handles
        .iter()
        .map(|handle| (name(handle).to_owned(), handle.clone()))
        .collect()
}

/// Starts the sender of the node's notices, if it has lifts to report on and a `notify`
/// setting.
fn start_notifications(
    config: &NodeConfig,
    store: Option<&Arc<dyn EventStore>>,
) -> Result<Option<notification::Notifications>, RuntimeError> {
    match (&config.notify, config.lifts.is_empty()) {
        (Some(notify), false) => {
            notification::Notifications::spawn(&config.name, notify.clone(), store.cloned())
                .map(Some)
                .map_err(|error| {
                    RuntimeError::Setup(format!("node `{}`: notify: {error}", config.name))
                })
        }
        _ => Ok(None),
    }
}

/// Starts the node's lifts; their archived faults go to `archived_faults` and to
/// `notifications`.
fn start_lifts(
    config: &NodeConfig,
    points: &Arc<NodePoints>,
    store: Option<&Arc<dyn EventStore>>,
    archived_faults: &tokio::sync::broadcast::Sender<lift::ArchivedFault>,
    notifications: Option<notification::Notifications>,
) -> Vec<lift::LiftHandle> {
    config
        .lifts
        .iter()
        .map(|lift| {
            let spec = lift::LiftSpec::new(lift, points);
            lift::spawn_lift(
                spec,
                Arc::clone(points),
                store.cloned(),
                archived_faults.clone(),
                notifications.clone(),
            )
        })
        .collect()
}

/// Starts the node's profiled devices (`[[node.device]]`) under the field-source
/// supervisor.
/// `connect = "node:NAME"` of a device resolved to that node's S7 server's address (its
/// host or the station's `bind`, `port_base` + its `port_offset`).
fn s7_server_address(project: &Project, mut device: FieldDeviceConfig) -> FieldDeviceConfig {
    let target = device
        .settings
        .get("connect")
        .and_then(toml::Value::as_str)
        .and_then(|connect| connect.strip_prefix(crate::device::s7::NODE_PREFIX))
        .and_then(|name| project.node(name))
        .and_then(|node| node.s7_server_address(&project.station));
    if let Some(address) = target {
        device.settings.insert(
            "connect".to_owned(),
            toml::Value::String(address.to_string()),
        );
    }
    device
}

/// An I/O image for each device of the selected nodes whose items a PLC is bound to.
fn device_images(
    project: &Project,
    nodes: &[(usize, Arc<NodePoints>)],
) -> simulation::DeviceImages {
    nodes
        .iter()
        .filter_map(|(index, _)| project.nodes.get(*index))
        .flat_map(|node| {
            node.devices
                .iter()
                .filter(|device| !device.io.is_empty())
                .map(|device| {
                    (
                        (node.name.clone(), device.name.clone()),
                        Arc::new(crate::device::IoImage::new()),
                    )
                })
        })
        .collect()
}

fn start_devices(
    project: &Project,
    config: &NodeConfig,
    points: &Arc<NodePoints>,
    kinds: &DeviceKinds,
    plant_ports: &plant_port::PlantPorts,
    images: &simulation::DeviceImages,
) -> Result<Vec<field::FieldDeviceHandle>, RuntimeError> {
    let setup = |device: &str, why: String| {
        RuntimeError::Setup(format!("node `{}`: device `{device}`: {why}", config.name))
    };
    config
        .devices
        .iter()
        .map(|device| {
            let device = &s7_server_address(project, plant_ports.device(&config.name, device));
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
            let image = images
                .get(&(config.name.clone(), device.name.clone()))
                .cloned();
            Ok(field::spawn_device(device, driver, Arc::clone(points), image))
        })
        .collect()
}

/// Starts the deletion of records older than the project's retention, if there is a
/// store.
fn start_retention(
    project: &Project,
    clock: &Arc<SimClock>,
    store: Option<&Arc<dyn EventStore>>,
) -> Option<RetentionHandle> {
    store.map(|store| {
        let days = u64::from(project.station.retention_days.max(1));
        let node_clock = NodeClock::new(Arc::clone(clock), project.station.time_zone);
        spawn_retention(
            Arc::clone(store),
            Retention::new(Duration::from_secs(days * 86_400)),
            move || node_clock.now(),
        )
    })
}

impl Runtime {
    /// Starts `project` (or the nodes `options.nodes` of it) on the current tokio runtime.
    pub async fn start(project: Project, options: RuntimeOptions) -> Result<Runtime, RuntimeError> {
        // The wall-clock instant of the simulated start: a real-time clock counts from it,
        // not from the end of the start-up (the store opened, the PLCs compiled), so that
        // at speed 1 a station started at `now` keeps the wall clock's time.
        let started = std::time::Instant::now();
        let selected = select_nodes(&project, &options.nodes)?;
        let store = open_event_store(&project, &options.store).await?;
        let recorder = match &store {
            Some(store) => Recorder::spawn(Arc::clone(store)),
            None => Recorder::disabled(),
        };
        let clock = SimClock::new(options.start);
        let zone = zone_of(&project);
        let (archived_faults, _) = tokio::sync::broadcast::channel(ARCHIVED_FAULTS_BACKLOG);
        let shared = node_points(&project, &selected, &clock, &recorder)?;
        // The simulation thread builds the PLCs (they cannot leave it) and runs the first
        // scan, so that each server starts with real values in its image.
        let images = device_images(&project, &shared);
        // The S7 servers' memories and events: the simulation thread takes the receiving
        // ends, the servers (started below) the sending ones.
        let mut served = Vec::new();
        let mut s7_servers = Vec::new();
        for (index, _) in &shared {
            if let Some(prepared) = project
                .nodes
                .get(*index)
                .and_then(s7_server::S7Prepared::new)
            {
                s7_servers.push((
                    prepared.node.clone(),
                    prepared.config.clone(),
                    Arc::clone(&prepared.memory),
                    prepared.sender.clone(),
                ));
                served.push(prepared);
            }
        }
        let (requests, thread) = start_simulation(
            &project,
            &shared,
            &clock,
            (options.pacing, started),
            images.clone(),
            served,
        )
        .await?;
        first_scan(&requests).await?;
        let mut s7_handles = HashMap::new();
        for (node, config, memory, sender) in s7_servers {
            let port = project.station.port_base.saturating_add(config.port_offset);
            let ip = project.node(&node).map_or(project.station.bind, |node| {
                node.listen_ip(&project.station)
            });
            let address = std::net::SocketAddr::new(ip, port);
            let handle = s7_server::start(&node, address, &config, memory, sender).await?;
            s7_handles.insert(node, handle);
        }

        let selected_indices: Vec<usize> = shared.iter().map(|(index, _)| *index).collect();
        let plant_ports = plant_port::open(&project, &selected_indices, &requests).await?;

        let local_clocks = LocalClocks::of(&shared);
        follow_lower_clocks(&project, &shared, &local_clocks);
        let (mut nodes, handlers) =
            start_servers(&project, &shared, &requests, &local_clocks, zone).await?;

        // Links, once every server of this process listens.
        for ((index, points), (node, handler)) in shared.iter().zip(nodes.iter_mut().zip(&handlers))
        {
            let Some(config) = project.nodes.get(*index) else {
                continue;
            };
            node.links = start_links(&project, config, points, &local_clocks)?;
            let _ = handler.links.set(by_name(&node.links, LinkHandle::name));
            node.lines = start_lines(config, points);
            let _ = handler
                .lines
                .set(by_name(&node.lines, line::LineHandle::name));
            let notifications = start_notifications(config, store.as_ref())?;
            node.lifts = start_lifts(
                config,
                points,
                store.as_ref(),
                &archived_faults,
                notifications,
            );
            node.devices = start_devices(
                &project,
                config,
                points,
                &options.device_kinds,
                &plant_ports,
                &images,
            )?;
            node.s7_server = s7_handles.remove(&config.name);
        }
        requests
            .send(SimRequest::Go)
            .map_err(|_| RuntimeError::Stopped)?;

        let retention = start_retention(&project, &clock, store.as_ref());
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
            plant_ports: plant_ports.handles,
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

    /// Loads programs into the running nodes' PLCs (a remote lab's student program), from
    /// any task.
    pub fn program_loader(&self) -> program::ProgramLoader {
        program::ProgramLoader::new(self.project.clone(), self.simulation.clone())
    }

    /// The plant's serial ports on pseudo-terminals, with the device on each.
    pub fn plant_ports(&self) -> &[plant_port::PlantPortHandle] {
        &self.plant_ports
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
        for port in &self.plant_ports {
            port.stop();
        }
        for server in self.nodes.iter().filter_map(|node| node.s7_server.as_ref()) {
            server.stop();
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
        for port in &self.plant_ports {
            port.stop();
        }
        for server in self.nodes.iter().filter_map(|node| node.s7_server.as_ref()) {
            server.stop();
        }
        let _ = self.simulation.send(SimRequest::Stop);
        for node in &self.nodes {
            if let Some(server) = &node.server {
                server.shutdown();
            }
        }
    }
}
