//! A node's IEC 104 client link to a lower node (concentration).
//!
//! Each link is a [`cs104::link::Link`](iec60870::cs104::link::Link) (the loop that keeps
//! a client connected, cut and restored, written once for the runtime and the HMI) with a
//! [`Concentrator`] as its observer: data of the lower node (spontaneous, interrogated,
//! periodic, return information) update the points whose source is `link:NAME/IOA`; when
//! the connection is lost those points turn invalid (IV, last value kept) and the link's
//! status point reports the failure; after reconnection the lower node's buffered events
//! and the general interrogation bring them back. On start (and every
//! [`CLOCK_SYNC_PERIOD`]) the node synchronises the lower node's clock with its own, so it
//! stays the time source while its upper link is down. Commands forwarded down the link
//! use the same client ([`LinkHandle::client`]); the observer reports their confirmation
//! and termination as it meets them in the lower node's stream
//! ([`LinkHandle::watch_command`]), after the data received before them, so a forwarded
//! command's return information is published here before its termination.
//!
//! A link's spec follows from the project ([`LinkSpec::new`]): the lower node's address,
//! the points its IOAs feed, its TLS, the lower clock when that node runs in this process.

use std::collections::HashMap;
use std::net::SocketAddr;
use std::sync::Arc;
use std::time::Duration;

use iec60870::asdu::{Asdu, CommonAddress, Ioa, TypeId};
use iec60870::cs104::client::{ClientConfig, ClientHandle};
use iec60870::cs104::link::{Link, LinkDown, LinkObserver};

use points::{PointId, PointSource};

use crate::config::{LinkConfig, NodeConfig, Project};

use super::clock::{LocalClocks, NodeClock};
use super::field::CommunicationStatus;
use super::forwarded::{CommandAnswers, CommandWatches};
use super::node::NodePoints;
use super::RuntimeError;

/// How often a node re-synchronises the clocks of the nodes below it.
pub const CLOCK_SYNC_PERIOD: Duration = Duration::from_secs(60);

/// What a link is configured to do.
#[derive(Debug, Clone)]
pub(crate) struct LinkSpec {
    pub name: String,
    pub address: SocketAddr,
    pub common_address: CommonAddress,
    pub interrogate_on_start: bool,
    pub clock_sync: bool,
    pub status_point: Option<String>,
    /// Remote IOA -> the local points it feeds.
    pub points: HashMap<u32, Vec<PointId>>,
    /// TLS with mutual authentication: the client configuration and the name the lower
    /// node's certificate must carry.
    pub tls: Option<iec60870::cs104::tls::ClientTls>,
    /// The lower node's clock when it runs in this process: both read the one simulated
    /// clock, so it is set directly. (A C_CS_NA_1 would arrive late by the network delay
    /// times the simulation speed, and skew the lower clock by that much.)
    pub local_clock: Option<Arc<NodeClock>>,
}

impl LinkSpec {
    /// The spec of the node `config`'s `link`: the points of `node` whose source is
    /// `link:NAME/IOA` by remote IOA, the TLS client configuration, the lower node's clock
    /// among `clocks`.
    pub(crate) fn new(
        project: &Project,
        config: &NodeConfig,
        link: &LinkConfig,
        node: &NodePoints,
        clocks: &LocalClocks,
    ) -> Result<LinkSpec, RuntimeError> {
        let Some(address) = project.link_address(link) else {
            return Err(RuntimeError::Setup(format!(
                "node `{}`: link `{}` has no address",
                config.name, link.name
            )));
        };
        let points = fed_points(config, link, node);
        let tls = client_tls(config, link, address)?;
        Ok(LinkSpec {
            tls,
            name: link.name.clone(),
            address,
            common_address: link.common_address,
            interrogate_on_start: link.interrogate_on_start,
            clock_sync: link.clock_sync,
            status_point: link.status_point.clone(),
            points,
            local_clock: clocks.lower(link),
        })
    }
}

/// Remote IOA -> the points of `node` it feeds (those whose source is `link:NAME/IOA`).
fn fed_points(
    config: &NodeConfig,
    link: &LinkConfig,
    node: &NodePoints,
) -> HashMap<u32, Vec<PointId>> {
    let mut map: HashMap<u32, Vec<PointId>> = HashMap::new();
    let db = node.lock();
    for point in &config.points {
        if let PointSource::Link { link: name, ioa } = &point.source {
            if name == &link.name {
                if let Some(id) = db.id(point.name.as_str()) {
                    map.entry(*ioa).or_default().push(id);
                }
            }
        }
    }
    map
}

/// The link's TLS client configuration and the name the lower node's certificate must
/// carry, if it uses TLS.
fn client_tls(
    config: &NodeConfig,
    link: &LinkConfig,
    address: SocketAddr,
) -> Result<Option<iec60870::cs104::tls::ClientTls>, RuntimeError> {
    let Some(files) = &link.tls else {
        return Ok(None);
    };
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
    let name = iec60870::cs104::tls::server_name(&address.ip().to_string()).map_err(setup)?;
    Ok(Some((client, name)))
}

/// A running link: its state, its client (for forwarded commands), cut and restore.
#[derive(Debug, Clone)]
pub struct LinkHandle {
    name: String,
    link: Link,
    commands: Arc<CommandWatches>,
}

impl LinkHandle {
    /// The link's name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Whether data transfer is started on the link.
    pub fn is_up(&self) -> bool {
        self.link.is_up()
    }

    /// The client, while the link is not cut.
    pub fn client(&self) -> Option<ClientHandle> {
        self.link.client()
    }

    /// Cuts the link (fault injection: a cable pulled): closes the connection and stays
    /// disconnected until [`LinkHandle::restore`].
    pub fn cut(&self) {
        self.link.cut();
    }

    /// Reconnects a cut link.
    pub fn restore(&self) {
        self.link.restore();
    }

    /// Watches for the answers of a command about to be sent down the link (type and the
    /// lower node's address).
    pub(crate) fn watch_command(&self, type_id: TypeId, ioa: Ioa) -> CommandAnswers {
        self.commands.watch(type_id, ioa)
    }

    /// Closes the link for good (runtime shutdown).
    pub(crate) fn stop(&self) {
        self.link.stop();
    }
}

/// Starts a link's task on the current tokio runtime.
pub(crate) fn spawn_link(spec: LinkSpec, node: Arc<NodePoints>) -> LinkHandle {
    let mut config = ClientConfig::new(spec.address.to_string(), spec.common_address);
    config.interrogate_on_start = spec.interrogate_on_start;
    config.reconnect = true;
    config.reconnect_delay = Duration::from_millis(200);
    config.reconnect_delay_max = Duration::from_secs(5);
    config.tls = spec.tls.clone();
    let origin = format!("link:{}", spec.name);
    let link = spec.name.clone();
    let comm = CommunicationStatus::new(
        origin.clone(),
        spec.status_point.clone(),
        move |source| matches!(source, PointSource::Link { link: name, .. } if *name == link),
    );
    comm.down(&node);
    let commands = Arc::new(CommandWatches::default());
    let name = spec.name.clone();
    let observer = Concentrator {
        spec,
        node,
        origin,
        comm,
        commands: Arc::clone(&commands),
    };
    LinkHandle {
        name,
        link: Link::spawn(config, Arc::new(observer)),
        commands,
    }
}

/// What a concentrator does with its link to a lower node: the lower node's values into
/// this node's points, its state into the status point, the lower clock kept in step,
/// forwarded commands' answers to whoever forwarded them.
struct Concentrator {
    spec: LinkSpec,
    node: Arc<NodePoints>,
    /// `link:NAME`, the origin of the changes the link makes.
    origin: String,
    /// Its status point and the points it feeds.
    comm: CommunicationStatus,
    commands: Arc<CommandWatches>,
}

impl LinkObserver for Concentrator {
    fn started(&self, client: &ClientHandle) {
        let (spec, node) = (&self.spec, &self.node);
        tracing::info!(node = %node.name(), link = %spec.name, address = %spec.address, "link up");
        self.comm.up(node);
        if spec.clock_sync {
            synchronise(spec, node, client);
        }
    }

    fn down(&self, why: &LinkDown) {
        tracing::warn!(node = %self.node.name(), link = %self.spec.name, reason = %why, "link down");
        // No answer to a forwarded command comes over a lost connection.
        self.commands.abandon_all();
        self.comm.down(&self.node);
    }

    fn asdu(&self, asdu: &Asdu) {
        apply(&self.spec, &self.node, &self.origin, asdu);
        if asdu.type_id.is_command() {
            self.commands.answered(asdu);
        }
    }

    fn period(&self) -> Option<Duration> {
        self.spec.clock_sync.then_some(CLOCK_SYNC_PERIOD)
    }

    fn every_period(&self, client: &ClientHandle) {
        synchronise(&self.spec, &self.node, client);
    }
}

fn synchronise(spec: &LinkSpec, node: &NodePoints, client: &ClientHandle) {
    if let Some(lower) = &spec.local_clock {
        lower.synchronise(node.clock().now());
        return;
    }
    let time = node.zone().to_cp56(node.clock().now());
    let client = client.clone();
    let name = node.name().to_owned();
    tokio::spawn(async move {
        match client.clock_sync(time).await {
            Ok(outcome) if outcome.positive => {}
            Ok(outcome) => {
                tracing::warn!(node = %name, cause = %outcome.cause, "clock synchronisation refused")
            }
            Err(error) => tracing::debug!(node = %name, %error, "clock synchronisation not sent"),
        }
    });
}

fn apply(spec: &LinkSpec, node: &NodePoints, origin: &str, asdu: &Asdu) {
    node.apply_received(origin, asdu, |ioa| spec.points.get(&ioa).map(Vec::as_slice));
}
