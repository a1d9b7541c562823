//! Records to columns and back: the one mapping both backends use.
//!
//! A record is written as a list of [`Param`]s in the order of [`COMMAND_INSERT`], [`LIFT_FAULT_INSERT`] or [`NOTIFICATION_INSERT`] and read back from
//! a row of the matching `*_COLUMNS` through [`Columns`], which each driver implements in
//! a few lines.

use chrono::{DateTime, NaiveDateTime, Utc};

use super::Param;
use crate::model::{
    quality_from_bits, Actor, CommandOutcome, CommandPhase, CommandRecord, EventCause, EventKey,
    EventRecord, PointValue, RecordId, SourceTime,
};
use crate::{LiftFaultRecord, NotificationOutcome, NotificationRecord, StoreError, StoreStats};

/// Converts a time to stored milliseconds since the Unix epoch (finer parts are dropped).
pub(crate) fn to_ms(t: DateTime<Utc>) -> i64 {
    t.timestamp_millis()
}

/// Converts stored milliseconds back to a time.
pub(crate) fn from_ms(ms: i64) -> Result<DateTime<Utc>, StoreError> {
    DateTime::from_timestamp_millis(ms)
        .ok_or_else(|| StoreError::Corrupt(format!("time {ms} ms out of range")))
}

/// The columns of a result row, as a driver reads them.
pub(crate) trait Columns {
    /// An integer column of any width (a boolean as 0 or 1); NULL is `None`.
    fn int(&self, i: usize) -> Result<Option<i64>, StoreError>;
    /// A floating-point column; NULL is `None`.
    fn real(&self, i: usize) -> Result<Option<f64>, StoreError>;
    /// A text column; NULL is `None`.
    fn text(&self, i: usize) -> Result<Option<String>, StoreError>;
    /// A bytes column (a packed block of events); NULL is `None`.
    fn blob(&self, i: usize) -> Result<Option<Vec<u8>>, StoreError>;

    /// An integer column that is never NULL.
    fn need_int(&self, i: usize) -> Result<i64, StoreError> {
        self.int(i)?
            .ok_or_else(|| StoreError::Corrupt(format!("column {i} is NULL")))
    }
    /// A stored enum code or flag set (a small integer, never NULL).
    fn code(&self, i: usize) -> Result<i16, StoreError> {
        let v = self.need_int(i)?;
        i16::try_from(v).map_err(|_| StoreError::Corrupt(format!("code {v} out of range")))
    }
    /// A text column that is never NULL.
    fn need_text(&self, i: usize) -> Result<String, StoreError> {
        self.text(i)?
            .ok_or_else(|| StoreError::Corrupt(format!("column {i} is NULL")))
    }
}

/// One column of a row read into memory ([`OwnedRow`]).
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Cell {
    Null,
    Int(i64),
    Real(f64),
    Text(String),
    Blob(Vec<u8>),
}

/// A row read into memory: what a snapshot of several statements answers.
#[derive(Debug, Clone, PartialEq, Default)]
pub(crate) struct OwnedRow(pub(crate) Vec<Cell>);

impl Columns for OwnedRow {
    fn int(&self, i: usize) -> Result<Option<i64>, StoreError> {
        match self.0.get(i) {
            Some(Cell::Int(v)) => Ok(Some(*v)),
            Some(Cell::Null) => Ok(None),
            other => Err(StoreError::Corrupt(format!(
                "column {i}: {other:?}, not an integer"
            ))),
        }
    }
    fn real(&self, i: usize) -> Result<Option<f64>, StoreError> {
        match self.0.get(i) {
            Some(Cell::Real(v)) => Ok(Some(*v)),
            // A database may answer an integral aggregate as an integer.
            #[allow(clippy::cast_precision_loss)]
            Some(Cell::Int(v)) => Ok(Some(*v as f64)),
            Some(Cell::Null) => Ok(None),
            other => Err(StoreError::Corrupt(format!(
                "column {i}: {other:?}, not a number"
            ))),
        }
    }
    fn text(&self, i: usize) -> Result<Option<String>, StoreError> {
        match self.0.get(i) {
            Some(Cell::Text(v)) => Ok(Some(v.clone())),
            Some(Cell::Null) => Ok(None),
            other => Err(StoreError::Corrupt(format!(
                "column {i}: {other:?}, not a text"
            ))),
        }
    }
    fn blob(&self, i: usize) -> Result<Option<Vec<u8>>, StoreError> {
        match self.0.get(i) {
            Some(Cell::Blob(v)) => Ok(Some(v.clone())),
            Some(Cell::Null) => Ok(None),
            other => Err(StoreError::Corrupt(format!(
                "column {i}: {other:?}, not bytes"
            ))),
        }
    }
}

/// Reads a row with this function (a record, an id, the stats).
pub(crate) type Decode<T> = fn(&dyn Columns) -> Result<T, StoreError>;

/// The columns a command record is written to, in the order of [`command_params`].
pub(crate) const COMMAND_INSERT: &str = "time_ms, actor_kind, actor, node, point, ioa, \
     value_kind, value_int, value_float, value_text, phase, outcome, detail";

/// The columns every event query selects, in the order [`event_from_row`] reads them.
pub(crate) const EVENT_COLUMNS: &str = "id, node, point, ioa, value_kind, value_int, value_float, \
     value_text, quality, source_ms, source_invalid, received_ms, cause, origin, source_id, \
     source_seq";

/// The columns every command query selects, in the order [`command_from_row`] reads them.
pub(crate) const COMMAND_COLUMNS: &str = "id, time_ms, actor_kind, actor, node, point, ioa, \
     value_kind, value_int, value_float, value_text, phase, outcome, detail";

/// The columns a lift fault record is written to, in the order of [`lift_fault_params`].
pub(crate) const LIFT_FAULT_INSERT: &str =
    "node, lift, stack_index, code, floor, target, board_ms, received_ms, filed_ms";

/// The columns every lift fault query selects, in the order [`lift_fault_from_row`] reads
/// them.
pub(crate) const LIFT_FAULT_COLUMNS: &str =
    "id, node, lift, stack_index, code, floor, target, board_ms, received_ms";

/// The columns a notification record is written to, in the order of
/// [`notification_params`].
pub(crate) const NOTIFICATION_INSERT: &str =
    "time_ms, rule, channel, recipient, source, subject, outcome, detail";

/// The columns every notification query selects, in the order [`notification_from_row`]
/// reads them.
pub(crate) const NOTIFICATION_COLUMNS: &str =
    "id, time_ms, rule, channel, recipient, source, subject, outcome, detail";

/// A key's sequence number as stored (checked by [`check_event`] to fit).
pub(crate) fn key_sequence(sequence: u64) -> i64 {
    i64::try_from(sequence).unwrap_or(i64::MAX)
}

/// A command record as the parameters of one row of [`COMMAND_INSERT`].
pub(crate) fn command_params(c: &CommandRecord) -> Vec<Param> {
    let mut row = vec![
        Param::int(to_ms(c.time)),
        Param::int(i64::from(actor_kind(&c.actor))),
        Param::text(c.actor.name()),
        Param::text(&c.node),
        Param::text(&c.point),
        Param::Int(c.ioa.map(i64::from)),
    ];
    row.extend(value_params(&c.value));
    row.extend([
        Param::int(i64::from(c.phase.code())),
        Param::int(i64::from(c.outcome.code())),
        Param::text(&c.detail),
    ]);
    row
}

/// An event from a row of [`EVENT_COLUMNS`].
pub(crate) fn event_from_row(r: &dyn Columns) -> Result<EventRecord, StoreError> {
    let quality = r.code(8)?;
    let source_invalid = r.need_int(10)? != 0;
    let cause = r.code(12)?;
    Ok(EventRecord {
        id: Some(r.need_int(0)?),
        node: r.need_text(1)?,
        point: r.need_text(2)?,
        ioa: ioa_from(r.int(3)?)?,
        value: value_from(r, 4)?,
        quality: quality_from_bits(u8::try_from(quality & 0xFF).unwrap_or(0)),
        source_time: r
            .int(9)?
            .map(|ms| {
                Ok::<_, StoreError>(SourceTime {
                    time: from_ms(ms)?,
                    invalid: source_invalid,
                })
            })
            .transpose()?,
        received_time: from_ms(r.need_int(11)?)?,
        cause: EventCause::from_code(cause)
            .ok_or_else(|| StoreError::Corrupt(format!("unknown cause {cause}")))?,
        origin: r.need_text(13)?,
        key: match (r.text(14)?, r.int(15)?) {
            (Some(source), Some(sequence)) => Some(EventKey {
                source,
                sequence: u64::try_from(sequence)
                    .map_err(|_| StoreError::Corrupt(format!("key sequence {sequence}")))?,
            }),
            _ => None,
        },
    })
}

/// A command record from a row of [`COMMAND_COLUMNS`].
pub(crate) fn command_from_row(r: &dyn Columns) -> Result<CommandRecord, StoreError> {
    let phase = r.code(11)?;
    let outcome = r.code(12)?;
    Ok(CommandRecord {
        id: Some(r.need_int(0)?),
        time: from_ms(r.need_int(1)?)?,
        actor: actor_from(r.code(2)?, r.need_text(3)?)?,
        node: r.need_text(4)?,
        point: r.need_text(5)?,
        ioa: ioa_from(r.int(6)?)?,
        value: value_from(r, 7)?,
        phase: CommandPhase::from_code(phase)
            .ok_or_else(|| StoreError::Corrupt(format!("unknown phase {phase}")))?,
        outcome: CommandOutcome::from_code(outcome)
            .ok_or_else(|| StoreError::Corrupt(format!("unknown outcome {outcome}")))?,
        detail: r.need_text(13)?,
    })
}

/// A board's wall-clock time as stored: its reading taken as if it were UTC.
pub(crate) fn naive_to_ms(t: NaiveDateTime) -> i64 {
    t.and_utc().timestamp_millis()
}

/// A lift fault record as the parameters of one row of [`LIFT_FAULT_INSERT`].
pub(crate) fn lift_fault_params(f: &LiftFaultRecord) -> Vec<Param> {
    vec![
        Param::text(&f.node),
        Param::text(&f.lift),
        Param::int(i64::from(f.stack_index)),
        Param::int(i64::from(f.code)),
        Param::int(i64::from(f.floor)),
        Param::int(i64::from(f.target)),
        Param::Int(f.board_time.map(naive_to_ms)),
        Param::int(to_ms(f.received_time)),
        Param::int(naive_to_ms(f.filed_time())),
    ]
}

/// A lift fault record from a row of [`LIFT_FAULT_COLUMNS`].
pub(crate) fn lift_fault_from_row(r: &dyn Columns) -> Result<LiftFaultRecord, StoreError> {
    let octet = |i: usize| {
        let v = r.need_int(i)?;
        u8::try_from(v).map_err(|_| StoreError::Corrupt(format!("octet {v} out of range")))
    };
    Ok(LiftFaultRecord {
        id: Some(r.need_int(0)?),
        node: r.need_text(1)?,
        lift: r.need_text(2)?,
        stack_index: octet(3)?,
        code: octet(4)?,
        floor: octet(5)?,
        target: octet(6)?,
        board_time: r
            .int(7)?
            .map(|ms| from_ms(ms).map(|t| t.naive_utc()))
            .transpose()?,
        received_time: from_ms(r.need_int(8)?)?,
    })
}

/// A notification record as the parameters of one row of [`NOTIFICATION_INSERT`].
pub(crate) fn notification_params(n: &NotificationRecord) -> Vec<Param> {
    vec![
        Param::int(to_ms(n.time)),
        Param::text(&n.rule),
        Param::text(&n.channel),
        Param::text(&n.recipient),
        Param::text(&n.source),
        Param::text(&n.subject),
        Param::int(i64::from(n.outcome.code())),
        Param::text(&n.detail),
    ]
}

/// A notification record from a row of [`NOTIFICATION_COLUMNS`].
pub(crate) fn notification_from_row(r: &dyn Columns) -> Result<NotificationRecord, StoreError> {
    let outcome = r.code(7)?;
    Ok(NotificationRecord {
        id: Some(r.need_int(0)?),
        time: from_ms(r.need_int(1)?)?,
        rule: r.need_text(2)?,
        channel: r.need_text(3)?,
        recipient: r.need_text(4)?,
        source: r.need_text(5)?,
        subject: r.need_text(6)?,
        outcome: NotificationOutcome::from_code(outcome).ok_or_else(|| {
            StoreError::Corrupt(format!("unknown notification outcome {outcome}"))
        })?,
        detail: r.need_text(8)?,
    })
}

/// The number a `SELECT count(*)` hands back.
pub(crate) fn count_from_row(r: &dyn Columns) -> Result<u64, StoreError> {
    let n = r.need_int(0)?;
    u64::try_from(n).map_err(|_| StoreError::Corrupt(format!("count {n} out of range")))
}

/// The id an `INSERT ... RETURNING id` hands back.
pub(crate) fn id_from_row(r: &dyn Columns) -> Result<RecordId, StoreError> {
    r.need_int(0)
}

/// The stats from the row of [`STATS`].
pub(crate) fn stats_from_row(r: &dyn Columns) -> Result<StoreStats, StoreError> {
    Ok(StoreStats {
        events: u64::try_from(r.need_int(0)?).unwrap_or(0),
        oldest_event: r.int(1)?.map(from_ms).transpose()?,
        newest_event: r.int(2)?.map(from_ms).transpose()?,
        commands: u64::try_from(r.need_int(3)?).unwrap_or(0),
    })
}

/// The value as its `(value_int, value_float, value_text)` columns.
pub(crate) fn value_columns(value: &PointValue) -> (Option<i64>, Option<f64>, Option<&str>) {
    match value {
        PointValue::Bool(b) => (Some(i64::from(*b)), None, None),
        PointValue::DoublePoint(d) => (Some(i64::from(*d)), None, None),
        PointValue::Int(i) => (Some(*i), None, None),
        // NaN is kept as a NULL float (SQLite turns NaN into NULL anyway).
        PointValue::Float(f) => (None, (!f.is_nan()).then_some(*f), None),
        PointValue::Bits(b) => (Some(i64::from(*b)), None, None),
        PointValue::Text(t) => (None, None, Some(t.as_str())),
    }
}

/// The value as the `(value_kind, value_int, value_float, value_text)` columns.
fn value_params(value: &PointValue) -> [Param; 4] {
    let kind = Param::int(i64::from(crate::model::value_kind_code(value)));
    let (int, float, text) = value_columns(value);
    [
        kind,
        Param::Int(int),
        Param::Real(float),
        Param::Text(text.map(str::to_owned)),
    ]
}

/// The value from its four columns starting at `first`; a row that does not fit is
/// [`StoreError::Corrupt`].
fn value_from(r: &dyn Columns, first: usize) -> Result<PointValue, StoreError> {
    let kind = r.code(first)?;
    let int = r.int(first + 1)?;
    let need_int =
        || int.ok_or_else(|| StoreError::Corrupt(format!("value kind {kind} without an integer")));
    let out_of_range =
        |v: i64| StoreError::Corrupt(format!("value {v} out of range for value kind {kind}"));
    Ok(match kind {
        1 => match need_int()? {
            0 => PointValue::Bool(false),
            1 => PointValue::Bool(true),
            v => return Err(out_of_range(v)),
        },
        2 => {
            let v = need_int()?;
            PointValue::DoublePoint(u8::try_from(v).map_err(|_| out_of_range(v))?)
        }
        3 => PointValue::Int(need_int()?),
        4 => PointValue::Float(r.real(first + 2)?.unwrap_or(f64::NAN)),
        5 => {
            let v = need_int()?;
            PointValue::Bits(u32::try_from(v).map_err(|_| out_of_range(v))?)
        }
        6 => PointValue::Text(r.text(first + 3)?.unwrap_or_default()),
        other => return Err(StoreError::Corrupt(format!("unknown value kind {other}"))),
    })
}

fn actor_kind(actor: &Actor) -> i16 {
    match actor {
        Actor::User(_) => 1,
        Actor::Remote(_) => 2,
    }
}

fn actor_from(kind: i16, name: String) -> Result<Actor, StoreError> {
    match kind {
        1 => Ok(Actor::User(name)),
        2 => Ok(Actor::Remote(name)),
        other => Err(StoreError::Corrupt(format!("unknown actor kind {other}"))),
    }
}

fn ioa_from(v: Option<i64>) -> Result<Option<u32>, StoreError> {
    v.map(|i| u32::try_from(i).map_err(|_| StoreError::Corrupt(format!("IOA {i} out of range"))))
        .transpose()
}

/// Checks what both backends must refuse alike: empty names, NUL characters (PostgreSQL
/// text cannot hold them), double-point values above 3.
fn check_text(what: &str, s: &str, may_be_empty: bool) -> Result<(), StoreError> {
    if !may_be_empty && s.is_empty() {
        return Err(StoreError::InvalidRecord(format!("empty {what}")));
    }
    if s.contains('\0') {
        return Err(StoreError::InvalidRecord(format!(
            "{what} {s:?} contains a NUL character"
        )));
    }
    Ok(())
}

fn check_value(v: &PointValue) -> Result<(), StoreError> {
    match v {
        PointValue::DoublePoint(d) if *d > 3 => Err(StoreError::InvalidRecord(format!(
            "double-point value {d} out of range 0..=3"
        ))),
        PointValue::Text(t) => check_text("text value", t, true),
        _ => Ok(()),
    }
}

/// Refuses an event no backend can store faithfully.
pub(crate) fn check_event(e: &EventRecord) -> Result<(), StoreError> {
    check_text("node name", &e.node, false)?;
    check_text("point name", &e.point, false)?;
    check_text("origin", &e.origin, true)?;
    if let Some(key) = &e.key {
        check_text("key source", &key.source, false)?;
        if i64::try_from(key.sequence).is_err() {
            return Err(StoreError::InvalidRecord(format!(
                "key sequence {} above {}",
                key.sequence,
                i64::MAX
            )));
        }
    }
    check_value(&e.value)
}

/// Refuses a command record no backend can store faithfully.
pub(crate) fn check_command(c: &CommandRecord) -> Result<(), StoreError> {
    check_text("actor", c.actor.name(), false)?;
    check_text("node name", &c.node, false)?;
    check_text("point name", &c.point, false)?;
    check_text("detail", &c.detail, true)?;
    check_value(&c.value)
}

/// Refuses a lift fault record no backend can store faithfully.
pub(crate) fn check_lift_fault(f: &LiftFaultRecord) -> Result<(), StoreError> {
    check_text("node name", &f.node, false)?;
    check_text("lift name", &f.lift, false)
}

/// Refuses a notification record no backend can store faithfully.
pub(crate) fn check_notification(n: &NotificationRecord) -> Result<(), StoreError> {
    check_text("rule", &n.rule, false)?;
    check_text("channel", &n.channel, false)?;
    check_text("recipient", &n.recipient, true)?;
    check_text("source", &n.source, true)?;
    check_text("subject", &n.subject, true)?;
    check_text("detail", &n.detail, true)
}
