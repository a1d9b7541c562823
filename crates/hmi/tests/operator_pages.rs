//! Issue 26, the operator pages: multi-pen trends (JSON and CSV, downsampled in the
//! store), user administration for level 9 (levels, 403s, CSRF, the last administrator,
//! the audit), and the station's command audit on the event list (a command from another
//! IEC 104 client with its origin, a refusal in the station's words), against the Vsetín
//! station running in-process with real IEC 104 on loopback.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing
)]

#[path = "support/chromium.rs"]
mod chromium;
#[path = "support/http.rs"]
mod http_client;
use http_client::{login_reply, request as http, Client};
use std::net::SocketAddr;
use std::path::Path;
use std::time::Duration;

use chrono::{DateTime, SecondsFormat, Utc};
use hmi::{Hmi, HmiOptions};
use iec60870::asdu::{CommandQualifier, CommonAddress, Element, Ioa, TypeId};
use iec60870::cs104::client::{spawn_client, ClientConfig, ClientHandle};
use iec60870::time::TimeZonePolicy;
use serde_json::{json, Value};
use station::config::Project;
use station::runtime::{Pacing, Runtime, RuntimeOptions, StoreChoice};
use store::{open_store, EventRecord, PointValue};
use testkit::ports::free_port_range;
use testkit::projects::vsetin;

/// The top node's points and commands as the HMI's points, one screen, three users.
fn screens(project: &Project, dir: &Path) {
    let top = project.top_node().unwrap();
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
    for c in &top.commands {
        csv.push_str(&format!(
            "{},{},{},\"{}\"\n",
            c.ioa, c.type_id, c.name, c.description
        ));
    }
    std::fs::write(dir.join("points.csv"), csv).unwrap();
    std::fs::write(
        dir.join("hmi.toml"),
        "title = \"Vsetín operator pages\"\ndefault_control_level = 5\n\
         [[screen]]\nid = \"rh\"\ntitle = \"RH\"\nfile = \"rh.svg\"\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("rh.svg"),
        r#"<svg xmlns="http://www.w3.org/2000/svg"><rect data-point="RH2_V1_FA1_Zapnut"/></svg>"#,
    )
    .unwrap();
    let mut users = hmi::users::Users::load(&dir.join("users.toml")).unwrap();
    users.add("admin", 9, "admin-pass").unwrap();
    users.add("operator", 5, "operator-pass").unwrap();
    users.add("viewer", 0, "viewer-pass").unwrap();
}

struct Setup {
    runtime: Runtime,
    hmi: Hmi,
    project: Project,
    dir: tempfile::TempDir,
}

impl Setup {
    fn hmi_store(&self) -> String {
        format!("sqlite:{}", self.dir.path().join("hmi.db").display())
    }

    fn rdrt(&self) -> SocketAddr {
        self.runtime
            .node("RDRT")
            .unwrap()
            .server
            .as_ref()
            .unwrap()
            .local_addr()
    }
}

/// The station with its own store (a file) and the HMI reading it as its archive when
/// `archive`.
async fn setup(archive: bool) -> Setup {
    let project = Project::load(&vsetin()).unwrap();
    let project = project.with_port_base(free_port_range(23));
    let dir = tempfile::tempdir().unwrap();
    screens(&project, dir.path());
    let station_store = format!("sqlite:{}", dir.path().join("station.db").display());
    let runtime = Runtime::start(
        project.clone(),
        RuntimeOptions {
            nodes: Vec::new(),
            pacing: Pacing::Manual,
            start: Utc::now(),
            store: StoreChoice::Url(station_store.clone()),
            device_kinds: station::device::DeviceKinds::builtin(),
        },
    )
    .await
    .unwrap();
    runtime.advance(Duration::from_secs(1)).await.unwrap();
    let rdrt = runtime
        .node("RDRT")
        .unwrap()
        .server
        .as_ref()
        .unwrap()
        .local_addr();
    let hmi = Hmi::start(HmiOptions {
        screens: dir.path().to_path_buf(),
        users: dir.path().join("users.toml"),
        connect: vec![rdrt.to_string()],
        common_address: CommonAddress::new(1),
        listen: "127.0.0.1:0".parse().unwrap(),
        store: Some(format!("sqlite:{}", dir.path().join("hmi.db").display())),
        zone: TimeZonePolicy::Zone(chrono_tz::Europe::Prague),
        local_address: Some([127, 0, 0, 2].into()),
        archive: archive.then_some(station_store),
    })
    .await
    .unwrap();
    Setup {
        runtime,
        hmi,
        project,
        dir,
    }
}

/// Waits (about 30 s at most) until `check` holds.
async fn until(what: &str, mut check: impl AsyncFnMut() -> bool) {
    for _ in 0..1500 {
        if check().await {
            return;
        }
        tokio::time::sleep(Duration::from_millis(20)).await;
    }
    panic!("timed out waiting until {what}");
}

fn rfc3339(t: DateTime<Utc>) -> String {
    t.to_rfc3339_opts(SecondsFormat::Millis, true)
}

/// Two measurements of the HMI's point list (float measurements), with their units.
async fn two_measurements(client: &Client) -> (String, String) {
    let points = client.get("/api/points").await.json();
    let names: Vec<String> = points["points"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|p| p["type"].as_str().is_some_and(|t| t.starts_with("M_ME")))
        .filter(|p| p["description"].as_str().is_some_and(|d| d.contains(", ")))
        .map(|p| p["name"].as_str().unwrap().to_owned())
        .collect();
    assert!(names.len() >= 2, "two measurements with units: {points}");
    (names[0].clone(), names[1].clone())
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn multi_pen_trend_as_json_and_csv_downsampled_in_the_store() {
    let s = setup(false).await;
    let admin = Client::login(s.hmi.address, "operator", "operator-pass").await;
    let (a, b) = two_measurements(&admin).await;
    // Known history written into the HMI's store: A every second for 100 s from t0,
    // B at t0 + 10 s and t0 + 50 s only.
    let t0 = DateTime::parse_from_rfc3339("2026-03-01T10:00:00Z")
        .unwrap()
        .with_timezone(&Utc);
    let history = open_store(&s.hmi_store()).await.unwrap();
    let mut events: Vec<EventRecord> = (0..100)
        .map(|i| {
            EventRecord::new(
                "RDRT",
                a.as_str(),
                PointValue::Float(f64::from(i)),
                t0 + chrono::Duration::seconds(i64::from(i)),
            )
        })
        .collect();
    events.push(EventRecord::new(
        "RDRT",
        b.as_str(),
        PointValue::Float(7.5),
        t0 + chrono::Duration::seconds(10),
    ));
    events.push(EventRecord::new(
        "RDRT",
        b.as_str(),
        PointValue::Float(-2.0),
        t0 + chrono::Duration::seconds(50),
    ));
    history.append_events(&events).await.unwrap();
    history.close().await.unwrap();
    let from = rfc3339(t0);
    let to = rfc3339(t0 + chrono::Duration::seconds(100));

    // Raw resolution (a bucket per 100 ms): every sample, pens in the order asked.
    let reply = admin
        .get(&format!(
            "/api/trend?points={b},{a}&from={from}&to={to}&width=1000"
        ))
        .await;
    assert_eq!(reply.status, 200, "{}", reply.body);
    let trend = reply.json();
    let series = trend["series"].as_array().unwrap();
    assert_eq!(series.len(), 2, "{trend}");
    assert_eq!(series[0]["point"], json!(b));
    assert_eq!(series[1]["point"], json!(a));
    assert!(
        series[0]["unit"].is_string(),
        "a unit for each pen: {trend}"
    );
    let b_samples = series[0]["samples"].as_array().unwrap();
    assert_eq!(b_samples.len(), 2, "{trend}");
    assert_eq!(
        b_samples[0],
        json!([
            (t0 + chrono::Duration::seconds(10)).timestamp_millis(),
            7.5,
            false
        ])
    );
    assert_eq!(b_samples[1][1], json!(-2.0));
    assert_eq!(series[1]["samples"].as_array().unwrap().len(), 100);

    // Ten pixels: ten buckets of ten values each, with min, mean and max.
    let reply = admin
        .get(&format!(
            "/api/trend?points={a}&from={from}&to={to}&width=10"
        ))
        .await;
    let trend = reply.json();
    let samples = trend["series"][0]["samples"].as_array().unwrap();
    assert_eq!(samples.len(), 10, "{trend}");
    assert_eq!(
        samples[3],
        json!([
            (t0 + chrono::Duration::seconds(30)).timestamp_millis(),
            34.5,
            false,
            30.0,
            39.0
        ])
    );

    // First and last value per bucket (index seeks).
    let reply = admin
        .get(&format!(
            "/api/trend?points={a}&from={from}&to={to}&width=10&mode=firstlast"
        ))
        .await;
    let trend = reply.json();
    assert_eq!(trend["mode"], "firstlast", "{trend}");
    let samples = trend["series"][0]["samples"].as_array().unwrap();
    assert_eq!(samples.len(), 20, "{trend}");
    assert_eq!(
        samples[6],
        json!([
            (t0 + chrono::Duration::seconds(30)).timestamp_millis(),
            30.0,
            false
        ])
    );
    assert_eq!(
        samples[7],
        json!([
            (t0 + chrono::Duration::seconds(39)).timestamp_millis(),
            39.0,
            false
        ])
    );
    let long_from = rfc3339(t0 - chrono::Duration::days(60));
    let long = admin
        .get(&format!(
            "/api/trend?points={a}&from={long_from}&to={to}&width=1000"
        ))
        .await
        .json();
    // 60 days: every value of a bucket still (its whole minute from the store's
    // rollups, the partial one at the range's end from the events), the 100 values in
    // the last bucket of 86 minutes: their mean, minimum and maximum.
    assert_eq!(long["mode"], "minmax", "60 days: {long}");
    assert_eq!(
        long["series"][0]["samples"],
        json!([[t0.timestamp_millis(), 49.5, false, 0.0, 99.0]]),
        "{long}"
    );

    // CSV: header time,B,A; a row per distinct time; empty cells where a pen has none.
    let reply = admin
        .get(&format!(
            "/api/trend?points={b},{a}&from={from}&to={to}&format=csv"
        ))
        .await;
    assert_eq!(reply.status, 200, "{}", reply.body);
    assert!(
        reply
            .header("content-type")
            .unwrap()
            .starts_with("text/csv"),
        "{:?}",
        reply.headers
    );
    let lines: Vec<&str> = reply.body.lines().collect();
    assert_eq!(lines[0], format!("time,{b},{a}"));
    assert_eq!(lines.len(), 101, "{}", reply.body);
    assert_eq!(lines[1], "2026-03-01T10:00:00.000+00:00,,0");
    assert_eq!(lines[11], "2026-03-01T10:00:10.000+00:00,7.5,10");

    // The single-pen form keeps its shape; bad requests are clear 4xx.
    let single = admin
        .get(&format!("/api/trend?point={a}&from={from}&to={to}"))
        .await
        .json();
    assert_eq!(single["point"], json!(a));
    assert_eq!(single["samples"].as_array().unwrap().len(), 100);
    for (query, status) in [
        (format!("points={a},NO_SUCH"), 404),
        (format!("points={a}&format=xml"), 400),
        (format!("points={a}&width=0"), 400),
        (format!("points={a}&mode=fastest"), 400),
        ("points=".to_owned(), 400),
        (format!("points={a}&from={to}&to={from}"), 400),
    ] {
        let reply = admin.get(&format!("/api/trend?{query}")).await;
        assert_eq!(reply.status, status, "{query}: {}", reply.body);
        assert!(reply.json()["error"].is_string(), "{query}: {}", reply.body);
    }
    s.hmi.shutdown().await;
    s.runtime.shutdown().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn users_are_administered_by_level_9_only_and_audited() {
    let s = setup(false).await;
    let address = s.hmi.address;
    let admin = Client::login(address, "admin", "admin-pass").await;
    let operator = Client::login(address, "operator", "operator-pass").await;
    let viewer = Client::login(address, "viewer", "viewer-pass").await;

    let list = admin.get("/api/users").await;
    assert_eq!(list.status, 200, "{}", list.body);
    let users = list.json();
    assert_eq!(users.as_array().unwrap().len(), 3, "{users}");
    let first = &users[0];
    assert_eq!(
        first,
        &json!({"name": "admin", "level": 9, "locked": false, "start": null})
    );
    assert!(!list.body.contains("argon2"), "never a hash: {}", list.body);

    // Below level 9: 403, to read and to change.
    assert_eq!(viewer.get("/api/users").await.status, 403);
    assert_eq!(operator.get("/api/users").await.status, 403);
    let refused = operator
        .post(
            "/api/users",
            json!({"name": "mallory", "level": 9, "password": "long enough"}),
        )
        .await;
    assert_eq!(refused.status, 403, "{}", refused.body);
    // Without the CSRF token: 403.
    let forged = http(
        address,
        "POST",
        "/api/users",
        &[("Cookie", &admin.cookie)],
        &json!({"name": "mallory", "level": 9, "password": "long enough"}).to_string(),
    )
    .await;
    assert_eq!(forged.status, 403, "{}", forged.body);

    // Add, change the level, reset the password, lock and unlock.
    let added = admin
        .post(
            "/api/users",
            json!({"name": "novak", "level": 3, "password": "first-pass"}),
        )
        .await;
    assert_eq!(added.status, 200, "{}", added.body);
    assert!(added
        .json()
        .as_array()
        .unwrap()
        .iter()
        .any(|u| u["name"] == "novak" && u["level"] == 3));
    assert_eq!(
        login_reply(address, "novak", "first-pass").await.status,
        200
    );
    let short = admin
        .post(
            "/api/users",
            json!({"name": "x", "level": 3, "password": "short"}),
        )
        .await;
    assert_eq!(short.status, 400, "{}", short.body);
    let level = admin
        .post("/api/users/novak/level", json!({"level": 6}))
        .await;
    assert_eq!(level.status, 200, "{}", level.body);
    let password = admin
        .post(
            "/api/users/novak/password",
            json!({"password": "second-pass"}),
        )
        .await;
    assert_eq!(password.status, 200, "{}", password.body);
    assert_eq!(
        login_reply(address, "novak", "first-pass").await.status,
        401
    );
    let novak = Client::login(address, "novak", "second-pass").await;
    assert_eq!(novak.get("/api/session").await.json()["level"], json!(6));
    let locked = admin
        .post("/api/users/novak/lock", json!({"locked": true}))
        .await;
    assert_eq!(locked.status, 200, "{}", locked.body);
    assert!(locked
        .json()
        .as_array()
        .unwrap()
        .iter()
        .any(|u| u["name"] == "novak" && u["locked"] == true));
    assert_eq!(
        login_reply(address, "novak", "second-pass").await.status,
        401,
        "a locked user cannot log in"
    );
    assert_eq!(
        novak.get("/api/session").await.status,
        401,
        "a locked user's sessions end"
    );
    let unlocked = admin
        .post("/api/users/novak/lock", json!({"locked": false}))
        .await;
    assert_eq!(unlocked.status, 200, "{}", unlocked.body);
    assert_eq!(
        login_reply(address, "novak", "second-pass").await.status,
        200
    );
    // The file holds it, with an argon2id hash.
    let file = std::fs::read_to_string(s.dir.path().join("users.toml")).unwrap();
    assert!(
        file.contains("[users.novak]") && file.contains("$argon2id$"),
        "{file}"
    );

    // The last unlocked level-9 user is never demoted, locked or removed.
    for (method, path, body) in [
        ("POST", "/api/users/admin/level", json!({"level": 8})),
        ("POST", "/api/users/admin/lock", json!({"locked": true})),
        ("DELETE", "/api/users/admin", json!({})),
    ] {
        let reply = admin.send(method, path, body).await;
        assert_eq!(reply.status, 409, "{path}: {}", reply.body);
        assert!(
            reply.json()["error"].as_str().unwrap().contains("last"),
            "{}",
            reply.body
        );
    }
    // Unknown users: 404.
    assert_eq!(
        admin
            .post("/api/users/nobody/level", json!({"level": 1}))
            .await
            .status,
        404
    );
    let removed = admin.send("DELETE", "/api/users/novak", json!({})).await;
    assert_eq!(removed.status, 200, "{}", removed.body);

    // Every change is audited: who, what, when.
    let mut details = Vec::new();
    until("the user administration audit", async || {
        let events = admin
            .get("/api/events?kind=command&user=admin")
            .await
            .json();
        details = events["items"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|e| e["point"] == "user:novak")
            .map(|e| e["detail"].as_str().unwrap().to_owned())
            .collect();
        details.len() == 6
    })
    .await;
    for expected in [
        "user `novak` added with level 3",
        "user `novak` set to level 6",
        "password of user `novak` reset",
        "user `novak` locked",
        "user `novak` unlocked",
        "user `novak` removed",
    ] {
        assert!(
            details.iter().any(|d| d == expected),
            "{expected}: {details:?}"
        );
    }
    s.hmi.shutdown().await;
    s.runtime.shutdown().await;
}

/// A dispatch client: another IEC 104 controlling station connected to RDRT.
fn dispatch(address: SocketAddr) -> ClientHandle {
    let mut config = ClientConfig::new(address.to_string(), CommonAddress::new(1));
    config.interrogate_on_start = false;
    config.reconnect_delay = Duration::from_millis(100);
    let (client, mut events) = spawn_client(config);
    tokio::spawn(async move { while events.recv().await.is_some() {} });
    client
}

/// Sends a single command from `client` while the station's clock advances.
async fn send_command(s: &Setup, client: &ClientHandle, ioa: u32) {
    let client = client.clone();
    let sent = tokio::spawn(async move {
        for _ in 0..200 {
            let outcome = client
                .command(
                    TypeId::C_SC_NA_1,
                    Ioa::try_new(ioa).unwrap(),
                    Element::SingleCommand {
                        on: true,
                        qualifier: CommandQualifier::new(0, false).unwrap(),
                    },
                    None,
                )
                .await;
            if outcome.is_ok() {
                return;
            }
            // Not connected yet.
            tokio::time::sleep(Duration::from_millis(50)).await;
        }
    });
    while !sent.is_finished() {
        s.runtime.advance(Duration::from_millis(50)).await.unwrap();
        tokio::time::sleep(Duration::from_millis(5)).await;
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn dispatch_commands_and_refusals_from_the_station_audit_on_the_event_list() {
    let s = setup(true).await;
    let viewer = Client::login(s.hmi.address, "viewer", "viewer-pass").await;
    let top = s.project.top_node().unwrap();
    let command = top
        .commands
        .iter()
        .find(|c| c.name == "RH2_VypnoutQF1")
        .unwrap();
    let ioa = command.ioa.get();
    let client = dispatch(s.rdrt());

    // The link to RH cut: the station refuses in its own words.
    s.runtime.link("RDRT", "RH").unwrap().cut();
    send_command(&s, &client, ioa).await;
    let mut found = Value::Null;
    until(
        "the dispatch command's refusal on the event list",
        async || {
            let events = viewer
                .get("/api/events?kind=command&point=RH2_VypnoutQF1")
                .await
                .json();
            assert_eq!(events["station_audit"], json!(true), "{events}");
            found = events["items"]
                .as_array()
                .unwrap()
                .iter()
                .find(|e| e["source"] == "station")
                .cloned()
                .unwrap_or(Value::Null);
            !found.is_null()
        },
    )
    .await;
    assert_eq!(found["kind"], "command", "{found}");
    assert!(
        found["origin"]
            .as_str()
            .unwrap()
            .starts_with("IEC 104 client 127.0.0.1:"),
        "the peer's address: {found}"
    );
    // ... and the redundancy group the station put it in (any client not named by the
    // project's groups is the dispatch systems').
    assert!(
        found["origin"]
            .as_str()
            .unwrap()
            .ends_with(" (group dispatch)"),
        "{found}"
    );
    assert_eq!(found["group"], "dispatch", "{found}");
    assert!(found["peer"].as_str().unwrap().starts_with("127.0.0.1:"));
    assert_ne!(found["outcome"], "executed", "{found}");
    assert_eq!(found["reason"], "link RH is cut", "{found}");
    assert_eq!(found["phase"], "execute", "{found}");

    // The link back: dispatch's next command is in the list too, newest first, whatever
    // the station made of it, with the same origin.
    s.runtime.link("RDRT", "RH").unwrap().restore();
    let first_id = found["id"].clone();
    send_command(&s, &client, ioa).await;
    let mut newest = Value::Null;
    until("dispatch's second command on the event list", async || {
        let events = viewer
            .get("/api/events?kind=command&point=RH2_VypnoutQF1")
            .await
            .json();
        let station: Vec<Value> = events["items"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|e| e["source"] == "station")
            .cloned()
            .collect();
        newest = station.first().cloned().unwrap_or(Value::Null);
        station.len() >= 2
    })
    .await;
    assert_ne!(newest["id"], first_id, "newest first: {newest}");
    assert_eq!(newest["origin"], found["origin"], "{newest}");
    s.hmi.shutdown().await;
    s.runtime.shutdown().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn without_the_station_store_the_event_list_says_so() {
    let s = setup(false).await;
    let viewer = Client::login(s.hmi.address, "viewer", "viewer-pass").await;
    let events = viewer.get("/api/events?kind=command").await.json();
    assert_eq!(events["station_audit"], json!(false), "{events}");
    assert!(
        events["note"]
            .as_str()
            .unwrap()
            .contains("this HMI's own commands"),
        "{events}"
    );
    s.hmi.shutdown().await;
    s.runtime.shutdown().await;
}

// ------------------------------------------------------------------ in a real browser

/// Logs in through the login page's form and waits for the application.
async fn browser_log_in(client: &fantoccini::Client, url: &str, user: &str, password: &str) {
    use fantoccini::Locator;
    client.goto(&format!("{url}/")).await.unwrap();
    chromium::until(
        client,
        "location.pathname === '/login' && document.getElementById('login-form')",
        "the login page",
    )
    .await;
    let name = client.find(Locator::Id("username")).await.unwrap();
    name.clear().await.unwrap();
    name.send_keys(user).await.unwrap();
    let field = client.find(Locator::Id("password")).await.unwrap();
    field.clear().await.unwrap();
    field.send_keys(password).await.unwrap();
    chromium::click(client, "#login-button").await;
    chromium::until(
        client,
        "location.pathname === '/' && document.body.dataset.ready === 'true'",
        "the application page",
    )
    .await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn trends_users_and_the_station_audit_in_a_real_browser() {
    use chromium::{browser_available, click, js, until as until_shown, Driver};
    let Some((driver, chromium)) = browser_available() else {
        return;
    };
    let s = setup(true).await;
    let api = Client::login(s.hmi.address, "admin", "admin-pass").await;
    let (a, b) = two_measurements(&api).await;
    // Half an hour ago, inside the page's default hour: A rising, B twice.
    let t0 = Utc::now() - chrono::Duration::minutes(30);
    let history = open_store(&s.hmi_store()).await.unwrap();
    let mut events: Vec<EventRecord> = (0..60)
        .map(|i| {
            EventRecord::new(
                "RDRT",
                a.as_str(),
                PointValue::Float(f64::from(i)),
                t0 + chrono::Duration::seconds(i64::from(i)),
            )
        })
        .collect();
    events.push(EventRecord::new(
        "RDRT",
        b.as_str(),
        PointValue::Float(7.5),
        t0 + chrono::Duration::seconds(10),
    ));
    events.push(EventRecord::new(
        "RDRT",
        b.as_str(),
        PointValue::Float(-2.0),
        t0 + chrono::Duration::seconds(50),
    ));
    history.append_events(&events).await.unwrap();
    history.close().await.unwrap();
    // Dispatch sends a command while the link to RH is cut.
    let top = s.project.top_node().unwrap();
    let ioa = top
        .commands
        .iter()
        .find(|c| c.name == "RH2_VypnoutQF1")
        .unwrap()
        .ioa
        .get();
    let dispatch_client = dispatch(s.rdrt());
    s.runtime.link("RDRT", "RH").unwrap().cut();
    send_command(&s, &dispatch_client, ioa).await;

    let driver = Driver::start(&driver, chromium);
    let client = driver.session(1280, 800).await;
    let url = format!("http://{}", s.hmi.address);
    browser_log_in(&client, &url, "admin", "admin-pass").await;

    // --- Multi-pen trend from the address, with a legend naming each pen and its unit.
    client
        .execute(&format!("location.hash = '#trends/{b},{a}';"), Vec::new())
        .await
        .unwrap();
    until_shown(
        &client,
        "!HMI.trend.loading && HMI.trend.series.length === 2 && HMI.trend.series[0].samples.length >= 2 \
         && HMI.trend.series[1].samples.some(s => s.length === 5 && s[3] < s[4])",
        "both pens loaded, A downsampled to min/max buckets",
    )
    .await;
    let legend = js(&client, "[...document.querySelectorAll('#trend-legend li')].map(li => [li.dataset.point, li.textContent])").await;
    assert_eq!(legend[0][0], json!(b), "{legend}");
    assert_eq!(legend[1][0], json!(a), "{legend}");
    for pen in legend.as_array().unwrap() {
        assert!(
            pen[1].as_str().unwrap().contains('['),
            "a unit in the legend: {legend}"
        );
    }
    // CSV export of the shown period: the link's address, fetched as the browser would.
    client
        .execute(
            "window.csvText = null; fetch(document.getElementById('trend-csv').href).then(r => r.text()).then(t => window.csvText = t);",
            Vec::new(),
        )
        .await
        .unwrap();
    until_shown(&client, "window.csvText !== null", "the CSV export").await;
    let csv = js(&client, "window.csvText").await;
    let csv = csv.as_str().unwrap();
    assert!(csv.starts_with(&format!("time,{b},{a}\n")), "{csv}");
    assert!(csv.lines().count() >= 4, "{csv}");
    assert_eq!(
        js(
            &client,
            "document.getElementById('trend-csv').getAttribute('download')"
        )
        .await,
        json!("trend.csv")
    );
    // Removing a pen from the legend updates the address.
    click(
        &client,
        &format!("#trend-legend li[data-point=\"{b}\"] .trend-remove"),
    )
    .await;
    until_shown(&client, &format!("location.hash === '#trends/{a}' && !HMI.trend.loading && HMI.trend.series.length === 1"), "one pen left").await;

    // --- User administration from the page.
    assert_eq!(
        js(&client, "document.getElementById('nav-users').hidden").await,
        json!(false)
    );
    client
        .execute("location.hash = '#users';", Vec::new())
        .await
        .unwrap();
    until_shown(
        &client,
        "document.querySelectorAll('#users-table tbody tr').length === 3",
        "the user list",
    )
    .await;
    client
        .execute(
            "const f = document.getElementById('user-add'); f.name.value = 'novak'; f.level.value = '3'; f.password.value = 'novak-pass'; f.requestSubmit();",
            Vec::new(),
        )
        .await
        .unwrap();
    until_shown(
        &client,
        "document.querySelector('#users-table tr[data-user=\"novak\"]')",
        "novak listed",
    )
    .await;
    client
        .execute(
            "const s = document.querySelector('#users-table tr[data-user=\"novak\"] select'); s.value = '6'; s.dispatchEvent(new Event('change'));",
            Vec::new(),
        )
        .await
        .unwrap();
    until_shown(
        &client,
        "document.getElementById('users-message').textContent.includes('novak is now level 6')",
        "the new level",
    )
    .await;
    click(&client, "#users-table tr[data-user=\"novak\"] .user-lock").await;
    until_shown(
        &client,
        "document.querySelector('#users-table tr[data-user=\"novak\"]').dataset.locked === 'true'",
        "novak locked",
    )
    .await;
    // The last administrator cannot lock himself out: the refusal in words.
    click(&client, "#users-table tr[data-user=\"admin\"] .user-lock").await;
    until_shown(&client, "document.getElementById('users-message').textContent.includes('last unlocked level-9 user')", "the refusal").await;
    assert_eq!(
        login_reply(s.hmi.address, "novak", "novak-pass")
            .await
            .status,
        401
    );
    let audit = api
        .get("/api/events?kind=command&point=user:novak")
        .await
        .json();
    assert_eq!(
        audit["items"].as_array().unwrap().len(),
        3,
        "added, level, locked: {audit}"
    );

    // --- The station's command audit on the event page: dispatch's refused command.
    client
        .execute("location.hash = '#events';", Vec::new())
        .await
        .unwrap();
    client
        .execute("const f = document.getElementById('event-filter'); f.kind.value = 'command'; f.point.value = 'RH2_VypnoutQF1'; f.requestSubmit();", Vec::new())
        .await
        .unwrap();
    let row = r#"[...document.querySelectorAll('#event-table tbody tr[data-kind="command"]')].find(r => r.textContent.includes('IEC 104 client 127.0.0.1:'))"#;
    until_shown(&client, row, "dispatch's command on the event page").await;
    let cells = js(
        &client,
        &format!("[...{row}.children].map(c => c.textContent)"),
    )
    .await;
    assert_eq!(cells[1], json!("command"), "{cells}");
    assert_eq!(cells[2], json!("RH2_VypnoutQF1"), "{cells}");
    assert!(
        cells[4]
            .as_str()
            .unwrap()
            .starts_with("IEC 104 client 127.0.0.1:"),
        "{cells}"
    );
    assert_ne!(cells[5], json!("executed"), "{cells}");
    assert_eq!(cells[6], json!("link RH is cut"), "{cells}");
    assert_eq!(
        js(&client, "document.getElementById('events-note').hidden").await,
        json!(true)
    );

    client.close().await.unwrap();
    s.hmi.shutdown().await;
    s.runtime.shutdown().await;
}
