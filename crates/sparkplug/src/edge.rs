//! The sans-IO edge node: the Sparkplug session of one node, fed with the node's metric
//! changes, the broker's connection events and the messages it receives, and answering
//! with the messages to publish and the commands to carry out. Time comes in as
//! milliseconds since the Unix epoch (the station's clock); nothing here does I/O.
//!
//! A session: the will (NDEATH with the session's `bdSeq`) is registered with the
//! connection; once connected (and, with a primary host, once the host's STATE says
//! online) the node publishes NBIRTH with seq 0, `bdSeq`, `Node Control/Rebirth` and
//! every node metric with its alias and current value, then a DBIRTH for each of its
//! devices (a metric's [`MetricSpec::device`]: a lift board, a relay on a serial line, a
//! field device) with that device's metrics; then NDATA or DDATA for each change, one seq
//! for all of the node's messages going on modulo 256 without a gap. Aliases are unique
//! across the node and its devices. A host writes node metrics with NCMD and a device's
//! with DCMD to that device. Changes that cannot go out (no connection, primary host
//! offline) are buffered (the oldest dropped past the limit, counted) and replayed after
//! the next birth, in order, as historical values. A rebirth asked for in NCMD keeps the
//! session and `bdSeq`; a new connection takes the next `bdSeq`.
//!
//! A device that stops answering dies: a metric marked [`MetricSpec::comm_alarm`] (the
//! device's communication alarm, TRUE while it does not answer) turning TRUE publishes
//! the device's DDEATH (with the next seq), and nothing more of the device goes out (its
//! changes are kept as its current values) until the alarm turns FALSE, which publishes a
//! new DBIRTH with the device's metrics as they are then. A device dead at the node's
//! birth gets no DBIRTH, and its buffered changes are not replayed (its values come with
//! its next birth).

use std::collections::{HashMap, VecDeque};

use crate::datatype::{DataType, QualityCode, Value};
use crate::payload::{Metric, MetricValue, Payload, PropertySet, PropertyValue, PropertyValueKind};
use crate::state::HostState;
use crate::topic::{valid_id, MessageType, Topic};

/// The metric carrying the session's birth/death sequence number.
pub const BD_SEQ: &str = "bdSeq";
/// The metric a host writes `true` to for a new birth.
pub const REBIRTH: &str = "Node Control/Rebirth";
/// The alias of [`BD_SEQ`]; a node's own metrics take aliases from [`FIRST_ALIAS`] on.
const BD_SEQ_ALIAS: u64 = 0;
/// The alias of [`REBIRTH`].
const REBIRTH_ALIAS: u64 = 1;
/// The alias of the first of the node's own metrics (in declaration order).
pub const FIRST_ALIAS: u64 = 2;
/// Historical values sent in one NDATA when a buffer is replayed.
const REPLAY_BATCH: usize = 64;

/// One metric of the node.
#[derive(Debug, Clone, PartialEq)]
pub struct MetricSpec {
    /// Its name (the point's name).
    pub name: String,
    /// Its type.
    pub datatype: DataType,
    /// Whether a host may write it (a command).
    pub writable: bool,
    /// The device it belongs to (its DBIRTH, DDATA and DCMD); `None`: the node's own.
    pub device: Option<String>,
    /// The device's communication alarm (a Boolean, TRUE while the device does not
    /// answer): its changes are the device's DDEATH and its next DBIRTH, not DDATA.
    pub comm_alarm: bool,
}

/// A metric's value at a time.
#[derive(Debug, Clone, PartialEq)]
pub struct Sample {
    /// The value.
    pub value: Value,
    /// Its quality.
    pub quality: QualityCode,
    /// When it was taken, in milliseconds since the Unix epoch.
    pub timestamp: u64,
}

/// Who the node is.
#[derive(Debug, Clone, PartialEq)]
pub struct EdgeConfig {
    /// The group id.
    pub group: String,
    /// The edge node id.
    pub edge_node: String,
    /// The host application whose STATE must be online before the node publishes.
    pub primary_host: Option<String>,
    /// Changes kept while the node cannot publish; past it the oldest are dropped.
    pub buffer_limit: usize,
}

/// A message to publish.
#[derive(Debug, Clone, PartialEq)]
pub struct Publish {
    /// Its topic.
    pub topic: String,
    /// Its payload.
    pub payload: Vec<u8>,
}

/// A host's write of a command metric, to be carried out by the node.
#[derive(Debug, Clone, PartialEq)]
pub struct Write {
    /// The metric's name.
    pub metric: String,
    /// The value written, in the metric's type.
    pub value: Value,
}

/// A host's write the node refused, and why.
#[derive(Debug, Clone, PartialEq)]
pub struct Refusal {
    /// The metric, as the host named it (its name, or `alias N`).
    pub metric: String,
    /// Why.
    pub reason: String,
}

/// What the node has to do.
#[derive(Debug, Clone, PartialEq)]
pub enum Output {
    /// Publish this.
    Publish(Publish),
    /// Carry out this write.
    Write(Write),
    /// Record this refusal.
    Refused(Refusal),
}

/// Why an edge node cannot be made.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum EdgeError {
    /// A group, node or host id cannot stand in a topic.
    #[error("`{0}` cannot be a Sparkplug id (empty, or with `/`, `+` or `#`)")]
    InvalidId(String),
    /// Two metrics of one name.
    #[error("metric `{0}` is declared twice")]
    DuplicateMetric(String),
    /// A metric of a reserved name.
    #[error("metric `{0}` has a name Sparkplug reserves")]
    ReservedMetric(String),
    /// A device id that cannot stand in a topic.
    #[error("metric `{metric}`'s device `{device}` cannot be a Sparkplug id (empty, or with `/`, `+` or `#`)")]
    InvalidDevice {
        /// The metric.
        metric: String,
        /// Its device.
        device: String,
    },
}

#[derive(Debug)]
struct Entry {
    spec: MetricSpec,
    current: Option<Sample>,
}

/// One edge node's Sparkplug session.
#[derive(Debug)]
pub struct EdgeNode {
    config: EdgeConfig,
    metrics: Vec<Entry>,
    by_name: HashMap<String, usize>,
    /// The devices, in the order their first metric is declared.
    devices: Vec<String>,
    bd_seq: u64,
    /// The seq of the next NDATA.
    next_seq: u8,
    connected: bool,
    host_online: bool,
    last_host_timestamp: u64,
    /// Birth published in this session (and the host, if any, online since).
    born: bool,
    buffer: VecDeque<(usize, Sample)>,
    dropped: u64,
}

impl EdgeNode {
    /// A node with these metrics, before its first connection (its `bdSeq` is 0).
    pub fn new(config: EdgeConfig, metrics: Vec<MetricSpec>) -> Result<EdgeNode, EdgeError> {
        for id in [&config.group, &config.edge_node]
            .into_iter()
            .chain(config.primary_host.as_ref())
        {
            if !valid_id(id) {
                return Err(EdgeError::InvalidId(id.clone()));
            }
        }
        let mut by_name = HashMap::new();
        let mut devices: Vec<String> = Vec::new();
        for (index, metric) in metrics.iter().enumerate() {
            if metric.name == BD_SEQ || metric.name == REBIRTH {
                return Err(EdgeError::ReservedMetric(metric.name.clone()));
            }
            if by_name.insert(metric.name.clone(), index).is_some() {
                return Err(EdgeError::DuplicateMetric(metric.name.clone()));
            }
            if let Some(device) = &metric.device {
                if !valid_id(device) {
                    return Err(EdgeError::InvalidDevice {
                        metric: metric.name.clone(),
                        device: device.clone(),
                    });
                }
                if !devices.contains(device) {
                    devices.push(device.clone());
                }
            }
        }
        let host_online = config.primary_host.is_none();
        Ok(EdgeNode {
            config,
            metrics: metrics
                .into_iter()
                .map(|spec| Entry {
                    spec,
                    current: None,
                })
                .collect(),
            by_name,
            devices,
            bd_seq: 0,
            next_seq: 0,
            connected: false,
            host_online,
            last_host_timestamp: 0,
            born: false,
            buffer: VecDeque::new(),
            dropped: 0,
        })
    }

    /// Who the node is.
    pub fn config(&self) -> &EdgeConfig {
        &self.config
    }

    /// The `bdSeq` of the current (or next) connection.
    pub fn bd_seq(&self) -> u64 {
        self.bd_seq
    }

    /// Whether the node publishes data now (born, host online).
    pub fn is_born(&self) -> bool {
        self.born
    }

    /// Changes dropped from a full buffer so far.
    pub fn dropped(&self) -> u64 {
        self.dropped
    }

    /// Changes waiting for the next birth.
    pub fn buffered(&self) -> usize {
        self.buffer.len()
    }

    /// The index of a metric by name (the key of [`EdgeNode::update`]).
    pub fn metric_index(&self, name: &str) -> Option<usize> {
        self.by_name.get(name).copied()
    }

    /// The alias of a metric by name.
    pub fn alias_of(&self, name: &str) -> Option<u64> {
        self.metric_index(name)
            .map(|index| index as u64 + FIRST_ALIAS)
    }

    /// The node's devices, in the order of their DBIRTHs.
    pub fn devices(&self) -> &[String] {
        &self.devices
    }

    fn topic(&self, message: MessageType) -> String {
        Topic::node(&self.config.group, message, &self.config.edge_node).to_string()
    }

    /// The topic of a message of the node (`device` `None`) or of one of its devices.
    fn topic_of(&self, message: MessageType, device: Option<&str>) -> String {
        match device {
            None => self.topic(message),
            Some(device) => Topic::Node {
                group: self.config.group.clone(),
                message,
                edge_node: self.config.edge_node.clone(),
                device: Some(device.to_owned()),
            }
            .to_string(),
        }
    }

    /// The device of a metric (`None`: the node's own, or no such metric).
    fn device_of(&self, index: usize) -> Option<&str> {
        self.metrics
            .get(index)
            .and_then(|entry| entry.spec.device.as_deref())
    }

    /// The topics to subscribe to once connected: the node's commands and, with a
    /// primary host, its STATE.
    pub fn subscriptions(&self) -> Vec<String> {
        let mut topics = vec![self.topic(MessageType::NCmd)];
        topics.push(format!(
            "{}/{}/DCMD/{}/+",
            crate::topic::NAMESPACE,
            self.config.group,
            self.config.edge_node
        ));
        if let Some(host) = &self.config.primary_host {
            topics.push(Topic::State { host: host.clone() }.to_string());
        }
        topics
    }

    /// The will of the current connection: NDEATH with its `bdSeq` (to be registered at
    /// QoS 1 before connecting).
    pub fn will(&self) -> Publish {
        let payload = Payload {
            timestamp: None,
            metrics: vec![Metric {
                name: Some(BD_SEQ.to_owned()),
                datatype: Some(DataType::Int64.code()),
                value: Some(MetricValue::LongValue(self.bd_seq)),
                ..Metric::default()
            }],
            ..Payload::default()
        };
        Publish {
            topic: self.topic(MessageType::NDeath),
            payload: payload.to_bytes(),
        }
    }

    /// The connection is up (the will registered): births, when the host allows.
    pub fn connected(&mut self, now: u64) -> Vec<Output> {
        self.connected = true;
        self.born = false;
        if self.host_online {
            self.birth(now)
        } else {
            Vec::new()
        }
    }

    /// The connection is lost: nothing goes out until the next, which takes the next
    /// `bdSeq` (its will to be registered from [`EdgeNode::will`]).
    pub fn disconnected(&mut self) {
        if self.connected {
            self.bd_seq = (self.bd_seq + 1) % 256;
        }
        self.connected = false;
        self.born = false;
    }

    /// A metric's value as it is when the node starts: taken into the next birth, not
    /// sent as a change. An unknown index is ignored.
    pub fn set(&mut self, index: usize, sample: Sample) {
        if let Some(entry) = self.metrics.get_mut(index) {
            entry.current = Some(sample);
        }
    }

    /// A metric changed (`index` from [`EdgeNode::metric_index`]): NDATA or its device's
    /// DDATA when born (a device's death or birth for its communication alarm, nothing
    /// while the device is dead), else buffered for the next birth. An unknown index is
    /// ignored.
    pub fn update(&mut self, index: usize, sample: Sample, now: u64) -> Vec<Output> {
        let Some(entry) = self.metrics.get(index) else {
            return Vec::new();
        };
        let device = entry.spec.device.clone();
        let was_dead = device.as_deref().is_some_and(|d| self.is_dead(d));
        if let Some(entry) = self.metrics.get_mut(index) {
            entry.current = Some(sample.clone());
        }
        if self.born {
            match device {
                Some(device) => {
                    let dead = self.is_dead(&device);
                    match (was_dead, dead) {
                        (false, true) => vec![self.device_death(&device, now)],
                        (true, false) => vec![self.device_birth(&device, now)],
                        (true, true) => Vec::new(),
                        (false, false) => {
                            let metric = self.data_metric(index, &sample, false);
                            vec![self.data(vec![metric], Some(&device), now)]
                        }
                    }
                }
                None => {
                    let metric = self.data_metric(index, &sample, false);
                    vec![self.data(vec![metric], None, now)]
                }
            }
        } else {
            if self.buffer.len() >= self.config.buffer_limit {
                self.buffer.pop_front();
                self.dropped += 1;
            }
            if self.config.buffer_limit > 0 {
                self.buffer.push_back((index, sample));
            }
            Vec::new()
        }
    }

    /// A message from the broker on one of [`EdgeNode::subscriptions`].
    pub fn received(&mut self, topic: &str, payload: &[u8], now: u64) -> Vec<Output> {
        match Topic::parse(topic) {
            Ok(Topic::State { host }) if self.config.primary_host.as_ref() == Some(&host) => {
                self.host_state(payload, now)
            }
            Ok(Topic::Node {
                group,
                message: message @ (MessageType::NCmd | MessageType::DCmd),
                edge_node,
                device,
            }) if group == self.config.group && edge_node == self.config.edge_node => {
                let device = match (message, device) {
                    (MessageType::DCmd, Some(device)) if self.devices.contains(&device) => {
                        Some(device)
                    }
                    (MessageType::DCmd, device) => {
                        return vec![refused(
                            &format!("device {}", device.unwrap_or_default()),
                            "this node has no such device",
                        )];
                    }
                    _ => None,
                };
                self.command(payload, device.as_deref(), now)
            }
            _ => Vec::new(),
        }
    }

    fn host_state(&mut self, payload: &[u8], now: u64) -> Vec<Output> {
        let state = match HostState::parse(payload) {
            Ok(state) => state,
            Err(error) => {
                tracing::warn!(node = %self.config.edge_node, %error, "primary host STATE ignored");
                return Vec::new();
            }
        };
        // An older STATE (a retained one overtaken by a newer) says nothing new.
        if state.timestamp < self.last_host_timestamp {
            return Vec::new();
        }
        self.last_host_timestamp = state.timestamp;
        match (state.online, self.host_online) {
            (true, false) => {
                self.host_online = true;
                if self.connected {
                    self.birth(now)
                } else {
                    Vec::new()
                }
            }
            (false, true) => {
                self.host_online = false;
                self.born = false;
                Vec::new()
            }
            _ => Vec::new(),
        }
    }

    /// A host's NCMD (`device` `None`) or DCMD to `device`.
    fn command(&mut self, payload: &[u8], device: Option<&str>, now: u64) -> Vec<Output> {
        let message = if device.is_some() { "DCMD" } else { "NCMD" };
        let payload = match Payload::decode_bytes(payload) {
            Ok(payload) => payload,
            Err(error) => return vec![refused(message, &error.to_string())],
        };
        let mut outputs = Vec::new();
        for metric in payload.metrics {
            let label = match (&metric.name, metric.alias) {
                (Some(name), _) => name.clone(),
                (None, Some(alias)) => format!("alias {alias}"),
                (None, None) => "a metric without name or alias".to_owned(),
            };
            let rebirth = device.is_none()
                && (metric.name.as_deref() == Some(REBIRTH)
                    || (metric.name.is_none() && metric.alias == Some(REBIRTH_ALIAS)));
            if rebirth {
                match metric.value {
                    Some(MetricValue::BooleanValue(true)) => {
                        if self.connected && self.host_online {
                            outputs.extend(self.birth(now));
                        }
                    }
                    Some(MetricValue::BooleanValue(false)) => {}
                    _ => outputs.push(refused(&label, "Node Control/Rebirth takes a Boolean")),
                }
                continue;
            }
            outputs.push(match self.write(&metric, device) {
                Ok(write) => Output::Write(write),
                Err(reason) => refused(&label, reason),
            });
        }
        outputs
    }

    fn write(&self, metric: &Metric, device: Option<&str>) -> Result<Write, &'static str> {
        let index = match (&metric.name, metric.alias) {
            (Some(name), _) => self.metric_index(name).ok_or("no such metric")?,
            (None, Some(alias)) => alias
                .checked_sub(FIRST_ALIAS)
                .and_then(|i| usize::try_from(i).ok())
                .filter(|i| *i < self.metrics.len())
                .ok_or("no metric of this alias")?,
            (None, None) => return Err("no name or alias"),
        };
        let entry = self.metrics.get(index).ok_or("no such metric")?;
        if entry.spec.device.as_deref() != device {
            return Err(match device {
                None => "a device's metric: write it with DCMD to its device",
                Some(_) => "not a metric of this device",
            });
        }
        if !entry.spec.writable {
            return Err("not writable");
        }
        if let Some(code) = metric.datatype {
            if code != entry.spec.datatype.code() {
                return Err("datatype differs from the birth's");
            }
        }
        let value = metric
            .value
            .as_ref()
            .and_then(|value| entry.spec.datatype.decode(value))
            .ok_or("value missing or not of the metric's type")?;
        Ok(Write {
            metric: entry.spec.name.clone(),
            value,
        })
    }

    /// NBIRTH (seq 0) with the node's metrics, a DBIRTH for each device with its
    /// metrics, then the buffered changes as historical NDATA and DDATA.
    fn birth(&mut self, now: u64) -> Vec<Output> {
        let mut metrics = vec![
            Metric {
                name: Some(BD_SEQ.to_owned()),
                alias: Some(BD_SEQ_ALIAS),
                timestamp: Some(now),
                datatype: Some(DataType::Int64.code()),
                value: Some(MetricValue::LongValue(self.bd_seq)),
                ..Metric::default()
            },
            Metric {
                name: Some(REBIRTH.to_owned()),
                alias: Some(REBIRTH_ALIAS),
                timestamp: Some(now),
                datatype: Some(DataType::Boolean.code()),
                value: Some(MetricValue::BooleanValue(false)),
                ..Metric::default()
            },
        ];
        metrics.extend(self.birth_metrics(None, now));
        let birth = Payload {
            timestamp: Some(now),
            metrics,
            seq: Some(0),
            ..Payload::default()
        };
        self.next_seq = 1;
        self.born = true;
        let mut outputs = vec![Output::Publish(Publish {
            topic: self.topic(MessageType::NBirth),
            payload: birth.to_bytes(),
        })];
        for device in self.devices.clone() {
            if !self.is_dead(&device) {
                outputs.push(self.device_birth(&device, now));
            }
        }
        // The buffer in order, each run of one device's (or the node's) changes in
        // messages of at most REPLAY_BATCH metrics; a dead device's are left out.
        let buffered: Vec<(usize, Sample)> = self.buffer.drain(..).collect();
        let mut run: Vec<Metric> = Vec::new();
        let mut run_device: Option<String> = None;
        for (index, sample) in &buffered {
            let device = self.device_of(*index).map(str::to_owned);
            if device.as_deref().is_some_and(|d| self.is_dead(d)) {
                continue;
            }
            if !run.is_empty() && (device != run_device || run.len() == REPLAY_BATCH) {
                let metrics = std::mem::take(&mut run);
                outputs.push(self.data(metrics, run_device.as_deref(), now));
            }
            run_device = device;
            run.push(self.data_metric(*index, sample, true));
        }
        if !run.is_empty() {
            outputs.push(self.data(run, run_device.as_deref(), now));
        }
        outputs
    }

    /// Whether `device` does not answer: its communication alarm is TRUE.
    fn is_dead(&self, device: &str) -> bool {
        self.metrics.iter().any(|entry| {
            entry.spec.comm_alarm
                && entry.spec.device.as_deref() == Some(device)
                && entry
                    .current
                    .as_ref()
                    .is_some_and(|sample| sample.value == Value::Bool(true))
        })
    }

    /// The DBIRTH of `device` with its metrics as they are, with the node's next seq.
    fn device_birth(&mut self, device: &str, now: u64) -> Output {
        let metrics = self.birth_metrics(Some(device), now);
        self.sequenced(MessageType::DBirth, Some(device), metrics, now)
    }

    /// The DDEATH of `device`: a timestamp and the node's next seq, no metrics.
    fn device_death(&mut self, device: &str, now: u64) -> Output {
        self.sequenced(MessageType::DDeath, Some(device), Vec::new(), now)
    }

    /// A message of the node (`device` `None`) or of a device, with these metrics, a
    /// timestamp and the node's next seq (every message after the NBIRTH takes one).
    fn sequenced(
        &mut self,
        message: MessageType,
        device: Option<&str>,
        metrics: Vec<Metric>,
        now: u64,
    ) -> Output {
        let payload = Payload {
            timestamp: Some(now),
            metrics,
            seq: Some(u64::from(self.next_seq)),
            ..Payload::default()
        };
        self.next_seq = self.next_seq.wrapping_add(1);
        Output::Publish(Publish {
            topic: self.topic_of(message, device),
            payload: payload.to_bytes(),
        })
    }

    /// The birth metrics of the node's own metrics (`device` `None`) or of a device's:
    /// name, alias, type, current value (null before the first), `Writable` for commands.
    fn birth_metrics(&self, device: Option<&str>, now: u64) -> Vec<Metric> {
        let mut metrics = Vec::new();
        for (index, entry) in self.metrics.iter().enumerate() {
            if entry.spec.device.as_deref() != device {
                continue;
            }
            let mut metric = match &entry.current {
                Some(sample) => value_metric(entry.spec.datatype, sample),
                None => Metric {
                    timestamp: Some(now),
                    is_null: Some(true),
                    ..Metric::default()
                },
            };
            metric.name = Some(entry.spec.name.clone());
            metric.alias = Some(index as u64 + FIRST_ALIAS);
            metric.datatype = Some(entry.spec.datatype.code());
            if entry.spec.writable {
                let properties = metric.properties.get_or_insert_with(PropertySet::default);
                properties.keys.push("Writable".to_owned());
                properties.values.push(PropertyValue {
                    r#type: Some(DataType::Boolean.code()),
                    is_null: None,
                    value: Some(PropertyValueKind::BooleanValue(true)),
                });
            }
            metrics.push(metric);
        }
        metrics
    }

    fn data_metric(&self, index: usize, sample: &Sample, historical: bool) -> Metric {
        let datatype = self
            .metrics
            .get(index)
            .map_or(DataType::Int64, |entry| entry.spec.datatype);
        let mut metric = value_metric(datatype, sample);
        metric.alias = Some(index as u64 + FIRST_ALIAS);
        if historical {
            metric.is_historical = Some(true);
        }
        metric
    }

    /// NDATA (`device` `None`) or DDATA of `device`, with the node's next seq.
    fn data(&mut self, metrics: Vec<Metric>, device: Option<&str>, now: u64) -> Output {
        let message = if device.is_some() {
            MessageType::DData
        } else {
            MessageType::NData
        };
        self.sequenced(message, device, metrics, now)
    }
}

/// A metric with a sample's value, timestamp and `Quality` (the value left out, `is_null`,
/// when it does not fit the type).
fn value_metric(datatype: DataType, sample: &Sample) -> Metric {
    let value = datatype.encode(&sample.value);
    Metric {
        timestamp: Some(sample.timestamp),
        is_null: value.is_none().then_some(true),
        value,
        properties: Some(PropertySet {
            keys: vec![QualityCode::PROPERTY.to_owned()],
            values: vec![PropertyValue {
                r#type: Some(DataType::Int32.code()),
                is_null: None,
                value: Some(PropertyValueKind::IntValue(sample.quality.code() as u32)),
            }],
        }),
        ..Metric::default()
    }
}

fn refused(metric: &str, reason: &str) -> Output {
    Output::Refused(Refusal {
        metric: metric.to_owned(),
        reason: reason.to_owned(),
    })
}
