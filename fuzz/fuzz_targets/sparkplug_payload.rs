//! Arbitrary bytes as what a broker hands an edge node: a Sparkplug B payload, an NCMD
//! (by name, by alias, rebirth) and a primary host's STATE, and arbitrary text as a
//! topic. Nothing may panic; a payload that decodes encodes to bytes that decode to it
//! again; the node's answers keep NBIRTH at seq 0 and DBIRTH, NDATA and DDATA counting
//! on without a gap.
#![no_main]

use libfuzzer_sys::fuzz_target;
use sparkplug::datatype::{DataType, QualityCode, Value};
use sparkplug::edge::{EdgeConfig, EdgeNode, MetricSpec, Output, Sample};
use sparkplug::payload::Payload;
use sparkplug::topic::Topic;

fuzz_target!(|data: &[u8]| {
    if let Ok(payload) = Payload::decode_bytes(data) {
        let again = Payload::decode_bytes(&payload.to_bytes()).expect("re-encoded payload decodes");
        // NaN floats compare unequal; compare the bytes instead.
        assert_eq!(again.to_bytes(), payload.to_bytes());
    }
    if let Ok(text) = std::str::from_utf8(data) {
        if let Ok(topic) = Topic::parse(text) {
            assert_eq!(topic.to_string(), text);
        }
    }
    let mut edge = EdgeNode::new(
        EdgeConfig {
            group: "g".into(),
            edge_node: "n".into(),
            primary_host: Some("h".into()),
            buffer_limit: 8,
        },
        vec![
            MetricSpec { name: "a".into(), datatype: DataType::Boolean, writable: true, device: None, comm_alarm: false },
            MetricSpec { name: "b".into(), datatype: DataType::Int16, writable: true, device: Some("d".into()), comm_alarm: false },
            MetricSpec { name: "c".into(), datatype: DataType::Float, writable: false, device: Some("d".into()), comm_alarm: false },
            MetricSpec { name: "d.status".into(), datatype: DataType::Boolean, writable: false, device: Some("d".into()), comm_alarm: true },
        ],
    )
    .expect("a valid node");
    edge.connected(0);
    let mut outputs = edge.received("spBv1.0/STATE/h", data, 1);
    outputs.extend(edge.received("spBv1.0/STATE/h", br#"{"online":true,"timestamp":5}"#, 2));
    outputs.extend(edge.received("spBv1.0/g/NCMD/n", data, 3));
    outputs.extend(edge.update(2, Sample { value: Value::Float(1.0), quality: QualityCode::Good, timestamp: 4 }, 4));
    outputs.extend(edge.received("spBv1.0/g/DCMD/n/d", data, 5));
    let mut expected = None;
    for output in outputs {
        if let Output::Publish(publish) = output {
            let payload = Payload::decode_bytes(&publish.payload).expect("our payloads decode");
            let seq = payload.seq.expect("births and data carry seq");
            if publish.topic.contains("/NBIRTH/") {
                // a birth (a rebirth asked for) starts the sequence again
                assert_eq!(seq, 0);
            } else if let Some(expected) = expected {
                assert_eq!(seq, expected);
            }
            expected = Some((seq + 1) % 256);
        }
    }
});
