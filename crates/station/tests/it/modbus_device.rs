//! A node's PLC bound to real I/O over Modbus TCP (`[[node.device]] kind = "modbus"`,
//! `[[node.io]] device = ...`): the station as the client of a device (here the `modbus`
//! crate's server on loopback): registers and coils read into the PLC, outputs written on
//! change, the device's silence turning its inputs invalid as a pulled module's, and the
//! link back.

use std::sync::Arc;
use std::time::{Duration, Instant};

use modbus::{DataModel, ModelConfig, Table, Values};
use points::PointValue;
use station::config::Project;
use station::runtime::{Pacing, Runtime, RuntimeOptions, StoreChoice};

const PROGRAM: &str = "PROGRAM Main
VAR
    Feedback : BOOL;
    Level : INT;
    Flow : REAL;
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
name = "IO1"
kind = "modbus"
ioa_base = 100
settings = {{ tcp = "127.0.0.1:{port}", unit = 1, cycle_ms = 20, timeout_ms = 500, retries = 0 }}

[[node.io]]
device = "IO1"
item = "discrete:5"
direction = "input"
variable = "Main.Feedback"

[[node.io]]
device = "IO1"
item = "holding:100:INT"
direction = "input"
variable = "Main.Level"

[[node.io]]
device = "IO1"
item = "input:10:REAL"
direction = "input"
variable = "Main.Flow"

[[node.io]]
device = "IO1"
item = "coils:0"
direction = "output"
variable = "Main.Cmd"

[[node.io]]
device = "IO1"
item = "holding:200:INT"
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

[[node.point]]
name = "Flow"
type = "M_ME_TF_1"
ioa = 3
source = "Main.Flow"
"#
    )
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
async fn a_plc_reads_and_drives_real_io_over_modbus_and_a_silent_device_invalidates_its_inputs() {
    let model = DataModel::new(ModelConfig::default());
    model
        .write(1, Table::DiscreteInputs, 5, &Values::Bits(vec![true]))
        .unwrap();
    model
        .write(
            1,
            Table::HoldingRegisters,
            100,
            &Values::Registers(vec![21]),
        )
        .unwrap();
    let flow = 12.5_f32.to_bits();
    model
        .write(
            1,
            Table::InputRegisters,
            10,
            &Values::Registers(vec![(flow >> 16) as u16, (flow & 0xFFFF) as u16]),
        )
        .unwrap();
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
    let port = listener.local_addr().unwrap().port();
    let server = tokio::spawn(modbus::io::serve_tcp(listener, model.clone()));

    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir_all(dir.path().join("plc")).unwrap();
    std::fs::write(dir.path().join("plc/main.st"), PROGRAM).unwrap();
    std::fs::write(dir.path().join("station.toml"), project(port)).unwrap();
    let project = Project::load(dir.path()).unwrap_or_else(|errors| panic!("{errors}"));
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
    let register = |address: u16| match model.read(1, Table::HoldingRegisters, address, 1) {
        Ok(Values::Registers(words)) => words[0],
        other => panic!("{other:?}"),
    };
    let coil = || match model.read(1, Table::Coils, 0, 1) {
        Ok(Values::Bits(bits)) => bits[0],
        other => panic!("{other:?}"),
    };

    until("the inputs read", &runtime, || {
        let (feedback, level, flow) = (point("Feedback"), point("Level"), point("Flow"));
        !feedback.quality.invalid
            && feedback.value == PointValue::Bool(true)
            && level.value == PointValue::Int(21)
            && matches!(flow.value, PointValue::Float(x) if (x - 12.5).abs() < 1e-6)
    })
    .await;
    assert_eq!(point("IO1.not_answering").value, PointValue::Bool(false));
    until("the output written", &runtime, || register(200) == 42).await;
    runtime
        .with_simulation(|sim| sim.plc("A").unwrap().write("Main.Cmd", "TRUE").unwrap())
        .await
        .unwrap();
    until("coil 0 driven", &runtime, coil).await;
    // A negative INT goes both ways as two's complement.
    model
        .write(
            1,
            Table::HoldingRegisters,
            100,
            &Values::Registers(vec![(-7_i16) as u16]),
        )
        .unwrap();
    until("the new level", &runtime, || {
        point("Level").value == PointValue::Int(-7) && register(200) == (-14_i16) as u16
    })
    .await;

    server.abort();
    until("the device not answering", &runtime, || {
        point("IO1.not_answering").value == PointValue::Bool(true)
            && point("Feedback").quality.invalid
            && point("Feedback").value == PointValue::Bool(true)
    })
    .await;
    runtime.shutdown().await;
}
