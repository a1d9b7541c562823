//! Durations on the command line, one convention for every option: a number with its
//! unit (`500ms`, `2s`, `10m`, `1h30m`, read by humantime), or a plain number in the
//! unit the option's help names (milliseconds for the serial lines' reply timeouts and
//! poll periods, where the field's tools count in ms; seconds elsewhere).
//!
//! Before, `--timeout` was milliseconds in `iec101`, `iec103` and `lift` and seconds in
//! `iec104 command`, `--poll-period` milliseconds beside `--counters-period` seconds,
//! with nothing to tell them apart but the help text.

use std::time::Duration;

/// The longest duration any option takes: a day... times 400 (a year of `--duration`).
const LONGEST: Duration = Duration::from_secs(400 * 86_400);

/// A duration whose plain numbers are seconds (`--duration 10`, `--t1 15`).
pub(crate) fn seconds(text: &str) -> Result<Duration, String> {
    parse(text, Duration::from_secs_f64, "s")
}

/// A duration whose plain numbers are milliseconds (`--timeout 500`).
pub(crate) fn millis(text: &str) -> Result<Duration, String> {
    parse(text, |ms| Duration::from_secs_f64(ms / 1000.0), "ms")
}

fn parse(text: &str, plain: fn(f64) -> Duration, unit: &str) -> Result<Duration, String> {
    let text = text.trim();
    let duration = match text.parse::<f64>() {
        Ok(number) if number.is_finite() && number >= 0.0 => {
            let duration = plain(number);
            if duration > LONGEST {
                return Err(format!("{text}{unit} is longer than the 400 days taken"));
            }
            duration
        }
        Ok(_) => return Err(format!("{text:?} is no duration: negative or not finite")),
        Err(_) => humantime::parse_duration(text).map_err(|error| {
            format!("{text:?} is no duration ({error}): write e.g. 500ms, 2s, 10m or 1h30m")
        })?,
    };
    if duration > LONGEST {
        return Err(format!("{text} is longer than the 400 days taken"));
    }
    Ok(duration)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn units_and_plain_numbers() {
        assert_eq!(seconds("500ms"), Ok(Duration::from_millis(500)));
        assert_eq!(seconds("2s"), Ok(Duration::from_secs(2)));
        assert_eq!(seconds("10m"), Ok(Duration::from_secs(600)));
        assert_eq!(seconds("1h30m"), Ok(Duration::from_secs(5400)));
        assert_eq!(seconds("2.5"), Ok(Duration::from_millis(2500)));
        assert_eq!(millis("250"), Ok(Duration::from_millis(250)));
        assert_eq!(millis("2s"), Ok(Duration::from_secs(2)));
        assert!(seconds("-1").is_err());
        assert!(seconds("ten").is_err_and(|e| e.contains("500ms")));
        assert!(seconds("1000d").is_err());
        assert!(seconds("NaN").is_err());
    }
}
