//! Interoperability with pymodbus 3.16 (an implementation that is not ours), both ways on
//! both transports: our client against a pymodbus server, a pymodbus client against our
//! server, over loopback TCP and RTU over a pseudo-terminal pair (19200 Bd 8N1).
//!
//! The peers are `tests/peer/pymodbus_server.py` and `tests/peer/pymodbus_client.py` of
//! this crate. Without pymodbus and pyserial the tests say SKIPPED and pass, unless
//! `STANICE_REQUIRE_PEERS=1` (set by `scripts/test.sh`, hence in CI), where a missing
//! peer fails them.

use std::path::PathBuf;
use std::process::Command;
use std::sync::mpsc::Receiver;
use std::time::Duration;

use modbus::{
    Client, ClientError, DataModel, ExceptionCode, ModelConfig, Table, Units, Values, WriteEvent,
};
use serde_json::Value;
use serial_line::io::Transport;
use testkit::peers;
use testkit::ports::free_port;
use testkit::process::{run_bounded, start_until_line_keeping_output, wait_for_line, Background};

use crate::support::*;

/// Whether pymodbus and pyserial import; panics when they must (CI) and do not.
fn pymodbus_available() -> bool {
    if peers::python_imports("pymodbus.client, pymodbus.server, serial") {
        return true;
    }
    peers::skip_or_fail(
        "interoperability peer missing (pymodbus 3.16.1 and pyserial for python3); run scripts/install-test-deps.sh",
    );
    false
}

fn script(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/peer")
        .join(name)
}

/// The pymodbus server with `args`, started until it says `ready`; its later lines (the
/// writes it saw, as JSON) are kept.
fn pymodbus_server(args: &[&str]) -> (Background, Receiver<String>) {
    let mut command = Command::new("python3");
    command.arg(script("pymodbus_server.py")).args(args);
    let (server, _, lines) =
        tokio::task::block_in_place(|| start_until_line_keeping_output(command, "ready"));
    (server, lines)
}

/// The pymodbus client's run with `args`: its JSON result.
fn pymodbus_client(args: &[&str]) -> Value {
    let mut command = Command::new("python3");
    command.arg(script("pymodbus_client.py")).args(args);
    let output = tokio::task::block_in_place(|| run_bounded(command, 120));
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(
        output.status.success(),
        "pymodbus client failed: {stdout}\n{}",
        String::from_utf8_lossy(&output.stderr)
    );
    serde_json::from_str(stdout.trim()).unwrap()
}

/// The pymodbus server's presets (see the script), read by our client; every write
/// function, checked by reading back and by the server's own report of the write;
/// exceptions 2 and, over TCP, 1 (pymodbus's RTU framer cannot cut a request of a
/// function it does not know and leaves it unanswered).
async fn against_the_pymodbus_server(client: &mut Client, writes: &Receiver<String>) {
    assert_eq!(
        client.read(1, Table::Coils, 0, 10).await.unwrap(),
        Values::Bits(vec![
            true, false, true, true, false, false, true, true, true, false
        ])
    );
    assert_eq!(
        client.read(1, Table::DiscreteInputs, 0, 8).await.unwrap(),
        Values::Bits(vec![false, true, true, false, true, false, false, true])
    );
    assert_eq!(
        client
            .read(1, Table::HoldingRegisters, 0, 10)
            .await
            .unwrap(),
        Values::Registers((100..110).collect())
    );
    assert_eq!(
        client.read(1, Table::InputRegisters, 0, 4).await.unwrap(),
        Values::Registers(vec![1000, 1001, 1002, 1003])
    );
    let server_saw = |expected: &str| {
        let line = tokio::task::block_in_place(|| wait_for_line(writes, expected));
        assert_eq!(line, expected);
    };
    client.write_coils(1, 50, &[true]).await.unwrap();
    server_saw(r#"{"table": "coils", "address": 50, "values": [true]}"#);
    client
        .write_coils(
            1,
            60,
            &[true, false, true, true, false, false, true, true, true],
        )
        .await
        .unwrap();
    server_saw(
        r#"{"table": "coils", "address": 60, "values": [true, false, true, true, false, false, true, true, true]}"#,
    );
    assert_eq!(
        client.read(1, Table::Coils, 59, 11).await.unwrap(),
        Values::Bits(vec![
            false, true, false, true, true, false, false, true, true, true, false
        ])
    );
    client.write_registers(1, 200, &[0xFFFF]).await.unwrap();
    server_saw(r#"{"table": "holding", "address": 200, "values": [65535]}"#);
    client
        .write_registers(1, 201, &[1, 2, 0x8000])
        .await
        .unwrap();
    server_saw(r#"{"table": "holding", "address": 201, "values": [1, 2, 32768]}"#);
    assert_eq!(
        client
            .read_write_registers(1, 200, 3, 202, &[7, 8])
            .await
            .unwrap(),
        [0xFFFF, 1, 7]
    );
    server_saw(r#"{"table": "holding", "address": 202, "values": [7, 8]}"#);
    assert_eq!(
        client
            .read(1, Table::HoldingRegisters, 9875, 125)
            .await
            .unwrap()
            .len(),
        125
    );
    let error = client
        .read(1, Table::HoldingRegisters, 9_999, 2)
        .await
        .unwrap_err();
    assert!(
        matches!(
            error,
            ClientError::Exception {
                code: ExceptionCode::ILLEGAL_DATA_ADDRESS,
                ..
            }
        ),
        "{error}"
    );
    if client.config().framing == modbus::Framing::Rtu {
        return;
    }
    // pymodbus answers `80 01` (the exception of function 0): taken as exception 1.
    let error = client.call_custom(1, 0x41, &[]).await.unwrap_err();
    assert!(
        matches!(
            error,
            ClientError::Exception {
                code: ExceptionCode::ILLEGAL_FUNCTION,
                ..
            }
        ),
        "{error}"
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn our_client_against_a_pymodbus_tcp_server() {
    if !pymodbus_available() {
        return;
    }
    let port = free_port();
    let (_server, writes) = pymodbus_server(&["--tcp", &port.to_string()]);
    let mut client = tcp_client(
        format!("127.0.0.1:{port}").parse().unwrap(),
        Duration::from_secs(10),
        0,
    )
    .await;
    against_the_pymodbus_server(&mut client, &writes).await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn our_client_against_a_pymodbus_rtu_server_over_a_pty() {
    if !pymodbus_available() {
        return;
    }
    let line = Transport::Pty.open().await.unwrap();
    let path = line.pty_path.clone().unwrap();
    let (_server, writes) = pymodbus_server(&["--serial", &path]);
    let mut client = Client::attach(
        line,
        config(modbus::Framing::Rtu, Duration::from_secs(10), 0),
    );
    against_the_pymodbus_server(&mut client, &writes).await;
}

/// Our server's model with what the client script expects.
fn model_for_the_pymodbus_client() -> DataModel {
    let model = DataModel::new(ModelConfig::new(Units::Single(1)));
    model
        .write(
            1,
            Table::DiscreteInputs,
            196,
            &Values::Bits(vec![false, true, true]),
        )
        .unwrap();
    model
        .write(
            1,
            Table::InputRegisters,
            8,
            &Values::Registers(vec![10, 11]),
        )
        .unwrap();
    model
}

/// What the client script got from our server, and what our server saw written.
fn check_the_pymodbus_clients_run(result: &Value, model: &DataModel, events: Vec<WriteEvent>) {
    let expected = serde_json::json!({
        "coil_10": [true],
        "coils_19": [false, true, false, true, true, false, false, true, true, true, false],
        "discrete_196": [false, true, true],
        "holding_100": [65535, 1, 2, 32768],
        "input_8": [10, 11],
        "read_write": [65535, 1, 7],
        "largest_read": 125,
        "exception_address": 2,
        "exception_function": 1,
        "exception_value": 3,
    });
    assert_eq!(result, &expected);
    assert_eq!(
        events
            .iter()
            .map(|e| (e.table, e.address, e.count()))
            .collect::<Vec<_>>(),
        [
            (Table::Coils, 10, 1),
            (Table::Coils, 20, 9),
            (Table::HoldingRegisters, 100, 1),
            (Table::HoldingRegisters, 101, 3),
            (Table::HoldingRegisters, 102, 2),
        ]
    );
    assert_eq!(
        model.read(1, Table::HoldingRegisters, 100, 4),
        Ok(Values::Registers(vec![0xFFFF, 1, 7, 8]))
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_pymodbus_tcp_client_against_our_server() {
    if !pymodbus_available() {
        return;
    }
    let model = model_for_the_pymodbus_client();
    let mut events = model.subscribe();
    let (address, _server) = tcp_server(model.clone()).await;
    let result = pymodbus_client(&["--tcp", &address.to_string()]);
    let events = std::iter::from_fn(|| events.try_recv().ok()).collect();
    check_the_pymodbus_clients_run(&result, &model, events);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_pymodbus_rtu_client_against_our_slave_over_a_pty() {
    if !pymodbus_available() {
        return;
    }
    let model = model_for_the_pymodbus_client();
    let mut events = model.subscribe();
    let (path, _slave) = rtu_slave(model.clone()).await;
    let result = pymodbus_client(&["--serial", &path]);
    let events = std::iter::from_fn(|| events.try_recv().ok()).collect();
    check_the_pymodbus_clients_run(&result, &model, events);
}
