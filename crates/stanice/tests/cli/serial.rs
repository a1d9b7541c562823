//! The serial masters against their simulators on pseudo-terminals: IEC 101 master and
//! slave, IEC 103 master and relay (the thesis session, commands, the disturbance record),
//! and the lift monitor.

use std::process::Stdio;
use std::time::{Duration, Instant};

use serde_json::Value;
use testkit::ports::free_port;
use testkit::process::{
    assert_success, run_bounded, start_until_line, start_until_line_keeping_output, wait_for_line,
    Background,
};
use testkit::projects::fresh_dir;

use crate::support::*;

/// `stanice iec101 slave` on a new pseudo-terminal and `stanice iec101 master` on its
/// other end, as two processes: the interrogation in JSON, then a command's echo.
#[test]
fn iec101_master_reads_a_slave_over_a_pseudo_terminal() {
    iec101_master_reads_a_slave(&["--ioa-size", "3"]);
}

/// The same on a balanced point-to-point link without link address.
#[test]
fn iec101_balanced_master_reads_a_slave_over_a_pseudo_terminal() {
    iec101_master_reads_a_slave(&["--ioa-size", "3", "--balanced", "--link-address-size", "0"]);
}

fn iec101_master_reads_a_slave(line_options: &[&str]) {
    let points = write_points(POINTS);
    let mut slave = stanice();
    slave
        .args(["iec101", "slave", "--pty", "--address", "3", "--ca", "7"])
        .args(line_options)
        .arg("--points")
        .arg(&points);
    let (_slave, line) = start_until_line(slave, "pty: ");
    let path = line.trim_start_matches("pty: ").trim().to_owned();
    let mut master = stanice();
    master
        .args([
            "iec101",
            "master",
            "--serial",
            &path,
            "--parity",
            "none",
            "--address",
            "3",
            "--ca",
            "7",
        ])
        .args(line_options)
        .args(["--gi", "--exit-after-gi", "--json"]);
    let output = run_bounded(master, 60);
    let stdout = assert_success(&output);
    let objects: Vec<Value> = stdout
        .lines()
        .map(|line| serde_json::from_str(line).unwrap())
        .collect();
    assert!(objects
        .iter()
        .any(|object| object["event"] == "link_up" && object["address"] == 3));
    let interrogated: Vec<&Value> = objects
        .iter()
        .filter(|object| object["cot"] == "inrogen")
        .collect();
    let ioas: std::collections::BTreeSet<u64> = interrogated
        .iter()
        .map(|object| object["ioa"].as_u64().unwrap())
        .collect();
    // Integrated totals answer counter interrogation only (C_CI_NA_1), not this one.
    assert_eq!(
        ioas,
        [281, 282, 1100, 2000, 5000].into_iter().collect(),
        "{stdout}"
    );
    let breaker = interrogated
        .iter()
        .find(|object| object["ioa"] == 2000)
        .unwrap();
    assert_eq!(breaker["value"], 2, "DPI 2 ON");
    let voltage = interrogated
        .iter()
        .find(|object| object["ioa"] == 1100)
        .unwrap();
    assert!((voltage["value"].as_f64().unwrap() - 0.335114).abs() < 1e-4);
    assert!(objects
        .iter()
        .any(|object| object["type"] == "C_IC_NA_1" && object["cot"] == "actterm"));
}

/// Starts `stanice iec103 relay --pty` with its console on a pipe; returns it, its
/// console and the path for the master.
fn relay_on_a_pty(extra: &[&str]) -> (Background, std::process::ChildStdin, String) {
    let mut relay = stanice();
    relay
        .args(["iec103", "relay", "--pty", "--address", "1"])
        .args(extra)
        .stdin(Stdio::piped());
    let (mut relay, line) = start_until_line(relay, "pty: ");
    let console = relay.0.stdin.take().unwrap();
    (
        relay,
        console,
        line.trim_start_matches("pty: ").trim().to_owned(),
    )
}

/// The PCVDEW6 session of the thesis (spec §6) against the relay simulator, telegram by
/// telegram: a reset to the wrong address times out; at address 1 the reset is
/// acknowledged with ACD, class 2 brings the measurands (zero, then 1.00 x rated after an
/// injection), class 2 before the next cycle brings no data, class 1 the identification
/// `REF630 11.3.` after reset CU and power on.
#[test]
fn iec103_master_replays_the_pcvdew6_session() {
    use std::io::Write as _;
    // One cycle at start and the next in half an hour: the second class 2 poll must find
    // no data, whatever the machine's speed.
    let (_relay, _console, path) = relay_on_a_pty(&["--cycle", "1800"]);
    // Single telegrams are not repeated: a generous answer timeout keeps a loaded machine
    // from turning a slow answer into a missing one.
    let telegrams = |path: &str, address: &str, list: &str| {
        let mut master = stanice();
        master.args([
            "iec103",
            "master",
            "--serial",
            path,
            "--parity",
            "none",
            "--address",
            address,
            "--timeout",
            "3000",
            "--telegrams",
            list,
        ]);
        assert_success(&run_bounded(master, 30))
    };
    let wrong = telegrams(&path, "3", "reset-link");
    assert!(
        wrong.contains("ResetRemoteLink to 3: Error: dataReceiveTimeOut"),
        "{wrong}"
    );
    let session = telegrams(
        &path,
        "1",
        "time,reset-link,class2,class2,class1,class1,class1",
    );
    let lines: Vec<&str> = session.lines().collect();
    let find = |needle: &str| {
        lines
            .iter()
            .position(|line| line.contains(needle))
            .unwrap_or_else(|| panic!("no line with {needle:?} in:\n{session}"))
    };
    assert!(session.contains("Send time:"), "{session}");
    assert!(lines[find("ResetRemoteLink to 1:")].contains("fixed CON Ack  LINK state <OU,AD>= AD"));
    let zero = find("148 Cycl.");
    assert!(
        lines[zero].contains(
            "Ir 0.00, Is 0.00, It 0.00, Ure 0.00, Use 0.00, Ute 0.00, P 0.00, Q 0.00, f 0.00"
        ),
        "{session}"
    );
    assert!(
        lines[zero + 2].contains("RequestClass2 to 1: fixed RES Nodata"),
        "{session}"
    );
    let reset_cu = find("3 RCU ASDU 5");
    assert!(
        lines[reset_cu].contains("Comp: 2 String: >REF630 11.3.<"),
        "{session}"
    );
    assert!(
        lines[find("5 C-Strt ASDU 5")].contains(">REF630 11.3.<"),
        "{session}"
    );

    // Injections, on a relay reporting every second: poll until a cycle carries them.
    let (_relay, mut console, path) = relay_on_a_pty(&["--cycle", "1"]);
    writeln!(console, "inject 1 1").unwrap();
    let deadline = Instant::now() + Duration::from_secs(20);
    loop {
        let poll = telegrams(&path, "1", "reset-link,class2");
        if poll.contains(
            "Ir 1.00, Is 1.00, It 1.00, Ure 1.00, Use 1.00, Ute 1.00, P 0.00, Q 0.00, f 0.00",
        ) {
            break;
        }
        assert!(
            Instant::now() < deadline,
            "the injection never showed: {poll}"
        );
        std::thread::sleep(Duration::from_millis(200));
    }
    writeln!(console, "inject 3 3").unwrap();
    let deadline = Instant::now() + Duration::from_secs(20);
    loop {
        let poll = telegrams(&path, "1", "reset-link,class2");
        // Beyond the limits: clamped at 2.4 x / 1.2 x rated with OV.
        if poll.contains("Ir 2.40 OV") && poll.contains("Ure 1.20 OV") {
            break;
        }
        assert!(Instant::now() < deadline, "no overflow shown: {poll}");
        std::thread::sleep(Duration::from_millis(200));
    }
}

/// A general command refused while the relay is in LOCAL (exit code 1), executed in
/// REMOTE, as JSON lines.
#[test]
fn iec103_command_is_refused_in_local_and_executed_in_remote() {
    use std::io::Write as _;
    let (_relay, mut console, path) = relay_on_a_pty(&[]);
    let master = |extra: &[&str]| {
        let mut master = stanice();
        master
            .args(["iec103", "master", "--serial", &path, "--parity", "none"])
            .args(["--gi", "--json"])
            .args(extra);
        run_bounded(master, 30)
    };
    let command = || master(&["--command", "1:160:OFF", "--exit-after-commands"]);
    let switch_is = |state: &str| {
        let gi = assert_success(&master(&["--exit-after-gi"]));
        gi.lines().any(|line| {
            line.contains("\"inf\":190") && line.contains(&format!("\"state\":\"{state}\""))
        })
    };
    // The console's operation takes effect on its own time: ask until the switch shows it.
    let wait_for_switch = |state: &str| {
        let deadline = Instant::now() + Duration::from_secs(20);
        while !switch_is(state) {
            assert!(Instant::now() < deadline, "the switch never showed {state}");
            std::thread::sleep(Duration::from_millis(100));
        }
    };
    writeln!(console, "local").unwrap();
    wait_for_switch("On");
    let refused = command();
    assert!(!refused.status.success(), "a refused command fails the run");
    let refused = String::from_utf8_lossy(&refused.stdout).into_owned();
    let result: Value = refused
        .lines()
        .map(|line| serde_json::from_str::<Value>(line).unwrap())
        .find(|object| object["event"] == "command")
        .unwrap();
    assert_eq!(result["positive"], false);
    assert_eq!(
        result["timed_out"], false,
        "refused, not unanswered: {refused}"
    );

    writeln!(console, "remote").unwrap();
    wait_for_switch("Off");
    let executed = assert_success(&command());
    assert!(executed.contains("\"positive\":true"), "{executed}");
}

/// An earth fault on the relay simulator: the master uploads its disturbance record
/// (ASDU 23-31) and writes it as COMTRADE 2013, four current channels and the tags.
#[test]
fn iec103_master_writes_the_disturbance_record_as_comtrade() {
    use std::io::Write as _;
    let (_relay, mut console, path) = relay_on_a_pty(&["--inject", "1,1"]);
    let dir = fresh_dir("comtrade");
    let mut master = stanice();
    master
        .args([
            "iec103",
            "master",
            "--serial",
            &path,
            "--parity",
            "none",
            "--gi",
            "--exit-after-records",
            "1",
            "--comtrade",
            "2013",
            "--disturbance-dir",
        ])
        .arg(&dir)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    let child = master.spawn().unwrap();
    // Whenever the fault comes, the master gets its record: announced spontaneously, or
    // listed when the master asks at start-up.
    writeln!(console, "fault").unwrap();
    let output = wait_bounded(child, 60);
    let stdout = assert_success(&output);
    assert!(
        stdout.contains(
            "disturbance record FAN 1 of device 1: 4 channels x 300 samples at 1000 us, 3 tags"
        ),
        "{stdout}"
    );
    let cfg = std::fs::read_to_string(dir.join("device1_fault1.cfg")).unwrap();
    let lines: Vec<&str> = cfg.lines().collect();
    assert_eq!(lines[0], "stanice iec103 master,103 device 1,2013");
    assert_eq!(lines[1], "6,4A,2D");
    assert!(
        lines[2].starts_with("1,IL1,1,,A,1,0,0,-32767,32767,100,1,P"),
        "{cfg}"
    );
    assert!(lines[5].starts_with("4,IN,N,,A,"), "{cfg}");
    assert_eq!(lines[6], "1,FUN160_INF92,,,0");
    assert_eq!(lines[7], "2,FUN1_INF160,,,1");
    assert_eq!(&lines[8..11], ["50", "1", "1000,300"]);
    assert_eq!(&lines[13..], ["ASCII", "1", "0,0", "F,0"]);
    let dat = std::fs::read_to_string(dir.join("device1_fault1.dat")).unwrap();
    assert_eq!(dat.lines().count(), 300);
    // Sample 141 (fault, tripped): trip ON, breaker still closed; sample 221: open.
    let fields = |n: usize| -> Vec<i64> {
        dat.lines()
            .nth(n - 1)
            .unwrap()
            .split(',')
            .map(|f| f.parse().unwrap())
            .collect()
    };
    assert_eq!(&fields(141)[6..], [1, 1]);
    assert_eq!(&fields(221)[6..], [1, 0]);
    assert_eq!(fields(250)[2], 0, "no current once the breaker is open");
}

/// The JSON lines of `stanice lift poll`.
fn lift_lines(stdout: &str) -> Vec<Value> {
    stdout
        .lines()
        .map(|line| serde_json::from_str::<Value>(line).unwrap_or_else(|e| panic!("{e}: {line}")))
        .collect()
}

/// `stanice lift simulate --pty` and `stanice lift poll --serial PATH --json` as two
/// processes: the status held from the simulator's console, the trip counters, a fault
/// injected from the console; a second monitor run with the same archive cursor prints
/// only the fault injected since, and a silent board is reported lost.
#[test]
fn lift_poll_reads_the_simulator_over_a_pseudo_terminal() {
    use std::io::Write as _;
    let mut simulator = stanice();
    simulator
        .args([
            "lift",
            "simulate",
            "--pty",
            "--floors",
            "4",
            "--seed",
            "3",
            "--speed",
            "20",
            "--fault-probability",
            "0",
            "--status-probability",
            "0",
        ])
        .stdin(Stdio::piped());
    let (mut simulator, line, answers) = start_until_line_keeping_output(simulator, "pty: ");
    let mut console = simulator.0.stdin.take().unwrap();
    let path = line.trim_start_matches("pty: ").trim().to_owned();
    // Each console operation is awaited by its answer, so no poll starts before the
    // board has taken it.
    let mut operate = |words: &str, answer: &str| {
        writeln!(console, "{words}").unwrap();
        wait_for_line(&answers, answer);
    };
    operate("status 18", "holding status 18");
    operate("fault 3C", "injected fault 0x3C");
    let archive = std::env::temp_dir().join(format!(
        "stanice-lift-{}-{}.cursor",
        std::process::id(),
        free_port()
    ));
    let poll = |seconds: &str| {
        let mut poll = stanice();
        poll.args([
            "lift",
            "poll",
            "--serial",
            &path,
            "--parity",
            "none",
            "--json",
            "--duration",
            seconds,
            "--poll-period",
            "100",
            "--counters-period",
            "1",
            "--timeout",
            "300",
        ])
        .arg("--archive")
        .arg(&archive);
        run_bounded(poll, 30)
    };
    let lines = lift_lines(&assert_success(&poll("3")));
    let kind = |lines: &[Value], kind: &str| -> Vec<Value> {
        lines
            .iter()
            .filter(|line| line["kind"] == kind)
            .cloned()
            .collect()
    };
    let statuses = kind(&lines, "status");
    let held = statuses
        .iter()
        .find(|s| s["status"] == 18)
        .unwrap_or_else(|| panic!("no status 18 in {lines:?}"));
    assert_eq!(held["status_text"], "Light-curtain fault");
    for field in ["position", "target", "direction", "time"] {
        assert!(!held[field].is_null(), "{field} missing in {held}");
    }
    assert!(held["time"].as_str().unwrap().len() == 8, "{held}");
    let counters = kind(&lines, "counters");
    assert_eq!(
        counters[0]["counters"].as_array().unwrap().len(),
        4,
        "{lines:?}"
    );
    let faults = kind(&lines, "fault");
    assert_eq!(faults.len(), 1, "{lines:?}");
    assert_eq!(faults[0]["fault_code"], 0x3C);
    assert_eq!(faults[0]["fault_text"], "Door fault");
    assert_eq!(faults[0]["index"], 0);
    assert_eq!(kind(&lines, "comm")[0]["status"], "ok");

    // A second monitor run with the stored cursor: only the new fault.
    operate("fault 11", "injected fault 0x11");
    operate("status auto", "status from the lift's operation again");
    let lines = lift_lines(&assert_success(&poll("3")));
    let faults = kind(&lines, "fault");
    assert_eq!(faults.len(), 1, "{lines:?}");
    assert_eq!(faults[0]["fault_code"], 0x11);
    assert_eq!(faults[0]["index"], 1);
    // Released from the console: the lift's own status again.
    assert_eq!(
        kind(&lines, "status").last().unwrap()["status"],
        1,
        "{lines:?}"
    );

    // The board goes silent: communication lost, and a monitor that never heard it ends
    // with exit code 2 saying so.
    operate("silent", "not answering");
    let output = poll("3");
    assert_eq!(output.status.code(), Some(2), "{output:?}");
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(stderr.contains("the board never answered"), "{stderr}");
    let lines = lift_lines(&String::from_utf8_lossy(&output.stdout));
    let comm: Vec<Value> = kind(&lines, "comm");
    assert_eq!(comm.last().unwrap()["status"], "lost", "{lines:?}");
    assert!(kind(&lines, "fault").is_empty());
    let _ = std::fs::remove_file(&archive);
}
