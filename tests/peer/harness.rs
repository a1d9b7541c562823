//! What the Rust tests that talk to the independent IEC 104 peer share: where the peer
//! scripts are, whether c104 and tshark are installed, and a tshark capture checked by
//! the IEC 104 dissector. Included by those tests with
//! `#[path = "../../../tests/peer/harness.rs"] mod peer;`.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use serde_json::Value;

/// The repository's root (the including crate lives in `crates/NAME`).
pub(crate) fn repository_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// A script of `tests/peer/`.
pub(crate) fn peer_script(name: &str) -> PathBuf {
    repository_root().join("tests/peer").join(name)
}

/// Whether c104 and tshark are here; panics when they must be (CI) and are not.
pub(crate) fn peers_available() -> bool {
    let c104 = Command::new("python3")
        .args(["-c", "import c104"])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|status| status.success());
    let tshark = Command::new("tshark")
        .arg("--version")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|status| status.success());
    if c104 && tshark {
        return true;
    }
    let message = format!(
        "interoperability peers missing (c104: {c104}, tshark: {tshark}); run scripts/install-test-deps.sh"
    );
    if std::env::var("STANICE_REQUIRE_PEERS").as_deref() == Ok("1") {
        panic!("{message}");
    }
    eprintln!("SKIPPED: {message}");
    false
}

/// A tshark capture of one port, checked by a dissector when stopped.
pub(crate) struct Capture {
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
    #[allow(dead_code)] // not every including test captures serial protocols
    pub(crate) fn start_ft12(label: &str, port: u16, protocol: &'static str) -> Capture {
        let mut capture = Capture::start(label, port);
        capture.ft12_protocol = Some(protocol);
        capture
    }

    /// Starts capturing `port` on loopback; `label` names the capture file.
    pub(crate) fn start(label: &str, port: u16) -> Capture {
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
    pub(crate) fn stop_and_check(mut self) -> Value {
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
