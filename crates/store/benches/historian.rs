//! The historian at volume: event ingestion per second into SQLite and PostgreSQL side by
//! side (batches as the recorder writes them, every event with its idempotent key;
//! PostgreSQL by binary COPY into the day partitions), then, on a large table, the p99 of
//! the event list (a page of the newest events, a page of one point) and of a 60-day
//! trend downsampled in the database.
//!
//! Ingestion is measured twice: as a backfill (200 points, the events spread over the 60
//! days, so each opens a trend minute of its own) and as a live stream (10,000 points
//! changing 300,000 times a second in all: the events of a figure lie within a second, as
//! a live system's do, and share their points' current minutes). The 60-day trend is
//! measured as the fill wrote the rollups and again after the closed days are rewritten
//! in key order, as the retention pass does (PostgreSQL).
//!
//! ```text
//! bash scripts/with-postgres.sh cargo bench -p store --bench historian
//! STANICE_BENCH_EVENTS=100000000 bash scripts/with-postgres.sh cargo bench -p store --bench historian
//! ```
//!
//! `STANICE_BENCH_EVENTS` sets the size of the large table (default 2,000,000: the issue's
//! 100 million take hours and about 30 GB per backend on the 2-core machine); the figure
//! printed says how many events the table held. Without `STANICE_TEST_POSTGRES_URL` only
//! SQLite runs; `STANICE_BENCH_BACKENDS=postgres` (or `sqlite`) runs one backend of the
//! two, for a large table whose other half was measured before. Durability: SQLite WAL
//! with synchronous=NORMAL; the PostgreSQL of
//! `scripts/with-postgres.sh` runs with synchronous_commit=off, fsync on (a crash of the
//! machine may lose the last commits, never consistency).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use chrono::{DateTime, Duration, TimeZone, Utc};
use std::time::Instant;

use store::{
    open_store, EventKey, EventQuery, EventRecord, EventStore, PointValue, TrendMode, TrendQuery,
};

/// Events per append, as today's figure (500) and as the recorder's largest batch.
const BATCHES: [usize; 3] = [500, 1024, 8192];
/// Events written per ingestion figure.
const INGEST_EVENTS: usize = 200_000;
/// The live ingestion: this many points (a regional dispatch's) ...
const LIVE_POINTS: usize = 10_000;
/// ... changing this many times a second in all (the issue's target), so that the event
/// times advance as a live system's do: the whole figure's events within a second or so.
const LIVE_RATE: usize = 300_000;
/// Points of the large table: a trend reads about `events / POINTS` rows.
const POINTS: usize = 200;
/// The large table spans this many days, ending at `end()`.
const DAYS: i64 = 60;
/// Queries per latency figure.
const QUERIES: usize = 100;

fn end() -> DateTime<Utc> {
    Utc.with_ymd_and_hms(2026, 5, 1, 0, 0, 0).unwrap()
}

/// Event `i` of `source` (its key's sequence), of point `p` of `node` at `at`: a boolean,
/// float or integer point by `p`.
fn keyed_event(node: String, p: usize, i: usize, at: DateTime<Utc>, source: &str) -> EventRecord {
    let value = match p % 4 {
        0 => PointValue::Bool(i % 2 == 0),
        1 | 2 => PointValue::Float((i % 1000) as f64 * 0.25),
        _ => PointValue::Int(i as i64),
    };
    let mut e = EventRecord::new(node.clone(), format!("{node}_P{p}"), value, at);
    e.ioa = Some(p as u32);
    e.with_key(EventKey::new(source, i as u64))
}

/// Event `i` of `total`, spread evenly over the last [`DAYS`] days.
fn event(i: usize, total: usize, source: &str) -> EventRecord {
    let span_ms = DAYS * 86_400_000;
    let at = end() - Duration::milliseconds(span_ms)
        + Duration::milliseconds((i as i128 * span_ms as i128 / total.max(1) as i128) as i64);
    let p = i % POINTS;
    keyed_event(format!("ROV{:02}", p % 12), p, i, at, source)
}

/// Event `i` of a live system's stream ([`LIVE_POINTS`] points, [`LIVE_RATE`] events a
/// second in all, starting at `start`).
fn live_event(i: usize, start: DateTime<Utc>, source: &str) -> EventRecord {
    let p = (i * 7919) % LIVE_POINTS; // every point in turn, not in name order
    let at = start + Duration::microseconds((i as i64 * 1_000_000) / LIVE_RATE as i64);
    keyed_event(format!("N{:02}", p % 50), p, i, at, source)
}

fn percentile(samples: &mut [f64], p: f64) -> f64 {
    samples.sort_by(|a, b| a.total_cmp(b));
    let i = ((samples.len() as f64 - 1.0) * p).round() as usize;
    samples[i.min(samples.len() - 1)]
}

#[derive(Default, Clone)]
struct Figures {
    ingest_per_s: Vec<f64>,
    live_ingest_per_s: Vec<f64>,
    table_events: u64,
    fill_per_s: f64,
    newest_p99_ms: f64,
    point_p99_ms: f64,
    trend_p99_ms: f64,
    trend_rows: usize,
    ends_p99_ms: f64,
    trend_written_p99_ms: f64,
    compacted_days: u64,
    compact_s: f64,
}

/// Events per second appending `events` in batches of `batch`.
async fn ingest(store: &dyn EventStore, batch: usize, events: Vec<EventRecord>) -> f64 {
    let start = Instant::now();
    for chunk in events.chunks(batch) {
        store.append_events(chunk).await.unwrap();
    }
    events.len() as f64 / start.elapsed().as_secs_f64()
}

async fn latency<F, Fut>(mut query: F) -> f64
where
    F: FnMut(usize) -> Fut,
    Fut: std::future::Future<Output = ()>,
{
    let mut samples = Vec::with_capacity(QUERIES);
    for i in 0..QUERIES {
        let start = Instant::now();
        query(i).await;
        samples.push(start.elapsed().as_secs_f64() * 1000.0);
    }
    percentile(&mut samples, 0.99)
}

async fn run(store: &dyn EventStore, large: usize) -> Figures {
    let mut f = Figures::default();
    // A backfill (events spread over the 60 days: each opens a minute of its own), then a
    // live stream (a second or so of [`LIVE_RATE`], after the backfill's days).
    for (n, batch) in BATCHES.into_iter().enumerate() {
        let source = format!("ingest-{n}");
        let events = (0..INGEST_EVENTS)
            .map(|i| event(i, INGEST_EVENTS, &source))
            .collect();
        f.ingest_per_s.push(ingest(store, batch, events).await);
        eprintln!(
            "  backfill, batch {batch}: {:.0} events/s",
            f.ingest_per_s[n]
        );
    }
    for (n, batch) in BATCHES.into_iter().enumerate() {
        let (source, start) = (format!("live-{n}"), end() + Duration::hours(n as i64));
        let events = (0..INGEST_EVENTS)
            .map(|i| live_event(i, start, &source))
            .collect();
        f.live_ingest_per_s.push(ingest(store, batch, events).await);
        eprintln!(
            "  live, batch {batch}: {:.0} events/s",
            f.live_ingest_per_s[n]
        );
    }
    // The large table, in the recorder's batches, reported as it grows.
    let start = Instant::now();
    let mut written = 0;
    while written < large {
        let n = (large - written).min(100_000);
        let events: Vec<_> = (written..written + n)
            .map(|i| event(i, large, "large"))
            .collect();
        for chunk in events.chunks(8192) {
            store.append_events(chunk).await.unwrap();
        }
        written += n;
        if written % 1_000_000 < 100_000 {
            eprintln!(
                "  {written} events, {:.0}/s",
                written as f64 / start.elapsed().as_secs_f64()
            );
        }
    }
    f.fill_per_s = large as f64 / start.elapsed().as_secs_f64();
    store
        .purge_older_than(end() - Duration::days(365))
        .await
        .unwrap(); // statistics, as the hourly retention pass refreshes them
    f.table_events = store.stats().await.unwrap().events;

    f.newest_p99_ms = latency(|_| async {
        let page = store
            .query_events(&EventQuery::default().with_limit(100))
            .await
            .unwrap();
        assert_eq!(page.items.len(), 100);
    })
    .await;
    f.point_p99_ms = latency(|i| async move {
        let page = store
            .query_events(
                &EventQuery::default()
                    .with_point(format!("ROV{:02}_P{}", (i % POINTS) % 12, i % POINTS))
                    .with_limit(100),
            )
            .await
            .unwrap();
        assert!(!page.items.is_empty());
    })
    .await;
    // A 60-day trend of a float point, 2,000 buckets (a wide chart's pixel columns).
    let trend = |i: usize, mode: TrendMode| {
        let p = 1 + 4 * (i % (POINTS / 4));
        TrendQuery::new(
            format!("ROV{:02}_P{p}", p % 12),
            end() - Duration::days(DAYS),
            end(),
            2_000,
        )
        .with_mode(mode)
    };
    let aggregated = |i: usize| {
        let q = trend(i, TrendMode::Aggregate);
        async move {
            assert!(!store.query_trend(&q).await.unwrap().is_empty());
        }
    };
    // As written, then with the closed days rewritten in the order trends read them, as
    // the hourly retention pass does (PostgreSQL; nothing to do on SQLite).
    f.trend_written_p99_ms = latency(aggregated).await;
    let start = Instant::now();
    f.compacted_days = store.compact_closed_days(Utc::now()).await.unwrap();
    f.compact_s = start.elapsed().as_secs_f64();
    f.trend_p99_ms = latency(aggregated).await;
    f.trend_rows = store
        .query_trend(&trend(1, TrendMode::Aggregate))
        .await
        .unwrap()
        .len();
    f.ends_p99_ms = latency(|i| {
        let q = trend(i, TrendMode::FirstLast);
        async move {
            assert!(!store.query_trend(&q).await.unwrap().is_empty());
        }
    })
    .await;
    f
}

async fn postgres_store(url: &str) -> Box<dyn EventStore> {
    let (client, conn) = tokio_postgres::connect(url, tokio_postgres::NoTls)
        .await
        .unwrap();
    tokio::spawn(conn);
    let schema = format!("historian_{}", std::process::id());
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
    let large: usize = std::env::var("STANICE_BENCH_EVENTS")
        .ok()
        .and_then(|v| v.replace('_', "").parse().ok())
        .unwrap_or(2_000_000);
    let rt = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .unwrap();
    rt.block_on(async {
        let backends = std::env::var("STANICE_BENCH_BACKENDS")
            .unwrap_or_else(|_| "sqlite,postgres".to_owned());
        let wanted = |name: &str| backends.split(',').any(|b| b.trim() == name);
        let dir = tempfile::tempdir().unwrap();
        let s = if wanted("sqlite") {
            let sqlite = open_store(&format!("sqlite:{}", dir.path().join("bench.db").display()))
                .await
                .unwrap();
            eprintln!("sqlite ...");
            Some(run(&*sqlite, large).await)
        } else {
            None
        };
        let p = match std::env::var("STANICE_TEST_POSTGRES_URL") {
            Ok(_) if !wanted("postgres") => None,
            Ok(url) if !url.is_empty() => {
                eprintln!("postgres ...");
                let pg = postgres_store(&url).await;
                Some(run(&*pg, large).await)
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
            "historian ({INGEST_EVENTS} keyed events per ingestion figure; large table of \
             {large} events over {DAYS} days, {POINTS} points; p99 of {QUERIES} queries)"
        );
        println!("{:<46} {:>14} {:>14}", "", "SQLite", "PostgreSQL");
        type Metric = Box<dyn Fn(&Figures) -> String>;
        let mut rows: Vec<(String, Metric)> = Vec::new();
        for (n, batch) in BATCHES.into_iter().enumerate() {
            rows.push((
                format!("ingest, backfill, batches of {batch} (events/s)"),
                Box::new(move |f| format!("{:.0}", f.ingest_per_s[n])),
            ));
        }
        for (n, batch) in BATCHES.into_iter().enumerate() {
            rows.push((
                format!("ingest, live, batches of {batch} (events/s)"),
                Box::new(move |f| format!("{:.0}", f.live_ingest_per_s[n])),
            ));
        }
        rows.push((
            "large table: events stored".into(),
            Box::new(|f| f.table_events.to_string()),
        ));
        rows.push((
            "large table: filled at (events/s)".into(),
            Box::new(|f| format!("{:.0}", f.fill_per_s)),
        ));
        rows.push((
            "event list, newest page of 100, p99 (ms)".into(),
            Box::new(|f| format!("{:.2}", f.newest_p99_ms)),
        ));
        rows.push((
            "event list, one point's page, p99 (ms)".into(),
            Box::new(|f| format!("{:.2}", f.point_p99_ms)),
        ));
        rows.push((
            "60-day trend min/max/avg as written, p99 (ms)".into(),
            Box::new(|f| format!("{:.2}", f.trend_written_p99_ms)),
        ));
        rows.push((
            "closed days rewritten in key order (days, s)".into(),
            Box::new(|f| format!("{}, {:.1}", f.compacted_days, f.compact_s)),
        ));
        rows.push((
            "60-day trend min/max/avg, p99 (ms)".into(),
            Box::new(|f| format!("{:.2}", f.trend_p99_ms)),
        ));
        rows.push((
            "60-day trend: buckets returned".into(),
            Box::new(|f| f.trend_rows.to_string()),
        ));
        rows.push((
            "60-day trend first/last, p99 (ms)".into(),
            Box::new(|f| format!("{:.2}", f.ends_p99_ms)),
        ));
        for (name, get) in rows {
            let sv = s.as_ref().map_or_else(|| "-".to_owned(), &get);
            let pv = p.as_ref().map_or_else(|| "-".to_owned(), &get);
            println!("{name:<46} {sv:>14} {pv:>14}");
        }
    });
}
