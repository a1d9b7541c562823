//! Storage rules: which changes of a point are worth a row in the history. A measurement
//! that jitters in its last digit, or a counter that changes every half second, must not
//! fill the history with rows nobody reads (a day of a 0.5 s counter is 172,800 rows).
//! Every change is still sent to every consumer; the rules thin out only what is stored.
//!
//! A point's [`StorageRule`] (part of its [`crate::PointSpec`]) sets:
//!
//! - a **deadband**, absolute ([`Deadband::Absolute`]: the value must move by more than
//!   this from the last stored value) or percent ([`Deadband::Percent`]: by more than this
//!   share of the last stored value's magnitude);
//! - a **storage rate limit** ([`StorageRule::min_interval`]): at most one stored value per
//!   interval of event time (the source's time tag where it is valid, else the time the
//!   station received the change); a change within it is left out and the next change after it is stored.
//!
//! Both apply to numeric values (integers, floats). Always stored, whatever the rule: the
//! first value of a point, every change of quality (a value turning invalid or valid
//! again is an event of its own), every value of a binary, double-point, bit-string or
//! text point (a breaker's state change is never thinned out), and every change that is
//! not spontaneous or cyclic (interrogation answers, return information).
//!
//! [`StorageFilter`] applies the rules: it remembers what was last stored of each point
//! and answers, change by change, whether this one is stored. The deadband is measured
//! from the last *stored* value, not the last seen one, so that a slow drift in steps
//! smaller than the band is still stored once it has moved by the band.

use std::collections::HashMap;
use std::time::Duration;

use chrono::{DateTime, Utc};

use crate::{EventCause, PointChange, PointValue, Quality};

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

/// Which changes of a point are stored. The default stores every change.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct StorageRule {
    /// The deadband; `None`: every change is stored.
    pub deadband: Option<Deadband>,
    /// At most one stored value per this interval of event time; `None`: no limit.
    pub min_interval: Option<Duration>,
}

impl StorageRule {
    /// A rule storing every change.
    pub fn every_change() -> StorageRule {
        StorageRule::default()
    }

    /// The rule with a deadband.
    pub fn with_deadband(mut self, deadband: Deadband) -> StorageRule {
        self.deadband = Some(deadband);
        self
    }

    /// The rule with a storage rate limit of one value per `interval`.
    pub fn with_min_interval(mut self, interval: Duration) -> StorageRule {
        self.min_interval = Some(interval);
        self
    }

    /// This rule's settings, each taken from `default` where this rule has none (a point's
    /// own rule over the station's default).
    pub fn or(self, default: StorageRule) -> StorageRule {
        StorageRule {
            deadband: self.deadband.or(default.deadband),
            min_interval: self.min_interval.or(default.min_interval),
        }
    }

    /// Whether every change is stored.
    pub fn is_every_change(&self) -> bool {
        *self == StorageRule::default()
    }
}

/// What was last stored of a point.
#[derive(Debug, Clone, Copy)]
struct Stored {
    value: Option<f64>,
    quality: Quality,
    at: DateTime<Utc>,
}

/// The memory of what was last stored of each point (by name), deciding change by change
/// whether a change is stored under its point's rule.
#[derive(Debug, Clone, Default)]
pub struct StorageFilter {
    last: HashMap<String, Stored>,
    left_out: u64,
}

impl StorageFilter {
    /// A filter that has stored nothing yet.
    pub fn new() -> StorageFilter {
        StorageFilter::default()
    }

    /// Whether `change` is stored under `rule`; remembers it when it is.
    pub fn admit(&mut self, rule: StorageRule, change: &PointChange) -> bool {
        let at = match change.source_time {
            Some(source) if !source.invalid => source.time,
            _ => change.received,
        };
        self.admit_value(
            &change.name,
            rule,
            &change.value,
            change.quality,
            at,
            change.cause,
        )
    }

    /// As [`StorageFilter::admit`], for a change given by its parts (`at`: its event time).
    pub fn admit_value(
        &mut self,
        point: &str,
        rule: StorageRule,
        value: &PointValue,
        quality: Quality,
        at: DateTime<Utc>,
        cause: EventCause,
    ) -> bool {
        let value = numeric(value);
        let keep = match (self.last.get(point), value) {
            (Some(last), Some(value)) if last.quality == quality && thinned(cause) => {
                let within_band = match (rule.deadband, last.value) {
                    (Some(band), Some(last)) => band.holds(last, value),
                    _ => false,
                };
                let too_soon = rule.min_interval.is_some_and(|interval| {
                    (at - last.at).to_std().is_ok_and(|since| since < interval)
                });
                !within_band && !too_soon
            }
            _ => true,
        };
        if keep {
            let stored = Stored { value, quality, at };
            match self.last.get_mut(point) {
                Some(last) => *last = stored,
                None => {
                    self.last.insert(point.to_owned(), stored);
                }
            }
        } else {
            self.left_out += 1;
        }
        keep
    }

    /// How many changes the rules left out so far.
    pub fn left_out(&self) -> u64 {
        self.left_out
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

/// Whether changes of this cause may be thinned out: changes, not answers.
fn thinned(cause: EventCause) -> bool {
    matches!(cause, EventCause::Spontaneous | EventCause::Cyclic)
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use chrono::TimeZone;
    use proptest::prelude::*;

    fn at(ms: i64) -> DateTime<Utc> {
        Utc.with_ymd_and_hms(2026, 3, 1, 0, 0, 0).unwrap() + chrono::Duration::milliseconds(ms)
    }

    fn admit(
        filter: &mut StorageFilter,
        rule: StorageRule,
        point: &str,
        v: PointValue,
        ms: i64,
    ) -> bool {
        filter.admit_value(
            point,
            rule,
            &v,
            Quality::GOOD,
            at(ms),
            EventCause::Spontaneous,
        )
    }

    #[test]
    fn absolute_deadband_is_measured_from_the_last_stored_value() {
        let rule = StorageRule::every_change().with_deadband(Deadband::Absolute(0.5));
        let mut filter = StorageFilter::new();
        let kept: Vec<bool> = [10.0, 10.3, 10.5, 10.6, 9.9, 11.0]
            .iter()
            .enumerate()
            .map(|(i, v)| admit(&mut filter, rule, "U", PointValue::Float(*v), i as i64))
            .collect();
        // 10.3 and 10.5 are within 0.5 of 10.0; 10.6 is not; 9.9 is 0.7 from 10.6.
        assert_eq!(kept, [true, false, false, true, true, true]);
        assert_eq!(filter.left_out(), 2);
    }

    #[test]
    fn percent_deadband_scales_with_the_value() {
        let rule = StorageRule::default().with_deadband(Deadband::Percent(1.0));
        let mut filter = StorageFilter::new();
        assert!(admit(&mut filter, rule, "I", PointValue::Int(1000), 0));
        assert!(!admit(&mut filter, rule, "I", PointValue::Int(1010), 1));
        assert!(admit(&mut filter, rule, "I", PointValue::Int(1011), 2));
        // Another point with the default rule: every change.
        let every = StorageRule::default();
        assert!(admit(&mut filter, every, "J", PointValue::Int(1000), 0));
        assert!(admit(&mut filter, every, "J", PointValue::Int(1001), 1));
    }

    #[test]
    fn a_counter_every_half_second_is_stored_once_a_minute() {
        let rule = StorageRule::default().with_min_interval(Duration::from_secs(60));
        let mut filter = StorageFilter::new();
        let day = 86_400_000 / 500;
        let stored = (0..day)
            .filter(|i| admit(&mut filter, rule, "C", PointValue::Int(*i), *i * 500))
            .count();
        assert_eq!(stored, 1440);
    }

    #[test]
    fn quality_changes_binary_points_and_answers_are_always_stored() {
        let rule = StorageRule::default()
            .with_deadband(Deadband::Absolute(100.0))
            .with_min_interval(Duration::from_secs(3600));
        let mut filter = StorageFilter::new();
        assert!(admit(&mut filter, rule, "U", PointValue::Float(1.0), 0));
        assert!(!admit(&mut filter, rule, "U", PointValue::Float(2.0), 1));
        let invalid = Quality {
            invalid: true,
            ..Quality::GOOD
        };
        let float = PointValue::Float(2.0);
        assert!(filter.admit_value("U", rule, &float, invalid, at(2), EventCause::Spontaneous));
        assert!(
            admit(&mut filter, rule, "U", float.clone(), 3),
            "valid again"
        );
        let answer = PointValue::Float(2.5);
        assert!(filter.admit_value(
            "U",
            rule,
            &answer,
            Quality::GOOD,
            at(4),
            EventCause::Interrogated
        ));
        for i in 0..10 {
            assert!(admit(
                &mut filter,
                rule,
                "Q",
                PointValue::Bool(i % 2 == 0),
                i
            ));
        }
    }

    #[test]
    fn a_points_own_settings_win_over_the_default() {
        let default = StorageRule::default()
            .with_deadband(Deadband::Percent(1.0))
            .with_min_interval(Duration::from_secs(1));
        let own = StorageRule::default().with_deadband(Deadband::Absolute(0.1));
        assert_eq!(
            own.or(default),
            StorageRule {
                deadband: Some(Deadband::Absolute(0.1)),
                min_interval: Some(Duration::from_secs(1)),
            }
        );
        assert!(StorageRule::default()
            .or(StorageRule::default())
            .is_every_change());
    }

    proptest! {
        /// Under an absolute deadband, every stored value is more than the band from the
        /// one stored before it, and every left-out value lies within the band of the last
        /// stored one: nothing that moved by the band is lost.
        #[test]
        fn stored_values_are_a_band_apart_and_nothing_beyond_it_is_lost(
            values in proptest::collection::vec(-1000.0f64..1000.0, 1..200),
            band in 0.0f64..50.0,
        ) {
            let rule = StorageRule::default().with_deadband(Deadband::Absolute(band));
            let mut filter = StorageFilter::new();
            let mut last_stored: Option<f64> = None;
            for (i, v) in values.iter().enumerate() {
                let kept = admit(&mut filter, rule, "P", PointValue::Float(*v), i as i64);
                match last_stored {
                    None => prop_assert!(kept),
                    Some(last) => prop_assert_eq!(kept, (v - last).abs() > band),
                }
                if kept {
                    last_stored = Some(*v);
                }
            }
        }

        /// Under a rate limit, stored values are at least the interval apart, and a value
        /// that came at least the interval after the last stored one is stored.
        #[test]
        fn stored_values_are_an_interval_apart(
            gaps in proptest::collection::vec(0i64..5_000, 1..200),
            interval_ms in 1u64..10_000,
        ) {
            let rule = StorageRule::default().with_min_interval(Duration::from_millis(interval_ms));
            let mut filter = StorageFilter::new();
            let mut now = 0;
            let mut last_stored: Option<i64> = None;
            for (i, gap) in gaps.iter().enumerate() {
                now += gap;
                let kept = admit(&mut filter, rule, "C", PointValue::Int(i as i64), now);
                match last_stored {
                    None => prop_assert!(kept),
                    Some(last) => prop_assert_eq!(kept, now - last >= interval_ms as i64),
                }
                if kept {
                    last_stored = Some(now);
                }
            }
        }
    }
}
