//! The throwaway PostgreSQL server of the tests (`scripts/with-postgres.sh`): its URL, a
//! plain client, and a fresh schema per test. Shared with the station's runtime tests,
//! which include this file (`#[path]`) to record into the same kind of server.

use std::sync::atomic::{AtomicU32, Ordering};

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
