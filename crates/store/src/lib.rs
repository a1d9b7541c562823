//! The Stanice event store: the record of every value change and command, and the
//! backends that keep them (SQLite, PostgreSQL).
//!
//! It is its own crate so that a controlling station such as the HMI, or a tool, can
//! record events without linking the soft PLC, its compiler and Cranelift. It stores the
//! point model's values (the `points` crate) and knows nothing of any protocol.
//!
//! # What it owns
//!
//! | module        | what it does                                                         |
//! |---------------|----------------------------------------------------------------------|
//! | `model`       | the records: [`EventRecord`], [`CommandRecord`] and their codes (values, quality and causes are the point model's) |
//! | `query`       | filters, ordering and keyset pages: [`EventQuery`], [`CommandQuery`], [`Page`]; offset pages with a total: [`CountedPage`] |
//! | `lift`        | the lift fault archive: [`LiftFaultArchive`] (a trait of its own), [`LiftFaultRecord`], [`LiftFaultQuery`], [`LiftFaultOrder`] |
//! | `trend`       | trends downsampled in the database: [`TrendQuery`], [`TrendBucket`] (min, max, mean per slice of the range) |
//! | `notification` | the record of e-mails and webhook calls sent or suppressed: [`NotificationLog`] (a trait of its own), [`NotificationRecord`], [`NotificationQuery`] |
//! | [`url`]       | store addresses: [`url::StoreUrl`] (`sqlite:PATH`, `sqlite::memory:`, `postgres://...`) |
//! | `history`     | the event history in blocks: events packed many to a row (`history::codec`), an append's blocks, the writer's passes into per-point segments and trend rollups, the event list, trends and retention over them; why: its module doc |
//! | `sql`         | what both backends share: the migrations, the queries' SQL, purge, stats, row mapping, and the `EventStore` behaviour itself |
//! | `sqlite`, `postgres` | the backends: how they reach their database, how an append's blocks go in (SQLite: prepared inserts on the writer thread; PostgreSQL: binary COPY), snapshots for trends, and retention (`postgres::partitions`: day partitions) |
//! | `recorder`    | [`Recorder`]: the bounded channel and batching writer in front of a store; gives every event an idempotent key ([`EventKey`]) |
//! | `retention`   | [`spawn_retention`]: the periodic purge of old history |
//!
//! The backends, the recorder and retention are the feature `database` (on by default);
//! without it the crate is the record and query types and store addresses, which is
//! what the project loader needs.
//!
//! # Data flow
//!
//! ```text
//!  value in (PLC, I/O, link) --> PointDb::update --> PointChange (report by exception)
//!  (the points crate)                                    | the point's StorageRule (deadband,
//!                                                        | rate limit: points::StorageFilter)
//!                                                        | EventRecord::of_change
//!  command audit (CommandRecord) -----------------+      v
//!                                                 +--> Recorder: bounded channel
//!                                                      (full: events dropped and counted,
//!                                                       commands wait for room)
//!                                                        | write task: an EventKey for each
//!                                                        | event, one transaction per burst
//!                                                        | (history: blocks, passes)
//!                                                        v
//!                      EventStore (SqliteStore | PostgresStore) --> query_events / query_commands
//!                                                        ^              (HMI event list, CLI)
//!                      spawn_retention: prepare_partitions (7 days ahead) and
//!                      purge_older_than every interval (events, commands,
//!                      notifications; never the lift fault archive)
//!
//!  lift monitor --append_lift_faults--> EventStore --query_lift_faults--> HMI fault archive
//!  notifier ----append_notification---> EventStore --query_notifications--> HMI
//! ```
//!
//! Every value change of every point ([`EventRecord`]) and every command with who issued it
//! and what became of it ([`CommandRecord`]) goes into an [`EventStore`]. The railway
//! station's regulator requires at least 60 days of events and a command audit with user
//! and time; the lift's fault archive and the HMI's event list read the same store.
//!
//! Two backends implement the trait with the same schema and the same behaviour, checked by
//! one shared test suite:
//!
//! - **SQLite** (`sqlite:PATH`, `sqlite::memory:`), embedded, the default. WAL mode; one
//!   writer connection on a dedicated thread and reader connections on their own threads,
//!   so async callers never block the runtime and queries never wait behind a batch.
//! - **PostgreSQL** (`postgres://...`), the production backend, through `tokio-postgres`
//!   with a small pool of connections.
//!
//! Open one with [`open_store`]; keep history bounded with [`spawn_retention`]; feed it
//! through a [`Recorder`] (batched, bounded, commands awaitable until committed).
//!
//! # Schema
//!
//! Tables `commands` (migration 1), `lift_faults` and `notifications` (migration 2) and
//! the event history (migration 6, below), versioned by `schema_version`; the migrations
//! are one list for both backends (SQL files under `migrations/`, column types filled in
//! per backend; some versions have a text of their own per backend), applied at open, so
//! a database of an older version is brought up to date when a newer program opens it.
//! Times are milliseconds since the Unix epoch (UTC) in 64-bit integers; values are split
//! into `value_kind` plus `value_int`/`value_float`/`value_text` in the command audit;
//! enums are stored as the stable codes of [`EventCause::code`], [`CommandOutcome::code`]
//! and [`CommandPhase::code`].
//!
//! Events are kept in blocks (schema version 6; the `history` module says why and how):
//! `event_blocks` holds an append's events of one minute packed into one row, with the
//! time spans, node, causes and IV count a query filters by; `event_segments` the same
//! events again per point and hour, packed by the writer's passes; `trend_rollups`
//! (version 4) per point with numeric values and per minute ([`ROLLUP_SPAN_MS`]) the first
//! and last event time and value, the minimum, maximum, sum and count of the values and
//! whether any was invalid, folded by the same passes; `event_keys` the [`EventKey`]s as
//! runs of sequences (appending an event whose key is stored already stores nothing and
//! answers the stored event's id, so a batch written again after a crash between its
//! commit and its acknowledgement is stored once); `event_names` the names as numbers.
//! An event's time ([`EventRecord::event_time`]) is what queries order by. Opening a
//! store of version 5 or before moves its rows of `events` into blocks, ids kept, and
//! folds the rollups again from them.
//!
//! On PostgreSQL the history and `commands` are RANGE-partitioned by UTC day (a table
//! `event_blocks_YYYYMMDD` per day, with its `event_segments_` and `trend_rollups_` days),
//! made at open for today and [`DAYS_AHEAD`] days ahead, again with every retention pass,
//! and for any day an append meets; a time years off (a source clock gone wild) lands in
//! the DEFAULT partition until its day is made. Each closed day's rollups are CLUSTERed
//! on (point, minute) once ([`EventStore::compact_closed_days`], with every retention
//! pass). Ids come from `event_counter`, a range per writer at a time, and the sequence
//! `command_ids`.
//!
//! A lift fault's board time has no zone: `lift_faults.board_ms` holds its wall-clock
//! reading as if it were UTC (NULL when the board sent an impossible date), and
//! `lift_faults.filed_ms` the time it is filtered and sorted by
//! ([`LiftFaultRecord::filed_time`]).
//!
//! # Retention
//!
//! [`spawn_retention`] deletes events (by event time), command records and notification
//! records older than its cutoff. On PostgreSQL events and command records go by whole
//! days: a day's partition is dropped (not deleted row by row) once all of it is older
//! than the cutoff, so up to a day more than the retention stays; SQLite deletes whole
//! blocks and segments and writes the few holding the cutoff again without the old
//! events, and deletes command records in chunks. (The notification record is an audit like the command audit, and grows
//! with every suppressed repeat of a flapping lift's fault.) The lift fault archive is never
//! purged: it is kept for years for the service figures (faults per year, MTBF), and it
//! grows by a board's fault stack, a few records a day at worst.
//!
//! # Example
//!
//! ```
//! # async fn demo() -> Result<(), store::StoreError> {
//! use store::{open_store, EventQuery, EventRecord, PointValue};
//! let store = open_store("sqlite::memory:").await?;
//! let now = chrono::Utc::now();
//! store
//!     .append_events(&[EventRecord::new("RH2", "RH2_V1_FA1_Zapnut", PointValue::Bool(true), now)])
//!     .await?;
//! let page = store.query_events(&EventQuery::default().with_point_prefix("RH2_")).await?;
//! assert_eq!(page.items.len(), 1);
//! # Ok(()) }
//! ```
#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]
#![cfg_attr(not(test), deny(clippy::indexing_slicing))]

mod error;
mod history;
mod lift;
mod model;
mod notification;
#[cfg(feature = "database")]
mod postgres;
mod query;
#[cfg(feature = "database")]
mod recorder;
#[cfg(feature = "database")]
mod retention;
#[cfg(feature = "database")]
mod sql;
#[cfg(feature = "database")]
mod sqlite;
mod trend;
pub mod url;

use chrono::{DateTime, Utc};
use std::future::Future;
use std::pin::Pin;

pub use error::StoreError;
pub use lift::{LiftFaultOrder, LiftFaultQuery, LiftFaultRecord};
pub use model::{
    quality_from_bits, quality_to_bits, value_kind_code, Actor, CommandOutcome, CommandPhase,
    CommandRecord, EventCause, EventKey, EventRecord, PointValue, Quality, RecordId, SourceTime,
};
pub use notification::{NotificationOutcome, NotificationQuery, NotificationRecord};
#[cfg(feature = "database")]
pub use postgres::partitions::{
    CLOSED_DAY_GRACE_MS, DAYS_AHEAD, ON_DEMAND_FUTURE_DAYS, ON_DEMAND_PAST_DAYS,
};
#[cfg(feature = "database")]
pub use postgres::{PostgresConfig, PostgresStore};
pub use query::{
    CommandQuery, CountedPage, Cursor, EventQuery, Order, Page, PointFilter, TimeBasis,
    DEFAULT_PAGE_SIZE, MAX_PAGE_SIZE,
};
#[cfg(feature = "database")]
pub use recorder::{AfterStored, Recorder, CHANNEL_CAPACITY, FORWARD_DEADLINE};
#[cfg(feature = "database")]
pub use retention::{spawn_retention, Retention, RetentionHandle};
#[cfg(feature = "database")]
pub use sqlite::SqliteStore;
pub use trend::{TrendBucket, TrendMode, TrendQuery, MAX_TREND_BUCKETS, ROLLUP_SPAN_MS};

/// Unpacks a block of the event history and answers how many events it held: the entry
/// of the block format's fuzz target (the format itself is internal).
#[doc(hidden)]
pub fn decode_event_block(bytes: &[u8]) -> Result<usize, StoreError> {
    history::codec::decode(bytes).map(|events| events.len())
}

/// A boxed future, so that [`EventStore`] can be used as `dyn EventStore`.
pub type StoreFuture<'a, T> = Pin<Box<dyn Future<Output = Result<T, StoreError>> + Send + 'a>>;

/// Row counts and the time span of what the store holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct StoreStats {
    /// Number of stored events.
    pub events: u64,
    /// Number of stored command records.
    pub commands: u64,
    /// Received time of the oldest stored event.
    pub oldest_event: Option<DateTime<Utc>>,
    /// Received time of the newest stored event.
    pub newest_event: Option<DateTime<Utc>>,
}

/// Which database a store runs on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Backend {
    /// Embedded SQLite.
    Sqlite,
    /// PostgreSQL server.
    Postgres,
}

/// The event and command-audit store. Implementations are cheap to share (`Arc<dyn
/// EventStore>`) and safe to call from many tasks at once.
///
/// The domain archives kept in the same database are traits of their own
/// ([`LiftFaultArchive`], [`NotificationLog`]), each one module: a new domain is a new
/// trait and its implementation, named here only as a supertrait, so that whoever holds
/// the store reaches them (`Arc<dyn EventStore>` coerces to `Arc<dyn LiftFaultArchive>`).
pub trait EventStore: LiftFaultArchive + NotificationLog + Send + Sync {
    /// The database behind this store.
    fn backend(&self) -> Backend;

    /// Appends a batch of events in one transaction (all or nothing) and returns the ids the
    /// store assigned, in the order of `events`. Ids grow with insertion order. Times keep
    /// millisecond precision. An event whose [`EventKey`] the store holds already is not
    /// stored again: its id is the stored event's.
    fn append_events<'a>(&'a self, events: &'a [EventRecord]) -> StoreFuture<'a, Vec<RecordId>>;

    /// Appends one command record and returns its id.
    fn append_command<'a>(&'a self, command: &'a CommandRecord) -> StoreFuture<'a, RecordId>;

    /// One page of events matching `query`.
    fn query_events<'a>(&'a self, query: &'a EventQuery) -> StoreFuture<'a, Page<EventRecord>>;

    /// One page of command records matching `query`.
    fn query_commands<'a>(
        &'a self,
        query: &'a CommandQuery,
    ) -> StoreFuture<'a, Page<CommandRecord>>;

    /// Deletes events whose event time ([`EventRecord::event_time`]) is before `cutoff`,
    /// and command and notification records older than `cutoff`; returns how many rows
    /// went. PostgreSQL drops whole days of events and command records (day partitions):
    /// the day holding the cutoff stays whole. The lift fault archive is never
    /// purged: it is kept for years (faults per year, MTBF).
    fn purge_older_than(&self, cutoff: DateTime<Utc>) -> StoreFuture<'_, u64>;

    /// Row counts and time span.
    fn stats(&self) -> StoreFuture<'_, StoreStats>;

    /// Makes the storage of the days from `now` on ready: on PostgreSQL the day partitions
    /// of today and [`DAYS_AHEAD`] days ahead (the store does it at open, and the retention
    /// task with each pass); nothing to do on SQLite.
    fn prepare_partitions(&self, now: DateTime<Utc>) -> StoreFuture<'_, ()> {
        let _ = now;
        Box::pin(async { Ok(()) })
    }

    /// Rewrites the history that no longer changes in the order queries read it; returns
    /// how many days it rewrote. On PostgreSQL each closed day's trend rollups (a day
    /// partition, [`CLOSED_DAY_GRACE_MS`] after its end) are CLUSTERed on (point, minute)
    /// once: a 60-day trend then reads a point's minutes from a few pages per day instead
    /// of one page per minute. Only that day's rollups are locked while it is rewritten.
    /// The retention task calls it with each pass; nothing to do on SQLite (its rollups
    /// are kept in key order).
    fn compact_closed_days(&self, now: DateTime<Utc>) -> StoreFuture<'_, u64> {
        let _ = now;
        Box::pin(async { Ok(0) })
    }

    /// A point's values over a time range, downsampled in the database: per slice of
    /// the range its minimum, maximum and mean (see [`TrendQuery`]), oldest first. The
    /// default answers [`StoreError::InvalidQuery`]: a store that cannot aggregate.
    fn query_trend<'a>(&'a self, query: &'a TrendQuery) -> StoreFuture<'a, Vec<TrendBucket>> {
        let _ = query;
        Box::pin(async {
            Err(StoreError::InvalidQuery(
                "this store cannot downsample a trend".to_owned(),
            ))
        })
    }

    /// Closes the store at a shutdown, after the last write: SQLite checkpoints its
    /// write-ahead log into the database file (no `-wal`/`-shm` files left behind),
    /// PostgreSQL returns its connections. Calls after it fail with
    /// [`StoreError::Closed`].
    fn close(&self) -> StoreFuture<'_, ()>;
}

/// The lift fault archive: the records of lift boards' fault stacks, kept for years
/// (faults per year, MTBF; retention never purges it).
pub trait LiftFaultArchive: Send + Sync {
    /// Appends records of lift boards' fault stacks in one transaction (all or nothing) and
    /// returns the ids the store assigned, in the order of `faults`. Ids grow with
    /// insertion order, which is the archive's order ([`LiftFaultOrder::Archived`]).
    fn append_lift_faults<'a>(
        &'a self,
        faults: &'a [LiftFaultRecord],
    ) -> StoreFuture<'a, Vec<RecordId>>;

    /// One page of the lift fault archive, sorted and filtered by `query`, with the number
    /// of records the filter matches.
    fn query_lift_faults<'a>(
        &'a self,
        query: &'a LiftFaultQuery,
    ) -> StoreFuture<'a, CountedPage<LiftFaultRecord>>;
}

/// The record of notifications sent, failed or suppressed (e-mail, webhook).
pub trait NotificationLog: Send + Sync {
    /// Appends one notification record and returns its id.
    fn append_notification<'a>(
        &'a self,
        record: &'a NotificationRecord,
    ) -> StoreFuture<'a, RecordId>;

    /// One page of notification records, newest first, with the number the filter matches.
    fn query_notifications<'a>(
        &'a self,
        query: &'a NotificationQuery,
    ) -> StoreFuture<'a, CountedPage<NotificationRecord>>;
}

/// Opens (and migrates) the store named by `url`:
///
/// - `sqlite:PATH` (also `sqlite://PATH`): a database file, created when missing;
/// - `sqlite::memory:`: a private in-memory database, gone when the store is dropped;
/// - `postgres://USER[:PASSWORD]@HOST[:PORT]/DB[?options]` or `postgresql://...`: a
///   PostgreSQL database (it must exist; the tables are created in the connection's
///   `search_path` schema).
#[cfg(feature = "database")]
pub async fn open_store(url: &str) -> Result<Box<dyn EventStore>, StoreError> {
    let url = crate::url::StoreUrl::parse(url).map_err(|error| StoreError::BadUrl {
        url: error.text,
        reason: error.reason,
    })?;
    open_store_at(&url).await
}

/// Opens (and migrates) the store at a parsed address.
#[cfg(feature = "database")]
pub async fn open_store_at(url: &crate::url::StoreUrl) -> Result<Box<dyn EventStore>, StoreError> {
    use crate::url::StoreUrl;
    Ok(match url {
        StoreUrl::SqliteMemory => Box::new(SqliteStore::open_in_memory().await?),
        StoreUrl::SqliteFile { path, cache_mib } => {
            Box::new(SqliteStore::open_with_cache(path, *cache_mib).await?)
        }
        StoreUrl::Postgres(url) => {
            Box::new(PostgresStore::connect(PostgresConfig::from_url(url)?).await?)
        }
    })
}

#[cfg(feature = "database")]
pub(crate) use crate::url::redact;
