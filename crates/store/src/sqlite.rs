//! The SQLite backend: embedded, WAL mode, connections on their own threads.
//!
//! One writer connection lives on a dedicated thread and takes jobs (closures) from a
//! queue; two reader connections share another queue, so a long query never holds up an
//! append and no async task ever blocks on SQLite. A `sqlite::memory:` database is private
//! to its connection, so there the writer serves the reads too.

use chrono::Utc;
use rusqlite::types::{ToSqlOutput, Value, ValueRef};
use rusqlite::{params_from_iter, Connection, OpenFlags, Row, ToSql, TransactionBehavior};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::sync::{Arc, Mutex};
use std::time::Duration;
use tokio::sync::oneshot;

use crate::history::codec::NameId;
use crate::history::write::{self, EventNames, HistoryWrite};
use crate::history::History;
use crate::sql::row::{event_from_row, Cell, Columns, Decode, OwnedRow, EVENT_COLUMNS};
use crate::sql::schema::{self, CURRENT_VERSION, VERSION_TABLE};
use crate::sql::{delete_older, insert_sql, Access, Database, Param, Statement};
use crate::{Backend, RecordId, StoreError, StoreFuture};

/// How long a connection waits for a lock held by another process before failing.
const BUSY_TIMEOUT: Duration = Duration::from_secs(5);

/// Reader connections of a file database.
const READERS: usize = 2;

/// The writer's page cache by default, in KiB.
const WRITER_CACHE_KIB: i64 = 65_536;
/// A reader's page cache by default (SQLite's own default), in KiB.
const READER_CACHE_KIB: i64 = 2_048;
/// Log pages (4 KiB) between automatic checkpoints.
const WAL_CHECKPOINT_PAGES: i64 = 16_384;

type Job = Box<dyn FnOnce(&mut Connection) + Send>;

/// What a connection's thread takes from its queue.
enum Message {
    /// Run a job on the connection.
    Run(Job),
    /// Close the connection and end the thread, then say so.
    Close(oneshot::Sender<()>),
}

/// Threads that each own a connection and run jobs from one shared queue.
#[derive(Clone)]
struct Worker {
    queue: mpsc::Sender<Message>,
    threads: usize,
}

impl Worker {
    fn spawn(name: &str, connections: Vec<Connection>) -> Result<Worker, StoreError> {
        let (queue, rx) = mpsc::channel::<Message>();
        let rx = Arc::new(Mutex::new(rx));
        let threads = connections.len();
        for (i, mut conn) in connections.into_iter().enumerate() {
            let rx = Arc::clone(&rx);
            std::thread::Builder::new()
                .name(format!("{name}-{i}"))
                .spawn(move || loop {
                    // The lock is held only while waiting for the next job.
                    let message = match rx.lock() {
                        Ok(rx) => rx.recv(),
                        Err(_) => break,
                    };
                    match message {
                        Ok(Message::Run(job)) => job(&mut conn),
                        Ok(Message::Close(done)) => {
                            // The connection closes before the answer: the last one to
                            // close checkpoints the write-ahead log and removes it.
                            drop(conn);
                            let _ = done.send(());
                            break;
                        }
                        Err(_) => break, // the store was dropped
                    }
                })
                .map_err(StoreError::Thread)?;
        }
        Ok(Worker { queue, threads })
    }

    async fn run<T, F>(&self, f: F) -> Result<T, StoreError>
    where
        T: Send + 'static,
        F: FnOnce(&mut Connection) -> Result<T, StoreError> + Send + 'static,
    {
        let (tx, rx) = oneshot::channel();
        self.queue
            .send(Message::Run(Box::new(move |conn| {
                let _ = tx.send(f(conn));
            })))
            .map_err(|_| StoreError::Closed)?;
        rx.await.map_err(|_| StoreError::Closed)?
    }

    /// Closes every connection once the jobs queued before have run; a thread that took a
    /// close takes nothing more, so each thread takes one.
    async fn close(&self) {
        let mut waits = Vec::with_capacity(self.threads);
        for _ in 0..self.threads {
            let (done, wait) = oneshot::channel();
            if self.queue.send(Message::Close(done)).is_ok() {
                waits.push(wait);
            }
        }
        for wait in waits {
            let _ = wait.await;
        }
    }
}

/// The SQLite event store. Open it with [`SqliteStore::open`] or through
/// [`crate::open_store`].
pub struct SqliteStore {
    writer: Worker,
    readers: Worker,
    path: Option<PathBuf>,
    history: History,
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

/// The page caches of the writer and of each reader, in KiB: the defaults, or `cache_mib`
/// shared out (each reader a sixteenth of it, at most its default; the writer the rest).
fn cache_kib(cache_mib: Option<u32>) -> (i64, i64) {
    match cache_mib {
        None => (WRITER_CACHE_KIB, READER_CACHE_KIB),
        Some(mib) => {
            let total = i64::from(mib) * 1024;
            let reader = (total / 16).min(READER_CACHE_KIB);
            let readers = i64::try_from(READERS).unwrap_or(i64::MAX);
            (total - readers * reader, reader)
        }
    }
}

fn open_writer(path: &Path, cache_kib: i64) -> Result<Connection, StoreError> {
    let mut conn = Connection::open(path)?;
    configure(&conn)?;
    // WAL: readers never block the writer nor the writer the readers. NORMAL sync in WAL
    // mode keeps the database consistent on power loss and loses at most the last
    // transactions since the previous checkpoint sync; a process crash loses nothing.
    let mode: String = conn.query_row("PRAGMA journal_mode = WAL", [], |r| r.get(0))?;
    if !mode.eq_ignore_ascii_case("wal") {
        tracing::warn!(%mode, "SQLite refused WAL mode");
    }
    conn.pragma_update(None, "synchronous", "NORMAL")?;
    // A 64 MiB page cache by default (SQLite's is 2 MiB): an append touches six indexes
    // (time, received time, point, node, invalid, key) whose pages of the recent past
    // then stay in memory instead of being read back for every batch. (A negative
    // `cache_size` is KiB.)
    conn.pragma_update(None, "cache_size", -cache_kib)?;
    // Checkpoint every 64 MiB of log instead of SQLite's 4 MiB: an append dirties index
    // pages all over the point index, and each checkpoint writes them into the file and
    // syncs it; fewer, larger checkpoints write a page once for many batches (measured on
    // the historian bench: 1.5x the events per second). The log file stays below ~64 MiB.
    conn.pragma_update(None, "wal_autocheckpoint", WAL_CHECKPOINT_PAGES)?;
    migrate(&conn)?;
    move_rows_into_blocks(&mut conn)?;
    // Analyses what needs it at open (SQLite's advice for long-lived connections), with
    // a bounded sample so a large database still opens quickly.
    conn.execute_batch("PRAGMA analysis_limit = 1000; PRAGMA optimize = 0x10002")?;
    Ok(conn)
}

fn open_reader(path: &Path, cache_kib: i64) -> Result<Connection, StoreError> {
    let conn = Connection::open_with_flags(
        path,
        OpenFlags::SQLITE_OPEN_READ_WRITE | OpenFlags::SQLITE_OPEN_NO_MUTEX,
    )?;
    configure(&conn)?;
    conn.pragma_update(None, "query_only", "ON")?;
    conn.pragma_update(None, "cache_size", -cache_kib)?;
    Ok(conn)
}

/// Applies the migrations newer than the database's `schema_version` in one immediate
/// (write-locked) transaction.
fn migrate(conn: &Connection) -> Result<(), StoreError> {
    let tx = rusqlite::Transaction::new_unchecked(conn, TransactionBehavior::Immediate)?;
    tx.execute_batch(&schema::expand(Backend::Sqlite, VERSION_TABLE))?;
    let current: i64 = tx.query_row(CURRENT_VERSION, [], |r| r.get(0))?;
    for step in schema::pending(Backend::Sqlite, current, Utc::now().timestamp_millis())? {
        tx.execute_batch(&step.sql)
            .map_err(|e| step.failed(e.into()))?;
        tracing::info!(version = step.version, "applied SQLite migration");
    }
    tx.commit()?;
    Ok(())
}

impl SqliteStore {
    /// Opens (creating and migrating when needed) the database file at `path`.
    pub async fn open(path: impl AsRef<Path>) -> Result<SqliteStore, StoreError> {
        SqliteStore::open_with_cache(path, None).await
    }

    /// [`SqliteStore::open`] with its page caches taking at most `cache_mib` MiB
    /// together (`None`: 64 MiB for the writer, 2 MiB for each reader).
    pub async fn open_with_cache(
        path: impl AsRef<Path>,
        cache_mib: Option<u32>,
    ) -> Result<SqliteStore, StoreError> {
        let path = path.as_ref().to_path_buf();
        let p = path.clone();
        let (writer_kib, reader_kib) = cache_kib(cache_mib);
        let (writer, readers) = tokio::task::spawn_blocking(move || {
            let writer = open_writer(&p, writer_kib)?;
            let readers = (0..READERS)
                .map(|_| open_reader(&p, reader_kib))
                .collect::<Result<Vec<_>, _>>()?;
            Ok::<_, StoreError>((writer, readers))
        })
        .await
        .map_err(|_| StoreError::Closed)??;
        Ok(SqliteStore {
            writer: Worker::spawn("sqlite-writer", vec![writer])?,
            readers: Worker::spawn("sqlite-reader", readers)?,
            path: Some(path),
            history: History::default(),
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
            history: History::default(),
        })
    }

    /// The store segmenting its tail after every append instead of every few thousand
    /// events: slower appends, for tests that must read every event through the
    /// segments and rollups.
    #[doc(hidden)]
    pub fn passing_after_every_append(mut self) -> SqliteStore {
        self.history.pass_every_append = true;
        self
    }

    /// The database file, `None` for an in-memory store.
    pub fn path(&self) -> Option<&Path> {
        self.path.as_deref()
    }
}

impl ToSql for Param {
    fn to_sql(&self) -> rusqlite::Result<ToSqlOutput<'_>> {
        Ok(match self {
            Param::Int(Some(i)) => ToSqlOutput::Owned(Value::Integer(*i)),
            Param::Real(Some(f)) => ToSqlOutput::Owned(Value::Real(*f)),
            Param::Text(Some(t)) => ToSqlOutput::Borrowed(ValueRef::Text(t.as_bytes())),
            Param::Int(None) | Param::Real(None) | Param::Text(None) => {
                ToSqlOutput::Owned(Value::Null)
            }
        })
    }
}

impl Columns for Row<'_> {
    fn int(&self, i: usize) -> Result<Option<i64>, StoreError> {
        Ok(self.get(i)?)
    }
    fn real(&self, i: usize) -> Result<Option<f64>, StoreError> {
        Ok(self.get(i)?)
    }
    fn text(&self, i: usize) -> Result<Option<String>, StoreError> {
        Ok(self.get(i)?)
    }
    fn blob(&self, i: usize) -> Result<Option<Vec<u8>>, StoreError> {
        Ok(self.get(i)?)
    }
}

/// Runs `sql` on `conn` and decodes every row.
fn rows<T>(
    conn: &Connection,
    sql: &str,
    params: &[Param],
    decode: Decode<T>,
) -> Result<Vec<T>, StoreError> {
    let mut stmt = conn.prepare_cached(sql)?;
    let mut rows = stmt.query(params_from_iter(params))?;
    let mut out = Vec::new();
    while let Some(row) = rows.next()? {
        out.push(decode(row)?);
    }
    Ok(out)
}

/// Appends `rows` of `table` in one immediate transaction; ids in their order.
fn insert_rows(
    conn: &mut Connection,
    table: &str,
    columns: &str,
    rows: impl IntoIterator<Item = Vec<Param>>,
) -> Result<Vec<RecordId>, StoreError> {
    let mut rows = rows.into_iter().peekable();
    let Some(first) = rows.peek() else {
        return Ok(Vec::new());
    };
    // One statement for the batch, and the row id from the connection rather than
    // RETURNING: per row, formatting the SQL, looking it up in the statement cache and
    // stepping a RETURNING row halved the batch throughput.
    let sql = insert_sql(Backend::Sqlite, table, columns, first);
    let tx = conn.transaction_with_behavior(TransactionBehavior::Immediate)?;
    let mut ids = Vec::with_capacity(rows.size_hint().0);
    {
        let mut stmt = tx.prepare_cached(&sql)?;
        for row in rows {
            stmt.execute(params_from_iter(&row))?;
            ids.push(tx.last_insert_rowid());
        }
    }
    tx.commit()?;
    Ok(ids)
}

/// Merges a pass's minute into `trend_rollups`: against a minute stored already the
/// earlier first value (on the same millisecond the stored one: a pass holds only events
/// with higher ids than the passes before) and the later last value (on the same
/// millisecond the pass's).
const MERGE_ROLLUP: &str = "INSERT INTO trend_rollups (point, start_ms, first_ms, last_ms, \
     min_value, max_value, sum_value, samples, invalid, first_value, last_value) \
     VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11) \
     ON CONFLICT (point, start_ms) DO UPDATE SET \
         first_value = CASE WHEN excluded.first_ms < first_ms OR first_value IS NULL \
                            THEN excluded.first_value ELSE first_value END, \
         last_value  = CASE WHEN excluded.last_ms >= last_ms OR last_value IS NULL \
                            THEN excluded.last_value ELSE last_value END, \
         first_ms  = min(first_ms, excluded.first_ms), \
         last_ms   = max(last_ms, excluded.last_ms), \
         min_value = min(min_value, excluded.min_value), \
         max_value = max(max_value, excluded.max_value), \
         sum_value = sum_value + excluded.sum_value, \
         samples   = samples + excluded.samples, \
         invalid   = max(invalid, excluded.invalid)";

/// Writes one append of the history in the open transaction `tx`.
fn write_history(tx: &rusqlite::Transaction<'_>, w: &HistoryWrite) -> Result<(), StoreError> {
    {
        let mut block = tx.prepare_cached(
            "INSERT INTO event_blocks (id, events, first_ms, last_ms, first_received_ms, \
             last_received_ms, node, causes, invalid, segmented, data) \
             VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11)",
        )?;
        for b in &w.blocks {
            block.execute(rusqlite::params![
                b.id,
                b.events,
                b.first_ms,
                b.last_ms,
                b.first_received_ms,
                b.last_received_ms,
                b.node,
                b.causes,
                b.invalid,
                b.segmented,
                b.data
            ])?;
        }
        let mut key = tx.prepare_cached(
            "INSERT INTO event_keys (source, first_seq, last_seq, first_id) \
             VALUES (?1, ?2, ?3, ?4)",
        )?;
        for k in &w.keys {
            key.execute(rusqlite::params![
                k.source,
                k.first_seq,
                k.last_seq,
                k.first_id
            ])?;
        }
    }
    tx.prepare_cached("UPDATE event_counter SET next_id = max(next_id, ?1)")?
        .execute([w.next_id])?;
    let Some(pass) = &w.pass else {
        return Ok(());
    };
    let mut segment = tx.prepare_cached(
        "INSERT INTO event_segments (point, start_ms, part, first_ms, last_ms, events, data) \
         VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7)",
    )?;
    for g in &pass.segments {
        segment.execute(rusqlite::params![
            g.point, g.start_ms, g.part, g.first_ms, g.last_ms, g.events, g.data
        ])?;
    }
    let mut rollup = tx.prepare_cached(MERGE_ROLLUP)?;
    for r in &pass.rollups {
        rollup.execute(rusqlite::params![
            &*r.point,
            r.start_ms,
            r.first_ms,
            r.last_ms,
            r.min,
            r.max,
            r.sum,
            r.samples,
            r.invalid,
            r.first_value,
            r.last_value
        ])?;
    }
    // Only blocks still unsegmented: another store on the same file (a tool appending to
    // the station's database) may have segmented them as its own tail.
    let mut segmented =
        tx.prepare_cached("UPDATE event_blocks SET segmented = 1 WHERE id = ?1 AND segmented = 0")?;
    for id in &pass.blocks {
        if segmented.execute([id])? != 1 {
            return Err(StoreError::Conflict(format!(
                "block {id} of a pass was segmented by another writer"
            )));
        }
    }
    Ok(())
}

/// Rows of `events` moved per transaction by [`move_rows_into_blocks`].
const ROWS_PER_MOVE: i64 = 65_536;

/// Moves the rows of `events` (schema version 5 and before) into blocks, segments and
/// rollups, with their ids and keys, oldest id first, a chunk per transaction that also
/// deletes the chunk's rows (an interrupted move goes on at the next open); the rollups
/// are folded again from the events (the first chunk empties them), then the table goes.
fn move_rows_into_blocks(conn: &mut Connection) -> Result<(), StoreError> {
    let legacy: i64 = conn.query_row(
        "SELECT count(*) FROM sqlite_master WHERE type = 'table' AND name = 'events'",
        [],
        |r| r.get(0),
    )?;
    if legacy == 0 {
        return Ok(());
    }
    let mut names: HashMap<String, NameId> = HashMap::new();
    {
        let mut stmt = conn.prepare("SELECT id, name FROM event_names")?;
        let mut rows = stmt.query([])?;
        while let Some(row) = rows.next()? {
            let id: i64 = row.get(0)?;
            names.insert(row.get(1)?, NameId::try_from(id).unwrap_or(0));
        }
    }
    let mut moved = 0u64;
    loop {
        let tx = conn.transaction_with_behavior(TransactionBehavior::Immediate)?;
        let blocks_stored: i64 =
            tx.query_row("SELECT count(*) FROM event_blocks", [], |r| r.get(0))?;
        if blocks_stored == 0 {
            tx.execute("DELETE FROM trend_rollups", [])?;
        }
        let events = rows(
            &tx,
            &format!("SELECT {EVENT_COLUMNS} FROM events ORDER BY id LIMIT ?1"),
            &[Param::int(ROWS_PER_MOVE)],
            event_from_row,
        )?;
        if events.is_empty() {
            tx.execute_batch("DROP TABLE events")?;
            tx.commit()?;
            if moved > 0 {
                tracing::info!(events = moved, "moved the events into blocks (schema 6)");
            }
            return Ok(());
        }
        let mut number = |name: &str| -> Result<NameId, StoreError> {
            if let Some(&id) = names.get(name) {
                return Ok(id);
            }
            tx.execute("INSERT INTO event_names (name) VALUES (?1)", [name])?;
            let id = NameId::try_from(tx.last_insert_rowid())
                .map_err(|_| StoreError::Corrupt("name number beyond 32 bits".to_owned()))?;
            names.insert(name.to_owned(), id);
            Ok(id)
        };
        let mut coded = Vec::with_capacity(events.len());
        let mut last_id = 0;
        for e in &events {
            let id = e.id.unwrap_or(0);
            last_id = id;
            let names = EventNames {
                node: number(&e.node)?,
                point: number(&e.point)?,
                origin: number(&e.origin)?,
                key_source: match &e.key {
                    Some(k) => Some(number(&k.source)?),
                    None => None,
                },
            };
            let mut one = write::number(
                std::slice::from_ref(e),
                |_| EventNames { ..names },
                &HashMap::new(),
                id,
            );
            coded.append(&mut one.new);
        }
        let mut tail = write::Tail::default();
        let mut block_rows = Vec::new();
        for (row, events) in write::blocks(&coded) {
            tail.add(row.id, &events);
            block_rows.push(row);
        }
        let by_id: HashMap<NameId, Arc<str>> = names
            .iter()
            .map(|(n, &id)| (id, Arc::from(n.as_str())))
            .collect();
        let write = HistoryWrite {
            next_id: last_id + 1,
            keys: write::runs_of(&coded),
            blocks: block_rows,
            pass: write::pass(&tail, |id| by_id.get(&id).cloned()),
        };
        write_history(&tx, &write)?;
        tx.execute("DELETE FROM events WHERE id <= ?1", [last_id])?;
        tx.commit()?;
        moved += events.len() as u64;
    }
}

/// The numbers of `names`, adding the missing ones.
fn name_ids(conn: &mut Connection, names: &[String]) -> Result<Vec<(NameId, String)>, StoreError> {
    let tx = conn.transaction_with_behavior(TransactionBehavior::Immediate)?;
    let mut pairs = Vec::with_capacity(names.len());
    {
        let mut add = tx.prepare_cached("INSERT OR IGNORE INTO event_names (name) VALUES (?1)")?;
        let mut get = tx.prepare_cached("SELECT id FROM event_names WHERE name = ?1")?;
        for name in names {
            add.execute([name])?;
            let id: i64 = get.query_row([name], |r| r.get(0))?;
            let id = NameId::try_from(id)
                .map_err(|_| StoreError::Corrupt(format!("name number {id}")))?;
            pairs.push((id, name.clone()));
        }
    }
    tx.commit()?;
    Ok(pairs)
}

/// Runs `statements` in one read transaction, rows into memory.
fn snapshot(
    conn: &mut Connection,
    statements: &[Statement],
) -> Result<Vec<Vec<OwnedRow>>, StoreError> {
    let tx = conn.transaction_with_behavior(TransactionBehavior::Deferred)?;
    let mut out = Vec::with_capacity(statements.len());
    for run in statements {
        let mut stmt = tx.prepare_cached(&run.sql)?;
        let columns = stmt.column_count();
        let mut rows = stmt.query(params_from_iter(&run.params))?;
        let mut read = Vec::new();
        while let Some(row) = rows.next()? {
            let mut cells = Vec::with_capacity(columns);
            for i in 0..columns {
                cells.push(match row.get_ref(i)? {
                    ValueRef::Null => Cell::Null,
                    ValueRef::Integer(v) => Cell::Int(v),
                    ValueRef::Real(v) => Cell::Real(v),
                    ValueRef::Text(t) => Cell::Text(String::from_utf8_lossy(t).into_owned()),
                    ValueRef::Blob(b) => Cell::Blob(b.to_vec()),
                });
            }
            read.push(OwnedRow(cells));
        }
        out.push(read);
    }
    tx.commit()?;
    Ok(out)
}

impl Database for SqliteStore {
    const BACKEND: Backend = Backend::Sqlite;

    fn rows<T: Send + 'static>(&self, run: Statement, each: Decode<T>) -> StoreFuture<'_, Vec<T>> {
        let worker = match run.access {
            Access::Read => &self.readers,
            Access::Write => &self.writer,
        };
        Box::pin(worker.run(move |c| rows(c, &run.sql, &run.params, each)))
    }

    fn execute(&self, sql: String, params: Vec<Param>) -> StoreFuture<'_, u64> {
        Box::pin(self.writer.run(move |c| {
            let n = c.prepare_cached(&sql)?.execute(params_from_iter(&params))?;
            Ok(u64::try_from(n).unwrap_or(u64::MAX))
        }))
    }

    fn history(&self) -> &History {
        &self.history
    }

    fn name_ids(&self, names: Vec<String>) -> StoreFuture<'_, Vec<(NameId, String)>> {
        Box::pin(self.writer.run(move |c| name_ids(c, &names)))
    }

    /// Ids come from `event_counter` a range at a time, so that two stores on one file
    /// (the station's and a tool's) never hand out the same ids.
    fn reserve_ids(&self, count: usize) -> StoreFuture<'_, Option<i64>> {
        Box::pin(self.writer.run(move |c| {
            let n = i64::try_from(count).unwrap_or(i64::MAX);
            let tx = c.transaction_with_behavior(TransactionBehavior::Immediate)?;
            let first: i64 = tx.query_row(
                "UPDATE event_counter SET next_id = next_id + ?1 RETURNING next_id - ?1",
                [n],
                |r| r.get(0),
            )?;
            tx.commit()?;
            Ok(Some(first))
        }))
    }

    fn write_history(&self, write: HistoryWrite) -> StoreFuture<'_, ()> {
        Box::pin(self.writer.run(move |c| {
            let tx = c.transaction_with_behavior(TransactionBehavior::Immediate)?;
            write_history(&tx, &write)?;
            tx.commit()?;
            Ok(())
        }))
    }

    fn snapshot(&self, statements: Vec<Statement>) -> StoreFuture<'_, Vec<Vec<OwnedRow>>> {
        Box::pin(self.readers.run(move |c| snapshot(c, &statements)))
    }

    fn insert_rows(
        &self,
        table: &'static str,
        columns: &'static str,
        rows: Vec<Vec<Param>>,
    ) -> StoreFuture<'_, Vec<RecordId>> {
        Box::pin(
            self.writer
                .run(move |c| insert_rows(c, table, columns, rows)),
        )
    }

    fn purge_history(&self, cutoff_ms: i64) -> StoreFuture<'_, u64> {
        Box::pin(async move {
            Ok(
                crate::history::purge::purge(self, &self.history, cutoff_ms).await?
                    + delete_older(self, "commands", "time_ms", cutoff_ms).await?,
            )
        })
    }

    fn analyze(&self) -> StoreFuture<'_, ()> {
        Box::pin(self.writer.run(|c| Ok(c.execute_batch("PRAGMA optimize")?)))
    }

    fn close(&self) -> StoreFuture<'_, ()> {
        Box::pin(async move {
            // Readers first, so that the writer's connection is the database's last: its
            // close checkpoints the write-ahead log into the file and deletes the -wal and
            // -shm files (a stopped station leaves one file behind).
            if self.path.is_some() {
                self.readers.close().await;
            }
            self.writer.close().await;
            Ok(())
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_cache_setting_bounds_every_connection_together() {
        assert_eq!(cache_kib(None), (65_536, 2_048));
        // 4 MiB: each reader 256 KiB, the writer the other 3.5 MiB.
        assert_eq!(cache_kib(Some(4)), (3_584, 256));
        // 64 MiB: readers at their default.
        assert_eq!(cache_kib(Some(64)), (61_440, 2_048));
        for mib in [1, 2, 7, 1000] {
            let (writer, reader) = cache_kib(Some(mib));
            assert_eq!(writer + 2 * reader, i64::from(mib) * 1024);
            assert!(writer > 0 && reader > 0);
        }
    }
}
