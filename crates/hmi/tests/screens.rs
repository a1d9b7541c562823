//! Screens that tell the truth, in a real browser (headless Chromium over WebDriver)
//! against the Vsetín station running in this process, as tests/browser.rs does:
//!
//! - the faceplate: a click on a bound element opens it with the point's name and
//!   description, its value and quality in words, the time tag with date and zone, the
//!   source and the commands whose state point it is; it follows the value and stays open
//!   until closed (Esc or its button);
//! - the control dialog speaks in words at every step: no raw value ("value 1", "1 — ON",
//!   "NAME = 1") in its value step, its confirmation, its outcome; a setpoint in hh:mm;
//! - the lighting cards: "lighting ON" only while the lamps carry current, MAN and ASTRO
//!   never both lit (a board put in manual mode), the time-window state, energy with a
//!   decimal; the RH2 feeders labelled; DDTS and DŘT showing their link state;
//! - a phone (390x844): every visible text drawn at 12 px or more (SVG text measured at its
//!   drawn size), no horizontal overflow, the Fit/1:1 tools not over the mimic's title.
//!
//! Without chromium and chromedriver (scripts/install-test-deps.sh) it says SKIPPED and
//! passes, unless `STANICE_REQUIRE_PEERS=1`.

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

use chrono::Utc;
use fantoccini::{Client, Locator};
use serde_json::{json, Value};

async fn log_in_ready(client: &Client, url: &str, user: &str, password: &str) {
    client.goto(&format!("{url}/")).await.unwrap();
    until(
        client,
        "location.pathname === '/login' && document.getElementById('login-form')",
        "the login page",
    )
    .await;
    let name = client.find(Locator::Id("username")).await.unwrap();
    name.send_keys(user).await.unwrap();
    let field = client.find(Locator::Id("password")).await.unwrap();
    field.send_keys(password).await.unwrap();
    click(client, "#login-button").await;
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

/// The faceplate's facts, by name (`value`, `quality`, `time`, `changed`, `source`,
/// `commands`), of its first section, with its title and point name.
async fn faceplate(client: &Client) -> Value {
    js(
        client,
        "(() => { const f = document.getElementById('faceplate'); const facts = {}; \
         for (const dd of f.querySelectorAll('section:first-child [data-fact]')) facts[dd.dataset.fact] = dd.textContent; \
         facts.open = f.open; facts.title = document.getElementById('faceplate-title').textContent; \
         facts.text = f.textContent; \
         facts.buttons = [...f.querySelectorAll('.faceplate-commands button')].map(b => b.textContent); \
         return facts; })()",
    )
    .await
}

/// Raw values a dialog must not show: "value 1", "1 — ON", "NAME = 1", "(1)", a bare
/// number of minutes.
const RAW_VALUE: &str = r"/value \d|\d+\s*—|=\s*-?\d|\(\d+\)|\d+ min\b|\btrue\b|\bfalse\b/";

/// The control dialog's visible text now.
async fn dialog_text(client: &Client) -> String {
    js(
        client,
        "(() => { const d = document.getElementById('control-dialog'); \
         return [...d.querySelectorAll('h3, p, dd, legend, label, .step:not([hidden]) p')] \
           .filter(e => e.getClientRects().length).map(e => e.textContent).join(' | '); })()",
    )
    .await
    .as_str()
    .unwrap()
    .to_owned()
}

async fn assert_in_words(client: &Client, step: &str) -> String {
    let text = dialog_text(client).await;
    let raw = js(client, &format!("{RAW_VALUE}.exec({text:?})")).await;
    assert_eq!(raw, Value::Null, "a raw value in the {step} step: {text}");
    text
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn screens_that_tell_the_truth() {
    let Some((driver, chromium)) = browser_available() else {
        return;
    };
    let site = Site::start(Utc::now(), 1.0).await;
    let url = site.url.clone();
    let driver = Driver::start(&driver, chromium);
    let client = driver.session(1280, 900).await;
    log_in_ready(&client, &url, "operator", "operator-vsetin").await;

    // --- The faceplate of breaker FA1.1 of RH2: opened by a click, all its facts in words.
    show_screen(&client, "rh2").await;
    let fa11 = r#"#mimic rect.breaker[data-point="RH2_V1_FA1.1"]"#;
    until(
        &client,
        &format!("document.querySelector('{fa11}').getAttribute('data-value') === 'on'"),
        "FA1.1 closed",
    )
    .await;
    assert_eq!(
        js(&client, "document.getElementById('faceplate').open").await,
        json!(false)
    );
    click(&client, fa11).await;
    until(
        &client,
        "document.getElementById('faceplate').open",
        "the faceplate",
    )
    .await;
    let facts = faceplate(&client).await;
    assert_eq!(facts["title"], json!("breaker FA1.1 closed"), "{facts}");
    assert!(
        facts["text"].as_str().unwrap().contains("RH2_V1_FA1.1"),
        "{facts}"
    );
    assert_eq!(
        facts["value"],
        json!("closed"),
        "the screen's words: {facts}"
    );
    assert_eq!(facts["quality"], json!("good"), "{facts}");
    let time_with_zone = r"/^\d{4}-\d\d-\d\d \d\d:\d\d:\d\d\.\d{3} UTC[+-]\d\d:\d\d/";
    assert_eq!(
        js(
            &client,
            &format!(
                "{time_with_zone}.test({:?})",
                facts["time"].as_str().unwrap()
            )
        )
        .await,
        json!(true),
        "the time tag with date and zone: {facts}"
    );
    let source = facts["source"].as_str().unwrap();
    assert!(
        source.contains("IOA 282")
            && source.contains("single point (M_SP_TB_1)")
            && source.contains("station 127.0.0.1:"),
        "{facts}"
    );
    assert_eq!(facts["commands"], json!("none"), "{facts}");
    // It follows the value and stays open: the plant trips FA1.1.
    site.operate("breaker-tripped RH2_FA1.1").await;
    until(
        &client,
        "document.querySelector('#faceplate [data-fact=\"value\"]').textContent === 'open'",
        "the faceplate showing FA1.1 open",
    )
    .await;
    let facts = faceplate(&client).await;
    assert_eq!(facts["open"], json!(true), "{facts}");
    assert_eq!(
        js(
            &client,
            &format!(
                "{time_with_zone}.test({:?})",
                facts["changed"].as_str().unwrap()
            )
        )
        .await,
        json!(true),
        "the last change seen, with date and zone: {facts}"
    );
    // Esc closes it.
    js(
        &client,
        "document.dispatchEvent(new KeyboardEvent('keydown', {key: 'Escape', bubbles: true})) || true",
    )
    .await;
    until(
        &client,
        "!document.getElementById('faceplate').open",
        "the faceplate closed by Esc",
    )
    .await;

    // QF1's state point: its faceplate offers the commands that show their state there.
    click(
        &client,
        r#"#mimic rect.breaker[data-point="RH2_P1_KHU3_Napeti_na_pripojeni"]"#,
    )
    .await;
    until(
        &client,
        "document.getElementById('faceplate').open",
        "QF1's faceplate",
    )
    .await;
    let facts = faceplate(&client).await;
    assert_eq!(
        facts["buttons"],
        json!(["Open QF1", "Close QF1"]),
        "{facts}"
    );
    assert_eq!(facts["value"], json!("closed (voltage behind)"), "{facts}");
    click(&client, "#faceplate-close").await;
    until(
        &client,
        "!document.getElementById('faceplate').open",
        "the faceplate closed by its button",
    )
    .await;
    // A click on a command element still opens the control dialog.
    click(&client, r#"[data-command="RH2_VypnoutQF1"] rect"#).await;
    until(
        &client,
        "document.getElementById('control-dialog').open && !document.getElementById('faceplate').open",
        "the control dialog, not the faceplate",
    )
    .await;
    let text = assert_in_words(&client, "value").await;
    assert!(text.contains("Open QF1"), "{text}");
    click(&client, "#control-next").await;
    until(
        &client,
        "document.getElementById('control-dialog').dataset.step === 'confirm'",
        "the confirmation",
    )
    .await;
    let text = assert_in_words(&client, "confirmation").await;
    assert!(text.contains("Open feeder breaker QF1 of RH2?"), "{text}");
    click(&client, "#control-execute").await;
    until(
        &client,
        "document.getElementById('control-outcome').dataset.outcome !== 'pending'",
        "the outcome (refused: the authority is with the dispatch)",
    )
    .await;
    let text = assert_in_words(&client, "outcome").await;
    assert!(text.contains("Open QF1: refused"), "{text}");
    click(&client, "#control-step-result button").await;

    // --- The RH2 feeders are labelled.
    let feeders = js(
        &client,
        "[...document.querySelectorAll('#mimic text.feeder')].map(t => t.textContent)",
    )
    .await;
    assert_eq!(
        feeders,
        json!(["ROV01–03", "ROV04–06", "ROV07–09", "ROV10–12", "OŘ"])
    );

    // --- Lighting: a board put in manual mode through the dialog, in words at every step.
    show_screen(&client, "lighting").await;
    let card = r##"#board-ROV01"##;
    until(
        &client,
        &format!("document.querySelector('{card} [data-text=\"ROV01_Osv_Rucne\"]').getAttribute('data-value') === 'off'"),
        "ROV01 in automatic mode",
    )
    .await;
    click(
        &client,
        &format!(r#"{card} [data-command="ROV01_W_Rucne"][data-command-value="1"] rect"#),
    )
    .await;
    until(
        &client,
        "document.getElementById('control-dialog').open",
        "the manual-mode dialog",
    )
    .await;
    assert_in_words(&client, "value").await;
    click(&client, "#control-next").await;
    until(
        &client,
        "document.getElementById('control-dialog').dataset.step === 'confirm'",
        "the confirmation",
    )
    .await;
    let text = assert_in_words(&client, "confirmation").await;
    assert!(
        text.contains("Put the lighting of ROV01 in manual mode?"),
        "{text}"
    );
    click(&client, "#control-execute").await;
    until(
        &client,
        "document.getElementById('control-outcome').dataset.outcome !== 'pending'",
        "the outcome",
    )
    .await;
    let text = assert_in_words(&client, "outcome").await;
    assert_eq!(
        js(
            &client,
            "document.getElementById('control-outcome').dataset.outcome"
        )
        .await,
        json!("executed"),
        "{text}"
    );
    click(&client, "#control-step-result button").await;
    until(
        &client,
        "HMI.points.get('ROV01_Osv_Rucne').value === true",
        "ROV01 in manual mode",
    )
    .await;
    // A time-window setpoint: entered and confirmed as hh:mm.
    click(
        &client,
        &format!(r#"{card} [data-command="ROV01_W_Cas1Zap"]"#),
    )
    .await;
    until(
        &client,
        "document.getElementById('control-dialog').open",
        "the setpoint dialog",
    )
    .await;
    js(
        &client,
        "(document.querySelector('#control-values input[type=time]').value = '18:30') === '18:30'",
    )
    .await;
    click(&client, "#control-next").await;
    until(
        &client,
        "document.getElementById('control-dialog').dataset.step === 'confirm'",
        "the setpoint's confirmation",
    )
    .await;
    let text = assert_in_words(&client, "setpoint confirmation").await;
    assert!(
        text.contains("time window 1, on time: set to 18:30?"),
        "{text}"
    );
    assert!(!text.contains("1110"), "{text}");
    client
        .find(Locator::Css("#control-step-confirm [data-close]"))
        .await
        .unwrap()
        .click()
        .await
        .unwrap();

    // The cards' rules, every board: "lighting ON" only with current, MAN and ASTRO never
    // both lit, the time window in words, energy with a decimal.
    let rules = "(() => { const lit = (e) => e && e.getAttribute('data-value') === 'on' && \
           getComputedStyle(e).visibility !== 'hidden'; const out = []; \
         for (const card of document.querySelectorAll('#mimic g[id^=\"board-\"]')) { \
           const b = card.id.slice(6) + '_'; const q = (s) => card.querySelector(s); \
           const current = HMI.points.get(b + 'PrRele').value; \
           const lamp = q(`text[data-text=\"${b}PrRele\"]`).textContent; \
           const man = lit(q(`text[data-text=\"${b}Osv_Rucne\"]`)); \
           const astro = lit(q(`text[data-text=\"${b}Set_Astral\"]`)); \
           out.push({board: b, ok: (lamp === 'lighting ON') === (current === true) && !(man && astro) \
             && /^(inside a time window|outside the time windows)$/.test(q(`text[data-text=\"${b}Zap_Cas\"]`).textContent) \
             && /^\\d+\\.\\d kWh$/.test(q(`text[data-text=\"${b}Energie_kWh\"]`).textContent), \
             lamp, current, man, astro}); } return out; })()";
    let cards = js(&client, rules).await;
    assert_eq!(cards.as_array().unwrap().len(), 13, "{cards}");
    for card in cards.as_array().unwrap() {
        assert_eq!(card["ok"], json!(true), "{card}");
    }
    let rov01 = &cards[0];
    assert_eq!(rov01["man"], json!(true), "ROV01's MAN lit: {rov01}");
    // Back to automatic, by the API (the dialog was shown above).
    let back = client
        .execute_async(
            "const done = arguments[arguments.length - 1]; \
             HMI.post('/api/command', {command: 'ROV01_W_Rucne', value: 0}).then(r => done(r.body.outcome));",
            Vec::new(),
        )
        .await
        .unwrap();
    assert_eq!(back, json!("executed"));

    // --- Topology: DDTS and DŘT show the dispatch link's state (no dispatch client here).
    show_screen(&client, "topology").await;
    let dispatch = js(
        &client,
        "[HMI.points.get('COMM_DISPATCH').value, \
          [...document.querySelectorAll('#mimic text[data-text=\"COMM_DISPATCH\"]')].map(t => t.textContent), \
          [...document.querySelectorAll('#mimic rect.comm-node[data-point=\"COMM_DISPATCH\"]')].map(r => r.getAttribute('data-value'))]",
    )
    .await;
    let down = dispatch[0].as_bool().expect("COMM_DISPATCH has a value");
    let words = if down { "link down" } else { "link up" };
    let state = if down { "on" } else { "off" };
    assert_eq!(dispatch[1], json!([words, words]), "{dispatch}");
    assert_eq!(dispatch[2], json!([state, state]), "{dispatch}");

    // --- A phone: text at 12 px or more, no horizontal overflow, nothing over the title.
    client.set_window_size(390, 844).await.unwrap();
    until(&client, "window.innerWidth <= 400", "the phone's width").await;
    for screen in ["supply", "rh2", "lighting", "topology"] {
        show_screen(&client, screen).await;
        until(
            &client,
            "document.getElementById('mimic').classList.contains('readable')",
            "the readable drawing",
        )
        .await;
        let small = js(
            &client,
            "(() => { const small = []; \
             for (const t of document.querySelectorAll('#mimic svg text')) { \
               if (!t.textContent.trim()) continue; const cs = getComputedStyle(t); \
               if (cs.visibility === 'hidden' || !t.getClientRects().length) continue; \
               const m = t.getScreenCTM(); const px = parseFloat(cs.fontSize) * Math.hypot(m.a, m.b); \
               if (px < 12) small.push([t.textContent, px]); } \
             for (const e of document.querySelectorAll('body *')) { \
               if (e.closest('svg')) continue; \
               if (![...e.childNodes].some(n => n.nodeType === 3 && n.textContent.trim())) continue; \
               if (!e.getClientRects().length) continue; const cs = getComputedStyle(e); \
               if (cs.visibility === 'hidden') continue; const px = parseFloat(cs.fontSize); \
               if (px < 12) small.push([e.tagName, e.id, e.className, e.textContent.slice(0, 30), px]); } \
             return small; })()",
        )
        .await;
        assert_eq!(small, json!([]), "text drawn under 12 px on {screen}");
        let width = js(
            &client,
            "[document.scrollingElement.scrollWidth, window.innerWidth]",
        )
        .await;
        assert!(
            width[0].as_f64().unwrap() <= width[1].as_f64().unwrap().min(390.0),
            "horizontal overflow on {screen}: {width}"
        );
        let overlap = js(
            &client,
            "(() => { const title = document.querySelector('#mimic svg text.title').getBoundingClientRect(); \
             return [...document.querySelectorAll('.mimic-tools > *')].filter(e => e.getClientRects().length).some(e => { \
               const r = e.getBoundingClientRect(); \
               return r.left < title.right && title.left < r.right && r.top < title.bottom && title.top < r.bottom; }); })()",
        )
        .await;
        assert_eq!(
            overlap,
            json!(false),
            "the tools over the title on {screen}"
        );
    }
    // And on a desk: the Fit/1:1 button is beside, not over, the title.
    client.set_window_size(1280, 900).await.unwrap();
    show_screen(&client, "supply").await;
    until(
        &client,
        "!document.getElementById('mimic-zoom').hidden && document.getElementById('mimic-zoom').getClientRects().length",
        "the Fit/1:1 button on a desk",
    )
    .await;
    let overlap = js(
        &client,
        "(() => { const t = document.querySelector('#mimic svg text.title').getBoundingClientRect(); \
         const r = document.getElementById('mimic-zoom').getBoundingClientRect(); \
         return r.left < t.right && t.left < r.right && r.top < t.bottom && t.top < r.bottom; })()",
    )
    .await;
    assert_eq!(overlap, json!(false), "Fit/1:1 over the title");

    assert_eq!(js(&client, "HMI.errors").await, json!([]), "script errors");
    client.close().await.unwrap();
    drop(driver);
    site.stop().await;
}
