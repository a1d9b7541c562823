//! The tokio adapter: one MQTT connection (rumqttc) per node, driving the node's
//! [`EdgeNode`], and [`MqttSink`], the station's point sink feeding it.
//!
//! Per node two tasks: the connection task polls rumqttc's event loop and reports
//! connections, losses and received messages; the node task owns the [`EdgeNode`] and
//! takes those reports and the sink's changes, publishing what the core answers. On a
//! loss the node task hands the connection task the next will (NDEATH with the next
//! `bdSeq`) before it reconnects. The sink never blocks the node: it hands each change
//! to the node task over a bounded channel and counts what does not fit.

use std::path::PathBuf;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use std::time::Duration;

use rumqttc::{
    AsyncClient, Event, EventLoop, LastWill, MqttOptions, Packet, QoS, TlsConfiguration, Transport,
};
use station::config::NodeConfig;
use station::runtime::sink::{PointSink, SinkError};
use station::runtime::{CommandPort, NodePoints, Runtime};
use tokio::sync::mpsc;

use crate::edge::{EdgeConfig, EdgeError, EdgeNode, Output, Publish, Refusal, Sample, Write};
use crate::points_map::{self, millis, sample_of_change, sample_of_point};

/// Changes waiting for a node task; past it the sink drops them (counted).
const SINK_QUEUE: usize = 65_536;
/// Changes a node keeps while it cannot publish (no broker, primary host offline).
const OFFLINE_BUFFER: usize = 100_000;
/// Requests waiting for rumqttc's event loop.
const CLIENT_QUEUE: usize = 1024;
/// The wait before reconnecting to a broker that could not be reached.
const RECONNECT_DELAY: Duration = Duration::from_secs(1);

/// Where and how the nodes connect: the station's `[mqtt]` table, or one made from
/// `--mqtt URL` (one concept, kept by the station's configuration).
pub use station::config::MqttConfig;

/// The redundancy group of MQTT hosts' commands when none is configured.
pub const DEFAULT_REDUNDANCY_GROUP: &str = "dispatch";

/// Why the MQTT publisher cannot start.
#[derive(Debug, thiserror::Error)]
pub enum MqttError {
    /// The broker's URL.
    #[error("MQTT URL `{url}`: {reason}")]
    Url {
        /// The URL.
        url: String,
        /// Why.
        reason: String,
    },
    /// The CA file.
    #[error("MQTT CA file {path}: {source}")]
    Ca {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// A node cannot be an edge node.
    #[error("node `{node}`: {source}")]
    Edge {
        /// The node.
        node: String,
        /// Why.
        source: EdgeError,
    },
}

/// The broker's address, from its URL.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct BrokerAddress {
    /// Host name or address.
    pub host: String,
    /// Port.
    pub port: u16,
    /// Over TLS (`mqtts://`).
    pub tls: bool,
}

impl BrokerAddress {
    /// Parses `mqtt://HOST[:PORT]` or `mqtts://HOST[:PORT]`.
    pub fn parse(text: &str) -> Result<BrokerAddress, MqttError> {
        let error = |reason: &str| MqttError::Url {
            url: text.to_owned(),
            reason: reason.to_owned(),
        };
        let url = url::Url::parse(text).map_err(|e| error(&e.to_string()))?;
        let tls = match url.scheme() {
            "mqtt" | "tcp" => false,
            "mqtts" | "ssl" => true,
            _ => return Err(error("the scheme must be mqtt:// or mqtts://")),
        };
        let host = url
            .host_str()
            .filter(|h| !h.is_empty())
            .ok_or_else(|| error("no host"))?
            .trim_start_matches('[')
            .trim_end_matches(']')
            .to_owned();
        if !matches!(url.path(), "" | "/") {
            return Err(error("a broker URL has no path"));
        }
        Ok(BrokerAddress {
            host,
            port: url.port().unwrap_or(if tls { 8883 } else { 1883 }),
            tls,
        })
    }
}

/// Counters of a node's publisher.
#[derive(Debug, Default)]
pub struct MqttStats {
    /// Changes the sink dropped (the node task's queue full).
    pub dropped: AtomicU64,
    /// Messages handed to the MQTT client.
    pub published: AtomicU64,
    /// Node births (NBIRTH) published; each carries its devices' births after it.
    pub births: AtomicU64,
    /// Connections made (each counted once what it had to publish at once is handed on).
    pub connections: AtomicU64,
}

/// A node's changes to its MQTT publisher.
pub struct MqttSink {
    node: String,
    index: Arc<std::collections::HashMap<String, usize>>,
    changes: mpsc::Sender<(usize, Sample)>,
    stats: Arc<MqttStats>,
    broker: String,
}

impl std::fmt::Debug for MqttSink {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("MqttSink")
            .field("node", &self.node)
            .field("broker", &self.broker)
            .finish_non_exhaustive()
    }
}

impl PointSink for MqttSink {
    fn publish(&self, change: &points::PointChange) -> Result<(), SinkError> {
        // Points the node does not own (forwarded from below) have no metric here.
        let Some(&index) = self.index.get(&change.name) else {
            return Ok(());
        };
        match self.changes.try_send((index, sample_of_change(change))) {
            Ok(()) => Ok(()),
            Err(mpsc::error::TrySendError::Full(_)) => {
                let dropped = self.stats.dropped.fetch_add(1, Ordering::Relaxed) + 1;
                if dropped.is_power_of_two() {
                    tracing::warn!(node = %self.node, dropped, "MQTT publisher behind: changes dropped");
                }
                Ok(())
            }
            // The node task has ended (the publisher stopped): nothing to hand over.
            Err(mpsc::error::TrySendError::Closed(_)) => Ok(()),
        }
    }

    fn describe(&self) -> String {
        format!("MQTT Sparkplug B {}", self.broker)
    }
}

/// A node's running publisher.
#[derive(Debug)]
pub struct MqttNode {
    /// The node.
    pub node: String,
    /// Its MQTT client id.
    pub client_id: String,
    /// Its counters.
    pub stats: Arc<MqttStats>,
    /// Hosts' writes of the node's command metrics and the refused ones, in order (taken
    /// by whoever carries them out; [`start_node`] takes them to the node's commands).
    pub writes: Option<mpsc::UnboundedReceiver<HostCommand>>,
    tasks: Vec<tokio::task::JoinHandle<()>>,
}

impl MqttNode {
    /// Stops the publisher at once, as a crash would: the connection is dropped without
    /// DISCONNECT, so the broker publishes the node's will (NDEATH).
    pub fn kill(&self) {
        for task in &self.tasks {
            task.abort();
        }
    }
}

impl Drop for MqttNode {
    fn drop(&mut self) {
        self.kill();
    }
}

/// Makes every node of a running project an edge node (group id the project's name or
/// `settings.group`, edge node id the node's name), each with its own connection.
pub fn start(runtime: &Runtime, settings: &MqttConfig) -> Result<Vec<MqttNode>, MqttError> {
    let group = settings
        .group
        .clone()
        .unwrap_or_else(|| runtime.project().station.name.clone());
    let mut started = Vec::new();
    for node in runtime.nodes() {
        let name = node.points.name();
        let Some(config) = runtime.project().nodes.iter().find(|n| n.name == name) else {
            continue;
        };
        started.push(start_node(
            settings,
            &group,
            config,
            &node.points,
            Some(node.commands.clone()),
        )?);
    }
    Ok(started)
}

/// Makes one node an edge node of `group`; hosts' writes of its command metrics go to
/// `commands` (without it they are refused).
pub fn start_node(
    settings: &MqttConfig,
    group: &str,
    config: &NodeConfig,
    points: &Arc<NodePoints>,
    commands: Option<CommandPort>,
) -> Result<MqttNode, MqttError> {
    // A bad URL is refused before anything is attached to the node.
    BrokerAddress::parse(&settings.url)?;
    let metrics = points_map::node_metrics(config, &points.points());
    let mut edge = EdgeNode::new(
        EdgeConfig {
            group: group.to_owned(),
            edge_node: config.name.clone(),
            primary_host: settings.primary_host.clone(),
            buffer_limit: OFFLINE_BUFFER,
        },
        metrics.specs,
    )
    .map_err(|source| MqttError::Edge {
        node: config.name.clone(),
        source,
    })?;
    let client_id = format!("stanice/{group}/{}", config.name);
    let index = Arc::new(metrics.index);
    // The sink is attached before the values are read: a change in between is both read
    // and queued, and the queued one, applied after, is the newer. The edge node takes
    // the values before its task starts, and the queued changes after.
    let (changes_tx, changes_rx) = mpsc::channel(SINK_QUEUE);
    let stats = Arc::new(MqttStats::default());
    points.attach_sink(Arc::new(MqttSink {
        node: config.name.clone(),
        index: Arc::clone(&index),
        changes: changes_tx,
        stats: Arc::clone(&stats),
        broker: settings.url.clone(),
    }));
    for point in points.points() {
        if let (Some(&i), Some(sample)) = (index.get(&point.spec.name), sample_of_point(&point)) {
            edge.set(i, sample);
        }
    }
    let clock = Arc::clone(points.clock());
    let mut node = spawn_edge(settings, edge, client_id, stats, changes_rx, move || {
        millis(clock.now())
    })?;
    if let (Some(port), Some(writes)) = (commands, node.writes.take()) {
        let actor = format!(
            "MQTT host {} via {}",
            settings.primary_host.as_deref().unwrap_or("(any)"),
            settings.url
        );
        let group = settings
            .redundancy_group
            .clone()
            .unwrap_or_else(|| DEFAULT_REDUNDANCY_GROUP.to_owned());
        node.tasks.push(tokio::spawn(carry_out_writes(
            config.name.clone(),
            port,
            writes,
            actor,
            group,
        )));
    }
    Ok(node)
}

/// Hosts' writes, in order, through the node's command path (routing, authority, audit).
async fn carry_out_writes(
    node: String,
    port: CommandPort,
    mut writes: mpsc::UnboundedReceiver<HostCommand>,
    actor: String,
    group: String,
) {
    let unknown = || points::PointValue::Text("?".to_owned());
    while let Some(command) = writes.recv().await {
        let write = match command {
            HostCommand::Write(write) => write,
            HostCommand::Refused(refusal) => {
                port.audit_refusal(&refusal.metric, unknown(), &refusal.reason, &actor);
                continue;
            }
        };
        let Some(element) = port
            .command_type(&write.metric)
            .and_then(|type_id| points_map::command_element(type_id, &write.value))
        else {
            let value = points::PointValue::Text(format!("{:?}", write.value));
            port.audit_refusal(
                &write.metric,
                value,
                "the value does not fit the command's type",
                &actor,
            );
            continue;
        };
        match port.execute(&write.metric, element, &actor, &group).await {
            Ok(()) => tracing::info!(%node, metric = %write.metric, "MQTT write carried out"),
            Err(error) => tracing::warn!(%node, %error, "MQTT write not carried out"),
        }
    }
}

/// Runs an edge node on its own MQTT connection: `changes` are its metrics' changes (by
/// index), `now` its clock in milliseconds since the Unix epoch.
pub fn spawn_edge(
    settings: &MqttConfig,
    edge: EdgeNode,
    client_id: String,
    stats: Arc<MqttStats>,
    changes: mpsc::Receiver<(usize, Sample)>,
    now: impl Fn() -> u64 + Send + 'static,
) -> Result<MqttNode, MqttError> {
    let broker = BrokerAddress::parse(&settings.url)?;
    let mut options = MqttOptions::new(&client_id, &broker.host, broker.port);
    options.set_keep_alive(Duration::from_secs(15));
    options.set_clean_session(true);
    options.set_max_packet_size(16 * 1024 * 1024, 16 * 1024 * 1024);
    if let Some(user) = &settings.username {
        options.set_credentials(user, settings.password.clone().unwrap_or_default());
    }
    if broker.tls {
        let tls = match &settings.ca {
            Some(path) => TlsConfiguration::Simple {
                ca: std::fs::read(path).map_err(|source| MqttError::Ca {
                    path: path.clone(),
                    source,
                })?,
                alpn: None,
                client_auth: None,
            },
            None => TlsConfiguration::default(),
        };
        options.set_transport(Transport::tls_with_config(tls));
    }
    options.set_last_will(last_will(&edge.will()));
    let (client, eventloop) = AsyncClient::new(options, CLIENT_QUEUE);
    let node = edge.config().edge_node.clone();
    let (events_tx, events_rx) = mpsc::unbounded_channel();
    let (will_tx, will_rx) = mpsc::unbounded_channel();
    let (writes_tx, writes_rx) = mpsc::unbounded_channel();
    let connection = tokio::spawn(connection_task(eventloop, events_tx, will_rx));
    let node_task = tokio::spawn(
        NodeTask {
            edge,
            client,
            now: Box::new(now),
            stats: Arc::clone(&stats),
            writes: writes_tx,
            will: will_tx,
        }
        .run(changes, events_rx),
    );
    tracing::info!(%node, %client_id, broker = %settings.url, "Sparkplug B edge node");
    Ok(MqttNode {
        node,
        client_id,
        stats,
        writes: Some(writes_rx),
        tasks: vec![connection, node_task],
    })
}

/// Drops what the event loop still holds for a lost session (requests queued by the
/// client and not yet sent, and those rumqttc keeps to send first on the next
/// connection); how many.
fn forget_lost_session(eventloop: &mut EventLoop) -> usize {
    eventloop.clean();
    let stale = eventloop.pending.len();
    eventloop.pending.clear();
    stale
}

fn last_will(will: &Publish) -> LastWill {
    LastWill::new(&will.topic, will.payload.clone(), QoS::AtLeastOnce, false)
}

/// A host's command as the node task passes it on.
#[derive(Debug, Clone, PartialEq)]
pub enum HostCommand {
    /// A write to carry out.
    Write(Write),
    /// A write the edge node refused (no such command, another datatype ...).
    Refused(Refusal),
}

/// What the connection task reports.
#[derive(Debug)]
enum ConnectionEvent {
    Connected,
    Message { topic: String, payload: Vec<u8> },
    Lost,
}

async fn connection_task(
    mut eventloop: EventLoop,
    events: mpsc::UnboundedSender<ConnectionEvent>,
    mut wills: mpsc::UnboundedReceiver<Publish>,
) {
    // One warning per outage, not one per attempt (a broker not there yet).
    let mut warned = false;
    loop {
        let event = match eventloop.poll().await {
            Ok(Event::Incoming(Packet::ConnAck(_))) => {
                warned = false;
                ConnectionEvent::Connected
            }
            Ok(Event::Incoming(Packet::Publish(publish))) => ConnectionEvent::Message {
                topic: publish.topic,
                payload: publish.payload.to_vec(),
            },
            Ok(_) => continue,
            Err(error) => {
                let client = &eventloop.mqtt_options.client_id();
                if warned {
                    tracing::debug!(%client, %error, "MQTT broker still not reached");
                } else {
                    tracing::warn!(%client, %error, "MQTT connection lost or refused; retrying every second");
                    warned = true;
                }
                if events.send(ConnectionEvent::Lost).is_err() {
                    return;
                }
                // The next connection's will (its bdSeq) before reconnecting. The node
                // task sends it once it has taken the loss in, so every message it queued
                // for the dead session is queued by now: dropped, so that no NDATA of the
                // old session goes out before the new NBIRTH (rumqttc would send them
                // first on the new connection). The birth carries every current value.
                let Some(will) = wills.recv().await else {
                    return;
                };
                let stale = forget_lost_session(&mut eventloop);
                if stale > 0 {
                    tracing::debug!(%stale, "messages of the lost MQTT session dropped");
                }
                eventloop.mqtt_options.set_last_will(last_will(&will));
                tokio::time::sleep(RECONNECT_DELAY).await;
                continue;
            }
        };
        if events.send(event).is_err() {
            return;
        }
    }
}

struct NodeTask {
    edge: EdgeNode,
    client: AsyncClient,
    now: Box<dyn Fn() -> u64 + Send>,
    stats: Arc<MqttStats>,
    writes: mpsc::UnboundedSender<HostCommand>,
    will: mpsc::UnboundedSender<Publish>,
}

impl NodeTask {
    fn now(&self) -> u64 {
        (self.now)()
    }

    async fn run(
        mut self,
        mut changes: mpsc::Receiver<(usize, Sample)>,
        mut events: mpsc::UnboundedReceiver<ConnectionEvent>,
    ) {
        loop {
            let outputs = tokio::select! {
                change = changes.recv() => match change {
                    Some((index, sample)) => {
                        let now = self.now();
                        self.edge.update(index, sample, now)
                    }
                    None => return,
                },
                event = events.recv() => match event {
                    Some(ConnectionEvent::Connected) => {
                        for topic in self.edge.subscriptions() {
                            if self.client.subscribe(topic, QoS::AtLeastOnce).await.is_err() {
                                return;
                            }
                        }
                        let now = self.now();
                        let outputs = self.edge.connected(now);
                        if self.carry_out(outputs).await.is_err() {
                            return;
                        }
                        self.stats.connections.fetch_add(1, Ordering::Relaxed);
                        Vec::new()
                    }
                    Some(ConnectionEvent::Message { topic, payload }) => {
                        let now = self.now();
                        self.edge.received(&topic, &payload, now)
                    }
                    Some(ConnectionEvent::Lost) => {
                        self.edge.disconnected();
                        if self.will.send(self.edge.will()).is_err() {
                            return;
                        }
                        Vec::new()
                    }
                    None => return,
                },
            };
            if self.carry_out(outputs).await.is_err() {
                return;
            }
        }
    }

    async fn carry_out(&mut self, outputs: Vec<Output>) -> Result<(), rumqttc::ClientError> {
        let node = self.edge.config().edge_node.clone();
        for output in outputs {
            match output {
                Output::Publish(publish) => {
                    if publish.topic.contains("/NBIRTH/") {
                        self.stats.births.fetch_add(1, Ordering::Relaxed);
                    }
                    // Sparkplug sends births and data at QoS 0, not retained.
                    self.client
                        .publish(publish.topic, QoS::AtMostOnce, false, publish.payload)
                        .await?;
                    self.stats.published.fetch_add(1, Ordering::Relaxed);
                }
                Output::Write(write) => {
                    tracing::info!(%node, metric = %write.metric, value = ?write.value, "MQTT write");
                    if self.writes.send(HostCommand::Write(write)).is_err() {
                        tracing::warn!(%node, "MQTT write not carried out: nobody takes the node's writes");
                    }
                }
                Output::Refused(refusal) => {
                    tracing::warn!(%node, metric = %refusal.metric, reason = %refusal.reason, "MQTT write refused");
                    let _ = self.writes.send(HostCommand::Refused(refusal));
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    /// Messages queued for a session that died do not go out on the next connection.
    #[test]
    fn a_lost_sessions_queued_messages_are_forgotten() {
        let options = MqttOptions::new("node", "127.0.0.1", 1);
        let (client, mut eventloop) = AsyncClient::new(options, CLIENT_QUEUE);
        for seq in 0..3u8 {
            client
                .try_publish("spBv1.0/g/NDATA/node", QoS::AtMostOnce, false, vec![seq])
                .unwrap();
        }
        assert_eq!(forget_lost_session(&mut eventloop), 3);
        assert!(eventloop.pending.is_empty());
        assert_eq!(
            forget_lost_session(&mut eventloop),
            0,
            "nothing left to send"
        );
    }
}
