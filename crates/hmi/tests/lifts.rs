//! The lift screens (docs/HMI.md, "Lift screens"): their HTTP API against a fault archive
//! written straight into a store (paging, sorting, filters, CSV, levels, bad input), and in
//! a real browser against the station runtime in this process watching three simulated
//! EKM66 boards, with the HMI reading the station's own store.
//!
//! The browser part needs chromedriver and Chromium (`scripts/install-test-deps.sh`); it
//! says SKIPPED and passes without them, unless `STANICE_REQUIRE_PEERS=1`.

#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing,
    missing_docs
)]

#[path = "support/chromium.rs"]
mod chromium;
#[path = "support/http.rs"]
mod http;
use chromium::{browser_available, js, until, Driver};
use http::{request, Reply};

use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use chrono::{NaiveDate, TimeDelta, Utc};
use fantoccini::Client;
use hmi::{Hmi, HmiOptions};
use iec60870::time::TimeZonePolicy;
use serde_json::{json, Value};
use station::config::Project;
use station::runtime::{Pacing, Runtime, RuntimeOptions, StoreChoice};
use store::LiftFaultRecord;
use testkit::ports::free_port_range;

fn fleet_points() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/lift-fleet/hmi/points.csv")
}

/// A screens folder: `points` as points.csv, one small mimic (so the first screen is not
/// the fleet list), lifts L1..L3 and the users Servis1 (level 9, starts on the fleet
/// list), tech (level 3) and viewer (level 0).
fn screens(dir: &Path, points: &str) {
    std::fs::write(dir.join("points.csv"), points).unwrap();
    std::fs::write(
        dir.join("hmi.toml"),
        r#"title = "Lift test"
[[screen]]
id = "overview"
title = "Overview"
file = "overview.svg"

[lift_levels]
export = 3
figures = 3

[[lift]]
name = "L1"
description = "Nádražní 12 <b>passenger</b>"
floors = 4

[[lift]]
name = "L2"
description = "Nádražní 14"
floors = 6

[[lift]]
name = "L3"
description = "Hospital"
floors = 3
"#,
    )
    .unwrap();
    std::fs::write(
        dir.join("overview.svg"),
        r#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 100 50"><text x="5" y="20">overview</text></svg>"#,
    )
    .unwrap();
    let mut users = hmi::users::Users::load(&dir.join("users.toml")).unwrap();
    users.add("Servis1", 9, "servis1-pass").unwrap();
    users.set_start("Servis1", Some("lifts")).unwrap();
    users.add("tech", 3, "tech-pass").unwrap();
    users.add("viewer", 0, "viewer-pass").unwrap();
}

// ---------------------------------------------------------------------------- HTTP

/// A request with the session cookie (none when empty).
async fn http(address: SocketAddr, method: &str, path: &str, cookie: &str, body: &str) -> Reply {
    let headers: Vec<(&str, &str)> = if cookie.is_empty() {
        Vec::new()
    } else {
        vec![("Cookie", cookie)]
    };
    request(address, method, path, &headers, body).await
}

async fn login(address: SocketAddr, user: &str, password: &str) -> String {
    let reply = http(
        address,
        "POST",
        "/api/login",
        "",
        &json!({"username": user, "password": password}).to_string(),
    )
    .await;
    assert_eq!(reply.status, 200, "{}", reply.body);
    reply
        .header("set-cookie")
        .unwrap()
        .split(';')
        .next()
        .unwrap()
        .to_owned()
}

// ---------------------------------------------------------------------------- API tests

fn record(lift: &str, index: u8, code: u8, minute: u32) -> LiftFaultRecord {
    LiftFaultRecord {
        id: None,
        node: "LIFTS".into(),
        lift: lift.into(),
        stack_index: index,
        code,
        floor: index % 4 + 1,
        target: 0,
        board_time: NaiveDate::from_ymd_opt(2025, 3, 1)
            .unwrap()
            .and_hms_opt(8, minute, 0),
        received_time: Utc::now() - TimeDelta::minutes(i64::from(60 - minute)),
    }
}

/// The example's screens folder loads: six lifts, the levels, users with start screens.
#[test]
fn lift_fleet_example_screens_load() {
    let folder = fleet_points().parent().unwrap().to_path_buf();
    let config = hmi::config::HmiConfig::load(&folder).unwrap();
    assert_eq!(config.lifts.len(), 6);
    assert_eq!(config.lift_levels.export, 3);
    let users = hmi::users::Users::load(&folder.join("users.toml")).unwrap();
    assert_eq!(users.start("Servis1"), Some("lifts"));
    assert_eq!(users.list().count(), 3);
    // points.csv is what `stanice points examples/lift-fleet` prints (ioa, type, name).
    let project = Project::load(&folder.join("..")).unwrap_or_else(|e| panic!("{:?}", e.errors()));
    let mut served: Vec<(u32, String, String)> = project
        .top_node()
        .unwrap()
        .points
        .iter()
        .map(|p| {
            (
                p.ioa.get(),
                points_iec::type_id(p.point_type).to_string(),
                p.name.clone(),
            )
        })
        .collect();
    served.sort();
    let mut listed: Vec<(u32, String, String)> = config
        .points
        .iter()
        .map(|p| (p.ioa, p.type_id.to_string(), p.name.clone()))
        .collect();
    listed.sort();
    assert_eq!(
        listed, served,
        "regenerate examples/lift-fleet/hmi/points.csv"
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn archive_api_pages_sorts_filters_and_exports() {
    let dir = tempfile::tempdir().unwrap();
    screens(
        dir.path(),
        &std::fs::read_to_string(fleet_points()).unwrap(),
    );
    let archive_url = format!("sqlite:{}", dir.path().join("station.sqlite").display());
    {
        let store = store::open_store(&archive_url).await.unwrap();
        // 30 faults of L1 (door faults and "faulty signal" ones), 5 of L2, one of L2
        // without a board time.
        let mut records = Vec::new();
        for i in 0..30u8 {
            let code = if i % 3 == 0 { 0x3C } else { 0x20 + i % 10 };
            records.push(record("L1", i, code, u32::from(i)));
        }
        for i in 0..5u8 {
            records.push(record("L2", i, 0x11, 40 + u32::from(i)));
        }
        let mut impossible = record("L2", 9, 0x05, 50);
        impossible.board_time = None;
        records.push(impossible);
        store.append_lift_faults(&records).await.unwrap();
        // What the station's notifier recorded: a mail sent for L1, one suppressed, a
        // webhook that failed for L2.
        for (minute, lift, channel, outcome) in [
            (1, "L1", "email", store::NotificationOutcome::Sent),
            (2, "L1", "email", store::NotificationOutcome::Suppressed),
            (3, "L2", "webhook", store::NotificationOutcome::Failed),
        ] {
            store
                .append_notification(&store::NotificationRecord {
                    id: None,
                    time: Utc::now() - TimeDelta::minutes(10 - minute),
                    rule: "door faults".into(),
                    channel: channel.into(),
                    recipient: "novak@example.cz".into(),
                    source: lift.into(),
                    subject: format!("[{lift}] fault 0x3C Door fault"),
                    outcome,
                    detail: "250 OK".into(),
                })
                .await
                .unwrap();
        }
    }
    let start = |archive: Option<String>| {
        let dir = dir.path().to_path_buf();
        async move {
            Hmi::start(HmiOptions {
                screens: dir.clone(),
                users: dir.join("users.toml"),
                // No station: the link stays down, the archive does not need it.
                connect: vec!["127.0.0.1:9".into()],
                common_address: iec60870::asdu::CommonAddress::new(1),
                listen: "127.0.0.1:0".parse().unwrap(),
                store: None,
                archive,
                zone: TimeZonePolicy::Zone(chrono_tz::Europe::Prague),
                local_address: None,
            })
            .await
            .unwrap()
        }
    };
    let hmi = start(Some(archive_url.clone())).await;
    let address = hmi.address;
    let servis = login(address, "Servis1", "servis1-pass").await;
    let viewer = login(address, "viewer", "viewer-pass").await;
    let get = |cookie: &str, path: &str| {
        let cookie = cookie.to_owned();
        let path = path.to_owned();
        async move { http(address, "GET", &path, &cookie, "").await }
    };

    // The session tells the start screen; the fleet its lifts and levels.
    let session = get(&servis, "/api/session").await.json();
    assert_eq!(session["start"], json!("lifts"));
    assert_eq!(
        get(&viewer, "/api/session").await.json()["start"],
        Value::Null
    );
    let fleet = get(&servis, "/api/lifts").await.json();
    assert_eq!(fleet["lifts"].as_array().unwrap().len(), 3);
    assert_eq!(
        fleet["lifts"][0]["description"],
        json!("Nádražní 12 <b>passenger</b>")
    );
    assert_eq!(fleet["levels"]["export"], json!(3));
    assert_eq!(fleet["archive"], json!(true));
    assert_eq!(fleet["allowed"]["export"], json!(true));
    assert!(fleet["statuses"].as_array().unwrap().len() > 50);
    let viewer_fleet = get(&viewer, "/api/lifts").await.json();
    assert_eq!(viewer_fleet["allowed"]["export"], json!(false));
    assert_eq!(viewer_fleet["allowed"]["archive"], json!(true));

    // Paging: 36 rows, 10 a page, newest board time first.
    let page = get(&servis, "/api/lifts/faults?limit=10").await.json();
    assert_eq!(page["total"], json!(36));
    assert_eq!(page["rows"].as_array().unwrap().len(), 10);
    let last = get(&servis, "/api/lifts/faults?limit=10&offset=30")
        .await
        .json();
    assert_eq!(last["rows"].as_array().unwrap().len(), 6);
    // Every row once over all pages.
    let mut ids = std::collections::HashSet::new();
    for offset in [0, 10, 20, 30] {
        let rows = get(
            &servis,
            &format!("/api/lifts/faults?limit=10&offset={offset}"),
        )
        .await
        .json();
        for row in rows["rows"].as_array().unwrap() {
            assert!(ids.insert(row["id"].as_str().unwrap().to_owned()));
        }
    }
    assert_eq!(ids.len(), 36);
    let row = &page["rows"][0];
    for key in [
        "date", "time", "hex", "english", "czech", "floor", "target", "received", "lift",
    ] {
        assert!(row.get(key).is_some(), "{key} missing in {row}");
    }

    // Sorting by code, both ways.
    let ascending = get(&servis, "/api/lifts/faults?sort=code&desc=false&limit=1000")
        .await
        .json();
    let codes: Vec<u64> = ascending["rows"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["code"].as_u64().unwrap())
        .collect();
    assert!(codes.windows(2).all(|w| w[0] <= w[1]), "{codes:?}");
    assert_eq!(ascending["rows"][0]["hex"], json!("05"));
    let descending = get(&servis, "/api/lifts/faults?sort=code&desc=true&limit=1")
        .await
        .json();
    assert_eq!(descending["rows"][0]["hex"], json!("3C"));

    // Filters: lift, code, an English word, a Czech word (with and without accents),
    // the date range.
    let l2 = get(&servis, "/api/lifts/faults?lift=L2").await.json();
    assert_eq!(l2["total"], json!(6));
    let door = get(&servis, "/api/lifts/faults?q=door").await.json();
    assert_eq!(door["total"], json!(10));
    assert!(door["rows"]
        .as_array()
        .unwrap()
        .iter()
        .all(|r| r["hex"] == json!("3C")));
    let czech = get(&servis, "/api/lifts/faults?q=sign%C3%A1l&lift=L1&lang=cs")
        .await
        .json();
    assert_eq!(czech["total"], json!(20));
    assert!(czech["rows"][0]["text"]
        .as_str()
        .unwrap()
        .starts_with("Chybn"));
    let dvere = get(&servis, "/api/lifts/faults?q=DVE%C5%98I").await.json();
    assert_eq!(dvere["total"], json!(10));
    let nothing = get(&servis, "/api/lifts/faults?q=zzzz-nothing")
        .await
        .json();
    assert_eq!(nothing["total"], json!(0));
    let code = get(&servis, "/api/lifts/faults?code=3c,11").await.json();
    assert_eq!(code["total"], json!(15));
    let range = get(
        &servis,
        "/api/lifts/faults?since=2025-03-01T08:10&until=2025-03-01T08:20",
    )
    .await
    .json();
    assert_eq!(range["total"], json!(10));
    let day = get(
        &servis,
        "/api/lifts/faults?since=2025-03-01&until=2025-03-01",
    )
    .await
    .json();
    assert_eq!(day["total"], json!(35));

    // CSV: header, both texts, every matching row, an attachment.
    let csv = get(&servis, "/api/lifts/faults.csv?lift=L1&q=door").await;
    assert_eq!(csv.status, 200, "{}", csv.body);
    assert!(csv.header("content-type").unwrap().starts_with("text/csv"));
    assert!(csv
        .header("content-disposition")
        .unwrap()
        .starts_with("attachment"));
    let mut lines = csv.body.trim_start_matches('\u{feff}').lines();
    assert_eq!(
        lines.next().unwrap(),
        "date,time,lift,code,english,czech,floor,target,received,index"
    );
    let rows: Vec<&str> = lines.collect();
    assert_eq!(rows.len(), 10);
    assert!(
        rows[0].starts_with("2025-03-01,08:27:00,L1,3C,Door fault,Porucha dveří,"),
        "{}",
        rows[0]
    );

    // Levels: the viewer reads the archive but gets no export and no figures.
    assert_eq!(get(&viewer, "/api/lifts/faults").await.status, 200);
    let refused = get(&viewer, "/api/lifts/faults.csv").await;
    assert_eq!(refused.status, 403, "{}", refused.body);
    assert!(refused.json()["error"].as_str().unwrap().contains("export"));
    assert_eq!(get(&viewer, "/api/lifts/figures").await.status, 403);

    // The record of notifications: newest first, by lift, level 3.
    let sent = get(&servis, "/api/lifts/notifications").await.json();
    assert_eq!(sent["total"], json!(3));
    assert_eq!(sent["rows"][0]["lift"], json!("L2"));
    assert_eq!(sent["rows"][0]["outcome"], json!("failed"));
    assert_eq!(sent["rows"][2]["outcome"], json!("sent"));
    let l1 = get(&servis, "/api/lifts/notifications?lift=L1&limit=1")
        .await
        .json();
    assert_eq!(l1["total"], json!(2));
    assert_eq!(l1["rows"].as_array().unwrap().len(), 1);
    assert_eq!(l1["rows"][0]["outcome"], json!("suppressed"));
    assert_eq!(get(&viewer, "/api/lifts/notifications").await.status, 403);
    for bad in ["lift=L9", "limit=0", "offset=-1", "nope=1"] {
        let reply = get(&servis, &format!("/api/lifts/notifications?{bad}")).await;
        assert_eq!(reply.status, 400, "{bad}: {}", reply.body);
    }
    assert_eq!(get("", "/api/lifts/faults").await.status, 401);

    // Figures: no history in this store, yet an answer for the fleet and each lift.
    let figures = get(&servis, "/api/lifts/figures?days=365").await.json();
    assert_eq!(figures["lifts"].as_array().unwrap().len(), 3);
    assert_eq!(figures["fleet"]["lifts"], json!(3));
    let one = get(&servis, "/api/lifts/L2/figures?days=30").await;
    assert_eq!(one.status, 200, "{}", one.body);
    assert_eq!(one.json()["name"], json!("L2"));
    assert_eq!(get(&servis, "/api/lifts/L9/figures").await.status, 404);

    // Bad input: a typed 400 naming the parameter, never a panic.
    for (query, parameter) in [
        ("limit=0", "limit"),
        ("limit=100000", "limit"),
        ("limit=-1", "limit"),
        ("offset=x", "offset"),
        ("sort=password", "sort"),
        ("desc=maybe", "desc"),
        ("code=3G", "code"),
        ("code=100", "code"),
        ("lift=L9", "lift"),
        ("since=2025-13-01", "since"),
        ("since=2025-03-02&until=2025-03-01", "until"),
        ("lang=de", "lang"),
    ] {
        let reply = get(&servis, &format!("/api/lifts/faults?{query}")).await;
        assert_eq!(reply.status, 400, "{query}: {}", reply.body);
        assert!(
            reply.json()["error"].as_str().unwrap().contains(parameter),
            "{query}: {}",
            reply.body
        );
    }
    let long = "x".repeat(101);
    assert_eq!(
        get(&servis, &format!("/api/lifts/faults?q={long}"))
            .await
            .status,
        400
    );
    assert_eq!(get(&servis, "/api/lifts/faults?nope=1").await.status, 400);
    for days in ["0", "3661", "x", "-5"] {
        assert_eq!(
            get(&servis, &format!("/api/lifts/figures?days={days}"))
                .await
                .status,
            400,
            "days={days}"
        );
    }
    hmi.shutdown().await;

    // Without the station's store: the lift screens say so, the archive is 404.
    let hmi = start(None).await;
    let servis = login(hmi.address, "Servis1", "servis1-pass").await;
    let fleet = http(hmi.address, "GET", "/api/lifts", &servis, "")
        .await
        .json();
    assert_eq!(fleet["archive"], json!(false));
    let none = http(hmi.address, "GET", "/api/lifts/faults", &servis, "").await;
    assert_eq!(none.status, 404);
    assert!(none.json()["error"]
        .as_str()
        .unwrap()
        .contains("no archive"));
    hmi.shutdown().await;
}

// ---------------------------------------------------------------------------- browser

async fn log_in(client: &Client, url: &str, user: &str, password: &str) {
    client.goto(&format!("{url}/login")).await.unwrap();
    until(
        client,
        "document.getElementById('login-form')",
        "the login page",
    )
    .await;
    let script = format!(
        "document.getElementById('username').value = {user:?}; \
         document.getElementById('password').value = {password:?}; \
         document.getElementById('login-button').click();"
    );
    client.execute(&script, Vec::new()).await.unwrap();
    until(
        client,
        "location.pathname === '/' && document.body.dataset.ready === 'true' && HMI.wsOpen",
        "the application",
    )
    .await;
}

async fn go(client: &Client, hash: &str) {
    client
        .execute(&format!("location.hash = {hash:?};"), Vec::new())
        .await
        .unwrap();
}

/// The station runtime of `project` and an HMI on the screens folder `screens` (its
/// users.toml) connected to its top node, with the station's store as its archive.
async fn start_station_and_hmi(project: Project, screens: &Path) -> (Runtime, Hmi) {
    let archive_url = project.station.store.clone();
    let top = project.top_node().unwrap().clone();
    let runtime = Runtime::start(
        project,
        RuntimeOptions {
            nodes: Vec::new(),
            pacing: Pacing::RealTime { speed: 1.0 },
            start: Utc::now(),
            store: StoreChoice::Project,
            device_kinds: station::device::DeviceKinds::builtin(),
        },
    )
    .await
    .unwrap();
    let server = runtime
        .node(&top.name)
        .and_then(|node| node.server.as_ref())
        .unwrap()
        .local_addr();
    let hmi = Hmi::start(HmiOptions {
        screens: screens.to_path_buf(),
        users: screens.join("users.toml"),
        connect: vec![server.to_string()],
        common_address: top.common_address,
        listen: "127.0.0.1:0".parse().unwrap(),
        store: None,
        archive: Some(archive_url),
        zone: TimeZonePolicy::Zone(chrono_tz::Europe::Prague),
        local_address: None,
    })
    .await
    .unwrap();
    (runtime, hmi)
}

const PROJECT: &str = r#"
[station]
name = "Lift test"
time_zone = "Europe/Prague"
store = "sqlite:events.sqlite"
port_base = 2414
bind = "127.0.0.1"

[[node]]
name = "LIFTS"
description = "three simulated boards"
common_address = 1

[node.server]
port_offset = 0

[[node.lift]]
name = "L1"
description = "Nádražní 12"
floors = 4
ioa_base = 1000
simulate = "ekm66"
poll_period_ms = 100
timeout_ms = 200
fault_stack = 32
fault_probability = 0.0

[[node.lift]]
name = "L2"
description = "Nádražní 14"
floors = 6
ioa_base = 1100
simulate = "ekm66"
poll_period_ms = 100
timeout_ms = 200
fault_probability = 0.0

[[node.lift]]
name = "L3"
description = "Hospital"
floors = 3
ioa_base = 1200
simulate = "ekm66"
poll_period_ms = 100
timeout_ms = 200
fault_probability = 0.0
"#;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn lift_screens_in_a_real_browser() {
    let Some((driver, chromium)) = browser_available() else {
        return;
    };
    let started = Instant::now();
    let project_dir = tempfile::tempdir().unwrap();
    std::fs::write(project_dir.path().join("station.toml"), PROJECT).unwrap();
    let project = Project::load(project_dir.path())
        .unwrap_or_else(|e| panic!("{:?}", e.errors()))
        .with_port_base(free_port_range(3));
    let top = project.top_node().unwrap().clone();
    let mut csv = String::from("ioa,type,name,description\n");
    for p in &top.points {
        csv.push_str(&format!(
            "{},{},{},\"{}\"\n",
            p.ioa,
            points_iec::type_id(p.point_type),
            p.name,
            p.description
        ));
    }
    let screens_dir = tempfile::tempdir().unwrap();
    screens(screens_dir.path(), &csv);
    let (runtime, hmi) = start_station_and_hmi(project, screens_dir.path()).await;
    let url = format!("http://{}", hmi.address);
    let driver = Driver::start(&driver, chromium);
    let client = driver.session(1280, 900).await;
    let mut timings = Vec::new();

    // --- Servis1 starts on the fleet list: every lift with its status colour.
    log_in(&client, &url, "Servis1", "servis1-pass").await;
    assert_eq!(
        js(&client, "document.body.dataset.current").await,
        json!("lifts")
    );
    let took = until(
        &client,
        "['L1','L2','L3'].every(n => { const r = document.querySelector(`#lift-table tr[data-lift=\"${n}\"]`); \
         return r && ['green','orange','red'].includes(r.dataset.class) && !r.querySelector('[data-invalid]'); })",
        "every lift with a colour class",
    )
    .await;
    timings.push(("fleet list coloured", took));
    // The description is text, not markup.
    assert_eq!(
        js(&client, "document.querySelector('#lift-table tr[data-lift=\"L1\"] td:nth-child(2)').textContent").await,
        json!("Nádražní 12 <b>passenger</b>")
    );
    assert_eq!(
        js(&client, "document.querySelectorAll('#lift-table b').length").await,
        json!(0)
    );

    // --- A cut cable: L2's communication alarm.
    runtime.operate("lift L2 silent").await.unwrap();
    let took = until(
        &client,
        "document.querySelector('#lift-table tr[data-lift=\"L2\"] td.comm[data-alarm=\"true\"]')",
        "L2 not answering",
    )
    .await;
    timings.push(("comm alarm shown", took));
    // The filter by communication alarm keeps only L2.
    client
        .execute(
            "const f = document.getElementById('lift-filter'); f.comm.checked = true; f.dispatchEvent(new Event('input'));",
            Vec::new(),
        )
        .await
        .unwrap();
    until(
        &client,
        "[...document.querySelectorAll('#lift-table tbody tr')].map(r => r.dataset.lift).join() === 'L2'",
        "only L2 with the communication filter",
    )
    .await;

    // --- The lift view: doors and floor as the points say.
    go(&client, "#lift/L1").await;
    until(
        &client,
        "(() => { const door = HMI.points.get('L1.door').value; const floor = HMI.points.get('L1.position').value; \
          const keys = ['unknown','closed','partly-open','open','fault']; \
          return document.getElementById('lift-car').dataset.door === keys[door] \
              && document.getElementById('lift-floor').textContent === String(floor) \
              && document.querySelectorAll('#lift-panel .cop-button[data-floor]').length === 4 \
              && document.querySelectorAll('#lift-trips .bar-row').length === 4 \
              && ['green','orange','red'].includes(document.getElementById('lift-status').dataset.class); })()",
        "the lift view with its doors, floor, panel and trips",
    )
    .await;

    // --- A fault on L1 appears in the archive by itself (L1.faults over the WebSocket).
    go(&client, "#faults/L1").await;
    until(
        &client,
        "document.getElementById('page-faults').dataset.loaded",
        "the archive",
    )
    .await;
    // The record of notifications below it (level 3; none sent in this project).
    until(
        &client,
        "!document.getElementById('notifications').hidden && document.getElementById('notifications').dataset.total === '0'",
        "the notification record",
    )
    .await;
    client
        .execute(
            "const f = document.getElementById('fault-filter'); f.limit.value = '10'; f.limit.dispatchEvent(new Event('change'));",
            Vec::new(),
        )
        .await
        .unwrap();
    runtime.operate("lift L1 fault 3C").await.unwrap();
    let took = until(
        &client,
        "document.querySelector('#fault-table tr[data-code=\"3C\"][data-lift=\"L1\"]')",
        "fault 3C in the archive table",
    )
    .await;
    timings.push(("fault in the archive", took));

    // --- Enough faults for two pages of ten.
    for code in ["3F", "20", "21", "22", "23", "24", "25", "26", "27", "28"] {
        runtime
            .operate(&format!("lift L1 fault {code}"))
            .await
            .unwrap();
    }
    until(
        &client,
        "Number(document.getElementById('page-faults').dataset.total) >= 11 \
         && document.getElementById('faults-page').textContent.endsWith('of 2')",
        "eleven faults on two pages",
    )
    .await;
    assert_eq!(
        js(
            &client,
            "document.querySelectorAll('#fault-table tbody tr').length"
        )
        .await,
        json!(10)
    );
    client
        .execute(
            "document.getElementById('faults-next').click();",
            Vec::new(),
        )
        .await
        .unwrap();
    until(
        &client,
        "document.getElementById('faults-page').textContent.startsWith('page 2') \
         && document.querySelectorAll('#fault-table tbody tr').length >= 1",
        "the second page",
    )
    .await;

    // Sorted by code with a click on its column: ascending, smallest first.
    client
        .execute(
            "document.querySelector('#fault-table th[data-sort=\"code\"]').click();",
            Vec::new(),
        )
        .await
        .unwrap();
    until(
        &client,
        "document.querySelector('#fault-table th[data-sort=\"code\"]').dataset.dir === 'asc' \
         && (() => { const c = [...document.querySelectorAll('#fault-table tbody tr')].map(r => parseInt(r.dataset.code, 16)); \
                     return c.length === 10 && c.every((x, i) => i === 0 || c[i - 1] <= x) && c[0] === 0x20; })()",
        "the archive sorted by code",
    )
    .await;

    // Filtered by an English word, then a Czech one.
    let filter = |text: &str| {
        format!(
            "const f = document.getElementById('fault-filter'); f.q.value = {text:?}; f.requestSubmit();"
        )
    };
    client.execute(&filter("door"), Vec::new()).await.unwrap();
    until(
        &client,
        "(() => { const c = [...document.querySelectorAll('#fault-table tbody tr')].map(r => r.dataset.code); \
                  return c.length === 2 && c.includes('3C') && c.includes('3F'); })()",
        "the door faults only",
    )
    .await;
    client.execute(&filter("signál"), Vec::new()).await.unwrap();
    until(
        &client,
        "(() => { const c = [...document.querySelectorAll('#fault-table tbody tr')].map(r => r.dataset.code); \
                  return c.length === 9 && c.every(x => x.startsWith('2')); })()",
        "the faulty-signal faults only",
    )
    .await;

    // The CSV export, fetched by the page: header and a row with both texts.
    client
        .execute(
            "window.csvText = null; fetch('/api/lifts/faults.csv?' + HMI.lifts.archiveParameters(false)) \
             .then(r => r.text()).then(t => { window.csvText = t; });",
            Vec::new(),
        )
        .await
        .unwrap();
    until(&client, "window.csvText", "the CSV export").await;
    let text = js(&client, "window.csvText").await;
    let text = text.as_str().unwrap().trim_start_matches('\u{feff}');
    let mut lines = text.lines();
    assert_eq!(
        lines.next().unwrap(),
        "date,time,lift,code,english,czech,floor,target,received,index"
    );
    let rows: Vec<&str> = lines.collect();
    assert_eq!(rows.len(), 9, "{text}");
    assert!(
        rows.iter()
            .any(|r| r.contains(",L1,20,Faulty stop signal,Chybný signál zastavení,")),
        "{text}"
    );
    assert_eq!(
        js(&client, "document.getElementById('faults-export').hidden").await,
        json!(false)
    );

    // --- Service figures of the fleet.
    go(&client, "#figures").await;
    until(
        &client,
        "document.querySelectorAll('#figures-table tbody tr').length === 3",
        "the figures of three lifts",
    )
    .await;
    let errors = js(&client, "HMI.errors").await;
    assert_eq!(errors, json!([]), "script errors");
    client.close().await.unwrap();

    // --- A read-only user on a phone: the first screen is the mimic (no start screen),
    // the mobile view shows the lifts and the fault list, the export is hidden and refused.
    let phone = driver.session(720, 1520).await;
    log_in(&phone, &url, "viewer", "viewer-pass").await;
    assert_eq!(
        js(&phone, "document.body.dataset.current").await,
        json!("screen/overview")
    );
    go(&phone, "#mobile").await;
    until(
        &phone,
        "document.querySelectorAll('#mobile-lifts .mobile-lift').length === 3 \
         && document.querySelector('#mobile-lifts .mobile-lift[data-lift=\"L2\"] .comm.alarm') \
         && document.querySelector('#mobile-faults tbody tr[data-code=\"3C\"]')",
        "the mobile view with its lifts and faults",
    )
    .await;
    assert_eq!(
        js(
            &phone,
            "[...document.querySelectorAll('#mobile-faults th')].map(t => t.textContent)"
        )
        .await,
        json!(["Date", "Time", "Fault description"])
    );
    assert_eq!(
        js(
            &phone,
            "document.querySelectorAll('#page-mobile svg, #page-mobile canvas').length"
        )
        .await,
        json!(0)
    );
    assert_eq!(js(&phone, "window.innerWidth <= 760 && getComputedStyle(document.getElementById('nav-toggle')).display !== 'none'").await, json!(true));
    go(&phone, "#faults").await;
    until(
        &phone,
        "document.getElementById('page-faults').dataset.loaded",
        "the viewer's archive",
    )
    .await;
    assert_eq!(
        js(&phone, "document.getElementById('faults-export').hidden").await,
        json!(true)
    );
    assert_eq!(
        js(&phone, "document.getElementById('notifications').hidden").await,
        json!(true)
    );
    assert_eq!(
        js(
            &phone,
            "document.querySelector('#nav a[href=\"#figures\"]') === null"
        )
        .await,
        json!(true)
    );
    phone
        .execute(
            "window.csvStatus = null; fetch('/api/lifts/faults.csv').then(r => { window.csvStatus = r.status; });",
            Vec::new(),
        )
        .await
        .unwrap();
    until(
        &phone,
        "window.csvStatus === 403",
        "the export refused to the viewer",
    )
    .await;
    assert_eq!(js(&phone, "HMI.errors").await, json!([]));
    phone.close().await.unwrap();

    hmi.shutdown().await;
    runtime.shutdown().await;
    eprintln!("lift screens: {timings:?}, {:?} in all", started.elapsed());
}

/// The pictures of the README's lift monitoring section, from `examples/lift-fleet` (its
/// station and screens, the store in a temporary folder): the fleet list, a lift view,
/// the fault archive, the service figures and the phone view. Run by hand:
/// `cargo test -p hmi --test lifts -- --ignored lift_screenshots`.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
#[ignore = "writes docs/screenshots/lift-*.png; run by hand"]
async fn lift_screenshots() {
    let Some((driver, chromium)) = browser_available() else {
        return;
    };
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let example = root.join("examples/lift-fleet");
    let project_dir = tempfile::tempdir().unwrap();
    std::fs::copy(
        example.join("station.toml"),
        project_dir.path().join("station.toml"),
    )
    .unwrap();
    let project = Project::load(project_dir.path())
        .unwrap_or_else(|e| panic!("{:?}", e.errors()))
        .with_port_base(free_port_range(3));
    let (runtime, hmi) = start_station_and_hmi(project, &example.join("hmi")).await;
    // Some history: trips for a while, faults of several kinds, one lift not answering.
    for (lift, code) in [
        ("L3", "3C"),
        ("L3", "11"),
        ("L2", "30"),
        ("L5", "12"),
        ("L1", "51"),
    ] {
        runtime
            .operate(&format!("lift {lift} fault {code}"))
            .await
            .unwrap();
    }
    runtime.operate("lift L4 status 18").await.unwrap();
    runtime.operate("lift L6 silent").await.unwrap();
    tokio::time::sleep(Duration::from_secs(8)).await;
    let url = format!("http://{}", hmi.address);
    let driver = Driver::start(&driver, chromium);
    let out = root.join("docs/screenshots");
    std::fs::create_dir_all(&out).unwrap();
    let client = driver.session(1400, 900).await;
    log_in(&client, &url, "Servis1", "servis1-ekm66").await;
    for (hash, ready, file) in [
        (
            "#lifts",
            "document.querySelectorAll('#lift-table tr[data-lift]').length === 6",
            "lift-fleet.png",
        ),
        (
            "#lift/L3",
            "document.getElementById('page-lift') && !document.getElementById('page-lift').hidden",
            "lift-view.png",
        ),
        (
            "#faults",
            "document.getElementById('page-faults').dataset.loaded",
            "lift-archive.png",
        ),
        (
            "#figures",
            "document.querySelector('#page-figures table')",
            "lift-figures.png",
        ),
    ] {
        go(&client, hash).await;
        until(&client, ready, file).await;
        tokio::time::sleep(Duration::from_millis(700)).await;
        std::fs::write(out.join(file), client.screenshot().await.unwrap()).unwrap();
    }
    let _ = client.close().await;
    let phone = driver.session(720, 1520).await;
    log_in(&phone, &url, "viewer", "viewer-ekm66").await;
    tokio::time::sleep(Duration::from_millis(1500)).await;
    std::fs::write(
        out.join("lift-mobile.png"),
        phone.screenshot().await.unwrap(),
    )
    .unwrap();
    let _ = phone.close().await;
    hmi.shutdown().await;
    runtime.shutdown().await;
}
