//! The PostgreSQL backend, through `tokio-postgres`.
//!
//! A small pool of connections (four by default) rather than one connection behind a
//! mutex: appends need a transaction, which holds its connection for the whole batch, and
//! an HMI paging through 60 days of history must not stall the event writer nor the other
//! way round. The pool is deadpool-postgres: a connection whose server went away is
//! recycled on the next checkout, so the store survives a server restart, and each
//! connection caches the statements prepared on it.
//!
//! The event history's tables and `commands` are partitioned by day ([`partitions`]).
//! An append's blocks (and a pass's segments) go in by binary COPY, in one transaction
//! with the runs of its keys ([`history`]); the keys stored already are looked up before
//! (`crate::history`), so a batch written twice (a crash or a lost connection between
//! the commit and its acknowledgement, then the retry) stores every event once.

mod history;
pub(crate) mod partitions;

use chrono::DateTime;
use chrono::Utc;
use deadpool_postgres::{HookError, Manager, ManagerConfig, Object, Pool, RecyclingMethod};
use std::str::FromStr;
use std::time::Duration;
use tokio_postgres::types::{ToSql, Type};
use tokio_postgres::{Client, NoTls, Row};

use crate::history::codec::NameId;
use crate::history::write::HistoryWrite;
use crate::sql::row::{id_from_row, Columns, Decode, OwnedRow};
use crate::sql::schema::{self, CURRENT_VERSION, VERSION_TABLE};
use crate::sql::{insert, Database, Param, Statement};
use crate::{redact, Backend, RecordId, StoreError, StoreFuture};
use partitions::{History, Partitions};

/// Advisory lock taken while migrating, so two processes never migrate at once.
const MIGRATION_LOCK: i64 = 0x5354_414E_4943_4531; // "STANICE1"

/// What each connection of the pool is set up with: no JIT compilation (the event
/// list's and the trends' queries span a plan node per day partition, and compiling them
/// took seconds where running them takes milliseconds).
const SESSION: &str = "SET jit = off; SET plan_cache_mode = force_generic_plan";

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
    history: crate::history::History,
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
    /// The store segmenting its tail after every append instead of every few thousand
    /// events: slower appends, for tests that must read every event through the
    /// segments and rollups.
    #[doc(hidden)]
    pub fn passing_after_every_append(mut self) -> PostgresStore {
        self.history.pass_every_append = true;
        self
    }

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
        let store = PostgresStore {
            pool,
            url: config.redacted_url,
            partitions,
            history: crate::history::History::default(),
        };
        history::move_rows_into_blocks(&store).await?;
        Ok(store)
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

    fn history(&self) -> &crate::history::History {
        &self.history
    }

    fn name_ids(&self, names: Vec<String>) -> StoreFuture<'_, Vec<(NameId, String)>> {
        Box::pin(async move {
            let connection = checkout(&self.pool).await?;
            connection
                .execute(
                    "INSERT INTO event_names (name) SELECT unnest($1::text[]) \
                     ON CONFLICT (name) DO NOTHING",
                    &[&names],
                )
                .await?;
            connection
                .query(
                    "SELECT id, name FROM event_names WHERE name = ANY($1::text[])",
                    &[&names],
                )
                .await?
                .iter()
                .map(|r| {
                    let id: i64 = r.try_get(0)?;
                    let id = NameId::try_from(id)
                        .map_err(|_| StoreError::Corrupt(format!("name number {id}")))?;
                    Ok((id, r.try_get(1)?))
                })
                .collect()
        })
    }

    fn reserve_ids(&self, count: usize) -> StoreFuture<'_, Option<i64>> {
        Box::pin(async move {
            let connection = checkout(&self.pool).await?;
            let n = i64::try_from(count).unwrap_or(i64::MAX);
            let first: i64 = connection
                .query_one(
                    "UPDATE event_counter SET next_id = next_id + $1::int8 \
                     RETURNING next_id - $1::int8",
                    &[&n],
                )
                .await?
                .try_get(0)?;
            Ok(Some(first))
        })
    }

    fn write_history(&self, write: HistoryWrite) -> StoreFuture<'_, ()> {
        Box::pin(async move {
            let mut connection = checkout(&self.pool).await?;
            self.make_days(
                &connection,
                History::Events,
                write.blocks.iter().map(|b| b.first_ms),
            )
            .await?;
            let insert = connection.prepare_cached(history::INSERT_BLOCKS).await?;
            if write.pass.is_none() {
                return history::write_blocks(&**connection, &insert, &write).await;
            }
            let tx = connection.transaction().await?;
            history::write_blocks(&*tx, &insert, &write).await?;
            history::write_pass(&tx, &write).await?;
            tx.commit().await?;
            Ok(())
        })
    }

    fn snapshot(&self, statements: Vec<Statement>) -> StoreFuture<'_, Vec<Vec<OwnedRow>>> {
        Box::pin(async move {
            let mut connection = checkout(&self.pool).await?;
            history::snapshot(&mut connection, &statements).await
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
            // The writer's tail may lose blocks: read again at the next append.
            let mut writer = self.history.writer.lock().await;
            *writer = None;
            let connection = checkout(&self.pool).await?;
            let mut gone = 0;
            for history in History::ALL {
                gone += self
                    .partitions
                    .drop_before(&connection, history, cutoff_ms)
                    .await?;
            }
            // The days' segments go with their blocks (not counted: the same events).
            self.partitions
                .drop_before(&connection, History::Segments, cutoff_ms)
                .await?;
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
                .batch_execute(
                    "ANALYZE event_blocks, event_segments, trend_rollups, commands, \
                     lift_faults, notifications",
                )
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
