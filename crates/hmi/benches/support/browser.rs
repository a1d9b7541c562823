//! What the HMI's browser benchmarks share beyond the workspace's Chromium support
//! (`testkit::chromium`): a session logged in through the API, the wall clock the browser
//! stamps with, and the p50/p99 report.
#![allow(dead_code)]

use std::time::{SystemTime, UNIX_EPOCH};

use fantoccini::Client;
use serde_json::json;

pub(crate) use testkit::chromium::js;
use testkit::chromium::{browser_available, Driver};

/// chromedriver and a browser session through it, or `None` (SKIPPED printed) without
/// them; the driver lives as long as the caller keeps it.
pub(crate) async fn start() -> Option<(Driver, Client)> {
    let (driver, chromium) = browser_available()?;
    let driver = Driver::start(&driver, chromium);
    let client = driver.session(1280, 1024).await;
    Some((driver, client))
}

/// The wall clock in ms, as the browser's `performance.timeOrigin + now()`.
pub(crate) fn now_ms() -> f64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .unwrap_or_default()
        .as_secs_f64()
        * 1e3
}

/// Logs `user` in through the HMI's API from its login page.
pub(crate) async fn login(client: &Client, url: &str, user: &str, password: &str) {
    client.goto(&format!("{url}/login")).await.unwrap();
    let login = client
        .execute_async(
            "const done = arguments[arguments.length - 1];\
             fetch('/api/login', {method: 'POST', headers: {'Content-Type': 'application/json'},\
               body: JSON.stringify({username: arguments[0], password: arguments[1]})})\
             .then(r => done(r.status)).catch(e => done(String(e)));",
            vec![json!(user), json!(password)],
        )
        .await
        .unwrap();
    assert_eq!(login, json!(200));
}

/// One line: the samples' count, p50, p99 and maximum in ms.
pub(crate) fn report(name: &str, mut samples: Vec<f64>) {
    if samples.is_empty() {
        println!("{name:<52} no samples");
        return;
    }
    samples.sort_by(f64::total_cmp);
    let at = |p: f64| samples[((samples.len() as f64 - 1.0) * p).round() as usize];
    println!(
        "{name:<52} n={:<4} p50 {:>6.2} ms  p99 {:>6.2} ms  max {:>6.2} ms",
        samples.len(),
        at(0.5),
        at(0.99),
        samples[samples.len() - 1]
    );
}
