//! How the command line prints times: RFC 3339 with the offset of a named zone
//! (`2026-11-26T23:40:00.123+01:00`), in text and JSON alike, so that no printed time is
//! without its zone.
//!
//! A station's times are UTC inside; a person reads them in the station's zone (the
//! project's `time_zone`, or `--time-zone`), and a program reads the offset.

use std::sync::OnceLock;

use chrono::{DateTime, SecondsFormat, Utc};
use chrono_tz::Tz;
use iec60870::time::{Cp56Time2a, TimeZonePolicy};

/// The zone of the running tool: the zone its peer's time tags are read in and its
/// printed times are shown in (`--time-zone`; UTC, as the test servers stamp, unless
/// said). Set once at the start of a command.
static TOOL_ZONE: OnceLock<TimeZonePolicy> = OnceLock::new();

/// Sets the tool's zone (the first call wins).
pub(crate) fn set_tool_zone(zone: TimeZonePolicy) {
    let _ = TOOL_ZONE.set(zone);
}

/// The tool's zone: the one set, else UTC.
pub(crate) fn tool_zone() -> TimeZonePolicy {
    TOOL_ZONE.get().copied().unwrap_or_default()
}

/// An instant as RFC 3339 with milliseconds, in the tool's zone with its offset.
pub(crate) fn stamp(time: DateTime<Utc>) -> String {
    match tool_zone() {
        TimeZonePolicy::Utc => time.to_rfc3339_opts(SecondsFormat::Millis, true),
        TimeZonePolicy::HostLocal => time
            .with_timezone(&chrono::Local)
            .to_rfc3339_opts(SecondsFormat::Millis, true),
        TimeZonePolicy::Zone(zone) => rfc3339(time, zone),
    }
}

/// Now, as [`stamp`] prints it.
pub(crate) fn now_stamp() -> String {
    stamp(Utc::now())
}

/// A time tag read in the tool's zone, printed with its offset; `None` for a tag that
/// names no instant (a day that does not exist).
pub(crate) fn tag_stamp(tag: &Cp56Time2a) -> Option<String> {
    tool_zone().from_cp56(tag).map(|source| stamp(source.time))
}

/// A time in `zone` as RFC 3339 with milliseconds and the zone's offset (`Z` in UTC).
pub(crate) fn rfc3339(time: DateTime<Utc>, zone: Tz) -> String {
    time.with_timezone(&zone)
        .to_rfc3339_opts(SecondsFormat::Millis, true)
}

/// Parses `--time-zone`: an IANA name (`Europe/Prague`) or `UTC`.
pub(crate) fn parse_zone(text: &str) -> Result<Tz, String> {
    text.parse::<Tz>()
        .map_err(|_| format!("{text:?} is no IANA time zone name (examples: Europe/Prague, UTC)"))
}

#[cfg(test)]
mod tests {
    use super::*;
    use chrono::TimeZone as _;

    #[test]
    fn prints_the_offset_of_the_zone() {
        let time = Utc
            .with_ymd_and_hms(2026, 1, 15, 15, 0, 0)
            .single()
            .unwrap_or_default();
        assert_eq!(
            rfc3339(time, chrono_tz::Europe::Prague),
            "2026-01-15T16:00:00.000+01:00"
        );
        assert_eq!(rfc3339(time, chrono_tz::UTC), "2026-01-15T15:00:00.000Z");
        let summer = Utc
            .with_ymd_and_hms(2026, 7, 15, 15, 0, 0)
            .single()
            .unwrap_or_default();
        assert_eq!(
            rfc3339(summer, chrono_tz::Europe::Prague),
            "2026-07-15T17:00:00.000+02:00"
        );
        assert!(parse_zone("Europe/Nowhere").is_err());
        assert_eq!(parse_zone("UTC"), Ok(chrono_tz::UTC));
    }
}
