//! Storage policy: which value changes of a point are worth a row. A measurement that
//! jitters in its last digit, or a counter that changes every half second, must not fill
//! the history with rows nobody reads (a day of a 0.5 s counter is 172,800 rows).
//!
//! Per point (or for every point by default) a [`PointPolicy`] sets:
//!
//! - a **deadband**, absolute ([`Deadband::Absolute`]: the value must move by more than
//!   this from the last stored value) or percent ([`Deadband::Percent`]: by more than this
//!   share of the last stored value's magnitude);
//! - a **storage rate limit** ([`PointPolicy::min_interval`]): at most one stored value per
//!   interval of event time; a change within it is left out (the next change after it is
//!   stored).
//!
//! Both apply to numeric values only (integers, floats). Always stored, whatever the
//! policy: the first value of a point, every change of quality (a value turning invalid or
//! valid again is an event of its own), every value of a binary, double-point, bit-string
//! or text point (a breaker's state change is never thinned out), and every event that is
//! not a spontaneous or cyclic change (interrogation answers, returns, commands' feedback).
//! What was left out is counted ([`crate::Recorder::suppressed`]).
//!
//! The policy is applied by the [`crate::Recorder`] before it writes
//! ([`crate::Recorder::spawn_with_policy`]); the store itself stores what it is given.

use std::collections::HashMap;
use std::time::Duration;

use chrono::{DateTime, Utc};

use crate::model::quality_to_bits;
use crate::{EventCause, EventRecord, PointValue};

/// How far a numeric value must move from the last stored one to be stored again.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Deadband {
    /// By more than this amount (in the point's units).
    Absolute(f64),
    /// By more than this percentage of the last stored value's magnitude (a last value of
    /// 0 stores any change).
    Percent(f64),
}

impl Deadband {
    /// Whether `value` lies within the band around `last` (and is left out).
    fn holds(self, last: f64, value: f64) -> bool {
        let moved = (value - last).abs();
        match self {
            Deadband::Absolute(band) => moved <= band,
            Deadband::Percent(percent) => moved <= last.abs() * percent / 100.0,
        }
    }
}

/// The storage policy of one point (or the default of all).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PointPolicy {
    /// The deadband; `None`: every change is stored.
    pub deadband: Option<Deadband>,
    /// At most one stored value per this interval of event time; `None`: no limit.
    pub min_interval: Option<Duration>,
}

impl PointPolicy {
    /// A policy storing every change.
    pub fn every_change() -> PointPolicy {
        PointPolicy::default()
    }

    /// The policy with a deadband.
    pub fn with_deadband(mut self, deadband: Deadband) -> PointPolicy {
        self.deadband = Some(deadband);
        self
    }

    /// The policy with a storage rate limit of one value per `interval`.
    pub fn with_min_interval(mut self, interval: Duration) -> PointPolicy {
        self.min_interval = Some(interval);
        self
    }
}

/// What was last stored of a point.
#[derive(Debug, Clone, Copy)]
struct Stored {
    value: Option<f64>,
    quality: u8,
    at: DateTime<Utc>,
}

/// The storage policy of a station: a default and per-point exceptions (by point name),
/// and the memory of what was last stored of each point (by node and point name).
#[derive(Debug, Clone, Default)]
pub struct StoragePolicy {
    default: PointPolicy,
    points: HashMap<String, PointPolicy>,
    last: HashMap<String, HashMap<String, Stored>>,
}

impl StoragePolicy {
    /// A policy applying `default` to every point without one of its own.
    pub fn new(default: PointPolicy) -> StoragePolicy {
        StoragePolicy {
            default,
            ..StoragePolicy::default()
        }
    }

    /// The policy with `policy` for the point named `point`.
    pub fn with_point(mut self, point: impl Into<String>, policy: PointPolicy) -> StoragePolicy {
        self.points.insert(point.into(), policy);
        self
    }

    /// Whether every change is stored (no deadband nor rate limit anywhere).
    pub fn is_every_change(&self) -> bool {
        self.default == PointPolicy::default()
            && self.points.values().all(|p| *p == PointPolicy::default())
    }

    /// The policy of `point`.
    pub fn of(&self, point: &str) -> PointPolicy {
        self.points.get(point).copied().unwrap_or(self.default)
    }

    /// Whether `event` is to be stored; remembers it when it is.
    pub fn admit(&mut self, event: &EventRecord) -> bool {
        let value = numeric(&event.value);
        let quality = quality_to_bits(event.quality);
        let at = event.event_time();
        let policy = self.of(&event.point);
        let node = match self.last.get_mut(&event.node) {
            Some(node) => node,
            None => self.last.entry(event.node.clone()).or_default(),
        };
        let keep = match (node.get(&event.point), value) {
            (Some(last), Some(value)) if last.quality == quality && thinned(event.cause) => {
                let within_band = match (policy.deadband, last.value) {
                    (Some(band), Some(last)) => band.holds(last, value),
                    _ => false,
                };
                let too_soon = policy.min_interval.is_some_and(|interval| {
                    (at - last.at).to_std().is_ok_and(|since| since < interval)
                });
                !within_band && !too_soon
            }
            _ => true,
        };
        if keep {
            let stored = Stored { value, quality, at };
            match node.get_mut(&event.point) {
                Some(last) => *last = stored,
                None => {
                    node.insert(event.point.clone(), stored);
                }
            }
        }
        keep
    }
}

/// The value as a number, for integers and floats (NaN counts as no number).
fn numeric(value: &PointValue) -> Option<f64> {
    match value {
        PointValue::Int(i) => Some(*i as f64),
        PointValue::Float(f) if !f.is_nan() => Some(*f),
        _ => None,
    }
}

/// Whether events of this cause may be thinned out: changes, not answers.
fn thinned(cause: EventCause) -> bool {
    matches!(cause, EventCause::Spontaneous | EventCause::Cyclic)
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use chrono::TimeZone;
    use points::Quality;

    fn at(ms: i64) -> DateTime<Utc> {
        Utc.with_ymd_and_hms(2026, 3, 1, 0, 0, 0).unwrap() + chrono::Duration::milliseconds(ms)
    }

    fn ev(point: &str, value: PointValue, ms: i64) -> EventRecord {
        EventRecord::new("RH2", point, value, at(ms))
    }

    #[test]
    fn absolute_deadband_is_measured_from_the_last_stored_value() {
        let mut p =
            StoragePolicy::new(PointPolicy::every_change().with_deadband(Deadband::Absolute(0.5)));
        let kept: Vec<bool> = [10.0, 10.3, 10.5, 10.6, 9.9, 11.0]
            .iter()
            .enumerate()
            .map(|(i, v)| p.admit(&ev("U", PointValue::Float(*v), i as i64)))
            .collect();
        // 10.3 and 10.5 are within 0.5 of 10.0; 10.6 is not; 9.9 is 0.7 from 10.6.
        assert_eq!(kept, [true, false, false, true, true, true]);
    }

    #[test]
    fn percent_deadband_scales_with_the_value() {
        let mut p = StoragePolicy::new(PointPolicy::default()).with_point(
            "I",
            PointPolicy::default().with_deadband(Deadband::Percent(1.0)),
        );
        assert!(p.admit(&ev("I", PointValue::Int(1000), 0)));
        assert!(!p.admit(&ev("I", PointValue::Int(1010), 1)));
        assert!(p.admit(&ev("I", PointValue::Int(1011), 2)));
        // Another point has the default: every change.
        assert!(p.admit(&ev("J", PointValue::Int(1000), 0)));
        assert!(p.admit(&ev("J", PointValue::Int(1001), 1)));
    }

    #[test]
    fn a_counter_every_half_second_is_stored_once_a_minute() {
        let mut p =
            StoragePolicy::new(PointPolicy::default().with_min_interval(Duration::from_secs(60)));
        let day = 86_400_000 / 500;
        let stored = (0..day)
            .filter(|i| p.admit(&ev("C", PointValue::Int(*i), *i * 500)))
            .count();
        assert_eq!(stored, 1440);
    }

    #[test]
    fn quality_changes_binary_points_and_answers_are_always_stored() {
        let mut p = StoragePolicy::new(
            PointPolicy::default()
                .with_deadband(Deadband::Absolute(100.0))
                .with_min_interval(Duration::from_secs(3600)),
        );
        assert!(p.admit(&ev("U", PointValue::Float(1.0), 0)));
        assert!(!p.admit(&ev("U", PointValue::Float(2.0), 1)));
        let mut invalid = ev("U", PointValue::Float(2.0), 2);
        invalid.quality = Quality {
            invalid: true,
            ..Quality::GOOD
        };
        assert!(p.admit(&invalid));
        assert!(p.admit(&ev("U", PointValue::Float(2.0), 3)), "valid again");
        let mut answer = ev("U", PointValue::Float(2.5), 4);
        answer.cause = EventCause::Interrogated;
        assert!(p.admit(&answer));
        for i in 0..10 {
            assert!(p.admit(&ev("Q", PointValue::Bool(i % 2 == 0), i)));
        }
        // The same point name on another node has its own memory.
        let mut other = ev("U", PointValue::Float(2.0), 5);
        other.node = "RH3".into();
        assert!(p.admit(&other));
        assert!(!StoragePolicy::new(
            PointPolicy::default().with_min_interval(Duration::from_secs(1))
        )
        .is_every_change());
        assert!(StoragePolicy::default().is_every_change());
    }
}
