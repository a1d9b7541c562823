//! The sans-IO edge node: births, data and sequence numbers, the will, rebirth, NCMD
//! writes, devices (DBIRTH, DDATA, DCMD), quality, primary host and buffering; payloads and topics round-trip.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use proptest::prelude::*;
use sparkplug::datatype::{DataType, QualityCode, Value};
use sparkplug::edge::{EdgeConfig, EdgeNode, MetricSpec, Output, Sample, BD_SEQ, REBIRTH};
use sparkplug::payload::{
    Metric, MetricValue, Payload, PropertySet, PropertyValue, PropertyValueKind,
};
use sparkplug::state::HostState;
use sparkplug::topic::{MessageType, Topic};

const NCMD: &str = "spBv1.0/plant/NCMD/rtu1";
const STATE: &str = "spBv1.0/STATE/scada";

fn node(primary_host: Option<&str>) -> EdgeNode {
    EdgeNode::new(
        EdgeConfig {
            group: "plant".into(),
            edge_node: "rtu1".into(),
            primary_host: primary_host.map(str::to_owned),
            buffer_limit: 1000,
        },
        vec![
            MetricSpec {
                name: "breaker".into(),
                datatype: DataType::Boolean,
                writable: false,
                device: None,
                comm_alarm: false,
            },
            MetricSpec {
                name: "voltage".into(),
                datatype: DataType::Float,
                writable: false,
                device: None,
                comm_alarm: false,
            },
            MetricSpec {
                name: "tap".into(),
                datatype: DataType::Int8,
                writable: false,
                device: None,
                comm_alarm: false,
            },
            MetricSpec {
                name: "breaker_cmd".into(),
                datatype: DataType::Boolean,
                writable: true,
                device: None,
                comm_alarm: false,
            },
            MetricSpec {
                name: "setpoint".into(),
                datatype: DataType::Int16,
                writable: true,
                device: None,
                comm_alarm: false,
            },
        ],
    )
    .unwrap()
}

/// Node `rtu1` of group `plant`, no primary host, a buffer of 1,000 changes.
fn plant_node(metrics: Vec<MetricSpec>) -> EdgeNode {
    EdgeNode::new(
        EdgeConfig {
            group: "plant".into(),
            edge_node: "rtu1".into(),
            primary_host: None,
            buffer_limit: 1000,
        },
        metrics,
    )
    .unwrap()
}

fn sample(value: Value, quality: QualityCode, timestamp: u64) -> Sample {
    Sample {
        value,
        quality,
        timestamp,
    }
}

/// The messages published, decoded, with their topics.
fn published(outputs: &[Output]) -> Vec<(String, Payload)> {
    outputs
        .iter()
        .filter_map(|o| match o {
            Output::Publish(p) => {
                Some((p.topic.clone(), Payload::decode_bytes(&p.payload).unwrap()))
            }
            _ => None,
        })
        .collect()
}

fn metric<'a>(payload: &'a Payload, name: &str) -> &'a Metric {
    payload
        .metrics
        .iter()
        .find(|m| m.name.as_deref() == Some(name))
        .unwrap_or_else(|| panic!("no metric {name} in {payload:?}"))
}

fn quality_of(metric: &Metric) -> Option<i32> {
    match metric.properties.as_ref()?.get("Quality")?.value {
        Some(PropertyValueKind::IntValue(code)) => Some(code as i32),
        _ => None,
    }
}

fn ncmd(metrics: Vec<Metric>) -> Vec<u8> {
    Payload {
        timestamp: Some(1),
        metrics,
        ..Payload::default()
    }
    .to_bytes()
}

fn state(online: bool, timestamp: u64) -> Vec<u8> {
    HostState { online, timestamp }.to_bytes()
}

#[test]
fn the_birth_carries_seq_0_bdseq_rebirth_and_every_metric_with_an_alias() {
    let mut edge = node(None);
    edge.set(1, sample(Value::Float(231.5), QualityCode::Good, 500));
    let births = published(&edge.connected(1000));
    assert_eq!(births.len(), 1);
    let (topic, birth) = &births[0];
    assert_eq!(topic, "spBv1.0/plant/NBIRTH/rtu1");
    assert_eq!(birth.seq, Some(0));
    assert_eq!(birth.timestamp, Some(1000));
    let bd_seq = metric(birth, BD_SEQ);
    assert_eq!(bd_seq.datatype, Some(DataType::Int64.code()));
    assert_eq!(bd_seq.value, Some(MetricValue::LongValue(0)));
    let rebirth = metric(birth, REBIRTH);
    assert_eq!(rebirth.datatype, Some(DataType::Boolean.code()));
    assert_eq!(rebirth.value, Some(MetricValue::BooleanValue(false)));
    let voltage = metric(birth, "voltage");
    assert_eq!(voltage.value, Some(MetricValue::FloatValue(231.5)));
    assert_eq!(voltage.timestamp, Some(500));
    assert_eq!(quality_of(voltage), Some(192));
    // Never updated: null, not a made-up zero.
    assert_eq!(metric(birth, "breaker").is_null, Some(true));
    let mut aliases: Vec<u64> = birth.metrics.iter().map(|m| m.alias.unwrap()).collect();
    aliases.sort_unstable();
    aliases.dedup();
    assert_eq!(aliases.len(), birth.metrics.len(), "aliases unique");
    let writable = metric(birth, "setpoint")
        .properties
        .as_ref()
        .unwrap()
        .get("Writable")
        .cloned();
    assert_eq!(
        writable.and_then(|v| v.value),
        Some(PropertyValueKind::BooleanValue(true))
    );
    assert!(metric(birth, "voltage")
        .properties
        .as_ref()
        .unwrap()
        .get("Writable")
        .is_none());
}

#[test]
fn data_follows_with_seq_modulo_256_timestamps_and_aliases() {
    let mut edge = node(None);
    edge.connected(0);
    let mut expected = 1u64;
    for i in 0..600u64 {
        let out = published(&edge.update(
            2,
            sample(Value::Int((i % 100) as i64 - 50), QualityCode::Good, i),
            10_000 + i,
        ));
        let (topic, data) = &out[0];
        assert_eq!(topic, "spBv1.0/plant/NDATA/rtu1");
        assert_eq!(data.seq, Some(expected), "change {i}");
        assert_eq!(data.timestamp, Some(10_000 + i));
        let metric = &data.metrics[0];
        assert_eq!(metric.alias, edge.alias_of("tap"));
        assert_eq!(metric.timestamp, Some(i));
        assert_eq!(
            DataType::Int8.decode(metric.value.as_ref().unwrap()),
            Some(Value::Int((i % 100) as i64 - 50))
        );
        expected = (expected + 1) % 256;
    }
}

#[test]
fn an_invalid_point_is_bad_and_a_change_of_validity_alone_is_published() {
    let mut edge = node(None);
    edge.connected(0);
    let good = published(&edge.update(0, sample(Value::Bool(true), QualityCode::Good, 1), 1));
    assert_eq!(quality_of(&good[0].1.metrics[0]), Some(192));
    let bad = published(&edge.update(0, sample(Value::Bool(true), QualityCode::Bad, 2), 2));
    assert_eq!(bad.len(), 1, "same value, new validity: published");
    assert_eq!(quality_of(&bad[0].1.metrics[0]), Some(0));
    let stale = published(&edge.update(0, sample(Value::Bool(true), QualityCode::Stale, 3), 3));
    assert_eq!(quality_of(&stale[0].1.metrics[0]), Some(500));
}

#[test]
fn the_will_is_ndeath_with_the_bdseq_of_the_birth_it_closes() {
    let mut edge = node(None);
    for session in 0..300u64 {
        let will = edge.will();
        assert_eq!(will.topic, "spBv1.0/plant/NDEATH/rtu1");
        let death = Payload::decode_bytes(&will.payload).unwrap();
        assert_eq!(death.seq, None);
        let births = published(&edge.connected(session));
        let birth = &births[0].1;
        assert_eq!(metric(&death, BD_SEQ).value, metric(birth, BD_SEQ).value);
        assert_eq!(
            metric(birth, BD_SEQ).value,
            Some(MetricValue::LongValue(session % 256))
        );
        edge.disconnected();
    }
}

#[test]
fn rebirth_keeps_the_bdseq_and_restarts_seq() {
    let mut edge = node(None);
    edge.disconnected(); // never connected: the bdSeq stays
    edge.connected(0);
    edge.disconnected();
    edge.connected(0);
    for i in 0..5 {
        edge.update(
            1,
            sample(Value::Float(f64::from(i)), QualityCode::Good, 1),
            1,
        );
    }
    let rebirth = Metric {
        name: Some(REBIRTH.into()),
        datatype: Some(DataType::Boolean.code()),
        value: Some(MetricValue::BooleanValue(true)),
        ..Metric::default()
    };
    let births = published(&edge.received(NCMD, &ncmd(vec![rebirth]), 7));
    assert_eq!(births.len(), 1);
    assert_eq!(births[0].0, "spBv1.0/plant/NBIRTH/rtu1");
    assert_eq!(births[0].1.seq, Some(0));
    assert_eq!(
        metric(&births[0].1, BD_SEQ).value,
        Some(MetricValue::LongValue(1))
    );
    assert_eq!(
        metric(&births[0].1, "voltage").value,
        Some(MetricValue::FloatValue(4.0))
    );
    let next = published(&edge.update(1, sample(Value::Float(9.0), QualityCode::Good, 8), 8));
    assert_eq!(next[0].1.seq, Some(1));
    // By alias alone, too.
    let by_alias = Metric {
        alias: Some(1),
        value: Some(MetricValue::BooleanValue(true)),
        ..Metric::default()
    };
    assert_eq!(
        published(&edge.received(NCMD, &ncmd(vec![by_alias]), 9))[0]
            .1
            .seq,
        Some(0)
    );
}

#[test]
fn ncmd_writes_a_command_metric_by_name_or_alias_and_refuses_the_rest() {
    let mut edge = node(None);
    edge.connected(0);
    let by_name = Metric {
        name: Some("setpoint".into()),
        datatype: Some(DataType::Int16.code()),
        value: Some(MetricValue::IntValue(-300i32 as u32)),
        ..Metric::default()
    };
    let by_alias = Metric {
        alias: edge.alias_of("breaker_cmd"),
        value: Some(MetricValue::BooleanValue(true)),
        ..Metric::default()
    };
    let wrong_type = Metric {
        name: Some("setpoint".into()),
        datatype: Some(DataType::Float.code()),
        value: Some(MetricValue::FloatValue(1.0)),
        ..Metric::default()
    };
    let read_only = Metric {
        name: Some("voltage".into()),
        value: Some(MetricValue::FloatValue(1.0)),
        ..Metric::default()
    };
    let unknown = Metric {
        alias: Some(999),
        value: Some(MetricValue::BooleanValue(true)),
        ..Metric::default()
    };
    let outputs = edge.received(
        NCMD,
        &ncmd(vec![by_name, by_alias, wrong_type, read_only, unknown]),
        1,
    );
    let writes: Vec<_> = outputs
        .iter()
        .filter_map(|o| match o {
            Output::Write(w) => Some((w.metric.as_str(), w.value.clone())),
            _ => None,
        })
        .collect();
    assert_eq!(
        writes,
        vec![
            ("setpoint", Value::Int(-300)),
            ("breaker_cmd", Value::Bool(true))
        ]
    );
    let refusals: Vec<_> = outputs
        .iter()
        .filter_map(|o| match o {
            Output::Refused(r) => Some((r.metric.as_str(), r.reason.as_str())),
            _ => None,
        })
        .collect();
    assert_eq!(
        refusals,
        vec![
            ("setpoint", "datatype differs from the birth's"),
            ("voltage", "not writable"),
            ("alias 999", "no metric of this alias"),
        ]
    );
    // Another node's commands, and garbage, are not ours / refused.
    assert!(edge
        .received("spBv1.0/plant/NCMD/rtu2", &[1, 2, 3], 1)
        .is_empty());
    assert!(matches!(
        edge.received(NCMD, &[0xff, 0xff], 1).as_slice(),
        [Output::Refused(_)]
    ));
}

/// A node with devices: NBIRTH with the node's metrics, a DBIRTH per device with its own
/// (aliases unique across the node), DDATA for a device's changes, one seq for all; DCMD
/// writes a device's command, NCMD may not, and a DCMD to another device is refused.
#[test]
fn devices_have_births_data_and_commands_of_their_own_under_one_seq() {
    let spec = |name: &str, datatype, writable, device: Option<&str>| MetricSpec {
        name: name.into(),
        datatype,
        writable,
        device: device.map(str::to_owned),
        comm_alarm: false,
    };
    let mut edge = plant_node(vec![
        spec("breaker", DataType::Boolean, false, None),
        spec("L1.position", DataType::Int32, false, Some("L1")),
        spec("REF1.trip", DataType::Boolean, false, Some("REF1")),
        spec("REF1.open", DataType::Boolean, true, Some("REF1")),
        spec("L1.status", DataType::Int32, false, Some("L1")),
    ]);
    assert_eq!(edge.devices(), ["L1", "REF1"]);
    // A change before the connection waits in the buffer, for the device's DDATA.
    edge.update(1, sample(Value::Int(3), QualityCode::Good, 5), 5);
    let births = published(&edge.connected(10));
    let topics: Vec<&str> = births.iter().map(|(t, _)| t.as_str()).collect();
    assert_eq!(
        topics,
        [
            "spBv1.0/plant/NBIRTH/rtu1",
            "spBv1.0/plant/DBIRTH/rtu1/L1",
            "spBv1.0/plant/DBIRTH/rtu1/REF1",
            "spBv1.0/plant/DDATA/rtu1/L1",
        ]
    );
    let seqs: Vec<Option<u64>> = births.iter().map(|(_, p)| p.seq).collect();
    assert_eq!(seqs, [Some(0), Some(1), Some(2), Some(3)]);
    let names = |payload: &Payload| -> Vec<String> {
        payload
            .metrics
            .iter()
            .filter_map(|m| m.name.clone())
            .collect()
    };
    assert_eq!(names(&births[0].1), [BD_SEQ, REBIRTH, "breaker"]);
    assert_eq!(names(&births[1].1), ["L1.position", "L1.status"]);
    assert_eq!(names(&births[2].1), ["REF1.trip", "REF1.open"]);
    let mut aliases: Vec<u64> = births[..3]
        .iter()
        .flat_map(|(_, p)| p.metrics.iter().filter_map(|m| m.alias))
        .collect();
    aliases.sort_unstable();
    aliases.dedup();
    assert_eq!(
        aliases.len(),
        2 + 5,
        "aliases unique across node and devices"
    );
    assert_eq!(births[3].1.metrics[0].is_historical, Some(true));
    assert_eq!(births[3].1.metrics[0].value, Some(MetricValue::IntValue(3)));
    // Changes: the node's in NDATA, a device's in its DDATA; the seq goes on.
    let data = published(&edge.update(2, sample(Value::Bool(true), QualityCode::Good, 20), 20));
    assert_eq!(data[0].0, "spBv1.0/plant/DDATA/rtu1/REF1");
    assert_eq!(data[0].1.seq, Some(4));
    let data = published(&edge.update(0, sample(Value::Bool(true), QualityCode::Good, 21), 21));
    assert_eq!(data[0].0, "spBv1.0/plant/NDATA/rtu1");
    assert_eq!(data[0].1.seq, Some(5));
    // DCMD to REF1 writes its command; NCMD may not; DCMD to L1 may not either.
    let open = || Metric {
        name: Some("REF1.open".into()),
        value: Some(MetricValue::BooleanValue(true)),
        ..Metric::default()
    };
    let written = edge.received("spBv1.0/plant/DCMD/rtu1/REF1", &ncmd(vec![open()]), 30);
    assert!(
        matches!(written.as_slice(), [Output::Write(w)] if w.metric == "REF1.open" && w.value == Value::Bool(true)),
        "{written:?}"
    );
    for (topic, reason) in [
        (NCMD, "a device's metric: write it with DCMD to its device"),
        ("spBv1.0/plant/DCMD/rtu1/L1", "not a metric of this device"),
        (
            "spBv1.0/plant/DCMD/rtu1/NOPE",
            "this node has no such device",
        ),
    ] {
        let refused = edge.received(topic, &ncmd(vec![open()]), 31);
        assert!(
            matches!(refused.as_slice(), [Output::Refused(r)] if r.reason == reason),
            "{topic}: {refused:?}"
        );
    }
    // A rebirth gives the NBIRTH and every DBIRTH again, seq from 0.
    let rebirth = Metric {
        name: Some(REBIRTH.into()),
        value: Some(MetricValue::BooleanValue(true)),
        ..Metric::default()
    };
    let again = published(&edge.received(NCMD, &ncmd(vec![rebirth]), 40));
    let seqs: Vec<Option<u64>> = again.iter().map(|(_, p)| p.seq).collect();
    assert_eq!(seqs, [Some(0), Some(1), Some(2)]);
    assert_eq!(again[2].0, "spBv1.0/plant/DBIRTH/rtu1/REF1");
    // A device id that cannot stand in a topic is refused.
    assert!(EdgeNode::new(
        EdgeConfig {
            group: "plant".into(),
            edge_node: "rtu1".into(),
            primary_host: None,
            buffer_limit: 1,
        },
        vec![spec("x", DataType::Boolean, false, Some("a/b"))],
    )
    .is_err());
}

/// A device whose communication alarm turns TRUE dies (DDEATH with the next seq), says
/// nothing while dead, and is born again (DBIRTH with its values as they are then) when
/// the alarm clears; a device dead at the node's birth has no DBIRTH and no replay.
#[test]
fn a_device_that_stops_answering_dies_and_is_born_again_when_it_answers() {
    let spec = |name: &str, datatype, device: &str, comm_alarm| MetricSpec {
        name: name.into(),
        datatype,
        writable: false,
        device: Some(device.to_owned()),
        comm_alarm,
    };
    let mut edge = plant_node(vec![
        spec("REF1.current", DataType::Float, "REF1", false),
        spec("REF1.status", DataType::Boolean, "REF1", true),
        spec("REF2.current", DataType::Float, "REF2", false),
        spec("REF2.status", DataType::Boolean, "REF2", true),
    ]);
    let good = |value, at| sample(value, QualityCode::Good, at);
    edge.set(1, good(Value::Bool(false), 1));
    // REF2 stops answering before the connection; its buffered change is not replayed.
    edge.update(3, good(Value::Bool(true), 2), 2);
    edge.update(2, good(Value::Float(7.0), 3), 3);
    let births = published(&edge.connected(10));
    let topics: Vec<&str> = births.iter().map(|(t, _)| t.as_str()).collect();
    assert_eq!(
        topics,
        [
            "spBv1.0/plant/NBIRTH/rtu1",
            "spBv1.0/plant/DBIRTH/rtu1/REF1"
        ]
    );
    // REF1 answers: DDATA; stops: DDEATH, seq going on, no metrics.
    let data = published(&edge.update(0, good(Value::Float(1.5), 20), 20));
    assert_eq!(data[0].0, "spBv1.0/plant/DDATA/rtu1/REF1");
    assert_eq!(data[0].1.seq, Some(2));
    let death = published(&edge.update(1, good(Value::Bool(true), 21), 21));
    assert_eq!(death.len(), 1);
    assert_eq!(death[0].0, "spBv1.0/plant/DDEATH/rtu1/REF1");
    assert_eq!(death[0].1.seq, Some(3));
    assert_eq!(death[0].1.timestamp, Some(21));
    assert!(death[0].1.metrics.is_empty());
    // Dead: its changes go nowhere, but are kept.
    assert!(edge.update(0, good(Value::Float(2.5), 22), 22).is_empty());
    // It answers again: a DBIRTH with the newest values, the alarm FALSE.
    let again = published(&edge.update(1, good(Value::Bool(false), 30), 30));
    assert_eq!(again.len(), 1);
    assert_eq!(again[0].0, "spBv1.0/plant/DBIRTH/rtu1/REF1");
    assert_eq!(again[0].1.seq, Some(4));
    assert_eq!(
        metric(&again[0].1, "REF1.current").value,
        Some(MetricValue::FloatValue(2.5))
    );
    assert_eq!(
        metric(&again[0].1, "REF1.status").value,
        Some(MetricValue::BooleanValue(false))
    );
    // REF2, dead since before the birth, is born when it answers, with its value.
    let born = published(&edge.update(3, good(Value::Bool(false), 40), 40));
    assert_eq!(born[0].0, "spBv1.0/plant/DBIRTH/rtu1/REF2");
    assert_eq!(born[0].1.seq, Some(5));
    assert_eq!(
        metric(&born[0].1, "REF2.current").value,
        Some(MetricValue::FloatValue(7.0))
    );
    // A rebirth leaves a dead device out again.
    edge.update(1, good(Value::Bool(true), 50), 50);
    let rebirth = Metric {
        name: Some(REBIRTH.into()),
        value: Some(MetricValue::BooleanValue(true)),
        ..Metric::default()
    };
    let topics: Vec<String> = published(&edge.received(NCMD, &ncmd(vec![rebirth]), 60))
        .into_iter()
        .map(|(t, _)| t)
        .collect();
    assert_eq!(
        topics,
        [
            "spBv1.0/plant/NBIRTH/rtu1",
            "spBv1.0/plant/DBIRTH/rtu1/REF2"
        ]
    );
}

#[test]
fn with_a_primary_host_nothing_goes_out_until_it_is_online_then_the_buffer_replays_in_order() {
    let mut edge = node(Some("scada"));
    assert!(edge.subscriptions().contains(&STATE.to_owned()));
    assert!(
        edge.connected(0).is_empty(),
        "no birth before the host is online"
    );
    for i in 0..100u64 {
        assert!(edge
            .update(1, sample(Value::Float(i as f64), QualityCode::Good, i), i)
            .is_empty());
    }
    assert!(edge.received(STATE, b"not json", 1).is_empty());
    let out = published(&edge.received(STATE, &state(true, 50), 200));
    assert_eq!(out[0].0, "spBv1.0/plant/NBIRTH/rtu1");
    assert_eq!(
        metric(&out[0].1, "voltage").value,
        Some(MetricValue::FloatValue(99.0))
    );
    let replayed: Vec<(u64, f32, bool)> = out[1..]
        .iter()
        .flat_map(|(_, p)| p.metrics.iter())
        .map(|m| match m.value {
            Some(MetricValue::FloatValue(x)) => {
                (m.timestamp.unwrap(), x, m.is_historical == Some(true))
            }
            _ => panic!(),
        })
        .collect();
    assert_eq!(
        replayed,
        (0..100).map(|i| (i, i as f32, true)).collect::<Vec<_>>()
    );
    let seqs: Vec<u64> = out.iter().map(|(_, p)| p.seq.unwrap()).collect();
    assert_eq!(seqs, (0..seqs.len() as u64).collect::<Vec<_>>());
    // Offline: silent again, buffering; an older retained STATE changes nothing.
    assert!(edge.received(STATE, &state(false, 60), 300).is_empty());
    assert!(edge
        .update(1, sample(Value::Float(-1.0), QualityCode::Good, 301), 301)
        .is_empty());
    assert!(edge.received(STATE, &state(true, 55), 302).is_empty());
    assert_eq!(edge.buffered(), 1);
    let again = published(&edge.received(STATE, &state(true, 70), 303));
    assert_eq!(again.len(), 2);
    assert_eq!(again[0].1.seq, Some(0));
}

#[test]
fn without_a_primary_host_the_node_does_not_wait() {
    let mut edge = node(None);
    assert_eq!(edge.subscriptions().len(), 2, "NCMD and DCMD only");
    assert_eq!(published(&edge.connected(0)).len(), 1);
    assert!(edge.received(STATE, &state(false, 1), 1).is_empty());
    assert_eq!(
        published(&edge.update(0, sample(Value::Bool(true), QualityCode::Good, 1), 1)).len(),
        1
    );
}

#[test]
fn a_full_buffer_drops_the_oldest_and_counts() {
    let mut edge = EdgeNode::new(
        EdgeConfig {
            group: "g".into(),
            edge_node: "n".into(),
            primary_host: None,
            buffer_limit: 3,
        },
        vec![MetricSpec {
            name: "x".into(),
            datatype: DataType::Int32,
            writable: false,
            device: None,
            comm_alarm: false,
        }],
    )
    .unwrap();
    for i in 0..5 {
        edge.update(0, sample(Value::Int(i), QualityCode::Good, i as u64), 0);
    }
    assert_eq!((edge.buffered(), edge.dropped()), (3, 2));
    let out = published(&edge.connected(10));
    let replayed: Vec<u32> = out[1]
        .1
        .metrics
        .iter()
        .map(|m| match m.value {
            Some(MetricValue::IntValue(v)) => v,
            _ => panic!(),
        })
        .collect();
    assert_eq!(replayed, vec![2, 3, 4]);
}

#[test]
fn ids_that_cannot_stand_in_a_topic_and_reserved_names_are_refused() {
    let config = |group: &str| EdgeConfig {
        group: group.into(),
        edge_node: "n".into(),
        primary_host: None,
        buffer_limit: 0,
    };
    assert!(EdgeNode::new(config("a/b"), vec![]).is_err());
    assert!(EdgeNode::new(config("a+"), vec![]).is_err());
    assert!(EdgeNode::new(config(""), vec![]).is_err());
    let reserved = vec![MetricSpec {
        name: BD_SEQ.into(),
        datatype: DataType::Int64,
        writable: false,
        device: None,
        comm_alarm: false,
    }];
    assert!(EdgeNode::new(config("g"), reserved).is_err());
    let twice = vec![
        MetricSpec {
            name: "x".into(),
            datatype: DataType::Int64,
            writable: false,
            device: None,
            comm_alarm: false,
        },
        MetricSpec {
            name: "x".into(),
            datatype: DataType::Int64,
            writable: false,
            device: None,
            comm_alarm: false,
        },
    ];
    assert!(EdgeNode::new(config("g"), twice).is_err());
}

#[test]
fn topics_parse_and_print() {
    for text in [
        "spBv1.0/plant/NBIRTH/rtu1",
        "spBv1.0/plant/DDATA/rtu1/meter",
        "spBv1.0/STATE/scada",
    ] {
        assert_eq!(Topic::parse(text).unwrap().to_string(), text);
    }
    for bad in [
        "spBv1.0/plant/NBIRTH",
        "spBv1.0/plant/NBIRTH/rtu1/dev",
        "spBv1.0/plant/DDATA/rtu1",
        "spAv1.0/plant/NDATA/x",
        "spBv1.0/plant/XDATA/x",
        "spBv1.0/STATE/",
    ] {
        assert!(Topic::parse(bad).is_err(), "{bad}");
    }
}

fn metric_value() -> impl Strategy<Value = Option<MetricValue>> {
    prop_oneof![
        Just(None),
        any::<u32>().prop_map(|v| Some(MetricValue::IntValue(v))),
        any::<u64>().prop_map(|v| Some(MetricValue::LongValue(v))),
        any::<i32>().prop_map(|v| Some(MetricValue::FloatValue(v as f32))),
        any::<i64>().prop_map(|v| Some(MetricValue::DoubleValue(v as f64))),
        any::<bool>().prop_map(|v| Some(MetricValue::BooleanValue(v))),
        ".{0,20}".prop_map(|v| Some(MetricValue::StringValue(v))),
        proptest::collection::vec(any::<u8>(), 0..20)
            .prop_map(|v| Some(MetricValue::BytesValue(v))),
    ]
}

fn any_metric() -> impl Strategy<Value = Metric> {
    (
        proptest::option::of(".{0,12}"),
        proptest::option::of(any::<u64>()),
        proptest::option::of(any::<u64>()),
        proptest::option::of(0u32..30),
        proptest::option::of(any::<bool>()),
        proptest::option::of(any::<i32>()),
        metric_value(),
    )
        .prop_map(
            |(name, alias, timestamp, datatype, is_null, quality, value)| Metric {
                name,
                alias,
                timestamp,
                datatype,
                is_null,
                properties: quality.map(|q| PropertySet {
                    keys: vec!["Quality".into()],
                    values: vec![PropertyValue {
                        r#type: Some(3),
                        is_null: None,
                        value: Some(PropertyValueKind::IntValue(q as u32)),
                    }],
                }),
                value,
                ..Metric::default()
            },
        )
}

proptest! {
    #[test]
    fn payloads_round_trip(
        timestamp in proptest::option::of(any::<u64>()),
        seq in proptest::option::of(0u64..256),
        metrics in proptest::collection::vec(any_metric(), 0..8),
    ) {
        let payload = Payload { timestamp, metrics, seq, ..Payload::default() };
        prop_assert_eq!(Payload::decode_bytes(&payload.to_bytes()).unwrap(), payload);
    }

    #[test]
    fn any_bytes_decode_or_fail_without_panic(bytes in proptest::collection::vec(any::<u8>(), 0..256)) {
        let _ = Payload::decode_bytes(&bytes);
        let mut edge = node(Some("scada"));
        edge.connected(0);
        let _ = edge.received(NCMD, &bytes, 1);
        let _ = edge.received(STATE, &bytes, 1);
    }

    #[test]
    fn any_topic_parses_or_fails_and_parsed_topics_print_back(text in "(spBv1\\.0/)?[a-zA-Z0-9/+#]{0,30}") {
        if let Ok(topic) = Topic::parse(&text) {
            prop_assert_eq!(topic.to_string(), text);
        }
    }

    #[test]
    fn integers_round_trip_through_their_type(value in any::<i64>(), type_index in 0usize..8) {
        let types = [DataType::Int8, DataType::Int16, DataType::Int32, DataType::Int64,
                     DataType::UInt8, DataType::UInt16, DataType::UInt32, DataType::UInt64];
        let (datatype, min, max) = match types[type_index] {
            DataType::Int8 => (DataType::Int8, i64::from(i8::MIN), i64::from(i8::MAX)),
            DataType::Int16 => (DataType::Int16, i64::from(i16::MIN), i64::from(i16::MAX)),
            DataType::Int32 => (DataType::Int32, i64::from(i32::MIN), i64::from(i32::MAX)),
            DataType::UInt8 => (DataType::UInt8, 0, i64::from(u8::MAX)),
            DataType::UInt16 => (DataType::UInt16, 0, i64::from(u16::MAX)),
            DataType::UInt32 => (DataType::UInt32, 0, i64::from(u32::MAX)),
            other => (other, i64::MIN, i64::MAX),
        };
        let value = value.clamp(min, max);
        let encoded = datatype.encode(&Value::Int(value)).unwrap();
        prop_assert_eq!(datatype.decode(&encoded), Some(Value::Int(value)));
    }

    /// Whatever happens (changes, rebirths, losses, host states), each session's messages
    /// are an NBIRTH with seq 0 followed by NDATA counting on modulo 256 without a gap, and
    /// each NBIRTH's bdSeq is the one of the will registered for its connection.
    #[test]
    fn sequence_numbers_never_skip(steps in proptest::collection::vec(0u8..6, 1..400)) {
        let mut edge = node(Some("scada"));
        let mut connected = false;
        let mut expected: Option<u64> = None;
        let mut will_bd_seq = None;
        let mut host_ts = 0;
        for (i, step) in steps.into_iter().enumerate() {
            let now = i as u64;
            let outputs = match step {
                0 | 1 => edge.update(i % 5, sample(Value::Bool(i % 2 == 0), QualityCode::Good, now), now),
                2 => {
                    let rebirth = Metric { name: Some(REBIRTH.into()), value: Some(MetricValue::BooleanValue(true)), ..Metric::default() };
                    edge.received(NCMD, &ncmd(vec![rebirth]), now)
                }
                3 => {
                    if connected { edge.disconnected(); connected = false; expected = None; Vec::new() }
                    else {
                        will_bd_seq = metric(&Payload::decode_bytes(&edge.will().payload).unwrap(), BD_SEQ).value.clone();
                        connected = true;
                        edge.connected(now)
                    }
                }
                4 => { host_ts += 1; edge.received(STATE, &state(true, host_ts), now) }
                _ => { host_ts += 1; expected = None; edge.received(STATE, &state(false, host_ts), now) }
            };
            for (topic, payload) in published(&outputs) {
                prop_assert!(connected, "published while disconnected");
                let seq = payload.seq.unwrap();
                match Topic::parse(&topic).unwrap() {
                    Topic::Node { message: MessageType::NBirth, .. } => {
                        prop_assert_eq!(seq, 0);
                        prop_assert_eq!(&metric(&payload, BD_SEQ).value, &will_bd_seq);
                    }
                    Topic::Node { message: MessageType::NData, .. } => {
                        prop_assert_eq!(Some(seq), expected, "NDATA out of sequence");
                    }
                    other => prop_assert!(false, "unexpected {:?}", other),
                }
                expected = Some((seq + 1) % 256);
            }
        }
    }
}
