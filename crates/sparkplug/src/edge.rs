//! The sans-IO edge node: the Sparkplug session of one node, fed with the node's metric
//! changes, the broker's connection events and the messages it receives, and answering
//! with the messages to publish and the commands to carry out. Time comes in as
//! milliseconds since the Unix epoch (the station's clock); nothing here does I/O.
//!
//! A session: the will (NDEATH with the session's `bdSeq`) is registered with the
//! connection; once connected (and, with a primary host, once the host's STATE says
//! online) the node publishes NBIRTH with seq 0, `bdSeq`, `Node Control/Rebirth` and
//! every metric with its alias and current value; then NDATA for each change, seq going
//! on modulo 256 without a gap. Changes that cannot go out (no connection, primary host
//! offline) are buffered (the oldest dropped past the limit, counted) and replayed after
//! the next birth, in order, as historical values. A rebirth asked for in NCMD keeps the
//! session and `bdSeq`; a new connection takes the next `bdSeq`.

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
        for (index, metric) in metrics.iter().enumerate() {
            if metric.name == BD_SEQ || metric.name == REBIRTH {
                return Err(EdgeError::ReservedMetric(metric.name.clone()));
            }
            if by_name.insert(metric.name.clone(), index).is_some() {
                return Err(EdgeError::DuplicateMetric(metric.name.clone()));
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

    fn topic(&self, message: MessageType) -> String {
        Topic::node(&self.config.group, message, &self.config.edge_node).to_string()
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

    /// A metric changed (`index` from [`EdgeNode::metric_index`]): NDATA when born, else
    /// buffered for the next birth. An unknown index is ignored.
    pub fn update(&mut self, index: usize, sample: Sample, now: u64) -> Vec<Output> {
        let Some(entry) = self.metrics.get_mut(index) else {
            return Vec::new();
        };
        entry.current = Some(sample.clone());
        if self.born {
            let metric = self.data_metric(index, &sample, false);
            vec![self.data(vec![metric], now)]
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
                if message == MessageType::DCmd {
                    let device = device.unwrap_or_default();
                    return vec![refused(
                        &format!("device {device}"),
                        "this node has no devices",
                    )];
                }
                self.command(payload, now)
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

    fn command(&mut self, payload: &[u8], now: u64) -> Vec<Output> {
        let payload = match Payload::decode_bytes(payload) {
            Ok(payload) => payload,
            Err(error) => return vec![refused("NCMD", &error.to_string())],
        };
        let mut outputs = Vec::new();
        for metric in payload.metrics {
            let label = match (&metric.name, metric.alias) {
                (Some(name), _) => name.clone(),
                (None, Some(alias)) => format!("alias {alias}"),
                (None, None) => "a metric without name or alias".to_owned(),
            };
            let rebirth = metric.name.as_deref() == Some(REBIRTH)
                || (metric.name.is_none() && metric.alias == Some(REBIRTH_ALIAS));
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
            outputs.push(match self.write(&metric) {
                Ok(write) => Output::Write(write),
                Err(reason) => refused(&label, reason),
            });
        }
        outputs
    }

    fn write(&self, metric: &Metric) -> Result<Write, &'static str> {
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

    /// NBIRTH (seq 0) with every metric, then the buffered changes as historical NDATA.
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
        for (index, entry) in self.metrics.iter().enumerate() {
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
        let buffered: Vec<(usize, Sample)> = self.buffer.drain(..).collect();
        for batch in buffered.chunks(REPLAY_BATCH) {
            let metrics = batch
                .iter()
                .map(|(index, sample)| self.data_metric(*index, sample, true))
                .collect();
            outputs.push(self.data(metrics, now));
        }
        outputs
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

    fn data(&mut self, metrics: Vec<Metric>, now: u64) -> Output {
        let payload = Payload {
            timestamp: Some(now),
            metrics,
            seq: Some(u64::from(self.next_seq)),
            ..Payload::default()
        };
        self.next_seq = self.next_seq.wrapping_add(1);
        Output::Publish(Publish {
            topic: self.topic(MessageType::NData),
            payload: payload.to_bytes(),
        })
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
