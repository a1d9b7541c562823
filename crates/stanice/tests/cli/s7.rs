//! `stanice s7`: `serve` as the PLC, `write` and `read` against it as a commissioning
//! engineer uses them — every item kind and type suffix round trip, the JSON lines
//! exactly, an item the PLC refuses among good ones, options after the items, the
//! TSAPs of --rack/--slot and --tsap as the server sees them, misspelt items, a refused
//! connection and a timeout in words, and the server's end on SIGTERM. Ports come from
//! the server binding 127.0.0.1:0 and printing the one it got.

use std::process::{Command, Output};
use std::sync::mpsc;
use std::time::{Duration, Instant};

use testkit::ports::free_port;
use testkit::process::{run_bounded, start_until_line_keeping_output, wait_for_line, Background};

use crate::support::*;

/// A `stanice s7 serve` on a port of its choosing, with its later output lines.
struct Server {
    process: Background,
    addr: String,
    lines: mpsc::Receiver<String>,
}

/// Starts `stanice s7 serve --listen 127.0.0.1:0 EXTRA...`; `json` adds `--json`.
fn serve(json: bool, extra: &[&str]) -> Server {
    let mut command = stanice();
    command
        .args(["s7", "serve", "--listen", "127.0.0.1:0"])
        .args(extra);
    if json {
        command.arg("--json");
    }
    let marker = if json {
        "\"listening\""
    } else {
        "S7 server on "
    };
    let (process, banner, lines) = start_until_line_keeping_output(command, marker);
    let addr = if json {
        let banner: serde_json::Value = serde_json::from_str(&banner).unwrap();
        banner["listening"].as_str().unwrap().to_owned()
    } else {
        let (_, rest) = banner.split_once("S7 server on ").unwrap();
        rest.split_once(": ").unwrap().0.to_owned()
    };
    assert!(!addr.ends_with(":0"), "the real port, not 0: {addr}");
    Server {
        process,
        addr,
        lines,
    }
}

/// Runs `stanice s7 ARGS...` to its end.
fn s7(args: &[&str]) -> Output {
    let mut command = stanice();
    command.arg("s7").args(args);
    run_bounded(command, 60)
}

fn stdout(output: &Output) -> String {
    String::from_utf8_lossy(&output.stdout).into_owned()
}

fn stderr(output: &Output) -> String {
    String::from_utf8_lossy(&output.stderr).into_owned()
}

/// Fails with the command's output unless it exited with `code`.
fn assert_code(output: &Output, code: i32) {
    assert_eq!(
        output.status.code(),
        Some(code),
        "stdout:\n{}\nstderr:\n{}",
        stdout(output),
        stderr(output)
    );
}

/// The next `count` lines of a server (bounded wait).
fn next_lines(lines: &mpsc::Receiver<String>, count: usize) -> Vec<String> {
    let deadline = Instant::now() + Duration::from_secs(20);
    let mut got = Vec::new();
    while got.len() < count {
        let left = deadline.saturating_duration_since(Instant::now());
        assert!(
            !left.is_zero(),
            "only {} of {count} lines: {got:?}",
            got.len()
        );
        if let Ok(line) = lines.recv_timeout(left.min(Duration::from_millis(200))) {
            got.push(line);
        }
    }
    got
}

/// Every item kind, written in one call, then read back in one call.
const WRITES: &[(&str, &str)] = &[
    ("DB1.DBX0.3", "true"),
    ("DB1.DBB1", "200"),
    ("DB1.DBW2", "1234"),
    ("DB1.DBD4", "4000000000"),
    ("DB1.DBD8:REAL", "21.5"),
    ("DB1.DBW12:INT", "-1234"),
    ("DB1.DBD14:DINT", "-100000"),
    ("DB1.DBB18:SINT", "-5"),
    ("MB10", "0x1F"),
    ("MW20", "65535"),
    ("MD24:REAL", "-0.125"),
    ("M11.0", "1"),
    ("IX0.1", "true"),
    ("IB1", "42"),
    ("QB0", "5"),
    ("QX1.2", "true"),
];

/// What `read --json` prints for each item (as written on its command line).
const READS: &[(&str, &str)] = &[
    ("DB1.DBX0.3", "true"),
    ("DB1.DBX0.2", "false"),
    ("DB1.DBB0", "8"),
    ("DB1.DBB1", "200"),
    ("DB1.DBW2", "1234"),
    ("DB1.DBD4", "4000000000"),
    ("DB1.DBD8:REAL", "21.5"),
    ("DB1.DBD8", "1101791232"),
    ("DB1.DBW12:INT", "-1234"),
    ("DB1.DBW12", "64302"),
    ("DB1.DBD14:DINT", "-100000"),
    ("DB1.DBB18:SINT", "-5"),
    ("MB10", "31"),
    ("MW20", "65535"),
    ("MW20:INT", "-1"),
    ("MD24:REAL", "-0.125"),
    ("M11.0", "true"),
    ("MX11.0", "true"),
    ("IX0.1", "true"),
    ("I0.1", "true"),
    ("IB1", "42"),
    ("QB0", "5"),
    ("QX1.2", "true"),
    ("Q1.2", "true"),
    ("db1.dbw2", "1234"),
    ("%MW20", "65535"),
];

#[test]
fn s7_write_then_read_round_trips_every_item_kind_and_type() {
    let server = serve(true, &["--db", "1:64", "--db", "2:16"]);
    let assignments: Vec<String> = WRITES
        .iter()
        .map(|(item, value)| format!("{item}={value}"))
        .collect();
    let mut args = vec!["write", "--connect", &server.addr];
    args.extend(assignments.iter().map(String::as_str));
    let output = s7(&args);
    assert_code(&output, 0);
    assert_eq!(
        stdout(&output).lines().next(),
        Some("DB1.DBX0.3 := true"),
        "{}",
        stdout(&output)
    );
    assert_eq!(stdout(&output).lines().count(), WRITES.len());

    // The server's JSON lines: one per item written, start and size in bytes.
    let written = next_lines(&server.lines, WRITES.len());
    for expected in [
        r#"{"area": "DB", "db": 1, "start": 0, "bit": 3, "size": 1, "data": "01"}"#,
        r#"{"area": "DB", "db": 1, "start": 2, "size": 2, "data": "04d2"}"#,
        r#"{"area": "DB", "db": 1, "start": 8, "size": 4, "data": "41ac0000"}"#,
        r#"{"area": "M", "start": 20, "size": 2, "data": "ffff"}"#,
        r#"{"area": "I", "start": 0, "bit": 1, "size": 1, "data": "01"}"#,
        r#"{"area": "Q", "start": 0, "size": 1, "data": "05"}"#,
    ] {
        assert!(
            written.iter().any(|line| line == expected),
            "no {expected} in {written:#?}"
        );
    }
    for line in &written {
        let json: serde_json::Value = serde_json::from_str(line).unwrap();
        assert!(json["start"].is_u64() && json["size"].is_u64(), "{line}");
    }

    let mut args = vec!["read", "--json", "--connect", &server.addr];
    args.extend(READS.iter().map(|(item, _)| *item));
    let output = s7(&args);
    assert_code(&output, 0);
    let expected: Vec<String> = READS
        .iter()
        .map(|(item, value)| format!(r#"{{"item": "{item}", "value": {value}}}"#))
        .collect();
    let text = stdout(&output);
    let got: Vec<&str> = text.lines().collect();
    assert_eq!(got, expected);

    // Without --json: readable lines, the item as written.
    let output = s7(&[
        "read",
        "--connect",
        &server.addr,
        "DB1.DBW2",
        "DB1.DBD8:REAL",
        "DB1.DBX0.3",
        "MW20:INT",
    ]);
    assert_code(&output, 0);
    assert_eq!(
        stdout(&output),
        "DB1.DBW2 = 1234\nDB1.DBD8:REAL = 21.5\nDB1.DBX0.3 = true\nMW20:INT = -1\n"
    );

    // A bit written alone leaves the other bits of its byte as they were.
    assert_code(
        &s7(&["write", "--connect", &server.addr, "DB1.DBX0.0=true"]),
        0,
    );
    let output = s7(&["read", "--connect", &server.addr, "DB1.DBB0"]);
    assert_eq!(stdout(&output), "DB1.DBB0 = 9\n");
    drop(server.process);
}

#[test]
fn s7_an_item_the_plc_refuses_is_reported_and_the_others_printed() {
    let server = serve(true, &["--db", "1:16"]);
    assert_code(
        &s7(&["write", "--connect", &server.addr, "DB1.DBW2=77", "MW20=5"]),
        0,
    );

    let output = s7(&[
        "read",
        "--json",
        "--connect",
        &server.addr,
        "DB1.DBW2",
        "DB9.DBW0",
        "MW20",
        "DB1.DBW16",
    ]);
    assert_code(&output, 1);
    assert_eq!(
        stdout(&output),
        concat!(
            r#"{"item": "DB1.DBW2", "value": 77}"#,
            "\n",
            r#"{"item": "DB9.DBW0", "error": "the PLC answered 0x0a (object does not exist)"}"#,
            "\n",
            r#"{"item": "MW20", "value": 5}"#,
            "\n",
            r#"{"item": "DB1.DBW16", "error": "the PLC answered 0x05 (address out of range)"}"#,
            "\n",
        )
    );
    let errors = stderr(&output);
    assert!(
        errors.contains("DB9.DBW0: the PLC answered 0x0a (object does not exist)"),
        "{errors}"
    );
    assert!(errors.contains("DB1.DBW16:"), "{errors}");
    assert!(!errors.contains("MW20"), "{errors}");

    // Without --json the good items print, the refused one goes to standard error only.
    let output = s7(&["read", "--connect", &server.addr, "DB9.DBW0", "DB1.DBW2"]);
    assert_code(&output, 1);
    assert_eq!(stdout(&output), "DB1.DBW2 = 77\n");
    assert!(stderr(&output).contains("DB9.DBW0"), "{}", stderr(&output));

    // A write: the refused item named, the other one written.
    let output = s7(&[
        "write",
        "--json",
        "--connect",
        &server.addr,
        "DB9.DBW0=1",
        "DB1.DBW2=78",
    ]);
    assert_code(&output, 1);
    assert_eq!(
        stdout(&output),
        concat!(
            r#"{"item": "DB9.DBW0", "error": "the PLC answered 0x0a (object does not exist)"}"#,
            "\n",
            r#"{"item": "DB1.DBW2", "written": 78}"#,
            "\n",
        )
    );
    assert!(stderr(&output).contains("DB9.DBW0"), "{}", stderr(&output));
    let output = s7(&["read", "--connect", &server.addr, "DB1.DBW2"]);
    assert_eq!(stdout(&output), "DB1.DBW2 = 78\n");
}

#[test]
fn s7_options_may_come_after_and_between_the_items() {
    let server = serve(false, &["--db", "1:16"]);
    let output = s7(&["write", "DB1.DBW2=7", "--connect", &server.addr, "MB3=9"]);
    assert_code(&output, 0);
    let output = s7(&["read", "DB1.DBW2", "--connect", &server.addr, "--json"]);
    assert_code(&output, 0);
    assert_eq!(stdout(&output), "{\"item\": \"DB1.DBW2\", \"value\": 7}\n");
    let output = s7(&[
        "read",
        "DB1.DBW2",
        "--json",
        "MB3",
        "--connect",
        &server.addr,
        "--timeout",
        "5s",
    ]);
    assert_code(&output, 0);
    assert_eq!(
        stdout(&output),
        "{\"item\": \"DB1.DBW2\", \"value\": 7}\n{\"item\": \"MB3\", \"value\": 9}\n"
    );
    // serve's options in any order, --listen last
    let mut command = stanice();
    command.args([
        "s7",
        "serve",
        "--db",
        "2:8",
        "--json",
        "--listen",
        "127.0.0.1:0",
    ]);
    let (_other, banner, _) = start_until_line_keeping_output(command, "\"listening\"");
    let banner: serde_json::Value = serde_json::from_str(&banner).unwrap();
    assert_eq!(banner["db"][0]["db"], 2);
    assert_eq!(banner["db"][0]["size"], 8);
}

#[test]
fn s7_rack_slot_and_tsap_reach_the_server() {
    let server = serve(false, &["--db", "1:16"]);
    assert_code(&s7(&["read", "--connect", &server.addr, "MB0"]), 0);
    wait_for_line(&server.lines, "connected (TSAPs 0100:0301)");
    // rack 1, slot 2: 0x03, 1 x 32 + 2 = 0x22
    assert_code(
        &s7(&[
            "read",
            "MB0",
            "--connect",
            &server.addr,
            "--rack",
            "1",
            "--slot",
            "2",
        ]),
        0,
    );
    wait_for_line(&server.lines, "connected (TSAPs 0100:0322)");
    assert_code(
        &s7(&["read", "--rack", "7", "--connect", &server.addr, "MB0"]),
        0,
    );
    // rack 7 slot 1 (the default): 7 x 32 + 1 = 0xe1
    wait_for_line(&server.lines, "connected (TSAPs 0100:03e1)");
    assert_code(
        &s7(&[
            "write",
            "--tsap",
            "1000:2001",
            "--connect",
            &server.addr,
            "QX0.1=1",
        ]),
        0,
    );
    wait_for_line(&server.lines, "connected (TSAPs 1000:2001)");
    // the write as the server prints it without --json
    wait_for_line(&server.lines, "wrote Q0.1 = 1");

    // --tsap excludes --rack and --slot; both are range-checked.
    let output = s7(&[
        "read",
        "--connect",
        &server.addr,
        "--tsap",
        "0100:0301",
        "--slot",
        "2",
        "MB0",
    ]);
    assert_code(&output, 2);
    assert!(
        stderr(&output).contains("cannot be used with"),
        "{}",
        stderr(&output)
    );
    let output = s7(&["read", "--connect", &server.addr, "--rack", "8", "MB0"]);
    assert_code(&output, 2);
    assert!(
        stderr(&output).contains("8 is not in 0..=7"),
        "{}",
        stderr(&output)
    );
    let output = s7(&[
        "read",
        "--connect",
        &server.addr,
        "--tsap",
        "100:301",
        "MB0",
    ]);
    assert_code(&output, 2);
    assert!(
        stderr(&output).contains("four hex digits"),
        "{}",
        stderr(&output)
    );
}

#[test]
fn s7_many_items_in_one_call_are_split_by_the_pdu_size() {
    let server = serve(false, &["--db", "1:128", "--pdu-size", "240"]);
    let assignments: Vec<String> = (0..50)
        .map(|i| format!("DB1.DBW{}:INT={}", i * 2, i * 100 - 2000))
        .collect();
    let mut args = vec!["write", "--connect", &server.addr];
    args.extend(assignments.iter().map(String::as_str));
    assert_code(&s7(&args), 0);
    wait_for_line(&server.lines, "set up: PDU size 240");
    let wrote = next_lines(&server.lines, 50);
    assert!(
        wrote.iter().all(|line| line.contains(" wrote DB1 bytes ")),
        "{wrote:?}"
    );

    let items: Vec<String> = (0..50).map(|i| format!("DB1.DBW{}:INT", i * 2)).collect();
    let mut args = vec!["read", "--connect", &server.addr];
    args.extend(items.iter().map(String::as_str));
    let output = s7(&args);
    assert_code(&output, 0);
    let expected: String = (0..50)
        .map(|i| format!("DB1.DBW{}:INT = {}\n", i * 2, i * 100 - 2000))
        .collect();
    assert_eq!(stdout(&output), expected);
}

#[test]
fn s7_misspelt_items_are_named_with_what_is_wrong() {
    // Nothing listens there: a spelling error must be found before connecting.
    let nowhere = format!("127.0.0.1:{}", free_port());
    for (args, words) in [
        (
            vec!["read", "DB1.DBX0.9"],
            "DB1.DBX0.9: bit number 9 is above 7",
        ),
        (
            vec!["read", "DB1.DBW2", "DB0.DBW2"],
            "DB0.DBW2: data block 0 does not exist",
        ),
        (vec!["read", "XW2"], "XW2: unknown area"),
        (
            vec!["read", "DB1.DBW2:FOO"],
            "DB1.DBW2:FOO: unknown type \"FOO\"",
        ),
        (
            vec!["read", "DB1.DBW2:REAL"],
            "DB1.DBW2:REAL: REAL does not fit a word",
        ),
        (vec!["read", "MW"], "MW: a byte number is missing"),
        (vec!["read", "M10"], "M10: a bit address needs a bit number"),
        (vec!["read", "DB1.DBW2.1"], "DB1.DBW2.1: only bit addresses"),
        (
            vec!["write", "DB1.DBW2=70000"],
            "DB1.DBW2: 70000 is out of range for WORD",
        ),
        (
            vec!["write", "DB1.DBX0.1=maybe"],
            "DB1.DBX0.1: \"maybe\" is not a BOOL",
        ),
        (
            vec!["write", "DB1.DBD8:REAL=abc"],
            "DB1.DBD8:REAL: \"abc\" is not a number",
        ),
        (vec!["write", "DB1.DBW2"], "DB1.DBW2: expected ITEM=VALUE"),
        (
            vec!["write", "DB1.DBX0.9=1"],
            "DB1.DBX0.9: bit number 9 is above 7",
        ),
    ] {
        let mut all = args.clone();
        all.extend(["--connect", nowhere.as_str()]);
        let output = s7(&all);
        assert_code(&output, 2);
        assert!(
            stderr(&output).contains(words),
            "{args:?}: expected {words:?} in\n{}",
            stderr(&output)
        );
        assert!(!stderr(&output).contains("refused"), "{}", stderr(&output));
    }
}

#[test]
fn s7_a_refused_connection_and_a_timeout_are_said_in_words() {
    let port = free_port();
    let output = s7(&["read", "--connect", &format!("127.0.0.1:{port}"), "MW20"]);
    assert_code(&output, 2);
    let errors = stderr(&output);
    assert!(
        errors.contains(&format!("cannot connect to 127.0.0.1:{port}"))
            && errors.contains("refused"),
        "{errors}"
    );

    // A listener that never answers: TCP connects (the backlog), the S7 connection does not.
    let silent = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = silent.local_addr().unwrap().to_string();
    let started = Instant::now();
    let output = s7(&["write", "--connect", &addr, "--timeout", "300ms", "MW20=1"]);
    assert_code(&output, 2);
    let errors = stderr(&output);
    assert!(
        errors.contains(&addr) && errors.contains("within 300ms"),
        "{errors}"
    );
    assert!(started.elapsed() < Duration::from_secs(30));
    drop(silent);
}

#[test]
fn s7_serve_stops_on_sigterm() {
    let server = serve(false, &["--db", "1:16"]);
    let mut child = server.process;
    let status = Command::new("kill")
        .args(["-TERM", &child.0.id().to_string()])
        .status()
        .unwrap();
    assert!(status.success());
    let deadline = Instant::now() + Duration::from_secs(20);
    let status = loop {
        if let Some(status) = child.0.try_wait().unwrap() {
            break status;
        }
        assert!(Instant::now() < deadline, "serve did not stop on SIGTERM");
        std::thread::sleep(Duration::from_millis(20));
    };
    assert!(status.success(), "{status}");
}

#[test]
fn s7_help_has_examples() {
    for sub in ["read", "write", "serve"] {
        let output = s7(&[sub, "--help"]);
        assert_code(&output, 0);
        let help = stdout(&output);
        assert!(help.contains("Examples:"), "{help}");
        assert!(help.contains(&format!("stanice s7 {sub} ")), "{help}");
    }
}
