//! The serial-line tools over TCP (as terminal servers and gateways carry them), captured
//! with tshark and decoded by Wireshark's own IEC 101 and IEC 103 dissectors: every frame
//! must dissect without a malformed packet, an expert warning or leftover bytes.

#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing
)]

#[path = "../../../tests/peer/harness.rs"]
mod peer;

use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

fn stanice() -> Command {
    let mut command = Command::new(env!("CARGO_BIN_EXE_stanice"));
    command.stdin(Stdio::null());
    command
}

fn free_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port()
}

/// A child killed when dropped.
struct Background(Child);

impl Drop for Background {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// Waits until something listens on the port (at most 20 s).
fn wait_listening(port: u16) {
    let deadline = Instant::now() + Duration::from_secs(20);
    while Instant::now() < deadline {
        if std::net::TcpStream::connect(("127.0.0.1", port)).is_ok() {
            return;
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    panic!("nothing listens on port {port}");
}

/// Runs a command to its end (at most `seconds`) and returns its stdout.
fn run_to_end(command: &mut Command, seconds: u64) -> String {
    let mut child = command
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let deadline = Instant::now() + Duration::from_secs(seconds);
    while Instant::now() < deadline {
        if child.try_wait().unwrap().is_some() {
            let output = child.wait_with_output().unwrap();
            assert!(
                output.status.success(),
                "failed: {}",
                String::from_utf8_lossy(&output.stderr)
            );
            return String::from_utf8_lossy(&output.stdout).into_owned();
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    let _ = child.kill();
    let _ = child.wait();
    panic!("did not finish within {seconds} s");
}

const POINTS: &str = "ioa,type,value,name\n\
281,M_SP_TB_1,1,FA1 closed\n\
2000,M_DP_TB_1,2,breaker\n\
1100,M_ME_NA_1,0.335114,U12\n\
5000,M_ME_NC_1,1904673.75,P\n\
2100,C_DC_NA_1,,breaker command\n";

#[test]
fn iec101_over_tcp_dissects_cleanly() {
    if !peer::peers_available() {
        return;
    }
    let port = free_port();
    let points =
        std::env::temp_dir().join(format!("stanice-101-capture-{}.csv", std::process::id()));
    std::fs::write(&points, POINTS).unwrap();
    let capture = peer::Capture::start_ft12("iec101", port, "iec60870_101");
    let _slave = Background(
        stanice()
            .args([
                "iec101",
                "slave",
                "--listen",
                &format!("127.0.0.1:{port}"),
                "--address",
                "3",
                "--ca",
                "7",
            ])
            .arg("--points")
            .arg(&points)
            .stdout(Stdio::null())
            .spawn()
            .unwrap(),
    );
    wait_listening(port);
    let out = run_to_end(
        stanice().args([
            "iec101",
            "master",
            "--tcp",
            &format!("127.0.0.1:{port}"),
            "--address",
            "3",
            "--ca",
            "7",
            "--gi",
            "--clock-sync",
            "--exit-after-gi",
            "--json",
        ]),
        60,
    );
    assert!(out.contains("\"actterm\""), "{out}");
    let report = capture.stop_and_check();
    eprintln!("capture report: {report}");
    // End of initialisation, clock sync and interrogation confirmed, 4 points, termination.
    assert!(report["asdus"].as_u64().unwrap() >= 10, "{report}");
}

#[test]
fn iec103_over_tcp_dissects_cleanly() {
    if !peer::peers_available() {
        return;
    }
    let port = free_port();
    let capture = peer::Capture::start_ft12("iec103", port, "iec60870_5_103");
    let _relay = Background(
        stanice()
            .args([
                "iec103",
                "relay",
                "--listen",
                &format!("127.0.0.1:{port}"),
                "--cycle",
                "1",
                "--inject",
                "1,1",
            ])
            .stdout(Stdio::null())
            .spawn()
            .unwrap(),
    );
    wait_listening(port);
    let out = run_to_end(
        stanice().args([
            "iec103",
            "master",
            "--tcp",
            &format!("127.0.0.1:{port}"),
            "--gi",
            "--clock-sync",
            "--command",
            "1:160:OFF",
            "--exit-after-commands",
            "--json",
        ]),
        60,
    );
    assert!(out.contains("\"positive\":true"), "{out}");
    let report = capture.stop_and_check();
    eprintln!("capture report: {report}");
    // Identification, time sync, GI (5 indications and its end), the command and its
    // acknowledgement at least.
    assert!(report["asdus"].as_u64().unwrap() >= 11, "{report}");
}
