//! Backend-specific behaviour: URLs, persistence across reopen, migrations.

use store::{
    open_store, Backend, EventQuery, EventStore, LiftFaultQuery, LiftFaultRecord, PointValue,
    SqliteStore, StoreError,
};

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
    let port = testkit::ports::free_port();
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

/// `?cache_mib=N`: the store opens with its page caches bounded and works; a cache of
/// 0 MiB is a bad address. (How the MiB are shared out: the unit test in src/sqlite.rs.)
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_sqlite_store_opens_with_a_bounded_cache() {
    let dir = tempfile::tempdir().unwrap();
    let url = format!(
        "sqlite:{}?cache_mib=2",
        dir.path().join("small.db").display()
    );
    let store = open_store(&url).await.unwrap();
    store
        .append_events(&[ev("A", PointValue::Int(1), 1)])
        .await
        .unwrap();
    assert_eq!(store.stats().await.unwrap().events, 1);
    store.close().await.unwrap();
    assert!(dir.path().join("small.db").exists());
    assert!(matches!(
        open_store("sqlite:x.db?cache_mib=0").await.err(),
        Some(StoreError::BadUrl { .. })
    ));
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
                supported: 6
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
                supported: 6
            }
        ),
        "{err}"
    );
    client
        .batch_execute(&format!("DROP SCHEMA {schema} CASCADE"))
        .await
        .unwrap();
}

/// Schema version 1 as the program of that version created it: its migration, with the
/// column types of `backend`, and its `schema_version` row; plus one event.
fn version_1(backend: Backend) -> String {
    let types: &[(&str, &str)] = match backend {
        Backend::Sqlite => &[
            ("{id}", "INTEGER PRIMARY KEY AUTOINCREMENT"),
            ("{name}", "TEXT"),
            ("{int8}", "INTEGER"),
            ("{int2}", "INTEGER"),
            ("{float8}", "REAL"),
            ("{bool}", "INTEGER"),
        ],
        Backend::Postgres => &[
            (
                "{id}",
                "BIGINT GENERATED BY DEFAULT AS IDENTITY PRIMARY KEY",
            ),
            ("{name}", "TEXT COLLATE \"C\""),
            ("{int8}", "BIGINT"),
            ("{int2}", "SMALLINT"),
            ("{float8}", "DOUBLE PRECISION"),
            ("{bool}", "BOOLEAN"),
        ],
    };
    let init = types.iter().fold(
        include_str!("../../migrations/0001_init.sql").to_owned(),
        |sql, (name, ty)| sql.replace(name, ty),
    );
    let int8 = if backend == Backend::Sqlite {
        "INTEGER"
    } else {
        "BIGINT"
    };
    let no = if backend == Backend::Sqlite {
        "0"
    } else {
        "false"
    };
    format!(
        "CREATE TABLE schema_version (version {int8} PRIMARY KEY, applied_ms {int8} NOT NULL);
         {init};
         INSERT INTO schema_version (version, applied_ms) VALUES (1, 0);
         INSERT INTO events (node, point, value_kind, value_int, quality, source_invalid,
             received_ms, event_ms, cause, origin)
         VALUES ('RH2', 'OLD', 3, 42, 0, {no}, 1000, 1000, 1, 'RH2');"
    )
}

/// What a store opened on the version-1 database must show: the old event, in the trend
/// rollups too (folded by the migration), and a working fault archive.
async fn check_migrated_to_2(store: &dyn EventStore) {
    let events = store.query_events(&EventQuery::default()).await.unwrap();
    assert_eq!(events.items.len(), 1);
    assert_eq!(events.items[0].point, "OLD");
    assert_eq!(events.items[0].value, PointValue::Int(42));
    let epoch = chrono::DateTime::<chrono::Utc>::UNIX_EPOCH;
    let day = store::TrendQuery::new("OLD", epoch, epoch + chrono::Duration::days(1), 1);
    assert_eq!(day.rollup_span_ms(), Some(60_000));
    let trend = store.query_trend(&day).await.unwrap();
    assert_eq!(
        trend.iter().map(|b| (b.min, b.count)).collect::<Vec<_>>(),
        [(42.0, 1)]
    );
    // Its minute's first and last value: the minute, folded before version 5, kept none,
    // so the trend finds them in the events.
    let ends = store
        .query_trend(&day.clone().with_mode(store::TrendMode::FirstLast))
        .await
        .unwrap();
    assert_eq!(
        ends.iter().map(|b| (b.first, b.last)).collect::<Vec<_>>(),
        [(Some(42.0), Some(42.0))]
    );
    let fault = LiftFaultRecord {
        id: None,
        node: "LIFTS".into(),
        lift: "V1".into(),
        stack_index: 3,
        code: 0x11,
        floor: 2,
        target: 0,
        board_time: None,
        received_time: crate::suite::at_ms(0),
    };
    store.append_lift_faults(&[fault]).await.unwrap();
    let archive = store
        .query_lift_faults(&LiftFaultQuery::default())
        .await
        .unwrap();
    assert_eq!(archive.total, 1);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn sqlite_migrates_a_version_1_database() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("events.db");
    rusqlite::Connection::open(&path)
        .unwrap()
        .execute_batch(&version_1(Backend::Sqlite))
        .unwrap();
    let store = SqliteStore::open(&path).await.unwrap();
    check_migrated_to_2(&store).await;
    drop(store);
    let conn = rusqlite::Connection::open(&path).unwrap();
    let versions: Vec<i64> = conn
        .prepare("SELECT version FROM schema_version ORDER BY version")
        .unwrap()
        .query_map([], |r| r.get(0))
        .unwrap()
        .collect::<Result<_, _>>()
        .unwrap();
    assert_eq!(versions, [1, 2, 3, 4, 5, 6]);
    // Opening again migrates nothing.
    drop(conn);
    check_reopened(
        &*open_store(&format!("sqlite:{}", path.display()))
            .await
            .unwrap(),
    )
    .await;
}

/// A reopened migrated store has its rows and migrates nothing twice.
async fn check_reopened(store: &dyn EventStore) {
    let archive = store
        .query_lift_faults(&LiftFaultQuery::default())
        .await
        .unwrap();
    assert_eq!(archive.total, 1);
    assert_eq!(store.stats().await.unwrap().events, 1);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn postgres_migrates_a_version_1_database() {
    let Some(url) = postgres_url("postgres_migrates_a_version_1_database") else {
        return;
    };
    let (schema, store_url) = postgres_schema(&url, "migrate_v1").await;
    let client = admin(&url).await.unwrap();
    client
        .batch_execute(&format!(
            "SET search_path TO {schema}; {}",
            version_1(Backend::Postgres)
        ))
        .await
        .unwrap();
    {
        let store = open_store(&store_url).await.unwrap();
        check_migrated_to_2(&*store).await;
        // Version 6 moved the rows of `events` (partitioned by day since version 3) into
        // blocks, partitioned by day too: the old event in its day's blocks, its id kept,
        // new ids after it; `events` is gone.
        let partitioned: i64 = client
            .query_one(
                &format!(
                    "SELECT count(*) FROM pg_partitioned_table \
                     WHERE partrelid IN ('{schema}.event_blocks'::regclass, \
                                         '{schema}.event_segments'::regclass, \
                                         '{schema}.commands'::regclass)"
                ),
                &[],
            )
            .await
            .unwrap()
            .get(0);
        assert_eq!(partitioned, 3);
        let events_table: Option<String> = client
            .query_one(&format!("SELECT to_regclass('{schema}.events')::text"), &[])
            .await
            .unwrap()
            .get(0);
        assert_eq!(events_table, None);
        let old_day: i64 = client
            .query_one(
                &format!("SELECT CAST(SUM(events) AS BIGINT) FROM {schema}.event_blocks_19700101"),
                &[],
            )
            .await
            .unwrap()
            .get(0);
        assert_eq!(old_day, 1);
        // Version 5 partitioned the rollups by day: the old event's minute in its day.
        let old_minutes: i64 = client
            .query_one(
                &format!("SELECT count(*) FROM {schema}.trend_rollups_19700101"),
                &[],
            )
            .await
            .unwrap()
            .get(0);
        assert_eq!(old_minutes, 1);
        let old = store.query_events(&EventQuery::default()).await.unwrap();
        let ids = store
            .append_events(&[ev("NEW", PointValue::Int(1), 0)])
            .await
            .unwrap();
        assert!(ids[0] > old.items[0].id.unwrap());
    }
    let versions: Vec<i64> = client
        .query(
            &format!("SELECT version FROM {schema}.schema_version ORDER BY version"),
            &[],
        )
        .await
        .unwrap()
        .iter()
        .map(|r| r.get(0))
        .collect();
    assert_eq!(versions, [1, 2, 3, 4, 5, 6]);
    let reopened = open_store(&store_url).await.unwrap();
    let archive = reopened
        .query_lift_faults(&LiftFaultQuery::default())
        .await
        .unwrap();
    assert_eq!(archive.total, 1);
    assert_eq!(reopened.stats().await.unwrap().events, 2);
    drop(reopened);
    client
        .batch_execute(&format!("DROP SCHEMA {schema} CASCADE"))
        .await
        .unwrap();
}

/// Schema version 6 moves a SQLite store's rows into blocks at open: every event with its
/// id, key and values (more than one chunk of the move), the trends folded again from
/// them, and ids going on after the largest.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn sqlite_moves_the_old_rows_into_blocks_with_their_ids() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("events.db");
    let conn = rusqlite::Connection::open(&path).unwrap();
    conn.execute_batch(&version_1(Backend::Sqlite)).unwrap();
    // 100,000 events of 7 points, a second apart, every third one's id skipped (gaps as
    // purges and ignored keys leave them), with a float value each.
    conn.execute_batch(
        "WITH RECURSIVE n (i) AS (SELECT 1 UNION ALL SELECT i + 1 FROM n WHERE i < 100000)
         INSERT INTO events (id, node, point, value_kind, value_float, quality,
             source_invalid, received_ms, event_ms, cause, origin)
         SELECT 10 + i * 3 / 2, 'RH2', 'P' || (i % 7), 4, i * 0.5, i % 2, 0,
                2000000 + i * 1000, 2000000 + i * 1000, 1, 'RH2'
         FROM n;",
    )
    .unwrap();
    drop(conn);
    let store = SqliteStore::open(&path).await.unwrap();
    let all = crate::suite::all_events(
        &store,
        EventQuery::default()
            .with_order(store::Order::OldestFirst)
            .with_limit(10_000),
    )
    .await;
    assert_eq!(all.len(), 100_001); // and the version-1 fixture's own event
    let moved: Vec<_> = all.iter().filter(|e| e.point != "OLD").collect();
    for (k, e) in moved.iter().enumerate() {
        let i = k as i64 + 1;
        assert_eq!(e.id, Some(10 + i * 3 / 2), "event {i}");
        assert_eq!(e.point, format!("P{}", i % 7));
        assert_eq!(e.value, PointValue::Float(i as f64 * 0.5));
        assert_eq!(e.quality.invalid, i % 2 == 1);
    }
    // One point's page through its segments, newest first.
    let p3 = store
        .query_events(&EventQuery::default().with_point("P3").with_limit(3))
        .await
        .unwrap();
    let times: Vec<i64> = p3
        .items
        .iter()
        .map(|e| e.event_time().timestamp_millis())
        .collect();
    // P3's newest: i = 99,998, 99,991, 99,984 (i % 7 == 3).
    assert_eq!(
        times,
        [99_998, 99_991, 99_984].map(|i: i64| 2_000_000 + i * 1000)
    );
    let start = chrono::DateTime::<chrono::Utc>::UNIX_EPOCH;
    let trend = store::TrendQuery::new("P0", start, start + chrono::Duration::days(2), 10);
    let buckets = store.query_trend(&trend).await.unwrap();
    let count: u64 = buckets.iter().map(|b| b.count).sum();
    assert_eq!(count, 100_000 / 7);
    let next = store
        .append_events(&[ev("NEW", PointValue::Int(1), 1)])
        .await
        .unwrap();
    assert!(next[0] > 10 + 100_000 * 3 / 2, "{next:?}");
    // The table is gone; opening again moves nothing.
    drop(store);
    let conn = rusqlite::Connection::open(&path).unwrap();
    let tables: i64 = conn
        .query_row(
            "SELECT count(*) FROM sqlite_master WHERE type = 'table' AND name = 'events'",
            [],
            |r| r.get(0),
        )
        .unwrap();
    assert_eq!(tables, 0);
    drop(conn);
    let again = SqliteStore::open(&path).await.unwrap();
    assert_eq!(again.stats().await.unwrap().events, 100_002);
}

/// The same move on PostgreSQL: the rows of every day partition of `events` into blocks
/// of their days, with their ids (read in time order through the day's index), then
/// `events` dropped.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn postgres_moves_the_old_rows_into_blocks_with_their_ids() {
    let Some(url) = postgres_url("postgres_moves_the_old_rows") else {
        return;
    };
    let (schema, store_url) = postgres_schema(&url, "moves").await;
    let client = admin(&url).await.unwrap();
    client
        .batch_execute(&format!(
            "SET search_path TO {schema}; {}; \
             INSERT INTO events (id, node, point, value_kind, value_float, quality, \
                 source_invalid, received_ms, event_ms, cause, origin) \
             SELECT 10 + i * 3 / 2, 'RH2', 'P' || (i % 7), 4, i * 0.5, i % 2, false, \
                    2000000 + i * 5000, 2000000 + i * 5000, 1, 'RH2' \
             FROM generate_series(1, 100000) AS i;",
            version_1(Backend::Postgres)
        ))
        .await
        .unwrap();
    let store = open_store(&store_url).await.unwrap();
    let all = crate::suite::all_events(
        &*store,
        EventQuery::default()
            .with_order(store::Order::OldestFirst)
            .with_limit(10_000),
    )
    .await;
    assert_eq!(all.len(), 100_001);
    let moved: Vec<_> = all.iter().filter(|e| e.point != "OLD").collect();
    for (k, e) in moved.iter().enumerate() {
        let i = k as i64 + 1;
        assert_eq!(e.id, Some(10 + i * 3 / 2), "event {i}");
        assert_eq!(e.value, PointValue::Float(i as f64 * 0.5));
        assert_eq!(e.quality.invalid, i % 2 == 1);
    }
    let days: i64 = client
        .query_one(
            &format!(
                "SELECT count(*) FROM pg_inherits i JOIN pg_class c ON c.oid = i.inhrelid \
                 WHERE i.inhparent = '{schema}.event_blocks'::regclass \
                   AND c.relname LIKE 'event_blocks_1970%'"
            ),
            &[],
        )
        .await
        .unwrap()
        .get(0);
    assert_eq!(days, 6, "the days 1970-01-01 to 06");
    let start = chrono::DateTime::<chrono::Utc>::UNIX_EPOCH;
    let trend = store::TrendQuery::new("P0", start, start + chrono::Duration::days(7), 10);
    let count: u64 = store
        .query_trend(&trend)
        .await
        .unwrap()
        .iter()
        .map(|b| b.count)
        .sum();
    assert_eq!(count, 100_000 / 7);
    let next = store
        .append_events(&[ev("NEW", PointValue::Int(1), 1)])
        .await
        .unwrap();
    assert!(next[0] > 10 + 100_000 * 3 / 2, "{next:?}");
    let events_table: Option<String> = client
        .query_one(&format!("SELECT to_regclass('{schema}.events')::text"), &[])
        .await
        .unwrap()
        .get(0);
    assert_eq!(events_table, None);
    drop(store);
    client
        .batch_execute(&format!("DROP SCHEMA {schema} CASCADE"))
        .await
        .unwrap();
}

/// Two stores on one SQLite file (the station's and a tool's) appending at once, each
/// passing after every append: ids never collide (they come from the file's counter a
/// range at a time), a pass that meets blocks the other segmented writes again, and
/// every event is listed once.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn sqlite_two_stores_on_one_file_append_at_once() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("events.db");
    let a = SqliteStore::open(&path)
        .await
        .unwrap()
        .passing_after_every_append();
    let b = SqliteStore::open(&path)
        .await
        .unwrap()
        .passing_after_every_append();
    let batch = |who: &str, round: i64| -> Vec<_> {
        (0..50)
            .map(|i| {
                ev(
                    &format!("{who}{}", i % 5),
                    PointValue::Int(i),
                    round * 1000 + i,
                )
            })
            .collect()
    };
    let (mut ids_a, mut ids_b) = (Vec::new(), Vec::new());
    for round in 0..20 {
        let (for_a, for_b) = (batch("A", round), batch("B", round));
        let (x, y) = tokio::join!(a.append_events(&for_a), b.append_events(&for_b));
        ids_a.extend(x.unwrap());
        ids_b.extend(y.unwrap());
    }
    let mut all: Vec<i64> = ids_a.iter().chain(&ids_b).copied().collect();
    all.sort_unstable();
    all.dedup();
    assert_eq!(all.len(), 2_000, "ids handed out twice");
    let listed = crate::suite::all_events(&a, EventQuery::default().with_limit(500)).await;
    assert_eq!(listed.len(), 2_000);
    let one = crate::suite::all_events(&b, EventQuery::default().with_point("A3")).await;
    assert_eq!(one.len(), 200);
}
