//! A station node as a Sparkplug B edge node against a real mosquitto broker, checked by
//! an independent consumer (paho-mqtt and Eclipse Tahu's published protobuf): the birth,
//! sequence numbers, values as the station had them, and the will when the connection
//! dies.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use points::{PointChange, PointValue};
use sparkplug::mqtt::{self, MqttConfig};
use station::config::Project;
use station::runtime::sink::{PointSink, SinkError};
use station::runtime::{Runtime, RuntimeOptions, StoreChoice};

/// Every change of the node, as the station published it, until stopped.
#[derive(Debug, Default)]
struct Recording {
    changes: Mutex<Vec<PointChange>>,
    stopped: AtomicBool,
}

impl PointSink for Recording {
    fn publish(&self, change: &PointChange) -> Result<(), SinkError> {
        if !self.stopped.load(Ordering::SeqCst) {
            self.changes.lock().unwrap().push(change.clone());
        }
        Ok(())
    }

    fn describe(&self) -> String {
        "recording".into()
    }
}

fn millis(change: &PointChange) -> u64 {
    let time = change.source_time.map_or(change.received, |s| s.time);
    time.timestamp_millis() as u64
}

/// Whether a value the consumer printed is the station's.
fn same_value(station: &PointValue, consumer: &serde_json::Value) -> bool {
    match station {
        PointValue::Bool(b) => consumer.as_bool() == Some(*b),
        PointValue::Float(x) => consumer.as_f64().is_some_and(|c| c as f32 == *x as f32),
        PointValue::Int(i) => consumer.as_i64() == Some(*i),
        PointValue::DoublePoint(d) => consumer.as_i64() == Some(i64::from(*d)),
        PointValue::Bits(b) => consumer.as_i64() == Some(i64::from(*b)),
        PointValue::Text(t) => consumer.as_str() == Some(t),
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn an_independent_consumer_sees_births_data_and_the_will() {
    if !testkit::mqtt::peers_available() {
        return;
    }
    let broker = testkit::mqtt::start_broker();
    let consumer = testkit::mqtt::Consumer::start(broker.port, "sorting", "S7", 20, 120);

    let dir = tempfile::tempdir().unwrap();
    testkit::mqtt::balance_project(dir.path(), "sorting");
    let project = Project::load(dir.path()).unwrap_or_else(|errors| panic!("{errors}"));
    let runtime = Runtime::start(
        project,
        RuntimeOptions {
            store: StoreChoice::Disabled,
            ..RuntimeOptions::default()
        },
    )
    .await
    .unwrap();
    let node = Arc::clone(&runtime.node("S7").unwrap().points);
    let recording = Arc::new(Recording::default());
    node.attach_sink(Arc::clone(&recording) as Arc<dyn PointSink>);
    let initial = node.points();
    let publishers = mqtt::start(
        &runtime,
        &MqttConfig {
            url: format!("mqtt://127.0.0.1:{}", broker.port),
            ..MqttConfig::default()
        },
    )
    .unwrap();
    assert_eq!(publishers.len(), 1);

    let lines = tokio::task::spawn_blocking(move || {
        consumer.wait_for(|l| l == "DATA 20", Duration::from_secs(90));
        consumer
    })
    .await
    .unwrap();
    // The connection dies as in a crash: no DISCONNECT, the broker sends the will.
    publishers[0].kill();
    recording.stopped.store(true, Ordering::SeqCst);
    let verdict = tokio::task::spawn_blocking(move || {
        lines.wait_for(|l| l.starts_with('{'), Duration::from_secs(60))
    })
    .await
    .unwrap();
    runtime.shutdown().await;

    let verdict: serde_json::Value = serde_json::from_str(&verdict).unwrap();
    assert_eq!(verdict["verdict"], "PASS", "{verdict}");
    assert_eq!(verdict["births"], serde_json::json!([0]));
    assert_eq!(verdict["deaths"], serde_json::json!([0]));

    // Every value the consumer got is one the station had, at the station's time.
    let changes = recording.changes.lock().unwrap().clone();
    let values = verdict["values"].as_array().unwrap();
    assert!(values.len() >= 20, "{values:?}");
    let mut weights = 0;
    for value in values {
        let [name, timestamp, value, quality] = value.as_array().unwrap().as_slice() else {
            panic!("{value}");
        };
        let name = name.as_str().unwrap();
        if value.is_null() {
            // Never updated before the birth.
            assert!(
                initial
                    .iter()
                    .any(|p| p.spec.name == name && p.received.is_none()),
                "{name}"
            );
            continue;
        }
        let timestamp = timestamp.as_u64().unwrap();
        let known = changes
            .iter()
            .filter(|c| c.name == name)
            .map(|c| (millis(c), &c.value, c.quality.invalid))
            .chain(
                initial
                    .iter()
                    .filter(|p| p.spec.name == name && p.received.is_some())
                    .map(|p| {
                        let time = p.source_time.map_or(p.received.unwrap(), |s| s.time);
                        (time.timestamp_millis() as u64, &p.value, p.quality.invalid)
                    }),
            )
            .any(|(at, v, invalid)| {
                at == timestamp && same_value(v, value) && (quality.as_i64() == Some(0)) == invalid
            });
        assert!(
            known,
            "{name} = {value} at {timestamp} (quality {quality}) was never the station's"
        );
        if name == "BAL.weight" {
            weights += 1;
        }
    }
    assert!(weights >= 10, "the weight changed {weights} times");
}

/// A Sparkplug host application played by the test: rumqttc on the same broker.
struct Host {
    client: rumqttc::AsyncClient,
    messages: tokio::sync::mpsc::UnboundedReceiver<(String, sparkplug::Payload)>,
    _task: tokio::task::JoinHandle<()>,
}

impl Host {
    async fn connect(port: u16) -> Host {
        let (client, mut events) = rumqttc::AsyncClient::new(
            rumqttc::MqttOptions::new("test-host", "127.0.0.1", port),
            64,
        );
        client
            .subscribe("spBv1.0/sorting/#", rumqttc::QoS::AtLeastOnce)
            .await
            .unwrap();
        let (sender, messages) = tokio::sync::mpsc::unbounded_channel();
        let (subscribed_tx, subscribed) = tokio::sync::oneshot::channel();
        let task = tokio::spawn(async move {
            let mut subscribed_tx = Some(subscribed_tx);
            while let Ok(event) = events.poll().await {
                match event {
                    rumqttc::Event::Incoming(rumqttc::Packet::SubAck(_)) => {
                        if let Some(s) = subscribed_tx.take() {
                            let _ = s.send(());
                        }
                    }
                    rumqttc::Event::Incoming(rumqttc::Packet::Publish(p)) => {
                        if let Ok(payload) = sparkplug::Payload::decode_bytes(&p.payload) {
                            let _ = sender.send((p.topic, payload));
                        }
                    }
                    _ => {}
                }
            }
        });
        tokio::time::timeout(Duration::from_secs(20), subscribed)
            .await
            .unwrap()
            .unwrap();
        Host {
            client,
            messages,
            _task: task,
        }
    }

    /// The next message on a topic containing `kind`, within 30 s.
    async fn next(&mut self, kind: &str) -> sparkplug::Payload {
        tokio::time::timeout(Duration::from_secs(30), async {
            loop {
                let (topic, payload) = self.messages.recv().await.unwrap();
                if topic.contains(kind) {
                    return payload;
                }
            }
        })
        .await
        .unwrap_or_else(|_| panic!("no {kind} within 30 s"))
    }

    async fn state(&self, online: bool, timestamp: u64) {
        self.client
            .publish(
                "spBv1.0/STATE/scada",
                rumqttc::QoS::AtLeastOnce,
                true,
                sparkplug::state::HostState { online, timestamp }.to_bytes(),
            )
            .await
            .unwrap();
    }
}

fn long_metric(payload: &sparkplug::Payload, name: &str) -> Option<u64> {
    payload
        .metrics
        .iter()
        .find(|m| m.name.as_deref() == Some(name))
        .and_then(|m| match m.value {
            Some(sparkplug::MetricValue::LongValue(v)) => Some(v),
            _ => None,
        })
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn with_a_primary_host_the_node_births_once_it_is_online_and_rebirths_on_ncmd() {
    if !testkit::mqtt::peers_available() {
        return;
    }
    let broker = testkit::mqtt::start_broker();
    let mut host = Host::connect(broker.port).await;
    host.state(false, 1).await;

    let dir = tempfile::tempdir().unwrap();
    testkit::mqtt::balance_project(dir.path(), "sorting");
    let project = Project::load(dir.path()).unwrap_or_else(|errors| panic!("{errors}"));
    let runtime = Runtime::start(
        project,
        RuntimeOptions {
            store: StoreChoice::Disabled,
            ..RuntimeOptions::default()
        },
    )
    .await
    .unwrap();
    let publishers = mqtt::start(
        &runtime,
        &MqttConfig {
            url: format!("mqtt://127.0.0.1:{}", broker.port),
            primary_host: Some("scada".into()),
            ..MqttConfig::default()
        },
    )
    .unwrap();
    let stats = Arc::clone(&publishers[0].stats);
    let deadline = std::time::Instant::now() + Duration::from_secs(30);
    while stats.connections.load(Ordering::SeqCst) == 0 {
        assert!(
            std::time::Instant::now() < deadline,
            "the node never connected"
        );
        tokio::time::sleep(Duration::from_millis(20)).await;
    }
    // Connected, the host offline: nothing published.
    assert_eq!(stats.births.load(Ordering::SeqCst), 0);
    assert_eq!(stats.published.load(Ordering::SeqCst), 0);

    host.state(true, 2).await;
    let birth = host.next("/NBIRTH/S7").await;
    assert_eq!(birth.seq, Some(0));
    let bd_seq = long_metric(&birth, "bdSeq");
    assert_eq!(bd_seq, Some(0));
    // The balance is a device of the node: its birth follows the node's, then its data
    // (what changed while the host was offline, as history, or a change since), in
    // sequence.
    let device_birth = host.next("/DBIRTH/S7/BAL").await;
    assert_eq!(device_birth.seq, Some(1));
    assert!(
        device_birth
            .metrics
            .iter()
            .any(|m| m.name.as_deref() == Some("BAL.weight")),
        "{device_birth:?}"
    );
    let data = host.next("/DDATA/S7/BAL").await;
    assert_eq!(data.seq, Some(2));

    let rebirth = sparkplug::Payload {
        timestamp: Some(3),
        metrics: vec![sparkplug::Metric {
            name: Some(sparkplug::edge::REBIRTH.into()),
            datatype: Some(sparkplug::DataType::Boolean.code()),
            value: Some(sparkplug::MetricValue::BooleanValue(true)),
            ..sparkplug::Metric::default()
        }],
        ..sparkplug::Payload::default()
    };
    host.client
        .publish(
            "spBv1.0/sorting/NCMD/S7",
            rumqttc::QoS::AtLeastOnce,
            false,
            rebirth.to_bytes(),
        )
        .await
        .unwrap();
    let again = host.next("/NBIRTH/S7").await;
    assert_eq!(again.seq, Some(0));
    let device_again = host.next("/DBIRTH/S7/BAL").await;
    assert_eq!(device_again.seq, Some(1));
    assert_eq!(device_again.metrics.len(), device_birth.metrics.len());
    assert_eq!(
        long_metric(&again, "bdSeq"),
        bd_seq,
        "same session, same bdSeq"
    );
    assert_eq!(again.metrics.len(), birth.metrics.len());
    assert_eq!(stats.births.load(Ordering::SeqCst), 2);
    drop(publishers);
    runtime.shutdown().await;
}

const BOARD_ST: &str = "PROGRAM Board
VAR
    Horn : BOOL;
    WindowMinutes : INT;
END_VAR
WindowMinutes := WindowMinutes;
END_PROGRAM
";

const BOARD_TOML: &str = r#"[station]
name = "sorting"
time_zone = "UTC"

[[node]]
name = "BOARD"
common_address = 21
sources = ["plc/board.st"]
[node.server]
port_offset = 0
redundancy_groups = [ { name = "hmi", clients = ["127.0.0.2"] }, { name = "dispatch" } ]
[[node.task]]
name = "fast"
interval_ms = 10
programs = ["Board"]
[[node.point]]
name = "Horn"
type = "M_SP_TB_1"
ioa = 102
source = "Board.Horn"
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
[[node.command]]
name = "Horn_From_HMI"
type = "C_SC_NA_1"
ioa = 204
target = "Board.Horn"
from_groups = ["hmi"]
"#;

/// NCMD writes go through the node's command path: carried out and audited with the MQTT
/// host as the actor; refused by range or redundancy group with their reason audited.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn ncmd_writes_are_routed_checked_and_audited_as_dispatch_commands() {
    use station::store::{CommandOutcome, CommandQuery};
    if !testkit::mqtt::peers_available() {
        return;
    }
    let broker = testkit::mqtt::start_broker();
    let mut host = Host::connect(broker.port).await;
    let dir =
        testkit::projects::folder(&[("station.toml", BOARD_TOML), ("plc/board.st", BOARD_ST)]);
    let project = Project::load(dir.path())
        .unwrap_or_else(|errors| panic!("{errors}"))
        .with_port_base(testkit::ports::free_port());
    let runtime = Runtime::start(
        project,
        RuntimeOptions {
            store: StoreChoice::Url("sqlite::memory:".into()),
            ..RuntimeOptions::default()
        },
    )
    .await
    .unwrap();
    let _publishers = mqtt::start(
        &runtime,
        &MqttConfig {
            url: format!("mqtt://127.0.0.1:{}", broker.port),
            ..MqttConfig::default()
        },
    )
    .unwrap();
    let birth = host.next("/NBIRTH/BOARD").await;
    let alias_of = |name: &str| {
        birth
            .metrics
            .iter()
            .find(|m| m.name.as_deref() == Some(name))
            .and_then(|m| m.alias)
            .unwrap_or_else(|| panic!("no {name} in the birth"))
    };
    let window_alias = alias_of("Window_On");
    let ncmd = sparkplug::Payload {
        timestamp: Some(1),
        metrics: vec![
            sparkplug::Metric {
                name: Some("Horn_Set".into()),
                datatype: Some(sparkplug::DataType::Boolean.code()),
                value: Some(sparkplug::MetricValue::BooleanValue(true)),
                ..sparkplug::Metric::default()
            },
            sparkplug::Metric {
                alias: Some(window_alias),
                value: Some(sparkplug::MetricValue::IntValue(2000)),
                ..sparkplug::Metric::default()
            },
            sparkplug::Metric {
                name: Some("Horn_From_HMI".into()),
                value: Some(sparkplug::MetricValue::BooleanValue(true)),
                ..sparkplug::Metric::default()
            },
            sparkplug::Metric {
                name: Some("Horn_Set".into()),
                datatype: Some(sparkplug::DataType::Int32.code()),
                value: Some(sparkplug::MetricValue::IntValue(1)),
                ..sparkplug::Metric::default()
            },
        ],
        ..sparkplug::Payload::default()
    };
    host.client
        .publish(
            "spBv1.0/sorting/NCMD/BOARD",
            rumqttc::QoS::AtLeastOnce,
            false,
            ncmd.to_bytes(),
        )
        .await
        .unwrap();
    let node = Arc::clone(&runtime.node("BOARD").unwrap().points);
    let store = runtime.store().unwrap();
    let deadline = std::time::Instant::now() + Duration::from_secs(30);
    let commands = loop {
        let commands = store
            .query_commands(&CommandQuery::default())
            .await
            .unwrap()
            .items;
        let horn_on = node.point("Horn").unwrap().value == PointValue::Bool(true);
        if commands.len() >= 4 && horn_on {
            break commands;
        }
        assert!(
            std::time::Instant::now() < deadline,
            "audit {commands:?}, horn on: {horn_on}"
        );
        tokio::time::sleep(Duration::from_millis(50)).await;
    };
    let record = |point: &str| {
        commands
            .iter()
            .find(|c| c.point == point)
            .unwrap_or_else(|| panic!("no audit of {point}: {commands:?}"))
    };
    let horn = commands
        .iter()
        .find(|c| c.point == "Horn_Set" && c.outcome == CommandOutcome::Executed)
        .unwrap_or_else(|| panic!("Horn_Set not executed: {commands:?}"));
    let wrong_type = commands
        .iter()
        .find(|c| c.point == "Horn_Set" && c.outcome == CommandOutcome::Refused)
        .unwrap_or_else(|| panic!("Horn_Set as Int32 not refused: {commands:?}"));
    assert!(
        wrong_type.detail.contains("datatype"),
        "{}",
        wrong_type.detail
    );
    assert!(wrong_type.actor.name().starts_with("MQTT host"));
    assert!(
        horn.actor.name().starts_with("MQTT host"),
        "{:?}",
        horn.actor
    );
    assert_eq!(horn.value, PointValue::Bool(true));
    let window = record("Window_On");
    assert_eq!(window.outcome, CommandOutcome::Refused);
    assert!(
        window.detail.contains("outside the range"),
        "{}",
        window.detail
    );
    let hmi_only = record("Horn_From_HMI");
    assert_eq!(hmi_only.outcome, CommandOutcome::Refused);
    assert!(
        hmi_only.detail.contains("accepted only from hmi") && hmi_only.detail.contains("dispatch"),
        "{}",
        hmi_only.detail
    );
    runtime.shutdown().await;
}
