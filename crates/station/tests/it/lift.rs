//! Lift monitoring in the station runtime: EKM66 boards (simulated in the process, or
//! on a pseudo-terminal driven by the test) become points served over IEC 104, their
//! fault logs go into the store's archive without a duplicate or a gap across restarts
//! of the monitor and of the board and across the wrap-around of the fault index, and a
//! board that stops answering turns its points invalid with the communication alarm on.

use std::collections::HashSet;
use std::ops::ControlFlow;
use std::path::Path;
use std::time::{Duration, Instant};

use devices::ekm66::io::{run_simulator, EndpointAction, Transport};
use devices::ekm66::simulator::{Simulator, SimulatorConfig};
use iec60870::asdu::CommonAddress;
use iec60870::cs104::client::{spawn_client, ClientConfig, ClientEvent};
use points::Point;
use station::config::Project;
use station::runtime::{Pacing, Runtime, RuntimeOptions, StoreChoice};
use station::store::{LiftFaultOrder, LiftFaultQuery, LiftFaultRecord, PointValue};
use tokio::sync::mpsc;

/// Waits (bounded) until `condition` holds, checking every 20 ms.
async fn wait_until<T>(
    what: &str,
    within: Duration,
    mut condition: impl FnMut() -> Option<T>,
) -> T {
    let deadline = Instant::now() + within;
    loop {
        if let Some(value) = condition() {
            return value;
        }
        assert!(Instant::now() < deadline, "timed out waiting for {what}");
        tokio::time::sleep(Duration::from_millis(20)).await;
    }
}

fn point(runtime: &Runtime, node: &str, name: &str) -> Point {
    runtime
        .node(node)
        .and_then(|node| node.points.point(name))
        .unwrap_or_else(|| panic!("no point {name}"))
}

fn valid_value(runtime: &Runtime, node: &str, name: &str) -> Option<PointValue> {
    let point = point(runtime, node, name);
    (point.has_value() && !point.quality.invalid).then_some(point.value)
}

async fn start(folder: &Path) -> Runtime {
    let project = Project::load(folder).unwrap_or_else(|errors| panic!("{errors}"));
    Runtime::start(
        project,
        RuntimeOptions {
            pacing: Pacing::RealTime { speed: 1.0 },
            store: StoreChoice::Project,
            ..RuntimeOptions::default()
        },
    )
    .await
    .unwrap()
}

async fn archive(runtime: &Runtime, lift: &str) -> Vec<LiftFaultRecord> {
    let query = LiftFaultQuery::default()
        .with_lifts([lift.to_owned()])
        .with_order(LiftFaultOrder::Archived, false)
        .with_page(0, 1000);
    runtime
        .store()
        .unwrap()
        .query_lift_faults(&query)
        .await
        .unwrap()
        .items
}

/// Waits until the lift's archive holds `count` records.
async fn archived(runtime: &Runtime, lift: &str, count: usize) -> Vec<LiftFaultRecord> {
    let deadline = Instant::now() + Duration::from_secs(30);
    loop {
        let records = archive(runtime, lift).await;
        if records.len() >= count {
            return records;
        }
        assert!(
            Instant::now() < deadline,
            "timed out waiting for {count} archived faults of {lift}; have {records:?}"
        );
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn simulated_lifts_become_points_served_over_iec104_and_archive_their_faults() {
    let dir = tempfile::tempdir().unwrap();
    let port = testkit::ports::free_port();
    std::fs::write(
        dir.path().join("station.toml"),
        format!(
            r#"
[station]
name = "lifts"
time_zone = "Europe/Prague"
store = "sqlite:events.sqlite"
port_base = {port}

[[node]]
name = "MON"
common_address = 7
server = {{ port_offset = 0 }}

[[node.lift]]
name = "L1"
floors = 4
ioa_base = 100
simulate = "ekm66"
poll_period_ms = 100
fault_probability = 0.0

[[node.lift]]
name = "L2"
floors = 8
ioa_base = 200
simulate = "ekm66"
poll_period_ms = 100
counters_period_ms = 500
"#
        ),
    )
    .unwrap();
    let runtime = start(dir.path()).await;
    for lift in ["L1", "L2"] {
        wait_until("the status of both lifts", Duration::from_secs(20), || {
            valid_value(&runtime, "MON", &format!("{lift}.status"))
        })
        .await;
    }
    assert_eq!(
        valid_value(&runtime, "MON", "L1.not_answering"),
        Some(PointValue::Bool(false))
    );
    wait_until("L2's trip counters", Duration::from_secs(20), || {
        valid_value(&runtime, "MON", "L2.floor8_trips")
    })
    .await;

    // A fault injected on the board is archived, with the board's time, and shown.
    let mut faults = runtime.archived_faults();
    runtime.operate("lift L1 fault 3C").await.unwrap();
    let record = tokio::time::timeout(Duration::from_secs(20), async {
        loop {
            let record = faults.recv().await.unwrap();
            if record.lift == "L1" {
                return record;
            }
        }
    })
    .await
    .expect("the fault is archived");
    assert_eq!(record.code, 0x3C);
    assert_eq!(record.node, "MON");
    assert!(record.id.is_some(), "committed to the store");
    assert!(record.board_time.is_some());
    assert_eq!(archive(&runtime, "L1").await, vec![record.clone()]);
    wait_until("L1.last_fault", Duration::from_secs(5), || {
        (valid_value(&runtime, "MON", "L1.last_fault") == Some(PointValue::Int(0x3C))).then_some(())
    })
    .await;
    assert_eq!(
        valid_value(&runtime, "MON", "L1.faults"),
        Some(PointValue::Int(1))
    );

    // The points are served over IEC 104: a general interrogation brings them.
    let (client, mut events) = spawn_client(ClientConfig::new(
        format!("127.0.0.1:{port}"),
        CommonAddress::new(7),
    ));
    let mut ioas = HashSet::new();
    tokio::time::timeout(Duration::from_secs(20), async {
        while let Some(event) = events.recv().await {
            match event {
                ClientEvent::Started => {
                    let _ = client.interrogate(20).await;
                }
                ClientEvent::Asdu(asdu) => {
                    ioas.extend(asdu.objects.iter().map(|object| object.ioa.get()));
                    if ioas.contains(&100) && ioas.contains(&(200 + 16 + 7)) {
                        return;
                    }
                }
                _ => {}
            }
        }
    })
    .await
    .expect("the lift points in the interrogation");

    // A board that stops answering: values invalid, the communication alarm on.
    runtime.operate("lift L2 silent").await.unwrap();
    wait_until("L2's communication alarm", Duration::from_secs(20), || {
        (valid_value(&runtime, "MON", "L2.not_answering") == Some(PointValue::Bool(true)))
            .then_some(())
    })
    .await;
    assert!(point(&runtime, "MON", "L2.status").quality.invalid);
    assert!(point(&runtime, "MON", "L2.floor1_trips").quality.invalid);
    assert!(!point(&runtime, "MON", "L1.status").quality.invalid);
    // The silent board's line-error count grows with every poll; the store keeps one
    // change of it a minute (it stored every one, 170,000 a day per cut cable).
    let errors = |runtime: &Runtime| match point(runtime, "MON", "L2.errors").value {
        PointValue::Int(count) => count,
        PointValue::Float(count) => count as i64,
        other => panic!("L2.errors is {other:?}"),
    };
    let first = errors(&runtime);
    wait_until("L2's line errors growing", Duration::from_secs(20), || {
        (errors(&runtime) >= first + 3).then_some(())
    })
    .await;
    runtime.recorder().flush().await;
    let stored = runtime
        .store()
        .unwrap()
        .query_events(&station::store::EventQuery::default().with_point("L2.errors"))
        .await
        .unwrap()
        .items;
    assert!(
        stored.len() <= 2,
        "{} changes of L2.errors stored within seconds: {stored:?}",
        stored.len()
    );
    runtime.operate("lift L2 answer").await.unwrap();
    wait_until("L2 answering again", Duration::from_secs(20), || {
        valid_value(&runtime, "MON", "L2.status")
    })
    .await;
    assert_eq!(
        valid_value(&runtime, "MON", "L2.not_answering"),
        Some(PointValue::Bool(false))
    );
    // The alarm is in the event history.
    runtime.recorder().flush().await;
    let alarms = runtime
        .store()
        .unwrap()
        .query_events(&station::store::EventQuery::default().with_point("L2.not_answering"))
        .await
        .unwrap()
        .items;
    assert!(
        alarms
            .iter()
            .any(|event| event.value == PointValue::Bool(true)),
        "{alarms:?}"
    );
    runtime.shutdown().await;
}

/// A board on a pseudo-terminal, driven by the test: it outlives the monitor.
struct Board {
    operations: mpsc::UnboundedSender<EndpointAction<Simulator>>,
    path: String,
}

impl Board {
    async fn start(config: SimulatorConfig) -> Board {
        let line = Transport::Pty.open().await.unwrap();
        let path = line.pty_path.clone().unwrap();
        let (operations, mut inbox) = mpsc::unbounded_channel();
        tokio::spawn(async move {
            // The whole line, its other end included: a pseudo-terminal whose other end
            // no one holds answers EIO between two openings by the monitor.
            let line = line;
            let mut board = Simulator::new(config, Instant::now());
            let end = run_simulator(line.stream, &mut board, &mut inbox, |_| {
                ControlFlow::Continue(())
            })
            .await;
            eprintln!("board ended: {end:?}");
        });
        Board { operations, path }
    }

    async fn with<R: Send + 'static>(
        &self,
        f: impl FnOnce(&mut Simulator) -> R + Send + 'static,
    ) -> R {
        let (reply, answer) = tokio::sync::oneshot::channel();
        self.operations
            .send(Box::new(move |board: &mut Simulator| {
                let _ = reply.send(f(board));
            }))
            .unwrap_or_else(|_| panic!("the board stopped"));
        answer.await.unwrap()
    }

    async fn fault(&self, code: u8) -> u8 {
        self.with(move |board| board.inject_fault(code).index).await
    }

    /// Switches the board off and on: its clock and state start again, its fault log
    /// and counters (non-volatile) stay.
    async fn power_cycle(&self) {
        self.with(|board| {
            *board = Simulator::with_memory(
                board.config().clone(),
                board.memory().clone(),
                Instant::now(),
            );
        })
        .await;
    }
}

fn pty_project(folder: &Path, port: &str) {
    std::fs::write(
        folder.join("station.toml"),
        format!(
            r#"
[station]
name = "machine room"
time_zone = "UTC"
store = "sqlite:events.sqlite"

[[node]]
name = "MON"
common_address = 1

[[node.lift]]
name = "L7"
floors = 5
ioa_base = 1
port = "{port}"
# A pseudo-terminal keeps no parity: 8N1, or the port refuses the board's 8E1.
parity = "none"
poll_period_ms = 100
timeout_ms = 300
"#
        ),
    )
    .unwrap();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_archive_has_every_fault_once_across_restarts_and_wrap_around_over_a_pty() {
    let mut config = SimulatorConfig::default();
    config.floors = 5;
    config.stack_size = 4;
    config.fault_probability = 0.0;
    config.status_probability = 0.0;
    let board = Board::start(config).await;
    let dir = tempfile::tempdir().unwrap();
    pty_project(dir.path(), &board.path);
    let mut expected = Vec::new();

    // Two faults before the monitor starts: read on start.
    for code in [0x01, 0x02] {
        expected.push((board.fault(code).await, code));
    }
    let runtime = start(dir.path()).await;
    archived(&runtime, "L7", 2).await;
    expected.push((board.fault(0x03).await, 0x03));
    archived(&runtime, "L7", 3).await;
    runtime.shutdown().await;

    // While the monitor is down the stack wraps (4 slots: indexes 3, 0).
    for code in [0x04, 0x05] {
        expected.push((board.fault(code).await, code));
    }
    let runtime = start(dir.path()).await;
    archived(&runtime, "L7", 5).await;

    // The board restarts; two more faults, the index wrapping again.
    board.power_cycle().await;
    for code in [0x06, 0x07] {
        expected.push((board.fault(code).await, code));
    }
    archived(&runtime, "L7", 7).await;
    // Give a duplicate the chance to show: twenty more queries answered.
    let answered = board.with(|board| board.queries_answered()).await;
    let deadline = Instant::now() + Duration::from_secs(20);
    while board.with(|board| board.queries_answered()).await < answered + 20 {
        assert!(Instant::now() < deadline, "the monitor stopped polling");
        tokio::time::sleep(Duration::from_millis(20)).await;
    }
    runtime.recorder().flush().await;
    let records = archive(&runtime, "L7").await;
    let got: Vec<(u8, u8)> = records
        .iter()
        .map(|record| (record.stack_index, record.code))
        .collect();
    assert_eq!(got, expected, "every fault once, in the board's order");
    assert_eq!(
        valid_value(&runtime, "MON", "L7.faults"),
        Some(PointValue::Int(7))
    );
    runtime.shutdown().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_new_fault_is_mailed_to_the_technician_and_recorded() {
    if !testkit::smtp::smtp_peer_available() {
        return;
    }
    let sink = testkit::smtp::SmtpSink::start();
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("station.toml"),
        format!(
            r#"
[station]
name = "lifts"
time_zone = "Europe/Prague"
store = "sqlite:events.sqlite"

[[node]]
name = "MON"
common_address = 7

[[node.lift]]
name = "L3"
description = "Hospital, bed lift"
floors = 8
ioa_base = 100
simulate = "ekm66"
poll_period_ms = 100
fault_probability = 0.0

[node.notify.smtp]
host = "127.0.0.1"
port = {port}
security = "none"
from = "Stanice <stanice@example.cz>"
timeout_s = 10

[node.notify.channel.technicians]
kind = "email"
to = ["novak@example.cz"]

[[node.notify.rule]]
name = "door faults"
sources = ["L*"]
classes = ["door-sequence", "comm-lost"]
channels = ["technicians"]
quiet_period_s = 600
"#,
            port = sink.port
        ),
    )
    .unwrap();
    let runtime = start(dir.path()).await;
    wait_until("L3's status", Duration::from_secs(20), || {
        valid_value(&runtime, "MON", "L3.status")
    })
    .await;
    // 0x3C is a door-sequence fault (docs/LIFT.md); 0x30 (main power) matches no rule.
    runtime.operate("lift L3 fault 30").await.unwrap();
    runtime.operate("lift L3 fault 3C").await.unwrap();
    let mails = tokio::task::spawn_blocking(move || {
        let mails = sink.wait_for(1);
        (sink, mails)
    })
    .await
    .unwrap();
    let (sink, mails) = mails;
    assert_eq!(mails.len(), 1, "{mails:?}");
    let mail = &mails[0];
    assert_eq!(mail["rcpt_tos"][0], "novak@example.cz");
    let subject = mail["subject"].as_str().unwrap();
    assert!(subject.starts_with("[L3] fault 0x3C"), "{subject}");
    let body = mail["body"].as_str().unwrap();
    assert!(body.contains("Porucha 0x3C"), "{body}");
    assert!(body.contains("Hospital, bed lift"), "{body}");
    // The same class again within the quiet period: recorded as suppressed, not mailed.
    runtime.operate("lift L3 fault 3D").await.unwrap();
    let store = runtime.store().unwrap();
    let deadline = Instant::now() + Duration::from_secs(20);
    let records = loop {
        let records = store
            .query_notifications(&station::store::NotificationQuery::default())
            .await
            .unwrap()
            .items;
        if records.len() >= 2 {
            break records;
        }
        assert!(
            Instant::now() < deadline,
            "notifications recorded: {records:?}"
        );
        tokio::time::sleep(Duration::from_millis(50)).await;
    };
    // Newest first.
    assert_eq!(
        records[1].outcome,
        station::store::NotificationOutcome::Sent
    );
    assert_eq!(records[1].recipient, "novak@example.cz");
    assert_eq!(records[1].source, "L3");
    assert_eq!(
        records[0].outcome,
        station::store::NotificationOutcome::Suppressed
    );
    assert!(records[0].detail.contains("quiet"), "{}", records[0].detail);
    // A board that stops answering: the communication alarm, mailed.
    runtime.operate("lift L3 silent").await.unwrap();
    let (sink, mails) = tokio::task::spawn_blocking(move || {
        let mails = sink.wait_for(2);
        (sink, mails)
    })
    .await
    .unwrap();
    let subject = mails[1]["subject"].as_str().unwrap();
    assert_eq!(subject, "[L3] controller board not answering");
    drop(sink);
    runtime.shutdown().await;
}
