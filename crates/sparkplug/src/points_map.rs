//! A station node's points and commands as Sparkplug metrics.
//!
//! A node publishes the points it owns: those whose source is its own (a PLC variable, a
//! device, a line, a status), not those it receives over an IEC 104 link from a lower
//! node, which that node publishes itself. Likewise its commands, but those it forwards
//! down a link (the lower node has them). Its commands are writable metrics: single and
//! double commands Boolean (true = ON/close, false = OFF/open), set-points of their IEC
//! type (normalized and float Float, scaled Int16), bitstrings UInt32, regulating steps
//! Boolean (true = higher).
//!
//! The points of a device the node reads (a watched lift's board, a relay or outstation on
//! a serial line, a profiled field device) are that device's metrics, in its DBIRTH and
//! DDATA under the device's name; so are the commands the node forwards to such a device
//! (a host writes them with DCMD). A device whose name cannot stand in a topic stays with
//! the node's own metrics, with a warning. A device's communication alarm (a serial-line
//! device's status point, a profiled device's, a lift board's "not answering") is its
//! DDEATH when it turns TRUE and its new DBIRTH when it turns FALSE.

use std::collections::HashMap;

use iec60870::asdu::{
    CommandQualifier, DoublePointState, Element, RegulatingStepState, SetpointQualifier, TypeId,
};
use points::{Point, PointChange, PointKind, PointSource, PointValue, Quality};
use station::config::{CommandTarget, NodeConfig};

use crate::datatype::{DataType, QualityCode, Value};
use crate::edge::{MetricSpec, Sample};

/// The metrics of a node and the index of each by name.
#[derive(Debug, Clone, Default)]
pub struct NodeMetrics {
    /// The metrics in order: the owned points in declaration order, then the commands.
    pub specs: Vec<MetricSpec>,
    /// Each point's metric index by point name (commands are not points).
    pub index: HashMap<String, usize>,
}

/// Whether the node owns the point (it is not forwarded from a lower node).
pub fn owns(point: &Point) -> bool {
    !matches!(point.spec.source, PointSource::Link { .. })
}

/// The device a point belongs to, as Sparkplug sees devices (`None`: the node's own: a
/// PLC variable, a link's or client group's or a whole line's status).
pub fn point_device(source: &PointSource) -> Option<&str> {
    match source {
        PointSource::Line { device, .. }
        | PointSource::DeviceStatus { device, .. }
        | PointSource::Device { device, .. }
        | PointSource::DeviceComm { device } => Some(device),
        PointSource::Lift { lift, .. } => Some(lift),
        PointSource::Variable(_)
        | PointSource::Link { .. }
        | PointSource::LinkStatus(_)
        | PointSource::ClientStatus(_)
        | PointSource::LineStatus { .. } => None,
    }
}

/// Whether the point is its device's communication alarm (TRUE while the device does not
/// answer): the device's DDEATH and DBIRTH in Sparkplug.
pub fn is_comm_alarm(source: &PointSource) -> bool {
    matches!(
        source,
        PointSource::DeviceStatus { .. }
            | PointSource::DeviceComm { .. }
            | PointSource::Lift {
                signal: points::LiftSignal::NotAnswering,
                ..
            }
    )
}

/// The device a command goes to (`None`: the node's own, a PLC variable).
pub fn command_device(target: &CommandTarget) -> Option<&str> {
    match target {
        CommandTarget::LineObject { device, .. } | CommandTarget::Line { device, .. } => {
            Some(device)
        }
        CommandTarget::Variable(_) | CommandTarget::Link { .. } => None,
    }
}

/// A device id as the metric's device, or `None` (with a warning) when it cannot stand
/// in a topic.
fn device_id(node: &str, metric: &str, device: Option<&str>) -> Option<String> {
    let device = device?;
    if crate::topic::valid_id(device) {
        Some(device.to_owned())
    } else {
        tracing::warn!(%node, %metric, %device, "a device name that cannot stand in a Sparkplug topic: its metric is the node's");
        None
    }
}

/// The metric type of a point kind.
pub fn point_datatype(kind: PointKind) -> DataType {
    match kind {
        PointKind::Single => DataType::Boolean,
        PointKind::Double => DataType::UInt8,
        PointKind::Step => DataType::Int8,
        PointKind::Bitstring => DataType::UInt32,
        PointKind::Normalized | PointKind::Float => DataType::Float,
        PointKind::Scaled => DataType::Int16,
        PointKind::Total => DataType::Int32,
    }
}

/// The metric type of a command type (`None`: not a command a host can write).
pub fn command_datatype(type_id: TypeId) -> Option<DataType> {
    Some(match type_id.value() {
        45 | 46 | 47 | 58 | 59 | 60 => DataType::Boolean,
        48 | 50 | 61 | 63 => DataType::Float,
        49 | 62 => DataType::Int16,
        51 | 64 => DataType::UInt32,
        _ => return None,
    })
}

/// The node's metrics: its owned points, then its own commands (not those forwarded down
/// a link; a command named as a point is left out, with a warning: a metric name is
/// unique).
pub fn node_metrics(config: &NodeConfig, points: &[Point]) -> NodeMetrics {
    let mut metrics = NodeMetrics::default();
    for point in points.iter().filter(|p| owns(p)) {
        metrics
            .index
            .insert(point.spec.name.clone(), metrics.specs.len());
        let device = device_id(
            &config.name,
            &point.spec.name,
            point_device(&point.spec.source),
        );
        metrics.specs.push(MetricSpec {
            name: point.spec.name.clone(),
            datatype: point_datatype(point.spec.point_type.kind),
            writable: false,
            comm_alarm: device.is_some() && is_comm_alarm(&point.spec.source),
            device,
        });
    }
    for command in config
        .commands
        .iter()
        .filter(|c| !matches!(c.target, CommandTarget::Link { .. }))
    {
        let Some(datatype) = command_datatype(command.type_id) else {
            continue;
        };
        if metrics.specs.iter().any(|m| m.name == command.name) {
            tracing::warn!(node = %config.name, command = %command.name, "command not published over MQTT: a point has its name");
            continue;
        }
        metrics.specs.push(MetricSpec {
            name: command.name.clone(),
            datatype,
            writable: true,
            device: device_id(&config.name, &command.name, command_device(&command.target)),
            comm_alarm: false,
        });
    }
    metrics
}

/// The Sparkplug quality of a station quality: invalid is bad, not topical stale.
pub fn quality(quality: Quality) -> QualityCode {
    if quality.invalid {
        QualityCode::Bad
    } else if quality.not_topical {
        QualityCode::Stale
    } else {
        QualityCode::Good
    }
}

/// A point value as a metric value.
pub fn value(value: &PointValue) -> Value {
    match value {
        PointValue::Bool(b) => Value::Bool(*b),
        PointValue::DoublePoint(d) => Value::Int(i64::from(*d)),
        PointValue::Int(i) => Value::Int(*i),
        PointValue::Float(x) => Value::Float(*x),
        PointValue::Bits(b) => Value::Int(i64::from(*b)),
        PointValue::Text(t) => Value::Text(t.clone()),
    }
}

/// Milliseconds since the Unix epoch (0 before it).
pub fn millis(time: chrono::DateTime<chrono::Utc>) -> u64 {
    u64::try_from(time.timestamp_millis()).unwrap_or(0)
}

/// A change as a sample: its value, quality and source time (the station's clock).
pub fn sample_of_change(change: &PointChange) -> Sample {
    let time = change.source_time.map_or(change.received, |s| s.time);
    Sample {
        value: value(&change.value),
        quality: quality(change.quality),
        timestamp: millis(time),
    }
}

/// A point's state as a sample (`None` before its first update).
pub fn sample_of_point(point: &Point) -> Option<Sample> {
    let received = point.received?;
    let time = point.source_time.map_or(received, |s| s.time);
    Some(Sample {
        value: value(&point.value),
        quality: quality(point.quality),
        timestamp: millis(time),
    })
}

/// A host's write of a command metric as the command element of its IEC type (an
/// execute; `None` when the value does not fit the type).
pub fn command_element(type_id: TypeId, value: &Value) -> Option<Element> {
    let qualifier = CommandQualifier::EXECUTE;
    Some(match (type_id.value(), value) {
        (45 | 58, Value::Bool(on)) => Element::SingleCommand { on: *on, qualifier },
        (46 | 59, Value::Bool(on)) => Element::DoubleCommand {
            state: if *on {
                DoublePointState::On
            } else {
                DoublePointState::Off
            },
            qualifier,
        },
        (47 | 60, Value::Bool(higher)) => Element::RegulatingStep {
            state: if *higher {
                RegulatingStepState::Higher
            } else {
                RegulatingStepState::Lower
            },
            qualifier,
        },
        (48 | 61, Value::Float(x)) if (-1.0..=1.0).contains(x) => Element::SetpointNormalized {
            raw: points::normalized::to_raw(*x),
            qualifier: SetpointQualifier::EXECUTE,
        },
        (49 | 62, Value::Int(i)) => Element::SetpointScaled {
            value: i16::try_from(*i).ok()?,
            qualifier: SetpointQualifier::EXECUTE,
        },
        (50 | 63, Value::Float(x)) => Element::SetpointFloat {
            value: *x as f32,
            qualifier: SetpointQualifier::EXECUTE,
        },
        (51 | 64, Value::Int(i)) => Element::BitstringCommand {
            bits: u32::try_from(*i).ok()?,
        },
        _ => return None,
    })
}
