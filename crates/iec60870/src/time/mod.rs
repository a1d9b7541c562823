//! Time tags: CP56Time2a, CP24Time2a and CP16Time2a (IEC 60870-5-4, used by 101/104).
//!
//! All three start with the milliseconds of the minute (0..59999) as a little-endian
//! `u16`. CP24Time2a adds the minute octet, CP56Time2a adds hour, day, month and year.
//!
//! # Bit layout of CP56Time2a
//!
//! | Octet | Bits | Meaning |
//! |---|---|---|
//! | 1-2 | all | milliseconds of the minute 0..59999, little endian |
//! | 3 | 0-5 | minute 0..59 |
//! | 3 | 6 | RES1, shown as `sub` (substituted) by test tools |
//! | 3 | 7 | IV, the time tag is invalid |
//! | 4 | 0-4 | hour 0..23 |
//! | 4 | 7 | SU, summer time |
//! | 5 | 0-4 | day of month 1..31 |
//! | 5 | 5-7 | day of week 1..7 (Monday = 1), 0 = not used |
//! | 6 | 0-3 | month 1..12 |
//! | 7 | 0-6 | year 0..99 |
//!
//! Other reserved bits are ignored on decode and sent as zero.
//!
//! # Century and time zone
//!
//! The year is two digits. This crate maps it to **2000..2099**, both ways: decoding year
//! 17 gives 2017, and a [`NaiveDateTime`] outside 2000..2099 cannot be encoded. The tag
//! carries wall-clock fields without a zone; whether they are UTC or local time (with SU
//! marking summer time) is a setting of the link, decided by the station, not by this
//! codec. The conversions here are therefore to and from [`NaiveDateTime`]; the link's
//! [`TimeZonePolicy`] turns tags into instants and back.

use std::fmt;

use chrono::{Datelike, NaiveDate, NaiveDateTime, Timelike};

mod zone;

pub use zone::{SourceTime, TimeZonePolicy, UnknownTimeZone};

/// Why a time tag could not be built or decoded.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum TimeError {
    /// A field is outside its range (e.g. minute 60, month 13).
    #[error("time tag field {field} out of range: {value}")]
    OutOfRange {
        /// Name of the field.
        field: &'static str,
        /// The value found.
        value: u32,
    },
    /// The byte slice does not have the tag's length.
    #[error("time tag needs {expected} octets, got {actual}")]
    WrongLength {
        /// Octets the tag needs.
        expected: usize,
        /// Octets given.
        actual: usize,
    },
    /// A calendar date outside 2000..2099 cannot be carried in a two-digit year.
    #[error("year {0} outside 2000..2099, the range of the two-digit year")]
    YearOutOfRange(i32),
    /// The fields are each in range but do not form a date (e.g. 30 February).
    #[error("no such date: {year:04}-{month:02}-{day:02}")]
    NoSuchDate {
        /// Full year.
        year: i32,
        /// Month 1..12.
        month: u8,
        /// Day of month 1..31.
        day: u8,
    },
}

/// Milliseconds in one minute; the upper bound (exclusive) of every millisecond field.
const MS_PER_MINUTE: u16 = 60_000;

fn check(field: &'static str, value: u32, min: u32, max: u32) -> Result<(), TimeError> {
    if value < min || value > max {
        Err(TimeError::OutOfRange { field, value })
    } else {
        Ok(())
    }
}

fn exact<const N: usize>(bytes: &[u8]) -> Result<[u8; N], TimeError> {
    <[u8; N]>::try_from(bytes).map_err(|_| TimeError::WrongLength {
        expected: N,
        actual: bytes.len(),
    })
}

/// Seven-octet time tag: full date and time to the millisecond, plus IV, SU and RES1.
///
/// Fields are private so that every value is in range; build one with [`Cp56Time2a::new`]
/// or [`Cp56Time2a::from_naive`], decode with [`Cp56Time2a::from_bytes`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Cp56Time2a {
    millisecond: u16,
    minute: u8,
    hour: u8,
    day: u8,
    day_of_week: u8,
    month: u8,
    year: u8,
    invalid: bool,
    summer_time: bool,
    substituted: bool,
}

/// 2000-01-01 00:00:00.000 with IV set: a tag that says it is not a valid time, for
/// when no real time can be given (a host clock outside 2000..=2099).
impl Default for Cp56Time2a {
    fn default() -> Self {
        Self {
            millisecond: 0,
            minute: 0,
            hour: 0,
            day: 1,
            day_of_week: 0,
            month: 1,
            year: 0,
            invalid: true,
            summer_time: false,
            substituted: false,
        }
    }
}

impl Cp56Time2a {
    /// Octets on the wire.
    pub const LEN: usize = 7;

    /// Builds a tag from its fields: `year` 0..99 (meaning 2000..2099), `month` 1..12,
    /// `day` 1..31, `hour` 0..23, `minute` 0..59, `millisecond` of the minute 0..59999.
    /// Day of week is 0 (not used) and all flags are clear; see the `with_*` builders.
    ///
    /// The day is checked against 1..31 only, as on the wire; [`Cp56Time2a::to_naive`]
    /// reports dates such as 30 February.
    pub fn new(
        year: u8,
        month: u8,
        day: u8,
        hour: u8,
        minute: u8,
        millisecond: u16,
    ) -> Result<Self, TimeError> {
        check("year", year.into(), 0, 99)?;
        check("month", month.into(), 1, 12)?;
        check("day", day.into(), 1, 31)?;
        check("hour", hour.into(), 0, 23)?;
        check("minute", minute.into(), 0, 59)?;
        check(
            "millisecond",
            millisecond.into(),
            0,
            u32::from(MS_PER_MINUTE) - 1,
        )?;
        Ok(Self {
            millisecond,
            minute,
            hour,
            day,
            day_of_week: 0,
            month,
            year,
            invalid: false,
            summer_time: false,
            substituted: false,
        })
    }

    /// Sets the day of week: 1 = Monday .. 7 = Sunday, 0 = not used.
    pub fn with_day_of_week(mut self, day_of_week: u8) -> Result<Self, TimeError> {
        check("day of week", day_of_week.into(), 0, 7)?;
        self.day_of_week = day_of_week;
        Ok(self)
    }

    /// Sets or clears IV (the time tag is invalid, e.g. the clock was never synchronised).
    #[must_use]
    pub fn with_invalid(mut self, invalid: bool) -> Self {
        self.invalid = invalid;
        self
    }

    /// Sets or clears SU (summer time).
    #[must_use]
    pub fn with_summer_time(mut self, summer_time: bool) -> Self {
        self.summer_time = summer_time;
        self
    }

    /// Sets or clears RES1, which test tools show as `sub` (substituted time).
    #[must_use]
    pub fn with_substituted(mut self, substituted: bool) -> Self {
        self.substituted = substituted;
        self
    }

    /// Milliseconds of the minute, 0..59999 (seconds included).
    pub fn millisecond(&self) -> u16 {
        self.millisecond
    }

    /// Whole seconds of the minute, 0..59.
    pub fn second(&self) -> u8 {
        // 59999 / 1000 = 59 always fits a u8.
        u8::try_from(self.millisecond / 1000).unwrap_or(59)
    }

    /// Minute 0..59.
    pub fn minute(&self) -> u8 {
        self.minute
    }

    /// Hour 0..23.
    pub fn hour(&self) -> u8 {
        self.hour
    }

    /// Day of month 1..31.
    pub fn day(&self) -> u8 {
        self.day
    }

    /// Day of week 1 (Monday) ..7 (Sunday), 0 when not used.
    pub fn day_of_week(&self) -> u8 {
        self.day_of_week
    }

    /// Month 1..12.
    pub fn month(&self) -> u8 {
        self.month
    }

    /// The two-digit year 0..99 as on the wire.
    pub fn year(&self) -> u8 {
        self.year
    }

    /// The full year by the century rule of this module: 2000 + [`Cp56Time2a::year`].
    pub fn full_year(&self) -> u16 {
        2000 + u16::from(self.year)
    }

    /// IV: the time tag is invalid.
    pub fn is_invalid(&self) -> bool {
        self.invalid
    }

    /// SU: summer time.
    pub fn is_summer_time(&self) -> bool {
        self.summer_time
    }

    /// RES1, shown as `sub` (substituted) by test tools.
    pub fn is_substituted(&self) -> bool {
        self.substituted
    }

    /// Decodes the seven octets; any field out of range is an error (day of week 0 is
    /// accepted, it means "not used").
    pub fn from_bytes(bytes: [u8; 7]) -> Result<Self, TimeError> {
        let [ms_lo, ms_hi, minute, hour, day, month, year] = bytes;
        let tag = Self::new(
            year & 0x7F,
            month & 0x0F,
            day & 0x1F,
            hour & 0x1F,
            minute & 0x3F,
            u16::from_le_bytes([ms_lo, ms_hi]),
        )?;
        Ok(tag
            .with_day_of_week(day >> 5)?
            .with_invalid(minute & 0x80 != 0)
            .with_substituted(minute & 0x40 != 0)
            .with_summer_time(hour & 0x80 != 0))
    }

    /// Decodes a slice that must be exactly [`Cp56Time2a::LEN`] octets long.
    pub fn decode(bytes: &[u8]) -> Result<Self, TimeError> {
        Self::from_bytes(exact(bytes)?)
    }

    /// The seven octets on the wire.
    pub fn to_bytes(&self) -> [u8; 7] {
        let [ms_lo, ms_hi] = self.millisecond.to_le_bytes();
        [
            ms_lo,
            ms_hi,
            self.minute | flag(self.substituted, 0x40) | flag(self.invalid, 0x80),
            self.hour | flag(self.summer_time, 0x80),
            self.day | (self.day_of_week << 5),
            self.month,
            self.year,
        ]
    }

    /// Appends the seven octets to `out`.
    pub fn encode(&self, out: &mut Vec<u8>) {
        out.extend_from_slice(&self.to_bytes());
    }

    /// Builds a tag from a calendar date and time in 2000..2099, with the day of week
    /// filled in (Monday = 1) and all flags clear. Sub-millisecond digits are dropped; a
    /// leap second (chrono's second 59 with 1000 ms or more) is held at 59.999 s.
    pub fn from_naive(datetime: NaiveDateTime) -> Result<Self, TimeError> {
        let full_year = datetime.year();
        if !(2000..=2099).contains(&full_year) {
            return Err(TimeError::YearOutOfRange(full_year));
        }
        let millis = datetime.second() * 1000 + datetime.nanosecond() / 1_000_000;
        let millisecond = u16::try_from(millis)
            .unwrap_or(MS_PER_MINUTE - 1)
            .min(MS_PER_MINUTE - 1);
        let narrow = |value: u32| u8::try_from(value).unwrap_or(u8::MAX);
        let tag = Self::new(
            narrow(u32::try_from(full_year - 2000).unwrap_or(u32::MAX)),
            narrow(datetime.month()),
            narrow(datetime.day()),
            narrow(datetime.hour()),
            narrow(datetime.minute()),
            millisecond,
        )?;
        tag.with_day_of_week(narrow(datetime.weekday().number_from_monday()))
    }

    /// The calendar date and time (flags and day of week are not consulted; check
    /// [`Cp56Time2a::is_invalid`] yourself). Fails for a date that does not exist, such
    /// as 2017-02-30.
    pub fn to_naive(&self) -> Result<NaiveDateTime, TimeError> {
        let year = i32::from(self.full_year());
        let no_such_date = TimeError::NoSuchDate {
            year,
            month: self.month,
            day: self.day,
        };
        let date = NaiveDate::from_ymd_opt(year, self.month.into(), self.day.into())
            .ok_or(no_such_date)?;
        let second = u32::from(self.millisecond / 1000);
        let milli = u32::from(self.millisecond % 1000);
        date.and_hms_milli_opt(self.hour.into(), self.minute.into(), second, milli)
            .ok_or(TimeError::OutOfRange {
                field: "millisecond",
                value: self.millisecond.into(),
            })
    }
}

impl TryFrom<NaiveDateTime> for Cp56Time2a {
    type Error = TimeError;

    fn try_from(datetime: NaiveDateTime) -> Result<Self, TimeError> {
        Self::from_naive(datetime)
    }
}

impl TryFrom<[u8; 7]> for Cp56Time2a {
    type Error = TimeError;

    fn try_from(bytes: [u8; 7]) -> Result<Self, TimeError> {
        Self::from_bytes(bytes)
    }
}

fn flag(set: bool, bit: u8) -> u8 {
    if set {
        bit
    } else {
        0
    }
}

/// Writes ` [IV SUB SU]` with only the flags that are set, or nothing when none is.
fn write_time_flags(f: &mut fmt::Formatter<'_>, flags: &[(bool, &'static str)]) -> fmt::Result {
    let mut first = true;
    for (_, name) in flags.iter().filter(|(set, _)| *set) {
        f.write_str(if first { " [" } else { " " })?;
        f.write_str(name)?;
        first = false;
    }
    if !first {
        f.write_str("]")?;
    }
    Ok(())
}

impl fmt::Display for Cp56Time2a {
    /// `2017-04-26 09:59:30.424 [IV]`: the flags IV, SUB and SU are listed only when set.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{:04}-{:02}-{:02} {:02}:{:02}:{:02}.{:03}",
            self.full_year(),
            self.month,
            self.day,
            self.hour,
            self.minute,
            self.millisecond / 1000,
            self.millisecond % 1000
        )?;
        write_time_flags(
            f,
            &[
                (self.invalid, "IV"),
                (self.substituted, "SUB"),
                (self.summer_time, "SU"),
            ],
        )
    }
}

/// Three-octet time tag: milliseconds and minute, plus IV and RES1 (`sub`).
///
/// Used by the 101 types with a short time tag (2, 4, .., 19); IEC 104 does not use them.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Cp24Time2a {
    millisecond: u16,
    minute: u8,
    invalid: bool,
    substituted: bool,
}

impl Cp24Time2a {
    /// Octets on the wire.
    pub const LEN: usize = 3;

    /// Builds a tag: `minute` 0..59, `millisecond` of the minute 0..59999, flags clear.
    pub fn new(minute: u8, millisecond: u16) -> Result<Self, TimeError> {
        check("minute", minute.into(), 0, 59)?;
        check(
            "millisecond",
            millisecond.into(),
            0,
            u32::from(MS_PER_MINUTE) - 1,
        )?;
        Ok(Self {
            millisecond,
            minute,
            invalid: false,
            substituted: false,
        })
    }

    /// Sets or clears IV (the time tag is invalid).
    #[must_use]
    pub fn with_invalid(mut self, invalid: bool) -> Self {
        self.invalid = invalid;
        self
    }

    /// Sets or clears RES1, shown as `sub` by test tools.
    #[must_use]
    pub fn with_substituted(mut self, substituted: bool) -> Self {
        self.substituted = substituted;
        self
    }

    /// Milliseconds of the minute, 0..59999.
    pub fn millisecond(&self) -> u16 {
        self.millisecond
    }

    /// Minute 0..59.
    pub fn minute(&self) -> u8 {
        self.minute
    }

    /// IV: the time tag is invalid.
    pub fn is_invalid(&self) -> bool {
        self.invalid
    }

    /// RES1, shown as `sub` by test tools.
    pub fn is_substituted(&self) -> bool {
        self.substituted
    }

    /// Decodes the three octets; out-of-range fields are an error.
    pub fn from_bytes(bytes: [u8; 3]) -> Result<Self, TimeError> {
        let [ms_lo, ms_hi, minute] = bytes;
        Ok(
            Self::new(minute & 0x3F, u16::from_le_bytes([ms_lo, ms_hi]))?
                .with_invalid(minute & 0x80 != 0)
                .with_substituted(minute & 0x40 != 0),
        )
    }

    /// Decodes a slice that must be exactly [`Cp24Time2a::LEN`] octets long.
    pub fn decode(bytes: &[u8]) -> Result<Self, TimeError> {
        Self::from_bytes(exact(bytes)?)
    }

    /// The three octets on the wire.
    pub fn to_bytes(&self) -> [u8; 3] {
        let [ms_lo, ms_hi] = self.millisecond.to_le_bytes();
        [
            ms_lo,
            ms_hi,
            self.minute | flag(self.substituted, 0x40) | flag(self.invalid, 0x80),
        ]
    }

    /// Appends the three octets to `out`.
    pub fn encode(&self, out: &mut Vec<u8>) {
        out.extend_from_slice(&self.to_bytes());
    }

    /// The minute and milliseconds of a date and time (flags clear); the hour and date
    /// are dropped, which is what the short tag is for.
    pub fn from_naive(datetime: NaiveDateTime) -> Self {
        let millis = datetime.second() * 1000 + datetime.nanosecond() / 1_000_000;
        Self {
            millisecond: u16::try_from(millis)
                .unwrap_or(MS_PER_MINUTE - 1)
                .min(MS_PER_MINUTE - 1),
            minute: u8::try_from(datetime.minute()).unwrap_or(0),
            invalid: false,
            substituted: false,
        }
    }

    /// Completes the short tag with the hour and date of `reference` (typically the time
    /// of reception): of the three candidates in the reference's hour, the previous and the
    /// next, the one closest to `reference` is chosen, so an event from 10:59:58 received
    /// at 11:00:01 resolves to 10:59:58.
    pub fn resolve(&self, reference: NaiveDateTime) -> Option<NaiveDateTime> {
        let hour_start = reference.date().and_hms_opt(reference.hour(), 0, 0)?;
        let offset = chrono::Duration::minutes(self.minute.into())
            + chrono::Duration::milliseconds(self.millisecond.into());
        let in_hour = hour_start.checked_add_signed(offset)?;
        let one_hour = chrono::Duration::hours(1);
        [
            in_hour.checked_sub_signed(one_hour),
            Some(in_hour),
            in_hour.checked_add_signed(one_hour),
        ]
        .into_iter()
        .flatten()
        .min_by_key(|candidate| (*candidate - reference).abs())
    }
}

impl TryFrom<[u8; 3]> for Cp24Time2a {
    type Error = TimeError;

    fn try_from(bytes: [u8; 3]) -> Result<Self, TimeError> {
        Self::from_bytes(bytes)
    }
}

impl fmt::Display for Cp24Time2a {
    /// `59:30.424 [IV]` (minute, seconds and milliseconds), flags only when set.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{:02}:{:02}.{:03}",
            self.minute,
            self.millisecond / 1000,
            self.millisecond % 1000
        )?;
        write_time_flags(f, &[(self.invalid, "IV"), (self.substituted, "SUB")])
    }
}

/// Four-octet time tag of IEC 60870-5-103: milliseconds, minute and hour, plus IV and SU
/// (no date: a receiver completes it with [`Cp32Time2a::resolve`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Cp32Time2a {
    millisecond: u16,
    minute: u8,
    hour: u8,
    invalid: bool,
    summer_time: bool,
}

impl Cp32Time2a {
    /// Octets on the wire.
    pub const LEN: usize = 4;

    /// Builds a tag: `hour` 0..23, `minute` 0..59, `millisecond` of the minute 0..59999.
    pub fn new(hour: u8, minute: u8, millisecond: u16) -> Result<Self, TimeError> {
        check("hour", hour.into(), 0, 23)?;
        check("minute", minute.into(), 0, 59)?;
        check(
            "millisecond",
            millisecond.into(),
            0,
            u32::from(MS_PER_MINUTE) - 1,
        )?;
        Ok(Self {
            millisecond,
            minute,
            hour,
            invalid: false,
            summer_time: false,
        })
    }

    /// Sets or clears IV (the relay's clock is not synchronised, or the tag is invalid).
    #[must_use]
    pub fn with_invalid(mut self, invalid: bool) -> Self {
        self.invalid = invalid;
        self
    }

    /// Sets or clears SU (summer time).
    #[must_use]
    pub fn with_summer_time(mut self, summer_time: bool) -> Self {
        self.summer_time = summer_time;
        self
    }

    /// Milliseconds of the minute, 0..59999.
    pub fn millisecond(&self) -> u16 {
        self.millisecond
    }

    /// Minute 0..59.
    pub fn minute(&self) -> u8 {
        self.minute
    }

    /// Hour 0..23.
    pub fn hour(&self) -> u8 {
        self.hour
    }

    /// IV: the time tag is invalid.
    pub fn is_invalid(&self) -> bool {
        self.invalid
    }

    /// SU: summer time.
    pub fn is_summer_time(&self) -> bool {
        self.summer_time
    }

    /// Decodes the four octets; out-of-range fields are an error, RES1/RES2 are ignored.
    pub fn from_bytes(bytes: [u8; 4]) -> Result<Self, TimeError> {
        let [ms_lo, ms_hi, minute, hour] = bytes;
        Ok(Self::new(
            hour & 0x1F,
            minute & 0x3F,
            u16::from_le_bytes([ms_lo, ms_hi]),
        )?
        .with_invalid(minute & 0x80 != 0)
        .with_summer_time(hour & 0x80 != 0))
    }

    /// Decodes a slice that must be exactly [`Cp32Time2a::LEN`] octets long.
    pub fn decode(bytes: &[u8]) -> Result<Self, TimeError> {
        Self::from_bytes(exact(bytes)?)
    }

    /// The four octets on the wire.
    pub fn to_bytes(&self) -> [u8; 4] {
        let [ms_lo, ms_hi] = self.millisecond.to_le_bytes();
        [
            ms_lo,
            ms_hi,
            self.minute | flag(self.invalid, 0x80),
            self.hour | flag(self.summer_time, 0x80),
        ]
    }

    /// Appends the four octets to `out`.
    pub fn encode(&self, out: &mut Vec<u8>) {
        out.extend_from_slice(&self.to_bytes());
    }

    /// The time of day of a date and time (flags clear); the date is dropped.
    pub fn from_naive(datetime: NaiveDateTime) -> Self {
        let millis = datetime.second() * 1000 + datetime.nanosecond() / 1_000_000;
        Self {
            millisecond: u16::try_from(millis)
                .unwrap_or(MS_PER_MINUTE - 1)
                .min(MS_PER_MINUTE - 1),
            minute: u8::try_from(datetime.minute()).unwrap_or(0),
            hour: u8::try_from(datetime.hour()).unwrap_or(0),
            invalid: false,
            summer_time: false,
        }
    }

    /// Completes the tag with the date of `reference` (typically the time of reception):
    /// of the same time of day on the reference's day, the day before and the day after,
    /// the one closest to `reference`, so a tag of 23:59:58 received at 00:00:01 lands on
    /// the previous day (the midnight roll-over that 103 masters get wrong).
    pub fn resolve(&self, reference: NaiveDateTime) -> Option<NaiveDateTime> {
        let day_start = reference.date().and_hms_opt(0, 0, 0)?;
        let offset = chrono::Duration::hours(self.hour.into())
            + chrono::Duration::minutes(self.minute.into())
            + chrono::Duration::milliseconds(self.millisecond.into());
        let in_day = day_start.checked_add_signed(offset)?;
        let one_day = chrono::Duration::days(1);
        [
            in_day.checked_sub_signed(one_day),
            Some(in_day),
            in_day.checked_add_signed(one_day),
        ]
        .into_iter()
        .flatten()
        .min_by_key(|candidate| (*candidate - reference).abs())
    }
}

impl fmt::Display for Cp32Time2a {
    /// `08:28:32.666 [IV SU]`, flags only when set.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{:02}:{:02}:{:02}.{:03}",
            self.hour,
            self.minute,
            self.millisecond / 1000,
            self.millisecond % 1000
        )?;
        write_time_flags(f, &[(self.invalid, "IV"), (self.summer_time, "SU")])
    }
}

/// Two-octet duration: milliseconds 0..59999 (elapsed, relay duration or operating time of
/// protection equipment, and the delay of C_CD_NA_1).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Default)]
pub struct Cp16Time2a(u16);

impl Cp16Time2a {
    /// Octets on the wire.
    pub const LEN: usize = 2;

    /// Builds a duration of `millisecond` 0..59999.
    pub fn new(millisecond: u16) -> Result<Self, TimeError> {
        check(
            "millisecond",
            millisecond.into(),
            0,
            u32::from(MS_PER_MINUTE) - 1,
        )?;
        Ok(Self(millisecond))
    }

    /// The duration in milliseconds.
    pub fn millisecond(&self) -> u16 {
        self.0
    }

    /// Decodes the two octets; values above 59999 are an error.
    pub fn from_bytes(bytes: [u8; 2]) -> Result<Self, TimeError> {
        Self::new(u16::from_le_bytes(bytes))
    }

    /// Decodes a slice that must be exactly [`Cp16Time2a::LEN`] octets long.
    pub fn decode(bytes: &[u8]) -> Result<Self, TimeError> {
        Self::from_bytes(exact(bytes)?)
    }

    /// The two octets on the wire.
    pub fn to_bytes(&self) -> [u8; 2] {
        self.0.to_le_bytes()
    }

    /// Appends the two octets to `out`.
    pub fn encode(&self, out: &mut Vec<u8>) {
        out.extend_from_slice(&self.to_bytes());
    }
}

impl TryFrom<u16> for Cp16Time2a {
    type Error = TimeError;

    fn try_from(millisecond: u16) -> Result<Self, TimeError> {
        Self::new(millisecond)
    }
}

impl fmt::Display for Cp16Time2a {
    /// `30.424 s`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}.{:03} s", self.0 / 1000, self.0 % 1000)
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::panic, clippy::indexing_slicing)]
mod tests {
    use super::*;

    #[test]
    fn cp32_round_trip_flags_and_midnight() {
        let tag = Cp32Time2a::new(8, 28, 32_666).unwrap().with_invalid(true);
        assert_eq!(tag.to_bytes(), [0x9A, 0x7F, 0x9C, 0x08]);
        assert_eq!(Cp32Time2a::from_bytes(tag.to_bytes()), Ok(tag));
        assert_eq!(tag.to_string(), "08:28:32.666 [IV]");
        assert!(Cp32Time2a::from_bytes([0, 0, 0, 24]).is_err());
        assert!(
            Cp32Time2a::from_bytes([0x60, 0xEA, 0, 0]).is_err(),
            "60000 ms"
        );
        let late = Cp32Time2a::new(23, 59, 58_000).unwrap();
        let after_midnight = NaiveDate::from_ymd_opt(2026, 11, 24)
            .unwrap()
            .and_hms_opt(0, 0, 1)
            .unwrap();
        assert_eq!(
            late.resolve(after_midnight),
            NaiveDate::from_ymd_opt(2026, 11, 23)
                .unwrap()
                .and_hms_opt(23, 59, 58)
        );
        let early = Cp32Time2a::new(0, 0, 1_000).unwrap();
        let before_midnight = NaiveDate::from_ymd_opt(2026, 11, 23)
            .unwrap()
            .and_hms_opt(23, 59, 59)
            .unwrap();
        assert_eq!(
            early.resolve(before_midnight),
            NaiveDate::from_ymd_opt(2026, 11, 24)
                .unwrap()
                .and_hms_opt(0, 0, 1)
        );
    }

    /// CP56 of the first M_DP_TB_1 line of spec §7.3.
    const BREAKER_OFF_TIME: [u8; 7] = [0xD8, 0x76, 0xBB, 0x09, 0x1A, 0x04, 0x11];

    #[test]
    fn decodes_the_spec_vector() {
        let tag = Cp56Time2a::from_bytes(BREAKER_OFF_TIME).unwrap();
        assert_eq!(tag.full_year(), 2017);
        assert_eq!((tag.month(), tag.day(), tag.day_of_week()), (4, 26, 0));
        assert_eq!(
            (tag.hour(), tag.minute(), tag.millisecond()),
            (9, 59, 30424)
        );
        assert!(tag.is_invalid());
        assert!(!tag.is_summer_time());
        assert!(!tag.is_substituted());
        assert_eq!(tag.to_bytes(), BREAKER_OFF_TIME);
        assert_eq!(tag.to_string(), "2017-04-26 09:59:30.424 [IV]");
    }

    #[test]
    fn flags_have_their_bits() {
        let tag = Cp56Time2a::new(17, 4, 7, 15, 43, 870)
            .unwrap()
            .with_summer_time(true)
            .with_substituted(true)
            .with_day_of_week(5)
            .unwrap();
        let bytes = tag.to_bytes();
        assert_eq!(bytes[2], 43 | 0x40);
        assert_eq!(bytes[3], 15 | 0x80);
        assert_eq!(bytes[4], 7 | (5 << 5));
        assert_eq!(Cp56Time2a::from_bytes(bytes).unwrap(), tag);
        assert_eq!(tag.to_string(), "2017-04-07 15:43:00.870 [SUB SU]");
    }

    #[test]
    fn rejects_out_of_range_fields() {
        let cases: [([u8; 7], &str); 6] = [
            ([0x60, 0xEA, 0, 0, 1, 1, 0], "millisecond"), // 60000
            ([0, 0, 60, 0, 1, 1, 0], "minute"),
            ([0, 0, 0, 24, 1, 1, 0], "hour"),
            ([0, 0, 0, 0, 0, 1, 0], "day"),
            ([0, 0, 0, 0, 1, 13, 0], "month"),
            ([0, 0, 0, 0, 1, 1, 100], "year"),
        ];
        for (bytes, field) in cases {
            match Cp56Time2a::from_bytes(bytes) {
                Err(TimeError::OutOfRange { field: found, .. }) => assert_eq!(found, field),
                other => panic!("{bytes:02X?}: expected {field} out of range, got {other:?}"),
            }
        }
    }

    #[test]
    fn reserved_bits_are_ignored() {
        // RES2 in the hour, RES3 in the month, RES4 in the year.
        let tag = Cp56Time2a::from_bytes([0, 0, 0, 0x60 | 5, 1, 0xF0 | 3, 0x80 | 20]).unwrap();
        assert_eq!((tag.hour(), tag.month(), tag.year()), (5, 3, 20));
    }

    #[test]
    fn naive_conversion_round_trips() {
        let when = NaiveDate::from_ymd_opt(2017, 4, 26)
            .unwrap()
            .and_hms_milli_opt(9, 59, 30, 424)
            .unwrap();
        let tag = Cp56Time2a::from_naive(when).unwrap();
        assert_eq!(tag.day_of_week(), 3); // a Wednesday
        assert_eq!(tag.to_naive().unwrap(), when);
        let too_late = NaiveDate::from_ymd_opt(2100, 1, 1)
            .unwrap()
            .and_hms_opt(0, 0, 0)
            .unwrap();
        assert_eq!(
            Cp56Time2a::from_naive(too_late),
            Err(TimeError::YearOutOfRange(2100))
        );
        let feb30 = Cp56Time2a::new(17, 2, 30, 0, 0, 0).unwrap();
        assert!(matches!(
            feb30.to_naive(),
            Err(TimeError::NoSuchDate { .. })
        ));
    }

    #[test]
    fn cp24_round_trips_and_resolves() {
        let tag = Cp24Time2a::from_bytes([0xD8, 0x76, 0xBB]).unwrap();
        assert_eq!((tag.minute(), tag.millisecond()), (59, 30424));
        assert!(tag.is_invalid());
        assert_eq!(tag.to_bytes(), [0xD8, 0x76, 0xBB]);
        assert_eq!(tag.to_string(), "59:30.424 [IV]");
        let received = NaiveDate::from_ymd_opt(2017, 4, 26)
            .unwrap()
            .and_hms_opt(10, 0, 1)
            .unwrap();
        let resolved = tag.resolve(received).unwrap();
        assert_eq!(resolved.to_string(), "2017-04-26 09:59:30.424");
        assert!(Cp24Time2a::from_bytes([0x60, 0xEA, 0]).is_err());
    }

    #[test]
    fn cp16_limits() {
        assert_eq!(
            Cp16Time2a::decode(&[0x5F, 0xEA]).unwrap().millisecond(),
            59999
        );
        assert!(Cp16Time2a::decode(&[0x60, 0xEA]).is_err());
        assert_eq!(
            Cp16Time2a::decode(&[0]),
            Err(TimeError::WrongLength {
                expected: 2,
                actual: 1
            })
        );
        assert_eq!(Cp16Time2a::new(1500).unwrap().to_string(), "1.500 s");
    }
}
