//! PostgreSQL's day partitions: made at open (today and 7 days ahead) and for the days
//! appends meet, a clock far off in the DEFAULT partition until its day is made, retention
//! by dropping whole days, and an older database converted with its rows.

use chrono::{Duration, Utc};
use store::{open_store, Actor, CommandOutcome, CommandPhase, CommandRecord};
use store::{PointValue, DAYS_AHEAD};

use crate::pg::{admin, postgres_schema, postgres_url};
use crate::suite::{at_ms, ev};

const DAY: i64 = 86_400_000;

/// The day partitions of `table` in `schema`, by name, and the rows of each.
async fn partitions(
    client: &tokio_postgres::Client,
    schema: &str,
    table: &str,
) -> Vec<(String, i64)> {
    let names: Vec<String> = client
        .query(
            "SELECT c.relname::text FROM pg_inherits i JOIN pg_class c ON c.oid = i.inhrelid \
             WHERE i.inhparent = to_regclass($1) ORDER BY 1",
            &[&format!("{schema}.{table}")],
        )
        .await
        .unwrap()
        .iter()
        .map(|r| r.get(0))
        .collect();
    let mut out = Vec::new();
    for name in names {
        // A block holds many events: the events of a day of blocks are their sum.
        let count = if table == "event_blocks" {
            "CAST(COALESCE(SUM(events), 0) AS BIGINT)"
        } else {
            "count(*)"
        };
        let rows: i64 = client
            .query_one(&format!("SELECT {count} FROM {schema}.{name}"), &[])
            .await
            .unwrap()
            .get(0);
        out.push((name, rows));
    }
    out
}

fn rows_of(parts: &[(String, i64)], name: &str) -> Option<i64> {
    parts.iter().find(|(n, _)| n == name).map(|(_, rows)| *rows)
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn postgres_days_are_partitions_made_ahead_on_demand_and_dropped_whole() {
    let Some(url) = postgres_url("postgres_days_are_partitions") else {
        return;
    };
    let (schema, store_url) = postgres_schema(&url, "partitions").await;
    let client = admin(&url).await.unwrap();
    let store = open_store(&store_url).await.unwrap();

    // At open: today and DAYS_AHEAD days ahead, of both tables, plus the DEFAULT ones.
    let parts = partitions(&client, &schema, "event_blocks").await;
    for d in 0..=DAYS_AHEAD {
        let name = format!(
            "event_blocks_{}",
            (Utc::now() + Duration::days(d)).format("%Y%m%d")
        );
        assert_eq!(rows_of(&parts, &name), Some(0), "{name} in {parts:?}");
    }
    assert_eq!(rows_of(&parts, "event_blocks_default"), Some(0));
    let name = format!(
        "commands_{}",
        (Utc::now() + Duration::days(DAYS_AHEAD)).format("%Y%m%d")
    );
    assert!(rows_of(&partitions(&client, &schema, "commands").await, &name).is_some());

    // Appends make the days they meet (2026-03-01 to 03-04), each row in its day.
    let events: Vec<_> = (0..400)
        .map(|i| ev("P", PointValue::Int(i), i * DAY / 100))
        .collect();
    store.append_events(&events).await.unwrap();
    let command = CommandRecord {
        id: None,
        time: at_ms(DAY + 5),
        actor: Actor::User("op".into()),
        node: "RDRT".into(),
        point: "P".into(),
        ioa: None,
        value: PointValue::Bool(true),
        phase: CommandPhase::Execute,
        outcome: CommandOutcome::Executed,
        detail: String::new(),
    };
    store.append_command(&command).await.unwrap();
    // A source clock years ahead: the DEFAULT partition, not a table of its own.
    let far = ev("P", PointValue::Int(-1), 3000 * DAY);
    store.append_events(&[far]).await.unwrap();
    let parts = partitions(&client, &schema, "event_blocks").await;
    for day in 1..=4 {
        assert_eq!(
            rows_of(&parts, &format!("event_blocks_2026030{day}")),
            Some(100)
        );
    }
    assert_eq!(rows_of(&parts, "event_blocks_default"), Some(1));
    let commands = partitions(&client, &schema, "commands").await;
    assert_eq!(rows_of(&commands, "commands_20260302"), Some(1));

    // When that day's partition is made (the calendar reached it), its row moves there.
    let far_day = at_ms(3000 * DAY);
    store
        .prepare_partitions(far_day - Duration::days(2))
        .await
        .unwrap();
    let parts = partitions(&client, &schema, "event_blocks").await;
    assert_eq!(rows_of(&parts, "event_blocks_default"), Some(0));
    assert_eq!(
        rows_of(
            &parts,
            &format!("event_blocks_{}", far_day.format("%Y%m%d"))
        ),
        Some(1)
    );

    // Retention at 03-03 06:00: the whole days before it go (two tables dropped), the day
    // holding the cutoff stays whole.
    let purged = store
        .purge_older_than(at_ms(2 * DAY + DAY / 4))
        .await
        .unwrap();
    assert_eq!(purged, 200 + 1);
    let parts = partitions(&client, &schema, "event_blocks").await;
    assert_eq!(rows_of(&parts, "event_blocks_20260301"), None);
    assert_eq!(rows_of(&parts, "event_blocks_20260302"), None);
    assert_eq!(rows_of(&parts, "event_blocks_20260303"), Some(100));
    assert_eq!(store.stats().await.unwrap().events, 201);
    assert_eq!(
        rows_of(
            &partitions(&client, &schema, "commands").await,
            "commands_20260302"
        ),
        None
    );
    // A late event of a dropped day does not bring the day back: DEFAULT, and the next
    // pass purges it.
    store
        .append_events(&[ev("P", PointValue::Int(7), 5)])
        .await
        .unwrap();
    let parts = partitions(&client, &schema, "event_blocks").await;
    assert_eq!(rows_of(&parts, "event_blocks_20260301"), None);
    assert_eq!(rows_of(&parts, "event_blocks_default"), Some(1));
    assert_eq!(store.purge_older_than(at_ms(2 * DAY)).await.unwrap(), 1);

    drop(store);
    client
        .batch_execute(&format!("DROP SCHEMA {schema} CASCADE"))
        .await
        .unwrap();
}

/// Two stores making the same days at once (two station processes on one database).
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn postgres_two_stores_make_the_same_days_at_once() {
    let Some(url) = postgres_url("postgres_two_stores_make_the_same_days") else {
        return;
    };
    let (schema, store_url) = postgres_schema(&url, "partitions_race").await;
    let a = open_store(&store_url).await.unwrap();
    let b = open_store(&store_url).await.unwrap();
    let batch = |offset: i64| -> Vec<_> {
        (0..300)
            .map(|i| ev("P", PointValue::Int(i), offset + i * DAY / 10))
            .collect()
    };
    let (first, second) = (batch(0), batch(1));
    let (x, y) = tokio::join!(a.append_events(&first), b.append_events(&second));
    x.unwrap();
    y.unwrap();
    assert_eq!(a.stats().await.unwrap().events, 600);
    drop((a, b));
    admin(&url)
        .await
        .unwrap()
        .batch_execute(&format!("DROP SCHEMA {schema} CASCADE"))
        .await
        .unwrap();
}

/// The physical order of a rollup day's rows (a plain scan), as (point, minute).
async fn rollup_rows(client: &tokio_postgres::Client, table: &str) -> Vec<(String, i64)> {
    client
        .query(&format!("SELECT point::text, start_ms FROM {table}"), &[])
        .await
        .unwrap()
        .iter()
        .map(|r| (r.get(0), r.get(1)))
        .collect()
}

/// Schema version 5: the trend rollups are partitioned by day, written as the events
/// come (all points of a minute together, so a point's minutes lie scattered) and
/// rewritten in key order once a day is closed; trends answer the same before and
/// after, a late event of a rewritten day is still folded, and retention drops the
/// rollup days with the event days.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn postgres_closed_rollup_days_are_rewritten_in_key_order_once() {
    let Some(url) = postgres_url("postgres_closed_rollup_days") else {
        return;
    };
    let (schema, store_url) = postgres_schema(&url, "rollup_days").await;
    let client = admin(&url).await.unwrap();
    let store = open_store(&store_url).await.unwrap();

    // Three days (2026-03-01 to 03), 12 points, a value per point every minute, one batch
    // per minute as a station's recorder writes them.
    const POINTS: i64 = 12;
    let minutes = 3 * 1440;
    let mut batch = Vec::new();
    for minute in 0..minutes {
        batch.clear();
        for p in 0..POINTS {
            let value = PointValue::Float(((minute * 7 + p * 13) % 101) as f64);
            batch.push(ev(&format!("P{p:02}"), value, minute * 60_000 + p));
        }
        store.append_events(&batch).await.unwrap();
    }
    let day_one = format!("{schema}.trend_rollups_20260301");
    let written = rollup_rows(&client, &day_one).await;
    assert_eq!(written.len(), (1440 * POINTS) as usize);
    let mut sorted = written.clone();
    sorted.sort();
    assert_ne!(
        written, sorted,
        "written in time order, all points of a minute together"
    );
    let trend = |point: &str| store::TrendQuery::new(point, at_ms(0), at_ms(3 * DAY), 72);
    let before = store.query_trend(&trend("P05")).await.unwrap();
    assert_eq!(before.len(), 72);

    // At 03-03 01:00 the first two days are closed (an hour after their end), the third
    // is not: two days rewritten, and only once.
    let now = at_ms(2 * DAY + 3_600_000);
    assert_eq!(store.compact_closed_days(now).await.unwrap(), 2);
    assert_eq!(store.compact_closed_days(now).await.unwrap(), 0);
    assert_eq!(rollup_rows(&client, &day_one).await, sorted);
    let day_two = rollup_rows(&client, &format!("{schema}.trend_rollups_20260302")).await;
    assert!(day_two.windows(2).all(|w| w[0] <= w[1]));
    let day_three = rollup_rows(&client, &format!("{schema}.trend_rollups_20260303")).await;
    assert!(!day_three.windows(2).all(|w| w[0] <= w[1]));
    assert_eq!(store.query_trend(&trend("P05")).await.unwrap(), before);

    // A late event of a rewritten day is folded as before.
    store
        .append_events(&[ev("P05", PointValue::Float(1000.0), 30)])
        .await
        .unwrap();
    let after = store.query_trend(&trend("P05")).await.unwrap();
    assert_eq!(after[0].max, 1000.0);
    assert_eq!(after[0].count, before[0].count + 1);
    assert_eq!(after[1..], before[1..]);

    // Retention at 03-02 06:00 drops the first day's events and rollups together.
    store.purge_older_than(at_ms(DAY + DAY / 4)).await.unwrap();
    let rollup_days = partitions(&client, &schema, "trend_rollups").await;
    assert_eq!(rows_of(&rollup_days, "trend_rollups_20260301"), None);
    assert_eq!(
        rows_of(&rollup_days, "trend_rollups_20260302"),
        Some(1440 * POINTS)
    );
    let trend_now = store.query_trend(&trend("P05")).await.unwrap();
    assert_eq!(trend_now.len(), 48);

    drop(store);
    client
        .batch_execute(&format!("DROP SCHEMA {schema} CASCADE"))
        .await
        .unwrap();
}
