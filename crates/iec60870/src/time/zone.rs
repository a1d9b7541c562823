//! Which clock the wall-clock fields of a CP56Time2a are read in: the link's time zone
//! policy, and the instant a time tag stands for.
//!
//! The tag has no zone of its own (see the module above). A station decides once whether
//! its tags are UTC or the local time of a zone with SU marking summer time, and every
//! part of it (the time tags it stamps, the time of a clock synchronisation, the age of a
//! time-tagged command, the events it stores) reads and writes tags through the one
//! [`TimeZonePolicy`] here.

use chrono::{DateTime, LocalResult, NaiveDateTime, Offset as _, TimeZone, Utc};
use chrono_tz::{OffsetComponents, Tz};

use super::Cp56Time2a;

/// The instant a time tag stands for, with the tag's IV bit: the point model's
/// [`points::SourceTime`].
pub use points::SourceTime;

/// The time zone CP56Time2a tags are written and read in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum TimeZonePolicy {
    /// UTC, SU never set (the default: unambiguous across DST).
    #[default]
    Utc,
    /// The local time of the host this runs on, SU set in summer time.
    HostLocal,
    /// The local time of a named zone (e.g. `Europe/Prague`), SU set while daylight-saving
    /// time is in force.
    Zone(Tz),
}

impl TimeZonePolicy {
    /// The CP56Time2a of an instant. Outside 2000..=2099 the tag is
    /// [`Cp56Time2a::default`] (2000-01-01 00:00 with IV set) rather than a lie.
    pub fn to_cp56(self, time: DateTime<Utc>) -> Cp56Time2a {
        let (naive, summer) = match self {
            TimeZonePolicy::Utc => (time.naive_utc(), false),
            TimeZonePolicy::HostLocal => {
                let local = time.with_timezone(&chrono::Local);
                (local.naive_local(), host_summer_time(&local))
            }
            TimeZonePolicy::Zone(tz) => {
                let local = time.with_timezone(&tz);
                let summer = !local.offset().dst_offset().is_zero();
                (local.naive_local(), summer)
            }
        };
        match Cp56Time2a::from_naive(naive) {
            Ok(tag) => tag.with_summer_time(summer),
            Err(_) => Cp56Time2a::default(),
        }
    }

    /// The instant of a CP56Time2a; the tag's own IV is carried into
    /// [`SourceTime::invalid`]. In a zone, an ambiguous local time (the hour repeated when
    /// summer time ends) is resolved by the SU bit; a local time that does not exist (the
    /// hour skipped when it begins) is read with the standard offset and marked invalid.
    /// `None` for a date that does not exist.
    pub fn from_cp56(self, tag: &Cp56Time2a) -> Option<SourceTime> {
        let naive = tag.to_naive().ok()?;
        let (time, invalid) = match self {
            TimeZonePolicy::Utc => (naive.and_utc(), false),
            TimeZonePolicy::HostLocal => resolve_local(
                &chrono::Local,
                naive,
                tag.is_summer_time(),
                host_summer_time,
            )?,
            TimeZonePolicy::Zone(tz) => resolve_local(&tz, naive, tag.is_summer_time(), |t| {
                !t.offset().dst_offset().is_zero()
            })?,
        };
        Some(SourceTime {
            time,
            invalid: invalid || tag.is_invalid(),
        })
    }
}

/// A time zone name that is neither `UTC`, `local` nor in the zone database.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown time zone `{0}` (UTC, local, or a zone name such as Europe/Prague)")]
pub struct UnknownTimeZone(pub String);

impl std::str::FromStr for TimeZonePolicy {
    type Err = UnknownTimeZone;

    /// `UTC`, `local` (the host's zone) or a zone database name (`Europe/Prague`).
    fn from_str(name: &str) -> Result<Self, Self::Err> {
        if name.eq_ignore_ascii_case("utc") {
            return Ok(TimeZonePolicy::Utc);
        }
        if name.eq_ignore_ascii_case("local") {
            return Ok(TimeZonePolicy::HostLocal);
        }
        name.parse::<Tz>()
            .map(TimeZonePolicy::Zone)
            .map_err(|_| UnknownTimeZone(name.to_owned()))
    }
}

/// Reads a local wall-clock time in `zone`; `summer` is the tag's SU bit and `is_summer`
/// tells which half of an ambiguous hour is summer time.
fn resolve_local<Z: TimeZone>(
    zone: &Z,
    naive: NaiveDateTime,
    summer: bool,
    is_summer: impl Fn(&DateTime<Z>) -> bool,
) -> Option<(DateTime<Utc>, bool)> {
    match zone.from_local_datetime(&naive) {
        LocalResult::Single(t) => Some((t.with_timezone(&Utc), false)),
        LocalResult::Ambiguous(a, b) => {
            let pick = if is_summer(&a) == summer { a } else { b };
            Some((pick.with_timezone(&Utc), false))
        }
        LocalResult::None => {
            // Read with the offset in force just before the gap (standard time).
            let before = naive.checked_sub_signed(chrono::TimeDelta::hours(3))?;
            let offset = match zone.from_local_datetime(&before) {
                LocalResult::Single(t) => t.offset().fix(),
                LocalResult::Ambiguous(t, _) => t.offset().fix(),
                LocalResult::None => return None,
            };
            let utc = naive.checked_sub_signed(chrono::TimeDelta::seconds(i64::from(
                offset.local_minus_utc(),
            )))?;
            Some((utc.and_utc(), true))
        }
    }
}

/// Whether a time of the host's zone is in daylight-saving time: its offset is larger
/// than the smaller of the offsets in January and July of its year (the host's zone
/// database gives no DST flag of its own).
fn host_summer_time(local: &DateTime<chrono::Local>) -> bool {
    use chrono::Datelike;
    let offset_at = |month: u32| {
        chrono::Local
            .with_ymd_and_hms(local.year(), month, 1, 12, 0, 0)
            .single()
            .map(|t| t.offset().fix().local_minus_utc())
    };
    match (offset_at(1), offset_at(7)) {
        (Some(january), Some(july)) => local.offset().fix().local_minus_utc() > january.min(july),
        _ => false,
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    fn prague() -> TimeZonePolicy {
        TimeZonePolicy::Zone(chrono_tz::Europe::Prague)
    }

    #[test]
    fn names() {
        assert_eq!("utc".parse(), Ok(TimeZonePolicy::Utc));
        assert_eq!("local".parse(), Ok(TimeZonePolicy::HostLocal));
        assert_eq!("Europe/Prague".parse(), Ok(prague()));
        assert!("Mars/Olympus".parse::<TimeZonePolicy>().is_err());
    }

    #[test]
    fn utc_round_trip() {
        let time = Utc.with_ymd_and_hms(2026, 7, 1, 10, 30, 0).unwrap();
        let tag = TimeZonePolicy::Utc.to_cp56(time);
        assert!(!tag.is_summer_time());
        assert_eq!(TimeZonePolicy::Utc.from_cp56(&tag).unwrap().time, time);
    }

    #[test]
    fn the_repeated_hour_is_told_apart_by_su() {
        // 2026-10-25 02:30 local happens twice in Prague: 00:30 UTC (CEST) and 01:30 UTC.
        let first = Utc.with_ymd_and_hms(2026, 10, 25, 0, 30, 0).unwrap();
        let second = Utc.with_ymd_and_hms(2026, 10, 25, 1, 30, 0).unwrap();
        let (a, b) = (prague().to_cp56(first), prague().to_cp56(second));
        assert_eq!((a.hour(), b.hour()), (2, 2));
        assert!(a.is_summer_time() && !b.is_summer_time());
        assert_eq!(prague().from_cp56(&a).unwrap().time, first);
        assert_eq!(prague().from_cp56(&b).unwrap().time, second);
    }

    #[test]
    fn the_skipped_hour_is_read_invalid() {
        // 2026-03-29 02:30 does not exist in Prague.
        let tag = Cp56Time2a::new(26, 3, 29, 2, 30, 0).unwrap();
        let read = prague().from_cp56(&tag).unwrap();
        assert!(read.invalid);
        assert_eq!(
            read.time,
            Utc.with_ymd_and_hms(2026, 3, 29, 1, 30, 0).unwrap()
        );
    }
}
