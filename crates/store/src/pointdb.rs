//! A node's point database: typed values with quality and source time, report by
//! exception, bulk invalidation and communication-status points.
//!
//! Every node (controller) holds one [`PointDb`], built from the [`PointSpec`]s of its
//! project. Values arrive from the node's PLC, its I/O or a lower node's IEC 104 link
//! ([`PointDb::update`]); the database checks them against the point's IEC type, keeps
//! the newest one and returns a [`PointChange`] only when something worth reporting
//! changed:
//!
//! - **Report by exception.** A change is returned when the value or the quality differs
//!   from the last *reported* one (before the first update: the type's zero with IV, the
//!   state interrogation shows). For measured values (normalized, scaled and floating
//!   point types) with a deadband, a value change smaller than the deadband since the last
//!   reported value is not reported (a change equal to the deadband is); the database
//!   still holds the new value. A quality change is always reported.
//! - **Wire precision.** Values are quantized to their wire representation on update: a
//!   normalized value is kept as `raw / 32768` with `raw = round(x * 32768)` (1.0
//!   saturates to `32767`, the largest raw value), a short float as the nearest `f32`.
//!   "Unchanged" therefore means "unchanged on the wire", and element round trips are
//!   exact.
//! - **Invalidation.** [`PointDb::invalidate_where`] and [`PointDb::invalidate_link`]
//!   set IV on the affected points (keeping their last value), as the TC700 does for the
//!   points of a failed I/O module (spec §7.2) and as a concentrator does for the points of
//!   a lower link that went down. The next good update clears IV again and is reported.
//! - **Communication status.** [`PointDb::set_link_status`] sets a single point to
//!   `NOT CommEnabled` (TRUE = communication failure), as the TC700's points 32..41 (§7.3).
//! - **Cyclic points.** [`PointDb::due_cyclic`] returns the cyclic points whose period
//!   elapsed; time is a parameter, the database never reads a clock.
//!
//! A change feeds the node's IEC 104 server ([`PointChange::to_element`],
//! [`PointChange::time_tag`], [`PointChange::iec_cause`]: `ServerHandle::update_with_cause`
//! when [`PointChange::send`] is set, `ServerHandle::set` otherwise) and the event store
//! ([`PointChange::to_event_record`]). [`from_element`] is the reverse, for points
//! concentrated from a lower node's IEC 104 data.
//!
//! Supported monitor types: single point (M_SP_*), double point (M_DP_*), step position
//! (M_ST_*), bitstring (M_BO_*), normalized (M_ME_NA/TA/TD/ND), scaled (M_ME_NB/TB/TE),
//! short float (M_ME_NC/TC/TF) and integrated totals (M_IT_*). Protection events (M_EP_*)
//! and packed single points (M_PS_NA_1) are refused.

use std::collections::HashMap;
use std::time::Duration;

use chrono::{DateTime, Utc};
use iec60870::asdu::{
    BinaryCounterReading, Cause, Cp56Time2a, DoublePointState, Element, Ioa, StepPosition, TimeTag,
    TypeId,
};
use iec60870::cs104::server::{ImageError, MonitorPoint, ProcessImage, ServerError, ServerHandle};

use crate::{EventCause, EventRecord, PointValue, Quality, SourceTime};

/// Where a point's value comes from.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub enum PointSource {
    /// A PLC variable path of the node.
    Variable(String),
    /// Point `ioa` received over the node's client link `link`.
    Link {
        /// The link's name.
        link: String,
        /// The IOA on the lower node.
        ioa: Ioa,
    },
    /// The state of the node's client link with this name (TRUE = link down), for a point
    /// named by the link's `status_point`; such a point has no `source`.
    LinkStatus(String),
    /// Whether a controlling station of the server's redundancy group with this name is
    /// connected (TRUE = none is), for a point named by the group's `status_point`.
    ClientStatus(String),
    /// A signal of a device on one of the node's serial lines (`line:LINE/DEVICE/...`).
    Line {
        /// The line's name.
        line: String,
        /// The device's name on the line.
        device: String,
        /// Which of the device's signals.
        signal: LineSignal,
    },
    /// Whether any device on a serial line answers (TRUE = none does), for a point named
    /// by the line's `status_point`.
    LineStatus {
        /// The line's name.
        line: String,
    },
    /// Whether a device on a serial line answers (TRUE = it does not), for a point named
    /// by the device's `status_point`.
    DeviceStatus {
        /// The line's name.
        line: String,
        /// The device's name.
        device: String,
    },
    /// A value of a watched lift (`[[node.lift]]`): the points each lift brings.
    Lift {
        /// The lift's name.
        lift: String,
        /// Which of its values.
        signal: LiftSignal,
    },
}

/// A value of a lift watched through its controller board (the points of a
/// `[[node.lift]]`, one per signal, at the lift's `ioa_base` + [`LiftSignal::offset`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum LiftSignal {
    /// The board's status code.
    Status,
    /// The status's colour class: 0 normal (green), 1 attention (orange), 2 fault (red).
    Colour,
    /// The car's floor.
    Position,
    /// The target floor of the trip.
    Target,
    /// 0 stopped, 1 up, 2 down (whatever the board's own coding).
    Direction,
    /// 0 unknown, 1 closed, 2 partly open, 3 open, 4 door fault.
    Door,
    /// TRUE while the board does not answer (the communication alarm).
    NotAnswering,
    /// TRUE while the lift is out of service (a fault status).
    OutOfService,
    /// TRUE while the lift is in inspection (maintenance) mode.
    Inspection,
    /// The code of the newest fault archived.
    LastFault,
    /// Line errors counted by the poller (time-outs, invalid frames).
    Errors,
    /// Faults archived from the board's log.
    Faults,
    /// Trips, all floors together.
    Trips,
    /// Trips to floor N (1-based).
    FloorTrips(u8),
}

impl LiftSignal {
    /// The least time between two stored changes of the signal's point, for the signals
    /// that change on every poll while something is wrong: a silent board's line-error
    /// count grew every 0.5 s, 170,000 stored events a day per cut cable. The point is
    /// still sent on every change; the store keeps the first change of each interval
    /// (and every change of quality). `None`: every change is stored.
    pub fn storage_interval(self) -> Option<std::time::Duration> {
        match self {
            LiftSignal::Errors => Some(std::time::Duration::from_secs(60)),
            _ => None,
        }
    }

    /// The signals every lift has, in IOA order (the floors' trip counters follow them).
    pub const COMMON: [LiftSignal; 13] = [
        LiftSignal::Status,
        LiftSignal::Colour,
        LiftSignal::Position,
        LiftSignal::Target,
        LiftSignal::Direction,
        LiftSignal::Door,
        LiftSignal::NotAnswering,
        LiftSignal::OutOfService,
        LiftSignal::Inspection,
        LiftSignal::LastFault,
        LiftSignal::Errors,
        LiftSignal::Faults,
        LiftSignal::Trips,
    ];

    /// The first offset of the floors' trip counters: the common signals leave room for
    /// three more before them.
    pub const FLOOR_TRIPS_OFFSET: u32 = 16;

    /// Its IOA's offset from the lift's `ioa_base`.
    pub fn offset(self) -> u32 {
        match self {
            LiftSignal::Status => 0,
            LiftSignal::Colour => 1,
            LiftSignal::Position => 2,
            LiftSignal::Target => 3,
            LiftSignal::Direction => 4,
            LiftSignal::Door => 5,
            LiftSignal::NotAnswering => 6,
            LiftSignal::OutOfService => 7,
            LiftSignal::Inspection => 8,
            LiftSignal::LastFault => 9,
            LiftSignal::Errors => 10,
            LiftSignal::Faults => 11,
            LiftSignal::Trips => 12,
            LiftSignal::FloorTrips(floor) => {
                Self::FLOOR_TRIPS_OFFSET + u32::from(floor.saturating_sub(1))
            }
        }
    }

    /// The point name's suffix after `LIFT.`: `status`, `floor3_trips` ...
    pub fn suffix(self) -> String {
        match self {
            LiftSignal::Status => "status".into(),
            LiftSignal::Colour => "colour".into(),
            LiftSignal::Position => "position".into(),
            LiftSignal::Target => "target".into(),
            LiftSignal::Direction => "direction".into(),
            LiftSignal::Door => "door".into(),
            LiftSignal::NotAnswering => "not_answering".into(),
            LiftSignal::OutOfService => "out_of_service".into(),
            LiftSignal::Inspection => "inspection".into(),
            LiftSignal::LastFault => "last_fault".into(),
            LiftSignal::Errors => "errors".into(),
            LiftSignal::Faults => "faults".into(),
            LiftSignal::Trips => "trips".into(),
            LiftSignal::FloorTrips(floor) => format!("floor{floor}_trips"),
        }
    }

    /// The IEC 104 type its point is sent as: indications as single points, codes and
    /// floors as scaled values, counts as integrated totals, all with CP56 time tags.
    pub fn type_id(self) -> TypeId {
        match self {
            LiftSignal::NotAnswering | LiftSignal::OutOfService | LiftSignal::Inspection => {
                TypeId::M_SP_TB_1
            }
            LiftSignal::Errors
            | LiftSignal::Faults
            | LiftSignal::Trips
            | LiftSignal::FloorTrips(_) => TypeId::M_IT_TB_1,
            _ => TypeId::M_ME_TE_1,
        }
    }

    /// What the point shows, for the point list.
    pub fn description(self) -> String {
        match self {
            LiftSignal::Status => "status code (EKM66 Appendix A)".into(),
            LiftSignal::Colour => "status colour: 0 normal, 1 attention, 2 fault".into(),
            LiftSignal::Position => "car floor".into(),
            LiftSignal::Target => "target floor".into(),
            LiftSignal::Direction => "direction: 0 stopped, 1 up, 2 down".into(),
            LiftSignal::Door => "doors: 0 unknown, 1 closed, 2 partly open, 3 open, 4 fault".into(),
            LiftSignal::NotAnswering => "board not answering (communication alarm)".into(),
            LiftSignal::OutOfService => "out of service".into(),
            LiftSignal::Inspection => "inspection mode".into(),
            LiftSignal::LastFault => "newest archived fault code (Appendix B)".into(),
            LiftSignal::Errors => "line errors (time-outs, invalid replies)".into(),
            LiftSignal::Faults => "faults archived".into(),
            LiftSignal::Trips => "trips, all floors".into(),
            LiftSignal::FloorTrips(floor) => format!("trips to floor {floor}"),
        }
    }
}

/// A signal of a device on a serial line, as its protocol names it.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub enum LineSignal {
    /// A protection device (IEC 103): the indication FUN/INF, or with `index` the
    /// index-th value of the measurand set FUN/INF.
    Iec103 {
        /// Function type.
        fun: u8,
        /// Information number.
        inf: u8,
        /// The position in a measurand set; `None` for an indication.
        index: Option<u8>,
    },
    /// An outstation (IEC 101): its information object at this address.
    Iec101 {
        /// The outstation's IOA.
        ioa: Ioa,
    },
}

/// How a point is transmitted upward.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Transmission {
    /// Sent spontaneously (COT 3) on every reported change.
    Spontaneous,
    /// Sent periodically (COT 1) with this period; changes only update the image.
    Cyclic(Duration),
    /// Only answered to interrogations; changes only update the image.
    InterrogationOnly,
}

/// The declaration of one point of a node.
#[derive(Debug, Clone, PartialEq)]
pub struct PointSpec {
    /// Unique name within the node.
    pub name: String,
    /// The monitor type used for spontaneous transmission (e.g. `M_SP_TB_1`).
    pub type_id: TypeId,
    /// Unique information object address within the node.
    pub ioa: Ioa,
    /// How the point is transmitted.
    pub transmission: Transmission,
    /// Interrogation groups 1..=16, bit 0 = group 1.
    pub groups: u16,
    /// Deadband for measured values (normalized, scaled, float), in the value's unit
    /// (a fraction for normalized values); `None` reports every change.
    pub deadband: Option<f64>,
    /// Where the value comes from (a PLC variable, a point over a link, a status), typed
    /// as the project says it: invalidation on a link's loss picks its points by it.
    pub source: PointSource,
    /// Free description.
    pub description: String,
}

/// Why a point database could not be built or a value was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PointDbError {
    /// Two points share a name.
    #[error("duplicate point name `{0}`")]
    DuplicateName(String),
    /// Two points share an IOA.
    #[error("points `{first}` and `{second}` share information object address {ioa}")]
    DuplicateIoa {
        /// The address.
        ioa: Ioa,
        /// The point declared first.
        first: String,
        /// The point declared second.
        second: String,
    },
    /// A point has an empty name.
    #[error("a point (IOA {0}) has an empty name")]
    EmptyName(Ioa),
    /// The point's type is not a supported monitor type.
    #[error("point `{name}`: type {type_id} is not supported by the point database")]
    UnsupportedType {
        /// Point name.
        name: String,
        /// Its type.
        type_id: TypeId,
    },
    /// A deadband on a non-measurement type, or a negative or non-finite one.
    #[error("point `{name}`: invalid deadband {deadband} (only finite, non-negative, on measured values)")]
    InvalidDeadband {
        /// Point name.
        name: String,
        /// The deadband.
        deadband: f64,
    },
    /// A cyclic point with a zero period.
    #[error("point `{0}`: cyclic period must be positive")]
    ZeroPeriod(String),
    /// No point with that name, IOA or id.
    #[error("unknown point {0}")]
    UnknownPoint(String),
    /// The value does not fit the point's type.
    #[error("point `{name}` ({type_id}): value {value} refused: {reason}")]
    ValueRefused {
        /// Point name.
        name: String,
        /// Its type.
        type_id: TypeId,
        /// The value given (displayed).
        value: String,
        /// Why.
        reason: &'static str,
    },
    /// An element that does not fit the type it was decoded for.
    #[error("element {element} does not fit type {type_id}")]
    ElementMismatch {
        /// The type.
        type_id: TypeId,
        /// The element's short name.
        element: &'static str,
    },
    /// The process image refused a point (should not happen for a checked database).
    #[error("process image: {0}")]
    Image(#[from] ImageError),
}

/// Index of a point in its database (declaration order), a cheap handle for hot paths.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct PointId(pub usize);

/// How a point is named in a call: by name, by IOA or by id.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PointKey<'a> {
    /// By name.
    Name(&'a str),
    /// By information object address.
    Ioa(Ioa),
    /// By id.
    Id(PointId),
}

impl<'a> From<&'a str> for PointKey<'a> {
    fn from(name: &'a str) -> Self {
        PointKey::Name(name)
    }
}

impl<'a> From<&'a String> for PointKey<'a> {
    fn from(name: &'a String) -> Self {
        PointKey::Name(name)
    }
}

impl From<Ioa> for PointKey<'_> {
    fn from(ioa: Ioa) -> Self {
        PointKey::Ioa(ioa)
    }
}

impl From<PointId> for PointKey<'_> {
    fn from(id: PointId) -> Self {
        PointKey::Id(id)
    }
}

impl std::fmt::Display for PointKey<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            PointKey::Name(n) => write!(f, "`{n}`"),
            PointKey::Ioa(ioa) => write!(f, "with IOA {ioa}"),
            PointKey::Id(id) => write!(f, "#{}", id.0),
        }
    }
}

pub use iec60870::time::TimeZonePolicy;

/// The value kinds, one per supported element family.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    Single,
    Double,
    Step,
    Bitstring,
    Normalized,
    Scaled,
    Float,
    Total,
}

impl Kind {
    fn of(type_id: TypeId) -> Option<Kind> {
        use TypeId::*;
        Some(match type_id {
            M_SP_NA_1 | M_SP_TA_1 | M_SP_TB_1 => Kind::Single,
            M_DP_NA_1 | M_DP_TA_1 | M_DP_TB_1 => Kind::Double,
            M_ST_NA_1 | M_ST_TA_1 | M_ST_TB_1 => Kind::Step,
            M_BO_NA_1 | M_BO_TA_1 | M_BO_TB_1 => Kind::Bitstring,
            M_ME_NA_1 | M_ME_TA_1 | M_ME_TD_1 | M_ME_ND_1 => Kind::Normalized,
            M_ME_NB_1 | M_ME_TB_1 | M_ME_TE_1 => Kind::Scaled,
            M_ME_NC_1 | M_ME_TC_1 | M_ME_TF_1 => Kind::Float,
            M_IT_NA_1 | M_IT_TA_1 | M_IT_TB_1 => Kind::Total,
            _ => return None,
        })
    }

    fn is_measurement(self) -> bool {
        matches!(self, Kind::Normalized | Kind::Scaled | Kind::Float)
    }

    /// The value a point holds before its first update.
    fn initial(self) -> PointValue {
        match self {
            Kind::Single => PointValue::Bool(false),
            Kind::Double => PointValue::DoublePoint(0),
            Kind::Step | Kind::Scaled | Kind::Total => PointValue::Int(0),
            Kind::Normalized | Kind::Float => PointValue::Float(0.0),
            Kind::Bitstring => PointValue::Bits(0),
        }
    }

    /// Checks a value and quantizes it to its wire representation.
    fn check(self, value: PointValue) -> Result<PointValue, &'static str> {
        match (self, value) {
            (Kind::Single, v @ PointValue::Bool(_)) => Ok(v),
            (Kind::Double, PointValue::DoublePoint(d)) if d <= 3 => Ok(PointValue::DoublePoint(d)),
            (Kind::Double, PointValue::DoublePoint(_)) => Err("double point state must be 0..=3"),
            (Kind::Step, PointValue::Int(i)) if (-64..=63).contains(&i) => Ok(PointValue::Int(i)),
            (Kind::Step, PointValue::Int(_)) => Err("step position must be -64..=63"),
            (Kind::Scaled, PointValue::Int(i)) if i16::try_from(i).is_ok() => {
                Ok(PointValue::Int(i))
            }
            (Kind::Scaled, PointValue::Int(_)) => Err("scaled value must be -32768..=32767"),
            (Kind::Total, PointValue::Int(i)) if i32::try_from(i).is_ok() => Ok(PointValue::Int(i)),
            (Kind::Total, PointValue::Int(_)) => Err("integrated total must fit 32 bits signed"),
            (Kind::Bitstring, v @ PointValue::Bits(_)) => Ok(v),
            (Kind::Normalized, PointValue::Float(x)) if (-1.0..=1.0).contains(&x) => {
                Ok(PointValue::Float(f64::from(normalized_raw(x)) / 32768.0))
            }
            (Kind::Normalized, PointValue::Float(_)) => Err("normalized value must be -1..=1"),
            (Kind::Float, PointValue::Float(x))
                if x.is_finite() && x.abs() <= f64::from(f32::MAX) =>
            {
                // In range: the cast rounds to the nearest f32.
                #[allow(clippy::cast_possible_truncation)]
                let single = x as f32;
                Ok(PointValue::Float(f64::from(single)))
            }
            (Kind::Float, PointValue::Float(_)) => {
                Err("short float must be finite and within the f32 range")
            }
            _ => Err("wrong value kind for the type"),
        }
    }
}

/// `round(x * 32768)` clamped to the i16 range; `x` is within -1..=1.
fn normalized_raw(x: f64) -> i16 {
    let scaled = (x * 32768.0).round();
    if scaled.is_nan() {
        return 0;
    }
    // The clamp makes the cast exact.
    #[allow(clippy::cast_possible_truncation)]
    let raw = scaled.clamp(f64::from(i16::MIN), f64::from(i16::MAX)) as i16;
    raw
}

/// The state of one point: its declaration and current value.
#[derive(Debug, Clone, PartialEq)]
pub struct Point {
    /// The declaration.
    pub spec: PointSpec,
    /// The newest value; before the first update, the type's zero with IV set.
    pub value: PointValue,
    /// Quality of the newest value ([`Quality::INVALID`] before the first update).
    pub quality: Quality,
    /// Source time of the newest value.
    pub source_time: Option<SourceTime>,
    /// When the newest value was received; `None` before the first update.
    pub received: Option<DateTime<Utc>>,
    kind: Kind,
    /// The last reported value and quality (`None`: nothing reported yet).
    reported: Option<(PointValue, Quality)>,
    /// Next cyclic transmission (`None`: due at the next [`PointDb::due_cyclic`]).
    next_due: Option<DateTime<Utc>>,
}

impl Point {
    /// Whether the point has received a value yet.
    pub fn has_value(&self) -> bool {
        self.received.is_some()
    }

    /// The point's current state as a change record (used for cyclic transmission).
    fn snapshot(&self, received: DateTime<Utc>, cause: EventCause, send: bool) -> PointChange {
        PointChange {
            name: self.spec.name.clone(),
            ioa: self.spec.ioa,
            type_id: self.spec.type_id,
            value: self.value.clone(),
            quality: self.quality,
            source_time: self.source_time,
            received,
            cause,
            send,
        }
    }

    /// Whether `value`/`quality` differ enough from the last reported ones.
    fn is_reportable(&self, value: &PointValue, quality: Quality) -> bool {
        let Some((last_value, last_quality)) = &self.reported else {
            return true;
        };
        if *last_quality != quality {
            return true;
        }
        match (self.spec.deadband, last_value, value) {
            (Some(band), PointValue::Float(a), PointValue::Float(b)) => {
                (b - a).abs() >= band && a != b
            }
            (Some(band), PointValue::Int(a), PointValue::Int(b)) => {
                a != b && (i128::from(*b) - i128::from(*a)).unsigned_abs() as f64 >= band
            }
            _ => last_value != value,
        }
    }
}

/// A reported change of a point (or a cyclic transmission of its current value).
#[derive(Debug, Clone, PartialEq)]
pub struct PointChange {
    /// Point name.
    pub name: String,
    /// Its address.
    pub ioa: Ioa,
    /// Its monitor type.
    pub type_id: TypeId,
    /// The value.
    pub value: PointValue,
    /// Its quality.
    pub quality: Quality,
    /// Its source time.
    pub source_time: Option<SourceTime>,
    /// When the station received or produced it.
    pub received: DateTime<Utc>,
    /// Why.
    pub cause: EventCause,
    /// Whether it is to be sent upward now (`ServerHandle::update_with_cause`): true for
    /// spontaneous points and cyclic transmissions; false for changes of cyclic and
    /// interrogation-only points, which only update the image (`ServerHandle::set`) and
    /// the store.
    pub send: bool,
}

impl PointChange {
    /// The IEC information element (value and quality). Step positions are sent not
    /// transient; integrated totals with sequence number 0, IV from the quality's IV and
    /// CY from its OV.
    pub fn to_element(&self) -> Element {
        to_element_of(self.type_id, &self.value, self.quality)
    }

    /// The CP56Time2a of the source time in the given zone, with IV from
    /// [`SourceTime::invalid`]; `None` without source time (the server then stamps the
    /// time of sending).
    pub fn time_tag(&self, zone: TimeZonePolicy) -> Option<Cp56Time2a> {
        self.source_time
            .map(|st| zone.to_cp56(st.time).with_invalid(st.invalid))
    }

    /// The cause of transmission for `ServerHandle::update_with_cause`.
    pub fn iec_cause(&self) -> Cause {
        match self.cause {
            EventCause::Cyclic => Cause::PERIODIC,
            EventCause::ReturnRemote | EventCause::Command => Cause::RETURN_REMOTE,
            EventCause::ReturnLocal => Cause::RETURN_LOCAL,
            EventCause::Interrogated => Cause::INTERROGATED_BY_STATION,
            EventCause::Spontaneous | EventCause::Local => Cause::SPONTANEOUS,
        }
    }

    /// Hands the change to the node's IEC 104 server: sent with
    /// `ServerHandle::update_with_cause` when [`send`](Self::send) is set, otherwise only
    /// written to the image with `ServerHandle::set` (interrogation and read show it).
    pub fn publish(&self, server: &ServerHandle, zone: TimeZonePolicy) -> Result<(), ServerError> {
        let time = self.time_tag(zone);
        if self.send {
            server.update_with_cause(self.ioa, self.to_element(), time, self.iec_cause())
        } else {
            let time = match self.type_id.time_tag() {
                iec60870::asdu::TimeTagKind::None => None,
                _ => time.map(TimeTag::Cp56),
            };
            server.set(self.ioa, self.to_element(), time)
        }
    }

    /// The store's record of this change.
    pub fn to_event_record(&self, node: &str, origin: &str) -> EventRecord {
        EventRecord {
            id: None,
            node: node.to_owned(),
            point: self.name.clone(),
            ioa: Some(self.ioa.get()),
            value: self.value.clone(),
            quality: self.quality,
            source_time: self.source_time,
            received_time: self.received,
            cause: self.cause,
            origin: origin.to_owned(),
        }
    }
}

/// The element of a (checked) value; a value of the wrong kind gives the type's zero
/// with IV set rather than a panic.
fn to_element_of(type_id: TypeId, value: &PointValue, quality: Quality) -> Element {
    let kind = Kind::of(type_id).unwrap_or(Kind::Single);
    let (value, quality) = match kind.check(value.clone()) {
        Ok(v) => (v, quality),
        Err(_) => (
            kind.initial(),
            Quality {
                invalid: true,
                ..quality
            },
        ),
    };
    let q = quality;
    let sp_quality = Quality {
        overflow: false,
        ..q
    };
    match (kind, value) {
        (Kind::Single, PointValue::Bool(on)) => Element::SinglePoint {
            on,
            quality: sp_quality,
        },
        (Kind::Double, PointValue::DoublePoint(d)) => Element::DoublePoint {
            state: DoublePointState::from_bits(d),
            quality: sp_quality,
        },
        (Kind::Step, PointValue::Int(i)) => Element::StepPosition {
            position: i8::try_from(i)
                .ok()
                .and_then(|v| StepPosition::new(v, false).ok())
                .unwrap_or_default(),
            quality: q,
        },
        (Kind::Bitstring, PointValue::Bits(bits)) => Element::Bitstring { bits, quality: q },
        (Kind::Normalized, PointValue::Float(x)) => Element::Normalized {
            raw: normalized_raw(x),
            quality: q,
        },
        (Kind::Scaled, PointValue::Int(i)) => Element::Scaled {
            value: i16::try_from(i).unwrap_or_default(),
            quality: q,
        },
        (Kind::Float, PointValue::Float(x)) => {
            // Checked to be within the f32 range.
            #[allow(clippy::cast_possible_truncation)]
            let value = x as f32;
            Element::Float { value, quality: q }
        }
        (Kind::Total, PointValue::Int(i)) => {
            let reading = BinaryCounterReading::new(i32::try_from(i).unwrap_or_default(), 0)
                .map(|r| r.with_invalid(quality.invalid).with_carry(quality.overflow));
            match reading {
                Ok(r) => Element::IntegratedTotal(r),
                Err(_) => Element::SinglePoint {
                    on: false,
                    quality: Quality::INVALID,
                },
            }
        }
        // Unreachable after `check`; kept total.
        _ => Element::SinglePoint {
            on: false,
            quality: Quality::INVALID,
        },
    }
}

/// Decodes a monitor element received for `type_id` (from a lower node's IEC 104 data)
/// into the database's value, quality and source time. The CP56Time2a is read in `zone`;
/// a CP24Time2a cannot be placed without a reference and gives no source time. Step
/// positions lose their transient bit; integrated totals map IV to IV and CY to OV.
pub fn from_element(
    type_id: TypeId,
    element: &Element,
    time: Option<&TimeTag>,
    zone: TimeZonePolicy,
) -> Result<(PointValue, Quality, Option<SourceTime>), PointDbError> {
    let mismatch = || PointDbError::ElementMismatch {
        type_id,
        element: element.short_name(),
    };
    let kind = Kind::of(type_id).ok_or_else(mismatch)?;
    if !element.family_matches(type_id) {
        return Err(mismatch());
    }
    let (value, quality) = match (kind, element) {
        (Kind::Single, Element::SinglePoint { on, quality }) => (PointValue::Bool(*on), *quality),
        (Kind::Double, Element::DoublePoint { state, quality }) => {
            (PointValue::DoublePoint(state.bits()), *quality)
        }
        (Kind::Step, Element::StepPosition { position, quality }) => {
            (PointValue::Int(i64::from(position.value())), *quality)
        }
        (Kind::Bitstring, Element::Bitstring { bits, quality }) => {
            (PointValue::Bits(*bits), *quality)
        }
        (Kind::Normalized, Element::Normalized { raw, quality }) => {
            (PointValue::Float(f64::from(*raw) / 32768.0), *quality)
        }
        (Kind::Scaled, Element::Scaled { value, quality }) => {
            (PointValue::Int(i64::from(*value)), *quality)
        }
        (Kind::Float, Element::Float { value, quality }) => {
            (PointValue::Float(f64::from(*value)), *quality)
        }
        (Kind::Total, Element::IntegratedTotal(r)) => (
            PointValue::Int(i64::from(r.value())),
            Quality {
                invalid: r.is_invalid(),
                overflow: r.is_carry(),
                ..Quality::GOOD
            },
        ),
        _ => return Err(mismatch()),
    };
    let source_time = time
        .and_then(TimeTag::as_cp56)
        .and_then(|tag| zone.from_cp56(tag));
    Ok((value, quality, source_time))
}

/// A node's point database.
#[derive(Debug, Clone)]
pub struct PointDb {
    node: String,
    points: Vec<Point>,
    by_name: HashMap<String, usize>,
    by_ioa: HashMap<u32, usize>,
    by_source: HashMap<PointSource, Vec<usize>>,
}

impl PointDb {
    /// Builds the database of `node`. Refuses duplicate names and IOAs, empty names,
    /// unsupported types, deadbands on non-measurement types (or negative / non-finite
    /// ones) and zero cyclic periods. Every point starts with its type's zero value and
    /// IV set.
    pub fn new(node: &str, specs: Vec<PointSpec>) -> Result<PointDb, PointDbError> {
        let mut db = PointDb {
            node: node.to_owned(),
            points: Vec::with_capacity(specs.len()),
            by_name: HashMap::new(),
            by_ioa: HashMap::new(),
            by_source: HashMap::new(),
        };
        for spec in specs {
            if spec.name.is_empty() {
                return Err(PointDbError::EmptyName(spec.ioa));
            }
            let kind = Kind::of(spec.type_id).ok_or_else(|| PointDbError::UnsupportedType {
                name: spec.name.clone(),
                type_id: spec.type_id,
            })?;
            if let Some(band) = spec.deadband {
                if !kind.is_measurement() || !band.is_finite() || band < 0.0 {
                    return Err(PointDbError::InvalidDeadband {
                        name: spec.name,
                        deadband: band,
                    });
                }
            }
            if spec.transmission == Transmission::Cyclic(Duration::ZERO) {
                return Err(PointDbError::ZeroPeriod(spec.name));
            }
            if db.by_name.contains_key(&spec.name) {
                return Err(PointDbError::DuplicateName(spec.name));
            }
            if let Some(&other) = db.by_ioa.get(&spec.ioa.get()) {
                return Err(PointDbError::DuplicateIoa {
                    ioa: spec.ioa,
                    first: db
                        .points
                        .get(other)
                        .map(|p| p.spec.name.clone())
                        .unwrap_or_default(),
                    second: spec.name,
                });
            }
            let index = db.points.len();
            db.by_name.insert(spec.name.clone(), index);
            db.by_ioa.insert(spec.ioa.get(), index);
            db.by_source
                .entry(spec.source.clone())
                .or_default()
                .push(index);
            db.points.push(Point {
                value: kind.initial(),
                quality: Quality::INVALID,
                source_time: None,
                received: None,
                kind,
                // The initial state (zero, IV) is what interrogation shows before any
                // update: an update that leaves it so is no change worth sending (a
                // concentrator starting before its lower nodes would otherwise send a
                // burst of invalid values upward).
                reported: Some((kind.initial(), Quality::INVALID)),
                next_due: None,
                spec,
            });
        }
        Ok(db)
    }

    /// The node's name.
    pub fn node(&self) -> &str {
        &self.node
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// Whether the database has no point.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// All points, in declaration order (the index is the [`PointId`]).
    pub fn points(&self) -> impl Iterator<Item = &Point> {
        self.points.iter()
    }

    /// The id of a point.
    pub fn id<'a>(&self, key: impl Into<PointKey<'a>>) -> Option<PointId> {
        match key.into() {
            PointKey::Name(name) => self.by_name.get(name).copied(),
            PointKey::Ioa(ioa) => self.by_ioa.get(&ioa.get()).copied(),
            PointKey::Id(id) => (id.0 < self.points.len()).then_some(id.0),
        }
        .map(PointId)
    }

    /// A point by name, IOA or id.
    pub fn get<'a>(&self, key: impl Into<PointKey<'a>>) -> Option<&Point> {
        self.id(key).and_then(|id| self.points.get(id.0))
    }

    /// The points fed by a source key (usually one).
    pub fn by_source<'s>(&'s self, source: &PointSource) -> impl Iterator<Item = &'s Point> + 's {
        self.by_source
            .get(source)
            .into_iter()
            .flatten()
            .filter_map(|&i| self.points.get(i))
    }

    fn point_mut(&mut self, key: PointKey<'_>) -> Result<&mut Point, PointDbError> {
        let id = self
            .id(key)
            .ok_or_else(|| PointDbError::UnknownPoint(key.to_string()))?;
        self.points
            .get_mut(id.0)
            .ok_or_else(|| PointDbError::UnknownPoint(key.to_string()))
    }

    /// Sets a point's value. The value is checked against the point's type and quantized
    /// to its wire form; the database keeps it whatever happens. Returns the change to
    /// report, if the value or quality differs from the last reported ones (see the
    /// module doc for deadbands).
    pub fn update<'a>(
        &mut self,
        key: impl Into<PointKey<'a>>,
        value: PointValue,
        quality: Quality,
        source_time: Option<SourceTime>,
        received: DateTime<Utc>,
        cause: EventCause,
    ) -> Result<Option<PointChange>, PointDbError> {
        let point = self.point_mut(key.into())?;
        let shown = value.to_string();
        let value = point
            .kind
            .check(value)
            .map_err(|reason| PointDbError::ValueRefused {
                name: point.spec.name.clone(),
                type_id: point.spec.type_id,
                value: shown,
                reason,
            })?;
        let report = point.is_reportable(&value, quality);
        point.value = value;
        point.quality = quality;
        point.source_time = source_time;
        point.received = Some(received);
        if !report {
            return Ok(None);
        }
        point.reported = Some((point.value.clone(), quality));
        let send = point.spec.transmission == Transmission::Spontaneous;
        Ok(Some(point.snapshot(received, cause, send)))
    }

    /// Like [`update`](Self::update), but reports the value even when it equals the last
    /// reported one: for events a lower node sent spontaneously, each of which is a change
    /// there. (A replay after a link outage may start with the value an interrogation
    /// already brought; dropping it would lose an event and its time tag.)
    pub fn update_event<'a>(
        &mut self,
        key: impl Into<PointKey<'a>>,
        value: PointValue,
        quality: Quality,
        source_time: Option<SourceTime>,
        received: DateTime<Utc>,
        cause: EventCause,
    ) -> Result<Option<PointChange>, PointDbError> {
        let key = key.into();
        if let Some(change) = self.update(key, value, quality, source_time, received, cause)? {
            return Ok(Some(change));
        }
        let point = self.point_mut(key)?;
        let send = point.spec.transmission == Transmission::Spontaneous;
        Ok(Some(point.snapshot(received, cause, send)))
    }

    /// Sets IV on every point the predicate selects (keeping value and other flags) and
    /// returns the changes, stamped with `now` as source time (the node detected the
    /// failure). Points already invalid are not reported again.
    pub fn invalidate_where(
        &mut self,
        mut predicate: impl FnMut(&PointSpec) -> bool,
        now: DateTime<Utc>,
    ) -> Vec<PointChange> {
        let mut changes = Vec::new();
        for point in &mut self.points {
            if !predicate(&point.spec) || point.quality.invalid {
                continue;
            }
            let quality = Quality {
                invalid: true,
                ..point.quality
            };
            point.quality = quality;
            point.source_time = Some(SourceTime {
                time: now,
                invalid: false,
            });
            point.received = Some(now);
            point.reported = Some((point.value.clone(), quality));
            let send = point.spec.transmission == Transmission::Spontaneous;
            changes.push(point.snapshot(now, EventCause::Spontaneous, send));
        }
        changes
    }

    /// [`invalidate_where`](Self::invalidate_where) for the points received over the
    /// client link `link` (when it goes down). Its status point is not one of them.
    pub fn invalidate_link(&mut self, link: &str, now: DateTime<Utc>) -> Vec<PointChange> {
        self.invalidate_where(
            |spec| matches!(&spec.source, PointSource::Link { link: name, .. } if name == link),
            now,
        )
    }

    /// Sets a communication-status single point from a link state: TRUE when the link is
    /// down (`NOT CommEnabled`, spec §7.3), good quality, source time `now`. The status
    /// point is the node's own: give it a source key outside the link's prefix, so that
    /// invalidating the link's points does not invalidate its status too.
    pub fn set_link_status<'a>(
        &mut self,
        point: impl Into<PointKey<'a>>,
        up: bool,
        now: DateTime<Utc>,
    ) -> Result<Option<PointChange>, PointDbError> {
        self.update(
            point,
            PointValue::Bool(!up),
            Quality::GOOD,
            Some(SourceTime {
                time: now,
                invalid: false,
            }),
            now,
            EventCause::Spontaneous,
        )
    }

    /// The cyclic points due at `now` with their current values (cause
    /// [`EventCause::Cyclic`], to be sent). A point is due at the first call and then every
    /// period after the previous due time; missed periods are skipped, not sent in a
    /// burst. Points that never received a value are not sent, but keep their schedule.
    pub fn due_cyclic(&mut self, now: DateTime<Utc>) -> Vec<PointChange> {
        let mut due = Vec::new();
        for point in &mut self.points {
            let Transmission::Cyclic(period) = point.spec.transmission else {
                continue;
            };
            if point.next_due.is_some_and(|next| next > now) {
                continue;
            }
            let period = chrono::TimeDelta::from_std(period).unwrap_or(chrono::TimeDelta::MAX);
            let mut next = point
                .next_due
                .and_then(|d| d.checked_add_signed(period))
                .unwrap_or(DateTime::<Utc>::MAX_UTC);
            if next <= now || point.next_due.is_none() {
                next = now
                    .checked_add_signed(period)
                    .unwrap_or(DateTime::<Utc>::MAX_UTC);
            }
            point.next_due = Some(next);
            if point.has_value() {
                due.push(point.snapshot(now, EventCause::Cyclic, true));
            }
        }
        due
    }

    /// The earliest time a cyclic point is due (`None` without cyclic points). A point
    /// never scheduled is due at once, reported as `now`.
    pub fn next_cyclic_due(&self, now: DateTime<Utc>) -> Option<DateTime<Utc>> {
        self.points
            .iter()
            .filter(|p| matches!(p.spec.transmission, Transmission::Cyclic(_)))
            .map(|p| p.next_due.unwrap_or(now))
            .min()
    }

    /// The IEC 104 server's process image: one monitor point per point, with the spec's
    /// type as event type, its groups, the newest value and, for time-tagged types, its
    /// source time as a CP56Time2a in `zone`.
    pub fn process_image(&self, zone: TimeZonePolicy) -> Result<ProcessImage, PointDbError> {
        let mut image = ProcessImage::new();
        for point in &self.points {
            let time = match point.spec.type_id.time_tag() {
                iec60870::asdu::TimeTagKind::None => None,
                _ => point
                    .source_time
                    .map(|st| TimeTag::Cp56(zone.to_cp56(st.time).with_invalid(st.invalid))),
            };
            image.add_monitor(MonitorPoint {
                ioa: point.spec.ioa,
                event_type: point.spec.type_id,
                groups: point.spec.groups,
                element: to_element_of(point.spec.type_id, &point.value, point.quality),
                time,
            })?;
        }
        Ok(image)
    }
}
