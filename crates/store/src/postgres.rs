//! The PostgreSQL backend, through `tokio-postgres`.
//!
//! A small pool of connections (four by default) rather than one connection behind a
//! mutex: appends need a transaction, which holds its connection for the whole batch, and
//! an HMI paging through 60 days of history must not stall the event writer nor the other
//! way round. The pool is deadpool-postgres: a connection whose server went away is
//! recycled on the next checkout, so the store survives a server restart, and each
//! connection caches the statements prepared on it.

use chrono::{DateTime, Utc};
use deadpool_postgres::{Manager, ManagerConfig, Object, Pool, RecyclingMethod};
use std::str::FromStr;
use std::time::Duration;
use tokio_postgres::types::ToSql;
use tokio_postgres::{Client, NoTls, Row};

use crate::model::{
    check_command, check_event, from_ms, quality_to_bits, to_ms, CommandRecord, EventRecord,
    RawCommand, RawEvent, RecordId,
};
use crate::query::{
    command_cursor, command_sql, event_cursor, event_sql, into_page, Dialect, Param,
};
use crate::{
    redact, Backend, CommandQuery, EventQuery, EventStore, Page, StoreError, StoreFuture,
    StoreStats,
};

/// The migrations, in version order.
const MIGRATIONS: &[(i64, &str)] = &[(1, include_str!("../migrations/postgres/0001_init.sql"))];

/// Advisory lock taken while migrating, so two processes never migrate at once.
const MIGRATION_LOCK: i64 = 0x5354_414E_4943_4531; // "STANICE1"

/// Rows per INSERT statement within one append transaction.
const INSERT_CHUNK: usize = 10_000;

/// Rows one purge statement deletes, so appends interleave with a large purge.
const PURGE_CHUNK: i64 = 10_000;

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
}

impl std::fmt::Debug for PostgresStore {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PostgresStore")
            .field("url", &self.url)
            .finish()
    }
}

async fn migrate(client: &mut Client) -> Result<(), StoreError> {
    let tx = client.transaction().await?;
    tx.execute("SELECT pg_advisory_xact_lock($1)", &[&MIGRATION_LOCK])
        .await?;
    tx.batch_execute(
        "CREATE TABLE IF NOT EXISTS schema_version (
             version    BIGINT PRIMARY KEY,
             applied_ms BIGINT NOT NULL
         )",
    )
    .await?;
    let current: i64 = tx
        .query_one(
            "SELECT coalesce(max(version), 0)::int8 FROM schema_version",
            &[],
        )
        .await?
        .try_get(0)?;
    let supported = MIGRATIONS.last().map(|m| m.0).unwrap_or(0);
    if current > supported {
        return Err(StoreError::SchemaTooNew {
            found: current,
            supported,
        });
    }
    for &(version, sql) in MIGRATIONS {
        if current >= version {
            continue;
        }
        tx.batch_execute(sql)
            .await
            .map_err(|e| StoreError::Migration {
                version,
                source: Box::new(e.into()),
            })?;
        tx.execute(
            "INSERT INTO schema_version (version, applied_ms) VALUES ($1, $2)",
            &[&version, &Utc::now().timestamp_millis()],
        )
        .await?;
        tracing::info!(version, "applied PostgreSQL migration");
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
            .build()
            .map_err(|error| StoreError::Pool(error.to_string()))?;
        let mut connection = checkout(&pool).await?;
        migrate(&mut connection).await?;
        drop(connection);
        Ok(PostgresStore {
            pool,
            url: config.redacted_url,
        })
    }
}

fn raw_event(r: &Row) -> Result<RawEvent, tokio_postgres::Error> {
    Ok(RawEvent {
        id: r.try_get(0)?,
        node: r.try_get(1)?,
        point: r.try_get(2)?,
        ioa: r.try_get(3)?,
        value_kind: r.try_get(4)?,
        value_int: r.try_get(5)?,
        value_float: r.try_get(6)?,
        value_text: r.try_get(7)?,
        quality: r.try_get(8)?,
        source_ms: r.try_get(9)?,
        source_invalid: r.try_get(10)?,
        received_ms: r.try_get(11)?,
        cause: r.try_get(12)?,
        origin: r.try_get(13)?,
    })
}

fn raw_command(r: &Row) -> Result<RawCommand, tokio_postgres::Error> {
    Ok(RawCommand {
        id: r.try_get(0)?,
        time_ms: r.try_get(1)?,
        actor_kind: r.try_get(2)?,
        actor: r.try_get(3)?,
        node: r.try_get(4)?,
        point: r.try_get(5)?,
        ioa: r.try_get(6)?,
        value_kind: r.try_get(7)?,
        value_int: r.try_get(8)?,
        value_float: r.try_get(9)?,
        value_text: r.try_get(10)?,
        phase: r.try_get(11)?,
        outcome: r.try_get(12)?,
        detail: r.try_get(13)?,
    })
}

fn sql_params(params: &[Param]) -> Vec<&(dyn ToSql + Sync)> {
    params
        .iter()
        .map(|p| match p {
            Param::Int(i) => i as &(dyn ToSql + Sync),
            Param::Text(t) => t as &(dyn ToSql + Sync),
        })
        .collect()
}

const INSERT_ONE: &str = "INSERT INTO events (node, point, ioa, value_kind, value_int, \
     value_float, value_text, quality, source_ms, source_invalid, received_ms, event_ms, cause, \
     origin) VALUES ($1, $2, $3, $4, $5, $6, $7, $8, $9, $10, $11, $12, $13, $14) RETURNING id";

const NEXT_IDS: &str = "SELECT nextval(pg_get_serial_sequence('events', 'id')) \
     FROM generate_series(1, $1::int8)";

const INSERT_COMMAND: &str = "INSERT INTO commands (time_ms, actor_kind, actor, node, point, \
     ioa, value_kind, value_int, value_float, value_text, phase, outcome, detail) \
     VALUES ($1, $2, $3, $4, $5, $6, $7, $8, $9, $10, $11, $12, $13) RETURNING id";

const INSERT_MANY: &str = "INSERT INTO events (id, node, point, ioa, value_kind, value_int, \
     value_float, value_text, quality, source_ms, source_invalid, received_ms, event_ms, cause, \
     origin) SELECT * FROM unnest($1::int8[], $2::text[], $3::text[], $4::int8[], $5::int2[], \
     $6::int8[], $7::float8[], $8::text[], $9::int2[], $10::int8[], $11::bool[], $12::int8[], \
     $13::int8[], $14::int2[], $15::text[])";

/// The columns of one event, as the statements bind them.
struct EventColumns<'a> {
    ioa: Option<i64>,
    kind: i16,
    int: Option<i64>,
    float: Option<f64>,
    text: Option<&'a str>,
    quality: i16,
    source_ms: Option<i64>,
    source_invalid: bool,
    received_ms: i64,
    event_ms: i64,
    cause: i16,
}

impl<'a> EventColumns<'a> {
    fn of(e: &'a EventRecord) -> EventColumns<'a> {
        let (kind, int, float, text) = e.value.to_columns();
        EventColumns {
            ioa: e.ioa.map(i64::from),
            kind,
            int,
            float,
            text,
            quality: i16::from(quality_to_bits(e.quality)),
            source_ms: e.source_time.map(|s| to_ms(s.time)),
            source_invalid: e.source_time.is_some_and(|s| s.invalid),
            received_ms: to_ms(e.received_time),
            event_ms: to_ms(e.event_time()),
            cause: e.cause.code(),
        }
    }
}

async fn insert_one(conn: &mut Object, e: &EventRecord) -> Result<RecordId, StoreError> {
    let c = EventColumns::of(e);
    let stmt = conn.prepare_cached(INSERT_ONE).await?;
    let row = conn
        .query_one(
            &stmt,
            &[
                &e.node,
                &e.point,
                &c.ioa,
                &c.kind,
                &c.int,
                &c.float,
                &c.text,
                &c.quality,
                &c.source_ms,
                &c.source_invalid,
                &c.received_ms,
                &c.event_ms,
                &c.cause,
                &e.origin,
            ],
        )
        .await?;
    Ok(row.try_get(0)?)
}

async fn insert_many(
    conn: &mut Object,
    events: &[EventRecord],
) -> Result<Vec<RecordId>, StoreError> {
    let stmt = conn.prepare_cached(INSERT_MANY).await?;
    let next_ids = conn.prepare_cached(NEXT_IDS).await?;
    let tx = conn.transaction().await?;
    // Ids come from the identity sequence first, so they are known, increasing and in the
    // order of `events` (RETURNING makes no promise about order).
    let n = i64::try_from(events.len()).unwrap_or(i64::MAX);
    let mut ids: Vec<i64> = tx
        .query(&next_ids, &[&n])
        .await?
        .iter()
        .map(|r| r.try_get(0))
        .collect::<Result<_, _>>()?;
    ids.sort_unstable();
    for (chunk, chunk_ids) in events.chunks(INSERT_CHUNK).zip(ids.chunks(INSERT_CHUNK)) {
        let cols: Vec<EventColumns<'_>> = chunk.iter().map(EventColumns::of).collect();
        let node: Vec<&str> = chunk.iter().map(|e| e.node.as_str()).collect();
        let point: Vec<&str> = chunk.iter().map(|e| e.point.as_str()).collect();
        let origin: Vec<&str> = chunk.iter().map(|e| e.origin.as_str()).collect();
        let ioa: Vec<Option<i64>> = cols.iter().map(|c| c.ioa).collect();
        let kind: Vec<i16> = cols.iter().map(|c| c.kind).collect();
        let int: Vec<Option<i64>> = cols.iter().map(|c| c.int).collect();
        let float: Vec<Option<f64>> = cols.iter().map(|c| c.float).collect();
        let text: Vec<Option<&str>> = cols.iter().map(|c| c.text).collect();
        let quality: Vec<i16> = cols.iter().map(|c| c.quality).collect();
        let source_ms: Vec<Option<i64>> = cols.iter().map(|c| c.source_ms).collect();
        let source_invalid: Vec<bool> = cols.iter().map(|c| c.source_invalid).collect();
        let received_ms: Vec<i64> = cols.iter().map(|c| c.received_ms).collect();
        let event_ms: Vec<i64> = cols.iter().map(|c| c.event_ms).collect();
        let cause: Vec<i16> = cols.iter().map(|c| c.cause).collect();
        let chunk_ids = chunk_ids.to_vec();
        tx.execute(
            &stmt,
            &[
                &chunk_ids,
                &node,
                &point,
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
                &origin,
            ],
        )
        .await?;
    }
    tx.commit().await?;
    Ok(ids)
}

async fn insert_command(conn: &mut Object, c: &CommandRecord) -> Result<RecordId, StoreError> {
    let (kind, int, float, text) = c.value.to_columns();
    let stmt = conn.prepare_cached(INSERT_COMMAND).await?;
    let row = conn
        .query_one(
            &stmt,
            &[
                &to_ms(c.time),
                &c.actor.kind_code(),
                &c.actor.name(),
                &c.node,
                &c.point,
                &c.ioa.map(i64::from),
                &kind,
                &int,
                &float,
                &text,
                &c.phase.code(),
                &c.outcome.code(),
                &c.detail,
            ],
        )
        .await?;
    Ok(row.try_get(0)?)
}

impl PostgresStore {
    async fn query_rows(&self, sql: &str, params: &[Param]) -> Result<Vec<Row>, StoreError> {
        let connection = checkout(&self.pool).await?;
        Ok(connection.query(sql, &sql_params(params)).await?)
    }
}

impl EventStore for PostgresStore {
    fn backend(&self) -> Backend {
        Backend::Postgres
    }

    fn append_events<'a>(&'a self, events: &'a [EventRecord]) -> StoreFuture<'a, Vec<RecordId>> {
        Box::pin(async move {
            if events.is_empty() {
                return Ok(Vec::new());
            }
            events.iter().try_for_each(check_event)?;
            let mut connection = checkout(&self.pool).await?;
            match events {
                [one] => insert_one(&mut connection, one).await.map(|id| vec![id]),
                _ => insert_many(&mut connection, events).await,
            }
        })
    }

    fn append_command<'a>(&'a self, command: &'a CommandRecord) -> StoreFuture<'a, RecordId> {
        Box::pin(async move {
            check_command(command)?;
            let mut connection = checkout(&self.pool).await?;
            insert_command(&mut connection, command).await
        })
    }

    fn query_events<'a>(&'a self, query: &'a EventQuery) -> StoreFuture<'a, Page<EventRecord>> {
        Box::pin(async move {
            let (sql, params) = event_sql(query, Dialect::Postgres)?;
            let rows = self.query_rows(&sql, &params).await?;
            let items = rows
                .iter()
                .map(|r| raw_event(r).map_err(StoreError::from)?.decode())
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
            let (sql, params) = command_sql(query, Dialect::Postgres)?;
            let rows = self.query_rows(&sql, &params).await?;
            let items = rows
                .iter()
                .map(|r| raw_command(r).map_err(StoreError::from)?.decode())
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
                     (SELECT id FROM {table} WHERE {col} < $1::int8 LIMIT $2::int8)"
                );
                loop {
                    let n = checkout(&self.pool)
                        .await?
                        .execute(&sql, &[&cutoff, &PURGE_CHUNK])
                        .await?;
                    total += n;
                    if n < PURGE_CHUNK.unsigned_abs() {
                        break;
                    }
                }
            }
            // Refresh the planner's statistics with each (hourly) retention pass, as the
            // SQLite backend does, rather than waiting for autovacuum after a bulk load.
            checkout(&self.pool)
                .await?
                .batch_execute("ANALYZE events, commands")
                .await?;
            Ok(total)
        })
    }

    fn stats(&self) -> StoreFuture<'_, StoreStats> {
        Box::pin(async move {
            let rows = self
                .query_rows(
                    "SELECT (SELECT count(*) FROM events)::int8, \
                     (SELECT min(received_ms) FROM events), \
                     (SELECT max(received_ms) FROM events), \
                     (SELECT count(*) FROM commands)::int8",
                    &[],
                )
                .await?;
            let row = rows
                .first()
                .ok_or_else(|| StoreError::Corrupt("stats returned no row".to_owned()))?;
            let events: i64 = row.try_get(0)?;
            let oldest: Option<i64> = row.try_get(1)?;
            let newest: Option<i64> = row.try_get(2)?;
            let commands: i64 = row.try_get(3)?;
            Ok(StoreStats {
                events: u64::try_from(events).unwrap_or(0),
                commands: u64::try_from(commands).unwrap_or(0),
                oldest_event: oldest.map(from_ms).transpose()?,
                newest_event: newest.map(from_ms).transpose()?,
            })
        })
    }
}
