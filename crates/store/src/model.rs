//! The records the store keeps: value changes ([`EventRecord`]) and the command audit
//! ([`CommandRecord`]), with the small enums they are made of.
//!
//! Every enum has a stable numeric code ([`EventCause::code`] and friends): that code, not
//! the Rust discriminant, is what the database holds, so reordering variants never changes
//! stored data.

use chrono::{DateTime, Utc};
use std::fmt;

/// Identifier of a stored row, assigned by the store in increasing order of insertion.
pub type RecordId = i64;

/// A typed point value, as the point database holds it.
#[derive(Debug, Clone, PartialEq)]
pub enum PointValue {
    /// Single-point information or a single command (on/off).
    Bool(bool),
    /// Double-point information or a double command: 0 and 3 indeterminate, 1 off, 2 on.
    DoublePoint(u8),
    /// Step position, scaled value, integrated total or any other integer.
    Int(i64),
    /// Normalized or short floating-point value.
    Float(f64),
    /// Bitstring of 32 bits.
    Bits(u32),
    /// Free text (device messages, fault descriptions).
    Text(String),
}

impl PointValue {
    /// The stable code of the value's kind as stored in the `value_kind` column.
    pub fn kind_code(&self) -> i16 {
        match self {
            PointValue::Bool(_) => 1,
            PointValue::DoublePoint(_) => 2,
            PointValue::Int(_) => 3,
            PointValue::Float(_) => 4,
            PointValue::Bits(_) => 5,
            PointValue::Text(_) => 6,
        }
    }
}

impl fmt::Display for PointValue {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            PointValue::Bool(b) => write!(f, "{}", if *b { "ON" } else { "OFF" }),
            PointValue::DoublePoint(0) => f.write_str("INTERMEDIATE"),
            PointValue::DoublePoint(1) => f.write_str("OFF"),
            PointValue::DoublePoint(2) => f.write_str("ON"),
            PointValue::DoublePoint(_) => f.write_str("INDETERMINATE"),
            PointValue::Int(i) => write!(f, "{i}"),
            PointValue::Float(x) => write!(f, "{x}"),
            PointValue::Bits(b) => write!(f, "0x{b:08X}"),
            PointValue::Text(t) => f.write_str(t),
        }
    }
}

/// Quality descriptor of a value: the IEC 60870-5 flags IV, NT, SB, BL and OV, the same
/// type the protocol stack uses, so values pass between link, point database and store
/// without conversion.
pub use iec60870::asdu::Quality;

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

/// The source time stamp of an event, as the outstation tagged it (the instant its
/// CP56Time2a stands for under the link's time zone policy, with the tag's IV bit).
pub use iec60870::time::SourceTime;

/// Why an event was produced (the cause of transmission, as the station sees it).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum EventCause {
    /// A spontaneous change (COT 3).
    Spontaneous,
    /// An answer to a (general or group) interrogation (COT 20..36).
    Interrogated,
    /// A cyclic or periodic transmission (COT 1).
    Cyclic,
    /// The result of a command (COT 11/12 as seen by the point database).
    Command,
    /// A local change at the node itself (local operation, PLC logic).
    Local,
    /// Return information caused by a remote command (COT 11).
    ReturnRemote,
    /// Return information caused by a local command (COT 12).
    ReturnLocal,
}

impl EventCause {
    /// Every cause, in code order.
    pub const ALL: [EventCause; 7] = [
        EventCause::Spontaneous,
        EventCause::Interrogated,
        EventCause::Cyclic,
        EventCause::Command,
        EventCause::Local,
        EventCause::ReturnRemote,
        EventCause::ReturnLocal,
    ];

    /// The stable stored code.
    pub fn code(self) -> i16 {
        match self {
            EventCause::Spontaneous => 1,
            EventCause::Interrogated => 2,
            EventCause::Cyclic => 3,
            EventCause::Command => 4,
            EventCause::Local => 5,
            EventCause::ReturnRemote => 6,
            EventCause::ReturnLocal => 7,
        }
    }

    /// The cause with this stored code, if any.
    pub fn from_code(code: i16) -> Option<EventCause> {
        EventCause::ALL.into_iter().find(|c| c.code() == code)
    }

    /// Why a monitor value received from an outstation was sent, by its cause of
    /// transmission; `None` for causes that carry no process value (activation,
    /// confirmations, the negative mirrors 44..47, initialisation).
    ///
    /// Every receiver of monitor data (a concentrator's link, the HMI, a gateway's line)
    /// classifies with this one table.
    pub fn of_received(cause: iec60870::asdu::Cause) -> Option<EventCause> {
        match cause.value() {
            1 => Some(EventCause::Cyclic),
            2 | 3 | 5 => Some(EventCause::Spontaneous),
            11 => Some(EventCause::ReturnRemote),
            12 => Some(EventCause::ReturnLocal),
            20..=36 => Some(EventCause::Interrogated),
            _ => None,
        }
    }

    /// Whether a monitor value received with this cause of transmission is an event in
    /// its own right, to be passed on even when equal to the last value: a spontaneous
    /// change (3) or return information (11, 12). An interrogated, cyclic, background or
    /// read value that did not change is no news.
    pub fn received_as_event(cause: iec60870::asdu::Cause) -> bool {
        matches!(cause.value(), 3 | 11 | 12)
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
}

impl EventRecord {
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
        }
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
    /// A controlling station over a link, by remote address (for example `10.0.0.5:40123`).
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
