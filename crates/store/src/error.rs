//! Errors of the event store.

/// Everything that can go wrong in the event store.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum StoreError {
    /// The store URL is not one of the accepted forms.
    #[error(
        "bad store URL {url:?}: {reason} (expected sqlite:PATH, sqlite::memory:, \
         postgres://USER@HOST:PORT/DB or postgresql://...)"
    )]
    BadUrl {
        /// The URL as given, with any password replaced by `***`.
        url: String,
        /// What is wrong with it.
        reason: String,
    },
    /// The query cannot be run (page size out of range, malformed cursor).
    #[error("invalid query: {0}")]
    InvalidQuery(String),
    /// A record cannot be stored as it is.
    #[error("invalid record: {0}")]
    InvalidRecord(String),
    /// A stored row does not decode (written by a newer version, or damaged).
    #[error("corrupt row: {0}")]
    Corrupt(String),
    /// The database was migrated by a newer version of Stanice.
    #[error("database schema version {found} is newer than this program knows ({supported})")]
    SchemaTooNew {
        /// The version found in `schema_version`.
        found: i64,
        /// The newest version this program has migrations for.
        supported: i64,
    },
    /// A migration failed.
    #[error("migration {version} failed: {source}")]
    Migration {
        /// The version of the failing migration.
        version: i64,
        /// Why.
        #[source]
        source: Box<StoreError>,
    },
    /// The SQLite backend failed.
    #[cfg(feature = "database")]
    #[error("sqlite: {0}")]
    Sqlite(#[from] rusqlite::Error),
    /// The PostgreSQL backend failed.
    #[cfg(feature = "database")]
    #[error("postgres: {}", postgres_message(.0))]
    Postgres(#[from] tokio_postgres::Error),
    /// A worker thread of the SQLite backend could not be started.
    #[error("cannot start a store thread: {0}")]
    Thread(#[source] std::io::Error),
    /// The store's worker thread is gone (the store is shutting down).
    #[error("the store is closed")]
    Closed,
    /// The connection pool failed (other than a database error or its closing).
    #[error("connection pool: {0}")]
    Pool(String),
    /// Another writer of the same store got there first; nothing was written and the
    /// write may be tried again.
    #[error("write conflict: {0}")]
    Conflict(String),
}

#[cfg(feature = "database")]
/// The error with the server's message: `tokio_postgres::Error` displays only "db error"
/// and keeps the server's words (and connection failures' causes) in its source.
fn postgres_message(e: &tokio_postgres::Error) -> String {
    let mut text = e.to_string();
    if let Some(db) = e.as_db_error() {
        text = format!(
            "{text}: {} {}: {}",
            db.severity(),
            db.code().code(),
            db.message()
        );
        if let Some(detail) = db.detail() {
            text.push_str(&format!(" ({detail})"));
        }
    } else if let Some(source) = std::error::Error::source(e) {
        let cause = source.to_string();
        if !text.contains(&cause) {
            text = format!("{text}: {cause}");
        }
    }
    text
}
