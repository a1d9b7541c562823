//! What SQLite and PostgreSQL share: the schema and its migrations ([`schema`]), the
//! queries' SQL ([`select`]), the mapping of records to columns and back ([`row`]), and the
//! whole [`EventStore`] behaviour on top of a few primitives each backend implements
//! ([`Database`]): run a statement, read rows, append a batch of events.
//!
//! ```text
//!  EventStore (here, once) --SQL text + Param list--> Database (sqlite.rs | postgres.rs)
//!        ^                                                  | rows, as Columns
//!        +------------- row::event_from_row & co. <---------+
//! ```

pub(crate) mod row;
pub(crate) mod schema;
mod select;

use chrono::{DateTime, Utc};

use crate::history::codec::NameId;
use crate::history::write::HistoryWrite;
use crate::history::History;
use crate::{
    Backend, CommandQuery, CommandRecord, CountedPage, EventQuery, EventRecord, EventStore,
    LiftFaultArchive, LiftFaultQuery, LiftFaultRecord, NotificationLog, NotificationQuery,
    NotificationRecord, Page, RecordId, StoreError, StoreFuture, StoreStats, TrendBucket,
    TrendQuery, MAX_TREND_BUCKETS, ROLLUP_SPAN_MS,
};
use row::OwnedRow;
use row::{
    check_command, check_event, check_lift_fault, check_notification, command_from_row,
    command_params, count_from_row, id_from_row, lift_fault_from_row, lift_fault_params,
    notification_from_row, notification_params, stats_from_row, to_ms, Decode, COMMAND_INSERT,
    LIFT_FAULT_INSERT, NOTIFICATION_INSERT,
};
use select::{command_cursor, command_sql, into_page, lift_fault_sql, notification_sql, Counted};

/// Rows one purge statement deletes, so appends interleave with a large purge.
const PURGE_CHUNK: i64 = 10_000;

/// A bound SQL parameter, typed so that PostgreSQL's placeholders can say their type.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Param {
    /// An integer of any width, or a typed NULL.
    Int(Option<i64>),
    /// A floating-point number, or a typed NULL.
    Real(Option<f64>),
    /// A text, or a typed NULL.
    Text(Option<String>),
}

impl Param {
    pub(crate) fn int(i: i64) -> Param {
        Param::Int(Some(i))
    }

    pub(crate) fn text(t: impl Into<String>) -> Param {
        Param::Text(Some(t.into()))
    }

    /// PostgreSQL's name of the type.
    fn pg_type(&self) -> &'static str {
        match self {
            Param::Int(_) => "int8",
            Param::Real(_) => "float8",
            Param::Text(_) => "text",
        }
    }

    /// The placeholder of parameter number `n` (from 1): `?n` or `$n::type`.
    pub(crate) fn placeholder(&self, backend: Backend, n: usize) -> String {
        match backend {
            Backend::Sqlite => format!("?{n}"),
            Backend::Postgres => format!("${n}::{}", self.pg_type()),
        }
    }
}

/// `INSERT INTO table (columns) VALUES (...)` for rows like `row` (the parameters'
/// types give PostgreSQL's placeholders).
pub(crate) fn insert_sql(backend: Backend, table: &str, columns: &str, row: &[Param]) -> String {
    let values: Vec<String> = row
        .iter()
        .enumerate()
        .map(|(i, p)| p.placeholder(backend, i + 1))
        .collect();
    format!(
        "INSERT INTO {table} ({columns}) VALUES ({})",
        values.join(", ")
    )
}

/// `INSERT INTO table (columns) VALUES (...) RETURNING id` for one row.
pub(crate) fn insert(backend: Backend, table: &str, columns: &str, row: Vec<Param>) -> Statement {
    Statement {
        access: Access::Write,
        sql: format!("{} RETURNING id", insert_sql(backend, table, columns, &row)),
        params: row,
    }
}

/// Which connection a statement needs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Access {
    /// A query: any connection (a reader).
    Read,
    /// A write: the writer (SQLite), any connection (PostgreSQL).
    Write,
}

/// A statement to run: its SQL, its parameters, and the connection it needs.
#[derive(Debug)]
pub(crate) struct Statement {
    pub(crate) access: Access,
    pub(crate) sql: String,
    pub(crate) params: Vec<Param>,
}

/// What a backend does itself; [`EventStore`] is built on it once for both.
pub(crate) trait Database: Send + Sync {
    /// The database behind it.
    const BACKEND: Backend;

    /// Runs a statement and decodes each row it returns with `each`.
    fn rows<T: Send + 'static>(&self, run: Statement, each: Decode<T>) -> StoreFuture<'_, Vec<T>>;

    /// Runs a writing statement; returns how many rows it changed.
    fn execute(&self, sql: String, params: Vec<Param>) -> StoreFuture<'_, u64>;

    /// Appends checked, non-empty `rows` (parameters in the order of `columns`, all of
    /// one shape) to `table` in one transaction; ids in their order. For the small batches
    /// of other tables than `events`.
    fn insert_rows(
        &self,
        table: &'static str,
        columns: &'static str,
        rows: Vec<Vec<Param>>,
    ) -> StoreFuture<'_, Vec<RecordId>>;

    /// Deletes events whose event time, and command records whose time, is before
    /// `cutoff_ms`; returns how many went. SQLite deletes rows in chunks; PostgreSQL drops
    /// whole day partitions (so up to a day more than the cutoff stays).
    fn purge_history(&self, cutoff_ms: i64) -> StoreFuture<'_, u64>;

    /// Deletes the trend rollups whose events [`Database::purge_history`] purged at
    /// `cutoff_ms`: those of the minutes before the cutoff's (a minute before it ends
    /// before the cutoff), by ranges of the key. PostgreSQL drops them by whole days.
    fn purge_rollups(&self, cutoff_ms: i64) -> StoreFuture<'_, ()>
    where
        Self: Sized,
    {
        Box::pin(delete_rollups_before(
            self,
            cutoff_ms.div_euclid(ROLLUP_SPAN_MS) * ROLLUP_SPAN_MS,
        ))
    }

    /// Rewrites what no longer changes in the order it is read
    /// ([`EventStore::compact_closed_days`]); nothing to do by default.
    fn compact_closed_days(&self, now: DateTime<Utc>) -> StoreFuture<'_, u64> {
        let _ = now;
        Box::pin(async { Ok(0) })
    }

    /// Before a command record of `time_ms` is appended (PostgreSQL makes its day's
    /// partition).
    fn before_command(&self, time_ms: i64) -> StoreFuture<'_, ()> {
        let _ = time_ms;
        Box::pin(async { Ok(()) })
    }

    /// Makes the storage for the days from `now` on ready ([`EventStore::prepare_partitions`]).
    fn prepare_partitions(&self, now: DateTime<Utc>) -> StoreFuture<'_, ()> {
        let _ = now;
        Box::pin(async { Ok(()) })
    }

    /// Refreshes the query planner's statistics.
    fn analyze(&self) -> StoreFuture<'_, ()>;

    /// The event history's state ([`crate::history`]: names, the writer).
    fn history(&self) -> &History;

    /// The numbers of `names` in `event_names`, adding those missing; one pair per name.
    fn name_ids(&self, names: Vec<String>) -> StoreFuture<'_, Vec<(NameId, String)>> {
        let _ = names;
        Box::pin(async { Err(StoreError::Closed) })
    }

    /// Takes `count` event ids from the store's counter for an append (several writers
    /// share it: PostgreSQL); `None`: the one writer counts them itself and stores the
    /// count with each write (SQLite).
    fn reserve_ids(&self, count: usize) -> StoreFuture<'_, Option<i64>> {
        let _ = count;
        Box::pin(async { Ok(None) })
    }

    /// Writes one append of the history (blocks, key runs, the event counter and a
    /// pass) in one transaction.
    fn write_history(&self, write: HistoryWrite) -> StoreFuture<'_, ()> {
        let _ = write;
        Box::pin(async { Err(StoreError::Closed) })
    }

    /// Runs read statements in one snapshot (one read transaction): a write committed
    /// meanwhile is seen by all of them or by none.
    fn snapshot(&self, statements: Vec<Statement>) -> StoreFuture<'_, Vec<Vec<OwnedRow>>> {
        let _ = statements;
        Box::pin(async { Err(StoreError::Closed) })
    }

    /// Closes the connections ([`EventStore::close`]).
    fn close(&self) -> StoreFuture<'_, ()>;
}

/// The one row a statement must return.
async fn one<D: Database, T: Send + 'static>(
    db: &D,
    run: Statement,
    decode: Decode<T>,
) -> Result<T, StoreError> {
    db.rows(run, decode)
        .await?
        .into_iter()
        .next()
        .ok_or_else(|| StoreError::Corrupt("a statement returned no row".to_owned()))
}

/// Deletes the rows of `table` whose `column` is before `cutoff_ms`, in chunks of
/// [`PURGE_CHUNK`] so that appends interleave with a large purge; returns how many went.
pub(crate) async fn delete_older<D: Database>(
    db: &D,
    table: &str,
    column: &str,
    cutoff_ms: i64,
) -> Result<u64, StoreError> {
    let (cutoff, limit) = (Param::int(cutoff_ms), Param::int(PURGE_CHUNK));
    let sql = format!(
        "DELETE FROM {table} WHERE id IN (SELECT id FROM {table} WHERE {column} < {} LIMIT {})",
        cutoff.placeholder(D::BACKEND, 1),
        limit.placeholder(D::BACKEND, 2)
    );
    let params = vec![cutoff, limit];
    let mut total = 0u64;
    loop {
        let n = db.execute(sql.clone(), params.clone()).await?;
        total += n;
        if n < PURGE_CHUNK.unsigned_abs() {
            return Ok(total);
        }
    }
}

/// A bucket of a first/last trend read from the rollups: the aggregates, then its first
/// and last value (NULL only where neither the minute nor the events have it: events
/// purged while their minute stayed).
async fn delete_rollups_before<D: Database>(db: &D, before_ms: i64) -> Result<(), StoreError> {
    let points = Statement {
        access: Access::Write,
        sql: "WITH RECURSIVE points (point) AS ( \
                  SELECT MIN(point) FROM trend_rollups \
                  UNION ALL \
                  SELECT (SELECT MIN(t.point) FROM trend_rollups t WHERE t.point > p.point) \
                  FROM points p WHERE p.point IS NOT NULL) \
              SELECT point FROM points WHERE point IS NOT NULL"
            .to_owned(),
        params: Vec::new(),
    };
    let points = db
        .rows(points, |r| {
            r.text(0)?
                .ok_or_else(|| StoreError::Corrupt("a rollup without a point".to_owned()))
        })
        .await?;
    let bind = |n: usize, p: &Param| p.placeholder(D::BACKEND, n);
    let (point, before, limit) = (
        bind(1, &Param::text("")),
        bind(2, &Param::int(0)),
        bind(3, &Param::int(0)),
    );
    // A chunk ends at the chunk's first start after it (a scalar subquery, computed once:
    // an `IN (SELECT ... LIMIT)` became a nested loop over the table on PostgreSQL).
    let sql = format!(
        "DELETE FROM trend_rollups WHERE point = {point} \
           AND start_ms < COALESCE((SELECT start_ms FROM trend_rollups \
                                    WHERE point = {point} AND start_ms < {before} \
                                    ORDER BY start_ms LIMIT 1 OFFSET {limit}), {before})"
    );
    for name in points {
        let params = vec![
            Param::text(name.as_str()),
            Param::int(before_ms),
            Param::int(PURGE_CHUNK),
        ];
        loop {
            let gone = db.execute(sql.clone(), params.clone()).await?;
            if gone < PURGE_CHUNK.unsigned_abs() {
                break;
            }
        }
    }
    Ok(())
}

/// An offset page and the number of rows its filter matches.
async fn counted<D: Database, T: Send + 'static>(
    db: &D,
    run: Counted,
    decode: Decode<T>,
) -> Result<CountedPage<T>, StoreError> {
    let total = one(db, run.count, count_from_row).await?;
    let items = db.rows(run.page, decode).await?;
    Ok(CountedPage { items, total })
}

impl<D: Database> EventStore for D {
    fn backend(&self) -> Backend {
        D::BACKEND
    }

    fn append_events<'a>(&'a self, events: &'a [EventRecord]) -> StoreFuture<'a, Vec<RecordId>> {
        Box::pin(async move {
            if events.is_empty() {
                return Ok(Vec::new());
            }
            events.iter().try_for_each(check_event)?;
            crate::history::append::append(self, self.history(), events).await
        })
    }

    fn append_command<'a>(&'a self, command: &'a CommandRecord) -> StoreFuture<'a, RecordId> {
        Box::pin(async move {
            check_command(command)?;
            self.before_command(to_ms(command.time)).await?;
            let run = insert(
                D::BACKEND,
                "commands",
                COMMAND_INSERT,
                command_params(command),
            );
            one(self, run, id_from_row).await
        })
    }

    fn query_events<'a>(&'a self, query: &'a EventQuery) -> StoreFuture<'a, Page<EventRecord>> {
        Box::pin(
            async move { crate::history::list::query_events(self, self.history(), query).await },
        )
    }

    fn query_commands<'a>(
        &'a self,
        query: &'a CommandQuery,
    ) -> StoreFuture<'a, Page<CommandRecord>> {
        Box::pin(async move {
            let items = self
                .rows(command_sql(query, D::BACKEND)?, command_from_row)
                .await?;
            Ok(into_page(items, query.limit, command_cursor))
        })
    }

    fn purge_older_than(&self, cutoff: DateTime<Utc>) -> StoreFuture<'_, u64> {
        Box::pin(async move {
            let cutoff = to_ms(cutoff);
            let mut total = self.purge_history(cutoff).await?;
            // Not `lift_faults`: the fault archive is kept for years (see the crate doc).
            total += delete_older(self, "notifications", "time_ms", cutoff).await?;
            // The trend rollups whose events are gone (not counted: they are not
            // records).
            self.purge_rollups(cutoff).await?;
            // Refresh the planner's statistics with each (hourly) retention pass: they
            // decide between the point index and the time index for prefix filters.
            self.analyze().await?;
            Ok(total)
        })
    }

    fn prepare_partitions(&self, now: DateTime<Utc>) -> StoreFuture<'_, ()> {
        Database::prepare_partitions(self, now)
    }

    fn compact_closed_days(&self, now: DateTime<Utc>) -> StoreFuture<'_, u64> {
        Database::compact_closed_days(self, now)
    }

    fn close(&self) -> StoreFuture<'_, ()> {
        Database::close(self)
    }

    fn query_trend<'a>(&'a self, query: &'a TrendQuery) -> StoreFuture<'a, Vec<TrendBucket>> {
        Box::pin(async move {
            if query.buckets == 0 || query.buckets > MAX_TREND_BUCKETS {
                return Err(StoreError::InvalidQuery(format!(
                    "a trend has 1 to {MAX_TREND_BUCKETS} buckets, not {}",
                    query.buckets
                )));
            }
            if query.to <= query.from {
                return Ok(Vec::new());
            }
            crate::history::trend::query_trend(self, self.history(), query).await
        })
    }

    fn stats(&self) -> StoreFuture<'_, StoreStats> {
        Box::pin(async move {
            let run = Statement {
                access: Access::Read,
                sql: crate::history::STATS.to_owned(),
                params: Vec::new(),
            };
            one(self, run, stats_from_row).await
        })
    }
}

impl<D: Database> LiftFaultArchive for D {
    fn append_lift_faults<'a>(
        &'a self,
        faults: &'a [LiftFaultRecord],
    ) -> StoreFuture<'a, Vec<RecordId>> {
        Box::pin(async move {
            if faults.is_empty() {
                return Ok(Vec::new());
            }
            faults.iter().try_for_each(check_lift_fault)?;
            let rows = faults.iter().map(lift_fault_params).collect();
            self.insert_rows("lift_faults", LIFT_FAULT_INSERT, rows)
                .await
        })
    }

    fn query_lift_faults<'a>(
        &'a self,
        query: &'a LiftFaultQuery,
    ) -> StoreFuture<'a, CountedPage<LiftFaultRecord>> {
        Box::pin(async move {
            counted(
                self,
                lift_fault_sql(query, D::BACKEND)?,
                lift_fault_from_row,
            )
            .await
        })
    }
}

impl<D: Database> NotificationLog for D {
    fn append_notification<'a>(
        &'a self,
        record: &'a NotificationRecord,
    ) -> StoreFuture<'a, RecordId> {
        Box::pin(async move {
            check_notification(record)?;
            let run = insert(
                D::BACKEND,
                "notifications",
                NOTIFICATION_INSERT,
                notification_params(record),
            );
            one(self, run, id_from_row).await
        })
    }

    fn query_notifications<'a>(
        &'a self,
        query: &'a NotificationQuery,
    ) -> StoreFuture<'a, CountedPage<NotificationRecord>> {
        Box::pin(async move {
            counted(
                self,
                notification_sql(query, D::BACKEND)?,
                notification_from_row,
            )
            .await
        })
    }
}
