//! Where a node's point changes go besides the store: the protocols that serve them to
//! the levels above. Today each node with a `[node.server]` has one, its IEC 104 server;
//! an IEC 101 slave on a serial line, an MQTT publisher or a gateway's 104 server are
//! further sinks of the same node, attached with [`NodePoints::attach_sink`]. Each gets
//! every change in the order the point database took it, once the store has committed
//! it (the recorder's writer calls them: a sink must not block).
//!
//! [`NodePoints::attach_sink`]: super::NodePoints::attach_sink

use iec60870::cs104::server::ServerHandle;

use iec60870::time::TimeZonePolicy;
use points::PointChange;

/// Why a sink did not take a change: its own error (a sink is another crate's protocol,
/// whose error type the node does not know).
pub type SinkError = Box<dyn std::error::Error + Send + Sync>;

/// A consumer of a node's point changes.
pub trait PointSink: Send + Sync + std::fmt::Debug {
    /// Takes one change; an error is logged with the sink's name and the point, and the
    /// other sinks and the store still get the change.
    fn publish(&self, change: &PointChange) -> Result<(), SinkError>;

    /// What the sink is, for logs (`IEC 104 server 127.0.0.1:2404`).
    fn describe(&self) -> String;
}

/// A node's IEC 104 server as a sink: changes to be sent go out spontaneously (or with
/// their cause), the others only update its process image.
#[derive(Debug, Clone)]
pub struct Iec104Sink {
    /// The server.
    pub server: ServerHandle,
    /// The zone of the time tags it sends.
    pub zone: TimeZonePolicy,
}

impl PointSink for Iec104Sink {
    fn publish(&self, change: &PointChange) -> Result<(), SinkError> {
        Ok(points_iec::publish(change, &self.server, self.zone)?)
    }

    fn describe(&self) -> String {
        format!("IEC 104 server {}", self.server.local_addr())
    }
}
