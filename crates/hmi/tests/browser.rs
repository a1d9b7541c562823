//! The web HMI in a real browser: headless Chromium driven over WebDriver (`fantoccini`
//! against Debian's `chromedriver`), against the Vsetín station running in this process
//! (the station runtime with every node and the plant simulation, as `stanice demo` runs
//! it) and the HMI library connected to its top controller RDRT from 127.0.0.2, the
//! address of the station's HMI link.
//!
//! What a person would do and see: log in (and fail with a wrong password), watch a breaker
//! change when the plant trips it, be refused QF1 of RH2 while the control authority is
//! with the dispatch (told in words, nothing sent), see it taken to this HMI by a user of
//! level 7 at another desk, operate QF1 through the control dialog and read
//! the outcome, find that command in the event list under the user's name and page back
//! through the history, zoom a trend, acknowledge and shelve a priority-1 alarm (badge and
//! sound), watch every value turn invalid and blink when the station link is cut (and when
//! the browser's own live connection drops, until it reconnects), open a malicious mimic
//! and find that nothing of it runs or stays in the page; as the read-only user,
//! see the controls disabled, be refused by the server and get no alarm buttons; and be
//! told to wait after guessing passwords. One station and one browser for all of it, in
//! about ten seconds.
//!
//! Chromium and chromedriver come from `scripts/install-test-deps.sh`. Without them the
//! tests say SKIPPED and pass, unless `STANICE_REQUIRE_PEERS=1` (set by `scripts/test.sh`,
//! hence in CI), where a missing browser fails them.
//!
//! `cargo test -p hmi --test browser -- --ignored screenshots` writes the PNGs of
//! `docs/screenshots/` (run by hand; see the README's "Web HMI").

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
use chromium::{browser_available, click, js, until, Driver};
use site::Site;
use std::time::{Duration, Instant};

use chrono::{DateTime, Utc};
use fantoccini::{Client, Locator};
use serde_json::{json, Value};
use testkit::projects::vsetin;
use testkit::repository_root;

/// A mimic written to do harm, as a careless or hostile drawing tool might: script
/// elements, event handlers, `javascript:`/`data:` links, and SMIL that would rewrite a
/// link into `javascript:` after the sanitiser looked (docs/HMI.md, "SVG bindings"). Each
/// payload records itself in `window.pwned` (and some call `alert`). A harmless binding,
/// a screen link and a harmless animation must survive.
const MALICIOUS_SVG: &str = r##"<svg xmlns="http://www.w3.org/2000/svg" xmlns:xlink="http://www.w3.org/1999/xlink"
     width="600" height="300" viewBox="0 0 600 300"
     onload="(window.pwned = window.pwned || []).push('svg onload'); alert('onload')">
  <script>(window.pwned = window.pwned || []).push('script')</script>
  <a id="evil-set"><set attributeName="href" to="javascript:(window.pwned = window.pwned || []).push('set href'); alert('set')"/>
    <text x="10" y="30" class="label">set href</text></a>
  <a id="evil-animate" href="#screen/malicious"><animate attributeName="href" values="javascript:(window.pwned = window.pwned || []).push('animate href')" dur="0.1s" fill="freeze"/>
    <text x="10" y="60" class="label">animate href</text></a>
  <a id="evil-xlink" xlink:href="javascript:(window.pwned = window.pwned || []).push('xlink href')"><text x="10" y="90" class="label">xlink href</text></a>
  <a id="evil-data" href="data:text/html,&lt;script&gt;alert('data')&lt;/script&gt;"><text x="10" y="120" class="label">data URL</text></a>
  <a id="evil-spaced" href=" java&#9;script:(window.pwned = window.pwned || []).push('spaced')"><text x="10" y="150" class="label">spaced scheme</text></a>
  <rect id="evil-on" x="200" y="10" width="60" height="30" class="box"
        onclick="(window.pwned = window.pwned || []).push('onclick')" onmouseover="(window.pwned = window.pwned || []).push('onmouseover')">
    <set attributeName="onclick" to="(window.pwned = window.pwned || []).push('set onclick')"/>
    <animate attributeName="ONMOUSEOVER" values="(window.pwned = window.pwned || []).push('animate on')" dur="0.1s" fill="freeze"/>
  </rect>
  <animateTransform id="evil-transform" attributeName="xlink:href" type="translate" values="javascript:alert('transform')" dur="0.1s"/>
  <image id="evil-image" x="300" y="10" width="10" height="10" href="no-such-image.png" onerror="(window.pwned = window.pwned || []).push('onerror')"/>
  <foreignObject x="0" y="0" width="10" height="10"><iframe xmlns="http://www.w3.org/1999/xhtml" src="javascript:alert('iframe')"></iframe></foreignObject>
  <rect id="good-breaker" x="200" y="100" width="30" height="30" class="breaker" data-point="RH2_V1_FA1_Zapnut"/>
  <text id="good-text" x="250" y="120" class="value" data-text="RDRT_SP21_HMI_Mistne" data-on="LOCAL" data-off="REMOTE"></text>
  <a id="good-link" href="#screen/rh2"><text x="200" y="180" class="label">to RH2</text></a>
  <rect id="good-animation" x="400" y="100" width="30" height="30" class="box">
    <animate attributeName="opacity" values="1;0.5;1" dur="0.2s" repeatCount="indefinite"/>
  </rect>
  <rect id="lab-level" x="500" y="150" width="20" height="100" class="box" data-level="RH2_V1_FA1.1" data-min="0" data-max="1"/>
  <rect id="lab-car" x="530" y="240" width="10" height="10" class="box" data-position="RH2_V1_FA1.1" data-min="0" data-max="1" data-dy="-100"/>
  <line id="lab-valve" x1="560" y1="200" x2="590" y2="200" class="label" data-rotate="RH2_V1_FA1.1" data-min="0" data-max="1" data-angle-max="90" data-cx="560" data-cy="200"/>
  <text id="lab-tripped" x="500" y="280" class="label" data-visible="RH2_V1_FA1.1" data-visible-when="off">FA1.1 open</text>
  <rect id="lab-meter" x="470" y="150" width="20" height="100" class="box" data-level="RZZ_U" data-max="500"/>
</svg>
"##;

/// A copy of the Vsetín screens folder with one more screen, `malicious`.
fn screens_with_malicious_mimic() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    let source = vsetin().join("hmi");
    for entry in std::fs::read_dir(&source).unwrap() {
        let entry = entry.unwrap();
        if entry.file_type().unwrap().is_file() {
            std::fs::copy(entry.path(), dir.path().join(entry.file_name())).unwrap();
        }
    }
    let mut toml = std::fs::read_to_string(dir.path().join("hmi.toml")).unwrap();
    toml.push_str(
        "\n[[screen]]\nid = \"malicious\"\ntitle = \"Malicious\"\nfile = \"malicious.svg\"\n",
    );
    std::fs::write(dir.path().join("hmi.toml"), toml).unwrap();
    std::fs::write(dir.path().join("malicious.svg"), MALICIOUS_SVG).unwrap();
    dir
}

// ---------------------------------------------------------------------------- helpers

/// Logs in through the login page's form.
async fn log_in(client: &Client, url: &str, user: &str, password: &str) {
    client.goto(&format!("{url}/")).await.unwrap();
    until(
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
    click(client, "#login-button").await;
}

/// Logs in and waits for the application with live, valid values.
async fn log_in_ready(client: &Client, url: &str, user: &str, password: &str) {
    log_in(client, url, user, password).await;
    until(
        client,
        "location.pathname === '/' && document.body.dataset.ready === 'true'",
        "the application page",
    )
    .await;
    until(
        client,
        "HMI.wsOpen && HMI.link.up && HMI.points.size > 400",
        "the live snapshot with the station link up",
    )
    .await;
}

async fn show_screen(client: &Client, id: &str) {
    client
        .execute(&format!("location.hash = '#screen/{id}';"), Vec::new())
        .await
        .unwrap();
    until(
        client,
        &format!("document.querySelector('#mimic svg[data-screen=\"{id}\"]')"),
        &format!("screen {id}"),
    )
    .await;
}

/// The attribute of the first element matching `css`, through the DOM.
async fn attribute(client: &Client, css: &str, name: &str) -> Value {
    js(client, &format!("(document.querySelector({css:?}) || {{getAttribute: () => 'MISSING'}}).getAttribute({name:?})")).await
}

// ---------------------------------------------------------------------------- the tests

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn operator_and_viewer_in_a_real_browser() {
    let Some((driver, chromium)) = browser_available() else {
        return;
    };
    let started = Instant::now();
    let screens = screens_with_malicious_mimic();
    let site = Site::start_with(Utc::now(), 1.0, screens.path().to_path_buf()).await;
    let driver = Driver::start(&driver, chromium);
    let client = driver.session(1280, 800).await;
    let url = site.url.clone();
    let mut timings = Vec::new();

    // --- Login: a wrong password is refused in words, the right one opens the HMI.
    log_in(&client, &url, "operator", "not-the-password").await;
    until(&client, "document.getElementById('login-message').textContent.includes('Wrong user name or password')", "the wrong-password message").await;
    log_in_ready(&client, &url, "operator", "operator-vsetin").await;
    assert_eq!(
        js(&client, "document.getElementById('user-name').textContent").await,
        json!("operator")
    );
    assert_eq!(
        js(&client, "document.getElementById('user-level').textContent").await,
        json!("level 5")
    );
    assert_eq!(attribute(&client, "#link", "data-state").await, json!("up"));
    timings.push(("logged in, live", started.elapsed()));

    // --- A breaker trips in the plant: the RH2 panel shows FA1.1 open.
    show_screen(&client, "rh2").await;
    let fa11 = r#"document.querySelector('#mimic rect.breaker[data-point="RH2_V1_FA1.1"]')"#;
    until(
        &client,
        &format!(
            "{fa11}.getAttribute('data-value') === 'on' && !{fa11}.hasAttribute('data-invalid')"
        ),
        "FA1.1 closed and valid",
    )
    .await;
    site.operate("breaker-tripped RH2_FA1.1").await;
    let took = until(
        &client,
        &format!("{fa11}.getAttribute('data-value') === 'off'"),
        "FA1.1 shown open after the trip",
    )
    .await;
    timings.push(("breaker trip shown", took));

    // Hovering a bound element tells its point.
    let hover = js(
        &client,
        &format!(
            "(() => {{ const e = {fa11}; const r = e.getBoundingClientRect(); \
             e.dispatchEvent(new PointerEvent('pointermove', {{bubbles: true, clientX: r.left + 2, clientY: r.top + 2}})); \
             const i = document.getElementById('point-info'); return [i && !i.hidden, i && i.textContent]; }})()"
        ),
    )
    .await;
    assert_eq!(hover[0], json!(true), "point information shows: {hover}");
    assert!(
        hover[1].as_str().unwrap().contains("RH2_V1_FA1.1")
            && hover[1].as_str().unwrap().contains("IOA 282"),
        "{hover}"
    );

    // --- The control authority is REMOTE (dispatch; the station starts so): a board
    // control is refused by the HMI itself, told in words, audited, and nothing is sent.
    let qf1_now = r#"document.querySelector('#mimic rect.breaker[data-point="RH2_P1_KHU3_Napeti_na_pripojeni"]').getAttribute('data-value')"#;
    let authority_text =
        r#"document.querySelector('#mimic text[data-text="RDRT_SP21_HMI_Mistne"]').textContent"#;
    until(
        &client,
        &format!("{qf1_now} === 'on' && {authority_text} === 'Control authority: REMOTE dispatch'"),
        "QF1 closed and the authority shown as remote",
    )
    .await;
    click(&client, r#"[data-command="RH2_VypnoutQF1"] rect"#).await;
    until(&client, "document.getElementById('control-dialog').open && document.getElementById('control-dialog').dataset.step === 'value'", "the control dialog").await;
    click(&client, "#control-next").await;
    until(
        &client,
        "document.getElementById('control-dialog').dataset.step === 'confirm'",
        "the confirmation step",
    )
    .await;
    click(&client, "#control-execute").await;
    until(
        &client,
        "document.getElementById('control-outcome').dataset.outcome !== 'pending'",
        "the refusal",
    )
    .await;
    let outcome = js(&client, "[document.getElementById('control-outcome').dataset.outcome, document.getElementById('control-outcome').textContent, document.getElementById('control-detail').textContent]").await;
    assert_eq!(outcome[0], json!("refused-authority"), "outcome: {outcome}");
    assert!(
        outcome[1]
            .as_str()
            .unwrap()
            .contains("refused: the control authority is not with this HMI"),
        "the refusal in words: {outcome}"
    );
    assert!(
        outcome[2]
            .as_str()
            .unwrap()
            .contains("RDRT_SP21_HMI_Mistne"),
        "the detail names the authority point: {outcome}"
    );
    // Nothing changed: the HMI sent nothing (the audit has the refusal and no `sent`
    // record, which precedes every command that leaves), and QF1 is still closed.
    let audit = client
        .execute_async(
            "const done = arguments[arguments.length - 1]; \
             HMI.api('/api/events?kind=command&point=RH2_VypnoutQF1').then(r => done(r.items.map(e => [e.outcome, e.user, e.detail])));",
            Vec::new(),
        )
        .await
        .unwrap();
    assert_eq!(audit.as_array().unwrap().len(), 1, "{audit}");
    assert_eq!(audit[0][0], json!("refused-authority"), "{audit}");
    assert_eq!(audit[0][1], json!("operator"), "{audit}");
    assert!(
        audit[0][2].as_str().unwrap().contains("control authority"),
        "{audit}"
    );
    assert_eq!(js(&client, qf1_now).await, json!("on"), "QF1 still closed");
    click(&client, "#control-step-result button").await;
    until(
        &client,
        "!document.getElementById('control-dialog').open",
        "the dialog closed",
    )
    .await;

    // --- The authority is taken to this HMI through the supply screen, by a user allowed
    // to (level 7; the operator's 5 is not: asserted below) at another desk. The
    // operator's board view follows live.
    let leader = driver.session(1280, 800).await;
    log_in_ready(&leader, &url, "admin", "admin-vsetin").await;
    show_screen(&leader, "supply").await;
    click(
        &leader,
        r#"[data-command="RDRT_HMI_Mistne"][data-command-value="1"] rect"#,
    )
    .await;
    until(
        &leader,
        "document.getElementById('control-dialog').open && document.getElementById('control-dialog').dataset.step === 'value'",
        "the authority dialog",
    )
    .await;
    click(&leader, "#control-next").await;
    until(
        &leader,
        "document.getElementById('control-dialog').dataset.step === 'confirm'",
        "the authority confirmation",
    )
    .await;
    click(&leader, "#control-execute").await;
    until(
        &leader,
        "document.getElementById('control-outcome').dataset.outcome === 'executed'",
        "the authority switched",
    )
    .await;
    until(
        &leader,
        r#"document.querySelector('#mimic rect.authority').getAttribute('data-value') === 'on'"#,
        "the authority shown as local on the supply screen",
    )
    .await;
    assert_eq!(
        js(&leader, "HMI.errors").await,
        json!([]),
        "script errors in the authority holder's page"
    );
    leader.close().await.unwrap();
    until(
        &client,
        &format!("{authority_text} === 'Control authority: LOCAL (this HMI)'"),
        "the operator's board view showing the authority local",
    )
    .await;

    // --- Operate QF1 (open) through the dialog: value, confirmation, outcome in words.
    let qf1 = r#"document.querySelector('#mimic rect.breaker[data-point="RH2_P1_KHU3_Napeti_na_pripojeni"]')"#;
    until(
        &client,
        &format!("{qf1}.getAttribute('data-value') === 'on'"),
        "QF1 closed (voltage behind it)",
    )
    .await;
    assert_eq!(
        js(&client, r#"document.querySelector('[data-command="RH2_VypnoutQF1"]').classList.contains('disabled')"#).await,
        json!(false),
        "the operator (level 5) may open QF1"
    );
    click(&client, r#"[data-command="RH2_VypnoutQF1"] rect"#).await;
    until(&client, "document.getElementById('control-dialog').open && document.getElementById('control-dialog').dataset.step === 'value'", "the control dialog").await;
    assert!(js(
        &client,
        "document.getElementById('control-title').textContent"
    )
    .await
    .as_str()
    .unwrap()
    .contains("Open QF1"));
    click(&client, "#control-next").await;
    until(
        &client,
        "document.getElementById('control-dialog').dataset.step === 'confirm'",
        "the confirmation step",
    )
    .await;
    let confirm = js(
        &client,
        "document.getElementById('control-confirm').textContent",
    )
    .await;
    assert!(
        confirm
            .as_str()
            .unwrap()
            .contains("Open feeder breaker QF1 of RH2?"),
        "{confirm}"
    );
    assert_eq!(
        js(&client, "document.getElementById('control-sbo').hidden").await,
        json!(false),
        "QF1 is select-before-operate"
    );
    let sent = Instant::now();
    click(&client, "#control-execute").await;
    until(
        &client,
        "document.getElementById('control-outcome').dataset.outcome !== 'pending'",
        "the command's outcome",
    )
    .await;
    timings.push(("QF1 open: outcome shown", sent.elapsed()));
    let outcome = js(&client, "[document.getElementById('control-outcome').dataset.outcome, document.getElementById('control-outcome').textContent]").await;
    assert_eq!(outcome[0], json!("executed"), "outcome: {outcome}");
    assert!(
        outcome[1].as_str().unwrap().contains("executed"),
        "{outcome}"
    );
    until(
        &client,
        &format!("{qf1}.getAttribute('data-value') === 'off'"),
        "QF1 shown open (no voltage behind it)",
    )
    .await;
    until(&client, r#"document.querySelector('#mimic path.bus[data-energised]') && !document.querySelector('#mimic path.bus[data-energised]').classList.contains('energised')"#, "the RH2 busbar drawn dead").await;
    timings.push(("QF1 open: busbar dead", sent.elapsed()));
    click(&client, "#control-step-result button").await;
    until(
        &client,
        "!document.getElementById('control-dialog').open",
        "the dialog closed",
    )
    .await;

    // --- The command is in the event list with the user's name.
    client
        .execute("location.hash = '#events';", Vec::new())
        .await
        .unwrap();
    until(
        &client,
        "document.body.dataset.current === 'events'",
        "the event page",
    )
    .await;
    client
        .execute("const f = document.getElementById('event-filter'); f.kind.value = 'command'; f.point.value = 'RH2_*'; f.requestSubmit();", Vec::new())
        .await
        .unwrap();
    let row = r#"[...document.querySelectorAll('#event-table tbody tr[data-kind="command"]')].find(r => r.textContent.includes('RH2_VypnoutQF1'))"#;
    until(&client, row, "the QF1 command in the event list").await;
    let cells = js(
        &client,
        &format!("[...{row}.children].map(c => c.textContent)"),
    )
    .await;
    assert_eq!(cells[2], json!("RH2_VypnoutQF1"), "{cells}");
    assert_eq!(
        cells[4],
        json!("HMI user operator"),
        "the event names the user: {cells}"
    );
    assert!(
        cells[5]
            .as_str()
            .unwrap()
            .to_lowercase()
            .contains("executed"),
        "{cells}"
    );

    // --- Paging over the whole history (the start-up image alone is hundreds of values):
    // the next page continues with older events.
    client
        .execute(
            "const f = document.getElementById('event-filter'); f.reset();",
            Vec::new(),
        )
        .await
        .unwrap();
    until(
        &client,
        "document.querySelectorAll('#event-table tbody tr[data-kind]').length === 50 && !document.getElementById('events-older').disabled",
        "a full first page of events with an older page",
    )
    .await;
    let last_of_first = js(
        &client,
        "[...document.querySelectorAll('#event-table tbody tr[data-kind]')].pop().dataset.id",
    )
    .await;
    let oldest_time = "[...document.querySelectorAll('#event-table tbody tr[data-kind]')].pop().children[0].textContent";
    let first_page_oldest = js(&client, oldest_time).await;
    click(&client, "#events-older").await;
    until(
        &client,
        "document.getElementById('events-page').textContent.startsWith('page 2')",
        "the second page",
    )
    .await;
    let second = js(&client, "[...document.querySelectorAll('#event-table tbody tr[data-kind]')].map(r => [r.dataset.id, r.children[0].textContent])").await;
    let second = second.as_array().unwrap();
    assert!(!second.is_empty(), "the second page has events");
    assert!(
        second.iter().all(|row| row[0] != last_of_first),
        "pages do not overlap"
    );
    assert!(
        second[0][1].as_str().unwrap() <= first_page_oldest.as_str().unwrap(),
        "page 2 starts where page 1 ended: {} after {}",
        second[0][1],
        first_page_oldest
    );

    // --- Trends: the configured list, the last hour, a drag zooms in, "Zoom out" goes back.
    client
        .execute("location.hash = '#trends';", Vec::new())
        .await
        .unwrap();
    until(
        &client,
        "[...document.getElementById('trend-point').options].some(o => o.value === 'ROV01_P_kW')",
        "the trend list with ROV01_P_kW",
    )
    .await;
    client
        .execute("const s = document.getElementById('trend-point'); s.value = 'ROV01_P_kW'; s.dispatchEvent(new Event('change')); document.querySelector('#trend-form [data-range=\"3600\"]').click();", Vec::new())
        .await
        .unwrap();
    until(
        &client,
        "!HMI.trend.loading && HMI.trend.point === 'ROV01_P_kW' && HMI.trend.to - HMI.trend.from === 3600000 && HMI.trend.samples.length > 0",
        "an hour of ROV01_P_kW with its samples",
    )
    .await;
    // Not following live values, so that the range stays put while zooming.
    let before = js(
        &client,
        "(document.getElementById('trend-follow').checked = false, [HMI.trend.from, HMI.trend.to])",
    )
    .await;
    client
        .execute(
            "const c = document.getElementById('trend-canvas'); const r = c.getBoundingClientRect(); \
             const at = (type, f) => c.dispatchEvent(new PointerEvent(type, {bubbles: true, pointerId: 1, \
               clientX: r.left + r.width * f, clientY: r.top + r.height / 2})); \
             at('pointerdown', 0.3); at('pointermove', 0.5); at('pointermove', 0.7); at('pointerup', 0.7);",
            Vec::new(),
        )
        .await
        .unwrap();
    until(
        &client,
        &format!("!HMI.trend.loading && HMI.trend.zoomStack.length === 1 && HMI.trend.from > {} && HMI.trend.to < {}", before[0], before[1]),
        "the chart zoomed into the dragged range",
    )
    .await;
    click(&client, "#trend-back").await;
    until(
        &client,
        &format!("!HMI.trend.loading && HMI.trend.zoomStack.length === 0 && HMI.trend.from === {} && HMI.trend.to === {}", before[0], before[1]),
        "the chart back at the hour",
    )
    .await;

    // --- An alarm of priority 1: listed in red, the badge and the sound call for attention,
    // acknowledged from the alarm list (the sound stops), shelved.
    site.operate("emergency-off RH2").await;
    client
        .execute("location.hash = '#alarms';", Vec::new())
        .await
        .unwrap();
    let alarm_row = r#"document.querySelector('#alarm-table tr[data-point="RH2_P1_KHVRH2_Havarijni_vypnuti"]')"#;
    until(
        &client,
        &format!("{alarm_row} && {alarm_row}.classList.contains('active') && {alarm_row}.classList.contains('unack')"),
        "the emergency-off alarm, active and unacknowledged",
    )
    .await;
    assert_eq!(
        js(&client, &format!("{alarm_row}.dataset.priority")).await,
        json!("1")
    );
    assert_eq!(
        js(
            &client,
            "document.getElementById('alarm-count').dataset.priority"
        )
        .await,
        json!("1")
    );
    until(
        &client,
        "document.body.dataset.sound === 'playing-p1'",
        "the alarm sound on",
    )
    .await;
    click(
        &client,
        r#"#alarm-table tr[data-point="RH2_P1_KHVRH2_Havarijni_vypnuti"] button.ack"#,
    )
    .await;
    until(
        &client,
        &format!(
            "!{alarm_row}.classList.contains('unack') && document.body.dataset.sound === 'silent'"
        ),
        "the alarm acknowledged and the sound off",
    )
    .await;
    // The operator picks 4 h; another alarm arriving meanwhile neither replaces the row nor
    // resets the choice.
    js(
        &client,
        &format!(
            "(window.pickedRow = {alarm_row}, {alarm_row}.querySelector('select').value = '240')"
        ),
    )
    .await;
    let alarms_before = js(&client, "HMI.alarms.size").await;
    // A door rather than a lamp: a lamp's failure alarms only while the lights are on,
    // which at speed 1 from the wall clock depends on the hour the test runs.
    site.operate("door-open RDRT_NN").await;
    until(
        &client,
        &format!("HMI.alarms.size > {alarms_before} && document.querySelectorAll('#alarm-table tbody tr').length > 1"),
        "another alarm listed",
    )
    .await;
    assert_eq!(
        js(
            &client,
            &format!(
                "[window.pickedRow === {alarm_row}, {alarm_row}.querySelector('select').value]"
            )
        )
        .await,
        json!([true, "240"]),
        "the row being used was rebuilt by an unrelated alarm"
    );
    click(
        &client,
        r#"#alarm-table tr[data-point="RH2_P1_KHVRH2_Havarijni_vypnuti"] button.shelve"#,
    )
    .await;
    until(
        &client,
        &format!("{alarm_row}.classList.contains('shelved')"),
        "the alarm shelved",
    )
    .await;
    let shelved_for_minutes = js(
        &client,
        &format!(
            "(Date.parse(HMI.alarms.get(Number({alarm_row}.dataset.id)).shelved_until) - HMI.now()) / 60000"
        ),
    )
    .await
    .as_f64()
    .unwrap();
    assert!(
        (230.0..=241.0).contains(&shelved_for_minutes),
        "shelved for {shelved_for_minutes} min, not the 4 h picked"
    );
    site.operate("clear emergency-off RH2").await;
    site.operate("clear door-open RDRT_NN").await;

    // --- The station link is cut: every bound value turns invalid and blinks.
    show_screen(&client, "supply").await;
    until(&client, "document.querySelectorAll('#mimic [data-point], #mimic [data-energised], #mimic [data-text]').length > 20", "the supply screen's bindings").await;
    assert_eq!(
        js(&client, r#"[...document.querySelectorAll('[data-command="RDRT_HMI_Mistne"]')].map(e => e.classList.contains('disabled'))"#).await,
        json!([true, true]),
        "the control authority needs level 7, not the operator's 5"
    );
    let cut = Instant::now();
    site.hmi().station.set_link(false);
    let all_invalid = "[...document.querySelectorAll('#mimic [data-point], #mimic [data-energised], #mimic [data-text]')].every(e => e.getAttribute('data-invalid') === 'true')";
    until(
        &client,
        all_invalid,
        "every bound element invalid after the link cut",
    )
    .await;
    timings.push(("link cut: all invalid", cut.elapsed()));
    assert_eq!(
        attribute(&client, "#link", "data-state").await,
        json!("down")
    );
    let blink = js(&client, r#"[...document.querySelectorAll('#mimic [data-invalid="true"]')].map(e => getComputedStyle(e).animationName).filter(n => !n.startsWith('lost')).length"#).await;
    assert_eq!(
        blink,
        json!(0),
        "every invalid element runs a 'lost' blink animation"
    );
    let banner = js(
        &client,
        "getComputedStyle(document.getElementById('mimic-banner')).display",
    )
    .await;
    assert_ne!(banner, json!("none"), "the link-down banner shows");
    site.hmi().station.set_link(true);
    until(
        &client,
        "HMI.link.up && !document.querySelector('#mimic [data-invalid]')",
        "valid values again after the link returns",
    )
    .await;
    timings.push(("link restored: all valid", cut.elapsed()));

    // --- The browser's own live connection drops: same blinking, then it reconnects.
    client.execute("HMI.ws.close();", Vec::new()).await.unwrap();
    until(
        &client,
        &format!("!HMI.wsOpen && {all_invalid}"),
        "every bound element invalid while the WebSocket is closed",
    )
    .await;
    assert_eq!(
        attribute(&client, "#link", "data-state").await,
        json!("offline")
    );
    until(
        &client,
        "HMI.wsOpen && !document.querySelector('#mimic [data-invalid]')",
        "the WebSocket reconnected with valid values",
    )
    .await;

    // --- A malicious mimic: nothing in it runs, the dangerous nodes and attributes are
    // gone from the page, its harmless binding and screen link work.
    show_screen(&client, "malicious").await;
    let mimic = "document.querySelector('#mimic svg[data-screen=\"malicious\"]')";
    // The SVG's own timeline: the payload animations (0.1 s, from time 0) would have run.
    until(
        &client,
        &format!("{mimic}.getCurrentTime() > 0.5"),
        "the malicious mimic's animations past their end",
    )
    .await;
    for target in [
        "#evil-set text",
        "#evil-animate text",
        "#evil-xlink text",
        "#evil-data text",
        "#evil-spaced text",
        "#evil-on",
    ] {
        click(&client, &format!("#mimic {target}")).await;
    }
    // Tasks run in order: once this link's navigation is done, any a payload link queued
    // before it would have run too.
    click(&client, "#mimic #good-link text").await;
    until(
        &client,
        r#"document.querySelector('#mimic svg[data-screen="rh2"]')"#,
        "the mimic's screen link followed to RH2",
    )
    .await;
    assert!(client.get_alert_text().await.is_err(), "no alert opened");
    assert_eq!(
        js(&client, "window.pwned === undefined ? null : window.pwned").await,
        Value::Null,
        "a payload of the malicious mimic ran"
    );
    show_screen(&client, "malicious").await;
    let dom = js(
        &client,
        &format!(
            "(() => {{ const svg = {mimic}; const all = [svg, ...svg.querySelectorAll('*')]; \
             const attributes = all.flatMap(e => [...e.attributes]); return {{ \
               elements: [...svg.querySelectorAll('script, foreignObject, iframe, set, animate, animateTransform')].map(e => e.id || e.parentNode.id + '>' + e.localName), \
               handlers: attributes.filter(a => a.name.toLowerCase().startsWith('on')).map(a => a.name), \
               links: attributes.filter(a => /href$/i.test(a.name)).map(a => a.value), \
               urls: attributes.filter(a => /javascript|data:/i.test(a.value)).map(a => a.name + '=' + a.value), \
               breaker: [svg.querySelector('#good-breaker').getAttribute('data-value'), HMI.valueWord(HMI.points.get('RH2_V1_FA1_Zapnut')), svg.querySelector('#good-breaker').hasAttribute('data-invalid')], \
               text: svg.querySelector('#good-text').textContent }}; }})()"
        ),
    )
    .await;
    assert_eq!(
        dom["elements"],
        json!(["good-animation>animate"]),
        "only the harmless animation is left: {dom}"
    );
    assert_eq!(
        dom["handlers"],
        json!([]),
        "no event handler attribute: {dom}"
    );
    assert_eq!(
        dom["links"],
        json!(["#screen/malicious", "#screen/rh2"]),
        "only the screen links are left: {dom}"
    );
    assert_eq!(dom["urls"], json!([]), "no javascript: or data: URL: {dom}");
    assert!(
        dom["breaker"][0] == dom["breaker"][1]
            && (dom["breaker"][0] == json!("on") || dom["breaker"][0] == json!("off"))
            && dom["breaker"][2] == json!(false),
        "the harmless binding shows FA1: {dom}"
    );
    assert_eq!(
        dom["text"],
        json!("LOCAL"),
        "the harmless text binding: {dom}"
    );

    // --- Level, position, rotation and visibility bindings follow live values: FA1.1,
    // tripped (0) since the start, recloses (1) when its trip is cleared.
    let lab = |id: &str| format!("document.querySelector('#mimic #{id}')");
    let (level, car, valve, tripped) = (
        lab("lab-level"),
        lab("lab-car"),
        lab("lab-valve"),
        lab("lab-tripped"),
    );
    until(
        &client,
        &format!(
            "HMI.points.get('RH2_V1_FA1.1').value === false \
             && {level}.getAttribute('y') === '250' && {level}.getAttribute('height') === '0' \
             && {car}.getAttribute('transform') === 'translate(0 0)' \
             && {valve}.getAttribute('transform') === 'rotate(0 560 200)' \
             && {tripped}.getAttribute('visibility') === 'visible'"
        ),
        "the level, position, rotation and visibility bindings at FA1.1 open",
    )
    .await;
    site.operate("clear breaker-tripped RH2_FA1.1").await;
    until(
        &client,
        &format!(
            "HMI.points.get('RH2_V1_FA1.1').value === true \
             && {level}.getAttribute('y') === '150' && {level}.getAttribute('height') === '100' \
             && {car}.getAttribute('transform') === 'translate(0 -100)' \
             && {valve}.getAttribute('transform') === 'rotate(90 560 200)' \
             && {tripped}.getAttribute('visibility') === 'hidden'"
        ),
        "the level, position, rotation and visibility bindings following FA1.1 closed",
    )
    .await;
    // A measurement on a range: RZZ's busbar voltage fills its bar to its share of 0..500 V.
    let meter = js(
        &client,
        &format!(
            "(() => {{ const e = {}; return [HMI.points.get('RZZ_U').value, \
             Number(e.getAttribute('y')), Number(e.getAttribute('height'))]; }})()",
            lab("lab-meter")
        ),
    )
    .await;
    let volts = meter[0]
        .as_f64()
        .unwrap_or_else(|| panic!("RZZ_U: {meter}"));
    let height = 100.0 * (volts / 500.0).clamp(0.0, 1.0);
    assert!(
        (meter[2].as_f64().unwrap() - height).abs() < 1e-6
            && (meter[1].as_f64().unwrap() - (250.0 - height)).abs() < 1e-6,
        "the meter's level follows RZZ_U: {meter}"
    );

    // --- The read-only user: controls disabled, and the server refuses them anyway.
    assert_eq!(
        js(&client, "HMI.errors").await,
        json!([]),
        "script errors in the operator's page"
    );
    click(&client, "#logout").await;
    until(
        &client,
        "location.pathname === '/login'",
        "the login page after logging out",
    )
    .await;
    log_in_ready(&client, &url, "viewer", "viewer-vsetin").await;
    assert_eq!(
        js(&client, "document.getElementById('user-level').textContent").await,
        json!("level 0")
    );
    show_screen(&client, "rh2").await;
    let disabled = js(&client, "[...document.querySelectorAll('#mimic [data-command]')].every(e => e.classList.contains('disabled'))").await;
    assert_eq!(
        disabled,
        json!(true),
        "every control is disabled for the viewer"
    );
    click(&client, r#"[data-command="RH2_ZapnoutQF1"] rect"#).await;
    until(&client, "[...document.querySelectorAll('.toast')].some(t => t.textContent.includes('not permitted'))", "the not-permitted message").await;
    assert_eq!(
        js(&client, "document.getElementById('control-dialog').open").await,
        json!(false),
        "no dialog for a disabled control"
    );
    let refused = client
        .execute_async(
            "const done = arguments[arguments.length - 1]; \
             HMI.post('/api/command', {command: 'RH2_ZapnoutQF1', value: 1}).then(r => done([r.status, r.body.outcome]));",
            Vec::new(),
        )
        .await
        .unwrap();
    assert_eq!(
        refused,
        json!([403, "refused-permission"]),
        "the server refuses the viewer's command"
    );

    // The viewer watches the alarms but neither acknowledges nor shelves them.
    site.operate("door-open RDRT_VN").await;
    client
        .execute("location.hash = '#alarms';", Vec::new())
        .await
        .unwrap();
    until(
        &client,
        r#"document.querySelector('#alarm-table tr[data-point="RDRT_SP27_Dvere_VN"]')"#,
        "the door alarm in the viewer's list",
    )
    .await;
    assert_eq!(
        js(
            &client,
            "document.querySelectorAll('#alarm-table button').length"
        )
        .await,
        json!(0),
        "no alarm buttons for the read-only user"
    );
    assert_eq!(
        js(&client, "HMI.errors").await,
        json!([]),
        "script errors in the viewer's page"
    );

    // --- Guessing passwords: after a few failures the login page says how long to wait
    // (last: it locks this address out).
    click(&client, "#logout").await;
    until(&client, "location.pathname === '/login'", "the login page").await;
    let mut locked = false;
    for _ in 0..10 {
        client
            .execute(
                "document.getElementById('username').value = 'intruder'; \
                 document.getElementById('password').value = 'guess'; \
                 document.getElementById('login-message').textContent = '';",
                Vec::new(),
            )
            .await
            .unwrap();
        click(&client, "#login-button").await;
        until(
            &client,
            "/Wrong|Too many/.test(document.getElementById('login-message').textContent)",
            "the answer to a wrong login",
        )
        .await;
        let message = js(
            &client,
            "document.getElementById('login-message').textContent",
        )
        .await;
        if message
            .as_str()
            .unwrap()
            .starts_with("Too many failed logins. Try again in")
        {
            locked = true;
            break;
        }
    }
    assert!(locked, "the login page never told of the lockout");
    assert_eq!(
        js(&client, "document.getElementById('login-button').disabled").await,
        json!(true),
        "the button waits out the lockout"
    );

    client.close().await.unwrap();
    drop(driver);
    site.stop().await;
    let total = started.elapsed();
    for (what, took) in &timings {
        eprintln!("  {what}: {:.0} ms", took.as_secs_f64() * 1000.0);
    }
    eprintln!("browser test: {:.1} s in all", total.as_secs_f64());
    assert!(
        total < Duration::from_secs(60),
        "the browser test took {total:?}"
    );
}

/// Screenshots of the main screens for docs/screenshots/ (run by hand:
/// `cargo test -p hmi --test browser -- --ignored screenshots`).
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
#[ignore = "writes docs/screenshots/*.png; run by hand"]
async fn screenshots() {
    let Some((driver, chromium)) = browser_available() else {
        return;
    };
    // A winter evening at 30 x speed: the towers switch on one after another at dusk and
    // their power shows in the trend.
    let start: DateTime<Utc> = "2025-01-15T15:15:00Z".parse().unwrap();
    let site = Site::start(start, 30.0).await;
    let driver = Driver::start(&driver, chromium);
    let client = driver.session(1280, 860).await;
    let out = repository_root().join("docs/screenshots");
    std::fs::create_dir_all(&out).unwrap();
    let shoot = |name: &'static str| {
        let client = client.clone();
        let path = out.join(name);
        async move {
            tokio::time::sleep(Duration::from_millis(400)).await;
            let png = client.screenshot().await.unwrap();
            std::fs::write(&path, png).unwrap();
            eprintln!("wrote {}", path.display());
        }
    };

    log_in_ready(&client, &site.url, "admin", "admin-vsetin").await;
    // The start-up transients (links coming up) are acknowledged; then the evening comes
    // on (about 20 simulated minutes), with some faults to look at.
    client
        .execute("location.hash = '#alarms';", Vec::new())
        .await
        .unwrap();
    until(
        &client,
        "document.body.dataset.current === 'alarms'",
        "the alarm page",
    )
    .await;
    tokio::time::sleep(Duration::from_secs(2)).await;
    click(&client, "#alarm-ack-all").await;
    // "Acknowledge shown" asks first (nothing may wait: then it only says so).
    if js(&client, "document.getElementById('alarm-ack-dialog').open").await == json!(true) {
        click(&client, "#alarm-ack-confirm").await;
    }
    tokio::time::sleep(Duration::from_secs(40)).await;
    site.operate("lamp-failure ROV03").await;
    site.operate("breaker-tripped RH2_FA1.3").await;
    site.operate("door-open RDRT_NN").await;
    site.operate("fuse-blown RZZ_FU1").await;
    tokio::time::sleep(Duration::from_secs(3)).await;

    // The administrator takes the control authority to this HMI (level 7).
    show_screen(&client, "supply").await;
    click(
        &client,
        r#"[data-command="RDRT_HMI_Mistne"][data-command-value="1"] rect"#,
    )
    .await;
    until(
        &client,
        "document.getElementById('control-dialog').open",
        "the authority dialog",
    )
    .await;
    click(&client, "#control-next").await;
    click(&client, "#control-execute").await;
    until(
        &client,
        "document.getElementById('control-outcome').dataset.outcome === 'executed'",
        "the authority switched",
    )
    .await;
    click(&client, "#control-step-result button").await;
    until(
        &client,
        r#"document.querySelector('rect.authority').getAttribute('data-value') === 'on'"#,
        "the authority shown as local",
    )
    .await;
    shoot("supply.png").await;
    show_screen(&client, "rh2").await;
    shoot("rh2.png").await;
    show_screen(&client, "rda").await;
    shoot("rda.png").await;
    show_screen(&client, "lighting").await;
    shoot("lighting.png").await;
    show_screen(&client, "topology").await;
    shoot("topology.png").await;

    // The control dialog at its confirmation step (closing QF1, which is closed: the
    // command is executed and recorded, the station stays as it is).
    show_screen(&client, "rh2").await;
    click(&client, r#"[data-command="RH2_ZapnoutQF1"] rect"#).await;
    until(
        &client,
        "document.getElementById('control-dialog').open",
        "the control dialog",
    )
    .await;
    click(&client, "#control-next").await;
    shoot("control.png").await;
    click(&client, "#control-execute").await;
    until(
        &client,
        "document.getElementById('control-outcome').dataset.outcome !== 'pending'",
        "the outcome",
    )
    .await;
    shoot("control-outcome.png").await;
    click(&client, "#control-step-result button").await;

    client
        .execute("location.hash = '#events';", Vec::new())
        .await
        .unwrap();
    until(
        &client,
        "document.querySelectorAll('#event-table tbody tr[data-kind]').length > 5",
        "events",
    )
    .await;
    shoot("events.png").await;
    client
        .execute("location.hash = '#alarms';", Vec::new())
        .await
        .unwrap();
    until(
        &client,
        "document.querySelectorAll('#alarm-table tbody tr').length > 0",
        "alarms",
    )
    .await;
    shoot("alarms.png").await;
    client
        .execute("location.hash = '#trends'; ", Vec::new())
        .await
        .unwrap();
    until(
        &client,
        "document.getElementById('trend-point').options.length > 0",
        "the trend list",
    )
    .await;
    client
        .execute("const s = document.getElementById('trend-point'); s.value = 'ROV01_P_kW'; s.dispatchEvent(new Event('change'));", Vec::new())
        .await
        .unwrap();
    until(
        &client,
        "HMI.trend.samples.length > 1 && !HMI.trend.loading",
        "trend samples",
    )
    .await;
    shoot("trends.png").await;

    // The link cut: everything blinks (caught in the "lost" phase or not, it is marked).
    show_screen(&client, "supply").await;
    site.hmi().station.set_link(false);
    until(
        &client,
        "document.body.classList.contains('link-down')",
        "link down",
    )
    .await;
    tokio::time::sleep(Duration::from_millis(600)).await;
    shoot("link-down.png").await;
    site.hmi().station.set_link(true);

    // A phone: the navigation collapses behind the menu button, the screen fits the width.
    client.set_window_size(390, 844).await.unwrap();
    show_screen(&client, "supply").await;
    shoot("mobile.png").await;
    click(&client, "#nav-toggle").await;
    shoot("mobile-menu.png").await;

    client.close().await.unwrap();
    drop(driver);
    site.stop().await;
}
