//! The `SELECT`s of the queries: filters, keyset pagination and pages, in either dialect;
//! and the offset pages of the lift fault archive and the notification record, each a
//! count and a page ([`Counted`]).

use chrono::{DateTime, NaiveDateTime, Utc};

use super::row::{
    naive_to_ms, to_ms, COMMAND_COLUMNS, EVENT_COLUMNS, LIFT_FAULT_COLUMNS, NOTIFICATION_COLUMNS,
};
use super::{Access, Param, Statement};
use crate::query::{Cursor, Order, PointFilter, TimeBasis, MAX_PAGE_SIZE};
use crate::{
    Backend, CommandQuery, CommandRecord, EventQuery, EventRecord, LiftFaultOrder, LiftFaultQuery,
    NotificationQuery, Page, StoreError, TrendMode, TrendQuery,
};

/// The aggregation of a trend: one row per non-empty bucket of the range, oldest first,
/// with the first and last time, min, max, mean, count and IV of its values (booleans,
/// integers and floats: value kinds 1, 3, 4).
///
/// Where the query has a rollup span ([`TrendQuery::rollup_span_ms`]), the whole minutes
/// inside the range are read from `trend_rollups` (each counted in the bucket its start
/// falls in, so a bucket's edges move to a minute's) and only the partial minutes at the
/// range's two ends from `events`: 60 days of a point are 86,400 minute rows, however
/// many events they hold. Otherwise every event of the range is read, through the index
/// on (point, event_ms).
///
/// A [`TrendMode::FirstLast`] query adds each bucket's first and last value, by two key
/// lookups per bucket: the kept first (last) value of the minute holding the bucket's
/// first (last) time, or, for a partial minute at an end of the range, the event's (by
/// (time, id) as the raw seeks read them). (Window functions over the slices, the plain
/// SQL for "the value of the row with the least time", took 268 ms on SQLite for 60
/// days: the lookups add a few milliseconds to the aggregation.)
pub(crate) fn trend_sql(query: &TrendQuery, backend: Backend) -> Statement {
    let (from_ms, to_ms) = (to_ms(query.from), to_ms(query.to));
    let mut b = SelectBuilder::new(backend);
    let point = b.bind(Param::text(query.point.as_str()));
    let from = b.bind(Param::int(from_ms));
    let width = b.bind(Param::int(query.bucket_ms()));
    let mut parts = Vec::new();
    let raw = |b: &mut SelectBuilder, start: i64, end: i64| {
        let (start, end) = (b.bind(Param::int(start)), b.bind(Param::int(end)));
        format!(
            "SELECT CAST((event_ms - {from}) / {width} AS BIGINT) AS bucket, \
                    event_ms AS first_ms, event_ms AS last_ms, v AS min_v, v AS max_v, \
                    v AS sum_v, 1 AS n, iv \
             FROM (SELECT event_ms, (quality & 1) AS iv, \
                          COALESCE(value_float, CAST(value_int AS DOUBLE PRECISION)) AS v \
                   FROM events \
                   WHERE point = {point} AND event_ms >= {start} AND event_ms < {end} \
                     AND value_kind IN (1, 3, 4) \
                     AND (value_float IS NOT NULL OR value_int IS NOT NULL)) AS raw"
        )
    };
    match query.rollup_span_ms() {
        Some(span) => {
            // The whole spans of the range, and the partial ones at its two ends.
            let inner_from = (from_ms + span - 1).div_euclid(span) * span;
            let inner_to = (to_ms.div_euclid(span) * span).max(inner_from);
            let (start, end) = (b.bind(Param::int(inner_from)), b.bind(Param::int(inner_to)));
            parts.push(format!(
                "SELECT CAST((start_ms - {from}) / {width} AS BIGINT) AS bucket, first_ms, \
                        last_ms, min_value AS min_v, max_value AS max_v, sum_value AS sum_v, \
                        samples AS n, invalid AS iv \
                 FROM trend_rollups \
                 WHERE point = {point} AND start_ms >= {start} \
                   AND start_ms < {end}"
            ));
            if from_ms < inner_from {
                parts.push(raw(&mut b, from_ms, inner_from.min(to_ms)));
            }
            if inner_to < to_ms {
                parts.push(raw(&mut b, inner_to, to_ms));
            }
        }
        None => parts.push(raw(&mut b, from_ms, to_ms)),
    }
    let aggregates = format!(
        "SELECT bucket, CAST(MIN(first_ms) AS BIGINT) AS first_ms, \
                CAST(MAX(last_ms) AS BIGINT) AS last_ms, MIN(min_v) AS min_v, \
                MAX(max_v) AS max_v, SUM(sum_v) / CAST(SUM(n) AS DOUBLE PRECISION) AS avg_v, \
                CAST(SUM(n) AS BIGINT) AS n, CAST(MAX(iv) AS BIGINT) AS iv \
         FROM ({}) AS slice GROUP BY bucket",
        parts.join(" UNION ALL ")
    );
    let columns = "first_ms, last_ms, min_v, max_v, avg_v, n, iv";
    let sql = match query.mode {
        TrendMode::Aggregate => {
            format!("SELECT {columns} FROM ({aggregates}) AS agg ORDER BY bucket")
        }
        TrendMode::FirstLast => {
            // The value at the bucket's first (last) time: its minute's kept value where
            // that minute's first (last) time is the bucket's, else (a partial minute at
            // an end of the range, or a minute folded before schema version 5, which
            // kept none) the event's, by one seek each.
            let end = |time: &str, kept: &str, order: &str| {
                format!(
                    "COALESCE( \
                       (SELECT r.{kept} FROM trend_rollups r \
                        WHERE r.point = {point} \
                          AND r.start_ms = agg.{time} - (agg.{time} % 60000 + 60000) % 60000 \
                          AND r.{time} = agg.{time}), \
                       (SELECT COALESCE(e.value_float, CAST(e.value_int AS DOUBLE PRECISION)) \
                        FROM events e \
                        WHERE e.point = {point} AND e.event_ms = agg.{time} \
                          AND e.value_kind IN (1, 3, 4) \
                          AND (e.value_float IS NOT NULL OR e.value_int IS NOT NULL) \
                        ORDER BY e.id {order} LIMIT 1))"
                )
            };
            format!(
                "SELECT {columns}, {}, {} FROM ({aggregates}) AS agg ORDER BY bucket",
                end("first_ms", "first_value", "ASC"),
                end("last_ms", "last_value", "DESC"),
            )
        }
    };
    Statement {
        access: Access::Read,
        sql,
        params: b.params,
    }
}

/// A `SELECT` under construction: a WHERE clause with its parameters.
struct SelectBuilder {
    backend: Backend,
    conds: Vec<String>,
    params: Vec<Param>,
}

impl SelectBuilder {
    fn new(backend: Backend) -> Self {
        SelectBuilder {
            backend,
            conds: Vec::new(),
            params: Vec::new(),
        }
    }

    /// Adds a parameter and returns its placeholder.
    fn bind(&mut self, p: Param) -> String {
        let placeholder = p.placeholder(self.backend, self.params.len() + 1);
        self.params.push(p);
        placeholder
    }

    fn cond(&mut self, c: String) {
        self.conds.push(c);
    }

    fn time_range(&mut self, col: &str, from: Option<DateTime<Utc>>, to: Option<DateTime<Utc>>) {
        if let Some(from) = from {
            let p = self.bind(Param::int(to_ms(from)));
            self.cond(format!("{col} >= {p}"));
        }
        if let Some(to) = to {
            let p = self.bind(Param::int(to_ms(to)));
            self.cond(format!("{col} < {p}"));
        }
    }

    fn point(&mut self, filter: &Option<PointFilter>) {
        match filter {
            None => {}
            Some(PointFilter::Exact(name)) => {
                let p = self.bind(Param::text(name));
                self.cond(format!("point = {p}"));
            }
            Some(PointFilter::Prefix(prefix)) if prefix.is_empty() => {}
            Some(PointFilter::Prefix(prefix)) => {
                // A byte-wise range: every name starting with `prefix` sorts at or after it
                // and before `prefix` + U+10FFFF (the largest scalar value), under SQLite's
                // BINARY and PostgreSQL's "C" collation alike, so the point index serves it.
                let lo = self.bind(Param::text(prefix));
                let hi = self.bind(Param::text(format!("{prefix}\u{10FFFF}")));
                self.cond(format!("point >= {lo} AND point < {hi}"));
            }
        }
    }

    fn text_eq(&mut self, col: &str, value: &Option<String>) {
        if let Some(v) = value {
            let p = self.bind(Param::text(v));
            self.cond(format!("{col} = {p}"));
        }
    }

    fn codes_in(&mut self, col: &str, codes: &[i16]) {
        self.any_of(col, codes.iter().map(|c| Param::int(i64::from(*c))));
    }

    /// `col IN (values)`; nothing when there are no values.
    fn any_of(&mut self, col: &str, values: impl IntoIterator<Item = Param>) {
        let list: Vec<String> = values.into_iter().map(|p| self.bind(p)).collect();
        if !list.is_empty() {
            self.cond(format!("{col} IN ({})", list.join(", ")));
        }
    }

    fn naive_range(
        &mut self,
        col: &str,
        since: Option<NaiveDateTime>,
        until: Option<NaiveDateTime>,
    ) {
        if let Some(since) = since {
            let p = self.bind(Param::int(naive_to_ms(since)));
            self.cond(format!("{col} >= {p}"));
        }
        if let Some(until) = until {
            let p = self.bind(Param::int(naive_to_ms(until)));
            self.cond(format!("{col} < {p}"));
        }
    }

    /// The count of the rows matching the conditions, and one page of them by offset.
    fn counted(
        mut self,
        columns: &str,
        table: &str,
        order_by: &str,
        offset: u64,
        limit: u32,
    ) -> Result<Counted, StoreError> {
        check_limit(usize::try_from(limit).unwrap_or(usize::MAX))?;
        let offset = i64::try_from(offset)
            .map_err(|_| StoreError::InvalidQuery(format!("offset {offset} out of range")))?;
        let filter = if self.conds.is_empty() {
            String::new()
        } else {
            format!(" WHERE {}", self.conds.join(" AND "))
        };
        let count = Statement {
            access: Access::Read,
            sql: format!("SELECT count(*) FROM {table}{filter}"),
            params: self.params.clone(),
        };
        let lim = self.bind(Param::int(i64::from(limit)));
        let off = self.bind(Param::int(offset));
        let page = Statement {
            access: Access::Read,
            sql: format!(
                "SELECT {columns} FROM {table}{filter} ORDER BY {order_by} LIMIT {lim} OFFSET {off}"
            ),
            params: self.params,
        };
        Ok(Counted { count, page })
    }

    fn keyset(&mut self, col: &str, order: Order, after: Option<Cursor>) -> &'static str {
        let (cmp, dir) = match order {
            Order::NewestFirst => ("<", "DESC"),
            Order::OldestFirst => (">", "ASC"),
        };
        if let Some(c) = after {
            let t = self.bind(Param::int(c.time_ms));
            let id = self.bind(Param::int(c.id));
            // The redundant plain bound lets an index on (name, time, id) use the range
            // after an equality on its first column (PostgreSQL uses a row comparison only
            // on leading index columns).
            let t2 = self.bind(Param::int(c.time_ms));
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
    ) -> Statement {
        // One row more than asked tells whether another page follows.
        let lim = self.bind(Param::int(
            i64::try_from(limit).unwrap_or(i64::MAX).saturating_add(1),
        ));
        let mut sql = format!("SELECT {columns} FROM {table}");
        if !self.conds.is_empty() {
            sql.push_str(" WHERE ");
            sql.push_str(&self.conds.join(" AND "));
        }
        sql.push_str(&format!(" ORDER BY {time_col} {dir}, id {dir} LIMIT {lim}"));
        Statement {
            access: Access::Read,
            sql,
            params: self.params,
        }
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

/// The SQL and parameters of an event query.
pub(crate) fn event_sql(q: &EventQuery, backend: Backend) -> Result<Statement, StoreError> {
    check_limit(q.limit)?;
    let mut b = SelectBuilder::new(backend);
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
pub(crate) fn command_sql(q: &CommandQuery, backend: Backend) -> Result<Statement, StoreError> {
    check_limit(q.limit)?;
    let mut b = SelectBuilder::new(backend);
    b.time_range("time_ms", q.from, q.to);
    b.text_eq("actor", &q.actor);
    b.point(&q.point);
    b.text_eq("node", &q.node);
    let outcomes: Vec<i16> = q.outcomes.iter().map(|c| c.code()).collect();
    b.codes_in("outcome", &outcomes);
    let dir = b.keyset("time_ms", q.order, q.after);
    Ok(b.finish(COMMAND_COLUMNS, "commands", "time_ms", dir, q.limit))
}

/// The two statements of an offset-paged query: how many rows match, and one page.
#[derive(Debug)]
pub(crate) struct Counted {
    pub(crate) count: Statement,
    pub(crate) page: Statement,
}

/// The statements of a lift fault archive query.
pub(crate) fn lift_fault_sql(q: &LiftFaultQuery, backend: Backend) -> Result<Counted, StoreError> {
    let mut b = SelectBuilder::new(backend);
    b.text_eq("node", &q.node);
    b.any_of("lift", q.lifts.iter().map(Param::text));
    b.any_of("code", q.codes.iter().map(|c| Param::int(i64::from(*c))));
    b.naive_range("filed_ms", q.since, q.until);
    b.naive_range(
        "received_ms",
        q.received_since.map(|t| t.naive_utc()),
        q.received_until.map(|t| t.naive_utc()),
    );
    let dir = if q.descending { "DESC" } else { "ASC" };
    let key = match q.order {
        LiftFaultOrder::Archived => None,
        LiftFaultOrder::BoardTime => Some("filed_ms"),
        LiftFaultOrder::Received => Some("received_ms"),
        LiftFaultOrder::Code => Some("code"),
        LiftFaultOrder::Lift => Some("lift"),
        LiftFaultOrder::Floor => Some("floor"),
    };
    // The id last, in the same direction: the order is total, so offsets cut it exactly.
    let order_by = match key {
        Some(key) => format!("{key} {dir}, id {dir}"),
        None => format!("id {dir}"),
    };
    b.counted(
        LIFT_FAULT_COLUMNS,
        "lift_faults",
        &order_by,
        q.offset,
        q.limit,
    )
}

/// The statements of a notification query (newest first).
pub(crate) fn notification_sql(
    q: &NotificationQuery,
    backend: Backend,
) -> Result<Counted, StoreError> {
    let mut b = SelectBuilder::new(backend);
    b.text_eq("source", &q.source);
    b.counted(
        NOTIFICATION_COLUMNS,
        "notifications",
        "time_ms DESC, id DESC",
        q.offset,
        q.limit,
    )
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
