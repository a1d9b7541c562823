//! What the HMI's browser benchmarks share: chromedriver and a headless Chromium on
//! loopback, a log-in, running JavaScript, and the p50/p99 report.
#![allow(dead_code)]

use std::net::{SocketAddr, TcpListener, TcpStream};
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use fantoccini::{Client, ClientBuilder};
use serde_json::{json, Value};

/// Whether chromium and chromedriver are installed (scripts/install-test-deps.sh).
pub(crate) fn available() -> bool {
    Path::new("/usr/bin/chromedriver").exists()
}

/// The wall clock in ms, as the browser's `performance.timeOrigin + now()`.
pub(crate) fn now_ms() -> f64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .unwrap()
        .as_secs_f64()
        * 1e3
}

pub(crate) fn free_port() -> u16 {
    TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port()
}

async fn session(driver_url: &str, profile: &Path) -> Client {
    let args = vec![
        "--headless".to_owned(),
        "--no-sandbox".to_owned(),
        "--disable-gpu".to_owned(),
        "--disable-quic".to_owned(),
        "--no-first-run".to_owned(),
        "--disable-background-networking".to_owned(),
        "--disable-component-update".to_owned(),
        "--disable-sync".to_owned(),
        "--disable-dev-shm-usage".to_owned(),
        "--window-size=1280,1024".to_owned(),
        format!("--user-data-dir={}", profile.display()),
    ];
    let mut capabilities = serde_json::Map::new();
    capabilities.insert("browserName".into(), json!("chrome"));
    capabilities.insert(
        "goog:chromeOptions".into(),
        json!({"args": args, "binary": "/usr/bin/chromium"}),
    );
    ClientBuilder::new(hyper_util::client::legacy::connect::HttpConnector::new())
        .capabilities(capabilities)
        .connect(driver_url)
        .await
        .expect("no WebDriver session")
}

pub(crate) async fn js(client: &Client, script: &str) -> Value {
    client.execute(script, vec![]).await.unwrap()
}

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

/// chromedriver on a free port and a browser session through it (the driver process and
/// the browser profile live as long as the caller keeps them).
pub(crate) async fn start() -> (Child, tempfile::TempDir, Client) {
    let port = free_port();
    let driver = Command::new("/usr/bin/chromedriver")
        .args([format!("--port={port}"), "--allowed-ips=127.0.0.1".into()])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let deadline = Instant::now() + Duration::from_secs(10);
    while TcpStream::connect(SocketAddr::from(([127, 0, 0, 1], port))).is_err() {
        assert!(Instant::now() < deadline, "chromedriver does not start");
        std::thread::sleep(Duration::from_millis(50));
    }
    let profile = tempfile::tempdir().unwrap();
    let client = session(&format!("http://127.0.0.1:{port}"), profile.path()).await;
    (driver, profile, client)
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
