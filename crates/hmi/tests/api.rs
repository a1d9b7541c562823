//! The HMI's API against the running Vsetín station (in process, simulated clock, real
//! IEC 104 on loopback): login and levels, controls with select-before-operate and their
//! audit, live updates over WebSocket, every value invalid when the link is lost, alarms,
//! and bad input refused cleanly.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing
)]

#[path = "support/http.rs"]
mod http_client;
use http_client::{request as http, Client};
use std::path::Path;
use std::time::Duration;

use futures_util::StreamExt as _;
use hmi::{Hmi, HmiOptions};
use iec60870::time::TimeZonePolicy;
use serde_json::{json, Value};
use station::config::Project;
use station::runtime::{Pacing, Runtime, RuntimeOptions, StoreChoice};
use testkit::ports::free_port_range;
use testkit::projects::vsetin;

/// A screens folder for the test: the top node's points, three users, one screen, and
/// `extra` appended to hmi.toml. QF1 of RH2 needs the control authority, as in Vsetín's
/// own hmi.toml; the authority command itself is left at the default level 5.
fn screens(project: &Project, dir: &Path, extra: &str) {
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
        r#"title = "Vsetín test"
default_control_level = 5
[[screen]]
id = "rh"
title = "RH"
file = "rh.svg"
[[control]]
command = "RH2_VypnoutQF1"
level = 5
select = true
local_point = "RH2_P1_SA1_Mistne"
authority = { point = "RDRT_SP21_HMI_Mistne" }
[[control]]
command = "RH2_ZapnoutQF1"
level = 5
select = true
local_point = "RH2_P1_SA1_Mistne"
authority = { point = "RDRT_SP21_HMI_Mistne" }
[[alarm]]
point = "RH2_P1_FV1_Prepetova_ochrana"
priority = 3
text = "RH2 surge arrester"
acknowledge = true
"#
        .to_owned()
            + extra,
    )
    .unwrap();
    std::fs::write(
        dir.join("rh.svg"),
        r#"<svg xmlns="http://www.w3.org/2000/svg"><rect data-point="RH2_V1_FA1_Zapnut"/></svg>"#,
    )
    .unwrap();
    let mut users = hmi::users::Users::load(&dir.join("users.toml")).unwrap();
    users.add("operator", 5, "operator-pass").unwrap();
    users.add("viewer", 0, "viewer-pass").unwrap();
}

struct Setup {
    runtime: Runtime,
    hmi: Hmi,
    _dir: tempfile::TempDir,
}

async fn setup() -> Setup {
    setup_with("").await
}

async fn setup_with(extra_toml: &str) -> Setup {
    let project = Project::load(&vsetin()).unwrap();
    let base = free_port_range(23);
    let project = project.with_port_base(base);
    let dir = tempfile::tempdir().unwrap();
    screens(&project, dir.path(), extra_toml);
    let runtime = Runtime::start(
        project,
        RuntimeOptions {
            nodes: Vec::new(),
            pacing: Pacing::Manual,
            start: chrono::Utc::now(),
            store: StoreChoice::Disabled,
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
        common_address: iec60870::asdu::CommonAddress::new(1),
        listen: "127.0.0.1:0".parse().unwrap(),
        store: Some("sqlite::memory:".into()),
        zone: TimeZonePolicy::Zone(chrono_tz::Europe::Prague),
        local_address: Some([127, 0, 0, 2].into()),
        archive: None,
    })
    .await
    .unwrap();
    Setup {
        runtime,
        hmi,
        _dir: dir,
    }
}

impl Client {
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

async fn until(what: &str, mut check: impl AsyncFnMut() -> bool) {
    for _ in 0..300 {
        if check().await {
            return;
        }
        tokio::time::sleep(Duration::from_millis(20)).await;
    }
    panic!("timed out waiting until {what}");
}

/// Takes the control authority to this HMI (command 2001 from the HMI's link) and waits
/// until the station reports it (RDRT's "HMI local" point TRUE).
async fn take_authority(s: &Setup, operator: &Client) {
    let taken = operator
        .post(
            "/api/command",
            json!({"command": "RDRT_HMI_Mistne", "value": true}),
        )
        .await;
    assert_eq!(taken.json()["outcome"], "executed", "{}", taken.body);
    for _ in 0..50 {
        s.runtime.advance(Duration::from_millis(100)).await.unwrap();
        if operator.point("RDRT_SP21_HMI_Mistne").await["value"] == json!(true) {
            return;
        }
    }
    panic!("the station never reported the authority with this HMI");
}

/// Issue 11: in Vsetín's own hmi.toml every board control (the functional elements of the
/// board views RH2, RZZ, RH1.2, RZS2 and RZS/RDA, spec 9.2) needs the authority with this HMI; the
/// authority command itself and the lighting boards' settings (the dispatch's own inputs,
/// spec 4.2) do not.
#[test]
fn vsetin_board_controls_need_the_control_authority() {
    let config = hmi::config::HmiConfig::load(&vsetin().join("hmi")).unwrap();
    let commands: Vec<&str> = config
        .points
        .iter()
        .filter(|p| p.type_id.is_command())
        .map(|p| p.name.as_str())
        .collect();
    let board = |name: &str| {
        ["RH2_", "RZZ_", "RH12_", "RZS2_", "RDA_"]
            .iter()
            .any(|b| name.starts_with(b))
    };
    assert_eq!(
        commands.iter().filter(|c| board(c)).count(),
        9,
        "QF1 open/close of RH2, RZZ, RH1.2 and RZS2, the RDA test run: {commands:?}"
    );
    for command in commands {
        let authority = config.control(command).authority;
        if board(command) {
            let authority = authority.unwrap_or_else(|| panic!("{command} needs the authority"));
            assert_eq!(authority.point, "RDRT_SP21_HMI_Mistne", "{command}");
            assert!(authority.state, "{command}: TRUE is HMI-local");
        } else {
            assert_eq!(authority, None, "{command} needs no authority");
        }
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn operator_controls_viewer_is_refused_and_both_are_audited() {
    let s = setup().await;
    let operator = Client::login(s.hmi.address, "operator", "operator-pass").await;
    until("the station values", async || {
        operator.point("RH2_P1_KHU3_Napeti_na_pripojeni").await["value"] == json!(true)
    })
    .await;
    let controls = operator.get("/api/controls").await.json();
    let open = controls
        .as_array()
        .unwrap()
        .iter()
        .find(|c| c["command"] == "RH2_VypnoutQF1")
        .unwrap();
    assert_eq!(open["select"], json!(true));
    assert_eq!(open["allowed"], json!(true));

    // A board control needs the control authority with this HMI (railway spec 9.2).
    take_authority(&s, &operator).await;

    // Operator: select-before-operate through RDRT -> RH1.1 -> RH2, QF1 opens.
    let reply = operator
        .post(
            "/api/command",
            json!({"command": "RH2_VypnoutQF1", "value": true}),
        )
        .await;
    assert_eq!(reply.json()["outcome"], "executed", "{}", reply.body);
    for _ in 0..50 {
        s.runtime.advance(Duration::from_millis(100)).await.unwrap();
        if operator.point("RH2_P1_KHU3_Napeti_na_pripojeni").await["value"] == json!(false) {
            break;
        }
    }
    assert_eq!(
        operator.point("RH2_P1_KHU3_Napeti_na_pripojeni").await["value"],
        json!(false)
    );

    // Viewer: sees everything, controls nothing.
    let viewer = Client::login(s.hmi.address, "viewer", "viewer-pass").await;
    assert_eq!(
        viewer.point("RH2_P1_KHU3_Napeti_na_pripojeni").await["value"],
        json!(false)
    );
    let reply = viewer
        .post(
            "/api/command",
            json!({"command": "RH2_ZapnoutQF1", "value": true}),
        )
        .await;
    assert_eq!(reply.status, 403);
    assert_eq!(reply.json()["outcome"], "refused-permission");

    // Local mode at the board: the station refuses, the HMI says why.
    s.runtime.operate("selector RH2 local").await.unwrap();
    for _ in 0..50 {
        s.runtime.advance(Duration::from_millis(100)).await.unwrap();
        if operator.point("RH2_P1_SA1_Mistne").await["value"] == json!(true) {
            break;
        }
    }
    let reply = operator
        .post(
            "/api/command",
            json!({"command": "RH2_ZapnoutQF1", "value": true}),
        )
        .await;
    assert_eq!(reply.json()["outcome"], "refused-local", "{}", reply.body);

    // The event list has the commands with the users' names, and the value changes.
    s.hmi.station.recorder().flush().await;
    let events = operator.get("/api/events?kind=command").await.json();
    let commands: Vec<(String, String, String)> = events["items"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| {
            (
                e["user"].as_str().unwrap().into(),
                e["point"].as_str().unwrap().into(),
                e["outcome"].as_str().unwrap().into(),
            )
        })
        .collect();
    assert!(
        commands.contains(&(
            "operator".into(),
            "RH2_VypnoutQF1".into(),
            "executed".into()
        )),
        "{commands:?}"
    );
    assert!(
        commands.contains(&(
            "viewer".into(),
            "RH2_ZapnoutQF1".into(),
            "refused-permission".into()
        )),
        "{commands:?}"
    );
    assert!(
        commands.contains(&(
            "operator".into(),
            "RH2_ZapnoutQF1".into(),
            "refused-local".into()
        )),
        "{commands:?}"
    );
    let by_viewer = operator.get("/api/events?user=viewer").await.json();
    assert_eq!(by_viewer["items"].as_array().unwrap().len(), 1);
    let values = operator
        .get("/api/events?kind=value&point=RH2_P1_KHU3*")
        .await
        .json();
    assert!(values["items"]
        .as_array()
        .unwrap()
        .iter()
        .any(|e| e["value"] == json!(false)));
    // Paging: one item per page walks the whole list without repeats.
    let mut seen = std::collections::HashSet::new();
    let mut cursor: Option<String> = None;
    for _ in 0..10_000 {
        let path = match &cursor {
            Some(c) => format!("/api/events?limit=1&cursor={c}"),
            None => "/api/events?limit=1".to_owned(),
        };
        let page = operator.get(&path).await.json();
        for item in page["items"].as_array().unwrap() {
            assert!(
                seen.insert(item["id"].as_str().unwrap().to_owned()),
                "repeated {item}"
            );
        }
        match page["next"].as_str() {
            Some(next) => cursor = Some(next.to_owned()),
            None => break,
        }
    }
    let all = operator.get("/api/events?limit=1000").await.json();
    assert_eq!(seen.len(), all["items"].as_array().unwrap().len());
    s.hmi.shutdown().await;
    s.runtime.shutdown().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn bad_input_is_refused_cleanly() {
    let s = setup().await;
    let address = s.hmi.address;
    let viewer = Client::login(address, "viewer", "viewer-pass").await;
    // Wrong passwords, then the rate limit (even the right password is refused then, and
    // from this address for any user).
    for _ in 0..5 {
        let reply = http(
            address,
            "POST",
            "/api/login",
            &[],
            r#"{"username":"operator","password":"guess"}"#,
        )
        .await;
        assert_eq!(reply.status, 401);
    }
    let reply = http(
        address,
        "POST",
        "/api/login",
        &[],
        r#"{"username":"operator","password":"operator-pass"}"#,
    )
    .await;
    assert_eq!(reply.status, 429);
    assert!(reply.json()["retry_after_s"].as_u64().unwrap() > 0);
    // Malformed and oversized bodies.
    assert_eq!(
        http(address, "POST", "/api/login", &[], "{not json")
            .await
            .status,
        400
    );
    let huge = format!(r#"{{"username":"{}","password":"x"}}"#, "a".repeat(100_000));
    assert_eq!(
        http(address, "POST", "/api/login", &[], &huge).await.status,
        413
    );
    let other = http(
        address,
        "POST",
        "/api/login",
        &[],
        r#"{"username":"viewer","password":"viewer-pass"}"#,
    )
    .await;
    assert_eq!(other.status, 429);
    // A session opened before the lockout keeps working.
    // No session, forged CSRF token, unknown command and screen.
    assert_eq!(
        http(address, "GET", "/api/points", &[], "").await.status,
        401
    );
    assert_eq!(http(address, "GET", "/", &[], "").await.status, 303);
    let forged = http(
        address,
        "POST",
        "/api/command",
        &[("Cookie", &viewer.cookie), ("X-CSRF-Token", "0000")],
        r#"{"command":"RH2_VypnoutQF1","value":true}"#,
    )
    .await;
    assert_eq!(forged.status, 403);
    let missing = http(
        address,
        "POST",
        "/api/command",
        &[("Cookie", &viewer.cookie)],
        r#"{"command":"RH2_VypnoutQF1","value":true}"#,
    )
    .await;
    assert_eq!(missing.status, 403);
    assert_eq!(
        viewer
            .post("/api/command", json!({"command": "NO_SUCH", "value": 1}))
            .await
            .status,
        404
    );
    assert_eq!(
        viewer
            .post(
                "/api/command",
                json!({"command": "RH2_VypnoutQF1", "value": "open"})
            )
            .await
            .status,
        400
    );
    assert_eq!(viewer.get("/api/screens/nothing").await.status, 404);
    assert_eq!(viewer.get("/api/trend?point=NO_SUCH").await.status, 404);
    assert_eq!(viewer.get("/api/trends").await.json(), json!([]));
    // Read-only: no alarm changes either.
    assert_eq!(
        viewer
            .post("/api/alarms/0/acknowledge", json!({}))
            .await
            .status,
        403
    );
    // Read-only: no alarm changes either.
    assert_eq!(
        viewer
            .post("/api/alarms/0/acknowledge", json!({}))
            .await
            .status,
        403
    );
    assert_eq!(viewer.get("/api/events?cursor=garbage").await.status, 400);
    // A request replayed after logout finds no session.
    assert_eq!(viewer.post("/api/logout", json!({})).await.status, 200);
    assert_eq!(
        viewer
            .post(
                "/api/command",
                json!({"command": "RH2_VypnoutQF1", "value": true})
            )
            .await
            .status,
        401
    );
    // The server still serves.
    assert_eq!(http(address, "GET", "/login", &[], "").await.status, 200);
    s.hmi.shutdown().await;
    s.runtime.shutdown().await;
}

/// A live message has exactly the fields its `type` has in `hmi::live::LiveMessage` (the
/// wire format app.js reads).
fn assert_live_message(message: &Value) {
    let fields: &[&str] = match message["type"].as_str() {
        Some("snapshot") => &["alarms", "link", "points", "type"],
        Some("point") => &[
            "description",
            "iec_type",
            "invalid",
            "ioa",
            "name",
            "quality",
            "time",
            "type",
            "value",
        ],
        Some("link") => &["address", "type", "up"],
        Some("alarm") => &[
            "acknowledged",
            "active",
            "cleared",
            "consequence_of",
            "id",
            "needs_acknowledgement",
            "oneshot",
            "out_of_service",
            "point",
            "priority",
            "raised",
            "shelve_reason",
            "shelved",
            "shelved_by",
            "shelved_until",
            "suppressed",
            "system",
            "text",
            "type",
        ],
        Some("command") => &["command", "outcome", "type", "user", "value"],
        _ => panic!("a live message of no known type: {message}"),
    };
    let mut keys: Vec<&str> = message
        .as_object()
        .unwrap()
        .keys()
        .map(String::as_str)
        .collect();
    keys.sort_unstable();
    assert_eq!(keys, fields, "{message}");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn live_updates_alarms_and_every_value_invalid_on_link_loss() {
    let s = setup().await;
    let operator = Client::login(s.hmi.address, "operator", "operator-pass").await;
    until("link up", async || {
        operator.get("/api/points").await.json()["link"]["up"] == json!(true)
    })
    .await;
    let mut request =
        tokio_tungstenite::tungstenite::client::IntoClientRequest::into_client_request(format!(
            "ws://{}/api/live",
            s.hmi.address
        ))
        .unwrap();
    request
        .headers_mut()
        .insert("Cookie", operator.cookie.parse().unwrap());
    let (mut socket, _) = tokio_tungstenite::connect_async(request).await.unwrap();
    let mut next = async || -> Value {
        let message = tokio::time::timeout(Duration::from_secs(10), socket.next())
            .await
            .unwrap()
            .unwrap()
            .unwrap();
        let message: Value = serde_json::from_str(message.to_text().unwrap()).unwrap();
        assert_live_message(&message);
        message
    };
    let snapshot = next().await;
    assert_eq!(snapshot["type"], "snapshot");
    assert!(snapshot["points"].as_array().unwrap().len() > 400);

    // A surge arrester trips at the board: the point and its alarm arrive live.
    s.runtime.operate("surge-arrester RH2_FV1").await.unwrap();
    s.runtime.advance(Duration::from_millis(200)).await.unwrap();
    let (mut point_seen, mut alarm_seen) = (false, false);
    for _ in 0..2000 {
        let message = next().await;
        if message["type"] == "point"
            && message["name"] == "RH2_P1_FV1_Prepetova_ochrana"
            && message["value"] == json!(true)
        {
            point_seen = true;
        }
        if message["type"] == "alarm" && message["active"] == json!(true) {
            alarm_seen = true;
        }
        if point_seen && alarm_seen {
            break;
        }
    }
    assert!(point_seen && alarm_seen);
    let alarms = operator.get("/api/alarms").await.json();
    let id = alarms[0]["id"].as_u64().unwrap();
    assert_eq!(
        operator
            .post(&format!("/api/alarms/{id}/acknowledge"), json!({}))
            .await
            .json()["acknowledged"],
        json!(true)
    );
    assert!(operator
        .post(&format!("/api/alarms/{id}/shelve"), json!({"minutes": 30}))
        .await
        .json()["shelved_until"]
        .is_string());

    // The HMI loses the station: link down, and every value invalid at once.
    s.hmi.station.set_link(false);
    let mut invalid = std::collections::HashSet::new();
    let mut link_down = false;
    let total = snapshot["points"].as_array().unwrap().len();
    for _ in 0..5000 {
        let message = next().await;
        if message["type"] == "link" && message["up"] == json!(false) {
            link_down = true;
        }
        if link_down && message["type"] == "point" && message["invalid"] == json!(true) {
            invalid.insert(message["name"].as_str().unwrap().to_owned());
        }
        // Every point that was valid is re-sent invalid (the few never valid need not be).
        if link_down && invalid.len() + 5 >= total {
            break;
        }
    }
    assert!(link_down);
    let points = operator.get("/api/points").await.json();
    assert!(points["points"]
        .as_array()
        .unwrap()
        .iter()
        .all(|p| p["invalid"] == json!(true)));
    assert!(
        invalid.len() + 5 >= total,
        "{} of {total} re-sent invalid",
        invalid.len()
    );
    // Back: values valid again after the interrogation.
    s.hmi.station.set_link(true);
    until("valid again", async || {
        operator.point("RH2_V1_FA1_Zapnut").await["invalid"] == json!(false)
    })
    .await;
    s.hmi.shutdown().await;
    s.runtime.shutdown().await;
}

/// Railway spec 9.2: board controls work only while the control authority is with this
/// HMI (RDRT's "HMI local" point, set by command 2001 from the HMI's link). The HMI
/// refuses them itself otherwise, audits the refusal and says why; a command it sends is
/// in the store (write-ahead, then its outcome) before the user hears the outcome.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn board_controls_need_the_control_authority_and_are_audited_before_the_outcome() {
    let s = setup_with(
        r#"
[[control]]
command = "RZZ_VypnoutQF1"
level = 5
select = true
authority = { point = "RDRT_SP21_HMI_Mistne" }
"#,
    )
    .await;
    let operator = Client::login(s.hmi.address, "operator", "operator-pass").await;
    until("the authority point", async || {
        operator.point("RDRT_SP21_HMI_Mistne").await["invalid"] == json!(false)
    })
    .await;
    assert_eq!(
        operator.point("RDRT_SP21_HMI_Mistne").await["value"],
        json!(false),
        "the station starts with the authority remote"
    );
    let refused = operator
        .post(
            "/api/command",
            json!({"command": "RZZ_VypnoutQF1", "value": true}),
        )
        .await;
    assert_eq!(refused.status, 409, "{}", refused.body);
    assert_eq!(refused.json()["outcome"], "refused-authority");
    let events = operator.get("/api/events?kind=command").await.json();
    let refusal = events["items"]
        .as_array()
        .unwrap()
        .iter()
        .find(|e| e["point"] == "RZZ_VypnoutQF1")
        .unwrap_or_else(|| panic!("refusal not audited: {events}"));
    assert_eq!(refusal["outcome"], "refused-authority");
    assert_eq!(refusal["user"], "operator");
    assert!(refusal["detail"]
        .as_str()
        .unwrap()
        .contains("control authority"));

    // The authority taken to this HMI (command 2001 from the HMI's link).
    take_authority(&s, &operator).await;
    let executed = operator
        .post(
            "/api/command",
            json!({"command": "RZZ_VypnoutQF1", "value": true}),
        )
        .await;
    assert_eq!(executed.json()["outcome"], "executed", "{}", executed.body);
    // No flush here: the positive outcome was only reported once both records were in.
    let events = operator
        .get("/api/events?kind=command&point=RZZ_VypnoutQF1")
        .await
        .json();
    let outcomes: Vec<&str> = events["items"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| e["outcome"].as_str().unwrap())
        .collect();
    assert_eq!(
        outcomes,
        ["executed", "sent", "refused-authority"],
        "{events}"
    );
    s.hmi.shutdown().await;
    s.runtime.shutdown().await;
}
