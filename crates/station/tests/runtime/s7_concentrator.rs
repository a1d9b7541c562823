//! A node as the thesis's S7-1500 concentrator (`[node.s7_server]`, the railway-station
//! thesis, section 3.3) and a node as its LOGO! board, the S7 client (`[[node.device]]
//! kind = "s7"`): the board's breaker contact written into the concentrator's markers
//! reaches dispatch as a point of the concentrator, a dispatch command on a marker reaches
//! the board's program, and the board's silence makes the connection's status TRUE and
//! the points it feeds invalid.

use std::time::Duration;

use points::PointValue;
use station::config::Project;
use station::runtime::{Runtime, StoreChoice};

use crate::harness::*;

const CONCENTRATOR: &str = "PROGRAM Concentrator
VAR
    CommRH2 : BOOL := TRUE;
END_VAR
END_PROGRAM
";

const LOGO: &str = "PROGRAM Logo
VAR
    Closed : BOOL;
    OpenCmd : BOOL;
    OpenSeen : BOOL;
END_VAR
    IF OpenCmd THEN
        OpenSeen := TRUE;
    END_IF;
END_PROGRAM
";

/// The C_SC_NA_1 command on the concentrator's %MX24.0.
const OPEN_QF1: u32 = 500;

fn project(base: u16) -> Project {
    let text = format!(
        r#"
[station]
name = "S7 concentration"
time_zone = "UTC"
port_base = {base}

[[node]]
name = "RH1.1"
common_address = 11
sources = ["plc/concentrator.st"]

[node.server]
port_offset = 0

[node.s7_server]
port_offset = 1
markers = 64

[[node.s7_server.connection]]
name = "RH2"
tsap = "0101"
status = "Concentrator.CommRH2"

[[node.task]]
name = "main"
interval_ms = 10
programs = ["Concentrator"]

[[node.point]]
name = "COMM_RH2"
type = "M_SP_TB_1"
ioa = 280
source = "Concentrator.CommRH2"

[[node.point]]
name = "RH2_QF1_Zapnut"
type = "M_SP_TB_1"
ioa = 281
source = "%MX20.0"
invalid_when = "Concentrator.CommRH2"

[[node.command]]
name = "RH2_VypnoutQF1"
type = "C_SC_NA_1"
ioa = {OPEN_QF1}
target = "%MX24.0"
pulse_ms = 300

[[node]]
name = "RH2"
common_address = 21
sources = ["plc/logo.st"]

[[node.task]]
name = "main"
interval_ms = 10
programs = ["Logo"]

[[node.device]]
name = "S7_RH11"
kind = "s7"
ioa_base = 900
settings = {{ connect = "node:RH1.1", tsap = "0200:0101", cycle_ms = 20 }}

[[node.io]]
device = "S7_RH11"
item = "M20.0"
direction = "output"
variable = "Logo.Closed"

[[node.io]]
device = "S7_RH11"
item = "M24.0"
direction = "input"
variable = "Logo.OpenCmd"
"#
    );
    let folder = project_folder(&[
        ("station.toml", &text),
        ("plc/concentrator.st", CONCENTRATOR),
        ("plc/logo.st", LOGO),
    ]);
    // The folder lives as long as the test process: the runtime reads the sources.
    let path = folder.keep();
    Project::load(&path).unwrap_or_else(|errors| panic!("{errors}"))
}

fn point(runtime: &Runtime, node: &str, name: &str) -> points::Point {
    runtime.node(node).unwrap().points.point(name).unwrap()
}

async fn plc_bool(runtime: &Runtime, node: &'static str, path: &'static str) -> bool {
    runtime
        .with_simulation(move |sim| sim.plc(node).unwrap().read(path).unwrap())
        .await
        .unwrap()
        == plc::vm::Val::Int(1)
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_logo_board_reports_to_its_s7_concentrator_and_takes_its_commands() {
    let base = free_port_range(2);
    let runtime = start(project(base), StoreChoice::Disabled).await;
    assert!(runtime.node("RH1.1").unwrap().s7_server.is_some());

    // The board connects: the connection's status FALSE.
    advance_until(&runtime, Duration::from_millis(20), "RH2 connected", || {
        point(&runtime, "RH1.1", "COMM_RH2").value == PointValue::Bool(false)
    })
    .await;
    // The board's contact closes: the concentrator's point, valid.
    runtime
        .with_simulation(|sim| {
            sim.plc("RH2")
                .unwrap()
                .write("Logo.Closed", "TRUE")
                .unwrap()
        })
        .await
        .unwrap();
    advance_until(
        &runtime,
        Duration::from_millis(20),
        "QF1 closed at RH1.1",
        || {
            let qf1 = point(&runtime, "RH1.1", "RH2_QF1_Zapnut");
            qf1.value == PointValue::Bool(true) && !qf1.quality.invalid
        },
    )
    .await;

    // An engineering tool writes the command byte by hand (MB24 = 0): the byte is the
    // PLC's again at its next change, so dispatch's command still reaches the board.
    let s7_address = runtime
        .node("RH1.1")
        .unwrap()
        .s7_server
        .as_ref()
        .unwrap()
        .local_addr();
    let tool = s7::io::Client::connect(
        s7_address,
        s7::ClientConfig::new(s7::Tsaps::rack_slot(0, 1)),
        Duration::from_secs(5),
    )
    .await
    .unwrap();
    let written = tool
        .write_values(&[("MB24".parse().unwrap(), s7::Value::Byte(0))])
        .await
        .unwrap();
    assert!(written.iter().all(Result::is_ok), "{written:?}");
    // The board's own bytes are not disturbed by it: QF1 still reads closed.
    for _ in 0..5 {
        runtime.advance(Duration::from_millis(20)).await.unwrap();
    }
    let qf1 = tool.read_values(&["M20.0".parse().unwrap()]).await.unwrap();
    assert_eq!(qf1[0].as_ref().unwrap(), &s7::Value::Bool(true));

    // Dispatch opens QF1: the pulse on %MX24.0 reaches the board's program.
    let address = runtime
        .node("RH1.1")
        .unwrap()
        .server
        .as_ref()
        .unwrap()
        .local_addr();
    let dispatch = Dispatch::connect(address, 11, false).await;
    assert!(dispatch.single_command(OPEN_QF1, true, false).await);
    let mut seen = false;
    for _ in 0..200 {
        runtime.advance(Duration::from_millis(20)).await.unwrap();
        tokio::time::sleep(Duration::from_millis(5)).await;
        if plc_bool(&runtime, "RH2", "Logo.OpenSeen").await {
            seen = true;
            break;
        }
    }
    assert!(seen, "the command's pulse reached the LOGO!'s program");

    // The board falls silent: the connection's status TRUE, its points invalid.
    for device in &runtime.node("RH2").unwrap().devices {
        device.stop();
    }
    advance_until(&runtime, Duration::from_millis(20), "RH2 lost", || {
        point(&runtime, "RH1.1", "COMM_RH2").value == PointValue::Bool(true)
            && point(&runtime, "RH1.1", "RH2_QF1_Zapnut").quality.invalid
    })
    .await;
    runtime.shutdown().await;
}
