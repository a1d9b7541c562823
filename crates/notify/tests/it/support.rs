//! Shared by the tests: notices, configurations, the SMTP sink process, webhook servers.

use std::collections::BTreeMap;
use std::io::{BufRead, BufReader, Write};
use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, Command, Stdio};
use std::time::{Duration, Instant};

use axum::Router;
use chrono::{DateTime, TimeZone, Utc};
use notify::{ChannelConfig, Notice, NotifyConfig, RuleConfig, Security, SmtpSettings};

pub(crate) fn t0() -> DateTime<Utc> {
    Utc.with_ymd_and_hms(2026, 3, 1, 8, 15, 0).unwrap()
}

pub(crate) fn notice(source: &str, class: &str) -> Notice {
    Notice {
        source: source.into(),
        class: class.into(),
        code: Some(17),
        title: "Porucha bezpečnostního okruhu".into(),
        text: "Rozpojen bezpečnostní okruh – dveře šachty ve 3. patře.\nKabina stojí.".into(),
        time: t0(),
        link: Some("https://stanice.example.cz/lifts/L3".into()),
    }
}

pub(crate) fn webhook(url: &str) -> ChannelConfig {
    toml::from_str(&format!(
        "kind = \"webhook\"\nurl = \"{url}\"\ntimeout_s = 5"
    ))
    .unwrap()
}

pub(crate) fn email(to: &[&str]) -> ChannelConfig {
    let to: Vec<String> = to.iter().map(|a| format!("\"{a}\"")).collect();
    toml::from_str(&format!("kind = \"email\"\nto = [{}]", to.join(", "))).unwrap()
}

pub(crate) fn smtp_plain(port: u16, timeout_s: u64) -> SmtpSettings {
    let mut smtp = SmtpSettings::new("127.0.0.1", "Stanice <stanice@example.cz>");
    smtp.security = Security::None;
    smtp.port = Some(port);
    smtp.timeout_s = timeout_s;
    smtp
}

pub(crate) fn config(
    smtp: Option<SmtpSettings>,
    channels: Vec<(&str, ChannelConfig)>,
    rules: Vec<RuleConfig>,
) -> NotifyConfig {
    let channels: BTreeMap<String, ChannelConfig> = channels
        .into_iter()
        .map(|(name, channel)| (name.to_owned(), channel))
        .collect();
    NotifyConfig::new(smtp, channels, rules)
}

pub(crate) fn rule(name: &str, channels: &[&str], quiet_period_s: u64) -> RuleConfig {
    let mut rule = RuleConfig::new(name, channels.iter().map(|c| (*c).to_owned()).collect());
    rule.quiet_period_s = quiet_period_s;
    rule
}

/// Whether python3 with aiosmtpd is here; panics when it must be (CI) and is not.
pub(crate) fn smtp_peer_available() -> bool {
    let ok = Command::new("python3")
        .args(["-c", "import aiosmtpd"])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|status| status.success());
    if ok {
        return true;
    }
    let message = "python3 with aiosmtpd missing; run scripts/install-test-deps.sh";
    if std::env::var("STANICE_REQUIRE_PEERS").as_deref() == Ok("1") {
        panic!("{message}");
    }
    eprintln!("SKIPPED: {message}");
    false
}

/// The aiosmtpd server of `tests/smtp_sink.py`, writing each message to a JSON file.
pub(crate) struct SmtpSink {
    child: Child,
    stdin: Option<ChildStdin>,
    dir: tempfile::TempDir,
    pub(crate) port: u16,
}

impl SmtpSink {
    /// Starts the sink and waits (bounded) until its port accepts connections.
    pub(crate) fn start() -> SmtpSink {
        let dir = tempfile::tempdir().unwrap();
        let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/smtp_sink.py");
        let mut child = Command::new("python3")
            .arg(script)
            .arg(dir.path())
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .spawn()
            .expect("start python3");
        let stdin = child.stdin.take();
        let mut line = String::new();
        BufReader::new(child.stdout.take().unwrap())
            .read_line(&mut line)
            .unwrap();
        let port: serde_json::Value =
            serde_json::from_str(&line).unwrap_or_else(|_| panic!("smtp_sink.py said {line:?}"));
        let port = u16::try_from(port["port"].as_u64().unwrap()).unwrap();
        let deadline = Instant::now() + Duration::from_secs(10);
        while std::net::TcpStream::connect(("127.0.0.1", port)).is_err() {
            assert!(Instant::now() < deadline, "SMTP sink never accepted");
            std::thread::sleep(Duration::from_millis(20));
        }
        SmtpSink {
            child,
            stdin,
            dir,
            port,
        }
    }

    /// Waits (bounded) until `count` messages are there; returns them in arrival order.
    pub(crate) fn wait_for(&self, count: usize) -> Vec<serde_json::Value> {
        let deadline = Instant::now() + Duration::from_secs(10);
        loop {
            let mut files: Vec<PathBuf> = std::fs::read_dir(self.dir.path())
                .unwrap()
                .map(|entry| entry.unwrap().path())
                .filter(|path| path.extension().is_some_and(|e| e == "json"))
                .collect();
            if files.len() >= count {
                files.sort();
                return files
                    .iter()
                    .map(|file| {
                        serde_json::from_str(&std::fs::read_to_string(file).unwrap()).unwrap()
                    })
                    .collect();
            }
            assert!(
                Instant::now() < deadline,
                "{} of {count} messages arrived",
                files.len()
            );
            std::thread::sleep(Duration::from_millis(20));
        }
    }
}

impl Drop for SmtpSink {
    fn drop(&mut self) {
        if let Some(mut stdin) = self.stdin.take() {
            let _ = stdin.flush();
        }
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Serves `router` on a free loopback port; the server lives as long as the runtime.
pub(crate) async fn serve(router: Router) -> SocketAddr {
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
    let address = listener.local_addr().unwrap();
    tokio::spawn(async move {
        axum::serve(listener, router).await.unwrap();
    });
    address
}

/// A loopback port nobody listens on (bound, then released).
pub(crate) fn refused_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port()
}
