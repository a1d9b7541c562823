//! The time-line of a run: every change of every signal and state value, as a logic
//! analyser records it, so that a student can scroll back to what went wrong.
//!
//! Stored as changes, not samples: a 10-ms scan over an hour is 360,000 scans, while the
//! slide's sensors change a few thousand times. The oldest changes go first once
//! [`Timeline::CAPACITY`] is reached; the value before the first kept change is kept
//! with it, so the picture of what remains stays right.

use std::collections::VecDeque;
use std::time::Duration;

use serde::Serialize;

/// One change of one channel.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Change {
    /// Simulated time, seconds.
    pub t: f64,
    /// The channel (index into [`Timeline::channels`]).
    pub channel: usize,
    /// Its new value (1/0 for a BOOL).
    pub value: f64,
}

/// What a channel is.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Channel {
    /// The signal's or state value's name.
    pub name: String,
    /// `input` (the PLC reads it), `output` (the PLC drives it) or `state`.
    pub kind: &'static str,
}

/// The recorded changes of a run.
#[derive(Debug, Clone, Default)]
pub struct Timeline {
    channels: Vec<Channel>,
    last: Vec<Option<f64>>,
    changes: VecDeque<Change>,
    /// Sequence number of the first change kept (changes are numbered from 0).
    first: u64,
}

impl Timeline {
    /// Changes kept at most.
    pub const CAPACITY: usize = 200_000;

    /// A time-line of `channels`.
    pub fn new(channels: Vec<Channel>) -> Timeline {
        let last = vec![None; channels.len()];
        Timeline {
            channels,
            last,
            changes: VecDeque::new(),
            first: 0,
        }
    }

    /// The channels.
    pub fn channels(&self) -> &[Channel] {
        &self.channels
    }

    /// Records the values at `time` (in channel order); only changes are kept.
    pub fn record(&mut self, time: Duration, values: &[f64]) {
        let t = time.as_secs_f64();
        for (channel, (value, last)) in values.iter().zip(self.last.iter_mut()).enumerate() {
            if *last != Some(*value) {
                *last = Some(*value);
                self.changes.push_back(Change {
                    t,
                    channel,
                    value: *value,
                });
            }
        }
        while self.changes.len() > Self::CAPACITY {
            self.changes.pop_front();
            self.first += 1;
        }
    }

    /// The number the next change will get: a client asks for changes from the number
    /// it saw last.
    pub fn next_number(&self) -> u64 {
        self.first + self.changes.len() as u64
    }

    /// The changes numbered `from` on (those still kept), and the number after them.
    pub fn since(&self, from: u64) -> (Vec<Change>, u64) {
        let skip = usize::try_from(from.saturating_sub(self.first)).unwrap_or(usize::MAX);
        (
            self.changes.iter().skip(skip).copied().collect(),
            self.next_number(),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_changes_are_kept_and_read_from_a_number() {
        let mut timeline = Timeline::new(vec![
            Channel {
                name: "K1".into(),
                kind: "input",
            },
            Channel {
                name: "EM1".into(),
                kind: "output",
            },
        ]);
        timeline.record(Duration::ZERO, &[1.0, 0.0]);
        timeline.record(Duration::from_millis(10), &[1.0, 0.0]);
        timeline.record(Duration::from_millis(20), &[1.0, 1.0]);
        let (all, next) = timeline.since(0);
        assert_eq!(all.len(), 3);
        assert_eq!(next, 3);
        assert_eq!(
            all[2],
            Change {
                t: 0.02,
                channel: 1,
                value: 1.0
            }
        );
        let (newer, _) = timeline.since(2);
        assert_eq!(newer.len(), 1);
        assert!(timeline.since(3).0.is_empty());
    }

    #[test]
    fn the_oldest_changes_go_first() {
        let mut timeline = Timeline::new(vec![Channel {
            name: "x".into(),
            kind: "state",
        }]);
        for i in 0..(Timeline::CAPACITY + 10) {
            timeline.record(Duration::from_millis(i as u64), &[i as f64]);
        }
        let (kept, next) = timeline.since(0);
        assert_eq!(kept.len(), Timeline::CAPACITY);
        assert_eq!(next, (Timeline::CAPACITY + 10) as u64);
        assert_eq!(kept[0].value, 10.0);
    }
}
