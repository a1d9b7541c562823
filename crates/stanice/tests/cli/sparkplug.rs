//! `stanice run PROJECT --mqtt mqtt://HOST:PORT`: the node publishes as a Sparkplug B edge
//! node to a real mosquitto broker, an independent consumer (paho-mqtt, Eclipse Tahu's
//! protobuf) checks births (the node's and its balance device's), sequence and values, and when the process is killed (-9) the
//! broker publishes its will, NDEATH with the birth's bdSeq.

use std::time::Duration;

use testkit::mqtt::{balance_project, peers_available, start_broker, Consumer};
use testkit::process::start_until;

use crate::support::stanice;

#[test]
fn run_with_mqtt_publishes_births_data_and_the_will_on_kill() {
    if !peers_available() {
        return;
    }
    let broker = start_broker();
    let consumer = Consumer::start(broker.port, "sorting", "S7", 10, 120);
    let dir = tempfile::tempdir().unwrap();
    balance_project(dir.path(), "sorting");
    let url = format!("mqtt://127.0.0.1:{}", broker.port);
    let mut command = stanice();
    command
        .arg("run")
        .arg(dir.path())
        .args(["--store", "none", "--mqtt", &url]);
    let mut station = start_until(command, "MQTT     Sparkplug B to");
    consumer.wait_for(|l| l == "DATA 10", Duration::from_secs(90));
    // kill -9: no clean disconnect, the broker sends the will.
    station.0.kill().unwrap();
    let _ = station.0.wait();
    let verdict = consumer.wait_for(|l| l.starts_with('{'), Duration::from_secs(60));
    let verdict: serde_json::Value = serde_json::from_str(&verdict).unwrap();
    assert_eq!(verdict["verdict"], "PASS", "{verdict}");
    assert_eq!(verdict["births"], serde_json::json!([0]));
    assert_eq!(verdict["deaths"], serde_json::json!([0]));
    // The balance is a device of the node: its points come in its DBIRTH and DDATA.
    assert_eq!(verdict["devices"], serde_json::json!(["BAL"]), "{verdict}");
    assert!(
        verdict["values"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|v| v[0] == "BAL.weight" && v[2].is_number())
            .count()
            >= 5,
        "{verdict}"
    );
}
