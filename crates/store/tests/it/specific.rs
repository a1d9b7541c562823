//! Backend-specific behaviour: URLs, persistence across reopen, migrations.

use store::{open_store, Backend, EventQuery, PointValue, SqliteStore, StoreError};

use crate::pg::{admin, postgres_schema, postgres_url};
use crate::suite::ev;

#[tokio::test]
async fn bad_urls_give_clear_errors() {
    for (url, needle) in [
        ("", "no scheme"),
        ("events.db", "no scheme"),
        ("mysql://localhost/db", "unknown scheme \"mysql\""),
        ("sqlite:", "no database path"),
        ("sqlite://", "no database path"),
        ("postgres://", "no host"),
        ("postgres://localhost", "no database name"),
        ("postgresql://u@localhost:notaport/db", "invalid"),
    ] {
        let err = open_store(url).await.err().unwrap();
        let text = err.to_string();
        assert!(matches!(err, StoreError::BadUrl { .. }), "{url}: {text}");
        assert!(text.contains(needle), "{url}: {text}");
        assert!(text.contains("expected sqlite:PATH"), "{url}: {text}");
    }
    // Passwords never show in errors.
    let err = open_store("postgres://admin:s3cret@localhost:bad/db")
        .await
        .err()
        .unwrap()
        .to_string();
    assert!(!err.contains("s3cret"), "{err}");
    assert!(err.contains("admin:***@"), "{err}");
    // A directory that does not exist is an SQLite error naming the problem.
    let err = open_store("sqlite:/nonexistent-dir/x/events.db")
        .await
        .err()
        .unwrap();
    assert!(matches!(err, StoreError::Sqlite(_)), "{err}");
}

#[tokio::test]
async fn postgres_unreachable_server_fails_at_open() {
    // A port nobody listens on (bound and released just now).
    let port = std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port();
    let err = open_store(&format!("postgres://postgres@127.0.0.1:{port}/x"))
        .await
        .err()
        .unwrap();
    assert!(matches!(err, StoreError::Postgres(_)), "{err}");
    assert!(err.to_string().to_lowercase().contains("connect"), "{err}");
}

#[tokio::test]
async fn postgres_unknown_database_fails_at_open() {
    let Some(url) = postgres_url("postgres_unknown_database_fails_at_open") else {
        return;
    };
    let (base, _) = url.rsplit_once('/').unwrap();
    let err = open_store(&format!("{base}/no_such_database_here"))
        .await
        .err()
        .unwrap();
    assert!(err.to_string().contains("no_such_database_here"), "{err}");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn sqlite_file_persists_across_reopen() {
    let dir = tempfile::tempdir().unwrap();
    let url = format!("sqlite:{}", dir.path().join("events.db").display());
    let ids = {
        let store = open_store(&url).await.unwrap();
        assert_eq!(store.backend(), Backend::Sqlite);
        store
            .append_events(&[
                ev("A", PointValue::Int(1), 1),
                ev("B", PointValue::Int(2), 2),
            ])
            .await
            .unwrap()
    };
    // WAL mode is on.
    assert!(dir.path().join("events.db-wal").exists());
    let store = open_store(&url).await.unwrap();
    let page = store.query_events(&EventQuery::default()).await.unwrap();
    assert_eq!(page.items.len(), 2);
    assert_eq!(page.items[1].id, Some(ids[0]));
    // New ids continue after the old ones.
    let more = store
        .append_events(&[ev("C", PointValue::Int(3), 3)])
        .await
        .unwrap();
    assert!(more[0] > ids[1]);
    // The `sqlite://` spelling opens the same file; two stores on one file coexist.
    let other = open_store(&format!(
        "sqlite://{}",
        dir.path().join("events.db").display()
    ))
    .await
    .unwrap();
    assert_eq!(other.stats().await.unwrap().events, 3);
}

#[tokio::test]
async fn sqlite_ids_are_never_reused_after_a_purge() {
    let dir = tempfile::tempdir().unwrap();
    let store = SqliteStore::open(dir.path().join("e.db")).await.unwrap();
    use store::EventStore;
    let a = store
        .append_events(&[ev("A", PointValue::Int(1), 1)])
        .await
        .unwrap();
    store
        .purge_older_than(crate::suite::at_ms(1_000_000))
        .await
        .unwrap();
    let b = store
        .append_events(&[ev("B", PointValue::Int(1), 1)])
        .await
        .unwrap();
    assert!(b[0] > a[0]);
    assert_eq!(store.path(), Some(dir.path().join("e.db").as_path()));
}

#[tokio::test]
async fn sqlite_memory_store_works_and_is_private() {
    let a = open_store("sqlite::memory:").await.unwrap();
    let b = open_store("sqlite::memory:").await.unwrap();
    a.append_events(&[ev("A", PointValue::Bool(true), 0)])
        .await
        .unwrap();
    assert_eq!(a.stats().await.unwrap().events, 1);
    assert_eq!(b.stats().await.unwrap().events, 0);
}

#[tokio::test]
async fn sqlite_refuses_a_newer_schema() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("events.db");
    drop(SqliteStore::open(&path).await.unwrap());
    let conn = rusqlite::Connection::open(&path).unwrap();
    conn.execute(
        "INSERT INTO schema_version (version, applied_ms) VALUES (99, 0)",
        [],
    )
    .unwrap();
    drop(conn);
    let err = SqliteStore::open(&path).await.unwrap_err();
    assert!(
        matches!(
            err,
            StoreError::SchemaTooNew {
                found: 99,
                supported: 1
            }
        ),
        "{err}"
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn postgres_persists_across_reopen_and_refuses_a_newer_schema() {
    let Some(url) = postgres_url("postgres_persists_across_reopen") else {
        return;
    };
    let (schema, store_url) = postgres_schema(&url, "reopen").await;
    {
        let store = open_store(&store_url).await.unwrap();
        assert_eq!(store.backend(), Backend::Postgres);
        store
            .append_events(&[ev("A", PointValue::Int(1), 1)])
            .await
            .unwrap();
    }
    // Opening again migrates nothing and sees the data; opening twice at once is safe.
    let (s1, s2) = tokio::join!(open_store(&store_url), open_store(&store_url));
    let (s1, s2) = (s1.unwrap(), s2.unwrap());
    assert_eq!(s1.stats().await.unwrap().events, 1);
    assert_eq!(s2.stats().await.unwrap().events, 1);
    drop((s1, s2));
    let client = admin(&url).await.unwrap();
    client
        .batch_execute(&format!(
            "INSERT INTO {schema}.schema_version (version, applied_ms) VALUES (42, 0)"
        ))
        .await
        .unwrap();
    let err = open_store(&store_url).await.err().unwrap();
    assert!(
        matches!(
            err,
            StoreError::SchemaTooNew {
                found: 42,
                supported: 1
            }
        ),
        "{err}"
    );
    client
        .batch_execute(&format!("DROP SCHEMA {schema} CASCADE"))
        .await
        .unwrap();
}
