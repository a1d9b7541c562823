//! A node's PLC bound to real I/O over S7 (`[[node.device]] kind = "s7"`, `[[node.io]]
//! device = ...`): the station as the S7 client of a PLC (here the `s7` crate's server on
//! loopback, as an S7-1500 or a LOGO! would answer): inputs read into the PLC, outputs
//! written on change, the device's silence turning its inputs invalid as a pulled I/O
//! module's, and the link back.

use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use points::PointValue;
use s7::io::{serve, SharedMemory};
use s7::{Address, Memory, ServerConfig, Value};
use station::config::Project;
use station::runtime::{Pacing, Runtime, RuntimeOptions, StoreChoice};

const PROGRAM: &str = "PROGRAM Main
VAR
    Feedback : BOOL;
    Level : INT;
    Cmd : BOOL;
    Echo : INT;
END_VAR
    Echo := Level * 2;
END_PROGRAM
";

fn project(port: u16) -> String {
    format!(
        r#"
[station]
name = "field"
time_zone = "UTC"

[[node]]
name = "A"
common_address = 1
sources = ["plc/main.st"]

[[node.task]]
name = "main"
interval_ms = 10
programs = ["Main"]

[[node.device]]
name = "PLC1"
kind = "s7"
ioa_base = 100
settings = {{ connect = "127.0.0.1:{port}", cycle_ms = 20, timeout_ms = 1000 }}

[[node.io]]
device = "PLC1"
item = "I0.1"
direction = "input"
variable = "Main.Feedback"

[[node.io]]
device = "PLC1"
item = "DB1.DBW2:INT"
direction = "input"
variable = "Main.Level"

[[node.io]]
device = "PLC1"
item = "Q0.0"
direction = "output"
variable = "Main.Cmd"

[[node.io]]
device = "PLC1"
item = "DB1.DBW4:INT"
direction = "output"
variable = "Main.Echo"

[[node.point]]
name = "Feedback"
type = "M_SP_TB_1"
ioa = 1
source = "Main.Feedback"

[[node.point]]
name = "Level"
type = "M_ME_NB_1"
ioa = 2
source = "Main.Level"
"#
    )
}

fn address(text: &str) -> Address {
    text.parse().unwrap()
}

async fn until(what: &str, runtime: &Runtime, mut condition: impl FnMut() -> bool) {
    let deadline = Instant::now() + Duration::from_secs(20);
    while !condition() {
        assert!(Instant::now() < deadline, "timed out waiting until {what}");
        runtime.advance(Duration::from_millis(20)).await.unwrap();
        tokio::time::sleep(Duration::from_millis(10)).await;
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_plc_reads_and_drives_real_io_over_s7_and_a_silent_device_invalidates_its_inputs() {
    let mut memory = Memory::default();
    memory.add_data_block(1, 16).unwrap();
    memory.set(&address("I0.1"), &Value::Bool(true)).unwrap();
    memory
        .set(&address("DB1.DBW2:INT"), &Value::Int(21))
        .unwrap();
    let memory: SharedMemory = Arc::new(Mutex::new(memory));
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
    let port = listener.local_addr().unwrap().port();
    let (events, _received) = tokio::sync::mpsc::channel(1024);
    let server = tokio::spawn(serve(
        listener,
        Arc::clone(&memory),
        ServerConfig::default(),
        events,
    ));

    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir_all(dir.path().join("plc")).unwrap();
    std::fs::write(dir.path().join("plc/main.st"), PROGRAM).unwrap();
    std::fs::write(dir.path().join("station.toml"), project(port)).unwrap();
    let project = Project::load(dir.path()).unwrap_or_else(|errors| panic!("{errors}"));
    assert_eq!(project.nodes[0].devices[0].io.len(), 4);
    let runtime = Runtime::start(
        project,
        RuntimeOptions {
            pacing: Pacing::Manual,
            store: StoreChoice::Disabled,
            ..RuntimeOptions::default()
        },
    )
    .await
    .unwrap();
    let node = Arc::clone(&runtime.node("A").unwrap().points);
    let point = |name: &str| node.point(name).unwrap();
    let read = |text: &str| memory.lock().unwrap().get(&address(text)).unwrap();

    // Inputs: the device's I0.1 and DB1.DBW2 in the PLC, its points valid.
    until("the inputs read", &runtime, || {
        let (feedback, level) = (point("Feedback"), point("Level"));
        !feedback.quality.invalid
            && feedback.value == PointValue::Bool(true)
            && !level.quality.invalid
            && level.value == PointValue::Int(21)
    })
    .await;
    assert_eq!(point("PLC1.not_answering").value, PointValue::Bool(false));
    // Outputs: Echo (2 x Level) written to DB1.DBW4; Cmd to Q0.0 when the PLC drives it.
    until("the output written", &runtime, || {
        read("DB1.DBW4:INT") == Value::Int(42)
    })
    .await;
    runtime
        .with_simulation(|sim| sim.plc("A").unwrap().write("Main.Cmd", "TRUE").unwrap())
        .await
        .unwrap();
    until("Q0.0 driven", &runtime, || {
        read("Q0.0") == Value::Bool(true)
    })
    .await;
    // A change at the device reaches the PLC.
    memory
        .lock()
        .unwrap()
        .set(&address("DB1.DBW2:INT"), &Value::Int(-7))
        .unwrap();
    until("the new level", &runtime, || {
        point("Level").value == PointValue::Int(-7) && read("DB1.DBW4:INT") == Value::Int(-14)
    })
    .await;

    // The device falls silent: its inputs invalid (last value kept), its status TRUE.
    server.abort();
    until("the device not answering", &runtime, || {
        point("PLC1.not_answering").value == PointValue::Bool(true)
    })
    .await;
    until("the inputs invalid", &runtime, || {
        let feedback = point("Feedback");
        feedback.quality.invalid && feedback.value == PointValue::Bool(true)
    })
    .await;

    // Back (the supervisor connects again within seconds): valid again.
    let listener = tokio::net::TcpListener::bind(("127.0.0.1", port))
        .await
        .unwrap();
    let (events, _received) = tokio::sync::mpsc::channel(1024);
    let server = tokio::spawn(serve(
        listener,
        Arc::clone(&memory),
        ServerConfig::default(),
        events,
    ));
    until("the device answering again", &runtime, || {
        point("PLC1.not_answering").value == PointValue::Bool(false)
            && !point("Feedback").quality.invalid
    })
    .await;
    server.abort();
    runtime.shutdown().await;
}

/// Device items are checked when the project loads: the device must be the node's, the
/// item an S7 address, the direction given; a kind without items says so.
#[test]
fn device_io_bindings_are_checked_at_load() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("station.toml");
    let base = r#"
[station]
name = "field"
time_zone = "UTC"

[[node]]
name = "A"
common_address = 1

[[node.device]]
name = "PLC1"
kind = "s7"
ioa_base = 100
settings = { connect = "127.0.0.1" }

[[node.device]]
name = "BAL"
kind = "balance"
ioa_base = 200
settings = { simulate = "red 1" }
"#;
    for (io, message) in [
        (
            "device = \"PLC9\"\nitem = \"I0.1\"\ndirection = \"input\"",
            "node[0].io[0].device",
        ),
        (
            "device = \"PLC1\"\nitem = \"DB1.DBX0.9\"\ndirection = \"input\"",
            "DB1.DBX0.9",
        ),
        (
            "device = \"PLC1\"\nitem = \"I0.1\"",
            "an I/O binding of a device needs direction",
        ),
        (
            "device = \"PLC1\"\nitem = \"I0.1\"\ndirection = \"sideways\"",
            "direction is input",
        ),
        (
            "device = \"BAL\"\nitem = \"I0.1\"\ndirection = \"input\"",
            "a `balance` device has no I/O items",
        ),
        (
            "item = \"I0.1\"\ndirection = \"input\"",
            "an I/O binding with item or direction needs device",
        ),
    ] {
        let text = format!("{base}\n[[node.io]]\n{io}\nvariable = \"Main.X\"\n");
        let errors = Project::parse(dir.path(), &file, &text)
            .unwrap_err()
            .to_string();
        assert!(errors.contains(message), "{io}: {errors}");
    }
}

/// `[node.s7_server]` is checked when the project loads: a PLC to serve, TSAPs of four
/// hex digits, connections unique, its port apart from the IEC 104 servers'.
#[test]
fn s7_servers_are_checked_at_load() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("station.toml");
    let text = |sources: &str, server: &str| {
        format!(
            r#"
[station]
name = "field"
time_zone = "UTC"

[[node]]
name = "A"
common_address = 1
{sources}

[node.server]
port_offset = 0

[node.s7_server]
{server}
"#
        )
    };
    let loaded = Project::parse(
        dir.path(),
        &file,
        &text(
            "",
            "port_offset = 1\nmarkers = 64\nconnection = [{ name = \"RH2\", tsap = \"0101\" }]",
        ),
    )
    .unwrap_err()
    .to_string();
    assert!(
        loaded.contains("an S7 server needs sources"),
        "no PLC to serve: {loaded}"
    );
    for (server, message) in [
        (
            "port_offset = 0",
            "node[0].s7_server.port_offset",
        ),
        (
            "port_offset = 1\nconnection = [{ name = \"RH2\", tsap = \"01\" }]",
            "TSAP `01`: four hex digits",
        ),
        (
            "port_offset = 1\nconnection = [{ name = \"RH2\", tsap = \"0101\" }, { name = \"RZZ\", tsap = \"0101\" }]",
            "repeats connection `RH2`",
        ),
        ("port_offset = 1\npdu_size = 100", "pdu_size"),
    ] {
        let errors = Project::parse(dir.path(), &file, &text("sources = [\"plc/main.st\"]", server))
            .unwrap_err()
            .to_string();
        assert!(errors.contains(message), "{server}: {errors}");
    }
}
