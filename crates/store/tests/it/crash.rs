//! Crash tests: a writer process appends a source's numbered events and acknowledges them
//! to the source (a file) only now and then, as a source that acknowledges lazily does; it
//! is killed with SIGKILL right after a commit it had not acknowledged yet, restarted (it
//! resumes from the last acknowledgement, so it writes again events already stored), killed
//! again, and finally runs to the end. Then the store must hold every sequence number of
//! the source exactly once: none lost, none twice. On SQLite and on PostgreSQL.
//!
//! The writer is this test binary itself, started with the ignored test
//! `crash::writer_process` and the environment below.

use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use chrono::{TimeZone, Utc};
use store::{open_store, EventKey, EventRecord, PointValue};

use crate::pg::{admin, postgres_schema, postgres_url};

/// Events of the source.
const TOTAL: u64 = 40_000;
/// Events per append.
const BATCH: u64 = 500;
/// The writer acknowledges every this many batches.
const ACK_EVERY: u64 = 4;
/// The source's identity.
const SOURCE: &str = "crash-test-source";
/// After how many commits of a run the writer is killed, one run each.
const KILL_AFTER: [u64; 3] = [3, 9, 6];

/// The writer: resumes from the acknowledgement file and appends the rest. Runs only as
/// the child of the crash tests (it is ignored otherwise).
#[test]
#[ignore = "the writer process of the crash tests, started by them"]
fn writer_process() {
    let (Ok(url), Ok(ack_file)) = (
        std::env::var("STANICE_CRASH_STORE"),
        std::env::var("STANICE_CRASH_ACK"),
    ) else {
        eprintln!("crash::writer_process is the crash tests' child, not a test by itself");
        return;
    };
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .unwrap();
    rt.block_on(async {
        let store = open_store(&url).await.unwrap();
        let mut acked: u64 = std::fs::read_to_string(&ack_file)
            .ok()
            .and_then(|s| s.trim().parse().ok())
            .unwrap_or(0);
        println!("RESUME {acked}");
        let t0 = Utc.with_ymd_and_hms(2026, 3, 1, 0, 0, 0).unwrap();
        let mut next = acked;
        let mut batches = 0u64;
        while next < TOTAL {
            let end = (next + BATCH).min(TOTAL);
            let events: Vec<EventRecord> = (next..end)
                .map(|seq| {
                    EventRecord::new(
                        "RH2",
                        format!("P{}", seq % 50),
                        PointValue::Int(seq as i64),
                        // Across two days: the PostgreSQL side meets a day boundary.
                        t0 + chrono::Duration::seconds(seq as i64 * 4),
                    )
                    .with_key(EventKey::new(SOURCE, seq))
                })
                .collect();
            store.append_events(&events).await.unwrap();
            next = end;
            batches += 1;
            println!("STORED {next}");
            if batches % ACK_EVERY == 0 || next == TOTAL {
                let tmp = format!("{ack_file}.tmp");
                std::fs::write(&tmp, next.to_string()).unwrap();
                std::fs::rename(&tmp, &ack_file).unwrap();
                acked = next;
                println!("ACKED {acked}");
            }
        }
        store.close().await.unwrap();
        println!("DONE {acked}");
    });
}

/// Starts the writer; when `kill_after` is given, kills it (SIGKILL) right after that
/// many commits of this run once it has one not acknowledged; returns what it reported
/// (its resume point, and whether it finished).
fn run_writer(url: &str, ack: &Path, kill_after: Option<u64>) -> (u64, bool) {
    let mut child = Command::new(std::env::current_exe().unwrap())
        .args([
            "--exact",
            "crash::writer_process",
            "--ignored",
            "--nocapture",
            "--test-threads=1",
        ])
        .env("STANICE_CRASH_STORE", url)
        .env("STANICE_CRASH_ACK", ack)
        .stdout(Stdio::piped())
        .stderr(Stdio::inherit())
        .spawn()
        .unwrap();
    let stdout = child.stdout.take().unwrap();
    let deadline = Instant::now() + Duration::from_secs(300);
    let (mut resumed, mut done, mut commits) = (None, false, 0);
    for line in BufReader::new(stdout).lines() {
        assert!(Instant::now() < deadline, "the writer takes too long");
        let Ok(line) = line else { break };
        // The first report follows libtest's "test ... " on the same line.
        let words: Vec<&str> = line.split_whitespace().collect();
        let (word, n) = match words.as_slice() {
            [.., word, n] => (*word, n.parse::<u64>().ok()),
            _ => ("", None),
        };
        match (word, n) {
            ("RESUME", Some(n)) => resumed = Some(n),
            ("STORED", Some(n)) => {
                commits += 1;
                // Killed right after a commit that is not acknowledged yet.
                if kill_after.is_some_and(|k| commits >= k) && n % (BATCH * ACK_EVERY) != 0 {
                    child.kill().unwrap();
                    break;
                }
            }
            ("DONE", Some(_)) => done = true,
            _ => {}
        }
    }
    let status = child.wait().unwrap();
    if kill_after.is_none() {
        assert!(
            status.success() && done,
            "the last run must finish: {status}"
        );
    }
    (resumed.expect("the writer started"), done)
}

/// Kills the writer three times mid-ingestion, then lets it finish; `stored` counts the
/// source's events in the store. Checks each restart had to write again what was stored.
fn kill_and_restart(url: &str, dir: &Path, stored: &dyn Fn() -> u64) {
    let ack = dir.join("ack");
    for kill_after in KILL_AFTER {
        let before = stored();
        let (resumed, done) = run_writer(url, &ack, Some(kill_after));
        assert!(!done, "killed before the end");
        assert!(
            resumed <= before,
            "resumed at {resumed} with {before} stored"
        );
        // The kill came after a commit not yet acknowledged: the next run writes again
        // events already stored.
        let acked: u64 = std::fs::read_to_string(&ack)
            .map(|s| s.trim().parse().unwrap())
            .unwrap_or(0);
        assert!(stored() > acked, "stored {} acked {acked}", stored());
    }
    let (resumed, done) = run_writer(url, &ack, None);
    assert!(done);
    assert!(resumed < TOTAL);
}

/// (rows, distinct sequence numbers, lowest, highest) of the source's events.
type Tally = (i64, i64, i64, i64);

/// The tally of the store at `url`, read through the store itself (the events are packed
/// in blocks): every event in time order, those of the test's source counted.
fn tally_of(url: &str) -> Tally {
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .unwrap();
    rt.block_on(async {
        let store = open_store(url).await.unwrap();
        let query = store::EventQuery::default()
            .with_order(store::Order::OldestFirst)
            .with_limit(10_000);
        let events = crate::suite::all_events(&*store, query).await;
        let seqs: Vec<i64> = events
            .iter()
            .filter_map(|e| e.key.as_ref())
            .filter(|k| k.source == "crash-test-source")
            .map(|k| k.sequence as i64)
            .collect();
        let distinct: std::collections::BTreeSet<i64> = seqs.iter().copied().collect();
        (
            seqs.len() as i64,
            distinct.len() as i64,
            distinct.first().copied().unwrap_or(-1),
            distinct.last().copied().unwrap_or(-1),
        )
    })
}

fn check(tally: Tally) {
    let total = TOTAL as i64;
    assert_eq!(
        tally,
        (total, total, 0, total - 1),
        "(rows, distinct, min, max)"
    );
}

#[test]
fn sqlite_kill_9_during_ingestion_loses_and_duplicates_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("events.db");
    let url = format!("sqlite:{}", path.display());
    let tally = || -> Tally {
        if path.exists() {
            tally_of(&url)
        } else {
            (0, 0, -1, -1)
        }
    };
    kill_and_restart(&url, dir.path(), &|| tally().0 as u64);
    check(tally());
}

#[test]
fn postgres_kill_9_during_ingestion_loses_and_duplicates_nothing() {
    let Some(server) = postgres_url("postgres_kill_9_during_ingestion") else {
        return;
    };
    let rt = tokio::runtime::Runtime::new().unwrap();
    let (schema, url) = rt.block_on(postgres_schema(&server, "crash"));
    let client = rt.block_on(admin(&server)).unwrap();
    let tally = || tally_of(&url);
    let dir = tempfile::tempdir().unwrap();
    kill_and_restart(&url, dir.path(), &|| tally().0 as u64);
    check(tally());
    rt.block_on(client.batch_execute(&format!("DROP SCHEMA {schema} CASCADE")))
        .unwrap();
}
