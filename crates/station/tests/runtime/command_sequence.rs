//! The command sequence through the station runtime, on the wire at the controlling
//! station: ACT_CON, then the return information of the command's feedback point (cause
//! 11), then ACT_TERM; on the board itself and through a concentrator that republishes
//! it, direct and select-before-operate, with and without a feedback point, and when the
//! feedback never changes (terminated after its wait, without return information).

use std::net::SocketAddr;
use std::sync::{Arc, Mutex};
use std::time::Duration;

use iec60870::asdu::{Asdu, Cause, CommandQualifier, CommonAddress, Element, Ioa, TypeId};
use iec60870::cs104::client::{spawn_client, ClientConfig, ClientEvent, ClientHandle};
use station::config::Project;
use station::runtime::{Runtime, StoreChoice};
use station::store::{CommandOutcome, CommandQuery};

use crate::harness::{eventually, free_port_range, links_up, project_folder, start, start_at};

const QF1_CLOSED: u32 = 100;
const QF2_CLOSED: u32 = 101;
const HORN: u32 = 102;
const QF1_CLOSE: u32 = 200;
const QF2_CLOSE_SBO: u32 = 201;
const HORN_SET: u32 = 202;

const BOARD_ST: &str = r#"
PROGRAM Board
VAR
    CmdQF1 : BOOL;
    CmdQF2 : BOOL;
    Horn : BOOL;
    QF1 : BOOL;
    QF2 : BOOL;
    WindowMinutes : INT;
    Operate1 : TON;
    Operate2 : TON;
END_VAR
(* A breaker follows its command after its operate time. *)
Operate1(IN := CmdQF1 <> QF1, PT := T#60ms);
IF Operate1.Q THEN QF1 := CmdQF1; END_IF;
Operate2(IN := CmdQF2 <> QF2, PT := T#60ms);
IF Operate2.Q THEN QF2 := CmdQF2; END_IF;
END_PROGRAM
"#;

const STATION_TOML: &str = r#"
[station]
name = "Command sequence"
time_zone = "Europe/Prague"

[[node]]
name = "TOP"
common_address = 1
[node.server]
port_offset = 0
[[node.link]]
name = "BOARD"
node = "BOARD"
republish = { ioa_offset = 0 }

[[node]]
name = "BOARD"
common_address = 21
sources = ["plc/board.st"]
[node.server]
port_offset = 1
max_command_age_ms = 10000
# The concentrator above and the test's own controlling station are independent
# masters: in one group, the test's STARTDT would take the data from the concentrator.
redundancy = "connection-is-group"
[[node.task]]
name = "fast"
interval_ms = 10
programs = ["Board"]
[[node.point]]
name = "QF1_Closed"
type = "M_SP_TB_1"
ioa = 100
source = "Board.QF1"
[[node.point]]
name = "QF2_Closed"
type = "M_SP_TB_1"
ioa = 101
source = "Board.QF2"
[[node.point]]
name = "Horn"
type = "M_SP_TB_1"
ioa = 102
source = "Board.Horn"
[[node.command]]
name = "QF1_Close"
type = "C_SC_NA_1"
ioa = 200
target = "Board.CmdQF1"
feedback = "QF1_Closed"
feedback_timeout_ms = 400
[[node.command]]
name = "QF2_Close"
type = "C_SC_NA_1"
ioa = 201
target = "Board.CmdQF2"
select_required = true
feedback = "QF2_Closed"
[[node.command]]
name = "Horn_Set"
type = "C_SC_NA_1"
ioa = 202
target = "Board.Horn"
[[node.command]]
name = "Window_On"
type = "C_SE_NB_1"
ioa = 203
target = "Board.WindowMinutes"
range = [0, 1439]
"#;

/// The project in a temporary folder, on free ports.
fn project() -> (tempfile::TempDir, Project) {
    let dir = project_folder(&[("station.toml", STATION_TOML), ("plc/board.st", BOARD_ST)]);
    let project = Project::load(dir.path()).unwrap_or_else(|errors| panic!("{errors}"));
    let project = project.with_port_base(free_port_range(2));
    (dir, project)
}

/// A controlling station that keeps every ASDU in the order it arrived.
struct Wire {
    client: ClientHandle,
    asdus: Arc<Mutex<Vec<Asdu>>>,
}

impl Wire {
    async fn connect(address: SocketAddr, common_address: u16) -> Wire {
        let config = ClientConfig::new(address.to_string(), CommonAddress::new(common_address));
        let (client, mut events) = spawn_client(config);
        let asdus = Arc::new(Mutex::new(Vec::new()));
        let started = Arc::new(Mutex::new(false));
        {
            let (asdus, started) = (Arc::clone(&asdus), Arc::clone(&started));
            tokio::spawn(async move {
                while let Some(event) = events.recv().await {
                    match event {
                        ClientEvent::Started => *started.lock().unwrap() = true,
                        ClientEvent::Asdu(asdu) => asdus.lock().unwrap().push(asdu),
                        _ => {}
                    }
                }
            });
        }
        eventually("the controlling station is started", || {
            *started.lock().unwrap()
        })
        .await;
        Wire { client, asdus }
    }

    fn received(&self) -> usize {
        self.asdus.lock().unwrap().len()
    }

    /// Sends a single command and, advancing the plant, returns the answers to it and the
    /// monitor objects of `feedback` received from `since` until its last answer (the
    /// confirmation of a select, else the termination).
    async fn command(
        &self,
        runtime: &Runtime,
        ioa: u32,
        on: bool,
        select: bool,
        feedback: u32,
    ) -> Vec<String> {
        let since = self.received();
        let qualifier = CommandQualifier::new(0, select).unwrap();
        let client = self.client.clone();
        let request = tokio::spawn(async move {
            client
                .command(
                    TypeId::C_SC_NA_1,
                    Ioa::try_new(ioa).unwrap(),
                    Element::SingleCommand { on, qualifier },
                    None,
                )
                .await
        });
        let last_cause = if select {
            Cause::ACTIVATION_CON
        } else {
            Cause::ACTIVATION_TERMINATION
        };
        let finished = |asdus: &[Asdu]| {
            asdus.iter().any(|asdu| {
                asdu.type_id == TypeId::C_SC_NA_1
                    && asdu.objects[0].ioa.get() == ioa
                    && (asdu.cot.cause == last_cause || asdu.cot.negative)
            })
        };
        for _ in 0..500 {
            if finished(&self.asdus.lock().unwrap()[since..]) {
                break;
            }
            runtime.advance(Duration::from_millis(10)).await.unwrap();
            tokio::time::sleep(Duration::from_millis(5)).await;
        }
        let outcome = request.await.unwrap().unwrap();
        assert!(outcome.positive, "{outcome:?}");
        let asdus = self.asdus.lock().unwrap()[since..].to_vec();
        asdus
            .iter()
            .filter_map(|asdu| {
                let address = asdu.objects[0].ioa.get();
                match (asdu.type_id, asdu.cot.cause) {
                    (TypeId::C_SC_NA_1, Cause::ACTIVATION_CON) if address == ioa => {
                        Some("ACT_CON".to_owned())
                    }
                    (TypeId::C_SC_NA_1, Cause::ACTIVATION_TERMINATION) if address == ioa => {
                        Some("ACT_TERM".to_owned())
                    }
                    (_, cause) if asdu.type_id.is_monitor() && address == feedback => {
                        Some(format!("{address} cause {}", cause.value()))
                    }
                    _ => None,
                }
            })
            .collect()
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn acknowledgement_return_information_termination_on_the_board_and_through_a_concentrator() {
    let _ = tracing_subscriber::fmt()
        .with_max_level(tracing::Level::INFO)
        .with_test_writer()
        .try_init();
    let (_dir, project) = project();
    let top_address = project
        .node("TOP")
        .unwrap()
        .server_address(&project.station)
        .unwrap();
    let board_address = project
        .node("BOARD")
        .unwrap()
        .server_address(&project.station)
        .unwrap();
    let runtime = start(project, StoreChoice::Disabled).await;
    links_up(&runtime).await;
    let top = Wire::connect(top_address, 1).await;
    let board = Wire::connect(board_address, 21).await;
    let return_information = |ioa: u32| format!("{ioa} cause 11");

    // Through the concentrator: direct execute with a feedback point.
    assert_eq!(
        top.command(&runtime, QF1_CLOSE, true, false, QF1_CLOSED)
            .await,
        ["ACT_CON", &return_information(QF1_CLOSED), "ACT_TERM"]
    );
    // On the board itself.
    assert_eq!(
        board
            .command(&runtime, QF1_CLOSE, false, false, QF1_CLOSED)
            .await,
        ["ACT_CON", &return_information(QF1_CLOSED), "ACT_TERM"]
    );
    // Select-before-operate through the concentrator: the select is confirmed alone.
    assert_eq!(
        top.command(&runtime, QF2_CLOSE_SBO, true, true, QF2_CLOSED)
            .await,
        ["ACT_CON"]
    );
    assert_eq!(
        top.command(&runtime, QF2_CLOSE_SBO, true, false, QF2_CLOSED)
            .await,
        ["ACT_CON", &return_information(QF2_CLOSED), "ACT_TERM"]
    );
    // No feedback point: confirmed and terminated; the value comes as a spontaneous
    // change of its own (cause 3), whenever the scan makes it: before the confirmation,
    // between, or after (seen once under load, first), never as return information.
    let answers = top.command(&runtime, HORN_SET, true, false, HORN).await;
    let sequence: Vec<&str> = answers
        .iter()
        .map(String::as_str)
        .filter(|answer| answer.starts_with("ACT_"))
        .collect();
    assert_eq!(sequence, ["ACT_CON", "ACT_TERM"], "{answers:?}");
    assert!(!answers.contains(&return_information(HORN)), "{answers:?}");

    // The breaker is already where the command wants it: no return information, the
    // termination follows when the wait (400 ms) runs out.
    top.command(&runtime, QF1_CLOSE, true, false, QF1_CLOSED)
        .await;
    let answers = top
        .command(&runtime, QF1_CLOSE, true, false, QF1_CLOSED)
        .await;
    assert_eq!(answers, ["ACT_CON", "ACT_TERM"]);
    runtime.shutdown().await;
}

/// Sends a time-tagged single command (C_SC_TA_1) stamped `age` before the node's clock
/// (negative: in the future), in the station's zone; returns whether it was confirmed.
async fn tagged_command(
    wire: &Wire,
    runtime: &Runtime,
    node: &str,
    ioa: u32,
    age: chrono::TimeDelta,
) -> bool {
    let points = &runtime.node(node).unwrap().points;
    let time = points.zone().to_cp56(points.clock().now() - age);
    let outcome = wire
        .client
        .command(
            TypeId::C_SC_TA_1,
            Ioa::try_new(ioa).unwrap(),
            Element::SingleCommand {
                on: true,
                qualifier: CommandQualifier::EXECUTE,
            },
            Some(time),
        )
        .await
        .unwrap();
    assert_eq!(outcome.cause, Cause::ACTIVATION_CON, "{outcome:?}");
    outcome.positive
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn stale_and_future_time_tagged_commands_are_refused_on_the_node_clock_and_audited() {
    let (_dir, project) = project();
    let board_address = project
        .node("BOARD")
        .unwrap()
        .server_address(&project.station)
        .unwrap();
    // The night summer time ends in Prague: 02:00-03:00 local happens twice; the node's
    // clock is at 02:30 CET, the second pass (01:30 UTC).
    let start_time =
        chrono::TimeZone::with_ymd_and_hms(&chrono::Utc, 2026, 10, 25, 1, 30, 0).unwrap();
    let runtime = start_at(
        project,
        StoreChoice::Url("sqlite::memory:".into()),
        start_time,
    )
    .await;
    links_up(&runtime).await;
    let board = Wire::connect(board_address, 21).await;
    let seconds = chrono::TimeDelta::seconds;

    // 9 s old: executed. An hour old (02:30 CEST, the first pass, SU set): refused,
    // although its wall-clock reading equals the node's. 11 s old and 11 s ahead: refused.
    assert!(tagged_command(&board, &runtime, "BOARD", HORN_SET, seconds(9)).await);
    assert!(!tagged_command(&board, &runtime, "BOARD", HORN_SET, seconds(3600)).await);
    assert!(!tagged_command(&board, &runtime, "BOARD", HORN_SET, seconds(11)).await);
    assert!(!tagged_command(&board, &runtime, "BOARD", HORN_SET, seconds(-11)).await);

    runtime.recorder().flush().await;
    let commands = runtime
        .store()
        .unwrap()
        .query_commands(&CommandQuery::default().with_node("BOARD"))
        .await
        .unwrap()
        .items;
    let outcomes: Vec<(CommandOutcome, String)> = commands
        .iter()
        .rev()
        .map(|c| (c.outcome, c.detail.clone()))
        .collect();
    assert_eq!(outcomes.len(), 4, "{outcomes:?}");
    assert_eq!(outcomes[0].0, CommandOutcome::Executed, "{outcomes:?}");
    for ((outcome, detail), expected) in outcomes[1..].iter().zip([
        "time tag 3600.000 s old, more than the 10.000 s allowed",
        "time tag 11.000 s old",
        "time tag 11.000 s in the future",
    ]) {
        assert_eq!(*outcome, CommandOutcome::Refused);
        assert!(detail.starts_with(expected), "{detail}");
    }
    assert!(commands.iter().all(|c| c.point == "Horn_Set"));
    runtime.shutdown().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn set_points_outside_the_project_range_are_refused_and_audited() {
    let (_dir, project) = project();
    let board_address = project
        .node("BOARD")
        .unwrap()
        .server_address(&project.station)
        .unwrap();
    let runtime = start(project, StoreChoice::Url("sqlite::memory:".into())).await;
    let board = Wire::connect(board_address, 21).await;
    let mut outcomes = Vec::new();
    for value in [-5, 0, 1439, 1440, 1441, 32767] {
        let outcome = board
            .client
            .command(
                TypeId::C_SE_NB_1,
                Ioa::try_new(203).unwrap(),
                Element::SetpointScaled {
                    value,
                    qualifier: iec60870::asdu::SetpointQualifier::EXECUTE,
                },
                None,
            )
            .await
            .unwrap();
        outcomes.push((value, outcome.positive));
    }
    assert_eq!(
        outcomes,
        [
            (-5, false),
            (0, true),
            (1439, true),
            (1440, false),
            (1441, false),
            (32767, false)
        ]
    );
    runtime.recorder().flush().await;
    let audit = runtime
        .store()
        .unwrap()
        .query_commands(&CommandQuery::default().with_node("BOARD"))
        .await
        .unwrap()
        .items;
    let refused: Vec<String> = audit
        .iter()
        .filter(|c| c.outcome == CommandOutcome::Refused)
        .map(|c| c.detail.clone())
        .collect();
    assert_eq!(refused.len(), 4, "{refused:?}");
    assert!(
        refused
            .iter()
            .any(|d| d == "value 32767 outside the range 0..=1439 of the project"),
        "{refused:?}"
    );
    runtime.shutdown().await;
}
