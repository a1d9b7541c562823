//! Alarm management to ISA-18.2 and EEMUA 191 (issue 26, docs/HMI.md "Alarm management"),
//! against the Vsetín station running in this process:
//!
//! - over HTTP: the initial state after the HMI's interrogation, shelving all three ways
//!   (the server ending a timed shelve within about a second, by hand, one-shot), who may
//!   shelve, suppression by design, out of service, chattering and flood detection each
//!   raising an alarm of its own, the audit of every action, and the KPI report;
//! - in headless Chromium: no alarm flood after the site starts, the alarm line inside a
//!   1280-px viewport, the confirmation before "acknowledge shown", one-shot shelving
//!   from the list, and the KPI report page.
//!
//! The station's control-authority point `RDRT_SP21_HMI_Mistne` follows the HMI's own
//! command `RDRT_HMI_Mistne`, so the HTTP test drives alarms on it at will.

#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing,
    missing_docs
)]

#[path = "support/chromium.rs"]
mod chromium;
#[path = "support/site.rs"]
mod site;
use site::Site;
#[path = "support/http.rs"]
mod http_support;

use std::path::Path;
use std::time::{Duration, Instant};

use chromium::{browser_available, click, js, until as until_js, Driver};
use chrono::{DateTime, Utc};
use fantoccini::Client as Browser;
use hmi::{Hmi, HmiOptions};
use http_support::{request as http, Client};
use iec60870::time::TimeZonePolicy;
use serde_json::{json, Value};
use station::config::Project;
use station::runtime::{Pacing, Runtime, RuntimeOptions, StoreChoice};
use testkit::ports::free_port_range;
use testkit::projects::vsetin;

const AUTHORITY: &str = "RDRT_SP21_HMI_Mistne";

/// Alarm ids of [`screens`]: the base alarm, then those of `ALARMS`.
const SURGE: u64 = 0;
const LOCAL_A: u64 = 1;
const LOCAL_B: u64 = 2;
const LOCAL_C: u64 = 3;
const LOCAL_D: u64 = 4;
const SURGE_SUPPRESSED: u64 = 5;
/// Configured alarms, hence the first chattering alarm's id and the flood alarm's.
const CONFIGURED: u64 = 6;

const ALARMS: &str = r#"
[[alarm]]
point = "RDRT_SP21_HMI_Mistne"
priority = 2
text = "HMI local A"
acknowledge = true
[[alarm]]
point = "RDRT_SP21_HMI_Mistne"
priority = 3
text = "HMI local B"
acknowledge = true
[[alarm]]
point = "RDRT_SP21_HMI_Mistne"
priority = 3
text = "HMI local C"
acknowledge = true
[[alarm]]
point = "RDRT_SP21_HMI_Mistne"
priority = 4
text = "HMI local D"
acknowledge = true
[[alarm]]
point = "RH2_P1_FV1_Prepetova_ochrana"
priority = 3
text = "RH2 surge arrester (suppressed while the HMI holds the authority)"
acknowledge = true
suppress_when = { point = "RDRT_SP21_HMI_Mistne", state = true }
"#;

/// A screens folder: the top node's points, the alarms above, four users.
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
        format!(
            r#"title = "Alarm management test"
default_control_level = 5
[[screen]]
id = "rh"
title = "RH"
file = "rh.svg"
[[alarm]]
point = "RH2_P1_FV1_Prepetova_ochrana"
priority = 3
text = "RH2 surge arrester"
acknowledge = true
{ALARMS}"#
        ),
    )
    .unwrap();
    std::fs::write(
        dir.join("rh.svg"),
        r#"<svg xmlns="http://www.w3.org/2000/svg"><rect data-point="RH2_V1_FA1_Zapnut"/></svg>"#,
    )
    .unwrap();
    let mut users = hmi::users::Users::load(&dir.join("users.toml")).unwrap();
    users.add("operator", 5, "operator-pass").unwrap();
    users.add("junior", 3, "junior-pass").unwrap();
    users.add("viewer", 0, "viewer-pass").unwrap();
}

struct Setup {
    runtime: Runtime,
    hmi: Hmi,
    _dir: tempfile::TempDir,
}

async fn setup() -> Setup {
    setup_with_store("sqlite::memory:").await
}

/// The HMI of the screens folder `dir` on `runtime`'s RDRT, with the event store `store`.
async fn start_hmi(runtime: &Runtime, dir: &Path, store: &str) -> Hmi {
    let rdrt = runtime
        .node("RDRT")
        .unwrap()
        .server
        .as_ref()
        .unwrap()
        .local_addr();
    Hmi::start(HmiOptions {
        screens: dir.to_path_buf(),
        users: dir.join("users.toml"),
        connect: vec![rdrt.to_string()],
        common_address: iec60870::asdu::CommonAddress::new(1),
        listen: "127.0.0.1:0".parse().unwrap(),
        store: Some(store.to_owned()),
        zone: TimeZonePolicy::Zone(chrono_tz::Europe::Prague),
        local_address: Some([127, 0, 0, 2].into()),
        archive: None,
    })
    .await
    .unwrap()
}

async fn setup_with_store(store: &str) -> Setup {
    let project = Project::load(&vsetin())
        .unwrap()
        .with_port_base(free_port_range(23));
    let dir = tempfile::tempdir().unwrap();
    screens(&project, dir.path());
    let runtime = Runtime::start(
        project,
        RuntimeOptions {
            nodes: Vec::new(),
            pacing: Pacing::Manual,
            start: Utc::now(),
            store: StoreChoice::Disabled,
            device_kinds: station::device::DeviceKinds::builtin(),
        },
    )
    .await
    .unwrap();
    runtime.advance(Duration::from_secs(1)).await.unwrap();
    let hmi = start_hmi(&runtime, dir.path(), store).await;
    Setup {
        runtime,
        hmi,
        _dir: dir,
    }
}

impl Client {
    /// `POST /api/alarms/{id}/{action}`, expecting 200; the alarm.
    async fn alarm_action(&self, id: u64, action: &str, body: Value) -> Value {
        let reply = self
            .post(&format!("/api/alarms/{id}/{action}"), body.clone())
            .await;
        assert_eq!(reply.status, 200, "{action} {body}: {}", reply.body);
        reply.json()
    }

    /// One alarm as `GET /api/alarms` lists it (`None`: not listed).
    async fn alarm(&self, id: u64) -> Option<Value> {
        let list = self.get("/api/alarms").await.json();
        list.as_array()
            .unwrap()
            .iter()
            .find(|a| a["id"] == json!(id))
            .cloned()
    }

    async fn point(&self, name: &str) -> Value {
        let points = self.get("/api/points").await.json();
        points["points"]
            .as_array()
            .unwrap()
            .iter()
            .find(|p| p["name"] == name)
            .unwrap()
            .clone()
    }
}

/// Waits until `check` holds, at most `limit`; how long it took.
async fn until(what: &str, limit: Duration, mut check: impl AsyncFnMut() -> bool) -> Duration {
    let started = Instant::now();
    while started.elapsed() < limit {
        if check().await {
            return started.elapsed();
        }
        tokio::time::sleep(Duration::from_millis(20)).await;
    }
    panic!("timed out after {limit:?} waiting until {what}");
}

/// Sets the control authority (the HMI's command) and waits until the station reports it.
async fn set_authority(s: &Setup, operator: &Client, local: bool) {
    let taken = operator
        .post(
            "/api/command",
            json!({"command": "RDRT_HMI_Mistne", "value": local}),
        )
        .await;
    assert_eq!(taken.json()["outcome"], "executed", "{}", taken.body);
    for _ in 0..50 {
        s.runtime.advance(Duration::from_millis(100)).await.unwrap();
        if operator.point(AUTHORITY).await["value"] == json!(local) {
            return;
        }
    }
    panic!("the station never reported the authority {local}");
}

fn waiting(alarm: &Value) -> bool {
    alarm["needs_acknowledgement"] == json!(true)
        && alarm["acknowledged"] == json!(false)
        && !alarm["raised"].is_null()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn shelving_suppression_out_of_service_chattering_flood_and_kpi_over_http() {
    let s = setup().await;
    let operator = Client::login(s.hmi.address, "operator", "operator-pass").await;
    let junior = Client::login(s.hmi.address, "junior", "junior-pass").await;
    let viewer = Client::login(s.hmi.address, "viewer", "viewer-pass").await;
    until("link up", Duration::from_secs(10), async || {
        operator.get("/api/points").await.json()["link"]["up"] == json!(true)
    })
    .await;
    let link_up = Utc::now();

    // --- The initial state: the authority taken inside the settle window raises nothing
    // until the window ends; active then, the four alarms are raised then.
    set_authority(&s, &operator, true).await;
    let a = operator.alarm(LOCAL_A).await.expect("listed while active");
    assert_eq!(a["active"], json!(true));
    if Utc::now() < link_up + chrono::Duration::seconds(7) {
        assert!(!waiting(&a), "raised inside the settle window: {a}");
    }
    until(
        "the alarms active at the end of the window raised",
        Duration::from_secs(20),
        async || operator.alarm(LOCAL_A).await.is_some_and(|a| waiting(&a)),
    )
    .await;
    let raised: DateTime<Utc> =
        serde_json::from_value(operator.alarm(LOCAL_A).await.unwrap()["raised"].clone()).unwrap();
    assert!(
        raised >= link_up + chrono::Duration::seconds(7),
        "raised at {raised}, link up at {link_up}"
    );

    // --- Who may shelve: level 5; a level-3 user and the read-only user are refused.
    let refused = junior
        .post(
            &format!("/api/alarms/{LOCAL_A}/shelve"),
            json!({"minutes": 5}),
        )
        .await;
    assert_eq!(refused.status, 403, "{}", refused.body);
    assert!(
        refused.json()["error"]
            .as_str()
            .unwrap()
            .contains("needs level 5, user has 3"),
        "{}",
        refused.body
    );
    let refused = viewer
        .post(
            &format!("/api/alarms/{LOCAL_A}/shelve"),
            json!({"minutes": 5}),
        )
        .await;
    assert_eq!(refused.status, 403, "{}", refused.body);
    // Exactly one of minutes, seconds or oneshot.
    for bad in [
        json!({}),
        json!({"minutes": 1, "seconds": 1}),
        json!({"oneshot": false}),
        json!({"minutes": 0}),
        json!({"hours": 1}),
        json!({"seconds": 1, "reason": "x".repeat(201)}),
    ] {
        let reply = operator
            .post(&format!("/api/alarms/{LOCAL_A}/shelve"), bad.clone())
            .await;
        assert!(
            (400..500).contains(&reply.status) && reply.json()["error"].is_string(),
            "{bad}: {} {}",
            reply.status,
            reply.body
        );
    }
    assert_eq!(
        operator
            .post("/api/alarms/9999/shelve", json!({"seconds": 5}))
            .await
            .status,
        404
    );

    // --- Timed shelve, ended by the server's timer within about a second: the alarm,
    // acknowledged before, returns unacknowledged (ISA-18.2).
    operator
        .alarm_action(LOCAL_A, "acknowledge", json!({}))
        .await;
    let shelved = operator
        .alarm_action(
            LOCAL_A,
            "shelve",
            json!({"seconds": 1, "reason": "checking the cabinet"}),
        )
        .await;
    assert_eq!(shelved["shelved"], json!(true));
    assert_eq!(shelved["oneshot"], json!(false));
    assert_eq!(shelved["shelve_reason"], json!("checking the cabinet"));
    let until_time: DateTime<Utc> =
        serde_json::from_value(shelved["shelved_until"].clone()).unwrap();
    // Listed while shelved.
    assert_eq!(
        operator.alarm(LOCAL_A).await.unwrap()["shelved"],
        json!(true)
    );
    until(
        "the timed shelve ended",
        Duration::from_secs(5),
        async || {
            operator
                .alarm(LOCAL_A)
                .await
                .is_some_and(|a| a["shelved"] == json!(false))
        },
    )
    .await;
    let late = Utc::now() - until_time;
    assert!(
        late < chrono::Duration::milliseconds(1200),
        "the shelve ended {late} after its time"
    );
    let ended = operator.alarm(LOCAL_A).await.unwrap();
    assert!(ended["shelved_until"].is_null(), "{ended}");
    assert!(waiting(&ended), "back unacknowledged: {ended}");

    // --- By hand: back acknowledged.
    let b = operator
        .alarm_action(LOCAL_B, "shelve", json!({"minutes": 30}))
        .await;
    let until_b: DateTime<Utc> = serde_json::from_value(b["shelved_until"].clone()).unwrap();
    assert!(
        (until_b - Utc::now() - chrono::Duration::minutes(30))
            .num_seconds()
            .abs()
            < 10
    );
    let unshelved = operator.alarm_action(LOCAL_B, "unshelve", json!({})).await;
    assert_eq!(unshelved["shelved"], json!(false));
    assert!(unshelved["shelved_until"].is_null());
    assert_eq!(unshelved["acknowledged"], json!(true));
    assert_eq!(
        operator
            .post(&format!("/api/alarms/{LOCAL_B}/unshelve"), json!({}))
            .await
            .status,
        400,
        "not shelved"
    );

    // --- One-shot: until the alarm returns to normal.
    let c = operator
        .alarm_action(LOCAL_C, "shelve", json!({"oneshot": true}))
        .await;
    assert_eq!(c["oneshot"], json!(true));
    assert!(c["shelved_until"].is_null());
    set_authority(&s, &operator, false).await;
    let c = until(
        "the one-shot shelve ended",
        Duration::from_secs(5),
        async || {
            operator
                .alarm(LOCAL_C)
                .await
                .is_none_or(|c| c["shelved"] == json!(false))
        },
    )
    .await;
    assert!(c < Duration::from_secs(5));
    let one_shot_inactive = operator
        .post(
            &format!("/api/alarms/{LOCAL_C}/shelve"),
            json!({"oneshot": true}),
        )
        .await;
    assert_eq!(one_shot_inactive.status, 400, "{}", one_shot_inactive.body);

    // --- Chattering (3 activations within 60 s) and a flood (10 within 10 min): alarms of
    // their own, the individual ones still raised.
    set_authority(&s, &operator, true).await;
    set_authority(&s, &operator, false).await;
    set_authority(&s, &operator, true).await;
    let chatter = until("the chattering alarm", Duration::from_secs(5), async || {
        operator
            .alarm(CONFIGURED + LOCAL_A)
            .await
            .is_some_and(|c| c["active"] == json!(true))
    })
    .await;
    assert!(chatter < Duration::from_secs(5));
    let chatter = operator.alarm(CONFIGURED + LOCAL_A).await.unwrap();
    assert_eq!(chatter["system"], json!(true));
    assert_eq!(chatter["point"], json!(AUTHORITY));
    assert!(
        chatter["text"]
            .as_str()
            .unwrap()
            .starts_with("Chattering: HMI local A"),
        "{chatter}"
    );
    assert!(waiting(&chatter));
    assert!(waiting(&operator.alarm(LOCAL_D).await.unwrap()));
    let flood = operator
        .alarm(2 * CONFIGURED)
        .await
        .expect("the flood alarm listed");
    assert_eq!(flood["active"], json!(true));
    assert!(
        flood["text"]
            .as_str()
            .unwrap()
            .starts_with("Alarm flood: 12 alarms"),
        "{flood}"
    );

    // --- Suppression by design: the surge arrester's second alarm is suppressed while
    // the HMI holds the authority (TRUE now), raised when the condition ends.
    s.runtime.operate("surge-arrester RH2_FV1").await.unwrap();
    s.runtime.advance(Duration::from_millis(300)).await.unwrap();
    until(
        "the surge arrester alarm",
        Duration::from_secs(5),
        async || operator.alarm(SURGE).await.is_some_and(|a| waiting(&a)),
    )
    .await;
    let suppressed = operator.alarm(SURGE_SUPPRESSED).await.unwrap();
    assert_eq!(suppressed["suppressed"], json!(true), "{suppressed}");
    assert_eq!(suppressed["active"], json!(true));
    assert!(!waiting(&suppressed), "{suppressed}");
    set_authority(&s, &operator, false).await;
    until(
        "the suppressed alarm raised when its condition ended",
        Duration::from_secs(5),
        async || {
            operator
                .alarm(SURGE_SUPPRESSED)
                .await
                .is_some_and(|a| a["suppressed"] == json!(false) && waiting(&a))
        },
    )
    .await;

    // --- Out of service: with a reason and who; back in service.
    let no_reason = operator
        .post(&format!("/api/alarms/{SURGE}/out-of-service"), json!({}))
        .await;
    assert_eq!(no_reason.status, 400, "{}", no_reason.body);
    assert_eq!(
        junior
            .post(
                &format!("/api/alarms/{SURGE}/out-of-service"),
                json!({"reason": "x"})
            )
            .await
            .status,
        403
    );
    let out = operator
        .alarm_action(
            SURGE,
            "out-of-service",
            json!({"reason": "arrester being replaced"}),
        )
        .await;
    assert_eq!(
        out["out_of_service"]["reason"],
        json!("arrester being replaced")
    );
    assert_eq!(out["out_of_service"]["user"], json!("operator"));
    assert!(!waiting(&out));
    assert!(operator.alarm(SURGE).await.unwrap()["out_of_service"].is_object());
    let back = operator.alarm_action(SURGE, "in-service", json!({})).await;
    assert!(back["out_of_service"].is_null());

    // --- Every action is in the HMI's audit, under the user's name.
    until("the audit records", Duration::from_secs(5), async || {
        let body = operator
            .get("/api/events?kind=command&limit=200")
            .await
            .body;
        [
            "alarm shelved until",
            "checking the cabinet",
            "alarm unshelved",
            "alarm shelved one-shot",
            "alarm taken out of service",
            "arrester being replaced",
            "alarm returned to service",
            "alarm acknowledged: HMI local A",
        ]
        .iter()
        .all(|text| body.contains(text))
    })
    .await;

    // --- The KPI report of the last hour.
    let from = (Utc::now() - chrono::Duration::hours(1))
        .to_rfc3339_opts(chrono::SecondsFormat::Secs, true);
    let to = (Utc::now() + chrono::Duration::minutes(1))
        .to_rfc3339_opts(chrono::SecondsFormat::Secs, true);
    let kpi = operator
        .get(&format!("/api/alarms/kpi?from={from}&to={to}"))
        .await;
    assert_eq!(kpi.status, 200, "{}", kpi.body);
    let kpi = kpi.json();
    // 3 x 4 authority alarms, the surge arrester, its suppressed twin when released.
    assert_eq!(kpi["alarms"], json!(14), "{kpi}");
    let per_hour = kpi["alarms_per_hour"].as_f64().unwrap();
    assert!((per_hour - 14.0 / (61.0 / 60.0)).abs() < 0.01, "{kpi}");
    assert_eq!(kpi["peak_per_10min"], json!(14), "{kpi}");
    let floods = kpi["floods"].as_array().unwrap();
    assert_eq!(floods.len(), 1, "{kpi}");
    assert_eq!(floods[0]["count"], json!(14));
    assert!(floods[0]["start"].is_string() && floods[0]["end"].is_string());
    let top = kpi["top"].as_array().unwrap();
    assert!(top.len() <= 10);
    assert_eq!(top[0]["point"], json!(AUTHORITY));
    assert_eq!(
        top[0]["count"],
        json!(3),
        "every activation, chattering included"
    );
    assert_eq!(top[0]["priority"], json!(2));
    assert_eq!(top[0]["text"], json!("HMI local A"));
    assert_eq!(
        kpi["priority_distribution"],
        json!({"1": 0, "2": 3, "3": 8, "4": 3})
    );
    assert_eq!(kpi["standing"], json!([]));
    assert_eq!(kpi["stale"], json!([]));
    for bad in [
        "from=yesterday",
        "from=2026-01-02T00:00:00Z&to=2026-01-01T00:00:00Z",
    ] {
        let reply = operator.get(&format!("/api/alarms/kpi?{bad}")).await;
        assert_eq!(reply.status, 400, "{bad}: {}", reply.body);
    }
    assert_eq!(
        http(s.hmi.address, "GET", "/api/alarms/kpi", &[], "")
            .await
            .status,
        401
    );

    s.hmi.shutdown().await;
    s.runtime.shutdown().await;
}

/// The KPI report reaches back before the HMI's start through the HMI's event store: the
/// activations of a previous run are read back from the value changes it recorded.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_kpi_report_reaches_back_across_a_restart_through_the_store() {
    let stores = tempfile::tempdir().unwrap();
    let url = format!("sqlite:{}", stores.path().join("hmi.sqlite").display());
    let s = setup_with_store(&url).await;
    let before_start = Utc::now() - chrono::Duration::minutes(5);
    let operator = Client::login(s.hmi.address, "operator", "operator-pass").await;
    until("link up", Duration::from_secs(10), async || {
        operator.get("/api/points").await.json()["link"]["up"] == json!(true)
    })
    .await;
    // The HMI takes the authority: the four alarms of its point, once each.
    set_authority(&s, &operator, true).await;
    until("the alarms raised", Duration::from_secs(20), async || {
        operator.alarm(LOCAL_D).await.is_some_and(|a| waiting(&a))
    })
    .await;
    let first = operator
        .get(&format!(
            "/api/alarms/kpi?from={}",
            before_start.to_rfc3339_opts(chrono::SecondsFormat::Secs, true)
        ))
        .await
        .json();
    assert_eq!(first["alarms"], json!(4), "{first}");
    let Setup { runtime, hmi, _dir } = s;
    hmi.shutdown().await;

    // A new HMI on the same store: its own log is empty, the store has the first run's.
    let hmi = start_hmi(&runtime, _dir.path(), &url).await;
    let operator = Client::login(hmi.address, "operator", "operator-pass").await;
    let to = Utc::now().to_rfc3339_opts(chrono::SecondsFormat::Millis, true);
    let kpi = operator
        .get(&format!(
            "/api/alarms/kpi?from={}&to={to}",
            before_start.to_rfc3339_opts(chrono::SecondsFormat::Secs, true)
        ))
        .await;
    assert_eq!(kpi.status, 200, "{}", kpi.body);
    let kpi = kpi.json();
    assert_eq!(kpi["from_store"], json!(true), "{kpi}");
    assert_eq!(kpi["alarms"], json!(4), "{kpi}");
    assert_eq!(
        kpi["priority_distribution"],
        json!({"1": 0, "2": 1, "3": 2, "4": 1})
    );
    assert_eq!(kpi["top"].as_array().unwrap().len(), 4, "{kpi}");
    hmi.shutdown().await;
    runtime.shutdown().await;
}

// ---------------------------------------------------------------------------- browser

/// Waits until the alarm of a door contact is active (or not) in the HMI.
async fn door_alarm(site: &Site, point: &str, active: bool) {
    let started = Instant::now();
    loop {
        let now = site
            .hmi()
            .station
            .alarms()
            .iter()
            .any(|a| a.point == point && !a.system && a.active);
        if now == active {
            return;
        }
        assert!(
            started.elapsed() < Duration::from_secs(10),
            "the alarm of {point} never became {active}"
        );
        tokio::time::sleep(Duration::from_millis(20)).await;
    }
}

async fn log_in_ready(client: &Browser, url: &str, user: &str, password: &str) {
    client.goto(&format!("{url}/")).await.unwrap();
    until_js(
        client,
        "location.pathname === '/login' && document.getElementById('login-form')",
        "the login page",
    )
    .await;
    let name = client
        .find(fantoccini::Locator::Id("username"))
        .await
        .unwrap();
    name.send_keys(user).await.unwrap();
    let field = client
        .find(fantoccini::Locator::Id("password"))
        .await
        .unwrap();
    field.send_keys(password).await.unwrap();
    click(client, "#login-button").await;
    until_js(
        client,
        "location.pathname === '/' && document.body.dataset.ready === 'true' && HMI.wsOpen && HMI.link.up && HMI.points.size > 400",
        "the application with the station link up",
    )
    .await;
}

/// Whether `css` is drawn inside a 1280-px-wide page without horizontal scrolling.
async fn inside_viewport(client: &Browser, css: &str) -> Value {
    js(
        client,
        &format!(
            "(() => {{ const r = document.querySelector({css:?}).getBoundingClientRect(); \
             return [r.left >= 0 && r.right <= window.innerWidth && r.width > 0 && r.height > 0, \
             document.documentElement.scrollWidth <= window.innerWidth, window.innerWidth <= 1280]; }})()"
        ),
    )
    .await
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn no_alarm_flood_at_start_and_the_alarm_line_in_a_real_browser() {
    let Some((driver, chromium)) = browser_available() else {
        return;
    };
    let site = Site::start(Utc::now(), 1.0).await;

    // --- No flood at start: from the link coming up (the interrogation) through 8 s after
    // it and 6 s more, at most 2 alarms wait for acknowledgement at any moment.
    let station = std::sync::Arc::clone(&site.hmi().station);
    let started = Instant::now();
    while !station.is_up() {
        assert!(started.elapsed() < Duration::from_secs(20), "no link");
        tokio::time::sleep(Duration::from_millis(20)).await;
    }
    let up = Instant::now();
    let mut most = 0;
    let mut waiting_texts = Vec::new();
    while up.elapsed() < Duration::from_secs(14) {
        let waiting: Vec<String> = station
            .alarms()
            .iter()
            .filter(|a| a.waiting())
            .map(|a| a.text.clone())
            .collect();
        if waiting.len() > most {
            most = waiting.len();
            waiting_texts = waiting;
        }
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
    eprintln!("alarms waiting after start: at most {most}: {waiting_texts:?}");
    assert!(
        most <= 2,
        "{most} alarms wait after start: {waiting_texts:?}"
    );

    // --- The alarm line on every page, inside a 1280-px viewport.
    let driver = Driver::start(&driver, chromium);
    let client = driver.session(1280, 800).await;
    log_in_ready(&client, &site.url, "operator", "operator-vsetin").await;
    site.operate("emergency-off RH2").await;
    until_js(
        &client,
        "document.getElementById('alarm-line').dataset.priority === '1' && \
         document.getElementById('alarm-line-text').textContent.includes('RH2: emergency off')",
        "the emergency-off alarm on the alarm line",
    )
    .await;
    let line = js(
        &client,
        "document.getElementById('alarm-line-text').textContent",
    )
    .await;
    let line = line.as_str().unwrap().to_owned();
    // The date and the zone with the time.
    let today = js(&client, "HMI.formatTime(new Date()).slice(0, 10)").await;
    assert!(line.contains(today.as_str().unwrap()), "{line}");
    assert!(
        line.contains("CET")
            || line.contains("GMT")
            || line.contains("UTC")
            || line.contains("CEST"),
        "no zone: {line}"
    );
    for page in ["#screen/supply", "#events", "#trends", "#alarms"] {
        client
            .execute(&format!("location.hash = '{page}';"), Vec::new())
            .await
            .unwrap();
        until_js(
            &client,
            &format!("location.hash === '{page}' && !document.getElementById('alarm-line').hidden"),
            page,
        )
        .await;
        let inside = inside_viewport(&client, "#alarm-line").await;
        assert_eq!(inside, json!([true, true, true]), "{page}: {inside}");
        let ack = inside_viewport(&client, "#alarm-line-ack").await;
        assert_eq!(ack[0], json!(true), "{page}: the line's button {ack}");
    }

    if std::env::var_os("STANICE_SCREENSHOTS").is_some() {
        let out = testkit::repository_root().join("docs/screenshots/alarm-line.png");
        std::fs::write(out, client.screenshot().await.unwrap()).unwrap();
    }

    // --- "Acknowledge shown" asks first; Cancel acknowledges nothing.
    site.operate("fuse-blown RZZ_FU1").await;
    let waiting_in_list = "[...HMI.alarms.values()].filter((a) => a.needs_acknowledgement && !a.acknowledged && a.raised).length";
    until_js(
        &client,
        &format!("{waiting_in_list} >= 1 && document.querySelectorAll('#alarm-table tr.unack').length >= 1"),
        "unacknowledged alarms listed",
    )
    .await;
    click(&client, "#alarm-ack-all").await;
    until_js(
        &client,
        "document.getElementById('alarm-ack-dialog').open && \
         /Acknowledge the \\d+ unacknowledged alarm/.test(document.getElementById('alarm-ack-question').textContent)",
        "the confirmation",
    )
    .await;
    let before = js(&client, waiting_in_list).await;
    click(&client, "#alarm-ack-cancel").await;
    until_js(
        &client,
        "!document.getElementById('alarm-ack-dialog').open",
        "the confirmation closed",
    )
    .await;
    assert_eq!(
        js(&client, waiting_in_list).await,
        before,
        "Cancel acknowledged"
    );
    click(&client, "#alarm-ack-all").await;
    until_js(
        &client,
        "document.getElementById('alarm-ack-dialog').open",
        "the confirmation again",
    )
    .await;
    click(&client, "#alarm-ack-confirm").await;
    until_js(
        &client,
        &format!("{waiting_in_list} === 0 && document.getElementById('alarm-line').dataset.priority === '0'"),
        "everything shown acknowledged and the alarm line quiet",
    )
    .await;

    // --- One-shot shelving from the list: until the alarm returns to normal.
    let row = r#"document.querySelector('#alarm-table tr[data-point="RH2_P1_KHVRH2_Havarijni_vypnuti"]')"#;
    js(
        &client,
        &format!("({row}.querySelector('select').value = 'oneshot', {row}.querySelector('input.reason').value = 'crew on site')"),
    )
    .await;
    click(
        &client,
        r#"#alarm-table tr[data-point="RH2_P1_KHVRH2_Havarijni_vypnuti"] button.shelve"#,
    )
    .await;
    until_js(
        &client,
        &format!("{row}.classList.contains('shelved') && {row}.textContent.includes('until it returns to normal') && {row}.textContent.includes('crew on site')"),
        "the alarm shelved one-shot",
    )
    .await;

    // --- Chattering and a flood: the four switchroom doors opened and closed three times
    // each within a minute: 12 activations, four chattering alarms and a flood alarm,
    // listed as alarms of their own (and the flood, priority 2, on the alarm line).
    for door in ["NN", "VN", "T1", "T2"] {
        let point = match door {
            "NN" => "RDRT_SP26_Dvere_NN",
            "VN" => "RDRT_SP27_Dvere_VN",
            "T1" => "RDRT_SP28_Dvere_T1",
            _ => "RDRT_SP29_Dvere_T2",
        };
        for _ in 0..3 {
            site.operate(&format!("door-open RDRT_{door}")).await;
            door_alarm(&site, point, true).await;
            site.operate(&format!("clear door-open RDRT_{door}")).await;
            door_alarm(&site, point, false).await;
        }
    }
    js(&client, "(document.querySelector('#alarm-filter select[name=state]').value = 'system', document.getElementById('alarm-filter').dispatchEvent(new Event('input')))").await;
    until_js(
        &client,
        "document.querySelectorAll('#alarm-table tbody tr').length === 5 && \
         document.querySelector('#alarm-table tr[data-point=\"alarm system\"]') && \
         document.querySelector('#alarm-table tr[data-point=\"alarm system\"]').textContent.includes('Alarm flood: ') && \
         [...document.querySelectorAll('#alarm-table tbody tr')].some((r) => r.textContent.includes('Chattering: LV switchroom door open (3 activations within 60 s)')) && \
         document.getElementById('alarm-line-text').textContent.includes('Alarm flood')",
        "four chattering alarms and the flood alarm listed, the flood on the alarm line",
    )
    .await;

    // --- The KPI report page, linked from the alarm page, against EEMUA 191.
    click(&client, "#alarm-report-link").await;
    until_js(
        &client,
        "document.body.dataset.current === 'alarm-report' && !HMI.alarmReport.loading && \
         document.querySelectorAll('#kpi-table tbody tr').length === 8 && \
         document.querySelectorAll('#kpi-top tbody tr').length >= 2",
        "the alarm report",
    )
    .await;
    let report = js(
        &client,
        "document.getElementById('page-alarm-report').textContent",
    )
    .await;
    let report = report.as_str().unwrap();
    for words in [
        "Alarms per hour",
        "< 6 very likely acceptable",
        "Peak alarms per 10 min",
        "< 10",
        "about 80 %",
        "RH2: emergency off",
        "LV switchroom door open",
    ] {
        assert!(
            report.contains(words),
            "{words} not in the report: {report}"
        );
    }
    let inside = inside_viewport(&client, "#kpi-table").await;
    assert_eq!(inside, json!([true, true, true]), "{inside}");
    // `STANICE_SCREENSHOTS=1`: the report and the alarm page for docs/screenshots/.
    if std::env::var_os("STANICE_SCREENSHOTS").is_some() {
        let out = testkit::repository_root().join("docs/screenshots");
        std::fs::write(
            out.join("alarm-report.png"),
            client.screenshot().await.unwrap(),
        )
        .unwrap();
        client
            .execute("location.hash = '#alarms';", Vec::new())
            .await
            .unwrap();
        until_js(
            &client,
            "document.body.dataset.current === 'alarms'",
            "the alarm page",
        )
        .await;
        std::fs::write(
            out.join("alarm-management.png"),
            client.screenshot().await.unwrap(),
        )
        .unwrap();
    }

    // --- On a phone (390 px wide) the alarm line stays one line that fits the width, its
    // text drawn at 12 px or more. (Headless Chromium's window is at least 500 px wide,
    // and the rest of the page is the phone layout's business: the line is measured at
    // 390 px itself.)
    let phone = driver.session(390, 844).await;
    log_in_ready(&phone, &site.url, "operator", "operator-vsetin").await;
    until_js(
        &phone,
        "document.getElementById('alarm-line').dataset.priority !== '0'",
        "the alarm line on the phone",
    )
    .await;
    let drawn = js(
        &phone,
        "(() => { const line = document.getElementById('alarm-line'); const kept = line.style.cssText; \
         line.style.flex = 'none'; line.style.width = '390px'; \
         const text = document.getElementById('alarm-line-text'); const size = parseFloat(getComputedStyle(text).fontSize); \
         const result = [line.scrollWidth <= 390, size >= 12, line.getBoundingClientRect().height < 3 * size]; \
         line.style.cssText = kept; return result; })()",
    )
    .await;
    assert_eq!(drawn, json!([true, true, true]), "{drawn}");

    drop(phone);
    drop(client);
    site.stop().await;
}
