//! The serial-line tools over TCP (as terminal servers and gateways carry them), captured
//! with tshark and decoded by Wireshark's own IEC 101 and IEC 103 dissectors: every frame
//! must dissect without a malformed packet, an expert warning or leftover bytes.

#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing
)]

use std::process::{Command, Stdio};
use std::time::Duration;

use testkit::peers;
use testkit::ports::{free_port, listening_within};
use testkit::process::{assert_success, run_bounded, Background};

fn stanice() -> Command {
    let mut command = Command::new(env!("CARGO_BIN_EXE_stanice"));
    command.stdin(Stdio::null());
    command
}

const POINTS: &str = "ioa,type,value,name\n\
281,M_SP_TB_1,1,FA1 closed\n\
2000,M_DP_TB_1,2,breaker\n\
1100,M_ME_NA_1,0.335114,U12\n\
5000,M_ME_NC_1,1904673.75,P\n\
2100,C_DC_NA_1,,breaker command\n";

#[test]
fn iec101_over_tcp_dissects_cleanly() {
    if !peers::peers_available() {
        return;
    }
    let port = free_port();
    let points =
        std::env::temp_dir().join(format!("stanice-101-capture-{}.csv", std::process::id()));
    std::fs::write(&points, POINTS).unwrap();
    let capture = peers::Capture::start_ft12("iec101", port, "iec60870_101");
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
    assert!(
        listening_within(port, Duration::from_secs(20)),
        "nothing listens on port {port}"
    );
    let mut master = stanice();
    master.args([
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
    ]);
    let out = assert_success(&run_bounded(master, 60));
    assert!(out.contains("\"actterm\""), "{out}");
    let report = capture.stop_and_check();
    eprintln!("capture report: {report}");
    // End of initialisation, clock sync and interrogation confirmed, 4 points, termination.
    assert!(report["asdus"].as_u64().unwrap() >= 10, "{report}");
}

#[test]
fn iec103_over_tcp_dissects_cleanly() {
    if !peers::peers_available() {
        return;
    }
    let port = free_port();
    let capture = peers::Capture::start_ft12("iec103", port, "iec60870_5_103");
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
    assert!(
        listening_within(port, Duration::from_secs(20)),
        "nothing listens on port {port}"
    );
    let mut master = stanice();
    master.args([
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
    ]);
    let out = assert_success(&run_bounded(master, 60));
    assert!(out.contains("\"positive\":true"), "{out}");
    let report = capture.stop_and_check();
    eprintln!("capture report: {report}");
    // Identification, time sync, GI (5 indications and its end), the command and its
    // acknowledgement at least.
    assert!(report["asdus"].as_u64().unwrap() >= 11, "{report}");
}
