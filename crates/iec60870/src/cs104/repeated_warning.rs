//! A warning that a peer can make repeat many times a second (a station refusing our
//! connections, clients flooding a full server): logged the first time and then at most
//! once per [`RepeatedWarning::INTERVAL`] with the number of repeats in between, so that
//! nobody can fill the log (a 55 MB log in two seconds was seen before this).

use std::time::Duration;

/// Counts the repeats of one warning between two log lines.
#[derive(Debug, Default)]
pub(crate) struct RepeatedWarning {
    last_logged: Option<tokio::time::Instant>,
    repeats: u64,
}

impl RepeatedWarning {
    /// The shortest time between two log lines of the same warning.
    pub(crate) const INTERVAL: Duration = Duration::from_secs(60);

    /// Whether to log now; `Some(repeats since the last log line)` if so.
    pub(crate) fn due(&mut self, now: tokio::time::Instant) -> Option<u64> {
        let due = self
            .last_logged
            .is_none_or(|last| now.duration_since(last) >= Self::INTERVAL);
        if due {
            self.last_logged = Some(now);
            Some(std::mem::take(&mut self.repeats))
        } else {
            self.repeats += 1;
            None
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn logs_once_per_interval_with_the_repeats() {
        let start = tokio::time::Instant::now();
        let mut warning = RepeatedWarning::default();
        assert_eq!(warning.due(start), Some(0));
        for _ in 0..1000 {
            assert_eq!(warning.due(start + Duration::from_secs(1)), None);
        }
        assert_eq!(warning.due(start + RepeatedWarning::INTERVAL), Some(1000));
        assert_eq!(warning.due(start + RepeatedWarning::INTERVAL), None);
    }
}
