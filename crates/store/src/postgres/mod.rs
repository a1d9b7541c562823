//! The PostgreSQL backend, through `tokio-postgres`.
//!
//! A small pool of connections (four by default) rather than one connection behind a
//! mutex: appends need a transaction, which holds its connection for the whole batch, and
//! an HMI paging through 60 days of history must not stall the event writer nor the other
//! way round. The pool is deadpool-postgres: a connection whose server went away is
//! recycled on the next checkout, so the store survives a server restart, and each
//! connection caches the statements prepared on it.
//!
//! `events` and `commands` are partitioned by day ([`partitions`]). Event batches go in
//! by binary COPY into a temporary staging table (one per connection, made when the pool
//! opens the connection) and from there by `INSERT ... SELECT ... ON CONFLICT DO NOTHING`
//! into `events`, in one transaction: the idempotent key ([`crate::EventKey`]) makes a
//! batch written twice (a crash or a lost connection between the commit and its
//! acknowledgement, then the retry) store every event once.

pub(crate) mod partitions;

use chrono::DateTime;
use chrono::Utc;
use deadpool_postgres::{HookError, Manager, ManagerConfig, Object, Pool, RecyclingMethod};
use std::str::FromStr;
use std::time::Duration;
use tokio_postgres::binary_copy::BinaryCopyInWriter;
use tokio_postgres::error::SqlState;
use tokio_postgres::types::{ToSql, Type};
use tokio_postgres::{Client, NoTls, Row};

use crate::model::{quality_to_bits, value_kind_code};
use crate::sql::row::{id_from_row, key_sequence, to_ms, value_columns, Columns, Decode};
use crate::sql::schema::{self, CURRENT_VERSION, VERSION_TABLE};
use crate::sql::{insert, Database, Param, Statement};
use crate::{redact, Backend, EventRecord, RecordId, StoreError, StoreFuture};
use partitions::{History, Partitions};

/// Advisory lock taken while migrating, so two processes never migrate at once.
const MIGRATION_LOCK: i64 = 0x5354_414E_4943_4531; // "STANICE1"

/// What each connection of the pool is set up with: no JIT compilation (the event
/// list's and the trends' queries span a plan node per day partition, and compiling them
/// took seconds where running them takes milliseconds), and the staging table.
const SESSION: &str = "SET jit = off; CREATE TEMP TABLE IF NOT EXISTS events_staging (
     id int8, node text, point text, ioa int8, value_kind int2, value_int int8,
     value_float float8, value_text text, quality int2, source_ms int8, source_invalid bool,
     received_ms int8, event_ms int8, cause int2, origin text, source_id text,
     source_seq int8) ON COMMIT DELETE ROWS";

/// The staging table of event batches ([`SESSION`]): a temporary table of the
/// connection (never written to the WAL), emptied at each commit. Its column types, in the
/// order the COPY writes them:
const STAGING_TYPES: [Type; 17] = [
    Type::INT8,
    Type::TEXT,
    Type::TEXT,
    Type::INT8,
    Type::INT2,
    Type::INT8,
    Type::FLOAT8,
    Type::TEXT,
    Type::INT2,
    Type::INT8,
    Type::BOOL,
    Type::INT8,
    Type::INT8,
    Type::INT2,
    Type::TEXT,
    Type::TEXT,
    Type::INT8,
];

/// How to reach the PostgreSQL server.
#[derive(Clone)]
#[non_exhaustive]
pub struct PostgresConfig {
    /// Connection parameters, parsed from the URL.
    pub connection: tokio_postgres::Config,
    /// Connections the store keeps at most (at least 1).
    pub pool_size: usize,
    redacted_url: String,
}

impl std::fmt::Debug for PostgresConfig {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PostgresConfig")
            .field("url", &self.redacted_url)
            .field("pool_size", &self.pool_size)
            .finish()
    }
}

impl PostgresConfig {
    /// Parses `postgres://USER[:PASSWORD]@HOST[:PORT]/DB[?key=value...]` (also
    /// `postgresql://`); the keys are libpq's (`sslmode` is not supported: connections are
    /// plain TCP or a Unix socket, `host=/path`). A connect timeout of 10 s applies unless the
    /// URL sets `connect_timeout`.
    pub fn from_url(url: &str) -> Result<PostgresConfig, StoreError> {
        let redacted_url = redact(url);
        let mut connection =
            tokio_postgres::Config::from_str(url).map_err(|e| StoreError::BadUrl {
                url: redacted_url.clone(),
                reason: e.to_string(),
            })?;
        if connection.get_hosts().is_empty() {
            return Err(StoreError::BadUrl {
                url: redacted_url,
                reason: "no host".to_owned(),
            });
        }
        if connection.get_dbname().is_none() {
            return Err(StoreError::BadUrl {
                url: redacted_url,
                reason: "no database name".to_owned(),
            });
        }
        if connection.get_connect_timeout().is_none() {
            connection.connect_timeout(Duration::from_secs(10));
        }
        Ok(PostgresConfig {
            connection,
            pool_size: 4,
            redacted_url,
        })
    }

    /// Keep at most this many connections (at least 1).
    pub fn with_pool_size(mut self, size: usize) -> Self {
        self.pool_size = size.max(1);
        self
    }
}

/// A connection checked out of the pool; it goes back when dropped.
async fn checkout(pool: &Pool) -> Result<Object, StoreError> {
    pool.get().await.map_err(|error| match error {
        deadpool_postgres::PoolError::Backend(error) => StoreError::Postgres(error),
        deadpool_postgres::PoolError::Closed => StoreError::Closed,
        other => StoreError::Pool(other.to_string()),
    })
}

/// The PostgreSQL event store. Open it with [`PostgresStore::connect`] or through
/// [`crate::open_store`].
pub struct PostgresStore {
    pool: Pool,
    url: String,
    partitions: Partitions,
}

impl std::fmt::Debug for PostgresStore {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PostgresStore")
            .field("url", &self.url)
            .finish()
    }
}

/// Applies the migrations newer than the database's `schema_version` in one transaction,
/// under an advisory lock so that two processes never migrate at once.
async fn migrate(client: &mut Client) -> Result<(), StoreError> {
    let tx = client.transaction().await?;
    tx.execute("SELECT pg_advisory_xact_lock($1)", &[&MIGRATION_LOCK])
        .await?;
    tx.batch_execute(&schema::expand(Backend::Postgres, VERSION_TABLE))
        .await?;
    let current: i64 = tx.query_one(CURRENT_VERSION, &[]).await?.try_get(0)?;
    for step in schema::pending(Backend::Postgres, current, Utc::now().timestamp_millis())? {
        tx.batch_execute(&step.sql)
            .await
            .map_err(|e| step.failed(e.into()))?;
        tracing::info!(version = step.version, "applied PostgreSQL migration");
    }
    tx.commit().await?;
    Ok(())
}

impl PostgresStore {
    /// Connects (one connection at once, so a wrong address or password fails here) and
    /// migrates the schema.
    pub async fn connect(config: PostgresConfig) -> Result<PostgresStore, StoreError> {
        let manager = Manager::from_config(
            config.connection,
            NoTls,
            ManagerConfig {
                // A cheap check that the connection is still open; a broken one is
                // replaced, so the store survives a server restart.
                recycling_method: RecyclingMethod::Fast,
            },
        );
        let pool = Pool::builder(manager)
            .max_size(config.pool_size.max(1))
            .post_create(deadpool_postgres::Hook::async_fn(|client, _| {
                Box::pin(async move {
                    client
                        .batch_execute(SESSION)
                        .await
                        .map_err(HookError::Backend)
                })
            }))
            .build()
            .map_err(|error| StoreError::Pool(error.to_string()))?;
        let mut connection = checkout(&pool).await?;
        migrate(&mut connection).await?;
        let partitions = Partitions::default();
        partitions.make_ahead(&connection, Utc::now()).await?;
        drop(connection);
        Ok(PostgresStore {
            pool,
            url: config.redacted_url,
            partitions,
        })
    }
}

impl Columns for Row {
    fn int(&self, i: usize) -> Result<Option<i64>, StoreError> {
        // The driver reads a column only as its own width.
        let ty = self.columns().get(i).map(|c| c.type_().clone());
        Ok(match ty {
            Some(Type::INT2) => self.try_get::<_, Option<i16>>(i)?.map(i64::from),
            Some(Type::INT4) => self.try_get::<_, Option<i32>>(i)?.map(i64::from),
            Some(Type::BOOL) => self.try_get::<_, Option<bool>>(i)?.map(i64::from),
            _ => self.try_get(i)?,
        })
    }
    fn real(&self, i: usize) -> Result<Option<f64>, StoreError> {
        Ok(self.try_get(i)?)
    }
    fn text(&self, i: usize) -> Result<Option<String>, StoreError> {
        Ok(self.try_get(i)?)
    }
    fn blob(&self, i: usize) -> Result<Option<Vec<u8>>, StoreError> {
        Ok(self.try_get(i)?)
    }
}

fn sql_params(params: &[Param]) -> Vec<&(dyn ToSql + Sync)> {
    params
        .iter()
        .map(|p| match p {
            Param::Int(i) => i as &(dyn ToSql + Sync),
            Param::Real(f) => f as &(dyn ToSql + Sync),
            Param::Text(t) => t as &(dyn ToSql + Sync),
        })
        .collect()
}

const NEXT_IDS: &str = "SELECT nextval('event_ids') FROM generate_series(1, $1::int8)";

const COPY_STAGING: &str = "COPY events_staging (id, node, point, ioa, value_kind, value_int, \
     value_float, value_text, quality, source_ms, source_invalid, received_ms, event_ms, cause, \
     origin, source_id, source_seq) FROM STDIN (FORMAT binary)";

const COPY_EVENTS: &str = "COPY events (id, node, point, ioa, value_kind, value_int, \
     value_float, value_text, quality, source_ms, source_invalid, received_ms, event_ms, cause, \
     origin, source_id, source_seq) FROM STDIN (FORMAT binary)";

const MOVE_STAGED: &str = "INSERT INTO events (id, node, point, ioa, value_kind, value_int, \
     value_float, value_text, quality, source_ms, source_invalid, received_ms, event_ms, cause, \
     origin, source_id, source_seq) SELECT * FROM events_staging ON CONFLICT DO NOTHING";

/// The staged events that were already stored (same key): their staged id and the stored.
const DUPLICATES: &str = "SELECT s.id, e.id FROM events_staging s JOIN events e \
     ON e.source_id = s.source_id AND e.source_seq = s.source_seq AND e.event_ms = s.event_ms \
     WHERE e.id <> s.id";

/// One event, in one statement (the recorder's batches are single events when the
/// station is quiet: no staging round trips for them).
const INSERT_ONE: &str = "INSERT INTO events (node, point, ioa, value_kind, value_int, \
     value_float, value_text, quality, source_ms, source_invalid, received_ms, event_ms, cause, \
     origin, source_id, source_seq) VALUES ($1::text, $2::text, $3::int8, $4::int2, $5::int8, \
     $6::float8, $7::text, $8::int2, $9::int8, $10::bool, $11::int8, $12::int8, $13::int2, \
     $14::text, $15::text, $16::int8) ON CONFLICT DO NOTHING RETURNING id";

/// The id of a stored event by its key.
const ID_OF_KEY: &str = "SELECT id FROM events \
     WHERE source_id = $1::text AND source_seq = $2::int8 AND event_ms = $3::int8";

/// Appends one event; an event whose key is stored already answers the stored id.
async fn insert_one(conn: &Object, e: &EventRecord) -> Result<RecordId, StoreError> {
    let stmt = conn.prepare_cached(INSERT_ONE).await?;
    let ioa = e.ioa.map(i64::from);
    let kind = value_kind_code(&e.value);
    let (int, float, text) = value_columns(&e.value);
    let quality = i16::from(quality_to_bits(e.quality));
    let source_ms = e.source_time.map(|s| to_ms(s.time));
    let source_invalid = e.source_time.is_some_and(|s| s.invalid);
    let received_ms = to_ms(e.received_time);
    let event_ms = to_ms(e.event_time());
    let cause = e.cause.code();
    let key_source = e.key.as_ref().map(|k| k.source.as_str());
    let key_seq = e.key.as_ref().map(|k| key_sequence(k.sequence));
    let rows = conn
        .query(
            &stmt,
            &[
                &e.node,
                &e.point,
                &ioa,
                &kind,
                &int,
                &float,
                &text,
                &quality,
                &source_ms,
                &source_invalid,
                &received_ms,
                &event_ms,
                &cause,
                &e.origin,
                &key_source,
                &key_seq,
            ],
        )
        .await?;
    let row = match rows.into_iter().next() {
        Some(row) => row,
        None => {
            let lookup = conn.prepare_cached(ID_OF_KEY).await?;
            conn.query_one(&lookup, &[&key_source, &key_seq, &event_ms])
                .await?
        }
    };
    Ok(row.try_get(0)?)
}

/// Writes `events` with their `ids` to a COPY (into `events` or the staging table: the
/// same columns in the same order, [`STAGING_TYPES`]).
async fn write_copy(
    writer: BinaryCopyInWriter,
    events: &[EventRecord],
    ids: &[i64],
) -> Result<u64, tokio_postgres::Error> {
    let mut writer = std::pin::pin!(writer);
    for (e, id) in events.iter().zip(ids) {
        let ioa = e.ioa.map(i64::from);
        let kind = value_kind_code(&e.value);
        let (int, float, text) = value_columns(&e.value);
        let quality = i16::from(quality_to_bits(e.quality));
        let source_ms = e.source_time.map(|s| to_ms(s.time));
        let source_invalid = e.source_time.is_some_and(|s| s.invalid);
        let received_ms = to_ms(e.received_time);
        let event_ms = to_ms(e.event_time());
        let cause = e.cause.code();
        let key_source = e.key.as_ref().map(|k| k.source.as_str());
        let key_seq = e.key.as_ref().map(|k| key_sequence(k.sequence));
        writer
            .as_mut()
            .write(&[
                id,
                &e.node,
                &e.point,
                &ioa,
                &kind,
                &int,
                &float,
                &text,
                &quality,
                &source_ms,
                &source_invalid,
                &received_ms,
                &event_ms,
                &cause,
                &e.origin,
                &key_source,
                &key_seq,
            ])
            .await?;
    }
    writer.as_mut().finish().await
}

/// `count` ids from the sequence, increasing (so in the order of the batch).
async fn next_ids(conn: &Object, count: usize) -> Result<Vec<i64>, StoreError> {
    let next_ids = conn.prepare_cached(NEXT_IDS).await?;
    let n = i64::try_from(count).unwrap_or(i64::MAX);
    let mut ids: Vec<i64> = conn
        .query(&next_ids, &[&n])
        .await?
        .iter()
        .map(|r| r.try_get(0))
        .collect::<Result<_, _>>()?;
    ids.sort_unstable();
    Ok(ids)
}

/// Appends a batch in one transaction, with ids from the sequence taken first (so they
/// are known, increasing and in the order of `events`). First by binary COPY straight
/// into `events`: a batch is new but for a retry after a crash, and one pass over the
/// rows is the cheapest. A key stored already makes that COPY fail as a whole (COPY has
/// no ON CONFLICT); the batch is then written again the careful way: COPY into the
/// staging table, then into `events` leaving out those whose key is stored (their id
/// answered as the stored one's).
async fn copy_events(
    conn: &mut Object,
    events: &[EventRecord],
) -> Result<Vec<RecordId>, StoreError> {
    let ids = next_ids(conn, events.len()).await?;
    let direct = conn.prepare_cached(COPY_EVENTS).await?;
    let tx = conn.transaction().await?;
    let sink = tx.copy_in(&direct).await?;
    let writer = BinaryCopyInWriter::new(sink, &STAGING_TYPES);
    match write_copy(writer, events, &ids).await {
        Ok(_) => {
            tx.commit().await?;
            return Ok(ids);
        }
        Err(error) if error.code() == Some(&SqlState::UNIQUE_VIOLATION) => {
            tracing::debug!("a batch held stored keys: written again without them");
            tx.rollback().await?;
        }
        Err(error) => return Err(error.into()),
    }
    copy_staged(conn, events, ids).await
}

/// [`copy_events`] for a batch holding events whose key is stored already.
async fn copy_staged(
    conn: &mut Object,
    events: &[EventRecord],
    mut ids: Vec<i64>,
) -> Result<Vec<RecordId>, StoreError> {
    let copy = conn.prepare_cached(COPY_STAGING).await?;
    let tx = conn.transaction().await?;
    let sink = tx.copy_in(&copy).await?;
    write_copy(BinaryCopyInWriter::new(sink, &STAGING_TYPES), events, &ids).await?;
    let stored = tx.execute(MOVE_STAGED, &[]).await?;
    if stored < u64::try_from(events.len()).unwrap_or(u64::MAX) {
        for row in tx.query(DUPLICATES, &[]).await? {
            let (staged, kept): (i64, i64) = (row.try_get(0)?, row.try_get(1)?);
            if let Some(slot) = ids.iter_mut().find(|id| **id == staged) {
                *slot = kept;
            }
        }
    }
    tx.commit().await?;
    Ok(ids)
}

impl PostgresStore {
    /// Makes the day partitions the times of `history` need (see [`partitions`]).
    async fn make_days(
        &self,
        client: &Client,
        history: History,
        times: impl IntoIterator<Item = i64>,
    ) -> Result<(), StoreError> {
        let missing = self.partitions.missing(history, times, Utc::now());
        if missing.is_empty() {
            return Ok(());
        }
        self.partitions.make(client, history, &missing).await
    }
}

impl Database for PostgresStore {
    const BACKEND: Backend = Backend::Postgres;

    fn rows<T: Send + 'static>(&self, run: Statement, each: Decode<T>) -> StoreFuture<'_, Vec<T>> {
        Box::pin(async move {
            let connection = checkout(&self.pool).await?;
            let params = sql_params(&run.params);
            // Prepared once per connection, queries too: their texts are a few shapes (the
            // values are parameters), and planning a query over every day partition cost
            // more than running it.
            let stmt = connection.prepare_cached(&run.sql).await?;
            let rows = connection.query(&stmt, &params).await?;
            rows.iter().map(|r| each(r)).collect()
        })
    }

    fn execute(&self, sql: String, params: Vec<Param>) -> StoreFuture<'_, u64> {
        Box::pin(async move {
            let connection = checkout(&self.pool).await?;
            Ok(connection.execute(&sql, &sql_params(&params)).await?)
        })
    }

    fn insert_events<'a>(&'a self, events: &'a [EventRecord]) -> StoreFuture<'a, Vec<RecordId>> {
        Box::pin(async move {
            let mut connection = checkout(&self.pool).await?;
            self.make_days(
                &connection,
                History::Events,
                events.iter().map(|e| to_ms(e.event_time())),
            )
            .await?;
            match events {
                [one] => Ok(vec![insert_one(&connection, one).await?]),
                _ => copy_events(&mut connection, events).await,
            }
        })
    }

    fn insert_rows(
        &self,
        table: &'static str,
        columns: &'static str,
        rows: Vec<Vec<Param>>,
    ) -> StoreFuture<'_, Vec<RecordId>> {
        Box::pin(async move {
            let Some(first) = rows.first() else {
                return Ok(Vec::new());
            };
            // Row by row, each returning its id, so the ids come in the rows' order: these
            // batches are small (a board's fault stack), unlike the events'.
            let sql = insert(Backend::Postgres, table, columns, first.clone()).sql;
            let mut connection = checkout(&self.pool).await?;
            let stmt = connection.prepare_cached(&sql).await?;
            let tx = connection.transaction().await?;
            let mut ids = Vec::with_capacity(rows.len());
            for row in &rows {
                let returned = tx.query_one(&stmt, &sql_params(row)).await?;
                ids.push(id_from_row(&returned)?);
            }
            tx.commit().await?;
            Ok(ids)
        })
    }

    fn before_command(&self, time_ms: i64) -> StoreFuture<'_, ()> {
        Box::pin(async move {
            let connection = checkout(&self.pool).await?;
            self.make_days(&connection, History::Commands, [time_ms])
                .await
        })
    }

    fn purge_history(&self, cutoff_ms: i64) -> StoreFuture<'_, u64> {
        Box::pin(async move {
            let connection = checkout(&self.pool).await?;
            let mut gone = 0;
            for history in History::ALL {
                gone += self
                    .partitions
                    .drop_before(&connection, history, cutoff_ms)
                    .await?;
            }
            Ok(gone)
        })
    }

    /// Whole days go, as the events' (their partitions dropped).
    fn purge_rollups(&self, cutoff_ms: i64) -> StoreFuture<'_, ()> {
        Box::pin(async move {
            let connection = checkout(&self.pool).await?;
            self.partitions
                .drop_before(&connection, History::Rollups, partitions::day_of(cutoff_ms))
                .await?;
            Ok(())
        })
    }

    fn compact_closed_days(&self, now: DateTime<Utc>) -> StoreFuture<'_, u64> {
        Box::pin(async move {
            let connection = checkout(&self.pool).await?;
            self.partitions.compact_closed_days(&connection, now).await
        })
    }

    fn prepare_partitions(&self, now: DateTime<Utc>) -> StoreFuture<'_, ()> {
        Box::pin(async move {
            let connection = checkout(&self.pool).await?;
            self.partitions.make_ahead(&connection, now).await
        })
    }

    fn analyze(&self) -> StoreFuture<'_, ()> {
        Box::pin(async move {
            let connection = checkout(&self.pool).await?;
            Ok(connection
                .batch_execute("ANALYZE events, commands, lift_faults, notifications")
                .await?)
        })
    }

    fn close(&self) -> StoreFuture<'_, ()> {
        Box::pin(async move {
            self.pool.close();
            Ok(())
        })
    }
}
