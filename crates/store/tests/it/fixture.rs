//! Fresh stores for each test.

use std::sync::Arc;

use store::{open_store, EventStore};

use crate::pg::{admin, postgres_schema, postgres_url};

/// A store under test and what must live as long as it.
pub(crate) struct Fixture {
    pub(crate) store: Arc<dyn EventStore>,
    _dir: Option<tempfile::TempDir>,
    pg_schema: Option<(String, String)>,
}

impl Fixture {
    /// Cleans up what outlives the process (PostgreSQL schemas).
    pub(crate) async fn finish(self) {
        if let Some((url, schema)) = &self.pg_schema {
            drop(self.store);
            if let Ok(client) = admin(url).await {
                let _ = client
                    .batch_execute(&format!("DROP SCHEMA IF EXISTS {schema} CASCADE"))
                    .await;
            }
        }
    }
}

/// A SQLite store on a fresh file (WAL, writer and reader threads).
pub(crate) async fn sqlite() -> Fixture {
    let dir = tempfile::tempdir().unwrap();
    let url = format!("sqlite:{}", dir.path().join("events.db").display());
    let store = open_store(&url).await.unwrap();
    Fixture {
        store: Arc::from(store),
        _dir: Some(dir),
        pg_schema: None,
    }
}

/// A SQLite store on a temp file that segments its tail after every append, so that the
/// suite reads every event through the segments and rollups as well as through the tail
/// (a store of its own passes only every few thousand events).
pub(crate) async fn sqlite_segmented() -> Fixture {
    let dir = tempfile::tempdir().unwrap();
    let store = store::SqliteStore::open(dir.path().join("events.db"))
        .await
        .unwrap()
        .passing_after_every_append();
    Fixture {
        store: Arc::new(store),
        _dir: Some(dir),
        pg_schema: None,
    }
}

/// A PostgreSQL store in a fresh schema that segments its tail after every append (see
/// [`sqlite_segmented`]), or `None` when the tests skip.
pub(crate) async fn postgres_segmented(test: &str) -> Option<Fixture> {
    let url = postgres_url(test)?;
    let (schema, store_url) = postgres_schema(&url, &format!("{test}_segmented")).await;
    let config = store::PostgresConfig::from_url(&store_url).unwrap();
    let store = store::PostgresStore::connect(config)
        .await
        .unwrap()
        .passing_after_every_append();
    Some(Fixture {
        store: Arc::new(store),
        _dir: None,
        pg_schema: Some((url, schema)),
    })
}

/// A PostgreSQL store in a fresh schema, or `None` when the tests skip.
pub(crate) async fn postgres(test: &str) -> Option<Fixture> {
    let url = postgres_url(test)?;
    let (schema, store_url) = postgres_schema(&url, test).await;
    let store = open_store(&store_url).await.unwrap();
    Some(Fixture {
        store: Arc::from(store),
        _dir: None,
        pg_schema: Some((url, schema)),
    })
}
