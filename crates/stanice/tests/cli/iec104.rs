//! The IEC 104 tools against `stanice iec104 server`: the client's JSON, times and analyser
//! lines, a command's exit code and the order of its answers, decode, and the server's
//! point file, command age and redundancy options.

use std::io::Read;
use std::process::{Command, Output};

use serde_json::Value;
use testkit::ports::free_port;
use testkit::process::{run_bounded, start_until};

use crate::support::*;

#[test]
fn client_prints_every_point_as_json() {
    let port = free_port();
    let _server = outstation(port, &[]);
    let mut client = stanice();
    client.args([
        "iec104",
        "client",
        &format!("127.0.0.1:{port}"),
        "--ca",
        "7",
        "--gi",
        "--json",
        "--exit-after-gi",
    ]);
    let output = run_bounded(client, 20);
    assert!(output.status.success());
    let lines: Vec<Value> = String::from_utf8_lossy(&output.stdout)
        .lines()
        .map(|line| {
            serde_json::from_str(line).unwrap_or_else(|error| panic!("not JSON ({error}): {line}"))
        })
        .collect();
    let point = |ioa: u64| {
        lines
            .iter()
            .find(|line| line["ioa"] == ioa && line["cot"] == "inrogen")
            .unwrap_or_else(|| panic!("no GI line for {ioa} in {lines:#?}"))
    };
    for line in lines.iter().filter(|line| line.get("ioa").is_some()) {
        for field in ["type", "cot", "ca", "ioa", "value", "quality", "time"] {
            assert!(line.get(field).is_some(), "{field} missing in {line}");
        }
    }
    assert_eq!(point(281)["type"], "M_SP_NA_1");
    assert_eq!(point(281)["value"], true);
    assert_eq!(point(281)["ca"], 7);
    assert_eq!(point(2000)["type"], "M_DP_NA_1");
    assert_eq!(point(2000)["value"], 2);
    assert_eq!(point(1100)["raw"], 10981);
    assert!((point(1100)["value"].as_f64().unwrap() - 0.335114).abs() < 1e-6);
    assert_eq!(point(5000)["value"], 1904673.75);
    assert_eq!(point(282)["quality"], serde_json::json!([]));
    // Counters answer counter interrogation, not GI.
    assert!(!lines.iter().any(|line| line["ioa"] == 800));
    // Times say their zone: UTC by default, as the test servers stamp.
    assert!(
        point(281)["received"].as_str().unwrap().ends_with('Z'),
        "{}",
        point(281)
    );
}

/// With `--time-zone` the client reads the station's time tags in that zone and prints
/// them, and the receive time, with the zone's offset (it printed the receive time in
/// UTC beside time tags in local time, and JSON times without an offset).
#[test]
fn the_client_prints_times_with_the_offset_of_its_zone() {
    let port = free_port();
    let _server = outstation(
        port,
        &[
            "--simulate",
            "--simulate-interval",
            "0.1",
            "--time-zone",
            "Europe/Prague",
        ],
    );
    let mut client = stanice();
    client.args([
        "iec104",
        "client",
        &format!("127.0.0.1:{port}"),
        "--ca",
        "7",
    ]);
    client.args(["--json", "--time-zone", "Europe/Prague", "--duration", "4"]);
    let output = run_bounded(client, 30);
    assert!(output.status.success(), "{output:?}");
    let lines: Vec<Value> = String::from_utf8_lossy(&output.stdout)
        .lines()
        .filter_map(|line| serde_json::from_str(line).ok())
        .collect();
    let prague = |text: &str| text.ends_with("+01:00") || text.ends_with("+02:00");
    let tagged: Vec<&Value> = lines
        .iter()
        .filter(|line| line["time"].is_string())
        .collect();
    assert!(!tagged.is_empty(), "no time-tagged object in {lines:#?}");
    for line in tagged {
        assert!(prague(line["time"].as_str().unwrap()), "{line}");
        assert!(prague(line["received"].as_str().unwrap()), "{line}");
        // The tag and the receipt name the same moment (the server stamps it as it sends).
        let tag = chrono::DateTime::parse_from_rfc3339(line["time"].as_str().unwrap()).unwrap();
        let received =
            chrono::DateTime::parse_from_rfc3339(line["received"].as_str().unwrap()).unwrap();
        assert!(
            (received - tag).num_seconds().abs() < 60,
            "tag and receipt an hour apart: {line}"
        );
    }
}

#[test]
fn client_prints_analyser_lines_and_simulated_events() {
    let port = free_port();
    let _server = outstation(port, &["--simulate", "--simulate-interval", "0.05"]);
    let mut client = stanice();
    client.args([
        "iec104",
        "client",
        &format!("127.0.0.1:{port}"),
        "--ca",
        "7",
        "--gi",
        "--duration",
        "2",
    ]);
    let output = run_bounded(client, 20);
    let text = String::from_utf8_lossy(&output.stdout);
    assert!(
        text.contains("C_IC_NA_1 (100) [sq=0 n=1] cot=actcon(7)"),
        "{text}"
    );
    assert!(text.contains("M_DP_NA_1 (3)"), "{text}");
    assert!(text.contains("cot=actterm(10)"), "{text}");
    assert!(
        text.contains("cot=spont(3)"),
        "no simulated event in {text}"
    );
}

#[test]
fn command_exit_codes_follow_the_confirmation() {
    let port = free_port();
    let _server = outstation(port, &[]);
    let command = |ioa: &str, kind: &str, value: &str, select: bool| {
        send_command(port, ioa, kind, value, select)
    };
    let positive = command("2021", "C_SC_NA_1", "1", false);
    let text = String::from_utf8_lossy(&positive.stdout);
    assert_eq!(positive.status.code(), Some(0), "{text}");
    assert!(
        text.contains("cot=actcon(7)") && text.contains("cot=actterm(10)"),
        "{text}"
    );

    let unknown = command("9999", "C_SC_NA_1", "1", false);
    let text = String::from_utf8_lossy(&unknown.stdout);
    assert_eq!(unknown.status.code(), Some(1), "{text}");
    assert!(
        text.contains("unknown object address(47)") && text.contains("PN"),
        "{text}"
    );

    let select_first = command("2100", "C_DC_NA_1", "ON", true);
    assert_eq!(
        select_first.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&select_first.stdout)
    );

    let wrong_type = command("2021", "C_DC_NA_1", "ON", false);
    assert_eq!(wrong_type.status.code(), Some(1));

    // Nobody listens: exit 2.
    let mut nobody = stanice();
    nobody.args([
        "iec104",
        "command",
        &format!("127.0.0.1:{}", free_port()),
        "--ca",
        "7",
        "--ioa",
        "1",
        "--type",
        "C_SC_NA_1",
        "--value",
        "1",
        "--timeout",
        "2",
    ]);
    assert_eq!(run_bounded(nobody, 20).status.code(), Some(2));
}

#[test]
fn decode_shows_the_thesis_vectors() {
    let mut decode = stanice();
    decode.args([
        "iec104",
        "decode",
        "68 15 00 00 00 00 1F 01 03 00 01 00 D0 07 00 01 D8 76 BB 09 1A 04 11",
    ]);
    let output = run_bounded(decode, 10);
    let text = String::from_utf8_lossy(&output.stdout);
    assert!(output.status.success(), "{text}");
    assert!(text.contains("I-format  N(S)=0 N(R)=0"), "{text}");
    assert!(text.contains("M_DP_TB_1 (31)"), "{text}");
    assert!(text.contains("2017-04-26 09:59:30.424"), "{text}");

    let mut decode = stanice();
    decode.args([
        "iec104",
        "decode",
        "--asdu",
        "0D 01 03 00 01 00 88 13 00 0E 81 E8 49 00",
    ]);
    let text = String::from_utf8_lossy(&run_bounded(decode, 10).stdout).to_string();
    assert!(text.contains("1904673.75"), "{text}");

    // A non-standard cause (COT 0 of the thesis log) is shown, not refused.
    let mut decode = stanice();
    decode.args([
        "iec104",
        "decode",
        "--asdu",
        "2E 01 00 00 01 00 34 08 00 02",
    ]);
    let output = run_bounded(decode, 10);
    assert!(output.status.success());
    assert!(String::from_utf8_lossy(&output.stdout).contains("not defined"));

    // Garbage: reported, exit 1, no panic.
    let mut decode = stanice();
    decode.args(["iec104", "decode", "68 FF 01 02 03"]);
    let output = run_bounded(decode, 10);
    assert_eq!(output.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&output.stdout).contains("malformed"));
}

#[test]
fn a_bad_point_file_names_its_line() {
    let points = write_points("ioa,type,value\n1,M_SP_NA_1,1\n2,M_ME_NC_1,hello\n");
    let mut server = stanice();
    server
        .args(["iec104", "server", "--listen", "127.0.0.1:0", "--points"])
        .arg(&points);
    let output = run_bounded(server, 10);
    assert!(!output.status.success());
    let mut stderr = String::new();
    (&output.stderr[..]).read_to_string(&mut stderr).unwrap();
    assert!(
        stderr.contains(&format!("{}:3: ", points.display())),
        "{stderr}"
    );
    assert!(stderr.contains("hello"), "{stderr}");
}

/// A command point and the monitor point that returns its effect, on one address.
const FEEDBACK_POINTS: &str = "ioa,type,value,name\n\
3000,M_DP_NA_1,1,QF1 position\n\
3000,C_DC_NA_1,,QF1 command\n\
3001,C_SC_NA_1,,horn\n";

/// `stanice iec104 server` on `port` (common address 7) serving FEEDBACK_POINTS, with
/// `extra` options.
fn feedback_outstation(port: u16, extra: &[&str]) -> Command {
    let mut server = stanice();
    server
        .args([
            "iec104",
            "server",
            "--listen",
            &format!("127.0.0.1:{port}"),
            "--ca",
            "7",
        ])
        .args(extra)
        .arg("--points")
        .arg(write_points(FEEDBACK_POINTS));
    server
}

fn send_command(port: u16, ioa: &str, kind: &str, value: &str, select: bool) -> Output {
    let mut command = stanice();
    command.args([
        "iec104",
        "command",
        &format!("127.0.0.1:{port}"),
        "--ca",
        "7",
        "--ioa",
        ioa,
        "--type",
        kind,
        "--value",
        value,
        "--timeout",
        "5",
    ]);
    if select {
        command.arg("--select");
    }
    run_bounded(command, 20)
}

#[test]
fn the_test_tool_confirms_returns_and_terminates_in_order_and_names_the_command() {
    let port = free_port();
    let server = feedback_outstation(port, &[]);
    let (_server, server_lines) = start_watching(server, "IEC 104 outstation on");
    assert!(
        wait_for_line(&server_lines, "IEC 104 outstation on")
            .contains("redundancy connection-is-group"),
        "the test tool's default mode"
    );

    let output = send_command(port, "3000", "C_DC_NA_1", "ON", false);
    let text = String::from_utf8_lossy(&output.stdout);
    assert_eq!(output.status.code(), Some(0), "{text}");
    let position = |needle: &str| {
        text.lines()
            .position(|line| line.contains(needle))
            .unwrap_or_else(|| panic!("no '{needle}' in\n{text}"))
    };
    let (confirmation, returned, termination) = (
        position("cot=actcon(7)"),
        position("cot=retrem(11)"),
        position("cot=actterm(10)"),
    );
    assert!(
        confirmation < returned && returned < termination,
        "ACT_CON, return information, ACT_TERM expected in that order:\n{text}"
    );
    // Each answer is printed when it arrives, before the verdict.
    assert!(termination < position("execute: positive confirmation and terminated"));
    // The server names the command by the command point, not the monitor point beside it.
    let logged = wait_for_line(&server_lines, "command C_DC_NA_1 ioa=3000");
    assert!(logged.contains("(QF1 command)"), "{logged}");
}

#[test]
fn the_test_tool_refuses_time_tagged_commands_older_than_its_maximum_command_delay() {
    // The command tool stamps its commands in UTC; a server reading tags as the time of
    // Kiritimati (UTC+14) finds them 14 hours old.
    let port = free_port();
    let server = feedback_outstation(
        port,
        &[
            "--max-command-age",
            "30",
            "--time-zone",
            "Pacific/Kiritimati",
        ],
    );
    let (_server, server_lines) = start_watching(server, "IEC 104 outstation on");
    let output = send_command(port, "3001", "C_SC_TA_1", "1", false);
    let text = String::from_utf8_lossy(&output.stdout);
    assert_eq!(output.status.code(), Some(1), "{text}");
    assert!(text.contains("execute: NEGATIVE confirmation"), "{text}");
    let refused = wait_for_line(&server_lines, "REFUSED");
    assert!(
        refused.contains("s old, more than the 30.000 s allowed"),
        "{refused}"
    );

    // Untagged commands are not checked.
    let output = send_command(port, "3001", "C_SC_NA_1", "1", false);
    assert_eq!(output.status.code(), Some(0));

    // A UTC server with the same limit executes the same command.
    let port = free_port();
    let server = feedback_outstation(port, &["--max-command-age", "30"]);
    let _server = start_until(server, "IEC 104 outstation on");
    let output = send_command(port, "3001", "C_SC_TA_1", "1", false);
    assert_eq!(
        output.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&output.stdout)
    );
}

#[test]
fn the_test_tool_checks_its_redundancy_options() {
    let points = write_points(FEEDBACK_POINTS);
    for (args, message) in [
        (
            vec!["--mode", "groups-by-address"],
            "needs at least one --group",
        ),
        (
            vec!["--group", "a=127.0.0.1"],
            "--group needs --mode groups-by-address",
        ),
        (vec!["--mode", "nonsense"], "invalid value 'nonsense'"),
        (
            vec!["--mode", "groups-by-address", "--group", "a=not-an-ip"],
            "'not-an-ip' is not an IP address",
        ),
    ] {
        let mut server = stanice();
        server
            .args([
                "iec104",
                "server",
                "--listen",
                "127.0.0.1:0",
                "--duration",
                "0.1",
                "--points",
            ])
            .arg(&points)
            .args(&args);
        let output = run_bounded(server, 20);
        let text = String::from_utf8_lossy(&output.stderr);
        assert!(!output.status.success(), "{args:?} was accepted");
        assert!(text.contains(message), "{args:?}: {text}");
    }
    let mut server = stanice();
    server
        .args([
            "iec104",
            "server",
            "--listen",
            "127.0.0.1:0",
            "--duration",
            "0.1",
            "--mode",
            "groups-by-address",
            "--group",
            "dispatch-a=127.0.0.1,127.0.0.2",
            "--group",
            "others=",
            "--points",
        ])
        .arg(&points);
    let output = run_bounded(server, 20);
    let text = String::from_utf8_lossy(&output.stdout);
    assert!(output.status.success(), "{text}");
    assert!(text.contains("redundancy groups-by-address"), "{text}");
}
