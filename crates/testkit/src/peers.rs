//! The interoperability peers: implementations that are not ours (c104, the Python bindings
//! of lib60870-C; hat-drivers; aiosmtpd; Chromium) and tshark, whose IEC 60870 dissectors
//! check every frame a test captures. The peer scripts live in `tests/peer/` and are
//! installed by `scripts/install-test-deps.sh`.
//!
//! A test whose peer is missing is skipped (it says SKIPPED and passes), unless
//! `STANICE_REQUIRE_PEERS=1` (set by `scripts/test.sh`, hence in CI), where it fails:
//! [`skip_or_fail`] is that rule, for every kind of peer.

use std::path::PathBuf;
use std::process::{Command, Stdio};

use serde_json::Value;

use crate::repository_root;

/// Whether peers must be there (`STANICE_REQUIRE_PEERS=1`): then a missing one fails the
/// test instead of skipping it.
pub fn required() -> bool {
    std::env::var("STANICE_REQUIRE_PEERS").as_deref() == Ok("1")
}

/// A peer is missing (`message` says which and how to install it): panics when peers are
/// required, else prints `SKIPPED: message` for the test to return.
pub fn skip_or_fail(message: &str) {
    if required() {
        panic!("{message}");
    }
    eprintln!("SKIPPED: {message}");
}

/// Whether python3 imports `modules` (a comma-separated list, as in `import`).
pub fn python_imports(modules: &str) -> bool {
    succeeds(Command::new("python3").args(["-c", &format!("import {modules}")]))
}

/// Whether a command runs and ends successfully (its output discarded).
fn succeeds(command: &mut Command) -> bool {
    command
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|status| status.success())
}

/// A script of `tests/peer/`.
pub fn peer_script(name: &str) -> PathBuf {
    repository_root().join("tests/peer").join(name)
}

/// Whether c104 and tshark are here; panics when they must be (CI) and are not.
pub fn peers_available() -> bool {
    let c104 = python_imports("c104");
    let tshark = succeeds(Command::new("tshark").arg("--version"));
    if c104 && tshark {
        return true;
    }
    skip_or_fail(&format!(
        "interoperability peers missing (c104: {c104}, tshark: {tshark}); run scripts/install-test-deps.sh"
    ));
    false
}

/// python3 running the c104 script `script` of `tests/peer/` (`c104_server.py`,
/// `c104_client.py`, `c104_dispatch.py`) against (or listening on) `127.0.0.1:port` with
/// common address 1; the caller adds the script's own options.
pub fn c104(script: &str, port: u16) -> Command {
    let mut command = Command::new("python3");
    command.arg(peer_script(script)).args([
        "--host",
        "127.0.0.1",
        "--port",
        &port.to_string(),
        "--ca",
        "1",
    ]);
    command
}

/// A tshark capture of one port, checked by a dissector when stopped.
pub struct Capture {
    file: PathBuf,
    port: u16,
    /// `None`: IEC 104 (`check_capture.py`); otherwise the FT1.2 protocol carried over
    /// TCP (`iec60870_101`, `iec60870_5_103`, checked by `check_capture_ft12.py`).
    ft12_protocol: Option<&'static str>,
    stopped: bool,
}

impl Capture {
    /// Starts capturing IEC 101 or 103 (`protocol`: tshark's dissector name) carried over
    /// TCP on `port`.
    pub fn start_ft12(label: &str, port: u16, protocol: &'static str) -> Capture {
        let mut capture = Capture::start(label, port);
        capture.ft12_protocol = Some(protocol);
        capture
    }

    /// Starts capturing `port` on loopback; `label` names the capture file.
    pub fn start(label: &str, port: u16) -> Capture {
        let file = std::env::temp_dir().join(format!(
            "stanice-{label}-{port}-{}.pcapng",
            std::process::id()
        ));
        let status = Command::new("bash")
            .arg(peer_script("capture.sh"))
            .args(["start", &port.to_string()])
            .arg(&file)
            .status()
            .unwrap();
        assert!(status.success(), "tshark capture did not start");
        Capture {
            file,
            port,
            ft12_protocol: None,
            stopped: false,
        }
    }

    /// Stops the capture and fails the test on any frame the dissector finds malformed,
    /// undecodable or of unknown type. Returns the checker's JSON report.
    pub fn stop_and_check(mut self) -> Value {
        self.stopped = true;
        let status = Command::new("bash")
            .arg(peer_script("capture.sh"))
            .arg("stop")
            .arg(&self.file)
            .stdout(Stdio::null())
            .status()
            .unwrap();
        assert!(status.success(), "tshark capture did not stop cleanly");
        let mut check = Command::new("python3");
        match self.ft12_protocol {
            None => check.arg(peer_script("check_capture.py")),
            Some(protocol) => check
                .arg(peer_script("check_capture_ft12.py"))
                .args(["--protocol", protocol]),
        };
        let output = check
            .arg(&self.file)
            .arg(self.port.to_string())
            .arg("--json")
            .output()
            .unwrap();
        let stdout = String::from_utf8_lossy(&output.stdout);
        assert!(
            output.status.success(),
            "tshark found problems in the frames on port {}:\n{stdout}\n{}",
            self.port,
            String::from_utf8_lossy(&output.stderr)
        );
        let _ = std::fs::remove_file(&self.file);
        stdout
            .lines()
            .rev()
            .find_map(|line| serde_json::from_str(line).ok())
            .unwrap_or(Value::Null)
    }
}

impl Drop for Capture {
    /// A test that fails before checking its capture must not leave tshark running.
    fn drop(&mut self) {
        if !self.stopped {
            let _ = Command::new("bash")
                .arg(peer_script("capture.sh"))
                .arg("stop")
                .arg(&self.file)
                .stdout(Stdio::null())
                .stderr(Stdio::null())
                .status();
            let _ = std::fs::remove_file(&self.file);
        }
    }
}
