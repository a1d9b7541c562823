//! Sparkplug B messages per second one edge node sustains with a mosquitto broker on
//! loopback: NDATA of one metric each, from the node's change channel through the
//! adapter and rumqttc to the broker, and on to a subscriber. Prints the node's publish
//! rate and the rate the subscriber received them at (QoS 0 both ways, as Sparkplug
//! sends data). Needs mosquitto (scripts/install-test-deps.sh); says so when missing.
//!
//! `cargo bench -p sparkplug --bench throughput`

#![allow(missing_docs, clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::path::PathBuf;
use std::process::{Command, Stdio};
use std::sync::atomic::Ordering;
use std::sync::Arc;
use std::time::{Duration, Instant};

use rumqttc::{AsyncClient, Event, MqttOptions, Packet, QoS};
use sparkplug::datatype::{DataType, QualityCode, Value};
use sparkplug::edge::{EdgeConfig, EdgeNode, MetricSpec, Sample};
use sparkplug::mqtt::{spawn_edge, MqttConfig, MqttStats};

const METRICS: usize = 100;
const CHANGES: u64 = 200_000;

fn now_ms() -> u64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_millis() as u64)
}

#[tokio::main(flavor = "multi_thread", worker_threads = 2)]
async fn main() {
    let Some(mosquitto) = ["/usr/sbin/mosquitto", "/usr/bin/mosquitto"]
        .iter()
        .map(PathBuf::from)
        .find(|p| p.exists())
    else {
        println!("SKIPPED: mosquitto missing; run scripts/install-test-deps.sh");
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let port = testkit::ports::free_port();
    let config = dir.path().join("mosquitto.conf");
    std::fs::write(
        &config,
        format!("listener {port} 127.0.0.1\nallow_anonymous true\nmax_queued_messages 0\n"),
    )
    .unwrap();
    let mut broker = Command::new(mosquitto)
        .arg("-c")
        .arg(&config)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    assert!(testkit::ports::listening_within(
        port,
        Duration::from_secs(20)
    ));

    // The subscriber, counting NDATA.
    let mut options = MqttOptions::new("bench-subscriber", "127.0.0.1", port);
    options.set_max_packet_size(1 << 20, 1 << 20);
    let (subscriber, mut events) = AsyncClient::new(options, 64);
    subscriber
        .subscribe("spBv1.0/bench/NDATA/+", QoS::AtMostOnce)
        .await
        .unwrap();
    let (subscribed_tx, subscribed_rx) = tokio::sync::oneshot::channel();
    let received = tokio::spawn(async move {
        let mut subscribed = Some(subscribed_tx);
        let mut count = 0u64;
        let mut last = Instant::now();
        loop {
            let event = tokio::time::timeout(Duration::from_secs(5), events.poll()).await;
            match event {
                Ok(Ok(Event::Incoming(Packet::SubAck(_)))) => {
                    if let Some(s) = subscribed.take() {
                        let _ = s.send(());
                    }
                }
                Ok(Ok(Event::Incoming(Packet::Publish(_)))) => {
                    count += 1;
                    last = Instant::now();
                    if count == CHANGES {
                        return (count, last);
                    }
                }
                Ok(Ok(_)) => {}
                // Quiet for 5 s, or the connection failed: what arrived is the count.
                Ok(Err(_)) | Err(_) => return (count, last),
            }
        }
    });
    subscribed_rx.await.unwrap();

    let specs = (0..METRICS)
        .map(|i| MetricSpec {
            name: format!("m{i}"),
            datatype: DataType::Double,
            writable: false,
            device: None,
            comm_alarm: false,
        })
        .collect();
    let edge = EdgeNode::new(
        EdgeConfig {
            group: "bench".into(),
            edge_node: "node".into(),
            primary_host: None,
            buffer_limit: 0,
        },
        specs,
    )
    .unwrap();
    let stats = Arc::new(MqttStats::default());
    let (changes, changes_rx) = tokio::sync::mpsc::channel(65_536);
    let settings = MqttConfig {
        url: format!("mqtt://127.0.0.1:{port}"),
        ..MqttConfig::default()
    };
    let node = spawn_edge(
        &settings,
        edge,
        "bench-node".into(),
        Arc::clone(&stats),
        changes_rx,
        now_ms,
    )
    .unwrap();
    let deadline = Instant::now() + Duration::from_secs(20);
    while stats.births.load(Ordering::Relaxed) == 0 {
        assert!(Instant::now() < deadline, "no birth");
        tokio::time::sleep(Duration::from_millis(10)).await;
    }

    let start = Instant::now();
    for i in 0..CHANGES {
        let sample = Sample {
            value: Value::Float(i as f64),
            quality: QualityCode::Good,
            timestamp: now_ms(),
        };
        changes
            .send(((i as usize) % METRICS, sample))
            .await
            .unwrap();
    }
    let deadline = Instant::now() + Duration::from_secs(120);
    while stats.published.load(Ordering::Relaxed) < CHANGES + 1 && Instant::now() < deadline {
        tokio::time::sleep(Duration::from_millis(5)).await;
    }
    let published_in = start.elapsed();
    let published = stats.published.load(Ordering::Relaxed) - 1;
    let (count, last) = received.await.unwrap();
    let received_in = last.duration_since(start);
    println!(
        "sparkplug: one edge node, {METRICS} metrics, {CHANGES} changes, broker on loopback (mosquitto)"
    );
    println!(
        "  node published  {published:>7} NDATA in {:>6.2} s = {:>8.0} messages/s",
        published_in.as_secs_f64(),
        published as f64 / published_in.as_secs_f64()
    );
    println!(
        "  subscriber got  {count:>7} NDATA in {:>6.2} s = {:>8.0} messages/s",
        received_in.as_secs_f64(),
        count as f64 / received_in.as_secs_f64()
    );
    node.kill();
    let _ = broker.kill();
    let _ = broker.wait();
}
