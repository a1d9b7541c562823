//! Shared pieces of the runtime scenario tests: the Vsetín project on free loopback ports,
//! and a dispatch client that records everything it receives.

use std::net::SocketAddr;
use std::sync::{Arc, Mutex};
use std::time::Duration;

use chrono::{DateTime, TimeZone, Utc};
use iec60870::asdu::{Asdu, CommonAddress, Element, Ioa, TimeTag};
use iec60870::cs104::client::{spawn_client, ClientConfig, ClientEvent, ClientHandle};
use station::config::Project;
use station::runtime::{Pacing, Runtime, RuntimeOptions, StoreChoice};

pub(crate) use testkit::ports::free_port_range;
pub(crate) use testkit::projects::{folder as project_folder, vsetin as vsetin_folder};

/// Winter evening 2025-01-15 16:00 UTC, unless a test needs another start.
pub(crate) fn default_start() -> DateTime<Utc> {
    Utc.with_ymd_and_hms(2025, 1, 15, 10, 0, 0).unwrap()
}

/// Loads the Vsetín project on free ports.
pub(crate) fn vsetin_project() -> Project {
    let project = Project::load(&vsetin_folder()).unwrap_or_else(|errors| panic!("{errors}"));
    let ports = project
        .nodes
        .iter()
        .filter_map(|n| n.server.as_ref().map(|s| s.port_offset))
        .max()
        .unwrap_or(0)
        + 1;
    project.with_port_base(free_port_range(ports))
}

/// Starts `project` with manual pacing and the given store.
pub(crate) async fn start(project: Project, store: StoreChoice) -> Runtime {
    start_at(project, store, default_start()).await
}

/// Starts `project` with manual pacing at `start`.
pub(crate) async fn start_at(
    project: Project,
    store: StoreChoice,
    start: DateTime<Utc>,
) -> Runtime {
    Runtime::start(
        project,
        RuntimeOptions {
            nodes: Vec::new(),
            pacing: Pacing::Manual,
            start,
            store,
            device_kinds: station::device::DeviceKinds::builtin(),
        },
    )
    .await
    .unwrap_or_else(|error| panic!("runtime does not start: {error}"))
}

/// Waits (real time, bounded) until `condition` holds.
pub(crate) async fn eventually(what: &str, mut condition: impl FnMut() -> bool) {
    for _ in 0..500 {
        if condition() {
            return;
        }
        tokio::time::sleep(Duration::from_millis(20)).await;
    }
    panic!("timed out waiting until {what}");
}

/// Advances plant time in steps, giving the links real time to carry what changed, until
/// `condition` holds (bounded).
pub(crate) async fn advance_until(
    runtime: &Runtime,
    step: Duration,
    what: &str,
    mut condition: impl FnMut() -> bool,
) {
    for _ in 0..400 {
        if condition() {
            return;
        }
        runtime.advance(step).await.unwrap();
        tokio::time::sleep(Duration::from_millis(10)).await;
    }
    panic!("timed out waiting until {what}");
}

/// Waits until every link of every node is up.
/// The address of the Vsetín top node RDRT's IEC 104 server (where dispatch connects).
pub(crate) fn rdrt_address(runtime: &Runtime) -> std::net::SocketAddr {
    runtime
        .node("RDRT")
        .unwrap()
        .server
        .as_ref()
        .unwrap()
        .local_addr()
}

pub(crate) async fn links_up(runtime: &Runtime) {
    eventually("every link is up", || {
        runtime
            .nodes()
            .iter()
            .all(|n| n.links.iter().all(|l| l.is_up()))
    })
    .await;
}

/// One information object a dispatch client received.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Received {
    pub(crate) ioa: u32,
    pub(crate) cause: u8,
    pub(crate) element: Element,
    pub(crate) time: Option<TimeTag>,
}

impl Received {
    pub(crate) fn on(&self) -> Option<bool> {
        match self.element {
            Element::SinglePoint { on, .. } => Some(on),
            _ => None,
        }
    }

    /// A short floating-point measurement's value.
    pub(crate) fn real(&self) -> Option<f32> {
        match self.element {
            Element::Float { value, .. } => Some(value),
            _ => None,
        }
    }

    pub(crate) fn invalid(&self) -> bool {
        match &self.element {
            Element::SinglePoint { quality, .. }
            | Element::DoublePoint { quality, .. }
            | Element::Float { quality, .. } => quality.invalid,
            _ => false,
        }
    }
}

/// A controlling station (dispatch) connected to a node's server.
pub(crate) struct Dispatch {
    pub(crate) client: ClientHandle,
    pub(crate) received: Arc<Mutex<Vec<Received>>>,
    pub(crate) started: Arc<Mutex<bool>>,
}

impl Dispatch {
    /// Connects to `address` (common address `ca`) and records every monitor object.
    pub(crate) async fn connect(address: SocketAddr, ca: u16, interrogate: bool) -> Dispatch {
        Dispatch::connect_from(address, ca, interrogate, None).await
    }

    /// As [`Dispatch::connect`], from a given local address (127.0.0.2 is the HMI panel of
    /// the Vsetín project).
    pub(crate) async fn connect_from(
        address: SocketAddr,
        ca: u16,
        interrogate: bool,
        local: Option<std::net::IpAddr>,
    ) -> Dispatch {
        let mut config = ClientConfig::new(address.to_string(), CommonAddress::new(ca));
        config.local_address = local;
        config.interrogate_on_start = interrogate;
        config.reconnect_delay = Duration::from_millis(100);
        let (client, mut events) = spawn_client(config);
        let received = Arc::new(Mutex::new(Vec::new()));
        let started = Arc::new(Mutex::new(false));
        {
            let received = Arc::clone(&received);
            let started = Arc::clone(&started);
            tokio::spawn(async move {
                while let Some(event) = events.recv().await {
                    match event {
                        ClientEvent::Started => *started.lock().unwrap() = true,
                        ClientEvent::Disconnected { .. } => *started.lock().unwrap() = false,
                        ClientEvent::Asdu(asdu) => record(&received, &asdu),
                        _ => {}
                    }
                }
            });
        }
        let dispatch = Dispatch {
            client,
            received,
            started,
        };
        let started = Arc::clone(&dispatch.started);
        eventually("the dispatch client is started", move || {
            *started.lock().unwrap()
        })
        .await;
        dispatch
    }

    /// Everything received so far.
    pub(crate) fn all(&self) -> Vec<Received> {
        self.received.lock().unwrap().clone()
    }

    /// What was received for `ioa`, in order.
    pub(crate) fn of(&self, ioa: u32) -> Vec<Received> {
        self.all().into_iter().filter(|r| r.ioa == ioa).collect()
    }

    /// The newest object received for `ioa`.
    pub(crate) fn last(&self, ioa: u32) -> Option<Received> {
        self.of(ioa).pop()
    }

    /// Sends a single command and returns whether it was confirmed positively.
    pub(crate) async fn single_command(&self, ioa: u32, on: bool, select: bool) -> bool {
        let qualifier = iec60870::asdu::CommandQualifier::new(0, select).unwrap();
        let outcome = self
            .client
            .command(
                iec60870::asdu::TypeId::C_SC_NA_1,
                Ioa::try_new(ioa).unwrap(),
                Element::SingleCommand { on, qualifier },
                None,
            )
            .await
            .unwrap();
        outcome.positive
    }
}

fn record(received: &Mutex<Vec<Received>>, asdu: &Asdu) {
    if !asdu.type_id.is_monitor() {
        return;
    }
    let mut received = received.lock().unwrap();
    for object in &asdu.objects {
        received.push(Received {
            ioa: object.ioa.get(),
            cause: asdu.cot.cause.value(),
            element: object.element.clone(),
            time: object.time,
        });
    }
}
