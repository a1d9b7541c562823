//! The PostgreSQL backend, through `tokio-postgres`.
//!
//! A small pool of connections (four by default) rather than one connection behind a
//! mutex: appends need a transaction, which holds its connection for the whole batch, and
//! an HMI paging through 60 days of history must not stall the event writer nor the other
//! way round. The pool is deadpool-postgres: a connection whose server went away is
//! recycled on the next checkout, so the store survives a server restart, and each
//! connection caches the statements prepared on it.

use chrono::Utc;
use deadpool_postgres::{Manager, ManagerConfig, Object, Pool, RecyclingMethod};
use std::str::FromStr;
use std::time::Duration;
use tokio_postgres::types::{ToSql, Type};
use tokio_postgres::{Client, NoTls, Row};

use crate::sql::row::{event_params, id_from_row, Columns, Decode, EVENT_INSERT};
use crate::sql::schema::{self, CURRENT_VERSION, VERSION_TABLE};
use crate::sql::{insert, Access, Database, Param, Statement};
use crate::{redact, Backend, EventRecord, RecordId, StoreError, StoreFuture};

/// Advisory lock taken while migrating, so two processes never migrate at once.
const MIGRATION_LOCK: i64 = 0x5354_414E_4943_4531; // "STANICE1"

/// Rows per INSERT statement within one append transaction.
const INSERT_CHUNK: usize = 10_000;

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
}

fn sql_params(params: &[Param]) -> Vec<&(dyn ToSql + Sync)> {
    params
        .iter()
        .map(|p| match p {
            Param::Int(i) => i as &(dyn ToSql + Sync),
            Param::Real(f) => f as &(dyn ToSql + Sync),
            Param::Text(t) => t as &(dyn ToSql + Sync),
            Param::Bool(b) => b as &(dyn ToSql + Sync),
        })
        .collect()
}

const NEXT_IDS: &str = "SELECT nextval(pg_get_serial_sequence('events', 'id')) \
     FROM generate_series(1, $1::int8)";

/// One column of a batch, for `unnest`.
enum Array {
    Int(Vec<Option<i64>>),
    Real(Vec<Option<f64>>),
    Text(Vec<Option<String>>),
    Bool(Vec<bool>),
}

impl Array {
    /// An empty column of the type of `p`.
    fn like(p: &Param, rows: usize) -> Array {
        match p {
            Param::Int(_) => Array::Int(Vec::with_capacity(rows)),
            Param::Real(_) => Array::Real(Vec::with_capacity(rows)),
            Param::Text(_) => Array::Text(Vec::with_capacity(rows)),
            Param::Bool(_) => Array::Bool(Vec::with_capacity(rows)),
        }
    }

    /// Adds a value (of the column's type: the rows come from one mapping).
    fn push(&mut self, p: Param) {
        match (self, p) {
            (Array::Int(a), Param::Int(v)) => a.push(v),
            (Array::Real(a), Param::Real(v)) => a.push(v),
            (Array::Text(a), Param::Text(v)) => a.push(v),
            (Array::Bool(a), Param::Bool(v)) => a.push(v),
            _ => {}
        }
    }

    fn as_sql(&self) -> &(dyn ToSql + Sync) {
        match self {
            Array::Int(a) => a,
            Array::Real(a) => a,
            Array::Text(a) => a,
            Array::Bool(a) => a,
        }
    }
}

/// Appends a batch in one transaction: ids from the identity sequence first, so they are
/// known, increasing and in the order of `events` (RETURNING makes no promise about
/// order), then one `INSERT ... SELECT FROM unnest(arrays)` per chunk.
async fn insert_many(
    conn: &mut Object,
    events: &[EventRecord],
) -> Result<Vec<RecordId>, StoreError> {
    let next_ids = conn.prepare_cached(NEXT_IDS).await?;
    let tx = conn.transaction().await?;
    let n = i64::try_from(events.len()).unwrap_or(i64::MAX);
    let mut ids: Vec<i64> = tx
        .query(&next_ids, &[&n])
        .await?
        .iter()
        .map(|r| r.try_get(0))
        .collect::<Result<_, _>>()?;
    ids.sort_unstable();
    for (chunk, chunk_ids) in events.chunks(INSERT_CHUNK).zip(ids.chunks(INSERT_CHUNK)) {
        let rows = chunk.iter().map(event_params);
        let mut columns: Vec<Array> =
            vec![Array::Int(chunk_ids.iter().map(|&i| Some(i)).collect())];
        let mut sql = None;
        for row in rows {
            if sql.is_none() {
                columns.extend(row.iter().map(|p| Array::like(p, chunk.len())));
                let arrays: Vec<String> = std::iter::once(&Param::Int(None))
                    .chain(&row)
                    .enumerate()
                    .map(|(i, p)| p.array_placeholder(i + 1))
                    .collect();
                sql = Some(format!(
                    "INSERT INTO events (id, {EVENT_INSERT}) SELECT * FROM unnest({})",
                    arrays.join(", ")
                ));
            }
            for (column, value) in columns.iter_mut().skip(1).zip(row) {
                column.push(value);
            }
        }
        let Some(sql) = sql else { continue };
        let stmt = tx.prepare_cached(&sql).await?;
        let params: Vec<&(dyn ToSql + Sync)> = columns.iter().map(Array::as_sql).collect();
        tx.execute(&stmt, &params).await?;
    }
    tx.commit().await?;
    Ok(ids)
}

impl Database for PostgresStore {
    const BACKEND: Backend = Backend::Postgres;

    fn rows<T: Send + 'static>(&self, run: Statement, each: Decode<T>) -> StoreFuture<'_, Vec<T>> {
        Box::pin(async move {
            let connection = checkout(&self.pool).await?;
            let params = sql_params(&run.params);
            // Writes are few statements, prepared once per connection; queries vary.
            let rows = match run.access {
                Access::Write => {
                    let stmt = connection.prepare_cached(&run.sql).await?;
                    connection.query(&stmt, &params).await?
                }
                Access::Read => connection.query(&run.sql, &params).await?,
            };
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
            match events {
                [one] => {
                    let run = insert(Backend::Postgres, "events", EVENT_INSERT, event_params(one));
                    self.rows(run, id_from_row).await
                }
                _ => insert_many(&mut checkout(&self.pool).await?, events).await,
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
