//! The live path of the web HMI, end to end: a value changes at the station until the
//! browser's DOM shows it, at p50/p99, with 10,000 points on one screen.
//!
//! ```text
//! cargo bench -p hmi --bench live [-- --samples N]
//! ```
//!
//! An IEC 104 outstation (this workspace's server) holds 10,000 measured values; the HMI
//! runs in this process, connected to it; a headless Chromium (Debian's, through
//! chromedriver) shows a screen of 10,000 bound elements. A MutationObserver stamps the
//! moment the measured element's `data-value` changes (`performance.timeOrigin + now()`,
//! the same wall clock as the Rust side's `SystemTime`). Two conditions, side by side:
//! the screen otherwise quiet, and the screen under load with all 10,000 points changing
//! every second (10,000 updates/s through the whole path), each split at the HMI's own
//! broadcast (IEC 104 and the HMI before it, the WebSocket and the page after). The page
//! answers each sample through one asynchronous WebDriver call rather than being polled,
//! so that the measurement puts no tasks on the main thread it measures.
//!
//! First it times filling the screen, twice: in a fresh page load (from the navigation's
//! start, by the page's own performance marks: loading, the live connection and its
//! snapshot, fetching, parsing, indexing and drawing the screen), and as a second screen
//! of 10,000 elements opened from the running page, as an operator's click does.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

#[path = "support/browser.rs"]
mod browser;
#[path = "../tests/support/outstation.rs"]
mod outstation;
use browser::{js, now_ms, report};
use outstation::{float, float_outstation, hmi_of};

use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use iec60870::asdu::Ioa;

const POINTS: u32 = 10_000;

fn screens(dir: &Path) {
    let mut csv = String::from("ioa,type,name,description\n");
    let mut svg =
        String::from("<svg xmlns=\"http://www.w3.org/2000/svg\" viewBox=\"0 0 1000 1000\">\n");
    for i in 1..=POINTS {
        csv.push_str(&format!("{i},M_ME_NC_1,P{i:05},measurement {i}\n"));
        let (x, y) = ((i - 1) % 100 * 10, (i - 1) / 100 * 10);
        svg.push_str(&format!(
            "<rect x=\"{x}\" y=\"{y}\" width=\"9\" height=\"9\" data-point=\"P{i:05}\"/>\n"
        ));
    }
    svg.push_str("</svg>\n");
    std::fs::write(dir.join("points.csv"), csv).unwrap();
    std::fs::write(dir.join("grid.svg"), &svg).unwrap();
    // The same drawing as a second screen, for opening one not yet fetched from a page
    // that is already running (an operator's click).
    std::fs::write(dir.join("grid2.svg"), svg).unwrap();
    std::fs::write(
        dir.join("hmi.toml"),
        "title = \"10,000 points\"\n[[screen]]\nid = \"grid\"\ntitle = \"Grid\"\nfile = \"grid.svg\"\n\
         [[screen]]\nid = \"grid2\"\ntitle = \"Grid 2\"\nfile = \"grid2.svg\"\n",
    )
    .unwrap();
    let mut users = hmi::users::Users::load(&dir.join("users.toml")).unwrap();
    users.add("bench", 0, "bench-password").unwrap();
}

fn main() {
    let samples: usize = std::env::args()
        .skip_while(|a| a != "--samples")
        .nth(1)
        .and_then(|n| n.parse().ok())
        .unwrap_or(200);
    // Says SKIPPED without chromium and chromedriver (scripts/install-test-deps.sh).
    if testkit::chromium::browser_available().is_none() {
        return;
    }
    tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .unwrap()
        .block_on(run(samples));
}

async fn run(samples: usize) {
    // The outstation and the HMI.
    let server = float_outstation(POINTS).await;
    let dir = tempfile::tempdir().unwrap();
    screens(dir.path());
    let hmi = hmi_of(&server, dir.path()).await;
    let url = format!("http://{}", hmi.address);
    // The browser, logged in.
    let Some((_driver, client)) = browser::start().await else {
        return;
    };
    browser::login(&client, &url, "bench", "bench-password").await;
    // The screen opened in a fresh page load: the fill is timed by the page itself, with
    // the performance marks the mimic sets when the screen is drawn and when every bound
    // point shows a valid value, from the navigation's start (loading the page, the
    // session, the live connection's snapshot, fetching, checking and binding the SVG).
    client
        .goto(&format!("{url}/?fill#screen/grid"))
        .await
        .unwrap();
    let started = Instant::now();
    let (drawn, filled, live_open, snapshot) = loop {
        let marks = js(
            &client,
            "(() => { const at = (name) => { const e = performance.getEntriesByName(name);                 return e.length ? e[e.length - 1].startTime : null; };                 return [at('hmi:screen-drawn'), at('hmi:screen-filled'), at('hmi:live-open'),                 at('hmi:snapshot')]; })()",
        )
        .await;
        if let (Some(drawn), Some(filled)) = (marks[0].as_f64(), marks[1].as_f64()) {
            let at = |i: usize| marks[i].as_f64().unwrap_or(f64::NAN);
            break (drawn, filled, at(2), at(3));
        }
        assert!(
            started.elapsed() < Duration::from_secs(60),
            "the screen did not fill: {marks}"
        );
        tokio::time::sleep(Duration::from_millis(20)).await;
    };
    let shown = js(
        &client,
        "document.querySelectorAll('[data-point][data-value]').length",
    )
    .await;
    assert_eq!(
        shown.as_u64(),
        Some(u64::from(POINTS)),
        "elements showing a value"
    );
    // Every mark of the page (app.js, mimic.js: the live connection, its snapshot, the
    // screen fetched, parsed, sanitised, inserted, indexed, drawn, filled), where the
    // time of a fill goes.
    let marks = js(
        &client,
        "performance.getEntriesByType('mark').filter(m => m.name.startsWith('hmi:'))             .map(m => `${m.name.slice(4)} ${m.startTime.toFixed(0)}`).join(', ')",
    )
    .await;
    println!(
        "HMI live path: IEC 104 outstation -> HMI -> WebSocket -> Chromium DOM; screen of {POINTS} bound elements ({filled:.0} ms to fill)"
    );
    println!(
        "  fill stages, from the page's navigation start: live connection open {live_open:.0} ms, its snapshot in {snapshot:.0} ms, screen drawn {drawn:.0} ms, every element showing a valid value {filled:.0} ms"
    );
    println!(
        "  the page's marks (ms): {}",
        marks.as_str().unwrap_or_default()
    );
    let loading = js(
        &client,
        "(() => { const n = performance.getEntriesByType('navigation')[0];             const scripts = performance.getEntriesByType('resource')             .filter(r => r.initiatorType === 'script' || r.initiatorType === 'link');             const last = Math.max(...scripts.map(r => r.responseEnd));             return `document ${n.responseEnd.toFixed(0)}, ${scripts.length} scripts and sheets loaded ${last.toFixed(0)}, DOM interactive ${n.domInteractive.toFixed(0)}, DOMContentLoaded ${n.domContentLoadedEventStart.toFixed(0)}`; })()",
    )
    .await;
    println!(
        "  the page's loading (ms): {}",
        loading.as_str().unwrap_or_default()
    );
    // The second screen opened from the running page, as a click on its link does: from
    // the screen's opening (its fetch not started before) to every element filled.
    js(&client, "(location.hash = '#screen/grid2', true)").await;
    let started = Instant::now();
    let (opened, switched) = loop {
        let marks = js(
            &client,
            "(() => { const at = (name) => { const e = performance.getEntriesByName(name)                 .filter(m => m.detail === 'grid2'); return e.length ? e[e.length - 1].startTime : null; };                 return [at('hmi:screen-open'), at('hmi:screen-filled')]; })()",
        )
        .await;
        if let (Some(opened), Some(filled)) = (marks[0].as_f64(), marks[1].as_f64()) {
            break (opened, filled);
        }
        assert!(
            started.elapsed() < Duration::from_secs(60),
            "the second screen did not fill: {marks}"
        );
        tokio::time::sleep(Duration::from_millis(20)).await;
    };
    let stages = js(
        &client,
        "(() => { const marks = performance.getEntriesByType('mark');             const from = marks.findLastIndex(m => m.name === 'hmi:screen-open');             const open = marks[from].startTime;             return marks.slice(from).filter(m => m.name.startsWith('hmi:screen'))             .map(m => `${m.name.slice(11)} +${(m.startTime - open).toFixed(0)}`).join(', '); })()",
    )
    .await;
    println!(
        "  a second screen of {POINTS} elements opened from the running page: filled {:.0} ms after its opening ({})",
        switched - opened,
        stages.as_str().unwrap_or_default()
    );
    js(
        &client,
        "(() => { window.__seen = []; const target = document.querySelector('[data-point=\"P00001\"]');\
         new MutationObserver(() => { window.__seen.push([target.getAttribute('data-value'),\
           performance.timeOrigin + performance.now()]);\
           const wake = window.__wake; window.__wake = null; if (wake) wake(); })\
         .observe(target, {attributes: true, attributeFilter: ['data-value']}); return true; })()",
    )
    .await;

    // The HMI's own broadcast of live messages, stamped here: where the station -> DOM
    // time goes (IEC 104 and the HMI, or the WebSocket and the page).
    let broadcast_seen: Arc<std::sync::Mutex<Vec<(String, f64)>>> = Arc::default();
    {
        let mut live = hmi.station.subscribe();
        let seen = Arc::clone(&broadcast_seen);
        tokio::spawn(async move {
            loop {
                match live.recv().await {
                    Ok(text) => {
                        if text.contains("\"name\":\"P00001\"") {
                            seen.lock().unwrap().push((text, now_ms()));
                        }
                    }
                    Err(tokio::sync::broadcast::error::RecvError::Lagged(_)) => {}
                    Err(_) => return,
                }
            }
        });
    }
    let mut value = 0.0f32;
    for load in [false, true] {
        let running = Arc::new(AtomicBool::new(load));
        let background = {
            let running = Arc::clone(&running);
            let server = server.clone();
            tokio::spawn(async move {
                // Every point but the measured one, once a second, in steps of 1,000 every
                // 100 ms.
                let mut round = 0u32;
                while running.load(Ordering::Relaxed) {
                    for k in 0..1_000u32 {
                        let ioa = 2 + (round * 1_000 + k) % (POINTS - 1);
                        let _ =
                            server.update(Ioa::try_new(ioa).unwrap(), float(round as f32), None);
                    }
                    round += 1;
                    tokio::time::sleep(Duration::from_millis(100)).await;
                }
            })
        };
        if load {
            tokio::time::sleep(Duration::from_secs(2)).await;
        }
        // The page's frame intervals meanwhile (one animation-frame callback per frame,
        // no task of its own): how long the main thread was held between frames.
        js(
            &client,
            "(() => { window.__frames = []; window.__framing = true; let last = null;\
             const tick = (t) => { if (last !== null) window.__frames.push(t - last); last = t;\
               if (window.__framing) requestAnimationFrame(tick); };\
             requestAnimationFrame(tick); return true; })()",
        )
        .await;
        let mut latencies = Vec::new();
        let mut broadcasts = Vec::new();
        for i in 0..samples {
            value += 1.0;
            js(&client, "(window.__seen.length = 0) === 0").await;
            let sent = now_ms();
            server
                .update(Ioa::try_new(1).unwrap(), float(value), None)
                .unwrap();
            // One WebDriver call per sample, answered by the page when the observer has
            // seen the value: polling the page every few ms would put tasks of the
            // measurement on the main thread it measures.
            let shown = tokio::time::timeout(
                Duration::from_secs(10),
                client.execute_async(
                    "const [expected, done] = arguments;                     const check = () => {                       const hit = window.__seen.find((entry) => parseFloat(entry[0]) === expected);                       if (hit) done(hit[1]); else window.__wake = check;                     };                     check();",
                    vec![serde_json::json!(value)],
                ),
            )
            .await
            .unwrap_or_else(|_| panic!("value {value} never shown"))
            .unwrap()
            .as_f64()
            .unwrap();
            latencies.push(shown - sent);
            {
                let mut seen = broadcast_seen.lock().unwrap();
                let text = format!("\"value\":{value}");
                if let Some((_, at)) = seen.iter().find(|(message, _)| message.contains(&text)) {
                    broadcasts.push(at - sent);
                }
                seen.clear();
            }
            tokio::time::sleep(Duration::from_millis(10 + (i as u64 * 7) % 13)).await;
        }
        running.store(false, Ordering::Relaxed);
        let _ = background.await;
        let frames = js(
            &client,
            "(() => { window.__framing = false; return window.__frames; })()",
        )
        .await;
        report(
            "  the page's frame intervals meanwhile",
            frames
                .as_array()
                .map(|a| a.iter().filter_map(|v| v.as_f64()).collect())
                .unwrap_or_default(),
        );
        report(
            "  of which to the HMI's broadcast (IEC 104 and the HMI)",
            broadcasts,
        );
        report(
            if load {
                "station -> DOM, all 10,000 points changing every s"
            } else {
                "station -> DOM, quiet screen of 10,000 points"
            },
            latencies,
        );
    }
    let _ = client.close().await;
    hmi.shutdown().await;
    server.shutdown();
}
