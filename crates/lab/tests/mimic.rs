//! The lab mimics in a real browser (headless Chromium): each model's panel follows the
//! program's outputs; ERR blinks or stays lit as the model says; RESET works from the
//! page; the time-line shows a past violation when scrolled back to it.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::path::{Path, PathBuf};
use std::time::Duration;

use fantoccini::Client;
use lab::run::DEFAULT_SCAN;
use lab::serve::{serve, serve_many, ServeSettings};
use lab::{RunSettings, Speed};
use plant::lab::{LabOptions, Profile};
use testkit::chromium::{browser_available, click, js, until_or_show, Driver};

fn examples() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/lab")
}

fn settings(model: &str, file: &str, speed: Speed) -> ServeSettings {
    let path = examples().join(file);
    let text = std::fs::read_to_string(&path).unwrap();
    ServeSettings {
        run: RunSettings {
            model: model.to_owned(),
            profile: Profile::Model,
            options: LabOptions::default(),
            duration: Duration::from_secs(3600),
            scan: DEFAULT_SCAN,
            speed,
        },
        sources: vec![(path.display().to_string(), text)],
        main: None,
        scenario: None,
        paused: false,
    }
}

/// Serves `file` against `model` on a free loopback port; the page's address.
async fn mimic(model: &str, file: &str, speed: Speed) -> String {
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
    let address = listener.local_addr().unwrap();
    let settings = settings(model, file, speed);
    tokio::spawn(async move { serve(listener, settings).await.unwrap() });
    format!("http://{address}/")
}

const STATE: &str = "JSON.stringify({state: window.LAB && LAB.state, shown: window.LAB && LAB.view.shown, violations: window.LAB && LAB.violations.length})";

async fn until(client: &Client, expression: &str, what: &str) {
    until_or_show(client, expression, what, STATE).await;
}

fn led_on(id: &str) -> String {
    format!("document.getElementById('led-{id}').dataset.on === '1'")
}

fn led_off(id: &str) -> String {
    format!("document.getElementById('led-{id}').dataset.on === '0'")
}

/// ERR seen both lit and dark while the model says it blinks.
async fn err_blinks(client: &Client) {
    js(client, "window.seen = new Set()").await;
    until(
        client,
        "document.getElementById('led-ERR').dataset.err === 'blinking' && window.seen.add(document.getElementById('led-ERR').dataset.on).size === 2",
        "ERR blinking (lit and dark in turn)",
    )
    .await;
}

/// The page is paused, RESET pressed on it: the model's errors gone, ERR as in the
/// model's initial state (`off`; the mixing unit blinks until its first solenoid).
/// `initial`: a JavaScript expression of the ERR LED's state after RESET (the model's
/// initial state; the PLC's outputs stay as they were when paused).
async fn reset_clears_err(client: &Client, initial: &str) {
    click(client, "#pause").await;
    until(client, "LAB.state.paused", "paused").await;
    click(client, "#button-reset").await;
    until(
        client,
        &format!("document.getElementById('led-ERR').dataset.err === ({initial}) && LAB.state.errors.length === 0"),
        "ERR as in the initial state after RESET",
    )
    .await;
}

/// The mixing unit's ERR after RESET: blinking "no solenoid yet" while no solenoid valve
/// is open; off when the paused program holds one open (its outputs stay over RESET: where
/// the program was when paused is a matter of timing).
const MIXING_INITIAL_ERR: &str =
    "['SV1', 'SV2', 'SV3', 'SV4', 'SV5'].some((s) => LAB.state.signals[s]) ? 'off' : 'blinking'";

/// A violation listed; after the time-line has moved past it, a click on it shows it.
async fn timeline_shows_past_violation(client: &Client) {
    until(client, "LAB.violations.length > 0", "a violation listed").await;
    js(client, "(document.getElementById('window').value = '10', document.getElementById('window').dispatchEvent(new Event('change')))").await;
    click(client, "#speed-max").await;
    until(
        client,
        "LAB.view.follow && LAB.state.t > LAB.violations[0].time_s + 30 && LAB.view.shown.violations === 0",
        "the violation scrolled out of the window",
    )
    .await;
    click(client, "#violations li").await;
    until(
        client,
        "!LAB.view.follow && LAB.view.shown.violations > 0 && LAB.view.shown.start <= LAB.violations[0].time_s",
        "the time-line scrolled back to the violation",
    )
    .await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_four_mimics_in_a_real_browser() {
    let Some((driver, chromium)) = browser_available() else {
        return;
    };
    let driver = Driver::start(&driver, chromium);
    let client = driver.session(1280, 900).await;

    // --- Slide: the track follows the reference program; EM1 then EM2.
    // (real time: the slide rests at K4 for only half a second)
    client
        .goto(&mimic("slide", "slide.st", Speed::Times(1.0)).await)
        .await
        .unwrap();
    until(
        &client,
        &format!("{} && {}", led_on("pos-10"), led_on("K4")),
        "the slide at K4",
    )
    .await;
    until(
        &client,
        &format!("{} && {}", led_on("EM2"), led_off("EM1")),
        "the slide going back",
    )
    .await;
    until(
        &client,
        &format!("{} && {}", led_on("pos-7"), led_on("K3")),
        "the slide at K3",
    )
    .await;

    // Collision: ERR blinks; RESET works; overtravel (the other wrong program) steady.
    client
        .goto(&mimic("slide", "class/carol.st", Speed::Times(1.0)).await)
        .await
        .unwrap();
    err_blinks(&client).await;
    client
        .goto(&mimic("slide", "class/boris.st", Speed::Times(10.0)).await)
        .await
        .unwrap();
    until(
        &client,
        &format!(
            "document.getElementById('led-ERR').dataset.err === 'steady' && {} && {}",
            led_on("K1"),
            led_on("K4")
        ),
        "steady ERR and every K lit after overtravel",
    )
    .await;
    reset_clears_err(&client, "'off'").await;
    until(
        &client,
        &format!("LAB.state.state.position === 1 && {}", led_on("pos-1")),
        "the slide back at K1",
    )
    .await;
    timeline_shows_past_violation(&client).await;

    // --- Crossroad: the heads follow the program.
    client
        .goto(&mimic("crossroad", "crossroad.st", Speed::Times(10.0)).await)
        .await
        .unwrap();
    until(
        &client,
        &format!("{} && {}", led_on("zel_spodek"), led_on("cerv_vrch")),
        "lower green, upper red",
    )
    .await;
    until(
        &client,
        &format!(
            "{} && {} && {}",
            led_on("zel_vrch"),
            led_on("zel_chodci"),
            led_on("cerv_spodek")
        ),
        "upper and pedestrians green",
    )
    .await;
    client
        .goto(
            &mimic(
                "crossroad",
                "wrong/crossroad_no_interlock.st",
                Speed::Times(10.0),
            )
            .await,
        )
        .await
        .unwrap();
    until(
        &client,
        "LAB.violations.some(v => v.kind.name === 'conflicting-greens')",
        "conflicting greens listed",
    )
    .await;

    // --- Mixing: ERR blinks until the first solenoid; tanks fill; overflow, RESET.
    client
        .goto(&mimic("mixing", "mixing.st", Speed::Times(1.0)).await)
        .await
        .unwrap();
    err_blinks(&client).await;
    click(&client, "#speed-10").await;
    until(
        &client,
        &format!("{} && {}", led_on("SV1"), led_on("H3")),
        "tank 1 filling past its minimum",
    )
    .await;
    until(
        &client,
        "Number(document.getElementById('liquid-1').getAttribute('height')) > 60",
        "tank 1 drawn more than half full",
    )
    .await;
    client
        .goto(&mimic("mixing", "wrong/mixing_overflow.st", Speed::Times(10.0)).await)
        .await
        .unwrap();
    until(
        &client,
        "document.getElementById('led-ERR').dataset.err === 'steady'",
        "steady ERR after the overflow",
    )
    .await;
    reset_clears_err(&client, MIXING_INITIAL_ERR).await;
    timeline_shows_past_violation(&client).await;

    // --- Washing: the drum turns, the level LEDs and the readout follow; overheat, RESET.
    client
        .goto(&mimic("washing", "washing.st", Speed::Times(10.0)).await)
        .await
        .unwrap();
    until(
        &client,
        &format!("{} && {}", led_on("napousteni"), led_on("topeni")),
        "filling and heating",
    )
    .await;
    until(
        &client,
        &format!("{} && {}", led_on("voda_100"), led_on("buben_vpravo")),
        "full, pre-wash turning",
    )
    .await;
    // The drum steps every half second (simulated): its LED is the state's position,
    // and the time-line has recorded it turning.
    until(
        &client,
        "document.getElementById('led-drum-' + LAB.state.state.drum).dataset.on === '1' && new Set(LAB.changes.filter(c => LAB.channels[c.channel].name === 'drum').map(c => c.value)).size >= 3",
        "the drum LEDs turning",
    )
    .await;
    until(
        &client,
        "document.getElementById('washing-readout').textContent.includes('°C')",
        "the readout",
    )
    .await;
    client
        .goto(&mimic("washing", "wrong/washing_overheat.st", Speed::Times(10.0)).await)
        .await
        .unwrap();
    until(
        &client,
        "document.getElementById('led-ERR').dataset.err === 'steady'",
        "steady ERR after overheating",
    )
    .await;
    reset_clears_err(&client, "'off'").await;
    timeline_shows_past_violation(&client).await;

    // --- A project of several models: an index, each mimic at its own address.
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
    let address = listener.local_addr().unwrap();
    let mimics = vec![
        (
            "the slide".to_owned(),
            settings("slide", "slide.st", Speed::Times(1.0)),
        ),
        (
            "the crossroad".to_owned(),
            settings("crossroad", "crossroad.st", Speed::Times(10.0)),
        ),
    ];
    tokio::spawn(async move { serve_many(listener, mimics).await.unwrap() });
    client.goto(&format!("http://{address}/")).await.unwrap();
    until(
        &client,
        "document.querySelectorAll('#models a').length === 2",
        "the index of two models",
    )
    .await;
    click(&client, "#models li:nth-child(2) a").await;
    until(
        &client,
        "location.pathname === '/m/1/' && LAB.state && LAB.state.model === 'crossroad'",
        "the crossroad's mimic",
    )
    .await;
    until(
        &client,
        &format!("{} && {}", led_on("zel_vrch"), led_on("cerv_spodek")),
        "its heads following its program",
    )
    .await;
    let _ = client.close().await;
}
