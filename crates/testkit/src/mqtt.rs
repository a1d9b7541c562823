//! The MQTT peers of the Sparkplug B tests: a mosquitto broker on a free loopback port
//! (Debian package `mosquitto`), the independent consumer `crates/sparkplug/tests/consumer.py`
//! (paho-mqtt and Eclipse Tahu's published protobuf, PyPI `paho-mqtt`, `tahu`), and a
//! project whose node changes by itself (a simulated balance).

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

/// A mosquitto broker, stopped on drop.
pub struct Broker {
    child: Child,
    /// Its loopback port.
    pub port: u16,
    _dir: tempfile::TempDir,
}

impl Drop for Broker {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn mosquitto() -> Option<PathBuf> {
    ["/usr/sbin/mosquitto", "/usr/bin/mosquitto"]
        .iter()
        .map(PathBuf::from)
        .find(|p| p.exists())
}

/// Whether mosquitto, paho-mqtt and tahu are here; says SKIPPED (or fails in CI) when not.
pub fn peers_available() -> bool {
    let broker = mosquitto().is_some();
    let consumer = crate::peers::python_imports("paho.mqtt.client, tahu.sparkplug_b_pb2");
    if broker && consumer {
        return true;
    }
    crate::peers::skip_or_fail(&format!(
        "Sparkplug peers missing (mosquitto: {broker}, paho-mqtt and tahu: {consumer}); run scripts/install-test-deps.sh"
    ));
    false
}

/// Starts mosquitto on a free loopback port and waits until it accepts.
pub fn start_broker() -> Broker {
    let dir = tempfile::tempdir().unwrap();
    let port = crate::ports::free_port();
    let config = dir.path().join("mosquitto.conf");
    std::fs::write(
        &config,
        format!("listener {port} 127.0.0.1\nallow_anonymous true\npersistence false\n"),
    )
    .unwrap();
    let child = Command::new(mosquitto().unwrap())
        .arg("-c")
        .arg(&config)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let broker = Broker {
        child,
        port,
        _dir: dir,
    };
    assert!(
        crate::ports::listening_within(port, Duration::from_secs(20)),
        "mosquitto does not listen on {port}"
    );
    broker
}

/// The consumer script, its output lines on a channel.
pub struct Consumer {
    child: Child,
    /// Its standard output, line by line.
    pub lines: mpsc::Receiver<String>,
}

impl Drop for Consumer {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

impl Consumer {
    /// Starts `consumer.py` and waits until it is subscribed.
    pub fn start(port: u16, group: &str, node: &str, min_data: u32, timeout_s: u32) -> Consumer {
        let script = crate::repository_root().join("crates/sparkplug/tests/consumer.py");
        let mut child = Command::new("python3")
            .arg(script)
            .args([
                port.to_string(),
                group.to_owned(),
                node.to_owned(),
                min_data.to_string(),
                timeout_s.to_string(),
            ])
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .spawn()
            .unwrap();
        let stdout = child.stdout.take().unwrap();
        let (sender, lines) = mpsc::channel();
        std::thread::spawn(move || {
            for line in BufReader::new(stdout).lines().map_while(Result::ok) {
                if sender.send(line).is_err() {
                    return;
                }
            }
        });
        let consumer = Consumer { child, lines };
        consumer.wait_for(|l| l == "READY", Duration::from_secs(30));
        consumer
    }

    /// Waits for a line that `matches`, returning it; panics at the deadline.
    pub fn wait_for(&self, matches: impl Fn(&str) -> bool, within: Duration) -> String {
        let deadline = Instant::now() + within;
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            match self.lines.recv_timeout(left) {
                Ok(line) if matches(&line) => return line,
                Ok(_) => {}
                Err(error) => panic!("consumer: no expected line within {within:?}: {error}"),
            }
        }
    }
}

/// A one-node project whose simulated balance changes its weight by itself.
pub fn balance_project(dir: &Path, name: &str) {
    std::fs::write(
        dir.join("station.toml"),
        format!(
            r#"
[station]
name = "{name}"
time_zone = "UTC"

[[node]]
name = "S7"
common_address = 1

[[node.device]]
name = "BAL"
kind = "balance"
description = "the sorter's balance"
ioa_base = 5000
settings = {{ simulate = "green 2", seed = 5 }}
"#
        ),
    )
    .unwrap();
}
