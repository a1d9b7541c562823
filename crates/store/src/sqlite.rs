//! The SQLite backend: embedded, WAL mode, connections on their own threads.
//!
//! One writer connection lives on a dedicated thread and takes jobs (closures) from a
//! queue; two reader connections share another queue, so a long query never holds up an
//! append and no async task ever blocks on SQLite. A `sqlite::memory:` database is private
//! to its connection, so there the writer serves the reads too.

use chrono::{DateTime, Utc};
use rusqlite::{params, params_from_iter, Connection, OpenFlags, Row, TransactionBehavior};
use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::sync::{Arc, Mutex};
use std::time::Duration;
use tokio::sync::oneshot;

use crate::model::{
    check_command, check_event, from_ms, quality_to_bits, to_ms, CommandRecord, EventRecord,
    RawCommand, RawEvent, RecordId,
};
use crate::query::{
    command_cursor, command_sql, event_cursor, event_sql, into_page, Dialect, Param,
};
use crate::{
    Backend, CommandQuery, EventQuery, EventStore, Page, StoreError, StoreFuture, StoreStats,
};

/// The migrations, in version order.
const MIGRATIONS: &[(i64, &str)] = &[(1, include_str!("../migrations/sqlite/0001_init.sql"))];

/// How long a connection waits for a lock held by another process before failing.
const BUSY_TIMEOUT: Duration = Duration::from_secs(5);

/// Reader connections of a file database.
const READERS: usize = 2;

/// Rows one purge job deletes, so appends interleave with a large purge.
const PURGE_CHUNK: i64 = 10_000;

type Job = Box<dyn FnOnce(&mut Connection) + Send>;

/// Threads that each own a connection and run jobs from one shared queue.
#[derive(Clone)]
struct Worker {
    queue: mpsc::Sender<Job>,
}

impl Worker {
    fn spawn(name: &str, connections: Vec<Connection>) -> Result<Worker, StoreError> {
        let (queue, rx) = mpsc::channel::<Job>();
        let rx = Arc::new(Mutex::new(rx));
        for (i, mut conn) in connections.into_iter().enumerate() {
            let rx = Arc::clone(&rx);
            std::thread::Builder::new()
                .name(format!("{name}-{i}"))
                .spawn(move || loop {
                    // The lock is held only while waiting for the next job.
                    let job = match rx.lock() {
                        Ok(rx) => rx.recv(),
                        Err(_) => break,
                    };
                    match job {
                        Ok(job) => job(&mut conn),
                        Err(_) => break, // the store was dropped
                    }
                })
                .map_err(StoreError::Thread)?;
        }
        Ok(Worker { queue })
    }

    async fn run<T, F>(&self, f: F) -> Result<T, StoreError>
    where
        T: Send + 'static,
        F: FnOnce(&mut Connection) -> Result<T, StoreError> + Send + 'static,
    {
        let (tx, rx) = oneshot::channel();
        self.queue
            .send(Box::new(move |conn| {
                let _ = tx.send(f(conn));
            }))
            .map_err(|_| StoreError::Closed)?;
        rx.await.map_err(|_| StoreError::Closed)?
    }
}

/// The SQLite event store. Open it with [`SqliteStore::open`] or through
/// [`crate::open_store`].
pub struct SqliteStore {
    writer: Worker,
    readers: Worker,
    path: Option<PathBuf>,
}

impl std::fmt::Debug for SqliteStore {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SqliteStore")
            .field("path", &self.path)
            .finish()
    }
}

fn configure(conn: &Connection) -> Result<(), StoreError> {
    conn.busy_timeout(BUSY_TIMEOUT)?;
    Ok(())
}

fn open_writer(path: &Path) -> Result<Connection, StoreError> {
    let conn = Connection::open(path)?;
    configure(&conn)?;
    // WAL: readers never block the writer nor the writer the readers. NORMAL sync in WAL
    // mode keeps the database consistent on power loss and loses at most the last
    // transactions since the previous checkpoint sync; a process crash loses nothing.
    let mode: String = conn.query_row("PRAGMA journal_mode = WAL", [], |r| r.get(0))?;
    if !mode.eq_ignore_ascii_case("wal") {
        tracing::warn!(%mode, "SQLite refused WAL mode");
    }
    conn.pragma_update(None, "synchronous", "NORMAL")?;
    migrate(&conn)?;
    // Analyses what needs it at open (SQLite's advice for long-lived connections), with
    // a bounded sample so a large database still opens quickly.
    conn.execute_batch("PRAGMA analysis_limit = 1000; PRAGMA optimize = 0x10002")?;
    Ok(conn)
}

fn open_reader(path: &Path) -> Result<Connection, StoreError> {
    let conn = Connection::open_with_flags(
        path,
        OpenFlags::SQLITE_OPEN_READ_WRITE | OpenFlags::SQLITE_OPEN_NO_MUTEX,
    )?;
    configure(&conn)?;
    conn.pragma_update(None, "query_only", "ON")?;
    Ok(conn)
}

/// Applies the migrations newer than the database's `schema_version`, each in its own
/// immediate (write-locked) transaction.
fn migrate(conn: &Connection) -> Result<(), StoreError> {
    conn.execute_batch(
        "CREATE TABLE IF NOT EXISTS schema_version (
             version    INTEGER PRIMARY KEY,
             applied_ms INTEGER NOT NULL
         )",
    )?;
    let supported = MIGRATIONS.last().map(|m| m.0).unwrap_or(0);
    for &(version, sql) in MIGRATIONS {
        let tx = rusqlite::Transaction::new_unchecked(conn, TransactionBehavior::Immediate)?;
        let current: i64 = tx.query_row(
            "SELECT coalesce(max(version), 0) FROM schema_version",
            [],
            |r| r.get(0),
        )?;
        if current > supported {
            return Err(StoreError::SchemaTooNew {
                found: current,
                supported,
            });
        }
        if current >= version {
            continue;
        }
        tx.execute_batch(sql).map_err(|e| StoreError::Migration {
            version,
            source: Box::new(e.into()),
        })?;
        tx.execute(
            "INSERT INTO schema_version (version, applied_ms) VALUES (?1, ?2)",
            params![version, Utc::now().timestamp_millis()],
        )?;
        tx.commit()?;
        tracing::info!(version, "applied SQLite migration");
    }
    Ok(())
}

impl SqliteStore {
    /// Runs a query on a reader connection and maps every row.
    async fn select<T: Send + 'static>(
        &self,
        sql: String,
        params: Vec<Param>,
        row: fn(&Row<'_>) -> rusqlite::Result<T>,
    ) -> Result<Vec<T>, StoreError> {
        let params = sql_params(params);
        self.readers
            .run(move |c| {
                let mut stmt = c.prepare_cached(&sql)?;
                let rows = stmt
                    .query_map(params_from_iter(params), row)?
                    .collect::<Result<Vec<_>, _>>()?;
                Ok(rows)
            })
            .await
    }

    /// Opens (creating and migrating when needed) the database file at `path`.
    pub async fn open(path: impl AsRef<Path>) -> Result<SqliteStore, StoreError> {
        let path = path.as_ref().to_path_buf();
        let p = path.clone();
        let (writer, readers) = tokio::task::spawn_blocking(move || {
            let writer = open_writer(&p)?;
            let readers = (0..READERS)
                .map(|_| open_reader(&p))
                .collect::<Result<Vec<_>, _>>()?;
            Ok::<_, StoreError>((writer, readers))
        })
        .await
        .map_err(|_| StoreError::Closed)??;
        Ok(SqliteStore {
            writer: Worker::spawn("sqlite-writer", vec![writer])?,
            readers: Worker::spawn("sqlite-reader", readers)?,
            path: Some(path),
        })
    }

    /// Opens a private in-memory database (for tests and demos).
    pub async fn open_in_memory() -> Result<SqliteStore, StoreError> {
        let conn = tokio::task::spawn_blocking(|| {
            let conn = Connection::open_in_memory()?;
            migrate(&conn)?;
            Ok::<_, StoreError>(conn)
        })
        .await
        .map_err(|_| StoreError::Closed)??;
        let writer = Worker::spawn("sqlite-memory", vec![conn])?;
        Ok(SqliteStore {
            readers: writer.clone(),
            writer,
            path: None,
        })
    }

    /// The database file, `None` for an in-memory store.
    pub fn path(&self) -> Option<&Path> {
        self.path.as_deref()
    }
}

fn sql_params(params: Vec<Param>) -> Vec<rusqlite::types::Value> {
    params
        .into_iter()
        .map(|p| match p {
            Param::Int(i) => rusqlite::types::Value::Integer(i),
            Param::Text(t) => rusqlite::types::Value::Text(t),
        })
        .collect()
}

fn raw_event(r: &Row<'_>) -> rusqlite::Result<RawEvent> {
    Ok(RawEvent {
        id: r.get(0)?,
        node: r.get(1)?,
        point: r.get(2)?,
        ioa: r.get(3)?,
        value_kind: r.get(4)?,
        value_int: r.get(5)?,
        value_float: r.get(6)?,
        value_text: r.get(7)?,
        quality: r.get(8)?,
        source_ms: r.get(9)?,
        source_invalid: r.get(10)?,
        received_ms: r.get(11)?,
        cause: r.get(12)?,
        origin: r.get(13)?,
    })
}

fn raw_command(r: &Row<'_>) -> rusqlite::Result<RawCommand> {
    Ok(RawCommand {
        id: r.get(0)?,
        time_ms: r.get(1)?,
        actor_kind: r.get(2)?,
        actor: r.get(3)?,
        node: r.get(4)?,
        point: r.get(5)?,
        ioa: r.get(6)?,
        value_kind: r.get(7)?,
        value_int: r.get(8)?,
        value_float: r.get(9)?,
        value_text: r.get(10)?,
        phase: r.get(11)?,
        outcome: r.get(12)?,
        detail: r.get(13)?,
    })
}

fn insert_events(
    conn: &mut Connection,
    events: &[EventRecord],
) -> Result<Vec<RecordId>, StoreError> {
    let tx = conn.transaction_with_behavior(TransactionBehavior::Immediate)?;
    let mut ids = Vec::with_capacity(events.len());
    {
        let mut stmt = tx.prepare_cached(
            "INSERT INTO events (node, point, ioa, value_kind, value_int, value_float, \
             value_text, quality, source_ms, source_invalid, received_ms, event_ms, cause, origin) \
             VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11, ?12, ?13, ?14)",
        )?;
        for e in events {
            let (kind, vi, vf, vt) = e.value.to_columns();
            stmt.execute(params![
                e.node,
                e.point,
                e.ioa,
                kind,
                vi,
                vf,
                vt,
                quality_to_bits(e.quality),
                e.source_time.map(|s| to_ms(s.time)),
                e.source_time.is_some_and(|s| s.invalid),
                to_ms(e.received_time),
                to_ms(e.event_time()),
                e.cause.code(),
                e.origin,
            ])?;
            ids.push(tx.last_insert_rowid());
        }
    }
    tx.commit()?;
    Ok(ids)
}

fn insert_command(conn: &mut Connection, c: &CommandRecord) -> Result<RecordId, StoreError> {
    let (kind, vi, vf, vt) = c.value.to_columns();
    let mut stmt = conn.prepare_cached(
        "INSERT INTO commands (time_ms, actor_kind, actor, node, point, ioa, value_kind, \
         value_int, value_float, value_text, phase, outcome, detail) \
         VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11, ?12, ?13)",
    )?;
    stmt.execute(params![
        to_ms(c.time),
        c.actor.kind_code(),
        c.actor.name(),
        c.node,
        c.point,
        c.ioa,
        kind,
        vi,
        vf,
        vt,
        c.phase.code(),
        c.outcome.code(),
        c.detail,
    ])?;
    Ok(conn.last_insert_rowid())
}

impl EventStore for SqliteStore {
    fn backend(&self) -> Backend {
        Backend::Sqlite
    }

    fn append_events<'a>(&'a self, events: &'a [EventRecord]) -> StoreFuture<'a, Vec<RecordId>> {
        Box::pin(async move {
            if events.is_empty() {
                return Ok(Vec::new());
            }
            events.iter().try_for_each(check_event)?;
            let events = events.to_vec();
            self.writer.run(move |c| insert_events(c, &events)).await
        })
    }

    fn append_command<'a>(&'a self, command: &'a CommandRecord) -> StoreFuture<'a, RecordId> {
        Box::pin(async move {
            check_command(command)?;
            let command = command.clone();
            self.writer.run(move |c| insert_command(c, &command)).await
        })
    }

    fn query_events<'a>(&'a self, query: &'a EventQuery) -> StoreFuture<'a, Page<EventRecord>> {
        Box::pin(async move {
            let (sql, params) = event_sql(query, Dialect::Sqlite)?;
            let rows = self.select(sql, params, raw_event).await?;
            let items = rows
                .into_iter()
                .map(RawEvent::decode)
                .collect::<Result<Vec<_>, _>>()?;
            let basis = query.time_basis;
            Ok(into_page(items, query.limit, |e| event_cursor(e, basis)))
        })
    }

    fn query_commands<'a>(
        &'a self,
        query: &'a CommandQuery,
    ) -> StoreFuture<'a, Page<CommandRecord>> {
        Box::pin(async move {
            let (sql, params) = command_sql(query, Dialect::Sqlite)?;
            let rows = self.select(sql, params, raw_command).await?;
            let items = rows
                .into_iter()
                .map(RawCommand::decode)
                .collect::<Result<Vec<_>, _>>()?;
            Ok(into_page(items, query.limit, command_cursor))
        })
    }

    fn purge_older_than(&self, cutoff: DateTime<Utc>) -> StoreFuture<'_, u64> {
        Box::pin(async move {
            let cutoff = to_ms(cutoff);
            let mut total = 0u64;
            for (table, col) in [("events", "received_ms"), ("commands", "time_ms")] {
                let sql = format!(
                    "DELETE FROM {table} WHERE id IN \
                     (SELECT id FROM {table} WHERE {col} < ?1 LIMIT ?2)"
                );
                loop {
                    let sql = sql.clone();
                    let n = self
                        .writer
                        .run(move |c| Ok(c.execute(&sql, params![cutoff, PURGE_CHUNK])?))
                        .await?;
                    total += n as u64;
                    if (n as i64) < PURGE_CHUNK {
                        break;
                    }
                }
            }
            // Refresh the planner's statistics now and then (cheap, hourly with retention):
            // they decide between the point index and the time index for prefix filters.
            self.writer
                .run(|c| Ok(c.execute_batch("PRAGMA optimize")?))
                .await?;
            Ok(total)
        })
    }

    fn stats(&self) -> StoreFuture<'_, StoreStats> {
        Box::pin(async move {
            let (events, oldest, newest, commands) = self
                .readers
                .run(|c| {
                    let (events, oldest, newest) = c.query_row(
                        "SELECT count(*), min(received_ms), max(received_ms) FROM events",
                        [],
                        |r| {
                            Ok((
                                r.get::<_, i64>(0)?,
                                r.get::<_, Option<i64>>(1)?,
                                r.get::<_, Option<i64>>(2)?,
                            ))
                        },
                    )?;
                    let commands: i64 =
                        c.query_row("SELECT count(*) FROM commands", [], |r| r.get(0))?;
                    Ok((events, oldest, newest, commands))
                })
                .await?;
            Ok(StoreStats {
                events: u64::try_from(events).unwrap_or(0),
                commands: u64::try_from(commands).unwrap_or(0),
                oldest_event: oldest.map(from_ms).transpose()?,
                newest_event: newest.map(from_ms).transpose()?,
            })
        })
    }
}
