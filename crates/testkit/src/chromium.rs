//! Headless Chromium for browser tests and benchmarks: finding chromedriver and Chromium
//! (skipped without them unless `STANICE_REQUIRE_PEERS=1`), chromedriver on a free loopback
//! port, sessions of a given window size, and the waits and clicks a person's eye and hand
//! would do. What a page is (the HMI's state for a failure message) is the caller's.

use std::net::TcpStream;
use std::os::unix::process::CommandExt as _;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use fantoccini::{Client, ClientBuilder, Locator};
use serde_json::{json, Value};

use crate::peers;
use crate::ports::free_port;

/// How long any one thing may take to appear in the browser.
pub const WAIT: Duration = Duration::from_secs(20);
/// How long chromedriver may take to listen (a cold start on a busy machine is slow).
pub const DRIVER_START: Duration = Duration::from_secs(60);

/// chromedriver and a Chromium for it, or None (then the test is skipped, unless peers
/// are required).
pub fn browser_available() -> Option<(PathBuf, Option<PathBuf>)> {
    let found = |names: &[&str]| {
        names.iter().find_map(|name| {
            std::env::var_os("PATH").and_then(|paths| {
                std::env::split_paths(&paths)
                    .map(|dir| dir.join(name))
                    .find(|path| path.is_file())
            })
        })
    };
    let driver = std::env::var_os("CHROMEDRIVER")
        .map(PathBuf::from)
        .or_else(|| found(&["chromedriver"]));
    let chromium = std::env::var_os("CHROMIUM")
        .map(PathBuf::from)
        .or_else(|| found(&["chromium", "chromium-browser", "google-chrome"]));
    if let (Some(driver), Some(chromium)) = (&driver, &chromium) {
        return Some((driver.clone(), Some(chromium.clone())));
    }
    let message = format!(
        "browser tests need chromedriver and chromium (found: {}, {}); run scripts/install-test-deps.sh",
        driver.map_or("no chromedriver".into(), |p| p.display().to_string()),
        chromium.map_or("no chromium".into(), |p| p.display().to_string()),
    );
    peers::skip_or_fail(&message);
    None
}

/// chromedriver on a free loopback port, killed when dropped, with a fresh profile folder.
pub struct Driver {
    child: Child,
    url: String,
    chromium: Option<PathBuf>,
    profile: tempfile::TempDir,
    sessions: std::sync::atomic::AtomicUsize,
}

impl Driver {
    /// Starts `driver` (chromedriver) for `chromium` (its default browser when `None`).
    pub fn start(driver: &Path, chromium: Option<PathBuf>) -> Driver {
        // chromedriver may lose its port to another process between our pick and its bind
        // (it then exits), or start slowly on a busy machine: a new port, three times.
        let mut failures = Vec::new();
        for attempt in 1..=3 {
            let port = free_port();
            // A process group of its own: the browsers it starts are in it, and a test
            // that fails (the Driver dropped while unwinding) kills them all, rather
            // than leaving headless Chromiums to eat the CPU of the tests after it.
            let mut child = Command::new(driver)
                .process_group(0)
                .arg(format!("--port={port}"))
                .arg("--allowed-ips=127.0.0.1")
                .stdin(Stdio::null())
                .stdout(Stdio::null())
                .stderr(Stdio::null())
                .spawn()
                .unwrap();
            let deadline = Instant::now() + DRIVER_START;
            let listening = loop {
                if TcpStream::connect(("127.0.0.1", port)).is_ok() {
                    break true;
                }
                if let Ok(Some(status)) = child.try_wait() {
                    failures.push(format!(
                        "attempt {attempt}: exited ({status}) on port {port}"
                    ));
                    break false;
                }
                if Instant::now() >= deadline {
                    let _ = child.kill();
                    let _ = child.wait();
                    failures.push(format!(
                        "attempt {attempt}: not listening on {port} within {DRIVER_START:?}"
                    ));
                    break false;
                }
                std::thread::sleep(Duration::from_millis(50));
            };
            if !listening {
                eprintln!("chromedriver: {}", failures.last().unwrap());
                continue;
            }
            return Driver::with(child, port, chromium);
        }
        panic!("chromedriver did not start: {failures:?}");
    }

    fn with(child: Child, port: u16, chromium: Option<PathBuf>) -> Driver {
        Driver {
            child,
            url: format!("http://127.0.0.1:{port}"),
            chromium,
            profile: tempfile::tempdir().unwrap(),
            sessions: std::sync::atomic::AtomicUsize::new(0),
        }
    }

    /// A new headless Chromium session.
    pub async fn session(&self, width: u32, height: u32) -> Client {
        let mut args = vec![
            "--headless".to_owned(),
            "--no-sandbox".to_owned(),
            "--disable-gpu".to_owned(),
            "--disable-quic".to_owned(),
            "--no-first-run".to_owned(),
            "--disable-background-networking".to_owned(),
            "--disable-component-update".to_owned(),
            "--disable-sync".to_owned(),
            "--disable-dev-shm-usage".to_owned(),
            "--autoplay-policy=no-user-gesture-required".to_owned(),
            format!("--window-size={width},{height}"),
        ];
        let n = self
            .sessions
            .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let profile = self.profile.path().join(format!("profile-{n}"));
        args.push(format!("--user-data-dir={}", profile.display()));
        let mut options = json!({ "args": args });
        if let Some(binary) = &self.chromium {
            options["binary"] = json!(binary.display().to_string());
        }
        let mut capabilities = serde_json::Map::new();
        capabilities.insert("browserName".into(), json!("chrome"));
        capabilities.insert("goog:chromeOptions".into(), options);
        let connector = hyper_util::client::legacy::connect::HttpConnector::new();
        ClientBuilder::new(connector)
            .capabilities(capabilities)
            .connect(&self.url)
            .await
            .expect("no WebDriver session (is chromium installed and matching chromedriver?)")
    }
}

impl Drop for Driver {
    fn drop(&mut self) {
        // The whole group (chromedriver and its browsers); `kill` the program rather
        // than a libc binding for one call.
        let _ = Command::new("kill")
            .args(["-KILL", "--", &format!("-{}", self.child.id())])
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .status();
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Evaluates a JavaScript expression in the page.
pub async fn js(client: &Client, expression: &str) -> Value {
    client
        .execute(&format!("return ({expression});"), Vec::new())
        .await
        .unwrap_or_else(|e| panic!("script `{expression}` failed: {e}"))
}

/// Waits until a JavaScript expression is truthy; fails with `what` and the page's state
/// (the JavaScript expression `state`, a string) after [`WAIT`]. Returns how long it took.
pub async fn until_or_show(client: &Client, expression: &str, what: &str, state: &str) -> Duration {
    let started = Instant::now();
    loop {
        let value = client
            .execute(
                &format!("try {{ return Boolean({expression}); }} catch (e) {{ return false; }}"),
                Vec::new(),
            )
            .await
            .unwrap_or(Value::Bool(false));
        if value == Value::Bool(true) {
            return started.elapsed();
        }
        if started.elapsed() > WAIT {
            let state = js(client, state).await;
            panic!("timed out after {WAIT:?} waiting for {what} (`{expression}`); page: {state}");
        }
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
}

/// Clicks the element `css` selects. An element replaced between finding and clicking
/// (a list re-rendered by a live update) is found again, as a person would, until [`WAIT`].
pub async fn click(client: &Client, css: &str) {
    let started = Instant::now();
    loop {
        let element = client
            .find(Locator::Css(css))
            .await
            .unwrap_or_else(|e| panic!("no element `{css}`: {e}"));
        match element.click().await {
            Ok(()) => return,
            Err(e) if e.is_stale_element_reference() && started.elapsed() < WAIT => {}
            Err(e) => panic!("cannot click `{css}`: {e}"),
        }
    }
}
