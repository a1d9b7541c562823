//! Trend benchmark: a 60-day trend of one measurement, downsampled in the store, over a
//! store holding a value every 5 s of that measurement and of a second one (two million
//! events), for a chart 1,600 pixels wide. Prints p50/p99 of the downsampled query, both
//! modes (first/last per bucket by index seeks, and min/max/mean, the HMI's default, read
//! from the store's minute rollups), and,
//! for comparison, how long reading the raw rows page by page takes (the HMI's trend
//! before downsampling read at most 20,000 of them).
//!
//! ```text
//! cargo bench -p store --bench trend
//! bash scripts/with-postgres.sh cargo bench -p store --bench trend
//! ```
//!
//! Without `STANICE_TEST_POSTGRES_URL` only SQLite runs (on a temp file, WAL).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use chrono::{Duration, TimeZone, Utc};
use std::time::Instant;

use store::{
    open_store, EventQuery, EventRecord, EventStore, Order, PointValue, TrendMode, TrendQuery,
};

/// One value every this many seconds.
const EVERY_S: i64 = 5;
const DAYS: i64 = 60;
/// The chart's width in pixels: one bucket each.
const BUCKETS: usize = 1_600;
const RUNS: usize = 40;

fn percentile(sorted: &[f64], p: f64) -> f64 {
    let i = ((sorted.len() as f64 - 1.0) * p).round() as usize;
    sorted[i.min(sorted.len() - 1)]
}

async fn fill(store: &dyn EventStore) -> usize {
    let t0 = Utc.with_ymd_and_hms(2026, 1, 1, 0, 0, 0).unwrap();
    let count = (DAYS * 86_400 / EVERY_S) as usize;
    let mut batch = Vec::with_capacity(10_000);
    for i in 0..count {
        let t = t0 + Duration::seconds(i as i64 * EVERY_S);
        let phase = i as f64 / 720.0;
        batch.push(EventRecord::new(
            "RH2",
            "RH2_U",
            PointValue::Float(27_500.0 + 500.0 * phase.sin()),
            t,
        ));
        batch.push(EventRecord::new(
            "RH2",
            "RH2_I",
            PointValue::Float(120.0 + 30.0 * phase.cos()),
            t,
        ));
        if batch.len() >= 10_000 {
            store.append_events(&batch).await.unwrap();
            batch.clear();
        }
    }
    store.append_events(&batch).await.unwrap();
    count
}

async fn run(name: &str, store: Box<dyn EventStore>) {
    let started = Instant::now();
    let count = fill(store.as_ref()).await;
    println!(
        "{name}: filled {} events ({count} per point, one every {EVERY_S} s for {DAYS} days) in {:.1} s",
        count * 2,
        started.elapsed().as_secs_f64()
    );
    let from = Utc.with_ymd_and_hms(2026, 1, 1, 0, 0, 0).unwrap();
    let to = from + Duration::days(DAYS);
    for (mode, runs) in [
        (TrendMode::FirstLast, RUNS),
        (TrendMode::Aggregate, RUNS / 4),
    ] {
        let query = TrendQuery::new("RH2_U", from, to, BUCKETS).with_mode(mode);
        let mut times = Vec::with_capacity(runs);
        let mut buckets = 0;
        for _ in 0..runs {
            let started = Instant::now();
            buckets = store.query_trend(&query).await.unwrap().len();
            times.push(started.elapsed().as_secs_f64() * 1000.0);
        }
        times.sort_by(f64::total_cmp);
        println!(
            "{name}: 60-day trend, {BUCKETS} buckets, {mode:?} ({buckets} returned, {runs} runs): p50 {:.1} ms, p99 {:.1} ms",
            percentile(&times, 0.5),
            percentile(&times, 0.99)
        );
    }
    // Before: every raw row, page by page (what a chart of the raw samples needs).
    let started = Instant::now();
    let mut rows = 0;
    let mut after = None;
    loop {
        let page = store
            .query_events(
                &EventQuery::default()
                    .with_point("RH2_U")
                    .with_range(Some(from), Some(to))
                    .with_order(Order::OldestFirst)
                    .with_limit(10_000)
                    .with_after(after),
            )
            .await
            .unwrap();
        rows += page.items.len();
        after = page.next;
        if after.is_none() {
            break;
        }
    }
    println!(
        "{name}: the same 60 days as raw rows ({rows}), paged: {:.0} ms",
        started.elapsed().as_secs_f64() * 1000.0
    );
    store.close().await.unwrap();
}

#[tokio::main(flavor = "multi_thread", worker_threads = 2)]
async fn main() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("trend.db");
    let sqlite = open_store(&format!("sqlite:{}", path.display()))
        .await
        .unwrap();
    run("SQLite", sqlite).await;
    if let Ok(url) = std::env::var("STANICE_TEST_POSTGRES_URL") {
        let postgres = open_store(&url).await.unwrap();
        run("PostgreSQL", postgres).await;
    }
}
