//! Alarms: fault points raised and cleared, with priorities, acknowledgement and shelving.
//!
//! An alarm is raised when its point takes the alarm value with good quality and cleared
//! when it leaves it (an invalid value changes nothing: the last known state stands). A
//! cleared alarm that needs acknowledgement stays listed until acknowledged. Shelving
//! hides an alarm from the active list (and silences it) for a set time; it never stops
//! the station from transmitting, nor the HMI from recording, the fault.

use chrono::{DateTime, Utc};
use serde::Serialize;

use crate::config::AlarmConfig;

/// One alarm's state.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Alarm {
    /// Stable id (the index of its definition).
    pub id: usize,
    /// The point.
    pub point: String,
    /// Text.
    pub text: String,
    /// 1 (highest) ..= 4.
    pub priority: u8,
    /// When it was last raised.
    pub raised: Option<DateTime<Utc>>,
    /// When it was last cleared (after it was raised).
    pub cleared: Option<DateTime<Utc>>,
    /// Whether it was acknowledged since it was raised.
    pub acknowledged: bool,
    /// Hidden until then.
    pub shelved_until: Option<DateTime<Utc>>,
    /// The fault is present.
    pub active: bool,
    /// Whether it needs acknowledgement.
    pub needs_acknowledgement: bool,
}

impl Alarm {
    /// Whether the alarm list shows it: active, or cleared but not yet acknowledged.
    pub fn listed(&self) -> bool {
        self.active || (self.needs_acknowledgement && !self.acknowledged && self.raised.is_some())
    }
}

/// Every configured alarm.
#[derive(Debug, Clone, Default)]
pub struct Alarms {
    alarms: Vec<Alarm>,
    when: Vec<bool>,
}

impl Alarms {
    /// The alarms of the configuration, all quiet.
    pub fn new(config: &[AlarmConfig]) -> Alarms {
        Alarms {
            alarms: config
                .iter()
                .enumerate()
                .map(|(id, c)| Alarm {
                    id,
                    point: c.point.clone(),
                    text: c.text.clone(),
                    priority: c.priority,
                    raised: None,
                    cleared: None,
                    acknowledged: false,
                    shelved_until: None,
                    active: false,
                    needs_acknowledgement: c.acknowledge,
                })
                .collect(),
            when: config.iter().map(|c| c.when).collect(),
        }
    }

    /// A single point changed; returns the alarms whose state changed.
    pub fn point(&mut self, name: &str, on: bool, invalid: bool, now: DateTime<Utc>) -> Vec<Alarm> {
        let mut changed = Vec::new();
        if invalid {
            return changed;
        }
        for (alarm, when) in self.alarms.iter_mut().zip(&self.when) {
            if alarm.point != name {
                continue;
            }
            let active = on == *when;
            if active == alarm.active {
                continue;
            }
            alarm.active = active;
            if active {
                alarm.raised = Some(now);
                alarm.cleared = None;
                alarm.acknowledged = false;
            } else {
                alarm.cleared = Some(now);
            }
            changed.push(alarm.clone());
        }
        changed
    }

    /// Acknowledges an alarm.
    pub fn acknowledge(&mut self, id: usize) -> Option<Alarm> {
        let alarm = self.alarms.get_mut(id)?;
        alarm.acknowledged = true;
        Some(alarm.clone())
    }

    /// Shelves an alarm until `until` (or unshelves it with `None`).
    pub fn shelve(&mut self, id: usize, until: Option<DateTime<Utc>>) -> Option<Alarm> {
        let alarm = self.alarms.get_mut(id)?;
        alarm.shelved_until = until;
        Some(alarm.clone())
    }

    /// The alarms the list shows, highest priority and newest first.
    pub fn listed(&self) -> Vec<Alarm> {
        let mut list: Vec<Alarm> = self.alarms.iter().filter(|a| a.listed()).cloned().collect();
        list.sort_by(|a, b| a.priority.cmp(&b.priority).then(b.raised.cmp(&a.raised)));
        list
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn config() -> Vec<AlarmConfig> {
        vec![
            AlarmConfig {
                point: "FAULT".into(),
                when: true,
                priority: 1,
                text: "fault".into(),
                acknowledge: true,
            },
            AlarmConfig {
                point: "READY".into(),
                when: false,
                priority: 3,
                text: "not ready".into(),
                acknowledge: false,
            },
        ]
    }

    #[test]
    fn raise_clear_acknowledge_and_invalid_values() {
        let now = Utc::now();
        let mut alarms = Alarms::new(&config());
        assert_eq!(alarms.point("FAULT", true, false, now).len(), 1);
        assert_eq!(alarms.point("FAULT", true, false, now).len(), 0);
        // An invalid value does not clear it.
        assert!(alarms.point("FAULT", false, true, now).is_empty());
        assert_eq!(alarms.listed().len(), 1);
        alarms.point("FAULT", false, false, now);
        // Cleared but not acknowledged: still listed.
        assert_eq!(alarms.listed().len(), 1);
        alarms.acknowledge(0);
        assert!(alarms.listed().is_empty());
        // `when = false` and no acknowledgement: listed exactly while active.
        alarms.point("READY", false, false, now);
        assert_eq!(alarms.listed()[0].text, "not ready");
        alarms.point("READY", true, false, now);
        assert!(alarms.listed().is_empty());
    }
}
