//! MQTT Sparkplug B (Sparkplug 3.0, namespace `spBv1.0`) edge nodes for the station: each
//! node of a running project becomes an edge node publishing its own points.
//!
//! ```text
//!  NodePoints ──PointChange──> MqttSink ──bounded channel──> node task (tokio)
//!  (station)      (sink)        (drops counted)              │ EdgeNode (sans-IO core)
//!                                                            │   births, data, seq, bdSeq,
//!                                                            │   buffer, STATE, NCMD
//!                                          rumqttc <─────────┘ publishes / will = NDEATH
//!                                          broker ──NCMD, STATE──> node task ──> writes
//!                                                                        │
//!                       station CommandPort <── checked writes, refusals ┘
//!                       (routing, authority of the MQTT redundancy group, audit)
//! ```
//!
//! | module       | what |
//! |--------------|------|
//! | [`payload`]  | the Sparkplug B protobuf payload as prost messages (field numbers of the published `sparkplug_b.proto`) |
//! | [`datatype`] | data type codes, values and the `Quality` property's codes |
//! | [`topic`]    | the topic namespace: `spBv1.0/{group}/{NBIRTH…DCMD}/{edge}[/{device}]`, `spBv1.0/STATE/{host}` |
//! | [`state`]    | a primary host's STATE JSON payload |
//! | [`edge`]     | the sans-IO edge node: births, NDATA with seq modulo 256, will, rebirth, NCMD writes, primary host and buffering |
//! | `mqtt`       | (feature `tokio`) the rumqttc adapter, one connection per node, and [`MqttSink`](mqtt::MqttSink), the station's point sink |
//! | `points_map` | (feature `tokio`) a station node's points and commands as metrics |
//!
//! Timestamps are the station's clock in milliseconds since the Unix epoch: the wall clock
//! at speed 1; at other speeds the simulated time, so a host sees the station's time.

pub mod datatype;
pub mod edge;
pub mod payload;
pub mod state;
pub mod topic;

#[cfg(feature = "tokio")]
pub mod mqtt;
#[cfg(feature = "tokio")]
pub mod points_map;

pub use datatype::{DataType, QualityCode, Value};
pub use edge::{EdgeConfig, EdgeError, EdgeNode, MetricSpec, Output, Publish, Sample};
pub use payload::{Metric, MetricValue, Payload};
pub use topic::{MessageType, Topic};
