//! The remote sorting lab in a real browser (headless Chromium): the station project
//! `examples/sorting-lab` (the sorting PLC and the supervisor on the simulated mechanism,
//! at 30 times real time) and its web HMI with the operator lease. An observer watches
//! and cannot take control; an operator takes the lease, switches to automatic, starts
//! the sorting and sees the balls counted into the shafts; a second operator is refused
//! while the lease is held and takes it once it is released; manual switching is refused
//! in automatic mode; the student tries a program on the Program page (its compile
//! errors shown file:line:col, the supervisor's lock-out in the trial's report), loads it
//! into the lab itself with the lease (refused to a user without it), meets the
//! supervisor there, and puts the lab's own program back; when the PLC link is cut every
//! element blinks.
//!
//! Chromium and chromedriver come from `scripts/install-test-deps.sh`; without them the
//! test says SKIPPED and passes, unless `STANICE_REQUIRE_PEERS=1` (CI).

#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing,
    missing_docs
)]

#[path = "support/chromium.rs"]
mod chromium;
use chromium::{browser_available, click, js, until, Driver};

use std::net::SocketAddr;

use fantoccini::{Client, Locator};
use hmi::{Hmi, HmiOptions, ServeConfig};
use iec60870::time::TimeZonePolicy;
use serde_json::json;
use station::config::Project;
use station::runtime::{Pacing, Runtime, RuntimeOptions, StoreChoice};
use testkit::ports::free_port_range;
use testkit::projects::{copy_project, example};

/// The lab (both PLCs, the mechanism) and its HMI, on free ports, the screens folder
/// copied so that the bookings file lands in a temporary folder.
struct Lab {
    runtime: Option<Runtime>,
    hmi: Option<Hmi>,
    url: String,
    _folder: tempfile::TempDir,
}

impl Lab {
    async fn start(speed: f64) -> Lab {
        let folder = tempfile::tempdir().unwrap();
        let project_folder = copy_project(&example("sorting-lab"), folder.path(), "sorting-lab");
        let project = Project::load(&project_folder)
            .unwrap_or_else(|e| panic!("{e}"))
            .with_port_base(free_port_range(2));
        let zone = project.station.time_zone;
        let runtime = Runtime::start(
            project,
            RuntimeOptions {
                nodes: Vec::new(),
                pacing: Pacing::RealTime { speed },
                start: chrono::Utc::now(),
                store: StoreChoice::Disabled,
                device_kinds: station::device::DeviceKinds::builtin(),
            },
        )
        .await
        .unwrap();
        let top = runtime.project().top_node().unwrap().clone();
        let server = runtime
            .node(&top.name)
            .and_then(|node| node.server.as_ref())
            .unwrap()
            .local_addr();
        let screens = project_folder.join("hmi");
        let mut serve = ServeConfig::default();
        // The trial the `stanice` binary gives its HMI, loading into the lab's SORTER.
        serve.trial = Some(std::sync::Arc::new(sorting::hmi_trial::SortingTrial::live(
            runtime.program_loader(),
            "SORTER",
            "main",
        )));
        let hmi = Hmi::start_with(
            HmiOptions {
                users: screens.join("users.toml"),
                screens,
                connect: vec![server.to_string()],
                common_address: top.common_address,
                listen: SocketAddr::from(([127, 0, 0, 1], 0)),
                store: Some("sqlite::memory:".into()),
                zone: TimeZonePolicy::Zone(zone),
                local_address: None,
                archive: None,
            },
            serve,
        )
        .await
        .unwrap();
        let url = format!("http://{}", hmi.address);
        Lab {
            runtime: Some(runtime),
            hmi: Some(hmi),
            url,
            _folder: folder,
        }
    }

    fn hmi(&self) -> &Hmi {
        self.hmi.as_ref().unwrap()
    }

    async fn stop(mut self) {
        if let Some(hmi) = self.hmi.take() {
            hmi.shutdown().await;
        }
        if let Some(runtime) = self.runtime.take() {
            runtime.shutdown().await;
        }
    }
}

async fn log_in(client: &Client, url: &str, user: &str, password: &str) {
    client.goto(&format!("{url}/")).await.unwrap();
    until(
        client,
        "location.pathname === '/login' && document.getElementById('login-form')",
        "the login page",
    )
    .await;
    until(
        client,
        "!document.getElementById('public').hidden",
        "the link to the public pages",
    )
    .await;
    client
        .find(Locator::Id("username"))
        .await
        .unwrap()
        .send_keys(user)
        .await
        .unwrap();
    client
        .find(Locator::Id("password"))
        .await
        .unwrap()
        .send_keys(password)
        .await
        .unwrap();
    click(client, "#login-button").await;
    until(
        client,
        "location.pathname === '/' && document.body.dataset.ready === 'true' && HMI.wsOpen && HMI.link.up",
        "the application with the live link",
    )
    .await;
    until(
        client,
        "document.querySelector('#mimic svg[data-screen=\"lab\"]') && document.body.dataset.lease",
        "the lab's mimic and the lease bar",
    )
    .await;
}

/// Operates the control `css` through the dialog; the outcome word.
async fn operate(client: &Client, css: &str) -> String {
    click(client, &format!("{css} rect")).await;
    until(
        client,
        "document.getElementById('control-dialog').open && document.getElementById('control-dialog').dataset.step === 'value'",
        "the control dialog",
    )
    .await;
    click(client, "#control-next").await;
    until(
        client,
        "document.getElementById('control-dialog').dataset.step === 'confirm'",
        "the confirmation step",
    )
    .await;
    click(client, "#control-execute").await;
    until(
        client,
        "document.getElementById('control-outcome').dataset.outcome !== 'pending'",
        "the outcome",
    )
    .await;
    let outcome = js(
        client,
        "[document.getElementById('control-outcome').dataset.outcome, document.getElementById('control-detail').textContent]",
    )
    .await;
    click(client, "#control-step-result button").await;
    until(
        client,
        "!document.getElementById('control-dialog').open",
        "the dialog closed",
    )
    .await;
    format!(
        "{} {}",
        outcome[0].as_str().unwrap_or(""),
        outcome[1].as_str().unwrap_or("")
    )
}

/// POSTs `body` (JavaScript) to `path` from the page, as the page's own code does: the
/// status, the error and the outcome's detail.
async fn post(client: &Client, path: &str, body: &str) -> serde_json::Value {
    client
        .execute_async(
            &format!(
                "const done = arguments[arguments.length - 1]; \
                 HMI.post('{path}', {body}).then(r => done([r.status, r.body.error || null, r.body.detail || null]));"
            ),
            Vec::new(),
        )
        .await
        .unwrap()
}

/// Types a program into the Program page's text box.
async fn type_program(client: &Client, name: &str, text: &str) {
    client
        .execute(
            "document.getElementById('program-name').value = arguments[0]; \
             document.getElementById('program-text').value = arguments[1];",
            vec![json!(name), json!(text)],
        )
        .await
        .unwrap();
}

async fn show_lab(client: &Client) {
    client
        .execute("location.hash = '#screen/lab';", Vec::new())
        .await
        .unwrap();
    until(
        client,
        "document.querySelector('#mimic svg[data-screen=\"lab\"]')",
        "the lab's mimic",
    )
    .await;
}

fn text(point: &str) -> String {
    format!("document.querySelector('#mimic text[data-text=\"{point}\"]').textContent")
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn observer_operator_lease_automatic_sorting_and_link_loss() {
    let Some((driver, chromium)) = browser_available() else {
        return;
    };
    let lab = Lab::start(30.0).await;
    let driver = Driver::start(&driver, chromium);
    let url = lab.url.clone();

    // --- The public page, without logging in.
    let observer = driver.session(1280, 800).await;
    observer.goto(&format!("{url}/public/")).await.unwrap();
    until(
        &observer,
        "document.querySelector('h1') && document.querySelector('h1').textContent === 'The remote sorting lab'",
        "the public page",
    )
    .await;

    // --- An observer watches: the lab's state, no Take control, the server says no.
    log_in(&observer, &url, "observer", "observer-lab").await;
    until(
        &observer,
        "document.getElementById('lease-text').textContent === 'control: free'",
        "the lease free",
    )
    .await;
    assert_eq!(
        js(&observer, "document.getElementById('lease-take').hidden").await,
        json!(true)
    );
    let refused = post(&observer, "/api/lease", "{}").await;
    assert_eq!(refused[0], json!(403), "{refused}");

    // --- The operator takes the lease.
    let operator = driver.session(1280, 800).await;
    log_in(&operator, &url, "operator", "operator-lab").await;
    click(&operator, "#lease-take").await;
    until(
        &operator,
        "document.body.dataset.lease === 'yours' && document.getElementById('lease-text').textContent.startsWith('control: you')",
        "the lease taken",
    )
    .await;
    until(
        &observer,
        "document.getElementById('lease-text').textContent === 'control: operator — you observe'",
        "the observer told who controls",
    )
    .await;

    // --- A second operator is refused while the lease is held, in words.
    let student = driver.session(1280, 800).await;
    log_in(&student, &url, "student", "student-lab").await;
    until(
        &student,
        "document.body.dataset.lease === 'other' && document.getElementById('lease-take').hidden",
        "the student sees the lab taken",
    )
    .await;
    let refused = post(&student, "/api/lease", "{}").await;
    assert_eq!(refused[0], json!(409), "{refused}");
    assert!(
        refused[1]
            .as_str()
            .unwrap()
            .contains("controlled by operator"),
        "{refused}"
    );
    let command = post(
        &student,
        "/api/command",
        "{command: 'SORT_Start', value: true}",
    )
    .await;
    assert_eq!(command[0], json!(409), "{command}");
    assert!(
        command[2].as_str().unwrap().contains("operator lease"),
        "{command}"
    );

    // --- Automatic mode; manual switching is then refused by the server.
    let outcome = operate(
        &operator,
        r#"[data-command="MODE_Automatic"][data-command-value="1"]"#,
    )
    .await;
    assert!(outcome.starts_with("executed"), "{outcome}");
    until(
        &operator,
        &format!("{} === 'AUTOMATIC'", text("SORT_Automatic")),
        "automatic mode shown",
    )
    .await;
    let outcome = operate(
        &operator,
        r#"[data-command="MAN_S1"][data-command-value="1"]"#,
    )
    .await;
    assert!(
        outcome.starts_with("refused-authority")
            && outcome.contains("manual switching is refused in automatic mode"),
        "{outcome}"
    );

    // --- Start: the balls are counted into the shafts, two of each colour.
    let outcome = operate(&operator, r#"[data-command="SORT_Start"]"#).await;
    assert!(outcome.starts_with("executed"), "{outcome}");
    until(
        &operator,
        &format!("{} === 'initialising'", text("SORT_State")),
        "the initialisation",
    )
    .await;
    for shaft in 1..=4 {
        let count = text(&format!("SORT_Shaft{shaft}"));
        until(
            &observer,
            &format!("{count} === '2 balls'"),
            &format!("two balls counted into shaft {shaft}"),
        )
        .await;
    }
    until(
        &operator,
        &format!(
            "{} === '1' && {} === 'idle'",
            text("SORT_Sortings"),
            text("SORT_State")
        ),
        "one sorting done",
    )
    .await;
    let colours = js(
        &observer,
        "[1,2,3,4].map(k => document.querySelector(`#mimic rect.shaft-colour[data-point=\"SORT_Colour${k}\"]`).getAttribute('data-value'))",
    )
    .await;
    assert_eq!(colours, json!(["1", "2", "3", "4"]));

    // --- The shafts' colours, chosen together: a repeated colour is forbidden in words and
    // O.K. is not offered (the server refuses it too); four different ones are sent.
    click(&operator, r#"[data-choice="colours"] rect"#).await;
    until(
        &operator,
        "document.getElementById('choice-dialog').open && document.querySelectorAll('#choice-fields select').length === 4",
        "the Choice! window",
    )
    .await;
    assert_eq!(
        js(&operator, "[document.getElementById('choice-message').textContent, [...document.querySelectorAll('#choice-fields select')].map(s => s.value)]").await,
        json!(["Allowed colour combination.", ["1", "2", "3", "4"]])
    );
    let pick = |values: [u8; 4]| {
        format!(
            "(() => {{ const v = {values:?}; document.querySelectorAll('#choice-fields select').forEach((s, i) => {{ s.value = String(v[i]); s.dispatchEvent(new Event('change')); }}); return true; }})()"
        )
    };
    js(&operator, &pick([1, 1, 3, 4])).await;
    assert_eq!(
        js(&operator, "[document.getElementById('choice-message').textContent, document.getElementById('choice-ok').disabled]").await,
        json!(["Forbidden colour combination!", true])
    );
    let refused = post(&operator, "/api/choices/colours", "{values: [1, 1, 3, 4]}").await;
    assert_eq!(refused[0], json!(409), "{refused}");
    assert_eq!(
        refused[1],
        json!("Forbidden colour combination!"),
        "{refused}"
    );
    js(&operator, &pick([4, 3, 2, 1])).await;
    assert_eq!(
        js(&operator, "document.getElementById('choice-ok').disabled").await,
        json!(false)
    );
    click(&operator, "#choice-ok").await;
    until(
        &observer,
        "[1,2,3,4].map(k => document.querySelector(`#mimic rect.shaft-colour[data-point=\"SORT_Colour${k}\"]`).getAttribute('data-value')).join() === '4,3,2,1'",
        "the new colours in every browser",
    )
    .await;

    // --- The operator releases; the student takes the lab.
    click(&operator, "#lease-release").await;
    until(
        &operator,
        "document.body.dataset.lease === 'free'",
        "the lease released",
    )
    .await;
    until(
        &student,
        "!document.getElementById('lease-take').hidden",
        "the student may take the lab",
    )
    .await;
    click(&student, "#lease-take").await;
    until(
        &student,
        "document.body.dataset.lease === 'yours'",
        "the student holds the lease",
    )
    .await;

    // --- The student tries a program on the Program page: one that does not compile is
    // shown with its file:line:col; a careless one sorts nothing and meets the supervisor.
    student
        .execute("location.hash = '#program';", Vec::new())
        .await
        .unwrap();
    until(
        &student,
        "document.body.dataset.current === 'program' && !document.getElementById('nav-program').hidden",
        "the Program page",
    )
    .await;
    let typed = "PROGRAM Broken\nVAR x : INT; END_VAR\nx := y;\nEND_PROGRAM\n";
    type_program(&student, "broken.st", typed).await;
    click(&student, "#program-check").await;
    until(
        &student,
        "document.getElementById('program-verdict').dataset.verdict === 'refused' && document.getElementById('program-diagnostics').textContent.includes('broken.st:3:')",
        "the compiler's diagnostics, file:line:col",
    )
    .await;
    let careless = "PROGRAM Careless\nVAR\n    cS1 AT %QX0.0 : BOOL;\n    t : TON;\nEND_VAR\n    t(IN := TRUE, PT := T#1H);\n    cS1 := t.ET < T#5S;\nEND_PROGRAM\n";
    type_program(&student, "careless.st", careless).await;
    click(&student, "#program-run").await;
    until(
        &student,
        "document.getElementById('program-verdict').dataset.verdict === 'failed'",
        "the trial's verdict",
    )
    .await;
    let report = js(
        &student,
        "document.getElementById('program-report').textContent",
    )
    .await;
    let report = report.as_str().unwrap();
    assert!(
        report.contains("supervisor: S1 locked out: on longer than MaxOnTime"),
        "{report}"
    );
    assert!(report.contains("NOT finished"), "{report}");

    // --- Loaded into the lab itself: refused to the operator (no lease), carried out for
    // the student who holds it; the lab's supervisor locks out S1, which the program
    // holds on (a high command keeps the lock-out, BS-A2); the lab's own program comes
    // back.
    let holder =
        "PROGRAM Holder\nVAR\n    cS1 AT %QX0.0 : BOOL;\nEND_VAR\n    cS1 := TRUE;\nEND_PROGRAM\n";
    let body = json!({"files": [{"name": "holder.st", "text": holder}]}).to_string();
    let refused = post(&operator, "/api/program/load", &body).await;
    assert_eq!(refused[0], json!(409), "{refused:?}");
    assert!(
        refused[2].as_str().unwrap().contains("operator lease"),
        "{refused:?}"
    );
    type_program(&student, "holder.st", holder).await;
    click(&student, "#program-load").await;
    until(
        &student,
        "document.getElementById('program-verdict').dataset.verdict === 'loaded' && document.getElementById('program-verdict').textContent.includes('PROGRAM Holder runs on the lab (SORTER, task main)')",
        "the program loaded into the lab",
    )
    .await;
    let runtime = lab.runtime.as_ref().unwrap();
    let s1_state = || {
        runtime
            .node("SUPERVISOR")
            .and_then(|node| node.points.point("SUP_S1_State"))
            .map(|point| point.value)
    };
    for _ in 0..600 {
        if s1_state() == Some(points::PointValue::Int(3)) {
            break;
        }
        tokio::time::sleep(std::time::Duration::from_millis(50)).await;
    }
    assert_eq!(
        s1_state(),
        Some(points::PointValue::Int(3)),
        "the lab's supervisor locks S1 out"
    );
    student
        .execute("window.confirm = () => true;", Vec::new())
        .await
        .unwrap();
    click(&student, "#program-restore").await;
    until(
        &student,
        "document.getElementById('program-verdict').dataset.verdict === 'loaded' && document.getElementById('program-verdict').textContent.includes('own program runs on SORTER again')",
        "the lab's own program restored",
    )
    .await;
    show_lab(&student).await;

    // --- The PLC link is cut: every element of the mimic blinks.
    lab.hmi().station.set_link(false);
    let all_invalid = "[...document.querySelectorAll('#mimic [data-point], #mimic [data-text]')].every(e => e.getAttribute('data-invalid') === 'true')";
    until(
        &observer,
        all_invalid,
        "every bound element invalid after the link cut",
    )
    .await;
    let not_blinking = js(
        &observer,
        r#"[...document.querySelectorAll('#mimic [data-invalid="true"]')].map(e => getComputedStyle(e).animationName).filter(n => !n.startsWith('lost')).length"#,
    )
    .await;
    assert_eq!(not_blinking, json!(0), "every invalid element blinks");
    lab.hmi().station.set_link(true);
    until(
        &observer,
        "HMI.link.up && !document.querySelector('#mimic [data-invalid]')",
        "valid values again after the link returns",
    )
    .await;

    for client in [&observer, &operator, &student] {
        assert_eq!(
            js(client, "HMI.errors").await,
            json!([]),
            "no script errors"
        );
    }
    for client in [observer, operator, student] {
        client.close().await.unwrap();
    }
    lab.stop().await;
}
