//! What a user reads: tools that never reach their peer say so, one convention for options,
//! messages that say what was meant, `--json` on every data command, and examples in every
//! `--help`.

use serde_json::Value;
use testkit::ports::free_port;
use testkit::process::{assert_success, run_bounded, start_until_line};
use testkit::projects::{fresh_dir, vsetin};

use crate::support::*;

/// Tools that never reach their peer, or whose request is refused, end non-zero with a
/// plain message (they printed a banner and exited 0, or hung, or retried forever).
#[test]
fn tools_that_never_reach_their_peer_say_so_and_fail() {
    // An IEC 101 master asking for station 4 of a line whose slave is 3.
    let points = write_points(POINTS);
    let mut slave = stanice();
    slave
        .args(["iec101", "slave", "--pty", "--address", "3", "--ca", "7"])
        .arg("--points")
        .arg(&points);
    let (_slave, line) = start_until_line(slave, "pty: ");
    let path = line.trim_start_matches("pty: ").trim().to_owned();
    let mut master = stanice();
    master
        .args(["iec101", "master", "--serial", &path, "--parity", "none"])
        .args([
            "--address",
            "4",
            "--ca",
            "7",
            "--timeout",
            "100",
            "--duration",
            "3",
        ]);
    let output = run_bounded(master, 60);
    let stderr = String::from_utf8_lossy(&output.stderr);
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert_eq!(output.status.code(), Some(2), "{stdout}\n{stderr}");
    assert!(stdout.contains("station 4 does not answer"), "{stdout}");
    assert!(stderr.contains("never reached station(s) 4"), "{stderr}");
    assert!(
        !stdout.contains('{') && !stderr.contains("Some("),
        "{stdout}\n{stderr}"
    );

    // An interrogation of a common address the outstation does not have: refused, said,
    // and --exit-after-gi ends with exit 1 instead of waiting for a termination.
    let port = free_port();
    let _outstation = outstation(port, &[]);
    let mut client = stanice();
    client.args(["iec104", "client", &format!("127.0.0.1:{port}")]);
    client.args(["--gi", "--ca", "5", "--exit-after-gi"]);
    let output = run_bounded(client, 30);
    assert_eq!(output.status.code(), Some(1), "{output:?}");
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        stderr.contains("refused the general interrogation"),
        "{stderr}"
    );

    // A host name that does not resolve: said at once, no retrying.
    let mut client = stanice();
    client.args([
        "iec104",
        "client",
        "no-such-host.invalid:2404",
        "--duration",
        "20",
    ]);
    let output = run_bounded(client, 30);
    assert!(!output.status.success());
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(stderr.contains("cannot resolve"), "{stderr}");

    // A server that is not there: the client ends with exit 2 naming the reason.
    let mut client = stanice();
    client.args([
        "iec104",
        "client",
        &format!("127.0.0.1:{}", free_port()),
        "--duration",
        "1",
    ]);
    let output = run_bounded(client, 30);
    assert_eq!(output.status.code(), Some(2), "{output:?}");
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(stderr.contains("never reached"), "{stderr}");

    // A serial device that does not exist: the operating system's reason, no retrying.
    let mut poll = stanice();
    poll.args([
        "lift",
        "poll",
        "--serial",
        "/dev/stanice-no-such-port",
        "--duration",
        "20",
    ]);
    let output = run_bounded(poll, 30);
    assert!(!output.status.success());
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(stderr.contains("No such file or directory"), "{stderr}");
}

/// One convention for the options of every command: durations take their unit (`5s`,
/// `250ms`; a word that is none is refused naming the form), `--ca` is 1 unless given in
/// `client` and `command` alike, and the web HMI's address is `--hmi-listen` in `hmi` and
/// `run` alike.
#[test]
fn options_follow_one_convention() {
    let port = free_port();
    let _server = outstation(port, &["--simulate-interval", "250ms"]);
    let mut command = stanice();
    command.args([
        "iec104",
        "command",
        &format!("127.0.0.1:{port}"),
        "--ca",
        "7",
    ]);
    command.args(["--ioa", "2021", "--type", "C_SC_NA_1", "--value", "ON"]);
    command.args(["--timeout", "5s", "--t1", "15s", "--t3", "1m"]);
    assert_success(&run_bounded(command, 30));

    let mut client = stanice();
    client.args(["iec104", "client", "127.0.0.1:2404", "--duration", "ten"]);
    let output = run_bounded(client, 30);
    assert!(!output.status.success());
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(stderr.contains("500ms, 2s, 10m"), "{stderr}");

    // Without --ca a command goes to common address 1, as the client's interrogation does:
    // this outstation is 7, so it is refused (a negative confirmation, not a usage error).
    let mut command = stanice();
    command.args(["iec104", "command", &format!("127.0.0.1:{port}")]);
    command.args(["--ioa", "2021", "--type", "C_SC_NA_1", "--value", "ON"]);
    let output = run_bounded(command, 30);
    assert_eq!(output.status.code(), Some(1), "{output:?}");

    let mut hmi = stanice();
    hmi.args(["hmi", "--connect", "127.0.0.1:1", "--screens"])
        .arg(vsetin().join("hmi"))
        .args([
            "--hmi-listen",
            "127.0.0.1:0",
            "--store",
            "none",
            "--duration",
            "500ms",
        ]);
    assert_success(&run_bounded(hmi, 60));
    let mut help = stanice();
    help.args(["run", "--help"]);
    assert!(assert_success(&run_bounded(help, 30)).contains("--hmi-listen"));
}

/// Messages a newcomer reads: `plc check` says what it checked, a mistyped name gets a
/// "did you mean", a missing `;` is shown where it goes, and `stanice run` shows an ST
/// error with its excerpt and code as `plc check` does.
#[test]
fn messages_say_what_was_meant() {
    let ok = write_source(
        "ok.st",
        "PROGRAM Main\nVAR Lamp : BOOL; END_VAR\nLamp := TRUE;\nEND_PROGRAM\n",
    );
    let mut check = stanice();
    check.args(["plc", "check"]).arg(&ok);
    let text = assert_success(&run_bounded(check, 30));
    assert!(text.contains("checked 1 file(s): 1 program(s)"), "{text}");

    let typo = write_source(
        "typo.st",
        "PROGRAM Main\nVAR Lamp : BOOL; END_VAR\nLmap := TRUE\nLamp := FALSE;\nEND_PROGRAM\n",
    );
    let mut check = stanice();
    check.args(["plc", "check"]).arg(&typo);
    let output = run_bounded(check, 30);
    assert!(!output.status.success());
    let text = String::from_utf8_lossy(&output.stdout);
    assert!(
        text.contains(":3:13: error: expected ';' at the end of this statement"),
        "{text}"
    );

    let typo = write_source(
        "typo2.st",
        "PROGRAM Main\nVAR Lamp : BOOL; END_VAR\nLmap := TRUE;\nEND_PROGRAM\n",
    );
    let mut check = stanice();
    check.args(["plc", "check"]).arg(&typo);
    let text = String::from_utf8_lossy(&run_bounded(check, 30).stdout).into_owned();
    assert!(text.contains("did you mean `Lamp`?"), "{text}");

    let mut run = stanice();
    run.args(["plc", "run"])
        .arg(&ok)
        .args(["--program", "Mian", "--cycles", "1"]);
    let output = run_bounded(run, 30);
    assert!(!output.status.success());
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(stderr.contains("did you mean `Main`?"), "{stderr}");

    let mut run = stanice();
    run.arg("run")
        .arg(vsetin())
        .args(["--node", "RDRTX", "--store", "none"]);
    let output = run_bounded(run, 60);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(stderr.contains("did you mean `RDRT`?"), "{stderr}");

    // An ST error in a project: the excerpt and the code, as plc check shows them.
    let dir = fresh_dir("st-error");
    let project = copy_vsetin(&dir, "proj");
    let file = project.join("plc/rdrt_io.st");
    let text = std::fs::read_to_string(&file).unwrap();
    let text = text.replacen("END_PROGRAM", "Lmapx := TRUE;\nEND_PROGRAM", 1);
    std::fs::write(&file, text).unwrap();
    let mut run = stanice();
    run.arg("run")
        .arg(&project)
        .args(["--store", "none", "--duration", "1"]);
    let output = run_bounded(run, 60);
    assert!(!output.status.success());
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(stderr.contains("undeclared name 'Lmapx'"), "{stderr}");
    assert!(stderr.contains("| Lmapx := TRUE;"), "the excerpt: {stderr}");
    assert!(stderr.contains("= code: E0101"), "the code: {stderr}");
}

/// `--json` on every command that prints data: command, points and decode print one
/// JSON object a line (events and the client are checked in points_and_events.rs and
/// iec104.rs).
#[test]
fn commands_that_print_data_take_json() {
    let port = free_port();
    let _server = outstation(port, &[]);
    let mut command = stanice();
    command.args([
        "iec104",
        "command",
        &format!("127.0.0.1:{port}"),
        "--ca",
        "7",
    ]);
    command.args([
        "--ioa",
        "2100",
        "--type",
        "C_DC_NA_1",
        "--value",
        "ON",
        "--json",
    ]);
    let text = assert_success(&run_bounded(command, 30));
    let lines: Vec<Value> = text
        .lines()
        .map(|line| serde_json::from_str(line).unwrap_or_else(|e| panic!("{e}: {line}")))
        .collect();
    assert!(lines.iter().any(|l| l["event"] == "sent"), "{text}");
    assert!(
        lines.iter().any(|l| l["event"] == "command_result"
            && l["confirmation"] == "positive"
            && l["terminated"] == true),
        "{text}"
    );

    let mut points = stanice();
    points.arg("points").arg(vsetin()).arg("--json");
    let text = assert_success(&run_bounded(points, 30));
    let first: Value = serde_json::from_str(text.lines().next().unwrap()).unwrap();
    assert!(
        first["ioa"].is_number() && first["name"].is_string(),
        "{first}"
    );

    let mut decode = stanice();
    decode.args(["iec104", "decode", "--json"]);
    decode.args(["68 15 00 00 00 00 1F 01 03 00 01 00 D0 07 00 01 D8 76 BB 09 1A 04 11"]);
    let text = assert_success(&run_bounded(decode, 30));
    let apdu: Value = serde_json::from_str(text.trim()).unwrap();
    assert_eq!(apdu["apci"]["format"], "I");
    assert_eq!(apdu["asdu"]["objects"][0]["ioa"], 2000);
}

/// The `--help` of `stanice` and of every subcommand (found by walking the Commands lists
/// of the help texts themselves) ends with an Examples section (issue 11).
#[test]
fn every_help_has_examples() {
    fn visit(path: &[String], visited: &mut Vec<String>) {
        let mut command = stanice();
        command.args(path).arg("--help");
        let text = assert_success(&run_bounded(command, 20));
        assert!(
            text.contains("\nExamples:\n  stanice "),
            "`stanice {} --help` has no examples:\n{text}",
            path.join(" ")
        );
        // `--verbose` and `--log` alike on every tool.
        assert!(
            text.contains("-v, --verbose") && text.contains("--log <LOG>"),
            "`stanice {} --help` lacks --verbose or --log:\n{text}",
            path.join(" ")
        );
        visited.push(path.join(" "));
        let Some((_, commands)) = text.split_once("\nCommands:\n") else {
            return;
        };
        for line in commands.lines().take_while(|l| !l.trim().is_empty()) {
            let name = line.split_whitespace().next().unwrap();
            if name != "help" {
                let mut sub = path.to_vec();
                sub.push(name.to_owned());
                visit(&sub, visited);
            }
        }
    }
    let mut visited = Vec::new();
    visit(&[], &mut visited);
    for expected in [
        "iec104 client",
        "run",
        "demo",
        "user add",
        "plc run",
        "events",
    ] {
        assert!(visited.iter().any(|v| v == expected), "{visited:?}");
    }

    // The analyser's quality notation is explained where it is used.
    let mut client = stanice();
    client.args(["iec104", "client", "--help"]);
    let text = assert_success(&run_bounded(client, 20));
    assert!(text.contains("[iv nt sb bl]"), "{text}");
    assert!(text.contains("NT not topical"), "{text}");
    assert!(text.contains("UPPER CASE = set"), "{text}");
}

/// A store address without its scheme is refused once, in plain words: the cause is not
/// printed twice ("bad store URL ...: bad store URL ...").
#[test]
fn a_bad_store_address_is_said_once() {
    let mut run = stanice();
    run.arg("run")
        .arg(vsetin())
        .args(["--store", "/tmp/no-scheme.db", "--log", "error"]);
    let output = run_bounded(run, 60);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_ne!(output.status.code(), Some(0), "{stderr}");
    assert_eq!(stderr.matches("bad store URL").count(), 1, "{stderr}");
    assert!(stderr.contains("expected sqlite:PATH"), "{stderr}");
}
