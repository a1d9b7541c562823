//! A fault on a lift's board until the web HMI's fault archive shows it in the browser,
//! with a fleet of lifts polled by one station node: the issue's "end-to-end latency from
//! a fault in the simulator to the archive and to the browser".
//!
//! ```text
//! cargo bench -p hmi --bench lift_fleet [-- --lifts 200 --faults 200]
//! ```
//!
//! The station runtime runs in this process with `--lifts` simulated EKM66 boards (status
//! every 1 s, the spec's rate), its archive in SQLite; the HMI is connected to it over IEC
//! 104 with the station's store as its archive; a headless Chromium shows the fault
//! archive (`#faults`), which reloads when a lift's `NAME.faults` point changes. A
//! MutationObserver stamps when each lift's row first appears in the table
//! (`performance.timeOrigin + now()`, the same wall clock as the Rust side). Side by side,
//! the same faults until the station has committed them (its archive broadcast).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

#[path = "support/browser.rs"]
mod browser;
use browser::{js, now_ms, report};

use std::collections::HashMap;
use std::time::{Duration, Instant};

use hmi::{Hmi, HmiOptions};
use iec60870::asdu::CommonAddress;
use iec60870::time::TimeZonePolicy;
use station::config::Project;
use station::runtime::{Pacing, Runtime, RuntimeOptions, StoreChoice};
use testkit::projects::{LiftBoard, LiftFleet};

fn arg(name: &str, default: usize) -> usize {
    std::env::args()
        .skip_while(|a| a != name)
        .nth(1)
        .and_then(|n| n.parse().ok())
        .unwrap_or(default)
}

fn main() {
    let lifts = arg("--lifts", 200);
    let faults = arg("--faults", 200).min(lifts);
    // Says SKIPPED without chromium and chromedriver (scripts/install-test-deps.sh).
    if testkit::chromium::browser_available().is_none() {
        return;
    }
    tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .unwrap()
        .block_on(run(lifts, faults));
}

/// The project (one node, `lifts` simulated boards) and the HMI's screens folder for it.
fn project(dir: &std::path::Path, lifts: usize) -> Project {
    let fleet = LiftFleet {
        time_zone: "UTC".to_owned(),
        port_base: testkit::ports::free_port(),
        boards: vec![LiftBoard::Simulated; lifts],
    };
    fleet.write(dir);
    let project = Project::load(dir).unwrap_or_else(|e| panic!("{e}"));
    let screens = dir.join("hmi");
    std::fs::create_dir_all(&screens).unwrap();
    let mut csv = String::from("ioa,type,name,description\n");
    for point in &project.nodes[0].points {
        csv.push_str(&format!(
            "{},{},{},\n",
            point.ioa,
            points_iec::type_id(point.point_type),
            point.name
        ));
    }
    std::fs::write(screens.join("points.csv"), csv).unwrap();
    std::fs::write(screens.join("hmi.toml"), fleet.hmi_toml("Lift fleet")).unwrap();
    let mut users = hmi::users::Users::load(&screens.join("users.toml")).unwrap();
    users.add("bench", 9, "bench-password").unwrap();
    project
}

async fn run(lifts: usize, faults: usize) {
    let dir = tempfile::tempdir().unwrap();
    let project = project(dir.path(), lifts);
    let store = format!("sqlite:{}", dir.path().join("events.sqlite").display());
    let runtime = Runtime::start(
        project,
        RuntimeOptions {
            pacing: Pacing::RealTime { speed: 1.0 },
            store: StoreChoice::Project,
            ..RuntimeOptions::default()
        },
    )
    .await
    .unwrap();
    let server = runtime.nodes()[0].server.as_ref().unwrap().local_addr();
    let hmi = Hmi::start(HmiOptions {
        screens: dir.path().join("hmi"),
        users: dir.path().join("hmi/users.toml"),
        connect: vec![server.to_string()],
        common_address: CommonAddress::new(1),
        listen: "127.0.0.1:0".parse().unwrap(),
        store: None,
        zone: TimeZonePolicy::Utc,
        local_address: None,
        archive: Some(store),
    })
    .await
    .unwrap();
    let url = format!("http://{}", hmi.address);
    let Some((_driver, client)) = browser::start().await else {
        return;
    };
    browser::login(&client, &url, "bench", "bench-password").await;
    client.goto(&format!("{url}/#faults")).await.unwrap();
    // Every lift answering, the archive page loaded (and empty).
    let started = Instant::now();
    while runtime.nodes()[0]
        .lifts
        .iter()
        .any(|lift| lift.counts().status_replies() == 0)
    {
        assert!(
            started.elapsed() < Duration::from_secs(60),
            "not every lift answers"
        );
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
    loop {
        let loaded = js(
            &client,
            "!!(document.getElementById('page-faults') || {dataset: {}}).dataset.loaded",
        )
        .await;
        if loaded.as_bool() == Some(true) {
            break;
        }
        assert!(
            started.elapsed() < Duration::from_secs(60),
            "the archive page does not load"
        );
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
    js(
        &client,
        "(() => { window.__seen = {}; const body = document.querySelector('#fault-table tbody');\
         new MutationObserver(() => { const t = performance.timeOrigin + performance.now();\
           for (const row of body.querySelectorAll('tr[data-lift]')) {\
             const lift = row.getAttribute('data-lift'); if (!(lift in window.__seen)) window.__seen[lift] = t; } })\
         .observe(body, {childList: true}); return true; })()",
    )
    .await;
    println!(
        "{lifts} simulated lifts on one node (status every 1 s); the HMI's fault archive in Chromium"
    );

    // One fault on each of `faults` lifts, 100 ms apart.
    let mut archived = runtime.archived_faults();
    let mut injected: HashMap<String, f64> = HashMap::new();
    let mut committed: HashMap<String, f64> = HashMap::new();
    let handles = runtime.nodes()[0].lifts.clone();
    let mut next = 0;
    let mut tick = tokio::time::interval(Duration::from_millis(100));
    let deadline = Instant::now() + Duration::from_secs(60 + faults as u64 / 5);
    while committed.len() < faults && Instant::now() < deadline {
        tokio::select! {
            _ = tick.tick(), if next < faults => {
                let lift = &handles[next];
                injected.insert(lift.name().to_owned(), now_ms());
                lift.operate(&["fault", "3C"]).await.unwrap();
                next += 1;
            }
            record = archived.recv() => {
                let record = record.unwrap();
                committed.entry(record.lift.clone()).or_insert_with(now_ms);
            }
        }
    }
    // The last rows reach the page after their commit.
    let mut seen = serde_json::Map::new();
    let wait = Instant::now();
    while seen.len() < faults && wait.elapsed() < Duration::from_secs(20) {
        seen = js(&client, "window.__seen")
            .await
            .as_object()
            .cloned()
            .unwrap_or_default();
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    let to_archive: Vec<f64> = injected
        .iter()
        .filter_map(|(lift, t0)| committed.get(lift).map(|t| t - t0))
        .collect();
    let to_browser: Vec<f64> = injected
        .iter()
        .filter_map(|(lift, t0)| seen.get(lift).and_then(|t| t.as_f64()).map(|t| t - t0))
        .collect();
    report("fault on the board -> archived (SQLite commit)", to_archive);
    report(
        "fault on the board -> row in the browser's archive table",
        to_browser,
    );
    println!(
        "(a fault is read in the poll cycle after it happens: the 1 s status period is most of it)"
    );
    let _ = client.close().await;
    hmi.shutdown().await;
    runtime.shutdown().await;
}
