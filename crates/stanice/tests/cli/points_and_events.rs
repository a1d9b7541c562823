//! `stanice points` and `stanice events` on a project: the points a node serves, and the
//! events a run recorded (a project that never ran is refused).

use std::io::{BufRead, BufReader};
use std::process::Stdio;

use serde_json::Value;
use testkit::ports;
use testkit::process::{assert_success, run_bounded};
use testkit::projects::{fresh_dir, vsetin};

use crate::support::*;

/// `stanice events`: a project that never ran is an error and gets no empty store, a
/// reader that stops early (`| head`) ends it quietly, and a cut at --limit is said.
#[test]
fn events_refuses_a_project_that_never_ran_and_survives_a_closed_pipe() {
    let dir = fresh_dir("events-cli");
    let project = copy_vsetin(&dir, "proj");
    let mut events = stanice();
    events.arg("events").arg(&project);
    let output = run_bounded(events, 30);
    assert!(!output.status.success());
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(stderr.contains("has not run yet"), "{stderr}");
    assert!(
        !project.join("events.sqlite").exists(),
        "an empty store was created"
    );

    let port = ports::free_port_range(23);
    let mut run = stanice();
    run.arg("run").arg(&project).args([
        "--port-base",
        &port.to_string(),
        "--speed",
        "10",
        "--duration",
        "2",
    ]);
    assert_success(&run_bounded(run, 60));

    // Three lines through a pipe that closes: no panic, exit 0.
    let mut events = stanice();
    events
        .arg("events")
        .arg(&project)
        .args(["--limit", "10000"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    let mut child = events.spawn().unwrap();
    let mut stdout = BufReader::new(child.stdout.take().unwrap());
    for _ in 0..3 {
        let mut line = String::new();
        stdout.read_line(&mut line).unwrap();
    }
    drop(stdout);
    let output = wait_bounded(child, 30);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");

    // A cut at the limit is said; times carry the station's offset.
    let mut events = stanice();
    events.arg("events").arg(&project).args(["--limit", "5"]);
    let output = run_bounded(events, 30);
    let stdout = assert_success(&output);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(stderr.contains("only the newest 5 records"), "{stderr}");
    let first = stdout.lines().nth(1).unwrap();
    let time = first.split(',').next().unwrap();
    assert!(
        time.ends_with("+01:00") || time.ends_with("+02:00"),
        "Europe/Prague's offset: {first}"
    );
    let mut events = stanice();
    events
        .arg("events")
        .arg(&project)
        .args(["--limit", "2", "--json", "--time-zone", "UTC"]);
    let stdout = assert_success(&run_bounded(events, 30));
    let record: Value = serde_json::from_str(stdout.lines().next().unwrap()).unwrap();
    assert!(record["time"].as_str().unwrap().ends_with('Z'), "{record}");
}

#[test]
fn points_lists_what_the_top_controller_serves() {
    let mut command = stanice();
    command.arg("points").arg(vsetin());
    let output = run_bounded(command, 20);
    assert!(output.status.success());
    let text = String::from_utf8_lossy(&output.stdout);
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("ioa,type,name,description"));
    let rows: Vec<&str> = lines.collect();
    assert!(
        rows.contains(&"281,M_SP_TB_1,RH2_V1_FA1_Zapnut,breaker FA1 closed"),
        "{text}"
    );
    assert!(
        rows.contains(&"2021,C_SC_NA_1,RH2_VypnoutQF1,open QF1"),
        "{text}"
    );
    assert!(
        rows.iter().any(|r| r.starts_with("32,M_SP_TB_1,COMM_RH,")),
        "{text}"
    );
    let mut command = stanice();
    command.arg("points").arg(vsetin()).args(["--node", "RH2"]);
    let output = run_bounded(command, 20);
    let text = String::from_utf8_lossy(&output.stdout);
    assert!(!text.contains("COMM_RH"), "{text}");
    assert_eq!(text.lines().count(), 1 + 18 + 4 + 2);
}

#[test]
fn run_records_events_that_events_lists() {
    let dir = std::env::temp_dir().join(format!("stanice-cli-{}-events", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let store = format!("sqlite:{}", dir.join("events.sqlite").display());
    let _ = std::fs::remove_file(dir.join("events.sqlite"));
    let port = ports::free_port_range(23);
    let mut run = stanice();
    run.arg("run")
        .arg(vsetin())
        .args(["--port-base", &port.to_string(), "--store", &store])
        .args(["--speed", "10", "--duration", "2"]);
    let output = run_bounded(run, 30);
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let mut events = stanice();
    events.arg("events").arg(vsetin()).args([
        "--store",
        &store,
        "--point",
        "RH2_P1_SA1_*",
        "--node",
        "RDRT",
    ]);
    let output = run_bounded(events, 20);
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let text = String::from_utf8_lossy(&output.stdout);
    // At RDRT, the values that came up the hierarchy from RH2.
    assert!(
        text.lines()
            .any(|l| l.contains(",RDRT,RH2_P1_SA1_Dalkove,293,ON,,Spontaneous,link:RH")),
        "{text}"
    );
    assert!(
        text.lines()
            .any(|l| l.contains(",RDRT,RH2_P1_SA1_Mistne,292,OFF,,Spontaneous,link:RH")),
        "{text}"
    );
}
