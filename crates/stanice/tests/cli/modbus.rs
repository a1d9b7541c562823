//! `stanice modbus`: read, write and serve as separate processes, over loopback TCP and
//! RTU over a pseudo-terminal: the JSON lines' shapes, the exception's message and exit
//! code, the timeout's, options after the positional arguments, the parity a
//! pseudo-terminal refuses, and SIGTERM ending the server.

use std::io::{BufRead, BufReader, Read};
use std::process::{Command, Output, Stdio};
use std::sync::mpsc::{self, Receiver};
use std::time::{Duration, Instant};

use serde_json::{json, Value};
use testkit::process::{assert_success, run_bounded, wait_for_line, Background};

use crate::support::*;

/// A running `stanice modbus serve`: its standard output and error, line by line.
struct Served {
    process: Background,
    stdout: Receiver<String>,
    stderr: Receiver<String>,
}

fn lines_of(pipe: impl Read + Send + 'static) -> Receiver<String> {
    let (sender, receiver) = mpsc::channel();
    std::thread::spawn(move || {
        for line in BufReader::new(pipe).lines().map_while(Result::ok) {
            if sender.send(line).is_err() {
                break;
            }
        }
    });
    receiver
}

/// `stanice modbus serve ARGS`.
fn serve(args: &[&str]) -> Served {
    let mut command = stanice();
    command
        .args(["modbus", "serve"])
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    let mut child = command.spawn().unwrap();
    let stdout = lines_of(child.stdout.take().unwrap());
    let stderr = lines_of(child.stderr.take().unwrap());
    Served {
        process: Background(child),
        stdout,
        stderr,
    }
}

/// A JSON-mode TCP server on a free port (port 0, the bound address read from its banner
/// on standard error): the server and `127.0.0.1:PORT`.
fn tcp_server(extra: &[&str]) -> (Served, String) {
    let mut args = vec!["--listen", "127.0.0.1:0", "--json"];
    args.extend_from_slice(extra);
    let served = serve(&args);
    let banner = wait_for_line(&served.stderr, "Modbus TCP server on ");
    let address = banner
        .trim_start_matches("Modbus TCP server on ")
        .split_whitespace()
        .next()
        .unwrap()
        .to_owned();
    (served, address)
}

/// A JSON-mode RTU slave on a new pseudo-terminal: the server and the path it printed
/// first.
fn pty_slave(extra: &[&str]) -> (Served, String) {
    let mut args = vec!["--pty", "--json"];
    args.extend_from_slice(extra);
    let served = serve(&args);
    let line = wait_for_line(&served.stdout, "pty: ");
    let path = line.trim_start_matches("pty: ").trim().to_owned();
    // The slave serves once it says so (on standard error in JSON mode).
    wait_for_line(&served.stderr, "Modbus RTU slave on");
    (served, path)
}

/// `stanice modbus ARGS`, to its end.
fn modbus(args: &[&str]) -> Output {
    let mut command = stanice();
    command.arg("modbus").args(args);
    run_bounded(command, 60)
}

fn stdout(output: &Output) -> String {
    String::from_utf8_lossy(&output.stdout).into_owned()
}

fn stderr(output: &Output) -> String {
    String::from_utf8_lossy(&output.stderr).into_owned()
}

/// The single JSON line a `--json` command printed, checked to be exactly `line`.
fn json_output(output: &Output, line: &str) -> Value {
    let text = assert_success(output);
    assert_eq!(text.trim_end(), line);
    serde_json::from_str(line).unwrap()
}

#[test]
fn modbus_write_read_and_serve_over_tcp_print_the_documented_json() {
    let (served, address) = tcp_server(&[]);
    let tcp = address.as_str();

    let output = modbus(&[
        "write",
        "--tcp",
        tcp,
        "--unit",
        "1",
        "--register",
        "100=1,-1,0x10",
    ]);
    assert_eq!(
        assert_success(&output).trim_end(),
        format!("unit 1 on tcp {tcp}: wrote holding registers 100..=102 = 1, 65535, 16 (FC 16)")
    );
    let output = modbus(&[
        "write",
        "--tcp",
        tcp,
        "--unit",
        "1",
        "--register",
        "103=-32768",
    ]);
    assert!(assert_success(&output).contains("(FC 6)"));
    let output = modbus(&[
        "write", "--tcp", tcp, "--unit", "1", "--coil", "5=1,0,on", "--json",
    ]);
    json_output(
        &output,
        r#"{"unit": 1, "table": "coils", "address": 5, "values": [true, false, true]}"#,
    );
    let output = modbus(&["write", "--tcp", tcp, "--unit", "1", "--coil", "9=true"]);
    assert!(assert_success(&output).contains("wrote coil 9 = true (FC 5)"));

    let value = json_output(
        &modbus(&[
            "read",
            "--tcp",
            tcp,
            "--unit",
            "1",
            "--holding",
            "100",
            "4",
            "--json",
        ]),
        r#"{"unit": 1, "table": "holding", "address": 100, "values": [1, 65535, 16, 32768]}"#,
    );
    assert_eq!(
        value,
        json!({"unit": 1, "table": "holding", "address": 100, "values": [1, 65535, 16, 32768]})
    );
    json_output(
        &modbus(&[
            "read", "--tcp", tcp, "--unit", "1", "--coils", "5", "5", "--json",
        ]),
        r#"{"unit": 1, "table": "coils", "address": 5, "values": [true, false, true, false, true]}"#,
    );
    json_output(
        &modbus(&[
            "read",
            "--tcp",
            tcp,
            "--unit",
            "1",
            "--discrete",
            "0",
            "2",
            "--json",
        ]),
        r#"{"unit": 1, "table": "discrete", "address": 0, "values": [false, false]}"#,
    );
    json_output(
        &modbus(&[
            "read", "--tcp", tcp, "--unit", "1", "--input", "9998", "2", "--json",
        ]),
        r#"{"unit": 1, "table": "input", "address": 9998, "values": [0, 0]}"#,
    );
    // Without --json, a table people read.
    let text = assert_success(&modbus(&[
        "read",
        "--tcp",
        tcp,
        "--unit",
        "1",
        "--holding",
        "100",
        "2",
    ]));
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(
        lines,
        [
            format!("unit 1 on tcp {tcp}, holding registers 100..=101").as_str(),
            "address  value     hex  signed",
            "    100      1  0x0001       1",
            "    101  65535  0xFFFF      -1",
        ]
    );

    // The server printed one line per write, in order.
    for expected in [
        r#"{"unit": 1, "table": "holding", "address": 100, "count": 3, "values": [1, 65535, 16]}"#,
        r#"{"unit": 1, "table": "holding", "address": 103, "count": 1, "values": [32768]}"#,
        r#"{"unit": 1, "table": "coils", "address": 5, "count": 3, "values": [true, false, true]}"#,
        r#"{"unit": 1, "table": "coils", "address": 9, "count": 1, "values": [true]}"#,
    ] {
        let line = wait_for_line(&served.stdout, "{");
        assert_eq!(line, expected);
        let _: Value = serde_json::from_str(&line).unwrap();
    }
    // Ctrl-C stops it, exit 0.
    stop_by_signal(served, "INT");
}

/// Sends `SIG{name}` to the server and checks that it ends, successfully, within 20 s.
fn stop_by_signal(served: Served, name: &str) {
    let mut process = served.process;
    let status = Command::new("kill")
        .args([&format!("-{name}"), &process.0.id().to_string()])
        .status()
        .unwrap();
    assert!(status.success());
    let deadline = Instant::now() + Duration::from_secs(20);
    let exit = loop {
        if let Some(exit) = process.0.try_wait().unwrap() {
            break exit;
        }
        assert!(Instant::now() < deadline, "serve did not stop on SIG{name}");
        std::thread::sleep(Duration::from_millis(20));
    };
    assert!(exit.success(), "SIG{name}: {exit}");
}

#[test]
fn options_may_come_after_the_positional_arguments() {
    let (_served, address) = tcp_server(&["--unit", "7"]);
    let tcp = address.as_str();
    assert_success(&modbus(&[
        "write",
        "--register",
        "3=42",
        "--unit",
        "7",
        "--tcp",
        tcp,
    ]));
    json_output(
        &modbus(&[
            "read",
            "3",
            "1",
            "--holding",
            "--json",
            "--unit",
            "7",
            "--tcp",
            tcp,
        ]),
        r#"{"unit": 7, "table": "holding", "address": 3, "values": [42]}"#,
    );
    json_output(
        &modbus(&[
            "read",
            "--json",
            "3",
            "--tcp",
            tcp,
            "1",
            "--unit",
            "7",
            "--holding",
        ]),
        r#"{"unit": 7, "table": "holding", "address": 3, "values": [42]}"#,
    );
}

#[test]
fn an_exception_is_a_nonzero_exit_naming_it() {
    let (_served, address) = tcp_server(&["--unit", "1"]);
    let tcp = address.as_str();
    let output = modbus(&[
        "read",
        "--tcp",
        tcp,
        "--unit",
        "1",
        "--holding",
        "9999",
        "2",
    ]);
    assert_eq!(output.status.code(), Some(1), "{}", stderr(&output));
    assert_eq!(stdout(&output), "");
    assert_eq!(
        stderr(&output).trim_end(),
        format!(
            "error: unit 1 on tcp {tcp} answered FC 3 (read holding registers) with exception illegal data address (code 2)"
        )
    );
    // Another unit of a single-unit server: exception 0x0B.
    let output = modbus(&["write", "--tcp", tcp, "--unit", "2", "--coil", "0=1"]);
    assert_eq!(output.status.code(), Some(1));
    assert!(
        stderr(&output).contains("gateway target device failed to respond (code 11)"),
        "{}",
        stderr(&output)
    );
    // What cannot be a request is refused before anything is sent.
    let output = modbus(&["read", "--tcp", tcp, "--unit", "1", "--holding", "0", "126"]);
    assert!(!output.status.success());
    assert!(
        stderr(&output).contains("quantity 126 outside 1..=125"),
        "{}",
        stderr(&output)
    );
    let output = modbus(&[
        "write",
        "--tcp",
        tcp,
        "--unit",
        "1",
        "--register",
        "0=70000",
    ]);
    assert!(!output.status.success());
    assert!(
        stderr(&output).contains("outside -32768..=65535"),
        "{}",
        stderr(&output)
    );
}

#[test]
fn modbus_rtu_over_a_pty_and_its_timeout() {
    let (served, path) = pty_slave(&["--unit", "1"]);
    let serial = path.as_str();
    // A pseudo-terminal keeps no parity: the client says it with --parity none.
    let output = modbus(&[
        "write",
        "--serial",
        serial,
        "--parity",
        "none",
        "--unit",
        "1",
        "--register",
        "10=5,6",
    ]);
    assert!(
        assert_success(&output).contains(&format!(
            "on serial {serial} 19200 Bd 8N1: wrote holding registers 10..=11"
        )),
        "{}",
        stdout(&output)
    );
    json_output(
        &modbus(&[
            "read",
            "9",
            "3",
            "--holding",
            "--json",
            "--serial",
            serial,
            "--parity",
            "none",
            "--unit",
            "1",
        ]),
        r#"{"unit": 1, "table": "holding", "address": 9, "values": [0, 5, 6]}"#,
    );
    assert_eq!(
        wait_for_line(&served.stdout, "{"),
        r#"{"unit": 1, "table": "holding", "address": 10, "count": 2, "values": [5, 6]}"#
    );
    // Another unit's request is not answered on a serial line: the timeout names the
    // port and the time; exit code 2.
    let started = Instant::now();
    let output = modbus(&[
        "read",
        "--serial",
        serial,
        "--parity",
        "none",
        "--unit",
        "2",
        "--coils",
        "0",
        "1",
        "--timeout",
        "200ms",
        "--retries",
        "1",
    ]);
    assert_eq!(output.status.code(), Some(2), "{}", stderr(&output));
    assert_eq!(
        stderr(&output).trim_end(),
        format!("error: no answer from unit 2 on serial {serial} 19200 Bd 8N1 within 200ms (2 attempts)")
    );
    assert!(started.elapsed() >= Duration::from_millis(400));
    // The slave still answers its own unit.
    json_output(
        &modbus(&[
            "read", "--serial", serial, "--parity", "none", "--unit", "1", "--coils", "0", "1",
            "--json",
        ]),
        r#"{"unit": 1, "table": "coils", "address": 0, "values": [false]}"#,
    );
}

#[test]
fn a_pty_refuses_even_parity_and_the_error_says_what_to_do() {
    let (_served, path) = pty_slave(&[]);
    // 19200 Bd 8E1 is the default; the pseudo-terminal keeps no parity.
    let output = modbus(&[
        "read",
        "--serial",
        &path,
        "--unit",
        "1",
        "--holding",
        "0",
        "1",
    ]);
    assert_eq!(output.status.code(), Some(1));
    let message = stderr(&output);
    assert!(
        message.contains(&format!(
            "serial {path}: the port refused parity even (it kept none)"
        )),
        "{message}"
    );
    assert!(message.contains("use --parity none"), "{message}");
    // Serving on a new pseudo-terminal with even parity is refused before it opens.
    let output = modbus(&["serve", "--pty", "--parity", "even"]);
    assert!(!output.status.success());
    assert!(
        stderr(&output).contains("--parity even is refused; use --parity none"),
        "{}",
        stderr(&output)
    );
}

#[test]
fn serve_in_text_mode_and_sigterm_ends_it() {
    let served = serve(&["--pty", "--unit", "4"]);
    let path = wait_for_line(&served.stdout, "pty: ")
        .trim_start_matches("pty: ")
        .trim()
        .to_owned();
    let banner = wait_for_line(&served.stdout, "Modbus RTU slave on");
    assert_eq!(
        banner,
        format!(
            "Modbus RTU slave on {path} (19200 Bd 8N1, unit 4), 10,000 of each table; Ctrl-C stops"
        )
    );
    assert_success(&modbus(&[
        "write", "--serial", &path, "--parity", "none", "--unit", "4", "--coil", "7=1,1",
    ]));
    assert_eq!(
        wait_for_line(&served.stdout, "wrote"),
        "unit 4 wrote coils 7..=8 = true, true"
    );
    stop_by_signal(served, "TERM");
}
