//! A node's point database: typed values with quality and source time, report by
//! exception, bulk invalidation and communication-status points.
//!
//! Every node (controller) holds one [`PointDb`], built from the [`PointSpec`]s of its
//! project. Values arrive from the node's PLC, its I/O or a lower node's IEC 104 link
//! ([`PointDb::update`]); the database checks them against the point's kind, keeps
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
//! A change goes to the node's sinks: its IEC 104 server (through the `points-iec`
//! adapter, which also brings a lower node's IEC data in), the event recorder, the HMI.

use std::collections::HashMap;
use std::time::Duration;

use chrono::{DateTime, Utc};

use crate::{
    EventCause, PointKind, PointSource, PointSpec, PointType, PointValue, Quality, SourceTime,
    Transmission,
};

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
        ioa: u32,
        /// The point declared first.
        first: String,
        /// The point declared second.
        second: String,
    },
    /// A point has an empty name.
    #[error("a point (IOA {0}) has an empty name")]
    EmptyName(u32),
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
    #[error("point `{name}` ({point_type}): value {value} refused: {reason}")]
    ValueRefused {
        /// Point name.
        name: String,
        /// Its type.
        point_type: PointType,
        /// The value given (displayed).
        value: String,
        /// Why.
        reason: &'static str,
    },
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
    Address(u32),
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

impl From<u32> for PointKey<'_> {
    fn from(address: u32) -> Self {
        PointKey::Address(address)
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
            PointKey::Address(ioa) => write!(f, "with IOA {ioa}"),
            PointKey::Id(id) => write!(f, "#{}", id.0),
        }
    }
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
    kind: PointKind,
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
            address: self.spec.address,
            point_type: self.spec.point_type,
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
    pub address: u32,
    /// Its type.
    pub point_type: PointType,
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
    /// Whether it is to be sent upward now: true for spontaneous points and cyclic
    /// transmissions; false for changes of cyclic and interrogation-only points, which
    /// only update what an interrogation answers (and the store).
    pub send: bool,
}

/// A node's point database.
#[derive(Debug, Clone)]
pub struct PointDb {
    node: String,
    points: Vec<Point>,
    by_name: HashMap<String, usize>,
    by_address: HashMap<u32, usize>,
    by_source: HashMap<PointSource, Vec<usize>>,
}

impl PointDb {
    /// Builds the database of `node`. Refuses duplicate names and IOAs, empty names,
    /// deadbands on non-measurement types (or negative / non-finite
    /// ones) and zero cyclic periods. Every point starts with its type's zero value and
    /// IV set.
    pub fn new(node: &str, specs: Vec<PointSpec>) -> Result<PointDb, PointDbError> {
        let mut db = PointDb {
            node: node.to_owned(),
            points: Vec::with_capacity(specs.len()),
            by_name: HashMap::new(),
            by_address: HashMap::new(),
            by_source: HashMap::new(),
        };
        for spec in specs {
            if spec.name.is_empty() {
                return Err(PointDbError::EmptyName(spec.address));
            }
            let kind = spec.point_type.kind;
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
            if let Some(&other) = db.by_address.get(&spec.address) {
                return Err(PointDbError::DuplicateIoa {
                    ioa: spec.address,
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
            db.by_address.insert(spec.address, index);
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

    /// A database of `node` with no point.
    pub fn empty(node: &str) -> PointDb {
        PointDb {
            node: node.to_owned(),
            points: Vec::new(),
            by_name: HashMap::new(),
            by_address: HashMap::new(),
            by_source: HashMap::new(),
        }
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
            PointKey::Address(address) => self.by_address.get(&address).copied(),
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
                point_type: point.spec.point_type,
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
            point.source_time = Some(SourceTime::at(now));
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
            Some(SourceTime::at(now)),
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
}
