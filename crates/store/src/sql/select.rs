//! The `SELECT`s of the queries: filters, keyset pagination and pages, in either dialect;
//! and the offset pages of the lift fault archive and the notification record, each a
//! count and a page ([`Counted`]).

use chrono::{DateTime, NaiveDateTime, Utc};

use super::row::{naive_to_ms, to_ms, COMMAND_COLUMNS, LIFT_FAULT_COLUMNS, NOTIFICATION_COLUMNS};
use super::{Access, Param, Statement};
use crate::query::{Cursor, Order, PointFilter, MAX_PAGE_SIZE};
use crate::{
    Backend, CommandQuery, CommandRecord, LiftFaultOrder, LiftFaultQuery, NotificationQuery, Page,
    StoreError,
};

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

/// The cursor after a command record.
pub(crate) fn command_cursor(c: &CommandRecord) -> Option<Cursor> {
    c.id.map(|id| Cursor::new(to_ms(c.time), id))
}
