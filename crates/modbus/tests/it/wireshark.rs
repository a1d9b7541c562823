//! Wireshark's Modbus/TCP dissectors (`mbtcp` and `modbus`, an implementation that is not
//! ours) over a captured exchange of our client with our TCP server: every function code
//! both ways and exception responses, with no malformed frame and no expert warning or
//! error.
//!
//! The capture is the workspace's `tests/peer/capture.sh` (tshark on loopback, one port);
//! the check is `tests/peer/check_mbtcp_capture.py` of this crate. Without tshark the
//! test says SKIPPED and passes, unless `STANICE_REQUIRE_PEERS=1` (CI), where it fails.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use modbus::{DataModel, ModelConfig, Units};
use serde_json::Value;
use testkit::peers;
use testkit::process::{run_bounded, run_within};

use crate::support::*;

/// The function codes whose requests and responses the capture must hold.
const FUNCTION_CODES: [u8; 9] = [1, 2, 3, 4, 5, 6, 15, 16, 23];

/// How long the capture may take to show what was sent (dumpcap writes its file every
/// half second or so).
const CAPTURE_WITHIN: Duration = Duration::from_secs(30);

fn tshark_available() -> bool {
    let runs = |program: &str| {
        Command::new(program)
            .arg("--version")
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .status()
            .is_ok_and(|status| status.success())
    };
    if runs("tshark") && runs("python3") {
        return true;
    }
    peers::skip_or_fail("tshark (and python3) missing; run scripts/install-test-deps.sh");
    false
}

fn capture_script() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/peer/capture.sh")
}

/// A tshark capture of one loopback port by `capture.sh` (it returns once tshark
/// captures, and stops it with SIGINT so it flushes); stopped when dropped if the test
/// did not stop it.
struct Capture {
    file: PathBuf,
    stopped: bool,
}

impl Capture {
    fn start(port: u16) -> Capture {
        let file = std::env::temp_dir().join(format!(
            "stanice-modbus-{port}-{}.pcapng",
            std::process::id()
        ));
        let status = Command::new("bash")
            .arg(capture_script())
            .args(["start", &port.to_string()])
            .arg(&file)
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .status()
            .unwrap();
        assert!(status.success(), "tshark capture did not start");
        Capture {
            file,
            stopped: false,
        }
    }

    /// The frames of the file so far that match a display `filter` (the file is being
    /// written: a last block cut short is not counted).
    fn frames(&self, filter: &str) -> usize {
        let mut command = Command::new("tshark");
        command.arg("-n").arg("-r").arg(&self.file).args([
            "-Y",
            filter,
            "-T",
            "fields",
            "-e",
            "frame.number",
        ]);
        let (output, _) = run_within(command, 60);
        String::from_utf8_lossy(&output.stdout)
            .lines()
            .filter(|line| !line.trim().is_empty())
            .count()
    }

    /// Waits (at most [`CAPTURE_WITHIN`]) until the file holds `count` frames matching
    /// `filter`; fails the test, saying `what` was missing, when it does not.
    // The crate's clippy.toml bans the clock and sleeping for its cores; a test waiting on
    // a child's file polls it with both.
    #[allow(clippy::disallowed_methods)]
    fn wait_for(&self, filter: &str, count: usize, what: &str) {
        let deadline = Instant::now() + CAPTURE_WITHIN;
        loop {
            let seen = self.frames(filter);
            if seen >= count {
                return;
            }
            assert!(
                Instant::now() < deadline,
                "the capture did not show {what} ({seen} of {count} frames `{filter}`) within {CAPTURE_WITHIN:?}"
            );
            std::thread::sleep(Duration::from_millis(100));
        }
    }

    fn stop(&mut self) {
        self.stopped = true;
        let status = Command::new("bash")
            .arg(capture_script())
            .arg("stop")
            .arg(&self.file)
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .status()
            .unwrap();
        assert!(status.success(), "tshark capture did not stop cleanly");
    }
}

impl Drop for Capture {
    fn drop(&mut self) {
        if !self.stopped {
            let _ = Command::new("bash")
                .arg(capture_script())
                .arg("stop")
                .arg(&self.file)
                .stdin(Stdio::null())
                .stdout(Stdio::null())
                .stderr(Stdio::null())
                .status();
        }
        let _ = std::fs::remove_file(&self.file);
        let mut stderr = self.file.clone().into_os_string();
        stderr.push(".stderr");
        let _ = std::fs::remove_file(stderr);
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn wireshark_dissects_our_client_and_server_cleanly() {
    if !tshark_available() {
        return;
    }
    let model = DataModel::new(ModelConfig::new(Units::Single(1)));
    let (address, _server) = tcp_server(model.clone()).await;
    let port = address.port();
    let mut capture = tokio::task::block_in_place(|| Capture::start(port));

    // Nothing else connects to the server: the client's connection is the port's only
    // one. Its SYN in the file shows that tshark sees the port before a request is sent.
    let mut client = tcp_client(address, Duration::from_secs(10), 0).await;
    tokio::task::block_in_place(|| {
        capture.wait_for(
            &format!("tcp.dstport == {port} && tcp.flags.syn == 1 && tcp.flags.ack == 0"),
            1,
            "the client's connection",
        );
    });
    // FC 1-6, 15, 16, 23 (the largest reads among them), then exception 2 to FC 3 and
    // exception 1 to a function code the server does not know.
    every_function_code(&mut client, &model, 1).await;
    exceptions_1_and_2(&mut client, 1).await;
    // The client closes, the server closes on its end of stream: once both FINs are in
    // the file, so is everything sent before them.
    drop(client);
    tokio::task::block_in_place(|| {
        capture.wait_for(
            &format!("tcp.port == {port} && tcp.flags.fin == 1"),
            2,
            "both ends closing",
        );
        capture.stop();
    });

    let mut check = Command::new("python3");
    check
        .arg(Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/peer/check_mbtcp_capture.py"))
        .arg(&capture.file)
        .arg(port.to_string())
        .arg("--json");
    let output = tokio::task::block_in_place(|| run_bounded(check, 120));
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(
        output.status.success(),
        "tshark found problems in the frames on port {port}:\n{stdout}\n{}",
        String::from_utf8_lossy(&output.stderr)
    );
    eprintln!("tshark: {stdout}");
    let report: Value = serde_json::from_str(stdout.lines().last().unwrap()).unwrap();
    let count = |key: &str, field: &str| {
        report
            .get(key)
            .and_then(|map| map.get(field))
            .and_then(Value::as_u64)
            .unwrap_or(0)
    };
    for code in FUNCTION_CODES {
        let code = code.to_string();
        assert!(
            count("requests", &code) >= 1,
            "no FC {code} request: {stdout}"
        );
        assert!(
            count("responses", &code) >= 1,
            "no FC {code} response: {stdout}"
        );
    }
    // Every request answered, with its own function code.
    assert_eq!(report["requests"], report["responses"], "{stdout}");
    // The exceptions as Wireshark reads them: function code, exception code.
    assert_eq!(
        report["exceptions"],
        serde_json::json!({"3/2": 1, "65/1": 1}),
        "{stdout}"
    );
    // Each request and each response one Modbus/TCP PDU; Wireshark paired every
    // response but the two exceptions with its request (by transaction id, as a response
    // from the server's port).
    let requests: u64 = report["requests"]
        .as_object()
        .unwrap()
        .values()
        .filter_map(Value::as_u64)
        .sum();
    assert_eq!(report["mbtcp"].as_u64(), Some(2 * requests), "{stdout}");
    assert_eq!(
        report["matched_responses"].as_u64(),
        Some(requests - 2),
        "{stdout}"
    );
}
