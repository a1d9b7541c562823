//! The messages of the live WebSocket `/api/live`: one enum, [`LiveMessage`], for every
//! message the server sends. `web/app.js` (`HMI.receive`) is the browser's side of it.
//!
//! ```text
//!  link::Station --(point, link, alarm, command)--> broadcast --> web::live --> browser
//!  web::live, on connecting and when a browser lags --(snapshot)--------------> browser
//! ```
//!
//! Each message is one JSON object (one WebSocket text frame) whose `type` names it. The
//! browser sends nothing that matters (anything it sends is read and dropped).

use chrono::{DateTime, Utc};
use serde::Serialize;
use serde_json::Value;

use crate::alarms::Alarm;
use crate::link::{ControlOutcome, PointView, Station};

/// The station link as the browsers see it.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct LinkState {
    /// Data transfer with the station is started (STARTDT confirmed).
    pub up: bool,
    /// The station's address(es), comma separated: main first, then alternates.
    pub address: String,
}

impl LinkState {
    /// The link of `station` now.
    pub fn of(station: &Station) -> LinkState {
        LinkState {
            up: station.is_up(),
            address: station.addresses().join(","),
        }
    }
}

/// One point in a `point` message: a [`PointView`] whose IEC type travels as `iec_type`,
/// since `type` names the message.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PointUpdate {
    /// Name.
    pub name: String,
    /// Address.
    pub ioa: u32,
    /// IEC type mnemonic (`M_SP_TB_1`, ...).
    pub iec_type: String,
    /// Description.
    pub description: String,
    /// bool (single), 0..=3 (double), number, or null before the first value.
    pub value: Value,
    /// Invalid (IV, or the link is down).
    pub invalid: bool,
    /// Quality flags set.
    pub quality: Vec<&'static str>,
    /// Source time.
    pub time: Option<DateTime<Utc>>,
}

impl From<PointView> for PointUpdate {
    fn from(point: PointView) -> PointUpdate {
        PointUpdate {
            name: point.name,
            ioa: point.ioa,
            iec_type: point.type_name,
            description: point.description,
            value: point.value,
            invalid: point.invalid,
            quality: point.quality,
            time: point.time,
        }
    }
}

/// A message of the live WebSocket, server to browser. The wire format is JSON with the
/// variant's name, in lower case, in `type`; the fields are the variant's.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "type", rename_all = "lowercase")]
pub enum LiveMessage {
    /// Everything at once: the first message on every socket, and again whenever the
    /// browser fell behind the updates (its copy is then replaced as a whole).
    ///
    /// `{"type": "snapshot", "link": {"up", "address"}, "points": [Point...],
    /// "alarms": [Alarm...]}`, a Point being `{"name", "ioa", "type" (the IEC type), "description",
    /// "value", "invalid", "quality", "time"}` ([`PointView`]) and an Alarm as in
    /// [`Alarm`]; the alarms are those the alarm list shows.
    Snapshot {
        /// The station link.
        link: LinkState,
        /// Every point.
        points: Vec<PointView>,
        /// The listed alarms.
        alarms: Vec<Alarm>,
    },
    /// One point changed (value, quality or time).
    ///
    /// `{"type": "point", "name", "ioa", "iec_type", "description", "value", "invalid",
    /// "quality", "time"}`: the browser keeps the IEC type it had from the snapshot.
    Point(PointUpdate),
    /// The station link came up or went down (when down, `point` messages follow that
    /// turn every point invalid).
    ///
    /// `{"type": "link", "up", "address"}`.
    Link(LinkState),
    /// One alarm changed: raised, cleared, acknowledged, shelved, suppressed, out of
    /// service or back.
    ///
    /// `{"type": "alarm", "id", "point", "text", "priority", "raised", "cleared",
    /// "acknowledged", "shelved_until", "active", "needs_acknowledgement", "shelved",
    /// "oneshot", "shelve_reason", "shelved_by", "suppressed", "out_of_service",
    /// "consequence_of", "system"}` ([`Alarm`]);
    /// the browser replaces its copy of the alarm with that `id`.
    Alarm(Alarm),
    /// A user's control and what it came to (every browser hears of every control).
    ///
    /// `{"type": "command", "user", "command", "value", "outcome"}`, the outcome in
    /// `/api/command`'s words (`executed`, `refused-local`, ...).
    Command {
        /// Who sent it.
        user: String,
        /// The command point.
        command: String,
        /// The value sent.
        value: f64,
        /// What it came to.
        outcome: ControlOutcome,
    },
}

impl LiveMessage {
    /// The snapshot of `station` now.
    pub fn snapshot(station: &Station) -> LiveMessage {
        LiveMessage::Snapshot {
            link: LinkState::of(station),
            points: station.points(),
            alarms: station.alarms(),
        }
    }

    /// The message as the text of one WebSocket frame.
    pub fn to_text(&self) -> String {
        // Nothing in a message can fail to serialize (string keys, finite numbers or null).
        serde_json::to_string(self).unwrap_or_else(|error| {
            tracing::error!(%error, "live message not serialised");
            String::from("{}")
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn point() -> PointView {
        PointView {
            name: "QF1".into(),
            ioa: 281,
            type_name: "M_SP_TB_1".into(),
            description: "feeder breaker".into(),
            value: json!(true),
            invalid: false,
            quality: vec!["SB"],
            time: None,
        }
    }

    fn wire(message: &LiveMessage) -> Value {
        serde_json::from_str(&message.to_text()).unwrap()
    }

    /// The wire format app.js reads, message by message.
    #[test]
    fn wire_format() {
        let link = LinkState {
            up: true,
            address: "127.0.0.1:2404".into(),
        };
        assert_eq!(
            wire(&LiveMessage::Link(link.clone())),
            json!({"type": "link", "up": true, "address": "127.0.0.1:2404"})
        );
        assert_eq!(
            wire(&LiveMessage::Point(point().into())),
            json!({"type": "point", "name": "QF1", "ioa": 281, "iec_type": "M_SP_TB_1",
                   "description": "feeder breaker", "value": true, "invalid": false,
                   "quality": ["SB"], "time": null})
        );
        assert_eq!(
            wire(&LiveMessage::Command {
                user: "operator".into(),
                command: "QF1_Off".into(),
                value: 1.0,
                outcome: ControlOutcome::RefusedLocal,
            }),
            json!({"type": "command", "user": "operator", "command": "QF1_Off", "value": 1.0,
                   "outcome": "refused-local"})
        );
        let alarm = crate::alarms::Alarms::new(&[crate::config::AlarmConfig {
            point: "QF1".into(),
            when: true,
            priority: 2,
            text: "tripped".into(),
            acknowledge: true,
            suppress_when: None,
            link: None,
        }])
        .point("QF1", true, false, Utc::now())
        .remove(0);
        let alarm_json = serde_json::to_value(&alarm).unwrap();
        let mut expected = alarm_json.clone();
        expected["type"] = json!("alarm");
        assert_eq!(wire(&LiveMessage::Alarm(alarm.clone())), expected);
        assert_eq!(
            wire(&LiveMessage::Snapshot {
                link,
                points: vec![point()],
                alarms: vec![alarm],
            }),
            json!({"type": "snapshot",
                   "link": {"up": true, "address": "127.0.0.1:2404"},
                   "points": [{"name": "QF1", "ioa": 281, "type": "M_SP_TB_1",
                               "description": "feeder breaker", "value": true,
                               "invalid": false, "quality": ["SB"], "time": null}],
                   "alarms": [alarm_json]})
        );
    }
}
