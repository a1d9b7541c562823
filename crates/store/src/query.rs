//! Queries over the store: filters, ordering and keyset pagination.
//!
//! Pages are cut by the key `(time, id)`: a [`Cursor`] holds the key of the last row handed
//! out, and the next page starts strictly after it. Rows with equal times are ordered by id,
//! so pages never repeat or skip a row, even while new rows are being appended.

use chrono::{DateTime, Utc};
use std::fmt;
use std::str::FromStr;

use crate::model::{
    to_ms, Actor, CommandOutcome, CommandRecord, EventCause, EventRecord, RecordId,
};
use crate::StoreError;

/// The largest page a query may ask for.
pub const MAX_PAGE_SIZE: usize = 10_000;

/// The page size of a query that does not set one.
pub const DEFAULT_PAGE_SIZE: usize = 100;

/// Which end a query starts from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Hash)]
pub enum Order {
    /// Newest first (the event list of an HMI).
    #[default]
    NewestFirst,
    /// Oldest first (exports, replays).
    OldestFirst,
}

/// Which time of an event a query filters and orders by.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Hash)]
pub enum TimeBasis {
    /// The event time: the source time stamp when present and valid, otherwise the
    /// received time (see [`crate::EventRecord::event_time`]).
    #[default]
    Source,
    /// The time this station received the event.
    Received,
}

/// A filter on point names.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub enum PointFilter {
    /// The point with exactly this name.
    Exact(String),
    /// Every point whose name starts with this text (case-sensitive, byte-wise), for
    /// example `RH2_` for all points of board RH2.
    Prefix(String),
}

impl PointFilter {
    /// The filter a user types: a point name, or a prefix when it ends in `*` (`RH2_*`).
    pub fn parse(text: &str) -> PointFilter {
        match text.strip_suffix('*') {
            Some(prefix) => PointFilter::Prefix(prefix.to_owned()),
            None => PointFilter::Exact(text.to_owned()),
        }
    }
}

/// Where the next page starts: the `(time, id)` key of the last row of the previous page.
///
/// Its text form (`Display`/`FromStr`, `<ms>:<id>`) can travel in URLs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Cursor {
    pub(crate) time_ms: i64,
    pub(crate) id: RecordId,
}

impl Cursor {
    /// The cursor just after a row with this time (in ms) and id.
    pub fn new(time_ms: i64, id: RecordId) -> Cursor {
        Cursor { time_ms, id }
    }
}

impl fmt::Display for Cursor {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}", self.time_ms, self.id)
    }
}

impl FromStr for Cursor {
    type Err = StoreError;

    fn from_str(s: &str) -> Result<Cursor, StoreError> {
        let bad = || StoreError::InvalidQuery(format!("bad cursor {s:?}, expected <ms>:<id>"));
        let (t, id) = s.split_once(':').ok_or_else(bad)?;
        Ok(Cursor {
            time_ms: t.parse().map_err(|_| bad())?,
            id: id.parse().map_err(|_| bad())?,
        })
    }
}

/// One page of query results.
#[derive(Debug, Clone, PartialEq)]
pub struct Page<T> {
    /// The rows, in the query's order.
    pub items: Vec<T>,
    /// The cursor of the next page, `None` when this page is the last.
    pub next: Option<Cursor>,
}

/// A query over events. Build it with [`EventQuery::default`] and the `with_*` methods.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct EventQuery {
    /// Which time [`Self::from`], [`Self::to`] and the ordering use.
    pub time_basis: TimeBasis,
    /// Only events at or after this time.
    pub from: Option<DateTime<Utc>>,
    /// Only events strictly before this time.
    pub to: Option<DateTime<Utc>>,
    /// Only these points.
    pub point: Option<PointFilter>,
    /// Only events of this node.
    pub node: Option<String>,
    /// Only events with one of these causes; empty means every cause.
    pub causes: Vec<EventCause>,
    /// Only events whose quality has IV set.
    pub invalid_only: bool,
    /// Newest or oldest first.
    pub order: Order,
    /// Rows per page, 1 to [`MAX_PAGE_SIZE`].
    pub limit: usize,
    /// Continue after this cursor (from the previous page's [`Page::next`]).
    pub after: Option<Cursor>,
}

impl Default for EventQuery {
    fn default() -> EventQuery {
        EventQuery {
            time_basis: TimeBasis::Source,
            from: None,
            to: None,
            point: None,
            node: None,
            causes: Vec::new(),
            invalid_only: false,
            order: Order::NewestFirst,
            limit: DEFAULT_PAGE_SIZE,
            after: None,
        }
    }
}

impl EventQuery {
    /// Filter and order by this time.
    pub fn with_time_basis(mut self, basis: TimeBasis) -> Self {
        self.time_basis = basis;
        self
    }
    /// Only events in `[from, to)`; either end may be open.
    pub fn with_range(mut self, from: Option<DateTime<Utc>>, to: Option<DateTime<Utc>>) -> Self {
        self.from = from;
        self.to = to;
        self
    }
    /// Only this point.
    pub fn with_point(mut self, name: impl Into<String>) -> Self {
        self.point = Some(PointFilter::Exact(name.into()));
        self
    }
    /// Only points whose names start with `prefix`.
    pub fn with_point_prefix(mut self, prefix: impl Into<String>) -> Self {
        self.point = Some(PointFilter::Prefix(prefix.into()));
        self
    }
    /// Only this node.
    pub fn with_node(mut self, node: impl Into<String>) -> Self {
        self.node = Some(node.into());
        self
    }
    /// Only these causes.
    pub fn with_causes(mut self, causes: impl IntoIterator<Item = EventCause>) -> Self {
        self.causes = causes.into_iter().collect();
        self
    }
    /// Only invalid (IV) events.
    pub fn with_invalid_only(mut self, invalid_only: bool) -> Self {
        self.invalid_only = invalid_only;
        self
    }
    /// Newest or oldest first.
    pub fn with_order(mut self, order: Order) -> Self {
        self.order = order;
        self
    }
    /// Rows per page.
    pub fn with_limit(mut self, limit: usize) -> Self {
        self.limit = limit;
        self
    }
    /// Continue after this cursor.
    pub fn with_after(mut self, after: Option<Cursor>) -> Self {
        self.after = after;
        self
    }
}

/// A query over the command audit. Build it with [`CommandQuery::default`] and the `with_*`
/// methods.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct CommandQuery {
    /// Only commands at or after this time.
    pub from: Option<DateTime<Utc>>,
    /// Only commands strictly before this time.
    pub to: Option<DateTime<Utc>>,
    /// Only commands of this user or remote address (compared with [`Actor::name`]).
    pub actor: Option<String>,
    /// Only commands to these points.
    pub point: Option<PointFilter>,
    /// Only commands to this node.
    pub node: Option<String>,
    /// Only commands with one of these outcomes; empty means every outcome.
    pub outcomes: Vec<CommandOutcome>,
    /// Newest or oldest first.
    pub order: Order,
    /// Rows per page, 1 to [`MAX_PAGE_SIZE`].
    pub limit: usize,
    /// Continue after this cursor.
    pub after: Option<Cursor>,
}

impl Default for CommandQuery {
    fn default() -> CommandQuery {
        CommandQuery {
            from: None,
            to: None,
            actor: None,
            point: None,
            node: None,
            outcomes: Vec::new(),
            order: Order::NewestFirst,
            limit: DEFAULT_PAGE_SIZE,
            after: None,
        }
    }
}

impl CommandQuery {
    /// Only commands in `[from, to)`; either end may be open.
    pub fn with_range(mut self, from: Option<DateTime<Utc>>, to: Option<DateTime<Utc>>) -> Self {
        self.from = from;
        self.to = to;
        self
    }
    /// Only commands of this user or remote address.
    pub fn with_actor(mut self, actor: &Actor) -> Self {
        self.actor = Some(actor.name().to_owned());
        self
    }
    /// Only commands of the user or remote address with this name.
    pub fn with_actor_name(mut self, name: impl Into<String>) -> Self {
        self.actor = Some(name.into());
        self
    }
    /// Only this point.
    pub fn with_point(mut self, name: impl Into<String>) -> Self {
        self.point = Some(PointFilter::Exact(name.into()));
        self
    }
    /// Only points whose names start with `prefix`.
    pub fn with_point_prefix(mut self, prefix: impl Into<String>) -> Self {
        self.point = Some(PointFilter::Prefix(prefix.into()));
        self
    }
    /// Only this node.
    pub fn with_node(mut self, node: impl Into<String>) -> Self {
        self.node = Some(node.into());
        self
    }
    /// Only these outcomes.
    pub fn with_outcomes(mut self, outcomes: impl IntoIterator<Item = CommandOutcome>) -> Self {
        self.outcomes = outcomes.into_iter().collect();
        self
    }
    /// Newest or oldest first.
    pub fn with_order(mut self, order: Order) -> Self {
        self.order = order;
        self
    }
    /// Rows per page.
    pub fn with_limit(mut self, limit: usize) -> Self {
        self.limit = limit;
        self
    }
    /// Continue after this cursor.
    pub fn with_after(mut self, after: Option<Cursor>) -> Self {
        self.after = after;
        self
    }
}

/// A bound SQL parameter.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Param {
    Int(i64),
    Text(String),
}

/// Placeholder syntax of a backend.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Dialect {
    /// `?1`, `?2`, ...
    Sqlite,
    /// `$1::int8`, `$2::text`, ...
    Postgres,
}

/// A `SELECT` under construction: a WHERE clause with its parameters.
pub(crate) struct SelectBuilder {
    dialect: Dialect,
    conds: Vec<String>,
    pub(crate) params: Vec<Param>,
}

impl SelectBuilder {
    fn new(dialect: Dialect) -> Self {
        SelectBuilder {
            dialect,
            conds: Vec::new(),
            params: Vec::new(),
        }
    }

    /// Adds a parameter and returns its placeholder.
    fn bind(&mut self, p: Param) -> String {
        let typ = match p {
            Param::Int(_) => "int8",
            Param::Text(_) => "text",
        };
        self.params.push(p);
        let n = self.params.len();
        match self.dialect {
            Dialect::Sqlite => format!("?{n}"),
            Dialect::Postgres => format!("${n}::{typ}"),
        }
    }

    fn cond(&mut self, c: String) {
        self.conds.push(c);
    }

    fn time_range(&mut self, col: &str, from: Option<DateTime<Utc>>, to: Option<DateTime<Utc>>) {
        if let Some(from) = from {
            let p = self.bind(Param::Int(to_ms(from)));
            self.cond(format!("{col} >= {p}"));
        }
        if let Some(to) = to {
            let p = self.bind(Param::Int(to_ms(to)));
            self.cond(format!("{col} < {p}"));
        }
    }

    fn point(&mut self, filter: &Option<PointFilter>) {
        match filter {
            None => {}
            Some(PointFilter::Exact(name)) => {
                let p = self.bind(Param::Text(name.clone()));
                self.cond(format!("point = {p}"));
            }
            Some(PointFilter::Prefix(prefix)) if prefix.is_empty() => {}
            Some(PointFilter::Prefix(prefix)) => {
                // A byte-wise range: every name starting with `prefix` sorts at or after it
                // and before `prefix` + U+10FFFF (the largest scalar value), under SQLite's
                // BINARY and PostgreSQL's "C" collation alike, so the point index serves it.
                let lo = self.bind(Param::Text(prefix.clone()));
                let hi = self.bind(Param::Text(format!("{prefix}\u{10FFFF}")));
                self.cond(format!("point >= {lo} AND point < {hi}"));
            }
        }
    }

    fn text_eq(&mut self, col: &str, value: &Option<String>) {
        if let Some(v) = value {
            let p = self.bind(Param::Text(v.clone()));
            self.cond(format!("{col} = {p}"));
        }
    }

    fn codes_in(&mut self, col: &str, codes: &[i16]) {
        if codes.is_empty() {
            return;
        }
        let list: Vec<String> = codes
            .iter()
            .map(|c| self.bind(Param::Int(i64::from(*c))))
            .collect();
        self.cond(format!("{col} IN ({})", list.join(", ")));
    }

    fn keyset(&mut self, col: &str, order: Order, after: Option<Cursor>) -> &'static str {
        let (cmp, dir) = match order {
            Order::NewestFirst => ("<", "DESC"),
            Order::OldestFirst => (">", "ASC"),
        };
        if let Some(c) = after {
            let t = self.bind(Param::Int(c.time_ms));
            let id = self.bind(Param::Int(c.id));
            // The redundant plain bound lets an index on (name, time, id) use the range
            // after an equality on its first column (PostgreSQL uses a row comparison only
            // on leading index columns).
            let t2 = self.bind(Param::Int(c.time_ms));
            self.cond(format!(
                "{col} {cmp}= {t2} AND ({col}, id) {cmp} ({t}, {id})"
            ));
        }
        dir
    }

    fn finish(
        mut self,
        columns: &str,
        table: &str,
        time_col: &str,
        dir: &str,
        limit: usize,
    ) -> (String, Vec<Param>) {
        // One row more than asked tells whether another page follows.
        let lim = self.bind(Param::Int(
            i64::try_from(limit).unwrap_or(i64::MAX).saturating_add(1),
        ));
        let mut sql = format!("SELECT {columns} FROM {table}");
        if !self.conds.is_empty() {
            sql.push_str(" WHERE ");
            sql.push_str(&self.conds.join(" AND "));
        }
        sql.push_str(&format!(" ORDER BY {time_col} {dir}, id {dir} LIMIT {lim}"));
        (sql, self.params)
    }
}

fn check_limit(limit: usize) -> Result<(), StoreError> {
    if limit == 0 || limit > MAX_PAGE_SIZE {
        return Err(StoreError::InvalidQuery(format!(
            "page size {limit} out of range 1..={MAX_PAGE_SIZE}"
        )));
    }
    Ok(())
}

/// The columns every event query selects, in the order the backends read them.
pub(crate) const EVENT_COLUMNS: &str = "id, node, point, ioa, value_kind, value_int, value_float, \
     value_text, quality, source_ms, source_invalid, received_ms, cause, origin";

/// The columns every command query selects, in the order the backends read them.
pub(crate) const COMMAND_COLUMNS: &str = "id, time_ms, actor_kind, actor, node, point, ioa, \
     value_kind, value_int, value_float, value_text, phase, outcome, detail";

/// The SQL and parameters of an event query, and the name of its time column.
pub(crate) fn event_sql(
    q: &EventQuery,
    dialect: Dialect,
) -> Result<(String, Vec<Param>), StoreError> {
    check_limit(q.limit)?;
    let mut b = SelectBuilder::new(dialect);
    let time_col = match q.time_basis {
        TimeBasis::Source => "event_ms",
        TimeBasis::Received => "received_ms",
    };
    b.time_range(time_col, q.from, q.to);
    b.point(&q.point);
    b.text_eq("node", &q.node);
    let causes: Vec<i16> = q.causes.iter().map(|c| c.code()).collect();
    b.codes_in("cause", &causes);
    if q.invalid_only {
        // Written exactly as the partial index's predicate so the planner matches them.
        b.cond("(quality & 1) <> 0".to_owned());
    }
    let dir = b.keyset(time_col, q.order, q.after);
    Ok(b.finish(EVENT_COLUMNS, "events", time_col, dir, q.limit))
}

/// The SQL and parameters of a command query.
pub(crate) fn command_sql(
    q: &CommandQuery,
    dialect: Dialect,
) -> Result<(String, Vec<Param>), StoreError> {
    check_limit(q.limit)?;
    let mut b = SelectBuilder::new(dialect);
    b.time_range("time_ms", q.from, q.to);
    b.text_eq("actor", &q.actor);
    b.point(&q.point);
    b.text_eq("node", &q.node);
    let outcomes: Vec<i16> = q.outcomes.iter().map(|c| c.code()).collect();
    b.codes_in("outcome", &outcomes);
    let dir = b.keyset("time_ms", q.order, q.after);
    Ok(b.finish(COMMAND_COLUMNS, "commands", "time_ms", dir, q.limit))
}

/// Cuts the extra row off a query result and computes the next cursor.
pub(crate) fn into_page<T>(
    mut items: Vec<T>,
    limit: usize,
    key: impl Fn(&T) -> Option<Cursor>,
) -> Page<T> {
    let more = items.len() > limit;
    items.truncate(limit);
    let next = if more {
        items.last().and_then(key)
    } else {
        None
    };
    Page { items, next }
}

/// The cursor after an event, by the query's time basis.
pub(crate) fn event_cursor(e: &EventRecord, basis: TimeBasis) -> Option<Cursor> {
    let t = match basis {
        TimeBasis::Source => e.event_time(),
        TimeBasis::Received => e.received_time,
    };
    e.id.map(|id| Cursor::new(to_ms(t), id))
}

/// The cursor after a command record.
pub(crate) fn command_cursor(c: &CommandRecord) -> Option<Cursor> {
    c.id.map(|id| Cursor::new(to_ms(c.time), id))
}
