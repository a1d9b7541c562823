//! How the IEC 103 tools show what they receive: PCVDEW6-like lines for people, one JSON
//! object per ASDU for scripts.
//!
//! Measurands II (INF 148) are shown as multiples of the rated value, the way relay
//! testers read them: the fraction times the standard's limit factor of each position
//! (2.4 for IL1-3, P, Q; 1.2 for UL1-3 and f), `OV`/`ER` after a flagged value.
//!
//! JSON fields: `address`, `type`, `cot`, `cot_name`, `ca`, `fun`, `inf`, then per type:
//! `state` and `dpi`, `time` (HH:MM:SS.mmm), `time_invalid`, `summer_time`, `sin`
//! (1, 2); `ret`, `fan` (2); `values` (list of {`fraction`, `rated`, `ov`, `er`}) (3, 9);
//! `col`, `text` (5); `scn` (8); `time` (6, ISO 8601); `raw` (hex) for the rest.

use iec60870::iec103::{dpi_text, type_name, Asdu, Body, Direction, INF_MEASURANDS_II};
use serde_json::{json, Value};

/// The channel names and limit factors of the standard measurand set II.
const MEASURANDS_II: [(&str, f64); 9] = [
    ("Ir", 2.4),
    ("Is", 2.4),
    ("It", 2.4),
    ("Ure", 1.2),
    ("Use", 1.2),
    ("Ute", 1.2),
    ("P", 2.4),
    ("Q", 2.4),
    ("f", 1.2),
];

/// The limit factor of measurand `index` of an ASDU, when the standard fixes it.
fn limit_factor(asdu: &Asdu, index: usize) -> Option<(&'static str, f64)> {
    (asdu.header.type_id == 9 && asdu.header.inf == INF_MEASURANDS_II)
        .then(|| MEASURANDS_II.get(index).copied())
        .flatten()
}

/// One ASDU as a line: `INF CAUSE decoded`.
pub(crate) fn text(asdu: &Asdu) -> String {
    let header = &asdu.header;
    let head = format!(
        "{} {} ASDU {} ({}) FUN {} INF {}",
        header.inf,
        header.cause.mnemonic(),
        header.type_id,
        type_name(header.type_id, Direction::Monitor),
        header.fun,
        header.inf
    );
    match &asdu.body {
        Body::Measurands(values) => {
            let shown: Vec<String> = values
                .iter()
                .enumerate()
                .map(|(index, value)| match limit_factor(asdu, index) {
                    Some((name, factor)) => {
                        let flags = flag_text(value.overflow(), value.error());
                        format!("{name} {:.2}{flags}", value.fraction() * factor)
                    }
                    None => format!("#{} {value}", index + 1),
                })
                .collect();
            format!("{head}: {}", shown.join(", "))
        }
        Body::Identification { col, .. } => format!(
            "{head}: Comp: {col} String: >{}<",
            asdu.identification_text().unwrap_or_default()
        ),
        Body::TimeTagged { dpi, time, sin } => {
            format!("{head}: {} {time} SIN {sin}", dpi_text(*dpi))
        }
        _ => {
            let full = asdu.to_string();
            // The body part of the codec's own line.
            let body = full
                .split_once(&format!("INF {}", header.inf))
                .map(|(_, rest)| rest.trim().to_owned())
                .unwrap_or(full);
            format!("{head}: {body}")
        }
    }
}

fn flag_text(overflow: bool, error: bool) -> String {
    let mut flags = String::new();
    if overflow {
        flags.push_str(" OV");
    }
    if error {
        flags.push_str(" ER");
    }
    flags
}

/// One ASDU as a JSON object.
pub(crate) fn json(address: u16, asdu: &Asdu) -> Value {
    let header = &asdu.header;
    let mut object = json!({
        "address": address,
        "type": header.type_id,
        "cot": header.cause.0,
        "cot_name": header.cause.name(),
        "ca": header.common_address,
        "fun": header.fun,
        "inf": header.inf,
    });
    let extra = match &asdu.body {
        Body::TimeTagged { dpi, time, sin } => json!({
            "dpi": dpi, "state": dpi_text(*dpi), "time": format!("{:02}:{:02}:{:02}.{:03}", time.hour(), time.minute(), time.millisecond() / 1000, time.millisecond() % 1000),
            "time_invalid": time.is_invalid(), "summer_time": time.is_summer_time(), "sin": sin,
        }),
        Body::TimeTaggedRelative {
            dpi,
            ret,
            fan,
            time,
            sin,
        } => json!({
            "dpi": dpi, "state": dpi_text(*dpi), "ret": ret, "fan": fan,
            "time": format!("{:02}:{:02}:{:02}.{:03}", time.hour(), time.minute(), time.millisecond() / 1000, time.millisecond() % 1000),
            "time_invalid": time.is_invalid(), "sin": sin,
        }),
        Body::Measurands(values) => json!({
            "values": values.iter().enumerate().map(|(index, value)| json!({
                "fraction": value.fraction(),
                "rated": limit_factor(asdu, index).map(|(_, factor)| value.fraction() * factor),
                "name": limit_factor(asdu, index).map(|(name, _)| name),
                "ov": value.overflow(),
                "er": value.error(),
            })).collect::<Vec<_>>(),
        }),
        Body::Identification { col, .. } => json!({
            "col": col, "text": asdu.identification_text(),
        }),
        Body::GiTermination { scn } | Body::GiInitiation { scn } => json!({ "scn": scn }),
        Body::TimeSync { time } => json!({
            "time": crate::printed_time::tag_stamp(time),
        }),
        _ => json!({
            "text": asdu.to_string(),
            "raw": asdu.to_bytes().unwrap_or_default().iter().map(|byte| format!("{byte:02X}")).collect::<String>(),
        }),
    };
    if let (Value::Object(object), Value::Object(extra)) = (&mut object, extra) {
        object.extend(extra);
    }
    object
}
