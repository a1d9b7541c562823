//! How the test tool shows what it receives: protocol-analyser text for people, one JSON
//! object per information object for scripts.
//!
//! JSON fields: `type` (mnemonic), `type_id`, `cot` (cause name), `cot_value`,
//! `negative`, `test`, `originator`, `ca`, `ioa`, `value` (bool for single points and
//! commands; integer DPI 0..3 for double points; fraction for normalized values, with
//! `raw`; number otherwise), `quality` (list of the set flags: IV, NT, SB, BL, OV),
//! `time` (the time tag as RFC 3339 with the offset of `--time-zone`, the zone the tag
//! is read in; or null), `time_invalid`, `summer_time`, `text` (the element as the
//! analyser prints it), `received` (when it arrived, RFC 3339 in the same zone).

use iec60870::asdu::{Asdu, Element, InformationObject, Quality, TimeTag};
use iec60870::cs104::client::ClientEvent;
use serde_json::{json, Value};

/// When something was received: RFC 3339 with the offset of the tool's zone
/// (`--time-zone`), the zone its time tags are read in too, so that the two agree.
pub(crate) fn receipt_time() -> String {
    crate::printed_time::now_stamp()
}

/// One event as analyser text (several lines for an ASDU with several objects).
pub(crate) fn analyser_text(event: &ClientEvent) -> String {
    let stamp = receipt_time();
    match event {
        ClientEvent::Connected { peer } => format!("{stamp} connected to {peer}"),
        ClientEvent::Started => format!("{stamp} STARTDT confirmed: data transfer started"),
        ClientEvent::Asdu(asdu) => format!("{stamp} {asdu}"),
        ClientEvent::Undecodable { error, raw } => format!(
            "{stamp} undecodable ASDU ({error}): {}",
            raw.iter()
                .map(|byte| format!("{byte:02X}"))
                .collect::<Vec<_>>()
                .join(" ")
        ),
        ClientEvent::Disconnected { reason } => format!("{stamp} disconnected: {reason}"),
    }
}

/// The value and quality of an element, as JSON.
pub(crate) fn element_value(element: &Element) -> (Value, Option<Value>, Option<&Quality>) {
    match element {
        Element::SinglePoint { on, quality } => (json!(on), None, Some(quality)),
        Element::DoublePoint { state, quality } => (json!(state.bits()), None, Some(quality)),
        Element::StepPosition { position, quality } => {
            (json!(position.value()), None, Some(quality))
        }
        Element::Bitstring { bits, quality } => (json!(bits), None, Some(quality)),
        Element::Normalized { raw, quality } => (
            json!(f64::from(Element::normalized_value(*raw))),
            Some(json!(raw)),
            Some(quality),
        ),
        Element::Scaled { value, quality } => (json!(value), None, Some(quality)),
        Element::Float { value, quality } => (json!(value), None, Some(quality)),
        Element::IntegratedTotal(reading) => (json!(reading.value()), None, None),
        Element::PackedSinglePoints {
            status,
            change,
            quality,
        } => (json!(status), Some(json!(change)), Some(quality)),
        Element::SingleCommand { on, .. } => (json!(on), None, None),
        Element::DoubleCommand { state, .. } => (json!(state.bits()), None, None),
        Element::RegulatingStep { state, .. } => (json!(state.bits()), None, None),
        Element::SetpointNormalized { raw, .. } => (
            json!(f64::from(Element::normalized_value(*raw))),
            Some(json!(raw)),
            None,
        ),
        Element::SetpointScaled { value, .. } => (json!(value), None, None),
        Element::SetpointFloat { value, .. } => (json!(value), None, None),
        Element::BitstringCommand { bits } => (json!(bits), None, None),
        Element::Interrogation { qualifier } => (json!(qualifier), None, None),
        other => (json!(other.to_string()), None, None),
    }
}

pub(crate) fn object_json(asdu: &Asdu, object: &InformationObject) -> Value {
    let (value, raw, quality) = element_value(&object.element);
    let mut quality = quality.map(Quality::set_flags).unwrap_or_default();
    if let Element::IntegratedTotal(reading) = &object.element {
        if reading.is_invalid() {
            quality.push("IV");
        }
    }
    let (time, time_invalid, summer_time) = match &object.time {
        Some(TimeTag::Cp56(time)) => (
            crate::printed_time::tag_stamp(time)
                .map(|stamp| json!(stamp))
                .unwrap_or(Value::Null),
            json!(time.is_invalid()),
            json!(time.is_summer_time()),
        ),
        Some(TimeTag::Cp24(time)) => (
            json!(format!(
                "{:02}:{:06.3}",
                time.minute(),
                f64::from(time.millisecond()) / 1000.0
            )),
            json!(time.is_invalid()),
            Value::Null,
        ),
        None => (Value::Null, Value::Null, Value::Null),
    };
    let mut line = json!({
        "type": asdu.type_id.mnemonic(),
        "type_id": asdu.type_id as u8,
        "cot": asdu.cot.cause.name(),
        "cot_value": asdu.cot.cause.value(),
        "negative": asdu.cot.negative,
        "test": asdu.cot.test,
        "originator": asdu.cot.originator,
        "ca": asdu.common_address.get(),
        "ioa": object.ioa.get(),
        "value": value,
        "quality": quality,
        "time": time,
        "time_invalid": time_invalid,
        "summer_time": summer_time,
        "text": object.element.to_string(),
        "received": receipt_time(),
    });
    if let (Some(raw), Some(map)) = (raw, line.as_object_mut()) {
        map.insert("raw".to_owned(), raw);
    }
    line
}

/// One event as JSON lines: one per information object; connection news as
/// `{"event": ...}` objects.
pub(crate) fn json_lines(event: &ClientEvent) -> Vec<String> {
    let lines: Vec<Value> = match event {
        ClientEvent::Asdu(asdu) => asdu
            .objects
            .iter()
            .map(|object| object_json(asdu, object))
            .collect(),
        ClientEvent::Connected { peer } => {
            vec![json!({"event": "connected", "peer": peer.to_string()})]
        }
        ClientEvent::Started => vec![json!({"event": "started"})],
        ClientEvent::Undecodable { error, raw } => vec![json!({
            "event": "undecodable",
            "error": error,
            "raw": raw.iter().map(|byte| format!("{byte:02X}")).collect::<String>(),
        })],
        ClientEvent::Disconnected { reason } => {
            vec![json!({"event": "disconnected", "reason": reason})]
        }
    };
    lines.into_iter().map(|line| line.to_string()).collect()
}
