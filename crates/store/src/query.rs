//! Queries over the store: filters, ordering and keyset pagination.
//!
//! Pages are cut by the key `(time, id)`: a [`Cursor`] holds the key of the last row handed
//! out, and the next page starts strictly after it. Rows with equal times are ordered by id,
//! so pages never repeat or skip a row, even while new rows are being appended.
//!
//! The lift fault archive and the notification record are paged by offset instead
//! ([`CountedPage`]): their tables sort by any column and show how many pages there are.

use chrono::{DateTime, Utc};
use std::fmt;
use std::str::FromStr;

use crate::model::{Actor, CommandOutcome, EventCause, RecordId};
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

/// One page of an offset-paged query (the lift fault archive, the notification record),
/// with the number of rows the whole query matches, for "page 3 of 12".
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct CountedPage<T> {
    /// The rows, in the query's order.
    pub items: Vec<T>,
    /// How many rows match the query's filter, on every page together. Counted by a
    /// statement of its own: a row appended between the two may be counted and not
    /// listed, or the other way round.
    pub total: u64,
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
