//! The records the store keeps: value changes ([`EventRecord`]) and the command audit
//! ([`CommandRecord`]), with the small enums they are made of.
//!
//! Every enum has a stable numeric code ([`EventCause::code`] and friends): that code, not
//! the Rust discriminant, is what the database holds, so reordering variants never changes
//! stored data.

use chrono::{DateTime, Utc};
use std::fmt;

use points::PointChange;

/// Identifier of a stored row, assigned by the store in increasing order of insertion.
pub type RecordId = i64;

pub use points::{EventCause, PointValue, Quality, SourceTime};

/// The stable code of a value's kind as stored in the `value_kind` column.
pub fn value_kind_code(value: &PointValue) -> i16 {
    match value {
        PointValue::Bool(_) => 1,
        PointValue::DoublePoint(_) => 2,
        PointValue::Int(_) => 3,
        PointValue::Float(_) => 4,
        PointValue::Bits(_) => 5,
        PointValue::Text(_) => 6,
    }
}

/// The quality flags as the stored bit mask: IV = 1, NT = 2, SB = 4, BL = 8, OV = 16 (both
/// backends; the on-the-wire octet differs and is the protocol's business).
pub fn quality_to_bits(quality: Quality) -> u8 {
    u8::from(quality.invalid)
        | u8::from(quality.not_topical) << 1
        | u8::from(quality.substituted) << 2
        | u8::from(quality.blocked) << 3
        | u8::from(quality.overflow) << 4
}

/// The quality flags from the stored bit mask (unknown bits are ignored).
pub fn quality_from_bits(bits: u8) -> Quality {
    Quality {
        invalid: bits & 1 != 0,
        not_topical: bits & 2 != 0,
        substituted: bits & 4 != 0,
        blocked: bits & 8 != 0,
        overflow: bits & 16 != 0,
    }
}

/// The idempotent key of an event: who produced it and its number in that source's
/// sequence. A store keeps one event per key, so writing a batch again (after a crash
/// between its commit and its acknowledgement, or a retry after a lost connection) never
/// stores an event twice. The [`crate::Recorder`] gives every event without a key one of
/// its own; a source that can replay after a restart (a journal, a buffering outstation)
/// sets its own, stable across restarts.
#[derive(Debug, Clone, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct EventKey {
    /// The source's identity (a node, a link, a recorder's run); not empty.
    pub source: String,
    /// The event's number in the source's sequence (at most `i64::MAX`).
    pub sequence: u64,
}

impl EventKey {
    /// The key of event number `sequence` of `source`.
    pub fn new(source: impl Into<String>, sequence: u64) -> EventKey {
        EventKey {
            source: source.into(),
            sequence,
        }
    }
}

/// One recorded value change of a point.
#[derive(Debug, Clone, PartialEq)]
pub struct EventRecord {
    /// Assigned by the store: `None` on append (any value given is ignored), `Some` in query
    /// results.
    pub id: Option<RecordId>,
    /// The node (controller) that owns the point.
    pub node: String,
    /// The point's name in the node's point database.
    pub point: String,
    /// The information object address, when the point has one.
    pub ioa: Option<u32>,
    /// The new value.
    pub value: PointValue,
    /// Quality flags of the value.
    pub quality: Quality,
    /// The source time stamp; `None` when the value came without a time tag.
    pub source_time: Option<SourceTime>,
    /// When this station received or produced the event (its own clock), ms precision.
    pub received_time: DateTime<Utc>,
    /// Why the event was produced.
    pub cause: EventCause,
    /// Where it came from: the link or node name it arrived over (or the node itself).
    pub origin: String,
    /// The idempotent key ([`EventKey`]); `None`: no deduplication.
    pub key: Option<EventKey>,
}

impl EventRecord {
    /// The record of a point database's change: `node` owns the point, `origin` is the
    /// link or node it came over.
    pub fn of_change(change: &PointChange, node: &str, origin: &str) -> EventRecord {
        EventRecord {
            id: None,
            node: node.to_owned(),
            point: change.name.clone(),
            ioa: Some(change.address),
            value: change.value.clone(),
            quality: change.quality,
            source_time: change.source_time,
            received_time: change.received,
            cause: change.cause,
            origin: origin.to_owned(),
            key: None,
        }
    }

    /// A spontaneous good-quality event without IOA or source time; adjust the fields as
    /// needed.
    pub fn new(
        node: impl Into<String>,
        point: impl Into<String>,
        value: PointValue,
        received_time: DateTime<Utc>,
    ) -> EventRecord {
        let node = node.into();
        EventRecord {
            id: None,
            origin: node.clone(),
            node,
            point: point.into(),
            ioa: None,
            value,
            quality: Quality::GOOD,
            source_time: None,
            received_time,
            cause: EventCause::Spontaneous,
            key: None,
        }
    }

    /// The event with the idempotent key `key`.
    pub fn with_key(mut self, key: EventKey) -> EventRecord {
        self.key = Some(key);
        self
    }

    /// The time the event is filed under for [`crate::TimeBasis::Source`]: the source time
    /// when present and valid, otherwise the received time.
    pub fn event_time(&self) -> DateTime<Utc> {
        match self.source_time {
            Some(SourceTime {
                time,
                invalid: false,
            }) => time,
            _ => self.received_time,
        }
    }
}

/// Who issued a command.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub enum Actor {
    /// A logged-in user of the HMI or the command line.
    User(String),
    /// A controlling station over a link, by remote address and, where the station
    /// classifies its clients, redundancy group (`10.0.0.5:40123 (group dispatch)`).
    Remote(String),
}

impl Actor {
    /// The user name or the remote address.
    pub fn name(&self) -> &str {
        match self {
            Actor::User(n) | Actor::Remote(n) => n,
        }
    }
}

impl fmt::Display for Actor {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Actor::User(n) => write!(f, "user {n}"),
            Actor::Remote(a) => write!(f, "remote {a}"),
        }
    }
}

/// The step of a select-before-operate sequence (or a direct execute).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum CommandPhase {
    /// Select (S/E = 1).
    Select,
    /// Execute (S/E = 0), after a select or direct.
    Execute,
}

impl CommandPhase {
    /// The stable stored code.
    pub fn code(self) -> i16 {
        match self {
            CommandPhase::Select => 1,
            CommandPhase::Execute => 2,
        }
    }

    /// The phase with this stored code, if any.
    pub fn from_code(code: i16) -> Option<CommandPhase> {
        match code {
            1 => Some(CommandPhase::Select),
            2 => Some(CommandPhase::Execute),
            _ => None,
        }
    }
}

/// What became of a command.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum CommandOutcome {
    /// Confirmed positively and carried out.
    Executed,
    /// Refused because the target board is in local mode (its Local/Remote switch).
    RefusedLocalMode,
    /// Refused because the user's permission level is too low.
    RefusedPermission,
    /// Refused for another reason (negative confirmation, interlock, unknown point).
    Refused,
    /// Accepted but the execution failed (no feedback, device error).
    Failed,
    /// No confirmation arrived in time.
    TimedOut,
    /// Refused because the control authority is elsewhere (the HMI's board controls while
    /// dispatch holds it, railway spec 9.2).
    RefusedAuthority,
}

impl CommandOutcome {
    /// Every outcome, in code order.
    pub const ALL: [CommandOutcome; 7] = [
        CommandOutcome::Executed,
        CommandOutcome::RefusedLocalMode,
        CommandOutcome::RefusedPermission,
        CommandOutcome::Refused,
        CommandOutcome::Failed,
        CommandOutcome::TimedOut,
        CommandOutcome::RefusedAuthority,
    ];

    /// The stable stored code.
    pub fn code(self) -> i16 {
        match self {
            CommandOutcome::Executed => 1,
            CommandOutcome::RefusedLocalMode => 2,
            CommandOutcome::RefusedPermission => 3,
            CommandOutcome::Refused => 4,
            CommandOutcome::Failed => 5,
            CommandOutcome::TimedOut => 6,
            CommandOutcome::RefusedAuthority => 7,
        }
    }

    /// The outcome with this stored code, if any.
    pub fn from_code(code: i16) -> Option<CommandOutcome> {
        CommandOutcome::ALL.into_iter().find(|c| c.code() == code)
    }
}

/// One audited command.
#[derive(Debug, Clone, PartialEq)]
pub struct CommandRecord {
    /// Assigned by the store: `None` on append (ignored), `Some` in query results.
    pub id: Option<RecordId>,
    /// When the command was issued (or its outcome became known), ms precision.
    pub time: DateTime<Utc>,
    /// Who issued it.
    pub actor: Actor,
    /// The node the command was addressed to.
    pub node: String,
    /// The target point's name.
    pub point: String,
    /// The target's information object address, when it has one.
    pub ioa: Option<u32>,
    /// The commanded value.
    pub value: PointValue,
    /// Select or execute.
    pub phase: CommandPhase,
    /// What became of it.
    pub outcome: CommandOutcome,
    /// Free text: the reason of a refusal, the device's answer, anything for the auditor.
    pub detail: String,
}

#[cfg(test)]
mod tests {
    use super::*;
    use chrono::TimeZone;
    use points::{PointKind, PointType, TimeStamp};

    #[test]
    fn a_change_becomes_its_event_record() {
        let at = |s| Utc.with_ymd_and_hms(2026, 1, 15, 12, 0, s).unwrap();
        let change = PointChange {
            name: "nb".into(),
            address: 6,
            point_type: PointType::new(PointKind::Scaled, TimeStamp::Full),
            value: PointValue::Int(7),
            quality: Quality::GOOD,
            source_time: Some(SourceTime::at(at(1))),
            received: at(2),
            cause: EventCause::ReturnRemote,
            send: true,
        };
        let r = EventRecord::of_change(&change, "RH1.1", "link:RH2");
        assert_eq!(r.node, "RH1.1");
        assert_eq!(r.origin, "link:RH2");
        assert_eq!(r.point, "nb");
        assert_eq!(r.ioa, Some(6));
        assert_eq!(r.value, PointValue::Int(7));
        assert_eq!(r.source_time, Some(SourceTime::at(at(1))));
        assert_eq!(r.received_time, at(2));
        assert_eq!(r.cause, EventCause::ReturnRemote);
        assert_eq!(r.id, None);
    }
}
