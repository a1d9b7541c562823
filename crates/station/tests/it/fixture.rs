//! Fresh stores for each test.

use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::Arc;

use station::store::{open_store, EventStore};

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

/// The server of the PostgreSQL tests, or `None` (with a SKIPPED note) when there is
/// none. With `STANICE_REQUIRE_PEERS=1` a missing server fails the test instead.
pub(crate) fn postgres_url(test: &str) -> Option<String> {
    match std::env::var("STANICE_TEST_POSTGRES_URL") {
        Ok(url) if !url.is_empty() => Some(url),
        _ => {
            if std::env::var("STANICE_REQUIRE_PEERS").as_deref() == Ok("1") {
                panic!(
                    "STANICE_REQUIRE_PEERS=1 but STANICE_TEST_POSTGRES_URL is not set: \
                     run the tests through scripts/with-postgres.sh"
                );
            }
            eprintln!(
                "SKIPPED {test}: STANICE_TEST_POSTGRES_URL not set \
                 (run through scripts/with-postgres.sh)"
            );
            None
        }
    }
}

/// A plain connection for test setup.
pub(crate) async fn admin(url: &str) -> Result<tokio_postgres::Client, tokio_postgres::Error> {
    let (client, conn) = tokio_postgres::connect(url, tokio_postgres::NoTls).await?;
    tokio::spawn(conn);
    Ok(client)
}

/// A fresh schema on the test server, and the URL that makes it the store's search path.
pub(crate) async fn postgres_schema(url: &str, test: &str) -> (String, String) {
    static NEXT: AtomicU32 = AtomicU32::new(0);
    let schema = format!(
        "t_{}_{}_{}",
        test.chars().take(30).collect::<String>(),
        std::process::id(),
        NEXT.fetch_add(1, Ordering::Relaxed)
    );
    let client = admin(url).await.unwrap();
    client
        .batch_execute(&format!(
            "DROP SCHEMA IF EXISTS {schema} CASCADE; CREATE SCHEMA {schema}"
        ))
        .await
        .unwrap();
    let sep = if url.contains('?') { '&' } else { '?' };
    let store_url = format!("{url}{sep}options=-c%20search_path%3D{schema}");
    (schema, store_url)
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
