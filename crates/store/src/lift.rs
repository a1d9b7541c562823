//! The fault archive of lift controller boards (Rekoba EKM66, lift spec 4.3 and 7): every
//! record read from a board's fault stack ([`LiftFaultRecord`]) and the query of the
//! archive table of the HMI ([`LiftFaultQuery`], answered as a [`CountedPage`]).
//!
//! Unlike the event list, the archive is paged by offset: its table is sorted by any
//! column, in either direction, and shows "page 3 of 12". Every order ends with the row id,
//! so it is total and pages never repeat or skip a row while the archive stands still.
//! The archive is kept for years (faults per year, MTBF): retention never purges it.
//!
//! # Board time
//!
//! A board writes the time of occurrence on its own clock, without a zone
//! ([`LiftFaultRecord::board_time`]); the store keeps that wall-clock reading as it is (as
//! if it were UTC) and never converts it. A record whose board time was impossible (month
//! 13) has none; for filtering ([`LiftFaultQuery::since`], [`LiftFaultQuery::until`]) and
//! for [`LiftFaultOrder::BoardTime`] such a record is filed under its received time's UTC
//! wall clock ([`LiftFaultRecord::filed_time`]), so it stays in the archive's time line
//! near where it belongs (the board's zone offset away at most) rather than at one end.

use chrono::{DateTime, NaiveDateTime, Utc};

use crate::model::RecordId;
use crate::query::DEFAULT_PAGE_SIZE;

/// One record of a lift board's fault stack, as archived.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct LiftFaultRecord {
    /// Assigned by the store: `None` on append (ignored), `Some` in query results. Ids grow
    /// with insertion, so they are the archive's order.
    pub id: Option<RecordId>,
    /// The station node watching the lift.
    pub node: String,
    /// The lift's name.
    pub lift: String,
    /// The record's slot in the board's fault stack.
    pub stack_index: u8,
    /// The fault code (lift spec Appendix B).
    pub code: u8,
    /// The floor the car was at.
    pub floor: u8,
    /// The target floor, when the fault happened while travelling.
    pub target: u8,
    /// When the fault happened, as the board's clock wrote it (no zone; milliseconds are
    /// the finest part kept); `None` when the board sent an impossible date.
    pub board_time: Option<NaiveDateTime>,
    /// When this station archived the record (its own clock), ms precision.
    pub received_time: DateTime<Utc>,
}

impl LiftFaultRecord {
    /// The time the record is filed under for time filters and [`LiftFaultOrder::BoardTime`]:
    /// the board time, or the received time's UTC wall clock when the board time is
    /// missing.
    pub fn filed_time(&self) -> NaiveDateTime {
        self.board_time
            .unwrap_or_else(|| self.received_time.naive_utc())
    }
}

/// The column a [`LiftFaultQuery`] sorts by. Every order is broken by the record id in the
/// same direction, so it is total.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Hash)]
pub enum LiftFaultOrder {
    /// Archive (insertion, id) order: with `descending` and a limit of N, the newest N
    /// records (what a restarted monitor rebuilds its archive cursor from).
    Archived,
    /// The board time (see [`LiftFaultRecord::filed_time`]).
    #[default]
    BoardTime,
    /// The time the station archived the record.
    Received,
    /// The fault code.
    Code,
    /// The lift's name (byte-wise).
    Lift,
    /// The floor the car was at.
    Floor,
}

/// A query over the lift fault archive. Build it with [`LiftFaultQuery::default`] (every
/// record, newest board time first, the first [`DEFAULT_PAGE_SIZE`] rows) and the `with_*`
/// methods.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub struct LiftFaultQuery {
    /// Only records of this node.
    pub node: Option<String>,
    /// Only records of these lifts; empty means every lift.
    pub lifts: Vec<String>,
    /// Only records with one of these fault codes; empty means every code (the HMI turns
    /// a text filter into the codes whose texts match).
    pub codes: Vec<u8>,
    /// Only records filed at or after this time (board time, see
    /// [`LiftFaultRecord::filed_time`]).
    pub since: Option<NaiveDateTime>,
    /// Only records filed strictly before this time.
    pub until: Option<NaiveDateTime>,
    /// Only records archived at or after this time (the station's clock: a board whose
    /// clock is wrong files its records elsewhere, the service figures count by this).
    pub received_since: Option<DateTime<Utc>>,
    /// Only records archived strictly before this time.
    pub received_until: Option<DateTime<Utc>>,
    /// The sort column.
    pub order: LiftFaultOrder,
    /// Largest first (and the id tie-break descending too).
    pub descending: bool,
    /// Rows of the sorted result to skip.
    pub offset: u64,
    /// Rows to return at most, 1 to [`crate::MAX_PAGE_SIZE`].
    pub limit: u32,
}

impl Default for LiftFaultQuery {
    fn default() -> LiftFaultQuery {
        LiftFaultQuery {
            node: None,
            lifts: Vec::new(),
            codes: Vec::new(),
            since: None,
            until: None,
            received_since: None,
            received_until: None,
            order: LiftFaultOrder::BoardTime,
            descending: true,
            offset: 0,
            limit: u32::try_from(DEFAULT_PAGE_SIZE).unwrap_or(u32::MAX),
        }
    }
}

impl LiftFaultQuery {
    /// The newest `n` records of `lift` in archive order, newest first: what a restarted
    /// monitor reads to rebuild its archive cursor.
    pub fn newest(node: impl Into<String>, lift: impl Into<String>, n: u32) -> LiftFaultQuery {
        LiftFaultQuery::default()
            .with_node(node)
            .with_lifts([lift.into()])
            .with_order(LiftFaultOrder::Archived, true)
            .with_page(0, n)
    }
    /// Only this node.
    pub fn with_node(mut self, node: impl Into<String>) -> Self {
        self.node = Some(node.into());
        self
    }
    /// Only these lifts (none: every lift).
    pub fn with_lifts<I>(mut self, lifts: I) -> Self
    where
        I: IntoIterator,
        I::Item: Into<String>,
    {
        self.lifts = lifts.into_iter().map(Into::into).collect();
        self
    }
    /// Only these fault codes (none: every code).
    pub fn with_codes(mut self, codes: impl IntoIterator<Item = u8>) -> Self {
        self.codes = codes.into_iter().collect();
        self
    }
    /// Only records filed in `[since, until)`; either end may be open.
    pub fn with_range(
        mut self,
        since: Option<NaiveDateTime>,
        until: Option<NaiveDateTime>,
    ) -> Self {
        self.since = since;
        self.until = until;
        self
    }
    /// Only records archived in `[since, until)` by the station's clock; either end may be
    /// open.
    pub fn with_received_range(
        mut self,
        since: Option<DateTime<Utc>>,
        until: Option<DateTime<Utc>>,
    ) -> Self {
        self.received_since = since;
        self.received_until = until;
        self
    }
    /// Sort by this column, largest first when `descending`.
    pub fn with_order(mut self, order: LiftFaultOrder, descending: bool) -> Self {
        self.order = order;
        self.descending = descending;
        self
    }
    /// Skip `offset` rows, return `limit` at most.
    pub fn with_page(mut self, offset: u64, limit: u32) -> Self {
        self.offset = offset;
        self.limit = limit;
        self
    }
}
