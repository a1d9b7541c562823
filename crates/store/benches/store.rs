//! Event store benchmark: append throughput (batches of 1 and of 500) and paged query
//! latency, SQLite and PostgreSQL side by side.
//!
//! ```text
//! bash scripts/with-postgres.sh cargo bench -p store --bench store
//! ```
//!
//! Without `STANICE_TEST_POSTGRES_URL` only SQLite runs. SQLite runs on a temp file (WAL,
//! synchronous=NORMAL); the throwaway PostgreSQL of `scripts/with-postgres.sh` runs with
//! synchronous_commit=off, the comparable durability.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use chrono::{Duration, TimeZone, Utc};
use std::time::Instant;

use store::{open_store, EventQuery, EventRecord, EventStore, PointValue};

const SINGLE: usize = 2_000;
const BATCH: usize = 500;
const BATCHES: usize = 200;
const PAGES: usize = 200;
const PAGE_SIZE: usize = 100;

fn event(i: usize) -> EventRecord {
    let t0 = Utc.with_ymd_and_hms(2026, 3, 1, 0, 0, 0).unwrap();
    let mut e = EventRecord::new(
        format!("ROV{:02}", i % 12),
        format!("ROV{:02}_P{}", i % 12, i % 40),
        match i % 3 {
            0 => PointValue::Bool(i % 2 == 0),
            1 => PointValue::Float(i as f64 * 0.25),
            _ => PointValue::Int(i as i64),
        },
        t0 + Duration::milliseconds(i as i64 * 10),
    );
    e.ioa = Some((i % 3000) as u32);
    e
}

#[derive(Default, Clone, Copy)]
struct Figures {
    single_per_s: f64,
    batch_per_s: f64,
    page_p50_ms: f64,
    page_p99_ms: f64,
    filtered_p50_ms: f64,
    filtered_p99_ms: f64,
    node_p50_ms: f64,
    node_p99_ms: f64,
}

fn percentile(samples: &mut [f64], p: f64) -> f64 {
    samples.sort_by(|a, b| a.total_cmp(b));
    let i = ((samples.len() as f64 - 1.0) * p).round() as usize;
    samples[i.min(samples.len() - 1)]
}

async fn walk(store: &dyn EventStore, query: EventQuery) -> Vec<f64> {
    let mut lat = Vec::with_capacity(PAGES);
    let mut after = None;
    for _ in 0..PAGES {
        let q = query.clone().with_after(after);
        let start = Instant::now();
        let page = store.query_events(&q).await.unwrap();
        lat.push(start.elapsed().as_secs_f64() * 1000.0);
        assert!(!page.items.is_empty());
        after = page.next;
        if after.is_none() {
            break;
        }
    }
    lat
}

async fn run(store: &dyn EventStore) -> Figures {
    let mut f = Figures::default();
    let mut n = 0;
    let start = Instant::now();
    for _ in 0..SINGLE {
        store.append_events(&[event(n)]).await.unwrap();
        n += 1;
    }
    f.single_per_s = SINGLE as f64 / start.elapsed().as_secs_f64();

    let start = Instant::now();
    for _ in 0..BATCHES {
        let batch: Vec<_> = (n..n + BATCH).map(event).collect();
        store.append_events(&batch).await.unwrap();
        n += BATCH;
    }
    f.batch_per_s = (BATCHES * BATCH) as f64 / start.elapsed().as_secs_f64();

    // A retention pass, as the station runs hourly (it also refreshes planner statistics).
    let t0 = Utc.with_ymd_and_hms(2026, 3, 1, 0, 0, 0).unwrap();
    store.purge_older_than(t0).await.unwrap();

    // Newest first over everything, then one board by prefix (a twelfth of the rows).
    let mut lat = walk(store, EventQuery::default().with_limit(PAGE_SIZE)).await;
    f.page_p50_ms = percentile(&mut lat, 0.5);
    f.page_p99_ms = percentile(&mut lat, 0.99);
    let mut lat = walk(
        store,
        EventQuery::default()
            .with_point_prefix("ROV07_")
            .with_limit(PAGE_SIZE),
    )
    .await;
    f.filtered_p50_ms = percentile(&mut lat, 0.5);
    f.filtered_p99_ms = percentile(&mut lat, 0.99);
    // The same board by node: an ordered index scan, no sort.
    let mut lat = walk(
        store,
        EventQuery::default()
            .with_node("ROV07")
            .with_limit(PAGE_SIZE),
    )
    .await;
    f.node_p50_ms = percentile(&mut lat, 0.5);
    f.node_p99_ms = percentile(&mut lat, 0.99);
    f
}

async fn postgres_store(url: &str) -> Box<dyn EventStore> {
    let (client, conn) = tokio_postgres::connect(url, tokio_postgres::NoTls)
        .await
        .unwrap();
    tokio::spawn(conn);
    let schema = format!("bench_{}", std::process::id());
    client
        .batch_execute(&format!(
            "DROP SCHEMA IF EXISTS {schema} CASCADE; CREATE SCHEMA {schema}"
        ))
        .await
        .unwrap();
    let sep = if url.contains('?') { '&' } else { '?' };
    open_store(&format!("{url}{sep}options=-c%20search_path%3D{schema}"))
        .await
        .unwrap()
}

fn main() {
    let rt = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .unwrap();
    rt.block_on(async {
        let dir = tempfile::tempdir().unwrap();
        let sqlite = open_store(&format!("sqlite:{}", dir.path().join("bench.db").display()))
            .await
            .unwrap();
        eprintln!("sqlite ...");
        let s = run(&*sqlite).await;
        let p = match std::env::var("STANICE_TEST_POSTGRES_URL") {
            Ok(url) if !url.is_empty() => {
                eprintln!("postgres ...");
                let pg = postgres_store(&url).await;
                Some(run(&*pg).await)
            }
            _ => {
                eprintln!(
                    "PostgreSQL skipped: STANICE_TEST_POSTGRES_URL not set \
                     (run through scripts/with-postgres.sh)"
                );
                None
            }
        };
        println!();
        println!(
            "event store ({} single appends, {} x {} batched, {} pages of {})",
            SINGLE, BATCHES, BATCH, PAGES, PAGE_SIZE
        );
        println!(
            "{:<34} {:>12} {:>12} {:>10}",
            "", "SQLite", "PostgreSQL", "SQLite/PG"
        );
        type Metric = fn(&Figures) -> f64;
        let rows: [(&str, Metric); 8] = [
            ("append, batch of 1 (events/s)", |f| f.single_per_s),
            ("append, batch of 500 (events/s)", |f| f.batch_per_s),
            ("page newest-first p50 (ms)", |f| f.page_p50_ms),
            ("page newest-first p99 (ms)", |f| f.page_p99_ms),
            ("page prefix filter p50 (ms)", |f| f.filtered_p50_ms),
            ("page prefix filter p99 (ms)", |f| f.filtered_p99_ms),
            ("page node filter p50 (ms)", |f| f.node_p50_ms),
            ("page node filter p99 (ms)", |f| f.node_p99_ms),
        ];
        for (name, get) in rows {
            let sv = get(&s);
            match &p {
                Some(p) => {
                    let pv = get(p);
                    println!("{name:<34} {sv:>12.2} {pv:>12.2} {:>10.2}", sv / pv);
                }
                None => println!("{name:<34} {sv:>12.2} {:>12} {:>10}", "-", "-"),
            }
        }
    });
}
